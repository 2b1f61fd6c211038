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


# ------------------------------------------------------------------------------ streamed pass
#
# self_intersections streams the sweep's candidates into the exact test, with shortcuts for
# faces that share vertex indices and a work budget. Its oracle is the two-step pass it
# replaced: every candidate pair collected by sort_and_sweep, then face_pairs_cross (the plain
# triangles_cross on every pair, no shortcut).


def two_step(vertices, faces) -> tuple[np.ndarray, int]:
    """The crossing pairs and the candidate count, as inspect found them before the stream."""
    from meshcol.collision.broadphase import sort_and_sweep

    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    candidates = sort_and_sweep(np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c))
    return candidates[face_pairs_cross(v, f, candidates)], len(candidates)


def assert_streamed_equals_two_step(vertices, faces) -> int:
    expected, candidates = two_step(vertices, faces)
    for threads in (1, 2):
        for block_pairs in (1, 7, 65536):
            found = core_pass(vertices, faces, threads=threads, block_pairs=block_pairs)
            assert found.complete and found.crossing is (len(expected) > 0)
            assert found.candidates == candidates
            assert found.count == len(expected)
            assert found.pairs.tolist() == expected.tolist()
    return len(expected)


def core_pass(vertices, faces, *, threads=0, block_pairs=65536, max_work=-1, keep=-1):
    """self_intersections with the core's block size and cost weights exposed."""
    from meshcol._native import core
    from meshcol.collision.self_intersection import SelfIntersections

    pairs, count, candidates, work, complete = core.self_intersecting_pairs(
        np.ascontiguousarray(vertices, float),
        np.ascontiguousarray(faces, np.int64),
        max_work=max_work,
        max_kept_pairs=keep,
        block_pairs=block_pairs,
        threads=threads,
    )
    return SelfIntersections(pairs, count, candidates, work, complete)


def fan(sections: int, *, overlap: bool = False, rotate: bool = False):
    """A flat fan of triangles around vertex 0 (a cylinder cap); with ``overlap`` every
    triangle spans two sectors, so neighbours overlap; rotated off the axes on request."""
    angles = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    rim = np.stack([np.cos(angles), np.sin(angles), np.full(sections, 0.5)], axis=1)
    vertices = np.vstack([[0.0, 0.0, 0.5], rim])
    step = 2 if overlap else 1
    faces = [[0, 1 + i, 1 + (i + step) % sections] for i in range(sections)]
    if rotate:
        c, s = np.cos(0.7), np.sin(0.7)
        turn = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.array(
            [[c, 0, s], [0, 1, 0], [-s, 0, c]]
        )
        vertices = vertices @ turn.T
    return vertices, np.asarray(faces, np.int64)


