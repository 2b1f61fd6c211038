"""Fidelity of a decomposition: volumes and two-sided Hausdorff distances to the mesh."""

from __future__ import annotations

import math

import numpy as np

from meshcol.decomposition.result import Fidelity
from meshcol.geometry.triangles import sample_surface, triangle_areas

__all__ = [
    "DEFAULT_SAMPLES",
    "coverage_tolerance",
    "fidelity",
    "points_to_parts",
    "points_to_triangles",
]


# Fidelity sampling defaults (points on the mesh surface and on the parts' surfaces).
DEFAULT_SAMPLES = 2000


DEFAULT_METRIC_SEED = 0


# Coverage tolerance as a fraction of the mesh's bounding-box diagonal.
DEFAULT_TOLERANCE_FRACTION = 0.01


# A point of a part's surface this close (fraction of the diagonal) to another part is on a
# face shared with it (a cut), not on the boundary of the union.
SHARED_FACE_FRACTION = 1e-6


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

    Each point is a one-vertex polytope; candidate (point, part) pairs are pruned with AABBs
    (a part whose box is farther than the point's nearest part centroid cannot be the closest)
    and measured in one :func:`meshcol.collision.narrowphase.distance_batch` call. ``owner[i]`` (optional)
    excludes part ``owner[i]`` from point ``i``'s candidates.
    """
    from meshcol.collision.narrowphase import distance_batch
    from meshcol.collision.shapes import ConvexSet

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
    shapes = ConvexSet.concatenate(
        ConvexSet.from_vertices(list(points[:, None, :])),
        ConvexSet.from_vertices([v for v, _ in parts]),
    )
    pairs = np.stack([i, n + j], axis=1).astype(np.int64)
    batch = distance_batch(shapes, None, pairs, threads=threads)
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
    mesh -> parts: sampled mesh surface points plus the mesh vertices (at most ``samples`` of
    them, chosen with the same seed), distance to the union of
    the parts by :func:`points_to_parts` (our GJK distance queries).
    parts -> mesh: sampled part surface points on the boundary of the union (a point within
    ``SHARED_FACE_FRACTION`` of the diagonal of another part lies on a cut shared between parts
    and is skipped), exact distance to the mesh triangles (:func:`points_to_triangles`).
    Volumes: manifold3d (hull of each part, boolean union; the mesh itself when manifold).
    """
    import manifold3d

    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    tol = coverage_tolerance(vertices, tolerance)
    diag = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    rng = np.random.default_rng(seed)
    corners = (
        vertices
        if len(vertices) <= samples
        else vertices[np.sort(rng.choice(len(vertices), samples, replace=False))]
    )
    mesh_points = np.concatenate([sample_surface(vertices, faces, samples, rng), corners])
    to_parts = points_to_parts(mesh_points, parts, threads=threads)

    areas = np.array([triangle_areas(v, f).sum() for v, f in parts])
    counts = np.maximum(1, np.round(samples * areas / areas.sum()).astype(np.int64))
    part_points = np.concatenate(
        [sample_surface(v, f, int(c), rng) for (v, f), c in zip(parts, counts)]
    )
    owner = np.repeat(np.arange(len(parts)), counts)
    if len(parts) > 1:
        shared = (
            points_to_parts(part_points, parts, owner, threads=threads)
            <= SHARED_FACE_FRACTION * diag
        )
        part_points = part_points[~shared]
    to_mesh = (
        points_to_triangles(part_points, vertices, faces, threads=threads)
        if len(part_points)
        else np.zeros(1)
    )

    # The parts are convex hulls already (closed, outward): their meshes are the solids.
    solids = [_manifold(v, f) for v, f in parts]
    union = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    union_volume = float(union.volume())
    mesh_volume = _manifold_volume(vertices, faces)
    return Fidelity(
        parts=len(parts),
        vertices_per_part=tuple(len(v) for v, _ in parts),
        mesh_volume=mesh_volume,
        union_volume=union_volume,
        volume_ratio=None if not mesh_volume else union_volume / mesh_volume,
        hausdorff_mesh_to_parts=float(to_parts.max()),
        hausdorff_parts_to_mesh=float(to_mesh.max()),
        uncovered_fraction=float((to_parts > tol).mean()),
        tolerance=tol,
        samples=samples,
    )
