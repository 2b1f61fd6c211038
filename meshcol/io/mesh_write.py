"""Writing meshes: OBJ and GLB byte for byte, other formats through trimesh, part layouts.

Every writer produces byte-identical files for identical input (shortest round-trip float
formatting, no timestamps, sorted JSON keys in GLB) and writes through a temporary file and a
rename, so no half-written file is ever left behind.
"""

from __future__ import annotations

import json
import os
import re
import struct
from collections.abc import Sequence
from typing import Any

import numpy as np

from meshcol.io.report import atomic_path

__all__ = [
    "LAYOUTS",
    "MESH_OUTPUT_EXTENSIONS",
    "MULTI_MESH_EXTENSIONS",
    "glb_bytes",
    "layout_file_pattern",
    "obj_text",
    "part_names",
    "safe_name",
    "write_meshes",
    "write_parts",
]

#: Mesh formats meshcol writes, by extension.
MESH_OUTPUT_EXTENSIONS = (".obj", ".stl", ".ply", ".off", ".glb")
#: Formats that hold several named meshes in one file.
MULTI_MESH_EXTENSIONS = (".obj", ".glb")


LAYOUTS = ("parts", "combined", "ucx")


_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def safe_name(name: str) -> str:
    """``name`` reduced to characters that are safe in file and object names."""
    cleaned = _UNSAFE.sub("_", name).strip("._")
    return cleaned or "body"


def _number(x: float) -> str:
    return repr(float(x) + 0.0)  # +0.0 turns -0.0 into 0.0


def obj_text(objects: Sequence[tuple[str, np.ndarray, np.ndarray]]) -> str:
    """Wavefront OBJ with one ``o`` object per (name, vertices, faces), 1-based global indices."""
    lines = ["# meshcol"]
    base = 1
    for name, vertices, faces in objects:
        lines.append(f"o {name}")
        lines.extend(f"v {_number(x)} {_number(y)} {_number(z)}" for x, y, z in vertices.tolist())
        lines.extend(f"f {a + base} {b + base} {c + base}" for a, b, c in faces.tolist())
        base += len(vertices)
    return "\n".join(lines) + "\n"


#: glTF's node matrix (column-major) that turns a Z-up frame into glTF's Y-up one: a rotation
#: of -90 degrees about X, (x, y, z) -> (x, z, -y).
Z_UP_TO_Y_UP = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]


