"""One task of a decomposition run: its meshes read and made canonical, looked up in the cache
before it is sent, what a worker does with it, and what the run stores of what comes back.

A task is ``(label, [(name, vertices, faces)], TaskOptions)``: a file's bodies
(:func:`meshcol.decomposition.batch.decompose_files`) or one mesh of a robot's link
(:func:`meshcol.decomposition.batch.decompose_meshes`). Workers read the cache but never write
it: the run stores what they return, entry by entry, so that a worker killed mid-task never
leaves an entry.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.decomposition.options import DecomposeOptions, RunOptions
from meshcol.decomposition.steps import stage
from meshcol.errors import InvalidMeshError

if TYPE_CHECKING:
    from meshcol.io.robot import RobotOptions

__all__ = [
    "BodyMesh",
    "TaskOptions",
    "decompose_task",
    "is_complete",
    "iter_files",
    "look_up",
    "search_task",
    "store_result",
    "worker_entry",
]

#: A body of a file as a task carries it: (name, canonical vertices (n, 3) float, canonical
#: faces (m, 3) int, its pose (4, 4): body frame to world).
BodyMesh = tuple[str, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class TaskOptions:
    """What a worker needs besides the meshes of its task.

    Attributes
    ----------
    options : DecomposeOptions
    cache_dir : str or None
        The cache as the run was given it (None: the worker's default cache folder).
    use_cache : bool
    threads : int
        The task's share of the cores for its distance queries (:meth:`RunOptions.threads`).
    """

    options: DecomposeOptions
    cache_dir: str | None = None
    use_cache: bool = True
    threads: int = 0

    @classmethod
    def of(cls, options: DecomposeOptions, run: RunOptions) -> TaskOptions:
        return cls(options, run.cache_dir, run.use_cache, run.threads())


def worker_entry(options: DecomposeOptions) -> Callable[[Any], Any]:
    """The function a worker runs on each task: a search per body when ``options`` search,
    else a decomposition per body."""
    return decompose_task if options.search_target() is None else search_task


def decompose_task(
    task: tuple[str, list[tuple[str, np.ndarray, np.ndarray]], TaskOptions],
) -> list[tuple[str, Any]]:
    """Worker entry: decompose every body of one task. ``task`` = (label, bodies, options).

    Reads the cache but never writes it (``write_cache=False``): the caller stores results.
    """
    from meshcol.decomposition.decompose import decompose

    _, bodies, settings = task
    return _each_body(
        bodies,
        lambda mesh: decompose(
            mesh,
            settings.options,
            cache_dir=settings.cache_dir,
            use_cache=settings.use_cache,
            write_cache=False,
            threads=settings.threads,
        ),
    )


def _each_body(
    bodies: list[tuple[str, np.ndarray, np.ndarray]], run: Callable[[Any], Any]
) -> list[tuple[str, Any]]:
    """``run`` on every body, in order; several bodies are a stage of the task's steps
    (:mod:`meshcol.decomposition.steps`), one unit each."""
    if len(bodies) == 1:
        name, vertices, faces = bodies[0]
        return [(name, run((vertices, faces)))]
    results = []
    with stage("body", len(bodies)) as bodies_done:
        bodies_done.note = bodies[0][0] if bodies else None
        for k, (name, vertices, faces) in enumerate(bodies):
            results.append((name, run((vertices, faces))))
            bodies_done.advance(bodies[k + 1][0] if k + 1 < len(bodies) else None)
    return results


def search_task(
    task: tuple[str, list[tuple[str, np.ndarray, np.ndarray]], TaskOptions],
) -> list[tuple[str, Any]]:
    """Worker entry: the fidelity search (:mod:`meshcol.decomposition.search`) of every body
    of one task, for the target of its options. Reads the cache but never writes it: the
    caller stores every step (:func:`store_result`)."""
    from meshcol.decomposition.search import search_decomposition

    _, bodies, settings = task
    target = settings.options.search_target()
    assert target is not None, "a search task needs a target"
    return _each_body(
        bodies,
        lambda mesh: search_decomposition(
            mesh,
            target,
            settings.options,
            cache_dir=settings.cache_dir,
            use_cache=settings.use_cache,
            write_cache=False,
            threads=settings.threads,
        ),
    )


def iter_files(
    inputs: Sequence[str], robot_options: RobotOptions | None = None
) -> Iterator[tuple[str, list[BodyMesh]]]:
    """(file, its bodies) per input file, as each is read
    (:func:`meshcol.io.scene.iter_inputs`, a robot read with ``robot_options``): one task per
    file; a manifest's bodies without a file of their own (primitives) belong to the
    manifest. Each part of a body is a body of its own, as check's colliders decompose it
    (same cache key)."""
    from meshcol.decomposition.canonical import canonical_geometry
    from meshcol.io.scene import iter_inputs

    for source, bodies in iter_inputs(list(inputs), robot_options=robot_options):
        canonical = []
        for body in (part for whole in bodies for part in whole.part_bodies()):
            try:
                v, f = canonical_geometry(body.vertices, body.faces)
            except InvalidMeshError as exc:
                stem = os.path.splitext(os.path.basename(source))[0]
                where = source if body.name == stem else f"{source}: {body.name}"
                raise InvalidMeshError(exc.message, where) from None
            canonical.append((body.name, v, f, body.pose))
        yield source, canonical


def look_up(
    meshes: Sequence[tuple[str, np.ndarray, np.ndarray]],
    options: DecomposeOptions,
    cache_dir: str,
) -> dict[str, Any]:
    """What the cache holds for each named mesh: its replayed search when ``options``
    search, else its decomposition; None where it holds nothing."""
    from meshcol.decomposition.decompose import cached_decomposition
    from meshcol.decomposition.search import cached_search

    target = options.search_target()
    if target is not None:
        return {
            name: cached_search((v, f), target, options, cache_dir=cache_dir)
            for name, v, f in meshes
        }
    return {
        name: cached_decomposition((v, f), options, cache_dir=cache_dir) for name, v, f in meshes
    }


def is_complete(found: Any, options: DecomposeOptions) -> bool:
    """Whether a look-up needs no worker: a search replayed from the cache is complete; a
    plain entry needs its metrics."""
    if found is None:
        return False
    return options.search_target() is not None or found.metrics is not None


def store_result(found: Any, before: Any, cache_root: str, options: DecomposeOptions) -> None:
    """Store what a worker returned for one body: every step of a search; a decomposition
    unless the cache already held it with the same metrics (``before``)."""
    from meshcol.decomposition import cache
    from meshcol.decomposition.search import store_steps

    if options.search_target() is not None:
        store_steps(found, cache_root)
    elif before is None or before.metrics != found.metrics:
        cache.store(found, cache_root)
