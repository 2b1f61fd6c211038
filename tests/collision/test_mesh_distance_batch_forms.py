"""mesh_distance_batch's one-call path (poses and pairs already in the core's form, and lists of
int pairs, read in place, the result dataclass built by the core) against its converting path:
the same results, field for field and bit for bit, whatever form the inputs come in."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh
from array_forms import pair_forms
from strategies import turned_about_z

from meshcol.collision.mesh_query import MeshDistanceBatch, MeshSet, mesh_distance_batch
from meshcol.types import Status

FIELDS = [
    "distance",
    "point_a",
    "point_b",
    "intersecting",
    "a_inside_b",
    "b_inside_a",
    "triangle_a",
    "triangle_b",
    "status",
]
DTYPES = {
    "distance": np.float64,
    "point_a": np.float64,
    "point_b": np.float64,
    "intersecting": np.bool_,
    "a_inside_b": np.bool_,
    "b_inside_a": np.bool_,
    "triangle_a": np.int64,
    "triangle_b": np.int64,
    "status": np.int8,
}


def scene() -> tuple[MeshSet, np.ndarray, np.ndarray]:
    """A torus, a box inside it, one crossing it and one apart: apart, crossing, nested, and a
    non-rigid pose (its pairs INVALID_INPUT)."""
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    cube = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
    p = np.stack(
        [
            np.eye(4),
            turned_about_z(0.3, (1.0, 0.0, 0.0)),  # inside the torus's tube
            turned_about_z(0.7, (1.3, 0.0, 0.0)),  # across its surface
            turned_about_z(1.1, (4.0, 1.0, 0.5)),  # apart
            np.diag([2.0, 1.0, 1.0, 1.0]),  # not rigid
        ]
    )
    meshes = MeshSet.from_arrays([torus, cube, cube, cube, cube], p, threads=1)
    pairs = np.array([[0, 1], [0, 2], [0, 3], [3, 0], [2, 3], [0, 4], [1, 1]], dtype=np.int64)
    return meshes, p, pairs


def same(r: MeshDistanceBatch, expected: MeshDistanceBatch) -> None:
    for name in FIELDS:
        got, want = getattr(r, name), getattr(expected, name)
        assert got.dtype == DTYPES[name] and got.flags.c_contiguous and got.flags.writeable
        np.testing.assert_array_equal(got, want, err_msg=name, strict=True)


def test_distance_batch_reads_every_input_form_alike() -> None:
    meshes, p, pairs = scene()
    # the reference: one pair at a time, each converted from a list (the converting path)
    rows = [mesh_distance_batch(meshes, p.tolist(), [list(map(int, q))]) for q in pairs]
    expected = MeshDistanceBatch(
        **{f: np.concatenate([getattr(r, f) for r in rows]) for f in FIELDS}  # type: ignore[arg-type]
    )
    statuses = expected.status.tolist()
    assert statuses.count(Status.INVALID_INPUT) == 1 and statuses.count(Status.CONVERGED) == 6
    assert expected.intersecting.tolist() == [False, True, False, False, False, False, True]
    assert expected.b_inside_a[0] and math.isnan(expected.distance[5])
    forms = pair_forms(pairs)
    for poses in (None, p, p.tolist(), np.asfortranarray(p), p.astype(np.float32)):
        for form in forms:
            r = mesh_distance_batch(meshes, poses, form, threads=1)
            assert type(r) is MeshDistanceBatch
            assert [f.name for f in dataclasses.fields(r)] == FIELDS
            if poses is None or isinstance(poses, list) or poses.dtype == np.float64:
                same(r, expected)
            else:  # float32 poses: rounded, so only the verdicts are compared
                assert r.intersecting.tolist() == expected.intersecting.tolist()
    # many pairs on two threads (the pairs are copied before the GIL is released)
    many = mesh_distance_batch(meshes, None, np.tile(pairs, (40, 1)), threads=2)
    for name in FIELDS:
        np.testing.assert_array_equal(
            getattr(many, name), np.concatenate([getattr(expected, name)] * 40), strict=True
        )
    assert len(mesh_distance_batch(meshes, None, pairs[:0])) == 0
    assert len(mesh_distance_batch(meshes, None, [])) == 0
    a = mesh_distance_batch(meshes, None, pairs[:1])
    b = mesh_distance_batch(meshes, None, pairs[:1])
    assert not np.shares_memory(a.point_a, b.point_a) and a.distance is not b.distance
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.distance = b.distance  # type: ignore[misc]
    # max_distance: beyond it inf and NaN points, within it the same distance
    cut = mesh_distance_batch(meshes, None, pairs, max_distance=0.5)
    far = expected.distance > 0.5
    assert np.all(np.isinf(cut.distance[far & (expected.status == 0)]))
    assert np.array_equal(cut.distance[~far], expected.distance[~far], equal_nan=True)


def test_distance_batch_bad_input_is_refused_as_before() -> None:
    meshes, p, pairs = scene()
    with pytest.raises(ValueError, match=r"^pairs: index 5 out of range for 5 meshes$"):
        mesh_distance_batch(meshes, None, [(0, 5)])
    with pytest.raises(ValueError, match=r"^pairs must"):
        mesh_distance_batch(meshes, None, [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"^poses must be \(5, 4, 4\), got \(2, 4, 4\)$"):
        mesh_distance_batch(meshes, p[:2], pairs)
    with pytest.raises(ValueError, match=r"^max_distance must be >= 0, got -1.0$"):
        mesh_distance_batch(meshes, None, pairs, max_distance=-1)
    with pytest.raises(ValueError, match=r"^max_distance must be >= 0, got nan$"):
        mesh_distance_batch(meshes, None, pairs, max_distance=math.nan)
    with pytest.raises(TypeError, match=r"^meshes must be a MeshSet"):
        mesh_distance_batch(object(), None, pairs)  # type: ignore[arg-type]
