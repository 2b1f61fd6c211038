"""Robots as they come from the wild (issue 29, items 4 to 10 and 19): package folders laid out
as pybullet and yourdfpy find them, xacro leftovers, MJCF collision filters, the MJCF written
(excludes, near-zero inertia), paths of a rebuilt URDF, one default configuration, GLB's up
axis, touching pairs in the collision matrix, and the project's own sample arm.

Each behaviour is compared with the consumer that defines it where it is installed (MuJoCo,
pybullet, trimesh); a missing one skips with the reason.
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import centred_cube_obj
from wild_collections import collection_file

from meshcol.cli import main
from meshcol.io.robot import RobotOptions, load_robot

pytest.importorskip("yourdfpy", reason="URDF reading needs yourdfpy (pip install meshcol[robots])")

CUBE_OBJ = centred_cube_obj(0.05)


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


def hull_to_mjcf(robot: Path, out: Path) -> Path:
    """``meshcol hull ROBOT --out-dir OUT --to mjcf``, which must pass; the MJCF written."""
    code, _, err = run("hull", str(robot), "--out-dir", str(out), "--to", "mjcf")
    assert code == 0, err
    return out / f"{robot.stem}.xml"


def mesh_link(name: str, reference: str) -> str:
    return (
        f'<link name="{name}"><visual><geometry><mesh filename="{reference}"/></geometry></visual>'
        f'<collision><geometry><mesh filename="{reference}"/></geometry></collision></link>'
    )


# --- item 4: package:// as pybullet and yourdfpy resolve it ----------------------------------


@pytest.mark.parametrize(
    "reference, mesh_at, urdf_at, peer",
    [
        # a folder NAME beside the URDF: pybullet (the reference without package://, from
        # the URDF's folder)
        ("package://my_robot/meshes/cube.obj", "my_robot/meshes/cube.obj", "r.urdf", "pybullet"),
        # REST from an ancestor of the URDF's folder: yourdfpy (package://NAME/ dropped, the
        # URDF's folder and its parents in turn)
        ("package://my_robot/meshes/cube.obj", "meshes/cube.obj", "a/b/r.urdf", "yourdfpy"),
        # NAME beside an ancestor: pybullet's rule, one folder up at a time
        ("package://my_robot/meshes/cube.obj", "my_robot/meshes/cube.obj", "a/b/r.urdf", None),
        # package:/// with no package name (talos_full_v2 of example-robot-data): the rest
        # from an ancestor, never the file system's root
        ("package:///pkg/meshes/cube.obj", "pkg/meshes/cube.obj", "a/r.urdf", None),
        # package://meshes/...: relative to the URDF's folder (pybullet)
        ("package://meshes/cube.obj", "meshes/cube.obj", "r.urdf", "pybullet"),
    ],
)
def test_package_folders_as_pybullet_and_yourdfpy_find_them(
    tmp_path, monkeypatch, reference, mesh_at, urdf_at, peer
):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.chdir(tmp_path / "..")
    write(tmp_path, mesh_at, CUBE_OBJ)
    robot = write(tmp_path, urdf_at, urdf(mesh_link("a", reference)))
    scene = load_robot(robot)
    assert [b.name for b in scene.bodies] == ["a"]
    assert np.ptp(scene.bodies[0].vertices, axis=0) == pytest.approx([0.1] * 3)
    code, _, err = run("check", str(robot))
    assert code == 0, err
    # the peer whose rule this is finds the same file
    if peer == "yourdfpy":
        import yourdfpy

        loaded = yourdfpy.URDF.load(
            str(robot), build_collision_scene_graph=True, load_collision_meshes=True
        )
        geometry = list(loaded.collision_scene.geometry.values())
        assert np.ptp(geometry[0].vertices, axis=0) == pytest.approx([0.1] * 3)
    elif peer == "pybullet":
        assert pybullet_collision_extent(robot) == pytest.approx([0.1] * 3, abs=0.01)


def pybullet_collision_extent(robot: Path) -> list[float]:
    """The collision box pybullet gives link -1 of a robot (mesh margins included)."""
    pybullet = pytest.importorskip("pybullet", reason="pip install 'meshcol[robots-wild]'")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(robot), useFixedBase=True, physicsClientId=client)
        low, high = pybullet.getAABB(body, -1, physicsClientId=client)
        return list(np.subtract(high, low))
    finally:
        pybullet.disconnect(client)


def test_package_path_flag_wins_over_the_folder_layout(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    write(tmp_path, "my_robot/meshes/cube.obj", CUBE_OBJ)
    write(tmp_path, "other/meshes/cube.obj", CUBE_OBJ.replace("0.05", "0.5"))
    robot = write(tmp_path, "r.urdf", urdf(mesh_link("a", "package://my_robot/meshes/cube.obj")))
    side = np.ptp(load_robot(robot).bodies[0].vertices, axis=0)[0]
    assert side == pytest.approx(0.1)
    options = RobotOptions(package_paths={"my_robot": str(tmp_path / "other")})
    assert np.ptp(load_robot(robot, options).bodies[0].vertices, axis=0)[0] == pytest.approx(1.0)


# --- item 5: xacro leftovers -----------------------------------------------------------------

XACRO_BODY = """
<link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="arm"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
  <origin xyz="$(optenv ARM_X 1.0) 0 0" rpy="${pi/2} 0 0"/>
  <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="${effort}" velocity="1"/>
