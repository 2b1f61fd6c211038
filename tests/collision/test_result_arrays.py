"""The result arrays the core makes for the batches and single-pair results (NumpyColumns in
cpp/bindings/ndarray.hpp): a small result's columns are slices of one native block, a large
result's columns each own their data; either way every column is a writable, C-contiguous
array of its own memory that outlives the result, and nothing is kept after the last one goes."""

from __future__ import annotations

import dataclasses
import gc
import itertools
import sys
import tracemalloc
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import trimesh
from strategies import turned_about_z

from meshcol import (
    Box,
    ConvexSet,
    Sphere,
    distance,
    distance_batch,
    intersects_batch,
    penetration,
    penetration_batch,
    signed_distance,
    signed_distance_batch,
    time_of_impact,
    time_of_impact_batch,
)
from meshcol.collision.mesh_query import MeshSet, mesh_distance_batch, mesh_intersects_batch

BLOCK_BYTES = 4096  # NumpyColumns::kBlockBytes


def shifted(x: float) -> np.ndarray:
    p = np.eye(4)
    p[0, 3] = x
    return p


def mesh_set(count: int) -> MeshSet:
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=12, minor_sections=6)
    return MeshSet.from_arrays([torus] * count, np.stack([shifted(3.0 * k) for k in range(count)]))


def convex_set(count: int) -> tuple[ConvexSet, np.ndarray]:
    shapes = ConvexSet.from_shapes([Sphere(0.5), Box((1.0, 0.6, 0.8))] * (count // 2))
    return shapes, np.stack([turned_about_z(0.1 * k, (0.8 * k, 0.0, 0.0)) for k in range(count)])


def batches(pair_count: int) -> dict[str, Callable[[], Any]]:
    """Each batch kind on `pair_count` pairs (cycling over a few shapes), as a call."""
    meshes = mesh_set(4)
    shapes, poses = convex_set(4)
    pairs = np.array(
        list(itertools.islice(itertools.cycle([[0, 1], [1, 2], [2, 3], [0, 3]]), pair_count))
    )
    ends = poses.copy()
    ends[:, 1, 3] += 1.0
    return {
        "mesh intersects": lambda: mesh_intersects_batch(meshes, None, pairs, threads=1),
        "mesh distance": lambda: mesh_distance_batch(meshes, None, pairs, threads=1),
        "distance": lambda: distance_batch(shapes, poses, pairs, threads=1),
        "penetration": lambda: penetration_batch(shapes, poses, pairs, threads=1),
        "signed distance": lambda: signed_distance_batch(shapes, poses, pairs, threads=1),
        "intersects": lambda: intersects_batch(shapes, poses, pairs, threads=1),
        "time of impact": lambda: time_of_impact_batch(shapes, poses, ends, pairs, threads=1),
    }


def single_pairs() -> dict[str, Callable[[], Any]]:
    a, b = Sphere(0.5), Box((1.0, 0.6, 0.8))
    pa, pb, pb_end = np.eye(4), shifted(2.0), shifted(0.2)
    return {
        "distance": lambda: distance(a, b, pa, pb),
        "penetration": lambda: penetration(a, b, pa, shifted(0.6)),
        "signed distance": lambda: signed_distance(a, b, pa, pb),
        "time of impact": lambda: time_of_impact(a, b, pa, pa, pb, pb_end),
    }


def columns(result: Any) -> list[np.ndarray]:
    return [
        v
        for v in (getattr(result, f.name) for f in dataclasses.fields(result))
        if isinstance(v, np.ndarray)
    ]


def block_of(arrays: list[np.ndarray]) -> object:
    """The one block every array is a slice of (none of them owns its data)."""
    bases = {id(a.base) for a in arrays}
    assert len(bases) == 1, "the columns of a small result share one block"
    block = arrays[0].base
    assert block is not None and not isinstance(block, np.ndarray)
    assert type(block).__module__ == "meshcol._core" and type(block).__name__ == "ResultBlock"
    assert not any(a.flags.owndata for a in arrays)
    return block


def apart(arrays: list[np.ndarray]) -> None:
    """Each column writable, C-contiguous, aligned, and of memory no other column shares."""
    for a in arrays:
        assert a.flags.writeable and a.flags.c_contiguous and a.flags.aligned
        assert a.ctypes.data % 16 == 0
    for x, y in itertools.combinations(arrays, 2):
        assert not np.shares_memory(x, y)


@pytest.mark.parametrize("name", list(batches(1)))
@pytest.mark.parametrize("pair_count", [1, 4])
def test_small_batch_columns_share_one_block(name: str, pair_count: int) -> None:
    result = batches(pair_count)[name]()
    arrays = columns(result)
    assert all(len(a) == pair_count for a in arrays)
    apart(arrays)
    block_of(arrays)


@pytest.mark.parametrize("name", list(single_pairs()))
def test_single_pair_results_share_one_block(name: str) -> None:
    arrays = columns(single_pairs()[name]())
    assert arrays and all(a.shape == (3,) for a in arrays)
    apart(arrays)
    block_of(arrays)


@pytest.mark.parametrize("name", list(batches(1)))
def test_large_batch_columns_own_their_data(name: str) -> None:
    # 4,100 pairs: every kind's columns pass the block's 4,096 bytes (2 bytes a pair at least)
    result = batches(4100)[name]()
    arrays = columns(result)
    assert sum(a.nbytes for a in arrays) > BLOCK_BYTES
    apart(arrays)
    assert all(a.flags.owndata and a.base is None for a in arrays)


@pytest.mark.parametrize("name", list(batches(1)))
def test_writing_a_column_changes_no_other(name: str) -> None:
    call = batches(3)[name]
    want = columns(call())
    for k in range(len(want)):
        arrays = columns(call())
        arrays[k][...] = 1
        for j, (got, expected) in enumerate(zip(arrays, want)):
            if j != k:
                np.testing.assert_array_equal(got, expected, strict=True)


def test_a_column_outlives_its_result_and_siblings() -> None:
    call = batches(2)["mesh distance"]
    want = call().distance.copy()
    kept = call().distance  # the result and its other eight columns are dropped here
    gc.collect()
    for _ in range(50):
        call()  # reuse of freed memory would show in `kept`
    np.testing.assert_array_equal(kept, want, strict=True)
    refs = sys.getrefcount(kept.base)
    assert refs == 2  # `kept`'s, and getrefcount's own argument


def test_results_keep_no_memory_or_references() -> None:
    calls = {**batches(1), **{f"pair {k}": v for k, v in single_pairs().items()}}
    block_type = type(calls["mesh intersects"]().intersecting.base)
    for call in calls.values():
        for _ in range(200):
            call()  # warm: caches, interned names, pymalloc arenas
    gc.collect()
    type_refs = sys.getrefcount(block_type)  # the type and each live block's
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for call in calls.values():
            for _ in range(20_000):
                call()
        gc.collect()
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    # 140,000 results of up to nine columns: a leaked block or array would be megabytes
    assert grown < 64 * 1024
    assert sys.getrefcount(block_type) == type_refs
