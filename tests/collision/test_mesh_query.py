"""Exact triangle-mesh queries: known answers, exact oracles, properties, python-fcl, bad input."""

from __future__ import annotations

import dataclasses
import math
import types
from fractions import Fraction

import numpy as np
import pytest
import trimesh
from array_forms import pair_forms
from hypothesis import given
from hypothesis import strategies as st

import meshcol
from meshcol._native import core as _core
from meshcol.collision.mesh_query import (
    MeshIntersectsBatch,
    MeshSet,
    mesh_distance,
    mesh_distance_batch,
    mesh_intersects_batch,
)
from meshcol.types import Body, Status

# --------------------------------------------------------------------------- helpers


def box(lower, upper) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=[lower, upper])


def pose(rotation=None, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def rotation_about(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return {
        "x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def rotation_from_quaternion(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def bowl(
    outer: float = 1.0, inner: float = 0.9, n: int = 24, sections: int = 48
) -> trimesh.Trimesh:
    """A closed hemispherical shell, opening upwards, rim at z = 0 (revolved profile)."""
    th = np.linspace(0.0, np.pi / 2, n)
    outer_arc = np.c_[outer * np.sin(th), -outer * np.cos(th)]
    inner_arc = np.c_[inner * np.sin(th[::-1]), -inner * np.cos(th[::-1])]
    return trimesh.creation.revolve(np.vstack([outer_arc, inner_arc]), sections=sections)


# Exact-in-numpy oracle for triangle pairs (independent of the C++ code): closest points of two
# segments by checking the interior stationary point and the four boundary edges of [0, 1]^2.


def _point_segment(p, a, b):
    d = b - a
    dd = np.einsum("...i,...i", d, d)
    t = np.where(dd > 0, np.einsum("...i,...i", p - a, d) / np.where(dd > 0, dd, 1), 0.0)
    t = np.clip(t, 0, 1)
    return np.linalg.norm(p - (a + t[..., None] * d), axis=-1)


def _segment_segment(p1, q1, p2, q2):
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    best = np.minimum.reduce(
        [
            _point_segment(p1, p2, q2),
            _point_segment(q1, p2, q2),
            _point_segment(p2, p1, q1),
            _point_segment(q2, p1, q1),
        ]
    )
    a, b, c = d1 @ d1, d1 @ d2, d2 @ d2
    e, f = d1 @ r, d2 @ r
    det = a * c - b * b
    if det > 1e-12 * a * c:
        s = (b * f - c * e) / det
        t = (a * f - b * e) / det
        if 0 <= s <= 1 and 0 <= t <= 1:
            best = min(best, np.linalg.norm(p1 + s * d1 - p2 - t * d2))
    return float(best)


def _point_triangle(p, t):
    e1, e2 = t[1] - t[0], t[2] - t[0]
    n = np.cross(e1, e2)
    if n @ n > 0:
        m = np.column_stack([e1, e2, n])
        u, v, w = np.linalg.solve(m, p - t[0])
        if u >= 0 and v >= 0 and u + v <= 1:
            return float(abs(w) * np.linalg.norm(n))
    return float(min(_point_segment(p, t[i], t[(i + 1) % 3]) for i in range(3)))


def oracle_separated_distance(a, b) -> float:
    """Exact distance of two non-intersecting triangles: 6 vertex-face and 9 edge-edge pairs."""
    d = min(_point_triangle(p, b) for p in a)
    d = min(d, min(_point_triangle(p, a) for p in b))
    for i in range(3):
        for j in range(3):
            d = min(d, _segment_segment(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]))
    return d


def _edge_crossings(a, b, exact: bool):
    """Margins of each edge of a crossing triangle b, solving p + t d = b0 + u e1 + v e2."""
    out = []
    for i in range(3):
        p, q = a[i], a[(i + 1) % 3]
        cols = [
            [q[k] - p[k] for k in range(3)],
            [b[0][k] - b[1][k] for k in range(3)],
            [b[0][k] - b[2][k] for k in range(3)],
        ]
        rhs = [b[0][k] - p[k] for k in range(3)]
        if exact:
            det = _det3(cols)
            if det == 0:
                out.append(None)
                continue
            sol = [
                Fraction(_det3([rhs if c == j else cols[c] for c in range(3)]), det)
                for j in range(3)
            ]
        else:
            m = np.array(cols, dtype=float).T
            if abs(np.linalg.det(m)) < 1e-9:
                out.append(None)
                continue
            sol = np.linalg.solve(m, np.array(rhs, dtype=float))
        t, u, v = sol
        out.append(min(t, 1 - t, u, v, 1 - u - v))
    return out


def _det3(c):
    (a, b, cc), (d, e, f), (g, h, i) = c[0], c[1], c[2]
    # columns given: determinant of [c0 c1 c2] as columns
    return a * (e * i - f * h) - d * (b * i - cc * h) + g * (b * f - cc * e)


# --------------------------------------------------------------------------- known answers


def test_unit_cubes_one_apart_along_x() -> None:
    r = mesh_distance(box([0, 0, 0], [1, 1, 1]), box([2, 0, 0], [3, 1, 1]))
    assert r.status == Status.CONVERGED
    assert r.distance == pytest.approx(1.0, abs=1e-12)
    assert r.point_a[0] == pytest.approx(1.0, abs=1e-12)
    assert r.point_b[0] == pytest.approx(2.0, abs=1e-12)
    assert np.linalg.norm(r.point_b - r.point_a) == pytest.approx(1.0, abs=1e-12)
    assert not (r.intersecting or r.a_inside_b or r.b_inside_a)
    a, b = box([0, 0, 0], [1, 1, 1]), box([2, 0, 0], [3, 1, 1])
    # the reported triangles hold the reported points
    assert _point_triangle(r.point_a, a.vertices[a.faces[r.triangle_a]]) == pytest.approx(
        0, abs=1e-12
    )
    assert _point_triangle(r.point_b, b.vertices[b.faces[r.triangle_b]]) == pytest.approx(
        0, abs=1e-12
    )


def test_parallel_faces_partially_overlapping_and_posed() -> None:
    a, b = box([0, 0, 0], [1, 1, 1]), box([0, 0, 0], [1, 1, 1])
    r = mesh_distance(a, b, pose(), pose(translation=(2.0, 0.5, 0.25)))
    assert r.distance == pytest.approx(1.0, abs=1e-12)
    assert r.point_a[0] == pytest.approx(1.0, abs=1e-12)


def test_edge_edge_crossing() -> None:
    # a: cube rotated 45 degrees about y (top edge along y at z = sqrt(2)/2); b: cube rotated 45
    # degrees about x (bottom edge along x), centred above at height sqrt(2) + gap.
    gap = 0.3
    a = b = box([-0.5] * 3, [0.5] * 3)
    h = math.sqrt(2) / 2
    r = mesh_distance(
        a,
        b,
        pose(rotation_about("y", math.pi / 4)),
        pose(rotation_about("x", math.pi / 4), (0, 0, 2 * h + gap)),
    )
    assert r.distance == pytest.approx(gap, abs=1e-12)
    assert r.point_a == pytest.approx([0, 0, h], abs=1e-12)
    assert r.point_b == pytest.approx([0, 0, h + gap], abs=1e-12)


def test_vertex_face() -> None:
    # b's body diagonal along z: its lowest vertex is sqrt(3)/2 below its centre.
    gap = 0.125
    diagonal = np.array([1.0, 1.0, 1.0]) / math.sqrt(3)
    axis = np.cross(diagonal, [0, 0, -1.0])
    angle = math.acos(diagonal @ [0, 0, -1.0])
    rot = trimesh.transformations.rotation_matrix(angle, axis)[:3, :3]
    cube = box([-0.5] * 3, [0.5] * 3)
    slab = box([-2, -2, -1], [2, 2, 0])
    r = mesh_distance(slab, cube, None, pose(rot, (0.1, -0.2, math.sqrt(3) / 2 + gap)))
    assert r.distance == pytest.approx(gap, abs=1e-12)
    assert r.point_a == pytest.approx([0.1, -0.2, 0.0], abs=1e-12)
    assert r.point_b == pytest.approx([0.1, -0.2, gap], abs=1e-12)


def test_touching_faces_is_distance_zero_and_intersecting() -> None:
    r = mesh_distance(box([0, 0, 0], [1, 1, 1]), box([1, 0.5, 0.5], [2, 1.5, 1.5]))
    assert r.distance == 0.0
    assert r.intersecting
    assert r.point_a[0] == pytest.approx(1.0, abs=1e-12)
    assert np.array_equal(r.point_a, r.point_b)
    assert not (r.a_inside_b or r.b_inside_a)


def test_touching_at_a_vertex() -> None:
    r = mesh_distance(box([0, 0, 0], [1, 1, 1]), box([1, 1, 1], [2, 2, 2]))
    assert r.distance == 0.0 and r.intersecting
    assert r.point_a == pytest.approx([1, 1, 1], abs=1e-12)


def test_overlapping_boxes_intersect() -> None:
    r = mesh_distance(box([0, 0, 0], [1, 1, 1]), box([0.5, 0.5, 0.5], [1.5, 1.5, 1.5]))
    assert r.distance == 0.0 and r.intersecting and not r.a_inside_b


def test_small_cube_inside_big_cube() -> None:
    small, big = box([0.4, 0.4, 0.4], [0.6, 0.6, 0.6]), box([0, 0, 0], [1, 1, 1])
    r = mesh_distance(small, big)
    assert not r.intersecting
    assert r.a_inside_b and not r.b_inside_a
    assert r.distance == pytest.approx(0.4, abs=1e-12)
    swapped = mesh_distance(big, small)
    assert swapped.b_inside_a and not swapped.a_inside_b
    assert swapped.distance == pytest.approx(0.4, abs=1e-12)


def test_inside_an_inward_wound_mesh_counts() -> None:
    big = box([0, 0, 0], [1, 1, 1])
    r = mesh_distance(box([0.4] * 3, [0.6] * 3), (big.vertices, big.faces[:, ::-1]))
    assert r.a_inside_b


def test_containment_beyond_max_distance() -> None:
    small, big = box([0.4] * 3, [0.6] * 3), box([0, 0, 0], [1, 1, 1])
    r = mesh_distance(small, big, max_distance=0.1)
    assert r.distance == math.inf and r.status == Status.CONVERGED
    assert np.isnan(r.point_a).all() and r.triangle_a == -1
    assert r.a_inside_b


def test_ball_in_bowl_is_separated_not_inside() -> None:
    shell = bowl()
    assert shell.is_watertight and shell.volume > 0
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    r = mesh_distance(ball, shell, pose(translation=(0, 0, -0.55)))
    assert not r.intersecting
    assert not (r.a_inside_b or r.b_inside_a)
    # 0.05 for the smooth shapes; the tessellations differ from them by less than 1e-3 there
    assert r.distance == pytest.approx(0.05, abs=1e-3)
    # while the ball is inside the bowl's convex hull
    hull = shell.convex_hull
    assert mesh_distance(ball, hull, pose(translation=(0, 0, -0.55))).a_inside_b


def test_max_distance_cut_off() -> None:
    meshes = MeshSet.from_arrays(
        [box([0, 0, 0], [1, 1, 1])] * 3,
        [pose(), pose(translation=(2, 0, 0)), pose(translation=(5, 0, 0))],
    )
    r = mesh_distance_batch(meshes, None, [[0, 1], [0, 2]], max_distance=2.0)
    assert r.distance[0] == pytest.approx(1.0, abs=1e-12)
    assert r.distance[1] == math.inf and np.isnan(r.point_a[1]).all()
    assert (r.status == Status.CONVERGED).all()
    exact = mesh_distance_batch(meshes, None, [[0, 1], [0, 2]], max_distance=4.0)
    assert exact.distance[1] == pytest.approx(4.0, abs=1e-12)  # the bound itself counts


def test_from_bodies_uses_body_transforms() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    bodies = [
        Body("a", None, cube.vertices, cube.faces),
        Body("b", None, cube.vertices, cube.faces, pose=pose(translation=(0, 0, 3))),
    ]
    meshes = MeshSet.from_bodies(bodies)
    assert mesh_distance_batch(meshes, None, [[0, 1]]).distance[0] == pytest.approx(2.0, abs=1e-12)
    assert mesh_distance(bodies[0], bodies[1]).distance == pytest.approx(2.0, abs=1e-12)


def test_public_names_are_exported() -> None:
    for name in (
        "MeshSet",
        "mesh_distance",
        "mesh_distance_batch",
        "mesh_intersects_batch",
        "MeshDistanceBatch",
        "MeshDistanceResult",
        "MeshIntersectsBatch",
    ):
        assert getattr(meshcol, name) is not None
    assert _core.defaults.mesh_bvh_leaf_size == 4
    assert _core.defaults.winding_number_inside == 0.5


# --------------------------------------------------------------------------- triangle oracle


def test_triangle_distance_matches_numpy_oracle_on_random_pairs() -> None:
    rng = np.random.default_rng(7)
    n = 1200
    a = rng.normal(size=(n, 3, 3))
    b = rng.normal(size=(n, 3, 3)) + rng.normal(size=(n, 1, 3)) * 0.8
    d, pa, pb, hit = _core.triangle_distance_batch(a, b)
    checked_apart = checked_hit = 0
    for k in range(n):
        crossings = _edge_crossings(a[k], b[k], False) + _edge_crossings(b[k], a[k], False)
        margins = [c for c in crossings if c is not None]
        if any(c > 1e-7 for c in margins):  # clearly intersecting
            checked_hit += 1
            assert hit[k] and d[k] == 0.0, k
            assert _point_triangle(pa[k], a[k]) < 1e-9 and _point_triangle(pa[k], b[k]) < 1e-9
        elif all(c < -1e-7 for c in margins) and len(margins) == 6:  # clearly apart
            checked_apart += 1
            expected = oracle_separated_distance(a[k], b[k])
            assert not hit[k], k
            assert d[k] == pytest.approx(expected, rel=1e-9, abs=1e-12), k
            assert np.linalg.norm(pb[k] - pa[k]) == pytest.approx(d[k], rel=1e-9, abs=1e-12)
            assert _point_triangle(pa[k], a[k]) < 1e-9 and _point_triangle(pb[k], b[k]) < 1e-9
    assert checked_apart > 400 and checked_hit > 100


def test_triangle_special_cases() -> None:
    def tri_d(a, b):
        d, pa, pb, hit = _core.triangle_distance_batch(np.array([a], float), np.array([b], float))
        return d[0], hit[0]

    t = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]
    assert tri_d(t, [[0.5, 0.5, 0], [1, 0.5, 0], [0.5, 1, 0]]) == (0.0, True)  # coplanar, inside
    assert tri_d(t, [[-1, 1, 0], [3, 1, 0], [1, 3, 0]]) == (0.0, True)  # coplanar, crossing edges
    assert tri_d(t, [[3, 3, 0], [4, 3, 0], [3, 4, 0]])[1] is np.False_  # coplanar, apart
    assert tri_d(t, [[3, 3, 0], [4, 3, 0], [3, 4, 0]])[0] == pytest.approx(math.sqrt(8), abs=1e-12)
    assert tri_d(t, [[2, 0, 0], [3, 0, 1], [3, 1, 1]]) == (0.0, True)  # shared vertex
    assert tri_d(t, [[0.5, 0.5, -1], [0.5, 0.5, 1], [0.6, 0.6, 1]]) == (0.0, True)  # pierced
    assert tri_d(t, [[0.5, 0.5, 0.5], [0.5, 0.5, 1], [0.5, 0.5, 2]])[0] == pytest.approx(
        0.5
    )  # degenerate
    assert tri_d(t, [[0.5, 0.5, -1], [0.5, 0.5, 1], [0.5, 0.5, 2]]) == (
        0.0,
        True,
    )  # degenerate pierces
    assert tri_d(t, [[1, 1, 1], [1, 1, 1], [1, 1, 1]])[0] == pytest.approx(1.0)  # a point


