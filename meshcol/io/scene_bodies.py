"""A valid scene manifest's bodies, one at a time: poses, motions, mesh files, primitives.

Each manifest entry becomes one :class:`meshcol.types.Body` (its file's objects are its
parts), in manifest order, with every error that only building a body can find (a repeated
name, a zero quaternion, a velocity without a duration, a mesh file that cannot be read, world
coordinates beyond the limit) as one :class:`meshcol.errors.SceneError` naming the body.
The common bodies may come built already (:func:`meshcol.io.scene_columns.bulk_bodies`).
"""

from __future__ import annotations

import math
import os
from collections.abc import MutableMapping, Sequence
from itertools import repeat
from typing import Any

import numpy as np

from meshcol.errors import MeshcolError, SceneError
from meshcol.io.mesh_read import MAX_COORDINATE, check_magnitude, load_mesh, split_rigid
from meshcol.io.paths import confine_all, joined_paths
from meshcol.io.physics_bodies import scaled_primitive
from meshcol.io.scene_primitives import manifest_primitive
from meshcol.types import Body, Spin, primitive_reach

__all__ = [
    "AXES",
    "IDENTITY",
    "build_bodies",
    "read_mesh_files",
    "read_mesh_names",
    "rotation_from_euler",
    "rotation_from_quaternion",
]

#: The index of each axis letter of an Euler order.
AXES = {"x": 0, "y": 1, "z": 2}

#: The identity pose, shared (read-only) by every body that needs no transform.
IDENTITY = np.eye(4)
IDENTITY.flags.writeable = False


def build_bodies(
    document: dict, source: str, files: MutableMapping[str, list[Body]], bulk: Sequence | None
) -> list[Body]:
    """Every body of a valid manifest, in order: ``bulk[i]`` where built already, else built
    here (and checked: names, motion, mesh file, world coordinates).

    Parameters
    ----------
    document : dict
        The manifest, valid under its schema.
    source : str
        Its path: mesh paths are relative to its folder; errors name it.
    files : dict of str to list of Body
        Mesh files read already, by normalised path; one read here is added.
    bulk : sequence of Body or None, or None
        Index-aligned with the bodies.
    """
    duration = document.get("duration")
    bodies: list[Body] = []
    names: set[str] = set()
    for index, spec in enumerate(document["bodies"]):
        built = bulk[index] if bulk is not None else None
        if built is not None:
            bodies.append(built)
            continue
        label = f"body {spec['name']!r}"
        if spec["name"] in names:
            raise SceneError(f"{label}: name used by an earlier body", source)
        names.add(spec["name"])
        if ("mesh" in spec) == ("primitive" in spec):
            raise SceneError(f"{label}: needs exactly one of 'mesh' or 'primitive'", source)
        motion = _motion(spec, duration, label, source)
        scale = _scale(spec.get("scale"))
        if "mesh" in spec:
            body = _mesh_body(spec, source, label, motion, scale, files)
        else:
            body = _primitive_body(spec, source, label, motion, scale)
        _check_world(body, label, source)
        bodies.append(body)
    return bodies


def read_mesh_files(document: Any, source: str) -> MutableMapping[str, list[Body]]:
    """Every mesh file the manifest names, read at once (OBJ and STL by the core, in parallel),
    keyed by normalised path (:class:`meshcol.io.mesh_read.MeshFiles`: the bodies of a file
    built when asked for). Empty when a file fails: the body loop then reads the files one
    by one and reports the first bad one with its body's name."""
    bodies = document["bodies"]
    try:  # each value once (a C loop), then only the distinct ones looked at
        found = dict.fromkeys(map(dict.get, bodies, repeat("mesh")))
    except TypeError:  # not a dict, or a value that is not hashable: one body at a time
        found = dict.fromkeys(spec["mesh"] for spec in bodies if isinstance(spec.get("mesh"), str))
    # each name once before the path arithmetic: 300,000 bodies may share 16 files
    return read_mesh_names([name for name in found if isinstance(name, str)], source)


