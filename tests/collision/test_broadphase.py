"""Broad phase: sort and sweep, incremental sweep and AABB tree against brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule

import meshcol
from meshcol.collision.broadphase import AabbTree, SortAndSweep, brute_force_pairs, sort_and_sweep


def _pairs(*rows):
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def _cross_brute(lo_a, hi_a, lo_b, hi_b):
    hit = ((lo_a[:, None, :] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None, :])).all(axis=2)
    i, j = np.nonzero(hit)
    return np.stack([i, j], axis=1).astype(np.int64)


def _all_pairs(lo, hi):
    """Every structure's answer on one set, for comparison with brute force."""
    yield "sort_and_sweep", sort_and_sweep(lo, hi)
    for axis in range(3):
        yield f"sort_and_sweep axis={axis}", sort_and_sweep(lo, hi, axis=axis)
    yield "SortAndSweep", SortAndSweep(lo, hi).pairs()
    tree = AabbTree()
    ids = tree.insert(lo, hi)
    tree.validate()
    yield "AabbTree.insert", ids[tree.query_pairs()]
    fat = AabbTree(margin=0.25)
    fat.insert(lo, hi)
    yield "AabbTree.insert margin", fat.query_pairs()
    built = AabbTree.from_boxes(lo, hi)
    built.validate()
    yield "AabbTree.from_boxes", built.query_pairs()


# ---------------------------------------------------------------------------------------------
# Known answers


def test_public_names():
    assert meshcol.sort_and_sweep is sort_and_sweep
    assert meshcol.AabbTree is AabbTree
    assert meshcol.SortAndSweep is SortAndSweep
    assert meshcol.brute_force_pairs is brute_force_pairs


def test_known_answer_touching_separated_and_point():
    lo = np.array([[0, 0, 0], [1, 0, 0], [2.5, 0, 0], [1, 1, 1], [3.0, 0.5, 0.5]], dtype=float)
    hi = np.array([[1, 1, 1], [2, 1, 1], [3.5, 1, 1], [1, 1, 1], [3.0, 0.5, 0.5]], dtype=float)
    # 0-1 share the face x = 1; 3 is a point on the corner of 0 and on the edge of 1;
    # 4 is a point inside 2; 1-2 are 0.5 apart.
    expected = _pairs((0, 1), (0, 3), (1, 3), (2, 4))
    for name, got in _all_pairs(lo, hi):
        assert np.array_equal(got, expected), name
    assert np.array_equal(brute_force_pairs(lo, hi), expected)


def test_empty_and_single():
    for n in (0, 1):
        lo = np.zeros((n, 3))
        for name, got in _all_pairs(lo, lo + 1):
            assert got.shape == (0, 2) and got.dtype == np.int64, name
    tree = AabbTree()
    assert len(tree) == 0 and tree.height == 0
    assert tree.query([0, 0, 0], [1, 1, 1]).shape == (0,)
    ids, fractions = tree.ray_cast([0, 0, 0], [1, 0, 0])
    assert ids.shape == (0,) and fractions.shape == (0,)
    tree.validate()


def test_axis_choice_by_variance():
    rng = np.random.default_rng(0)
    lo = rng.random((50, 3)) * [1.0, 100.0, 10.0]
    assert SortAndSweep(lo, lo + 0.1).axis == 1
    assert SortAndSweep(lo, lo + 0.1, axis=2).axis == 2


def test_lattice_of_touching_unit_cubes_uses_threads_and_grid():
    # 40^3 unit cubes on the integer lattice: each touches its 26 neighbours exactly.
    # Large enough for the multi-threaded paths and the cross-axis grid.
    k = 40
    lo = np.stack(np.meshgrid(*[np.arange(k, dtype=float)] * 3, indexing="ij"), -1).reshape(-1, 3)
    expected_count = ((3 * k - 2) ** 3 - k**3) // 2
    pairs = sort_and_sweep(lo, lo + 1.0)
    assert pairs.shape == (expected_count, 2)
    a, b = lo[pairs[:, 0]], lo[pairs[:, 1]]
    assert np.abs(a - b).max() == 1.0 and (pairs[:, 0] < pairs[:, 1]).all()
    assert np.array_equal(np.unique(pairs, axis=0), pairs)  # sorted, no duplicates
    tree = AabbTree.from_boxes(lo, lo + 1.0)
    assert np.array_equal(tree.query_pairs(), pairs)
    sweep = SortAndSweep(lo, lo + 1.0)
    assert np.array_equal(sweep.pairs(), pairs)
    # Shrinking every box a little separates all of them.
    assert sort_and_sweep(lo + 1e-9, lo + 1.0 - 1e-9).shape == (0, 2)


