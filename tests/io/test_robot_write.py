"""Rebuilt collision geometry written back (``meshcol hull|decompose ROBOT --out-dir``).

Every description written is loaded again (yourdfpy and meshcol's reader for URDF, MuJoCo's
compiler for MJCF, trimesh for GLB, pxr for USD) and its collision geometry, posed by the
file at a joint configuration, is compared with the colliders meshcol computed.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.decomposition.options import RunOptions

pytest.importorskip("yourdfpy")
mujoco = pytest.importorskip("mujoco")
etree = pytest.importorskip("lxml.etree")

ROBOT = """\
<?xml version="1.0"?>
<!-- a small robot: keep this comment -->
<robot name="small">
  <link name="base">
    <visual><geometry><mesh filename="meshes/body.stl"/></geometry></visual>
    <collision name="shell">
      <origin xyz="0 0 0.1" rpy="0 0 0.3"/>
      <geometry><mesh filename="meshes/body.stl" scale="1 2 1"/></geometry>
    </collision>
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.05 0.06 0.07"/></geometry></collision>
    <inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
    <custom_tag foo="bar"/>
  </link>
  <link name="frame_only"/>
  <link name="arm">
    <collision><origin xyz="0 0.1 0" rpy="0.2 0 0"/><geometry><mesh filename="meshes/arm.obj"/></geometry></collision>
    <inertial><mass value="0.5"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="tip">
    <collision><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.02" length="0.1"/></geometry></collision>
    <inertial><mass value="0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="finger">
    <collision><geometry><mesh filename="meshes/body.stl" scale="0.2 0.2 0.2"/></geometry></collision>
    <inertial><mass value="0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="fixed0" type="fixed"><parent link="base"/><child link="frame_only"/><origin xyz="0 0 0.3"/></joint>
  <joint name="j1" type="revolute"><parent link="frame_only"/><child link="arm"/>
    <origin xyz="0 0 0.2" rpy="0 0.1 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.3 0 0"/></joint>
  <joint name="j3" type="prismatic"><parent link="arm"/><child link="finger"/><origin xyz="0 0 0.1"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.5" effort="1" velocity="1"/><mimic joint="j1" multiplier="0.2" offset="0.1"/></joint>
</robot>
"""

MJCF = """\
<mujoco model="small">
  <compiler meshdir="assets"/>
  <default>
    <default class="collision"><geom contype="1" conaffinity="1" group="3"/></default>
    <default class="visual"><geom contype="0" conaffinity="0" group="1"/></default>
  </default>
  <asset>
    <mesh name="body" file="body.stl" scale="1 2 1"/>
    <mesh name="arm" file="arm.obj"/>
  </asset>
  <worldbody>
    <body name="base" pos="0 0 1">
      <geom class="visual" type="mesh" mesh="body"/>
      <geom class="collision" type="mesh" mesh="body" pos="0 0 0.1" euler="0 0 20" friction="0.5 0.1 0.1"/>
      <geom class="collision" type="box" size="0.1 0.1 0.1" pos="0.3 0 0"/>
      <body name="arm" pos="0 0 0.3" euler="10 0 0">
        <joint name="j" type="hinge" axis="0 1 0" range="-30 30"/>
        <frame pos="0 0.05 0" euler="0 0 30"><frame pos="0.02 0 0" euler="10 0 0">
          <geom name="armcol" type="mesh" mesh="arm" pos="0 0.1 0" axisangle="1 0 0 15"/>
        </frame></frame>
        <geom type="capsule" size="0.02 0.05" pos="0.1 0 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _meshes(folder: Path) -> None:
    import trimesh

    folder.mkdir(parents=True, exist_ok=True)
    trimesh.creation.box((0.2, 0.1, 0.3)).export(folder / "body.stl")
    a = trimesh.creation.box((0.1, 0.1, 0.1))
    b = trimesh.creation.icosphere(2, 0.05)
    b.apply_translation((0.2, 0, 0))
    with open(folder / "arm.obj", "w") as f:  # two objects: one collision element, two meshes
        f.write("o cube\n")
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in a.vertices)
        f.writelines(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in a.faces)
        f.write("o ball\n")
        n = len(a.vertices)
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in b.vertices)
        f.writelines(f"f {i + n + 1} {j + n + 1} {k + n + 1}\n" for i, j, k in b.faces)


@pytest.fixture
def urdf(tmp_path: Path) -> Path:
    _meshes(tmp_path / "robot" / "meshes")
    path = tmp_path / "robot" / "small.urdf"
    path.write_text(ROBOT)
    return path


