"""The typed options of the decomposition floor, each made and validated once where a request
enters.

- :class:`DecomposeOptions`: what decides a decomposition and what a run aims at: the engine
  and its parameters (those of the cache key), the fidelity target and its search, the
  metrics' sampling. ``meshcol decompose`` builds one from its flags and the public functions
  (:func:`meshcol.decompose`, :func:`meshcol.decompose_files`) from their keywords; every stage
  after takes it as it is: the engine's parameter set
  (:func:`meshcol.decomposition.engines.resolve_params`), the cache key, the search's steps,
  the worker tasks, the run manifest's fingerprint and the report's settings.
- :class:`RunOptions`: where a run's decompositions go: worker processes and their timeout,
  the cache, the executor.
- :class:`SearchTarget`: what one body's fidelity search must meet
  (:meth:`DecomposeOptions.search_target`).

Each validates itself in its constructor and raises ValueError with the message users have
always had (``threshold must be in (0, 1], got 0.0``); an object that exists is valid.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from meshcol.decomposition.engines import (
    HULL_COUNT_PARAMETER,
    check_options,
    engine_options_used,
    resolve_params,
)
from meshcol.decomposition.fidelity import DEFAULT_SAMPLES

if TYPE_CHECKING:
    from meshcol.io.targets import Target

__all__ = [
    "DEFAULT_SEARCH_STEPS",
    "DEFAULT_SEARCH_TOLERANCE",
    "ENGINE_FIELDS",
    "SEARCH_MODES",
    "DecomposeOptions",
    "FrozenMapping",
    "RUN_FIELDS",
    "RunOptions",
    "SearchTarget",
    "search_target",
    "split_fields",
]

#: ``--search``: ``auto`` searches when a target is given; ``off`` only checks the target.
SEARCH_MODES = ("auto", "off")
#: Engine calls (cached or not) a body's search may make (``--search-steps``).
DEFAULT_SEARCH_STEPS = 8
#: The search stops when its threshold bracket is this narrow: ``hi / lo <= 1 + tolerance``.
DEFAULT_SEARCH_TOLERANCE = 0.1

#: The fields of :class:`DecomposeOptions` that are the engine's parameters (with the input's
#: geometry, they decide the parts and the cache key), in the order reports list them.
ENGINE_FIELDS = (
    "engine",
    "threshold",
    "max_hulls",
    "max_vertices",
    "preprocess",
    "resolution",
    "seed",
    "engine_options",
)


class FrozenMapping(Mapping[str, Any]):
    """A read-only mapping (the engine options of a frozen :class:`DecomposeOptions`):
    picklable, equal to any mapping with the same items, hashable when its values are."""

    def __init__(self, items: Mapping[str, Any] | None = None) -> None:
        self._items = dict(items or {})

    def __getitem__(self, key: str) -> Any:
        return self._items[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __hash__(self) -> int:
        return hash(tuple(self._items.items()))

    def __repr__(self) -> str:
        return repr(self._items)


@dataclass(frozen=True)
class SearchTarget:
    """What a search must meet, and how long it may look.

    Attributes
    ----------
    max_hausdorff : float or None
        Largest Hausdorff distance, either way, in the input's units.
    max_parts : int or None
        Most parts.
    max_steps : int
        Most steps (decompositions, cached or not) per body.
    tolerance : float
        Relative width of the threshold bracket at which bisection stops.
    """

    max_hausdorff: float | None = None
    max_parts: int | None = None
    max_steps: int = DEFAULT_SEARCH_STEPS
    tolerance: float = DEFAULT_SEARCH_TOLERANCE

    def __post_init__(self) -> None:
        if self.max_hausdorff is None and self.max_parts is None:
            raise ValueError("a search needs max_hausdorff or max_parts")
        if self.max_hausdorff is not None and not (
            math.isfinite(self.max_hausdorff) and self.max_hausdorff >= 0
        ):
            raise ValueError(f"max_hausdorff must be finite and >= 0, got {self.max_hausdorff}")
        if self.max_parts is not None and self.max_parts < 1:
            raise ValueError(f"max_parts must be at least 1, got {self.max_parts}")
        if self.max_steps < 1:
            raise ValueError(f"search steps must be at least 1, got {self.max_steps}")
        if not (math.isfinite(self.tolerance) and self.tolerance > 0):
            raise ValueError(f"search tolerance must be finite and > 0, got {self.tolerance}")

    def to_dict(self) -> dict[str, Any]:
        return {
            "max_hausdorff": self.max_hausdorff,
            "max_parts": self.max_parts,
            "max_steps": self.max_steps,
            "tolerance": self.tolerance,
        }


def search_target(
    max_hausdorff: float | None,
    max_parts: int | None,
    search: str = "auto",
    steps: int = DEFAULT_SEARCH_STEPS,
    tolerance: float = DEFAULT_SEARCH_TOLERANCE,
) -> SearchTarget | None:
    """The target of a run's search, or None when it does not search (``search="off"``, or
    neither limit given: the limits are then only checked).

    Raises
    ------
    ValueError
        An unknown ``search`` mode, or a limit, step count or tolerance out of range.
    """
    if search not in SEARCH_MODES:
        raise ValueError(f"search must be one of {', '.join(SEARCH_MODES)}, got {search!r}")
    if max_parts is not None and max_parts < 1:
        raise ValueError(f"max_parts must be at least 1, got {max_parts}")
    if search == "off" or (max_hausdorff is None and max_parts is None):
        return None
    return SearchTarget(max_hausdorff, max_parts, int(steps), float(tolerance))


@dataclass(frozen=True)
class DecomposeOptions:
    """What decides a decomposition, and what a run of them aims at.

    Attributes
    ----------
    engine : {"coacd", "vhacd"}
        CoACD, or V-HACD (needs ``vhacdx``: ``pip install 'meshcol[vhacd]'``).
    threshold : float, optional
        CoACD's concavity threshold, in (0, 1] (CoACD only; default the engine's 0.05).
    max_hulls : int, optional
        Most parts per body (at least 1).
    max_vertices : int, optional
        Most vertices per part (at least 4): passed to the engine and enforced on every part
        (a part with more is replaced by its budgeted hull, which still encloses it).
    preprocess : {"auto", "on", "off"}
        CoACD's manifold preprocessing; ``auto`` turns it on exactly when the mesh is not a
        closed, consistently oriented manifold.
    resolution : int, optional
        CoACD's sampling resolution or V-HACD's voxel count.
    seed : int
        CoACD's random seed (V-HACD is deterministic when run synchronously).
    engine_options : mapping
        Any other parameter of the engine, by its snake_case name, as given (text included:
        each value is coerced to the type of the parameter).
    max_hausdorff : float, optional
        The fidelity target: the largest Hausdorff distance, either way, in the input's units.
    max_parts : int, optional
        The most parts per body.
    search : {"auto", "off"}
        ``auto``: each body's engine parameters are searched for the target (when one is
        given, :mod:`meshcol.decomposition.search`); ``off``: the target is only checked.
    search_steps : int
        Most decompositions (cached or not) one body's search makes.
    search_tolerance : float
        The search stops when its threshold bracket is this narrow (``hi / lo <= 1 + it``).
    samples : int
        Surface points sampled for the fidelity metrics.
    tolerance : float, optional
        Coverage tolerance of ``uncovered_fraction``; default 1% of the bounding-box diagonal.

    Raises
    ------
    ValueError
        Unknown engine, unknown or ill-typed engine option, a value out of range, a threshold
        for V-HACD, an unknown search mode.
    """

    engine: str = "coacd"
    threshold: float | None = None
    max_hulls: int | None = None
    max_vertices: int | None = None
    preprocess: str = "auto"
    resolution: int | None = None
    seed: int = 0
    engine_options: Mapping[str, Any] = field(default_factory=FrozenMapping)
    max_hausdorff: float | None = None
    max_parts: int | None = None
    search: str = "auto"
    search_steps: int = DEFAULT_SEARCH_STEPS
    search_tolerance: float = DEFAULT_SEARCH_TOLERANCE
    samples: int = DEFAULT_SAMPLES
    tolerance: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "engine_options", FrozenMapping(self.engine_options))
        check_options(self)
        self.search_target()
        if self.tolerance is not None and not (
            math.isfinite(self.tolerance) and self.tolerance >= 0
        ):
            raise ValueError(f"tolerance must be finite and >= 0, got {self.tolerance}")

    @classmethod
    def given(cls, options: DecomposeOptions | None = None, **fields: Any) -> DecomposeOptions:
        """``options`` with ``fields`` replaced, or the options of ``fields`` alone: how a
        public function's keywords become one object."""
        if options is None:
            return cls(**fields)
        return dataclasses.replace(options, **fields) if fields else options

    def search_target(self) -> SearchTarget | None:
        """What each body's search must meet, or None when the run does not search."""
        return search_target(
            self.max_hausdorff,
            self.max_parts,
            self.search,
            self.search_steps,
            self.search_tolerance,
        )

    def step(
        self, threshold: float | None, max_hulls: int | None, resolution: int
    ) -> DecomposeOptions:
        """The options of one step of a search: these three on the engine's axis (a
        V-HACD step keeps the run's threshold, None)."""
        if self.engine != "coacd":
            threshold = self.threshold
        return dataclasses.replace(
            self, threshold=threshold, max_hulls=max_hulls, resolution=resolution
        )

    def aimed_at(self, target: Target) -> DecomposeOptions:
        """The options that aim the engine at an engine target's limits.

        The vertex budget (the tighter of ``max_vertices`` and the target's,
        :func:`meshcol.collision.limits.budget_vertices`) is enforced on every part as
        before; the hull count (the tighter of ``max_hulls`` and the target's) goes to the
        engine's own parameter and ``max_hulls`` becomes None, so that an engine
        overshooting it has its parts merged by
        :func:`meshcol.decomposition.target.apply_target` (still enclosing), never its
        smallest parts dropped.
        """
        from meshcol.collision.limits import budget_vertices

        engine_options = dict(self.engine_options)
        max_vertices = self.max_vertices
        budget = budget_vertices(target.limits)
        if budget is not None:
            max_vertices = budget if max_vertices is None else min(max_vertices, budget)
        count = target.limits.get("max_hulls")
        if self.max_hulls is not None:
            count = self.max_hulls if count is None else min(int(count), self.max_hulls)
        if count is not None:
            key = HULL_COUNT_PARAMETER[self.engine]
            given = engine_options.get(key)
            engine_options[key] = (
                int(count) if given in (None, -1, "-1") else min(int(count), int(given))
            )
        return dataclasses.replace(
            self, max_hulls=None, max_vertices=max_vertices, engine_options=engine_options
        )

    def engine_settings(self) -> dict[str, Any]:
        """The engine's parameters as given (:data:`ENGINE_FIELDS`), JSON-ready."""
        settings = {name: getattr(self, name) for name in ENGINE_FIELDS}
        settings["engine_options"] = dict(self.engine_options)
        return settings

    def report_settings(self) -> dict[str, Any]:
        """The engine's parameters for a report: the fields as given (null: the default),
        the engine options as the engine took them (typed: ``20``, not the flag's ``"20"``),
        and ``engine_parameters``, every parameter of the engine with the value the run used
        (``preprocess_mode`` ``auto`` means per mesh: ``off`` for a closed one, else ``on``;
        each body's ``params`` says which)."""
        settings = self.engine_settings()
        settings["engine_options"] = engine_options_used(self.engine, self.engine_options)
        used = resolve_params(self)
        if self.engine == "coacd" and "preprocess_mode" not in self.engine_options:
            used["preprocess_mode"] = self.preprocess
        settings["engine_parameters"] = used
        return settings

    def result_settings(self) -> dict[str, Any]:
        """What decides a run's results: the engine's parameters and, when it searches, the
        search's target (the run manifest's fingerprint)."""
        settings = self.engine_settings()
        target = self.search_target()
        if target is not None:
            settings["search"] = target.to_dict()
        return settings

    def search_settings(self) -> dict[str, Any]:
        """The report's settings of the fidelity search: ``max_parts``, ``search`` (the
        mode), and ``search_steps``, ``search_tolerance`` (null when the run does not
        search)."""
        target = self.search_target()
        return {
            "max_parts": self.max_parts,
            "search": self.search,
            "search_steps": None if target is None else target.max_steps,
            "search_tolerance": None if target is None else target.tolerance,
        }


