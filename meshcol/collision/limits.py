"""Engine limits of convex parts: measured once, for everybody, and met by enclosing hulls.

:func:`measure_parts` is the one measurement of what engines limit (vertices, triangles,
polygons after merging coplanar triangles, polygons meeting at a vertex, the oblong ratio,
the thickness and the volume of each part); :func:`limit_violations` compares measures with
a target's limits (the keys of :mod:`meshcol.io.targets`, the rule ids of
:data:`RULES`). :func:`fit_hull` and :func:`fit_parts` build parts that meet every limit
and still enclose their input: hulls are only ever grown (a thin part thickened, a flat one
given a volume) or simplified by supporting planes (:func:`meshcol.collision.hull.convex_hull`),
never pulled inward; what each limit cost is measured against the exact hull of the input.

The target is duck-typed (an object with a ``limits`` mapping, or the mapping itself), so
that this layer stays free of :mod:`meshcol.io`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.collision.hull import (
    ExactHull,
    convex_hull,
    distance_to_hull,
    exact_hull,
)
from meshcol.errors import InvalidMeshError

__all__ = [
    "APPLY_ORDER",
    "COPLANAR_RELATIVE_TOLERANCE",
    "RULES",
    "LimitCost",
    "PartMeasures",
    "TargetFit",
    "Violation",
    "budget_vertices",
    "fit_hull",
    "fit_parts",
    "limit_violations",
    "measure_hull",
    "measure_parts",
    "merge_groups",
    "polygon_labels",
    "scaled_limits",
]

#: Limit key -> (rule id, rule name): the ids are stable forever (registered by ``meshcol rules``).
RULES: dict[str, tuple[str, str]] = {
    "max_hull_vertices": ("MC101", "hull-vertices-over-limit"),
    "max_oblong_ratio": ("MC102", "not-gpu-compatible-oblong"),
    "max_hull_polygons": ("MC103", "hull-polygons-over-limit"),
    "max_hull_triangles": ("MC104", "hull-triangles-over-limit"),
    "max_faces_per_vertex": ("MC105", "faces-per-vertex-over-limit"),
    "max_hulls": ("MC106", "hull-count-over-limit"),
    "min_thickness": ("MC107", "part-too-thin"),
    "min_volume": ("MC201", "volume-too-small"),
}
#: The order :func:`fit_parts` meets limits in (merging, growth, then the count budgets),
#: which is the order the marginal costs are measured in (:class:`LimitCost`).
APPLY_ORDER = (
    "max_hulls",
    "min_thickness",
    "min_volume",
    "max_oblong_ratio",
    "max_hull_vertices",
    "max_hull_triangles",
    "max_hull_polygons",
    "max_faces_per_vertex",
)
#: Two adjacent hull triangles are one polygon when each one's far vertex is within this
#: fraction of the part's bounding-box diagonal of the other's plane (and their normals agree).
COPLANAR_RELATIVE_TOLERANCE = 1e-9
#: Growth rounds (thickness, volume, oblong ratio) and budget rounds tried before a limit is
#: declared unmet.
GROWTH_ROUNDS = 12
BUDGET_ROUNDS = 8
#: Relative slack of the >= tests on lengths and volumes (rounding of grown coordinates).
GROWTH_SLACK = 1e-9


# ---------------------------------------------------------------------------------------
# measurement


@dataclass(frozen=True, eq=False)
class PartMeasures:
    """What engines limit, one row per part (arrays of equal length).

    Attributes
    ----------
    vertices : (p,) int64
        Vertices of the part's convex hull (what an engine cooks from its points).
    triangles : (p,) int64
        Triangles of the hull (``2 * vertices - 4`` for a polytope).
    polygons : (p,) int64
        Faces after merging coplanar adjacent triangles (:func:`polygon_labels`).
    max_faces_per_vertex : (p,) int64
        The most polygons meeting at one vertex.
    oblong_ratio : (p,) float64
        Largest distance from the in-sphere centre to a vertex over the in-sphere radius
        (>= 1; ``inf`` for a part without volume).
    inradius : (p,) float64
        Radius of the largest ball inside the part (Chebyshev centre of its half-spaces).
    thickness : (p,) float64
        Smallest width of the part across one of its face planes (0 when flat). Input units.
    volume : (p,) float64
        Volume of the hull. Input units cubed.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    polygons: np.ndarray
    max_faces_per_vertex: np.ndarray
    oblong_ratio: np.ndarray
    inradius: np.ndarray
    thickness: np.ndarray
    volume: np.ndarray

    def __len__(self) -> int:
        return len(self.vertices)

    def row(self, i: int) -> dict[str, Any]:
        """Part ``i`` as a JSON-ready dict (``oblong_ratio`` None when infinite)."""
        ratio = float(self.oblong_ratio[i])
        return {
            "vertices": int(self.vertices[i]),
            "triangles": int(self.triangles[i]),
            "polygons": int(self.polygons[i]),
            "max_faces_per_vertex": int(self.max_faces_per_vertex[i]),
            "oblong_ratio": ratio if np.isfinite(ratio) else None,
            "inradius": float(self.inradius[i]),
            "thickness": float(self.thickness[i]),
            "volume": float(self.volume[i]),
        }


