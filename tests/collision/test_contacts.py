"""Mesh contacts (meshcol.collision.contacts): known depths, an exact oracle (the separating
axis theorem over the 11 axes in rational arithmetic), the invariant that moving b by the
depth along the normal separates the deepest pair, the listed contacts, coal as an oracle on
corpus meshes, and every status and error."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import trimesh
from conftest import sized
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from meshcol._native import core
from meshcol.collision.contacts import mesh_contacts_batch
from meshcol.collision.mesh_query import MeshSet
from meshcol.types import Status

FLOOR = np.array([[-10.0, -10, 0], [10, -10, 0], [0, 10, 0]])  # normal +z


def _triangle_set(pairs_of_triangles) -> MeshSet:
    """One-triangle meshes a0, b0, a1, b1, ... (local frames = world)."""
    meshes = []
    for a, b in pairs_of_triangles:
        meshes += [
            (np.asarray(a, float), np.array([[0, 1, 2]])),
            (np.asarray(b, float), np.array([[0, 1, 2]])),
        ]
    return MeshSet.from_arrays(meshes, orient=False, threads=1)


def _triangle_contacts(pairs_of_triangles, **kwargs):
    meshes = _triangle_set(pairs_of_triangles)
    pairs = np.arange(len(meshes), dtype=np.int64).reshape(-1, 2)
    return mesh_contacts_batch(meshes, None, pairs, threads=1, **kwargs)


def _box(lo, hi) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=[lo, hi])


def test_a_spike_through_a_floor_is_its_tip_deep_along_the_floor_normal():
    spike = [[0, 0, -0.3], [1, 0, 2], [-1, 0, 2]]
    r = _triangle_contacts([(FLOOR, spike)])
    assert r.status[0] == Status.CONVERGED
    assert r.count[0] == 1
    assert r.depth[0] == pytest.approx(0.3, abs=1e-15)
    np.testing.assert_allclose(r.normal[0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(r.point[0], [0, 0, -0.15], atol=1e-15)
    assert (r.triangle_a[0], r.triangle_b[0]) == (0, 0)


def test_an_edge_pair_can_be_the_shortest_way_out():
    a = [[-1, 0, 0], [1, 0, 0], [0, 0, -5]]
    b = [[0, -1, -0.1], [0, 1, -0.1], [0, 0, 5]]
    r = _triangle_contacts([(a, b)])
    assert r.depth[0] == pytest.approx(0.1, abs=1e-15)
    np.testing.assert_allclose(r.normal[0], [0, 0, 1], atol=1e-15)


def test_coplanar_and_degenerate_pairs():
    big = [[0, 0, 0], [20, 0, 0], [0, 20, 0]]
    needle = [[0, 0, -0.3], [0, 0, 2], [0, 0, 2]]
    segment, other = [[-1, 0, 0], [1, 0, 0], [1, 0, 0]], [[0, -1, 0], [0, 1, 0], [0, 1, 0]]
    along = [[-2, 0, 0], [0.5, 0, 0], [0.5, 0, 0]]
    r = _triangle_contacts([(FLOOR, big), (FLOOR, needle), (segment, other), (segment, along)])
    assert list(r.count) == [1, 1, 1, 1]
    assert r.depth[0] == 0.0  # coplanar: exactly
    assert abs(r.normal[0][2]) == pytest.approx(1.0)
    assert r.depth[1] == pytest.approx(0.3, abs=1e-15)
    assert r.depth[2] == 0.0  # two crossing segments: a flat difference
    assert r.depth[3] == 0.0 and np.isnan(r.normal[3]).all()  # collinear: no axis at all


def test_many_contacts_are_listed_in_face_order_and_capped_from_the_front():
    """346 crossing pairs of two 5,120-face spheres (the core sorts 256 or more by their bytes):
    listed once each in order of (face a, face b), and a cap keeps the first of that order."""
    sphere = trimesh.creation.icosphere(subdivisions=4)
    meshes = MeshSet.from_arrays([sphere, sphere], threads=1)
    poses = np.stack([np.eye(4), np.eye(4)])
    poses[1, :3, 3] = [0.7, 0.2, 0.1]
    every = mesh_contacts_batch(meshes, poses, [[0, 1]], max_contacts=100_000)
    keys = list(zip(every.contact_triangle_a.tolist(), every.contact_triangle_b.tolist()))
    assert len(keys) == every.count[0] == 346
    assert keys == sorted(set(keys))
    assert max(a for a, _ in keys) > 256 and max(b for _, b in keys) > 256  # more than one byte
    capped = mesh_contacts_batch(meshes, poses, [[0, 1]], max_contacts=300)
    assert capped.count[0] == 346
    kept = list(zip(capped.contact_triangle_a.tolist(), capped.contact_triangle_b.tolist()))
    assert kept == keys[:300]


def test_a_bar_through_a_box_face_is_its_end_deep():
    """The bar's end is 0.1 inside the box; its sides cross only the box's x = 1 face."""
    box, bar = _box([-1, -1, -1], [1, 1, 1]), _box([0.9, -0.5, -0.5], [3, 0.5, 0.5])
    meshes = MeshSet.from_arrays([box, bar], threads=1)
    r = mesh_contacts_batch(meshes, None, [[0, 1]], max_contacts=100)
    assert r.count[0] > 0
    assert r.depth[0] == pytest.approx(0.1, abs=1e-14)
    np.testing.assert_allclose(r.normal[0], [1, 0, 0], atol=1e-14)
    x_face = np.flatnonzero(np.isclose(box.triangles_center[:, 0], 1.0))
    assert r.triangle_a[0] in x_face
    assert r.contact_offsets.tolist() == [0, r.count[0]]
    assert set(r.contact_triangle_a) <= set(x_face)
    assert r.contact_depth.max() == r.depth[0]
    keys = list(zip(r.contact_triangle_a, r.contact_triangle_b))
    assert keys == sorted(keys)
    # moving the bar out by the depth leaves the box's face touched, not crossed
    moved = np.eye(4)
    moved[0, 3] = 0.1 + 1e-12
    out = mesh_contacts_batch(meshes, np.stack([np.eye(4), moved]), [[0, 1]])
    assert out.count[0] == 0


def test_disjoint_and_nested_meshes_have_no_contact():
    box, small = _box([-1, -1, -1], [1, 1, 1]), _box([-0.2, -0.2, -0.2], [0.2, 0.2, 0.2])
    away = np.eye(4)
    away[0, 3] = 5
    meshes = MeshSet.from_arrays([box, small, small], np.stack([np.eye(4), np.eye(4), away]))
    r = mesh_contacts_batch(meshes, None, [[0, 1], [0, 2]], max_contacts=5)
    assert r.count.tolist() == [0, 0]
    assert r.depth.tolist() == [0.0, 0.0]
    assert np.isnan(r.normal).all() and np.isnan(r.point).all()
    assert r.triangle_a.tolist() == [-1, -1]
    assert r.contact_offsets.tolist() == [0, 0, 0]
    assert r.contact_normal.shape == (0, 3)


def _sat_depth2(a, b) -> Fraction:
    """The squared penetration depth of two intersecting integer triangles, exactly: the
    minimum over the 11 axes (a zero cross product is no axis) of overlap^2 / |axis|^2."""
    a = [[Fraction(int(x)) for x in p] for p in a]
    b = [[Fraction(int(x)) for x in p] for p in b]

    def sub(p, q):
        return [p[0] - q[0], p[1] - q[1], p[2] - q[2]]

    def cross(p, q):
        return [p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]]

    def dot(p, q):
        return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]

    ea = [sub(a[1], a[0]), sub(a[2], a[1]), sub(a[0], a[2])]
    eb = [sub(b[1], b[0]), sub(b[2], b[1]), sub(b[0], b[2])]
    axes = [cross(ea[0], ea[1]), cross(eb[0], eb[1])] + [cross(x, y) for x in ea for y in eb]
    best = None
    for c in axes:
        if not any(c):
            continue
        pa, pb = [dot(c, p) for p in a], [dot(c, p) for p in b]
        overlap = max(min(max(pa) - min(pb), max(pb) - min(pa)), Fraction(0))
        d2 = overlap * overlap / dot(c, c)
        best = d2 if best is None or d2 < best else best
    return Fraction(0) if best is None else best


def test_depths_equal_the_exact_separating_axis_oracle_on_integer_triangles():
    rng = np.random.default_rng(5)
    count = sized(4000)  # 2,000 in the fast lane: the oracle's rationals take most of the time
    candidates = [(rng.integers(-4, 5, (3, 3)), rng.integers(-4, 5, (3, 3))) for _ in range(count)]
    # some coplanar and degenerate ones on purpose: b in a's plane z = 0, repeated corners
    for k in range(0, 400, 4):
        a, b = candidates[k]
        a[:, 2] = 0
        b[:, 2] = 0
        candidates[k + 1][1][2] = candidates[k + 1][1][1]
    r = _triangle_contacts(candidates)
    crossing = np.flatnonzero(r.count == 1)
    assert len(crossing) > count // 4
    exact = np.array([float(_sat_depth2(*candidates[k])) for k in crossing])
    np.testing.assert_allclose(r.depth[crossing] ** 2, exact, rtol=1e-12, atol=1e-24)
    assert (r.depth[crossing] == 0.0).sum() >= (exact == 0.0).sum()  # exact zeros stay zero


@st.composite
def _crossing_triangles(draw):
    """Two triangles, most of them crossing: b is moved (when drawn so) so that its centroid
    lands on a's, a point of both up to rounding; the others stay where they were drawn."""
    coords = st.floats(-1, 1, allow_nan=False, allow_infinity=False, width=64)
    a = np.array(draw(st.lists(coords, min_size=9, max_size=9))).reshape(3, 3)
    b = np.array(draw(st.lists(coords, min_size=9, max_size=9))).reshape(3, 3)
    if draw(st.booleans()):
        b = b - b.mean(axis=0) + a.mean(axis=0)
    return a, b


