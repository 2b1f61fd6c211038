"""Where the tasks of a run execute: the local worker pool, or a Ray cluster.

:class:`Executor` is the one interface :mod:`meshcol.decomposition.batch` drives: ``start()``
(workers up, the engine loading, before the tasks are known), ``run(tasks)`` (outcomes as
they complete, one :class:`~meshcol.decomposition.jobs.TaskOutcome` per task) and
``close(interrupted=...)``. :class:`~meshcol.decomposition.jobs.WorkerPool` is the local
implementation; :class:`RayExecutor` runs one Ray task per file on a cluster (a local one
started on 127.0.0.1 by default, or ``address``), with the same per-task guarantees: a task
over ``timeout`` is cancelled by force (``ray.cancel(ref, force=True)``: its worker process is
killed), a worker that crashes or is killed fails only its task, and each task's engine gets
the thread settings the local pool gives its workers (:func:`~meshcol.decomposition.jobs.
worker_env`). Ray is imported only when a Ray executor starts (``pip install 'meshcol[ray]'``).
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any, Protocol

from meshcol.decomposition.jobs import (
    STEP,
    TaskOutcome,
    WorkerPool,
    _call,
    _sigint_blocked,
    _SignalGuard,
    worker_env,
)
from meshcol.decomposition.ray_start import (
    LIGHT_INIT,
    OWN_CLUSTER,
    in_worker,
    light_head,
    node_manager_address,
    prestart_workers,
    running_cluster,
    task_payload,
)
from meshcol.decomposition.run_keywords import check_run
from meshcol.decomposition.steps import reporting_to
from meshcol.errors import MissingDependencyError

__all__ = ["EXECUTORS", "Executor", "RayExecutor", "check_run", "make_executor", "run_each"]

#: The values of ``meshcol decompose --executor``.
EXECUTORS = ("local", "ray")

_RAY_HINT = "--executor ray needs Ray: pip install 'meshcol[ray]'"


class Executor(Protocol):
    """What runs the tasks of a run (the local pool, Ray)."""

    def start(self, workers: int | None = None) -> Executor:
        """Start up to ``workers`` workers now (they load the engine meanwhile)."""
        ...

    def run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        """Run every task (read lazily); yield outcomes as they complete."""
        ...

    def close(self, *, interrupted: bool = False) -> None:
        """Stop every worker (``interrupted``: at once, nothing waited for)."""
        ...


@contextlib.contextmanager
def _native_stderr_dropped() -> Iterator[None]:
    """Drop what is written to file descriptor 2 during the block: Ray's core logs each failed
    attempt to reach an address from C++ (about 25 lines for an unreachable one), past
    Python's logging; the error that follows is the command's one line."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        with open(os.devnull, "wb") as sink:
            os.dup2(sink.fileno(), 2)
        yield
    finally:
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def make_executor(
    kind: str,
    fn: Callable[[Any], Any],
    jobs: int,
    *,
    timeout: float | None = None,
    threads_per_job: int | None = None,
    prepare: Callable[[], None] | None = None,
    address: str | None = None,
    preload: tuple[str, ...] | None = None,
) -> Executor:
    """The executor ``kind`` (``local`` or ``ray``) for ``fn`` over ``jobs`` parallel tasks.

    ``preload``: local only, what the workers' fork server imports first (default the
    task's module: :func:`~meshcol.decomposition.jobs.task_preload`).

    ``address``: Ray only, the cluster to join (``ray://host:10001``, ``host:6379``, ``auto``);
    default a running Ray (``RAY_ADDRESS``, ``ray start`` on this machine), else a local Ray
    of ``jobs`` CPUs on 127.0.0.1, stopped on ``close()`` (``"local"``: always that).

    Raises
    ------
    ValueError
        An unknown ``kind``, or ``address`` with the local executor.
    MissingDependencyError
        ``ray`` without Ray installed.
    """
    if kind == "local":
        if address is not None:
            raise ValueError("a Ray address needs the ray executor")
        return WorkerPool(
            fn,
            jobs,
            timeout=timeout,
            threads_per_job=threads_per_job,
            prepare=prepare,
            preload=preload,
        )
    if kind == "ray":
        return RayExecutor(
            fn,
            jobs,
            timeout=timeout,
            threads_per_job=threads_per_job,
            prepare=prepare,
            address=address,
        )
    raise ValueError(f"unknown executor {kind!r}: expected one of {', '.join(EXECUTORS)}")


