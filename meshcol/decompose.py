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
frame); nothing here applies a body's transform.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.errors import InvalidMeshError, MissingDependencyError
from meshcol.inspect import is_closed_manifold

__all__ = [
    "ENGINES",
    "Decomposition",
    "Fidelity",
    "decompose",
    "cached_decomposition",
    "convex_parts",
    "resolve_params",
    "canonical_geometry",
    "cache_key",
    "fidelity",
]

ENGINES = ("coacd", "vhacd")

# Bump when the cache entry layout or the canonicalisation of inputs or parts changes.
CACHE_FORMAT = 1

# Fidelity sampling defaults (points on the mesh surface and on the parts' surfaces).
DEFAULT_SAMPLES = 2000
DEFAULT_METRIC_SEED = 0
# Coverage tolerance as a fraction of the mesh's bounding-box diagonal.
DEFAULT_TOLERANCE_FRACTION = 0.01
# A point of a part's surface this close (fraction of the diagonal) to another part is on a
# face shared with it (a cut), not on the boundary of the union.
SHARED_FACE_FRACTION = 1e-6
# Relative size under which the mesh counts as flat (singular values of the centred vertices).
FLAT_FRACTION = 1e-9

# Engine parameters meshcol exposes, with their defaults (None = the engine's default or
# derived from a common option). The names are the engines' own, in snake_case.
_COACD_DEFAULTS: dict[str, Any] = {
    "threshold": 0.05,
    "max_convex_hull": -1,
    "preprocess_mode": "auto",
    "preprocess_resolution": 50,
    "resolution": 2000,
    "mcts_nodes": 20,
    "mcts_iterations": 150,
    "mcts_max_depth": 3,
    "pca": False,
    "merge": True,
    "decimate": False,
    "max_ch_vertex": 256,
    "extrude": False,
    "extrude_margin": 0.01,
    "apx_mode": "ch",
    "seed": 0,
}
_VHACD_DEFAULTS: dict[str, Any] = {
    "max_convex_hulls": 64,
    "resolution": 400000,
    "minimum_volume_percent_error_allowed": 1.0,
    "max_recursion_depth": 10,
    "shrink_wrap": True,
    "fill_mode": "flood",
    "max_num_vertices_per_ch": 64,
    "min_edge_length": 2,
    "find_best_plane": False,
}


@dataclass(frozen=True)
class Fidelity:
    """How faithfully the parts approximate the mesh.

    Attributes
    ----------
    parts : int
        Number of convex parts.
    vertices_per_part : tuple of int
        Hull vertex count of each part, in part order.
    mesh_volume : float or None
        Volume of the mesh (manifold3d; None when the mesh does not bound a volume).
    union_volume : float
        Volume of the union of the parts (manifold3d boolean union of the part hulls).
    volume_ratio : float or None
        ``union_volume / mesh_volume``.
    hausdorff_mesh_to_parts : float
        Largest distance from a sampled point of the mesh surface to the union of the parts
        (0 inside a part), computed with :func:`meshcol.query.distance_batch`.
    hausdorff_parts_to_mesh : float
        Largest distance from a sampled point of the boundary of the union of the parts to the
        mesh surface (exact point-triangle distances).
    uncovered_fraction : float
        Fraction of the sampled mesh surface points farther than ``tolerance`` from the union.
    tolerance : float
        Coverage tolerance, in mesh units.
    samples : int
        Points sampled on the mesh surface (the parts get as many).
    """

    parts: int
    vertices_per_part: tuple[int, ...]
    mesh_volume: float | None
    union_volume: float
    volume_ratio: float | None
    hausdorff_mesh_to_parts: float
    hausdorff_parts_to_mesh: float
    uncovered_fraction: float
    tolerance: float
    samples: int

    def as_dict(self) -> dict[str, Any]:
        return {
            "parts": self.parts,
            "vertices_per_part": list(self.vertices_per_part),
            "mesh_volume": self.mesh_volume,
            "union_volume": self.union_volume,
            "volume_ratio": self.volume_ratio,
            "hausdorff_mesh_to_parts": self.hausdorff_mesh_to_parts,
            "hausdorff_parts_to_mesh": self.hausdorff_parts_to_mesh,
            "uncovered_fraction": self.uncovered_fraction,
            "tolerance": self.tolerance,
            "samples": self.samples,
        }


