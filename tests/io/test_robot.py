"""Robot descriptions (URDF, MJCF) as scenes, and self-collision checks of them.

Hand-written descriptions cover each edge case; the corpus robots (Franka Panda, Solo) are
checked against independent computations: yourdfpy's own forward kinematics, MuJoCo's, and
python-fcl on the same convex hulls.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import itertools
import json
import math
import pickle
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from meshcol.analysis.check import check_scene
from meshcol.analysis.check_policy import CheckOptions
from meshcol.cli import main
from meshcol.errors import SceneError
from meshcol.io.robot import RobotOptions, is_robot_file, load_robot
from meshcol.io.scene import load_inputs
from meshcol.types import Box, Capsule, Cylinder, Sphere

pytest.importorskip("yourdfpy", reason="URDF reading needs yourdfpy (pip install meshcol[robots])")

CUBE_OBJ = """v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i = "xyz".index(axis)
    m = np.eye(4)
    j, k = (i + 1) % 3, (i + 2) % 3
    m[j, j], m[j, k], m[k, j], m[k, k] = c, -s, s, c
    return m


def trans(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def rpy(r: float, p: float, y: float) -> np.ndarray:
    return rot("z", y) @ rot("y", p) @ rot("x", r)


def urdf(body: str, name: str = "bot") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n{body}\n</robot>\n'


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def error_line(*args: str) -> str:
    code, _, err = run(*args)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("meshcol: error: "), err
    assert "Traceback" not in err
    return lines[0]


CHAIN = """
<link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="arm">
  <collision><origin xyz="0 0 0.5"/><geometry><cylinder radius="0.05" length="1"/></geometry></collision>
</link>
<link name="frame"/>
<link name="hand">
  <collision><origin xyz="0.1 0 0" rpy="0 1.5707963267948966 0"/><geometry><capsule radius="0.03" length="0.1"/></geometry></collision>
  <collision name="palm"><geometry><sphere radius="0.04"/></geometry></collision>
</link>
<joint name="shoulder" type="revolute">
  <parent link="base"/><child link="arm"/>
  <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/>
</joint>
<joint name="wrist_mount" type="fixed">
  <parent link="arm"/><child link="frame"/><origin xyz="0 0 1"/>
</joint>
<joint name="slide" type="prismatic">
  <parent link="frame"/><child link="hand"/>
  <origin xyz="0 0 0.05" rpy="0 0 1.5707963267948966"/><axis xyz="1 0 0"/>
  <limit lower="0" upper="0.2" effort="1" velocity="1"/>
</joint>
"""


def test_urdf_links_are_bodies_posed_by_forward_kinematics(tmp_path):
    path = write(tmp_path, "chain.urdf", urdf(CHAIN))
    scene = load_robot(path, RobotOptions(joints={"shoulder": 0.4, "slide": 0.15}))
    names = [b.name for b in scene.bodies]
    assert names == ["base", "arm", "hand"]  # 'frame' has no collision geometry
    base, arm, hand = scene.bodies
    # one primitive element: exact, posed at link pose x origin
    assert base.primitive == Box((0.2, 0.2, 0.2)) and base.parts == ()
    assert arm.primitive == Cylinder(0.05, 1.0)
    arm_link = trans(0, 0, 0.1) @ rpy(0.1, 0.2, 0.3) @ rot("y", 0.4)
    np.testing.assert_allclose(arm.pose, arm_link @ trans(0, 0, 0.5), atol=1e-12)
    # nested frames through the geometry-less 'frame' link; prismatic along its own x
    hand_link = arm_link @ trans(0, 0, 1) @ trans(0, 0, 0.05) @ rot("z", math.pi / 2)
    hand_link = hand_link @ trans(0.15, 0, 0)
    np.testing.assert_allclose(hand.pose, hand_link, atol=1e-12)
    # several elements: tessellated parts, in the link frame, origins baked in
    assert hand.primitive is None and hand.parts == ("capsule0", "palm")
    capsule = hand.vertices[: hand.faces[: hand.part_faces[1]].max() + 1]
    centre = 0.5 * (capsule.min(axis=0) + capsule.max(axis=0))
    np.testing.assert_allclose(centre, [0.1, 0, 0], atol=1e-9)
    extent = capsule.max(axis=0) - capsule.min(axis=0)
    np.testing.assert_allclose(extent, [0.16, 0.06, 0.06], atol=1e-3)  # along link x
    palm = hand.vertices[hand.faces[hand.part_faces[1] :].ravel()]
    np.testing.assert_allclose(np.linalg.norm(palm, axis=1), 0.04, atol=1e-9)
    # adjacency: the frame link without geometry does not hide arm-hand
    assert set(scene.excluded_pairs) == {("arm", "base", "adjacent"), ("arm", "hand", "adjacent")}
    assert scene.units == "m" and scene.source == str(path)


def test_capsule_exact_when_alone(tmp_path):
    text = urdf(
        '<link name="a"><collision><geometry><capsule radius="0.1" length="0.4"/></geometry>'
        "</collision></link>"
    )
    (body,) = load_robot(write(tmp_path, "c.urdf", text)).bodies
    assert body.primitive == Capsule(0.1, 0.4)


#: Two sibling links: ``pair``'s sphere (radius 0.1, at the link origin) beside a part given
#: by ``{other}``, and ``block``, a box of half size 0.1 centred at (0.5, 0.4, 0.3): the
#: sphere is sqrt(0.29) - 0.1 from it, along an oblique direction no tessellation vertex of
#: the sphere lies on. Their parent, ``root``, has a part far below (a link without geometry
#: would make them adjacent through it).
SPHERE_AND_BOX = """
<link name="root">
  <collision><origin xyz="0 0 -5"/><geometry><sphere radius="0.1"/></geometry></collision>
</link>
<link name="pair">
  <collision name="ball"><geometry><sphere radius="0.1"/></geometry></collision>
  {other}
</link>
<link name="block">
  <collision><origin xyz="0.5 0.4 0.3"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
</link>
<joint name="j1" type="fixed"><parent link="root"/><child link="pair"/></joint>
<joint name="j2" type="fixed"><parent link="root"/><child link="block"/></joint>
"""
FAR_CAPSULE = (
    '<collision name="rod"><origin xyz="-1 0 0" rpy="0 1.5707963267948966 0"/>'
    '<geometry><capsule radius="0.05" length="0.4"/></geometry></collision>'
)
FAR_MESH = '<collision name="cube"><origin xyz="-2 0 0"/><geometry><mesh filename="cube.obj"/></geometry></collision>'


@pytest.mark.parametrize("kind", ["hull", "decomposed", "fit", "box", "sphere", "mesh"])
def test_primitives_of_a_link_of_several_elements_are_exact(tmp_path, kind):
    """A link of several elements keeps each primitive element exact for the queries, under
    every collider kind (as a link of one primitive is): its tessellation, the body's
    triangles for outputs, missed the sphere's distance by about 1e-4 (MuJoCo's
    mj_geomDistance on gymnasium's humanoid showed it: tests/io/test_mjcf_oracle.py)."""
    path = write(tmp_path, "two.urdf", urdf(SPHERE_AND_BOX.format(other=FAR_CAPSULE)))
    scene = load_robot(path)
    pair = next(b for b in scene.bodies if b.name == "pair")
    assert pair.parts == ("ball", "rod") and pair.primitive is None
    assert [p.primitive for p in pair.part_primitives] == [Sphere(0.1), Capsule(0.05, 0.4)]
    np.testing.assert_allclose(
        pair.part_primitives[1].pose, trans(-1, 0, 0) @ rot("y", math.pi / 2)
    )
    report = check_scene(scene, CheckOptions(collider=kind, clearance=1.0))
    (row,) = report.pairs
    assert {row["body_a"], row["body_b"]} == {"pair", "block"}
    assert "ball" in (row["part_a"], row["part_b"])
    assert abs(row["signed_distance"] - (math.sqrt(0.29) - 0.1)) <= 1e-12
    (body,) = [b for b in report.bodies if b["name"] == "pair"]
    assert body["collider"] == "primitive" and body["convex_parts"] == 2


def test_a_link_of_a_mesh_and_a_primitive_keeps_the_primitive_exact(tmp_path):
    write(tmp_path, "cube.obj", CUBE_OBJ)
    path = write(tmp_path, "mixed.urdf", urdf(SPHERE_AND_BOX.format(other=FAR_MESH)))
    scene = load_robot(path)
    pair = next(b for b in scene.bodies if b.name == "pair")
    assert pair.part_primitives[0].primitive == Sphere(0.1) and pair.part_primitives[1] is None
    report = check_scene(scene, CheckOptions(clearance=1.0))
    (row,) = report.pairs
    assert abs(row["signed_distance"] - (math.sqrt(0.29) - 0.1)) <= 1e-12
    (body,) = [b for b in report.bodies if b["name"] == "pair"]
    assert body["collider"] == "hull" and body["convex_parts"] == 2
    # --shape mesh measures a mixed link on its triangles (the CHANGELOG's one exception):
    # the sphere's tessellation, inside the sphere, a little farther from the block
    (row,) = check_scene(scene, CheckOptions(collider="mesh", clearance=1.0)).pairs
    assert 0.0 < row["signed_distance"] - (math.sqrt(0.29) - 0.1) < 5e-4


def test_mimic_joint_follows_its_master(tmp_path):
    text = urdf("""
<link name="base"/><link name="left"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
<link name="right"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
<joint name="j1" type="prismatic"><parent link="base"/><child link="left"/><axis xyz="0 1 0"/>
  <limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
<joint name="j2" type="prismatic"><parent link="base"/><child link="right"/><axis xyz="0 1 0"/>
  <limit lower="-0.2" upper="0.2" effort="1" velocity="1"/>
  <mimic joint="j1" multiplier="-2" offset="0.01"/></joint>""")
    path = write(tmp_path, "mimic.urdf", text)
    left, right = load_robot(path, RobotOptions(joints={"j1": 0.03})).bodies
    np.testing.assert_allclose(left.pose[:3, 3], [0, 0.03, 0], atol=1e-12)
    np.testing.assert_allclose(right.pose[:3, 3], [0, -2 * 0.03 + 0.01, 0], atol=1e-12)
    line = error_line("check", str(path), "--joint", "j2=0.01")
    assert "mimic.urdf" in line and "'j2'" in line and "mimics joint 'j1'" in line


def test_mesh_scale_and_relative_path(tmp_path):
    write(tmp_path, "meshes/cube.obj", CUBE_OBJ)
    text = urdf(
        '<link name="a"><collision><origin xyz="1 0 0"/><geometry>'
        '<mesh filename="../meshes/cube.obj" scale="2 1 -0.5"/></geometry></collision></link>'
    )
    (body,) = load_robot(write(tmp_path, "urdf/m.urdf", text)).bodies
    np.testing.assert_allclose(body.vertices.min(axis=0), [0, -0.5, -0.25])
    np.testing.assert_allclose(body.vertices.max(axis=0), [2, 0.5, 0.25])
    # the mirror (negative scale) keeps outward winding: a positive volume
    v, f = body.vertices, body.faces
    volume = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6
    assert volume == pytest.approx(2 * 1 * 0.5)


def test_package_uris(tmp_path, monkeypatch):
    write(tmp_path, "ws/src/my_robot/meshes/cube.obj", CUBE_OBJ)
    text = urdf(
        '<link name="a"><collision><geometry><mesh filename="package://my_robot/meshes/cube.obj"/>'
        "</geometry></collision></link>"
    )
    # the folder layout: the description sits inside the package's folder
    inside = write(tmp_path, "ws/src/my_robot/urdf/r.urdf", text)
    assert len(load_robot(inside).bodies) == 1
    # elsewhere: unknown until --package-path or ROS_PACKAGE_PATH names the folder
    outside = write(tmp_path, "elsewhere/r.urdf", text)
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    line = error_line("check", str(outside))
    assert "r.urdf" in line and "link 'a'" in line and "unknown package 'my_robot'" in line
    pkg = str(tmp_path / "ws/src/my_robot")
    code, _, err = run("check", str(outside), "--package-path", f"my_robot={pkg}")
    assert code == 0, err
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws/src"))
    assert len(load_robot(outside).bodies) == 1


def test_a_package_uri_of_a_file_alone_is_the_file_beside_the_description(tmp_path):
    """``package://cube.obj`` (no folder after the package: Genesis's wheel.urdf) is read as
    pybullet reads it, the file ``cube.obj`` beside the description; a file that is not
    there is still an unknown package."""
    write(tmp_path, "wheel/cube.obj", CUBE_OBJ)
    mesh = '<link name="a"><collision><geometry><mesh filename="package://{}"/></geometry></collision></link>'
    path = write(tmp_path, "wheel/w.urdf", urdf(mesh.format("cube.obj")))
    (body,) = load_robot(path).bodies
    assert body.vertices.shape == (8, 3)
    missing = write(tmp_path, "wheel/m.urdf", urdf(mesh.format("gone.obj")))
    assert "unknown package 'gone.obj'" in error_line("check", str(missing))
    pybullet = pytest.importorskip("pybullet", reason="pybullet reads the file too (robots-wild)")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        shapes = pybullet.getCollisionShapeData(
            pybullet.loadURDF(str(path), physicsClientId=client), -1, physicsClientId=client
        )
        assert shapes[0][4].decode().endswith("cube.obj")
    finally:
        pybullet.disconnect(client)


@pytest.mark.parametrize(
    "body, words",
    [
        ("<link name='a'><collision>", ["malformed XML", "line"]),
        (
            "<link name='a'/><joint name='j' type='fixed'><parent link='nowhere'/>"
            "<child link='a'/></joint>",
            ["joint 'j'", "parent link 'nowhere' does not exist"],
        ),
        (
            "<link name='a'/><link name='b'/><link name='c'/>"
            "<joint name='ab' type='fixed'><parent link='a'/><child link='b'/></joint>"
            "<joint name='bc' type='fixed'><parent link='b'/><child link='c'/></joint>"
            "<joint name='ca' type='fixed'><parent link='c'/><child link='a'/></joint>",
            ["joint cycle", "'ab'", "'bc'", "'ca'"],
        ),
        (
            "<link name='a'><collision><geometry><mesh filename='missing.stl'/></geometry>"
            "</collision></link>",
            ["link 'a'", "mesh file 'missing.stl' not found"],
        ),
        (
            "<link name='a'><collision><geometry><mesh filename='package://nopkg/x.stl'/>"
            "</geometry></collision></link>",
            ["link 'a'", "unknown package 'nopkg'"],
        ),
        (
            "<link name='a'><collision><geometry><sphere radius='-1'/></geometry></collision>"
            "</link>",
            ["link 'a'", "sphere radius"],
        ),
    ],
)
def test_bad_urdf_is_one_line_exit_2(tmp_path, monkeypatch, body, words):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    path = write(tmp_path, "bad.urdf", urdf(body))
    line = error_line("check", str(path))
    assert "bad.urdf" in line
    for word in words:
        assert word in line, line


def test_unreadable_mesh_names_link(tmp_path):
    write(tmp_path, "broken.stl", "solid x\nfacet normal 0 0 1\n outer loop\n")
    text = urdf(
        '<link name="arm"><collision><geometry><mesh filename="broken.stl"/></geometry>'
        "</collision></link>"
    )
    line = error_line("check", str(write(tmp_path, "r.urdf", text)))
    assert "r.urdf" in line and "link 'arm'" in line and "broken.stl" in line


def test_joint_values_checked(tmp_path):
    path = write(tmp_path, "chain.urdf", urdf(CHAIN))
    line = error_line("check", str(path), "--joint", "shoulder=1.5")
    assert "chain.urdf" in line and "joint 'shoulder'" in line and "outside its limits" in line
    assert "[-1, 1]" in line
    assert "joint 'elbow' does not exist" in error_line("check", str(path), "--joint", "elbow=0")
    assert "is fixed" in error_line("check", str(path), "--joint", "wrist_mount=0")
    assert "NAME=VALUE" in error_line("check", str(path), "--joint", "shoulder")
    assert "a URDF has no keyframes" in error_line("check", str(path), "--keyframe")
    joints = write(tmp_path, "q.json", json.dumps({"shoulder": 0.5, "slide": 0.1}))
    code, out, err = run("check", str(path), "--joints", str(joints), "--joint", "slide=0.2")
    assert code in (0, 1), err
    expected = load_inputs(
        [path], robot_options=RobotOptions(joints={"shoulder": 0.5, "slide": 0.2})
    )
    file_only = load_inputs(
        [path], robot_options=RobotOptions(joints={"shoulder": 0.5, "slide": 0.1})
    )

    def hand_box(report: dict) -> np.ndarray:
        return np.array(next(b["aabb"] for b in report["bodies"] if b["name"] == "hand"))

    got = hand_box(json.loads(out))
    np.testing.assert_allclose(got, hand_box(check_scene(expected).to_dict()), atol=1e-12)
    assert not np.allclose(got, hand_box(check_scene(file_only).to_dict()))


def test_robot_options_are_checked_when_made_and_never_change():
    joints = {"a": 1, "b": np.float32(0.5)}
    options = RobotOptions(joints=joints, package_paths={"p": Path("/x")}, srdf=Path("s.srdf"))
    joints["a"] = 2.0  # the options hold a copy
    assert dict(options.joints) == {"a": 1.0, "b": 0.5}
    assert all(type(v) is float for v in options.joints.values())
    assert dict(options.package_paths) == {"p": "/x"} and options.srdf == "s.srdf"
    with pytest.raises(TypeError):
        options.joints["a"] = 3.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.keyframe = True
    assert pickle.loads(pickle.dumps(options)) == options  # they travel to worker processes
    assert dataclasses.replace(options, keyframe=True).joints == options.joints
    for bad, message in [
        ({"a": math.nan}, "joint 'a': value must be finite, got nan"),
        ({"a": math.inf}, "joint 'a': value must be finite, got inf"),
        ({"a": "1"}, "joint 'a': value must be a number, got '1'"),
        ({"a": True}, "joint 'a': value must be a number, got True"),
        ({1: 0.0}, "joint name must be a string, got 1"),
    ]:
        with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
            RobotOptions(joints=bad)
    with pytest.raises(ValueError, match="package name must be a non-empty string"):
        RobotOptions(package_paths={"": "/x"})
    with pytest.raises(ValueError, match="package 'p': folder must be a non-empty path"):
        RobotOptions(package_paths={"p": ""})
    with pytest.raises(TypeError, match="keyframe must be True or False, got 1"):
        RobotOptions(keyframe=1)


@pytest.mark.parametrize(
    "function",
    [
        "meshcol.io.scene:load_inputs",
        "meshcol.io.scene:iter_inputs",
        "meshcol.io.scene:as_scene",
        "meshcol.analysis.check:check",
        "meshcol.analysis.sweep:sweep",
        "meshcol.analysis.inspect:inspect",
        "meshcol.analysis.hull:hull",
        "meshcol.analysis.fit:fit",
        "meshcol.analysis.collision_matrix:collision_matrix",
        "meshcol.analysis.rebuild:robot_colliders",
        "meshcol.analysis.rebuild:rebuild_hulls",
        "meshcol.analysis.rebuild:rebuild_decomposition",
        "meshcol.analysis.rebuild:rebuild_fits",
        "meshcol.decomposition.batch:decompose_files",
    ],
)
def test_every_entry_point_that_reads_a_robot_takes_its_options(function):
    module, name = function.split(":")
    parameter = inspect.signature(getattr(importlib.import_module(module), name)).parameters
    assert parameter["robot_options"].default is None


def test_robot_options_reach_the_library_as_an_argument(tmp_path):
    from meshcol.analysis.check import check

    path = write(tmp_path, "chain.urdf", urdf(CHAIN))
    options = RobotOptions(joints={"shoulder": 0.5}, include_adjacent=True)
    report = check([path], robot_options=options)
    default = check([path])
    assert report.summary["excluded_pairs"] == 0 < default.summary["excluded_pairs"]

    def arm_pose(scene) -> np.ndarray:
        return next(b.pose for b in scene.bodies if b.name == "arm")

    moved = arm_pose(load_inputs([path], robot_options=options))
    assert not np.allclose(moved, arm_pose(load_inputs([path])))


def test_zero_outside_limits_is_the_middle_of_the_limits_with_a_warning(tmp_path):
    """MoveIt's default configuration (issue 29, item 9): the one collision-matrix uses."""
    text = urdf(
        "<link name='a'/><link name='b'><collision><geometry><sphere radius='0.1'/></geometry>"
        "</collision></link><joint name='j' type='prismatic'><parent link='a'/><child link='b'/>"
        "<axis xyz='1 0 0'/><limit lower='0.5' upper='1' effort='1' velocity='1'/></joint>"
    )
    scene = load_robot(write(tmp_path, "z.urdf", text))
    np.testing.assert_allclose(scene.bodies[0].pose[:3, 3], [0.75, 0, 0])
    assert any("zero is outside its limits" in w and "middle, 0.75" in w for w in scene.warnings)


TOUCHING = """
<link name="base"><collision><geometry><box size="1 1 1"/></geometry></collision></link>
<link name="a"><collision><geometry><box size="1 1 1"/></geometry></collision></link>
<link name="b"><collision name="left"><origin xyz="0 -5 0"/><geometry><sphere radius="0.1"/></geometry></collision>
  <collision name="right"><origin xyz="-0.1 0 0"/><geometry><sphere radius="0.3"/></geometry></collision></link>
<joint name="ja" type="fixed"><parent link="base"/><child link="a"/><origin xyz="0.5 0 0"/></joint>
<joint name="jb" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 0"/></joint>
"""


def test_check_self_collision_adjacency_and_srdf(tmp_path):
    path = write(tmp_path, "t.urdf", urdf(TOUCHING))
    # base-a and a-b are adjacent (left out); base-b is not: b's 'right' sphere reaches base
    code, out, err = run("check", str(path))
    report = json.loads(out)
    assert code == 1, err
    assert [(p["body_a"], p["body_b"]) for p in report["pairs"]] == [("base", "b")]
    (pair,) = report["pairs"]
    assert pair["part_b"] == "right" and pair["part_a"] is None
    assert pair["status"] == "penetrating" and pair["depth"] == pytest.approx(0.4, abs=0.02)
    assert "base <-> b/right (FAIL)" in err and "1 candidate pair, 2 excluded" in err
    assert report["summary"]["excluded_pairs"] == 2
    assert {
        (e["body_a"], e["body_b"], e["reason"]) for e in report["settings"]["excluded_pairs"]
    } == {
        ("a", "base", "adjacent"),
        ("a", "b", "adjacent"),
    }
    # --include-adjacent: every overlapping pair
    code, out, _ = run("check", str(path), "--include-adjacent")
    pairs = {tuple(sorted((p["body_a"], p["body_b"]))) for p in json.loads(out)["pairs"]}
    assert pairs == {("a", "base"), ("a", "b"), ("b", "base")}
    # an SRDF disabling base-b: passes
    srdf = write(
        tmp_path,
        "t.srdf",
        '<robot name="bot"><disable_collisions link1="base" link2="b" reason="Never"/>'
        '<disable_collisions link1="base" link2="ghost" reason="Never"/></robot>',
    )
    code, out, err = run("check", str(path), "--srdf", str(srdf))
    report = json.loads(out)
    assert code == 0, err
    assert report["pairs"] == [] and report["summary"]["excluded_pairs"] == 3
    assert ("b", "base", "srdf: Never") in {
        (e["body_a"], e["body_b"], e["reason"]) for e in report["settings"]["excluded_pairs"]
    }
    assert "'ghost'" in err and "warning" in err
    bad = write(tmp_path, "bad.srdf", "<robot><disable_collisions link1='a'></robot>")
    assert "bad.srdf" in error_line("check", str(path), "--srdf", str(bad))


def test_excluded_mask_is_applied_to_any_scene():
    """check_scene leaves out a scene's excluded pairs whatever made the scene."""
    from meshcol.types import Body, Scene

    def cube(name, x):
        v = np.array(list(itertools.product([-0.5, 0.5], repeat=3)), dtype=float)
        hull = ConvexHull(v)
        pose = trans(x, 0, 0)
        return Body(name=name, source=None, vertices=v, faces=hull.simplices, pose=pose)

    bodies = tuple(cube(f"c{i}", 0.9 * i) for i in range(5))  # each overlaps its neighbours
    full = check_scene(Scene(bodies=bodies))
    assert full.summary["candidate_pairs"] == 4
    excluded = (("c1", "c2", "x"), ("c3", "c4", "y"), ("c0", "c4", "far apart anyway"))
    some = check_scene(Scene(bodies=bodies, excluded_pairs=excluded))
    assert {(p["body_a"], p["body_b"]) for p in some.pairs} == {("c0", "c1"), ("c2", "c3")}
    assert some.summary["excluded_pairs"] == 2
    for a, b in (("c0", "c1"), ("c2", "c3")):
        want = next(p for p in full.pairs if (p["body_a"], p["body_b"]) == (a, b))
        got = next(p for p in some.pairs if (p["body_a"], p["body_b"]) == (a, b))
        assert got["signed_distance"] == pytest.approx(want["signed_distance"])


def test_robot_file_detection(tmp_path):
    assert is_robot_file(write(tmp_path, "a.xml", "<?xml version='1.0'?>\n<!-- x -->\n<mujoco/>"))
    assert is_robot_file(write(tmp_path, "b.xml", "<robot name='x'/>"))
    assert not is_robot_file(write(tmp_path, "c.xml", "<scene/>"))
    assert is_robot_file(tmp_path / "d.urdf")
    path = write(tmp_path, "r.urdf", urdf(CHAIN))
    line = error_line("check", str(path), str(path))
    assert "robot description cannot be combined" in line


def test_every_scene_command_takes_a_robot(tmp_path):
    path = write(tmp_path, "chain.urdf", urdf(CHAIN))
    for command in (["hull"], ["inspect"]):
        code, out, err = run(*command, str(path), "--joint", "shoulder=0.2", "--report", "-")
        assert code in (0, 1), err
        assert "hand" in out


# --- MJCF -------------------------------------------------------------------------------------

MJCF = """<mujoco model="m">
  <compiler angle="radian"/>
  <default>
    <default class="link"><geom type="capsule" size="0.05 0.2"/></default>
  </default>
  <include file="parts.xml"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="base" pos="0 0 0.5">
      <geom name="base_box" type="box" size="0.1 0.2 0.3"/>
      <body name="upper" pos="0 0 0.3" euler="0 0 0.5">
        <joint name="hinge" type="hinge" axis="0 1 0" range="-1 1" limited="true"/>
        <geom class="link" name="upper_geom" pos="0 0 0.25"/>
        <geom name="visual" type="sphere" size="0.5" contype="0" conaffinity="0"/>
        <body name="lower" pos="0 0 0.5">
          <joint name="slider" type="slide" axis="1 0 0" range="0 0.3"/>
          <geom name="lower_a" type="sphere" size="0.05"/>
          <geom name="lower_b" type="mesh" mesh="cube" pos="0.2 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <contact><exclude body1="base" body2="lower"/></contact>
  <keyframe><key name="bent" qpos="0.7 0.1"/></keyframe>
</mujoco>
"""

PARTS = (
    """<mujoco><asset><mesh name="cube" file="cube.obj" scale="0.1 0.1 0.1"/></asset></mujoco>"""
)


@pytest.fixture
def mjcf(tmp_path) -> Path:
    pytest.importorskip("mujoco", reason="MJCF reading needs mujoco (pip install meshcol[robots])")
    write(tmp_path, "cube.obj", CUBE_OBJ)
    write(tmp_path, "parts.xml", PARTS)
    return write(tmp_path, "m.xml", MJCF)


def test_mjcf_bodies_posed_by_mujoco(mjcf):
    scene = load_robot(mjcf, RobotOptions(joints={"hinge": 0.3}))
    base, upper, lower = scene.bodies
    assert [b.name for b in scene.bodies] == ["base", "upper", "lower"]  # floor plane skipped
    assert base.primitive == Box((0.2, 0.4, 0.6))
    np.testing.assert_allclose(base.pose, trans(0, 0, 0.5), atol=1e-12)
    # the default class gives the capsule its size; the contype=0 sphere is not collision
    assert upper.primitive == Capsule(0.05, 0.4)
    upper_frame = trans(0, 0, 0.8) @ rot("z", 0.5) @ rot("y", 0.3)
    np.testing.assert_allclose(upper.pose, upper_frame @ trans(0, 0, 0.25), atol=1e-9)
    # the included mesh asset, scaled by MuJoCo, as the second part of 'lower'
    assert lower.parts == ("lower_a", "lower_b")
    np.testing.assert_allclose(lower.pose, upper_frame @ trans(0, 0, 0.5), atol=1e-9)
    cube = lower.vertices[lower.faces[lower.part_faces[1] :].ravel()]
    np.testing.assert_allclose(cube.min(axis=0), [0.15, -0.05, -0.05], atol=1e-9)
    assert set(scene.excluded_pairs) == {
        ("base", "upper", "adjacent"),
        ("lower", "upper", "adjacent"),
        ("base", "lower", "mjcf <exclude>"),
    }


def test_mjcf_keyframe_and_limits(mjcf):
    scene = load_robot(mjcf, RobotOptions(keyframe=True))
    upper_frame = trans(0, 0, 0.8) @ rot("z", 0.5) @ rot("y", 0.7)
    np.testing.assert_allclose(
        scene.bodies[2].pose, upper_frame @ trans(0, 0, 0.5) @ trans(0.1, 0, 0), atol=1e-9
    )
    line = error_line("check", str(mjcf), "--joint", "hinge=2")
    assert "m.xml" in line and "joint 'hinge'" in line and "outside its limits [-1, 1]" in line
    assert "joint 'nope' does not exist" in error_line("check", str(mjcf), "--joint", "nope=0")


def test_a_keyframe_past_a_limit_is_checked_where_mujoco_starts(mjcf):
    """A keyframe is the model's own data and MuJoCo starts from it even past a joint's
    limits (Menagerie's tetheria hand: 0.0026 rad past a finger's), so --keyframe keeps the
    value with a warning; a value given past a limit is still refused, keyframe or not."""
    import mujoco

    text = mjcf.read_text().replace('qpos="0.7 0.1"', 'qpos="1.2 0.1"')
    mjcf.write_text(text)
    scene = load_robot(mjcf, RobotOptions(keyframe=True))
    assert any(
        "joint 'hinge': the keyframe's value 1.2 is outside its limits [-1, 1]" in w
        for w in scene.warnings
    )
    model = mujoco.MjModel.from_xml_path(str(mjcf))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    lower = model.body("lower").id
    (body,) = [b for b in scene.bodies if b.name == "lower"]
    np.testing.assert_allclose(body.pose[:3, 3], data.xpos[lower], atol=1e-12)
    np.testing.assert_allclose(body.pose[:3, :3], data.xmat[lower].reshape(3, 3), atol=1e-12)
    line = error_line("check", str(mjcf), "--keyframe", "--joint", "slider=0.5")
    assert "joint 'slider'" in line and "outside its limits [0, 0.3]" in line
    code, _, err = run("check", str(mjcf), "--keyframe")
    assert code in (0, 1) and "the keyframe's value 1.2" in err


def test_mjcf_mujoco_rejects(tmp_path):
    pytest.importorskip("mujoco")
    path = write(
        tmp_path,
        "bad.xml",
        '<mujoco><worldbody><body name="a"><geom type="sphere" size="0.1"/>'
        '<joint name="j" type="wobble"/></body></worldbody></mujoco>',
    )
    line = error_line("check", str(path))
    assert "bad.xml" in line and "MuJoCo rejects it" in line and "wobble" in line


# --- the corpus robots ----------------------------------------------------------------------


@pytest.fixture
def panda(corpus) -> Path:
    path = corpus / "robots" / "panda_description" / "urdf" / "panda.urdf"
    if not path.is_file():
        pytest.skip("corpus robots not present")
    return path


def _yourdfpy_poses(path: Path, cfg: dict[str, float]) -> dict[str, np.ndarray]:
    import yourdfpy

    model = yourdfpy.URDF.load(
        str(path), build_scene_graph=True, load_meshes=False, filename_handler=lambda fname: fname
    )
    model.update_cfg(cfg)
    return {link: model.get_transform(link, model.base_link) for link in model.link_map}


def test_panda_forward_kinematics_matches_yourdfpy(panda):
    import yourdfpy

    model = yourdfpy.URDF.load(str(panda), build_scene_graph=False, load_meshes=False)
    rng = np.random.default_rng(7)
    for _ in range(5):
        cfg = {}
        for name in model.actuated_joint_names:
            limit = model.joint_map[name].limit
            cfg[name] = float(rng.uniform(limit.lower, limit.upper))
        scene = load_robot(panda, RobotOptions(joints=cfg))
        expected = _yourdfpy_poses(panda, cfg)
        assert len(scene.bodies) == 11
        for body in scene.bodies:
            np.testing.assert_allclose(body.pose, expected[body.name], atol=1e-9)
        # the mimic finger follows panda_finger_joint1 (yourdfpy's own mimic handling)
        right = next(b for b in scene.bodies if b.name == "panda_rightfinger")
        np.testing.assert_allclose(right.pose, expected["panda_rightfinger"], atol=1e-9)


def _fcl_colliding(scene, excluded: set[tuple[str, str]]) -> set[tuple[str, str]]:
    """Link pairs whose convex hulls intersect, by python-fcl (every pair, no broad phase)."""
    fcl = pytest.importorskip("fcl")
    objects = {}
    for body in scene.bodies:
        hull = ConvexHull(body.vertices)  # scipy's qhull: independent of meshcol's hulls
        faces = np.hstack([np.full((len(hull.simplices), 1), 3), hull.simplices]).ravel()
        shape = fcl.Convex(body.vertices, len(hull.simplices), faces)
        objects[body.name] = fcl.CollisionObject(
            shape, fcl.Transform(body.pose[:3, :3], body.pose[:3, 3])
        )
    found = set()
    for a, b in itertools.combinations(sorted(objects), 2):
        if (a, b) in excluded:
            continue
        result = fcl.CollisionResult()
        if fcl.collide(objects[a], objects[b], fcl.CollisionRequest(), result):
            found.add((a, b))
    return found


def test_panda_self_collision_matches_fcl(panda):
    srdf = panda.parent.parent / "srdf" / "panda.srdf"
    for srdf_file in (None, srdf):
        scene = load_robot(panda, RobotOptions(srdf=None if srdf_file is None else str(srdf_file)))
        report = check_scene(scene)
        ours = {
            tuple(sorted((p["body_a"], p["body_b"])))
            for p in report.pairs
            if p["status"] in ("contact", "penetrating", "contained")
        }
        excluded = {(a, b) for a, b, _ in scene.excluded_pairs}
        excluded |= {(b, a) for a, b in excluded}
        assert ours == {tuple(sorted(p)) for p in _fcl_colliding(scene, excluded)}
        if srdf_file is None:
            # hulls: the wrist (link5) reaches the hand and link7; the closed fingers touch.
            # MoveIt's setup assistant marked exactly these "Default" (in collision at the
            # default configuration) in the SRDF.
            assert ours == {
                ("panda_hand", "panda_link5"),
                ("panda_link5", "panda_link7"),
                ("panda_leftfinger", "panda_rightfinger"),
            }
            default = {
                tuple(sorted(m.groups()[:2]))
                for m in re.finditer(
                    r'link1="([^"]+)" link2="([^"]+)" reason="(Default)"', srdf.read_text()
                )
            }
            assert ours == default
        else:
            assert ours == set() and report.passed  # MoveIt's matrix disables all of those


def test_panda_cli_with_srdf_passes(panda):
    srdf = panda.parent.parent / "srdf" / "panda.srdf"
    code, out, err = run("check", str(panda), "--srdf", str(srdf))
    assert code == 0, err
    report = json.loads(out)
    assert report["summary"]["bodies"] == 11
    assert "panda_joint4" in err  # zero is outside its limits: the warning says where it is


def test_solo_loads_obj_meshes(corpus):
    path = corpus / "robots" / "solo_description" / "robots" / "solo.urdf"
    if not path.is_file():
        pytest.skip("corpus robots not present")
    scene = load_robot(path)
    assert len(scene.bodies) == 13
    assert all(len(b.faces) > 100 for b in scene.bodies)
    expected = _yourdfpy_poses(path, {})
    for body in scene.bodies:
        np.testing.assert_allclose(body.pose, expected[body.name], atol=1e-9)


def test_panda_as_mjcf_matches_urdf_kinematics(panda, tmp_path):
    """The same arm written as MJCF (primitives at the URDF's joint origins): MuJoCo's
    kinematics and ours agree link by link."""
    mujoco = pytest.importorskip("mujoco")
    import yourdfpy

    model = yourdfpy.URDF.load(str(panda), build_scene_graph=False, load_meshes=False)
    chain = [model.joint_map[f"panda_joint{i}"] for i in range(1, 8)]
    xml, close = [], []
    for joint in chain:
        t = joint.origin
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(t[:3, :3]).ravel())
        lo, hi = joint.limit.lower, joint.limit.upper
        xml.append(
            f'<body name="{joint.child}" pos="{" ".join(map(str, t[:3, 3]))}" '
            f'quat="{" ".join(map(str, quat))}"><joint name="{joint.name}" axis="0 0 1" '
            f'range="{lo} {hi}"/><geom type="sphere" size="0.05"/>'
        )
        close.append("</body>")
    text = (
        '<mujoco><compiler angle="radian"/><worldbody>'
        + "".join(xml)
        + "".join(close)
        + "</worldbody></mujoco>"
    )
    path = write(tmp_path, "arm.xml", text)
    cfg = {j.name: 0.5 * (j.limit.lower + j.limit.upper) + 0.1 for j in chain}
    ours = {b.name: b.pose for b in load_robot(path, RobotOptions(joints=cfg)).bodies}
    expected = _yourdfpy_poses(panda, cfg)
    base = expected["panda_link0"]
    for name, pose in ours.items():
        np.testing.assert_allclose(pose, np.linalg.inv(base) @ expected[name], atol=1e-6)


