"""The depth interval of ``check``: ``depth <= minimum translation distance <= depth_upper``.

``depth`` is what the narrow phase and the mesh stage measured: for convex pairs the
penetration depth of the closest part pair (exact for one part each, the largest part pair's
otherwise: any separating translation separates every part pair, so a lower bound); for mesh
pairs the mesh depth (a lower bound of the minimum translation distance when the other mesh
is closed). ``depth_upper`` is the penetration depth of two convex sets that enclose the
bodies: a translation that separates them separates the bodies, so it bounds the minimum
translation distance from above. The stage runs after :func:`~meshcol.analysis.mesh_phase.
mesh_phase` and before :func:`~meshcol.analysis.pairs.classify`, and lowers a ``depth`` above
``depth_upper`` to it (an open mesh's depth can exceed it), so that the interval always holds.
A row with an MJCF plane's half-space has ``depth_upper = depth``: the depth of the body's
deepest part below the plane is the minimum translation distance itself.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from meshcol.analysis.pairs import NO_ANSWER, PairTable, PlacedColliders
from meshcol.vocabulary import HALF_SPACE_COLLIDER

__all__ = ["depth_bounds", "support", "supports"]

_SPHERE, _BOX, _CAPSULE, _CYLINDER, _ELLIPSOID, _HALFSPACE = 1, 2, 3, 4, 5, 6
#: How far off its normal (relative) a direction still reads a half-space's support as its
#: plane's height: the narrow phase's normal is the plane's, rotated there and back.
_NORMAL_SLACK = 1e-9


def depth_bounds(table: PairTable, placed: PlacedColliders, threads: int = 0) -> PairTable:
    """``depth_upper`` of every row, and ``depth`` lowered to it where it exceeded it.

    Rows apart (``distance > 0``, neither nested nor undecided) get ``depth_upper = 0``;
    rows touching, crossing, nested or undecided
    the penetration depth of the bodies' enclosing convex sets (each body's one convex part,
    or the convex hull of all its parts, a primitive part by its box's corners), measured as
    the overlap of their support functions along the narrow phase's normal: an exact upper
    bound whatever the solver's tolerance. NaN where the query gave no answer.
    """
    if len(table) == 0:
        return dataclasses.replace(table, depth_upper=np.zeros(0))
    upper = np.zeros(len(table))
    rows = np.flatnonzero(~(table.distance > 0.0) | table.contained | table.undecided)
    exact = _half_space_rows(table, placed)[rows]
    if exact.any():  # the depth of a body's deepest part below a plane is its own: exact
        upper[rows[exact]] = table.depth[rows[exact]]
        rows = rows[~exact]
    if len(rows):
        upper[rows] = _enclosing_depths(table, placed, rows, threads)
    depth = table.depth.copy()
    over = np.isfinite(upper) & (depth > upper)
    depth[over] = upper[over]
    signed = table.signed_distance.copy()
    signed[over] = table.distance[over] - depth[over]
    return dataclasses.replace(table, depth=depth, depth_upper=upper, signed_distance=signed)


def _half_space_rows(table: PairTable, placed: PlacedColliders) -> np.ndarray:
    """Mask of the rows with a half-space's body (an MJCF plane: collider ``plane``)."""
    kinds = placed.colliders.kinds
    if HALF_SPACE_COLLIDER not in kinds:
        return np.zeros(len(table), dtype=bool)
    plane = np.array([kind == HALF_SPACE_COLLIDER for kind in kinds], dtype=bool)
    return plane[table.body_a] | plane[table.body_b]


