"""Running decompositions over many files in worker processes.

:func:`run_tasks` runs one task per file in worker processes (``forkserver`` where available,
else ``spawn``: CoACD is C++ that holds the GIL, so threads would not help), kills a worker that
exceeds the per-file timeout and replaces it, and reports every task's outcome, so one failing
or stuck file never stops the others. A :class:`WorkerPool` can be started before the tasks
are known, so the workers' start-up overlaps the caller's reading of the input files.
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.connection
import os
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "TaskOutcome",
    "WorkerPool",
    "decompose_task",
    "run_tasks",
    "worker_env",
]

# Seconds a worker gets to exit after terminate() before kill().
_TERMINATE_GRACE = 2.0


@dataclass(frozen=True)
class TaskOutcome:
    """What became of one task: ``status`` is ``ok``, ``failed`` or ``timeout``."""

    index: int
    status: str
    value: Any = None
    message: str | None = None
    seconds: float = 0.0


def _call(fn: Callable[[Any], Any], task: Any) -> tuple[str, Any]:
    # The process boundary: any error in one task becomes that task's status so that the
    # others still run (the message keeps the exception type for the report).
    try:
        return "ok", fn(task)
    except Exception as exc:  # noqa: BLE001 - reported per task, never swallowed
        return "failed", f"{type(exc).__name__}: {exc}"


def _worker_main(
    conn: multiprocessing.connection.Connection,
    fn: Callable[[Any], Any],
    env: dict[str, str],
    prepare: Callable[[], None] | None,
) -> None:
    # Before any engine loads: OpenMP reads OMP_NUM_THREADS once, when its library loads.
    os.environ.update(env)
    if prepare is not None:
        # Load the engine now, while the parent is still reading its input files.
        try:
            prepare()
        except Exception:  # noqa: BLE001 - the first task meets the same error and reports it
            pass
    while True:
        try:
            message = conn.recv()
        except EOFError:
            return
        if message is None:
            return
        index, task = message
        status, value = _call(fn, task)
        conn.send((index, status, value))


class _Worker:
    def __init__(
        self,
        ctx: Any,
        fn: Callable[[Any], Any],
        env: dict[str, str],
        prepare: Callable[[], None] | None,
    ) -> None:
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, fn, env, prepare), daemon=True)
        self.process.start()
        child.close()
        self.index: int | None = None
        self.started = 0.0
        self.used = False

    @property
    def task_index(self) -> int:
        """Index of the task this (busy) worker runs."""
        assert self.index is not None, "the worker has no task"
        return self.index

    def assign(self, index: int, task: Any) -> None:
        self.index, self.started, self.used = index, time.perf_counter(), True
        self.conn.send((index, task))

    def kill(self) -> None:
        self.process.terminate()
        self.process.join(_TERMINATE_GRACE)
        if self.process.is_alive():
            self.process.kill()
            self.process.join()
        self.conn.close()

    def close(self) -> None:
        try:
            self.conn.send(None)
        except OSError:
            pass
        self.process.join(_TERMINATE_GRACE)
        if self.process.is_alive():
            self.kill()
        else:
            self.conn.close()


def _context(env: dict[str, str]) -> Any:
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" not in methods:
        return multiprocessing.get_context("spawn")  # each worker applies `env` first
    ctx = multiprocessing.get_context("forkserver")
    # Workers fork from a server that has already imported the heavy modules (not the engines:
    # they load OpenMP, whose thread count each worker sets first). The server inherits this
    # process's environment when it starts, and its preloaded numpy sizes its thread pool
    # then: start it with the workers' thread settings.
    ctx.set_forkserver_preload(
        [
            "meshcol.decomposition.decompose",
            "meshcol.decomposition.jobs",
            "scipy.spatial",
            "manifold3d",
            "trimesh",
        ]
    )
    saved = {key: os.environ.get(key) for key in env}
    os.environ.update(env)
    try:
        from multiprocessing import forkserver

        forkserver.ensure_running()
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    return ctx


def worker_env(jobs: int, threads_per_job: int | None = None) -> dict[str, str]:
    """Thread settings of the workers of a ``jobs``-process run (variables the user has set win).

    Each engine (CoACD is parallel inside, with OpenMP) gets ``2 * cores / jobs`` threads, at
    most ``cores``, that sleep when idle (``OMP_WAIT_POLICY=PASSIVE``): while one worker is
    in a serial stretch, or has no file left, the others' parallel loops take up its cores,
    and a last long file does not run on one core while the rest idle (the measurement is in
    benchmarks/RESULTS.md, "decompose"). numpy's
    OpenBLAS pool, which spins, gets ``cores // jobs``.
    """
    cores = os.cpu_count() or 1
    share = max(1, cores // jobs)
    env: dict[str, str] = {}
    if threads_per_job is not None:
        env["OMP_NUM_THREADS"] = str(threads_per_job)
    elif "OMP_NUM_THREADS" not in os.environ:
        env["OMP_NUM_THREADS"] = str(min(cores, max(1, -(-2 * cores // jobs))))
    if "OMP_WAIT_POLICY" not in os.environ:
        env["OMP_WAIT_POLICY"] = "PASSIVE"
    if "OPENBLAS_NUM_THREADS" not in os.environ:
        # numpy's OpenBLAS sizes its pool from OMP_NUM_THREADS unless this is set, and only
        # when it loads: in the forkserver, before any worker runs. Unlimited, every worker's
        # BLAS spins on every core and the workers slow each other down (benchmarks/RESULTS.md).
        env["OPENBLAS_NUM_THREADS"] = str(share)
    return env


class WorkerPool:
    """Worker processes for :func:`run_tasks`, which can start before the tasks are known.

    ``start()`` forks the workers (from a ``forkserver`` that has imported the heavy modules)
    and lets each run ``prepare`` (for instance, import the engine), so their start-up
    overlaps the caller's own work (reading the input files); ``run(tasks)`` then feeds them.
    A worker that exceeds ``timeout`` on a task is killed and replaced. Use as a context
    manager, or call ``close()``.
    """

    def __init__(
        self,
        fn: Callable[[Any], Any],
        jobs: int,
        *,
        timeout: float | None = None,
        threads_per_job: int | None = None,
        prepare: Callable[[], None] | None = None,
    ) -> None:
        if jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {jobs}")
        self.fn, self.jobs, self.timeout, self.prepare = fn, jobs, timeout, prepare
        self.env = worker_env(jobs, threads_per_job)
        self._ctx: Any = None
        self._idle: list[_Worker] = []
        self._busy: list[_Worker] = []

    def start(self, workers: int | None = None) -> WorkerPool:
        """Start ``workers`` (default ``jobs``, at most ``jobs``) processes now."""
        if self._ctx is None:
            self._ctx = _context(self.env)
        count = self.jobs if workers is None else min(workers, self.jobs)
        while len(self._idle) + len(self._busy) < count:
            self._idle.append(self._new_worker())
        return self

    def _new_worker(self) -> _Worker:
        return _Worker(self._ctx, self.fn, self.env, self.prepare)

    def run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        """Run every task; yield outcomes as they complete.

        ``tasks`` may be a generator that reads a file per task: it is read ahead as fast as
        it goes, one task between polls of the workers, and each task goes to a worker as
        soon as one is free. So the first files are decomposed while the rest are read, and
        an exception from the generator (unusable input) comes as early as reading allows
        (busy workers are then killed on ``close()``).
        """
        self.start(0)
        source = enumerate(tasks)
        more = True
        pending: deque[tuple[int, Any]] = deque()
        idle, busy, timeout = self._idle, self._busy, self.timeout
        while True:
            while pending and len(busy) < self.jobs:
                worker = idle.pop() if idle else self._new_worker()
                worker.assign(*pending.popleft())
                busy.append(worker)
            if more:
                item = next(source, None)
                if item is None:
                    more = False
                else:
                    pending.append(item)
                if not busy:
                    continue
                wait_for: float | None = 0.0  # poll, then read on
            elif not busy:
                return
            else:
                wait_for = None
            now = time.perf_counter()
            if timeout is not None:
                limit = max(0.0, min(w.started + timeout for w in busy) - now)
                wait_for = limit if wait_for is None else min(wait_for, limit)
            handles: list[Any] = [w.conn for w in busy] + [w.process.sentinel for w in busy]
            ready = set(multiprocessing.connection.wait(handles, wait_for))
            now = time.perf_counter()
            for worker in list(busy):
                seconds = now - worker.started
                if worker.conn in ready:
                    try:
                        index, status, value = worker.conn.recv()
                    except (EOFError, OSError):
                        ready.add(worker.process.sentinel)
                    else:
                        busy.remove(worker)
                        idle.append(worker)
                        if status == "ok":
                            yield TaskOutcome(index, status, value, seconds=seconds)
                        else:
                            yield TaskOutcome(index, status, message=value, seconds=seconds)
                        continue
                if worker.process.sentinel in ready:
                    busy.remove(worker)
                    worker.process.join()
                    code = worker.process.exitcode
                    worker.conn.close()
                    yield TaskOutcome(
                        worker.task_index,
                        "failed",
                        message=f"worker process died (exit code {code})",
                        seconds=seconds,
                    )
                elif timeout is not None and seconds >= timeout:
                    busy.remove(worker)
                    worker.kill()
                    yield TaskOutcome(
                        worker.task_index,
                        "timeout",
                        message=f"timed out after {timeout:g} s",
                        seconds=seconds,
                    )

    def close(self) -> None:
        """Stop every worker: a busy one, or one that never had a task (it may still be
        loading the engine: nothing to wait for), is killed; the others exit cleanly."""
        for worker in self._busy:
            worker.kill()
        for worker in self._idle:
            if worker.used:
                worker.close()
            else:
                worker.kill()
        self._busy.clear()
        self._idle.clear()

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def run_tasks(
    fn: Callable[[Any], Any],
    tasks: Iterable[Any],
    *,
    jobs: int = 1,
    timeout: float | None = None,
    threads_per_job: int | None = None,
    pool: WorkerPool | None = None,
) -> Iterator[TaskOutcome]:
    """Run ``fn(task)`` for every task; yield outcomes as they complete.

    Parameters
    ----------
    fn : callable
        A module-level function (it is sent to worker processes).
    tasks : iterable
        Picklable task arguments, read lazily (one whenever a worker is free).
    jobs : int
        Worker processes. With ``jobs == 1`` and no timeout, tasks run in this process.
    timeout : float, optional
        Seconds one task may take; its worker is then killed and replaced, and the task's
        status is ``timeout``.
    threads_per_job : int, optional
        OpenMP threads per worker (see :func:`worker_env`). Results do not depend on it.
    pool : WorkerPool, optional
        Workers already started (for ``fn``); they are used instead of ``jobs``, ``timeout``
        and ``threads_per_job``, and left running.
    """
    if pool is not None:
        yield from pool.run(tasks)
        return
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    if jobs == 1 and timeout is None:
        # In this process: every task is read (and checked) before the first runs.
        for index, task in enumerate(list(tasks)):
            start = time.perf_counter()
            status, value = _call(fn, task)
            seconds = time.perf_counter() - start
            if status == "ok":
                yield TaskOutcome(index, status, value, seconds=seconds)
            else:
                yield TaskOutcome(index, status, message=value, seconds=seconds)
        return
    with WorkerPool(fn, jobs, timeout=timeout, threads_per_job=threads_per_job) as workers:
        yield from workers.run(tasks)


# --------------------------------------------------------------------------------------------
# writers


def decompose_task(
    task: tuple[str, list[tuple[str, np.ndarray, np.ndarray]], dict[str, Any]],
) -> list[tuple[str, Any]]:
    """Worker entry: decompose every body of one file. ``task`` = (path, bodies, options)."""
    from meshcol.decomposition.decompose import decompose

    _, bodies, options = task
    return [(name, decompose((vertices, faces), **options)) for name, vertices, faces in bodies]
