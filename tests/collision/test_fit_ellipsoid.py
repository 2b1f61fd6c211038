"""The minimum-volume enclosing ellipsoid (``fit --shape ellipsoid``) against oracles.

Known answers: an ellipsoid whose John points (the images of +-e_i) are among the points IS
the minimum enclosing ellipsoid of any points on or inside it; a box's corners have the box's
ellipsoid scaled by sqrt(3). Independent references: a plain numpy Khachiyan (no drop steps,
uniform start, many iterations), whose weights also give a dual LOWER bound of the minimum
volume (Todd 2016, ch. 2), and SciPy's SLSQP on the primal problem (made feasible by
scaling), which converges tighter than Khachiyan can in a test's time. Enclosure is checked
in float64 with numpy and exactly, in rational arithmetic, of the ellipsoid as written.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize
from scipy.spatial import ConvexHull
from test_fit import random_rotation

from meshcol.collision.fit import (
    CONTAINMENT_MARGIN,
    ELLIPSOID_TOLERANCE,
    FitStatus,
    enclosing_ellipsoid,
    enclosing_sphere,
    fit_batch,
    primitive_volume,
    signed_distances,
)
from meshcol.types import Ellipsoid


def _norms(fit, points: np.ndarray) -> np.ndarray:
    """|diag(1 / a) R^T (p - c)| of each point, float64."""
    local = (points - fit.pose[:3, 3]) @ fit.pose[:3, :3]
    return np.linalg.norm(local / np.asarray(fit.primitive.semi_axes), axis=1)


def _inside_exactly(fit, points: np.ndarray) -> bool:
    """Every point inside the ellipsoid as written (its float pose and semi-axes taken as
    exact numbers), decided in rational arithmetic: no margin, no rounding."""
    rotation = [[Fraction(float(x)) for x in row] for row in fit.pose[:3, :3]]
    center = [Fraction(float(x)) for x in fit.pose[:3, 3]]
    axes = [Fraction(float(a)) for a in fit.primitive.semi_axes]
    for p in points:
        e = [Fraction(float(x)) - c for x, c in zip(p, center)]
        local = [sum(rotation[i][k] * e[i] for i in range(3)) for k in range(3)]
        if sum((local[k] / axes[k]) ** 2 for k in range(3)) > 1:
            return False
    return True


def _unit_ball(d: int) -> float:
    return math.pi ** (d / 2) / math.gamma(d / 2 + 1)


def _khachiyan(points: np.ndarray, iterations: int = 5000) -> tuple[float, float]:
    """Plain Khachiyan (1996): (volume of its ellipsoid scaled to hold every point, the dual
    lower bound of the minimum volume from its weights)."""
    n, d = points.shape
    q = np.c_[points, np.ones(n)]
    u = np.full(n, 1.0 / n)
    for _ in range(iterations):
        m = np.einsum("ij,jk,ik->i", q, np.linalg.inv(q.T @ (u[:, None] * q)), q)
        j = int(np.argmax(m))
        step = (m[j] - d - 1) / ((d + 1) * (m[j] - 1))
        if step <= 1e-13:
            break
        u *= 1 - step
        u[j] += step
    c = u @ points
    s = (points - c).T @ (u[:, None] * (points - c))
    k2 = np.max(np.einsum("ij,jk,ik->i", points - c, np.linalg.inv(s), points - c))
    ball = _unit_ball(d)
    return ball * math.sqrt(np.linalg.det(s * k2)), ball * math.sqrt(np.linalg.det(s * d))


def _slsqp(points: np.ndarray) -> float:
    """The primal problem (min -log det L subject to |L^T (p - c)| <= 1) by SLSQP from the
    covariance ellipsoid; its answer scaled to hold every point: an upper bound."""
    n, d = points.shape
    c0 = points.mean(axis=0)
    s0 = np.cov((points - c0).T)
    k = np.max(np.einsum("ij,jk,ik->i", points - c0, np.linalg.inv(s0), points - c0))
    low = np.tril_indices(d)
    z0 = np.r_[np.linalg.cholesky(np.linalg.inv(s0 * k * 1.01))[low], c0]

    def unpack(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lower = np.zeros((d, d))
        lower[low] = z[: len(low[0])]
        return lower, z[len(low[0]) :]

    def objective(z: np.ndarray) -> float:
        return -float(np.sum(np.log(np.abs(np.diag(unpack(z)[0])))))

    def room(z: np.ndarray) -> np.ndarray:
        lower, c = unpack(z)
        y = (points - c) @ lower
        return 1.0 - np.sum(y * y, axis=1)

    result = minimize(
        objective,
        z0,
        constraints=[{"type": "ineq", "fun": room}],
        method="SLSQP",
        tol=1e-15,
        options={"maxiter": 2000},
    )
    lower, c = unpack(result.x)
    k = np.max(np.linalg.norm((points - c) @ lower, axis=1))
    return _unit_ball(d) * k**d / abs(float(np.prod(np.diag(lower))))


def _cloud(seed: int, n: int) -> np.ndarray:
    """Hull vertices of a random elongated cloud, rotated and moved."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3)) * rng.uniform(0.2, 3.0, 3)
    points = points @ random_rotation(seed).T + rng.normal(size=3) * 5
    return points[ConvexHull(points).vertices]


