"""Scene manifests (JSON or TOML) and the inputs of every command.

A manifest lists rigid bodies, each a mesh file or an analytic primitive, with a pose and an
optional end pose for continuous collision. Its structure is the JSON Schema shipped as
``meshcol/schemas/scene.schema.json`` (every field is described there); manifests are
validated against it and every problem becomes one :class:`meshcol.errors.SceneError` line
naming the manifest, the body and the field.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
from collections.abc import Iterator, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import InputFileError, MeshcolError, SceneError
from meshcol.io.mesh_read import load_mesh, split_rigid
from meshcol.types import Body, Box, Capsule, Cylinder, Primitive, Scene, Sphere

__all__ = [
    "MANIFEST_EXTENSIONS",
    "SCHEMA_PATH",
    "iter_inputs",
    "load_inputs",
    "as_scene",
    "load_scene",
    "rotation_from_euler",
    "rotation_from_quaternion",
]

#: Extensions read as scene manifests; anything else is a mesh or glTF scene file.
MANIFEST_EXTENSIONS = (".json", ".toml")

#: The JSON Schema of a manifest.
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schemas" / "scene.schema.json"

# Tessellation of primitive bodies (their exact shape is in Body.primitive).
_SPHERE_SUBDIVISIONS = 3  # icosphere: 642 vertices
_ROUND_SECTIONS = 32  # around the axis of capsules and cylinders

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


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Load a scene manifest (``.json`` or ``.toml``).

    Parameters
    ----------
    path : str or path-like
        The manifest. Mesh paths inside it are relative to its folder.

    Returns
    -------
    Scene
        Bodies in manifest order (a mesh file with several bodies gives ``<name>/<sub>`` for
        each, in file order), the manifest's ``units`` and ``duration``, ``source = path``.

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
    ``S`` and any transform ``L`` a mesh file gives a sub-body are combined as ``T S L`` and
    split again into a rigid transform and a part baked into the vertices (see
    :func:`meshcol.io.mesh_read.split_rigid`), so every ``Body.pose`` is rigid.
    """
    source = os.fspath(path)
    file = Path(source)
    _check_manifest_file(file, source)
    document = _parse(file, source)
    _validate(document, source)
    units = document.get("units")
    duration = document.get("duration")

    bodies: list[Body] = []
    names: set[str] = set()
    taken: set[str] = set()  # names of the bodies made so far (sub-bodies included)
    files: dict[str, list[Body]] = {}  # each mesh file is read once, however many instances
    for spec in document["bodies"]:
        label = f"body {spec['name']!r}"
        if spec["name"] in names:
            raise SceneError(f"{label}: name used by an earlier body", source)
        names.add(spec["name"])
        if ("mesh" in spec) == ("primitive" in spec):
            raise SceneError(f"{label}: needs exactly one of 'mesh' or 'primitive'", source)
        start = _pose(spec.get("position"), spec.get("rotation"), label, "rotation", source)
        end = _end_pose(spec, start, duration, label, source)
        scale = _scale(spec.get("scale"))
        if "mesh" in spec:
            new = _mesh_bodies(spec, file, source, label, start, end, scale, files)
        else:
            new = [_primitive_body(spec, source, label, start, end, scale)]
        for body in new:
            if body.name in taken:
                raise SceneError(f"{label}: body name {body.name!r} is already taken", source)
            taken.add(body.name)
        bodies.extend(new)
    return Scene(bodies=tuple(bodies), units=units, source=source, duration=duration)


