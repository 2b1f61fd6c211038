"""The hierarchy's fast paths against the exact sums they replace.

The fast winding number (Barill et al. 2018, with a rigorous remainder bound) against the
O(F) sum of solid angles, its containment verdicts against thresholding that sum, and the
distance traversal on oriented node boxes against a brute-force minimum over triangle pairs.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st
from oracles import quaternion_rotation

from meshcol._native import core as _core
from meshcol.collision.mesh_query import MeshSet, mesh_distance_batch

# --------------------------------------------------------------------------- meshes


def _open_cap() -> trimesh.Trimesh:
    """A sphere with its top cut away: an open surface whose winding number takes every value
    between 0 and 1, so the refinement has to reach the exact sum near |w| = 1/2."""
    ball = trimesh.creation.icosphere(subdivisions=3)
    keep = ball.triangles_center[:, 2] < 0.4
    return trimesh.Trimesh(ball.vertices, ball.faces[keep], process=False)


def _inward_box() -> trimesh.Trimesh:
    b = trimesh.creation.box(extents=[2.0, 1.0, 0.5])
    return trimesh.Trimesh(b.vertices, b.faces[:, ::-1], process=False)


MESHES = [
    trimesh.creation.icosphere(subdivisions=3),
    trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24),
    _open_cap(),
    _inward_box(),
    trimesh.creation.cylinder(radius=0.5, height=3.0, sections=40),
]
SET = MeshSet.from_arrays(MESHES)


def _points(mesh: trimesh.Trimesh, seed: int, log_offset: float, n: int = 40) -> np.ndarray:
    """Points at distance about 10**log_offset * extent from the surface (both sides), from
    random surface samples: near the surface the far field is least accurate."""
    rng = np.random.default_rng(seed)
    extent = float(mesh.extents.max())
    samples, faces = trimesh.sample.sample_surface(mesh, n, seed=seed)
    normals = mesh.face_normals[faces]
    offset = extent * 10.0**log_offset * rng.uniform(-1.0, 1.0, (n, 1))
    jitter = extent * 10.0**log_offset * rng.normal(size=(n, 3)) * 0.3
    return np.ascontiguousarray(samples + normals * offset + jitter)


mesh_index = st.integers(0, len(MESHES) - 1)
seeds = st.integers(0, 2**31 - 1)
log_offsets = st.floats(-6.0, 1.5)


# --------------------------------------------------------------------------- fast winding number


@given(mesh_index, seeds, log_offsets, st.sampled_from([0.0, 1e-3, 0.05, 0.2]))
def test_fast_winding_number_is_within_its_bound(i, seed, log_offset, max_error) -> None:
    points = _points(MESHES[i], seed, log_offset)
    exact = SET.winding_number(i, points)
    value, error, visits = SET.fast_winding_number(i, points, max_error)
    assert np.all(error <= max_error + 1e-12)
    assert np.all(np.abs(value - exact) <= error + 1e-9), np.max(np.abs(value - exact) - error)
    if max_error == 0.0:
        assert np.all(error == 0.0)
        assert np.all(visits >= len(MESHES[i].faces))  # every triangle summed
    assert np.all(visits > 0)


@given(mesh_index, seeds, log_offsets)
def test_containment_verdicts_equal_the_exact_sum(i, seed, log_offset) -> None:
    points = _points(MESHES[i], seed, log_offset)
    exact = SET.winding_number(i, points)
    inside, visits = SET.winding_number_inside(i, points)
    decided = np.abs(np.abs(exact) - 0.5) > 1e-9
    assert np.array_equal(inside[decided], (np.abs(exact) >= 0.5)[decided])
    assert np.all(visits > 0)


@pytest.mark.slow
def test_open_surface_verdicts_on_a_dense_grid() -> None:
    """Many points around the open cap, where |w| crosses 1/2 on a curved sheet."""
    g = np.linspace(-1.3, 1.3, 23)
    points = np.ascontiguousarray(np.stack(np.meshgrid(g, g, g), -1).reshape(-1, 3))
    exact = SET.winding_number(2, points)
    inside, _ = SET.winding_number_inside(2, points)
    assert 0 < inside.sum() < len(points)
    fractional = (np.abs(exact) > 0.05) & (np.abs(exact) < 0.95)
    assert fractional.sum() > 100  # the cut-away top is seen at many angles
    decided = np.abs(np.abs(exact) - 0.5) > 1e-9
    assert np.array_equal(inside[decided], (np.abs(exact) >= 0.5)[decided])


def test_far_points_use_the_far_field() -> None:
    """A point far from the mesh is decided by a few node expansions, not F triangles."""
    far = np.array([[30.0, -20.0, 10.0], [0.0, 0.0, 50.0]])
    for i, mesh in enumerate(MESHES):
        inside, visits = SET.winding_number_inside(i, far)
        assert not inside.any()
        assert visits.max() <= 8 < len(mesh.faces)
    value, error, visits = SET.fast_winding_number(1, far, 1e-6)
    assert np.abs(value).max() <= 1e-6 and visits.max() < len(MESHES[1].faces) / 10


def test_fast_winding_number_on_corpus_meshes(corpus) -> None:
    names = ("torus.STL", "fandisk.obj", "ballA.off", "soup.stl")
    meshes = [trimesh.load(corpus / "trimesh-models" / n, force="mesh") for n in names]
    s = MeshSet.from_arrays(meshes)
    rng = np.random.default_rng(3)
    for i, mesh in enumerate(meshes):
        lo, hi = mesh.bounds
        points = rng.uniform(lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo), (600, 3))
        exact = s.winding_number(i, points)
        inside, visits = s.winding_number_inside(i, points)
        decided = np.abs(np.abs(exact) - 0.5) > 1e-9
        assert np.array_equal(inside[decided], (np.abs(exact) >= 0.5)[decided]), names[i]
        value, error, _ = s.fast_winding_number(i, points, 0.1)
        assert np.all(np.abs(value - exact) <= error + 1e-9), names[i]
        if s._handle.closed(i):
            # the refinement stops far short of the O(F) sum on a closed mesh
            assert visits.mean() < len(mesh.faces) / 4, names[i]


def test_invalid_points_give_nan() -> None:
    value, error, _ = SET.fast_winding_number(0, [[np.nan, 0.0, 0.0]], 0.1)
    assert np.isnan(value[0]) and np.isnan(error[0])
    with pytest.raises(ValueError, match="max_error"):
        SET.fast_winding_number(0, [[0.0, 0.0, 0.0]], -1.0)


# --------------------------------------------------------------------------- containment


def test_containment_of_disjoint_pairs_equals_the_exact_winding_number() -> None:
    """Small balls all around and inside a torus: a_inside_b from the fast winding number
    equals thresholding the exact sum at every vertex of the ball (all agree: disjoint)."""
    torus = MESHES[1]
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.05)
    rng = np.random.default_rng(11)
    count = 300
    centres = rng.uniform([-1.4, -1.4, -0.4], [1.4, 1.4, 0.4], (count, 3))
    poses = np.tile(np.eye(4), (count + 1, 1, 1))
    poses[1:, :3, 3] = centres
    s = MeshSet.from_arrays([torus] + [ball] * count, poses)
    pairs = np.c_[np.arange(1, count + 1), np.zeros(count, dtype=np.int64)]
    r = mesh_distance_batch(s, None, pairs)
    disjoint = ~r.intersecting
    assert disjoint.sum() > 200
    vertices = (ball.vertices[None, :, :] + centres[:, None, :]).reshape(-1, 3)
    exact = np.abs(s.winding_number(0, vertices).reshape(count, -1)) >= 0.5
    agree = exact.all(axis=1) | ~exact.any(axis=1)
    assert agree[disjoint].all()
    assert np.array_equal(r.a_inside_b[disjoint], exact[disjoint, 0])
    assert 30 < r.a_inside_b.sum() < count - 30  # both verdicts occur
    assert not r.b_inside_a.any()


# --------------------------------------------------------------------------- oriented boxes


def _brute_force_distance(a, pa, b, pb) -> float:
    ta = trimesh.transform_points(a.vertices, pa)[a.faces]
    tb = trimesh.transform_points(b.vertices, pb)[b.faces]
    ia, ib = np.meshgrid(np.arange(len(ta)), np.arange(len(tb)), indexing="ij")
    d, _, _, _ = _core.triangle_distance_batch(
        np.ascontiguousarray(ta[ia.ravel()]), np.ascontiguousarray(tb[ib.ravel()])
    )
    return float(d.min())


quaternions = st.tuples(*[st.floats(-1, 1) for _ in range(4)]).filter(
    lambda q: sum(x * x for x in q) > 0.01
)
SMALL = [
    trimesh.creation.torus(1.0, 0.3, major_sections=20, minor_sections=10),
    trimesh.creation.icosphere(subdivisions=2),
    trimesh.creation.cylinder(0.4, 2.0, sections=16),
]
SMALL_SET = MeshSet.from_arrays(SMALL)


@given(st.integers(0, 2), st.integers(0, 2), quaternions, quaternions, st.floats(0.0, 1.5))
def test_rotated_near_pairs_equal_brute_force(i, j, qa, qb, gap) -> None:
    """Rotated copies at gaps from touching to about a mesh size: the oriented-box bounds
    never prune the closest triangle pair."""
    if i == j:
        return
    pa, pb = np.eye(4), np.eye(4)
    pa[:3, :3], pb[:3, :3] = quaternion_rotation(qa), quaternion_rotation(qb)
    pb[:3, 3] = [2.2 + gap, 0.3, -0.2]
    poses = np.tile(np.eye(4), (len(SMALL), 1, 1))
    poses[i], poses[j] = pa, pb
    r = mesh_distance_batch(SMALL_SET, poses, [[i, j]])
    if r.intersecting[0]:
        return
    expected = _brute_force_distance(SMALL[i], pa, SMALL[j], pb)
    assert r.distance[0] == pytest.approx(expected, rel=1e-9, abs=1e-12)


def test_oriented_boxes_hold_their_triangles(corpus) -> None:
    """validate() checks every node's oriented box and far-field radius against its corners."""
    names = ("torus.STL", "fandisk.obj", "soup.stl", "counter.unitsmm.STL")
    meshes = [trimesh.load(corpus / "trimesh-models" / n, force="mesh") for n in names]
    assert MeshSet.from_arrays(meshes).validate()
    assert SET.validate() and SMALL_SET.validate()
