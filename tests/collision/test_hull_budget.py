"""The budgeted hull's loop in the core (meshcol/collision/hull_budget.py): its clip against
qhull's half-space intersection, its hulls against the numpy loop and exact oracles."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol._native import core
from meshcol.collision.hull import (
    convex_hull,
    exact_hull,
    hull_within_budget,
    hulls_within_budgets,
)
from meshcol.collision.hull_budget import (
    CONTAINS_RELATIVE_DISTANCE,
    CONVERGED_RELATIVE_DISTANCE,
    CUT_CANDIDATES,
    MERGE_RELATIVE_DISTANCE,
    _checked_polytope,
    _intersect,
    _merge_close,
    _simplify,
    _simplify_qhull,
    _start_simplex,
    simplify_many,
)
from meshcol.errors import InvalidMeshError
from meshcol.geometry.triangles import closest_points_on_triangles

# ---------------------------------------------------------------------------------------
# the clip against qhull


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _qhull_vertices(planes: np.ndarray, radius: float) -> np.ndarray:
    """The vertices of {x : n . x <= offset} by scipy's qhull (the origin inside), merged."""
    from scipy.spatial import HalfspaceIntersection

    halfspaces = np.hstack([planes[:, :3], -planes[:, 3:]])
    return _merge_close(HalfspaceIntersection(halfspaces, np.zeros(3)).intersections, radius)