def test_level_layout_with_large_boxes_matches_brute_force():
    rng = np.random.default_rng(3)
    n = 3000
    lo = np.column_stack([rng.random(n) * 100, rng.random(n) * 100, np.zeros(n)])
    hi = lo + rng.random((n, 3)) * [1.5, 1.5, 1.0]
    lo[:5] = [[0, 0, -1], [0, 0, 0], [40, 0, 0], [0, 60, 0], [10, 10, 0]]
    hi[:5] = [[100, 100, 0], [100, 1, 3], [41, 100, 3], [100, 61, 3], [90, 90, 0.5]]
    expected = brute_force_pairs(lo, hi)
    for name, got in _all_pairs(lo, hi):
        assert np.array_equal(got, expected), name


# ---------------------------------------------------------------------------------------------
# Errors


@pytest.mark.parametrize(
    "call",
    [
        lambda lo, hi: sort_and_sweep(lo, hi),
        lambda lo, hi: SortAndSweep(lo, hi),
        lambda lo, hi: AabbTree().insert(lo, hi),
        lambda lo, hi: AabbTree.from_boxes(lo, hi),
        lambda lo, hi: brute_force_pairs(lo, hi),
    ],
)
def test_bad_boxes_name_the_first_bad_index(call):
    lo = np.zeros((10, 3))
    hi = np.ones((10, 3))
    bad = hi.copy()
    bad[7, 1] = np.nan
    bad[8, 0] = np.inf
    with pytest.raises(ValueError, match=r"^aabb_min/aabb_max: box 7 is not finite$"):
        call(lo, bad)
    inverted = hi.copy()
    inverted[3, 2] = -1.0
    inverted[5, 0] = -1.0
    with pytest.raises(ValueError, match=r"^aabb_min/aabb_max: box 3 has min > max$"):
        call(lo, inverted)
    with pytest.raises(ValueError, match=r"^aabb_min must be \(n, 3\), got \(4, 2\)$"):
        call(np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(
        ValueError, match=r"^aabb_max must be \(10, 3\) like aabb_min, got \(9, 3\)$"
    ):
        call(lo, hi[:9])


def test_other_argument_errors():
    lo, hi = np.zeros((3, 3)), np.ones((3, 3))
    with pytest.raises(ValueError, match=r"^axis must be None, 0, 1 or 2, got 3$"):
        sort_and_sweep(lo, hi, axis=3)
    sweep = SortAndSweep(lo, hi)
    with pytest.raises(ValueError, match=r"^aabb_min must be \(3, 3\) as before, got \(2, 3\)$"):
        sweep.update(lo[:2], hi[:2])
    with pytest.raises(ValueError, match=r"^margin must be finite and >= 0, got -1.0$"):
        AabbTree(margin=-1.0)
    tree = AabbTree()
    ids = tree.insert(lo, hi)
    with pytest.raises(ValueError, match=r"^ids: 7 is not in the tree$"):
        tree.remove([7])
    with pytest.raises(ValueError, match=r"^ids: 1 appears twice$"):
        tree.remove([1, 1])
    assert len(tree) == 3  # nothing removed by the failed calls
    with pytest.raises(ValueError, match=r"^aabb_min must be \(2, 3\) like ids, got \(3, 3\)$"):
        tree.move(ids[:2], lo, hi)
    with pytest.raises(ValueError, match=r"^aabb_min must be \(3,\) or \(1, 3\), got \(2, 3\)$"):
        tree.query(lo[:2], hi[:2])
    with pytest.raises(ValueError, match=r"^direction is not finite$"):
        tree.ray_cast([0, 0, 0], [np.nan, 0, 0])
    with pytest.raises(ValueError, match=r"^max_fraction must be finite and >= 0"):
        tree.ray_cast([0, 0, 0], [1, 0, 0], -1.0)
    with pytest.raises(ValueError, match=r"^other must be an AabbTree, got int$"):
        tree.query_pairs(3)
    tree.validate()


# ---------------------------------------------------------------------------------------------
# Properties: equal to brute force


@st.composite
def box_sets(draw, max_n=40):
    """Boxes on a coarse integer lattice (so touching and identical boxes are common), with
    zero sizes allowed, scaled to tiny, unit or huge coordinates and shifted."""
    n = draw(st.integers(0, max_n))
    scale = draw(st.sampled_from([1e-12, 1.0, 1e12]))
    offset = draw(st.sampled_from([0.0, -3.0, 5e11])) * (scale if scale < 1 else 1.0)
    coords = st.integers(0, 8)
    lo = np.array(
        draw(st.lists(st.tuples(coords, coords, coords), min_size=n, max_size=n)), dtype=float
    ).reshape(n, 3)
    size = np.array(
        draw(st.lists(st.tuples(*[st.integers(0, 3)] * 3), min_size=n, max_size=n)), dtype=float
    ).reshape(n, 3)
    if n and draw(st.booleans()):
        lo[n // 2 :] = lo[0]  # many identical boxes
        size[n // 2 :] = size[0]
    return lo * scale + offset, (lo + size) * scale + offset


@given(box_sets())
def test_all_structures_equal_brute_force(boxes):
    lo, hi = boxes
    expected = brute_force_pairs(lo, hi)
    for name, got in _all_pairs(lo, hi):
        assert np.array_equal(got, expected), name


@settings(max_examples=40)
@given(box_sets(max_n=400), st.integers(0, 2**32 - 1))
def test_larger_sets_use_the_grid_and_equal_brute_force(boxes, seed):
    lo, hi = boxes
    rng = np.random.default_rng(seed)
    # Spread the lattice so that the cross-axis grid has several cells.
    shift = rng.integers(0, 40, size=lo.shape) * (hi - lo).max(initial=1.0)
    lo, hi = lo + shift, hi + shift
    expected = brute_force_pairs(lo, hi)
    assert np.array_equal(sort_and_sweep(lo, hi), expected)
    assert np.array_equal(AabbTree.from_boxes(lo, hi).query_pairs(), expected)


@settings(max_examples=60)
@given(box_sets(max_n=300), st.integers(0, 2**32 - 1), st.integers(1, 12))
def test_groups_drop_exactly_the_pairs_within_a_group(boxes, seed, count):
    lo, hi = boxes
    rng = np.random.default_rng(seed)
    shift = rng.integers(0, 20, size=lo.shape) * (hi - lo).max(initial=1.0)
    lo, hi = lo + shift, hi + shift
    groups = rng.integers(0, count, size=len(lo))
    everything = brute_force_pairs(lo, hi)
    expected = everything[groups[everything[:, 0]] != groups[everything[:, 1]]]
    assert np.array_equal(sort_and_sweep(lo, hi, groups=groups), expected)
    # one group per box changes nothing
    assert np.array_equal(sort_and_sweep(lo, hi, groups=np.arange(len(lo))), everything)


def test_groups_must_have_one_id_per_box():
    lo = np.zeros((3, 3))
    with pytest.raises(ValueError, match=r"groups must be \(3,\), got \(2,\)"):
        sort_and_sweep(lo, lo + 1, groups=[0, 1])


@given(box_sets(max_n=60), st.integers(0, 2**32 - 1), st.sampled_from([1e-3, 0.3, 5.0]))
def test_incremental_sweep_equals_brute_force_over_steps(boxes, seed, motion):
    lo, hi = boxes
    rng = np.random.default_rng(seed)
    sweep = SortAndSweep(lo, hi)
    scale = max(np.abs(hi).max(initial=1.0), 1e-300)
    for _ in range(3):
        step = rng.normal(size=lo.shape) * motion * (hi - lo).max(initial=1.0)
        step[rng.random(len(lo)) < 0.5] = 0.0
        lo, hi = lo + step, hi + step
        assert np.array_equal(sweep.update(lo, hi), brute_force_pairs(lo, hi))
        assert np.array_equal(sweep.pairs(), brute_force_pairs(lo, hi))
    assert scale > 0


@given(box_sets(max_n=30), box_sets(max_n=30))
def test_tree_against_tree_equals_brute_force(a, b):
    tree_a, tree_b = AabbTree(), AabbTree(margin=0.5)
    ids_a = tree_a.insert(*a)
    ids_b = tree_b.insert(*b)
    expected = _cross_brute(a[0], a[1], b[0], b[1])
    got = tree_a.query_pairs(tree_b)
    # map ids back to rows (ids are rows here: fresh trees hand out 0..n-1)
    assert np.array_equal(ids_a, np.arange(len(a[0]))) and np.array_equal(
        ids_b, np.arange(len(b[0]))
    )
    assert np.array_equal(got, expected)
    assert np.array_equal(AabbTree.from_boxes(*a).query_pairs(AabbTree.from_boxes(*b)), expected)


@given(box_sets(max_n=40), st.integers(0, 8), st.integers(0, 8))
def test_box_query_equals_brute_force(boxes, corner, size):
    lo, hi = boxes
    tree = AabbTree(margin=1.0)
    tree.insert(lo, hi)
    scale = np.abs(np.concatenate([lo.ravel(), hi.ravel(), [1.0]])).max()
    q_lo = np.full(3, corner * scale / 8.0)
    q_hi = q_lo + size * scale / 8.0
    expected = np.flatnonzero(((lo <= q_hi) & (q_lo <= hi)).all(axis=1))
    assert np.array_equal(tree.query(q_lo, q_hi), expected)
    assert np.array_equal(tree.query(q_lo[None], q_hi[None]), expected)


def _slab_fractions(lo, hi, origin, direction, max_fraction):
    t0 = np.zeros(len(lo))
    t1 = np.full(len(lo), max_fraction)
    ok = np.ones(len(lo), dtype=bool)
    for k in range(3):
        if direction[k] == 0.0:
            ok &= (lo[:, k] <= origin[k]) & (origin[k] <= hi[:, k])
            continue
        a = (lo[:, k] - origin[k]) / direction[k]
        b = (hi[:, k] - origin[k]) / direction[k]
        t0 = np.maximum(t0, np.minimum(a, b))
        t1 = np.minimum(t1, np.maximum(a, b))
    ok &= t0 <= t1
    return np.flatnonzero(ok), t0


@given(
    box_sets(max_n=40),
    st.tuples(*[st.integers(-2, 10)] * 3),
    st.tuples(*[st.integers(-3, 3)] * 3),
    st.sampled_from([0.5, 1.0, 4.0]),
)
def test_ray_cast_equals_brute_force(boxes, origin, direction, max_fraction):
    lo, hi = boxes
    scale = np.abs(np.concatenate([lo.ravel(), [1.0]])).max() / 8.0
    origin = np.array(origin, dtype=float) * scale
    direction = np.array(direction, dtype=float) * scale
    tree = AabbTree(margin=0.1 * scale)
    tree.insert(lo, hi)
    hit, t0 = _slab_fractions(lo, hi, origin, direction, max_fraction)
    order = np.lexsort((hit, t0[hit]))
    ids, fractions = tree.ray_cast(origin, direction, max_fraction)
    assert np.array_equal(ids, hit[order])
    assert np.array_equal(fractions, t0[hit][order])


def test_ray_cast_known_answer():
    lo = np.array([[2.0, -1, -1], [5, -1, -1], [-1, -1, -1], [2, 3, -1]])
    tree = AabbTree()
    tree.insert(lo, lo + [1.0, 2, 2])
    ids, fractions = tree.ray_cast([0, 0, 0], [10, 0, 0])
    assert ids.tolist() == [2, 0, 1]
    assert fractions.tolist() == [0.0, 0.2, 0.5]
    ids, _ = tree.ray_cast([0, 0, 0], [10, 0, 0], max_fraction=0.3)
    assert ids.tolist() == [2, 0]


# ---------------------------------------------------------------------------------------------
# The tree: edits, fat margin, balance


class TreeEdits(RuleBasedStateMachine):
    """Random insert / remove / move / rebuild sequences; the tree must stay valid and answer
    exactly as brute force over the model's boxes."""

    @initialize(margin=st.sampled_from([0.0, 0.5, 3.0]))
    def start(self, margin):
        self.tree = AabbTree(margin=margin)
        self.boxes: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @rule(
        corners=st.lists(
            st.tuples(*[st.integers(0, 12)] * 3, st.integers(0, 3)), min_size=1, max_size=6
        )
    )
    def insert(self, corners):
        lo = np.array([c[:3] for c in corners], dtype=float)
        hi = lo + np.array([c[3] for c in corners], dtype=float)[:, None]
        ids = self.tree.insert(lo, hi)
        assert len(set(ids.tolist()) & set(self.boxes)) == 0
        for i, box_id in enumerate(ids.tolist()):
            self.boxes[box_id] = (lo[i], hi[i])

    @precondition(lambda self: self.boxes)
    @rule(data=st.data())
    def remove(self, data):
        ids = data.draw(
            st.lists(st.sampled_from(sorted(self.boxes)), min_size=1, max_size=4, unique=True)
        )
        self.tree.remove(ids)
        for box_id in ids:
            del self.boxes[box_id]

    @precondition(lambda self: self.boxes)
    @rule(data=st.data(), step=st.sampled_from([0.25, 1.0, 6.0]))
    def move(self, data, step):
        ids = data.draw(
            st.lists(st.sampled_from(sorted(self.boxes)), min_size=1, max_size=5, unique=True)
        )
        deltas = (
            np.array(
                data.draw(
                    st.lists(
                        st.tuples(*[st.integers(-2, 2)] * 3), min_size=len(ids), max_size=len(ids)
                    )
                ),
                dtype=float,
            )
            * step
        )
        lo = np.array([self.boxes[i][0] for i in ids]) + deltas
        hi = np.array([self.boxes[i][1] for i in ids]) + deltas
        moved = self.tree.move(ids, lo, hi)
        assert moved.dtype == np.bool_ and moved.shape == (len(ids),)
        for k, box_id in enumerate(ids):
            self.boxes[box_id] = (lo[k], hi[k])

    @rule()
    def rebuild(self):
        self.tree.rebuild()

    @invariant()
    def valid_and_exact(self):
        self.tree.validate()
        assert len(self.tree) == len(self.boxes)
        ids = np.array(sorted(self.boxes), dtype=np.int64)
        if ids.size == 0:
            assert self.tree.query_pairs().shape == (0, 2)
            return
        lo = np.array([self.boxes[i][0] for i in ids]).reshape(-1, 3)
        hi = np.array([self.boxes[i][1] for i in ids]).reshape(-1, 3)
        assert np.array_equal(self.tree.query_pairs(), ids[brute_force_pairs(lo, hi)])


TreeEdits.TestCase.settings = settings(max_examples=60, stateful_step_count=25, deadline=None)
test_tree_edits = TreeEdits.TestCase
test_tree_edits.pytestmark = [pytest.mark.slow]


def test_move_within_the_fat_margin_changes_nothing():
    tree = AabbTree(margin=0.5)
    lo = np.array([[0.0, 0, 0], [3, 0, 0]])
    ids = tree.insert(lo, lo + 1)
    moved = tree.move(ids, lo + 0.4, lo + 1.4)
    assert moved.tolist() == [False, False]
    moved = tree.move(ids, lo + [0.4, 0, 0.6], lo + [1.4, 1, 1.6])
    assert moved.tolist() == [True, True]
    # Results follow the exact boxes, not the fat ones.
    assert tree.query_pairs().shape == (0, 2)
    tree.validate()
    # A move inside the fat box that makes the exact boxes touch is seen at once.
    wide = AabbTree(margin=2.0)
    ids = wide.insert(lo, lo + 1)
    assert wide.query_pairs().shape == (0, 2)
    assert wide.move(ids[1:], [[1.0, 0, 0]], [[2.0, 1, 1]]).tolist() == [False]
    assert wide.query_pairs().tolist() == [[0, 1]]
    assert wide.query([1.0, 1, 1], [1.0, 1, 1]).tolist() == [0, 1]
    wide.validate()


def test_removed_ids_are_reused_and_tree_stays_valid():
    tree = AabbTree()
    ids = tree.insert(np.zeros((5, 3)), np.ones((5, 3)))
    tree.remove(ids[[1, 3]])
    assert len(tree) == 3
    assert sorted(tree.insert(np.zeros((2, 3)), np.ones((2, 3))).tolist()) == [1, 3]
    assert tree.query_pairs().shape == (10, 2)
    tree.validate()


@pytest.mark.parametrize("n", [256, 4096])
def test_height_for_boxes_inserted_in_a_row(n):
    lo = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])
    tree = AabbTree()
    tree.insert(lo, lo + 0.5)
    tree.validate()
    assert tree.height < 2 * math.log2(n)


def test_height_for_boxes_inserted_on_a_grid_then_after_every_box_moves():
    k = 64
    n = k * k
    xy = (
        np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="ij"), -1)
        .reshape(-1, 2)
        .astype(float)
    )
    lo = np.column_stack([xy, np.zeros(n)])
    tree = AabbTree(margin=0.1)
    ids = tree.insert(lo, lo + 0.8)
    tree.validate()
    assert tree.height < 2 * math.log2(n)
    rng = np.random.default_rng(7)
    for _ in range(3):
        lo = lo + rng.normal(scale=2.0, size=lo.shape)
        assert tree.move(ids, lo, lo + 0.8).all()
    tree.validate()
    assert tree.height < 3 * math.log2(n)
    assert np.array_equal(tree.query_pairs(), sort_and_sweep(lo, lo + 0.8))