def read_mesh_names(names: Sequence[str], source: str) -> MutableMapping[str, list[Body]]:
    """:func:`read_mesh_files` of the mesh names a manifest uses, each once, in order of first
    use (a manifest's columns give them without its document)."""
    from meshcol.io.mesh_read import read_meshes

    folder = os.path.dirname(source)
    joined = joined_paths(folder, names, normalise=True)
    paths = list(dict.fromkeys(confine_all(joined, source, names)))  # inside --root
    try:
        return read_meshes(paths)
    except MeshcolError:
        return {}


# --- rotations and poses ------------------------------------------------------------------------


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
    if len(order) != 3 or any(axis not in AXES for axis in order):
        raise ValueError(f"order must be three of x, y, z, got {order!r}")
    matrix = np.eye(3)
    for axis, angle in zip(order, angles_deg):
        matrix = _axis_rotation(AXES[axis], math.radians(float(angle))) @ matrix
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


class _Motion:
    """A body's start pose, end pose (None: static) and spin (None: the shortest turn)."""

    __slots__ = ("end", "spin", "start")

    def __init__(self, start: np.ndarray, end: np.ndarray | None, spin: Spin | None) -> None:
        self.start, self.end, self.spin = start, end, spin


def _motion(spec: dict, duration: float | None, label: str, source: str) -> _Motion:
    """The start pose, and the end pose by ``end_position``/``end_rotation`` (reached the
    shortest way) or by ``velocity``/``angular_velocity`` over the duration (a :class:`Spin`
    of ``|w| * duration`` radians, whatever the size)."""
    start = _pose(spec.get("position"), spec.get("rotation"), label, "rotation", source)
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
        return _Motion(start, end, None)
    if by_velocity:
        return _by_velocity(spec, start, duration, label, source)
    return _Motion(start, None, None)


def _by_velocity(
    spec: dict, start: np.ndarray, duration: float | None, label: str, source: str
) -> _Motion:
    if duration is None:
        field = "velocity" if "velocity" in spec else "angular_velocity"
        raise SceneError(f"{label}: {field} needs the manifest's 'duration'", source)
    end = start.copy()
    end[:3, 3] += np.asarray(spec.get("velocity", [0.0, 0.0, 0.0]), dtype=float) * duration
    if "angular_velocity" not in spec:
        return _Motion(start, end, None)
    turn = np.asarray(spec["angular_velocity"], dtype=float) * duration
    if not np.all(np.isfinite(turn)):
        raise SceneError(f"{label}: angular_velocity * duration is not finite", source)
    spin = Spin(turn)
    end[:3, :3] = spin.matrix() @ start[:3, :3]
    return _Motion(start, end, spin)


def _sub_spin(motion: _Motion, rigid: np.ndarray) -> Spin | None:
    """A sub-body's spin: the manifest body's turn (the shortest one to an end rotation), about
    the manifest body's origin, where the file places the sub-body's own origin elsewhere; so
    the sub-bodies move as one rigid body."""
    if motion.end is None or not np.any(rigid[:3, 3]):
        return motion.spin
    spin = motion.spin
    return Spin(None if spin is None else spin.rotation, pivot=motion.start[:3, 3].copy())


def _scale(value) -> np.ndarray:
    if value is None:
        return np.ones(3)
    if isinstance(value, list):
        return np.asarray(value, dtype=np.float64)
    return np.full(3, float(value))


# --- mesh bodies --------------------------------------------------------------------------------


def _mesh_body(
    spec: dict,
    source: str,
    label: str,
    motion: _Motion,
    scale: np.ndarray,
    files: MutableMapping[str, list[Body]],
) -> Body:
    mesh_source = os.path.join(os.path.dirname(source), spec["mesh"])
    loaded = _mesh_file(spec["mesh"], mesh_source, source, label, files)
    if len(loaded) > 1:
        rigid = np.eye(4)
        vertices, faces, parts, part_faces = _merged_parts(loaded, scale)
    else:
        rigid, vertices, faces = _one_object(loaded[0], scale)
        parts, part_faces = (), None
    start, end = motion.start, motion.end
    return Body(
        name=spec["name"],
        source=mesh_source,
        vertices=np.ascontiguousarray(vertices),
        faces=np.ascontiguousarray(faces),
        pose=start if rigid is IDENTITY else start @ rigid,
        end_pose=None if end is None else end if rigid is IDENTITY else end @ rigid,
        collider=spec.get("shape"),
        parts=parts,
        part_faces=part_faces,
        spin=_sub_spin(motion, rigid),
    )


