"""Convex hulls: exact answers, flat and degenerate input, budgets that still enclose."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from meshcol.collision.facet_distance import nearest_on_facets
from meshcol.collision.hull import HullResult, closest_points_on_triangles, convex_hull
from meshcol.errors import InvalidMeshError

CUBE = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def outside_distance(points: np.ndarray, hull_vertices: np.ndarray) -> float:
    """Largest distance by which a point lies outside the convex hull of ``hull_vertices``."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(hull_vertices)
    return float((points @ hull.equations[:, :3].T + hull.equations[:, 3]).max())


def assert_encloses(points: np.ndarray, result: HullResult, budget: int) -> None:
    scale = float(np.linalg.norm(np.ptp(points, axis=0)))
    assert len(result.vertices) <= budget
    assert outside_distance(points, result.vertices) <= 1e-9 * scale
    # faces wound outward: the divergence-theorem volume is the (positive) hull volume
    assert signed_volume(result.vertices, result.faces) == pytest.approx(result.volume, rel=1e-9)
    assert result.added_volume == pytest.approx(
        result.volume - result.exact_volume, abs=1e-12 * scale**3
    )
    assert result.added_volume >= 0.0
    assert result.max_distance >= 0.0


# ---------------------------------------------------------------------------------------
# known answers


def test_cube_hull_is_the_cube() -> None:
    result = convex_hull(CUBE)
    assert len(result.vertices) == 8 and len(result.faces) == 12
    assert result.volume == pytest.approx(1.0, abs=1e-12)
    assert result.area == pytest.approx(6.0, abs=1e-12)
    assert signed_volume(result.vertices, result.faces) == pytest.approx(1.0, abs=1e-12)
    assert not result.flat and not result.simplified
    assert result.added_volume_fraction is None  # no budget asked


def test_interior_points_are_not_hull_vertices() -> None:
    rng = np.random.default_rng(3)
    points = np.vstack([CUBE, rng.uniform(0.1, 0.9, size=(200, 3))])
    result = convex_hull(points)
    assert sorted(map(tuple, result.vertices)) == sorted(map(tuple, CUBE))


def test_budget_above_exact_count_returns_exact_hull() -> None:
    result = convex_hull(CUBE, max_vertices=8)
    assert len(result.vertices) == 8
    assert result.volume == pytest.approx(1.0)
    assert result.added_volume == 0.0 and result.added_volume_fraction == 0.0
    assert result.max_distance == 0.0


@pytest.mark.parametrize("budget", [4, 5, 6, 7])
def test_box_budget_distance_is_exact(budget: int) -> None:
    """For a box the distance to the exact hull has a closed form: |v - clip(v)|."""
    lo, hi = np.array([-1.0, 0.0, 2.0]), np.array([2.0, 0.5, 3.5])
    points = lo + CUBE * (hi - lo)
    result = convex_hull(points, max_vertices=budget)
    assert_encloses(points, result, budget)
    clipped = np.clip(result.vertices, lo, hi)
    expected = np.linalg.norm(result.vertices - clipped, axis=1).max()
    assert result.max_distance == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert result.max_distance > 0.0  # 8 corners cannot fit in fewer vertices
    assert result.added_volume_fraction == pytest.approx(result.volume / 2.25 - 1.0)


def test_tetrahedron_budget_four_is_exact() -> None:
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    result = convex_hull(tet, max_vertices=4)
    assert result.volume == pytest.approx(1 / 6)
    assert result.max_distance == 0.0


# ---------------------------------------------------------------------------------------
# flat and degenerate input


def test_coplanar_points_give_a_flat_polygon() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    result = convex_hull(square)
    assert result.flat
    assert result.volume == 0.0 and result.exact_volume == 0.0
    assert result.area == pytest.approx(1.0)
    assert len(result.vertices) == 4 and len(result.faces) == 2
    assert sorted(map(tuple, result.vertices)) == sorted(map(tuple, square[:4]))