def _enclosing_sets(
    placed: PlacedColliders, bodies: np.ndarray
) -> tuple[Any, np.ndarray, np.ndarray]:
    """The convex set enclosing each body of ``bodies`` (sorted, unique) as one set with its
    world poses, and each body's shape there (``slot``, indexed by body): a body of one part
    is that part of the colliders' own set, at its pose (nothing copied); a body of several
    parts is the hull of its parts' points (:func:`_part_points`), at the identity, after
    them."""
    from meshcol.collision.shapes import ConvexSet

    colliders = placed.colliders
    offsets = colliders.body_part_offsets
    slot = np.full(len(offsets) - 1, -1, dtype=np.int64)
    single = offsets[bodies + 1] - offsets[bodies] == 1
    slot[bodies[single]] = offsets[bodies[single]]
    several = bodies[~single].tolist()
    if not several:
        return colliders.shapes, placed.part_poses, slot
    hulls = ConvexSet.from_vertices(
        [
            np.concatenate(
                [
                    _part_points(colliders.shapes, p, placed.part_poses[p])
                    for p in range(offsets[body], offsets[body + 1])
                ]
            )
            for body in several
        ]
    )
    count = len(colliders.shapes)
    slot[several] = count + np.arange(len(several))
    shapes = ConvexSet.concatenate(colliders.shapes, hulls)
    poses = np.concatenate([placed.part_poses, np.tile(np.eye(4), (len(several), 1, 1))])
    return shapes, np.ascontiguousarray(poses), slot


def _part_points(shapes: Any, part: int, pose: np.ndarray) -> np.ndarray:
    """World points whose hull encloses part ``part``: its hull vertices, or its primitive's
    bounding box corners."""
    kind = int(shapes.kinds[part])
    if kind == 0:
        local = shapes.vertices[shapes.offsets[part] : shapes.offsets[part + 1]]
    else:
        r, h = shapes.params[part, 0], shapes.params[part, 1]
        half = {
            _SPHERE: (r, r, r),
            _BOX: tuple(shapes.params[part, :3]),
            _CAPSULE: (r, r, h + r),
            _CYLINDER: (r, r, h),
            _ELLIPSOID: tuple(shapes.params[part, :3]),
        }[kind]
        signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
        local = signs * np.asarray(half, dtype=np.float64)
    return local @ pose[:3, :3].T + pose[:3, 3]


def support(shapes: Any, index: int, pose: np.ndarray, direction: np.ndarray) -> float:
    """``max over x in shape of x . direction``, shape ``index`` of ``shapes`` at the world
    ``pose`` (its support function; exact for primitives, over the hull vertices for a
    polytope). One shape; :func:`supports` is the same for many at once, to the bit."""
    index_array = np.array([index], dtype=np.int64)
    poses = np.asarray(pose, dtype=np.float64).reshape(1, 4, 4)
    return float(supports(shapes, index_array, poses, np.reshape(direction, (1, 3)))[0])


def supports(
    shapes: Any, index: np.ndarray, poses: np.ndarray, directions: np.ndarray
) -> np.ndarray:
    """The support function of shape ``index[k]`` at ``poses[k]`` along ``directions[k]``,
    for every k: arrays in, arrays out, no loop over shapes (polytopes: one stacked product
    per vertex count).

    Each value is what the one-shape arithmetic gives (``R.T @ d``, ``t @ d``, then the
    shape's formula), to the bit: the stacked products make the same BLAS call per item as
    the one-shape products (``tests/test_depth_bounds.py`` holds them to it).
    """
    k = len(index)
    out = np.empty(k)
    if k == 0:
        return out
    rotation_t = poses[:, :3, :3].transpose(0, 2, 1)
    local = np.matmul(rotation_t, directions[:, :, None])[:, :, 0]
    base = np.matmul(poses[:, None, :3, 3], directions[:, :, None])[:, 0, 0]
    kind = shapes.kinds[index].astype(np.int64)
    p = shapes.params[index]
    length = np.sqrt(np.matmul(local[:, None, :], local[:, :, None])[:, 0, 0])
    along = np.abs(local[:, 2])
    box = np.matmul(np.abs(local)[:, None, :], p[:, :3, None])[:, 0, 0]
    radial = np.sqrt(np.maximum(length * length - along * along, 0.0))
    stretched = local * p[:, :3]  # an ellipsoid's: |A R^T d|
    ellipsoid = np.sqrt(np.matmul(stretched[:, None, :], stretched[:, :, None])[:, 0, 0])
    primitive = np.select(
        [kind == _SPHERE, kind == _BOX, kind == _CAPSULE, kind == _ELLIPSOID],
        [
            base + p[:, 0] * length,
            base + box,
            base + p[:, 1] * along + p[:, 0] * length,
            base + ellipsoid,
        ],
        base + p[:, 1] * along + p[:, 0] * radial,
    )
    out[:] = primitive
    half_space = np.flatnonzero(kind == _HALFSPACE)
    if len(half_space):  # bounded only along its normal (local +z): its plane's height there
        sideways = np.hypot(local[half_space, 0], local[half_space, 1])
        normal = (local[half_space, 2] > 0.0) & (sideways <= _NORMAL_SLACK * length[half_space])
        out[half_space] = np.where(normal, base[half_space], np.inf)
    polytope = np.flatnonzero(kind == 0)
    if len(polytope):
        out[polytope] = base[polytope] + _vertex_maxima(shapes, index[polytope], local[polytope])
    return out


