"""The fixed-stride climb lists a ConvexSet carries beside its CSR adjacency.

Oracles: the lists the core makes from a set's CSR adjacency (``ClimbLists``), which the
hill climbs were shown to follow bit for bit (cpp/tests/test_narrowphase.cpp); and a set of
the same arrays without lists (built from a caller's arrays), whose shapes climb on the CSR
arrays. The hull packing writes the lists with the adjacency; ``take`` and ``concatenate``
carry them; each must hold exactly what the core makes of the set's own adjacency, byte for
byte, and the queries answer alike with and without them.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from meshcol import penetration_batch, signed_distance_batch
from meshcol.collision.hull import pack_hulls
from meshcol.collision.shapes import ConvexSet, Sphere


def ellipsoid_points(rng: np.random.Generator, n: int) -> np.ndarray:
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True) * rng.uniform(0.5, 1.5, size=3)


def bipyramid(ring: int) -> np.ndarray:
    # its two apexes have `ring` neighbours: more than a fixed-stride list holds
    t = 2 * np.pi * np.arange(ring) / ring
    points = np.stack([np.cos(t), np.sin(t), np.zeros(ring)], axis=1)
    return np.concatenate([points, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])


def made_from_arrays(s: ConvexSet) -> ConvexSet:
    """The same shapes from their arrays, as a caller hands them: no climb lists."""
    return ConvexSet(**{name: getattr(s, name) for name in ConvexSet._FIELDS})


def assert_lists_are_the_adjacency_s(s: ConvexSet) -> None:
    offsets, lists = s._core.climb_arrays()  # the core's, made from the CSR arrays
    assert s.climb_list_offsets.tobytes() == np.asarray(offsets).tobytes()
    assert s.climb_lists.tobytes() == np.asarray(lists).tobytes()
    assert s.climb_lists.dtype == np.uint8 and s.climb_lists.shape[1:] == (16,)
    assert s.climb_lists.ctypes.data % 16 == 0 or len(s.climb_lists) == 0
    assert not s.climb_lists.flags.writeable and not s.climb_list_offsets.flags.writeable


def mixed_shapes(rng: np.random.Generator) -> list[object]:
    shapes: list[object] = [Sphere(0.4)]
    shapes += [ellipsoid_points(rng, n) for n in (20, 33, 64, 200, 256)]
    shapes += [rng.normal(size=(300, 3)), bipyramid(24), np.full((40, 3), np.nan)]
    flat = rng.normal(size=(60, 3))
    flat[:, 2] = 0.5 * flat[:, 0]
    shapes += [flat, np.ones((3, 3))]
    # every point on its hull, more than 8-bit entries index: 16-bit lists, two rows each
    shapes += [ellipsoid_points(rng, 257)]
    return shapes


def test_packed_sets_hold_the_lists_their_adjacency_makes() -> None:
    rng = np.random.default_rng(7)
    made = ConvexSet.from_shapes(mixed_shapes(rng))
    assert made._core.sealed
    assert_lists_are_the_adjacency_s(made)
    counts = np.diff(made.climb_list_offsets)
    sizes = np.diff(made.offsets)
    # lists for the polytopes that climb (more than 32 vertices), none for the bipyramid
    assert counts[0] == 0 and counts[1] == 0
    assert list(counts[2:6]) == list(sizes[2:6])
    assert counts[7] == 0 and sizes[7] == 26
    assert counts[8] == 40  # kept as given: empty lists, as the CSR ones
    assert counts[5] == 256 == sizes[5]  # the largest with 8-bit lists, a row a vertex
    assert sizes[11] == 257 and counts[11] == 2 * 257  # 16-bit lists, two rows a vertex
    narrow = made.climb_lists[: made.climb_list_offsets[11]]
    wide = made.climb_lists[made.climb_list_offsets[11] :].view(np.uint16).reshape(-1, 16)
    assert (narrow[:, 0] <= 15).all() and (wide[:, 0] <= 15).all() and len(wide) == 257


def test_from_point_slices_take_and_concatenate_carry_the_lists() -> None:
    rng = np.random.default_rng(8)
    clouds = [ellipsoid_points(rng, n) for n in (64, 10, 256, 48)]
    points = np.concatenate(clouds)
    offsets = np.concatenate([[0], np.cumsum([len(c) for c in clouds])])
    kinds = np.array([0, 1, 0, 0, 2, 0], np.int8)
    params = np.zeros((6, 4))
    params[1, 0], params[4, :3] = 0.5, 0.3
    sliced = ConvexSet.from_point_slices(kinds, params, points, offsets)
    assert sliced._core.sealed
    assert_lists_are_the_adjacency_s(sliced)
    taken = sliced.take([5, 2, 2, 1, 0, 3])
    assert_lists_are_the_adjacency_s(taken)
    assert np.diff(taken.climb_list_offsets).tolist() == [48, 0, 0, 0, 64, 256]
    hulls = ConvexSet.from_vertices(clouds)
    joined = ConvexSet.concatenate(taken, hulls, sliced)
    assert_lists_are_the_adjacency_s(joined)
    assert len(joined.climb_lists) == 3 * 368
    empty = sliced.take(np.zeros(0, np.int64))
    assert empty.climb_list_offsets.tolist() == [0] and empty.climb_lists.shape == (0, 16)


def test_sets_with_and_without_the_packings_lists_answer_alike() -> None:
    rng = np.random.default_rng(9)
    shapes = [ellipsoid_points(rng, n) for n in (64, 256, 40, 200, 64, 256)]
    made = ConvexSet.from_vertices(shapes)
    plain = made_from_arrays(made)
    assert not plain._core.sealed and len(plain.climb_lists) == 0
    assert plain.climb_list_offsets.tolist() == [0] * (len(made) + 1)
    assert len(made.climb_lists) == 64 + 256 + 40 + 200 + 64 + 256
    sets = [made, made.take(np.arange(len(made))), plain, plain.take([0, 1, 2, 3, 4, 5])]
    count = len(made)
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, 3] = rng.uniform(-1.0, 1.0, size=(count, 3))
    pairs = np.array([(i, j) for i in range(count) for j in range(i + 1, count)])
    first = penetration_batch(sets[0], poses, pairs, threads=1)
    first_sd = signed_distance_batch(sets[0], poses, pairs, threads=1)
    assert (first.depth > 0).any() and (first_sd.signed_distance > 0).any()
    for other in sets[1:]:
        got = penetration_batch(other, poses, pairs, threads=1)
        assert got.depth.tobytes() == first.depth.tobytes()
        assert got.normal.tobytes() == first.normal.tobytes()
        assert got.point_a.tobytes() == first.point_a.tobytes()
        sd = signed_distance_batch(other, poses, pairs, threads=1)
        assert sd.signed_distance.tobytes() == first_sd.signed_distance.tobytes()
        assert sd.point_b.tobytes() == first_sd.point_b.tobytes()


def adopted(s: ConvexSet, offsets: np.ndarray, lists: np.ndarray) -> ConvexSet:
    """A set of ``s``'s arrays handed ``offsets`` and ``lists`` (not the packing's: checked)."""
    arrays = {name: getattr(s, name) for name in ConvexSet._FIELDS}
    return ConvexSet._adopt(**arrays, climb_list_offsets=offsets, climb_lists=lists)


def test_lists_handed_over_are_checked_unless_the_packing_s_own() -> None:
    rng = np.random.default_rng(10)
    made = ConvexSet.from_vertices([ellipsoid_points(rng, 64), ellipsoid_points(rng, 40)])

    def adopt(offsets: np.ndarray, lists: np.ndarray) -> ConvexSet:
        return adopted(made, offsets, lists)

    good = adopt(made.climb_list_offsets, np.array(made.climb_lists))
    assert good.climb_lists.tobytes() == made.climb_lists.tobytes()
    bad = np.array(made.climb_lists)
    bad[70, 1] = 40  # shape 1 has 40 vertices
    with pytest.raises(ValueError, match="climb_lists hold a list out of range"):
        adopt(made.climb_list_offsets, bad)
    bad = np.array(made.climb_lists)
    bad[3, 0] = 16  # more entries than slots
    with pytest.raises(ValueError, match="climb_lists hold a list out of range"):
        adopt(made.climb_list_offsets, bad)
    # a shape's lists are one a vertex or none
    with pytest.raises(ValueError, match="climb_lists hold a list out of range"):
        adopt(np.array([0, 64, 100]), np.array(made.climb_lists[:100]))
    with pytest.raises(ValueError, match="climb_list_offsets"):
        adopt(np.array([0, 64, 200]), np.array(made.climb_lists))
    # a shape of more than 256 vertices has 16-bit lists, two rows a vertex, checked as such
    large = ConvexSet.from_vertices([ellipsoid_points(rng, 300)])
    assert len(large.vertices) == 300 and len(large.climb_lists) == 600
    wide = large.climb_lists.view(np.uint16).reshape(300, 16)  # count, then 15 entries
    assert (wide[:, 0] >= 4).all() and (wide[:, 0] <= 15).all()
    assert (wide[:, 1:].max() > 255) and (wide[:, 1:] < 300).all()
    same = adopted(large, large.climb_list_offsets, np.array(large.climb_lists))
    assert same.climb_lists.tobytes() == large.climb_lists.tobytes()
    bad = np.array(large.climb_lists)
    bad.view(np.uint16).reshape(300, 16)[7, 1] = 300  # one past the last vertex
    with pytest.raises(ValueError, match="climb_lists hold a list out of range"):
        adopted(large, large.climb_list_offsets, bad)
    # a row a vertex is too few for such a shape
    with pytest.raises(ValueError, match="climb_lists hold a list out of range"):
        adopted(large, np.array([0, 300]), np.array(large.climb_lists[:300]))
    with pytest.raises(ValueError, match="go together"):
        made._core.__class__(
            *(getattr(made, name) for name in ConvexSet._FIELDS), None, made.climb_list_offsets
        )


def test_unpickled_packings_lists_are_aligned_for_the_core() -> None:
    # The core reads each row as a 16-byte record, so a set copies rows that are not 16-byte
    # aligned (numpy's own buffers are; a view into another buffer may not be).
    rng = np.random.default_rng(11)
    packed = pack_hulls([ellipsoid_points(rng, 64) for _ in range(3)])
    loaded = pickle.loads(pickle.dumps(packed))
    kinds, params, rows = np.zeros(3, np.int8), np.zeros((3, 4)), np.arange(3)
    made = ConvexSet._assemble(kinds, params, rows, loaded)
    assert made.climb_lists.ctypes.data % 16 == 0
    assert made.climb_lists.tobytes() == packed.climb_lists.tobytes()
    buffer = np.zeros(len(packed.climb_lists) * 16 + 16, np.uint8)
    skew = (8 - buffer.ctypes.data % 16) % 16  # 8 bytes past a 16-byte boundary
    skewed = buffer[skew : skew + 16 * len(packed.climb_lists)].reshape(-1, 16)
    skewed[...] = packed.climb_lists
    assert skewed.ctypes.data % 16 != 0
    again = adopted(made, made.climb_list_offsets, skewed)
    assert again.climb_lists.ctypes.data % 16 == 0
    assert again.climb_lists.tobytes() == packed.climb_lists.tobytes()
