"""Fidelity of a decomposition: volumes and two-sided Hausdorff distances to the mesh."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from meshcol.decomposition.result import Fidelity
from meshcol.geometry.topology import is_closed_manifold, manifold_solid
from meshcol.geometry.triangles import point_triangle_distances, sample_surface

__all__ = [
    "DEFAULT_SAMPLES",
    "METRICS_VERSION",
    "bounded_maximum",
    "coverage_tolerance",
    "farthest_outside_solid",
    "fidelity",
    "points_to_parts",
    "points_to_triangles",
    "signed_distances_to_solid",
]


# Fidelity sampling defaults (points on the mesh surface and on the parts' surfaces).
DEFAULT_SAMPLES = 2000


DEFAULT_METRIC_SEED = 0


#: Version of the metrics' definitions: cached metrics of another version are measured again
#: (the parts are kept). 2: parts -> mesh measured to the mesh's solid, part vertices sampled.
#: 3: parts -> mesh a proved upper bound (:func:`bounded_maximum`), not a sample.
METRICS_VERSION = 3


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


def _manifold_volume(vertices: np.ndarray, faces: np.ndarray) -> float | None:
    import manifold3d

    m = manifold_solid(vertices, faces)
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
        Points sampled on the mesh surface (mesh -> parts; parts -> mesh is bounded, not
        sampled).
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

    parts -> mesh: a proved upper bound, not a sample, of the largest distance from the
    boundary of the parts' union to the mesh: to the solid it bounds when the mesh is closed
    and consistently wound (``mesh_is_solid``; 0 inside), else to its surface (exact
    point-triangle distances). Both distances are 1-Lipschitz, so over a triangle of a part
    they exceed the value at its centroid by at most the triangle's radius; triangles whose
    bound could beat the largest value measured are quartered and measured again
    (:func:`bounded_maximum`), until the bound is within ``BOUND_RELATIVE_GAP`` of that value
    plus ``BOUND_ABSOLUTE_FRACTION`` of the diagonal. Pieces wholly within
    ``SHARED_FACE_FRACTION`` of the diagonal of another part lie on a cut shared with it (up
    to the engines' slivers), not on the boundary of the union, and are left out. A part that
    sticks out of the mesh by h gives h (or a little more); parts that stay inside give
    about 0, however they are cut.

    Volumes: manifold3d (hull of each part, boolean union; the mesh itself when manifold).
    An inconsistently wound mesh is wound consistently first
    (:func:`meshcol.collision.orientation.orient_consistently`), so a closed one is a solid.
    """
    # the native core, imported when a fidelity is measured (`meshcol --help` imports this)
    from meshcol.collision.orientation import orient_consistently

    vertices = np.asarray(vertices, dtype=np.float64)
    faces = orient_consistently(vertices, np.asarray(faces, dtype=np.int64)).faces
    tol = coverage_tolerance(vertices, tolerance)
    rng = np.random.default_rng(seed)
    # Mesh points first, then the parts': one generator, in this order, for every result.
    to_parts = points_to_parts(_mesh_points(vertices, faces, samples, rng), parts, threads=threads)
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
        hausdorff_parts_to_mesh=_farthest_from_mesh(parts, vertices, faces, solid, threads),
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


