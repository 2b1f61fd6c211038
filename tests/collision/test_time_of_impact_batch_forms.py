"""The time-of-impact batch's one-call path (poses, turns, pivots and pairs already in the core's
form read in place, the result dataclass built by the core) against its converting path: the
same results, field for field and bit for bit, whatever form the inputs come in."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from array_forms import pair_forms, unaligned_copy
from strategies import turned_about_z

from meshcol import Box, Capsule, ConvexSet, Sphere, time_of_impact_batch
from meshcol.collision.time_of_impact import TimeOfImpactBatch
from meshcol.types import TimeOfImpactStatus

DTYPES = {
    "time_of_impact": np.float64,
    "point": np.float64,
    "normal": np.float64,
    "iterations": np.int32,
    "status": np.int8,
}


def scene() -> tuple[ConvexSet, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Shapes that hit, miss, start overlapped and turn, one with a non-rigid end pose (its
    pairs INVALID_INPUT); the turns (one of more than half a turn) and the pivots."""
    shapes = ConvexSet.from_shapes(
        [
            Box((1.0, 1.0, 1.0)),
            Sphere(0.5),
            Capsule(0.2, 1.0),
            np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
            Sphere(0.3),
        ]
    )
    start = np.stack(
        [
            np.eye(4),
            turned_about_z(0.3, (3.0, 0.1, 0.0)),
            turned_about_z(0.7, (0.0, 3.0, 0.5)),
            turned_about_z(1.1, (-4.0, 1.0, 0.5)),
            turned_about_z(0.0, (0.2, 0.0, 0.0)),
        ]
    )
    end = np.stack(
        [
            turned_about_z(2.5, (0.0, 0.0, 0.0)),
            turned_about_z(0.3, (-1.0, 0.1, 0.0)),
            turned_about_z(0.2, (0.0, -2.0, 0.5)),
            turned_about_z(1.1, (-4.0, 9.0, 0.5)),
            np.diag([2.0, 1.0, 1.0, 1.0]),
        ]
    )
    rotations = np.array(
        [[0.0, 0.0, 2.5], [0.0, 0.0, 0.0], [0.0, 0.0, -0.5], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    )
    pivots = np.array(
        [[0.0, 0.0, 0.0], [3.0, 0.1, 0.0], [0.1, 3.0, 0.5], [-4.0, 1.0, 0.5], [0.2, 0.0, 0.0]]
    )
    pairs = np.array([[0, 1], [0, 2], [1, 2], [3, 0], [2, 3], [0, 4], [1, 1]], dtype=np.int64)
    return shapes, start, end, rotations, pivots, pairs


def same(r: TimeOfImpactBatch, expected: TimeOfImpactBatch) -> None:
    for f in dataclasses.fields(expected):
        got, want = getattr(r, f.name), getattr(expected, f.name)
        assert got.dtype == DTYPES[f.name] and got.flags.c_contiguous and got.flags.writeable
        np.testing.assert_array_equal(got, want, err_msg=f.name, strict=True)


def float_forms(a: np.ndarray) -> list:
    """``a`` (float64) as itself, read-only, a list, Fortran order, unaligned, a subclass."""
    read_only = a.copy()
    read_only.flags.writeable = False
    return [
        a,
        read_only,
        a.tolist(),
        np.asfortranarray(a),
        unaligned_copy(a),
        a.view(np.ma.MaskedArray),
        a.astype(a.dtype.newbyteorder()),
    ]


@pytest.mark.parametrize("turned", [False, True], ids=["shortest", "given turns"])
def test_the_batch_reads_every_input_form_alike(turned: bool) -> None:
    shapes, start, end, rotations, pivots, pairs = scene()
    turns = (rotations, pivots) if turned else (None, None)

    def run(s, e, p, r=None, c=None, threads=1):
        return time_of_impact_batch(shapes, s, e, p, rotations=r, pivots=c, threads=threads)

    # the reference: one pair at a time, every argument a list (the converting path)
    listed = [None if t is None else t.tolist() for t in turns]
    rows = [run(start.tolist(), end.tolist(), [list(map(int, q))], *listed) for q in pairs]
    expected = TimeOfImpactBatch(
        **{
            f.name: np.concatenate([getattr(r, f.name) for r in rows])
            for f in dataclasses.fields(TimeOfImpactBatch)
        }
    )
    statuses = expected.status.tolist()
    assert statuses.count(TimeOfImpactStatus.INVALID_INPUT) == 1
    assert TimeOfImpactStatus.HIT in statuses and TimeOfImpactStatus.SEPARATED in statuses
    for s in float_forms(start):
        r = run(s, end, pairs, *turns)
        assert type(r) is TimeOfImpactBatch
        same(r, expected)
    for form in pair_forms(pairs):
        same(run(start, end, form, *turns), expected)
    if turned:
        for r_form, c_form in zip(float_forms(rotations), float_forms(pivots)):
            same(run(start, end, pairs, r_form, c_form), expected)
    # many pairs on two threads (the arrays are pinned before the GIL is released)
    many = run(start, end, np.tile(pairs, (40, 1)), *turns, threads=2)
    for f in dataclasses.fields(TimeOfImpactBatch):
        want = np.concatenate([getattr(expected, f.name)] * 40)
        np.testing.assert_array_equal(getattr(many, f.name), want, strict=True)
    assert len(run(start, end, pairs[:0]).status) == 0
    assert len(run(start, end, []).status) == 0
    a, b = run(start, end, pairs[:1]), run(start, end, pairs[:1])
    assert not np.shares_memory(a.status, b.status)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.status = b.status  # type: ignore[misc]


def test_the_batch_refuses_bad_input_as_before() -> None:
    shapes, start, end, rotations, pivots, pairs = scene()
    with pytest.raises(ValueError, match=r"^pairs: index 5 out of range for 5 shapes$"):
        time_of_impact_batch(shapes, start, end, [(0, 5)])
    with pytest.raises(ValueError, match=r"^pairs: index -1 out of range for 5 shapes$"):
        time_of_impact_batch(shapes, start, end, np.array([[0, -1]]))
    with pytest.raises(ValueError, match=r"^pairs must be \(P, 2\)"):
        time_of_impact_batch(shapes, start, end, [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"^end_poses must be \(5, 4, 4\), got \(2, 4, 4\)$"):
        time_of_impact_batch(shapes, start, end[:2], pairs)
    with pytest.raises(ValueError, match=r"^start_poses and end_poses are required$"):
        time_of_impact_batch(shapes, start, None, pairs)
    with pytest.raises(ValueError, match=r"^rotations must be \(5, 3\), got \(4, 3\)$"):
        time_of_impact_batch(shapes, start, end, pairs, rotations=rotations[:4])
    with pytest.raises(ValueError, match=r"^pivots must be \(5, 3\), got \(5, 2\)$"):
        time_of_impact_batch(shapes, start, end, pairs, pivots=pivots[:, :2])
    with pytest.raises(ValueError, match=r"^tolerance must be finite and > 0, got nan$"):
        time_of_impact_batch(shapes, start, end, pairs, tolerance=float("nan"))
    with pytest.raises(TypeError, match=r"^shapes must be a ConvexSet"):
        time_of_impact_batch(object(), start, end, pairs)  # type: ignore[arg-type]
