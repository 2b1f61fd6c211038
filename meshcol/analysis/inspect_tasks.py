"""``meshcol inspect`` as one executor task per file (``--jobs``, ``--timeout``, Ray).

:func:`inspect_in_tasks` plans the tasks (a manifest's or a robot's meshes grouped by mesh
file, or one task per input file that reads it), runs them
(:func:`meshcol.decomposition.executor.run_each`) and puts their inspections back in the
order, with the names and errors, of the run in one process.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from typing import Any

from meshcol.analysis.health import Inspected, body_meshes, inspect_meshes
from meshcol.errors import MeshcolError
from meshcol.types import Body

__all__ = ["inspect_in_tasks"]

#: One task: ``(path, the meshes to inspect or None to read the file in the task, units)``.
FileTask = tuple[str, list[Body] | None, str | None]
#: What a task returns when it ran: ``(the bodies it read or None, an inspection or its
#: InvalidMeshError per mesh)``.
TaskValue = tuple[list[Body] | None, list[Any]]


def inspect_in_tasks(
    inputs: list[Any],
    scene_bodies: list[Body] | None,
    units: str | None,
    skip: Callable[[str, MeshcolError], None],
    progress: Callable[[str], None] | None,
    **run: Any,
) -> tuple[list[Body], list[Inspected]]:
    """The inspections of :func:`meshcol.analysis.inspect.inspect`, one executor task per
    file.

    Parameters
    ----------
    inputs : list of path
        The input files.
    scene_bodies : list of Body or None
        A manifest's or a robot's bodies, read by the caller (their meshes go out grouped by
        mesh file); None: each input file is read in its task.
    units : str or None
        The manifest's units (each mesh's declared units).
    skip : callable
        ``skip(path, error)`` for each file whose task failed (died, ran over its time, or
        could not read the file), in file order.
    progress : callable, optional
        Receives ``inspect: 3/10 files``.
    **run
        ``jobs``, ``timeout``, ``executor``, ``address`` of
        :func:`meshcol.decomposition.executor.run_each`.

    Returns
    -------
    bodies : list of Body
        The bodies, named as the sequential run names them (``unique_name`` in input order).
    inspected : list of Inspected
        Their meshes' inspections, in input order.
    """
    if scene_bodies is not None:
        meshes = body_meshes(scene_bodies)
        tasks, slots = _scene_tasks(os.fspath(inputs[0]), meshes, units)
        values = _run_tasks(tasks, skip, progress, run)
        return scene_bodies, _scene_inspected(meshes, slots, values)
    tasks = [(os.fspath(path), None, None) for path in inputs]
    return _files_inspected(_run_tasks(tasks, skip, progress, run))


def _inspect_file(task: FileTask) -> tuple[TaskValue | None, Exception | None]:
    """Worker entry of a parallel inspect: one file's ``(path, meshes, declared units)``
    (``meshes`` None: read the file here) to ``((bodies read here or None, [inspection or
    its InvalidMeshError per mesh]), None)``, or ``(None, the MeshcolError that made the
    file unreadable)``."""
    from meshcol.io.mesh_read import load_mesh

    path, meshes, units = task
    bodies = None
    if meshes is None:
        try:
            bodies = load_mesh(path)
        except MeshcolError as error:
            return None, error
        meshes = [part for _, _, part in body_meshes(bodies)]
    return (bodies, inspect_meshes(meshes, units)), None


def _scene_tasks(
    source: str, meshes: Sequence[tuple[str, str | None, Body]], units: str | None
) -> tuple[list[FileTask], list[list[int]]]:
    """A scene's meshes grouped by mesh file: one task per file, and the indices (in
    ``meshes``) of each task's meshes."""
    groups: dict[str, list[int]] = {}
    for index, (_, _, part) in enumerate(meshes):
        groups.setdefault(part.source or source or part.name, []).append(index)
    tasks: list[FileTask] = [
        (path, [meshes[k][2] for k in indices], units) for path, indices in groups.items()
    ]
    return tasks, list(groups.values())


def _run_tasks(
    tasks: list[FileTask],
    skip: Callable[[str, MeshcolError], None],
    progress: Callable[[str], None] | None,
    run: dict[str, Any],
) -> list[TaskValue | None]:
    """Each task's value, in task order; None (and ``skip``) for a task that failed."""
    from meshcol.decomposition.executor import run_each

    outcomes: dict[int, Any] = {}
    for outcome in run_each(_inspect_file, tasks, **run):
        outcomes[outcome.index] = outcome
        if progress is not None:
            progress(f"inspect: {len(outcomes)}/{len(tasks)} files")
    return [_task_value(path, outcomes[index], skip) for index, (path, _, _) in enumerate(tasks)]


def _task_value(
    path: str, outcome: Any, skip: Callable[[str, MeshcolError], None]
) -> TaskValue | None:
    if outcome.status != "ok":
        skip(path, MeshcolError(outcome.message or outcome.status, path))
        return None
    value, error = outcome.value
    if error is not None:
        skip(path, error)
        return None
    return value


def _scene_inspected(
    meshes: Sequence[tuple[str, str | None, Body]],
    slots: list[list[int]],
    values: list[TaskValue | None],
) -> list[Inspected]:
    """The scene's meshes with their inspections, in scene order; the meshes of a failed
    task left out (its file's error is already recorded)."""
    found: dict[int, Any] = {}
    for indices, value in zip(slots, values):
        if value is not None:
            found.update(zip(indices, value[1]))
    return [
        (body_name, part_name, part, found[index])
        for index, (body_name, part_name, part) in enumerate(meshes)
        if index in found
    ]


def _files_inspected(values: list[TaskValue | None]) -> tuple[list[Body], list[Inspected]]:
    """The bodies the tasks read, renamed as one process names them (``name#2`` for a name
    seen in an earlier file), and their meshes' inspections under those names."""
    from meshcol.types import unique_name

    bodies: list[Body] = []
    inspected: list[Inspected] = []
    used_names: dict[str, int] = {}
    for value in values:
        if value is None:
            continue
        read, results = value
        assert read is not None
        renamed_bodies = [_renamed(body, unique_name(body.name, used_names)) for body in read]
        original_names = {renamed.name: body.name for renamed, body in zip(renamed_bodies, read)}
        bodies.extend(renamed_bodies)
        for (body_name, part_name, part), result in zip(body_meshes(renamed_bodies), results):
            original = original_names[body_name]
            inspected.append(
                (body_name, part_name, part, _renamed_result(result, part, body_name, original))
            )
    return bodies, inspected


def _renamed(body: Body, name: str) -> Body:
    return body if body.name == name else dataclasses.replace(body, name=name)


def _renamed_result(result: Any, part: Body, body_name: str, original: str) -> Any:
    """An inspection (or its error) made in a task under the body's name in its file, under
    the name the run gives it."""
    if isinstance(result, MeshcolError):
        # raised before the body was renamed (``name#2``): its message names the mesh
        before = original + part.name[len(body_name) :]
        prefix = f"body '{before}': "
        if body_name != original and result.message.startswith(prefix):
            message = f"body '{part.name}': {result.message[len(prefix) :]}"
            return type(result)(message, result.path)
        return result
    if result.name != part.name:
        return dataclasses.replace(result, name=part.name)
    return result
