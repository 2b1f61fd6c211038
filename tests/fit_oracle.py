"""Test oracle: the pure-Python enclosing fits meshcol had before the core's (cpp/src/fit.cpp).

Kept only to compare the core against (volumes, containment) and for benchmarks/bench_fit.py;
the package has one engine, the core. What follows is the original module's text.

Enclosing primitives of a point set: the sphere, box, cylinder and capsule that contain it.

Arrays in, primitives out; the 2-D polygons the box and the round fits need come from the one
exact hull (:mod:`meshcol.collision.hull`). Every fit contains every input point: after the search, each primitive is grown
by the largest amount any point lies outside it (evaluated exactly in the fit's own frame),
plus a margin of :data:`CONTAINMENT_MARGIN` times the points' extent that covers the rounding
of that evaluation and of a caller's later transform. Enclosing the vertices of a mesh
encloses the mesh, since every primitive is convex.

How near to the smallest each fit is:

- **sphere**: the minimum enclosing ball (Welzl 1991, the randomised incremental algorithm,
  with a fixed seed so that a fit is deterministic), exact up to rounding;
- **box**: near-minimal oriented box. The smallest box has a face flush with a hull face in
  almost every case (O'Rourke 1985 shows it has two adjacent faces flush with hull edges);
  each hull face normal (the largest :data:`BOX_NORMALS`, by area) is tried as an axis with
  the minimum-area rectangle of the points projected on its plane (rotating calipers,
  Freeman and Shapira 1975), besides the principal axes; the best frame is then polished by
  a local search over rotations;
- **cylinder**: along the best of the box's and the principal axes, then polished; radius by
  the minimum enclosing circle of the points projected across the axis, length by their
  extent along it (exact for its axis);
- **capsule**: along the best axis as for the cylinder; for a radius r the shortest segment
  that keeps every point within r is exact, and r is searched between the projected circle's
  radius and the radius of a ball centred on the axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from meshcol.types import Box, Capsule, Cylinder, Primitive, Sphere

__all__ = [
    "BOX_NORMALS",
    "CONTAINMENT_MARGIN",
    "FIT_SHAPES",
    "PrimitiveFit",
    "enclosing_box",
    "enclosing_capsule",
    "enclosing_cylinder",
    "enclosing_sphere",
    "fit_all",
    "fit_primitive",
    "minimum_ball",
    "primitive_volume",
    "signed_distances",
]

#: The primitives :func:`fit_primitive` fits, simplest first (the order ``auto`` prefers).
FIT_SHAPES = ("sphere", "capsule", "box", "cylinder")

#: Relative margin (times the points' extent) every fit keeps beyond its farthest point.
CONTAINMENT_MARGIN = 1e-9

#: How many hull face normals (the largest by area) the box search tries as an axis.
BOX_NORMALS = 200

_SEED = 0x6D657368  # the fixed shuffle of Welzl's algorithm: the same fit every run


@dataclass(frozen=True)
class PrimitiveFit:
    """An enclosing primitive and where it sits.

    Attributes
    ----------
    primitive : Sphere, Box, Capsule or Cylinder
        Centred on its local origin; capsule and cylinder along local z.
    pose : (4, 4) float64
        Local to the points' frame (rigid): ``points = R @ local + t``.
    volume : float
        The primitive's volume.
    excess : float
        How far the farthest point lay outside the searched primitive before it was grown
        to contain it (0 when none did; a measure of the search's rounding).
    """

    primitive: Primitive
    pose: np.ndarray
    volume: float
    excess: float

    @property
    def shape(self) -> str:
        return type(self.primitive).__name__.lower()


def primitive_volume(primitive: Primitive) -> float:
    """Volume of a primitive."""
    if isinstance(primitive, Sphere):
        return 4.0 / 3.0 * math.pi * primitive.radius**3
    if isinstance(primitive, Box):
        return float(np.prod(primitive.size))
    if isinstance(primitive, Capsule):
        r = primitive.radius
        return math.pi * r * r * primitive.length + 4.0 / 3.0 * math.pi * r**3
    return math.pi * primitive.radius**2 * primitive.length


def signed_distances(primitive: Primitive, local_points: np.ndarray) -> np.ndarray:
    """How far each point (n, 3), in the primitive's local frame, lies outside it.

    Positive outside, <= 0 inside. Exact for the sphere, capsule and cylinder's radial part;
    for the box and the cylinder's caps, the largest excess over one face (a lower bound of
    the Euclidean distance outside, exact inside and on faces): zero exactly on the surface."""
    p = np.asarray(local_points, dtype=np.float64).reshape(-1, 3)
    if isinstance(primitive, Sphere):
        return np.linalg.norm(p, axis=1) - primitive.radius
    if isinstance(primitive, Box):
        return np.max(np.abs(p) - 0.5 * np.asarray(primitive.size), axis=1)
    radial = np.hypot(p[:, 0], p[:, 1])
    half = 0.5 * primitive.length
    if isinstance(primitive, Capsule):
        beyond = np.maximum(np.abs(p[:, 2]) - half, 0.0)
        return np.hypot(radial, beyond) - primitive.radius
    return np.maximum(radial - primitive.radius, np.abs(p[:, 2]) - half)


def _grown(primitive: Primitive, amount: float) -> Primitive:
    if isinstance(primitive, Sphere):
        return Sphere(primitive.radius + amount)
    if isinstance(primitive, Box):
        return Box(tuple(s + 2.0 * amount for s in primitive.size))  # type: ignore[arg-type]
    if isinstance(primitive, Capsule):
        return Capsule(primitive.radius + amount, primitive.length)
    return Cylinder(primitive.radius + amount, primitive.length + 2.0 * amount)


def _finish(primitive: Primitive, rotation: np.ndarray, center: np.ndarray, points: np.ndarray):
    """Grow the primitive until it holds every point (exactly evaluated), plus the margin."""
    local = (points - center) @ rotation
    excess = float(np.max(signed_distances(primitive, local))) if len(points) else 0.0
    extent = float(np.max(np.ptp(points, axis=0))) if len(points) else 0.0
    scale = max(extent, float(np.max(np.abs(points))) * 1e-6 if len(points) else 0.0, 1e-300)
    grown = _grown(primitive, max(excess, 0.0) + CONTAINMENT_MARGIN * scale)
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = center
    return PrimitiveFit(grown, pose, primitive_volume(grown), max(excess, 0.0))


# ---------------------------------------------------------------------------------------------
# Minimum enclosing ball (any dimension; 2-D circles for cylinders and capsules)


def _ball_through(support: np.ndarray) -> tuple[np.ndarray, float]:
    """Smallest ball with every support point (k, d) on its boundary: centre in their affine
    hull, by least squares (a degenerate set gives the best ball through its span)."""
    p0 = support[0]
    if len(support) == 1:
        return p0.copy(), 0.0
    a = support[1:] - p0
    rhs = 0.5 * np.einsum("ij,ij->i", a, a)
    gram = a @ a.T
    if len(a) == 1:
        coefficients = rhs / gram[0] if gram[0, 0] > 0 else np.zeros(1)
    elif len(a) == 2:  # Cramer's rule: the common case, without a solver's overhead
        det = gram[0, 0] * gram[1, 1] - gram[0, 1] * gram[1, 0]
        if abs(det) > 1e-14 * gram[0, 0] * gram[1, 1]:
            coefficients = np.array(
                [
                    (rhs[0] * gram[1, 1] - gram[0, 1] * rhs[1]) / det,
                    (gram[0, 0] * rhs[1] - rhs[0] * gram[1, 0]) / det,
                ]
            )
        else:
            coefficients = np.linalg.lstsq(gram, rhs, rcond=None)[0]
    else:
        coefficients = np.linalg.lstsq(gram, rhs, rcond=None)[0]
    center = p0 + coefficients @ a
    return center, float(np.max(np.sum((support - center) ** 2, axis=1)))


def minimum_ball(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre (d,) and radius of the smallest ball that holds every point (n, d).

    Welzl's algorithm (1991) in its iterative form, with the points in a fixed pseudo-random
    order; each "first point outside" is found by one array scan. The radius is the exact
    largest distance from the centre found, so every point is inside (up to the rounding of
    one distance)."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    n, d = pts.shape
    if n == 0:
        raise ValueError("no points")
    pts = pts[np.random.default_rng(_SEED).permutation(n)]
    scale = float(np.max(np.abs(pts - pts[0]))) or 1.0
    tolerance = (1e-12 * scale) ** 2

    def first_outside(center: np.ndarray, r2: float, start: int, end: int) -> int:
        if start >= end:
            return -1
        chunk = pts[start:end] - center
        outside = np.einsum("ij,ij->i", chunk, chunk) > r2 + tolerance + 1e-12 * r2
        k = int(np.argmax(outside))
        return start + k if outside[k] else -1

    def ball(end: int, support: list[int]) -> tuple[np.ndarray, float]:
        if support:
            center, r2 = _ball_through(pts[support])
            start = 0
        else:
            center, r2 = pts[0].copy(), 0.0
            start = 1
        if len(support) == d + 1:
            return center, r2
        i = first_outside(center, r2, start, end)
        while i >= 0:
            center, r2 = ball(i, [*support, i])
            i = first_outside(center, r2, i + 1, end)
        return center, r2

    center, _ = ball(n, [])
    radius = float(np.sqrt(np.max(np.sum((pts - center) ** 2, axis=1))))
    return center, radius


def enclosing_sphere(points: np.ndarray) -> PrimitiveFit:
    """The minimum enclosing sphere of points (n, 3)."""
    pts = _as_points(points)
    center, radius = minimum_ball(pts)
    return _finish(Sphere(radius), np.eye(3), center, pts)


# ---------------------------------------------------------------------------------------------
# Oriented boxes


def _frame(axis: np.ndarray) -> np.ndarray:
    """A right-handed rotation whose third column is the unit ``axis``."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = helper - (helper @ z) * z  # the world x axis where it can be: z up gives identity
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _principal_axes(points: np.ndarray) -> np.ndarray:
    centered = points - points.mean(axis=0)
    _, vectors = np.linalg.eigh(centered.T @ centered)
    rotation = vectors[:, ::-1].copy()
    if np.linalg.det(rotation) < 0:
        rotation[:, 2] *= -1
    return rotation