integer_triangle = st.lists(
    st.lists(st.integers(-2, 2), min_size=3, max_size=3), min_size=3, max_size=3
)


@given(integer_triangle, integer_triangle, st.permutations(range(3)), st.booleans())
def test_integer_triangles_exact_and_order_independent(a, b, perm, swap) -> None:
    """Small-integer triangles (coplanar, touching, degenerate cases galore) are exact."""
    a, b = np.array(a, float), np.array(b, float)
    d, pa, pb, hit = _core.triangle_distance_batch(np.array([a, b]), np.array([b, a[perm]]))
    # independent of argument order and vertex order
    assert hit[0] == hit[1]
    assert d[0] == pytest.approx(d[1], rel=1e-12, abs=1e-15)
    if hit[0]:
        assert d[0] == 0.0
        assert _point_triangle(pa[0], a) < 1e-9 and _point_triangle(pa[0], b) < 1e-9
    else:
        assert d[0] == pytest.approx(oracle_separated_distance(a, b), rel=1e-9, abs=1e-12)
        # exact rational check: no edge of one crosses the other (non-coplanar edges only)
        ia, ib = a.astype(int).tolist(), b.astype(int).tolist()
        for x, y in ((ia, ib), (ib, ia)):
            for margin in _edge_crossings(x, y, True):
                assert margin is None or margin < 0


