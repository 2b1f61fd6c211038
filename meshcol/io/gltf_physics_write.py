"""A glTF/GLB asset written back with its colliders (``--to gltf-physics``): one GLB holding
the asset and, per body, collider nodes in both physics extensions engines read.

Each body's colliders become child nodes of its render node (the mesh node the body was read
from), named ``<node>_collider_NN``, each carrying:

- ``KHR_physics_rigid_bodies.collider``: an exact primitive as a ``KHR_implicit_shapes``
  shape, a convex part as ``geometry.node`` (a node outside every scene holding the part's
  mesh at the collider's transform, so it is never drawn) with ``convexHull: true``;
- ``OMI_physics_body.collider`` (what Godot 4 imports): an ``OMI_physics_shape`` shape, the
  same primitive or a ``convex`` shape of the part's mesh.

Capsules and cylinders lie along the node's Y axis (both extensions'), boxes along its axes.
A primitive's node undoes its render node's scale (its world transform is the primitive's
rigid pose); under a render node whose inverse is no translation-rotation-scale (a shear), it
is written as the convex mesh that encloses it
(:func:`meshcol.io.primitives.enclosing_primitive_mesh`).
Vertices are stored as 32-bit floats (glTF's). Every buffer of the input (a ``.gltf``'s
files and data URIs, a GLB's binary chunk) and every image file is copied into the one
binary chunk, so the output stands alone.
"""

from __future__ import annotations

import copy
import json
import mimetypes
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.gltf import read_document
from meshcol.io.gltf_physics import (
    KHR_BODIES,
    KHR_SHAPES,
    OMI_BODY,
    OMI_SHAPE,
    GltfFile,
    has_physics,
    node_worlds,
)
from meshcol.io.physics_bodies import axis_turn
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Primitive, Sphere

__all__ = ["NodeColliders", "gltf_physics_path", "physics_schema_problems", "write_gltf_physics"]

#: The JSON Schemas of the extensions' objects (written from the published specifications).
SCHEMA_FOLDER = Path(__file__).resolve().parent.parent / "schemas" / "gltf_physics"

_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_FLOAT, _UNSIGNED_INT = 5126, 5125


@dataclass(frozen=True)
class NodeColliders:
    """The colliders of one body, in the world frame.

    Attributes
    ----------
    body : str
        The body's name as meshcol reads the asset (``<stem>`` or ``<stem>/<node name>``).
    parts : tuple
        ``("mesh", vertices (n, 3), faces (m, 3))`` for a convex part, or ``("primitive",
        Primitive, pose (4, 4))`` for an exact primitive (capsule and cylinder along the
        pose's z), world frame.
    """

    body: str
    parts: tuple[tuple[str, Any, Any], ...]


def gltf_physics_path(source: str, out_dir: str) -> str:
    """Where ``--to gltf-physics`` writes the asset: ``<out_dir>/<stem>.glb``."""
    return str(Path(out_dir) / f"{Path(source).stem}.glb")


