"""``meshcol ci`` on a repository of 10,000 assets: cold, after one changed file, and with
``--changed-since`` on a commit touching 1% of them.

Writes a git repository of N small OBJ props (boxes of different sizes in 100 folders, every
one inspected), a ``meshcol.toml``, and runs the command line as a user would (a new process
each time, so the times include Python's start and every import):

1. cold: an empty result cache;
2. warm: the same tree again (every job from the cache);
3. one changed file: one prop edited, the rest from the cache;
4. ``--changed-since HEAD~1`` after a commit that touched 1% of the props, with the cache
   (the changed jobs recomputed, the others not run), and without it.

Each run's JSON report of the unchanged tree is compared: the cold and the cached report
must be the same bytes. Rounds alternate the warm and one-change runs. Each run prints its
wall time and its CPU time (user + system of the command and the processes it waited for:
what a loaded machine does not move).

Python's bytecode is cached (in a folder beside the repository, ``PYTHONPYCACHEPREFIX``) as an
installed package has it, even where ``PYTHONDONTWRITEBYTECODE`` is set: otherwise every run
compiles every module it imports again, about 0.2 s of CPU a user never pays.
``--no-bytecode`` measures that way all the same.

``--compare CMD`` (another build's command line, e.g. ``/work/base/.venv/bin/meshcol``) also
runs the warm and one-changed steps with CMD, alternated with this build's in every round
(A/B), on the same repository and cache.

    .venv/bin/python benchmarks/bench_ci.py --assets 10000 --jobs 2 --rounds 3
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "cli"))
from ci_repo import box_obj, commit

CONFIG = """[[assets]]
glob = "props/**/*.obj"
inspect = { fail-on = ["not-watertight"] }
"""


def untimed(text: str) -> object:
    """A JSON report without its measured times and timestamps."""

    def strip(value: object) -> object:
        if isinstance(value, dict):
            return {
                k: strip(v)
                for k, v in value.items()
                if "seconds" not in k and k not in ("time", "generated_at")
            }
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    return strip(json.loads(text))


def make(root: Path, count: int) -> list[Path]:
    files = []
    for i in range(count):
        folder = root / "props" / f"f{i % 100:02d}"
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"p{i:05d}.obj"
        path.write_text(box_obj(1.0 + (i % 7) * 0.25, name=f"p{i:05d}"))
        files.append(path)
    (root / "meshcol.toml").write_text(CONFIG)
    commit(root, "assets", init=True)
    return files


#: The command line of meshcol (``--meshcol``); default the entry point beside this Python.
COMMAND: list[str] = [str(Path(sys.executable).with_name("meshcol"))]


#: The environment of every run (:func:`main` sets the bytecode cache).
ENV: dict[str, str] = dict(os.environ)

#: CPU seconds (user + system) of the last :func:`meshcol` run and the processes it waited for.
LAST_CPU: list[float] = [0.0]


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def meshcol(root: Path, *args: str, command: list[str] | None = None) -> tuple[float, str, str]:
    before = _children_cpu()
    start = time.perf_counter()
    done = subprocess.run(
        [*(command or COMMAND), "ci", *args], cwd=root, capture_output=True, text=True, env=ENV
    )
    seconds = time.perf_counter() - start
    LAST_CPU[0] = _children_cpu() - before
    if done.returncode not in (0, 1):
        raise SystemExit(f"meshcol ci failed ({done.returncode}): {done.stderr[-2000:]}")
    return seconds, done.stdout, done.stderr.strip().splitlines()[-1]


def span(times: list[float], cold: float | None = None) -> str:
    """``min-max s`` (and the ratio to ``cold``)."""
    text = f"{min(times):.2f}-{max(times):.2f} s"
    if cold is not None:
        text += f" ({cold / max(times):.0f}x-{cold / min(times):.0f}x)"
    return text


def compare(
    root: Path, files: list[Path], jobs: tuple[str, ...], rounds: int, other: list[str]
) -> None:
    """The warm and one-changed steps, this build (B) and ``other`` (A) alternated per round;
    wall and CPU ranges of each.

    A gets a copy of B's cache without the run index (the builds may lay it out differently,
    and each run rewrites it), which A's first, untimed, run writes again: each build then
    reads an index of its own."""
    cache = Path(jobs[jobs.index("--cache-dir") + 1])
    cache_a = cache.with_name(cache.name + "-A")
    shutil.rmtree(cache_a, ignore_errors=True)
    shutil.copytree(cache, cache_a)
    shutil.rmtree(cache_a / "results" / "index", ignore_errors=True)
    jobs_a = tuple(str(cache_a) if str(x) == str(cache) else x for x in jobs)
    meshcol(root, *jobs_a, command=other)
    wall: dict[str, list[float]] = {f"{k} {w}": [] for k in "AB" for w in ("warm", "changed")}
    cpu: dict[str, list[float]] = {key: [] for key in wall}
    edit = len(files) // 2
    for k in range(rounds):
        for name in "AB" if k % 2 == 0 else "BA":
            command = other if name == "A" else COMMAND
            flags = jobs_a if name == "A" else jobs
            seconds, _, _ = meshcol(root, *flags, command=command)
            wall[f"{name} warm"].append(seconds)
            cpu[f"{name} warm"].append(LAST_CPU[0])
            path = files[edit]
            edit += 1
            path.write_text(box_obj(7.0 + k, name=path.stem))
            seconds, _, line = meshcol(root, *flags, command=command)
            wall[f"{name} changed"].append(seconds)
            cpu[f"{name} changed"].append(LAST_CPU[0])
            print(
                f"  round {k + 1} {name} one changed: {seconds:.2f} s, CPU {LAST_CPU[0]:.2f} s  {line}"
            )
    print(f"A = {' '.join(other)}; B = {' '.join(COMMAND)}")
    for key in wall:
        print(f"  {key:<10} wall {span(wall[key])}, CPU {span(cpu[key])}")
    shutil.rmtree(cache_a, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--assets", type=int, default=10_000)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--keep", help="build the repository here and keep it")
    parser.add_argument("--meshcol", help="the meshcol command line (default: the entry point)")
    parser.add_argument(
        "--fresh", action="store_true", help="also a second cold run, compared but its times"
    )
    parser.add_argument("--compare", help="another build's meshcol command line (A/B rounds)")
    parser.add_argument(
        "--no-bytecode", action="store_true", help="no bytecode cache: compile every import"
    )
    args = parser.parse_args()
    if args.meshcol:
        COMMAND[:] = args.meshcol.split()

    root = Path(args.keep or tempfile.mkdtemp(prefix="bench-ci-"))
    cache = root.parent / (root.name + "-cache")
    shutil.rmtree(cache, ignore_errors=True)
    bytecode = root.parent / (root.name + "-pycache")
    if not args.no_bytecode:
        ENV.pop("PYTHONDONTWRITEBYTECODE", None)
        ENV["PYTHONPYCACHEPREFIX"] = str(bytecode)
    try:
        start = time.perf_counter()
        files = make(root, args.assets)
        print(f"repository: {args.assets} assets written in {time.perf_counter() - start:.1f} s")
        jobs = ("-j", str(args.jobs), "--cache-dir", str(cache))

        cold, cold_report, line = meshcol(root, *jobs, "--report", "-")
        print(f"cold:      {cold:7.2f} s, CPU {LAST_CPU[0]:.2f} s   {line}")
        if args.fresh:
            _, fresh, _ = meshcol(root, "-j", str(args.jobs), "--no-cache", "--report", "-")
            assert untimed(fresh) == untimed(cold_report), "--no-cache report differs"
            print("a second cold run (--no-cache) gives the same report but its times")
        warm_times, change_times, junit_times, json_times = [], [], [], []
        warm_cpu: list[float] = []
        change_cpu: list[float] = []
        junit, report = str(root.parent / "r.xml"), str(root.parent / "r.json")
        reference = cold_report  # the report of the tree as it is, as first computed
        for k in range(args.rounds):
            seconds, warm_report, line = meshcol(root, *jobs, "--report", "-")
            print(f"warm, JSON report: {seconds:7.2f} s   {line}")
            assert warm_report == reference, "the cached report differs from the computed one"
            seconds, _, line = meshcol(root, *jobs)
            warm_times.append(seconds)
            warm_cpu.append(LAST_CPU[0])
            print(f"warm, verdict:     {seconds:7.2f} s, CPU {LAST_CPU[0]:.2f} s   {line}")
            for n, (times, outputs) in enumerate(
                (
                    (change_times, ()),
                    (junit_times, ("--junit", junit)),
                    (json_times, ("--report", report)),
                )
            ):
                path = files[3 * k + n]
                path.write_text(box_obj(5.0 + k, name=path.stem))
                seconds, _, line = meshcol(root, *jobs, *outputs)
                times.append(seconds)
                if not outputs:
                    change_cpu.append(LAST_CPU[0])
                if outputs and outputs[0] == "--report":
                    reference = Path(report).read_text()
                print(
                    f"1 changed {' '.join(outputs) or '(verdict)':<20}: {seconds:7.2f} s, "
                    f"CPU {LAST_CPU[0]:.2f} s   {line}"
                )
        print("every cached report == the report first computed for that tree, byte for byte")
        if args.compare:
            compare(root, files, jobs, args.rounds, args.compare.split())
            commit(root, "the A/B rounds' edits")  # not in the 1% commit below

        touched = files[-max(1, args.assets // 100) :]
        for path in touched:
            path.write_text(box_obj(9.0, name=path.stem))
        commit(root, "1% of the assets")
        since, _, line = meshcol(root, *jobs, "--changed-since", "HEAD~1")
        since_cpu = LAST_CPU[0]
        print(
            f"--changed-since HEAD~1 ({len(touched)} files), cache: {since:7.2f} s, "
            f"CPU {since_cpu:.2f} s   {line}"
        )
        nocache, _, line = meshcol(
            root, "-j", str(args.jobs), "--no-cache", "--changed-since", "HEAD~1"
        )
        print(
            f"--changed-since HEAD~1, --no-cache: {nocache:7.2f} s, CPU {LAST_CPU[0]:.2f} s   "
            f"{line}"
        )
        print(
            f"summary: cold {cold:.2f} s; warm verdict {span(warm_times, cold)} (CPU "
            f"{span(warm_cpu)}); one changed: verdict {span(change_times, cold)} (CPU "
            f"{span(change_cpu)}), --junit {span(junit_times, cold)}, --report JSON "
            f"{span(json_times, cold)}; changed-since 1%: {since:.2f} s ({cold / since:.0f}x, "
            f"CPU {since_cpu:.2f} s), without the cache {nocache:.2f} s"
        )
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
        shutil.rmtree(cache, ignore_errors=True)
        shutil.rmtree(bytecode, ignore_errors=True)
        for name in ("r.json", "r.xml"):
            if (root.parent / name).exists():
                os.unlink(root.parent / name)


if __name__ == "__main__":
    main()
