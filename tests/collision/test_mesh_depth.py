"""Mesh penetration depth and the status of concave pairs (issue 12, item 2).

A cube lowered into a concave host (a box with a cavity, a mug, a shape sorter) until the
triangles touch, then moved by 0, +-1e-9, +-1e-7 along the approach, is a resting contact: its
status must come from the meshes, never from the hulls' depth (which called 16 of 28 such
sub-tolerance overlaps penetrating, by up to 0.148 on a 1 m host). The mesh depth is a lower
bound of the minimum translation distance; for boxes that is checked against the analytic one.
"""

from __future__ import annotations

import math
from pathlib import Path

import manifold3d
import numpy as np
import pytest
import trimesh
from hypothesis import example, given
from hypothesis import strategies as st
from oracles import quaternion_rotation

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.collision.mesh_query import (
    MeshSet,
    mesh_intersection_volume,
    mesh_penetration_depth_batch,
)
from meshcol.types import Body, Scene, Status

OFFSETS = (0.0, 1e-9, -1e-9, 1e-7, -1e-7)
TOLERANCE = 1e-6  # CheckOptions' default


def box(lower, upper) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=[lower, upper])


def _solid(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    return manifold3d.Manifold(
        manifold3d.Mesh64(
            np.ascontiguousarray(mesh.vertices, dtype=np.float64),
            np.ascontiguousarray(mesh.faces, dtype=np.uint64),
        )
    )


def _mesh(solid: manifold3d.Manifold) -> trimesh.Trimesh:
    m = solid.to_mesh64()
    return trimesh.Trimesh(
        np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts, dtype=np.int64), process=False
    )


def _cylinder(radius: float, z0: float, z1: float, x: float = 0.0, y: float = 0.0):
    return manifold3d.Manifold.cylinder(z1 - z0, radius, radius, 48).translate((x, y, z0))


# Each host: (mesh, the cube resting in it touching the triangles, the approach axis).
# The hosts are about 1 m across, as in the issue.


def box_with_cavity():
    host = _solid(box([0, 0, 0], [1, 1, 1])) - _solid(box([0.25, 0.25, 0.5], [0.75, 0.75, 2]))
    return _mesh(host), box([0.3, 0.3, 0.5], [0.7, 0.7, 0.9])


def mug():
    body = _cylinder(0.5, 0.0, 1.0) - _cylinder(0.4, 0.1, 2.0)
    handle = manifold3d.Manifold.cube((0.3, 0.1, 0.6)).translate((0.45, -0.05, 0.2))
    handle -= manifold3d.Manifold.cube((0.2, 0.2, 0.4)).translate((0.45, -0.1, 0.3))
    return _mesh(body + handle), box([-0.2, -0.2, 0.1], [0.2, 0.2, 0.5])


def shape_sorter():
    # A square pocket exactly as wide as the cube (walls touching all round, top flush with
    # the host's top) and a round hole through.
    host = _solid(box([0, 0, 0], [1, 1, 0.5]))
    host -= _solid(box([0.1, 0.1, 0.2], [0.4, 0.4, 1.0]))
    host -= _cylinder(0.15, -1.0, 1.0, 0.7, 0.7)
    return _mesh(host), box([0.1, 0.1, 0.2], [0.4, 0.4, 0.5])


def bowl_host():
    # A hemispherical shell; the cube's bottom face rests on a flat inner floor cut into it.
    shell = manifold3d.Manifold.sphere(1.0, 64) - manifold3d.Manifold.sphere(0.9, 64)
    shell -= manifold3d.Manifold.cube((4, 4, 4)).translate((-2, -2, 0))
    floor = manifold3d.Manifold.cube((1.2, 1.2, 0.3)).translate((-0.6, -0.6, -1.0))
    host = (shell + floor) ^ manifold3d.Manifold.sphere(1.0, 64)
    return _mesh(host), box([-0.2, -0.2, -0.7], [0.2, 0.2, -0.3])