def polygon_labels(vertices: np.ndarray, faces: np.ndarray, tolerance: float) -> np.ndarray:
    """Label of the polygon each triangle of a closed convex mesh belongs to.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        A closed, consistently wound triangle mesh (a hull); several meshes may be given at
        once with disjoint vertex ranges.
    tolerance : float or (m,) float
        Largest distance of a triangle's far vertex from its neighbour's plane for the two
        to be coplanar (absolute, input units; per triangle for several meshes).

    Returns
    -------
    (m,) int64
        Labels 0..k-1, one per polygon (connected coplanar triangles).

    Notes
    -----
    Triangles sharing an edge are paired by sorting their undirected edges; a pair is
    coplanar when both far vertices lie within ``tolerance`` of the other's plane and the
    normals point the same way. Polygons are the connected components of the coplanar pairs
    (``scipy.sparse.csgraph``), all vectorised.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    faces = np.asarray(faces, dtype=np.int64)
    m = len(faces)
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    v = np.asarray(vertices, dtype=np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    normals = np.cross(b - a, c - a)
    lengths = np.linalg.norm(normals, axis=1)
    normals = normals / np.where(lengths > 0, lengths, 1.0)[:, None]
    # edge k of face f is (faces[f, k], faces[f, (k + 1) % 3]); its far vertex faces[f, k + 2]
    starts = faces.reshape(-1)
    ends = faces[:, [1, 2, 0]].reshape(-1)
    far = faces[:, [2, 0, 1]].reshape(-1)
    owner = np.repeat(np.arange(m), 3)
    keys = np.stack([np.minimum(starts, ends), np.maximum(starts, ends)], axis=1)
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    keys, owner, far = keys[order], owner[order], far[order]
    same = (keys[1:] == keys[:-1]).all(axis=1)
    first = np.nonzero(same)[0]
    f1, f2 = owner[first], owner[first + 1]
    v1, v2 = far[first], far[first + 1]  # v1 is a vertex of f1, v2 of f2
    tol = np.broadcast_to(np.asarray(tolerance, dtype=np.float64), (m,))
    limit = np.minimum(tol[f1], tol[f2])
    d12 = np.abs(np.einsum("ij,ij->i", v[v2] - v[faces[f1, 0]], normals[f1]))
    d21 = np.abs(np.einsum("ij,ij->i", v[v1] - v[faces[f2, 0]], normals[f2]))
    coplanar = (
        (d12 <= limit) & (d21 <= limit) & (np.einsum("ij,ij->i", normals[f1], normals[f2]) > 0)
    )
    graph = coo_matrix((np.ones(int(coplanar.sum())), (f1[coplanar], f2[coplanar])), shape=(m, m))
    _, labels = connected_components(graph, directed=False)
    return labels.astype(np.int64)


def _inscribed_ball(normals: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the largest ball in ``{x : normals @ x + offsets <= 0}`` (unit
    normals): the Chebyshev centre, a linear programme (HiGHS)."""
    from scipy.optimize import linprog

    a_ub = np.hstack([normals, np.ones((len(normals), 1))])
    result = linprog(
        c=[0.0, 0.0, 0.0, -1.0],
        A_ub=a_ub,
        b_ub=-offsets,
        bounds=[(None, None)] * 3 + [(0.0, None)],
        method="highs",
    )
    if result.status != 0:  # never seen for a bounded polytope; never crash on it
        return np.zeros(3), 0.0
    return np.asarray(result.x[:3]), float(max(result.x[3], 0.0))