def run_each(
    fn: Callable[[Any], Any],
    tasks: Sequence[Any],
    *,
    executor: str = "local",
    jobs: int = 1,
    timeout: float | None = None,
    address: str | None = None,
) -> Iterator[TaskOutcome]:
    """Run ``fn(task)`` for every task on the executor ``executor``; yield outcomes as they
    complete: the per-file tasks of ``inspect`` and ``check`` (``decompose`` drives its
    executor itself, to overlap reading with the work).

    The executor starts with ``min(jobs, len(tasks))`` workers and is closed however the
    caller leaves: abandoning the generator (an exception, ``close()``) or a signal kills
    every worker at once (a local Ray started for the run is stopped). Each task's threads
    are the local pool's share (:func:`~meshcol.decomposition.jobs.worker_env`).
    """
    if not tasks:
        return
    pool = make_executor(executor, fn, jobs, timeout=timeout, address=address)
    try:
        pool.start(min(jobs, len(tasks)))
        outcomes = pool.run(tasks)
        try:
            yield from outcomes
        finally:
            # closed here, not when garbage collected: the pool's signal handlers go with it
            getattr(outcomes, "close", lambda: None)()
    except BaseException as exc:
        pool.close(interrupted=not isinstance(exc, Exception))
        raise
    pool.close()


def import_ray(local: bool = False) -> Any:
    """The ``ray`` module, or MissingDependencyError with the install hint.

    ``local``: a local Ray may be started; on Linux, Ray resolves 127.0.0.1 to the machine's
    network address unless told that this is no multi-machine cluster (the variable below,
    read when Ray is first imported), so a local Ray binds to the loopback address only.
    The same for a cluster at a loopback address (see :func:`_loopback_only`)."""
    if local and "ray" not in sys.modules:
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    try:
        import ray
    except ImportError:
        raise MissingDependencyError(_RAY_HINT) from None
    return ray


def _is_loopback(address: str) -> bool:
    """``127.0.0.1:6379``, ``localhost:6379``, ``[::1]:6379`` (``ray://`` too): a cluster on
    this machine's loopback interface only."""
    host = address.split("://", 1)[-1].rsplit(":", 1)[0].strip("[]").lower()
    return host in ("localhost", "::1") or host.startswith("127.")


def _is_local(address: str) -> bool:
    """A cluster whose head is on this machine (a loopback address, or one ``ray start``
    recorded here): not Ray Client (``ray://``), whose raylets this process cannot reach."""
    return not address.startswith("ray://") and (
        _is_loopback(address) or address == running_cluster()
    )


