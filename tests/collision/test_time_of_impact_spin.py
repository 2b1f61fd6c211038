"""Spins past half a turn: the motion is the specified angle, not the shortest rotation.

A "clock hand" (a bar from its local origin out along +x) turns about z through its origin.
Turned by theta, it sweeps the angles [0, theta]; the shortest rotation to the same end turns
the other way, by theta - 2 pi, and sweeps [theta - 2 pi, 0] instead. Posts placed in one of
the two sectors tell the two motions apart, with analytic first contacts.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

import meshcol
from meshcol import ConvexSet, Sphere, distance_batch, interpolate_pose, time_of_impact
from meshcol.cli import main
from meshcol.collision.time_of_impact import (
    shortest_rotation,
    swept_aabbs,
    time_of_impact_batch,
)
from meshcol.types import Body, Spin, TimeOfImpactStatus

HALF_WIDTH = 0.05  # of the hand, in y and z
LENGTH = 2.0  # of the hand, along local x from its origin
POST_RADIUS = 0.1
POST_DISTANCE = 1.5  # of the post's centre from the axis
TOLERANCE = 1e-7


def hand_points() -> np.ndarray:
    """The hand's corners: x in [0, LENGTH], y and z in [-HALF_WIDTH, HALF_WIDTH]."""
    return np.array(
        [[x, y, z] for x in (0.0, LENGTH) for y in (-HALF_WIDTH, HALF_WIDTH) for z in (-0.05, 0.05)]
    )


def rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def pose(position=(0.0, 0.0, 0.0), rotation=None) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = position
    return m


def post_at(angle: float) -> np.ndarray:
    return pose((POST_DISTANCE * math.cos(angle), POST_DISTANCE * math.sin(angle), 0.0))


def contact_angle(post_angle: float) -> float:
    """Hand angle at first contact with a post ahead of it (turning +z): the hand's leading
    face, HALF_WIDTH off its centre line, meets the ball when the centre's distance from the
    line, POST_DISTANCE sin(gap), is HALF_WIDTH + POST_RADIUS."""
    return post_angle - math.asin((HALF_WIDTH + POST_RADIUS) / POST_DISTANCE)


def spin_toi(theta: float, post_angle: float, **kwargs):
    return time_of_impact(
        hand_points(),
        Sphere(POST_RADIUS),
        pose(),
        pose(rotation=rot_z(theta)),
        post_at(post_angle),
        post_at(post_angle),
        spin_a=Spin([0.0, 0.0, theta]),
        tolerance=TOLERANCE,
        **kwargs,
    )


@pytest.mark.parametrize("turns", [1.35, 1.5, 1.62, 1.79])
def test_hand_spun_past_half_a_turn_hits_the_post_on_its_way(turns):
    # The post at 0.75 pi lies in the sector the spin sweeps, not in the one the shortest
    # rotation (turns - 2 pi, the other way) sweeps: it used to be reported as missed.
    theta = turns * math.pi
    post = 0.75 * math.pi
    r = spin_toi(theta, post)
    assert r.status == TimeOfImpactStatus.HIT
    expected = contact_angle(post) / theta
    assert r.time_of_impact <= expected + 1e-12
    assert r.time_of_impact == pytest.approx(expected, abs=1e-6)


def test_a_spin_of_one_and_a_half_pi_misses_the_post_behind_it():
    # The post at -0.25 pi (= 1.75 pi) is a quarter turn past the end of the 1.5 pi spin and a
    # quarter turn behind its start: the closest approach is 1.5 sin(pi/4) - 0.15 > 0.9. The
    # shortest rotation (-0.5 pi) would sweep right through it.
    r = spin_toi(1.5 * math.pi, -0.25 * math.pi)
    assert r.status == TimeOfImpactStatus.SEPARATED
    shortest = time_of_impact(
        hand_points(),
        Sphere(POST_RADIUS),
        pose(),
        pose(rotation=rot_z(1.5 * math.pi)),
        post_at(-0.25 * math.pi),
        post_at(-0.25 * math.pi),
        tolerance=TOLERANCE,
    )
    # An end pose alone is the shortest rotation, as documented: -0.5 pi, into the post.
    assert shortest.status == TimeOfImpactStatus.HIT
    assert shortest.time_of_impact == pytest.approx(
        (0.25 * math.pi - math.asin(0.15 / 1.5)) / (0.5 * math.pi), abs=1e-6
    )


