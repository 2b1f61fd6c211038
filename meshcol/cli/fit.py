"""``meshcol fit``: the enclosing sphere, box, capsule, cylinder or ellipsoid of each body."""

from __future__ import annotations

import functools

import click

from meshcol.analysis.fit import DEFAULT_VOLUME_TOLERANCE, SHAPE_CHOICES
from meshcol.cli import CONTEXT_SETTINGS
from meshcol.cli.common import (
    FiniteFloat,
    mesh_outputs,
    plural,
    report_format,
    report_options,
    robot_options,
    snapshots_option,
    to_option,
    verdict,
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


@click.command(
    "fit",
    short_help="Enclosing primitive (box, sphere, capsule, cylinder, ellipsoid) of each body.",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option(
    "--shape",
    type=click.Choice(SHAPE_CHOICES),
    default="auto",
    show_default=True,
    help="The primitive; auto fits four and takes the simplest (sphere, capsule, box, "
    "cylinder; never the ellipsoid, which not every engine has) within --volume-tolerance of "
    "the hull's volume, else keeps the hull; a body that is a primitive (an ellipsoid too) "
    "keeps itself, exactly.",
)
@click.option(
    "--volume-tolerance",
    type=FiniteFloat(min=0.0),
    default=DEFAULT_VOLUME_TOLERANCE,
    show_default=True,
    metavar="T",
    help="For --shape auto: take a primitive whose volume is at most (1 + T) times the "
    "convex hull's.",
)
@click.option(
    "-o",
    "--output",
    "output",
    metavar="FILE",
    help="Write the fits to FILE as Unreal collision parts (UBX_, USP_, UCP_; UCX_ for a "
    "cylinder, an ellipsoid or a kept hull), meshes that contain the primitive; several "
    "bodies need .obj or .glb.  [default: no mesh file]",
)
@click.option(
    "--out-dir",
    metavar="DIR",
    help="Write one DIR/<body>.obj per body; for a robot description, the description "
    "rebuilt with primitive colliders.  [default: no mesh files]",
)
@to_option("the fits", gltf=True)
@urdf_capsules_option
@report_options(default="stdout when no mesh is written, else no report")
@robot_options()
@snapshots_option
def fit(
    inputs: tuple[str, ...],
    shape: str,
    volume_tolerance: float,
    output: str | None,
    out_dir: str | None,
    to: str | None,
    urdf_capsules: str | None,
    report: str | None,
    fmt: str | None,
    robot_options: RobotOptions,
    snapshots: str | None,
) -> None:
    """Enclosing primitive of each body: it contains every vertex of the mesh.

    INPUT is mesh files (OBJ, STL, PLY, OFF, glTF/GLB, FBX, COLLADA, USD), one scene manifest
    or a robot description; fits are in the WORLD frame, like hulls.

    sphere: the minimum enclosing sphere. box: a near-minimal oriented box (hull face
    normals and principal axes tried, then polished). cylinder and capsule: along the best
    axis found, radius by the smallest circle across it. ellipsoid: the minimum-volume
    enclosing ellipsoid (Khachiyan's method), its volume certified within 1e-6 of the
    minimum's, then scaled so that no vertex is outside. Each is grown by the rounding of its
    search so that it contains every vertex.

    The report (JSON or CSV, one row per body) gives the primitive's parameters (radius,
    length, full size; an ellipsoid's size is twice its semi-axes), its centre and rotation
    (quaternion w, x, y, z; capsule and cylinder along local z), its volume, volume_ratio =
    volume / mesh volume (closed meshes only), hull_ratio = volume / hull volume, and
    max_gap, the largest distance from the primitive's surface to the mesh (sampled). With
    --shape auto, simpler_primitive says a primitive is within the tolerance ("could use a
    simpler primitive") and candidates lists all four.

    A robot description (URDF, or MJCF) with --out-dir is rebuilt: each collision mesh
    element becomes its fit, written as the description's own primitive (URDF <box>,
    <sphere>, <cylinder>; MJCF geom types, ellipsoid included) with an <origin> in the link
    frame; a hull kept by --shape auto goes to OUT/<link>_NN.obj. URDF has no capsule: one
    is written as a <cylinder> and a <sphere> at each end, three <collision> elements
    (NAME_00, NAME_01, NAME_02), which ROS (urdfdom), yourdfpy, pybullet and MuJoCo all read;
    --urdf-capsules extension writes <capsule> instead, for pybullet and MuJoCo only. URDF
    has no ellipsoid: --shape ellipsoid needs --to mjcf, usd or glb. Visuals, inertials, joints and existing primitive
    elements are untouched. --to mjcf, glb and usd as for meshcol hull.

    \b
    Examples:
      meshcol fit crate.obj                            report on stdout
      meshcol fit props/*.obj --shape box --report boxes.csv
      meshcol fit level.json -o level_colliders.obj --report fits.json
      meshcol fit panda.urdf --out-dir panda_fits/ --to mjcf --shape capsule
      meshcol fit parts/*.obj --shape ellipsoid --report ellipsoids.csv
      meshcol fit props/*.obj --shape box --format markdown --snapshots pr/
    """
    robot = mesh_outputs(inputs, output, out_dir, to, fmt, report)
    capsules = urdf_capsules_of(urdf_capsules, inputs, robot, to)

    from meshcol.analysis.fit import fit as run_fit

    check_outputs(
        files={"-o": output, "--report": report},
        folders={"--out-dir": out_dir, "--snapshots": snapshots},
        inputs=inputs,
    )
    fmt = report_format(report, fmt)
    from meshcol.analysis.rebuild import rebuild_fits

    result = run_mesh_command(
        "fit",
        inputs,
        robot,
        (output, out_dir, to, report),
        run_fit,
        functools.partial(
            rebuild_fits,
            warn=lambda message: click.echo(f"meshcol: warning: {message}", err=True),
            urdf_capsules=capsules,
        ),
        shape=shape,
        volume_tolerance=volume_tolerance,
        robot_options=robot_options,
    )
    for warning in () if robot else result.warnings:  # a robot rebuilt warned as it went
        click.echo(f"meshcol: warning: {warning}", err=True)
    from meshcol.analysis.review import fit_page
    from meshcol.cli.common import write_outputs

    def review() -> object:
        return fit_page(result, inputs, robot_options)

    emit = report_wanted(report, output, out_dir)
    write_outputs(result, review, fmt, report, None, snapshots, emit)
    s = result.summary
    shapes = ", ".join(f"{count} {name}" for name, count in s["shapes"].items() if count)
    detail = f"{plural(s['bodies'], 'body', 'bodies')} ({shapes or 'none'})"
    if shape == "auto":
        detail += f", {s['simpler_primitive']} could use a simpler primitive"
    detail += written_to(result, output, out_dir, robot)
    click.echo(verdict("fit", True, detail), err=True)