def write_gltf_physics(source: str, colliders: Sequence[NodeColliders], path: str) -> str:
    """Write the asset ``source`` with ``colliders`` as one GLB at ``path`` (atomic).

    Colliders the asset already has (either extension) are replaced: taken out with what
    existed only for them (:func:`meshcol.io.gltf_physics_strip.strip_colliders`), everything
    else kept.

    Returns
    -------
    str
        What was replaced (``replaced 2 KHR_physics_rigid_bodies and 2 OMI_physics_body
        collider(s) already in the asset``), empty when the asset had none.

    Raises
    ------
    InvalidMeshError
        A body that is no mesh node of the asset.
    """
    from meshcol.io.gltf_physics_strip import strip_colliders
    from meshcol.io.report import atomic_path

    file = Path(source)
    document, binary = read_document(file, source)
    kind = "GLB" if file.suffix.lower() == ".glb" else "GLTF"
    document = copy.deepcopy(document)
    gltf = GltfFile(document, binary, file, source, kind)
    for key, want in (("extensions", dict), ("extensionsUsed", list)):
        if not isinstance(document.get(key, want()), want):
            raise gltf.error(f"'{key}' is not an {'object' if want is dict else 'array'}")
    owners = _render_nodes(gltf, [c.body for c in colliders])  # before any node is renumbered

    def sound(left: dict) -> None:  # what stays of the asset's physics (bodies, triggers)
        problems = physics_schema_problems(left)
        if problems:
            raise gltf.error(f"its physics extensions break their schema: {problems[0]}")

    stripped = strip_colliders(document, sound) if has_physics(document) else None
    if stripped is not None and stripped.nodes:
        owners = [stripped.renumbered[k] for k in owners]
    out = _Builder(gltf)
    out.pack_buffers(compact=stripped is not None and bool(stripped.colliders))
    worlds, _ = node_worlds(gltf)
    nodes = out.nodes
    numbered: dict[int, int] = {}  # a node of several primitives is several bodies
    for entry, k in zip(colliders, owners):
        base = _node_name(nodes, k)
        inverse = np.linalg.inv(worlds[k])
        for part in entry.parts:
            j = numbered[k] = numbered.get(k, -1) + 1
            out.collider(k, f"{base}_collider_{j:02d}", part, worlds[k], inverse)
    data = out.glb()
    problems = physics_schema_problems(out.document)
    if problems:  # a bug of this writer: never write it
        raise InvalidMeshError(f"--to gltf-physics wrote an invalid extension: {problems[0]}")
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data)
    return stripped.summary() if stripped is not None else ""


def physics_schema_problems(document: Any) -> list[str]:
    """Every place a glTF document's physics extension objects break their JSON Schema
    (``meshcol/schemas/gltf_physics``): ``"<JSON pointer>: <problem>"``, empty when none."""
    import jsonschema

    def validator(name: str) -> Any:
        schema = json.loads((SCHEMA_FOLDER / f"{name}.schema.json").read_text())
        return jsonschema.Draft202012Validator(schema)

    top = _extensions(document)
    checks = [
        ("/extensions/" + name, top.get(name), name) for name in (KHR_BODIES, KHR_SHAPES, OMI_SHAPE)
    ]
    nodes = document.get("nodes", [])
    for k, node in enumerate(nodes if isinstance(nodes, list) else []):
        for name in (KHR_BODIES, OMI_BODY):
            value = _extensions(node).get(name)
            checks.append((f"/nodes/{k}/extensions/{name}", value, f"{name}.node"))
    problems = []
    for pointer, value, schema in checks:
        if value is None:
            continue
        for error in validator(schema).iter_errors(value):
            where = "".join(f"/{p}" for p in error.absolute_path)
            problems.append(f"{pointer}{where}: {error.message}")
    return problems


def _extensions(holder: Any) -> dict:
    """``holder``'s ``extensions`` object ({} when it has none or not an object)."""
    value = holder.get("extensions", {}) if isinstance(holder, dict) else {}
    return value if isinstance(value, dict) else {}


def _shapes(document: dict, name: str) -> list:
    container = _extensions(document).get(name)
    shapes = container.get("shapes") if isinstance(container, dict) else None
    return shapes if isinstance(shapes, list) else []


def _node_name(nodes: list, k: int) -> str:
    name = nodes[k].get("name")
    return name if isinstance(name, str) and name else f"node_{k}"


def _render_nodes(gltf: GltfFile, bodies: list[str]) -> list[int]:
    """The index of the mesh node each body was read from: the asset's mesh nodes read as
    :func:`meshcol.io.mesh_read.load_mesh` reads them, each with its node index
    (:func:`meshcol.io.gltf.mesh_node_indices`) and the body name it gets; names are only
    how a body is looked up, so repeated and missing node names match too."""
    from meshcol.io.gltf import mesh_node_indices
    from meshcol.io.mesh_read import node_body_names

    indexed = mesh_node_indices(gltf.file, gltf.source)
    names = node_body_names(gltf.file, [node for _, node in indexed], godot_hints=True)
    index_of = {name: index for (name, _), (index, _) in zip(names, indexed)}
    found = []
    for body in bodies:
        if body not in index_of:
            raise InvalidMeshError(
                f"--to gltf-physics: body '{body}' is none of the asset's mesh nodes", gltf.source
            )
        found.append(index_of[body])
    return found


