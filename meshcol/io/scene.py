"""Scene manifests (JSON or TOML) and the inputs of every command.

A manifest lists rigid bodies, each a mesh file or an analytic primitive, with a pose and an
optional end pose for continuous collision. Its structure is the JSON Schema shipped as
``meshcol/schemas/scene.schema.json`` (every field is described there); manifests are
validated against it and every problem becomes one :class:`meshcol.errors.SceneError` line
naming the manifest, the body and the field.
"""

from __future__ import annotations

import contextlib
import dataclasses
import gc
import json
import math
import os
import re
import sys
from collections.abc import Callable, Iterator, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import InputFileError, MeshcolError, SceneError
from meshcol.io.mesh_read import MAX_COORDINATE, check_magnitude, load_mesh, split_rigid
from meshcol.io.primitives import primitive_mesh
from meshcol.io.robot import RobotOptions, is_robot_file, load_robot
from meshcol.types import Body, Box, Capsule, Cylinder, Primitive, Scene, Sphere, Spin
from meshcol.vocabulary import MANIFEST_EXTENSIONS, SCENE_SHAPES

__all__ = [
    "MANIFEST_EXTENSIONS",
    "SCHEMA_PATH",
    "iter_inputs",
    "load_inputs",
    "as_scene",
    "collector_paused",
    "load_scene",
    "manifest_mesh_files",
    "unique_name",
    "rotation_from_euler",
    "rotation_from_quaternion",
]


#: The JSON Schema of a manifest.
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schemas" / "scene.schema.json"

# What a wrongly typed field should have been, by field name (the last name in its path).
_EXPECTED = {
    "bodies": "a non-empty array of bodies",
    "units": "a non-empty string",
    "duration": "a positive number (seconds)",
    "name": "a non-empty string",
    "mesh": "a non-empty string (a file path)",
    "primitive": 'an object with a "type" (sphere, box, capsule or cylinder)',
    "type": "one of sphere, box, capsule, cylinder",
    "radius": "a positive number",
    "length": "a positive number",
    "size": "an array of 3 positive numbers",
    "position": "an array of 3 numbers",
    "end_position": "an array of 3 numbers",
    "velocity": "an array of 3 numbers",
    "angular_velocity": "an array of 3 numbers (rad/s)",
    "rotation": '{"quaternion": [w, x, y, z]} or {"euler_deg": [a, b, c], "order": "xyz"}',
    "end_rotation": '{"quaternion": [w, x, y, z]} or {"euler_deg": [a, b, c], "order": "xyz"}',
    "quaternion": "an array of 4 numbers [w, x, y, z]",
    "euler_deg": "an array of 3 numbers (degrees)",
    "order": "a string of three axes such as xyz, zyx or zxz",
    "scale": "a positive number or an array of 3 positive numbers",
    "shape": "one of hull, decomposed, mesh",
}

_AXES = {"x": 0, "y": 1, "z": 2}

#: Deepest nesting of arrays and objects a manifest may have (a real one has four levels).
MAX_NESTING = 32
#: Largest turn, in radians, a body may make over the motion (angular_velocity x duration):
#: 160,000 revolutions; beyond, sin and cos of the angle carry no precision.
MAX_TURN = 1e6


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
        return _load_scene(path)


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector off for the block (back on after, if it was on).

    Decoding and loading a manifest make millions of objects and free none: each collection
    the allocations trigger walks them all for nothing (a 300,000-body manifest decoded in
    3.5 s with it, 1.2-2.1 s without). What they make has no cycles; reference counting frees
    it as before. ``check`` pauses it the same way while it packs colliders and builds its
    report rows (hundreds of thousands of dicts and lists at 100,000 bodies).
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _load_scene(path: str | os.PathLike[str]) -> Scene:
    source = os.fspath(path)
    file = Path(source)
    _check_manifest_file(file, source)
    document = _parse(file, source)
    _validate(document, source)
    columns = _columns_of(document)  # None: the manifest takes the body-by-body path
    _check_magnitudes(document, source, columns)
    units = document.get("units")
    duration = document.get("duration")

    files = _read_mesh_files(document, source)  # each mesh file read once, all in parallel
    # The common bodies (static, unscaled, one object each) built together; every other body,
    # and every body whose checks might fail, one by one in order, so errors come as before.
    bulk = _bulk_bodies(columns, source, files) if columns is not None and files else None
    bodies: list[Body] = []
    names: set[str] = set()
    for index, spec in enumerate(document["bodies"]):
        if bulk is not None:
            body = bulk[index]
            if body is not None:
                bodies.append(body)
                continue
        label = f"body {spec['name']!r}"
        if spec["name"] in names:
            raise SceneError(f"{label}: name used by an earlier body", source)
        names.add(spec["name"])
        if ("mesh" in spec) == ("primitive" in spec):
            raise SceneError(f"{label}: needs exactly one of 'mesh' or 'primitive'", source)
        start = _pose(spec.get("position"), spec.get("rotation"), label, "rotation", source)
        end, spin = _end_pose(spec, start, duration, label, source)
        scale = _scale(spec.get("scale"))
        if "mesh" in spec:
            new = _mesh_bodies(spec, file, source, label, start, end, spin, scale, files)
        else:
            new = [_primitive_body(spec, source, label, start, end, spin, scale)]
        for body in new:
            _check_world(body, label, source)
        bodies.extend(new)
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
        there is exactly one, else None; ``units`` is None without a manifest.

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
    bodies = [body for _, file_bodies in iter_inputs(paths) for body in file_bodies]
    source = os.fspath(paths[0]) if len(paths) == 1 else None
    return Scene(bodies=tuple(bodies), units=None, source=source)


def _single_manifest(paths: Sequence[str | os.PathLike[str]]) -> str | os.PathLike[str] | None:
    """The manifest or robot description among ``paths`` (it must come alone), or None."""
    if len(paths) == 0:
        raise InputFileError("no input files given")
    manifests = [
        p
        for p in paths
        if Path(os.fspath(p)).suffix.lower() in MANIFEST_EXTENSIONS or is_robot_file(p)
    ]
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
    used: set[str] = set()
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


def unique_name(name: str, used: set[str]) -> str:
    """``name``, or ``name#2``, ``name#3``... when taken: the one rule of :func:`load_inputs`
    for bodies of several files, for callers that read files elsewhere (worker processes) and
    name their bodies here, in input order. The name returned is added to ``used``."""
    unique, k = name, 2
    while unique in used:
        unique = f"{name}#{k}"
        k += 1
    used.add(unique)
    return unique


