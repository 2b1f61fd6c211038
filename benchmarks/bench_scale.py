"""Whole scenes of unique assets, end to end (issue 14): ``meshcol check`` from the command
line, loading included, against trimesh's ``CollisionManager`` and coal's
``DynamicAABBTreeArrayCollisionManager`` doing the same job (load every file, add every body,
collide, one distance per candidate pair).

Scenes: N bodies, each with its own asset file (no two alike): convex props (hulls of 24 to
48 random points on an ellipsoid) and concave props (L-shaped brackets, extruded), about one
in three concave, written as OBJ files plus a JSON manifest, on a jittered grid on the floor
(turned about z) spaced for about 2-3 box overlaps per body. Written once into
``benchmarks/.cache/scale/<N>`` (deterministic seed; delete the folder to regenerate).

Also: a 2-million-triangle mesh (a closed torus, binary STL) beside a cube, checked end to
end; and a 300,000-body manifest (instances of 16 assets) loaded (``load_inputs``, in a
fresh process).

Primitive rows (issue 32): manifests of N primitive bodies and no mesh file (``--primitives``):
``spheres`` (every body a sphere), ``mixed`` (spheres, boxes, capsules and cylinders in
turn, a third of them turned) and ``ellipsoids`` (as mixed, with an ellipsoid of semi-axes
(r, 0.2, 0.25) fifth in turn), on a jittered 3-D grid of pitch 0.8 m with sizes 0.2-0.45 m, so
a few bodies in a hundred touch or overlap a neighbour; ``pile`` (spheres all within 0.1 m of
the origin: N(N-1)/2 candidate pairs, the memory a pair costs); ``meshcol check`` from the command
line, report written, with its wall and CPU time and peak memory.

Each meshcol row also gives its stages from the report (load, check, and the rest of the wall
time: start-up, imports, writing the report). With ``--stages`` each unique-asset size is also
run once more under ``check_stages.py`` (CPU seconds of every stage, in one process: the output
guard, reading the files, the native read inside it, the bodies, the colliders, the hulls
inside them, the geometry keys, the pair stages, the report), the figures a loaded machine
does not move.

Every meshcol figure is a fresh ``meshcol check`` process, timed from outside, with its peak
resident memory (``RUSAGE_CHILDREN`` of a one-child wrapper), after one untimed run of each
side of each case (:func:`warm_up`: bytecode compiled, files in the page cache). Peers run in this process,
loading included, and are skipped with a printed reason when missing or past ``--peer-max``.

Run: .venv/bin/python benchmarks/bench_scale.py [--sizes 1000 10000 100000] [--peer-max 10000]
     [--extras] [--threads 0] [--primitives 100000 1000000]
     [--primitive-kinds spheres mixed ellipsoids]
     [--stages]
Reader alone: .venv/bin/python benchmarks/bench_scale.py --reader --sizes 100000 --repeat 3
     [--baseline ../main/.venv/bin/meshcol]   (the core's read_mesh_files over the unique-asset
     files, one thread, user and system CPU seconds of the call in a fresh process: the system
     part is the kernel's opening and reading, which a loaded machine inflates; with
     --baseline, alternated)
Fit rows (session 39): .venv/bin/python benchmarks/bench_scale.py --baseline
     ../main/.venv/bin/meshcol --repeat 3 --sizes 1000 10000 --fit box auto   (``meshcol fit
     --shape S scene.json --report``, A/B alternated as below; the two sides' reports compared
     field by field: how many max_gap values moved and by how much, and any other field that
     differs)
A/B: .venv/bin/python benchmarks/bench_scale.py --baseline ../main/.venv/bin/meshcol --repeat 3
     [--sizes 10000 100000] [--extras] [--primitives 10000] [--stages]   (runs alternated, each
     side first every other round; wall, CPU and peak RSS ranges; the two sides' last reports
     compared byte for byte, clock fields masked; --stages: each side's CPU seconds per stage,
     one run each, for the unique-asset sizes)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
CACHE = ROOT / ".cache" / "scale"
SPACING = 1.2  # grid pitch (m) of props about 0.8-1.6 m wide: about 2.5 box overlaps per body


# ---------------------------------------------------------------------------------------------
# Assets


def convex_prop(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random hull: 24-48 points on an ellipsoid of semi-axes 0.4-0.8 m, its triangles."""
    from scipy.spatial import ConvexHull

    p = rng.normal(size=(int(rng.integers(24, 49)), 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    p *= rng.uniform(0.4, 0.8, size=3)
    hull = ConvexHull(p)
    faces = hull.simplices.copy()
    # outward winding: the normal points away from the centroid
    centre = p.mean(axis=0)
    a, b, c = p[faces[:, 0]], p[faces[:, 1]], p[faces[:, 2]]
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), a - centre) < 0
    faces[inward] = faces[inward][:, ::-1]
    used, faces = np.unique(faces, return_inverse=True)
    return p[used], faces.reshape(-1, 3)


