"""Brute-force exact oracles for convex polytopes (numpy only, independent of meshcol).

- ``polytope_distance``: the distance between two convex polytopes is reached by a
  vertex-face, face-vertex or edge-edge pair of hull features, so it is the minimum of
  point-triangle and segment-segment distances over all of them (Ericson 2004, sec. 5.1.5 and
  5.1.9), once SAT has shown the shapes apart.
- ``sat_depth``: the penetration depth of two convex polytopes is the minimum, over the face
  normals of both and the cross products of all edge pairs, of the overlap along that axis.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull


def hull_features(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles (t, 3, 3), edges (e, 2, 3) and outward unit normals (t, 3) of a 3D hull."""
    hull = ConvexHull(points)
    tris = points[hull.simplices]
    e = np.concatenate(
        [hull.simplices[:, [0, 1]], hull.simplices[:, [1, 2]], hull.simplices[:, [2, 0]]]
    )
    e = np.unique(np.sort(e, axis=1), axis=0)
    return tris, points[e], hull.equations[:, :3]


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def point_triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distances (n,) from points p (n, 3) to triangles tri (n, 3, 3), Ericson 5.1.5."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        q = a + ab * v[:, None] + ac * w[:, None]
        # edge regions
        t_ab = np.where(d1 - d3 != 0, d1 / (d1 - d3), 0.0)
        t_ac = np.where(d2 - d6 != 0, d2 / (d2 - d6), 0.0)
        t_bc = np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) / ((d4 - d3) + (d5 - d6)), 0.0)
    regions = [
        (d1 <= 0) & (d2 <= 0),
        a,
        (d3 >= 0) & (d4 <= d3),
        b,
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),
        a + ab * t_ab[:, None],
        (d6 >= 0) & (d5 <= d6),
        c,
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        a + ac * t_ac[:, None],
        (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),
        b + (c - b) * t_bc[:, None],
    ]
    out = q.copy()
    done = np.zeros(len(p), dtype=bool)
    for mask, point in zip(regions[::2], regions[1::2]):
        take = mask & ~done
        out[take] = point[take]
        done |= mask
    # Plane projection for the face region (as exact as floating point allows).
    n = np.cross(ab, ac)
    nn = _dot(n, n)
    face = ~done & (nn > 0)
    dist = np.linalg.norm(p - out, axis=1)
    dist[face] = np.abs(_dot(n[face], ap[face])) / np.sqrt(nn[face])
    return dist


def segment_segment_distance(p1, q1, p2, q2) -> np.ndarray:
    """Distances (n,) between segments p1q1 and p2q2 (n, 3 each), Ericson 5.1.9."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = _dot(d1, d1), _dot(d2, d2), _dot(d2, r)
    c, b = _dot(d1, r), _dot(d1, d2)
    eps = 1e-300
    s = np.zeros(len(p1))
    t = np.zeros(len(p1))
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = a * e - b * b
        s = np.where(denom > eps * (a * e + eps), np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        s = np.where(a <= eps, 0.0, s)
        t = np.where(e > eps, (b * s + f) / e, 0.0)
        s_low = np.where(a > eps, np.clip(-c / a, 0, 1), 0.0)
        s_high = np.where(a > eps, np.clip((b - c) / a, 0, 1), 0.0)
    s = np.where(t < 0, s_low, np.where(t > 1, s_high, s))
    t = np.clip(t, 0, 1)
    c1 = p1 + d1 * s[:, None]
    c2 = p2 + d2 * t[:, None]
    return np.linalg.norm(c1 - c2, axis=1)


def sat_depth(pa: np.ndarray, pb: np.ndarray) -> float:
    """Minimum overlap of two 3D convex point sets over all SAT axes (< 0 when apart)."""
    _, ea, na = hull_features(pa)
    _, eb, nb = hull_features(pb)
    da = ea[:, 1] - ea[:, 0]
    db = eb[:, 1] - eb[:, 0]
    cr = np.cross(da[:, None, :], db[None, :, :]).reshape(-1, 3)
    lens = np.linalg.norm(cr, axis=1)
    cr = cr[lens > 1e-9 * lens.max()] / lens[lens > 1e-9 * lens.max()][:, None]
    axes = np.concatenate([na, -nb, cr, -cr])
    overlap = (pa @ axes.T).max(axis=0) - (pb @ axes.T).min(axis=0)
    return float(overlap.min())


def polytope_distance(pa: np.ndarray, pb: np.ndarray) -> float:
    """Exact distance of two 3D convex point sets (0 when they touch or overlap)."""
    if sat_depth(pa, pb) >= 0.0:
        return 0.0
    ta, ea, _ = hull_features(pa)
    tb, eb, _ = hull_features(pb)
    best = np.inf
    for points, tris in ((pa, tb), (pb, ta)):
        p = np.repeat(points, len(tris), axis=0)
        t = np.tile(tris, (len(points), 1, 1))
        best = min(best, point_triangle_distance(p, t).min())
    i, j = np.meshgrid(np.arange(len(ea)), np.arange(len(eb)), indexing="ij")
    i, j = i.ravel(), j.ravel()
    best = min(best, segment_segment_distance(ea[i, 0], ea[i, 1], eb[j, 0], eb[j, 1]).min())
    return float(best)


def transform(points: np.ndarray, pose: np.ndarray | None) -> np.ndarray:
    """World coordinates of local points under a row-major 4x4 pose."""
    if pose is None:
        return np.asarray(points, dtype=np.float64)
    return points @ pose[:3, :3].T + pose[:3, 3]


def box_corners(size) -> np.ndarray:
    h = np.asarray(size, dtype=np.float64) / 2.0
    return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h


def quaternion_rotation(q) -> np.ndarray:
    """The rotation matrix of quaternion ``q`` = (w, x, y, z), normalised first."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