def rotation_from_quaternion(quaternion: Sequence[float]) -> np.ndarray:
    """Rotation matrix of a quaternion ``[w, x, y, z]`` (normalised first).

    Returns
    -------
    (3, 3) float64
        Proper rotation. Raises ValueError for a zero or non-finite quaternion.
    """
    # plain floats: numpy's per-call cost is most of the time for four numbers, and a scene
    # can hold 100,000 rotations
    q = [float(v) for v in quaternion]
    if len(q) != 4:
        raise ValueError("quaternion must have 4 components")
    if not all(math.isfinite(v) for v in q):
        raise ValueError("quaternion must be finite")
    # divide by the largest component first: |q| of a huge quaternion would overflow
    largest = max(abs(v) for v in q)
    if largest == 0.0:
        raise ValueError("quaternion must be non-zero")
    q = [v / largest for v in q]
    norm = math.sqrt(sum(v * v for v in q))
    w, x, y, z = (v / norm for v in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rotation_from_euler(angles_deg: Sequence[float], order: str) -> np.ndarray:
    """Rotation matrix of three extrinsic rotations about the world axes.

    Parameters
    ----------
    angles_deg : (3,) float
        Degrees, one per letter of ``order``.
    order : str
        Three axes from ``xyz`` (e.g. ``"xyz"``, ``"zxz"``), the first applied first.

    Returns
    -------
    (3, 3) float64
        For ``order="xyz"``, ``Rz(c) @ Ry(b) @ Rx(a)``. Extrinsic ``xyz`` equals intrinsic
        ``ZYX`` (scipy: ``Rotation.from_euler("xyz", angles, degrees=True)``).
    """
    if len(order) != 3 or any(axis not in _AXES for axis in order):
        raise ValueError(f"order must be three of x, y, z, got {order!r}")
    matrix = np.eye(3)
    for axis, angle in zip(order, angles_deg):
        matrix = _axis_rotation(_AXES[axis], math.radians(float(angle))) @ matrix
    return matrix


def _axis_rotation(axis: int, angle: float) -> np.ndarray:
    # exact zeros and ones for right angles, so axis-aligned props stay exactly aligned
    c, s = _exact_cos_sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    matrix = np.eye(3)
    matrix[i, i] = c
    matrix[j, j] = c
    matrix[i, j] = -s
    matrix[j, i] = s
    return matrix


def _exact_cos_sin(angle: float) -> tuple[float, float]:
    quarter = angle / (math.pi / 2)
    if quarter == round(quarter):
        return [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][round(quarter) % 4]
    return math.cos(angle), math.sin(angle)


def _rotation(spec: dict | None, label: str, field: str, source: str) -> np.ndarray:
    if spec is None:
        return np.eye(3)
    if "quaternion" in spec:
        try:
            return rotation_from_quaternion(spec["quaternion"])
        except ValueError as error:
            raise SceneError(f"{label}: {field}.{error}", source) from None
    return rotation_from_euler(spec["euler_deg"], spec["order"])


def _pose(position, rotation, label: str, field: str, source: str) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = _rotation(rotation, label, field, source)
    if position is not None:
        matrix[:3, 3] = position
    return matrix


def _end_pose(spec: dict, start: np.ndarray, duration, label: str, source: str):
    """The end pose and, for an angular velocity, the spin: ``(end, spin)``, either None.

    An ``end_rotation`` is reached the shortest way (no spin); an ``angular_velocity`` turns
    the body by ``|w| * duration`` radians, whatever the size (a :class:`Spin`).
    """
    by_pose = "end_position" in spec or "end_rotation" in spec
    by_velocity = "velocity" in spec or "angular_velocity" in spec
    if by_pose and by_velocity:
        raise SceneError(
            f"{label}: give the end pose either as end_position/end_rotation or as "
            "velocity/angular_velocity, not both",
            source,
        )
    if by_pose:
        end = start.copy()
        if "end_rotation" in spec:
            end[:3, :3] = _rotation(spec["end_rotation"], label, "end_rotation", source)
        if "end_position" in spec:
            end[:3, 3] = spec["end_position"]
        return end, None
    if by_velocity:
        if duration is None:
            field = "velocity" if "velocity" in spec else "angular_velocity"
            raise SceneError(f"{label}: {field} needs the manifest's 'duration'", source)
        end = start.copy()
        end[:3, 3] += np.asarray(spec.get("velocity", [0.0, 0.0, 0.0]), dtype=float) * duration
        if "angular_velocity" not in spec:
            return end, None
        turn = np.asarray(spec["angular_velocity"], dtype=float) * duration
        if not np.all(np.isfinite(turn)):
            raise SceneError(f"{label}: angular_velocity * duration is not finite", source)
        spin = Spin(turn)
        end[:3, :3] = spin.matrix() @ start[:3, :3]
        return end, spin
    return None, None


def _sub_spin(spin: Spin | None, start: np.ndarray, end, rigid: np.ndarray) -> Spin | None:
    """A sub-body's spin: the manifest body's turn (the shortest one to an end rotation), about
    the manifest body's origin, where the file places the sub-body's own origin elsewhere; so
    the sub-bodies move as one rigid body."""
    if end is None or not np.any(rigid[:3, 3]):
        return spin
    return Spin(None if spin is None else spin.rotation, pivot=start[:3, 3].copy())


def _scale(value) -> np.ndarray:
    if value is None:
        return np.ones(3)
    if isinstance(value, list):
        return np.asarray(value, dtype=np.float64)
    return np.full(3, float(value))


def _read_mesh_files(document: Any, source: str) -> dict[str, list[Body]]:
    """Every mesh file the manifest names, read at once (OBJ and STL by the core, in parallel),
    keyed by normalised path. Empty when a file fails: the body loop then reads the files one
    by one and reports the first bad one with its body's name."""
    from meshcol.io.mesh_read import load_meshes

    folder = os.path.dirname(source)
    meshes = dict.fromkeys(
        spec["mesh"] for spec in document["bodies"] if isinstance(spec.get("mesh"), str)
    )  # each name once before the path arithmetic: 300,000 bodies may share 16 files
    paths = list(dict.fromkeys(os.path.normpath(os.path.join(folder, m)) for m in meshes))
    try:
        return dict(zip(paths, load_meshes(paths)))
    except MeshcolError:
        return {}


def _mesh_bodies(
    spec, manifest: Path, source, label, start, end, spin, scale, files: dict[str, list[Body]]
) -> list[Body]:
    mesh = spec["mesh"]
    mesh_source = os.path.join(os.path.dirname(source), mesh)
    key = os.path.normpath(mesh_source)
    loaded = files.get(key)
    if loaded is None:
        if not Path(mesh_source).is_file() and not Path(mesh_source).is_dir():
            raise SceneError(f"{label}: mesh file {mesh!r} not found", source)
        try:
            loaded = load_mesh(mesh_source)
        except MeshcolError as error:
            raise SceneError(f"{label}: mesh file {mesh!r}: {error.message}", source) from None
        files[key] = loaded
    if len(loaded) == 1 and not np.any(scale != 1.0) and _is_identity(loaded[0].pose):
        # the common case (one object, no scale, no node transform): nothing to split or bake
        (sub,) = loaded
        rigid = _IDENTITY
        vertices, faces = sub.vertices, sub.faces
        parts: tuple[str, ...] = ()
        part_faces = None
    elif len(loaded) == 1:
        (sub,) = loaded
        rigid, linear = split_rigid(np.diag([*scale, 1.0]) @ sub.pose)
        vertices, faces = sub.vertices, sub.faces
        if linear is not None:
            vertices = vertices @ linear.T
            if np.linalg.det(linear) < 0:
                faces = faces[:, ::-1]
        parts = ()
        part_faces = None
    else:
        # One body of several parts: each part's node transform and the body's scale are
        # baked into its vertices, so the parts share the body's frame and pose.
        rigid = np.eye(4)
        stretch = np.diag([*scale, 1.0])
        blocks_v, blocks_f, counts = [], [], []
        base = 0
        for sub in loaded:
            matrix = stretch @ sub.pose
            part_faces_local = (
                sub.faces[:, ::-1] if np.linalg.det(matrix[:3, :3]) < 0 else sub.faces
            )
            blocks_v.append(sub.vertices @ matrix[:3, :3].T + matrix[:3, 3])
            blocks_f.append(part_faces_local + base)
            counts.append(len(sub.faces))
            base += len(sub.vertices)
        vertices = np.concatenate(blocks_v)
        faces = np.concatenate(blocks_f)
        parts = tuple(sub.name.split("/", 1)[1] for sub in loaded)
        part_faces = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return [
        Body(
            name=spec["name"],
            source=mesh_source,
            vertices=np.ascontiguousarray(vertices),
            faces=np.ascontiguousarray(faces),
            pose=start if rigid is _IDENTITY else start @ rigid,
            end_pose=None if end is None else end if rigid is _IDENTITY else end @ rigid,
            collider=spec.get("shape"),
            parts=parts,
            part_faces=part_faces,
            spin=_sub_spin(spin, start, end, rigid),
        )
    ]


_IDENTITY = np.eye(4)
_IDENTITY.flags.writeable = False


def _is_identity(matrix: np.ndarray) -> bool:
    return matrix is _IDENTITY or bool(np.array_equal(matrix, _IDENTITY))


def _bulk_bodies(columns: _Columns, source: str, files: dict[str, list[Body]]) -> list | None:
    """The manifest's common bodies, built together: index-aligned with its bodies, a Body
    for each static, unscaled mesh body whose file holds one object without a transform and
    whose world coordinates are plainly within the limit; None for the others (built one by
    one). None in all when names repeat (the body loop says which).

    Each body is what the body loop would build, to the bit: the same rotation arithmetic
    (:func:`_quaternion_matrices`, :func:`_euler_matrices`), the same vertex and face arrays
    of its file, the same bound of its world coordinates as :func:`_check_world`.
    """
    names = columns.names
    n = len(names)
    if len(set(names)) != n:
        return None
    folder = os.path.dirname(source)
    # Per mesh name: its path and its one object (None: the body loop builds its bodies), and
    # the reach of _check_world, sqrt(3) max |v|; per file, but in one numpy pass for all.
    meshes = list(dict.fromkeys(m for m in columns.meshes if m is not None))
    paths = [os.path.join(folder, mesh) for mesh in meshes]
    loaded = [files.get(os.path.normpath(path)) for path in paths]
    single = [f is not None and len(f) == 1 for f in loaded]
    ones = [f[0] for f, one in zip(loaded, single) if one]  # type: ignore[index]
    plain = np.zeros(len(meshes), dtype=bool)
    reaches = np.full(len(meshes), math.inf)
    if ones:
        arrays = [np.ascontiguousarray(b.vertices) for b in ones]
        sizes = np.array([len(v) for v in arrays], dtype=np.int64)
        largest = np.zeros(len(ones))
        filled = sizes > 0
        if filled.any():
            # the largest |coordinate| of each object: one reduction over the flat coordinates
            # (a max over rows of 3 first costs more than the rest of this function)
            magnitudes = np.abs(np.concatenate(arrays).reshape(-1))
            starts = np.concatenate([[0], np.cumsum(sizes[filled])[:-1]]) * 3
            largest[filled] = np.maximum.reduceat(magnitudes, starts)
        rows = np.flatnonzero(single)
        plain[rows] = (np.stack([b.pose for b in ones]) == _IDENTITY).all(axis=(1, 2))
        reaches[rows] = largest * math.sqrt(3.0)
    objects: dict[str | None, tuple[str, np.ndarray, np.ndarray] | None] = {None: None}
    reach_of: dict[str | None, float] = {None: math.inf}
    for k, (mesh, path, files_of) in enumerate(zip(meshes, paths, loaded)):
        if plain[k]:
            (sub,) = files_of  # type: ignore[misc]
            objects[mesh] = (
                path,
                np.ascontiguousarray(sub.vertices),
                np.ascontiguousarray(sub.faces),
            )
            reach_of[mesh] = float(reaches[k])
        else:
            objects[mesh], reach_of[mesh] = None, math.inf
    reach = np.array([reach_of[m] for m in columns.meshes]).reshape(n)
    position = columns.vectors.get("position", np.zeros((n, 3)))
    common = ~columns.moving & ~columns.scaled
    common &= reach + np.abs(position).max(axis=1, initial=0.0) <= MAX_COORDINATE

    rotations = np.tile(np.eye(3), (n, 1, 1))
    quaternion = columns.rotation == 1
    if quaternion.any():
        q = columns.quaternion
        nonzero = np.abs(q).max(axis=1) > 0  # a zero quaternion: the body loop says so
        rows = np.flatnonzero(quaternion)
        common[rows[~nonzero]] = False
        rotations[rows[nonzero]] = _quaternion_matrices(q[nonzero])
    euler = columns.rotation == 2
    if euler.any():
        rotations[euler] = _euler_matrices(columns.euler, columns.orders)
    poses = np.zeros((n, 4, 4))
    poses[:, :3, :3] = rotations
    poses[:, :3, 3] = position
    poses[:, 3, 3] = 1.0

    out: list[Body | None] = [None] * n
    shapes = columns.shapes
    for i in np.flatnonzero(common).tolist():
        mesh_source, vertices, faces = objects[columns.meshes[i]]  # type: ignore[misc]
        out[i] = Body(
            name=names[i],
            source=mesh_source,
            vertices=vertices,
            faces=faces,
            pose=poses[i],
            collider=shapes[i],
        )
    return out


def _quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """:func:`rotation_from_quaternion` of each row of ``q`` ((n, 4) float64, finite, none
    zero): (n, 3, 3), by the same operations in the same order, so to the same bits."""
    q = q / np.abs(q).max(axis=1, keepdims=True)
    norm = np.sqrt(q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3])
    w, x, y, z = (q[:, k] / norm for k in range(4))
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - w * z)
    out[:, 0, 2] = 2 * (x * z + w * y)
    out[:, 1, 0] = 2 * (x * y + w * z)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - w * x)
    out[:, 2, 0] = 2 * (x * z - w * y)
    out[:, 2, 1] = 2 * (y * z + w * x)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out


