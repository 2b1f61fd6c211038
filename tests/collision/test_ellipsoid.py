"""Exact ellipsoids (``Ellipsoid``, ``ShapeKind.ELLIPSOID``): known answers, certificates,
coal, and time of impact by dense sampling.

The tight oracle is a certificate from support functions computed here in numpy (the core's
are not used): for a separated pair, the plane normal to the reported normal gives a lower
bound of the distance (the gap between the shapes' supports along it) and the witness points
an upper bound; for a penetrating pair, the overlap of the supports along the reported normal
bounds the minimum translation from above, and along any other direction too. coal 3.0.3 is a
loose oracle here: its default GJK stops up to 3e-5 from the distance on ellipsoid pairs at
``gjk_tolerance`` 1e-12 (its Nesterov variant within about 4e-8), and its EPA, at
``epa_tolerance`` 1e-6, reports depths up to 2e-3 (relative) off the least overlap, and none
at all (``-DBL_MAX``) on some pairs below 1e-8; so meshcol is held to the certificates (1e-11
for distances, EPA's curved tolerance for depths) and to coal at coal's own accuracy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from strategies import pose_matrix, rotation_from_quaternion

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Cylinder,
    Ellipsoid,
    Sphere,
    distance,
    interpolate_pose,
    penetration,
    time_of_impact,
)
from meshcol.collision.narrowphase import signed_distance, signed_distance_batch
from meshcol.types import (
    Status,
    TimeOfImpactStatus,
    primitive_mesh,
    primitive_reach,
    primitive_vertex_count,
)

KINDS = ("sphere", "box", "capsule", "cylinder", "polytope", "ellipsoid")


def rotation(rng: np.random.Generator) -> np.ndarray:
    return rotation_from_quaternion(rng.normal(size=4))


def pose(turn: np.ndarray | None = None, at=(0.0, 0.0, 0.0)) -> np.ndarray:
    return pose_matrix(np.eye(3) if turn is None else turn, at)


def random_shape(rng: np.random.Generator, kind: str):
    if kind == "ellipsoid":
        return Ellipsoid(tuple(rng.uniform(0.2, 1.5, 3)))
    if kind == "sphere":
        return Sphere(rng.uniform(0.2, 1.0))
    if kind == "box":
        return Box(tuple(rng.uniform(0.3, 2.0, 3)))
    if kind == "capsule":
        return Capsule(rng.uniform(0.2, 0.8), rng.uniform(0.2, 2.0))
    if kind == "cylinder":
        return Cylinder(rng.uniform(0.2, 0.8), rng.uniform(0.2, 2.0))
    points = rng.normal(size=(20, 3)) * rng.uniform(0.3, 1.0, 3)
    from scipy.spatial import ConvexHull

    return points[ConvexHull(points).vertices]


def support(shape, world: np.ndarray, n: np.ndarray) -> float:
    """max over the shape at ``world`` of ``n . x``, from its definition."""
    turn, t = world[:3, :3], world[:3, 3]
    local = turn.T @ n
    if isinstance(shape, Ellipsoid):
        return float(n @ t + np.linalg.norm(np.asarray(shape.semi_axes) * local))
    if isinstance(shape, Sphere):
        return float(n @ t + shape.radius * np.linalg.norm(n))
    if isinstance(shape, Box):
        return float(n @ t + np.abs(local) @ (np.asarray(shape.size) / 2.0))
    if isinstance(shape, Capsule):
        return float(n @ t + shape.radius * np.linalg.norm(n) + shape.length / 2 * abs(local[2]))
    if isinstance(shape, Cylinder):
        return float(
            n @ t + shape.radius * math.hypot(local[0], local[1]) + shape.length / 2 * abs(local[2])
        )
    return float(n @ t + np.max(np.asarray(shape) @ local))


def support_point(shape, world: np.ndarray, n: np.ndarray) -> np.ndarray:
    """A point of the shape at ``world`` where ``n . x`` is largest (``n`` unit)."""
    turn, t = world[:3, :3], world[:3, 3]
    u = turn.T @ n
    if isinstance(shape, Ellipsoid):
        axes = np.asarray(shape.semi_axes)
        local = axes**2 * u / np.linalg.norm(axes * u)
    elif isinstance(shape, Sphere):
        local = shape.radius * u
    elif isinstance(shape, Box):
        local = np.where(u >= 0.0, 1.0, -1.0) * np.asarray(shape.size) / 2.0
    elif isinstance(shape, Capsule):
        local = np.array([0.0, 0.0, math.copysign(shape.length / 2, u[2])]) + shape.radius * u
    elif isinstance(shape, Cylinder):
        planar = math.hypot(u[0], u[1])
        local = np.array(
            [
                shape.radius * u[0] / planar,
                shape.radius * u[1] / planar,
                math.copysign(shape.length / 2, u[2]),
            ]
        )
    else:
        points = np.asarray(shape)
        local = points[np.argmax(points @ u)]
    return turn @ local + t


def overlap(a, pose_a, b, pose_b, n: np.ndarray) -> float:
    """How far the shapes overlap along the unit ``n`` (a to b): negative when the plane
    normal to ``n`` separates them, by that gap."""
    return support(a, pose_a, n) + support(b, pose_b, -n)


def pairs(seed: int, kind: str, count: int, reach: float):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        a, b = random_shape(rng, "ellipsoid"), random_shape(rng, kind)
        pose_a = pose(rotation(rng), rng.normal(size=3) * 0.2)
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        pose_b = pose(rotation(rng), pose_a[:3, 3] + direction * rng.uniform(0.0, reach))
        yield a, b, pose_a, pose_b


# --- the type and its packing ---------------------------------------------------------------


def test_ellipsoid_is_validated_and_frozen():
    e = Ellipsoid((1, 2.5, 0))
    assert e.semi_axes == (1.0, 2.5, 0.0) and all(type(v) is float for v in e.semi_axes)
    for bad in [(1, -1, 1), (1, math.nan, 1), (1, math.inf, 1)]:
        with pytest.raises(ValueError, match="semi_axes must be finite and >= 0"):
            Ellipsoid(bad)
    with pytest.raises(ValueError, match=r"semi_axes must be \(3,\), got \(2,\)"):
        Ellipsoid((1, 2))
    with pytest.raises(AttributeError):
        e.semi_axes = (1.0, 1.0, 1.0)  # type: ignore[misc]


def test_tessellation_is_the_unit_icosphere_scaled_as_the_mjcf_reader_made_it():
    import trimesh

    axes = (0.3, 0.05, 0.12)
    vertices, faces = primitive_mesh(Ellipsoid(axes))
    unit = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    expected = np.array(unit.vertices, dtype=np.float64) * np.asarray(axes, dtype=np.float64)
    assert vertices.tobytes() == expected.tobytes()
    assert faces.tobytes() == np.array(unit.faces, dtype=np.int64).tobytes()
    assert primitive_vertex_count(Ellipsoid(axes)) == len(vertices) == 642
    assert primitive_vertex_count(Ellipsoid((1e-9, 1e9, 0.0))) == 642
    assert np.linalg.norm(vertices, axis=1).max() <= primitive_reach(Ellipsoid(axes))
    assert primitive_reach(Ellipsoid(axes)) == pytest.approx(0.3, rel=1e-11)


def test_packed_as_its_kind_and_semi_axes():
    e = Ellipsoid((0.5, 0.25, 2.0))
    shapes = ConvexSet.from_shapes([e, Sphere(1.0)])
    assert int(shapes.kinds[0]) == 5 and shapes.params[0].tolist() == [0.5, 0.25, 2.0, 0.0]
    assert shapes.primitive(0) == e
    again = ConvexSet.from_primitives([5], [[0.5, 0.25, 2.0, 0.0]])
    assert again.primitive(0) == e
    with pytest.raises(ValueError, match="SPHERE to HALFSPACE"):  # 6 is an MJCF plane's
        ConvexSet.from_primitives([7], [[1.0, 1.0, 1.0, 0.0]])
    low, high = shapes.aabbs(np.stack([pose(), pose()]))
    assert low[0].tolist() == [-0.5, -0.25, -2.0] and high[0].tolist() == [0.5, 0.25, 2.0]


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(*[st.floats(0.0, 10.0)] * 3),
    st.tuples(*[st.floats(-1.0, 1.0)] * 4),
    st.tuples(*[st.floats(-5.0, 5.0)] * 3),
)
def test_world_box_is_exact(axes, quaternion, at):
    """The world AABB's faces touch the ellipsoid: half extent sqrt(sum_j (R_ij a_j)^2)."""
    q = np.asarray(quaternion)
    if np.linalg.norm(q) < 1e-3:
        q = np.array([1.0, 0.0, 0.0, 0.0])
    turn = rotation_from_quaternion(q)
    world = pose(turn, at)
    shapes = ConvexSet.from_shapes([Ellipsoid(axes)])
    low, high = shapes.aabbs(world[None])
    half = np.sqrt(((turn * np.asarray(axes)) ** 2).sum(axis=1))
    np.testing.assert_allclose(high[0], np.asarray(at) + half, rtol=0, atol=1e-12)
    np.testing.assert_allclose(low[0], np.asarray(at) - half, rtol=0, atol=1e-12)
    for k in range(3):
        e = np.eye(3)[k]
        assert high[0][k] == pytest.approx(support(Ellipsoid(axes), world, e), abs=1e-12)