@settings(max_examples=300, deadline=None)
@given(_crossing_triangles())
def test_moving_b_by_the_depth_along_the_normal_separates_the_pair(pair):
    a, b = pair
    r = _triangle_contacts([(a, b)])
    assume(r.count[0] == 1)  # a pair that does not cross has nothing to check
    depth, normal = r.depth[0], r.normal[0]
    assert depth >= 0.0
    assert depth <= r.face_depth[0] + 1e-12  # the minimum translation: no more than coal's
    if np.isnan(normal).any():  # two parallel segments or points: a flat difference
        assert depth == 0.0
        return
    assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-12)
    moved = b + (depth + 1e-9) * normal
    after = _triangle_contacts([(a, moved)])
    assert after.count[0] == 0


def test_listed_contacts_match_per_pair_calls_and_the_deepest():
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    poses = np.tile(np.eye(4), (4, 1, 1))
    poses[1, :3, 3] = (0.5, 0.1, 0.0)
    poses[2, :3, :3] = trimesh.transformations.euler_matrix(0.3, 0.2, 0.1)[:3, :3]
    poses[3, :3, 3] = (9, 0, 0)
    meshes = MeshSet.from_arrays([torus] * 4, poses)
    pairs = np.array([[0, 1], [0, 2], [0, 3], [1, 2]])
    whole = mesh_contacts_batch(meshes, None, pairs, max_contacts=10**6, threads=2)
    assert whole.contact_offsets[-1] == whole.count.sum()
    assert whole.count[2] == 0 and whole.count[[0, 1, 3]].min() > 0
    for k in range(len(pairs)):
        one = mesh_contacts_batch(meshes, None, pairs[k : k + 1], max_contacts=10**6, threads=1)
        rows = slice(whole.contact_offsets[k], whole.contact_offsets[k + 1])
        np.testing.assert_array_equal(one.contact_depth, whole.contact_depth[rows])
        np.testing.assert_array_equal(one.contact_triangle_b, whole.contact_triangle_b[rows])
        assert one.depth[0] == whole.depth[k] or (k == 2 and one.depth[0] == 0.0)
        if whole.count[k]:
            assert whole.contact_depth[rows].max() == whole.depth[k]
            assert (whole.contact_depth[rows] >= 0).all()
    few = mesh_contacts_batch(meshes, None, pairs, max_contacts=3)
    assert np.diff(few.contact_offsets).tolist() == np.minimum(whole.count, 3).tolist()
    np.testing.assert_array_equal(few.depth, whole.depth)
    np.testing.assert_array_equal(few.count, whole.count)


