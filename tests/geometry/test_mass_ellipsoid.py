"""Mass properties of an ellipsoid (meshcol.geometry.mass): closed forms where they exist
(volume, solid inertia, the area of spheroids, a flat ellipse's shell), the sphere's answers
for a round one, a fine tessellation, and the quadrature's own convergence."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import meshcol.geometry.mass as mass
from meshcol.geometry.mass import mass_properties, primitive_mass_properties
from meshcol.types import Ellipsoid, Sphere


def test_volume_and_solid_inertia_closed_forms() -> None:
    """V = 4/3 pi a b c (= 8 pi for 1, 2, 3); I_xx = V (b^2 + c^2) / 5."""
    p = primitive_mass_properties(Ellipsoid((1.0, 2.0, 3.0)))
    assert p.volume == pytest.approx(8.0 * math.pi, rel=1e-15)
    np.testing.assert_allclose(
        p.inertia, np.diag([13.0, 10.0, 5.0]) * 8.0 * math.pi / 5.0, rtol=1e-15, atol=0
    )
    assert p.center_of_mass.tolist() == [0.0, 0.0, 0.0]


def test_a_round_ellipsoid_is_the_sphere() -> None:
    e, s = (
        primitive_mass_properties(Ellipsoid((0.7, 0.7, 0.7))),
        primitive_mass_properties(Sphere(0.7)),
    )
    assert e.volume == pytest.approx(s.volume, rel=1e-15)
    assert e.area == pytest.approx(s.area, rel=1e-14)
    np.testing.assert_allclose(e.inertia, s.inertia, rtol=1e-14, atol=0)
    np.testing.assert_allclose(e.shell_inertia, s.shell_inertia, rtol=1e-13, atol=1e-300)


@pytest.mark.parametrize("a, c", [(1.0, 3.0), (1.0, 100.0), (2.0, 0.5), (1.0, 0.01)])
def test_spheroid_areas_closed_forms(a: float, c: float) -> None:
    """Prolate (c > a): 2 pi a^2 (1 + c asin(e) / (a e)); oblate: 2 pi a^2 (1 + (1 - e^2)
    atanh(e) / e), e the eccentricity."""
    if c > a:
        e = math.sqrt(1.0 - a * a / (c * c))
        expected = 2 * math.pi * a * a * (1.0 + c * math.asin(e) / (a * e))
    else:
        e = math.sqrt(1.0 - c * c / (a * a))
        expected = 2 * math.pi * a * a * (1.0 + (1.0 - e * e) * math.atanh(e) / e)
    for axes in [(a, a, c), (c, a, a), (a, c, a)]:
        assert primitive_mass_properties(Ellipsoid(axes)).area == pytest.approx(expected, rel=1e-13)


def test_a_flat_ellipse_has_two_sides() -> None:
    """Area 2 pi a b; shell moments of both sides: 2 (pi a b) a^2 / 4 about the long axis'
    perpendicular."""
    a, b = 2.0, 0.5
    p = primitive_mass_properties(Ellipsoid((a, 0.0, b)))
    plate = math.pi * a * b
    assert p.volume == 0.0
    assert p.area == pytest.approx(2.0 * plate, rel=1e-15)
    second = np.array([2.0 * plate * a * a / 4.0, 0.0, 2.0 * plate * b * b / 4.0])
    np.testing.assert_allclose(np.diag(p.shell_inertia), second.sum() - second, rtol=1e-15, atol=0)


@pytest.mark.parametrize("axes", [(0.3, 0.5, 0.4), (1.0, 0.2, 0.6)])
def test_a_fine_tessellation_converges_to_it(axes) -> None:
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=1.0)
    mesh = mass_properties(sphere.vertices * np.asarray(axes), sphere.faces)
    exact = primitive_mass_properties(Ellipsoid(axes))
    assert mesh.volume == pytest.approx(exact.volume, rel=1e-3)
    assert mesh.area == pytest.approx(exact.area, rel=1e-3)
    np.testing.assert_allclose(np.diag(mesh.inertia), np.diag(exact.inertia), rtol=2e-3)
    np.testing.assert_allclose(np.diag(mesh.shell_inertia), np.diag(exact.shell_inertia), rtol=2e-3)


@pytest.mark.parametrize(
    "axes", [(1.0, 2.0, 3.0), (1.0, 100.0, 1.0), (0.01, 1.0, 1.0), (1, 10, 100)]
)
def test_the_shell_quadrature_has_converged(axes, monkeypatch) -> None:
    """Four times the nodes in both angles change the shell moments by less than 1e-13."""
    used = primitive_mass_properties(Ellipsoid(axes)).shell_inertia
    monkeypatch.setattr(mass, "_ELLIPSOID_NODES", 4 * mass._ELLIPSOID_NODES)
    monkeypatch.setattr(mass, "_ELLIPSOID_AZIMUTHS", 4 * mass._ELLIPSOID_AZIMUTHS)
    mass._ellipsoid_rule.cache_clear()
    try:
        finer = primitive_mass_properties(Ellipsoid(axes)).shell_inertia
    finally:
        monkeypatch.undo()
        mass._ellipsoid_rule.cache_clear()
    np.testing.assert_allclose(np.diag(used), np.diag(finer), rtol=1e-13, atol=0)


def test_semi_axes_in_any_order_give_the_moments_in_that_order() -> None:
    p = primitive_mass_properties(Ellipsoid((0.3, 1.7, 0.9)))
    q = primitive_mass_properties(Ellipsoid((0.9, 0.3, 1.7)))
    np.testing.assert_allclose(
        np.diag(q.shell_inertia), np.diag(p.shell_inertia)[[2, 0, 1]], rtol=1e-13, atol=0
    )
