"""glTF physics extensions read as a scene: Khronos ``KHR_physics_rigid_bodies`` with
``KHR_implicit_shapes``, and OMI's ``OMI_physics_body`` with ``OMI_physics_shape`` (what
Godot 4 imports and exports).

A glTF file that uses neither is read as before (:mod:`meshcol.io.gltf`: every mesh node a
body); one that uses them is a scene of its own (``MeshFormat.scene``):

- a body is a node with ``motion`` (either extension), its descendants' colliders its parts;
  else a render node (a mesh, no collider) with its child colliders (what ``--to
  gltf-physics`` writes), named as the node reads without physics; else a collider node is
  a static body of its own;
- a collider's shape decides its geometry: an implicit shape (box, sphere, capsule,
  cylinder, along the node's Y axis) is that exact primitive (a tapered capsule or cylinder,
  radii unequal, is its convex hull); KHR ``geometry.node`` is that node's mesh at that
  node's transform, its hull when ``convexHull`` is true (collider ``hull``), else its
  triangles (``mesh``); OMI ``convex`` is a mesh's hull, ``trimesh`` its triangles;
- triggers are not solid: not read, a warning counts them; so are KHR planes;
- KHR collision filters (``collisionSystems``, ``collideWithSystems``,
  ``notCollideWithSystems``) exclude the body pairs none of whose colliders collide
  (``Scene.excluded_pairs``); a node ``A`` collides with ``B`` when both ``doesCollide(A,
  B)`` and ``doesCollide(B, A)`` hold, the specification's rule;
- render meshes are not colliders (a warning counts the mesh nodes not read).

Units are metres (glTF's), Y up as the file has it: ``Scene.units`` is ``"m"``.
"""

from __future__ import annotations

import base64
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.body_names import ancestor_names
from meshcol.io.gltf import check_references, read_document
from meshcol.io.gltf_godot import hint_conflict, hint_groups, hinted_name
from meshcol.io.physics_bodies import BodyGroup, FileScene, ShapeElement
from meshcol.io.safe_read import read_input
from meshcol.types import Box, Capsule, Cylinder, Primitive, Sphere

__all__ = [
    "PHYSICS_EXTENSIONS",
    "GltfFile",
    "has_physics",
    "node_worlds",
    "read_glb_scene",
    "read_gltf_scene",
    "render_meshes_only",
]

KHR_BODIES = "KHR_physics_rigid_bodies"
KHR_SHAPES = "KHR_implicit_shapes"
OMI_BODY = "OMI_physics_body"
OMI_SHAPE = "OMI_physics_shape"
#: The extensions read here.
PHYSICS_EXTENSIONS = (KHR_BODIES, KHR_SHAPES, OMI_BODY, OMI_SHAPE)

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
# Mesh compressions whose accessors hold no data of their own (never read as zeros)
_COMPRESSIONS = {"KHR_draco_mesh_compression", "EXT_meshopt_compression"}
#: Most nodes one file may hold (a bound on the work of a hostile file).
MAX_NODES = 1_000_000


_RENDER_ONLY: ContextVar[bool] = ContextVar("meshcol_gltf_render_only", default=False)


@contextmanager
def render_meshes_only() -> Iterator[None]:
    """Within it, a glTF file reads as its mesh nodes whatever physics it has (the scene
    readers return None): ``--to gltf-physics`` makes new colliders from the render meshes,
    not from the colliders it replaces."""
    token = _RENDER_ONLY.set(True)
    try:
        yield
    finally:
        _RENDER_ONLY.reset(token)


def read_gltf_scene(file: Path, source: str) -> FileScene | None:
    """The physics scene of a ``.gltf`` file, or None when it uses no physics extension."""
    document, binary = read_document(file, source)
    return _scene(document, binary, file, source, "GLTF")


def read_glb_scene(file: Path, source: str) -> FileScene | None:
    """The physics scene of a ``.glb`` file, or None when it uses no physics extension."""
    document, binary = read_document(file, source)
    return _scene(document, binary, file, source, "GLB")


def has_physics(document: Any) -> bool:
    """True when a glTF document uses one of :data:`PHYSICS_EXTENSIONS`."""
    if not isinstance(document, dict):
        return False
    used = document.get("extensionsUsed", [])
    return isinstance(used, list) and any(name in used for name in PHYSICS_EXTENSIONS)