def _box_volume(points: np.ndarray, rotation: np.ndarray) -> float:
    local = points @ rotation
    return float(np.prod(np.ptp(local, axis=0)))


def _hull_2d(points: np.ndarray) -> np.ndarray:
    """Vertices of the convex polygon of 2-D points (n, 2), in order around it: the one exact
    hull (:func:`meshcol.collision.hull.exact_hull`) of the points lifted to a plane (for
    collinear or coincident points: their extremes)."""
    from meshcol.collision.hull import exact_hull

    lifted = np.column_stack([points, np.zeros(len(points))])
    return np.ascontiguousarray(exact_hull(lifted).vertices[:, :2])


def _min_area_rectangle(points_2d: np.ndarray) -> tuple[float, float]:
    """(area, angle) of the smallest rectangle around 2-D points: one side lies along an edge
    of their convex polygon (Freeman and Shapira 1975), every edge tried at once."""
    polygon = _hull_2d(points_2d)
    if len(polygon) < 3:
        edge = polygon[-1] - polygon[0]
        return 0.0, float(np.arctan2(edge[1], edge[0])) if len(polygon) == 2 else 0.0
    edges = np.roll(polygon, -1, axis=0) - polygon
    angles = np.arctan2(edges[:, 1], edges[:, 0])
    cos, sin = np.cos(angles), np.sin(angles)
    u = polygon[:, 0][None, :] * cos[:, None] + polygon[:, 1][None, :] * sin[:, None]
    v = -polygon[:, 0][None, :] * sin[:, None] + polygon[:, 1][None, :] * cos[:, None]
    areas = np.ptp(u, axis=1) * np.ptp(v, axis=1)
    best = int(np.argmin(areas))
    return float(areas[best]), float(angles[best])


