"""The decomposition engines (CoACD, V-HACD): their parameters, versions and one call each."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from meshcol.errors import MissingDependencyError

__all__ = ["ENGINES", "engine_version", "prepare_engine", "resolve_params", "run_engine"]


ENGINES = ("coacd", "vhacd")


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


def engine_version(engine: str) -> str:
    """Installed version of an engine's package; raises MissingDependencyError if absent."""
    import importlib.metadata  # here: 25 ms to import, and every command's --engine imports us

    package = {"coacd": "coacd", "vhacd": "vhacdx"}[engine]
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        hint = "pip install coacd" if engine == "coacd" else "pip install 'meshcol[vhacd]'"
        raise MissingDependencyError(
            f"engine {engine!r} needs the {package} package: {hint}"
        ) from None


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
            raise ValueError(
                f"{engine} option {key!r} must be {kind.__name__}, got {value!r}"
            ) from None
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


def run_engine(
    engine: str, vertices: np.ndarray, faces: np.ndarray, params: Mapping[str, Any]
) -> list:
    if engine == "coacd":
        try:
            import coacd
        except ImportError:
            raise MissingDependencyError(
                "engine 'coacd' needs the coacd package: pip install coacd"
            ) from None
        coacd.set_log_level("error")
        p = dict(params)
        return coacd.run_coacd(coacd.Mesh(vertices, faces), **p)
    try:
        import vhacdx
    except ImportError:
        raise MissingDependencyError(
            "engine 'vhacd' needs the vhacdx package: pip install 'meshcol[vhacd]'"
        ) from None
    hulls = vhacdx.compute_vhacd(
        np.ascontiguousarray(vertices, dtype=np.float64),
        np.ascontiguousarray(faces, dtype=np.uint32),
        maxConvexHulls=params["max_convex_hulls"],
        resolution=params["resolution"],
        minimumVolumePercentErrorAllowed=params["minimum_volume_percent_error_allowed"],
        maxRecursionDepth=params["max_recursion_depth"],
        shrinkWrap=params["shrink_wrap"],
        fillMode=params["fill_mode"],
        maxNumVerticesPerCH=params["max_num_vertices_per_ch"],
        # Synchronous: the asynchronous mode's thread timing must not change the result.
        asyncACD=False,
        minEdgeLength=params["min_edge_length"],
        findBestPlane=params["find_best_plane"],
    )
    # vhacdx returns (vertices (n, 3) float64, faces (m, 3) uint32); older builds returned a
    # flat face list: accept both.
    return [(np.asarray(v, dtype=np.float64), np.asarray(f).reshape(-1, 3)) for v, f in hulls]


def prepare_engine(engine: str) -> None:
    """Worker start-up: import the engine's module (and so its OpenMP runtime) ahead of the
    first task."""
    if engine == "coacd":
        import coacd  # noqa: F401
    elif engine == "vhacd":
        import vhacdx  # noqa: F401