class GltfFile:
    """A glTF document's parts the physics reader needs, every access checked."""

    def __init__(self, document: Any, binary: bytes | None, file: Path, source: str, kind: str):
        self.document, self.binary, self.file = document, binary, file
        self.source, self.kind = source, kind
        self.buffers: dict[int, bytes] = {}

    def error(self, problem: str) -> InvalidMeshError:
        return InvalidMeshError(f"cannot parse {self.kind} file: {problem}", self.source)

    def items(self, name: str, owner: Any = None) -> list:
        value = (self.document if owner is None else owner).get(name, [])
        if not isinstance(value, list):
            raise self.error(f"'{name}' is not an array")
        return value

    def item(self, name: str, index: Any, where: str, owner: Any = None) -> dict:
        items = self.items(name, owner)
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(items):
            raise self.error(f"{where} refers to {name} {index!r}, but there are {len(items)}")
        value = items[index]
        if not isinstance(value, dict):
            raise self.error(f"{name} {index} is not an object")
        return value

    def extension(self, name: str) -> dict:
        value = self.document.get("extensions", {}).get(name, {})
        return value if isinstance(value, dict) else {}

    def buffer(self, index: int) -> bytes:
        if index in self.buffers:
            return self.buffers[index]
        spec = self.item("buffers", index, "a bufferView")
        uri = spec.get("uri")
        if uri is None:
            if self.binary is None or index != 0:
                raise self.error(f"buffer {index} has no uri and the file no binary chunk")
            data = self.binary
        elif not isinstance(uri, str):
            raise self.error(f"buffer {index} uri is not a string")
        elif uri.startswith("data:"):
            try:
                data = base64.b64decode(uri.split(",", 1)[1], validate=True)
            except (IndexError, ValueError):
                raise self.error(f"buffer {index} has a data uri that is not base64") from None
        else:
            path = self.file.parent / unquote(uri)
            try:
                data = read_input(path, "mesh")  # a regular file within the cap, never a pipe
            except OSError as error:
                raise self.error(
                    f"buffer {index} file {uri!r} cannot be read: {error.strerror or error}"
                ) from None
        self.buffers[index] = data
        return data

    def accessor(self, index: Any, where: str, components: int) -> np.ndarray:
        spec = self.item("accessors", index, where)
        if "sparse" in spec:
            raise self.error(f"accessor {index} is sparse (not read by meshcol)")
        count = spec.get("count")
        dtype = _DTYPES.get(spec.get("componentType", -1))
        width = _COMPONENTS.get(str(spec.get("type")))
        if width != components or dtype is None or not isinstance(count, int) or count < 0:
            raise self.error(f"accessor {index} is not what {where} needs")
        if "bufferView" not in spec:
            return np.zeros((count, width))
        view = self.item("bufferViews", spec["bufferView"], f"accessor {index}")
        buffer = view.get("buffer")
        if isinstance(buffer, bool) or not isinstance(buffer, int):
            raise self.error(f"bufferView {spec['bufferView']} has no buffer")
        data = self.buffer(buffer)
        item = np.dtype(dtype).itemsize
        stride = view.get("byteStride") or item * width
        start = int(view.get("byteOffset", 0)) + int(spec.get("byteOffset", 0))
        end = int(view.get("byteOffset", 0)) + int(view.get("byteLength", 0))
        need = start + stride * max(count - 1, 0) + item * width if count else start
        if need > min(end, len(data)) or start < 0 or stride < item * width:
            raise self.error(f"accessor {index} reads past its bufferView or buffer")
        array = np.ndarray(
            (count, width), dtype=dtype, buffer=data, offset=start, strides=(stride, item)
        )
        return np.array(array, dtype=np.float64 if dtype == "<f4" else np.int64)

    def mesh(self, index: Any, where: str) -> tuple[np.ndarray, np.ndarray]:
        """A mesh's triangles (every TRIANGLES primitive), in the mesh's frame."""
        spec = self.item("meshes", index, where)
        blocks_v, blocks_f, base = [], [], 0
        for k, primitive in enumerate(self.items("primitives", spec)):
            if not isinstance(primitive, dict) or primitive.get("mode", 4) != 4:
                continue
            compressed = primitive.get("extensions", {})
            if isinstance(compressed, dict) and set(compressed) & _COMPRESSIONS:
                raise self.error(
                    f"mesh {index} primitive {k} is compressed "
                    f"({', '.join(sorted(set(compressed) & _COMPRESSIONS))}), which meshcol "
                    "does not decode"
                )
            attributes = primitive.get("attributes", {})
            if not isinstance(attributes, dict) or "POSITION" not in attributes:
                continue
            what = f"mesh {index} primitive {k}"
            vertices = self.accessor(attributes["POSITION"], f"{what} POSITION", 3)
            if "indices" in primitive:
                faces = self.accessor(primitive["indices"], f"{what} indices", 1).reshape(-1)
            else:
                faces = np.arange(len(vertices))
            if len(faces) % 3 or (len(faces) and (faces.min() < 0 or faces.max() >= len(vertices))):
                raise self.error(f"{what} has indices that are not triangles of its vertices")
            blocks_v.append(vertices)
            blocks_f.append(faces.reshape(-1, 3) + base)
            base += len(vertices)
        if not blocks_v:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
        return np.concatenate(blocks_v), np.concatenate(blocks_f)


