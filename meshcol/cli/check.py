"""``meshcol check``: all-pairs collision analysis of a scene."""

from __future__ import annotations

import sys
from typing import Any

import click

from meshcol.analysis.check_policy import FAIL_ON, MAX_PAIRS
from meshcol.cli.common import (
    TABLE_ROWS,
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
    rows_left,
    snapshots_option,
    target_option,
    threads_option,
    timeout_option,
    verdict,
)
from meshcol.io.robot import RobotOptions
from meshcol.vocabulary import COLLIDER_KINDS

FAIL_ON_CHOICES = tuple(FAIL_ON)
SHAPE_CHOICES = COLLIDER_KINDS


def _parse_fail_on(ctx: click.Context, param: click.Parameter, value: str) -> str:
    from meshcol.analysis.check_policy import failing_rules
    from meshcol.analysis.rules import UnknownRuleError

    try:
        failing_rules(value)
    except UnknownRuleError as exc:
        raise click.BadParameter(str(exc), ctx, param) from None
    return value


def _parse_ignore(
    ctx: click.Context, param: click.Parameter, value: tuple[str, ...]
) -> tuple[str, ...]:
    from meshcol.analysis.check_policy import parse_ignore_rule

    for rule in value:
        try:
            parse_ignore_rule(rule)
        except ValueError as exc:
            raise click.BadParameter(str(exc), ctx, param) from None
    return value


@click.command(
    "check", short_help="Every pair of bodies: apart, clearance, contact, penetrating or contained."
)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@collider_option("Collision shape of each body (a manifest's per-body 'shape' overrides it).")
@click.option(
    "--tolerance",
    type=FiniteFloat(min=0.0),
    default=1e-6,
    show_default=True,
    help="Contact band in scene units: |signed distance| <= T counts as touching.",
)
@click.option(
    "--clearance",
    type=FiniteFloat(min=0.0),
    default=0.0,
    show_default=True,
    help="Minimum gap required; closer pairs get status 'clearance'.",
)
@click.option(
    "--fail-on",
    default="penetration",
    show_default=True,
    metavar="LEVEL|RULES",
    callback=_parse_fail_on,
    help="Least severe status that fails the run (exit 1): "
    + ", ".join(FAIL_ON_CHOICES)
    + "; or comma-separated rule ids or names (MC501,MC301, penetrating, missing-collider, "
    "all; 'meshcol rules'): MC506 fails a robot with no collision geometry, which a level "
    "passes.",
)
@click.option(
    "--ignore",
    "ignore",
    multiple=True,
    metavar="A:B",
    callback=_parse_ignore,
    help="Pair designed to touch (globs allowed, either order); repeatable.  [default: none]",
)
@click.option(
    "--baseline",
    type=click.Path(dir_okay=False),
    default=None,
    metavar="OLD.json",
    help="Previous JSON report: fail only on pairs that are new or worse.  [default: none, "
    "every violating pair fails]",
)
@click.option(
    "--max-pairs",
    type=click.IntRange(min=0),
    default=MAX_PAIRS,
    show_default=True,
    metavar="N",
    help="Most candidate pairs a run may hold (each costs memory): a scene with more is "
    "refused (exit 2, nothing written) before its pairs are measured.",
)
@threads_option()
@engine_option("Decomposition engine for 'decomposed' bodies missing from the cache.")
@click.option(
    "--threshold",
    type=FiniteFloat(min=0.0, max=1.0, min_open=True),
    default=None,
    help="Decomposition concavity threshold (as in 'meshcol decompose').  [default: 0.05]",
)
@cache_dir_option()
@jobs_option(
    "Files prepared at once (read, and decomposed for --shape decomposed), each a task in a "
    "worker process or on Ray; the pairs are measured here, on --threads (1: all in this "
    "process, unless --timeout or --executor ray)."
)
@timeout_option(
    "Seconds allowed per file's task; a file over it is an error (exit 2).  [default: no limit]"
)
@executor_options()
@target_option(
    "Measure each body's convex parts against an engine's limits (meshcol targets); "
    "each limit a part is past is a finding (MC101..MC107, MC201) that fails the run "
    "with a --fail-on level."
)
@report_options(default="the report on stdout; the summary on stderr")
@robot_options(exclusions=True)
@html_option
@snapshots_option
def check(
    inputs: tuple[str, ...],
    shape: str,
    engine: str,
    threshold: float | None,
    cache_dir: str | None,
    report: str | None,
    fmt: str | None,
    html: str | None,
    snapshots: str | None,
    robot_options: RobotOptions,
    **options: Any,
) -> None:
    """Check every pair of bodies for contact, clearance and interpenetration.

    INPUT is mesh files (each body at its own coordinates, as parts exported in place), one
    scene manifest (JSON/TOML), glTF/GLB scenes, or one robot description (URDF, MJCF): its
    links are the bodies, posed at --joint/--joints (default: MoveIt's default configuration, zero or the middle of
    limits that exclude zero, as collision-matrix), their collision elements
    the parts; links joined by a joint are left out (--include-adjacent keeps them), and so
    are the --srdf file's <disable_collisions> pairs. Files given directly give one body per
    object, named <stem>/<object> (where names repeat in a USD, glTF, FBX or COLLADA file, by
    the end of the prim or node path that tells them apart: level/crate_01/mesh; else #2, #3);
    a manifest body is its whole file, whose objects are its parts (never checked
    against each other; pairs name them as part_a, part_b). Statuses per pair: separated,
    clearance, contact, penetrating, contained. The report (JSON or CSV) goes to --report FILE
    or to stdout; a short summary goes to stderr. Exit 0 when the policy passes, 1 when it
    fails, 2 on bad input. Points are world coordinates; normals point from body_a to body_b.

    \b
    Examples:
      meshcol check level/scene.json
      meshcol check parts/*.stl --clearance 0.5 --fail-on clearance --report out.json
      meshcol check scene.glb --shape decomposed --ignore 'door*:frame*'
      meshcol check scene.json --baseline last_week.json > today.json
      meshcol check panda.urdf --srdf panda.srdf --joint panda_joint4=-1.5
      meshcol check props/*.obj --shape decomposed -j 2 --executor ray
    """
    from meshcol.analysis.check import check as run_check
    from meshcol.cli.common import write_outputs
    from meshcol.io.outputs import check_outputs

    check_outputs(
        files={"--report": report, "--html": html},
        folders={"--snapshots": snapshots},
        inputs=inputs,
        named_inputs={"the --baseline": options["baseline"]},
    )
    fmt = report_format(report, fmt)
    decompose_options = _decompose_options(engine, threshold, cache_dir)
    progress = Progress(command="check", heartbeat=True)
    try:
        result = run_check(
            list(inputs),
            progress=progress,
            collider=shape,
            decompose_options=decompose_options,
            robot_options=robot_options,
            **options,
        )
    finally:
        progress.done()

    def review() -> Any:
        return _review_page(result, inputs, shape, decompose_options, robot_options)

    write_outputs(result, review, fmt, report, html, snapshots)
    for warning in result.warnings:
        click.echo(f"meshcol: warning: {warning}", err=True)
    click.echo(summary_table(result), err=True)
    sys.exit(result.exit_code)


