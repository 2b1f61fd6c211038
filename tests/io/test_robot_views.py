"""A robot's collision and visual scenes from one read (``load_robot_views``, what
``meshcol inspect`` compares): the same scenes as two reads, an MJCF compiled once, a mesh file
that both use read once, and a visual read that fails left as its error beside the collision
scene."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import UNIT_CUBE_OBJ

import meshcol.io.mesh_read as mesh_read
import meshcol.io.robot as robot_module
from meshcol.cli import main
from meshcol.errors import SceneError
from meshcol.io.robot import load_robot, load_robot_views
from meshcol.types import Capsule, Scene

SAMPLES = Path(__file__).resolve().parents[2] / "samples" / "robot"

#: A link whose first <collision> is a capsule and whose first <visual> a box: the
#: collision's capsule must not stand in for the visual's box.
CAPSULE_ROBOT = """<robot name="cap">
  <link name="base">
    <visual><geometry><box size="0.2 0.2 0.2"/></geometry></visual>
    <collision><geometry><capsule radius="0.1" length="0.4"/></geometry></collision>
  </link>
</robot>
"""

#: An MJCF whose bodies have visual geoms (colliding with nothing) beside colliding ones.
MJCF = """<mujoco>
  <worldbody>
    <body name="base">
      <geom type="box" size="0.1 0.1 0.1"/>
      <geom type="sphere" size="0.15" contype="0" conaffinity="0"/>
      <body name="arm" pos="0 0 0.3">
        <joint name="hinge" type="hinge" axis="0 1 0" range="-1 1"/>
        <geom type="capsule" size="0.05 0.1"/>
        <geom type="box" size="0.06 0.06 0.12" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

#: A visual mesh that is not there: the visual read fails, the collision read does not.
MISSING_VISUAL = """<robot name="mv">
  <link name="base">
    <visual><geometry><mesh filename="gone.stl"/></geometry></visual>
    <collision><geometry><mesh filename="cube.obj"/></geometry></collision>
  </link>
</robot>
"""


def _same(one: Scene, other: Scene) -> None:
    assert [b.name for b in one.bodies] == [b.name for b in other.bodies]
    assert one.excluded_pairs == other.excluded_pairs
    assert one.warnings == other.warnings
    for a, b in zip(one.bodies, other.bodies):
        assert a.primitive == b.primitive and a.parts == b.parts
        assert np.array_equal(a.pose, b.pose)
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


@pytest.mark.parametrize("name", ["arm.urdf", "model.xml"])
def test_views_are_the_two_reads_from_one(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if name.endswith(".xml"):
        pytest.importorskip("mujoco")
        path = tmp_path / name
        path.write_text(MJCF)
    else:
        pytest.importorskip("yourdfpy")
        path = SAMPLES / name
    collision, visual = load_robot(path), load_robot(path, visual=True)
    reads: list[str] = []
    reader = robot_module._reader

    def counted(kind: str):
        read = reader(kind)

        def wrapped(*args, **kwargs):
            reads.append(kind)
            return read(*args, **kwargs)

        return wrapped

    monkeypatch.setattr(robot_module, "_reader", counted)
    views = load_robot_views(path)
    assert len(reads) == 1  # one parse or one compile for both scenes
    assert isinstance(views[1], Scene) and visual.bodies  # the sample has visuals
    _same(views[0], collision)
    _same(views[1], visual)


def test_a_mesh_file_both_scenes_use_is_read_once(monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("yourdfpy")
    batches: list[list[str]] = []
    load_meshes = mesh_read.load_meshes

    def recorded(paths, *args, **kwargs):
        batches.append([Path(p).name for p in paths])
        return load_meshes(paths, *args, **kwargs)

    monkeypatch.setattr(mesh_read, "load_meshes", recorded)
    load_robot_views(SAMPLES / "arm.urdf")
    read = [name for batch in batches for name in batch]
    assert read and len(read) == len(set(read)), batches  # arm's links share their meshes


def test_a_collision_capsule_is_not_the_visual_of_the_same_index(tmp_path: Path) -> None:
    pytest.importorskip("yourdfpy")
    path = tmp_path / "cap.urdf"
    path.write_text(CAPSULE_ROBOT)
    collision, visual = load_robot_views(path)
    assert isinstance(visual, Scene)
    assert collision.bodies[0].primitive == Capsule(0.1, 0.4)
    assert not isinstance(visual.bodies[0].primitive, Capsule)
    size = visual.bodies[0].vertices.max(axis=0) - visual.bodies[0].vertices.min(axis=0)
    assert np.allclose(size, 0.2)


def test_a_visual_read_that_fails_is_its_error_and_inspect_warns(tmp_path: Path) -> None:
    pytest.importorskip("yourdfpy")
    (tmp_path / "cube.obj").write_text(UNIT_CUBE_OBJ)
    path = tmp_path / "mv.urdf"
    path.write_text(MISSING_VISUAL)
    collision, visual = load_robot_views(path)
    assert [b.name for b in collision.bodies] == ["base"]
    assert isinstance(visual, SceneError) and "gone.stl" in str(visual)
    report = tmp_path / "r.json"
    result = CliRunner().invoke(main, ["inspect", str(path), "--report", str(report)])
    assert result.exit_code == 0, result.stderr
    warnings = json.loads(report.read_text())["warnings"]
    assert any(w.startswith("visual geometry not read") and "gone.stl" in w for w in warnings), (
        warnings
    )
