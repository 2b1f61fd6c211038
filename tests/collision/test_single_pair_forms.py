"""The single-pair queries (distance, penetration, signed_distance, intersects,
time_of_impact) against the batch's row for the same pair, bit for bit: two primitives (one
native call), Bodies of one, point sets and meshes (a packed set), every pose form and the
bad inputs, whose messages stay those of the packing path."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
import trimesh
from strategies import turned_about_z

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Cylinder,
    Sphere,
    distance,
    distance_batch,
    intersects,
    intersects_batch,
    penetration,
    penetration_batch,
    signed_distance,
    signed_distance_batch,
    time_of_impact,
    time_of_impact_batch,
)
from meshcol.collision.narrowphase import (
    DistanceResult,
    PenetrationResult,
    SignedDistanceResult,
)
from meshcol.collision.time_of_impact import TimeOfImpactResult
from meshcol.types import Body, Spin, Status, TimeOfImpactStatus

PRIMITIVES = [Sphere(0.5), Box((1.0, 0.6, 0.8)), Capsule(0.3, 1.2), Cylinder(0.4, 0.9)]
TILT = turned_about_z(0.4, (0.0, 0.0, 0.0)) @ np.array(
    [[1.0, 0, 0, 0], [0, 0.6, -0.8, 0], [0, 0.8, 0.6, 0], [0, 0, 0, 1]]
)


def moved(pose: np.ndarray, translation: tuple[float, float, float]) -> np.ndarray:
    out = pose.copy()
    out[:3, 3] = translation
    return out


# (pose_a, pose_b): identity both, one given, apart, touching-near, overlapping deep, turned,
# a non-rigid pose and a NaN pose (INVALID_INPUT).
POSES = [
    (None, None),
    (None, moved(np.eye(4), (2.5, 0.0, 0.0))),
    (turned_about_z(0.3, (0.1, -0.2, 0.0)), None),
    (turned_about_z(0.3, (0.0, 0.0, 0.0)), moved(TILT, (3.0, 1.0, -0.5))),
    (np.eye(4), moved(np.eye(4), (0.9, 0.0, 0.0))),
    (TILT, turned_about_z(1.2, (0.2, 0.1, 0.05))),
    (np.diag([2.0, 1.0, 1.0, 1.0]), None),
    (np.full((4, 4), np.nan), np.eye(4)),
]
SINGLES = [
    (distance, distance_batch, DistanceResult),
    (penetration, penetration_batch, PenetrationResult),
    (signed_distance, signed_distance_batch, SignedDistanceResult),
]


def stacked(pose_a, pose_b) -> np.ndarray | None:
    if pose_a is None and pose_b is None:
        return None
    return np.stack([np.eye(4) if p is None else p for p in (pose_a, pose_b)])


def same_as_row(result, batch, row: int = 0) -> None:
    """Every field of a single-pair result equals the batch's ``row``, bit for bit."""
    for f in dataclasses.fields(result):
        got, want = getattr(result, f.name), getattr(batch, f.name)[row]
        if f.name == "status":
            assert type(got) is Status and got == int(want)
        elif f.name == "iterations":
            assert type(got) is int and got == int(want)
        elif np.ndim(want):
            assert got.shape == (3,) and got.dtype == np.float64
            assert got.tobytes() == want.tobytes(), f.name
        else:
            assert type(got) is float and np.float64(got).tobytes() == want.tobytes(), f.name


def check_pair(a, b, pose_a, pose_b, shapes=None, poses=None, row=(0, 1)) -> None:
    """The four single-pair queries of (a, b) against the batch over ``shapes`` (default:
    the two-shape set) at the pair ``row``."""
    if shapes is None:
        shapes, poses = ConvexSet.from_shapes([a, b]), stacked(pose_a, pose_b)
    pairs = np.array([row], dtype=np.int64)
    for single, batch, result_type in SINGLES:
        result = single(a, b, pose_a, pose_b)
        assert type(result) is result_type
        same_as_row(result, batch(shapes, poses, pairs, threads=1))
        assert isinstance(result.status, Status)
    expected = intersects_batch(shapes, poses, pairs, threads=1)
    if expected.status[0] == Status.INVALID_INPUT:
        with pytest.raises(ValueError, match="NaN/inf coordinates, an empty shape or a non-rigid"):
            intersects(a, b, pose_a, pose_b)
    else:
        got = intersects(a, b, pose_a, pose_b)
        assert type(got) is bool and got == bool(expected.intersects[0])


