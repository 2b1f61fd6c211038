"""``meshcol sweep``: continuous collision over a scene's motion (time of impact, tunnelling)."""

from __future__ import annotations

import sys

import click

from meshcol.analysis.sweep import FAIL_ON
from meshcol.cli import CONTEXT_SETTINGS
from meshcol.cli.common import (
    TABLE_ROWS,
    FiniteFloat,
    Progress,
    cache_dir_option,
    collider_option,
    html_option,
    plural,
    report_format,
    report_options,
    robot_options,
    rows_left,
    snapshots_option,
    threads_option,
    verdict,
    write_outputs,
)
from meshcol.io.outputs import check_outputs
from meshcol.io.robot import RobotOptions


@click.command(
    "sweep",
    short_help="First contact of moving bodies (time of impact) and the hits that tunnel.",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("manifest", metavar="MANIFEST")
@collider_option(
    "Collision shape of each body: convex hull, convex decomposition, or the "
    "triangles of the mesh (surface contact)."
)
@click.option(
    "--tolerance",
    type=FiniteFloat(min=0.0, min_open=True),
    metavar="T",
    help="Contact distance in scene units.  [default: 1e-6 x the diagonal of the "
    "scene's swept bounds]",
)
@report_options(default="the report on stdout; a summary on stderr")
@click.option(
    "--fail-on",
    "fail_on",
    type=click.Choice(FAIL_ON),
    default="hit",
    show_default=True,
    help="'hit': exit 1 when a pair hits, overlaps at the start or cannot be "
    "decided; 'none': always exit 0 after a successful run.",
)
@threads_option("Worker threads (0: all cores).")
@cache_dir_option(
    "Decompose cache folder for --shape decomposed; bodies missing from it are "
    "decomposed now.  [default: the user cache, as 'meshcol decompose']"
)
@robot_options()
@html_option
@snapshots_option
def sweep(
    manifest: str,
    shape: str,
    tolerance: float | None,
    report: str | None,
    fmt: str | None,
    fail_on: str,
    threads: int,
    cache_dir: str | None,
    html: str | None,
    snapshots: str | None,
    robot_options: RobotOptions,
) -> None:
    """First contact of moving bodies: meshcol sweep MANIFEST [options].

    MANIFEST is a scene manifest whose bodies have start poses and end poses
    (`end_position` / `end_rotation`, or `velocity` / `angular_velocity` with the manifest's
    `duration`); bodies without an end pose stay still. Each body moves over the motion with
    its origin moving linearly and turning at constant angular velocity about it: by the whole
    angle of `angular_velocity` x `duration` (several turns included), or the shortest way
    to an `end_rotation`. The report lists every pair of bodies that is not separated during the
    motion: its status (HIT, OVERLAPPED_AT_START or FAILED), toi (fraction of the motion),
    time in seconds when the manifest has a duration, the world contact point and normal
    (a to b), both poses at impact (4x4), and `tunnelled` when a discrete check at the start
    and end poses alone misses the contact.

    Exit status: 0 no contact (or --fail-on none), 1 contact found, 2 unusable input.

    \b
    Examples:
      meshcol sweep samples/bullet/scene.json            JSON report on stdout
      meshcol sweep level.json --report sweep.csv --fail-on none
      meshcol sweep level.json --shape mesh --tolerance 1e-5 --report -
      meshcol sweep level.json --format markdown --snapshots pr/ > pr/sweep.md
    """
    from meshcol.analysis.review import sweep_page
    from meshcol.analysis.sweep import sweep as run_sweep

    check_outputs(
        files={"--report": report, "--html": html},
        folders={"--snapshots": snapshots},
        inputs=[manifest],
    )
    fmt = report_format(report, fmt)
    decompose_options = {} if cache_dir is None else {"cache_dir": cache_dir}
    progress = Progress(command="sweep", heartbeat=True)  # the library reports no steps
    try:
        result = run_sweep(
            manifest,
            collider=shape,
            tolerance=tolerance,
            threads=threads,
            decompose_options=decompose_options,
            fail_on=fail_on,
            robot_options=robot_options,
        )
    finally:
        progress.done()
    write_outputs(result, lambda: sweep_page(result), fmt, report, html, snapshots)
    for warning in result.warnings:
        click.echo(f"meshcol: warning: {warning}", err=True)
    click.echo(summary_lines(manifest, result), err=True)
    sys.exit(result.exit_code)


def summary_lines(manifest: str, result) -> str:
    """The summary on stderr: counts, one ``meshcol: fail:`` line for each of the first
    :data:`~meshcol.cli.common.TABLE_ROWS` pairs that are not separated (the undecided ones,
    then by time of impact), and the verdict line."""
    s = result.summary
    lines = [
        f"meshcol: sweep: {plural(s['bodies'], 'body')} ({s['moving_bodies']} moving), "
        f"{plural(s['candidate_pairs'], 'candidate pair')}, {plural(s['hits'], 'hit')} "
        f"({s['tunnelled']} tunnelled), {s['overlapped_at_start']} overlapped at start, "
        f"{s['failed']} undecided"
    ]
    # the undecided pairs first, then the earliest contacts
    first = result.columns.first(TABLE_ROWS)
    for h in first:
        when = "" if h.time is None else f" (t = {h.time:.6g} s)"
        extra = ", tunnelled" if h.tunnelled else ""
        kind = "fail" if result.exit_code else "note"
        lines.append(
            f"meshcol: {kind}: {manifest}: '{h.body_a}' and '{h.body_b}': {h.status.name} at time of "
            f"impact {h.time_of_impact:.6g}{when}{extra}"
        )
    lines += rows_left(len(first), len(result.hits))
    if not result.hits:
        detail = "no pair touches during the motion"
    else:
        touch = "touches" if len(result.hits) == 1 else "touch"
        detail = f"{plural(len(result.hits), 'pair')} {touch} during the motion"
        if not result.exit_code:
            detail += " (--fail-on none)"
    lines.append(verdict("sweep", result.exit_code == 0, detail))
    return "\n".join(lines)