def test_several_turns_hit_on_the_first_pass():
    # Four full turns end where they start; the post at 0.5 pi is met in the first turn.
    theta = 8.0 * math.pi
    r = spin_toi(theta, 0.5 * math.pi)
    assert r.status == TimeOfImpactStatus.HIT
    assert r.time_of_impact == pytest.approx(contact_angle(0.5 * math.pi) / theta, abs=1e-6)


def test_interpolated_pose_is_at_the_true_angle():
    theta = 1.5 * math.pi
    start, end = pose((1.0, 2.0, 3.0)), pose((1.0, 2.0, 3.0), rot_z(theta))
    for t in (0.25, 0.5, 0.8):
        p = interpolate_pose(start, end, t, rotation=[0, 0, theta])
        np.testing.assert_allclose(p[:3, :3], rot_z(theta * t), atol=1e-14)
        np.testing.assert_allclose(p[:3, 3], [1, 2, 3], atol=1e-14)
    # Without a turn: the shortest rotation, -0.5 pi.
    p = interpolate_pose(start, end, 0.5)
    np.testing.assert_allclose(p[:3, :3], rot_z(-0.25 * math.pi), atol=1e-14)
    np.testing.assert_allclose(shortest_rotation(start, end), [0, 0, -0.5 * math.pi], atol=1e-14)


def test_pivot_carries_the_origin_on_an_arc():
    # A body whose origin is 1 off the pivot, half a turn about z through the pivot at the
    # world origin: its origin goes round the arc, not along the chord.
    start, end = pose((1.0, 0.0, 0.0)), pose((-1.0, 0.0, 0.0), rot_z(math.pi))
    mid = interpolate_pose(start, end, 0.5, rotation=[0, 0, math.pi], pivot=[0, 0, 0])
    np.testing.assert_allclose(mid[:3, 3], [0, 1, 0], atol=1e-14)
    np.testing.assert_allclose(mid[:3, :3], rot_z(0.5 * math.pi), atol=1e-14)


def test_turn_that_misses_the_end_rotation_is_invalid():
    cs = ConvexSet.from_shapes([hand_points(), Sphere(0.1)])
    start = np.stack([pose(), post_at(0.0)])
    end = np.stack([pose(rotation=rot_z(1.0)), post_at(0.0)])
    r = time_of_impact_batch(cs, start, end, [[0, 1]], rotations=[[0, 0, 2.0], [0, 0, 0]])
    assert r.status[0] == TimeOfImpactStatus.INVALID_INPUT
    with pytest.raises(ValueError, match="rotations must be"):
        time_of_impact_batch(cs, start, end, [[0, 1]], rotations=[[0, 0, 1.0]])
    with pytest.raises(ValueError, match="does not reach the end rotation"):
        interpolate_pose(start, end, [0.5, 0.5], rotation=[[0, 0, 2.0], [0, 0, 0]])
    with pytest.raises(ValueError, match="does not turn the pose into the end pose"):
        Body(
            "b",
            None,
            hand_points(),
            np.zeros((0, 3), np.int64),
            pose(),
            end[0],
            spin=Spin([0, 0, 2.0]),
        )


