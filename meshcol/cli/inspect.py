"""``meshcol inspect``: is each mesh fit to be a collider?"""

from __future__ import annotations

import sys

import click

from meshcol.analysis.inspect import RULES
from meshcol.cli.common import (
    Progress,
    check_outputs,
    executor_options,
    html_option,
    jobs_option,
    plural,
    render_html,
    report_format,
    report_options,
    robot_options,
    timeout_option,
    verdict,
    write_html,
)


def _parse_rules(ctx: click.Context, param: click.Parameter, value: str | None) -> tuple[str, ...]:
    if value is None:
        return ()
    names = [v.strip() for v in value.split(",") if v.strip()]
    if "all" in names:
        return RULES
    unknown = [n for n in names if n not in RULES]
    if unknown:
        raise click.BadParameter(
            f"unknown rule {unknown[0]!r} (valid rules: all, {', '.join(RULES)})", ctx, param
        )
    return tuple(dict.fromkeys(names))


@click.command(
    "inspect",
    short_help="Mesh health of each body: fit to be a collider?",
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@report_options(default="the report on stdout; a summary table on stderr")
@click.option(
    "--fail-on",
    "fail_on",
    metavar="RULES",
    callback=_parse_rules,
    help="Comma-separated findings that make the run exit 1: "
    + ", ".join(RULES)
    + " (or all).  [default: none, the run reports only]",
)
@jobs_option(
    "Files inspected at once, each a task in a worker process or on Ray (1: one after "
    "another in this process, unless --timeout or --executor ray)."
)
@timeout_option(
    "Seconds allowed per file; a file over it is stopped and reported as not inspected "
    "(exit 2).  [default: no limit]"
)
@executor_options()
@robot_options()
@html_option
def inspect(
    inputs: tuple[str, ...],
    report: str | None,
    fmt: str | None,
    fail_on: tuple[str, ...],
    jobs: int,
    timeout: float | None,
    executor: str,
    ray_address: str | None,
    html: str | None,
) -> None:
    """Health check of each body's mesh: fit to be a collider?

    INPUT is mesh files (OBJ, STL, PLY, OFF, glTF, GLB; every object, solid or mesh node is
    a body) or one scene manifest. Per body: vertices, faces, connected components,
    watertight, consistent winding, signed volume (closed meshes only), world-frame bounding
    box and size, degenerate (zero-area) faces, duplicate faces, boundary and non-manifold
    edges (more than two faces), self-intersections (pairs of crossing faces), manifold3d's
    status, and a units guess with its reason (a chair 400 units tall is millimetres).

    Faces cross when their open triangles share a point, decided exactly (no tolerance):
    faces that only touch (a shared vertex or edge, a T-junction) do not. A closed mesh with
    a negative volume is inverted (inside out): meshcol hull is unaffected (a hull has no
    winding) and notes it; meshcol decompose reverses the faces before the engine runs.

    Findings are named as the --fail-on rules; a run exits 1 when a body has a finding
    listed in --fail-on (after writing the report), 0 otherwise, 2 on unusable input. A batch
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
      meshcol inspect lib/*.glb -j 2 --timeout 60 --executor ray --report health.json
    """
    from meshcol.analysis.inspect import inspect as run_inspect
    from meshcol.analysis.review import inspect_page
    from meshcol.cli.common import emit_report

    check_outputs(inputs, [("--report", report), ("--html", html)])
    fmt = report_format(report, fmt)
    progress = Progress(command="inspect", heartbeat=True)
    try:
        result = run_inspect(
            list(inputs),
            fail_on=fail_on,
            progress=progress,
            jobs=jobs,
            timeout=timeout,
            executor=executor,
            ray_address=ray_address,
        )
    finally:
        progress.done()
    page = render_html(html, lambda: inspect_page(result, inputs))
    emit_report(result, fmt, report)
    write_html(html, page)

    _print_table(result.bodies)
    for row in result.failed:
        click.echo(
            f"meshcol: fail: {row['source']}: body '{row['name']}': "
            + ", ".join(row["failed_rules"]),
            err=True,
        )
    for error in result.errors:
        body = "" if error["body"] is None else f"body '{error['body']}': "
        click.echo(f"meshcol: error: {error['source']}: {body}{error['message']}", err=True)
    s = result.summary
    detail = f"{plural(s['bodies'], 'body')}, {s['with_findings']} with findings"
    if fail_on:
        detail += f", {s['failed']} failing --fail-on {','.join(fail_on)}"
    if result.errors:
        detail += f", {plural(len(result.errors), 'input')} not inspected"
    click.echo(verdict("inspect", result.exit_code == 0, detail), err=True)
    sys.exit(result.exit_code)


#: Rows of the summary table; a longer batch ends with "N more".
TABLE_ROWS = 20


def _print_table(rows: list[dict]) -> None:
    """A short human summary on stderr."""
    header = ("body", "faces", "closed", "volume", "size", "units", "findings")
    lines = [header]
    for row in rows[:TABLE_ROWS]:
        volume = "-" if row["volume"] is None else f"{row['volume']:.4g}"
        size = " x ".join(f"{s:.3g}" for s in row["size"])
        lines.append(
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
    if len(lines) == 1:
        return
    widths = [max(len(line[i]) for line in lines) for i in range(len(header) - 1)]
    for line in lines:
        cells = [cell.ljust(width) for cell, width in zip(line, widths)]
        click.echo("  ".join([*cells, line[-1]]).rstrip(), err=True)
    if len(rows) > TABLE_ROWS:
        click.echo(f"... {len(rows) - TABLE_ROWS} more (every body is in the report)", err=True)
