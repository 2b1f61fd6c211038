"""Inside or outside a triangle mesh by ray parity, voted over several directions.

The fallback inside test for a mesh whose faces cannot be wound consistently (a
non-orientable surface: its winding number means nothing): a point is inside when a ray from
it crosses the surface an odd number of times. A ray that passes near an edge or a vertex of
the mesh, or along a face's plane, could be counted wrong by rounding: that direction abstains
for that point. The directions that do not abstain vote; a point is decided only when they
all agree, and when at least :data:`PARITY_MIN_VOTES` of them voted.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PARITY_DIRECTIONS", "PARITY_MIN_VOTES", "ray_parity"]

#: Ray directions tried per point: fixed, irrational-looking, spread over the sphere (no two
#: along one axis or plane of a modelled part).
PARITY_DIRECTIONS = np.array(
    [
        [0.2876, 0.5327, 0.7962],
        [-0.6131, 0.2189, 0.7591],
        [0.4418, -0.8247, 0.3531],
        [-0.3392, -0.4473, -0.8276],
        [0.8493, 0.3114, -0.4262],
        [-0.7708, -0.5951, 0.2274],
        [0.1357, 0.9518, -0.2752],
    ]
)
#: Fewest non-abstaining directions for a verdict.
PARITY_MIN_VOTES = 3
#: A crossing whose barycentric coordinates or whose angle with the face come within this
#: relative margin of zero abstains (well above the rounding of the sums involved).
_GRAZE = 1e-9


def ray_parity(
    points: np.ndarray, vertices: np.ndarray, faces: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Whether each point is inside the mesh by ray parity, and whether that is decided.

    Parameters
    ----------
    points : (n, 3) float
        Query points, in the mesh's frame.
    vertices : (v, 3) float
    faces : (m, 3) int

    Returns
    -------
    inside, decided : (n,) bool, (n,) bool
        ``inside`` is meaningful where ``decided``: every direction of
        :data:`PARITY_DIRECTIONS` that did not abstain (grazing an edge, a vertex or a face's
        plane) counted the same parity, and at least :data:`PARITY_MIN_VOTES` did.

    Notes
    -----
    Moeller and Trumbore 1997's ray-triangle test per direction, with a margin: a hit whose
    barycentric coordinates or whose ray-plane angle are within a relative ``1e-9`` of the
    boundary makes the direction abstain, so a counted crossing is never a rounding artefact.
    Brute force over the triangles (the fallback is for the rare meshes that need it).
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    n = len(points)
    votes = np.zeros((len(PARITY_DIRECTIONS), n), dtype=np.int8)  # 1 inside, -1 out, 0 abstain
    if len(corners) == 0 or n == 0:
        return np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    a = corners[:, 0]
    e1, e2 = corners[:, 1] - a, corners[:, 2] - a
    for k, raw in enumerate(PARITY_DIRECTIONS):
        direction = raw / np.linalg.norm(raw)
        pvec = np.cross(direction, e2)
        det = np.einsum("ij,ij->i", e1, pvec)
        scale = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
        flat = np.abs(det) <= _GRAZE * scale
        safe = np.where(flat, 1.0, det)
        for i, point in enumerate(points):
            tvec = point - a
            u = np.einsum("ij,ij->i", tvec, pvec) / safe
            qvec = np.cross(tvec, e1)
            v = (qvec @ direction) / safe
            t = np.einsum("ij,ij->i", e2, qvec) / safe
            w = 1.0 - u - v
            reach = np.abs(t) > _GRAZE * np.sqrt(scale)
            inner = (u > _GRAZE) & (v > _GRAZE) & (w > _GRAZE)
            near = (u > -_GRAZE) & (v > -_GRAZE) & (w > -_GRAZE) & ~inner
            ahead = t > 0
            # grazing: an edge or vertex, a face's plane along the ray, or the point on a face
            graze = ~flat & ahead & near
            graze |= ~flat & inner & ~reach
            graze |= flat & _coplanar_hit(point, direction, corners)
            if graze.any():
                continue
            crossings = int(np.count_nonzero(~flat & inner & ahead & reach))
            votes[k, i] = 1 if crossings % 2 else -1
    inside = (votes == 1).sum(axis=0)
    outside = (votes == -1).sum(axis=0)
    decided = ((inside == 0) | (outside == 0)) & (inside + outside >= PARITY_MIN_VOTES)
    return inside > 0, decided


def _coplanar_hit(point: np.ndarray, direction: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Triangles parallel to the ray (flat ``det``) whose plane holds it, within a relative
    margin: the ray may run along them, which a parity count cannot settle."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1)
    reach = np.linalg.norm(corners[:, 0] - point, axis=1) + 1.0
    offset = np.abs(np.einsum("ij,ij->i", corners[:, 0] - point, normal))
    return offset <= 1e-9 * length * reach
