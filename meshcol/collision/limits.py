"""Engine limits of convex parts: measured once, for everybody.

:func:`measure_parts` is the one measurement of what engines limit (vertices, triangles,
polygons after merging coplanar triangles, polygons meeting at a vertex, the oblong ratio,
the thickness and the volume of each part); :func:`limit_violations` compares measures with
a target's limits (the keys of :mod:`meshcol.io.targets`, the rule ids of
:data:`RULES`). :mod:`meshcol.collision.target_fit` builds parts that meet every limit
and still enclose their input.

The target is duck-typed (an object with a ``limits`` mapping, or the mapping itself), so
that this layer stays free of :mod:`meshcol.io`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.arrays import as_offsets
from meshcol.collision.hull import ExactHull, exact_hull
from meshcol.vocabulary import LIMITS

__all__ = [
    "add_balls",
    "COPLANAR_RELATIVE_TOLERANCE",
    "RULES",
    "PartMeasures",
    "Violation",
    "budget_vertices",
    "inscribed_balls",
    "limit_violations",
    "measures_table",
    "measure_hull",
    "measure_hulls",
    "measure_parts",
    "polygon_labels",
    "scaled_limits",
]

#: Limit key -> (rule id, rule name), in rule id order (the order violations are listed in).
RULES: dict[str, tuple[str, str]] = {
    key: (rule, name) for key, (rule, name, _) in sorted(LIMITS.items(), key=lambda kv: kv[1][0])
}
#: Two adjacent hull triangles are one polygon when each one's far vertex is within this
#: fraction of the part's bounding-box diagonal of the other's plane (and their normals agree).
COPLANAR_RELATIVE_TOLERANCE = 1e-9
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
        (>= 1; ``inf`` for a part without volume). Where the largest ball can slide (a box
        longer than wide), the centre is the lexicographic one (:func:`inscribed_balls`).
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
    (:func:`meshcol.geometry.graph.connected_components`), all vectorised.
    """
    return _polygon_labels(vertices, faces, tolerance)[0]


def _polygon_labels(
    vertices: np.ndarray, faces: np.ndarray, tolerance: Any
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`polygon_labels`, and each triangle's doubled area (the length of its
    unnormalised normal)."""
    from meshcol.geometry.graph import connected_components

    faces = np.asarray(faces, dtype=np.int64)
    m = len(faces)
    if m == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
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
    _, labels = connected_components(m, np.stack([f1[coplanar], f2[coplanar]], axis=1))
    return labels.astype(np.int64), lengths


def inscribed_balls(
    planes: np.ndarray, offsets: np.ndarray, threads: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre and radius of the largest ball in each polytope ``{x : n . x + d <= 0}``.

    Parameters
    ----------
    planes : (p, 4) float
        Unit-normal planes ``(n_x, n_y, n_z, d)``; polytope ``h`` owns
        ``planes[offsets[h]:offsets[h + 1]]``.
    offsets : (h + 1,) int
    threads : int
        Threads of the core's call (0: all).

    Returns
    -------
    centres : (h, 3) float64
    radii : (h,) float64
        >= 0; 0 for an empty polytope.
    status : (h,) int8
        :class:`meshcol.types.Status` codes: ``CONVERGED`` (0) where the core settled the
        linear programme. Any other polytope (the step cap, an unbounded or non-finite one)
        is settled again by HiGHS (``scipy.optimize.linprog``), the reference, and keeps the
        core's code, so that callers and tests see which ones it was.

    Notes
    -----
    The Chebyshev centre (Boyd and Vandenberghe 2004, 8.5.1): maximise ``r`` subject to
    ``n_i . x + r <= -d_i``, a linear programme in 4 unknowns, solved for every polytope in
    one threaded call of the core (``core.inscribed_balls``, an active-set simplex with
    Bland's rule, ``cpp/src/inscribed_ball.cpp``). The radius is the least distance from the
    centre found to a plane. Where the largest ball can slide (a box longer than wide, a
    prism, a plate), the centre is the lexicographic one: the planes it must touch are held
    and the least distance to the others is maximised in turn, so that the centre (and the
    oblong ratio read from it) is the polytope's own, not a solver's pivot (HiGHS, which
    this replaced, gave one of the optimal centres, by its pivots).
    """
    from meshcol._native import core

    status, centres, radii = core.inscribed_balls(
        np.ascontiguousarray(planes, dtype=np.float64),
        np.ascontiguousarray(offsets, dtype=np.int64),
        threads,
    )
    for h in np.nonzero(status != 0)[0]:
        rows = planes[offsets[h] : offsets[h + 1]]
        centres[h], radii[h] = _inscribed_ball_highs(rows[:, :3], rows[:, 3])
    return centres, radii, status


