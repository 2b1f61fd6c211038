"""CPU time of writing one ``meshcol check`` report (issue 32 items 4-5): the JSON report of a
manifest written to a file through the run's output guard (``staged_outputs``: a temporary
file renamed into place), several times in one process, with user and system seconds apart.

Each side runs in a child process of its own Python (``--baseline``: another environment's,
e.g. main's, alternated with this one), checks the manifest once (not timed), then writes its
report ``--writes`` times; each write prints its user, system and wall seconds. User time is
the formatting (every thread); system time is the kernel copying the text into the page cache
and the rename, which swings with the machine's memory and load.

Run: .venv/bin/python benchmarks/bench_report_write.py MANIFEST [--baseline ../base/.venv/bin/python]
     [--rounds 2] [--writes 3] [--out /tmp/report-write]
e.g. benchmarks/bench_report_write.py benchmarks/.cache/scale/primitives-spheres100000/scene.json
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import same_reports

_CHILD = """
import resource, sys, time
from meshcol.analysis.check import check
from meshcol.io.formats import write_report
from meshcol.io.staging import staged_outputs

manifest, out, writes = sys.argv[1], sys.argv[2], int(sys.argv[3])
report = check([manifest], fail_on="none")
for _ in range(writes):
    a, w = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    with staged_outputs():
        write_report(report, "json", out)
    b = resource.getrusage(resource.RUSAGE_SELF)
    print(b.ru_utime - a.ru_utime, b.ru_stime - a.ru_stime, time.perf_counter() - w)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("manifest")
    parser.add_argument("--baseline", help="another environment's python (A/B, alternated)")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--writes", type=int, default=3)
    parser.add_argument("--out", default=None, help="folder for the reports (a temporary one)")
    args = parser.parse_args()
    sides = {"this": sys.executable}
    if args.baseline:
        sides["baseline"] = args.baseline
    out = Path(args.out or tempfile.mkdtemp(prefix="report-write-"))
    out.mkdir(parents=True, exist_ok=True)
    figures: dict[str, list[tuple[float, float, float]]] = {side: [] for side in sides}
    print(f"load average before: {os.getloadavg()}")
    for round_ in range(args.rounds):
        order = list(sides.items())
        for side, python in order[::-1] if round_ % 2 else order:
            report = str(out / f"report-{side}.json")
            lines = subprocess.run(
                [python, "-c", _CHILD, args.manifest, report, str(args.writes)],
                capture_output=True,
                text=True,
                check=True,
            ).stdout.split("\n")
            figures[side] += [tuple(map(float, line.split())) for line in lines if line]
    for side, runs in figures.items():
        user, system, wall = zip(*runs)
        print(
            f"{side:>9}: user {min(user):.3f}-{max(user):.3f} s, system "
            f"{min(system):.3f}-{max(system):.3f} s, wall {min(wall):.3f}-{max(wall):.3f} s "
            f"({len(runs)} writes)"
        )
    if args.baseline:
        print(f"reports: {same_reports(out, list(sides))}")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