def test_single_triangle_is_flat() -> None:
    result = convex_hull(np.array([[0, 0, 0], [2, 0, 0], [0, 2, 1]], float))
    assert result.flat and len(result.faces) == 1
    assert result.area == pytest.approx(0.5 * np.linalg.norm(np.cross([2, 0, 0], [0, 2, 1])))


def test_flat_budget_encloses_in_the_plane() -> None:
    angles = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    circle = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    rotation, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
    points = circle @ rotation.T + [3.0, -1.0, 2.0]
    result = convex_hull(points, max_vertices=8)
    assert result.flat and len(result.vertices) <= 8
    normal = rotation[:, 2]
    assert np.abs((result.vertices - [3.0, -1.0, 2.0]) @ normal).max() < 1e-12
    # every input point inside the polygon: in plane coordinates, left of every edge
    local = (points - [3.0, -1.0, 2.0]) @ rotation[:, :2]
    ring = (result.vertices - [3.0, -1.0, 2.0]) @ rotation[:, :2]
    edges = np.roll(ring, -1, axis=0) - ring
    cross = edges[:, 0][:, None] * (local[:, 1] - ring[:, 1][:, None]) - edges[:, 1][:, None] * (
        local[:, 0] - ring[:, 0][:, None]
    )
    orientation = np.sign(cross.sum())
    assert (cross * orientation >= -1e-12).all()
    # a circumscribed octagon of a unit circle reaches 1/cos(pi/8) at its corners
    assert 1 / np.cos(np.pi / 8) - 1 - 1e-9 <= result.max_distance < 0.5


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (np.zeros((0, 3)), "mesh has no vertices: there is no hull"),
        (np.ones((5, 3)), "all vertices coincide: there is no meaningful hull"),
        (
            np.outer(np.arange(5.0), [1, 2, 3]),
            "all vertices are collinear: there is no meaningful hull",
        ),
        (
            np.array([[0, 0, 0], [1, np.nan, 0], [0, 1, 0], [0, 0, 1]]),
            "vertices contain NaN or infinite coordinates",
        ),
        (
            np.array([[0, 0, 0], [1, np.inf, 0], [0, 1, 0], [0, 0, 1]]),
            "vertices contain NaN or infinite coordinates",
        ),
    ],
)
def test_unusable_points_raise(points: np.ndarray, message: str) -> None:
    with pytest.raises(InvalidMeshError) as info:
        convex_hull(points)
    assert str(info.value) == message


def test_bad_arguments_are_value_errors() -> None:
    with pytest.raises(ValueError, match=r"points must be \(n, 3\), got \(4, 2\)"):
        convex_hull(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="max_vertices must be >= 4, got 3"):
        convex_hull(CUBE, max_vertices=3)


# ---------------------------------------------------------------------------------------
# budgets: corpus meshes and random clouds


@pytest.fixture(scope="module")
def sphere_points() -> np.ndarray:
    rng = np.random.default_rng(11)
    v = rng.normal(size=(1500, 3))
    return v / np.linalg.norm(v, axis=1)[:, None] * 2.0 + [5.0, -3.0, 1.0]


@pytest.mark.parametrize("budget", [4, 8, 16, 32, 64, 255])
def test_budget_encloses_sphere_cloud(sphere_points: np.ndarray, budget: int) -> None:
    result = convex_hull(sphere_points, max_vertices=budget)
    assert result.exact_vertex_count > 255
    assert_encloses(sphere_points, result, budget)
    assert result.max_distance > 0.0
    # more vertices, tighter hull: a 255-vertex hull of a radius-2 sphere is within 5%
    if budget == 255:
        assert result.max_distance < 0.1
        assert result.added_volume_fraction < 0.05


def test_distance_is_bracketed_by_plane_and_vertex_distances(sphere_points: np.ndarray) -> None:
    from scipy.spatial import ConvexHull

    result = convex_hull(sphere_points, max_vertices=64)
    exact = ConvexHull(sphere_points)
    lower = (result.vertices @ exact.equations[:, :3].T + exact.equations[:, 3]).max(axis=1)
    corners = sphere_points[exact.vertices]
    upper = np.linalg.norm(result.vertices[:, None, :] - corners[None, :, :], axis=2).min(axis=1)
    assert lower.max() <= result.max_distance + 1e-12
    assert result.max_distance <= upper.max() + 1e-12


