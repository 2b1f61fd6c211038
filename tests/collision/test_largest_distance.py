"""The largest distance from points to a mesh (:meth:`MeshSet.largest_distances`, its grid
form :meth:`MeshSet.largest_distances_to_patches`) and the grids of primitives' surfaces
(:mod:`meshcol.collision.primitive_surface`).

Oracles: the unpruned search (the maximum of :meth:`MeshSet.closest_points`, bit for bit);
for the grids, points drawn on each surface analytically (no sample may be farther than the
documented spacing from one) and gaps whose exact value is known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol.collision.mesh_query import MeshSet
from meshcol.collision.primitive_fit import BOX, CAPSULE, CYLINDER, ELLIPSOID, SPHERE
from meshcol.collision.primitive_surface import surface_patches, surface_samples
from meshcol.types import Status

KINDS = (SPHERE, CAPSULE, BOX, CYLINDER, ELLIPSOID)


def _random_mesh(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    vertices = rng.normal(size=(n, 3)) * rng.uniform(0.1, 3.0, 3) + rng.normal(size=3)
    return vertices, rng.integers(0, n, size=(m, 3))


def _random_primitives(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    kind = rng.choice(KINDS, size=count)
    params = rng.uniform(0.05, 2.0, size=(count, 3))
    return kind, params


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(1, 300))
def test_largest_distance_is_the_unpruned_maximum_bit_for_bit(
    seed: int, faces: int, points: int
) -> None:
    rng = np.random.default_rng(seed)
    meshes = [_random_mesh(rng, 3 * faces, faces) for _ in range(3)]
    mesh_set = MeshSet.from_arrays(meshes, orient=False)
    counts = rng.integers(0, points + 1, size=3)
    counts[0] = points
    query = rng.normal(size=(int(counts.sum()), 3)) * rng.uniform(0.1, 5.0)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    items = rng.integers(0, 3, size=3)
    results = [mesh_set.largest_distances(query, offsets, items, threads=t) for t in (1, 2)]
    for distance, point, status in results:
        for k, mesh in enumerate(items.tolist()):
            block = query[offsets[k] : offsets[k + 1]]
            if len(block) == 0:
                assert math.isnan(distance[k]) and point[k] == -1
                continue
            exact = mesh_set.closest_points(mesh, block, threads=1)[0]
            assert distance[k] == exact.max()  # bit for bit
            assert exact[point[k]] == exact.max()
            assert status[k] == Status.CONVERGED
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(*results))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_patches_give_the_maximum_over_their_nodes_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    kind, params = _random_primitives(rng, 6)
    patches = surface_patches(kind, params, int(rng.integers(16, 2000)))
    points, offsets = patches.points()
    # meshes inside, across and beside the primitives: gaps small and large
    meshes = [_random_mesh(rng, 24, int(rng.integers(1, 30))) for _ in range(6)]
    mesh_set = MeshSet.from_arrays(meshes, orient=False)
    by_blocks = [mesh_set.largest_distances_to_patches(patches, threads=t) for t in (1, 2)]
    for distance, point, status in by_blocks:
        assert (status == Status.CONVERGED).all()
        for k in range(6):
            exact = mesh_set.closest_points(k, points[offsets[k] : offsets[k + 1]], threads=1)[0]
            assert distance[k] == exact.max()
            assert exact[point[k]] == exact.max()
    assert all(np.array_equal(a, b) for a, b in zip(*by_blocks))
    pointwise = mesh_set.largest_distances(points, offsets)[0]
    assert np.array_equal(pointwise, by_blocks[0][0])


def test_an_invalid_mesh_is_invalid_input() -> None:
    mesh_set = MeshSet.from_arrays([(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))])
    distance, point, status = mesh_set.largest_distances(np.ones((4, 3)), [0, 4])
    assert math.isnan(distance[0]) and point[0] == -1 and status[0] == Status.INVALID_INPUT
    patches = surface_patches([SPHERE], [[1.0, 0, 0]], 64)
    distance, _, status = mesh_set.largest_distances_to_patches(patches)
    assert math.isnan(distance[0]) and status[0] == Status.INVALID_INPUT


def _on_surface(kind: int, p: np.ndarray, rng: np.random.Generator, n: int) -> np.ndarray:
    """n points drawn on the surface of one primitive, by its analytic form."""
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    if kind == SPHERE:
        return p[0] * direction
    if kind == ELLIPSOID:
        return direction * p  # the unit sphere scaled: on the ellipsoid
    if kind == BOX:
        q = rng.uniform(-0.5, 0.5, size=(n, 3)) * p
        axis = rng.integers(0, 3, size=n)
        q[np.arange(n), axis] = np.sign(rng.normal(size=n)) * p[axis] / 2
        return q
    r, half = p[0], p[1] / 2
    angle = rng.uniform(0, 2 * math.pi, n)
    ring = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n)])
    side = ring * r + np.outer(rng.uniform(-half, half, n), [0, 0, 1])
    if kind == CAPSULE:
        ends = direction * r + np.outer(np.sign(direction[:, 2]) * half, [0, 0, 1])
    else:
        ends = ring * r * np.sqrt(rng.uniform(0, 1, n))[:, None]
        ends[:, 2] = np.sign(rng.normal(size=n)) * half
    return np.where((rng.uniform(size=n) < 0.5)[:, None], side, ends)


@pytest.mark.parametrize("count", [50, pytest.param(700, marks=pytest.mark.slow)])
@pytest.mark.parametrize("kind", KINDS)
def test_every_surface_point_is_within_the_spacing_of_a_sample(kind: int, count: int) -> None:
    rng = np.random.default_rng(kind)
    cases = ([1.0, 2.0, 0.5], [0.3, 0.05, 1.7], [2.0, 1.0, 1.0], [0.02, 3.0, 0.2], [0, 3.0, 0])
    for params in cases:  # the last a segment (no area) but for the sphere, a point
        p = np.array(params)
        points, offsets, spacing = surface_samples([kind], [p], count)
        assert offsets[-1] == len(points) < 12 * count + 40  # about count
        probe = _on_surface(kind, p, rng, 2000)
        nearest = np.sqrt(((probe[:, None, :] - points[None]) ** 2).sum(-1).min(axis=1))
        assert nearest.max() <= spacing[0]


def test_samples_lie_on_the_surface() -> None:
    kind = np.array(KINDS)
    params = np.array([[0.7, 0, 0], [0.5, 2.0, 0], [1, 2, 3], [0.5, 1.0, 0], [0.4, 1.5, 0.9]])
    points, offsets, _ = surface_samples(kind, params, 500)
    sphere, capsule, box, cylinder, ellipsoid = (
        points[offsets[i] : offsets[i + 1]] for i in range(5)
    )
    assert np.allclose(np.linalg.norm(sphere, axis=1), 0.7)
    axis = capsule.copy()
    axis[:, 2] -= np.clip(axis[:, 2], -1.0, 1.0)
    assert np.allclose(np.linalg.norm(axis, axis=1), 0.5)
    assert np.allclose(np.abs(np.abs(box) - [0.5, 1, 1.5]).min(axis=1), 0.0)
    ring = np.abs(np.linalg.norm(cylinder[:, :2], axis=1) - 0.5)
    assert np.allclose(np.minimum(ring, np.abs(np.abs(cylinder[:, 2]) - 0.5)), 0.0)
    assert np.allclose(((ellipsoid / [0.4, 1.5, 0.9]) ** 2).sum(axis=1), 1.0)


def _speck(at=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """A triangle 1e-9 across at `at`: a point, as a mesh."""
    return np.array(at) + 1e-9 * np.eye(3), np.array([[0, 1, 2]])


def _cube(side: float) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]]
    faces += [[2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    return (corners - 0.5) * side, np.array(faces)


# (kind, params, mesh, exact largest gap): the farthest point of the primitive from the mesh
CASES = [
    (BOX, [4.0, 4.0, 4.0], _cube(2.0), math.sqrt(3.0)),  # corner to corner
    (BOX, [2.0, 2.0, 2.0], _cube(2.0), 0.0),  # a box around itself
    (SPHERE, [math.sqrt(3.0)], _cube(2.0), math.sqrt(3.0) - 1.0),  # axis point to a face
    (SPHERE, [1.5], _speck((0.3, -0.2, 0.1)), 1.5 + math.sqrt(0.14)),  # the antipode
    (ELLIPSOID, [0.5, 2.0, 1.0], _speck(), 2.0),  # the largest semi-axis
    (ELLIPSOID, [1.0, 0.3, 0.7], _speck((0.1, 0.0, 0.0)), 1.1),
    (CAPSULE, [1.0, 2.0], _speck(), 2.0),  # a pole
    (CYLINDER, [1.0, 4.0], _speck(), math.sqrt(5.0)),  # the rim
]


@pytest.mark.parametrize("kind, params, mesh, exact", CASES)
def test_gaps_of_known_cases_are_within_the_spacing(kind, params, mesh, exact) -> None:
    p = np.zeros(3)
    p[: len(params)] = params
    for count in (64, 4096):
        patches = surface_patches([kind], [p], count)
        gap = MeshSet.from_arrays([mesh]).largest_distances_to_patches(patches)[0][0]
        # a lower bound within the spacing; the speck's 1e-9 and rounding on top
        assert exact - patches.spacing[0] - 1e-8 <= gap <= exact + 1e-8
