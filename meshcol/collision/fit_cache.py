"""The hulls and measures of target fits, each made once and asked for in batches.

A fit (:func:`meshcol.collision.target_fit.fit_parts`) is a sequence of steps, each reading
hulls within budgets (:func:`meshcol.collision.hull.hull_within_budget`) and measures of
exact hulls (:func:`meshcol.collision.limits.measure_hulls`) before it decides the next. Its
steps are written as a generator that yields what it asks for (:func:`ask_hull`,
:func:`ask_measures`) and is sent the answers; :func:`run_steps` runs the generators of many
fits side by side, and answers every question they ask in one round with one batch: one
:func:`meshcol.collision.hull.hulls_within_budgets` (one native budget loop over all the
hulls past their budgets) and one :func:`measure_hulls`. Each fit still takes the steps it
would take alone and is answered what it would be alone (a hull and a measure are functions
of their points and budgets), so a batch of fits gives what the fits give one by one.
"""

from __future__ import annotations

import hashlib
from collections.abc import Generator, Sequence
from typing import Any

import numpy as np

from meshcol.collision.facet_distance import rows_per_block
from meshcol.collision.hull import (
    ExactHull,
    distance_to_hull,
    exact_hull,
    hulls_within_budgets,
)
from meshcol.collision.limits import add_balls, measure_hulls, measures_table
from meshcol.errors import InvalidMeshError

__all__ = [
    "FitCache",
    "FitSteps",
    "ask_hull",
    "ask_measure",
    "ask_measure_parts",
    "ask_measures",
    "measure_batch",
    "outside_distance",
    "run_steps",
]

#: A fit's steps: yields lists of questions (:func:`ask_hull`, :func:`ask_measures`), is sent
#: their answers in a list, returns its result.
FitSteps = Generator[list[tuple[Any, ...]], list[Any], Any]


class FitCache:
    """The hulls of one fit, each computed once: a fit and the fits of its costs
    (:class:`~meshcol.collision.target_fit.LimitCost`) ask for the same exact hulls and the
    same budgeted hulls (:func:`convex_hull`) of the same points (under ``--target physx``
    three of four fits of a scanned part ask for the same 255 vertices), and a hull is a
    function of its points and budgets, so the answers are the same. Likewise the measures
    of an exact hull (:func:`meshcol.collision.limits.measure_hull`: a small part's fit
    asked for the same six times, each seeking its in-sphere), with the in-sphere added only
    when a caller reads it, and the distance from a hull made here to an exact hull
    (:func:`outside_distance`), by the two objects (held here, so that their ids stay
    theirs)."""

    def __init__(self) -> None:
        self._exact: dict[tuple[Any, ...], ExactHull] = {}
        self._made: dict[tuple[Any, ...], Any] = {}
        self._measures: dict[tuple[Any, ...], dict[str, Any]] = {}
        self._balls: set[tuple[Any, ...]] = set()
        self._distances: dict[tuple[int, int], tuple[float, Any, Any]] = {}
        self._keys: dict[int, tuple[np.ndarray, tuple[Any, ...]]] = {}
        self._hulls_of: dict[tuple[Any, ...], tuple[tuple[Any, ...], np.ndarray]] = {}

    def _key(self, points: np.ndarray) -> tuple[Any, ...]:
        """The key of a (contiguous) array: its shape and a hash of its bytes, hashed once
        per array object (held here, so that its id stays its own; a fit never writes into
        an array it has asked about)."""
        held = self._keys.get(id(points))
        if held is None:
            key = (points.shape, hashlib.blake2b(points.data, digest_size=16).digest())
            held = self._keys[id(points)] = (points, key)
        return held[1]

    def exact(self, points: np.ndarray) -> ExactHull:
        """:func:`exact_hull` of ``points``."""
        pts = np.ascontiguousarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            return exact_hull(pts)  # the error it raises
        key = self._key(pts)
        if key not in self._exact:
            self._exact[key] = exact_hull(pts)
        return self._exact[key]

    def _hull_vertices(self, points: np.ndarray) -> tuple[tuple[Any, ...], np.ndarray]:
        """The key and the array of the vertices of the exact hull of (contiguous)
        ``points``, found once per distinct ``points``."""
        key = self._key(points)
        found = self._hulls_of.get(key)
        if found is None:
            vertices = self.exact(points).vertices
            found = self._hulls_of[key] = (self._key(vertices), vertices)
        return found

    def _hull_key(
        self, points: np.ndarray, max_vertices: int | None, max_planes: int | None
    ) -> tuple[Any, ...]:
        key = (*self._key(np.ascontiguousarray(points, dtype=np.float64)), max_vertices)
        return key + (max_planes,)

    def outside_distance(self, points: np.ndarray, hull: ExactHull) -> float:
        """:func:`outside_distance` of ``points`` to ``hull``, once per pair of objects."""
        key = (id(points), id(hull))
        if key not in self._distances:
            self._distances[key] = (outside_distance(points, hull), points, hull)
        return self._distances[key][0]