</joint>
"""


def test_xacro_leftovers_warn_and_read_as_xacro_or_the_urdf_default(tmp_path, monkeypatch):
    monkeypatch.delenv("ARM_X", raising=False)
    robot = write(tmp_path, "r.urdf", urdf(XACRO_BODY))
    scene = load_robot(robot)
    arm = next(b for b in scene.bodies if b.name == "arm")
    assert arm.pose[:3, 3] == pytest.approx([1.0, 0.0, 0.0])  # $(optenv ARM_X 1.0): its default
    assert arm.pose[:3, :3] == pytest.approx(np.eye(3))  # rpy ${pi/2}: URDF's default, zero
    text = "\n".join(scene.warnings)
    assert "joint 'j': <origin xyz='$(optenv ARM_X 1.0) 0 0'>" in text
    assert "read as '1.0 0 0'" in text
    assert "<origin rpy='${pi/2} 0 0'>" in text and "URDF default (0 0 0)" in text
    assert "<limit effort='${effort}'>" in text
    monkeypatch.setenv("ARM_X", "2.5")
    moved = next(b for b in load_robot(robot).bodies if b.name == "arm")
    assert moved.pose[0, 3] == pytest.approx(2.5)
    code, _, err = run("check", str(robot))
    assert code == 0 and "xacro leftover" in err


def test_rebuilt_urdf_and_mjcf_of_xacro_leftovers_are_what_was_read(tmp_path, monkeypatch):
    """``hull --to urdf|mjcf`` rewrites the file as the reader read it (pybullet_data's husky
    kept its ``$(optenv ...)`` in the rebuilt URDF, which yourdfpy and MuJoCo refused)."""
    monkeypatch.delenv("ARM_X", raising=False)
    robot = write(tmp_path, "r.urdf", urdf(XACRO_BODY))
    for target in ("urdf", "mjcf"):
        code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / target), "--to", target)
        assert code == 0, err
    text = (tmp_path / "urdf" / "r.urdf").read_text()
    assert "$(" not in text and "${" not in text
    yourdfpy = pytest.importorskip("yourdfpy")
    model = yourdfpy.URDF.load(str(tmp_path / "urdf" / "r.urdf"), load_meshes=False)
    assert model.joint_map["j"].origin[:3, 3] == pytest.approx([1.0, 0.0, 0.0])
    mujoco = pytest.importorskip("mujoco")
    mujoco.MjModel.from_xml_path(str(tmp_path / "mjcf" / "r.xml"))


def test_xacro_leftover_without_a_default_names_the_attribute(tmp_path):
    body = XACRO_BODY.replace('<sphere radius="0.1"/>', '<sphere radius="${r}"/>')
    robot = write(tmp_path, "r.urdf", urdf(body))
    code, _, err = run("check", str(robot))
    assert code == 2 and "Traceback" not in err
    assert "link 'arm': <sphere radius='${r}'>" in err and "run xacro first" in err


# --- item 6: MJCF contype/conaffinity --------------------------------------------------------

FILTERED_MJCF = """
<mujoco model="filtered">
  <default>
    <default class="ghost"><geom contype="{contype}" conaffinity="{conaffinity}"/></default>
  </default>
  <worldbody>
{bodies}
  </worldbody>