@pytest.mark.parametrize("name", ["unit_sphere.STL", "torus.STL", "fandisk.obj", "busted.STL"])
@pytest.mark.parametrize("budget", [4, 8, 16, 32, 64, 255])
def test_budget_encloses_corpus_meshes(corpus, name: str, budget: int) -> None:
    from meshcol.io.mesh_read import load_mesh

    (body,) = load_mesh(corpus / "trimesh-models" / name)
    points = body.world_vertices()
    result = convex_hull(points, max_vertices=budget)
    assert_encloses(points, result, budget)


@settings(max_examples=40)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(5, 60), st.just(3)),
        elements=st.floats(-100, 100, allow_nan=False, width=32),
    ),
    st.sampled_from([4, 5, 8, 16, 64]),
)
def test_budget_encloses_random_clouds(points: np.ndarray, budget: int) -> None:
    scale = float(np.linalg.norm(np.ptp(points, axis=0)))
    try:
        result = convex_hull(points, max_vertices=budget)
    except InvalidMeshError:
        return  # coincident or collinear: no hull (tested above)
    if result.flat:
        assert len(result.vertices) <= budget
        return
    assert_encloses(points, result, budget)
    assert result.max_distance <= scale


def test_closest_points_on_triangles_match_dense_sampling() -> None:
    rng = np.random.default_rng(2)
    triangles = rng.normal(size=(50, 3, 3))
    points = rng.normal(size=(50, 3)) * 2
    closest = closest_points_on_triangles(points, triangles)
    u, v = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    keep = u + v <= 1
    bary = np.stack([1 - u[keep] - v[keep], u[keep], v[keep]], axis=1)
    for p, tri, c in zip(points, triangles, closest):
        samples = bary @ tri
        best = np.linalg.norm(samples - p, axis=1).min()
        got = np.linalg.norm(c - p)
        assert got <= best + 1e-12  # never worse than any sample
        assert got >= best - 0.02 * np.ptp(tri, axis=0).max()  # and samples get close


def _numpy_facet_search(points, facets, in_front):
    """The budget loop's search as numpy code: every marked (point, facet) pair's closest
    point (:func:`closest_points_on_triangles`), the nearest per point, ties to the first."""
    return nearest_on_facets(points, facets, in_front, closest_points_on_triangles)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 12), st.integers(1, 60))
def test_core_facet_search_is_numpys_bit_for_bit(seed: int, count: int, facet_count: int) -> None:
    """``core.distances_to_facets`` (the budget loop's inner search) gives numpy's doubles:
    triangles in general position, degenerate ones (a repeated corner, collinear corners),
    points on corners and edges, shared corners (ties between facets)."""
    from meshcol._native import core

    rng = np.random.default_rng(seed)
    grid = rng.integers(-3, 4, size=(facet_count, 3, 3)).astype(float) / 2
    facets = np.where(rng.random((facet_count, 1, 1)) < 0.5, grid, rng.normal(size=grid.shape))
    facets[rng.random(facet_count) < 0.2, 2] = facets[0, 0]  # a corner shared with facet 0
    repeated = rng.random(facet_count) < 0.1
    facets[repeated, 1] = facets[repeated, 0]
    collinear = rng.random(facet_count) < 0.1
    facets[collinear, 2] = 2 * facets[collinear, 1] - facets[collinear, 0]
    points = rng.normal(size=(count, 3)) * rng.choice([1e-3, 1.0, 1e3], size=(count, 1))
    on = rng.random(count) < 0.3
    points[on] = facets[rng.integers(0, facet_count, on.sum()), 0]
    in_front = rng.random((count, facet_count)) < 0.7
    distances, closest = core.distances_to_facets(points, np.ascontiguousarray(facets), in_front)
    expected_distances, expected_closest = _numpy_facet_search(points, facets, in_front)
    np.testing.assert_array_equal(distances, expected_distances)
    np.testing.assert_array_equal(closest, expected_closest)