def test_scene_error_type(tmp_path):
    with pytest.raises(SceneError, match="joint cycle"):
        load_robot(
            write(
                tmp_path,
                "cyc.urdf",
                urdf(
                    "<link name='a'/><link name='b'/>"
                    "<joint name='x' type='fixed'><parent link='a'/><child link='b'/></joint>"
                    "<joint name='y' type='fixed'><parent link='b'/><child link='a'/></joint>"
                ),
            )
        )


def test_collada_collision_meshes(panda, tmp_path):
    """A DAE collision mesh (pycollada) is read in the same frame and units as the STL."""
    pytest.importorskip("collada", reason="COLLADA meshes need pycollada")
    meshes = panda.parent.parent / "meshes"
    links = "".join(
        f'<link name="{kind}"><collision><geometry><mesh filename="{meshes / kind / name}"/>'
        "</geometry></collision></link>"
        for kind, name in (("visual", "link3.dae"), ("collision", "link3.stl"))
    )
    joint = '<joint name="j" type="fixed"><parent link="visual"/><child link="collision"/></joint>'
    dae, stl = load_robot(write(tmp_path, "dae.urdf", urdf(links + joint))).bodies
    assert len(dae.parts) > 1  # the DAE's objects are the link's parts
    np.testing.assert_allclose(dae.vertices.min(axis=0), stl.vertices.min(axis=0), atol=2e-3)
    np.testing.assert_allclose(dae.vertices.max(axis=0), stl.vertices.max(axis=0), atol=2e-3)


