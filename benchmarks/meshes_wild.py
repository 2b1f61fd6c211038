"""Wild meshes through ``meshcol hull``, ``fit`` and ``inspect``, against oracles that share
none of their code: every STL file of the real collections installed from the registries (the
Menagerie wheels, example-robot-data, pybullet_data, dm_control, genesis-world; the folders
``bench_robots_wild.py`` reads its robots from), 150 files a command as a user runs it, each
command's JSON report read.

Hulls: each body's ``exact_hull_volume`` compared with scipy's qhull

- on the vertices meshcol read (``meshcol.io.mesh_read.load_mesh``): the same point set, so
  the volumes must agree to rounding (``--tolerance``, relative; exit 1 past it);
- on trimesh's reading of the file (an independent reader, no vertex merging): meshcol merges
  positions equal to 8 decimals (trimesh's own merge tolerance, ``merge_vertices``), so a
  vertex within 1e-8 units of another is not a point of meshcol's hull; the largest relative
  difference shows what that merge costs.

Fits (``--shape`` sphere, box, cylinder, capsule and ellipsoid, one command each): every vertex
meshcol read is inside the primitive of the report (centre, quaternion, radius, length, size),
by the tests' oracle (``fit_oracle.signed_distances``, numpy); the largest excess over all
bodies, relative to the body's extent, must be at most 0 (fits are grown by their search's rounding, 1e-9 of the extent: the worst is about
-1e-10).

Inspect: each body's ``watertight``, ``winding_consistent`` (when watertight) and ``volume``
(when both) against trimesh's ``is_watertight``, ``is_winding_consistent`` and ``volume`` of
its own reading of the file (``process=True``: positions merged to 8 decimals, as meshcol
merges); every disagreement is listed (the volume to 1e-9, relative).

Run:  .venv/bin/python benchmarks/meshes_wild.py [--limit N] [--only hulls|fits|inspect]
      (make robots-wild / robots-menagerie install the collections)
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_robots_wild import MENAGERIE_PACKAGES, example_robot_data, meshcol, package_folder
from scipy.spatial import ConvexHull

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the oracles

#: Files a ``meshcol hull`` command reads.
CHUNK = 150


def collection_roots() -> dict[str, Path]:
    """The installed collections' folders, by name."""
    roots = {name: package_folder(module) for name, (module, _) in MENAGERIE_PACKAGES.items()}
    roots.update(pybullet_data=package_folder("pybullet_data"))
    roots.update(dm_control=package_folder("dm_control"))
    genesis = package_folder("genesis")
    roots.update({"genesis-world": None if genesis is None else genesis / "assets"})
    robots = example_robot_data()  # under <site>/cmeel.prefix/share/example-robot-data/robots
    if robots:
        roots["example-robot-data"] = next(p for p in robots[0].parents if p.name == "robots")
    return {name: root for name, root in roots.items() if root is not None}


def stl_files(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.suffix.lower() == ".stl" and p.is_file())


def reports(files: list[Path], work: Path, *command: str) -> tuple[list[dict], list[str]]:
    """Every body row of ``meshcol COMMAND...`` over ``files``, and the commands that
    failed (run by ``bench_robots_wild.meshcol``: a timeout, a traceback whatever the exit
    code, or an exit outside 0 and 1). Each run writes a report of its own, removed first, so
    a run that wrote none is never read from an earlier one."""
    rows, failed = [], []
    for start in range(0, len(files), CHUNK):
        report = work / f"{'-'.join(command).replace('--', '')}-{start}.json"
        report.unlink(missing_ok=True)
        chunk = [str(f) for f in files[start : start + CHUNK]]
        code, last = meshcol(*command, *chunk, "--report", str(report))
        if code not in (0, 1) or last.startswith("TRACEBACK") or not report.is_file():
            failed.append(f"files {start}-{start + len(chunk)}: exit {code}: {last}")
            continue
        rows.extend(json.loads(report.read_text())["bodies"])
    return rows, failed


def read_vertices(source: str) -> np.ndarray:
    """The vertices meshcol read of a file, in the world frame."""
    from meshcol.io.mesh_read import load_mesh

    return np.vstack([body.world_vertices() for body in load_mesh(source)])


def compare(row: dict) -> tuple[float, float]:
    """``(relative difference on meshcol's vertices, on trimesh's)`` of one body's hull
    volume against qhull's."""
    import trimesh

    ours = row["exact_hull_volume"]
    read = read_vertices(row["source"])
    same = ConvexHull(read).volume
    raw = np.asarray(trimesh.load(row["source"], process=False, force="mesh").vertices)
    other = ConvexHull(raw).volume
    return abs(ours - same) / same, abs(ours - other) / other


