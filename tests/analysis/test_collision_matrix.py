"""``meshcol collision-matrix``: classes and rates on robots whose answer is known, MoveIt's SRDFs
of the corpus, SRDF written and read back, determinism, bad input."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from lxml import etree

from meshcol.analysis.collision_matrix import collision_matrix
from meshcol.cli import main
from meshcol.io.kinematics import adjacent_links
from meshcol.io.robot import RobotOptions, load_robot_model

# An arm of half thickness W from R0 to R1 about the z axis at height 1, a wall filling y >= 0
# around it: a convex box meets the half-space y >= 0 iff one of its corners does, which is
# (for angle t) R1 sin t + W |cos t| >= 0 or R0 sin t + W |cos t| >= 0, so the arm touches
# the wall for a fraction (pi + 2 atan(W / R0)) / (2 pi) of the turn.
W, R0, R1 = 0.01, 0.1, 1.0
ARM_WALL_RATE = (math.pi + 2 * math.atan(W / R0)) / (2 * math.pi)
# A ball of radius 0.1 lifted by l in [0, 1] above a post whose top is at 0.87: it touches the
# post for l <= 0.97.
SLIDER_POST_RATE = 0.97

ARM_URDF = f"""<?xml version="1.0"?>
<robot name="arm">
  <link name="base">
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="wall">
    <collision><origin xyz="0 1 1"/><geometry><box size="4 2 1"/></geometry></collision>
  </link>
  <joint name="wall_mount" type="fixed"><parent link="base"/><child link="wall"/></joint>
  <link name="spin">
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="spin" type="continuous">
    <origin xyz="0 0 1"/><axis xyz="0 0 1"/><parent link="base"/><child link="spin"/>
  </joint>
  <link name="arm">
    <collision>
      <origin xyz="{(R0 + R1) / 2} 0 0"/><geometry><box size="{R1 - R0} {2 * W} {2 * W}"/></geometry>
    </collision>
  </link>
  <joint name="arm_mount" type="fixed"><parent link="spin"/><child link="arm"/></joint>
  <link name="arm2">
    <collision>
      <origin xyz="{(R0 + R1) / 2} 0 0"/><geometry><box size="{R1 - R0} {2 * W} {2 * W}"/></geometry>
    </collision>
  </link>
  <joint name="spin2" type="continuous">
    <origin xyz="0 0 1"/><axis xyz="0 0 1"/><parent link="base"/><child link="arm2"/>
    <mimic joint="spin" multiplier="-1"/>
  </joint>
  <link name="post">
    <collision><origin xyz="3 0 -0.065"/><geometry><box size="0.2 0.2 1.87"/></geometry></collision>
  </link>
  <joint name="post_mount" type="fixed"><parent link="base"/><child link="post"/></joint>
  <link name="slider">
    <collision><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
  <joint name="lift" type="prismatic">
    <origin xyz="3 0 0"/><axis xyz="0 0 1"/><parent link="base"/><child link="slider"/>
    <limit lower="0" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>
"""

ADJACENT = {
    ("base", "wall"),
    ("base", "spin"),
    ("arm", "spin"),
    ("arm2", "base"),
    ("base", "post"),
    ("base", "slider"),
}

ARM_MJCF = f"""<mujoco model="mjarm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <geom type="sphere" size="0.05"/>
      <body name="wall"><geom type="box" pos="0 1 1" size="2 1 0.5"/></body>
      <body name="arm" pos="0 0 1">
        <joint name="spin" type="hinge" axis="0 0 1" range="-3.141592653589793 3.141592653589793"/>
        <geom type="box" pos="{(R0 + R1) / 2} 0 0" size="{(R1 - R0) / 2} {W} {W}"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def arm(tmp_path: Path) -> Path:
    path = tmp_path / "arm.urdf"
    path.write_text(ARM_URDF)
    return path


def by_pair(report) -> dict:
    return {(p["link_a"], p["link_b"]): p for p in report.pairs}


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def within(rate: float, expected: float, samples: int) -> bool:
    """Within 4.5 standard deviations of a binomial proportion (a false alarm ~1e-5)."""
    return abs(rate - expected) <= 4.5 * math.sqrt(expected * (1 - expected) / samples) + 1e-12


