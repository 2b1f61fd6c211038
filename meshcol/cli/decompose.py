"""``meshcol decompose``: convex decomposition of many files, cached, parallel, measured."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import click

from meshcol.cli.common import (
    FiniteFloat,
    Progress,
    emit_report,
    executor_options,
    finish_outputs,
    html_option,
    jobs_option,
    render_html,
    report_format,
    robot_options,
    target_option,
    timeout_option,
    to_option,
    verdict,
    write_html,
)
from meshcol.cli.mesh_outputs import urdf_capsules_of, urdf_capsules_option
from meshcol.decomposition.engines import ENGINES
from meshcol.decomposition.options import (
    DEFAULT_SEARCH_STEPS,
    DEFAULT_SEARCH_TOLERANCE,
    SEARCH_MODES,
    DecomposeOptions,
    RunOptions,
)
from meshcol.io.formats import REPORT_FORMATS, describe_formats
from meshcol.io.mesh_write import LAYOUTS
from meshcol.io.robot import RobotOptions
from meshcol.io.targets import target_names

#: The command's help (``meshcol decompose -h``).
_HELP = """Split meshes into convex parts for collision (meshcol decompose).

Each body of each INPUT is decomposed (CoACD by default), its parts are made canonical
(convex hull, sorted by centroid), written to --out-dir and measured: volume of their
union against the mesh's, Hausdorff distances both ways (how far the mesh surface is from
the parts, and how far the boundary of their union sticks out of the mesh's solid: cuts
inside the mesh count 0), and the fraction of the mesh surface they leave uncovered. Results are cached by geometry and parameters, so a second
run costs milliseconds. Exit 1 when a file failed or timed out, a body misses
--max-hausdorff or --max-parts, or a part misses a --target limit (each said on stderr with its rule id); exit 2 for unusable input or an output that cannot be written (every output
location is checked before the work starts, and nothing is written on failure); 130 on
Ctrl-C, 143 on SIGTERM, with no output, no cache entry and no worker left behind.

A robot description (URDF, or MJCF) is rebuilt: the parts of each collision element's
meshes (in parallel with --jobs, one mesh a task) go to OUT/<link>_NN.obj in the link's
frame, and a copy of the description, OUT/<robot>.urdf, has one <collision> element per
part (visuals, inertials, joints, comments and unknown tags untouched; box, sphere,
cylinder and capsule elements kept, being exact; URDF has no capsule: a <capsule> is
written as a <cylinder> and two <sphere>s, or kept with --urdf-capsules extension). --to
mjcf writes OUT/<robot>.xml in MuJoCo Menagerie's convention; --to glb and --to usd the
parts at the joint configuration. --layout and --format do not apply. --target fits each mesh object's
parts (an element of k objects gives each max_hulls // k; more objects than max_hulls
is an MC106 finding on the element).

Fidelity targets: --max-hausdorff D and/or --max-parts N search each body's CoACD
threshold (V-HACD: its hull count), bracketing from --threshold then bisecting, and raise
the resolution when even the finest threshold misses D, for the fewest parts within D (N
alone: the smallest Hausdorff within N parts). Every step is an ordinary cached
decomposition (a repeated or resumed run replays the search from the cache) and is in
the report's "search" of each body, the chosen one marked; a body no step meets fails
(exit 1), naming its best step. --max-hausdorff used to only check the run's result:
--search off keeps that.

