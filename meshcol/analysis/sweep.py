"""The scene sweep behind ``meshcol sweep``: first contact of every pair of moving bodies.

Each body's collider comes from :func:`meshcol.analysis.colliders.build_colliders` (``mesh``
bodies as their triangles); every pair of parts of different bodies, at least one moving, goes
to :func:`meshcol.collision.time_of_impact.time_of_impact_batch`. The motion model, the
statuses and their guarantees are those of :mod:`meshcol.collision.time_of_impact`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.pairs import overlapping_pairs
from meshcol.errors import MeshcolError, SceneError
from meshcol.io.report import vector_columns
from meshcol.io.robot import RobotOptions
from meshcol.io.scene import as_scene
from meshcol.types import Body, Scene, TimeOfImpactStatus
from meshcol.vocabulary import COLLIDER_KINDS

__all__ = ["FAIL_ON", "SweepHit", "SweepReport", "sweep"]

#: ``fail_on`` policies: ``hit`` fails the run on any pair that is not separated.
FAIL_ON = ("hit", "none")
#: The motion model, as the report states it.
MOTION = (
    "pivot (local origin unless given) moves linearly; constant angular velocity about it, "
    "the whole angle (shortest way to an end_rotation)"
)
#: Columns of :meth:`SweepReport.to_csv`, one row per pair (poses flattened row-major).
CSV_COLUMNS = (
    "body_a",
    "body_b",
    "part_a",
    "part_b",
    "status",
    "time_of_impact",
    "time",
    *vector_columns("point"),
    *vector_columns("normal"),
    "tunnelled",
    *vector_columns("pose_a", 16),
    *vector_columns("pose_b", 16),
    "iterations",
    "units",
)


#: Scene-relative default tolerance of :func:`sweep`: this times the scene's bounding diagonal.
RELATIVE_TOLERANCE = 1e-6


# ---------------------------------------------------------------------------------------------
# Scene sweep


@dataclass(frozen=True)
class SweepHit:
    """One body pair that is not separated during the motion.

    Attributes
    ----------
    body_a, body_b : str
        Body names (``body_a`` comes first in the scene).
    part_a, part_b : str or None
        The parts of a body of several parts (``Body.parts``) that meet first; None for a
        body of one part.
    status : TimeOfImpactStatus
        ``HIT``, ``OVERLAPPED_AT_START`` or ``FAILED``.
    time_of_impact : float
        Fraction of the motion (for ``FAILED``: the last safe lower bound).
    time : float or None
        ``time_of_impact * duration`` in seconds, when the scene has a duration.
    point : (3,) float64
        World contact point at the time of impact.
    normal : (3,) float64
        World unit normal from a towards b at the time of impact.
    pose_a, pose_b : (4, 4) float64
        Both bodies' world-from-local poses at the time of impact.
    tunnelled : bool
        True for a hit that a discrete check at the start and end poses alone misses (the
        bodies overlap neither at the start nor at the end).
    iterations : int
        Steps of the pair query that decided the pair.
    """

    body_a: str
    body_b: str
    part_a: str | None
    part_b: str | None
    status: TimeOfImpactStatus
    time_of_impact: float
    time: float | None
    point: np.ndarray
    normal: np.ndarray
    pose_a: np.ndarray
    pose_b: np.ndarray
    tunnelled: bool
    iterations: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields (lists for arrays, the status by name), numbers rounded to 12
        significant digits (far below the tolerance) so reports compare across machines."""
        return {
            "body_a": self.body_a,
            "body_b": self.body_b,
            "part_a": self.part_a,
            "part_b": self.part_b,
            "status": self.status.name,
            "time_of_impact": _round(self.time_of_impact),
            "time": _round(self.time),
            "point": _round(self.point),
            "normal": _round(self.normal),
            "pose_a": _round(self.pose_a),
            "pose_b": _round(self.pose_b),
            "tunnelled": self.tunnelled,
            "iterations": self.iterations,
        }


def _round(value: Any) -> Any:
    """Floats (or nested arrays of them) to 12 significant digits, -0.0 as 0.0."""
    if value is None:
        return None
    if isinstance(value, np.ndarray):
        return [_round(v) for v in value.tolist()]
    if isinstance(value, list):
        return [_round(v) for v in value]
    value = float(value)
    return float(f"{value:.12g}") + 0.0 if np.isfinite(value) else value