@contextlib.contextmanager
def _loopback_only(address: str) -> Iterator[None]:
    """While joining a cluster at a loopback address: Ray rewrites 127.0.0.1 in the address
    to this machine's network address (its multi-machine default), where a cluster started
    with ``--node-ip-address=127.0.0.1`` does not listen, and ``ray.init`` then retries for
    minutes. The environment variable of :func:`import_ray` is read only when Ray is first
    imported; when Ray was imported before, its (private) constant is set for the call."""
    if not _is_loopback(address):
        yield
        return
    try:
        from ray._private import ray_constants
    except ImportError:  # another layout: the variable of import_ray is all there is
        yield
        return
    previous = getattr(ray_constants, "ENABLE_RAY_CLUSTER", None)
    ray_constants.ENABLE_RAY_CLUSTER = False
    try:
        yield
    finally:
        if previous is not None:
            ray_constants.ENABLE_RAY_CLUSTER = previous


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """SIGINT and SIGTERM held back during the block, then honoured (their handler called,
    so KeyboardInterrupt or meshcol's ``Terminated`` is raised at the block's end).

    Around ``ray.init`` and ``ray.shutdown``: an exception raised by a signal inside either,
    or between ``ray.init``'s return and the executor recording that it owns that Ray, left
    Ray's core worker running, never shut down, to the interpreter's exit, where its threads
    crashed the process (SIGSEGV in ``TaskManager::RecordMetrics`` instead of exit 130: one
    Ctrl-C test run in 3 to 12 here). Blocking SIGINT in this thread is not enough: Python
    runs handlers in the main thread whichever thread the signal reached (the progress
    timer's, Ray's), so the handlers are replaced for the block. SIGINT is also blocked in
    this thread, for the processes started meanwhile to inherit (see ``_connect``).
    """
    if threading.current_thread() is not threading.main_thread():
        with _sigint_blocked():
            yield
        return
    caught: list[int] = []
    previous: dict[int, Callable[[int, Any], Any]] = {}
    for number in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
        if number is None:
            continue
        handler = signal.getsignal(number)
        if callable(handler):
            previous[number] = handler
            signal.signal(number, lambda n, _frame: caught.append(n))
    try:
        with _sigint_blocked():  # a SIGINT pending on this thread arrives as the mask goes
            yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        for number in dict.fromkeys(caught):
            previous[number](number, None)


def _errors_to_stderr() -> None:
    """Ray's driver prints the cluster's error messages (``(raylet) A worker died or was
    killed ...``) on stdout, whatever ``log_to_driver``: on a killed worker it corrupted the
    report that ``meshcol inspect --executor ray > report.json`` writes there. Once this
    process has connected an executor, they go to stderr, with meshcol's own messages (the
    failure is also the file's error in the report); for good, as a message may come after
    the run, while the report is written. Ray's printer is private: if its layout differs,
    nothing is changed."""
    from ray._private import worker

    original = getattr(worker, "print_to_stdstream", None)
    if original is None or getattr(original, "_meshcol_stderr", False):
        return

    def to_stderr(data: dict[str, Any], *args: Any, **kwargs: Any) -> Any:
        return original({**data, "is_err": True}, *args, **kwargs)

    to_stderr._meshcol_stderr = True  # type: ignore[attr-defined]
    worker.print_to_stdstream = to_stderr


@contextlib.contextmanager
def _prompt_stop() -> Iterator[None]:
    """While ``ray.shutdown`` stops the local Ray this process started: the processes after
    the raylet are stopped together, not one by one.

    Ray stops its processes one at a time, each with a SIGTERM and up to a second's wait
    before a SIGKILL. The raylet exits within that second (it stops its workers and agents
    first), but the GCS server and the autoscaler monitor did not, here: each took its whole
    second, about 1 s of a 1.1-1.35 s shutdown, on every run. During the block, once the
    raylet is stopped as Ray stops it, the others get their SIGTERM together and 0.25 s to
    exit; Ray's own loop then kills (SIGKILL) and reaps whatever is left. Nothing of a run is
    in those processes (the driver has every result), and they are the ones Ray would kill a
    second later. Ray's node object is private: if its layout differs, Ray stops them as
    usual.
    """
    try:
        from ray._private import ray_constants
        from ray._private import worker as ray_worker

        node: Any = ray_worker._global_node
        raylet = ray_constants.PROCESS_TYPE_RAYLET
        original = node.kill_all_processes
        node.all_processes  # noqa: B018 - the layout this relies on
        node._kill_process_type  # noqa: B018
    except (ImportError, AttributeError):
        yield
        return

    def kill_all(check_alive: bool = True, allow_graceful: bool = False, wait: bool = False) -> Any:
        if allow_graceful:
            if raylet in node.all_processes:
                node._kill_process_type(raylet, check_alive=False, allow_graceful=True, wait=wait)
            live = [
                info.process
                for infos in node.all_processes.values()
                for info in infos
                if info.process.poll() is None
            ]
            for process in live:
                process.terminate()
            deadline = time.monotonic() + 0.25
            while time.monotonic() < deadline and any(p.poll() is None for p in live):
                time.sleep(0.005)
        return original(check_alive=check_alive, allow_graceful=False, wait=wait)

    node.kill_all_processes = kill_all
    try:
        yield
    finally:
        node.kill_all_processes = original