def concave_prop(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """An L-shaped bracket (a closed, non-convex prism) of random size, centred."""
    w, h = rng.uniform(0.8, 1.5), rng.uniform(0.8, 1.5)
    t = rng.uniform(0.15, 0.35) * min(w, h)
    depth = rng.uniform(0.3, 0.8)
    outline = np.array([[0, 0], [w, 0], [w, t], [t, t], [t, h], [0, h]], dtype=np.float64)
    outline -= outline.mean(axis=0)
    n = len(outline)
    vertices = np.concatenate(
        [np.c_[outline, np.full(n, -depth / 2)], np.c_[outline, np.full(n, depth / 2)]]
    )
    caps = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]  # the L as a fan from its corner 0
    faces = [(c, b, a) for a, b, c in caps] + [(a + n, b + n, c + n) for a, b, c in caps]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    return vertices, np.array(faces, dtype=np.int64)


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def scene_folder(n: int) -> Path:
    """``benchmarks/.cache/scale/<n>`` with ``scene.json`` and ``assets/``; written once."""
    folder = CACHE / str(n)
    manifest = folder / "scene.json"
    if manifest.exists():
        return folder
    rng = np.random.default_rng(n)
    (folder / "assets").mkdir(parents=True, exist_ok=True)
    side = math.ceil(math.sqrt(n))
    bodies = []
    for i in range(n):
        vertices, faces = concave_prop(rng) if i % 3 == 2 else convex_prop(rng)
        name = f"a{i:06d}.obj"
        write_obj(folder / "assets" / name, vertices, faces)
        gx, gy = divmod(i, side)
        x, y = gx * SPACING + rng.normal(0, 0.1), gy * SPACING + rng.normal(0, 0.1)
        bodies.append(
            {
                "name": f"prop{i:06d}",
                "mesh": f"assets/{name}",
                "position": [round(x, 6), round(y, 6), 0.8],
                "rotation": {
                    "euler_deg": [0.0, 0.0, round(rng.uniform(0, 360), 3)],
                    "order": "xyz",
                },
            }
        )
    tmp = manifest.with_suffix(".tmp")
    tmp.write_text(json.dumps({"units": "m", "bodies": bodies}))
    tmp.rename(manifest)
    return folder


def big_mesh_folder() -> Path:
    """A closed torus of 2,000,000 triangles (binary STL) beside a unit cube."""
    folder = CACHE / "mesh2m"
    manifest = folder / "scene.json"
    if manifest.exists():
        return folder
    import trimesh

    folder.mkdir(parents=True, exist_ok=True)
    u_count, v_count = 2000, 500  # 2 * u * v triangles
    u = np.linspace(0, 2 * np.pi, u_count, endpoint=False)
    v = np.linspace(0, 2 * np.pi, v_count, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    big, small = 1.0, 0.3
    vertices = np.stack(
        [
            (big + small * np.cos(vv)) * np.cos(uu),
            (big + small * np.cos(vv)) * np.sin(uu),
            small * np.sin(vv),
        ],
        -1,
    ).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(u_count), np.arange(v_count), indexing="ij")
    a = i * v_count + j
    b = ((i + 1) % u_count) * v_count + j
    c = ((i + 1) % u_count) * v_count + (j + 1) % v_count
    d = i * v_count + (j + 1) % v_count
    faces = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)
    trimesh.Trimesh(vertices, faces, process=False).export(folder / "torus.stl")
    trimesh.creation.box(extents=(0.5, 0.5, 0.5)).export(folder / "cube.stl")
    bodies = [
        {"name": "torus", "mesh": "torus.stl"},
        {"name": "cube", "mesh": "cube.stl", "position": [1.6, 0.0, 0.0]},
    ]
    manifest.write_text(json.dumps({"units": "m", "bodies": bodies}))
    return folder


