"""``meshcol hull``: convex hulls, optionally within an engine's vertex budget."""

from __future__ import annotations

import functools
from typing import Any

import click

from meshcol.cli import CONTEXT_SETTINGS
from meshcol.cli.common import (
    html_option,
    mesh_outputs,
    plural,
    report_format,
    report_options,
    robot_options,
    snapshots_option,
    target_option,
    to_option,
    verdict,
    write_outputs,
)
from meshcol.cli.mesh_outputs import (
    report_wanted,
    run_mesh_command,
    urdf_capsules_of,
    urdf_capsules_option,
    written_to,
)
from meshcol.io.outputs import check_outputs
from meshcol.io.robot import RobotOptions
from meshcol.io.targets import target_names


@click.command(
    "hull",
    short_help="Convex hull of each body, optionally within a vertex budget.",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option(
    "-o",
    "--output",
    "output",
    metavar="FILE",
    help="Write the hull(s) to FILE (format from the extension: .obj .stl .ply .off "
    ".glb). Several bodies need .obj or .glb (one named object each).  [default: no mesh "
    "file]",
)
@click.option(
    "--out-dir",
    metavar="DIR",
    help="Write one DIR/<body>.obj per body (characters other than letters, digits, "
    "'.', '-' and '_' become '_').  [default: no mesh files]",
)
@click.option(
    "--max-vertices",
    type=click.IntRange(min=4),
    metavar="N",
    help="At most N vertices per hull (PhysX: 255, GPU pipelines: 64), still enclosing the "
    "input.  [default: no budget, the exact hull]",
)
@target_option(
    "Fit every hull to an engine's limits (meshcol targets lists them: "
    f"{', '.join(target_names())}) or to your own profile; "
    "a tighter --max-vertices still wins. Exit 1 when a limit cannot be met."
)
@to_option("the hulls", gltf=True)
@urdf_capsules_option
@report_options(default="stdout when no mesh is written, else no report")
@robot_options()
@html_option
@snapshots_option
def hull(
    inputs: tuple[str, ...],
    output: str | None,
    out_dir: str | None,
    max_vertices: int | None,
    target: Any,
    to: str | None,
    urdf_capsules: str | None,
    report: str | None,
    fmt: str | None,
    html: str | None,
    snapshots: str | None,
    robot_options: RobotOptions,
) -> None:
    """Convex hull of each body, optionally within a vertex budget.

    INPUT is mesh files (OBJ, STL, PLY, OFF, glTF/GLB, FBX, COLLADA, USD; every object, solid
    or mesh node is a body), one scene manifest or a robot description. Hulls are in the WORLD frame: each body's scene transform
    is applied, so exported colliders sit in place over the input.

    With --max-vertices the hull keeps at most N vertices and still contains every input
    vertex: its faces are grown outward (never pulled in), and the report gives the volume
    this added and the largest distance from the simplified hull to the exact one.

    With --target every hull meets all the engine's limits (vertices, polygons after
    merging coplanar triangles, triangles, polygons per vertex, minimum thickness and
    volume, the GPU oblong ratio), still enclosing the input: thin or flat bodies are
    thickened, never shrunk. Each row's "target" says what each limit cost, in the order
    limits are applied: marginal added volume (these sum to the row's added_volume),
    cumulative largest distance, and the limit's standalone cost; and lists any limit that
    could not be met, with its rule id (MC101..); those exit 1.

    The report (JSON or CSV, one row per body) gives the input and hull sizes, the hull
    volume, the mesh volume (closed meshes only, else null), volume_ratio = mesh volume /
    hull volume (1 for a convex mesh) and, with a budget, added_volume,
    added_volume_fraction and max_distance. Coplanar input gives a flat 2-D hull (a
    warning on stderr, flat: true, volume 0); collinear or single-point input has no hull
    and exits 2.

    A robot description (URDF, or MJCF) with --out-dir is rebuilt: one hull per
    collision element (its meshes together), written as OUT/<link>_NN.obj in the link's
    frame, and a copy of the description, OUT/<robot>.urdf, whose <collision> elements use
    them (no <origin>: the element's origin and scale are in the hull); visuals, inertials,
    joints, comments and unknown tags are untouched, and box, sphere, cylinder and capsule
    elements are kept as they are (already exact; URDF has no capsule: a <capsule> is
    written as a <cylinder> and two <sphere>s, or kept with --urdf-capsules extension). --to mjcf writes OUT/<robot>.xml in
    MuJoCo Menagerie's convention (visual geoms group 2, contype/conaffinity 0; collision
    geoms group 3); --to glb and --to usd write the colliders at the joint configuration.
    --target fits each element's hull as it fits a mesh's (the description is in metres).

    \b
    Examples:
      meshcol hull chair.obj                          report on stdout
      meshcol hull panda.urdf --max-vertices 64 --out-dir panda_hulls/
      meshcol hull panda.urdf --out-dir out/ --to mjcf --joint panda_joint4=-1.5
      meshcol hull chair.obj --max-vertices 64 -o chair_hull.obj
      meshcol hull props/*.obj --target physx-gpu --out-dir hulls
      meshcol hull props/*.obj --max-vertices 255 --out-dir hulls --report hulls.csv
      meshcol hull level.json -o level_hulls.glb --report -
      meshcol hull props/*.obj --target physx-gpu --format markdown --snapshots pr/
    """
    robot = mesh_outputs(inputs, output, out_dir, to, fmt, report)
    capsules = urdf_capsules_of(urdf_capsules, inputs, robot, to)

    from meshcol.analysis.hull import hull as run_hull
    from meshcol.analysis.review import hull_page

    check_outputs(
        files={"-o": output, "--report": report, "--html": html},
        folders={"--out-dir": out_dir, "--snapshots": snapshots},
        inputs=inputs,
    )
    fmt = report_format(report, fmt)
    from meshcol.analysis.rebuild import rebuild_hulls

    result = run_mesh_command(
        "hull",
        inputs,
        robot,
        (output, out_dir, to, report),
        run_hull,
        functools.partial(rebuild_hulls, urdf_capsules=capsules),
        max_vertices=max_vertices,
        target=target,
        warn=lambda message: click.echo(f"meshcol: warning: {message}", err=True),
        robot_options=robot_options,
    )

    def review() -> Any:
        return hull_page(result, inputs, robot_options)

    emit = report_wanted(report, output, out_dir)
    write_outputs(result, review, fmt, report, html, snapshots, emit)
    _say_violations(result)
    detail = _summary(result, target, output, out_dir, robot)
    click.echo(verdict("hull", result.exit_code == 0, detail), err=True)
    if result.exit_code:
        click.get_current_context().exit(result.exit_code)


def _say_violations(result: Any) -> None:
    """One stderr line per limit a hull could not meet."""
    for body, violation in result.violations:
        click.echo(
            f"meshcol: {violation.rule} {violation.rule_name}: body '{body}' {violation.message}",
            err=True,
        )


def _summary(result: Any, target: Any, output: str | None, out_dir: str | None, robot: bool) -> str:
    """The verdict line's detail: hulls, vertices, flat ones, where written, the target."""
    s = result.summary
    detail = f"{plural(s['bodies'], 'hull')}, {plural(s['hull_vertices'], 'vertex', 'vertices')}"
    if s["flat"]:
        detail += f", {s['flat']} flat"
    detail += written_to(result, output, out_dir, robot)
    if target is not None:
        missed = s["target_violations"]
        detail += f", target {target.name}: " + (
            "every limit met" if not missed else f"{plural(missed, 'limit')} not met"
        )
    return detail
