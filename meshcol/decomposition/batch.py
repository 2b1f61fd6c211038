"""Convex decomposition of many files, or of many meshes: the runs behind ``meshcol decompose``.

Files are read one by one and each goes to a worker (:mod:`meshcol.decomposition.jobs`) as
soon as it is read, so work starts at once and a library is never held in memory whole. Cached
bodies are looked up before a file is sent, and what the workers return is stored in the cache
by this process, entry by entry as files finish (a worker never writes it;
:mod:`meshcol.decomposition.tasks`). Every output location is checked before the work starts
(:func:`meshcol.io.outputs.check_outputs`), and each file's planned parts against the inputs
and the caller's other outputs as it is read. Unusable input still stops the run before
anything is written: the parts are written at the end, all together
(:mod:`meshcol.decomposition.writing`), and the cache entries of the files before the bad one
are valid entries.
"""

from __future__ import annotations

import contextlib
import functools
import os
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from meshcol.decomposition.options import DecomposeOptions, RunOptions, split_fields
from meshcol.decomposition.report import DecomposeReport
from meshcol.decomposition.steps import ProgressText, Snapshot, StepClock, describe
from meshcol.decomposition.tasks import (
    BodyMesh,
    TaskOptions,
    decompose_task,
    is_complete,
    iter_files,
    look_up,
    store_result,
    worker_entry,
)
from meshcol.decomposition.writing import FileResult, OutputGuard, PartsLayout, write_files
from meshcol.errors import InvalidMeshError, MeshcolError
from meshcol.io.robot import RobotOptions

__all__ = ["decompose_files", "decompose_meshes"]


def decompose_files(
    inputs: Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str],
    options: DecomposeOptions | None = None,
    run: RunOptions | None = None,
    *,
    layout: str = "parts",
    fmt: str = "obj",
    target: Any = None,
    progress: Callable[[str], None] | None = None,
    other_outputs: Sequence[str | os.PathLike[str]] = (),
    run_manifest: str | os.PathLike[str] | None = None,
    resume: bool = False,
    robot_options: RobotOptions | None = None,
    **fields: Any,
) -> DecomposeReport:
    """Decompose every body of every input file into convex parts and write them.

    Parameters
    ----------
    inputs : sequence of paths
        Mesh files (every object, solid or mesh node is a body) or one scene manifest.
    out_dir : path
        Folder for the parts (created if missing), in the world frame (each body's pose
        applied).
    options, run : DecomposeOptions, RunOptions, optional
        What decides the parts and what the run aims at (the fidelity target, its search);
        where the files go (one task each) and the cache.
    layout, fmt : {"parts", "combined", "ucx"}, {"obj", "glb"}
        Files per body (:func:`meshcol.io.mesh_write.write_parts`), their format.
    target : Target, optional
        An engine profile (:mod:`meshcol.io.targets`): its vertex budget and hull count go to
        the engine (:meth:`DecomposeOptions.aimed_at`), then every body's parts are fitted to
        all its limits, still enclosing (:func:`meshcol.decomposition.target.apply_target`).
        A limit that cannot be met fails the run (exit 1).
    progress : callable, optional
        Receives one-line progress messages (``decompose: 3/10 files``).
    other_outputs : sequence of paths
        Files the caller will write besides the parts (``--report``): parts that would
        replace one, or an input, are an error before anything is written.
    run_manifest : path, optional
        Keep every file's state in this JSON file as the run goes
        (:mod:`meshcol.decomposition.manifest`); needs the cache.
    resume : bool
        Read ``run_manifest`` first: files done are taken from the cache, the others run.
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.iter_inputs`).
    **fields
        Fields of either (``engine="vhacd"``, ``jobs=4``), which replace those given.

    Returns
    -------
    DecomposeReport
        ``exit_code`` 1 when a file failed or timed out or a body misses the fidelity target
        or a limit of the engine target.

    Raises
    ------
    ValueError
        Options refused, or that contradict each other (``ucx`` with ``glb``, ``resume``
        without ``run_manifest``, a run manifest without the cache).
    MeshcolError
        Unusable input, an output folder that cannot be written (``out_dir``, the cache), two
        bodies that would write the same files, or parts that would replace an input or an
        ``other_outputs`` file; nothing is written.
    """
    options, run = split_fields(options, run, fields)
    _check_layout_and_manifest(layout, fmt, run, run_manifest, resume)
    if target is not None:
        options = options.aimed_at(target)
    paths = [os.fspath(p) for p in inputs]
    parts = PartsLayout(os.fspath(out_dir), layout, fmt)
    _check_destinations(paths, parts, run, run_manifest)
    settings = _settings(options, run, parts, target)
    manifest = _manifest(options, run_manifest, resume)
    guard = OutputGuard(parts, [*paths, *(os.fspath(p) for p in other_outputs)])
    results = _run_files(paths, options, run, guard, manifest, progress, robot_options)
    files, rows = write_files(results, parts, options, target, run.threads())
    return DecomposeReport(
        files, rows, settings, None, layout, fmt, options.max_hausdorff, options.max_parts
    )


