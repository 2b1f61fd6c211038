"""Running decompositions over many files in worker processes.

:func:`run_tasks` runs one task per file in worker processes (``forkserver`` where available,
else ``spawn``: CoACD is C++ that holds the GIL, so threads would not help), kills a worker that
exceeds the per-file timeout and replaces it, and reports every task's outcome, so one failing
or stuck file never stops the others. A :class:`WorkerPool` can be started before the tasks
are known, so the workers' start-up overlaps the caller's reading of the input files.

Tasks always run in workers, one job included: native code that holds a process does not see
its signals, while the parent waiting on its workers does, at once. Interrupted (SIGINT, or
SIGTERM turned into an exception by the command line), the parent kills its workers as it
unwinds (:meth:`WorkerPool.close`); workers ignore SIGINT (a terminal's Ctrl-C reaches the
whole process group: the parent decides), and on Linux die with the process that forked them
(``PR_SET_PDEATHSIG``), so even a parent killed outright leaves none running.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from meshcol.decomposition.steps import reporting_to

__all__ = [
    "TaskOutcome",
    "WorkerPool",
    "run_tasks",
    "worker_env",
]

# Seconds a worker gets to exit after terminate() before kill().
_TERMINATE_GRACE = 2.0
# Longest single wait on the workers (a day; the loop waits again): what select() accepts.
_LONGEST_WAIT = 86400.0


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


# prctl(2) option: a signal for this process when the thread that forked it exits.
_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """Linux: SIGKILL this worker when its parent (the fork server, which exits with the main
    process) goes, however it goes. Elsewhere, and should the parent go before this runs, the
    worker still ends when it next reads its pipe (EOF) instead of a task."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)


def _watch_parent(alive: multiprocessing.connection.Connection) -> None:
    """End this worker the moment the process that started it is gone, however it went
    (SIGKILL too): a thread waits on a pipe whose only writing end that process holds, and
    the kernel closes it when the process dies. The worker's parent is the fork server, which
    outlives a killed main process, so ``_die_with_parent`` alone does not end it; this works
    on every platform, while the engine computes in the main thread."""

    def wait() -> None:
        try:
            alive.recv()
        except (EOFError, OSError):
            pass
        os._exit(1)

    threading.Thread(target=wait, name="meshcol-parent-watch", daemon=True).start()


def _worker_main(
    conn: multiprocessing.connection.Connection,
    fn: Callable[[Any], Any],
    env: dict[str, str],
    prepare: Callable[[], None] | None,
    alive: multiprocessing.connection.Connection | None = None,
) -> None:
    # Ctrl-C reaches the whole process group; the parent stops the workers itself.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent()
    if alive is not None:
        _watch_parent(alive)
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
        # the engine's own steps go to the parent as they happen (its progress line)
        with reporting_to(functools.partial(_send_step, conn, index)):
            status, value = _call(fn, task)
        conn.send((index, status, value))


#: The status of a worker's message that reports a step, not the task's outcome.
STEP = "step"


def _send_step(conn: multiprocessing.connection.Connection, index: int, snapshot: Any) -> None:
    conn.send((index, STEP, snapshot))


# Seconds between deliveries of a signal whose exception was swallowed (see _SignalGuard).
_REDELIVER_INTERVAL = 0.1


