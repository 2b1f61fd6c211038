"""Robots whose links have no collision geometry (issue 29, rule MC506).

Five robots of example-robot-data (human.urdf, TwoDofs, ...), gymnasium's swimmer and three
MuJoCo Menagerie models have only visual geometry: pybullet and MuJoCo load them, there is
simply nothing to collide. meshcol refused them with exit 2 ("no link has collision
geometry"); every robot command now takes them: exit 0 with an MC506 finding naming the file,
zero pairs, an SRDF that disables nothing, and ``--to`` outputs without colliders that their
consumers load. ``--fail-on MC506`` fails the run (exit 1). A description that is broken
(no link at all, not XML) is still refused (exit 2). The robots below are our own.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from meshcol.cli import main

#: Three links and two joints, each link with a <visual> box and no <collision>.
VISUAL_URDF = """<?xml version="1.0"?>
<robot name="ghost">
  <link name="base"><visual><geometry><box size="0.2 0.2 0.1"/></geometry></visual></link>
  <link name="arm">
    <visual><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.03" length="0.5"/></geometry></visual>
  </link>
  <link name="hand"><visual><geometry><sphere radius="0.05"/></geometry></visual></link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.05"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="wrist" type="fixed"><parent link="arm"/><child link="hand"/><origin xyz="0 0 0.5"/></joint>
</robot>
"""

#: The same in MJCF: every geom ``contype="0" conaffinity="0"`` (as gymnasium's swimmer body).
VISUAL_MJCF = """<mujoco model="ghost">
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="base" pos="0 0 0.5">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.05"/>
      <body name="arm" pos="0 0 0.05">
        <joint name="shoulder" type="hinge" axis="0 1 0" range="-1 1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.5" size="0.03"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def run(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stderr


@pytest.fixture
def ghost_urdf(tmp_path: Path) -> Path:
    path = tmp_path / "ghost.urdf"
    path.write_text(VISUAL_URDF)
    return path


@pytest.fixture
def ghost_mjcf(tmp_path: Path) -> Path:
    pytest.importorskip("mujoco")
    path = tmp_path / "ghost.xml"
    path.write_text(VISUAL_MJCF)
    return path


def _valid(report: dict) -> dict:
    """The report, checked against its published schema."""
    import jsonschema

    schemas = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"
    schema = json.loads((schemas / f"{report['command']}_report.schema.json").read_text())
    jsonschema.validate(report, schema)
    return report


def _mc506(findings: list[dict], robot: Path) -> dict:
    (found,) = [f for f in findings if f["rule"] == "MC506"]
    assert found["name"] == "no-collision-geometry" and found["severity"] == "warning"
    assert found["body"] == robot.name and robot.name in found["message"]
    assert "no link has collision geometry" in found["message"]
    return found


@pytest.mark.parametrize("kind", ["urdf", "mjcf"])
def test_check_reports_zero_pairs_and_the_finding(kind, request, tmp_path: Path) -> None:
    robot = request.getfixturevalue(f"ghost_{kind}")
    report = tmp_path / "r.json"
    code, err = run("check", str(robot), "--report", str(report))
    assert code == 0, err
    data = _valid(json.loads(report.read_text()))
    assert data["pairs"] == [] and data["summary"]["bodies"] == 0
    _mc506(data["findings"], robot)
    assert not any(f["failed"] for f in data["findings"])
    # one warning line on stderr naming the rule and the file
    warning = [line for line in err.splitlines() if "MC506" in line]
    assert len(warning) == 1 and robot.name in warning[0], err
    assert "no link has collision geometry" in warning[0]


@pytest.mark.parametrize("fail_on", ["MC506", "no-collision-geometry", "all"])
def test_fail_on_the_rule_exits_1(ghost_urdf: Path, tmp_path: Path, fail_on: str) -> None:
    report = tmp_path / "r.json"
    code, err = run("check", str(ghost_urdf), "--fail-on", fail_on, "--report", str(report))
    assert code == 1, err
    assert _mc506(json.loads(report.read_text())["findings"], ghost_urdf)["failed"] is True
    assert "MC506" in err and "fail" in err


def test_inspect_reports_the_finding(ghost_urdf: Path, tmp_path: Path) -> None:
    report = tmp_path / "i.json"
    code, err = run("inspect", str(ghost_urdf), "--report", str(report))
    assert code == 0, err
    _mc506(json.loads(report.read_text())["findings"], ghost_urdf)
    code, err = run("inspect", str(ghost_urdf), "--fail-on", "MC506")
    assert code == 1, err


def test_collision_matrix_writes_an_srdf_that_disables_nothing(
    ghost_urdf: Path, tmp_path: Path
) -> None:
    # srdfdom's Model::initXml (MoveIt's SRDF parser, src/model.cpp) needs a <robot> root
    # whose name is the URDF's; every child (groups, disable_collisions, ...) is optional:
    # a <robot> without <disable_collisions> is a model with no pair disabled.
    etree = pytest.importorskip("lxml.etree")
    from meshcol.io.srdf import read_srdf

    srdf, report = tmp_path / "ghost.srdf", tmp_path / "m.json"
    code, err = run(
        "collision-matrix", str(ghost_urdf), "--samples", "50", "-o", str(srdf),
        "--report", str(report),
    )  # fmt: skip
    assert code == 0, err
    root = etree.parse(str(srdf)).getroot()
    assert root.tag == "robot" and root.get("name") == "ghost"
    assert root.findall("disable_collisions") == []
    assert read_srdf(str(srdf), {"base", "arm", "hand"}) == ([], [])
    data = _valid(json.loads(report.read_text()))
    assert data["pairs"] == [] and data["summary"]["links"] == 0
    _mc506(data["findings"], ghost_urdf)
    assert "MC506" in err


def test_collision_matrix_of_an_mjcf(ghost_mjcf: Path, tmp_path: Path) -> None:
    report = tmp_path / "m.json"
    code, err = run("collision-matrix", str(ghost_mjcf), "--samples", "20", "--report", str(report))
    assert code == 0, err
    _mc506(json.loads(report.read_text())["findings"], ghost_mjcf)


def _load_urdf_peers(urdf: Path) -> None:
    """pybullet and yourdfpy load the URDF written (each skipped when missing)."""
    try:
        import pybullet
    except ImportError:
        pass
    else:
        client = pybullet.connect(pybullet.DIRECT)
        try:
            body = pybullet.loadURDF(str(urdf), useFixedBase=True, physicsClientId=client)
            assert pybullet.getNumJoints(body, physicsClientId=client) == 2
        finally:
            pybullet.disconnect(client)
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(urdf), load_collision_meshes=True)
    assert sorted(robot.link_map) == ["arm", "base", "hand"]