# --- known answers ----------------------------------------------------------------------------


@pytest.mark.parametrize("phi", [0.0, 0.3, 1.0, math.pi / 2])
def test_distance_to_a_box_face_is_the_reach_along_its_normal(phi):
    """Turned by phi about z, the ellipsoid reaches sqrt((a cos)^2 + (b sin)^2) along x."""
    a, b = 0.5, 2.0
    e, box = Ellipsoid((a, b, 1.25)), Box((2.0, 10.0, 10.0))
    turn = rotation_from_quaternion(np.array([math.cos(phi / 2), 0.0, 0.0, math.sin(phi / 2)]))
    reach = math.hypot(a * math.cos(phi), b * math.sin(phi))
    r = distance(e, box, pose(turn), pose(None, (4.0, 0.1, -0.2)))
    assert r.status == Status.CONVERGED
    assert r.distance == pytest.approx(3.0 - reach, abs=1e-12)
    sunk = penetration(e, box, pose(turn), pose(None, (1.0 + reach - 0.1, 0.1, -0.2)))
    assert sunk.depth == pytest.approx(0.1, rel=1e-7)
    assert sunk.normal == pytest.approx([1.0, 0.0, 0.0], abs=1e-6)


def test_a_round_ellipsoid_answers_as_the_sphere():
    rng = np.random.default_rng(7)
    for _ in range(60):
        r = rng.uniform(0.2, 1.0)
        other = random_shape(rng, str(rng.choice(KINDS)))
        pa, pb = pose(rotation(rng)), pose(rotation(rng), rng.normal(size=3))
        e = signed_distance(Ellipsoid((r, r, r)), other, pa, pb)
        s = signed_distance(Sphere(r), other, pa, pb)
        if s.signed_distance > 0:
            assert e.signed_distance == pytest.approx(s.signed_distance, abs=1e-12)
        else:
            assert e.signed_distance == pytest.approx(s.signed_distance, rel=2e-7, abs=1e-12)