def test_mjcf_equality_joint_is_a_mimic(tmp_path):
    pytest.importorskip("mujoco")
    text = """<mujoco><worldbody>
      <body name="left"><joint name="a" type="slide" axis="0 1 0" range="0 0.04"/>
        <geom type="sphere" size="0.01"/></body>
      <body name="right"><joint name="b" type="slide" axis="0 1 0" range="-0.2 0.2"/>
        <geom type="sphere" size="0.01"/></body>
    </worldbody>
    <equality><joint joint1="b" joint2="a" polycoef="0.01 -2 0 0 0"/></equality></mujoco>"""
    path = write(tmp_path, "eq.xml", text)
    left, right = load_robot(path, RobotOptions(joints={"a": 0.03})).bodies
    np.testing.assert_allclose(left.pose[:3, 3], [0, 0.03, 0], atol=1e-12)
    np.testing.assert_allclose(right.pose[:3, 3], [0, 0.01 - 2 * 0.03, 0], atol=1e-12)
    line = error_line("check", str(path), "--joint", "b=0")
    assert "eq.xml" in line and "joint 'b' follows joint 'a'" in line


def test_mjcf_qpos0_outside_limits_is_the_middle_of_the_limits(tmp_path):
    pytest.importorskip("mujoco")
    text = """<mujoco><worldbody><body name="a">
      <joint name="s" type="slide" axis="1 0 0" range="0.5 1"/><geom type="sphere" size="0.1"/>
    </body></worldbody></mujoco>"""
    scene = load_robot(write(tmp_path, "q.xml", text))
    np.testing.assert_allclose(scene.bodies[0].pose[:3, 3], [0.75, 0, 0])
    assert any("qpos0 0 is outside its limits [0.5, 1]" in w for w in scene.warnings)


