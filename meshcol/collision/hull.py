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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.facet_distance import (
    closest_points_on_segments,
    distances_to_facets,
    rows_per_block,
)
from meshcol.collision.hull_budget import CONTAINS_RELATIVE_DISTANCE, _simplify, simplify_many
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
    "hulls_within_budgets",
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
    return _budgeted_result(exact, vertex_budget, q_vertices, distance)


def _budgeted_result(
    exact: ExactHull, vertex_budget: int, q_vertices: np.ndarray, distance: float
) -> HullResult:
    """The result of a simplified 3-D hull: the hull of ``q_vertices`` and what it added.
    Raises :class:`InvalidMeshError` when that hull does not contain the exact hull (to
    :data:`CONTAINS_RELATIVE_DISTANCE` of its diagonal): never a hull within the budget that
    lets the input out."""
    q = exact_hull(q_vertices)
    if (
        q.dimension != 3
        or _outside(exact.vertices, q) > CONTAINS_RELATIVE_DISTANCE * exact.diagonal
    ):
        raise InvalidMeshError(
            f"could not build a hull within {vertex_budget} vertices that contains the input"
        )
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


def _outside(points: np.ndarray, hull: ExactHull) -> float:
    """How far the farthest of ``points`` lies in front of a face plane of the 3-D ``hull``."""
    return float((points @ hull.equations[:, :3].T + hull.equations[:, 3]).max())


def hulls_within_budgets(
    exacts: Sequence[ExactHull],
    budgets: Sequence[tuple[int | None, int | None]],
    threads: int = 0,
) -> list[HullResult | InvalidMeshError]:
    """:func:`hull_within_budget` of many exact hulls, each with its own ``(max_vertices,
    max_planes)``, in order: the 3-D hulls past their budgets simplified in one native call
    (:func:`simplify_many`, ``threads`` over them; 0: all cores), the others as
    :func:`hull_within_budget` makes them. A hull that has none gets its error in its place
    (a budget under :data:`MIN_MAX_VERTICES` raises ``ValueError``, as there)."""
    results: list[HullResult | InvalidMeshError | None] = []
    over: list[tuple[int, int, int | None]] = []
    for i, (exact, (max_vertices, max_planes)) in enumerate(zip(exacts, budgets, strict=True)):
        _check_budgets(max_vertices, max_planes)
        if exact.dimension == 3:
            vertex_budget, plane_budget = _budgets(exact, max_vertices, max_planes)
            if vertex_budget is not None and not _fits(exact, vertex_budget, plane_budget):
                over.append((i, vertex_budget, plane_budget))
                results.append(None)
                continue
        try:
            results.append(hull_within_budget(exact, max_vertices, max_planes))
        except InvalidMeshError as exc:
            results.append(exc)
    bodies = [
        (e.vertices, e.vertices[e.faces], e.equations, budget, e.diagonal, planes)
        for e, budget, planes in ((exacts[i], b, p) for i, b, p in over)
    ]
    simplified: list[Any]
    try:
        simplified = simplify_many(bodies, threads)
    except InvalidMeshError:  # a loop that failed (never seen): the bodies one by one
        simplified = []
        for body in bodies:
            try:
                simplified.append(simplify_many([body], threads)[0])
            except InvalidMeshError as exc:
                simplified.append(exc)
    for (i, budget, _), made in zip(over, simplified, strict=True):
        try:
            if isinstance(made, InvalidMeshError):
                raise made
            results[i] = _budgeted_result(exacts[i], budget, *made)
        except InvalidMeshError as exc:
            results[i] = exc
    return results  # type: ignore[return-value]


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
