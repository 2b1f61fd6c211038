"""A robot's self-collision matrix: which link pairs a planner never needs to check.

The classification of MoveIt's setup assistant (``compute_default_collisions.cpp``), every
pair of links with collision geometry getting the first class that applies:

1. ``adjacent``: joined by a joint, or with only links without geometry between them
   (:func:`meshcol.io.kinematics.adjacent_links`, MoveIt's connection graph);
2. ``default``: colliding at the default configuration (zero, or the middle of the limits when
   zero is outside them, as MoveIt's ``setToDefaultValues``; ``--joint`` values win; MJCF:
   ``qpos0`` or the first keyframe);
3. ``always``: colliding in at least ``always_fraction`` of the samples (MoveIt: 95 %);
4. ``never``: colliding in none of the samples;
5. ``sometimes``: the others, with their collision rate; these stay checked.

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
link boxes then part boxes, vectorised over (configuration, pair); the boolean GJK of the
survivors in one batched call (:func:`meshcol.collision.narrowphase.intersects_batch`; with a
padding, the GJK distance).
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

from meshcol.analysis.check import _cartesian_part_pairs
from meshcol.analysis.colliders import build_colliders
from meshcol.errors import SceneError
from meshcol.io.paths import display_path
from meshcol.io.robot import RobotOptions
from meshcol.types import Status
from meshcol.vocabulary import MATRIX_COLLIDERS

__all__ = [
    "MATRIX_CLASSES",
    "SRDF_REASON",
    "MatrixOptions",
    "CollisionMatrixReport",
    "collision_matrix",
]

#: Classes of a link pair, in precedence order.
MATRIX_CLASSES = ("adjacent", "default", "always", "never", "sometimes")
#: The SRDF reason written for each class (``sometimes`` pairs are not written).
SRDF_REASON = {"adjacent": "Adjacent", "default": "Default", "always": "Always", "never": "Never"}
#: Columns of :meth:`CollisionMatrixReport.to_csv`, one row per link pair.
CSV_COLUMNS = [
    "link_a",
    "link_b",
    "class",
    "reason",
    "collisions",
    "rate",
    "adjacent",
    "default_collision",
    "failed_queries",
]
#: Vertices of the parts replicated for one native call (parts x configurations per call):
#: large enough that a call measures a few hundred configurations of a typical arm, small enough
#: that replicating them (memory bound) stays a small share of the run.
BATCH_VERTICES = 1 << 18
#: Configurations per native call, at most.
MAX_BATCH = 1024


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
    always_fraction : float
        Pairs colliding in at least this fraction of the samples are ``always`` (MoveIt: 0.95).
    threads : int
        Threads for the native queries; 0 means all cores.
    batch : int or None
        Configurations per native call; None: as many as :data:`BATCH_VERTICES` allows (at
        most :data:`MAX_BATCH`). The results never depend on it.
    decompose_options : dict
        Options of the convex decomposition for ``decomposed``.
    """

    samples: int = 10_000
    seed: int = 0
    collider: str = "hull"
    padding: float = 0.0
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
        ``default_collision``, ``failed_queries``; adjacent pairs are never measured (their
        collisions, rate and default_collision are None), as MoveIt never checks them.
    joints : list of dict
        The sampled joints: name, lower, upper, default.
    summary : dict
        Counts per class, timings (``seconds_per_configuration``), samples and seed.
    settings : dict
        The options used.
    warnings : list of str
        Joints held at their default, colliders that could not be built as asked.
    """

    robot: str
    pairs: list[dict]
    joints: list[dict]
    summary: dict
    settings: dict
    warnings: list[str] = field(default_factory=list)

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
        """The SRDF text: one ``<disable_collisions>`` per disabled pair."""
        from meshcol.io.srdf import srdf_text

        s = self.summary
        comment = (
            f"meshcol collision-matrix: {s['samples']} samples, seed {s['seed']}, "
            f"{self.settings['collider']} colliders, padding {self.settings['padding']:g} m"
        )
        return srdf_text(self.robot, self.disabled_pairs(), comment)


class _Sampler:
    """Which (configuration, link pair) collide: the batched broad and narrow phase."""

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
        # Every part pair of every link pair, grouped by link pair (computed once).
        self.part_pairs = _cartesian_part_pairs(self.pairs, colliders.body_part_offsets)
        part_of = colliders.body_part_offsets
        sizes = (part_of[i + 1] - part_of[i]) * (part_of[j + 1] - part_of[j])
        self.pair_sizes = sizes.astype(np.int64)
        self.pair_start = np.zeros(len(sizes), dtype=np.int64)
        np.cumsum(sizes[:-1], out=self.pair_start[1:])
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
        from meshcol.collision.narrowphase import distance_batch, intersects_batch

        began = time.perf_counter()
        c, h, colliders = len(q), self.h, self.colliders
        link_poses = self.kinematics.link_poses(q)  # (c, links, 4, 4)
        body_poses = link_poses[:, self.body_link] @ self.offsets  # (c, bodies, 4, 4)
        poses = np.empty((self.batch * h, 4, 4))
        poses[:] = np.eye(4)
        part_poses = body_poses[:, colliders.part_body]
        if colliders.part_offsets is not None:  # fit primitives sit off their link's origin
            part_poses = part_poses @ colliders.part_offsets
        poses[: c * h] = part_poses.reshape(-1, 4, 4)
        middle = time.perf_counter()
        self.kinematics_seconds += middle - began

        # World boxes of the parts' local boxes (Arvo 1990: centre moved, half extents by |R|):
        # never smaller than the parts' own world boxes, and numpy over every configuration.
        rotation = poses[: c * h, :3, :3]
        centre = np.einsum("kij,kj->ki", rotation, self.local_centre[np.tile(np.arange(h), c)])
        centre += poses[: c * h, :3, 3]
        half = np.einsum("kij,kj->ki", np.abs(rotation), self.local_half[np.tile(np.arange(h), c)])
        half += 0.5 * self.padding
        lo = (centre - half).reshape(c, h, 3)
        hi = (centre + half).reshape(c, h, 3)
        starts = colliders.body_part_offsets[:-1]
        body_lo = np.minimum.reduceat(lo, starts, axis=1)
        body_hi = np.maximum.reduceat(hi, starts, axis=1)
        a, b = self.pairs[:, 0], self.pairs[:, 1]
        # NaN boxes (an invalid pose or shape) compare False: the pair goes to the narrow
        # phase, which gives it its status.
        apart = np.any((body_lo[:, a] > body_hi[:, b]) | (body_lo[:, b] > body_hi[:, a]), axis=2)
        apart |= self.skip
        config, pair = np.nonzero(~apart)
        # The part pairs of the overlapping (configuration, link pair) candidates.
        sizes = self.pair_sizes[pair]
        owner = np.repeat(np.arange(len(pair)), sizes)
        first = np.zeros(len(sizes), dtype=np.int64)
        np.cumsum(sizes[:-1], out=first[1:])
        rows = self.pair_start[pair][owner] + np.arange(int(sizes.sum())) - first[owner]
        pa, pb = self.part_pairs[rows, 0], self.part_pairs[rows, 1]
        cfg = config[owner]
        keep = ~np.any((lo[cfg, pa] > hi[cfg, pb]) | (lo[cfg, pb] > hi[cfg, pa]), axis=1)
        cfg, pa, pb, owner = cfg[keep], pa[keep], pb[keep], owner[keep]
        narrow = np.stack([cfg * h + pa, cfg * h + pb], axis=1)
        self.narrow_pairs += len(narrow)
        if self.padding > 0:
            result = distance_batch(self.tiled, poses, narrow, threads=self.threads)
            hit = result.distance <= self.padding
        else:
            checked = intersects_batch(self.tiled, poses, narrow, threads=self.threads)
            hit = checked.intersects
        status = np.asarray(checked.status if self.padding == 0 else result.status)
        bad = np.isin(status, (int(Status.INVALID_INPUT), int(Status.OUT_OF_RANGE)))
        np.add.at(self.failed, pair[owner[bad]], 1)
        collides = np.zeros((c, len(self.pairs)), dtype=bool)
        collides[config[owner[hit & ~bad]], pair[owner[hit & ~bad]]] = True
        self.collision_seconds += time.perf_counter() - middle
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
    from meshcol.io.inputs import is_robot_file
    from meshcol.io.kinematics import adjacent_links
    from meshcol.io.robot import load_robot_model

    opts = MatrixOptions(**options)
    opts.validate()
    report = progress or (lambda message: None)
    source = os.fspath(robot)
    began = time.perf_counter()
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
        "decomposed" if opts.collider == "decomposed" else "hull",
        mesh_parts="hull",
        decompose_options=opts.decompose_options,
        progress=report,
    )
    bodies = colliders.bodies
    link_index = {name: i for i, name in enumerate(kinematics.links)}
    stray = [b.name for b in bodies if b.name not in link_index]
    if stray:
        raise SceneError(f"body {stray[0]!r} is no link of the robot (a UCX_ link name?)", source)
    body_link = np.array([link_index[b.name] for b in bodies], dtype=np.int64)
    loaded = kinematics.link_poses(kinematics.loaded[None])[0]
    offsets = np.linalg.inv(loaded[body_link]) @ np.stack([b.pose for b in bodies])
    load_seconds = time.perf_counter() - began

    space = kinematics.space
    names = [b.name for b in bodies]
    adjacent = set(adjacent_links(kinematics.links, kinematics.edges, names))
    i, j = np.triu_indices(len(bodies), k=1)
    skip = np.array(
        [tuple(sorted((names[a], names[b]))) in adjacent for a, b in zip(i, j)], dtype=bool
    )
    sampler = _Sampler(
        kinematics,
        colliders,
        body_link,
        offsets,
        opts.padding,
        _batch(opts, len(colliders.shapes.vertices)),
        opts.threads,
        skip,
    )
    at_default = sampler.collide(space.default[None])[0]
    configurations = space.sample(opts.samples, opts.seed)
    counts = np.zeros(len(sampler.pairs), dtype=np.int64)
    step = max(sampler.batch, 1)
    for start in range(0, opts.samples, step):
        counts += sampler.collide(configurations[start : start + step]).sum(axis=0)
        report(f"collision-matrix: {min(start + step, opts.samples)}/{opts.samples} configurations")
    seconds = time.perf_counter() - began

    rate = counts / opts.samples
    pairs = []
    for (i, j), hits, r, default, failed in zip(
        sampler.pairs.tolist(),
        counts.tolist(),
        rate.tolist(),
        at_default.tolist(),
        sampler.failed.tolist(),
    ):
        a, b = sorted((names[i], names[j]))
        is_adjacent = (a, b) in adjacent
        if is_adjacent:
            kind = "adjacent"
        elif default:
            kind = "default"
        elif r >= opts.always_fraction:
            kind = "always"
        elif hits == 0:
            kind = "never"
        else:
            kind = "sometimes"
        pairs.append(
            {
                "link_a": a,
                "link_b": b,
                "class": kind,
                "reason": SRDF_REASON.get(kind),
                "collisions": None if is_adjacent else hits,
                "rate": None if is_adjacent else r,
                "adjacent": is_adjacent,
                "default_collision": None if is_adjacent else bool(default),
                "failed_queries": failed,
            }
        )
    pairs.sort(key=lambda p: (p["link_a"], p["link_b"]))
    joints = [
        {"name": n, "lower": lo, "upper": hi, "default": d}
        for n, lo, hi, d in zip(
            space.names, space.lower.tolist(), space.upper.tolist(), space.default.tolist()
        )
    ]
    by_class = {k: sum(p["class"] == k for p in pairs) for k in MATRIX_CLASSES}
    sampling = sampler.kinematics_seconds + sampler.collision_seconds
    summary = {
        "links": len(bodies),
        "link_pairs": len(pairs),
        "pairs_by_class": by_class,
        "disabled_pairs": len(pairs) - by_class["sometimes"],
        "samples": opts.samples,
        "seed": opts.seed,
        "sampled_joints": len(space),
        "convex_parts": len(colliders.part_body),
        "narrow_phase_pairs": sampler.narrow_pairs,
        "failed_queries": int(sampler.failed.sum()),
        "seconds": round(seconds, 6),
        "load_seconds": round(load_seconds, 6),
        "kinematics_seconds": round(sampler.kinematics_seconds, 6),
        "collision_seconds": round(sampler.collision_seconds, 6),
        "seconds_per_configuration": sampling / (opts.samples + 1),
    }
    settings = {
        "samples": opts.samples,
        "seed": opts.seed,
        "collider": opts.collider,
        "padding": opts.padding,
        "always_fraction": opts.always_fraction,
        "threads": opts.threads,
        "inputs": [display_path(source, posix=True)],
    }
    # The scene's pose is not the default configuration here: its joint-limit notes go.
    warnings = [w for w in scene.warnings if "outside its limits" not in w]
    warnings += [
        f"joint {n!r}: zero is outside its limits [{lo:g}, {hi:g}]; the default configuration "
        f"has it at the middle, {d:g} (give --joint {n}=VALUE to choose)"
        for n, lo, hi, d in zip(space.names, space.lower, space.upper, space.default)
        if not lo <= 0.0 <= hi and n not in given
    ]
    warnings += [*colliders.warnings, *kinematics.held]
    return CollisionMatrixReport(
        kinematics.name or Path(source).stem, pairs, joints, summary, settings, warnings
    )


def _batch(options: MatrixOptions, vertices: int) -> int:
    """Configurations per native call (see :attr:`MatrixOptions.batch`)."""
    if options.batch is not None:
        return min(options.batch, options.samples)
    return max(1, min(options.samples, MAX_BATCH, BATCH_VERTICES // max(vertices, 1)))