# ---------------------------------------------------------------------------------------------
# Known answers


def test_classes_and_rates_at_the_zero_default(arm: Path) -> None:
    report = collision_matrix(arm, samples=4000, seed=3)
    pairs = by_pair(report)
    assert len(pairs) == 21  # 7 links with geometry
    assert {k for k, p in pairs.items() if p["class"] == "adjacent"} == ADJACENT
    # At zero both arms point along +x: they overlap each other and touch the wall; the ball
    # rests in the post; the hub always sits in the wall.
    default = {("arm", "wall"), ("arm2", "wall"), ("arm", "arm2"), ("spin", "wall")}
    default.add(("post", "slider"))
    assert {k for k, p in pairs.items() if p["class"] == "default"} == default
    assert pairs[("spin", "wall")]["rate"] == 1.0
    never = set(pairs) - ADJACENT - default
    assert {k for k, p in pairs.items() if p["class"] == "never"} == never
    assert all(pairs[k]["collisions"] == 0 for k in never)
    assert within(pairs[("arm", "wall")]["rate"], ARM_WALL_RATE, 4000)
    assert within(pairs[("post", "slider")]["rate"], SLIDER_POST_RATE, 4000)
    # adjacent pairs are never measured, as MoveIt never checks them
    assert all(pairs[k]["rate"] is None and pairs[k]["collisions"] is None for k in ADJACENT)
    s = report.summary
    assert s["pairs_by_class"] == {
        "adjacent": 6,
        "excluded": 0,
        "default": 5,
        "always": 0,
        "never": 10,
        "sometimes": 0,
    }
    assert s["samples"] == 4000 and s["seed"] == 3 and s["sampled_joints"] == 2
    assert s["seconds_per_configuration"] > 0 and s["failed_queries"] == 0
    assert [j["name"] for j in report.joints] == ["spin", "lift"]
    assert report.joints[0]["lower"] == -math.pi and report.joints[0]["upper"] == math.pi


def test_default_configuration_from_the_joint_values(arm: Path) -> None:
    # The arm pointing at -y clears the wall (its mimic twin points at +y); the ball lifted
    # clear of the post collides in 97 % of the samples: always.
    given = RobotOptions(joints={"spin": -math.pi / 2, "lift": 1.0})
    report = collision_matrix(arm, samples=4000, seed=3, robot_options=given)
    pairs = by_pair(report)
    assert pairs[("arm", "wall")]["class"] == "sometimes"
    assert within(pairs[("arm", "wall")]["rate"], ARM_WALL_RATE, 4000)
    assert pairs[("arm2", "wall")]["class"] == "default"
    assert pairs[("post", "slider")]["class"] == "always"
    assert pairs[("post", "slider")]["reason"] == "Always"
    assert pairs[("arm", "arm2")]["class"] == "sometimes"
    assert 0 < pairs[("arm", "arm2")]["rate"] < 0.2
    assert [j["default"] for j in report.joints] == [-math.pi / 2, 1.0]
    # sometimes pairs are not written
    assert ("arm", "wall", "Never") not in report.disabled_pairs()
    assert all(p["reason"] is None for p in report.pairs if p["class"] == "sometimes")


def test_mimic_joint_follows_its_leader(arm: Path) -> None:
    model = load_robot_model(arm)
    kin = model.kinematics
    assert kin.space.names == ("spin", "lift")
    q = kin.space.sample(50, seed=1)
    poses = kin.link_poses(q)
    arm_i, arm2_i, slider_i = (kin.links.index(n) for n in ("arm", "arm2", "slider"))
    angle = np.arctan2(poses[:, arm_i, 1, 0], poses[:, arm_i, 0, 0])
    angle2 = np.arctan2(poses[:, arm2_i, 1, 0], poses[:, arm2_i, 0, 0])
    np.testing.assert_allclose(angle, np.angle(np.exp(1j * q[:, 0])), atol=1e-12)
    np.testing.assert_allclose(angle2, -angle, atol=1e-12)
    np.testing.assert_allclose(poses[:, slider_i, 2, 3], q[:, 1], atol=1e-12)
    # the batched poses at the loaded configuration are the scene's
    at = kin.link_poses(kin.loaded[None])[0]
    for body in model.scene.bodies:
        if body.primitive is None:
            np.testing.assert_allclose(at[kin.links.index(body.name)], body.pose, atol=1e-12)


