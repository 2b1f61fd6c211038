"""Enclosing primitives of primitives, in closed form: no tessellation, no margin.

A body that IS a primitive (``Body.primitive``) is fitted from its parameters, batched by
kind with numpy over arrays of parameters (:func:`closed_form_fits`): a manifest of a million
primitives is a few array operations, never a loop over them. Each fit is centred on the
primitive's centre, in its frame (capsule and cylinder along local z; the ellipsoid's
semi-axes sorted descending by a permutation of the axes, as :mod:`meshcol.collision.fit`
gives them). The forms, F around K (h = l / 2 for a capsule or cylinder of length l):

===========  ==========  ==============  ==============  ===============  ===============
F \\ K        sphere r    box (size s)    capsule r, l    cylinder r, l    ellipsoid a
===========  ==========  ==============  ==============  ===============  ===============
sphere       r           abs(s) / 2      h + r           hypot(r, h)      max(a)
box          2r cube     s               2r, 2r, l + 2r  2r, 2r, l        2a
ellipsoid    r, r, r     sqrt(3) s / 2   see below       r√(3/2) ×2, h√3  a
capsule      r, 0        --              r, l            --               --
cylinder     r, 2r       --              r, l + 2r       r, l             --
===========  ==========  ==============  ==============  ===============  ===============

Every one of them is the MINIMUM (radius for the sphere, volume for the others):

- a primitive around its own kind is itself, and a sphere's capsule (length 0) is the sphere;
- sphere: K holds two antipodal points at that distance from its centre (corners, poles, rim
  points, the ends of the major axis), so no ball of smaller radius holds both;
- box: in any frame the box is at least K's width along each of its axes, its volume the
  product of the widths. A ball's widths are 2r. A capsule (ball plus segment) has widths
  2r + l t_i, t_i = |cos| of the axis to box axis i, sum t_i >= sum t_i^2 = 1, so the
  product is >= (2r)^3 + (2r)^2 l sum t_i >= (2r)^2 (2r + l). A cylinder (disk plus segment)
  has widths 2r s_i + l t_i (s_i = sqrt(1 - t_i^2)); the terms with one segment factor
  alone give 4 r^2 l sum_i t_i s_j s_k, and s_j s_k = sqrt(t_i^2 + t_j^2 t_k^2) >= t_i, so
  the product is >= 4 r^2 l. An ellipsoid's widths are 2 sqrt(u_i^T A^2 u_i), whose product
  is >= 8 det(A) by Hadamard's inequality (the diagonal of A^2 in the box's frame);
- ellipsoid: the minimum-volume enclosing ellipsoid is unique (John 1948), so it has every
  symmetry of K: a box's is the box's affine image of the cube's, the ball through the
  corners (sqrt(3) times the half sides); a cylinder's or capsule's is axis-aligned with
  two equal semi-axes a and c along the axis, a 1-parameter family. The cylinder's rim
  points (r, h) on its surface: minimise a^2 c with r^2/a^2 + h^2/c^2 = 1, which gives
  r^2/a^2 = 2/3. The capsule (the hull of two balls of radius r at +-h) is inside iff
  sqrt(a^2 (1 - t^2) + c^2 t^2) >= h t + r for t in [0, 1] (the support function), so
  c^2 = a^2 (1 + h^2 / (a^2 - r^2)) while a^2 <= r^2 + h r; minimising a^4 c^2 there gives
  a^2 = r^2 + h r^2 / (q + h), c^2 = a^2 (1 + h (q + h) / r^2) with q = sqrt(h^2 + 3 r^2);
- cylinder around a ball: radius >= r and length >= 2r; around a capsule of axis u along
  the cylinder's axis w (t = |u . w|, s = sqrt(1 - t^2)): radius r + h s, length 2r + 2h t,
  and log((r + h s)^2 (r + h t)) is concave in the angle, so its minimum is at an end of
  [0, pi/2]: t = 1, the capsule's own axis.

The pairs marked -- (a capsule around a box, a cylinder or an ellipsoid; a cylinder around a
box or an ellipsoid) have no closed form here: the caller fits them as before, by the
point-set search of :mod:`meshcol.collision.fit` around a polytope that contains K (a box's
8 corners, exact; a round primitive's enclosing tessellation).

:func:`largest_gaps`: how far the fitted primitive's surface strays from K, by support
functions (both convex, K inside F): the largest distance from a point of F to K is
max over unit m of h_F(m) - h_K(m).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from meshcol.collision.fit import FIT_SHAPES
from meshcol.collision.shapes import ShapeKind, primitive_params
from meshcol.types import Primitive

__all__ = [
    "GAP_DIRECTIONS",
    "ClosedFormFits",
    "closed_form_fits",
    "largest_gaps",
    "primitive_parameters",
    "solid_primitives",
    "support",
]

SPHERE, CAPSULE, BOX, CYLINDER, ELLIPSOID = range(5)  # FIT_SHAPES' order

#: Unit directions of :func:`largest_gaps`' coarse search (before its refinement).
GAP_DIRECTIONS = 256

_GAP_SEARCH_STEPS = 200  # pattern-search steps at most (27 halvings reach 1e-9, moves add)


def primitive_parameters(
    primitives: Sequence[Primitive | None],
) -> tuple[np.ndarray, np.ndarray]:
    """Kind and parameters of each primitive, the arrays :func:`closed_form_fits` takes.

    Returns
    -------
    kind : (N,) int8
        Index into :data:`meshcol.collision.fit.FIT_SHAPES`; -1 for None.
    params : (N, 3) float64
        As :class:`meshcol.collision.fit.FitBatch`'s: sphere radius; box sides; capsule and
        cylinder radius, length; ellipsoid semi-axes (unused entries 0).
    """
    fit_kind: dict[int, int] = {
        ShapeKind.SPHERE: SPHERE,
        ShapeKind.BOX: BOX,
        ShapeKind.CAPSULE: CAPSULE,
        ShapeKind.CYLINDER: CYLINDER,
        ShapeKind.ELLIPSOID: ELLIPSOID,
    }
    kind = np.full(len(primitives), -1, dtype=np.int8)
    params = np.zeros((len(primitives), 3))
    for i, p in enumerate(primitives):
        if p is not None:
            core_kind, core_params = primitive_params(p)  # the core's packing, halves
            kind[i] = fit_kind[core_kind]
            params[i] = core_params[:3]
    # full lengths (doubling a half is exact): a box's sides, a capsule's or cylinder's length
    params[kind == BOX] *= 2.0
    params[(kind == CAPSULE) | (kind == CYLINDER), 1] *= 2.0
    return kind, params


@dataclass(frozen=True, eq=False)
class ClosedFormFits:
    """One shape fitted around N primitives, one array per field.

    Attributes
    ----------
    shape : str
    exact : (N,) bool
        Whether the body has a closed form (a primitive of positive volume, of a pair with
        one); the other rows are zeros.
    params : (N, 3) float64
        As :class:`meshcol.collision.fit.FitBatch`'s.
    rotation : (N, 3, 3) float64
        The fit's local axes in the primitive's frame (``K = R @ local``; centred: no
        translation). The identity but for the ellipsoid's sorted axes.
    volume : (N,) float64
    """

    shape: str
    exact: np.ndarray
    params: np.ndarray
    rotation: np.ndarray
    volume: np.ndarray


def solid_primitives(kind: np.ndarray, params: np.ndarray) -> np.ndarray:
    """(N,) bool: the primitives of positive volume (a capsule of length 0 is a ball), those
    :func:`closed_form_fits` fits; a flat or empty one is left to the point-set fits."""
    kind = np.asarray(kind)
    p = np.asarray(params, dtype=np.float64).reshape(-1, 3)
    positive = p > 0
    radius, every = positive[:, 0], positive.all(axis=1)
    return np.select(
        [kind == SPHERE, kind == CAPSULE, kind == CYLINDER, kind == BOX, kind == ELLIPSOID],
        [radius, radius, radius & positive[:, 1], every, every],
        False,
    )


def _volume(shape: str, q: np.ndarray) -> np.ndarray:
    if shape == "sphere":
        return 4.0 / 3.0 * np.pi * q[:, 0] ** 3
    if shape == "box":
        return np.prod(q, axis=1)
    if shape == "ellipsoid":
        return 4.0 / 3.0 * np.pi * np.prod(q, axis=1)
    if shape == "capsule":
        return np.pi * q[:, 0] ** 2 * q[:, 1] + 4.0 / 3.0 * np.pi * q[:, 0] ** 3
    return np.pi * q[:, 0] ** 2 * q[:, 1]


def _capsule_ellipsoid(r: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Semi-axes (a, a, c) of a capsule's minimum enclosing ellipsoid (module docstring)."""
    q = np.sqrt(h * h + 3.0 * r * r)
    a2 = r * r + h * r * r / (q + h)
    c2 = a2 * (1.0 + h * (q + h) / (r * r))
    a = np.sqrt(a2)
    return np.stack([a, a, np.sqrt(c2)], axis=1)


