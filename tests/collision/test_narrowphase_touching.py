"""Touching pairs: EPA's start when GJK ends on the boundary (a segment or a triangle through
the origin), against the exact SAT oracle, on the smooth hulls assets are made of and on
degenerate ones (flat, needle-thin, duplicated vertices, faces flush)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import box_corners, sat_depth, transform
from strategies import pose_matrix, rotation_from_quaternion

from meshcol import ConvexSet, distance_batch, signed_distance_batch
from meshcol.types import Status


def ellipsoid_hull(n: int, rng: np.random.Generator) -> np.ndarray:
    """n points on an ellipsoid: every one is a hull vertex (bench_narrowphase's family)."""
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return p * rng.uniform(0.7, 1.3, size=3)


def brought_to_contact(shapes: list[np.ndarray], rng: np.random.Generator):
    """Pairs (2k, 2k + 1) at random poses a little apart, then b moved along the pair's normal
    by the distance: touching up to rounding. The set, the touching poses and the pairs."""
    cs = ConvexSet.from_vertices(shapes)
    poses = np.stack(
        [
            pose_matrix(rotation_from_quaternion(rng.normal(size=4)), rng.uniform(-0.5, 0.5, 3))
            for _ in shapes
        ]
    )
    # Centres 4 apart: every shape here lies within 2 of its origin, so the pair is apart.
    away = rng.normal(size=(len(shapes) // 2, 3))
    poses[1::2, :3, 3] = poses[0::2, :3, 3] + away / np.linalg.norm(away, axis=1)[:, None] * 4.0
    pairs = np.arange(len(shapes), dtype=np.int64).reshape(-1, 2)
    apart = distance_batch(cs, poses, pairs, threads=1)
    moved = poses.copy()
    moved[1::2, :3, 3] -= apart.distance[:, None] * apart.normal
    return cs, moved, pairs, apart.normal


def check_against_sat(shapes, cs, poses, pairs, tolerance: float) -> None:
    got = signed_distance_batch(cs, poses, pairs, threads=1)
    assert np.all(got.status == Status.CONVERGED)
    for k, (ia, ib) in enumerate(pairs):
        wa, wb = transform(shapes[ia], poses[ia]), transform(shapes[ib], poses[ib])
        truth = max(sat_depth(wa, wb), 0.0)
        assert abs(got.depth[k] - truth) <= tolerance, (k, got.depth[k], truth)
        assert got.distance[k] <= tolerance
        # A unit vector along which the two do not overlap: b moved by depth * normal only
        # touches. It need not be the direction the pair came from: touching at a vertex or
        # an edge of a - b (most pairs of smooth hulls), every direction of its normal cone
        # is as good, and EPA gives one of its faces' normals (see the next tests).
        assert abs(np.linalg.norm(got.normal[k]) - 1.0) <= 1e-9
        n = got.normal[k]
        assert (wa @ n).max() - (wb @ n).min() <= tolerance, (k, n)


def test_smooth_hulls_touching_match_sat():
    rng = np.random.default_rng(32)
    shapes = [ellipsoid_hull(n, rng) for n in (16, 32, 64) for _ in range(6)]
    cs, poses, pairs, _ = brought_to_contact(shapes, rng)
    check_against_sat(shapes, cs, poses, pairs, 1e-12)


def test_flush_faces_have_depth_zero_and_the_face_normal():
    # Unit cubes face to face, exactly flush, then turned about the shared normal: GJK ends
    # on a face of a - b through the origin (no tetrahedron), EPA blows it up.
    cube = box_corners((1, 1, 1))
    shapes = [cube, cube, cube, cube]
    c, s = np.cos(0.3), np.sin(0.3)
    turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    poses = np.stack(
        [
            pose_matrix(np.eye(3), (0, 0, 0)),
            pose_matrix(np.eye(3), (0, 0, 1)),
            pose_matrix(np.eye(3), (0, 0, 0)),
            pose_matrix(turn, (0.2, 0.1, 1)),
        ]
    )
    cs = ConvexSet.from_vertices(shapes)
    pairs = np.array([[0, 1], [2, 3]], dtype=np.int64)
    got = signed_distance_batch(cs, poses, pairs, threads=1)
    np.testing.assert_array_equal(got.depth, [0.0, 0.0])
    np.testing.assert_array_equal(got.distance, [0.0, 0.0])
    np.testing.assert_allclose(got.normal, [[0, 0, 1], [0, 0, 1]], atol=1e-12)


def test_touching_at_a_face_has_that_face_normal():
    # Touching at a face of a - b, the normal is unique: a tetrahedron's vertex on a cube's
    # top face (vertex-face) and two turned boxes edge on edge (edge-edge, the normal along
    # the cross product of the edges), each a little apart, then moved along the normal by
    # the distance as the smooth-hull family is.
    tetra = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.5], [-0.5, 0.9, 0.5], [-0.5, -0.9, 0.5]])
    cube = box_corners((1, 1, 1))  # edges 1 long
    # Bars 2 long with a square section of side 0.2 turned by 45 degrees about their length,
    # so that an edge runs along the top and the bottom (0.1 * sqrt(2) off the axis).
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    on_edge = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    bar = box_corners((2, 0.2, 0.2)) @ on_edge.T
    c, s = np.cos(0.7), np.sin(0.7)
    turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    shapes = [cube, tetra, bar, bar]
    poses = np.stack(
        [
            pose_matrix(np.eye(3), (0, 0, 0)),
            pose_matrix(np.eye(3), (0.1, -0.2, 0.5 + 1.0 + 0.25)),
            pose_matrix(np.eye(3), (0, 0, 0)),
            pose_matrix(turn, (0.05, 0.03, 0.2 * np.sqrt(2) + 0.3)),
        ]
    )
    cs = ConvexSet.from_vertices(shapes)
    pairs = np.array([[0, 1], [2, 3]], dtype=np.int64)
    apart = distance_batch(cs, poses, pairs, threads=1)
    np.testing.assert_allclose(apart.distance, [0.25, 0.3], atol=1e-12)
    moved = poses.copy()
    moved[1::2, :3, 3] -= apart.distance[:, None] * apart.normal
    got = signed_distance_batch(cs, moved, pairs, threads=1)
    assert np.all(got.status == Status.CONVERGED)
    assert np.all(np.abs(got.depth) <= 1e-15) and np.all(got.distance == 0.0)
    np.testing.assert_allclose(got.normal, [[0, 0, 1], [0, 0, 1]], atol=1e-12)


