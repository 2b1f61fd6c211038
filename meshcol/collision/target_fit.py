"""Convex parts fitted to an engine's limits: enclosing hulls that meet every limit.

:func:`fit_hull` and :func:`fit_parts` build parts that meet every limit of a target
(measured by :func:`meshcol.collision.limits.measure_parts`) and still enclose their input:
hulls are only ever grown (a thin part thickened, a flat one given a volume) or simplified by
supporting planes (:func:`meshcol.collision.hull.convex_hull`), never pulled inward; what each
limit cost is measured against the exact hull of the input (:class:`LimitCost`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.collision.fit_cache import (
    FitCache,
    FitSteps,
    ask_hull,
    ask_measure,
    ask_measure_parts,
    measure_batch,
    run_steps,
)
from meshcol.collision.hull import exact_hull
from meshcol.collision.limits import (
    GROWTH_SLACK,
    PART_MEASURES,
    RULES,
    PartMeasures,
    Violation,
    budget_vertices,
    limit_violations,
    scaled_limits,
)
from meshcol.errors import InvalidMeshError

__all__ = [
    "APPLY_ORDER",
    "FitCache",
    "LimitCost",
    "TargetFit",
    "fit_caches",
    "fit_hull",
    "fit_hulls",
    "fit_parts",
    "merge_groups",
]

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
#: Growth rounds (thickness, volume, oblong ratio) and budget rounds tried before a limit is
#: declared unmet.
GROWTH_ROUNDS = 12
#: A round of growing and simplifying again that lowers the oblong ratio by less than this
#: fraction has made no progress: the fit keeps the previous round's (smaller) part.
OBLONG_PROGRESS = 0.01
BUDGET_ROUNDS = 8
#: Most planes a budget round gives the supporting-plane hull. Its loop adds a plane a cut and
#: intersects them all again at each one, so its work grows with the square of the budget:
#: a big hull fitted to ``max_faces_per_vertex`` alone (one polygon fewer than the exact
#: hull's 23,841, Menagerie's ``robotiq_fts300_top.stl``) ran for hours. A hull of planes in
#: general position has three polygons at a vertex, so a few hundred planes meet that limit.
MAX_PLANE_BUDGET = 256


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


def fit_caches(
    point_sets: Sequence[Any], limits: Mapping[str, float] | None = None
) -> list[FitCache]:
    """One :class:`FitCache` per point set for :func:`fit_hull`, holding what its fit reads
    first: the exact hull of the points and its measures (the ``before`` measure, the
    ``after`` one of a hull that meets the limits as it is, and what growing reads first:
    one row, :func:`measure_batch` measures a hull once), all measured in one batch. The
    in-sphere only with ``max_oblong_ratio`` in ``limits`` (the ``before`` measure reads it
    then); otherwise a fit's later round adds it where it is asked for. A set whose hull
    cannot be made is left for its fit to raise about."""
    caches = [FitCache() for _ in point_sets]
    requests = []
    for cache, points in zip(caches, point_sets, strict=True):
        pts = np.asarray(points, dtype=np.float64)
        try:
            exact = cache.exact(pts)
        except (InvalidMeshError, ValueError):
            continue
        requests.append((cache, exact.vertices))
    measure_batch(requests, ball="max_oblong_ratio" in (limits or {}))
    return caches


def _grow(
    points: np.ndarray, limits: Mapping[str, float], notes: list[str], hulls: FitCache
) -> FitSteps:
    """The points grown (never shrunk) until their hull meets ``min_thickness``,
    ``min_volume`` and ``max_oblong_ratio``, or :data:`GROWTH_ROUNDS` are spent."""
    thickness = float(limits.get("min_thickness", 0.0))
    volume = float(limits.get("min_volume", 0.0))
    oblong = limits.get("max_oblong_ratio")
    if thickness <= 0 and volume <= 0 and oblong is None:
        return points
    pts = points
    for _ in range(GROWTH_ROUNDS):
        hull = hulls.exact(pts)
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
        m = yield from ask_measure(hulls, pts, oblong is not None)
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


def _budgeted(
    points: np.ndarray, limits: Mapping[str, float], notes: list[str], hulls: FitCache
) -> FitSteps:
    """The exact hull of ``points`` if it meets the count limits, else the supporting-plane
    hull within them (budgets tightened until the measures agree)."""
    vertices = budget_vertices(limits)
    planes = limits.get("max_hull_polygons")
    per_vertex = limits.get("max_faces_per_vertex")
    result = yield from ask_hull(hulls, points, vertices)
    if result.flat:
        return result
    m = yield from ask_measure(hulls, result.vertices, False)
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
        if current > MAX_PLANE_BUDGET:
            notes.append(f"plane budget capped at {MAX_PLANE_BUDGET} (from {int(current)})")
            current = MAX_PLANE_BUDGET
        plane_budget = max(int(current), 4)
        if too_many_vertices and vertices is not None:
            vertices = max(vertices - 1, 4)
        result = yield from ask_hull(hulls, points, vertices, plane_budget)
        m = yield from ask_measure(hulls, result.vertices, False)
    if _counts_met(m, limits):
        return result
    # the last resort always meets every count limit a profile may set (>= 4 vertices, >= 4
    # polygons, >= 3 per vertex, >= 4 triangles): the smallest supporting tetrahedron
    notes.append("reduced to the enclosing tetrahedron (no larger hull met the budgets)")
    return (yield from ask_hull(hulls, points, 4, 4))


def _counts_met(m: Mapping[str, Any], limits: Mapping[str, float]) -> bool:
    return all(
        key not in limits or m[name] <= limits[key]
        for key, name in PART_MEASURES.items()
        if key != "max_oblong_ratio"
    )


def _growth_met(m: Mapping[str, Any], limits: Mapping[str, float]) -> bool:
    slack = 1 - GROWTH_SLACK
    return (
        m["thickness"] >= limits.get("min_thickness", 0.0) * slack
        and m["volume"] >= limits.get("min_volume", 0.0) * slack
        and ("max_oblong_ratio" not in limits or m["oblong_ratio"] <= limits["max_oblong_ratio"])
    )


def _fit_one(
    points: np.ndarray, limits: Mapping[str, float], notes: list[str], hulls: FitCache
) -> FitSteps:
    """Grow, then simplify; simplification can lengthen a part (its far vertices move out),
    so a part whose growth limits it broke is grown again from the simplified hull."""
    pts = points
    result = None
    kept: tuple[Any, float] | None = None  # the last round's result and its oblong ratio
    others = {key: value for key, value in limits.items() if key != "max_oblong_ratio"}
    for _ in range(3):
        written = len(notes)
        grown = yield from _grow(pts, limits, notes, hulls)
        result = yield from _budgeted(grown, limits, notes, hulls)
        if result.flat:
            return result
        m = yield from ask_measure(hulls, result.vertices, "max_oblong_ratio" in limits)
        if _growth_met(m, limits):
            return result
        rounder = kept is None or m["oblong_ratio"] < kept[1] * (1 - OBLONG_PROGRESS)
        if not rounder and _growth_met(m, others):
            # Grown rounder, then simplified back no rounder (four vertices cannot have a
            # ratio under 3): the earlier, smaller part, and the ratio left as a violation.
            del notes[written:]
            notes.append(
                f"max_oblong_ratio {float(limits['max_oblong_ratio']):g} not reached: "
                "growing the part and simplifying it again made it no rounder"
            )
            return kept[0]  # type: ignore[index]
        kept = (result, float(m["oblong_ratio"]))
        pts = result.vertices
    return result


def fit_parts(
    parts: Sequence[tuple[Any, Any]], target: Any, length_scale: float = 1.0, cache=None
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
    cache : FitCache, optional
        These parts' hulls and measures made already (:func:`fit_caches`), for one fit.

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
       a plane budget, tightened until :func:`meshcol.collision.limits.measure_hull` agrees.
    4. The result is re-measured and compared (:func:`limit_violations`). What each limit
       cost (``costs``, :class:`LimitCost`) is measured twice: marginally, by fitting the
       limits of :data:`APPLY_ORDER` one more at a time (a limit the previous cumulative
       fit already meets adds nothing and is not refitted), so the marginal costs sum to
       the total; and standalone, each limit the exact hulls were past fitted alone.
    """
    (fit,) = run_steps([_fit_parts(parts, target, length_scale, cache)])
    if isinstance(fit, InvalidMeshError):
        raise fit
    return fit