def _around(shape: str, kind: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(has a closed form (N,), params (N, 3)) of ``shape`` around each primitive."""
    r, length = p[:, 0], p[:, 1]
    h = 0.5 * length
    is_ = [kind == k for k in range(5)]
    zero = np.zeros_like(r)
    if shape == "sphere":
        radius = np.select(
            is_,
            [r, r + h, 0.5 * np.linalg.norm(p, axis=1), np.hypot(r, h), p.max(axis=1)],
        )
        return kind >= 0, np.stack([radius, zero, zero], axis=1)
    if shape == "box":
        cube = np.stack([2 * r, 2 * r, 2 * r], axis=1)
        capsule = np.stack([2 * r, 2 * r, length + 2 * r], axis=1)
        cylinder = np.stack([2 * r, 2 * r, length], axis=1)
        out = np.select([m[:, None] for m in is_], [cube, capsule, p, cylinder, 2.0 * p])
        return kind >= 0, out
    if shape == "ellipsoid":
        ball = np.stack([r, r, r], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            capsule = _capsule_ellipsoid(r, h)
        side = np.sqrt(1.5) * r
        cylinder = np.stack([side, side, np.sqrt(3.0) * h], axis=1)
        box = 0.5 * np.sqrt(3.0) * p
        out = np.select([m[:, None] for m in is_], [ball, capsule, box, cylinder, p])
        return kind >= 0, out
    if shape == "capsule":
        known = is_[SPHERE] | is_[CAPSULE]
        return known, np.stack([r, np.where(is_[CAPSULE], length, 0.0), zero], axis=1)
    known = is_[SPHERE] | is_[CAPSULE] | is_[CYLINDER]
    cylinder_length = np.select([is_[SPHERE], is_[CAPSULE]], [2 * r, length + 2 * r], length)
    return known, np.stack([r, cylinder_length, zero], axis=1)


def _sorted_axes(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Semi-axes sorted descending and the rotation (a signed permutation, det +1) whose
    column j is the primitive's axis that fit axis j lies along."""
    order = np.argsort(-axes, axis=1, kind="stable")
    n = len(axes)
    rotation = np.zeros((n, 3, 3))
    rows = np.arange(n)
    for j in range(3):
        rotation[rows, order[:, j], j] = 1.0
    odd = np.linalg.det(rotation) < 0
    rotation[odd, :, 2] *= -1.0  # the ellipsoid is symmetric: flip its third axis
    return np.take_along_axis(axes, order, axis=1), rotation


def closed_form_fits(kind: np.ndarray, params: np.ndarray, shape: str) -> ClosedFormFits:
    """``shape`` (one of :data:`meshcol.collision.fit.FIT_SHAPES`) around N primitives
    (:func:`primitive_parameters`), each in its primitive's frame; ``exact`` says which
    rows have a closed form (the module docstring lists them)."""
    if shape not in FIT_SHAPES:
        raise ValueError(f"unknown shape {shape!r} (expected one of {', '.join(FIT_SHAPES)})")
    kind = np.asarray(kind, dtype=np.int8)
    p = np.asarray(params, dtype=np.float64).reshape(-1, 3)
    known, out = _around(shape, kind, p)
    exact = known & solid_primitives(kind, p)
    out = np.where(exact[:, None], out, 0.0)
    rotation = np.broadcast_to(np.eye(3), (len(p), 3, 3)).copy()
    if shape == "ellipsoid":
        out, rotation = _sorted_axes(out)
    return ClosedFormFits(shape, exact, out, rotation, np.where(exact, _volume(shape, out), 0.0))


def support(kind: int, params: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Support function h(m) = max over the primitive of m . x, centred in its frame:
    ``params`` (n, 3) of one kind, unit directions ``m`` (n, d, 3) in its frame -> (n, d)."""
    p = params[:, None, :]
    if kind == SPHERE:
        return np.broadcast_to(p[..., 0], m.shape[:2]).copy()
    if kind == BOX:
        return (np.abs(m) @ (0.5 * params)[:, :, None])[..., 0]
    if kind == ELLIPSOID:
        return np.linalg.norm(m * p, axis=2)
    half = 0.5 * p[..., 1]
    axial = half * np.abs(m[..., 2])
    if kind == CAPSULE:
        return p[..., 0] + axial
    return p[..., 0] * np.hypot(m[..., 0], m[..., 1]) + axial


def _directions() -> np.ndarray:
    """The coarse search's unit directions: :data:`GAP_DIRECTIONS` of a Fibonacci lattice
    on the sphere (near uniform) and the 26 of the cubic lattice (axes, face and body
    diagonals), where the boxes' and most forms' largest gaps lie."""
    k = np.arange(GAP_DIRECTIONS) + 0.5
    z = 1.0 - 2.0 * k / GAP_DIRECTIONS
    angle = np.pi * (3.0 - np.sqrt(5.0)) * k
    rho = np.sqrt(1.0 - z * z)
    fibonacci = np.stack([rho * np.cos(angle), rho * np.sin(angle), z], axis=1)
    lattice = np.array(
        [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if i or j or k],
        dtype=np.float64,
    )
    both = np.concatenate([fibonacci, lattice])
    return both / np.linalg.norm(both, axis=1, keepdims=True)


def _gap(
    kind: int,
    params: np.ndarray,
    fit_kind: int,
    fit_params: np.ndarray,
    poses: np.ndarray,
    m: np.ndarray,
) -> np.ndarray:
    """h_F(m) - h_K(m) for directions m (n, d, 3) in K's frame; F posed by ``poses``."""
    local = m @ poses[:, :3, :3]  # R^T m, row-wise
    offset = (m @ poses[:, :3, 3:])[..., 0]
    return support(fit_kind, fit_params, local) + offset - support(kind, params, m)


def _largest_gap_of(
    kind: int, params: np.ndarray, fit_kind: int, fit_params: np.ndarray, poses: np.ndarray
) -> np.ndarray:
    """:func:`largest_gaps` of n primitives of one kind, fitted by one kind: the best of
    the coarse directions, then a pattern search on the sphere of directions around it."""
    coarse = _directions()
    n = len(params)
    values = _gap(
        kind, params, fit_kind, fit_params, poses, np.broadcast_to(coarse, (n, *coarse.shape))
    )
    best = values.argmax(axis=1)
    rows = np.arange(n)
    m, value = coarse[best], values[rows, best]
    pattern = np.array([(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)])
    step = np.full(n, 0.1)  # per row: a row's answer does not depend on its batch
    for _ in range(_GAP_SEARCH_STEPS):
        active = step > 1e-9
        if not active.any():
            break
        # a tangent basis at m: u across the axis m is least along, v = m x u
        helper = np.eye(3)[np.abs(m).argmin(axis=1)]
        u = np.cross(m, helper)
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        v = np.cross(m, u)
        trial = m[:, None, :] + step[:, None, None] * (
            pattern[None, :, :1] * u[:, None, :] + pattern[None, :, 1:] * v[:, None, :]
        )
        trial /= np.linalg.norm(trial, axis=2, keepdims=True)
        tried = _gap(kind, params, fit_kind, fit_params, poses, trial)
        pick = tried.argmax(axis=1)
        better = active & (tried[rows, pick] > value)
        m = np.where(better[:, None], trial[rows, pick], m)
        value = np.where(better, tried[rows, pick], value)
        step = np.where(better | ~active, step, 0.5 * step)
    return np.maximum(value, 0.0)


def _least_half_width(kind: np.ndarray, params: np.ndarray) -> np.ndarray:
    """min over unit m of h_K(m) per primitive: a box's least half side, a capsule's radius,
    a cylinder's least of radius and half length (r sqrt(1 - t^2) + h t is concave in t, so
    least at t = 0 or 1), an ellipsoid's least semi-axis."""
    p = params
    return np.select(
        [kind == SPHERE, kind == CAPSULE, kind == BOX, kind == CYLINDER, kind == ELLIPSOID],
        [p[:, 0], p[:, 0], 0.5 * p.min(axis=1), np.minimum(p[:, 0], 0.5 * p[:, 1]), p.min(axis=1)],
    )


def _corner_distance(kind: np.ndarray, params: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """Distance from the point ``corner`` (n, 3) to a centred sphere, capsule or cylinder."""
    r, h = params[:, 0], 0.5 * params[:, 1]
    radial = np.hypot(corner[:, 0], corner[:, 1])
    beyond = np.maximum(corner[:, 2] - h, 0.0)
    distance = np.select(
        [kind == SPHERE, kind == CAPSULE],
        [np.linalg.norm(corner, axis=1) - r, np.hypot(radial, beyond) - r],
        np.hypot(np.maximum(radial - r, 0.0), beyond),
    )
    return np.maximum(distance, 0.0)


def largest_gaps(
    kind: np.ndarray,
    params: np.ndarray,
    fit_kind: np.ndarray,
    fit_params: np.ndarray,
    poses: np.ndarray,
    chunk: int = 2048,
) -> np.ndarray:
    """The largest distance from a point of each fitted primitive F to the primitive K it
    encloses: max over unit m of h_F(m) - h_K(m) (for p outside a convex K,
    dist(p, K) = max_m m . p - h_K(m); its largest over F is that, and K inside F makes it
    >= 0); for a ball centred on K, r - K's least half width, for an unturned box centred on
    a sphere, capsule or cylinder, its corner's distance (exact); else by the
    :data:`GAP_DIRECTIONS` (and 26 lattice) directions then a pattern search
    from the best: a lower bound, equal to it where the largest gap is at a lattice
    direction (a primitive in its own kind: 0) and within rounding elsewhere but where the
    search stops at another local maximum.

    Parameters
    ----------
    kind, params : (N,) int8 and (N, 3)
        The primitives K (:func:`primitive_parameters`), each in its own frame.
    fit_kind, fit_params : (N,) int8 and (N, 3)
        The fits F, as the same arrays.
    poses : (N, 4, 4)
        Each fit's local frame in its K's frame (rigid).
    chunk : int
        Primitives per array operation (memory: about chunk x 700 x 3 doubles).

    Returns
    -------
    (N,) float64
    """
    kind = np.asarray(kind)
    fit_kind = np.asarray(fit_kind)
    out = np.zeros(len(kind))
    # a primitive fitted by itself (same kind and numbers, unmoved) has no gap
    itself = (kind == fit_kind) & np.all(params == fit_params, axis=1)
    itself &= np.all(poses.reshape(-1, 16) == np.eye(4).ravel(), axis=1)
    # a ball centred on K: max_m r - h_K(m) = r - min_m h_K(m), K's least half width
    centred = (fit_kind == SPHERE) & np.all(poses[:, :3, 3] == 0.0, axis=1) & ~itself
    out[centred] = np.maximum(fit_params[centred, 0] - _least_half_width(kind, params)[centred], 0)
    # an unturned box centred on a round K: the distance is convex, so largest at a corner
    unmoved = np.all(poses.reshape(-1, 16) == np.eye(4).ravel(), axis=1)
    round_ = (kind == SPHERE) | (kind == CAPSULE) | (kind == CYLINDER)
    boxed = (fit_kind == BOX) & unmoved & round_ & ~itself
    out[boxed] = _corner_distance(kind[boxed], params[boxed], 0.5 * fit_params[boxed])
    for k in np.unique(kind):
        for f in np.unique(fit_kind[kind == k]):
            index = np.flatnonzero((kind == k) & (fit_kind == f) & ~itself & ~centred & ~boxed)
            for start in range(0, len(index), chunk):
                i = index[start : start + chunk]
                out[i] = _largest_gap_of(int(k), params[i], int(f), fit_params[i], poses[i])
    return out
