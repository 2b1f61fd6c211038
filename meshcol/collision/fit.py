"""Enclosing primitives of point sets: the sphere, box, cylinder, capsule and ellipsoid that
contain them.

Arrays in, primitives out. The fits run in the C++ core (``cpp/src/fit.cpp``), batched over
point sets (:func:`fit_batch`: one native call, threads over sets, GIL released, a status per
fit); the single-set functions below are that batch of one. Every fit starts from the set's
exact hull (the core's Quickhull) and contains every input point: after the search, each
primitive is grown by the largest amount any input point lies outside it (evaluated in the
fit's own frame), plus a margin of :data:`CONTAINMENT_MARGIN` times the points' extent that
covers the rounding of that evaluation and of a caller's later transform. Enclosing the
vertices of a mesh encloses the mesh, since every primitive is convex.

How near to the smallest each fit is:

- **sphere**: the minimum enclosing ball (Welzl 1991, the randomised incremental algorithm,
  with a fixed seed so that a fit is deterministic), exact up to rounding;
- **box**: near-minimal oriented box. The smallest box has a face flush with a hull face in
  almost every case (O'Rourke 1985 shows it has two adjacent faces flush with hull edges);
  each hull plane normal (the largest :data:`BOX_NORMALS`, by area) is tried as an axis with
  the minimum-area rectangle of the points projected on its plane (rotating calipers,
  Freeman and Shapira 1975; Toussaint 1983), besides the world and principal axes; the best
  few frames are then polished by a local search over rotations;
- **cylinder**: along the best of the box's and the principal axes, then polished; radius by
  the minimum enclosing circle of the points projected across the axis, length by their
  extent along it (exact for its axis);
- **capsule**: along the best axis as for the cylinder; for a radius r the shortest segment
  that keeps every point within r is exact, and r is searched (a grid, then golden-section
  steps) between the projected circle's radius and the radius of a ball centred on the axis.
  The axis polish of both only takes a trial axis better than its best so far, so a trial
  that a lower bound proves no better is not fitted: the cylinder's from the last best
  circle's support points, the capsule's by branch and bound over its radius range (the
  segment's length is convex in the radius); the answer is the full search's, to the bit;
- **ellipsoid**: the minimum-volume enclosing ellipsoid of the hull's vertices, by
  Khachiyan's method (1996) with Kumar and Yildirim's start (2005) and Todd and Yildirim's
  drop steps (2007), run on the vertices mapped to a unit box along their principal axes
  (the problem is affine-equivariant). It stops on a certificate: the dual bound (Todd 2016)
  proves the volume within (1 + :data:`ELLIPSOID_TOLERANCE`) of the minimum's. The ellipsoid
  is then SCALED by the largest Mahalanobis norm of any input point (so the farthest lies on
  its surface, none outside) and gets the margin on each semi-axis: within (1 + tolerance) of
  the minimum volume plus that margin. A flat set's ellipsoid is its plane's minimum
  ellipse, a collinear set's its segment, both as thick as the margin.

:data:`AUTO_SHAPES` are the four ``auto`` chooses among (``meshcol fit --shape auto``):
not every engine has an ellipsoid, so ``auto`` never takes one.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from meshcol.collision.arrays import as_offsets
from meshcol.errors import InvalidMeshError
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, HalfSpace, Primitive, Sphere

__all__ = [
    "AUTO_SHAPES",
    "BOX_NORMALS",
    "CONTAINMENT_MARGIN",
    "ELLIPSOID_TOLERANCE",
    "FIT_SHAPES",
    "FitBatch",
    "FitStatus",
    "PrimitiveFit",
    "enclosing_box",
    "enclosing_capsule",
    "enclosing_cylinder",
    "enclosing_ellipsoid",
    "enclosing_sphere",
    "fit_all",
    "fit_batch",
    "fit_primitive",
    "minimum_ball",
    "primitive_from_params",
    "primitive_volume",
    "signed_distances",
]

#: The primitives :func:`fit_primitive` fits, simplest first (the order ``auto`` prefers);
#: their index is the core's ``FitShape`` code.
FIT_SHAPES = ("sphere", "capsule", "box", "cylinder", "ellipsoid")

#: The primitives ``auto`` chooses among, in its order of preference: every engine has them
#: (an ellipsoid is MuJoCo's, not PhysX's, Unreal's or URDF's).
AUTO_SHAPES = FIT_SHAPES[:4]

#: Relative margin (times the points' extent) every fit keeps beyond its farthest point.
#: Mirrors the core's ``defaults.fit_containment_margin`` (``tests/collision/test_fit.py`` checks).
CONTAINMENT_MARGIN = 1e-9

#: How many hull plane normals (the largest by area) the box search tries as an axis.
#: Mirrors the core's ``defaults.fit_box_normals``.
BOX_NORMALS = 200

#: The ellipsoid's volume is certified within (1 + this) of the minimum enclosing
#: ellipsoid's (before the containment margin). Mirrors ``defaults.fit_ellipsoid_tolerance``.
ELLIPSOID_TOLERANCE = 1e-6


class FitStatus(enum.IntEnum):
    """Outcome of one fit; mirrors ``FitStatus`` in ``cpp/include/meshcol/fit.hpp``."""

    OK = 0  #: fitted; contains every point
    MAX_ITERATIONS = 1  #: fitted and contains every point, but a search cap was hit
    INVALID_INPUT = 2  #: no hull (no points, NaN/inf, overflow): see ``FitBatch.hull_status``
    FAILED = 3  #: the fit's numbers were not finite (never seen): no fit


@dataclass(frozen=True)
class PrimitiveFit:
    """An enclosing primitive and where it sits.

    Attributes
    ----------
    primitive : Sphere, Box, Capsule, Cylinder or Ellipsoid
        Centred on its local origin; capsule and cylinder along local z; an ellipsoid's
        semi-axes along local x, y, z (descending).
    pose : (4, 4) float64
        Local to the points' frame (rigid): ``points = R @ local + t``.
    volume : float
        The primitive's volume.
    excess : float
        How far the farthest point lay outside the searched primitive before it was grown
        to contain it (0 when none did; a measure of the search's rounding).
    status : FitStatus
        OK, or MAX_ITERATIONS when a search cap stopped it early (it still contains every
        point).
    """

    primitive: Primitive
    pose: np.ndarray
    volume: float
    excess: float
    status: FitStatus = FitStatus.OK

    @property
    def shape(self) -> str:
        return type(self.primitive).__name__.lower()


@dataclass(frozen=True, eq=False)
class FitBatch:
    """The fits of H point sets, one array per field (K = the shapes asked for).

    Attributes
    ----------
    shapes : tuple of str
        The K shapes, in the order of the columns.
    hull_status : (H,) int8
        :class:`meshcol.collision.hull.HullStatus` of each set's exact hull.
    dimension : (H,) int8
        The hull's dimension (3, 2 flat, 1 collinear, 0 one point; -1 no hull).
    hull_volume : (H,) float64
    hull_vertex_offsets : (H + 1,) int64
        Set h's hull vertices are ``hull_vertices[hull_vertex_offsets[h]:...[h + 1]]``.
    hull_vertices : (V,) int64
        Indices into each set's own points.
    hull_face_offsets : (H + 1,) int64
    hull_faces : (F, 3) int64
        Triangles indexing each set's hull vertices (3-D: outward; 2-D: a fan).
    status : (H, K) int8
        :class:`FitStatus` of each fit.
    params : (H, K, 3) float64
        sphere: radius; box: sizes along local x, y, z; capsule and cylinder: radius,
        length; ellipsoid: semi-axes along local x, y, z. NaN without a fit.
    poses : (H, K, 4, 4) float64
        Local to the set's frame.
    volume, excess : (H, K) float64
    """

    shapes: tuple[str, ...]
    hull_status: np.ndarray
    dimension: np.ndarray
    hull_volume: np.ndarray
    hull_vertex_offsets: np.ndarray
    hull_vertices: np.ndarray
    hull_face_offsets: np.ndarray
    hull_faces: np.ndarray
    status: np.ndarray
    params: np.ndarray
    poses: np.ndarray
    volume: np.ndarray
    excess: np.ndarray

    def __len__(self) -> int:
        return len(self.hull_status)

    def fitted(self, h: int) -> bool:
        """Whether set ``h`` has every fit (its points had a hull)."""
        return bool(np.all(self.status[h] <= FitStatus.MAX_ITERATIONS))

    def fit(self, h: int, shape: str) -> PrimitiveFit:
        """The fit of ``shape`` around set ``h``.

        Raises
        ------
        InvalidMeshError
            The set had no hull (no points, NaN or infinite coordinates, overflow).
        """
        k = self.shapes.index(shape)
        status = FitStatus(int(self.status[h, k]))
        if status > FitStatus.MAX_ITERATIONS:
            raise self.error(h)
        primitive = primitive_from_params(shape, self.params[h, k])
        pose = self.poses[h, k].copy()
        return PrimitiveFit(
            primitive, pose, float(self.volume[h, k]), float(self.excess[h, k]), status
        )

    def fits(self, h: int) -> dict[str, PrimitiveFit]:
        """Every fit of set ``h``, keyed by shape (in the order of :attr:`shapes`)."""
        return {name: self.fit(h, name) for name in self.shapes}

    def hull(self, h: int) -> tuple[np.ndarray, np.ndarray]:
        """(vertex indices into set h's points, faces into those vertices) of its hull."""
        v = self.hull_vertices[self.hull_vertex_offsets[h] : self.hull_vertex_offsets[h + 1]]
        f = self.hull_faces[self.hull_face_offsets[h] : self.hull_face_offsets[h + 1]]
        return v, f

    def error(self, h: int) -> InvalidMeshError:
        """The one-line error of a set without fits (as :func:`exact_hull` words it)."""
        from meshcol.collision.hull import HullStatus, _no_hull

        status = HullStatus(int(self.hull_status[h]))
        if int(self.dimension[h]) >= 0:
            return InvalidMeshError("the fit's numbers were not finite (please report this input)")
        return _no_hull(status, self._points[h] if self._points is not None else np.zeros((0, 3)))

    _points: Sequence[np.ndarray] | None = field(default=None, repr=False)


def primitive_from_params(shape: str, p: np.ndarray) -> Primitive:
    """The primitive of one row of :attr:`FitBatch.params` (the same layout)."""
    if shape == "sphere":
        return Sphere(float(p[0]))
    if shape == "box":
        return Box((float(p[0]), float(p[1]), float(p[2])))
    if shape == "capsule":
        return Capsule(float(p[0]), float(p[1]))
    if shape == "ellipsoid":
        return Ellipsoid((float(p[0]), float(p[1]), float(p[2])))
    return Cylinder(float(p[0]), float(p[1]))


def fit_batch(
    point_sets: Sequence[np.ndarray], shape: str | Sequence[str] = "all", threads: int = 0
) -> FitBatch:
    """Enclosing primitives of many point sets in one native call.

    Parameters
    ----------
    point_sets : sequence of (n_i, 3) float
        Any frames; each set's fits are in its own frame.
    shape : str or sequence of str
        One of :data:`FIT_SHAPES`, several, or ``"all"`` (every one, in that order).
    threads : int
        Threads over sets (0: all cores). The result does not depend on it.

    Returns
    -------
    FitBatch
        A set without a hull (no points, NaN or infinite coordinates, beyond the hull's
        coordinate range) gets status INVALID_INPUT; collinear and single-point sets are
        fitted (their primitives as thin as the margin), with their ``dimension`` said.

    Raises
    ------
    ValueError
        An unknown shape, or a set that is not (n, 3).

    Notes
    -----
    The box's frame seeds the cylinder and capsule searches; it is computed once per set
    however many shapes are asked for.
    """
    from meshcol._native import core

    names = FIT_SHAPES if shape == "all" else (shape,) if isinstance(shape, str) else tuple(shape)
    for name in names:
        if name not in FIT_SHAPES:
            raise ValueError(f"unknown shape {name!r} (expected one of {', '.join(FIT_SHAPES)})")
    sets = []
    for points in point_sets:
        pts = np.ascontiguousarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"points must be (n, 3), got {pts.shape}")
        sets.append(pts)
    counts = np.fromiter((len(p) for p in sets), dtype=np.int64, count=len(sets))
    offsets = as_offsets(counts)
    packed = np.concatenate(sets) if sets else np.zeros((0, 3))
    codes = np.array([FIT_SHAPES.index(n) for n in names], dtype=np.int8)
    # the core's arrays are in the order of FitBatch's fields
    result = core.fit_primitives(np.ascontiguousarray(packed), offsets, codes, int(threads))
    return FitBatch(tuple(names), *result, _points=sets)


def primitive_volume(primitive: Primitive) -> float:
    """Volume of a primitive."""
    if isinstance(primitive, Sphere):
        return 4.0 / 3.0 * math.pi * primitive.radius**3
    if isinstance(primitive, Box):
        return float(np.prod(primitive.size))
    if isinstance(primitive, Capsule):
        r = primitive.radius
        return math.pi * r * r * primitive.length + 4.0 / 3.0 * math.pi * r**3
    if isinstance(primitive, Ellipsoid):
        a, b, c = primitive.semi_axes
        return 4.0 / 3.0 * math.pi * a * b * c
    if isinstance(primitive, HalfSpace):
        return math.inf
    return math.pi * primitive.radius**2 * primitive.length


def signed_distances(primitive: Primitive, local_points: np.ndarray) -> np.ndarray:
    """How far each point (n, 3), in the primitive's local frame, lies outside it.

    Positive outside, <= 0 inside. Exact for the sphere, capsule and cylinder's radial part;
    for the box and the cylinder's caps, the largest excess over one face (a lower bound of
    the Euclidean distance outside, exact inside and on faces): zero exactly on the surface.
    For an ellipsoid a lower bound outside, scaled by its smallest semi-axis.
    The core's growth evaluates the same expressions."""
    p = np.asarray(local_points, dtype=np.float64).reshape(-1, 3)
    if isinstance(primitive, Sphere):
        return np.linalg.norm(p, axis=1) - primitive.radius
    if isinstance(primitive, Box):
        return np.max(np.abs(p) - 0.5 * np.asarray(primitive.size), axis=1)
    if isinstance(primitive, Ellipsoid):
        # (|p / a| - 1) min(a): the point is on the boundary of the ellipsoid scaled by
        # k = |p / a|, which lies (k - 1) min(a) or more outside it (a flat one gives 0; the
        # core's growth of a fitted ellipsoid evaluates the same)
        axes = np.asarray(primitive.semi_axes)
        smallest = float(axes.min())
        if smallest == 0.0:
            return np.zeros(len(p))
        return (np.linalg.norm(p / axes, axis=1) - 1.0) * smallest
    if isinstance(primitive, HalfSpace):  # the height above its plane, exact
        return p[:, 2].copy()
    radial = np.hypot(p[:, 0], p[:, 1])
    half = 0.5 * primitive.length
    if isinstance(primitive, Capsule):
        beyond = np.maximum(np.abs(p[:, 2]) - half, 0.0)
        return np.hypot(radial, beyond) - primitive.radius
    return np.maximum(radial - primitive.radius, np.abs(p[:, 2]) - half)


def minimum_ball(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre (d,) and radius of the smallest ball that holds every point (n, d), d <= 3.

    Welzl's algorithm (1991) in the core, iterative, with the points in a fixed pseudo-random
    order. The radius is the exact largest distance from the centre found, so every point is
    inside (up to the rounding of one distance)."""
    from meshcol._native import core

    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or not 1 <= pts.shape[1] <= 3:
        raise ValueError(f"points must be (n, d) with 1 <= d <= 3, got {pts.shape}")
    if len(pts) == 0:
        raise ValueError("no points")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points must be finite")
    center, radius, _ = core.minimum_ball(pts)
    return center, float(radius)


def _one(shape: str | Sequence[str], points: np.ndarray) -> FitBatch:
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise ValueError(f"points must be (n, 3) with n >= 1, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points must be finite")
    batch = fit_batch([pts], shape, threads=1)
    if not batch.fitted(0):
        raise ValueError(batch.error(0).message)
    return batch


def enclosing_sphere(points: np.ndarray) -> PrimitiveFit:
    """The minimum enclosing sphere of points (n, 3)."""
    return _one("sphere", points).fit(0, "sphere")


def enclosing_box(points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """A near-minimal oriented box around points (n, 3). ``faces`` is accepted for
    compatibility and unused: the core takes the candidate axes from its own exact hull."""
    return _one("box", points).fit(0, "box")


def enclosing_cylinder(points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """A cylinder around points (n, 3) along the best of the near-minimal box's and the
    principal axes, polished by a local search (``faces``: unused, as for the box)."""
    return _one("cylinder", points).fit(0, "cylinder")


def enclosing_capsule(points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """A capsule around points (n, 3) along the best axis, as :func:`enclosing_cylinder`;
    radius and segment searched together for that axis."""
    return _one("capsule", points).fit(0, "capsule")


def enclosing_ellipsoid(points: np.ndarray) -> PrimitiveFit:
    """The minimum-volume enclosing ellipsoid of points (n, 3), within (1 +
    :data:`ELLIPSOID_TOLERANCE`) of the minimum volume, scaled to contain every point (status
    MAX_ITERATIONS when the iteration cap stopped it before the certificate: it still
    contains every point).

    Notes
    -----
    Khachiyan (1996); Kumar and Yildirim (2005); Todd and Yildirim (2007); the stopping
    certificate is the dual bound of Todd (2016), *Minimum-Volume Ellipsoids*.
    """
    return _one("ellipsoid", points).fit(0, "ellipsoid")


def fit_primitive(shape: str, points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """The enclosing primitive named by ``shape`` (one of :data:`FIT_SHAPES`)."""
    if shape not in FIT_SHAPES:
        raise ValueError(f"unknown shape {shape!r} (expected one of {', '.join(FIT_SHAPES)})")
    return _one(shape, points).fit(0, shape)


def fit_all(points: np.ndarray, faces: np.ndarray | None = None) -> dict[str, PrimitiveFit]:
    """Every primitive of :data:`FIT_SHAPES` around points (n, 3), keyed by shape; the box is
    fitted once and its axes seed the capsule and cylinder searches."""
    return _one("all", points).fits(0)
