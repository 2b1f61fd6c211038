"""Convex hulls of point sets: exact (the core's Quickhull), or within a vertex budget and
still enclosing.

Every hull of meshcol is :func:`exact_hull`: collision shapes (:class:`ConvexSet` packs many
in one native call, :func:`pack_hulls`), ``meshcol hull``, decomposition parts and the start
of the budgeted hull. It runs in the C++ core (``cpp/src/quickhull.cpp``), which is why hulls
live in :mod:`meshcol.collision` and not in the numpy-only :mod:`meshcol.geometry`.

Physics engines cap the vertex count of a convex collider (PhysX 255, GPU pipelines 64).
:func:`convex_hull` returns the exact hull, or with ``max_vertices`` a hull with at most that
many vertices that still contains every input point: its faces are grown outward, never
pulled inward, so a simplified collider can only make contact earlier, never let an object
sink in.
"""

from __future__ import annotations

import enum
import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.facet_distance import (
    closest_points_on_segments,
    distances_to_facets,
    rows_per_block,
)
from meshcol.errors import InvalidMeshError
from meshcol.geometry.triangles import closest_points_on_triangles

__all__ = [
    "FLAT_RELATIVE_TOLERANCE",
    "MAX_ABS_COORDINATE",
    "MIN_MAX_VERTICES",
    "ExactHull",
    "HullResult",
    "HullStatus",
    "PackedHulls",
    "convex_hull",
    "distance_to_hull",
    "exact_hull",
    "hull_within_budget",
    "pack_hulls",
]


class HullStatus(enum.IntEnum):
    """What a point set's hull is.

    Mirrors ``HullStatus`` in ``cpp/include/meshcol/hull.hpp`` (bound as
    ``meshcol._core.HullStatus``; ``tests/test_native.py`` checks they match).
    """

    OK = 0  #: a 3-D polytope
    FLAT = 1  #: coplanar points (the flatness rule): a convex polygon
    COLLINEAR = 2  #: collinear points: a segment
    SINGLE_POINT = 3  #: all points coincide (within the flatness rule)
    EMPTY = 4  #: no points: no hull
    NON_FINITE = 5  #: a NaN or infinite coordinate: no hull
    OVERFLOW = 6  #: a coordinate beyond :data:`MAX_ABS_COORDINATE`: no hull
    FAILED = 7  #: its own consistency check failed (never seen), or over 2**31 - 1 points


#: The smallest vertex budget: a tetrahedron.
MIN_MAX_VERTICES = 4
#: The one flatness rule of meshcol. Points are flat (coplanar), collinear or one point when
#: their width across their best-fit plane (line) is at most this fraction of their
#: bounding-box diagonal: hulls, collision shapes, decomposition input and swept triangles
#: all decide with it (:attr:`ExactHull.dimension`). The core decides it: this mirrors its
#: ``defaults.flat_relative_tolerance`` (``tests/test_native.py`` checks they are equal; the
#: module stays importable without loading the core).
FLAT_RELATIVE_TOLERANCE = 1e-9
#: Hulls of coordinates beyond this magnitude are refused (:attr:`HullStatus.OVERFLOW`): their
#: volumes, products of three coordinates, would overflow double precision. Mirrors the
#: core's ``defaults.hull_max_abs_coordinate``.
MAX_ABS_COORDINATE = 1e100
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
    target_fit : TargetFit or None
        With an engine target (:func:`meshcol.collision.target_fit.fit_hull`): the fit this hull
        is, its measures, costs and violations.
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
    target_fit: Any = None

    @property
    def simplified(self) -> bool:
        """True when the budget forced a hull other than the exact one."""
        return self.max_distance > 0.0 or len(self.vertices) != self.exact_vertex_count


