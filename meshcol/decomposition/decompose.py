"""Convex decomposition: engines, canonical parts, a content-addressed cache, fidelity metrics.

A decomposition replaces a triangle mesh by a few convex parts whose union approximates it.
:func:`decompose` runs an engine (CoACD by default, V-HACD through ``vhacdx`` as the second),
turns its output into canonical convex parts (each part is the convex hull of the engine's
part, vertices in lexicographic order, outward triangles in a fixed order; parts sorted by
centroid then volume), measures how faithful the result is, and stores it in a
content-addressed cache so that the next call with the same geometry and parameters costs
milliseconds. :func:`cached_decomposition` only looks the cache up (``meshcol check --shape
decomposed`` uses it).

Frames: parts are in the frame of the vertices given (a :class:`~meshcol.types.Body`'s local
frame); nothing here applies a body's pose.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.decomposition import cache
from meshcol.decomposition.canonical import (
    as_mesh_arrays,
    cache_key,
    canonical_faces,
    canonical_geometry,
    canonical_part,
)
from meshcol.decomposition.engines import engine_version, resolve_params, run_engine
from meshcol.decomposition.fidelity import coverage_tolerance, fidelity
from meshcol.decomposition.options import DecomposeOptions
from meshcol.decomposition.result import Decomposition, Fidelity
from meshcol.decomposition.steps import stage
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import is_closed_manifold, orient_outward

__all__ = ["cached_decomposition", "decompose"]


#: The end of the note of a cache entry stored before parts over ``max_hulls`` were merged
#: (an earlier meshcol kept the largest and dropped the rest): such an entry is decomposed again.
_DROPPED_NOTE = " largest (max_hulls)"

#: Parts as the stages pass them on: (vertices (n, 3) float, faces (m, 3) int, volume).
_Part = tuple[np.ndarray, np.ndarray, float]


@dataclass(frozen=True)
class _Input:
    """A mesh made ready for the engine and the cache: canonical, outward, keyed."""

    vertices: np.ndarray
    faces: np.ndarray  #: canonical and outward (the input's own winding is in the key)
    closed: bool
    flipped: bool  #: the input was inside out
    params: dict[str, Any]
    version: str
    key: str
    tolerance: float  #: the metrics' coverage tolerance


def _prepare(mesh: Any, options: DecomposeOptions) -> _Input:
    """Canonical geometry, the engine's parameters and the cache key of ``mesh``."""
    vertices, faces = canonical_geometry(*as_mesh_arrays(mesh))
    closed = is_closed_manifold(faces)
    params = resolve_params(options, closed=closed)
    version = engine_version(options.engine)
    key = cache_key(vertices, faces, options.engine, version, params)
    # An inside-out input is the same solid: the engine and the metrics get it outward (CoACD
    # decomposes an inverted mesh badly); the key keeps the input's winding, so the note
    # stored with the entry is true of every input that finds it.
    outward, flipped = orient_outward(vertices, faces)
    if flipped:
        outward = canonical_faces(outward)  # exactly the outward mesh's canonical faces
    tolerance = coverage_tolerance(vertices, options.tolerance)
    return _Input(vertices, outward, closed, flipped, params, version, key, tolerance)


def _merge_parts(
    parts: list[_Part], reduced: list[bool], count: int, budget: int | None
) -> tuple[list[_Part], list[bool]]:
    """At most ``count`` parts, groups merged by :func:`meshcol.collision.target_fit.merge_groups`,
    each group's part the canonical hull of its parts' vertices (budgeted as every part), with
    whether each was reduced to the vertex budget."""
    from meshcol.collision.target_fit import merge_groups

    merged: list[_Part] = []
    flags: list[bool] = []
    for group in merge_groups([v for v, _, _ in parts], count):
        if len(group) == 1:
            merged.append(parts[group[0]])
            flags.append(reduced[group[0]])
            continue
        canon = canonical_part(np.vstack([parts[i][0] for i in group]), budget)
        if canon is None:  # cannot happen: the parts had volume, so does their hull
            raise InvalidMeshError("merging parts over max_hulls left a flat hull")
        merged.append(canon[:3])
        flags.append(canon[3])
    return merged, flags


