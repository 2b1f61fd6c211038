"""glTF documents written by hand for the tests: unit cubes in a data URI that any node may
use (the tests of glTF readers, body names and physics extensions)."""

from __future__ import annotations

import base64

import numpy as np
import trimesh

#: The cube every document holds: a unit box about the origin.
CUBE = trimesh.creation.box(extents=[1.0, 1.0, 1.0])


def cube_document(
    nodes: list,
    roots: list,
    primitives: int = 1,
    extensions: dict | None = None,
    used: list | None = None,
) -> dict:
    """A glTF document of ``nodes`` (scene roots ``roots``) whose mesh 0 is the cube and
    mesh 1 the cube ``primitives`` times; ``extensions`` and ``extensionsUsed`` when given."""
    points = np.asarray(CUBE.vertices, dtype="<f4").tobytes()
    indices = np.asarray(CUBE.faces, dtype="<u4").tobytes()
    blob = points + indices
    primitive = {"attributes": {"POSITION": 0}, "indices": 1}
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [primitive]}, {"primitives": [primitive] * primitives}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": len(CUBE.vertices),
                "type": "VEC3",
                "min": [-0.5] * 3,
                "max": [0.5] * 3,
            },
            {"bufferView": 1, "componentType": 5125, "count": CUBE.faces.size, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(points)},
            {"buffer": 0, "byteOffset": len(points), "byteLength": len(indices)},
        ],
        "buffers": [
            {
                "byteLength": len(blob),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode(),
            }
        ],
    }
    if extensions is not None:
        document["extensions"] = extensions
    if used is not None:
        document["extensionsUsed"] = used
    return document
