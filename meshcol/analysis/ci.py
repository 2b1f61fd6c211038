"""``meshcol ci``: every configured inspect, hull, fit and check over a repository, as one run.

The stages: :func:`plan` (every file the configuration names, the commands it runs with its
resolved settings, each checked once here: rule names, targets, ignore rules), then
:func:`run_ci` (each job looked up in the result cache, :mod:`meshcol.decomposition.
result_cache`, by its file's content, settings and meshcol's version; the misses run as
tasks of one process pool, :func:`meshcol.decomposition.executor.run_each`, each confined
to the root, :func:`meshcol.io.paths.confined_to`), then one :class:`~meshcol.analysis.
ci_report.CiReport` (one verdict, one exit code, every format). ``changed`` (``--changed-
since``) limits the run to the jobs whose file, or a file it read, changed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import os
import subprocess
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from meshcol.analysis.ci_report import REPORT_KEYS, CiReport, CiRun
from meshcol.errors import MeshcolError
from meshcol.io.config import Config, ConfigError, Resolved, resolve_all

__all__ = [
    "Job",
    "changed_files",
    "job_pair_cache",
    "plan",
    "repository_root",
    "result_store",
    "run_ci",
    "run_job",
]


@dataclass(frozen=True)
class Job:
    """One command on one file: its settings as the command takes them (JSON values), the
    files besides the input whose content it depends on (baseline, target profile)."""

    command: str
    path: str
    kind: str
    settings: Mapping[str, Any]
    sections: tuple[str, ...] = ()
    extra_files: tuple[str, ...] = field(default_factory=tuple)

    @property
    def label(self) -> str:
        return f"{self.command} {self.path}"


def _origin_error(resolved: Resolved, config: Config, key: str, problem: str) -> ConfigError:
    origin = resolved.origins.get(key, "default")
    if origin.startswith(config.path.name + ":"):
        where = f"{config.path}:{origin.rsplit(':', 1)[1]}"
        return ConfigError(f"{key}: {problem} (for {resolved.path})", where)
    return ConfigError(f"{key}: {problem} (from {origin}, for {resolved.path})")


def _ignored_rules(resolved: Resolved, config: Config, command: str) -> tuple[str, ...]:
    from meshcol.analysis.rules import UnknownRuleError, select_rules

    rules: list[str] = []
    for entry in resolved.values["ignore"]:
        if "rule" in entry:
            try:
                rules.extend(select_rules(entry["rule"], command))
            except UnknownRuleError:
                continue  # a rule of another command: not this one's to ignore
    return tuple(rules)


def _settings(resolved: Resolved, config: Config, command: str) -> dict[str, Any]:
    """The settings of one command, checked (rule names, levels, ignore entries, target):
    a bad one is a ConfigError naming the key and its line."""
    from meshcol.analysis.rules import UnknownRuleError, select_rules
    from meshcol.io.targets import load_target

    values = resolved.command_settings(command)
    out: dict[str, Any] = {
        k: v for k, v in values.items() if k not in ("ignore", "fail-on", "baseline")
    }
    ignored = _ignored_rules(resolved, config, command)
    out["ignored_rules"] = list(ignored)
    if values["target"] is not None:
        try:
            load_target(_in_folder(config, values["target"]))
        except MeshcolError as exc:
            raise _origin_error(resolved, config, "target", exc.message) from None
    for entry in values["ignore"]:
        if "rule" not in entry and "pair" not in entry:
            raise _origin_error(resolved, config, "ignore", "an entry needs 'rule' or 'pair'")
    if command == "inspect":
        try:
            fail_on = select_rules(values["fail-on"], "inspect")
        except UnknownRuleError as exc:
            raise _origin_error(resolved, config, "inspect.fail-on", str(exc)) from None
        out["fail-on"] = [rule for rule in fail_on if rule not in ignored]
    if command == "check":
        from meshcol.analysis.check_policy import failing_rules, parse_ignore_rule

        try:
            rules = failing_rules(values["fail-on"], target=values["target"] is not None)
        except UnknownRuleError as exc:
            raise _origin_error(resolved, config, "check.fail-on", str(exc)) from None
        kept = [rule for rule in rules if rule not in ignored]
        out["fail-on"] = values["fail-on"] if len(kept) == len(rules) else ",".join(kept) or "none"
        pairs = [entry["pair"] for entry in values["ignore"] if "pair" in entry]
        for pair in pairs:
            try:
                parse_ignore_rule(pair)
            except ValueError as exc:
                raise _origin_error(resolved, config, "ignore", str(exc)) from None
        out["ignore"] = pairs
        out["baseline"] = values["baseline"]
    return out


def _checked(
    resolved: Resolved, config: Config, command: str
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """A command's settings checked (:func:`_settings`) and the files besides the input
    they name (a baseline, a target's .toml), whose content is part of the job's key."""
    settings = _settings(resolved, config, command)
    named = [("baseline", settings.get("baseline")), ("target", settings["target"])]
    extra = tuple(
        _in_folder(config, value)
        for key, value in named
        if isinstance(value, str) and (key == "baseline" or value.endswith(".toml"))
    )
    return settings, extra


def _in_folder(config: Config, path: str) -> str:
    return _in_folder_path(os.fspath(config.folder), path)


def plan(
    config: Config,
    overrides: Mapping[str, tuple[Any, str]] = {},
    files: Iterable[str] | None = None,
) -> list[Job]:
    """Every job of the configuration: per file the sections match (``files``: default
    every file under the config's folder), per command it runs, in file then command order.

    Raises
    ------
    ConfigError
        A setting no command accepts (an unknown rule, a bad ``ignore`` entry, a target
        that does not load), naming the key and its line.
    """
    jobs = []
    # one check per resolution the files share
    checked: dict[tuple[int, str], tuple[dict[str, Any], tuple[str, ...]]] = {}
    listed = files if files is not None else config.files()
    for path, resolutions in resolve_all(config, listed, overrides):
        for resolved in resolutions:
            for command in resolved.commands:
                memo = (id(resolved.values), command)
                if memo not in checked:
                    named = dataclasses.replace(resolved, path=path)  # for its messages
                    checked[memo] = _checked(named, config, command)
                settings, extra = checked[memo]
                jobs.append(Job(command, path, resolved.kind, settings, resolved.sections, extra))
    return jobs


def changed_files(folder: str | os.PathLike[str], ref: str) -> set[str]:
    """Files changed since ``ref`` (``git diff --name-only REF``, and files git does not
    track yet), relative to ``folder``, ``/``-separated.

    Raises
    ------
    MeshcolError
        Not a git repository, or an unknown ``ref`` (git's words).
    """
    out: set[str] = set()
    for args in (
        ["diff", "--name-only", "--relative", ref, "--"],
        ["ls-files", "--others", "--exclude-standard"],
    ):
        try:
            done = subprocess.run(
                ["git", "-C", os.fspath(folder), *args],
                capture_output=True,
                text=True,
                check=False,
            )
        except OSError as exc:
            raise MeshcolError(f"--changed-since needs git: {exc}") from None
        if done.returncode != 0:
            words = " ".join(done.stderr.split()) or f"git {' '.join(args)} failed"
            raise MeshcolError(f"--changed-since {ref}: {words}")
        out.update(line.strip() for line in done.stdout.splitlines() if line.strip())
    return out


def repository_root(folder: str | os.PathLike[str]) -> str:
    """The top folder of the git repository holding ``folder``; ``folder`` itself outside
    one (or without git)."""
    try:
        done = subprocess.run(
            ["git", "-C", os.fspath(folder), "rev-parse", "--show-toplevel"],
            capture_output=True,
            text=True,
            check=False,
        )
    except OSError:
        return os.fspath(folder)
    top = done.stdout.strip()
    return top if done.returncode == 0 and top else os.fspath(folder)


# --- one job -------------------------------------------------------------------------------------


def _robot(settings: Mapping[str, Any], folder: str) -> Any:
    from meshcol.io.robot import RobotOptions

    srdf = settings["srdf"]
    packages = {
        name: os.path.join(folder, path) for name, path in settings["package-paths"].items()
    }
    return RobotOptions(
        dict(settings["joints"]),
        settings["keyframe"],
        packages,
        None if srdf is None else os.path.join(folder, srdf),
        settings["include-adjacent"],
    )


def _execute(job: Job, folder: str, pair_cache: Any = None) -> Any:
    """Run the job's command in this process; its report (a check keeps its pairs'
    answers in ``pair_cache``, :class:`meshcol.analysis.pair_cache.PairCache`)."""
    from meshcol.io.targets import load_target

    s = job.settings
    _confine_named(s, folder)
    target = None if s["target"] is None else load_target(_in_folder_path(folder, s["target"]))
    robot = _robot(s, folder)
    if job.command == "inspect":
        from meshcol.analysis.inspect import inspect
        from meshcol.analysis.physics import PhysicsOptions

        physics = PhysicsOptions(
            shape=s["shape"],
            volume_ratio=s["volume-ratio"],
            com_offset=s["com-offset"],
            inertia_ratio=s["inertia-ratio"],
            min_relative_volume=s["min-relative-volume"],
            min_volume=s["min-volume"],
            target=target,
        )
        return inspect(
            [job.path], fail_on=tuple(s["fail-on"]), physics=physics, robot_options=robot
        )
    if job.command == "hull":
        from meshcol.analysis.hull import hull

        return hull([job.path], max_vertices=s["max-vertices"], target=target, robot_options=robot)
    if job.command == "fit":
        from meshcol.analysis.fit import fit

        return fit(
            [job.path],
            shape=s["shape"],
            volume_tolerance=s["volume-tolerance"],
            robot_options=robot,
        )
    from meshcol.analysis.check import check

    baseline = s["baseline"]
    return check(
        [job.path],
        collider=s["shape"],
        tolerance=s["tolerance"],
        clearance=s["clearance"],
        fail_on=s["fail-on"],
        ignore=tuple(s["ignore"]),
        baseline=None if baseline is None else os.path.join(folder, baseline),
        target=target,
        robot_options=robot,
        pair_cache=pair_cache,
    )


def _confine_named(settings: Mapping[str, Any], folder: str) -> None:
    """The files the configuration names for a job (baseline, target profile, SRDF, package
    folders) inside the root too: a pull request can change the configuration as well."""
    from meshcol.io.paths import confine

    named = [settings.get("baseline"), settings.get("srdf"), *settings["package-paths"].values()]
    target = settings["target"]
    if target is not None and _in_folder_path(folder, target) != target:
        named.append(target)
    for path in named:
        if path is not None:
            confine(os.path.join(folder, path), "the configuration", path)


def _in_folder_path(folder: str, path: str) -> str:
    """A path the config names: relative to its folder (a target's bare name stays)."""
    if path.endswith(".toml") or "/" in path or os.sep in path:
        return os.path.join(folder, path)
    return path


@contextlib.contextmanager
def _working_folder(folder: str) -> Iterator[None]:
    """The block runs in ``folder`` (job inputs and report paths are relative to it)."""
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(before)


def run_job(task: tuple[Job, str, str | None, Any, bool, Any]) -> dict[str, Any]:
    """One job in this process (a worker's entry): ``(job, folder, root, pair_cache,
    pictures, keep)`` (``pair_cache`` None, or a check's :class:`~meshcol.analysis.pair_cache.
    PairCache`). Returns its result as JSON values (the report, its CI suite, the exit code)
    and ``reads``, every file its input named; with ``pictures``, a failing job's result
    keeps what its pictures need (:func:`meshcol.analysis.snapshots.pictures_data`).
    An unusable input is ``{"error": message}``. ``keep`` (``(key, store)`` or None): the
    result is stored here, in the worker, while the run goes on (the process that hands out
    the jobs writes nothing per job, and no worker waits for it)."""
    from meshcol.io.paths import confined_to, recording_reads

    job, folder, root, pair_cache, pictures, keep = task
    with _working_folder(folder), confined_to(root), recording_reads() as reads:
        try:
            report = _execute(job, folder, pair_cache)
            result = CiRun.result_of(report)
            if pictures and result["exit_code"] == 1:
                from meshcol.analysis.snapshots import pictures_data

                robot = _robot(job.settings, folder)
                shape = job.settings["shape"]
                result["pictures"] = pictures_data(job.command, job.path, shape, report, robot)
        except MeshcolError as exc:
            return {"error": str(exc), "reads": []}
    result["reads"] = sorted({_rel(folder, path) for path in reads})
    if keep is not None:
        from meshcol.decomposition.result_cache import Digests

        digests = keep[2] if len(keep) > 2 else Digests(folder)
        _keep(keep[0], job, result, folder, keep[1], digests)
    return result


def _keep(
    key: str, job: Job, result: Mapping[str, Any], folder: str, store: Any, digests: Any
) -> None:
    """Store a job's result (:func:`meshcol.decomposition.result_cache.store_result`): its
    entry, the digests of the files it read and of its baseline or target file, its
    report's text beside it."""
    from meshcol.decomposition.result_cache import store_result

    depends = {path: digests(path) for path in result["reads"]}
    for extra in job.extra_files:
        depends[_rel(folder, extra)] = digests(extra)
    entry = {k: v for k, v in result.items() if k != "report_text"}
    store_result(key, entry, depends, store, result.get("report_text"))


# --- the run -------------------------------------------------------------------------------------


def run_ci(
    config: Config,
    *,
    overrides: Mapping[str, tuple[Any, str]] = {},
    root: str | os.PathLike[str] | None = None,
    changed: Collection[str] | None = None,
    changed_since: str | None = None,
    cache_dir: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
    snapshots: bool = False,
) -> CiReport:
    """Run every job of ``config`` (:func:`plan`) and gather one report.

    Parameters
    ----------
    root : path, optional
        Every path a file names must resolve inside it (default the config's ``root``, else
        its folder).
    changed : collection of str, optional
        Files (relative to the config's folder) changed since ``changed_since``: only the
        jobs whose file is among them, or that read one of them in their cached run (a
        scene whose mesh changed), or that have no cached run to tell, run.
    cache_dir : path or URL, optional
        The store (default the config's ``cache-dir``, else the user cache).
    use_cache : bool
        Look results up and store them (``--no-cache``: neither).
    snapshots : bool
        Each failing job's result keeps what its pictures need (``--snapshots``): a
        failing job whose cache entry has none (from a run without) runs again.
    """
    folder = os.fspath(config.folder)
    if root is None:
        root = os.path.join(folder, config.get("root") or ".")
    root = os.path.realpath(root)
    cache_dir = result_store(config, cache_dir)
    store = _Results(config, cache_dir if use_cache else None, use_cache)
    runs: dict[int, CiRun] = {}
    pending: list[tuple[int, Job, str]] = []
    skipped = 0
    keys: dict[int, str] = {}
    unchanged: dict[int, CiRun] = {}  # --changed-since: cached jobs it leaves out
    for index, job in enumerate(plan(config, overrides)):
        # without the cache no key is needed: no file of the repository is read for one
        key = keys[index] = store.key(job) if store.enabled else ""
        cached = store.look_up(key)
        reads = None if cached is None else store.reads(key, cached)
        if changed is not None and not _touched(job, changed, reads, folder):
            skipped += 1
            if cached is not None:  # not in the report, but kept in the next run's index
                unchanged[index] = CiRun(job, cached, cached=True)
            continue
        if cached is not None and snapshots and cached["exit_code"] == 1:
            cached = store.with_pictures(key, cached)
        if cached is not None:
            fetch, text = store.fetchers(key)
            runs[index] = CiRun(job, cached, cached=True, fetch=fetch, fetch_text=text)
        else:
            pending.append((index, job, key))
    if progress is not None and pending:
        progress(f"ci: {len(runs)} jobs from the cache, {len(pending)} to run")
    # one job (the asset that changed) runs here: starting a pool costs seconds
    here = jobs == 1 or len(pending) <= 1
    tasks = [
        (job, folder, root, store.pair_cache(job), snapshots, store.keeper(key, here))
        for _, job, key in pending
    ]
    if here:
        outcomes: Iterable[Any] = (run_job(task) for task in tasks)
    else:
        from meshcol.decomposition.executor import run_each  # not for a warm run

        outcomes = (_outcome(o, tasks) for o in run_each(run_job, tasks, jobs=jobs))
    for done, (position, result) in enumerate(_numbered(outcomes, here), start=1):
        index, job, _ = pending[position]
        runs[index] = CiRun(job, result, cached=False)
        if progress is not None:
            progress(f"ci: {done}/{len(pending)} jobs")
    everything = {**runs, **unchanged}
    store.write_index((everything[i], keys[i]) for i in sorted(everything))
    return CiReport(
        runs=tuple(runs[i] for i in sorted(runs)),
        config=config.path,
        root=root,
        changed_since=changed_since,
        skipped=skipped,
        docs_url=config.get("docs-url"),
    )


class _Results:
    """The result cache as a run uses it: the run's index read once (a warm run's lookups),
    entries read when the index lacks a job or a report is written, each result stored as
    it comes and the index written at the end."""

    def __init__(self, config: Config, cache_dir: Any, enabled: bool) -> None:
        from meshcol.decomposition.result_cache import (
            Digests,
            load_index,
            read_index,
            result_key,
        )

        self.folder = os.fspath(config.folder)
        self.cache_dir, self.enabled = cache_dir, enabled
        self.name = f"{Digests()(config.path)}:{config.path.name}"
        index = read_index(self.name, cache_dir) if enabled else {}
        self.digests = Digests(self.folder, index.get("stats"), index.get("written_ns", 0))
        self.result_key = result_key
        self.index = load_index(index, self.digests)
        entries = index.get("entries", {})
        self.depends = {key: entries[key]["depends"] for key in self.index}
        self.changed = False
        self._settings: dict[int, str] = {}

    def key(self, job: Job) -> str:
        """The job's cache key (the settings' part once per settings shared by jobs)."""
        shared = self._settings.get(id(job.settings))
        if shared is None:
            shared = self.result_key(job.command, dict(job.settings), "")
            self._settings[id(job.settings)] = shared
        parts = [shared, job.path, self.digests(job.path)]
        for extra in job.extra_files:
            parts += [_rel(self.folder, extra), self.digests(extra)]
        return hashlib.sha256("\0".join(parts).encode()).hexdigest()

    def pair_cache(self, job: Job) -> Any:
        """The job's pair cache (:func:`job_pair_cache`), None without a cache."""
        return job_pair_cache(job, self.cache_dir) if self.enabled else None

    def look_up(self, key: str) -> Mapping[str, Any] | None:
        """What the run keeps of a cached result (the index's summary, else the entry)."""
        from meshcol.decomposition.result_cache import load_result

        if not self.enabled:
            return None
        summary = self.index.get(key)
        if summary is not None:
            return summary
        self.changed = True
        return load_result(key, self.digests, self.cache_dir)

    def with_pictures(self, key: str, cached: Mapping[str, Any]) -> Mapping[str, Any] | None:
        """A cached failing result with what its pictures need (its entry, read here), or
        None: its entry has none, the job runs again."""
        from meshcol.decomposition.result_cache import load_result

        entry = (
            cached if isinstance(cached, dict) else load_result(key, self.digests, self.cache_dir)
        )
        return entry if isinstance(entry, dict) and "pictures" in entry else None

    def reads(self, key: str, cached: Mapping[str, Any]) -> Collection[str]:
        """The files a cached result read (its dependencies, from the index without
        decoding its summary)."""
        depends = self.depends.get(key)
        return list(cached.get("reads", [])) if depends is None else depends.keys()

    def fetchers(
        self, key: str
    ) -> tuple[Callable[[], dict[str, Any] | None], Callable[[], str | None]]:
        """What reads the entry's result, and its report's text, when a format needs them."""
        from meshcol.decomposition.result_cache import load_text

        return functools.partial(self._fetch, key), functools.partial(
            load_text, key, self.cache_dir
        )

    def _fetch(self, key: str) -> dict[str, Any] | None:
        from meshcol.decomposition.result_cache import load_result

        return load_result(key, self.digests, self.cache_dir)

    def _depends(self, job: Job, result: Mapping[str, Any]) -> dict[str, str]:
        depends = {path: self.digests(path) for path in result["reads"]}
        for extra in job.extra_files:
            depends[_rel(self.folder, extra)] = self.digests(extra)
        return depends

    def keeper(self, key: str, here: bool) -> tuple[Any, ...] | None:
        """Where a job stores its result (:func:`run_job`'s ``keep``); None without a cache.
        A job run ``here`` (in this process) digests its files with the run's digests (the
        index's stats: a scene's 3,000 meshes are not read again); a worker with its own."""
        if not self.enabled:
            return None
        return (key, self.cache_dir, self.digests) if here else (key, self.cache_dir)

    def write_index(self, runs: Iterable[tuple[CiRun, str]]) -> None:
        from meshcol.decomposition.result_cache import store_index

        if not self.enabled or not self.changed:
            return  # every job came from the index, whose files were unchanged
        entries = {}
        for run, key in runs:
            if "error" in run.result:
                continue
            summary: Mapping[str, Any] = run.result
            if isinstance(summary, dict):  # not a Summary of the index: drop its report
                summary = {k: v for k, v in summary.items() if k not in REPORT_KEYS}
            depends = self.depends.get(key) if run.cached else None
            entries[key] = (
                summary,
                self._depends(run.job, summary) if depends is None else depends,
            )
        store_index(self.name, entries, self.digests.stats(), self.cache_dir)


def job_pair_cache(job: Job, cache_dir: Any) -> Any:
    """Where a check job keeps its pairs' answers (:mod:`meshcol.analysis.pair_cache`): the
    store ``cache_dir`` (as :func:`result_store` gives it), under the scene's path and the
    job's settings; None for the other commands."""
    if job.command != "check":
        return None  # and no numpy imported for it
    from meshcol.analysis.pair_cache import PairCache
    from meshcol.decomposition.result_cache import result_key

    return PairCache(cache_dir, f"{job.path}\0{result_key(job.command, dict(job.settings), '')}")


def result_store(config: Config, cache_dir: str | os.PathLike[str] | None) -> Any:
    """The result cache's store of a run: ``cache_dir`` (``--cache-dir``), else the
    config's ``cache-dir`` (relative to its folder), else None (the user cache)."""
    if cache_dir is None and config.get("cache-dir") is not None:
        return _store(os.fspath(config.folder), config.get("cache-dir"))
    return cache_dir


def _store(folder: str, cache_dir: str) -> str:
    from meshcol.decomposition.cache import is_url

    return cache_dir if is_url(cache_dir) else os.path.join(folder, cache_dir)


def _rel(folder: str, path: str) -> str:
    """A dependency as the cache keeps it: relative to the config's folder when inside."""
    relative = os.path.relpath(path, folder)
    return path if relative.startswith("..") else relative.replace(os.sep, "/")


def _touched(
    job: Job, changed: Collection[str], reads: Collection[str] | None, folder: str
) -> bool:
    """Whether ``job`` must run under ``--changed-since``: its file changed, or a file its
    last run read (``reads``, per the cache; None: a miss, which runs when a scene's), or a
    baseline or target file."""
    if job.path in changed or any(_rel(folder, e) in changed for e in job.extra_files):
        return True
    if reads is None:
        return job.kind == "scenes"  # a scene's meshes are unknown without a cached run
    return any(path in changed for path in reads)


def _outcome(outcome: Any, tasks: Sequence[Any]) -> tuple[int, dict[str, Any]]:
    if outcome.status == "ok":
        return outcome.index, outcome.value
    job = tasks[outcome.index][0]
    why = outcome.message or outcome.status
    return outcome.index, {"error": f"{job.path}: {job.command} did not finish: {why}", "reads": []}


def _numbered(outcomes: Iterable[Any], in_order: bool) -> Iterable[tuple[int, dict[str, Any]]]:
    if in_order:
        yield from enumerate(outcomes)
    else:
        yield from outcomes