def _vertex_maxima(shapes: Any, index: np.ndarray, local: np.ndarray) -> np.ndarray:
    """``max(vertices_h @ local[k])`` of each polytope ``h = index[k]``, grouped by vertex
    count (NaN for one without vertices: its queries never answer, so none asks)."""
    starts = shapes.offsets[index]
    counts = shapes.offsets[index + 1] - starts
    out = np.empty(len(index))
    for count in np.unique(counts).tolist():
        group = np.flatnonzero(counts == count)
        rows = starts[group][:, None] + np.arange(count)
        products = np.matmul(shapes.vertices[rows], local[group][:, :, None])[:, :, 0]
        out[group] = products.max(axis=1) if count else np.nan
    return out


def _penetrations(
    table: PairTable,
    rows: np.ndarray,
    single: np.ndarray,
    shapes: Any,
    poses: np.ndarray,
    pairs: np.ndarray,
    threads: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Depth, normal and status of the enclosing sets' penetration query of each row. Two
    bodies of one part each (``single``) are enclosed by those parts, the very pair the narrow phase
    measured (``PairTable.convex_*``): its answer is taken, the same bits a second query
    would give (a query's answer depends on its shapes and poses alone); the others are
    measured in one batch."""
    from meshcol.collision.narrowphase import penetration_batch

    reuse = single & (table.convex_status[rows] >= 0)
    depth = table.convex_depth[rows].copy()
    normal = table.convex_normal[rows].copy()
    status = table.convex_status[rows].copy()
    fresh = np.flatnonzero(~reuse)
    if len(fresh):
        found = penetration_batch(shapes, poses, pairs[fresh], threads=threads)
        depth[fresh], normal[fresh], status[fresh] = found.depth, found.normal, found.status
    return depth, normal, status


def _enclosing_depths(
    table: PairTable, placed: PlacedColliders, rows: np.ndarray, threads: int
) -> np.ndarray:
    """The enclosing sets' penetration depth of each row, as the support overlap along the
    normal EPA / SAT finds (NaN when the query gave no answer)."""
    a, b = table.body_a[rows], table.body_b[rows]
    used = np.zeros(len(placed.body_min), dtype=bool)  # the bodies of the rows, sorted, once:
    used[a] = used[b] = True  # np.unique's hash of 500,000 indices costs 0.4 s, this 5 ms
    shapes, poses, slot = _enclosing_sets(placed, np.flatnonzero(used))
    pairs = np.stack([slot[a], slot[b]], axis=1)
    counts = np.diff(placed.colliders.body_part_offsets)
    single = (counts[a] == 1) & (counts[b] == 1)
    depth, normal, status = _penetrations(table, rows, single, shapes, poses, pairs, threads)
    out = np.full(len(rows), np.nan)
    answered = ~np.isin(status, NO_ANSWER)
    deep = answered & (depth > 0.0) & np.isfinite(normal).all(axis=1)
    out[answered & ~deep & (depth == 0.0)] = 0.0
    k = np.flatnonzero(deep)
    i, j = pairs[k, 0], pairs[k, 1]
    # moving b by t * normal separates the sets once t >= h_a(n) + h_b(-n)
    overlap = supports(shapes, i, poses[i], normal[k]) + supports(shapes, j, poses[j], -normal[k])
    # max(overlap, depth, 0.0) as Python's max: NaN only when the overlap is NaN
    out[k] = np.where(np.isnan(overlap), np.nan, np.maximum(np.maximum(overlap, depth[k]), 0.0))
    return out
