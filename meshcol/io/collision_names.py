"""Collision naming conventions in mesh files, one place for every format that has node or
object names (OBJ, glTF/GLB, FBX).

Unreal Engine's prefixes (its FBX Static Mesh pipeline, "Collision"): an object named
``<PREFIX>_<render mesh>_<NN>`` is collision geometry of the render mesh ``<render mesh>``,
not render geometry; ``UCX`` a convex hull, ``UBX`` a box, ``USP`` a sphere, ``UCP`` a
capsule (:data:`UNREAL_PREFIXES`). The engine fits the primitive to the part's vertices, so
meshcol uses the enclosing primitive of that kind (:func:`meshcol.analysis.fit.fit_point_sets`),
queried exactly.

Godot's import hints (its "Node type customization using name suffixes", glTF and FBX
scenes): a node whose name ends in ``-col`` or ``-colonly`` collides as its triangles (a
trimesh shape), ``-convcol`` or ``-convcolonly`` as its convex hull; ``-rigid`` makes it a
rigid body, which every meshcol body is (:data:`GODOT_HINTS`). The hint is cut from the body's
name and becomes the body's collider kind, as a manifest's ``shape`` would.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = [
    "GODOT_HINTS",
    "UNREAL_PREFIXES",
    "CollisionPart",
    "GodotHint",
    "collision_part",
    "godot_hint",
]

#: Unreal's collision prefixes and the collider each stands for.
UNREAL_PREFIXES: dict[str, str] = {"UCX": "convex", "UBX": "box", "USP": "sphere", "UCP": "capsule"}

_PART = re.compile(r"^(?P<prefix>UCX|UBX|USP|UCP)_(?P<owner>.+)_(?P<index>\d+)$")


@dataclass(frozen=True)
class CollisionPart:
    """What an Unreal collision name says.

    Attributes
    ----------
    owner : str
        The render mesh the part belongs to.
    index : int
        Its ``NN``.
    kind : str
        ``convex``, ``box``, ``sphere`` or ``capsule``.
    """

    owner: str
    index: int
    kind: str


def collision_part(name: str) -> CollisionPart | None:
    """The Unreal collision part ``name`` names (``UBX_Crate_01``: a box of ``Crate``), or
    None when it is render geometry."""
    match = _PART.match(name)
    if match is None:
        return None
    return CollisionPart(match["owner"], int(match["index"]), UNREAL_PREFIXES[match["prefix"]])


#: Godot's name suffixes and the collider kind each gives (None: the body's own).
GODOT_HINTS: dict[str, str | None] = {
    "-colonly": "mesh",
    "-convcolonly": "hull",
    "-convcol": "hull",
    "-col": "mesh",
    "-rigid": None,
}


@dataclass(frozen=True)
class GodotHint:
    """A Godot import hint in a node name: the name without it, the hint, and the collider
    kind it gives (None for ``-rigid``)."""

    name: str
    hint: str
    collider: str | None


def godot_hint(name: str) -> GodotHint | None:
    """The Godot hint that ends ``name`` (``Floor-col``), or None."""
    for hint, collider in GODOT_HINTS.items():
        if name.endswith(hint) and len(name) > len(hint):
            return GodotHint(name[: -len(hint)], hint, collider)
    return None