def _random_planes(seed: int, count: int, kinds: list[str]) -> np.ndarray:
    """A tetrahedron about the origin and ``count`` more planes, each of a kind: random,
    through a vertex of the polytope so far (cutting), a repeat of a plane, a parallel plane
    1e-12 out, or a cut 1e-12 deep at a vertex."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    base = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) / np.sqrt(3)
    normals = base @ (q * np.sign(np.diag(r))).T
    planes = np.hstack([normals, rng.uniform(1.0, 3.0, size=(4, 1))])
    for k in range(count):
        kind = kinds[k % len(kinds)]
        vertices = _qhull_vertices(planes, 0.0)
        if kind == "random":
            row = np.append(_unit(rng.normal(size=3)), rng.uniform(0.3, 2.0))
        elif kind == "repeat":
            row = planes[rng.integers(len(planes))].copy()
        elif kind == "parallel":
            row = planes[rng.integers(len(planes))] + [0, 0, 0, 1e-12]
        else:  # through a vertex, or 1e-12 inside it
            v = vertices[rng.integers(len(vertices))]
            n = _unit(v + 0.5 * np.linalg.norm(v) * _unit(rng.normal(size=3)))
            depth = 1e-12 if kind == "shallow" else 0.0
            row = np.append(n, n @ v - depth)
        if row[3] <= 0.05:  # keep the origin well inside
            continue
        planes = np.vstack([planes, row])
    return planes


def _assert_same_points(a: np.ndarray, b: np.ndarray, tolerance: float) -> None:
    assert len(a) == len(b)
    gaps = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    assert gaps.min(axis=1).max() <= tolerance
    assert gaps.min(axis=0).max() <= tolerance


@settings(max_examples=200, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(0, 40),
    st.lists(
        st.sampled_from(["random", "vertex", "repeat", "parallel", "shallow"]),
        min_size=1,
        max_size=5,
    ),
)
def test_clip_is_qhulls_intersection(seed: int, count: int, kinds: list[str]) -> None:
    planes = _random_planes(seed, count, kinds)
    scale = 10.0  # the tetrahedron's offsets are at most 3: a diagonal below 10
    radius = MERGE_RELATIVE_DISTANCE * scale
    ok, vertices = core.clip_planes(planes, radius)
    assert ok
    expected = _qhull_vertices(planes, radius)
    # the same polytope to 1e-9 of the scale: after a cut a rounding error deep, vertices a
    # little farther apart than the merge radius are one vertex in one and two in the other
    # (qhull's own intersections of nearly coincident planes move by more than the radius)
    coarse = 1e-9 * scale
    _assert_same_points(_merge_close(vertices, coarse), _merge_close(expected, coarse), coarse)
    if "shallow" not in kinds and "vertex" not in kinds:
        assert len(vertices) == len(expected)
    # and every vertex is inside every plane (to rounding) and on three of them at least
    signed = vertices @ planes[:, :3].T - planes[:, 3]
    assert signed.max() <= 1e-12 * scale
    assert ((np.abs(signed) <= 1e-9 * scale).sum(axis=1) >= 3).all()


def test_clip_of_a_cube_by_its_corner_planes_is_a_truncated_cube() -> None:
    k = 1 / np.sqrt(3)
    tetrahedron = np.array(
        [[k, k, k, 30 * k], [k, -k, -k, 30 * k], [-k, k, -k, 30 * k], [-k, -k, k, 30 * k]]
    )
    cube = np.array([[s * (i == a) for i in range(3)] + [1.0] for a in range(3) for s in (1, -1)])
    corners = np.array([[x, y, z] for x in (1, -1) for y in (1, -1) for z in (1, -1)], float)
    cuts = np.hstack([corners * k, np.full((8, 1), 3 * k - 0.5)])  # 0.5 below each corner
    ok, vertices = core.clip_planes(np.vstack([tetrahedron, cube, cuts]), 1e-11)
    assert ok and len(vertices) == 24  # each corner a triangle
    assert np.abs(vertices).max() == pytest.approx(1.0, abs=1e-12)
    assert np.sort(np.abs(vertices), axis=1)[:, 1:] == pytest.approx(1.0, abs=1e-12)


def test_clip_reports_an_empty_polytope() -> None:
    k = 1 / np.sqrt(3)
    planes = np.array([[k, k, k, 1], [k, -k, -k, 1], [-k, k, -k, 1], [-k, -k, k, 1], [1, 0, 0, -5]])
    ok, vertices = core.clip_planes(planes, 1e-11)
    assert not ok and vertices.shape == (0, 3)


# ---------------------------------------------------------------------------------------
# the loop against the numpy loop and exact oracles


def _brute_distances(points: np.ndarray, exact) -> np.ndarray:
    """Exact distance from each point to the solid hull, over every facet (no pruning)."""
    triangles = exact.vertices[exact.faces]
    inside = (points @ exact.equations[:, :3].T + exact.equations[:, 3]).max(axis=1) <= 0
    out = np.empty(len(points))
    for i, p in enumerate(points):
        closest = closest_points_on_triangles(np.broadcast_to(p, (len(triangles), 3)), triangles)
        out[i] = np.sqrt(((closest - p) ** 2).sum(axis=1).min())
    out[inside] = 0.0
    return out


def _cloud(seed: int, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, 3)) * rng.uniform(0.1, 3.0, size=3) + rng.uniform(-50, 50, size=3)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("budget", [4, 7, 16, 40])
def test_budget_hull_encloses_and_reports_the_exact_distance(seed: int, budget: int) -> None:
    from scipy.spatial import ConvexHull

    points = _cloud(seed, 300)
    result = convex_hull(points, max_vertices=budget)
    exact = exact_hull(points)
    assert len(result.vertices) <= budget
    hull = ConvexHull(result.vertices)
    assert (points @ hull.equations[:, :3].T + hull.equations[:, 3]).max() <= 1e-12 * exact.diagonal
    expected = _brute_distances(result.vertices, exact).max()
    assert result.max_distance == pytest.approx(expected, rel=1e-12, abs=1e-15 * exact.diagonal)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("budget", [5, 12])
def test_core_loop_picks_the_numpy_loops_planes(seed: int, budget: int, monkeypatch) -> None:
    # random clouds have no ties between vertex distances: both loops make the same cuts,
    # so their polytopes differ by rounding only. (Longer loops, that go on cutting at the
    # budget, meet planes through vertices that the clip and qhull count differently by a
    # vertex now and then, and go separate ways from there: RESULTS.md gives how often.)
    exact = exact_hull(_cloud(100 + seed, 400))
    args = (exact.vertices, exact.vertices[exact.faces], exact.equations, budget, exact.diagonal)
    fallbacks = _count_fallbacks(monkeypatch)
    vertices, distance = _simplify(*args)
    assert not fallbacks  # the core's loop answered: a fallback would compare qhull's to itself
    reference, reference_distance = _simplify_qhull(*args)
    _assert_same_points(vertices, reference, 1e-9 * exact.diagonal)
    assert distance == pytest.approx(reference_distance, rel=1e-9)


def _count_fallbacks(monkeypatch) -> list:
    """The calls of the numpy loop made from now on (the core's fallback), recorded."""
    import meshcol.collision.hull_budget as hull_budget

    calls: list = []
    numpy_loop = hull_budget._simplify_qhull

    def counted(*args, **kwargs):
        calls.append(args)
        return numpy_loop(*args, **kwargs)

    monkeypatch.setattr(hull_budget, "_simplify_qhull", counted)
    return calls


@pytest.mark.parametrize("max_planes", [4, 6, 11, 20])
def test_plane_budget_is_kept(max_planes: int, monkeypatch) -> None:
    exact = exact_hull(_cloud(7, 500))
    result = hull_within_budget(exact, 64, max_planes)
    normals = np.round(exact_hull(result.vertices).equations[:, :3], 9)
    assert len(np.unique(normals, axis=0)) <= max_planes
    args = (exact.vertices, exact.vertices[exact.faces], exact.equations, 64, exact.diagonal)
    fallbacks = _count_fallbacks(monkeypatch)
    vertices, _ = _simplify(*args, max_planes=max_planes)
    assert not fallbacks
    reference, _ = _simplify_qhull(*args, max_planes=max_planes)
    _assert_same_points(vertices, reference, 1e-9 * exact.diagonal)


def test_batch_on_threads_is_the_loop_of_singles() -> None:
    exacts = [exact_hull(_cloud(200 + i, 50 + 40 * i)) for i in range(12)]
    bodies = [(e.vertices, e.vertices[e.faces], e.equations, 9, e.diagonal, None) for e in exacts]
    singles = [simplify_many([body], threads=1)[0] for body in bodies]
    for threads in (1, 2, 0):
        batch = simplify_many(bodies, threads=threads)
        for (v, d), (v1, d1) in zip(batch, singles):
            assert v.tobytes() == v1.tobytes() and d == d1
    results = hulls_within_budgets(exacts, [(9, None)] * len(exacts), threads=2)
    for result, exact in zip(results, exacts):
        single = hull_within_budget(exact, 9)
        assert result.vertices.tobytes() == single.vertices.tobytes()
        assert result.max_distance == single.max_distance


def test_many_keeps_flat_and_small_hulls_as_single_calls_do() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.2, 0]], float)
    exacts = [exact_hull(square), exact_hull(_cloud(1, 6)), exact_hull(_cloud(2, 100))]
    results = hulls_within_budgets(exacts, [(4, None)] * len(exacts))
    # independent of the single call the batch uses for these: the square stays flat, four
    # of its corners; the 6-point cloud and the 100-point cloud are cut to 4 vertices
    assert results[0].flat and len(results[0].vertices) == 4
    assert all(len(r.vertices) <= 4 for r in results)
    for result, exact in zip(results, exacts):
        single = hull_within_budget(exact, 4)
        assert result.vertices.tobytes() == single.vertices.tobytes()
        assert result.flat == single.flat and result.max_distance == single.max_distance