_QUARTER_COS = np.array([1.0, 0.0, -1.0, 0.0])
_QUARTER_SIN = np.array([0.0, 1.0, 0.0, -1.0])


def _euler_matrices(angles_deg: np.ndarray, orders: Sequence[str]) -> np.ndarray:
    """:func:`rotation_from_euler` of each row of ``angles_deg`` ((n, 3) float64) in its
    order: (n, 3, 3), the same axis rotations (math's cos and sin, exact at right angles)
    multiplied in the same order by one stacked matmul per axis, so to the same bits."""
    n = len(orders)
    rows = np.arange(n)
    matrix = np.tile(np.eye(3), (n, 1, 1))
    others = np.array([(1, 2), (2, 0), (0, 1)])
    for step in range(3):
        axis = np.array([_AXES[order[step]] for order in orders], dtype=np.int64).reshape(n)
        # _exact_cos_sin of each angle: math.radians is one product by pi / 180, as here
        angle = angles_deg[:, step] * (math.pi / 180.0)
        quarter = angle / (math.pi / 2)
        exact = quarter == np.round(quarter)
        # round(quarter) % 4 of an integral quarter, exactly at any size (fmod is exact)
        turns = np.mod(np.where(exact, quarter, 0.0), 4.0).astype(np.int64)
        c, s = _QUARTER_COS[turns], _QUARTER_SIN[turns]
        other = angle[~exact].tolist()
        c[~exact] = list(map(math.cos, other))  # math's, not numpy's: the same bits as one body
        s[~exact] = list(map(math.sin, other))
        i, j = others[axis].T
        turn = np.zeros((n, 3, 3))
        turn[rows, axis, axis] = 1.0
        turn[rows, i, i] = c
        turn[rows, j, j] = c
        turn[rows, i, j] = -s
        turn[rows, j, i] = s
        matrix = np.matmul(turn, matrix)
    return matrix