@pytest.mark.parametrize("a, b", list(itertools.product(PRIMITIVES, repeat=2)))
def test_primitive_pairs_equal_the_batch_row(a, b) -> None:
    for pose_a, pose_b in POSES:
        check_pair(a, b, pose_a, pose_b)


def test_primitive_pairs_equal_the_row_of_a_larger_set() -> None:
    shapes = ConvexSet.from_shapes([Sphere(0.1), *PRIMITIVES])
    poses = np.stack([np.eye(4)] + [turned_about_z(0.5 * k, (0.7 * k, 0.2, 0.0)) for k in range(4)])
    for i, j in itertools.product(range(4), repeat=2):
        check_pair(
            PRIMITIVES[i], PRIMITIVES[j], poses[i + 1], poses[j + 1], shapes, poses, (i + 1, j + 1)
        )


def test_point_sets_meshes_and_bodies_equal_the_batch_row() -> None:
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.2, 0.2, 0.2]])
    mesh = trimesh.creation.box(extents=(0.8, 0.5, 0.6))
    pose = turned_about_z(0.2, (0.6, 0.3, 0.1))
    body_sphere = Body.of_primitive("s", None, Sphere(0.4), pose=turned_about_z(0.1, (1.0, 0, 0)))
    body_box = Body.of_primitive("b", None, Box((0.5, 0.5, 0.5)))
    body_mesh = Body("m", None, mesh.vertices, mesh.faces, pose=pose)
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]])
    cloud = np.random.default_rng(4).normal(size=(64, 3))
    shapes = [
        points,
        mesh,
        body_sphere,
        body_box,
        body_mesh,
        Capsule(0.2, 0.4),
        flat,  # a polygon
        flat[:2] * 2.0,  # a segment
        flat[1:2],  # a point
        np.zeros((0, 3)),  # no points: INVALID_INPUT
        np.array([[0.0, 0, 0], [np.nan, 0, 0], [0, 1, 0], [0, 0, 1]]),  # INVALID_INPUT
        points * 1e300,  # beyond the hull's range: kept as given, its points scanned
        cloud,
    ]
    for a, b in itertools.product(shapes, repeat=2):
        for pose_a, pose_b in [(None, None), (None, pose), (TILT, moved(TILT, (1.5, 0.0, 0.0)))]:
            # a Body without an explicit pose is at its own
            own_a = a.pose if isinstance(a, Body) and pose_a is None else pose_a
            own_b = b.pose if isinstance(b, Body) and pose_b is None else pose_b
            set_poses = stacked(own_a, own_b)
            check_pair(a, b, pose_a, pose_b, ConvexSet.from_shapes([a, b]), set_poses)


@pytest.mark.parametrize(
    "form",
    [
        lambda p: p.tolist(),
        lambda p: np.asfortranarray(p),
        lambda p: p.astype(np.float32).astype(np.float64),
        lambda p: p.astype(np.float32),
        lambda p: np.pad(p, 1)[1:-1, 1:-1],
        lambda p: p.astype(np.int64) if np.all(p == np.round(p)) else p,
    ],
)
def test_every_pose_form_gives_the_array_answer(form) -> None:
    pose_b = moved(TILT, (1.2, 0.3, 0.0))
    for a, b in itertools.product(PRIMITIVES, repeat=2):
        for single, batch, _ in SINGLES:
            expected = batch(
                ConvexSet.from_shapes([a, b]),
                np.stack([np.eye(4), np.asarray(form(pose_b), dtype=np.float64)]),
                [[0, 1]],
                threads=1,
            )
            same_as_row(single(a, b, None, form(pose_b)), expected)