</mujoco>
"""


def filtered_model(tmp_path: Path, contype: int, conaffinity: int) -> Path:
    bodies = "\n".join(
        f'    <body name="b{k}" pos="{0.15 * k} 0 1"><freejoint/>'
        f'<geom class="ghost" type="box" size="0.1 0.1 0.1"/></body>'
        for k in range(4)
    )
    text = FILTERED_MJCF.format(contype=contype, conaffinity=conaffinity, bodies=bodies)
    return write(tmp_path, f"m{contype}{conaffinity}.xml", text)


def mujoco_contact_pairs(path: Path) -> set[tuple[str, str]]:
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)]
    pairs = set()
    for k in range(data.ncon):
        a = names[model.geom_bodyid[data.contact[k].geom1]]
        b = names[model.geom_bodyid[data.contact[k].geom2]]
        pairs.add((min(a, b), max(a, b)))
    return pairs


@pytest.mark.parametrize(
    "contype, conaffinity, collide", [(1, 0, False), (1, 1, True), (2, 3, True)]
)
def test_mjcf_contype_conaffinity_as_mujoco_filters_them(tmp_path, contype, conaffinity, collide):
    path = filtered_model(tmp_path, contype, conaffinity)
    in_mujoco = mujoco_contact_pairs(path)
    assert bool(in_mujoco) == collide  # the defaults class resolved by MuJoCo's compiler
    scene = load_robot(path)
    excluded = {(a, b): why for a, b, why in scene.excluded_pairs}
    code, out, err = run("check", str(path), "--report", str(tmp_path / "r.json"))
    report = json.loads((tmp_path / "r.json").read_text())
    found = {
        (min(p["body_a"], p["body_b"]), max(p["body_a"], p["body_b"]))
        for p in report["pairs"]
        if p["status"] in ("penetrating", "contact", "contained")
    }
    if collide:
        assert not excluded and found == in_mujoco == {("b0", "b1"), ("b1", "b2"), ("b2", "b3")}
        assert code == 1
    else:
        assert set(excluded.values()) == {"mjcf contype/conaffinity"} and len(excluded) == 6
        assert not found and code == 0, err


def test_collision_matrix_classes_filtered_pairs_excluded(tmp_path):
    path = filtered_model(tmp_path, 1, 0)
    srdf = tmp_path / "m.srdf"
    code, _, err = run(
        "collision-matrix", str(path), "--samples", "20", "-o", str(srdf),
        "--report", str(tmp_path / "m.json"),
    )  # fmt: skip
    assert code == 0, err
    report = json.loads((tmp_path / "m.json").read_text())
    assert report["summary"]["pairs_by_class"]["excluded"] == 6
    for pair in report["pairs"]:
        assert pair["class"] == "excluded" and pair["reason"] == "User"
        assert pair["excluded_by"] == "mjcf contype/conaffinity" and pair["collisions"] is None
    assert srdf.read_text().count('reason="User"') == 6


# --- item 19: touching pairs are in contact for the collision matrix -------------------------


def test_collision_matrix_counts_a_pair_touching_at_1e_11_as_colliding(tmp_path):
    gap = 6.9e-12
    body = f"""
<link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
<link name="a"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
<link name="b"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
<joint name="ja" type="continuous"><parent link="base"/><child link="a"/>
  <origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
<joint name="jb" type="continuous"><parent link="base"/><child link="b"/>
  <origin xyz="{1.2 + gap!r} 0 0"/><axis xyz="0 0 1"/></joint>