def test_swept_aabb_encloses_a_full_turn():
    # A whole turn ends where it starts: the union of the start and end boxes would be the
    # hand's own box, yet it sweeps the disk of radius |corner|.
    cs = ConvexSet.from_shapes([hand_points()])
    start = end = pose()[None]
    lo, hi = swept_aabbs(cs, start, end, rotations=[[0, 0, 2 * math.pi]])
    reach = math.hypot(LENGTH, HALF_WIDTH, 0.05)
    assert lo[0, 0] <= -LENGTH and lo[0, 1] <= -LENGTH and hi[0, 1] >= LENGTH
    for t in np.linspace(0, 1, 101):
        p = interpolate_pose(start, end, [t], rotation=[[0, 0, 2 * math.pi]])
        a, b = cs.aabbs(p)
        assert np.all(a >= lo - 1e-12) and np.all(b <= hi + 1e-12)
    assert np.all(hi[0] - lo[0] <= 2 * reach + 1e-12)


# ---------------------------------------------------------------------------------------------
# Dense sampling of the specified motion


def sampled_distances(start, end, rotations, times):
    """Exact distance (GJK on the hull and the sphere) of the hand and the post at each time,
    at the poses of the specified motion."""
    shapes = ConvexSet.from_shapes([hand_points(), Sphere(POST_RADIUS)])
    return np.array(
        [
            distance_batch(
                shapes, interpolate_pose(start, end, np.full(2, t), rotation=rotations), [[0, 1]]
            ).distance[0]
            for t in times
        ]
    )


@settings(max_examples=60, deadline=None)
@given(
    theta=st.floats(0.05, 4.0 * math.pi),
    axis=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(0.5, 1)),
    post_angle=st.floats(-math.pi, math.pi),
    post_height=st.floats(-0.15, 0.15),
    post_distance=st.floats(0.3, 2.3),
    drift=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-0.2, 0.2)),
)
def test_spin_matches_dense_sampling(theta, axis, post_angle, post_height, post_distance, drift):
    k = np.asarray(axis) / np.linalg.norm(axis)
    rotation = k * theta
    turn = Spin(rotation).matrix()
    start = np.stack(
        [
            pose(),
            pose(
                (
                    post_distance * math.cos(post_angle),
                    post_distance * math.sin(post_angle),
                    post_height,
                )
            ),
        ]
    )
    end = start.copy()
    end[0, :3, :3] = turn
    end[0, :3, 3] = drift
    rotations = np.stack([rotation, np.zeros(3)])
    cs = ConvexSet.from_shapes([hand_points(), Sphere(POST_RADIUS)])
    r = time_of_impact_batch(cs, start, end, [[0, 1]], rotations=rotations, tolerance=TOLERANCE)
    status = TimeOfImpactStatus(int(r.status[0]))
    times = np.linspace(0.0, 1.0, 2001)
    d = sampled_distances(start, end, rotations, times)
    # Lipschitz bound of the distance: no point moves faster than |drift| + theta * reach.
    reach = float(np.linalg.norm(hand_points(), axis=1).max())
    speed = float(np.linalg.norm(drift)) + theta * reach
    slack = speed * (times[1] - times[0]) / 2.0
    touching = np.flatnonzero(d <= 0.0)
    if status in (TimeOfImpactStatus.HIT, TimeOfImpactStatus.OVERLAPPED_AT_START):
        t = float(r.time_of_impact[0])
        # Touching (within tolerance) at the reported time, and no earlier sampled contact.
        (at,) = sampled_distances(start, end, rotations, [t])
        assert at <= TOLERANCE * 1.01
        if len(touching):
            assert t <= times[touching[0]] + 1e-12
        # Nothing touched before: every sample before t is clear.
        assert np.all(d[times < t - 1e-12] > 0.0)
    else:
        assert status == TimeOfImpactStatus.SEPARATED, status
        assert len(touching) == 0
    if np.all(d - slack > TOLERANCE):
        assert status == TimeOfImpactStatus.SEPARATED


# ---------------------------------------------------------------------------------------------
# The scene path: manifest angular_velocity -> meshcol sweep


