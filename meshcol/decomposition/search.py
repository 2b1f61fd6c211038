"""Fidelity targets: the engine parameters that give the fewest parts within a Hausdorff limit.

``meshcol decompose --max-hausdorff D`` (and/or ``--max-parts N``) searches, body by body, one
engine parameter, the *axis*, for the decomposition that meets the target with the fewest
parts:

- CoACD: the concavity ``threshold`` (larger: fewer, looser parts), on a log scale between
  :data:`COACD_THRESHOLD_RANGE`; when even the finest threshold misses ``D``, the sampling
  ``resolution`` is raised (:data:`RESOLUTION_FACTOR`, at most :data:`RESOLUTION_RAISES`
  times) and the threshold searched again at it.
- V-HACD: the hull count ``max_convex_hulls`` (fewer: coarser), between 1 and the run's
  ``max_hulls`` (default the engine's 64); then the voxel ``resolution`` as for CoACD. Its
  concavity (``minimum_volume_percent_error_allowed``) stays as given (``-E``).

A step is a plain decomposition with those parameters (:func:`meshcol.decomposition.decompose.
decompose`): the same cache key as ``meshcol decompose --threshold T --resolution R``, so every
step is cached and a repeated or resumed search runs no engine. A step *meets* the target
when both one-sided Hausdorff distances are at most ``D`` (as
:func:`within_max_hausdorff` judges them, the ``--max-hausdorff`` check of every run) and it has at most ``N``
parts.

The search, for ``D`` (with or without ``N``): Hausdorff grows with the threshold, so the
coarsest step within ``D`` is bracketed from the start value (the run's ``--threshold``, else
the engine's default), doubling the threshold while steps meet ``D`` or halving it while they
do not, then bisected (geometric mean, rounded to :data:`SIGNIFICANT_DIGITS` digits so that a
reported threshold reproduces the step exactly) until the bracket is within ``tolerance``
(``hi / lo <= 1 + tolerance``), the step budget is spent, or a step of one part meets it. For
``N`` alone, the finest step with at most ``N`` parts (the smallest Hausdorff the budget buys)
is bracketed and bisected the same way. The chosen step is, among those that meet the target,
the one with the fewest parts (``N`` alone: the smallest Hausdorff), ties to the smaller
Hausdorff (fewer parts), then the earlier step. The engines are not exactly monotonic: the
choice is made over every step, never only the last bracket. When no step meets the target,
the best step (the smallest excess over the limits, ``max(H / D, parts / N)``) is reported as
the failure, with why the search stopped.

Deterministic: the steps depend only on the measured results, which depend only on the
geometry, the parameters and the seed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from meshcol.decomposition.options import (
    DEFAULT_SEARCH_STEPS,
    DEFAULT_SEARCH_TOLERANCE,
    SEARCH_MODES,
    DecomposeOptions,
    SearchTarget,
    search_target,
)
from meshcol.decomposition.result import Decomposition
from meshcol.decomposition.steps import Stage, stage

__all__ = [
    "COACD_THRESHOLD_RANGE",
    "DEFAULT_SEARCH_STEPS",
    "DEFAULT_SEARCH_TOLERANCE",
    "SEARCH_MODES",
    "SearchResult",
    "SearchStep",
    "SearchTarget",
    "cached_search",
    "meets_target",
    "run_search",
    "search_decomposition",
    "search_target",
    "store_steps",
    "within_max_hausdorff",
]

#: CoACD's concavity thresholds searched (its documented range is 0.01 to 1).
COACD_THRESHOLD_RANGE = (0.01, 1.0)
#: Thresholds of the search are rounded to this many significant digits.
SIGNIFICANT_DIGITS = 3
#: Resolution raise when the finest value of the axis misses ``max_hausdorff``.
RESOLUTION_FACTOR = 2
#: Most resolution raises per search.
RESOLUTION_RAISES = 2


def meets_target(
    metrics: Mapping[str, Any], max_hausdorff: float | None, max_parts: int | None
) -> bool:
    """Whether a decomposition's metrics (``Fidelity.to_dict()``) meet both limits: Hausdorff
    both ways numbers no larger than ``max_hausdorff``, at most ``max_parts`` parts."""
    parts = metrics.get("parts")
    parts_ok = max_parts is None or (isinstance(parts, int) and parts <= max_parts)
    return parts_ok and within_max_hausdorff(metrics, max_hausdorff)


def within_max_hausdorff(metrics: Mapping[str, Any], limit: float | None) -> bool:
    """Whether a body passes ``--max-hausdorff``: both one-sided Hausdorff distances are
    numbers no larger than ``limit``. True without a limit; False when a distance is missing
    or NaN (a gate never passes what it could not measure)."""
    if limit is None:
        return True
    values = [metrics.get(k) for k in ("hausdorff_mesh_to_parts", "hausdorff_parts_to_mesh")]
    return all(isinstance(v, (int, float)) and v <= limit for v in values)


@dataclass(frozen=True, eq=False)
class SearchStep:
    """One decomposition the search made (or found in the cache).

    Attributes
    ----------
    index : int
        Order of the step in the search (0 first).
    threshold : float or None
        CoACD's concavity threshold (None for V-HACD).
    max_hulls : int or None
        The run's ``max_hulls`` (CoACD), or the step's hull count (V-HACD, the axis).
    resolution : int
        CoACD's sampling resolution or V-HACD's voxel count.
    decomposition : Decomposition
        The step's decomposition, metrics measured.
    seconds : float
        Wall time of the step in this run (a cache hit: the look-up).
    meets : bool
        The step meets the target.
    """

    index: int
    threshold: float | None
    max_hulls: int | None
    resolution: int
    decomposition: Decomposition
    seconds: float
    meets: bool

    def hausdorff(self) -> float:
        """The larger one-sided Hausdorff distance (NaN when either is not measured)."""
        m = self.decomposition.metrics
        if m is None:
            return math.nan
        return max(m.hausdorff_mesh_to_parts, m.hausdorff_parts_to_mesh)

    @property
    def parts(self) -> int:
        return len(self.decomposition.parts)

    def describe(self) -> str:
        """``step 3 (threshold 0.1, resolution 2000)``."""
        knobs = [
            f"threshold {self.threshold:g}" if self.threshold is not None else None,
            f"max_hulls {self.max_hulls}" if self.threshold is None else None,
            f"resolution {self.resolution}",
        ]
        return f"step {self.index} ({', '.join(k for k in knobs if k)})"

    def to_dict(self, chosen: bool = False) -> dict[str, Any]:
        m = self.decomposition.metrics
        return {
            "index": self.index,
            "threshold": self.threshold,
            "max_hulls": self.max_hulls,
            "resolution": self.resolution,
            "parts": self.parts,
            "hausdorff_mesh_to_parts": None if m is None else m.hausdorff_mesh_to_parts,
            "hausdorff_parts_to_mesh": None if m is None else m.hausdorff_parts_to_mesh,
            "volume_ratio": None if m is None else m.volume_ratio,
            "seconds": round(self.seconds, 3),
            "from_cache": self.decomposition.from_cache,
            "cache_key": self.decomposition.cache_key,
            "meets": self.meets,
            "chosen": chosen,
        }


@dataclass(frozen=True, eq=False)
class SearchResult:
    """A body's search: every step, the one chosen, and whether it met the target.

    Attributes
    ----------
    target : SearchTarget
    axis : {"threshold", "max_hulls"}
        The parameter searched.
    steps : tuple of SearchStep
        In the order they were made.
    chosen : int
        Index of the chosen step: the best that meets the target, else the best of all.
    met : bool
        A step met the target.
    stopped : str
        Why the search ended (``tolerance``, ``steps``, ``one part``, ``range``).
    reason : str
        One line: the chosen step and why it was chosen, or why none met the target.
    """

    target: SearchTarget
    axis: str
    steps: tuple[SearchStep, ...]
    chosen: int
    met: bool
    stopped: str
    reason: str

    @property
    def decomposition(self) -> Decomposition:
        """The chosen step's decomposition (the parts a run writes)."""
        return self.steps[self.chosen].decomposition

    @property
    def engine_calls(self) -> int:
        """Steps that ran the engine (not found in the cache)."""
        return sum(not s.decomposition.from_cache for s in self.steps)

    def to_dict(self) -> dict[str, Any]:
        return {
            "target": self.target.to_dict(),
            "axis": self.axis,
            "met": self.met,
            "chosen": self.chosen,
            "stopped": self.stopped,
            "reason": self.reason,
            "engine_calls": self.engine_calls,
            "steps": [s.to_dict(chosen=s.index == self.chosen) for s in self.steps],
        }


