"""Convex hulls of point sets: exact (qhull), or within a vertex budget and still enclosing.

Physics engines cap the vertex count of a convex collider (PhysX 255, GPU pipelines 64).
:func:`convex_hull` returns the exact hull, or with ``max_vertices`` a hull with at most that
many vertices that still contains every input point: its faces are grown outward, never
pulled inward, so a simplified collider can only make contact earlier, never let an object
sink in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshcol.errors import InvalidMeshError

__all__ = ["HullResult", "convex_hull", "MIN_MAX_VERTICES"]

#: The smallest vertex budget: a tetrahedron.
MIN_MAX_VERTICES = 4
#: Points are flat (collinear) when their extent across the best-fit plane (line) is at most
#: this fraction of their bounding-box diagonal.
FLAT_RELATIVE_TOLERANCE = 1e-9
#: The budget loop stops early once the simplified hull is within this fraction of the
#: diagonal of the exact hull.
CONVERGED_RELATIVE_DISTANCE = 1e-9
#: Simplified-hull vertices closer than this fraction of the diagonal are merged.
MERGE_RELATIVE_DISTANCE = 1e-11
#: Orientations tried for the starting simplex (the smallest enclosing one is kept).
START_ORIENTATIONS = 64
#: Far vertices tried per step before the budget loop gives up.
CUT_CANDIDATES = 8


@dataclass(frozen=True, eq=False)
class HullResult:
    """A convex hull, exact or simplified within a vertex budget.

    Attributes
    ----------
    vertices : (k, 3) float64
        Hull vertices, in the frame of the input points. Exact hull: a subset of the input
        points, unchanged. Simplified hull: new points (intersections of grown face planes).
    faces : (m, 3) int64
        Triangles indexing ``vertices``, wound counter-clockwise seen from outside. For a flat
        hull, a fan triangulation of the polygon (one side only).
    volume : float
        Volume enclosed by ``vertices``/``faces`` (0 for a flat hull).
    area : float
        Surface area of the hull; for a flat hull, the area of the polygon (one side).
    flat : bool
        The input points are coplanar: the hull is a 2-D polygon in their plane.
    exact_vertex_count, exact_face_count : int
        Size of the exact hull (equal to ``len(vertices)``, ``len(faces)`` without a budget).
    exact_volume : float
        Volume of the exact hull (0 when flat).
    max_vertices : int or None
        The vertex budget asked for, or None.
    added_volume : float
        ``volume - exact_volume`` (>= 0; 0 without simplification).
    added_volume_fraction : float or None
        ``added_volume / exact_volume``; None when the exact volume is 0 (flat).
    max_distance : float
        Largest distance from a point of this hull to the exact hull (one-sided Hausdorff
        distance; 0 when exact). Input units.
    """

    vertices: np.ndarray
    faces: np.ndarray
    volume: float
    area: float
    flat: bool
    exact_vertex_count: int
    exact_face_count: int
    exact_volume: float
    max_vertices: int | None = None
    added_volume: float = 0.0
    added_volume_fraction: float | None = None
    max_distance: float = 0.0

    @property
    def simplified(self) -> bool:
        """True when the budget forced a hull other than the exact one."""
        return self.max_distance > 0.0 or len(self.vertices) != self.exact_vertex_count


def convex_hull(points: np.ndarray, max_vertices: int | None = None) -> HullResult:
    """Convex hull of a point set, optionally with at most ``max_vertices`` vertices.

    Parameters
    ----------
    points : (n, 3) float
        Input points (e.g. a mesh's vertices), in any frame; the result is in the same frame.
    max_vertices : int, optional
        Vertex budget (>= 4). The result then has at most this many vertices and still
        contains every input point.

    Returns
    -------
    HullResult

    Raises
    ------
    InvalidMeshError
        No points, non-finite coordinates, or points that span no area (one point or
        collinear): there is no meaningful hull.
    ValueError
        ``points`` is not (n, 3) or ``max_vertices`` < 4.

    Notes
    -----
    The exact hull is qhull's Quickhull (Barber, Dobkin and Huhdanpaa 1996) through
    ``scipy.spatial.ConvexHull`` with option ``Qt`` (triangulated output), retried with ``QJ``
    (joggled input) when qhull reports a precision problem. Coplanar points give a 2-D hull,
    computed by qhull on the plane coordinates.

    The budgeted hull is built from supporting planes of the exact hull H (planes touching H
    with H on their inner side), so it always encloses H, and thus every input point:

    1. Start from the smallest of ``START_ORIENTATIONS`` simplices (tetrahedron, or triangle
       when flat) whose faces are supporting planes of H.
    2. Find the vertex v of the current polytope Q farthest from H, with its closest point p
       on H (exact point-to-facet distances over the facets of H that v sees).
    3. Add the supporting plane at p with normal ``(v - p) / |v - p|``: it is the cut that
       removes v most deeply. Recompute Q as the intersection of the half-spaces
       (``scipy.spatial.HalfspaceIntersection``, interior point: the centroid of H's vertices).
    4. Keep the cut if Q still has at most ``max_vertices`` vertices (else try the next
       farthest vertices, up to ``CUT_CANDIDATES``), and repeat from 2 until no cut fits or Q
       is within ``CONVERGED_RELATIVE_DISTANCE`` of H.

    This is the plane-based "grow the faces outward" scheme of engine cookers, driven by
    the Hausdorff distance: each step reduces the largest deviation where it is. The
    reported ``max_distance`` is exact: the distance to a convex set is a convex function,
    so its maximum over the polytope Q is reached at a vertex of Q.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), got {pts.shape}")
    if max_vertices is not None and int(max_vertices) < MIN_MAX_VERTICES:
        raise ValueError(f"max_vertices must be >= {MIN_MAX_VERTICES}, got {max_vertices}")
    if len(pts) == 0:
        raise InvalidMeshError("mesh has no vertices: there is no hull")
    if not np.isfinite(pts).all():
        raise InvalidMeshError("vertices contain NaN or infinite coordinates")

    scale = float(np.linalg.norm(np.ptp(pts, axis=0)))
    if scale == 0.0:
        raise InvalidMeshError("all vertices coincide: there is no meaningful hull")
    centre = pts.mean(axis=0)
    _, _, axes = np.linalg.svd(pts - centre, full_matrices=False)
    widths = np.ptp((pts - centre) @ axes.T, axis=0)
    if widths[1] <= FLAT_RELATIVE_TOLERANCE * scale:
        raise InvalidMeshError("all vertices are collinear: there is no meaningful hull")

    exact = None
    if widths[2] > FLAT_RELATIVE_TOLERANCE * scale:
        exact = _exact_hull_3d(pts)
    if exact is None:
        return _flat_hull(pts, centre, axes[:2], scale, max_vertices)

    hull_points, simplices, equations, volume, area = exact
    result_kwargs = dict(
        flat=False,
        exact_vertex_count=len(np.unique(simplices)),
        exact_face_count=len(simplices),
        exact_volume=volume,
        max_vertices=None if max_vertices is None else int(max_vertices),
    )
    vertices, faces = _compact(hull_points, simplices)
    if max_vertices is None or len(vertices) <= max_vertices:
        return HullResult(vertices=vertices, faces=faces, volume=volume, area=area,
                          added_volume_fraction=0.0 if max_vertices is not None else None,
                          **result_kwargs)

    facets = vertices[faces]
    eq = equations
    q_vertices, distance = _simplify(vertices, facets, eq, int(max_vertices), scale)
    from scipy.spatial import ConvexHull

    q_hull = ConvexHull(q_vertices, qhull_options="Qt")
    q_faces = _orient(q_vertices, q_hull.simplices, q_hull.equations)
    q_vertices, q_faces = _compact(q_vertices, q_faces)
    added = max(float(q_hull.volume) - volume, 0.0)
    return HullResult(
        vertices=q_vertices, faces=q_faces, volume=float(q_hull.volume),
        area=float(q_hull.area), added_volume=added, added_volume_fraction=added / volume,
        max_distance=distance, **result_kwargs,
    )


# ---------------------------------------------------------------------------------------
# exact hulls


def _exact_hull_3d(pts: np.ndarray):
    """qhull in 3-D: (points, oriented simplices, equations, volume, area), None when flat."""
    from scipy.spatial import ConvexHull, QhullError

    for options in ("Qt", "QJ"):
        try:
            hull = ConvexHull(pts, qhull_options=options)
        except QhullError:
            continue
        if hull.volume <= 0.0:
            return None
        simplices = _orient(pts, hull.simplices, hull.equations)
        return pts, simplices, hull.equations, float(hull.volume), float(hull.area)
    return None


def _flat_hull(pts, centre, plane_axes, scale, max_vertices) -> HullResult:
    """2-D hull of coplanar points, as a fan-triangulated polygon in their plane."""
    from scipy.spatial import ConvexHull, QhullError

    coords = (pts - centre) @ plane_axes.T
    try:
        hull = ConvexHull(coords)
    except QhullError as exc:  # unreachable after the collinearity test; kept as a message
        raise InvalidMeshError("all vertices are collinear: there is no meaningful hull") from exc
    ring = hull.vertices  # counter-clockwise in the plane coordinates
    exact_area = float(hull.volume)  # qhull's 2-D "volume" is the area
    exact_count = len(ring)
    kwargs = dict(flat=True, exact_vertex_count=exact_count, exact_face_count=exact_count - 2,
                  exact_volume=0.0, volume=0.0,
                  max_vertices=None if max_vertices is None else int(max_vertices))
    if max_vertices is None or exact_count <= max_vertices:
        return HullResult(vertices=pts[ring].copy(), faces=_fan(len(ring)), area=exact_area, **kwargs)

    ring_points = coords[ring]
    n = len(ring_points)
    segments = np.stack([ring_points, ring_points[np.r_[1:n, 0]]], axis=1)
    edges = segments[:, 1] - segments[:, 0]
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)  # outward for a CCW ring
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = -np.einsum("ij,ij->i", normals, segments[:, 0])
    equations = np.hstack([normals, offsets[:, None]])
    q_coords, distance = _simplify(ring_points, segments, equations, int(max_vertices), scale)
    q_hull = ConvexHull(q_coords)
    q_ring = q_coords[q_hull.vertices]
    return HullResult(vertices=centre + q_ring @ plane_axes, faces=_fan(len(q_ring)),
                      area=float(q_hull.volume), max_distance=distance, **kwargs)


