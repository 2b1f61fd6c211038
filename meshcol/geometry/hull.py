"""Convex hulls of point sets: exact (qhull), or within a vertex budget and still enclosing.

Physics engines cap the vertex count of a convex collider (PhysX 255, GPU pipelines 64).
:func:`convex_hull` returns the exact hull, or with ``max_vertices`` a hull with at most that
many vertices that still contains every input point: its faces are grown outward, never
pulled inward, so a simplified collider can only make contact earlier, never let an object
sink in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import unique_rows
from meshcol.geometry.triangles import closest_points_on_triangles

__all__ = [
    "FLAT_RELATIVE_TOLERANCE",
    "MIN_MAX_VERTICES",
    "ExactHull",
    "HullResult",
    "convex_hull",
    "dimension_of",
    "exact_hull",
    "principal_widths",
]

#: The smallest vertex budget: a tetrahedron.
MIN_MAX_VERTICES = 4
#: The one flatness rule of meshcol. Points are flat (coplanar), collinear or one point when
#: their width across their best-fit plane (line) is at most this fraction of their
#: bounding-box diagonal: hulls, collision shapes, decomposition input and swept triangles
#: all decide with it (:func:`dimension_of`).
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
    exact = exact_hull(pts)
    if exact.dimension == 0:
        raise InvalidMeshError("all vertices coincide: there is no meaningful hull")
    if exact.dimension == 1:
        raise InvalidMeshError("all vertices are collinear: there is no meaningful hull")
    if exact.dimension == 2:
        return _flat_hull(exact, max_vertices)

    volume = exact.volume
    result_kwargs: dict[str, Any] = dict(
        flat=False,
        exact_vertex_count=len(exact.vertices),
        exact_face_count=len(exact.faces),
        exact_volume=volume,
        max_vertices=None if max_vertices is None else int(max_vertices),
    )
    vertices, faces = exact.vertices, exact.faces
    if max_vertices is None or len(vertices) <= max_vertices:
        return HullResult(
            vertices=vertices.copy(),
            faces=faces.copy(),
            volume=volume,
            area=exact.area,
            added_volume_fraction=0.0 if max_vertices is not None else None,
            **result_kwargs,
        )

    q_vertices, distance = _simplify(
        vertices, vertices[faces], exact.equations, int(max_vertices), exact.diagonal
    )
    q = exact_hull(q_vertices)
    added = max(q.volume - volume, 0.0)
    return HullResult(
        vertices=q.vertices,
        faces=q.faces,
        volume=q.volume,
        area=q.area,
        added_volume=added,
        added_volume_fraction=added / volume,
        max_distance=distance,
        **result_kwargs,
    )


# ---------------------------------------------------------------------------------------
# exact hulls


@dataclass(frozen=True, eq=False)
class ExactHull:
    """The exact convex hull of a point set, in every dimension it can have.

    Attributes
    ----------
    dimension : int
        0 (one point), 1 (collinear), 2 (coplanar) or 3, by :data:`FLAT_RELATIVE_TOLERANCE`.
    vertices : (k, 3) float64
        The hull's vertices, a subset of the distinct input points (``-0.0`` as ``0.0``). In
        3-D they are in lexicographic order; in 2-D they are the polygon's ring,
        counter-clockwise about ``normal``; in 1-D the segment's two ends; in 0-D the point.
    faces : (m, 3) int64
        3-D: triangles wound counter-clockwise seen from outside. 2-D: a fan triangulation of
        the ring (one side). Empty otherwise.
    equations : (m, 4) float64
        3-D: each face's outward plane ``n . x + c = 0`` (unit ``n``). Empty otherwise.
    neighbors : (m, 3) int64
        3-D: ``neighbors[f, j]`` is the face across the edge opposite corner ``j`` of face
        ``f``. Empty otherwise.
    normal : (3,) float64
        2-D: the unit normal of the polygon's plane. Zero otherwise.
    volume, area : float
        Enclosed volume (0 below 3-D) and surface area (2-D: the polygon's area, one side).
    diagonal : float
        Bounding-box diagonal of the input points (the scale of the tolerances).
    """

    dimension: int
    vertices: np.ndarray
    faces: np.ndarray
    equations: np.ndarray
    neighbors: np.ndarray
    normal: np.ndarray
    volume: float
    area: float
    diagonal: float


def principal_widths(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Centre, principal axes (3, 3), widths along them (3,) and bounding-box diagonal.

    The widths are the extents of the points along the axes of their best-fit plane (SVD of
    the centred points), largest first: the point set's thickness is ``widths[2]``.
    """
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) == 0:
        return np.zeros(3), np.eye(3), np.zeros(3), 0.0
    extent = pts.max(axis=0) - pts.min(axis=0)
    diagonal = math.sqrt(float(extent @ extent))
    centre = pts.mean(axis=0)
    if diagonal == 0.0 or not np.isfinite(diagonal):
        return centre, np.eye(3), np.zeros(3), diagonal
    centred = pts - centre
    if len(centred) < 3:  # rows at the centre change no width but give a full frame
        centred = np.vstack([centred, np.zeros((3 - len(centred), 3))])
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    along = centred @ axes.T
    widths = along.max(axis=0) - along.min(axis=0)
    return centre, axes, widths, diagonal


