"""The single-pair API, one call per pair as a user's loop makes them: what a call costs.

``distance(a, b, pose_a, pose_b)``, ``penetration``, ``signed_distance``, ``intersects`` and
``time_of_impact`` on every ordered pair of the four primitives (sphere, box, capsule,
cylinder), turned poses, a third of the pairs apart, a third near and a third overlapping; then
Box vs Sphere alone (the issue's row), a one-pair ``distance_batch`` on a ready set, and the
shapes whose hull is built per call (a 64-point cloud, a trimesh icosphere of 642 vertices,
against a box). Peers on the same pairs, one call each in a Python loop with their objects
made before the clock starts (what their single-pair API needs): coal's ``distance`` and
``collide``, python-fcl's ``distance`` and ``collide``; and meshcol's own one-pair batches on
sets packed beforehand (the query's cost, the floor of a single call). CPU time (``time.process_time``),
best of ``--rounds``, microseconds a call.

Run: .venv/bin/python benchmarks/bench_single_pair.py [--rounds 7] [--repeat 200]
A/B: .venv/bin/python benchmarks/with_other_meshcol.py /work/base20 benchmarks/bench_single_pair.py
"""

from __future__ import annotations

import argparse
import itertools
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from meshcol import (
    Box,
    Capsule,
    ConvexSet,
    Cylinder,
    Sphere,
    distance,
    distance_batch,
    intersects,
    intersects_batch,
    penetration,
    penetration_batch,
    signed_distance,
    signed_distance_batch,
    time_of_impact,
    time_of_impact_batch,
)

PRIMITIVES = [Sphere(0.5), Box((1.0, 0.6, 0.8)), Capsule(0.3, 1.2), Cylinder(0.4, 0.9)]