def test_distance_to_a_point_is_the_closest_point_of_the_surface():
    """A point (a sphere of radius 0) outside: the closest point solves
    sum (a_i p_i / (t + a_i^2))^2 = 1 for t >= 0, bisected here."""
    rng = np.random.default_rng(3)
    for _ in range(100):
        axes = rng.uniform(0.2, 1.5, 3)
        p = rng.normal(size=3) * 2.0
        if ((p / axes) ** 2).sum() <= 1.05:
            continue
        lo, hi = 0.0, 10.0 * float(np.linalg.norm(axes * p))
        for _ in range(200):
            t = 0.5 * (lo + hi)
            lo, hi = (t, hi) if ((axes * p / (t + axes**2)) ** 2).sum() > 1.0 else (lo, t)
        closest = axes**2 * p / (lo + axes**2)
        r = distance(Ellipsoid(tuple(axes)), Sphere(0.0), None, pose(None, p))
        assert r.distance == pytest.approx(float(np.linalg.norm(p - closest)), abs=1e-12)


def test_touching_pairs_are_at_distance_zero():
    """b moved so that its support point along -n is a's along n: the plane normal to n
    through it holds them apart, and they share that point."""
    rng = np.random.default_rng(11)
    for kind in KINDS:
        for a, b, pose_a, _ in pairs(100 + KINDS.index(kind), kind, 20, 1.0):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            pose_b = pose(rotation(rng))
            pose_b[:3, 3] = support_point(a, pose_a, n) - support_point(b, pose_b, -n)
            r = signed_distance(a, b, pose_a, pose_b)
            assert abs(r.signed_distance) <= 1e-9, (kind, r)
            assert r.normal @ n == pytest.approx(1.0, abs=1e-5) or r.distance == 0.0