def _is_trs(matrix: np.ndarray) -> bool:
    """True when ``matrix`` is a translation, rotation and scale (glTF's node transform):
    orthogonal columns, no mirror."""
    linear = matrix[:3, :3]
    gram = linear.T @ linear
    off = gram - np.diag(np.diag(gram))
    return bool(np.abs(off).max() <= 1e-12 * gram.max() and np.linalg.det(linear) > 0)


def _khr_shape(primitive: Primitive) -> dict[str, Any]:
    if isinstance(primitive, Box):
        return {"type": "box", "box": {"size": [float(v) for v in primitive.size]}}
    if isinstance(primitive, Sphere):
        return {"type": "sphere", "sphere": {"radius": float(primitive.radius)}}
    kind = "capsule" if isinstance(primitive, Capsule) else "cylinder"
    assert isinstance(primitive, (Capsule, Cylinder))
    r = float(primitive.radius)
    return {
        "type": kind,
        kind: {"height": float(primitive.length), "radiusTop": r, "radiusBottom": r},
    }


class _Builder:
    """The output document and its one binary chunk, grown part by part."""

    def __init__(self, gltf: GltfFile) -> None:
        self.gltf = gltf
        self.document = gltf.document
        self.nodes: list = gltf.items("nodes")
        self.blob = bytearray()
        # the shapes an asset keeps (its triggers'), the new ones after them
        self.khr_shapes: list[dict[str, Any]] = list(_shapes(self.document, KHR_SHAPES))
        self.omi_shapes: list[dict[str, Any]] = list(_shapes(self.document, OMI_SHAPE))

    def _append(self, data: bytes, target: int | None = None) -> int:
        """A new bufferView over ``data`` (4-byte aligned) in buffer 0; its index."""
        self.blob += b"\x00" * (-len(self.blob) % 4)
        view: dict[str, Any] = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.blob += data
        views = self.document.setdefault("bufferViews", [])
        views.append(view)
        return len(views) - 1

    def pack_buffers(self, compact: bool = False) -> None:
        """Every input buffer into the one binary chunk, views re-pointed; image files
        embedded. ``compact``: only the bytes of the views there are (after colliders were
        taken out), each view 4-byte aligned."""
        if compact:
            for view in self.gltf.items("bufferViews"):
                start = int(view.get("byteOffset", 0))
                end = start + int(view.get("byteLength", 0))
                data = self.gltf.buffer(view["buffer"])[start:end]
                self.blob += b"\x00" * (-len(self.blob) % 4)
                view["byteOffset"] = len(self.blob)
                view["buffer"] = 0
                self.blob += data
        else:
            buffers = self.gltf.items("buffers")
            offsets = []
            for k in range(len(buffers)):
                self.blob += b"\x00" * (-len(self.blob) % 4)
                offsets.append(len(self.blob))
                self.blob += self.gltf.buffer(k)
            for view in self.gltf.items("bufferViews"):
                view["byteOffset"] = int(view.get("byteOffset", 0)) + offsets[view["buffer"]]
                view["buffer"] = 0
        for k, image in enumerate(self.gltf.items("images")):
            uri = image.get("uri") if isinstance(image, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:"):
                try:
                    data = (self.gltf.file.parent / unquote(uri)).read_bytes()
                except OSError as error:
                    raise self.gltf.error(
                        f"image {k} file {uri!r} cannot be read: {error.strerror or error}"
                    ) from None
                mime = mimetypes.guess_type(uri)[0] or "application/octet-stream"
                image.pop("uri")
                image["bufferView"] = self._append(data)
                image["mimeType"] = mime

    def _mesh(self, name: str, vertices: np.ndarray, faces: np.ndarray) -> int:
        points = np.ascontiguousarray(vertices, dtype="<f4")
        indices = np.ascontiguousarray(faces, dtype="<u4").reshape(-1)
        accessors = self.document.setdefault("accessors", [])
        position = {
            "bufferView": self._append(points.tobytes(), _ARRAY_BUFFER),
            "componentType": _FLOAT,
            "count": len(points),
            "type": "VEC3",
            "min": points.min(axis=0).astype(float).tolist(),
            "max": points.max(axis=0).astype(float).tolist(),
        }
        accessors.append(position)
        accessors.append(
            {
                "bufferView": self._append(indices.tobytes(), _ELEMENT_ARRAY_BUFFER),
                "componentType": _UNSIGNED_INT,
                "count": len(indices),
                "type": "SCALAR",
            }
        )
        meshes = self.document.setdefault("meshes", [])
        primitive = {"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1}
        meshes.append({"name": name, "primitives": [{**primitive, "mode": 4}]})
        return len(meshes) - 1

    def collider(
        self, owner: int, name: str, part: tuple, world: np.ndarray, inverse: np.ndarray
    ) -> None:
        """One collider node under node ``owner`` (world transform ``world``)."""
        node: dict[str, Any] = {"name": name}
        kind, a, b = part
        if kind == "primitive":
            local = inverse @ np.asarray(b, dtype=np.float64)
            if isinstance(a, (Capsule, Cylinder)):
                local = local @ np.linalg.inv(axis_turn("Y"))  # meshcol's z onto the node's Y
            # KHR_implicit_shapes has no ellipsoid: one is written as its enclosing mesh
            if _is_trs(local) and not isinstance(a, Ellipsoid):
                if not np.array_equal(local, np.eye(4)):
                    node["matrix"] = local.T.reshape(-1).tolist()
                self.khr_shapes.append(_khr_shape(a))
                self.omi_shapes.append(_khr_shape(a))
                node["extensions"] = {
                    KHR_BODIES: {"collider": {"geometry": {"shape": len(self.khr_shapes) - 1}}},
                    OMI_BODY: {"collider": {"shape": len(self.omi_shapes) - 1}},
                }
                self._child(owner, node)
                return
            from meshcol.io.primitives import enclosing_primitive_mesh

            vertices, faces = enclosing_primitive_mesh(a)
            pose = np.asarray(b, dtype=np.float64)
            kind, a, b = "mesh", vertices @ pose[:3, :3].T + pose[:3, 3], faces
        local_vertices = np.asarray(a, dtype=np.float64) @ inverse[:3, :3].T + inverse[:3, 3]
        mesh = self._mesh(name, local_vertices, np.asarray(b))
        geometry: dict[str, Any] = {"name": f"{name}_geometry", "mesh": mesh}
        if not np.array_equal(world, np.eye(4)):
            geometry["matrix"] = world.T.reshape(-1).tolist()
        self.nodes.append(geometry)  # in no scene: never drawn
        self.omi_shapes.append({"type": "convex", "convex": {"mesh": mesh}})
        node["extensions"] = {
            KHR_BODIES: {
                "collider": {"geometry": {"node": len(self.nodes) - 1, "convexHull": True}}
            },
            OMI_BODY: {"collider": {"shape": len(self.omi_shapes) - 1}},
        }
        self._child(owner, node)

    def _child(self, owner: int, node: dict[str, Any]) -> None:
        self.nodes.append(node)
        self.nodes[owner].setdefault("children", []).append(len(self.nodes) - 1)

    def glb(self) -> bytes:
        """The GLB bytes: the document (extensions declared) and the binary chunk."""
        document = self.document
        extensions = document.setdefault("extensions", {})
        used = document.setdefault("extensionsUsed", [])
        wanted = [KHR_BODIES, OMI_BODY, OMI_SHAPE]
        if self.khr_shapes:
            extensions[KHR_SHAPES] = {**extensions.get(KHR_SHAPES, {}), "shapes": self.khr_shapes}
            wanted.insert(1, KHR_SHAPES)
        extensions[OMI_SHAPE] = {**extensions.get(OMI_SHAPE, {}), "shapes": self.omi_shapes}
        used.extend(name for name in wanted if name not in used)
        self.blob += b"\x00" * (-len(self.blob) % 4)
        document["buffers"] = [{"byteLength": len(self.blob)}] if self.blob else []
        if not self.blob:
            document.pop("bufferViews", None)
        text = json.dumps(document, separators=(",", ":")).encode("utf-8")
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<I4s", len(text), b"JSON") + text
        if self.blob:
            chunks += struct.pack("<I4s", len(self.blob), b"BIN\x00") + bytes(self.blob)
        return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks
