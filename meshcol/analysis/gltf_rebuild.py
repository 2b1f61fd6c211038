"""``meshcol hull|fit ASSET.glb --out-dir OUT --to gltf-physics``: the command's colliders
written back into a copy of the asset (:mod:`meshcol.io.gltf_physics_write`), so the asset
and its colliders stay one file.

``hull``: one convex part per body (its hull, within the command's budget or target);
``fit``: the chosen primitive per body (exact), or its hull when ``auto`` kept the hull;
``decompose``: each body's convex parts as the run wrote them (``OUT/<body>_NN.obj``, world
frame; its cache, jobs and target apply as to any run), read back and written into the asset.

An asset that already has colliders (a re-run on what ``--to gltf-physics`` wrote, or an
engine's export) is read as its render meshes (its physics ignored), and its colliders are
replaced by the new ones; the report says what was replaced (``warnings``; decompose's
``settings["replaced"]``).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from typing import Any

from meshcol.errors import MeshcolError

__all__ = ["GLTF_EXTENSIONS", "decompose_gltf", "is_gltf", "node_colliders", "rebuild_gltf"]

#: What ``--to gltf-physics`` takes.
GLTF_EXTENSIONS = (".glb", ".gltf")


def is_gltf(path: str | os.PathLike[str]) -> bool:
    """True for a ``.glb`` or ``.gltf`` path."""
    return os.path.splitext(os.fspath(path))[1].lower() in GLTF_EXTENSIONS


def node_colliders(result: Any) -> list[Any]:
    """Each body's colliders (world frame) from a ``hull`` or ``fit`` report."""
    from meshcol.io.gltf_physics_write import NodeColliders

    out = []
    names = [row["name"] for row in result.bodies]
    if hasattr(result, "hulls"):
        for name, hull in zip(names, result.hulls):
            out.append(NodeColliders(name, (("mesh", hull.vertices, hull.faces),)))
        return out
    for name, fits in zip(names, result.fits):
        chosen = fits.primitive_fit
        if chosen is None:
            part = ("mesh", fits.hull_vertices, fits.hull_faces)
        else:
            part = ("primitive", chosen.primitive, chosen.pose)
        out.append(NodeColliders(name, (part,)))
    return out


def rebuild_gltf(
    path: str,
    out_dir: str,
    run: Callable[..., Any],
    *,
    reserved: Sequence[tuple[str, str | None]] = (),
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> Any:
    """Run ``run`` (:func:`meshcol.analysis.hull.hull` or :func:`meshcol.analysis.fit.fit`)
    on the asset and write ``OUT/<stem>.glb`` with its colliders.

    Returns
    -------
    The command's report, ``description`` the GLB written and ``to`` ``"gltf-physics"``.

    Raises
    ------
    MeshcolError
        The input is not glTF/GLB, the output would replace an input or a reserved file,
        or the asset cannot take the colliders (see
        :func:`meshcol.io.gltf_physics_write.write_gltf_physics`).
    """
    from meshcol.io.gltf_physics import render_meshes_only
    from meshcol.io.gltf_physics_write import gltf_physics_path, write_gltf_physics
    from meshcol.io.outputs import check_outputs

    if not is_gltf(path):
        raise MeshcolError("--to gltf-physics needs a glTF or GLB asset", path)
    target = gltf_physics_path(path, out_dir)
    os.makedirs(out_dir, exist_ok=True)
    check_outputs(
        files={"the asset written": target, **dict(reserved)},
        inputs=[path],
    )
    with render_meshes_only():
        result = run(
            [path], output=None, out_dir=None, reserved=reserved, progress=progress, **options
        )
    replaced = write_gltf_physics(path, node_colliders(result), target)
    warnings = (*result.warnings, replaced) if replaced else result.warnings
    return dataclasses.replace(result, description=target, to="gltf-physics", warnings=warnings)


def decompose_gltf(path: str, out_dir: str, options: Any, run: Any, **kwargs: Any) -> Any:
    """``meshcol decompose ASSET.glb --out-dir OUT --to gltf-physics``: the run over the asset
    (:func:`meshcol.decomposition.batch.decompose_files`, its parts in ``OUT``), then
    ``OUT/<stem>.glb`` with each body's parts.

    Returns
    -------
    DecomposeReport
        The run's report, ``settings`` naming the GLB (``description``) and ``to``.
    """
    from meshcol.decomposition.batch import decompose_files
    from meshcol.io.gltf_physics import render_meshes_only
    from meshcol.io.gltf_physics_write import (
        NodeColliders,
        gltf_physics_path,
        write_gltf_physics,
    )
    from meshcol.io.mesh_read import load_mesh
    from meshcol.io.staging import written_path

    if not is_gltf(path):
        raise MeshcolError("--to gltf-physics needs a glTF or GLB asset", path)
    target = gltf_physics_path(path, out_dir)
    with render_meshes_only():
        report = decompose_files([path], out_dir, options, run, layout="parts", fmt="obj", **kwargs)
    colliders = []
    for entry in report.files:
        if entry["status"] != "ok":
            raise MeshcolError(f"decomposition {entry['status']}: {entry['message']}", path)
        for body in entry["bodies"]:
            parts = []
            for output in body["outputs"]:
                written = written_path(os.path.join(out_dir, os.path.basename(output)))
                (part,) = load_mesh(written, merge=False)
                parts.append(("mesh", part.world_vertices(), part.faces))
            colliders.append(NodeColliders(body["name"], tuple(parts)))
    replaced = write_gltf_physics(path, colliders, target)
    report.settings.update(description=target, to="gltf-physics")
    if replaced:
        report.settings["replaced"] = replaced
    return report