def test_bad_inputs_keep_their_messages() -> None:
    sphere, box = Sphere(0.5), Box((1.0, 1.0, 1.0))
    for single in (distance, penetration, signed_distance, intersects):
        with pytest.raises(ValueError, match=r"^pose_a must be \(4, 4\), got \(3, 3\)$"):
            single(sphere, box, np.eye(3), None)
        with pytest.raises(ValueError, match=r"^pose_b must be \(4, 4\), got \(16,\)$"):
            single(sphere, box, None, np.eye(4).ravel())
        with pytest.raises(
            ValueError, match=r"^b must be a Sphere, Box, Capsule, Cylinder, Ellipsoid, mesh"
        ):
            single(sphere, "box", None, None)
        with pytest.raises(ValueError, match=r"^a must be \(n, 3\), got \(2, 2\)$"):
            single(np.zeros((2, 2)), box, np.eye(3), None)  # the shape first, then the pose
    with pytest.raises(ValueError, match="NaN/inf coordinates"):
        intersects(sphere, box, np.full((4, 4), np.inf), None)


def toi_motions():
    """(start_a, end_a, start_b, end_b): a hit, a miss, overlapping at the start, a turn, a
    non-rigid end, identities."""
    return [
        (None, None, moved(np.eye(4), (4.0, 0, 0)), moved(np.eye(4), (-1.0, 0, 0))),
        (np.eye(4), np.eye(4), moved(np.eye(4), (4.0, 3.0, 0)), moved(np.eye(4), (-4.0, 3.0, 0))),
        (np.eye(4), moved(np.eye(4), (0.1, 0, 0)), np.eye(4), None),
        (
            turned_about_z(0.0, (0, 0, 0)),
            turned_about_z(2.0, (0, 0, 0)),
            moved(TILT, (1.6, 0, 0)),
            moved(TILT, (1.2, 0.5, 0)),
        ),
        (np.eye(4), np.diag([1.0, 2.0, 1.0, 1.0]), moved(np.eye(4), (3.0, 0, 0)), None),
    ]


def same_toi(result: TimeOfImpactResult, batch) -> None:
    assert type(result) is TimeOfImpactResult
    assert type(result.status) is TimeOfImpactStatus and result.status == int(batch.status[0])
    want = float(batch.time_of_impact[0])
    if math.isnan(want):
        assert result.time_of_impact is None
    else:
        assert type(result.time_of_impact) is float
        assert np.float64(result.time_of_impact).tobytes() == np.float64(want).tobytes()
    assert result.point.tobytes() == batch.point[0].tobytes()
    assert result.normal.tobytes() == batch.normal[0].tobytes()
    assert type(result.iterations) is int and result.iterations == int(batch.iterations[0])


def toi_batch(a, b, starts, ends, **options):
    def pose(p):
        return np.eye(4) if p is None else np.asarray(p, dtype=np.float64)

    return time_of_impact_batch(
        ConvexSet.from_shapes([a, b]),
        np.stack([pose(p) for p in starts]),
        np.stack([pose(p) for p in ends]),
        [[0, 1]],
        threads=1,
        **options,
    )


@pytest.mark.parametrize("a, b", list(itertools.product(PRIMITIVES, repeat=2)))
def test_time_of_impact_of_primitives_equals_the_batch_row(a, b) -> None:
    for start_a, end_a, start_b, end_b in toi_motions():
        for options in ({}, {"tolerance": 1e-2}, {"max_iterations": 2}):
            got = time_of_impact(a, b, start_a, end_a, start_b, end_b, **options)
            same_toi(got, toi_batch(a, b, (start_a, start_b), (end_a, end_b), **options))


