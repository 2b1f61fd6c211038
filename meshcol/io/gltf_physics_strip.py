"""The physics colliders of a glTF document taken out, so that ``--to gltf-physics`` can write
new ones in their place (a re-run of ``hull``, ``fit`` or ``decompose`` on an asset it wrote).

What goes: every node's collider (``KHR_physics_rigid_bodies.collider``,
``OMI_physics_body.collider``, the node-level ``OMI_physics_shape`` of OMI's earlier draft);
then what existed only for them: nodes left with nothing (no mesh, child, camera, skin, extras
or extension; a KHR collider's geometry node counts as nothing when it is in no scene), the
shapes no trigger uses, the meshes only those nodes and shapes drew, their accessors and
buffer views. Everything else stays, renumbered where something before it went: bodies
(``motion``), triggers, joints, render meshes, materials, skins, animations, other extensions,
names and extras.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from meshcol.io.gltf_physics import KHR_BODIES, KHR_SHAPES, OMI_BODY, OMI_SHAPE

__all__ = ["Stripped", "strip_colliders"]

# what a node may hold and still be nothing once its collider is gone
_BARE = {"name", "matrix", "translation", "rotation", "scale"}


@dataclass
class Stripped:
    """What :func:`strip_colliders` took out: counts, for the command's message."""

    colliders: dict[str, int] = field(default_factory=dict)  # extension -> colliders
    nodes: int = 0
    meshes: int = 0
    renumbered: dict[int, int] = field(default_factory=dict)  # old node index -> new

    def summary(self) -> str:
        """``replaced 2 KHR_physics_rigid_bodies and 2 OMI_physics_body colliders`` (empty
        when nothing was there)."""
        if not self.colliders:
            return ""
        parts = " and ".join(f"{n} {name}" for name, n in self.colliders.items())
        return f"replaced {parts} collider(s) already in the asset"


def strip_colliders(
    document: dict[str, Any], check: Callable[[dict[str, Any]], None] | None = None
) -> Stripped:
    """Take every physics collider out of ``document`` (changed in place; see the module).
    ``check(document)`` is called once the colliders are out and before anything is
    renumbered (what it reports names the nodes as the file does)."""
    out = Stripped()
    nodes = _list(document, "nodes")
    geometry_nodes: set[int] = set()
    candidates: set[int] = set()
    for k, node in enumerate(nodes):
        if not isinstance(node, dict):
            continue
        extensions = node.get("extensions")
        if not isinstance(extensions, dict):
            continue
        for name in (KHR_BODIES, OMI_BODY):
            value = extensions.get(name)
            if isinstance(value, dict) and "collider" in value:
                collider = value.pop("collider")
                out.colliders[name] = out.colliders.get(name, 0) + 1
                candidates.add(k)
                geometry = collider.get("geometry") if isinstance(collider, dict) else None
                if isinstance(geometry, dict) and _index(geometry.get("node"), len(nodes)):
                    geometry_nodes.add(geometry["node"])
                if not value:
                    del extensions[name]
        legacy = extensions.get(OMI_SHAPE)
        if isinstance(legacy, dict) and "shape" in legacy:  # OMI's earlier draft
            del extensions[OMI_SHAPE]
            out.colliders[OMI_BODY] = out.colliders.get(OMI_BODY, 0) + 1
            candidates.add(k)
        if not extensions:
            del node["extensions"]
    if check is not None:
        check(document)
    if not out.colliders:
        return out
    dropped_meshes = _strip_shapes(document, nodes)
    removed = _dead_nodes(document, nodes, candidates, geometry_nodes)
    dropped_meshes |= {nodes[k]["mesh"] for k in removed if _index(nodes[k].get("mesh"), None)}
    out.nodes = len(removed)
    out.renumbered = _renumber_nodes(document, removed)
    out.meshes = _drop_meshes(document, dropped_meshes)
    return out


def _top(document: dict) -> dict:
    value = document.get("extensions", {})
    return value if isinstance(value, dict) else {}


def _list(owner: Any, name: str) -> list:
    value = owner.get(name, []) if isinstance(owner, dict) else []
    return value if isinstance(value, list) else []


def _index(value: Any, size: int | None) -> bool:
    return (
        isinstance(value, int)
        and not isinstance(value, bool)
        and value >= 0
        and (size is None or value < size)
    )