def instances_folder(n: int = 300_000) -> Path:
    """A manifest of ``n`` bodies instancing 16 asset files (the loader's per-body cost)."""
    folder = CACHE / f"instances{n}"
    manifest = folder / "scene.json"
    if manifest.exists():
        return folder
    rng = np.random.default_rng(3)
    (folder / "assets").mkdir(parents=True, exist_ok=True)
    for k in range(16):
        write_obj(folder / "assets" / f"p{k:02d}.obj", *convex_prop(rng))
    side = math.ceil(math.sqrt(n))
    bodies = [
        {
            "name": f"b{i:06d}",
            "mesh": f"assets/p{i % 16:02d}.obj",
            "position": [(i // side) * 2.0, (i % side) * 2.0, 0.8],
            "rotation": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
        }
        for i in range(n)
    ]
    manifest.write_text(json.dumps({"units": "m", "bodies": bodies}))
    return folder


def primitives_folder(n: int, kind: str) -> Path:
    """A manifest of ``n`` primitive bodies (``kind``: spheres, mixed, ellipsoids (mixed with
    ellipsoids), or pile: spheres all overlapping), no mesh file."""
    folder = CACHE / f"primitives-{kind}{n}"
    manifest = folder / "scene.json"
    if manifest.exists():
        return folder
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(5)
    side = math.ceil(n ** (1 / 3))
    index = np.arange(n)
    grid = np.stack([index % side, index // side % side, index // side // side], axis=1)
    position = (0.8 * grid + rng.uniform(-0.05, 0.05, (n, 3))).round(6).tolist()
    if kind == "pile":  # every body within 0.1 m of the origin: every pair a candidate
        position = rng.uniform(-0.05, 0.05, (n, 3)).round(6).tolist()
    size = rng.uniform(0.2, 0.45, n).round(6).tolist()
    quaternion = rng.normal(size=(n, 4)).round(6).tolist()
    bodies = []
    for i in range(n):
        r = size[i]
        k = 0 if kind == "spheres" else i % 5 if kind == "ellipsoids" else i % 4
        body: dict = {
            "name": f"p{i:07d}",
            "primitive": [
                {"type": "sphere", "radius": r},
                {"type": "box", "size": [2 * r, 0.4, 0.5]},
                {"type": "capsule", "radius": r / 2, "length": 0.4},
                {"type": "cylinder", "radius": r / 2, "length": 0.5},
                {"type": "ellipsoid", "semi_axes": [r, 0.2, 0.25]},
            ][k],
            "position": position[i],
        }
        if kind in ("mixed", "ellipsoids") and i % 3 == 0:
            body["rotation"] = {"quaternion": quaternion[i]}
        bodies.append(body)
    manifest.write_text(json.dumps({"units": "m", "bodies": bodies}))
    return folder


# ---------------------------------------------------------------------------------------------
# Runs

_WRAPPER = (
    "import resource, subprocess, sys, time\n"
    "t = time.perf_counter()\n"
    "rc = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL).returncode\n"
    "t = time.perf_counter() - t\n"
    "u = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
    "print(rc, t, u.ru_maxrss, u.ru_utime + u.ru_stime, u.ru_utime)\n"
)

#: Figures of the last :func:`timed` call: CPU seconds (user + system, every thread), and the
#: user part alone (the system part, page faults and file opens, swings most with the load).
LAST_CPU = [0.0, 0.0]


def timed(command: list[str]) -> tuple[int, float, float]:
    """Exit code, wall seconds and peak RSS (MiB) of ``command`` in a fresh process (its CPU
    seconds in ``LAST_CPU[0]``: on a shared machine, steadier than the wall time)."""
    out = subprocess.run(
        [sys.executable, "-c", _WRAPPER, *command], capture_output=True, text=True, check=True
    ).stdout.split()
    LAST_CPU[0], LAST_CPU[1] = float(out[3]), float(out[4])
    return int(out[0]), float(out[1]), float(out[2]) / 1024


def stages(report: dict, wall: float) -> str:
    """The run's stages from its report: load (read, validate, build the bodies), check
    (colliders, broad, narrow and mesh phases, the report's rows) and the rest of the wall
    time (start-up, imports, writing the report)."""
    summary = report.get("summary", {})
    load, check = summary.get("load_seconds"), summary.get("seconds")
    if load is None or check is None:
        return "stages: -"
    return f"stages: load {load:.2f} s, check {check:.2f} s, rest {wall - load - check:.2f} s"


def meshcol_check(
    folder: Path, threads: int, meshcol: str | None = None, report_name: str = "report.json"
) -> tuple[int, float, float, dict]:
    """``meshcol check`` of the folder's manifest (``meshcol``: the executable, this
    environment's by default), its report written to ``folder / report_name``."""
    meshcol = meshcol or str(Path(sys.executable).parent / "meshcol")
    report = folder / report_name
    rc, seconds, rss = timed(
        [
            meshcol,
            "check",
            str(folder / "scene.json"),
            "--threads",
            str(threads),
            "--report",
            str(report),
            "--fail-on",
            "none",
        ]
    )
    data = json.loads(report.read_text()) if report.exists() else {}
    return rc, seconds, rss, data


def meshcol_fit(
    folder: Path, shape: str, threads: int, meshcol: str, report_name: str
) -> tuple[int, float, float, dict]:
    """``meshcol fit --shape shape`` of the folder's manifest, its report written to
    ``folder / report_name`` (the first run of each side is untimed: :func:`ab`)."""
    report = folder / report_name
    command = [meshcol, "fit", "--shape", shape, str(folder / "scene.json")]
    rc, seconds, rss = timed([*command, "--report", str(report)])  # fit has no --threads
    return rc, seconds, rss, json.loads(report.read_text()) if report.exists() else {}


def fit_reports_change(folder: Path, sides: list[str]) -> str:
    """How the sides' last fit reports differ: rows whose max_gap moved, the largest move,
    and the other body fields that differ (none expected)."""
    this, base = (json.loads((folder / f"report-{s}.json").read_text())["bodies"] for s in sides)
    moved = [
        abs(a["max_gap"] - b["max_gap"]) for a, b in zip(this, base) if a["max_gap"] != b["max_gap"]
    ]
    others = sum(1 for a, b in zip(this, base) for k in a if k != "max_gap" and a[k] != b.get(k))
    largest = f", largest move {max(moved):.3g}" if moved else ""
    return f"max_gap moved in {len(moved)} of {len(this)} rows{largest}; other fields differing: {others}"


def warm_up(folder: Path, threads: int, meshcol: str | None = None) -> None:
    """One untimed ``meshcol check`` of the folder's manifest: the timed runs then find the
    package's bytecode compiled and the files in the page cache. The first run after a build
    or a merge compiles every module the check imports (an editable install has no compiled
    bytecode; about 0.6 s of CPU on one core), which made one timed run in two or three of a
    fresh main about 2 s slower (RESULTS.md, issue 32 item 5, session 22)."""
    rc, _, _, _ = meshcol_check(folder, threads, meshcol, "report-warm-up.json")
    if rc not in (0, 1):
        raise SystemExit(f"{meshcol or 'meshcol'} check exited {rc} on {folder} (warm-up)")
    (folder / "report-warm-up.json").unlink(missing_ok=True)


def bytecode_note() -> str:
    """A line for the header when Python may not write bytecode: each run of a package without
    compiled bytecode then compiles its modules again, and every run pays it."""
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return (
            "note: PYTHONDONTWRITEBYTECODE is set: runs compile modules that have no bytecode "
            "yet, every time (prefix env -u PYTHONDONTWRITEBYTECODE)"
        )
    return ""


#: Stages of a unique-asset check beyond ``check_stages.STAGES``: the whole output guard and
#: its mesh paths; the whole load; inside the file read, the formats and the native read (and
#: the Python around it); inside the bodies in bulk, the files' objects and their arrays read
#: in bulk; inside the colliders, the colliders built as arrays, their repeats found
#: (``_first_equal``) and the hulls (one batched call), or the per-body path's hull call and
#: geometry keys when a scene needs it.
UNIQUE_STAGES = [
    ("meshcol.io.outputs", "check_outputs"),
    ("meshcol.io.scene", "manifest_mesh_files"),
    ("meshcol.io.mesh_read", "_formats_of"),
    ("meshcol.io.mesh_read", "_read_native"),
    ("meshcol.io.scene_columns", "lone_objects"),
    ("meshcol.io.scene_columns", "_plain_objects"),
    ("meshcol.analysis.check", "_load"),
    ("meshcol.analysis.colliders", "bulk_colliders"),
    ("meshcol.analysis.bulk_colliders", "_first_equal"),
    ("meshcol.collision.shapes", "pack_hull_slices"),
    ("meshcol.collision.shapes", "pack_hulls"),
    ("meshcol.analysis.geometry_cache", "geometry_key"),
    ("meshcol.analysis.colliders", "_geometry_key"),  # where builds before session 37 keep it
]

_STAGE_RUN = (
    "import importlib, sys; sys.path.insert(0, {bench!r}); import check_stages as c; "
    "c.STAGES += [(m, f) for m, f in {extra!r} if hasattr(importlib.import_module(m), f)]; "
    "sys.argv = ['check_stages.py', *sys.argv[1:]]; c.main()"
)  # a stage the build (a --baseline) does not have is left out


def stage_times(folder: Path, threads: int, python: str = sys.executable) -> list[str]:
    """CPU seconds of each stage of one ``meshcol check`` of the folder's manifest
    (``check_stages.py`` with :data:`UNIQUE_STAGES` added), as its printed lines."""
    code = _STAGE_RUN.format(bench=str(ROOT), extra=UNIQUE_STAGES)
    command = [python, "-c", code, str(folder / "scene.json"), "--threads", str(threads)]
    command += ["--report", str(folder / "report-stages.json"), "--fail-on", "none"]
    out = subprocess.run(command, capture_output=True, text=True, check=False).stdout
    lines = out.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("stage CPU")), None)
    return lines[start:] if start is not None else [f"stages failed: {out[-300:]}"]


_READ_ONLY = (
    "import json, os, resource, sys\n"
    "from meshcol._native import core\n"
    "folder = sys.argv[1]\n"
    "bodies = json.load(open(os.path.join(folder, 'scene.json')))['bodies']\n"
    "paths = [os.path.join(folder, b['mesh']) for b in bodies]\n"
    "a = resource.getrusage(resource.RUSAGE_SELF)\n"
    "core.read_mesh_files(paths, [0] * len(paths), merge=True, threads=1)\n"
    "b = resource.getrusage(resource.RUSAGE_SELF)\n"
    "print(b.ru_utime - a.ru_utime, b.ru_stime - a.ru_stime)\n"
)


def reader_rows(args: argparse.Namespace) -> None:
    """CPU seconds of the core's ``read_mesh_files`` over each unique-asset scene's files (one
    thread, a fresh process a run; with ``--baseline``, its Python alternated with this)."""
    sides = {"this": sys.executable}
    if args.baseline:
        sides["baseline"] = str(Path(args.baseline).parent / "python")
    for n in args.sizes:
        folder = scene_folder(n)
        runs: dict[str, list[tuple[float, float]]] = {side: [] for side in sides}
        for round_ in range(args.repeat):
            # each side first every other round: the first run of a round may find the files
            # out of the page cache (a loaded machine evicts them) and pay for the disk
            order = list(sides.items())
            for side, python in order[::-1] if round_ % 2 else order:
                out = subprocess.run(
                    [python, "-c", _READ_ONLY, str(folder)],
                    capture_output=True,
                    text=True,
                    check=True,
                    cwd=ROOT.parent.parent,  # not a worktree: each side imports its own meshcol
                )
                user, system = out.stdout.split()[-2:]
                runs[side].append((float(user), float(system)))
        for side, figures in runs.items():
            user_s, system_s = zip(*figures)
            print(
                f"read {n:,} files, {side}: user {min(user_s):.2f}-{max(user_s):.2f} s, "
                f"system {min(system_s):.2f}-{max(system_s):.2f} s "
                f"({len(figures)} runs; load avg {os.getloadavg()[0]:.2f})"
            )


def loaded_meshes(folder: Path):
    """Every body of the manifest as (name, trimesh, 4x4 pose), loaded as a user would."""
    import trimesh
    from scipy.spatial.transform import Rotation

    manifest = json.loads((folder / "scene.json").read_text())
    out = []
    for body in manifest["bodies"]:
        mesh = trimesh.load(folder / body["mesh"], force="mesh")
        pose = np.eye(4)
        pose[:3, 3] = body.get("position", [0, 0, 0])
        rot = body.get("rotation")
        if rot and "euler_deg" in rot:
            pose[:3, :3] = Rotation.from_euler(
                rot["order"], rot["euler_deg"], degrees=True
            ).as_matrix()
        out.append((body["name"], mesh, pose))
    return out


def candidate_pairs(bodies) -> np.ndarray:
    """Index pairs whose world boxes overlap (given to the peers for free: numpy, not timed
    apart; trimesh's manager cannot list them)."""
    from meshcol import sort_and_sweep

    lo = np.array([(m.vertices @ p[:3, :3].T + p[:3, 3]).min(0) for _, m, p in bodies])
    hi = np.array([(m.vertices @ p[:3, :3].T + p[:3, 3]).max(0) for _, m, p in bodies])
    return sort_and_sweep(lo, hi)


def run_trimesh(folder: Path) -> tuple[float, int]:
    import fcl
    from trimesh.collision import CollisionManager

    start = time.perf_counter()
    bodies = loaded_meshes(folder)
    manager = CollisionManager()
    for name, mesh, pose in bodies:
        manager.add_object(name, mesh, transform=pose)
    _, names = manager.in_collision_internal(return_names=True)
    objs = [manager._objs[name]["obj"] for name, _, _ in bodies]
    request = fcl.DistanceRequest()
    for i, j in candidate_pairs(bodies):
        fcl.distance(objs[i], objs[j], request, fcl.DistanceResult())
    return time.perf_counter() - start, len(names)


def coal_pass(models_and_poses, candidates: np.ndarray) -> int:
    """coal as trimesh is used: every object in a DynamicAABBTreeArrayCollisionManager, one
    ``collide`` over the manager (all contacts, not the first), then ``coal.distance`` per
    candidate pair (handed over for free: coal's pair-collecting callback cannot give its pairs
    to Python, nor can Python subclass the callback). Returns the contacts found."""
    import coal

    manager = coal.DynamicAABBTreeArrayCollisionManager()
    objects = []
    for model, pose in models_and_poses:
        obj = coal.CollisionObject(model, coal.Transform3s(pose[:3, :3], pose[:3, 3]))
        objects.append(obj)
        manager.registerObject(obj)
    manager.setup()
    callback = coal.CollisionCallBackDefault()
    callback.data.request.num_max_contacts = 1 << 30
    manager.collide(callback)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for i, j in candidates:
        result.clear()
        coal.distance(objects[i], objects[j], request, result)
    return int(callback.data.result.numContacts())


def coal_model(vertices: np.ndarray, faces: np.ndarray):
    import coal

    model = coal.BVHModelOBBRSS()
    model.beginModel(len(faces), len(vertices))
    model.addVertices(np.asarray(vertices, dtype=np.float64))
    model.addTriangles(np.asarray(faces, dtype=np.int64))
    model.endModel()
    return model


def run_coal(folder: Path) -> tuple[float, int]:
    start = time.perf_counter()
    bodies = loaded_meshes(folder)
    items = [(coal_model(m.vertices, m.faces), pose) for _, m, pose in bodies]
    hits = coal_pass(items, candidate_pairs(bodies))
    return time.perf_counter() - start, hits


def peer(name: str, fn, folder: Path, n: int, peer_max: int) -> str:
    if n > peer_max:
        return f"skipped (N > --peer-max {peer_max})"
    try:
        seconds, hits = fn(folder)
    except ImportError as error:
        return f"skipped ({error.name or error} not installed)"
    return f"{seconds:.2f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[1000, 10000, 100000])
    parser.add_argument("--peer-max", type=int, default=10000, help="largest N given to peers")
    parser.add_argument("--threads", type=int, default=0, help="meshcol --threads")
    parser.add_argument("--repeat", type=int, default=1, help="meshcol runs per size (best)")
    parser.add_argument(
        "--extras",
        action="store_true",
        help="the 2M-triangle mesh and the 300,000-body manifest too",
    )
    parser.add_argument(
        "--primitives",
        type=int,
        nargs="*",
        default=[],
        help="sizes of the primitive-body manifests to check (e.g. 100000 1000000)",
    )
    parser.add_argument(
        "--reader",
        action="store_true",
        help="only the core's read of each unique-asset scene's files (see the docstring)",
    )
    parser.add_argument(
        "--stages",
        action="store_true",
        help="each unique-asset size also run under check_stages.py: CPU and wall seconds per stage",
    )
    parser.add_argument(
        "--primitive-kinds",
        nargs="+",
        default=["spheres", "mixed"],
        choices=["spheres", "mixed", "ellipsoids", "pile"],
        help="pile: N spheres within 0.1 m of the origin, N(N-1)/2 candidate pairs",
    )
    parser.add_argument(
        "--baseline",
        metavar="MESHCOL",
        help="another meshcol executable (e.g. main's .venv/bin/meshcol): its runs alternate "
        "with this one's, --repeat times each, and only meshcol is timed (A/B)",
    )
    parser.add_argument(
        "--fit",
        nargs="+",
        default=[],
        choices=["sphere", "capsule", "box", "cylinder", "ellipsoid", "auto"],
        help="with --baseline: meshcol fit --shape S of each unique-asset size, not check",
    )
    args = parser.parse_args()
    if args.reader:
        reader_rows(args)
        return
    if args.baseline:
        ab(args)
        return
    print(
        f"cores: {os.cpu_count()}; meshcol --threads {args.threads}; cache {CACHE}; "
        f"load average {os.getloadavg()[0]:.2f} (each row: after it; one untimed run first)"
    )
    if bytecode_note():
        print(bytecode_note())
    print(
        f"{'N':>7} {'pairs':>7} {'meshcol s':>10} {'peak MiB':>9} {'trimesh+fcl':>24} "
        f"{'ratio':>6} {'coal':>24} {'ratio':>6} {'load avg':>9}"
    )
    for n in args.sizes:
        t0 = time.perf_counter()
        folder = scene_folder(n)
        made = time.perf_counter() - t0
        if made > 1:
            print(f"  (generated {n} assets in {made:.1f} s)")
        warm_up(folder, args.threads)
        runs = [meshcol_check(folder, args.threads) for _ in range(args.repeat)]
        rc, seconds, rss, report = min(runs, key=lambda r: r[1])
        pairs = len(report.get("pairs", [])) if rc in (0, 1) else f"rc={rc}"
        t_fcl = peer("trimesh", run_trimesh, folder, n, args.peer_max)
        t_coal = peer("coal", run_coal, folder, n, args.peer_max)

        def ratio(text: str) -> str:
            return f"{float(text.split()[0]) / seconds:5.1f}x" if text.endswith(" s") else "-"

        print(
            f"{n:>7} {pairs!s:>7} {seconds:>10.2f} {rss:>9.0f} {t_fcl:>24} {ratio(t_fcl):>6} "
            f"{t_coal:>24} {ratio(t_coal):>6} {os.getloadavg()[0]:>9.2f}"
        )
        print(f"{'':>7} {stages(report, seconds)}")
        if args.stages:
            for line in stage_times(folder, args.threads):
                print(f"{'':>7} {line}")
    for n in args.primitives:
        for kind in args.primitive_kinds:
            folder = primitives_folder(n, kind)
            warm_up(folder, args.threads)
            runs = []
            for _ in range(args.repeat):
                rc, seconds, rss, report = meshcol_check(folder, args.threads)
                runs.append((seconds, LAST_CPU[0], rss))
            wall, cpu, rss_runs = zip(*runs)
            pairs = len(report.get("pairs", [])) if rc == 0 else f"rc={rc}"
            print(
                f"{n:,} {kind} primitives: meshcol check {min(wall):.2f}-{max(wall):.2f} s wall, "
                f"{min(cpu):.2f}-{max(cpu):.2f} s CPU, peak {max(rss_runs):.0f} MiB, "
                f"{pairs} pairs reported (load avg {os.getloadavg()[0]:.2f}); last run's "
                f"{stages(report, wall[-1])}"
            )
    if args.extras:
        folder = big_mesh_folder()
        rc, seconds, rss, _ = meshcol_check(folder, args.threads)
        print(
            f"2,000,000-triangle torus beside a cube: meshcol check {seconds:.2f} s, "
            f"peak {rss:.0f} MiB (rc {rc})"
        )
        folder = instances_folder()
        code = (
            f"import meshcol; s = meshcol.load_inputs([{str(folder / 'scene.json')!r}]); "
            "print(len(s.bodies))"
        )
        rc, seconds, rss = timed([sys.executable, "-c", code])
        print(
            f"300,000-body manifest: load_inputs {seconds:.2f} s in a fresh process "
            f"(imports included), peak {rss:.0f} MiB (rc {rc})"
        )


#: Report fields that differ between any two runs (clocks), masked before comparing.
_CLOCK_FIELDS = (b'"generated_at": ', b'"seconds": ', b'"load_seconds": ')


def same_reports(folder: Path, sides: list[str]) -> str:
    """Whether the last report of each side is the same bytes, clock fields masked."""

    def masked(side: str) -> list[bytes]:
        lines = (folder / f"report-{side}.json").read_bytes().split(b"\n")
        return [
            line.split(b": ")[0] if line.lstrip().startswith(_CLOCK_FIELDS) else line
            for line in lines
        ]

    first, *others = (masked(side) for side in sides)
    if all(other == first for other in others):
        return f"identical bytes ({len(first):,} lines; clock fields masked)"
    return "DIFFER"


def ab(args: argparse.Namespace) -> None:
    """This meshcol against ``--baseline``, runs alternated: wall, CPU and peak RSS ranges;
    with ``--extras``, ``load_inputs`` of the 300,000-body manifest by each one's Python."""
    mine = str(Path(sys.executable).parent / "meshcol")
    sides = {"this": mine, "baseline": args.baseline}
    print(f"cores: {os.cpu_count()}; A/B, {args.repeat} alternated runs each; {os.getloadavg()}")
    print(f"(one untimed run of each side first, for each case) {bytecode_note()}".rstrip())
    print(f"{'case':>24} {'side':>9} {'wall s':>13} {'CPU s':>13} {'user s':>13} {'peak MiB':>11}")

    def show(case: str, figures: dict[str, list[tuple[float, ...]]]) -> None:
        for side, runs in figures.items():
            wall, cpu, rss, user = zip(*runs)
            print(
                f"{case:>24} {side:>9} {min(wall):6.2f}-{max(wall):<6.2f} "
                f"{min(cpu):6.2f}-{max(cpu):<6.2f} {min(user):6.2f}-{max(user):<6.2f} "
                f"{min(rss):5.0f}-{max(rss):<5.0f}"
            )

    cases = [(f"check, {n} unique", scene_folder(n)) for n in args.sizes] + [
        (f"{n} {kind} primitives", primitives_folder(n, kind))
        for n in args.primitives
        for kind in args.primitive_kinds
    ]
    if args.fit:
        cases = [(f"fit {s}, {n} unique", scene_folder(n)) for n in args.sizes for s in args.fit]
    for case, folder in cases:
        figures: dict[str, list[tuple[float, ...]]] = {side: [] for side in sides}
        shape = case.split(",")[0].split()[1] if case.startswith("fit ") else None
        for side, meshcol in sides.items():
            if shape is None:
                warm_up(folder, args.threads, meshcol)
            else:
                meshcol_fit(folder, shape, args.threads, meshcol, f"report-{side}.json")
        for round_ in range(args.repeat):
            # each side first every other round (the first run of a round may find the files
            # out of the page cache)
            order = list(sides.items())
            for side, meshcol in order[::-1] if round_ % 2 else order:
                name = f"report-{side}.json"
                if shape is None:
                    rc, seconds, rss, _ = meshcol_check(folder, args.threads, meshcol, name)
                else:
                    rc, seconds, rss, _ = meshcol_fit(folder, shape, args.threads, meshcol, name)
                if rc != 0:  # --fail-on none: anything else is a crash (a traceback is 1)
                    raise SystemExit(f"{side} meshcol {case} exited {rc} on {folder}")
                figures[side].append((seconds, LAST_CPU[0], rss, LAST_CPU[1]))
        show(case, figures)
        if shape is None:
            print(f"{'':>24} reports: {same_reports(folder, list(sides))}")
        else:
            print(f"{'':>24} reports: {fit_reports_change(folder, list(sides))}")
        if args.stages and "unique" in case:  # CPU seconds per stage, one run a side
            for side, meshcol in sides.items():
                print(f"{'':>24} {side} stages:")
                for line in stage_times(folder, args.threads, str(Path(meshcol).parent / "python")):
                    print(f"{'':>26} {line}")
    if args.extras:
        manifest = str(instances_folder() / "scene.json")
        code = f"import meshcol; s = meshcol.load_inputs([{manifest!r}]); print(len(s.bodies))"
        figures = {side: [] for side in sides}
        for _ in range(args.repeat):
            for side, meshcol in sides.items():
                python = str(Path(meshcol).parent / "python")
                rc, seconds, rss = timed([python, "-c", code])
                if rc != 0:
                    raise SystemExit(f"{side} load_inputs exited {rc}")
                figures[side].append((seconds, LAST_CPU[0], rss, LAST_CPU[1]))
        show("load 300,000 bodies", figures)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
