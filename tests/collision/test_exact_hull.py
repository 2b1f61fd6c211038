"""The exact hull (the core's Quickhull) and the packed convex set it produces in one pass.

Oracles: known answers (cubes with points on their edges and faces, polygons, segments),
qhull through scipy (the hull meshcol used before, and the reference for vertex sets) on the
corpus and on random clouds, and invariants (every point inside, vertices are input points,
outward convex faces, a closed surface of Euler characteristic 2).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial import ConvexHull

from meshcol import Status, distance_batch
from meshcol.collision.hull import (
    FLAT_RELATIVE_TOLERANCE,
    MAX_ABS_COORDINATE,
    HullStatus,
    convex_hull,
    exact_hull,
    pack_hulls,
)
from meshcol.collision.shapes import ConvexSet
from meshcol.errors import InvalidMeshError

CUBE = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])


def qhull_vertex_set(points: np.ndarray) -> set[tuple[float, ...]]:
    unique = np.unique(np.asarray(points, dtype=np.float64) + 0.0, axis=0)
    hull = ConvexHull(unique)
    return set(map(tuple, unique[hull.vertices]))


def cube_surface_grid(n: int) -> np.ndarray:
    """Every point of an n x n x n grid on the unit cube's surface: edges and faces are
    crowded with points that are on the hull but none of its vertices."""
    t = np.linspace(0.0, 1.0, n)
    g = np.stack(np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
    return g[((g == 0.0) | (g == 1.0)).any(axis=1)]


def assert_valid_hull(points: np.ndarray, tolerance: float) -> None:
    """The invariants of a 3-D exact hull of ``points``."""
    hull = exact_hull(points)
    assert hull.dimension == 3 and hull.status == HullStatus.OK
    v, f = hull.vertices, hull.faces
    # vertices are input points, each once, in lexicographic order
    assert (points[hull.indices] + 0.0 == v).all()
    assert len(np.unique(v, axis=0)) == len(v)
    assert (np.lexsort(v.T[::-1]) == np.arange(len(v))).all()
    # every input point inside every face plane (within the tolerance)
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert (points @ normals.T + offsets).max() <= tolerance
    # faces wound outward and their planes through their corners
    tri = v[f]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", cross, normals) > 0).all()
    assert np.abs(np.einsum("ijk,ik->ij", tri, normals) + offsets[:, None]).max() <= tolerance
    # a closed 2-manifold of genus 0: every edge in two faces, once each way; V - E + F = 2
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    undirected = np.unique(np.sort(directed, axis=1), axis=0)
    assert 2 * len(undirected) == len(directed)
    assert len(v) - len(undirected) + len(f) == 2
    # every vertex used, and the volume that of the faces
    assert set(f.ravel()) == set(range(len(v)))
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0
    assert signed == pytest.approx(hull.volume, rel=1e-9)


# ---------------------------------------------------------------------------------------
# known answers and degenerate input


def test_cube_with_points_on_its_edges_and_faces_has_eight_vertices() -> None:
    grid = cube_surface_grid(5)
    rng = np.random.default_rng(0)
    # sorted, shuffled, and the corners last: Quickhull meets coplanar ties in every order
    orders = [grid, rng.permutation(grid), np.vstack([grid[~np.isin(grid, CUBE).all(1)], CUBE])]
    for points in orders:
        hull = exact_hull(np.vstack([points, rng.uniform(0.1, 0.9, (50, 3))]))
        assert set(map(tuple, hull.vertices)) == set(map(tuple, CUBE))
        assert hull.volume == pytest.approx(1.0, abs=1e-12)
        assert hull.area == pytest.approx(6.0, abs=1e-12)
        assert len(hull.faces) == 12


def test_duplicates_do_not_change_the_hull() -> None:
    points = np.vstack([CUBE] * 5)[np.random.default_rng(1).permutation(40)]
    hull = exact_hull(points)
    assert (hull.vertices == CUBE).all()  # lexicographic order
    assert len(hull.faces) == 12 and hull.volume == pytest.approx(1.0, abs=1e-12)


def test_coplanar_points_give_a_ring_about_the_normal() -> None:
    t = np.linspace(-1.0, 1.0, 7)
    uv = np.stack(np.meshgrid(t, t), axis=-1).reshape(-1, 2)
    u, w = np.array([1.0, 2.0, 2.0]) / 3.0, np.array([2.0, -2.0, 1.0]) / 3.0
    points = 5.0 + uv[:, :1] * u + uv[:, 1:] * w
    hull = exact_hull(points)
    assert hull.status == HullStatus.FLAT and hull.dimension == 2
    assert len(hull.vertices) == 4  # the corners only: edge points are dropped
    assert hull.area == pytest.approx(4.0, rel=1e-12) and hull.volume == 0.0
    ring = hull.vertices
    turn = np.cross(ring[1] - ring[0], ring[2] - ring[1])
    assert turn @ hull.normal > 0  # counter-clockwise about the normal
    assert abs(hull.normal @ u) < 1e-12 and abs(hull.normal @ w) < 1e-12
    assert len(hull.faces) == 2


def test_collinear_and_single_point_input() -> None:
    line = np.outer(np.linspace(0.0, 1.0, 9), [1.0, 2.0, 3.0])[::-1]
    hull = exact_hull(line)
    assert hull.status == HullStatus.COLLINEAR and hull.dimension == 1
    assert set(map(tuple, hull.vertices)) == {(0.0, 0.0, 0.0), (1.0, 2.0, 3.0)}
    point = exact_hull(np.tile([[2.0, -0.0, 1.0]], (6, 1)))
    assert point.status == HullStatus.SINGLE_POINT and point.dimension == 0
    assert point.vertices.tolist() == [[2.0, 0.0, 1.0]]
    with pytest.raises(InvalidMeshError, match="collinear"):
        convex_hull(line)


def test_width_at_the_flatness_rule_decides_the_dimension() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    diagonal = np.sqrt(2.0)
    thin = np.vstack([square, [[0.5, 0.5, 0.5 * FLAT_RELATIVE_TOLERANCE * diagonal]]])
    thick = np.vstack([square, [[0.5, 0.5, 4.0 * FLAT_RELATIVE_TOLERANCE * diagonal]]])
    assert exact_hull(thin).dimension == 2
    assert exact_hull(thick).dimension == 3


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (np.zeros((0, 3)), "no vertices"),
        (np.array([[0, 0, 0], [1, np.nan, 0], [0, 1, 0], [0, 0, 1.0]]), "NaN or infinite"),
        (np.array([[0, 0, 0], [1, 0, -np.inf], [0, 1, 0], [0, 0, 1.0]]), "NaN or infinite"),
        (
            np.array([[1e308, 0, 0], [-1e308, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
            r"vertex coordinate 1e\+308 is beyond \+-1e\+100: hull volumes would overflow",
        ),
        (np.array([[0, 0, 0], [0, 0, -3e200], [0, 1, 0], [1, 0, 0.0]]), "-3e\\+200 is beyond"),
    ],
)
def test_points_without_a_hull_raise_one_line(points: np.ndarray, message: str) -> None:
    with pytest.raises(InvalidMeshError, match=message):
        exact_hull(points)
    with pytest.raises(InvalidMeshError, match=message):
        convex_hull(points)


def test_huge_and_tiny_coordinates_within_range_are_exact() -> None:
    # scaled by powers of ten (not exact in binary), the hull is still the cube's corners
    for scale in (1e-150, 1e-8, 1e8, 1e99):
        points = np.vstack([CUBE, cube_surface_grid(4), np.full((1, 3), 0.5)]) * scale
        hull = exact_hull(points)
        assert len(hull.vertices) == 8, scale
        assert hull.volume == pytest.approx(scale**3, rel=1e-12)
    assert exact_hull(CUBE * MAX_ABS_COORDINATE).dimension == 3


def test_far_from_the_origin() -> None:
    rng = np.random.default_rng(5)
    points = rng.normal(size=(300, 3)) + 1e6
    assert set(map(tuple, exact_hull(points).vertices)) == qhull_vertex_set(points)


# ---------------------------------------------------------------------------------------
# #13: +-1e308 hung in numpy's SVD; now one line, exit 2, at once


def test_convex_hull_of_1e308_points_returns_at_once() -> None:
    code = (
        "import numpy as np, meshcol\n"
        "from meshcol.errors import InvalidMeshError\n"
        "p = np.eye(3)[[0, 1, 2, 0]] + np.array([[1e308, 0, 0]] * 2 + [[-1e308, 0, 0]] * 2)\n"
        "try:\n"
        "    meshcol.convex_hull(p)\n"
        "except InvalidMeshError as e:\n"
        "    print(e)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert "1e+308 is beyond" in done.stdout


def test_meshcol_hull_on_bodies_at_1e308_exits_2(tmp_path: Path) -> None:
    tet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    (tmp_path / "tet.obj").write_text(tet)
    scene = tmp_path / "scene.json"
    bodies = [
        {"name": "a", "mesh": "tet.obj", "position": [1e308, 0, 0]},
        {"name": "b", "mesh": "tet.obj", "position": [-1e308, 0, 0]},
    ]
    scene.write_text(json.dumps({"bodies": bodies}))
    done = subprocess.run(
        [sys.executable, "-m", "meshcol", "hull", str(scene)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    # one line naming the manifest or mesh, the body and the value (the loader refuses such
    # positions; the hull refuses coordinates beyond 1e100 for library callers)
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("meshcol: error: "), done.stderr
    assert "'a'" in lines[0] and "1e+308" in lines[0], lines[0]


# ---------------------------------------------------------------------------------------
# the packed set


def test_packed_cube_adjacency_faces_and_edges() -> None:
    cs = ConvexSet.from_vertices([np.vstack([cube_surface_grid(3), [[0.5, 0.5, 0.5]]])])
    assert (cs.vertices == CUBE).all()
    assert cs.hull_status.tolist() == [HullStatus.OK]
    normals = {tuple(n) for n in np.round(cs.face_normals, 12) + 0.0}
    assert normals == {tuple(s * e) for e in np.eye(3) for s in (1.0, -1.0)}
    assert sorted(map(tuple, np.abs(cs.edge_directions))) == [(0, 0, 1), (0, 1, 0), (1, 0, 0)]
    # neighbours of each corner in the triangulation: ascending, padded with itself to 4k
    tri = exact_hull(CUBE).faces
    for i in range(8):
        lst = cs.adjacency[cs.adjacency_offsets[i] : cs.adjacency_offsets[i + 1]]
        expected = sorted({int(j) for t in tri if i in t for j in t if j != i})
        assert len(lst) % 4 == 0
        assert lst[: len(expected)].tolist() == expected
        assert (lst[len(expected) :] == i).all()


def test_packed_degenerate_shapes_and_statuses() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    segment = np.array([[0, 0, 0], [0.5, 0.5, 0.5], [2, 2, 2]], float)
    point = np.ones((3, 3))
    nan = CUBE.copy()
    nan[2, 1] = np.nan
    huge = CUBE * 1e200
    cs = ConvexSet.from_vertices([square, segment, point, nan, np.zeros((0, 3)), huge, CUBE])
    assert cs.hull_status.tolist() == [
        HullStatus.FLAT,
        HullStatus.COLLINEAR,
        HullStatus.SINGLE_POINT,
        HullStatus.NON_FINITE,
        HullStatus.EMPTY,
        HullStatus.OVERFLOW,
        HullStatus.OK,
    ]
    assert np.diff(cs.offsets).tolist() == [4, 2, 1, 8, 0, 8, 8]
    assert np.diff(cs.face_offsets).tolist() == [2, 0, 0, 0, 0, 0, 6]
    assert np.diff(cs.edge_offsets).tolist() == [2, 1, 0, 0, 0, 0, 3]
    assert cs.face_normals[:2].tolist() in ([[0, 0, 1], [0, 0, -1]], [[0, 0, -1], [0, 0, 1]])
    np.testing.assert_allclose(cs.edge_directions[2], np.ones(3) / np.sqrt(3.0))
    # NaN and empty shapes answer INVALID_INPUT; the 1e200 cube, kept as its points, answers
    # right: the unit cube at x = 5 is inside it
    poses = np.tile(np.eye(4), (7, 1, 1))
    poses[6, 0, 3] = 5.0
    r = distance_batch(cs, poses, [[6, 3], [6, 4], [6, 5], [6, 0], [6, 1], [6, 2]])
    assert r.status.tolist()[:2] == [Status.INVALID_INPUT] * 2
    assert r.status.tolist()[2:] == [Status.CONVERGED] * 4
    assert r.distance[2] == 0.0


def test_take_and_concatenate_keep_the_statuses() -> None:
    cs = ConvexSet.from_vertices([CUBE, np.ones((2, 3))])
    both = ConvexSet.concatenate(cs, cs.take([1, 0]))
    assert both.hull_status.tolist() == [0, 3, 3, 0]


def test_batched_arrays_equal_one_at_a_time() -> None:
    rng = np.random.default_rng(7)
    clouds = rng.normal(size=(64, 40, 3))
    whole = pack_hulls(clouds, threads=2)
    for i in (0, 17, 63):
        one = pack_hulls([clouds[i]])
        rows = slice(whole.offsets[i], whole.offsets[i + 1])
        assert (whole.vertices[rows] == one.vertices).all()
        first, last = (
            whole.adjacency_offsets[whole.offsets[i]],
            whole.adjacency_offsets[whole.offsets[i + 1]],
        )
        assert (whole.adjacency[first:last] == one.adjacency).all()
        faces = slice(whole.face_offsets[i], whole.face_offsets[i + 1])
        assert (whole.face_normals[faces] == one.face_normals).all()


# ---------------------------------------------------------------------------------------
# qhull on the corpus and on random clouds


def corpus_bodies(root: Path):
    from meshcol.errors import MeshcolError
    from meshcol.io.mesh_read import load_mesh

    suffixes = {".stl", ".obj", ".off", ".ply", ".glb"}
    for path in sorted(p for p in root.rglob("*") if p.suffix.lower() in suffixes):
        try:
            bodies = load_mesh(path)
        except MeshcolError:
            continue  # empty or broken files: tested by the loaders
        for body in bodies:
            yield path, body


def test_vertex_sets_equal_qhull_on_the_corpus(corpus: Path) -> None:
    compared = 0
    for path, body in corpus_bodies(corpus):
        points = np.asarray(body.world_vertices(), dtype=np.float64)
        hull = exact_hull(points)
        if hull.dimension < 3:
            continue
        unique = np.unique(points + 0.0, axis=0)
        reference = ConvexHull(unique)
        assert set(map(tuple, hull.vertices)) == set(map(tuple, unique[reference.vertices])), path
        assert hull.volume == pytest.approx(reference.volume, rel=1e-9), path
        assert hull.area == pytest.approx(reference.area, rel=1e-9), path
        compared += 1
    assert compared >= 50


def test_corpus_packing_faces_and_edges_match_qhull_facets(corpus: Path) -> None:
    """One normal per qhull facet (merged coplanar triangles share their plane)."""
    for name in ("fandisk.obj", "busted.STL", "featuretype.STL"):
        from meshcol.io.mesh_read import load_mesh

        (body,) = load_mesh(corpus / "trimesh-models" / name)
        points = body.world_vertices()
        cs = ConvexSet.from_vertices([points])
        reference = ConvexHull(np.unique(points + 0.0, axis=0))
        planes = np.unique(np.round(reference.equations[:, :3], 9), axis=0)
        assert len(cs.face_normals) == len(planes), name
        assert len(np.unique(np.round(cs.face_normals, 9), axis=0)) == len(planes), name


clouds = arrays(
    np.float64,
    st.tuples(st.integers(4, 80), st.just(3)),
    elements=st.floats(-100, 100, allow_nan=False, width=32),
)
grids = arrays(
    np.float64,
    st.tuples(st.integers(4, 80), st.just(3)),
    elements=st.integers(-3, 3).map(float),  # many duplicates, collinear and coplanar points
)


@settings(max_examples=150, deadline=None)
@given(st.one_of(clouds, grids))
def test_random_clouds_equal_qhull_and_keep_the_invariants(points: np.ndarray) -> None:
    hull = exact_hull(points)
    if hull.dimension < 3:
        return
    scale = float(np.abs(points).max())
    assert_valid_hull(points, 1e-12 * scale)
    unique = np.unique(points, axis=0)
    gaps = np.linalg.norm(unique[:, None] - unique[None], axis=2) + np.eye(len(unique)) * scale
    if gaps.min() > 1e-9 * scale:
        # points closer than the tolerance are interchangeable: either may be the vertex
        assert set(map(tuple, hull.vertices)) == qhull_vertex_set(points)


@st.composite
def rotated_grids(draw) -> np.ndarray:
    """Integer grid points under a rotation: collinear and coplanar up to rounding, where
    thin triangles (normals lost to cancellation) and ties abound."""
    points = draw(grids)
    q = np.array(draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4)))
    if np.linalg.norm(q) < 1e-3:
        q = np.array([0.5, 0.5, 0.5, 0.5])
    w, x, y, z = q / np.linalg.norm(q)
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return points @ rotation.T


@settings(max_examples=150, deadline=None)
@given(rotated_grids())
def test_rotated_grids_keep_the_invariants(points: np.ndarray) -> None:
    if exact_hull(points).dimension == 3:
        assert_valid_hull(points, 1e-12 * float(np.abs(points).max()))


@pytest.mark.slow
def test_random_subsets_of_grids_keep_every_point_inside() -> None:
    """Seeded cases of the kinds that once lost points: random subsets of a grid in thirds
    (a corner of a face polygon taken for an edge point through a thin triangle whose plain
    cross product was zero) and rotated integer grids (badly rounded face planes)."""
    t = np.linspace(0.0, 1.0, 4)
    thirds = np.stack(np.meshgrid(t, t, t), axis=-1).reshape(-1, 3)
    rng = np.random.default_rng(2224)
    for _ in range(300):
        n = int(rng.integers(8, 64))
        points = thirds[rng.permutation(len(thirds))[:n]]
        if exact_hull(points).dimension == 3:
            assert_valid_hull(points, 1e-12)
            assert set(map(tuple, exact_hull(points).vertices)) == qhull_vertex_set(points)
        rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        grid = rng.integers(-4, 5, size=(n, 3)).astype(float) @ rotation.T
        if exact_hull(grid).dimension == 3:
            assert_valid_hull(grid, 1e-12 * float(np.abs(grid).max()))


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.integers(4, 300), st.integers(0, 2**32 - 1))
def test_points_on_a_sphere_are_all_vertices(n: int, seed: int) -> None:
    p = np.random.default_rng(seed).normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    hull = exact_hull(p)
    assert len(hull.vertices) == n
    assert_valid_hull(p, 1e-12)
    # general position: triangles only, every edge its own class
    cs = ConvexSet.from_vertices([p])
    assert len(cs.face_normals) == len(hull.faces)
    assert len(cs.edge_directions) == 3 * len(hull.faces) // 2


# --------------------------------------------------------------------------- interior filter


def _hull_triangles(points: np.ndarray) -> set[frozenset[tuple[float, ...]]]:
    hull = exact_hull(points)
    return {frozenset(map(tuple, hull.vertices[f])) for f in hull.faces}


def _torus(u_count: int, v_count: int) -> np.ndarray:
    u = np.linspace(0, 2 * np.pi, u_count, endpoint=False)
    v = np.linspace(0, 2 * np.pi, v_count, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = 1.0 + 0.3 * np.cos(vv)
    return np.stack([r * np.cos(uu), r * np.sin(uu), 0.3 * np.sin(vv)], -1).reshape(-1, 3)


@pytest.mark.parametrize("seed", range(3))
def test_interior_points_of_large_inputs_change_nothing(seed: int) -> None:
    """Large inputs (4,096 points and more) drop points well inside the hull of their extremes
    before Quickhull: the triangulation is the one of the surface points alone (few enough to
    be built unfiltered), face for face, and the vertex set qhull's."""
    rng = np.random.default_rng(seed)
    surface = rng.normal(size=(3000, 3))
    surface /= np.linalg.norm(surface, axis=1, keepdims=True)
    surface *= rng.uniform(0.5, 2.0, 3)  # an ellipsoid
    inside = rng.uniform(-0.4, 0.4, size=(2000, 3))  # deep inside: the filter drops these
    shell = surface * rng.uniform(0.9, 1.0, size=(3000, 1))  # just under the surface
    points = np.concatenate([shell, surface, inside])[rng.permutation(8000)]
    assert len(surface) < 4096
    assert _hull_triangles(points) == _hull_triangles(surface)
    assert set(map(tuple, exact_hull(points).vertices)) == qhull_vertex_set(points)


