"""Time of impact: known answers, oracle cases, analytic spheres, dense-sampling properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Sphere,
    distance,
    distance_batch,
    interpolate_pose,
    time_of_impact,
    time_of_impact_batch,
)
from meshcol.types import TimeOfImpactStatus


def pose(position=(0.0, 0.0, 0.0), rotation=None) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = position
    return m


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_axis(axis, angle: float) -> np.ndarray:
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def quaternion_matrix(wxyz) -> np.ndarray:
    w, x, y, z = np.asarray(wxyz, dtype=float) / np.linalg.norm(wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


# ---------------------------------------------------------------------------------------------
# Known answers


def test_boxes_translation_face_contact():
    # Unit boxes, b from x = 3 to x = 0: faces meet when the centres are 1 apart, t = 2/3.
    r = time_of_impact(
        Box((1, 1, 1)), Box((1, 1, 1)), pose(), pose(), pose((3, 0, 0)), pose(), tolerance=1e-9
    )
    assert r.status == TimeOfImpactStatus.HIT
    assert r.time_of_impact == pytest.approx(2.0 / 3.0, abs=1e-9)
    assert r.time_of_impact <= 2.0 / 3.0
    np.testing.assert_allclose(r.normal, [1.0, 0.0, 0.0], atol=1e-12)
    assert r.point[0] == pytest.approx(0.5, abs=1e-8)


def test_spheres_head_on_closed_form():
    # a (r 0.5) from x = 0 to x = 2, b (r 0.25) resting at x = 2: contact at a = 1.25, t = 0.625.
    r = time_of_impact(
        Sphere(0.5), Sphere(0.25), pose(), pose((2, 0, 0)), pose((2, 0, 0)), pose((2, 0, 0))
    )
    assert r.status == TimeOfImpactStatus.HIT
    assert r.time_of_impact == pytest.approx(0.625, abs=1e-15)
    np.testing.assert_allclose(r.point, [1.75, 0, 0], atol=1e-15)
    np.testing.assert_allclose(r.normal, [1, 0, 0], atol=1e-15)


def test_receding_and_parallel_motion_are_separated():
    r = time_of_impact(
        Box((1, 1, 1)), Box((1, 1, 1)), pose(), pose((-1, 0, 0)), pose((2, 0, 0)), pose((2, 0, 0))
    )
    assert r.status == TimeOfImpactStatus.SEPARATED and r.time_of_impact is None
    r = time_of_impact(
        Box((1, 1, 1)), Box((1, 1, 1)), pose(), pose((0, 5, 0)), pose((2, 0, 0)), pose((2, 5, 0))
    )
    assert r.status == TimeOfImpactStatus.SEPARATED


def test_overlapped_at_start():
    r = time_of_impact(
        Box((1, 1, 1)), Sphere(1), pose(), pose((1, 0, 0)), pose((1, 0, 0)), pose((1, 0, 0))
    )
    assert r.status == TimeOfImpactStatus.OVERLAPPED_AT_START and r.time_of_impact == 0.0
    np.testing.assert_array_equal(r.normal, [0.0, 0.0, 0.0])


def test_invalid_input_and_bad_arguments():
    cs = ConvexSet.from_shapes([Box((1, 1, 1)), Box((1, 1, 1))])
    start = np.stack([pose(), pose((3, 0, 0))])
    end = start.copy()
    end[1, 0, 0] = np.nan
    r = time_of_impact_batch(cs, start, end, [[0, 1]])
    assert r.status[0] == TimeOfImpactStatus.INVALID_INPUT and np.isnan(r.time_of_impact[0])
    skew = start.copy()
    skew[0, :3, :3] *= 2.0  # not rigid
    assert (
        time_of_impact_batch(cs, skew, start, [[0, 1]]).status[0]
        == TimeOfImpactStatus.INVALID_INPUT
    )
    with pytest.raises(ValueError, match=r"tolerance must be finite and > 0, got 0"):
        time_of_impact_batch(cs, start, start, [[0, 1]], tolerance=0)
    with pytest.raises(ValueError, match=r"start_poses must be \(2, 4, 4\), got \(1, 4, 4\)"):
        time_of_impact_batch(cs, start[:1], start, [[0, 1]])
    with pytest.raises(ValueError, match=r"pairs: index 2 out of range for 2 shapes"):
        time_of_impact_batch(cs, start, start, [[0, 2]])


def test_interpolate_pose_endpoints_and_constant_rate():
    start = pose((1, 2, 3), rot_axis((1, 1, 0), 0.3))
    end = pose((3, 2, 1), rot_axis((0, 1, 2), 2.0))
    np.testing.assert_allclose(interpolate_pose(start, end, 0.0), start, atol=1e-15)
    np.testing.assert_allclose(interpolate_pose(start, end, 1.0), end, atol=1e-15)
    mid = interpolate_pose(start, end, 0.5)
    np.testing.assert_allclose(mid[:3, 3], [2, 2, 2], atol=1e-15)
    # Equal angles on both halves; the origin is the reference point.
    rel = end[:3, :3] @ start[:3, :3].T
    total = np.arccos((np.trace(rel) - 1) / 2)
    half = np.arccos((np.trace(mid[:3, :3] @ start[:3, :3].T) - 1) / 2)
    assert half == pytest.approx(total / 2, abs=1e-12)
    np.testing.assert_allclose(mid[:3, :3] @ mid[:3, :3].T, np.eye(3), atol=1e-14)


# ---------------------------------------------------------------------------------------------
# Oracle cases (end pose = start pose + velocity)


def _oracle_shape(spec):
    if spec["type"] == "sphere":
        return Sphere(spec["radius"])
    if spec["type"] == "box":
        return Box(tuple(spec["size"]))
    raise AssertionError(f"unexpected oracle shape {spec['type']}")


def _toi_cases():
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parents[2].parent / "shared" / "oracles" / "cases.json"
    if not path.is_file():
        return [pytest.param(None, marks=pytest.mark.skip(reason="oracle cases absent"))]
    cases = [c for c in json.loads(path.read_text())["cases"] if c["query"] == "time_of_impact"]
    return [pytest.param(c, id=c["id"]) for c in cases]


@pytest.mark.parametrize("case", _toi_cases())
def test_oracle_time_of_impact(case, oracle_cases):
    assert case["id"] in {c["id"] for c in oracle_cases}
    poses = {}
    for side in "ab":
        p = case[f"pose_{side}"]
        start = pose(p["position"], quaternion_matrix(p["quaternion_wxyz"]))
        end = start.copy()
        end[:3, 3] += np.asarray(case[f"velocity_{side}"], dtype=float)
        poses[side] = (start, end)
    r = time_of_impact(
        _oracle_shape(case["a"]),
        _oracle_shape(case["b"]),
        *poses["a"],
        *poses["b"],
        tolerance=1e-10,
    )
    expected = case["expect"]["toi"]
    if expected is None:
        assert r.status == TimeOfImpactStatus.SEPARATED and r.time_of_impact is None
    else:
        assert r.status == TimeOfImpactStatus.HIT
        assert r.time_of_impact == pytest.approx(expected, abs=max(case["tolerance"], 1e-12))


# ---------------------------------------------------------------------------------------------
# Analytic spheres (hypothesis)

coord = st.floats(-5, 5, allow_nan=False)
vec3 = st.tuples(coord, coord, coord)


def analytic_sphere_toi(c0, dv, radius):
    """First t in [0, 1] with |c0 + t dv| = radius, or None (a test-side quadratic)."""
    a, b, c = dv @ dv, 2 * c0 @ dv, c0 @ c0 - radius * radius
    if a == 0.0:
        return None
    disc = b * b - 4 * a * c
    if disc < 0:
        return None
    t = (-b - np.sqrt(disc)) / (2 * a)
    return t if 0.0 <= t <= 1.0 else None


@given(
    ca=vec3,
    cb=vec3,
    va=vec3,
    vb=vec3,
    ra=st.floats(0.05, 2),
    rb=st.floats(0.05, 2),
    as_capsule=st.booleans(),
)
def test_sphere_pairs_match_the_quadratic(ca, cb, va, vb, ra, rb, as_capsule):
    ca, cb, va, vb = map(np.asarray, (ca, cb, va, vb))
    c0, dv = cb - ca, (cb + vb) - (ca + va) - (cb - ca)
    if np.linalg.norm(c0) - (ra + rb) <= 1e-3:
        return  # overlapping at the start: tested elsewhere
    tol = 1e-9
    # A zero-length capsule is a sphere that goes through the ray cast (radius as margin).
    b_shape = Capsule(rb, 0.0) if as_capsule else Sphere(rb)
    r = time_of_impact(
        Sphere(ra), b_shape, pose(ca), pose(ca + va), pose(cb), pose(cb + vb), tolerance=tol
    )
    expected = analytic_sphere_toi(c0, dv, ra + rb)
    speed = np.linalg.norm(dv)
    if expected is not None:
        assert r.status == TimeOfImpactStatus.HIT
        assert r.time_of_impact <= expected + 1e-12
        # Within the tolerance in distance: the time error is at most tol / closing speed
        # (+ rounding); grazing contacts close slowly, so compare distances there.
        d = np.linalg.norm(c0 + r.time_of_impact * dv) - (ra + rb)
        assert d <= tol * (1 + 1e-6) + 1e-12
    else:
        closest = min(np.linalg.norm(c0 + t * dv) for t in np.linspace(0, 1, 2001))
        if r.status == TimeOfImpactStatus.HIT:
            assert closest - (ra + rb) <= tol + 1e-6 * speed  # a near miss within reach
        else:
            assert r.status == TimeOfImpactStatus.SEPARATED


# ---------------------------------------------------------------------------------------------
# Rotation: a bar turning past a box


BAR = Box((4.0, 0.2, 0.2))


def _bar_case(box_centre):
    return dict(
        a=BAR,
        b=Box((0.5, 0.5, 0.5)),
        start_pose_a=pose(),
        end_pose_a=pose(rotation=rot_z(np.pi / 2)),
        start_pose_b=pose(box_centre),
        end_pose_b=pose(box_centre),
    )


def _distance_at(case, t):
    pa = interpolate_pose(case["start_pose_a"], case["end_pose_a"], t)
    pb = interpolate_pose(case["start_pose_b"], case["end_pose_b"], t)
    return distance(case["a"], case["b"], pa, pb).distance


def test_bar_rotating_into_a_box_hits_where_dense_sampling_does():
    case = _bar_case((1.5, 1.5, 0.0))
    # No contact at the start nor at the end: a discrete check misses it.
    assert _distance_at(case, 0.0) > 0.1 and _distance_at(case, 1.0) > 0.1
    tol = 1e-7
    r = time_of_impact(**case, tolerance=tol)
    assert r.status == TimeOfImpactStatus.HIT
    assert _distance_at(case, r.time_of_impact) <= tol
    assert _distance_at(case, max(0.0, r.time_of_impact - 1e-4)) > 0.0
    # First contact by sampling + bisection: toi is a lower bound, close to it.
    ts = np.linspace(0, 1, 2001)
    first = next(i for i, t in enumerate(ts) if _distance_at(case, t) == 0.0)
    lo, hi = ts[first - 1], ts[first]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _distance_at(case, mid) == 0.0 else (mid, hi)
    assert r.time_of_impact <= hi
    assert hi - r.time_of_impact < 1e-5
    # The contact is on the bar's leading face (+y side), near the box's corner region.
    assert r.normal @ (np.array([1.5, 1.5, 0.0]) - r.point) > 0.0


def test_bar_rotating_past_a_box_near_miss_is_separated():
    # Bar corners reach radius sqrt(2^2 + 0.1^2) = 2.0025; the box's nearest corner is at
    # radius |(1.25, 1.25) + 0.8 (1, 1)| ~ 2.90: clear miss, but the swept bounds overlap.
    case = _bar_case((2.05, 2.05, 0.0))
    r = time_of_impact(**case, tolerance=1e-7)
    assert r.status == TimeOfImpactStatus.SEPARATED
    # Grazing: the nearest box corner just inside the circle swept by the bar's corners.
    case = _bar_case((1.66, 0.9, 0.0))
    r = time_of_impact(**case, tolerance=1e-7)
    ts = np.linspace(0, 1, 2001)
    touches = any(_distance_at(case, t) == 0.0 for t in ts)
    assert touches == (r.status == TimeOfImpactStatus.HIT)


def test_failed_gives_a_safe_lower_bound():
    case = _bar_case((1.5, 1.5, 0.0))
    r = time_of_impact(**case, tolerance=1e-7, max_iterations=2)
    assert r.status == TimeOfImpactStatus.FAILED
    assert 0.0 < r.time_of_impact < 1.0
    assert all(_distance_at(case, t) > 0.0 for t in np.linspace(0.0, r.time_of_impact, 200))


# ---------------------------------------------------------------------------------------------
# Random hulls, random rotations and translations: never SEPARATED when sampling sees contact


def _random_hull(rng, n):
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return p * rng.uniform(0.3, 1.0, size=3) + rng.normal(scale=0.1, size=3)


def _random_rotation(rng):
    q = rng.normal(size=4)
    return quaternion_matrix(q)


def _dense_distances(cs, starts, ends, ts):
    """Distances of the pair (0, 1) of ``cs`` at each instant of ``ts``."""
    k = len(ts)
    big = ConvexSet.concatenate(*([cs] * k))
    poses = np.concatenate([interpolate_pose(starts, ends, np.full(2, t)) for t in ts])
    pairs = np.arange(2 * k).reshape(k, 2)
    return distance_batch(big, poses, pairs, threads=0).distance


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3))
def test_random_hulls_never_miss_a_sampled_contact(seed):
    rng = np.random.default_rng(seed)
    ts = np.linspace(0, 1, 2000)
    checked = hits = 0
    for _ in range(12):
        cs = ConvexSet.from_vertices([_random_hull(rng, 32), _random_hull(rng, 32)])
        rotate = rng.uniform() < 0.7
        # Both bodies cross the region around the origin: hits, misses and near misses.
        starts = np.stack(
            [
                pose(rng.uniform(-3, 3, 3), _random_rotation(rng)),
                pose(rng.uniform(-3, 3, 3), _random_rotation(rng)),
            ]
        )
        ends = starts.copy()
        ends[:, :3, 3] = -starts[:, :3, 3] + rng.normal(scale=0.8, size=(2, 3))
        if rotate:
            ends[:, :3, :3] = np.stack([_random_rotation(rng), _random_rotation(rng)])
        tol = 1e-7
        r = time_of_impact_batch(cs, starts, ends, [[0, 1]], tolerance=tol, threads=1)
        status = TimeOfImpactStatus(int(r.status[0]))
        d = _dense_distances(cs, starts, ends, ts)
        if d[0] <= tol:
            assert status == TimeOfImpactStatus.OVERLAPPED_AT_START
            continue
        checked += 1
        touching = np.flatnonzero(d == 0.0)
        if len(touching):
            assert status == TimeOfImpactStatus.HIT, (
                f"missed a sampled contact at t={ts[touching[0]]}"
            )
            hits += 1
            # Bisection between the last free sample and the first touching one.
            i = touching[0]
            lo, hi = ts[i - 1], ts[i]
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                dm = _dense_distances(cs, starts, ends, [mid])[0]
                lo, hi = (lo, mid) if dm == 0.0 else (mid, hi)
            assert r.time_of_impact[0] <= hi
        if status == TimeOfImpactStatus.HIT:
            t = float(r.time_of_impact[0])
            at, before = _dense_distances(cs, starts, ends, [t, max(0.0, t - 1e-6)])
            assert at <= tol * (1 + 1e-9)
            assert before > 0.0
        else:
            assert status == TimeOfImpactStatus.SEPARATED
            assert d.min() > tol / 2
    assert checked >= 6 and hits >= 2  # the sample exercises both outcomes


def test_batch_equals_loop_of_singles():
    rng = np.random.default_rng(7)
    hulls = [_random_hull(rng, 16) for _ in range(6)]
    cs = ConvexSet.from_vertices(hulls)
    starts = np.stack([pose(rng.uniform(-1.5, 1.5, 3), _random_rotation(rng)) for _ in range(6)])
    ends = np.stack([pose(rng.uniform(-1.5, 1.5, 3), _random_rotation(rng)) for _ in range(6)])
    pairs = np.array([(i, j) for i in range(6) for j in range(i + 1, 6)])
    batch = time_of_impact_batch(cs, starts, ends, pairs, threads=2)
    for k, (i, j) in enumerate(pairs):
        single = time_of_impact(hulls[i], hulls[j], starts[i], ends[i], starts[j], ends[j])
        assert batch.status[k] == single.status
        if single.time_of_impact is None:
            assert np.isnan(batch.time_of_impact[k])
        else:
            assert batch.time_of_impact[k] == single.time_of_impact