class _SignalGuard:
    """While a pool runs (main thread only): a SIGINT or SIGTERM whose handler raised is
    delivered again, every ``_REDELIVER_INTERVAL`` seconds, until its exception has left the
    pool's loop, in case code the loop calls swallowed it (trimesh catches ``BaseException``
    around its imports, which take seconds on a busy machine).

    Only handlers installed from Python are wrapped (the default SIGINT handler raises
    KeyboardInterrupt); a signal left to its default action ends the process, and the
    workers with it (``_die_with_parent``). While the loop is suspended at a ``yield`` the
    caller's own code runs: its exceptions are the caller's, and are never delivered again.
    """

    def __init__(self) -> None:
        self.previous: dict[int, Callable[[int, Any], Any]] = {}
        self.pending: int | None = None
        self.suspended = False
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> _SignalGuard:
        if threading.current_thread() is threading.main_thread():
            for number in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
                if number is None:
                    continue
                handler = signal.getsignal(number)
                if callable(handler):
                    self.previous[number] = handler
                    signal.signal(number, self._handle)
        return self

    def _handle(self, number: int, frame: Any) -> None:
        try:
            self.previous[number](number, frame)
        except BaseException:
            if not self.suspended:
                with self._lock:
                    self.pending = number
                    if self._thread is None:
                        self._thread = threading.Thread(target=self._redeliver, daemon=True)
                        self._thread.start()
            raise

    def _redeliver(self) -> None:
        while not self._done.wait(_REDELIVER_INTERVAL):
            with self._lock:
                if self.pending is not None and not self._done.is_set():
                    os.kill(os.getpid(), self.pending)

    def __exit__(self, *exc: object) -> None:
        with self._lock:
            self.pending = None
            self._done.set()
        for number, handler in self.previous.items():
            signal.signal(number, handler)


class _Pending(Exception):
    """A worker reported steps, and its task goes on."""


class _Worker:
    def __init__(
        self,
        ctx: Any,
        fn: Callable[[Any], Any],
        env: dict[str, str],
        prepare: Callable[[], None] | None,
    ) -> None:
        self.conn, child = ctx.Pipe()
        # `alive`: the worker's watchdog reads it; only this process holds its writing end
        watched, self.alive = ctx.Pipe(duplex=False)
        self.process = ctx.Process(
            target=_worker_main, args=(child, fn, env, prepare, watched), daemon=True
        )
        self.process.start()
        child.close()
        watched.close()
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
        self.alive.close()

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
            self.alive.close()


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread for the block (a signal that comes meanwhile waits)."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


#: What the fork server of a decompose run imports before it forks the workers: the heavy
#: modules every decomposition needs (not the engines: they load OpenMP, whose thread count
#: each worker sets first).
ENGINE_PRELOAD = (
    "meshcol.decomposition.decompose",
    "meshcol.decomposition.jobs",
    "scipy.spatial",
    "manifold3d",
    "trimesh",
)


def task_preload(fn: Callable[[Any], Any]) -> tuple[str, ...]:
    """What the fork server imports for the tasks of ``fn`` by default: this module and the
    meshcol module that defines ``fn`` (the task imports the rest it needs). An inspect or
    ``meshcol ci`` pool then imports no scipy or trimesh it would not use (issue 31)."""
    module = getattr(getattr(fn, "func", fn), "__module__", None) or ""
    extra = (module,) if module.startswith("meshcol.") and module != __name__ else ()
    return (__name__, *extra)


def _context(env: dict[str, str], preload: tuple[str, ...] = ENGINE_PRELOAD) -> Any:
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" not in methods:
        return multiprocessing.get_context("spawn")  # each worker applies `env` first
    ctx = multiprocessing.get_context("forkserver")
    # Workers fork from a server that has already imported ``preload``. The server inherits
    # this process's environment when it starts, and its preloaded numpy sizes its thread
    # pool then: start it with the workers' thread settings. One server serves the process:
    # the first pool's preload stays (a later pool's workers import what they miss).
    ctx.set_forkserver_preload(list(preload))
    # The server runs `python -c`, which puts the working folder first on sys.path before it
    # imports the preloaded modules: run from a folder that holds a `meshcol/` directory (the
    # repository's root, with a regular install), the workers imported that instead of the
    # installed package. PYTHONSAFEPATH (Python 3.11+) leaves it out, for the server and the
    # workers it forks.
    server_env = {**env, "PYTHONSAFEPATH": "1"}
    saved = {key: os.environ.get(key) for key in server_env}
    os.environ.update(server_env)
    try:
        from multiprocessing import forkserver, resource_tracker

        # The server and the workers it forks inherit a blocked SIGINT: a terminal's Ctrl-C,
        # sent to the whole process group, reaches only this process, which stops them (the
        # server would otherwise die mid-import with a traceback). The resource tracker
        # starts first: starting, it unblocks SIGINT itself.
        resource_tracker.ensure_running()
        with _sigint_blocked():
            forkserver.ensure_running()
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    return ctx