def test_many_with_their_own_budgets_are_the_singles_and_keep_their_errors() -> None:
    line = np.outer(np.linspace(0, 1, 5), [1.0, 2.0, 3.0])
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.2, 0]], float)
    exacts = [exact_hull(_cloud(10 + i, 40 + 30 * i)) for i in range(6)]
    exacts += [exact_hull(line), exact_hull(square)]
    budgets = [(9, None), (None, 12), (20, 8), (4, 4), (None, None), (200, 300)]
    budgets += [(9, None), (4, None)]
    for made, exact, (vertices, planes) in zip(
        hulls_within_budgets(exacts, budgets), exacts, budgets, strict=True
    ):
        if exact.dimension == 1:
            assert isinstance(made, InvalidMeshError)
            with pytest.raises(InvalidMeshError, match=re.escape(made.message)):
                hull_within_budget(exact, vertices, planes)
            continue
        single = hull_within_budget(exact, vertices, planes)
        assert made.vertices.tobytes() == single.vertices.tobytes()
        assert made.faces.tobytes() == single.faces.tobytes()
        assert (made.volume, made.max_distance, made.added_volume, made.max_vertices) == (
            single.volume,
            single.max_distance,
            single.added_volume,
            single.max_vertices,
        )
    with pytest.raises(ValueError, match="max_planes must be >= 4"):
        hulls_within_budgets(exacts[:1], [(9, 3)])


# ---------------------------------------------------------------------------------------
# the core's own polytope: where qhull's intersection of its planes breaks the budget

DATA = Path(__file__).resolve().parent.parent / "data"


def _core_loop(exact, budget: int, max_planes: int | None):
    """The core's loop on one exact hull: its planes (P, 4), its polytope (V, 3), status."""
    v = exact.vertices
    normals = _start_simplex(v)
    start = np.hstack([normals, (normals @ v.T).max(axis=1)[:, None]])
    planes, _, corners, _, status = core.budget_hull_planes(
        v,
        np.array([0, len(v)]),
        v[exact.faces],
        exact.equations,
        np.array([0, len(exact.faces)]),
        start,
        np.array([budget]),
        np.array([-1 if max_planes is None else max_planes]),
        np.array([CONVERGED_RELATIVE_DISTANCE * exact.diagonal]),
        np.array([MERGE_RELATIVE_DISTANCE * exact.diagonal]),
        CUT_CANDIDATES,
        1,
    )
    return planes, corners, int(status[0])


