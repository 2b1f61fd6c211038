"""All-pairs collision analysis of a scene: the engine behind ``meshcol check``.

Pipeline (arrays end to end; Python loops run over bodies, never over pairs):

1. Each body becomes convex parts in its local frame: its convex hull (``hull``), its convex
   decomposition (``decomposed``; ``UCX_<body>_NN`` parts in the input are used as given, as
   Unreal does), or its exact primitive. Bodies checked as ``mesh`` keep their hull for the
   broad phase only, and are measured on their triangles: distance, and for pairs whose
   surfaces touch, cross or nest, the mesh depth (the deepest sampled point of one surface
   inside the other, a lower bound of the minimum translation distance; never the hulls'
   depth, which calls a concave resting contact penetrating) and, when the pair penetrates
   and both meshes are closed, the volume of their intersection (manifold3d).
2. World AABBs of the parts, reduced per body and inflated by half the clearance band on each
   side, go to sort and sweep: candidate body pairs.
3. Parts of candidate body pairs go to a second sort and sweep; the convex part pairs to the
   batched narrow phase (GJK distance, EPA/SAT depth), and pairs where either body is a
   ``mesh`` to the exact triangle-mesh query (distance, intersection, containment).
4. Results are reduced per body pair (smallest signed distance wins) and classified. A body
   of several parts (``Body.parts``: a manifest body whose file holds several objects) is one
   body: its parts are never paired with each other, and a pair names the parts that come
   closest (``part_a``, ``part_b``).

Statuses, in increasing severity: ``separated`` (distance >= clearance), ``clearance``
(tolerance < distance < clearance), ``contact`` (|signed distance| <= tolerance),
``penetrating`` (depth > tolerance), ``contained`` (one body lies wholly inside the other's
closed surface; judged on the real meshes, so a ball in a bowl's hull is penetrating with
``hull`` shapes but not contained). Every point is in the world frame, every normal points from
body ``a`` to body ``b``, ``signed_distance = distance - depth``.
"""

from __future__ import annotations

import contextlib
import fnmatch
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any

import numpy as np

from meshcol.analysis.colliders import COLLIDER_KINDS, _geometry_key, build_colliders
from meshcol.errors import InputFileError
from meshcol.io.paths import display_path, display_paths
from meshcol.io.report import vector_columns
from meshcol.io.robot import RobotOptions
from meshcol.types import Scene, Status
from meshcol.vocabulary import PAIR_STATUSES

__all__ = [
    "PAIR_STATUSES",
    "FAIL_ON",
    "CheckOptions",
    "CheckReport",
    "check",
    "check_scene",
]

SEVERITY = {name: i for i, name in enumerate(PAIR_STATUSES)}
#: Query statuses whose numbers are not the answer: the pair is reported ``query_failed``.
_NO_ANSWER = (int(Status.INVALID_INPUT), int(Status.OUT_OF_RANGE))

# --fail-on value -> least severe status that violates the policy
FAIL_ON = {
    "penetration": "penetrating",
    "contact": "contact",
    "clearance": "clearance",
    "none": None,
}
#: The rule (meshcol.analysis.rules) of each pair status but ``separated``.
PAIR_RULES = {
    "clearance": "MC504",
    "contact": "MC503",
    "penetrating": "MC501",
    "contained": "MC502",
}


def failing_rules(fail_on: str, target: bool = False) -> tuple[str, ...]:
    """The rule ids a ``--fail-on`` value fails on: a status level (``penetration``,
    ``contact``, ``clearance``, ``none``: that status and the more severe ones, and with a
    ``target`` its limits' rules, :data:`meshcol.analysis.rules.TARGET_RULES`) or comma-separated rule ids or names
    (``MC501,missing-collider``, ``all``).

    Raises
    ------
    UnknownRuleError
        Neither a level nor rules of check (a ValueError; the message lists the valid ones).
    """
    from meshcol.analysis.rules import TARGET_RULES, UnknownRuleError, select_rules

    if fail_on in FAIL_ON:
        least = FAIL_ON[fail_on]
        if least is None:
            return ()
        levels = tuple(PAIR_RULES[s] for s in PAIR_STATUSES[SEVERITY[least] :])
        return levels + (TARGET_RULES if target else ())
    try:
        return select_rules(fail_on, "check")
    except UnknownRuleError as exc:
        raise UnknownRuleError(f"{exc} (or a level: {', '.join(FAIL_ON)})") from None


