"""Answers at every magnitude a double holds: exact, or a status that says they are not.

GJK and EPA form squared norms and products of several lengths; at 1e155 those overflow, and a
sphere that far from a box came out at distance 0, intersecting, status CONVERGED. Pairs whose
lengths leave [2^-100, 2^100] are now moved and scaled by a power of two (exact) first. The
oracle is analytic, in exact rational arithmetic on the doubles actually passed (positions near
a large common offset are rounded when they are written down; the answer is that of the
rounded input).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import meshcol
from meshcol import (
    Box,
    ConvexSet,
    Sphere,
    distance,
    intersects,
    penetration,
    signed_distance,
    signed_distance_batch,
    time_of_impact,
)
from meshcol.types import Status, TimeOfImpactStatus

RELATIVE = 1e-12  # of the pair's extent (centre distance plus sizes)


def translation(x, y=0.0, z=0.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = [x, y, z]
    return m


def rounded(value: Fraction) -> float:
    """The float nearest an exact value (inf beyond the largest double)."""
    try:
        return float(value)
    except OverflowError:
        return math.copysign(math.inf, value)


def centre_gap(centre_a, centre_b) -> float:
    """Largest coordinate of the exact difference of two centres as given."""
    return max(rounded(abs(Fraction(b) - Fraction(a))) for a, b in zip(centre_a, centre_b))


def exact_box_sphere_distance(half, centre_a, centre_b, radius) -> float:
    """Distance of an axis-aligned box (half extents, centre) and a sphere, from the exact
    difference of the centres as given (Fractions): each excess over the box rounded once,
    then ``math.hypot`` (correctly scaled, no overflow in the squares)."""
    excess = [
        rounded(max(Fraction(0), abs(Fraction(cb) - Fraction(ca)) - Fraction(h)))
        for h, ca, cb in zip(half, centre_a, centre_b)
    ]
    return max(0.0, math.hypot(*excess) - radius)


def exact_box_box_depth(half_a, half_b, centre_a, centre_b) -> Fraction:
    """Penetration depth of two axis-aligned boxes: the least overlap over the three axes."""
    overlaps = [
        Fraction(ha) + Fraction(hb) - abs(Fraction(cb) - Fraction(ca))
        for ha, hb, ca, cb in zip(half_a, half_b, centre_a, centre_b)
    ]
    return min(overlaps)


def test_sphere_far_from_box_is_far():
    # The defect of issue #12: at 1e155 the distance was 0.0, intersects True, status OK.
    for x in (1e155, 1e200, 1e300, 1.7e308):
        r = distance(Box((1, 1, 1)), Sphere(0.5), None, translation(x))
        assert r.status == Status.CONVERGED
        assert r.distance == pytest.approx(x - 1.0, rel=1e-15)
        assert not intersects(Box((1, 1, 1)), Sphere(0.5), None, translation(x))
        p = penetration(Box((1, 1, 1)), Sphere(0.5), None, translation(x))
        assert p.depth == 0.0 and p.status == Status.CONVERGED
        s = signed_distance(Box((1, 1, 1)), Sphere(0.5), None, translation(x))
        assert s.signed_distance == pytest.approx(x, rel=1e-15)


def test_distance_beyond_the_largest_double_is_out_of_range():
    r = distance(Box((1, 1, 1)), Sphere(0.5), translation(-1.5e308), translation(1.5e308))
    assert r.status == Status.OUT_OF_RANGE
    # The boolean is still decided: they are far apart.
    assert not intersects(Box((1, 1, 1)), Sphere(0.5), translation(-1.5e308), translation(1.5e308))


def test_time_of_impact_at_large_and_tiny_scales():
    for s in (1e-300, 1e-160, 1.0, 1e160, 1e300):
        r = time_of_impact(
            Box((s, s, s)),
            Sphere(0.25 * s),
            None,
            None,
            translation(5 * s),
            translation(0.0),
            tolerance=1e-9 * s,
        )
        assert r.status == TimeOfImpactStatus.HIT
        # Contact when the sphere's centre reaches 0.75 s: t = 4.25 / 5.
        assert r.time_of_impact == pytest.approx(0.85, abs=1e-8)
        assert r.point[0] == pytest.approx(0.5 * s, rel=1e-6)


magnitudes = st.integers(-300, 300).map(lambda e: 10.0**e)
offsets = st.one_of(st.just(0.0), st.integers(-300, 307).map(lambda e: 10.0**e))
signs = st.sampled_from([-1.0, 1.0])
unit_reals = st.floats(0.05, 1.0)


@settings(deadline=None)
@given(
    scale=magnitudes,
    offset=offsets,
    offset_sign=signs,
    half=st.tuples(unit_reals, unit_reals, unit_reals),
    radius=unit_reals,
    direction=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
    far=st.sampled_from([1.0, 1e10, 1e100, 1e200]),
)
def test_box_sphere_distance_is_exact_or_flagged(
    scale, offset, offset_sign, half, radius, direction, far
):
    centre_a = np.full(3, offset_sign * offset)
    with np.errstate(over="ignore"):
        centre_b = centre_a + np.asarray(direction) * scale * far
    if not np.all(np.isfinite(centre_b)):
        return  # not a position a double holds
    h = np.asarray(half) * scale
    r_ = radius * scale
    box, sphere = Box(tuple(2 * h)), Sphere(r_)
    pa, pb = translation(*centre_a), translation(*centre_b)
    got = distance(box, sphere, pa, pb)
    if got.status != Status.CONVERGED:
        assert got.status == Status.OUT_OF_RANGE
        return
    expected = exact_box_sphere_distance(h, centre_a, centre_b, r_)
    extent = (
        float(
            np.abs(
                np.array(
                    [Fraction(b) - Fraction(a) for a, b in zip(centre_a, centre_b)], dtype=float
                )
            ).max()
        )
        + float(np.abs(h).max())
        + r_
    )
    assert abs(got.distance - expected) <= RELATIVE * extent
    if expected > RELATIVE * extent:
        assert not intersects(box, sphere, pa, pb)
    sd = signed_distance(box, sphere, pa, pb)
    assert sd.status in (Status.CONVERGED, Status.OUT_OF_RANGE)
    if sd.status == Status.CONVERGED and expected > RELATIVE * extent:
        assert abs(sd.signed_distance - expected) <= RELATIVE * extent


@settings(deadline=None)
@given(
    scale=magnitudes,
    offset=offsets,
    offset_sign=signs,
    half_a=st.tuples(unit_reals, unit_reals, unit_reals),
    half_b=st.tuples(unit_reals, unit_reals, unit_reals),
    fraction=st.tuples(st.floats(-0.9, 0.9), st.floats(-0.9, 0.9), st.floats(-0.9, 0.9)),
)
def test_box_box_penetration_is_exact_or_flagged(
    scale, offset, offset_sign, half_a, half_b, fraction
):
    # Overlapping boxes: b's centre a fraction of the way to touching on every axis.
    ha, hb = np.asarray(half_a) * scale, np.asarray(half_b) * scale
    centre_a = np.full(3, offset_sign * offset)
    centre_b = centre_a + np.asarray(fraction) * (ha + hb)
    a, b = Box(tuple(2 * ha)), Box(tuple(2 * hb))
    pa, pb = translation(*centre_a), translation(*centre_b)
    got = penetration(a, b, pa, pb)
    expected = exact_box_box_depth(ha, hb, centre_a, centre_b)
    extent = float(np.abs(ha + hb).max())
    if expected <= 0:
        return  # rounding of the offset pushed them apart: not an overlap case
    assert got.status in (Status.CONVERGED, Status.OUT_OF_RANGE)
    if got.status == Status.CONVERGED:
        assert abs(got.depth - float(expected)) <= RELATIVE * extent
        assert intersects(a, b, pa, pb)


@settings(deadline=None)
@given(
    scales=st.lists(magnitudes, min_size=2, max_size=12),
    offset=offsets,
)
def test_batch_equals_the_analytic_answers(scales, offset):
    # One batch mixing every magnitude: box k and sphere k, 3 sizes apart along x.
    shapes, poses, pairs, expected = [], [], [], []
    for k, s in enumerate(scales):
        shapes += [Box((s, s, s)), Sphere(0.5 * s)]
        poses += [translation(offset), translation(offset + 3.0 * s)]
        pairs.append([2 * k, 2 * k + 1])
        expected.append(
            exact_box_sphere_distance(
                [0.5 * s] * 3, [offset, 0, 0], [offset + 3.0 * s, 0, 0], 0.5 * s
            )
        )
    r = signed_distance_batch(ConvexSet.from_shapes(shapes), np.stack(poses), pairs)
    for k, s in enumerate(scales):
        if r.status[k] == Status.CONVERGED:
            if expected[k] > RELATIVE * 4 * s:
                assert abs(r.signed_distance[k] - expected[k]) <= RELATIVE * 4 * s
            else:  # the offset swallowed the gap (1e17 + 3 == 1e17): they overlap
                assert r.signed_distance[k] <= RELATIVE * 4 * s
        else:
            assert r.status[k] == Status.OUT_OF_RANGE


@settings(deadline=None)
@given(scale=magnitudes, offset=offsets, y=st.floats(-0.4, 0.4), start=st.floats(2.0, 20.0))
def test_time_of_impact_is_exact_or_flagged(scale, offset, y, start):
    # A sphere (radius 0.25 s) flying along -x at a unit box (half 0.5 s): contact when its
    # centre reaches 0.75 s (its y offset keeps the contact on the face).
    s = scale
    b0 = translation(offset + start * s, y * s)
    b1 = translation(offset - start * s, y * s)
    r = time_of_impact(
        Box((s, s, s)),
        Sphere(0.25 * s),
        translation(offset),
        translation(offset),
        b0,
        b1,
        tolerance=1e-9 * s,
    )
    # The positions as a double holds them (1e17 + 2 is 1e17): the exact oracle is theirs.
    x0 = Fraction(b0[0, 3]) - Fraction(offset)
    x1 = Fraction(b1[0, 3]) - Fraction(offset)
    contact = Fraction(0.75) * Fraction(s)
    if r.status == TimeOfImpactStatus.INVALID_INPUT:
        return  # the tolerance is under the precision of the offset positions
    if x0 <= contact + Fraction(1e-9) * Fraction(s):
        assert r.status == TimeOfImpactStatus.OVERLAPPED_AT_START
        return
    if x1 >= contact:
        assert r.status == TimeOfImpactStatus.SEPARATED
        return
    assert r.status == TimeOfImpactStatus.HIT
    expected = float((x0 - contact) / (x0 - x1))
    assert r.time_of_impact <= expected + 1e-12
    assert r.time_of_impact == pytest.approx(expected, abs=1e-8)


def test_denormal_shapes():
    # Sizes below the smallest normal double are still lengths.
    s = 1e-310
    r = distance(Box((s, s, s)), Sphere(0.5 * s), translation(0.0), translation(3 * s))
    assert r.status == Status.CONVERGED
    assert r.distance == pytest.approx(2 * s, rel=1e-6)


def test_out_of_range_is_a_named_status():
    assert meshcol.Status.OUT_OF_RANGE == 5


def test_mesh_queries_out_of_their_range_say_so():
    # The mesh hierarchies keep float boxes and squared distances: beyond about 1e30 the pair
    # gets OUT_OF_RANGE (it was distance inf, CONVERGED at 1e155), within it the answer.
    import trimesh

    from meshcol import MeshSet, mesh_distance, mesh_intersects_batch

    box = trimesh.creation.box((1, 1, 1))
    octahedron = trimesh.creation.icosphere(0, radius=0.5)
    r = mesh_distance(box, octahedron, None, translation(1e29))
    assert r.status == Status.CONVERGED and r.distance == pytest.approx(1e29, rel=1e-12)
    for x in (1e31, 1e155, 1e300):
        r = mesh_distance(box, octahedron, None, translation(x))
        assert r.status == Status.OUT_OF_RANGE and np.isnan(r.distance)
        meshes = MeshSet.from_arrays([box, octahedron])
        hit = mesh_intersects_batch(meshes, np.stack([np.eye(4), translation(x)]), [[0, 1]])
        assert hit.status[0] == Status.OUT_OF_RANGE and not hit.intersecting[0]


@pytest.mark.parametrize("scale", [1e-200, 1.0, 1e200])
def test_turning_time_of_impact_is_scale_free(scale):
    # A bar (a box primitive, 4 x 0.1 x 0.1, centred) turning a quarter turn about z into a
    # sphere (conservative advancement): the fraction is the same at every scale, the contact
    # point scales with it.
    from meshcol import Spin

    bar = Box((4.0 * scale, 0.1 * scale, 0.1 * scale))
    ball = translation(0.0, 1.5 * scale)
    end = np.eye(4)
    end[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    r = time_of_impact(
        bar,
        Sphere(0.1 * scale),
        np.eye(4),
        end,
        ball,
        ball,
        spin_a=Spin([0, 0, 0.5 * math.pi]),
        tolerance=1e-9 * scale,
    )
    assert r.status == TimeOfImpactStatus.HIT
    expected = (0.5 * math.pi - math.asin(0.15 / 1.5)) / (0.5 * math.pi)
    assert r.time_of_impact == pytest.approx(expected, abs=1e-7)
    assert math.hypot(*r.point) == pytest.approx(1.5 * scale * math.cos(math.asin(0.1)), rel=1e-3)