def measure_hull(hull: ExactHull) -> dict[str, Any]:
    """The measures of one exact hull (:class:`PartMeasures`' fields, plus ``normals``:
    the unit normals of its polygons, and ``thin_normal``: the direction of its thickness).
    Lower-dimensional hulls (flat, collinear, a point) get thickness and volume 0."""
    k = len(hull.vertices)
    if hull.dimension < 3:
        thin = hull.normal if hull.dimension == 2 else np.zeros(3)
        return {
            "vertices": k,
            "triangles": len(hull.faces),
            "polygons": 1 if hull.dimension == 2 else 0,
            "max_faces_per_vertex": 1 if hull.dimension == 2 else 0,
            "oblong_ratio": np.inf,
            "inradius": 0.0,
            "thickness": 0.0,
            "volume": 0.0,
            "normals": thin[None, :] if hull.dimension == 2 else np.zeros((0, 3)),
            "thin_normal": thin,
        }
    tolerance = COPLANAR_RELATIVE_TOLERANCE * max(hull.diagonal, 1e-300)
    labels = polygon_labels(hull.vertices, hull.faces, tolerance)
    polygons = int(labels.max()) + 1
    pairs = np.unique(np.stack([hull.faces.reshape(-1), np.repeat(labels, 3)], axis=1), axis=0)
    per_vertex = np.bincount(pairs[:, 0], minlength=k)
    # one plane per polygon: its largest triangle's equation (the most accurate normal)
    v = hull.vertices
    areas = np.linalg.norm(
        np.cross(
            v[hull.faces[:, 1]] - v[hull.faces[:, 0]], v[hull.faces[:, 2]] - v[hull.faces[:, 0]]
        ),
        axis=1,
    )
    order = np.lexsort((-areas, labels))
    lead = order[np.r_[True, labels[order][1:] != labels[order][:-1]]]
    planes = hull.equations[lead]
    normals, offsets = planes[:, :3], planes[:, 3]
    projections = normals @ v.T
    widths = projections.max(axis=1) - projections.min(axis=1)
    thinnest = int(np.argmin(widths))
    centre, radius = _inscribed_ball(normals, offsets)
    reach = float(np.linalg.norm(v - centre, axis=1).max())
    return {
        "vertices": k,
        "triangles": len(hull.faces),
        "polygons": polygons,
        "max_faces_per_vertex": int(per_vertex.max()),
        "oblong_ratio": reach / radius if radius > 0 else np.inf,
        "inradius": radius,
        "thickness": float(widths[thinnest]),
        "volume": float(hull.volume),
        "normals": normals,
        "thin_normal": normals[thinnest],
    }


_MEASURE_FIELDS = (
    "vertices",
    "triangles",
    "polygons",
    "max_faces_per_vertex",
    "oblong_ratio",
    "inradius",
    "thickness",
    "volume",
)


def measure_parts(parts: Sequence[tuple[Any, Any]]) -> PartMeasures:
    """Measure convex parts as an engine sees them: the exact hull of each part's vertices.

    Parameters
    ----------
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        The parts' vertices and faces (the faces are not used: engines cook the hull of the
        points, and so does this).

    Returns
    -------
    PartMeasures

    Raises
    ------
    InvalidMeshError
        A part without vertices, or with a non-finite coordinate.

    Notes
    -----
    Each part's hull is the core's exact hull (:func:`meshcol.collision.hull.exact_hull`);
    polygons by :func:`polygon_labels`; the in-sphere is the Chebyshev centre of the
    polygons' half-spaces (a linear programme, ``scipy.optimize.linprog``); the oblong ratio
    is the farthest vertex from that centre over its radius; the thickness is the smallest
    width over the polygons' normals, which is the exact minimum width of a part whose
    thinnest direction is face-to-vertex (slabs, boxes, plates) and an upper bound, at most
    about 15% above, when it is edge-to-edge (a tetrahedron).
    """
    rows = [measure_hull(exact_hull(np.asarray(v, dtype=np.float64))) for v, _ in parts]
    columns = {
        name: np.array(
            [row[name] for row in rows],
            dtype=np.float64
            if name in ("oblong_ratio", "inradius", "thickness", "volume")
            else np.int64,
        )
        for name in _MEASURE_FIELDS
    }
    if not rows:
        columns = {
            name: np.zeros(
                0,
                dtype=np.float64
                if name in ("oblong_ratio", "inradius", "thickness", "volume")
                else np.int64,
            )
            for name in _MEASURE_FIELDS
        }
    return PartMeasures(**columns)


# ---------------------------------------------------------------------------------------
# limits


@dataclass(frozen=True)
class Violation:
    """One limit a part (or a body's part count) is past.

    Attributes
    ----------
    limit : str
        The limit key (``max_hull_vertices``, ...).
    part : int or None
        The part, or None for a body's part count (``max_hulls``).
    measured : float
        What was measured (the unit of the limit: a count, input units, input units cubed).
    threshold : float
        The limit, in the same unit (lengths and volumes converted to the input's units).
    """

    limit: str
    part: int | None
    measured: float
    threshold: float

    @property
    def rule(self) -> str:
        """The rule id (``MC101``)."""
        return RULES[self.limit][0]

    @property
    def rule_name(self) -> str:
        """The rule name (``hull-vertices-over-limit``)."""
        return RULES[self.limit][1]

    @property
    def message(self) -> str:
        """One line: what is past which limit."""
        where = "the body" if self.part is None else f"part {self.part}"
        if self.limit.startswith("min_"):
            return f"{where}: {self.limit} {self.measured:.6g} < {self.threshold:.6g}"
        measured = "inf" if not np.isfinite(self.measured) else f"{self.measured:.6g}"
        return f"{where}: {self.limit} {measured} > {self.threshold:.6g}"

    def to_dict(self) -> dict[str, Any]:
        measured = float(self.measured)
        return {
            "rule": self.rule,
            "rule_name": self.rule_name,
            "limit": self.limit,
            "part": self.part,
            "measured": measured if np.isfinite(measured) else None,
            "threshold": float(self.threshold),
            "message": self.message,
        }


