"""Polygon faces split into triangles: the one splitter of the mesh readers (OFF, FBX, USD).

The work is done in the native core (``cpp/src/triangulate.cpp``), one call per mesh over its
whole face-count array, the GIL released: a convex face (every turn to the left in the plane of
its Newell normal, one full turn in all) is fanned from its first corner; any other face is ear
clipped in that plane (Eberly, "Triangulation by Ear Clipping", 2002), and a face with no ear
left (no area, or not simple) is fanned. The core repeats the arithmetic of the numpy splitter
it replaced (issue 30's read-speed item), so the triangles are the same, bit for bit
(``tests/io/test_polygons.py`` keeps that splitter as the oracle).

OBJ's native reader fans every polygon (as trimesh does) while it parses: a different rule,
kept, since OBJ reports would otherwise change.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PolygonError", "TooManyTriangles", "triangulate_faces", "triangulate_polygons"]

_NO_HOLES = np.zeros(0, dtype=np.int64)


class PolygonError(ValueError):
    """Counts or indices that do not make polygon faces (the message says which)."""


class TooManyTriangles(PolygonError):
    """The faces would make more triangles than the caller allows."""


def triangulate_faces(
    vertices: np.ndarray,
    counts: np.ndarray,
    indices: np.ndarray,
    *,
    holes: np.ndarray | None = None,
    reverse: bool = False,
    max_triangles: int = -1,
) -> np.ndarray:
    """Triangles of a polygon mesh, in face order.

    Parameters
    ----------
    vertices : (n, 3) float
    counts : (m,) int
        Corners of each face; faces of fewer than 3 (points, edges) give no triangle.
    indices : (sum(counts),) int
        Every face's vertex indices, one face after the other.
    holes : (h,) int, optional
        Faces left out (USD ``holeIndices``); indices outside ``[0, m)`` are ignored.
    reverse : bool
        Reverse each triangle's winding (USD ``leftHanded``).
    max_triangles : int
        Refuse more triangles than this (-1: no limit), before any is made.

    Returns
    -------
    (t, 3) int64
        Face ``f`` of ``k >= 3`` corners gives ``k - 2`` consecutive triangles.

    Raises
    ------
    PolygonError
        A negative count, counts that do not add up to ``len(indices)``, an index out of
        range; :class:`TooManyTriangles` for more than ``max_triangles`` triangles.
    """
    from meshcol._native import core

    try:
        return core.triangulate_polygons(
            np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3),
            np.ascontiguousarray(counts, dtype=np.int64).reshape(-1),
            np.ascontiguousarray(indices, dtype=np.int64).reshape(-1),
            _NO_HOLES if holes is None else np.ascontiguousarray(holes, dtype=np.int64),
            reverse=reverse,
            max_triangles=max_triangles,
        )
    except OverflowError as error:
        raise TooManyTriangles(str(error)) from None
    except ValueError as error:
        raise PolygonError(str(error)) from None


def triangulate_polygons(
    vertices: np.ndarray, corners: np.ndarray, sizes: np.ndarray
) -> np.ndarray:
    """Triangles of polygon faces of ``sizes`` (each >= 3) corners ``corners``, in face order:
    :func:`triangulate_faces` without holes, (sum(sizes) - 2 m, 3) int64."""
    return triangulate_faces(vertices, sizes, corners)