def _check_layout_and_manifest(
    layout: str, fmt: str, run: RunOptions, run_manifest: Any, resume: bool
) -> None:
    """ValueError for options of :func:`decompose_files` that contradict each other."""
    if layout == "ucx" and fmt == "glb":
        raise ValueError("layout 'ucx' writes OBJ only, not glb")
    if resume and run_manifest is None:
        raise ValueError("resume needs run_manifest")
    if run_manifest is not None and not run.use_cache:
        raise ValueError("run_manifest needs the cache (it keeps the results of finished files)")


def _check_destinations(
    paths: list[str], parts: PartsLayout, run: RunOptions, run_manifest: Any
) -> None:
    """Every output location, before the work (:func:`meshcol.io.outputs.check_outputs`)."""
    from meshcol.io.outputs import check_outputs

    check_outputs(
        files={"run_manifest": None if run_manifest is None else os.fspath(run_manifest)},
        folders={"out_dir": parts.out_dir, "cache_dir": run.local_cache_folder()},
        inputs=paths,
    )


def _settings(
    options: DecomposeOptions, run: RunOptions, parts: PartsLayout, target: Any
) -> dict[str, Any]:
    """The report's settings: the engine options as the run used them (aimed at the target),
    and how the run was made."""
    settings = {
        **options.report_settings(),
        **run.settings(),
        "out_dir": parts.out_dir,
        "layout": parts.layout,
        "format": parts.fmt,
        "max_hausdorff": options.max_hausdorff,
        **options.search_settings(),
        "frame": "world",
        "executor": run.executor,
        "ray_address": run.ray_address,
    }
    if target is not None:
        settings.update(target=target.name, target_limits=dict(target.limits))
    return settings


def _manifest(options: DecomposeOptions, run_manifest: Any, resume: bool) -> Any:
    """The run manifest, or None; resuming reads it, and refuses one of other options."""
    from meshcol.decomposition.manifest import RunManifest

    if run_manifest is None:
        return None
    # What decides the results: resuming with other options would mix two runs.
    return RunManifest(run_manifest, options.result_settings(), resume=resume)


def _is_manifest(inputs: Sequence[str]) -> bool:
    from meshcol.io.inputs import is_manifest

    return any(is_manifest(p) for p in inputs)


