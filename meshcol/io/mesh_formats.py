"""The mesh file formats meshcol reads: one registry from a file extension to its reader.

Each :class:`MeshFormat` says how a format is read and the conventions it carries: the core's
parallel reader (OBJ, STL) or a Python reader that returns the file's mesh nodes, what an
unnamed object is called, the units it returns and what it needs installed.
:func:`meshcol.io.mesh_read.load_mesh` and ``load_meshes`` look a file up here and nowhere
else; so do the manifests, the robot loaders and the fuzz target.

Adding a format is one module with a reader (``read(file, source) -> list[MeshNode]``, see
:data:`MeshNode`; corrupt content raises :class:`meshcol.errors.InvalidMeshError` worded
``cannot parse <NAME> file: ...``) and one entry in :data:`FORMATS` (ARCHITECTURE.md, "Add a
mesh format").
"""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from meshcol.errors import InputFileError, MeshcolError, MissingDependencyError
from meshcol.io import dae, fbx, gltf, gltf_physics, mesh_trimesh, off, usd_read
from meshcol.io.physics_bodies import FileScene
from meshcol.io.safe_read import check_input

__all__ = [
    "FORMATS",
    "MESH_EXTENSIONS",
    "MeshFormat",
    "MeshNode",
    "check_file",
    "declared_units",
    "format_notes",
    "mesh_format",
    "read_natively",
]

#: One mesh node of a file: ``(name, matrix, vertices, faces, ancestors)``; ``matrix`` (4, 4)
#: is the node's world transform (scale, shear and mirror allowed: the loader splits them off),
#: ``vertices`` (n, 3) and ``faces`` (m, 3) array-likes in the node's frame, ``ancestors`` the
#: names of the nodes above it from the root down (empty: at the root, or a format without a
#: hierarchy), which tell apart nodes of one name (:mod:`meshcol.io.body_names`).
MeshNode = tuple[str, np.ndarray, object, object, tuple[str, ...]]


@dataclass(frozen=True)
class MeshFormat:
    """How one mesh file format is read.

    Attributes
    ----------
    name : str
        The format's name (``"off"``); messages say ``cannot parse OFF file``.
    extensions : tuple of str
        Its file extensions, lower case with the dot.
    read : callable or None
        ``read(file: Path, source: str) -> list[MeshNode]``: every mesh node of the file, in
        file order (none: no faces). None for a format the core reads.
    native : int or None
        The core's reader (``read_mesh_files``' format code): read in parallel, merged by
        the core.
    unnamed : str or None
        The name of an object the file leaves unnamed, in a file of several (OBJ:
        ``default``); None: the file's stem.
    requires : tuple of str or None
        ``(module, install hint)``: a module the reader needs, checked before reading.
    units : str or None
        The length unit the reader returns vertices in, whatever the file's own (FBX: ``m``,
        converted from its ``UnitScaleFactor``; COLLADA: ``m``, from its ``<unit meter>``):
        reported in the envelope's ``units`` when every input says the same. None: the format
        does not say.
    godot_hints : bool
        Node names may end in Godot's import hints (``-col``, ``-convcol``, ``-colonly``,
        ``-convcolonly``, ``-rigid``: :mod:`meshcol.io.collision_names`), as in the glTF and
        FBX scenes Godot imports: the loader cuts the hint from the body's name and makes it
        the body's collider kind.
    notes : callable or None
        ``notes(file, source) -> list[str]``: what the file holds that the reader leaves out
        (FBX: materials, skins, cameras, lights, animation), one short phrase each, for
        reports' warnings (:func:`format_notes`).
    scene : callable or None
        ``scene(file: Path, source: str) -> FileScene | None``: for a file that is a scene
        of its own (USD, glTF with physics extensions: bodies with their colliders and exact
        primitives, excluded pairs, units, warnings; :mod:`meshcol.io.physics_bodies`),
        read instead of ``read``; None from it: nothing beyond ``read``'s nodes.
    """

    name: str
    extensions: tuple[str, ...]
    read: Callable[[Path, str], list] | None = None
    native: int | None = None
    unnamed: str | None = None
    requires: tuple[str, str] | None = None
    units: str | None = None
    godot_hints: bool = False
    notes: Callable[[Path, str], list[str]] | None = None
    scene: Callable[[Path, str], FileScene | None] | None = None