def _local_ray_processes() -> list[Any]:
    """Every process of the local Ray this process started: the ones Ray tracks (the raylet,
    the GCS server, the monitors) and their descendants (the workers, the agents), as
    ``psutil`` processes; empty if Ray's node layout or psutil (bundled with Ray) is absent."""
    try:
        import psutil  # type: ignore[import-untyped]
        from ray._private import worker as ray_worker

        node: Any = ray_worker._global_node
        tracked = [info.process.pid for infos in node.all_processes.values() for info in infos]
    except (ImportError, AttributeError):
        return []
    found: dict[int, Any] = {}
    for pid in tracked:
        try:
            process = psutil.Process(pid)
            for each in [process, *process.children(recursive=True)]:
                found[each.pid] = each
        except psutil.Error:
            continue
    return list(found.values())


def _stop_remaining(processes: Sequence[Any], grace: float = 2.0, bound: float = 10.0) -> None:
    """Wait (at most ``grace`` s) for ``processes`` to exit after ``ray.shutdown``, kill
    (SIGKILL) what is left, and wait (at most ``bound`` s) for those to be gone.

    Ray stops the processes it tracks, but the raylet's children (its workers and agents)
    exit on their own once the raylet is gone; on a loaded machine the raylet outlived its
    second of grace, was killed, and its orphans were still running when ``close()``
    returned (two, under two CPU-bound processes, every run). Nothing of a run is in them."""
    if not processes:
        return
    import psutil

    _, alive = psutil.wait_procs(processes, timeout=grace)
    for process in alive:
        try:
            process.kill()
        except psutil.Error:
            continue
    psutil.wait_procs(alive, timeout=bound)


def _ray_call(
    fn: Callable[[Any], Any], task: Any, env: Mapping[str, str] | None = None
) -> Iterator[tuple[str, Any]]:
    """Runs in a Ray worker, as a Ray generator: the task's steps as it makes them
    (``(STEP, snapshot)``, :mod:`meshcol.decomposition.steps`), then its outcome (an error of
    the task is its outcome, as in the local pool; only a dead or cancelled worker reaches
    the driver as a Ray error). The task runs in a thread of the worker; this generator
    passes on what it reports, so the driver's progress line has the steps on Ray too.
    ``env``: on a cluster, the task comes pickled, opened once the thread settings are in
    place (ray_start.in_worker)."""
    if env is not None:
        task = in_worker(env, task)
    reports: queue.Queue[tuple[str, Any]] = queue.Queue()

    def work() -> None:
        with reporting_to(lambda snapshot: reports.put((STEP, snapshot))):
            outcome = _call(fn, task)
        reports.put(("done", outcome))

    threading.Thread(target=work, name="meshcol-task", daemon=True).start()
    while True:
        kind, value = reports.get()
        yield kind, value
        if kind == "done":
            return


def _is_pair(value: Any) -> bool:
    return isinstance(value, tuple) and len(value) == 2


def _ray_prepare(prepare: Callable[[], None]) -> None:
    # A task of its own, sent through _ray_call like the others: tasks of one remote function
    # are one scheduling class, for which Ray leases the same workers (a second function got
    # a third worker started on a two-CPU cluster, seconds after the first two).
    try:
        prepare()
    except Exception:  # noqa: BLE001 - the first task meets the same error and reports it
        pass


