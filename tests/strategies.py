"""Hypothesis strategies for the narrow phase: convex point clouds, primitives and poses."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from meshcol import Box, Capsule, Cylinder, Sphere


def rotation_from_quaternion(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def pose_matrix(rotation: np.ndarray, translation) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def turned_about_z(angle: float, translation) -> np.ndarray:
    """The pose turned by ``angle`` radians about z, then moved by ``translation``."""
    c, s = math.cos(angle), math.sin(angle)
    return pose_matrix(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]), translation)


coordinate = st.floats(-2.0, 2.0, allow_nan=False, allow_infinity=False)


@st.composite
def poses(draw, spread: float = 2.0) -> np.ndarray:
    """Rigid (4, 4) poses: a random unit quaternion and a translation in a cube."""
    q = np.array(draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4)))
    if np.linalg.norm(q) < 1e-3:
        q = np.array([1.0, 0, 0, 0])
    t = draw(st.lists(st.floats(-spread, spread), min_size=3, max_size=3))
    return pose_matrix(rotation_from_quaternion(q), t)


@st.composite
def hulls(draw, min_points: int = 4, max_points: int = 14) -> np.ndarray:
    """Full-dimensional point clouds (n, 3) around the origin (seeded numpy for speed)."""
    seed = draw(st.integers(0, 2**32 - 1))
    n = draw(st.integers(min_points, max_points))
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 3)) * rng.uniform(0.2, 1.5, size=3)
    # Keep them well spread: a tetrahedron guarantees a 3D hull.
    pts[:4] = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) * 0.4
    return pts


primitives = st.one_of(
    st.builds(Sphere, st.floats(0.1, 1.5)),
    st.builds(
        lambda x, y, z: Box((x, y, z)), st.floats(0.1, 2), st.floats(0.1, 2), st.floats(0.1, 2)
    ),
    st.builds(Capsule, st.floats(0.1, 1), st.floats(0.0, 2)),
    st.builds(Cylinder, st.floats(0.1, 1), st.floats(0.1, 2)),
)

shapes = st.one_of(hulls(), primitives)