def as_scene(inputs: Any) -> Scene:
    """A scene from what the library's analyses accept: a Scene, a Body, a sequence of
    Bodies, or input paths (:func:`load_inputs`; a single mesh file becomes the source).

    Parameters
    ----------
    inputs : Scene, Body, sequence of Body, path or sequence of paths

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
    scene = load_inputs(inputs)
    if scene.source is None and len(inputs) == 1:
        scene = dataclasses.replace(scene, source=os.fspath(inputs[0]))
    return scene


def load_inputs(paths: Sequence[str | os.PathLike[str]]) -> Scene:
    """Turn a command's input paths into one scene.

    Parameters
    ----------
    paths : sequence of str or path-like
        Either one scene manifest, or any number of mesh and glTF/GLB scene files.

    Returns
    -------
    Scene
        The manifest's scene; or every body of every file in order. A name that clashes with
        an earlier body's gets ``#2``, ``#3``... appended. ``source`` is the input path when
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
        return load_scene(manifest)
    bodies = [body for _, file_bodies in iter_inputs(paths) for body in file_bodies]
    source = os.fspath(paths[0]) if len(paths) == 1 else None
    return Scene(bodies=tuple(bodies), units=None, source=source)


def _single_manifest(paths: Sequence[str | os.PathLike[str]]) -> str | os.PathLike[str] | None:
    """The manifest among ``paths`` (it must come alone), or None."""
    if len(paths) == 0:
        raise InputFileError("no input files given")
    manifests = [p for p in paths if Path(os.fspath(p)).suffix.lower() in MANIFEST_EXTENSIONS]
    if manifests and len(paths) > 1:
        raise SceneError(
            "a scene manifest cannot be combined with other inputs: give it alone", manifests[0]
        )
    return manifests[0] if manifests else None


def iter_inputs(
    paths: Sequence[str | os.PathLike[str]],
) -> Iterator[tuple[str, list[Body]]]:
    """:func:`load_inputs` one file at a time: ``(file, its bodies)`` as each file is read.

    The same bodies, names and errors as :func:`load_inputs`, but a caller can start work on
    the first file while the next is read (``meshcol decompose``). A manifest is read whole
    and its bodies come grouped by mesh file (primitives under the manifest's path), in order
    of first appearance.
    """
    manifest = _single_manifest(paths)
    if manifest is not None:
        scene = load_scene(manifest)
        groups: dict[str, list[Body]] = {}
        for body in scene.bodies:
            groups.setdefault(body.source or scene.source or body.name, []).append(body)
        yield from groups.items()
        return
    used: set[str] = set()
    for path in paths:
        bodies: list[Body] = []
        for body in load_mesh(path):
            name, k = body.name, 2
            while name in used:
                name = f"{body.name}#{k}"
                k += 1
            used.add(name)
            bodies.append(body if name == body.name else dataclasses.replace(body, name=name))
        yield os.fspath(path), bodies


def rotation_from_quaternion(quaternion: Sequence[float]) -> np.ndarray:
    """Rotation matrix of a quaternion ``[w, x, y, z]`` (normalised first).

    Returns
    -------
    (3, 3) float64
        Proper rotation. Raises ValueError for a zero or non-finite quaternion.
    """
    q = np.asarray(quaternion, dtype=np.float64)
    norm = float(np.linalg.norm(q))
    if not math.isfinite(norm) or norm < 1e-12:
        raise ValueError("quaternion must be non-zero and finite")
    w, x, y, z = q / norm
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
        except ValueError:
            raise SceneError(f"{label}: {field}.quaternion must not be zero", source) from None
    return rotation_from_euler(spec["euler_deg"], spec["order"])


def _pose(position, rotation, label: str, field: str, source: str) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = _rotation(rotation, label, field, source)
    if position is not None:
        matrix[:3, 3] = position
    return matrix


def _end_pose(spec: dict, start: np.ndarray, duration, label: str, source: str):
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
        return end
    if by_velocity:
        if duration is None:
            field = "velocity" if "velocity" in spec else "angular_velocity"
            raise SceneError(f"{label}: {field} needs the manifest's 'duration'", source)
        end = start.copy()
        end[:3, 3] += np.asarray(spec.get("velocity", [0.0, 0.0, 0.0]), dtype=float) * duration
        turn = np.asarray(spec.get("angular_velocity", [0.0, 0.0, 0.0]), dtype=float) * duration
        end[:3, :3] = _rotation_vector(turn) @ start[:3, :3]
        return end
    return None