def _limits_of(target: Any) -> Mapping[str, float]:
    return target if isinstance(target, Mapping) else target.limits


def scaled_limits(target: Any, length_scale: float = 1.0) -> dict[str, float]:
    """A target's limits in the input's units: ``min_thickness`` times ``length_scale``
    (input units per metre), ``min_volume`` times its cube; counts unchanged."""
    limits = dict(_limits_of(target))
    if "min_thickness" in limits:
        limits["min_thickness"] = float(limits["min_thickness"]) * length_scale
    if "min_volume" in limits:
        limits["min_volume"] = float(limits["min_volume"]) * length_scale**3
    return limits


_PART_LIMITS = {
    "max_hull_vertices": "vertices",
    "max_hull_polygons": "polygons",
    "max_hull_triangles": "triangles",
    "max_faces_per_vertex": "max_faces_per_vertex",
    "max_oblong_ratio": "oblong_ratio",
}


def limit_violations(
    target: Any, measures: PartMeasures, part_count: int, length_scale: float = 1.0
) -> list[Violation]:
    """Every limit of ``target`` the parts are past, part by part, in limit-key order.

    Parameters
    ----------
    target : Target or mapping
        :class:`meshcol.io.targets.Target`, or its ``limits`` mapping.
    measures : PartMeasures
        From :func:`measure_parts`.
    part_count : int
        The body's convex parts (for ``max_hulls``).
    length_scale : float
        Input units per metre (:meth:`meshcol.io.targets.Target.length_scale`): the profile's
        ``min_thickness`` (m) and ``min_volume`` (m^3) are converted with it.

    Returns
    -------
    list of Violation
        ``min_thickness`` and ``min_volume`` are met within a relative ``1e-9`` (grown
        coordinates round).
    """
    limits = scaled_limits(target, length_scale)
    found: list[Violation] = []
    if "max_hulls" in limits and part_count > limits["max_hulls"]:
        found.append(Violation("max_hulls", None, float(part_count), float(limits["max_hulls"])))
    for key, name in _PART_LIMITS.items():
        if key in limits:
            values = getattr(measures, name)
            for i in np.nonzero(values > limits[key])[0]:
                found.append(Violation(key, int(i), float(values[i]), float(limits[key])))
    for key, name in (("min_thickness", "thickness"), ("min_volume", "volume")):
        if key in limits and limits[key] > 0:
            values = getattr(measures, name)
            for i in np.nonzero(values < limits[key] * (1 - GROWTH_SLACK))[0]:
                found.append(Violation(key, int(i), float(values[i]), float(limits[key])))
    order = {key: n for n, key in enumerate(RULES)}
    found.sort(key=lambda v: (-1 if v.part is None else v.part, order[v.limit]))
    return found


