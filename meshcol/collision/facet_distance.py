"""Exact distances from points to a convex polytope given by its facets: the search of
:func:`meshcol.collision.hull.convex_hull`'s budget loop and of
:func:`meshcol.collision.hull.distance_to_hull`, and the block size their big products keep
to (a product of many points and many facets goes a block of points at a time)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "PRODUCT_BLOCK",
    "closest_points_on_segments",
    "distances_to_facets",
    "nearest_on_facets",
    "rows_per_block",
]

#: Doubles of one block of a points x facets product (32 MB): a bigger product (a part's
#: 12,388 vertices against its exact hull's 24,772 facets took 4.9 GB) goes a block of
#: points at a time.
PRODUCT_BLOCK = 1 << 22


def rows_per_block(columns: int) -> int:
    """How many rows of ``columns`` doubles make one :data:`PRODUCT_BLOCK`."""
    return max(1, PRODUCT_BLOCK // max(columns, 1))


#: Relative rounding allowed in a facet plane's signed distance (:func:`distances_to_facets`).
_ROUNDING = 1e-12


def distances_to_facets(points, facets, equations):
    """Exact distance (and closest point) from each point to a convex polytope.

    A point outside the polytope has its closest point on a facet whose plane it lies in
    front of, so only those facets are searched; points inside get distance 0.
    ``equations`` is ``(normals.T, offsets)``, the transpose contiguous for a fast product.

    "In front" allows a rounding error: a point on the surface can lie a rounding error in
    front of a coplanar facet that does not hold it and behind the one that does (a vertex of
    a box and the two triangles of a face); searching only the first would give that facet's
    distance instead of 0. A facet searched in excess is harmless: its closest point is on the
    surface, never nearer than the true one.

    3-D facets are searched in the core (``core.distances_to_facets``: the arithmetic of
    :func:`meshcol.geometry.triangles.closest_points_on_triangles` and
    :func:`nearest_on_facets`, step for step, without the candidate pairs' arrays); segments
    (a flat hull's edges) by :func:`nearest_on_facets` here.
    """
    dim = points.shape[1]
    signed = points @ equations[0] + equations[1]
    outside = signed.max(axis=1, initial=-np.inf) > 0.0
    scale = max(float(np.abs(facets).max(initial=0.0)), float(np.abs(points).max(initial=0.0)))
    in_front = (signed > -_ROUNDING * max(scale, 1e-300)) & outside[:, None]
    if dim == 3:
        from meshcol._native import core

        return core.distances_to_facets(
            np.ascontiguousarray(points), np.ascontiguousarray(facets), in_front
        )
    return nearest_on_facets(points, facets, in_front, closest_points_on_segments)


def nearest_on_facets(
    points: np.ndarray,
    facets: np.ndarray,
    in_front: np.ndarray,
    closest_on: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """Distance and closest point of each point over the facets ``in_front`` marks for it
    (``closest_on(points, facets)`` pairs rows; ties go to the first facet); 0 and the point
    itself for a point with none."""
    distances = np.zeros(len(points))
    closest = points.copy()
    p_index, f_index = np.nonzero(in_front)
    if len(p_index) == 0:
        return distances, closest
    candidates = closest_on(points[p_index], facets[f_index])
    d2 = ((candidates - points[p_index]) ** 2).sum(axis=1)
    order = np.lexsort((d2, p_index))
    first = np.ones(len(order), bool)
    first[1:] = p_index[order][1:] != p_index[order][:-1]
    best = order[first]
    distances[p_index[best]] = np.sqrt(d2[best])
    closest[p_index[best]] = candidates[best]
    return distances, closest


def closest_points_on_segments(p: np.ndarray, segments: np.ndarray) -> np.ndarray:
    a, b = segments[:, 0], segments[:, 1]
    ab = b - a
    t = np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab
