"""Continuous collision: time of impact of moving convex shapes, and the scene sweep.

Motion, fixed once for the whole module (the C++ core, ``cpp/include/meshcol/toi.hpp``,
implements it):

- Each body moves from its start pose to its end pose over ``t`` in [0, 1]. Its reference point
  is its LOCAL ORIGIN: the origin's world position moves linearly, and the body turns about it
  at constant angular velocity from the start to the end rotation (slerp of the relative
  rotation ``R0.T @ R1``, the shorter way, angle in [0, pi]). :func:`interpolate_pose` gives
  the pose at any ``t``.
- ``toi`` is the fraction of the motion in [0, 1]; ``time = toi * duration`` when the scene
  gives a duration in seconds.
- ``tolerance`` is an absolute distance (world units): the shapes are in contact when their
  distance is at most ``tolerance``.

Statuses (:class:`meshcol.types.ToiStatus`) and what each guarantees:

- ``HIT``: the distance at ``toi`` is <= tolerance, and the shapes do not touch before ``toi``
  (``toi`` is a lower bound of the first instant of contact, within about
  ``tolerance / closing speed`` of it).
- ``SEPARATED``: the distance stays above ``tolerance / 2`` during the whole motion. A pair that
  touches during the motion is never ``SEPARATED`` (a closest approach between
  ``tolerance / 2`` and ``tolerance`` may be reported either way).
- ``OVERLAPPED_AT_START``: within ``tolerance`` at ``t = 0``; ``toi = 0``.
- ``FAILED``: the iteration cap was reached; ``toi`` is the last safe lower bound.
- ``INVALID_INPUT``: NaN/inf coordinates, an empty shape or a non-rigid pose.

Results give ``point`` (world, the midpoint of the closest points at ``toi``) and ``normal``
(world, unit, from a towards b at ``toi``; zero when overlapping at the start).

Notes
-----
Two spheres: closed form (the centre distance is the square root of a quadratic in t).
Translation only (neither body turns, or only spheres do): GJK ray cast on the Minkowski
difference (van den Bergen 2004), sphere and capsule radii as margins. Otherwise: conservative
advancement (Mirtich 1996; Zhang et al. 2006) with a rigorous bound on the closing speed of the
separating slab: relative linear speed along the normal plus, per body,
``angle * |normal x axis| * bounding radius about the local origin``; each step aims at
``tolerance / 2`` so a contact is never stepped over.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from meshcol.errors import MeshcolError, SceneError
from meshcol.query import ConvexSet, ShapeKind, _as_pairs, _as_set, _pack_any
from meshcol.types import Body, Scene, ToiStatus

__all__ = [
    "TimeOfImpactResult",
    "TimeOfImpactBatch",
    "SweepHit",
    "SweepReport",
    "interpolate_pose",
    "time_of_impact",
    "time_of_impact_batch",
    "sweep",
    "SHAPE_MODES",
]

#: Collision shapes the sweep can use for each body.
SHAPE_MODES = ("hull", "decomposed", "mesh")

#: Scene-relative default tolerance of :func:`sweep`: this times the scene's bounding diagonal.
RELATIVE_TOLERANCE = 1e-6


def _defaults() -> Any:
    from meshcol import _core

    return _core.defaults


@dataclass(frozen=True)
class TimeOfImpactResult:
    """Time of impact of one pair (see the module docstring for the guarantees).

    Attributes
    ----------
    status : ToiStatus
    toi : float or None
        Fraction of the motion in [0, 1]; None when ``SEPARATED`` or ``INVALID_INPUT``.
    point : (3,) float64
        World, midpoint of the closest points at ``toi`` (NaN when there is none).
    normal : (3,) float64
        World, unit, from a towards b at ``toi`` (zero when overlapping at the start).
    iterations : int
        Cast or advancement steps.
    """

    status: ToiStatus
    toi: float | None
    point: np.ndarray
    normal: np.ndarray
    iterations: int


@dataclass(frozen=True)
class TimeOfImpactBatch:
    """Per-pair times of impact, in pair order.

    Attributes
    ----------
    toi : (P,) float64
        Fraction of the motion in [0, 1]; NaN for ``SEPARATED`` and ``INVALID_INPUT`` pairs.
    point : (P, 3) float64
        World contact point at ``toi`` (midpoint of the closest points).
    normal : (P, 3) float64
        World unit normal from a towards b at ``toi``.
    iterations : (P,) int32
    status : (P,) int8
        :class:`meshcol.types.ToiStatus` values.
    """

    toi: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


def _as_pose_stack(poses: Any, h: int, name: str) -> np.ndarray:
    arr = np.ascontiguousarray(poses, dtype=np.float64)
    if arr.shape != (h, 4, 4):
        raise ValueError(f"{name} must be ({h}, 4, 4), got {arr.shape}")
    return arr


def _tolerance(tolerance: float | None) -> float:
    if tolerance is None:
        return float(_defaults().toi_tolerance)
    value = float(tolerance)
    if not np.isfinite(value) or value <= 0.0:
        raise ValueError(f"tolerance must be finite and > 0, got {tolerance}")
    return value


def interpolate_pose(start_pose: Any, end_pose: Any, t: Any) -> np.ndarray:
    """Pose at time ``t`` of the motion from ``start_pose`` to ``end_pose``.

    Parameters
    ----------
    start_pose, end_pose : (4, 4) or (N, 4, 4) float
        Rigid world-from-local poses, row-major.
    t : float or (N,) float
        Fractions of the motion (0: start, 1: end).

    Returns
    -------
    (4, 4) or (N, 4, 4) float64
        Translation linear in ``t``; rotation slerped about the local origin.
    """
    from meshcol import _core

    start = np.asarray(start_pose, dtype=np.float64)
    single = start.ndim == 2
    start = np.ascontiguousarray(start.reshape(-1, 4, 4))
    end = np.ascontiguousarray(np.asarray(end_pose, dtype=np.float64).reshape(-1, 4, 4))
    times = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=np.float64).reshape(-1),
                                                 (len(start),)))
    out = _core.interpolate_poses(start, end, times)
    return out[0] if single else out


def time_of_impact_batch(
    shapes: ConvexSet,
    start_poses: Any,
    end_poses: Any,
    pairs: Any,
    *,
    tolerance: float | None = None,
    max_iterations: int | None = None,
    threads: int = 0,
) -> TimeOfImpactBatch:
    """Time of impact of each pair of moving shapes.

    Parameters
    ----------
    shapes : ConvexSet
    start_poses, end_poses : (H, 4, 4) float
        Rigid world-from-local poses of every shape at the start and at the end of the
        motion, row-major.
    pairs : (P, 2) int
        Indices into ``shapes``.
    tolerance : float, optional
        Absolute contact distance (default ``_core.defaults.toi_tolerance``).
    max_iterations : int, optional
        Cap on cast/advancement steps per pair (default
        ``_core.defaults.toi_max_iterations``); a pair reaching it is ``FAILED``.
    threads : int
        Worker threads; 0 uses all cores.

    Returns
    -------
    TimeOfImpactBatch
        One array per field, in pair order.

    Raises
    ------
    ValueError
        Wrong array shapes, an index out of range, or a tolerance that is not > 0.

    Notes
    -----
    See the module docstring for the motion model, the guarantees and the algorithms.
    """
    from meshcol import _core

    cs = _as_set(shapes)
    h = len(cs)
    start = _as_pose_stack(start_poses, h, "start_poses")
    end = _as_pose_stack(end_poses, h, "end_poses")
    idx = _as_pairs(pairs, h)
    cap = int(_defaults().toi_max_iterations if max_iterations is None else max_iterations)
    r = _core.time_of_impact_batch(cs._core, start, end, idx, _tolerance(tolerance), cap,
                                   int(threads))
    return TimeOfImpactBatch(r["toi"], r["point"], r["normal"], r["iterations"], r["status"])


def time_of_impact(
    a: Any,
    b: Any,
    start_pose_a: Any,
    end_pose_a: Any,
    start_pose_b: Any,
    end_pose_b: Any,
    *,
    tolerance: float | None = None,
    max_iterations: int | None = None,
) -> TimeOfImpactResult:
    """Time of impact of two convex shapes, each moving from a start to an end pose.

    Parameters
    ----------
    a, b : Sphere, Box, Capsule, Cylinder, trimesh.Trimesh, Body or (n, 3) float
        Shapes in their local frames (meshes and point sets by their convex hull).
    start_pose_a, end_pose_a, start_pose_b, end_pose_b : (4, 4) float or None
        Rigid world-from-local poses (None: identity).
    tolerance, max_iterations
        As :func:`time_of_impact_batch`.

    Returns
    -------
    TimeOfImpactResult
    """
    cs = ConvexSet._from_packed([_pack_any(a, "a"), _pack_any(b, "b")])
    poses = []
    for name, pose in (("start_pose_a", start_pose_a), ("end_pose_a", end_pose_a),
                       ("start_pose_b", start_pose_b), ("end_pose_b", end_pose_b)):
        m = np.eye(4) if pose is None else np.asarray(pose, dtype=np.float64)
        if m.shape != (4, 4):
            raise ValueError(f"{name} must be (4, 4), got {m.shape}")
        poses.append(m)
    r = time_of_impact_batch(cs, np.stack([poses[0], poses[2]]), np.stack([poses[1], poses[3]]),
                             np.array([[0, 1]]), tolerance=tolerance,
                             max_iterations=max_iterations, threads=1)
    toi = float(r.toi[0])
    return TimeOfImpactResult(ToiStatus(int(r.status[0])), None if np.isnan(toi) else toi,
                              r.point[0], r.normal[0], int(r.iterations[0]))


# ---------------------------------------------------------------------------------------------
# Scene sweep


@dataclass(frozen=True)
class SweepHit:
    """One body pair that is not separated during the motion.

    Attributes
    ----------
    a, b : str
        Body names (``a`` comes first in the scene).
    status : ToiStatus
        ``HIT``, ``OVERLAPPED_AT_START`` or ``FAILED``.
    toi : float
        Fraction of the motion (for ``FAILED``: the last safe lower bound).
    time : float or None
        ``toi * duration`` in seconds, when the scene has a duration.
    point : (3,) float64
        World contact point at ``toi``.
    normal : (3,) float64
        World unit normal from a towards b at ``toi``.
    pose_a, pose_b : (4, 4) float64
        Both bodies' world-from-local poses at ``toi``.
    tunnelled : bool
        True for a hit that a discrete check at the start and end poses alone misses (the
        bodies overlap neither at the start nor at the end).
    iterations : int
        Steps of the pair query that decided the pair.
    """

    a: str
    b: str
    status: ToiStatus
    toi: float
    time: float | None
    point: np.ndarray
    normal: np.ndarray
    pose_a: np.ndarray
    pose_b: np.ndarray
    tunnelled: bool
    iterations: int

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready fields (lists for arrays, the status by name), numbers rounded to 12
        significant digits (far below the tolerance) so reports compare across machines."""
        return {
            "a": self.a, "b": self.b, "status": self.status.name, "toi": _round(self.toi),
            "time": _round(self.time), "point": _round(self.point),
            "normal": _round(self.normal), "pose_a": _round(self.pose_a),
            "pose_b": _round(self.pose_b), "tunnelled": self.tunnelled,
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
    shape : str
        Collision shape mode (``hull``, ``decomposed`` or ``mesh``).
    tolerance : float
        Contact distance used (world units).
    hits : tuple of SweepHit
        Every body pair that is not ``SEPARATED``, sorted by (a, b) names.
    candidate_pairs : int
        Body pairs whose swept bounds overlap (the pairs the narrow phase ran on).
    shape_pairs : int
        Convex-piece pairs the narrow phase ran on.
    """

    scene: Scene
    shape: str
    tolerance: float
    hits: tuple[SweepHit, ...]
    candidate_pairs: int
    shape_pairs: int
    moving: tuple[bool, ...] = field(default=())

    @property
    def failed(self) -> bool:
        """True when any pair hits, overlaps at the start or could not be decided."""
        return bool(self.hits)

    def summary(self) -> dict[str, int]:
        count = {s: sum(h.status == s for h in self.hits) for s in ToiStatus}
        return {
            "bodies": len(self.scene.bodies),
            "moving_bodies": int(sum(self.moving)),
            "candidate_pairs": self.candidate_pairs,
            "shape_pairs": self.shape_pairs,
            "hits": count[ToiStatus.HIT],
            "tunnelled": sum(h.tunnelled for h in self.hits),
            "overlapped_at_start": count[ToiStatus.OVERLAPPED_AT_START],
            "failed": count[ToiStatus.FAILED],
        }

    def as_dict(self) -> dict[str, Any]:
        """The JSON report body (without tool and settings headers)."""
        return {
            "units": self.scene.units,
            "duration": self.scene.duration,
            "bodies": [{"name": b.name, "source": b.source, "moving": m}
                       for b, m in zip(self.scene.bodies, self.moving)],
            "summary": self.summary(),
            "pairs": [h.as_dict() for h in self.hits],
        }


def _is_moving(body: Body) -> bool:
    return body.end_transform is not None and not np.array_equal(body.end_transform,
                                                                 body.transform)


def _bounding_radii(cs: ConvexSet) -> np.ndarray:
    """Radius of a ball about each shape's local origin holding the whole shape."""
    h = len(cs)
    radii = np.zeros(h)
    norms = np.linalg.norm(cs.vertices, axis=1) if len(cs.vertices) else np.zeros(0)
    for i in range(h):
        k, p = cs.kinds[i], cs.params[i]
        if k == ShapeKind.POLYTOPE:
            lo, hi = cs.offsets[i], cs.offsets[i + 1]
            radii[i] = norms[lo:hi].max() if hi > lo else np.nan
        elif k == ShapeKind.SPHERE:
            radii[i] = p[0]
        elif k == ShapeKind.BOX:
            radii[i] = np.linalg.norm(p[:3])
        elif k == ShapeKind.CAPSULE:
            radii[i] = p[0] + p[1]
        else:
            radii[i] = np.hypot(p[0], p[1])
    return radii


def swept_aabbs(cs: ConvexSet, start_poses: np.ndarray, end_poses: np.ndarray,
                threads: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Conservative world AABBs of shapes over their whole motion.

    Parameters
    ----------
    cs : ConvexSet
    start_poses, end_poses : (H, 4, 4) float

    Returns
    -------
    aabb_min, aabb_max : (H, 3) float64

    Notes
    -----
    A shape that does not turn (or a sphere) sweeps the union of its start and end AABBs
    exactly (an AABB moves rigidly under translation). A turning shape stays inside the ball
    of its bounding radius about its local origin, whose centre moves linearly: the AABB of
    that swept ball. (The union of the start and end AABBs alone is NOT conservative under
    rotation: a bar turning by 90 degrees sweeps corners outside both.)
    """
    lo0, hi0 = cs.aabbs(start_poses, threads=threads)
    lo1, hi1 = cs.aabbs(end_poses, threads=threads)
    lo, hi = np.minimum(lo0, lo1), np.maximum(hi0, hi1)
    turning = np.any(start_poses[:, :3, :3] != end_poses[:, :3, :3], axis=(1, 2))
    turning &= cs.kinds != ShapeKind.SPHERE
    if np.any(turning):
        r = _bounding_radii(cs)[turning][:, None]
        t0, t1 = start_poses[turning, :3, 3], end_poses[turning, :3, 3]
        lo[turning] = np.minimum(t0, t1) - r
        hi[turning] = np.maximum(t0, t1) + r
    return lo, hi


def _candidate_pairs(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(K, 2) int64 pairs i < j whose AABBs overlap (sort and sweep)."""
    from meshcol.broadphase import sort_and_sweep

    return sort_and_sweep(lo, hi)


def _triangle_set(body: Body) -> tuple[ConvexSet, int]:
    """Every non-degenerate triangle of a body's mesh as a 3-vertex polytope."""
    tri = np.asarray(body.vertices, dtype=np.float64)[np.asarray(body.faces, dtype=np.int64)]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    n = np.cross(e1, e2)
    area2 = np.linalg.norm(n, axis=1)
    scale = np.ptp(body.vertices, axis=0).max() if len(body.vertices) else 0.0
    keep = area2 > 1e-12 * scale * scale
    tri, n, area2 = tri[keep], n[keep], area2[keep]
    t = len(tri)
    unit = n / area2[:, None] if t else np.zeros((0, 3))
    edges = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    edges = edges / np.linalg.norm(edges, axis=2, keepdims=True) if t else np.zeros((0, 3, 3))
    step3 = np.arange(t + 1, dtype=np.int64) * 3
    local = np.array([[1, 2], [0, 2], [0, 1]], dtype=np.int32)
    return ConvexSet(
        vertices=tri.reshape(-1, 3),
        offsets=step3,
        kinds=np.zeros(t, np.int8),
        params=np.zeros((t, 4)),
        adjacency_offsets=np.arange(3 * t + 1, dtype=np.int64) * 2,
        adjacency=np.tile(local.reshape(-1), t),
        face_offsets=np.arange(t + 1, dtype=np.int64) * 2,
        face_normals=np.stack([unit, -unit], axis=1).reshape(-1, 3),
        edge_offsets=step3,
        edge_directions=edges.reshape(-1, 3),
    ), int(np.count_nonzero(~keep))


def _body_pieces(body: Body, mode: str, decompose_options: dict | None = None) -> ConvexSet:
    """The convex pieces of one body under a shape mode (primitives are always exact)."""
    if body.primitive is not None or mode == "hull":
        return ConvexSet.from_meshes([body])
    if mode == "decomposed":
        from meshcol.decompose import convex_parts

        return ConvexSet.from_vertices(convex_parts(body, **(decompose_options or {})))
    return _triangle_set(body)[0]


def _body_shapes(bodies: Sequence[Body], mode: str,
                 decompose_options: dict | None = None) -> tuple[ConvexSet, np.ndarray]:
    """All convex pieces of the bodies (a body's own ``shape`` overrides ``mode``) and the
    owner (body index) of each."""
    sets = [_body_pieces(b, b.shape or mode, decompose_options) for b in bodies]
    owner = np.concatenate([np.full(len(s), i, dtype=np.int64) for i, s in enumerate(sets)]
                           or [np.zeros(0, np.int64)])
    return ConvexSet.concatenate(*sets), owner


def _load(inputs: Any) -> Scene:
    if isinstance(inputs, Scene):
        return inputs
    if isinstance(inputs, Body):
        return Scene(bodies=(inputs,))
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    inputs = list(inputs)
    if inputs and all(isinstance(b, Body) for b in inputs):
        return Scene(bodies=tuple(inputs))
    from meshcol.scene import load_inputs

    scene = load_inputs(inputs)
    if scene.source is None and len(inputs) == 1:
        scene = Scene(bodies=scene.bodies, units=scene.units, source=os.fspath(inputs[0]),
                      duration=scene.duration)
    return scene


def sweep(
    inputs: Any,
    *,
    shape: str = "hull",
    tolerance: float | None = None,
    max_iterations: int | None = None,
    threads: int = 0,
    decompose_options: dict | None = None,
) -> SweepReport:
    """Continuous collision over a scene: the first contact of every pair of bodies.

    Parameters
    ----------
    inputs : Scene, sequence of Body, or path(s) of a scene manifest / meshes
        Bodies with start poses (``Body.transform``) and end poses (``Body.end_transform``;
        None for a static body).
    shape : {"hull", "decomposed", "mesh"}
        Collision shape of each body: its convex hull (primitives exactly); its convex
        decomposition (``meshcol.decompose``); or its triangles, each swept as a 3-vertex
        polytope (surface contact: a body that starts wholly inside another is not found).
    tolerance : float, optional
        Contact distance in world units (default ``1e-6`` x the diagonal of the scene's swept
        bounds).
    max_iterations : int, optional
        Per-pair step cap (see :func:`time_of_impact_batch`).
    threads : int
        Worker threads; 0 uses all cores.
    decompose_options : dict, optional
        Options of :func:`meshcol.decompose.convex_parts` for ``decomposed`` bodies (from the
        decompose cache when present, else decomposed now).

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
    the tolerance. Narrow phase: :func:`time_of_impact_batch` on every pair of convex pieces of
    different bodies, at least one of them moving; a body pair takes the earliest contact of
    its pieces (``FAILED`` when an undecided piece pair could come earlier). Static-static
    pairs are skipped: they cannot start touching. ``tunnelled``: a discrete check
    (:func:`meshcol.query.intersects_batch`) finds no overlap at the start poses nor at the
    end poses.
    """
    from meshcol.query import intersects_batch

    if shape not in SHAPE_MODES:
        raise ValueError(f"shape must be one of {', '.join(SHAPE_MODES)}, got {shape!r}")
    scene = _load(inputs)
    bodies = scene.bodies
    moving = np.array([_is_moving(b) for b in bodies], dtype=bool)
    if not any(b.end_transform is not None for b in bodies):
        raise SceneError("no body has an end pose or a velocity: nothing moves, nothing to sweep",
                         scene.source)
    cs, owner = _body_shapes(bodies, shape, decompose_options)
    start_body = np.stack([np.asarray(b.transform, dtype=np.float64) for b in bodies])
    end_body = np.stack([np.asarray(b.transform if b.end_transform is None else b.end_transform,
                                    dtype=np.float64) for b in bodies])
    start, end = np.ascontiguousarray(start_body[owner]), np.ascontiguousarray(end_body[owner])
    lo, hi = swept_aabbs(cs, start, end, threads)
    if tolerance is None:
        finite = np.all(np.isfinite(lo), axis=1) & np.all(np.isfinite(hi), axis=1)
        diagonal = (float(np.linalg.norm(hi[finite].max(axis=0) - lo[finite].min(axis=0)))
                    if np.any(finite) else 0.0)
        tol = RELATIVE_TOLERANCE * diagonal if diagonal > 0.0 else _tolerance(None)
    else:
        tol = _tolerance(tolerance)
    bad = ~(np.all(np.isfinite(lo), axis=1) & np.all(np.isfinite(hi), axis=1))
    if np.any(bad):
        body = bodies[int(owner[np.argmax(bad)])]
        raise MeshcolError(f"body '{body.name}': invalid shape or pose (NaN/inf, empty or not "
                           "rigid)", body.source or scene.source)
    pairs = _candidate_pairs(lo - 0.5 * tol, hi + 0.5 * tol)
    if len(pairs):
        oa, ob = owner[pairs[:, 0]], owner[pairs[:, 1]]
        keep = (oa != ob) & (moving[oa] | moving[ob])
        pairs = pairs[keep]
        # Piece pairs ordered as their bodies (a first in the scene).
        swap = owner[pairs[:, 0]] > owner[pairs[:, 1]]
        pairs[swap] = pairs[swap][:, ::-1]
    toi = time_of_impact_batch(cs, start, end, pairs, tolerance=tol,
                               max_iterations=max_iterations, threads=threads)
    at_start = intersects_batch(cs, start, pairs, threads=threads).intersects
    at_end = intersects_batch(cs, end, pairs, threads=threads).intersects

    body_pairs = owner[pairs] if len(pairs) else np.zeros((0, 2), np.int64)
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (i, j) in enumerate(body_pairs.tolist()):
        groups.setdefault((i, j), []).append(k)
    hits = []
    for (i, j), ks in groups.items():
        ks = np.asarray(ks)
        status = toi.status[ks]
        if np.any(status == ToiStatus.INVALID_INPUT):
            raise MeshcolError(f"bodies '{bodies[i].name}' and '{bodies[j].name}': invalid "
                               "shape or pose", scene.source)
        live = ks[status != ToiStatus.SEPARATED]
        if len(live) == 0:
            continue
        best = live[np.argmin(toi.toi[live])]
        best_status = ToiStatus(int(toi.status[best]))
        if np.any(toi.status[ks] == ToiStatus.OVERLAPPED_AT_START):
            best = ks[np.argmax(toi.status[ks] == ToiStatus.OVERLAPPED_AT_START)]
            best_status = ToiStatus.OVERLAPPED_AT_START
        elif best_status == ToiStatus.HIT and np.any(toi.status[live] == ToiStatus.FAILED):
            failed = live[toi.status[live] == ToiStatus.FAILED]
            if toi.toi[failed].min() < toi.toi[best]:
                best_status = ToiStatus.FAILED
        t = float(toi.toi[best])
        poses = interpolate_pose(np.stack([start_body[i], start_body[j]]),
                                 np.stack([end_body[i], end_body[j]]), [t, t])
        tunnelled = (best_status == ToiStatus.HIT and not np.any(at_start[ks])
                     and not np.any(at_end[ks]))
        hits.append(SweepHit(
            a=bodies[i].name, b=bodies[j].name, status=best_status, toi=t,
            time=None if scene.duration is None else t * float(scene.duration),
            point=toi.point[best].copy(), normal=toi.normal[best].copy(),
            pose_a=poses[0], pose_b=poses[1], tunnelled=bool(tunnelled),
            iterations=int(toi.iterations[best])))
    hits.sort(key=lambda h: (h.a, h.b))
    return SweepReport(scene=scene, shape=shape, tolerance=tol, hits=tuple(hits),
                       candidate_pairs=len(groups), shape_pairs=len(pairs),
                       moving=tuple(bool(m) for m in moving))
