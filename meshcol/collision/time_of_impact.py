"""Continuous collision: time of impact of moving convex shapes.

Motion, fixed once for the whole module (the C++ core, ``cpp/include/meshcol/toi.hpp``,
implements it):

- Each body moves from its start pose to its end pose over ``t`` in [0, 1] by a screw: a
  PIVOT (a world point; the body's local origin unless given) moves linearly, and the body
  turns about it at constant angular velocity ``w = angle * axis`` (a fixed world axis), by
  ``angle * t`` radians at time ``t``. The ``angle`` may be of any size: a spin of 1.5 or 4
  turns is that spin, in the time of impact, the motion bound and the poses reported.
- The turn is given as a world rotation vector ``rotation = angle * axis`` (``rotations`` /
  :class:`meshcol.types.Spin`; a manifest's ``angular_velocity * duration``), which must take
  the start rotation to the end rotation. Without one, the body turns the SHORTEST way from
  its start to its end rotation (angle in [0, pi]) about its local origin: an end pose alone
  cannot say how many turns lie between. :func:`interpolate_pose` gives the pose at any ``t``.
- ``time_of_impact`` is the fraction of the motion in [0, 1]; ``time = time_of_impact * duration`` when the scene
  gives a duration in seconds.
- ``tolerance`` is an absolute distance (world units): the shapes are in contact when their
  distance is at most ``tolerance``.

Statuses (:class:`meshcol.types.TimeOfImpactStatus`) and what each guarantees:

- ``HIT``: the distance at ``time_of_impact`` is <= tolerance, and the shapes do not touch before ``time_of_impact``
  (``time_of_impact`` is a lower bound of the first instant of contact, within about
  ``tolerance / closing speed`` of it).
- ``SEPARATED``: the distance stays above ``tolerance / 2`` during the whole motion. A pair that
  touches during the motion is never ``SEPARATED`` (a closest approach between
  ``tolerance / 2`` and ``tolerance`` may be reported either way).
- ``OVERLAPPED_AT_START``: within ``tolerance`` at ``t = 0``; ``time_of_impact = 0``.
- ``FAILED``: the iteration cap was reached; ``time_of_impact`` is the last safe lower bound.
- ``INVALID_INPUT``: NaN/inf coordinates, an empty shape, a non-rigid pose, a turn that does
  not take the start rotation to the end rotation, or lengths beyond a double (a path or a
  radius over 1.8e308, a tolerance under 2^-1074 of the pair's size).

Any magnitude: a pair whose lengths leave [2^-100, 2^100] is moved and scaled by a power of two
(exact) for the query, as in :mod:`meshcol.collision.narrowphase`.

Results give ``point`` (world, the midpoint of the closest points at ``time_of_impact``) and ``normal``
(world, unit, from a towards b at ``time_of_impact``; zero when overlapping at the start).

Notes
-----
Two spheres: closed form (the centre distance is the square root of a quadratic in t).
Translation only (neither body turns, or only spheres about their centres do): GJK ray cast on the Minkowski
difference (van den Bergen 2004), sphere and capsule radii as margins. Otherwise: conservative
advancement (Mirtich 1996; Zhang et al. 2006) with a rigorous bound on the closing speed of the
separating slab: relative linear speed of the pivots along the normal plus, per body,
``angle * |normal x axis| * lever arm`` (the largest distance of a point from the axis line
through the pivot, a swept ball's radius excluded; the whole angle, any size); each
step aims at ``tolerance / 2`` so a contact is never stepped over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from meshcol._native import core, defaults
from meshcol.collision.arrays import as_pairs, as_pose, as_poses, as_vectors
from meshcol.collision.narrowphase import body_pose, native_shape
from meshcol.collision.shapes import ConvexSet, ShapeKind, as_convex_set
from meshcol.types import Body, Spin, TimeOfImpactStatus

__all__ = [
    "contact_tolerance",
    "TimeOfImpactResult",
    "TimeOfImpactBatch",
    "interpolate_pose",
    "shortest_rotation",
    "swept_aabbs",
    "time_of_impact",
    "time_of_impact_batch",
]


@dataclass(frozen=True)
class TimeOfImpactResult:
    """Time of impact of one pair (see the module docstring for the guarantees).

    Attributes
    ----------
    status : TimeOfImpactStatus
    time_of_impact : float or None
        Fraction of the motion in [0, 1]; None when ``SEPARATED`` or ``INVALID_INPUT``.
    point : (3,) float64
        World, midpoint of the closest points at ``time_of_impact`` (NaN when there is none).
    normal : (3,) float64
        World, unit, from a towards b at ``time_of_impact`` (zero when overlapping at the start).
    iterations : int
        Cast or advancement steps.
    """

    status: TimeOfImpactStatus
    time_of_impact: float | None
    point: np.ndarray
    normal: np.ndarray
    iterations: int


@dataclass(frozen=True)
class TimeOfImpactBatch:
    """Per-pair times of impact, in pair order.

    Attributes
    ----------
    time_of_impact : (P,) float64
        Fraction of the motion in [0, 1]; NaN for ``SEPARATED`` and ``INVALID_INPUT`` pairs.
    point : (P, 3) float64
        World contact point at ``time_of_impact`` (midpoint of the closest points).
    normal : (P, 3) float64
        World unit normal from a towards b at ``time_of_impact``.
    iterations : (P,) int32
    status : (P,) int8
        :class:`meshcol.types.TimeOfImpactStatus` values.
    """

    time_of_impact: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


def contact_tolerance(tolerance: float | None) -> float:
    """The contact distance of a time-of-impact query: ``tolerance`` checked, or the default."""
    if tolerance is None:
        return float(defaults.toi_tolerance)
    value = float(tolerance)
    if not np.isfinite(value) or value <= 0.0:
        raise ValueError(f"tolerance must be finite and > 0, got {tolerance}")
    return value


def interpolate_pose(
    start_pose: Any, end_pose: Any, t: Any, *, rotation: Any = None, pivot: Any = None
) -> np.ndarray:
    """Pose at time ``t`` of the motion from ``start_pose`` to ``end_pose``.

    Parameters
    ----------
    start_pose, end_pose : (4, 4) or (N, 4, 4) float
        Rigid world-from-local poses, row-major.
    t : float or (N,) float
        Fractions of the motion (0: start, 1: end).
    rotation : (3,) or (N, 3) float, optional
        World rotation vectors of the turns (axis x angle, any angle), which must take each
        start rotation to its end rotation; default: the shortest rotation.
    pivot : (3,) or (N, 3) float, optional
        World points the bodies turn about, at the start; default: their local origins.

    Returns
    -------
    (4, 4) or (N, 4, 4) float64
        The pivot moved linearly in ``t``, the body turned about it by ``t`` times the turn.

    Raises
    ------
    ValueError
        A pose that is not rigid, a turn that does not reach the end rotation, a ``t`` that is
        not finite, or mismatched lengths.
    """
    start = np.asarray(start_pose, dtype=np.float64)
    single = start.ndim == 2
    start = np.ascontiguousarray(start.reshape(-1, 4, 4))
    end = np.ascontiguousarray(np.asarray(end_pose, dtype=np.float64).reshape(-1, 4, 4))
    times = np.ascontiguousarray(
        np.broadcast_to(np.asarray(t, dtype=np.float64).reshape(-1), (len(start),))
    )
    rotations = as_vectors(rotation, len(start), "rotation")
    pivots = as_vectors(pivot, len(start), "pivot")
    out = core.interpolate_poses(start, end, times, rotations, pivots)
    return out[0] if single else out


def shortest_rotation(start_pose: Any, end_pose: Any) -> np.ndarray:
    """World rotation vector of the shortest turn from a start to an end pose.

    Parameters
    ----------
    start_pose, end_pose : (4, 4) or (N, 4, 4) float
        Rigid world-from-local poses.

    Returns
    -------
    (3,) or (N, 3) float64
        ``angle * axis``, angle in [0, pi], with ``R_end = Rot(axis, angle) @ R_start``: the
        turn a motion takes when none is given.
    """
    start = np.asarray(start_pose, dtype=np.float64)
    single = start.ndim == 2
    start = np.ascontiguousarray(start.reshape(-1, 4, 4))
    end = np.ascontiguousarray(np.asarray(end_pose, dtype=np.float64).reshape(-1, 4, 4))
    if end.shape != start.shape:
        raise ValueError(f"end_pose must be {start.shape}, got {end.shape}")
    out = core.shortest_rotations(start, end)
    return out[0] if single else out


def time_of_impact_batch(
    shapes: ConvexSet,
    start_poses: Any,
    end_poses: Any,
    pairs: Any,
    *,
    rotations: Any = None,
    pivots: Any = None,
    tolerance: float | None = None,
    max_iterations: int | None = None,
    threads: int = 0,
) -> TimeOfImpactBatch:
    """Time of impact of each pair of moving shapes.

    Parameters
    ----------
    shapes : ConvexSet
    start_poses, end_poses : (H, 4, 4) float
        Rigid world-from-local poses of every shape at the start and at the end of the
        motion, row-major.
    pairs : (P, 2) int
        Indices into ``shapes``.
    rotations : (H, 3) float, optional
        World rotation vector of each shape's turn over the motion (axis x angle in radians, any
        angle), which must take its start rotation to its end rotation (else its pairs are
        ``INVALID_INPUT``). Default: the shortest rotation from start to end (at most pi).
    pivots : (H, 3) float, optional
        World point each shape turns about, at the start (default: its local origin).
    tolerance : float, optional
        Absolute contact distance (default ``meshcol._native.defaults.toi_tolerance``).
    max_iterations : int, optional
        Cap on cast/advancement steps per pair (default
        ``meshcol._native.defaults.toi_max_iterations``); a pair reaching it is ``FAILED``.
    threads : int
        Worker threads; 0 uses all cores.

    Returns
    -------
    TimeOfImpactBatch
        One array per field, in pair order.

    Raises
    ------
    ValueError
        Wrong array shapes, an index out of range, or a tolerance that is not > 0.

    Notes
    -----
    See the module docstring for the motion model, the guarantees and the algorithms.
    """
    # One native call reads arguments already in the core's form in place and builds the
    # result (None: an argument to convert here, with its message, and ask again), as the
    # narrow phase's batches do.
    tol = contact_tolerance(tolerance)
    cap = int(defaults.toi_max_iterations if max_iterations is None else max_iterations)
    threads = int(threads)
    try:
        packed = shapes._core
    except AttributeError:
        as_convex_set(shapes)  # TypeError for the wrong container
        raise
    args = (start_poses, end_poses, pairs, rotations, pivots)
    result = core.time_of_impact_object(packed, *args, tol, cap, threads, TimeOfImpactBatch)
    if result is None:
        h = len(shapes)
        start = as_poses(start_poses, h, "start_poses")
        end = as_poses(end_poses, h, "end_poses")
        if start is None or end is None:
            raise ValueError("start_poses and end_poses are required")
        args = (
            start,
            end,
            as_pairs(pairs, h),
            as_vectors(rotations, h, "rotations"),
            as_vectors(pivots, h, "pivots"),
        )
        result = core.time_of_impact_object(packed, *args, tol, cap, threads, TimeOfImpactBatch)
        if result is None:  # the converters give the core's form: never declined twice
            raise AssertionError("the core declined converted arguments")
    return cast(TimeOfImpactBatch, result)


def time_of_impact(
    a: Any,
    b: Any,
    start_pose_a: Any,
    end_pose_a: Any,
    start_pose_b: Any,
    end_pose_b: Any,
    *,
    spin_a: Spin | None = None,
    spin_b: Spin | None = None,
    tolerance: float | None = None,
    max_iterations: int | None = None,
) -> TimeOfImpactResult:
    """Time of impact of two convex shapes, each moving from a start to an end pose.

    Parameters
    ----------
    a, b : Sphere, Box, Capsule, Cylinder, Ellipsoid, trimesh.Trimesh, Body or (n, 3) float
        Shapes in their local frames (meshes and point sets by their convex hull).
    start_pose_a, end_pose_a, start_pose_b, end_pose_b : (4, 4) float or None
        Rigid world-from-local poses (None: a Body's own pose and end pose, else identity).
    spin_a, spin_b : Spin, optional
        How each shape turns (any angle, about a pivot); default: a Body's own ``spin`` when it
        gives the end pose, else the shortest rotation about the local origin.
    tolerance, max_iterations
        As :func:`time_of_impact_batch`.

    Returns
    -------
    TimeOfImpactResult
    """
    if spin_a is None and spin_b is None:
        result = _native_pair(
            (a, start_pose_a, end_pose_a), (b, start_pose_b, end_pose_b), tolerance, max_iterations
        )
        if result is not None:
            return result
    shapes = ConvexSet.from_shapes([a, b], names=("a", "b"))
    starts, ends = _pair_poses(
        (a, start_pose_a, end_pose_a, "a"), (b, start_pose_b, end_pose_b, "b")
    )
    spins = (_spin_of(a, spin_a, end_pose_a), _spin_of(b, spin_b, end_pose_b))
    rotations, pivots = _turns(starts, ends, spins)
    batch = time_of_impact_batch(
        shapes,
        starts,
        ends,
        np.array([[0, 1]]),
        rotations=rotations,
        pivots=pivots,
        tolerance=tolerance,
        max_iterations=max_iterations,
        threads=1,
    )
    return _first_result(batch)


# Status members by value, for the core to hand out (calling the enum costs more than a query).
_STATUSES = tuple(TimeOfImpactStatus(v) for v in range(len(TimeOfImpactStatus)))
_INT_MAX = 2**31 - 1  # the core's iteration cap is a C int


def _native_pair(
    move_a: tuple[Any, Any, Any], move_b: tuple[Any, Any, Any], tolerance: Any, max_iterations: Any
) -> TimeOfImpactResult | None:
    """The time of impact made by one native call on two shapes, each moving (shape, start
    pose, end pose) the shortest way (no spin), packed as :meth:`ConvexSet.from_shapes` packs
    them; None for a Body that spins, or a shape, pose or option in a form the core does not
    read (the caller packs a set, whose messages then apply, in their order)."""
    args: list[Any] = []
    for (shape, start, end), name in ((move_a, "a"), (move_b, "b")):
        if end is None and isinstance(shape, Body) and shape.spin is not None:
            return None
        native = native_shape(shape, name)
        if native is None:
            return None
        args += [*native, body_pose(shape) if start is None else start]
        args.append(body_pose(shape, True) if end is None else end)
    # a tolerance or cap in another form is checked by the packing path, after the poses
    if tolerance is None:
        tolerance = defaults.toi_tolerance
    elif type(tolerance) is not float or not 0.0 < tolerance < math.inf:
        return None
    if max_iterations is None:
        max_iterations = defaults.toi_max_iterations
    elif type(max_iterations) is not int or not 1 <= max_iterations <= _INT_MAX:
        return None
    kind_a, a, start_a, end_a, kind_b, b, start_b, end_b = args
    result = core.shape_pair_toi_object(
        kind_a,
        a,
        kind_b,
        b,
        start_a,
        end_a,
        start_b,
        end_b,
        tolerance,
        max_iterations,
        TimeOfImpactResult,
        _STATUSES,
    )
    return cast("TimeOfImpactResult | None", result)


def _pair_poses(*moves: tuple[Any, Any, Any, str]) -> tuple[np.ndarray, np.ndarray]:
    """The (2, 4, 4) start and end poses of two moving shapes, checked in argument order.

    Each move is (shape, start pose, end pose, name); a pose that is None is the shape's own
    (a Body's ``pose`` or ``end_pose``), else the identity.
    """
    starts, ends = [], []
    for shape, start, end, name in moves:
        starts.append(
            as_pose(body_pose(shape, False) if start is None else start, f"start_pose_{name}")
        )
        ends.append(as_pose(body_pose(shape, True) if end is None else end, f"end_pose_{name}"))
    return np.stack(starts), np.stack(ends)


def _spin_of(shape: Any, spin: Spin | None, end_pose: Any) -> Spin | None:
    """The spin a shape turns by: the one given, else a Body's own when it gives the end pose."""
    if spin is not None or end_pose is not None or not isinstance(shape, Body):
        return spin
    return shape.spin


def _turns(
    starts: np.ndarray, ends: np.ndarray, spins: tuple[Spin | None, Spin | None]
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The (2, 3) rotation vectors and pivots of the turns, or (None, None) without a spin.

    A shape without a spin (or a spin without a rotation or a pivot) takes the shortest
    rotation from its start to its end pose, about its local origin.
    """
    if all(spin is None for spin in spins):
        return None, None
    shortest = shortest_rotation(starts, ends)
    rotations = np.stack(
        [
            shortest[k] if spin is None or spin.rotation is None else spin.rotation
            for k, spin in enumerate(spins)
        ]
    )
    pivots = np.stack(
        [
            starts[k, :3, 3] if spin is None or spin.pivot is None else spin.pivot
            for k, spin in enumerate(spins)
        ]
    )
    return rotations, pivots


def _first_result(batch: TimeOfImpactBatch) -> TimeOfImpactResult:
    """The result of the batch's one pair."""
    fraction = float(batch.time_of_impact[0])
    return TimeOfImpactResult(
        TimeOfImpactStatus(int(batch.status[0])),
        None if np.isnan(fraction) else fraction,
        batch.point[0],
        batch.normal[0],
        int(batch.iterations[0]),
    )


def swept_aabbs(
    cs: ConvexSet,
    start_poses: np.ndarray,
    end_poses: np.ndarray,
    threads: int = 0,
    *,
    rotations: Any = None,
    pivots: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Conservative world AABBs of shapes over their whole motion.

    Parameters
    ----------
    cs : ConvexSet
    start_poses, end_poses : (H, 4, 4) float
    threads : int
    rotations, pivots : (H, 3) float, optional
        The turns and pivots, as :func:`time_of_impact_batch`.

    Returns
    -------
    aabb_min, aabb_max : (H, 3) float64

    Notes
    -----
    A shape that does not turn (or a sphere turning about its centre) sweeps the union of its
    start and end AABBs exactly (an AABB moves rigidly under translation). A turning shape stays
    inside the ball of its bounding radius about its pivot (radius about the local origin plus
    the origin's distance from the pivot), whose centre moves linearly: the AABB of that swept
    ball (widened by the pivot offset, as the pivot's end is known only to within it), which
    encloses a spin of any angle. (The union of the start and end AABBs alone is NOT
    conservative under rotation: a bar turning by 90 degrees, or by a full turn, sweeps corners
    outside both.)
    """
    start = np.ascontiguousarray(start_poses, dtype=np.float64)
    end = np.ascontiguousarray(end_poses, dtype=np.float64)
    h = len(start)
    lo0, hi0 = cs.aabbs(start, threads=threads)
    lo1, hi1 = cs.aabbs(end, threads=threads)
    lo, hi = np.minimum(lo0, lo1), np.maximum(hi0, hi1)
    turns = as_vectors(rotations, h, "rotations")
    centres = as_vectors(pivots, h, "pivots")
    if turns is None:
        turning = np.any(start[:, :3, :3] != end[:, :3, :3], axis=(1, 2))
    else:
        turning = np.any(turns != 0.0, axis=1)
    pivot = start[:, :3, 3] if centres is None else centres
    offset = np.linalg.norm(start[:, :3, 3] - pivot, axis=1)
    turning &= (cs.kinds != ShapeKind.SPHERE) | (offset > 0.0)
    if np.any(turning):
        # The body stays within r + offset of its pivot c(t) = c0 + t v, and c0, c1 lie within
        # `offset` of the local origin's start and end T0, T1 (c1 = T1 - Rot(turn) (T0 - c0)):
        # every point of every instant is within r + 2 offset of the segment T0 T1.
        r = (cs._core.bounding_radii(threads)[turning] + 2.0 * offset[turning])[:, None]
        t0, t1 = start[turning, :3, 3], end[turning, :3, 3]
        lo[turning] = np.minimum(t0, t1) - r
        hi[turning] = np.maximum(t0, t1) + r
    return lo, hi