def budget_vertices(limits: Mapping[str, float]) -> int | None:
    """The vertex budget the limits allow: ``max_hull_vertices``, and ``(T + 4) // 2`` for
    ``max_hull_triangles`` T (a triangulated polytope of V vertices has 2V - 4 triangles)."""
    budgets = []
    if "max_hull_vertices" in limits:
        budgets.append(int(limits["max_hull_vertices"]))
    if "max_hull_triangles" in limits:
        budgets.append((int(limits["max_hull_triangles"]) + 4) // 2)
    return max(min(budgets), 4) if budgets else None


# ---------------------------------------------------------------------------------------
# fitting


@dataclass(frozen=True)
class LimitCost:
    """What meeting one limit cost a body (measured against the exact hull of its input).

    Two figures, which answer different questions:

    - **marginal** (``marginal_added_volume``): the limits are applied one more at a time in
      :data:`APPLY_ORDER`; a limit's marginal cost is the volume the fit with it and every
      limit before it adds over the fit without it. The marginal costs of a body's limits
      sum to its total ``added_volume`` (exactly: the last cumulative fit is the fit). A
      marginal cost can be negative when a later limit reshapes what an earlier one grew.
    - **standalone** (``standalone_added_volume``): the limit's own fit against the exact
      hull, as if the profile had no other limit. Standalone costs do not add up (two
      limits often pay for the same growth).

    Attributes
    ----------
    limit : str
        The limit key.
    threshold : float
        The limit, in the input's units.
    before : float or None
        Worst measure of the exact hull(s) (the most vertices, the least thickness, ...).
    after : float or None
        Worst measure of the result.
    met : bool
    order : int
        Position of the limit in :data:`APPLY_ORDER` among the profile's limits (0 first).
    marginal_added_volume : float
        Volume added by applying this limit after the ones before it (sums to the total).
    cumulative_added_volume : float
        Volume added by this limit and every one before it.
    cumulative_max_distance : float
        Largest distance from that cumulative fit to the exact hull (input units).
    standalone_added_volume : float
        Volume added to meet this limit alone (its own fit against the exact hull).
    standalone_max_distance : float
        Largest distance from that standalone fit to the exact hull (input units).
    """

    limit: str
    threshold: float
    before: float | None
    after: float | None
    met: bool
    order: int
    marginal_added_volume: float
    cumulative_added_volume: float
    cumulative_max_distance: float
    standalone_added_volume: float
    standalone_max_distance: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "limit": self.limit,
            "rule": RULES[self.limit][0],
            "threshold": self.threshold,
            "before": self.before,
            "after": self.after,
            "met": self.met,
            "order": self.order,
            "marginal_added_volume": self.marginal_added_volume,
            "cumulative_added_volume": self.cumulative_added_volume,
            "cumulative_max_distance": self.cumulative_max_distance,
            "standalone_added_volume": self.standalone_added_volume,
            "standalone_max_distance": self.standalone_max_distance,
        }


@dataclass(frozen=True, eq=False)
class TargetFit:
    """Parts that meet a target's limits, and what that cost.

    Attributes
    ----------
    parts : tuple of ((k, 3) float64, (m, 3) int64)
        The parts (hulls, outward triangles), in the input's frame; each encloses the
        input it stands for.
    measures : PartMeasures
        The parts re-measured (:func:`measure_parts`).
    violations : tuple of Violation
        Limits still unmet (empty when the target is met).
    costs : tuple of LimitCost
        One per limit of the target, in :data:`APPLY_ORDER`; their
        ``marginal_added_volume`` sum to ``added_volume``.
    added_volume : float
        Volume of the parts minus that of the exact hulls they replace (>= 0).
    max_distance : float
        Largest distance from a part to the exact hull it replaces (input units).
    notes : tuple of str
        What was done (``thickened part 0 by 0.002``, ``merged 40 parts into 32``).
    """

    parts: tuple[tuple[np.ndarray, np.ndarray], ...]
    measures: PartMeasures
    violations: tuple[Violation, ...]
    costs: tuple[LimitCost, ...]
    added_volume: float
    max_distance: float
    notes: tuple[str, ...] = field(default=())

    @property
    def met(self) -> bool:
        return not self.violations

    def to_dict(self) -> dict[str, Any]:
        return {
            "met": self.met,
            "added_volume": self.added_volume,
            "max_distance": self.max_distance,
            "costs": [c.to_dict() for c in self.costs],
            "violations": [v.to_dict() for v in self.violations],
            "parts": [self.measures.row(i) for i in range(len(self.measures))],
            "notes": list(self.notes),
        }


def _segment_sum(points: np.ndarray, direction: np.ndarray, length: float) -> np.ndarray:
    """Points of the Minkowski sum of ``points`` with the segment of ``length`` along
    ``direction`` centred on the origin: the solid grows by ``length`` across ``direction``
    and still holds every point."""
    half = 0.5 * length * direction
    return np.vstack([points - half, points + half])


def _null_axes(points: np.ndarray, dimension: int) -> np.ndarray:
    """Unit directions (3 - dimension, 3) across which the points have no extent."""
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=True)
    return vt[dimension:]


