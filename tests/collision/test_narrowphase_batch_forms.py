"""The convex batches' one-call path (poses and pairs already in the core's form, and lists of
int pairs, read in place, the result dataclass built by the core) against their converting path:
the same results, field for field and bit for bit, whatever form the inputs come in."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from array_forms import pair_forms
from strategies import turned_about_z

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Sphere,
    distance_batch,
    intersects_batch,
    penetration_batch,
    signed_distance_batch,
)
from meshcol.collision.narrowphase import (
    DistanceBatch,
    IntersectsBatch,
    PenetrationBatch,
    SignedDistanceBatch,
)
from meshcol.types import Status

BATCHES = [
    (distance_batch, DistanceBatch),
    (penetration_batch, PenetrationBatch),
    (signed_distance_batch, SignedDistanceBatch),
    (intersects_batch, IntersectsBatch),
]
DTYPES = {
    "distance": np.float64,
    "depth": np.float64,
    "signed_distance": np.float64,
    "normal": np.float64,
    "point_a": np.float64,
    "point_b": np.float64,
    "iterations": np.int32,
    "status": np.int8,
    "intersects": np.bool_,
}


def scene() -> tuple[ConvexSet, np.ndarray, np.ndarray]:
    """A box, a sphere overlapping it, a capsule apart, a tetrahedron touching nothing, a
    sphere with a non-rigid pose (its pairs INVALID_INPUT), and pairs over them."""
    shapes = ConvexSet.from_shapes(
        [
            Box((1.0, 1.0, 1.0)),
            Sphere(0.5),
            Capsule(0.2, 1.0),
            np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
            Sphere(0.3),
        ]
    )
    p = np.stack(
        [
            np.eye(4),
            turned_about_z(0.3, (0.8, 0.1, 0.0)),
            turned_about_z(0.7, (3.0, 0.0, 0.5)),
            turned_about_z(1.1, (-4.0, 1.0, 0.5)),
            np.diag([2.0, 1.0, 1.0, 1.0]),
        ]
    )
    pairs = np.array([[0, 1], [0, 2], [1, 2], [3, 0], [2, 3], [0, 4], [1, 1]], dtype=np.int64)
    return shapes, p, pairs


def same(r, expected) -> None:
    for f in dataclasses.fields(expected):
        got, want = getattr(r, f.name), getattr(expected, f.name)
        assert got.dtype == DTYPES[f.name] and got.flags.c_contiguous and got.flags.writeable
        np.testing.assert_array_equal(got, want, err_msg=f.name, strict=True)


@pytest.mark.parametrize(
    ("batch", "result_type"), BATCHES, ids=lambda x: getattr(x, "__name__", "")
)
def test_a_batch_reads_every_input_form_alike(batch, result_type) -> None:
    shapes, p, pairs = scene()
    # the reference: one pair at a time, each converted from a list (the converting path)
    rows = [batch(shapes, p.tolist(), [list(map(int, q))]) for q in pairs]
    expected = result_type(
        **{
            f.name: np.concatenate([getattr(r, f.name) for r in rows])
            for f in dataclasses.fields(result_type)
        }
    )
    statuses = expected.status.tolist()
    assert statuses.count(Status.INVALID_INPUT) == 1
    if result_type is IntersectsBatch:
        assert expected.intersects.tolist() == [True, False, False, False, False, False, True]
    for poses in (None, p, p.tolist(), np.asfortranarray(p), p.astype(np.float32)):
        for form in pair_forms(pairs):
            r = batch(shapes, poses, form, threads=1)
            assert type(r) is result_type
            if poses is None:
                assert r.status.tolist()[5] != Status.INVALID_INPUT  # no pose: identity
            elif isinstance(poses, list) or poses.dtype == np.float64:
                same(r, expected)
            else:  # float32 poses: rounded, so only the statuses are compared
                assert r.status.tolist() == statuses
    if result_type is SignedDistanceBatch:
        np.testing.assert_array_equal(expected.signed_distance, expected.distance - expected.depth)
    # many pairs on two threads (the pairs are copied before the GIL is released)
    many = batch(shapes, p, np.tile(pairs, (40, 1)), threads=2)
    for f in dataclasses.fields(result_type):
        want = np.concatenate([getattr(expected, f.name)] * 40)
        np.testing.assert_array_equal(getattr(many, f.name), want, strict=True)
    assert len(batch(shapes, None, pairs[:0]).status) == 0
    assert len(batch(shapes, None, []).status) == 0
    a, b = batch(shapes, None, pairs[:1]), batch(shapes, None, pairs[:1])
    assert a.status is not b.status and not np.shares_memory(a.status, b.status)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.status = b.status  # type: ignore[misc]


@pytest.mark.parametrize(
    ("batch", "result_type"), BATCHES, ids=lambda x: getattr(x, "__name__", "")
)
def test_a_batch_refuses_bad_input_as_before(batch, result_type) -> None:
    shapes, p, pairs = scene()
    with pytest.raises(ValueError, match=r"^pairs: index 5 out of range for 5 shapes$"):
        batch(shapes, None, [(0, 5)])
    with pytest.raises(ValueError, match=r"^pairs: index -1 out of range for 5 shapes$"):
        batch(shapes, p, np.array([[0, -1]]))
    with pytest.raises(ValueError, match=r"^pairs must be \(P, 2\)"):
        batch(shapes, None, [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"^pairs must hold integer indices"):
        batch(shapes, None, [[0.0, 1.0]])
    with pytest.raises(ValueError, match=r"^poses must be \(5, 4, 4\), got \(2, 4, 4\)$"):
        batch(shapes, p[:2], pairs)
    with pytest.raises(TypeError, match=r"^shapes must be a ConvexSet"):
        batch(object(), None, pairs)


def symmetric_scene() -> tuple[ConvexSet, np.ndarray, np.ndarray]:
    """Spheres tessellated symmetrically (every plane a triangle, 42-258 vertices: the shapes
    whose supports climb) at poses on the axes and diagonals, turned by quarter turns: support
    directions meet exactly tied vertices, and the closest points of parallel edges and faces
    are not unique, so any start or state that a query keeps from an earlier one shows up."""
    import trimesh

    meshes = [
        trimesh.creation.icosphere(subdivisions=1),
        trimesh.creation.icosphere(subdivisions=2),
        trimesh.creation.uv_sphere(count=[12, 12]),
        trimesh.creation.capsule(height=1.0, radius=0.5, count=[10, 10]),
        trimesh.creation.uv_sphere(count=[8, 16]),
    ]
    rng = np.random.default_rng(0)
    steps = np.array([d for d in np.ndindex(3, 3, 3) if d != (1, 1, 1)], dtype=float) - 1.0
    shapes, poses = [], []
    for k in range(300):
        shapes.append(np.asarray(meshes[k % len(meshes)].vertices))
        c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][rng.integers(4)]
        pose = np.eye(4)
        pose[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        pose[:3, 3] = steps[rng.integers(len(steps))] * rng.choice([0.5, 1.0, 1.5, 2.0, 3.0])
        poses.append(pose)
    pairs = np.array(
        [(i, j) for i in range(0, 300, 3) for j in range(i + 1, min(i + 30, 300), 2)],
        dtype=np.int64,
    )
    return ConvexSet.from_vertices(shapes), np.stack(poses), pairs


@pytest.mark.parametrize(
    ("batch", "result_type"), BATCHES, ids=lambda x: getattr(x, "__name__", "")
)
def test_a_batch_answers_alike_on_every_call_and_thread_count(batch, result_type) -> None:
    # The answer of a pair is a function of its two shapes and poses only: not of the queries
    # the set answered before (a set keeps checked radii between calls), nor of the threads.
    shapes, poses, pairs = symmetric_scene()
    first = batch(shapes, poses, pairs, threads=1)
    assert isinstance(first, result_type)
    for threads in (1, 2, 1, 3):
        same(batch(shapes, poses, pairs, threads=threads), first)
    fresh, _, _ = symmetric_scene()
    reversed_first = batch(fresh, poses, pairs[::-1].copy(), threads=1)
    for f in dataclasses.fields(first):
        np.testing.assert_array_equal(
            getattr(reversed_first, f.name)[::-1], getattr(first, f.name), err_msg=f.name
        )