def write_hand_scene(folder, turns: float, post_angle: float) -> str:
    trimesh.convex.convex_hull(hand_points()).export(folder / "hand.obj")
    duration = 2.0
    manifest = {
        "units": "m",
        "duration": duration,
        "bodies": [
            {
                "name": "hand",
                "mesh": "hand.obj",
                "angular_velocity": [0.0, 0.0, turns * math.pi / duration],
            },
            {
                "name": "post",
                "primitive": {"type": "sphere", "radius": POST_RADIUS},
                "position": post_at(post_angle)[:3, 3].tolist(),
            },
        ],
    }
    path = folder / "spin.json"
    path.write_text(json.dumps(manifest))
    return str(path)


def test_cli_sweep_reports_the_spin_hit_at_the_true_angle(tmp_path):
    path = write_hand_scene(tmp_path, 1.5, 0.75 * math.pi)
    out = tmp_path / "report.json"
    result = CliRunner().invoke(main, ["sweep", path, "--report", str(out)])
    assert result.exit_code == 1, result.output
    report = json.loads(out.read_text())
    (pair,) = report["pairs"]
    assert (pair["body_a"], pair["body_b"], pair["status"]) == ("hand", "post", "HIT")
    alpha = contact_angle(0.75 * math.pi)
    assert pair["time_of_impact"] == pytest.approx(alpha / (1.5 * math.pi), abs=1e-5)
    assert pair["time"] == pytest.approx(pair["time_of_impact"] * 2.0)
    # The reported pose is the hand at the contact angle, not on the shortest path.
    np.testing.assert_allclose(np.array(pair["pose_a"])[:3, :3], rot_z(alpha), atol=1e-5)
    assert report["summary"]["moving_bodies"] == 1


def test_cli_sweep_passes_a_spin_that_misses(tmp_path):
    path = write_hand_scene(tmp_path, 1.5, -0.25 * math.pi)
    result = CliRunner().invoke(main, ["sweep", path])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["pairs"] == []


def test_full_turn_body_is_moving_and_sweeps(tmp_path):
    # Two whole turns end at the start pose; the post in the way is still hit.
    path = write_hand_scene(tmp_path, 2.0, 0.5 * math.pi)
    report = meshcol.sweep(path)
    assert report.moving == (True, False)
    (hit,) = report.hits
    assert hit.status == TimeOfImpactStatus.HIT
    assert hit.time_of_impact == pytest.approx(
        contact_angle(0.5 * math.pi) / (2 * math.pi), abs=1e-5
    )


def write_two_box_glb(path) -> None:
    """Two 0.2 boxes as nodes "near" (at the origin) and "far" (placed 1 along x)."""
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box((0.2, 0.2, 0.2)), node_name="near", geom_name="near")
    scene.add_geometry(
        trimesh.creation.box((0.2, 0.2, 0.2)),
        node_name="far",
        geom_name="far",
        transform=pose((1.0, 0.0, 0.0)),
    )
    scene.export(path)


def test_sub_bodies_of_a_file_spin_as_one_body(tmp_path):
    # A file with two boxes, one placed 1 along x by its node: the manifest body spins half a
    # turn about its origin, and both sub-bodies stay one rigid body at every instant (the
    # offset one goes round the arc about the body's origin, not along the chord).
    write_two_box_glb(tmp_path / "pair.glb")
    manifest = {
        "duration": 1.0,
        "bodies": [
            {
                "name": "pair",
                "mesh": "pair.glb",
                "position": [0.0, 0.0, 0.0],
                "angular_velocity": [0.0, 0.0, math.pi],
            }
        ],
    }
    (tmp_path / "s.json").write_text(json.dumps(manifest))
    (pair,) = meshcol.load_scene(tmp_path / "s.json").bodies
    assert pair.parts == ("near", "far") and pair.spin is not None
    far_centre = pair.part_meshes()[1][1].mean(axis=0)  # the parts share the body's frame
    np.testing.assert_allclose(far_centre, [1, 0, 0], atol=1e-12)
    mid = interpolate_pose(pair.pose, pair.end_pose, 0.5, rotation=pair.spin.rotation)
    np.testing.assert_allclose(mid[:3, :3] @ far_centre + mid[:3, 3], [0, 1, 0], atol=1e-12)


