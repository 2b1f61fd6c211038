"""Every triangle of a mesh as a convex part: what stands for a ``mesh`` body in the convex
queries when the caller asks for its surface (:func:`meshcol.analysis.colliders.build_colliders`
with ``mesh_parts="triangles"``: sweep's surface contact)."""

from __future__ import annotations

import numpy as np

from meshcol.collision.hull import FLAT_RELATIVE_TOLERANCE
from meshcol.collision.shapes import ConvexSet
from meshcol.types import Body

__all__ = ["triangle_parts"]


def triangle_parts(body: Body) -> ConvexSet:
    """Every triangle of a body's mesh as a convex part (local frame).

    A triangle with an area is a 3-vertex polytope; one that is collinear or a point by the
    flatness rule (:data:`meshcol.collision.hull.FLAT_RELATIVE_TOLERANCE`, relative to its own
    size) is packed as the segment or point it is, so no triangle is ever dropped.
    """
    return _triangle_parts(body)[0]


def _triangle_parts(body: Body) -> tuple[ConvexSet, np.ndarray]:
    """:func:`triangle_parts` and the face of each part (solid triangles first, then flat)."""
    tri = np.asarray(body.vertices, dtype=np.float64)[np.asarray(body.faces, dtype=np.int64)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    longest = np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2).max(axis=1) if len(tri) else area2
    with np.errstate(invalid="ignore", divide="ignore"):
        height = np.where(longest > 0, area2 / longest, 0.0)
    keep = np.isfinite(height) & (height > FLAT_RELATIVE_TOLERANCE * longest)
    flat = ConvexSet.from_vertices(list(tri[~keep])) if np.any(~keep) else None
    tri, n, area2 = tri[keep], n[keep], area2[keep]
    t = len(tri)
    unit = n / area2[:, None] if t else np.zeros((0, 3))
    # the three sides as true edges: their direction classes are the core's (computed when
    # SAT first needs them)
    sides = np.array([[0, 1], [1, 2], [2, 0]], dtype=np.int32)
    step3 = np.arange(t + 1, dtype=np.int64) * 3
    local = np.array([[1, 2], [0, 2], [0, 1]], dtype=np.int32)
    solid = ConvexSet._adopt(
        vertices=tri.reshape(-1, 3),
        offsets=step3,
        kinds=np.zeros(t, np.int8),
        params=np.zeros((t, 4)),
        adjacency_offsets=np.arange(3 * t + 1, dtype=np.int64) * 2,
        adjacency=np.tile(local.reshape(-1), t),
        face_offsets=np.arange(t + 1, dtype=np.int64) * 2,
        face_normals=np.stack([unit, -unit], axis=1).reshape(-1, 3),
        edge_pair_offsets=step3,
        edge_pairs=np.tile(sides, (t, 1)),
    )
    order = np.concatenate([np.flatnonzero(keep), np.flatnonzero(~keep)])
    return (solid if flat is None else ConvexSet.concatenate(solid, flat)), order