# --------------------------------------------------------------------------- mesh properties


def _mesh_library() -> list[trimesh.Trimesh]:
    return [
        box([-0.5, -0.3, -0.2], [0.5, 0.3, 0.2]),
        trimesh.creation.icosphere(subdivisions=1, radius=0.6),
        trimesh.creation.torus(0.6, 0.2, major_sections=16, minor_sections=8),
        trimesh.creation.cylinder(radius=0.3, height=1.2, sections=12),
        bowl(n=6, sections=12),
    ]


LIBRARY = _mesh_library()
LIBRARY_SET = MeshSet.from_arrays(LIBRARY)


def _triangle_pairs_intersect(ta: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Exact intersection of triangle pairs ta[k], tb[k] (n, 3, 3), independent of the C++ test.

    Non-coplanar triangles meet iff an edge of one crosses the other (closed): solve
    p + t d = b0 + u e1 + v e2 per edge. A float solve decides the edges whose margin
    min(t, 1 - t, u, v, 1 - u - v) is clearly away from 0 on a well-conditioned system; every
    other pair is decided in exact rational arithmetic (Fraction of each double).
    """
    n = len(ta)
    hit = np.zeros(n, dtype=bool)
    unsure = np.zeros(n, dtype=bool)
    for x, y in ((ta, tb), (tb, ta)):
        for i in range(3):
            p, q = x[:, i], x[:, (i + 1) % 3]
            m = np.stack([q - p, y[:, 0] - y[:, 1], y[:, 0] - y[:, 2]], axis=2)
            scale = np.prod(np.linalg.norm(m, axis=1), axis=1)
            det = np.linalg.det(m)
            good = np.abs(det) > 1e-6 * np.maximum(scale, 1e-300)
            sol = np.full((n, 3), np.nan)
            sol[good] = np.linalg.solve(m[good], (y[good, 0] - p[good])[..., None])[..., 0]
            t, u, v = sol[:, 0], sol[:, 1], sol[:, 2]
            margin = np.minimum.reduce([t, 1 - t, u, v, 1 - u - v])
            hit |= good & (margin > 1e-9)
            unsure |= ~good | (np.abs(margin) <= 1e-9)
    for k in np.flatnonzero(unsure & ~hit):
        a = [[Fraction(float(c)) for c in row] for row in ta[k]]
        b = [[Fraction(float(c)) for c in row] for row in tb[k]]
        hit[k] = _exact_triangles_intersect(a, b)
    return hit


def _sub(p, q):
    return [p[0] - q[0], p[1] - q[1], p[2] - q[2]]


def _orient3(a, b, c, d) -> int:
    det = _det3([_sub(a, d), _sub(b, d), _sub(c, d)])
    return (det > 0) - (det < 0)


def _exact_triangles_intersect(a, b) -> bool:
    """Exact test on rational triangles (non-degenerate): edge crossings, else the coplanar
    case in the projection that keeps the common plane's area."""
    crossings = _edge_crossings(a, b, True) + _edge_crossings(b, a, True)
    if any(c is not None and c >= 0 for c in crossings):
        return True
    if any(_orient3(b[0], b[1], b[2], p) != 0 for p in a):
        return False  # not coplanar; a parallel edge (None) cannot meet the other triangle
    # Coplanar: drop the axis along which the plane's normal is largest.
    n = [
        (b[1][1] - b[0][1]) * (b[2][2] - b[0][2]) - (b[1][2] - b[0][2]) * (b[2][1] - b[0][1]),
        (b[1][2] - b[0][2]) * (b[2][0] - b[0][0]) - (b[1][0] - b[0][0]) * (b[2][2] - b[0][2]),
        (b[1][0] - b[0][0]) * (b[2][1] - b[0][1]) - (b[1][1] - b[0][1]) * (b[2][0] - b[0][0]),
    ]
    drop = max(range(3), key=lambda k: abs(n[k]))
    keep = [k for k in range(3) if k != drop]
    a2 = [[p[k] for k in keep] for p in a]
    b2 = [[p[k] for k in keep] for p in b]

    def o2(p, q, r) -> int:
        v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        return (v > 0) - (v < 0)

    def inside(p, t) -> bool:
        s = [o2(t[i], t[(i + 1) % 3], p) for i in range(3)]
        return all(x >= 0 for x in s) or all(x <= 0 for x in s)

    def on_segment(p, q, r) -> bool:  # r on [p, q], given collinear
        return min(p[0], q[0]) <= r[0] <= max(p[0], q[0]) and min(p[1], q[1]) <= r[1] <= max(
            p[1], q[1]
        )

    def meet(p, q, r, s) -> bool:
        o = [o2(p, q, r), o2(p, q, s), o2(r, s, p), o2(r, s, q)]
        if o[0] * o[1] < 0 and o[2] * o[3] < 0:
            return True
        return (
            (o[0] == 0 and on_segment(p, q, r))
            or (o[1] == 0 and on_segment(p, q, s))
            or (o[2] == 0 and on_segment(r, s, p))
            or (o[3] == 0 and on_segment(r, s, q))
        )

    if any(inside(p, b2) for p in a2) or any(inside(p, a2) for p in b2):
        return True
    return any(
        meet(a2[i], a2[(i + 1) % 3], b2[j], b2[(j + 1) % 3]) for i in range(3) for j in range(3)
    )


def brute_force(a: trimesh.Trimesh, pa, b: trimesh.Trimesh, pb) -> tuple[float, bool]:
    """(distance, intersecting) over all triangle pairs: intersection by the exact oracle
    above, distance by the C++ triangle-pair distance of the pairs that do not intersect."""
    ta = trimesh.transform_points(a.vertices, pa)[a.faces]
    tb = trimesh.transform_points(b.vertices, pb)[b.faces]
    ia, ib = np.meshgrid(np.arange(len(ta)), np.arange(len(tb)), indexing="ij")
    ia, ib = ia.ravel(), ib.ravel()
    d, _, _, hit = _core.triangle_distance_batch(
        np.ascontiguousarray(ta[ia]), np.ascontiguousarray(tb[ib])
    )
    # only pairs whose boxes overlap can intersect
    lo_a, hi_a, lo_b, hi_b = ta.min(1), ta.max(1), tb.min(1), tb.max(1)
    near = np.all((lo_a[ia] <= hi_b[ib]) & (lo_b[ib] <= hi_a[ia]), axis=1)
    exact = np.zeros(len(ia), dtype=bool)
    exact[near] = _triangle_pairs_intersect(ta[ia[near]], tb[ib[near]])
    # the C++ pair test agrees with the exact one
    assert np.array_equal(hit, exact), np.flatnonzero(hit != exact)[:5]
    return float(d[~exact].min()) if (~exact).any() else 0.0, bool(exact.any())


quaternion = st.tuples(*[st.floats(-1, 1) for _ in range(4)]).filter(
    lambda q: sum(x * x for x in q) > 0.01
)
translation = st.tuples(*[st.floats(-1.5, 1.5) for _ in range(3)])
poses = st.builds(lambda q, t: pose(rotation_from_quaternion(q), t), quaternion, translation)
mesh_index = st.integers(0, len(LIBRARY) - 1)


@given(mesh_index, mesh_index, poses, poses)
def test_bvh_distance_equals_brute_force_over_triangle_pairs(i, j, pa, pb) -> None:
    if i == j:
        return  # one mesh posed twice: see the symmetry test
    r = mesh_distance_batch(LIBRARY_SET, _poses_for(i, j, pa, pb), [[i, j]])
    d, hit = brute_force(LIBRARY[i], pa, LIBRARY[j], pb)
    assert bool(r.intersecting[0]) == (hit or d == 0.0)
    assert r.distance[0] == pytest.approx(0.0 if hit else d, rel=1e-9, abs=1e-12)
    assert np.linalg.norm(r.point_b[0] - r.point_a[0]) == pytest.approx(
        r.distance[0], rel=1e-9, abs=1e-12
    )


def _poses_for(i, j, pa, pb) -> np.ndarray:
    p = np.tile(np.eye(4), (len(LIBRARY), 1, 1))
    p[i], p[j] = pa, pb
    return p


@given(mesh_index, mesh_index, poses, poses, poses)
def test_symmetry_and_rigid_invariance(i, j, pa, pb, motion) -> None:
    if i == j:
        return  # the pose array holds one pose per mesh
    p = _poses_for(i, j, pa, pb)
    moved = p.copy()
    moved[i], moved[j] = motion @ pa, motion @ pb
    r = mesh_distance_batch(LIBRARY_SET, p, [[i, j], [j, i]])
    m = mesh_distance_batch(LIBRARY_SET, moved, [[i, j]])
    assert r.distance[0] == pytest.approx(r.distance[1], rel=1e-9, abs=1e-12)
    assert r.intersecting[0] == r.intersecting[1]
    assert r.a_inside_b[0] == r.b_inside_a[1] and r.b_inside_a[0] == r.a_inside_b[1]
    assert m.distance[0] == pytest.approx(r.distance[0], rel=1e-9, abs=1e-9)
    assert m.intersecting[0] == r.intersecting[0] or r.distance[0] < 1e-9
    # AABB gap is a lower bound
    wa = trimesh.transform_points(LIBRARY[i].vertices, pa)
    wb = trimesh.transform_points(LIBRARY[j].vertices, pb)
    gap = np.maximum(0, np.maximum(wa.min(0) - wb.max(0), wb.min(0) - wa.max(0)))
    assert r.distance[0] >= np.linalg.norm(gap) - 1e-12
    # intersects-only query agrees
    assert mesh_intersects_batch(LIBRARY_SET, p, [[i, j]]).intersecting[0] == r.intersecting[0]


@given(
    st.lists(st.tuples(mesh_index, mesh_index), min_size=1, max_size=12),
    st.lists(poses, min_size=len(LIBRARY), max_size=len(LIBRARY)),
    st.integers(0, 3),
    st.floats(0.0, 2.0),
)
def test_batch_equals_loop_of_singles(pairs, pose_list, threads, max_distance) -> None:
    p = np.stack(pose_list)
    r = mesh_distance_batch(LIBRARY_SET, p, pairs, threads=threads, max_distance=max_distance)
    full = mesh_distance_batch(LIBRARY_SET, p, pairs, threads=1)
    for k, (i, j) in enumerate(pairs):
        s = mesh_distance(LIBRARY[i], LIBRARY[j], p[i], p[j], max_distance=max_distance)
        assert s.distance == r.distance[k] or (np.isnan(s.distance) and np.isnan(r.distance[k]))
        assert s.intersecting == r.intersecting[k] and s.a_inside_b == r.a_inside_b[k]
        assert s.b_inside_a == r.b_inside_a[k] and s.status == r.status[k]
        if full.distance[k] <= max_distance:
            assert r.distance[k] == full.distance[k]
        else:
            assert r.distance[k] == math.inf
        assert r.a_inside_b[k] == full.a_inside_b[k]


def test_bvh_validates_on_corpus_and_library(corpus) -> None:
    assert LIBRARY_SET.validate()
    meshes = [
        trimesh.load(corpus / "trimesh-models" / name, force="mesh")
        for name in ("torus.STL", "fandisk.obj", "soup.stl", "ballA.off")
    ]
    assert MeshSet.from_arrays(meshes).validate()


def test_winding_number_inside_outside() -> None:
    w = LIBRARY_SET.winding_number(1, [[0, 0, 0], [2, 0, 0], [0.1, 0.2, -0.3]])
    assert w == pytest.approx([1.0, 0.0, 1.0], abs=1e-9)


# --------------------------------------------------------------------------- python-fcl


def _fcl_model(fcl, mesh: trimesh.Trimesh):
    m = fcl.BVHModel()
    m.beginModel(len(mesh.vertices), len(mesh.faces))
    m.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    m.endModel()
    return m


def _fcl_distance(fcl, ma, pa, mb, pb) -> tuple[float, bool]:
    oa = fcl.CollisionObject(ma, fcl.Transform(pa[:3, :3], pa[:3, 3]))
    ob = fcl.CollisionObject(mb, fcl.Transform(pb[:3, :3], pb[:3, 3]))
    collision = fcl.CollisionResult()
    fcl.collide(oa, ob, fcl.CollisionRequest(), collision)
    return fcl.distance(oa, ob, fcl.DistanceRequest(), fcl.DistanceResult()), collision.is_collision


def test_ball_pair_from_corpus_intersects(corpus) -> None:
    fcl = pytest.importorskip("fcl")
    a = trimesh.load(corpus / "trimesh-models" / "ballA.off", force="mesh")
    b = trimesh.load(corpus / "trimesh-models" / "ballB.off", force="mesh")
    r = mesh_distance(a, b)
    assert r.intersecting and r.distance == 0.0
    assert _fcl_distance(fcl, _fcl_model(fcl, a), np.eye(4), _fcl_model(fcl, b), np.eye(4))[1]
    # the witness lies on both reported triangles
    assert _point_triangle(r.point_a, a.vertices[a.faces[r.triangle_a]]) < 1e-9
    assert _point_triangle(r.point_a, b.vertices[b.faces[r.triangle_b]]) < 1e-9
    # moved apart along x by 20 (their extents overlap by about 13.8): separated, as fcl says
    d, hit = _fcl_distance(
        fcl, _fcl_model(fcl, a), np.eye(4), _fcl_model(fcl, b), pose(translation=(20, 0, 0))
    )
    apart = mesh_distance(a, b, None, pose(translation=(20, 0, 0)))
    assert not hit and not apart.intersecting
    assert apart.distance == pytest.approx(d, rel=1e-9)


def test_pins_scene_matches_fcl(corpus) -> None:
    fcl = pytest.importorskip("fcl")
    parts = trimesh.load(corpus / "trimesh-models" / "pins.glb").dump()
    meshes = MeshSet.from_arrays(parts)
    models = [_fcl_model(fcl, m) for m in parts]
    pairs = np.array([(i, j) for i in range(len(parts)) for j in range(i + 1, len(parts))])
    r = mesh_distance_batch(meshes, None, pairs)
    for k, (i, j) in enumerate(pairs):
        d, hit = _fcl_distance(fcl, models[i], np.eye(4), models[j], np.eye(4))
        assert bool(r.intersecting[k]) == hit, (i, j)
        if not hit:
            assert r.distance[k] == pytest.approx(d, rel=1e-9), (i, j)


@pytest.mark.parametrize("name", ["torus.STL", "fandisk.obj"])
def test_posed_copies_match_fcl(corpus, name) -> None:
    fcl = pytest.importorskip("fcl")
    mesh = trimesh.load(corpus / "trimesh-models" / name, force="mesh")
    model = _fcl_model(fcl, mesh)
    meshes = MeshSet.from_arrays([mesh])
    rng = np.random.default_rng(3)
    extent = float(mesh.extents.max())
    agreed_apart = 0
    for _ in range(12):
        pb = pose(rotation_from_quaternion(rng.normal(size=4)), rng.normal(size=3) * extent * 0.8)
        d, hit = _fcl_distance(fcl, model, np.eye(4), model, pb)
        two = MeshSet.from_arrays([mesh, mesh], np.stack([np.eye(4), pb]))
        r = mesh_distance_batch(two, None, [[0, 1]])
        assert bool(r.intersecting[0]) == hit
        if not hit:
            agreed_apart += 1
            assert r.distance[0] == pytest.approx(d, rel=1e-9)
    assert agreed_apart >= 3
    assert len(meshes) == 1


# --------------------------------------------------------------------------- bad input


def test_face_index_out_of_range_names_the_mesh() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    bad_faces = cube.faces.copy()
    bad_faces[3, 1] = 8
    with pytest.raises(
        ValueError, match=r"^meshes\[1\]: face vertex index 8 out of range \[0, 8\)$"
    ):
        MeshSet.from_arrays([cube, (cube.vertices, bad_faces)])
    with pytest.raises(
        ValueError, match=r"^mesh 1: face 3 has vertex index 8 out of range \[0, 8\)$"
    ):
        _core.MeshBvhSet(
            np.vstack([cube.vertices] * 2),
            np.vstack([cube.faces, bad_faces]).astype(np.int64),
            np.array([0, 8, 16]),
            np.array([0, 12, 24]),
        )


def test_malformed_calls_raise_value_error() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    meshes = MeshSet.from_arrays([cube, cube])
    with pytest.raises(ValueError, match=r"^poses must be \(2, 4, 4\), got \(3, 3\)$"):
        mesh_distance_batch(meshes, np.eye(3), [[0, 1]])
    with pytest.raises(ValueError, match=r"^pairs must be \(P, 2\), got \(3,\)$"):
        mesh_distance_batch(meshes, None, [0, 1, 1])
    with pytest.raises(ValueError, match=r"^pairs: index 2 out of range for 2 meshes$"):
        mesh_distance_batch(meshes, None, [[0, 2]])
    with pytest.raises(ValueError, match=r"^max_distance must be >= 0, got -1.0$"):
        mesh_distance_batch(meshes, None, [[0, 1]], max_distance=-1)
    with pytest.raises(ValueError, match=r"^meshes\[0\]: vertices must be \(n, 3\), got \(8, 2\)$"):
        MeshSet.from_arrays([(cube.vertices[:, :2], cube.faces)])
    with pytest.raises(ValueError, match=r"^meshes\[0\]: faces must be integers, got float64$"):
        MeshSet.from_arrays([(cube.vertices, cube.faces.astype(float))])
    assert len(mesh_distance_batch(meshes, None, np.zeros((0, 2), int))) == 0


def test_bad_data_sets_pair_status_only() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    nan_vertices = cube.vertices.copy()
    nan_vertices[2, 1] = np.nan
    inf_vertices = cube.vertices.copy()
    inf_vertices[0, 0] = np.inf
    meshes = MeshSet.from_arrays(
        [
            cube,
            (nan_vertices, cube.faces),
            (inf_vertices, cube.faces),
            (cube.vertices, np.zeros((0, 3), int)),
            cube,
        ]
    )
    assert meshes.valid.tolist() == [True, False, False, False, True]
    p = np.tile(np.eye(4), (5, 1, 1))
    p[4, :3, 3] = (3, 0, 0)
    r = mesh_distance_batch(meshes, p, [[0, 1], [2, 0], [0, 3], [0, 4]])
    assert r.status.tolist() == [Status.INVALID_INPUT] * 3 + [Status.CONVERGED]
    assert np.isnan(r.distance[:3]).all() and r.distance[3] == pytest.approx(2.0)
    assert mesh_intersects_batch(meshes, p, [[0, 1], [0, 4]]).status.tolist() == [3, 0]
    for bad in (np.diag([2.0, 1, 1, 1]), np.full((4, 4), np.nan)):
        q = p.copy()
        q[4] = bad
        r = mesh_distance_batch(meshes, q, [[0, 4], [0, 0]])
        assert r.status.tolist() == [Status.INVALID_INPUT, Status.CONVERGED]
        assert r.distance[1] == 0.0 and r.intersecting[1]


# --------------------------------------------------------------------------- point queries


def brute_point_mesh_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest of all triangles: the nearest of the three
    edges (point-segment), or the plane when the projection falls inside a non-degenerate
    triangle."""
    p = points[:, None, None, :]
    a, b = triangles, np.roll(triangles, -1, axis=1)
    ab = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.einsum("...i,...i", p - a, ab) / np.einsum("...i,...i", ab, ab), 0.0, 1.0)
    t = np.nan_to_num(t)
    edge = np.linalg.norm(p - (a + ab * t[..., None]), axis=-1).min(axis=2)
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    nn = np.einsum("ij,ij->i", n, n)
    q = points[:, None, :]
    inside = nn > 0
    for k in range(3):
        e = triangles[:, (k + 1) % 3] - triangles[:, k]
        inside = inside & (np.einsum("ij,pij->pi", np.cross(e, n), q - triangles[:, k]) <= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        plane = np.abs(np.einsum("ij,pij->pi", n, q - triangles[:, 0])) / np.sqrt(nn)
    return np.where(inside, np.minimum(plane, edge), edge).min(axis=1)


@pytest.mark.parametrize("seed", range(6))
def test_closest_points_equal_brute_force(seed) -> None:
    rng = np.random.default_rng(seed)
    vertices = rng.uniform(-1.0, 1.0, (40, 3))
    faces = rng.integers(0, 40, (60, 3))
    faces[:5, 1] = faces[:5, 0]  # degenerate: a repeated corner
    vertices[faces[5:8, 2]] = (vertices[faces[5:8, 0]] + vertices[faces[5:8, 1]]) / 2  # collinear
    tri = vertices[faces]
    w = rng.dirichlet(np.ones(3), 50)
    on_surface = np.einsum("pk,pki->pi", w, tri[rng.integers(0, len(faces), 50)])
    points = np.vstack([rng.uniform(-2.0, 2.0, (150, 3)), on_surface, vertices[faces[:10, 2]]])
    meshes = MeshSet.from_arrays([(vertices, faces)])
    d, closest = meshes.closest_points(0, points)
    assert np.allclose(d, brute_point_mesh_distance(points, tri), rtol=0, atol=1e-12)
    assert np.allclose(np.linalg.norm(closest - points, axis=1), d, rtol=0, atol=1e-12)
    assert np.all(d[150:] <= 1e-12)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("offset", "scale"), [(0.0, 1.0), (1e6, 1e-3), (-3e4, 50.0)], ids=["unit", "far-small", "big"]
)
def test_closest_points_on_curved_closed_meshes_equal_brute_force(offset, scale) -> None:
    """The point search prunes by the nodes' oriented boxes (thin slabs on a curved surface):
    from points deep inside, on and near the surface, and far away, of a rotated sphere and
    torus far from the origin (where the boxes' rounding pad is smallest relative to the
    subtractions), the distance is the brute-force minimum over the triangles."""
    rng = np.random.default_rng(3)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    for mesh in (trimesh.creation.icosphere(3), trimesh.creation.torus(1.0, 0.3)):
        vertices = (mesh.vertices @ rotation.T) * scale + offset
        tri = vertices[mesh.faces]
        w = rng.dirichlet(np.ones(3), 60)
        on_surface = np.einsum("pk,pki->pi", w, tri[rng.integers(0, len(mesh.faces), 60)])
        unit = rng.normal(size=(240, 3))
        unit /= np.linalg.norm(unit, axis=1, keepdims=True)
        radii = np.repeat([0.05, 0.5, 0.95, 1.02, 3.0, 1e3], 40)[:, None]
        points = np.vstack([(unit * radii) @ rotation.T * scale + offset, on_surface])
        d, closest = MeshSet.from_arrays([(vertices, mesh.faces)]).closest_points(0, points)
        tolerance = 1e-12 * (abs(offset) + scale * 1e3)
        assert np.allclose(d, brute_point_mesh_distance(points, tri), rtol=1e-12, atol=tolerance)
        assert np.allclose(np.linalg.norm(closest - points, axis=1), d, rtol=1e-12, atol=tolerance)


def test_closest_points_known_answers_and_bad_input() -> None:
    meshes = MeshSet.from_arrays(
        [box((0, 0, 0), (1, 1, 1)), (np.full((3, 3), np.nan), [[0, 1, 2]])]
    )
    points = np.array([[0.5, 0.5, 3.0], [2.0, 2.0, 0.5], [0.5, 0.5, 0.4], [np.nan, 0.0, 0.0]])
    d, closest = meshes.closest_points(0, points)
    assert d[:3] == pytest.approx([2.0, math.sqrt(2.0), 0.4], abs=1e-12)
    assert closest[0] == pytest.approx([0.5, 0.5, 1.0], abs=1e-12)
    assert np.isnan(d[3]) and np.all(np.isnan(closest[3]))
    d, closest = meshes.closest_points(1, points)  # invalid mesh: NaN, no error
    assert np.all(np.isnan(d)) and np.all(np.isnan(closest))
    with pytest.raises(ValueError, match="points must be"):
        meshes.closest_points(0, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="out of range"):
        meshes.closest_points(2, points)
    assert meshes.closest_points(0, np.zeros((0, 3)))[0].shape == (0,)


def test_triangle_pair_far_apart_is_not_reported_touching() -> None:
    """Found by the BVH-against-brute-force property (a torus and a bowl, both rotated); the
    BVH answer (0.0685) matches python-fcl, the triangle-pair oracle does not."""
    a = np.array(
        [
            [
                [-0.39999999999999997, 1.9594348786357654e-17, -1.469576158976824e-17],
                [-0.42367142301913435, 0.21843135463250812, 0.055539545781161624],
                [-0.3695518130045147, 0.09184402376762155, 0.12245869835682871],
            ]
        ]
    )
    b = np.array(
        [
            [
                [-0.4500000000000001, 0.4676537180435968, 0.6235382907247958],
                [-6.123233995736766e-17, 0.6, 0.8],
                [-5.5109105961630896e-17, 0.54, 0.7200000000000001],
            ]
        ]
    )
    distance, _, _, hit = _core.triangle_distance_batch(a, b)
    assert not hit[0]
    assert distance[0] == pytest.approx(0.61995555, rel=1e-6)


# --------------------------------------------------------------------------- extreme inputs

_DENORMAL_BUILD = """
import numpy as np, trimesh
from meshcol.collision.mesh_query import MeshSet, mesh_distance_batch
ball = trimesh.creation.icosphere(subdivisions=2)
for scale in (1e-310, 1e-320, 5e-324, 0.0, 1e300):
    meshes = MeshSet.from_arrays(
        [(ball.vertices * scale, ball.faces), (ball.vertices * scale + 0.5 * scale, ball.faces)]
    )
    assert meshes.valid.all() and meshes.validate(), scale
    r = mesh_distance_batch(meshes, None, [[0, 1]])
    # an answer, or the range rule's OUT_OF_RANGE (5) for lengths outside [2^-100, 2^100]
    assert r.status[0] in (0, 5), scale
    assert r.status[0] == 5 or (r.distance[0] == 0.0 and r.intersecting[0]), scale
print("ok")
"""


def test_hierarchy_of_denormal_and_huge_vertices_builds_without_crashing() -> None:
    """Vertices near 1e-310 gave a NaN SAH bin index (kBins / extent overflowed to inf and
    0 * inf is NaN) and a crash (issue 13). Run in a child process so that a crash fails this
    test instead of killing the session."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _DENORMAL_BUILD], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert out.stdout.strip() == "ok"


def test_non_finite_vertices_make_the_mesh_invalid_not_a_crash() -> None:
    ball = trimesh.creation.icosphere(subdivisions=1)
    for bad in (np.nan, np.inf, -np.inf):
        v = ball.vertices.copy()
        v[3, 1] = bad
        meshes = MeshSet.from_arrays([(v, ball.faces), ball])
        assert meshes.valid.tolist() == [False, True]
        r = mesh_distance_batch(meshes, None, [[0, 1]])
        assert r.status[0] == Status.INVALID_INPUT and math.isnan(r.distance[0])


def test_overflowing_distance_is_out_of_range_not_converged() -> None:
    """Coordinates near 1e236 overflow the squared distances: the pair used to report
    CONVERGED with distance inf (found by the fuzz target `meshes`). The range check answers
    first (OUT_OF_RANGE, NaN); an overflow inside the range would be DEGENERATE."""
    a = box([-1e236, -1e236, -1e236], [-5e235, -5e235, -5e235])
    b = box([5e235, 5e235, 5e235], [1e236, 1e236, 1e236])
    for radius in (math.inf, 1.0):
        r = mesh_distance_batch(MeshSet.from_arrays([a, b]), None, [[0, 1]], max_distance=radius)
        assert r.status[0] == Status.OUT_OF_RANGE and math.isnan(r.distance[0])


# --------------------------------------------------------------------------- single-pair path


@given(
    st.lists(poses, min_size=len(LIBRARY), max_size=len(LIBRARY)),
    st.lists(st.tuples(mesh_index, mesh_index), min_size=1, max_size=8),
)
def test_single_pair_intersects_equals_the_batch(pose_list, pairs) -> None:
    """MeshSet.intersects (default poses, and poses given per call) gives the batch's
    verdicts, and the batch with poses=None (the core's cached copy of the set's poses) the
    batch with the same poses passed."""
    p = np.stack(pose_list)
    posed = MeshSet.from_arrays(LIBRARY, p)
    batch = mesh_intersects_batch(LIBRARY_SET, p, pairs)
    cached = mesh_intersects_batch(posed, None, np.asarray(pairs, dtype=np.int64))
    assert np.array_equal(cached.intersecting, batch.intersecting)
    assert np.array_equal(cached.status, batch.status)
    distance = mesh_distance_batch(posed, None, pairs)
    assert np.array_equal(distance.intersecting, batch.intersecting)
    for k, (i, j) in enumerate(pairs):
        assert posed.intersects(i, j) == batch.intersecting[k]
        # a Fortran-ordered copy exercises the binding's copy of a strided pose
        assert LIBRARY_SET.intersects(i, j, p[i], np.asfortranarray(p[j])) == batch.intersecting[k]
        assert LIBRARY_SET.intersects(i, j, p[i].tolist(), p[j]) == batch.intersecting[k]


def test_a_copy_at_the_same_rotated_pose_intersects_itself() -> None:
    """A duplicated prop: the same mesh twice at one rotated pose. Their relative pose must be
    the identity exactly (R^T R rounds otherwise, moving the copy off its own surface, and the
    exact triangle tests then found the coincident meshes apart). Found by the property test
    above (mesh 0 paired with itself)."""
    q = np.array([0.0, 0.90625, 0.67578125, 0.0])
    p = pose(rotation_from_quaternion(q / np.linalg.norm(q)), (0.25, -3.0, 7.0))
    for index, mesh in enumerate(LIBRARY):
        twice = MeshSet.from_arrays([mesh, mesh], np.stack([p, p]))
        assert twice.intersects(0, 1), index
        assert mesh_intersects_batch(twice, None, [(0, 1)]).intersecting[0], index
        assert mesh_distance_batch(twice, None, [(0, 1)]).distance[0] == 0.0, index


def test_single_pair_intersects_known_answers_and_bad_input() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    nan_vertices = cube.vertices.copy()
    nan_vertices[0, 0] = np.nan
    p = np.stack([np.eye(4), pose(translation=(0.5, 0.5, 0.5)), pose(translation=(3, 0, 0))])
    meshes = MeshSet.from_arrays([cube, cube, cube], p)
    assert meshes.intersects(0, 1) and not meshes.intersects(0, 2)
    assert meshes.intersects(0, 2, None, pose(translation=(1.0, 0, 0)))  # touching counts
    assert not meshes.intersects(0, 1, None, pose(translation=(1.5, 0, 0)))
    with pytest.raises(ValueError, match=r"^mesh index 3 out of range for 3 meshes$"):
        meshes.intersects(0, 3)
    with pytest.raises(ValueError, match=r"^mesh index -1 out of range for 3 meshes$"):
        meshes.intersects(-1, 0)
    with pytest.raises(ValueError, match=r"^pose_j must be \(4, 4\), got \(3, 3\)$"):
        meshes.intersects(0, 1, None, np.eye(3))
    with pytest.raises(ValueError, match=r"^pose_i must be \(4, 4\), got \(16,\)$"):
        meshes.intersects(0, 1, np.zeros(16))
    for bad in (np.full((4, 4), np.nan), np.diag([2.0, 1, 1, 1])):
        with pytest.raises(ValueError, match=r"^pose of mesh 1 is not rigid or not finite$"):
            meshes.intersects(0, 1, None, bad)
    # a non-rigid default pose: the batch reports INVALID_INPUT, the single pair raises
    q = p.copy()
    q[1, 0, 0] = 2.0
    skewed = MeshSet.from_arrays([cube, cube, cube], q)
    assert mesh_intersects_batch(skewed, None, [[0, 1]]).status.tolist() == [Status.INVALID_INPUT]
    assert mesh_distance_batch(skewed, None, [[0, 1]]).status.tolist() == [Status.INVALID_INPUT]
    with pytest.raises(ValueError, match=r"^pose of mesh 1 is not rigid or not finite$"):
        skewed.intersects(0, 1)
    invalid = MeshSet.from_arrays([cube, (nan_vertices, cube.faces)])
    with pytest.raises(
        ValueError, match=r"^mesh 1 is not valid \(a non-finite vertex or no faces\)$"
    ):
        invalid.intersects(0, 1)
    far = MeshSet.from_arrays([cube, cube], np.stack([np.eye(4), pose(translation=(1e200, 0, 0))]))
    assert mesh_intersects_batch(far, None, [[0, 1]]).status.tolist() == [Status.OUT_OF_RANGE]
    with pytest.raises(ValueError, match=r"OUT_OF_RANGE"):
        far.intersects(0, 1)


def test_int64_pairs_are_range_checked_by_the_core_with_the_same_message() -> None:
    cube = box([0, 0, 0], [1, 1, 1])
    meshes = MeshSet.from_arrays([cube, cube])
    for call in (mesh_intersects_batch, mesh_distance_batch, meshcol.mesh_penetration_depth_batch):
        for bad in ([[0, 2]], [[-1, 0]]):
            with pytest.raises(ValueError, match=r"^pairs: index -?\d out of range for 2 meshes$"):
                call(meshes, None, np.array(bad, dtype=np.int64))
            with pytest.raises(ValueError, match=r"^pairs: index -?\d out of range for 2 meshes$"):
                call(meshes, None, bad)
        assert len(call(meshes, None, np.zeros((0, 2), np.int64))) == 0
    # floats are refused, never truncated to indices
    with pytest.raises(ValueError, match=r"integer"):
        mesh_intersects_batch(meshes, None, np.array([[0.0, 1.0]]))


def test_intersects_batch_reads_every_input_form_alike() -> None:
    """The batch's one-call path (arrays already in the core's form, and lists of int pairs,
    read in place) and its converting path give the same results, in a result built with
    the dataclass's fields, as fresh writable arrays."""
    cube = box([0, 0, 0], [1, 1, 1])
    p = np.stack([np.eye(4), pose(translation=(0.5, 0.5, 0.5)), pose(translation=(3, 0, 0))])
    meshes = MeshSet.from_arrays([cube, cube, cube], p)
    pairs = np.array([[0, 1], [0, 2], [1, 2], [2, 2]], dtype=np.int64)
    expected = [True, False, False, True]
    forms = pair_forms(pairs)
    for poses in (None, p, p.tolist(), p.astype(np.float32).astype(np.float64)):
        for form in forms:
            r = mesh_intersects_batch(meshes, poses, form, threads=1)
            assert isinstance(r, MeshIntersectsBatch)
            assert [f.name for f in dataclasses.fields(r)] == ["intersecting", "status"]
            assert r.intersecting.dtype == np.bool_ and r.status.dtype == np.int8
            assert r.intersecting.flags.writeable and r.status.flags.c_contiguous
            assert r.intersecting.tolist() == expected, (type(form), type(poses))
            assert r.status.tolist() == [Status.CONVERGED] * 4
    # many pairs on several threads (the pairs are copied before the GIL is released)
    many = np.tile(pairs, (300, 1))
    for threads in (1, 2):
        r = mesh_intersects_batch(meshes, None, many, threads=threads)
        assert r.intersecting.tolist() == expected * 300
    assert len(mesh_intersects_batch(meshes, None, pairs[:0])) == 0
    # every call makes its own arrays
    a = mesh_intersects_batch(meshes, None, pairs[:1])
    b = mesh_intersects_batch(meshes, None, pairs[:1])
    assert a.intersecting is not b.intersecting and not np.shares_memory(a.status, b.status)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.intersecting = b.intersecting  # type: ignore[misc]
    assert len(mesh_intersects_batch(meshes, None, [])) == 0
    for bad in ([[True, False]], [[0, 1, 2]], [(0.0, 1.0)]):
        with pytest.raises(ValueError, match=r"^pairs must"):
            mesh_intersects_batch(meshes, None, bad)
    with pytest.raises(ValueError, match=r"^pairs: index 3 out of range for 3 meshes$"):
        mesh_intersects_batch(meshes, None, [(0, 3)])
    with pytest.raises(ValueError, match=r"^poses must be \(3, 4, 4\), got \(2, 4, 4\)$"):
        mesh_intersects_batch(meshes, p[:2], pairs)
    with pytest.raises(TypeError, match=r"MeshSet"):
        mesh_intersects_batch(cube, None, pairs)  # type: ignore[arg-type]
    # the type is checked when the call fails: a handle that is not a set's is refused alike
    for impostor in (types.SimpleNamespace(_handle=object()), types.SimpleNamespace(_handle=1)):
        with pytest.raises(TypeError, match=r"^meshes must be a MeshSet, got SimpleNamespace$"):
            mesh_intersects_batch(impostor, None, pairs)  # type: ignore[arg-type]


def test_intersects_batch_result_of_any_dataclass() -> None:
    """The core builds its result as the class's generated __init__ would: the field setters
    of a slotted class are looked up once per class, and another class (slotted or not) asked
    for in between gets its own, so the two never mix."""

    @dataclasses.dataclass(frozen=True)
    class Plain:
        intersecting: np.ndarray
        status: np.ndarray

    @dataclasses.dataclass(frozen=True, slots=True)
    class Slotted:
        intersecting: np.ndarray
        status: np.ndarray

    cube = box([0, 0, 0], [1, 1, 1])
    meshes = MeshSet.from_arrays([cube, cube], np.stack([np.eye(4), pose(translation=(3, 0, 0))]))
    pairs = np.array([[0, 0], [0, 1]], dtype=np.int64)
    for kind in (MeshIntersectsBatch, Plain, Slotted, Plain, MeshIntersectsBatch, Slotted):
        r = meshes._handle.intersects_batch(None, pairs, 1, kind)
        assert type(r) is kind
        assert r.intersecting.tolist() == [True, False]
        assert r.status.tolist() == [Status.CONVERGED] * 2
    with pytest.raises(TypeError, match=r"result_type must be a class"):
        meshes._handle.intersects_batch(None, pairs, 1, "not a class")


# --------------------------------------------------------------------------- shared hierarchies


def test_one_mesh_object_given_twice_is_checked_and_wound_once(monkeypatch) -> None:
    """The same input arrays given for several meshes (one trimesh twice, whose vertices
    convert to a new array at each call) are checked and wound once, and the meshes share the
    arrays; other arrays of the same bytes are wound on their own and still share a hierarchy."""
    import meshcol.collision.mesh_query as mesh_query

    calls = []
    wound = mesh_query._oriented
    monkeypatch.setattr(
        mesh_query, "_oriented", lambda v, f, orient: calls.append(len(f)) or wound(v, f, orient)
    )
    a = trimesh.creation.icosphere(1)
    meshes = MeshSet.from_arrays([a, a, (a.vertices, a.faces), a.copy()], threads=1)
    assert len(calls) == 2  # a (also given as the pair of its own arrays), and the copy
    assert meshes._handle.distinct_count() == 1
    blocks = [meshes.faces[meshes.face_offsets[i] : meshes.face_offsets[i + 1]] for i in range(4)]
    for block in blocks[1:]:
        np.testing.assert_array_equal(block, blocks[0])


def test_instances_share_one_hierarchy_with_the_answers_of_their_own() -> None:
    """Meshes of the same vertex and face bytes (instances of one asset, or equal copies) share
    one hierarchy; every query on a set of interleaved instances gives, bit for bit, what the
    sets of the two meshes of each pair alone give."""
    from meshcol.collision.mesh_query import mesh_penetration_depth_batch

    a, b = trimesh.creation.icosphere(2), trimesh.creation.capsule(height=1.0, radius=0.4)
    rng = np.random.default_rng(5)
    order = [a, b, a, a.copy(), b, b.copy()]  # copies: other arrays, the same bytes
    poses = np.tile(np.eye(4), (len(order), 1, 1))
    for p in poses:  # random rotations (det +1), centres within reach of each other
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        p[:3, :3] = q * np.sign(np.diag(r)) * np.sign(np.linalg.det(q * np.sign(np.diag(r))))
        p[:3, 3] = rng.uniform(-0.8, 0.8, 3)
    shared = MeshSet.from_arrays(order, poses, threads=1)
    assert len(shared) == 6 and shared._handle.distinct_count() == 2
    assert shared.validate()
    pairs = np.array([(i, j) for i in range(6) for j in range(6) if i != j])
    for i, j in pairs.tolist():
        alone = MeshSet.from_arrays([order[i], order[j]], poses[[i, j]], threads=1)
        one = np.array([[0, 1]])
        for query in (mesh_distance_batch, mesh_intersects_batch, mesh_penetration_depth_batch):
            want = query(alone, None, one, threads=1)
            got = query(shared, None, np.array([[i, j]]), threads=1)
            for field in dataclasses.fields(want):
                np.testing.assert_array_equal(getattr(got, field.name), getattr(want, field.name))
