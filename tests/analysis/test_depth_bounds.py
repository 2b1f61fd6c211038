"""The depth interval's batched support functions against the one-shape arithmetic they
replace (issue 32: the stage ran a Python loop over its pairs and bodies), to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from meshcol.analysis.depth_bounds import supports
from meshcol.collision.shapes import Box, Capsule, ConvexSet, Cylinder, Sphere


def one_support(shapes: ConvexSet, index: int, pose: np.ndarray, direction: np.ndarray) -> float:
    """The support function as the stage computed it one pair at a time before it was
    batched (the reference: the same numpy calls in the same order)."""
    rotation, origin = pose[:3, :3], pose[:3, 3]
    local = rotation.T @ direction
    base = float(origin @ direction)
    kind = int(shapes.kinds[index])
    p = shapes.params[index]
    if kind == 0:
        vertices = shapes.vertices[shapes.offsets[index] : shapes.offsets[index + 1]]
        return base + float((vertices @ local).max())
    length = float(np.linalg.norm(local))
    along = abs(float(local[2]))
    if kind == 1:
        return base + p[0] * length
    if kind == 2:
        return base + float(np.abs(local[:3]) @ p[:3])
    if kind == 3:
        return base + p[1] * along + p[0] * length
    radial = float(np.sqrt(max(length * length - along * along, 0.0)))
    return base + p[1] * along + p[0] * radial


def random_poses(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    poses = np.zeros((n, 4, 4))
    poses[:, 0, :3] = np.stack(
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], 1
    )
    poses[:, 1, :3] = np.stack(
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], 1
    )
    poses[:, 2, :3] = np.stack(
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], 1
    )
    poses[:, :3, 3] = rng.normal(scale=30.0, size=(n, 3))
    poses[:, 3, 3] = 1.0
    return poses


@pytest.mark.parametrize("seed", [0, 1])
def test_batched_supports_are_the_one_shape_values_to_the_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    primitives = [Sphere(0.3), Box((0.2, 1.5, 0.7)), Capsule(0.25, 0.9), Cylinder(0.4, 0.05)]
    clouds = [rng.normal(size=(int(m), 3)) * rng.uniform(0.1, 3.0) for m in (4, 5, 9, 17, 64, 300)]
    flat = [np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])]  # a triangle
    shapes = ConvexSet.concatenate(
        ConvexSet.from_shapes(primitives), ConvexSet.from_vertices(clouds + flat)
    )
    k = 3000
    index = rng.integers(0, len(shapes), size=k)
    poses = random_poses(rng, k)
    directions = rng.normal(size=(k, 3))
    directions[::7] /= np.linalg.norm(directions[::7], axis=1, keepdims=True)
    directions[5::11, :2] = 0.0  # along an axis: a cylinder's radial part is zero
    found = supports(shapes, index, poses, directions)
    expected = np.array(
        [one_support(shapes, int(h), poses[i], directions[i]) for i, h in enumerate(index)]
    )
    assert found.dtype == np.float64
    assert np.array_equal(found, expected)  # bit for bit, not close


def test_supports_of_nothing_is_empty() -> None:
    shapes = ConvexSet.from_shapes([Sphere(1.0)])
    out = supports(shapes, np.zeros(0, dtype=np.int64), np.zeros((0, 4, 4)), np.zeros((0, 3)))
    assert out.shape == (0,)


def test_support_of_a_sphere_and_a_box_is_their_reach_along_the_direction() -> None:
    shapes = ConvexSet.from_shapes([Sphere(0.5), Box((2.0, 4.0, 6.0))])
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, 3] = [1.0, 2.0, 3.0]
    d = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 1.0]]) / np.array([[1.0], [np.sqrt(3.0)]])
    found = supports(shapes, np.array([0, 1]), poses, d)
    assert found[0] == pytest.approx(3.5)
    assert found[1] == pytest.approx((6.0 + 1.0 + 2.0 + 3.0) / np.sqrt(3.0))


def test_single_part_rows_take_the_narrow_phase_answer_to_the_bit() -> None:
    """Two bodies of one part each: depth_bounds reads the convex phase's own penetration
    answer instead of asking again; the interval is the same bits as a fresh query's."""
    import dataclasses

    from scipy.spatial import ConvexHull

    from meshcol.analysis.colliders import build_colliders
    from meshcol.analysis.depth_bounds import depth_bounds
    from meshcol.analysis.pairs import broad_phase, convex_phase, place
    from meshcol.types import Body

    rng = np.random.default_rng(7)
    bodies = []
    poses = random_poses(rng, 60)
    poses[:, :3, 3] = rng.uniform(0.0, 2.5, size=(60, 3))
    for i in range(60):
        if i % 3 == 0:
            primitive = [Sphere(0.4), Box((0.6, 0.3, 0.5)), Capsule(0.2, 0.5)][i % 9 // 3]
            bodies.append(Body.of_primitive(f"p{i}", None, primitive, pose=poses[i]))
        else:
            points = rng.normal(size=(int(rng.integers(8, 40)), 3)) * 0.3
            hull = ConvexHull(points)
            bodies.append(Body(f"m{i}", None, points, hull.simplices.astype(np.int64), poses[i]))
    placed = place(build_colliders(bodies, "hull"))
    table = broad_phase(placed, 0.0)
    table = convex_phase(table, placed)
    reused = depth_bounds(table, placed)
    fresh = depth_bounds(
        dataclasses.replace(table, convex_status=np.full(len(table), -1, dtype=np.int64)), placed
    )
    assert (table.convex_status >= 0).all()
    assert (reused.depth_upper > 0).sum() > 10  # overlapping pairs were bounded
    for name in ("depth_upper", "depth", "signed_distance"):
        assert np.array_equal(getattr(reused, name), getattr(fresh, name), equal_nan=True), name
