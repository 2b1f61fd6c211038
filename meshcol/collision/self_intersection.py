"""Self-intersections of a triangle mesh: which pairs of its faces cross, decided exactly.

Two faces cross when their relative interiors (the open triangles) share a point: in different
planes, they meet along a segment through both interiors; in one plane, they overlap with
positive area. Touching is not crossing: faces that meet only at a point or along their
boundaries (a shared vertex or edge, a T-junction, a vertex resting on a face) do not cross.
Faces on the same three vertices are duplicates, not crossings.

The verdict is exact for finite coordinates: every decision is the sign of an orientation
determinant of input points (orient2d, orient3d), evaluated in floating point with an error
bound and exactly when the bound cannot decide (Shewchuk 1997). There is no tolerance.

:func:`self_intersections` finds them with a work budget: candidate pairs (faces whose boxes
overlap) stream from the core's sort and sweep into the exact test without being collected, and
the work is bounded by :data:`MAX_WORK`. Past it the answer is a lower bound ("at least K pairs
cross"), or undecided when none was found; never a clean verdict.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol._native import core, defaults
from meshcol.collision.arrays import as_mesh

__all__ = [
    "MAX_WORK",
    "MAX_KEPT_PAIRS",
    "SelfIntersections",
    "face_pairs_cross",
    "self_intersecting_pairs",
    "self_intersections",
]


def _mesh(vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    v, f = as_mesh(vertices, faces)
    if f.size and not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"faces must be integers, got {f.dtype}")
    if not np.isfinite(v).all():
        raise ValueError("vertices contain NaN or infinite coordinates")
    return v, np.ascontiguousarray(f, dtype=np.int64)


def face_pairs_cross(vertices: Any, faces: Any, pairs: Any, *, threads: int = 0) -> np.ndarray:
    """Whether each given pair of faces of a mesh crosses (see the module notes).

    Parameters
    ----------
    vertices : (n, 3) float
        Any frame.
    faces : (m, 3) int
        Indices into ``vertices``.
    pairs : (k, 2) int
        Indices into ``faces``.
    threads : int
        0 uses every core.

    Returns
    -------
    (k,) bool

    Raises
    ------
    ValueError
        Wrong shapes, non-finite coordinates, or an index out of range (naming the face or
        pair).

    Notes
    -----
    In the C++ core, GIL released, threads over pairs. Non-coplanar pairs: the interval test
    on the line where the planes meet (Moller 1997; Guigue and Devillers 2003) with every
    comparison an orient3d sign; coplanar pairs: no edge line weakly separates them (orient2d
    signs). Degenerate (collinear) faces cross nothing.
    """
    v, f = _mesh(vertices, faces)
    p = np.asarray(pairs)
    if p.size == 0:
        p = p.reshape(0, 2)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"pairs must be (k, 2), got {p.shape}")
    return core.face_pairs_cross(v, f, np.ascontiguousarray(p, dtype=np.int64), threads)


#: The work budget per mesh, in units of one candidate face pair (bounding boxes overlap)
#: decided by the floating-point filters; an orientation past a filter costs
#: ``defaults.self_intersection_slow_cost`` more, one evaluated exactly
#: ``defaults.self_intersection_exact_cost`` more again (``defaults.inc``). Ordinary assets, a
#: cylinder of 20,000 sections included, are decided in full; a pile of faces through one
#: point stops after about a minute on 2 cores (benchmarks/RESULTS.md).
MAX_WORK: int = defaults.self_intersection_max_work
#: At most this many crossing pairs are returned (their count is not capped): the review page
#: draws the faces of these.
MAX_KEPT_PAIRS: int = defaults.self_intersection_max_kept_pairs


@dataclass(frozen=True)
class SelfIntersections:
    """The crossing face pairs of a mesh, and whether every candidate pair was decided.

    Attributes
    ----------
    pairs : (k, 2) int64
        Crossing face pairs ``i < j``, sorted lexicographically; at most ``max_kept_pairs``
        of them (the first the sweep found).
    count : int
        Crossing pairs among the candidates decided (not capped by ``max_kept_pairs``): the
        mesh's exact count when ``complete``, else a lower bound.
    candidates : int
        Candidate pairs decided.
    work : int
        Work units spent on them (see :data:`MAX_WORK`).
    complete : bool
        Every candidate pair was decided (the work budget was not reached).
    """

    pairs: np.ndarray
    count: int
    candidates: int
    work: int
    complete: bool

    @property
    def crossing(self) -> bool | None:
        """True when two faces cross, False when none does, None (undecided) when none was
        found before the budget ran out."""
        if self.count:
            return True
        return False if self.complete else None


def self_intersections(
    vertices: Any,
    faces: Any,
    skip: Any = None,
    *,
    max_work: int | None = None,
    max_kept_pairs: int | None = None,
    threads: int = 0,
) -> SelfIntersections:
    """The pairs of faces of a mesh that cross each other, within a work budget.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    skip : (m,) bool, optional
        Faces to leave out (``meshcol inspect`` skips the faces it reports as degenerate).
    max_work : int, optional
        Work units spent at most (default :data:`MAX_WORK`; negative: no budget).
    max_kept_pairs : int, optional
        Crossing pairs returned at most (default :data:`MAX_KEPT_PAIRS`; negative: all).
    threads : int
        0 uses every core.

    Returns
    -------
    SelfIntersections

    Notes
    -----
    Candidates are the face pairs whose bounding boxes overlap (touching counts), from the
    native sort and sweep; it streams them in blocks to the exact test (:func:`face_pairs_cross`'s
    verdict, with exact shortcuts for faces that share vertices), so the memory held is the
    faces' and the crossing pairs kept, never every candidate (a fan of n faces around one
    vertex has n^2 / 2). The blocks come in an order fixed by the mesh alone and a block's work
    is the same on any thread; past the budget the pass keeps the longest run of whole blocks
    within it, so the result does not depend on ``threads``. The work counts the orientation
    tests the floating-point filters could not decide because they cost up to 30 times a
    filtered one: a budget of candidates alone would let a pile of exactly degenerate faces run
    30 times longer than a fan of as many candidates.
    """
    v, f = _mesh(vertices, faces)
    keep = np.ones(len(f), bool) if skip is None else ~np.asarray(skip, bool).reshape(-1)
    if len(keep) != len(f):
        raise ValueError(f"skip must be ({len(f)},) like faces, got ({len(keep)},)")
    index = np.nonzero(keep)[0]
    if len(index) < 2:
        return SelfIntersections(np.zeros((0, 2), np.int64), 0, 0, 0, True)
    kept = f[index]
    if kept.min() < 0 or kept.max() >= len(v):
        raise ValueError(f"faces index vertices out of range [0, {len(v)})")
    budget = MAX_WORK if max_work is None else int(max_work)
    cap = MAX_KEPT_PAIRS if max_kept_pairs is None else int(max_kept_pairs)
    pairs, count, candidates, work, complete = core.self_intersecting_pairs(
        v,
        np.ascontiguousarray(kept),
        max_work=budget,
        max_kept_pairs=cap,
        threads=threads,
    )
    # index is increasing, so the pairs stay i < j and sorted
    return SelfIntersections(index[pairs], int(count), int(candidates), int(work), bool(complete))


def self_intersecting_pairs(
    vertices: Any, faces: Any, skip: Any = None, *, threads: int = 0
) -> np.ndarray:
    """Pairs of faces of a mesh that cross each other: :func:`self_intersections`' pairs.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    skip : (m,) bool, optional
        Faces to leave out.
    threads : int
        0 uses every core.

    Returns
    -------
    (k, 2) int64
        Face index pairs ``i < j``, sorted lexicographically: every crossing pair when the
        pass was complete and found at most :data:`MAX_KEPT_PAIRS`; otherwise the first
        :data:`MAX_KEPT_PAIRS` found within the budget (:func:`self_intersections` says which).
    """
    return self_intersections(vertices, faces, skip, threads=threads).pairs
