"""Fits written into robot descriptions (``meshcol fit ROBOT --out-dir OUT``).

Every description written is read back by a reader that is not meshcol's (yourdfpy for URDF;
MuJoCo's compiler for MJCF and for the URDF written) and every
collision mesh of the INPUT, posed by that reader at a joint configuration, must lie inside
the primitive the OUTPUT puts on its link.
"""

# The fixtures urdf, mjcf and panda come from test_robot_write (one copy); as test
# parameters they shadow the imported names, which is how pytest finds them.
# ruff: noqa: F811

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_robot_write import mjcf, panda, run, urdf  # noqa: F401 - the fixtures

pytest.importorskip("yourdfpy")
mujoco = pytest.importorskip("mujoco")
etree = pytest.importorskip("lxml.etree")

TOL = 1e-7
#: The other shapes of a parametrized test: the full lane only (the fast lane keeps one).
SLOW = pytest.mark.slow


def inside(points: np.ndarray, kind: str, size: np.ndarray, tol: float = TOL) -> np.ndarray:
    """Points (primitive frame) inside a primitive given MuJoCo-style: kind and half sizes
    (box: half extents; sphere: r; cylinder, capsule: r, half length)."""
    if kind == "box":
        return np.all(np.abs(points) <= size[:3] + tol, axis=1)
    if kind == "sphere":
        return np.linalg.norm(points, axis=1) <= size[0] + tol
    radial = np.linalg.norm(points[:, :2], axis=1)
    if kind == "cylinder":
        return (radial <= size[0] + tol) & (np.abs(points[:, 2]) <= size[1] + tol)
    assert kind == "capsule"
    z = np.clip(points[:, 2], -size[1], size[1])
    return np.hypot(radial, points[:, 2] - z) <= size[0] + tol