def convex_hull(
    points: np.ndarray, max_vertices: int | None = None, *, max_planes: int | None = None
) -> HullResult:
    """Convex hull of a point set, optionally with at most ``max_vertices`` vertices.

    Parameters
    ----------
    points : (n, 3) float
        Input points (e.g. a mesh's vertices), in any frame; the result is in the same frame.
    max_vertices : int, optional
        Vertex budget (>= 4). The result then has at most this many vertices and still
        contains every input point.
    max_planes : int, optional
        At most this many face planes (polygons, once coplanar triangles are merged) in the
        simplified hull (>= 4); the exact hull is kept only when it has at most
        ``max_vertices`` vertices and at most ``max_planes`` triangles (each plane holds one
        at least), else the hull is simplified within both budgets (``max_vertices``
        defaulting to the exact hull's count). Ignored for flat input.

    Returns
    -------
    HullResult

    Raises
    ------
    InvalidMeshError
        No points, non-finite coordinates, coordinates beyond :data:`MAX_ABS_COORDINATE`, or
        points that span no area (one point or collinear): there is no meaningful hull.
    ValueError
        ``points`` is not (n, 3) or ``max_vertices`` < 4.

    Notes
    -----
    The exact hull is :func:`exact_hull` (Quickhull in the core). Coplanar points give a 2-D
    hull, a polygon in their plane.

    The budgeted hull (:func:`_simplify`, whose docstring gives the steps) is built from
    supporting planes of the exact hull H (planes touching H with H on their inner side), so
    it always encloses H, and thus every input point. Each step cuts the vertex of the
    current polytope farthest from H by the supporting plane nearest it, the plane-based
    "grow the faces outward" scheme of engine cookers driven by the Hausdorff distance. The
    reported ``max_distance`` is exact: the distance to a convex set is a convex function, so
    its maximum over the polytope is reached at one of its vertices.
    """
    pts = _checked_points(points, max_vertices, max_planes)
    return hull_within_budget(exact_hull(pts), max_vertices, max_planes)


def hull_within_budget(
    exact: ExactHull, max_vertices: int | None = None, max_planes: int | None = None
) -> HullResult:
    """:func:`convex_hull` of points whose exact hull is ``exact`` (budgets as there): for a
    caller that holds the exact hull already."""
    _check_budgets(max_vertices, max_planes)
    if exact.dimension == 0:
        raise InvalidMeshError("all vertices coincide: there is no meaningful hull")
    if exact.dimension == 1:
        raise InvalidMeshError("all vertices are collinear: there is no meaningful hull")
    if exact.dimension == 2:
        return _flat_hull(exact, max_vertices)
    vertex_budget, plane_budget = _budgets(exact, max_vertices, max_planes)
    if vertex_budget is None or _fits(exact, vertex_budget, plane_budget):
        return _exact_result(exact, vertex_budget)
    return _simplified_result(exact, vertex_budget, plane_budget)


def _checked_points(
    points: np.ndarray, max_vertices: int | None, max_planes: int | None
) -> np.ndarray:
    """The points as (n, 3) float64, the budgets checked (ValueError names the argument)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), got {pts.shape}")
    _check_budgets(max_vertices, max_planes)
    return pts


def _check_budgets(max_vertices: int | None, max_planes: int | None) -> None:
    if max_vertices is not None and int(max_vertices) < MIN_MAX_VERTICES:
        raise ValueError(f"max_vertices must be >= {MIN_MAX_VERTICES}, got {max_vertices}")
    if max_planes is not None and int(max_planes) < MIN_MAX_VERTICES:
        raise ValueError(f"max_planes must be >= {MIN_MAX_VERTICES}, got {max_planes}")


def _budgets(
    exact: ExactHull, max_vertices: int | None, max_planes: int | None
) -> tuple[int | None, int | None]:
    """The vertex and plane budgets of a 3-D hull; a plane budget alone keeps the exact
    hull's vertex count (at least :data:`MIN_MAX_VERTICES`) as the vertex budget."""
    plane_budget = None if max_planes is None else int(max_planes)
    if max_vertices is not None:
        return int(max_vertices), plane_budget
    if plane_budget is not None:
        return max(len(exact.vertices), MIN_MAX_VERTICES), plane_budget
    return None, None


def _fits(exact: ExactHull, vertex_budget: int, plane_budget: int | None) -> bool:
    """Whether the exact hull is within the budgets (each plane holds a triangle at least)."""
    planes_fit = plane_budget is None or len(exact.faces) <= plane_budget
    return len(exact.vertices) <= vertex_budget and planes_fit


