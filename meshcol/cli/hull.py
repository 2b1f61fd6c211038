"""``meshcol hull``: convex hulls, optionally within an engine's vertex budget."""

from __future__ import annotations

import os
import re
from pathlib import Path

import click

from meshcol._version import __version__
from meshcol.cli.common import report_options
from meshcol.io.report import atomic_path, dumps_csv, dumps_json, emit, report_format

#: Mesh formats the hull can be written in (by output extension).
OUTPUT_EXTENSIONS = (".obj", ".stl", ".ply", ".off", ".glb")
#: Output formats that hold several named meshes in one file.
MULTI_BODY_EXTENSIONS = (".obj", ".glb")
#: Decimal places of OBJ coordinates: enough to round-trip float64 for meshes of any
#: practical size, so a written hull still encloses its input.
OBJ_DIGITS = 16
SCHEMA_VERSION = 1
CSV_COLUMNS = (
    "name", "source", "input_vertices", "input_faces", "hull_vertices", "hull_faces",
    "hull_volume", "hull_area", "mesh_volume", "volume_ratio", "flat", "max_vertices",
    "exact_hull_vertices", "exact_hull_faces", "exact_hull_volume", "added_volume",
    "added_volume_fraction", "max_distance", "output",
)


@click.command("hull", context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option("-o", "--output", "output", metavar="FILE",
              help="Write the hull(s) to FILE (format from the extension: .obj .stl .ply .off "
                   ".glb). Several bodies need .obj or .glb (one named object each).")
@click.option("--out-dir", metavar="DIR",
              help="Write one DIR/<body>.obj per body ('/' in names becomes '_').")
@click.option("--max-vertices", type=click.IntRange(min=4), metavar="N",
              help="At most N vertices per hull (PhysX: 255, GPU pipelines: 64), still "
                   "enclosing the input.")
@report_options(default="stdout when no mesh is written, else no report")
def hull(inputs: tuple[str, ...], output: str | None, out_dir: str | None,
         max_vertices: int | None, report: str | None, fmt: str | None) -> None:
    """Convex hull of each body, optionally within a vertex budget.

    INPUT is mesh files (OBJ, STL, PLY, OFF, glTF, GLB; every object, solid or mesh node is
    a body) or one scene manifest. Hulls are in the WORLD frame: each body's scene transform
    is applied, so exported colliders sit in place over the input.

    With --max-vertices the hull keeps at most N vertices and still contains every input
    vertex: its faces are grown outward (never pulled in), and the report gives the volume
    this added and the largest distance from the simplified hull to the exact one.

    The report (JSON or CSV, one row per body) gives the input and hull sizes, the hull
    volume, the mesh volume (closed meshes only, else null), volume_ratio = mesh volume /
    hull volume (1 for a convex mesh) and, with a budget, added_volume,
    added_volume_fraction and max_distance. Coplanar input gives a flat 2-D hull (a
    warning on stderr, flat: true, volume 0); collinear or single-point input has no hull
    and exits 2.

    \b
    Examples:
      meshcol hull chair.obj                          report on stdout
      meshcol hull chair.obj --max-vertices 64 -o chair_hull.obj
      meshcol hull props/*.obj --max-vertices 255 --out-dir hulls --report hulls.csv
      meshcol hull level.json -o level_hulls.glb --report -
    """
    if output and out_dir:
        raise click.UsageError("give either -o/--output or --out-dir, not both")
    if output:
        extension = os.path.splitext(output)[1].lower()
        if extension not in OUTPUT_EXTENSIONS:
            raise click.BadParameter(
                f"unknown mesh extension {extension or '(none)'!r} in {output!r} "
                f"(expected {', '.join(OUTPUT_EXTENSIONS)})", param_hint="'-o' / '--output'")

    from meshcol.errors import InvalidMeshError
    from meshcol.geometry.hull import convex_hull
    from meshcol.geometry.topology import closed_volume
    from meshcol.io.scene import load_inputs

    scene = load_inputs(list(inputs))
    bodies = scene.bodies
    if output and len(bodies) > 1 and os.path.splitext(output)[1].lower() not in MULTI_BODY_EXTENSIONS:
        raise click.UsageError(
            f"-o {output}: {len(bodies)} bodies need a file that holds several meshes "
            f"({', '.join(MULTI_BODY_EXTENSIONS)}) or --out-dir")

    # compute everything first: a bad body stops the run before any file is written
    hulls = []
    for body in bodies:
        try:
            result = convex_hull(body.world_vertices(), max_vertices=max_vertices)
        except InvalidMeshError as exc:
            raise InvalidMeshError(f"body '{body.name}': {exc.message}", body.source) from exc
        if result.flat:
            click.echo(f"meshcol: warning: {body.source}: body '{body.name}' is flat: "
                       "the hull is a 2-D polygon", err=True)
        hulls.append(result)

    destinations: list[str | None] = [None] * len(bodies)
    if output:
        _write_meshes(output, [b.name for b in bodies], hulls)
        destinations = [output] * len(bodies)
    elif out_dir:
        destinations = _out_dir_paths(out_dir, [b.name for b in bodies])
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        for name, path, result in zip([b.name for b in bodies], destinations, hulls):
            _write_meshes(path, [name], [result])

    rows = [_row(body, result, closed_volume(body.vertices, body.faces), destination)
            for body, result, destination in zip(bodies, hulls, destinations)]
    if report is None and (output or out_dir):
        return
    kind = report_format(report, fmt)
    if kind == "csv":
        text = dumps_csv(rows, CSV_COLUMNS)
    else:
        text = dumps_json({
            "schema_version": SCHEMA_VERSION,
            "tool": {"name": "meshcol", "version": __version__},
            "command": "hull",
            "settings": {"max_vertices": max_vertices, "frame": "world",
                         "output": output, "out_dir": out_dir},
            "units": scene.units,
            "bodies": rows,
        })
    emit(text, report)


def _row(body, result, mesh_volume: float | None, destination: str | None) -> dict:
    budget = result.max_vertices is not None
    ratio = None
    if mesh_volume is not None and result.volume > 0:
        ratio = abs(mesh_volume) / result.volume
    return {
        "name": body.name,
        "source": body.source,
        "input_vertices": int(len(body.vertices)),
        "input_faces": int(len(body.faces)),
        "hull_vertices": int(len(result.vertices)),
        "hull_faces": int(len(result.faces)),
        "hull_volume": result.volume,
        "hull_area": result.area,
        "mesh_volume": mesh_volume,
        "volume_ratio": ratio,
        "flat": result.flat,
        "note": "coplanar input: the hull is a 2-D polygon (volume 0)" if result.flat else None,
        "max_vertices": result.max_vertices,
        "exact_hull_vertices": result.exact_vertex_count,
        "exact_hull_faces": result.exact_face_count,
        "exact_hull_volume": result.exact_volume,
        "added_volume": result.added_volume if budget else None,
        "added_volume_fraction": result.added_volume_fraction if budget else None,
        "max_distance": result.max_distance if budget else None,
        "output": destination,
    }


def _out_dir_paths(out_dir: str, names: list[str]) -> list[str]:
    """``DIR/<name>.obj`` per body, names made file-safe and unique."""
    paths, used = [], set()
    for name in names:
        safe = re.sub(r"[^\w.#=+-]", "_", name).strip(".") or "body"
        candidate, k = safe, 2
        while candidate.lower() in used:
            candidate = f"{safe}-{k}"
            k += 1
        used.add(candidate.lower())
        paths.append(os.path.join(out_dir, candidate + ".obj"))
    return paths


def _write_meshes(path: str, names: list[str], hulls: list) -> None:
    """Write one or several hull meshes to ``path`` atomically (format from its extension)."""
    import trimesh

    meshes = [trimesh.Trimesh(vertices=h.vertices, faces=h.faces, process=False) for h in hulls]
    extension = os.path.splitext(path)[1].lower()
    if len(meshes) == 1 and extension != ".glb":
        target = meshes[0]
    else:
        target = trimesh.Scene()
        for name, mesh in zip(names, meshes):
            target.add_geometry(mesh, geom_name=name, node_name=name)
    with atomic_path(path) as tmp:
        if extension == ".obj":
            data = trimesh.exchange.obj.export_obj(target, include_normals=False,
                                                   include_color=False, include_texture=False,
                                                   write_texture=False, header=None,
                                                   digits=OBJ_DIGITS)
            with open(tmp, "w", encoding="utf-8", newline="\n") as f:
                f.write(data)
        else:
            target.export(tmp, file_type=extension[1:])
