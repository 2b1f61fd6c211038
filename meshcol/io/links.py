"""A robot link as a :class:`~meshcol.types.Body`: what the URDF and MJCF readers share.

A link whose only collision element is a box, sphere, cylinder or capsule stays that exact
primitive (:func:`primitive_body`); a link of several elements is a body of parts
(:func:`parts_body`), every element's origin baked into its vertices and every primitive
tessellated (:func:`meshcol.io.primitives.primitive_mesh`, the tessellation manifests use)
for what draws or exports the body, and kept with its origin (``Body.part_primitives``) for
the queries, which use it exactly. :class:`CollisionElement` records the element behind each
part, for the writers that rebuild a description (:mod:`meshcol.io.robot_write`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from meshcol.types import Body, PartPrimitive, Primitive, unique_name

__all__ = [
    "JOINT_TOLERANCE",
    "CollisionElement",
    "LinkElement",
    "one_line",
    "parts_body",
    "primitive_body",
    "tessellate",
]

#: Joint values this far outside a limit are taken as on it.
JOINT_TOLERANCE = 1e-9


@dataclass(frozen=True, eq=False)
class CollisionElement:
    """The collision element (URDF ``<collision>``, MJCF collision geom) behind one part of a
    link's body, for writers that rebuild a description (:mod:`meshcol.io.robot_write`).

    Attributes
    ----------
    link : str
        The link (URDF) or body (MJCF) name, the :class:`~meshcol.types.Body` name.
    index : int
        URDF: position among the link's ``<collision>`` elements (file order); MJCF: the geom
        id in the compiled model.
    origin : (4, 4) float64
        The element's frame in the link frame (URDF ``<origin>``; MJCF the compiled geom pose).
    primitive : Primitive or None
        The exact shape, or None for a mesh.
    vertices : (n, 3) float64 or None
        A mesh element's vertices in the element's frame, its scale applied (one entry per
        object of a mesh file of several objects).
    faces : (m, 3) int64 or None
    """

    link: str
    index: int
    origin: np.ndarray
    primitive: Primitive | None
    vertices: np.ndarray | None
    faces: np.ndarray | None


class LinkElement(NamedTuple):
    """One part of a link as a reader found it: a primitive, or a mesh in its own frame.

    Attributes
    ----------
    name : str
        The part's name (the element's name, else its mesh file or primitive kind).
    origin : (4, 4) float64
        The element's frame in the link frame.
    primitive : Primitive or None
    vertices : (n, 3) float64 or None
        A mesh in the element's frame (None for a primitive).
    faces : (m, 3) int64 or None
    """

    name: str
    origin: np.ndarray
    primitive: Primitive | None
    vertices: np.ndarray | None
    faces: np.ndarray | None


def one_line(text: str) -> str:
    """A library's message on one line (its whitespace runs as single spaces)."""
    return " ".join(text.split())


def tessellate(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    """The triangles of a primitive in its own frame: ``(vertices, faces)``."""
    from meshcol.io.primitives import primitive_mesh

    return primitive_mesh(primitive)


def primitive_body(name: str, source: str, primitive: Primitive, pose: np.ndarray) -> Body:
    """A link of one primitive element: the exact primitive at the element's world pose."""
    return Body.of_primitive(name, source, primitive, pose=pose)


def parts_body(
    name: str,
    source: str,
    pose: np.ndarray,
    elements: Sequence[LinkElement],
    exact: Sequence[PartPrimitive | None] | None = None,
) -> Body:
    """One body of parts in the link frame: every element's origin (and tessellation) baked,
    and each primitive element kept exact with its origin (``Body.part_primitives``), or
    each part's exact shape as ``exact`` gives it (elements baked by their reader).

    Parts are named after their elements, ``#2``, ``#3``... appended to a name already
    taken; a link of one element is a plain mesh body (no parts)."""
    blocks_v, blocks_f, counts, names = [], [], [], []
    if exact is None:
        exact = [
            None if e.primitive is None else PartPrimitive(e.primitive, e.origin) for e in elements
        ]
    base = 0
    used: dict[str, int] = {}
    for part, origin, primitive, vertices, faces in elements:
        if primitive is not None:
            vertices, faces = tessellate(primitive)
        assert vertices is not None and faces is not None
        identity = np.array_equal(origin, np.eye(4))  # the USD and glTF readers' parts
        blocks_v.append(vertices if identity else vertices @ origin[:3, :3].T + origin[:3, 3])
        # a first mesh part's faces are taken as they are (a million-triangle copy saved);
        # a primitive's come from a shared cache: copied
        blocks_f.append(faces + base if base or primitive is not None else faces)
        counts.append(len(faces))
        base += len(vertices)
        names.append(unique_name(part, used))
    if len(elements) == 1:
        return Body(
            name=name,
            source=source,
            vertices=np.ascontiguousarray(blocks_v[0]),
            faces=np.ascontiguousarray(blocks_f[0], dtype=np.int64),
            pose=pose,
        )
    return Body(
        name=name,
        source=source,
        vertices=np.ascontiguousarray(np.concatenate(blocks_v)),
        faces=np.ascontiguousarray(np.concatenate(blocks_f), dtype=np.int64),
        pose=pose,
        parts=tuple(names),
        part_faces=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        part_primitives=tuple(exact) if any(p is not None for p in exact) else (),
    )
