"""Writes bench_mesh_query.py's four single-pair depth rows as raw arrays for driver.cpp.

Run: .venv/bin/python benchmarks/mesh_query_driver/dump_depth_rows.py OUT_DIR

Meshes ``m4`` (ballA), ``m5`` (ballB), ``m6`` (torus), ``m7`` (the 12,288-face floor), in the
format of dump_family.py, and one pose pair per row: ``m4_balls.p`` (query with ``B=5``),
``m6_moved.p`` (the torus against its copy), ``m7_floor.p`` (``B=6``: the floor against the
resting torus) and ``m6_turned.p`` (the torus against a turned copy), the very pairs of
``depth_rows``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import bench_mesh_query as bench


def main() -> None:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    rows = bench.single_depth_rows()
    ball_a, ball_b, balls = rows["ballA vs ballB (overlapping)"]
    torus, _, moved = rows["torus vs copy moved 30%"]
    floor, _, resting = rows["torus resting on a 12,288-face floor"]
    turned = rows["torus vs turned copy moved 30%"][2]
    meshes = {4: ball_a, 5: ball_b, 6: torus, 7: floor}
    for k, mesh in meshes.items():
        np.ascontiguousarray(mesh.vertices, dtype=np.float64).tofile(out / f"m{k}.v")
        np.ascontiguousarray(mesh.faces, dtype=np.int64).tofile(out / f"m{k}.f")
    poses = {"m4_balls": balls, "m6_moved": moved, "m7_floor": resting, "m6_turned": turned}
    for name, pb in poses.items():
        np.ascontiguousarray(np.stack([np.eye(4), pb]), dtype=np.float64).tofile(out / f"{name}.p")


if __name__ == "__main__":
    main()