def test_adjacency_through_links_without_geometry() -> None:
    # a - f - {b, c} with f bare: a, b and c are all adjacent; d below b is adjacent to b only
    links = ["a", "f", "b", "c", "d"]
    edges = np.array([[0, 1], [1, 2], [1, 3], [2, 4]])
    assert adjacent_links(links, edges, ["a", "b", "c", "d"]) == [
        ("a", "b"),
        ("a", "c"),
        ("b", "c"),
        ("b", "d"),
    ]


def test_mjcf_input(tmp_path: Path) -> None:
    path = tmp_path / "arm.xml"
    path.write_text(ARM_MJCF)
    report = collision_matrix(path, samples=3000, seed=2)
    pairs = by_pair(report)
    assert report.robot == "mjarm"
    assert {k for k, p in pairs.items() if p["class"] == "adjacent"} == {
        ("arm", "base"),
        ("base", "wall"),
    }
    assert pairs[("arm", "wall")]["class"] == "default"
    assert within(pairs[("arm", "wall")]["rate"], ARM_WALL_RATE, 3000)


def test_padding_counts_near_misses(arm: Path) -> None:
    # the hub (radius 0.05) and the arm (from 0.1) are 0.05 apart: padded by 0.06 they collide
    plain = by_pair(collision_matrix(arm, samples=200, seed=1))
    padded = by_pair(collision_matrix(arm, samples=200, seed=1, padding=0.06))
    assert plain[("arm2", "spin")]["class"] == "never"
    assert padded[("arm2", "spin")]["rate"] == 1.0


# ---------------------------------------------------------------------------------------------
# Determinism


def test_same_seed_same_matrix_whatever_the_batch(arm: Path) -> None:
    one = collision_matrix(arm, samples=600, seed=7)
    two = collision_matrix(arm, samples=600, seed=7, batch=37, threads=1)
    other = collision_matrix(arm, samples=600, seed=8)
    assert one.pairs == two.pairs
    assert [p["collisions"] for p in one.pairs] != [p["collisions"] for p in other.pairs]


def test_a_robot_of_many_links_takes_fewer_configurations_a_call() -> None:
    """A call's broad phase holds configurations x link pairs boxes: a chain of 500 links
    (124,750 pairs) took 1,024 configurations a call, 7 GB, before BATCH_PAIRS bounded it."""
    from meshcol.analysis.collision_matrix import BATCH_PAIRS, MatrixOptions, _batch

    options = MatrixOptions()
    assert _batch(options, 1_000, 21) == 262  # an arm: the vertices bound it, as before
    assert _batch(options, 1_000, 124_750) * 124_750 <= BATCH_PAIRS
    assert _batch(options, 1_000, 10**8) == 1  # never none
    assert _batch(MatrixOptions(batch=37), 1_000, 124_750) == 37  # the caller's choice wins


# ---------------------------------------------------------------------------------------------
# CLI, SRDF written and read back