def _grow(points: np.ndarray, limits: Mapping[str, float], notes: list[str]) -> np.ndarray:
    """The points grown (never shrunk) until their hull meets ``min_thickness``,
    ``min_volume`` and ``max_oblong_ratio``, or :data:`GROWTH_ROUNDS` are spent."""
    thickness = float(limits.get("min_thickness", 0.0))
    volume = float(limits.get("min_volume", 0.0))
    oblong = limits.get("max_oblong_ratio")
    if thickness <= 0 and volume <= 0 and oblong is None:
        return points
    pts = points
    for _ in range(GROWTH_ROUNDS):
        hull = exact_hull(pts)
        if hull.dimension < 3:
            if thickness <= 0 and volume <= 0:
                # only the oblong ratio asks for a volume: give it the least one that meets it
                extent = max(hull.diagonal, 1e-300)
                length = 2.0 * extent / float(oblong)  # type: ignore[arg-type]
            else:
                length = thickness
                if volume > 0:
                    if hull.dimension == 2:
                        length = max(length, volume / max(hull.area, 1e-300))
                    else:
                        length = max(length, volume ** (1.0 / 3.0))
            if length <= 0:
                return pts
            axes = _null_axes(pts, hull.dimension)
            base = hull.vertices
            for axis in axes:
                base = _segment_sum(base, axis, length)
            notes.append(f"gave a {hull.dimension}-D input a thickness of {length:.6g}")
            pts = base
            continue
        m = measure_hull(hull)
        normal = m["thin_normal"]
        if thickness > 0 and m["thickness"] < thickness * (1 - GROWTH_SLACK):
            grow = thickness - m["thickness"]
            notes.append(f"thickened by {grow:.6g} to min_thickness {thickness:.6g}")
        elif volume > 0 and m["volume"] < volume * (1 - GROWTH_SLACK):
            # the projected area across the thin normal is at most half the surface area
            grow = (volume - m["volume"]) / max(0.5 * hull.area, 1e-300)
            notes.append(f"thickened by {grow:.6g} to min_volume {volume:.6g}")
        elif oblong is not None and m["oblong_ratio"] > float(oblong):
            reach = m["oblong_ratio"] * m["inradius"]
            grow = 2.0 * (reach / float(oblong) - m["inradius"])
            notes.append(f"thickened by {grow:.6g} to max_oblong_ratio {float(oblong):g}")
        else:
            return pts
        pts = _segment_sum(hull.vertices, normal, max(grow, 0.0) * (1 + 4 * GROWTH_SLACK))
    return pts


def _budgeted(points: np.ndarray, limits: Mapping[str, float], notes: list[str]):
    """The exact hull of ``points`` if it meets the count limits, else the supporting-plane
    hull within them (budgets tightened until the measures agree)."""
    vertices = budget_vertices(limits)
    planes = limits.get("max_hull_polygons")
    per_vertex = limits.get("max_faces_per_vertex")
    result = convex_hull(points, max_vertices=vertices)
    if result.flat:
        return result
    m = measure_hull(exact_hull(result.vertices))
    plane_budget = None if planes is None else int(planes)
    for _ in range(BUDGET_ROUNDS):
        too_many_planes = planes is not None and m["polygons"] > planes
        too_many_per_vertex = per_vertex is not None and m["max_faces_per_vertex"] > per_vertex
        too_many_vertices = vertices is not None and m["vertices"] > vertices
        if not (too_many_planes or too_many_per_vertex or too_many_vertices):
            return result
        current = plane_budget if plane_budget is not None else m["polygons"]
        if too_many_planes:
            current = min(current, int(planes)) - max(m["polygons"] - int(planes), 0)  # type: ignore[arg-type]
        if too_many_per_vertex:
            current = min(current, m["polygons"] - 1)
        plane_budget = max(int(current), 4)
        if too_many_vertices and vertices is not None:
            vertices = max(vertices - 1, 4)
        result = convex_hull(points, max_vertices=vertices, max_planes=plane_budget)
        m = measure_hull(exact_hull(result.vertices))
    if _counts_met(m, limits):
        return result
    # the last resort always meets every count limit a profile may set (>= 4 vertices, >= 4
    # polygons, >= 3 per vertex, >= 4 triangles): the smallest supporting tetrahedron
    notes.append("reduced to the enclosing tetrahedron (no larger hull met the budgets)")
    return convex_hull(points, max_vertices=4, max_planes=4)


def _counts_met(m: Mapping[str, Any], limits: Mapping[str, float]) -> bool:
    return all(
        key not in limits or m[name] <= limits[key]
        for key, name in _PART_LIMITS.items()
        if key != "max_oblong_ratio"
    )


def _growth_met(m: Mapping[str, Any], limits: Mapping[str, float]) -> bool:
    slack = 1 - GROWTH_SLACK
    return (
        m["thickness"] >= limits.get("min_thickness", 0.0) * slack
        and m["volume"] >= limits.get("min_volume", 0.0) * slack
        and ("max_oblong_ratio" not in limits or m["oblong_ratio"] <= limits["max_oblong_ratio"])
    )


def _fit_one(points: np.ndarray, limits: Mapping[str, float], notes: list[str]):
    """Grow, then simplify; simplification can lengthen a part (its far vertices move out),
    so a part whose growth limits it broke is grown again from the simplified hull."""
    pts = points
    result = None
    for _ in range(3):
        result = _budgeted(_grow(pts, limits, notes), limits, notes)
        if result.flat:
            return result
        if _growth_met(measure_hull(exact_hull(result.vertices)), limits):
            return result
        pts = result.vertices
    return result


