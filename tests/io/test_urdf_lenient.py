"""URDF that pybullet reads and a strict parser refuses (meshcol.io.urdf_lenient): read as
pybullet reads it, each repair named in a warning, anything else still refused.

The cases are pybullet_data's own robots (minitaur, quadruped, bike, table_square: XML version
"0.0"; biped2d, diff_ring: blank lines first; humanoid: a NUL byte last; cube_no_rotation:
lower above upper; racecar_differential: a scale of four numbers, microtaur: an ``rpy`` of four;
spirit40newer: a joint's second ``<axis>``; bike and biped2d: ``0.07,`` and ``-1.57.``),
written small here; the last test reads the real files when pybullet is
installed, and compares the link frames with pybullet's own.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.errors import SceneError
from meshcol.io.robot import RobotOptions, load_robot, load_robot_model

pytest.importorskip("yourdfpy", reason="URDF reading needs yourdfpy (pip install meshcol[robots])")

#: Two boxes on a revolute joint and a third on a prismatic one, {placeholders} for the cases.
ROBOT = """{head}<robot name="bot">
  <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="{arm_xyz}"/>
    <geometry><box size="0.1 0.1 0.4"/></geometry></collision></link>
  <link name="slider"><collision><geometry><mesh filename="cube.obj" scale="{scale}"/></geometry>
    </collision></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit effort="1" velocity="1" lower="{lower}" upper="{upper}"/></joint>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="slider"/>
    <origin xyz="0.5 0 0"/><axis xyz="1 0 0"/>{slide_limit}</joint>
