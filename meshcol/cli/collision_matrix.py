"""``meshcol collision-matrix``: a robot's self-collision matrix, written as SRDF."""

from __future__ import annotations

import contextlib

import click

from meshcol.analysis.collision_matrix import MATRIX_CLASSES
from meshcol.cli.common import (
    TABLE_ROWS,
    FiniteFloat,
    Progress,
    cache_dir_option,
    collider_option,
    engine_option,
    finish_outputs,
    plural,
    report_format,
    robot_options,
    rows_left,
    threads_option,
    verdict,
)
from meshcol.io.robot import RobotOptions
from meshcol.vocabulary import MATRIX_COLLIDERS

#: Most joint configurations one run samples (MoveIt's default is 10,000; each sample's link
#: poses are held at once).
MAX_SAMPLES = 10_000_000


def _at_most_max_samples(value: int) -> int:
    if value > MAX_SAMPLES:
        raise click.BadParameter(
            f"{value} is more than the {MAX_SAMPLES:,} samples one run can hold",
            param_hint="'--samples'",
        )
    return value


@click.command(
    "collision-matrix",
    short_help="Sample a robot's joints: link pairs adjacent, default, always, never, sometimes.",
)
@click.argument("robot", metavar="ROBOT")
@click.option(
    "--samples",
    type=click.IntRange(min=1),
    callback=lambda ctx, param, value: _at_most_max_samples(value),
    default=10_000,
    show_default=True,
    help="Random joint configurations (uniform within the limits).",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seed of the configurations: the same seed gives the same matrix.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False, allow_dash=True),
    default=None,
    metavar="FILE.srdf",
    help="Write the SRDF <disable_collisions> entries to FILE ('-': stdout).  [default: stdout, "
    "unless --report is '-']",
)
@click.option(
    "--report",
    type=click.Path(dir_okay=False, allow_dash=True),
    default=None,
    metavar="FILE",
    help="Write the report (every pair, its class and rate) to FILE ('-': stdout), JSON or CSV "
    "by its extension (.json, .csv; JSON otherwise).  [default: none]",
)
@collider_option(
    "Collision shape of each collision element (primitives are always exact).",
    MATRIX_COLLIDERS,
)
@click.option(
    "--padding",
    type=FiniteFloat(min=0.0),
    default=0.0,
    show_default=True,
    help="Metres: links closer than this count as colliding.",
)
@click.option(
    "--always-fraction",
    type=FiniteFloat(min=0.0, max=1.0, min_open=True),
    default=0.95,
    show_default=True,
    help="Pairs colliding in at least this fraction of the samples are 'always' (MoveIt: 0.95).",
)
@threads_option()
@engine_option("Decomposition engine for --shape decomposed (parts missing from the cache).")
@cache_dir_option()
@robot_options()
def collision_matrix(
    robot: str,
    samples: int,
    seed: int,
    output: str | None,
    report: str | None,
    shape: str,
    padding: float,
    always_fraction: float,
    threads: int,
    engine: str,
    cache_dir: str | None,
    robot_options: RobotOptions,
) -> None:
    """Classify every pair of links of ROBOT (URDF or MJCF) as MoveIt's setup assistant does.

    Joint configurations are sampled uniformly within the limits (continuous joints over
    [-pi, pi]; mimic joints follow their leader; fixed joints stay fixed). Each pair of links
    with collision geometry is, in this order: adjacent (joined by a joint, or through links
    without geometry), excluded (a pair the description never collides: MJCF <exclude>,
    bodies welded together, contype/conaffinity that never match), default (colliding at the
    default configuration, the one check uses: zero, or the middle of limits that exclude
    zero; --joint/--joints set it), always (colliding in at least --always-fraction of the
    samples), never (in none of them), or sometimes (with its rate). Colliding means within
    --padding plus check's contact tolerance (1e-6 m): touching counts. The first five are
    written as SRDF <disable_collisions> entries (reasons Adjacent, User, Default, Always,
    Never) to --output; --report writes every pair with its class and collision rate as
    JSON. Exit 0 when written, 2 on bad input (nothing written).

    \b
    Examples:
      meshcol collision-matrix panda.urdf --samples 10000 --seed 1 -o panda.srdf
      meshcol collision-matrix robot.xml -o robot.srdf --report matrix.json
      meshcol check panda.urdf --srdf panda.srdf
    """
    from meshcol.analysis.collision_matrix import CollisionMatrixReport
    from meshcol.analysis.collision_matrix import collision_matrix as run
    from meshcol.io.formats import formats_for, report_text
    from meshcol.io.outputs import check_outputs

    if output is not None and output == report:
        raise click.BadParameter(
            f"{output!r} is also the --report: give two files", param_hint="'-o' / '--output'"
        )
    srdf_to = "-" if output is None and report != "-" else output
    check_outputs(files={"-o/--output": srdf_to, "--report": report}, inputs=[robot])
    formats = formats_for(CollisionMatrixReport)
    fmt = report_format(report, None, format_option=False, formats=formats)
    decompose: dict = {"engine": engine}
    if cache_dir is not None:
        decompose["cache_dir"] = cache_dir
    progress = Progress(command="collision-matrix", heartbeat=True)
    try:
        result = run(
            robot,
            progress=progress,
            samples=samples,
            seed=seed,
            collider=shape,
            padding=padding,
            always_fraction=always_fraction,
            threads=threads,
            decompose_options=decompose,
            robot_options=robot_options,
        )
    finally:
        progress.done()

    _write_all(
        [
            (srdf_to, result.to_srdf()),
            (report, report_text(result, fmt)),
        ]
    )
    finish_outputs()
    for warning in result.warnings:
        click.echo(f"meshcol: warning: {warning}", err=True)
    click.echo(summary_table(result), err=True)


def _write_all(files: list[tuple[str | None, str]]) -> None:
    """Write each ``(path, text)``: both files or neither (each is renamed into place only once
    both are written), then the ``-`` ones to stdout; None paths are skipped."""
    from meshcol.io.report import atomic_path, emit

    with contextlib.ExitStack() as stack:
        for path, text in files:
            if path in (None, "-"):
                continue
            with open(stack.enter_context(atomic_path(path)), "w", encoding="utf-8") as f:
                f.write(text)
    for path, text in files:
        if path == "-":
            emit(text, None)


def summary_table(result) -> str:
    """A short human summary: counts per class, the most frequent sometimes pairs, the verdict."""
    s = result.summary
    lines = [
        f"meshcol: collision-matrix: {plural(s['links'], 'link')}, "
        f"{plural(s['link_pairs'], 'pair')}, {plural(s['samples'], 'sample')} (seed {s['seed']}, "
        f"{s['seconds_per_configuration'] * 1e6:.1f} us per configuration, {s['seconds']:.3f} s "
        "in all)",
        "  " + "  ".join(f"{name}: {s['pairs_by_class'][name]}" for name in MATRIX_CLASSES),
    ]
    checked = sorted(
        (p for p in result.pairs if p["class"] == "sometimes"), key=lambda p: -p["rate"]
    )
    if checked:
        lines.append(f"  {'rate':>8}  sometimes colliding (still checked)")
        for p in checked[:TABLE_ROWS]:
            lines.append(f"  {p['rate']:8.4f}  {p['link_a']} <-> {p['link_b']}")
        lines += rows_left(TABLE_ROWS, len(checked))
    detail = (
        f"{plural(s['disabled_pairs'], 'pair')} disabled, "
        f"{plural(s['pairs_by_class']['sometimes'], 'pair')} still checked"
    )
    lines.append(verdict("collision-matrix", True, detail))
    return "\n".join(lines)
