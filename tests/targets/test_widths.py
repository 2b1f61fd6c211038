"""Hull widths by support climbs (``core.hull_widths``) against a brute-force maximum over
every vertex, bit for bit."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol._native import core
from meshcol.collision.hull import exact_hull


def fused(a: float, b: float, c: float) -> float:
    """``fma(a, b, c)``, correctly rounded (exact rationals, then one rounding)."""
    return float(Fraction(a) * Fraction(b) + Fraction(c))


def projection(p: np.ndarray, d: np.ndarray) -> float:
    """The projection the widths take: ``fma(d.z, p.z, fma(d.y, p.y, d.x * p.x))``."""
    return fused(d[2], p[2], fused(d[1], p[1], d[0] * p[0]))


def brute_widths(vertices: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Largest minus smallest projection over every vertex. Each vertex is first projected
    in plain floating point, which is within a few rounding errors of the fused chain; the
    vertices within a million of those of the extremes are then projected exactly."""
    plain = directions @ vertices.T
    slack = 1e-10 * (np.abs(directions) @ np.abs(vertices).T).max(axis=1)
    widths = np.empty(len(directions))
    for i, d in enumerate(directions):
        top = np.nonzero(plain[i] >= plain[i].max() - slack[i])[0]
        bottom = np.nonzero(plain[i] <= plain[i].min() + slack[i])[0]
        widths[i] = max(projection(vertices[j], d) for j in top) - min(
            projection(vertices[j], d) for j in bottom
        )
    return widths


def plane_normals(hull) -> np.ndarray:
    return np.ascontiguousarray(hull.equations[:, :3])


def unit(rng: np.random.Generator, n: int) -> np.ndarray:
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


@st.composite
def hull_points(draw) -> np.ndarray:
    """Points whose hulls climb differently: round (many vertices, small steps), boxy (whole
    faces of exactly coplanar vertices, ties), far from the origin (rounding), flattened."""
    seed = draw(st.integers(0, 2**32 - 1))
    n = draw(st.integers(8, 400))
    kind = draw(st.sampled_from(["sphere", "grid", "far", "slab"]))
    rng = np.random.default_rng(seed)
    if kind == "grid":
        steps = draw(st.integers(2, 7))
        p = rng.integers(0, steps + 1, size=(n, 3)).astype(float) / steps
        p = np.vstack([p, [[0, 0, 0], [1, 1, 1], [1, 0, 0], [0, 1, 1]]])
    else:
        p = unit(rng, n) * rng.uniform(0.5, 1.0, size=(n, 1)) ** 0.1
    if kind == "far":
        p = p * draw(st.sampled_from([1e-3, 1.0, 1e4])) + rng.uniform(-1e3, 1e3, size=3)
    if kind == "slab":
        p[:, 2] *= draw(st.sampled_from([1e-2, 1e-5]))
    return p


@settings(max_examples=40, deadline=None)
@given(hull_points(), st.integers(0, 2**32 - 1))
def test_climbed_widths_are_the_brute_force_maximum_bit_for_bit(points, seed) -> None:
    hull = exact_hull(points)
    if hull.dimension < 3:
        return
    rng = np.random.default_rng(seed)
    directions = np.ascontiguousarray(np.vstack([plane_normals(hull), unit(rng, 40)]))
    widths = core.hull_widths(hull.vertices, hull.faces, directions)
    expected = brute_widths(hull.vertices, directions)
    assert widths.dtype == np.float64 and widths.shape == (len(directions),)
    np.testing.assert_array_equal(widths, expected)


def test_widths_of_a_box_are_its_extents() -> None:
    corners = np.array([[x, y, z] for x in (0, 2) for y in (0, 3) for z in (0, 5)], float)
    hull = exact_hull(corners)
    axes = np.eye(3)
    np.testing.assert_array_equal(core.hull_widths(hull.vertices, hull.faces, axes), [2, 3, 5])
    diagonal = np.array([[1.0, 1.0, 0.0]]) / np.sqrt(2.0)
    assert core.hull_widths(hull.vertices, hull.faces, diagonal)[0] == pytest.approx(
        5 / np.sqrt(2.0), abs=1e-14
    )


def test_widths_of_a_large_round_hull_match_the_brute_force() -> None:
    """A hull of 5,000 vertices, as ``measure_hull`` climbs it (above the size where the
    product of every normal with every vertex is taken instead)."""
    from meshcol.collision.limits import WIDTH_CLIMB_MIN_VERTICES, _widths

    rng = np.random.default_rng(11)
    hull = exact_hull(unit(rng, 5000) * [1.0, 0.7, 0.2] + [3.0, -1.0, 2.0])
    assert len(hull.vertices) > WIDTH_CLIMB_MIN_VERTICES
    directions = np.vstack([plane_normals(hull)[:400], unit(rng, 100)])
    widths = _widths(directions, hull.vertices, hull.faces)
    np.testing.assert_array_equal(widths, brute_widths(hull.vertices, directions))


def test_bad_faces_are_a_value_error() -> None:
    hull = exact_hull(unit(np.random.default_rng(2), 50))
    faces = hull.faces.copy()
    faces[3, 1] = len(hull.vertices)
    with pytest.raises(ValueError, match="faces must index the vertices"):
        core.hull_widths(hull.vertices, faces, np.eye(3))
    with pytest.raises(ValueError, match="vertices must be"):
        core.hull_widths(np.zeros((0, 3)), hull.faces, np.eye(3))