def test_flat_and_degenerate_ellipsoids():
    disc = Ellipsoid((2.0, 1.0, 0.0))
    assert distance(disc, Sphere(0.25), None, pose(None, (0.3, 0.2, 0.5))).distance == (
        pytest.approx(0.25, abs=1e-12)
    )
    assert distance(disc, Sphere(0.25), None, pose(None, (3.0, 0.0, 0.0))).distance == (
        pytest.approx(0.75, abs=1e-12)
    )
    point = Ellipsoid((0.0, 0.0, 0.0))
    assert distance(point, Box((1.0, 1.0, 1.0)), None, pose(None, (0, 3, 4))).distance == (
        pytest.approx(math.hypot(2.5, 3.5), abs=1e-12)
    )


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e150, 1e300])
def test_huge_and_tiny_ellipsoids_answer_as_the_unit_sized_pair(scale):
    """The core rescales a pair by a power of two; the semi-axes are lengths like the rest."""
    e, s = Ellipsoid((1.0, 2.0, 0.5)), Sphere(0.25)
    big_e, big_s = Ellipsoid((scale, 2.0 * scale, 0.5 * scale)), Sphere(0.25 * scale)
    for at, rel in [((3.0, 0.5, 0.2), 1e-12), ((1.0, 0.5, 0.2), 2e-7)]:  # apart, overlapping
        unit = signed_distance(e, s, None, pose(None, at))
        scaled = signed_distance(big_e, big_s, None, pose(None, np.asarray(at) * scale))
        assert scaled.status == Status.CONVERGED
        assert scaled.signed_distance / scale == pytest.approx(unit.signed_distance, rel=rel)