class _Miss(Exception):
    """A step the cache does not have (:func:`cached_search`)."""


# --------------------------------------------------------------------------------------------
# the axis of each engine


def _round(value: float) -> float:
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


@dataclass
class _Axis:
    """Positions on the engine's axis as numbers that grow towards coarser (fewer parts)."""

    name: str
    start: float
    finest: float
    coarsest: float
    integer: bool

    def coarser(self, x: float) -> float | None:
        if x >= self.coarsest:
            return None
        if self.integer:  # hull counts: halved (x is -hulls)
            return min(self.coarsest, -float(max(1, math.floor(-x / 2))))
        return min(self.coarsest, _round(x * 2))

    def finer(self, x: float) -> float | None:
        if x <= self.finest:
            return None
        if self.integer:
            return max(self.finest, -float(-x * 2))
        return max(self.finest, _round(x / 2))

    def between(self, a: float, b: float, tolerance: float) -> float | None:
        """A point strictly between ``a < b``, or None when the bracket is within tolerance."""
        if self.integer:
            lo, hi = -b, -a  # hull counts, lo < hi
            if hi - lo <= max(1.0, tolerance * lo):
                return None
            return -float(math.floor((lo + hi) / 2))
        if b / a <= 1 + tolerance:
            return None
        mid = _round(math.sqrt(a * b))
        return mid if a < mid < b else None


