"""A manifest of primitive bodies kept as columns, from the manifest to the packed shapes.

A manifest of 1,000,000 spheres, boxes, capsules, cylinders and ellipsoids needs no Python
object per body to be checked: its names, primitive types, lengths and poses are arrays
already (:class:`meshcol.io.scene_columns.Columns`). :class:`PrimitiveBodies` keeps them so: a
sequence of :class:`~meshcol.types.Body` that makes a body only when one is asked for by
index (a writer, a pair that needs its triangles), each the body the body loop builds, to the
bit. The check reads its columns instead (the readers of
:mod:`meshcol.io.column_bodies`, and the packing of
:mod:`meshcol.analysis.primitive_colliders`).

The loader takes this path when every body of a plainly valid manifest is a static, unscaled
primitive within the coordinate limit, and names are unique (:func:`primitive_bodies`); any
other manifest is built body by body as before.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from meshcol.io.column_bodies import ColumnBodies
from meshcol.io.scene_schema import PRIMITIVE_TRIPLES, PRIMITIVE_TYPES
from meshcol.types import (
    REGULAR_LENGTHS,
    REGULAR_VERTEX_COUNTS,
    Body,
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    Primitive,
    Sphere,
    primitive_vertex_count,
)

__all__ = ["PrimitiveBodies", "manifest_primitive", "primitive_of"]

_SPHERE, _BOX, _CAPSULE, _CYLINDER, _ELLIPSOID = (
    PRIMITIVE_TYPES.index(k) for k in ("sphere", "box", "capsule", "cylinder", "ellipsoid")
)
#: The :class:`~meshcol.types.Primitive` class of each index of :data:`PRIMITIVE_TYPES`.
_CLASSES: dict[int, type] = {
    _SPHERE: Sphere,
    _BOX: Box,
    _CAPSULE: Capsule,
    _CYLINDER: Cylinder,
    _ELLIPSOID: Ellipsoid,
}


def primitive_of(kind: int, lengths: Sequence[float]) -> Primitive:
    """The primitive of a type index (:data:`PRIMITIVE_TYPES`) and the manifest's lengths
    (a box's size, a sphere's ``(radius, 0, 0)``, a capsule's or cylinder's ``(radius,
    length, 0)``, an ellipsoid's semi-axes), as the body loop builds it from the same
    numbers."""
    a, b, c = (float(x) for x in lengths)
    if kind == _BOX:
        return Box((a, b, c))
    if kind == _ELLIPSOID:
        return Ellipsoid((a, b, c))
    if kind == _SPHERE:
        return Sphere(a)
    return Capsule(a, b) if kind == _CAPSULE else Cylinder(a, b)


def manifest_primitive(options: dict) -> Primitive:
    """The primitive of a valid manifest ``primitive`` object, before any scale: what
    :func:`primitive_of` makes of its columns."""
    kind = options["type"]
    field = PRIMITIVE_TRIPLES.get(kind)
    lengths = options[field] if field else (options["radius"], options.get("length", 0.0), 0.0)
    return primitive_of(PRIMITIVE_TYPES.index(kind), lengths)


class PrimitiveBodies(ColumnBodies):
    """Static primitive bodies as columns (:class:`~meshcol.io.column_bodies.ColumnBodies`).

    Attributes
    ----------
    names : list of str
        Unique, in manifest order.
    source : str
        The manifest: every body's ``source``.
    kinds : (n,) int8
        Each body's type, an index of :data:`PRIMITIVE_TYPES`.
    lengths : (n, 3) float64
        Its lengths as the manifest gives them (see :func:`primitive_of`).
    poses : (n, 4, 4) float64
        Its rigid world-from-local pose (no body moves).
    colliders : list of str or None
        Its manifest ``shape`` (a primitive is always queried exactly; kept for the body).
    """

    def __init__(
        self,
        names: list[str],
        source: str,
        kinds: np.ndarray,
        lengths: np.ndarray,
        poses: np.ndarray,
        colliders: list[str | None],
    ) -> None:
        super().__init__(names, poses, colliders)
        n = len(names)
        if kinds.shape != (n,) or lengths.shape != (n, 3):
            raise ValueError(f"primitive columns of {n} bodies have other lengths")
        self.source = source
        self.kinds = kinds
        self.lengths = lengths

    def make(self, i: int) -> Body:
        return Body.plain(
            self.names[i],
            self.source,
            None,
            None,
            self.poses[i],
            self.primitive(i),
            self.colliders[i],
        )

    def sources(self) -> list[str | None]:
        return [self.source] * len(self)

    def primitive(self, index: int) -> Primitive:
        """The primitive of body ``index``."""
        return primitive_of(int(self.kinds[index]), self.lengths[index].tolist())

    def vertex_counts(self) -> np.ndarray:
        """(n,) int64: each body's ``vertex_count`` (its tessellation's vertex count), made
        only for the primitives whose lengths are not all within :data:`REGULAR_LENGTHS`."""
        low, high = REGULAR_LENGTHS
        used = np.zeros((len(self), 3), dtype=bool)
        used[:, 0] = True
        used[self.kinds == _BOX] = True
        used[(self.kinds == _CAPSULE) | (self.kinds == _CYLINDER), 1] = True
        used[self.kinds == _ELLIPSOID] = False  # the unit sphere's, scaled: never merged
        inside = (self.lengths >= low) & (self.lengths <= high)
        regular = (inside | ~used).all(axis=1)
        by_kind = np.zeros(len(_CLASSES), dtype=np.int64)
        for kind, cls in _CLASSES.items():
            by_kind[kind] = REGULAR_VERTEX_COUNTS[cls]
        counts = by_kind[self.kinds.astype(np.int64)]
        for i in np.flatnonzero(~regular).tolist():
            counts[i] = primitive_vertex_count(self.primitive(i))
        return counts