def test_batch_on_threads_is_the_loop_of_single_pairs_and_symmetric():
    """A set mixing ellipsoids with every kind, its pairs on two threads: each answer the
    single pair's, bit for bit; swapped pairs the same distance, the normal reversed; a common
    rigid motion changes no distance."""
    rng = np.random.default_rng(21)
    shapes = [random_shape(rng, KINDS[k % len(KINDS)]) for k in range(60)]
    shapes += [random_shape(rng, "ellipsoid") for _ in range(60)]
    poses = np.stack([pose(rotation(rng), rng.normal(size=3) * 2.0) for _ in shapes])
    pairs = np.array([(k, 60 + k) for k in range(60)] + [(60 + k, k) for k in range(60)])
    batch = signed_distance_batch(ConvexSet.from_shapes(shapes), poses, pairs, threads=2)
    for row, (i, j) in enumerate(pairs[:60]):
        one = signed_distance(shapes[i], shapes[j], poses[i], poses[j])
        assert batch.signed_distance[row] == one.signed_distance
        assert batch.normal[row].tobytes() == one.normal.tobytes()
        swapped = batch.signed_distance[60 + row]
        if one.signed_distance > 0:
            assert swapped == pytest.approx(one.signed_distance, abs=1e-11)
            assert batch.normal[60 + row] == pytest.approx(-one.normal, abs=1e-5)
        else:
            assert swapped == pytest.approx(one.signed_distance, rel=2e-7, abs=1e-12)
    motion = pose(rotation(rng), (5.0, -3.0, 2.0))
    moved = signed_distance_batch(
        ConvexSet.from_shapes(shapes), motion @ poses, pairs[:60], threads=2
    )
    separated = batch.signed_distance[:60] > 0
    np.testing.assert_allclose(
        moved.signed_distance[separated], batch.signed_distance[:60][separated], atol=1e-11
    )


# --- certificates -----------------------------------------------------------------------------


@pytest.mark.parametrize("kind", KINDS)
def test_separated_distances_are_certified_to_1e_11(kind):
    """lower (the gap along the reported normal) <= distance <= |point_a - point_b|, both
    within 1e-11 (on these unit-sized pairs), with point_a on the ellipsoid's surface.

    The gap is within 1e-13 of the distance on most pairs; an ellipsoid against a face or an
    edge (box, cylinder, polytope) ends GJK where its simplex, a sliver, makes no more progress
    in floating point: up to 9e-12 here."""
    rng = np.random.default_rng(5)
    count = 0
    for a, b, pose_a, pose_b in pairs(1000 + KINDS.index(kind), kind, 120, 4.0):
        r = distance(a, b, pose_a, pose_b)
        if r.distance <= 1e-6:
            continue
        count += 1
        assert r.status == Status.CONVERGED
        gap = -overlap(a, pose_a, b, pose_b, r.normal)
        assert r.distance - gap <= 1e-11 and gap - r.distance <= 1e-12, (r.distance, gap)
        assert np.linalg.norm(r.point_b - r.point_a) - r.distance <= 1e-12
        local = pose_a[:3, :3].T @ (r.point_a - pose_a[:3, 3])
        assert ((local / np.asarray(a.semi_axes)) ** 2).sum() == pytest.approx(1.0, abs=1e-10)
        for u in rng.normal(size=(20, 3)):  # point_b is in b: below b's support everywhere
            assert u @ r.point_b <= support(b, pose_b, u) + 1e-12
    assert count >= 30


@pytest.mark.parametrize("kind", KINDS)
def test_penetration_depths_are_certified(kind):
    """The depth is the overlap along the reported normal to EPA's curved tolerance (1e-7,
    relative), and no direction overlaps less (random ones, and coal's when installed)."""
    rng = np.random.default_rng(9)
    count = 0
    for a, b, pose_a, pose_b in pairs(2000 + len(kind), kind, 100, 1.2):
        r = penetration(a, b, pose_a, pose_b)
        if r.depth <= 1e-6:
            continue
        count += 1
        along = overlap(a, pose_a, b, pose_b, r.normal)
        assert 0.0 <= along - r.depth <= 2e-7 * r.depth + 1e-12, (r.depth, along)
        directions = rng.normal(size=(200, 3))
        least = min(overlap(a, pose_a, b, pose_b, u / np.linalg.norm(u)) for u in directions)
        assert r.depth <= least + 1e-12
    assert count >= 30


# --- coal -------------------------------------------------------------------------------------