def rotation(rng: np.random.Generator) -> np.ndarray:
    w, x, y, z = (q := rng.normal(size=4)) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def pose(rng: np.random.Generator, gap: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rotation(rng)
    direction = rng.normal(size=3)
    m[:3, 3] = gap * direction / np.linalg.norm(direction)
    return m


def pairs(seed: int = 3) -> list[tuple[object, object, np.ndarray, np.ndarray]]:
    """Every ordered primitive pair at three centre distances (apart, near, overlapping)."""
    rng = np.random.default_rng(seed)
    return [
        (a, b, pose(rng, 0.0), pose(rng, gap))
        for gap in (3.0, 1.2, 0.3)
        for a, b in itertools.product(PRIMITIVES, repeat=2)
    ]


def best_us(fn: Callable[[], object], calls: int, rounds: int) -> float:
    """CPU microseconds a call: best of ``rounds`` runs of ``fn`` (which makes ``calls``)."""
    best = np.inf
    for _ in range(rounds):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best / calls * 1e6


def meshcol_rows(rows, repeat: int, rounds: int) -> dict[str, float]:
    def loop(query: Callable[..., object]) -> Callable[[], None]:
        def run() -> None:
            for _ in range(repeat):
                for a, b, pa, pb in rows:
                    query(a, b, pa, pb)

        return run

    def toi(a: object, b: object, pa: np.ndarray, pb: np.ndarray) -> object:
        return time_of_impact(a, b, pa, pa, pb, np.eye(4))

    n = repeat * len(rows)
    return {
        name: best_us(loop(query), n, rounds)
        for name, query in [
            ("distance", distance),
            ("penetration", penetration),
            ("signed_distance", signed_distance),
            ("intersects", intersects),
            ("time_of_impact", toi),
        ]
    }


def batch_rows(rows, repeat: int, rounds: int) -> dict[str, float]:
    """The same pairs as one-pair batches on two-shape sets packed before the clock starts:
    about the query's own cost."""
    ready = [
        (ConvexSet.from_shapes([a, b]), np.stack([pa, pb]), np.stack([pa, np.eye(4)]))
        for a, b, pa, pb in rows
    ]
    pair = np.array([[0, 1]], dtype=np.int64)

    def loop(batch: Callable[..., object]) -> Callable[[], None]:
        def run() -> None:
            for _ in range(repeat):
                for shapes, poses, _ in ready:
                    batch(shapes, poses, pair, threads=1)

        return run

    def toi() -> None:
        for _ in range(repeat):
            for shapes, starts, ends in ready:
                time_of_impact_batch(shapes, starts, ends, pair, threads=1)

    n = repeat * len(rows)
    out = {
        name: best_us(loop(batch), n, rounds)
        for name, batch in [
            ("distance", distance_batch),
            ("penetration", penetration_batch),
            ("signed_distance", signed_distance_batch),
            ("intersects", intersects_batch),
        ]
    }
    out["time_of_impact"] = best_us(toi, n, rounds)
    return out


def geometry(library: Any, s: object) -> object:
    """The primitive ``s`` as coal's or python-fcl's geometry (the same constructors)."""
    if isinstance(s, Sphere):
        return library.Sphere(s.radius)
    if isinstance(s, Box):
        return library.Box(*s.size)
    if isinstance(s, Capsule):
        return library.Capsule(s.radius, s.length)
    assert isinstance(s, Cylinder)
    return library.Cylinder(s.radius, s.length)


def coal_rows(rows, repeat: int, rounds: int) -> dict[str, float] | None:
    try:
        import coal
    except ImportError:
        return None

    def transform(m: np.ndarray) -> object:
        return coal.Transform3s(np.ascontiguousarray(m[:3, :3]), np.ascontiguousarray(m[:3, 3]))

    made = [
        (geometry(coal, a), transform(pa), geometry(coal, b), transform(pb))
        for a, b, pa, pb in rows
    ]
    d_request, d_result = coal.DistanceRequest(), coal.DistanceResult()
    c_request, c_result = coal.CollisionRequest(), coal.CollisionResult()

    def dist() -> None:
        for _ in range(repeat):
            for ga, ta, gb, tb in made:
                d_result.clear()
                coal.distance(ga, ta, gb, tb, d_request, d_result)

    def collide() -> None:
        for _ in range(repeat):
            for ga, ta, gb, tb in made:
                c_result.clear()
                coal.collide(ga, ta, gb, tb, c_request, c_result)

    n = repeat * len(rows)
    return {"distance": best_us(dist, n, rounds), "intersects": best_us(collide, n, rounds)}


def fcl_rows(rows, repeat: int, rounds: int) -> dict[str, float] | None:
    try:
        import fcl
    except ImportError:
        return None

    def obj(s: object, m: np.ndarray) -> object:
        return fcl.CollisionObject(geometry(fcl, s), fcl.Transform(m[:3, :3], m[:3, 3]))

    made = [(obj(a, pa), obj(b, pb)) for a, b, pa, pb in rows]
    d_request = fcl.DistanceRequest(enable_nearest_points=True)
    c_request = fcl.CollisionRequest()

    def dist() -> None:
        for _ in range(repeat):
            for oa, ob in made:
                fcl.distance(oa, ob, d_request, fcl.DistanceResult())

    def collide() -> None:
        for _ in range(repeat):
            for oa, ob in made:
                fcl.collide(oa, ob, c_request, fcl.CollisionResult())

    n = repeat * len(rows)
    return {"distance": best_us(dist, n, rounds), "intersects": best_us(collide, n, rounds)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--repeat", type=int, default=200, help="loops over the 48 pairs")
    args = parser.parse_args()
    rows = pairs()
    print(f"us a call, CPU, best of {args.rounds}; {len(rows)} primitive pairs x {args.repeat}")
    ours = meshcol_rows(rows, args.repeat, args.rounds)
    peers = {"batch": batch_rows(rows, args.repeat, args.rounds)}
    peers["coal"] = coal_rows(rows, args.repeat, args.rounds)
    peers["fcl"] = fcl_rows(rows, args.repeat, args.rounds)
    print("(batch: the same pairs as one-pair batches on sets packed beforehand)")
    print(f"{'query':<16} {'meshcol':>8} {'batch':>8} {'coal':>8} {'fcl':>8}")
    for name, us in ours.items():
        cells = [
            f"{p[name]:>8.2f}" if p is not None and name in p else f"{'-':>8}"
            for p in peers.values()
        ]
        print(f"{name:<16} {us:>8.2f} {' '.join(cells)}")

    rng = np.random.default_rng(11)
    box, sphere, pa, pb = Box((1.0, 0.6, 0.8)), Sphere(0.5), pose(rng, 0.0), pose(rng, 1.5)
    shapes, poses, pair = ConvexSet.from_shapes([box, sphere]), np.stack([pa, pb]), [[0, 1]]
    cloud = np.random.default_rng(5).normal(size=(64, 3))
    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=3)
    n = 20 * args.repeat
    single = [
        ("Box-Sphere distance", lambda: distance(box, sphere, pa, pb), n),
        ("Box-Sphere time_of_impact", lambda: time_of_impact(box, sphere, pa, pa, pb, pa), n),
        ("Box-Sphere distance_batch", lambda: distance_batch(shapes, poses, pair, threads=1), n),
        ("cloud64-Box distance", lambda: distance(cloud, box, pa, pb), n // 10),
        ("icosphere642-Box distance", lambda: distance(ball, box, pa, pb), n // 40),
    ]
    print(f"\n{'one pair':<28} {'meshcol':>8}")
    for name, call, calls in single:

        def run(call: Callable[[], object] = call, calls: int = calls) -> None:
            for _ in range(calls):
                call()

        print(f"{name:<28} {best_us(run, calls, args.rounds):>8.2f}")


if __name__ == "__main__":
    main()
