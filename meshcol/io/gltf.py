"""glTF 2.0 files (``.gltf`` JSON, ``.glb`` binary): their references checked, their mesh nodes
read by trimesh and put back in the file's node order, one body per node (its primitives
together).

trimesh indexes the file's lists with its references: a negative index silently takes an
object from the end, a missing one fails with an unnamed IndexError or KeyError. Every
reference is checked first and a bad one named (``node 3 refers to mesh 7, but the file has
2 meshes``).
"""

from __future__ import annotations

import io
import json
import struct
from collections.abc import Callable
from itertools import groupby
from operator import itemgetter
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.body_names import ancestor_names
from meshcol.io.mesh_trimesh import load_scene, local_uri, scene_nodes
from meshcol.io.paths import confine_uris
from meshcol.io.safe_read import read_input

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = ["check_references", "mesh_node_indices", "read_document", "read_glb", "read_gltf"]

#: A mesh node of a glTF file as read (:data:`meshcol.io.mesh_formats.MeshNode`) with the
#: index of the document's node it comes from.
IndexedNode = tuple[int, "MeshNode"]


def read_gltf(file: Path, source: str) -> list[MeshNode]:
    """The mesh nodes of a ``.gltf`` file, in the file's node order."""
    return _read_nodes(file, source, "gltf")


def read_glb(file: Path, source: str) -> list[MeshNode]:
    """The mesh nodes of a ``.glb`` file, in the file's node order."""
    return _read_nodes(file, source, "glb")


def mesh_node_indices(file: Path, source: str) -> list[IndexedNode]:
    """Each mesh node :func:`read_glb`/:func:`read_gltf` return, in the same order, with the
    index of the document's node it comes from (one per node, its primitives together): what
    a body read from the file is matched back to (``--to gltf-physics``), whatever the
    nodes' names (missing, repeated)."""
    kind = "glb" if file.suffix.lower() == ".glb" else "gltf"
    return _read_indexed(file, source, kind)


def _read_nodes(file: Path, source: str, kind: str) -> list[MeshNode]:
    """The mesh nodes of a glTF (``kind`` ``gltf``) or GLB file."""
    return [node for _, node in _read_indexed(file, source, kind)]


def _read_indexed(file: Path, source: str, kind: str) -> list[IndexedNode]:
    """The mesh nodes of a glTF or GLB file with their node indices: read once through the
    guarded read, its document checked, then trimesh's scene of the same bytes."""
    data = read_input(source, "mesh")
    document = _glb_json(data, source) if kind == "glb" else _gltf_json(data, source)
    check_references(document, kind.upper(), source)
    scene = load_scene(file, kind, source, io.BytesIO(data))
    nodes = scene_nodes(scene)
    indices = _node_indices(document, scene, [n[0] for n in nodes], source)
    names, parent = _node_names(document), _parents(document)
    # the document's node order (a node's primitives in trimesh's order): trimesh's graph
    # order differs, and its frame names (mesh_1, <name>_<hash>) are not the nodes'
    ordered = sorted(zip(indices, nodes), key=itemgetter(0))
    return [
        (
            k,
            (
                _own_name(document, k) or group[0][0],
                *_one_mesh(group),
                ancestor_names(k, parent, names),
            ),
        )
        for k, group in (
            (k, [node for _, node in run]) for k, run in groupby(ordered, itemgetter(0))
        )
    ]


def _one_mesh(primitives: list[MeshNode]) -> tuple[np.ndarray, object, object]:
    """``(matrix, vertices, faces)`` of one node's primitives as one mesh: a node is one
    object, its primitives the parts drawn with different materials. So a node is one body,
    as a COLLADA node of several geometries is, as a rigid body's collider is in the
    physics extensions, and as engines import a node (a mesh of submeshes); the two
    primitives of Genesis's camera.glb were checked as two bodies penetrating each other.
    trimesh hangs each primitive under the node with an identity matrix, so all share the
    node's frame (the first's)."""
    matrix = primitives[0][1]
    if len(primitives) == 1:
        return matrix, primitives[0][2], primitives[0][3]
    blocks_v, blocks_f, base = [], [], 0
    for _, _, points, triangles, _ in primitives:
        points = np.asarray(points, dtype=np.float64)
        blocks_v.append(points)
        blocks_f.append(np.asarray(triangles, dtype=np.int64) + base)
        base += len(points)
    return matrix, np.concatenate(blocks_v), np.concatenate(blocks_f)


