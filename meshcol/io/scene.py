"""Scene manifests (JSON or TOML) and the inputs of every command.

A manifest lists rigid bodies, each a mesh file or an analytic primitive, with a pose and an
optional end pose for continuous collision. Its structure is the JSON Schema shipped as
``meshcol/schemas/scene.schema.json`` (every field is described there); manifests are
validated against it and every problem becomes one :class:`meshcol.errors.SceneError` line
naming the manifest, the body and the field.

Loading a manifest is a list of stages, each in its module: read the text
(:mod:`meshcol.io.scene_parse`), validate it (:mod:`meshcol.io.scene_validate`; the common
manifest column by column, :mod:`meshcol.io.scene_columns`), read its mesh files once, build
its common bodies in bulk, then the others one by one (:mod:`meshcol.io.scene_bodies`). A
manifest of static primitives only stays columns (:mod:`meshcol.io.scene_primitives`). A plain
JSON manifest of static mesh and primitive bodies is read natively, straight into those columns
(:mod:`meshcol.io.scene_native`), and needs no document when every body is built from them.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from meshcol.errors import InputFileError, MeshcolError, SceneError
from meshcol.io.inputs import input_kind, is_robot_file
from meshcol.io.mesh_formats import declared_units
from meshcol.io.mesh_read import load_mesh
from meshcol.io.paths import confine_all, joined_paths
from meshcol.io.robot import RobotOptions, load_robot
from meshcol.io.scene_bodies import (
    build_bodies,
    read_mesh_files,
    rotation_from_euler,
    rotation_from_quaternion,
)
from meshcol.io.scene_columns import bulk_bodies, manifest_meshes, primitive_bodies
from meshcol.io.scene_native import native_manifest, native_scene
from meshcol.io.scene_parse import collector_paused, read_document
from meshcol.io.scene_schema import SCHEMA_PATH
from meshcol.io.scene_validate import (
    check_magnitudes,
    check_nesting,
    document_columns,
    validate,
)
from meshcol.types import Body, Scene, unique_name

__all__ = [
    "SCHEMA_PATH",
    "is_scene_file",
    "iter_inputs",
    "load_inputs",
    "as_scene",
    "collector_paused",
    "load_scene",
    "manifest_mesh_files",
    "rotation_from_euler",
    "rotation_from_quaternion",
]


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Load a scene manifest (``.json`` or ``.toml``).

    Parameters
    ----------
    path : str or path-like
        The manifest. Mesh paths inside it are relative to its folder.

    Returns
    -------
    Scene
        One body per manifest entry, in manifest order: a mesh file with several objects
        (OBJ objects or groups, glTF mesh nodes, STL solids) gives one body whose ``parts``
        are those objects, in file order; the manifest's ``units`` and ``duration``,
        ``source = path``.

    Raises
    ------
    InputFileError
        The manifest is missing, unreadable, a directory, or not ``.json``/``.toml``.
    SceneError
        Malformed manifest, schema violation, duplicate name, missing or broken mesh file.
        One line: ``scene.json: body 'ball': position must be an array of 3 numbers``.

    Notes
    -----
    A body's world pose is ``T = [R | p]`` from ``rotation`` and ``position``; its ``scale``
    ``S`` and any transform ``L`` the mesh file gives an object are combined as ``T S L``. For
    a file of one object, ``S L`` is split into a rigid transform and a part baked into the
    vertices (see :func:`meshcol.io.mesh_read.split_rigid`); for a body of several parts, each
    part's ``S L`` is baked into its vertices and the body's pose is ``T``. Either way every
    ``Body.pose`` is rigid.
    """
    with collector_paused():
        return _load_scene(os.fspath(path))


def _load_scene(source: str) -> Scene:
    native = native_scene(source)  # a plain JSON manifest, read natively
    if native is not None and native.scene is not None:
        return native.scene
    document, text = read_document(source)
    columns = validate(document, text, source)  # None: the manifest takes the body-by-body path
    check_magnitudes(document, source, columns)
    units, duration = document.get("units"), document.get("duration")
    primitives = primitive_bodies(columns, source) if columns is not None else None
    if primitives is not None:  # every body a static primitive: columns, no object per body
        return Scene(bodies=primitives, units=units, source=source, duration=duration)
    if native is not None and native.files is not None:  # read natively, bodies left over
        files, bulk = native.files, native.bulk  # what the next two lines make of it
    else:
        files = read_mesh_files(document, source)  # each mesh file read once, all in parallel
        # The common bodies (static, unscaled, one object each) built together; every other
        # body, and every body whose checks might fail, one by one in order, so errors come
        # as before.
        bulk = bulk_bodies(columns, source, files) if columns is not None else None
    bodies = build_bodies(document, source, files, bulk)
    return Scene(bodies=tuple(bodies), units=units, source=source, duration=duration)


