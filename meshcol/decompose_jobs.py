"""Running decompositions over many files, and writing their parts.

:func:`run_tasks` runs one task per file in worker processes (``forkserver`` where available,
else ``spawn``: CoACD is C++ that holds the GIL, so threads would not help), kills a worker that
exceeds the per-file timeout and replaces it, and reports every task's outcome, so one failing
or stuck file never stops the others. A :class:`WorkerPool` can be started before the tasks
are known, so the workers' start-up overlaps the caller's reading of the input files. The writers produce byte-identical files for identical
parts: fixed float formatting (shortest round-trip ``repr``), no timestamps, fixed JSON key
order in GLB.
"""

from __future__ import annotations

import json
import multiprocessing
import multiprocessing.connection
import os
import re
import struct
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.report import atomic_path

__all__ = [
    "TaskOutcome", "WorkerPool", "run_tasks", "worker_env", "write_parts", "obj_text", "glb_bytes",
    "safe_name", "decompose_task", "prepare_engine",
]

LAYOUTS = ("parts", "combined", "ucx")
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
        self, ctx: Any, fn: Callable[[Any], Any], env: dict[str, str], prepare: Callable[[], None] | None
    ) -> None:
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, fn, env, prepare), daemon=True)
        self.process.start()
        child.close()
        self.index: int | None = None
        self.started = 0.0
        self.used = False

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
        ["meshcol.decompose", "meshcol.decompose_jobs", "scipy.spatial", "manifold3d", "trimesh"]
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
    and a last long file does not run on one core while the rest idle (measured on 2 cores,
    10 corpus meshes: 17.6 s with two threads per worker against 19.1 s with one). numpy's
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
        # BLAS spins on every core and the workers slow each other down (measured: --jobs 2
        # at 0.93x).
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
                        worker.index, "failed", message=f"worker process died (exit code {code})", seconds=seconds
                    )
                elif timeout is not None and seconds >= timeout:
                    busy.remove(worker)
                    worker.kill()
                    yield TaskOutcome(
                        worker.index, "timeout", message=f"timed out after {timeout:g} s", seconds=seconds
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

_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def safe_name(name: str) -> str:
    """``name`` reduced to characters that are safe in file and object names."""
    cleaned = _UNSAFE.sub("_", name).strip("._")
    return cleaned or "body"


def _number(x: float) -> str:
    return repr(float(x) + 0.0)  # +0.0 turns -0.0 into 0.0


def obj_text(objects: Sequence[tuple[str, np.ndarray, np.ndarray]]) -> str:
    """Wavefront OBJ with one ``o`` object per (name, vertices, faces), 1-based global indices."""
    lines = ["# meshcol decompose"]
    base = 1
    for name, vertices, faces in objects:
        lines.append(f"o {name}")
        lines.extend(f"v {_number(x)} {_number(y)} {_number(z)}" for x, y, z in vertices.tolist())
        lines.extend(f"f {a + base} {b + base} {c + base}" for a, b, c in faces.tolist())
        base += len(vertices)
    return "\n".join(lines) + "\n"


def glb_bytes(objects: Sequence[tuple[str, np.ndarray, np.ndarray]]) -> bytes:
    """Binary glTF 2.0 with one node (and mesh) per (name, vertices, faces).

    Positions are float32 (as glTF requires), indices uint32; no timestamps, sorted JSON keys.
    """
    blob = bytearray()
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []
    meshes: list[dict[str, Any]] = []
    nodes: list[dict[str, Any]] = []
    for i, (name, vertices, faces) in enumerate(objects):
        position = np.ascontiguousarray(vertices, dtype="<f4")
        index = np.ascontiguousarray(faces, dtype="<u4").reshape(-1)
        for data, target in ((position, 34962), (index, 34963)):
            views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes, "target": target})
            blob += data.tobytes()
            blob += b"\0" * (-len(blob) % 4)
        accessors.append({
            "bufferView": 2 * i, "componentType": 5126, "count": len(position), "type": "VEC3",
            "min": position.min(axis=0).astype(float).tolist(),
            "max": position.max(axis=0).astype(float).tolist(),
        })
        accessors.append({"bufferView": 2 * i + 1, "componentType": 5125, "count": len(index), "type": "SCALAR"})
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": 2 * i}, "indices": 2 * i + 1, "mode": 4}]})
        nodes.append({"name": name, "mesh": i})
    doc = {
        "asset": {"version": "2.0", "generator": "meshcol decompose"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    text = json.dumps(doc, sort_keys=True, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    out = bytearray(struct.pack("<4sII", b"glTF", 2, total))
    out += struct.pack("<I4s", len(text), b"JSON") + text
    out += struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob)
    return bytes(out)


def part_names(body: str, count: int, prefix: str = "") -> list[str]:
    """``[prefix]<body>_NN`` for each part, NN zero-padded to at least two digits."""
    width = max(2, len(str(count - 1)))
    return [f"{prefix}{body}_{i:0{width}d}" for i in range(count)]


def write_parts(
    body: str,
    parts: Sequence[tuple[np.ndarray, np.ndarray]],
    out_dir: str | os.PathLike[str],
    layout: str = "parts",
    fmt: str = "obj",
) -> list[str]:
    """Write parts in a layout; returns the paths written, in order.

    ``parts``: one file per part, ``<body>_NN.obj`` (or ``.glb``); ``combined``: one
    ``<body>.obj`` with one object per part, or one ``<body>.glb`` with one node per part;
    ``ucx``: one ``<body>_ucx.obj`` whose objects are named ``UCX_<body>_NN`` (Unreal's
    convention for custom collision). Every file is written atomically.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"unknown layout {layout!r}")
    if fmt not in ("obj", "glb"):
        raise ValueError(f"unknown format {fmt!r}")
    body = safe_name(body)
    out_dir = os.fspath(out_dir)
    written: list[str] = []

    def emit(path: str, objects: list[tuple[str, np.ndarray, np.ndarray]]) -> None:
        data: str | bytes = glb_bytes(objects) if path.endswith(".glb") else obj_text(objects)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                f.write(data if isinstance(data, bytes) else data.encode())
        written.append(path)

    if layout == "parts":
        for name, (v, f) in zip(part_names(body, len(parts)), parts):
            emit(os.path.join(out_dir, f"{name}.{fmt}"), [(name, v, f)])
    elif layout == "combined":
        names = part_names(body, len(parts))
        emit(os.path.join(out_dir, f"{body}.{fmt}"), [(n, v, f) for n, (v, f) in zip(names, parts)])
    else:
        names = part_names(body, len(parts), prefix="UCX_")
        emit(os.path.join(out_dir, f"{body}_ucx.obj"), [(n, v, f) for n, (v, f) in zip(names, parts)])
    return written


def prepare_engine(engine: str) -> None:
    """Worker start-up: import the engine's module (and so its OpenMP runtime) ahead of the
    first task."""
    if engine == "coacd":
        import coacd  # noqa: F401
    elif engine == "vhacd":
        import vhacdx  # noqa: F401


def decompose_task(task: tuple[str, list[tuple[str, np.ndarray, np.ndarray]], dict[str, Any]]) -> list[tuple[str, Any]]:
    """Worker entry: decompose every body of one file. ``task`` = (path, bodies, options)."""
    from meshcol.decompose import decompose

    _, bodies, options = task
    return [(name, decompose((vertices, faces), **options)) for name, vertices, faces in bodies]