def _fit_parts(
    parts: Sequence[tuple[Any, Any]], target: Any, length_scale: float, cache: FitCache | None
) -> FitSteps:
    """:func:`fit_parts`'s steps (:func:`meshcol.collision.fit_cache.run_steps`)."""
    limits = scaled_limits(target, length_scale)
    inputs = [np.asarray(v, dtype=np.float64) for v, _ in parts]
    if not inputs:
        raise InvalidMeshError("no parts to fit to the target")
    hulls = cache or FitCache()
    exacts = [hulls.exact(p) for p in inputs]
    for e in exacts:
        if e.dimension < 2 and not (limits.get("min_thickness", 0) or limits.get("min_volume", 0)):
            raise InvalidMeshError(
                "all vertices are collinear or coincide: there is no meaningful hull"
            )
    # only compared with the limits: the in-sphere (a linear programme) only for the ratio
    ball = "max_oblong_ratio" in limits
    before = yield from ask_measure_parts(hulls, [e.vertices for e in exacts], ball)
    notes: list[str] = []
    groups = [[i] for i in range(len(inputs))]
    max_hulls = limits.get("max_hulls")
    if max_hulls is not None and len(groups) > max_hulls:
        groups = merge_groups(inputs, int(max_hulls))
        notes.append(f"merged {len(inputs)} parts into {len(groups)} (max_hulls)")
    out_parts, added, distance = yield from _fit_groups(
        inputs, exacts, groups, limits, notes, hulls
    )
    after = yield from ask_measure_parts(hulls, [v for v, _ in out_parts], True)
    violations = limit_violations(limits, after, len(out_parts))

    costs = yield from _costs(
        inputs, exacts, groups, limits, before, after, violations, (added, distance), hulls
    )
    return TargetFit(
        parts=tuple(out_parts),
        measures=after,
        violations=tuple(violations),
        costs=tuple(costs),
        added_volume=added,
        max_distance=distance,
        notes=tuple(dict.fromkeys(notes)),
    )