@pytest.mark.parametrize(
    "text, words",
    [
        ("", ["malformed XML"]),
        ("<mesh/>", ["not a URDF", "<mesh>"]),
        (urdf("<link name='a'><collision><geometry/></collision></link>"), ["invalid URDF"]),
        (urdf("<link name='a'/><link name='a'/>"), ["link 'a'", "earlier link"]),
        (
            urdf(
                "<link name='a'/><link name='b'/><link name='c'/>"
                "<joint name='x' type='fixed'><parent link='a'/><child link='c'/></joint>"
                "<joint name='y' type='fixed'><parent link='b'/><child link='c'/></joint>"
            ),
            ["link 'c' is the child of two joints", "'x'", "'y'"],
        ),
        (urdf("<link name='a'/><link name='b'/>"), ["several root links", "'a'", "'b'"]),
        (
            urdf(
                "<link name='a'><collision><geometry><mesh filename='x.obj' scale='1 0 1'/>"
                "</geometry></collision></link>"
            ),
            ["link 'a'", "mesh scale"],
        ),
        (
            urdf(
                "<link name='a'><collision><origin xyz='nan 0 0'/><geometry>"
                "<sphere radius='1'/></geometry></collision></link>"
            ),
            ["link 'a'", "not finite"],
        ),
        (
            urdf(
                "<link name='a'/><link name='b'><collision><geometry><sphere radius='1'/>"
                "</geometry></collision></link><joint name='j' type='fixed'><parent link='a'/>"
                "<child link='b'/><origin xyz='1e300 0 0'/></joint>"
            ),
            ["link 'b'", "beyond the limit"],
        ),
    ],
)
def test_hostile_urdf(tmp_path, text, words):
    path = write(tmp_path, "h.urdf", text)
    line = error_line("check", str(path))
    assert "h.urdf" in line
    for word in words:
        assert word in line, line


