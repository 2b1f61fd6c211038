"""inspect and check over many files: the Ray executor vs the local pool (issue 18).

In one process, on executors already up (a cluster's steady state; a run that starts its own
Ray pays its start-up, measured in bench_decompose.py section 4), alternating local / Ray /
in-process each round, reports compared for equality (timings aside):

1. ``inspect`` of the corpus meshes, each file given ``--copies`` times (one task per file);
2. ``check --shape decomposed`` of the same files with a warm cache (the per-file work is
   reading, canonicalising and the cache lookups; the pairs run on the driver);
3. the per-task overhead, from no-op tasks (``--jobs 2``, warm workers).

decompose itself (Ray vs local on the corpus meshes): ``bench_decompose.py --only ray``.

``--one-off`` (issue 32 item 6) instead times a one-off command, each run a new process as a
user types it: ``meshcol decompose`` of 3 corpus files (``--jobs 2 --no-cache``, the CoACD
settings of bench_decompose.py), on the local pool, on a Ray of its own (``--ray-address
local``: this build's light one), on a Ray that ``ray start --head`` left running (joined,
found by its address file), and, with ``--compare CMD``, on another build's Ray of its own
(never joined: the cluster's workers run this build); rounds alternate the order. Wall time (the issue's figure); the CPU time of the
command and what it waited for (Ray's daemons are not all waited for); the CPU time of every
process it started (sampled every 0.05 s: :class:`TreeCPU`), and of the running cluster's
processes and workers meanwhile. A run that leaves a process it started behind fails the
benchmark. Outputs compared.

``--start-up`` times Ray's start alone, each run a new process: a RayExecutor of its own
(2 CPUs on 127.0.0.1) started, 4 trivial tasks, closed; this build's light start against
Ray's default processes (the autoscaler monitor, the log monitor: main's), alternated.

Usage: python benchmarks/bench_ray.py [--rounds 3] [--copies 3]
       python benchmarks/bench_ray.py --start-up [--rounds 3]
       python benchmarks/bench_ray.py --one-off [--rounds 5] [--compare /work/base/.venv/bin/meshcol]
"""

from __future__ import annotations

import argparse
import os
import resource
import secrets
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_decompose import COACD, CORPUS, MESHES, same_tree, spread, task_overhead

#: The one-off command's files: three small corpus meshes.
ONE_OFF = ["trimesh-models/torus.STL", "trimesh-models/angle_block.STL", "trimesh-models/round.stl"]


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


class TreeCPU:
    """CPU time (user + system) of every process under some roots, sampled every ``every`` s
    in a thread: a process's last sample counts, so a process that exits between two samples
    loses at most ``every`` s of its CPU; one that lives less than ``every`` s may be missed.
    Processes that leave the tree (orphans of a killed raylet) keep their last sample."""

    def __init__(self, roots: list[int], every: float = 0.05) -> None:
        import psutil

        self.psutil, self.every = psutil, every
        self.roots = [psutil.Process(pid) for pid in roots]
        self.last: dict[tuple[int, float], float] = {}
        self.first: dict[tuple[int, float], float] = {}
        self.alive: set[tuple[int, float]] = set()
        self._stop = threading.Event()
        self.sample()
        self.first = dict(self.last)
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def sample(self) -> None:
        alive = set()
        for root in self.roots:
            try:
                tree = [root, *root.children(recursive=True)]
            except self.psutil.Error:
                continue
            for each in tree:
                try:
                    key = (each.pid, each.create_time())
                    times = each.cpu_times()
                except self.psutil.Error:
                    continue
                self.last[key] = times.user + times.system
                alive.add(key)
        self.alive = alive

    def _loop(self) -> None:
        while not self._stop.wait(self.every):
            self.sample()

    def stop(self) -> float:
        """CPU s used since this started, by the processes seen."""
        self._stop.set()
        self._thread.join()
        return sum(v - self.first.get(k, 0.0) for k, v in self.last.items())