def as_scene(inputs: Any, robot_options: RobotOptions | None = None) -> Scene:
    """A scene from what the library's analyses accept: a Scene, a Body, a sequence of
    Bodies, or input paths (:func:`load_inputs`; a single mesh file becomes the source).

    Parameters
    ----------
    inputs : Scene, Body, sequence of Body, path or sequence of paths
    robot_options : RobotOptions, optional
        How a robot description among the paths is read.

    Returns
    -------
    Scene
    """
    if isinstance(inputs, Scene):
        return inputs
    if isinstance(inputs, Body):
        return Scene(bodies=(inputs,))
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    inputs = list(inputs)
    if inputs and all(isinstance(b, Body) for b in inputs):
        return Scene(bodies=tuple(inputs))
    scene = load_inputs(inputs, robot_options=robot_options)
    if scene.source is None and len(inputs) == 1:
        scene = dataclasses.replace(scene, source=os.fspath(inputs[0]))
    return scene


def load_inputs(
    paths: Sequence[str | os.PathLike[str]], robot_options: RobotOptions | None = None
) -> Scene:
    """Turn a command's input paths into one scene.

    Parameters
    ----------
    paths : sequence of str or path-like
        Either one scene manifest, one robot description (URDF or MJCF,
        :func:`meshcol.io.robot.load_robot`), or any number of mesh and glTF/GLB scene
        files.
    robot_options : RobotOptions, optional
        How a robot description is read (joint values, packages, SRDF, adjacency); nothing
        for other inputs.

    Returns
    -------
    Scene
        The manifest's scene (one body per manifest entry, its file's objects as its
        parts); the robot's (one body per link with collision geometry); or, for mesh and glTF/GLB files given directly, one body per object of every
        file, in order (``<stem>/<object>`` when a file holds several). A name that clashes
        with an earlier body's gets ``#2``, ``#3``... appended. ``source`` is the input path when
        there is exactly one, else None; ``units`` without a manifest: what every mesh file's
        format converts to (FBX: ``m``), else None.

    Raises
    ------
    InputFileError
        No inputs, or a file that cannot be read (see :func:`meshcol.io.mesh_read.load_mesh`).
    SceneError
        A manifest given together with other inputs, or a malformed manifest.
    InvalidMeshError
        A mesh file with unusable content.
    """
    manifest = _single_manifest(paths)
    if manifest is not None:
        if is_robot_file(manifest):
            return load_robot(manifest, robot_options)
        return load_scene(manifest)
    source = os.fspath(paths[0]) if len(paths) == 1 else None
    if any(is_scene_file(path) for path in paths):
        return _file_scenes(paths, source)
    bodies = [body for _, file_bodies in iter_inputs(paths) for body in file_bodies]
    return Scene(bodies=tuple(bodies), units=declared_units(paths), source=source)


def is_scene_file(path: str | os.PathLike[str]) -> bool:
    """True for a mesh file whose format reads it as a scene of its own (USD: excluded pairs,
    units, warnings beside the bodies; ``MeshFormat.scene``)."""
    from meshcol.io.mesh_formats import mesh_format

    try:
        return mesh_format(os.fspath(path)).scene is not None
    except InputFileError:
        return False