def test_time_of_impact_of_bodies_point_sets_and_spins() -> None:
    start, end = moved(np.eye(4), (3.0, 0, 0)), moved(np.eye(4), (-2.0, 0, 0))
    moving = Body.of_primitive("m", None, Box((0.5, 0.5, 0.5)), pose=start, end_pose=end)
    resting = Body.of_primitive("r", None, Sphere(0.4))
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    got = time_of_impact(moving, resting, None, None, None, None)
    same_toi(got, toi_batch(Box((0.5, 0.5, 0.5)), Sphere(0.4), (start, None), (end, None)))
    got = time_of_impact(points, moving, None, None, None, None)
    same_toi(got, toi_batch(points, Box((0.5, 0.5, 0.5)), (None, start), (None, end)))
    # a spin (given, or a Body's own) takes the packing path: the same answer as the batch's
    spin = Spin(np.array([0.0, 0.0, 2.0 * math.pi]))
    spinning = Body.of_primitive(
        "s", None, Box((0.5, 0.5, 0.5)), pose=start, end_pose=start, spin=spin
    )
    expected = time_of_impact_batch(
        ConvexSet.from_shapes([Box((0.5, 0.5, 0.5)), Sphere(0.4)]),
        np.stack([start, moved(np.eye(4), (2.4, 0, 0))]),
        np.stack([start, moved(np.eye(4), (2.4, 0, 0))]),
        [[0, 1]],
        rotations=np.array([[0.0, 0.0, 2.0 * math.pi], [0.0, 0.0, 0.0]]),
        pivots=np.array([start[:3, 3], [2.4, 0, 0]]),
        threads=1,
    )
    b_pose = moved(np.eye(4), (2.4, 0, 0))
    same_toi(time_of_impact(spinning, Sphere(0.4), None, None, b_pose, b_pose), expected)
    same_toi(
        time_of_impact(
            Box((0.5, 0.5, 0.5)), Sphere(0.4), start, start, b_pose, b_pose, spin_a=spin
        ),
        expected,
    )


def test_time_of_impact_options_and_bad_inputs() -> None:
    a, b = Sphere(0.5), Box((1.0, 1.0, 1.0))
    start_b, end_b = moved(np.eye(4), (4.0, 0, 0)), np.eye(4)
    expected = toi_batch(a, b, (None, start_b), (None, end_b), tolerance=0.25, max_iterations=3)
    for tolerance in (0.25, np.float64(0.25)):
        for cap in (3, np.int64(3)):
            got = time_of_impact(
                a, b, None, None, start_b, end_b, tolerance=tolerance, max_iterations=cap
            )
            same_toi(got, expected)
    for tolerance in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match=r"^tolerance must be finite and > 0"):
            time_of_impact(a, b, None, None, start_b, end_b, tolerance=tolerance)
    with pytest.raises(ValueError, match=r"^max_iterations must be >= 1, got 0$"):
        time_of_impact(a, b, None, None, start_b, end_b, max_iterations=0)
    # a pose is checked before the tolerance, as the packing path does
    with pytest.raises(ValueError, match=r"^start_pose_b must be \(4, 4\), got \(3, 3\)$"):
        time_of_impact(a, b, None, None, np.eye(3), end_b, tolerance=-1.0)
    with pytest.raises(ValueError, match=r"^end_pose_a must be \(4, 4\), got \(4,\)$"):
        time_of_impact(a, b, None, np.ones(4), start_b, end_b)


def test_shapes_in_the_cores_form_pack_no_set(monkeypatch) -> None:
    """Primitives, Bodies, meshes and float64 point arrays, with array or no poses, take the
    one native call."""

    def refuse(*args, **kwargs):
        raise AssertionError("a set was packed")

    monkeypatch.setattr(ConvexSet, "from_shapes", classmethod(refuse))
    body = Body.of_primitive("b", None, Capsule(0.2, 0.5), pose=moved(np.eye(4), (1.0, 0, 0)))
    mesh = trimesh.creation.icosphere(subdivisions=1)
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    mesh_body = Body("m", None, mesh.vertices, mesh.faces, pose=moved(np.eye(4), (0, 1.0, 0)))
    for a, b in itertools.product([*PRIMITIVES, body, mesh, points, mesh_body], repeat=2):
        for pose_a, pose_b in POSES[:6]:
            for single, _, result_type in SINGLES:
                assert type(single(a, b, pose_a, pose_b)) is result_type
            assert type(intersects(a, b, pose_a, pose_b)) is bool
            got = time_of_impact(a, b, pose_a, None, pose_b, np.eye(4), tolerance=1e-3)
            assert type(got) is TimeOfImpactResult
