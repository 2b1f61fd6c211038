"""Convex decomposition of many files: the run behind ``meshcol decompose``.

Files are read one by one and each goes to a worker (:mod:`meshcol.decomposition.jobs`) as
soon as it is read, so work starts at once and a library is never held in memory whole. Cached
bodies are looked up before a file is sent, and what the workers return is stored in the cache
by this process, entry by entry as files finish (a worker never writes it). Every output
location is checked before the work starts (:func:`meshcol.io.outputs.check_outputs`), and each
file's planned parts against the inputs and the caller's other outputs as it is read. Unusable
input still stops the run before anything is written: the parts are written at the end, all
together (:func:`meshcol.io.outputs.staged_folder`), and the cache entries of the files before
the bad one are valid entries.
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from meshcol.decomposition.search import within_max_hausdorff
from meshcol.errors import InvalidMeshError, MeshcolError
from meshcol.io.robot import RobotOptions

__all__ = [
    "CSV_COLUMNS",
    "DecomposeReport",
    "decompose_files",
    "decompose_meshes",
    "within_max_hausdorff",
]

#: Columns of :meth:`DecomposeReport.to_csv`: one row per body, and one per failed file.
CSV_COLUMNS = (
    "path",
    "body",
    "status",
    "message",
    "parts",
    "vertices_per_part",
    "mesh_volume",
    "union_volume",
    "volume_ratio",
    "hausdorff_mesh_to_parts",
    "hausdorff_parts_to_mesh",
    "uncovered_fraction",
    "tolerance",
    "mesh_is_solid",
    "repaired",
    "from_cache",
    "hausdorff_ok",
    "parts_ok",
    "search_met",
    "search_steps",
)


@dataclass(frozen=True)
class DecomposeReport:
    """What :func:`decompose_files` did.

    Attributes
    ----------
    files : list of dict
        Per input file: ``path``, ``status`` (``ok``, ``failed``, ``timeout``), ``message``,
        ``seconds`` and ``bodies`` (name, outputs relative to the output folder, cache key,
        from_cache, engine, engine_version, params, repaired, notes, metrics, hausdorff_ok).
    rows : list of dict
        The CSV rows (:data:`CSV_COLUMNS`).
    settings : dict
        The options of the run.
    units : str or None
        Always None for now: parts keep the coordinates (and units) of their input files.
    layout, fmt : str
        Files per body and their format (as :func:`decompose_files` took them).
    max_hausdorff : float or None
        Hausdorff limit that fails the run.
    max_parts : int or None
        Part limit that fails the run.
    """

    files: list[dict[str, Any]]
    rows: list[dict[str, Any]]
    settings: dict[str, Any]
    units: str | None = None
    layout: str = "parts"
    fmt: str = "obj"
    max_hausdorff: float | None = None
    max_parts: int | None = None

    @property
    def summary(self) -> dict[str, int]:
        """Counts: files by status, bodies, parts, bodies over ``max_hausdorff`` or
        ``max_parts`` and, with a target, bodies that miss one of its limits
        (``target_missed``)."""
        counts = {
            "files": len(self.files),
            "ok": sum(1 for f in self.files if f["status"] == "ok"),
            "failed": sum(1 for f in self.files if f["status"] == "failed"),
            "timeout": sum(1 for f in self.files if f["status"] == "timeout"),
            "bodies": sum(len(f["bodies"]) for f in self.files),
            "parts": sum(b["metrics"].get("parts", 0) for f in self.files for b in f["bodies"]),
            "hausdorff_exceeded": sum(
                not b["hausdorff_ok"] for f in self.files for b in f["bodies"]
            ),
            "parts_exceeded": sum(
                not b.get("parts_ok", True) for f in self.files for b in f["bodies"]
            ),
        }
        if "target" in self.settings:
            counts["target_missed"] = sum(
                not b.get("target_ok", True) for f in self.files for b in f["bodies"]
            )
        return counts

    @property
    def exit_code(self) -> int:
        """1 when a file failed or timed out, a body exceeds ``max_hausdorff`` or
        ``max_parts`` (a search that met neither) or misses a limit of its target; else 0."""
        s = self.summary
        exceeded = s["hausdorff_exceeded"] or s["parts_exceeded"] or s.get("target_missed", 0)
        return 1 if s["failed"] or s["timeout"] or exceeded else 0

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, then ``layout``, ``format`` and
        ``max_hausdorff`` (also in ``settings``; kept at the top level for existing readers),
        ``files`` and ``summary``."""
        from meshcol.io.report import envelope

        return {
            **envelope("decompose", self.settings, self.units),
            "layout": self.layout,
            "format": self.fmt,
            "max_hausdorff": self.max_hausdorff,
            "files": self.files,
            "summary": self.summary,
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def to_csv(self) -> str:
        from meshcol.io.report import dumps_csv

        columns = (*CSV_COLUMNS, "target_ok") if "target" in self.settings else CSV_COLUMNS
        return dumps_csv(self.rows, columns)

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``) with its parts and fidelity, a failure over ``max_hausdorff``; a file
        that failed is an error case, one that timed out a failure (both fail the run). A
        file's seconds are shared among its bodies."""
        from meshcol.io.ci import CiCase, CiSuite, number

        limit = self.max_hausdorff
        cases = []
        for f in self.files:
            path = f["path"]
            if f["status"] != "ok":
                cases.append(
                    CiCase(
                        name=path,
                        classname="meshcol.decompose",
                        outcome="error" if f["status"] == "failed" else "failure",
                        message=f"{f['status']}: {f['message']}",
                        file=path,
                        kind=f["status"],
                        time=f.get("seconds"),
                    )
                )
                continue
            share = (f.get("seconds") or 0.0) / max(len(f["bodies"]), 1)
            for body in f["bodies"]:
                m = body["metrics"]
                message = (
                    f"{m.get('parts', 0)} parts, volume ratio {number(m.get('volume_ratio'))}, "
                    f"Hausdorff mesh to parts {number(m.get('hausdorff_mesh_to_parts'))}, "
                    f"parts to mesh {number(m.get('hausdorff_parts_to_mesh'))}, uncovered "
                    f"{number(m.get('uncovered_fraction'))}"
                )
                ok = body["hausdorff_ok"]
                if not ok:
                    message += f" > --max-hausdorff {number(limit)}"
                cases.append(
                    CiCase(
                        name=f"{path}::{body['name']}",
                        classname="meshcol.decompose",
                        outcome="passed" if ok else "failure",
                        message=message,
                        file=path,
                        kind=None if ok else "max-hausdorff",
                        time=share,
                    )
                )
        s = self.summary
        verdict = f"{s['files']} files, {s['bodies']} bodies, {s['parts']} parts"
        for key, what in (("failed", "failed"), ("timeout", "timed out")):
            if s[key]:
                verdict += f", {s[key]} {what}"
        if s["hausdorff_exceeded"]:
            verdict += f", {s['hausdorff_exceeded']} over --max-hausdorff"
        return CiSuite(
            "decompose",
            tuple(cases),
            self.settings,
            seconds=sum(f.get("seconds") or 0.0 for f in self.files),
            verdict=verdict,
            units=self.units,
        )