def _file_scenes(paths: Sequence[str | os.PathLike[str]], source: str | None) -> Scene:
    """Mesh files of which some are scenes of their own: every file's bodies named as
    :func:`load_inputs` names them, the files' excluded pairs (renamed with their bodies),
    their warnings, and their units when every file declares the same."""
    from meshcol.io.mesh_read import load_file_scene

    used: dict[str, int] = {}
    bodies: list[Body] = []
    pairs: list[tuple[str, str, str]] = []
    warnings: list[str] = []
    units: set[str | None] = set()
    for path in paths:
        scene = load_file_scene(path)
        if scene is None:
            scene = Scene(bodies=tuple(load_mesh(path)), units=declared_units([path]))
        renamed: dict[str, str] = {}
        for body in scene.bodies:
            renamed[body.name] = name = unique_name(body.name, used)
            bodies.append(body if name == body.name else dataclasses.replace(body, name=name))
        for a, b, reason in scene.excluded_pairs:
            a, b = sorted((renamed[a], renamed[b]))
            pairs.append((a, b, reason))
        prefix = "" if len(paths) == 1 else f"{os.fspath(path)}: "
        warnings.extend(prefix + warning for warning in scene.warnings)
        units.add(scene.units)
    return Scene(
        bodies=tuple(bodies),
        units=units.pop() if len(units) == 1 else None,
        source=source,
        excluded_pairs=tuple(pairs),
        warnings=tuple(warnings),
    )


def _single_manifest(paths: Sequence[str | os.PathLike[str]]) -> str | os.PathLike[str] | None:
    """The manifest or robot description among ``paths`` (it must come alone), or None."""
    if len(paths) == 0:
        raise InputFileError("no input files given")
    manifests = [p for p in paths if input_kind(p) != "mesh"]
    if manifests and len(paths) > 1:
        what = "a robot description" if is_robot_file(manifests[0]) else "a scene manifest"
        raise SceneError(
            f"{what} cannot be combined with other inputs: give it alone", manifests[0]
        )
    return manifests[0] if manifests else None


def iter_inputs(
    paths: Sequence[str | os.PathLike[str]],
    on_error: Callable[[str, MeshcolError], None] | None = None,
    robot_options: RobotOptions | None = None,
) -> Iterator[tuple[str, list[Body]]]:
    """:func:`load_inputs` one file at a time: ``(file, its bodies)`` as each file is read.

    The same bodies, names and errors as :func:`load_inputs`, but a caller can start work on
    the first file while the next is read (``meshcol decompose``). A manifest is read whole
    and its bodies come grouped by mesh file (primitives under the manifest's path), in order
    of first appearance.

    ``on_error(path, error)``, when given, receives each mesh file that cannot be read and the
    others are still yielded (``meshcol inspect`` keeps going); a manifest is read whole, so
    its errors are raised whatever ``on_error`` is. ``robot_options``: as
    :func:`load_inputs`.
    """
    manifest = _single_manifest(paths)
    if manifest is not None:
        robot = is_robot_file(manifest)
        scene = load_robot(manifest, robot_options) if robot else load_scene(manifest)
        groups: dict[str, list[Body]] = {}
        for body in scene.bodies:
            groups.setdefault(body.source or scene.source or body.name, []).append(body)
        yield from groups.items()
        return
    used: dict[str, int] = {}
    for path in paths:
        bodies: list[Body] = []
        try:
            loaded = load_mesh(path)
        except MeshcolError as error:
            if on_error is None:
                raise
            on_error(os.fspath(path), error)
            continue
        for body in loaded:
            name = unique_name(body.name, used)
            bodies.append(body if name == body.name else dataclasses.replace(body, name=name))
        yield os.fspath(path), bodies


def manifest_mesh_files(path: str | os.PathLike[str]) -> list[str]:
    """The mesh files a manifest refers to (relative to its folder), without loading them.

    Returns
    -------
    list of str
        In manifest order, each once; empty when the manifest cannot be read or parsed (then
        :func:`load_scene` reports why).
    """
    source = os.fspath(path)
    native = native_manifest(source)
    if native is not None:  # read natively: the column of names, without the document
        names = manifest_meshes(native.columns)
    else:
        try:
            document, text = read_document(source)
            check_nesting(document, text, source)
        except MeshcolError:
            return []
        names = _document_meshes(document)
    paths = joined_paths(os.path.dirname(source), names)
    return list(dict.fromkeys(confine_all(paths, source, names)))


def _document_meshes(document: Any) -> list[str]:
    """The mesh names of a decoded manifest, valid or not, each once, in order."""
    found = document_columns(document)
    if found is not None:  # valid: the column of names, without a loop over the bodies
        return manifest_meshes(found)
    bodies = document.get("bodies") if isinstance(document, dict) else None
    meshes: dict[str, None] = {}
    for spec in bodies if isinstance(bodies, list) else []:
        mesh = spec.get("mesh") if isinstance(spec, dict) else None
        if isinstance(mesh, str) and mesh:
            meshes[mesh] = None
    return list(meshes)