def _node_matrix(node: dict) -> np.ndarray:
    """A node's local transform, (4, 4) column convention (glTF's ``matrix`` is
    column-major; else translation, rotation ``[x, y, z, w]``, scale)."""
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T
    import trimesh

    x, y, z, w = (float(v) for v in node.get("rotation", [0, 0, 0, 1]))
    matrix = np.eye(4)
    turn = trimesh.transformations.quaternion_matrix([w, x, y, z])[:3, :3]
    matrix[:3, :3] = turn * np.asarray(node.get("scale", [1, 1, 1]), dtype=np.float64)
    matrix[:3, 3] = np.asarray(node.get("translation", [0, 0, 0]), dtype=np.float64)
    return matrix


def node_worlds(gltf: GltfFile) -> tuple[dict[int, np.ndarray], dict[int, int]]:
    """Every node's world transform (nodes outside the scene: from their own root) and its
    parent; a node with two parents or a cycle is refused."""
    nodes = gltf.items("nodes")
    if len(nodes) > MAX_NODES:
        raise gltf.error(f"more than {MAX_NODES} nodes")
    parent: dict[int, int] = {}
    for k, node in enumerate(nodes):
        for child in node.get("children", []) if isinstance(node, dict) else []:
            gltf.item("nodes", child, f"node {k} children")
            if child in parent or child == k:
                raise gltf.error(f"node {child} has two parents or is its own child")
            parent[child] = k
    worlds: dict[int, np.ndarray] = {}
    for k in range(len(nodes)):
        chain, current = [], k
        while current not in worlds:
            chain.append(current)
            if current not in parent:
                break
            current = parent[current]
            if len(chain) > len(nodes):
                raise gltf.error(f"node {k}'s parents form a cycle")
        above = worlds.get(current, np.eye(4)) if current not in chain else np.eye(4)
        for index in reversed(chain):
            node = gltf.item("nodes", index, "a scene")
            above = worlds[index] = above @ _node_matrix(node)
    return worlds, parent


def _ext(node: dict) -> tuple[dict, str]:
    """The node's physics extension object and its name ({} when none)."""
    extensions = node.get("extensions", {})
    if not isinstance(extensions, dict):
        return {}, ""
    for name in (KHR_BODIES, OMI_BODY):
        value = extensions.get(name)
        if isinstance(value, dict) and (name == KHR_BODIES or set(value) & _NODE_KEYS):
            return value, name
    return _legacy_omi(extensions)


_NODE_KEYS = {"motion", "collider", "trigger"}


def _legacy_omi(extensions: dict) -> tuple[dict, str]:
    """OMI's earlier draft (what Godot 4.1 and 4.2 write): a body ``{"type": ...}`` (``trigger``
    makes its shapes triggers, any other type is a body) and a node-level
    ``OMI_physics_shape {"shape": i}`` for a collider, read as the current form."""
    body, shape = extensions.get(OMI_BODY), extensions.get(OMI_SHAPE)
    out: dict[str, Any] = {}
    if isinstance(body, dict) and "type" in body:
        out["legacy_trigger" if body["type"] == "trigger" else "motion"] = {"type": body["type"]}
    if isinstance(shape, dict) and "shape" in shape:
        out["collider"] = {"shape": shape["shape"]}
    return (out, OMI_BODY) if out else ({}, "")