def body_report(
    path: str,
    name: str,
    outputs: list[str],
    d: Any,
    max_hausdorff: float | None,
    max_parts: int | None = None,
    search: Any = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """A decomposed body's entry in its file's ``bodies`` and its CSV row: the one layout of
    both, for files (:func:`decompose_files`) and robot links (``analysis.rebuild``).
    ``search``: the body's :class:`~meshcol.decomposition.search.SearchResult` (``d`` is its
    chosen step), or None."""
    metrics = d.metrics.to_dict() if d.metrics is not None else {}
    ok = within_max_hausdorff(metrics, max_hausdorff)
    parts_ok = max_parts is None or len(d.parts) <= max_parts
    body = {
        "name": name,
        "outputs": outputs,
        "cache_key": d.cache_key,
        "from_cache": d.from_cache,
        "engine": d.engine,
        "engine_version": d.engine_version,
        "params": dict(d.params),
        "repaired": d.repaired,
        "notes": list(d.notes),
        "metrics": metrics,
        "hausdorff_ok": ok,
        "parts_ok": parts_ok,
        "search": None if search is None else search.to_dict(),
    }
    row = {
        "path": path,
        "body": name,
        "status": "ok",
        **metrics,
        "repaired": d.repaired,
        "from_cache": d.from_cache,
        "hausdorff_ok": ok,
        "parts_ok": parts_ok,
        "search_met": None if search is None else search.met,
        "search_steps": None if search is None else len(search.steps),
    }
    return body, row


def task_options(
    jobs: int,
    cache_dir: str | os.PathLike[str] | None,
    use_cache: bool,
    **params: Any,
) -> dict[str, Any]:
    """The options every decomposition task gets: the engine parameters, the cache, and the
    worker's thread share (parallel tasks share the cores: each worker's distance queries get
    its part of them)."""
    return {
        **params,
        "cache_dir": None if cache_dir is None else os.fspath(cache_dir),
        "use_cache": use_cache,
        "threads": 0 if jobs == 1 else max(1, (os.cpu_count() or 1) // jobs),
    }


def decompose_files(
    inputs: Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str],
    *,
    engine: str = "coacd",
    threshold: float | None = None,
    max_hulls: int | None = None,
    max_vertices: int | None = None,
    preprocess: str = "auto",
    resolution: int | None = None,
    seed: int = 0,
    engine_options: Mapping[str, Any] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    cache_dir: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
    layout: str = "parts",
    fmt: str = "obj",
    max_hausdorff: float | None = None,
    max_parts: int | None = None,
    search: str = "auto",
    search_steps: int | None = None,
    search_tolerance: float | None = None,
    progress: Callable[[str], None] | None = None,
    other_outputs: Sequence[str | os.PathLike[str]] = (),
    executor: str = "local",
    ray_address: str | None = None,
    run_manifest: str | os.PathLike[str] | None = None,
    resume: bool = False,
    target: Any = None,
    robot_options: RobotOptions | None = None,
) -> DecomposeReport:
    """Decompose every body of every input file into convex parts and write them.

    Parameters
    ----------
    inputs : sequence of paths
        Mesh files (every object, solid or mesh node is a body) or one scene manifest.
    out_dir : path
        Folder for the parts (created if missing), in the world frame (each body's pose
        applied).
    engine, threshold, max_hulls, max_vertices, preprocess, resolution, seed, engine_options
        As :func:`meshcol.decomposition.decompose.decompose`.
    jobs : int
        Files decomposed in parallel processes (1: one at a time in this process, the engine
        using every core).
    timeout : float, optional
        Seconds allowed per file; a file over it is stopped and reported as ``timeout``.
    cache_dir : path or URL, optional
        Cache folder, possibly on a file system several machines share, or an fsspec URL
        (``file://``, ``memory://``, ``s3://``, ``gs://``; :mod:`meshcol.decomposition.cache`).
        Default: the user cache folder.
    use_cache : bool
        False: neither read nor write the cache.
    layout : {"parts", "combined", "ucx"}
        Files per body (:func:`meshcol.io.mesh_write.write_parts`).
    fmt : {"obj", "glb"}
        Output format (``ucx`` writes OBJ only).
    max_hausdorff : float, optional
        The fidelity target: the largest Hausdorff distance, either way, in the input's units.
        With ``search="auto"``, each body's engine parameters are searched for the fewest parts
        within it (:mod:`meshcol.decomposition.search`); with ``search="off"`` the run's
        parameters are used and the limit only checked. Either way a body over it (or whose
        metrics are missing or not a number) fails the run.
    max_parts : int, optional
        The most parts per body: searched for (the best fidelity within it, or with
        ``max_hausdorff`` a bound on the fewest parts) or, with ``search="off"``, checked.
    search : {"auto", "off"}
        ``auto``: search when a limit is given; ``off``: only check the limits.
    search_steps, search_tolerance : optional
        The search's step budget per body and threshold tolerance (defaults
        :data:`~meshcol.decomposition.search.DEFAULT_SEARCH_STEPS`, ``DEFAULT_SEARCH_TOLERANCE``).
    progress : callable, optional
        Receives one-line progress messages (``decompose: 3/10 files``).
    other_outputs : sequence of paths
        Files the caller will write besides the parts (``meshcol decompose --report``): a
        body whose parts would replace one is an error before anything is written, as is one
        whose parts would replace an input.
    executor : {"local", "ray"}
        Where the files are decomposed (:mod:`meshcol.decomposition.executor`): the local
        worker pool, or one Ray task per file.
    ray_address : str, optional
        The Ray cluster to use (default: a local Ray of ``jobs`` CPUs, started and stopped
        by the run).
    run_manifest : path, optional
        Keep every file's state in this JSON file as the run goes
        (:mod:`meshcol.decomposition.manifest`); needs the cache.
    resume : bool
        Read ``run_manifest`` first: files done are taken from the cache, the others run.
    target : Target, optional
        An engine profile (:mod:`meshcol.io.targets`): every body's parts meet all its
        limits and still enclose the body (:func:`apply_target`); its vertex budget and hull
        count go to the engine, and the tighter of each and ``max_vertices`` /
        ``max_hulls`` applies. A limit that cannot be met fails the run (exit 1).
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.iter_inputs`).

    Returns
    -------
    DecomposeReport
        ``exit_code`` 1 when a file failed or timed out or ``max_hausdorff`` was exceeded.

    Raises
    ------
    ValueError
        Contradictory options (``ucx`` with ``glb``, ``cache_dir`` without the cache,
        ``threshold`` with an engine other than CoACD), bad engine options or search options.
    MeshcolError
        Unusable input, an output folder that cannot be written (``out_dir``, the cache), two
        bodies that would write the same files, or parts that would replace an input or an
        ``other_outputs`` file; nothing is written.
    """
    from meshcol.decomposition.cache import default_cache_dir, local_folder
    from meshcol.decomposition.engines import prepare_engine, resolve_params
    from meshcol.decomposition.executor import make_executor
    from meshcol.decomposition.jobs import decompose_task
    from meshcol.decomposition.manifest import RunManifest
    from meshcol.decomposition.search import search_task
    from meshcol.io.outputs import check_outputs

    fidelity = _search_target(max_hausdorff, max_parts, search, search_steps, search_tolerance)
    if layout == "ucx" and fmt == "glb":
        raise ValueError("layout 'ucx' writes OBJ only, not glb")
    if not use_cache and cache_dir is not None:
        raise ValueError("cache_dir needs use_cache")
    if engine != "coacd" and threshold is not None:
        raise ValueError("threshold applies to engine 'coacd' only")
    if resume and run_manifest is None:
        raise ValueError("resume needs run_manifest")
    if run_manifest is not None and not use_cache:
        raise ValueError("run_manifest needs the cache (it keeps the results of finished files)")
    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    engine_options = dict(engine_options or {})
    resolve_params(engine, engine_options=engine_options)
    if target is not None:
        max_hulls, max_vertices, engine_options = target_options(
            target, engine, max_hulls, max_vertices, engine_options
        )
    paths = [os.fspath(p) for p in inputs]
    out_dir = os.fspath(out_dir)
    cache_root = None
    if use_cache:
        cache_root = os.fspath(cache_dir) if cache_dir is not None else str(default_cache_dir())
    check_outputs(
        files={"run_manifest": None if run_manifest is None else os.fspath(run_manifest)},
        folders={"out_dir": out_dir, "cache_dir": local_folder(cache_root)},
        inputs=paths,
    )
    options = task_options(
        jobs,
        cache_dir,
        use_cache,
        engine=engine,
        threshold=threshold,
        max_hulls=max_hulls,
        max_vertices=max_vertices,
        preprocess=preprocess,
        resolution=resolution,
        seed=seed,
        engine_options=engine_options,
    )
    if fidelity is not None:
        options["search"] = fidelity.to_dict()
    # The report's settings: the engine options as given (not the per-worker thread share),
    # and how the run was made.
    settings = {key: value for key, value in options.items() if key not in ("threads", "search")}
    settings.update(
        jobs=jobs,
        timeout=timeout,
        out_dir=out_dir,
        layout=layout,
        format=fmt,
        max_hausdorff=max_hausdorff,
        **_search_settings(fidelity, max_parts, search),
        frame="world",
        executor=executor,
        ray_address=ray_address,
    )
    if target is not None:
        settings.update(target=target.name, target_limits=dict(target.limits))
    manifest = None
    if run_manifest is not None:
        # What decides the results: resuming with other options would mix two runs.
        decided = {key: value for key, value in options.items() if key in _RESULT_OPTIONS}
        manifest = RunManifest(run_manifest, decided, resume=resume)

    # The engines always run in workers, so that this process stays responsive to signals.
    pool = make_executor(
        executor,
        decompose_task if fidelity is None else search_task,
        jobs,
        timeout=timeout,
        prepare=functools.partial(prepare_engine, engine),
        address=ray_address,
    )
    try:
        if jobs > 1 or executor != "local":
            # Workers start now and load the engine while this process reads the files; one
            # local job starts its worker at the first file the cache does not have (a run of
            # hits needs none).
            pool.start(min(jobs, len(paths)))
        files, rows = _run(
            paths,
            out_dir,
            options,
            pool,
            cache_root=cache_root,
            layout=layout,
            fmt=fmt,
            max_hausdorff=max_hausdorff,
            max_parts=max_parts,
            progress=progress,
            protected=[*paths, *(os.fspath(p) for p in other_outputs)],
            manifest=manifest,
            target=target,
            robot_options=robot_options,
        )
    except BaseException as exc:
        # A signal (KeyboardInterrupt, SIGTERM's exception) abandons the run: no process stays.
        pool.close(interrupted=not isinstance(exc, Exception))
        raise
    pool.close()
    return DecomposeReport(files, rows, settings, None, layout, fmt, max_hausdorff, max_parts)


def _search_target(
    max_hausdorff: float | None,
    max_parts: int | None,
    search: str,
    steps: int | None,
    tolerance: float | None,
) -> Any:
    """The run's :class:`~meshcol.decomposition.search.SearchTarget`, or None (no search)."""
    from meshcol.decomposition import search as fidelity_search

    return fidelity_search.search_target(
        max_hausdorff,
        max_parts,
        search,
        fidelity_search.DEFAULT_SEARCH_STEPS if steps is None else steps,
        fidelity_search.DEFAULT_SEARCH_TOLERANCE if tolerance is None else tolerance,
    )


def _search_settings(target: Any, max_parts: int | None, search: str) -> dict[str, Any]:
    """The report's settings of the fidelity search: ``max_parts``, ``search`` (the mode)
    and ``search_steps``, ``search_tolerance`` (null when the run does not search)."""
    return {
        "max_parts": max_parts,
        "search": search,
        "search_steps": None if target is None else target.max_steps,
        "search_tolerance": None if target is None else target.tolerance,
    }


#: The engine parameter of each engine's hull count (a target's ``max_hulls`` goes there, so
#: that meshcol merges any excess parts, enclosing, rather than drop them).
_ENGINE_HULL_COUNT = {"coacd": "max_convex_hull", "vhacd": "max_convex_hulls"}


def target_options(
    target: Any,
    engine: str,
    max_hulls: int | None,
    max_vertices: int | None,
    engine_options: Mapping[str, Any],
) -> tuple[None, int | None, dict[str, Any]]:
    """The engine options that aim at a target: ``(max_hulls, max_vertices, engine_options)``.

    The vertex budget (the tighter of ``max_vertices`` and the target's,
    :func:`meshcol.collision.limits.budget_vertices`) is enforced on every part as before;
    the hull count (the tighter of ``max_hulls`` and the target's) goes to the engine's own
    parameter and ``max_hulls`` becomes None, so that an engine overshooting it has its
    parts merged by :func:`apply_target` (still enclosing), never its smallest parts dropped.
    """
    from meshcol.collision.limits import budget_vertices

    options = dict(engine_options)
    budget = budget_vertices(target.limits)
    if budget is not None:
        max_vertices = budget if max_vertices is None else min(max_vertices, budget)
    count = target.limits.get("max_hulls")
    if max_hulls is not None:
        count = max_hulls if count is None else min(int(count), max_hulls)
    if count is not None:
        key = _ENGINE_HULL_COUNT[engine]
        given = options.get(key)
        options[key] = int(count) if given in (None, -1, "-1") else min(int(count), int(given))
    return None, max_vertices, options


def apply_target(
    target: Any,
    d: Any,
    vertices: Any,
    faces: Any,
    units: str | None = None,
    threads: int = 0,
) -> tuple[Any, dict[str, Any]]:
    """A body's decomposition fitted to a target, re-measured, and its report entry.

    The parts (``d.parts``, in the body's frame) go through
    :func:`meshcol.collision.target_fit.fit_parts` (merged to ``max_hulls``, each grown and
    simplified to the per-part limits, every part still enclosing what it replaces); the
    fidelity metrics are measured again on the fitted parts (same samples and tolerance),
    so the report describes what is written. The cache keeps the engine's parts.

    Returns
    -------
    (Decomposition, dict)
        The fitted decomposition and the body's ``target`` entry (name, met, costs,
        violations, per-part measures).
    """
    import dataclasses

    from meshcol.collision.target_fit import fit_parts
    from meshcol.decomposition.fidelity import fidelity
    from meshcol.geometry.topology import orient_outward

    fit = fit_parts(d.parts, target.limits, target.length_scale(units))
    metrics = d.metrics
    if metrics is not None:
        outward, _ = orient_outward(vertices, faces)
        metrics = fidelity(
            vertices,
            outward,
            fit.parts,
            samples=metrics.samples,
            tolerance=metrics.tolerance,
            threads=threads,
        )
    notes = tuple(d.notes) + tuple(f"target {target.name}: {note}" for note in fit.notes)
    fitted = dataclasses.replace(d, parts=fit.parts, metrics=metrics, notes=notes)
    return fitted, {"name": target.name, **fit.to_dict()}


def _run(
    inputs: list[str],
    out_dir: str,
    options: dict[str, Any],
    pool: Any,
    *,
    cache_root: str | None,
    layout: str,
    fmt: str,
    max_hausdorff: float | None,
    progress: Callable[[str], None] | None,
    protected: list[str],
    manifest: Any = None,
    max_parts: int | None = None,
    target: Any = None,
    robot_options: RobotOptions | None = None,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Load, look up the cache, decompose, store, write: the file entries and the CSV rows.

    With ``options["search"]`` each body's result is a search
    (:class:`~meshcol.decomposition.search.SearchResult`): replayed from the cache when every
    step is there, else run by a worker; every step is stored."""
    from meshcol.decomposition import cache
    from meshcol.decomposition import search as fidelity_search
    from meshcol.decomposition.decompose import cached_decomposition
    from meshcol.io.mesh_write import layout_file_pattern, safe_name, write_parts
    from meshcol.io.outputs import staged_folder

    files: list[tuple[str, list[tuple[str, Any, Any, Any]]]] = []
    names: dict[str, str] = {}
    results: dict[int, Any] = {}
    looked_up: dict[int, dict[str, Any]] = {}
    task_file: list[int] = []
    key_options = {k: v for k, v in options.items() if k not in ("use_cache", "search")}
    fidelity = None
    if options.get("search") is not None:
        fidelity = fidelity_search.SearchTarget(**options["search"])

    def lookup_body(v: Any, f: Any) -> Any:
        if fidelity is not None:
            return fidelity_search.cached_search((v, f), fidelity, **key_options)
        return cached_decomposition((v, f), **key_options)

    def complete(found: Any) -> bool:
        # A search replayed from the cache is complete; a plain entry needs its metrics.
        return found is not None and (fidelity is not None or found.metrics is not None)

    report_progress = progress or (lambda message: None)
    done, failed, sent, total = 0, 0, 0, None if _is_manifest(inputs) else len(inputs)
    slots = getattr(pool, "slots", 1)
    guard = _OutputGuard(out_dir, protected)

    def step(status: str = "ok", task: bool = False) -> None:
        nonlocal done, failed, sent
        done += 1
        failed += status != "ok"
        sent -= task
        text = f"decompose: {done}{'' if total is None else f'/{total}'} files"
        if failed:
            text += f", {failed} failed"
        running = min(sent, slots)
        if running:
            text += f", {running} running"
        report_progress(text)

    def tasks() -> Iterator[tuple[str, list, dict]]:
        nonlocal total, sent
        for path, bodies in _iter_load(inputs, robot_options):
            guard.protect(path)
            for name, _, _, _ in bodies:
                clean = safe_name(name)
                if clean in names:
                    raise MeshcolError(
                        f"two bodies would write {clean!r} (also from {names[clean]}): rename one",
                        path,
                    )
                names[clean] = path
                guard.plan(name, layout_file_pattern(clean, layout, fmt))
            i = len(files)
            files.append((path, bodies))
            if manifest is not None:
                manifest.pending(path)
            start = time.perf_counter()
            lookup = {}
            if cache_root is not None:
                lookup = {name: lookup_body(v, f) for name, v, f, _ in bodies}
            looked_up[i] = lookup
            if lookup and all(complete(d) for d in lookup.values()):
                hits = [(name, lookup[name]) for name, _, _, _ in bodies]
                results[i] = ("ok", hits, None, time.perf_counter() - start)
                if manifest is not None:
                    manifest.finished(path, "ok", seconds=time.perf_counter() - start)
                step()
                continue
            if manifest is not None and manifest.was_done(path):
                report_progress(
                    f"decompose: {path}: done by the resumed run, but not in the cache: "
                    "decomposing it again"
                )
            task_file.append(i)
            sent += 1
            yield (path, [(name, v, f) for name, v, f, _ in bodies], options)
        total = len(files)

    # Closed here, not when garbage collected: the pool's signal handlers go with it.
    try:
        with contextlib.closing(pool.run(tasks())) as outcomes:
            for outcome in outcomes:
                i = task_file[outcome.index]
                results[i] = (outcome.status, outcome.value, outcome.message, outcome.seconds)
                if outcome.status == "ok" and cache_root is not None:
                    # This process stores what the worker made (or measured again), as it
                    # arrives; the manifest says done only once the entry is stored.
                    for name, d in outcome.value:
                        if fidelity is not None:
                            fidelity_search.store_steps(d, cache_root)
                            continue
                        before = looked_up[i].get(name)
                        if before is None or before.metrics != d.metrics:
                            cache.store(d, cache_root)
                if manifest is not None:
                    manifest.finished(files[i][0], outcome.status, outcome.message, outcome.seconds)
                step(outcome.status, task=True)
    finally:
        if manifest is not None:
            manifest.write()  # however the run ends: what finished is on record

    rows: list[dict[str, Any]] = []
    file_reports: list[dict[str, Any]] = []
    writes = any(results[i][0] == "ok" and results[i][1] for i in range(len(files)))
    with staged_folder(out_dir) if writes else contextlib.nullcontext(out_dir) as stage:
        for i, (path, bodies) in enumerate(files):
            status, value, message, seconds = results[i]
            entry: dict[str, Any] = {
                "path": path,
                "status": status,
                "message": message,
                "bodies": [],
                "seconds": round(seconds, 3),
            }
            if status == "ok":
                transforms = {name: t for name, _, _, t in bodies}
                meshes = {name: (v, f) for name, v, f, _ in bodies}
                for name, found in value:
                    searched = found if fidelity is not None else None
                    d = found.decomposition if searched is not None else found
                    t = transforms[name]
                    target_entry = None
                    if target is not None:
                        d, target_entry = apply_target(
                            target, d, *meshes[name], threads=options.get("threads", 0)
                        )
                    world = [(v @ t[:3, :3].T + t[:3, 3], f) for v, f in d.parts]
                    written = write_parts(name, world, stage, layout, fmt)
                    outputs = [os.path.relpath(p, stage) for p in written]
                    body, row = body_report(
                        path, name, outputs, d, max_hausdorff, max_parts, searched
                    )
                    if target_entry is not None:
                        body["target"] = target_entry
                        body["target_ok"] = target_entry["met"]
                        row["target_ok"] = target_entry["met"]
                    entry["bodies"].append(body)
                    rows.append(row)
            else:
                rows.append({"path": path, "status": status, "message": message})
            file_reports.append(entry)
    return file_reports, rows


def decompose_meshes(
    meshes: Sequence[tuple[str, Any, Any]],
    *,
    engine: str = "coacd",
    threshold: float | None = None,
    max_hulls: int | None = None,
    max_vertices: int | None = None,
    preprocess: str = "auto",
    resolution: int | None = None,
    seed: int = 0,
    engine_options: Mapping[str, Any] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    cache_dir: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
    progress: Callable[[str], None] | None = None,
) -> list[Any]:
    """Decompose named meshes, each a task of its own: the decomposition of every mesh, in order.

    The run of :func:`decompose_files` for meshes already in memory (the parts of a robot's
    links, ``meshcol decompose ROBOT.urdf``): the cache is looked up first, the misses go to
    ``jobs`` worker processes (one mesh per task, so a robot's links run in parallel), and
    this process stores what comes back. Parts are in the frame of the vertices given.

    Parameters
    ----------
    meshes : sequence of (label, (n, 3) float, (m, 3) int)
        The meshes; ``label`` names a mesh in errors (``link 'hand'``).
    engine, threshold, ..., use_cache
        As :func:`decompose_files`.
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
    from meshcol.decomposition import cache
    from meshcol.decomposition.cache import default_cache_dir
    from meshcol.decomposition.canonical import canonical_geometry
    from meshcol.decomposition.decompose import cached_decomposition
    from meshcol.decomposition.engines import prepare_engine, resolve_params
    from meshcol.decomposition.jobs import WorkerPool, decompose_task

    engine_options = dict(engine_options or {})
    resolve_params(engine, engine_options=engine_options)
    cache_root = None
    if use_cache:
        cache_root = os.fspath(cache_dir) if cache_dir is not None else str(default_cache_dir())
    options = task_options(
        jobs,
        cache_root,
        use_cache,
        engine=engine,
        threshold=threshold,
        max_hulls=max_hulls,
        max_vertices=max_vertices,
        preprocess=preprocess,
        resolution=resolution,
        seed=seed,
        engine_options=engine_options,
    )
    key_options = {k: v for k, v in options.items() if k not in ("use_cache", "cache_dir")}
    results: list[Any] = [None] * len(meshes)
    missing: list[int] = []
    canonical = []
    for i, (label, vertices, faces) in enumerate(meshes):
        try:
            v, f = canonical_geometry(vertices, faces)
        except InvalidMeshError as exc:
            raise InvalidMeshError(f"{label}: {exc.message}", exc.path) from None
        canonical.append((v, f))
        hit = None
        if cache_root is not None:
            hit = cached_decomposition((v, f), cache_dir=cache_root, **key_options)
        if hit is not None and hit.metrics is not None:
            results[i] = hit
        else:
            missing.append(i)
    report = progress or (lambda message: None)
    done = len(meshes) - len(missing)
    if missing:
        report(f"decompose: {done}/{len(meshes)} meshes")
        pool: Any = WorkerPool(
            decompose_task, jobs, timeout=timeout, prepare=functools.partial(prepare_engine, engine)
        )
        tasks = ((meshes[i][0], [(meshes[i][0], *canonical[i])], options) for i in missing)
        try:
            with contextlib.closing(pool.run(tasks)) as outcomes:
                for outcome in outcomes:
                    i = missing[outcome.index]
                    if outcome.status != "ok":
                        what = "timed out" if outcome.status == "timeout" else "failed"
                        raise MeshcolError(
                            f"{meshes[i][0]}: decomposition {what}: {outcome.message}"
                        )
                    results[i] = outcome.value[0][1]
                    if cache_root is not None:
                        cache.store(results[i], cache_root)
                    done += 1
                    report(f"decompose: {done}/{len(meshes)} meshes")
        except BaseException as exc:
            pool.close(interrupted=not isinstance(exc, Exception))
            raise
        pool.close()
    return results


# Options of the run that decide its results (the run manifest's fingerprint).
_RESULT_OPTIONS = (
    "engine",
    "threshold",
    "max_hulls",
    "max_vertices",
    "preprocess",
    "resolution",
    "seed",
    "engine_options",
    "search",
)


class _OutputGuard:
    """Refuses, before anything is written, parts that would replace a protected file (an
    input, a source file a manifest names, the caller's report): each body's file-name
    pattern in the output folder is checked against each protected file, whichever comes
    first."""

    def __init__(self, out_dir: str, protected: list[str]) -> None:
        from meshcol.io.outputs import same_file

        self._same_file = same_file
        self.out_dir = out_dir
        self.patterns: list[tuple[str, re.Pattern[str]]] = []
        self.protected: list[str] = []
        for path in protected:
            self.protect(path)

    def _in_out_dir(self, path: str) -> bool:
        return self._same_file(os.path.dirname(os.path.abspath(path)), self.out_dir)

    def protect(self, path: str) -> None:
        if path in self.protected:
            return
        self.protected.append(path)
        if self._in_out_dir(path):
            for body, pattern in self.patterns:
                self._check(body, pattern, path)

    def plan(self, body: str, pattern: re.Pattern[str]) -> None:
        self.patterns.append((body, pattern))
        for path in self.protected:
            if self._in_out_dir(path):
                self._check(body, pattern, path)

    def _check(self, body: str, pattern: re.Pattern[str], path: str) -> None:
        if pattern.fullmatch(os.path.basename(path)):
            raise MeshcolError(
                f"the parts of body {body!r} would replace this file (output folder "
                f"{self.out_dir}): choose another output folder",
                path,
            )


def _is_manifest(inputs: Sequence[str]) -> bool:
    from meshcol.io.inputs import is_manifest

    return any(is_manifest(p) for p in inputs)


def _iter_load(
    inputs: list[str], robot_options: RobotOptions | None = None
) -> Iterator[tuple[str, list[tuple[str, Any, Any, Any]]]]:
    """(file, [(body name, canonical vertices, canonical faces, transform)]) per input file,
    as each is read (:func:`meshcol.io.scene.iter_inputs`): one task per file; a manifest's
    bodies without a file of their own (primitives) belong to the manifest."""
    from meshcol.decomposition.canonical import canonical_geometry
    from meshcol.io.scene import iter_inputs

    for source, bodies in iter_inputs(list(inputs), robot_options=robot_options):
        canonical = []
        # each part of a body is decomposed on its own, as check's colliders do (same cache key)
        for body in (part for whole in bodies for part in whole.part_bodies()):
            try:
                v, f = canonical_geometry(body.vertices, body.faces)
            except InvalidMeshError as exc:
                where = (
                    source
                    if body.name == os.path.splitext(os.path.basename(source))[0]
                    else f"{source}: {body.name}"
                )
                raise InvalidMeshError(exc.message, where) from None
            canonical.append((body.name, v, f, body.pose))
        yield source, canonical
