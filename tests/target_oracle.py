"""An independent count of what engine profiles limit, for the target tests.

Nothing here uses :mod:`meshcol.collision.limits`: each part's hull is scipy's (Qhull),
polygons are its facets grouped by plane equation, the in-sphere is a linear programme on
those planes (scipy.optimize.linprog; where the largest ball can slide, the lexicographic
centre, as meshcol's, by linear programmes of their own). The tests compare these counts with a profile's
limits, so a bug in meshcol's own measurement cannot hide a violated limit.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

#: Relative tolerance (of the part's bounding-box diagonal) for "same plane" and "inside".
PLANE_TOL = 1e-7


def _diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.ptp(points, axis=0)))


def count(vertices: Any, plane_tol: float = PLANE_TOL) -> dict[str, float]:
    """The measures of one convex part: vertices, triangles, polygons, faces per vertex,
    oblong ratio (farthest vertex from the in-sphere centre over its radius), thickness
    (least width across a polygon's normal) and volume. ``plane_tol``: how far (relative
    to the diagonal) two facets' planes may be apart and be one polygon; float32 vertices
    (MuJoCo's compiled model) need about 1e-5."""
    v = np.unique(np.asarray(vertices, dtype=np.float64), axis=0)
    diagonal = _diagonal(v)
    flat = _flat_frame(v)
    if flat is not None:  # a polygon: one face (the engine cooks a plate)
        polygon = ConvexHull(flat[0])
        k = len(polygon.vertices)
        return {
            "vertices": k,
            "triangles": k - 2,
            "polygons": 1,
            "max_faces_per_vertex": 1,
            "oblong_ratio": np.inf,
            "thickness": 0.0,
            "volume": 0.0,
        }
    hull = ConvexHull(v)
    eq = hull.equations
    labels = np.full(len(eq), -1)
    planes: list[np.ndarray] = []
    for i, e in enumerate(eq):
        for k, p in enumerate(planes):
            if e[:3] @ p[:3] > 1 - plane_tol and abs(e[3] - p[3]) <= plane_tol * diagonal:
                labels[i] = k
                break
        else:
            labels[i] = len(planes)
            planes.append(e)
    per_vertex = [
        len({int(labels[f]) for f in range(len(eq)) if k in hull.simplices[f]})
        for k in hull.vertices
    ]
    normals = np.array([p[:3] for p in planes])
    offsets = np.array([p[3] for p in planes])
    widths = (normals @ v.T).max(axis=1) - (normals @ v.T).min(axis=1)
    centre, radius = inscribed_ball(normals, offsets)
    reach = float(np.linalg.norm(v[hull.vertices] - centre, axis=1).max())
    return {
        "vertices": len(hull.vertices),
        "triangles": 2 * len(hull.vertices) - 4,
        "polygons": len(planes),
        "max_faces_per_vertex": max(per_vertex),
        "oblong_ratio": reach / radius if radius > 0 else np.inf,
        "thickness": float(widths.min()),
        "volume": float(hull.volume),
    }


def inscribed_ball(normals: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the largest ball in ``{x : normals @ x + offsets <= 0}``, the
    centre the lexicographic one where the ball can slide, by HiGHS (linprog) stage by
    stage: each stage maximises the least distance ``t`` to the planes not yet held (the
    held ones kept at their distance); the planes of positive dual value are then held at
    ``base + t`` (they are there in every optimum), until no direction keeps every held plane
    as far (:func:`_slides`, itself six linear programmes)."""
    m = len(normals)
    level = np.full(m, np.nan)
    base, radius, centre = 0.0, 0.0, np.zeros(3)
    for stage in range(8):
        free = np.isnan(level)
        lp = linprog(
            c=[0, 0, 0, -1],
            A_ub=np.hstack([normals, free[:, None].astype(np.float64)]),
            b_ub=-offsets - np.where(free, base, level),
            bounds=[(None, None)] * 4,
            method="highs",
        )
        centre, reached = lp.x[:3], base + lp.x[3]
        if stage == 0:
            radius = max(reached, 0.0)
            if radius == 0.0:
                break
        level[free & (-lp.ineqlin.marginals > 1e-9)] = reached
        if not _slides(normals[~np.isnan(level)]):
            break
        base = reached
    return centre, radius


def _slides(held: np.ndarray) -> bool:
    """Whether some unit-box direction ``u != 0`` has ``held @ u <= 0``."""
    for axis in range(3):
        for sign in (1.0, -1.0):
            c = np.zeros(3)
            c[axis] = -sign
            lp = linprog(c=c, A_ub=held, b_ub=np.zeros(len(held)), bounds=[(-1, 1)] * 3)
            if lp.status == 0 and -lp.fun > 1e-9:
                return True
    return False


def _flat_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(2-D coordinates, origin, basis (3, 3))`` of coplanar points, else None."""
    origin = points.mean(axis=0)
    _, s, vt = np.linalg.svd(points - origin)
    if len(s) == 3 and s[2] > PLANE_TOL * max(s[0], 1e-300):
        return None
    return (points - origin) @ vt[:2].T, origin, vt


#: Limit key -> (measure, "max" or "min").
LIMITS = {
    "max_hull_vertices": ("vertices", "max"),
    "max_hull_triangles": ("triangles", "max"),
    "max_hull_polygons": ("polygons", "max"),
    "max_faces_per_vertex": ("max_faces_per_vertex", "max"),
    "max_oblong_ratio": ("oblong_ratio", "max"),
    "min_thickness": ("thickness", "min"),
    "min_volume": ("volume", "min"),
}


def missed(
    parts: list[Any],
    limits: Mapping[str, float],
    length_scale: float = 1.0,
    plane_tol: float = PLANE_TOL,
) -> set[str]:
    """The limit keys the parts miss, counted here (lengths converted by ``length_scale``,
    input units per metre; a 1e-6 relative slack on the measured floats, the counts exact)."""
    out = set()
    if "max_hulls" in limits and len(parts) > limits["max_hulls"]:
        out.add("max_hulls")
    for part in parts:
        measures = count(part, plane_tol)
        for key, (name, sense) in LIMITS.items():
            if key not in limits:
                continue
            limit = float(limits[key])
            if key == "min_thickness":
                limit *= length_scale
            elif key == "min_volume":
                limit *= length_scale**3
            value = measures[name]
            if sense == "max" and value > limit * (1 + 1e-6):
                out.add(key)
            if sense == "min" and value < limit * (1 - 1e-6):
                out.add(key)
    return out


def encloses(part: Any, points: Any, tol: float = 1e-9) -> bool:
    """Every point lies in the convex hull of ``part`` (scipy's plane equations, ``tol`` of
    the points' extent)."""
    points = np.asarray(points, dtype=np.float64)
    part = np.asarray(part, dtype=np.float64)
    scale = max(float(np.ptp(points, axis=0).max()), 1e-300)
    flat = _flat_frame(part)
    if flat is not None:  # a polygon holds points in its plane and inside its outline
        _, origin, basis = flat
        off_plane = np.abs((points - origin) @ basis[2])
        eq = ConvexHull((part - origin) @ basis[:2].T).equations
        inside = ((points - origin) @ basis[:2].T) @ eq[:, :2].T + eq[:, 2]
        return bool(off_plane.max() <= tol * scale and inside.max() <= tol * scale)
    eq = ConvexHull(part).equations
    return bool((points @ eq[:, :3].T + eq[:, 3]).max() <= tol * scale)
