"""Many mesh files read at once, kept as the reader's packed arrays: a mapping from each file's
path to its bodies (:func:`meshcol.io.mesh_read.read_meshes`) that builds a file's
:class:`meshcol.types.Body` objects only when asked for them.

A manifest of 100,000 unique assets needs no Body per file: its bodies are built from the
files' arrays in bulk (:func:`lone_objects` gives them, with the largest coordinate of each,
in one numpy pass over the packed vertices).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping, MutableMapping, Sequence

import numpy as np

from meshcol.types import Body

__all__ = ["MeshFiles", "PackedObjects", "lone_objects"]

_EYE = np.eye(4)  # copied per body: a third of the time of np.eye(4)


class PackedObjects:
    """One object per file, packed: file ``j``'s vertices are
    ``vertices[v_off[j]:v_off[j + 1]]`` ((V, 3) float64) and its faces
    ``faces[f_off[j]:f_off[j + 1]]`` ((F, 3) int64, indexing its own vertices), in its frame
    (no transform)."""

    def __init__(
        self, vertices: np.ndarray, faces: np.ndarray, v_off: np.ndarray, f_off: np.ndarray
    ) -> None:
        self.vertices, self.faces = vertices, faces
        self.v_off, self.f_off = v_off.tolist(), f_off.tolist()
        self._largest: np.ndarray | None = None

    def arrays(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) of file ``j``: views, C-contiguous."""
        vo, fo = self.v_off, self.f_off
        return self.vertices[vo[j] : vo[j + 1]], self.faces[fo[j] : fo[j + 1]]

    def largest(self) -> np.ndarray:
        """The largest |coordinate| of each file's vertices (0 for none): one reduction over
        the flat coordinates."""
        if self._largest is None:
            starts = np.asarray(self.v_off, dtype=np.int64)
            sizes = np.diff(starts)
            largest = np.zeros(len(sizes))
            filled = sizes > 0
            if filled.any():
                magnitudes = np.abs(self.vertices.reshape(-1))
                largest[filled] = np.maximum.reduceat(magnitudes, starts[:-1][filled] * 3)
            self._largest = largest
        return self._largest


class MeshFiles(MutableMapping[str, list[Body]]):
    """The bodies of each file read, by its path as given (the first of repeated paths), in
    the order :func:`meshcol.io.mesh_read.load_mesh` gives them; files read later may be
    added (``files[path] = bodies``).

    ``sources[j]``'s bodies are ``bodies[j]`` when built already, else the one object
    ``packed`` holds for it, named after the file's stem, identity pose.
    """

    def __init__(
        self,
        sources: Sequence[str],
        bodies: list[list[Body] | None],
        packed: PackedObjects | None = None,
    ) -> None:
        self.sources = list(sources)
        self._bodies = bodies
        self.packed = packed
        self._index: dict[str, int] | None = None

    def index(self) -> dict[str, int]:
        """Position of each path (its first)."""
        if self._index is None:
            index: dict[str, int] = {}
            for j, source in enumerate(self.sources):
                index.setdefault(source, j)
            self._index = index
        return self._index

    def file(self, j: int) -> list[Body]:
        """The bodies of ``sources[j]``."""
        bodies = self._bodies[j]
        if bodies is None:
            assert self.packed is not None
            source = self.sources[j]
            vertices, faces = self.packed.arrays(j)
            bodies = [Body.plain(stem(source), source, vertices, faces, _EYE.copy())]
            self._bodies[j] = bodies
        return bodies

    def per_file(self) -> list[list[Body]]:
        """The bodies of every path, in order (repeated paths included)."""
        return [self.file(j) for j in range(len(self.sources))]

    def __getitem__(self, key: str) -> list[Body]:
        return self.file(self.index()[key])

    def __setitem__(self, key: str, bodies: list[Body]) -> None:
        j = self.index().get(key)
        if j is None:
            self.index()[key] = len(self.sources)
            self.sources.append(key)
            self._bodies.append(bodies)
        else:
            self._bodies[j] = bodies

    def __delitem__(self, key: str) -> None:
        raise TypeError("mesh files read are never removed")

    def __iter__(self) -> Iterator[str]:
        return iter(self.index())

    def __len__(self) -> int:
        return len(self.index())


def lone_objects(
    files: Mapping[str, list[Body]], keys: Sequence[str]
) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray] | None]]:
    """Of each of ``keys`` (paths of ``files``): whether its file is read and holds one object
    without a transform, the largest |coordinate| of that object (0 without vertices, inf
    when it is not such an object), and its (vertices, faces), C-contiguous (None when not).

    In one numpy pass for the files a :class:`MeshFiles` holds packed; from the bodies for
    the others.
    """
    n = len(keys)
    lone = np.zeros(n, dtype=bool)
    largest = np.full(n, np.inf)
    arrays: list[tuple[np.ndarray, np.ndarray] | None] = [None] * n
    others = list(range(n))
    if isinstance(files, MeshFiles) and files.packed is not None:
        index, built, packed = files.index(), files._bodies, files.packed
        spots = [index.get(key, -1) for key in keys]
        packed_rows = [k for k, j in enumerate(spots) if j >= 0 and built[j] is None]
        if packed_rows:
            positions = np.asarray([spots[k] for k in packed_rows], dtype=np.int64)
            lone[packed_rows] = True
            largest[packed_rows] = packed.largest()[positions]
            for k, j in zip(packed_rows, positions.tolist()):
                arrays[k] = packed.arrays(j)
            done = set(packed_rows)
            others = [k for k in others if k not in done]
    loaded = [files.get(keys[k]) for k in others]
    ones = [(k, f[0]) for k, f in zip(others, loaded) if f is not None and len(f) == 1]
    for k, body in ones:
        if (np.asarray(body.pose) == _EYE).all():
            lone[k] = True
            vertices = np.ascontiguousarray(body.vertices)
            largest[k] = float(np.abs(vertices).max()) if vertices.size else 0.0
            arrays[k] = (vertices, np.ascontiguousarray(body.faces))
    return lone, largest, arrays


def stem(source: str) -> str:
    """``Path(source).stem`` without building a Path (a scene may name 100,000 files)."""
    name = (
        os.path.basename(source.rstrip("/")) if source.endswith("/") else os.path.basename(source)
    )
    dot = name.rfind(".")
    return name[:dot] if 0 < dot < len(name) - 1 else name
