"""Ray casts on meshes (meshcol.collision.ray_cast): known hits, a brute-force oracle, the
invariance under a common rigid motion, and the errors and statuses of bad rays."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from meshcol.collision.mesh_query import MeshSet
from meshcol.collision.ray_cast import mesh_ray_cast_batch
from meshcol.types import Status

BOX = trimesh.creation.box(extents=(1.0, 1.0, 1.0))  # [-0.5, 0.5]^3, outward-wound


def _pose(rotation: np.ndarray, translation) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = translation
    return pose


def _rotation(angles) -> np.ndarray:
    return trimesh.transformations.euler_matrix(*angles)[:3, :3]


def _brute_force(vertices, faces, origins, directions):
    """Nearest hit distance of each ray over every triangle (Moller-Trumbore), inf for none."""
    unit = directions / np.linalg.norm(directions, axis=1)[:, None]
    t0, t1, t2 = (vertices[faces[:, k]] for k in range(3))
    e1, e2 = t1 - t0, t2 - t0
    best = np.full(len(origins), np.inf)
    for k, (o, d) in enumerate(zip(origins, unit)):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - t0
            u = np.einsum("ij,ij->i", s, p) * inv
            q = np.cross(s, e1)
            v = (q @ d) * inv
            t = np.einsum("ij,ij->i", e2, q) * inv
        ok = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0)
        if ok.any():
            best[k] = t[ok].min()
    return best


def test_a_ray_straight_down_lands_on_the_top_face() -> None:
    meshes = MeshSet.from_arrays([(BOX.vertices, BOX.faces)])
    r = mesh_ray_cast_batch(meshes, 0, [[0.1, 0.2, 3.0]], [[0.0, 0.0, -5.0]])
    assert r.hit.tolist() == [True]
    assert r.status.tolist() == [Status.CONVERGED]
    assert r.distance[0] == pytest.approx(2.5, abs=1e-15)
    assert r.point[0] == pytest.approx([0.1, 0.2, 0.5], abs=1e-15)
    assert r.normal[0] == pytest.approx([0.0, 0.0, 1.0], abs=1e-15)
    assert BOX.face_normals[r.triangle[0]] == pytest.approx([0.0, 0.0, 1.0])


def test_posed_meshes_each_ray_against_its_own_mesh() -> None:
    turned = _pose(_rotation((0.0, 0.0, math.pi / 4)), [10.0, 0.0, 0.0])
    meshes = MeshSet.from_arrays([(BOX.vertices, BOX.faces)] * 2, np.stack([np.eye(4), turned]))
    r = mesh_ray_cast_batch(
        meshes,
        [0, 1, 1],
        [[0, 0, 3], [20, 0, 0.1], [20, 5, 0]],
        [[0, 0, -1], [-1, 0, 0], [-1, 0, 0]],
    )
    assert r.hit.tolist() == [True, True, False]
    assert r.distance[:2] == pytest.approx([2.5, 10 - math.sqrt(0.5)], abs=1e-12)
    assert math.isinf(r.distance[2]) and r.triangle[2] == -1
    assert np.isnan(r.point[2]).all() and np.isnan(r.normal[2]).all()


def test_a_ray_down_a_shared_edge_or_at_a_corner_still_hits() -> None:
    meshes = MeshSet.from_arrays([(BOX.vertices, BOX.faces)])
    # every face of the box is two triangles: rays down both diagonals of the top face, and
    # one at a corner along the main diagonal
    origins = [[0.25, 0.25, 2.0], [0.25, -0.25, 2.0], [-0.25, 0.25, 2.0], [2.5, 2.5, 2.5]]
    directions = [[0, 0, -1], [0, 0, -1], [0, 0, -1], [-1, -1, -1]]
    r = mesh_ray_cast_batch(meshes, 0, origins, directions)
    assert r.hit.all()
    assert r.distance == pytest.approx([1.5, 1.5, 1.5, 2 * math.sqrt(3)], abs=1e-12)


def test_the_distance_cap_and_a_ray_from_the_surface() -> None:
    meshes = MeshSet.from_arrays([(BOX.vertices, BOX.faces)])
    down = [[0.0, 0.0, 3.0]], [[0.0, 0.0, -1.0]]
    assert not mesh_ray_cast_batch(meshes, 0, *down, max_distance=2.4).hit[0]
    assert mesh_ray_cast_batch(meshes, 0, *down, max_distance=2.5).hit[0]
    from_top = mesh_ray_cast_batch(meshes, 0, [[0.0, 0.0, 0.5]], [[0.0, 0.0, 1.0]])
    assert from_top.hit[0] and from_top.distance[0] == 0.0
    inside = mesh_ray_cast_batch(meshes, 0, [[0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]])
    assert inside.distance[0] == pytest.approx(0.5, abs=1e-15)
    assert inside.normal[0] == pytest.approx([1.0, 0.0, 0.0])  # the face's side: along the ray


def test_hits_agree_with_brute_force_on_a_posed_sphere() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=3)
    pose = _pose(_rotation((0.3, -1.1, 2.0)), [0.4, -0.2, 1.5])
    meshes = MeshSet.from_arrays([(sphere.vertices, sphere.faces)], pose[None])
    rng = np.random.default_rng(7)
    origins = rng.uniform(-3, 3, size=(400, 3)) + pose[:3, 3]
    targets = rng.uniform(-1.2, 1.2, size=(400, 3)) + pose[:3, 3]
    directions = targets - origins
    r = mesh_ray_cast_batch(meshes, 0, origins, directions, threads=1)
    world = sphere.vertices @ pose[:3, :3].T + pose[:3, 3]
    expected = _brute_force(world, sphere.faces, origins, directions)
    assert np.array_equal(r.hit, np.isfinite(expected))
    assert r.hit.sum() > 150  # most aim at the sphere
    assert r.distance[r.hit] == pytest.approx(expected[r.hit], rel=1e-12, abs=1e-12)
    unit = directions / np.linalg.norm(directions, axis=1)[:, None]
    assert r.point[r.hit] == pytest.approx(origins[r.hit] + unit[r.hit] * r.distance[r.hit, None])
    # the batch is a loop of single rays, on any number of threads
    again = mesh_ray_cast_batch(meshes, 0, origins, directions, threads=0)
    for name in ("hit", "distance", "point", "normal", "triangle", "status"):
        assert np.array_equal(getattr(r, name), getattr(again, name), equal_nan=name != "hit")


@given(
    angles=st.tuples(*[st.floats(-math.pi, math.pi)] * 3),
    shift=st.tuples(*[st.floats(-50, 50)] * 3),
)
def test_a_common_rigid_motion_moves_the_hits_with_it(angles, shift) -> None:
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    motion = _pose(_rotation(angles), shift)
    rng = np.random.default_rng(3)
    origins = rng.uniform(-2, 2, size=(60, 3))
    directions = rng.normal(size=(60, 3))
    here = mesh_ray_cast_batch(
        MeshSet.from_arrays([(torus.vertices, torus.faces)]), 0, origins, directions
    )
    moved = mesh_ray_cast_batch(
        MeshSet.from_arrays([(torus.vertices, torus.faces)], motion[None]),
        0,
        origins @ motion[:3, :3].T + motion[:3, 3],
        directions @ motion[:3, :3].T,
    )
    # a hit within rounding of a face's edge may go to its neighbour: same distance either way
    assert np.array_equal(here.hit, moved.hit)
    assert moved.distance[moved.hit] == pytest.approx(here.distance[here.hit], rel=1e-9, abs=1e-9)


def test_bad_rays_get_a_status_and_bad_arguments_an_error() -> None:
    skewed = np.eye(4)
    skewed[0, 0] = 2.0
    meshes = MeshSet.from_arrays([(BOX.vertices, BOX.faces)] * 2, np.stack([np.eye(4), skewed]))
    r = mesh_ray_cast_batch(
        meshes,
        [0, 0, 1],
        [[0, 0, 3], [np.nan, 0, 3], [0, 0, 3]],
        [[0, 0, 0], [0, 0, -1], [0, 0, -1]],
    )
    assert r.status.tolist() == [Status.INVALID_INPUT] * 3
    assert np.isnan(r.distance).all() and not r.hit.any()
    with pytest.raises(ValueError, match=r"mesh_indices: index 2 out of range for 2 meshes"):
        mesh_ray_cast_batch(meshes, 2, [[0, 0, 3]], [[0, 0, -1]])
    with pytest.raises(ValueError, match=r"directions must be \(1, 3\) like origins, got \(2, 3\)"):
        mesh_ray_cast_batch(meshes, 0, [[0, 0, 3]], [[0, 0, -1], [0, 0, 1]])
    with pytest.raises(ValueError, match=r"mesh_indices must be \(1,\) or one index, got \(2,\)"):
        mesh_ray_cast_batch(meshes, [0, 1], [[0, 0, 3]], [[0, 0, -1]])
    with pytest.raises(ValueError, match=r"max_distance must be >= 0, got -1.0"):
        mesh_ray_cast_batch(meshes, 0, [[0, 0, 3]], [[0, 0, -1]], max_distance=-1)
    with pytest.raises(TypeError, match="meshes must be a MeshSet"):
        mesh_ray_cast_batch([BOX], 0, [[0, 0, 3]], [[0, 0, -1]])
