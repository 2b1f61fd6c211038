"""``meshcol ci --changed-since REF`` with the result cache and without it, A/B alternated.

Takes a repository whose last commit touched some of its assets (``bench_ci.py --keep DIR``
then a commit), and for each build a warm cache of the tree before that commit, holding its
own run index (``--cache-a``, ``--cache-b``: copies of one cache each build ran warm once).
Every run starts from a fresh copy of its build's cache, so each is the first run after the
commit. Prints wall and CPU of each run and their ranges; CPU is the ``meshcol`` process's
(the jobs of the pool run in workers it does not wait for, so they are not counted).

    .venv/bin/python benchmarks/bench_ci_since.py --repo /tmp/r --cache-a /tmp/ca \\
        --cache-b /tmp/cb --compare /work/base14/.venv/bin/meshcol --rounds 2
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", required=True)
    parser.add_argument("--cache-a", required=True)
    parser.add_argument("--cache-b", required=True)
    parser.add_argument("--compare", required=True, help="build A's meshcol command line")
    parser.add_argument("--ref", default="HEAD~1")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    commands = {"A": args.compare.split(), "B": [str(Path(sys.executable).with_name("meshcol"))]}
    caches = {"A": args.cache_a, "B": args.cache_b}
    scratch = Path(tempfile.mkdtemp(prefix="bench-since-"))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(scratch / "pycache")  # as an installed package has it
    times: dict[tuple[str, str], list[tuple[float, float]]] = {}
    try:
        for k in range(args.rounds):
            for build in "AB" if k % 2 == 0 else "BA":
                for mode in ("cache", "no-cache"):
                    run = scratch / "cache"
                    shutil.rmtree(run, ignore_errors=True)
                    shutil.copytree(caches[build], run)
                    flags = ["--cache-dir", str(run)] if mode == "cache" else ["--no-cache"]
                    before = resource.getrusage(resource.RUSAGE_CHILDREN)
                    start = time.perf_counter()
                    done = subprocess.run(
                        [*commands[build], "ci", "-j", str(args.jobs), *flags,
                         "--changed-since", args.ref],
                        cwd=args.repo, capture_output=True, text=True, env=env,
                    )  # fmt: skip
                    wall = time.perf_counter() - start
                    after = resource.getrusage(resource.RUSAGE_CHILDREN)
                    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
                    if done.returncode not in (0, 1):
                        raise SystemExit(f"{build} {mode} failed: {done.stderr[-2000:]}")
                    times.setdefault((build, mode), []).append((wall, cpu))
                    line = done.stderr.strip().splitlines()[-1]
                    print(f"round {k + 1} {build} {mode:<8} {wall:6.2f} s, CPU {cpu:.2f} s  {line}")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    print(f"A = {args.compare}; B = {' '.join(commands['B'])}")
    for (build, mode), values in sorted(times.items()):
        walls, cpus = [w for w, _ in values], [c for _, c in values]
        print(
            f"  {build} {mode:<8} wall {min(walls):.2f}-{max(walls):.2f} s, "
            f"CPU {min(cpus):.2f}-{max(cpus):.2f} s"
        )


if __name__ == "__main__":
    main()
