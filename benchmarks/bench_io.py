"""Mesh loading benchmark: meshcol's native OBJ/STL readers vs trimesh, one run, A/B alternated.

Run from the repository root:  .venv/bin/python benchmarks/bench_io.py [--files N] [--rounds R]

Cases, each measured as a user pays it (Python call to geometry in numpy arrays):

- N unique small assets (the hull of 300 random points, about 600 triangles), written once as
  OBJ and as binary STL into ``benchmarks/.cache/io``: trimesh (``trimesh.load(file,
  process=False)`` per file, no merge) against ``meshcol.io.mesh_read.load_meshes`` (parsing
  in the core on all cores, merged) and ``load_mesh`` per file (merged).
- One large OBJ and binary STL (a 1000 x 1000 grid sphere, 2 million triangles).
- With ``--usd-quads Q``: one USD crate file (``.usdc``) of 8 grid-sphere meshes of quads,
  Q quads in all, under transformed Xforms, centimetres, Y up (4.5 million quads make
  about 100 MB): usd-core alone (open the stage, traverse it, every mesh's points, counts and
  indices copied into numpy arrays) against ``load_mesh`` (that, plus world transforms,
  triangulation, units and axes; with and without the vertex merge).

Rounds alternate the readers; the range (min-max) over rounds is printed with the ratios.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from meshcol.io.mesh_read import load_mesh, load_meshes

CACHE = Path(__file__).resolve().parent / ".cache" / "io"


def small_assets(count: int) -> dict[str, list[Path]]:
    rng = np.random.default_rng(7)
    files: dict[str, list[Path]] = {"obj": [], "stl": []}
    CACHE.mkdir(parents=True, exist_ok=True)
    for i in range(count):
        paths = {kind: CACHE / f"asset{i:05d}.{kind}" for kind in files}
        if not all(p.exists() for p in paths.values()):
            points = rng.normal(size=(300, 3)) + rng.uniform(-50, 50, size=3)
            hull = ConvexHull(points)
            mesh = trimesh.Trimesh(points, hull.simplices, process=True)
            for p in paths.values():
                mesh.export(p)
        for kind, p in paths.items():
            files[kind].append(p)
    return files


def large_sphere() -> dict[str, Path]:
    paths = {kind: CACHE / f"sphere2m.{kind}" for kind in ("obj", "stl")}
    if not all(p.exists() for p in paths.values()):
        CACHE.mkdir(parents=True, exist_ok=True)
        n = 1000
        theta, phi = np.meshgrid(
            np.linspace(0, np.pi, n + 1)[1:-1], np.linspace(0, 2 * np.pi, n, endpoint=False)
        )
        rings = np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1
        )
        rings = rings.transpose(1, 0, 2).reshape(-1, 3)  # ring by ring
        vertices = np.vstack([rings, [[0, 0, 1], [0, 0, -1]]])
        r, c = np.meshgrid(np.arange(n - 2), np.arange(n), indexing="ij")
        a, b = r * n + c, r * n + (c + 1) % n
        d, e = a + n, b + n
        faces = np.concatenate(
            [np.stack([a, d, b], -1).reshape(-1, 3), np.stack([b, d, e], -1).reshape(-1, 3)]
        )
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        for p in paths.values():
            mesh.export(p)
    return paths


def usd_level(quads: int) -> Path:
    """The USD case's file (made once per size)."""
    from pxr import Gf, Usd, UsdGeom

    path = CACHE / f"level{quads}.usdc"
    if path.exists():
        return path
    CACHE.mkdir(parents=True, exist_ok=True)
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    n = max(4, int(np.sqrt(quads / 8)))
    theta, phi = np.meshgrid(np.linspace(0.1, np.pi - 0.1, n), np.linspace(0, 2 * np.pi, n))
    points = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    points = (100.0 * points.reshape(-1, 3)).astype(np.float32)
    r, c = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    corners = np.stack([r * n + c, r * n + c + 1, (r + 1) * n + c + 1, (r + 1) * n + c], -1)
    indices = corners.reshape(-1).astype(np.int32)
    from pxr import Vt

    for k in range(8):
        xform = UsdGeom.Xform.Define(stage, f"/World/part{k}")
        xform.AddTranslateOp().Set(Gf.Vec3d(300.0 * k, 0, 0))
        xform.AddRotateYOp().Set(10.0 * k)
        mesh = UsdGeom.Mesh.Define(stage, f"/World/part{k}/mesh")
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
        mesh.CreateFaceVertexCountsAttr(
            Vt.IntArray.FromNumpy(np.full(len(corners.reshape(-1, 4)), 4, np.int32))
        )
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    stage.GetRootLayer().Save()
    return path


def usd_core_alone(path: Path) -> list:
    """usd-core's own read of every mesh into numpy arrays: the floor meshcol is held to."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    out = []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            mesh = UsdGeom.Mesh(prim)
            out.append(
                (
                    np.asarray(mesh.GetPointsAttr().Get(), dtype=np.float64),
                    np.asarray(mesh.GetFaceVertexCountsAttr().Get(), dtype=np.int64),
                    np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), dtype=np.int64),
                )
            )
    return out


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def compare(label: str, readers: dict, rounds: int, per: int) -> None:
    times: dict[str, list[float]] = {name: [] for name in readers}
    for _ in range(rounds):
        for name, fn in readers.items():  # alternated within each round
            times[name].append(timed(fn))
    base = next(iter(readers))
    best_base = min(times[base])
    for name, values in times.items():
        lo, hi = min(values), max(values)
        unit = 1e6 / per if per > 1 else 1e3
        suffix = "us/file" if per > 1 else "ms"
        print(
            f"{label:<28} {name:<26} {lo * unit:9.1f}-{hi * unit:9.1f} {suffix}"
            f"   x{best_base / lo:6.1f} vs {base}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--usd-quads", type=int, default=0, help="the USD case's size (0: none)")
    parser.add_argument("--usd-only", action="store_true", help="only the USD case")
    args = parser.parse_args()
    if args.usd_quads:
        path = usd_level(args.usd_quads)
        compare(
            f"USD {path.stat().st_size / 1e6:.0f} MB",
            {
                "usd-core alone": lambda: usd_core_alone(path),
                "meshcol load_mesh": lambda: load_mesh(path),
                "meshcol load_mesh merge=False": lambda: load_mesh(path, merge=False),
            },
            max(2, args.rounds // 2),
            1,
        )
    if args.usd_only:
        return
    files = small_assets(args.files)
    for kind, paths in files.items():
        compare(
            f"{args.files} small {kind.upper()}",
            {
                "trimesh.load per file": lambda paths=paths: [
                    trimesh.load(p, process=False) for p in paths
                ],
                "meshcol load_mesh per file": lambda paths=paths: [load_mesh(p) for p in paths],
                "meshcol load_meshes": lambda paths=paths: load_meshes(paths),
            },
            args.rounds,
            len(paths),
        )
    for kind, path in large_sphere().items():
        compare(
            f"2M-triangle {kind.upper()}",
            {
                "trimesh.load": lambda path=path: trimesh.load(path, process=False),
                "meshcol load_mesh": lambda path=path: load_mesh(path),
            },
            max(2, args.rounds // 2),
            1,
        )


if __name__ == "__main__":
    main()