def local(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    return (points - pose[:3, 3]) @ pose[:3, :3]


def urdf_input_meshes(path: Path, cfg: dict) -> dict[str, list[np.ndarray]]:
    """World vertices of each mesh collision element of the INPUT, by link: yourdfpy's link
    poses and file names (its package:// handler), trimesh's mesh loading."""
    import trimesh
    import yourdfpy

    model = yourdfpy.URDF.load(str(path))
    model.update_cfg(cfg)
    out: dict[str, list[np.ndarray]] = {}
    for link in model.robot.links:
        for c in link.collisions:
            if c.geometry.mesh is None:
                continue
            file = model._filename_handler(c.geometry.mesh.filename)
            loaded = trimesh.load(str(file), force="scene")
            v = np.concatenate([np.asarray(g.vertices) for g in loaded.geometry.values()])
            if c.geometry.mesh.scale is not None:
                v = v * np.broadcast_to(np.asarray(c.geometry.mesh.scale, dtype=float), (3,))
            world = model.get_transform(link.name) @ (
                c.origin if c.origin is not None else np.eye(4)
            )
            out.setdefault(link.name, []).append(v @ world[:3, :3].T + world[:3, 3])
    return out


def urdf_output_primitives(
    path: Path, cfg: dict
) -> dict[str, list[tuple[str, np.ndarray, np.ndarray]]]:
    """(kind, half sizes, world pose) of each primitive collision element, via yourdfpy."""
    import yourdfpy

    model = yourdfpy.URDF.load(str(path))
    model.update_cfg(cfg)
    out: dict[str, list] = {}
    for link in model.robot.links:
        pose = model.get_transform(link.name)
        for c in link.collisions:
            g = c.geometry
            world = pose @ (c.origin if c.origin is not None else np.eye(4))
            if g.box is not None:
                entry = ("box", np.asarray(g.box.size) / 2.0)
            elif g.sphere is not None:
                entry = ("sphere", np.array([g.sphere.radius]))
            elif g.cylinder is not None:
                entry = ("cylinder", np.array([g.cylinder.radius, g.cylinder.length / 2.0]))
            else:
                continue
            out.setdefault(link.name, []).append((*entry, world))
    return out


def mujoco_geoms(xml: Path, qpos: dict) -> tuple[dict, dict]:
    """MuJoCo's compiled model at qpos: mesh collision geoms' world vertices, and primitive
    collision geoms' (kind, size, world pose), by body; collision = contype or conaffinity."""
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    for name, value in qpos.items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    mujoco.mj_forward(model, data)
    kinds = {
        int(mujoco.mjtGeom.mjGEOM_BOX): "box",
        int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
        int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
        int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
        int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
    }
    meshes: dict[str, list] = {}
    primitives: dict[str, list] = {}
    for g in range(model.ngeom):
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            continue
        body = model.body(model.geom_bodyid[g]).name
        pose = np.eye(4)
        pose[:3, :3] = data.geom_xmat[g].reshape(3, 3)
        pose[:3, 3] = data.geom_xpos[g]
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            m = model.geom_dataid[g]
            start = model.mesh_vertadr[m]
            v = model.mesh_vert[start : start + model.mesh_vertnum[m]]
            meshes.setdefault(body, []).append(v @ pose[:3, :3].T + pose[:3, 3])
        else:
            kind = kinds[int(model.geom_type[g])]
            primitives.setdefault(body, []).append((kind, np.array(model.geom_size[g]), pose))
    return meshes, primitives


def assert_enclosed(meshes: dict, primitives: dict, new: int, union: bool = False) -> None:
    """Each input mesh lies inside one of its link's primitives (``union``: each of its
    vertices inside one of them, as a capsule written as a cylinder and two spheres holds
    it), and ``new`` primitives are used that way, one per mesh."""
    used = 0
    for link, clouds in meshes.items():
        for cloud in clouds:
            held = [inside(local(cloud, p[2]), p[0], p[1]) for p in primitives.get(link, [])]
            hits = np.any(held, axis=0).all() if union else any(h.all() for h in held)
            assert hits, f"{link}: an input mesh is not inside any primitive of the output"
            used += 1
    assert used == new


@pytest.mark.parametrize(
    "shape", ["auto", *(pytest.param(s, marks=SLOW) for s in ("box", "sphere", "cylinder"))]
)
def test_fit_urdf_primitives_enclose_the_input_meshes(urdf: Path, tmp_path: Path, shape) -> None:
    out = tmp_path / "out"
    report = tmp_path / "fits.json"
    code, stdout, stderr = run(
        "fit",
        str(urdf),
        "--out-dir",
        str(out),
        "--shape",
        shape,
        "--report",
        str(report),
        "--joint",
        "j1=0.4",
    )
    assert code == 0, stderr
    assert stdout == ""
    assert sorted(p.name for p in out.iterdir()) == ["small.urdf"]  # primitives: no mesh file
    for cfg in ({}, {"j1": 0.4}, {"j1": -0.9}):
        meshes = urdf_input_meshes(urdf, cfg)
        primitives = urdf_output_primitives(out / "small.urdf", cfg)
        assert_enclosed(meshes, primitives, new=3)  # base shell, the arm's two objects, finger
    data = json.loads(report.read_text())
    schema = Path(__file__).resolve().parents[2] / "meshcol/schemas/fit_report.schema.json"
    jsonschema.Draft202012Validator(json.loads(schema.read_text())).validate(data)
    assert data["settings"]["frame"] == "link"
    assert data["settings"]["description"] == str(out / "small.urdf")
    assert [row["name"] for row in data["bodies"]] == ["base/0", "arm/0", "finger/0"]
    if shape != "auto":
        assert {row["shape"] for row in data["bodies"]} == {shape}
    # the rest of the file is untouched: the kept box and cylinder, visuals, custom tags
    root = etree.fromstring((out / "small.urdf").read_bytes())
    base = root.find("link[@name='base']")
    assert base.find("custom_tag").get("foo") == "bar"
    assert base.findall("collision")[1].find("geometry/box").get("size") == "0.05 0.06 0.07"
    assert base.find("collision").get("name") == "shell"
    tip = root.find("link[@name='tip']")
    assert tip.find("collision/geometry/cylinder").get("radius") == "0.02"


def test_fit_urdf_parameters_are_the_reported_ones(urdf: Path, tmp_path: Path) -> None:
    """The file's numbers are the fit's, and the report's parameters (link frame)."""
    from meshcol.analysis.rebuild import robot_colliders

    out = tmp_path / "out"
    report = tmp_path / "fits.json"
    assert (
        run(
            "fit", str(urdf), "--out-dir", str(out), "--shape", "cylinder", "--report", str(report)
        )[0]
        == 0
    )
    robot, _ = robot_colliders(urdf, "fit", fit_options={"shape": "cylinder"})
    fitted = [c for c in robot.colliders if c.fitted]
    rows = json.loads(report.read_text())["bodies"]
    root = etree.fromstring((out / "small.urdf").read_bytes())
    for c, row in zip(fitted, rows):
        element = root.find(f"link[@name='{c.link}']").findall("collision")[c.index]
        cylinder = element.find("geometry/cylinder")
        assert float(cylinder.get("radius")) == c.primitive.radius == row["radius"]
        assert float(cylinder.get("length")) == c.primitive.length == row["length"]
        xyz = [float(v) for v in element.find("origin").get("xyz").split()]
        np.testing.assert_allclose(xyz, c.origin[:3, 3], atol=1e-15)
        np.testing.assert_allclose(row["center"], c.origin[:3, 3], atol=1e-15)


@pytest.mark.parametrize(
    "shape", ["capsule", *(pytest.param(s, marks=SLOW) for s in ("box", "auto"))]
)
def test_fit_urdf_to_mjcf_and_capsules_through_mujoco(urdf: Path, tmp_path: Path, shape) -> None:
    out = tmp_path / "urdf"
    assert run("fit", str(urdf), "--out-dir", str(out), "--shape", shape)[0] == 0
    mj = tmp_path / "mjcf"
    code, _, stderr = run("fit", str(urdf), "--out-dir", str(mj), "--shape", shape, "--to", "mjcf")
    assert code == 0, stderr
    unfused = out / "unfused.urdf"
    unfused.write_text(
        (out / "small.urdf")
        .read_text()
        .replace("</robot>", '<mujoco><compiler fusestatic="false"/></mujoco></robot>')
    )
    for angle in (0.0, 0.7):
        # j3 mimics j1 in the URDF; MuJoCo keeps qpos as set: give both
        qpos = {"j1": angle, "j3": 0.2 * angle + 0.1}
        meshes = urdf_input_meshes(urdf, {"j1": angle})
        for xml in (mj / "small.xml",):
            _, primitives = mujoco_geoms(xml, qpos)
            assert_enclosed(meshes, primitives, new=3)
        # the URDF written (a capsule as a cylinder and two spheres) through MuJoCo's own
        # URDF importer, every link kept a body
        _, primitives = mujoco_geoms(unfused, qpos)
        assert_enclosed(meshes, primitives, new=3, union=True)
    root = etree.fromstring((mj / "small.xml").read_bytes())
    groups = {g.get("group") for g in root.iter("geom") if g.get("contype") != "0"}
    assert groups == {"3"}


@pytest.mark.parametrize(
    "shape", ["capsule", *(pytest.param(s, marks=SLOW) for s in ("box", "sphere", "cylinder"))]
)
def test_fit_mjcf_to_mjcf_geoms_in_frames(mjcf: Path, tmp_path: Path, shape) -> None:
    out = tmp_path / "out"
    code, _, stderr = run("fit", str(mjcf), "--out-dir", str(out), "--shape", shape)
    assert code == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == ["small.xml"]
    for angle in (0.0, 0.4):
        meshes, _ = mujoco_geoms(mjcf, {"j": angle})
        found_meshes, primitives = mujoco_geoms(out / "small.xml", {"j": angle})
        assert found_meshes == {}  # every collision mesh became a primitive
        assert_enclosed(meshes, primitives, new=2)
    root = etree.fromstring((out / "small.xml").read_bytes())
    assert not any(m.get("name") == "arm" for m in root.iter("mesh"))  # no geom uses it now
    armcol = next(g for g in root.iter("geom") if g.get("name") == "armcol")
    assert (armcol.get("type") or "sphere") == shape and armcol.get("mesh") is None  # default
    shell = next(g for g in root.iter("geom") if g.get("friction") == "0.5 0.1 0.1")
    assert (shell.get("type") or "sphere") == shape  # its other attributes stay


@pytest.mark.slow
def test_fit_robot_glb_and_usd(urdf: Path, tmp_path: Path) -> None:
    import trimesh

    out = tmp_path / "glb"
    assert run("fit", str(urdf), "--out-dir", str(out), "--to", "glb", "--shape", "box")[0] == 0
    scene = trimesh.load(out / "small.glb", force="scene")
    names = sorted(scene.graph.nodes_geometry)
    # one node per element: three fitted boxes (the arm's two objects are one element), the
    # kept box and cylinder
    assert names == ["arm_box0", "base_box0", "base_box1", "finger_box0", "tip_cylinder0"]
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdPhysics

    out = tmp_path / "usd"
    assert run("fit", str(urdf), "--out-dir", str(out), "--to", "usd", "--shape", "sphere")[0] == 0
    stage = Usd.Stage.Open(str(out / "small.usda"))
    spheres = [p for p in stage.Traverse() if p.IsA(UsdGeom.Sphere)]
    assert len(spheres) == 3
    assert all(p.HasAPI(UsdPhysics.CollisionAPI) for p in spheres)


def test_fit_robot_bad_input(urdf: Path, mjcf: Path, tmp_path: Path) -> None:
    code, _, stderr = run("fit", str(mjcf), "--out-dir", str(tmp_path / "o"), "--to", "urdf")
    assert code == 2 and "--to urdf needs a URDF input" in stderr
    code, _, stderr = run("fit", str(urdf), "--to", "mjcf")
    assert code == 2 and "--to needs one robot description" in stderr
    assert not (tmp_path / "o").exists()


@given(st.floats(-np.pi, np.pi), st.floats(-np.pi / 2, np.pi / 2), st.floats(-np.pi, np.pi))
def test_rpy_round_trip(roll: float, pitch: float, yaw: float) -> None:
    from meshcol.geometry.rotations import quaternion_from_matrix, rpy_from_matrix
    from meshcol.io.scene import rotation_from_quaternion

    def rx(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])

    def ry(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])

    def rz(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

    rotation = rz(yaw) @ ry(pitch) @ rx(roll)
    r, p, y = rpy_from_matrix(rotation)
    np.testing.assert_allclose(rz(y) @ ry(p) @ rx(r), rotation, atol=1e-7)
    q = quaternion_from_matrix(rotation)
    assert q[0] >= 0
    np.testing.assert_allclose(rotation_from_quaternion(q), rotation, atol=1e-12)
    for lock in (np.pi / 2, -np.pi / 2):  # gimbal lock: still the same rotation
        rotation = rz(yaw) @ ry(lock) @ rx(roll)
        r, p, y = rpy_from_matrix(rotation)
        np.testing.assert_allclose(rz(y) @ ry(p) @ rx(r), rotation, atol=1e-7)


@pytest.mark.slow
def test_panda_capsules_to_mjcf_enclose_its_meshes(panda: Path, tmp_path: Path) -> None:
    joints = {"panda_joint2": -0.5, "panda_joint4": -2.0, "panda_finger_joint1": 0.02}
    out = tmp_path / "mjcf"
    args = ["fit", str(panda), "--out-dir", str(out), "--to", "mjcf", "--shape", "capsule"]
    code, _, stderr = run(*args)
    assert code == 0, stderr
    meshes = urdf_input_meshes(panda, joints)
    _, primitives = mujoco_geoms(out / "panda.xml", dict(joints, panda_finger_joint2=0.02))
    assert_enclosed(meshes, primitives, new=sum(len(v) for v in meshes.values()))