def _mesh_file(
    mesh: str, mesh_source: str, source: str, label: str, files: MutableMapping[str, list[Body]]
) -> list[Body]:
    """The objects of a body's mesh file: read already, or read now (the error names the
    body)."""
    key = os.path.normpath(mesh_source)
    loaded = files.get(key)
    if loaded is None:
        if not os.path.lexists(mesh_source):  # a pipe or a device: load_mesh says what it is
            raise SceneError(f"{label}: mesh file {mesh!r} not found", source)
        try:
            loaded = load_mesh(mesh_source)
        except MeshcolError as error:
            raise SceneError(f"{label}: mesh file {mesh!r}: {error.message}", source) from None
        files[key] = loaded
    return loaded


def _one_object(sub: Body, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rigid, vertices, faces)`` of a file's only object: its scale and transform split
    into a rigid part and one baked into the vertices (nothing to do in the common case)."""
    if not np.any(scale != 1.0) and _is_identity(sub.pose):
        return IDENTITY, sub.vertices, sub.faces
    rigid, linear = split_rigid(np.diag([*scale, 1.0]) @ sub.pose)
    vertices, faces = sub.vertices, sub.faces
    if linear is not None:
        vertices = vertices @ linear.T
        if np.linalg.det(linear) < 0:
            faces = faces[:, ::-1]
    return rigid, vertices, faces


def _merged_parts(
    loaded: list[Body], scale: np.ndarray
) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], np.ndarray]:
    """One body of several parts: each part's node transform and the body's scale baked into
    its vertices, so the parts share the body's frame and pose. Returns the vertices, faces,
    part names and part face offsets."""
    stretch = np.diag([*scale, 1.0])
    blocks_v, blocks_f, counts = [], [], []
    base = 0
    for sub in loaded:
        matrix = stretch @ sub.pose
        local_faces = sub.faces[:, ::-1] if np.linalg.det(matrix[:3, :3]) < 0 else sub.faces
        blocks_v.append(sub.vertices @ matrix[:3, :3].T + matrix[:3, 3])
        blocks_f.append(local_faces + base)
        counts.append(len(sub.faces))
        base += len(sub.vertices)
    parts = tuple(sub.name.split("/", 1)[1] for sub in loaded)
    part_faces = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return np.concatenate(blocks_v), np.concatenate(blocks_f), parts, part_faces


def _is_identity(matrix: np.ndarray) -> bool:
    return matrix is IDENTITY or bool(np.array_equal(matrix, IDENTITY))


# --- primitive bodies ---------------------------------------------------------------------------


def _primitive_body(
    spec: dict, source: str, label: str, motion: _Motion, scale: np.ndarray
) -> Body:
    """A primitive body: its primitive scaled as :func:`scaled_primitive` scales a USD or glTF
    one (a box or an ellipsoid per axis, a sphere scaled unevenly an ellipsoid, a cylinder
    along its axis); a capsule takes a uniform scale only (its caps would stretch), a cylinder
    the same scale in x and y (else its section is an ellipse)."""
    options = spec["primitive"]
    kind = options["type"]
    primitive = manifest_primitive(options)
    if np.any(scale != 1.0):
        scaled = scaled_primitive(primitive, np.diag([*scale, 1.0]))
        if scaled is None:  # a positive diagonal: no shear, so a capsule or a cylinder
            need = "a uniform scale" if kind == "capsule" else "the same scale in x and y"
            raise SceneError(f"{label}: a {kind} takes {need} only", source)
        primitive = scaled[0]
    return Body.of_primitive(
        spec["name"],
        source,
        primitive,
        pose=motion.start,
        end_pose=motion.end,
        collider=spec.get("shape"),
        spin=motion.spin,
    )


def _check_world(body: Body, label: str, source: str) -> None:
    """A body's world coordinates (scale, pose, mesh and motion combined) within the limit."""
    reach = (
        float(np.abs(body.vertices).max(initial=0.0)) * math.sqrt(3.0)
        if body.primitive is None
        else primitive_reach(body.primitive)  # bounds its tessellation's vertices
    )
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
