"""Rotations from an angle about an axis (:func:`meshcol.geometry.rotations.axis_angle_matrix`,
COLLADA's ``<rotate>``) against SciPy's rotation vectors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from meshcol.geometry.rotations import axis_angle_matrix


@pytest.mark.parametrize("seed", range(4))
def test_axis_angle_is_scipys_rotation_vector(seed: int) -> None:
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3) * rng.uniform(0.1, 10.0)  # any length: normalised
    angle = rng.uniform(-2 * np.pi, 2 * np.pi)
    expected = Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()
    np.testing.assert_allclose(axis_angle_matrix(axis, angle), expected, atol=1e-14)


def test_a_quarter_turn_is_exact_enough_and_no_axis_is_no_turn() -> None:
    turn = axis_angle_matrix([0, 0, 2], np.pi / 2)
    np.testing.assert_allclose(turn @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    for axis in ([0, 0, 0], [np.nan, 0, 0], [np.inf, 0, 0]):
        assert np.array_equal(axis_angle_matrix(axis, 1.0), np.eye(3))
