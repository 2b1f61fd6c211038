"""The faster hull path of issue 32 (item 2) against the path it replaced.

Oracles: the packed arrays the old path (main 50405b3) produced for a fixed set of inputs,
kept in tests/data/hull_pack_50405b3.json and compared exactly (every vertex, adjacency
list, face normal and edge direction bit for bit: smooth hulls, clouds and degenerate sets;
the edge directions, no longer packed, as a ConvexSet computes them from the packed edges);
and qhull through scipy on smooth hulls, whose triangulation is unique (no four points
coplanar): the same triangles and the same vertex adjacency.

The edge classes a ConvexSet computes on first read from its vertices and true edges
(``edge_pairs``) against those the packing stored before (main 6b141aa): the golden packing
byte for byte (signs of zero included); for concatenated and taken sets, the rows of their
sources' classes that the old ``concatenate`` and ``take`` copied; for triangle parts, the
unit sides the old ``triangle_parts`` wrote (the core gives each class its canonical sign, so
equal up to sign); and SAT's answers, the same whether a query or a read computed them first.
"""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from meshcol.analysis.triangle_parts import triangle_parts
from meshcol.collision.hull import HullStatus, exact_hull, pack_hulls
from meshcol.collision.narrowphase import penetration_batch
from meshcol.collision.shapes import Box, ConvexSet, Sphere
from meshcol.types import Body

GOLDEN_PACK = Path(__file__).resolve().parents[1] / "data" / "hull_pack_50405b3.json"


def ellipsoid_points(rng: np.random.Generator, n: int) -> np.ndarray:
    """n points on a randomly turned ellipsoid (semi-axes 0.5-1.5): every one a vertex."""
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    p *= rng.uniform(0.5, 1.5, size=3)
    return p @ Rotation.random(random_state=rng).as_matrix().T


def golden_inputs() -> list[np.ndarray]:
    """The point sets of the golden file (the old path packed them)."""
    rng = np.random.default_rng(32)
    sets = [ellipsoid_points(rng, n) for n in (4, 16, 24, 40)]
    sets += [rng.normal(size=(n, 3)) for n in (5, 20, 32)]
    sphere = ellipsoid_points(rng, 24)
    sets.append(sphere + 1e-12 * rng.normal(size=sphere.shape))  # cospherical, 1e-12 noise
    sets.append(np.floor(2.0 * rng.normal(size=(40, 3))))  # lattice: coplanar faces
    dup = rng.normal(size=(18, 3))
    dup[1::3] = dup[0:-1:3]
    sets.append(dup)  # duplicates
    flat = rng.normal(size=(12, 3))
    flat[:, 2] = 0.25 * flat[:, 0] - 0.5 * flat[:, 1]
    sets.append(flat)  # coplanar: a polygon
    sets.append(np.outer(rng.normal(size=6), [1.0, -2.0, 0.5]))  # collinear: a segment
    sets.append(np.ones((3, 3)))  # one point
    sets.append(sphere * 1e90)  # huge (within range)
    sets.append(sphere * 1e-150)  # tiny
    sets.append(sphere * 1e200)  # beyond range: kept as given
    box = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    sets.append(np.concatenate([box, 0.5 * rng.uniform(-1, 1, size=(10, 3))]))
    return sets


def packed_as_lists(point_sets: list[np.ndarray]) -> dict[str, list]:
    packed = pack_hulls(point_sets, threads=1)
    got = {name: np.asarray(getattr(packed, name)).tolist() for name in PACKED_FIELDS}
    computed = ConvexSet.from_vertices(point_sets)  # every shape a polytope: the same offsets
    for name in COMPUTED_FIELDS:
        got[name] = getattr(computed, name).tolist()
    return got


PACKED_FIELDS = (
    "status",
    "vertices",
    "offsets",
    "adjacency_offsets",
    "adjacency",
    "face_offsets",
    "face_normals",
)
COMPUTED_FIELDS = ("edge_offsets", "edge_directions")


def test_packing_equals_the_old_paths_arrays_bit_for_bit() -> None:
    want = json.loads(GOLDEN_PACK.read_text())
    got = packed_as_lists(golden_inputs())
    assert got["status"][-2] == int(HullStatus.OVERFLOW)
    for name in PACKED_FIELDS + COMPUTED_FIELDS:
        assert got[name] == want[name], name


def test_packing_on_two_threads_equals_one() -> None:
    rng = np.random.default_rng(3)
    sets = [ellipsoid_points(rng, 64) for _ in range(40)] + golden_inputs()
    one, two = pack_hulls(sets, threads=1), pack_hulls(sets, threads=2)
    for name in (*PACKED_FIELDS, "edge_pair_offsets", "edge_pairs"):
        assert np.array_equal(getattr(one, name), getattr(two, name), equal_nan=True), name