def _scene(
    document: Any, binary: bytes | None, file: Path, source: str, kind: str
) -> FileScene | None:
    if not has_physics(document) or _RENDER_ONLY.get():
        return None
    check_references(document, kind, source)
    gltf = GltfFile(document, binary, file, source, kind)
    worlds, parent = node_worlds(gltf)
    nodes = gltf.items("nodes")
    groups: dict[int, BodyGroup] = {}
    filters: dict[int, list[Any]] = {}
    warnings: list[str] = []
    triggers = planes = 0
    colliders_of: set[int] = set()
    conflicts: set[str] = set()
    for k, node in enumerate(nodes):
        ext, name = _ext(node)
        if "trigger" in ext:
            triggers += 1
        collider = ext.get("collider")
        if not isinstance(collider, dict):
            continue
        up = parent.get(k)
        if up is not None and "legacy_trigger" in _ext(nodes[up])[0]:
            triggers += 1  # a shape of an earlier-draft OMI trigger body
            continue
        element = _collider_element(gltf, k, node, collider, name, worlds)
        if element is None:
            planes += 1
            continue
        colliders_of.add(k)
        owner = _body_node(k, parent, nodes)
        group = _owner_group(groups, owner, nodes, worlds)
        conflicts.update(_conflicts(nodes, {k, owner}, element))
        element.name = _node_name(nodes, k) if k != owner else element.name
        group.elements.append(element)
        filters.setdefault(owner, []).append(collider.get("collisionFilter"))
    for node in nodes:
        ext, _ = _ext(node)
        geometry = ext.get("collider", {}).get("geometry", {}) if ext else {}
        if isinstance(geometry, dict) and isinstance(geometry.get("node"), int):
            colliders_of.add(geometry["node"])
    drawn = _in_scenes(gltf)
    _add_hinted(gltf, drawn, parent, worlds, groups, colliders_of)
    names = [_node_name(nodes, k) for k in range(len(nodes))]
    for k, group in groups.items():
        group.ancestors = ancestor_names(k, parent, names)
    warnings.extend(sorted(conflicts))
    render = sum(
        1
        for k in drawn
        if isinstance(nodes[k], dict) and "mesh" in nodes[k] and k not in colliders_of | set(groups)
    )
    if triggers:
        warnings.append(f"{triggers} trigger(s) not checked (triggers are not solid)")
    if planes:
        warnings.append(f"{planes} plane collider(s) not checked (a plane is not a solid)")
    if render and groups:
        warnings.append(
            f"{render} mesh node(s) with no collider of their own not read (render geometry)"
        )
    return FileScene(list(groups.values()), _filtered_pairs(gltf, filters), "m", warnings)


def _owner_group(groups: dict[int, BodyGroup], owner: int, nodes: list, worlds: dict) -> BodyGroup:
    """The group of body node ``owner``, made on first use; named as the node without a Godot
    hint (the extensions win over it)."""
    group = groups.get(owner)
    if group is None:
        name = hinted_name(_node_name(nodes, owner))
        group = groups[owner] = BodyGroup(str(owner), name, worlds[owner])
    return group


def _conflicts(nodes: list, which: set[int], element: ShapeElement) -> list[str]:
    """A warning for each of the nodes ``which`` whose Godot hint asks for another collider
    than ``element``, the one the extensions give."""
    found = (hint_conflict(_node_name(nodes, n), element) for n in sorted(which))
    return [w for w in found if w]


def _add_hinted(
    gltf: GltfFile,
    drawn: set[int],
    parent: dict[int, int],
    worlds: dict,
    groups: dict[int, BodyGroup],
    colliders_of: set[int],
) -> None:
    """The drawn mesh nodes with no collider whose name carries a Godot collision hint
    (:mod:`meshcol.io.gltf_godot`): each a body of its own, or a part of the rigid body
    (``motion``) it hangs under; added to ``groups`` and ``colliders_of``."""
    nodes = gltf.items("nodes")
    for k, hinted in hint_groups(gltf, nodes, drawn - colliders_of - set(groups), worlds).items():
        colliders_of.add(k)
        body = _motion_node(k, parent, nodes)
        if body is None:
            groups[k] = hinted
            continue
        _owner_group(groups, body, nodes, worlds).elements.extend(hinted.elements)


