"""MeshSet.intersects with poses passed per call: a (4, 4) float64 numpy array is read from
numpy's own struct, every other form through the buffer protocol or converted by numpy; each
form must give the batch's verdict, and a wrong shape the same error, whatever the form."""

from __future__ import annotations

import re

import numpy as np
import pytest
import trimesh
from array_forms import unaligned_copy

from meshcol.collision.mesh_query import MeshSet, mesh_intersects_batch


def posed(quarter_turns: int, translation) -> np.ndarray:
    """A turn about z by a multiple of 90 degrees (exact entries, the same pose in float32)."""
    c, s = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[quarter_turns % 4]
    p = np.eye(4)
    p[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    p[:3, 3] = translation
    return p


def pose_forms(p: np.ndarray) -> list:
    """``p`` (a (4, 4) float64 array) as itself, read-only, a list, float32, Fortran order, a
    strided view, the other byte order, a subclass, unaligned data and a view of a stack."""
    read_only = p.copy()
    read_only.flags.writeable = False
    stack = np.stack([np.eye(4), p])
    return [
        p,
        read_only,
        p.tolist(),
        p.astype(np.float32),
        np.asfortranarray(p),
        np.ascontiguousarray(p.T).T,
        p.astype(p.dtype.newbyteorder()),
        p.view(np.ma.MaskedArray),
        unaligned_copy(p),
        stack[1],  # a C-contiguous view of another array
    ]


def test_every_pose_form_gives_the_batch_verdict() -> None:
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=16, minor_sections=8)
    cube = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
    meshes = MeshSet.from_arrays([torus, cube])
    verdicts = []
    # across the tube's surface, inside the tube (no crossing), well apart; every entry exact
    # in float32, so that every form is the same pose
    for p in (posed(1, (1.25, 0.0, 0.0)), posed(0, (1.0, 0.0, 0.0)), posed(3, (4.0, 1.0, 0.5))):
        batch = mesh_intersects_batch(meshes, np.stack([np.eye(4), p]), [[0, 1]])
        expected = bool(batch.intersecting[0])
        verdicts.append(expected)
        for form in pose_forms(p):
            assert meshes.intersects(0, 1, None, form) is expected, type(form)
            assert meshes.intersects(1, 0, form, None) is expected, type(form)
            # the class's method, which a set's own (the native method, bound) stands in for
            assert MeshSet.intersects(meshes, 0, 1, None, form) is expected, type(form)
        assert meshes.intersects(0, 1, np.eye(4), p) is expected
    assert verdicts == [True, False, False]


def test_a_wrong_shape_is_refused_alike_in_every_form() -> None:
    cube = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    meshes = MeshSet.from_arrays([cube, cube])
    for bad in (np.eye(3), np.eye(4)[:3], np.zeros((4, 4, 1)), np.eye(4).ravel()):
        shape = bad.shape
        for form in (bad, np.asfortranarray(bad), bad.astype(np.float32), bad.tolist()):
            message = f"pose_j must be (4, 4), got {shape}"
            with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
                meshes.intersects(0, 1, None, form)