"""
    robot = write(tmp_path, "touch.urdf", urdf(body))
    code, _, err = run("collision-matrix", str(robot), "--samples", "50", "--report",
                       str(tmp_path / "m.json"))  # fmt: skip
    assert code == 0, err
    report = json.loads((tmp_path / "m.json").read_text())
    pair = next(p for p in report["pairs"] if (p["link_a"], p["link_b"]) == ("a", "b"))
    assert pair["class"] == "default" and pair["default_collision"] is True
    assert report["settings"]["tolerance"] == 1e-6
    # check, with the same tolerance, calls the pair a contact
    code, _, err = run("check", str(robot), "--report", str(tmp_path / "c.json"))
    statuses = {
        (p["body_a"], p["body_b"]): p["status"]
        for p in json.loads((tmp_path / "c.json").read_text())["pairs"]
    }
    assert statuses.get(("a", "b"), statuses.get(("b", "a"))) == "contact"


# --- item 9: one default configuration ---------------------------------------------------------


def test_check_and_collision_matrix_share_moveits_default_configuration(samples, tmp_path):
    robot = samples / "robot" / "arm.urdf"
    scene = load_robot(robot)
    assert any("joint 'elbow'" in w and "middle, 1.4" in w for w in scene.warnings)
    forearm = next(b for b in scene.bodies if b.name == "forearm")
    upper = next(b for b in scene.bodies if b.name == "upper_arm")
    relative = np.linalg.inv(upper.pose) @ forearm.pose
    assert math.atan2(relative[0, 2], relative[0, 0]) == pytest.approx(1.4)  # about y
    code, _, err = run("collision-matrix", str(robot), "--samples", "20", "--report",
                       str(tmp_path / "m.json"))  # fmt: skip
    assert code == 0, err
    joints = {
        j["name"]: j["default"] for j in json.loads((tmp_path / "m.json").read_text())["joints"]
    }
    assert joints["elbow"] == pytest.approx(1.4) and joints["lift"] == 0.0
    mjcf = load_robot(samples / "robot" / "arm.xml")
    assert any("joint 'elbow'" in w and "middle, 1.4" in w for w in mjcf.warnings)
    for command in ("check", "collision-matrix"):
        code, out, _ = run(command, "--help")
        assert code == 0 and "middle of limits that exclude zero" in " ".join(out.split())


# --- item 7: the MJCF written ------------------------------------------------------------------


def rest_contacts(xml: Path, excluded: set[tuple[str, str]]) -> list[tuple[str, str]]:
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)]
    found = []
    for k in range(data.ncon):
        a = names[model.geom_bodyid[data.contact[k].geom1]]
        b = names[model.geom_bodyid[data.contact[k].geom2]]
        if (min(a, b), max(a, b)) in excluded:
            found.append((min(a, b), max(a, b)))
    for _ in range(100):
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos))
    return found


@pytest.mark.parametrize("name", ["arm.urdf", "arm.xml"])
def test_mjcf_written_excludes_what_meshcol_excludes(samples, tmp_path, name):
    pytest.importorskip("mujoco")
    robot = samples / "robot" / name
    excluded = {(min(a, b), max(a, b)) for a, b, _ in load_robot(robot).excluded_pairs}
    assert ("base_link", "turntable") in excluded
    if name == "arm.xml":  # the input: base_link is welded to the world, MuJoCo collides it
        assert ("base_link", "turntable") in rest_contacts(robot, excluded)
    code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / "out"), "--to", "mjcf")
    assert code == 0, err
    written = tmp_path / "out" / "arm.xml"
    text = written.read_text()
    assert '<exclude body1="base_link" body2="turntable"/>' in text
    assert "meshcol: " in text and "<contact><exclude>" in text
    assert rest_contacts(written, excluded) == []


@pytest.mark.parametrize(
    "base, base_inertia, words",
    [
        ("base", 'ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"', "mjMINVAL"),
        # a full inertia that is not positive definite (anymal's base in example-robot-data)
        (
            "base",
            'ixx="0.01" ixy="0.05" ixz="0" iyy="0.01" iyz="0" izz="0.01"',
            "positive eigenvalues",
        ),
        # singular, its least eigenvalue 2e-18, on a root link named "world" (MuJoCo's world
        # body, which no bound reaches): positive in numpy, not above MuJoCo's mjMINVAL
        # (pybullet_data's biped2d)
        (
            "world",
            'ixx="0.2125" ixy="-0.005" ixz="0.0225" iyy="0.205" iyz="0.045" izz="0.0125"',
            "positive eigenvalues",
        ),
    ],
)
def test_near_zero_inertia_links_are_bounded_as_converters_do(tmp_path, base, base_inertia, words):
    mujoco = pytest.importorskip("mujoco")
    body = f"""
<link name="{base}"><inertial><mass value="1"/><inertia {base_inertia}/></inertial>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="motor"><inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
  <collision><origin xyz="0 0 0.3"/><geometry><sphere radius="0.05"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="{base}"/><child link="motor"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
