"""FBX files (binary 7.x and ASCII), read with ufbx: every mesh node at its world transform,
in metres, in meshcol's frame.

ufbx (the ``ufbx`` package, Python bindings of the single-file C loader) evaluates each
node's whole FBX transform: translation, rotation with its order, pre- and post-rotation,
rotation and scaling offsets and pivots, scaling, the inherit type, and the geometric
transform that applies to the geometry only (``geometry_to_world``). The file's
``UnitScaleFactor`` and its axes (``UpAxis``, ``FrontAxis``, ``CoordAxis`` and their signs)
are converted by ufbx to :data:`FRAME`: right-handed, Z up, -Y front, +X right, in metres (the
frame of Blender, of URDF and MJCF, and of the USD meshcol writes). Bodies read from FBX
report ``units = "m"``.

Only geometry is read: materials, textures, skins and blend shapes (the mesh at its bind
pose), cameras, lights and animation (the rest pose) are left out, never an error
(:func:`ignored` says what a file had). Polygons are split as OFF's are (a fan from the first
corner when convex, as the OBJ reader does; ear clipping when not); point and line faces
carry no area and are skipped. A mesh instanced by several nodes is one body per node.

Untrusted input: a declared count is never trusted beyond the file's content (ufbx ignores
an ASCII array's count and refuses a binary array that does not fit), a parent chain deeper
than :data:`MAX_NODE_DEPTH` or a cyclic one is refused, and so is a file of more than
:data:`MAX_INDICES` polygon corners before they are copied; each failure is one ``cannot
parse FBX file: ...`` line, a truncated binary file's naming the record it cuts.
"""

from __future__ import annotations

import ctypes
import gc
import struct
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.body_names import ancestor_names
from meshcol.io.polygons import triangulate_polygons
from meshcol.io.safe_read import read_input

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = [
    "FRAME",
    "MAX_INDICES",
    "MAX_NODE_DEPTH",
    "UNITS",
    "ignored",
    "polygon_triangles",
    "read_fbx",
]

#: The frame FBX geometry is converted to (documented in ARCHITECTURE.md, "FBX").
FRAME = "right-handed, +Z up, -Y front, +X right"
#: The units FBX geometry is converted to, reported in the envelope's ``units``.
UNITS = "m"
#: Deepest parent chain accepted (a cyclic or hostile hierarchy stops here).
MAX_NODE_DEPTH = 512
#: Most polygon-vertex indices in one file (about 2 GB of int64 triangles).
MAX_INDICES = 200_000_000


def _load(file: Path, source: str, **options: Any) -> Any:
    """The ufbx scene of ``file``, converted to metres and :data:`FRAME`. The bytes are read
    once by the guarded reader (a pipe, a device or a file over the cap is refused before
    ufbx sees it; ufbx opening the path itself would block on a pipe) and parsed in memory."""
    import ufbx

    data = read_input(file, "mesh")
    try:
        return ufbx.load_memory(
            data,
            file_format=ufbx.FileFormat.FBX,  # never OBJ, which ufbx also reads
            no_format_from_content=True,
            target_axes=ufbx.axes_right_handed_z_up,
            target_unit_meters=1.0,
            space_conversion=ufbx.SpaceConversion.TRANSFORM_ROOT,
            ignore_embedded=True,
            load_external_files=False,
            node_depth_limit=MAX_NODE_DEPTH,
            **({"ignore_animation": True} | options),
        )
    except ufbx.UfbxError as error:
        reason = _truncation(data) or _reason(error)
        raise InvalidMeshError(f"cannot parse FBX file: {reason}", source) from None


def _reason(error: Exception) -> str:
    """ufbx's error as one line, lower case."""
    text = " ".join(str(error).split()) or type(error).__name__
    return text[:1].lower() + text[1:]


_BINARY_MAGIC = b"Kaydara FBX Binary  \x00"