def _coal_shape(coal, shape):
    if isinstance(shape, Ellipsoid):
        return coal.Ellipsoid(*shape.semi_axes)
    if isinstance(shape, Sphere):
        return coal.Sphere(shape.radius)
    if isinstance(shape, Box):
        return coal.Box(*shape.size)
    if isinstance(shape, Capsule):
        return coal.Capsule(shape.radius, shape.length)
    if isinstance(shape, Cylinder):
        return coal.Cylinder(shape.radius, shape.length)
    points = coal.StdVec_Vec3s()
    for p in np.asarray(shape):
        points.append(np.array(p))
    return coal.Convex.convexHull(points, False, None)


def _coal_transform(coal, world: np.ndarray):
    return coal.Transform3s(np.ascontiguousarray(world[:3, :3]), np.ascontiguousarray(world[:3, 3]))


@pytest.mark.parametrize("kind", KINDS)
def test_coal_agrees_to_its_own_accuracy(kind):
    coal = pytest.importorskip("coal")
    separated = penetrating = 0
    for a, b, pose_a, pose_b in pairs(3000 + len(kind), kind, 100, 3.0):
        ca, cb = _coal_shape(coal, a), _coal_shape(coal, b)
        ta, tb = _coal_transform(coal, pose_a), _coal_transform(coal, pose_b)
        r = signed_distance(a, b, pose_a, pose_b)
        if r.signed_distance > 1e-6:
            request = coal.DistanceRequest()
            request.gjk_tolerance = 1e-12
            request.gjk_variant = coal.GJKVariant.NesterovAcceleration
            request.gjk_max_iterations = 10000
            result = coal.DistanceResult()
            coal.distance(ca, ta, cb, tb, request, result)
            assert r.signed_distance == pytest.approx(result.min_distance, abs=1e-7)
            separated += 1
        elif r.signed_distance < -1e-6:
            request = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 1)
            request.epa_tolerance = 1e-6
            result = coal.CollisionResult()
            coal.collide(ca, ta, cb, tb, request, result)
            assert result.isCollision()
            contact = result.getContacts()[0]
            coal_depth = -contact.penetration_depth
            # no more than the overlap along coal's normal (the depth is the least overlap),
            # and as deep as coal's to coal's tolerance
            normal = np.asarray(contact.normal, dtype=np.float64)
            assert -r.signed_distance <= overlap(a, pose_a, b, pose_b, normal) + 1e-12
            assert -r.signed_distance == pytest.approx(coal_depth, rel=5e-3)
            penetrating += 1
    assert separated >= 20 and penetrating >= 10


# --- time of impact ---------------------------------------------------------------------------


def test_time_of_impact_of_a_turning_ellipsoid_is_where_dense_sampling_finds_contact():
    """A long ellipsoid turning a quarter turn as it slides past a box: it reaches the box
    only by turning."""
    case = dict(
        a=Ellipsoid((2.0, 0.15, 0.2)),
        b=Box((0.5, 0.5, 0.5)),
        start_pose_a=pose(None, (0.0, -0.6, 0.0)),
        end_pose_a=pose(rotation_from_quaternion(np.array([1.0, 0.0, 0.0, 1.0])), (0.3, -0.6, 0.0)),
        start_pose_b=pose(None, (1.4, 0.9, 0.0)),
        end_pose_b=pose(None, (1.4, 0.9, 0.0)),
    )

    def gap(t: float) -> float:
        pa = interpolate_pose(case["start_pose_a"], case["end_pose_a"], t)
        return distance(case["a"], case["b"], pa, case["start_pose_b"]).distance

    assert gap(0.0) > 0.1 and gap(1.0) > 0.0
    tol = 1e-7
    r = time_of_impact(**case, tolerance=tol)
    assert r.status == TimeOfImpactStatus.HIT
    assert gap(r.time_of_impact) <= tol
    ts = np.linspace(0.0, 1.0, 2001)
    first = next(i for i, t in enumerate(ts) if gap(t) == 0.0)
    lo, hi = ts[first - 1], ts[first]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if gap(mid) == 0.0 else (mid, hi)
    assert r.time_of_impact <= hi and hi - r.time_of_impact < 1e-5