def _run_files(
    paths: list[str],
    options: DecomposeOptions,
    run: RunOptions,
    guard: OutputGuard,
    manifest: Any,
    progress: Callable[[str], None] | None,
    robot_options: RobotOptions | None = None,
) -> list[FileResult]:
    """Every file read, looked up and, unless the cache has it, decomposed by a worker: what
    became of each, in input order. The engines always run in workers, so that this process
    stays responsive to signals."""
    from meshcol.decomposition.engines import prepare_engine
    from meshcol.decomposition.executor import make_executor
    from meshcol.decomposition.jobs import ENGINE_PRELOAD

    total = None if _is_manifest(paths) else len(paths)
    counter = _FileCounter(progress, total)
    if total is not None:
        counter.report(f"decompose: 0/{total} files")  # until the first file is done
    pool = make_executor(
        run.executor,
        worker_entry(options),
        run.jobs,
        timeout=run.timeout,
        prepare=functools.partial(prepare_engine, options.engine),
        address=run.ray_address,
        preload=ENGINE_PRELOAD,
    )
    try:
        if run.jobs > 1 or run.executor != "local":
            # Workers start now and load the engine while this process reads the files; one
            # local job starts its worker at the first file the cache does not have (a run of
            # hits needs none).
            pool.start(min(run.jobs, len(paths)))
        counter.slots = getattr(pool, "slots", 1)
        file_run = _FileRun(paths, options, run, guard, manifest, counter, robot_options)
        if hasattr(pool, "on_step"):  # the executor passes its tasks' steps on
            pool.on_step = file_run.step
        results = file_run.results(pool)
    except BaseException as exc:
        # A signal (KeyboardInterrupt, SIGTERM's exception) abandons the run: no process stays.
        pool.close(interrupted=not isinstance(exc, Exception))
        raise
    pool.close()
    return results


class _FileCounter:
    """The run's progress messages: ``decompose: 3/10 files, 1 failed, 2 running``; once
    every file left is running, where each is (the engine's steps, :mod:`meshcol.decomposition.
    steps`) and the time left they justify."""

    def __init__(
        self, progress: Callable[[str], None] | None, total: int | None, noun: str = "files"
    ) -> None:
        self.report = progress or (lambda message: None)
        self.total = total  # None until a manifest's files are all read
        self.noun = noun
        self.slots = 1
        self.done = self.failed = self.sent = 0
        self.clocks: dict[int, tuple[str, StepClock]] = {}  # per running task: file, steps

    def file_done(self, status: str = "ok", task: int | None = None) -> None:
        self.done += 1
        self.failed += status != "ok"
        if task is not None:
            self.sent -= 1
            self.clocks.pop(task, None)
        self.report(self._text())

    def _text(self) -> str:
        total = "" if self.total is None else f"/{self.total}"
        text = f"decompose: {self.done}{total} {self.noun}"
        if self.failed:
            text += f", {self.failed} failed"
        running = min(self.sent, self.slots)
        if running:
            text += f", {running} running"
        return text

    def step(self, task: int, path: str, snapshot: Snapshot) -> None:
        """A running task's steps: shown, with the time left, once every file left runs."""
        if task not in self.clocks:
            self.clocks[task] = (path, StepClock())
        self.clocks[task][1].update(snapshot)
        left_files = None if self.total is None else self.total - self.done
        if left_files != len(self.clocks) or len(self.clocks) > self.slots:
            return  # files wait: the file count's own estimate says more
        text = self._text()
        if len(self.clocks) == 1:
            where = describe(snapshot)
            text += f"; {path}: {where}" if where else f"; {path}"
        clocks = [clock for _, clock in self.clocks.values()]
        self.report(ProgressText(text, functools.partial(_slowest, clocks)))


def _slowest(clocks: list[StepClock]) -> tuple[float, bool] | None:
    """The time left of tasks that run side by side: the longest, once each has one."""
    lefts = [clock.left() for clock in clocks]
    if not lefts or any(left is None for left in lefts):
        return None
    known = [left for left in lefts if left is not None]
    return max(seconds for seconds, _ in known), any(bound for _, bound in known)