def _primitive_body(spec, source, label, start, end, spin, scale) -> Body:
    options = spec["primitive"]
    kind = options["type"]
    if kind == "box":
        size = np.asarray(options["size"], dtype=np.float64) * scale
        primitive: Primitive = Box((float(size[0]), float(size[1]), float(size[2])))
    else:
        if not np.all(scale == scale[0]):
            raise SceneError(f"{label}: a {kind} takes a uniform scale only", source)
        radius = float(options["radius"] * scale[0])
        length = float(options.get("length", 0.0) * scale[0])
        primitive = (
            Sphere(radius)
            if kind == "sphere"
            else Capsule(radius, length)
            if kind == "capsule"
            else Cylinder(radius, length)
        )
    vertices, faces = primitive_mesh(primitive)
    return Body(
        name=spec["name"],
        source=source,
        vertices=vertices,
        faces=faces,
        pose=start,
        end_pose=end,
        primitive=primitive,
        collider=spec.get("shape"),
        spin=spin,
    )


# --- reading and validating ---------------------------------------------------------------------


def _check_manifest_file(file: Path, source: str) -> None:
    if not file.exists():
        raise InputFileError("file not found", source)
    if file.is_dir():
        raise InputFileError("is a directory, not a scene manifest", source)
    if file.suffix.lower() not in MANIFEST_EXTENSIONS:
        raise InputFileError(
            f"unknown scene manifest extension {file.suffix or '(none)'!r} (expected .json, .toml)",
            source,
        )


def _parse(file: Path, source: str) -> Any:
    try:
        data = file.read_bytes()
    except OSError as error:
        raise InputFileError(f"cannot read file: {error.strerror or error}", source) from None
    key = os.path.abspath(source)
    cached = _PARSED.get(key)
    if cached is not None and cached[0] == data:
        return cached[1]  # the same bytes parsed a moment ago (the output check reads it too)
    try:
        text = data.decode("utf-8-sig")  # a byte-order mark, as some editors write, is dropped
    except UnicodeDecodeError:
        raise SceneError("manifest is not UTF-8 text", source) from None
    with collector_paused():
        document = _decode(file, text, source)
    # A document of the schema's common shape is at most five levels deep: only another one
    # needs the walk that bounds its depth (before jsonschema, which recurses, sees it).
    columns = _columns(document)
    plain = columns is not None or _plainly_valid_by_body(document)
    if not plain and _nesting(document) > MAX_NESTING:
        raise SceneError(_too_deep(text, "[{"), source)
    _PARSED.clear()  # one manifest kept: a run reads its manifest twice, never many
    _PARSED[key] = (data, document, plain, columns)
    return document