class RayExecutor:
    """One Ray task per file, on a local Ray (default) or the cluster at ``address``.

    At most ``slots`` tasks are in flight (``jobs`` on the local Ray it starts; the cluster's
    CPU count otherwise), so that a library is never submitted, nor held in memory, whole, and
    a task's ``timeout`` counts from its submission, which is when a free CPU starts it (Ray's
    worker start-up, the first time, included). Tasks are not retried (``max_retries=0``): a
    file whose worker died is reported failed, like the local pool's.

    Parameters
    ----------
    fn : callable
        What each task runs (pickled to the workers: a module-level function, or a closure).
    jobs : int
        CPUs of the local Ray this starts (ignored with ``address``).
    timeout : float, optional
        Seconds per task before it is cancelled by force.
    threads_per_job : int, optional
        OpenMP threads per task (default as the local pool: :func:`worker_env`).
    prepare : callable, optional
        Run once per worker by ``start()`` (loads the engine).
    address : str, optional
        A running cluster. Default: the Ray already running that
        :func:`~meshcol.decomposition.ray_start.running_cluster` finds (``RAY_ADDRESS``, a
        ``ray start`` on this machine), else a light local Ray is started, and stopped by
        ``close()``; ``"local"``: always that. A Ray already initialised in this process
        (``ray.init()`` by the caller) is used as is.
    """

    def __init__(
        self,
        fn: Callable[[Any], Any],
        jobs: int,
        *,
        timeout: float | None = None,
        threads_per_job: int | None = None,
        prepare: Callable[[], None] | None = None,
        address: str | None = None,
    ) -> None:
        if jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {jobs}")
        self.fn, self.jobs, self.timeout, self.prepare = fn, jobs, timeout, prepare
        found = address is None
        if address is None:
            # a Ray already running (RAY_ADDRESS, `ray start`) is joined; else one is started
            address = running_cluster()
        elif address == OWN_CLUSTER:
            address = None
        self._found = found and address is not None
        self.address = address
        self.ray = import_ray(local=address is None or _is_loopback(address))
        self._owned = False
        self._remote: Any = None
        self._task_env: dict[str, str] | None = None
        self._slots = jobs
        self._inflight: dict[Any, tuple[int, float]] = {}
        #: receives (task index, steps snapshot) as tasks report their steps
        self.on_step: Callable[[int, Any], None] | None = None
        # Environment of each task's worker: the local pool's thread settings for ``jobs``
        # processes; on a cluster, each CPU runs a task (the pool's ``jobs == cores``).
        self.env = worker_env(jobs, threads_per_job)
        if address is not None and threads_per_job is None:
            self.env = {**self.env, "OMP_NUM_THREADS": "2", "OPENBLAS_NUM_THREADS": "1"}

    @property
    def slots(self) -> int:
        """Tasks in flight at most (after ``start()``)."""
        return self._slots

    def _connect(self) -> None:
        if self._remote is not None:
            return
        ray = self.ray
        if not ray.is_initialized():
            common = {
                "include_dashboard": False,
                "logging_level": logging.ERROR,
                "log_to_driver": False,
                "configure_logging": True,
            }
            # Signals deferred from before ray.init until this executor owns the Ray it started
            # or joined (see _signals_deferred). A local Ray's processes also inherit the
            # blocked SIGINT, so a terminal's Ctrl-C (sent to the whole process group) reaches
            # only this process, which stops them (ray.shutdown) instead of leaving a
            # half-dead cluster.
            with _signals_deferred():
                if self.address is None:
                    self._init_local(ray, common)
                else:
                    common.pop("include_dashboard")
                    with _loopback_only(self.address), _native_stderr_dropped():
                        try:
                            ray.init(address=self.address, **common)
                        except ConnectionError as exc:
                            message = _join_failure(self.address, exc)
                            if self._found:
                                message += (
                                    f"; {self.address} was found running ($RAY_ADDRESS or "
                                    "`ray start`): --ray-address local starts a Ray of the "
                                    "run's own"
                                )
                            raise ConnectionError(message) from None
                self._owned = True
        _errors_to_stderr()
        if self.address is None and self._owned:
            self._slots = self.jobs
        else:
            cpus = int(ray.cluster_resources().get("CPU", 0))
            self._slots = max(1, cpus)
        options: dict[str, Any] = {"num_cpus": 1, "max_retries": 0}
        # A cluster (or a Ray the caller started): the thread settings go with each task, set
        # by the task itself. Not a runtime_env: Ray starts new workers for one (seconds each),
        # never the idle ones the cluster keeps (ray_start.in_worker).
        self._task_env = None if self._owned and self.address is None else dict(self.env)
        self._remote = ray.remote(_ray_call).options(**options)

    def _init_local(self, ray: Any, common: dict[str, Any]) -> None:
        # The local Ray's processes inherit this environment: its workers, prestarted with
        # it, run the tasks as they are (a per-task environment would start other workers,
        # seconds each on a small machine). It starts light (ray_start.light_head).
        saved = {key: os.environ.get(key) for key in self.env}
        os.environ.update(self.env)
        try:
            with light_head():
                ray.init(
                    address="local",
                    num_cpus=self.jobs,
                    _node_ip_address="127.0.0.1",
                    **{**common, **LIGHT_INIT},
                )
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value

    def start(self, workers: int | None = None) -> RayExecutor:
        """Join or start the cluster; with ``prepare``, warm up to ``workers`` workers."""
        self._connect()
        if self.prepare is not None:
            count = self._slots if workers is None else min(workers, self._slots)
            # Fire and forget: each warms a worker (the engine imported) that later tasks reuse.
            prepare: Any = self.prepare
            if self._task_env is not None:
                prepare = task_payload(prepare)
            for _ in range(count):
                self._remote.remote(_ray_prepare, prepare, self._task_env)
        return self

    def run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        """Run every task; yield outcomes as they complete (see ``WorkerPool.run``: tasks are
        read ahead one per poll, and a signal is never lost while tasks run)."""
        self._connect()
        with _SignalGuard() as guard:
            for outcome in self._run(tasks):
                guard.suspended = True
                yield outcome
                guard.suspended = False

    def _run(self, tasks: Iterable[Any]) -> Iterator[TaskOutcome]:
        ray = self.ray
        source = enumerate(tasks)
        more = True
        pending: list[tuple[int, Any]] = []
        inflight, timeout = self._inflight, self.timeout
        while True:
            while pending and len(inflight) < self._slots:
                index, task = pending.pop(0)
                if self._task_env is not None:
                    task = task_payload(task)
                ref = self._remote.remote(self.fn, task, self._task_env)
                inflight[ref] = (index, time.perf_counter())
            if more:
                item = next(source, None)
                if item is None:
                    more = False
                else:
                    pending.append(item)
                if not inflight:
                    continue
                wait_for: float | None = 0.0
            elif not inflight:
                return
            else:
                wait_for = None
            now = time.perf_counter()
            if timeout is not None:
                limit = max(0.0, min(t + timeout for _, t in inflight.values()) - now)
                wait_for = limit if wait_for is None else min(wait_for, limit)
            # Bounded waits, so that a signal's exception is raised here within a second.
            wait_for = 1.0 if wait_for is None else min(wait_for, 1.0)
            ready, _ = ray.wait(list(inflight), num_returns=1, timeout=wait_for)
            if ready:
                # Collect everything that is done now, not one per wait.
                ready, _ = ray.wait(list(inflight), num_returns=len(inflight), timeout=0)
            now = time.perf_counter()
            for ref in ready:
                outcome = self._next(ref, now)
                if outcome is not None:
                    yield outcome
            if timeout is not None:
                now = time.perf_counter()
                for ref, (index, started) in list(inflight.items()):
                    if now - started >= timeout:
                        del inflight[ref]
                        self._cancel(ref)
                        yield TaskOutcome(
                            index,
                            "timeout",
                            message=f"timed out after {timeout:g} s",
                            seconds=now - started,
                        )

    def _next(self, generator: Any, now: float) -> TaskOutcome | None:
        """The next item of a task (a Ray generator, :func:`_ray_call`) that has one: its
        steps go to ``on_step`` (None: the task goes on), its outcome ends it."""
        ray = self.ray
        index, started = self._inflight[generator]
        try:
            item = ray.get(next(generator))
        except StopIteration:  # cannot happen: the outcome is its last item
            item = ("done", ("failed", "the task ended without an outcome"))
        except ray.exceptions.RayError as exc:
            del self._inflight[generator]
            return TaskOutcome(index, "failed", message=_ray_failure(exc), seconds=now - started)
        if _is_pair(item) and item[0] == STEP:
            if self.on_step is not None:
                self.on_step(index, item[1])
            return None
        del self._inflight[generator]
        if not (_is_pair(item) and item[0] == "done" and _is_pair(item[1])):
            # A worker of another meshcol build (a cluster installed apart from this run)
            # answers in another form: never read as an outcome (an old driver took a new
            # worker's steps for results and passed a run of 0 bodies).
            message = (
                "the Ray worker's reply is not this meshcol's: is the cluster running "
                "another meshcol build?"
            )
            return TaskOutcome(index, "failed", message=message, seconds=now - started)
        status, result = item[1]
        if status == "ok":
            return TaskOutcome(index, status, result, seconds=now - started)
        return TaskOutcome(index, status, message=result, seconds=now - started)

    def _cancel(self, ref: Any) -> None:
        try:
            self.ray.cancel(ref, force=True)
        except Exception:  # noqa: BLE001 - a task that ended meanwhile needs no cancel
            pass

    def close(self, *, interrupted: bool = False) -> None:
        """Cancel (by force) what is still in flight; stop the local Ray this started."""
        if not self._owned:
            # A cluster outlives the run: its tasks of this run are stopped one by one. A
            # local Ray this started goes whole with its workers (ray.shutdown).
            for ref in list(self._inflight):
                self._cancel(ref)
        self._inflight.clear()
        if self._owned:
            # A cluster joined on this machine keeps idle workers ready for the next run (see
            # ray_start.prestart_workers), once this run's job (and its workers) is gone.
            raylet = None
            if self.address is not None and not interrupted and _is_local(self.address):
                raylet = node_manager_address(self.ray)
            # Never interrupted half-way (see _signals_deferred).
            with _signals_deferred():
                started = _local_ray_processes()
                with _prompt_stop():
                    self.ray.shutdown()
                    self._owned = False
                _stop_remaining(started)
            if raylet is not None:
                prestart_workers(raylet, self._slots)
        self._remote = None

    def __enter__(self) -> RayExecutor:
        return self

    def __exit__(self, kind: type[BaseException] | None, *exc: object) -> None:
        self.close(interrupted=kind is not None and not issubclass(kind, Exception))


def _join_failure(address: str, exc: BaseException, environ: Any = None) -> str:
    """One line for a Ray cluster that could not be joined, with the hint a cluster started
    with token authentication needs (Ray says only "Failed to connect" when the token is
    missing: its GCS refuses the client, ``InvalidAuthToken``, in log lines of its own)."""
    environ = os.environ if environ is None else environ
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    if environ.get("RAY_AUTH_MODE", "").lower() == "token":
        return f"{first} (RAY_AUTH_MODE=token: is the token the cluster's?)"
    return (
        f"{first}; a cluster started with token authentication needs RAY_AUTH_MODE=token "
        "here too, with its token in RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token"
    )


def _ray_failure(exc: BaseException) -> str:
    """One line for a task Ray could not finish (a dead worker, a lost node)."""
    name = type(exc).__name__
    if "WorkerCrashed" in name or "ActorDied" in name:
        return f"worker process died ({name})"
    if "NodeDied" in name or "ObjectLost" in name or "OwnerDied" in name:
        return f"Ray lost the task's node or result ({name})"
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{name}: {first}" if first else name