</robot>{tail}"""
PLAIN = {
    "head": '<?xml version="1.0"?>\n',
    "arm_xyz": "0 0 0.2",
    "scale": "0.1 0.1 0.1",
    "lower": "-1",
    "upper": "1",
    "slide_limit": '<limit effort="1" velocity="1" lower="0" upper="0.3"/>',
    "tail": "\n",
}
CUBE = "\n".join(
    [f"v {x} {y} {z}" for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    + ["f 1 2 4", "f 1 4 3", "f 5 7 8", "f 5 8 6", "f 1 5 6", "f 1 6 2"]
    + ["f 3 4 8", "f 3 8 7", "f 1 3 7", "f 1 7 5", "f 2 6 8", "f 2 8 4"]
)


def robot(tmp_path: Path, binary: bool = False, **changes: str) -> Path:
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "cube.obj").write_text(CUBE)
    path = tmp_path / "bot.urdf"
    text = ROBOT.format(**{**PLAIN, **changes})
    if binary:
        path.write_bytes(text.encode().replace(b"@NUL@", b"\0"))
    else:
        path.write_text(text)
    return path


def poses(path: Path, **options) -> dict[str, np.ndarray]:
    return {b.name: b.pose for b in load_robot(path, RobotOptions(**options)).bodies}


@pytest.mark.parametrize(
    "changes, words",
    [
        ({"head": '<?xml version="0.0" ?>\n'}, "the XML declaration gives version '0.0'"),
        ({"head": "<?xml version='2.0'?>"}, "the XML declaration gives version '2.0'"),
        ({"head": '\n\n  \n<?xml version="1.0"?>\n'}, "blank lines before the XML declaration"),
        ({"tail": "\r\n@NUL@"}, "NUL bytes after the root element"),
        ({"arm_xyz": "0, 0, 0.2"}, "<origin> of link 'arm': xyz='0, 0, 0.2' read as '0 0 0.2'"),
        ({"lower": "-1.0.", "upper": "1,"}, "lower='-1.0.' read as '-1.0'"),
        ({"scale": "0.1 0.1 0.1 0.1"}, "scale '0.1 0.1 0.1 0.1' has 4 numbers"),
        ({"arm_xyz": "0 0 0.2 0"}, "<origin> of link 'arm': xyz '0 0 0.2 0' has 4 numbers"),
    ],
)
def test_what_pybullet_reads_past_is_read_with_a_warning(tmp_path, changes, words):
    expected = poses(robot(tmp_path / "plain"))
    path = robot(tmp_path / "case", binary=True, **changes)
    scene = load_robot(path)
    assert any(words in w for w in scene.warnings), scene.warnings
    got = {b.name: b.pose for b in scene.bodies}
    assert got.keys() == expected.keys()
    for name, pose in got.items():
        np.testing.assert_array_equal(pose, expected[name])
    slider = next(b for b in scene.bodies if b.name == "slider")
    assert np.ptp(slider.vertices, axis=0) == pytest.approx([0.2, 0.2, 0.2])


@pytest.mark.parametrize(
    "changes, words",
    [
        ({"head": '<?xml version="1.0"?>\n<!-- unclosed '}, "malformed XML"),
        ({"tail": "\n<robot/>"}, "malformed XML"),  # content after the root, not NULs
        ({"head": '<!-- a comment -->\n<?xml version="1.0"?>\n'}, "malformed XML"),
        ({"arm_xyz": "0 zero 0.2"}, "invalid URDF"),  # no leading number: the loader says
    ],
)
def test_anything_else_malformed_is_still_refused(tmp_path, changes, words):
    with pytest.raises(SceneError, match=words):
        load_robot(robot(tmp_path, **changes))


def test_a_joints_second_axis_is_left_out_as_pybullet_reads_the_first(tmp_path):
    """spirit40newer's ``RL_lower_joint`` has two ``<axis>`` (MuJoCo's importer refuses a
    repeated element); pybullet reads the first, and so does meshcol, with a warning."""
    plain = robot(tmp_path / "plain")
    twice = tmp_path / "twice" / "bot.urdf"
    robot(tmp_path / "twice")
    text = plain.read_text().replace(
        '<axis xyz="0 1 0"/>', '<axis xyz="0 1 0"/><axis xyz="1 0 0"/>'
    )
    twice.write_text(text)
    scene = load_robot(twice, RobotOptions(joints={"hinge": 0.7}))
    assert "joint 'hinge': 2 <axis> elements: the first is read" in scene.warnings
    expected = poses(plain, joints={"hinge": 0.7})
    for body in scene.bodies:
        np.testing.assert_array_equal(body.pose, expected[body.name])


def test_lower_above_upper_is_no_limit_as_bullet_reads_it(tmp_path):
    path = robot(tmp_path, lower="1", upper="-1", slide_limit='<limit lower="1" upper="-1"/>')
    scene = load_robot(path)
    assert sum("Bullet's way of saying none" in w for w in scene.warnings) == 2
    # the hinge is free: zero by default, any value given (outside the old [1, -1] too)
    turned = poses(path, joints={"hinge": 2.5, "slide": 0.75})
    np.testing.assert_allclose(turned["slider"][:3, 3], [1.25, 0, 0], atol=1e-12)
    arm = turned["arm"][:3, :3]
    np.testing.assert_allclose(arm[:, 2], [math.sin(2.5), 0, math.cos(2.5)], atol=1e-12)


def test_a_prismatic_joint_without_limits_is_held_by_collision_matrix(tmp_path):
    """Unsampled, at its value (given or zero), and named in the report, as MJCF's slide
    joints without a range are (it was refused: 'its range cannot be sampled')."""
    path = robot(tmp_path, slide_limit="")
    out = tmp_path / "m.json"
    result = CliRunner().invoke(
        main,
        ["collision-matrix", str(path), "--samples", "20", "--joint", "slide=0.2"]
        + ["--report", str(out), "-o", str(tmp_path / "m.srdf")],
    )
    assert result.exit_code == 0, result.stderr
    import json

    report = json.loads(out.read_text())
    assert [j["name"] for j in report["joints"]] == ["hinge"]
    assert any(
        "'slide' is a prismatic joint without limits: kept at 0.2" in w for w in report["warnings"]
    )
    (pair,) = [p for p in report["pairs"] if {p["link_a"], p["link_b"]} == {"arm", "slider"}]
    assert pair["class"] in ("never", "sometimes", "always", "default")


def pybullet_data_robots() -> list[Path]:
    pybullet_data = pytest.importorskip(
        "pybullet_data", reason="pip install 'meshcol[robots-wild]'"
    )
    root = Path(pybullet_data.getDataPath())
    names = (
        "quadruped/minitaur.urdf",
        "bicycle/bike.urdf",
        "biped/biped2d_pybullet.urdf",
        "differential/diff_ring.urdf",
        "humanoid/humanoid.urdf",
        "cube_no_rotation.urdf",
        "racecar/racecar_differential.urdf",
        "quadruped/microtaur/microtaur.urdf",
        "quadruped/spirit40newer.urdf",
    )
    return [root / name for name in names]


def test_pybullet_data_robots_read_with_pybullets_link_frames():
    """Each file loads in pybullet and here, with warnings here; at check's default
    configuration (zero, or the middle of limits that exclude it) every link frame but the
    base's is where pybullet puts it (``getLinkState``'s URDF link frame)."""
    pybullet = pytest.importorskip("pybullet", reason="pip install 'meshcol[robots-wild]'")
    for path in pybullet_data_robots():
        model = load_robot_model(path)
        assert model.scene.warnings, path
        kinematics = model.kinematics
        ours = dict(zip(kinematics.links, kinematics.link_poses(kinematics.loaded[None])[0]))
        client = pybullet.connect(pybullet.DIRECT)
        try:
            body = pybullet.loadURDF(str(path), physicsClientId=client, useFixedBase=True)
            joints = range(pybullet.getNumJoints(body, physicsClientId=client))
            for j in joints:
                info = pybullet.getJointInfo(body, j, physicsClientId=client)
                lower, upper = info[8], info[9]  # check's default: zero, or the middle
                value = 0.0 if lower > upper or lower <= 0.0 <= upper else 0.5 * (lower + upper)
                pybullet.resetJointState(body, j, value, physicsClientId=client)
            for j in joints:
                link = pybullet.getJointInfo(body, j, physicsClientId=client)[12].decode()
                frame = pybullet.getLinkState(body, j, physicsClientId=client)[4]
                np.testing.assert_allclose(
                    ours[link][:3, 3], frame, atol=1e-6, err_msg=f"{path}: {link}"
                )
        finally:
            pybullet.disconnect(client)