@dataclass(frozen=True)
class SweepReport:
    """What :func:`sweep` found.

    Attributes
    ----------
    scene : Scene
    bodies : tuple of Body
        The scene's bodies less the ``UCX_`` parts that became colliders.
    collider : str
        Default collider kind (``hull``, ``decomposed`` or ``mesh``).
    tolerance : float
        Contact distance used (world units).
    hits : tuple of SweepHit
        Every body pair that is not ``SEPARATED``, sorted by (body_a, body_b) names.
    candidate_pairs : int
        Body pairs whose swept bounds overlap (the pairs the narrow phase ran on).
    part_pairs : int
        Pairs of convex parts the narrow phase ran on.
    moving : tuple of bool
        Per body of ``bodies``: whether it moves.
    fail_on : str
        ``hit`` (any pair that is not separated fails the run) or ``none``.
    separated : tuple of (str, str)
        The candidate body pairs (moving, swept bounds overlapping) that stay separated, as
        ``(body_a, body_b)`` names.
    """

    scene: Scene
    bodies: tuple[Body, ...]
    collider: str
    tolerance: float
    hits: tuple[SweepHit, ...]
    candidate_pairs: int
    part_pairs: int
    moving: tuple[bool, ...] = field(default=())
    fail_on: str = "hit"
    warnings: tuple[str, ...] = ()
    separated: tuple[tuple[str, str], ...] = ()

    @property
    def failed(self) -> bool:
        """True when any pair hits, overlaps at the start or could not be decided."""
        return bool(self.hits)

    @property
    def exit_code(self) -> int:
        """1 when ``fail_on`` is ``hit`` and a pair is not separated, else 0."""
        return 1 if self.fail_on == "hit" and self.failed else 0

    @property
    def summary(self) -> dict[str, int]:
        """Counts: bodies, moving bodies, candidate and part pairs, hits by status."""
        count = {s: sum(h.status == s for h in self.hits) for s in TimeOfImpactStatus}
        return {
            "bodies": len(self.bodies),
            "moving_bodies": int(sum(self.moving)),
            "candidate_pairs": self.candidate_pairs,
            "part_pairs": self.part_pairs,
            "hits": count[TimeOfImpactStatus.HIT],
            "tunnelled": sum(h.tunnelled for h in self.hits),
            "overlapped_at_start": count[TimeOfImpactStatus.OVERLAPPED_AT_START],
            "failed": count[TimeOfImpactStatus.FAILED],
        }

    @property
    def settings(self) -> dict[str, Any]:
        """The options of the run, as the report states them."""
        return {
            "shape": self.collider,
            "tolerance": float(f"{self.tolerance:.12g}"),
            "fail_on": self.fail_on,
            "motion": MOTION,
            "frame": "world",
        }

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, ``failed`` (the policy verdict), duration,
        bodies, summary and one entry per pair that is not separated."""
        from meshcol.io.report import envelope

        return {
            **envelope("sweep", self.settings, self.scene.units),
            "failed": self.exit_code == 1,
            "warnings": list(self.warnings),
            "duration": self.scene.duration,
            "bodies": [
                {"name": b.name, "source": b.source, "parts": list(b.parts), "moving": m}
                for b, m in zip(self.bodies, self.moving)
            ],
            "summary": self.summary,
            "pairs": [h.to_dict() for h in self.hits],
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per candidate
        pair (``body_a <-> body_b``); a pair that hits, overlaps at the start or cannot be
        decided is a failure under ``--fail-on hit`` (a warning under ``none``), with its
        time of impact, point and normal; the pairs that stay separated pass."""
        from meshcol.io.ci import CiCase, CiSuite, collapse_passed, details, number

        units = self.scene.units
        source = self.scene.source
        fail = self.fail_on == "hit"
        cases = []
        for hit in self.hits:
            if hit.status == TimeOfImpactStatus.HIT:
                message = f"HIT at time of impact {number(hit.time_of_impact)}"
            elif hit.status == TimeOfImpactStatus.OVERLAPPED_AT_START:
                message = "OVERLAPPED_AT_START: the bodies overlap before they move"
            else:
                message = (
                    f"FAILED: undecided, no contact before time of impact "
                    f"{number(hit.time_of_impact)}"
                )
            if hit.time is not None and hit.status != TimeOfImpactStatus.OVERLAPPED_AT_START:
                message += f" (t = {number(hit.time, 's')})"
            if hit.tunnelled:
                message += ", tunnelled (missed at the start and end poses)"
            cases.append(
                CiCase(
                    name=f"{hit.body_a} <-> {hit.body_b}",
                    classname="meshcol.sweep",
                    outcome="failure" if fail else "passed",
                    message=message,
                    file=source,
                    kind=hit.status.name,
                    details=details(
                        [
                            ("part_a", hit.part_a),
                            ("part_b", hit.part_b),
                            ("point", _round(hit.point)),
                            ("normal", _round(hit.normal)),
                            ("iterations", hit.iterations),
                            ("units", units),
                        ]
                    )
                    if fail
                    else "",
                    warn=not fail,
                )
            )
        for a, b in self.separated:
            cases.append(
                CiCase(
                    name=f"{a} <-> {b}",
                    classname="meshcol.sweep",
                    message="separated during the whole motion",
                    file=source,
                )
            )
        cases.sort(key=lambda case: case.name)
        s = self.summary
        return CiSuite(
            "sweep",
            tuple(collapse_passed(cases, "pairs", "meshcol.sweep")),
            self.settings,
            warnings=tuple(self.warnings),
            verdict=f"{s['hits']} hits, {s['overlapped_at_start']} overlapped at start, "
            f"{s['failed']} undecided of {s['candidate_pairs']} candidate pairs",
            units=units,
        )

    def to_csv(self) -> str:
        """One row per pair (:data:`CSV_COLUMNS`): vectors split into ``_x/_y/_z`` columns,
        poses into 16 columns ``_00`` ... ``_33`` (row-major), as every command's CSV."""
        from meshcol.io.report import dumps_csv, split_vectors

        sizes = {"point": 3, "normal": 3, "pose_a": 16, "pose_b": 16}
        units = self.scene.units
        return dumps_csv(
            [split_vectors(dict(h.to_dict(), units=units), sizes) for h in self.hits], CSV_COLUMNS
        )


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
        hits=tuple(hits),
        candidate_pairs=candidate_pairs,
        part_pairs=len(pairs),
        moving=tuple(bool(m) for m in motion.moving),
        fail_on=fail_on,
        warnings=colliders.warnings,
        separated=tuple(sorted(separated)),
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


