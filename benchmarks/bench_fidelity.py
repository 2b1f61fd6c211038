"""Fidelity search benchmark: CoACD at its default threshold vs ``--max-hausdorff`` search.

Run from the repository root:  .venv/bin/python benchmarks/bench_fidelity.py [--quick]

For a few corpus meshes (../shared/corpus), the target D is a fraction of the mesh's
bounding-box diagonal (``--fraction``, default 2%). Printed per mesh: parts and the larger
one-sided Hausdorff distance of the default threshold (0.05), and of the search's chosen step;
the search's cost in engine calls and seconds (cold cache), and the replay from the cache
(warm). No peer: no other tool searches decomposition parameters for a fidelity target. The
machine is shared: times are single runs, ranges over ``--repeats`` where asked.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

from meshcol.decomposition.decompose import decompose
from meshcol.decomposition.search import SearchTarget, search_decomposition

CORPUS = Path(__file__).resolve().parent.parent.parent / "shared" / "corpus"
MESHES = [
    "trimesh-models/7_8ths_cube.stl",
    "trimesh-models/angle_block.STL",
    "coacd-examples/SnowFlake.obj",
]
# CoACD settings of the fast test lane, so that the benchmark runs in minutes on 2 cores.
FAST = {
    "resolution": 500,
    "engine_options": {"mcts_iterations": 20, "mcts_nodes": 8, "mcts_max_depth": 2},
}


def hausdorff(d) -> float:
    return max(d.metrics.hausdorff_mesh_to_parts, d.metrics.hausdorff_parts_to_mesh)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the first mesh only")
    parser.add_argument("--fraction", type=float, default=0.02)
    parser.add_argument("--steps", type=int, default=8)
    args = parser.parse_args()
    names = MESHES[:1] if args.quick else MESHES
    print(
        f"{'mesh':28} {'D':>9} {'default':>16} {'search':>16} {'calls':>5} {'cold s':>7} {'warm s':>7}"
    )
    for name in names:
        path = CORPUS / name
        if not path.is_file():
            print(f"{name}: absent (../shared/corpus)")
            continue
        mesh = trimesh.load(path, force="mesh")
        v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        d_limit = args.fraction * float(np.linalg.norm(np.ptp(v, axis=0)))
        target = SearchTarget(max_hausdorff=d_limit, max_steps=args.steps)
        with tempfile.TemporaryDirectory() as cache:
            plain = decompose((v, f), cache_dir=cache, use_cache=False, **FAST)
            start = time.perf_counter()
            result = search_decomposition((v, f), target, cache_dir=cache, **FAST)
            cold = time.perf_counter() - start
            start = time.perf_counter()
            replay = search_decomposition((v, f), target, cache_dir=cache, **FAST)
            warm = time.perf_counter() - start
            assert replay.engine_calls == 0
        chosen = result.decomposition
        print(
            f"{name:28} {d_limit:9.4g} {len(plain.parts):4d} p {hausdorff(plain):9.4g} "
            f"{len(chosen.parts):4d} p {hausdorff(chosen):9.4g} {result.engine_calls:5d} "
            f"{cold:7.2f} {warm:7.2f}  {'met' if result.met else 'MISSED'} ({result.stopped})"
        )


if __name__ == "__main__":
    main()
