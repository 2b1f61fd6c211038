"""Bit-identity of two checkouts' narrow phase on the benchmark's pairs: builds
narrowphase_driver.cpp against each checkout's ``cpp/src``, runs both on every case dumped by
narrowphase_cases.py (one thread), and compares the raw results (distances, depths, normals and
both points of every pair) byte for byte. Exit 1 when a case differs.

Run (cases from ``narrowphase_cases.py CASES``):
    .venv/bin/python benchmarks/narrowphase_identity.py CASES --base /work/base16
"""

from __future__ import annotations

import argparse
import filecmp
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRIVER = ROOT / "benchmarks" / "narrowphase_driver.cpp"


def build(checkout: Path, out: Path) -> Path:
    """The driver compiled against ``checkout``'s core (the flags of its header comment)."""
    sources = sorted(str(p) for p in (checkout / "cpp" / "src").glob("*.cpp"))
    cmd = ["g++", "-std=c++17", "-O3", f"-I{checkout / 'cpp' / 'include'}", str(DRIVER)]
    header = checkout / "cpp" / "include" / "meshcol" / "narrowphase.hpp"
    if "class ShapeRadii" not in header.read_text():
        cmd.append("-DNO_SHAPE_RADII")  # a core from before the radii kept between batches
    if "class EdgeClasses" not in header.read_text():
        cmd.append("-DEAGER_EDGES")  # a core from before the edge classes were computed lazily
    if "class ClimbLists" in header.read_text():
        cmd.append("-DCLIMB_LISTS")  # a core whose sets make fixed-stride climb lists
    subprocess.run([*cmd, *sources, "-lpthread", "-o", str(out)], check=True)
    return out


def run(driver: Path, case: Path, out: Path) -> str:
    """The driver's summary line for one case; the raw results go to ``out``."""
    kind = "0" if case.name.endswith("separated") else "1"
    done = subprocess.run(
        [str(driver), str(case), kind, "1", str(out)], check=True, capture_output=True, text=True
    )
    return done.stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", type=Path, help="directory written by narrowphase_cases.py")
    parser.add_argument("--base", type=Path, required=True, help="the other checkout")
    parser.add_argument("--head", type=Path, default=ROOT, help="default: this checkout")
    args = parser.parse_args()
    cases = sorted(p for p in args.cases.iterdir() if (p / "pairs.bin").is_file())
    if not cases:
        sys.exit(f"{args.cases}: no cases (run narrowphase_cases.py first)")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        with ThreadPoolExecutor(2) as pool:
            base_job = pool.submit(build, args.base, work / "driver_base")
            head_job = pool.submit(build, args.head, work / "driver_head")
            drivers = (base_job.result(), head_job.result())
        differ = 0
        for case in cases:
            outs = (work / f"{case.name}.base", work / f"{case.name}.head")
            for driver, out in zip(drivers, outs):
                run(driver, case, out)
            same = filecmp.cmp(outs[0], outs[1], shallow=False)
            differ += not same
            print(f"{case.name:>18}  {'identical' if same else 'DIFFERENT'}")
    print(f"{len(cases) - differ} of {len(cases)} cases bit-identical")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
