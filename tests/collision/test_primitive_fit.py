"""Closed-form fits around primitives (meshcol.collision.primitive_fit) against independent
oracles: dense points of the primitive's exact surface (ray cast from its centre) all inside
the fit, one of them on the fit's boundary (within 1e-9), and for minimality the core's point
fits of tessellations (the minimum ball of the surface points; the box and ellipsoid fitted
around a tessellation that contains the primitive, which cannot be smaller than the minimum;
the ellipsoid's Khachiyan fit of the inscribed tessellation, which cannot be larger)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from meshcol.collision.fit import (
    enclosing_box,
    enclosing_capsule,
    enclosing_cylinder,
    enclosing_ellipsoid,
    minimum_ball,
    primitive_from_params,
    signed_distances,
)
from meshcol.collision.primitive_fit import (
    closed_form_fits,
    largest_gaps,
    primitive_parameters,
    solid_primitives,
)
from meshcol.io.primitives import enclosing_primitive_mesh, primitive_mesh
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Sphere

BODIES = [
    Sphere(0.5),
    Box((1.0, 2.0, 3.0)),
    Box((0.02, 5.0, 0.3)),
    Capsule(0.2, 1.0),
    Capsule(1.0, 0.1),
    Cylinder(0.3, 1.0),
    Cylinder(2.0, 0.1),
    Ellipsoid((0.3, 0.2, 0.1)),
    Ellipsoid((0.1, 0.7, 0.4)),
]

_LATTICE = np.array(
    [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if i or j or k],
    dtype=np.float64,
)

#: (fit shape, body type) pairs with a closed form.
CLOSED = {
    "sphere": (Sphere, Box, Capsule, Cylinder, Ellipsoid),
    "box": (Sphere, Box, Capsule, Cylinder, Ellipsoid),
    "ellipsoid": (Sphere, Box, Capsule, Cylinder, Ellipsoid),
    "capsule": (Sphere, Capsule),
    "cylinder": (Sphere, Capsule, Cylinder),
}


def _boundary_scale(primitive, d: np.ndarray) -> np.ndarray:
    """s > 0 with s d on the primitive's surface, per direction (n, 3) from its centre."""
    if isinstance(primitive, Sphere):
        return primitive.radius / np.linalg.norm(d, axis=1)
    if isinstance(primitive, Box):
        return 1.0 / np.max(np.abs(d) / (0.5 * np.asarray(primitive.size)), axis=1)
    if isinstance(primitive, Ellipsoid):
        return 1.0 / np.linalg.norm(d / np.asarray(primitive.semi_axes), axis=1)
    rho, z = np.hypot(d[:, 0], d[:, 1]), np.abs(d[:, 2])
    r, h = primitive.radius, 0.5 * primitive.length
    with np.errstate(divide="ignore", invalid="ignore"):
        side = np.where(rho > 0, r / rho, np.inf)
        cap = np.where(z > 0, h / z, np.inf)
    if isinstance(primitive, Cylinder):
        return np.minimum(side, cap)
    # capsule: the side while within the segment's span, else the end ball
    a = rho * rho + z * z
    ball = (h * z + np.sqrt(np.maximum(h * h * z * z - a * (h * h - primitive.radius**2), 0))) / a
    return np.where(side * z <= h, side, ball)