@dataclass(frozen=True)
class CheckOptions:
    """Settings of one check run.

    Attributes
    ----------
    collider : str
        Default collider kind: ``hull``, ``decomposed`` or ``mesh``
        (:mod:`meshcol.analysis.colliders`); a manifest's per-body ``shape`` overrides it;
        primitives are always exact.
    tolerance : float
        Contact band, in scene units: pairs with ``|signed_distance| <= tolerance`` touch.
    clearance : float
        Minimum gap required; pairs closer than it (but not touching) have status
        ``clearance``. 0 disables the band.
    fail_on : str
        ``penetration`` (default), ``contact``, ``clearance`` or ``none`` (that status and the
        more severe ones fail), or comma-separated rule ids or names (:func:`failing_rules`).
    ignore : tuple of str
        ``A:B`` rules with shell-style globs on body names; matching pairs (either order) are
        reported as ignored and never fail the run.
    baseline : dict or None
        A previous JSON report: only pairs that are new or worse than in it fail the run.
    threads : int
        Threads for the native queries; 0 means all cores.
    decompose_options : dict
        Options for on-the-fly convex decomposition (``decomposed`` bodies not in the cache).
    target : meshcol.io.targets.Target, optional
        An engine profile: each body's convex parts are measured against its limits
        (:func:`meshcol.analysis.rules.target_findings`); with a status level in ``fail_on``
        (not ``none``) its findings fail the run too.
    """

    collider: str = "hull"
    tolerance: float = 1e-6
    clearance: float = 0.0
    fail_on: str = "penetration"
    ignore: tuple[str, ...] = ()
    baseline: dict | None = None
    baseline_source: str | None = None
    threads: int = 0
    decompose_options: dict = field(default_factory=dict)
    target: Any = None

    def validate(self) -> None:
        if self.collider not in COLLIDER_KINDS:
            raise ValueError(
                f"collider must be one of {', '.join(COLLIDER_KINDS)}, got {self.collider!r}"
            )
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0):
            raise ValueError(f"tolerance must be a finite number >= 0, got {self.tolerance!r}")
        if not (math.isfinite(self.clearance) and self.clearance >= 0):
            raise ValueError(f"clearance must be a finite number >= 0, got {self.clearance!r}")
        failing_rules(self.fail_on)
        for rule in self.ignore:
            parse_ignore_rule(rule)


def parse_ignore_rule(rule: str) -> tuple[str, str]:
    """Split an ``A:B`` ignore rule into its two glob patterns."""
    parts = rule.split(":")
    if len(parts) != 2 or not parts[0] or not parts[1]:
        raise ValueError(f"ignore rule must look like A:B (globs allowed), got {rule!r}")
    return parts[0], parts[1]


@dataclass(frozen=True)
class CheckReport:
    """The outcome of a check: everything the JSON report holds.

    Attributes
    ----------
    bodies : list of dict
        Per body: name, file, collider, parts (names; empty for a body of one part),
        convex_parts, vertices, aabb (world ``[[min], [max]]``).
    pairs : list of dict
        Per candidate body pair, sorted by (body_a, body_b): body_a, body_b, part_a, part_b
        (the parts that come closest, None for a body of one part), status, distance, depth,
        signed_distance, normal, point_a, point_b, convex_part_a, convex_part_b, ignored,
        violation, query_failed, intersection_volume.
    summary : dict
        Counts, extremes, pass/fail and timings.
    settings : dict
        The options used.
    units : str or None
        From the manifest.
    warnings : list of str
        What the run could not do as asked (``UCX_`` parts naming nothing, flat bodies that
        could not be decomposed), one line each.
    findings : list of dict
        Finding records (:class:`meshcol.analysis.rules.Finding` fields and ``failed``):
        MC301 per body without a usable collider, and a target's limits per body and part. A
        pair's rule is its status (:data:`PAIR_RULES`), in ``pairs``, not repeated here.
    """

    bodies: list[dict]
    pairs: list[dict]
    summary: dict
    settings: dict
    units: str | None
    generated_at: str
    warnings: list[str] = field(default_factory=list)
    findings: list[dict] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return bool(self.summary["passed"])

    @property
    def exit_code(self) -> int:
        """0 when the policy passes, 1 when it is violated."""
        return 0 if self.passed else 1

    def to_dict(self) -> dict:
        """The JSON report: the common envelope, ``generated_at``, bodies, summary, pairs."""
        from meshcol.io.report import envelope

        return {
            **envelope("check", self.settings, self.units),
            "generated_at": self.generated_at,
            "warnings": self.warnings,
            "bodies": self.bodies,
            "summary": self.summary,
            "pairs": self.pairs,
            "findings": self.findings,
        }

    def worst_pairs(self, count: int = 10) -> list[dict]:
        """Up to ``count`` pairs that are not separated, most penetrating (smallest signed
        distance) first, ties in report order (``heapq.nsmallest`` is ``sorted()[:count]``
        without sorting 100,000 pairs to print ten)."""
        import heapq

        inf = float("inf")
        touching = (p for p in self.pairs if p["status"] != "separated")
        return heapq.nsmallest(
            count,
            touching,
            key=lambda p: inf if p["signed_distance"] is None else p["signed_distance"],
        )

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per candidate pair
        (``body_a <-> body_b``): a failure when it violates ``--fail-on``, skipped when an
        ``--ignore`` rule spares a pair the policy would fail, else passed; the message has
        the status and its numbers. More than :data:`meshcol.io.ci.MAX_PASSED_CASES` passed
        pairs become one case. The file is the scene input, or body_a's file."""
        from meshcol.io.ci import CiSuite, collapse_passed

        files = {b["name"]: b["file"] for b in self.bodies}
        inputs = self.settings.get("inputs") or []
        scene = inputs[0] if len(inputs) == 1 else None
        threshold = FAIL_ON[self.settings["fail_on"]]
        least = SEVERITY[threshold] if threshold is not None else len(PAIR_STATUSES)
        settings = self.settings
        cases = [_ci_case(p, files, scene, least, settings, self.units) for p in self.pairs]
        s = self.summary
        verb = "violates" if s["violations"] == 1 else "violate"
        return CiSuite(
            "check",
            tuple(collapse_passed(cases, "pairs", "meshcol.check")),
            settings,
            seconds=(s["seconds"] or 0.0) + (s["load_seconds"] or 0.0),
            warnings=tuple(self.warnings),
            verdict=f"{s['violations']} of {s['candidate_pairs']} candidate pairs {verb} "
            f"--fail-on {settings['fail_on']}",
            units=self.units,
        )

    def to_csv(self) -> str:
        from meshcol.io.report import dumps_csv, split_vectors

        sizes = {"normal": 3, "point_a": 3, "point_b": 3}
        rows = [split_vectors(dict(p, units=self.units), sizes) for p in self.pairs]
        return dumps_csv(rows, CSV_COLUMNS)