HOSTS = {
    "box_with_cavity": box_with_cavity(),
    "mug": mug(),
    "shape_sorter": shape_sorter(),
    "bowl": bowl_host(),
}


def _pose(rotation: np.ndarray | None = None, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def _scene(host: trimesh.Trimesh, cube: trimesh.Trimesh, offset: float, motion: np.ndarray):
    """Host and cube under a common rigid motion, the cube moved by offset along the approach
    (the host's z axis: positive lifts it)."""
    lift = _pose(translation=(0.0, 0.0, offset))
    return Scene(
        (
            Body("host", None, np.asarray(host.vertices), np.asarray(host.faces), motion),
            Body("cube", None, np.asarray(cube.vertices), np.asarray(cube.faces), motion @ lift),
        )
    )


def test_hosts_are_closed_and_the_cubes_sit_in_their_hulls() -> None:
    for name, (host, cube) in HOSTS.items():
        assert host.is_watertight and host.is_winding_consistent and host.volume > 0, name
        hull = MeshSet.from_arrays([host.convex_hull, cube])
        depth = mesh_penetration_depth_batch(hull, None, [[0, 1]]).depth[0]
        # the hull-based depth the issue saw: far above the tolerance for every host
        assert depth > 0.05, name


@pytest.mark.parametrize("name", sorted(HOSTS))
@pytest.mark.parametrize("offset", OFFSETS)
def test_cube_resting_in_a_concave_host_is_contact(name: str, offset: float) -> None:
    host, cube = HOSTS[name]
    report = check_scene(_scene(host, cube, offset, np.eye(4)), CheckOptions(collider="mesh"))
    (pair,) = report.pairs
    assert pair["status"] == "contact", pair
    assert report.passed
    assert pair["depth"] <= max(0.0, -offset) * (1 + 1e-6) + 1e-12
    assert pair["distance"] <= max(0.0, offset) * (1 + 1e-6) + 1e-12
    assert abs(pair["signed_distance"]) <= TOLERANCE
    assert pair["intersection_volume"] is None  # only penetrating pairs get one
    assert not pair["query_failed"]


quaternion = st.tuples(*[st.floats(-1, 1) for _ in range(4)]).filter(
    lambda q: sum(x * x for x in q) > 0.01
)
translation = st.tuples(*[st.floats(-10, 10) for _ in range(3)])


@given(st.sampled_from(sorted(HOSTS)), st.sampled_from(OFFSETS), quaternion, translation)
def test_resting_contact_under_any_rigid_motion_is_never_penetrating(
    name: str, offset: float, q, t
) -> None:
    """The class of the defect: rounding of a rotated, translated scene makes the touching
    triangles cross by ~1e-16 to 1e-7; the status must stay contact and the depth tiny."""
    host, cube = HOSTS[name]
    scene = _scene(host, cube, offset, _pose(quaternion_rotation(q), t))
    (pair,) = check_scene(scene, CheckOptions(collider="mesh")).pairs
    assert pair["status"] == "contact", pair
    assert pair["depth"] <= 1e-7 + 1e-9


@pytest.mark.parametrize("name", sorted(HOSTS))
def test_cube_sunk_into_the_floor_reports_the_sinking_as_depth(name: str) -> None:
    """Sunk by 0.01 into the host's floor: the minimum translation distance is 0.01 (lift it
    back), and the mesh depth finds exactly that; penetrating, with the overlap's volume."""
    host, cube = HOSTS[name]
    sink = 0.01
    report = check_scene(_scene(host, cube, -sink, np.eye(4)), CheckOptions(collider="mesh"))
    (pair,) = report.pairs
    assert pair["status"] == "penetrating"
    assert pair["depth"] == pytest.approx(sink, rel=1e-9)
    assert pair["depth"] <= sink * (1 + 1e-12)
    assert pair["normal"] == pytest.approx([0, 0, 1], abs=1e-9)  # the cube (b) moves up
    side = np.ptp(cube.vertices, axis=0)
    assert pair["intersection_volume"] == pytest.approx(side[0] * side[1] * sink, rel=1e-6)
    assert not report.passed


box_extent = st.tuples(*[st.floats(0.05, 2.0) for _ in range(3)])
box_centre = st.tuples(*[st.floats(-1.0, 1.0) for _ in range(3)])


@given(box_extent, box_centre, box_extent, box_centre)
@example((1.0, 1.0, 2.0), (0.5, 0.0, 0.0), (1.0, 1.0, 2.0), (0.0, -0.25, -0.5))
@example((1.0, 1.0, 2.0), (0.5, 0.25, -0.5), (1.0, 1.0, 2.0), (0.0, 0.0, 0.0))
def test_depth_of_overlapping_boxes_never_exceeds_the_translation_distance(ea, ca, eb, cb) -> None:
    """For axis-aligned boxes the minimum translation distance is along an axis (their
    Minkowski difference is a box): the smallest over the axes of the shorter push out,
    min(hi_a - lo_b, hi_b - lo_a). The mesh depth is a lower bound of it, and not a useless
    one: positive whenever the boxes overlap by more than rounding."""
    ea, ca, eb, cb = (np.array(v) for v in (ea, ca, eb, cb))
    lo_a, hi_a, lo_b, hi_b = ca - ea / 2, ca + ea / 2, cb - eb / 2, cb + eb / 2
    push = np.minimum(hi_a - lo_b, hi_b - lo_a)
    mtd = float(max(0.0, push.min()))
    meshes = MeshSet.from_arrays([box(lo_a, hi_a), box(lo_b, hi_b)])
    r = mesh_penetration_depth_batch(meshes, None, [[0, 1], [1, 0]])
    assert (r.status == Status.CONVERGED).all()
    assert r.depth[0] <= mtd * (1 + 1e-12) + 1e-12
    assert r.depth[1] == pytest.approx(r.depth[0], rel=1e-12, abs=1e-15)
    if mtd > 1e-9:
        assert r.depth[0] > 0.0
        # the witness pair: b moves along the normal, point_b - point_a = -depth * normal
        gap = r.point_b[0] - r.point_a[0]
        assert gap == pytest.approx(-r.depth[0] * r.normal[0], abs=1e-12)
    else:
        assert np.isnan(r.normal[0]).all() or r.depth[0] <= 1e-9


def test_crossing_bars_with_flush_faces_are_penetrating() -> None:
    """No vertex of either bar is inside the other and every edge lies on the other's surface
    or outside it: only points off both surfaces (stepped in from the crossing) see the
    overlap. Minimum translation distance 0.2."""
    a = box([-2, -0.1, -0.1], [2, 0.1, 0.1])
    b = box([-0.1, -2, -0.1], [0.1, 2, 0.1])
    r = mesh_penetration_depth_batch(MeshSet.from_arrays([a, b]), None, [[0, 1]])
    assert 0.05 < r.depth[0] <= 0.2


def test_coincident_duplicates_are_penetrating() -> None:
    """A body duplicated onto itself (a common authoring slip): every surface point of one lies
    on the other, yet the overlap is total (minimum translation distance 1)."""
    a = box([0, 0, 0], [1, 1, 1])
    scene = Scene(
        tuple(Body(n, None, np.asarray(a.vertices), np.asarray(a.faces)) for n in ("a", "b"))
    )
    (pair,) = check_scene(scene, CheckOptions(collider="mesh")).pairs
    assert pair["status"] == "penetrating"
    assert 0.1 < pair["depth"] <= 1.0
    assert pair["intersection_volume"] == pytest.approx(1.0, rel=1e-9)


def test_edge_through_a_thin_wall_counts() -> None:
    """A tilted bar pierces a thin wall: its vertices are all outside the wall, and the wall's
    vertices all outside the bar; the pieces of the bar's edges inside the wall give depth."""
    wall = box([-1, -1, -0.05], [1, 1, 0.05])
    bar = trimesh.creation.box(extents=[0.1, 0.1, 1.0])
    tilt = _pose(quaternion_rotation([math.cos(0.2), math.sin(0.2), 0, 0]))
    meshes = MeshSet.from_arrays([wall, bar], np.stack([np.eye(4), tilt]))
    r = mesh_penetration_depth_batch(meshes, None, [[0, 1]])
    assert 0.0 < r.depth[0] <= 0.05 + 1e-12


def test_nested_pair_gets_the_depth_of_its_deepest_vertex() -> None:
    small, big = box([0.4] * 3, [0.6] * 3), box([0, 0, 0], [1, 1, 1])
    r = mesh_penetration_depth_batch(MeshSet.from_arrays([small, big]), None, [[0, 1]])
    assert r.depth[0] == pytest.approx(0.4, abs=1e-12)
    assert r.deepest_mesh[0] == 0


def test_separated_pair_has_no_depth_and_invalid_pairs_say_so() -> None:
    a, b = box([0, 0, 0], [1, 1, 1]), box([2, 0, 0], [3, 1, 1])
    v = np.asarray(a.vertices).copy()
    v[0, 0] = np.nan
    meshes = MeshSet.from_arrays([a, b, (v, a.faces)])
    r = mesh_penetration_depth_batch(meshes, None, [[0, 1], [0, 2]])
    assert r.depth[0] == 0.0 and r.deepest_mesh[0] == -1 and np.isnan(r.normal[0]).all()
    assert r.status[0] == Status.CONVERGED
    assert r.status[1] == Status.INVALID_INPUT and math.isnan(r.depth[1])


def test_intersection_volume_needs_two_closed_meshes() -> None:
    a, b = box([0, 0, 0], [1, 1, 1]), box([0.5, 0.5, 0.5], [2, 2, 2])
    open_a = (np.asarray(a.vertices), np.asarray(a.faces)[:-1])
    meshes = MeshSet.from_arrays([a, b, open_a])
    volumes = mesh_intersection_volume(meshes, None, [[0, 1], [1, 0], [2, 1]])
    assert volumes[:2] == pytest.approx([0.125, 0.125], rel=1e-12)
    assert math.isnan(volumes[2])


def _open_copy(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """The mesh plus one tiny stray triangle far away: no longer closed, so the core decides
    inside by the generalized winding number instead of exact ray crossings."""
    v = np.asarray(mesh.vertices)
    far = v.max(axis=0) + 10.0
    stray = np.array([far, far + [1e-3, 0, 0], far + [0, 1e-3, 0]])
    faces = np.vstack([np.asarray(mesh.faces), len(v) + np.arange(3)[None]])
    return np.vstack([v, stray]), faces


def test_core_closedness_agrees_with_topology() -> None:
    from meshcol.geometry.topology import is_closed_manifold

    meshes = [host for host, _ in HOSTS.values()] + [cube for _, cube in HOSTS.values()]
    meshes += [_open_copy(m) for m in meshes[:2]]
    flipped = box([0, 0, 0], [1, 1, 1])
    half = np.asarray(flipped.faces).copy()
    half[:2] = half[:2, ::-1]  # two faces wound the other way
    meshes += [(flipped.vertices, half), (flipped.vertices, np.asarray(flipped.faces)[:-1])]
    s = MeshSet.from_arrays(meshes)
    for i in range(len(s)):
        assert s._handle.closed(i) == is_closed_manifold(s.mesh(i)[1]), i


@given(st.sampled_from(sorted(HOSTS)), quaternion, st.tuples(*[st.floats(-0.5, 0.5)] * 3))
# a wedge point on the cavity's wall plane, on an edge between two coplanar triangles: the
# generalized winding number of the open copy cancelled to 0 there (0.2167 against 0.2330)
@example("box_with_cavity", (0.0, 0.0, 0.5, 1.0), (0.25, 0.0, 0.125))
def test_exact_ray_crossings_agree_with_the_winding_number(name: str, q, t) -> None:
    """The depth of a closed pair (inside decided by exact signed ray crossings) equals the
    depth of the same pair made open by a stray far triangle (generalized winding number)."""
    host, _ = HOSTS[name]
    cube = box([-0.3, -0.3, -0.3], [0.3, 0.3, 0.3])
    pose = _pose(quaternion_rotation(q), np.array(t) + host.bounds.mean(axis=0))
    closed = MeshSet.from_arrays([host, cube], np.stack([np.eye(4), pose]))
    opened = MeshSet.from_arrays([_open_copy(host), cube], np.stack([np.eye(4), pose]))
    assert closed._handle.closed(0) and not opened._handle.closed(0)
    a = mesh_penetration_depth_batch(closed, None, [[0, 1], [1, 0]])
    b = mesh_penetration_depth_batch(opened, None, [[0, 1], [1, 0]])
    assert a.depth == pytest.approx(b.depth, rel=1e-9, abs=1e-12)


SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.parametrize("offset", OFFSETS)
def test_sample_ball_lowered_onto_the_bowl_is_contact(offset: float) -> None:
    """samples/bowl with --shape mesh passes (a gap of about 0.05); lowered along the closest
    points' normal until the triangles touch, then moved by the offsets, it still passes."""
    from meshcol.io.scene import load_scene

    scene = load_scene(SAMPLES / "bowl" / "scene.json")
    report = check_scene(scene, CheckOptions(collider="mesh"))
    (pair,) = report.pairs
    assert pair["status"] == "separated" and report.passed
    normal, gap = np.array(pair["normal"]), pair["distance"]
    bodies = list(scene.bodies)
    moved = next(i for i, b in enumerate(bodies) if b.name == pair["body_b"])
    shift = _pose(translation=-(gap - offset) * normal)
    b = bodies[moved]
    bodies[moved] = Body(b.name, b.source, b.vertices, b.faces, shift @ b.pose)
    (touching,) = check_scene(Scene(tuple(bodies)), CheckOptions(collider="mesh")).pairs
    assert touching["status"] == "contact", touching
    assert touching["depth"] <= max(0.0, -offset) + 1e-12


@pytest.mark.slow
def test_fans_stacked_face_to_face_stop_at_the_near_pair_cap() -> None:
    """Two cylinders of 5,000 sections stacked cap to cap: every triangle of one cap touches
    every triangle of the other at the centre, 25 million near pairs, past the core's
    ``mesh_depth_max_near_pairs`` (24 million; 8,000 sections took 1.6 GB and 21 s). The depth
    is MAX_ITERATIONS with depth 0 (nothing decided: still a lower bound), and ``check``
    reports the pair as a failed query, not a clean contact; 1,000 sections, 1e6 near pairs,
    are decided: a contact, depth 0."""
    from meshcol._native import core

    assert core.defaults.mesh_depth_max_near_pairs == 24_000_000
    for sections, status in ((5000, Status.MAX_ITERATIONS), (1000, Status.CONVERGED)):
        cylinder = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=sections)
        meshes = MeshSet.from_arrays([cylinder, cylinder])
        poses = np.stack([np.eye(4), np.eye(4)])
        poses[1, 2, 3] = 1.0
        r = mesh_penetration_depth_batch(meshes, poses, [[0, 1]])
        assert r.status[0] == status and r.depth[0] == 0.0
        v, f = np.asarray(cylinder.vertices), np.asarray(cylinder.faces)
        scene = Scene(tuple(Body(name, None, v, f, pose) for name, pose in zip("ab", poses)))
        (pair,) = check_scene(scene, CheckOptions(collider="mesh")).pairs
        assert pair["query_failed"] == (status == Status.MAX_ITERATIONS), pair
        assert pair["status"] == "contact" and pair["distance"] == 0.0, pair
