"""The native polygon splitter (:mod:`meshcol.io.polygons`, ``cpp/src/triangulate.cpp``)
against the numpy splitter it replaced, kept here as the oracle: the same triangles, bit for
bit, on quads, n-gons, mixed sizes, degenerate faces and coordinates, holes and leftHanded
winding; bad counts are refused with one message. Then the USD reader end to end."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from meshcol.io.polygons import PolygonError, TooManyTriangles, triangulate_faces

# -- the oracle: the numpy splitter of meshcol.io.off before issue 30's read-speed work ------


def old_triangulate(vertices: np.ndarray, corners: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    vertices = np.asarray(vertices, dtype=np.float64)
    corners = np.asarray(corners, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    starts = np.zeros(len(sizes), dtype=np.int64)
    np.cumsum(sizes[:-1], out=starts[1:])
    first_triangle = starts - 2 * np.arange(len(sizes), dtype=np.int64)
    out = np.empty((int(sizes.sum()) - 2 * len(sizes), 3), dtype=np.int64)
    for size in np.unique(sizes).tolist():
        which = np.flatnonzero(sizes == size)
        polygons = corners[starts[which][:, None] + np.arange(size)]
        rows = first_triangle[which][:, None] + np.arange(size - 2)
        if size == 3:
            out[rows[:, 0]] = polygons
            continue
        fan = np.stack(
            [np.repeat(polygons[:, :1], size - 2, axis=1), polygons[:, 1:-1], polygons[:, 2:]],
            axis=2,
        )
        convex = _old_convex(vertices[polygons])
        out[rows[convex].ravel()] = fan[convex].reshape(-1, 3)
        for p in np.flatnonzero(~convex).tolist():
            out[rows[p]] = _old_ear_clip(vertices, polygons[p])
    return out


def _old_plane(points: np.ndarray) -> np.ndarray:
    nxt = np.roll(points, -1, axis=-2)
    normal = np.stack(
        [
            np.sum((points[..., 1] - nxt[..., 1]) * (points[..., 2] + nxt[..., 2]), axis=-1),
            np.sum((points[..., 2] - nxt[..., 2]) * (points[..., 0] + nxt[..., 0]), axis=-1),
            np.sum((points[..., 0] - nxt[..., 0]) * (points[..., 1] + nxt[..., 1]), axis=-1),
        ],
        axis=-1,
    )
    axis = np.argmax(np.abs(normal), axis=-1)
    u, v = (axis + 1) % 3, (axis + 2) % 3
    pu = np.take_along_axis(points, u[..., None, None].repeat(points.shape[-2], -2), -1)[..., 0]
    pv = np.take_along_axis(points, v[..., None, None].repeat(points.shape[-2], -2), -1)[..., 0]
    sign = np.where(np.take_along_axis(normal, axis[..., None], -1)[..., 0] < 0, -1.0, 1.0)
    return np.stack([pu, pv * sign[..., None]], axis=-1)


def _old_convex(points: np.ndarray) -> np.ndarray:
    uv = _old_plane(points)
    edge = np.roll(uv, -1, axis=-2) - uv
    prev = np.roll(edge, 1, axis=-2)
    turn = prev[..., 0] * edge[..., 1] - prev[..., 1] * edge[..., 0]
    if points.shape[-2] <= 4:
        return np.all(turn > 0, axis=-1)
    angle = np.arctan2(turn, np.sum(prev * edge, axis=-1))
    total = np.sum(angle, axis=-1)
    return np.all(turn > 0, axis=-1) & (np.abs(total - 2 * np.pi) < 1e-6)


def _old_ear_clip(vertices: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    uv = _old_plane(vertices[polygon][None])[0]
    remaining = list(range(len(polygon)))
    triangles = []

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    while len(remaining) > 3:
        n = len(remaining)
        for k in range(n):
            i, j, m = remaining[k - 1], remaining[k], remaining[(k + 1) % n]
            a, b, c = uv[i], uv[j], uv[m]
            if cross(a, b, c) <= 0:
                continue
            inside = False
            for r in remaining:
                if r in (i, j, m):
                    continue
                p = uv[r]
                if cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0:
                    inside = True
                    break
            if not inside:
                triangles.append((i, j, m))
                del remaining[k]
                break
        else:
            break
    triangles.extend(
        (remaining[0], remaining[t], remaining[t + 1]) for t in range(1, len(remaining) - 1)
    )
    return polygon[np.asarray(triangles, dtype=np.int64)]


def old_usd_faces(
    points: np.ndarray, counts: np.ndarray, indices: np.ndarray, holes: np.ndarray, left: bool
) -> np.ndarray:
    """What io/usd_read.py's _mesh made of a mesh before the splitter moved into the core."""
    keep = counts >= 3
    if holes.size:
        keep[holes[(holes >= 0) & (holes < len(counts))]] = False
    corners = np.repeat(keep, counts)
    sizes = counts[keep]
    faces = old_triangulate(points, indices[corners], sizes) if sizes.size else None
    if faces is None:
        faces = np.zeros((0, 3), dtype=np.int64)
    if left:
        faces = faces[:, ::-1]
    return np.ascontiguousarray(faces, dtype=np.int64)