def _rotation_vector(vector: np.ndarray) -> np.ndarray:
    """Rodrigues' formula: rotation by ``|v|`` radians about ``v / |v|``."""
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return np.eye(3)
    k = vector / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * (cross @ cross)


def _scale(value) -> np.ndarray:
    if value is None:
        return np.ones(3)
    if isinstance(value, list):
        return np.asarray(value, dtype=np.float64)
    return np.full(3, float(value))


def _mesh_bodies(
    spec, manifest: Path, source, label, start, end, scale, files: dict[str, list[Body]]
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
    stretch = np.diag([*scale, 1.0])
    bodies = []
    for sub in loaded:
        rigid, linear = split_rigid(stretch @ sub.pose)
        vertices, faces = sub.vertices, sub.faces
        if linear is not None:
            vertices = vertices @ linear.T
            if np.linalg.det(linear) < 0:
                faces = faces[:, ::-1]
        sub_name = sub.name.split("/", 1)[1] if len(loaded) > 1 else None
        bodies.append(
            Body(
                name=spec["name"] if sub_name is None else f"{spec['name']}/{sub_name}",
                source=mesh_source,
                vertices=np.ascontiguousarray(vertices),
                faces=np.ascontiguousarray(faces),
                pose=start @ rigid,
                end_pose=None if end is None else end @ rigid,
                collider=spec.get("shape"),
            )
        )
    return bodies


def _primitive_body(spec, source, label, start, end, scale) -> Body:
    import trimesh

    options = spec["primitive"]
    kind = options["type"]
    if kind == "box":
        size = np.asarray(options["size"], dtype=np.float64) * scale
        primitive: Primitive = Box((float(size[0]), float(size[1]), float(size[2])))
        mesh = trimesh.creation.box(extents=size)
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
        if kind == "sphere":
            mesh = trimesh.creation.icosphere(subdivisions=_SPHERE_SUBDIVISIONS, radius=radius)
        elif kind == "capsule":
            mesh = trimesh.creation.capsule(
                height=length, radius=radius, count=[_ROUND_SECTIONS, _ROUND_SECTIONS]
            )
        else:
            mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=_ROUND_SECTIONS)
    return Body(
        name=spec["name"],
        source=source,
        vertices=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
        faces=np.ascontiguousarray(mesh.faces, dtype=np.int64),
        pose=start,
        end_pose=end,
        primitive=primitive,
        collider=spec.get("shape"),
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
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise SceneError("manifest is not UTF-8 text", source) from None
    if file.suffix.lower() == ".toml":
        if sys.version_info >= (3, 11):
            import tomllib
        else:
            import tomli as tomllib
        try:
            document = tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            raise SceneError(f"invalid TOML: {str(error).splitlines()[0]}", source) from None
    else:
        try:
            document = json.loads(text)
        except json.JSONDecodeError as error:
            raise SceneError(
                f"invalid JSON at line {error.lineno} column {error.colno}: {error.msg}", source
            ) from None
    return document


def _first_non_finite(value: Any, path: list) -> list | None:
    if isinstance(value, float) and not math.isfinite(value):
        return path
    items = (
        value.items()
        if isinstance(value, dict)
        else (enumerate(value) if isinstance(value, list) else ())
    )
    for key, item in items:
        found = _first_non_finite(item, [*path, key])
        if found is not None:
            return found
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
_SHAPES = frozenset({"hull", "decomposed", "mesh"})
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
    if type(document) is not dict or not document.keys() <= _TOP_FIELDS:
        return False
    units = document.get("units", "m")
    duration = document.get("duration", 1.0)
    bodies = document.get("bodies")
    if type(units) is not str or not units:
        return False
    if not _is_number(duration) or not duration > 0:
        return False
    if type(bodies) is not list or not bodies:
        return False
    for body in bodies:
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
    if _plainly_valid(document):
        return
    where = _first_non_finite(document, [])
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