def _decompose(
    command: list[str],
    out: Path,
    extra: list[str],
    env: dict[str, str],
    cluster: list[int] | None = None,
) -> tuple[float, float, float, float]:
    """One ``meshcol decompose`` of the ONE_OFF files into ``out``: (wall s, CPU s it waited
    for, CPU s of every process it started (sampled), CPU s of the ``cluster`` processes and
    their workers meanwhile (sampled)). Fails if a process it started outlives it."""
    files = [str(CORPUS / name) for name in ONE_OFF]
    args = [*command, "decompose", *files, "-o", str(out), "--no-cache", "--jobs", "2", *COACD]
    cpu, start = _cpu(), time.perf_counter()
    nearby = TreeCPU(cluster or [])
    proc = subprocess.Popen(
        [*args, *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    tree = TreeCPU([proc.pid])
    _, stderr = proc.communicate()
    seconds = time.perf_counter() - start
    tree.sample()
    left = [pid for pid, _ in tree.alive if pid != proc.pid]
    started, around = tree.stop(), nearby.stop()
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(args[:2])} failed ({proc.returncode}): {stderr[-2000:]}")
    if left:
        raise SystemExit(f"{' '.join(args[:2])} left processes running: {left}")
    return seconds, _cpu() - cpu, started, around


def _ray_head(temp: str, env: dict[str, str]) -> subprocess.Popen:
    """``ray start --head`` of 2 CPUs on 127.0.0.1 whose address file is under ``temp``."""
    ray_cli = shutil.which("ray", path=os.path.dirname(sys.executable)) or "ray"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = [ray_cli, "start", "--head", f"--port={port}", "--num-cpus=2", "--disable-usage-stats"]
    start += ["--node-ip-address=127.0.0.1", "--include-dashboard=false"]
    proc = subprocess.Popen(
        start, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    out, _ = proc.communicate(timeout=300)
    if proc.returncode != 0:
        raise SystemExit(f"ray start failed: {out.decode()[-2000:]}")
    return proc


#: One start of a local Ray as RayExecutor makes it (KIND=light) or with Ray's defaults.
START_UP = """
import contextlib, os, time
t0 = time.perf_counter()
import meshcol.decomposition.executor as ex
if os.environ["KIND"] == "default":
    ex.light_head, ex.LIGHT_INIT = contextlib.nullcontext, {}
with ex.RayExecutor(abs, 2, address="local") as e:
    e.start()
    assert sorted(o.value for o in e.run([-1, -2, 3, 4])) == [1, 2, 3, 4]
    from ray._private import worker
    kinds = sorted(worker._global_node.all_processes)
print(time.perf_counter() - t0, ",".join(kinds))
"""


def start_up(rounds: int) -> None:
    """Ray's start alone: light (this build) and default, alternated, a process each."""
    env = {**os.environ, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
    env.pop("RAY_ADDRESS", None)
    wall: dict[str, list[float]] = {"light": [], "default": []}
    cpu: dict[str, list[float]] = {"light": [], "default": []}
    for r in range(rounds):
        for kind in ("light", "default") if r % 2 == 0 else ("default", "light"):
            before = _cpu()
            done = subprocess.run(
                [sys.executable, "-c", START_UP],
                capture_output=True,
                text=True,
                env={**env, "KIND": kind},
            )
            if done.returncode != 0:
                raise SystemExit(done.stderr[-2000:])
            seconds, kinds = done.stdout.split()
            wall[kind].append(float(seconds))
            cpu[kind].append(_cpu() - before)
            print(
                f"round {r + 1} {kind}: {float(seconds):.2f} s, CPU {cpu[kind][-1]:.2f} s, {kinds}"
            )
    for kind in wall:
        print(f"{kind:<8} wall {spread(wall[kind])}, CPU (waited for) {spread(cpu[kind])}")


def _cluster_pids(temp: str) -> list[int]:
    """The processes of the ``ray start`` cluster whose files are under ``temp``."""
    import psutil

    found = []
    for each in psutil.process_iter(["cmdline"]):
        if any(temp in arg for arg in each.info["cmdline"] or ()):
            found.append(each.pid)
    return found


def one_off(rounds: int, compare: str | None) -> None:
    """The one-off command on each executor, a new process each time, alternated."""
    work = Path(tempfile.mkdtemp(prefix="bench_ray_once_"))
    temp = tempfile.mkdtemp(prefix="mcb", dir="/tmp")  # Ray's socket paths stay short
    mine = [sys.executable, "-m", "meshcol"]
    # Two environments: one where nothing runs (RAY_TMPDIR of its own, no address file) and
    # one whose address file names the running `ray start` cluster (token auth: Ray 2.60).
    auth = {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}
    base = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    alone = {**base, **auth, "RAY_TMPDIR": str(work / "none")}
    joined = {**base, **auth, "RAY_TMPDIR": temp, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
    kinds: dict[str, tuple[list[str], list[str], dict[str, str]]] = {
        "local pool": (mine, [], alone),
        "own Ray (light)": (mine, ["--executor", "ray", "--ray-address", "local"], alone),
        "joined Ray": (mine, ["--executor", "ray"], joined),
    }
    if compare:
        # Only its own Ray: the running cluster's workers run this build's meshcol, so another
        # build joining it would time a driver of one build on workers of another (an old
        # driver passed 0 bodies on new workers; it is not a measure of either build).
        kinds["own Ray (--compare)"] = (compare.split(), ["--executor", "ray"], alone)
    head = _ray_head(temp, joined)
    cluster = _cluster_pids(temp)
    figures = ("wall", "CPU waited for", "CPU started", "CPU cluster")
    seen: dict[str, dict[str, list[float]]] = {k: {f: [] for f in figures} for k in kinds}
    try:
        _decompose(mine, work / "warm-up", ["--executor", "ray"], joined)  # the workers up
        order = list(kinds)
        for r in range(rounds):
            for kind in order if r % 2 == 0 else order[::-1]:
                command, extra, env = kinds[kind]
                out = work / f"{kind}-{r}"
                values = _decompose(command, out, extra, env, cluster)
                for figure, value in zip(figures, values, strict=True):
                    seen[kind][figure].append(value)
            print(
                f"round {r + 1} (load {os.getloadavg()[0]:.1f}): "
                + ", ".join(f"{k} {seen[k]['wall'][-1]:.2f} s" for k in kinds)
            )
        reference = work / "local pool-0"
        same = all(same_tree(reference, work / f"{k}-{r}") for k in kinds for r in range(rounds))
        local = seen["local pool"]["wall"]
        for kind in kinds:
            ratios = [b / a for a, b in zip(local, seen[kind]["wall"], strict=True)]
            print(
                f"{kind:<24} / local pool {min(ratios):.2f}-{max(ratios):.2f} "
                f"(median {statistics.median(ratios):.2f})"
            )
            for figure in figures:
                print(f"  {figure:<15} {spread(seen[kind][figure])}")
        print(f"identical outputs: {same}; no process left behind by any run")
    finally:
        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(head.pid, sig)
            except ProcessLookupError:
                break
            time.sleep(2)
        shutil.rmtree(work, ignore_errors=True)
        shutil.rmtree(temp, ignore_errors=True)


def _noop(x: int) -> int:
    return x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--copies", type=int, default=3, help="times each corpus file is given")
    parser.add_argument("--one-off", action="store_true", help="a one-off command's start-up")
    parser.add_argument("--compare", help="with --one-off: another build's meshcol command")
    parser.add_argument("--start-up", action="store_true", help="Ray's start alone")
    args = parser.parse_args()
    try:
        import ray
    except ImportError:
        print("Ray is not installed (pip install 'meshcol[ray]'): nothing to compare")
        return
    if args.one_off:
        one_off(args.rounds, args.compare)
        return
    if args.start_up:
        start_up(args.rounds)
        return
    from meshcol.analysis.check import check
    from meshcol.analysis.inspect import inspect

    work = Path(tempfile.mkdtemp(prefix="bench_ray_"))
    try:
        # distinct paths (one task each), the same geometry: copies of the corpus files
        files: list[str] = []
        for c in range(args.copies):
            for name in MESHES:
                target = work / f"c{c}" / Path(name).name
                target.parent.mkdir(exist_ok=True)
                shutil.copy(CORPUS / name, target)
                files.append(str(target))
        print(
            f"ray {ray.__version__}; {len(files)} files ({len(MESHES)} corpus meshes x "
            f"{args.copies}); --jobs 2; executors already up; rounds alternated"
        )
        ray.init(
            address="local",
            num_cpus=2,
            include_dashboard=False,
            _node_ip_address="127.0.0.1",
            log_to_driver=False,
            logging_level="ERROR",
        )
        cache = work / "cache"
        # CoACD at bench_decompose.py's moderate settings
        decompose_options = {
            "engine": "coacd",
            "threshold": 0.1,
            "preprocess": "off",
            "resolution": 1000,
            "engine_options": {"mcts_iterations": 60, "mcts_nodes": 12, "mcts_max_depth": 2},
            "cache_dir": str(cache),
        }
        check_options = {
            "collider": "decomposed",
            "decompose_options": decompose_options,
            "fail_on": "none",
        }

        def run_inspect(kind: str) -> tuple[float, object]:
            start = time.perf_counter()
            if kind == "in-process":
                report = inspect(files)
            else:
                report = inspect(files, jobs=2, executor=kind)
            return time.perf_counter() - start, report.to_dict()

        def run_check(kind: str) -> tuple[float, object]:
            start = time.perf_counter()
            if kind == "in-process":
                report = check(files, **check_options)
            else:
                report = check(files, jobs=2, executor=kind, **check_options)
            seconds = time.perf_counter() - start
            out = report.to_dict()
            out.pop("generated_at", None)
            out["summary"] = {
                k: v for k, v in out["summary"].items() if k not in ("seconds", "load_seconds")
            }
            return seconds, out

        run_check("in-process")  # fills the cache: the rounds below all hit it
        for section, fn in (("inspect", run_inspect), ("check --shape decomposed", run_check)):
            fn("ray")  # Ray's workers for these tasks up (their runtime_env) before timing
            times: dict[str, list[float]] = {"in-process": [], "local": [], "ray": []}
            reference = None
            same = True
            for r in range(args.rounds):
                kinds = (
                    ("local", "ray", "in-process") if r % 2 == 0 else ("ray", "local", "in-process")
                )
                for kind in kinds:
                    seconds, report = fn(kind)
                    times[kind].append(seconds)
                    reference = report if reference is None else reference
                    same = same and report == reference
                print(
                    f"  {section} round {r + 1}: "
                    + ", ".join(f"{k} {times[k][-1]:.2f} s" for k in ("in-process", "local", "ray"))
                )
            ratios = [b / a for a, b in zip(times["local"], times["ray"], strict=True)]
            print(
                f"{section}: in-process {spread(times['in-process'])}, local "
                f"{spread(times['local'])}, ray {spread(times['ray'])}; ray/local "
                f"{min(ratios):.3f}-{max(ratios):.3f} (median {statistics.median(ratios):.3f}); "
                f"per file: local {statistics.median(times['local']) / len(files) * 1e3:.1f} ms, "
                f"ray {statistics.median(times['ray']) / len(files) * 1e3:.1f} ms; "
                f"identical reports: {same}"
            )

        task_overhead(_noop)
        ray.shutdown()
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