def _truncation(data: bytes) -> str | None:
    """How a binary FBX file's bytes ``data`` are cut short, when they are: the first
    top-level record that ends past their end (ufbx says only ``failed to load``); None
    otherwise."""
    if not data.startswith(_BINARY_MAGIC) or len(data) < 27:
        return None
    version = int.from_bytes(data[23:27], "little")
    wide = version >= 7500  # 64-bit record headers from FBX 7.5
    head = 25 if wide else 13
    at = 27
    while at + head <= len(data):
        if wide:
            end, _, _ = struct.unpack_from("<QQQ", data, at)
        else:
            end, _, _ = struct.unpack_from("<III", data, at)
        length = data[at + head - 1]
        if end == 0:  # the null record that closes the list
            return None
        name = data[at + head : at + head + length].decode("latin-1")
        if end > len(data) or end <= at:
            return f"truncated: record {name!r} ends at byte {end}, the file has {len(data)} bytes"
        at = end
    return f"truncated: the file ends inside a record header at byte {at}"


def read_fbx(file: Path, source: str) -> list[MeshNode]:
    """Every mesh node of an FBX file, in ufbx's node order (parents before children).

    Parameters
    ----------
    file : Path
    source : str
        The path as given, for messages.

    Returns
    -------
    list of MeshNode
        ``(name, matrix, vertices, faces, ancestors)`` per node with a mesh of at least one
        polygon: ``matrix`` the node's geometry-to-world transform (in metres, :data:`FRAME`),
        ``vertices`` (n, 3) float64 and ``faces`` (m, 3) int64 in the node's geometry frame,
        ``ancestors`` the names of the nodes above it (the root's children down).

    Raises
    ------
    InvalidMeshError
        Truncated, corrupt or not FBX; a hierarchy too deep; too many indices.
    """
    nodes, geometry = _with_scene(file, source, _mesh_nodes)
    triangles = {
        key: polygon_triangles(vertices, polygons[:, 0], polygons[:, 1], indices)
        for key, (vertices, polygons, indices) in geometry.items()
    }
    out: list[MeshNode] = []
    for name, matrix, key, ancestors in nodes:
        if len(triangles[key]):
            out.append((name, matrix, geometry[key][0], triangles[key], ancestors))
    return out


