"""The decomposition engines (CoACD, V-HACD): their parameters, versions and one call each."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import MissingDependencyError

if TYPE_CHECKING:
    from meshcol.decomposition.options import DecomposeOptions

__all__ = [
    "ENGINES",
    "HULL_COUNT_PARAMETER",
    "check_options",
    "engine_version",
    "prepare_engine",
    "resolve_params",
    "run_engine",
]


ENGINES = ("coacd", "vhacd")

#: The engine parameter of each engine's hull count (a target's ``max_hulls`` goes there, so
#: that meshcol merges any excess parts, enclosing, rather than drop them).
HULL_COUNT_PARAMETER = {"coacd": "max_convex_hull", "vhacd": "max_convex_hulls"}


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


# The range of each numeric engine parameter: (least, greatest), None for no bound; a float
# must also be finite. Outside it the engine misbehaves silently (a negative iteration count
# runs no search) or loops: refused when the options are made.
_RANGES: dict[str, tuple[float | None, float | None]] = {
    "max_convex_hull": (-1, None),  # -1: no limit
    "preprocess_resolution": (1, None),
    "resolution": (1, None),
    "mcts_nodes": (1, None),
    "mcts_iterations": (1, None),
    "mcts_max_depth": (1, None),
    "max_ch_vertex": (4, None),
    "extrude_margin": (0, None),
    "seed": (0, None),
    "max_convex_hulls": (1, None),
    "minimum_volume_percent_error_allowed": (0, 100),
    "max_recursion_depth": (1, None),
    "max_num_vertices_per_ch": (4, None),
    "min_edge_length": (1, None),
}


def _check_range(engine: str, key: str, value: Any) -> None:
    """ValueError naming the option when a number is non-finite or out of its range."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return
    if not math.isfinite(value):
        raise ValueError(f"{engine} option {key!r} must be finite, got {value!r}")
    low, high = _RANGES.get(key, (None, None))
    if (low is not None and value < low) or (high is not None and value > high):
        bounds = f">= {low:g}" if high is None else f"in [{low:g}, {high:g}]"
        raise ValueError(f"{engine} option {key!r} must be {bounds}, got {value!r}")


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


def check_options(options: DecomposeOptions) -> None:
    """Raise ValueError for what the engine cannot take: an unknown engine, a budget out of
    range, an unknown preprocessing mode, an unknown or ill-typed engine option, a threshold
    out of (0, 1] or given to V-HACD. :class:`DecomposeOptions` calls it once, when made."""
    if options.engine not in ENGINES:
        raise ValueError(f"unknown engine {options.engine!r}: choose one of {', '.join(ENGINES)}")
    if options.max_vertices is not None and options.max_vertices < 4:
        raise ValueError(f"max_vertices must be at least 4, got {options.max_vertices}")
    if options.max_hulls is not None and options.max_hulls < 1:
        raise ValueError(f"max_hulls must be at least 1, got {options.max_hulls}")
    if options.preprocess not in ("auto", "on", "off"):
        raise ValueError(f"preprocess must be auto, on or off, got {options.preprocess!r}")
    given = _engine_options(options.engine, options.engine_options)
    if options.engine == "coacd":
        threshold = options.threshold
        if threshold is None:
            threshold = given.get("threshold", _COACD_DEFAULTS["threshold"])
        if not 0.0 < float(threshold) <= 1.0:
            raise ValueError(f"threshold must be in (0, 1], got {float(threshold)}")
    elif options.threshold is not None:
        raise ValueError("threshold applies to the coacd engine only")


def resolve_params(options: DecomposeOptions, *, closed: bool = True) -> dict[str, Any]:
    """The engine's full parameter set (the cache key's) for ``options``.

    Parameters
    ----------
    options : DecomposeOptions
        Valid by construction (:func:`check_options`).
    closed : bool
        Whether the canonical input is a closed manifold (for ``preprocess="auto"``).

    Returns
    -------
    dict
        Every parameter of ``_COACD_DEFAULTS`` or ``_VHACD_DEFAULTS``, by the engine's
        snake_case name: the defaults, then the engine options, then the common options.
    """
    defaults = _COACD_DEFAULTS if options.engine == "coacd" else _VHACD_DEFAULTS
    params = {**defaults, **_engine_options(options.engine, options.engine_options)}
    if options.engine == "coacd":
        return _coacd_params(params, options, closed)
    return _vhacd_params(params, options)


def engine_options_used(engine: str, engine_options: Mapping[str, Any]) -> dict[str, Any]:
    """The engine options as the engine takes them: coerced to their parameters' types."""
    return _engine_options(engine, engine_options)


def _engine_options(engine: str, engine_options: Mapping[str, Any]) -> dict[str, Any]:
    """The engine options coerced to their parameters' types; ValueError for an unknown or
    ill-typed one."""
    defaults = _COACD_DEFAULTS if engine == "coacd" else _VHACD_DEFAULTS
    unknown = sorted(set(engine_options) - set(defaults))
    if unknown:
        raise ValueError(
            f"unknown {engine} option {unknown[0]!r}: known options are {', '.join(sorted(defaults))}"
        )
    coerced = {}
    for key, value in engine_options.items():
        kind = type(defaults[key])
        try:
            coerced[key] = _coerce(value, kind)
        except (TypeError, ValueError):
            raise ValueError(
                f"{engine} option {key!r} must be {kind.__name__}, got {value!r}"
            ) from None
        _check_range(engine, key, coerced[key])
    return coerced


def _coacd_params(
    params: dict[str, Any], options: DecomposeOptions, closed: bool
) -> dict[str, Any]:
    if options.threshold is not None:
        params["threshold"] = float(options.threshold)
    if options.max_hulls is not None:
        params["max_convex_hull"] = int(options.max_hulls)
    if options.max_vertices is not None:
        params["decimate"] = True
        params["max_ch_vertex"] = int(options.max_vertices)
    if options.resolution is not None:
        params["resolution"] = int(options.resolution)
    params["seed"] = int(options.seed)
    given = "preprocess_mode" in options.engine_options
    mode = params["preprocess_mode"] if given else options.preprocess
    if mode == "auto":
        mode = "off" if closed else "on"
    params["preprocess_mode"] = mode
    return params


def _vhacd_params(params: dict[str, Any], options: DecomposeOptions) -> dict[str, Any]:
    if options.max_hulls is not None:
        params["max_convex_hulls"] = int(options.max_hulls)
    if options.max_vertices is not None:
        params["max_num_vertices_per_ch"] = int(options.max_vertices)
    if options.resolution is not None:
        params["resolution"] = int(options.resolution)
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