def dimension_of(widths: np.ndarray, diagonal: float) -> int:
    """How many dimensions points with these principal widths span (the flatness rule)."""
    if diagonal == 0.0:
        return 0
    return int(np.count_nonzero(widths > FLAT_RELATIVE_TOLERANCE * diagonal))


_NO_FACES = np.zeros((0, 3), dtype=np.int64)


def exact_hull(points: np.ndarray) -> ExactHull:
    """The exact convex hull of finite points (qhull), flat and degenerate inputs included.

    Parameters
    ----------
    points : (n, 3) float
        At least one point, all finite (callers validate and name the input).

    Returns
    -------
    ExactHull

    Notes
    -----
    Quickhull (Barber, Dobkin and Huhdanpaa 1996) through ``scipy.spatial.ConvexHull``, retried
    with joggled input (``QJ``) when qhull reports a precision problem. The dimension comes
    from the one flatness rule (:data:`FLAT_RELATIVE_TOLERANCE`); coplanar points get a 2-D
    hull computed by qhull on their plane coordinates. Every convex hull in meshcol (collision
    shapes, ``meshcol hull``, decomposition parts) is this one.
    """
    from scipy.spatial import ConvexHull, QhullError

    pts, _ = unique_rows(np.asarray(points, dtype=np.float64) + 0.0)
    centre, axes, widths, diagonal = principal_widths(pts)
    dim = dimension_of(widths, diagonal)
    empty4 = np.zeros((0, 4))
    zero3 = np.zeros(3)
    if dim == 3:
        hull = None
        for options in (None, "QJ"):
            try:
                hull = ConvexHull(pts, qhull_options=options)
                break
            except QhullError:
                continue
        if hull is not None and hull.volume > 0.0:
            keep = hull.vertices  # sorted input order, as the input is sorted
            remap = np.full(len(pts), -1, dtype=np.int64)
            remap[keep] = np.arange(len(keep))
            faces = remap[hull.simplices]
            neighbors = np.asarray(hull.neighbors, dtype=np.int64)
            equations = np.asarray(hull.equations, dtype=np.float64)
            vertices = np.ascontiguousarray(pts[keep])
            # A face is wound outward when (v1 - v0) x (v2 - v0) points along its plane's
            # normal: the sign of the triple product, written out (np.cross is slow on
            # small arrays and this runs once per collision shape).
            a = vertices[faces[:, 1]] - vertices[faces[:, 0]]
            b = vertices[faces[:, 2]] - vertices[faces[:, 0]]
            n = equations
            flip = (
                n[:, 0] * (a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1])
                + n[:, 1] * (a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2])
                + n[:, 2] * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
            ) < 0
            # Reversing a triangle swaps corners 0 and 2, and so the edges opposite them.
            faces[flip] = faces[flip][:, ::-1]
            neighbors[flip] = neighbors[flip][:, ::-1]
            return ExactHull(
                3,
                vertices,
                faces,
                equations,
                neighbors,
                zero3,
                float(hull.volume),
                float(hull.area),
                diagonal,
            )
        dim = 2
    if dim == 2:
        uv = (pts - centre) @ axes[:2].T
        try:
            polygon = ConvexHull(uv)
        except QhullError:
            dim = 1
        else:
            ring = polygon.vertices  # counter-clockwise in the plane coordinates
            area = float(polygon.volume)  # qhull's 2-D "volume" is the area
            normal = np.cross(axes[0], axes[1])
            normal /= np.linalg.norm(normal)
            return ExactHull(
                2,
                np.ascontiguousarray(pts[ring]),
                _fan(len(ring)),
                empty4,
                _NO_FACES,
                normal,
                0.0,
                area,
                diagonal,
            )
    if dim == 1:
        t = (pts - centre) @ axes[0]
        ends = np.ascontiguousarray(pts[[int(np.argmin(t)), int(np.argmax(t))]])
        return ExactHull(1, ends, _NO_FACES, empty4, _NO_FACES, zero3, 0.0, 0.0, diagonal)
    return ExactHull(
        0, np.ascontiguousarray(pts[:1]), _NO_FACES, empty4, _NO_FACES, zero3, 0.0, 0.0, diagonal
    )


