"""Validation of the arrays every collision query takes: points, poses and index pairs.

Each function normalises its input once (C-contiguous float64 or int64) and raises
``ValueError`` naming the argument and the shape it got, so every query reports wrong input
the same way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["as_mesh", "as_offsets", "as_points", "as_pose", "as_poses", "as_pairs"]


def as_mesh(vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    """A triangle mesh's arrays: vertices as C-contiguous (n, 3) float64, faces as given
    (an empty array as (0, 3)) once they are (m, 3); the caller converts the faces after
    its own checks of their type."""
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must be (n, 3), got {v.shape}")
    if f.size == 0:
        f = f.reshape(0, 3)
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"faces must be (m, 3), got {f.shape}")
    return v, f


def as_points(v: Any, name: str) -> np.ndarray:
    """Points as an (n, 3) float64 array (a single (3,) point becomes (1, 3))."""
    arr = np.asarray(v, dtype=np.float64)
    if arr.ndim == 1 and arr.shape == (3,):
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be (n, 3), got {arr.shape}")
    return arr


def as_pose(pose: Any, name: str) -> np.ndarray:
    """One rigid pose as a (4, 4) float64 array (None: identity)."""
    m = np.eye(4) if pose is None else np.asarray(pose, dtype=np.float64)
    if m.shape != (4, 4):
        raise ValueError(f"{name} must be (4, 4), got {m.shape}")
    return m


def as_poses(poses: Any, h: int, name: str = "poses") -> np.ndarray | None:
    """``poses`` as a C-contiguous (h, 4, 4) float64 array, or None (identity)."""
    if poses is None:
        return None
    arr = np.ascontiguousarray(poses, dtype=np.float64)
    if arr.shape != (h, 4, 4):
        raise ValueError(f"{name} must be ({h}, 4, 4), got {arr.shape}")
    return arr


def as_vectors(v: Any, h: int, name: str) -> np.ndarray | None:
    """``v`` as a C-contiguous (h, 3) float64 array (a (3,) vector when h == 1), or None."""
    if v is None:
        return None
    arr = np.asarray(v, dtype=np.float64)
    if arr.shape == (3,) and h == 1:
        arr = arr.reshape(1, 3)
    if arr.shape != (h, 3):
        raise ValueError(f"{name} must be ({h}, 3), got {arr.shape}")
    return np.ascontiguousarray(arr)


def as_pairs(pairs: Any, h: int, items: str = "shapes") -> np.ndarray:
    """``pairs`` as a C-contiguous (P, 2) int64 array of indices below ``h`` (the ``items``,
    named in the error), or ValueError."""
    arr = np.asarray(pairs)
    if arr.size == 0:
        arr = arr.reshape(-1, 2) if arr.ndim == 2 or arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"pairs must be (P, 2), got {arr.shape}")
    if arr.size and arr.dtype.kind not in "iu":
        raise ValueError(f"pairs must hold integer indices, got dtype {arr.dtype}")
    if arr.dtype != np.int64 or not arr.flags.c_contiguous:
        arr = np.ascontiguousarray(arr, dtype=np.int64)
    if arr.size:
        # A few pairs (one query per call) are checked as Python ints: two numpy reductions
        # cost more than the native query they guard.
        if arr.size <= 64:
            flat = arr.ravel().tolist()
            low, high = min(flat), max(flat)
        else:
            low, high = int(arr.min()), int(arr.max())
        if low < 0 or high >= h:
            bad = arr[(arr < 0) | (arr >= h)][0]
            raise ValueError(f"pairs: index {bad} out of range for {h} {items}")
    return arr


def as_offsets(counts: Any) -> np.ndarray:
    """(n + 1,) int64 group offsets of ``n`` groups of ``counts`` rows (``[0, c0, c0 + c1,
    ...]``): how the core's batched calls take their groups."""
    offsets = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return offsets