def _exact_summary(exact: ExactHull, vertex_budget: int | None) -> dict[str, Any]:
    """The fields of a 3-D :class:`HullResult` that describe the exact hull and the budget."""
    return dict(
        flat=False,
        exact_vertex_count=len(exact.vertices),
        exact_face_count=len(exact.faces),
        exact_volume=exact.volume,
        max_vertices=vertex_budget,
    )


def _exact_result(exact: ExactHull, vertex_budget: int | None) -> HullResult:
    """The exact 3-D hull as the result (its own copy of the arrays)."""
    return HullResult(
        vertices=exact.vertices.copy(),
        faces=exact.faces.copy(),
        volume=exact.volume,
        area=exact.area,
        added_volume_fraction=0.0 if vertex_budget is not None else None,
        **_exact_summary(exact, vertex_budget),
    )


def _simplified_result(
    exact: ExactHull, vertex_budget: int, plane_budget: int | None
) -> HullResult:
    """The supporting-plane hull within the budgets (:func:`_simplify`), with what it added."""
    q_vertices, distance = _simplify(
        exact.vertices,
        exact.vertices[exact.faces],
        exact.equations,
        vertex_budget,
        exact.diagonal,
        max_planes=plane_budget,
    )
    q = exact_hull(q_vertices)
    added = max(q.volume - exact.volume, 0.0)
    return HullResult(
        vertices=q.vertices,
        faces=q.faces,
        volume=q.volume,
        area=q.area,
        added_volume=added,
        added_volume_fraction=added / exact.volume,
        max_distance=distance,
        **_exact_summary(exact, vertex_budget),
    )


# ---------------------------------------------------------------------------------------
# exact hulls


@dataclass(frozen=True, eq=False)
class ExactHull:
    """The exact convex hull of a point set, in every dimension it can have.

    Attributes
    ----------
    status : HullStatus
        OK (3-D), FLAT, COLLINEAR or SINGLE_POINT (the points without a hull raise).
    dimension : int
        0 (one point), 1 (collinear), 2 (coplanar) or 3, by :data:`FLAT_RELATIVE_TOLERANCE`.
    vertices : (k, 3) float64
        The hull's vertices, a subset of the input points (``-0.0`` as ``0.0``). In 3-D they
        are in lexicographic order; in 2-D they are the polygon's ring, counter-clockwise about
        ``normal``; in 1-D the segment's two ends; in 0-D the lexicographically smallest point.
    indices : (k,) int64
        Rows of the input points that ``vertices`` are.
    faces : (m, 3) int64
        3-D: triangles wound counter-clockwise seen from outside. 2-D: a fan triangulation of
        the ring (one side). Empty otherwise.
    equations : (m, 4) float64
        3-D: each face's outward plane ``n . x + c = 0`` (unit ``n``). Empty otherwise.
    normal : (3,) float64
        2-D: the unit normal of the polygon's plane. Zero otherwise.
    volume, area : float
        Enclosed volume (0 below 3-D) and surface area (2-D: the polygon's area, one side).
    diagonal : float
        Bounding-box diagonal of the input points (the scale of the tolerances).
    """

    status: HullStatus
    dimension: int
    vertices: np.ndarray
    indices: np.ndarray
    faces: np.ndarray
    equations: np.ndarray
    normal: np.ndarray
    volume: float
    area: float
    diagonal: float


def _no_hull(status: HullStatus, points: np.ndarray) -> InvalidMeshError:
    """The error for points that have no hull (one line, naming the offending value)."""
    if status == HullStatus.EMPTY:
        return InvalidMeshError("mesh has no vertices: there is no hull")
    if status == HullStatus.NON_FINITE:
        return InvalidMeshError("vertices contain NaN or infinite coordinates")
    if status == HullStatus.OVERFLOW:
        value = float(points.flat[int(np.argmax(np.abs(points)))])
        return InvalidMeshError(
            f"vertex coordinate {value:g} is beyond +-{MAX_ABS_COORDINATE:g}: "
            "hull volumes would overflow"
        )
    return InvalidMeshError("the hull failed its consistency check (please report this input)")


