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
from collections.abc import Mapping
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
from meshcol.decomposition.fidelity import DEFAULT_SAMPLES, coverage_tolerance, fidelity
from meshcol.decomposition.result import Decomposition, Fidelity
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import is_closed_manifold, orient_outward

__all__ = ["cached_decomposition", "decompose"]


# --------------------------------------------------------------------------------------------
# input


# --------------------------------------------------------------------------------------------
# parameters and cache keys


# --------------------------------------------------------------------------------------------
# engines


# --------------------------------------------------------------------------------------------
# public entry points


#: The end of the note of a cache entry stored before parts over ``max_hulls`` were merged
#: (an earlier meshcol kept the largest and dropped the rest): such an entry is decomposed again.
_DROPPED_NOTE = " largest (max_hulls)"


def _merge_parts(
    parts: list[tuple[np.ndarray, np.ndarray, float]],
    reduced: list[bool],
    count: int,
    budget: int | None,
) -> tuple[list[tuple[np.ndarray, np.ndarray, float]], list[bool]]:
    """At most ``count`` parts, groups merged by :func:`meshcol.collision.target_fit.merge_groups`,
    each group's part the canonical hull of its parts' vertices (budgeted as every part), with
    whether each was reduced to the vertex budget."""
    from meshcol.collision.target_fit import merge_groups

    merged: list[tuple[np.ndarray, np.ndarray, float]] = []
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
    *,
    engine: str = "coacd",
    threshold: float | None = None,
    max_hulls: int | None = None,
    max_vertices: int | None = None,
    preprocess: str = "auto",
    resolution: int | None = None,
    seed: int = 0,
    engine_options: Mapping[str, Any] | None = None,
    metrics: bool = True,
    samples: int = DEFAULT_SAMPLES,
    tolerance: float | None = None,
    cache_dir: str | None = None,
    use_cache: bool = True,
    write_cache: bool = True,
    threads: int = 0,
) -> Decomposition:
    """Convex decomposition of a mesh, from the cache when possible, stored in it otherwise.

    Parameters
    ----------
    mesh : Body, trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        The mesh, in any frame; parts come back in the same frame.
    engine : {"coacd", "vhacd"}
        CoACD (default) or V-HACD (needs ``vhacdx``: ``pip install 'meshcol[vhacd]'``).
    threshold, max_hulls, max_vertices, preprocess, resolution, seed, engine_options
        See :func:`resolve_params`. ``max_vertices`` is enforced on every part: a part whose
        hull has more vertices is replaced by the budgeted hull of
        :func:`meshcol.collision.hull.convex_hull`, which still encloses the part.
    metrics : bool
        Compute :class:`Fidelity` metrics (stored in the cache with the parts).
    samples : int
        Surface points sampled for the metrics.
    tolerance : float, optional
        Coverage tolerance for ``uncovered_fraction``; default 1% of the bounding-box diagonal.
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

    Returns
    -------
    Decomposition

    Raises
    ------
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
    outward mesh, and a note says so.
    CoACD: Wei et al., "Approximate convex decomposition for 3D meshes with collision-aware
    concavity and tree search", SIGGRAPH 2022.
    """
    vertices, faces = canonical_geometry(*as_mesh_arrays(mesh))
    closed = is_closed_manifold(faces)
    params = resolve_params(
        engine,
        threshold=threshold,
        max_hulls=max_hulls,
        max_vertices=max_vertices,
        preprocess=preprocess,
        resolution=resolution,
        seed=seed,
        closed=closed,
        engine_options=engine_options,
    )
    version = engine_version(engine)
    key = cache_key(vertices, faces, engine, version, params)
    # An inside-out input is the same solid: the engine and the metrics get it outward (CoACD
    # decomposes an inverted mesh badly); the key keeps the input's winding, so the note
    # stored with the entry is true of every input that finds it.
    faces, flipped = orient_outward(vertices, faces)
    if flipped:
        faces = canonical_faces(faces)  # exactly the outward mesh's canonical faces
    tol = coverage_tolerance(vertices, tolerance)
    if use_cache:
        hit = cache.load(key, cache_dir)
        if hit is not None and any(note.endswith(_DROPPED_NOTE) for note in hit.notes):
            hit = None  # made before parts over max_hulls were merged: they were dropped
        if hit is not None:
            if not metrics or _metrics_match(hit.metrics, samples, tol):
                return hit
            # Same parts, other sampling settings: measure again, keep the parts.
            remeasured = fidelity(
                vertices, faces, hit.parts, samples=samples, tolerance=tol, threads=threads
            )
            hit = dataclasses.replace(hit, metrics=remeasured)
            if write_cache:
                cache.store(hit, cache_dir)
            return hit

    raw = run_engine(engine, vertices, faces, params)
    budget = max_vertices
    parts: list[tuple[np.ndarray, np.ndarray, float]] = []
    reduced_flags: list[bool] = []
    dropped = 0
    for part_vertices, _ in raw:
        canon = canonical_part(part_vertices, budget)
        if canon is None:
            dropped += 1
            continue
        parts.append(canon[:3])
        reduced_flags.append(canon[3])
    if not parts:
        raise InvalidMeshError(f"{engine} returned no part with a volume")
    merged_from = 0
    if max_hulls is not None and len(parts) > max_hulls:
        # The engines treat the hull count as a target; never exceed it, and never lose what a
        # part covers: the parts whose merged hull adds the least volume are merged (the hull
        # of a group encloses each of its parts), within the vertex budget as every part.
        merged_from = len(parts)
        parts, reduced_flags = _merge_parts(parts, reduced_flags, max_hulls, budget)
    order = sorted(
        range(len(parts)),
        key=lambda i: (*parts[i][0].mean(axis=0).tolist(), parts[i][2], len(parts[i][0])),
    )
    parts_sorted = tuple((parts[i][0], parts[i][1]) for i in order)
    notes = []
    if flipped:
        notes.append("input is inside out (negative volume): decomposed with its faces reversed")
    repaired = engine == "coacd" and params["preprocess_mode"] == "on" and not closed
    if repaired:
        notes.append(
            "input is not a closed manifold: CoACD's preprocessing rebuilt it before decomposing"
        )
    elif not closed:
        notes.append("input is not a closed manifold: the engine decomposed it as given")
    if dropped:
        notes.append(f"dropped {dropped} flat part(s) the engine returned")
    if merged_from:
        notes.append(
            f"{engine} returned {merged_from} parts: merged into {len(parts_sorted)} "
            "(max_hulls; each merged part is the hull of the parts it replaces)"
        )
    reduced = sum(reduced_flags)
    if reduced:
        notes.append(f"reduced {reduced} part(s) to at most {budget} vertices (enclosing hull)")
    result = Decomposition(
        parts=parts_sorted,
        engine=engine,
        engine_version=version,
        params=params,
        cache_key=key,
        metrics=(
            fidelity(vertices, faces, parts_sorted, samples=samples, tolerance=tol, threads=threads)
            if metrics
            else None
        ),
        repaired=repaired,
        notes=tuple(notes),
    )
    if use_cache and write_cache:
        cache.store(result, cache_dir)
    return result


def cached_decomposition(
    mesh: Any, *, cache_dir: str | None = None, **options: Any
) -> Decomposition | None:
    """The cached decomposition of ``mesh`` for these options, or None; never runs an engine.

    Takes the same options as :func:`decompose` (``metrics``, ``samples``, ``tolerance``,
    ``use_cache``, ``write_cache`` and ``threads`` are ignored: metrics come back as stored).
    """
    for ignored in ("metrics", "samples", "tolerance", "use_cache", "write_cache", "threads"):
        options.pop(ignored, None)
    engine = options.pop("engine", "coacd")
    vertices, faces = canonical_geometry(*as_mesh_arrays(mesh))
    params = resolve_params(engine, closed=is_closed_manifold(faces), **options)
    key = cache_key(vertices, faces, engine, engine_version(engine), params)
    return cache.load(key, cache_dir)


def _metrics_match(m: Fidelity | None, samples: int, tolerance: float) -> bool:
    return m is not None and m.samples == samples and m.tolerance == tolerance


# --------------------------------------------------------------------------------------------
# fidelity