#: Columns of :meth:`CheckReport.to_csv`, one row per pair (vectors split, as every command).
CSV_COLUMNS = [
    "body_a",
    "body_b",
    "part_a",
    "part_b",
    "status",
    "distance",
    "depth",
    "signed_distance",
    *vector_columns("normal"),
    *vector_columns("point_a"),
    *vector_columns("point_b"),
    "convex_part_a",
    "convex_part_b",
    "ignored",
    "violation",
    "query_failed",
    "intersection_volume",
    "units",
]


def _ci_case(
    pair: dict,
    files: dict[str, str | None],
    scene: str | None,
    least: int,
    settings: dict,
    units: str | None,
) -> Any:
    """The CI case of one pair of a check report (:meth:`CheckReport.ci_suite`)."""
    from meshcol.io.ci import CiCase, details, number

    status = pair["status"]
    a, b = pair["body_a"], pair["body_b"]
    if status == "separated":
        message = f"separated: distance {number(pair['distance'], units)}"
    elif status == "clearance":
        message = (
            f"clearance: distance {number(pair['distance'], units)} < --clearance "
            f"{number(settings['clearance'], units)}"
        )
    elif status == "contact":
        message = (
            f"contact: signed distance {number(pair['signed_distance'], units)} (tolerance "
            f"{number(settings['tolerance'], units)})"
        )
    else:
        inside = "one body inside the other, " if status == "contained" else ""
        message = (
            f"{status}: {inside}depth {number(pair['depth'], units)}, signed distance "
            f"{number(pair['signed_distance'], units)}"
        )
        if pair["intersection_volume"] is not None:
            message += f", intersection volume {number(pair['intersection_volume'])}"
    if pair["query_failed"]:
        message += " (query failed: the numbers are not the answer)"
    outcome = "passed"
    if pair["violation"]:
        outcome = "failure"
        message += f" (--fail-on {settings['fail_on']})"
    elif SEVERITY[status] >= least:
        if pair["ignored"]:
            outcome = "skipped"
            message = f"ignored by --ignore: {message}"
        else:
            message += " (not worse than the --baseline)"
    text = ""
    if outcome != "passed":
        text = details(
            [
                ("body_a", f"{a} ({files.get(a)})" if files.get(a) else a),
                ("body_b", f"{b} ({files.get(b)})" if files.get(b) else b),
                ("part_a", pair["part_a"]),
                ("part_b", pair["part_b"]),
                ("distance", pair["distance"]),
                ("depth", pair["depth"]),
                ("signed_distance", pair["signed_distance"]),
                ("intersection_volume", pair["intersection_volume"]),
                ("point_a", pair["point_a"]),
                ("point_b", pair["point_b"]),
                ("normal", pair["normal"]),
                ("units", units),
            ]
        )
    return CiCase(
        name=f"{a} <-> {b}",
        classname="meshcol.check",
        outcome=outcome,
        message=message,
        file=scene or files.get(a),
        kind=status,
        details=text,
    )


# ---------------------------------------------------------------------------------------------
# Shapes


# ---------------------------------------------------------------------------------------------
# Pair selection