def _simulate(xml: Path) -> None:
    """MuJoCo compiles the MJCF written and steps it 100 times."""
    import mujoco
    import numpy as np

    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    for _ in range(100):
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos))
    assert data.ncon == 0  # nothing collides


@pytest.mark.parametrize("command", ["hull", "fit"])
def test_every_output_is_written_and_loads(ghost_urdf: Path, tmp_path: Path, command) -> None:
    pytest.importorskip("mujoco")
    for to in ("urdf", "mjcf", "glb", "usd"):
        if to == "usd" and not _has("pxr"):
            continue
        out = tmp_path / f"{command}-{to}"
        code, err = run(command, str(ghost_urdf), "--out-dir", str(out), "--to", to)
        assert code == 0, (to, err)
        assert "MC506" in err, err
        written = {p.suffix for p in out.iterdir()}
        assert written == {{"urdf": ".urdf", "mjcf": ".xml", "glb": ".glb", "usd": ".usda"}[to]}
        description = next(out.iterdir())
        if to == "urdf":
            _load_urdf_peers(description)
        elif to == "mjcf":
            _simulate(description)
        elif to == "glb":
            trimesh = pytest.importorskip("trimesh")
            assert len(trimesh.load(str(description), force="scene").geometry) == 0
        else:
            from pxr import Usd, UsdPhysics

            stage = Usd.Stage.Open(str(description))
            assert stage is not None
            assert not any(p.HasAPI(UsdPhysics.CollisionAPI) for p in stage.Traverse())


