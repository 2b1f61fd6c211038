"""Dumps bench_narrowphase.py's smooth-hull cases (16, 64 and 256 points; separated, touching
and penetrating; 2,000 pairs each) as raw arrays for narrowphase_driver.cpp, so that
callgrind counts the core's instructions on exactly the benchmark's pairs; and the same cases
of 8-point hulls, the one size whose penetrating pairs run SAT (its work bound stops it on
the larger ones), and of the box-like family (``box_*``: cuboids and wedges). The set's
computed edge classes (``edge_offsets``, ``edge_directions``) are written beside its arrays,
for a core from before they were computed on first use.

Run: .venv/bin/python benchmarks/narrowphase_cases.py OUT_DIR
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_narrowphase import make_case, touching_case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out_dir", type=Path, help="folder to write the cases into")
    out = parser.parse_args().out_dir
    out.mkdir(parents=True, exist_ok=True)
    for n in (8, 16, 64, 256, 0):  # 0: the box-like family (cuboids and wedges)
        for label in ("separated", "touching", "penetrating"):
            cs, poses, pairs, shapes = make_case(n, 2000, label == "penetrating", n, n == 0)
            if label == "touching":
                cs, poses, pairs, shapes = touching_case(cs, poses, pairs, shapes)
            fields = (*cs._FIELDS, "edge_offsets", "edge_directions")
            arrays = {f: np.ascontiguousarray(getattr(cs, f)) for f in fields}
            arrays["poses"] = np.ascontiguousarray(poses, dtype=np.float64)
            arrays["pairs"] = np.ascontiguousarray(pairs, dtype=np.int64)
            case = out / f"{n if n else 'box'}_{label}"
            case.mkdir(exist_ok=True)
            for name, a in arrays.items():
                a.tofile(case / f"{name}.bin")
            print(case, len(cs), len(pairs))


if __name__ == "__main__":
    main()