"""
    robot = write(tmp_path, "quad.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert 'boundmass="0.001"' in text and 'boundinertia="1e-06"' in text
    assert "meshcol: MuJoCo rejected the model as written" in text and words in text
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "quad.xml"))
    motor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "motor")
    assert model.body_mass[motor] == pytest.approx(1e-3)


def test_a_visual_primitive_of_size_zero_is_left_out_of_the_mjcf(tmp_path):
    """pybullet_data's laikago_toes draws each toe as a sphere of radius 0: MuJoCo refuses a
    geom of size 0, so the MJCF leaves that visual out, with a note (it draws nothing)."""
    mujoco = pytest.importorskip("mujoco")
    body = """
<link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="toe"><visual><geometry><sphere radius="0.0"/></geometry></visual>
  <visual><geometry><box size="0.1 0 0.1"/></geometry></visual>
  <visual><geometry><sphere radius="0.02"/></geometry></visual>
  <collision><geometry><sphere radius="0.03"/></geometry></collision></link>
<joint name="j" type="fixed"><parent link="base"/><child link="toe"/><origin xyz="0 0 0.3"/></joint>
"""
    robot = write(tmp_path, "toes.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert "link 'toe': visual sphere of radius 0.0 left out" in text
    assert "link 'toe': visual box of size '0.1 0 0.1' left out" in text
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "toes.xml"))
    sizes = [model.geom_size[g][0] for g in range(model.ngeom) if model.geom_group[g] == 2]
    assert sizes == [pytest.approx(0.02)]  # the one visual with a size


def test_a_spherical_limit_mujoco_cannot_state_is_left_out_of_the_mjcf(tmp_path):
    """pybullet_data's spherical_joint_limit: ``<limit lower="0.2" upper=".8" twist=".3">``,
    pybullet's swing and twist ranges; MuJoCo's importer would make ``0.2 0.8`` a ball
    range and refuses any that does not start at 0. The ball is unlimited, with a note; a
    limit from 0 (MuJoCo's own reading of the importer's input) is kept."""
    mujoco = pytest.importorskip("mujoco")
    inertial = '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>'
    body = f"""
<link name="chest">{inertial}<collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="neck">{inertial}<collision><geometry><sphere radius="0.05"/></geometry></collision></link>
<link name="head">{inertial}<collision><geometry><sphere radius="0.05"/></geometry></collision></link>
<joint name="neck" type="spherical"><parent link="chest"/><child link="neck"/>
  <origin xyz="0 0 0.5"/><limit effort="1000.0" lower="0.2" upper=".8" twist=".3"/></joint>
<joint name="nod" type="spherical"><parent link="neck"/><child link="head"/>
  <origin xyz="0 0 0.5"/><limit effort="10" lower="0" upper="0.5"/></joint>
"""
    robot = write(tmp_path, "ball.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert "joint 'neck': spherical limits (lower 0.2, upper .8) have no MuJoCo form" in text
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "ball.xml"))
    neck, nod = (model.joint(n).id for n in ("neck", "nod"))
    assert model.jnt_type[neck] == model.jnt_type[nod] == mujoco.mjtJoint.mjJNT_BALL
    assert not model.jnt_limited[neck]
    assert model.jnt_limited[nod] and list(model.jnt_range[nod]) == [0.0, 0.5]


def test_an_obj_visual_with_faces_without_normals_is_converted_for_mujoco(tmp_path):
    """pybullet_data's table_square draws an OBJ whose faces give normals, but for some:
    MuJoCo's reader refuses it ("normal index out of bounds"), so the MJCF draws a
    converted copy, with a note; an OBJ whose every face gives its normals is used as is."""
    mujoco = pytest.importorskip("mujoco")
    corners = [f"v {x} {y} {z}" for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    mixed = "\n".join([*corners, "vn 0 0 -1", "f 1//1 3//1 4//1", "f 1 4 2", "f 5 6 8", "f 1 2 6"])
    whole = "\n".join([*corners, "vn 0 0 -1", "f 1//1 3//1 4//1", "f 1//1 4//1 2//1"])
    write(tmp_path, "mixed.obj", mixed)
    write(tmp_path, "whole.obj", whole)
    body = """
<link name="top"><visual><geometry><mesh filename="mixed.obj"/></geometry></visual>
  <visual><geometry><mesh filename="whole.obj"/></geometry></visual>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