# ---------------------------------------------------------------------------------------------
# Known answers


@pytest.mark.parametrize("seed", range(4))
def test_points_on_a_known_ellipsoid_give_that_ellipsoid(seed: int) -> None:
    rng = np.random.default_rng(seed)
    axes = np.sort(rng.uniform(0.05, 4.0, 3))[::-1]
    rotation, center = random_rotation(100 + seed), rng.normal(size=3) * 10
    directions = rng.normal(size=(300, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    # +-e_i with weights 1/6 satisfy John's conditions: no smaller ellipsoid holds them
    directions = np.concatenate([directions, np.eye(3), -np.eye(3)])
    points = (directions * axes) @ rotation.T + center
    fit = enclosing_ellipsoid(points)
    assert fit.status == FitStatus.OK
    truth = 4.0 / 3.0 * math.pi * float(np.prod(axes))
    assert truth * (1 - 1e-12) <= fit.volume <= truth * (1 + ELLIPSOID_TOLERANCE) * (1 + 1e-7)
    # volume within 1e-6 puts each axis within about its square root
    assert np.asarray(fit.primitive.semi_axes) == pytest.approx(axes, rel=3e-3)
    assert fit.pose[:3, 3] == pytest.approx(center, abs=3e-3 * axes[0])
    alignment = np.abs(fit.pose[:3, :3].T @ rotation)
    assert np.all(np.max(alignment, axis=1) > 0.999)
    assert np.max(_norms(fit, points)) <= 1.0
    assert _inside_exactly(fit, points)


def test_a_box_has_its_ellipsoid_scaled_by_root_three() -> None:
    size = np.array([3.0, 1.0, 0.4])
    corners = np.array(np.meshgrid(*[[-0.5, 0.5]] * 3)).reshape(3, -1).T * size
    rotation = random_rotation(9)
    fit = enclosing_ellipsoid(corners @ rotation.T + [1.0, 2.0, -3.0])
    expected = 0.5 * np.sqrt(3.0) * size
    assert np.asarray(fit.primitive.semi_axes) == pytest.approx(expected, rel=1e-3)
    truth = 4.0 / 3.0 * math.pi * float(np.prod(expected))
    assert truth * (1 - 1e-12) <= fit.volume <= truth * (1 + ELLIPSOID_TOLERANCE) * (1 + 1e-7)
    assert fit.pose[:3, 3] == pytest.approx([1.0, 2.0, -3.0], abs=1e-3)


def test_a_regular_tetrahedron_has_its_circumscribed_sphere() -> None:
    tetra = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])
    fit = enclosing_ellipsoid(tetra)
    assert np.asarray(fit.primitive.semi_axes) == pytest.approx([math.sqrt(3.0)] * 3, rel=1e-3)
    assert fit.volume >= 4.0 / 3.0 * math.pi * 3.0**1.5 * (1 - 1e-12)


# ---------------------------------------------------------------------------------------------
# Against independent references


#: The seeds of a parametrized test beyond the first: the full lane only.
SEEDS = [0, *(pytest.param(s, marks=pytest.mark.slow) for s in (1, 2))]


@pytest.mark.parametrize("seed", SEEDS)
def test_volume_is_within_the_tolerance_of_independent_references(seed: int) -> None:
    points = _cloud(seed, 40)
    fit = enclosing_ellipsoid(points)
    upper, lower = _khachiyan(points)
    # never below the minimum (the references' dual bound), never worse than either
    # reference's enclosing ellipsoid by more than the tolerance
    assert fit.volume >= lower
    assert fit.volume <= upper * (1 + ELLIPSOID_TOLERANCE)
    assert fit.volume <= _slsqp(points) * (1 + ELLIPSOID_TOLERANCE) * (1 + 1e-7)
    assert fit.volume <= enclosing_sphere(points).volume * (1 + ELLIPSOID_TOLERANCE)
    assert np.max(_norms(fit, points)) <= 1.0
    assert _inside_exactly(fit, points)


@pytest.mark.parametrize("seed", SEEDS)
def test_a_flat_set_has_its_plane_ellipse_as_thin_as_the_margin(seed: int) -> None:
    rng = np.random.default_rng(seed)
    flat = rng.normal(size=(25, 2)) * [2.0, 0.5]
    flat = flat[ConvexHull(flat).vertices]
    rotation, center = random_rotation(seed), rng.normal(size=3)
    points = np.c_[flat, np.zeros(len(flat))] @ rotation.T + center
    fit = enclosing_ellipsoid(points)
    a, b, c = fit.primitive.semi_axes
    extent = float(np.max(np.ptp(points, axis=0)))
    assert c <= 10 * CONTAINMENT_MARGIN * extent
    _, lower = _khachiyan(flat)
    area = math.pi * a * b
    assert lower <= area <= _slsqp(flat) * (1 + ELLIPSOID_TOLERANCE) * (1 + 1e-7)
    assert abs(fit.pose[:3, 2] @ rotation[:, 2]) == pytest.approx(1.0, abs=1e-9)
    assert _inside_exactly(fit, points)


