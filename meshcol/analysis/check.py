"""All-pairs collision analysis of a scene: the engine behind ``meshcol check``.

A check is a short list of stages over one pair table (:mod:`meshcol.analysis.pairs`), arrays
end to end (Python loops run over bodies, never over pairs):

1. ``build_colliders``: each body becomes convex parts in its local frame: its convex hull
   (``hull``), its convex decomposition (``decomposed``; ``UCX_<body>_NN`` parts in the input
   are used as given, as Unreal does), its fitted primitives (``fit``) or its exact primitive.
   Bodies checked as ``mesh`` keep their hull for the broad phase only.
2. ``place``: world poses and boxes of every part and body.
3. ``broad_phase``: body boxes grown by the clearance band and the tolerance go to sort and
   sweep, then their parts' boxes: candidate body pairs and the part pairs to measure.
4. ``convex_phase``: every part pair in one batched narrow-phase call (GJK distance, EPA/SAT
   depth); each body pair keeps its smallest signed distance.
5. ``mesh_phase``: pairs where either body is a ``mesh``, and convex pairs that may nest, on
   the triangles: distance and containment, and for pairs whose surfaces touch, cross or
   nest the mesh depth (the deepest sampled point of one surface inside the other, a lower
   bound of the minimum translation distance; never the hulls' depth, which calls a concave
   resting contact penetrating) and, when the pair penetrates and both meshes are closed,
   the volume of their intersection (manifold3d).
6. ``depth_bounds``: ``depth_upper``, the penetration depth of convex sets enclosing the two
   bodies (an upper bound of the minimum translation distance), so that ``depth <= minimum
   translation distance <= depth_upper``; a depth above it is lowered to it.
7. ``classify``, then the policy (:func:`~meshcol.analysis.check_policy.apply_policy`:
   ``--fail-on``, ``--ignore``, ``--baseline``), then the report's rows
   (:func:`~meshcol.analysis.check_report.check_report`).

A body of several parts (``Body.parts``: a manifest body whose file holds several objects) is
one body: its parts are never paired with each other, and a pair names the parts that come
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
import dataclasses
import os
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from meshcol.analysis.check_policy import FAIL_ON, CheckOptions, apply_policy
from meshcol.analysis.check_report import CheckReport, check_report
from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.depth_bounds import depth_bounds
from meshcol.analysis.geometry_cache import geometry_key
from meshcol.analysis.mesh_phase import mesh_phase
from meshcol.analysis.pairs import (
    PairTable,
    PlacedColliders,
    broad_phase,
    classify,
    convex_phase,
    place,
)
from meshcol.analysis.primitive_colliders import primitive_colliders
from meshcol.errors import TooManyPairsError
from meshcol.io.column_bodies import body_names
from meshcol.io.robot import RobotOptions
from meshcol.types import Scene, unique_name
from meshcol.vocabulary import PAIR_STATUSES

__all__ = [
    "PAIR_STATUSES",
    "FAIL_ON",
    "CheckOptions",
    "CheckReport",
    "check",
    "check_scene",
]


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
    options = options or CheckOptions()
    report = progress or (lambda message: None)
    started = time.perf_counter()
    # a manifest of primitives only, as columns: packed from its arrays, no object a body
    colliders = primitive_colliders(scene.bodies) or build_colliders(
        scene.bodies,
        options.collider,
        mesh_parts="hull",
        decompose_options=options.decompose_options,
        progress=report,
        decompose=decompose,
    )
    placed = place(colliders, options.threads)
    report(f"{len(colliders.bodies)} bodies, {len(colliders.part_body)} convex parts")
    # the broad phase pairs bodies within the clearance band and the contact tolerance
    margin = options.clearance + options.tolerance
    table = broad_phase(placed, margin, scene.excluded_pairs, options.max_pairs, scene.part_filter)
    table = narrow_phase(table, placed, options)
    table = classify(table, options.tolerance, options.clearance)
    table = apply_policy(table, body_names(colliders.bodies), options)
    seconds = time.perf_counter() - started
    return check_report(table, placed, scene, options, seconds, load_seconds)


def narrow_phase(table: PairTable, placed: PlacedColliders, options: CheckOptions) -> PairTable:
    """The measuring stages (convex, mesh, depth bounds) on the broad phase's pairs; with
    ``options.pair_cache``, only on the pairs it has no answer for
    (:mod:`meshcol.analysis.pair_cache`)."""

    def stages(rows: PairTable) -> PairTable:
        rows = convex_phase(rows, placed, options.threads)
        rows = mesh_phase(rows, placed, options.tolerance, options.threads)
        return depth_bounds(rows, placed, options.threads)

    if options.pair_cache is None:
        return stages(table)
    margin = options.clearance + options.tolerance
    measured: PairTable = options.pair_cache.measure(
        table, placed, options.tolerance, margin, stages
    )
    return measured


#: The robot options of a check given none: every default, and an MJCF's planes read.
_HALF_SPACES = RobotOptions(half_spaces=True)


def with_half_spaces(robot_options: RobotOptions | None) -> RobotOptions:
    """The robot options a check reads a description with: an MJCF's planes as half-space
    bodies (``RobotOptions.half_spaces``), the floor a robot stands on checked with it."""
    if robot_options is None:
        return _HALF_SPACES
    return dataclasses.replace(robot_options, half_spaces=True)


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
        The Ray cluster (default: a running one, else a local Ray of ``jobs`` CPUs,
        stopped at the end: :class:`~meshcol.decomposition.executor.RayExecutor`).
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
    from meshcol.io.mesh_formats import format_notes
    from meshcol.io.scene import collector_paused
    from meshcol.io.scene_parse import forget_documents

    paths = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    from meshcol.decomposition.run_keywords import check_run

    check_run(jobs, timeout, options.get("threads", 0))
    opts = CheckOptions.from_keywords(**options)
    started = time.perf_counter()
    run = {"jobs": jobs, "timeout": timeout, "executor": executor, "address": ray_address}
    scene, decompose = _load(paths, opts, progress, with_half_spaces(robot_options), **run)
    forget_documents()  # loaded: its manifest's decoded text is not read again
    notes = format_notes(paths)  # what the readers left out (an FBX's lights...), as inspect
    if notes:
        scene = dataclasses.replace(scene, warnings=(*scene.warnings, *notes))
    with collector_paused():
        try:
            return check_scene(
                scene,
                opts,
                progress=progress,
                load_seconds=time.perf_counter() - started,
                decompose=decompose,
            )
        except TooManyPairsError as error:  # the scene named: the one line says which
            name = os.fspath(paths[0]) + (f" and {len(paths) - 1} more" if len(paths) > 1 else "")
            raise TooManyPairsError(error.message, scene.source or name) from None


def _load(
    inputs: list[str | os.PathLike[str]],
    options: CheckOptions,
    progress: Callable[[str], None] | None,
    robot_options: RobotOptions | None = None,
    **run: Any,
) -> tuple[Scene, Callable[..., list[np.ndarray]] | None]:
    """The scene, and the convex parts made by per-file tasks when ``run`` asks for them
    (``jobs`` > 1, a ``timeout`` or an executor other than ``local``); else everything here."""
    if run["jobs"] > 1 or run["timeout"] is not None or run["executor"] != "local":
        return _prepare_files(inputs, options, progress, robot_options, **run)
    from meshcol.io.scene import load_inputs

    return load_inputs(inputs, robot_options=robot_options), None


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
        parts[geometry_key(*mesh)] = found = convex_parts(mesh, **options)
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
    (names given here, in input order, by :func:`meshcol.types.unique_name`) and the
    convex parts the tasks made, for ``check_scene(decompose=)``. Errors are the sequential
    run's: the first unreadable file in input order (decomposition errors are met again by
    ``check_scene``, as in a sequential run); a file whose task failed or ran over the
    timeout is an error naming it."""
    import dataclasses

    from meshcol.analysis.colliders import convex_parts
    from meshcol.decomposition.executor import run_each
    from meshcol.errors import MeshcolError
    from meshcol.io.inputs import is_whole_scene
    from meshcol.io.mesh_formats import declared_units
    from meshcol.io.scene import is_scene_file, iter_inputs, load_inputs

    kind, decompose_options = options.collider, options.decompose_options
    # a USD stage or glTF physics file carries excluded pairs and units: read it here, whole
    whole = is_whole_scene(inputs) or any(is_scene_file(p) for p in inputs)
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
        used: dict[str, int] = {}
        for index in range(len(tasks)):
            for body in outcomes[index].value[0]:
                name = unique_name(body.name, used)
                bodies.append(body if name == body.name else dataclasses.replace(body, name=name))
        source = os.fspath(inputs[0]) if len(inputs) == 1 else None
        scene = Scene(bodies=tuple(bodies), units=declared_units(inputs), source=source)

    def decompose(mesh: Any, **options: Any) -> list[np.ndarray]:
        found = parts.get(geometry_key(*mesh))
        return convex_parts(mesh, **options) if found is None else found

    return scene, decompose


def _outcome_text(outcome: Any) -> str:
    """``timed out after 3 s``, ``failed: worker process died (exit code -9)``."""
    if outcome.status == "timeout":
        return outcome.message or "timed out"
    return f"failed: {outcome.message}"