"""
    robot = write(tmp_path, "table.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert "visual mesh 'mixed.obj' converted (faces without normals" in text
    assert "'whole.obj' converted" not in text
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "table.xml"))
    assert model.nmesh == 2
    assert sorted(int(model.mesh_facenum[m]) for m in range(2)) == [2, 4]


# --- item 8: a rebuilt URDF whose visuals came through a package path --------------------------


def test_rebuilt_urdf_points_package_visuals_at_their_files(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    write(tmp_path, "pkg/my_robot/meshes/cube.obj", CUBE_OBJ)
    robot = write(
        tmp_path, "pkg/r.urdf", urdf(mesh_link("a", "package://my_robot/meshes/cube.obj"))
    )
    out = tmp_path / "elsewhere" / "out"
    code, _, err = run("hull", str(robot), "--out-dir", str(out))
    assert code == 0, err
    from lxml import etree

    root = etree.parse(str(out / "r.urdf")).getroot()
    visual = root.find("link/visual/geometry/mesh").get("filename")
    assert visual == "../../pkg/my_robot/meshes/cube.obj"
    assert (out / visual).resolve() == (tmp_path / "pkg/my_robot/meshes/cube.obj").resolve()
    pybullet = pytest.importorskip("pybullet", reason="pip install 'meshcol[robots-wild]'")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        monkeypatch.chdir(out)
        body = pybullet.loadURDF("r.urdf", physicsClientId=client)
        shapes = pybullet.getVisualShapeData(body, physicsClientId=client)
        assert shapes and shapes[0][4].decode().endswith("cube.obj")
    finally:
        pybullet.disconnect(client)


# --- item 10: GLB up axis, the pybullet target ---------------------------------------------------


def glb_json(path: Path) -> dict:
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20 : 20 + length])


def test_glb_of_a_robot_is_y_up_for_both_readers(samples, tmp_path):
    trimesh = pytest.importorskip("trimesh")
    robot = samples / "robot" / "arm.urdf"
    code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path), "--to", "glb")
    assert code == 0, err
    glb = tmp_path / "arm.glb"
    document = glb_json(glb)
    assert document["asset"]["extras"] == {"meshcol_source_up_axis": "Z"}
    z_up = np.concatenate([b.world_vertices() for b in load_robot(robot).bodies])
    # trimesh applies the node transforms: the arm's height is along +Y
    dumped = trimesh.load(str(glb), force="scene").to_geometry()
    low, high = dumped.bounds
    assert high[1] == pytest.approx(z_up[:, 2].max(), abs=1e-5)
    assert low[2] == pytest.approx(-z_up[:, 1].max(), abs=1e-5)
    # meshcol's own glTF reader agrees
    from meshcol.io.scene import load_inputs

    scene = load_inputs([glb])
    y_up = np.concatenate([b.world_vertices() for b in scene.bodies])
    assert y_up[:, 1].max() == pytest.approx(z_up[:, 2].max(), abs=1e-5)
    assert y_up[:, 1].min() == pytest.approx(z_up[:, 2].min(), abs=1e-5)


def test_pybullet_target_uses_the_urdf_importers_margin():
    from meshcol.io.targets import load_target

    pybullet, bullet = load_target("pybullet"), load_target("bullet")
    assert pybullet.limits["min_thickness"] == pytest.approx(2 * 0.001)
    assert bullet.limits["min_thickness"] == pytest.approx(2 * 0.04)
    source = next(s for s in pybullet.sources if s.limit == "min_thickness")
    assert "gUrdfDefaultCollisionMargin = 0.001" in source.quote
    assert "BulletUrdfImporter.cpp" in source.url


# --- item 18: the sample arm -------------------------------------------------------------------


def test_sample_arm_urdf_and_mjcf_are_the_same_robot(samples):
    mujoco = pytest.importorskip("mujoco")
    urdf_scene = load_robot(samples / "robot" / "arm.urdf")
    mjcf_scene = load_robot(samples / "robot" / "arm.xml")
    names = [b.name for b in urdf_scene.bodies]
    assert names == [b.name for b in mjcf_scene.bodies]
    for a, b in zip(urdf_scene.bodies, mjcf_scene.bodies):
        assert a.world_vertices().min(axis=0) == pytest.approx(
            b.world_vertices().min(axis=0), abs=1e-6
        )
        assert a.world_vertices().max(axis=0) == pytest.approx(
            b.world_vertices().max(axis=0), abs=1e-6
        )
    mujoco.MjModel.from_xml_path(str(samples / "robot" / "arm.xml"))
    excluded = {(a, b): why for a, b, why in mjcf_scene.excluded_pairs}
    assert excluded[("finger_left", "turntable")] == "mjcf contype/conaffinity"
    assert ("finger_left", "finger_right") not in excluded


def test_sample_arm_checks_with_its_fingers_touching(samples, tmp_path):
    code, out, err = run("check", str(samples / "robot" / "arm.urdf"), "--report",
                         str(tmp_path / "c.json"))  # fmt: skip
    assert code == 0, err
    pairs = json.loads((tmp_path / "c.json").read_text())["pairs"]
    touching = [(p["body_a"], p["body_b"]) for p in pairs if p["status"] == "contact"]
    assert touching == [("finger_left", "finger_right")]


# --- what the sweep of the collections found ---------------------------------------------------


def test_link_names_that_are_no_usd_identifiers_are_written(tmp_path):
    pytest.importorskip("pxr", reason="pip install 'meshcol[usd]'")
    from pxr import Usd, UsdPhysics

    body = (
        "<link name='link_8.0'><collision><geometry><box size='0.1 0.1 0.1'/></geometry>"
        "</collision></link>"
    )
    robot = write(tmp_path, "hand.urdf", urdf(body))
    code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / "out"), "--to", "usd")
    assert code == 0, err
    stage = Usd.Stage.Open(str(tmp_path / "out" / "hand.usda"))
    colliders = [p for p in stage.Traverse() if p.HasAPI(UsdPhysics.CollisionAPI)]
    assert [p.GetName() for p in colliders] == ["link_8_0_box0"]


def test_mjcf_of_a_urdf_leaves_out_a_visual_without_triangles(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    lines_only = """<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="6">0 0 0 1 0 0</float_array>
      <technique_common><accessor source="#pa" count="2" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <lines count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1</p></lines>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""
    write(tmp_path, "foot.dae", lines_only)
    body = (
        "<link name='foot'><visual><geometry><mesh filename='foot.dae'/></geometry></visual>"
        "<collision><geometry><sphere radius='0.05'/></geometry></collision></link>"
        "<link name='toe'><visual><geometry><mesh filename='file:///nowhere/Toe.mesh'/>"
        "</geometry></visual><collision><geometry><sphere radius='0.02'/></geometry>"
        "</collision></link><joint name='j' type='fixed'><parent link='foot'/>"
        "<child link='toe'/><origin xyz='0.1 0 0'/></joint>"
    )
    robot = write(tmp_path, "leg.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert "link 'foot': visual mesh 'foot.dae' left out" in text
    assert "link 'toe': visual mesh 'file:///nowhere/Toe.mesh' left out (not found)" in text
    mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "leg.xml"))