def test_a_robot_without_links_or_name(tmp_path):
    # Issue 29: example-robot-data's ur3.urdf is an empty <robot> without a name (xacro's
    # output of a macro file); yourdfpy's words were "invalid URDF: 'name'".
    empty = write(tmp_path, "ur3.urdf", '<robot xmlns:xacro="http://wiki.ros.org/xacro"></robot>')
    assert error_line("check", str(empty)).endswith("ur3.urdf: the robot has no <link> element")
    box = "<link name='a'><collision><geometry><box size='1 1 1'/></geometry></collision></link>"
    scene = load_robot(write(tmp_path, "anon.urdf", f"<robot>{box}</robot>"))
    assert [b.name for b in scene.bodies] == ["a"]
    assert "the <robot> element has no name: named after the file" in scene.warnings


def test_a_mimic_of_a_missing_joint_is_ignored_with_a_warning(tmp_path):
    # Issue 29: alex_psyonic_hands (example-robot-data) names a joint that does not exist in a
    # <mimic>; pybullet never reads mimics and yourdfpy only logs it: both load the robot.
    # Before, meshcol refused it ("mimics joint 'ghost', which does not exist").
    text = urdf(
        "<link name='a'><collision><geometry><box size='1 1 1'/></geometry></collision></link>"
        "<link name='b'><collision><origin xyz='0 3 0'/><geometry><box size='1 1 1'/>"
        "</geometry></collision></link><joint name='m' type='revolute'><parent link='a'/>"
        "<child link='b'/><axis xyz='0 0 1'/><mimic joint='ghost' multiplier='2'/>"
        "<limit lower='0.5' upper='1' effort='1' velocity='1'/></joint>"
    )
    path = write(tmp_path, "m.urdf", text)
    scene = load_robot(path)
    assert any(
        "joint 'm' mimics joint 'ghost', which does not exist: the mimic is ignored" in w
        for w in scene.warnings
    )
    # a joint of its own: MoveIt's default (the middle of limits excluding zero), or given
    b = next(body for body in scene.bodies if body.name == "b")
    turned = np.array([[np.cos(0.75), -np.sin(0.75)], [np.sin(0.75), np.cos(0.75)]])
    np.testing.assert_allclose(b.pose[:2, :2], turned, atol=1e-12)
    given = load_robot(path, RobotOptions(joints={"m": 1.0}))
    b = next(body for body in given.bodies if body.name == "b")
    np.testing.assert_allclose(b.pose[0, 0], np.cos(1.0), atol=1e-12)