def fit_parts(
    parts: Sequence[tuple[Any, Any]],
    target: Any,
    length_scale: float = 1.0,
) -> TargetFit:
    """Parts that meet every limit of ``target``, each enclosing the input it replaces.

    Parameters
    ----------
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        One body's convex parts (a decomposition), or one mesh (a hull), in any frame.
    target : Target or mapping
        The limits (:class:`meshcol.io.targets.Target` or its ``limits``).
    length_scale : float
        Input units per metre, for ``min_thickness`` and ``min_volume``.

    Returns
    -------
    TargetFit
        ``violations`` lists what could not be met (empty when the target is met).

    Raises
    ------
    InvalidMeshError
        A part without vertices or with non-finite coordinates; collinear or single-point
        input with no thickness limit to grow it by.

    Notes
    -----
    1. ``max_hulls``: while there are too many parts, the pair whose merged hull adds the
       least volume is merged (the hull of both still holds both).
    2. Each part is grown, never shrunk: across its thinnest face normal by the Minkowski sum
       with a centred segment, until its thickness, its volume and its oblong ratio meet the
       limits (flat or collinear input first gets a thickness across its missing axes).
    3. Each part's hull is then simplified by supporting planes
       (:func:`meshcol.collision.hull.convex_hull`) within the vertex budget
       (:func:`budget_vertices`) and, when the polygons or the polygons per vertex are over,
       a plane budget, tightened until :func:`measure_hull` agrees.
    4. The result is re-measured and compared (:func:`limit_violations`). What each limit
       cost (``costs``, :class:`LimitCost`) is measured twice: marginally, by fitting the
       limits of :data:`APPLY_ORDER` one more at a time (a limit the previous cumulative
       fit already meets adds nothing and is not refitted), so the marginal costs sum to
       the total; and standalone, each limit the exact hulls were past fitted alone.
    """
    limits = scaled_limits(target, length_scale)
    inputs = [np.asarray(v, dtype=np.float64) for v, _ in parts]
    if not inputs:
        raise InvalidMeshError("no parts to fit to the target")
    exacts = [exact_hull(p) for p in inputs]
    for e in exacts:
        if e.dimension < 2 and not (limits.get("min_thickness", 0) or limits.get("min_volume", 0)):
            raise InvalidMeshError(
                "all vertices are collinear or coincide: there is no meaningful hull"
            )
    before = measure_parts([(e.vertices, e.faces) for e in exacts])
    notes: list[str] = []
    groups = [[i] for i in range(len(inputs))]
    max_hulls = limits.get("max_hulls")
    if max_hulls is not None and len(groups) > max_hulls:
        groups = merge_groups(inputs, int(max_hulls))
        notes.append(f"merged {len(inputs)} parts into {len(groups)} (max_hulls)")
    out_parts, added, distance = _fit_groups(inputs, exacts, groups, limits, notes)
    after = measure_parts(out_parts)
    violations = limit_violations(limits, after, len(out_parts))

    costs = _costs(inputs, exacts, groups, limits, before, after, violations, added, distance)
    return TargetFit(
        parts=tuple(out_parts),
        measures=after,
        violations=tuple(violations),
        costs=tuple(costs),
        added_volume=added,
        max_distance=distance,
        notes=tuple(dict.fromkeys(notes)),
    )


def _costs(inputs, exacts, groups, limits, before, after, violations, added, distance):
    """The :class:`LimitCost` of every limit: marginal (cumulative fits in
    :data:`APPLY_ORDER`, the last one being the fit itself) and standalone."""
    count = len(inputs)
    singles = [[i] for i in range(count)]
    binding = {v.limit for v in limit_violations(limits, before, count)}
    keys = [key for key in APPLY_ORDER if key in limits]
    cumulative: list[tuple[float, float]] = []
    applied: dict[str, float] = {}
    previous = (0.0, 0.0)
    previous_parts: list[tuple[np.ndarray, np.ndarray]] | None = None
    for n, key in enumerate(keys):
        applied[key] = limits[key]
        if n == len(keys) - 1:
            previous = (added, distance)  # every limit: the fit itself
        elif previous_parts is None or _violated(key, applied, previous_parts):
            prefix_groups = groups if "max_hulls" in applied else singles
            previous_parts, cost_added, cost_distance = _fit_groups(
                inputs, exacts, prefix_groups, applied, []
            )
            previous = (cost_added, cost_distance)
        cumulative.append(previous)
    costs = []
    for n, key in enumerate(keys):
        if key not in binding:
            alone_added, alone_distance = 0.0, 0.0
        elif len(binding) == 1 and len(keys) == 1:
            alone_added, alone_distance = added, distance
        else:
            alone_groups = groups if key == "max_hulls" else singles
            _, alone_added, alone_distance = _fit_groups(
                inputs, exacts, alone_groups, {key: limits[key]}, []
            )
        costs.append(
            LimitCost(
                limit=key,
                threshold=float(limits[key]),
                before=_worst(key, before, count),
                after=_worst(key, after, len(groups)),
                met=not any(v.limit == key for v in violations),
                order=n,
                marginal_added_volume=cumulative[n][0] - (cumulative[n - 1][0] if n else 0.0),
                cumulative_added_volume=cumulative[n][0],
                cumulative_max_distance=cumulative[n][1],
                standalone_added_volume=alone_added,
                standalone_max_distance=alone_distance,
            )
        )
    return costs


