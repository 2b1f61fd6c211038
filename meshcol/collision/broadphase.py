"""Broad phase: the few overlapping pairs among many axis-aligned boxes.

Two structures, both in the C++ core and both exact (no false positives, no misses):

- :func:`sort_and_sweep` and its incremental form :class:`SortAndSweep`: sort the boxes on
  one axis and sweep, with a coarse grid over the two other axes so that a uniform cloud of
  boxes does not degrade into a quadratic scan.
- :class:`AabbTree`: a dynamic bounding volume tree (insert, remove, move with a fat margin,
  box and ray queries, pairs within one tree or between two), after Box2D v3.

Boxes are given as two ``(n, 3)`` float arrays, ``aabb_min`` and ``aabb_max`` (world frame).
Intervals are closed: boxes that touch overlap. Pairs come back as ``(k, 2)`` int64 arrays,
sorted lexicographically, with ``i < j`` for pairs within one set.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from meshcol._native import core

__all__ = ["sort_and_sweep", "SortAndSweep", "AabbTree", "brute_force_pairs"]


def _boxes(aabb_min: Any, aabb_max: Any) -> tuple[np.ndarray, np.ndarray]:
    """Both box arrays as C-contiguous float64 ``(n, 3)``, or ValueError naming the argument."""
    lo = np.ascontiguousarray(aabb_min, dtype=np.float64)
    hi = np.ascontiguousarray(aabb_max, dtype=np.float64)
    if lo.ndim != 2 or lo.shape[1] != 3:
        raise ValueError(f"aabb_min must be (n, 3), got {lo.shape}")
    if hi.shape != lo.shape:
        raise ValueError(f"aabb_max must be {lo.shape} like aabb_min, got {hi.shape}")
    return lo, hi


def _point(value: Any, name: str) -> np.ndarray:
    p = np.ascontiguousarray(value, dtype=np.float64)
    if p.shape != (3,):
        raise ValueError(f"{name} must be (3,), got {p.shape}")
    return p


def _one_box(aabb_min: Any, aabb_max: Any) -> tuple[np.ndarray, np.ndarray]:
    lo = np.ascontiguousarray(aabb_min, dtype=np.float64)
    hi = np.ascontiguousarray(aabb_max, dtype=np.float64)
    if lo.shape not in ((3,), (1, 3)):
        raise ValueError(f"aabb_min must be (3,) or (1, 3), got {lo.shape}")
    if hi.shape not in ((3,), (1, 3)):
        raise ValueError(f"aabb_max must be (3,) or (1, 3), got {hi.shape}")
    return lo.reshape(3), hi.reshape(3)


def _ids(ids: Any) -> np.ndarray:
    arr = np.asarray(ids)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"ids must be (n,), got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(f"ids must be integers, got {arr.dtype}")
    return np.ascontiguousarray(arr, dtype=np.int64)


def _axis(axis: int | None) -> int:
    if axis is None:
        return -1
    if (
        isinstance(axis, (bool, np.bool_))
        or not isinstance(axis, (int, np.integer))
        or not 0 <= axis <= 2
    ):
        raise ValueError(f"axis must be None, 0, 1 or 2, got {axis!r}")
    return int(axis)


def sort_and_sweep(
    aabb_min: Any,
    aabb_max: Any,
    axis: int | None = None,
    groups: Any = None,
    max_pairs: int | None = None,
) -> np.ndarray:
    """All pairs of overlapping boxes, by sort and sweep.

    Parameters
    ----------
    aabb_min : (n, 3) float
        Minimum corners (world frame).
    aabb_max : (n, 3) float
        Maximum corners (world frame), ``aabb_max >= aabb_min``.
    axis : {None, 0, 1, 2}
        Sweep axis; None chooses the axis of largest variance of the box centres.
    groups : (n,) int, optional
        A group id per box: boxes of the same group are never paired (the convex parts of
        one body). None pairs every overlapping box.
    max_pairs : int, optional
        A cap on the pairs: with more, the sweep stops early, holding at most about this
        many pairs a thread, and raises :class:`meshcol.errors.TooManyPairsError`. A pile of
        n boxes that all overlap has n(n-1)/2 pairs; the cap keeps it from filling memory.

    Returns
    -------
    pairs : (k, 2) int64
        Indices ``i < j`` of the boxes that overlap (touching counts) and lie in different
        groups, sorted lexicographically.

    Raises
    ------
    ValueError
        Wrong shapes (naming the argument), or a box that is not finite or has min > max
        (naming the first such box).
    TooManyPairsError
        More than ``max_pairs`` pairs (a subclass of ValueError).

    Notes
    -----
    Sort and sweep (Baraff 1992; Cohen et al. 1995; Ericson 2004, 7.5.2): the boxes are
    sorted by their minimum on the sweep axis and each is compared with the boxes that start
    inside its interval, overlap on the other axes confirming. Because one axis prunes badly
    for boxes spread in 3D (a slab holds O(n^(2/3)) boxes), the two other axes get a coarse
    grid a few median box sizes wide ("multi box pruning", as PhysX MBP); a pair seen in
    several cells is reported by one cell only. The grid changes the speed, never the
    result. Runs in C++ on all cores with the GIL released.
    """
    lo, hi = _boxes(aabb_min, aabb_max)
    if max_pairs is not None and max_pairs < 0:
        raise ValueError(f"max_pairs must be None or >= 0, got {max_pairs}")
    cap = -1 if max_pairs is None else int(max_pairs)
    ids = None
    if groups is not None:
        ids = np.ascontiguousarray(groups, dtype=np.int64)
        if ids.shape != (len(lo),):
            raise ValueError(f"groups must be ({len(lo)},), got {ids.shape}")
    pairs = core.sort_and_sweep(lo, hi, _axis(axis), groups=ids, max_pairs=cap)
    if pairs is None:
        from meshcol.errors import TooManyPairsError

        raise TooManyPairsError(f"more than {cap:,} overlapping pairs among {len(lo):,} boxes")
    return pairs


def brute_force_pairs(aabb_min: Any, aabb_max: Any) -> np.ndarray:
    """All pairs of overlapping boxes by testing every pair: the reference for tests.

    Parameters
    ----------
    aabb_min, aabb_max : (n, 3) float
        Box corners (world frame).

    Returns
    -------
    pairs : (k, 2) int64
        As :func:`sort_and_sweep`. Costs O(n^2) time and memory in chunks of rows: use it
        for checking, not for large n.
    """
    lo, hi = _boxes(aabb_min, aabb_max)
    bad_finite = ~np.isfinite(lo).all(axis=1) | ~np.isfinite(hi).all(axis=1)
    bad_order = (lo > hi).any(axis=1)
    bad = np.flatnonzero(bad_finite | bad_order)
    if bad.size:
        i = int(bad[0])
        problem = "is not finite" if bad_finite[i] else "has min > max"
        raise ValueError(f"aabb_min/aabb_max: box {i} {problem}")
    n = lo.shape[0]
    found = []
    chunk = max(1, 2_000_000 // max(n, 1))
    for start in range(0, n, chunk):
        a_lo, a_hi = lo[start : start + chunk, None, :], hi[start : start + chunk, None, :]
        hit = ((a_lo <= hi[None]) & (lo[None] <= a_hi)).all(axis=2)
        rows, cols = np.nonzero(hit)
        rows = rows + start
        keep = rows < cols
        found.append(np.stack([rows[keep], cols[keep]], axis=1))
    if not found:
        return np.zeros((0, 2), dtype=np.int64)
    return np.concatenate(found).astype(np.int64, copy=False)


class SortAndSweep:
    """Incremental sort and sweep for a scene whose boxes move a little between steps.

    Parameters
    ----------
    aabb_min, aabb_max : (n, 3) float
        Boxes of the first step (world frame).
    axis : {None, 0, 1, 2}
        Sweep axis; None chooses by variance of the first step's centres, then keeps it.

    Notes
    -----
    The classic incremental method (Baraff 1992; Cohen et al. 1995), per cell of the
    cross-axis grid of :func:`sort_and_sweep`: the grid of the first step is kept, and so is
    each cell's order on the sweep axis. :meth:`update` refreshes the coordinates in that
    order, re-sorts each cell by insertion sort (O(entries + moves) on nearly sorted cells
    instead of a fresh grid, scatter and O(n log n) sort), moves the few boxes that left
    their cells by merging them into their new cells, and sweeps. When more than
    ``defaults.sort_and_sweep_max_cell_changes`` of the boxes changed cells, or a cell's
    insertion sort would exceed ``defaults.sort_and_sweep_max_shifts_per_box`` moves per
    entry, the motion was not small: the step rebuilds the grid or sorts that cell afresh
    (``last_shifts`` is then -1). Results equal :func:`sort_and_sweep` exactly, whatever the
    motion. The pair arrays returned are read-only views of what the object keeps for
    :meth:`pairs` (no copy); a later :meth:`update` leaves them unchanged.

    Examples
    --------
    >>> sweep = SortAndSweep(aabb_min, aabb_max)        # doctest: +SKIP
    >>> pairs = sweep.update(aabb_min + dt * v, aabb_max + dt * v)  # doctest: +SKIP
    """

    def __init__(self, aabb_min: Any, aabb_max: Any, axis: int | None = None) -> None:
        lo, hi = _boxes(aabb_min, aabb_max)
        self._sweep = core.SortAndSweep(lo, hi, _axis(axis))

    def pairs(self) -> np.ndarray:
        """Overlapping pairs of the last step: (k, 2) int64 (read-only), i < j, sorted."""
        return self._sweep.pairs()

    def update(self, aabb_min: Any, aabb_max: Any) -> np.ndarray:
        """Moves the boxes (same count) and returns the new (k, 2) int64 pairs (read-only)."""
        lo, hi = _boxes(aabb_min, aabb_max)
        if lo.shape[0] != len(self._sweep):
            raise ValueError(f"aabb_min must be ({len(self._sweep)}, 3) as before, got {lo.shape}")
        return self._sweep.update(lo, hi)

    @property
    def axis(self) -> int:
        """The sweep axis (0, 1 or 2)."""
        return self._sweep.axis

    @property
    def last_shifts(self) -> int:
        """Element moves of the last step's insertion sorts; -1 when the step sorted afresh."""
        return self._sweep.last_shifts

    def __len__(self) -> int:
        return len(self._sweep)


