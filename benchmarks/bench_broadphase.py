"""Broad phase benchmark: meshcol sort-and-sweep and AABB tree vs python-fcl and coal.

Run from the repository root:  .venv/bin/python benchmarks/bench_broadphase.py [--quick]

Scenes: N random cubes in the unit cube, sized for about 2.5 overlaps per box (the measured
average is printed), for N = 1e3 .. 1e6; and a level-like layout (many small props on a
100 x 100 plane plus a few large floor and wall slabs). Every time is end to end from Python,
as a user pays it: building the peers' Python objects is included, and so is meshcol's input
conversion and output array. Each figure is the best of several runs (the machine is shared).

Peers (both optional): python-fcl ``DynamicAABBTreeCollisionManager`` with a Python callback
counting pairs (python-fcl has no other way to list them); coal
``DynamicAABBTreeArrayCollisionManager`` with its C++ ``CollisionCallBackCollect``.
At N = 1e6 both peers are extrapolated from N = 1e5 (N log N) and marked so: python-fcl
is slow there, and coal 3.0.3 with a million objects ended the process with SIGSEGV in our
one attempt.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from meshcol.collision.broadphase import AabbTree, SortAndSweep, sort_and_sweep

try:
    import fcl
except ImportError:  # optional peer
    fcl = None
try:
    import coal
except ImportError:  # optional peer
    coal = None


def best_of(fn, repeats):
    best, result = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def random_cubes(n, rng):
    # Cubes of side s with uniform centres overlap when centres are within s on every axis:
    # expected overlaps per box ~ (n - 1) (2 s)^3 = 2.5 (a little less near the walls).
    side = (2.5 / n) ** (1 / 3) / 2
    lo = rng.random((n, 3))
    return lo, lo + side


def level_layout(n, rng):
    """Props on a 100 x 100 plane (sizes 0.3..1.2, heights up to 2), plus floor and walls."""
    big = 16
    props = n - big
    side = np.sqrt(1.0 * 100 * 100 / props) / 2 * rng.uniform(0.5, 1.5, size=(props, 1))
    xy = rng.random((props, 2)) * 100
    lo = np.column_stack([xy, np.zeros(props)])
    hi = lo + np.column_stack([side, side, rng.uniform(0.2, 2.0, props)])
    floor = [[0, 0, -0.5], [0, 0, 0]], [[100, 100, 0], [50, 50, 0.1]]
    walls_lo = (
        [[0, 0, 0], [0, 99, 0], [0, 0, 0], [99, 0, 0]]
        + [[12.5 * k, 0, 0] for k in range(1, 8)]
        + [[0, 25, 0], [0, 50, 0], [0, 75, 0]]
    )
    walls_hi = (
        [[100, 1, 4], [100, 100, 4], [1, 100, 4], [100, 100, 4]]
        + [[12.5 * k + 0.3, 100, 3] for k in range(1, 8)]
        + [[100, 25.3, 3], [100, 50.3, 3], [100, 75.3, 3]]
    )
    big_lo = np.array(floor[0] + walls_lo[: big - 2], dtype=float)
    big_hi = np.array(floor[1] + walls_hi[: big - 2], dtype=float)
    return np.vstack([lo, big_lo]), np.vstack([hi, big_hi])


def meshcol_tree(lo, hi):
    return AabbTree.from_boxes(lo, hi).query_pairs()


def meshcol_tree_inserted(lo, hi):
    tree = AabbTree()
    tree.insert(lo, hi)
    return tree.query_pairs()


def fcl_pairs(lo, hi):
    centres, sizes = (lo + hi) / 2, hi - lo
    objects = [fcl.CollisionObject(fcl.Box(*s), fcl.Transform(c)) for c, s in zip(centres, sizes)]
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objects)
    manager.setup()
    count = [0]

    def callback(o1, o2, data):
        data[0] += 1
        return False

    manager.collide(count, callback)
    return count[0]


def coal_pairs(lo, hi):
    centres, sizes = (lo + hi) / 2, hi - lo
    eye = np.eye(3)
    objects = [
        coal.CollisionObject(coal.Box(*s), coal.Transform3s(eye, c)) for c, s in zip(centres, sizes)
    ]
    manager = coal.DynamicAABBTreeArrayCollisionManager()
    for o in objects:
        manager.registerObject(o)
    manager.setup()
    collect = coal.CollisionCallBackCollect(8 * len(objects) + 1024)
    manager.collide(collect)
    return collect.numCollisionPairs()


def row(name, n, seconds, pairs, note=""):
    print(
        f"  {name:<34} N={n:>8}  {seconds * 1e3:10.2f} ms  pairs={pairs}{('  ' + note) if note else ''}"
    )


def run_scene(label, lo, hi, repeats, peers):
    n = len(lo)
    t_sas, pairs = best_of(lambda: sort_and_sweep(lo, hi), repeats)
    k = len(pairs)
    print(f"{label}: N={n}, overlapping pairs={k}, average overlaps per box={2 * k / n:.2f}")
    row("meshcol sort_and_sweep", n, t_sas, k)
    t_tree, tp = best_of(lambda: meshcol_tree(lo, hi), repeats)
    assert np.array_equal(tp, pairs)
    row("meshcol AabbTree.from_boxes+pairs", n, t_tree, len(tp))
    t_ins, ip = best_of(lambda: meshcol_tree_inserted(lo, hi), max(1, repeats // 2))
    assert np.array_equal(ip, pairs)
    row("meshcol AabbTree.insert+pairs", n, t_ins, len(ip))
    results = {"sas": t_sas, "tree": t_tree, "insert": t_ins}
    if coal is not None and "coal" in peers:
        t, c = best_of(lambda: coal_pairs(lo, hi), 1 if n >= 10**5 else repeats)
        row("coal DynamicAABBTreeArray (collect)", n, t, c, "" if c == k else f"(meshcol {k})")
        results["coal"] = t
    if fcl is not None and "fcl" in peers:
        t, c = best_of(lambda: fcl_pairs(lo, hi), 1 if n >= 10**5 else repeats)
        row("python-fcl DynamicAABBTree", n, t, c, "" if c == k else f"(meshcol {k})")
        results["fcl"] = t
    for peer in ("coal", "fcl"):
        if peer in results:
            print(
                f"    {peer} / meshcol sort_and_sweep = {results[peer] / t_sas:6.1f}x, "
                f"{peer} / meshcol tree = {results[peer] / t_tree:6.1f}x"
            )
    return results


def incremental(n, rng, repeats):
    """A moving scene: every box moves by a normal step of `fraction` x its size, and back.

    One SortAndSweep is built before timing; each timed update() is one step of the scene
    (a small motion from the previous step). A fresh sort_and_sweep of the same boxes is timed
    right before each update, so both see the same machine load; the ratio printed is the
    median of the per-step ratios (robust on a shared machine), the times the best of each.
    Both results are checked equal.
    """
    lo, hi = random_cubes(n, rng)
    side = hi[0, 0] - lo[0, 0]
    print(
        f"Incremental sweep, N={n}: update() per step of a moving scene vs a fresh sort_and_sweep"
    )
    for fraction in (0.001, 0.01, 0.1):
        step = rng.normal(scale=fraction * side, size=lo.shape)
        moved_lo, moved_hi = lo + step, hi + step
        sweep = SortAndSweep(lo, hi)
        fresh_times, update_times = [], []
        for _ in range(repeats):
            t_fresh, fresh = best_of(lambda: sort_and_sweep(moved_lo, moved_hi), 1)
            t_inc, got = best_of(lambda: sweep.update(moved_lo, moved_hi), 1)
            assert np.array_equal(got, fresh)
            fresh_times.append(t_fresh)
            update_times.append(t_inc)
            moves = sweep.last_shifts
            sweep.update(lo, hi)  # the next step moves back: again a small motion
        ratio = float(np.median(np.array(fresh_times) / np.array(update_times)))
        print(
            f"  motion {fraction:>5} x box size: update {min(update_times) * 1e3:8.2f} ms, "
            f"fresh {min(fresh_times) * 1e3:8.2f} ms, fresh / update = {ratio:4.2f}x (median of "
            f"{repeats} paired steps), insertion-sort moves = {moves}"
        )


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help="stop at N = 1e5")
    args = parser.parse_args()
    rng = np.random.default_rng(12345)
    print(f"peers: python-fcl {'yes' if fcl else 'missing'}, coal {'yes' if coal else 'missing'}")
    sizes = [10**3, 10**4, 10**5] + ([] if args.quick else [10**6])
    peer_1e5 = {}
    for n in sizes:
        lo, hi = random_cubes(n, rng)
        peers = {"coal", "fcl"} if n <= 10**5 else set()
        res = run_scene("Random cubes", lo, hi, 5 if n <= 10**5 else 3, peers)
        if n == 10**5:
            peer_1e5 = {p: res[p] for p in ("coal", "fcl") if p in res}
        if n == 10**6:
            for peer, t in peer_1e5.items():
                est = t * 10 * math.log(1e6) / math.log(1e5)
                print(
                    f"  {peer:<34} N= 1000000  ~{est * 1e3:9.0f} ms  EXTRAPOLATED from N=1e5 as "
                    f"N log N, not measured ({est / res['sas']:.0f}x sort_and_sweep)"
                )
        print()
    for n in [10**4, 10**5]:
        lo, hi = level_layout(n, rng)
        run_scene("Level layout", lo, hi, 5, {"coal", "fcl"})
        print()
    incremental(10**5, rng, 9)
    if not args.quick:
        incremental(10**6, rng, 5)


if __name__ == "__main__":
    main()