def _flat_hull(exact: ExactHull, max_vertices: int | None) -> HullResult:
    """The 2-D hull of coplanar points as a fan-triangulated polygon, within a budget."""
    from scipy.spatial import ConvexHull

    ring = exact.vertices
    exact_count = len(ring)
    kwargs: dict[str, Any] = dict(
        flat=True,
        exact_vertex_count=exact_count,
        exact_face_count=exact_count - 2,
        exact_volume=0.0,
        volume=0.0,
        max_vertices=None if max_vertices is None else int(max_vertices),
    )
    if max_vertices is None or exact_count <= max_vertices:
        return HullResult(vertices=ring.copy(), faces=exact.faces.copy(), area=exact.area, **kwargs)
    # Plane coordinates with the ring counter-clockwise about the normal.
    u = ring[1] - ring[0]
    u /= np.linalg.norm(u)
    plane_axes = np.stack([u, np.cross(exact.normal, u)])
    centre = ring.mean(axis=0)
    ring_points = (ring - centre) @ plane_axes.T
    n = len(ring_points)
    segments = np.stack([ring_points, ring_points[np.r_[1:n, 0]]], axis=1)
    edges = segments[:, 1] - segments[:, 0]
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)  # outward for a CCW ring
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = -np.einsum("ij,ij->i", normals, segments[:, 0])
    equations = np.hstack([normals, offsets[:, None]])
    q_coords, distance = _simplify(
        ring_points, segments, equations, int(max_vertices), exact.diagonal
    )
    q_hull = ConvexHull(q_coords)
    q_ring = q_coords[q_hull.vertices]
    return HullResult(
        vertices=centre + q_ring @ plane_axes,
        faces=_fan(len(q_ring)),
        area=float(q_hull.volume),
        max_distance=distance,
        **kwargs,
    )


def _fan(n: int) -> np.ndarray:
    """Fan triangulation of a convex polygon with ``n`` vertices in order."""
    i = np.arange(1, n - 1, dtype=np.int64)
    return np.stack([np.zeros_like(i), i, i + 1], axis=1)


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
    equations = (
        np.ascontiguousarray(equations[:, :dim].T),
        np.ascontiguousarray(equations[:, dim]),
    )
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
                    polytope, distances, closest, trial, facets, equations, scale
                )
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
    best, best_size = base, np.inf
    for rotation in rotations:
        normals = base @ rotation.T
        offsets = (normals @ hull_vertices.T).max(axis=1)
        corners = np.array(
            [
                np.linalg.solve(
                    normals[[i for i in range(dim + 1) if i != skip]],
                    offsets[[i for i in range(dim + 1) if i != skip]],
                )
                for skip in range(dim + 1)
            ]
        )
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
