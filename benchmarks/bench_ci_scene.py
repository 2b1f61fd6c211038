"""``meshcol ci`` on one scene of thousands of bodies after one of its meshes changed: the
per-pair cache (only the pairs of the changed body measured again) against the per-job
cache alone (the whole scene's narrow phase again).

Writes a repository with one manifest of N bodies (each its own OBJ file: boxes, tilted
boxes and icospheres on a crowded grid, so that most bodies have a few neighbours inside the
broad phase's margin, some touching or penetrating), a ``meshcol.toml`` that checks it, and
runs the command line as a user would (a new process each time). Then, in alternating rounds:

- A, per pair: one mesh edited (a different body each time), ``meshcol ci`` with the cache;
- B, per job: another mesh edited, the per-pair entries removed from the cache first, so the
  run is what a job-level cache gives (the scene's job re-runs whole).

The figures are the child processes' CPU time (user + system, ``RUSAGE_CHILDREN``: what the
machine's load does not move much) and wall time. Then the narrow phase alone, in this
process (CPU time): one body moved, through the pair cache against without it, alternated,
the two tables equal to the bit. At the end the cached report of the final tree is compared
with a cold ``--no-cache`` run's: the same bytes but the times.

    .venv/bin/python benchmarks/bench_ci_scene.py --bodies 3000 --rounds 3
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ci import untimed

CONFIG = """[[scenes]]
path = "level/scene.json"
check = { fail-on = "penetration", clearance = 0.05 }
"""

#: The command line of meshcol; default the entry point beside this Python.
COMMAND: list[str] = [str(Path(sys.executable).with_name("meshcol"))]


def mesh_text(kind: int, size: float) -> str:
    """A box (kind 0 and 1) or an icosahedron (kind 2) of about ``size``."""
    if kind < 2:
        h = size / 2
        corners = [(x, y, z) for z in (-h, h) for y in (-h, h) for x in (-h, h)]
        faces = [(1, 3, 4), (1, 4, 2), (5, 6, 8), (5, 8, 7), (1, 2, 6), (1, 6, 5)]
        faces += [(2, 4, 8), (2, 8, 6), (4, 3, 7), (4, 7, 8), (3, 1, 5), (3, 5, 7)]
    else:
        t = (1 + math.sqrt(5)) / 2
        s = size / 2 / math.sqrt(1 + t * t)
        raw = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t)]
        raw += [(0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
        corners = [(x * s, y * s, z * s) for x, y, z in raw]
        faces = [(1, 12, 6), (1, 6, 2), (1, 2, 8), (1, 8, 11), (1, 11, 12), (2, 6, 10)]
        faces += [(6, 12, 5), (12, 11, 3), (11, 8, 7), (8, 2, 9), (4, 10, 5), (4, 5, 3)]
        faces += [(4, 3, 7), (4, 7, 9), (4, 9, 10), (5, 10, 6), (3, 5, 12), (7, 3, 11)]
        faces += [(9, 7, 8), (10, 9, 2)]
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in corners]
    return "\n".join(lines + [f"f {a} {b} {c}" for a, b, c in faces]) + "\n"


def make(root: Path, count: int) -> None:
    (root / "level" / "meshes").mkdir(parents=True)
    side = math.ceil(math.sqrt(count))
    bodies = []
    for i in range(count):
        kind = i % 3
        size = 0.9 + 0.15 * ((i * 7) % 5)
        (root / "level" / "meshes" / f"m{i:05d}.obj").write_text(mesh_text(kind, size))
        body = {
            "name": f"b{i:05d}",
            "mesh": f"meshes/m{i:05d}.obj",
            "position": [float(i % side), float(i // side), 0.0],
        }
        if kind == 1:
            body["rotation"] = {"euler_deg": [0.0, 0.0, 30.0], "order": "xyz"}
        bodies.append(body)
    (root / "level" / "scene.json").write_text(
        json.dumps({"units": "m", "bodies": bodies}, indent=1)
    )
    (root / "meshcol.toml").write_text(CONFIG)


def meshcol(root: Path, *args: str) -> tuple[float, float, str]:
    """Run ``meshcol ci ARGS`` in ``root``: (wall seconds, child CPU seconds, stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([*COMMAND, "ci", *args], cwd=root, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode not in (0, 1):
        raise SystemExit(f"meshcol ci failed ({done.returncode}): {done.stderr[-2000:]}")
    return wall, cpu, done.stdout


def edit(root: Path, index: int, count: int) -> None:
    """Reshape one body's mesh (a little larger: its pairs change, the others do not)."""
    path = root / "level" / "meshes" / f"m{index % count:05d}.obj"
    path.write_text(mesh_text(index % 3, 1.27 + 0.01 * (index % 7)))  # never a size made


def narrow_phase_times(root: Path, rounds: int) -> None:
    """In this process, the narrow phase alone (``analysis.check.narrow_phase``) of the scene
    after one body moved: through the pair cache (A) against without it (B), alternated,
    CPU time; each A's table checked equal to B's to the bit."""
    import dataclasses

    import numpy as np

    from meshcol.analysis.check import CheckOptions, narrow_phase
    from meshcol.analysis.colliders import build_colliders
    from meshcol.analysis.pair_cache import PairCache
    from meshcol.analysis.pairs import MEASURES, broad_phase, place
    from meshcol.io.scene import load_inputs

    scene = load_inputs([str(root / "level" / "scene.json")])
    store = root.parent / "narrow-cache"
    plain = CheckOptions(clearance=0.05)
    cached = CheckOptions(clearance=0.05, pair_cache=PairCache(store, "level"))

    def table_of(bodies: tuple) -> tuple:
        placed = place(build_colliders(bodies, "hull"))
        return broad_phase(placed, 0.05 + plain.tolerance), placed

    table, placed = table_of(scene.bodies)
    narrow_phase(table, placed, cached)  # the cache of the scene as it was
    times: dict[str, list[float]] = {"A per pair": [], "B none": []}
    for k in range(rounds):
        bodies = list(scene.bodies)
        moved = bodies[(k * 53 + 7) % len(bodies)]
        pose = moved.pose.copy()
        pose[2, 3] += 0.05 * (k + 1)
        bodies[(k * 53 + 7) % len(bodies)] = dataclasses.replace(moved, pose=pose)
        table, placed = table_of(tuple(bodies))
        start = time.process_time()
        a = narrow_phase(table, placed, cached)
        times["A per pair"].append(time.process_time() - start)
        start = time.process_time()
        b = narrow_phase(table, placed, plain)
        times["B none"].append(time.process_time() - start)
        for name in (*MEASURES, "depth_upper"):
            left, right = getattr(a, name), getattr(b, name)
            assert np.array_equal(left, right, equal_nan=left.dtype.kind == "f"), name
        counts = cached.pair_cache.counts
        print(f"narrow round {k + 1}: {counts['measured']} of {len(table)} pairs measured")
    for name, values in times.items():
        print(f"narrow phase {name}: cpu {min(values):.3f}-{max(values):.3f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bodies", type=int, default=3000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--keep", action="store_true", help="Keep the repository.")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="meshcol-bench-ci-scene-"))
    root, cache = folder / "repo", folder / "cache"
    root.mkdir()
    make(root, args.bodies)
    flags = ["--cache-dir", str(cache), "--report", "-"]
    wall, cpu, cold = meshcol(root, *flags)
    pairs = json.loads(cold)["runs"][0]["report"]["summary"]
    print(f"{args.bodies} bodies, {pairs.get('candidate_pairs', '?')} candidate pairs")
    print(f"cold: wall {wall:.2f} s, cpu {cpu:.2f} s")
    rows: dict[str, list[tuple[float, float]]] = {"A per pair": [], "B per job": []}
    for k in range(args.rounds):
        edit(root, 2 * k * 37 + 11, args.bodies)
        rows["A per pair"].append(meshcol(root, *flags)[:2])
        edit(root, (2 * k + 1) * 37 + 11, args.bodies)
        shutil.rmtree(cache / "results" / "pairs", ignore_errors=True)
        rows["B per job"].append(meshcol(root, *flags)[:2])
        print(f"round {k + 1}: A {rows['A per pair'][-1]}, B {rows['B per job'][-1]}")
    for name, values in rows.items():
        walls, cpus = [v[0] for v in values], [v[1] for v in values]
        print(
            f"{name}: wall {min(walls):.2f}-{max(walls):.2f} s, "
            f"cpu {min(cpus):.2f}-{max(cpus):.2f} s"
        )
    narrow_phase_times(root, args.rounds)
    edit(root, 5, args.bodies)
    _, _, cached = meshcol(root, *flags)
    _, _, fresh = meshcol(root, "--no-cache", "--report", "-")
    same = untimed(cached) == untimed(fresh)
    print(f"cached report after one more change == cold report: {same}")
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    if not same:
        raise SystemExit("the cached report differs from the cold one")


if __name__ == "__main__":
    main()
