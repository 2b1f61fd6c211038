"""What the commands that write meshes (``hull``, ``fit``) share after their usage checks
(:func:`meshcol.cli.common.mesh_outputs`): the error of a single-mesh file given several
bodies, the summary's "written to" clause, and (``decompose`` too) ``--urdf-capsules``."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import click

from meshcol.cli.common import Progress, plural
from meshcol.io.paths import display_path
from meshcol.vocabulary import URDF_CAPSULES


@contextmanager
def several_bodies_need_a_scene_file() -> Iterator[None]:
    """Turn ``OutputDestinationError`` (several bodies, ``-o`` of a single-mesh format) into
    the usage error that names the formats that hold several meshes."""
    from meshcol.analysis.hull import OutputDestinationError
    from meshcol.io.mesh_write import MULTI_MESH_EXTENSIONS

    try:
        yield
    except OutputDestinationError as exc:
        raise click.UsageError(
            f"-o {exc.output}: {exc.bodies} bodies need a file that holds several meshes "
            f"({', '.join(MULTI_MESH_EXTENSIONS)}) or --out-dir"
        ) from None


def report_wanted(report: str | None, output: str | None, out_dir: str | None) -> bool:
    """Whether the run writes its report: to ``--report``, or on stdout when no mesh is
    written (``-o``, ``--out-dir``); meshes written without ``--report`` leave none."""
    return report is not None or not (output or out_dir)


def written_to(result: Any, output: str | None, out_dir: str | None, robot: bool) -> str:
    """The summary clause saying where the meshes went ("" when nowhere): the ``-o`` file, a
    rebuilt robot's description, or the count of files in ``--out-dir``."""
    if output:
        return f", written to {display_path(output)}"
    if robot and result.description is not None:
        # --to gltf-physics says which colliders of the asset it replaced
        replaced = "".join(f" ({w})" for w in result.warnings if w.startswith("replaced "))
        return f", written to {display_path(result.description)}{replaced}"
    if out_dir:
        files = plural(result.summary["files_written"], "file")
        return f", {files} written to {display_path(out_dir)}"
    return ""


def run_mesh_command(
    command: str,
    inputs: Sequence[str],
    robot: bool,
    destinations: tuple[str | None, str | None, str | None, str | None],
    run: Callable[..., Any],
    rebuild: Callable[..., Any],
    **options: Any,
) -> Any:
    """Run ``hull`` or ``fit``: ``rebuild`` for one robot description with ``--out-dir``,
    else ``run`` on the inputs, with the command's progress display and ``options``.
    ``destinations`` are ``(-o, --out-dir, --to, --report)``."""
    output, out_dir, to, report = destinations
    progress = Progress(command=command, heartbeat=True)
    with several_bodies_need_a_scene_file():
        try:
            if robot:
                assert out_dir is not None
                reserved = (("the --report file", report),) if report not in (None, "-") else ()
                if to == "gltf-physics":
                    from meshcol.analysis.gltf_rebuild import rebuild_gltf

                    return rebuild_gltf(
                        inputs[0], out_dir, run, reserved=reserved, progress=progress, **options
                    )
                return rebuild(
                    inputs[0], out_dir, to=to, reserved=reserved, progress=progress, **options
                )
            return run(
                list(inputs),
                output=output,
                out_dir=out_dir,
                reserved=[("--report", report)],
                progress=progress,
                **options,
            )
        finally:
            progress.done()


def urdf_capsules_option(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Add ``--urdf-capsules standard|extension`` (parameter ``urdf_capsules``, None when
    not given): how a URDF written holds a capsule (:data:`meshcol.vocabulary.URDF_CAPSULES`)."""
    return click.option(
        "--urdf-capsules",
        type=click.Choice(URDF_CAPSULES),
        default=None,
        help="A URDF written (--to urdf): each capsule as a <cylinder> and two <sphere>s, "
        "the same solid in elements every URDF reader knows (standard), or as one "
        "<capsule>, which only pybullet and MuJoCo read (extension).  [default: standard]",
    )(fn)


def urdf_capsules_of(value: str | None, inputs: Sequence[str], robot: bool, to: str | None) -> str:
    """The ``--urdf-capsules`` form of the run (``standard`` when not given); a usage error
    when it is given and no URDF is written (not one URDF input with --out-dir and --to urdf,
    the default for a URDF)."""
    if value is None:
        return "standard"
    if robot and to in (None, "urdf"):
        from meshcol.io.robot import description_kind

        if description_kind(inputs[0]) == "urdf":
            return value
    raise click.UsageError(
        "--urdf-capsules applies to a URDF written: one URDF input, --out-dir and --to urdf"
    )
