"""Triangles on arrays: closest points, point distances, areas, surface samples, degeneracy."""

from __future__ import annotations

import numpy as np

__all__ = [
    "DEGENERATE_RELATIVE_HEIGHT",
    "closest_points_on_triangles",
    "degenerate_faces",
    "face_heights",
    "point_triangle_distances",
    "sample_surface",
    "triangle_areas",
]


def closest_points_on_triangles(p: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Closest point on each triangle to each point, vectorised.

    Parameters
    ----------
    p : (n, 3) float
    triangles : (n, 3, 3) float

    Returns
    -------
    (n, 3) float

    Notes
    -----
    Ericson, Real-Time Collision Detection (2004), 5.1.5: Voronoi regions of the vertices,
    then the edges, else the projection onto the face.
    """
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2

    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        result = a + v[:, None] * ab + w[:, None] * ac  # face region
        # edge regions
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    on_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    result = np.where(on_bc[:, None], b + np.nan_to_num(t_bc)[:, None] * (c - b), result)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    result = np.where(on_ac[:, None], a + np.nan_to_num(t_ac)[:, None] * ac, result)
    # applied in reverse order of Ericson's early returns, so the first test wins
    result = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, result)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    result = np.where(on_ab[:, None], a + np.nan_to_num(t_ab)[:, None] * ab, result)
    result = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, result)
    result = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, result)
    # a degenerate (zero-area) triangle leaves NaN in the face region: fall back to its
    # closest vertex
    bad = ~np.isfinite(result).all(axis=1)
    if bad.any():
        corners = triangles[bad]
        d = ((corners - p[bad][:, None, :]) ** 2).sum(axis=2)
        result[bad] = corners[np.arange(len(corners)), d.argmin(axis=1)]
    return result


def point_triangle_distances(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance from each point (n, 3) to its triangle (n, 3, 3) (Ericson 2004, 5.1.5)."""
    return np.linalg.norm(p - closest_points_on_triangles(p, tri), axis=1)


def triangle_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of each triangle, (m,) float64."""
    t = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)


def sample_surface(
    vertices: np.ndarray, faces: np.ndarray, count: int, rng: np.random.Generator
) -> np.ndarray:
    """``count`` points uniformly distributed on the triangles (area-weighted), (count, 3)."""
    tri = vertices[faces]
    area = triangle_areas(vertices, faces)
    total = area.sum()
    if count <= 0 or total <= 0:
        return np.empty((0, 3))
    which = rng.choice(len(faces), size=count, p=area / total)
    r1, r2 = rng.random(count), rng.random(count)
    s = np.sqrt(r1)
    t = tri[which]
    return (
        (1 - s)[:, None] * t[:, 0] + (s * (1 - r2))[:, None] * t[:, 1] + (s * r2)[:, None] * t[:, 2]
    )


#: A face is degenerate when its height (twice its area over its longest edge) is at most
#: this fraction of the mesh's bounding-box diagonal: it then has no usable normal. 1e-7 is
#: just above float32 rounding, the precision of STL files.
DEGENERATE_RELATIVE_HEIGHT = 1e-7


def face_heights(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What :func:`degenerate_faces` compares with a length, measured once for a mesh judged
    at several sizes (one mesh instanced at many poses, each with its own diagonal).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    heights : (m,) float64
        Each face's height on its longest edge (twice its area over that edge's length; 0
        when every edge has length 0).
    repeated : (m,) bool
        The face names one vertex twice.
    """
    tri = vertices[faces]
    twice_area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    longest = np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2).max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        height = np.where(longest > 0, twice_area / longest, 0.0)
    repeated = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    )
    return height, repeated


def degenerate_faces(
    vertices: np.ndarray,
    faces: np.ndarray,
    diagonal: float,
    *,
    heights: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """(m,) bool: faces with a repeated vertex or a height at most
    ``DEGENERATE_RELATIVE_HEIGHT * diagonal`` (they have no usable normal).

    ``heights``, :func:`face_heights` of the same vertices and faces when already measured,
    spares measuring them again."""
    height, repeated = face_heights(vertices, faces) if heights is None else heights
    return repeated | (height <= DEGENERATE_RELATIVE_HEIGHT * diagonal)
