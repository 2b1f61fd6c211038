"""A few pairs queried on a big set: what a batch costs when it names few of the set's shapes.

A simulation step, an editor's drag or an incremental check asks about a handful of pairs of a
scene that holds many bodies. The batch should cost what those pairs need: this script times
``distance_batch`` (with and without poses) and ``time_of_impact_batch`` for P pairs on a
``ConvexSet`` of H primitives (spheres, boxes, capsules, cylinders; random turned poses in a
cube whose side grows with H so that a body has a few neighbours), for H up to a million, and
coal's ``distance`` on the same P pairs in a Python loop (geometries and transforms made
before the clock starts) as the peer. Then ``mesh_distance_batch`` with poses on a ``MeshSet``
of H tetrahedra (up to ``--mesh-max``), against coal's distance between the same pairs of
``BVHModelOBBRSS`` tetrahedra. CPU time, best of ``--rounds``, microseconds a batch.

Run: .venv/bin/python benchmarks/bench_small_batches.py [--sizes 1000 100000 1000000]
     [--pairs 1 10 100] [--rounds 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from meshcol import ConvexSet, distance_batch, time_of_impact_batch
from meshcol.collision.mesh_query import MeshSet, mesh_distance_batch
from meshcol.collision.shapes import ShapeKind

TETRAHEDRON = (
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]),
)


def scene(h: int, seed: int = 7) -> tuple[ConvexSet, np.ndarray, np.ndarray, np.ndarray]:
    """H primitives, their start and end poses (H, 4, 4), and their kinds and params."""
    rng = np.random.default_rng(seed)
    kinds = (ShapeKind.SPHERE + np.arange(h) % 4).astype(np.int8)
    params = np.zeros((h, 4))
    params[:, :3] = rng.uniform(0.2, 0.5, (h, 3))
    side = 2.0 * np.cbrt(h)
    poses = []
    for _ in range(2):
        q = rng.normal(size=(h, 4))
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        w, x, y, z = q.T
        p = np.zeros((h, 4, 4))
        p[:, 0, :3] = np.c_[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)]
        p[:, 1, :3] = np.c_[2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)]
        p[:, 2, :3] = np.c_[2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]
        p[:, :3, 3] = rng.uniform(0.0, side, (h, 3))
        p[:, 3, 3] = 1.0
        poses.append(p)
    return ConvexSet.from_primitives(kinds, params), poses[0], poses[1], params


def coal_loop(kinds: np.ndarray, params: np.ndarray, poses: np.ndarray, pairs: np.ndarray):
    """Coal's distance on `pairs` in a Python loop, objects made beforehand (None: no coal)."""
    try:
        import coal
    except ImportError:
        return None
    used = np.unique(pairs)
    make = {
        int(ShapeKind.SPHERE): lambda p: coal.Sphere(p[0]),
        int(ShapeKind.BOX): lambda p: coal.Box(*(2.0 * p[:3])),
        int(ShapeKind.CAPSULE): lambda p: coal.Capsule(p[0], 2.0 * p[1]),
        int(ShapeKind.CYLINDER): lambda p: coal.Cylinder(p[0], 2.0 * p[1]),
    }
    objects = {
        int(i): (
            make[int(kinds[i])](params[i]),
            coal.Transform3s(
                np.ascontiguousarray(poses[i, :3, :3]), np.ascontiguousarray(poses[i, :3, 3])
            ),
        )
        for i in used
    }
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    rows = [(objects[int(a)], objects[int(b)]) for a, b in pairs]

    def run() -> None:
        for (ga, ta), (gb, tb) in rows:
            result.clear()
            coal.distance(ga, ta, gb, tb, request, result)

    return run


def coal_mesh_loop(poses: np.ndarray, pairs: np.ndarray):
    """Coal's distance between BVH tetrahedra on `pairs`, objects made beforehand."""
    try:
        import coal
    except ImportError:
        return None
    model = coal.BVHModelOBBRSS()
    model.beginModel(4, 4)
    model.addVertices(TETRAHEDRON[0])
    model.addTriangles(TETRAHEDRON[1])
    model.endModel()
    transforms = {
        int(i): coal.Transform3s(
            np.ascontiguousarray(poses[i, :3, :3]), np.ascontiguousarray(poses[i, :3, 3])
        )
        for i in np.unique(pairs)
    }
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    rows = [(transforms[int(a)], transforms[int(b)]) for a, b in pairs]

    def run() -> None:
        for ta, tb in rows:
            result.clear()
            coal.distance(model, ta, model, tb, request, result)

    return run


def best_cpu_us(fn, rounds: int) -> float:
    best = np.inf
    for _ in range(rounds):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 100000, 1000000])
    parser.add_argument("--pairs", type=int, nargs="+", default=[1, 10, 100])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--mesh-max", type=int, default=100000, help="largest mesh set")
    args = parser.parse_args()
    print("us a batch, CPU, best of", args.rounds, "(coal: the same pairs in a Python loop)")
    print(
        f"{'shapes':>9} {'pairs':>6} {'distance':>10} {'+ poses':>10} {'toi':>10} {'coal':>10} {'coal / +poses':>14}"
    )
    for h in args.sizes:
        shapes, start, end, params = scene(h)
        rng = np.random.default_rng(h)
        for p in args.pairs:
            pairs = rng.integers(0, h, (p, 2))
            plain = best_cpu_us(lambda: distance_batch(shapes, None, pairs, threads=1), args.rounds)
            posed = best_cpu_us(
                lambda: distance_batch(shapes, start, pairs, threads=1), args.rounds
            )
            toi = best_cpu_us(
                lambda: time_of_impact_batch(shapes, start, end, pairs, threads=1), args.rounds
            )
            run = coal_loop(shapes.kinds, params, start, pairs)
            peer = best_cpu_us(run, args.rounds) if run else float("nan")
            print(
                f"{h:>9} {p:>6} {plain:>10.1f} {posed:>10.1f} {toi:>10.1f} {peer:>10.1f} {peer / posed:>14.2f}"
            )
    print(
        "\nmesh_distance_batch with poses on H tetrahedra (coal: BVHModelOBBRSS in a Python loop)"
    )
    print(f"{'meshes':>9} {'pairs':>6} {'+ poses':>10} {'coal':>10} {'coal / meshcol':>15}")
    for h in (size for size in args.sizes if size <= args.mesh_max):
        meshes = MeshSet.from_arrays([TETRAHEDRON] * h)
        _, start, _, _ = scene(h)
        rng = np.random.default_rng(h)
        for p in args.pairs:
            pairs = rng.integers(0, h, (p, 2))
            posed = best_cpu_us(
                lambda: mesh_distance_batch(meshes, start, pairs, threads=1), args.rounds
            )
            run = coal_mesh_loop(start, pairs)
            peer = best_cpu_us(run, args.rounds) if run else float("nan")
            print(f"{h:>9} {p:>6} {posed:>10.1f} {peer:>10.1f} {peer / posed:>15.2f}")


if __name__ == "__main__":
    main()