def _crossing_pairs_by_brute_force(a: trimesh.Trimesh, b: trimesh.Trimesh, shift):
    """Every (face of a, face of b) pair that crosses, b moved by ``shift`` (a's frame): each
    pair whose boxes touch, by the exact one-triangle query; and how many pairs touch."""
    ta = np.asarray(a.vertices)[a.faces]
    tb = (np.asarray(b.vertices) + np.asarray(shift, float))[b.faces]
    lo_a, hi_a, lo_b, hi_b = ta.min(1), ta.max(1), tb.min(1), tb.max(1)
    touch = ((lo_a[:, None] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None])).all(-1)
    i, j = np.nonzero(touch)
    crossing = _triangle_contacts(list(zip(ta[i], tb[j]))).count == 1
    return set(zip(i[crossing].tolist(), j[crossing].tolist())), len(i)


@pytest.mark.parametrize("case", ["tori", "boxes flush"])
def test_equal_rotations_list_every_crossing_pair(case):
    """Pairs whose poses' rotations are equal take the axis-aligned descent (b's node boxes
    moved by the translation): it lists exactly the crossing pairs of every triangle pair whose
    boxes touch, surfaces resting flush on each other included, and max_work counts each of
    those pairs once (CHANGELOG, session 28)."""
    if case == "tori":
        a = b = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
        shift, least = (0.45, 0.1, 0.05), 100
    else:  # b's bottom face on a's top face: every gap there is exactly 0
        a, b = _box((0, 0, 0), (2, 2, 1)), _box((0.5, 0.25, 0), (1.5, 1.75, 1))
        shift, least = (0.0, 0.0, 1.0), 8
    pose_b = np.eye(4)
    pose_b[:3, 3] = shift
    meshes = MeshSet.from_arrays([a, b], np.stack([np.eye(4), pose_b]), orient=False, threads=1)
    r = mesh_contacts_batch(meshes, None, [[0, 1]], max_contacts=10**6, threads=1)
    listed = set(zip(r.contact_triangle_a.tolist(), r.contact_triangle_b.tolist()))
    expected, touching = _crossing_pairs_by_brute_force(a, b, shift)
    assert len(expected) >= least and listed == expected
    assert r.count[0] == len(expected)
    for cap, status in ((touching, Status.CONVERGED), (touching - 1, Status.MAX_ITERATIONS)):
        capped = mesh_contacts_batch(meshes, None, [[0, 1]], max_work=cap, threads=1)
        assert capped.status[0] == status