def _stop_fork_server() -> None:
    """Kill the fork server this process started, if any, at once (it exits by itself only
    after its preloading, when it sees that this process has gone). The server is private
    to ``multiprocessing``: when its layout differs, it is left to exit by itself."""
    from multiprocessing import forkserver

    server = getattr(forkserver, "_forkserver", None)
    pid = getattr(server, "_forkserver_pid", None)
    stop = getattr(server, "_stop", None)
    if pid is None or stop is None:
        return
    with contextlib.suppress(OSError):
        os.kill(pid, signal.SIGKILL)
    with contextlib.suppress(OSError):
        stop()  # closes our end of its pipe and reaps it (at once: it is dead)


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

    ``start()`` forks the workers (from a ``forkserver`` that has imported ``preload``:
    default :func:`task_preload`, :data:`ENGINE_PRELOAD` for decompose) and lets each run
    ``prepare`` (for instance, import the engine), so their start-up overlaps the caller's
    own work (reading the input files); ``run(tasks)`` then feeds them. A worker that
    exceeds ``timeout`` on a task is killed and replaced. Use as a context manager, or call
    ``close()``.
    """

    def __init__(
        self,
        fn: Callable[[Any], Any],
        jobs: int,
        *,
        timeout: float | None = None,
        threads_per_job: int | None = None,
        prepare: Callable[[], None] | None = None,
        preload: tuple[str, ...] | None = None,
    ) -> None:
        if jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {jobs}")
        self.fn, self.jobs, self.timeout, self.prepare = fn, jobs, timeout, prepare
        self.preload = task_preload(fn) if preload is None else preload
        self.env = worker_env(jobs, threads_per_job)
        self._ctx: Any = None
        #: receives (task index, steps snapshot) as workers report their steps
        self.on_step: Callable[[int, Any], None] | None = None
        self._idle: list[_Worker] = []
        self._busy: list[_Worker] = []

    @property
    def slots(self) -> int:
        """Tasks that run at once (``jobs``)."""
        return self.jobs

    def start(self, workers: int | None = None) -> WorkerPool:
        """Start ``workers`` (default ``jobs``, at most ``jobs``) processes now."""
        count = self.jobs if workers is None else min(workers, self.jobs)
        while len(self._idle) + len(self._busy) < count:
            self._idle.append(self._new_worker())
        return self

    def _new_worker(self) -> _Worker:
        if self._ctx is None:  # the fork server starts with the first worker, not before
            self._ctx = _context(self.env, self.preload)
        return _Worker(self._ctx, self.fn, self.env, self.prepare)

    def run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        """Run every task; yield outcomes as they complete.

        ``tasks`` may be a generator that reads a file per task: it is read ahead as fast as
        it goes, one task between polls of the workers, and each task goes to a worker as
        soon as one is free. So the first files are decomposed while the rest are read, and
        an exception from the generator (unusable input) comes as early as reading allows
        (busy workers are then killed on ``close()``).

        A SIGINT or SIGTERM whose handler raises (KeyboardInterrupt; ``meshcol``'s SIGTERM
        handler) is delivered again until its exception leaves this loop, should code that
        ``tasks`` calls swallow it (trimesh catches ``BaseException`` around its imports), so
        that an interrupt is never lost while workers run.
        """
        with _SignalGuard() as guard:
            for outcome in self._run(tasks):
                guard.suspended = True
                yield outcome
                guard.suspended = False

    def _run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        source = enumerate(tasks)
        more = True
        pending: deque[tuple[int, Any]] = deque()
        while True:
            self._assign(pending)
            if more:
                more = self._read_ahead(source, pending)
                if not self._busy:
                    continue
                wait_for: float | None = 0.0  # poll, then read on
            elif not self._busy:
                return
            else:
                wait_for = None
            yield from self._collect(self._wait(wait_for))

    def _assign(self, pending: deque[tuple[int, Any]]) -> None:
        """Give pending tasks to idle workers (new ones up to ``jobs``)."""
        while pending and len(self._busy) < self.jobs:
            worker = self._idle.pop() if self._idle else self._new_worker()
            worker.assign(*pending.popleft())
            self._busy.append(worker)

    @staticmethod
    def _read_ahead(source: Iterator[tuple[int, Any]], pending: deque[tuple[int, Any]]) -> bool:
        """Read one more task; False when there are no more."""
        item = next(source, None)
        if item is None:
            return False
        pending.append(item)
        return True

    def _wait(self, wait_for: float | None) -> set[Any]:
        """The busy workers' pipes and sentinels that are ready within ``wait_for`` seconds
        (None: until one is), at most until the first task's timeout."""
        if self.timeout is not None:
            now = time.perf_counter()
            limit = max(0.0, min(w.started + self.timeout for w in self._busy) - now)
            wait_for = limit if wait_for is None else min(wait_for, limit)
        handles: list[Any] = [w.conn for w in self._busy]
        handles += [w.process.sentinel for w in self._busy]
        if wait_for is not None:  # a timeout of 1e308 s waits as long as none: no overflow
            wait_for = min(wait_for, _LONGEST_WAIT)
        return set(multiprocessing.connection.wait(handles, wait_for))

    def _collect(self, ready: set[Any]) -> Iterator[TaskOutcome]:
        """The outcome of every busy worker that answered, died or ran out of time."""
        now = time.perf_counter()
        for worker in list(self._busy):
            seconds = now - worker.started
            if worker.conn in ready:
                try:
                    outcome = self._receive(worker, seconds)
                except _Pending:
                    outcome = None
                    ready.discard(worker.conn)  # steps only: the task goes on
                else:
                    if outcome is not None:
                        yield outcome
                        continue
                    ready.add(worker.process.sentinel)
            if worker.process.sentinel in ready:
                yield self._died(worker, seconds)
            elif self.timeout is not None and seconds >= self.timeout:
                yield self._timed_out(worker, seconds)

    def _receive(self, worker: _Worker, seconds: float) -> TaskOutcome | None:
        """A worker's answer (the worker is idle again), or None when its pipe broke. The
        step reports before it go to ``on_step``; with no answer yet, the worker stays busy
        (``_Pending``)."""
        try:
            while True:
                index, status, value = worker.conn.recv()
                if status != STEP:
                    break
                if self.on_step is not None:
                    self.on_step(index, value)
                if not worker.conn.poll():
                    raise _Pending
        except (EOFError, OSError):
            return None
        self._busy.remove(worker)
        self._idle.append(worker)
        if status == "ok":
            return TaskOutcome(index, status, value, seconds=seconds)
        return TaskOutcome(index, status, message=value, seconds=seconds)

    def _died(self, worker: _Worker, seconds: float) -> TaskOutcome:
        self._busy.remove(worker)
        worker.process.join()
        code = worker.process.exitcode
        worker.conn.close()
        return TaskOutcome(
            worker.task_index,
            "failed",
            message=f"worker process died (exit code {code})",
            seconds=seconds,
        )

    def _timed_out(self, worker: _Worker, seconds: float) -> TaskOutcome:
        self._busy.remove(worker)
        worker.kill()
        return TaskOutcome(
            worker.task_index,
            "timeout",
            message=f"timed out after {self.timeout:g} s",
            seconds=seconds,
        )

    def close(self, *, interrupted: bool = False) -> None:
        """Stop every worker: a busy one, or one that never had a task (it may still be
        loading the engine: nothing to wait for), is killed; the others exit cleanly.

        ``interrupted``: the run is being abandoned (a signal): every worker is killed, and
        the fork server too, which may still be importing its preloaded modules and would
        otherwise outlive this process by seconds.
        """
        for worker in self._busy:
            worker.kill()
        for worker in self._idle:
            if worker.used and not interrupted:
                worker.close()
            else:
                worker.kill()
        self._busy.clear()
        self._idle.clear()
        if interrupted and self._ctx is not None:
            _stop_fork_server()

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, kind: type[BaseException] | None, *exc: object) -> None:
        self.close(interrupted=kind is not None and not issubclass(kind, Exception))


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
        Worker processes (always at least one: tasks never run in this process, so that it
        stays responsive to signals while native code runs).
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
    with WorkerPool(fn, jobs, timeout=timeout, threads_per_job=threads_per_job) as workers:
        yield from workers.run(tasks)
