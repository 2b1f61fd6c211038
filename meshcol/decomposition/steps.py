"""The engine's own steps, reported from the worker that makes them to the progress line.

A decomposition task runs in a worker process (:mod:`meshcol.decomposition.jobs`, or a Ray
worker): the parent sees only when a whole file ends, so a run of one file showed no more than
its elapsed time. The code that makes the steps of a task says where it is with
:func:`stage` (``with stage("search step", at_most=12) as s: ... s.advance()``): the bodies
of a file, the steps of a fidelity search. Stages nest; each report is the whole stack,
outermost first, as :data:`Snapshot` (plain tuples: it crosses a pipe). Without a sink
(:func:`reporting_to`) a report costs a function call and goes nowhere.

The parent keeps a :class:`StepClock` per task: the time each unit of each stage took, and
from it an estimate of the time left that is honest: none until a unit of the stage that
decides it has finished (the average of finished units, raised by a unit under way that
overruns it, times the units left, plus what is left of the unit under way); never negative;
a stage whose total is a budget (``at_most``: a search stops early when its bracket closes)
counts every unit of the budget, and says so (``search step 3 of at most 12``). A stage without a total (an engine that does not say how much it has left) gives
no number: the line shows where the work is and its elapsed time.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

__all__ = [
    "ProgressText",
    "Snapshot",
    "Stage",
    "StepClock",
    "describe",
    "reporting_to",
    "stage",
]

#: One stage as reported: (name, units done, total units or None, total is a budget, note).
Level = tuple[str, int, "int | None", bool, "str | None"]
#: The stack of stages under way, outermost first.
Snapshot = tuple[Level, ...]

_lock = threading.Lock()
_sink: Callable[[Snapshot], None] | None = None
_stack: list[Stage] = []


class Stage:
    """One stage under way (:func:`stage`): ``advance()`` when a unit of it is done."""

    def __init__(self, name: str, total: int | None, at_most: bool) -> None:
        self.name, self.total, self.at_most = name, total, at_most
        self.done = 0
        self.note: str | None = None

    def advance(self, note: str | None = None) -> None:
        """One more unit done (``note``: what the next one is, for the line)."""
        self.done += 1
        self.note = note
        _report()

    def level(self) -> Level:
        return (self.name, self.done, self.total, self.at_most, self.note)


@contextlib.contextmanager
def stage(name: str, total: int | None = None, *, at_most: int | None = None) -> Iterator[Stage]:
    """A stage of ``total`` units (or at most ``at_most``; neither: unknown), reported as it
    starts, at each ``advance()`` and as it ends."""
    current = Stage(name, total if at_most is None else at_most, at_most is not None)
    _stack.append(current)
    _report()
    try:
        yield current
    finally:
        _stack.remove(current)
        _report()


@contextlib.contextmanager
def reporting_to(sink: Callable[[Snapshot], None] | None) -> Iterator[None]:
    """Send every report of this process to ``sink`` for the block (a worker's pipe). A
    sink that fails is dropped: progress never fails a task."""
    global _sink
    previous = _sink
    _sink = sink
    try:
        yield
    finally:
        _sink = previous


def _report() -> None:
    global _sink
    sink = _sink
    if sink is None:
        return
    snapshot = tuple(s.level() for s in _stack)
    with _lock:
        try:
            sink(snapshot)
        except Exception:  # noqa: BLE001 - a broken pipe ends the task elsewhere, not here
            _sink = None


def describe(snapshot: Snapshot) -> str:
    """``body 2/3 (gear), search step 4 of at most 12``: where the task is."""
    parts = []
    for name, done, total, at_most, note in snapshot:
        if total is None:
            text = name
        elif at_most:
            text = f"{name} {min(done + 1, total)} of at most {total}"
        else:
            text = f"{name} {min(done + 1, total)}/{total}"
        parts.append(f"{text} ({note})" if note else text)
    return ", ".join(parts)


class StepClock:
    """The parent's view of one task's steps: when each unit of each stage started and how
    long the finished ones took, and from that the time left (:meth:`left`)."""

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self.clock = clock
        self.snapshot: Snapshot = ()
        #: per level: (name, total, the outer levels' units) it belongs to, when its current
        #: unit started, and the durations of its finished units
        self._keys: list[tuple[Any, ...]] = []
        self._started: list[float] = []
        self._durations: list[list[float]] = []

    def update(self, snapshot: Snapshot) -> None:
        """A report from the task."""
        now = self.clock()
        keys = []
        for depth, (name, _done, total, _at_most, _note) in enumerate(snapshot):
            outer = tuple(level[1] for level in snapshot[:depth])
            keys.append((name, total, outer))
        for depth, key in enumerate(keys):
            done = snapshot[depth][1]
            if depth < len(self._keys) and self._keys[depth] == key:
                before = self.snapshot[depth][1]
                if done > before:
                    # units finished since the last report share the time evenly
                    each = (now - self._started[depth]) / (done - before)
                    self._durations[depth].extend([each] * (done - before))
                    self._started[depth] = now
                continue
            # a new stage at this depth (or a new unit of an outer one): start afresh
            del self._keys[depth:], self._started[depth:], self._durations[depth:]
            self._keys.append(key)
            self._started.append(now)
            self._durations.append([])
        del self._keys[len(keys) :], self._started[len(keys) :], self._durations[len(keys) :]
        self.snapshot = snapshot

    def left(self) -> tuple[float, bool] | None:
        """(seconds left, whether it counts a budget's units that may not run), or None while
        no finished unit justifies a number."""
        return self._left(0, self.clock())

    def _left(self, depth: int, now: float) -> tuple[float, bool] | None:
        if depth >= len(self.snapshot):
            return None
        _name, done, total, at_most, _note = self.snapshot[depth]
        if total is None:
            return None
        remaining = max(0, total - done - 1)  # whole units after the current one
        inner = self._left(depth + 1, now)
        durations = self._durations[depth]
        if not durations:
            if remaining == 0 and inner is not None:
                return inner[0], inner[1] or at_most
            return None
        in_unit = now - self._started[depth]
        mean = sum(durations) / len(durations)
        # A unit that overruns the average raises it: the units to come are no cheaper than
        # the finished ones and the one under way (so the estimate never falls as it overruns).
        mean = max(mean, (sum(durations) + in_unit) / (len(durations) + 1))
        if inner is not None:
            current, bound = inner
        else:
            current, bound = max(0.0, mean - in_unit), False
        if done >= total:
            current = 0.0
        return max(0.0, current + remaining * mean), bound or at_most


class ProgressText(str):
    """A progress message (a ``str``, for every progress callable) that carries its time
    left: the command line's display asks ``time_left()`` each time it draws the line, so
    the figure counts down between two reports."""

    time_left: Callable[[], tuple[float, bool] | None]

    def __new__(cls, text: str, time_left: Callable[[], tuple[float, bool] | None]) -> Any:
        made = super().__new__(cls, text)
        made.time_left = time_left
        return made
