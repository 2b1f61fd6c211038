"""Ellipsoid pairs (issue 32 item 4): meshcol's exact ellipsoids against its capsules and
cylinders, against the 642-vertex tessellation the MJCF reader made of them before, and
against coal per call from Python.

Families of random pairs (semi-axes, radii, lengths 0.2-1.5, random turns), separated (centres
2.5-4 apart) and penetrating (0.2-0.8 apart): meshcol ``signed_distance_batch`` on one thread,
per pair; coal ``distance`` (separated) or ``collide`` with one contact (penetrating) per call
from Python, request and result reused, at its default tolerances; plus coal's per-call floor
(two spheres), the share of its figure that is the Python loop. CPU time, rounds alternating
the sides, best and range per row; ratios of the best times.

Run: .venv/bin/python benchmarks/bench_ellipsoid.py [--pairs 4000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_narrowphase import cpu_time, random_rotation
from bench_single_pair import geometry

from meshcol import Box, Capsule, ConvexSet, Cylinder, Ellipsoid, Sphere, signed_distance_batch
from meshcol.types import primitive_mesh


def make(kind: str, rng: np.random.Generator):
    u = rng.uniform(0.2, 1.5, 3)
    if kind == "ellipsoid":
        return Ellipsoid(tuple(u))
    if kind == "tessellated":  # what the MJCF reader made of an ellipsoid geom before
        return primitive_mesh(Ellipsoid(tuple(u)))[0]
    if kind == "capsule":
        return Capsule(u[0] / 2, u[1])
    if kind == "cylinder":
        return Cylinder(u[0] / 2, u[1])
    if kind == "sphere":
        return Sphere(u[0])
    return Box(tuple(u))


def coal_shape(coal, shape):
    """The shape as coal's geometry (bench_single_pair's for the primitives it knows)."""
    if isinstance(shape, Ellipsoid):
        return coal.Ellipsoid(*shape.semi_axes)
    if not isinstance(shape, np.ndarray):
        return geometry(coal, shape)
    points = coal.StdVec_Vec3s()
    for p in shape:
        points.append(np.array(p))
    return coal.Convex.convexHull(points, False, None)


def case(kind_a: str, kind_b: str, n: int, penetrating: bool, seed: int):
    rng = np.random.default_rng(seed)
    shapes, poses = [], []
    for _ in range(n):
        shapes += [make(kind_a, rng), make(kind_b, rng)]
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        gap = rng.uniform(0.2, 0.8) if penetrating else rng.uniform(2.5, 4.0)
        for at in (np.zeros(3), direction * gap):
            m = np.eye(4)
            m[:3, :3], m[:3, 3] = random_rotation(rng), at
            poses.append(m)
    pairs = np.arange(2 * n, dtype=np.int64).reshape(n, 2)
    return shapes, np.array(poses), pairs


def row(label, kind_a, kind_b, penetrating, args, coal) -> tuple[float, float | None]:
    shapes, poses, pairs = case(kind_a, kind_b, args.pairs, penetrating, seed=len(label))
    packed = ConvexSet.from_shapes(shapes)
    n = len(pairs)

    def run_meshcol():
        signed_distance_batch(packed, poses, pairs, threads=1)

    run_coal = None
    if coal is not None:
        objects = [
            (coal_shape(coal, s), coal.Transform3s(np.ascontiguousarray(p[:3, :3]), p[:3, 3]))
            for s, p in zip(shapes, poses)
        ]
        if penetrating:
            request, result = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 1), None

            def run_coal():
                for ia, ib in pairs:
                    (ga, ta), (gb, tb) = objects[ia], objects[ib]
                    coal.collide(ga, ta, gb, tb, request, coal.CollisionResult())
        else:
            request, result = coal.DistanceRequest(), coal.DistanceResult()

            def run_coal():
                for ia, ib in pairs:
                    result.clear()
                    (ga, ta), (gb, tb) = objects[ia], objects[ib]
                    coal.distance(ga, ta, gb, tb, request, result)

    ours, theirs = [], []
    for k in range(args.rounds):
        order = [run_meshcol, run_coal] if k % 2 == 0 else [run_coal, run_meshcol]
        for fn in order:
            if fn is None:
                continue
            (ours if fn is run_meshcol else theirs).append(cpu_time(fn) / n * 1e6)
    mine = min(ours)
    text = f"{label:34s} meshcol {mine:7.3f} us ({min(ours):.3f}-{max(ours):.3f})"
    peer = min(theirs) if theirs else None
    if peer is not None:
        text += f"  coal {peer:7.3f} us ({min(theirs):.3f}-{max(theirs):.3f})  coal/meshcol {peer / mine:5.2f}"
    print(text, flush=True)
    return mine, peer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=4000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    try:
        import coal
    except ImportError:
        coal = None
    if coal is not None:
        a, b = coal.Sphere(1.0), coal.Sphere(1.0)
        ta = coal.Transform3s(np.eye(3), np.zeros(3))
        tb = coal.Transform3s(np.eye(3), np.ones(3))
        request, result = coal.DistanceRequest(), coal.DistanceResult()

        def floor():
            for _ in range(2000):
                result.clear()
                coal.distance(a, ta, b, tb, request, result)

        print(
            f"coal per-call floor from Python (two spheres): {cpu_time(floor) / 2000 * 1e6:.3f} us"
        )
    families = [
        ("capsule", "capsule"),
        ("cylinder", "cylinder"),
        ("ellipsoid", "ellipsoid"),
        ("ellipsoid", "capsule"),
        ("ellipsoid", "sphere"),
        ("ellipsoid", "box"),
        ("ellipsoid", "cylinder"),
        ("tessellated", "tessellated"),
        ("tessellated", "capsule"),
    ]
    for penetrating in (False, True):
        for kind_a, kind_b in families:
            label = f"{kind_a}-{kind_b} {'penetrating' if penetrating else 'separated'}"
            row(label, kind_a, kind_b, penetrating, args, coal)


if __name__ == "__main__":
    main()
