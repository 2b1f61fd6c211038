"""Godot's import hints in a glTF file that also has physics extensions: which one decides a
node's collider.

Godot reads both a node name's hint (``-col``, ``-colonly``: the node's triangles;
``-convcol``, ``-convcolonly``: their hull; :mod:`meshcol.io.collision_names`) and the physics
extensions (``OMI_physics_body``, ``KHR_physics_rigid_bodies``). meshcol's precedence:

- a node with explicit physics (a collider of its own, or colliders hanging from it as its
  body) is read from the extensions: they win, the hint is cut from the body's name, and a
  warning names the node when the hint asks for another collider than the extension gives
  (``-convcol`` on a node whose collider is a box or its triangles);
- a mesh node without a collider whose name carries a collision hint is a body of its own,
  its collider the hint's, exactly as in a file without physics extensions (under a node
  with ``motion``, a part of that rigid body);
- other mesh nodes (no physics, no collision hint; ``-rigid`` alone gives no shape) are render
  geometry, not read (the physics reader's warning counts them).
"""

from __future__ import annotations

from typing import Any

from meshcol.io.collision_names import godot_hint
from meshcol.io.physics_bodies import BodyGroup, ShapeElement

__all__ = ["hint_conflict", "hint_groups", "hinted_name"]


def hinted_name(name: str) -> str:
    """``name`` without the Godot hint that ends it (``Crate-convcol``: ``Crate``)."""
    hint = godot_hint(name)
    return name if hint is None else hint.name


def hint_conflict(name: str, element: ShapeElement) -> str | None:
    """The warning for a node named ``name`` whose collider from the physics extensions is
    ``element``, when the name's Godot hint asks for another collider; None when they agree
    or there is no such hint."""
    hint = godot_hint(name)
    if hint is None or hint.collider is None:
        return None
    if element.primitive is not None:
        given = type(element.primitive).__name__.lower()
    else:
        given = "triangles" if element.collider == "mesh" else "hull"
    wanted = "triangles" if hint.collider == "mesh" else "hull"
    if given == wanted:
        return None
    return (
        f"node '{name}': its physics extension's collider ({given}) is read, not the Godot "
        f"hint {hint.hint} ({wanted})"
    )


def hint_groups(gltf: Any, nodes: list, candidates: set[int], worlds: dict) -> dict[int, BodyGroup]:
    """A body for each of the mesh nodes ``candidates`` (drawn, no physics of their own or
    around them) whose name carries a Godot collision hint: the node's triangles at its world
    transform, the hint's collider kind; by node index, in node order."""
    out: dict[int, BodyGroup] = {}
    for k in sorted(candidates):
        node = nodes[k]
        name = node.get("name") if isinstance(node, dict) else None
        hint = godot_hint(name) if isinstance(name, str) else None
        if hint is None or hint.collider is None or "mesh" not in node:
            continue
        vertices, faces = gltf.mesh(node["mesh"], f"node {k}")
        if not len(faces):
            continue
        element = ShapeElement(hint.name, worlds[k], None, vertices, faces, hint.collider)
        out[k] = BodyGroup(str(k), hint.name, worlds[k], [element])
    return out