@dataclass(frozen=True, eq=False)
class Decomposition:
    """A convex decomposition of one mesh.

    Attributes
    ----------
    parts : tuple of ((n_i, 3) float64, (m_i, 3) int64)
        Convex parts as (vertices, faces), in the input's frame; each part is its own convex
        hull with outward-oriented triangles. Sorted by centroid (x, y, z), then volume.
    engine : str
        ``"coacd"`` or ``"vhacd"``.
    engine_version : str
        Installed version of the engine's package.
    params : dict
        The engine parameters used, after defaults and ``auto`` were resolved.
    cache_key : str
        sha256 hex digest of the canonical geometry, engine, engine version and parameters.
    metrics : Fidelity or None
        Fidelity metrics, unless they were turned off.
    repaired : bool
        True when the input was not a closed, consistently oriented manifold and the engine's
        preprocessing rebuilt it (CoACD ``preprocess_mode="on"``).
    notes : tuple of str
        Remarks for the report (repairs, dropped flat parts, vertex budgets enforced).
    from_cache : bool
        True when this result was read from the cache.
    """

    parts: tuple[tuple[np.ndarray, np.ndarray], ...]
    engine: str
    engine_version: str
    params: Mapping[str, Any]
    cache_key: str
    metrics: Fidelity | None = None
    repaired: bool = False
    notes: tuple[str, ...] = ()
    from_cache: bool = field(default=False, compare=False)

    def meshes(self) -> list[Any]:
        """The parts as ``trimesh.Trimesh`` objects."""
        import trimesh

        return [trimesh.Trimesh(v, f, process=False) for v, f in self.parts]


# --------------------------------------------------------------------------------------------
# input