@settings(max_examples=30, deadline=None)
@given(st.integers(5, 200), st.integers(0, 2**32 - 1))
def test_smooth_hulls_equal_qhull_triangle_for_triangle(n: int, seed: int) -> None:
    points = ellipsoid_points(np.random.default_rng(seed), n)
    hull = exact_hull(points)
    reference = ConvexHull(points)
    assert sorted(hull.indices) == sorted(reference.vertices) == list(range(n))
    ours = {frozenset(hull.indices[f]) for f in hull.faces}
    assert ours == {frozenset(s) for s in reference.simplices}
    # the packed adjacency: each vertex's neighbours in that triangulation, padded with itself
    packed = pack_hulls([points], threads=1)
    rows = {tuple(v): i for i, v in enumerate(points)}
    local = np.array([rows[tuple(v)] for v in packed.vertices])
    counts = np.diff(packed.adjacency_offsets)
    assert (counts % 4 == 0).all()
    owner = np.repeat(np.arange(len(local)), counts)
    real = packed.adjacency != owner
    ours_edges = {
        (int(a), int(b)) for a, b in zip(local[owner[real]], local[packed.adjacency[real]])
    }
    tri = reference.simplices
    pairs = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    assert ours_edges == {(int(a), int(b)) for a, b in np.concatenate([pairs, pairs[:, ::-1]])}
    assert len(packed.face_normals) == len(reference.simplices)


def test_computed_classes_equal_the_old_packings_bytes() -> None:
    want = json.loads(GOLDEN_PACK.read_text())
    cs = ConvexSet.from_vertices(golden_inputs())
    assert cs.edge_offsets.tobytes() == np.array(want["edge_offsets"], np.int64).tobytes()
    old = np.array(want["edge_directions"], np.float64).reshape(-1, 3)
    assert cs.edge_directions.tobytes() == old.tobytes()
    assert np.any((old == 0.0) & np.signbit(old))  # -0.0 in the golden: compared as such
    assert not cs.edge_directions.flags.writeable and not cs.edge_offsets.flags.writeable
    assert cs.edge_directions is cs.edge_directions  # computed once


def _rows(offsets: np.ndarray, indices: np.ndarray) -> np.ndarray:
    return np.concatenate(
        [np.arange(offsets[h], offsets[h + 1]) for h in indices] + [np.zeros(0, np.int64)]
    )


def _mesh_body(rng: np.random.Generator) -> Body:
    vertices = rng.normal(size=(30, 3))
    faces = rng.integers(0, 30, size=(40, 3))
    faces[0] = [0, 1, 1]  # a segment
    faces[1] = [2, 3, 4]
    vertices[4] = 0.5 * (vertices[2] + vertices[3])  # collinear: flat
    return Body(name="mesh", source=None, vertices=vertices, faces=faces)


def test_concatenated_and_taken_sets_compute_their_sources_classes() -> None:
    rng = np.random.default_rng(12)
    hulls = ConvexSet.from_vertices(golden_inputs())
    mixed = ConvexSet.from_shapes([Box((1, 2, 3)), rng.normal(size=(40, 3)), Sphere(1.0)])
    parts = triangle_parts(_mesh_body(rng))
    sets = (hulls, mixed, parts)
    # each source read only after the combined set's classes (no reuse of a cache)
    both = ConvexSet.concatenate(*sets)
    old = np.concatenate([s.edge_directions for s in sets])
    assert both.edge_directions.tobytes() == old.tobytes()
    assert np.array_equal(
        np.diff(both.edge_offsets), np.concatenate([np.diff(s.edge_offsets) for s in sets])
    )
    idx = np.array([5, 0, 5, len(both) - 1, len(hulls) + 1, len(hulls), 12, len(hulls) + 4])
    taken = both.take(idx)
    assert (
        taken.edge_directions.tobytes()
        == both.edge_directions[_rows(both.edge_offsets, idx)].tobytes()
    )
    assert np.array_equal(np.diff(taken.edge_offsets), np.diff(both.edge_offsets)[idx])