#: Every format, in the order messages list their extensions.
FORMATS: tuple[MeshFormat, ...] = (
    MeshFormat("obj", (".obj",), native=0, unnamed="default"),
    MeshFormat("stl", (".stl",), native=1),
    MeshFormat("ply", (".ply",), read=mesh_trimesh.read_ply),
    MeshFormat("off", (".off",), read=off.read_off_file),
    MeshFormat(
        "glb", (".glb",), read=gltf.read_glb, scene=gltf_physics.read_glb_scene, godot_hints=True
    ),
    MeshFormat(
        "gltf",
        (".gltf",),
        read=gltf.read_gltf,
        scene=gltf_physics.read_gltf_scene,
        godot_hints=True,
    ),
    MeshFormat(
        "fbx",
        (".fbx",),
        read=fbx.read_fbx,
        requires=("ufbx", "reading FBX (.fbx) needs ufbx: pip install 'meshcol[fbx]'"),
        units=fbx.UNITS,
        godot_hints=True,
        notes=fbx.ignored,
    ),
    MeshFormat(
        "dae",
        (".dae",),
        read=dae.read_dae,
        requires=(
            "collada",  # pycollada
            "reading COLLADA (.dae) needs pycollada: pip install 'meshcol[robots]'",
        ),
        units=dae.UNITS,
    ),
    MeshFormat(
        "usd",
        usd_read.USD_EXTENSIONS,
        scene=usd_read.read_usd_scene,
        requires=("pxr", "reading USD needs usd-core: pip install 'meshcol[usd]'"),
    ),
)

_BY_EXTENSION = {extension: fmt for fmt in FORMATS for extension in fmt.extensions}

#: File extensions (lower case) that :func:`meshcol.io.mesh_read.load_mesh` reads, mapped to
#: the format's name.
MESH_EXTENSIONS: dict[str, str] = {ext: fmt.name for fmt in FORMATS for ext in fmt.extensions}


def mesh_format(source: str) -> MeshFormat:
    """The format of ``source`` by its extension (InputFileError when unknown)."""
    fmt = _BY_EXTENSION.get(os.path.splitext(source)[1].lower())
    if fmt is None:
        known = ", ".join(MESH_EXTENSIONS)
        suffix = os.path.splitext(source)[1] or "(none)"
        raise InputFileError(f"unknown mesh file extension {suffix!r} (expected {known})", source)
    return fmt


def declared_units(sources: Sequence[str | os.PathLike[str]]) -> str | None:
    """The units every one of ``sources`` is read in (:attr:`MeshFormat.units`), or None
    when one format does not say, two differ, or there are none."""
    units = {
        fmt.units if fmt is not None else None
        for fmt in (_BY_EXTENSION.get(os.path.splitext(os.fspath(s))[1].lower()) for s in sources)
    }
    return units.pop() if len(units) == 1 else None


def format_notes(sources: Sequence[str | os.PathLike[str]]) -> list[str]:
    """One warning per file of ``sources`` whose reader left content out
    (:attr:`MeshFormat.notes`): ``level.fbx: not read (geometry only): 1 material, 1
    camera``. A file that cannot be read gets none (its error is said elsewhere)."""
    out = []
    for path in sources:
        source = os.fspath(path)
        fmt = _BY_EXTENSION.get(os.path.splitext(source)[1].lower())
        if fmt is None or fmt.notes is None:
            continue
        try:
            left_out = fmt.notes(Path(source), source)
        except MeshcolError:
            continue
        if left_out:
            out.append(f"{source}: not read (geometry only): {', '.join(left_out)}")
    return out


def read_natively(source: str) -> bool:
    """True when the core reads ``source`` (by its extension): it can go in the one parallel
    call of :func:`meshcol.io.mesh_read.load_meshes`."""
    fmt = _BY_EXTENSION.get(os.path.splitext(source)[1].lower())
    return fmt is not None and fmt.native is not None


def check_file(source: str) -> MeshFormat:
    """The format of ``source``, once it is known to be a readable file: missing, a directory,
    an unknown extension, a missing dependency or an unreadable file raise, in that order."""
    file = Path(source)
    if not file.exists():  # says which: not found, a link that dangles or loops
        check_input(source, "mesh")
    if file.is_dir():
        raise InputFileError("is a directory, not a mesh file", source)
    fmt = mesh_format(source)
    if fmt.requires is not None:
        module, hint = fmt.requires
        if importlib.util.find_spec(module) is None:
            raise MissingDependencyError(hint, source)
    check_input(source, "mesh")  # a regular file within the cap, never a pipe or a device
    return fmt
