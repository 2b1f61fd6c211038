"""Collider kinds: one builder per word of the vocabulary, and the kinds added by that recipe.

``box`` and ``sphere`` (each part's enclosing oriented box or minimum sphere) were added by
ARCHITECTURE.md's recipe "Add a collider kind": a word in ``meshcol.vocabulary`` and an entry
in ``analysis.colliders._BUILDERS``; the command-line choices follow by themselves.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from meshcol.analysis import colliders
from meshcol.analysis.colliders import build_colliders
from meshcol.cli import main
from meshcol.collision.shapes import ShapeKind
from meshcol.io.mesh_write import obj_text
from meshcol.io.scene import load_inputs
from meshcol.vocabulary import COLLIDER_KINDS

SAMPLES = os.path.join(os.path.dirname(__file__), "..", "samples")


def _scene(tmp_path, objects: dict[str, trimesh.Trimesh]):
    path = tmp_path / "parts.obj"
    path.write_text(obj_text([(n, m.vertices, m.faces) for n, m in objects.items()]))
    manifest = tmp_path / "scene.json"
    manifest.write_text(json.dumps({"units": "m", "bodies": [{"name": "b", "mesh": "parts.obj"}]}))
    return load_inputs([os.fspath(manifest)]).bodies


def test_every_collider_kind_has_exactly_one_builder() -> None:
    assert set(colliders._BUILDERS) == set(COLLIDER_KINDS)


def test_sphere_kind_is_the_minimum_sphere_of_a_cube(tmp_path) -> None:
    cube = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    cube.apply_translation((5.0, -1.0, 0.5))
    built = build_colliders(_scene(tmp_path, {"cube": cube}), "sphere")
    assert built.kinds == ("sphere",)
    assert int(built.shapes.kinds[0]) == ShapeKind.SPHERE
    # the minimum enclosing sphere of a cube of side 2: its half diagonal, at its centre
    assert built.shapes.params[0, 0] == pytest.approx(math.sqrt(3.0), rel=1e-6)
    centre = built.part_poses()[0][:3, 3]
    assert centre == pytest.approx([5.0, -1.0, 0.5], abs=1e-6)


def test_box_kind_encloses_every_vertex_of_each_part(tmp_path) -> None:
    rng = np.random.default_rng(7)
    rotation = trimesh.transformations.random_rotation_matrix(rng.random(3))
    slab = trimesh.creation.box(extents=(3.0, 1.0, 0.25), transform=rotation)
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    ball.apply_translation((4.0, 0.0, 0.0))
    bodies = _scene(tmp_path, {"slab": slab, "ball": ball})
    built = build_colliders(bodies, "box")
    assert built.kinds == ("box",)
    assert [int(k) for k in built.shapes.kinds] == [ShapeKind.BOX, ShapeKind.BOX]
    poses = built.part_poses()
    for part, mesh in enumerate((slab, ball)):
        half = built.shapes.params[part, :3]
        local = (np.asarray(mesh.vertices) - poses[part][:3, 3]) @ poses[part][:3, :3]
        assert np.all(np.abs(local) <= half + 1e-9)
    # the slab's box is the slab itself (a box fits a box), in any orientation
    assert sorted(2 * built.shapes.params[0, :3]) == pytest.approx([0.25, 1.0, 3.0], rel=1e-6)


def test_flat_part_stays_its_polygon_under_box(tmp_path) -> None:
    square = trimesh.Trimesh(
        vertices=[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], faces=[[0, 1, 2], [0, 2, 3]]
    )
    built = build_colliders(_scene(tmp_path, {"square": square}), "box")
    assert int(built.shapes.kinds[0]) == ShapeKind.POLYTOPE


@pytest.mark.parametrize(("shape", "code"), [("sphere", 1), ("box", 1), ("mesh", 0)])
def test_ball_in_bowl_by_collider_kind(shape: str, code: int) -> None:
    """The ball lies in the bowl's hollow: its exact mesh is apart, but the bowl's enclosing
    sphere or box reaches through it (a phantom collision, as with hulls)."""
    scene = os.path.join(SAMPLES, "bowl", "scene.json")
    result = CliRunner().invoke(main, ["check", scene, "--shape", shape, "--report", "-"])
    assert result.exit_code == code, result.output
    pair = json.loads(result.stdout)["pairs"][0]
    assert pair["status"] == ("separated" if shape == "mesh" else "penetrating")
