"""Mesh loading benchmark: meshcol's native OBJ/STL readers vs trimesh, one run, A/B alternated.

Run from the repository root:  .venv/bin/python benchmarks/bench_io.py [--files N] [--rounds R]

Cases, each measured as a user pays it (Python call to geometry in numpy arrays):

- N unique small assets (the hull of 300 random points, about 600 triangles), written once as
  OBJ and as binary STL into ``benchmarks/.cache/io``: trimesh (``trimesh.load(file,
  process=False)`` per file, no merge) against ``meshcol.io.mesh_read.load_meshes`` (parsing
  in the core on all cores, merged) and ``load_mesh`` per file (merged).
- One large OBJ and binary STL (a 1000 x 1000 grid sphere, 2 million triangles).
- ``--fbx``: one large binary FBX (trimesh's UV sphere of 2.0 million vertices and 4.0 million
  triangles, uncompressed arrays, about 100 MB, written here): ufbx alone (``ufbx.load_file``
  with meshcol's options, vertices and indices copied into numpy arrays, the floor meshcol's
  reader can reach) against ``meshcol.io.fbx.read_fbx`` (that plus triangulation) and
  ``load_mesh`` (plus the vertex merge); and assimp-py, when installed, as the other
  candidate reader (``assimp_py.import_file`` with triangulation, float32 arrays).
- With ``--usd-quads Q``: one USD crate file (``.usdc``) of 8 grid-sphere meshes of quads,
  Q quads in all, under transformed Xforms, centimetres, Y up (4.5 million quads make
  about 100 MB): usd-core alone (open the stage, traverse it, every mesh's points, counts and
  indices copied into numpy arrays) against ``load_mesh`` (that, plus world transforms,
  triangulation, units and axes; with and without the vertex merge).

Rounds alternate the readers; the range (min-max) over rounds is printed with the ratios.

``--usd-ab PYTHON`` (with ``--usd-quads Q``): the USD case A/B against another build, each
reader in a fresh single-process child (``PYTHON``, e.g. ``/work/base/.venv/bin/python``, the
build before the polygon splitter moved into the core, then this one, alternated round by
round); CPU time (``time.process_time``, what a loaded machine moves least) and wall time of
usd-core alone, usd-core plus the least triangulation any reader needs (the quads fanned by
numpy indexing, the points transformed: the floor), ``load_mesh(merge=False)`` and
``load_mesh``.
"""

from __future__ import annotations

import argparse
import json
import struct
import subprocess
import sys
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


def _record(node: tuple, at: int) -> bytes:
    """One FBX 7.4 binary node record ``(name, properties, count, children)`` starting at
    byte ``at`` (its end offset is absolute)."""
    name, properties, count, children = node
    label = name.encode()
    start = at + 13 + len(label) + len(properties)
    nested = b""
    for child in children:
        nested += _record(child, start + len(nested))
    if children:
        nested += bytes(13)  # the null record that closes a list
    end = start + len(nested)
    return (
        struct.pack("<IIIB", end, count, len(properties), len(label)) + label + properties + nested
    )


def _array(code: bytes, values: np.ndarray) -> bytes:
    data = values.tobytes()
    return code + struct.pack("<III", len(values), 0, len(data)) + data


def _string(text: str) -> bytes:
    return b"S" + struct.pack("<I", len(text)) + text.encode()


def _long(value: int) -> bytes:
    return b"L" + struct.pack("<q", value)


