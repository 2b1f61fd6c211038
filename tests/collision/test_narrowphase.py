"""Narrow phase: known answers, peer cases, exact oracles, python-fcl, properties, bad input."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from conftest import ORACLES
from hypothesis import assume, given
from hypothesis import strategies as st
from oracles import box_corners, polytope_distance, sat_depth, transform
from strategies import hulls, pose_matrix, poses, rotation_from_quaternion, shapes

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Cylinder,
    ShapeKind,
    Sphere,
    distance,
    distance_batch,
    intersects,
    intersects_batch,
    penetration,
    penetration_batch,
    signed_distance,
    signed_distance_batch,
)
from meshcol.collision.narrowphase import SignedDistanceBatch
from meshcol.types import Body, Status

CUBE = box_corners((1, 1, 1))


def translation(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    return pose_matrix(np.eye(3), (x, y, z))


def rot_z(deg: float, t=(0, 0, 0)) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return pose_matrix(np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]), t)


def close(value: float, expected: float, rel: float = 1e-9, abs_: float = 1e-12) -> bool:
    return abs(value - expected) <= rel * abs(expected) + abs_


# ---------------------------------------------------------------------------------------------
# Known answers


def test_boxes_one_apart():
    r = distance(CUBE, CUBE, None, translation(2.0))
    assert r.distance == pytest.approx(1.0, abs=1e-12)
    assert r.status == Status.CONVERGED
    np.testing.assert_allclose(r.normal, [1, 0, 0], atol=1e-12)
    assert r.point_a[0] == pytest.approx(0.5, abs=1e-12)
    assert r.point_b[0] == pytest.approx(1.5, abs=1e-12)
    np.testing.assert_allclose(r.point_b - r.point_a, r.distance * r.normal, atol=1e-12)


def test_rotated_cubes_issue_case_is_exact():
    # Two cubes of side 2 ("unit" half extent), one at (4, 4, 0) turned 45 degrees about z.
    expected = 3 * math.sqrt(2) - 1
    for a in (box_corners((2, 2, 2)), Box((2, 2, 2))):
        r = distance(a, a, None, rot_z(45, (4, 4, 0)))
        assert abs(r.distance - expected) <= 1e-12
        assert signed_distance(a, a, None, rot_z(45, (4, 4, 0))).signed_distance == (
            pytest.approx(expected, abs=1e-12)
        )


@pytest.mark.parametrize("gap", [0.0, 1e-9, 1e-3, 0.5])
def test_parallel_faces_kissing_and_small_gaps(gap):
    # Face-face contact: GJK sees a whole face pair, the answer is the plane gap.
    big = box_corners((3, 2, 1))
    small = box_corners((1, 1, 1))
    r = distance(big, small, None, translation(0.3, 0.2, 1.0 + gap))
    assert abs(r.distance - gap) <= 1e-12 + 1e-9 * gap
    assert intersects(big, small, None, translation(0.3, 0.2, 1.0 + gap)) == (gap == 0.0)


def test_edge_edge_and_vertex_face():
    # Edge-edge: a cube turned 45 deg about x above one turned 45 deg about y (crossed edges).
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    rx = pose_matrix(np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), (0.1, -0.05, 3))
    ry = pose_matrix(np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]), (0, 0, 0))
    r = distance(CUBE, CUBE, ry, rx)
    assert r.distance == pytest.approx(3 - 2 * math.sqrt(0.5), abs=1e-12)
    # Vertex-face: a cube balanced on a corner above a face.
    q = rotation_from_quaternion(np.array([0.88807383, 0.3250576, -0.3250576, 0.0]))
    corner = np.min((CUBE @ q.T)[:, 2])
    r = distance(CUBE, CUBE, None, pose_matrix(q, (0.1, 0.1, 0.5 - corner + 0.25)))
    assert r.distance == pytest.approx(0.25, abs=1e-12)


def test_spheres_capsules_cylinders():
    r = distance(Sphere(1), Sphere(2), None, translation(0, 5, 0))
    assert r.distance == pytest.approx(2.0, abs=1e-12)
    np.testing.assert_allclose(r.point_a, [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(r.point_b, [0, 3, 0], atol=1e-12)
    # Capsule side (segment along z) against a box face.
    r = distance(Capsule(0.5, 4), Box((1, 1, 1)), None, translation(2, 0, 1))
    assert r.distance == pytest.approx(1.0, abs=1e-12)
    # Cylinder rim against a box: curved, converges to the tolerance.
    r = distance(Cylinder(1, 2), Box((2, 2, 2)), None, translation(3, 0, 0))
    assert r.distance == pytest.approx(1.0, abs=1e-9)
    r = distance(Cylinder(1, 2), Sphere(0.5), None, translation(2, 2, 0))
    assert r.distance == pytest.approx(math.sqrt(8) - 1.5, abs=1e-7)
    # Capsule-capsule overlap by the radii only: exact depth.
    p = penetration(Capsule(1, 2), Capsule(1, 2), None, translation(1.5, 0, 0))
    assert p.depth == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(p.normal, [1, 0, 0], atol=1e-12)


def test_degenerate_polytopes_point_segment_polygon():
    point = np.array([[0.0, 0.0, 2.0]])
    segment = np.array([[-1.0, 0.0, 2.0], [1.0, 0.0, 2.0]])
    square = box_corners((2, 2, 0))  # eight points, four distinct: a polygon
    assert distance(CUBE, point).distance == pytest.approx(1.5, abs=1e-12)
    assert distance(CUBE, segment).distance == pytest.approx(1.5, abs=1e-12)
    assert distance(square, point).distance == pytest.approx(2.0, abs=1e-12)
    assert distance(square, segment, None, translation(0, 3, -2)).distance == pytest.approx(2.0)
    assert intersects(square, CUBE)
    assert penetration(square, CUBE).depth == pytest.approx(0.5, abs=1e-12)
    cs = ConvexSet.from_vertices([point, segment, square])
    assert list(np.diff(cs.offsets)) == [1, 2, 4]


def test_overlap_fields():
    r = distance(CUBE, CUBE, None, translation(0.5))
    assert r.distance == 0.0 and r.status == Status.CONVERGED
    np.testing.assert_array_equal(r.normal, [0, 0, 0])
    p = penetration(CUBE, CUBE, None, translation(0.7, 0.1))
    assert p.depth == pytest.approx(0.3, abs=1e-12)
    np.testing.assert_allclose(p.normal, [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(p.point_a - p.point_b, p.depth * p.normal, atol=1e-12)
    s = signed_distance(CUBE, CUBE, None, translation(0.7, 0.1))
    assert s.signed_distance == pytest.approx(-0.3, abs=1e-12)
    assert s.distance == 0.0 and s.depth == pytest.approx(0.3, abs=1e-12)
    # Separated: depth 0, signed distance = distance.
    assert penetration(CUBE, CUBE, None, translation(3.0)).depth == 0.0
    assert signed_distance(CUBE, CUBE, None, translation(3.0)).signed_distance == (
        pytest.approx(2.0, abs=1e-12)
    )


def test_convex_set_layout_and_constructors():
    cs = ConvexSet.from_shapes([CUBE, Sphere(1), Box((2, 4, 6)), Capsule(1, 3), Cylinder(2, 5)])
    assert len(cs) == 5
    assert list(cs.kinds) == [
        ShapeKind.POLYTOPE,
        ShapeKind.SPHERE,
        ShapeKind.BOX,
        ShapeKind.CAPSULE,
        ShapeKind.CYLINDER,
    ]
    np.testing.assert_allclose(cs.params[2, :3], [1, 2, 3])
    np.testing.assert_allclose(cs.params[3, :2], [1, 1.5])
    np.testing.assert_allclose(cs.params[4, :2], [2, 2.5])
    assert list(cs.offsets) == [0, 8, 8, 8, 8, 8]
    assert [cs.primitive(h) for h in range(5)] == [
        None,
        Sphere(1),
        Box((2, 4, 6)),
        Capsule(1, 3),
        Cylinder(2, 5),
    ]
    assert cs.vertices.dtype == np.float64 and cs.offsets.dtype == np.int64
    assert cs.kinds.dtype == np.int8
    with pytest.raises(ValueError):
        cs.vertices[0, 0] = 1.0
    lo, hi = cs.aabbs(np.stack([translation(1)] * 5))
    np.testing.assert_allclose(lo[3], [0, -1, -2.5])
    np.testing.assert_allclose(hi[4], [3, 2, 2.5])
    both = ConvexSet.concatenate(cs, ConvexSet.from_vertices([CUBE * 2]))
    assert len(both) == 6 and list(both.offsets) == [0, 8, 8, 8, 8, 8, 16]
    d1 = distance_batch(both, None, [[0, 5], [2, 5]]).distance
    d2 = [distance(CUBE, CUBE * 2).distance, distance(Box((2, 4, 6)), CUBE * 2).distance]
    np.testing.assert_array_equal(d1, d2)


def test_from_meshes_trimesh_and_body():
    import trimesh

    sphere_mesh = trimesh.creation.icosphere(subdivisions=2)
    body = Body(
        "ball",
        None,
        np.zeros((0, 3)),
        np.zeros((0, 3), np.int64),
        primitive=Sphere(1.0),
    )
    box_body = Body("box", None, CUBE, np.zeros((0, 3), np.int64))
    cs = ConvexSet.from_meshes([sphere_mesh, body, box_body])
    assert list(cs.kinds) == [0, 1, 0]
    assert np.diff(cs.offsets)[0] == len(sphere_mesh.vertices)
    poses_ = np.stack([translation(), translation(3), translation(0, 3)])
    d = distance_batch(cs, poses_, [[0, 1], [1, 2]]).distance
    assert d[0] == pytest.approx(1.0, abs=1e-12)  # icosphere vertices lie on the unit sphere
    assert d[1] == pytest.approx(math.hypot(2.5, 2.5) - 1.0, abs=1e-12)


# ---------------------------------------------------------------------------------------------
# Peer cases (../shared/oracles/cases.json)


def _load_case_ids() -> list:
    if not ORACLES.is_file():
        return [pytest.param(None, marks=pytest.mark.skip(reason="cases.json not present"))]
    # time_of_impact cases are tests/test_toi.py's.
    return [
        pytest.param(case["id"], id=case["id"])
        for case in json.loads(ORACLES.read_text())["cases"]
        if case["query"] != "time_of_impact"
    ]


def _case_shape(spec: dict):
    if spec["type"] == "box":
        return Box(tuple(spec["size"]))
    if spec["type"] == "sphere":
        return Sphere(spec["radius"])
    if spec["type"] == "capsule":
        return Capsule(spec["radius"], spec["length"])
    if spec["type"] == "cylinder":
        return Cylinder(spec["radius"], spec["length"])
    raise AssertionError(f"unknown shape {spec['type']}")


def _case_pose(spec: dict) -> np.ndarray:
    if "matrix3" in spec:
        rotation = np.array(spec["matrix3"], dtype=np.float64)
    else:
        rotation = rotation_from_quaternion(np.array(spec["quaternion_wxyz"], dtype=np.float64))
    return pose_matrix(rotation, spec["position"])


@pytest.mark.parametrize("case_id", _load_case_ids())
def test_peer_case(case_id, oracle_cases):
    case = next(c for c in oracle_cases if c["id"] == case_id)
    a, b = _case_shape(case["a"]), _case_shape(case["b"])
    pa, pb = _case_pose(case["pose_a"]), _case_pose(case["pose_b"])
    expect, tol = case["expect"], case["tolerance"]
    query = case["query"]
    if query == "distance":
        r = distance(a, b, pa, pb)
        assert r.status == Status.CONVERGED
        assert r.distance == pytest.approx(expect["distance"], abs=tol)
    elif query == "signed_distance":
        r = signed_distance(a, b, pa, pb)
        assert r.status == Status.CONVERGED
        assert r.signed_distance == pytest.approx(expect["signed_distance"], abs=tol)
    elif query == "penetration":
        r = penetration(a, b, pa, pb)
        assert r.status == Status.CONVERGED
        assert r.depth == pytest.approx(expect["depth"], abs=tol)
        assert abs(np.dot(r.normal, expect["normal_axis"])) == pytest.approx(1.0, abs=1e-9)
        # a -> b: b moved by depth * normal only touches.
        moved = pb.copy()
        moved[:3, 3] += r.normal * (r.depth + 1e-6)
        assert not intersects(a, b, pa, moved)
    elif query == "intersects":
        assert intersects(a, b, pa, pb) == expect["intersects"]
        if "normal" in expect:
            r = penetration(a, b, pa, pb)
            assert r.depth == pytest.approx(0.0, abs=tol)
            np.testing.assert_allclose(r.normal, expect["normal"], atol=1e-9)
    else:
        raise AssertionError(f"unexpected query {query}")
    if "point_a" in expect:
        np.testing.assert_allclose(r.point_a, expect["point_a"], atol=max(tol, 1e-9) * 10)
        np.testing.assert_allclose(r.point_b, expect["point_b"], atol=max(tol, 1e-9) * 10)


# ---------------------------------------------------------------------------------------------
# Exact oracles


def _structured_boxes(n: int, seed: int):
    """Integer box sizes, rotations in multiples of 45 degrees about axes, integer offsets."""
    rng = np.random.default_rng(seed)
    angles = np.radians(np.arange(8) * 45.0)

    def rot(axis: int, angle: float) -> np.ndarray:
        c, s = math.cos(angle), math.sin(angle)
        i, j = [k for k in range(3) if k != axis]
        r = np.eye(3)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
        return r

    for _ in range(n):
        sizes = rng.integers(1, 4, size=(2, 3)).astype(float)
        rotations = []
        for _ in range(2):
            r = np.eye(3)
            for _ in range(rng.integers(0, 3)):
                r = rot(int(rng.integers(0, 3)), float(rng.choice(angles))) @ r
            rotations.append(r)
        offset = rng.integers(-4, 5, size=3).astype(float)
        yield (
            sizes[0],
            sizes[1],
            pose_matrix(rotations[0], (0, 0, 0)),
            pose_matrix(rotations[1], offset),
        )


def test_structured_box_family_distance_and_depth_exact():
    cases = list(_structured_boxes(400, seed=3))
    boxes, pose_list, pairs = [], [], []
    for sa, sb, pa, pb in cases:
        boxes += [Box(tuple(sa)), Box(tuple(sb)), box_corners(sa), box_corners(sb)]
        pose_list += [pa, pb, pa, pb]
        k = len(boxes) - 4
        pairs += [[k, k + 1], [k + 2, k + 3]]
    cs = ConvexSet.from_shapes(boxes)
    poses_ = np.stack(pose_list)
    res = signed_distance_batch(cs, poses_, pairs)
    assert np.all(res.status == Status.CONVERGED)
    worst = 0.0
    for i, (sa, sb, pa, pb) in enumerate(cases):
        wa, wb = transform(box_corners(sa), pa), transform(box_corners(sb), pb)
        depth = sat_depth(wa, wb)
        truth = polytope_distance(wa, wb) if depth < 0 else 0.0
        true_depth = max(depth, 0.0)
        for k in (2 * i, 2 * i + 1):  # box primitive, then the same box as a polytope
            assert close(res.distance[k], truth), (i, k, res.distance[k], truth)
            assert close(res.depth[k], true_depth), (i, k, res.depth[k], true_depth)
            worst = max(worst, abs(res.distance[k] - truth), abs(res.depth[k] - true_depth))
    assert worst <= 1e-12 * 8


def test_random_hulls_against_oracles():
    rng = np.random.default_rng(11)
    clouds, pose_list, pairs = [], [], []
    for i in range(120):
        for _ in range(2):
            n = int(rng.integers(4, 24))
            clouds.append(rng.normal(size=(n, 3)) * rng.uniform(0.3, 1.5, size=3))
            q = rng.normal(size=4)
            pose_list.append(pose_matrix(rotation_from_quaternion(q), rng.uniform(-2.5, 2.5, 3)))
        pairs.append([2 * i, 2 * i + 1])
    cs = ConvexSet.from_vertices(clouds)
    poses_ = np.stack(pose_list)
    res = signed_distance_batch(cs, poses_, pairs)
    n_overlap = 0
    for i, (ia, ib) in enumerate(pairs):
        wa, wb = transform(clouds[ia], poses_[ia]), transform(clouds[ib], poses_[ib])
        depth = sat_depth(wa, wb)
        if depth >= 0:
            n_overlap += 1
            assert res.distance[i] == 0.0
            assert close(res.depth[i], depth), (i, res.depth[i], depth)
        else:
            truth = polytope_distance(wa, wb)
            assert close(res.distance[i], truth), (i, res.distance[i], truth)
            assert res.depth[i] == 0.0
    assert 20 < n_overlap < 100  # both regimes are exercised


def test_hill_climbing_large_hulls_match_oracle():
    rng = np.random.default_rng(5)
    clouds = []
    for _ in range(8):
        p = rng.normal(size=(80, 3))
        clouds.append(p / np.linalg.norm(p, axis=1)[:, None] * rng.uniform(0.5, 1.5))
    cs = ConvexSet.from_vertices(clouds)
    assert np.all(np.diff(cs.offsets) > 32)  # hill climbing is in use
    pose_list = [
        pose_matrix(rotation_from_quaternion(rng.normal(size=4)), rng.uniform(-2, 2, 3))
        for _ in clouds
    ]
    pairs = np.array([[i, i + 1] for i in range(0, 8, 2)])
    res = signed_distance_batch(cs, np.stack(pose_list), pairs)
    for i, (ia, ib) in enumerate(pairs):
        wa, wb = transform(clouds[ia], pose_list[ia]), transform(clouds[ib], pose_list[ib])
        d = sat_depth(wa, wb)
        if d >= 0:
            assert close(res.depth[i], d, rel=1e-9), (res.depth[i], d)
        else:
            truth = polytope_distance(wa, wb)
            assert close(res.distance[i], truth), (res.distance[i], truth)


def test_hill_climbing_matches_vertex_scan():
    """The climbs (one shape or both at once, warm or cold starts, padded neighbour lists)
    give the same answers as scanning every vertex: the same set packed without adjacency."""
    from meshcol._native import core as _core

    rng = np.random.default_rng(11)
    clouds = []
    for n in (20, 40, 64, 64, 100, 200, 33, 500) * 3:
        p = rng.normal(size=(n, 3))
        clouds.append(p / np.linalg.norm(p, axis=1)[:, None] * rng.uniform(0.5, 1.5, 3))
    cs = ConvexSet.from_vertices(clouds)
    k = np.diff(cs.adjacency_offsets)
    assert np.all(k % 4 == 0) and np.all(k > 0)  # lists padded with the vertex itself
    scan = _core.PackedConvexSet(
        cs.vertices,
        cs.offsets,
        cs.kinds,
        cs.params,
        None,
        None,
        cs.face_offsets,
        cs.face_normals,
        cs.edge_pair_offsets,
        cs.edge_pairs,
    )
    h = len(clouds)
    pose_list = np.stack(
        [
            pose_matrix(rotation_from_quaternion(rng.normal(size=4)), rng.uniform(-1.2, 1.2, 3))
            for _ in range(h)
        ]
    )
    pairs = np.array([(i, j) for i in range(h) for j in range(h) if i != j], dtype=np.int64)
    got = cs._core.query_object(3, pose_list, pairs, 1, SignedDistanceBatch)
    want = scan.query_object(3, pose_list, pairs, 1, SignedDistanceBatch)
    assert np.sum(got.depth > 0) > 10 and np.sum(got.distance > 0) > 10
    np.testing.assert_array_equal(got.status, want.status)
    np.testing.assert_allclose(got.distance, want.distance, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(got.depth, want.depth, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(got.normal, want.normal, atol=1e-9)


@pytest.mark.slow
def test_python_fcl_compared_where_it_is_right():
    fcl = pytest.importorskip("fcl")

    def fcl_distance(sa, pa, sb, pb):
        oa = fcl.CollisionObject(fcl.Box(*sa), fcl.Transform(pa[:3, :3], pa[:3, 3]))
        ob = fcl.CollisionObject(fcl.Box(*sb), fcl.Transform(pb[:3, :3], pb[:3, 3]))
        return fcl.distance(oa, ob, fcl.DistanceRequest(), fcl.DistanceResult())

    # The issue's example: fcl is off by ~5%, meshcol is exact.
    p = rot_z(45, (4, 4, 0))
    assert abs(fcl_distance((2, 2, 2), np.eye(4), (2, 2, 2), p) - (3 * math.sqrt(2) - 1)) > 1e-3
    ours_err, fcl_err, agree = [], [], 0
    for sa, sb, pa, pb in itertools.islice(_structured_boxes(300, seed=8), 300):
        wa, wb = transform(box_corners(sa), pa), transform(box_corners(sb), pb)
        if sat_depth(wa, wb) >= 0:
            continue
        truth = polytope_distance(wa, wb)
        ours = distance(Box(tuple(sa)), Box(tuple(sb)), pa, pb).distance
        theirs = fcl_distance(sa, pa, sb, pb)
        assert close(ours, truth)
        if truth < 1e-9:
            continue  # touching up to rounding: compared absolutely above
        ours_err.append(abs(ours - truth) / truth)
        fcl_err.append(abs(theirs - truth) / truth)
        if fcl_err[-1] < 1e-6:
            agree += 1
            assert abs(ours - theirs) <= 1e-6 * truth
    assert max(ours_err) <= 1e-9
    assert agree > len(fcl_err) // 2  # fcl is right on most pairs: it is a fair comparison


# ---------------------------------------------------------------------------------------------
# Properties


def _tolerance(*shape_list) -> float:
    """Relative tolerance of a depth: EPA converges only slowly on a cylinder's curved side
    (every other shape kind is exact: polytopes by SAT/EPA, spheres and capsules by cores)."""
    return 1e-4 if any(isinstance(s, Cylinder) for s in shape_list) else 1e-7


@given(shapes, shapes, poses(), poses())
def test_symmetry(a, b, pa, pb):
    d_ab = distance(a, b, pa, pb)
    d_ba = distance(b, a, pb, pa)
    assert close(d_ab.distance, d_ba.distance, rel=1e-7, abs_=1e-9)
    p_ab = penetration(a, b, pa, pb)
    p_ba = penetration(b, a, pb, pa)
    assert close(p_ab.depth, p_ba.depth, rel=_tolerance(a, b), abs_=1e-7)


@given(shapes, shapes, poses(), poses(), poses(spread=50.0))
def test_invariance_under_common_rigid_motion(a, b, pa, pb, motion):
    before = signed_distance(a, b, pa, pb)
    after = signed_distance(a, b, motion @ pa, motion @ pb)
    assert close(after.signed_distance, before.signed_distance, rel=_tolerance(a, b), abs_=1e-8)
    if before.distance > 0:
        # Closest points need not be unique (face contact): check their gap instead.
        gap = np.linalg.norm(after.point_b - after.point_a)
        assert close(gap, after.distance, rel=1e-6, abs_=1e-9)


@given(st.lists(shapes, min_size=2, max_size=5), st.data())
def test_aabb_gap_at_most_distance(shape_list, data):
    cs = ConvexSet.from_shapes(shape_list)
    poses_ = np.stack([data.draw(poses()) for _ in shape_list])
    lo, hi = cs.aabbs(poses_)
    pairs = np.array(list(itertools.combinations(range(len(shape_list)), 2)))
    d = distance_batch(cs, poses_, pairs).distance
    for (i, j), dist in zip(pairs, d):
        gap = np.maximum(0.0, np.maximum(lo[i] - hi[j], lo[j] - hi[i]))
        assert np.linalg.norm(gap) <= dist + 1e-9


@given(shapes, shapes, poses(), poses())
def test_intersects_iff_distance_zero(a, b, pa, pb):
    assert intersects(a, b, pa, pb) == (distance(a, b, pa, pb).distance == 0.0)


@given(hulls(), hulls(), poses(spread=0.8), poses(spread=0.8))
def test_depth_normal_separates(a, b, pa, pb):
    r = penetration(a, b, pa, pb)
    assume(r.depth > 1e-3)
    assert r.status == Status.CONVERGED
    eps = 1e-7
    out, inside = pb.copy(), pb.copy()
    out[:3, 3] += (r.depth + eps) * r.normal
    inside[:3, 3] += (r.depth - eps) * r.normal
    assert not intersects(a, b, pa, out)
    assert intersects(a, b, pa, inside)
    np.testing.assert_allclose(r.point_a - r.point_b, r.depth * r.normal, atol=1e-9)


@given(st.lists(shapes, min_size=2, max_size=5), st.data())
def test_batch_equals_loop_of_singles(shape_list, data):
    cs = ConvexSet.from_shapes(shape_list)
    poses_ = np.stack([data.draw(poses()) for _ in shape_list])
    pairs = np.array(list(itertools.permutations(range(len(shape_list)), 2)))
    batch = signed_distance_batch(cs, poses_, pairs, threads=2)
    hits = intersects_batch(cs, poses_, pairs)
    dist = distance_batch(cs, poses_, pairs)
    for k, (i, j) in enumerate(pairs):
        single = signed_distance(shape_list[i], shape_list[j], poses_[i], poses_[j])
        assert batch.signed_distance[k] == single.signed_distance
        np.testing.assert_array_equal(batch.normal[k], single.normal)
        assert hits.intersects[k] == intersects(shape_list[i], shape_list[j], poses_[i], poses_[j])
        assert dist.distance[k] == batch.distance[k]


def test_threads_give_identical_results():
    rng = np.random.default_rng(2)
    clouds = [rng.normal(size=(40, 3)) for _ in range(40)]
    cs = ConvexSet.from_vertices(clouds)
    poses_ = np.stack([translation(*rng.uniform(-3, 3, 3)) for _ in clouds])
    pairs = np.array(list(itertools.combinations(range(40), 2)))
    one = signed_distance_batch(cs, poses_, pairs, threads=1)
    many = signed_distance_batch(cs, poses_, pairs, threads=0)
    np.testing.assert_array_equal(one.signed_distance, many.signed_distance)
    np.testing.assert_array_equal(one.point_a, many.point_a)


def _clouds_one_nan(
    rng: np.random.Generator, count: int, points: int, nan_shape: int, spread: float
) -> tuple[list[np.ndarray], np.ndarray]:
    """``count`` Gaussian clouds of ``points`` points, the first point of shape ``nan_shape``
    NaN, and a translation pose each within ``spread`` of the origin."""
    clouds = [rng.normal(size=(points, 3)) for _ in range(count)]
    clouds[nan_shape][0] = np.nan
    poses_ = np.stack([translation(*rng.uniform(-spread, spread, 3)) for _ in clouds])
    return clouds, poses_


def test_large_set_checks_only_the_shapes_pairs_use():
    # 600 shapes (the per-shape checks run on threads), a NaN shape and a non-rigid pose
    # among them, pairs on a subset: each pair's answer is the two-shape set's, bad ones
    # INVALID_INPUT, the same on any number of threads.
    rng = np.random.default_rng(5)
    clouds, poses_ = _clouds_one_nan(rng, 600, 24, nan_shape=7, spread=6.0)
    cs = ConvexSet.from_vertices(clouds)
    poses_[11, 0, 0] = 2.0  # not rigid
    pairs = np.concatenate([rng.integers(0, 600, size=(300, 2)), [[7, 8], [9, 11], [12, 13]]])
    one = signed_distance_batch(cs, poses_, pairs, threads=1)
    many = signed_distance_batch(cs, poses_, pairs, threads=0)
    for name in ("signed_distance", "normal", "point_a", "point_b", "status", "iterations"):
        np.testing.assert_array_equal(getattr(one, name), getattr(many, name))
    bad = np.isin(pairs, [7, 11]).any(axis=1)
    assert np.all(one.status[bad] == Status.INVALID_INPUT)
    assert np.all(one.status[~bad] != Status.INVALID_INPUT)
    for k in rng.choice(np.flatnonzero(~bad), size=20, replace=False):
        i, j = pairs[k]
        pair_set = cs.take([i, j])
        single = signed_distance_batch(pair_set, poses_[[i, j]], [[0, 1]], threads=1)
        assert single.signed_distance[0] == one.signed_distance[k]


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1.0, 1e3, 1e6])
def test_scale_invariance(scale):
    # Relative tolerances: the same layout at any scale gives the same relative answer.
    p = rot_z(45, (4 * scale, 4 * scale, 0))
    a = box_corners((2, 2, 2)) * scale
    r = distance(a, a, None, p)
    assert close(r.distance, (3 * math.sqrt(2) - 1) * scale, rel=1e-12, abs_=0)
    s = signed_distance(a, a, None, translation(1.5 * scale, 0.5 * scale))
    assert close(s.signed_distance, -0.5 * scale, rel=1e-9, abs_=0)
    t = distance(a, a, None, translation(2 * scale))
    assert t.distance == 0.0 and intersects(a, a, None, translation(2 * scale))


# ---------------------------------------------------------------------------------------------
# Bad input


def test_malformed_calls_raise_value_error_naming_the_argument():
    cs = ConvexSet.from_shapes([CUBE, Sphere(1)])
    with pytest.raises(ValueError, match=r"poses must be \(2, 4, 4\), got \(3, 3\)"):
        distance_batch(cs, np.eye(3), [[0, 1]])
    with pytest.raises(ValueError, match=r"pairs: index 2 out of range for 2 shapes"):
        distance_batch(cs, None, [[0, 2]])
    with pytest.raises(ValueError, match=r"pairs: index -1 out of range"):
        penetration_batch(cs, None, [[-1, 0]])
    with pytest.raises(ValueError, match=r"pairs must be \(P, 2\), got \(3,\)"):
        intersects_batch(cs, None, [0, 1, 1])
    with pytest.raises(ValueError, match=r"pairs must hold integer indices"):
        signed_distance_batch(cs, None, [[0.0, 1.0]])
    with pytest.raises(TypeError, match=r"shapes must be a ConvexSet"):
        distance_batch([CUBE, CUBE], None, [[0, 1]])
    with pytest.raises(ValueError, match=r"vertex_lists\[1\] must be \(n, 3\)"):
        ConvexSet.from_vertices([CUBE, np.zeros((4, 2))])
    with pytest.raises(ValueError, match=r"pose_b must be \(4, 4\)"):
        distance(CUBE, CUBE, None, np.eye(3))
    with pytest.raises(ValueError, match=r"radius must be finite and >= 0"):
        Sphere(-1.0)
    with pytest.raises(ValueError, match=r"size must be \(3,\)"):
        Box((1, 2))
    with pytest.raises(ValueError, match=r"b must be a Sphere"):
        distance(CUBE, object())
    # The native layer checks again (a hand-made set).
    from meshcol._native import core as _core

    with pytest.raises(ValueError, match="offsets"):
        _core.PackedConvexSet(
            CUBE,
            np.array([0, 9]),
            np.zeros(1, np.int8),
            np.zeros((1, 4)),
            None,
            None,
            None,
            None,
            None,
            None,
        )


def test_later_batches_on_a_set_answer_as_a_fresh_set():
    # The set keeps each shape's checked radius from the first batch that uses it: later
    # batches (shapes met before and new ones, the NaN shape, a pose made non-rigid after the
    # first batch) must give a fresh set's answers, bit for bit.
    rng = np.random.default_rng(9)
    clouds, poses_ = _clouds_one_nan(rng, 30, 40, nan_shape=4, spread=3.0)
    kept = ConvexSet.from_vertices(clouds)
    first = np.array([[0, 1], [2, 3], [4, 5], [1, 2]])
    signed_distance_batch(kept, poses_, first, threads=1)
    poses_[3, 0, 0] = 2.0  # not rigid from now on
    later = np.concatenate([first, rng.integers(0, 30, size=(60, 2))])
    for _ in range(2):
        got = signed_distance_batch(kept, poses_, later, threads=1)
        fresh = signed_distance_batch(ConvexSet.from_vertices(clouds), poses_, later, threads=1)
        for name in ("signed_distance", "normal", "point_a", "point_b", "status", "iterations"):
            np.testing.assert_array_equal(getattr(got, name), getattr(fresh, name))
    bad = np.isin(later, [3, 4]).any(axis=1)
    assert np.all(got.status[bad] == Status.INVALID_INPUT)
    assert np.all(got.status[~bad] != Status.INVALID_INPUT)


def test_a_set_is_not_changed_by_writes_to_the_arrays_it_was_made_from():
    # The kept radii are only right while the set's arrays never change: the constructor copies
    # what it is given, so a write through the caller's array (or another view of its memory)
    # after a first batch cannot leave a NaN shape with a radius checked before it (a
    # confident answer instead of INVALID_INPUT).
    rng = np.random.default_rng(3)
    made = ConvexSet.from_vertices([rng.normal(size=(8, 3)), rng.normal(size=(8, 3)) + [5, 0, 0]])
    arrays = {name: np.array(getattr(made, name)) for name in ConvexSet._FIELDS}
    memory = arrays["vertices"]
    arrays["vertices"] = memory[:]  # a view: the set sees no more of the caller's memory
    kinds = np.zeros(2, np.int8)
    params = np.ones((2, 4))
    given = ConvexSet(**arrays)
    primitives = ConvexSet.from_primitives(kinds + ShapeKind.SPHERE, params[:])
    pairs = np.array([[0, 1]])
    before = signed_distance_batch(given, None, pairs, threads=1)
    spheres = signed_distance_batch(primitives, None, pairs, threads=1)
    memory[:] = np.nan
    params[:] = np.nan
    assert memory.flags.writeable and params.flags.writeable  # the caller's arrays stay theirs
    after = signed_distance_batch(given, None, pairs, threads=1)
    np.testing.assert_array_equal(after.signed_distance, before.signed_distance)
    np.testing.assert_array_equal(after.status, [Status.CONVERGED])
    again = signed_distance_batch(primitives, None, pairs, threads=1)
    np.testing.assert_array_equal(again.signed_distance, spheres.signed_distance)
    np.testing.assert_array_equal(again.status, [Status.CONVERGED])
    assert not np.shares_memory(given.vertices, memory)


def test_empty_pairs():
    cs = ConvexSet.from_shapes([CUBE, CUBE])
    r = signed_distance_batch(cs, None, np.zeros((0, 2), np.int64))
    assert r.signed_distance.shape == (0,) and r.point_a.shape == (0, 3)


def test_bad_data_gives_invalid_input_per_pair():
    nan_cloud = CUBE.copy()
    nan_cloud[3, 1] = np.nan
    inf_cloud = CUBE.copy()
    inf_cloud[0, 0] = np.inf
    cs = ConvexSet.from_vertices([CUBE, nan_cloud, inf_cloud, np.zeros((0, 3)), CUBE])
    poses_ = np.stack([translation(), translation(), translation(), translation(), translation(3)])
    pairs = [[0, 1], [0, 2], [0, 3], [0, 4], [4, 0]]
    for fn in (distance_batch, penetration_batch, signed_distance_batch, intersects_batch):
        r = fn(cs, poses_, pairs)
        assert list(r.status) == [Status.INVALID_INPUT] * 3 + [Status.CONVERGED] * 2
    bad_pose = poses_.copy()
    bad_pose[4, 0, 0] = 2.0  # scaled: not rigid
    r = distance_batch(cs, bad_pose, pairs)
    assert r.status[3] == Status.INVALID_INPUT and r.status[4] == Status.INVALID_INPUT
    assert np.isnan(r.distance[3])
    bad_pose[4] = translation(3)
    bad_pose[4, 1, 3] = np.nan
    assert distance_batch(cs, bad_pose, pairs).status[3] == Status.INVALID_INPUT
    mirrored = translation(3)
    mirrored[2, 2] = -1.0  # det -1: a reflection
    assert distance(CUBE, CUBE, None, mirrored).status == Status.INVALID_INPUT
    with pytest.raises(ValueError, match="non-rigid"):
        intersects(CUBE, nan_cloud)
    lo, hi = cs.aabbs()
    assert np.all(np.isnan(lo[1:4])) and np.all(np.isfinite(lo[[0, 4]]))


def test_public_names_are_exported():
    import meshcol.collision.narrowphase
    import meshcol.collision.shapes

    for name in (
        "ConvexSet",
        "Sphere",
        "Box",
        "Capsule",
        "Cylinder",
        "DistanceResult",
        "PenetrationResult",
        "distance",
        "penetration",
        "intersects",
        "signed_distance",
        "distance_batch",
        "penetration_batch",
        "intersects_batch",
        "signed_distance_batch",
        "ShapeKind",
        "SignedDistanceResult",
    ):
        module = (
            meshcol.collision.shapes
            if name in ("ConvexSet", "Sphere", "Box", "Capsule", "Cylinder", "ShapeKind")
            else meshcol.collision.narrowphase
        )
        assert getattr(meshcol, name) is getattr(module, name)
    from meshcol._native import core as _core

    assert _core.defaults.gjk_max_iterations > 0 and _core.defaults.contact_tolerance < 1e-12


def test_bodies_are_queried_at_their_own_pose() -> None:
    """Two unit boxes 5 apart as Bodies: the single-pair queries use Body.pose (issue 11)."""
    import trimesh

    import meshcol

    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    a = Body("a", None, np.asarray(cube.vertices), np.asarray(cube.faces))
    b = Body(
        "b", None, np.asarray(cube.vertices), np.asarray(cube.faces), pose=translation(5, 0, 0)
    )
    assert distance(a, b).distance == pytest.approx(4.0, abs=1e-12)
    assert meshcol.mesh_distance(a, b).distance == pytest.approx(4.0, abs=1e-12)
    # An explicit pose wins over the body's own.
    assert distance(a, b, None, np.eye(4)).distance == pytest.approx(0.0, abs=1e-12)
    # Time of impact: b stays at its own pose, a moves 6 towards it: contact after 4 of 6.
    r = meshcol.time_of_impact(a, b, None, translation(6, 0, 0), None, None)
    assert r.time_of_impact == pytest.approx(4.0 / 6.0, abs=1e-6)


def test_witness_points_are_the_distance_apart_on_a_degenerate_simplex():
    """A cylinder's side against a box edge parallel to it, turned by a motion with 2e-16
    entries: GJK's simplex is nearly degenerate, its barycentric weights inaccurate, and the
    witness points stood 4e-6 (relative) farther apart than the distance (found by
    test_invariance_under_common_rigid_motion). b's point is now a's point minus v."""
    motion = np.array(
        [
            [2.220446049250313e-16, 0, 1, 0],
            [0, -1, 0, 0],
            [1, 0, 2.220446049250313e-16, 0],
            [0, 0, 0, 1],
        ]
    )
    pb = np.eye(4)
    pb[:3, 3] = 1.0
    for pose_a, pose_b in ((np.eye(4), pb), (motion, motion @ pb)):
        r = signed_distance(Cylinder(0.5, 1.625), Box((1.75, 0.5, 1.0)), pose_a, pose_b)
        assert r.distance == pytest.approx(0.26034531628727703, rel=1e-12)
        gap = np.linalg.norm(r.point_b - r.point_a)
        assert gap == pytest.approx(r.distance, rel=1e-12)