def test_ros_package_path_finds_nested_packages(tmp_path, monkeypatch):
    write(tmp_path, "ws/src/some_repo/my_robot/package.xml", "<package/>")
    write(tmp_path, "ws/src/some_repo/my_robot/meshes/cube.obj", CUBE_OBJ)
    text = urdf(
        "".join(
            f'<link name="l{i}"><collision><origin xyz="{3 * i} 0 0"/><geometry>'
            '<mesh filename="package://my_robot/meshes/cube.obj"/></geometry></collision></link>'
            for i in range(3)
        )
        + "".join(
            f'<joint name="j{i}" type="fixed"><parent link="l{i - 1}"/><child link="l{i}"/></joint>'
            for i in (1, 2)
        )
    )
    path = write(tmp_path, "elsewhere/r.urdf", text)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "nothing") + ":" + str(tmp_path / "ws"))
    scene = load_robot(path)
    assert [b.name for b in scene.bodies] == ["l0", "l1", "l2"]
    for i, body in enumerate(scene.bodies):  # one file for three links, each at its origin
        np.testing.assert_allclose(body.vertices.min(axis=0), [3 * i - 0.5, -0.5, -0.5])


def test_panda_primitive_model_matches_coal_on_exact_primitives(panda):
    """panda_collision.urdf (spheres and cylinders only, several a link): every part is its
    exact primitive, and every pair's signed distance agrees with coal's on the same
    primitives (GJK and EPA at a 1e-12 tolerance) to 1e-9 m. Before session 37 the parts were
    tessellated and this test allowed 2 mm. python-fcl is no oracle here: its cylinder-cylinder
    distance missed coal's by 6e-5 on panda_hand and panda_link4."""
    coal = pytest.importorskip("coal")
    import yourdfpy

    path = panda.parent / "panda_collision.urdf"
    scene = load_robot(path)
    report = check_scene(scene, CheckOptions(clearance=10.0))
    poses = {b.name: b.pose for b in scene.bodies}
    # panda_joint4's limits [-3.0718, -0.0698] exclude zero: MoveIt's default, their middle
    expected = _yourdfpy_poses(path, {"panda_joint4": (-3.0718 - 0.0698) / 2})
    for name, pose in poses.items():
        np.testing.assert_allclose(pose, expected[name], atol=1e-9)
        assert next(b for b in scene.bodies if b.name == name).parts[0] == "cylinder0"
    model = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
    shapes: dict[str, list] = {}
    for link in model.robot.links:
        for collision in link.collisions:
            g = collision.geometry
            shape = (
                coal.Sphere(g.sphere.radius)
                if g.sphere is not None
                else coal.Cylinder(g.cylinder.radius, g.cylinder.length)
            )
            world = poses[link.name] @ (np.eye(4) if collision.origin is None else collision.origin)
            shapes.setdefault(link.name, []).append(
                (shape, coal.Transform3s(world[:3, :3], world[:3, 3]))
            )
    excluded = {(a, b) for a, b, _ in scene.excluded_pairs}
    measured = {tuple(sorted((p["body_a"], p["body_b"]))): p for p in report.pairs}
    request = coal.DistanceRequest()
    request.gjk_tolerance = request.epa_tolerance = 1e-12
    compared = 0
    for a, b in itertools.combinations(sorted(shapes), 2):
        if (a, b) in excluded:
            continue
        distances = [
            coal.distance(sa, ta, sb, tb, request, coal.DistanceResult())
            for sa, ta in shapes[a]
            for sb, tb in shapes[b]
        ]
        if min(distances) < -1e300:  # coal's EPA fails on the touching fingers' cylinders
            assert measured[(a, b)]["status"] == "contact", (a, b)
            continue
        assert abs(measured[(a, b)]["signed_distance"] - min(distances)) <= 1e-9, (a, b)
        compared += 1
    assert compared == len(measured) - 1 == 44
    deep = [p for p in report.pairs if p["signed_distance"] < -2e-3]
    assert len(deep) == 5  # the coarse spheres of the wrist reach the hand, fingers, link1