def test_identical_boxes_do_not_make_a_chain():
    n = 2048
    tree = AabbTree()
    tree.insert(np.zeros((n, 3)), np.ones((n, 3)))
    tree.validate()
    assert tree.height < 2 * math.log2(n)
    assert tree.query_pairs().shape == (n * (n - 1) // 2, 2)


def test_rebuild_keeps_ids_and_lowers_sah_cost():
    rng = np.random.default_rng(1)
    lo = rng.random((3000, 3)) * 50
    tree = AabbTree()
    ids = tree.insert(lo, lo + 1)
    before = tree.query_pairs()
    tree.rebuild()
    tree.validate()
    assert np.array_equal(tree.query_pairs(), before)
    assert np.array_equal(
        tree.query(lo[5], lo[5]),
        np.sort(ids[np.flatnonzero(((lo <= lo[5]) & (lo[5] <= lo + 1)).all(1))]),
    )
    fresh = AabbTree.from_boxes(lo, lo + 1)
    assert fresh.area_ratio == pytest.approx(tree.area_ratio)
    assert fresh.height < 3 * math.log2(len(lo))


def test_incremental_sweep_reuses_the_order():
    rng = np.random.default_rng(2)
    lo = rng.random((5000, 3)) * 100
    sweep = SortAndSweep(lo, lo + 1)
    small = lo + rng.normal(scale=1e-4, size=lo.shape)
    assert np.array_equal(sweep.update(small, small + 1), sort_and_sweep(small, small + 1))
    assert 0 <= sweep.last_shifts < len(lo)
    shuffled = rng.random((5000, 3)) * 100
    assert np.array_equal(
        sweep.update(shuffled, shuffled + 1), sort_and_sweep(shuffled, shuffled + 1)
    )
    assert sweep.last_shifts == -1  # not nearly sorted: fell back to a full sort
    assert len(sweep) == 5000


@settings(max_examples=15)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1e-3, 0.05, 0.5, 3.0]))
def test_incremental_sweep_with_grid_cells_equals_brute_force(seed, motion):
    # Enough boxes for the cross-axis grid; motions from "stays in its cells" to "many boxes
    # change cells" (merged into their new cells) to "rebuild"; some boxes leave the first
    # step's bounds (clamped to the border cells) and some grow.
    rng = np.random.default_rng(seed)
    n = 1500
    lo = rng.random((n, 3)) * 40
    hi = lo + rng.uniform(0.0, 1.5, size=lo.shape)
    sweep = SortAndSweep(lo, hi)
    for step in range(3):
        delta = rng.normal(size=lo.shape) * motion
        delta[rng.random(n) < 0.3] = 0.0
        lo = lo + delta
        hi = hi + delta + (rng.random((n, 1)) < 0.01) * 5.0 * step
        assert np.array_equal(sweep.update(lo, hi), brute_force_pairs(lo, hi))
        assert np.array_equal(sweep.pairs(), brute_force_pairs(lo, hi))
    if motion == 1e-3:
        assert sweep.last_shifts >= 0  # kept the cells: no rebuild for small motions


