"""A manifest of primitive bodies kept as columns, from the manifest to the packed shapes.

A manifest of 1,000,000 spheres, boxes, capsules and cylinders needs no Python object per
body to be checked: its names, primitive types, lengths and poses are arrays already
(:class:`meshcol.io.scene_columns.Columns`). :class:`PrimitiveBodies` keeps them so: a
sequence of :class:`~meshcol.types.Body` that makes a body only when one is asked for by
index (a writer, a pair that needs its triangles), each the body the body loop builds, to the
bit. The check reads its columns instead (:func:`body_names`, :func:`body_sources`,
:func:`vertex_counts`, and the packing of :mod:`meshcol.analysis.primitive_colliders`).

The loader takes this path when every body of a plainly valid manifest is a static, unscaled
primitive within the coordinate limit, and names are unique (:func:`primitive_bodies`); any
other manifest is built body by body as before.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, overload

import numpy as np

from meshcol.io.scene_schema import PRIMITIVE_TYPES
from meshcol.types import (
    REGULAR_LENGTHS,
    REGULAR_VERTEX_COUNTS,
    Body,
    Box,
    Capsule,
    Cylinder,
    Primitive,
    Sphere,
    primitive_vertex_count,
)

__all__ = [
    "PrimitiveBodies",
    "body_names",
    "body_parts",
    "body_sources",
    "vertex_counts",
]

_SPHERE, _BOX, _CAPSULE, _CYLINDER = (
    PRIMITIVE_TYPES.index(k) for k in ("sphere", "box", "capsule", "cylinder")
)
#: The :class:`~meshcol.types.Primitive` class of each index of :data:`PRIMITIVE_TYPES`.
_CLASSES: dict[int, type] = {_SPHERE: Sphere, _BOX: Box, _CAPSULE: Capsule, _CYLINDER: Cylinder}


def primitive_of(kind: int, lengths: Sequence[float]) -> Primitive:
    """The primitive of a type index (:data:`PRIMITIVE_TYPES`) and the manifest's lengths
    (a box's size, a sphere's ``(radius, 0, 0)``, a capsule's or cylinder's ``(radius,
    length, 0)``), as the body loop builds it from the same numbers."""
    a, b, c = (float(x) for x in lengths)
    if kind == _BOX:
        return Box((a, b, c))
    if kind == _SPHERE:
        return Sphere(a)
    return Capsule(a, b) if kind == _CAPSULE else Cylinder(a, b)


class PrimitiveBodies(Sequence[Body]):
    """Static primitive bodies as columns: a sequence of :class:`~meshcol.types.Body` whose
    bodies are made on first access by index (then kept).

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
        n = len(names)
        if kinds.shape != (n,) or lengths.shape != (n, 3) or poses.shape != (n, 4, 4):
            raise ValueError(f"primitive columns of {n} bodies have other lengths")
        self.names = names
        self.source = source
        self.kinds = kinds
        self.lengths = lengths
        self.poses = poses
        self.colliders = colliders
        self._made: dict[int, Body] = {}

    def __len__(self) -> int:
        return len(self.names)

    @overload
    def __getitem__(self, index: int) -> Body: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[Body]: ...

    def __getitem__(self, index: int | slice) -> Body | Sequence[Body]:
        if isinstance(index, slice):
            return tuple(self[i] for i in range(len(self))[index])
        i = range(len(self))[index]  # IndexError, negative indices
        body = self._made.get(i)
        if body is None:
            primitive = self.primitive(i)
            body = Body.plain(
                self.names[i], self.source, None, None, self.poses[i], primitive, self.colliders[i]
            )
            self._made[i] = body
        return body

    def __iter__(self) -> Iterator[Body]:
        return (self[i] for i in range(len(self)))

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
        inside = (self.lengths >= low) & (self.lengths <= high)
        regular = (inside | ~used).all(axis=1)
        by_kind = np.zeros(len(_CLASSES), dtype=np.int64)
        for kind, cls in _CLASSES.items():
            by_kind[kind] = REGULAR_VERTEX_COUNTS[cls]
        counts = by_kind[self.kinds.astype(np.int64)]
        for i in np.flatnonzero(~regular).tolist():
            counts[i] = primitive_vertex_count(self.primitive(i))
        return counts


def body_names(bodies: Sequence[Body]) -> list[str]:
    """Each body's name, in order (a :class:`PrimitiveBodies`' without making its bodies)."""
    if isinstance(bodies, PrimitiveBodies):
        return bodies.names
    return [body.name for body in bodies]


def body_sources(bodies: Sequence[Body]) -> list[str | None]:
    """Each body's ``source``, in order (without making a :class:`PrimitiveBodies`' bodies)."""
    if isinstance(bodies, PrimitiveBodies):
        return [bodies.source] * len(bodies)
    return [body.source for body in bodies]


def body_parts(bodies: Sequence[Body], index: Sequence[int]) -> list[tuple[str, ...]]:
    """The part names of the bodies ``index``, in that order (a primitive body has none)."""
    if isinstance(bodies, PrimitiveBodies):
        return [()] * len(index)
    return [tuple(bodies[i].parts) for i in index]


def vertex_counts(bodies: Sequence[Body], index: Any = None) -> np.ndarray:
    """(k,) int64: ``vertex_count`` of the bodies ``index`` (all when None), in that order,
    never tessellating a primitive for it."""
    picked = np.arange(len(bodies)) if index is None else np.asarray(index, dtype=np.int64)
    if isinstance(bodies, PrimitiveBodies):
        return bodies.vertex_counts()[picked]
    return np.asarray([bodies[i].vertex_count for i in picked.tolist()], dtype=np.int64)