@pytest.mark.parametrize(
    ("turns", "post_angle"), [(1.6, 0.8 * math.pi), (1.6, 1.85 * math.pi), (1.1, 1.85 * math.pi)]
)
def test_corpus_part_spun_past_half_a_turn_matches_dense_sampling(
    corpus, tmp_path, turns, post_angle
):
    # A real part (idler_riser.STL, its origin at a corner, so it swings like a hand) spins
    # past half a turn about z into, or short of, a small teapot; the oracle samples the
    # specified spin densely with the exact hull distance. On the shortest rotation the first
    # was a miss, the second a hit at 0.70 instead of 0.86, the third a hit that never is.
    riser = corpus / "trimesh-models" / "idler_riser.STL"
    teapot = corpus / "trimesh-models" / "teapot.stl"
    if not riser.is_file() or not teapot.is_file():
        pytest.skip("corpus meshes missing")
    theta = turns * math.pi
    centre = [3.2 * math.cos(post_angle), 3.2 * math.sin(post_angle), 0.0]
    manifest = {
        "duration": 1.0,
        "bodies": [
            {"name": "riser", "mesh": str(riser), "angular_velocity": [0.0, 0.0, theta]},
            {"name": "teapot", "mesh": str(teapot), "scale": 0.02, "position": centre},
        ],
    }
    path = tmp_path / "spin.json"
    path.write_text(json.dumps(manifest))
    report = meshcol.sweep(path, tolerance=1e-6)
    scene = report.scene
    moving, still = scene.bodies
    shapes = ConvexSet.from_shapes([moving, still])
    times = np.linspace(0.0, 1.0, 4001)
    gaps = np.array(
        [
            distance_batch(
                shapes,
                np.stack(
                    [
                        interpolate_pose(
                            moving.pose, moving.end_pose, t, rotation=moving.spin.rotation
                        ),
                        still.pose,
                    ]
                ),
                [[0, 1]],
            ).distance[0]
            for t in times
        ]
    )
    reach = float(np.linalg.norm(moving.vertices, axis=1).max())
    slack = theta * reach * (times[1] - times[0]) / 2.0
    touching = np.flatnonzero(gaps <= 0.0)
    if len(touching):
        (hit,) = report.hits
        assert hit.status == TimeOfImpactStatus.HIT
        assert hit.time_of_impact <= times[touching[0]] + 1e-12
        assert np.all(gaps[times < hit.time_of_impact - 1e-12] > 0.0)
        at = distance_batch(shapes, np.stack([hit.pose_a, hit.pose_b]), [[0, 1]]).distance[0]
        assert at <= 1e-6 * 1.01
    else:
        assert np.all(gaps - slack > 1e-6), "too close to call by sampling"
        assert report.hits == ()


def test_sub_bodies_reach_an_end_rotation_as_one_body(tmp_path):
    # The same two-box file given an end_rotation (a quarter turn, reached the shortest way):
    # the offset box turns about the manifest body's origin too, so halfway it is at 45 deg.
    write_two_box_glb(tmp_path / "pair.glb")
    manifest = {
        "bodies": [
            {
                "name": "pair",
                "mesh": "pair.glb",
                "end_rotation": {"euler_deg": [0, 0, 90], "order": "xyz"},
            }
        ],
    }
    (tmp_path / "s.json").write_text(json.dumps(manifest))
    (pair,) = meshcol.load_scene(tmp_path / "s.json").bodies
    far_centre = pair.part_meshes()[1][1].mean(axis=0)
    mid = interpolate_pose(pair.pose, pair.end_pose, 0.5)
    h = math.sqrt(0.5)
    np.testing.assert_allclose(mid[:3, :3] @ far_centre + mid[:3, 3], [h, h, 0], atol=1e-12)
    report = meshcol.sweep(tmp_path / "s.json")
    assert report.moving == (True,) and report.hits == ()  # parts of one body never pair