def _first_contacts(
    colliders: Any, motion: _Motion, pairs: np.ndarray, contacts: _Contacts, scene: Scene
) -> tuple[list[SweepHit], list[tuple[str, str]], int]:
    """Per candidate body pair, its first contact: ``(hits sorted by names, the pairs that
    stay separated, the number of candidate body pairs)``."""
    owner = colliders.part_body
    body_pairs = owner[pairs] if len(pairs) else np.zeros((0, 2), np.int64)
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (i, j) in enumerate(body_pairs.tolist()):
        groups.setdefault((i, j), []).append(k)
    hits = []
    separated: list[tuple[str, str]] = []
    for (i, j), members in groups.items():
        hit = _first_contact(colliders, motion, pairs, contacts, scene, (i, j), members)
        if hit is None:
            separated.append((colliders.bodies[i].name, colliders.bodies[j].name))
        else:
            hits.append(hit)
    hits.sort(key=lambda h: (h.body_a, h.body_b))
    return hits, separated, len(groups)


def _first_contact(
    colliders: Any,
    motion: _Motion,
    pairs: np.ndarray,
    contacts: _Contacts,
    scene: Scene,
    body_pair: tuple[int, int],
    members: Sequence[int],
) -> SweepHit | None:
    """The first contact of body pair ``(i, j)`` from its part pairs ``members`` (None when
    it stays separated): overlapping at the start wins, else the earliest hit, ``FAILED`` when
    an undecided part pair could come earlier."""
    from meshcol.collision.time_of_impact import interpolate_pose

    i, j = body_pair
    bodies, toi = colliders.bodies, contacts.toi
    ks = np.asarray(members)
    status = toi.status[ks]
    if np.any(status == TimeOfImpactStatus.INVALID_INPUT):
        raise MeshcolError(
            f"bodies '{bodies[i].name}' and '{bodies[j].name}': invalid shape or pose",
            scene.source,
        )
    live = ks[status != TimeOfImpactStatus.SEPARATED]
    if len(live) == 0:
        return None
    fraction = toi.time_of_impact
    best = live[np.argmin(fraction[live])]
    best_status = TimeOfImpactStatus(int(toi.status[best]))
    if np.any(status == TimeOfImpactStatus.OVERLAPPED_AT_START):
        best = ks[np.argmax(status == TimeOfImpactStatus.OVERLAPPED_AT_START)]
        best_status = TimeOfImpactStatus.OVERLAPPED_AT_START
    elif best_status == TimeOfImpactStatus.HIT:
        failed = live[toi.status[live] == TimeOfImpactStatus.FAILED]
        if len(failed) and fraction[failed].min() < fraction[best]:
            best_status = TimeOfImpactStatus.FAILED
    t = float(fraction[best])
    part_a, part_b = colliders.part_names(
        [i, j], colliders.part_label[[pairs[best, 0], pairs[best, 1]]]
    )
    rotations, pivots = motion.body_rotations, motion.body_pivots
    poses = interpolate_pose(
        np.stack([motion.start_body[i], motion.start_body[j]]),
        np.stack([motion.end_body[i], motion.end_body[j]]),
        [t, t],
        rotation=None if rotations is None else rotations[[i, j]],
        pivot=None if pivots is None else pivots[[i, j]],
    )
    tunnelled = (
        best_status == TimeOfImpactStatus.HIT
        and not np.any(contacts.at_start[ks])
        and not np.any(contacts.at_end[ks])
    )
    return SweepHit(
        body_a=bodies[i].name,
        body_b=bodies[j].name,
        part_a=part_a,
        part_b=part_b,
        status=best_status,
        time_of_impact=t,
        time=None if scene.duration is None else t * float(scene.duration),
        point=toi.point[best].copy(),
        normal=toi.normal[best].copy(),
        pose_a=poses[0],
        pose_b=poses[1],
        tunnelled=bool(tunnelled),
        iterations=int(toi.iterations[best]),
    )