class _FileRun:
    """A run over files in progress: each file read and planned, looked up in the cache, sent
    to a worker unless the cache has it whole, and its outcome recorded (and stored) as it
    arrives."""

    def __init__(
        self,
        paths: list[str],
        options: DecomposeOptions,
        run: RunOptions,
        guard: OutputGuard,
        manifest: Any,
        counter: _FileCounter,
        robot_options: RobotOptions | None = None,
    ) -> None:
        self.paths, self.options, self.guard = paths, options, guard
        self.robot_options = robot_options
        self.manifest, self.counter = manifest, counter
        self.task_options = TaskOptions.of(options, run)
        self.cache_root = run.cache_root()
        self.files: list[tuple[str, list[BodyMesh]]] = []
        self.outcomes: dict[int, tuple[str, Any, str | None, float]] = {}
        self.looked_up: dict[int, dict[str, Any]] = {}  # per file, the cache's entries
        self.task_file: list[int] = []  # the file of each task sent

    def results(self, pool: Any) -> list[FileResult]:
        """Run every file through ``pool``: what became of each, in input order."""
        # Closed here, not when garbage collected: the pool's signal handlers go with it.
        try:
            with contextlib.closing(pool.run(self._tasks())) as outcomes:
                for outcome in outcomes:
                    self._record(outcome)
        finally:
            if self.manifest is not None:
                self.manifest.write()  # however the run ends: what finished is on record
        return [
            FileResult(path, bodies, *self.outcomes[i])
            for i, (path, bodies) in enumerate(self.files)
        ]

    def _tasks(self) -> Iterator[tuple[str, list, TaskOptions]]:
        """The task of each file the cache does not have whole, as each file is read."""
        for path, bodies in iter_files(self.paths, self.robot_options):
            self.guard.plan_file(path, bodies)
            index = len(self.files)
            self.files.append((path, bodies))
            if self.manifest is not None:
                self.manifest.pending(path)
            if self._from_cache(index, path, bodies):
                continue
            if self.manifest is not None and self.manifest.was_done(path):
                self.counter.report(
                    f"decompose: {path}: done by the resumed run, but not in the cache: "
                    "decomposing it again"
                )
            self.task_file.append(index)
            self.counter.sent += 1
            yield (path, [(name, v, f) for name, v, f, _ in bodies], self.task_options)
        self.counter.total = len(self.files)

    def _from_cache(self, index: int, path: str, bodies: list[BodyMesh]) -> bool:
        """Whether the cache has every body of the file (then recorded as done)."""
        start = time.perf_counter()
        found: dict[str, Any] = {}
        if self.cache_root is not None:
            meshes = [(name, v, f) for name, v, f, _ in bodies]
            found = look_up(meshes, self.options, self.cache_root)
        self.looked_up[index] = found
        if not found or not all(is_complete(d, self.options) for d in found.values()):
            return False
        hits = [(name, found[name]) for name, _, _, _ in bodies]
        self.outcomes[index] = ("ok", hits, None, time.perf_counter() - start)
        if self.manifest is not None:
            self.manifest.finished(path, "ok", seconds=time.perf_counter() - start)
        self.counter.file_done()
        return True

    def _record(self, outcome: Any) -> None:
        """A worker's outcome: recorded, stored in the cache (this process stores what the
        worker made, or measured again, as it arrives; the manifest says done only once the
        entry is stored), and counted."""
        index = self.task_file[outcome.index]
        self.outcomes[index] = (outcome.status, outcome.value, outcome.message, outcome.seconds)
        if outcome.status == "ok" and self.cache_root is not None:
            for name, found in outcome.value:
                before = self.looked_up[index].get(name)
                store_result(found, before, self.cache_root, self.options)
        if self.manifest is not None:
            path = self.files[index][0]
            self.manifest.finished(path, outcome.status, outcome.message, outcome.seconds)
        self.counter.file_done(outcome.status, task=outcome.index)

    def step(self, task: int, snapshot: Snapshot) -> None:
        """A running task reported its steps (the executor's ``on_step``)."""
        self.counter.step(task, self.files[self.task_file[task]][0], snapshot)