def write_fbx(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """A binary FBX 7.4 file of one mesh node (uncompressed arrays, default settings)."""
    polygon = faces.astype(np.int32).copy()
    polygon[:, 2] = -polygon[:, 2] - 1  # a polygon's last corner is stored as ~index
    geometry = (
        ("Vertices", _array(b"d", vertices.astype(np.float64).reshape(-1)), 1, ()),
        ("PolygonVertexIndex", _array(b"i", polygon.reshape(-1)), 1, ()),
    )
    nodes = (
        ("FBXHeaderExtension", b"", 0, (("FBXVersion", b"I" + struct.pack("<i", 7400), 1, ()),)),
        (
            "Objects",
            b"",
            0,
            (
                (
                    "Geometry",
                    _long(100) + _string("Sphere\x00\x01Geometry") + _string("Mesh"),
                    3,
                    geometry,
                ),
                ("Model", _long(200) + _string("Sphere\x00\x01Model") + _string("Mesh"), 3, ()),
            ),
        ),
        (
            "Connections",
            b"",
            0,
            (
                ("C", _string("OO") + _long(200) + _long(0), 3, ()),
                ("C", _string("OO") + _long(100) + _long(200), 3, ()),
            ),
        ),
    )
    out = bytearray(b"Kaydara FBX Binary  \x00\x1a\x00" + struct.pack("<I", 7400))
    for node in nodes:
        out += _record(node, len(out))
    out += bytes(13)
    path.write_bytes(bytes(out))


def large_fbx() -> Path:
    path = CACHE / "sphere2m.fbx"
    if not path.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        mesh = trimesh.creation.uv_sphere(radius=1.0, count=[1000, 1000])
        write_fbx(path, np.asarray(mesh.vertices), np.asarray(mesh.faces))
    return path


def ufbx_alone(path: Path) -> None:
    """ufbx's load and the copy of every mesh into arrays: what meshcol cannot go below."""
    import ufbx

    scene = ufbx.load_file(
        str(path),
        file_format=ufbx.FileFormat.FBX,
        target_axes=ufbx.axes_right_handed_z_up,
        target_unit_meters=1.0,
        ignore_animation=True,
        ignore_embedded=True,
    )
    for node in scene.nodes:
        mesh = node.mesh
        if mesh is not None:
            np.array(memoryview(mesh.vertices))
            np.array(memoryview(mesh.faces))
            np.fromiter(mesh.vertex_indices, dtype=np.int64, count=mesh.num_indices)
            tuple(node.geometry_to_world)
        del mesh
    del node
    scene.free()


def assimp_alone(path: Path) -> None:
    import assimp_py

    scene = assimp_py.import_file(str(path), assimp_py.Process_Triangulate)
    for mesh in scene.meshes:
        np.frombuffer(mesh.vertices, dtype=np.float32).copy()
        np.frombuffer(mesh.indices, dtype=np.uint32).copy()


def compare_fbx(rounds: int) -> None:
    import gc
    import importlib.util

    from meshcol.io.fbx import read_fbx

    path = large_fbx()
    print(f"{path.name}: {path.stat().st_size / 1e6:.0f} MB")
    readers = {
        "ufbx alone + copy": lambda: ufbx_alone(path),
        "meshcol read_fbx": lambda: read_fbx(path, str(path)),
        "meshcol load_mesh": lambda: load_mesh(path),
    }
    if importlib.util.find_spec("assimp_py") is not None:
        try:
            assimp_alone(path)
            readers["assimp-py (float32)"] = lambda: assimp_alone(path)
        except RuntimeError as error:  # assimp-py 1.1 refuses this minimal file
            print(f"assimp-py: {' '.join(str(error).split())}")
    gc.disable()  # ufbx 0.0.5's objects crash the collector (meshcol.io.fbx says why)
    try:
        compare("100 MB binary FBX", readers, rounds, 1)
    finally:
        gc.enable()


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


def usd_core_fanned(path: Path) -> list:
    """usd-core alone, then the least any reader must add: every quad fanned into two
    triangles by numpy indexing (no convexity test), every point turned into the world."""
    out = []
    for points, _, indices in usd_core_alone(path):
        quads = indices.reshape(-1, 4)
        triangles = quads[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3)
        out.append((np.einsum("ij,nj->ni", np.eye(3), points), triangles))
    return out


def usd_child(path: Path) -> None:
    """One fresh process's CPU and wall times of the USD readers (``--usd-child``), as JSON."""
    readers = {
        "usd-core alone": lambda: usd_core_alone(path),
        "usd-core + fan": lambda: usd_core_fanned(path),
        "load_mesh merge=False": lambda: load_mesh(path, merge=False),
        "load_mesh": lambda: load_mesh(path),
    }
    usd_core_alone(path)  # imports and usd-core's first open out of the figures
    out = {}
    for name, fn in readers.items():
        cpu, wall = time.process_time(), time.perf_counter()
        fn()
        out[name] = (time.process_time() - cpu, time.perf_counter() - wall)
    print(json.dumps(out))


def usd_ab(path: Path, other: str, rounds: int) -> None:
    """A (``other``'s build) and B (this one) alternated, each round a fresh child of each."""
    builds = {"A " + other: other, "B " + sys.executable: sys.executable}
    times: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for _ in range(rounds):
        for build, python in builds.items():
            run = subprocess.run(
                [python, __file__, "--usd-child", str(path)],
                capture_output=True,
                text=True,
                check=True,
            )
            for name, value in json.loads(run.stdout.splitlines()[-1]).items():
                times.setdefault((build, name), []).append(tuple(value))
    print(f"USD {path.stat().st_size / 1e6:.0f} MB, {rounds} rounds, CPU s (wall s) min-max")
    for (build, name), values in times.items():
        cpu = [v[0] for v in values]
        wall = [v[1] for v in values]
        print(
            f"{build[:60]:<60} {name:<22} {min(cpu):7.2f}-{max(cpu):7.2f}"
            f"  ({min(wall):6.2f}-{max(wall):6.2f})"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--fbx", action="store_true", help="only the large FBX case")
    parser.add_argument("--usd-quads", type=int, default=0, help="the USD case's size (0: none)")
    parser.add_argument("--usd-only", action="store_true", help="only the USD case")
    parser.add_argument("--usd-ab", metavar="PYTHON", help="the USD case A/B against PYTHON")
    parser.add_argument("--usd-child", metavar="PATH", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.usd_child:
        usd_child(Path(args.usd_child))
        return
    if args.usd_ab:
        usd_ab(usd_level(args.usd_quads or 1_600_000), args.usd_ab, args.rounds)
        return
    if args.fbx:
        compare_fbx(args.rounds)
        return
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
