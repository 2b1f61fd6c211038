"""Rotation matrices to and from the parameters description formats use: quaternions, URDF's
roll-pitch-yaw, an angle about an axis."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["axis_angle_matrix", "quaternion_from_matrix", "rpy_from_matrix"]


def quaternion_from_matrix(rotation: np.ndarray) -> list[float]:
    """Unit quaternion ``[w, x, y, z]`` with ``w >= 0`` of a rotation matrix (Shepperd's
    method: the largest of the four squared components is taken first, so no branch divides
    by a small number)."""
    m = np.asarray(rotation, dtype=np.float64)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s]
    q_arr = np.asarray(q) / np.linalg.norm(q)
    if q_arr[0] < 0:
        q_arr = -q_arr
    return [float(v) for v in q_arr]


def rpy_from_matrix(rotation: np.ndarray) -> list[float]:
    """URDF's ``rpy`` (roll, pitch, yaw: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``) of a rotation.

    At gimbal lock (pitch of +-pi/2) roll is 0 and yaw takes the whole turn about z."""
    m = np.asarray(rotation, dtype=np.float64)
    sine = -float(m[2, 0])
    pitch = math.asin(max(-1.0, min(1.0, sine)))
    if abs(sine) < 1.0 - 1e-12:
        roll = math.atan2(float(m[2, 1]), float(m[2, 2]))
        yaw = math.atan2(float(m[1, 0]), float(m[0, 0]))
    else:  # cos(pitch) = 0: only roll - yaw (pitch > 0) or roll + yaw is defined
        roll = 0.0
        yaw = math.atan2(-float(m[0, 1]), float(m[1, 1]))
    return [roll, pitch, yaw]


def axis_angle_matrix(axis: np.ndarray | list[float], radians: float) -> np.ndarray:
    """The (3, 3) rotation of ``radians`` about ``axis`` (any length; a zero or non-finite
    axis: no rotation), Rodrigues' formula."""
    axis_array = np.asarray(axis, dtype=np.float64)
    norm = float(np.linalg.norm(axis_array))
    if not norm > 0.0 or not math.isfinite(norm):
        return np.eye(3)
    x, y, z = axis_array / norm
    cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(radians) * cross + (1.0 - math.cos(radians)) * (cross @ cross)