def glb_bytes(objects: Sequence[tuple[str, np.ndarray, np.ndarray]], z_up: bool = False) -> bytes:
    """Binary glTF 2.0 with one node (and mesh) per (name, vertices, faces).

    Positions are float32 (as glTF requires), indices uint32; no timestamps, sorted JSON keys.
    ``z_up``: the coordinates are in a Z-up frame (a robot's world, ROS REP 103): the nodes
    become children of one root node ``z_up_to_y_up`` whose matrix (:data:`Z_UP_TO_Y_UP`)
    turns them into glTF's Y-up frame (glTF 2.0, 3.4: "glTF uses a right-handed coordinate
    system ... +Y up"), and ``asset.extras.meshcol_source_up_axis`` says ``"Z"``: a reader
    that applies node transforms (every conforming one) sees the robot upright.
    """
    blob = bytearray()
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []
    meshes: list[dict[str, Any]] = []
    nodes: list[dict[str, Any]] = []
    for i, (name, vertices, faces) in enumerate(objects):
        position = np.ascontiguousarray(vertices, dtype="<f4")
        index = np.ascontiguousarray(faces, dtype="<u4").reshape(-1)
        for data, target in ((position, 34962), (index, 34963)):
            views.append(
                {"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes, "target": target}
            )
            blob += data.tobytes()
            blob += b"\0" * (-len(blob) % 4)
        accessors.append(
            {
                "bufferView": 2 * i,
                "componentType": 5126,
                "count": len(position),
                "type": "VEC3",
                "min": position.min(axis=0).astype(float).tolist(),
                "max": position.max(axis=0).astype(float).tolist(),
            }
        )
        accessors.append(
            {"bufferView": 2 * i + 1, "componentType": 5125, "count": len(index), "type": "SCALAR"}
        )
        meshes.append(
            {
                "name": name,
                "primitives": [
                    {"attributes": {"POSITION": 2 * i}, "indices": 2 * i + 1, "mode": 4}
                ],
            }
        )
        nodes.append({"name": name, "mesh": i})
    roots = list(range(len(nodes)))
    asset: dict[str, Any] = {"version": "2.0", "generator": "meshcol"}
    if z_up:
        nodes.append({"name": "z_up_to_y_up", "children": roots, "matrix": Z_UP_TO_Y_UP})
        roots = [len(nodes) - 1]
        asset["extras"] = {"meshcol_source_up_axis": "Z"}
    doc = {
        "asset": asset,
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    text = json.dumps(doc, sort_keys=True, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    out = bytearray(struct.pack("<4sII", b"glTF", 2, total))
    out += struct.pack("<I4s", len(text), b"JSON") + text
    out += struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob)
    return bytes(out)


def part_names(body: str, count: int, prefix: str = "") -> list[str]:
    """``[prefix]<body>_NN`` for each part, NN zero-padded to at least two digits."""
    width = max(2, len(str(count - 1)))
    return [f"{prefix}{body}_{i:0{width}d}" for i in range(count)]


def layout_file_pattern(body: str, layout: str = "parts", fmt: str = "obj") -> re.Pattern[str]:
    """The names of the files :func:`write_parts` may write for ``body`` in ``layout``, however
    many parts it has: a regular expression for a file name (no folder) to ``fullmatch``."""
    if layout not in LAYOUTS:
        raise ValueError(f"unknown layout {layout!r}")
    body = re.escape(safe_name(body))
    if layout == "parts":
        return re.compile(rf"{body}_\d{{2,}}\.{fmt}")
    if layout == "combined":
        return re.compile(rf"{body}\.{fmt}")
    return re.compile(rf"{body}_ucx\.obj")


def write_parts(
    body: str,
    parts: Sequence[tuple[np.ndarray, np.ndarray]],
    out_dir: str | os.PathLike[str],
    layout: str = "parts",
    fmt: str = "obj",
) -> list[str]:
    """Write parts in a layout; returns the paths written, in order.

    ``parts``: one file per part, ``<body>_NN.obj`` (or ``.glb``); ``combined``: one
    ``<body>.obj`` with one object per part, or one ``<body>.glb`` with one node per part;
    ``ucx``: one ``<body>_ucx.obj`` whose objects are named ``UCX_<body>_NN`` (Unreal's
    convention for custom collision). Every file is written atomically.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"unknown layout {layout!r}")
    if fmt not in ("obj", "glb"):
        raise ValueError(f"unknown format {fmt!r}")
    body = safe_name(body)
    out_dir = os.fspath(out_dir)
    written: list[str] = []

    def emit(path: str, objects: list[tuple[str, np.ndarray, np.ndarray]]) -> None:
        write_meshes(path, objects)
        written.append(path)

    if layout == "parts":
        for name, (v, f) in zip(part_names(body, len(parts)), parts):
            emit(os.path.join(out_dir, f"{name}.{fmt}"), [(name, v, f)])
    elif layout == "combined":
        names = part_names(body, len(parts))
        emit(os.path.join(out_dir, f"{body}.{fmt}"), [(n, v, f) for n, (v, f) in zip(names, parts)])
    else:
        names = part_names(body, len(parts), prefix="UCX_")
        emit(
            os.path.join(out_dir, f"{body}_ucx.obj"), [(n, v, f) for n, (v, f) in zip(names, parts)]
        )
    return written


def write_meshes(
    path: str | os.PathLike[str],
    meshes: Sequence[tuple[str, np.ndarray, np.ndarray]],
    z_up: bool = False,
) -> None:
    """Write named meshes ``(name, vertices, faces)`` to ``path``, atomically (``z_up``: GLB of
    Z-up coordinates, turned to glTF's Y-up by a root node, :func:`glb_bytes`).

    The format comes from the extension (:data:`MESH_OUTPUT_EXTENSIONS`). OBJ and GLB are
    written by :func:`obj_text` and :func:`glb_bytes` (one object or node per mesh); STL, PLY
    and OFF hold one mesh and go through trimesh.

    Raises
    ------
    ValueError
        An unknown extension, or several meshes for a single-mesh format.
    """
    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lower()
    if extension not in MESH_OUTPUT_EXTENSIONS:
        raise ValueError(
            f"unknown mesh extension {extension or '(none)'!r} "
            f"(expected {', '.join(MESH_OUTPUT_EXTENSIONS)})"
        )
    if len(meshes) != 1 and extension not in MULTI_MESH_EXTENSIONS:
        raise ValueError(f"{extension} holds one mesh, got {len(meshes)}")
    with atomic_path(path) as tmp:
        if extension == ".obj":
            with open(tmp, "w", encoding="utf-8", newline="\n") as f:
                f.write(obj_text(meshes))
        elif extension == ".glb":
            with open(tmp, "wb") as f:
                f.write(glb_bytes(meshes, z_up=z_up))
        else:
            import trimesh

            _, vertices, faces = meshes[0]
            trimesh.Trimesh(vertices=vertices, faces=faces, process=False).export(
                tmp, file_type=extension[1:]
            )