def _in_scenes(gltf: GltfFile) -> set[int]:
    """The nodes of the file's scenes (drawn), the roots' descendants included."""
    nodes = gltf.items("nodes")
    todo = [
        n
        for scene in gltf.items("scenes")
        if isinstance(scene, dict)
        for n in scene.get("nodes", [])
    ]
    seen: set[int] = set()
    while todo:
        k = todo.pop()
        if isinstance(k, int) and 0 <= k < len(nodes) and k not in seen:
            seen.add(k)
            node = nodes[k]
            todo.extend(node.get("children", []) if isinstance(node, dict) else [])
    return seen


def _node_name(nodes: list, k: int) -> str:
    name = nodes[k].get("name") if isinstance(nodes[k], dict) else None
    return name if isinstance(name, str) and name else f"node_{k}"


def _motion_node(k: int, parent: dict[int, int], nodes: list) -> int | None:
    """The node with ``motion`` (a rigid body) at or above node ``k``, or None."""
    current: int | None = k
    while current is not None:
        if "motion" in _ext(nodes[current])[0]:
            return current
        current = parent.get(current)
    return None


def _body_node(k: int, parent: dict[int, int], nodes: list) -> int:
    """The node with ``motion`` at or above node ``k``; else the render node (a node with a
    mesh and no collider) node ``k`` hangs from, whose collider it is; else ``k``."""
    body = _motion_node(k, parent, nodes)
    if body is not None:
        return body
    up = parent.get(k)
    if up is not None and "mesh" in nodes[up] and "collider" not in _ext(nodes[up])[0]:
        return up
    return k


def _collider_element(
    gltf: GltfFile, k: int, node: dict, collider: dict, extension: str, worlds: dict
) -> ShapeElement | None:
    """The element of node ``k``'s collider (None for a plane)."""
    name = _node_name(gltf.items("nodes"), k)
    where = f"node {k} collider"
    if extension == KHR_BODIES:
        geometry = collider.get("geometry", collider)
        if not isinstance(geometry, dict):
            raise gltf.error(f"{where} geometry is not an object")
        if "node" in geometry:
            target = gltf.item("nodes", geometry["node"], f"{where} geometry")
            if "mesh" not in target:
                raise gltf.error(f"{where} geometry node {geometry['node']} has no mesh")
            vertices, faces = gltf.mesh(target["mesh"], f"node {geometry['node']}")
            kind = "hull" if geometry.get("convexHull") is True else "mesh"
            world = worlds[geometry["node"]]
            return ShapeElement(name, world, None, vertices, faces, kind)
        shapes = gltf.items("shapes", gltf.extension(KHR_SHAPES))
        shape = gltf.item("shapes", geometry.get("shape"), f"{where} geometry", {"shapes": shapes})
        return _shape_element(gltf, name, worlds[k], shape, where, khr=True)
    shapes = gltf.items("shapes", gltf.extension(OMI_SHAPE))
    shape = gltf.item("shapes", collider.get("shape"), where, {"shapes": shapes})
    return _shape_element(gltf, name, worlds[k], shape, where, khr=False)


# Each extension's defaults: (box size, sphere radius, capsule height, capsule radius,
# cylinder height, cylinder radius). KHR_implicit_shapes' schemas; OMI_physics_shape's README.
_DEFAULTS = {True: (1.0, 0.5, 0.5, 0.25, 0.5, 0.25), False: (1.0, 0.5, 1.0, 0.5, 2.0, 0.5)}