def _as_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a Body, a trimesh.Trimesh or a (vertices, faces) pair."""
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        vertices, faces = mesh.vertices, mesh.faces
    elif isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices, faces = mesh
    else:
        raise TypeError("mesh must be a Body, a trimesh.Trimesh or a (vertices, faces) pair")
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidMeshError(f"vertices must be (n, 3), got {vertices.shape}")
    if faces.size == 0:
        raise InvalidMeshError("mesh has no faces")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidMeshError(f"faces must be (m, 3), got {faces.shape}")
    return vertices, faces.astype(np.int64, copy=False)


def canonical_geometry(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh in a canonical form that does not depend on vertex or face order.

    Vertices with bit-identical coordinates are merged (``-0.0`` counts as ``0.0``), unused
    vertices dropped, and the rest sorted lexicographically; each triangle is rotated so its
    smallest index comes first (winding kept), triangles that collapsed are dropped, duplicates
    removed, and triangles sorted.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    vertices : (k, 3) float64, C-contiguous
    faces : (l, 3) int64, C-contiguous

    Raises
    ------
    InvalidMeshError
        No faces, indices out of range, non-finite coordinates, or a flat mesh.
    """
    vertices, faces = _as_arrays((vertices, faces))
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMeshError("face indices out of range")
    used = np.unique(faces)
    if not np.isfinite(vertices[used]).all():
        raise InvalidMeshError("mesh has non-finite vertex coordinates")
    unique, inverse = _unique_rows(vertices[used] + 0.0)
    remap = np.empty(len(vertices), dtype=np.int64)
    remap[used] = inverse
    f = remap[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    if len(f) == 0:
        raise InvalidMeshError("mesh has no faces with three distinct vertices")
    shift = np.argmin(f, axis=1)
    rows = np.arange(len(f))[:, None]
    f = f[rows, (shift[:, None] + np.arange(3)) % 3]
    f, _ = _unique_rows(f)
    # Vertices only referenced by dropped triangles go too.
    used = np.unique(f)
    if len(used) != len(unique):
        remap = np.full(len(unique), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        unique, f = unique[used], remap[f]
    centred = unique - unique.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    if len(unique) < 4 or singular[-1] <= FLAT_FRACTION * max(singular[0], 1e-300):
        raise InvalidMeshError("mesh is flat (all vertices lie in one plane): it encloses no volume")
    return np.ascontiguousarray(unique), np.ascontiguousarray(f)


def _unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct rows in lexicographic order and, per input row, its index among them.

    The same result as ``np.unique(rows, axis=0, return_inverse=True)``, several times faster.
    """
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    start = np.ones(len(rows), dtype=bool)
    start[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    group = np.cumsum(start) - 1
    inverse = np.empty(len(rows), dtype=np.int64)
    inverse[order] = group
    return ordered[start], inverse


# --------------------------------------------------------------------------------------------
# parameters and cache keys


def engine_version(engine: str) -> str:
    """Installed version of an engine's package; raises MissingDependencyError if absent."""
    package = {"coacd": "coacd", "vhacd": "vhacdx"}[engine]
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        hint = "pip install coacd" if engine == "coacd" else "pip install 'meshcol[vhacd]'"
        raise MissingDependencyError(f"engine {engine!r} needs the {package} package: {hint}") from None


def resolve_params(
    engine: str = "coacd",
    *,
    threshold: float | None = None,
    max_hulls: int | None = None,
    max_vertices: int | None = None,
    preprocess: str = "auto",
    resolution: int | None = None,
    seed: int = 0,
    closed: bool = True,
    engine_options: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The engine's full parameter set for the common options.

    Parameters
    ----------
    engine : {"coacd", "vhacd"}
    threshold : float, optional
        CoACD concavity threshold (CoACD only).
    max_hulls : int, optional
        Most parts per body.
    max_vertices : int, optional
        Most vertices per part (at least 4). Passed to the engine and enforced afterwards.
    preprocess : {"auto", "on", "off"}
        CoACD manifold preprocessing; ``auto`` turns it on exactly when the mesh is not a
        closed, consistently oriented manifold (``closed``).
    resolution : int, optional
        CoACD sampling resolution or V-HACD voxel count.
    seed : int
        CoACD random seed (V-HACD is deterministic when run synchronously).
    closed : bool
        Whether the canonical input is a closed manifold (for ``preprocess="auto"``).
    engine_options : mapping, optional
        Any other parameter of the engine, by its snake_case name (see ``_COACD_DEFAULTS``,
        ``_VHACD_DEFAULTS``).

    Raises
    ------
    ValueError
        Unknown engine, unknown or ill-typed option.
    """
    engine_options = dict(engine_options or {})
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}: choose one of {', '.join(ENGINES)}")
    if max_vertices is not None and max_vertices < 4:
        raise ValueError(f"max_vertices must be at least 4, got {max_vertices}")
    if max_hulls is not None and max_hulls < 1:
        raise ValueError(f"max_hulls must be at least 1, got {max_hulls}")
    if preprocess not in ("auto", "on", "off"):
        raise ValueError(f"preprocess must be auto, on or off, got {preprocess!r}")
    defaults = _COACD_DEFAULTS if engine == "coacd" else _VHACD_DEFAULTS
    unknown = sorted(set(engine_options) - set(defaults))
    if unknown:
        raise ValueError(
            f"unknown {engine} option {unknown[0]!r}: known options are {', '.join(sorted(defaults))}"
        )
    params = dict(defaults)
    for key, value in engine_options.items():
        kind = type(defaults[key])
        try:
            params[key] = _coerce(value, kind)
        except (TypeError, ValueError):
            raise ValueError(f"{engine} option {key!r} must be {kind.__name__}, got {value!r}") from None
    if engine == "coacd":
        if threshold is not None:
            params["threshold"] = float(threshold)
        if not 0.0 < params["threshold"] <= 1.0:
            raise ValueError(f"threshold must be in (0, 1], got {params['threshold']}")
        if max_hulls is not None:
            params["max_convex_hull"] = int(max_hulls)
        if max_vertices is not None:
            params["decimate"] = True
            params["max_ch_vertex"] = int(max_vertices)
        if resolution is not None:
            params["resolution"] = int(resolution)
        params["seed"] = int(seed)
        mode = preprocess if "preprocess_mode" not in engine_options else params["preprocess_mode"]
        if mode == "auto":
            mode = "off" if closed else "on"
        params["preprocess_mode"] = mode
    else:
        if threshold is not None:
            raise ValueError("threshold applies to the coacd engine only")
        if max_hulls is not None:
            params["max_convex_hulls"] = int(max_hulls)
        if max_vertices is not None:
            params["max_num_vertices_per_ch"] = int(max_vertices)
        if resolution is not None:
            params["resolution"] = int(resolution)
    return params


def _coerce(value: Any, kind: type) -> Any:
    if kind is bool:
        if isinstance(value, str):
            if value.lower() in ("1", "true", "yes", "on"):
                return True
            if value.lower() in ("0", "false", "no", "off"):
                return False
            raise ValueError(value)
        return bool(value)
    if kind is int and isinstance(value, float) and not value.is_integer():
        raise ValueError(value)
    return kind(value)


def cache_key(
    vertices: np.ndarray, faces: np.ndarray, engine: str, version: str, params: Mapping[str, Any]
) -> str:
    """sha256 hex digest of canonical geometry, engine, engine version and parameters.

    ``vertices`` and ``faces`` must already be canonical (:func:`canonical_geometry`); their
    exact float64 and int64 little-endian bytes are hashed.
    """
    h = hashlib.sha256()
    header = {"format": CACHE_FORMAT, "engine": engine, "version": version, "params": dict(params)}
    h.update(json.dumps(header, sort_keys=True).encode())
    h.update(np.int64(len(vertices)).tobytes())
    h.update(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(faces, dtype="<i8").tobytes())
    return h.hexdigest()


# --------------------------------------------------------------------------------------------
# engines


def _run_engine(engine: str, vertices: np.ndarray, faces: np.ndarray, params: Mapping[str, Any]) -> list:
    if engine == "coacd":
        try:
            import coacd
        except ImportError:
            raise MissingDependencyError("engine 'coacd' needs the coacd package: pip install coacd") from None
        coacd.set_log_level("error")
        p = dict(params)
        return coacd.run_coacd(coacd.Mesh(vertices, faces), **p)
    try:
        import vhacdx
    except ImportError:
        raise MissingDependencyError(
            "engine 'vhacd' needs the vhacdx package: pip install 'meshcol[vhacd]'"
        ) from None
    p = params
    hulls = vhacdx.compute_vhacd(
        np.ascontiguousarray(vertices, dtype=np.float64),
        np.ascontiguousarray(faces, dtype=np.uint32),
        maxConvexHulls=p["max_convex_hulls"],
        resolution=p["resolution"],
        minimumVolumePercentErrorAllowed=p["minimum_volume_percent_error_allowed"],
        maxRecursionDepth=p["max_recursion_depth"],
        shrinkWrap=p["shrink_wrap"],
        fillMode=p["fill_mode"],
        maxNumVerticesPerCH=p["max_num_vertices_per_ch"],
        # Synchronous: the asynchronous mode's thread timing must not change the result.
        asyncACD=False,
        minEdgeLength=p["min_edge_length"],
        findBestPlane=p["find_best_plane"],
    )
    # vhacdx returns (vertices (n, 3) float64, faces (m, 3) uint32); older builds returned a
    # flat face list: accept both.
    return [(np.asarray(v, dtype=np.float64), np.asarray(f).reshape(-1, 3)) for v, f in hulls]


def _greedy_hull_subset(points: np.ndarray, budget: int) -> np.ndarray:
    """At most ``budget`` of ``points`` whose hull best approximates theirs (from inside).

    Starts from a large tetrahedron and repeatedly adds the point farthest outside the current
    hull (the quickhull insertion order, stopped early). The result lies inside the original
    hull, so it can only lose coverage; the fidelity metrics show how much.
    """
    from scipy.spatial import ConvexHull

    i0 = int(np.lexsort(points.T[::-1])[0])
    chosen = [i0]
    d = np.linalg.norm(points - points[i0], axis=1)
    chosen.append(int(np.argmax(d)))
    a, b = points[chosen[0]], points[chosen[1]]
    ab = (b - a) / np.linalg.norm(b - a)
    rel = points - a
    d = np.linalg.norm(rel - np.outer(rel @ ab, ab), axis=1)
    chosen.append(int(np.argmax(d)))
    n = np.cross(b - a, points[chosen[2]] - a)
    chosen.append(int(np.argmax(np.abs(rel @ n))))
    while len(chosen) < budget:
        eq = ConvexHull(points[chosen]).equations
        outside = (points @ eq[:, :3].T + eq[:, 3]).max(axis=1)
        outside[chosen] = -np.inf
        k = int(np.argmax(outside))
        if outside[k] <= 0.0:
            break
        chosen.append(k)
    return points[np.sort(chosen)]


def _canonical_part(points: np.ndarray, budget: int | None) -> tuple[np.ndarray, np.ndarray, float, bool] | None:
    """(vertices, faces, volume, reduced) of the hull of ``points``, or None when it is flat."""
    from scipy.spatial import ConvexHull
    from scipy.spatial import QhullError

    points = np.unique(np.asarray(points, dtype=np.float64) + 0.0, axis=0)
    if len(points) < 4:
        return None
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    points = points[np.sort(hull.vertices)]
    reduced = False
    if budget is not None and len(points) > budget:
        points = _greedy_hull_subset(points, budget)
        reduced = True
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    if hull.volume <= 0.0:
        return None
    keep = np.unique(hull.simplices)
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    vertices = points[keep]  # still lexicographic: np.unique sorted them and we kept order
    faces = remap[hull.simplices]
    v0, v1, v2 = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(v1 - v0, v2 - v0), hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, [0, 2, 1]]
    shift = np.argmin(faces, axis=1)
    faces = faces[np.arange(len(faces))[:, None], (shift[:, None] + np.arange(3)) % 3]
    faces = faces[np.lexsort(faces.T[::-1])]
    return np.ascontiguousarray(vertices), np.ascontiguousarray(faces), float(hull.volume), reduced


# --------------------------------------------------------------------------------------------
# public entry points


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
        hull has more vertices is replaced by the hull of a greedy subset of them (farthest
        point outside first), which lies inside the original part.
    metrics : bool
        Compute :class:`Fidelity` metrics (stored in the cache with the parts).
    samples : int
        Surface points sampled for the metrics.
    tolerance : float, optional
        Coverage tolerance for ``uncovered_fraction``; default 1% of the bounding-box diagonal.
    cache_dir : str, optional
        Cache folder; default :func:`meshcol.decompose_cache.default_cache_dir`.
    use_cache : bool
        Read and write the cache.
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
    fixed seed, and parts are canonicalised and sorted, so equal inputs give equal parts.
    CoACD: Wei et al., "Approximate convex decomposition for 3D meshes with collision-aware
    concavity and tree search", SIGGRAPH 2022.
    """
    from meshcol import decompose_cache

    vertices, faces = canonical_geometry(*_as_arrays(mesh))
    closed = is_closed_manifold(faces)
    params = resolve_params(
        engine, threshold=threshold, max_hulls=max_hulls, max_vertices=max_vertices,
        preprocess=preprocess, resolution=resolution, seed=seed, closed=closed,
        engine_options=engine_options,
    )
    version = engine_version(engine)
    key = cache_key(vertices, faces, engine, version, params)
    tol = _tolerance(vertices, tolerance)
    if use_cache:
        hit = decompose_cache.load(key, cache_dir)
        if hit is not None:
            if not metrics or _metrics_match(hit.metrics, samples, tol):
                return hit
            # Same parts, other sampling settings: measure again, keep the parts.
            remeasured = fidelity(vertices, faces, hit.parts, samples=samples, tolerance=tol, threads=threads)
            hit = dataclasses.replace(hit, metrics=remeasured)
            decompose_cache.store(hit, cache_dir)
            return hit

    raw = _run_engine(engine, vertices, faces, params)
    budget = max_vertices
    parts: list[tuple[np.ndarray, np.ndarray, float]] = []
    dropped = reduced = 0
    for part_vertices, _ in raw:
        canon = _canonical_part(part_vertices, budget)
        if canon is None:
            dropped += 1
            continue
        parts.append(canon[:3])
        reduced += canon[3]
    if not parts:
        raise InvalidMeshError(f"{engine} returned no part with a volume")
    order = sorted(
        range(len(parts)),
        key=lambda i: (*parts[i][0].mean(axis=0).tolist(), parts[i][2], len(parts[i][0])),
    )
    parts_sorted = tuple((parts[i][0], parts[i][1]) for i in order)
    if max_hulls is not None and len(parts_sorted) > max_hulls:
        # The engines treat the hull count as a target; never exceed it: keep the largest.
        by_volume = sorted(order, key=lambda i: -parts[i][2])[:max_hulls]
        keep = set(by_volume)
        parts_sorted = tuple((parts[i][0], parts[i][1]) for i in order if i in keep)
        truncated = len(parts) - max_hulls
    else:
        truncated = 0
    notes = []
    repaired = engine == "coacd" and params["preprocess_mode"] == "on" and not closed
    if repaired:
        notes.append("input is not a closed manifold: CoACD's preprocessing rebuilt it before decomposing")
    elif not closed:
        notes.append("input is not a closed manifold: the engine decomposed it as given")
    if dropped:
        notes.append(f"dropped {dropped} flat part(s) the engine returned")
    if truncated:
        notes.append(f"{engine} returned {len(parts)} parts: kept the {max_hulls} largest (max_hulls)")
    if reduced:
        notes.append(f"reduced {reduced} part(s) to at most {budget} vertices (greedy hull subset)")
    result = Decomposition(
        parts=parts_sorted,
        engine=engine,
        engine_version=version,
        params=params,
        cache_key=key,
        metrics=(fidelity(vertices, faces, parts_sorted, samples=samples, tolerance=tol, threads=threads)
                 if metrics else None),
        repaired=repaired,
        notes=tuple(notes),
    )
    if use_cache:
        decompose_cache.store(result, cache_dir)
    return result


def cached_decomposition(mesh: Any, *, cache_dir: str | None = None, **options: Any) -> Decomposition | None:
    """The cached decomposition of ``mesh`` for these options, or None; never runs an engine.

    Takes the same options as :func:`decompose` (``metrics``, ``samples``, ``tolerance`` and
    ``use_cache``, ``threads`` are ignored: metrics come back as stored).
    """
    from meshcol import decompose_cache

    for ignored in ("metrics", "samples", "tolerance", "use_cache", "threads"):
        options.pop(ignored, None)
    engine = options.pop("engine", "coacd")
    vertices, faces = canonical_geometry(*_as_arrays(mesh))
    params = resolve_params(engine, closed=is_closed_manifold(faces), **options)
    key = cache_key(vertices, faces, engine, engine_version(engine), params)
    return decompose_cache.load(key, cache_dir)


def _tolerance(vertices: np.ndarray, tolerance: float | None) -> float:
    if tolerance is not None:
        if not (math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance must be finite and >= 0, got {tolerance}")
        return float(tolerance)
    return DEFAULT_TOLERANCE_FRACTION * float(np.linalg.norm(np.ptp(vertices, axis=0)))


def _metrics_match(m: Fidelity | None, samples: int, tolerance: float) -> bool:
    return m is not None and m.samples == samples and m.tolerance == tolerance


# --------------------------------------------------------------------------------------------
# fidelity


def _sample_surface(vertices: np.ndarray, faces: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` points uniformly distributed on the triangles (area-weighted), (count, 3)."""
    tri = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    total = area.sum()
    if count <= 0 or total <= 0:
        return np.empty((0, 3))
    which = rng.choice(len(faces), size=count, p=area / total)
    r1, r2 = rng.random(count), rng.random(count)
    s = np.sqrt(r1)
    t = tri[which]
    return (1 - s)[:, None] * t[:, 0] + (s * (1 - r2))[:, None] * t[:, 1] + (s * r2)[:, None] * t[:, 2]


def points_to_parts(
    points: np.ndarray,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    owner: np.ndarray | None = None,
    *,
    threads: int = 0,
) -> np.ndarray:
    """Distance from each point to the union of convex parts (0 inside a part), (n,) float64.

    Each point is a one-vertex polytope; candidate (point, part) pairs are pruned with AABBs
    (a part whose box is farther than the point's nearest part centroid cannot be the closest)
    and measured in one :func:`meshcol.query.distance_batch` call. ``owner[i]`` (optional)
    excludes part ``owner[i]`` from point ``i``'s candidates.
    """
    from meshcol.query import ConvexSet, distance_batch

    points = np.ascontiguousarray(points, dtype=np.float64)
    n, k = len(points), len(parts)
    lo = np.array([v.min(axis=0) for v, _ in parts])
    hi = np.array([v.max(axis=0) for v, _ in parts])
    centre = np.array([v.mean(axis=0) for v, _ in parts])  # inside the hull: an upper bound
    result = np.full(n, np.inf)
    pairs_i, pairs_j = [], []
    chunk = max(1, 4_000_000 // max(k, 1))
    for start in range(0, n, chunk):
        p = points[start:start + chunk]
        gap = np.maximum(np.maximum(lo[None] - p[:, None], p[:, None] - hi[None]), 0.0)
        lower = np.linalg.norm(gap, axis=2)
        upper = np.linalg.norm(p[:, None] - centre[None], axis=2)
        if owner is not None:
            own = owner[start:start + chunk]
            lower[np.arange(len(p)), own] = np.inf
            upper[np.arange(len(p)), own] = np.inf
        bound = upper.min(axis=1)
        i, j = np.nonzero(lower <= bound[:, None])
        pairs_i.append(i + start)
        pairs_j.append(j)
    i = np.concatenate(pairs_i)
    j = np.concatenate(pairs_j)
    if len(i) == 0:
        return result
    shapes = ConvexSet.concatenate(
        ConvexSet.from_vertices(list(points[:, None, :])),
        ConvexSet.from_vertices([v for v, _ in parts]),
    )
    pairs = np.stack([i, n + j], axis=1).astype(np.int64)
    batch = distance_batch(shapes, None, pairs, threads=threads)
    # fmin skips NaN (a pair the query rejected): a point whose pairs all failed stays inf.
    np.fmin.at(result, i, np.asarray(batch.distance, dtype=np.float64))
    return result


def points_to_triangles(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Exact distance from each point to the nearest triangle, (n,) float64.

    An upper bound comes from the exact distances to the triangles with the nearest
    centroids; then every triangle whose centroid lies within (bound + its bounding radius) is
    measured. Triangles are binned by radius (powers of two) so a few large triangles do not
    widen the search for all. Closest point on a triangle follows Ericson, Real-Time Collision
    Detection (2004), 5.1.5.
    """
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=np.float64)
    tri = vertices[faces]
    centroid = tri.mean(axis=1)
    radius = np.linalg.norm(tri - centroid[:, None], axis=2).max(axis=1)
    k = min(8, len(faces))
    _, near = cKDTree(centroid).query(points, k=k)
    near = near.reshape(len(points), k)
    upper = _point_triangle_distance(np.repeat(points, k, axis=0), tri[near.reshape(-1)])
    result = upper.reshape(len(points), k).min(axis=1)
    level = np.floor(np.log2(np.maximum(radius, 1e-300))).astype(np.int64)
    for lv in np.unique(level):
        members = np.nonzero(level == lv)[0]
        reach = result + float(radius[members].max())
        candidates = cKDTree(centroid[members]).query_ball_point(points, reach, return_sorted=False)
        lengths = np.fromiter(map(len, candidates), dtype=np.int64, count=len(points))
        if lengths.sum() == 0:
            continue
        pi = np.repeat(np.arange(len(points)), lengths)
        ti = members[np.concatenate([np.asarray(c, dtype=np.int64) for c in candidates])]
        for start in range(0, len(pi), 1_000_000):
            a, b = pi[start:start + 1_000_000], ti[start:start + 1_000_000]
            np.minimum.at(result, a, _point_triangle_distance(points[a], tri[b]))
    return result


def _point_triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance from each point (n, 3) to its triangle (n, 3, 3) (Ericson 2004, 5.1.5)."""
    from meshcol.hulls import closest_points_on_triangles

    return np.linalg.norm(p - closest_points_on_triangles(p, tri), axis=1)


def _manifold_volume(vertices: np.ndarray, faces: np.ndarray) -> float | None:
    import manifold3d

    m = manifold3d.Manifold(
        manifold3d.Mesh64(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.uint64))
        if hasattr(manifold3d, "Mesh64") else
        manifold3d.Mesh(np.ascontiguousarray(vertices, dtype=np.float32), np.ascontiguousarray(faces, dtype=np.uint32))
    )
    if m.status() != manifold3d.Error.NoError or m.is_empty():
        return None
    return float(m.volume())


def fidelity(
    vertices: np.ndarray,
    faces: np.ndarray,
    parts: tuple[tuple[np.ndarray, np.ndarray], ...],
    *,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_METRIC_SEED,
    tolerance: float | None = None,
    threads: int = 0,
) -> Fidelity:
    """Fidelity metrics of ``parts`` against the mesh (``vertices``, ``faces``).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        Convex parts in the mesh's frame.
    samples : int
        Points sampled on the mesh surface, and as many on the parts' surfaces.
    seed : int
        Sampling seed (fixed: the metrics are deterministic).
    tolerance : float, optional
        Coverage tolerance; default 1% of the bounding-box diagonal.
    threads : int
        Threads for the distance queries; 0 uses all cores.

    Notes
    -----
    mesh -> parts: sampled mesh surface points plus the mesh vertices (at most ``samples`` of
    them, chosen with the same seed), distance to the union of
    the parts by :func:`points_to_parts` (our GJK distance queries).
    parts -> mesh: sampled part surface points on the boundary of the union (a point within
    ``SHARED_FACE_FRACTION`` of the diagonal of another part lies on a cut shared between parts
    and is skipped), exact distance to the mesh triangles (:func:`points_to_triangles`).
    Volumes: manifold3d (hull of each part, boolean union; the mesh itself when manifold).
    """
    import manifold3d

    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    tol = _tolerance(vertices, tolerance)
    diag = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    rng = np.random.default_rng(seed)
    corners = vertices if len(vertices) <= samples else vertices[np.sort(rng.choice(len(vertices), samples, replace=False))]
    mesh_points = np.concatenate([_sample_surface(vertices, faces, samples, rng), corners])
    to_parts = points_to_parts(mesh_points, parts, threads=threads)

    areas = np.array([_area(v, f) for v, f in parts])
    counts = np.maximum(1, np.round(samples * areas / areas.sum()).astype(np.int64))
    part_points = np.concatenate([_sample_surface(v, f, int(c), rng) for (v, f), c in zip(parts, counts)])
    owner = np.repeat(np.arange(len(parts)), counts)
    if len(parts) > 1:
        shared = points_to_parts(part_points, parts, owner, threads=threads) <= SHARED_FACE_FRACTION * diag
        part_points = part_points[~shared]
    to_mesh = points_to_triangles(part_points, vertices, faces) if len(part_points) else np.zeros(1)

    hulls = [manifold3d.Manifold.hull_points(np.ascontiguousarray(v)) for v, _ in parts]
    union = manifold3d.Manifold.batch_boolean(hulls, manifold3d.OpType.Add)
    union_volume = float(union.volume())
    mesh_volume = _manifold_volume(vertices, faces)
    return Fidelity(
        parts=len(parts),
        vertices_per_part=tuple(len(v) for v, _ in parts),
        mesh_volume=mesh_volume,
        union_volume=union_volume,
        volume_ratio=None if not mesh_volume else union_volume / mesh_volume,
        hausdorff_mesh_to_parts=float(to_parts.max()),
        hausdorff_parts_to_mesh=float(to_mesh.max()),
        uncovered_fraction=float((to_parts > tol).mean()),
        tolerance=tol,
        samples=samples,
    )


def _area(vertices: np.ndarray, faces: np.ndarray) -> float:
    t = vertices[faces]
    return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())


def convex_parts(mesh: Any, **options: Any) -> list[np.ndarray]:
    """Vertices of the convex parts of ``mesh`` (its frame), for collision queries.

    Taken from the cache when ``meshcol decompose`` (or an earlier call) stored them for the
    same geometry and options; otherwise decomposed now, without fidelity metrics, and cached.

    Parameters
    ----------
    mesh : Body, trimesh mesh or (vertices, faces)
    **options
        As :func:`decompose` (``engine``, ``threshold``, ``cache_dir``, ...).

    Returns
    -------
    list of (n_i, 3) float64
    """
    result = cached_decomposition(mesh, **options)
    if result is None:
        result = decompose(mesh, **{**options, "metrics": False})
    return [np.asarray(v, dtype=np.float64) for v, _ in result.parts]
