"""The in-sphere of a polytope (``core.inscribed_balls``, :func:`inscribed_balls`) against
analytic answers (boxes, a regular octahedron, a tetrahedron's 3V/A, a slab), against HiGHS
(``scipy.optimize.linprog``, the reference it replaced: radius, and the lexicographic centre
of tests/target_oracle.py where the ball can slide) on random polytopes, on degenerate ones
(flat, needles, 1e-9-thin, far from the origin), and the status path (what the core does
not settle is settled by HiGHS, never guessed)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from target_oracle import inscribed_ball as oracle_ball

from meshcol._native import core
from meshcol.collision import limits
from meshcol.collision.hull import exact_hull
from meshcol.collision.limits import inscribed_balls, measure_hull, measure_hulls
from meshcol.types import Status


def box_planes(lo, hi) -> np.ndarray:
    """The six unit-normal planes (n, d) of the box [lo, hi]."""
    rows = []
    for axis in range(3):
        n = np.zeros(3)
        n[axis] = 1.0
        rows.append([*n, -hi[axis]])
        rows.append([*-n, lo[axis]])
    return np.array(rows, dtype=np.float64)


def hull_planes(points: np.ndarray) -> np.ndarray:
    """The polygon planes measure_hull reads (unit normals, offsets)."""
    m = measure_hull(exact_hull(points), ball=False)
    return np.hstack([m["normals"], m["offsets"][:, None]])


def one(planes: np.ndarray) -> tuple[np.ndarray, float, int]:
    status, centres, radii = core.inscribed_balls(planes, np.array([0, len(planes)]))
    return centres[0], float(radii[0]), int(status[0])


def least_distance(planes: np.ndarray, centre: np.ndarray) -> float:
    return float((-(planes[:, :3] @ centre + planes[:, 3])).min())


@pytest.mark.parametrize(
    ("lo", "hi"),
    [((-1, -1, -1), (1, 1, 1)), ((10, 20, 30), (12, 26, 31)), ((0, 0, 0), (5, 1e-9, 3))],
)
def test_box_ball_is_half_the_least_side_at_the_centre(lo, hi) -> None:
    centre, radius, status = one(box_planes(lo, hi))
    half = 0.5 * min(h - low for h, low in zip(hi, lo, strict=True))
    assert status == Status.CONVERGED
    assert radius == pytest.approx(half, rel=1e-12)
    # the lexicographic centre of a box is its centre, however long its sides
    assert centre == pytest.approx(0.5 * (np.array(lo) + np.array(hi)), abs=1e-12)


def test_regular_octahedron_ball() -> None:
    points = np.vstack([np.eye(3), -np.eye(3)])
    centre, radius, status = one(hull_planes(points))
    assert status == Status.CONVERGED
    assert radius == pytest.approx(1 / np.sqrt(3), rel=1e-14)
    assert np.abs(centre).max() < 1e-14


def test_tetrahedron_ball_is_3v_over_a_at_the_incentre() -> None:
    p = np.array([[0.3, -0.2, 0.1], [2.0, 0.1, -0.4], [0.5, 1.7, 0.2], [0.4, 0.3, 1.9]])
    areas = np.array(
        [
            0.5 * np.linalg.norm(np.cross(*(np.delete(p, k, 0)[1:] - np.delete(p, k, 0)[0])))
            for k in range(4)
        ]
    )
    volume = abs(np.linalg.det(p[1:] - p[0])) / 6
    centre, radius, status = one(hull_planes(p))
    assert status == Status.CONVERGED
    assert radius == pytest.approx(3 * volume / areas.sum(), rel=1e-13)
    assert centre == pytest.approx(areas @ p / areas.sum(), abs=1e-13)


def test_slab_half_space_empty_and_bad_planes_are_statuses() -> None:
    slab = np.array([[1.0, 0, 0, -1], [-1, 0, 0, -1]])
    _, radius, status = one(slab)
    assert status == Status.DEGENERATE and radius == pytest.approx(1.0)
    assert one(np.array([[1.0, 0, 0, -1]]))[2] == Status.DEGENERATE  # unbounded
    empty = np.vstack([box_planes((-1, -1, -1), (1, 1, 1)), [[1.0, 0, 0, 2.0]]])
    _, radius, status = one(empty)  # x <= -2 inside x >= -1: nothing
    assert status == Status.DEGENERATE and radius == 0.0
    nan = box_planes((-1, -1, -1), (1, 1, 1))
    nan[2, 3] = np.nan
    assert one(nan)[2] == Status.INVALID_INPUT
    assert one(np.zeros((0, 4)))[2] == Status.INVALID_INPUT


def test_offsets_are_checked() -> None:
    with pytest.raises(ValueError, match="offsets"):
        core.inscribed_balls(box_planes((0, 0, 0), (1, 1, 1)), np.array([0, 7]))


def test_what_the_core_does_not_settle_highs_does(monkeypatch) -> None:
    planes = hull_planes(np.random.default_rng(3).normal(size=(30, 3)))
    offsets = np.array([0, len(planes)])
    real = core.inscribed_balls

    def unsettled(p, o, threads=0):
        status, centres, radii = real(p, o, threads)
        status[:] = int(Status.MAX_ITERATIONS)
        centres[:] = 7.0
        return status, centres, radii

    monkeypatch.setattr(core, "inscribed_balls", unsettled)
    centres, radii, status = inscribed_balls(planes, offsets)
    reference = limits._inscribed_ball_highs(planes[:, :3], planes[:, 3])
    assert status[0] == Status.MAX_ITERATIONS  # reported
    assert radii[0] == reference[1] and np.array_equal(centres[0], reference[0])


def _cloud(seed: int, n: int, kind: str) -> np.ndarray:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3))
    if kind == "needle":
        points[:, 1:] *= 1e-3
    elif kind == "thin":
        points[:, 2] *= 1e-9
    elif kind == "prism":  # a polygon extruded: the ball slides across the prism
        ring = rng.normal(size=(n, 2))
        points = np.vstack(
            [np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.full(n, 0.2)])]
        )
    elif kind == "far":
        points = points + 1e6
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return points @ rotation.T


@settings(max_examples=120, deadline=None)
@given(
    st.integers(0, 2**31 - 1),
    st.integers(5, 60),
    st.sampled_from(["random", "needle", "thin", "prism", "far"]),
)
def test_ball_against_highs(seed: int, n: int, kind: str) -> None:
    points = _cloud(seed, n, kind)
    hull = exact_hull(points)
    if hull.dimension < 3:
        return
    planes = hull_planes(points)
    centre, radius, status = one(planes)
    assert status == Status.CONVERGED
    scale = float(np.abs(points).max())
    rounding = 1e-12 * scale
    # the ball is inside, and as large as HiGHS's (its centre's own least distance)
    assert least_distance(planes, centre) == pytest.approx(radius, abs=rounding)
    reference, _ = limits._inscribed_ball_highs(planes[:, :3], planes[:, 3])
    assert radius >= least_distance(planes, reference) - rounding
    # the same centre as the oracle's lexicographic one, by HiGHS stages
    expected, expected_radius = oracle_ball(planes[:, :3], planes[:, 3])
    assert radius == pytest.approx(expected_radius, rel=1e-6, abs=rounding)
    extent = float(np.ptp(points, axis=0).max())
    assert np.linalg.norm(centre - expected) <= 1e-5 * extent + rounding


def test_batch_is_the_loop_of_singles_and_measures_the_same() -> None:
    rng = np.random.default_rng(11)
    hulls = [exact_hull(rng.normal(size=(int(rng.integers(5, 40)), 3))) for _ in range(200)]
    batched = measure_hulls(hulls)
    planes = [np.hstack([r["normals"], r["offsets"][:, None]]) for r in batched]
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in planes])])
    status, centres, radii = core.inscribed_balls(np.vstack(planes), offsets, 2)
    for n, (hull, row) in enumerate(zip(hulls, batched, strict=True)):
        single = measure_hull(hull)
        for key in ("inradius", "oblong_ratio", "thickness", "polygons", "max_faces_per_vertex"):
            assert single[key] == row[key]
        c, r, s = one(planes[n])
        assert (s, r) == (status[n], radii[n]) and np.array_equal(c, centres[n])