# -- polygons to split -----------------------------------------------------------------------


def _ring(k: int, rng: np.random.Generator, *, star: bool = False) -> np.ndarray:
    """k points around a circle, jittered radius (a star shape when ``star``), tilted in 3-D."""
    if star:
        angle = np.linspace(0, 2 * np.pi, k + 1)[:-1]
    else:
        angle = np.sort(rng.uniform(0, 2 * np.pi, k))
    radius = rng.uniform(0.3, 1.0, k) if star else np.ones(k)
    flat = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(k)])
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return flat @ q.T * 10 ** rng.uniform(-3, 3) + rng.normal(size=3)


def _mesh(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A soup of faces of every kind: triangles, convex quads and n-gons, stars, reflex
    quads, pentagrams, collinear, zero-area, repeated-corner, points and edges (counts 0-2),
    faces whose corners come from other faces."""
    points, counts, indices = [], [], []

    def add(corners: np.ndarray) -> None:
        base = sum(len(p) for p in points)
        points.append(corners)
        counts.append(len(corners))
        indices.extend(range(base, base + len(corners)))

    for _ in range(60):
        kind = rng.integers(0, 9)
        k = int(rng.integers(3, 12))
        if kind == 0:
            add(_ring(k, rng))
        elif kind == 1:
            add(_ring(max(k, 5), rng, star=True))
        elif kind == 2:  # a reflex (dart) quad
            add(np.array([[0, 0, 0], [2, 1, 0], [0, 0.3, 0], [-2, 1, 0]]) + rng.normal(size=3))
        elif kind == 3:  # a pentagram: every turn left, two turns in all
            t = np.arange(5) * 4 * np.pi / 5
            add(np.column_stack([np.cos(t), np.sin(t), np.zeros(5)]))
        elif kind == 4:  # collinear corners: no area
            add(np.outer(np.linspace(0, 1, k), rng.normal(size=3)))
        elif kind == 5:  # every corner the same point
            add(np.repeat(rng.normal(size=(1, 3)), k, axis=0))
        elif kind == 6:  # a convex polygon with a repeated corner
            ring = _ring(k, rng)
            add(np.insert(ring, 1, ring[1], axis=0))
        elif kind == 7:  # a point or an edge: no triangle
            m = int(rng.integers(0, 3))
            base = sum(len(p) for p in points)
            points.append(rng.normal(size=(m, 3)))
            counts.append(m)
            indices.extend(range(base, base + m))
        else:  # an exact square on the grid (ties everywhere)
            add(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float) * k)
    return np.vstack([p.reshape(-1, 3) for p in points]), np.array(counts), np.array(indices)


@pytest.mark.parametrize("seed", range(12))
def test_same_triangles_as_the_numpy_splitter(seed: int) -> None:
    rng = np.random.default_rng(seed)
    points, counts, indices = _mesh(rng)
    # corners shared between faces, in another order: the faces index the points freely
    perm = rng.permutation(len(points))
    points, indices = points[np.argsort(perm)], perm[indices]
    holes = rng.choice(len(counts) + 5, size=4, replace=False) - 2  # some out of range
    for left in (False, True):
        got = triangulate_faces(points, counts, indices, holes=holes, reverse=left)
        want = old_usd_faces(points, counts.copy(), indices, holes, left)
        assert got.dtype == np.int64 and got.shape == want.shape
        assert np.array_equal(got, want)


@pytest.mark.parametrize("size", [4, 5, 7, 8, 9, 17, 130, 300])
def test_same_triangles_on_one_size(size: int) -> None:
    """All-quad meshes (the common USD case), and sizes around numpy's summing blocks (8, 128)."""
    rng = np.random.default_rng(size)
    rings = [_ring(size, rng, star=bool(i % 2)) for i in range(6 if size < 100 else 2)]
    points = np.vstack(rings)
    counts = np.full(len(rings), size)
    indices = np.arange(len(points))
    got = triangulate_faces(points, counts, indices)
    assert np.array_equal(got, old_triangulate(points, indices, counts))


def test_quads_fanned_and_reversed() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    counts, indices = np.array([4]), np.arange(4)
    assert triangulate_faces(square, counts, indices).tolist() == [[0, 1, 2], [0, 2, 3]]
    reversed_ = triangulate_faces(square, counts, indices, reverse=True)
    assert reversed_.tolist() == [[2, 1, 0], [3, 2, 0]]
    dart = np.array([[2, 1, 0], [0, 0.3, 0], [-2, 1, 0], [0, 0, 0]])
    # a fan from corner 0 would cut outside the dart: the cut runs from the reflex corner 1
    assert triangulate_faces(dart, counts, indices).tolist() == [[3, 0, 1], [1, 2, 3]]


def test_empty_and_no_triangle_faces() -> None:
    none = triangulate_faces(np.zeros((0, 3)), np.zeros(0, int), np.zeros(0, int))
    assert none.shape == (0, 3) and none.dtype == np.int64
    points = np.eye(3)
    assert triangulate_faces(points, np.array([0, 1, 2]), np.array([0, 0, 1])).shape == (0, 3)
    holes = triangulate_faces(points, np.array([3]), np.arange(3), holes=np.array([0]))
    assert holes.shape == (0, 3)


@pytest.mark.parametrize(
    ("counts", "indices", "words"),
    [
        ([3, -1, 4], [0, 1, 2, 0, 1, 2], "face 1 has a negative vertex count (-1)"),
        ([3, 3], [0, 1, 2], "face vertex counts add up to 6, but there are 3 face vertex"),
        ([3], [0, 1, 2, 0], "face vertex counts add up to 3, but there are 4 face vertex"),
        ([2**62, 2**62, 2**62, 2**62], [0, 1, 2], "add up to more than 2^64, but there are 3"),
        ([2_000_000_000], [0, 1, 2], "add up to 2000000000, but there are 3 face vertex"),
        ([3], [0, 1, 3], "face vertex index 3 refers to a point the mesh does not have (3 "),
        ([3], [0, -1, 2], "face vertex index -1 refers to a point"),
    ],
)
def test_bad_counts_and_indices_are_refused(counts: list, indices: list, words: str) -> None:
    with pytest.raises(PolygonError) as error:
        triangulate_faces(np.eye(3), np.array(counts), np.array(indices))
    assert words in str(error.value) and "\n" not in str(error.value)


def test_triangle_budget_is_checked_before_splitting() -> None:
    counts, indices = np.array([5, 3]), np.array([0, 1, 2, 0, 1, 0, 1, 2])
    assert len(triangulate_faces(np.eye(3), counts, indices, max_triangles=4)) == 4
    with pytest.raises(TooManyTriangles, match="more than 3 triangles"):
        triangulate_faces(np.eye(3), counts, indices, max_triangles=3)


# -- the USD reader end to end ---------------------------------------------------------------


def test_usd_mesh_reads_the_same_triangles(tmp_path: Path) -> None:
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    from meshcol.io.usd_read import read_usd_scene

    rng = np.random.default_rng(99)
    points, counts, indices = _mesh(rng)
    holes = np.array([1, 4, 7])
    path = tmp_path / "mixed.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    for name, left in (("right", False), ("left", True)):
        mesh = UsdGeom.Mesh.Define(stage, f"/{name}")
        mesh.CreatePointsAttr(points.tolist())
        mesh.CreateFaceVertexCountsAttr(counts.tolist())
        mesh.CreateFaceVertexIndicesAttr(indices.tolist())
        mesh.CreateHoleIndicesAttr(holes.tolist())
        if left:
            mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    stage.Save()
    scene = read_usd_scene(path, str(path))
    elements = {g.elements[0].name: g.elements[0] for g in scene.groups}
    # usd-core stores the points as float32: the oracle splits the points the file holds
    stored = points.astype(np.float32).astype(np.float64)
    for name, left in (("right", False), ("left", True)):
        element = elements[name]
        want = old_usd_faces(stored, counts.copy(), indices, holes, left)
        assert np.array_equal(element.faces, want), name


def test_same_triangles_on_regular_polygons() -> None:
    """Regular k-gons (their turns add up to one turn within rounding: the 1e-6 test decides)
    and the same corners rounded to float32, in planes of every orientation."""
    rng = np.random.default_rng(5)
    points, counts = [], []
    for k in range(5, 41):
        t = np.linspace(0, 2 * np.pi, k, endpoint=False)
        ring = np.column_stack([np.cos(t), np.sin(t), np.zeros(k)])
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        for corners in (ring @ q.T, (ring @ q.T).astype(np.float32).astype(np.float64)):
            points.append(corners)
            counts.append(k)
    vertices, counts_ = np.vstack(points), np.array(counts)
    indices = np.arange(len(vertices))
    got = triangulate_faces(vertices, counts_, indices)
    assert np.array_equal(got, old_triangulate(vertices, indices, counts_))
