"""A glTF of many nodes sharing a few meshes (issue 29 item 12: 100,000 overlapping nodes
aborted the native core): writes the file, then times ``meshcol inspect`` and ``meshcol check``
on it in fresh processes (wall and CPU time of the child, its peak memory) and prints the
verdicts' first lines.

    .venv/bin/python benchmarks/bench_gltf_nodes.py [--nodes 100000] [--layout grid|pile]

``grid``: nodes on a grid whose pitch makes each touch its neighbours (candidate pairs grow
with the nodes); ``pile``: every node within one mesh's size of the origin (every pair is a
candidate: the case that must be refused, not computed).
"""

from __future__ import annotations

import argparse
import json
import resource
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh


def _meshes() -> list[trimesh.Trimesh]:
    return [
        trimesh.creation.box(extents=(1.0, 1.0, 1.0)),
        trimesh.creation.icosphere(subdivisions=1, radius=0.6),
        trimesh.creation.cylinder(radius=0.4, height=1.0, sections=12),
        trimesh.creation.capsule(height=0.6, radius=0.3, count=(8, 8)),
    ]


def write_glb(path: Path, nodes: int, layout: str, seed: int = 29) -> None:
    """A GLB of ``nodes`` nodes, each an instance of one of four shared meshes."""
    blobs, views, accessors, meshes = [], [], [], []
    offset = 0
    for mesh in _meshes():
        v = np.asarray(mesh.vertices, dtype=np.float32)
        f = np.asarray(mesh.faces, dtype=np.uint32)
        for data, target, kind, count, extra in (
            (v, 34962, "VEC3", len(v), {"min": v.min(0).tolist(), "max": v.max(0).tolist()}),
            (f.reshape(-1), 34963, "SCALAR", f.size, {}),
        ):
            raw = data.tobytes()
            views.append(
                {"buffer": 0, "byteOffset": offset, "byteLength": len(raw), "target": target}
            )
            accessors.append(
                {
                    "bufferView": len(views) - 1,
                    "componentType": 5126 if data.dtype == np.float32 else 5125,
                    "count": int(count),
                    "type": kind,
                    **extra,
                }
            )
            blobs.append(raw)
            offset += len(raw)
        meshes.append(
            {
                "primitives": [
                    {"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1}
                ]
            }
        )
    rng = np.random.default_rng(seed)
    if layout == "grid":
        side = int(np.ceil(nodes ** (1 / 3)))
        cells = np.stack(np.unravel_index(np.arange(nodes), (side, side, side)), 1)
        where = cells * 0.95  # neighbours overlap by 5 cm
    else:
        where = rng.uniform(-0.5, 0.5, size=(nodes, 3))
    node_list = [
        {"mesh": int(k % len(meshes)), "translation": [float(x) for x in where[k]]}
        for k in range(nodes)
    ]
    document = {
        "asset": {"version": "2.0", "generator": "meshcol benchmarks/bench_gltf_nodes.py"},
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": meshes,
        "nodes": node_list,
        "scenes": [{"nodes": list(range(nodes))}],
        "scene": 0,
    }
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary = b"".join(blobs)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    with open(path, "wb") as out:
        out.write(struct.pack("<4sII", b"glTF", 2, total))
        out.write(struct.pack("<I4s", len(text), b"JSON") + text)
        out.write(struct.pack("<I4s", len(binary), b"BIN\0") + binary)


def timed(args: list[str]) -> tuple[float, float, float, int, str]:
    """Wall s, child CPU s, child peak RSS (MB), exit code and stderr's last line."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    last = (done.stderr.strip().splitlines() or [""])[-1]
    return wall, cpu, after.ru_maxrss / 1024, done.returncode, last


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100_000)
    parser.add_argument("--layout", choices=("grid", "pile"), default="grid")
    parser.add_argument("--keep", type=Path, help="write the GLB here (default: a temp folder)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = args.keep or Path(folder) / f"nodes_{args.nodes}_{args.layout}.glb"
        start = time.perf_counter()
        write_glb(path, args.nodes, args.layout)
        print(
            f"wrote {path.name} ({path.stat().st_size / 1e6:.1f} MB) in "
            f"{time.perf_counter() - start:.1f} s"
        )
        meshcol = [sys.executable, "-m", "meshcol"]
        runs = {
            "inspect": [*meshcol, "inspect", str(path), "--format", "json"],
            "check": [*meshcol, "check", str(path), "--shape", "hull", "--fail-on", "none"],
        }
        for name, command in runs.items():
            wall, cpu, rss, code, last = timed(command)
            print(f"{name}: exit {code}, {wall:.1f} s wall, {cpu:.1f} s CPU, peak {rss:.0f} MB")
            print(f"  {last[:200]}")


if __name__ == "__main__":
    main()
