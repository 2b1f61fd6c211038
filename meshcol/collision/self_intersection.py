"""Self-intersections of a triangle mesh: which pairs of its faces cross, decided exactly.

Two faces cross when their relative interiors (the open triangles) share a point: in different
planes, they meet along a segment through both interiors; in one plane, they overlap with
positive area. Touching is not crossing: faces that meet only at a point or along their
boundaries (a shared vertex or edge, a T-junction, a vertex resting on a face) do not cross.
Faces on the same three vertices are duplicates, not crossings.

The verdict is exact for finite coordinates: every decision is the sign of an orientation
determinant of input points (orient2d, orient3d), evaluated in floating point with an error
bound and exactly when the bound cannot decide (Shewchuk 1997). There is no tolerance.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_mesh
from meshcol.collision.broadphase import sort_and_sweep

__all__ = ["face_pairs_cross", "self_intersecting_pairs"]


def _mesh(vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    v, f = as_mesh(vertices, faces)
    if f.size and not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"faces must be integers, got {f.dtype}")
    if not np.isfinite(v).all():
        raise ValueError("vertices contain NaN or infinite coordinates")
    return v, np.ascontiguousarray(f, dtype=np.int64)


def face_pairs_cross(vertices: Any, faces: Any, pairs: Any, *, threads: int = 0) -> np.ndarray:
    """Whether each given pair of faces of a mesh crosses (see the module notes).

    Parameters
    ----------
    vertices : (n, 3) float
        Any frame.
    faces : (m, 3) int
        Indices into ``vertices``.
    pairs : (k, 2) int
        Indices into ``faces``.
    threads : int
        0 uses every core.

    Returns
    -------
    (k,) bool

    Raises
    ------
    ValueError
        Wrong shapes, non-finite coordinates, or an index out of range (naming the face or
        pair).

    Notes
    -----
    In the C++ core, GIL released, threads over pairs. Non-coplanar pairs: the interval test
    on the line where the planes meet (Moller 1997; Guigue and Devillers 2003) with every
    comparison an orient3d sign; coplanar pairs: no edge line weakly separates them (orient2d
    signs). Degenerate (collinear) faces cross nothing.
    """
    v, f = _mesh(vertices, faces)
    p = np.asarray(pairs)
    if p.size == 0:
        p = p.reshape(0, 2)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"pairs must be (k, 2), got {p.shape}")
    return core.face_pairs_cross(v, f, np.ascontiguousarray(p, dtype=np.int64), threads)


def self_intersecting_pairs(
    vertices: Any, faces: Any, skip: Any = None, *, threads: int = 0
) -> np.ndarray:
    """Pairs of faces of a mesh that cross each other.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    skip : (m,) bool, optional
        Faces to leave out (``meshcol inspect`` skips the faces it reports as degenerate).
    threads : int
        0 uses every core.

    Returns
    -------
    (k, 2) int64
        Face index pairs ``i < j``, sorted lexicographically.

    Notes
    -----
    Candidates are the faces whose bounding boxes overlap (touching counts), from the native
    :func:`meshcol.collision.broadphase.sort_and_sweep`; :func:`face_pairs_cross` decides each
    candidate exactly in one native call.
    """
    v, f = _mesh(vertices, faces)
    keep = np.ones(len(f), bool) if skip is None else ~np.asarray(skip, bool).reshape(-1)
    if len(keep) != len(f):
        raise ValueError(f"skip must be ({len(f)},) like faces, got ({len(keep)},)")
    index = np.nonzero(keep)[0]
    if len(index) < 2:
        return np.zeros((0, 2), np.int64)
    kept = f[index]
    if kept.min() < 0 or kept.max() >= len(v):
        raise ValueError(f"faces index vertices out of range [0, {len(v)})")
    a, b, c = v[kept[:, 0]], v[kept[:, 1]], v[kept[:, 2]]
    candidates = sort_and_sweep(np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c))
    # index is increasing, so the pairs stay i < j and sorted
    candidates = index[candidates]
    return candidates[face_pairs_cross(v, f, candidates, threads=threads)]