def test_round_shapes_spinning_about_their_own_axis_are_decided():
    # A capsule turning about its own axis moves no point: its lever arm is 0 and the pair is
    # decided at once; a cylinder's lever arm is its radius, not its half length (the bound
    # was the bounding radius, and both ran out of steps: FAILED).
    from meshcol import Capsule, Cylinder

    for shape, most in ((Capsule(0.1, 2.0), 1), (Cylinder(0.1, 2.0), 400)):
        post = pose((0.1 + 0.1 + 1e-3, 0.0, 0.3))
        r = time_of_impact(
            shape,
            Sphere(0.1),
            pose(),
            pose(rotation=rot_z(0.9 * math.pi)),
            post,
            post,
            tolerance=TOLERANCE,
        )
        assert r.status == TimeOfImpactStatus.SEPARATED and r.iterations <= most


shape_makers = st.sampled_from(["box", "capsule", "cylinder", "sphere", "points"])


def make_shape(kind: str, size: float):
    from meshcol import Box, Capsule, Cylinder

    if kind == "box":
        return Box((size, 0.6 * size, 0.3 * size))
    if kind == "capsule":
        return Capsule(0.2 * size, size)
    if kind == "cylinder":
        return Cylinder(0.2 * size, size)
    if kind == "sphere":
        return Sphere(0.3 * size)
    return (
        np.array(
            [
                [1, 0.2, 0.1],
                [-0.4, 0.7, 0.2],
                [0.1, -0.6, 0.4],
                [0.2, 0.1, -0.8],
                [-0.3, -0.2, -0.3],
            ]
        )
        * size
    )


@settings(max_examples=30, deadline=None)
@given(
    kind_a=shape_makers,
    kind_b=shape_makers,
    size=st.floats(0.3, 1.5),
    theta=st.floats(0.0, 4.0 * math.pi),
    axis=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.3, 1)),
    pivot=st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6), st.floats(-0.6, 0.6)),
    other=st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-0.5, 0.5)),
)
def test_any_shape_spinning_about_a_pivot_matches_dense_sampling(
    kind_a, kind_b, size, theta, axis, pivot, other
):
    k = np.asarray(axis) / np.linalg.norm(axis)
    rotation = k * theta
    cs = ConvexSet.from_shapes([make_shape(kind_a, size), make_shape(kind_b, 0.7)])
    start = np.stack([pose(), pose(other)])
    end = start.copy()
    turn = Spin(rotation).matrix()
    end[0, :3, :3] = turn
    end[0, :3, 3] = np.asarray(pivot) + turn @ (-np.asarray(pivot))
    rotations = np.stack([rotation, np.zeros(3)])
    pivots = np.stack([np.asarray(pivot), start[1, :3, 3]])
    r = time_of_impact_batch(
        cs, start, end, [[0, 1]], rotations=rotations, pivots=pivots, tolerance=TOLERANCE
    )
    status = TimeOfImpactStatus(int(r.status[0]))
    times = np.linspace(0.0, 1.0, 1501)
    poses = interpolate_pose(
        np.repeat(start[:1], len(times), 0),
        np.repeat(end[:1], len(times), 0),
        times,
        rotation=np.repeat(rotations[:1], len(times), 0),
        pivot=np.repeat(pivots[:1], len(times), 0),
    )
    d = np.array([distance_batch(cs, np.stack([p, start[1]]), [[0, 1]]).distance[0] for p in poses])
    touching = np.flatnonzero(d <= 0.0)
    if status in (TimeOfImpactStatus.HIT, TimeOfImpactStatus.OVERLAPPED_AT_START):
        t = float(r.time_of_impact[0])
        if len(touching):
            assert t <= times[touching[0]] + 1e-12
        assert np.all(d[times < t - 1e-12] > 0.0)
    else:
        assert status == TimeOfImpactStatus.SEPARATED, status
        assert len(touching) == 0