def _trigger_shape_users(nodes: list) -> dict[str, list[dict]]:
    """Per shape extension, the objects of the remaining triggers that hold a shape index."""
    users: dict[str, list[dict]] = {KHR_SHAPES: [], OMI_SHAPE: []}
    for node in nodes:
        extensions = node.get("extensions", {}) if isinstance(node, dict) else {}
        if not isinstance(extensions, dict):
            continue
        khr, omi = extensions.get(KHR_BODIES), extensions.get(OMI_BODY)
        trigger = khr.get("trigger") if isinstance(khr, dict) else None
        geometry = trigger.get("geometry") if isinstance(trigger, dict) else None
        if isinstance(geometry, dict) and "shape" in geometry:
            users[KHR_SHAPES].append(geometry)
        trigger = omi.get("trigger") if isinstance(omi, dict) else None
        if isinstance(trigger, dict) and "shape" in trigger:
            users[OMI_SHAPE].append(trigger)
    return users


def _shape_mesh_holders(document: dict) -> list[dict]:
    """The ``convex``/``trimesh`` objects of the OMI shapes, each holding a mesh index."""
    container = _top(document).get(OMI_SHAPE, {})
    out = []
    for shape in _list(container, "shapes"):
        for kind in ("convex", "trimesh"):
            held = shape.get(kind) if isinstance(shape, dict) else None
            if isinstance(held, dict) and _index(held.get("mesh"), None):
                out.append(held)
    return out


def _strip_shapes(document: dict, nodes: list) -> set[int]:
    """Keep the shapes of both extensions the remaining triggers use, renumbered; the meshes
    of the OMI shapes that go."""
    before = {id(h): h["mesh"] for h in _shape_mesh_holders(document)}
    top = _top(document)
    for name, holders in _trigger_shape_users(nodes).items():
        container = top.get(name) if isinstance(top, dict) else None
        shapes = _list(container, "shapes")
        keep = sorted({h["shape"] for h in holders if _index(h["shape"], len(shapes))})
        new = {old: i for i, old in enumerate(keep)}
        for holder in holders:
            if _index(holder["shape"], None):
                holder["shape"] = new.get(holder["shape"], holder["shape"])
        if isinstance(container, dict):
            container["shapes"] = [shapes[k] for k in keep]
            if not keep and set(container) == {"shapes"}:  # nothing left: the writer adds it
                del top[name]
                used = _list(document, "extensionsUsed")
                if name in used:
                    used.remove(name)
    after = {id(h) for h in _shape_mesh_holders(document)}
    return {mesh for key, mesh in before.items() if key not in after}


def _dead_nodes(document: dict, nodes: list, candidates: set[int], geometry: set[int]) -> set[int]:
    """The collider and collision-geometry nodes left with nothing, none referenced by what
    stays (skins, animations, triggers, joints); a node whose children all go may go too."""
    drawn = _drawn(document, nodes)
    pinned = _pinned_nodes(document, nodes)
    removed: set[int] = set()
    changed = True
    while changed:
        changed = False
        for k in sorted((candidates | geometry) - removed - pinned):
            node = nodes[k]
            if not isinstance(node, dict):
                continue
            allowed = _BARE | ({"mesh"} if k in geometry and k not in drawn else set())
            children = [c for c in _list(node, "children") if c not in removed]
            if set(node) - allowed - {"children"} or children:
                continue
            if "mesh" in node and k in candidates and k not in geometry:
                continue
            removed.add(k)
            changed = True
    return removed


def _drawn(document: dict, nodes: list) -> set[int]:
    todo = [n for scene in _list(document, "scenes") for n in _list(scene, "nodes")]
    seen: set[int] = set()
    while todo:
        k = todo.pop()
        if _index(k, len(nodes)) and k not in seen:
            seen.add(k)
            todo.extend(_list(nodes[k], "children"))
    return seen


def _pinned_nodes(document: dict, nodes: list) -> set[int]:
    """Nodes something that stays refers to (besides scenes and parents)."""
    pinned: set[int] = set()
    for skin in _list(document, "skins"):
        pinned.update(j for j in _list(skin, "joints") if _index(j, None))
        if isinstance(skin, dict) and _index(skin.get("skeleton"), None):
            pinned.add(skin["skeleton"])
    for animation in _list(document, "animations"):
        for channel in _list(animation, "channels"):
            target = channel.get("target", {}) if isinstance(channel, dict) else {}
            if isinstance(target, dict) and _index(target.get("node"), None):
                pinned.add(target["node"])
    for holder, key in _node_refs_in_physics(nodes):
        pinned.add(holder[key])
    return pinned


