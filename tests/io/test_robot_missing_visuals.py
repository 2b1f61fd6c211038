"""A rebuilt URDF whose input names visual meshes that are not there (issue 29, items 2 and 8).

example-robot-data's romeo_laas_small names visual meshes of an SDK folder that is not
shipped: pybullet refused the URDF ``hull --to urdf`` wrote (it kept those visuals). The URDF
written now leaves out each ``<visual>`` whose mesh file does not exist (a comment in its
place, a warning naming the link and the reference, the same line in the report), and every
reference that exists is rewritten to resolve from the output folder. The robot below is our
own: a package folder beside its ``urdf/`` folder, one visual found through ``package://``,
two missing (one through ``package://``, one relative).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import UNIT_CUBE_OBJ

from meshcol.cli import main

ROBOT = """<robot name="mv">
  <link name="base">
    <visual><geometry><mesh filename="package://pkg/meshes/cube.obj" scale="0.1 0.1 0.1"/></geometry></visual>
    <visual><geometry><mesh filename="package://pkg/meshes/gone.stl"/></geometry></visual>
    <collision><geometry><mesh filename="package://pkg/meshes/cube.obj" scale="0.1 0.1 0.1"/></geometry></collision>
  </link>
  <link name="tip">
    <visual><geometry><mesh filename="../meshes/absent.dae"/></geometry></visual>
    <collision><origin xyz="0 0 0.3"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="tip"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    meshes = tmp_path / "pkg" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "cube.obj").write_text(UNIT_CUBE_OBJ)
    (tmp_path / "pkg" / "urdf").mkdir()
    path = tmp_path / "pkg" / "urdf" / "mv.urdf"
    path.write_text(ROBOT)
    return path


def _written(robot: Path, tmp_path: Path, command: str, *extra: str) -> tuple[Path, str, dict]:
    out, report = tmp_path / f"out-{command}", tmp_path / f"{command}.json"
    result = CliRunner().invoke(
        main, [command, str(robot), "--out-dir", str(out), "--report", str(report), *extra]
    )
    assert result.exit_code == 0, result.stderr
    return out / "mv.urdf", result.stderr, json.loads(report.read_text())


def _missing_lines(lines: list[str]) -> None:
    base = [w for w in lines if "link 'base'" in w]
    tip = [w for w in lines if "link 'tip'" in w]
    assert len(base) == 1 and "'package://pkg/meshes/gone.stl'" in base[0], lines
    assert len(tip) == 1 and "'../meshes/absent.dae'" in tip[0], lines
    assert all("left out of the URDF written" in w for w in base + tip)


def test_missing_visuals_are_left_out_and_the_rest_resolves(robot: Path, tmp_path: Path) -> None:
    etree = pytest.importorskip("lxml.etree")
    urdf, err, report = _written(robot, tmp_path, "hull")
    _missing_lines([line for line in err.splitlines() if line.startswith("meshcol: warning:")])
    _missing_lines(report["warnings"])  # the note in the report
    jsonschema = pytest.importorskip("jsonschema")
    schema = Path(__file__).resolve().parents[2] / "meshcol/schemas/hull_report.schema.json"
    jsonschema.validate(report, json.loads(schema.read_text()))
    root = etree.parse(str(urdf)).getroot()
    visuals = {
        link.get("name"): [m.get("filename") for m in link.iter("mesh") if m.getparent().getparent().tag == "visual"]
        for link in root.findall("link")
    }  # fmt: skip
    assert visuals == {"base": ["../pkg/meshes/cube.obj"], "tip": []}
    assert (urdf.parent / visuals["base"][0]).resolve() == (robot.parents[1] / "meshes/cube.obj")
    comments = [c.text for c in root.iter(etree.Comment)]
    assert any("gone.stl" in c and "left out" in c for c in comments), comments
    # every mesh the URDF names exists, from the output folder
    for mesh in root.iter("mesh"):
        assert (urdf.parent / mesh.get("filename")).is_file(), mesh.get("filename")


def test_pybullet_and_yourdfpy_load_the_urdf_written(robot: Path, tmp_path: Path) -> None:
    pybullet = pytest.importorskip("pybullet", reason="pybullet not installed (make robots-wild)")
    urdf, _, _ = _written(robot, tmp_path, "fit")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(urdf), useFixedBase=True, physicsClientId=client)
        assert pybullet.getNumJoints(body, physicsClientId=client) == 1
    finally:
        pybullet.disconnect(client)
    yourdfpy = pytest.importorskip("yourdfpy")
    loaded = yourdfpy.URDF.load(str(urdf), load_meshes=True, load_collision_meshes=True)
    assert len(loaded.scene.geometry) == 1  # the cube visual, found from the output folder


def test_decompose_and_mjcf_say_so_too(robot: Path, tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    out = tmp_path / "mj"
    result = CliRunner().invoke(main, ["hull", str(robot), "--out-dir", str(out), "--to", "mjcf"])
    assert result.exit_code == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if "left out of the MJCF" in line]
    assert len(lines) == 2, result.stderr
