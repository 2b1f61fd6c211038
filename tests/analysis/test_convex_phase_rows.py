"""The convex phase's shortcut when every row has one part pair, in row order (every body one
part: a manifest of primitives, of hulls): the columns it gives are the general path's, to
the bit (the general path taken by the same table with its rows reordered)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
from test_primitive_columns import document

from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.pairs import PairTable, body_boxes, broad_phase, convex_phase, place
from meshcol.analysis.primitive_colliders import primitive_colliders
from meshcol.io.scene import load_scene


def test_rows_of_one_part_pair_are_the_general_paths(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document(48)))
    scene = load_scene(path)
    for colliders in (primitive_colliders(scene.bodies), build_colliders(list(scene.bodies))):
        placed = place(colliders, threads=1)
        table = broad_phase(placed, margin=0.2)
        assert len(table) > 40 and np.array_equal(table.part_row, np.arange(len(table)))
        fast = convex_phase(table, placed, threads=1)
        order = np.arange(len(table))[::-1].copy()  # part_row out of order: the general path
        general = convex_phase(table.take(order), placed, threads=1)
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        general = general.take(back)
        for field in dataclasses.fields(PairTable):
            x, y = getattr(fast, field.name), getattr(general, field.name)
            if isinstance(x, np.ndarray):
                assert (x.dtype, x.shape) == (y.dtype, y.shape), field.name
                assert x.tobytes() == y.tobytes(), field.name
        assert (fast.signed_distance < 0).any() and (fast.signed_distance > 0).any()


def test_body_boxes_of_one_part_bodies_are_the_parts_boxes():
    rng = np.random.default_rng(1)
    low = rng.normal(size=(7, 3))
    high = low + 1
    body_min, body_max = body_boxes(low, high, np.arange(8))
    assert np.array_equal(body_min, np.minimum.reduceat(low, np.arange(7), axis=-2))
    assert np.array_equal(body_max, np.maximum.reduceat(high, np.arange(7), axis=-2))
    two = body_boxes(low, high, np.array([0, 2, 7]))  # several parts a body: their union
    assert np.array_equal(two[0], np.stack([low[:2].min(0), low[2:].min(0)]))