_coord = st.floats(-2.0, 2.0, allow_nan=False, width=32)
_angle = st.floats(-3.0, 3.0, allow_nan=False, width=32)
_joint = st.fixed_dictionaries(
    {
        "type": st.sampled_from(["revolute", "continuous", "prismatic", "fixed"]),
        "xyz": st.tuples(_coord, _coord, _coord),
        "rpy": st.tuples(_angle, _angle, _angle),
        "axis": st.tuples(_coord, _coord, _coord).filter(
            lambda a: math.sqrt(sum(x * x for x in a)) > 1e-3
        ),
        "value": st.floats(-1.0, 1.0, allow_nan=False, width=32),
    }
)


@pytest.mark.slow
@settings(max_examples=60)
@given(joints=st.lists(_joint, min_size=1, max_size=6), branch=st.booleans())
def test_forward_kinematics_matches_yourdfpy(tmp_path_factory, joints, branch):
    """Random trees of revolute, continuous, prismatic and fixed joints with arbitrary
    origins and axes: every link pose equals yourdfpy's own forward kinematics."""
    folder = tmp_path_factory.mktemp("fk")
    links = "".join(
        f'<link name="l{i}"><collision><geometry><sphere radius="0.1"/></geometry></collision>'
        "</link>"
        for i in range(len(joints) + 1)
    )
    text, cfg = [], {}
    for i, j in enumerate(joints, start=1):
        # unit axes: yourdfpy moves a prismatic joint by axis x value unnormalized (see
        # test_prismatic_axis_is_normalized for ours)
        norm = math.sqrt(sum(x * x for x in j["axis"]))
        j = {**j, "axis": tuple(x / norm for x in j["axis"])}
        parent = 0 if branch and i % 2 == 0 else i - 1  # some links branch off the root
        limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
        text.append(
            f'<joint name="j{i}" type="{j["type"]}"><parent link="l{parent}"/>'
            f'<child link="l{i}"/><origin xyz="{" ".join(map(repr, j["xyz"]))}" '
            f'rpy="{" ".join(map(repr, j["rpy"]))}"/>'
            f'<axis xyz="{" ".join(map(repr, j["axis"]))}"/>{limit}</joint>'
        )
        if j["type"] != "fixed":
            cfg[f"j{i}"] = j["value"]
    path = write(folder, "fk.urdf", urdf(links + "".join(text)))
    scene = load_robot(path, RobotOptions(joints=cfg))
    expected = _yourdfpy_poses(path, cfg)
    for body in scene.bodies:
        np.testing.assert_allclose(body.pose, expected[body.name], atol=1e-9)