def pile(count: int, seed: int = 0):
    """Long thin triangles (d, -d, e) through the origin: every pair's boxes overlap, and
    d, -d of two faces are exactly coplanar (exact zeros)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    e = 0.01 * rng.normal(size=(count, 3))
    return np.stack([d, -d, e], axis=1).reshape(-1, 3), np.arange(3 * count).reshape(count, 3)


def test_streamed_pass_equals_two_step_on_fans_and_piles() -> None:
    assert assert_streamed_equals_two_step(*fan(300)) == 0
    assert assert_streamed_equals_two_step(*fan(300, rotate=True)) == 0
    # each triangle spans two sectors: it overlaps its neighbours on both sides
    assert assert_streamed_equals_two_step(*fan(300, overlap=True)) == 300
    # rotated, the rounded rim leaves the plane by ulps: overlapping neighbours cross only
    # where one's far corners straddle the other's plane
    assert 0 < assert_streamed_equals_two_step(*fan(300, overlap=True, rotate=True)) <= 300
    assert assert_streamed_equals_two_step(*pile(200)) > 1000


def test_streamed_pass_equals_two_step_on_closed_and_crossing_meshes() -> None:
    import trimesh

    sphere = trimesh.creation.uv_sphere(radius=1.0, count=[24, 24])
    assert assert_streamed_equals_two_step(sphere.vertices, sphere.faces) == 0
    cylinder = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=256)
    assert assert_streamed_equals_two_step(cylinder.vertices, cylinder.faces) == 0
    # two boxes through each other (crossing), and two touching at a corner (not crossing)
    box = trimesh.creation.box()
    for shift, crossing in (((0.5, 0.5, 0.5), True), ((1.0, 1.0, 1.0), False)):
        vertices = np.vstack([box.vertices, box.vertices + shift])
        faces = np.vstack([box.faces, box.faces + len(box.vertices)])
        assert (assert_streamed_equals_two_step(vertices, faces) > 0) is crossing


@pytest.mark.parametrize(
    "seed", [0, 1, *(pytest.param(seed, marks=pytest.mark.slow) for seed in range(2, 6))]
)
def test_streamed_pass_equals_two_step_on_random_soups(seed: int) -> None:
    rng = np.random.default_rng(seed)
    # grid points: shared vertices and edges, coplanar, collinear and touching faces
    points = rng.integers(-2, 3, size=(40, 3)).astype(float)
    if seed % 2:
        points += rng.normal(scale=1e-13, size=points.shape) * (rng.random(points.shape) < 0.3)
    faces = rng.integers(0, 40, size=(300, 3))
    assert_streamed_equals_two_step(points, faces)


@st.composite
def small_meshes(draw):
    """A few faces on a few points: grid, coplanar (dyadic plane) or float coordinates, so
    that faces share vertex indices, edges and planes, and touch."""
    count = draw(st.integers(3, 9))
    kind = draw(st.sampled_from(["grid", "plane", "float"]))
    if kind == "plane":
        alpha, beta = (draw(st.integers(-4, 4)) / 4 for _ in range(2))
        xy = [draw(st.tuples(GRID, GRID)) for _ in range(count)]
        points = [[x, y, alpha * x + beta * y] for x, y in xy]
    else:
        coordinate = GRID if kind == "grid" else FLOAT
        points = [list(draw(st.tuples(coordinate, coordinate, coordinate))) for _ in range(count)]
    index = st.integers(0, count - 1)
    faces = draw(st.lists(st.tuples(index, index, index), min_size=2, max_size=12))
    return np.asarray(points, float), np.asarray(faces, np.int64)


@given(small_meshes())
def test_streamed_pass_equals_two_step_on_generated_meshes(mesh) -> None:
    assert_streamed_equals_two_step(*mesh)


@given(triangle_pairs())
def test_shared_vertex_shortcuts_equal_the_exact_oracle(pair) -> None:
    # the same points merged into shared vertex indices: the shortcuts decide such pairs
    a, b = pair
    points, faces = np.unique(np.asarray(a + b, float), axis=0, return_inverse=True)
    faces = faces.reshape(2, 3)
    duplicate = sorted(faces[0].tolist()) == sorted(faces[1].tolist())
    found = core_pass(points, faces)
    assert found.complete
    assert (found.count == 1) is (not duplicate and exact_cross(a, b))


def test_budget_stops_deterministically_at_whole_blocks() -> None:
    vertices, faces = fan(400, overlap=True)
    full = core_pass(vertices, faces, block_pairs=64)
    assert full.complete and full.count == 400
    # the budget is the whole work: complete; one unit less: not
    assert core_pass(vertices, faces, block_pairs=64, max_work=full.work).complete
    short = core_pass(vertices, faces, block_pairs=64, max_work=full.work - 1)
    assert not short.complete and short.work <= full.work - 1
    for budget in (0, 500, 5_000, full.work // 3):
        runs = [
            core_pass(vertices, faces, block_pairs=64, max_work=budget, threads=t)
            for t in (1, 2, 2)
        ]
        first = runs[0]
        assert not first.complete and first.work <= budget and first.candidates < full.candidates
        for other in runs[1:]:  # the same on any thread, every time
            assert (other.count, other.candidates, other.work) == (
                first.count,
                first.candidates,
                first.work,
            )
            assert other.pairs.tolist() == first.pairs.tolist()
        # a lower bound: the pairs found are crossing pairs of the full answer
        assert first.count <= full.count
        assert set(map(tuple, first.pairs.tolist())) <= set(map(tuple, full.pairs.tolist()))
        assert first.crossing is (True if first.count else None)


def test_kept_pairs_are_capped_but_not_their_count() -> None:
    vertices, faces = pile(120)
    full = core_pass(vertices, faces)
    capped = core_pass(vertices, faces, keep=25)
    assert full.complete and capped.complete and capped.count == full.count > 25
    assert len(capped.pairs) == 25
    assert set(map(tuple, capped.pairs.tolist())) <= set(map(tuple, full.pairs.tolist()))
    assert capped.pairs.tolist() == sorted(capped.pairs.tolist())


def test_self_intersections_skips_faces_and_maps_indices_back() -> None:
    from meshcol.collision.self_intersection import self_intersections

    vertices, faces = fan(40, overlap=True)
    skip = np.zeros(len(faces), bool)
    skip[::2] = True
    found = self_intersections(vertices, faces, skip)
    expected, _ = two_step(vertices, faces)
    keep = [p for p in expected.tolist() if not skip[p[0]] and not skip[p[1]]]
    assert found.complete and found.pairs.tolist() == keep and found.count == len(keep)
    undecided = self_intersections(vertices, faces, skip, max_work=0)
    assert not undecided.complete and undecided.count == 0 and undecided.crossing is None
