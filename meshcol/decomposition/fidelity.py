"""Fidelity of a decomposition: volumes and two-sided Hausdorff distances to the mesh."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from meshcol.decomposition.result import Fidelity
from meshcol.geometry.topology import is_closed_manifold
from meshcol.geometry.triangles import sample_surface, triangle_areas

__all__ = [
    "DEFAULT_SAMPLES",
    "METRICS_VERSION",
    "coverage_tolerance",
    "farthest_outside_solid",
    "fidelity",
    "points_to_parts",
    "points_to_triangles",
]


# Fidelity sampling defaults (points on the mesh surface and on the parts' surfaces).
DEFAULT_SAMPLES = 2000


DEFAULT_METRIC_SEED = 0


#: Version of the metrics' definitions: cached metrics of another version are measured again
#: (the parts are kept). 2: parts -> mesh measured to the mesh's solid, part vertices sampled.
METRICS_VERSION = 2


# Coverage tolerance as a fraction of the mesh's bounding-box diagonal.
DEFAULT_TOLERANCE_FRACTION = 0.01


# A point of a part's surface this close (fraction of the diagonal) to another part is on a
# face shared with it (a cut), not on the boundary of the union. CoACD leaves slivers of about
# 1e-5 of the diagonal between the two sides of a cut (measured on torus.STL); 1e-4 closes them
# and is still far below any collision tolerance.
SHARED_FACE_FRACTION = 1e-4


def coverage_tolerance(vertices: np.ndarray, tolerance: float | None) -> float:
    """``tolerance`` checked, or the default fraction of the bounding-box diagonal."""
    if tolerance is not None:
        if not (math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance must be finite and >= 0, got {tolerance}")
        return float(tolerance)
    return DEFAULT_TOLERANCE_FRACTION * float(np.linalg.norm(np.ptp(vertices, axis=0)))


def points_to_parts(
    points: np.ndarray,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    owner: np.ndarray | None = None,
    *,
    threads: int = 0,
) -> np.ndarray:
    """Distance from each point to the union of convex parts (0 inside a part), (n,) float64.

    Each point is a sphere of radius 0; candidate (point, part) pairs are pruned with AABBs
    (a part whose box is farther than the point's nearest part centroid cannot be the closest)
    and measured in one :func:`meshcol.collision.narrowphase.distance_batch` call. ``owner[i]`` (optional)
    excludes part ``owner[i]`` from point ``i``'s candidates.
    """
    from meshcol.collision.narrowphase import distance_batch
    from meshcol.collision.shapes import ConvexSet
    from meshcol.types import Sphere

    points = np.ascontiguousarray(points, dtype=np.float64)
    n, k = len(points), len(parts)
    lo = np.array([v.min(axis=0) for v, _ in parts])
    hi = np.array([v.max(axis=0) for v, _ in parts])
    centre = np.array([v.mean(axis=0) for v, _ in parts])  # inside the hull: an upper bound
    result = np.full(n, np.inf)
    pairs_i, pairs_j = [], []
    chunk = max(1, 4_000_000 // max(k, 1))
    for start in range(0, n, chunk):
        p = points[start : start + chunk]
        gap = np.maximum(np.maximum(lo[None] - p[:, None], p[:, None] - hi[None]), 0.0)
        lower = np.linalg.norm(gap, axis=2)
        upper = np.linalg.norm(p[:, None] - centre[None], axis=2)
        if owner is not None:
            own = owner[start : start + chunk]
            lower[np.arange(len(p)), own] = np.inf
            upper[np.arange(len(p)), own] = np.inf
        bound = upper.min(axis=1)
        i, j = np.nonzero(lower <= bound[:, None])
        pairs_i.append(i + start)
        pairs_j.append(j)
    i = np.concatenate(pairs_i)
    j = np.concatenate(pairs_j)
    if len(i) == 0:
        return result
    # Each point is a sphere of radius 0 placed by its pose: packed without a hull per point.
    shapes = ConvexSet.concatenate(
        ConvexSet.from_shapes([Sphere(0.0)] * n),
        ConvexSet.from_vertices([v for v, _ in parts]),
    )
    poses = np.tile(np.eye(4), (n + k, 1, 1))
    poses[:n, :3, 3] = points
    pairs = np.stack([i, n + j], axis=1).astype(np.int64)
    batch = distance_batch(shapes, poses, pairs, threads=threads)
    # fmin skips NaN (a pair the query rejected): a point whose pairs all failed stays inf.
    np.fmin.at(result, i, np.asarray(batch.distance, dtype=np.float64))
    return result


def points_to_triangles(
    points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, *, threads: int = 0
) -> np.ndarray:
    """Exact distance from each point to the nearest triangle, (n,) float64.

    One native query on the mesh's hierarchy (:meth:`meshcol.collision.mesh_query.MeshSet.
    closest_points`: branch and bound, exact point-triangle distance, Ericson 2004, 5.1.5).
    """
    from meshcol.collision.mesh_query import MeshSet

    meshes = MeshSet.from_arrays([(vertices, faces)], threads=1)
    distances, _ = meshes.closest_points(0, points, threads=threads)
    return distances


def farthest_outside_solid(points: np.ndarray, meshes: Any, *, threads: int = 0) -> float:
    """Largest distance from ``points`` to the solid a closed mesh bounds (0 inside it).

    Parameters
    ----------
    points : (n, 3) float
        Query points, in the mesh's frame.
    meshes : meshcol.collision.mesh_query.MeshSet
        The mesh, as mesh 0; closed and consistently wound (either way round).
    threads : int
        Threads for the closest-point queries; 0 uses all cores.

    Returns
    -------
    float
        The largest distance to the mesh surface among the points outside it; 0 when every
        point is inside; NaN when a point is not finite.

    Notes
    -----
    Exact, and cheap: each point's closest surface point comes from the mesh's hierarchy
    (:meth:`MeshSet.closest_faces`). Where it lies inside a face, the point is on the side of
    that face its normal says (the segment to it crosses no surface, or a surface point
    would be nearer). The others (closest point on an edge or a corner) are classified by
    the generalized winding number (:meth:`MeshSet.contains`, Jacobson et al. 2013), farthest
    first, and only while they could raise the answer: the first outside one ends the
    search. A ball of radius d around an inside point holds no surface, so every point in it
    is inside too and is not tested.
    """
    from scipy.spatial import cKDTree

    points = np.ascontiguousarray(points, dtype=np.float64)
    distances, closest, face = meshes.closest_faces(0, points, threads=threads)
    if len(points) == 0:
        return 0.0
    if np.isnan(distances).any():
        return float("nan")
    vertices, faces = meshes.mesh(0)
    corners = vertices[faces]
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    normals = np.cross(b - a, c - a)
    # Outward (positive volume) or inward: the side a face's normal points to is outside.
    orientation = 1.0 if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() >= 0 else -1.0
    interior = _inside_face(closest, a[face], b[face], c[face])
    side = orientation * np.einsum("ij,ij->i", points - closest, normals[face])
    outside = interior & (side > 0.0)
    best = float(distances[outside].max()) if outside.any() else 0.0
    # Undecided: closest point on an edge or a corner, and farther than the answer so far.
    settled = interior | (distances <= best)
    if settled.all():
        return best
    order = np.argsort(-distances, kind="stable")
    tree = None
    batch = 16
    while True:
        pending = order[~settled[order]][:batch]
        if len(pending) == 0:
            return best
        out = ~meshes.contains(0, points[pending])
        if out.any():
            # Farthest first: every point not yet settled is no farther than these.
            return max(best, float(distances[pending[out]].max()))
        settled[pending] = True
        if tree is None:
            tree = cKDTree(points)
        # Shrunk a little so that a point on the ball's sphere (on the surface) is left out.
        balls = tree.query_ball_point(points[pending], distances[pending] * (1.0 - 1e-9))
        covered = [np.asarray(ball, dtype=np.int64) for ball in balls if len(ball)]
        if covered:
            settled[np.concatenate(covered)] = True
        batch = min(2 * batch, 1024)


def _inside_face(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Whether each point ``q`` (on its triangle's plane) lies strictly inside the triangle
    (a, b, c), away from its edges by a relative margin: barycentric coordinates > 1e-9."""
    e0, e1, w = b - a, c - a, q - a
    d00 = np.einsum("ij,ij->i", e0, e0)
    d01 = np.einsum("ij,ij->i", e0, e1)
    d11 = np.einsum("ij,ij->i", e1, e1)
    d20 = np.einsum("ij,ij->i", w, e0)
    d21 = np.einsum("ij,ij->i", w, e1)
    denominator = d00 * d11 - d01 * d01
    with np.errstate(divide="ignore", invalid="ignore"):
        v = (d11 * d20 - d01 * d21) / denominator
        u = (d00 * d21 - d01 * d20) / denominator
    margin = 1e-9
    return (denominator > 0) & (v > margin) & (u > margin) & (1.0 - u - v > margin)


def _manifold(vertices: np.ndarray, faces: np.ndarray):
    import manifold3d

    return manifold3d.Manifold(
        manifold3d.Mesh64(
            np.ascontiguousarray(vertices, dtype=np.float64),
            np.ascontiguousarray(faces, dtype=np.uint64),
        )
    )


def _manifold_volume(vertices: np.ndarray, faces: np.ndarray) -> float | None:
    import manifold3d

    m = _manifold(vertices, faces)
    if m.status() != manifold3d.Error.NoError or m.is_empty():
        return None
    return float(m.volume())


def fidelity(
    vertices: np.ndarray,
    faces: np.ndarray,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    *,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_METRIC_SEED,
    tolerance: float | None = None,
    threads: int = 0,
) -> Fidelity:
    """Fidelity metrics of ``parts`` against the mesh (``vertices``, ``faces``).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        Convex parts in the mesh's frame.
    samples : int
        Points sampled on the mesh surface, and as many on the parts' surfaces.
    seed : int
        Sampling seed (fixed: the metrics are deterministic).
    tolerance : float, optional
        Coverage tolerance; default 1% of the bounding-box diagonal.
    threads : int
        Threads for the distance queries; 0 uses all cores.

    Notes
    -----
    The two one-sided distances measure how far each shape's surface strays from the other
    shape (its solid, where it has one), so that what lies inside both (cuts between parts,
    gaps between them deep in the mesh) never counts:

    mesh -> parts: sampled mesh surface points plus the mesh vertices (at most ``samples`` of
    them, chosen with the same seed); distance to the union of the parts, 0 inside a part
    (:func:`points_to_parts`, our GJK distance queries).

    parts -> mesh: sampled points of the parts' surfaces plus the parts' vertices (at most
    ``samples``), keeping those on the boundary of the union: a point within
    ``SHARED_FACE_FRACTION`` of the diagonal of another part (inside it, or on a cut shared
    with it up to the engines' slivers) is not. Their distance to the mesh: to the solid it
    bounds when the mesh is closed and consistently wound (``mesh_is_solid``; 0 inside,
    :func:`farthest_outside_solid`), else to its surface (exact point-triangle distances).
    A part that sticks out of the mesh by h gives h; parts that stay inside give 0, however
    they are cut.

    Volumes: manifold3d (hull of each part, boolean union; the mesh itself when manifold).
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    tol = coverage_tolerance(vertices, tolerance)
    rng = np.random.default_rng(seed)
    # Mesh points first, then the parts': one generator, in this order, for every result.
    to_parts = points_to_parts(_mesh_points(vertices, faces, samples, rng), parts, threads=threads)
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    boundary = _boundary_points(parts, samples, rng, diagonal, threads)
    solid = is_closed_manifold(faces)
    union_volume = _union_volume(parts)
    mesh_volume = _manifold_volume(vertices, faces)
    return Fidelity(
        parts=len(parts),
        vertices_per_part=tuple(len(v) for v, _ in parts),
        mesh_volume=mesh_volume,
        union_volume=union_volume,
        volume_ratio=None if not mesh_volume else union_volume / mesh_volume,
        hausdorff_mesh_to_parts=float(to_parts.max()),
        hausdorff_parts_to_mesh=_farthest_from_mesh(boundary, vertices, faces, solid, threads),
        uncovered_fraction=float((to_parts > tol).mean()),
        tolerance=tol,
        samples=samples,
        mesh_is_solid=solid,
    )


def _mesh_points(
    vertices: np.ndarray, faces: np.ndarray, samples: int, rng: np.random.Generator
) -> np.ndarray:
    """``samples`` points of the mesh surface and at most ``samples`` of its vertices."""
    corners = _at_most(vertices, samples, rng)
    return np.concatenate([sample_surface(vertices, faces, samples, rng), corners])


def _boundary_points(
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    samples: int,
    rng: np.random.Generator,
    diagonal: float,
    threads: int,
) -> np.ndarray:
    """Points of the parts' surfaces (``samples`` by area, and at most ``samples`` of their
    vertices) on the boundary of their union: those within ``SHARED_FACE_FRACTION`` of the
    diagonal of another part are not."""
    areas = np.array([triangle_areas(v, f).sum() for v, f in parts])
    counts = np.maximum(1, np.round(samples * areas / areas.sum()).astype(np.int64))
    part_vertices = np.concatenate([v for v, _ in parts])
    vertex_owner = np.repeat(np.arange(len(parts)), [len(v) for v, _ in parts])
    kept = _at_most(np.arange(len(part_vertices)), samples, rng)
    points = np.concatenate(
        [
            *(sample_surface(v, f, int(c), rng) for (v, f), c in zip(parts, counts)),
            part_vertices[kept],
        ]
    )
    if len(parts) == 1:
        return points
    owner = np.concatenate([np.repeat(np.arange(len(parts)), counts), vertex_owner[kept]])
    shared = (
        points_to_parts(points, parts, owner, threads=threads) <= SHARED_FACE_FRACTION * diagonal
    )
    return points[~shared]


def _farthest_from_mesh(
    points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, solid: bool, threads: int
) -> float:
    """The largest distance of ``points`` to the mesh's solid (0 inside) when it is one,
    else to its surface; 0 without points."""
    from meshcol.collision.mesh_query import MeshSet

    if not len(points):
        return 0.0
    if solid:
        meshes = MeshSet.from_arrays([(vertices, faces)], threads=1)
        return farthest_outside_solid(points, meshes, threads=threads)
    return float(points_to_triangles(points, vertices, faces, threads=threads).max())


def _union_volume(parts: tuple[tuple[np.ndarray, np.ndarray], ...]) -> float:
    """Volume of the union of the parts (manifold3d's boolean union)."""
    import manifold3d

    # The parts are convex hulls already (closed, outward): their meshes are the solids.
    solids = [_manifold(v, f) for v, f in parts]
    union = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    return float(union.volume())


def _at_most(rows: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``rows``, or ``count`` of them chosen with ``rng`` (in their order) when there are more."""
    if len(rows) <= count:
        return rows
    return rows[np.sort(rng.choice(len(rows), count, replace=False))]