def decompose(
    mesh: Any,
    options: DecomposeOptions | None = None,
    *,
    metrics: bool = True,
    cache_dir: str | None = None,
    use_cache: bool = True,
    write_cache: bool = True,
    threads: int = 0,
    **fields: Any,
) -> Decomposition:
    """Convex decomposition of a mesh, from the cache when possible, stored in it otherwise.

    Parameters
    ----------
    mesh : Body, trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        The mesh, in any frame; parts come back in the same frame.
    options : DecomposeOptions, optional
        The engine, its parameters and the metrics' sampling (``samples``, ``tolerance``).
    metrics : bool
        Compute :class:`Fidelity` metrics (stored in the cache with the parts).
    cache_dir : str, optional
        Cache folder; default :func:`meshcol.cache.default_cache_dir`.
    use_cache : bool
        Read and write the cache.
    write_cache : bool
        False: read the cache but leave storing the result to the caller (``meshcol
        decompose`` stores what its worker processes return, so that a worker killed or
        interrupted never writes an entry).
    threads : int
        Threads for the metrics' distance queries; 0 uses all cores.
    **fields
        Fields of :class:`DecomposeOptions` (``engine="vhacd"``, ``threshold=0.02``), which
        replace those of ``options``.

    Returns
    -------
    Decomposition

    Raises
    ------
    ValueError
        Options that :class:`DecomposeOptions` refuses.
    InvalidMeshError
        Empty, non-finite or flat mesh.
    MissingDependencyError
        The engine's package is not installed.

    Notes
    -----
    Determinism: the engine runs on the canonical geometry (:func:`canonical_geometry`) with a
    fixed seed, and parts are canonicalised and sorted, so equal inputs give equal parts. A
    closed input wound inside out (negative volume) is decomposed with its faces reversed
    (:func:`meshcol.geometry.topology.orient_outward`), so it gets the parts and metrics of the
    outward mesh, and a note says so. ``max_vertices`` is enforced on every part: a part whose
    hull has more vertices is replaced by the budgeted hull of
    :func:`meshcol.collision.hull.convex_hull`, which still encloses the part.
    CoACD: Wei et al., "Approximate convex decomposition for 3D meshes with collision-aware
    concavity and tree search", SIGGRAPH 2022.
    """
    options = DecomposeOptions.given(options, **fields)
    source = _prepare(mesh, options)
    if use_cache:
        hit = _from_cache(source, options, metrics, cache_dir, write_cache, threads)
        if hit is not None:
            return hit
    result = _decomposition(source, options, metrics, threads)
    if use_cache and write_cache:
        cache.store(result, cache_dir)
    return result


def _from_cache(
    source: _Input,
    options: DecomposeOptions,
    metrics: bool,
    cache_dir: str | None,
    write_cache: bool,
    threads: int,
) -> Decomposition | None:
    """The cache's entry of ``source``, measured again (and stored) when its metrics were
    sampled otherwise; None when there is none (or one made before parts were merged)."""
    hit = cache.load(source.key, cache_dir)
    if hit is None or any(note.endswith(_DROPPED_NOTE) for note in hit.notes):
        return None  # an entry made before parts over max_hulls were merged: they were dropped
    if not metrics or _metrics_match(hit.metrics, options.samples, source.tolerance):
        return hit
    # Same parts, other sampling settings: measure again, keep the parts.
    remeasured = _measure(source, options, hit.parts, threads)
    hit = dataclasses.replace(hit, metrics=remeasured)
    if write_cache:
        cache.store(hit, cache_dir)
    return hit


def _measure(
    source: _Input,
    options: DecomposeOptions,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    threads: int,
) -> Fidelity:
    return fidelity(
        source.vertices,
        source.faces,
        parts,
        samples=options.samples,
        tolerance=source.tolerance,
        threads=threads,
    )


#: The engines as the progress line names them.
_ENGINE_NAMES = {"coacd": "CoACD", "vhacd": "V-HACD"}


def _measured(
    source: _Input,
    options: DecomposeOptions,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    threads: int,
) -> Fidelity:
    """:func:`_measure` as a stage of the task's steps (the fidelity check)."""
    with stage("fidelity check"):
        return _measure(source, options, parts, threads)


