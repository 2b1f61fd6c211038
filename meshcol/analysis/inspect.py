"""``meshcol inspect``: is each mesh fit to be a collider, and is its collider fit for physics?

:func:`inspect` runs as named stages: read the inputs; inspect each mesh
(:func:`meshcol.analysis.health.inspect_body`: a manifest body's parts one by one, with its
declared units, so ``suspect-units`` compares the guess with them), here or one executor task
per file (:mod:`meshcol.analysis.inspect_tasks`); turn the inspections into findings; then
measure each body's collider against its visual mesh
(:func:`meshcol.analysis.physics.physics_readiness`); and return an
:class:`~meshcol.analysis.inspect_report.InspectReport`.

A batch keeps going: a mesh file that cannot be read, or a body that cannot be inspected (no
faces), becomes an entry of :attr:`InspectReport.errors` and the run's exit code is 2; the
other bodies are reported. What a mesh alone decides (its topology, crossings, manifold status)
is measured once however many bodies instance it (:mod:`meshcol.analysis.geometry_cache`); what
a body's pose decides (its bounds, its degenerate faces, its units guess) for each body, so the
report is the one of each body alone.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from meshcol.analysis.geometry_cache import GeometryCache
from meshcol.analysis.health import (
    RULES,
    Inspected,
    MeshInspection,
    body_meshes,
    guess_units,
    health_findings,
    inspect_body,
    inspect_meshes,
    units_by_body,
)
from meshcol.analysis.inspect_report import InspectReport
from meshcol.analysis.inspect_tasks import inspect_in_tasks
from meshcol.analysis.physics import PhysicsOptions, physics_readiness
from meshcol.analysis.rules import Finding
from meshcol.errors import InvalidMeshError, MeshcolError
from meshcol.io.robot import RobotOptions
from meshcol.types import Body

__all__ = [
    "InspectReport",
    "MeshInspection",
    "RULES",
    "PhysicsOptions",
    "inspect",
    "inspect_body",
    "guess_units",
]


def inspect(
    inputs: Any,
    *,
    fail_on: Sequence[str] | str = (),
    physics: PhysicsOptions | None = None,
    progress: Callable[[str], None] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    executor: str = "local",
    ray_address: str | None = None,
    robot_options: RobotOptions | None = None,
) -> InspectReport:
    """Inspect every body of the inputs: is each mesh fit to be a collider, and is its
    collider fit for physics?

    Parameters
    ----------
    inputs : path or sequence of paths
        Mesh files (every object, solid or mesh node is a body), one scene manifest, or one
        robot description (URDF, MJCF: its links' collision geometry, against their visual
        geometry).
    fail_on : sequence of str or str
        Rule ids or names (``MC401``, ``not-watertight``, ``all``) whose findings fail the
        run (:attr:`InspectReport.exit_code`).
    physics : PhysicsOptions, optional
        The collider and the tolerances of the physics rules.
    progress : callable, optional
        Receives one line per body inspected (``inspect: 3/10 bodies``), or per file with
        an executor (``inspect: 3/10 files``).
    jobs : int
        Files inspected at once, each a task of its own in a worker process or a Ray task
        (:mod:`meshcol.analysis.inspect_tasks`). 1, without ``timeout`` or Ray: every body
        in this process, one after another.
    timeout : float, optional
        Seconds a file's task may take; it is then stopped (its worker killed) and the file
        is an entry of :attr:`InspectReport.errors`, as is a file whose worker died.
    executor : {"local", "ray"}
        Where the tasks run (:func:`meshcol.decomposition.executor.make_executor`).
    ray_address : str, optional
        The Ray cluster (default: a running one, else a local Ray of ``jobs`` CPUs,
        stopped at the end: :class:`~meshcol.decomposition.executor.RayExecutor`).
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.robot.load_robot`).

    Returns
    -------
    InspectReport
        The same report whichever executor ran it.

    Raises
    ------
    UnknownRuleError
        An unknown rule in ``fail_on`` (a ValueError).
    MeshcolError
        A manifest that cannot be used, or inputs none of which could be inspected.
    """
    options, rules = _policy(physics, fail_on)
    paths = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
    run = _task_run(jobs, timeout, executor, ray_address)
    errors = _InputErrors()
    scene = _read_inputs(paths, errors, read_files=run is None, robot_options=robot_options)
    geometries = GeometryCache()  # health and physics measure each mesh once between them
    bodies, inspected = _inspect_bodies(paths, scene, errors, progress, geometries, run)
    inspections, findings, unusable = _health(inspected, errors)
    if not inspections and errors.first is not None:
        raise errors.first
    usable = [body for body in bodies if body.name not in unusable]
    rows, physics_findings = physics_readiness(
        usable, options, visuals=scene.visuals, units=scene.units, _geometries=geometries
    )
    return InspectReport(
        tuple(inspections),
        rules,
        scene.units,
        tuple(errors.records),
        tuple(scene.findings + findings + physics_findings),
        tuple(rows),
        options,
        tuple(scene.warnings),
    )


def _policy(
    physics: PhysicsOptions | None, fail_on: Sequence[str] | str
) -> tuple[PhysicsOptions, tuple[str, ...]]:
    """The physics options, validated, and the rule ids that fail the run: ``fail_on``'s,
    else a target's limits."""
    from meshcol.analysis.rules import TARGET_RULES, select_rules

    options = physics or PhysicsOptions()
    rules = select_rules(fail_on, "inspect")
    if not rules and options.target is not None:
        rules = TARGET_RULES  # a target's limits fail the run unless --fail-on says otherwise
    options.validate()
    return options, rules


def _task_run(
    jobs: int, timeout: float | None, executor: str, ray_address: str | None
) -> dict[str, Any] | None:
    """How the executor tasks run (:func:`meshcol.decomposition.executor.run_each`'s
    keywords), or None: every mesh in this process."""
    from meshcol.decomposition.run_keywords import check_run

    check_run(jobs, timeout)
    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    if jobs > 1 or timeout is not None or executor != "local":
        return {"jobs": jobs, "timeout": timeout, "executor": executor, "address": ray_address}
    return None


class _InputErrors:
    """The inputs that could not be inspected, as the report lists them, and the first
    error (raised when nothing could be inspected)."""

    def __init__(self) -> None:
        self.records: list[dict[str, Any]] = []
        self.first: MeshcolError | None = None

    def add(self, path: str, error: MeshcolError, body: str | None = None) -> None:
        if self.first is None:
            self.first = error
        self.records.append({"source": path, "body": body, "message": error.message})


@dataclass
class _Inputs:
    """What :func:`inspect` read before inspecting: the bodies (None: the files are read in
    their tasks), the manifest's units, a robot's visual geometry per link, the warnings of
    the reading and a robot's findings (MC506)."""

    bodies: list[Body] | None
    units: str | None = None
    visuals: dict[str, Body] | None = None
    warnings: list[str] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)


def _read_inputs(
    paths: list[Any],
    errors: _InputErrors,
    read_files: bool,
    robot_options: RobotOptions | None = None,
) -> _Inputs:
    """One manifest (read whole: its problem stops the run), one robot description (read with
    ``robot_options``), or mesh files (an unreadable one is an error of the report; not read
    here when ``read_files`` is false)."""
    from meshcol.io.inputs import input_kind
    from meshcol.io.mesh_read import load_file_scene
    from meshcol.io.scene import is_scene_file, iter_inputs, load_scene

    kind = input_kind(paths[0]) if len(paths) == 1 else "mesh"
    if kind == "manifest":
        scene = load_scene(paths[0])
        return _Inputs(list(scene.bodies), scene.units)
    if kind == "robot":
        return _read_robot(paths[0], robot_options)
    from meshcol.io.mesh_formats import declared_units, format_notes

    if len(paths) == 1 and is_scene_file(paths[0]):  # USD, glTF physics: units, warnings
        try:
            whole = load_file_scene(paths[0])
        except MeshcolError as error:
            errors.add(os.fspath(paths[0]), error)
            return _Inputs([])
        if whole is not None:
            return _Inputs(list(whole.bodies), whole.units, None, list(whole.warnings))
    if not read_files:
        return _Inputs(None, declared_units(paths), warnings=format_notes(paths))
    files = iter_inputs(paths, on_error=errors.add)
    bodies = [body for _, file_bodies in files for body in file_bodies]
    return _Inputs(bodies, declared_units(paths), warnings=format_notes(paths))


def _read_robot(path: Any, robot_options: RobotOptions | None = None) -> _Inputs:
    """A robot's links (their collision geometry) and its visual geometry per link, from one
    read of the description with ``robot_options``."""
    from meshcol.analysis.rules import robot_findings
    from meshcol.io.robot import load_robot_views

    scene, visual = load_robot_views(path, robot_options)
    warnings, findings = list(scene.warnings), robot_findings(scene)  # MC506: nothing collides
    if isinstance(visual, MeshcolError):
        warning = f"visual geometry not read, links compared with their collision meshes: {visual}"
        return _Inputs(list(scene.bodies), scene.units, {}, [*warnings, warning], findings)
    visuals = {body.name: body for body in visual.bodies}
    return _Inputs(list(scene.bodies), scene.units, visuals, warnings, findings)


def _inspect_bodies(
    paths: list[Any],
    scene: _Inputs,
    errors: _InputErrors,
    progress: Callable[[str], None] | None,
    geometries: GeometryCache,
    run: dict[str, Any] | None,
) -> tuple[list[Body], list[Inspected]]:
    """The bodies and each of their meshes inspected: in executor tasks (``run``), else in
    this process, one after another."""
    if run is not None:
        return inspect_in_tasks(paths, scene.bodies, scene.units, errors.add, progress, **run)
    assert scene.bodies is not None
    meshes = body_meshes(scene.bodies)
    outcomes = inspect_meshes([part for _, _, part in meshes], scene.units, progress, geometries)
    inspected = [
        (body_name, part_name, part, outcome)
        for (body_name, part_name, part), outcome in zip(meshes, outcomes)
    ]
    return scene.bodies, inspected


def _health(
    inspected: list[Inspected], errors: _InputErrors
) -> tuple[list[MeshInspection], list[Finding], set[str]]:
    """The inspections in input order, their findings, and the bodies a mesh of which could
    not be inspected (an error each; left out of the physics)."""
    inspections: list[MeshInspection] = []
    findings: list[Finding] = []
    unusable: set[str] = set()
    for body_name, part_name, part, outcome in units_by_body(inspected):
        if isinstance(outcome, InvalidMeshError):
            errors.add(outcome.path or part.source or "", outcome, part.name)
            unusable.add(body_name)
        else:
            inspections.append(outcome)
            findings.extend(health_findings(outcome, body_name, part_name))
    return inspections, findings, unusable