def _rotation_vector(rotation: np.ndarray, w: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(w))
    if angle == 0.0:
        return rotation
    k = w / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    turn = np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * (cross @ cross)
    return turn @ rotation


def _polish(
    cost, x0: np.ndarray, step: float, iterations: int = 60, smallest: float = 1e-6
) -> np.ndarray:
    """A small pattern search (coordinate steps, halved on failure) from ``x0``: cheap,
    derivative-free and monotone, for the non-smooth volume of a box or cylinder."""
    x, best = x0.copy(), cost(x0)
    for _ in range(iterations):
        improved = False
        for k in range(len(x)):
            for sign in (1.0, -1.0):
                trial = x.copy()
                trial[k] += sign * step
                value = cost(trial)
                if value < best:
                    x, best, improved = trial, value, True
                    break
        if not improved:
            step *= 0.5
            if step < smallest:
                break
    return x


def _face_normals(points: np.ndarray, faces: np.ndarray | None, limit: int) -> np.ndarray:
    if faces is None or len(faces) == 0:
        return np.empty((0, 3))
    tri = points[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1)
    keep = area > 0
    normals, area = cross[keep] / area[keep, None], area[keep]
    # Merge (anti)parallel normals: a box axis and its negative are the same frame.
    flip = (normals[:, 2] < 0) | ((normals[:, 2] == 0) & (normals[:, 1] < 0))
    normals[flip] *= -1
    rounded = np.round(normals, 6)
    _, first, inverse = np.unique(rounded, axis=0, return_index=True, return_inverse=True)
    totals = np.bincount(inverse.ravel(), weights=area)
    order = np.argsort(-totals)[:limit]
    return normals[first[order]]


