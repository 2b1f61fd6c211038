"""The pair table and the stages that fill it: the broad and narrow phase of ``check``, the
broad phase that ``sweep`` and ``collision-matrix`` share with it.

A :class:`PairTable` holds one row per candidate body pair, one array per field (a struct of
arrays): the bodies, the part pairs the narrow phase measures, then what the stages find
(distances, points, normals, depth, containment, status, policy flags). ``check`` is a short
list of stages, each taking the table and returning it with more columns filled::

    placed = place(colliders)                                   # world poses and boxes
    table = broad_phase(placed, margin, excluded)               # candidate pairs
    table = convex_phase(table, placed)                         # GJK / EPA / SAT
    table = mesh_phase(table, placed, tolerance)                # triangles (mesh_phase.py)
    table = classify(table, tolerance, clearance)               # statuses

A new status touches :func:`classify`; a new collider kind the stage that measures it.

The broad phase is one mechanism in two forms. For one placement of many bodies (``check``,
``sweep``): :func:`overlapping_pairs`, sort and sweep on boxes grown by a margin, pairs
oriented by body, first on bodies, then on their parts. For many placements of a few bodies
(``collision-matrix``: a robot at thousands of configurations): :func:`broad_phase_batch`,
the same two steps as dense box tests vectorised over the placements, each body pair's part
pairs listed once (:class:`PartPairIndex`). Both keep a part pair when the two boxes overlap
(closed intervals: touching counts), and both take body boxes as the union of their parts'
(:func:`body_boxes`).

Every point is in the world frame, every normal points from body ``a`` to body ``b``,
``signed_distance = distance - depth``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.io.column_bodies import body_names
from meshcol.types import PartFilter, Status
from meshcol.vocabulary import PAIR_STATUSES

__all__ = [
    "MEASURES",
    "NO_ANSWER",
    "SEVERITY",
    "PairTable",
    "PartPairIndex",
    "PlacedColliders",
    "body_boxes",
    "broad_phase",
    "broad_phase_batch",
    "cartesian_part_pairs",
    "classify",
    "convex_phase",
    "excluded_mask",
    "filter_parts",
    "overlapping_pairs",
    "place",
]

#: Index of each pair status in :data:`meshcol.vocabulary.PAIR_STATUSES` (its severity).
SEVERITY = {name: i for i, name in enumerate(PAIR_STATUSES)}
#: Query statuses whose numbers are not the answer: the pair is reported ``query_failed``.
NO_ANSWER = (int(Status.INVALID_INPUT), int(Status.OUT_OF_RANGE))

# ---------------------------------------------------------------------------------------------
# The table


@dataclass(frozen=True, eq=False)
class PairTable:
    """Candidate body pairs and what the stages found, one array per field, one row per pair.

    Frozen: a stage returns a new table (:meth:`writable` copies the columns it fills).

    Attributes
    ----------
    body_a, body_b : (k,) int64
        Body indices (into ``Colliders.bodies``), ``body_a < body_b``.
    part_pairs : (m, 2) int64
        The convex part pairs (indices into ``Colliders.shapes``) the narrow phase measures,
        each oriented (part of body a, part of body b).
    part_row : (m,) int64
        The row of each part pair.
    excluded_pairs : int
        Body pairs whose boxes overlap but that the scene excludes (never rows).
    signed_distance, distance, depth : (k,) float64
        ``inf``, ``inf``, 0 until measured. ``depth`` is a lower bound of the minimum
        translation distance that separates the pair.
    depth_upper : (k,) float64
        An upper bound of the same (:func:`meshcol.analysis.depth_bounds.depth_bounds`): 0
        until measured and for pairs apart; NaN when its query gave no answer.
    normal, point_a, point_b : (k, 3) float64
        World frame; NaN until measured.
    part_a, part_b : (k,) int64
        The convex parts (index within the body) that come closest; -1 when unknown or
        measured on the triangles.
    label_a, label_b : (k,) int64
        Which named part (``Body.parts``) holds the closest points; -1 for a body of one part.
    contained : (k,) bool
        One body lies wholly inside the other's closed surface.
    undecided : (k,) bool
        No inside test decides whether the pair overlaps or nests (a non-orientable mesh whose
        ray parity splits): ``depth`` is then 0, a lower bound, and :func:`classify` calls the
        pair ``undecided`` unless ``depth_upper`` is within the tolerance.
    query_failed : (k,) bool
        A query's status says its numbers are not the answer.
    intersection_volume : (k,) float64
        Volume of the two closed meshes' intersection; NaN when not measured.
    status : (k,) int64
        Index into :data:`meshcol.vocabulary.PAIR_STATUSES`; 0 (separated) until classified.
    ignored, violation : (k,) bool
        Policy flags of ``check``: spared by an ignore rule; fails the run.
    convex_depth, convex_normal, convex_status : (k,) float64, (k, 3) float64, (k,) int64
        The narrow phase's own answer for the row's closest part pair (depth, normal, query
        status), as :func:`convex_phase` found it, whatever later stages make of the row;
        status -1 until measured. For two bodies of one convex part each, that pair is the
        bodies' enclosing sets, whose depth :func:`~meshcol.analysis.depth_bounds.
        depth_bounds` then reads here instead of measuring it again.
    partial : (k,) bool
        The scene's part filter (:class:`~meshcol.types.PartFilter`) left some of the row's
        part pairs out: it is measured on its allowed convex part pairs only, never on the
        bodies' whole triangles (:func:`~meshcol.analysis.mesh_phase.mesh_phase`).
    """

    body_a: np.ndarray
    body_b: np.ndarray
    part_pairs: np.ndarray
    part_row: np.ndarray
    excluded_pairs: int
    signed_distance: np.ndarray
    distance: np.ndarray
    depth: np.ndarray
    depth_upper: np.ndarray
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    part_a: np.ndarray
    part_b: np.ndarray
    label_a: np.ndarray
    label_b: np.ndarray
    contained: np.ndarray
    undecided: np.ndarray
    query_failed: np.ndarray
    intersection_volume: np.ndarray
    status: np.ndarray
    ignored: np.ndarray
    violation: np.ndarray
    convex_depth: np.ndarray
    convex_normal: np.ndarray
    convex_status: np.ndarray
    partial: np.ndarray

    @classmethod
    def of_candidates(
        cls,
        body_pairs: np.ndarray,
        part_pairs: np.ndarray,
        part_row: np.ndarray,
        excluded_pairs: int = 0,
    ) -> PairTable:
        """A table of candidate pairs, nothing measured yet."""
        k = len(body_pairs)
        return cls(
            body_a=body_pairs[:, 0],
            body_b=body_pairs[:, 1],
            part_pairs=part_pairs,
            part_row=part_row,
            excluded_pairs=excluded_pairs,
            signed_distance=np.full(k, np.inf),
            distance=np.full(k, np.inf),
            depth=np.zeros(k),
            depth_upper=np.zeros(k),
            normal=np.full((k, 3), np.nan),
            point_a=np.full((k, 3), np.nan),
            point_b=np.full((k, 3), np.nan),
            part_a=np.full(k, -1, dtype=np.int64),
            part_b=np.full(k, -1, dtype=np.int64),
            label_a=np.full(k, -1, dtype=np.int64),
            label_b=np.full(k, -1, dtype=np.int64),
            contained=np.zeros(k, dtype=bool),
            undecided=np.zeros(k, dtype=bool),
            query_failed=np.zeros(k, dtype=bool),
            intersection_volume=np.full(k, np.nan),
            status=np.zeros(k, dtype=np.int64),
            ignored=np.zeros(k, dtype=bool),
            violation=np.zeros(k, dtype=bool),
            convex_depth=np.full(k, np.nan),
            convex_normal=np.full((k, 3), np.nan),
            convex_status=np.full(k, -1, dtype=np.int64),
            partial=np.zeros(k, dtype=bool),
        )

    def __len__(self) -> int:
        return len(self.body_a)

    @property
    def body_pairs(self) -> np.ndarray:
        """(k, 2) int64: ``body_a``, ``body_b`` side by side."""
        return np.stack([self.body_a, self.body_b], axis=1)

    def writable(self, *names: str) -> PairTable:
        """The same table with the columns ``names`` copied, for a stage to fill."""
        return dataclasses.replace(self, **{name: getattr(self, name).copy() for name in names})

    def take(self, order: np.ndarray) -> PairTable:
        """The rows ``order`` (a permutation), part pairs following their rows."""
        moved = np.empty(len(order), dtype=np.int64)
        moved[order] = np.arange(len(order))
        rows = {
            f.name: getattr(self, f.name)[order]
            for f in dataclasses.fields(self)
            if f.name not in ("part_pairs", "part_row", "excluded_pairs")
        }
        return dataclasses.replace(self, part_row=moved[self.part_row], **rows)


#: The columns the narrow-phase stages fill.
MEASURES = (
    "signed_distance",
    "distance",
    "depth",
    "normal",
    "point_a",
    "point_b",
    "part_a",
    "part_b",
    "label_a",
    "label_b",
    "contained",
    "undecided",
    "query_failed",
    "intersection_volume",
)


@dataclass(frozen=True, eq=False)
class PlacedColliders:
    """Colliders at their world poses.

    Attributes
    ----------
    colliders : meshcol.analysis.colliders.Colliders
    part_poses : (n_parts, 4, 4) float64
        World-from-local pose of every convex part.
    part_min, part_max : (n_parts, 3) float64
        World boxes of the parts.
    body_min, body_max : (n_bodies, 3) float64
        World boxes of the bodies (the union of their parts': a ``mesh`` body's hull box is
        its mesh's box).
    """

    colliders: Any
    part_poses: np.ndarray
    part_min: np.ndarray
    part_max: np.ndarray
    body_min: np.ndarray
    body_max: np.ndarray


def place(colliders: Any, threads: int = 0) -> PlacedColliders:
    """The colliders at their bodies' poses: every part's world pose and box, every body's."""
    part_poses = colliders.part_poses()
    part_min, part_max = colliders.shapes.aabbs(part_poses, threads=threads)
    body_min, body_max = body_boxes(part_min, part_max, colliders.body_part_offsets)
    return PlacedColliders(colliders, part_poses, part_min, part_max, body_min, body_max)


# ---------------------------------------------------------------------------------------------
# Broad phase


def body_boxes(
    part_min: np.ndarray, part_max: np.ndarray, body_part_offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Body boxes as the union of their parts' boxes (parts of a body are contiguous).

    Parameters
    ----------
    part_min, part_max : (..., n_parts, 3) float
        Part boxes, any leading axes (configurations).
    body_part_offsets : (n_bodies + 1,) int64
        Body ``i`` owns parts ``offsets[i]:offsets[i + 1]``; every body at least one.

    Returns
    -------
    body_min, body_max : (..., n_bodies, 3) float64
    """
    starts = body_part_offsets[:-1]
    if len(starts) == 0:
        empty = np.zeros((*part_min.shape[:-2], 0, 3))
        return empty, empty.copy()
    if len(starts) == part_min.shape[-2]:  # one part a body: its box is the body's (as is)
        return part_min, part_max
    return (
        np.minimum.reduceat(part_min, starts, axis=-2),
        np.maximum.reduceat(part_max, starts, axis=-2),
    )


def overlapping_pairs(
    aabb_min: np.ndarray,
    aabb_max: np.ndarray,
    margin: float,
    groups: np.ndarray | None = None,
    max_pairs: int | None = None,
) -> np.ndarray:
    """Pairs of boxes that overlap once each side grows by ``margin / 2``, by sort and sweep.

    Parameters
    ----------
    aabb_min, aabb_max : (n, 3) float
        World boxes.
    margin : float
        The gap still counted as overlap (``check``: clearance and tolerance).
    groups : (n,) int64, optional
        A group per box (the body of a part): boxes of one group never pair, and each pair is
        oriented so that its first box has the smaller group.
    max_pairs : int, optional
        The sweep's cap (:func:`meshcol.collision.broadphase.sort_and_sweep`): more pairs
        raise ``TooManyPairsError`` without holding them all.

    Returns
    -------
    (k, 2) int64
        Sorted as :func:`meshcol.collision.broadphase.sort_and_sweep` gives them, then
        oriented.
    """
    from meshcol.collision.broadphase import sort_and_sweep

    half = 0.5 * margin
    unbounded = _unbounded(aabb_min, aabb_max)
    if unbounded is not None:
        pairs = _with_unbounded(aabb_min - half, aabb_max + half, unbounded, groups, max_pairs)
    else:
        pairs = sort_and_sweep(aabb_min - half, aabb_max + half, groups=groups, max_pairs=max_pairs)
    if groups is not None and len(pairs):
        swap = groups[pairs[:, 0]] > groups[pairs[:, 1]]
        pairs[swap] = pairs[swap][:, ::-1]
    return pairs


def _above_half_spaces(placed: PlacedColliders, pairs: np.ndarray, margin: float) -> np.ndarray:
    """Mask of the body pairs of a half-space (an MJCF plane's body: one part of kind
    ``HALFSPACE``) whose other body's box lies more than ``margin`` above its plane: a
    tilted plane's box is unbounded along every axis, so the boxes' sweep pairs it with
    everything. The box's lowest corner along the normal is at most the body's lowest point,
    so no pair within the margin is dropped."""
    from meshcol.collision.shapes import ShapeKind

    colliders = placed.colliders
    drop = np.zeros(len(pairs), dtype=bool)
    half = colliders.shapes.kinds == ShapeKind.HALFSPACE
    if len(pairs) == 0 or not half.any():
        return drop
    plane = np.zeros(len(placed.body_min), dtype=bool)
    plane[colliders.part_body[half]] = True
    first = plane[pairs[:, 0]]
    rows = np.flatnonzero(first ^ plane[pairs[:, 1]])
    owner = np.where(first[rows], pairs[rows, 0], pairs[rows, 1])
    other = np.where(first[rows], pairs[rows, 1], pairs[rows, 0])
    pose = placed.part_poses[colliders.body_part_offsets[owner]]
    normal, origin = pose[:, :3, 2], pose[:, :3, 3]
    lowest = np.where(normal > 0.0, placed.body_min[other], placed.body_max[other])
    drop[rows] = np.einsum("ij,ij->i", normal, lowest - origin) > margin
    return drop


def _unbounded(aabb_min: np.ndarray, aabb_max: np.ndarray) -> np.ndarray | None:
    """The indices of the boxes with an infinite side and no NaN (a half-space's,
    ``ShapeKind.HALFSPACE``), or None when there is none (a NaN box is the sweep's error)."""
    infinite = np.isinf(aabb_min).any(axis=1) | np.isinf(aabb_max).any(axis=1)
    if not infinite.any():
        return None
    infinite &= ~(np.isnan(aabb_min).any(axis=1) | np.isnan(aabb_max).any(axis=1))
    return np.flatnonzero(infinite) if infinite.any() else None


def _with_unbounded(
    lo: np.ndarray,
    hi: np.ndarray,
    unbounded: np.ndarray,
    groups: np.ndarray | None,
    max_pairs: int | None,
) -> np.ndarray:
    """:func:`overlapping_pairs`' pairs (boxes grown already) when some boxes are unbounded:
    the bounded ones by the sweep, each unbounded one against every box by the same
    interval test (an array expression per unbounded box: a scene has a floor or a few),
    lexicographically sorted as the sweep sorts its own."""
    from meshcol.collision.broadphase import sort_and_sweep

    bounded = np.setdiff1d(np.arange(len(lo)), unbounded)
    own = None if groups is None else groups[bounded]
    found = [bounded[sort_and_sweep(lo[bounded], hi[bounded], groups=own, max_pairs=max_pairs)]]
    for u in unbounded.tolist():
        meets = np.all((lo <= hi[u]) & (lo[u] <= hi), axis=1)
        meets[u] = False
        meets[unbounded[unbounded < u]] = False  # a pair of two unbounded boxes once
        if groups is not None:
            meets &= groups != groups[u]
        others = np.flatnonzero(meets)
        found.append(np.stack([np.minimum(others, u), np.maximum(others, u)], axis=1))
    pairs = np.concatenate(found).reshape(-1, 2)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def excluded_mask(
    names: Sequence[str], excluded: Sequence[tuple[str, str, str]], pairs: np.ndarray
) -> np.ndarray:
    """Boolean mask of the body pairs (rows of ``pairs``, a < b) that ``excluded`` names
    (``Scene.excluded_pairs``: a robot's adjacent links, an SRDF's disabled pairs)."""
    if not excluded or len(pairs) == 0:
        return np.zeros(len(pairs), dtype=bool)
    index = {name: i for i, name in enumerate(names)}
    known = [(index[a], index[b]) for a, b, _ in excluded if a in index and b in index]
    if not known:
        return np.zeros(len(pairs), dtype=bool)
    ends = np.array(known, dtype=np.int64)
    n = len(names)
    keys = np.minimum(ends[:, 0], ends[:, 1]) * n + np.maximum(ends[:, 0], ends[:, 1])
    return np.isin(pairs[:, 0] * n + pairs[:, 1], keys)


def cartesian_part_pairs(body_pairs: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Every (part of a, part of b) pair of the body pairs, grouped by body pair in order and
    within one lexicographically, without a Python loop.

    Parameters
    ----------
    body_pairs : (k, 2) int64
    offsets : (n_bodies + 1,) int64
        Body ``i`` owns parts ``offsets[i]:offsets[i + 1]``.

    Returns
    -------
    (m, 2) int64
    """
    if len(body_pairs) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    na = offsets[body_pairs[:, 0] + 1] - offsets[body_pairs[:, 0]]
    nb = offsets[body_pairs[:, 1] + 1] - offsets[body_pairs[:, 1]]
    sizes = na * nb
    pair_of = np.repeat(np.arange(len(body_pairs)), sizes)
    starts = np.zeros(len(sizes), dtype=np.int64)
    np.cumsum(sizes[:-1], out=starts[1:])
    local = np.arange(sizes.sum()) - starts[pair_of]
    ia = offsets[body_pairs[pair_of, 0]] + local // nb[pair_of]
    ib = offsets[body_pairs[pair_of, 1]] + local % nb[pair_of]
    return np.stack([ia, ib], axis=1)


def _too_many(count: str, bodies: int, max_pairs: int | None) -> Exception:
    from meshcol.errors import TooManyPairsError

    return TooManyPairsError(
        f"{count} candidate pairs among {bodies:,} bodies, more than --max-pairs "
        f"{max_pairs:,} allows (the memory a run holds grows with its pairs: raise "
        "--max-pairs, or check the scene in parts)"
    )


def broad_phase(
    placed: PlacedColliders,
    margin: float,
    excluded: Sequence[tuple[str, str, str]] = (),
    max_pairs: int | None = None,
    part_filter: PartFilter | None = None,
) -> PairTable:
    """Candidate body pairs and the part pairs to measure for each.

    Body pairs whose boxes, grown by ``margin``, overlap (:func:`overlapping_pairs`), less
    those ``excluded`` names; for each, the part pairs whose boxes overlap the same way (parts
    of one body never pair), or every part pair when none does (so that every candidate gets
    a distance). With a ``part_filter`` (an MJCF's geom filters), only the part pairs it
    allows (:func:`filter_parts`).

    Raises
    ------
    TooManyPairsError
        More than ``max_pairs`` candidate body pairs, found before any part pair, table row
        or measure is made: the sweep itself stops once it holds ``max_pairs`` plus one pair
        per ``excluded`` entry (the most the exclusions could remove), so that a pile of
        bodies never fills memory with its pairs; within that, the exact count is named.
    """
    table = _candidates(placed, margin, excluded, max_pairs)
    if part_filter is None or len(table) == 0:
        return table
    return filter_parts(table, placed.colliders, part_filter)


def _candidates(
    placed: PlacedColliders,
    margin: float,
    excluded: Sequence[tuple[str, str, str]],
    max_pairs: int | None,
) -> PairTable:
    """:func:`broad_phase` without a part filter."""
    from meshcol.errors import TooManyPairsError

    colliders = placed.colliders
    names = body_names(colliders.bodies)
    sweep_cap = None if max_pairs is None else max_pairs + len(excluded)
    try:
        body_pairs = overlapping_pairs(
            placed.body_min, placed.body_max, margin, max_pairs=sweep_cap
        )
    except TooManyPairsError:
        raise _too_many(f"more than {max_pairs:,}", len(names), max_pairs) from None
    left_out = excluded_mask(names, excluded, body_pairs)
    above = _above_half_spaces(placed, body_pairs, margin)
    body_pairs = body_pairs[~(left_out | above)]
    if max_pairs is not None and len(body_pairs) > max_pairs:
        raise _too_many(f"{len(body_pairs):,}", len(names), max_pairs)
    if len(body_pairs) == 0:
        empty = np.zeros((0, 2), dtype=np.int64)
        return PairTable.of_candidates(body_pairs, empty, empty[:, 0], int(left_out.sum()))
    owner = colliders.part_body
    if len(owner) == len(names):  # one part a body: its box is the body's, its pairs theirs
        rows = np.arange(len(body_pairs), dtype=np.int64)
        return PairTable.of_candidates(body_pairs, body_pairs.copy(), rows, int(left_out.sum()))
    n = max(len(names), 1)
    key = body_pairs[:, 0] * n + body_pairs[:, 1]
    part_pairs = overlapping_pairs(placed.part_min, placed.part_max, margin, groups=owner)
    part_key = owner[part_pairs[:, 0]] * n + owner[part_pairs[:, 1]]
    if left_out.any() or above.any():  # part pairs of excluded body pairs
        keep = np.isin(part_key, key)
        part_pairs, part_key = part_pairs[keep], part_key[keep]
    # Body pairs whose parts' boxes never meet are still measured: all their part pairs.
    uncovered = cartesian_part_pairs(
        body_pairs[~np.isin(key, part_key)], colliders.body_part_offsets
    )
    if len(uncovered):
        part_pairs = np.concatenate([part_pairs, uncovered])
        part_key = np.concatenate([part_key, owner[uncovered[:, 0]] * n + owner[uncovered[:, 1]]])
    part_row = np.searchsorted(key, part_key)  # body pairs are sorted, so keys are too
    return PairTable.of_candidates(body_pairs, part_pairs, part_row, int(left_out.sum()))


def filter_parts(table: PairTable, colliders: Any, part_filter: PartFilter) -> PairTable:
    """The candidates with only the part pairs ``part_filter`` allows (MuJoCo's per-geom
    test). A row whose box-overlapping part pairs are all left out gets every allowed one
    (as a row whose boxes never meet gets every one); a row with none allowed is dropped and
    counted excluded (an MJCF's reader excludes such body pairs already, with their reason);
    ``partial`` marks the rows some part pair of which is left out."""
    from meshcol.analysis.part_filter import part_geoms

    owner = colliders.part_body
    filt = part_geoms(part_filter, body_names(colliders.bodies), owner, colliders.part_label)
    body_pairs = table.body_pairs
    every = cartesian_part_pairs(body_pairs, colliders.body_part_offsets)
    offsets = colliders.body_part_offsets
    sizes = (offsets[body_pairs[:, 0] + 1] - offsets[body_pairs[:, 0]]) * (
        offsets[body_pairs[:, 1] + 1] - offsets[body_pairs[:, 1]]
    )
    every_row = np.repeat(np.arange(len(table)), sizes)
    every_ok = filt.allowed(every, owner)
    allowed = np.bincount(every_row[every_ok], minlength=len(table))
    partial = np.bincount(every_row[~every_ok], minlength=len(table)) > 0
    if not partial.any():
        return table
    ok = filt.allowed(table.part_pairs, owner)
    part_pairs, part_row = table.part_pairs[ok], table.part_row[ok]
    bare = np.bincount(part_row, minlength=len(table)) == 0
    refill = every_ok & bare[every_row]  # rows whose overlapping pairs were all left out
    part_pairs = np.concatenate([part_pairs, every[refill]])
    part_row = np.concatenate([part_row, every_row[refill]])
    kept = allowed > 0
    renumber = np.cumsum(kept) - 1
    out = PairTable.of_candidates(
        body_pairs[kept],
        part_pairs,
        renumber[part_row],
        table.excluded_pairs + int((~kept).sum()),
    )
    return dataclasses.replace(out, partial=partial[kept])


@dataclass(frozen=True, eq=False)
class PartPairIndex:
    """Every part pair of every listed body pair, grouped by body pair (computed once, for
    :func:`broad_phase_batch`).

    Attributes
    ----------
    body_pairs : (p, 2) int64
    part_pairs : (m, 2) int64
        :func:`cartesian_part_pairs` of ``body_pairs``.
    sizes, starts : (p,) int64
        Body pair ``r`` owns ``part_pairs[starts[r]:starts[r] + sizes[r]]``.
    """

    body_pairs: np.ndarray
    part_pairs: np.ndarray
    sizes: np.ndarray
    starts: np.ndarray

    @classmethod
    def of(
        cls,
        body_pairs: np.ndarray,
        offsets: np.ndarray,
        colliders: Any = None,
        part_filter: PartFilter | None = None,
    ) -> PartPairIndex:
        """The index; with ``part_filter`` (and the ``colliders`` it names parts of), only
        the part pairs it allows (:func:`filter_parts`' rule)."""
        a, b = body_pairs[:, 0], body_pairs[:, 1]
        sizes = ((offsets[a + 1] - offsets[a]) * (offsets[b + 1] - offsets[b])).astype(np.int64)
        part_pairs = cartesian_part_pairs(body_pairs, offsets)
        if part_filter is not None and len(part_pairs):
            from meshcol.analysis.part_filter import part_geoms

            owner = colliders.part_body
            names = body_names(colliders.bodies)
            ok = part_geoms(part_filter, names, owner, colliders.part_label).allowed(
                part_pairs, owner
            )
            row = np.repeat(np.arange(len(body_pairs)), sizes)
            part_pairs, sizes = part_pairs[ok], np.bincount(row[ok], minlength=len(body_pairs))
        starts = np.zeros(len(sizes), dtype=np.int64)
        np.cumsum(sizes[:-1], out=starts[1:])
        return cls(body_pairs, part_pairs, sizes.astype(np.int64), starts)

    def expand(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The part pairs of the body pairs ``rows`` (repeats allowed), in order: ``(owner,
        part_pairs)``, ``owner[i]`` the position in ``rows`` of part pair ``i``'s body pair."""
        sizes = self.sizes[rows]
        owner = np.repeat(np.arange(len(rows)), sizes)
        first = np.zeros(len(sizes), dtype=np.int64)
        np.cumsum(sizes[:-1], out=first[1:])
        picked = self.starts[rows][owner] + np.arange(int(sizes.sum())) - first[owner]
        return owner, self.part_pairs[picked]


def _apart(lo: np.ndarray, hi: np.ndarray, a: Any, b: Any) -> np.ndarray:
    """Boxes ``a`` and ``b`` (indices on the second-last axis) are apart on some axis; NaN
    boxes compare False, so they are never apart (the narrow phase gives them a status)."""
    return np.any((lo[..., a, :] > hi[..., b, :]) | (lo[..., b, :] > hi[..., a, :]), axis=-1)


def broad_phase_batch(
    part_min: np.ndarray,
    part_max: np.ndarray,
    body_part_offsets: np.ndarray,
    index: PartPairIndex,
    skip: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The broad phase of many placements of a few bodies: which part pairs to measure.

    Parameters
    ----------
    part_min, part_max : (c, n_parts, 3) float
        Part boxes at each of ``c`` placements (margin included).
    body_part_offsets : (n_bodies + 1,) int64
    index : PartPairIndex
        The body pairs considered and their part pairs.
    skip : (p,) bool
        Body pairs never measured.

    Returns
    -------
    placement, row, part_pairs : (m,) int64, (m,) int64, (m, 2) int64
        For each part pair to measure: its placement, its body pair (row of
        ``index.body_pairs``) and the two parts, grouped by (placement, body pair).
    """
    body_min, body_max = body_boxes(part_min, part_max, body_part_offsets)
    a, b = index.body_pairs[:, 0], index.body_pairs[:, 1]
    apart = _apart(body_min, body_max, a, b) | skip
    placement, row = np.nonzero(~apart)
    owner, part_pairs = index.expand(row)
    at = placement[owner]
    pa, pb = part_pairs[:, 0], part_pairs[:, 1]
    keep = ~np.any(
        (part_min[at, pa] > part_max[at, pb]) | (part_min[at, pb] > part_max[at, pa]), axis=1
    )
    return at[keep], row[owner[keep]], part_pairs[keep]


# ---------------------------------------------------------------------------------------------
# Narrow phase


def _closest_per_row(rows: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Index of the smallest value of each row (rows need not be sorted; ties: first)."""
    if len(rows) < 2 or bool((rows[1:] > rows[:-1]).all()):  # each row once, in order
        return np.arange(len(rows), dtype=np.int64)
    order = np.lexsort((values, rows))
    sorted_rows = rows[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = sorted_rows[1:] != sorted_rows[:-1]
    return order[first]


def convex_phase(table: PairTable, placed: PlacedColliders, threads: int = 0) -> PairTable:
    """Every part pair's signed distance in one native call (GJK, EPA, exact SAT); each row
    takes its closest part pair (smallest signed distance; a failed query only when every
    part pair of the row failed).

    Fills every measured column but ``contained`` and ``intersection_volume``; a ``mesh``
    body's numbers here are its hull's, which :func:`mesh_phase` replaces.
    """
    if len(table) == 0:
        return table
    from meshcol.collision.narrowphase import signed_distance_batch

    colliders = placed.colliders
    found = signed_distance_batch(
        colliders.shapes, placed.part_poses, table.part_pairs, threads=threads
    )
    failed = np.isin(found.status, NO_ANSWER)
    part_row = table.part_row
    # one part pair a row, in row order (every body one part): each row takes its own
    in_order = len(part_row) == len(table) and bool((part_row[1:] > part_row[:-1]).all())
    best = (
        None
        if in_order
        else _closest_per_row(part_row, np.where(failed, np.inf, found.signed_distance))
    )

    def pick(values: np.ndarray) -> np.ndarray:
        return values if best is None else values[best]

    closest_a, closest_b = pick(table.part_pairs[:, 0]), pick(table.part_pairs[:, 1])
    values = {
        "convex_depth": pick(found.depth).copy(),  # depth's own array: no column shares one
        "convex_normal": pick(found.normal),
        "convex_status": pick(found.status),
        "signed_distance": pick(found.signed_distance),
        "distance": pick(found.distance),
        "depth": pick(found.depth),
        "normal": pick(found.normal),
        "point_a": pick(found.point_a),
        "point_b": pick(found.point_b),
        "part_a": colliders.part_index[closest_a],
        "part_b": colliders.part_index[closest_b],
        "label_a": colliders.part_label[closest_a],
        "label_b": colliders.part_label[closest_b],
        "query_failed": pick(failed),
    }
    if best is None:  # every row filled in order: the values are the columns (their types)
        columns = {
            name: v.astype(getattr(table, name).dtype, copy=False) for name, v in values.items()
        }
        return dataclasses.replace(table, **columns)
    rows = part_row[best]
    out = table.writable(*MEASURES, "convex_depth", "convex_normal", "convex_status")
    for name, v in values.items():
        getattr(out, name)[rows] = v
    return out


# ---------------------------------------------------------------------------------------------
# Classification


def classify(table: PairTable, tolerance: float, clearance: float) -> PairTable:
    """Each row's status: ``clearance`` (distance < clearance), ``contact`` (|signed
    distance| <= tolerance), ``undecided`` (no inside test decides, and ``depth_upper`` is
    above the tolerance or unknown), ``penetrating`` (signed distance < -tolerance),
    ``contained`` (one body inside the other), else ``separated``; the most severe that
    applies."""
    status = np.zeros(len(table), dtype=np.int64)
    signed = table.signed_distance
    status[table.distance < clearance] = SEVERITY["clearance"]
    status[(signed <= tolerance) & (signed >= -tolerance)] = SEVERITY["contact"]
    # undecided: no inside test settles it, and the hulls leave room for a penetration
    open_question = table.undecided & ~(table.depth_upper <= tolerance)
    status[open_question] = SEVERITY["undecided"]
    status[signed < -tolerance] = SEVERITY["penetrating"]
    status[table.contained] = SEVERITY["contained"]
    return dataclasses.replace(table, status=status)