def _inscribed_ball_highs(normals: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`inscribed_balls` of one polytope by HiGHS (``scipy.optimize.linprog``): the
    reference the core's answer is tested against, and what settles a polytope the core
    could not (origin and 0 where HiGHS cannot either)."""
    from scipy.optimize import linprog

    if len(normals) == 0 or not (np.isfinite(normals).all() and np.isfinite(offsets).all()):
        return np.zeros(3), 0.0
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


#: Doubles of one block of :func:`_widths`' projections (32 MB).
WIDTH_BLOCK = 1 << 22
#: Hulls of more vertices than this get their widths from the core's support climbs
#: (``core.hull_widths``); smaller ones from the product of every normal with every vertex.
WIDTH_CLIMB_MIN_VERTICES = 1024


def _widths(normals: np.ndarray, points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Width of the hull ``points`` (``faces`` its triangles) along each unit normal: the
    largest minus the smallest projection of a vertex.

    Up to :data:`WIDTH_CLIMB_MIN_VERTICES` vertices, every projection as a matrix product
    a block of normals at a time (memory stays at :data:`WIDTH_BLOCK` doubles however many
    normals; each row's values are the same whatever the blocks). Larger hulls: the core's
    support climbs on the hull's edges (``core.hull_widths``), warm-started from the previous
    normal's supports, in time about the polygons times the square root of the vertices
    instead of their product (a scanned part of 12,388 hull vertices and 23,841 polygons:
    295 million projections). Each climb's projections are the fused chain a BLAS product
    computes, and the climb reads every vertex near its top, so a width is the same double
    as the maximum and minimum over all vertices (``tests/targets/test_widths.py``)."""
    if len(points) > WIDTH_CLIMB_MIN_VERTICES:
        from meshcol._native import core

        return core.hull_widths(
            np.ascontiguousarray(points, dtype=np.float64),
            np.ascontiguousarray(faces, dtype=np.int64),
            np.ascontiguousarray(normals, dtype=np.float64),
        )
    rows = max(1, WIDTH_BLOCK // max(len(points), 1))
    widths = np.empty(len(normals))
    for start in range(0, len(normals), rows):
        projections = normals[start : start + rows] @ points.T
        widths[start : start + rows] = projections.max(axis=1) - projections.min(axis=1)
    return widths


def measure_hull(hull: ExactHull, ball: bool = True) -> dict[str, Any]:
    """The measures of one exact hull (:class:`PartMeasures`' fields, plus ``normals`` and
    ``offsets``: the unit normals and offsets of its polygons' planes, and ``thin_normal``:
    the direction of its thickness). Lower-dimensional hulls (flat, collinear, a point) get
    thickness and volume 0. Without ``ball``, a 3-D hull's in-sphere (a linear programme
    over its polygons) is not sought: ``inradius`` and ``oblong_ratio`` are NaN."""
    return measure_hulls([hull], ball)[0]


def measure_hulls(hulls: Sequence[ExactHull], ball: bool = True) -> list[dict[str, Any]]:
    """:func:`measure_hull` of each hull: the polygons of all 3-D hulls labelled in one
    vectorised pass (:func:`polygon_labels` on their union), the in-spheres in one call of
    the core (:func:`inscribed_balls`); each hull's measures are the ones it has alone."""
    rows: list[dict[str, Any]] = [{} for _ in hulls]
    for n, hull in enumerate(hulls):
        if hull.dimension < 3:
            rows[n] = _flat_measures(hull)
    solids = [n for n, hull in enumerate(hulls) if hull.dimension == 3]
    for n, row in zip(solids, _solid_measures([hulls[n] for n in solids]), strict=True):
        rows[n] = row
    if ball:
        add_balls(hulls, rows)
    return rows


def add_balls(hulls: Sequence[ExactHull], rows: Sequence[dict[str, Any]]) -> None:
    """Set ``inradius`` and ``oblong_ratio`` of the :func:`measure_hull` rows of 3-D
    ``hulls`` (measured without ``ball``), every in-sphere in one call of the core."""
    solids = [n for n, hull in enumerate(hulls) if hull.dimension == 3]
    if solids:
        planes = np.vstack(
            [np.hstack([rows[n]["normals"], rows[n]["offsets"][:, None]]) for n in solids]
        )
        offsets = as_offsets([len(rows[n]["offsets"]) for n in solids])
        centres, radii, _ = inscribed_balls(planes, offsets)
        for n, centre, radius in zip(solids, centres, radii, strict=True):
            reach = float(np.linalg.norm(hulls[n].vertices - centre, axis=1).max())
            rows[n]["inradius"] = float(radius)
            rows[n]["oblong_ratio"] = reach / radius if radius > 0 else np.inf


def _flat_measures(hull: ExactHull) -> dict[str, Any]:
    """:func:`measure_hull` of a hull below 3-D: thickness and volume 0, no in-sphere."""
    thin = hull.normal if hull.dimension == 2 else np.zeros(3)
    return {
        "vertices": len(hull.vertices),
        "triangles": len(hull.faces),
        "polygons": 1 if hull.dimension == 2 else 0,
        "max_faces_per_vertex": 1 if hull.dimension == 2 else 0,
        "oblong_ratio": np.inf,
        "inradius": 0.0,
        "thickness": 0.0,
        "volume": 0.0,
        "normals": thin[None, :] if hull.dimension == 2 else np.zeros((0, 3)),
        "offsets": np.zeros(1 if hull.dimension == 2 else 0),
        "thin_normal": thin,
    }


def _solid_measures(hulls: Sequence[ExactHull]) -> list[dict[str, Any]]:
    """:func:`measure_hull` of 3-D hulls without the in-sphere (NaN), all at once.

    The hulls are stacked with disjoint vertex ranges: a polygon never spans two of them,
    and the union's labels number each hull's polygons in the order its own would (by
    smallest triangle), so every per-hull figure is the one it has alone. One plane per
    polygon: its largest triangle's equation (the most accurate normal). Widths are taken
    hull by hull (:func:`_widths`)."""
    if not hulls:
        return []
    vertex_counts = np.array([len(h.vertices) for h in hulls], dtype=np.int64)
    face_counts = np.array([len(h.faces) for h in hulls], dtype=np.int64)
    vertex_starts = as_offsets(vertex_counts)[:-1]
    face_starts = as_offsets(face_counts)[:-1]
    vertices = np.vstack([h.vertices for h in hulls])
    faces = np.vstack([h.faces for h in hulls]) + np.repeat(vertex_starts, face_counts)[:, None]
    tolerance = np.repeat(
        [COPLANAR_RELATIVE_TOLERANCE * max(h.diagonal, 1e-300) for h in hulls], face_counts
    )
    labels, areas = _polygon_labels(vertices, faces, tolerance)
    first_label = labels[face_starts]
    polygons = np.maximum.reduceat(labels, face_starts) - first_label + 1
    # polygons meeting at each vertex: the distinct (vertex, polygon) pairs
    span = int(labels.max()) + 1
    keys = np.unique(faces.reshape(-1) * span + np.repeat(labels, 3))
    per_vertex = np.bincount(keys // span, minlength=len(vertices))
    most = np.maximum.reduceat(per_vertex, vertex_starts)
    order = np.lexsort((-areas, labels))
    lead = order[np.r_[True, labels[order][1:] != labels[order][:-1]]]
    planes = np.vstack([h.equations for h in hulls])[lead]
    rows = []
    for n, hull in enumerate(hulls):
        own = planes[first_label[n] : first_label[n] + polygons[n]]
        normals, offsets = own[:, :3], own[:, 3]
        widths = _widths(normals, hull.vertices, hull.faces)
        thinnest = int(np.argmin(widths))
        rows.append(
            {
                "vertices": int(vertex_counts[n]),
                "triangles": int(face_counts[n]),
                "polygons": int(polygons[n]),
                "max_faces_per_vertex": int(most[n]),
                "oblong_ratio": np.nan,
                "inradius": np.nan,
                "thickness": float(widths[thinnest]),
                "volume": float(hull.volume),
                "normals": normals,
                "offsets": offsets,
                "thin_normal": normals[thinnest],
            }
        )
    return rows


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


def measure_parts(parts: Sequence[tuple[Any, Any]], ball: bool = True) -> PartMeasures:
    """Measure convex parts as an engine sees them: the exact hull of each part's vertices.

    Parameters
    ----------
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        The parts' vertices and faces (the faces are not used: engines cook the hull of the
        points, and so does this).
    ball : bool
        Seek each part's in-sphere (``inradius``, ``oblong_ratio``; else NaN for a 3-D part):
        what a measure without ``max_oblong_ratio`` can skip (:func:`measure_hull`).

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
    polygons' half-spaces (a linear programme, :func:`inscribed_balls`); the oblong ratio
    is the farthest vertex from that centre over its radius; the thickness is the smallest
    width over the polygons' normals, which is the exact minimum width of a part whose
    thinnest direction is face-to-vertex (slabs, boxes, plates) and an upper bound, at most
    about 15% above, when it is edge-to-edge (a tetrahedron).
    """
    hulls = [exact_hull(np.asarray(v, dtype=np.float64)) for v, _ in parts]
    return measures_table(measure_hulls(hulls, ball))


def measures_table(rows: Sequence[Mapping[str, Any]]) -> PartMeasures:
    """:class:`PartMeasures` of :func:`measure_hull` rows, one a part."""
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


def limits_of(target: Any) -> Mapping[str, float]:
    return target if isinstance(target, Mapping) else target.limits


def scaled_limits(target: Any, length_scale: float = 1.0) -> dict[str, float]:
    """A target's limits in the input's units: ``min_thickness`` times ``length_scale``
    (input units per metre), ``min_volume`` times its cube; counts unchanged."""
    limits = dict(limits_of(target))
    if "min_thickness" in limits:
        limits["min_thickness"] = float(limits["min_thickness"]) * length_scale
    if "min_volume" in limits:
        limits["min_volume"] = float(limits["min_volume"]) * length_scale**3
    return limits


#: Limit key -> the field of :class:`PartMeasures` it limits (the per-part count limits).
PART_MEASURES = {
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
    for key, name in PART_MEASURES.items():
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