def test_interior_filter_split_over_threads_changes_nothing() -> None:
    """Above 2 x 131,072 points the filter's scans run in chunks on threads (where the
    machine has them), combined in chunk order: the triangulation is still the one of the
    surface points alone, whichever chunk holds each extreme, its duplicates and the points
    just under the surface."""
    rng = np.random.default_rng(11)
    surface = rng.normal(size=(3000, 3))
    surface /= np.linalg.norm(surface, axis=1, keepdims=True)
    surface *= (0.7, 1.3, 2.0)
    inside = rng.uniform(-0.3, 0.3, size=(300_000, 3))
    shell = surface[rng.integers(0, 3000, 20_000)] * rng.uniform(0.95, 1.0, size=(20_000, 1))
    points = np.concatenate([inside, shell, surface, surface[:50]])[rng.permutation(323_050)]
    assert _hull_triangles(points) == _hull_triangles(surface)


def test_large_torus_and_cube_grid_equal_qhull() -> None:
    """A grid torus (half its points inside the hull, flat rings on top and bottom) and a
    crowded cube surface with points inside, both above the filter's size."""
    torus = _torus(160, 40)
    assert set(map(tuple, exact_hull(torus).vertices)) == qhull_vertex_set(torus)
    grid = cube_surface_grid(30)
    inner = np.random.default_rng(5).uniform(0.001, 0.999, size=(5000, 3))
    cube = np.concatenate([grid, inner])
    hull = exact_hull(cube)
    assert set(map(tuple, hull.vertices)) == set(map(tuple, CUBE))
    assert _hull_triangles(cube) == _hull_triangles(CUBE)


@settings(max_examples=60)
@given(
    st.tuples(*[st.floats(0.01, 100.0) for _ in range(3)]),
    st.tuples(*[st.floats(-1e3, 1e3) for _ in range(3)]),
    st.integers(0, 2**32 - 1),
)
def test_distance_to_a_box_hull_is_the_analytic_one(half, centre, seed) -> None:
    """Points on the surface (vertices, where the two triangles of a face meet) are at 0, not
    at the distance of a coplanar triangle they lie a rounding error in front of; points
    around the box are at the analytic box distance."""
    from meshcol.collision.hull import distance_to_hull

    h, c = np.array(half), np.array(centre)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    rotation, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    corners = c + (signs * h) @ rotation.T
    hull = exact_hull(corners)
    rng = np.random.default_rng(seed)
    local = np.vstack(
        [signs * h, rng.uniform(-3, 3, (200, 3)) * h, signs * h * rng.uniform(0, 1, (8, 1))]
    )
    expected = np.linalg.norm(np.maximum(np.abs(local) - h, 0.0), axis=1)
    got = distance_to_hull(c + local @ rotation.T, hull)
    scale = np.abs(c).max() + h.max()
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9 * scale)