def excess(shape: str, row: dict, vertices: np.ndarray) -> float:
    """How far the farthest vertex is outside the fitted primitive (negative: inside), in
    the body's units; capsules and cylinders along their local z (the tests' oracle,
    ``fit_oracle.signed_distances``, for all but the ellipsoid)."""
    from fit_oracle import signed_distances
    from oracles import quaternion_rotation

    from meshcol.types import Box, Capsule, Cylinder, Sphere

    local = (vertices - np.asarray(row["center"])) @ quaternion_rotation(row["quaternion"])
    if shape == "ellipsoid":  # a radial excess, scaled to the least semi-axis
        semi = np.asarray(row["size"]) / 2
        return float((np.sqrt(((local / semi) ** 2).sum(axis=1)).max() - 1) * semi.min())
    primitive = {
        "sphere": lambda: Sphere(row["radius"]),
        "box": lambda: Box(tuple(row["size"])),
        "capsule": lambda: Capsule(row["radius"], row["length"] or 0.0),
        "cylinder": lambda: Cylinder(row["radius"], row["length"]),
    }[shape]()
    return float(signed_distances(primitive, local).max())


#: The primitives of ``meshcol fit --shape``.
SHAPES = ("sphere", "box", "cylinder", "capsule", "ellipsoid")


def check_hulls(name: str, files: list[Path], work: Path) -> float:
    """Print one collection's hull comparison; the largest difference on the same vertices."""
    rows, failed = reports(files, work, "hull")
    same, other = zip(*(compare(row) for row in rows)) if rows else ((0.0,), (0.0,))
    print(
        f"{name}: hull of {len(files)} STL files, {len(rows)} hulls; relative volume "
        f"difference from qhull on meshcol's vertices at most {max(same):.2e}, on trimesh's "
        f"(no merge) at most {max(other):.2e}; commands failed: {len(failed)}"
    )
    for line in failed:
        print(f"  {line}")
    return max(same) if not failed else float("inf")


def check_fits(name: str, files: list[Path], work: Path) -> float:
    """Print one collection's fit containment per shape; the largest relative excess."""
    worst = -float("inf")
    for shape in SHAPES:
        rows, failed = reports(files, work, "fit", "--shape", shape)
        excesses = [
            excess(shape, row, v) / float(np.ptp(v, axis=0).max())
            for row in rows
            for v in (read_vertices(row["source"]),)
        ]
        largest = max(excesses, default=0.0)
        worst = max(worst, largest if not failed else float("inf"))
        print(
            f"{name}: fit --shape {shape} of {len(files)} STL files, {len(rows)} fits; the "
            f"farthest vertex at {largest:.2e} of the extent (<= 0: inside); commands "
            f"failed: {len(failed)}"
        )
        for line in failed:
            print(f"  {line}")
    return worst


def disagreements(row: dict) -> list[str]:
    """What trimesh says otherwise of one body's topology and volume."""
    import trimesh

    mesh = trimesh.load(row["source"], force="mesh")
    if row["watertight"] != mesh.is_watertight:
        return [f"watertight {row['watertight']}, trimesh {mesh.is_watertight}"]
    if row["watertight"] and row["winding_consistent"] != mesh.is_winding_consistent:
        return [f"winding {row['winding_consistent']}, trimesh {mesh.is_winding_consistent}"]
    volume = row["volume"]
    if volume is not None and abs(volume - mesh.volume) > 1e-9 * abs(mesh.volume):
        return [f"volume {volume!r}, trimesh {mesh.volume!r}"]
    return []


def check_inspect(name: str, files: list[Path], work: Path) -> int:
    """Print one collection's inspect comparison; the number of disagreements."""
    rows, failed = reports(files, work, "inspect")
    found = [(row["source"], line) for row in rows for line in disagreements(row)]
    print(
        f"{name}: inspect of {len(files)} STL files, {len(rows)} bodies; disagreements "
        f"with trimesh: {len(found)}; commands failed: {len(failed)}"
    )
    for source, line in found + [("", line) for line in failed]:
        print(f"  {source}: {line}")
    return len(found) + len(failed)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--limit", type=int, default=None, help="files per collection")
    parser.add_argument("--tolerance", type=float, default=1e-12, help="hull volumes")
    parser.add_argument("--only", choices=("hulls", "fits", "inspect"), default=None)
    parser.add_argument("--collection", action="append", help="only these (repeatable)")
    args = parser.parse_args()
    hulls, fits, inspected = 0.0, -float("inf"), 0
    with tempfile.TemporaryDirectory() as scratch:
        for name, root in collection_roots().items():
            if args.collection and name not in args.collection:
                continue
            files = stl_files(root)[: args.limit]
            if not files:
                print(f"{name}: no STL file")
                continue
            if args.only in (None, "hulls"):
                hulls = max(hulls, check_hulls(name, files, Path(scratch)))
            if args.only in (None, "fits"):
                fits = max(fits, check_fits(name, files, Path(scratch)))
            if args.only in (None, "inspect"):
                inspected += check_inspect(name, files, Path(scratch))
    print(
        f"hulls: largest volume difference on the same vertices {hulls:.2e} (tolerance "
        f"{args.tolerance:g}); fits: farthest vertex at {fits:.2e} of the extent; inspect: "
        f"{inspected} disagreements"
    )
    return 0 if hulls <= args.tolerance and fits <= 0 and inspected == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