def degenerate_hull(kind: str, rng: np.random.Generator) -> np.ndarray:
    p = ellipsoid_hull(int(rng.integers(8, 40)), rng)
    if kind == "flat":  # a polygon: zero thickness along z
        p[:, 2] = 0.0
    elif kind == "needle":  # a long thin spindle
        p *= np.array([1e-3, 1e-3, 2.0])
    elif kind == "duplicated":  # every point twice, a few three times
        p = np.concatenate([p, p, p[:3]])
    return p


@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from(["flat", "needle", "duplicated", "smooth"]),
    st.sampled_from(["flat", "needle", "duplicated", "smooth"]),
)
def test_degenerate_hulls_touching_match_sat(seed, kind_a, kind_b):
    rng = np.random.default_rng(seed)
    shapes = [degenerate_hull(kind_a, rng), degenerate_hull(kind_b, rng)]
    cs, poses, pairs, _ = brought_to_contact(shapes, rng)
    got = signed_distance_batch(cs, poses, pairs, threads=1)
    assert got.status[0] == Status.CONVERGED
    # Touching up to the rounding of the move: depth and distance both about 0.
    assert 0.0 <= got.depth[0] <= 1e-12
    assert 0.0 <= got.distance[0] <= 1e-12
    if kind_a != "flat" and kind_b != "flat":  # the oracle needs 3D hulls
        wa, wb = transform(shapes[0], poses[0]), transform(shapes[1], poses[1])
        assert abs(got.depth[0] - max(sat_depth(wa, wb), 0.0)) <= 1e-12