def test_segments_points_and_bad_sets() -> None:
    line = np.outer(np.linspace(-1.0, 2.0, 7), [1.0, 2.0, 2.0]) + [0.5, 0.0, 0.0]
    point = np.tile([[1.0, 2.0, 3.0]], (4, 1))
    nan = _cloud(1, 30)
    nan[2, 0] = np.nan
    batch = fit_batch([line, point, nan, np.zeros((0, 3)), _cloud(2, 30)], "ellipsoid")
    assert list(batch.status[:, 0]) == [
        FitStatus.OK,
        FitStatus.OK,
        FitStatus.INVALID_INPUT,
        FitStatus.INVALID_INPUT,
        FitStatus.OK,
    ]
    segment = batch.fit(0, "ellipsoid")
    margin = CONTAINMENT_MARGIN * 9.0  # times the extent: on each semi-axis, twice at most
    assert 4.5 <= segment.primitive.semi_axes[0] <= 4.5 + 2 * margin  # half of the length 9
    assert segment.primitive.semi_axes[2] <= 2 * margin
    assert abs(segment.pose[:3, 0] @ [1 / 3, 2 / 3, 2 / 3]) == pytest.approx(1.0, abs=1e-12)
    assert segment.pose[:3, 3] == pytest.approx([1.0, 1.0, 1.0], abs=1e-9)
    for h, points in enumerate((line, point)):
        fit = batch.fit(h, "ellipsoid")
        local = (points - fit.pose[:3, 3]) @ fit.pose[:3, :3]
        assert np.max(signed_distances(fit.primitive, local)) <= 0.0
        assert _inside_exactly(fit, points)
    assert np.all(np.isnan(batch.params[2:4, 0]))


# ---------------------------------------------------------------------------------------------
# Invariants


coordinates = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(5, 60), st.floats(1e-3, 1e3))
def test_rigid_motions_scaling_and_linear_maps_move_the_ellipsoid_with_the_points(
    seed: int, n: int, scale: float
) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3)) * rng.uniform(0.1, 2.0, 3)
    rotation, shift = random_rotation(seed % 997), rng.normal(size=3) * 10
    base = enclosing_ellipsoid(points)
    moved = enclosing_ellipsoid(points @ rotation.T + shift)
    scaled = enclosing_ellipsoid(points * scale)
    tolerance = 1 + 2 * ELLIPSOID_TOLERANCE + 1e-7
    assert moved.volume / base.volume == pytest.approx(1.0, abs=tolerance - 1)
    assert scaled.volume / (base.volume * scale**3) == pytest.approx(1.0, abs=tolerance - 1)
    size = float(base.primitive.semi_axes[0])
    axes = np.asarray(base.primitive.semi_axes)
    assert np.asarray(moved.primitive.semi_axes) == pytest.approx(axes, rel=3e-3, abs=3e-3 * size)
    assert np.asarray(scaled.primitive.semi_axes) == pytest.approx(
        axes * scale, rel=3e-3, abs=3e-3 * size * scale
    )
    expected = rotation @ base.pose[:3, 3] + shift
    assert moved.pose[:3, 3] == pytest.approx(expected, abs=3e-3 * size)
    # any linear map (aspect kept within 100, so that the margin stays negligible): the
    # minimum ellipsoid's volume scales by |det|
    linear = rotation @ np.diag(10.0 ** rng.uniform(-1.0, 1.0, 3))
    mapped = enclosing_ellipsoid(points @ linear.T)
    ratio = mapped.volume / (base.volume * abs(np.linalg.det(linear)))
    assert ratio == pytest.approx(1.0, abs=3 * ELLIPSOID_TOLERANCE)
    for fit, cloud in (
        (base, points),
        (moved, points @ rotation.T + shift),
        (scaled, points * scale),
    ):
        assert np.max(_norms(fit, cloud)) <= 1.0
        assert fit.volume == pytest.approx(primitive_volume(fit.primitive), rel=1e-12)
        assert fit.volume <= enclosing_sphere(cloud).volume * (1 + ELLIPSOID_TOLERANCE)
        assert isinstance(fit.primitive, Ellipsoid)


def test_the_tolerance_mirrors_the_core() -> None:
    from meshcol._native import core
    from meshcol.collision.fit import AUTO_SHAPES, FIT_SHAPES

    assert core.defaults.fit_ellipsoid_tolerance == ELLIPSOID_TOLERANCE
    assert FIT_SHAPES.index("ellipsoid") == 4  # the core's FitShape::ELLIPSOID
    assert "ellipsoid" not in AUTO_SHAPES
