"""Mesh formats read by trimesh's loaders (PLY, glTF/GLB): a file's scene graph as
mesh nodes, with trimesh's exceptions turned into one line that names the file.

Only geometry is loaded (``process=False``, no materials kept): a textured file loads
without Pillow.
"""

from __future__ import annotations

import io
import os
import struct
import urllib.parse
import zlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import InvalidMeshError, MeshcolError
from meshcol.io.safe_read import read_input

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = ["PARSE_ERRORS", "read_bytes", "read_ply", "scene_nodes"]

#: What trimesh's (and pycollada's) parsers raise on corrupt content. Listed explicitly
#: rather than catching Exception, so programming errors still surface with a traceback.
PARSE_ERRORS = (
    ValueError,  # includes json.JSONDecodeError and UnicodeDecodeError
    IndexError,
    KeyError,
    TypeError,
    AttributeError,
    AssertionError,
    EOFError,
    OverflowError,
    NotImplementedError,
    UnboundLocalError,  # trimesh 5.2's PLY reader, on a face element it cannot read
    struct.error,
    zlib.error,
)


def read_ply(file: Path, source: str) -> list[MeshNode]:
    """The meshes of a PLY file, named after their geometry (a header that is not UTF-8 is
    re-encoded from Latin-1 first)."""
    header = _ply_bytes(file, source)
    stream = None if header is None else io.BytesIO(header)
    return scene_nodes(load_scene(file, "ply", source, stream), by_geometry=True)


def scene_nodes(scene: Any, by_geometry: bool = False) -> list[MeshNode]:
    """``(name, matrix, vertices, faces, ())`` of every mesh node of a trimesh scene, in graph
    order, named by node (or by geometry); point clouds, paths and faceless meshes are not
    bodies. No ancestors: glTF's are the document's (:mod:`meshcol.io.gltf`)."""
    nodes: list[MeshNode] = []
    for node in scene.graph.nodes_geometry:
        matrix, geometry_name = scene.graph[node]
        geometry = scene.geometry[geometry_name]
        faces = getattr(geometry, "faces", None)
        if faces is None or len(faces) == 0:
            continue
        name = geometry_name if by_geometry else str(node)
        nodes.append((name, np.asarray(matrix, dtype=np.float64), geometry.vertices, faces, ()))
    return nodes


def load_scene(file: Path, file_type: str, source: str, stream: io.BytesIO | None = None):
    """trimesh's scene of ``file`` (or of ``stream``, its bytes mended), every parse error
    as :class:`InvalidMeshError` ``cannot parse <TYPE> file: ...``.

    trimesh never opens a file itself: the file's bytes come from the guarded read, and the
    files it refers to (glTF buffers and images) from :func:`local_resolver`'s."""
    import trimesh

    if stream is None:
        stream = io.BytesIO(read_input(source, "mesh"))
    stream.name = file.name  # trimesh names an unnamed object after it
    try:
        return trimesh.load_scene(
            stream, file_type=file_type, process=False, resolver=local_resolver(file, source)
        )
    except MeshcolError:
        raise  # a reference refused, or a referenced file the guarded read refused
    except FileNotFoundError as error:
        # a glTF buffer or image the file refers to
        raise InvalidMeshError(
            f"cannot parse {file_type.upper()} file: referenced file {error.args[-1]!r} not found",
            source,
        ) from None
    except PARSE_ERRORS as error:
        detail = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise InvalidMeshError(
            f"cannot parse {file_type.upper()} file: {detail[:200]}", source
        ) from None


def local_uri(uri: str) -> str | None:
    """What is wrong with a reference ``uri`` inside a mesh file (a glTF buffer), or None for a
    local relative path: meshcol reads no network resource, and no absolute path, which would
    make the file mean something else on another machine."""
    parsed = urllib.parse.urlsplit(uri)
    if parsed.scheme and len(parsed.scheme) > 1:  # one letter: a Windows drive
        return f"{parsed.scheme}: URIs are not read (only files beside the mesh file)"
    if uri.startswith(("/", "\\")) or (parsed.scheme and len(parsed.scheme) == 1):
        return "absolute paths are not read (only files beside the mesh file)"
    return None


def local_resolver(file: Path, source: str) -> Any:
    """A trimesh resolver for the files ``file`` refers to: relative local paths only (URIs
    with a scheme and absolute paths raise :class:`InvalidMeshError`), read by the guarded
    read with the cap of a glTF buffer; never trimesh's fallback to a file of the same name
    in the mesh's folder."""
    import trimesh.resolvers

    class _LocalResolver(trimesh.resolvers.Resolver):
        def __init__(self) -> None:
            self.folder = file.parent

        def get(self, name: str) -> bytes:
            problem = local_uri(name)
            if problem is not None:
                raise InvalidMeshError(f"cannot read reference {name[:200]!r}: {problem}", source)
            target = self.folder / urllib.parse.unquote(name)
            if not os.path.lexists(target):
                raise FileNotFoundError(name)
            return read_input(target, "buffer")

        def write(self, name: str, data: Any) -> None:
            raise NotImplementedError("meshcol never writes through a reader")

        def keys(self) -> Any:
            return iter(())

        def namespaced(self, namespace: str) -> Any:
            raise NotImplementedError("meshcol reads no archives")

    return _LocalResolver()


def read_bytes(file: Path, source: str) -> bytes:
    """The file's bytes, by the guarded read (:func:`meshcol.io.safe_read.read_input`):
    InputFileError naming it when it cannot be read, is not a regular file or is too large."""
    del file  # ``source`` names the same file as the user typed it
    return read_input(source, "mesh")


def _ply_bytes(file: Path, source: str) -> bytes | None:
    """A PLY file whose header (comments, obj_info) is not UTF-8, with the header re-encoded
    from Latin-1; None when the file needs nothing (the data after the header is untouched)."""
    data = read_bytes(file, source)
    end = data.find(b"end_header")
    if end < 0:
        return None
    try:
        data[:end].decode("utf-8")
        return None
    except UnicodeDecodeError:
        return data[:end].decode("latin-1").encode("utf-8") + data[end:]
