"""COLLADA files of the installed robot collections (example-robot-data, pybullet_data, ...)
read as the ROS tools read them: in the unit the file declares, its up axis not applied (RViz).
Oracles: tiago's STL visuals of the same links, and pybullet's own COLLADA loader. Each test
skips, with the reason, when its collection is missing (pip install 'meshcol[robots-wild]').
"""

from __future__ import annotations

import site
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from dae_files import placed_cube
from wild_collections import collection_file

from meshcol.cli import main
from meshcol.io.mesh_read import load_mesh

pytest.importorskip("collada", reason="COLLADA needs pycollada (pip install 'meshcol[robots]')")

TIAGO_ARM = ("tiago_description", "meshes", "arm")

#: tiago's arm: each collision DAE (Y_UP, metres) and the STL visual of the same link.
TIAGO_PAIRS = [(f"arm_{n}_collision.dae", f"arm_{n}.stl") for n in range(1, 7)] + [
    ("arm_5_collision-wrist-2010.dae", "arm_5-wrist-2010.stl"),
    ("arm_6_collision-wrist-2010.dae", "arm_6-wrist-2010.stl"),
]

#: A few wild files for the fast lane: tiago (Y_UP), pybullet's centimetre duck and inch
#: cone, anymal's foot (a material missing from its library), a racecar part of two nodes.
FAST_WILD = [
    ("example-robot-data", *TIAGO_ARM, "arm_1_collision.dae"),
    ("example-robot-data", "anymal_b_simple_description", "meshes", "foot", "anymal_foot.dae"),
    ("pybullet_data", "duck.dae"),
    ("pybullet_data", "racecar", "meshes", "cone.dae"),
    ("pybullet_data", "racecar", "meshes", "hokuyo.dae"),
]


def bounds(path: Path) -> np.ndarray:
    """(2, 3) world bounds of every body of a mesh file."""
    bodies = load_mesh(path)
    points = np.concatenate([b.vertices @ b.pose[:3, :3].T + b.pose[:3, 3] for b in bodies])
    return np.array([points.min(axis=0), points.max(axis=0)])


@pytest.mark.parametrize("collision, visual", TIAGO_PAIRS)
def test_tiago_collision_dae_matches_its_stl_visual(collision, visual):
    dae = bounds(collection_file("example-robot-data", *TIAGO_ARM, collision))
    stl = bounds(collection_file("example-robot-data", *TIAGO_ARM, visual))
    assert np.abs(dae - stl).max() < 0.002
    # the file says Y_UP: turned to Z up (x, -z, y) it would not match (by 4.7 to 224 mm)
    turned = np.sort(np.array([dae[:, 0], -dae[:, 2], dae[:, 1]]).T, axis=0)
    assert np.abs(turned - stl).max() > 0.002


def test_pybullet_scales_the_units_as_meshcol(tmp_path):
    """pybullet's COLLADA loader (Bullet's, not pycollada) as the oracle of the unit: the
    collision mesh it builds from a URDF (its convex hull's vertices, ``getMeshData``) has
    the bounds meshcol reads, on the inch cone (Z_UP), a generated centimetre cube and the
    centimetre duck (Y_UP: pybullet's collision mesh does not turn it either)."""
    pybullet = pytest.importorskip("pybullet", reason="pip install 'meshcol[robots-wild]'")
    cone = collection_file("pybullet_data", "racecar", "meshes", "cone.dae")
    duck = collection_file("pybullet_data", "duck.dae")
    cube = tmp_path / "cube_cm.dae"
    cube.write_text(placed_cube("0.01"))
    client = pybullet.connect(pybullet.DIRECT)
    try:
        for mesh in (cone, cube, duck):
            robot = tmp_path / f"{mesh.stem}.urdf"  # pybullet caches a URDF by its name
            robot.write_text(
                f'<robot name="r"><link name="l"><collision><geometry><mesh filename="{mesh}"/>'
                "</geometry></collision></link></robot>"
            )
            body = pybullet.loadURDF(str(robot), useFixedBase=True, physicsClientId=client)
            count, vertices = pybullet.getMeshData(body, physicsClientId=client)
            assert count > 0
            points = np.array(vertices)
            expected = [points.min(axis=0), points.max(axis=0)]
            np.testing.assert_allclose(bounds(mesh), expected, atol=1e-5, err_msg=mesh.name)
    finally:
        pybullet.disconnect(client)
    np.testing.assert_allclose(bounds(cone), [[-0.075, -0.075, 0], [0.075, 0.075, 0.17]], atol=1e-6)


def inspect_cleanly(path: Path) -> None:
    """``meshcol inspect PATH`` reads the file: a report, no error, no traceback."""
    result = CliRunner().invoke(main, ["inspect", str(path), "--format", "json"])
    assert "Traceback" not in result.output, result.output
    assert result.exit_code == 0, f"{path}: {result.stderr}"
    assert '"units": "m"' in result.stdout


@pytest.mark.parametrize("parts", FAST_WILD, ids=[parts[-1] for parts in FAST_WILD])
def test_wild_dae_files_inspect_cleanly(parts):
    inspect_cleanly(collection_file(*parts))


def wild_dae_files() -> list[Path]:
    """Every .dae file of the installed packages (300 with the robots-wild extras)."""
    found: set[Path] = set()
    for base in site.getsitepackages():
        found.update(p for p in Path(base).rglob("*") if p.suffix.lower() == ".dae")
    return sorted(found)


def test_every_wild_dae_file_inspects_cleanly():
    files = wild_dae_files()
    if not files:
        pytest.skip("no COLLADA file installed (pip install 'meshcol[robots-wild]')")
    for path in files:
        inspect_cleanly(path)
