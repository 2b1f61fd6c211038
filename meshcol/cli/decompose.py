"""``meshcol decompose``: convex decomposition of many files, cached, parallel, measured."""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Iterator
from typing import Any

import click

from meshcol.errors import InvalidMeshError, MeshcolError


def _engine_option(ctx: click.Context, param: click.Parameter, values: tuple[str, ...]) -> dict[str, str]:
    options: dict[str, str] = {}
    for item in values:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise click.BadParameter(f"expected KEY=VALUE, got {item!r}", ctx=ctx, param=param)
        options[key.strip().replace("-", "_")] = value.strip()
    return options


@click.command("decompose")
@click.argument("inputs", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--out-dir", "-o", required=True, type=click.Path(file_okay=False), help="Folder for the parts (created if missing).")
@click.option("--engine", type=click.Choice(["coacd", "vhacd"]), default="coacd", show_default=True, help="Decomposition engine (vhacd needs meshcol[vhacd]).")
@click.option("--threshold", type=click.FloatRange(0, 1, min_open=True), default=None, help="CoACD concavity threshold (default 0.05); lower gives more, tighter parts.")
@click.option("--max-hulls", type=click.IntRange(min=1), default=None, help="Most parts per body.")
@click.option("--max-vertices", type=click.IntRange(min=4), default=None, help="Most vertices per part (enforced).")
@click.option("--preprocess", type=click.Choice(["auto", "on", "off"]), default="auto", show_default=True, help="CoACD manifold preprocessing; auto: on for non-manifold input.")
@click.option("--resolution", type=click.IntRange(min=1), default=None, help="CoACD sampling resolution or V-HACD voxel count.")
@click.option("--seed", type=int, default=0, show_default=True, help="CoACD random seed.")
@click.option("--engine-option", "-E", "engine_options", multiple=True, callback=_engine_option, metavar="KEY=VALUE", help="Any other engine parameter, e.g. -E mcts_iterations=50 (repeatable).")
@click.option("--jobs", "-j", type=click.IntRange(min=1), default=1, show_default=True, help="Files decomposed in parallel processes (1: one at a time, CoACD using every core).")
@click.option("--timeout", type=click.FloatRange(0, min_open=True), default=None, help="Seconds allowed per file; a file over it is stopped and reported.")
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None, help="Cache folder (default: the user cache folder, meshcol/decompose).")
@click.option("--no-cache", is_flag=True, help="Neither read nor write the cache.")
@click.option("--layout", type=click.Choice(["parts", "combined", "ucx"]), default="parts", show_default=True, help="parts: one file per part; combined: one file per body; ucx: UCX_<body>_NN objects.")
@click.option("--format", "fmt", type=click.Choice(["obj", "glb"]), default="obj", show_default=True, help="Output format (glb: one node per part; not with ucx).")
@click.option("--report", type=click.Path(dir_okay=False), default=None, help="Write the JSON or CSV report here instead of stdout.")
@click.option("--max-hausdorff", type=click.FloatRange(min=0), default=None, help="Fail (exit 1) when a body's Hausdorff distance, either way, exceeds this.")
@click.pass_context
def decompose_command(
    ctx: click.Context,
    inputs: tuple[str, ...],
    out_dir: str,
    engine: str,
    threshold: float | None,
    max_hulls: int | None,
    max_vertices: int | None,
    preprocess: str,
    resolution: int | None,
    seed: int,
    engine_options: dict[str, str],
    jobs: int,
    timeout: float | None,
    cache_dir: str | None,
    no_cache: bool,
    layout: str,
    fmt: str,
    report: str | None,
    max_hausdorff: float | None,
) -> None:
    """Split meshes into convex parts for collision (meshcol decompose).

    Each body of each INPUT is decomposed (CoACD by default), its parts are made canonical
    (convex hull, sorted by centroid), written to --out-dir and measured: volume of their
    union against the mesh's, Hausdorff distances both ways, and the fraction of the mesh
    surface they leave uncovered. Results are cached by geometry and parameters, so a second
    run costs milliseconds. Exit 1 when a file failed or timed out, or --max-hausdorff was
    exceeded; exit 2 for unusable input.

    \b
    Examples:
      meshcol decompose mug.obj --out-dir collision/
      meshcol decompose props/*.obj -o collision/ --jobs 4 --timeout 120 --report decompose.json
      meshcol decompose chair.obj -o out/ --layout ucx --max-hulls 16 --max-vertices 32
      meshcol decompose bottle.obj -o out/ --engine vhacd --layout combined --format glb
      meshcol decompose snowflake.obj -o out/ --preprocess off --threshold 0.02 -E mcts_iterations=50
    """
    from meshcol.decomposition.engines import prepare_engine, resolve_params
    from meshcol.decomposition.jobs import WorkerPool, decompose_task

    if layout == "ucx" and fmt == "glb":
        raise click.UsageError("--layout ucx writes OBJ only: drop --format glb")
    if no_cache and cache_dir is not None:
        raise click.UsageError("--cache-dir and --no-cache exclude each other")
    if engine != "coacd" and threshold is not None:
        raise click.UsageError("--threshold applies to --engine coacd only")
    try:
        resolve_params(engine, engine_options=engine_options)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--engine-option'") from None

    options: dict[str, Any] = {
        "engine": engine, "threshold": threshold, "max_hulls": max_hulls,
        "max_vertices": max_vertices, "preprocess": preprocess, "resolution": resolution,
        "seed": seed, "engine_options": engine_options,
        "cache_dir": cache_dir, "use_cache": not no_cache,
        # Parallel files share the cores: each worker's distance queries get its share.
        "threads": 0 if jobs == 1 else max(1, (os.cpu_count() or 1) // jobs),
    }

    pool = None
    if jobs > 1 or timeout is not None:
        # Workers start now and load the engine while this process reads the files.
        pool = WorkerPool(decompose_task, jobs, timeout=timeout,
                          prepare=functools.partial(prepare_engine, engine))
        pool.start(min(jobs, len(inputs)))
    try:
        code = _decompose_files(inputs, out_dir, options, pool, jobs=jobs, timeout=timeout,
                                no_cache=no_cache, layout=layout, fmt=fmt,
                                max_hausdorff=max_hausdorff, report=report)
    finally:
        if pool is not None:
            pool.close()
    if code:
        ctx.exit(code)


def _decompose_files(
    inputs: tuple[str, ...], out_dir: str, options: dict[str, Any], pool: Any, *, jobs: int,
    timeout: float | None, no_cache: bool, layout: str, fmt: str, max_hausdorff: float | None,
    report: str | None,
) -> int:
    """The run after option checks: load, look up the cache, decompose, write, report.
    Returns the exit code (1 when a file failed or a body exceeds ``max_hausdorff``)."""
    from meshcol.decomposition.decompose import cached_decomposition
    from meshcol.cli.common import Progress
    from meshcol.decomposition.jobs import decompose_task, run_tasks
    from meshcol.io.mesh_write import safe_name, write_parts
    from meshcol.io.report import dumps_csv, dumps_json, emit, report_format

    # Files are read one by one and each goes to a worker as soon as it is read, so work
    # starts at once and a library is never held in memory whole. Unusable input (exit 2)
    # still stops the run before anything is written: outputs are written at the end, and
    # the workers' cache entries for the files before it are valid entries.
    files: list[tuple[str, list[tuple[str, Any, Any, Any]]]] = []
    names: dict[str, str] = {}
    results: dict[int, Any] = {}
    task_file: list[int] = []
    key_options = {k: v for k, v in options.items() if k != "use_cache"}
    progress = Progress()
    done, total = 0, None if _is_manifest(inputs) else len(inputs)

    def step() -> None:
        nonlocal done
        done += 1
        progress.message(f"decompose: {done}{'' if total is None else f'/{total}'} files")

    def tasks() -> Iterator[tuple[str, list, dict]]:
        nonlocal total
        for path, bodies in _iter_load(inputs):
            for name, _, _, _ in bodies:
                clean = safe_name(name)
                if clean in names:
                    raise MeshcolError(
                        f"two bodies would write {clean!r} (also from {names[clean]}): rename one", path
                    )
                names[clean] = path
            i = len(files)
            files.append((path, bodies))
            start = time.perf_counter()
            lookup = {}
            if not no_cache:
                lookup = {name: cached_decomposition((v, f), **key_options) for name, v, f, _ in bodies}
            if lookup and all(d is not None and d.metrics is not None for d in lookup.values()):
                hits = [(name, lookup[name]) for name, _, _, _ in bodies]
                results[i] = ("ok", hits, None, time.perf_counter() - start)
                step()
                continue
            task_file.append(i)
            yield (path, [(name, v, f) for name, v, f, _ in bodies], options)
        total = len(files)

    for outcome in run_tasks(decompose_task, tasks(), jobs=jobs, timeout=timeout, pool=pool):
        i = task_file[outcome.index]
        results[i] = (outcome.status, outcome.value, outcome.message, outcome.seconds)
        step()
    progress.done()
    os.makedirs(out_dir, exist_ok=True)

    rows: list[dict[str, Any]] = []
    file_reports: list[dict[str, Any]] = []
    failed = exceeded = 0
    for i, (path, bodies) in enumerate(files):
        status, value, message, seconds = results[i]
        entry: dict[str, Any] = {"path": path, "status": status, "message": message, "bodies": [],
                                 "seconds": round(seconds, 3)}
        if status != "ok":
            failed += 1
        else:
            transforms = {name: t for name, _, _, t in bodies}
            for name, d in value:
                t = transforms[name]
                world = [(v @ t[:3, :3].T + t[:3, 3], f) for v, f in d.parts]
                written = write_parts(name, world, out_dir, layout, fmt)
                m = d.metrics.to_dict() if d.metrics is not None else {}
                worst = max(m.get("hausdorff_mesh_to_parts", 0.0), m.get("hausdorff_parts_to_mesh", 0.0))
                ok = max_hausdorff is None or worst <= max_hausdorff
                exceeded += not ok
                body = {
                    "name": name,
                    "outputs": [os.path.relpath(p, out_dir) for p in written],
                    "cache_key": d.cache_key,
                    "from_cache": d.from_cache,
                    "engine": d.engine,
                    "engine_version": d.engine_version,
                    "params": dict(d.params),
                    "repaired": d.repaired,
                    "notes": list(d.notes),
                    "metrics": m,
                    "hausdorff_ok": ok,
                }
                entry["bodies"].append(body)
                rows.append({"path": path, "body": name, "status": status, **m,
                             "repaired": d.repaired, "from_cache": d.from_cache, "hausdorff_ok": ok})
        if status != "ok":
            rows.append({"path": path, "status": status, "message": message})
        file_reports.append(entry)

    summary = {
        "files": len(files),
        "ok": sum(1 for f in file_reports if f["status"] == "ok"),
        "failed": sum(1 for f in file_reports if f["status"] == "failed"),
        "timeout": sum(1 for f in file_reports if f["status"] == "timeout"),
        "bodies": sum(len(f["bodies"]) for f in file_reports),
        "parts": sum(b["metrics"].get("parts", 0) for f in file_reports for b in f["bodies"]),
        "hausdorff_exceeded": exceeded,
    }
    if report_format(report, None) == "csv":
        columns = ["path", "body", "status", "message", "parts", "vertices_per_part", "mesh_volume",
                   "union_volume", "volume_ratio", "hausdorff_mesh_to_parts", "hausdorff_parts_to_mesh",
                   "uncovered_fraction", "tolerance", "repaired", "from_cache", "hausdorff_ok"]
        text = dumps_csv(rows, columns)
    else:
        text = dumps_json({"command": "decompose", "layout": layout, "format": fmt,
                           "max_hausdorff": max_hausdorff, "files": file_reports, "summary": summary})
    emit(text, report)
    for f in file_reports:
        if f["status"] != "ok":
            click.echo(f"meshcol: {f['status']}: {f['path']}: {f['message']}", err=True)
    return 1 if failed or exceeded else 0


def _is_manifest(inputs: tuple[str, ...]) -> bool:
    from meshcol.io.scene import MANIFEST_EXTENSIONS

    return any(os.path.splitext(p)[1].lower() in MANIFEST_EXTENSIONS for p in inputs)


def _iter_load(inputs: tuple[str, ...]) -> Iterator[tuple[str, list[tuple[str, Any, Any, Any]]]]:
    """(file, [(body name, canonical vertices, canonical faces, transform)]) per input file,
    as each is read (:func:`meshcol.scene.iter_inputs`): one task per file; a manifest's
    bodies without a file of their own (primitives) belong to the manifest."""
    from meshcol.decomposition.canonical import canonical_geometry
    from meshcol.io.scene import iter_inputs

    for source, bodies in iter_inputs(list(inputs)):
        canonical = []
        for body in bodies:
            try:
                v, f = canonical_geometry(body.vertices, body.faces)
            except InvalidMeshError as exc:
                where = source if body.name == os.path.splitext(os.path.basename(source))[0] else f"{source}: {body.name}"
                raise InvalidMeshError(exc.message, where) from None
            canonical.append((body.name, v, f, body.pose))
        yield source, canonical