# The last manifest parsed, by absolute path: its bytes, its document (never modified by the
# readers), whether the hand-written check passed it and its columns, so the output check and
# the loading of one run parse and check it once.
_PARSED: dict[str, tuple[bytes, Any, bool, _Columns | None]] = {}


def _columns_of(document: Any) -> _Columns | None:
    """The columns of a valid document (:func:`_columns`), from :func:`_parse`'s cache when
    it parsed this very document."""
    for entry in _PARSED.values():
        if entry[1] is document:
            return entry[3]
    return _columns(document)


def _decode(file: Path, text: str, source: str) -> Any:
    """The parsed JSON or TOML document; syntax errors and runaway nesting as SceneError."""
    if file.suffix.lower() == ".toml":
        if sys.version_info >= (3, 11):
            import tomllib
        else:
            import tomli as tomllib
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            raise SceneError(f"invalid TOML: {str(error).splitlines()[0]}", source) from None
        except RecursionError:
            raise SceneError(_too_deep(text, "[{"), source) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise SceneError(
            f"invalid JSON at line {error.lineno} column {error.colno}: {error.msg}", source
        ) from None
    except RecursionError:
        raise SceneError(_too_deep(text, "[{"), source) from None


def _too_deep(text: str, openers: str) -> str:
    """The message for a document the parser could not descend: where the nesting passes
    :data:`MAX_NESTING` (brackets inside strings are counted too: a bound, not a parse)."""
    depth = 0
    for line_number, line in enumerate(text.splitlines(), start=1):
        for char in line:
            depth += char in openers
            depth -= char in "]}"
            if depth > MAX_NESTING:
                return (
                    f"manifest nests arrays and objects more than {MAX_NESTING} deep "
                    f"(line {line_number})"
                )
    return f"manifest nests arrays and objects more than {MAX_NESTING} deep"


def _children(value: Any) -> Iterator[tuple[Any, Any]]:
    if isinstance(value, dict):
        return iter(value.items())
    if isinstance(value, list):
        return enumerate(value)
    return iter(())


