"""``meshcol inspect``: is each mesh fit to be a collider?"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import Any

import click

from meshcol.cli import CONTEXT_SETTINGS
from meshcol.cli.common import (
    FiniteFloat,
    Progress,
    cache_dir_option,
    collider_option,
    engine_option,
    executor_options,
    html_option,
    jobs_option,
    plural,
    report_format,
    report_options,
    robot_options,
    snapshots_option,
    target_option,
    timeout_option,
    verdict,
    write_outputs,
)
from meshcol.io.outputs import check_outputs
from meshcol.io.robot import RobotOptions


def _parse_rules(ctx: click.Context, param: click.Parameter, value: str | None) -> tuple[str, ...]:
    from meshcol.analysis.rules import UnknownRuleError, select_rules

    if value is None:
        return ()
    try:
        return select_rules(value, "inspect")
    except UnknownRuleError as exc:
        raise click.BadParameter(str(exc), ctx, param) from None


def _physics_options(command: Callable[..., None]) -> Callable[..., None]:
    """Hand the physics rules' options (--shape, the tolerances, --engine, --cache-dir,
    --target) to ``command`` as one :class:`~meshcol.analysis.physics.PhysicsOptions`,
    ``physics`` (validated by the library)."""

    @functools.wraps(command)
    def with_physics(
        *,
        shape: str,
        volume_ratio: float,
        com_offset: float,
        inertia_ratio: float,
        min_relative_volume: float,
        min_volume: float,
        engine: str,
        cache_dir: str | None,
        target: Any,
        **others: Any,
    ) -> None:
        from meshcol.analysis.physics import PhysicsOptions

        physics = PhysicsOptions(
            shape=shape,
            volume_ratio=volume_ratio,
            com_offset=com_offset,
            inertia_ratio=inertia_ratio,
            min_relative_volume=min_relative_volume,
            min_volume=min_volume,
            decompose_options={"engine": engine}
            | ({} if cache_dir is None else {"cache_dir": cache_dir}),
            target=target,
        )
        command(physics=physics, **others)

    return with_physics


@click.command(
    "inspect",
    short_help="Mesh health of each body: fit to be a collider?",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@report_options(default="the report on stdout; a summary table on stderr")
@click.option(
    "--fail-on",
    "fail_on",
    metavar="RULES",
    callback=_parse_rules,
    help="Comma-separated rules whose findings make the run exit 1: ids or names "
    "(MC401 or not-watertight; 'meshcol rules' lists them), or all.  "
    "[default: none, the run reports only]",
)
@collider_option(
    "Collider of each body for the physics rules, as in check (a manifest body's "
    "'shape' overrides it)."
)
@click.option(
    "--volume-ratio",
    type=FiniteFloat(min=1.0),
    default=2.0,
    show_default=True,
    help="MC205: collider volume over visual volume allowed, either way.",
)
@click.option(
    "--com-offset",
    type=FiniteFloat(min=0.0),
    default=0.05,
    show_default=True,
    help="MC206: centre-of-mass offset allowed, as a fraction of the visual bounding-box diagonal.",
)
@click.option(
    "--inertia-ratio",
    type=FiniteFloat(min=1.0),
    default=1.5,
    show_default=True,
    help="MC207: ratio allowed between principal moments of inertia per unit mass.",
)
@click.option(
    "--min-relative-volume",
    type=FiniteFloat(min=0.0),
    default=1e-6,
    show_default=True,
    help="MC202: a convex part under this volume over its diagonal cubed is flat.",
)
@click.option(
    "--min-volume",
    type=FiniteFloat(min=0.0),
    default=1e-15,
    show_default=True,
    help="MC203: a collider under this volume (cubic units) is too small to simulate.",
)
@engine_option("Decomposition engine for --shape decomposed bodies missing from the cache.")
@cache_dir_option()
@jobs_option(
    "Files inspected at once, each a task in a worker process or on Ray (1: one after "
    "another in this process, unless --timeout or --executor ray)."
)
@timeout_option(
    "Seconds allowed per file; a file over it is stopped and reported as not inspected "
    "(exit 2).  [default: no limit]"
)
@executor_options()
@target_option(
    "Measure each body's collider (--shape) against an engine's limits (meshcol "
    "targets): each limit a part is past is a finding (MC101..MC107, MC201) that fails "
    "the run unless --fail-on lists other rules."
)
@robot_options()
@html_option
@snapshots_option
@_physics_options
def inspect(
    inputs: tuple[str, ...],
    report: str | None,
    fmt: str | None,
    fail_on: tuple[str, ...],
    physics: Any,
    jobs: int,
    timeout: float | None,
    executor: str,
    ray_address: str | None,
    html: str | None,
    snapshots: str | None,
    robot_options: RobotOptions,
) -> None:
    """Health check of each body's mesh: fit to be a collider?

    INPUT is mesh files (OBJ, STL, PLY, OFF, glTF/GLB, FBX, COLLADA, USD; every object, solid
    or mesh node is a body), one scene manifest or a robot description. Per body: vertices, faces, connected components,
    watertight, consistent winding, signed volume (closed meshes only), world-frame bounding
    box and size, degenerate (zero-area) faces, duplicate faces, boundary and non-manifold
    edges (more than two faces), self-intersections (pairs of crossing faces), manifold3d's
    status, and a units guess with its reason (a chair 400 units tall is millimetres).

    Physics readiness, per body: its collider (--shape, the convex hull by default; a robot
    link's collision elements, compared with its visual elements) and its visual mesh get
    mass properties (volume, centre of mass, inertia about it, solid and shell; world frame,
    density 1); the rules MC202..MC207 and MC301..MC303 compare them and flag flat, tiny,
    inverted or missing colliders and UCX_ parts naming nothing. Every finding is a record
    (body, part, rule id and name, measured value, limit, message) in the report's
    "findings"; 'meshcol rules' documents each rule.

    Faces cross when their open triangles share a point, decided exactly (no tolerance):
    faces that only touch (a shared vertex or edge, a T-junction) do not. A closed mesh with
    a negative volume is inverted (inside out): meshcol hull is unaffected (a hull has no
    winding) and notes it; meshcol decompose reverses the faces before the engine runs.

    A run exits 1 when a finding's rule is listed in --fail-on (after writing the report), 0 otherwise, 2 on unusable input. A batch
    keeps going: a file that cannot be read is an entry of the report's "errors" and a
    'meshcol: error:' line, the other files are inspected and reported, and the run exits 2.
    A summary table goes to stderr (the first 20 bodies, then "N more").

    With --jobs N, --timeout or --executor ray, each file is a task of its own (read and
    inspected in a worker process, or a Ray task; a manifest is read here and its bodies go
    out grouped by mesh file): a file whose task dies or runs over --timeout is a "not
    inspected" entry of the report's "errors" (exit 2) while the others finish. The report
    is the same whichever executor ran it.

    \b
    Examples:
      meshcol inspect chair.obj                       JSON report on stdout
      meshcol inspect props/*.obj --report health.csv
      meshcol inspect level.json --fail-on not-watertight,self-intersecting
      meshcol inspect props/*.obj --report - --format csv --fail-on all
      meshcol inspect robot.urdf --fail-on MC301,MC204,collider-volume-mismatch
      meshcol inspect lib/*.glb -j 2 --timeout 60 --executor ray --report health.json
    """
    from meshcol.analysis.inspect import inspect as run_inspect
    from meshcol.analysis.review import inspect_page

    check_outputs(
        files={"--report": report, "--html": html},
        folders={"--snapshots": snapshots},
        inputs=inputs,
    )
    fmt = report_format(report, fmt)
    progress = Progress(command="inspect", heartbeat=True)
    try:
        result = run_inspect(
            list(inputs),
            fail_on=fail_on,
            physics=physics,
            progress=progress,
            jobs=jobs,
            timeout=timeout,
            executor=executor,
            ray_address=ray_address,
            robot_options=robot_options,
        )
    finally:
        progress.done()

    def review() -> Any:
        return inspect_page(result, inputs, robot_options)

    write_outputs(result, review, fmt, report, html, snapshots)
    click.echo("\n".join(summary_lines(result)), err=True)
    sys.exit(result.exit_code)


#: Rows of the summary table; a longer batch ends with "N more".
TABLE_ROWS = 20


def summary_lines(result: Any) -> list[str]:
    """What a run says on stderr: a short table of the bodies, the warnings, each failing
    finding and each input not inspected, then the verdict."""
    lines = _table(result.bodies)
    lines += [f"meshcol: warning: {warning}" for warning in result.warnings]
    for found in result.failed_findings:
        where = f"body '{found.body}'" + ("" if found.part is None else f" part '{found.part}'")
        source = result.source_of(found)
        lines.append(
            f"meshcol: fail: {source + ': ' if source else ''}{where}: {found.rule} "
            f"{found.name}: {found.message}"
        )
    for error in result.errors:
        body = "" if error["body"] is None else f"body '{error['body']}': "
        lines.append(f"meshcol: error: {error['source']}: {body}{error['message']}")
    counts = result.summary
    detail = f"{plural(counts['bodies'], 'body')}, {counts['with_findings']} with findings"
    if result.fail_on:
        detail += f", {counts['failed']} failing --fail-on {','.join(result.fail_on)}"
    if result.errors:
        detail += f", {plural(len(result.errors), 'input')} not inspected"
    lines.append(verdict("inspect", result.exit_code == 0, detail))
    return lines


def _table(rows: list[dict]) -> list[str]:
    """A short human summary of the bodies (none when there are none)."""
    header = ("body", "faces", "closed", "volume", "size", "units", "findings")
    cells = [header]
    for row in rows[:TABLE_ROWS]:
        volume = "-" if row["volume"] is None else f"{row['volume']:.4g}"
        size = " x ".join(f"{s:.3g}" for s in row["size"])
        cells.append(
            (
                row["name"],
                str(row["faces"]),
                "yes" if row["watertight"] else "no",
                volume,
                size,
                row["units_guess"],
                ", ".join(row["findings"]) or "ok",
            )
        )
    if len(cells) == 1:
        return []
    widths = [max(len(line[i]) for line in cells) for i in range(len(header) - 1)]
    lines = [
        "  ".join([*(cell.ljust(width) for cell, width in zip(line, widths)), line[-1]]).rstrip()
        for line in cells
    ]
    if len(rows) > TABLE_ROWS:
        lines.append(f"... {len(rows) - TABLE_ROWS} more (every body is in the report)")
    return lines