def _own_name(document: Any, k: int) -> str | None:
    """The name document node ``k`` has (None: none): a mesh node's body is named so, not as
    trimesh renames a repeated name (``mesh_1``) or the frame of each of a node's primitives
    (``<name>_<hash>``); an unnamed node keeps trimesh's name."""
    node = document.get("nodes", [])[k]
    name = node.get("name") if isinstance(node, dict) else None
    return name if isinstance(name, str) and name else None


def _node_names(document: Any) -> list[str]:
    """Each document node's name, its index for one without (as trimesh names its frame)."""
    out = []
    for k, node in enumerate(document.get("nodes", [])):
        name = node.get("name") if isinstance(node, dict) else None
        out.append(name if isinstance(name, str) and name else str(k))
    return out


def _parents(document: Any) -> dict[int, int]:
    """Each document node's parent (checked: one each, no cycle)."""
    parent = {}
    for k, node in enumerate(document.get("nodes", [])):
        for child in node.get("children", []) if isinstance(node, dict) else []:
            parent[child] = k
    return parent


def _node_indices(document: Any, scene: Any, frames: list[str], source: str) -> list[int]:
    """The document node each of trimesh's frames ``frames`` stands for. trimesh names the
    frame of node ``i`` ``unique_name(name or str(i))`` in node order (a node named as its
    base frame renamed), and a node of several primitives has one child frame per primitive;
    the same names are made here, so repeated and missing names are told apart."""
    from trimesh.exchange.gltf import DEFAULT_BASE_FRAME
    from trimesh.util import unique_name

    nodes = document.get("nodes", [])
    name_index: dict[str, int] = {}
    counts: dict[str | None, int] = {}
    for i, node in enumerate(nodes):
        name = node.get("name", str(i)) if isinstance(node, dict) else str(i)
        name_index[unique_name(name, name_index, counts=counts)] = i
    names = {v: k for k, v in name_index.items()}
    world = name_index.get(DEFAULT_BASE_FRAME)
    if world is not None:
        names[world] = unique_name(DEFAULT_BASE_FRAME, set(names.values()))
    index_of = {name: i for i, name in names.items()}
    parents = scene.graph.transforms.parents
    out = []
    for frame in frames:
        index = index_of.get(frame, index_of.get(parents.get(frame, None)))
        if index is None:  # trimesh named a frame otherwise: a change of trimesh's
            raise InvalidMeshError(
                f"cannot parse {'GLB' if source.lower().endswith('.glb') else 'GLTF'} file: "
                f"mesh frame {frame!r} matches no node",
                source,
            )
        out.append(index)
    return out


def _decode_json(text: bytes, kind: str, source: str) -> Any:
    """A glTF document's JSON (a GLB's JSON chunk), every problem one line."""
    try:
        return json.loads(text.decode("utf-8-sig"))
    except json.JSONDecodeError as error:
        raise InvalidMeshError(
            f"cannot parse {kind} file: invalid JSON at line {error.lineno} column "
            f"{error.colno}: {error.msg}",
            source,
        ) from None
    except UnicodeDecodeError:
        raise InvalidMeshError(f"cannot parse {kind} file: not UTF-8 text", source) from None
    except RecursionError:
        raise InvalidMeshError(
            f"cannot parse {kind} file: its JSON nests arrays and objects too deep", source
        ) from None
    except ValueError as error:  # an integer of thousands of digits
        raise InvalidMeshError(
            f"cannot parse {kind} file: {str(error).splitlines()[0][:120]}", source
        ) from None


def _gltf_json(data: bytes, source: str) -> Any:
    return _decode_json(data, "GLTF", source)