def test_every_status():
    box = _box([-1, -1, -1], [1, 1, 1])
    sheared, far, near = np.eye(4), np.eye(4), np.eye(4)
    sheared[0, 1] = 0.5
    far[0, 3] = 1e40
    near[:3, 3] = (0.5, 0.25, 0.125)
    empty = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    meshes = MeshSet.from_arrays(
        [box, box, box, box, empty], np.stack([np.eye(4), sheared, far, near, np.eye(4)])
    )
    r = mesh_contacts_batch(meshes, None, [[0, 1], [0, 2], [0, 3], [0, 4]])
    assert r.status.tolist() == [
        Status.INVALID_INPUT,
        Status.OUT_OF_RANGE,
        Status.CONVERGED,
        Status.INVALID_INPUT,
    ]
    assert np.isnan(r.depth[[0, 1, 3]]).all()
    capped = mesh_contacts_batch(meshes, None, [[0, 3]], max_work=2)
    assert capped.status[0] == Status.MAX_ITERATIONS
    assert capped.count[0] <= min(2, r.count[2])
    assert core.defaults.mesh_contacts_max_work > 10**6


def test_errors_name_the_argument():
    meshes = MeshSet.from_arrays([_box([-1, -1, -1], [1, 1, 1])] * 2)
    with pytest.raises(ValueError, match=r"^max_contacts must be >= 0, got -1$"):
        mesh_contacts_batch(meshes, None, [[0, 1]], max_contacts=-1)
    with pytest.raises(ValueError, match=r"^max_work must be >= 0, got -5$"):
        mesh_contacts_batch(meshes, None, [[0, 1]], max_work=-5)
    with pytest.raises(ValueError, match="out of range"):
        mesh_contacts_batch(meshes, None, [[0, 2]])
    with pytest.raises(ValueError, match=r"poses must be \(2, 4, 4\)"):
        mesh_contacts_batch(meshes, np.eye(4)[None], [[0, 1]])
    with pytest.raises(TypeError, match="meshes must be a MeshSet, got list"):
        mesh_contacts_batch([], None, [[0, 1]])  # type: ignore[arg-type]


