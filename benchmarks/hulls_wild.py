"""Wild meshes' exact hulls against qhull: every STL file of the real collections installed from
the registries (the Menagerie wheels, example-robot-data, pybullet_data, dm_control; the
folders ``bench_robots_wild.py`` reads its robots from), through ``meshcol hull`` as a user runs
it (150 files a command, its JSON report), each body's ``exact_hull_volume`` compared with
scipy's qhull:

- on the vertices meshcol read (``meshcol.io.mesh_read.load_mesh``): the same point set, so
  the volumes must agree to rounding (``--tolerance``, relative; exit 1 past it);
- on trimesh's reading of the file (an independent reader, no vertex merging): meshcol merges
  positions equal to 8 decimals (trimesh's own merge tolerance, ``merge_vertices``), so a
  vertex within 1e-8 units of another is not a point of meshcol's hull; the largest relative
  difference shows what that merge costs.

Run:  .venv/bin/python benchmarks/hulls_wild.py [--limit N]
      (make robots-wild / robots-menagerie install the collections)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_robots_wild import MENAGERIE_PACKAGES, example_robot_data, package_folder
from scipy.spatial import ConvexHull

#: Files a ``meshcol hull`` command reads.
CHUNK = 150


def collection_roots() -> dict[str, Path]:
    """The installed collections' folders, by name."""
    roots = {name: package_folder(module) for name, (module, _) in MENAGERIE_PACKAGES.items()}
    roots.update(pybullet_data=package_folder("pybullet_data"))
    roots.update(dm_control=package_folder("dm_control"))
    robots = example_robot_data()  # under <site>/cmeel.prefix/share/example-robot-data/robots
    if robots:
        roots["example-robot-data"] = next(p for p in robots[0].parents if p.name == "robots")
    return {name: root for name, root in roots.items() if root is not None}


def stl_files(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.suffix.lower() == ".stl" and p.is_file())


def hull_reports(files: list[Path], work: Path) -> tuple[list[dict], list[str]]:
    """Every body row of ``meshcol hull`` over ``files``, and the commands that failed."""
    rows, failed = [], []
    for start in range(0, len(files), CHUNK):
        report = work / f"hull{start}.json"
        chunk = [str(f) for f in files[start : start + CHUNK]]
        run = subprocess.run(
            [sys.executable, "-m", "meshcol", "hull", *chunk, "--report", str(report)],
            capture_output=True,
            text=True,
        )
        if run.returncode not in (0, 1) or not report.is_file():
            last = (run.stderr.strip().splitlines() or [""])[-1]
            failed.append(f"files {start}-{start + len(chunk)}: exit {run.returncode}: {last}")
            continue
        rows.extend(json.loads(report.read_text())["bodies"])
    return rows, failed


def compare(row: dict) -> tuple[float, float]:
    """``(relative difference on meshcol's vertices, on trimesh's)`` of one body's hull
    volume against qhull's."""
    import trimesh

    from meshcol.io.mesh_read import load_mesh

    ours = row["exact_hull_volume"]
    read = np.vstack([body.world_vertices() for body in load_mesh(row["source"])])
    same = ConvexHull(read).volume
    raw = np.asarray(trimesh.load(row["source"], process=False, force="mesh").vertices)
    other = ConvexHull(raw).volume
    return abs(ours - same) / same, abs(ours - other) / other


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--limit", type=int, default=None, help="files per collection")
    parser.add_argument("--tolerance", type=float, default=1e-12)
    args = parser.parse_args()
    worst = 0.0
    with tempfile.TemporaryDirectory() as scratch:
        for name, root in collection_roots().items():
            files = stl_files(root)[: args.limit]
            if not files:
                print(f"{name}: no STL file")
                continue
            rows, failed = hull_reports(files, Path(scratch))
            same, other = zip(*(compare(row) for row in rows)) if rows else ((0.0,), (0.0,))
            worst = max(worst, max(same))
            print(
                f"{name}: {len(files)} STL files, {len(rows)} hulls; relative volume "
                f"difference from qhull on meshcol's vertices at most {max(same):.2e}, on "
                f"trimesh's (no merge) at most {max(other):.2e}; commands failed: "
                f"{len(failed)}"
            )
            for line in failed:
                print(f"  {line}")
    print(f"largest difference on the same vertices: {worst:.2e} (tolerance {args.tolerance:g})")
    return 0 if worst <= args.tolerance else 1


if __name__ == "__main__":
    sys.exit(main())