def _glb_json(data: bytes, source: str) -> Any:
    """The JSON chunk of a GLB file, its header and chunk lengths checked (glTF 2.0, 4.4: the
    header's length is the file's, every chunk lies within it)."""
    if len(data) < 20 or data[:4] != b"glTF":
        raise InvalidMeshError("cannot parse GLB file: no glTF binary header", source)
    version, total, length, kind = struct.unpack("<III4s", data[4:20])
    if version != 2:
        raise InvalidMeshError(
            f"cannot parse GLB file: version {version} (only glTF 2.0 is read)", source
        )
    if total != len(data):
        raise InvalidMeshError(
            f"cannot parse GLB file: its header says {total} bytes, the file has {len(data)}",
            source,
        )
    if kind != b"JSON" or 20 + length > len(data):
        raise InvalidMeshError("cannot parse GLB file: the first chunk is not JSON", source)
    end = 20 + length
    while end < len(data):  # the chunks after the JSON one (the BIN chunk) fit in the file
        if end + 8 > len(data):
            raise InvalidMeshError(
                f"cannot parse GLB file: a chunk header is cut off at byte {end}", source
            )
        (chunk,) = struct.unpack("<I", data[end : end + 4])
        if end + 8 + chunk > len(data):
            raise InvalidMeshError(
                f"cannot parse GLB file: the chunk at byte {end} says {chunk} bytes, past the "
                "end of the file",
                source,
            )
        end += 8 + chunk
    return _decode_json(data[20 : 20 + length], "GLB", source)


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


class _Document:
    """A glTF document's lists, and a check that a reference names one of their items."""

    def __init__(self, document: Any, kind: str, source: str) -> None:
        if not isinstance(document, dict):
            raise InvalidMeshError(f"cannot parse {kind} file: the JSON is not an object", source)
        self.document, self.kind, self.source = document, kind, source

    def items(self, name: str) -> list:
        value = self.document.get(name, [])
        if not isinstance(value, list):
            raise self.error(f"'{name}' is not an array")
        return value

    def check(self, where: str, value: Any, name: str) -> None:
        count = len(self.items(name))
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < count:
            raise self.error(
                f"{where} refers to {_SINGULAR[name]} {value!r}, but the file has {count} {name}"
            )

    def error(self, problem: str) -> InvalidMeshError:
        return InvalidMeshError(f"cannot parse {self.kind} file: {problem}", self.source)


def check_references(document: Any, kind: str, source: str) -> None:
    """Refuse references to objects the glTF document does not have, naming the reference
    (``kind``: ``GLTF`` or ``GLB``, for the message)."""
    gltf = _Document(document, kind, source)
    confine_uris(document, source)  # every buffer and image file inside --root (io.paths)
    for check in _CHECKS:
        check(gltf)


def _check_scenes(gltf: _Document) -> None:
    for k, scene in enumerate(gltf.items("scenes")):
        roots = scene.get("nodes", []) if isinstance(scene, dict) else []
        if not isinstance(roots, list):
            raise gltf.error(f"scene {k} nodes is not an array")
        for node in roots:
            gltf.check(f"scene {k}", node, "nodes")
    if "scene" in gltf.document:
        gltf.check("'scene'", gltf.document["scene"], "scenes")


def _check_nodes(gltf: _Document) -> None:
    parent: dict[int, int] = {}
    for k, node in enumerate(gltf.items("nodes")):
        if not isinstance(node, dict):
            continue
        children = node.get("children", [])
        if not isinstance(children, list):
            raise gltf.error(f"node {k} children is not an array")
        for child in children:
            gltf.check(f"node {k} children", child, "nodes")
            if child in parent or child == k:
                raise gltf.error(f"node {child} has two parents or is its own child")
            parent[child] = k
        if "mesh" in node:
            gltf.check(f"node {k}", node["mesh"], "meshes")
    done: set[int] = set()  # glTF 2.0, 3.5.3: the nodes form disjoint trees, no cycle
    for k in sorted(parent):
        path: set[int] = set()
        current = k
        while current in parent and current not in done:
            if current in path:
                raise gltf.error(f"node {k}'s parents form a cycle")
            path.add(current)
            current = parent[current]
        done |= path


def _check_meshes(gltf: _Document) -> None:
    for k, mesh in enumerate(gltf.items("meshes")):
        primitives = mesh.get("primitives", []) if isinstance(mesh, dict) else []
        for j, primitive in enumerate(primitives):
            if not isinstance(primitive, dict):
                continue
            attributes = primitive.get("attributes", {})
            if isinstance(attributes, dict) and "POSITION" in attributes:
                where = f"mesh {k} primitive {j} POSITION"
                gltf.check(where, attributes["POSITION"], "accessors")
            if "indices" in primitive:
                gltf.check(f"mesh {k} primitive {j} indices", primitive["indices"], "accessors")