def _node_refs_in_physics(nodes: list) -> list[tuple[dict, str]]:
    """``(holder, key)`` of every node index the remaining KHR objects hold (a trigger's
    geometry node, a joint's connected node)."""
    refs = []
    for node in nodes:
        extensions = node.get("extensions", {}) if isinstance(node, dict) else {}
        khr = extensions.get(KHR_BODIES, {}) if isinstance(extensions, dict) else {}
        if not isinstance(khr, dict):
            continue
        trigger = khr.get("trigger")
        geometry = trigger.get("geometry") if isinstance(trigger, dict) else None
        if isinstance(geometry, dict) and _index(geometry.get("node"), None):
            refs.append((geometry, "node"))
        joint = khr.get("joint")
        if isinstance(joint, dict) and _index(joint.get("connectedNode"), None):
            refs.append((joint, "connectedNode"))
    return refs


def _renumber_nodes(document: dict, removed: set[int]) -> dict[int, int]:
    nodes = _list(document, "nodes")
    new: dict[int, int] = {}
    for k in range(len(nodes)):
        if k not in removed:
            new[k] = len(new)

    def renumber(values: list) -> list:
        return [new[v] for v in values if _index(v, None) and v in new]

    for scene in _list(document, "scenes"):
        if isinstance(scene, dict) and "nodes" in scene:
            scene["nodes"] = renumber(_list(scene, "nodes"))
    for node in nodes:
        if isinstance(node, dict) and "children" in node:
            node["children"] = renumber(_list(node, "children"))
            if not node["children"]:
                del node["children"]
    for skin in _list(document, "skins"):
        if isinstance(skin, dict):
            skin["joints"] = renumber(_list(skin, "joints"))
            if _index(skin.get("skeleton"), None) and skin["skeleton"] in new:
                skin["skeleton"] = new[skin["skeleton"]]
    for animation in _list(document, "animations"):
        for channel in _list(animation, "channels"):
            target = channel.get("target", {}) if isinstance(channel, dict) else {}
            if (
                isinstance(target, dict)
                and _index(target.get("node"), None)
                and target["node"] in new
            ):
                target["node"] = new[target["node"]]
    for holder, key in _node_refs_in_physics(nodes):
        holder[key] = new.get(holder[key], holder[key])
    document["nodes"] = [n for k, n in enumerate(nodes) if k not in removed]
    return new


def _drop_meshes(document: dict, candidates: set[int]) -> int:
    """Remove the candidate meshes nothing draws any more, then the accessors and buffer
    views only they used; every reference renumbered. The count of meshes removed."""
    meshes = _list(document, "meshes")
    holders = _shape_mesh_holders(document)
    used = {
        n["mesh"]
        for n in _list(document, "nodes")
        if isinstance(n, dict) and _index(n.get("mesh"), None)
    } | {h["mesh"] for h in holders}
    gone = {m for m in candidates if _index(m, len(meshes)) and m not in used}
    if not gone:
        return 0
    new = {k: i for i, k in enumerate(k for k in range(len(meshes)) if k not in gone)}
    for node in _list(document, "nodes"):
        if isinstance(node, dict) and _index(node.get("mesh"), None) and node["mesh"] in new:
            node["mesh"] = new[node["mesh"]]
    for holder in holders:
        holder["mesh"] = new.get(holder["mesh"], holder["mesh"])
    accessors = {a for m in gone for a in _mesh_accessors(meshes[m])}
    document["meshes"] = [m for k, m in enumerate(meshes) if k not in gone]
    _drop_accessors(document, accessors)
    return len(gone)


def _mesh_accessors(mesh: Any) -> list[int]:
    out: list[int] = []
    for primitive in _list(mesh, "primitives"):
        if not isinstance(primitive, dict):
            continue
        attributes = primitive.get("attributes", {})
        if isinstance(attributes, dict):
            out.extend(v for v in attributes.values() if _index(v, None))
        if _index(primitive.get("indices"), None):
            out.append(primitive["indices"])
        for target in _list(primitive, "targets"):
            if isinstance(target, dict):
                out.extend(v for v in target.values() if _index(v, None))
    return out


