"""The scene sweep behind ``meshcol sweep``: first contact of every pair of moving bodies.

Each body's collider comes from :func:`meshcol.analysis.colliders.build_colliders` (``mesh``
bodies as their triangles); every pair of parts of different bodies, at least one moving, goes
to :func:`meshcol.collision.time_of_impact.time_of_impact_batch`. The motion model, the
statuses and their guarantees are those of :mod:`meshcol.collision.time_of_impact`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.analysis.check_report import name_ranks
from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.pairs import overlapping_pairs
from meshcol.analysis.sweep_report import (
    CSV_COLUMNS,
    MOTION,
    NamePairs,
    SweepHit,
    SweepHits,
    SweepReport,
)
from meshcol.errors import MeshcolError, SceneError
from meshcol.io.column_bodies import body_names
from meshcol.io.robot import RobotOptions
from meshcol.io.scene import as_scene
from meshcol.types import Body, Scene, TimeOfImpactStatus
from meshcol.vocabulary import COLLIDER_KINDS

__all__ = [
    "CSV_COLUMNS",
    "FAIL_ON",
    "MOTION",
    "FirstContacts",
    "SweepHit",
    "SweepHits",
    "SweepReport",
    "first_contacts",
    "sweep",
]

#: ``fail_on`` policies: ``hit`` fails the run on any pair that is not separated.
FAIL_ON = ("hit", "none")

#: Scene-relative default tolerance of :func:`sweep`: this times the scene's bounding diagonal.
RELATIVE_TOLERANCE = 1e-6


def _is_moving(body: Body) -> bool:
    if body.spin is not None and body.spin.rotation is not None and body.spin.angle:
        return True  # a whole number of turns ends where it started, yet moves
    return body.end_pose is not None and not np.array_equal(body.end_pose, body.pose)


def _turns(
    bodies: tuple[Body, ...], start: np.ndarray, end: np.ndarray, offset_parts: bool = False
):
    """Per body, the world rotation vector of its turn and the world pivot it turns about:
    its spin, else the shortest rotation about its local origin. ``(None, None)`` when no body
    spins and no part sits off its body's origin (``offset_parts``): the core then takes the
    shortest rotations itself, about each part's origin, which is then its body's."""
    from meshcol.collision.time_of_impact import shortest_rotation

    if not offset_parts and not any(b.spin is not None for b in bodies):
        return None, None
    rotations = shortest_rotation(start, end).reshape(-1, 3)
    pivots = start[:, :3, 3].copy()
    for k, body in enumerate(bodies):
        if body.spin is not None:
            if body.spin.rotation is not None:
                rotations[k] = body.spin.rotation
            if body.spin.pivot is not None:
                pivots[k] = body.spin.pivot
    return rotations, pivots


def sweep(
    inputs: Any,
    *,
    collider: str = "hull",
    tolerance: float | None = None,
    max_iterations: int | None = None,
    threads: int = 0,
    decompose_options: dict | None = None,
    fail_on: str = "hit",
    robot_options: RobotOptions | None = None,
) -> SweepReport:
    """Continuous collision over a scene: the first contact of every pair of bodies.

    Parameters
    ----------
    inputs : Scene, sequence of Body, or path(s) of a scene manifest / meshes
        Bodies with start poses (``Body.pose``) and end poses (``Body.end_pose``; None for a
        static body).
    collider : {"hull", "decomposed", "mesh"}
        Default collider kind (:mod:`meshcol.analysis.colliders`): the convex hull
        (primitives exactly); the convex decomposition (``UCX_`` parts when given); or the
        triangles, each swept as a polytope (surface contact: a body that starts wholly
        inside another is not found).
    tolerance : float, optional
        Contact distance in world units (default ``1e-6`` x the diagonal of the scene's swept
        bounds).
    max_iterations : int, optional
        Per-pair step cap (see :func:`time_of_impact_batch`).
    threads : int
        Worker threads; 0 uses all cores.
    decompose_options : dict, optional
        Options of :func:`meshcol.analysis.colliders.convex_parts` for ``decomposed`` bodies
        (from the decompose cache when present, else decomposed now).
    fail_on : {"hit", "none"}
        Policy of :attr:`SweepReport.exit_code`: ``hit`` fails on any pair that is not
        separated.
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.load_inputs`).

    Returns
    -------
    SweepReport

    Raises
    ------
    SceneError
        When no body moves (no end pose or velocity anywhere).

    Notes
    -----
    Broad phase: sort and sweep on conservative swept AABBs (:func:`swept_aabbs`), widened by
    the tolerance. Narrow phase: :func:`time_of_impact_batch` on every pair of convex parts of
    different bodies, at least one of them moving; a body pair takes the earliest contact of
    its parts (``FAILED`` when an undecided part pair could come earlier). Static-static
    pairs are skipped: they cannot start touching. ``tunnelled``: a discrete check
    (:func:`meshcol.collision.narrowphase.intersects_batch`) finds no overlap at the start
    poses nor at the end poses.
    """
    scene = _moving_scene(inputs, collider, fail_on, robot_options)
    colliders = build_colliders(
        scene.bodies, collider, mesh_parts="triangles", decompose_options=decompose_options
    )
    motion = _Motion.of(colliders)
    lo, hi, tol = _swept_boxes(colliders, motion, scene, tolerance, threads)
    pairs = _candidates(lo, hi, tol, colliders.part_body, motion.moving)
    contacts = _Contacts.of(colliders, motion, pairs, tol, max_iterations, threads)
    hits, separated, candidate_pairs = _first_contacts(colliders, motion, pairs, contacts, scene)
    return SweepReport(
        scene=scene,
        bodies=tuple(colliders.bodies),
        collider=collider,
        tolerance=tol,
        hits=hits,
        candidate_pairs=candidate_pairs,
        part_pairs=len(pairs),
        moving=tuple(bool(m) for m in motion.moving),
        fail_on=fail_on,
        warnings=colliders.warnings,
        separated=separated,
    )


def _moving_scene(
    inputs: Any, collider: str, fail_on: str, robot_options: RobotOptions | None = None
) -> Scene:
    """The scene of ``inputs`` (a robot read with ``robot_options``), the options checked
    first; SceneError when no body moves."""
    if collider not in COLLIDER_KINDS:
        raise ValueError(f"collider must be one of {', '.join(COLLIDER_KINDS)}, got {collider!r}")
    if fail_on not in FAIL_ON:
        raise ValueError(f"fail_on must be one of {', '.join(FAIL_ON)}, got {fail_on!r}")
    scene = as_scene(inputs, robot_options)
    if not any(b.end_pose is not None for b in scene.bodies):
        raise SceneError(
            "no body has an end pose or a velocity: nothing moves, nothing to sweep", scene.source
        )
    return scene


@dataclass(frozen=True, eq=False)
class _Motion:
    """Every body's and part's motion.

    Attributes
    ----------
    moving : (n_bodies,) bool
    start_body, end_body : (n_bodies, 4, 4) float64
        World poses of the bodies at the start and the end (the start for a static body).
    start, end : (n_parts, 4, 4) float64
        The same of every part.
    body_rotations, body_pivots : (n_bodies, 3) float64 or None
        Each body's turn and pivot (:func:`_turns`); None: the core's shortest rotations.
    rotations, pivots : (n_parts, 3) float64 or None
        The same per part (parts share their body's frame, so its turn and pivot).
    """

    moving: np.ndarray
    start_body: np.ndarray
    end_body: np.ndarray
    start: np.ndarray
    end: np.ndarray
    body_rotations: np.ndarray | None
    body_pivots: np.ndarray | None
    rotations: np.ndarray | None
    pivots: np.ndarray | None

    @classmethod
    def of(cls, colliders: Any) -> _Motion:
        bodies, owner = colliders.bodies, colliders.part_body
        moving = np.array([_is_moving(b) for b in bodies], dtype=bool)
        start_body = np.stack([np.asarray(b.pose, dtype=np.float64) for b in bodies])
        end_body = np.stack(
            [
                np.asarray(b.pose if b.end_pose is None else b.end_pose, dtype=np.float64)
                for b in bodies
            ]
        )
        start, end = colliders.part_poses(), colliders.part_poses(end=True)
        body_rotations, body_pivots = _turns(
            bodies, start_body, end_body, colliders.part_offsets is not None
        )
        return cls(
            moving,
            start_body,
            end_body,
            start,
            end,
            body_rotations,
            body_pivots,
            None if body_rotations is None else body_rotations[owner],
            None if body_pivots is None else body_pivots[owner],
        )


def _swept_boxes(
    colliders: Any, motion: _Motion, scene: Scene, tolerance: float | None, threads: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """World boxes of every part over its whole motion, and the contact tolerance (given, else
    :data:`RELATIVE_TOLERANCE` of the boxes' diagonal); MeshcolError naming the first body
    whose box is not finite."""
    from meshcol.collision.time_of_impact import contact_tolerance, swept_aabbs

    lo, hi = swept_aabbs(
        colliders.shapes,
        motion.start,
        motion.end,
        threads,
        rotations=motion.rotations,
        pivots=motion.pivots,
    )
    finite = np.all(np.isfinite(lo), axis=1) & np.all(np.isfinite(hi), axis=1)
    if tolerance is None:
        diagonal = (
            float(np.linalg.norm(hi[finite].max(axis=0) - lo[finite].min(axis=0)))
            if np.any(finite)
            else 0.0
        )
        tol = RELATIVE_TOLERANCE * diagonal if diagonal > 0.0 else contact_tolerance(None)
    else:
        tol = contact_tolerance(tolerance)
    if not np.all(finite):
        body = colliders.bodies[int(colliders.part_body[np.argmax(~finite)])]
        raise MeshcolError(
            f"body '{body.name}': invalid shape or pose (NaN/inf, empty or not rigid)",
            body.source or scene.source,
        )
    return lo, hi, tol


def _candidates(
    lo: np.ndarray, hi: np.ndarray, tol: float, owner: np.ndarray, moving: np.ndarray
) -> np.ndarray:
    """Part pairs of different bodies whose swept boxes come within ``tol``, at least one of
    them moving (static pairs cannot start touching), each ordered as its bodies (a first in
    the scene): the broad phase of :func:`meshcol.analysis.pairs.overlapping_pairs`."""
    pairs = overlapping_pairs(lo, hi, tol, groups=owner)  # no pair within a body
    if len(pairs):
        pairs = pairs[moving[owner[pairs[:, 0]]] | moving[owner[pairs[:, 1]]]]
    return pairs


@dataclass(frozen=True, eq=False)
class _Contacts:
    """The narrow phase of every candidate part pair: its time of impact, and whether it
    overlaps at the start and at the end poses."""

    toi: Any  # meshcol.collision.time_of_impact.TimeOfImpactBatch
    at_start: np.ndarray
    at_end: np.ndarray

    @classmethod
    def of(
        cls,
        colliders: Any,
        motion: _Motion,
        pairs: np.ndarray,
        tol: float,
        max_iterations: int | None,
        threads: int,
    ) -> _Contacts:
        from meshcol.collision.narrowphase import intersects_batch
        from meshcol.collision.time_of_impact import time_of_impact_batch

        shapes = colliders.shapes
        toi = time_of_impact_batch(
            shapes,
            motion.start,
            motion.end,
            pairs,
            rotations=motion.rotations,
            pivots=motion.pivots,
            tolerance=tol,
            max_iterations=max_iterations,
            threads=threads,
        )
        at_start = intersects_batch(shapes, motion.start, pairs, threads=threads).intersects
        at_end = intersects_batch(shapes, motion.end, pairs, threads=threads).intersects
        return cls(toi, at_start, at_end)


@dataclass(frozen=True, eq=False)
class FirstContacts:
    """The first contact of every body pair of a table of part pairs
    (:func:`first_contacts`), the body pairs in the order the table first names them.

    Attributes
    ----------
    body_pairs : (G, 2) int64
        The body pairs.
    row : (G,) int64
        The part pair (row of the table) that decides each: the first overlapping at the
        start, else the earliest not separated; -1 for a pair that stays separated.
    status : (G,) int64
        :class:`TimeOfImpactStatus` of each pair: that row's, ``FAILED`` for a ``HIT`` when an
        undecided row of the pair could come earlier, ``SEPARATED`` when every row is.
    tunnelled : (G,) bool
        A ``HIT`` none of whose rows overlaps at the start or at the end.
    invalid : int
        The first pair (in that order) with an ``INVALID_INPUT`` row, or -1.
    """

    body_pairs: np.ndarray
    row: np.ndarray
    status: np.ndarray
    tunnelled: np.ndarray
    invalid: int


def first_contacts(
    body_pairs: np.ndarray,
    status: np.ndarray,
    fraction: np.ndarray,
    at_start: np.ndarray,
    at_end: np.ndarray,
) -> FirstContacts:
    """Per body pair, the first contact of its part pairs, by segment operations over the
    rows sorted by body pair (no loop over pairs): overlapping at the start wins (the first
    such row), else the earliest row that is not separated (the first of equal fractions; a
    NaN fraction first, as ``np.argmin``), made ``FAILED`` when that row is a ``HIT`` and a
    ``FAILED`` row of the pair has a smaller fraction.

    Parameters
    ----------
    body_pairs : (P, 2) int
        Each row's bodies.
    status : (P,) int
        Each row's :class:`TimeOfImpactStatus`.
    fraction : (P,) float
        Each row's time of impact.
    at_start, at_end : (P,) bool
        Whether each row overlaps at the start and at the end poses.

    Returns
    -------
    FirstContacts
    """
    S = TimeOfImpactStatus
    count = len(status)
    body_pairs = np.asarray(body_pairs, dtype=np.int64).reshape(-1, 2)
    if count == 0:
        none = np.zeros(0, dtype=np.int64)
        return FirstContacts(body_pairs, none, none, np.zeros(0, dtype=bool), -1)
    key = body_pairs[:, 0] * (int(body_pairs.max()) + 1) + body_pairs[:, 1]
    order = np.argsort(key, kind="stable")  # each pair's rows together, in table order
    new = np.ones(count, dtype=bool)
    new[1:] = key[order[1:]] != key[order[:-1]]
    starts = np.flatnonzero(new)
    seg = np.cumsum(new) - 1
    groups = len(starts)
    st = np.asarray(status, dtype=np.int64)[order]
    fr = np.asarray(fraction, dtype=np.float64)[order]

    best = np.full(groups, -1, dtype=np.int64)  # a sorted position per pair
    live = np.flatnonzero(st != S.SEPARATED)
    nan = np.isnan(fr[live])
    ranked = live[np.lexsort((live, np.where(nan, 0.0, fr[live]), ~nan, seg[live]))]
    found, first = np.unique(seg[ranked], return_index=True)
    best[found] = ranked[first]
    chosen = np.full(groups, int(S.SEPARATED), dtype=np.int64)
    chosen[found] = st[best[found]]
    overlapped = np.flatnonzero(st == S.OVERLAPPED_AT_START)
    found, first = np.unique(seg[overlapped], return_index=True)
    best[found] = overlapped[first]
    chosen[found] = int(S.OVERLAPPED_AT_START)
    failed = np.flatnonzero(st == S.FAILED)
    earliest_failed = np.full(groups, np.inf)
    with np.errstate(invalid="ignore"):  # a NaN fraction stays NaN (as ndarray.min)
        np.minimum.at(earliest_failed, seg[failed], fr[failed])
    hit = chosen == S.HIT
    chosen[hit & (earliest_failed < np.where(best >= 0, fr[best], np.inf))] = int(S.FAILED)
    touching = np.zeros(groups, dtype=bool)
    touching[
        seg[np.asarray(at_start, dtype=bool)[order] | np.asarray(at_end, dtype=bool)[order]]
    ] = True
    invalid_groups = np.unique(seg[st == S.INVALID_INPUT])

    appear = np.argsort(order[starts], kind="stable")  # the pairs as the table names them
    place = np.empty(groups, dtype=np.int64)
    place[appear] = np.arange(groups)
    invalid = int(place[invalid_groups].min()) if len(invalid_groups) else -1
    best = best[appear]
    return FirstContacts(
        body_pairs[order[starts[appear]]],
        np.where(best >= 0, order[np.maximum(best, 0)], -1),
        chosen[appear],
        ((chosen == S.HIT) & ~touching)[appear],
        invalid,
    )


def _first_contacts(
    colliders: Any, motion: _Motion, pairs: np.ndarray, contacts: _Contacts, scene: Scene
) -> tuple[SweepHits, NamePairs, int]:
    """Per candidate body pair, its first contact (:func:`first_contacts`): ``(the hits as
    columns sorted by names, the pairs that stay separated sorted by names, the number of
    candidate body pairs)``; MeshcolError naming the first body pair with an invalid part
    pair."""
    toi = contacts.toi
    owner = colliders.part_body
    body_pairs = owner[pairs] if len(pairs) else np.zeros((0, 2), np.int64)
    first = first_contacts(
        body_pairs, toi.status, toi.time_of_impact, contacts.at_start, contacts.at_end
    )
    names = body_names(colliders.bodies)
    if first.invalid >= 0:
        i, j = first.body_pairs[first.invalid].tolist()
        raise MeshcolError(
            f"bodies '{names[i]}' and '{names[j]}': invalid shape or pose", scene.source
        )
    rank = name_ranks(names)
    hit = first.status != TimeOfImpactStatus.SEPARATED
    apart = first.body_pairs[~hit]
    apart = apart[np.lexsort((rank[apart[:, 1]], rank[apart[:, 0]]))]
    separated = NamePairs(names, apart[:, 0], apart[:, 1])
    touching = np.flatnonzero(hit)
    touching = touching[
        np.lexsort((rank[first.body_pairs[touching, 1]], rank[first.body_pairs[touching, 0]]))
    ]
    hits = _hit_columns(colliders, motion, pairs, toi, scene, first, touching, names)
    return hits, separated, len(first.status)


def _hit_columns(
    colliders: Any,
    motion: _Motion,
    pairs: np.ndarray,
    toi: Any,
    scene: Scene,
    first: FirstContacts,
    index: np.ndarray,
    names: list[str],
) -> SweepHits:
    """The hits ``index`` of ``first`` as columns: their part names, the poses of both
    bodies at the time of impact (one batched interpolation), point, normal, iterations."""
    from meshcol.analysis.sweep_report import codes_of
    from meshcol.collision.time_of_impact import interpolate_pose

    k = len(index)
    a, b = first.body_pairs[index, 0], first.body_pairs[index, 1]
    rows = first.row[index]
    t = toi.time_of_impact[rows]
    labels = colliders.part_label[pairs[rows]] if k else np.zeros((0, 2), np.int64)
    both = np.concatenate([a, b])
    labels = np.concatenate([labels[:, 0], labels[:, 1]])
    part_codes, parts = np.full(2 * k, -1, dtype=np.int64), list[str]()
    if (labels >= 0).any():  # some body of several parts
        part_codes, parts = codes_of(colliders.part_names(both, labels))
    rotations, pivots = motion.body_rotations, motion.body_pivots
    poses = (
        interpolate_pose(
            motion.start_body[both],
            motion.end_body[both],
            np.concatenate([t, t]),
            rotation=None if rotations is None else rotations[both],
            pivot=None if pivots is None else pivots[both],
        )
        if k
        else np.zeros((0, 4, 4))
    )
    return SweepHits(
        names=names,
        body_a=a,
        body_b=b,
        parts=parts,
        part_a=part_codes[:k],
        part_b=part_codes[k:],
        status=first.status[index],
        time_of_impact=t,
        time=None if scene.duration is None else t * float(scene.duration),
        point=toi.point[rows],
        normal=toi.normal[rows],
        pose_a=poses[:k],
        pose_b=poses[k:],
        tunnelled=first.tunnelled[index],
        iterations=np.asarray(toi.iterations[rows], dtype=np.int64),
    )