def test_missing_robot_dependencies_are_named(tmp_path, monkeypatch):
    import importlib.util
    import sys

    path = write(tmp_path, "chain.urdf", urdf(CHAIN))
    monkeypatch.setitem(sys.modules, "yourdfpy", None)  # import fails as if not installed
    line = error_line("check", str(path))
    assert "chain.urdf" in line and "yourdfpy" in line and "meshcol[robots]" in line
    monkeypatch.setitem(sys.modules, "mujoco", None)
    mjcf = write(tmp_path, "m.xml", "<mujoco/>")
    line = error_line("check", str(mjcf))
    assert "m.xml" in line and "needs mujoco" in line
    monkeypatch.undo()
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name, *a: None if name == "collada" else find_spec(name, *a),
    )
    write(tmp_path, "x.dae", "<COLLADA/>")
    text = urdf(
        '<link name="v"><collision><geometry><mesh filename="x.dae"/></geometry></collision></link>'
    )
    line = error_line("check", str(write(tmp_path, "d.urdf", text)))
    assert "d.urdf" in line and "link 'v'" in line and "pycollada" in line


def test_prismatic_axis_is_normalized(tmp_path):
    """A URDF axis that is not a unit vector gives the direction only, as KDL, Pinocchio and
    MuJoCo read it: a prismatic joint moves by its value along that direction."""
    text = urdf(
        "<link name='a'/><link name='b'><collision><geometry><sphere radius='0.1'/></geometry>"
        "</collision></link><joint name='j' type='prismatic'><parent link='a'/><child link='b'/>"
        "<axis xyz='0 0 2'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
    )
    scene = load_robot(write(tmp_path, "p.urdf", text), RobotOptions(joints={"j": 0.5}))
    np.testing.assert_allclose(scene.bodies[0].pose[:3, 3], [0, 0, 0.5])


@pytest.mark.parametrize("axis", ["0 0 0", "nan 0 1"])
def test_bad_joint_axis(tmp_path, axis):
    text = urdf(
        "<link name='a'/><link name='b'/><joint name='j' type='revolute'><parent link='a'/>"
        f"<child link='b'/><axis xyz='{axis}'/>"
        "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
    )
    line = error_line("check", str(write(tmp_path, "ax.urdf", text)))
    assert "ax.urdf" in line and "joint 'j': axis must be a finite non-zero vector" in line


def test_check_and_collision_matrix_share_one_adjacency_rule(tmp_path):
    """MoveIt's rule in both: links with only geometry-less links between them are adjacent,
    the two wheels under a bare root included (not joined to each other by any joint)."""
    from meshcol.analysis.collision_matrix import collision_matrix

    box = '<collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>'
    joint = (
        '<joint name="{n}" type="{t}"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="{x} 0 0"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )
    text = urdf(
        '<link name="root"/>'
        f'<link name="wheel_l">{box}</link><link name="wheel_r">{box}</link>'
        f'<link name="mount"/><link name="arm">{box}</link>'
        + joint.format(n="jl", t="continuous", p="root", c="wheel_l", x=-1)
        + joint.format(n="jr", t="continuous", p="root", c="wheel_r", x=1)
        + joint.format(n="jm", t="fixed", p="wheel_l", c="mount", x=0)
        + joint.format(n="ja", t="revolute", p="mount", c="arm", x=0.5)
    )
    path = write(tmp_path, "cart.urdf", text)
    scene = load_robot(path)
    adjacent = {tuple(sorted(p[:2])) for p in scene.excluded_pairs if p[2] == "adjacent"}
    assert adjacent == {("wheel_l", "wheel_r"), ("arm", "wheel_l")}
    matrix = collision_matrix(path, samples=50, seed=1)
    from_matrix = {
        tuple(sorted((e["link_a"], e["link_b"]))) for e in matrix.pairs if e["class"] == "adjacent"
    }
    assert from_matrix == adjacent