def enclosing_box(points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """A near-minimal oriented box around points (n, 3); ``faces`` (m, 3) of their convex
    hull (over ``points``) give the candidate axes (without them: the principal axes only)."""
    pts = _as_points(points)
    candidates = [np.eye(3), _principal_axes(pts)]
    for normal in _face_normals(pts, faces, BOX_NORMALS):
        frame = _frame(normal)
        plane = pts @ frame[:, :2]
        _, angle = _min_area_rectangle(plane)
        c, s = math.cos(angle), math.sin(angle)
        x = c * frame[:, 0] + s * frame[:, 1]
        candidates.append(np.column_stack([x, np.cross(normal, x), normal]))
    volumes = np.array([_box_volume(pts, r) for r in candidates])
    # The first of the equal best (to rounding): an axis-aligned box stays axis-aligned.
    rotation = candidates[int(np.argmax(volumes <= volumes.min() * (1 + 1e-9)))]
    w = _polish(lambda w: _box_volume(pts, _rotation_vector(rotation, w)), np.zeros(3), 0.05)
    rotation = _rotation_vector(rotation, w)
    local = pts @ rotation
    low, high = local.min(axis=0), local.max(axis=0)
    center = rotation @ (0.5 * (low + high))
    return _finish(Box(tuple(high - low)), rotation, center, pts)


# ---------------------------------------------------------------------------------------------
# Cylinders and capsules along an axis


def _direction(theta_phi: np.ndarray) -> np.ndarray:
    theta, phi = theta_phi
    return np.array(
        [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]
    )


def _angles(axis: np.ndarray) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    return np.array([math.acos(max(-1.0, min(1.0, a[2]))), math.atan2(a[1], a[0])])


def _across(points: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame with z along ``axis``, the points' 2-D coordinates across it and their
    coordinates along it."""
    frame = _frame(axis)
    return frame, points @ frame[:, :2], points @ frame[:, 2]


def _cylinder_on(points: np.ndarray, axis: np.ndarray):
    frame, plane, along = _across(points, axis)
    center_2d, radius = minimum_ball(_hull_2d(plane))
    low, high = float(along.min()), float(along.max())
    center = frame[:, :2] @ center_2d + frame[:, 2] * 0.5 * (low + high)
    return Cylinder(radius, high - low), frame, center


def _capsule_on(points: np.ndarray, axis: np.ndarray):
    frame, plane, along = _across(points, axis)
    center_2d, r_min = minimum_ball(_hull_2d(plane))
    radial2 = np.sum((plane - center_2d) ** 2, axis=1)
    middle = 0.5 * (float(along.min()) + float(along.max()))
    r_max = float(np.sqrt(np.max(radial2 + (along - middle) ** 2)))
    r_max = max(r_max, r_min)

    def segment(radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        reach = np.sqrt(np.maximum(radii[:, None] ** 2 - radial2[None, :], 0.0))
        top = np.max(along[None, :] - reach, axis=1)
        bottom = np.min(along[None, :] + reach, axis=1)
        return top, bottom

    def volumes(radii: np.ndarray) -> np.ndarray:
        top, bottom = segment(radii)
        length = np.maximum(top - bottom, 0.0)
        return math.pi * radii**2 * length + 4.0 / 3.0 * math.pi * radii**3

    low, high = r_min, r_max
    for _ in range(4):  # a coarse grid, then finer grids around the best radius
        radii = np.linspace(low, high, 33)
        best = int(np.argmin(volumes(radii)))
        low, high = radii[max(best - 1, 0)], radii[min(best + 1, len(radii) - 1)]
    radius = float(radii[best])
    top, bottom = (float(x[0]) for x in segment(np.array([radius])))
    length = max(top - bottom, 0.0)
    mid = 0.5 * (top + bottom)
    center = frame[:, :2] @ center_2d + frame[:, 2] * mid
    return Capsule(radius, length), frame, center


def _along_best_axis(points: np.ndarray, make, axes: list[np.ndarray]) -> PrimitiveFit:
    def cost(theta_phi: np.ndarray) -> float:
        return primitive_volume(make(points, _direction(theta_phi))[0])

    starts = [_angles(a) for a in axes]
    start = min(starts, key=cost)
    best = _polish(cost, start, 0.05, iterations=40, smallest=1e-3)
    primitive, frame, center = make(points, _direction(best))
    return _finish(primitive, frame, center, points)


def _candidate_axes(points: np.ndarray, faces: np.ndarray | None) -> list[np.ndarray]:
    box = enclosing_box(points, faces).pose[:3, :3]
    principal = _principal_axes(points)
    return [*box.T, *principal.T]


def enclosing_cylinder(
    points: np.ndarray, faces: np.ndarray | None = None, axes: list[np.ndarray] | None = None
) -> PrimitiveFit:
    """A cylinder around points (n, 3) along the best of the candidate ``axes`` (default: the
    near-minimal box's and the principal axes), polished by a local search."""
    pts = _as_points(points)
    return _along_best_axis(pts, _cylinder_on, axes or _candidate_axes(pts, faces))


def enclosing_capsule(
    points: np.ndarray, faces: np.ndarray | None = None, axes: list[np.ndarray] | None = None
) -> PrimitiveFit:
    """A capsule around points (n, 3) along the best of the candidate ``axes``, as
    :func:`enclosing_cylinder`; radius and segment searched together for that axis."""
    pts = _as_points(points)
    return _along_best_axis(pts, _capsule_on, axes or _candidate_axes(pts, faces))


def fit_primitive(shape: str, points: np.ndarray, faces: np.ndarray | None = None) -> PrimitiveFit:
    """The enclosing primitive named by ``shape`` (one of :data:`FIT_SHAPES`)."""
    if shape == "sphere":
        return enclosing_sphere(points)
    if shape == "box":
        return enclosing_box(points, faces)
    if shape == "cylinder":
        return enclosing_cylinder(points, faces)
    if shape == "capsule":
        return enclosing_capsule(points, faces)
    raise ValueError(f"unknown shape {shape!r} (expected one of {', '.join(FIT_SHAPES)})")


def fit_all(points: np.ndarray, faces: np.ndarray | None = None) -> dict[str, PrimitiveFit]:
    """Every primitive of :data:`FIT_SHAPES` around points (n, 3), keyed by shape; the box is
    fitted once and its axes seed the capsule and cylinder searches."""
    pts = _as_points(points)
    box = enclosing_box(pts, faces)
    axes = [*box.pose[:3, :3].T, *_principal_axes(pts).T]
    fits = {
        "sphere": enclosing_sphere(pts),
        "capsule": enclosing_capsule(pts, axes=axes),
        "box": box,
        "cylinder": enclosing_cylinder(pts, axes=axes),
    }
    return {name: fits[name] for name in FIT_SHAPES}


def _as_points(points: np.ndarray) -> np.ndarray:
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise ValueError(f"points must be (n, 3) with n >= 1, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points must be finite")
    return pts