def test_cli_writes_srdf_and_report_and_check_reads_it(arm: Path, tmp_path: Path) -> None:
    srdf, report = tmp_path / "arm.srdf", tmp_path / "m.json"
    result = run(
        "collision-matrix", str(arm), "--samples", "500", "-o", str(srdf), "--report", str(report)
    )
    assert result.exit_code == 0, result.output
    assert "collision-matrix: PASS: 21 pairs disabled, 0 pairs still checked" in result.stderr
    data = json.loads(report.read_text())
    assert data["command"] == "collision-matrix" and data["settings"]["samples"] == 500
    root = etree.parse(str(srdf)).getroot()
    assert root.tag == "robot" and root.get("name") == "arm"
    written = {
        (e.get("link1"), e.get("link2"), e.get("reason")) for e in root.iter("disable_collisions")
    }
    expected = {
        (p["link_a"], p["link_b"], p["reason"]) for p in data["pairs"] if p["reason"] is not None
    }
    assert written == expected and len(written) == 21
    # meshcol's own reader takes it: every pair excluded, the check passes
    scene = load_robot_model(arm, RobotOptions(srdf=str(srdf))).scene
    assert len(scene.excluded_pairs) == 21
    checked = run("check", str(arm), "--srdf", str(srdf), "--include-adjacent")
    assert checked.exit_code == 0, checked.output
    assert json.loads(checked.stdout)["summary"]["candidate_pairs"] == 0


def test_cli_srdf_to_stdout_by_default(arm: Path) -> None:
    result = run("collision-matrix", str(arm), "--samples", "50")
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith('<?xml version="1.0" encoding="UTF-8"?>\n<robot name="arm">')
    report = run("collision-matrix", str(arm), "--samples", "50", "--report", "-")
    assert json.loads(report.stdout)["summary"]["samples"] == 50


# ---------------------------------------------------------------------------------------------
# Bad input: one line, exit 2, nothing written


@pytest.mark.parametrize(
    "args, message",
    [
        (["--samples", "0"], "invalid value for '--samples': 0 is not in the range x>=1"),
        (["--seed", "-1"], "invalid value for '--seed': -1 is not in the range x>=0"),
        (["--padding", "nan"], "invalid value for '--padding': 'nan' is not a finite number"),
    ],
)
def test_bad_options(arm: Path, tmp_path: Path, args: list[str], message: str) -> None:
    out = tmp_path / "out.srdf"
    result = run("collision-matrix", str(arm), "-o", str(out), *args)
    assert result.exit_code == 2
    assert result.stderr == f"meshcol: error: {message} (see 'meshcol collision-matrix -h')\n"
    assert not out.exists()


def test_unwritable_output(arm: Path, tmp_path: Path) -> None:
    report = tmp_path / "m.json"
    result = run(
        "collision-matrix",
        str(arm),
        "--samples",
        "10",
        "-o",
        str(tmp_path / "missing" / "x.srdf"),
        "--report",
        str(report),
    )
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("meshcol: error: ") and "missing" in lines[0]
    assert not report.exists()


def test_malformed_robot(tmp_path: Path) -> None:
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="x"><link name="a">')
    out = tmp_path / "out.srdf"
    result = run("collision-matrix", str(bad), "-o", str(out))
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.urdf" in lines[0] and "malformed XML" in lines[0]
    assert not out.exists()


def test_not_a_robot(tmp_path: Path) -> None:
    mesh = tmp_path / "cube.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    result = run("collision-matrix", str(mesh))
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        f"meshcol: error: {mesh}: not a robot description (expected .urdf, .mjcf, or .xml with "
        "<robot> or <mujoco>)"
    )


def test_output_and_report_one_file(arm: Path, tmp_path: Path) -> None:
    same = str(tmp_path / "x.json")
    result = run("collision-matrix", str(arm), "-o", same, "--report", same)
    assert result.exit_code == 2 and "give two files" in result.stderr
    assert not Path(same).exists()


def test_unknown_joint_value(arm: Path) -> None:
    result = run("collision-matrix", str(arm), "--joint", "nope=1")
    assert result.exit_code == 2
    assert "joint 'nope' does not exist" in result.stderr


# ---------------------------------------------------------------------------------------------
# Golden report (timings zeroed)