def _axis(engine: str, params: Mapping[str, Any], max_parts: int | None) -> _Axis:
    if engine == "coacd":
        t = float(params["threshold"])
        lo, hi = COACD_THRESHOLD_RANGE
        return _Axis("threshold", t, min(lo, t), max(hi, t), integer=False)
    # V-HACD: from the run's hull count (never more than max_parts) down to one hull.
    top = int(params["max_convex_hulls"])
    if max_parts is not None:
        top = min(top, max_parts)
    return _Axis("max_hulls", -float(top), -float(top), -1.0, integer=True)


# --------------------------------------------------------------------------------------------
# the search


def run_search(
    target: SearchTarget,
    engine: str,
    params: Mapping[str, Any],
    evaluate: Callable[[float | None, int | None, int], Decomposition],
    *,
    max_hulls: int | None = None,
    clock: Callable[[], float] = time.perf_counter,
) -> SearchResult:
    """Search the engine's axis for the fewest parts that meet ``target``.

    Parameters
    ----------
    target : SearchTarget
    engine : {"coacd", "vhacd"}
    params : mapping
        The engine's resolved parameters of the run (:func:`meshcol.decomposition.engines.
        resolve_params`): the start of the axis and the resolution.
    evaluate : callable
        ``evaluate(threshold, max_hulls, resolution)`` -> the decomposition with those
        parameters, metrics measured (``threshold`` None for V-HACD).
    max_hulls : int, optional
        The run's ``max_hulls`` (CoACD: kept in every step).
    clock : callable
        Seconds, for each step's time.

    Returns
    -------
    SearchResult
    """
    axis = _axis(engine, params, target.max_parts)
    search = _Search(target, axis, int(params["resolution"]), evaluate, max_hulls, clock)
    stopped = search.run()
    return _result(target, axis, search.steps, stopped)