def outside_distance(points: np.ndarray, hull: ExactHull) -> float:
    """Largest distance from ``points`` to the solid ``hull``, 0 for points on or inside it
    (within rounding: ``1e-12`` of its diagonal in front of every face plane), so that a
    part's own vertices report 0 rather than a rounding error."""
    if hull.dimension == 3:
        normals, offsets = hull.equations[:, :3].T, hull.equations[:, 3]
        step = rows_per_block(len(offsets))  # a big part's vertices: by blocks of rows
        highest = np.concatenate(
            [
                (points[start : start + step] @ normals + offsets).max(axis=1)
                for start in range(0, max(len(points), 1), step)
            ]
        )
        outside = highest > 1e-12 * max(hull.diagonal, 1e-300)
        if not outside.any():
            return 0.0
        points = points[outside]
    return float(distance_to_hull(points, hull).max())


def measure_batch(
    requests: Sequence[tuple[FitCache, np.ndarray]], ball: bool
) -> list[dict[str, Any]]:
    """The measures of the exact hull of each request's points, from its cache or measured
    now: every missing one in one :func:`measure_hulls` call, every missing in-sphere (when
    ``ball``) in one :func:`add_balls` call. A hull is measured once, as the hull of its
    vertices: points and the vertices of their hull (a fit's input and its ``before``
    parts) share one row."""
    sets = [np.ascontiguousarray(p, dtype=np.float64) for _, p in requests]
    for p in sets:
        if p.ndim != 2 or p.shape[1] != 3:
            exact_hull(p)  # the error it raises
    hulls = [cache._hull_vertices(p) for (cache, _), p in zip(requests, sets, strict=True)]
    keys = [key for key, _ in hulls]
    sets = [vertices for _, vertices in hulls]
    missing: dict[tuple[int, Any], tuple[FitCache, np.ndarray]] = {}
    for (cache, _), key, p in zip(requests, keys, sets, strict=True):
        if key not in cache._measures:
            missing[(id(cache), key)] = (cache, p)
    if missing:
        rows = measure_hulls([cache.exact(p) for cache, p in missing.values()], ball=False)
        for ((_, key), (cache, _)), row in zip(missing.items(), rows, strict=True):
            cache._measures[key] = row
    if ball:
        unballed: dict[tuple[int, Any], tuple[FitCache, np.ndarray]] = {}
        for (cache, _), key, p in zip(requests, keys, sets, strict=True):
            if key not in cache._balls:
                unballed[(id(cache), key)] = (cache, p)
        if unballed:
            add_balls(
                [cache.exact(p) for cache, p in unballed.values()],
                [cache._measures[key] for (_, key), (cache, _) in unballed.items()],
            )
        for (_, key), (cache, _) in unballed.items():
            cache._balls.add(key)
    return [cache._measures[key] for (cache, _), key in zip(requests, keys, strict=True)]


def ask_hull(
    cache: FitCache,
    points: np.ndarray,
    max_vertices: int | None = None,
    max_planes: int | None = None,
) -> FitSteps:
    """:func:`~meshcol.collision.hull.hull_within_budget` of the exact hull of ``points``
    (each made once in ``cache``), asked of :func:`run_steps` (``yield from``); raises what
    that raises."""
    (answer,) = yield [("hull", cache, points, max_vertices, max_planes)]
    if isinstance(answer, Exception):
        raise answer
    return answer