@pytest.fixture
def mjcf(tmp_path: Path) -> Path:
    _meshes(tmp_path / "model" / "assets")
    path = tmp_path / "model" / "small.xml"
    path.write_text(MJCF)
    return path


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def computed(path: Path, method: str = "hull", joints: dict | None = None, **kw):
    """What meshcol computes: the colliders and each part's world vertices by link."""
    from meshcol.analysis.rebuild import robot_colliders
    from meshcol.io.robot import RobotOptions

    robot, _ = robot_colliders(path, method, robot_options=RobotOptions(joints=joints or {}), **kw)
    world: dict[str, list[np.ndarray]] = {}
    for c in robot.colliders:
        pose = robot.link_poses[c.link]
        for v, _ in c.parts:
            world.setdefault(c.link, []).append(v @ pose[:3, :3].T + pose[:3, 3])
    return robot, world


def same_points(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Equal point sets (every point of each within ``tol`` of one of the other)."""
    from scipy.spatial import cKDTree

    if len(a) == 0 or len(b) == 0:
        return False
    return bool(cKDTree(b).query(a)[0].max() <= tol and cKDTree(a).query(b)[0].max() <= tol)


def contains(points: np.ndarray, part: np.ndarray, tol: float) -> bool:
    """Every point of ``part`` is within ``tol`` of one of ``points`` (yourdfpy merges the
    collision elements of a link into one geometry node)."""
    from scipy.spatial import cKDTree

    return bool(cKDTree(points).query(part)[0].max() <= tol)


def match_all(expected: dict[str, list[np.ndarray]], found: dict[str, list[np.ndarray]], tol):
    assert sorted(expected) == sorted(found)
    for link, parts in expected.items():
        assert len(parts) == len(found[link]), link
        remaining = list(found[link])
        for part in parts:
            hit = [i for i, other in enumerate(remaining) if same_points(part, other, tol)]
            assert hit, f"{link}: a computed part is not in the file"
            remaining.pop(hit[0])


def mujoco_parts(xml: Path, qpos: dict[str, float]) -> tuple[dict, object, object]:
    """World vertices of every mesh collision geom (group 3) by body, after mj_kinematics."""
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    for name, value in qpos.items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    mujoco.mj_forward(model, data)  # equality constraints do not move qpos: set mimic by hand
    found: dict[str, list[np.ndarray]] = {}
    for g in range(model.ngeom):
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH or model.geom_group[g] != 3:
            continue
        m = model.geom_dataid[g]
        v = model.mesh_vert[model.mesh_vertadr[m] : model.mesh_vertadr[m] + model.mesh_vertnum[m]]
        world = v @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        found.setdefault(model.body(model.geom_bodyid[g]).name, []).append(world)
    return found, model, data


# --- URDF out -------------------------------------------------------------------------------


@pytest.mark.parametrize("joints", [{}, {"j1": 0.7}])
def test_hull_urdf_loads_and_holds_the_computed_hulls(urdf: Path, tmp_path: Path, joints) -> None:
    import yourdfpy

    from meshcol.io.robot import RobotOptions, load_robot

    out = tmp_path / "out"
    args = ["hull", str(urdf), "--max-vertices", "16", "--out-dir", str(out)]
    for name, value in joints.items():
        args += ["--joint", f"{name}={value}"]
    code, stdout, stderr = run(*args)
    assert code == 0, stderr
    assert stdout == ""
    assert "written to" in stderr
    written = out / "small.urdf"
    assert sorted(p.name for p in out.iterdir()) == [
        "arm_00.obj",
        "base_00.obj",
        "finger_00.obj",
        "small.urdf",
    ]
    robot, expected = computed(urdf, max_vertices=16, joints=joints)
    # one hull per mesh element: the arm's two objects are one collider
    assert [len(c.parts) for c in robot.colliders if c.primitive is None] == [1, 1, 1]
    assert all(len(v) <= 16 for parts in expected.values() for v in parts)

    # meshcol's reader: the same vertices at the same world poses (OBJ round-trips exactly)
    back = load_robot(written, RobotOptions(joints=joints))
    found = {}
    for body in back.bodies:
        if body.primitive is None:
            meshes = [v for _, v, _ in body.part_meshes()] if body.parts else [body.vertices]
            found[body.name] = [m @ body.pose[:3, :3].T + body.pose[:3, 3] for m in meshes]
    # the base keeps its box (tessellated by the reader): compare the hull parts only
    found["base"] = [found["base"][0]]
    match_all(expected, found, 1e-12)

    # yourdfpy: the same, through its own scene graph and mesh loading
    model = yourdfpy.URDF.load(
        str(written), build_collision_scene_graph=True, load_collision_meshes=True
    )
    model.update_cfg(joints or {})
    scene = model.collision_scene
    by_file = {}
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        v = np.asarray(geometry.vertices) @ transform[:3, :3].T + transform[:3, 3]
        by_file[len(by_file)] = v
    flat = [v for parts in expected.values() for v in parts]
    for part in flat:
        assert any(contains(v, part, 1e-9) for v in by_file.values())


def test_urdf_keeps_everything_but_the_rebuilt_collisions(urdf: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert run("hull", str(urdf), "--out-dir", str(out))[0] == 0
    text = (out / "small.urdf").read_text()
    assert text.startswith('<?xml version="1.0" encoding="utf-8"?>\n<!-- a small robot')
    before = etree.fromstring(urdf.read_bytes())
    after = etree.fromstring(text.encode())

    def dump(root, tag):
        return [etree.tostring(e) for e in root.iter(tag)]

    for tag in ("inertial", "joint", "custom_tag"):
        assert dump(before, tag) == dump(after, tag), tag
    # visuals as they were, but a relative mesh path now relative to OUT (the same file)
    (visual,) = after.iter("visual")
    mesh = visual.find("geometry/mesh")
    assert (out / mesh.get("filename")).resolve() == (urdf.parent / "meshes/body.stl").resolve()
    mesh.set("filename", "meshes/body.stl")
    assert dump(before, "visual") == dump(after, "visual")
    base = after.find("link[@name='base']")
    shell, box = base.findall("collision")
    assert shell.get("name") == "shell" and shell.find("origin") is None
    assert shell.find("geometry/mesh").attrib == {"filename": "base_00.obj"}
    assert etree.tostring(box) == etree.tostring(before.find("link[@name='base']")[2])
    tip = after.find("link[@name='tip']/collision")
    assert tip.find("geometry/cylinder") is not None and tip.find("origin") is not None


@pytest.mark.slow
def test_decompose_urdf_parts_cache_and_jobs(urdf: Path, tmp_path: Path) -> None:
    out, cache = tmp_path / "out", tmp_path / "cache"
    report = tmp_path / "r.json"
    args = ["decompose", str(urdf), "--out-dir", str(out), "--cache-dir", str(cache), "-j", "2"]
    code, _, stderr = run(*args, "--report", str(report))
    assert code == 0, stderr
    first = json.loads(report.read_text())
    assert first["settings"]["frame"] == "link"
    assert first["settings"]["description"].endswith("small.urdf")
    names = [b["name"] for b in first["files"][0]["bodies"]]
    # each object of the arm's mesh is decomposed on its own (as check's colliders are)
    assert names == ["base/0", "arm/0/0", "arm/0/1", "finger/0"]
    robot, expected = computed(urdf, "decompose", run=RunOptions(cache_dir=str(cache)))
    root = etree.fromstring((out / "small.urdf").read_bytes())
    arm = root.findall("link[@name='arm']/collision")
    assert len(arm) == sum(len(c.parts) for c in robot.colliders if c.link == "arm")
    assert [c.find("geometry/mesh").get("filename") for c in arm] == [
        f"arm_{k:02d}.obj" for k in range(len(arm))
    ]
    from meshcol.io.robot import load_robot

    back = load_robot(out / "small.urdf")
    arm_body = next(b for b in back.bodies if b.name == "arm")
    found = [
        v @ arm_body.pose[:3, :3].T + arm_body.pose[:3, 3] for _, v, _ in arm_body.part_meshes()
    ]
    match_all({"arm": expected["arm"]}, {"arm": found}, 1e-12)
    # a second run: every mesh from the cache
    again = tmp_path / "again"
    report2 = tmp_path / "r2.json"
    assert (
        run(
            "decompose",
            str(urdf),
            "-o",
            str(again),
            "--cache-dir",
            str(cache),
            "--report",
            str(report2),
        )[0]
        == 0
    )
    assert all(b["from_cache"] for b in json.loads(report2.read_text())["files"][0]["bodies"])
    assert (again / "arm_00.obj").read_bytes() == (out / "arm_00.obj").read_bytes()


def test_two_elements_of_one_link_each_get_their_parts(tmp_path: Path) -> None:
    """Two mesh elements of one link, each rebuilt as several parts (a decomposition): the
    second's parts replace the second element, not a copy of the first (the writer once
    looked the element up after the first's copies had shifted the link's elements, and the
    second kept its input mesh)."""
    import dataclasses

    import trimesh

    from meshcol.analysis.rebuild import robot_colliders
    from meshcol.io.robot import load_robot
    from meshcol.io.robot_write import write_robot

    trimesh.creation.box([0.1, 0.1, 0.1]).export(tmp_path / "cube.obj")
    (tmp_path / "two.urdf").write_text(
        '<robot name="two"><link name="base">'
        '<collision name="first"><geometry><mesh filename="cube.obj"/></geometry></collision>'
        '<collision name="second"><origin xyz="0 0 1"/>'
        '<geometry><mesh filename="cube.obj"/></geometry></collision>'
        "</link></robot>"
    )
    robot, _ = robot_colliders(tmp_path / "two.urdf", "hull")
    # each hull split in two halves along x: two parts per element, as a decomposition gives
    halves = []
    for c in robot.colliders:
        v, f = c.parts[0]
        low, high = v.copy(), v.copy()
        low[:, 0] = np.minimum(v[:, 0], v[:, 0].mean())
        high[:, 0] = np.maximum(v[:, 0], v[:, 0].mean())
        halves.append(dataclasses.replace(c, parts=((low, f), (high, f))))
    robot = dataclasses.replace(robot, colliders=tuple(halves))
    write_robot(robot, tmp_path / "out")
    root = etree.fromstring((tmp_path / "out" / "two.urdf").read_bytes())
    elements = root.findall("link/collision")
    names = ["first_00", "first_01", "second_00", "second_01"]
    assert [e.get("name") for e in elements] == names
    assert not root.findall("link/collision/origin")  # the second's origin is in its parts
    files = [e.find("geometry/mesh").get("filename") for e in elements]
    assert files == [f"base_{k:02d}.obj" for k in range(4)]
    (body,) = load_robot(tmp_path / "out" / "two.urdf").bodies
    found = [v @ body.pose[:3, :3].T + body.pose[:3, 3] for _, v, _ in body.part_meshes()]
    expected = [v for c in robot.colliders for v, _ in c.parts]
    match_all({"base": expected}, {"base": found}, 1e-12)


# --- MJCF out -------------------------------------------------------------------------------


@pytest.mark.parametrize("joint", [0.0, 0.6])
def test_hull_urdf_to_mjcf_compiles_in_the_menagerie_convention(
    urdf: Path, tmp_path: Path, joint: float
) -> None:
    out = tmp_path / "out"
    code, _, stderr = run(
        "hull", str(urdf), "--max-vertices", "16", "--out-dir", str(out), "--to", "mjcf"
    )
    assert code == 0, stderr
    xml = out / "small.xml"
    _, expected = computed(urdf, max_vertices=16, joints={"j1": joint})
    found, model, data = mujoco_parts(xml, {"j1": joint, "j3": 0.2 * joint + 0.1})
    match_all(expected, found, 1e-6)  # MuJoCo keeps float32 vertices
    root = etree.fromstring(xml.read_bytes())
    visual = [g for g in root.iter("geom") if g.get("contype") == "0"]
    assert visual and all(g.get("group") == "2" and g.get("conaffinity") == "0" for g in visual)
    collision = [g for g in root.iter("geom") if g.get("contype") != "0"]
    assert collision and all(g.get("group") == "3" for g in collision)
    meshes = {m.get("name") for m in root.iter("mesh")}
    assert {"base_00", "arm_00", "finger_00"} <= meshes
    # every link a body, the mimic joint an equality, the primitives as they were
    assert {model.body(b).name for b in range(model.nbody)} >= {"base", "frame_only", "arm", "tip"}
    assert model.neq == 1
    box = next(g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX)
    assert np.allclose(model.geom_size[box], [0.025, 0.03, 0.035])
    cylinder = next(
        g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER
    )
    from meshcol.io.robot import RobotOptions, load_robot

    tip = next(
        b for b in load_robot(urdf, RobotOptions(joints={"j1": joint})).bodies if b.name == "tip"
    )
    assert np.allclose(data.geom_xpos[cylinder], tip.pose[:3, 3], atol=1e-9)


def test_hull_mjcf_to_mjcf(mjcf: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, _, stderr = run("hull", str(mjcf), "--out-dir", str(out), "--max-vertices", "20")
    assert code == 0, stderr
    xml = out / "small.xml"
    assert sorted(p.name for p in out.iterdir()) == ["arm_00.obj", "base_00.obj", "small.xml"]
    for angle in (0.0, 0.4):
        _, expected = computed(mjcf, max_vertices=20, joints={"j": angle})
        found, model, _ = mujoco_parts(xml, {"j": angle})
        match_all(expected, found, 1e-6)
    root = etree.fromstring(xml.read_bytes())
    # the visual geom keeps the original mesh (file relative to OUT), in group 2
    body_mesh = next(m for m in root.iter("mesh") if m.get("name") == "body")
    assert (out / body_mesh.get("file")).resolve() == (
        mjcf.parent / "assets" / "body.stl"
    ).resolve()
    assert not any(m.get("name") == "arm" for m in root.iter("mesh"))  # no geom uses it now
    geoms = {g.get("name"): g for g in root.iter("geom") if g.get("name")}
    assert geoms["armcol"].get("mesh") == "arm_00"
    friction = [g for g in root.iter("geom") if g.get("mesh") == "base_00"]
    assert friction[0].get("friction") == "0.5 0.1 0.1"


# --- GLB and USD ----------------------------------------------------------------------------


def test_hull_glb_one_node_per_part(urdf: Path, tmp_path: Path) -> None:
    import trimesh

    out = tmp_path / "out"
    assert run("hull", str(urdf), "--out-dir", str(out), "--to", "glb", "--joint", "j1=0.3")[0] == 0
    scene = trimesh.load(out / "small.glb", force="scene")
    names = sorted(scene.graph.nodes_geometry)
    assert names == sorted(["base_00", "base_box1", "arm_00", "tip_cylinder0", "finger_00"])
    _, expected = computed(urdf, joints={"j1": 0.3})
    for link, parts in expected.items():
        v = np.asarray(scene.geometry[f"{link}_00"].vertices)
        assert same_points(parts[0], v, 1e-6)


def test_hull_usd_opens_with_physics_colliders(urdf: Path, tmp_path: Path) -> None:
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdPhysics

    out = tmp_path / "out"
    assert run("hull", str(urdf), "--out-dir", str(out), "--to", "usd", "--joint", "j1=0.3")[0] == 0
    stage = Usd.Stage.Open(str(out / "small.usda"))
    assert stage is not None
    _, expected = computed(urdf, joints={"j1": 0.3})
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 3
    cache = UsdGeom.XformCache()
    for prim in meshes:
        assert prim.HasAPI(UsdPhysics.CollisionAPI) and prim.HasAPI(UsdPhysics.MeshCollisionAPI)
        assert UsdPhysics.MeshCollisionAPI(prim).GetApproximationAttr().Get() == "convexHull"
        points = np.array(UsdGeom.Mesh(prim).GetPointsAttr().Get(), dtype=float)
        m = np.array(cache.GetLocalToWorldTransform(prim), dtype=float)  # row vectors
        world = points @ m[:3, :3] + m[3, :3]
        link = prim.GetParent().GetName()
        assert same_points(expected[link][0], world, 1e-6)
    cube = [p for p in stage.Traverse() if p.IsA(UsdGeom.Cube)]
    assert len(cube) == 1 and cube[0].HasAPI(UsdPhysics.CollisionAPI)


def test_usd_without_usd_core_exits_2(urdf: Path, tmp_path: Path, monkeypatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "pxr", None)
    out = tmp_path / "out"
    code, _, stderr = run("hull", str(urdf), "--out-dir", str(out), "--to", "usd")
    assert code == 2
    assert stderr == (
        f"meshcol: error: {urdf}: --to usd needs usd-core (pip install 'meshcol[usd]')\n"
    )
    assert not out.exists()


# --- bad input: exit 2, one line, nothing written ------------------------------------------


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t.replace("</robot>", ""), "malformed XML"),
        (
            lambda t: t.replace(
                'filename="meshes/arm.obj"', 'filename="package://nowhere/arm.obj"'
            ),
            "unknown package 'nowhere'",
        ),
        (lambda t: t.replace("meshes/arm.obj", "meshes/missing.obj"), "link 'arm': mesh file"),
    ],
)
@pytest.mark.parametrize("command", ["hull", "decompose"])
def test_bad_urdf_writes_nothing(urdf: Path, tmp_path: Path, edit, message, command) -> None:
    urdf.write_text(edit(ROBOT))
    out = tmp_path / "out"
    code, _, stderr = run(command, str(urdf), "--out-dir", str(out), "--to", "mjcf")
    assert code == 2
    assert stderr.startswith(f"meshcol: error: {urdf}") and message in stderr
    assert stderr.count("\n") == 1
    assert not out.exists()


def test_unreadable_mesh_and_rejected_mjcf(urdf: Path, mjcf: Path, tmp_path: Path) -> None:
    (urdf.parent / "meshes" / "arm.obj").write_text("this is not a mesh\n")
    code, _, stderr = run("hull", str(urdf), "--out-dir", str(tmp_path / "a"))
    assert code == 2 and "link 'arm'" in stderr and stderr.count("\n") == 1
    assert not (tmp_path / "a").exists()
    mjcf.write_text(MJCF.replace('type="hinge"', 'type="hinge" range="1 2 3"'))
    code, _, stderr = run("hull", str(mjcf), "--out-dir", str(tmp_path / "b"))
    assert code == 2 and "MuJoCo rejects it" in stderr and stderr.count("\n") == 1
    assert not (tmp_path / "b").exists()


def test_output_never_replaces_the_input(urdf: Path) -> None:
    before = urdf.read_text()
    code, _, stderr = run("hull", str(urdf), "--out-dir", str(urdf.parent))
    assert code == 2 and "would overwrite the input" in stderr
    assert urdf.read_text() == before
    assert not (urdf.parent / "base_00.obj").exists()


def test_to_needs_a_robot_and_mjcf_cannot_become_urdf(mjcf: Path, tmp_path: Path) -> None:
    code, _, stderr = run("hull", str(mjcf), "--to", "mjcf")
    assert code == 2 and "--to needs one robot description" in stderr
    code, _, stderr = run("hull", str(mjcf), "--out-dir", str(tmp_path / "o"), "--to", "urdf")
    assert code == 2 and "MJCF to URDF" in stderr
    assert not (tmp_path / "o").exists()


# --- the corpus Panda -----------------------------------------------------------------------


@pytest.fixture
def panda(corpus) -> Path:
    path = corpus / "robots" / "panda_description" / "urdf" / "panda.urdf"
    if not path.is_file():
        pytest.skip("corpus robots not present")
    return path


@pytest.mark.slow
def test_panda_hulls_urdf_and_mjcf(panda: Path, tmp_path: Path) -> None:
    import yourdfpy

    joints = {"panda_joint2": -0.5, "panda_joint4": -2.0, "panda_finger_joint1": 0.02}
    _, expected = computed(panda, max_vertices=64, joints=joints)
    assert len(expected) == 9
    out = tmp_path / "urdf"
    assert run("hull", str(panda), "--max-vertices", "64", "--out-dir", str(out))[0] == 0
    model = yourdfpy.URDF.load(
        str(out / "panda.urdf"), build_collision_scene_graph=True, load_collision_meshes=True
    )
    model.update_cfg(joints)
    scene = model.collision_scene
    meshes = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        meshes.append(
            np.asarray(scene.geometry[name].vertices) @ transform[:3, :3].T + transform[:3, 3]
        )
    for parts in expected.values():
        assert any(contains(v, parts[0], 1e-9) for v in meshes)

    mj = tmp_path / "mjcf"
    assert (
        run("hull", str(panda), "--max-vertices", "64", "--out-dir", str(mj), "--to", "mjcf")[0]
        == 0
    )
    qpos = dict(joints, panda_finger_joint2=0.02)
    found, model_mj, _ = mujoco_parts(mj / "panda.xml", qpos)
    match_all(expected, found, 1e-6)
    assert model_mj.nbody == 14  # world and every link, fixed ones included


@pytest.mark.slow
@pytest.mark.parametrize("name", ["solo.urdf", "solo12.urdf"])
def test_solo_hulls_to_mjcf(corpus, name: str, tmp_path: Path) -> None:
    path = corpus / "robots" / "solo_description" / "robots" / name
    if not path.is_file():
        pytest.skip("corpus robots not present")
    out = tmp_path / "out"
    code, _, stderr = run(
        "hull", str(path), "--max-vertices", "32", "--out-dir", str(out), "--to", "mjcf"
    )
    assert code == 0, stderr
    _, expected = computed(path, max_vertices=32)
    found, _, _ = mujoco_parts(out / path.with_suffix(".xml").name, {})
    match_all(expected, found, 1e-6)
