"""Narrow phase: distance, penetration and intersection of convex shapes.

Frames and signs (fixed once, here, for every function of this module):

- Each shape is given in its own local frame; a pose is a rigid row-major 4x4 matrix mapping
  local to world (``world = R @ local + t``); ``None`` means identity.
- Every returned point and normal is in the world frame.
- ``distance >= 0`` (0 when the shapes touch or overlap); ``depth >= 0`` (0 when they are
  apart); ``signed_distance = distance - depth``.
- ``normal`` is a unit vector from shape ``a`` towards shape ``b``. When separated,
  ``point_b - point_a = distance * normal``; when overlapping, moving ``b`` by
  ``depth * normal`` brings the shapes into contact and ``point_a - point_b = depth * normal``
  (``point_a`` is the deepest point of ``a`` inside ``b`` and vice versa).
- Touching counts as intersecting. Two shapes closer than ``defaults.contact_tolerance``
  times the pair's length scale (bounding radii plus centre distance) touch.
- Any magnitude a double holds: a pair whose lengths leave [2^-100, 2^100] (1e-30..1e30) is
  moved to a's origin and scaled by a power of two before the query and back after it (exact),
  so a sphere 1e300 from a box is 1e300 away. An answer beyond the largest double (shapes near
  +-1e308) gets ``Status.OUT_OF_RANGE``, never a number taken for the answer.

Shapes are packed into a :class:`ConvexSet` (arrays, built once) and the ``*_batch`` functions
query (P, 2) index pairs in one native call (GIL released, threads over pairs). The
single-pair functions (:func:`distance`, ...) run the same code on a two-shape set, packed
by one native call that also builds the result (a point set's or mesh's hull is built per
call); shapes or poses in other forms are packed by :meth:`ConvexSet.from_shapes`.

Notes
-----
Distance is GJK (van den Bergen 2003) with Ericson's (2004) Voronoi-region closest-point
subalgorithm, in shape ``a``'s frame, ending exactly on polytopes when a support point
repeats. Spheres and capsules are a point or segment swept by a radius, added exactly.
Penetration is EPA from GJK's final simplex with silhouette expansion (van den Bergen 2003),
verified, and replaced when they disagree, by an exact separating-axis test over face normals
and edge-edge cross products for boxes and small polytopes (Ericson 2004, sec. 5.2.1).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, TypeVar, cast

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_pairs, as_pose, as_poses
from meshcol.collision.shapes import ConvexSet, ShapeKind, _item, as_convex_set
from meshcol.types import Body, Box, Capsule, Cylinder, Ellipsoid, HalfSpace, Sphere, Status

__all__ = [
    "DistanceBatch",
    "PenetrationBatch",
    "SignedDistanceBatch",
    "IntersectsBatch",
    "DistanceResult",
    "PenetrationResult",
    "SignedDistanceResult",
    "distance",
    "penetration",
    "intersects",
    "signed_distance",
    "distance_batch",
    "penetration_batch",
    "intersects_batch",
    "signed_distance_batch",
]


# ---------------------------------------------------------------------------------------------
# Packing


# ---------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class DistanceBatch:
    """Per-pair distances, in pair order.

    Attributes
    ----------
    distance : (P,) float64
        >= 0; 0 for touching or overlapping pairs.
    point_a, point_b : (P, 3) float64
        World closest points (a common point when overlapping).
    normal : (P, 3) float64
        World unit normal from a to b; zero for overlapping pairs.
    iterations : (P,) int32
    status : (P,) int8
        :class:`meshcol.types.Status` values.
    """

    distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class PenetrationBatch:
    """Per-pair penetration, in pair order.

    Attributes
    ----------
    depth : (P,) float64
        >= 0; 0 for separated pairs.
    normal : (P, 3) float64
        World unit normal from a to b: moving b by ``depth * normal`` brings the pair into
        contact (for separated pairs: the direction of the closest points).
    point_a, point_b : (P, 3) float64
        World witness points, ``point_a - point_b = depth * normal`` (closest points when
        separated).
    iterations : (P,) int32
    status : (P,) int8
    """

    depth: np.ndarray
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class SignedDistanceBatch:
    """Per-pair signed distance (``distance - depth``) with both parts, in pair order.

    Fields as in :class:`DistanceBatch` and :class:`PenetrationBatch`; ``point_a``,
    ``point_b`` and ``normal`` are closest points when separated and witness points when
    overlapping.
    """

    signed_distance: np.ndarray
    distance: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class IntersectsBatch:
    """Per-pair intersection test (touching counts), in pair order.

    Attributes
    ----------
    intersects : (P,) bool
    status : (P,) int8
    """

    intersects: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class DistanceResult:
    """Distance between two shapes (see the module docstring for frames and signs)."""

    distance: float
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    iterations: int
    status: Status


@dataclass(frozen=True)
class PenetrationResult:
    """Penetration of two shapes (see the module docstring for frames and signs)."""

    depth: float
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: int
    status: Status


@dataclass(frozen=True)
class SignedDistanceResult:
    """Signed distance ``distance - depth`` of two shapes, with both parts."""

    signed_distance: float
    distance: float
    depth: float
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: int
    status: Status


# ---------------------------------------------------------------------------------------------
# Batched queries

# The result layouts of the core's query_object (bind_narrowphase.cpp).
_DISTANCE, _PENETRATION, _INTERSECTS, _SIGNED_DISTANCE = 0, 1, 2, 3

_Batch = TypeVar("_Batch", DistanceBatch, PenetrationBatch, SignedDistanceBatch, IntersectsBatch)


def _batch(
    layout: int, result_type: type[_Batch], shapes: Any, poses: Any, pairs: Any, threads: int
) -> _Batch:
    """One batch as ``result_type``, built by the core. Poses and pairs already in the core's
    form (C-contiguous float64 (H, 4, 4) poses; int64 (P, 2) pairs or a list of int pairs) are
    read in place by one native call; anything else is None, then converted and checked here
    (as_poses, as_pairs: their messages) and asked again. A one-pair batch thus costs about its
    query, its arrays and the result object."""
    threads = int(threads)
    try:
        result = shapes._core.query_object(layout, poses, pairs, threads, result_type)
    except AttributeError:
        as_convex_set(shapes)  # TypeError for the wrong container
        raise
    if result is None:
        h = len(shapes)
        result = shapes._core.query_object(
            layout, as_poses(poses, h), as_pairs(pairs, h), threads, result_type
        )
        if result is None:  # as_poses and as_pairs give the core's form: never declined twice
            raise AssertionError("the core declined converted poses and pairs")
    return cast(_Batch, result)


def distance_batch(shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0) -> DistanceBatch:
    """Distance between the shapes of each pair (GJK).

    Parameters
    ----------
    shapes : ConvexSet
    poses : (H, 4, 4) float or None
        Rigid world-from-local poses, row-major (None: identity).
    pairs : (P, 2) int
        Indices into ``shapes``.
    threads : int
        Worker threads; 0 uses all cores.

    Returns
    -------
    DistanceBatch
        One array per field, in pair order; a pair whose shape or pose is invalid (NaN/inf,
        empty, non-rigid) gets ``Status.INVALID_INPUT`` and NaN fields.

    Raises
    ------
    ValueError
        Wrong array shapes, non-integer pairs or an index out of range.
    """
    return _batch(_DISTANCE, DistanceBatch, shapes, poses, pairs, threads)


def penetration_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> PenetrationBatch:
    """Penetration depth of each pair (GJK, then EPA and exact SAT where overlapping).

    Parameters and errors as :func:`distance_batch`. Separated pairs get ``depth = 0`` and
    their closest points.
    """
    return _batch(_PENETRATION, PenetrationBatch, shapes, poses, pairs, threads)


def signed_distance_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> SignedDistanceBatch:
    """Signed distance ``distance - depth`` of each pair: GJK for all, EPA (+ exact SAT for
    small polytopes) only for the overlapping ones.

    Parameters and errors as :func:`distance_batch`.
    """
    return _batch(_SIGNED_DISTANCE, SignedDistanceBatch, shapes, poses, pairs, threads)


def intersects_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> IntersectsBatch:
    """Whether each pair touches or overlaps (boolean GJK with early exit).

    Parameters and errors as :func:`distance_batch`; invalid pairs give ``False`` with
    ``Status.INVALID_INPUT``.
    """
    return _batch(_INTERSECTS, IntersectsBatch, shapes, poses, pairs, threads)


# ---------------------------------------------------------------------------------------------
# Single pairs

_PAIR = np.array([[0, 1]], dtype=np.int64)

# The packed kind of each primitive type (exact types: a subclass takes the packing path).
PRIMITIVE_KINDS: dict[type, int] = {
    Sphere: int(ShapeKind.SPHERE),
    Box: int(ShapeKind.BOX),
    Capsule: int(ShapeKind.CAPSULE),
    Cylinder: int(ShapeKind.CYLINDER),
    Ellipsoid: int(ShapeKind.ELLIPSOID),
    HalfSpace: int(ShapeKind.HALFSPACE),
}
# Status members by value, for the core to hand out (calling the enum costs more than a query).
_STATUSES = tuple(Status(v) for v in range(len(Status)))


def native_shape(shape: Any, name: str) -> tuple[int, Any] | None:
    """(kind, what the core's single-pair calls read) of one shape of a pair: a primitive
    itself or a Body's, else the points of a Body, mesh or array as
    :meth:`ConvexSet.from_shapes` takes them (with its messages, ``name`` in them); None for a
    primitive of a subclass (the packing path reads it)."""
    kind = PRIMITIVE_KINDS.get(type(shape))
    if kind is not None:
        return kind, shape
    if isinstance(shape, Body) and shape.primitive is not None:
        kind = PRIMITIVE_KINDS.get(type(shape.primitive))
        return None if kind is None else (kind, shape.primitive)
    kind, _, points = _item(shape, name)
    return None if points is None else (kind, points)


def _native_pair(
    layout: int, result_type: type | None, a: Any, b: Any, pose_a: Any, pose_b: Any
) -> Any:
    """The single-pair result made by one native call on the two shapes packed as
    :meth:`ConvexSet.from_shapes` packs them (a Body at its own pose when none is given): a
    ``result_type`` (for ``_INTERSECTS`` a bool, and ``result_type`` unused); None when a
    shape or pose is in a form the core does not read (the caller packs a set, whose
    messages then apply)."""
    kind_a, kind_b = PRIMITIVE_KINDS.get(type(a)), PRIMITIVE_KINDS.get(type(b))
    if kind_a is not None and kind_b is not None:  # two primitives, the common call: no more
        return core.shape_pair_object(
            layout, kind_a, a, kind_b, b, pose_a, pose_b, result_type, _STATUSES
        )
    shape_a, shape_b = native_shape(a, "a"), native_shape(b, "b")
    if shape_a is None or shape_b is None:
        return None
    pose_a = body_pose(a) if pose_a is None else pose_a
    pose_b = body_pose(b) if pose_b is None else pose_b
    return core.shape_pair_object(
        layout, *shape_a, *shape_b, pose_a, pose_b, result_type, _STATUSES
    )


def _pair_set(a: Any, b: Any, pose_a: Any, pose_b: Any) -> tuple[ConvexSet, np.ndarray | None]:
    """A two-shape set and its poses; a Body without an explicit pose uses ``Body.pose``."""
    cs = ConvexSet.from_shapes([a, b], names=("a", "b"))
    pose_a = body_pose(a) if pose_a is None else pose_a
    pose_b = body_pose(b) if pose_b is None else pose_b
    if pose_a is None and pose_b is None:
        return cs, None
    return cs, np.stack([as_pose(pose_a, "pose_a"), as_pose(pose_b, "pose_b")])


_Single = TypeVar("_Single", DistanceResult, PenetrationResult, SignedDistanceResult)


def _first_row(batch: Any, result_type: type[_Single]) -> _Single:
    """The single-pair result from row 0 of a batch (the fields have the batch's names)."""
    values: dict[str, Any] = {}
    for f in dataclasses.fields(result_type):
        value = getattr(batch, f.name)[0]
        if f.name == "status":
            values[f.name] = Status(int(value))
        elif f.name == "iterations":
            values[f.name] = int(value)
        else:
            values[f.name] = value if np.ndim(value) else float(value)
    return result_type(**values)


def body_pose(shape: Any, end: bool = False) -> np.ndarray | None:
    """A Body's start (or end) pose, None for any other shape (identity)."""
    if not isinstance(shape, Body):
        return None
    if end and shape.end_pose is not None:
        return shape.end_pose
    return shape.pose


def distance(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> DistanceResult:
    """Distance between two convex shapes.

    Parameters
    ----------
    a, b : Sphere, Box, Capsule, Cylinder, Ellipsoid, trimesh.Trimesh, Body or (n, 3) float
        Shapes in their local frames (meshes and point sets by their convex hull).
    pose_a, pose_b : (4, 4) float or None
        Rigid world-from-local poses. None: a Body's own ``pose``, identity for the rest.

    Returns
    -------
    DistanceResult
        See :class:`DistanceBatch` for the fields.
    """
    result = _native_pair(_DISTANCE, DistanceResult, a, b, pose_a, pose_b)
    if result is not None:
        return cast(DistanceResult, result)
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    return _first_row(distance_batch(cs, poses, _PAIR, threads=1), DistanceResult)


def penetration(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> PenetrationResult:
    """Penetration depth of two convex shapes (0 when apart); arguments as :func:`distance`."""
    result = _native_pair(_PENETRATION, PenetrationResult, a, b, pose_a, pose_b)
    if result is not None:
        return cast(PenetrationResult, result)
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    return _first_row(penetration_batch(cs, poses, _PAIR, threads=1), PenetrationResult)


def signed_distance(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> SignedDistanceResult:
    """Signed distance (distance - depth) of two convex shapes; arguments as
    :func:`distance`."""
    result = _native_pair(_SIGNED_DISTANCE, SignedDistanceResult, a, b, pose_a, pose_b)
    if result is not None:
        return cast(SignedDistanceResult, result)
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    return _first_row(signed_distance_batch(cs, poses, _PAIR, threads=1), SignedDistanceResult)


def intersects(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> bool:
    """True when two convex shapes touch or overlap; arguments as :func:`distance`.

    Raises
    ------
    ValueError
        Also for invalid data (NaN/inf, an empty shape, a non-rigid pose): a bool cannot
        carry a status (the batch form reports ``Status.INVALID_INPUT`` instead).
    """
    hit = _native_pair(_INTERSECTS, None, a, b, pose_a, pose_b)
    if hit is not None:
        return bool(hit)
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    r = intersects_batch(cs, poses, _PAIR, threads=1)
    if r.status[0] == Status.INVALID_INPUT:
        raise ValueError(
            "a, b, pose_a or pose_b: NaN/inf coordinates, an empty shape or a non-rigid pose"
        )
    return bool(r.intersects[0])