def test_an_unranged_slide_joint_is_held_not_refused(tmp_path):
    pytest.importorskip("mujoco")
    text = """<mujoco><worldbody><body name="torso">
      <joint name="rootx" type="slide" axis="1 0 0"/><geom type="sphere" size="0.1"/>
      <body name="leg" pos="0 0 -0.3"><joint name="knee" axis="0 1 0" range="-1 1"/>
        <geom type="capsule" size="0.05" fromto="0 0 0 0 0 -0.3"/></body>
    </body></worldbody></mujoco>"""
    path = write(tmp_path, "walker.xml", text)
    code, _, err = run("check", str(path), "--report", str(tmp_path / "c.json"))
    assert code == 0, err
    code, _, err = run("collision-matrix", str(path), "--samples", "10", "--report",
                       str(tmp_path / "m.json"))  # fmt: skip
    assert code == 0, err
    report = json.loads((tmp_path / "m.json").read_text())
    assert [j["name"] for j in report["joints"]] == ["knee"]
    assert any("joint 'rootx' is a slide joint without a range" in w for w in report["warnings"])


# --- a few robots of the real collections (benchmarks/bench_robots_wild.py runs them all) -----


@pytest.mark.slow
@pytest.mark.parametrize(
    "package, parts",
    [
        ("example-robot-data", ("ur_description", "urdf", "ur5_robot.urdf")),
        ("example-robot-data", ("solo_description", "robots", "solo.urdf")),
        ("gymnasium", ("envs", "mujoco", "assets", "ant.xml")),
        ("dm_control", ("suite", "cartpole.xml")),
    ],
)
def test_collection_robots_check_and_their_mjcf_rests_without_excluded_contacts(
    tmp_path, package, parts
):
    pytest.importorskip("mujoco")
    robot = collection_file(package, *parts)
    code, _, err = run("check", str(robot), "--report", str(tmp_path / "c.json"))
    assert code in (0, 1), err
    excluded = {(min(a, b), max(a, b)) for a, b, _ in load_robot(robot).excluded_pairs}
    code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / "out"), "--to", "mjcf")
    assert code == 0, err
    assert rest_contacts(tmp_path / "out" / f"{robot.stem}.xml", excluded) == []
    if robot.suffix == ".urdf":
        code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / "urdf"))
        assert code == 0, err
        assert pybullet_collision_extent(tmp_path / "urdf" / robot.name)


