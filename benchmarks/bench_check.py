"""Benchmark: `meshcol.check_scene` vs trimesh's CollisionManager on level-like scenes.

Both do the same job on the same convex hulls: find every pair of bodies whose boxes meet,
decide whether they collide, and give each such candidate pair a distance. trimesh (through
python-fcl) is used as a user would: a CollisionManager for the collisions, then one
`fcl.distance` call per candidate pair, on the manager's own objects. The candidate pairs are
handed to the peer for free (taken from meshcol's broad phase), which favours the peer.

Times exclude loading; the last column is loading the same scene from a manifest of OBJ
instances (`meshcol.load_inputs`), measured apart.

Run:  .venv/bin/python benchmarks/bench_check.py [--sizes 100 1000 10000] [--clearance 0.25]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def level_scene(n: int, seed: int = 0):
    """n props on a plane: instances of a few convex meshes, spaced so each has a few near
    neighbours and about 2% interpenetrate."""
    import trimesh

    from meshcol.types import Body, Scene

    rng = np.random.default_rng(seed)
    protos = [
        trimesh.creation.box(extents=(1.0, 1.0, 1.0)),
        trimesh.creation.box(extents=(2.0, 0.6, 0.8)),
        trimesh.creation.cylinder(radius=0.5, height=1.2, sections=32),
        trimesh.creation.icosphere(subdivisions=2, radius=0.6),
        trimesh.creation.capsule(height=1.0, radius=0.3, count=[16, 8]),
    ]
    protos = [(np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)) for m in protos]
    side = int(np.ceil(np.sqrt(n)))
    spacing = 2.0
    bodies = []
    for i in range(n):
        gx, gy = divmod(i, side)
        v, f = protos[i % len(protos)]
        angle = rng.uniform(0, 2 * np.pi)
        c, s = np.cos(angle), np.sin(angle)
        t = np.eye(4)
        t[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        jitter = rng.normal(0, 0.12, 2)
        t[:3, 3] = [gx * spacing + jitter[0], gy * spacing + jitter[1], 0.6]
        bodies.append(Body(f"prop_{i:05d}", None, v, f, t))
    return Scene(tuple(bodies), units="m")


def load_seconds(scene) -> float:
    """Loading, reported apart: the same scene written as a manifest of OBJ instances, then
    read back with `meshcol.load_inputs`."""
    import json
    import tempfile
    from pathlib import Path

    import trimesh

    from meshcol.io.scene import load_inputs

    with tempfile.TemporaryDirectory() as tmp:
        files: dict[int, str] = {}
        bodies = []
        for body in scene.bodies:
            key = body.vertices.ctypes.data
            if key not in files:
                files[key] = f"proto_{len(files)}.obj"
                trimesh.Trimesh(body.vertices, body.faces, process=False).export(
                    Path(tmp) / files[key]
                )
            r = body.pose[:3, :3]
            w = np.sqrt(max(0.0, 1.0 + np.trace(r))) / 2  # rotations here are about z only
            z = (r[1, 0] - r[0, 1]) / (4 * w)
            bodies.append(
                {
                    "name": body.name,
                    "mesh": files[key],
                    "position": body.pose[:3, 3].tolist(),
                    "rotation": {"quaternion": [w, 0.0, 0.0, z]},
                }
            )
        manifest = Path(tmp) / "scene.json"
        manifest.write_text(json.dumps({"units": "m", "bodies": bodies}))
        start = time.perf_counter()
        load_inputs([manifest])
        return time.perf_counter() - start


def run_meshcol(scene, threads: int, clearance: float = 0.0):
    from meshcol.analysis.check import CheckOptions, check_scene

    start = time.perf_counter()
    report = check_scene(scene, CheckOptions(collider="hull", threads=threads, clearance=clearance))
    return time.perf_counter() - start, report


def run_trimesh(scene, report):
    import fcl
    import trimesh
    from trimesh.collision import CollisionManager

    start = time.perf_counter()
    manager = CollisionManager()
    hulls = {}
    for body in scene.bodies:
        key = body.vertices.ctypes.data
        if key not in hulls:  # instances share a hull, as in meshcol
            hulls[key] = trimesh.Trimesh(body.vertices, body.faces).convex_hull
        manager.add_object(body.name, hulls[key], transform=body.pose)
    _, names = manager.in_collision_internal(return_names=True)
    objs = {name: manager._objs[name]["obj"] for name in manager._objs}
    request = fcl.DistanceRequest()
    distances = []
    for p in report.pairs:
        distances.append(
            fcl.distance(objs[p["body_a"]], objs[p["body_b"]], request, fcl.DistanceResult())
        )
    seconds = time.perf_counter() - start
    return seconds, names, np.asarray(distances)


def run_coal(scene, report):
    """coal, the same job on the same hulls: a DynamicAABBTreeArrayCollisionManager collide,
    then ``coal.distance`` per candidate pair, handed over for free (bench_scale.coal_pass)."""
    import trimesh
    from bench_scale import coal_model, coal_pass

    start = time.perf_counter()
    models = {}
    items = []
    for body in scene.bodies:
        key = body.vertices.ctypes.data
        if key not in models:  # instances share a hull, as in meshcol
            hull = trimesh.Trimesh(body.vertices, body.faces).convex_hull
            models[key] = coal_model(hull.vertices, hull.faces)
        items.append((models[key], body.pose))
    index = {body.name: i for i, body in enumerate(scene.bodies)}
    candidates = [(index[p["a"]], index[p["b"]]) for p in report.pairs]
    hits = coal_pass(items, candidates)
    return time.perf_counter() - start, hits


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument(
        "--peer-max", type=int, default=10000, help="largest scene given to the peer"
    )
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--clearance",
        type=float,
        default=0.25,
        help="clearance band: pairs closer than this are candidates too",
    )
    args = parser.parse_args()

    from meshcol._native import core as _core

    try:
        import coal  # noqa: F401

        has_coal = True
    except ImportError:
        has_coal = False
        print("coal: skipped (not installed; pip install coal)")

    print(
        f"meshcol check vs trimesh CollisionManager (+ fcl.distance per candidate pair); "
        f"{_core.hardware_threads()} hardware threads; clearance {args.clearance}"
    )
    print(
        f"{'bodies':>7} {'pairs':>7} {'hits':>5} {'meshcol 1T s':>13} {'meshcol all s':>14} "
        f"{'trimesh s':>10} {'ratio':>7} {'hits agree':>10} {'coal s':>7} {'ratio':>6} "
        f"{'coal contacts':>13} {'load s':>7}"
    )
    for n in args.sizes:
        scene = level_scene(n)
        run_meshcol(scene, 1, args.clearance)  # warm up: imports, first native call
        t1 = min(run_meshcol(scene, 1, args.clearance)[0] for _ in range(args.repeat))
        tall, report = min(
            (run_meshcol(scene, 0, args.clearance) for _ in range(args.repeat)), key=lambda r: r[0]
        )
        hits = {
            (p["body_a"], p["body_b"])
            for p in report.pairs
            if p["status"] in ("penetrating", "contained", "contact")
        }
        if n <= args.peer_max:
            tp, names, _ = run_trimesh(scene, report)
            peer_hits = {tuple(sorted(pair)) for pair in names}
            agree = "yes" if peer_hits == hits else f"no ({len(peer_hits ^ hits)} differ)"
            ratio = f"{tp / t1:6.1f}x"
            tps = f"{tp:10.3f}"
        else:
            ratio, tps, agree = "   n/a", "       n/a", "n/a"
        tc, coal_ratio, coal_hits = "n/a", "n/a", "n/a"
        if has_coal and n <= args.peer_max:
            seconds, count = run_coal(scene, report)
            tc, coal_ratio, coal_hits = f"{seconds:.3f}", f"{seconds / t1:.1f}x", str(count)
        print(
            f"{n:>7} {len(report.pairs):>7} {len(hits):>5} {t1:>13.4f} {tall:>14.4f} {tps} {ratio:>7} "
            f"{agree:>10} {tc:>7} {coal_ratio:>6} {coal_hits:>13} {load_seconds(scene):>7.2f}"
        )


if __name__ == "__main__":
    main()
