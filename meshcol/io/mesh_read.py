"""Load mesh files (OBJ, STL, PLY, OFF, glTF, GLB) as rigid bodies, geometry only.

A file may hold several bodies: OBJ objects (or groups, when the file has no objects), STL
solids, glTF mesh nodes. Each becomes one :class:`meshcol.types.Body` whose vertices are in its
local frame with any scale, shear or mirror of the scene graph baked in, and whose
``pose`` is the rigid rest of the node's world matrix.

Materials, textures, normals and UVs are never loaded: a textured file loads without Pillow,
and vertices split along UV or normal seams are merged back by position.
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import InputFileError, InvalidMeshError, MissingDependencyError
from meshcol.io.off import read_off
from meshcol.types import Body

__all__ = [
    "MAX_COORDINATE",
    "MESH_EXTENSIONS",
    "check_magnitude",
    "load_mesh",
    "load_meshes",
    "merge_vertices",
    "split_rigid",
]

#: File extensions (lower case) that :func:`load_mesh` reads, mapped to trimesh's file type.
MESH_EXTENSIONS: dict[str, str] = {
    ".obj": "obj",
    ".stl": "stl",
    ".ply": "ply",
    ".off": "off",
    ".glb": "glb",
    ".gltf": "gltf",
}

# A matrix whose linear part is orthonormal to this tolerance is taken as rigid as it is,
# so exact rotations (and identity) stay exact instead of going through an SVD.
_RIGID_TOL = 1e-12

#: Largest coordinate magnitude accepted anywhere (file vertices, and world coordinates after a
#: manifest's scale, pose and motion). Beyond it the 1e-8 merge grid of vertex positions
#: overflows 64-bit integers (at 9.2e10) and the float64 spacing of coordinates (2e-6 at 1e10)
#: is coarser than any contact tolerance; volumes and normals overflow long before 1e308.
MAX_COORDINATE = 1e10


def check_magnitude(values: np.ndarray, what: str, source: str | None) -> None:
    """Raise :class:`InvalidMeshError` when a value of ``values`` exceeds
    :data:`MAX_COORDINATE` in magnitude, naming the first such value (``what`` says whose)."""
    values = np.asarray(values, dtype=np.float64)
    over = np.abs(values) > MAX_COORDINATE
    if over.any():
        first = np.argwhere(over)[0]
        where = f" {int(first[0]) + 1}" if values.ndim == 2 else ""
        raise InvalidMeshError(
            f"{what}{where} has coordinate {values[tuple(first)]:.6g}, beyond the limit of "
            f"+/-{MAX_COORDINATE:g}",
            source,
        )


# Vertices closer than this (per coordinate, absolute) are merged: trimesh's own merge
# tolerance (trimesh.constants.tol.merge), so watertightness agrees with trimesh's processing.
_MERGE_DIGITS = 8

# What trimesh's parsers raise on corrupt content. Listed explicitly rather than catching
# Exception, so programming errors still surface with a traceback.
_PARSE_ERRORS = (
    ValueError,  # includes json.JSONDecodeError and UnicodeDecodeError
    IndexError,
    KeyError,
    TypeError,
    AttributeError,
    AssertionError,
    EOFError,
    OverflowError,
    NotImplementedError,
    struct.error,
    zlib.error,
)


def load_mesh(
    path: str | os.PathLike[str], *, merge: bool = True, collada: bool = False
) -> list[Body]:
    """Load every body of one mesh file.

    Parameters
    ----------
    path : str or path-like
        An ``.obj``, ``.stl`` (ascii or binary), ``.ply``, ``.off``, ``.glb`` or ``.gltf``
        file. Kept verbatim as each body's ``source``.
    merge : bool, optional
        Merge vertices at the same position (to 1e-8, per coordinate), also across UV and
        normal seams, and drop unreferenced vertices. On by default: topology checks
        (watertight, manifold) are only meaningful after it.
    collada : bool, optional
        Also accept ``.dae`` (COLLADA, read by trimesh with pycollada), as robot descriptions
        reference it (:mod:`meshcol.io.robot`); off for the commands' own mesh inputs.

    Returns
    -------
    list of Body
        In file order (glTF: scene-graph order). Named after the file stem when the file holds
        one body, else ``<stem>/<object, solid or node name>``; names are unique.
        ``vertices`` (n, 3) float64 are in the body's local frame with scale baked in;
        ``faces`` (m, 3) int64; ``pose`` (4, 4) is rigid, world from local.

    Raises
    ------
    InputFileError
        Missing, unreadable, a directory, or an unknown extension.
    InvalidMeshError
        Corrupt content, no faces, non-finite coordinates, face indices out of range.

    Notes
    -----
    A node matrix ``M`` with scale, shear or mirror is split by polar decomposition
    (Higham 1986; computed from the SVD ``A = W S V^T``): ``A = R B`` with ``R`` a rotation
    (det +1) and ``B`` symmetric. ``B`` is baked into the vertices and ``R`` with ``M``'s
    translation becomes the transform; when ``det B < 0`` (a mirror) the face winding is
    flipped so that outward normals stay outward.
    """
    source = os.fspath(path)
    file = Path(source)
    if collada and file.suffix.lower() == ".dae":
        if not file.is_file():
            _check_file(file, source)  # missing or a directory: says so
        import importlib.util

        if importlib.util.find_spec("collada") is None:  # trimesh reads COLLADA with it
            raise MissingDependencyError(
                "reading COLLADA (.dae) needs pycollada: pip install 'meshcol[robots]'", source
            )
        file_type = "dae"
    else:
        file_type = _check_file(file, source)
    if file_type in _NATIVE_FORMATS:
        return load_meshes([source], merge=merge)[0]
    nodes = _read_nodes(file, file_type, source)
    if not nodes:
        raise InvalidMeshError("mesh has no faces", source)

    stem = file.stem
    bodies: list[Body] = []
    used: set[str] = set()
    for name, matrix, vertices, faces in nodes:
        vertices = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces, dtype=np.int64)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
            raise InvalidMeshError("mesh is not made of triangles", source)
        if not np.isfinite(vertices).all():
            raise InvalidMeshError("mesh has non-finite vertex coordinates", source)
        check_magnitude(vertices, "vertex", source)
        if not np.isfinite(matrix).all():
            raise InvalidMeshError("scene graph has a non-finite transform", source)
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise InvalidMeshError("face index out of range", source)
        try:
            transform, linear = split_rigid(matrix)
        except InvalidMeshError as error:
            raise InvalidMeshError(error.message, source) from None
        if linear is not None:
            vertices = vertices @ linear.T
            if np.linalg.det(linear) < 0:
                faces = faces[:, ::-1]
        if merge:
            vertices, faces = merge_vertices(vertices, faces)
        full = stem if len(nodes) == 1 else f"{stem}/{name}"
        full = _unique(full, used)
        bodies.append(
            Body(
                name=full,
                source=source,
                vertices=np.ascontiguousarray(vertices),
                faces=np.ascontiguousarray(faces),
                pose=transform,
            )
        )
    return bodies


#: Formats the native core reads (OBJ, binary and ASCII STL), with their code in the core.
_NATIVE_FORMATS = {"obj": 0, "stl": 1}
_CORRUPT = 4  # the core's ReadStatus::Corrupt
_EYE = np.eye(4)  # copied per body: a third of the time of np.eye(4)


def load_meshes(
    paths: Sequence[str | os.PathLike[str]], *, merge: bool = True, threads: int = 0
) -> list[list[Body]]:
    """Load many mesh files at once: :func:`load_mesh` for each, with OBJ and STL files read
    and parsed by the native core in parallel (GIL released).

    Parameters
    ----------
    paths : list of str or path-like
    merge : bool, optional
        As :func:`load_mesh`.
    threads : int, optional
        Reader threads for the OBJ and STL files; 0 means all cores.

    Returns
    -------
    list of list of Body
        One list per path, in order, each as :func:`load_mesh` returns it.

    Raises
    ------
    InputFileError, InvalidMeshError
        As :func:`load_mesh`, for the first path (in order) that fails.

    Notes
    -----
    The native readers: OBJ ``v`` and ``f`` lines (any encoding; comments, ``vt``, ``vn``,
    materials and everything else skipped), polygons fan-triangulated, 1-based or negative
    (relative) indices, never 0 or out of range; ``o`` lines start bodies, or ``g`` lines when
    the file has none. STL: binary when the size is 84 + 50 x the triangle count, else ASCII
    (one body per ``solid``). Other formats go through trimesh, one file at a time.
    """
    from meshcol._native import core

    sources = [os.fspath(p) for p in paths]
    types = []
    for source in sources:
        try:
            types.append(_file_type(source))
        except InputFileError:
            _check_file(Path(source), source)  # a missing file or a directory says so first
            raise
    native = [i for i, t in enumerate(types) if t in _NATIVE_FORMATS]
    out: list[list[Body] | None] = [None] * len(sources)
    if native:
        vertices, faces, v_off, f_off, owner, raw_names, status, raw_errors = core.read_mesh_files(
            [sources[i] for i in native],
            [_NATIVE_FORMATS[types[i]] for i in native],
            merge=merge,
            threads=threads,
        )
        # one vectorised pass finds the objects with a coordinate beyond the limit
        big_rows = np.flatnonzero((np.abs(vertices) > MAX_COORDINATE).any(axis=1))
        big = (
            set(np.searchsorted(v_off, big_rows, side="right").tolist()) if len(big_rows) else set()
        )
        if (
            not big
            and len(owner) == len(native)
            and bool((owner == np.arange(len(native))).all())
            and not status.any()
        ):
            # The common scene: every file read, one object each, no coordinate too big. Each
            # body is what the loop below builds (a lone object is named by its file's stem).
            vo, fo = v_off.tolist(), f_off.tolist()
            for j, i in enumerate(native):
                out[i] = [
                    Body(
                        name=_stem(sources[i]),
                        source=sources[i],
                        vertices=vertices[vo[j] : vo[j + 1]],
                        faces=faces[fo[j] : fo[j + 1]],
                        pose=_EYE.copy(),
                    )
                ]
        else:
            names = [_text(n) for n in raw_names]
            errors = [_text(e) for e in raw_errors]
            per_file: list[list[int]] = [[] for _ in native]
            for k, f in enumerate(owner.tolist()):
                per_file[f].append(k)
            for j, i in enumerate(native):
                if status[j] == _CORRUPT:
                    raise InvalidMeshError(
                        f"cannot parse {types[i].upper()} file: {errors[j]}", sources[i]
                    )
                if status[j] != 0:
                    raise InputFileError(errors[j], sources[i])
                objects = per_file[j]
                if not objects:
                    raise InvalidMeshError("mesh has no faces", sources[i])
                stem = _stem(sources[i])
                used: set[str] = set()
                bodies = []
                for k in objects:
                    if k + 1 in big:
                        check_magnitude(vertices[v_off[k] : v_off[k + 1]], "vertex", sources[i])
                    name = names[k] or ("default" if types[i] == "obj" else stem)
                    full = _unique(stem if len(objects) == 1 else f"{stem}/{name}", used)
                    bodies.append(
                        Body(
                            name=full,
                            source=sources[i],
                            vertices=vertices[v_off[k] : v_off[k + 1]],
                            faces=faces[f_off[k] : f_off[k + 1]],
                            pose=_EYE.copy(),
                        )
                    )
                out[i] = bodies
    for i in range(len(sources)):
        if out[i] is None:
            out[i] = load_mesh(sources[i], merge=merge)
    return out  # type: ignore[return-value]


def _stem(source: str) -> str:
    """``Path(source).stem`` without building a Path (a scene may name 100,000 files)."""
    name = (
        os.path.basename(source.rstrip("/")) if source.endswith("/") else os.path.basename(source)
    )
    dot = name.rfind(".")
    return name[:dot] if 0 < dot < len(name) - 1 else name


def _text(data: bytes) -> str:
    """Bytes of a file as text: UTF-8, else Latin-1 (which maps every byte)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def split_rigid(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Split an affine 4x4 matrix into a rigid transform and a linear part to bake.

    Parameters
    ----------
    matrix : (4, 4) float
        Affine, world from local (row-major; last row ``0 0 0 1``).

    Returns
    -------
    rigid : (4, 4) float64
        Rotation (det +1) and the matrix's translation.
    linear : (3, 3) float64 or None
        Symmetric part ``B`` with ``matrix[:3, :3] == rigid[:3, :3] @ B``, to apply to local
        vertices; None when the matrix is already rigid (to 1e-12).

    Raises
    ------
    InvalidMeshError
        When the linear part is singular (a zero scale flattens the mesh).

    Notes
    -----
    Polar decomposition from the SVD ``A = W S V^T``: ``R = W V^T`` and ``B = V S V^T``
    (Higham 1986). If ``det R < 0`` the singular vector of the smallest singular value is
    negated, which moves the mirror into ``B`` (then ``det B < 0``) and keeps ``R`` proper.
    """
    matrix = np.asarray(matrix, dtype=np.float64)
    linear = matrix[:3, :3]
    rigid = np.eye(4)
    rigid[:3, 3] = matrix[:3, 3]
    if np.abs(linear.T @ linear - np.eye(3)).max() <= _RIGID_TOL and np.linalg.det(linear) > 0:
        rigid[:3, :3] = linear
        return rigid, None
    w, s, vt = np.linalg.svd(linear)
    if s[-1] <= s[0] * 1e-12:
        raise InvalidMeshError("scene graph transform is singular (zero scale)")
    if np.linalg.det(w @ vt) < 0:
        w[:, -1] = -w[:, -1]
        s = s.copy()
        s[-1] = -s[-1]
    rigid[:3, :3] = w @ vt
    return rigid, (vt.T * s) @ vt


def merge_vertices(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices at the same position and drop unreferenced ones.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    vertices : (k, 3) float64
        Unique positions, in the input order of their first occurrence.
    faces : (m, 3) int64
        The same triangles (none removed, even if one becomes degenerate).

    Notes
    -----
    Positions are compared after rounding to 8 decimals, trimesh's merge tolerance, and
    only positions count: normals and UVs are ignored, so UV seams close.
    """
    from meshcol._native import core

    vertices = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    return core.merge_vertices(vertices, faces, _MERGE_DIGITS)


def _file_type(source: str) -> str:
    """The file type of ``source`` from its extension (InputFileError when unknown)."""
    file_type = MESH_EXTENSIONS.get(os.path.splitext(source)[1].lower())
    if file_type is None:
        known = ", ".join(MESH_EXTENSIONS)
        suffix = os.path.splitext(source)[1] or "(none)"
        raise InputFileError(f"unknown mesh file extension {suffix!r} (expected {known})", source)
    return file_type


def _check_file(file: Path, source: str) -> str:
    if not file.exists():
        raise InputFileError("file not found", source)
    if file.is_dir():
        raise InputFileError("is a directory, not a mesh file", source)
    file_type = _file_type(source)
    try:
        with open(file, "rb"):
            pass
    except OSError as error:
        raise InputFileError(f"cannot read file: {error.strerror or error}", source) from None
    return file_type


def _read_nodes(file: Path, file_type: str, source: str) -> list:
    """``(name, matrix, vertices, faces)`` of every mesh node of a PLY, OFF or glTF/GLB file,
    in file order (OBJ and STL go to the core's readers, :func:`load_meshes`)."""
    if file_type == "off":
        off_vertices, off_faces = read_off(_read_bytes(file, source), source)
        return [(file.stem, np.eye(4), off_vertices, off_faces)] if len(off_faces) else []
    scene = _read_scene(file, file_type, source)
    nodes = []
    for node in scene.graph.nodes_geometry:
        matrix, geometry_name = scene.graph[node]
        geometry = scene.geometry[geometry_name]
        faces = getattr(geometry, "faces", None)
        if faces is None or len(faces) == 0:
            continue  # point clouds, paths, faceless meshes: not bodies
        name = geometry_name if file_type == "ply" else str(node)
        nodes.append((name, np.asarray(matrix, dtype=np.float64), geometry.vertices, faces))
    if file_type in ("glb", "gltf"):
        nodes = _gltf_file_order(file, file_type, nodes)
    return nodes


def _read_bytes(file: Path, source: str) -> bytes:
    try:
        return file.read_bytes()
    except OSError as error:
        raise InputFileError(f"cannot read file: {error.strerror or error}", source) from None


def _read_scene(file: Path, file_type: str, source: str):
    import io

    import trimesh

    options: dict = {"process": False}
    stream = None
    if file_type == "ply":
        header = _ply_bytes(file, source)
        if header is not None:
            stream = io.BytesIO(header)
    elif file_type == "gltf":
        _check_gltf(_check_json(file, source), "GLTF", source)
    elif file_type == "glb":
        _check_gltf(_glb_json(file, source), "GLB", source)
    try:
        if stream is not None:
            stream.name = file.name  # trimesh names an unnamed object after it
            return trimesh.load_scene(stream, file_type=file_type, **options)
        return trimesh.load_scene(str(file), file_type=file_type, **options)
    except FileNotFoundError as error:
        # a glTF buffer or image the file refers to
        raise InvalidMeshError(
            f"cannot parse {file_type.upper()} file: referenced file {error.args[-1]!r} not found",
            source,
        ) from None
    except _PARSE_ERRORS as error:
        detail = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise InvalidMeshError(
            f"cannot parse {file_type.upper()} file: {detail[:200]}", source
        ) from None


def _ply_bytes(file: Path, source: str) -> bytes | None:
    """A PLY file whose header (comments, obj_info) is not UTF-8, with the header re-encoded
    from Latin-1; None when the file needs nothing (the data after the header is untouched)."""
    data = _read_bytes(file, source)
    end = data.find(b"end_header")
    if end < 0:
        return None
    try:
        data[:end].decode("utf-8")
        return None
    except UnicodeDecodeError:
        return data[:end].decode("latin-1").encode("utf-8") + data[end:]


def _check_json(file: Path, source: str) -> Any:
    import json

    try:
        return json.loads(file.read_bytes().decode("utf-8-sig"))
    except json.JSONDecodeError as error:
        raise InvalidMeshError(
            f"cannot parse GLTF file: invalid JSON at line {error.lineno} column {error.colno}: "
            f"{error.msg}",
            source,
        ) from None
    except UnicodeDecodeError:
        raise InvalidMeshError("cannot parse GLTF file: not UTF-8 text", source) from None


def _glb_json(file: Path, source: str) -> Any:
    """The JSON chunk of a GLB file (its header checked)."""
    import json

    data = file.read_bytes()
    if len(data) < 20 or data[:4] != b"glTF":
        raise InvalidMeshError("cannot parse GLB file: no glTF binary header", source)
    length, kind = struct.unpack("<I4s", data[12:20])
    if kind != b"JSON" or 20 + length > len(data):
        raise InvalidMeshError("cannot parse GLB file: the first chunk is not JSON", source)
    try:
        return json.loads(data[20 : 20 + length].decode("utf-8-sig"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise InvalidMeshError(
            "cannot parse GLB file: its JSON chunk is not valid", source
        ) from None


_SINGULAR = {
    "scenes": "scene",
    "nodes": "node",
    "meshes": "mesh",
    "accessors": "accessor",
    "bufferViews": "bufferView",
    "buffers": "buffer",
}
# glTF 2.0: byte, unsigned byte, short, unsigned short, unsigned int, float
_COMPONENT_TYPES = (5120, 5121, 5122, 5123, 5125, 5126)
_ACCESSOR_TYPES = ("SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4")


def _check_gltf(document: Any, kind: str, source: str) -> None:
    """Refuse references to objects the glTF file does not have, naming the reference.

    trimesh would index its lists with them: a negative index silently takes an object from
    the end, a missing one fails with an unnamed IndexError or KeyError.
    """
    if not isinstance(document, dict):
        raise InvalidMeshError(f"cannot parse {kind} file: the JSON is not an object", source)

    def items(name: str) -> list:
        value = document.get(name, [])
        if not isinstance(value, list):
            raise InvalidMeshError(f"cannot parse {kind} file: '{name}' is not an array", source)
        return value

    def check(where: str, value: Any, name: str) -> None:
        count = len(items(name))
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < count:
            raise InvalidMeshError(
                f"cannot parse {kind} file: {where} refers to {_SINGULAR[name]} {value!r}, but "
                f"the file has {count} {name}",
                source,
            )

    for k, scene in enumerate(items("scenes")):
        for node in scene.get("nodes", []) if isinstance(scene, dict) else []:
            check(f"scene {k}", node, "nodes")
    if "scene" in document:
        check("'scene'", document["scene"], "scenes")
    for k, node in enumerate(items("nodes")):
        if not isinstance(node, dict):
            continue
        for child in node.get("children", []):
            check(f"node {k} children", child, "nodes")
        if "mesh" in node:
            check(f"node {k}", node["mesh"], "meshes")
    for k, mesh in enumerate(items("meshes")):
        primitives = mesh.get("primitives", []) if isinstance(mesh, dict) else []
        for j, primitive in enumerate(primitives):
            if not isinstance(primitive, dict):
                continue
            attributes = primitive.get("attributes", {})
            for attribute in ("POSITION",):
                if isinstance(attributes, dict) and attribute in attributes:
                    check(f"mesh {k} primitive {j} {attribute}", attributes[attribute], "accessors")
            if "indices" in primitive:
                check(f"mesh {k} primitive {j} indices", primitive["indices"], "accessors")
    for k, accessor in enumerate(items("accessors")):
        if not isinstance(accessor, dict):
            continue
        if "bufferView" in accessor:
            check(f"accessor {k}", accessor["bufferView"], "bufferViews")
        if accessor.get("componentType") not in _COMPONENT_TYPES:
            raise InvalidMeshError(
                f"cannot parse {kind} file: accessor {k} has componentType "
                f"{accessor.get('componentType')!r} (expected one of "
                f"{', '.join(map(str, _COMPONENT_TYPES))})",
                source,
            )
        if accessor.get("type") not in _ACCESSOR_TYPES:
            raise InvalidMeshError(
                f"cannot parse {kind} file: accessor {k} has type {accessor.get('type')!r} "
                f"(expected one of {', '.join(_ACCESSOR_TYPES)})",
                source,
            )
    for k, view in enumerate(items("bufferViews")):
        if isinstance(view, dict):
            check(f"bufferView {k}", view.get("buffer"), "buffers")
    for k, buffer in enumerate(items("buffers")):
        # only a GLB's first buffer may leave out its uri (it is the binary chunk)
        if isinstance(buffer, dict) and "uri" not in buffer and (kind == "GLTF" or k > 0):
            raise InvalidMeshError(
                f"cannot parse {kind} file: buffer {k} has no uri (only the first buffer of a "
                "GLB file may be its binary chunk)",
                source,
            )


def _gltf_file_order(file: Path, file_type: str, nodes: list) -> list:
    """Order glTF mesh nodes as the file's node list does (trimesh's graph order differs)."""
    import json

    data = file.read_bytes()
    if file_type == "glb":
        length = struct.unpack("<I", data[12:16])[0]
        data = data[20 : 20 + length]
    index: dict[str, int] = {}
    for k, node in enumerate(json.loads(data).get("nodes", [])):
        index.setdefault(str(node.get("name", "")), k)
    # unnamed nodes keep trimesh's relative order, after the named ones
    return sorted(nodes, key=lambda item: index.get(item[0], len(index)))


def _unique(name: str, used: set[str]) -> str:
    candidate, k = name, 2
    while candidate in used:
        candidate = f"{name}#{k}"
        k += 1
    used.add(candidate)
    return candidate