def _pose_translated(x, y, z) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = (x, y, z)
    return pose


@pytest.mark.parametrize("case", ["balls", "torus"])
def test_contacts_agree_with_coal_on_corpus_meshes(corpus, case):
    """bench_mesh_query.py's depth cases: every crossing pair is one of coal's contacts, with
    coal's per-pair depth as face_depth; coal's other contacts are pairs its GJK puts within
    its tolerance that the exact test finds apart; the minimum translation is never more."""
    coal = pytest.importorskip("coal")
    models = corpus / "trimesh-models"
    if case == "balls":
        a, b = (trimesh.load(models / n, force="mesh") for n in ("ballA.off", "ballB.off"))
        pose_b = np.eye(4)
    else:
        a = b = trimesh.load(models / "torus.STL", force="mesh")
        e = float(a.extents[0])
        pose_b = _pose_translated(0.3 * e, 0.01 * e, 0)
    meshes = MeshSet.from_arrays([a, b], np.stack([np.eye(4), pose_b]))
    r = mesh_contacts_batch(meshes, None, [[0, 1]], max_contacts=10**6)
    models_coal = []
    for m in (a, b):
        model = coal.BVHModelOBBRSS()
        model.beginModel(len(m.faces), len(m.vertices))
        model.addVertices(np.asarray(m.vertices, float))
        model.addTriangles(np.asarray(m.faces, np.int64))
        model.endModel()
        models_coal.append(model)
    request = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 10**6)
    result = coal.CollisionResult()
    coal.collide(
        models_coal[0],
        coal.Transform3s(np.eye(3), np.zeros(3)),
        models_coal[1],
        coal.Transform3s(np.ascontiguousarray(pose_b[:3, :3]), np.ascontiguousarray(pose_b[:3, 3])),
        request,
        result,
    )
    theirs = {(c.b1, c.b2): abs(c.penetration_depth) for c in result.getContacts()}
    ours = {
        (int(i), int(j)): (d, f)
        for i, j, d, f in zip(
            r.contact_triangle_a, r.contact_triangle_b, r.contact_depth, r.contact_face_depth
        )
    }
    assert r.count[0] == len(ours) > 100
    assert set(ours) <= set(theirs)
    tolerance = request.gjk_tolerance  # coal's GJK and EPA tolerance, 1e-6
    extra = sorted(set(theirs) - set(ours))
    if extra:
        ta = a.vertices[a.faces[[k[0] for k in extra]]]
        tb = b.vertices[b.faces[[k[1] for k in extra]]] @ pose_b[:3, :3].T + pose_b[:3, 3]
        gaps, _, _, hit = core.triangle_distance_batch(
            np.ascontiguousarray(ta), np.ascontiguousarray(tb)
        )
        assert not hit.any() and gaps.max() <= tolerance
    for key, (depth, face_depth) in ours.items():
        assert face_depth == pytest.approx(theirs[key], abs=request.epa_tolerance)
        assert depth <= face_depth + 1e-12
    assert r.face_depth[0] == pytest.approx(max(theirs[k] for k in ours), abs=request.epa_tolerance)
    assert r.depth[0] == r.contact_depth.max()
