"""Exact self-intersection verdicts: the native crossing test against a rational oracle.

Two faces cross when their open triangles share a point (meshcol.collision.self_intersection).
The oracle below decides that with ``fractions.Fraction`` arithmetic on the exact values of
the float coordinates, by a different route from the core: coplanar pairs by clipping one
triangle against the other and measuring the area left; other pairs by intersecting each
closed triangle with the other's plane, overlapping the two pieces on the common line and
testing whether the middle of the overlap lies strictly inside both triangles.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from meshcol.collision.self_intersection import face_pairs_cross, self_intersecting_pairs

# ------------------------------------------------------------------------------ exact oracle

Vec = tuple[Fraction, Fraction, Fraction]


def _sub(p: Vec, q: Vec) -> Vec:
    return (p[0] - q[0], p[1] - q[1], p[2] - q[2])


def _add(p: Vec, q: Vec) -> Vec:
    return (p[0] + q[0], p[1] + q[1], p[2] + q[2])


def _scale(p: Vec, s: Fraction) -> Vec:
    return (p[0] * s, p[1] * s, p[2] * s)


def _dot(p: Vec, q: Vec) -> Fraction:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _cross(p: Vec, q: Vec) -> Vec:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def _exact(triangle) -> list[Vec]:
    return [tuple(Fraction(float(x)) for x in p) for p in triangle]  # type: ignore[misc]


def _strictly_inside(m: Vec, t: list[Vec], n: Vec) -> bool:
    """m (in the plane of t) is in the open triangle t of normal n."""
    return all(_dot(n, _cross(_sub(t[i], m), _sub(t[(i + 1) % 3], m))) > 0 for i in range(3))


def _plane_section(t: list[Vec], side: list[Fraction]) -> list[Vec]:
    """Points spanning the closed triangle t's meeting with a plane (its vertices' sides)."""
    points = [t[i] for i in range(3) if side[i] == 0]
    for i in range(3):
        j = (i + 1) % 3
        if side[i] * side[j] < 0:
            points.append(_add(t[i], _scale(_sub(t[j], t[i]), side[i] / (side[i] - side[j]))))
    return points


def _clipped_area(a: list[Vec], b: list[Vec], nb: Vec) -> Fraction:
    """Twice the area (times |nb|) of triangle a clipped to the closed triangle b."""
    polygon = list(a)
    for i in range(3):
        q, r = b[i], b[(i + 1) % 3]
        side = [_dot(nb, _cross(_sub(r, q), _sub(p, q))) for p in polygon]
        clipped = []
        for k, p in enumerate(polygon):
            nxt, s_next = polygon[(k + 1) % len(polygon)], side[(k + 1) % len(polygon)]
            if side[k] >= 0:
                clipped.append(p)
            if side[k] * s_next < 0:
                clipped.append(_add(p, _scale(_sub(nxt, p), side[k] / (side[k] - s_next))))
        polygon = clipped
        if len(polygon) < 3:
            return Fraction(0)
    total: Vec = (Fraction(0), Fraction(0), Fraction(0))
    for k, p in enumerate(polygon):
        total = _add(total, _cross(p, polygon[(k + 1) % len(polygon)]))
    return abs(_dot(nb, total))


def exact_cross(a, b) -> bool:
    """Whether the open triangles a and b ((3, 3) float each) share a point, exactly."""
    ta, tb = _exact(a), _exact(b)
    na = _cross(_sub(ta[1], ta[0]), _sub(ta[2], ta[0]))
    nb = _cross(_sub(tb[1], tb[0]), _sub(tb[2], tb[0]))
    zero = (0, 0, 0)
    if na == zero or nb == zero:
        return False  # a degenerate triangle has no interior
    side_b = [_dot(na, _sub(p, ta[0])) for p in tb]
    if all(s == 0 for s in side_b):
        return _clipped_area(ta, tb, nb) > 0
    side_a = [_dot(nb, _sub(p, tb[0])) for p in ta]
    piece_a, piece_b = _plane_section(ta, side_a), _plane_section(tb, side_b)
    if not piece_a or not piece_b:
        return False
    line = _cross(na, nb)  # both pieces lie on the line where the planes meet
    ends_a = sorted(piece_a, key=lambda p: _dot(line, p))
    ends_b = sorted(piece_b, key=lambda p: _dot(line, p))
    low = max(ends_a[0], ends_b[0], key=lambda p: _dot(line, p))
    high = min(ends_a[-1], ends_b[-1], key=lambda p: _dot(line, p))
    if _dot(line, low) >= _dot(line, high):
        return False  # a point or nothing in common
    middle = _scale(_add(low, high), Fraction(1, 2))
    return _strictly_inside(middle, ta, na) and _strictly_inside(middle, tb, nb)


def native_cross(a, b) -> bool:
    vertices = np.vstack([np.asarray(a, float), np.asarray(b, float)])
    return bool(face_pairs_cross(vertices, [[0, 1, 2], [3, 4, 5]], [[0, 1]])[0])


# ------------------------------------------------------------------------------ known answers

A = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


@pytest.mark.parametrize(
    ("b", "crossing"),
    [
        # through the interior of A, by a lot and by 1e-12
        ([[0.2, 0.2, -1.0], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0]], True),
        ([[0.2, 0.2, -1e-12], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0]], True),
        # a vertex resting on A's interior; an edge lying in A: touching only
        ([[0.2, 0.2, 0.0], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0]], False),
        ([[0.2, 0.2, 0.0], [0.4, 0.2, 0.0], [0.2, 0.3, 1.0]], False),
        # parallel to A and 1e-12 above it (within the old snapping tolerance of 1e-10)
        ([[0.1, 0.1, 1e-12], [0.9, 0.1, 1e-12], [0.1, 0.8, 1e-12]], False),
        # tilted but entirely above A by 1e-12 to 3e-12
        ([[0.1, 0.1, 1e-12], [0.9, 0.1, 3e-12], [0.1, 0.8, 2e-12]], False),
        # straddling A's plane by 1e-12 over A's interior: crossing
        ([[0.1, 0.1, -1e-12], [0.9, 0.05, 1e-12], [0.05, 0.8, 1e-12]], True),
        # coplanar: overlapping, inside with every vertex on A's boundary, identical, touching
        ([[0.5, 0.5, 0.0], [-0.5, 0.5, 0.0], [0.5, -0.5, 0.0]], True),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.5, 0.0]], True),
        ([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], True),
        ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], False),
        # sharing an edge: folded onto A, unfolded, and at an angle
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.8, 0.0]], True),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, -0.8, 0.0]], False),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.8, 1e-12]], False),
        # sharing a vertex: apart, and piercing A from it
        ([[0.0, 0.0, 0.0], [-1.0, 0.0, 1.0], [0.0, -1.0, 1.0]], False),
        ([[0.0, 0.0, 0.0], [0.4, 0.4, -1.0], [0.4, 0.4, 1.0]], True),
        # degenerate (collinear) through A: no interior, no crossing
        ([[0.2, 0.2, -1.0], [0.2, 0.2, 0.0], [0.2, 0.2, 1.0]], False),
    ],
)
def test_known_pairs(b, crossing: bool) -> None:
    assert exact_cross(A, b) is crossing  # the oracle agrees with the geometry
    assert native_cross(A, b) is crossing
    assert native_cross(b, A) is crossing
    assert native_cross(A[::-1], b[::-1]) is crossing  # winding does not matter


def test_near_coplanar_faces_of_a_mesh_are_exact() -> None:
    # A face in the plane z = x + y and one 1e-12 above it (within the old snapping tolerance
    # of 1e-10 of the diagonal, which reported them crossing): apart. Moved down through it by
    # 2e-12 at one corner: crossing.
    v = np.array(
        [[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
        + [[0.1, 0.1, 0.2 + 1e-12], [0.8, 0.1, 0.9 + 1e-12], [0.1, 0.8, 0.9 + 1e-12]]
    )
    assert self_intersecting_pairs(v, [[0, 1, 2], [3, 4, 5]]).tolist() == []
    v[3, 2] = 0.2 - 1e-12
    assert self_intersecting_pairs(v, [[0, 1, 2], [3, 4, 5]]).tolist() == [[0, 1]]


def test_pole_fan_of_a_fine_uv_sphere_does_not_cross() -> None:
    # Two faces of the south pole fan of trimesh's 650 x 650 UV sphere, one face apart: they
    # share the pole, and their other corners lie in one plane z = const. With a third face
    # making the bounding box the sphere's, the old test (snapping at 1e-10 of the diagonal)
    # found them coplanar and overlapping; exactly, they meet at the pole only.
    h = float.fromhex
    ring_z = h("-0x1.fffe76e04aee7p-1")
    v = np.array(
        [
            [0.0, 0.0, -1.0],
            [h("0x1.3d3c97be6251dp-8"), 0.0, ring_z],
            [h("0x1.3d3ba4e97276fp-8"), h("0x1.88844a1fb5f88p-16"), ring_z],
            [h("0x1.3d38cc6c16a7bp-8"), h("0x1.88831dab12e11p-15"), ring_z],
            [h("0x1.3d340e4aaa266p-8"), h("0x1.2660deaf68481p-14"), ring_z],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
        ]
    )
    faces = [[1, 0, 2], [3, 0, 4], [5, 6, 7]]
    assert self_intersecting_pairs(v, faces).tolist() == []
    assert exact_cross(v[faces[0]], v[faces[1]]) is False


def test_duplicate_faces_and_index_errors() -> None:
    v = np.array(A + [[0.0, 0.0, 1.0]])
    # the same three vertices (either winding) is a duplicate, reported apart
    assert face_pairs_cross(v, [[0, 1, 2], [2, 1, 0]], [[0, 1]]).tolist() == [False]
    # the same positions under other indices overlap with positive area
    v2 = np.vstack([v, A])
    assert face_pairs_cross(v2, [[0, 1, 2], [4, 5, 6]], [[0, 1]]).tolist() == [True]
    with pytest.raises(ValueError, match=r"pair 0 has face index 2 out of range \[0, 2\)"):
        face_pairs_cross(v, [[0, 1, 2], [0, 1, 3]], [[0, 2]])
    with pytest.raises(ValueError, match=r"face 1 has vertex index 9 out of range \[0, 4\)"):
        face_pairs_cross(v, [[0, 1, 2], [0, 1, 9]], [[0, 1]])
    with pytest.raises(ValueError, match=r"pairs must be \(k, 2\), got \(3,\)"):
        face_pairs_cross(v, [[0, 1, 2]], [0, 1, 2])
    assert face_pairs_cross(v, [[0, 1, 2]], np.zeros((0, 2), int)).shape == (0,)
    v[3, 0] = np.nan
    with pytest.raises(ValueError, match="vertices contain NaN or infinite coordinates"):
        face_pairs_cross(v, [[0, 1, 2], [0, 1, 3]], [[0, 1]])


def test_fine_uv_sphere_does_not_self_intersect() -> None:
    # trimesh's 650 x 650 UV sphere (1,684,800 faces): the old test reported 2,600 crossing
    # pairs in its pole fans.
    import trimesh

    sphere = trimesh.creation.uv_sphere(radius=1.0, count=[650, 650])
    assert self_intersecting_pairs(sphere.vertices, sphere.faces).shape == (0, 2)


def test_vertex_pushed_through_a_uv_sphere_crosses_the_far_side() -> None:
    import trimesh

    sphere = trimesh.creation.uv_sphere(radius=1.0, count=[60, 60])
    assert len(self_intersecting_pairs(sphere.vertices, sphere.faces)) == 0
    vertices = np.array(sphere.vertices)
    top = int(np.argmax(vertices[:, 2]))
    vertices[top] = [0.0, 0.0, -1.5]  # the north pole pulled out through the south pole
    pairs = self_intersecting_pairs(vertices, sphere.faces)
    moved = (sphere.faces == top).any(axis=1)
    assert len(pairs) > 0 and moved[pairs].any(axis=1).all()


# ------------------------------------------------------------------------------ properties

# Snapped coordinates (small integers) make coplanar, collinear, shared and touching
# configurations common; dyadic offsets keep them exact.
GRID = st.integers(-2, 2).map(float)
FLOAT = st.floats(-2.0, 2.0, allow_nan=False, allow_infinity=False)
TINY = st.sampled_from([0.0, 1e-12, -1e-12, 2.0**-45, -(2.0**-52), 1e-15, 3e-13])


def _triangle(coordinate):
    point = st.tuples(coordinate, coordinate, coordinate)
    return st.tuples(point, point, point).map(lambda t: [list(p) for p in t])


@st.composite
def triangle_pairs(draw):
    kind = draw(
        st.sampled_from(
            ["float", "grid", "shared-vertex", "shared-edge", "coplanar", "near", "scaled"]
        )
    )
    coordinate = draw(st.sampled_from([GRID, FLOAT]))
    a = draw(_triangle(coordinate))
    b = draw(_triangle(coordinate))
    if kind == "float":
        a, b = draw(_triangle(FLOAT)), draw(_triangle(FLOAT))
    elif kind == "grid":
        a, b = draw(_triangle(GRID)), draw(_triangle(GRID))
    elif kind == "shared-vertex":
        b[draw(st.integers(0, 2))] = list(a[draw(st.integers(0, 2))])
    elif kind == "shared-edge":
        i = draw(st.integers(0, 2))
        first, second = list(a[i]), list(a[(i + 1) % 3])
        b = [first, second, b[2]] if draw(st.booleans()) else [second, first, b[2]]
    elif kind == "coplanar":
        # points of the plane z = alpha x + beta y + gamma (dyadic: exactly representable)
        alpha, beta, gamma = (draw(st.integers(-4, 4)) / 4 for _ in range(3))
        xy = st.tuples(GRID, GRID)
        a = [[x, y, alpha * x + beta * y + gamma] for x, y in (draw(xy) for _ in range(3))]
        b = [[x, y, alpha * x + beta * y + gamma] for x, y in (draw(xy) for _ in range(3))]
    if kind in ("near", "coplanar", "grid", "shared-vertex", "shared-edge"):
        # nudge some coordinates by amounts at or below the old snapping tolerance
        for t in (a, b):
            for p in t:
                p[2] += draw(TINY)
    if kind == "scaled":
        scale = 2.0 ** draw(st.integers(-20, 20))
        offset = draw(st.sampled_from([0.0, 1000.0, -3.5e6]))
        a = [[x * scale + offset for x in p] for p in a]
        b = [[x * scale + offset for x in p] for p in b]
    return a, b


@given(triangle_pairs())
def test_native_verdict_equals_the_exact_oracle(pair) -> None:
    a, b = pair
    expected = exact_cross(a, b)
    assert native_cross(a, b) is expected
    assert native_cross(b, a) is expected
    # a cyclic relabelling and a reversal of either triangle change nothing
    assert native_cross(a[1:] + a[:1], b[::-1]) is expected


@pytest.mark.slow
def test_batch_equals_the_oracle_on_a_random_soup() -> None:
    rng = np.random.default_rng(7)
    # 70 faces on 40 grid points: many shared vertices, edges, coplanar and touching pairs
    points = rng.integers(-2, 3, size=(40, 3)).astype(float)
    faces = rng.integers(0, 40, size=(70, 3))
    i, j = np.triu_indices(len(faces), 1)
    pairs = np.stack([i, j], axis=1)
    verdict = face_pairs_cross(points, faces, pairs)
    shared3 = [sorted(faces[p].tolist()) == sorted(faces[q].tolist()) for p, q in pairs]
    expected = [
        not dup and exact_cross(points[faces[p]], points[faces[q]])
        for (p, q), dup in zip(pairs.tolist(), shared3)
    ]
    assert verdict.tolist() == expected
    assert 0 < sum(expected) < len(expected)
    # self_intersecting_pairs (broad phase + this) finds exactly the crossing pairs
    assert self_intersecting_pairs(points, faces).tolist() == pairs[verdict].tolist()