class _Search:
    """One body's search in progress: its steps, and the stages that make them (bracket the
    edge of the target on the axis, bisect the bracket, raise the resolution)."""

    def __init__(
        self,
        target: SearchTarget,
        axis: _Axis,
        resolution: int,
        evaluate: Callable[[float | None, int | None, int], Decomposition],
        max_hulls: int | None,
        clock: Callable[[], float],
    ) -> None:
        self.target, self.axis, self.resolution = target, axis, resolution
        self.evaluate, self.max_hulls, self.clock = evaluate, max_hulls, clock
        self.steps: list[SearchStep] = []
        self._progress = Stage("search step", None, False)
        # With a Hausdorff limit, the predicate that brackets is "within D" (true at the fine
        # end, the fewest parts at its coarse edge); with a part limit alone, "at most N
        # parts" (true at the coarse end, the best fidelity at its fine edge).
        self.by_hausdorff = target.max_hausdorff is not None

    def run(self) -> str:
        """Every stage, from the start of the axis: why the search stopped (each step a unit
        of the task's steps, :mod:`meshcol.decomposition.steps`, out of the step budget)."""
        with stage("search step", at_most=self.target.max_steps) as self._progress:
            return self._stages()

    def _stages(self) -> str:
        x, raises = self.axis.start, 0
        while True:
            stopped, good_x, bad_x = self._bracket(x)
            if stopped == "one part":
                return stopped
            if good_x is not None and bad_x is not None:
                return self._bisect(good_x, bad_x)
            if not self._can_raise(stopped, good_x, raises):
                return stopped or "range"
            # Even the finest value of the axis misses D: sample finer, search again.
            raises += 1
            self.resolution *= RESOLUTION_FACTOR
            x = self.axis.finest

    def _bracket(self, x: float) -> tuple[str | None, float | None, float | None]:
        """Steps from ``x`` towards the unknown edge until the last good and the last bad
        position are known: (why it stopped first, or None; good position; bad position)."""
        s = self._step(x)
        if self._done_early(s):
            return "one part", None, None
        good_x: float | None = x if self._good(s) else None
        bad_x: float | None = None if self._good(s) else x
        while good_x is None or bad_x is None:
            if not self._has_budget():
                return "steps", good_x, bad_x
            # Towards the unknown edge: from good, coarser with D (finer with N alone); from
            # bad, the other way.
            toward_coarse = (good_x is not None) == self.by_hausdorff
            following = self.axis.coarser(x) if toward_coarse else self.axis.finer(x)
            if following is None:
                return "range", good_x, bad_x
            x = following
            s = self._step(x)
            if self._done_early(s):
                return "one part", good_x, bad_x
            if self._good(s):
                good_x = x
            else:
                bad_x = x
        return None, good_x, bad_x

    def _bisect(self, good_x: float, bad_x: float) -> str:
        """Bisect the bracket until it is within the tolerance: why it stopped."""
        while True:
            lo, hi = sorted((good_x, bad_x))
            mid = self.axis.between(lo, hi, self.target.tolerance)
            if mid is None:
                return "tolerance"
            if not self._has_budget():
                return "steps"
            s = self._step(mid)
            if self._done_early(s):
                return "one part"
            if self._good(s):
                good_x = mid
            else:
                bad_x = mid

    def _can_raise(self, stopped: str | None, good_x: float | None, raises: int) -> bool:
        """Whether to raise the resolution: nothing on the axis met D, the axis ran out, and
        raises and steps are left."""
        return (
            good_x is None
            and self.by_hausdorff
            and stopped == "range"
            and raises < RESOLUTION_RAISES
            and self._has_budget()
        )

    def _step(self, x: float) -> SearchStep:
        threshold = x if self.axis.name == "threshold" else None
        hulls = self.max_hulls if self.axis.name == "threshold" else int(-x)
        started = self.clock()
        d = self.evaluate(threshold, hulls, self.resolution)
        metrics = {} if d.metrics is None else d.metrics.to_dict()
        s = SearchStep(
            len(self.steps),
            threshold,
            hulls,
            self.resolution,
            d,
            self.clock() - started,
            meets_target(metrics, self.target.max_hausdorff, self.target.max_parts),
        )
        self.steps.append(s)
        self._progress.advance()
        return s

    def _good(self, s: SearchStep) -> bool:
        m = s.decomposition.metrics
        if self.by_hausdorff:
            return m is not None and meets_target(m.to_dict(), self.target.max_hausdorff, None)
        return s.parts <= (self.target.max_parts or 0)

    def _has_budget(self) -> bool:
        return len(self.steps) < self.target.max_steps

    def _done_early(self, s: SearchStep) -> bool:
        # One part within D: nothing coarser can have fewer.
        return self.by_hausdorff and self._good(s) and s.parts == 1


def _result(
    target: SearchTarget, axis: _Axis, steps: list[SearchStep], stopped: str
) -> SearchResult:
    meeting = [s for s in steps if s.meets]

    def h(s: SearchStep) -> float:
        value = s.hausdorff()
        return math.inf if math.isnan(value) else value

    if meeting:
        if target.max_hausdorff is not None:
            best = min(meeting, key=lambda s: (s.parts, h(s), s.index))
        else:
            best = min(meeting, key=lambda s: (h(s), s.parts, s.index))
        limits = _limits(target)
        reason = (
            f"{best.describe()}: {best.parts} part(s), Hausdorff {h(best):.6g} ({limits}), "
            f"chosen of {len(steps)} step(s); search stopped: {_stopped(stopped, target)}"
        )
        return SearchResult(target, axis.name, tuple(steps), best.index, True, stopped, reason)

    def excess(s: SearchStep) -> float:
        over = []
        if target.max_hausdorff is not None:
            d = target.max_hausdorff
            over.append(h(s) / d if d > 0 else (0.0 if h(s) == 0 else math.inf))
        if target.max_parts is not None:
            over.append(s.parts / target.max_parts)
        return max(over)

    best = min(steps, key=lambda s: (excess(s), s.parts, h(s), s.index))
    why = []
    if target.max_hausdorff is not None and h(best) > target.max_hausdorff:
        why.append(f"Hausdorff {h(best):.6g} > max_hausdorff {target.max_hausdorff:g}")
    if target.max_parts is not None and best.parts > target.max_parts:
        why.append(f"{best.parts} parts > max_parts {target.max_parts}")
    reason = (
        f"no step met the target: best {best.describe()}: {best.parts} part(s), "
        f"{'; '.join(why) or 'not measured'}; search stopped: {_stopped(stopped, target)}"
    )
    return SearchResult(target, axis.name, tuple(steps), best.index, False, stopped, reason)