def _with_scene(file: Path, source: str, extract: Callable[[Any], Any], **options: Any) -> Any:
    """``extract(scene)`` of the file's ufbx scene, with Python's garbage collector off from
    the load until the scene is freed and every ufbx object is gone: ufbx 0.0.5's objects
    crashed the collector while their scene lived (most likely the missing references that
    :func:`_kept` now adds; kept off as a second guard). ``extract`` returns
    plain data; an :class:`InvalidMeshError` it raises is raised again out here, so that no
    traceback keeps a ufbx object alive."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        result, problem = _extract(file, source, extract, options)
    finally:
        if enabled:
            gc.enable()
    if problem is not None:
        raise InvalidMeshError(problem, source)
    return result


def _extract(
    file: Path, source: str, extract: Callable[[Any], Any], options: dict[str, Any]
) -> tuple[Any, str | None]:
    scene = _load(file, source, **options)
    try:
        return extract(scene), None
    except InvalidMeshError as error:
        return None, error.message
    finally:
        scene.free()


def _kept(element: Any) -> Any:
    """``element``, a ufbx element object (or None), with the reference ufbx 0.0.5 does not
    add: its bindings hand out an element's cached object without a new reference, so each
    access leaves the object a reference short; once the caller drops it, the cache (which
    the scene's context releases when freed) holds freed memory, and the Python heap is
    corrupted at random (workers segfaulted in ``scene.free()``). One reference added per
    access keeps the count right."""
    if element is not None:
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(element))
    return element


def _mesh_nodes(
    scene: Any,
) -> tuple[list[tuple[str, np.ndarray, int, tuple[str, ...]]], dict[int, tuple]]:
    """``(name, geometry-to-world matrix, mesh key, ancestors' names)`` of every node with a
    mesh, and per mesh key its vertices, polygons ``(begin, count)`` and polygon-vertex
    indices, copied out."""
    nodes: list[tuple[str, np.ndarray, int, tuple[str, ...]]] = []
    geometry: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    total = 0
    # each node's name and parent (index in scene.nodes, its typed_id; none for the root and
    # its children), known before its children's: ufbx lists parents first
    labels: list[str] = []
    parents: dict[int, int] = {}
    # one pass over the nodes only: iterating ufbx's mesh list as well crashes ufbx 0.0.5
    for k, node in enumerate(map(_kept, scene.nodes)):
        up = _kept(node.parent)
        if up is not None and not up.is_root:
            parents[k] = int(up.typed_id)
        labels.append(str(node.name or f"node{k}"))
        mesh = _kept(node.mesh)
        if mesh is None or mesh.num_faces == 0:
            continue
        key = int(mesh.element_id)
        if key not in geometry:
            total += int(mesh.num_indices)
            if total > MAX_INDICES:
                raise InvalidMeshError(
                    f"cannot parse FBX file: over {MAX_INDICES} polygon-vertex indices"
                )
            geometry[key] = _arrays(mesh)
        name = str(node.name or mesh.name or f"node{k}")
        nodes.append(
            (name, _matrix(node.geometry_to_world), key, ancestor_names(k, parents, labels))
        )
    return nodes, geometry


def _matrix(m: Any) -> np.ndarray:
    """A ufbx affine matrix (four columns) as a 4x4 row-major array."""
    out = np.eye(4)
    out[:3, :4] = np.array([tuple(m.c0), tuple(m.c1), tuple(m.c2), tuple(m.c3)]).T
    return out


def _arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, polygons ``(begin, count)`` and polygon-vertex indices of one mesh, copied
    out of ufbx."""
    vertices = np.array(memoryview(mesh.vertices), dtype=np.float64).reshape(-1, 3)
    polygons = np.array(memoryview(mesh.faces), dtype=np.int64).reshape(-1, 2)
    indices = np.fromiter(mesh.vertex_indices, dtype=np.int64, count=int(mesh.num_indices))
    return vertices, polygons, indices


def polygon_triangles(
    vertices: np.ndarray, begin: np.ndarray, count: np.ndarray, indices: np.ndarray
) -> np.ndarray:
    """Triangles of the polygons ``indices[begin:begin + count]`` (those of fewer than 3
    corners, points and lines, skipped), split as OFF's are
    (:func:`meshcol.io.polygons.triangulate_polygons`: a fan when convex, else ear clipping),
    (m, 3) int64."""
    keep = count >= 3
    if not keep.all():
        begin, count = begin[keep], count[keep]
    if len(count) == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if len(indices) == 3 * len(count) and (count == 3).all():  # triangles, one after another
        corners = indices
    else:
        starts = np.cumsum(count) - count
        within = np.arange(int(count.sum()), dtype=np.int64) - np.repeat(starts, count)
        corners = indices[np.repeat(begin, count) + within]
    if corners.min() < 0 or corners.max() >= len(vertices):
        raise ValueError("polygon corner out of range")  # ufbx checks this: never met
    if len(corners) == 3 * len(count):  # triangles only: nothing to split
        return corners.reshape(-1, 3)
    return triangulate_polygons(vertices, corners, count)


def ignored(file: Path, source: str) -> list[str]:
    """What an FBX file holds that meshcol leaves out, one note each (``3 materials``,
    ``1 camera``...; skins and animation too); empty when it is geometry only."""
    counts = _with_scene(
        file, source, _content_counts, ignore_geometry=True, ignore_animation=False
    )
    return [f"{n} {what}{'' if n == 1 else 's'}" for n, what in counts if n]


def _content_counts(scene: Any) -> list[tuple[int, str]]:
    return [
        (len(scene.materials), "material"),
        (len(scene.skin_deformers), "skin"),
        (len(scene.blend_deformers), "blend shape deformer"),
        (len(scene.cameras), "camera"),
        (len(scene.lights), "light"),
        (len(scene.anim_stacks), "animation stack"),
    ]
