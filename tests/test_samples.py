"""The generated samples: reproducible, loadable, and as their ground truth says."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys

import numpy as np
import pytest

from meshcol.io.scene import load_scene


def test_regenerating_gives_identical_files(samples, tmp_path):
    subprocess.run(
        [sys.executable, str(samples / "make_samples.py"), str(tmp_path)], check=True, timeout=120
    )
    generated = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(
        p.relative_to(samples)
        for p in samples.rglob("*")
        if p.is_file() and p.name != "make_samples.py" and "__pycache__" not in p.parts
    )
    assert generated == committed
    for relative in generated:
        assert (tmp_path / relative).read_bytes() == (samples / relative).read_bytes(), relative
    total = sum((samples / p).stat().st_size for p in committed)
    assert total < 1_000_000


def edges_closed(faces: np.ndarray) -> bool:
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    directed = {tuple(e) for e in edges.tolist()}
    return len(directed) == len(edges) and all((b, a) in directed for a, b in directed)


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


@pytest.mark.parametrize("scene", ["bowl", "bullet", "level"])
def test_scenes_load_closed_outward_meshes(samples, scene):
    loaded = load_scene(samples / scene / "scene.json")
    assert loaded.units == "m"
    for body in loaded.bodies:
        assert edges_closed(body.faces), body.name
        assert signed_volume(body.vertices, body.faces) > 0, body.name


def test_bowl_ball_rests_inside_with_a_small_gap_and_inside_the_hull(samples):
    from scipy.spatial import ConvexHull

    bowl, ball = load_scene(samples / "bowl" / "scene.json").bodies
    v, f = bowl.world_vertices(), bowl.faces
    points = ball.world_vertices()
    centre = (points.max(axis=0) + points.min(axis=0)) / 2
    radius = np.linalg.norm(points - centre, axis=1).max()
    assert radius == pytest.approx(0.35, rel=1e-9)
    # distance from a point to a triangle is at least its distance to the triangle's plane:
    # a rigorous lower bound on the gap between the ball (inside its radius) and the bowl
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    plane_distance = np.abs(np.einsum("ij,ij->i", normals, centre - v[f[:, 0]]))
    gap_lower = plane_distance.min() - radius
    pole = np.array([0.0, 0.0, -0.9])  # the inner wall's bottom pole
    assert np.any(np.all(v == pole, axis=1))
    gap_upper = np.linalg.norm(pole - centre) - radius  # the inner pole is a bowl vertex
    assert 0.10 * radius < gap_lower <= gap_upper < 0.16 * radius
    # the bowl's convex hull swallows the ball whole
    hull = ConvexHull(v)
    inside = points @ hull.equations[:, :3].T + hull.equations[:, 3]
    assert (inside < -1e-3).all()


def test_bullet_tunnels_through_the_wall(samples):
    wall, bullet = load_scene(samples / "bullet" / "scene.json").bodies
    low, high = wall.world_vertices().min(axis=0), wall.world_vertices().max(axis=0)
    start, end = bullet.world_vertices(), bullet.world_vertices(end=True)
    assert start[:, 0].max() < low[0] - 0.5 and end[:, 0].min() > high[0] + 0.5
    # the swept path crosses the wall's slab inside its y/z extent
    assert (low[1:] < start.min(axis=0)[1:]).all() and (start.max(axis=0)[1:] < high[1:]).all()
    assert np.allclose(bullet.end_pose[:3, 3] - bullet.pose[:3, 3], [2, 0, 0])
    assert high[0] - low[0] == pytest.approx(0.05)
    assert start[:, 1].max() - start[:, 1].min() == pytest.approx(0.02)


def aabb_overlap(a_low, a_high, b_low, b_high):
    """Per-axis overlap; depth (min translation) = min over axes when all are positive."""
    return np.minimum(a_high - b_low, b_high - a_low)


def test_level_matches_expected(samples):
    scene = load_scene(samples / "level" / "scene.json")
    expected = json.loads((samples / "level" / "expected.json").read_text())
    assert len(scene.bodies) >= 21
    boxes = {
        b.name: (b.world_vertices().min(axis=0), b.world_vertices().max(axis=0))
        for b in scene.bodies
    }
    planted = {(p["a"], p["b"]): p for p in expected["interpenetrations"]}
    resting = {(p["a"], p["b"]) for p in expected["resting_contacts"]}
    assert 3 <= len(planted) <= 4 and len(resting) >= 2
    for a, b in itertools.combinations(boxes, 2):
        overlap = aabb_overlap(*boxes[a], *boxes[b])
        key = (a, b) if (a, b) in planted or (a, b) in resting else (b, a)
        if key in planted:
            entry = planted[key]
            assert (overlap > 0).all()
            assert overlap.min() == pytest.approx(entry["depth"], abs=1e-12)
            axis = int(np.argmin(overlap))
            direction = np.sign(boxes[key[1]][0][axis] - boxes[key[0]][0][axis])
            assert entry["normal"] == [float(direction) if k == axis else 0.0 for k in range(3)]
            # planted pairs are boxes: 8 vertices, so the AABB depth is the true depth
            assert all(len(next(x for x in scene.bodies if x.name == n).vertices) == 8 for n in key)
        elif key in resting:
            assert overlap.min() == pytest.approx(0.0, abs=1e-9)
        else:
            assert -overlap.min() >= expected["min_clearance"] - 1e-9, (a, b)