class AabbTree:
    """Dynamic AABB tree: a binary tree of boxes with objects at the leaves.

    Parameters
    ----------
    margin : float
        Fat margin (world units, >= 0): each leaf stores its box grown by ``margin`` so that
        :meth:`move` within it costs nothing. Results never depend on it: queries confirm
        with the exact boxes.

    Notes
    -----
    After Box2D v3 ``dynamic_tree.c`` (Catto), in 3D: insertion picks the sibling that
    minimises the surface area heuristic (SAH) cost by a greedy branch-and-bound descent
    (Bittner et al. 2013); each ancestor on the way up may swap a child with a grandchild
    when that shrinks the internal area (tree rotations, Kopta et al. 2012) and is rebalanced
    by height when its children's heights differ by more than
    ``defaults.tree_max_height_imbalance`` (so identical or aligned boxes cannot grow a
    chain). :meth:`rebuild` and :meth:`from_boxes` build top-down by binned SAH (Wald 2007).
    Pairs come from a simultaneous descent of the tree against itself or another tree,
    descending the larger node first (Ericson 2004, 6.5.2), on all cores.

    Ids are int64 handles returned by :meth:`insert`; the id of a removed box may be reused
    by a later insertion.
    """

    def __init__(self, margin: float = 0.0) -> None:
        margin = float(margin)
        if not np.isfinite(margin) or margin < 0.0:
            raise ValueError(f"margin must be finite and >= 0, got {margin}")
        self._tree = core.AabbTree(margin)

    @classmethod
    def from_boxes(cls, aabb_min: Any, aabb_max: Any, margin: float = 0.0) -> AabbTree:
        """A tree built top-down (binned SAH) over ``n`` boxes, with ids ``0 .. n-1``.

        Parameters
        ----------
        aabb_min, aabb_max : (n, 3) float
            Box corners (world frame).
        margin : float
            Fat margin, as in the constructor.
        """
        lo, hi = _boxes(aabb_min, aabb_max)
        tree = cls(margin)
        tree._tree.build(lo, hi)
        return tree

    def insert(self, aabb_min: Any, aabb_max: Any) -> np.ndarray:
        """Inserts ``n`` boxes one after the other; returns their ids, (n,) int64.

        A single box is given as ``(1, 3)`` arrays. All boxes are validated before any is
        inserted.
        """
        lo, hi = _boxes(aabb_min, aabb_max)
        return self._tree.insert(lo, hi)

    def remove(self, ids: Any) -> None:
        """Removes the objects ``ids`` ((n,) int). Every id must be live, and appear once."""
        self._tree.remove(_ids(ids))

    def move(self, ids: Any, aabb_min: Any, aabb_max: Any) -> np.ndarray:
        """Gives objects new boxes; returns (n,) bool, True where the tree had to change.

        A box still inside its fat box (the box at the last insertion or reinsertion, grown by
        ``margin``) changes no node and returns False.
        """
        index = _ids(ids)
        lo, hi = _boxes(aabb_min, aabb_max)
        if lo.shape[0] != index.shape[0]:
            raise ValueError(f"aabb_min must be ({index.shape[0]}, 3) like ids, got {lo.shape}")
        return self._tree.move(index, lo, hi)

    def query(self, aabb_min: Any, aabb_max: Any) -> np.ndarray:
        """Ids of the objects overlapping one box ((3,) or (1, 3) corners), ascending int64."""
        lo, hi = _one_box(aabb_min, aabb_max)
        return self._tree.query(lo, hi)

    def query_pairs(self, other: AabbTree | None = None) -> np.ndarray:
        """Overlapping pairs, (k, 2) int64, sorted lexicographically.

        Parameters
        ----------
        other : AabbTree, optional
            None: pairs within this tree, ``id_i < id_j``. Another tree: pairs
            ``(id in self, id in other)``.
        """
        if other is None:
            return self._tree.query_pairs()
        if not isinstance(other, AabbTree):
            raise ValueError(f"other must be an AabbTree, got {type(other).__name__}")
        return self._tree.query_pairs_with(other._tree)

    def ray_cast(
        self, origin: Any, direction: Any, max_fraction: float = 1.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Objects met by the segment ``origin + t * direction``, ``0 <= t <= max_fraction``.

        Parameters
        ----------
        origin, direction : (3,) float
            World frame; ``direction`` need not be unit (``t`` is in its units).
        max_fraction : float
            Largest ``t``, >= 0.

        Returns
        -------
        ids : (k,) int64
            Objects hit, sorted by entry fraction then id.
        fractions : (k,) float64
            Entry ``t`` of each (0 when the origin is inside the box).
        """
        return self._tree.ray_cast(
            _point(origin, "origin"), _point(direction, "direction"), float(max_fraction)
        )

    def rebuild(self) -> None:
        """Rebuilds the whole tree top-down by binned SAH, keeping the ids (for static sets)."""
        self._tree.rebuild()

    def validate(self) -> None:
        """Raises RuntimeError on any broken invariant (for tests)."""
        self._tree.validate()

    @property
    def height(self) -> int:
        """Edges on the longest root-to-leaf path (0 for an empty or one-box tree)."""
        return self._tree.height

    @property
    def margin(self) -> float:
        """The fat margin."""
        return self._tree.margin

    @property
    def area_ratio(self) -> float:
        """Internal node area over root area (the SAH quality measure; lower is better)."""
        return self._tree.area_ratio

    def __len__(self) -> int:
        return len(self._tree)