def test_an_mjcf_rebuilt_loads(ghost_mjcf: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, err = run("hull", str(ghost_mjcf), "--out-dir", str(out), "--to", "mjcf")
    assert code == 0, err
    _simulate(out / "ghost.xml")


def test_decompose_writes_the_description(ghost_urdf: Path, tmp_path: Path) -> None:
    out, report = tmp_path / "out", tmp_path / "d.json"
    code, err = run("decompose", str(ghost_urdf), "--out-dir", str(out), "--report", str(report))
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["ghost.urdf"]
    assert "MC506" in err
    (entry,) = _valid(json.loads(report.read_text()))["files"]
    assert "MC506" in entry["message"] and entry["status"] == "ok"
    _load_urdf_peers(out / "ghost.urdf")


def _has(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is not None


@pytest.mark.parametrize(
    ("name", "text", "words"),
    [
        ("empty.urdf", '<robot name="empty"></robot>', "the robot has no <link> element"),
        ("cut.urdf", '<robot name="cut"><link name="a">', "malformed XML"),
        ("empty.xml", "<mujoco/>", "the model has no body and no geom"),
    ],
)
def test_a_broken_description_is_still_refused(tmp_path: Path, name, text, words) -> None:
    if name.endswith(".xml"):
        pytest.importorskip("mujoco")
    path = tmp_path / name
    path.write_text(text)
    for command in ("check", "collision-matrix", "inspect", "hull"):
        extra = ["--out-dir", str(tmp_path / "out")] if command == "hull" else []
        code, err = run(command, str(path), *extra)
        assert code == 2, (command, err)
        assert words in err and name in err, (command, err)
        assert not (tmp_path / "out").exists()


def test_the_api_returns_the_finding(ghost_urdf: Path) -> None:
    import meshcol

    report = meshcol.check(ghost_urdf)
    assert report.exit_code == 0 and report.to_dict()["pairs"] == []
    assert [f["rule"] for f in report.findings] == ["MC506"]
    assert meshcol.load_robot(ghost_urdf).bodies == ()


@pytest.mark.parametrize("command", ["hull", "fit"])
def test_the_robot_as_meshes_warns(ghost_urdf: Path, tmp_path: Path, command: str) -> None:
    code, err = run(command, str(ghost_urdf), "-o", str(tmp_path / "all.obj"))
    assert code == 0, err
    assert "MC506 no-collision-geometry" in err and "ghost.urdf" in err


@pytest.mark.parametrize("fmt", ["junit", "sarif", "github"])
def test_ci_formats_carry_the_failing_finding(ghost_urdf: Path, tmp_path: Path, fmt) -> None:
    # A --fail-on list of rules (not a level) crashed every CI format (KeyError: 'MC506').
    report = tmp_path / f"r.{fmt}"
    code, err = run(
        "check", str(ghost_urdf), "--fail-on", "MC506", "--format", fmt, "--report", str(report)
    )
    assert code == 1, err
    assert "MC506" in report.read_text() and "Traceback" not in err


def test_a_rule_list_spares_ignored_pairs_in_junit(tmp_path: Path) -> None:
    # Two overlapping boxes, --fail-on MC501 with the pair ignored: a skipped case (as the
    # level 'penetration' gives), not a KeyError.
    box = "<geometry><box size='1 1 1'/></geometry>"
    robot = tmp_path / "two.urdf"
    robot.write_text(
        f"<robot name='two'><link name='a'><collision>{box}</collision></link>"
        f"<link name='b'><collision><origin xyz='0.5 0 0'/>{box}</collision></link>"
        "<joint name='j' type='floating'><parent link='a'/><child link='b'/></joint></robot>"
    )
    for fail_on in ("MC501", "penetration"):
        report = tmp_path / f"{fail_on}.xml"
        args = ["--include-adjacent", "--ignore", "a:b", "--format", "junit"]
        code, err = run("check", str(robot), "--fail-on", fail_on, *args, "--report", str(report))
        assert code == 0, err
        assert "<skipped" in report.read_text() and "ignored by --ignore" in report.read_text()


def test_inspect_keeps_the_warnings_of_reading_the_robot(tmp_path: Path) -> None:
    # inspect dropped what reading the description warned of (here a xacro leftover).
    robot = tmp_path / "x.urdf"
    robot.write_text(
        "<robot name='x'><link name='a'><collision><origin xyz='0 0 $(optenv Z 0.5)'/>"
        "<geometry><box size='1 1 1'/></geometry></collision></link></robot>"
    )
    report = tmp_path / "i.json"
    code, err = run("inspect", str(robot), "--report", str(report))
    assert code == 0, err
    (warning,) = json.loads(report.read_text())["warnings"]
    assert "xacro leftover" in warning and "$(optenv Z 0.5)" in warning
    assert "xacro leftover" in err


def test_a_rebuild_prints_the_warnings_of_reading_the_robot(tmp_path: Path) -> None:
    # hull/fit/decompose ROBOT --out-dir dropped what reading the robot warned of.
    robot = tmp_path / "x.urdf"
    robot.write_text(
        "<robot name='x'><link name='a'><collision><origin xyz='0 0 $(optenv Z 0.5)'/>"
        "<geometry><box size='1 1 1'/></geometry></collision></link></robot>"
    )
    code, err = run("hull", str(robot), "--out-dir", str(tmp_path / "out"))
    assert code == 0, err
    assert "xacro leftover" in err and "$(optenv Z 0.5)" in err