def test_a_visual_mesh_too_thin_for_a_volume_inertia_gets_a_shell_inertia(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    write(tmp_path, "nub.obj", "v 0 0 0\nv 0.01 0 0\nv 0 0.01 0\nv 0.01 0.01 0\nf 1 2 3\nf 2 4 3\n")
    body = (
        "<link name='hand'><inertial><mass value='1'/><inertia ixx='0.01' ixy='0' ixz='0' "
        "iyy='0.01' iyz='0' izz='0.01'/></inertial>"
        "<visual><geometry><mesh filename='nub.obj'/></geometry></visual>"
        "<collision><geometry><sphere radius='0.05'/></geometry></collision></link>"
    )
    robot = write(tmp_path, "hand.urdf", urdf(body))
    text = hull_to_mjcf(robot, tmp_path / "out").read_text()
    assert "mesh volume is too small" in text and 'with inertia="shell"' in text
    mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "hand.xml"))


BALL_URDF = """<robot name="r">
  <link name="base"><collision><geometry><mesh filename="ball.obj"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.5 0 0"/>
    <geometry><mesh filename="ball.obj"/></geometry></collision></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


@pytest.mark.parametrize("fmt", ["urdf", "mjcf", "usd"])
def test_a_capsule_fit_of_length_zero_is_written_as_its_sphere(tmp_path, fmt):
    """The capsule fit of a ball has length 0: MuJoCo refused the rebuilt model ("size 1 must
    be positive"), as it did example-robot-data's borinot_flying_arm_2. The same solid is
    written as a sphere; MuJoCo's reading of it holds every vertex of the ball."""
    mujoco = pytest.importorskip("mujoco")
    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    ball.export(tmp_path / "ball.obj")
    (tmp_path / "r.urdf").write_text(BALL_URDF)
    out = tmp_path / "out"
    args = ["fit", str(tmp_path / "r.urdf"), "--out-dir", str(out), "--to", fmt]
    code, _, err = run(*args, "--shape", "capsule")
    assert code == 0, err
    if fmt == "usd":  # the rebuilt robot holds the sphere whatever the format
        pxr = pytest.importorskip("pxr")
        (stage_file,) = out.glob("*.usd*")
        stage = pxr.Usd.Stage.Open(str(stage_file))
        kinds = [prim.GetTypeName() for prim in stage.Traverse()]
        assert kinds.count("Sphere") == 2 and "Capsule" not in kinds, kinds
        return
    if fmt == "urdf":
        assert "<capsule" not in (out / "r.urdf").read_text()
        model = mujoco.MjModel.from_xml_string((out / "r.urdf").read_text())
    else:
        model = mujoco.MjModel.from_xml_path(str(out / "r.xml"))
    spheres = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
    assert len(spheres) == 2
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    for g, at in zip(sorted(spheres, key=lambda g: data.geom_xpos[g][0]), (0.0, 0.5)):
        centre = data.geom_xpos[g]
        reach = np.linalg.norm(ball.vertices + [at, 0, 0] - centre, axis=1).max()
        assert reach <= model.geom_size[g][0] + 1e-12


def test_capsule_fit_of_borinot_compiles_in_mujoco(tmp_path):
    pytest.importorskip("mujoco")
    robot = collection_file(
        "example-robot-data", "borinot_description", "urdf", "borinot_flying_arm_2.urdf"
    )
    out = tmp_path / "out"
    code, _, err = run(
        "fit", str(robot), "--out-dir", str(out), "--to", "mjcf", "--shape", "capsule"
    )
    assert code == 0, err