def test_a_cap_on_pairs_stops_a_pile_without_holding_its_pairs():
    from meshcol.errors import TooManyPairsError

    n = 3000  # a pile: 4,498,500 pairs, 72 MB as the (k, 2) array it would return
    lo = np.repeat(np.linspace(0.0, 0.01, n)[:, None], 3, axis=1)
    hi = lo + 1.0
    with pytest.raises(TooManyPairsError, match=r"more than 1,000 overlapping pairs among 3,000"):
        sort_and_sweep(lo, hi, max_pairs=1000)
    groups = np.arange(n) // 2  # pairs within a group do not count towards the cap
    with pytest.raises(TooManyPairsError):
        sort_and_sweep(lo, hi, groups=groups, max_pairs=10_000)
    few_lo, few_hi = lo[:50], hi[:50]
    every = sort_and_sweep(few_lo, few_hi)
    assert len(every) == 50 * 49 // 2
    np.testing.assert_array_equal(sort_and_sweep(few_lo, few_hi, max_pairs=len(every)), every)
    with pytest.raises(TooManyPairsError):
        sort_and_sweep(few_lo, few_hi, max_pairs=len(every) - 1)
    assert len(sort_and_sweep(lo[:1], hi[:1], max_pairs=0)) == 0
    with pytest.raises(ValueError, match="max_pairs must be None or >= 0"):
        sort_and_sweep(lo, hi, max_pairs=-1)