def exact_hull(points: Any) -> ExactHull:
    """The exact convex hull of points, flat and degenerate inputs included.

    Parameters
    ----------
    points : (n, 3) float
        Any frame; the hull is in the same frame.

    Returns
    -------
    ExactHull

    Raises
    ------
    InvalidMeshError
        No points, a NaN or infinite coordinate, or one beyond :data:`MAX_ABS_COORDINATE`.
    ValueError
        ``points`` is not (n, 3).

    Notes
    -----
    Quickhull (Barber, Dobkin and Huhdanpaa 1996) in the core (``cpp/src/quickhull.cpp``),
    GIL released. The dimension comes from the one flatness rule
    (:data:`FLAT_RELATIVE_TOLERANCE`, principal widths against the bounding-box diagonal);
    coplanar points get a polygon (Andrew's monotone chain in their plane). Which faces a new
    point sees is decided by exact orientation signs (Shewchuk 1997), so the polytope stays
    convex and its topology consistent on any input; a point within
    ``defaults.hull_relative_tolerance`` times the largest absolute coordinate of a face's
    plane is on the hull (qhull's coplanar points), and vertices left on an edge or inside a
    face by such ties are removed. The vertex set matches qhull's (``tests/collision/test_exact_hull.py``).
    """
    from meshcol._native import core

    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), got {pts.shape}")
    status, dimension, indices, faces, equations, normal, volume, area, diagonal = core.exact_hull(
        pts
    )
    status = HullStatus(status)
    if dimension < 0:
        raise _no_hull(status, pts)
    return ExactHull(
        status,
        int(dimension),
        pts[indices] + 0.0,
        indices,
        faces,
        equations,
        normal,
        float(volume),
        float(area),
        float(diagonal),
    )


@dataclass(frozen=True, eq=False)
class PackedHulls:
    """The hulls of many point sets as the arrays of a :class:`ConvexSet`'s polytopes.

    ``status`` (H,) int8 holds a :class:`HullStatus` per set; a set without a hull keeps its
    points as given, with no adjacency and no features (queries report INVALID_INPUT when
    it has no points or NaN, and scan the points otherwise).
    The other fields are those of :class:`meshcol.collision.shapes.ConvexSet`.
    """

    status: np.ndarray
    vertices: np.ndarray
    offsets: np.ndarray
    adjacency_offsets: np.ndarray
    adjacency: np.ndarray
    face_offsets: np.ndarray
    face_normals: np.ndarray
    edge_pair_offsets: np.ndarray
    edge_pairs: np.ndarray
    climb_list_offsets: np.ndarray
    climb_lists: np.ndarray

    def __getstate__(self) -> dict[str, Any]:
        # The packing's seal (pack_hull_slices) vouches for these arrays in this process only:
        # a copy or an unpickled packing is checked like any other arrays.
        state = dict(self.__dict__)
        state.pop("_seal", None)
        return state