@functools.lru_cache(maxsize=1)
def _directions(seed: int) -> np.ndarray:
    """The directions every surface shares: random ones, a fine meridian (the round ones'
    extremes lie on one by symmetry) in two planes and the 26 lattice directions."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0.0, np.pi, 1_000_001)
    meridian = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    directions = np.concatenate(
        [rng.normal(size=(100_000, 3)), meridian, _LATTICE, meridian[:, [1, 0, 2]]]
    )
    directions.flags.writeable = False
    return directions


@functools.lru_cache(maxsize=4)
def _surface(primitive, seed: int = 0) -> np.ndarray:
    """Points of the primitive's exact surface: the shared directions and, for a box, an
    ellipsoid or a cylinder, the lattice stretched to its corners or rims. Cached (read-only):
    several fits of one body read the same two million points."""
    directions = [_directions(seed)]
    if isinstance(primitive, Box):
        directions.append(_LATTICE * np.asarray(primitive.size))
    if isinstance(primitive, Ellipsoid):
        directions.append(_LATTICE * np.asarray(primitive.semi_axes))
    if isinstance(primitive, Cylinder):  # its rims
        r, h = primitive.radius, 0.5 * primitive.length
        directions.append(_LATTICE * np.array([r, r, h]))
    d = np.concatenate(directions)
    points = d * _boundary_scale(primitive, d)[:, None]
    points.flags.writeable = False
    return points


def _fit(shape: str, primitive):
    kind, params = primitive_parameters([primitive])
    form = closed_form_fits(kind, params, shape)
    return form, primitive_from_params(shape, form.params[0]), form.rotation[0]


def _pairs():
    for shape, types in CLOSED.items():
        for body in BODIES:
            if isinstance(body, types):
                yield shape, body


def _first_of_each_kind(cases):
    """The cases as parameters, each after the first of its fit shape (for (shape, body)
    cases) or of its body type marked slow: the fast lane runs each closed form's oracle
    for one body (about 1 s a case: a million exact surface points), ``make test`` every
    (shape, body) pair."""
    seen = set()
    for case in cases:
        key = case[0] if isinstance(case, tuple) else type(case)
        yield pytest.param(
            *(case if isinstance(case, tuple) else (case,)),
            marks=() if key not in seen else pytest.mark.slow,
        )
        seen.add(key)


@pytest.mark.parametrize(("shape", "body"), list(_first_of_each_kind(_pairs())))
def test_closed_form_contains_and_touches(shape: str, body) -> None:
    form, fitted, rotation = _fit(shape, body)
    assert form.exact[0]
    points = _surface(body)
    scale = float(np.abs(points).max())
    outside = signed_distances(fitted, points @ rotation)  # local = R^T p, row-wise
    assert outside.max() <= 1e-12 * scale
    assert outside.max() >= -1e-9 * scale  # the fit touches the body


@pytest.mark.parametrize("body", list(_first_of_each_kind(BODIES)))
def test_sphere_is_the_minimum_ball(body) -> None:
    _, fitted, _ = _fit("sphere", body)
    _, radius = minimum_ball(_surface(body))
    assert fitted.radius == pytest.approx(radius, rel=1e-9)


@pytest.mark.parametrize("body", list(_first_of_each_kind(BODIES)))
def test_box_and_ellipsoid_no_larger_than_the_point_fits(body) -> None:
    """The closed forms are minimal: the core's fits of a polytope that contains the body
    contain it too, so they are no smaller; the minimum ellipsoid of the inscribed polytope
    (a subset) is no larger."""
    enclosing = enclosing_primitive_mesh(body)[0]
    box, _, _ = _fit("box", body)
    assert box.volume[0] <= enclosing_box(enclosing).volume * (1 + 1e-12)
    ellipsoid, _, _ = _fit("ellipsoid", body)
    assert ellipsoid.volume[0] <= enclosing_ellipsoid(enclosing).volume * (1 + 1e-12)
    inscribed = enclosing_ellipsoid(primitive_mesh(body)[0]).volume
    assert inscribed <= ellipsoid.volume[0] * (1 + 2e-6)


@pytest.mark.parametrize("body", [b for b in BODIES if isinstance(b, (Sphere, Capsule))])
def test_capsule_and_cylinder_no_larger_than_the_point_fits(body) -> None:
    enclosing = enclosing_primitive_mesh(body)[0]
    capsule, _, _ = _fit("capsule", body)
    assert capsule.volume[0] <= enclosing_capsule(enclosing).volume * (1 + 1e-12)
    cylinder, _, _ = _fit("cylinder", body)
    assert cylinder.volume[0] <= enclosing_cylinder(enclosing).volume * (1 + 1e-12)


@pytest.mark.parametrize("body", [Cylinder(0.3, 1.0), Capsule(0.2, 1.0), Capsule(1.0, 0.1)])
def test_round_ellipsoid_is_the_least_of_its_family(body) -> None:
    """Axis-aligned ellipsoids (a, a, c) around the cylinder or capsule: for each a, the
    least c that holds the dense surface points; SciPy's bounded minimum of the volume a^2 c
    over a is the closed form's (to 1e-9: the volume is flat at the minimum, so a wrong a is
    found by its volume)."""
    from scipy.optimize import minimize_scalar

    _, fitted, _ = _fit("ellipsoid", body)
    points = _surface(body)
    rho2, z2 = points[:, 0] ** 2 + points[:, 1] ** 2, points[:, 2] ** 2
    a0 = fitted.semi_axes[1]

    def least_volume(a: float) -> float:
        if np.any(rho2 >= a * a):
            return np.inf
        return a * a * np.sqrt(np.max(z2 / (1.0 - rho2 / (a * a))))

    low = max(0.9 * a0, np.sqrt(rho2.max()) * (1 + 1e-9))  # a must clear the widest point
    best = minimize_scalar(
        least_volume, bounds=(low, 1.1 * a0), method="bounded", options={"xatol": 1e-12 * a0}
    )
    assert least_volume(a0) <= best.fun * (1 + 1e-9)
    assert least_volume(a0) == pytest.approx(np.prod(fitted.semi_axes), rel=1e-9)
    assert best.x == pytest.approx(a0, rel=1e-3)


def test_box_around_a_cylinder_or_capsule_beats_random_frames() -> None:
    """The product of the widths along any frame's axes (support functions) is no less."""
    rng = np.random.default_rng(1)
    frames = np.linalg.qr(rng.normal(size=(20_000, 3, 3)))[0]
    for body in (Cylinder(0.3, 1.0), Cylinder(2.0, 0.1), Capsule(0.2, 1.0)):
        box, _, _ = _fit("box", body)
        r, h = body.radius, 0.5 * body.length
        t = np.abs(frames[:, 2, :])  # the axis against each frame axis
        s = np.sqrt(np.clip(1 - t * t, 0, 1))
        widths = 2 * (r * s + h * t) if isinstance(body, Cylinder) else 2 * (r + h * t)
        assert np.prod(widths, axis=1).min() >= box.volume[0] * (1 - 1e-12)


