"""``meshcol inspect`` speed: the whole body inspection and its self-intersection step.

Measures :func:`meshcol.analysis.health.inspect_body` and
:func:`meshcol.collision.self_intersection.self_intersecting_pairs` on trimesh's UV sphere (a
clean closed mesh, fine pole fans) and on corpus meshes, and prints the crossing pairs found.
With ``--baseline FILE`` (a copy of an older ``meshcol/analysis/health.py``, e.g. ``git show
main:meshcol/analysis/health.py > /tmp/old_inspect.py``) the old inspection runs in the same
process, alternated with the new one, and the ratios are printed.

    .venv/bin/python benchmarks/bench_inspect.py --sphere 650 --rounds 2 \\
        --mesh ../shared/corpus/trimesh-models/counter.unitsmm.STL --baseline /tmp/old_inspect.py
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
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
    args = parser.parse_args()

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


if __name__ == "__main__":
    main()
