"""Writes bench_mesh_query.py's real-mesh family (meshes and poses) as raw arrays for driver.cpp.

Run: .venv/bin/python benchmarks/mesh_query_driver/dump_family.py OUT_DIR [PAIRS]

For each family mesh K (0 fandisk, 1 Solo lower leg, 2 idler riser, 3 Panda link3):
``mK.v`` (float64 vertices), ``mK.f`` (int64 faces) and ``mK_CONFIG.p`` (PAIRS x 2 row-major
4x4 float64 poses) for CONFIG near, touching, apart, with the script's seed (7), so the C++
driver queries the very pairs the Python rows time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import bench_mesh_query as bench


def main() -> None:
    out = Path(sys.argv[1])
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 300
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(7)
    for k, (name, path) in enumerate(bench.FAMILY):
        mesh = bench.centred(trimesh.load(path, force="mesh"))
        np.ascontiguousarray(mesh.vertices, dtype=np.float64).tofile(out / f"m{k}.v")
        np.ascontiguousarray(mesh.faces, dtype=np.int64).tofile(out / f"m{k}.f")
        for config, poses in bench.family_sets(mesh, count, rng).items():
            np.ascontiguousarray(poses, dtype=np.float64).tofile(out / f"m{k}_{config}.p")
        print(name, len(mesh.vertices), len(mesh.faces))


if __name__ == "__main__":
    main()