def _check_accessors(gltf: _Document) -> None:
    for k, accessor in enumerate(gltf.items("accessors")):
        if not isinstance(accessor, dict):
            continue
        if "bufferView" in accessor:
            gltf.check(f"accessor {k}", accessor["bufferView"], "bufferViews")
        if accessor.get("componentType") not in _COMPONENT_TYPES:
            raise gltf.error(
                f"accessor {k} has componentType {accessor.get('componentType')!r} (expected "
                f"one of {', '.join(map(str, _COMPONENT_TYPES))})"
            )
        if accessor.get("type") not in _ACCESSOR_TYPES:
            raise gltf.error(
                f"accessor {k} has type {accessor.get('type')!r} (expected one of "
                f"{', '.join(_ACCESSOR_TYPES)})"
            )


def _check_buffers(gltf: _Document) -> None:
    for k, view in enumerate(gltf.items("bufferViews")):
        if isinstance(view, dict):
            gltf.check(f"bufferView {k}", view.get("buffer"), "buffers")
    for k, buffer in enumerate(gltf.items("buffers")):
        # only a GLB's first buffer may leave out its uri (it is the binary chunk)
        if isinstance(buffer, dict) and "uri" not in buffer and (gltf.kind == "GLTF" or k > 0):
            raise gltf.error(
                f"buffer {k} has no uri (only the first buffer of a GLB file may be its binary "
                "chunk)"
            )
        uri = buffer.get("uri") if isinstance(buffer, dict) else None
        if uri is None:
            continue
        if not isinstance(uri, str):
            raise gltf.error(f"buffer {k} has uri {uri!r}, not a string")
        if uri.startswith("data:"):
            if ";base64," not in uri[:200]:
                raise gltf.error(f"buffer {k} is a data: URI that is not base64")
            continue
        problem = local_uri(uri)
        if problem is not None:
            raise gltf.error(f"buffer {k} has uri {uri[:120]!r}: {problem}")


#: Extensions that change how geometry is stored: a reader that does not decode them would read
#: the file's fallback (or nothing) as if it were the mesh. None is decoded here.
_COMPRESSION_EXTENSIONS = {
    "KHR_draco_mesh_compression": "Draco mesh compression",
    "EXT_meshopt_compression": "meshopt compression",
    "KHR_meshopt_compression": "meshopt compression",
}


def _check_required_extensions(gltf: _Document) -> None:
    """Refuse a file that requires an extension which compresses geometry (glTF 2.0, 3.12: a
    loader must not load a file whose required extension it does not support)."""
    required = gltf.items("extensionsRequired")
    for name in required:
        if isinstance(name, str) and name in _COMPRESSION_EXTENSIONS:
            raise gltf.error(
                f"it requires {name} ({_COMPRESSION_EXTENSIONS[name]}), which meshcol does not "
                "decode: export it uncompressed"
            )


_CHECKS: tuple[Callable[[_Document], None], ...] = (
    _check_required_extensions,
    _check_scenes,
    _check_nodes,
    _check_meshes,
    _check_accessors,
    _check_buffers,
)


def read_document(file: Path, source: str) -> tuple[Any, bytes | None]:
    """A ``.gltf`` or ``.glb`` file's JSON document and a GLB's binary chunk (None for
    ``.gltf`` or a GLB without one): for the physics extensions' reader
    (:mod:`meshcol.io.gltf_physics`)."""
    data = read_input(file, "mesh")  # the guarded read every glTF reader uses
    if file.suffix.lower() == ".glb":
        return _glb_json(data, source), _glb_binary(data)
    return _gltf_json(data, source), None


def _glb_binary(data: bytes) -> bytes | None:
    """The binary chunk of a GLB file's bytes (after its JSON chunk), or None."""
    if len(data) < 20:
        return None
    length = struct.unpack("<I", data[12:16])[0]
    start = 20 + length + (-length % 4)
    if start + 8 > len(data):
        return None
    size, kind = struct.unpack("<I4s", data[start : start + 8])
    if kind != b"BIN\x00" or start + 8 + size > len(data):
        return None
    return data[start + 8 : start + 8 + size]
