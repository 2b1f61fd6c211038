"""``meshcol inspect`` speed: the whole body inspection and its self-intersection step.

Measures :func:`meshcol.analysis.health.inspect_body` and
:func:`meshcol.collision.self_intersection.self_intersecting_pairs` on trimesh's UV sphere (a
clean closed mesh, fine pole fans) and on corpus meshes, and prints the crossing pairs found.
With ``--baseline FILE`` (a copy of an older ``meshcol/analysis/health.py``, e.g. ``git show
main:meshcol/analysis/health.py > /tmp/old_inspect.py``) the old inspection runs in the same
process, alternated with the new one, and the ratios are printed.

    .venv/bin/python benchmarks/bench_inspect.py --sphere 650 --rounds 2 \\
        --mesh ../shared/corpus/trimesh-models/counter.unitsmm.STL --baseline /tmp/old_inspect.py

With ``--fans`` or ``--piles`` it times whole ``meshcol inspect`` runs instead (wall time and
peak RSS by ``/usr/bin/time``) on the meshes whose face boxes all overlap: trimesh cylinders
of so many sections (their caps are fans around one vertex; OBJ) and piles of long thin
triangles through the origin (each ``(d, -d, 0.01 e)``, d a random unit vector, e normal;
PLY). ``--old-meshcol`` (another checkout's ``.venv/bin/meshcol``) runs alternated with this
one; every run is capped at ``--memory-cap`` GB of address space, so a run that would hold
every candidate pair fails instead of waking the OOM killer on a shared machine.

    .venv/bin/python benchmarks/bench_inspect.py --sphere 0 --fans 8000,20000 \\
        --piles 10000,30000 --rounds 2 --old-meshcol ../main/.venv/bin/meshcol
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _load_baseline(path: str):
    spec = importlib.util.spec_from_file_location("baseline_inspect", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sphere", type=int, default=650, help="UV sphere segments (0: none)")
    parser.add_argument("--mesh", action="append", default=[], help="a mesh file (repeatable)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline", help="an older meshcol/analysis/health.py to compare")
    parser.add_argument("--fans", default="", help="cylinder sections, comma-separated")
    parser.add_argument("--piles", default="", help="pile triangle counts, comma-separated")
    parser.add_argument("--old-meshcol", help="another checkout's meshcol to alternate with")
    parser.add_argument("--memory-cap", type=float, default=6.0, help="GB of address space")
    args = parser.parse_args()
    if args.fans or args.piles:
        _inspect_runs(args)
        return

    import trimesh

    from meshcol.analysis.health import inspect_body
    from meshcol.collision.self_intersection import self_intersecting_pairs
    from meshcol.io.mesh_read import load_mesh
    from meshcol.types import Body

    bodies = []
    if args.sphere:
        s = trimesh.creation.uv_sphere(radius=1.0, count=[args.sphere, args.sphere])
        name = f"uv_sphere_{args.sphere}"
        bodies.append(Body(name=name, source=name, vertices=s.vertices, faces=s.faces))
    for path in args.mesh:
        bodies.extend(load_mesh(path))
    baseline = _load_baseline(args.baseline) if args.baseline else None

    for body in bodies:
        faces = np.asarray(body.faces)
        print(f"{Path(str(body.source)).name} '{body.name}': {len(faces)} faces")
        new_body, new_pairs, old_body, old_pairs = [], [], [], []
        for _ in range(args.rounds):
            t, pairs = _timed(self_intersecting_pairs, body.vertices, faces)
            new_pairs.append(t)
            t, report = _timed(inspect_body, body)
            new_body.append(t)
            if baseline is not None:
                t, old = _timed(baseline.self_intersecting_pairs, body.vertices, faces)
                old_pairs.append(t)
                t, old_report = _timed(baseline.inspect_body, body)
                old_body.append(t)
        line = f"  new: pairs {min(new_pairs):.2f}-{max(new_pairs):.2f} s"
        line += f", inspect_body {min(new_body):.2f}-{max(new_body):.2f} s"
        line += f", {len(pairs)} crossing pairs, findings {report.findings}"
        print(line)
        if baseline is not None:
            line = f"  old: pairs {min(old_pairs):.2f}-{max(old_pairs):.2f} s"
            line += f", inspect_body {min(old_body):.2f}-{max(old_body):.2f} s"
            line += f", {len(old)} crossing pairs, findings {old_report.findings}"
            print(line)
            print(
                f"  old / new: pairs {np.median(old_pairs) / np.median(new_pairs):.1f}x, "
                f"inspect_body {np.median(old_body) / np.median(new_body):.1f}x"
            )


def _pile(count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    e = 0.01 * rng.normal(size=(count, 3))
    return np.stack([d, -d, e], axis=1).reshape(-1, 3), np.arange(3 * count).reshape(count, 3)


def _write_cases(args, folder: Path) -> list[Path]:
    import trimesh

    paths = []
    for sections in filter(None, args.fans.split(",")):
        path = folder / f"cylinder_{sections}.obj"
        trimesh.creation.cylinder(radius=1, height=1, sections=int(sections)).export(path)
        paths.append(path)
    for count in filter(None, args.piles.split(",")):
        path = folder / f"pile_{count}.ply"
        trimesh.Trimesh(*_pile(int(count)), process=False).export(path)
        paths.append(path)
    return paths


def _run(meshcol: str, path: Path, cap_gb: float) -> str:
    """One capped ``meshcol inspect`` run: ``wall s, peak RSS, verdict``."""
    cap = int(cap_gb * 2**30)
    command = ["prlimit", f"--as={cap}", "/usr/bin/time", "-f", "%e %M", meshcol, "inspect"]
    done = subprocess.run([*command, str(path)], capture_output=True, text=True)
    wall, rss = done.stderr.strip().splitlines()[-1].split()[-2:]
    line = f"{float(wall):6.1f} s {int(rss) / 2**20:5.2f} GB"
    if done.returncode not in (0, 1):
        said = [text for text in done.stderr.splitlines() if text.startswith("meshcol:")]
        return line + f", exit {done.returncode}: {(said or ['?'])[-1][:90]}"
    (body,) = json.loads(done.stdout)["bodies"]
    return line + (
        f", self_intersecting {body['self_intersecting']}, "
        f"{body['self_intersecting_pairs']} pairs, findings {body['findings']}"
    )


def _inspect_runs(args) -> None:
    """Whole ``meshcol inspect`` runs, this checkout's and ``--old-meshcol``'s alternated."""
    new = str(Path(sys.executable).with_name("meshcol"))
    with tempfile.TemporaryDirectory() as folder:
        for path in _write_cases(args, Path(folder)):
            print(f"{path.name} ({path.stat().st_size / 2**20:.1f} MB)", flush=True)
            for round_ in range(args.rounds):
                print(f"  new {round_ + 1}: {_run(new, path, args.memory_cap)}", flush=True)
                if args.old_meshcol:
                    line = _run(args.old_meshcol, path, args.memory_cap)
                    print(f"  old {round_ + 1}: {line}", flush=True)


if __name__ == "__main__":
    main()