def _limits(target: SearchTarget) -> str:
    limits = []
    if target.max_hausdorff is not None:
        limits.append(f"max_hausdorff {target.max_hausdorff:g}")
    if target.max_parts is not None:
        limits.append(f"max_parts {target.max_parts}")
    return ", ".join(limits)


def _stopped(stopped: str, target: SearchTarget) -> str:
    return {
        "tolerance": f"bracket within the tolerance ({target.tolerance:g})",
        "steps": f"step budget spent ({target.max_steps} steps)",
        "one part": "one part meets the target",
        "range": "end of the parameter range",
    }[stopped]


# --------------------------------------------------------------------------------------------
# entry points


def _search(
    mesh: Any,
    target: SearchTarget,
    options: DecomposeOptions,
    decomposition: Callable[[Any, DecomposeOptions], Decomposition | None],
) -> SearchResult:
    """The search of ``mesh`` with ``decomposition(mesh, step options)`` making each step."""
    from meshcol.decomposition.canonical import as_mesh_arrays, canonical_geometry
    from meshcol.decomposition.engines import resolve_params
    from meshcol.geometry.topology import is_closed_manifold

    vertices, faces = canonical_geometry(*as_mesh_arrays(mesh))
    params = resolve_params(options, closed=is_closed_manifold(faces))

    def evaluate(threshold: float | None, hulls: int | None, resolution: int) -> Decomposition:
        d = decomposition((vertices, faces), options.step(threshold, hulls, resolution))
        if d is None or d.metrics is None:
            raise _Miss
        return d

    return run_search(target, options.engine, params, evaluate, max_hulls=options.max_hulls)


def search_decomposition(
    mesh: Any,
    target: SearchTarget,
    options: DecomposeOptions | None = None,
    *,
    cache_dir: str | None = None,
    use_cache: bool = True,
    write_cache: bool = True,
    threads: int = 0,
    **fields: Any,
) -> SearchResult:
    """Search the engine's parameters for the fewest parts of ``mesh`` that meet ``target``.

    Parameters
    ----------
    mesh : Body, trimesh.Trimesh or ((n, 3) float, (m, 3) int)
    target : SearchTarget
    options : DecomposeOptions, optional
        The run's options: ``threshold`` and ``resolution`` are the start of the search.
    cache_dir, use_cache, write_cache, threads
        As :func:`meshcol.decomposition.decompose.decompose` (metrics are always measured).
    **fields
        Fields of :class:`DecomposeOptions`, which replace those of ``options``.

    Returns
    -------
    SearchResult
        Every step (each a cached decomposition unless ``use_cache`` is off), the chosen one.
    """
    from meshcol.decomposition.decompose import decompose

    def decomposition(mesh: Any, step: DecomposeOptions) -> Decomposition:
        return decompose(
            mesh,
            step,
            cache_dir=cache_dir,
            use_cache=use_cache,
            write_cache=write_cache,
            threads=threads,
        )

    return _search(mesh, target, DecomposeOptions.given(options, **fields), decomposition)


def cached_search(
    mesh: Any,
    target: SearchTarget,
    options: DecomposeOptions | None = None,
    *,
    cache_dir: str | None = None,
    **fields: Any,
) -> SearchResult | None:
    """The search of :func:`search_decomposition` replayed from the cache alone, or None as
    soon as a step is missing (or has no metrics); never runs an engine."""
    from meshcol.decomposition.decompose import cached_decomposition

    def decomposition(mesh: Any, step: DecomposeOptions) -> Decomposition | None:
        return cached_decomposition(mesh, step, cache_dir=cache_dir)

    try:
        return _search(mesh, target, DecomposeOptions.given(options, **fields), decomposition)
    except _Miss:
        return None


def store_steps(result: SearchResult, cache_dir: str) -> None:
    """Store every step of a search in the cache (those it holds, with the same metrics, are
    left as they are)."""
    from meshcol.decomposition import cache

    for s in result.steps:
        d = s.decomposition
        before = cache.load(d.cache_key, cache_dir) if d.from_cache else None
        if before is None or before.metrics != d.metrics:
            cache.store(d, cache_dir)
