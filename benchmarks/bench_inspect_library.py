"""``meshcol inspect`` at library scale, A/B: CPU seconds of whole runs of two builds.

Times ``meshcol inspect INPUT --report FILE`` with this checkout's ``.venv/bin/meshcol`` and a
baseline executable, alternated (B A A B per round), on the scale scenes of
:mod:`bench_scale` (unique convex props, 1,000 and 10,000), a torus of about a million faces
(written once to ``benchmarks/.cache/``) and any ``--mesh`` given (Menagerie's
``d405_solid.stl``). CPU is the child's user + system time (``RUSAGE_CHILDREN``); each line
gives the range over the rounds and the load average before the round, and whether the two
reports are byte-identical.

    .venv/bin/python benchmarks/bench_inspect_library.py --baseline ../base40/.venv/bin/meshcol \\
        --rounds 3 --mesh .../mujoco_menagerie/aloha/assets/d405_solid.stl
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import scene_folder

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / "benchmarks" / ".cache"


def torus_file(sections: int = 1000) -> Path:
    """A torus of ``2 * sections * sections / 2`` faces (about a million for 1000), as OBJ."""
    import trimesh

    path = CACHE / f"torus-{sections}.obj"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        mesh = trimesh.creation.torus(
            major_radius=0.4,
            minor_radius=0.1,
            major_sections=sections,
            minor_sections=sections // 2,
        )
        mesh.export(path)
    return path


def run(executable: str, target: str, report: Path) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one inspect run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [executable, "inspect", target, "--report", str(report)],
        check=False,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"},
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="the other build's meshcol")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--scenes", default="1000,10000", help="scale scenes, comma-separated")
    parser.add_argument("--torus", type=int, default=1000, help="torus sections (0: none)")
    parser.add_argument("--mesh", action="append", default=[], help="a mesh file (repeatable)")
    args = parser.parse_args()
    new = str(ROOT / ".venv" / "bin" / "meshcol")
    targets = [str(scene_folder(int(n)) / "scene.json") for n in args.scenes.split(",") if n]
    if args.torus:
        targets.append(str(torus_file(args.torus)))
    targets += args.mesh
    with tempfile.TemporaryDirectory() as tmp:
        for target in targets:
            times: dict[str, list[float]] = {"A": [], "B": []}
            loads = []
            for _ in range(args.rounds):
                loads.append(os.getloadavg()[0])
                for side in "BAAB":
                    executable = new if side == "A" else args.baseline
                    cpu, _ = run(executable, target, Path(tmp) / f"{side}.json")
                    times[side].append(cpu)
            same = (Path(tmp) / "A.json").read_bytes() == (Path(tmp) / "B.json").read_bytes()
            a, b = times["A"], times["B"]
            print(
                f"{Path(target).parent.name}/{Path(target).name}: "
                f"new {min(a):.2f}-{max(a):.2f} s CPU, base {min(b):.2f}-{max(b):.2f} s, "
                f"ratio {min(b) / min(a):.2f}x (best), load {min(loads):.1f}-{max(loads):.1f}, "
                f"reports {'identical' if same else 'DIFFER'}",
                flush=True,
            )


if __name__ == "__main__":
    main()
