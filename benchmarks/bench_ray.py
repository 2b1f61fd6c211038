"""inspect and check over many files: the Ray executor vs the local pool (issue 18).

In one process, on executors already up (a cluster's steady state; a run that starts its own
Ray pays its start-up, measured in bench_decompose.py section 4), alternating local / Ray /
in-process each round, reports compared for equality (timings aside):

1. ``inspect`` of the corpus meshes, each file given ``--copies`` times (one task per file);
2. ``check --shape decomposed`` of the same files with a warm cache (the per-file work is
   reading, canonicalising and the cache lookups; the pairs run on the driver);
3. the per-task overhead, from no-op tasks (``--jobs 2``, warm workers).

decompose itself (Ray vs local on the corpus meshes): ``bench_decompose.py --only ray``.

Usage: python benchmarks/bench_ray.py [--rounds 3] [--copies 3]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_decompose import CORPUS, MESHES, spread, task_overhead


def _noop(x: int) -> int:
    return x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--copies", type=int, default=3, help="times each corpus file is given")
    args = parser.parse_args()
    try:
        import ray
    except ImportError:
        print("Ray is not installed (pip install 'meshcol[ray]'): nothing to compare")
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