def _costs(inputs, exacts, groups, limits, before, after, violations, fitted, hulls) -> FitSteps:
    """The :class:`LimitCost` of every limit: marginal (cumulative fits in
    :data:`APPLY_ORDER`, the last one being the fit itself, whose added volume and distance
    are ``fitted``) and standalone."""
    added, distance = fitted
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
        if n == len(keys) - 1 or (not binding and groups == singles):
            # every limit: the fit itself; or exact hulls that meet every limit, which each
            # prefix of the limits fits as the whole does (no growth, no budget, no merge)
            previous = (added, distance)
        elif previous_parts is None or (yield from _violated(key, applied, previous_parts, hulls)):
            prefix_groups = groups if "max_hulls" in applied else singles
            previous_parts, cost_added, cost_distance = yield from _fit_groups(
                inputs, exacts, prefix_groups, applied, [], hulls
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
            _, alone_added, alone_distance = yield from _fit_groups(
                inputs, exacts, alone_groups, {key: limits[key]}, [], hulls
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


def _violated(key: str, limits: Mapping[str, float], parts, hulls: FitCache) -> FitSteps:
    """Whether ``parts`` miss the limit ``key`` (so that applying it changes the fit)."""
    measures = yield from ask_measure_parts(
        hulls, [v for v, _ in parts], "max_oblong_ratio" in limits
    )
    return any(v.limit == key for v in limit_violations(limits, measures, len(parts)))


def fit_hull(
    points: Any, target: Any, length_scale: float = 1.0, cache: FitCache | None = None
) -> TargetFit:
    """One enclosing hull of ``points`` (n, 3) that meets ``target``: :func:`fit_parts`
    with one part (``cache``: from :func:`fit_caches`)."""
    (fit,) = fit_hulls([points], target, length_scale, [cache or FitCache()])
    if isinstance(fit, InvalidMeshError):
        raise fit
    return fit


def fit_hulls(
    point_sets: Sequence[Any],
    target: Any,
    length_scale: float = 1.0,
    caches: Sequence[FitCache] | None = None,
) -> list[TargetFit | InvalidMeshError]:
    """:func:`fit_hull` of each point set, the fits run side by side
    (:func:`meshcol.collision.fit_cache.run_steps`: each round's hulls and measures of all
    in one batch); a set that has no fit gets the error :func:`fit_hull` raises in its
    place. ``caches``: one :class:`FitCache` per set (default: :func:`fit_caches`)."""
    sets = [np.asarray(points, dtype=np.float64) for points in point_sets]
    if caches is None:
        caches = fit_caches(sets, scaled_limits(target, length_scale))
    empty = np.zeros((0, 3), dtype=np.int64)
    return run_steps(
        [
            _fit_parts([(pts, empty)], target, length_scale, cache)
            for pts, cache in zip(sets, caches, strict=True)
        ]
    )


def _fit_groups(inputs, exacts, groups, limits, notes, hulls) -> FitSteps:
    """Fit each group of parts (the hull of their union) to the per-part limits: the parts,
    the volume they add over the exact hulls of their members, and the largest distance
    from a part to the exact hull of its members' points (for a merged group that hull
    covers the gap the merge filled: its volume counts in the added volume, not in the
    distance)."""
    parts, added, distance = [], 0.0, 0.0
    for group in groups:
        points = np.vstack([inputs[i] for i in group])
        result = yield from _fit_one(points, limits, notes, hulls)
        parts.append((result.vertices, result.faces))
        union = exacts[group[0]] if len(group) == 1 else hulls.exact(points)
        added += max(float(result.volume) - sum(float(exacts[i].volume) for i in group), 0.0)
        if len(result.vertices):
            distance = max(distance, hulls.outside_distance(result.vertices, union))
    return parts, added, distance


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
    name = {**PART_MEASURES, "min_thickness": "thickness", "min_volume": "volume"}[key]
    values = getattr(measures, name)
    if len(values) == 0:
        return None
    worst = float(values.min() if key.startswith("min_") else values.max())
    return worst if np.isfinite(worst) else None
