"""Benchmark ``meshcol decompose``: parallel files, cache hits, CoACD vs V-HACD.

Runs the command line as users do (``python -m meshcol decompose``), on corpus meshes:

1. ``--jobs 1`` (single-threaded, and by default with CoACD's OpenMP on all cores) vs
   ``--jobs 2`` without the cache, alternating for ``--rounds`` rounds (wall time, outputs
   compared byte for byte);
2. a cache miss vs a cache hit of the same command (whole command, then ``decompose()`` alone);
3. CoACD vs V-HACD: parts, seconds and fidelity per mesh, side by side;
4. the Ray executor vs the local pool (``--jobs 2``, no cache), alternating: the whole command
   (a local Ray started and stopped by each run) and ``decompose_files`` in one process on a
   Ray already running (the steady state of a cluster), outputs compared byte for byte; and
   the per-task overhead of each executor (no-op tasks).

Usage: python benchmarks/bench_decompose.py [--quick] [--rounds 3] [--only ray]
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CORPUS = Path(__file__).resolve().parents[1].parent / "shared" / "corpus"
MESHES = [
    "coacd-examples/Octocat-v2.obj",
    "trimesh-models/torus.STL",
    "trimesh-models/fandisk.obj",
    "trimesh-models/featuretype.STL",
    "trimesh-models/octagonal_pocket.stl",
    "trimesh-models/plate_holes.STL",
    "trimesh-models/idler_riser.STL",
    "trimesh-models/angle_block.STL",
    "trimesh-models/1002_tray_bottom.STL",
    "trimesh-models/round.stl",
]
# CoACD at a moderate setting: threshold 0.1, fewer tree-search iterations than the default.
COACD = [
    "--threshold",
    "0.1",
    "--preprocess",
    "off",
    "--resolution",
    "1000",
    "-E",
    "mcts_iterations=60",
    "-E",
    "mcts_nodes=12",
    "-E",
    "mcts_max_depth=2",
]
VHACD = ["--engine", "vhacd", "--resolution", "100000", "--max-hulls", "32"]


def run(args: list[str], env: dict[str, str] | None = None) -> tuple[float, dict]:
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        report = f.name
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "meshcol", "decompose", *args, "--report", report],
        capture_output=True,
        text=True,
        env={**os.environ, **(env or {})},
    )
    seconds = time.perf_counter() - start
    if proc.returncode not in (0, 1):
        raise SystemExit(f"meshcol decompose failed ({proc.returncode}): {proc.stderr}")
    data = json.loads(Path(report).read_text())
    os.unlink(report)
    return seconds, data


def same_tree(a: Path, b: Path) -> bool:
    names = sorted(p.name for p in a.iterdir())
    if names != sorted(p.name for p in b.iterdir()):
        return False
    return all(filecmp.cmp(a / n, b / n, shallow=False) for n in names)


def metrics(report: dict) -> dict[str, dict]:
    return {
        Path(f["path"]).name: (
            {**f["bodies"][0]["metrics"], "seconds": f["seconds"]}
            if f["status"] == "ok"
            else {"status": f["status"]}
        )
        for f in report["files"]
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="first 4 meshes only")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the jobs comparison")
    parser.add_argument("--only", choices=["ray"], help="only the executor comparison (4)")
    args = parser.parse_args()
    meshes = [str(CORPUS / m) for m in (MESHES[:4] if args.quick else MESHES)]
    missing = [m for m in meshes if not Path(m).is_file()]
    if missing:
        raise SystemExit(f"corpus not found: {missing[0]}")
    work = Path(tempfile.mkdtemp(prefix="bench-decompose-"))
    print(
        f"{len(meshes)} corpus meshes, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}"
    )
    if args.only == "ray":
        bench_ray(meshes, work, args.rounds)
        shutil.rmtree(work)
        return

    # 1. jobs 1 vs jobs 2 (no cache). The three runs alternate, round after round, so a
    # change in the machine's speed (a shared 2-core VM: +-15% between minutes) hits all three.
    one = {"OMP_NUM_THREADS": "1"}  # CoACD single-threaded: one core for --jobs 1
    times: dict[str, list[float]] = {"single": [], "default": [], "jobs2": []}
    for r in range(args.rounds):
        s1, _ = run(
            [*meshes, "-o", str(work / f"s1_{r}"), "--no-cache", "--jobs", "1", *COACD], one
        )
        t1, r1 = run([*meshes, "-o", str(work / f"j1_{r}"), "--no-cache", "--jobs", "1", *COACD])
        t2, _ = run([*meshes, "-o", str(work / f"j2_{r}"), "--no-cache", "--jobs", "2", *COACD])
        times["single"].append(s1)
        times["default"].append(t1)
        times["jobs2"].append(t2)
        print(
            f"round {r + 1}: jobs 1 single-threaded {s1:6.2f} s, jobs 1 default {t1:6.2f} s, "
            f"jobs 2 {t2:6.2f} s: {s1 / t2:.2f}x / {t1 / t2:.2f}x"
        )
    identical = all(
        same_tree(work / "j1_0", work / f"{k}_{r}")
        for k in ("s1", "j1", "j2")
        for r in range(args.rounds)
    )
    best = {k: min(v) for k, v in times.items()}
    median = statistics.median
    print("\n## --jobs 1 vs --jobs 2 (CoACD, no cache)")
    print(
        f"best of {args.rounds}: jobs 1 single-threaded {best['single']:.2f} s, jobs 1 default "
        f"(CoACD's OpenMP on all cores) {best['default']:.2f} s, jobs 2 {best['jobs2']:.2f} s"
    )
    print(
        f"speed-up of jobs 2 over jobs 1 on one core: {best['single'] / best['jobs2']:.2f}x (best "
        f"times), {median([a / b for a, b in zip(times['single'], times['jobs2'])]):.2f}x (median "
        f"of rounds); over default jobs 1: {best['default'] / best['jobs2']:.2f}x, "
        f"{median([a / b for a, b in zip(times['default'], times['jobs2'])]):.2f}x"
    )
    print(f"identical outputs in every run: {identical}")

    # 2. cache miss vs hit
    cache = work / "cache"
    miss, rm = run([*meshes, "-o", str(work / "miss"), "--cache-dir", str(cache), *COACD])
    hit, rh = run([*meshes, "-o", str(work / "hit"), "--cache-dir", str(cache), *COACD])
    assert all(b["from_cache"] for f in rh["files"] for b in f["bodies"])
    print("\n## cache miss vs hit")
    print(
        f"whole command (includes ~1 s of Python start-up, imports and file parsing): miss {miss:.2f} s, "
        f"hit {hit:.3f} s, ratio {miss / hit:.0f}x, identical outputs: {same_tree(work / 'miss', work / 'hit')}"
    )
    from meshcol import decompose
    from meshcol.io.mesh_read import load_mesh

    options = {
        "threshold": 0.1,
        "preprocess": "off",
        "resolution": 1000,
        "cache_dir": str(cache),
        "engine_options": {"mcts_iterations": 60, "mcts_nodes": 12, "mcts_max_depth": 2},
    }
    ratios, hit_total, miss_total = [], 0.0, 0.0
    for f in rm["files"]:
        body = load_mesh(f["path"])[0]
        start = time.perf_counter()
        assert decompose(body, **options).from_cache
        seconds = time.perf_counter() - start
        ratios.append(f["seconds"] / seconds)
        hit_total += seconds
        miss_total += f["seconds"]
        print(
            f"  {Path(f['path']).name:24} {len(body.faces):>7} faces: miss {f['seconds']:7.2f} s, "
            f"hit {seconds * 1000:7.1f} ms, ratio {ratios[-1]:7.0f}x"
        )
    print(
        f"decompose() per body (canonical geometry, key, cache read): miss {miss_total:.2f} s, "
        f"hit {hit_total * 1000:.0f} ms in all, ratio {miss_total / hit_total:.0f}x (smallest {min(ratios):.0f}x)"
    )

    # 3. CoACD vs V-HACD
    tv, rv = run([*meshes, "-o", str(work / "vhacd"), "--no-cache", "--jobs", "1", *VHACD])
    mc, mv = metrics(r1), metrics(rv)
    print(f"\n## CoACD vs V-HACD (all files, --jobs 1): CoACD {t1:.1f} s, V-HACD {tv:.1f} s")
    print(
        f"{'mesh':24} {'seconds':>13} {'parts':>11} {'vol ratio':>13} {'H mesh>parts':>15} {'H parts>mesh':>15} "
        f"{'uncovered':>13}"
    )
    for name in mc:
        a, b = mc[name], mv[name]
        if "parts" not in a or "parts" not in b:
            print(f"{name:24} coacd {a.get('status', 'ok')}, vhacd {b.get('status', 'ok')}")
            continue
        print(
            f"{name:24} {a['seconds']:6.2f}/{b['seconds']:<6.2f} {a['parts']:>5}/{b['parts']:<5} {a['volume_ratio'] or 0:6.3f}/{b['volume_ratio'] or 0:<6.3f} "
            f"{a['hausdorff_mesh_to_parts']:7.4f}/{b['hausdorff_mesh_to_parts']:<7.4f} "
            f"{a['hausdorff_parts_to_mesh']:7.4f}/{b['hausdorff_parts_to_mesh']:<7.4f} "
            f"{a['uncovered_fraction']:6.3f}/{b['uncovered_fraction']:<6.3f}"
        )
    print("(each cell: CoACD/V-HACD; H = one-sided Hausdorff distance in mesh units)")
    bench_ray(meshes, work, args.rounds)
    shutil.rmtree(work)


def _noop(task: object) -> object:
    return task


def spread(values: list[float]) -> str:
    return f"{min(values):.2f}-{max(values):.2f} s (median {statistics.median(values):.2f})"


def bench_ray(meshes: list[str], work: Path, rounds: int) -> None:
    """4. The Ray executor vs the local pool, alternated round by round."""
    try:
        import ray
    except ImportError:
        print("\n## Ray executor vs local pool: skipped (pip install 'meshcol[ray]')")
        return
    from meshcol.decomposition.batch import decompose_files

    print(f"\n## Ray executor vs local pool (--jobs 2, no cache), ray {ray.__version__}")
    cli: dict[str, list[float]] = {"local": [], "ray": []}
    for r in range(rounds):
        for kind in ("local", "ray"):
            seconds, _ = run(
                [*meshes, "-o", str(work / f"cli_{kind}_{r}"), "--no-cache", "--jobs", "2"]
                + ["--executor", kind, *COACD]
            )
            cli[kind].append(seconds)
        print(
            f"round {r + 1}: whole command, local {cli['local'][-1]:6.2f} s, ray "
            f"{cli['ray'][-1]:6.2f} s: ray/local {cli['ray'][-1] / cli['local'][-1]:.3f}"
        )
    same = all(
        same_tree(work / "cli_local_0", work / f"cli_{k}_{r}")
        for k in ("local", "ray")
        for r in range(rounds)
    )
    ratios = [b / a for a, b in zip(cli["local"], cli["ray"], strict=True)]
    print(
        f"whole command: local {spread(cli['local'])}, ray {spread(cli['ray'])}; ray/local "
        f"{min(ratios):.3f}-{max(ratios):.3f}; identical outputs: {same}"
    )

    # In one process, on a Ray already up (a cluster's steady state: no start-up per run).
    ray.init(
        address="local",
        num_cpus=2,
        include_dashboard=False,
        _node_ip_address="127.0.0.1",
        log_to_driver=False,
        logging_level="ERROR",
    )
    options = {
        "threshold": 0.1,
        "preprocess": "off",
        "resolution": 1000,
        "use_cache": False,
        "jobs": 2,
        "engine_options": {"mcts_iterations": 60, "mcts_nodes": 12, "mcts_max_depth": 2},
    }
    warm = decompose_files(meshes[:1], work / "warm", executor="ray", **options)
    assert warm.exit_code == 0
    steady: dict[str, list[float]] = {"local": [], "ray": []}
    for r in range(rounds):
        for kind in ("local", "ray"):
            start = time.perf_counter()
            decompose_files(meshes, work / f"lib_{kind}_{r}", executor=kind, **options)
            steady[kind].append(time.perf_counter() - start)
        print(
            f"round {r + 1}: decompose_files, local {steady['local'][-1]:6.2f} s, ray "
            f"{steady['ray'][-1]:6.2f} s: ray/local {steady['ray'][-1] / steady['local'][-1]:.3f}"
        )
    ratios = [b / a for a, b in zip(steady["local"], steady["ray"], strict=True)]
    same = all(
        same_tree(work / "cli_local_0", work / f"lib_{k}_{r}")
        for k in ("local", "ray")
        for r in range(rounds)
    )
    print(
        f"decompose_files on a running Ray: local {spread(steady['local'])}, ray "
        f"{spread(steady['ray'])}; ray/local {min(ratios):.3f}-{max(ratios):.3f}; identical "
        f"outputs: {same}"
    )

    task_overhead(_noop)
    ray.shutdown()


def task_overhead(noop, n: int = 400) -> None:
    """Print the per-task overhead of each executor: ``n`` no-op tasks (``noop``, defined in
    the running script so that Ray sends it by value), workers already up, 3 samples."""
    from meshcol.decomposition.executor import RayExecutor
    from meshcol.decomposition.jobs import WorkerPool

    for kind in ("local", "ray"):
        samples = []
        for _ in range(3):
            executor = RayExecutor(noop, 2) if kind == "ray" else WorkerPool(noop, 2)
            with executor:
                executor.start()
                list(executor.run(range(20)))  # workers up and warm
                start = time.perf_counter()
                outcomes = list(executor.run(range(n)))
                samples.append((time.perf_counter() - start) / n)
            assert all(o.status == "ok" for o in outcomes)
        print(
            f"per-task overhead, {kind}: {min(samples) * 1e3:.2f}-{max(samples) * 1e3:.2f} ms "
            f"per task ({n} no-op tasks, 2 workers, 3 samples)"
        )


if __name__ == "__main__":
    main()
