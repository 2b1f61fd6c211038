"""Ellipsoids fitted into robot descriptions (``meshcol fit ROBOT --shape ellipsoid``).

MuJoCo's compiler reads the MJCF written (from a URDF and from an MJCF): each fitted geom is
an ellipsoid whose size is the report's semi-axes, and every collision mesh of the INPUT,
posed by a reader that is not meshcol's (yourdfpy, MuJoCo), lies inside it at several joint
configurations. URDF has no ellipsoid: the fit is refused there before anything is written.
"""

# The fixtures urdf and mjcf come from test_robot_write (one copy); as test parameters they
# shadow the imported names, which is how pytest finds them.
# ruff: noqa: F811

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_fit_robot import TOL, local, mujoco_geoms, urdf_input_meshes
from test_robot_write import mjcf, run, urdf  # noqa: F401 - the fixtures

pytest.importorskip("yourdfpy")
mujoco = pytest.importorskip("mujoco")


def ellipsoid_geoms(xml: Path, qpos: dict) -> tuple[dict, dict]:
    """MuJoCo's compiled model at qpos (:func:`mujoco_geoms`): collision meshes' world
    vertices, and ellipsoid collision geoms' (semi-axes, world pose), by body name."""
    meshes, primitives = mujoco_geoms(xml, qpos)
    ellipsoids = {
        body: [(size, pose) for kind, size, pose in found if kind == "ellipsoid"]
        for body, found in primitives.items()
    }
    return meshes, {body: found for body, found in ellipsoids.items() if found}


def assert_inside(meshes: dict, ellipsoids: dict, count: int) -> None:
    """Each input mesh lies inside one ellipsoid of its link; ``count`` meshes in all."""
    seen = 0
    for link, clouds in meshes.items():
        for cloud in clouds:
            # (|p / a| - 1) min(a): a lower bound of the distance outside, within TOL as
            # for the other primitives (MuJoCo keeps mesh vertices in float32)
            excess = [
                (np.max(np.linalg.norm(local(cloud, pose) / size, axis=1)) - 1.0) * size.min()
                for size, pose in ellipsoids.get(link, [])
            ]
            assert excess and min(excess) <= TOL, link
            seen += 1
    assert seen == count


def test_fit_urdf_to_mjcf_ellipsoids_through_mujoco(urdf: Path, tmp_path: Path) -> None:
    out, report = tmp_path / "mjcf", tmp_path / "fits.json"
    args = ["fit", str(urdf), "--out-dir", str(out), "--shape", "ellipsoid", "--to", "mjcf"]
    code, _, stderr = run(*args, "--report", str(report))
    assert code == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == ["small.xml"]
    rows = json.loads(report.read_text())["bodies"]
    assert [row["name"] for row in rows] == ["base/0", "arm/0", "finger/0"]
    for angle in (0.0, 0.7, -0.9):
        qpos = {"j1": angle, "j3": 0.2 * angle + 0.1}  # j3 mimics j1 in the URDF
        _, ellipsoids = ellipsoid_geoms(out / "small.xml", qpos)
        assert sorted(ellipsoids) == ["arm", "base", "finger"]
        assert_inside(urdf_input_meshes(urdf, {"j1": angle}), ellipsoids, count=3)
    # the geom's size is the fit's semi-axes (the report gives twice them, as full extents)
    for row in rows:
        ((size, _),) = ellipsoids[row["name"].split("/")[0]]
        np.testing.assert_allclose(size, np.asarray(row["size"]) / 2.0, rtol=1e-12)


def test_fit_mjcf_to_mjcf_ellipsoids(mjcf: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, _, stderr = run("fit", str(mjcf), "--out-dir", str(out), "--shape", "ellipsoid")
    assert code == 0, stderr
    for angle in (0.0, 0.4):
        meshes, _ = ellipsoid_geoms(mjcf, {"j": angle})
        found, ellipsoids = ellipsoid_geoms(out / "small.xml", {"j": angle})
        assert found == {}  # every collision mesh became an ellipsoid
        assert_inside(meshes, ellipsoids, count=2)


def test_fit_urdf_refuses_an_ellipsoid(urdf: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, stdout, stderr = run("fit", str(urdf), "--out-dir", str(out), "--shape", "ellipsoid")
    assert code == 2 and stdout == ""
    assert stderr == (
        f"meshcol: error: {urdf}: URDF has no ellipsoid: write the fits with --to mjcf, usd "
        "or glb, or fit another --shape\n"
    )
    assert not out.exists()


@pytest.mark.slow
def test_fit_urdf_to_usd_writes_a_containing_mesh(urdf: Path, tmp_path: Path) -> None:
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    out = tmp_path / "usd"
    args = ["fit", str(urdf), "--out-dir", str(out), "--to", "usd", "--shape", "ellipsoid"]
    assert run(*args)[0] == 0
    stage = Usd.Stage.Open(str(out / "small.usda"))
    names = sorted(p.GetName() for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    assert names == ["arm_ellipsoid0", "base_ellipsoid0", "finger_ellipsoid0"]


def test_fit_urdf_to_mjcf_keeps_a_sphere_where_the_ellipsoid_is(tmp_path: Path) -> None:
    """A link whose own sphere sits where the fitted ellipsoid's centre falls, listed first:
    MuJoCo's importer sees two spheres there (the URDF's and the ellipsoid's placeholder),
    and the ellipsoid is made of the placeholder, by its radius, not of the first found."""
    import trimesh

    corners = np.array([[x, y, z] for x in (-0.3, 0.3) for y in (-0.1, 0.1) for z in (-0.05, 0.05)])
    trimesh.Trimesh(corners, trimesh.convex.convex_hull(corners).faces).export(tmp_path / "box.obj")

    def fit(sphere_at: str) -> tuple[dict, dict]:
        (tmp_path / "one.urdf").write_text(
            f'<robot name="one"><link name="base"><collision><origin xyz="{sphere_at}"/>'
            '<geometry><sphere radius="0.02"/></geometry></collision><collision>'
            '<geometry><mesh filename="box.obj"/></geometry></collision></link></robot>'
        )
        out, report = tmp_path / "out", tmp_path / "fits.json"
        args = ["fit", str(tmp_path / "one.urdf"), "--out-dir", str(out), "--to", "mjcf"]
        code, _, stderr = run(*args, "--shape", "ellipsoid", "--report", str(report))
        assert code == 0, stderr
        (row,) = json.loads(report.read_text())["bodies"]
        model = mujoco.MjModel.from_xml_path(str(out / "one.xml"))
        geoms = {int(model.geom_type[g]): model.geom_size[g].copy() for g in range(model.ngeom)}
        return row, geoms

    row, _ = fit("1 1 1")
    # the fit's centre is the box's to its tolerance, not exactly 0: put the sphere there
    row, geoms = fit(" ".join(repr(float(c)) for c in row["center"]))
    assert sorted(geoms) == [mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_ELLIPSOID]
    assert geoms[mujoco.mjtGeom.mjGEOM_SPHERE][0] == 0.02
    ellipsoid = geoms[mujoco.mjtGeom.mjGEOM_ELLIPSOID]
    np.testing.assert_allclose(ellipsoid, np.asarray(row["size"]) / 2.0, rtol=1e-12)
    # the box's minimum ellipsoid has its corners on it: sqrt(3) times the half sides
    np.testing.assert_allclose(
        sorted(ellipsoid), np.sqrt(3) * np.array([0.05, 0.1, 0.3]), rtol=1e-5
    )