def _fan(n: int) -> np.ndarray:
    """Fan triangulation of a convex polygon with ``n`` vertices in order."""
    i = np.arange(1, n - 1, dtype=np.int64)
    return np.stack([np.zeros_like(i), i, i + 1], axis=1)


def _orient(points: np.ndarray, simplices: np.ndarray, equations: np.ndarray) -> np.ndarray:
    """Wind each triangle counter-clockwise seen from outside (along its facet normal)."""
    simplices = np.asarray(simplices, dtype=np.int64).copy()
    tri = points[simplices]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("ij,ij->i", normal, equations[:, :3]) < 0
    simplices[flip] = simplices[flip][:, ::-1]
    return simplices


def _compact(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keep only the points ``faces`` use, renumbered."""
    used, inverse = np.unique(faces, return_inverse=True)
    return points[used].copy(), inverse.reshape(faces.shape).astype(np.int64)


# ---------------------------------------------------------------------------------------
# budgeted hulls (dimension-generic: 3-D, or 2-D for flat input)


def _simplify(hull_vertices, facets, equations, budget, scale):
    """Supporting-plane polytope with <= ``budget`` vertices around the exact hull.

    ``hull_vertices`` (k, d) are the exact hull's vertices, ``facets`` (m, d, d) its facet
    simplices and ``equations`` (m, d + 1) their outward planes ``n . x + c = 0``.
    Returns the polytope's vertices (q, d) and its exact distance to the hull.
    """
    interior = hull_vertices.mean(axis=0)
    dim = hull_vertices.shape[1]
    equations = (np.ascontiguousarray(equations[:, :dim].T), np.ascontiguousarray(equations[:, dim]))
    tolerance = CONVERGED_RELATIVE_DISTANCE * scale
    normals = _start_simplex(hull_vertices)
    offsets = (normals @ hull_vertices.T).max(axis=1)
    polytope = _intersect(normals, offsets, interior, scale)
    if polytope is None:  # qhull failed on four planes: not seen, but never crash on it
        raise InvalidMeshError(f"qhull could not build a hull within {budget} vertices")
    distances, closest = _distances_to_hull(polytope, facets, equations)
    for _ in range(4 * budget + 16):
        order = np.argsort(-distances, kind="stable")
        accepted = False
        for index in order[:CUT_CANDIDATES]:
            if distances[index] <= tolerance:
                break
            normal = (polytope[index] - closest[index]) / distances[index]
            offset = float((hull_vertices @ normal).max())
            trial_normals = np.vstack([normals, normal])
            trial_offsets = np.append(offsets, offset)
            trial = _intersect(trial_normals, trial_offsets, interior, scale)
            if trial is not None and len(trial) <= budget:
                distances, closest = _update_distances(
                    polytope, distances, closest, trial, facets, equations, scale)
                normals, offsets, polytope = trial_normals, trial_offsets, trial
                accepted = True
                break
        if not accepted:
            break
    # the loop reused distances of vertices that survived a cut; report a fresh, exact one
    distances, _ = _distances_to_hull(polytope, facets, equations)
    return polytope, float(distances.max())


def _update_distances(old, old_distances, old_closest, new, facets, equations, scale):
    """Distances of ``new`` vertices, reusing those of vertices ``old`` already had."""
    from scipy.spatial import cKDTree

    gap, match = cKDTree(old).query(new, distance_upper_bound=MERGE_RELATIVE_DISTANCE * scale)
    known = np.isfinite(gap)
    distances = np.empty(len(new))
    closest = np.empty_like(new)
    distances[known] = old_distances[match[known]]
    closest[known] = old_closest[match[known]]
    if (~known).any():
        distances[~known], closest[~known] = _distances_to_hull(new[~known], facets, equations)
    return distances, closest


def _start_simplex(hull_vertices: np.ndarray) -> np.ndarray:
    """Unit normals (d + 1, d) of the smallest of several supporting regular-simplex shapes."""
    dim = hull_vertices.shape[1]
    rng = np.random.default_rng(0)
    if dim == 3:
        base = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) / np.sqrt(3)
        rotations = [np.eye(3)]
        for _ in range(START_ORIENTATIONS - 1):
            q, r = np.linalg.qr(rng.normal(size=(3, 3)))
            rotations.append(q * np.sign(np.diag(r)))
    else:
        angles = np.pi / 2 + np.array([0, 2, 4]) * np.pi / 3
        base = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        rotations = []
        for t in np.linspace(0, 2 * np.pi / 3, START_ORIENTATIONS, endpoint=False):
            c, s = np.cos(t), np.sin(t)
            rotations.append(np.array([[c, -s], [s, c]]))
    best, best_size = None, np.inf
    for rotation in rotations:
        normals = base @ rotation.T
        offsets = (normals @ hull_vertices.T).max(axis=1)
        corners = []
        for skip in range(dim + 1):
            keep = [i for i in range(dim + 1) if i != skip]
            corners.append(np.linalg.solve(normals[keep], offsets[keep]))
        corners = np.array(corners)
        size = abs(np.linalg.det(corners[1:] - corners[0]))
        if size < best_size:
            best, best_size = normals, size
    return best


def _intersect(normals, offsets, interior, scale):
    """Vertices of ``{x : normals @ x <= offsets}``, near-duplicates merged; None on failure."""
    from scipy.spatial import HalfspaceIntersection, QhullError

    halfspaces = np.hstack([normals, -offsets[:, None]])
    try:
        points = HalfspaceIntersection(halfspaces, interior).intersections
    except QhullError:
        return None
    if not np.isfinite(points).all():
        return None
    return _merge_close(points, MERGE_RELATIVE_DISTANCE * scale)


def _merge_close(points: np.ndarray, radius: float) -> np.ndarray:
    """One representative per cluster of points closer than ``radius`` (the farthest out)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return points
    n = len(points)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    # keep, per cluster, the point farthest from the centroid: the merged polytope then
    # still contains the cluster up to ``radius``
    centroid = points.mean(axis=0)
    reach = np.linalg.norm(points - centroid, axis=1)
    order = np.lexsort((-reach, labels))
    first = np.ones(n, bool)
    first[1:] = labels[order][1:] != labels[order][:-1]
    return points[order[first]]


def _distances_to_hull(points, facets, equations):
    """Exact distance (and closest point) from each point to a convex polytope.

    A point outside the polytope has its closest point on a facet whose plane it lies in
    front of, so only those facets are searched; points inside get distance 0.
    ``equations`` is ``(normals.T, offsets)``, the transpose contiguous for a fast product.
    """
    dim = points.shape[1]
    in_front = points @ equations[0] + equations[1] > 0.0
    distances = np.zeros(len(points))
    closest = points.copy()
    p_index, f_index = np.nonzero(in_front)
    if len(p_index) == 0:
        return distances, closest
    if dim == 3:
        candidates = closest_points_on_triangles(points[p_index], facets[f_index])
    else:
        candidates = _closest_points_on_segments(points[p_index], facets[f_index])
    d2 = ((candidates - points[p_index]) ** 2).sum(axis=1)
    order = np.lexsort((d2, p_index))
    first = np.ones(len(order), bool)
    first[1:] = p_index[order][1:] != p_index[order][:-1]
    best = order[first]
    distances[p_index[best]] = np.sqrt(d2[best])
    closest[p_index[best]] = candidates[best]
    return distances, closest


def _closest_points_on_segments(p: np.ndarray, segments: np.ndarray) -> np.ndarray:
    a, b = segments[:, 0], segments[:, 1]
    ab = b - a
    t = np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def closest_points_on_triangles(p: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Closest point on each triangle to each point, vectorised.

    Parameters
    ----------
    p : (n, 3) float
    triangles : (n, 3, 3) float

    Returns
    -------
    (n, 3) float

    Notes
    -----
    Ericson, Real-Time Collision Detection (2004), 5.1.5: Voronoi regions of the vertices,
    then the edges, else the projection onto the face.
    """
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2

    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        result = a + v[:, None] * ab + w[:, None] * ac  # face region
        # edge regions
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    on_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    result = np.where(on_bc[:, None], b + np.nan_to_num(t_bc)[:, None] * (c - b), result)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    result = np.where(on_ac[:, None], a + np.nan_to_num(t_ac)[:, None] * ac, result)
    # applied in reverse order of Ericson's early returns, so the first test wins
    result = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, result)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    result = np.where(on_ab[:, None], a + np.nan_to_num(t_ab)[:, None] * ab, result)
    result = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, result)
    result = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, result)
    # a degenerate (zero-area) triangle leaves NaN in the face region: fall back to its
    # closest vertex
    bad = ~np.isfinite(result).all(axis=1)
    if bad.any():
        corners = triangles[bad]
        d = ((corners - p[bad][:, None, :]) ** 2).sum(axis=2)
        result[bad] = corners[np.arange(len(corners)), d.argmin(axis=1)]
    return result