def _shape_element(
    gltf: GltfFile, name: str, world: np.ndarray, shape: dict, where: str, khr: bool
) -> ShapeElement | None:
    kind = shape.get("type")
    # the parameters sit under the type's name; OMI's earlier draft put them beside "type"
    params = shape.get(kind, shape if not khr else {}) if isinstance(kind, str) else {}
    if not isinstance(params, dict):
        raise gltf.error(f"{where} shape {kind!r} parameters are not an object")
    box, sphere, cap_h, cap_r, cyl_h, cyl_r = _DEFAULTS[khr]
    primitive: Primitive
    try:
        if kind == "plane":
            return None
        if kind == "box":
            x, y, z = (float(v) for v in params.get("size", [box] * 3))
            primitive = Box((x, y, z))
        elif kind == "sphere":
            primitive = Sphere(float(params.get("radius", sphere)))
        elif kind in ("capsule", "cylinder"):
            height = float(params.get("height", cap_h if kind == "capsule" else cyl_h))
            default = cap_r if kind == "capsule" else cyl_r
            top = float(params.get("radiusTop", default))
            bottom = float(params.get("radiusBottom", default))
            if top != bottom:
                vertices, faces = _tapered(kind, height, top, bottom)
                return ShapeElement(name, world, None, vertices, faces, "hull")
            primitive = Capsule(top, height) if kind == "capsule" else Cylinder(top, height)
        elif kind in ("convex", "trimesh") and not khr:
            vertices, faces = gltf.mesh(params.get("mesh"), f"{where} shape {kind}")
            collider = "hull" if kind == "convex" else "mesh"
            return ShapeElement(name, world, None, vertices, faces, collider)
        else:
            raise gltf.error(f"{where} has shape type {kind!r}, which meshcol does not read")
    except (TypeError, ValueError) as error:
        if isinstance(error, InvalidMeshError):
            raise
        raise gltf.error(f"{where} shape {kind!r} has a bad parameter: {error}") from None
    axis = "Y" if isinstance(primitive, (Capsule, Cylinder)) else "Z"  # box sizes: node axes
    return ShapeElement(name, world, primitive, None, None, None, axis=axis)


def _tapered(kind: str, height: float, top: float, bottom: float):
    """A tapered cylinder (a frustum) or tapered capsule (two balls and the cone tangent to
    both), along Y: a closed convex surface of revolution, 32 sections around."""
    half = height / 2
    if kind == "cylinder":
        profile = [(0.0, -half), (bottom, -half), (top, half), (0.0, half)]
    else:
        # the outer tangent leaves each ball at latitude a, sin a = (bottom - top) / height
        a = float(np.arcsin(np.clip((bottom - top) / height, -1.0, 1.0)))
        low = np.linspace(-np.pi / 2, a, 9)
        high = np.linspace(a, np.pi / 2, 9)
        profile = [(bottom * np.cos(t), -half + bottom * np.sin(t)) for t in low]
        profile += [(top * np.cos(t), half + top * np.sin(t)) for t in high[1:]]
    return _lathe(np.asarray(profile, dtype=np.float64))


def _lathe(profile: np.ndarray, sections: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """The surface of a profile ``(radius, y)`` from the bottom pole to the top pole turned
    about Y: vertices, and outward triangles (the poles' degenerate ones merge away)."""
    angles = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    rings = len(profile)
    radius, y = profile[:, 0][:, None], profile[:, 1][:, None]
    vertices = np.stack(
        [radius * np.cos(angles), np.broadcast_to(y, (rings, sections)), -radius * np.sin(angles)],
        axis=2,
    ).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings - 1), np.arange(sections), indexing="ij")
    a, b = i * sections + j, i * sections + (j + 1) % sections
    c, d = a + sections, b + sections
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)]).reshape(-1, 3)
    return vertices, faces.astype(np.int64)


def _does_collide(a: dict | None, b: dict | None) -> bool:
    """KHR_physics_rigid_bodies: ``A`` collides with ``B`` unless ``B``'s filter leaves
    ``A``'s systems out (``collideWithSystems``) or names them all
    (``notCollideWithSystems``)."""
    systems = set((a or {}).get("collisionSystems", []))
    if b is None:
        return True
    if "collideWithSystems" in b:
        return bool(systems) and systems <= set(b["collideWithSystems"])
    if "notCollideWithSystems" in b:
        return not (systems and systems <= set(b["notCollideWithSystems"]))
    return True


def _filtered_pairs(gltf: GltfFile, filters: dict[int, list[Any]]) -> list[tuple[str, str, str]]:
    """The body pairs (group keys) none of whose colliders' filters let them collide."""
    table = gltf.items("collisionFilters", gltf.extension(KHR_BODIES))
    if not table:
        return []

    def spec(index: Any) -> dict | None:
        if index is None:
            return None
        return gltf.item("collisionFilters", index, "a collider", {"collisionFilters": table})

    resolved = {owner: [spec(i) for i in indices] for owner, indices in filters.items()}
    out = []
    owners = list(resolved)
    for i, a in enumerate(owners):
        for b in owners[i + 1 :]:
            if not any(
                _does_collide(x, y) and _does_collide(y, x)
                for x in resolved[a]
                for y in resolved[b]
            ):
                out.append((str(a), str(b), f"{KHR_BODIES} collision filters"))
    return out