def ask_measures(cache: FitCache, point_sets: Sequence[np.ndarray], ball: bool) -> FitSteps:
    """:func:`~meshcol.collision.limits.measure_hull` rows of the exact hulls of
    ``point_sets`` (the in-sphere when ``ball``; a row measured with it serves callers
    without; each made once in ``cache``), asked of :func:`run_steps` (``yield from``)."""
    (answer,) = yield [("measures", cache, list(point_sets), ball)]
    return answer


def ask_measure(cache: FitCache, points: np.ndarray, ball: bool) -> FitSteps:
    """:func:`ask_measures` of one point set."""
    return (yield from ask_measures(cache, [points], ball))[0]


def ask_measure_parts(cache: FitCache, point_sets: Sequence[np.ndarray], ball: bool) -> FitSteps:
    """:func:`ask_measures` as :class:`~meshcol.collision.limits.PartMeasures` (a part a set)."""
    return measures_table((yield from ask_measures(cache, point_sets, ball)))


def run_steps(steps: Sequence[FitSteps]) -> list[Any]:
    """Run fits' steps side by side to their ends: per round, each live fit takes its next
    step and the questions of all are answered at once (:func:`_answer`). Returns each
    fit's result, or the :class:`InvalidMeshError` it raised, in order."""
    results: list[Any] = [None] * len(steps)
    answers: dict[int, Any] = dict.fromkeys(range(len(steps)))
    while answers:
        questions: dict[int, list[tuple[Any, ...]]] = {}
        for i, answer in answers.items():
            try:
                questions[i] = steps[i].send(answer)
            except StopIteration as stop:
                results[i] = stop.value
            except InvalidMeshError as exc:
                results[i] = exc
        answers = _answer(questions)
    return results


def _answer(questions: dict[int, list[tuple[Any, ...]]]) -> dict[int, list[Any]]:
    """The answers of a round's questions, per fit: the measures without in-sphere in one
    batch, then those with, then every hull (the budgeted ones in one native call)."""
    flat = [(i, n, q) for i, asked in questions.items() for n, q in enumerate(asked)]
    answers: dict[int, list[Any]] = {i: [None] * len(asked) for i, asked in questions.items()}
    for ball in (False, True):
        measured = [(i, n, q) for i, n, q in flat if q[0] == "measures" and q[3] is ball]
        sets = [(q[1], p) for _, _, q in measured for p in q[2]]
        rows = measure_batch(sets, ball) if sets else []
        start = 0
        for i, n, q in measured:
            answers[i][n] = rows[start : start + len(q[2])]
            start += len(q[2])
    hulls = [(i, n, q) for i, n, q in flat if q[0] == "hull"]
    for (i, n, _), made in zip(hulls, _hulls([q[1:] for _, _, q in hulls]), strict=True):
        answers[i][n] = made
    return answers


def _hulls(questions: Sequence[tuple[Any, ...]]) -> list[Any]:
    """:func:`ask_hull`'s answer to each question (the hull, or the error
    :func:`~meshcol.collision.hull.hull_within_budget` raises): the hulls no cache holds
    made in one :func:`hulls_within_budgets`."""
    made: list[Any] = [None] * len(questions)
    todo: dict[tuple[int, Any], tuple[FitCache, Any, ExactHull, tuple[Any, Any]]] = {}
    failed: dict[tuple[int, Any], InvalidMeshError] = {}
    for n, (cache, points, max_vertices, max_planes) in enumerate(questions):
        try:
            exact = cache.exact(points)
        except InvalidMeshError as exc:
            made[n] = exc
            continue
        key = cache._hull_key(points, max_vertices, max_planes)
        if key in cache._made:
            made[n] = cache._made[key]
        else:
            todo.setdefault((id(cache), key), (cache, key, exact, (max_vertices, max_planes)))
    if todo:
        built = hulls_within_budgets([t[2] for t in todo.values()], [t[3] for t in todo.values()])
        for (name, (cache, key, _, _)), hull in zip(todo.items(), built, strict=True):
            if isinstance(hull, InvalidMeshError):
                failed[name] = hull
            else:
                cache._made[key] = hull
    for n, (cache, points, max_vertices, max_planes) in enumerate(questions):
        if made[n] is None:
            key = cache._hull_key(points, max_vertices, max_planes)
            made[n] = cache._made[key] if key in cache._made else failed[(id(cache), key)]
    return made