def _assert_hull_of_own_vertices(corners, planes, points, budget, scale) -> None:
    """``corners`` is a convex polytope within ``budget`` that contains ``points``, each face
    of scipy's hull of it on one of ``planes`` (the polytope is their intersection)."""
    from scipy.spatial import ConvexHull

    assert 4 <= len(corners) <= budget
    hull = ConvexHull(corners)
    assert len(hull.vertices) == len(corners)  # every vertex extreme: convex position
    tolerance = CONTAINS_RELATIVE_DISTANCE * scale
    assert (points @ hull.equations[:, :3].T + hull.equations[:, 3]).max() <= tolerance
    assert (corners @ planes[:, :3].T - planes[:, 3]).max() <= tolerance
    # a face's plane n . x + c = 0 is a plane of the loop (n, offset = -c)
    gaps = np.abs(hull.equations[:, None, :3] - planes[None, :, :3]).sum(axis=2)
    gaps += np.abs(hull.equations[:, None, 3] + planes[None, :, 3]) / scale
    assert gaps.min(axis=1).max() <= 1e-6


def test_a_plane_through_an_edge_keeps_the_cores_polytope(monkeypatch) -> None:
    # one of the 116 props of the 10,000-prop scale scene under --target isaac that fell back
    # to the numpy loop: a cut plane through an edge meets its two planes in one line, and
    # qhull's intersection of the planes has a 65th point, on that edge
    data = json.loads((DATA / "hull_budget_edge_plane.json").read_text())
    points = np.array(data["points"])
    budget, max_planes = data["max_vertices"], data["max_planes"]
    exact = exact_hull(points)
    planes, corners, status = _core_loop(exact, budget, max_planes)
    assert status == 0
    qhull = _intersect(planes[:, :3], planes[:, 3], points.mean(axis=0), exact.diagonal)
    assert len(qhull) > budget
    _assert_hull_of_own_vertices(corners, planes, points, budget, exact.diagonal)
    # qhull's point that is not a vertex: on three planes through one line, refused
    gaps = np.linalg.norm(qhull[:, None] - corners[None], axis=2).min(axis=1)
    extra = qhull[np.argmax(gaps)]
    assert gaps.max() > 1e-3 * exact.diagonal
    assert _checked_polytope(corners, planes, budget, exact.diagonal) is not None
    assert _checked_polytope(np.vstack([corners, extra]), planes, 99, exact.diagonal) is None
    fallbacks = _count_fallbacks(monkeypatch)
    result = hull_within_budget(exact, budget, max_planes)
    assert not fallbacks
    assert sorted(map(tuple, result.vertices)) == sorted(map(tuple, corners))
    expected = _brute_distances(result.vertices, exact).max()
    assert result.max_distance == pytest.approx(expected, rel=1e-12, abs=1e-15 * exact.diagonal)
    normals = np.round(exact_hull(result.vertices).equations[:, :3], 9)
    assert len(np.unique(normals, axis=0)) <= max_planes


def _ellipsoid_prop(seed: int) -> np.ndarray:
    """``bench_scale.convex_prop``'s points: 24-48 on an ellipsoid of semi-axes 0.4-0.8."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(int(rng.integers(24, 49)), 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return p * rng.uniform(0.4, 0.8, size=3)


@settings(max_examples=80, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from(["ellipsoid", "cloud"]),
    st.integers(4, 64),
    st.one_of(st.none(), st.integers(4, 64)),
)
def test_core_polytope_is_qhulls_hull_of_its_vertices(
    seed: int, kind: str, budget: int, max_planes: int | None
) -> None:
    points = _ellipsoid_prop(seed) if kind == "ellipsoid" else _cloud(seed, 60)
    exact = exact_hull(points)
    planes, corners, status = _core_loop(exact, budget, max_planes)
    assert status == 0
    if max_planes is not None:
        assert len(planes) <= max(max_planes, 4)
    _assert_hull_of_own_vertices(corners, planes, exact.vertices, budget, exact.diagonal)
    assert _checked_polytope(corners, planes, budget, exact.diagonal) is not None