\b
Examples:
  meshcol decompose mug.obj --out-dir collision/
  meshcol decompose panda.urdf --out-dir panda_parts/ --jobs 2 --to mjcf
  meshcol decompose props/*.obj -o collision/ --jobs 4 --timeout 120 --report decompose.json
  meshcol decompose chair.obj -o out/ --layout ucx --max-hulls 16 --max-vertices 32
  meshcol decompose bottle.obj -o out/ --engine vhacd --layout combined --format glb
  meshcol decompose snowflake.obj -o out/ --preprocess off --threshold 0.02 -E mcts_iterations=50
  meshcol decompose lib/*.obj -o out/ --executor ray --ray-address auto --cache-dir s3://b/c
  meshcol decompose lib/*.obj -o out/ --run-manifest run.json --resume
  meshcol decompose mug.obj -o out/ --max-hausdorff 0.002 --search-steps 10
  meshcol decompose mug.obj -o out/ --max-parts 8
  meshcol decompose props/*.obj -o out/ --target isaac
"""


def _engine_option(
    ctx: click.Context, param: click.Parameter, values: tuple[str, ...]
) -> dict[str, str]:
    options: dict[str, str] = {}
    for item in values:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise click.BadParameter(f"expected KEY=VALUE, got {item!r}", ctx=ctx, param=param)
        options[key.strip().replace("-", "_")] = value.strip()
    return options


class _MeshFormat(click.Choice):
    """``--format obj|glb``, which names the report formats' option when given one."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and value.lower() in REPORT_FORMATS:
            self.fail(
                f"{value!r} is a report format: decompose's --format is the parts' mesh "
                f"format (obj, glb); give --report-format {value.lower()}",
                param,
                ctx,
            )
        return super().convert(value, param, ctx)


@click.command(
    "decompose",
    short_help="Convex decompositions of mesh libraries: cached, parallel, measured.",
    help=_HELP,
)
@click.argument("inputs", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--out-dir",
    "-o",
    required=True,
    type=click.Path(file_okay=False),
    help="Folder for the parts (created if missing).",
)
@click.option(
    "--engine",
    type=click.Choice(ENGINES),
    default="coacd",
    show_default=True,
    help="Decomposition engine (vhacd needs meshcol[vhacd]).",
)
@click.option(
    "--threshold",
    type=FiniteFloat(0, 1, min_open=True),
    default=None,
    help="CoACD concavity threshold; lower gives more, tighter parts.  [default: 0.05]",
)
@click.option(
    "--max-hulls",
    type=click.IntRange(min=1),
    default=None,
    help="Most parts per body.  [default: no limit]",
)
@click.option(
    "--max-vertices",
    type=click.IntRange(min=4),
    default=None,
    help="Most vertices per part (enforced).  [default: no limit]",
)
@target_option(
    "Fit every body's parts to an engine's limits (meshcol targets: "
    f"{', '.join(target_names())}) or your own profile, still enclosing; "
    "tighter --max-hulls/--max-vertices win. Exit 1 when a limit cannot be met."
)
@click.option(
    "--preprocess",
    type=click.Choice(["auto", "on", "off"]),
    default="auto",
    show_default=True,
    help="CoACD manifold preprocessing; auto: on for non-manifold input.",
)
@click.option(
    "--resolution",
    type=click.IntRange(min=1),
    default=None,
    help="CoACD sampling resolution or V-HACD voxel count.  [default: the engine's]",
)
@click.option("--seed", type=int, default=0, show_default=True, help="CoACD random seed.")
@click.option(
    "--engine-option",
    "-E",
    "engine_options",
    multiple=True,
    callback=_engine_option,
    metavar="KEY=VALUE",
    help="Any other engine parameter, e.g. -E mcts_iterations=50 (repeatable).  [default: "
    "the engine's]",
)
@jobs_option("Files decomposed in parallel processes (1: one at a time, CoACD using every core).")
@timeout_option()
@click.option(
    "--cache-dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Cache folder (may be shared by several machines) or fsspec URL (file://, s3://, "
    "gs://, memory://).  [default: the user cache folder, meshcol/decompose]",
)
@click.option("--no-cache", is_flag=True, help="Neither read nor write the cache.")
@click.option(
    "--layout",
    type=click.Choice(LAYOUTS),
    default="parts",
    show_default=True,
    help="parts: one file per part; combined: one file per body; ucx: UCX_<body>_NN objects.",
)
@click.option(
    "--format",
    "fmt",
    type=_MeshFormat(["obj", "glb"]),
    default="obj",
    show_default=True,
    help="Output format (glb: one node per part; not with ucx).",
)
@to_option("the parts", gltf=True)
@urdf_capsules_option
@click.option(
    "--report",
    type=click.Path(dir_okay=False),
    default=None,
    help="Write the report here ('-': stdout).  [default: no report: the parts are the "
    "output, as with hull -o and fit -o]",
)
@click.option(
    "--report-format",
    "report_fmt",
    type=click.Choice(REPORT_FORMATS),
    default=None,
    help=f"Report format: {describe_formats()}",
)
@click.option(
    "--max-hausdorff",
    type=FiniteFloat(min=0),
    default=None,
    help="Fidelity target: the largest Hausdorff distance, either way (mesh units). Each body's "
    "threshold (and resolution) is searched for the fewest parts within it; exit 1 when no "
    "step meets it. With --search off: only checked.  [default: no limit]",
)
@click.option(
    "--max-parts",
    type=click.IntRange(min=1),
    default=None,
    help="Fidelity target: the most parts per body; alone, the search finds the best fidelity "
    "within it. With --search off: only checked.  [default: no limit]",
)
@click.option(
    "--search",
    type=click.Choice(SEARCH_MODES),
    default="auto",
    show_default=True,
    help="auto: search the engine's parameters when --max-hausdorff or --max-parts is given; "
    "off: just check them (the run's parameters, exit 1 when exceeded).",
)
@click.option(
    "--search-steps",
    type=click.IntRange(min=1),
    default=DEFAULT_SEARCH_STEPS,
    show_default=True,
    help="Most decompositions (cached or not) one body's search makes.",
)
@click.option(
    "--search-tolerance",
    type=FiniteFloat(0, min_open=True),
    default=DEFAULT_SEARCH_TOLERANCE,
    show_default=True,
    help="The search stops when its threshold bracket is this narrow (hi/lo <= 1 + it).",
)
@click.option(
    "--run-manifest",
    type=click.Path(dir_okay=False),
    default=None,
    metavar="FILE.json",
    help="Keep every file's state (done, failed and why, pending) in this file as the run "
    "goes.  [default: none]",
)
@click.option(
    "--resume",
    is_flag=True,
    help="With --run-manifest: skip the files a previous run finished (taken from the "
    "cache), retry the others.",
)
@executor_options()
@click.pass_context
@robot_options()
@html_option
def decompose_command(
    ctx: click.Context,
    inputs: tuple[str, ...],
    out_dir: str,
    engine: str,
    threshold: float | None,
    max_hulls: int | None,
    max_vertices: int | None,
    target: Any,
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
    to: str | None,
    urdf_capsules: str | None,
    report: str | None,
    report_fmt: str | None,
    max_hausdorff: float | None,
    max_parts: int | None,
    search: str,
    search_steps: int,
    search_tolerance: float,
    html: str | None,
    run_manifest: str | None,
    resume: bool,
    executor: str,
    ray_address: str | None,
    robot_options: RobotOptions,
) -> None:
    # an unknown --report extension stops the run before it starts
    report_fmt = report_format(report, report_fmt, option="--report-format")
    _check_flags(engine, threshold, layout, fmt, no_cache, cache_dir, resume, run_manifest)
    options = _options(ctx)
    run = RunOptions(jobs, timeout, cache_dir, not no_cache, executor, ray_address)
    outputs = _Outputs(out_dir, layout, fmt, to, report, report_fmt, html, run_manifest, resume)
    # Every output location, before any work: a run never fails after the work for want of
    # a folder, and never replaces one of its inputs.
    _check_destinations(inputs, outputs, run)
    robot = _robot_input(ctx, inputs, options, run, outputs)
    capsules = urdf_capsules_of(urdf_capsules, inputs, robot, to)
    progress = Progress(command="decompose", heartbeat=True)
    try:
        result = _decompose(
            inputs, options, run, outputs, target, robot, progress.message, robot_options, capsules
        )
    finally:
        progress.done()
    if robot:
        _print_robot(result, outputs)
    else:
        _print_files(result, outputs, inputs, robot_options)
    if result.exit_code:
        ctx.exit(result.exit_code)


@dataclass(frozen=True)
class _Outputs:
    """What the command writes, and where (its flags as given)."""

    out_dir: str
    layout: str
    fmt: str
    to: str | None
    report: str | None
    report_fmt: str
    html: str | None
    run_manifest: str | None
    resume: bool

    @property
    def report_file(self) -> str | None:
        """The --report file (None for stdout)."""
        return None if self.report in (None, "-") else self.report


def _check_flags(
    engine: str,
    threshold: float | None,
    layout: str,
    fmt: str,
    no_cache: bool,
    cache_dir: str | None,
    resume: bool,
    run_manifest: str | None,
) -> None:
    """Usage errors of flags that exclude each other."""
    if layout == "ucx" and fmt == "glb":
        raise click.UsageError("--layout ucx writes OBJ only: drop --format glb")
    if no_cache and cache_dir is not None:
        raise click.UsageError("--cache-dir and --no-cache exclude each other")
    if engine != "coacd" and threshold is not None:
        raise click.UsageError("--threshold applies to --engine coacd only")
    if resume and run_manifest is None:
        raise click.UsageError("--resume needs --run-manifest")
    if run_manifest is not None and no_cache:
        raise click.UsageError(
            "--run-manifest needs the cache (it keeps the results of finished files): "
            "drop --no-cache"
        )


def _options(ctx: click.Context) -> DecomposeOptions:
    """The options of the flags named as their fields (``--max-hulls``: ``max_hulls``);
    what only the engine can refuse is an --engine-option error (the flags' types have
    checked the rest)."""
    names = {f.name for f in dataclasses.fields(DecomposeOptions)}
    try:
        return DecomposeOptions(**{k: v for k, v in ctx.params.items() if k in names})
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--engine-option'") from None


def _check_destinations(inputs: tuple[str, ...], outputs: _Outputs, run: RunOptions) -> None:
    """Exit 2 before any work when an output cannot be written or would replace an input
    (:func:`meshcol.io.outputs.check_outputs`)."""
    from meshcol.io.outputs import check_outputs

    cache_label = "--cache-dir" if run.cache_dir is not None else "the cache folder"
    check_outputs(
        files={
            "--report": outputs.report_file,
            "--html": outputs.html,
            "--run-manifest": outputs.run_manifest,
        },
        folders={"--out-dir": outputs.out_dir, cache_label: run.local_cache_folder()},
        inputs=inputs,
    )


def _robot_input(
    ctx: click.Context,
    inputs: tuple[str, ...],
    options: DecomposeOptions,
    run: RunOptions,
    outputs: _Outputs,
) -> bool:
    """Whether the input is one robot description; usage errors for the flags that do not
    apply to one (and for --to without one)."""
    from click.core import ParameterSource

    from meshcol.io.inputs import is_robot_file

    if outputs.to == "gltf-physics":
        from meshcol.analysis.gltf_rebuild import is_gltf

        if len(inputs) != 1 or not is_gltf(inputs[0]) or outputs.out_dir is None:
            raise click.UsageError("--to gltf-physics needs one glTF/GLB asset and --out-dir")
        return True
    robot = len(inputs) == 1 and is_robot_file(inputs[0])
    if outputs.to is not None and not robot:
        raise click.UsageError("--to needs one robot description (URDF, MJCF)")
    if not robot:
        return False
    for name, flag in (("layout", "--layout"), ("fmt", "--format")):
        if ctx.get_parameter_source(name) == ParameterSource.COMMANDLINE:
            raise click.UsageError(
                f"{flag} does not apply to a robot description (parts go to "
                "OUT/<link>_NN.obj; --to chooses the description's format)"
            )
    for flag, given in (
        ("--executor ray", run.executor == "ray"),
        ("--run-manifest", outputs.run_manifest is not None),
        ("--resume", outputs.resume),
    ):
        if given:
            raise click.UsageError(
                f"{flag} does not apply to a robot description yet (its links run in the "
                "local worker pool, --jobs)"
            )
    if options.search_target() is not None:
        raise click.UsageError(
            "the fidelity search (--max-hausdorff, --max-parts) does not apply to a robot "
            "description yet: add --search off to check --max-hausdorff only"
        )
    if options.max_parts is not None:
        raise click.UsageError("--max-parts does not apply to a robot description yet")
    return True


def _decompose(
    inputs: tuple[str, ...],
    options: DecomposeOptions,
    run: RunOptions,
    outputs: _Outputs,
    target: Any,
    robot: bool,
    progress: Callable[[str], None],
    robot_options: RobotOptions,
    urdf_capsules: str = "standard",
) -> Any:
    """The one library call: a robot's rebuild, or the run over files."""
    from meshcol.analysis.rebuild import rebuild_decomposition
    from meshcol.decomposition.batch import decompose_files

    report_file = outputs.report_file
    if outputs.to == "gltf-physics":
        from meshcol.analysis.gltf_rebuild import decompose_gltf

        return decompose_gltf(
            inputs[0],
            outputs.out_dir,
            options,
            run,
            target=target,
            progress=progress,
            other_outputs=[p for p in (report_file, outputs.html) if p],
            robot_options=robot_options,
        )
    if robot:
        return rebuild_decomposition(
            inputs[0],
            outputs.out_dir,
            options,
            run,
            to=outputs.to,
            reserved=(("the --report file", report_file),) if report_file else (),
            progress=progress,
            target=target,
            robot_options=robot_options,
            warn=lambda message: click.echo(f"meshcol: warning: {message}", err=True),
            urdf_capsules=urdf_capsules,
        )
    return decompose_files(
        inputs,
        outputs.out_dir,
        options,
        run,
        layout=outputs.layout,
        fmt=outputs.fmt,
        target=target,
        progress=progress,
        other_outputs=[p for p in (report_file, outputs.html, outputs.run_manifest) if p],
        run_manifest=outputs.run_manifest,
        resume=outputs.resume,
        robot_options=robot_options,
    )


def _print_robot(result: Any, outputs: _Outputs) -> None:
    """A robot's report (with --report), its target findings and the verdict."""
    if outputs.report is not None:
        emit_report(result, outputs.report_fmt, outputs.report)
    finish_outputs()
    _echo_target_violations(result)
    detail = f"{_summary(result)}, written to {result.settings['description']}"
    if result.settings.get("replaced"):  # --to gltf-physics on an asset with colliders
        detail += f" ({result.settings['replaced']})"
    click.echo(verdict("decompose", result.exit_code == 0, detail), err=True)


def _print_files(
    result: Any, outputs: _Outputs, inputs: tuple[str, ...], robot_options: RobotOptions
) -> None:
    """The report, the review page, each file that failed and each target missed, and the
    verdict."""
    from meshcol.analysis.review import decompose_page

    page = render_html(
        outputs.html, lambda: decompose_page(result, outputs.out_dir, inputs, robot_options)
    )
    if outputs.report is not None:  # the parts are the output, as for hull -o
        emit_report(result, outputs.report_fmt, outputs.report)
    write_html(outputs.html, page)
    finish_outputs()
    for entry in result.files:
        if entry["status"] != "ok":
            click.echo(f"meshcol: {entry['status']}: {entry['path']}: {entry['message']}", err=True)
        for body in entry["bodies"]:
            if body["search"] is not None and not body["search"]["met"]:
                reason = body["search"]["reason"]
                click.echo(
                    f"meshcol: target missed: {entry['path']}: {body['name']}: {reason}", err=True
                )
    _echo_target_violations(result)
    click.echo(verdict("decompose", result.exit_code == 0, _summary(result)), err=True)


def _echo_target_violations(result: Any) -> None:
    """One stderr line per target limit a body missed, with its rule id."""
    for entry in result.files:
        for body in entry["bodies"]:
            for violation in body.get("target", {}).get("violations", []):
                click.echo(
                    f"meshcol: {violation['rule']} {violation['rule_name']}: {entry['path']}: "
                    f"body '{body['name']}' {violation['message']}",
                    err=True,
                )


def _summary(result: Any) -> str:
    """``3 files, 5 bodies, 42 parts`` and what failed, for the verdict line."""
    from meshcol.cli.common import plural

    counts = result.summary
    text = (
        f"{plural(counts['files'], 'file')}, {plural(counts['bodies'], 'body')}, "
        f"{plural(counts['parts'], 'part')}"
    )
    for key, what in (("failed", "failed"), ("timeout", "timed out")):
        if counts[key]:
            text += f", {counts[key]} {what}"
    if counts["hausdorff_exceeded"]:
        text += f", {counts['hausdorff_exceeded']} over --max-hausdorff"
    if counts["parts_exceeded"]:
        text += f", {counts['parts_exceeded']} over --max-parts"
    if counts.get("target_missed"):
        text += f", {counts['target_missed']} missing a target limit"
    return text