def pack_hulls(point_sets: Sequence[np.ndarray] | np.ndarray, threads: int = 0) -> PackedHulls:
    """Exact hulls of many point sets, packed for the narrow phase in one native call.

    Parameters
    ----------
    point_sets : sequence of (n_i, 3) float64, or (H, n, 3) float
        Already validated point arrays (:func:`meshcol.collision.arrays.as_points`).
    threads : int
        Threads over sets (0: all cores).

    Returns
    -------
    PackedHulls

    Notes
    -----
    Per set, the hull of :func:`exact_hull` and, in the same pass: the neighbours of each
    vertex in the hull's triangulation (ascending, padded with the vertex itself to a multiple
    of four for the core's hill climbing), one outward normal per plane, and the true edges
    (triangulation edges between different planes, as local vertex index pairs), the features
    exact SAT needs; and the same neighbour lists at a fixed stride for the climbs (the
    ``climb_lists`` of a :class:`ConvexSet`). Flat sets give their polygon, its two normals and its edges; collinear
    sets their segment; single points the point. The edges' direction classes (one unit
    direction per class of parallel edges, unsigned, grouped at 12 digits) are not packed: a
    :class:`ConvexSet` computes each shape's when SAT first needs them, or all of them when
    its ``edge_directions`` are first read.
    """
    if isinstance(point_sets, np.ndarray) and point_sets.ndim == 3:
        h, n = point_sets.shape[:2]
        points = np.ascontiguousarray(point_sets, dtype=np.float64).reshape(-1, 3)
        offsets = np.arange(h + 1, dtype=np.int64) * n
    else:
        counts = np.fromiter((len(p) for p in point_sets), dtype=np.int64, count=len(point_sets))
        offsets = np.zeros(len(counts) + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        points = (
            np.ascontiguousarray(np.concatenate(point_sets), dtype=np.float64)
            if len(point_sets)
            else np.zeros((0, 3))
        )
    return pack_hull_slices(points, offsets, threads)


def pack_hull_slices(points: np.ndarray, offsets: np.ndarray, threads: int = 0) -> PackedHulls:
    """:func:`pack_hulls` of point sets already packed: set ``h`` is
    ``points[offsets[h]:offsets[h + 1]]``, ``points`` (V, 3) float64 C-contiguous and
    ``offsets`` (H + 1,) int64 (a reader's arrays, no copy per set)."""
    from meshcol._native import core

    made = core.pack_polytopes(points, offsets, int(threads))
    packed, seal = PackedHulls(*made[:11]), made[11]
    # The core's word that the index arrays are the ones it wrote, which a ConvexSet made from
    # them passes back instead of reading every index again. Not a field (the fields are the
    # arrays); the arrays it vouches for are read-only from here on, as a ConvexSet's are.
    for index in (
        packed.adjacency_offsets,
        packed.adjacency,
        packed.edge_pairs,
        packed.climb_lists,
    ):
        index.setflags(write=False)
    object.__setattr__(packed, "_seal", seal)
    return packed


def _flat_hull(exact: ExactHull, max_vertices: int | None) -> HullResult:
    """The 2-D hull of coplanar points as a fan-triangulated polygon, within a budget."""
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
    q = exact_hull(centre + q_coords @ plane_axes)
    q_ring = q.vertices if q.normal @ exact.normal >= 0 else q.vertices[::-1]
    return HullResult(
        vertices=q_ring,
        faces=_fan(len(q_ring)),
        area=q.area,
        max_distance=distance,
        **kwargs,
    )


def _fan(n: int) -> np.ndarray:
    """Fan triangulation of a convex polygon with ``n`` vertices in order."""
    i = np.arange(1, n - 1, dtype=np.int64)
    return np.stack([np.zeros_like(i), i, i + 1], axis=1)


# ---------------------------------------------------------------------------------------
# budgeted hulls (dimension-generic: 3-D, or 2-D for flat input)


def _simplify(hull_vertices, facets, equations, budget, scale, max_planes=None):
    """Supporting-plane polytope with <= ``budget`` vertices (and, with ``max_planes``, at
    most that many planes) around the exact hull.

    ``hull_vertices`` (k, d) are the exact hull's vertices, ``facets`` (m, d, d) its facet
    simplices and ``equations`` (m, d + 1) their outward planes ``n . x + c = 0``.
    Returns the polytope's vertices (q, d) and its exact distance to the hull.

    The steps, with H the exact hull and Q the polytope:

    1. Start from the smallest of ``START_ORIENTATIONS`` simplices (tetrahedron, or triangle
       when flat) whose faces are supporting planes of H.
    2. Find the vertex v of Q farthest from H, with its closest point p on H (exact
       point-to-facet distances over the facets of H that v sees).
    3. Add the supporting plane at p with normal ``(v - p) / |v - p|``: it is the cut that
       removes v most deeply. Recompute Q as the intersection of the half-spaces
       (``scipy.spatial.HalfspaceIntersection``, interior point: the centroid of H's vertices).
    4. Keep the cut if Q still has at most ``budget`` vertices (else try the next farthest
       vertices, up to ``CUT_CANDIDATES``), and repeat from 2 until no cut fits or Q is within
       ``CONVERGED_RELATIVE_DISTANCE`` of H.

    Each step reduces the largest deviation where it is. The loop runs in Python on top of
    the native exact hull (a few cuts, each a half-space intersection).
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
        raise InvalidMeshError(f"could not build a hull within {budget} vertices")
    distances, closest = distances_to_facets(polytope, facets, equations)
    for _ in range(4 * budget + 16):
        if max_planes is not None and len(normals) >= max_planes:
            break
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
    distances, _ = distances_to_facets(polytope, facets, equations)
    return polytope, float(distances.max())


def distance_to_hull(points: np.ndarray, hull: ExactHull) -> np.ndarray:
    """Distance from each point to the solid of an exact hull (0 inside).

    Parameters
    ----------
    points : (n, 3) float
        Same frame as the hull.
    hull : ExactHull
        Any dimension: a polytope, a polygon, a segment or a point.

    Returns
    -------
    (n,) float64
        Exact Euclidean distances.

    Notes
    -----
    3-D: only the facets whose plane a point lies in front of are searched (the closest point
    of a convex polytope to an outside point is on such a facet), as the budget loop of
    :func:`convex_hull` does. A polygon: its fan triangles; a segment or a point: directly.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    v = hull.vertices
    if hull.dimension == 3:
        equations = (
            np.ascontiguousarray(hull.equations[:, :3].T),
            np.ascontiguousarray(hull.equations[:, 3]),
        )
        facets, step = v[hull.faces], rows_per_block(len(hull.faces))
        if len(pts) <= step:
            return distances_to_facets(pts, facets, equations)[0]
        parts = [
            distances_to_facets(pts[start : start + step], facets, equations)[0]
            for start in range(0, len(pts), step)
        ]
        return np.concatenate(parts)
    if hull.dimension == 2:
        triangles = v[hull.faces]
        best = np.full(len(pts), np.inf)
        for triangle in triangles:
            closest = closest_points_on_triangles(pts, np.broadcast_to(triangle, (len(pts), 3, 3)))
            best = np.minimum(best, np.linalg.norm(closest - pts, axis=1))
        return best
    if hull.dimension == 1:
        segment = np.broadcast_to(v[:2], (len(pts), 2, 3))
        return np.linalg.norm(closest_points_on_segments(pts, segment) - pts, axis=1)
    return np.linalg.norm(pts - v[0], axis=1)


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
        distances[~known], closest[~known] = distances_to_facets(new[~known], facets, equations)
    return distances, closest


def _start_simplex(hull_vertices: np.ndarray) -> np.ndarray:
    """Unit normals (d + 1, d) of the smallest of several supporting regular-simplex shapes."""
    dim = hull_vertices.shape[1]
    normals, skips = _start_orientations(dim)
    offsets = (normals @ hull_vertices.T).max(axis=2)  # (orientations, d + 1)
    # each simplex's corners at once: corner k solves the planes but plane k
    corners = np.linalg.solve(normals[:, skips], offsets[:, skips, None])[..., 0]
    sizes = np.abs(np.linalg.det(corners[:, 1:] - corners[:, :1]))
    return normals[int(np.argmin(sizes))]


@functools.cache
def _start_orientations(dim: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``START_ORIENTATIONS`` turned regular simplices' unit normals (orientations, d + 1,
    d), the first unturned, and the planes (d + 1, d) each corner lies on (all but one)."""
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
    normals = np.stack([base @ rotation.T for rotation in rotations])
    skips = np.array([[i for i in range(dim + 1) if i != skip] for skip in range(dim + 1)])
    normals.flags.writeable = False
    return normals, skips


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
    from scipy.spatial import cKDTree

    from meshcol.geometry.graph import connected_components

    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return points
    n = len(points)
    _, labels = connected_components(n, pairs)
    # keep, per cluster, the point farthest from the centroid: the merged polytope then
    # still contains the cluster up to ``radius``
    centroid = points.mean(axis=0)
    reach = np.linalg.norm(points - centroid, axis=1)
    order = np.lexsort((-reach, labels))
    first = np.ones(n, bool)
    first[1:] = labels[order][1:] != labels[order][:-1]
    return points[order[first]]
