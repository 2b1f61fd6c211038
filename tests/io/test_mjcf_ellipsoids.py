"""MJCF ellipsoid geoms: read as exact ``Ellipsoid`` primitives (alone, or as parts of a body
of several geoms), drawn and exported as the tessellation they were read as before, and written
back as ellipsoid geoms (MJCF) or that tessellation (USD, GLB). Distances against MuJoCo are in
test_mjcf_oracle.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.io.robot import RobotOptions
from meshcol.types import Capsule, Ellipsoid, primitive_mesh

pytest.importorskip("mujoco", reason="MJCF reading needs mujoco (pip install meshcol[robots])")

MODEL = Path(__file__).resolve().parents[1] / "data" / "mjcf_ellipsoids.xml"


def read() -> dict:
    from meshcol.io.mjcf import read_mjcf

    scene = read_mjcf(str(MODEL), RobotOptions()).scene()
    return {b.name: b for b in scene.bodies}


def unit_sphere_times(axes) -> np.ndarray:
    """What the reader made of an ellipsoid geom before: the unit icosphere times its size."""
    import trimesh

    unit = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    return np.array(unit.vertices, dtype=np.float64) * np.asarray(axes, dtype=np.float64)


def test_a_body_of_one_ellipsoid_is_that_primitive():
    bodies = read()
    head = bodies["head"]
    assert head.primitive == Ellipsoid((0.08, 0.06, 0.05))
    assert head.vertices.tobytes() == unit_sphere_times((0.08, 0.06, 0.05)).tobytes()
    flat = bodies["tail"]
    assert flat.primitive == Ellipsoid((0.08, 0.04, 0.01))


def test_a_body_of_several_geoms_keeps_its_ellipsoids_exact():
    bodies = read()
    torso = bodies["torso"]
    kinds = [None if p is None else type(p.primitive) for p in torso.part_primitives]
    assert kinds == [Ellipsoid, Capsule]
    trunk = torso.part_primitives[0]
    assert trunk.primitive == Ellipsoid((0.2, 0.12, 0.08))
    # the part's triangles: the old tessellation at the geom's pose in the body frame, bytes
    origin = trunk.pose
    first = torso.part_faces[1]
    count = len(np.unique(torso.faces[:first]))
    expected = unit_sphere_times((0.2, 0.12, 0.08)) @ origin[:3, :3].T + origin[:3, 3]
    assert torso.vertices[:count].tobytes() == expected.tobytes()


def run(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stderr


def test_hull_to_mjcf_keeps_the_ellipsoid_geoms(tmp_path: Path):
    import mujoco

    code, stderr = run("hull", str(MODEL), "--out-dir", str(tmp_path))
    assert code == 0, stderr
    written = mujoco.MjModel.from_xml_path(str(tmp_path / MODEL.name))
    original = mujoco.MjModel.from_xml_path(str(MODEL))
    ellipsoid = int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)
    assert (written.geom_type == ellipsoid).sum() == (original.geom_type == ellipsoid).sum() == 6
    mine = written.geom_size[written.geom_type == ellipsoid]
    theirs = original.geom_size[original.geom_type == ellipsoid]
    np.testing.assert_array_equal(mine, theirs)


def test_hull_to_usd_writes_each_ellipsoid_as_its_tessellation(tmp_path: Path):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdPhysics

    assert run("hull", str(MODEL), "--out-dir", str(tmp_path), "--to", "usd")[0] == 0
    stage = Usd.Stage.Open(str(tmp_path / "mjcf_ellipsoids.usda"))
    prims = {p.GetName(): p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)}
    assert sorted(prims) == sorted(
        f"{link}_ellipsoid{k}"
        for link, k in [("torso", 1), ("head", 3), ("front", 4), ("paw", 6), ("front2", 8)]
        + [("tail", 10)]
    )
    bodies = read()
    cache = UsdGeom.XformCache()
    head = prims["head_ellipsoid3"]
    assert UsdPhysics.MeshCollisionAPI(head).GetApproximationAttr().Get() == "convexHull"
    points = np.array(UsdGeom.Mesh(head).GetPointsAttr().Get(), dtype=float)
    m = np.array(cache.GetLocalToWorldTransform(head), dtype=float)  # row vectors
    world = points @ m[:3, :3] + m[3, :3]
    pose = bodies["head"].pose
    expected = primitive_mesh(bodies["head"].primitive)[0] @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_allclose(world, expected, rtol=0, atol=1e-6)  # USD points are floats


def test_hull_to_glb_draws_each_ellipsoid_as_its_tessellation(tmp_path: Path):
    import trimesh

    assert run("hull", str(MODEL), "--out-dir", str(tmp_path), "--to", "glb")[0] == 0
    scene = trimesh.load(tmp_path / "mjcf_ellipsoids.glb", force="scene")
    assert "head_ellipsoid3" in scene.graph.nodes_geometry
    mesh = scene.geometry["head_ellipsoid3"]
    assert len(mesh.vertices) == 642 and len(mesh.faces) == 1280
    assert mesh.is_convex