def _ignore_mask(
    names: Sequence[str], rules: Sequence[str], a: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """Boolean mask of pairs (a[k], b[k]) matched by any ``A:B`` glob rule, either order."""
    mask = np.zeros(len(a), dtype=bool)
    for rule in rules:
        pa, pb = parse_ignore_rule(rule)
        ma = np.fromiter((fnmatch.fnmatchcase(n, pa) for n in names), dtype=bool, count=len(names))
        mb = np.fromiter((fnmatch.fnmatchcase(n, pb) for n in names), dtype=bool, count=len(names))
        mask |= (ma[a] & mb[b]) | (mb[a] & ma[b])
    return mask


def _excluded_mask(
    names: Sequence[str], excluded: Sequence[tuple[str, str, str]], pairs: np.ndarray
) -> np.ndarray:
    """Boolean mask of the body pairs (rows of ``pairs``, a < b) that ``excluded`` names."""
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


def _cartesian_part_pairs(body_pairs: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """All (part of a, part of b) pairs of the given body pairs, without a Python loop."""
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


def _first_per_group(keys: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Index of the smallest value within each run of equal keys (keys need not be sorted)."""
    order = np.lexsort((values, keys))
    sorted_keys = keys[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = sorted_keys[1:] != sorted_keys[:-1]
    return order[first]


# ---------------------------------------------------------------------------------------------
# The check


def check_scene(
    scene: Scene,
    options: CheckOptions | None = None,
    *,
    progress: Callable[[str], None] | None = None,
    load_seconds: float | None = None,
    decompose: Callable[..., list[np.ndarray]] | None = None,
) -> CheckReport:
    """Check every pair of bodies of a loaded scene.

    Parameters
    ----------
    scene : Scene
        Bodies with their poses (``meshcol.load_inputs``).
    options : CheckOptions, optional
        Shapes, tolerance, clearance, policy; defaults when omitted.
    progress : callable, optional
        Receives one-line progress messages.
    load_seconds : float, optional
        Reported as the time the scene took to load.
    decompose : callable, optional
        Convex parts computed elsewhere (``build_colliders(decompose=)``).

    Returns
    -------
    CheckReport
    """
    from meshcol.collision.broadphase import sort_and_sweep
    from meshcol.collision.narrowphase import signed_distance_batch

    options = options or CheckOptions()
    options.validate()
    progress = progress or (lambda message: None)
    start = time.perf_counter()

    shapes = build_colliders(
        scene.bodies,
        options.collider,
        mesh_parts="hull",
        decompose_options=options.decompose_options,
        progress=progress,
        decompose=decompose,
    )
    bodies = shapes.bodies
    n = len(bodies)
    names = [b.name for b in bodies]
    part_poses = shapes.part_poses()
    progress(f"{n} bodies, {len(shapes.part_body)} convex parts")

    # World AABBs: parts, then bodies (parts of a body are contiguous).
    part_min, part_max = shapes.shapes.aabbs(part_poses, threads=options.threads)
    if n:
        starts = shapes.body_part_offsets[:-1]
        body_min = np.minimum.reduceat(part_min, starts, axis=0)
        body_max = np.maximum.reduceat(part_max, starts, axis=0)
    else:
        body_min = body_max = np.zeros((0, 3))
    # A mesh body's hull AABB equals its mesh AABB, so the broad phase is the same for it.
    mesh_bodies = np.array([s == "mesh" for s in shapes.kinds], dtype=bool)

    band = options.clearance + options.tolerance
    half = 0.5 * band
    candidates = sort_and_sweep(body_min - half, body_max + half)
    # Pairs the scene excludes (a robot's adjacent links, SRDF) are never measured.
    excluded = _excluded_mask(names, scene.excluded_pairs, candidates)
    candidates = candidates[~excluded]
    ca, cb = candidates[:, 0], candidates[:, 1]
    ignored = _ignore_mask(names, options.ignore, ca, cb) if len(candidates) else np.zeros(0, bool)

    # Results per candidate body pair.
    k = len(candidates)
    sd = np.full(k, np.inf)
    distance = np.full(k, np.inf)
    depth = np.zeros(k)
    normal = np.full((k, 3), np.nan)
    point_a = np.full((k, 3), np.nan)
    point_b = np.full((k, 3), np.nan)
    part_a = np.full(k, -1, dtype=np.int64)
    part_b = np.full(k, -1, dtype=np.int64)
    label_a = np.full(k, -1, dtype=np.int64)  # Body.parts index of the closest parts
    label_b = np.full(k, -1, dtype=np.int64)
    contained = np.zeros(k, dtype=bool)
    failed = np.zeros(k, dtype=bool)
    intersection_volume = np.full(k, np.nan)

    use_mesh = mesh_bodies[ca] | mesh_bodies[cb] if k else np.zeros(0, bool)

    # Convex pairs (also gives hull depths for mesh pairs that intersect).
    if k:
        key = ca * max(n, 1) + cb
        # parts of one body (its hulls, UCX parts, decomposition) never pair: one group each
        part_pairs = sort_and_sweep(part_min - half, part_max + half, groups=shapes.part_body)
        pb_a = shapes.part_body[part_pairs[:, 0]]
        pb_b = shapes.part_body[part_pairs[:, 1]]
        # Orient every part pair as (part of body a, part of body b) with a < b.
        swap = pb_a > pb_b
        part_pairs[swap] = part_pairs[swap][:, ::-1]
        pb_a, pb_b = np.minimum(pb_a, pb_b), np.maximum(pb_a, pb_b)
        part_key = pb_a * max(n, 1) + pb_b
        if excluded.any():  # part pairs of excluded body pairs
            keep = np.isin(part_key, key)
            part_pairs, part_key = part_pairs[keep], part_key[keep]
        # Body pairs whose parts' boxes never meet are still measured: all their part pairs.
        covered = np.isin(key, part_key)
        extra = _cartesian_part_pairs(candidates[~covered], shapes.body_part_offsets)
        if len(extra):
            part_pairs = np.concatenate([part_pairs, extra])
            part_key = np.concatenate(
                [
                    part_key,
                    shapes.part_body[extra[:, 0]] * max(n, 1) + shapes.part_body[extra[:, 1]],
                ]
            )
        result = signed_distance_batch(
            shapes.shapes, part_poses, part_pairs, threads=options.threads
        )
        bad = np.isin(result.status, _NO_ANSWER)
        value = np.where(bad, np.inf, result.signed_distance)
        best = _first_per_group(part_key, value)
        slot = np.searchsorted(key, part_key[best])  # candidates are sorted, so keys are too
        sd[slot] = result.signed_distance[best]
        distance[slot] = result.distance[best]
        depth[slot] = result.depth[best]
        normal[slot] = result.normal[best]
        point_a[slot] = result.point_a[best]
        point_b[slot] = result.point_b[best]
        part_a[slot] = shapes.part_index[part_pairs[best, 0]]
        part_b[slot] = shapes.part_index[part_pairs[best, 1]]
        label_a[slot] = shapes.part_label[part_pairs[best, 0]]
        label_b[slot] = shapes.part_label[part_pairs[best, 1]]
        failed[slot] = bad[best]

    # Exact triangle-mesh queries: pairs involving a `mesh` body, and containment of
    # convex pairs that overlap (judged on the real surfaces).
    # One body can only lie inside another if its box lies inside the other's box.
    overlap = (sd <= options.tolerance) & ~use_mesh
    if k:
        a_in_b = np.all((body_min[ca] >= body_min[cb]) & (body_max[ca] <= body_max[cb]), axis=1)
        b_in_a = np.all((body_min[cb] >= body_min[ca]) & (body_max[cb] <= body_max[ca]), axis=1)
        overlap &= a_in_b | b_in_a
    exact = use_mesh | overlap
    if exact.any():
        from meshcol.collision.mesh_query import (
            MeshSet,
            mesh_distance_batch,
            mesh_intersection_volume,
            mesh_penetration_depth_batch,
        )

        involved = np.unique(candidates[exact].ravel())
        local = np.full(n, -1, dtype=np.int64)
        local[involved] = np.arange(len(involved))
        meshes = MeshSet.from_bodies([bodies[i] for i in involved])
        poses = np.stack([bodies[i].pose for i in involved])
        idx = np.flatnonzero(exact)
        mres = mesh_distance_batch(meshes, poses, local[candidates[idx]], threads=options.threads)
        inside = (mres.a_inside_b | mres.b_inside_a) & ~mres.intersecting
        contained[idx] = inside
        m = use_mesh[idx]
        im = idx[m]
        # Mesh bodies: everything from the triangles, never from the hulls (a hull's depth
        # calls a concave resting contact penetrating). Apart: the exact distance. Crossing,
        # touching or nested: the mesh depth, a lower bound of the minimum translation
        # distance (mesh_penetration_depth_batch).
        hit = mres.intersecting[m] | inside[m]
        distance[im] = np.where(hit, 0.0, mres.distance[m])
        depth[im] = 0.0
        sep = ~hit
        point_a[im[sep]] = mres.point_a[m][sep]
        point_b[im[sep]] = mres.point_b[m][sep]
        gap = mres.point_b[m][sep] - mres.point_a[m][sep]
        length = np.linalg.norm(gap, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            normal[im[sep]] = np.where(length > 0, gap / length, normal[im[sep]])
        failed[im] = np.isin(mres.status[m], _NO_ANSWER)
        if hit.any():
            ih = im[hit]
            pairs_hit = local[candidates[ih]]
            dres = mesh_penetration_depth_batch(meshes, poses, pairs_hit, threads=options.threads)
            deep = dres.depth > 0.0
            depth[ih] = np.where(np.isfinite(dres.depth), dres.depth, 0.0)
            point_a[ih[deep]] = dres.point_a[deep]
            point_b[ih[deep]] = dres.point_b[deep]
            normal[ih[deep]] = dres.normal[deep]
            # Touching without depth: the shared point, and the normal of a's face there.
            touch = ~deep & mres.intersecting[m][hit]
            shared = mres.point_a[m][hit][touch]
            point_a[ih[touch]] = shared
            point_b[ih[touch]] = shared
            normal[ih[touch]] = _face_normals(
                meshes, pairs_hit[touch, 0], mres.triangle_a[m][hit][touch], poses
            )
            failed[ih] |= dres.status != int(Status.CONVERGED)
            volume_rows = ih[deep & (depth[ih] > options.tolerance)]
            if len(volume_rows):
                intersection_volume[volume_rows] = mesh_intersection_volume(
                    meshes, poses, local[candidates[volume_rows]]
                )
        sd[im] = distance[im] - depth[im]
        part_a[im] = -1
        part_b[im] = -1
        # the parts holding the closest points (hull parts where the surfaces cross)
        tri_a, tri_b = mres.triangle_a[m], mres.triangle_b[m]
        label_a[im] = np.where(tri_a >= 0, shapes.face_labels(ca[im], tri_a), label_a[im])
        label_b[im] = np.where(tri_b >= 0, shapes.face_labels(cb[im], tri_b), label_b[im])

    # Classification.
    tol = options.tolerance
    status_index = np.zeros(k, dtype=np.int64)
    status_index[distance < options.clearance] = SEVERITY["clearance"]
    status_index[(sd <= tol) & (sd >= -tol)] = SEVERITY["contact"]
    status_index[sd < -tol] = SEVERITY["penetrating"]
    status_index[contained] = SEVERITY["contained"]

    fail_rules = failing_rules(options.fail_on, options.target is not None)
    failing_status = [SEVERITY[s] for s, rule in PAIR_RULES.items() if rule in fail_rules]
    violation = np.isin(status_index, failing_status) & ~ignored
    if options.baseline is not None:
        idx = np.flatnonzero(violation)
        violation[idx] = _worse_than_baseline(
            options.baseline,
            names,
            candidates[idx],
            status_index[idx],
            depth[idx],
            distance[idx],
            tol,
        )
    seconds = time.perf_counter() - start

    # Report rows: columns converted once, then zipped (no per-pair numpy calls).
    columns = zip(
        ca.tolist(),
        cb.tolist(),
        status_index.tolist(),
        _nums(distance),
        _nums(depth),
        _nums(sd),
        _vecs(normal),
        _vecs(point_a),
        _vecs(point_b),
        part_a.tolist(),
        part_b.tolist(),
        shapes.part_names(ca, label_a),
        shapes.part_names(cb, label_b),
        ignored.tolist(),
        violation.tolist(),
        failed.tolist(),
        _nums(intersection_volume),
    )
    pairs = [
        {
            "body_a": names[a],
            "body_b": names[b],
            "part_a": na,
            "part_b": nb,
            "status": PAIR_STATUSES[s],
            "distance": d,
            "depth": dp,
            "signed_distance": sdv,
            "normal": nv,
            "point_a": pa,
            "point_b": pb,
            "convex_part_a": ia if ia >= 0 else None,
            "convex_part_b": ib if ib >= 0 else None,
            "ignored": ig,
            "violation": vi,
            "query_failed": fa,
            "intersection_volume": vol,
        }
        for a, b, s, d, dp, sdv, nv, pa, pb, ia, ib, na, nb, ig, vi, fa, vol in columns
    ]
    pairs.sort(key=lambda p: (p["body_a"], p["body_b"]))
    findings = _findings(shapes, options, scene.units, fail_rules)

    part_counts = np.diff(shapes.body_part_offsets).tolist()
    files = display_paths([body.source for body in bodies], posix=True)
    body_rows = [
        {
            "name": body.name,
            "file": file,
            "collider": kind,
            "parts": list(body.parts),
            "convex_parts": parts,
            "vertices": len(body.vertices),
            "aabb": [lo, hi],
        }
        for body, file, kind, parts, lo, hi in zip(
            bodies, files, shapes.kinds, part_counts, _vecs(body_min), _vecs(body_max)
        )
    ]
    body_rows.sort(key=lambda r: r["name"])

    by_status = {s: int(np.count_nonzero(status_index == SEVERITY[s])) for s in PAIR_STATUSES}
    finite_distance = distance[np.isfinite(distance)]
    summary = {
        "bodies": n,
        "candidate_pairs": k,
        "pairs_by_status": by_status,
        "ignored_pairs": int(np.count_nonzero(ignored)),
        "excluded_pairs": int(np.count_nonzero(excluded)),
        "failed_queries": int(np.count_nonzero(failed)),
        "min_distance": _num(finite_distance.min()) if len(finite_distance) else None,
        "max_depth": _num(depth.max()) if k else None,
        "violations": int(np.count_nonzero(violation)),
        "failed_findings": sum(f["failed"] for f in findings),
        "passed": not any(f["failed"] for f in findings) and not bool(violation.any()),
        "seconds": round(seconds, 6),
        "load_seconds": None if load_seconds is None else round(load_seconds, 6),
    }
    settings = {
        "collider": options.collider,
        "tolerance": options.tolerance,
        "clearance": options.clearance,
        "fail_on": options.fail_on,
        "fail_on_rules": list(fail_rules),
        "ignore": list(options.ignore),
        "baseline": display_path(options.baseline_source, posix=True),
        "excluded_pairs": [
            {"body_a": a, "body_b": b, "reason": reason} for a, b, reason in scene.excluded_pairs
        ],
        "inputs": [display_path(scene.source, posix=True)]
        if scene.source
        else sorted({file or "" for file, b in zip(files, bodies) if b.source}),
    }
    if options.target is not None:
        settings["target"] = options.target.name
        settings["target_limits"] = dict(options.target.limits)
    return CheckReport(
        body_rows,
        pairs,
        summary,
        settings,
        scene.units,
        datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        [*scene.warnings, *shapes.warnings],
        findings,
    )


def _findings(
    shapes: Any, options: CheckOptions, units: str | None, fail_rules: Sequence[str]
) -> list[dict]:
    """Body finding records, each with ``failed`` (its rule fails the run): MC301 per body
    without a usable collider (every convex part a segment or a point: no area), then a
    target's limits (:func:`meshcol.analysis.rules.target_findings`). Pairs are not
    repeated here: a pair's status is its rule (:data:`PAIR_RULES`, ``meshcol rules``)."""
    from meshcol.analysis.rules import finding, target_findings
    from meshcol.collision.hull import HullStatus

    records = []
    no_area = np.isin(shapes.shapes.hull_status, (HullStatus.COLLINEAR, HullStatus.SINGLE_POINT))
    no_area &= shapes.shapes.kinds == 0  # polytopes
    counts = np.diff(shapes.body_part_offsets)
    starts = shapes.body_part_offsets[:-1]
    if len(no_area) and len(starts):
        flat_parts = np.add.reduceat(no_area.astype(np.int64), starts)
        for b in np.flatnonzero((flat_parts == counts) & (counts > 0)).tolist():
            records.append(
                finding(
                    "MC301",
                    shapes.bodies[b].name,
                    None,
                    0.0,
                    0.0,
                    "no area: the collider is a segment or a point (every face degenerate)",
                )
            )
    if options.target is not None:
        records.extend(target_findings(shapes, options.target, units))
    return [dict(f.to_dict(), failed=f.rule in fail_rules) for f in records]


def _worse_than_baseline(
    baseline: dict,
    names: Sequence[str],
    candidates: np.ndarray,
    status_index: np.ndarray,
    depth: np.ndarray,
    distance: np.ndarray,
    tol: float,
) -> np.ndarray:
    """True for pairs that are new, or worse than in the baseline report."""
    old = {}
    for p in baseline.get("pairs", []):
        a, b = sorted((p["body_a"], p["body_b"]))
        old[(a, b)] = p
    worse = np.ones(len(candidates), dtype=bool)
    for i, (a, b) in enumerate(candidates):  # violating pairs only matter; few
        before = old.get(tuple(sorted((names[a], names[b]))))
        if before is None:
            continue
        prev = SEVERITY.get(before.get("status"), -1)
        if status_index[i] > prev:
            continue
        if status_index[i] < prev:
            worse[i] = False
            continue
        old_depth = before.get("depth") or 0.0
        old_distance = before.get("distance")
        deeper = depth[i] > old_depth + tol
        closer = old_distance is not None and distance[i] < old_distance - tol
        worse[i] = bool(deeper or closer)
    return worse


def load_baseline(path: str) -> dict:
    """Read a previous JSON report for ``--baseline``."""
    from meshcol.io.report import read_json_file

    data = read_json_file(path, "baseline report", "baseline")
    if not isinstance(data, dict) or not isinstance(data.get("pairs"), list):
        raise InputFileError("baseline is not a meshcol check report (no 'pairs' list)", path)
    for p in data["pairs"]:
        if not isinstance(p, dict) or not {"body_a", "body_b", "status"} <= p.keys():
            raise InputFileError(
                "baseline is not a meshcol check report (pair without body_a, body_b, status)",
                path,
            )
    return data


def check(
    inputs: Sequence[str | os.PathLike[str]] | str | os.PathLike[str],
    *,
    progress: Callable[[str], None] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    executor: str = "local",
    ray_address: str | None = None,
    robot_options: RobotOptions | None = None,
    **options: Any,
) -> CheckReport:
    """Load inputs and check every pair of bodies.

    Parameters
    ----------
    inputs : path or sequence of paths
        Mesh files (each body at its own coordinates), one scene manifest (JSON/TOML) or
        glTF/GLB scenes.
    jobs : int
        Files prepared at once, each a task of its own in a worker process or a Ray task:
        reading the file and, for ``decomposed`` bodies, their convex parts (through the
        cache; each task's engine gets its share of the cores,
        :func:`meshcol.decomposition.jobs.worker_env`). A manifest or robot is read here
        and only its decompositions go out, grouped by mesh file. The pair phase always runs
        here, on ``threads``. 1, without ``timeout`` or Ray: everything in this process.
    timeout : float, optional
        Seconds one file's task may take; a file over it, or whose worker dies, is an error
        (the pair phase needs every body).
    executor : {"local", "ray"}
        Where the tasks run (:func:`meshcol.decomposition.executor.make_executor`).
    ray_address : str, optional
        The Ray cluster (default: a local Ray of ``jobs`` CPUs, stopped at the end).
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.load_inputs`).
    **options
        Fields of :class:`CheckOptions` (``collider``, ``tolerance``, ``clearance``, ``fail_on``,
        ``ignore``, ``baseline`` (a path or a report dict), ``threads``, ``decompose_options``).
    progress : callable, optional
        Receives one-line progress messages.

    Returns
    -------
    CheckReport
        ``report.passed`` / ``report.exit_code`` apply the policy; the same report whichever
        executor prepared the files.

    Notes
    -----
    Broad phase: sort and sweep (Baraff 1992) on world AABBs. Narrow phase: GJK (van den Bergen
    2003) and EPA with exact SAT on small polytopes; exact triangle-mesh distance and a winding
    number containment test (Jacobson et al. 2013) for ``mesh`` shapes.
    """
    from meshcol.io.scene import collector_paused, load_inputs

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    baseline = options.pop("baseline", None)
    if isinstance(baseline, (str, os.PathLike)):
        options["baseline_source"] = os.fspath(baseline)
        baseline = load_baseline(os.fspath(baseline))
    if "ignore" in options:
        options["ignore"] = tuple(options["ignore"])
    opts = CheckOptions(baseline=baseline, **options)
    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    opts.validate()
    started = time.perf_counter()
    decompose = None
    if jobs > 1 or timeout is not None or executor != "local":
        scene, decompose = _prepare_files(
            list(inputs),
            opts,
            progress,
            jobs=jobs,
            timeout=timeout,
            executor=executor,
            address=ray_address,
            robot_options=robot_options,
        )
    else:
        scene = load_inputs(list(inputs), robot_options=robot_options)
    with collector_paused():
        return check_scene(
            scene,
            opts,
            progress=progress,
            load_seconds=time.perf_counter() - started,
            decompose=decompose,
        )


def _check_file(task: tuple[str, list[Any] | None, str, dict]) -> tuple[Any, Any, Any]:
    """Worker entry of a parallel check: one file's ``(path, bodies, collider kind,
    decompose options)`` (``bodies`` None: read the file here) to ``(bodies read or None,
    {mesh key: convex parts}, MeshcolError or None)``. The convex parts are those
    :func:`build_colliders` asks for on this file's bodies, through the cache; should it
    fail on them, the parts made so far are returned, and the caller's own
    :func:`build_colliders` meets (and reports) the error as a sequential run does."""
    from meshcol.analysis.colliders import convex_parts
    from meshcol.errors import MeshcolError
    from meshcol.io.mesh_read import load_mesh

    path, given, kind, decompose_options = task
    try:
        bodies = load_mesh(path) if given is None else given
    except MeshcolError as error:
        return None, {}, error
    parts: dict[bytes, list[np.ndarray]] = {}

    def record(mesh: Any, **options: Any) -> list[np.ndarray]:
        parts[_geometry_key(*mesh)] = found = convex_parts(mesh, **options)
        return found

    if any(b.primitive is None and (b.collider or kind) == "decomposed" for b in bodies):
        # Only the convex parts are kept: the caller builds the scene's colliders whole.
        with contextlib.suppress(MeshcolError):
            build_colliders(bodies, kind, decompose_options=decompose_options, decompose=record)
    return (bodies if given is None else None), parts, None


def _prepare_files(
    inputs: list[str | os.PathLike[str]],
    options: CheckOptions,
    progress: Callable[[str], None] | None,
    robot_options: RobotOptions | None = None,
    **run: Any,
) -> tuple[Scene, Callable[..., list[np.ndarray]]]:
    """:func:`load_inputs` and the decompositions with one executor task per file: the scene
    (names given here, in input order, by :func:`meshcol.io.scene.unique_name`) and the
    convex parts the tasks made, for ``check_scene(decompose=)``. Errors are the sequential
    run's: the first unreadable file in input order (decomposition errors are met again by
    ``check_scene``, as in a sequential run); a file whose task failed or ran over the
    timeout is an error naming it."""
    import dataclasses

    from meshcol.analysis.colliders import convex_parts
    from meshcol.decomposition.executor import run_each
    from meshcol.errors import MeshcolError
    from meshcol.io.inputs import is_whole_scene
    from meshcol.io.scene import iter_inputs, load_inputs, unique_name

    kind, decompose_options = options.collider, options.decompose_options
    whole = is_whole_scene(inputs)
    scene: Scene | None = None
    if whole:  # a manifest or robot is read here; its decompositions go out per mesh file
        scene = load_inputs(inputs, robot_options=robot_options)
        tasks: list[tuple[str, list[Any] | None, str, dict]] = [
            (path, bodies, kind, decompose_options)
            for path, bodies in iter_inputs(inputs, robot_options=robot_options)
        ]
    else:
        tasks = [(os.fspath(p), None, kind, decompose_options) for p in inputs]
    outcomes: dict[int, Any] = {}
    report = progress or (lambda message: None)
    for outcome in run_each(_check_file, tasks, **run):
        outcomes[outcome.index] = outcome
        report(f"check: {len(outcomes)}/{len(tasks)} files")
    parts: dict[bytes, list[np.ndarray]] = {}
    for index, (path, _, _, _) in enumerate(tasks):
        outcome = outcomes[index]
        if outcome.status != "ok":
            raise MeshcolError(f"its task {_outcome_text(outcome)}", path)
        _, found, error = outcome.value
        if error is not None:
            raise error
        parts.update(found)
    if scene is None:
        bodies: list[Any] = []
        used: set[str] = set()
        for index in range(len(tasks)):
            for body in outcomes[index].value[0]:
                name = unique_name(body.name, used)
                bodies.append(body if name == body.name else dataclasses.replace(body, name=name))
        source = os.fspath(inputs[0]) if len(inputs) == 1 else None
        scene = Scene(bodies=tuple(bodies), units=None, source=source)

    def decompose(mesh: Any, **options: Any) -> list[np.ndarray]:
        found = parts.get(_geometry_key(*mesh))
        return convex_parts(mesh, **options) if found is None else found

    return scene, decompose


def _outcome_text(outcome: Any) -> str:
    """``timed out after 3 s``, ``failed: worker process died (exit code -9)``."""
    if outcome.status == "timeout":
        return outcome.message or "timed out"
    return f"failed: {outcome.message}"


def _face_normals(meshes: Any, mesh: np.ndarray, face: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """World unit normals (n, 3) of face ``face[k]`` of mesh ``mesh[k]`` (NaN when degenerate
    or when the face is -1)."""
    out = np.full((len(mesh), 3), np.nan)
    ok = face >= 0
    if not ok.any():
        return out
    rows = meshes.faces[meshes.face_offsets[mesh[ok]] + face[ok]]
    corners = meshes.vertices[meshes.vertex_offsets[mesh[ok], None] + rows]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    local = np.stack(
        [
            e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1],
            e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
            e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0],
        ],
        axis=1,
    )
    world = np.einsum("kij,kj->ki", poses[mesh[ok], :3, :3], local)
    length = np.linalg.norm(world, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out[ok] = np.where(length > 0, world / length, np.nan)
    return out


def _nums(values: np.ndarray) -> list[float | None]:
    """Floats as a list, non-finite ones as None."""
    return [v if math.isfinite(v) else None for v in values.tolist()]


def _vecs(values: np.ndarray) -> list[list[float] | None]:
    """Rows of 3-vectors as lists, rows with a non-finite entry as None."""
    finite = np.all(np.isfinite(values), axis=1).tolist()
    return [row if ok else None for row, ok in zip(values.tolist(), finite)]


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None