def test_golden_report(arm: Path, golden, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(arm.parent)
    result = run("collision-matrix", "arm.urdf", "--samples", "300", "--seed", "5", "--report", "-")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    data = copy.deepcopy(data)
    data["tool"]["version"] = "<version>"
    for key in (
        "seconds",
        "load_seconds",
        "kinematics_seconds",
        "collision_seconds",
        "seconds_per_configuration",
    ):
        data["summary"][key] = 0.0
    golden("collision-matrix_arm.json", json.dumps(data, sort_keys=True, indent=2) + "\n")


# ---------------------------------------------------------------------------------------------
# MoveIt's matrices of the corpus


def _srdf_pairs(path: Path) -> dict[tuple[str, str], str]:
    root = etree.parse(str(path)).getroot()
    return {
        tuple(sorted((e.get("link1"), e.get("link2")))): e.get("reason")
        for e in root.iter("disable_collisions")
    }


def test_panda_matches_moveit(corpus: Path) -> None:
    panda = corpus / "robots" / "panda_description"
    report = collision_matrix(panda / "urdf" / "panda.urdf", samples=10_000, seed=1)
    ours = {(p["link_a"], p["link_b"]): p["reason"] for p in report.pairs if p["reason"]}
    theirs = _srdf_pairs(panda / "srdf" / "panda.srdf")
    adjacent = {k for k, r in theirs.items() if r == "Adjacent"}
    assert {k for k, r in ours.items() if r == "Adjacent"} == adjacent
    # The Default and Never entries: hulls are larger than MoveIt's meshes (so a pair MoveIt
    # never saw colliding may be seen here), and 10,000 samples miss rare contacts either way;
    # on the Panda every entry agrees, reason included.
    same = {k for k in theirs if ours.get(k) == theirs[k]}
    assert len(same) / len(theirs) >= 0.95
    assert len(set(ours) ^ set(theirs)) <= 2


def test_solo_matches_its_srdf(corpus: Path) -> None:
    solo = corpus / "robots" / "solo_description"
    report = collision_matrix(solo / "robots" / "solo12.urdf", samples=2000, seed=1)
    ours = {(p["link_a"], p["link_b"]): p["reason"] for p in report.pairs if p["reason"]}
    theirs = _srdf_pairs(solo / "srdf" / "solo.srdf")
    assert set(theirs.values()) == {"Adjacent"}  # a hand-written SRDF: adjacent links only
    adjacent = {k for k, r in ours.items() if r == "Adjacent"}
    assert set(theirs) <= adjacent
    # the four feet, on fixed ankle joints, are adjacent to their lower legs (MoveIt says so
    # too); the hand-written SRDF leaves them out
    assert adjacent - set(theirs) == {
        (f"{leg}_FOOT", f"{leg}_LOWER_LEG") for leg in ["FL", "FR", "HL", "HR"]
    }


def test_default_is_the_middle_of_limits_that_exclude_zero(tmp_path: Path) -> None:
    # as MoveIt's setToDefaultValues: the ball sits at 1.5, inside the post reaching 1.6; it
    # touches the post for lift <= 1.65
    path = tmp_path / "lift.urdf"
    path.write_text(
        '<robot name="lift"><link name="base"><collision><origin xyz="0 0 0.8"/><geometry>'
        '<box size="0.2 0.2 1.6"/></geometry></collision></link>'
        '<link name="mid"><collision><origin xyz="5 0 0"/><geometry><sphere radius="0.1"/>'
        "</geometry></collision></link>"
        '<joint name="m" type="fixed"><parent link="base"/><child link="mid"/></joint>'
        '<link name="ball"><collision><geometry><sphere radius="0.05"/></geometry></collision>'
        '</link><joint name="lift" type="prismatic"><axis xyz="0 0 1"/><parent link="mid"/>'
        '<child link="ball"/>'
        '<limit lower="1" upper="2" effort="1" velocity="1"/></joint></robot>'
    )
    report = collision_matrix(path, samples=400, seed=0)
    assert report.joints == [{"name": "lift", "lower": 1.0, "upper": 2.0, "default": 1.5}]
    pairs = by_pair(report)
    assert pairs[("ball", "base")]["class"] == "default"
    assert within(pairs[("ball", "base")]["rate"], 0.65, 400)
    assert report.warnings == [
        "joint 'lift': zero is outside its limits [1, 2]; the default configuration has it at "
        "the middle, 1.5 (give --joint lift=VALUE to choose)"
    ]
