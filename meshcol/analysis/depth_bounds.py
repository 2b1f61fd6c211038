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
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from meshcol.analysis.pairs import NO_ANSWER, PairTable, PlacedColliders

__all__ = ["depth_bounds", "support"]

_SPHERE, _BOX, _CAPSULE, _CYLINDER = 1, 2, 3, 4


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
    if len(rows):
        upper[rows] = _enclosing_depths(table, placed, rows, threads)
    depth = table.depth.copy()
    over = np.isfinite(upper) & (depth > upper)
    depth[over] = upper[over]
    signed = table.signed_distance.copy()
    signed[over] = table.distance[over] - depth[over]
    return dataclasses.replace(table, depth=depth, depth_upper=upper, signed_distance=signed)


class _Enclosing:
    """The convex set enclosing each body, built once per body the rows involve."""

    def __init__(self, placed: PlacedColliders) -> None:
        self.placed = placed
        self.colliders = placed.colliders
        self.made: dict[int, tuple[Any, np.ndarray]] = {}

    def of(self, body: int) -> tuple[Any, np.ndarray]:
        """(ConvexSet of one shape, its world pose) enclosing ``body``."""
        if body not in self.made:
            self.made[body] = self._make(body)
        return self.made[body]

    def _make(self, body: int) -> tuple[Any, np.ndarray]:
        from meshcol.collision.shapes import ConvexSet

        shapes = self.colliders.shapes
        lo, hi = self.colliders.body_part_offsets[body : body + 2].tolist()
        if hi - lo == 1:
            return shapes.take([lo]), self.placed.part_poses[lo]
        points = np.concatenate(
            [_part_points(shapes, p, self.placed.part_poses[p]) for p in range(lo, hi)]
        )
        return ConvexSet.from_vertices([points]), np.eye(4)


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
        }[kind]
        signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
        local = signs * np.asarray(half, dtype=np.float64)
    return local @ pose[:3, :3].T + pose[:3, 3]


def support(shapes: Any, index: int, pose: np.ndarray, direction: np.ndarray) -> float:
    """``max over x in shape of x . direction``, shape ``index`` of ``shapes`` at the world
    ``pose`` (its support function; exact for primitives, over the hull vertices for a
    polytope)."""
    rotation, origin = pose[:3, :3], pose[:3, 3]
    local = rotation.T @ direction
    base = float(origin @ direction)
    kind = int(shapes.kinds[index])
    p = shapes.params[index]
    if kind == 0:
        vertices = shapes.vertices[shapes.offsets[index] : shapes.offsets[index + 1]]
        return base + float((vertices @ local).max())
    length = float(np.linalg.norm(local))
    along = abs(float(local[2]))
    if kind == _SPHERE:
        return base + p[0] * length
    if kind == _BOX:
        return base + float(np.abs(local[:3]) @ p[:3])
    if kind == _CAPSULE:
        return base + p[1] * along + p[0] * length
    radial = float(np.sqrt(max(length * length - along * along, 0.0)))
    return base + p[1] * along + p[0] * radial


def _enclosing_depths(
    table: PairTable, placed: PlacedColliders, rows: np.ndarray, threads: int
) -> np.ndarray:
    """The enclosing sets' penetration depth of each row, as the support overlap along the
    normal EPA / SAT finds (NaN when the query gave no answer)."""
    from meshcol.collision.narrowphase import penetration_batch
    from meshcol.collision.shapes import ConvexSet

    enclosing = _Enclosing(placed)
    bodies = np.unique(np.concatenate([table.body_a[rows], table.body_b[rows]])).tolist()
    slot = {body: k for k, body in enumerate(bodies)}
    # One-part bodies are their part: taken together, one take per run of them (a take per
    # body copied the whole set's offsets each time: quadratic in the bodies, minutes for a
    # 100,000-node glTF); bodies of several parts get their enclosing hull.
    offsets = placed.colliders.body_part_offsets
    pieces: list[Any] = []
    pose_list: list[np.ndarray] = []
    run: list[int] = []
    for body in bodies:
        lo, hi = int(offsets[body]), int(offsets[body + 1])
        if hi - lo == 1:
            run.append(lo)
            pose_list.append(placed.part_poses[lo])
            continue
        if run:
            pieces.append(placed.colliders.shapes.take(run))
            run = []
        made, pose = enclosing.of(body)
        pieces.append(made)
        pose_list.append(pose)
    if run:
        pieces.append(placed.colliders.shapes.take(run))
    shapes = pieces[0] if len(pieces) == 1 else ConvexSet.concatenate(*pieces)
    poses = np.ascontiguousarray(np.stack(pose_list))
    pairs = np.array(
        [
            [slot[a], slot[b]]
            for a, b in zip(table.body_a[rows].tolist(), table.body_b[rows].tolist())
        ],
        dtype=np.int64,
    ).reshape(-1, 2)
    found = penetration_batch(shapes, poses, pairs, threads=threads)
    out = np.full(len(rows), np.nan)
    for k, (i, j) in enumerate(pairs.tolist()):
        if int(found.status[k]) in NO_ANSWER:
            continue
        normal = found.normal[k]
        if not found.depth[k] > 0.0 or not np.all(np.isfinite(normal)):
            out[k] = 0.0 if found.depth[k] == 0.0 else np.nan
            continue
        # moving b by t * normal separates the sets once t >= h_a(n) + h_b(-n)
        overlap = support(shapes, i, poses[i], normal) + support(shapes, j, poses[j], -normal)
        out[k] = max(overlap, float(found.depth[k]), 0.0)
    return out