def _review_page(
    result: Any,
    inputs: tuple[str, ...],
    shape: str,
    decompose: dict,
    robot_options: RobotOptions,
) -> Any:
    from meshcol.analysis.review import check_page  # only with --html

    return check_page(result, inputs, shape, decompose, robot_options)


def _decompose_options(engine: str, threshold: float | None, cache_dir: str | None) -> dict:
    options: dict = {"engine": engine}
    if threshold is not None:
        options["threshold"] = threshold
    if cache_dir is not None:
        options["cache_dir"] = cache_dir
    return options


def summary_table(result: Any) -> str:
    """A short human summary: counts per status, the worst pairs, the failing findings, the
    verdict line."""
    failed = [f for f in result.findings if f["failed"]]
    lines = [*_count_lines(result), *_worst_lines(result), *_finding_lines(failed)]
    lines.append(verdict("check", result.summary["passed"], _verdict_detail(result, failed)))
    return "\n".join(lines)


def _count_lines(result: Any) -> list[str]:
    """Bodies, candidate pairs and times; then the count of each status."""
    s = result.summary
    excluded = f", {s['excluded_pairs']} excluded" if s.get("excluded_pairs") else ""
    return [
        f"meshcol: check: {plural(s['bodies'], 'body')}, "
        f"{plural(s['candidate_pairs'], 'candidate pair')}{excluded} "
        f"({s['seconds']:.3f} s check, {s['load_seconds'] or 0:.3f} s load)",
        "  " + "  ".join(f"{name}: {count}" for name, count in s["pairs_by_status"].items()),
    ]


def _worst_lines(result: Any) -> list[str]:
    """The most penetrating pairs that are not separated, one line each."""
    worst = result.worst_pairs(TABLE_ROWS)
    if not worst:
        return []
    units = f" {result.units}" if result.units else ""
    lines = [f"  {'status':<12} {'signed dist':>12}  pair"]
    for p in worst:
        value = "" if p["signed_distance"] is None else f"{p['signed_distance']:.6g}"
        flag = " (ignored)" if p["ignored"] else (" (FAIL)" if p["violation"] else "")
        a = p["body_a"] if p["part_a"] is None else f"{p['body_a']}/{p['part_a']}"
        b = p["body_b"] if p["part_b"] is None else f"{p['body_b']}/{p['part_b']}"
        lines.append(f"  {p['status']:<12} {value:>12}{units}  {a} <-> {b}{flag}")
    by_status = result.summary["pairs_by_status"]
    touching = sum(count for name, count in by_status.items() if name != "separated")
    return lines + rows_left(len(worst), touching)


def _finding_lines(failed: list[dict]) -> list[str]:
    """One ``meshcol: fail:`` line per failing finding, up to :data:`TABLE_ROWS`."""
    lines = []
    for f in failed[:TABLE_ROWS]:
        where = f"body '{f['body']}'" + ("" if f["part"] is None else f" part '{f['part']}'")
        lines.append(f"meshcol: fail: {where}: {f['rule']} {f['name']}: {f['message']}")
    if len(failed) > TABLE_ROWS:
        lines.append(f"  ... {len(failed) - TABLE_ROWS} more failing findings (in the report)")
    return lines


def _verdict_detail(result: Any, failed: list[dict]) -> str:
    s, fail_on = result.summary, result.settings["fail_on"]
    if s["passed"]:
        return f"no pair violates --fail-on {fail_on}"
    violate = "violates" if s["violations"] == 1 else "violate"
    detail = f"{plural(s['violations'], 'pair')} {violate} --fail-on {fail_on}"
    if failed:
        detail += f", {plural(len(failed), 'finding')} {'fails' if len(failed) == 1 else 'fail'}"
    return detail