#: The fields of :class:`RunOptions`, which the public functions also take as keywords.
RUN_FIELDS = ("jobs", "timeout", "cache_dir", "use_cache", "executor", "ray_address")


@dataclass(frozen=True)
class RunOptions:
    """Where a run's decompositions go.

    Attributes
    ----------
    jobs : int
        Tasks run in parallel processes (1: one at a time, the engine using every core).
    timeout : float, optional
        Seconds allowed per task; a task over it is stopped and reported as ``timeout``.
    cache_dir : path or URL, optional
        Cache folder, possibly on a file system several machines share, or an fsspec URL
        (:mod:`meshcol.decomposition.cache`). Default: the user cache folder.
    use_cache : bool
        False: neither read nor write the cache.
    executor : {"local", "ray"}
        Where the tasks run (:mod:`meshcol.decomposition.executor`).
    ray_address : str, optional
        The Ray cluster to use (default: a local Ray of ``jobs`` CPUs, started and stopped
        by the run).

    Raises
    ------
    ValueError
        ``jobs`` below 1, ``cache_dir`` without the cache, ``ray_address`` without Ray.
    """

    jobs: int = 1
    timeout: float | None = None
    cache_dir: str | None = None
    use_cache: bool = True
    executor: str = "local"
    ray_address: str | None = None

    def __post_init__(self) -> None:
        if self.cache_dir is not None:
            object.__setattr__(self, "cache_dir", os.fspath(self.cache_dir))
        if self.jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {self.jobs}")
        if not self.use_cache and self.cache_dir is not None:
            raise ValueError("cache_dir needs use_cache")
        if self.executor != "ray" and self.ray_address is not None:
            raise ValueError("ray_address needs executor 'ray'")

    @classmethod
    def given(cls, run: RunOptions | None = None, **fields: Any) -> RunOptions:
        """As :meth:`DecomposeOptions.given`."""
        if run is None:
            return cls(**fields)
        return dataclasses.replace(run, **fields) if fields else run

    def cache_root(self) -> str | None:
        """The cache folder or URL (the default one when none is given), None without the
        cache."""
        from meshcol.decomposition.cache import default_cache_dir

        if not self.use_cache:
            return None
        return self.cache_dir if self.cache_dir is not None else str(default_cache_dir())

    def local_cache_folder(self) -> str | None:
        """The cache's local folder, to check before a run; None for a remote URL or no
        cache."""
        from meshcol.decomposition.cache import local_folder

        return local_folder(self.cache_root())

    def threads(self) -> int:
        """Each task's share of the cores for its distance queries (0: all of them, when
        one task runs at a time)."""
        return 0 if self.jobs == 1 else max(1, (os.cpu_count() or 1) // self.jobs)

    def settings(self) -> dict[str, Any]:
        """``jobs``, ``timeout``, ``cache_dir`` (the folder or URL used: the default one
        when none was given; null without the cache) and ``use_cache``, for reports."""
        return {
            "jobs": self.jobs,
            "timeout": self.timeout,
            "cache_dir": self.cache_root(),
            "use_cache": self.use_cache,
        }


def split_fields(
    options: DecomposeOptions | None, run: RunOptions | None, fields: Mapping[str, Any]
) -> tuple[DecomposeOptions, RunOptions]:
    """The keywords of a public function (fields of either class) as the two objects."""
    run_fields = {k: v for k, v in fields.items() if k in RUN_FIELDS}
    option_fields = {k: v for k, v in fields.items() if k not in RUN_FIELDS}
    return DecomposeOptions.given(options, **option_fields), RunOptions.given(run, **run_fields)