def _violated(key: str, limits: Mapping[str, float], parts) -> bool:
    """Whether ``parts`` miss the limit ``key`` (so that applying it changes the fit)."""
    measures = measure_parts(parts)
    return any(v.limit == key for v in limit_violations(limits, measures, len(parts)))


def fit_hull(points: Any, target: Any, length_scale: float = 1.0) -> TargetFit:
    """One enclosing hull of ``points`` (n, 3) that meets ``target``: :func:`fit_parts`
    with one part."""
    pts = np.asarray(points, dtype=np.float64)
    return fit_parts([(pts, np.zeros((0, 3), dtype=np.int64))], target, length_scale)


def _fit_groups(inputs, exacts, groups, limits, notes):
    """Fit each group of parts (the hull of their union) to the per-part limits: the parts,
    the volume they add over the exact hulls of their members, and the largest distance
    from a part to the exact hull of its members' points (for a merged group that hull
    covers the gap the merge filled: its volume counts in the added volume, not in the
    distance)."""
    parts, added, distance = [], 0.0, 0.0
    for group in groups:
        points = np.vstack([inputs[i] for i in group])
        result = _fit_one(points, limits, notes)
        parts.append((result.vertices, result.faces))
        union = exacts[group[0]] if len(group) == 1 else exact_hull(points)
        added += max(float(result.volume) - sum(float(exacts[i].volume) for i in group), 0.0)
        if len(result.vertices):
            distance = max(distance, _outside_distance(result.vertices, union))
    return parts, added, distance


def _outside_distance(points: np.ndarray, hull: ExactHull) -> float:
    """Largest distance from ``points`` to the solid ``hull``, 0 for points on or inside it
    (within rounding: ``1e-12`` of its diagonal in front of every face plane), so that a
    part's own vertices report 0 rather than a rounding error."""
    if hull.dimension == 3:
        signed = points @ hull.equations[:, :3].T + hull.equations[:, 3]
        outside = signed.max(axis=1) > 1e-12 * max(hull.diagonal, 1e-300)
        if not outside.any():
            return 0.0
        points = points[outside]
    return float(distance_to_hull(points, hull).max())


def merge_groups(inputs: list[np.ndarray], count: int) -> list[list[int]]:
    """Which parts to merge so that at most ``count`` remain: groups of indices of
    ``inputs`` (each a part's points), each sorted, whose hulls enclose every part.

    Greedy: each step merges the two groups whose hull adds the least volume over their own
    hulls (pair costs recomputed only for the new group). The one mechanism behind a target's
    ``max_hulls`` and :func:`meshcol.decomposition.decompose.decompose`'s ``max_hulls``."""
    groups: list[list[int]] = [[i] for i in range(len(inputs))]
    points = [inputs[i] for i in range(len(inputs))]
    volumes = [_volume(p) for p in points]

    def merged_cost(a: int, b: int) -> float:
        return _volume(np.vstack([points[a], points[b]])) - volumes[a] - volumes[b]

    alive = list(range(len(groups)))
    costs = {(a, b): merged_cost(a, b) for n, a in enumerate(alive) for b in alive[n + 1 :]}
    while len(alive) > count:
        (a, b), _ = min(costs.items(), key=lambda item: (item[1], item[0]))
        groups[a] = groups[a] + groups[b]
        points[a] = exact_hull(np.vstack([points[a], points[b]])).vertices
        volumes[a] = _volume(points[a])
        alive.remove(b)
        costs = {k: v for k, v in costs.items() if b not in k and a not in k}
        for other in alive:
            if other != a:
                key = (min(a, other), max(a, other))
                costs[key] = merged_cost(*key)
    return [sorted(groups[a]) for a in alive]


def _volume(points: np.ndarray) -> float:
    hull = exact_hull(points)
    return float(hull.volume) if hull.dimension == 3 else 0.0


def _worst(key: str, measures: PartMeasures, count: int) -> float | None:
    if key == "max_hulls":
        return float(count)
    name = {**_PART_LIMITS, "min_thickness": "thickness", "min_volume": "volume"}[key]
    values = getattr(measures, name)
    if len(values) == 0:
        return None
    worst = float(values.min() if key.startswith("min_") else values.max())
    return worst if np.isfinite(worst) else None