def decompose_meshes(
    meshes: Sequence[tuple[str, Any, Any]],
    options: DecomposeOptions | None = None,
    run: RunOptions | None = None,
    *,
    progress: Callable[[str], None] | None = None,
    **fields: Any,
) -> list[Any]:
    """Decompose named meshes, each a task of its own: the decomposition of every mesh, in order.

    The run of :func:`decompose_files` for meshes already in memory (the parts of a robot's
    links, ``meshcol decompose ROBOT.urdf``): the cache is looked up first, the misses go to
    ``run.jobs`` worker processes (one mesh per task, so a robot's links run in parallel), and
    this process stores what comes back. Parts are in the frame of the vertices given.

    Parameters
    ----------
    meshes : sequence of (label, (n, 3) float, (m, 3) int)
        The meshes; ``label`` names a mesh in errors (``link 'hand'``).
    options, run, **fields
        As :func:`decompose_files` (the local worker pool; no search).
    progress : callable, optional
        Receives ``decompose: 3/10 meshes``.

    Returns
    -------
    list of Decomposition

    Raises
    ------
    MeshcolError
        A mesh that cannot be decomposed, failed or timed out in its worker, naming its label.
    """
    options, run = split_fields(options, run, fields)
    canonical = _canonical_meshes(meshes)
    cache_root = run.cache_root()
    results = _cached_meshes(canonical, options, cache_root)
    missing = [i for i, found in enumerate(results) if found is None]
    if missing:
        _decompose_missing(canonical, missing, results, TaskOptions.of(options, run), run, progress)
    return results


def _canonical_meshes(
    meshes: Sequence[tuple[str, Any, Any]],
) -> list[tuple[str, Any, Any]]:
    """(label, canonical vertices, canonical faces) of each mesh; an unusable one is an
    error that names its label."""
    from meshcol.decomposition.canonical import canonical_geometry

    canonical = []
    for label, vertices, faces in meshes:
        try:
            v, f = canonical_geometry(vertices, faces)
        except InvalidMeshError as exc:
            raise InvalidMeshError(f"{label}: {exc.message}", exc.path) from None
        canonical.append((label, v, f))
    return canonical


def _cached_meshes(
    canonical: list[tuple[str, Any, Any]], options: DecomposeOptions, cache_root: str | None
) -> list[Any]:
    """Each mesh's cached decomposition with its metrics, or None."""
    from meshcol.decomposition.decompose import cached_decomposition

    results: list[Any] = [None] * len(canonical)
    if cache_root is None:
        return results
    for i, (_, v, f) in enumerate(canonical):
        hit = cached_decomposition((v, f), options, cache_dir=cache_root)
        if hit is not None and hit.metrics is not None:
            results[i] = hit
    return results


def _decompose_missing(
    canonical: list[tuple[str, Any, Any]],
    missing: list[int],
    results: list[Any],
    task_options: TaskOptions,
    run: RunOptions,
    progress: Callable[[str], None] | None,
) -> None:
    """The meshes the cache did not have, one worker task each, stored as they arrive."""
    from meshcol.decomposition import cache
    from meshcol.decomposition.engines import prepare_engine
    from meshcol.decomposition.jobs import ENGINE_PRELOAD, WorkerPool

    cache_root = run.cache_root()
    counter = _FileCounter(progress, len(canonical), noun="meshes")
    counter.done, counter.slots = len(canonical) - len(missing), run.jobs
    counter.report(counter._text())
    prepare = functools.partial(prepare_engine, task_options.options.engine)
    pool: Any = WorkerPool(
        decompose_task, run.jobs, timeout=run.timeout, prepare=prepare, preload=ENGINE_PRELOAD
    )
    pool.on_step = lambda k, snapshot: counter.step(k, canonical[missing[k]][0], snapshot)

    def tasks() -> Iterator[tuple[str, list, TaskOptions]]:
        for i in missing:
            counter.sent += 1
            yield (canonical[i][0], [canonical[i]], task_options)

    try:
        with contextlib.closing(pool.run(tasks())) as outcomes:
            for outcome in outcomes:
                i = missing[outcome.index]
                if outcome.status != "ok":
                    what = "timed out" if outcome.status == "timeout" else "failed"
                    raise MeshcolError(
                        f"{canonical[i][0]}: decomposition {what}: {outcome.message}"
                    )
                results[i] = outcome.value[0][1]
                if cache_root is not None:
                    cache.store(results[i], cache_root)
                counter.file_done(task=outcome.index)
    except BaseException as exc:
        pool.close(interrupted=not isinstance(exc, Exception))
        raise
    pool.close()
