"""Collision shapes found in a scene file, grouped into bodies: what the readers of physics
scene formats share (USD's UsdPhysics, :mod:`meshcol.io.usd_read`; glTF's physics
extensions, :mod:`meshcol.io.gltf_physics`).

A reader finds :class:`ShapeElement` s (a primitive or a triangle mesh at its world
transform, with the collider kind the file asks for), gathers them in :class:`BodyGroup` s
(the rigid body they belong to, or a static collider on its own) and returns a
:class:`FileScene`; :func:`meshcol.io.mesh_read.load_file_scene` makes each group one
:class:`~meshcol.types.Body`. A group of one primitive stays that exact primitive when its
transform scales it into one (:func:`scaled_primitive`, which a manifest's ``scale`` takes
too: a box or an ellipsoid by any scale along its axes; a sphere uniformly, or unevenly into
an ellipsoid; a capsule or cylinder evenly across its axis); anything else becomes a body of
parts (:func:`meshcol.io.links.parts_body`, primitives tessellated, as robot links are).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Primitive, Sphere

__all__ = [
    "FAITHFUL_ORDER",
    "BodyGroup",
    "FileScene",
    "ShapeElement",
    "axis_turn",
    "choose_collider",
    "scaled_primitive",
]

#: Collider kinds from the most faithful to the coarsest: a body whose parts ask for
#: different kinds takes the first of them.
FAITHFUL_ORDER = ("mesh", "decomposed", "hull", "box", "sphere")


@dataclass
class ShapeElement:
    """One piece of collision geometry.

    Attributes
    ----------
    name : str
        The part's name within its body (a path relative to the body's prim or node).
    world : (4, 4) float64
        World from the element's own frame (scale, shear and mirror allowed).
    primitive : Primitive or None
        The exact shape, axis along the element's ``axis``; None for a mesh.
    vertices : (n, 3) float64 or None
        A mesh in the element's frame.
    faces : (m, 3) int64 or None
    collider : str or None
        The collider kind the file asks for (:data:`meshcol.vocabulary.COLLIDER_KINDS`);
        None: the run's (``--shape``).
    axis : {"X", "Y", "Z"}
        The axis of a capsule or cylinder in the element's frame (meshcol's is z).
    """

    name: str
    world: np.ndarray
    primitive: Primitive | None
    vertices: np.ndarray | None
    faces: np.ndarray | None
    collider: str | None
    axis: str = "Z"


@dataclass
class BodyGroup:
    """The elements of one body.

    Attributes
    ----------
    key : str
        What the file calls the body (a prim path, a node index): unique per file.
    name : str
        The body's name before the file's stem is put in front.
    world : (4, 4) float64
        World from the body's frame (its rigid part becomes the body's pose).
    elements : list of ShapeElement
    ancestors : tuple of str
        The names of the body's ancestors in the file, from the root down to its parent (a
        prim path's, a node's parents'): what tells apart bodies of one name
        (:mod:`meshcol.io.body_names`). Empty: at the root.
    """

    key: str
    name: str
    world: np.ndarray
    elements: list[ShapeElement] = field(default_factory=list)
    ancestors: tuple[str, ...] = ()


@dataclass
class FileScene:
    """What a physics scene reader found in one file.

    Attributes
    ----------
    groups : list of BodyGroup
        One per body, in the file's order.
    excluded : list of (str, str, str)
        Pairs of group keys never checked against each other, with the reason.
    units : str or None
        The length unit every coordinate is in (``"m"``).
    warnings : list of str
        What the reader skipped or approximated, one line each.
    """

    groups: list[BodyGroup]
    excluded: list[tuple[str, str, str]] = field(default_factory=list)
    units: str | None = None
    warnings: list[str] = field(default_factory=list)


def axis_turn(axis: str) -> np.ndarray:
    """(4, 4) from a primitive along z (meshcol's) to one along ``axis`` (a cyclic
    permutation of the axes: a rotation)."""
    turn = np.eye(4)
    if axis == "X":  # z -> x
        turn[:3, :3] = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    elif axis == "Y":  # z -> y
        turn[:3, :3] = [[0, 1, 0], [0, 0, 1], [1, 0, 0]]
    return turn


def choose_collider(kinds: list[str | None], warnings: list[str], name: str) -> str | None:
    """The collider kind of a body whose parts ask for ``kinds`` (None: the run's): the
    most faithful (:data:`FAITHFUL_ORDER`), with a warning when they differ."""
    asked = {k for k in kinds if k is not None}
    if not asked:
        return None
    chosen = next(k for k in FAITHFUL_ORDER if k in asked)
    if len(asked) > 1:
        warnings.append(
            f"{name}: its parts ask for different colliders ({', '.join(sorted(asked))}): "
            f"the body is checked as {chosen}"
        )
    return chosen


def scaled_primitive(
    primitive: Primitive, origin: np.ndarray
) -> tuple[Primitive, np.ndarray] | None:
    """The primitive as ``origin`` (4, 4) scales it, and ``origin``'s rigid part; None when
    the scale makes it no primitive (a capsule stretched, a cylinder squashed, a shear). A
    sphere scaled unevenly is an ellipsoid, exactly."""
    linear = origin[:3, :3]
    scale = np.linalg.norm(linear, axis=0)
    if scale.min() <= 0:
        return None
    rotation = linear / scale
    if np.abs(rotation.T @ rotation - np.eye(3)).max() > 1e-9:
        return None  # sheared
    if np.linalg.det(rotation) < 0:
        rotation[:, 2] = -rotation[:, 2]  # every primitive is symmetric under z -> -z
    rigid = np.eye(4)
    rigid[:3, :3], rigid[:3, 3] = rotation, origin[:3, 3]

    def even(i: int, j: int) -> bool:
        return bool(np.isclose(scale[i], scale[j], rtol=1e-12, atol=0.0))

    if isinstance(primitive, Box):
        return Box(tuple(np.asarray(primitive.size) * scale)), rigid
    if isinstance(primitive, Sphere):
        if even(0, 1) and even(0, 2):
            return Sphere(primitive.radius * scale[0]), rigid
        return Ellipsoid(tuple(primitive.radius * scale)), rigid
    if isinstance(primitive, Ellipsoid):
        return Ellipsoid(tuple(np.asarray(primitive.semi_axes) * scale)), rigid
    if not even(0, 1):
        return None
    if isinstance(primitive, Capsule):
        if not even(0, 2):
            return None  # a capsule stretched along its axis stretches its caps
        return Capsule(primitive.radius * scale[0], primitive.length * scale[2]), rigid
    assert isinstance(primitive, Cylinder)
    return Cylinder(primitive.radius * scale[0], primitive.length * scale[2]), rigid