def signed_distances_to_solid(points: np.ndarray, meshes: Any, *, threads: int = 0) -> np.ndarray:
    """Signed distance (n,) of each point to the solid a closed mesh bounds: the distance to
    its surface, negative inside (mesh 0 of ``meshes``, consistently wound either way round).

    Inside and outside as :func:`farthest_outside_solid` decides them: the side of the face
    holding the closest point where it lies inside that face, else the generalized winding
    number (:meth:`MeshSet.contains`).
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    distances, closest, face = meshes.closest_faces(0, points, threads=threads)
    if len(points) == 0:
        return distances
    vertices, faces = meshes.mesh(0)
    corners = vertices[faces]
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    normals = np.cross(b - a, c - a)
    orientation = 1.0 if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() >= 0 else -1.0
    ok = face >= 0
    interior = np.zeros(len(points), dtype=bool)
    side = np.zeros(len(points))
    interior[ok] = _inside_face(closest[ok], a[face[ok]], b[face[ok]], c[face[ok]])
    side[ok] = orientation * np.einsum("ij,ij->i", points[ok] - closest[ok], normals[face[ok]])
    inside = interior & (side < 0.0)
    rest = ok & ~interior
    if rest.any():
        inside[rest] = meshes.contains(0, points[rest])
    return np.where(inside, -distances, distances)


#: The parts -> mesh distance is refined until its proved upper bound exceeds the largest
#: distance measured by at most this fraction of it, plus :data:`BOUND_ABSOLUTE_FRACTION` of
#: the mesh's diagonal (or until :data:`BOUND_MAX_EVALUATIONS` points were measured).
BOUND_RELATIVE_GAP = 0.02
#: See :data:`BOUND_RELATIVE_GAP`.
BOUND_ABSOLUTE_FRACTION = 1e-4
#: Most points measured for one bound; past it the bound is kept as proved, only looser.
BOUND_MAX_EVALUATIONS = 400_000


def bounded_maximum(
    triangles: np.ndarray,
    value: Any,
    gap: Any,
    skip: Any = None,
    *,
    max_evaluations: int = BOUND_MAX_EVALUATIONS,
    cover: Any = None,
) -> tuple[float, float]:
    """A proved upper bound and an attained value of ``max(0, sup f)`` over triangles, for a
    1-Lipschitz function ``f``.

    Parameters
    ----------
    triangles : (t, 3, 3) float
        Corners of each triangle.
    value : callable (k, 3) -> (k,)
        ``f`` at points; ``|f(p) - f(q)| <= |p - q|``.
    gap : callable float -> float
        The slack allowed above the largest value measured ``m``: refinement stops once the
        bound is within ``m + gap(m)``.
    skip : callable ((k, 3) centres, (k,) radii, (k,) rows) -> (k,) bool, optional
        Triangles (given by a ball holding them and their row in ``triangles``) to leave out.
    max_evaluations : int
        Most points measured; past it the bound stands, only looser.
    cover : callable ((k, 3, 3) triangles, (k, 3) centres) -> (k,), optional
        Another upper bound of ``f`` over each triangle (as ``f`` on the mesh: the distance
        to a convex piece of what ``f`` measures the distance to, largest at a corner); the
        smaller bound counts.

    Returns
    -------
    (upper, attained) : (float, float)
        ``attained <= max(0, sup f) <= upper``.

    Notes
    -----
    Branch and bound: each triangle lies in the ball of radius ``r`` (its farthest corner)
    around its centroid ``c``, so ``f <= f(c) + r`` on it (Lipschitz). Triangles whose bound
    exceeds the best value measured by more than the gap are cut in four at the midpoints of
    their edges, and measured again; the others are settled, and the answer is the largest
    bound of the settled ones (Piyavskii 1972's bound on a triangulation). ``cover`` may
    settle a triangle at once: for the parts against a mesh, the distance to the mesh face
    nearest the centroid, convex, so at most its value at the worst corner; a part's face
    that lies on the mesh's surface is settled at about 0 without being refined.
    """
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    rows = np.arange(len(tri))
    attained, settled, evaluations = 0.0, 0.0, 0
    while len(tri):
        centre = tri.mean(axis=1)
        radius = np.linalg.norm(tri - centre[:, None], axis=2).max(axis=1)
        if skip is not None:
            keep = ~skip(centre, radius, rows)
            tri, centre, radius, rows = tri[keep], centre[keep], radius[keep], rows[keep]
            if not len(tri):
                break
        measured = np.asarray(value(centre), dtype=np.float64)
        evaluations += len(tri)
        attained = max(attained, float(np.max(measured, initial=0.0)))
        bound = measured + radius
        if cover is not None:
            bound = np.minimum(bound, cover(tri, centre))
        open_ = bound > attained + gap(attained)
        settled = max(settled, float(np.max(bound[~open_], initial=0.0)))
        if not open_.any():
            break
        if evaluations + 4 * int(open_.sum()) > max_evaluations:
            settled = max(settled, float(bound[open_].max()))
            break
        tri, rows = _quartered(tri[open_]), np.repeat(rows[open_], 4)
    return max(settled, attained), attained


def _quartered(tri: np.ndarray) -> np.ndarray:
    """Each triangle (t, 3, 3) cut in four at its edge midpoints, (4t, 3, 3)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    quarters = np.stack(
        [
            np.stack([a, ab, ca], axis=1),
            np.stack([ab, b, bc], axis=1),
            np.stack([ca, bc, c], axis=1),
            np.stack([ab, bc, ca], axis=1),
        ],
        axis=1,
    )
    return quarters.reshape(-1, 3, 3)


def _flat_neighbours(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(m, 3) int64: per face and edge, the face across it when the two make a flat convex
    quadrilateral (coplanar, the diagonals crossing), else -1."""
    m = len(faces)
    out = np.full((m, 3), -1, dtype=np.int64)
    if m == 0:
        return out
    a = faces.reshape(-1)
    b = faces[:, [1, 2, 0]].reshape(-1)
    n = int(faces.max()) + 1
    keys = np.minimum(a, b) * n + np.maximum(a, b)
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    twin = np.flatnonzero(ordered[1:] == ordered[:-1])
    single = np.ones(len(twin), dtype=bool)  # edges of exactly two faces
    single[1:] &= twin[1:] != twin[:-1] + 1
    single[:-1] &= twin[:-1] + 1 != twin[1:]
    twin = twin[single]
    h1, h2 = order[twin], order[twin + 1]
    f1, f2 = h1 // 3, h2 // 3
    v = np.asarray(vertices, dtype=np.float64)
    # the vertex of each face opposite the shared edge
    o1 = faces[f1, (h1 % 3 + 2) % 3]
    o2 = faces[f2, (h2 % 3 + 2) % 3]
    p, q = v[a[h1]], v[b[h1]]
    normal = np.cross(q - p, v[o1] - p)
    size = np.linalg.norm(normal, axis=1)
    off_plane = np.abs(np.einsum("ij,ij->i", v[o2] - p, normal))
    scale = np.linalg.norm(v[o2] - p, axis=1) * size
    coplanar = (size > 0) & (off_plane <= 1e-12 * scale)
    # convex: o1 and o2 on opposite sides of the edge line, p and q on opposite sides of o1-o2
    side1 = np.einsum("ij,ij->i", np.cross(q - p, v[o1] - p), normal)
    side2 = np.einsum("ij,ij->i", np.cross(q - p, v[o2] - p), normal)
    d = v[o2] - v[o1]
    across_p = np.einsum("ij,ij->i", np.cross(d, p - v[o1]), normal)
    across_q = np.einsum("ij,ij->i", np.cross(d, q - v[o1]), normal)
    convex = coplanar & (side1 * side2 < 0) & (across_p * across_q < 0)
    out[f1[convex], h1[convex] % 3] = f2[convex]
    out[f2[convex], h2[convex] % 3] = f1[convex]
    return out


def _face_cover(
    tri: np.ndarray, face: np.ndarray, vertices: np.ndarray, faces: np.ndarray, flat: np.ndarray
) -> np.ndarray:
    """An upper bound (k,) of the distance to the mesh over each triangle (k, 3, 3): the
    distance to a convex piece of the surface (the face ``face[k]``, or it and a neighbour
    making a flat convex quadrilateral with it), convex, so largest at a corner."""
    ok = face >= 0
    out = np.full(len(tri), np.inf)
    if not ok.any():
        return out
    tri, face = tri[ok], face[ok]

    def corner_distances(corners: np.ndarray, to: np.ndarray) -> np.ndarray:
        nearest = vertices[faces[to]]
        return np.stack([point_triangle_distances(corners[:, k], nearest) for k in range(3)], 1)

    own = corner_distances(tri, face)
    best = own.max(axis=1)
    for edge in range(3):
        other = flat[face, edge]
        has = other >= 0
        if has.any():
            quad = np.minimum(own[has], corner_distances(tri[has], other[has]))
            best[has] = np.minimum(best[has], quad.max(axis=1))
    out[ok] = best
    return out


#: A triangle certified inside the solid is shrunk by this fraction towards its centroid
#: before the test that it crosses no face; its bound is this fraction of its radius.
INTERIOR_SHRINK = 1e-13


def _interior_cover(
    tri: np.ndarray, meshes: Any, vertices: np.ndarray, faces: np.ndarray, threads: int
) -> np.ndarray:
    """An upper bound (k,) of the distance to the solid over each triangle: about 0
    (``INTERIOR_SHRINK`` of its radius) for a triangle whose copy shrunk towards its centroid
    has its centroid inside and crosses no face of the mesh (so the copy, connected, lies in
    the solid; every point of the triangle is within the shrink of it), else inf."""
    from meshcol.collision.mesh_query import MeshSet, mesh_intersects_batch

    out = np.full(len(tri), np.inf)
    centre = tri.mean(axis=1, keepdims=True)
    candidates = np.flatnonzero(
        signed_distances_to_solid(centre[:, 0], meshes, threads=threads) < 0
    )
    if not len(candidates):
        return out
    centre = centre[candidates]
    shrunk = centre + (tri[candidates] - centre) * (1.0 - INTERIOR_SHRINK)
    one = np.array([[0, 1, 2]], dtype=np.int64)
    pieces = MeshSet.from_arrays([(vertices, faces), *((t, one) for t in shrunk)], threads=1)
    pairs = np.stack([np.zeros(len(candidates)), np.arange(1, len(candidates) + 1)], 1)
    crossing = mesh_intersects_batch(pieces, None, pairs.astype(np.int64), threads=threads)
    clear = ~crossing.intersecting & (crossing.status == 0)
    radius = np.linalg.norm(tri[candidates] - centre, axis=2).max(axis=1)
    out[candidates[clear]] = INTERIOR_SHRINK * radius[clear]
    return out


def _farthest_from_mesh(
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    vertices: np.ndarray,
    faces: np.ndarray,
    solid: bool,
    threads: int,
) -> float:
    """A proved upper bound of the largest distance of the boundary of the parts' union to
    the mesh's solid (0 inside) when it is one, else to its surface (:func:`bounded_maximum`
    over the parts' triangles); 0 without parts."""
    from meshcol.collision.mesh_query import MeshSet

    if not parts:
        return 0.0
    meshes = MeshSet.from_arrays([(vertices, faces)], threads=1)
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    triangles = np.concatenate([v[f] for v, f in parts])
    owner = np.repeat(np.arange(len(parts)), [len(f) for _, f in parts])

    def value(points: np.ndarray) -> np.ndarray:
        if solid:
            return signed_distances_to_solid(points, meshes, threads=threads)
        return meshes.closest_points(0, points, threads=threads)[0]

    def gap(best: float) -> float:
        return BOUND_RELATIVE_GAP * best + BOUND_ABSOLUTE_FRACTION * diagonal

    flat = _flat_neighbours(vertices, faces)

    def cover(tri: np.ndarray, centre: np.ndarray) -> np.ndarray:
        _, _, face = meshes.closest_faces(0, centre, threads=threads)
        bound = _face_cover(tri, face, vertices, faces, flat)
        if solid:
            bound = np.minimum(bound, _interior_cover(tri, meshes, vertices, faces, threads))
        return bound

    def shared(centre: np.ndarray, radius: np.ndarray, rows: np.ndarray) -> np.ndarray:
        # wholly within the shared-face distance of another part: a cut, not the boundary
        near = points_to_parts(centre, parts, owner[rows], threads=threads)
        return near + radius <= SHARED_FACE_FRACTION * diagonal

    skip = shared if len(parts) > 1 else None
    return bounded_maximum(triangles, value, gap, skip, cover=cover)[0]


def _union_volume(parts: tuple[tuple[np.ndarray, np.ndarray], ...]) -> float:
    """Volume of the union of the parts (manifold3d's boolean union)."""
    import manifold3d

    # The parts are convex hulls already (closed, outward): their meshes are the solids.
    solids = [manifold_solid(v, f) for v, f in parts]
    union = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    return float(union.volume())


def _at_most(rows: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``rows``, or ``count`` of them chosen with ``rng`` (in their order) when there are more."""
    if len(rows) <= count:
        return rows
    return rows[np.sort(rng.choice(len(rows), count, replace=False))]