def _decomposition(
    source: _Input, options: DecomposeOptions, metrics: bool, threads: int
) -> Decomposition:
    """Run the engine: its parts canonical, within the budgets, sorted, noted and measured."""
    with stage(_ENGINE_NAMES.get(options.engine, options.engine)):
        raw = run_engine(options.engine, source.vertices, source.faces, source.params)
    parts, reduced, dropped = _canonical_parts(raw, options)
    merged_from = 0
    if options.max_hulls is not None and len(parts) > options.max_hulls:
        # The engines treat the hull count as a target; never exceed it, and never lose what a
        # part covers: the parts whose merged hull adds the least volume are merged (the hull
        # of a group encloses each of its parts), within the vertex budget as every part.
        merged_from = len(parts)
        parts, reduced = _merge_parts(parts, reduced, options.max_hulls, options.max_vertices)
    order = sorted(
        range(len(parts)),
        key=lambda i: (*parts[i][0].mean(axis=0).tolist(), parts[i][2], len(parts[i][0])),
    )
    parts_sorted = tuple((parts[i][0], parts[i][1]) for i in order)
    repaired = options.engine == "coacd" and source.params["preprocess_mode"] == "on"
    repaired = repaired and not source.closed
    counts = {"dropped": dropped, "merged_from": merged_from, "reduced": sum(reduced)}
    return Decomposition(
        parts=parts_sorted,
        engine=options.engine,
        engine_version=source.version,
        params=source.params,
        cache_key=source.key,
        metrics=_measured(source, options, parts_sorted, threads) if metrics else None,
        repaired=repaired,
        notes=_notes(source, options, repaired, len(parts_sorted), counts),
    )


def _canonical_parts(raw: list, options: DecomposeOptions) -> tuple[list[_Part], list[bool], int]:
    """The engine's parts as canonical hulls within ``max_vertices``: the parts, whether
    each was reduced to the budget, and how many flat ones were dropped."""
    parts: list[_Part] = []
    reduced: list[bool] = []
    dropped = 0
    for part_vertices, _ in raw:
        canon = canonical_part(part_vertices, options.max_vertices)
        if canon is None:
            dropped += 1
            continue
        parts.append(canon[:3])
        reduced.append(canon[3])
    if not parts:
        raise InvalidMeshError(f"{options.engine} returned no part with a volume")
    return parts, reduced, dropped


def _notes(
    source: _Input, options: DecomposeOptions, repaired: bool, parts: int, counts: dict[str, int]
) -> tuple[str, ...]:
    """What a decomposition's reader should know: the input's winding and repair, and the
    parts dropped, merged or reduced."""
    notes = []
    if source.flipped:
        notes.append("input is inside out (negative volume): decomposed with its faces reversed")
    if repaired:
        notes.append(
            "input is not a closed manifold: CoACD's preprocessing rebuilt it before decomposing"
        )
    elif not source.closed:
        notes.append("input is not a closed manifold: the engine decomposed it as given")
    if counts["dropped"]:
        notes.append(f"dropped {counts['dropped']} flat part(s) the engine returned")
    if counts["merged_from"]:
        notes.append(
            f"{options.engine} returned {counts['merged_from']} parts: merged into {parts} "
            "(max_hulls; each merged part is the hull of the parts it replaces)"
        )
    if counts["reduced"]:
        notes.append(
            f"reduced {counts['reduced']} part(s) to at most {options.max_vertices} vertices "
            "(enclosing hull)"
        )
    return tuple(notes)


#: Keywords of :func:`decompose` that a cache look-up does not use.
_LOOKUP_IGNORES = ("metrics", "use_cache", "write_cache", "threads")


def cached_decomposition(
    mesh: Any,
    options: DecomposeOptions | None = None,
    *,
    cache_dir: str | None = None,
    **fields: Any,
) -> Decomposition | None:
    """The cached decomposition of ``mesh`` for these options, or None; never runs an engine.

    Takes the options of :func:`decompose` (``metrics``, ``use_cache``, ``write_cache`` and
    ``threads`` are ignored, and so are the metrics' ``samples`` and ``tolerance``: metrics
    come back as stored).
    """
    for ignored in _LOOKUP_IGNORES:
        fields.pop(ignored, None)
    options = DecomposeOptions.given(options, **fields)
    vertices, faces = canonical_geometry(*as_mesh_arrays(mesh))
    params = resolve_params(options, closed=is_closed_manifold(faces))
    key = cache_key(vertices, faces, options.engine, engine_version(options.engine), params)
    return cache.load(key, cache_dir)


def _metrics_match(m: Fidelity | None, samples: int, tolerance: float) -> bool:
    return m is not None and m.samples == samples and m.tolerance == tolerance
