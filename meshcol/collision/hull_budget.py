"""The budgeted hull's loop: a polytope of supporting planes of an exact hull, cut where it is
farthest from the hull while its vertex count stays within a budget (:func:`_simplify`, the
steps of :func:`meshcol.collision.hull.convex_hull` with ``max_vertices``).

In 3-D the loop runs in the C++ core (``cpp/src/hull_budget.cpp``, many bodies a call on
threads, :func:`simplify_many`): it keeps the polytope as its vertices and the planes through
each, so a trial cut is a clip of the vertices, not a new half-space intersection. The core
returns the accepted planes and its final polytope. The polytope handed back is qhull's
intersection of those planes (:func:`_intersect`, the call the loop made for every trial
before), so a body whose planes the core picks as the loop in numpy did gets the same
vertices up to rounding. Where that intersection breaks the budget, it is the core's own
polytope, checked (:func:`_checked_polytope`): a cut plane that touches the polytope along an
edge meets two planes of that edge in the edge's line, and qhull reports one more point, on
the edge, or it splits a vertex of four planes or more into points a little farther apart
than the merge radius (94 and 22 of the 10,000 props of ``bench_scale`` under ``--target
isaac``; RESULTS.md, session 43). Only a body the core could not serve (a degenerate start, a polytope that fails
the check) is simplified again by the loop in numpy (:func:`_simplify_qhull`), which also
simplifies flat input (2-D).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np

from meshcol.collision.arrays import as_offsets
from meshcol.collision.facet_distance import distances_to_facets
from meshcol.errors import InvalidMeshError

__all__ = [
    "CONTAINS_RELATIVE_DISTANCE",
    "CONVERGED_RELATIVE_DISTANCE",
    "CUT_CANDIDATES",
    "MERGE_RELATIVE_DISTANCE",
    "START_ORIENTATIONS",
    "simplify_many",
]

#: The budget loop stops early once the simplified hull is within this fraction of the
#: diagonal of the exact hull.
CONVERGED_RELATIVE_DISTANCE = 1e-9
#: Simplified-hull vertices closer than this fraction of the diagonal are merged.
MERGE_RELATIVE_DISTANCE = 1e-11
#: A budgeted hull contains the exact hull to this fraction of its diagonal (a merge of
#: near-duplicate vertices moves one by up to :data:`MERGE_RELATIVE_DISTANCE`), and a vertex
#: of the core's polytope lies inside each of its planes to it.
CONTAINS_RELATIVE_DISTANCE = MERGE_RELATIVE_DISTANCE
#: A vertex of the core's polytope lies on a plane when within this fraction of the diagonal.
ON_PLANE_RELATIVE_DISTANCE = 1e-9
#: Orientations tried for the starting simplex (the smallest enclosing one is kept).
START_ORIENTATIONS = 64
#: Far vertices tried per step before the budget loop gives up.
CUT_CANDIDATES = 8


def _simplify(hull_vertices, facets, equations, budget, scale, max_planes=None):
    """Supporting-plane polytope with <= ``budget`` vertices (and, with ``max_planes``, at
    most that many planes) around the exact hull.

    ``hull_vertices`` (k, d) are the exact hull's vertices, ``facets`` (m, d, d) its facet
    simplices and ``equations`` (m, d + 1) their outward planes ``n . x + c = 0``.
    Returns the polytope's vertices (q, d) and its exact distance to the hull. 3-D: the
    core's loop (:func:`simplify_many` of one body); 2-D: :func:`_simplify_qhull`, whose
    docstring gives the steps.
    """
    if hull_vertices.shape[1] == 3:
        return simplify_many([(hull_vertices, facets, equations, budget, scale, max_planes)])[0]
    return _simplify_qhull(hull_vertices, facets, equations, budget, scale, max_planes)


def simplify_many(
    bodies: Sequence[tuple[Any, ...]], threads: int = 0
) -> list[tuple[np.ndarray, float]]:
    """:func:`_simplify` of many 3-D bodies, the loops in one native call.

    Parameters
    ----------
    bodies : sequence of (hull_vertices, facets, equations, budget, scale, max_planes)
        Per body the arguments of :func:`_simplify`: (k, 3) exact hull vertices, (m, 3, 3)
        facets, (m, 4) outward planes, the vertex budget (>= 4), the diagonal and the plane
        budget (None: none).
    threads : int
        Threads over bodies (0: all cores).

    Returns
    -------
    list of ((q, 3) float64, float)
        Per body, the polytope's vertices and its exact distance to the hull.

    Notes
    -----
    The core runs each body's loop (the steps of :func:`_simplify_qhull`, every trial a clip
    of the current polytope) and returns its accepted planes and final polytope; the
    polytope is their half-space intersection by qhull (:func:`_intersect`), or where that
    breaks the budget the core's own (:func:`_checked_polytope`), and its distance the exact
    one of ``distances_to_facets``. A body whose start is degenerate or whose polytope fails
    the check goes through :func:`_simplify_qhull` instead.
    """
    from meshcol._native import core

    if len(bodies) == 0:
        return []
    vertices = [np.ascontiguousarray(b[0], dtype=np.float64) for b in bodies]
    facets = [np.ascontiguousarray(b[1], dtype=np.float64) for b in bodies]
    equations = [np.ascontiguousarray(b[2], dtype=np.float64) for b in bodies]
    starts = []
    for v in vertices:
        normals = _start_simplex(v)
        starts.append(np.hstack([normals, (normals @ v.T).max(axis=1)[:, None]]))
    scales = np.array([float(b[4]) for b in bodies])
    planes, plane_offsets, corners, corner_offsets, status = core.budget_hull_planes(
        np.concatenate(vertices),
        as_offsets([len(v) for v in vertices]),
        np.concatenate(facets),
        np.concatenate(equations),
        as_offsets([len(f) for f in facets]),
        np.ascontiguousarray(np.concatenate(starts)),
        np.array([int(b[3]) for b in bodies], dtype=np.int64),
        np.array([-1 if b[5] is None else int(b[5]) for b in bodies], dtype=np.int64),
        CONVERGED_RELATIVE_DISTANCE * scales,
        MERGE_RELATIVE_DISTANCE * scales,
        CUT_CANDIDATES,
        int(threads),
    )
    results = []
    for i, body in enumerate(bodies):
        if status[i] != 0:
            results.append(_simplify_qhull(*body))
            continue
        body_planes = planes[plane_offsets[i] : plane_offsets[i + 1]]
        interior = vertices[i].mean(axis=0)
        polytope = _intersect(body_planes[:, :3], body_planes[:, 3], interior, scales[i])
        if polytope is None or len(polytope) > int(body[3]):
            # qhull's points include one on an edge (planes through one line) or a split
            # vertex: the core's own polytope, checked
            polytope = _checked_polytope(
                corners[corner_offsets[i] : corner_offsets[i + 1]], body_planes, body[3], scales[i]
            )
        if polytope is None:
            results.append(_simplify_qhull(*body))
            continue
        split = (
            np.ascontiguousarray(equations[i][:, :3].T),
            np.ascontiguousarray(equations[i][:, 3]),
        )
        distances, _ = distances_to_facets(polytope, facets[i], split)
        results.append((polytope, float(distances.max())))
    return results


def _checked_polytope(
    corners: np.ndarray, planes: np.ndarray, budget: int, scale: float
) -> np.ndarray | None:
    """The core's polytope of one body when it is one of its ``planes`` (P, 4) as (n, offset):
    within the budget, finite, every vertex inside every plane and on three of them not
    through one line (:data:`CONTAINS_RELATIVE_DISTANCE`, :data:`ON_PLANE_RELATIVE_DISTANCE`
    of ``scale``); else None. Whether it contains the exact hull is checked with its faces
    (:func:`meshcol.collision.hull.hulls_within_budgets`)."""
    if not 4 <= len(corners) <= budget or not np.isfinite(corners).all():
        return None
    tolerance = CONTAINS_RELATIVE_DISTANCE * scale
    signed = corners @ planes[:, :3].T - planes[:, 3]
    if signed.max() > tolerance:
        return None
    # on three planes not through one line: the normals of the planes through a vertex span
    # 3-D, the least eigenvalue of the sum of their outer products above 1e-12 (rounding
    # leaves about 1e-16 for normals of planes through one line; the vertices of the 116
    # scale props of RESULTS.md, session 43, have 5e-6 and more)
    on = (np.abs(signed) <= ON_PLANE_RELATIVE_DISTANCE * scale).astype(np.float64)
    normals = planes[:, :3]
    spans = np.einsum("vp,pi,pj->vij", on, normals, normals)
    if np.linalg.eigvalsh(spans)[:, 0].min() <= 1e-12:
        return None
    return np.array(corners)


def _simplify_qhull(hull_vertices, facets, equations, budget, scale, max_planes=None):
    """Supporting-plane polytope with <= ``budget`` vertices (and, with ``max_planes``, at
    most that many planes) around the exact hull.

    ``hull_vertices`` (k, d) are the exact hull's vertices, ``facets`` (m, d, d) its facet
    simplices and ``equations`` (m, d + 1) their outward planes ``n . x + c = 0``.
    Returns the polytope's vertices (q, d) and its exact distance to the hull.

    The steps, with H the exact hull and Q the polytope:

    1. Start from the smallest of ``START_ORIENTATIONS`` simplices (tetrahedron, or triangle
       when flat) whose faces are supporting planes of H.
    2. Find the vertex v of Q farthest from H, with its closest point p on H (exact
       point-to-facet distances over the facets of H that v sees).
    3. Add the supporting plane at p with normal ``(v - p) / |v - p|``: it is the cut that
       removes v most deeply. Recompute Q as the intersection of the half-spaces
       (``scipy.spatial.HalfspaceIntersection``, interior point: the centroid of H's vertices).
    4. Keep the cut if Q still has at most ``budget`` vertices (else try the next farthest
       vertices, up to ``CUT_CANDIDATES``), and repeat from 2 until no cut fits or Q is within
       ``CONVERGED_RELATIVE_DISTANCE`` of H.

    Each step reduces the largest deviation where it is. This is the loop in numpy (a
    half-space intersection a trial): flat input (2-D) takes it, and a 3-D body the core's
    loop (:func:`simplify_many`) could not serve.
    """
    interior = hull_vertices.mean(axis=0)
    dim = hull_vertices.shape[1]
    equations = (
        np.ascontiguousarray(equations[:, :dim].T),
        np.ascontiguousarray(equations[:, dim]),
    )
    tolerance = CONVERGED_RELATIVE_DISTANCE * scale
    normals = _start_simplex(hull_vertices)
    offsets = (normals @ hull_vertices.T).max(axis=1)
    polytope = _intersect(normals, offsets, interior, scale)
    if polytope is None:  # qhull failed on four planes: not seen, but never crash on it
        raise InvalidMeshError(f"could not build a hull within {budget} vertices")
    distances, closest = distances_to_facets(polytope, facets, equations)
    for _ in range(4 * budget + 16):
        if max_planes is not None and len(normals) >= max_planes:
            break
        order = np.argsort(-distances, kind="stable")
        accepted = False
        for index in order[:CUT_CANDIDATES]:
            if distances[index] <= tolerance:
                break
            normal = (polytope[index] - closest[index]) / distances[index]
            offset = float((hull_vertices @ normal).max())
            trial_normals = np.vstack([normals, normal])
            trial_offsets = np.append(offsets, offset)
            trial = _intersect(trial_normals, trial_offsets, interior, scale)
            if trial is not None and len(trial) <= budget:
                distances, closest = _update_distances(
                    polytope, distances, closest, trial, facets, equations, scale
                )
                normals, offsets, polytope = trial_normals, trial_offsets, trial
                accepted = True
                break
        if not accepted:
            break
    # the loop reused distances of vertices that survived a cut; report a fresh, exact one
    distances, _ = distances_to_facets(polytope, facets, equations)
    return polytope, float(distances.max())


def _update_distances(old, old_distances, old_closest, new, facets, equations, scale):
    """Distances of ``new`` vertices, reusing those of vertices ``old`` already had."""
    from scipy.spatial import cKDTree

    gap, match = cKDTree(old).query(new, distance_upper_bound=MERGE_RELATIVE_DISTANCE * scale)
    known = np.isfinite(gap)
    distances = np.empty(len(new))
    closest = np.empty_like(new)
    distances[known] = old_distances[match[known]]
    closest[known] = old_closest[match[known]]
    if (~known).any():
        distances[~known], closest[~known] = distances_to_facets(new[~known], facets, equations)
    return distances, closest


def _start_simplex(hull_vertices: np.ndarray) -> np.ndarray:
    """Unit normals (d + 1, d) of the smallest of several supporting regular-simplex shapes."""
    dim = hull_vertices.shape[1]
    normals, skips = _start_orientations(dim)
    offsets = (normals @ hull_vertices.T).max(axis=2)  # (orientations, d + 1)
    # each simplex's corners at once: corner k solves the planes but plane k
    corners = np.linalg.solve(normals[:, skips], offsets[:, skips, None])[..., 0]
    sizes = np.abs(np.linalg.det(corners[:, 1:] - corners[:, :1]))
    return normals[int(np.argmin(sizes))]


@functools.cache
def _start_orientations(dim: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``START_ORIENTATIONS`` turned regular simplices' unit normals (orientations, d + 1,
    d), the first unturned, and the planes (d + 1, d) each corner lies on (all but one)."""
    rng = np.random.default_rng(0)
    if dim == 3:
        base = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) / np.sqrt(3)
        rotations = [np.eye(3)]
        for _ in range(START_ORIENTATIONS - 1):
            q, r = np.linalg.qr(rng.normal(size=(3, 3)))
            rotations.append(q * np.sign(np.diag(r)))
    else:
        angles = np.pi / 2 + np.array([0, 2, 4]) * np.pi / 3
        base = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        rotations = []
        for t in np.linspace(0, 2 * np.pi / 3, START_ORIENTATIONS, endpoint=False):
            c, s = np.cos(t), np.sin(t)
            rotations.append(np.array([[c, -s], [s, c]]))
    normals = np.stack([base @ rotation.T for rotation in rotations])
    skips = np.array([[i for i in range(dim + 1) if i != skip] for skip in range(dim + 1)])
    normals.flags.writeable = False
    return normals, skips


def _intersect(normals, offsets, interior, scale):
    """Vertices of ``{x : normals @ x <= offsets}``, near-duplicates merged; None on failure."""
    from scipy.spatial import HalfspaceIntersection, QhullError

    halfspaces = np.hstack([normals, -offsets[:, None]])
    try:
        points = HalfspaceIntersection(halfspaces, interior).intersections
    except QhullError:
        return None
    if not np.isfinite(points).all():
        return None
    return _merge_close(points, MERGE_RELATIVE_DISTANCE * scale)


def _merge_close(points: np.ndarray, radius: float) -> np.ndarray:
    """One representative per cluster of points closer than ``radius`` (the farthest out)."""
    from scipy.spatial import cKDTree

    from meshcol.geometry.graph import connected_components

    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return points
    n = len(points)
    _, labels = connected_components(n, pairs)
    # keep, per cluster, the point farthest from the centroid: the merged polytope then
    # still contains the cluster up to ``radius``
    centroid = points.mean(axis=0)
    reach = np.linalg.norm(points - centroid, axis=1)
    order = np.lexsort((-reach, labels))
    first = np.ones(n, bool)
    first[1:] = labels[order][1:] != labels[order][:-1]
    return points[order[first]]
