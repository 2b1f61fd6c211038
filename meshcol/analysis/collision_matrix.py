"""A robot's self-collision matrix: which link pairs a planner never needs to check.

The classification of MoveIt's setup assistant (``compute_default_collisions.cpp``), every
pair of links with collision geometry getting the first class that applies:

1. ``adjacent``: joined by a joint, or with only links without geometry between them
   (:func:`meshcol.io.kinematics.adjacent_links`, MoveIt's connection graph);
2. ``excluded``: a pair the description itself never collides, with its reason in
   ``excluded_by`` (MJCF: ``<contact><exclude>``, bodies welded together, geoms whose
   ``contype``/``conaffinity`` never match; an ``--srdf`` file's pairs), written to SRDF with
   MoveIt's reason for pairs disabled by hand, ``User``;
3. ``default``: colliding at the default configuration (zero, or the middle of the limits when
   zero is outside them, as MoveIt's ``setToDefaultValues``; ``--joint`` values win; MJCF:
   ``qpos0`` or the first keyframe);
4. ``always``: colliding in at least ``always_fraction`` of the samples (MoveIt: 95 %);
5. ``never``: colliding in none of the samples;
6. ``sometimes``: the others, with their collision rate; these stay checked.

The first four are written as SRDF ``<disable_collisions>`` entries with MoveIt's reasons
(``Adjacent``, ``Default``, ``Always``, ``Never``). Where MoveIt estimates ``always`` in rounds
of 200 samples, here every pair's rate is measured on all the samples (the same threshold on
a larger sample). Configurations are uniform within the joint limits (continuous joints over
``[-pi, pi]``), mimic joints follow their leader, fixed joints stay fixed
(:meth:`meshcol.io.kinematics.JointSpace.sample`, seeded: the same seed gives the same matrix).

Pipeline, arrays end to end (Python loops over chunks of configurations and over joints, never
over pairs): link poses of a chunk of configurations at once (:mod:`meshcol.io.kinematics`);
the links' convex parts (:func:`meshcol.analysis.colliders.build_colliders`, hulls by default)
replicated once per configuration of a chunk in one :class:`~meshcol.collision.shapes.ConvexSet`
so that one native call measures every (configuration, part pair) candidate; world boxes of
every part of every configuration (each part's local box, moved: Arvo 1990); the broad phase on
link boxes then part boxes, vectorised over (configuration, pair) (the batched form of the
broad phase ``check`` uses, :func:`meshcol.analysis.pairs.broad_phase_batch`); the boolean GJK
of the survivors in one batched call (:func:`meshcol.collision.narrowphase.intersects_batch`;
then the GJK distance of the pairs found apart: within the padding and the contact
tolerance counts as colliding, as touching does for ``check``).

Stages: ``_robot_links`` (the robot and its links' colliders) -> ``_sample`` (the default
configuration and the samples, chunk by chunk: poses, boxes, broad phase, narrow phase) ->
``_classify`` (MoveIt's class of each link pair) -> ``_matrix_report``.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.analysis.check_policy import CheckOptions
from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.pairs import NO_ANSWER, PartPairIndex, broad_phase_batch
from meshcol.analysis.rules import robot_findings
from meshcol.errors import SceneError
from meshcol.io.paths import display_path
from meshcol.io.robot import RobotOptions
from meshcol.vocabulary import MATRIX_COLLIDERS

__all__ = [
    "MATRIX_CLASSES",
    "SRDF_REASON",
    "MatrixOptions",
    "CollisionMatrixReport",
    "collision_matrix",
]

#: Classes of a link pair, in precedence order.
MATRIX_CLASSES = ("adjacent", "excluded", "default", "always", "never", "sometimes")
#: The SRDF reason written for each class (``sometimes`` pairs are not written).
SRDF_REASON = {
    "adjacent": "Adjacent",
    "excluded": "User",
    "default": "Default",
    "always": "Always",
    "never": "Never",
}
#: Columns of :meth:`CollisionMatrixReport.to_csv`, one row per link pair.
CSV_COLUMNS = [
    "link_a",
    "link_b",
    "class",
    "reason",
    "collisions",
    "rate",
    "adjacent",
    "excluded_by",
    "default_collision",
    "failed_queries",
]
#: Vertices of the parts replicated for one native call (parts x configurations per call):
#: large enough that a call measures a few hundred configurations of a typical arm, small enough
#: that replicating them (memory bound) stays a small share of the run.
BATCH_VERTICES = 1 << 18
#: Configurations per native call, at most.
MAX_BATCH = 1024
#: Link pairs x configurations of one call's broad phase (its box tests are arrays of that
#: many rows): 2 million, about 50 MB an array, however many links (a chain of 500 links
#: asked 1,024 configurations x 124,750 pairs, 7 GB, before this bound).
BATCH_PAIRS = 1 << 21


@dataclass(frozen=True)
class MatrixOptions:
    """Settings of one collision-matrix run.

    Attributes
    ----------
    samples : int
        Random configurations (MoveIt's setup assistant: 10,000 by default).
    seed : int
        Seed of the configurations.
    collider : str
        ``hull`` (each collision element's convex hull; primitives exact) or ``decomposed``.
    padding : float
        Metres: links closer than this count as colliding (0: touching or overlapping).
    tolerance : float
        Metres: the contact tolerance, as ``check``'s (``CheckOptions.tolerance``): links
        within ``padding + tolerance`` of each other count as colliding, so that a pair
        touching at 1e-11 m is in contact here as it is for ``check`` and pybullet.
    always_fraction : float
        Pairs colliding in at least this fraction of the samples are ``always`` (MoveIt: 0.95).
    threads : int
        Threads for the native queries; 0 means all cores.
    batch : int or None
        Configurations per native call; None: as many as :data:`BATCH_VERTICES` and
        :data:`BATCH_PAIRS` allow (at most :data:`MAX_BATCH`). The results never depend on
        it.
    decompose_options : dict
        Options of the convex decomposition for ``decomposed``.
    """

    samples: int = 10_000
    seed: int = 0
    collider: str = "hull"
    padding: float = 0.0
    tolerance: float = CheckOptions.tolerance
    always_fraction: float = 0.95
    threads: int = 0
    batch: int | None = None
    decompose_options: dict = field(default_factory=dict)

    def validate(self) -> None:
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 1:
            raise ValueError(f"samples must be an integer >= 1, got {self.samples!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")
        if self.collider not in MATRIX_COLLIDERS:
            raise ValueError(
                f"collider must be one of {', '.join(MATRIX_COLLIDERS)}, got {self.collider!r}"
            )
        if not (math.isfinite(self.padding) and self.padding >= 0):
            raise ValueError(f"padding must be a finite number >= 0, got {self.padding!r}")
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0):
            raise ValueError(f"tolerance must be a finite number >= 0, got {self.tolerance!r}")
        if not (0 < self.always_fraction <= 1):
            raise ValueError(f"always_fraction must be in (0, 1], got {self.always_fraction!r}")
        if self.batch is not None and self.batch < 1:
            raise ValueError(f"batch must be >= 1, got {self.batch!r}")


@dataclass(frozen=True)
class CollisionMatrixReport:
    """The collision matrix of a robot: everything the JSON report and the SRDF hold.

    Attributes
    ----------
    robot : str
        The robot's name (the SRDF's ``<robot name>``).
    pairs : list of dict
        Every pair of links with collision geometry, sorted by (link_a, link_b), link_a <
        link_b: ``class``, ``reason`` (the SRDF reason, None for ``sometimes``),
        ``collisions`` (samples in collision), ``rate`` (collisions / samples), ``adjacent``,
        ``excluded_by`` (the description's reason for an ``excluded`` pair, else None),
        ``default_collision``, ``failed_queries``; adjacent and excluded pairs are never
        measured (their collisions, rate and default_collision are None), as MoveIt never
        checks disabled pairs.
    joints : list of dict
        The sampled joints: name, lower, upper, default.
    summary : dict
        Counts per class, timings (``seconds_per_configuration``), samples and seed.
    settings : dict
        The options used.
    warnings : list of str
        Joints held at their default, colliders that could not be built as asked.
    findings : list of dict
        Findings of registered rules (:mod:`meshcol.analysis.rules`): MC506 for a robot
        with no collision geometry (no pairs, an SRDF that disables none).
    """

    robot: str
    pairs: list[dict]
    joints: list[dict]
    summary: dict
    settings: dict
    warnings: list[str] = field(default_factory=list)
    findings: list[dict] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        """0: a matrix has no policy to fail."""
        return 0

    def disabled_pairs(self) -> list[tuple[str, str, str]]:
        """``(link1, link2, reason)`` of every pair the SRDF disables, sorted by links."""
        return [
            (p["link_a"], p["link_b"], p["reason"]) for p in self.pairs if p["reason"] is not None
        ]

    def to_dict(self) -> dict:
        """The JSON report: the common envelope, robot, joints, summary, pairs."""
        from meshcol.io.report import envelope

        return {
            **envelope("collision-matrix", self.settings, "m"),
            "robot": self.robot,
            "warnings": self.warnings,
            "findings": self.findings,
            "joints": self.joints,
            "summary": self.summary,
            "pairs": self.pairs,
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def to_csv(self) -> str:
        """One row per pair (:data:`CSV_COLUMNS`)."""
        from meshcol.io.report import dumps_csv

        return dumps_csv(self.pairs, CSV_COLUMNS)

    def to_srdf(self) -> str:
        """The SRDF text: one ``<disable_collisions>`` per disabled pair. A robot with no
        collision geometry (MC506) gets its ``<robot name>`` alone: MoveIt's parser (srdfdom,
        ``Model::initXml``) needs only that root and its name, every child being optional."""
        from meshcol.io.srdf import srdf_text

        s = self.summary
        comment = (
            f"meshcol collision-matrix: {s['samples']} samples, seed {s['seed']}, "
            f"{self.settings['collider']} colliders, padding {self.settings['padding']:g} m"
        )
        return srdf_text(self.robot, self.disabled_pairs(), comment)


@dataclass(frozen=True, eq=False)
class _RobotLinks:
    """A robot's links with collision geometry, ready to sample.

    Attributes
    ----------
    source : str
    scene : Scene
        At the loaded configuration.
    kinematics : UrdfKinematics or MjcfKinematics
    colliders : Colliders
        One body per link with geometry.
    body_link : (n_bodies,) int64
        Each body's link (index into ``kinematics.links``).
    offsets : (n_bodies, 4, 4) float64
        Each body's pose in its link's frame.
    adjacent : set of (str, str)
        Adjacent link pairs (sorted names), never measured.
    excluded : dict of (str, str) to str
        The other pairs the description excludes (sorted names -> reason), never measured.
    given_joints : mapping
        Joint values given by the robot options (``--joint``).
    """

    source: str
    scene: Any
    kinematics: Any
    colliders: Any
    body_link: np.ndarray
    offsets: np.ndarray
    adjacent: set[tuple[str, str]]
    excluded: dict[tuple[str, str], str]
    given_joints: Any

    @property
    def names(self) -> list[str]:
        return [b.name for b in self.colliders.bodies]


def _robot_links(
    source: str,
    options: MatrixOptions,
    report: Callable[[str], None],
    robot_options: RobotOptions | None = None,
) -> _RobotLinks:
    """Load the robot (read with ``robot_options``) and build its links' colliders (hulls, or
    the decomposition)."""
    from meshcol.io.inputs import is_robot_file
    from meshcol.io.kinematics import adjacent_links
    from meshcol.io.robot import load_robot_model

    if os.path.isfile(source) and not is_robot_file(source):
        raise SceneError(
            "not a robot description (expected .urdf, .mjcf, or .xml with <robot> or <mujoco>)",
            source,
        )
    robot_options = RobotOptions() if robot_options is None else robot_options
    model = load_robot_model(source, robot_options)
    given = robot_options.joints
    scene, kinematics = model.scene, model.kinematics
    colliders = build_colliders(
        scene.bodies,
        "decomposed" if options.collider == "decomposed" else "hull",
        mesh_parts="hull",
        decompose_options=options.decompose_options,
        progress=report,
    )
    bodies = colliders.bodies
    link_index = {name: i for i, name in enumerate(kinematics.links)}
    stray = [b.name for b in bodies if b.name not in link_index]
    if stray:
        raise SceneError(f"body {stray[0]!r} is no link of the robot (a UCX_ link name?)", source)
    body_link = np.array([link_index[b.name] for b in bodies], dtype=np.int64)
    loaded = kinematics.link_poses(kinematics.loaded[None])[0]
    poses = np.stack([b.pose for b in bodies]) if bodies else np.zeros((0, 4, 4))
    offsets = np.linalg.inv(loaded[body_link]) @ poses  # none: no link has geometry (MC506)
    names = [b.name for b in bodies]
    adjacent = set(adjacent_links(kinematics.links, kinematics.edges, names))
    excluded = {
        (min(a, b), max(a, b)): reason
        for a, b, reason in scene.excluded_pairs
        if reason != "adjacent" and (min(a, b), max(a, b)) not in adjacent
    }
    return _RobotLinks(
        source, scene, kinematics, colliders, body_link, offsets, adjacent, excluded, given
    )


class _Sampler:
    """Which (configuration, link pair) collide: link poses, part boxes, the shared batched
    broad phase (:func:`meshcol.analysis.pairs.broad_phase_batch`), the narrow phase."""

    def __init__(
        self,
        kinematics: Any,
        colliders: Any,
        body_link: np.ndarray,
        offsets: np.ndarray,
        padding: float,
        batch: int,
        threads: int,
        skip: np.ndarray | None = None,
        part_filter: Any = None,
    ) -> None:
        self.kinematics = kinematics
        self.colliders = colliders
        self.body_link = body_link
        self.offsets = offsets
        self.padding = padding
        self.threads = threads
        self.batch = batch
        n = len(colliders.bodies)
        self.h = len(colliders.part_body)
        i, j = np.triu_indices(n, k=1)
        self.pairs = np.stack([i, j], axis=1).astype(np.int64)
        # pairs never measured (adjacent links: never checked, as MoveIt's setup assistant)
        self.skip = np.zeros(len(self.pairs), bool) if skip is None else np.asarray(skip, bool)
        # Every part pair of every link pair, grouped by link pair (computed once); an MJCF's
        # only those its geom filters let collide (Scene.part_filter)
        self.index = PartPairIndex.of(
            self.pairs, colliders.body_part_offsets, colliders, part_filter
        )
        self.tiled = colliders.shapes.take(np.tile(np.arange(self.h), batch))
        local_lo, local_hi = colliders.shapes.aabbs(None)
        self.local_centre = 0.5 * (local_lo + local_hi)
        self.local_half = 0.5 * (local_hi - local_lo)
        self.narrow_pairs = 0
        self.failed = np.zeros(len(self.pairs), dtype=np.int64)
        self.kinematics_seconds = 0.0
        self.collision_seconds = 0.0

    def collide(self, configurations: np.ndarray) -> np.ndarray:
        """(n, pairs) bool: link pair k collides at configuration c."""
        out = np.zeros((len(configurations), len(self.pairs)), dtype=bool)
        for start in range(0, len(configurations), self.batch):
            chunk = configurations[start : start + self.batch]
            out[start : start + len(chunk)] = self._chunk(chunk)
        return out

    def _chunk(self, q: np.ndarray) -> np.ndarray:
        began = time.perf_counter()
        poses = self._part_poses(q)
        middle = time.perf_counter()
        self.kinematics_seconds += middle - began
        lo, hi = self._part_boxes(poses, len(q))
        configuration, pair, part_pairs = broad_phase_batch(
            lo, hi, self.colliders.body_part_offsets, self.index, self.skip
        )
        collides = self._narrow_phase(poses, configuration, pair, part_pairs, len(q))
        self.collision_seconds += time.perf_counter() - middle
        return collides

    def _part_poses(self, q: np.ndarray) -> np.ndarray:
        """(batch * parts, 4, 4): every part's world pose at each configuration of ``q``, then
        identities up to the batch (the tiled shapes' size)."""
        colliders = self.colliders
        link_poses = self.kinematics.link_poses(q)  # (c, links, 4, 4)
        body_poses = link_poses[:, self.body_link] @ self.offsets  # (c, bodies, 4, 4)
        poses = np.empty((self.batch * self.h, 4, 4))
        poses[:] = np.eye(4)
        part_poses = body_poses[:, colliders.part_body]
        if colliders.part_offsets is not None:  # fit primitives sit off their link's origin
            part_poses = part_poses @ colliders.part_offsets
        poses[: len(q) * self.h] = part_poses.reshape(-1, 4, 4)
        return poses

    def _part_boxes(self, poses: np.ndarray, c: int) -> tuple[np.ndarray, np.ndarray]:
        """(c, parts, 3) world boxes of the parts' local boxes, grown by half the padding
        (Arvo 1990: centre moved, half extents by |R|): never smaller than the parts' own
        world boxes, and numpy over every configuration."""
        h = self.h
        rotation = poses[: c * h, :3, :3]
        centre = np.einsum("kij,kj->ki", rotation, self.local_centre[np.tile(np.arange(h), c)])
        centre += poses[: c * h, :3, 3]
        half = np.einsum("kij,kj->ki", np.abs(rotation), self.local_half[np.tile(np.arange(h), c)])
        half += 0.5 * self.padding
        return (centre - half).reshape(c, h, 3), (centre + half).reshape(c, h, 3)

    def _narrow_phase(
        self,
        poses: np.ndarray,
        configuration: np.ndarray,
        pair: np.ndarray,
        part_pairs: np.ndarray,
        c: int,
    ) -> np.ndarray:
        """(c, pairs) bool from the part pairs the broad phase kept: boolean GJK, then the GJK
        distance of the pairs it finds apart (within the padding and contact tolerance: a
        hit); a failed query counts in ``failed``, never as a hit."""
        from meshcol.collision.narrowphase import distance_batch, intersects_batch

        h = self.h
        narrow = np.stack(
            [configuration * h + part_pairs[:, 0], configuration * h + part_pairs[:, 1]], axis=1
        )
        self.narrow_pairs += len(narrow)
        checked = intersects_batch(self.tiled, poses, narrow, threads=self.threads)
        hit = np.asarray(checked.intersects, dtype=bool).copy()
        bad = np.isin(np.asarray(checked.status), NO_ANSWER)
        apart = np.flatnonzero(~hit & ~bad)
        if self.padding > 0 and len(apart):
            measured = distance_batch(self.tiled, poses, narrow[apart], threads=self.threads)
            near = np.asarray(measured.distance) <= self.padding
            failed = np.isin(np.asarray(measured.status), NO_ANSWER)
            hit[apart] = near & ~failed
            bad[apart] = failed
        np.add.at(self.failed, pair[bad], 1)
        collides = np.zeros((c, len(self.pairs)), dtype=bool)
        collides[configuration[hit & ~bad], pair[hit & ~bad]] = True
        return collides


def collision_matrix(
    robot: str | os.PathLike[str],
    *,
    progress: Callable[[str], None] | None = None,
    robot_options: RobotOptions | None = None,
    **options: Any,
) -> CollisionMatrixReport:
    """Sample a robot's configurations and classify every pair of links.

    Parameters
    ----------
    robot : path
        A URDF or MJCF file.
    progress : callable, optional
        Receives one-line progress messages (``collision-matrix: 3000/10000 configurations``).
    robot_options : RobotOptions, optional
        How the robot is read: its joint values (the default configuration), packages and
        keyframe (:func:`meshcol.io.robot.load_robot_model`).
    **options
        Fields of :class:`MatrixOptions`.

    Returns
    -------
    CollisionMatrixReport

    Raises
    ------
    SceneError, InputFileError
        The file is not a robot description, or is one meshcol cannot read (one line).

    Notes
    -----
    As MoveIt's setup assistant (Coleman 2012, ``compute_default_collisions.cpp``), with every
    pair's rate measured on all the samples. Narrow phase: boolean GJK (Gilbert et al. 1988;
    van den Bergen 2003) on the links' convex parts, batched over every candidate.
    """
    opts = MatrixOptions(**options)
    opts.validate()
    report = progress or (lambda message: None)
    began = time.perf_counter()
    links = _robot_links(os.fspath(robot), opts, report, robot_options)
    load_seconds = time.perf_counter() - began
    sampler = _sampler(links, opts)
    at_default, counts = _sample(sampler, links.kinematics.space, opts, report)
    seconds = time.perf_counter() - began
    pairs = _classify(links, sampler, counts, at_default, opts)
    return _matrix_report(links, sampler, pairs, opts, seconds, load_seconds)


def _sampler(links: _RobotLinks, options: MatrixOptions) -> _Sampler:
    """The sampler of every link pair but the adjacent and excluded ones."""
    names = links.names
    i, j = np.triu_indices(len(names), k=1)
    skip = np.array(
        [
            (pair := tuple(sorted((names[a], names[b])))) in links.adjacent
            or pair in links.excluded
            for a, b in zip(i, j)
        ],
        dtype=bool,
    )
    colliders = links.colliders
    return _Sampler(
        links.kinematics,
        colliders,
        links.body_link,
        links.offsets,
        options.padding + options.tolerance,
        _batch(options, len(colliders.shapes.vertices), len(i)),
        options.threads,
        skip,
        links.scene.part_filter,
    )


def _sample(
    sampler: _Sampler, space: Any, options: MatrixOptions, report: Callable[[str], None]
) -> tuple[np.ndarray, np.ndarray]:
    """Collisions at the default configuration, and per link pair the number of sampled
    configurations in collision."""
    at_default = sampler.collide(space.default[None])[0]
    configurations = space.sample(options.samples, options.seed)
    counts = np.zeros(len(sampler.pairs), dtype=np.int64)
    step = max(sampler.batch, 1)
    for start in range(0, options.samples, step):
        counts += sampler.collide(configurations[start : start + step]).sum(axis=0)
        done = min(start + step, options.samples)
        report(f"collision-matrix: {done}/{options.samples} configurations")
    return at_default, counts


def _pair_class(
    adjacent: bool, excluded: bool, default: bool, rate: float, hits: int, always: float
) -> str:
    """MoveIt's class of a link pair: the first that applies."""
    if adjacent:
        return "adjacent"
    if excluded:
        return "excluded"
    if default:
        return "default"
    if rate >= always:
        return "always"
    if hits == 0:
        return "never"
    return "sometimes"


def _classify(
    links: _RobotLinks,
    sampler: _Sampler,
    counts: np.ndarray,
    at_default: np.ndarray,
    options: MatrixOptions,
) -> list[dict]:
    """One row per link pair, sorted by (link_a, link_b): its class, SRDF reason, rate."""
    names = links.names
    rate = counts / options.samples
    pairs = []
    for (i, j), hits, r, default, failed in zip(
        sampler.pairs.tolist(),
        counts.tolist(),
        rate.tolist(),
        at_default.tolist(),
        sampler.failed.tolist(),
    ):
        a, b = sorted((names[i], names[j]))
        is_adjacent = (a, b) in links.adjacent
        excluded_by = None if is_adjacent else links.excluded.get((a, b))
        unmeasured = is_adjacent or excluded_by is not None
        kind = _pair_class(
            is_adjacent, excluded_by is not None, default, r, hits, options.always_fraction
        )
        pairs.append(
            {
                "link_a": a,
                "link_b": b,
                "class": kind,
                "reason": SRDF_REASON.get(kind),
                "collisions": None if unmeasured else hits,
                "rate": None if unmeasured else r,
                "adjacent": is_adjacent,
                "excluded_by": excluded_by,
                "default_collision": None if unmeasured else bool(default),
                "failed_queries": failed,
            }
        )
    pairs.sort(key=lambda p: (p["link_a"], p["link_b"]))
    return pairs


def _matrix_report(
    links: _RobotLinks,
    sampler: _Sampler,
    pairs: list[dict],
    options: MatrixOptions,
    seconds: float,
    load_seconds: float,
) -> CollisionMatrixReport:
    """The report: joints, summary, settings and warnings around the classified pairs."""
    space = links.kinematics.space
    joints = [
        {"name": n, "lower": lo, "upper": hi, "default": d}
        for n, lo, hi, d in zip(
            space.names, space.lower.tolist(), space.upper.tolist(), space.default.tolist()
        )
    ]
    by_class = {k: sum(p["class"] == k for p in pairs) for k in MATRIX_CLASSES}
    sampling = sampler.kinematics_seconds + sampler.collision_seconds
    summary = {
        "links": len(links.colliders.bodies),
        "link_pairs": len(pairs),
        "pairs_by_class": by_class,
        "disabled_pairs": len(pairs) - by_class["sometimes"],
        "samples": options.samples,
        "seed": options.seed,
        "sampled_joints": len(space),
        "convex_parts": len(links.colliders.part_body),
        "narrow_phase_pairs": sampler.narrow_pairs,
        "failed_queries": int(sampler.failed.sum()),
        "seconds": round(seconds, 6),
        "load_seconds": round(load_seconds, 6),
        "kinematics_seconds": round(sampler.kinematics_seconds, 6),
        "collision_seconds": round(sampler.collision_seconds, 6),
        "seconds_per_configuration": sampling / (options.samples + 1),
    }
    settings = {
        "samples": options.samples,
        "seed": options.seed,
        "collider": options.collider,
        "padding": options.padding,
        "tolerance": options.tolerance,
        "always_fraction": options.always_fraction,
        "threads": options.threads,
        "inputs": [display_path(links.source, posix=True)],
    }
    robot = links.kinematics.name or Path(links.source).stem
    findings = [f.to_dict() for f in robot_findings(links.scene)]
    return CollisionMatrixReport(
        robot, pairs, joints, summary, settings, _warnings(links), findings
    )


def _warnings(links: _RobotLinks) -> list[str]:
    """The scene's warnings but its joint-limit notes (the scene's pose is not the default
    configuration here), joints whose default is not zero, colliders not built as asked,
    joints held."""
    space = links.kinematics.space
    warnings = [w for w in links.scene.warnings if "outside its limits" not in w]
    warnings += [
        f"joint {n!r}: zero is outside its limits [{lo:g}, {hi:g}]; the default configuration "
        f"has it at the middle, {d:g} (give --joint {n}=VALUE to choose)"
        for n, lo, hi, d in zip(space.names, space.lower, space.upper, space.default)
        if not lo <= 0.0 <= hi and n not in links.given_joints
    ]
    warnings += [*links.colliders.warnings, *links.kinematics.held]
    return warnings


def _batch(options: MatrixOptions, vertices: int, pairs: int) -> int:
    """Configurations per native call (see :attr:`MatrixOptions.batch`)."""
    if options.batch is not None:
        return min(options.batch, options.samples)
    most = min(MAX_BATCH, BATCH_VERTICES // max(vertices, 1), BATCH_PAIRS // max(pairs, 1))
    return max(1, min(options.samples, most))
