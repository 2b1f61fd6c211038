"""Bodies kept as columns: a sequence of :class:`~meshcol.types.Body` that makes a body only
when one is asked for by index, and the readers of a scene's bodies that take the columns
instead.

A manifest of 100,000 unique mesh assets or 1,000,000 primitives needs no Python object per
body to be checked: its names, poses and shapes are arrays already, and so are its files'
vertices (the core's packed read). :class:`ColumnBodies` keeps them so; each body it makes is
the body the body loop builds, to the bit, and is kept once made. Two kinds:
:class:`meshcol.io.scene_primitives.PrimitiveBodies` (static primitives) and
:class:`MeshBodies` (static, unscaled bodies of one-object mesh files). The check reads their
columns (:func:`body_names`, :func:`body_sources`, :func:`body_parts`, :func:`vertex_counts`,
the colliders' packing and the parts' poses) and so makes none of them.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, overload

import numpy as np

from meshcol.io.mesh_read import PackedObjects
from meshcol.types import Body

__all__ = [
    "ColumnBodies",
    "MeshBodies",
    "body_names",
    "body_parts",
    "body_sources",
    "vertex_counts",
]


class ColumnBodies(Sequence[Body]):
    """Static bodies of one part each, as columns; a :class:`Body` is made on first access
    by index (then kept).

    Attributes
    ----------
    names : list of str
        Unique, in manifest order.
    poses : (n, 4, 4) float64
        Each body's rigid world-from-local pose (no body moves).
    colliders : list of str or None
        Each body's manifest ``shape``.
    """

    def __init__(self, names: list[str], poses: np.ndarray, colliders: list[str | None]) -> None:
        n = len(names)
        if poses.shape != (n, 4, 4) or len(colliders) != n:
            raise ValueError(f"columns of {n} bodies have other lengths")
        self.names = names
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
            body = self._made[i] = self.make(i)
        return body

    def __iter__(self) -> Iterator[Body]:
        return (self[i] for i in range(len(self)))

    def make(self, i: int) -> Body:
        """Body ``i`` as the body loop builds it (0 <= i < n)."""
        raise NotImplementedError

    def sources(self) -> list[str | None]:
        """Each body's ``source``, in order."""
        raise NotImplementedError

    def vertex_counts(self) -> np.ndarray:
        """(n,) int64: each body's ``vertex_count``."""
        raise NotImplementedError


class MeshBodies(ColumnBodies):
    """Static, unscaled bodies of mesh files that hold one object each, at their poses: body
    ``i`` is the one object of file ``files[mesh[i]]``, packed in ``packed`` at
    ``objects[mesh[i]]``.

    Attributes
    ----------
    files : list of str
        Each mesh file's path as the body loop joins it (every body's ``source``).
    mesh : (n,) int64
        Each body's file, an index of ``files``.
    objects : (m,) int64
        Each file's object in ``packed``.
    packed : PackedObjects
        The files' vertices and faces as the core read them.
    """

    def __init__(
        self,
        names: list[str],
        files: list[str],
        mesh: np.ndarray,
        objects: np.ndarray,
        packed: PackedObjects,
        poses: np.ndarray,
        colliders: list[str | None],
    ) -> None:
        super().__init__(names, poses, colliders)
        if mesh.shape != (len(names),) or objects.shape != (len(files),):
            raise ValueError(f"mesh columns of {len(names)} bodies have other lengths")
        self.files = files
        self.mesh = mesh
        self.objects = objects
        self.packed = packed

    def make(self, i: int) -> Body:
        k = int(self.mesh[i])
        vertices, faces = self.packed.arrays(int(self.objects[k]))
        return Body.plain(
            self.names[i], self.files[k], vertices, faces, self.poses[i], None, self.colliders[i]
        )

    def body_objects(self) -> np.ndarray:
        """(n,) int64: each body's object in ``packed``."""
        return self.objects[self.mesh]

    def sources(self) -> list[str | None]:
        return list(map(self.files.__getitem__, self.mesh.tolist()))

    def vertex_counts(self) -> np.ndarray:
        counts = np.diff(np.asarray(self.packed.v_off, dtype=np.int64))
        return counts[self.body_objects()]


def body_names(bodies: Sequence[Body]) -> list[str]:
    """Each body's name, in order (column bodies' without making them)."""
    if isinstance(bodies, ColumnBodies):
        return bodies.names
    return [body.name for body in bodies]


def body_sources(bodies: Sequence[Body]) -> list[str | None]:
    """Each body's ``source``, in order (column bodies' without making them)."""
    if isinstance(bodies, ColumnBodies):
        return bodies.sources()
    return [body.source for body in bodies]


def body_parts(bodies: Sequence[Body], index: Sequence[int]) -> list[tuple[str, ...]]:
    """The part names of the bodies ``index``, in that order (a column body has none)."""
    if isinstance(bodies, ColumnBodies):
        return [()] * len(index)
    return [tuple(bodies[i].parts) for i in index]


def vertex_counts(bodies: Sequence[Body], index: Any = None) -> np.ndarray:
    """(k,) int64: ``vertex_count`` of the bodies ``index`` (all when None), in that order,
    never tessellating a primitive for it."""
    picked = np.arange(len(bodies)) if index is None else np.asarray(index, dtype=np.int64)
    if isinstance(bodies, ColumnBodies):
        return bodies.vertex_counts()[picked]
    return np.asarray([bodies[i].vertex_count for i in picked.tolist()], dtype=np.int64)