def _accessor_holders(document: dict) -> list[tuple[dict, str]]:
    """``(holder, key)`` of every accessor index the document holds."""
    refs: list[tuple[dict, str]] = []
    for mesh in _list(document, "meshes"):
        for primitive in _list(mesh, "primitives"):
            if not isinstance(primitive, dict):
                continue
            attributes = primitive.get("attributes", {})
            if isinstance(attributes, dict):
                refs.extend((attributes, key) for key in attributes)
            if "indices" in primitive:
                refs.append((primitive, "indices"))
            for target in _list(primitive, "targets"):
                if isinstance(target, dict):
                    refs.extend((target, key) for key in target)
    for skin in _list(document, "skins"):
        if isinstance(skin, dict) and "inverseBindMatrices" in skin:
            refs.append((skin, "inverseBindMatrices"))
    for animation in _list(document, "animations"):
        for sampler in _list(animation, "samplers"):
            if isinstance(sampler, dict):
                refs.extend((sampler, key) for key in ("input", "output") if key in sampler)
    for node in _list(document, "nodes"):
        extensions = node.get("extensions", {}) if isinstance(node, dict) else {}
        instancing = (
            extensions.get("EXT_mesh_gpu_instancing") if isinstance(extensions, dict) else None
        )
        attributes = instancing.get("attributes") if isinstance(instancing, dict) else None
        if isinstance(attributes, dict):
            refs.extend((attributes, key) for key in attributes)
    return refs


def _drop_accessors(document: dict, candidates: set[int]) -> None:
    accessors = _list(document, "accessors")
    holders = [(h, k) for h, k in _accessor_holders(document) if _index(h[k], None)]
    used = {holder[key] for holder, key in holders}
    gone = {a for a in candidates if _index(a, len(accessors)) and a not in used}
    if not gone:
        return
    new = {k: i for i, k in enumerate(k for k in range(len(accessors)) if k not in gone)}
    for holder, key in holders:
        holder[key] = new.get(holder[key], holder[key])
    views: set[Any] = set()
    for a in gone:
        spec = accessors[a] if isinstance(accessors[a], dict) else {}
        views.add(spec.get("bufferView"))
        sparse = spec.get("sparse", {})
        for part in ("indices", "values"):
            if isinstance(sparse, dict) and isinstance(sparse.get(part), dict):
                views.add(sparse[part].get("bufferView"))
    document["accessors"] = [a for k, a in enumerate(accessors) if k not in gone]
    _drop_views(document, {v for v in views if _index(v, None)})


def _view_holders(document: dict) -> list[tuple[dict, str]]:
    refs: list[tuple[dict, str]] = []
    for accessor in _list(document, "accessors"):
        if not isinstance(accessor, dict):
            continue
        if "bufferView" in accessor:
            refs.append((accessor, "bufferView"))
        sparse = accessor.get("sparse", {})
        for part in ("indices", "values"):
            if isinstance(sparse, dict) and isinstance(sparse.get(part), dict):
                refs.append((sparse[part], "bufferView"))
    for image in _list(document, "images"):
        if isinstance(image, dict) and "bufferView" in image:
            refs.append((image, "bufferView"))
    for mesh in _list(document, "meshes"):
        for primitive in _list(mesh, "primitives"):
            extensions = primitive.get("extensions", {}) if isinstance(primitive, dict) else {}
            for value in extensions.values() if isinstance(extensions, dict) else []:
                if isinstance(value, dict) and "bufferView" in value:  # Draco
                    refs.append((value, "bufferView"))
    return refs


def _drop_views(document: dict, candidates: set[int]) -> None:
    views = _list(document, "bufferViews")
    holders = [(h, k) for h, k in _view_holders(document) if _index(h[k], None)]
    used = {holder[key] for holder, key in holders}
    gone = {v for v in candidates if _index(v, len(views)) and v not in used}
    if not gone:
        return
    new = {k: i for i, k in enumerate(k for k in range(len(views)) if k not in gone)}
    for holder, key in holders:
        holder[key] = new.get(holder[key], holder[key])
    document["bufferViews"] = [v for k, v in enumerate(views) if k not in gone]