def _nesting(document: Any) -> int:
    """Depth of arrays and objects (0 for a scalar), without recursion."""
    deepest, stack = 0, [(document, 0)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            deepest = max(deepest, depth + 1)
            if depth + 1 <= MAX_NESTING:
                stack.extend((child, depth + 1) for _, child in _children(value))
    return deepest


def _first_non_finite(document: Any) -> list | None:
    """Path to the first NaN or infinity in document order, or None."""
    stack: list[tuple[Any, list]] = [(document, [])]
    while stack:
        value, path = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            return path
        stack.extend(reversed([(item, [*path, key]) for key, item in _children(value)]))
    return None


# The common manifest, checked by hand: JSON Schema validation costs about 0.7 ms of Python per
# body, which a 100,000-body scene cannot afford. _plainly_valid accepts only documents the
# schema accepts with every number finite (tests/test_scene_validation.py holds it to
# jsonschema on generated documents); anything else, including any field it does not know,
# goes to the walk for non-finite numbers and to jsonschema, which write the message. Keep it
# in step with schemas/scene.schema.json.
_TOP_FIELDS = frozenset({"units", "duration", "bodies"})
_BODY_FIELDS = frozenset(
    {
        "name",
        "mesh",
        "primitive",
        "position",
        "rotation",
        "scale",
        "end_position",
        "end_rotation",
        "velocity",
        "angular_velocity",
        "shape",
    }
)
_VECTOR_FIELDS = ("position", "end_position", "velocity", "angular_velocity")
_ORDERS = frozenset(
    {"xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz"}
)
_SHAPES = frozenset(SCENE_SHAPES)
_PRIMITIVE_KEYS = {
    "sphere": frozenset({"type", "radius"}),
    "box": frozenset({"type", "size"}),
    "capsule": frozenset({"type", "radius", "length"}),
    "cylinder": frozenset({"type", "radius", "length"}),
}


def _is_number(x: Any) -> bool:
    """A finite JSON number (bool is not one; non-finite ones fail elsewhere, with a message)."""
    return type(x) is int or (type(x) is float and math.isfinite(x))


def _is_numbers(x: Any, n: int, positive: bool = False) -> bool:
    if type(x) is not list or len(x) != n:
        return False
    return all(_is_number(v) and (not positive or v > 0) for v in x)


def _is_rotation(r: Any) -> bool:
    if type(r) is not dict:
        return False
    if len(r) == 1:
        return _is_numbers(r.get("quaternion"), 4)
    order = r.get("order")
    return (
        len(r) == 2
        and _is_numbers(r.get("euler_deg"), 3)
        and type(order) is str
        and (order in _ORDERS)
    )


def _is_primitive(p: Any) -> bool:
    if type(p) is not dict:
        return False
    kind = p.get("type")
    fields = _PRIMITIVE_KEYS.get(kind) if type(kind) is str else None
    if fields is None or p.keys() != fields:
        return False
    if kind == "box":
        return _is_numbers(p["size"], 3, positive=True)
    if not (_is_number(p["radius"]) and p["radius"] > 0):
        return False
    return kind == "sphere" or (_is_number(p["length"]) and p["length"] > 0)


def _plainly_valid(document: Any) -> bool:
    """True only when ``document`` is valid under the scene schema (False: ask jsonschema)."""
    return _columns(document) is not None or _plainly_valid_by_body(document)


def _plain_top(document: Any) -> bool:
    """The manifest's own fields (not its bodies') as the schema wants them."""
    if type(document) is not dict or not document.keys() <= _TOP_FIELDS:
        return False
    units = document.get("units", "m")
    duration = document.get("duration", 1.0)
    bodies = document.get("bodies")
    if type(units) is not str or not units:
        return False
    if not _is_number(duration) or not duration > 0:
        return False
    return type(bodies) is list and bool(bodies)


def _plainly_valid_by_body(document: Any) -> bool:
    """:func:`_plainly_valid` one body at a time: what :func:`_columns` does not pass (a
    number beyond a double, say) may still be valid."""
    if not _plain_top(document):
        return False
    for body in document["bodies"]:
        if type(body) is not dict or not body.keys() <= _BODY_FIELDS:
            return False
        name = body.get("name")
        if type(name) is not str or not name:
            return False
        mesh = body.get("mesh")
        if mesh is None:
            if "mesh" in body or not _is_primitive(body.get("primitive")):
                return False
        elif type(mesh) is not str or not mesh or "primitive" in body:
            return False
        for field in _VECTOR_FIELDS:
            if field in body and not _is_numbers(body[field], 3):
                return False
        for field in ("rotation", "end_rotation"):
            if field in body and not _is_rotation(body[field]):
                return False
        if "scale" in body:
            scale = body["scale"]
            if not (_is_number(scale) and scale > 0) and not _is_numbers(scale, 3, positive=True):
                return False
        if "shape" in body and (type(body["shape"]) is not str or body["shape"] not in _SHAPES):
            return False
    return True


@dataclasses.dataclass(frozen=True, eq=False)
class _Columns:
    """The bodies of a plainly valid manifest as columns, index-aligned with its bodies (n):
    what the loader's bulk path and the magnitude check read instead of the bodies.

    Attributes
    ----------
    names, meshes, shapes : list
        Per body (``meshes[i]`` and ``shapes[i]`` None where absent).
    primitive, moving, scaled : (n,) bool
        A primitive body; one with an end pose or a velocity; one with a scale other than 1.
    vectors : dict of str to (n, 3) float64
        ``position``, ``end_position``, ``velocity``, ``angular_velocity``, zeros where
        absent; a field no body has is not in it.
    scale : (n, 3) float64 or None
        Ones where absent; None when no body has one.
    rotation : (n,) int8
        0 none, 1 quaternion, 2 Euler angles.
    quaternion : (nq, 4) float64
        The quaternions of the bodies with ``rotation == 1``, in order.
    euler, orders : (ne, 3) float64, list of str
        The angles and orders of the bodies with ``rotation == 2``, in order.
    """

    names: list[str]
    meshes: list[str | None]
    shapes: list[str | None]
    primitive: np.ndarray
    moving: np.ndarray
    scaled: np.ndarray
    vectors: dict[str, np.ndarray]
    scale: np.ndarray | None
    rotation: np.ndarray
    quaternion: np.ndarray
    euler: np.ndarray
    orders: list[str]


_NUMBER_TYPES = frozenset({int, float})
_QUATERNION_KEYS = frozenset({"quaternion"})
_EULER_KEYS = frozenset({"euler_deg", "order"})
_MOTION_FIELDS = ("end_position", "end_rotation", "velocity", "angular_velocity")


def _number_rows(values: list, width: int) -> np.ndarray | None:
    """``values``, lists of ``width`` finite JSON numbers each, as (len, width) float64; None
    for anything else (bool is not a number; an integer beyond a double is left to the
    body-by-body check)."""
    if not values:
        return np.zeros((0, width))
    if set(map(type, values)) != {list} or set(map(len, values)) != {width}:
        return None
    flat = [v for row in values for v in row]
    if not set(map(type, flat)) <= _NUMBER_TYPES:
        return None
    try:
        rows = np.array(flat, dtype=np.float64).reshape(-1, width)
    except OverflowError:
        return None
    return rows if np.isfinite(rows).all() else None


def _spread(rows: np.ndarray, mask: np.ndarray | None, n: int, fill: float) -> np.ndarray:
    """Rows of the bodies ``mask`` selects (all when None) in an (n, width) array."""
    if mask is None:
        return rows
    out = np.full((n, rows.shape[1]), fill)
    out[mask] = rows
    return out


def _columns(document: Any) -> _Columns | None:
    """The columns of ``document`` when it is plainly valid, checked column by column; None
    when it is not, or when this check cannot tell (then :func:`_plainly_valid_by_body`
    decides). It passes only documents the body-by-body check passes
    (``tests/test_scene_validation.py`` holds it to that), at a small fraction of the cost:
    a 300,000-body manifest is checked in C loops over columns, not in Python per body."""
    if not _plain_top(document):
        return None
    bodies = document["bodies"]
    n = len(bodies)
    if set(map(type, bodies)) != {dict}:
        return None
    layouts: dict[frozenset, int] = {}
    for keys in map(frozenset, bodies):
        layouts[keys] = layouts.get(keys, 0) + 1
    for keys in layouts:
        if (
            not keys <= _BODY_FIELDS
            or "name" not in keys
            or ("mesh" in keys) == ("primitive" in keys)
        ):
            return None
    count = {f: sum(c for keys, c in layouts.items() if f in keys) for f in _BODY_FIELDS}

    def column(field: str) -> tuple[list, np.ndarray | None]:
        """The values of the bodies that have ``field``, and which those are (None: all)."""
        if count[field] == n:
            return [b[field] for b in bodies], None
        mask = np.fromiter((field in b for b in bodies), dtype=bool, count=n)
        return [b[field] for b in bodies if field in b], mask

    def spread_list(values: list, mask: np.ndarray | None) -> list:
        if mask is None:
            return values
        found = iter(values)
        return [next(found) if there else None for there in mask.tolist()]

    def present(field: str) -> np.ndarray:
        if count[field] in (0, n):
            return np.full(n, count[field] == n)
        return column(field)[1]  # type: ignore[return-value]

    names, _ = column("name")
    if set(map(type, names)) != {str} or "" in names:
        return None
    meshes: list = [None] * n
    if count["mesh"]:
        values, mask = column("mesh")
        if set(map(type, values)) != {str} or "" in values:
            return None
        meshes = spread_list(values, mask)
    if count["primitive"] and not all(map(_is_primitive, column("primitive")[0])):
        return None
    vectors = {}
    for field in _VECTOR_FIELDS:
        if count[field]:
            values, mask = column(field)
            rows = _number_rows(values, 3)
            if rows is None:
                return None
            vectors[field] = _spread(rows, mask, n, 0.0)
    rotation = np.zeros(n, dtype=np.int8)
    quaternion, euler, orders = np.zeros((0, 4)), np.zeros((0, 3)), []
    for field in ("rotation", "end_rotation"):
        if not count[field]:
            continue
        values, mask = column(field)
        if set(map(type, values)) != {dict}:
            return None
        is_quaternion = [r.keys() == _QUATERNION_KEYS for r in values]
        if not all(q or r.keys() == _EULER_KEYS for q, r in zip(is_quaternion, values)):
            return None
        q_rows = _number_rows([r["quaternion"] for r in values if len(r) == 1], 4)
        e_values = [r for r in values if len(r) == 2]
        e_rows = _number_rows([r["euler_deg"] for r in e_values], 3)
        e_orders = [r["order"] for r in e_values]
        if q_rows is None or e_rows is None or not set(map(type, e_orders)) <= {str}:
            return None
        if not set(e_orders) <= _ORDERS:
            return None
        if field == "rotation":
            kinds = np.where(np.array(is_quaternion, dtype=bool), 1, 2).astype(np.int8)
            rotation = _spread(kinds.reshape(-1, 1), mask, n, 0).astype(np.int8).reshape(n)
            quaternion, euler, orders = q_rows, e_rows, e_orders
    scale = None
    scaled = np.zeros(n, dtype=bool)
    if count["scale"]:
        values, mask = column("scale")
        if not set(map(type, values)) <= {int, float, list}:
            return None
        is_list = [type(v) is list for v in values]
        uniform = [v for v, listed in zip(values, is_list) if not listed]
        try:
            factors = np.array(uniform, dtype=np.float64)
        except OverflowError:
            return None
        rows = _number_rows([v for v in values if type(v) is list], 3)
        if rows is None or not (np.isfinite(factors).all() and (factors > 0).all()):
            return None
        if not (rows > 0).all():
            return None
        given = np.empty((len(values), 3))
        listed = np.array(is_list, dtype=bool).reshape(len(values))
        given[listed] = rows
        given[~listed] = factors[:, None]
        scale = _spread(given, mask, n, 1.0)
        scaled = (scale != 1.0).any(axis=1)
    shapes: list = [None] * n
    if count["shape"]:
        values, mask = column("shape")
        if set(map(type, values)) != {str} or not set(values) <= _SHAPES:
            return None
        shapes = spread_list(values, mask)
    moving = np.zeros(n, dtype=bool)
    for field in _MOTION_FIELDS:
        moving |= present(field)
    return _Columns(
        names=names,
        meshes=meshes,
        shapes=shapes,
        primitive=present("primitive"),
        moving=moving,
        scaled=scaled,
        vectors=vectors,
        scale=scale,
        rotation=rotation,
        quaternion=quaternion,
        euler=euler,
        orders=orders,
    )


#: Manifest fields that are lengths or positions (checked against MAX_COORDINATE).
_LENGTH_FIELDS = ("position", "end_position", "scale")
_PRIMITIVE_FIELDS = ("size", "radius", "length")


def _check_magnitudes(document: dict, source: str, columns: _Columns | None = None) -> None:
    """Every length, position and motion of a valid manifest within the limits meshcol
    computes with: one line naming the body, the field, the value and its line.

    With the manifest's ``columns``, only the bodies a vectorised pass finds near a limit (or
    primitive: their sizes are not in the columns) are checked one by one, in order: the
    same first error, without 300,000 bodies of Python."""
    duration = document.get("duration")
    bodies = document["bodies"]
    indices: Sequence[int] = range(len(bodies))
    if columns is not None:
        indices = np.flatnonzero(_near_limits(columns, duration)).tolist()
    for index in indices:
        spec = bodies[index]
        label = _body_label(document, index)
        fields = [(name, spec.get(name)) for name in _LENGTH_FIELDS]
        fields += [
            (f"primitive.{name}", spec.get("primitive", {}).get(name)) for name in _PRIMITIVE_FIELDS
        ]
        for name, value in fields:
            values = value if isinstance(value, list) else [] if value is None else [value]
            for v in values:
                if abs(v) > MAX_COORDINATE:
                    raise _at_line(
                        f"{label}: {name} {v:.6g} is beyond the limit of +/-{MAX_COORDINATE:g}",
                        source,
                        spec["name"],
                        name,
                    )
        if "scale" in spec:
            scales = spec["scale"] if isinstance(spec["scale"], list) else [spec["scale"]]
            for value in scales:
                if 0 < value < 1.0 / MAX_COORDINATE:
                    raise _at_line(
                        f"{label}: scale {value:.6g} is below the limit of "
                        f"{1.0 / MAX_COORDINATE:g}: the body would collapse to a point",
                        source,
                        spec["name"],
                        "scale",
                    )
        if duration is None:
            continue
        for name, limit, unit in (
            ("velocity", MAX_COORDINATE, ""),
            ("angular_velocity", MAX_TURN, " rad"),
        ):
            value = spec.get(name)
            if value is None:
                continue
            motion = max(abs(v) for v in value) * duration  # Python floats: inf, never an error
            if motion > limit:
                raise _at_line(
                    f"{label}: {name} x duration is {motion:.6g}{unit}, beyond the limit of "
                    f"{limit:g}{unit} ({name} {_numbers(value)}, duration {duration:g} s)",
                    source,
                    spec["name"],
                    name,
                )


def _near_limits(columns: _Columns, duration: float | None) -> np.ndarray:
    """(n,) bool: the bodies :func:`_check_magnitudes` must look at one by one: primitives,
    and every body with a value within a factor of two of a limit (a margin, so rounding an
    integer to a double never hides one beyond it)."""
    near = columns.primitive.copy()
    lengths = [columns.vectors.get("position"), columns.vectors.get("end_position"), columns.scale]
    for values in lengths:
        if values is not None:
            near |= (np.abs(values) >= 0.5 * MAX_COORDINATE).any(axis=1)
    if columns.scale is not None:
        near |= (columns.scale <= 2.0 / MAX_COORDINATE).any(axis=1)
    if duration is not None:
        with np.errstate(over="ignore"):
            for name, limit in (("velocity", MAX_COORDINATE), ("angular_velocity", MAX_TURN)):
                values = columns.vectors.get(name)
                if values is not None:
                    near |= np.abs(values).max(axis=1) * float(duration) >= 0.5 * limit
    return near


def _at_line(message: str, source: str, body: str, field: str) -> SceneError:
    """``message`` with `` (line N)``, the line of ``field`` in the body named ``body``."""
    line = _line_of(source, body, field.split(".")[-1])
    return SceneError(message if line is None else f"{message} (line {line})", source)


def _line_of(source: str, body: str, field: str) -> int | None:
    """1-based line of ``field`` within the body named ``body`` (JSON or TOML text): the
    first after the body's name line, before the next body's; else the last before it."""
    try:
        lines = Path(source).read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    names = re.compile(r"""["']?\bname["']?\s*[:=]\s*["']([^"']*)["']""")
    key = re.compile(r"""(?:^|[\s{,"'])""" + re.escape(field) + r"""["']?\s*[:=]""")
    starts = [(i, m.group(1)) for i, text in enumerate(lines) for m in names.finditer(text)]
    for k, (start, name) in enumerate(starts):
        if name != body:
            continue
        end = starts[k + 1][0] if k + 1 < len(starts) else len(lines)
        begin = starts[k - 1][0] + 1 if k > 0 else 0
        after = [i for i in range(start, max(end, start + 1)) if key.search(lines[i])]
        before = [i for i in range(begin, start) if key.search(lines[i])]
        found = after[:1] or before[-1:]
        return (found[0] if found else start) + 1
    return None


def _numbers(values: list) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"


def _check_world(body: Body, label: str, source: str) -> None:
    """A body's world coordinates (scale, pose, mesh and motion combined) within the limit."""
    reach = float(np.abs(body.vertices).max(initial=0.0)) * math.sqrt(3.0)
    for pose, when in ((body.pose, ""), (body.end_pose, " at the end of the motion")):
        if pose is None:
            continue
        # |R v + t| per coordinate is at most sqrt(3) max|v| + max|t| (R a rotation): the
        # exact check runs only for a body that might reach the limit.
        if reach + float(np.abs(pose[:3, 3]).max()) <= MAX_COORDINATE:
            continue
        world = body.vertices @ pose[:3, :3].T + pose[:3, 3]
        try:
            check_magnitude(world, "world vertex", None)
        except MeshcolError as error:
            mesh = ""
            if body.source is not None and body.source != source:
                mesh = f" (mesh {os.path.basename(body.source)!r})"
            raise SceneError(f"{label}{when}: {error.message}{mesh}", source) from None


def manifest_mesh_files(path: str | os.PathLike[str]) -> list[str]:
    """The mesh files a manifest refers to (relative to its folder), without loading them.

    Returns
    -------
    list of str
        In manifest order, each once; empty when the manifest cannot be read or parsed (then
        :func:`load_scene` reports why).
    """
    source = os.fspath(path)
    try:
        document = _parse(Path(source), source)
    except MeshcolError:
        return []
    bodies = document.get("bodies") if isinstance(document, dict) else None
    meshes: dict[str, None] = {}
    for spec in bodies if isinstance(bodies, list) else []:
        mesh = spec.get("mesh") if isinstance(spec, dict) else None
        if isinstance(mesh, str) and mesh:
            meshes[mesh] = None
    folder = os.path.dirname(source)
    return list(dict.fromkeys(os.path.join(folder, mesh) for mesh in meshes))


@lru_cache(maxsize=1)
def _validator():
    import jsonschema

    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def _validate(document: Any, source: str) -> None:
    """Raises SceneError for a non-finite number (first, in document order) or a schema
    violation; the common manifest passes by the hand-written check alone, which also requires
    every number it meets to be finite."""
    if any(entry[1] is document and entry[2] for entry in _PARSED.values()):
        return  # _parse checked this very document
    if _plainly_valid(document):
        return
    where = _first_non_finite(document)
    if where is not None:
        raise SceneError(f"{_describe(document, where)} must be finite", source)
    errors = list(_validator().iter_errors(document))
    if not errors:
        return
    # report the first problem in document order; missing/unknown fields before wrong values
    priority = {"additionalProperties": 0, "required": 1}

    def key(error):
        path = [(0, p, "") if isinstance(p, int) else (1, 0, p) for p in error.absolute_path]
        return (path, priority.get(error.validator, 2))

    error = min(errors, key=key)
    raise SceneError(_message(document, error), source)


def _message(document: Any, error) -> str:
    path = list(error.absolute_path)
    branch = _rotation_branch(error)
    if branch is not None:
        return _message(document, branch)
    if error.validator == "additionalProperties":
        allowed = set(error.schema.get("properties", {}))
        extra = sorted(set(error.instance) - allowed)
        names = ", ".join(repr(_join(path[_field_start(path) :], name)) for name in extra)
        noun = "field" if len(extra) == 1 else "fields"
        return _prefixed(document, path, f"unknown {noun} {names}")
    if error.validator == "required":
        missing = [name for name in error.validator_value if name not in error.instance]
        return _prefixed(
            document, path, f"missing field {_join(path[_field_start(path) :], missing[0])!r}"
        )
    if not path:
        return "manifest must be an object (a table in TOML)"
    if path == ["bodies", path[-1]] and isinstance(path[-1], int):
        if error.validator == "oneOf":
            return f"{_body_label(document, path[1])}: needs exactly one of 'mesh' or 'primitive'"
        return f"bodies[{path[1]}] must be an object (a table in TOML)"
    return f"{_describe(document, path)} must be {_expected(path)}"


def _rotation_branch(error):
    """For a rotation of a recognisable form, the error inside that form (e.g. a bad order)."""
    if error.validator != "oneOf" or not isinstance(error.instance, dict):
        return None
    if "quaternion" in error.instance:
        form = 0
    elif "euler_deg" in error.instance:
        form = 1
    else:
        return None
    inner = [
        e for e in error.context if e.relative_schema_path and e.relative_schema_path[0] == form
    ]
    if not inner:
        return None
    priority = {"additionalProperties": 0, "required": 1}
    return min(inner, key=lambda e: (len(e.absolute_path), priority.get(e.validator, 2)))


def _field_start(path: list) -> int:
    return 2 if len(path) >= 2 and path[0] == "bodies" and isinstance(path[1], int) else 0


def _join(fields: list, name: str | None = None) -> str:
    parts = [str(p) for p in fields if not isinstance(p, int)]
    if name is not None:
        parts.append(name)
    return ".".join(parts)


def _body_label(document: Any, index: int) -> str:
    try:
        name = document["bodies"][index]["name"]
    except (KeyError, IndexError, TypeError):
        name = None
    return f"body {name!r}" if isinstance(name, str) and name else f"bodies[{index}]"


def _prefixed(document: Any, path: list, message: str) -> str:
    start = _field_start(path)
    if start:
        return f"{_body_label(document, path[1])}: {message}"
    return message


def _describe(document: Any, path: list) -> str:
    """``body 'ball': position`` or ``duration``, for a path into the document."""
    start = _field_start(path)
    field = _join(path[start:]) or _join(path)
    if start:
        return f"{_body_label(document, path[1])}: {field}"
    return field


def _expected(path: list) -> str:
    names = [p for p in path if isinstance(p, str)]
    return _EXPECTED.get(names[-1], "valid") if names else "valid"
