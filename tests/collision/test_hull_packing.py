"""The faster hull path of issue 32 (item 2) against the path it replaced.

Oracles: the packed arrays the old path (main 50405b3) produced for a fixed set of inputs,
kept in tests/data/hull_pack_50405b3.json and compared exactly (every vertex, adjacency
list, face normal and edge direction bit for bit: smooth hulls, clouds and degenerate sets);
and qhull through scipy on smooth hulls, whose triangulation is unique (no four points
coplanar): the same triangles and the same vertex adjacency.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from meshcol.collision.hull import HullStatus, exact_hull, pack_hulls

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
    return {name: np.asarray(getattr(packed, name)).tolist() for name in FIELDS}


FIELDS = (
    "status",
    "vertices",
    "offsets",
    "adjacency_offsets",
    "adjacency",
    "face_offsets",
    "face_normals",
    "edge_offsets",
    "edge_directions",
)


def test_packing_equals_the_old_paths_arrays_bit_for_bit() -> None:
    want = json.loads(GOLDEN_PACK.read_text())
    got = packed_as_lists(golden_inputs())
    assert got["status"][-2] == int(HullStatus.OVERFLOW)
    for name in FIELDS:
        assert got[name] == want[name], name


def test_packing_on_two_threads_equals_one() -> None:
    rng = np.random.default_rng(3)
    sets = [ellipsoid_points(rng, 64) for _ in range(40)] + golden_inputs()
    one, two = pack_hulls(sets, threads=1), pack_hulls(sets, threads=2)
    for name in FIELDS:
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