def test_no_closed_form_and_flat_primitives_are_left_out() -> None:
    kind, params = primitive_parameters(
        [None, Box((1, 0, 1)), Sphere(0.0), Capsule(1, 0), Cylinder(1, 2), Ellipsoid((1, 2, 3))]
    )
    assert solid_primitives(kind, params).tolist() == [False, False, False, True, True, True]
    assert closed_form_fits(kind, params, "capsule").exact.tolist() == [0, 0, 0, 1, 0, 0]
    assert closed_form_fits(kind, params, "cylinder").exact.tolist() == [0, 0, 0, 1, 1, 0]
    assert closed_form_fits(kind, params, "sphere").exact.tolist() == [0, 0, 0, 1, 1, 1]


def test_ellipsoid_axes_descending_by_a_rotation() -> None:
    form, fitted, rotation = _fit("ellipsoid", Ellipsoid((0.1, 0.7, 0.4)))
    assert fitted.semi_axes == (0.7, 0.4, 0.1)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    assert np.allclose(
        np.abs(rotation @ np.diag(fitted.semi_axes) @ rotation.T), np.diag([0.1, 0.7, 0.4])
    )


def _distance(body, points: np.ndarray) -> np.ndarray:
    """Exact distance from points outside or on the body (its frame) to it."""
    if isinstance(body, Sphere):
        return np.maximum(np.linalg.norm(points, axis=1) - body.radius, 0)
    if isinstance(body, Box):
        return np.linalg.norm(np.maximum(np.abs(points) - 0.5 * np.asarray(body.size), 0), axis=1)
    rho, z = np.hypot(points[:, 0], points[:, 1]), np.abs(points[:, 2])
    h = 0.5 * body.length
    if isinstance(body, Capsule):
        return np.maximum(np.hypot(rho, np.maximum(z - h, 0)) - body.radius, 0)
    return np.hypot(np.maximum(rho - body.radius, 0), np.maximum(z - h, 0))


@pytest.mark.parametrize(
    ("shape", "body"),
    list(_first_of_each_kind(p for p in _pairs() if not isinstance(p[1], Ellipsoid))),
)
def test_largest_gap_against_dense_surface_points(shape: str, body) -> None:
    """The support-function gap against the largest exact distance from dense points of the
    fit's surface to the body (a lower bound that the points approach)."""
    form, fitted, rotation = _fit(shape, body)
    kind, params = primitive_parameters([body])
    fit_kind, fit_params = primitive_parameters([fitted])
    pose = np.eye(4)
    pose[:3, :3] = rotation
    gap = largest_gaps(kind, params, fit_kind, fit_params, pose[None])[0]
    sampled = _distance(body, _surface(fitted) @ rotation.T).max()
    scale = float(max(np.abs(params).max(), np.abs(fit_params).max()))
    assert sampled <= gap + 1e-9 * scale
    assert gap <= sampled + 1e-6 * scale
    if type(fitted) is type(body):
        assert gap == 0.0


@pytest.mark.parametrize(
    "body",
    [
        Box((1.0, 2.0, 3.0)),
        pytest.param(Box((0.3, 0.5, 2.0)), marks=pytest.mark.slow),
        pytest.param(Cylinder(0.3, 1.0), marks=pytest.mark.slow),
    ],
)
@pytest.mark.parametrize("shape", ["capsule", "cylinder"])
def test_largest_gap_of_a_point_set_fit(shape: str, body) -> None:
    """A pair without a closed form keeps the point-set fit, turned and moved in the body's
    frame; its gap (support functions with that pose) against the dense oracle."""
    from meshcol.analysis.fit import fit_body
    from meshcol.types import Body

    vertices, faces = primitive_mesh(body)
    fits, _, gap = fit_body(Body("b", None, vertices, faces, primitive=body), shape)
    fitted = fits.primitive_fit
    points = _surface(fitted.primitive) @ fitted.pose[:3, :3].T + fitted.pose[:3, 3]
    sampled = _distance(body, points).max()
    assert sampled <= gap + 1e-9 and gap <= sampled + 1e-6