def test_triangle_parts_classes_are_their_unit_sides_up_to_sign() -> None:
    body = _mesh_body(np.random.default_rng(4))
    parts = triangle_parts(body)
    solid = np.flatnonzero(np.diff(parts.offsets) == 3)
    tri = parts.vertices[_rows(parts.offsets, solid)].reshape(-1, 3, 3)
    sides = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    old = (sides / np.linalg.norm(sides, axis=2, keepdims=True)).reshape(-1, 3)  # as written before
    assert np.array_equal(np.diff(parts.edge_offsets)[solid], np.full(len(solid), 3))
    got = parts.edge_directions[_rows(parts.edge_offsets, solid)]
    flipped = np.all(got == -old, axis=1)
    assert np.all(np.all(got == old, axis=1) | flipped)
    assert 0 < flipped.sum() < len(old)  # both signs occur: the test tells them apart
    # the canonical sign: the first component beyond 1e-12 is positive
    lead = np.where(
        np.abs(got[:, 0]) > 1e-12,
        got[:, 0],
        np.where(np.abs(got[:, 1]) > 1e-12, got[:, 1], got[:, 2]),
    )
    assert np.all(lead > 0)


@pytest.mark.parametrize("read_first", [False, True])
def test_sat_reads_the_same_classes_whoever_computes_them(read_first: bool) -> None:
    # Small polytopes (SAT runs) and a box, penetrating: a set whose classes were read before
    # the query (one native call over all shapes) and one whose query computed them answer
    # alike, bit for bit.
    rng = np.random.default_rng(21)
    shapes = [rng.normal(size=(n, 3)) for n in (6, 8, 10, 12) * 6] + [Box((1.0, 0.5, 0.8))]
    pairs = np.array([(i, j) for i in range(len(shapes)) for j in range(len(shapes)) if i != j])
    poses = np.tile(np.eye(4), (len(shapes), 1, 1))
    poses[:, :3, 3] = rng.uniform(-0.3, 0.3, size=(len(shapes), 3))
    first, second = ConvexSet.from_shapes(shapes), ConvexSet.from_shapes(shapes)
    if read_first:
        assert len(first.edge_directions) > 0
    a = penetration_batch(first, poses, pairs, threads=2)
    b = penetration_batch(second, poses, pairs, threads=1)
    for name in ("depth", "normal", "point_a", "point_b", "status", "iterations"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
    assert first.edge_directions.tobytes() == second.edge_directions.tobytes()


def test_a_set_takes_the_edges_not_their_classes() -> None:
    made = ConvexSet.from_vertices([np.random.default_rng(1).normal(size=(9, 3))])
    arrays = {name: getattr(made, name) for name in ConvexSet._FIELDS}
    assert ConvexSet(**arrays).edge_directions.tobytes() == made.edge_directions.tobytes()
    with pytest.raises(TypeError, match="edge_directions"):
        ConvexSet(**arrays, edge_directions=made.edge_directions)
    bad = dict(arrays, edge_pairs=np.array(arrays["edge_pairs"]) + 9)
    with pytest.raises(ValueError, match="edge_pairs holds an index out of range"):
        ConvexSet(**bad)


@pytest.mark.parametrize("at", [0, 4095, 4096, 9999])
def test_a_large_set_checks_every_shape_s_indices(at: int) -> None:
    # 10,000 shapes: the checks of the adjacency and the edges run on threads (blocks of
    # shapes); one wrong index in any shape's block is found.
    made = ConvexSet.from_vertices(np.random.default_rng(3).normal(size=(10_000, 8, 3)))
    arrays = {name: np.array(getattr(made, name)) for name in ConvexSet._FIELDS}
    assert len(ConvexSet(**arrays)) == 10_000
    n = made.offsets[at + 1] - made.offsets[at]
    adjacency = arrays["adjacency"].copy()
    adjacency[made.adjacency_offsets[made.offsets[at + 1]] - 1] = n
    with pytest.raises(ValueError, match="adjacency holds an index out of range"):
        ConvexSet(**dict(arrays, adjacency=adjacency))
    edges = arrays["edge_pairs"].copy()
    edges[made.edge_pair_offsets[at], 1] = -1
    with pytest.raises(ValueError, match="edge_pairs holds an index out of range"):
        ConvexSet(**dict(arrays, edge_pairs=edges))


def test_a_set_made_from_points_is_vouched_for_by_its_packing() -> None:
    # ConvexSet.from_vertices / from_shapes hand the packing's own index arrays, in its
    # layout (primitives between the polytopes own none), with the packing's seal: the set
    # does not read their indices again. The same arrays copied are checked, and the two
    # sets answer alike.
    rng = np.random.default_rng(5)
    shapes: list[object] = [Sphere(0.5), rng.normal(size=(12, 3)), Box((1.0, 2.0, 0.5))]
    shapes += [ellipsoid_points(rng, 20), rng.normal(size=(7, 3))]
    for made in (
        ConvexSet.from_vertices(rng.normal(size=(30, 16, 3))),
        ConvexSet.from_shapes(shapes),
    ):
        assert made._core.sealed
        copied = ConvexSet(
            **{name: getattr(made, name) for name in ConvexSet._FIELDS},
            hull_status=made.hull_status,
        )
        assert not copied._core.sealed
        count = len(made)
        poses = np.tile(np.eye(4), (count, 1, 1))
        poses[:, :3, 3] = rng.uniform(-1.0, 1.0, size=(count, 3))
        pairs = np.array([(i, j) for i in range(count) for j in range(i + 1, count)])
        ours, theirs = (
            penetration_batch(made, poses, pairs),
            penetration_batch(copied, poses, pairs),
        )
        assert ours.depth.tobytes() == theirs.depth.tobytes()
        assert ours.normal.tobytes() == theirs.normal.tobytes()
    packed = pack_hulls(rng.normal(size=(3, 10, 3)))
    for index in (packed.adjacency_offsets, packed.adjacency, packed.edge_pairs):
        assert not index.flags.writeable
    # The seal stays in its process: a pickled packing loads without it, and is checked.
    loaded = pickle.loads(pickle.dumps(packed))
    assert not hasattr(loaded, "_seal")
    assert loaded.adjacency.tobytes() == packed.adjacency.tobytes()
    kinds, params, rows = np.zeros(3, np.int8), np.zeros((3, 4)), np.arange(3)
    assert ConvexSet._assemble(kinds, params, rows, packed)._core.sealed
    assert not ConvexSet._assemble(kinds, params, rows, loaded)._core.sealed


def test_a_seal_vouches_only_for_its_own_arrays_in_its_own_layout() -> None:
    # Anything else is checked as before: another array (a copy with a wrong index), offsets
    # that move a shape's boundary (its indices then reach past its vertices), a polytope
    # called a primitive, another packing's seal.
    from meshcol._native import core

    rng = np.random.default_rng(6)
    points = rng.normal(size=(4, 10, 3))
    packed = pack_hulls(points)
    seal = packed._seal  # type: ignore[attr-defined]

    def made(**changed: np.ndarray) -> object:
        arrays = dict(
            vertices=packed.vertices,
            offsets=packed.offsets,
            kinds=np.zeros(4, np.int8),
            params=np.zeros((4, 4)),
            adjacency_offsets=packed.adjacency_offsets,
            adjacency=packed.adjacency,
            face_offsets=packed.face_offsets,
            face_normals=packed.face_normals,
            edge_pair_offsets=packed.edge_pair_offsets,
            edge_pairs=packed.edge_pairs,
        )
        arrays.update(changed)
        return core.PackedConvexSet(**arrays, seal=seal)

    assert made().sealed  # type: ignore[attr-defined]
    adjacency = packed.adjacency.copy()
    adjacency[0] = 10
    with pytest.raises(ValueError, match="adjacency holds an index out of range"):
        made(adjacency=adjacency)
    offsets = packed.offsets.copy()
    offsets[1] -= 1
    with pytest.raises(ValueError, match="adjacency holds an index out of range"):
        made(offsets=offsets)
    kinds = np.zeros(4, np.int8)
    kinds[2] = 1
    assert not made(kinds=kinds).sealed  # type: ignore[attr-defined]
    other = pack_hulls(points)
    assert not core.PackedConvexSet(
        packed.vertices,
        packed.offsets,
        np.zeros(4, np.int8),
        np.zeros((4, 4)),
        packed.adjacency_offsets,
        packed.adjacency,
        packed.face_offsets,
        packed.face_normals,
        packed.edge_pair_offsets,
        packed.edge_pairs,
        other._seal,  # type: ignore[attr-defined]
    ).sealed


def test_a_seal_does_not_vouch_for_a_set_of_fewer_shapes_than_it_packed() -> None:
    # A packing whose last shape is empty (no points) ends its offsets where the shape before
    # it ends, so a set of only the first three polytopes matches every offset it has: the
    # seal still refuses it (it vouches for exactly the packed shapes), and the set is checked.
    from meshcol._native import core

    rng = np.random.default_rng(8)
    packed = pack_hulls([rng.normal(size=(10, 3)) for _ in range(3)] + [np.zeros((0, 3))])
    assert packed.offsets[3] == packed.offsets[4]
    assert packed.edge_pair_offsets[3] == packed.edge_pair_offsets[4]

    def made(count: int) -> object:
        return core.PackedConvexSet(
            packed.vertices,
            packed.offsets[: count + 1],
            np.zeros(count, np.int8),
            np.zeros((count, 4)),
            packed.adjacency_offsets,
            packed.adjacency,
            packed.face_offsets[: count + 1],
            packed.face_normals,
            packed.edge_pair_offsets[: count + 1],
            packed.edge_pairs,
            packed._seal,  # type: ignore[attr-defined]
        )

    assert made(4).sealed  # type: ignore[attr-defined]
    assert not made(3).sealed  # type: ignore[attr-defined]
