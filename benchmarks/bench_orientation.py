"""Orientation of a shuffled mesh: the core's ``orient_faces`` (cpp/src/orientation.cpp)
against the Python version it replaced (tests/geometry/orientation_reference.py), on the same
faces in one process, A and B alternated. CPU time of single-threaded runs
(``time.process_time``), so the figure holds on a loaded machine; the results must be equal.

    .venv/bin/python benchmarks/bench_orientation.py [--faces 1000000] [--rounds 3]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "geometry"))

from orientation_reference import reference_orientation

from meshcol.collision.orientation import orient_consistently


def shuffled_torus(faces: int, seed: int = 29) -> tuple[np.ndarray, np.ndarray]:
    """A torus of about ``faces`` faces, half of them reversed at random."""
    minor = max(3, round((faces / 8) ** 0.5))
    major = max(3, faces // (2 * minor))
    mesh = trimesh.creation.torus(1.0, 0.3, major_sections=major, minor_sections=minor)
    f = np.asarray(mesh.faces, dtype=np.int64)
    flip = np.random.default_rng(seed).random(len(f)) < 0.5
    return np.asarray(mesh.vertices), np.where(flip[:, None], f[:, ::-1], f)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--faces", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    v, f = shuffled_torus(args.faces)
    times: dict[str, list[float]] = {"python": [], "core": []}
    for _ in range(args.rounds):
        for name, run in (("python", reference_orientation), ("core", orient_consistently)):
            start = time.process_time()
            found = run(v, f)
            times[name].append(time.process_time() - start)
            if name == "python":
                expected = found
        assert np.array_equal(found.faces, expected.faces) and found.closed == expected.closed
    print(f"{len(f)} faces, shuffled torus; CPU seconds over {args.rounds} alternated rounds")
    for name, values in times.items():
        print(f"  {name:7s} {min(values):.3f} - {max(values):.3f}")
    ratio = min(times["python"]) / min(times["core"])
    print(f"  speed-up (best vs best): {ratio:.1f}x; results equal")


if __name__ == "__main__":
    main()
