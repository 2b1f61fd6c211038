"""Narrow-phase benchmark: meshcol batched queries vs python-fcl (and coal, if installed),
per call, on the same pairs of convex hulls (the smooth-hull family of issue 32: points on
random ellipsoids, every one a hull vertex, randomly turned; 16, 32, 64, 128, 256 and 512
vertices, ``--sizes``), separated, touching (each pair of a separated case moved along its
normal until it touches: signed distance about 0) and penetrating, with meshcol on one
thread, python-fcl and coal per call from Python, in CPU time over rounds that alternate the
three (a shared machine moves wall times 2-6x; CPU time far less), and the ratios of their
best times to meshcol's; plus coal's per-call floor from Python (two spheres), so the reader
sees how much of coal's figure is the Python loop. Also reports the worst accuracy
seen against the exact brute-force oracles (tests/oracles.py) on a subset of the pairs.

Then the cache case of issue 14 (``--only-unique`` runs it alone): 40,000 bodies, each with
its own 64-vertex hull in memory (``ConvexSet.take`` copies of 256 hulls at random rotations
on a jittered lattice), pairs as the broad phase gives them (sort and sweep of the world
boxes, about 2.8 overlaps per body). The reference is the same pairs with everything in
cache: the scene cut into neighbourhoods of 256 bodies, each its own small set and batch
(pairs across neighbourhoods left out of every row). Rows: the bodies numbered in random
order (as a manifest may list them) and in spatial (Morton) order; plus the older
reference, 256 bodies whose few hundred pairs repeat. Ratio to the in-cache row per pair;
target <= 1.5.

With ``--boxes``, also a box-like family: cuboids (8 corners) and wedges (6), rotated, whose
coplanar triangles merge into faces and whose edges are parallel in classes (row ``box``).

Run: .venv/bin/python benchmarks/bench_narrowphase.py [--pairs 4000] [--unique-shapes 40000]
     [--only-unique] [--sizes 16 64 256] [--boxes] [--skip-unique] [--rounds 5]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from meshcol import ConvexSet, distance_batch, signed_distance_batch


def sphere_hull(n: int, rng: np.random.Generator) -> np.ndarray:
    """n points on an ellipsoid: every one is a hull vertex."""
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return p * rng.uniform(0.7, 1.3, size=3)


def box_like(rng: np.random.Generator) -> np.ndarray:
    """A cuboid (8 corners) or a wedge (a right triangular prism, 6 corners), half extents
    0.4-1.3, as polytope vertices: the parts of assets with few vertices, whose coplanar
    triangles merge into one face and whose edges fall into parallel classes."""
    hx, hy, hz = rng.uniform(0.4, 1.3, size=3)
    corners = np.array([[x, y, z] for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)])
    if rng.uniform() < 0.5:
        return corners
    # The prism over the triangle (-hx, -hy), (-hx, hy), (hx, -hy), along z.
    return corners[:6]


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def make_case(n_vertices: int, n_pairs: int, penetrating: bool, seed: int, boxes: bool = False):
    """A scene of 256 hulls at random poses in a 9 x 9 x 9 box (each hull in several pairs,
    as broad-phase output is); pairs drawn from those that are separated (centres at most 4
    apart) or that overlap, as asked. With ``boxes``, cuboids and wedges (``box_like``)
    instead of ``n_vertices`` points on ellipsoids."""
    rng = np.random.default_rng(seed)
    n_shapes = 256
    shapes = [box_like(rng) if boxes else sphere_hull(n_vertices, rng) for _ in range(n_shapes)]
    cs = ConvexSet.from_vertices(shapes)
    poses = np.tile(np.eye(4), (n_shapes, 1, 1))
    for p in poses:
        p[:3, :3] = random_rotation(rng)
        p[:3, 3] = rng.uniform(0, 9, size=3)
    i, j = np.triu_indices(n_shapes, 1)
    near = np.linalg.norm(poses[i, :3, 3] - poses[j, :3, 3], axis=1) < 4.0
    candidates = np.stack([i[near], j[near]], axis=1)
    depth = signed_distance_batch(cs, poses, candidates).signed_distance
    chosen = candidates[depth < 0] if penetrating else candidates[depth > 0]
    pairs = chosen[rng.integers(0, len(chosen), size=n_pairs)]
    return cs, poses, np.ascontiguousarray(pairs), shapes


def touching_case(cs: ConvexSet, poses: np.ndarray, pairs: np.ndarray, shapes: list):
    """Each pair on its own two poses, b moved along the pair's normal by its distance, so the
    two touch (signed distance about 0, either sign by rounding): (set, poses, pairs, shapes)
    with shapes ``2k`` and ``2k + 1`` the pair ``k``."""
    result = distance_batch(cs, poses, pairs, threads=1)
    rows = pairs.reshape(-1)
    moved = poses[rows].copy()
    moved[1::2, :3, 3] -= result.distance[:, None] * result.normal
    touching = np.arange(len(rows), dtype=np.int64).reshape(-1, 2)
    return cs.take(rows), moved, touching, [shapes[r] for r in rows.tolist()]


def time_it(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def fcl_objects(shapes, poses):
    import fcl
    from scipy.spatial import ConvexHull

    objects = []
    for pts, pose in zip(shapes, poses):
        hull = ConvexHull(pts)
        faces = np.hstack([np.full((len(hull.simplices), 1), 3), hull.simplices]).ravel()
        geom = fcl.Convex(pts, len(hull.simplices), faces)
        objects.append(fcl.CollisionObject(geom, fcl.Transform(pose[:3, :3], pose[:3, 3])))
    return objects


def coal_objects(shapes, poses):
    import coal

    out = []
    for pts, pose in zip(shapes, poses):
        vec = coal.StdVec_Vec3s()
        for q in np.asarray(pts):
            vec.append(q)
        geom = coal.ConvexBase.convexHull(vec, False, "")
        tf = coal.Transform3s(pose[:3, :3], pose[:3, 3])
        out.append((geom, tf))
    return out


def lattice_scene(templates: ConvexSet, n_bodies: int, seed: int, spacing: float = 2.15):
    """``n_bodies`` copies of random templates at random rotations on a jittered cubic
    lattice (about 2.8 box overlaps per body), numbered in random order; the set, poses and
    the broad phase's candidate pairs (sort and sweep, index order)."""
    from meshcol import sort_and_sweep

    rng = np.random.default_rng(seed)
    side = int(np.ceil(n_bodies ** (1 / 3)))
    cells = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    cells = cells[rng.permutation(len(cells))[:n_bodies]]
    poses = np.tile(np.eye(4), (n_bodies, 1, 1))
    for p in poses:
        p[:3, :3] = random_rotation(rng)
    poses[:, :3, 3] = cells * spacing + rng.uniform(-0.35, 0.35, size=(n_bodies, 3))
    cs = templates.take(rng.integers(0, len(templates), size=n_bodies))
    lo, hi = cs.aabbs(poses)
    return cs, poses, sort_and_sweep(lo, hi)


def morton_order(points: np.ndarray) -> np.ndarray:
    """Indices of ``points`` (n, 3) in Morton (Z-curve) order on a 1024^3 grid."""
    extent = max(float(np.max(points.max(0) - points.min(0))), 1e-300)
    q = ((points - points.min(0)) / extent * 1023).astype(np.int64)
    code = np.zeros(len(points), dtype=np.int64)
    for bit in range(10):
        for axis in range(3):
            code |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
    return np.argsort(code, kind="stable")


def unique_case(args) -> None:
    """Issue 14 item 3: per-pair cost when every body has its own shape in memory."""
    rng = np.random.default_rng(64)
    templates = ConvexSet.from_vertices([sphere_hull(64, rng) for _ in range(256)])
    cs, poses, pairs = lattice_scene(templates, args.unique_shapes, seed=2)
    # The same scene renumbered in spatial order (what packing in that order would give).
    perm = morton_order(poses[:, :3, 3])
    rank = np.empty_like(perm)
    rank[perm] = np.arange(len(perm))
    cs_s, poses_s = cs.take(perm), np.ascontiguousarray(poses[perm])
    pairs_s = np.sort(rank[pairs], axis=1)
    pairs_s = pairs_s[np.lexsort((pairs_s[:, 1], pairs_s[:, 0]))]
    # Neighbourhoods of 256 consecutive bodies in spatial order, each its own set: in cache.
    hood = 256
    inside = pairs_s[:, 0] // hood == pairs_s[:, 1] // hood
    kept = np.ascontiguousarray(pairs_s[inside])
    groups = []
    for g in np.unique(kept[:, 0] // hood):
        sel = kept[kept[:, 0] // hood == g]
        idx = np.arange(g * hood, min((g + 1) * hood, len(cs_s)))
        groups.append(
            (
                cs_s.take(idx),
                np.ascontiguousarray(poses_s[idx]),
                np.ascontiguousarray(sel - g * hood),
            )
        )
    kept_random = np.ascontiguousarray(np.sort(perm[kept], axis=1))
    kept_random = kept_random[np.lexsort((kept_random[:, 1], kept_random[:, 0]))]
    shared = lattice_scene(templates, 256, seed=1)
    reps = max(1, len(kept) // max(1, len(shared[2])))
    shared_pairs = np.ascontiguousarray(np.tile(shared[2], (reps, 1)))
    mb = sum(getattr(cs, f).nbytes for f in ConvexSet._FIELDS) / 2**20
    print(
        f"\nunique shapes: {len(cs)} bodies of 64 vertices ({mb:.0f} MiB packed), "
        f"{len(pairs)} broad-phase pairs ({2 * len(pairs) / len(cs):.2f} per body), "
        f"{len(kept)} inside neighbourhoods of {hood} timed; one thread, best of "
        f"{args.repeat} alternated rounds"
    )
    print(f"{'query':>11} {'case':>40} {'us/pair':>8} {'/ cache':>8}")

    def grouped(fn):
        for g_cs, g_poses, g_pairs in groups:
            fn(g_cs, g_poses, g_pairs, threads=1)

    for query, fn in (("distance", distance_batch), ("signed", signed_distance_batch)):
        rows = [
            ("same pairs in cache (256-body sets)", lambda: grouped(fn), len(kept)),
            (
                "unique, bodies in random order",
                lambda: fn(cs, poses, kept_random, threads=1),
                len(kept),
            ),
            (
                "unique, bodies in spatial order",
                lambda: fn(cs_s, poses_s, kept, threads=1),
                len(kept),
            ),
            (
                "256 bodies, their pairs repeated",
                lambda: fn(shared[0], shared[1], shared_pairs, threads=1),
                len(shared_pairs),
            ),
        ]
        # Rounds alternate the rows, so that each sees the same minutes of a shared machine.
        best = [np.inf] * len(rows)
        for _ in range(args.repeat):
            for r, (_, run, count) in enumerate(rows):
                best[r] = min(best[r], time_it(run, 1) / count * 1e6)
        for (label, _, _), us in zip(rows, best):
            print(f"{query:>11} {label:>40} {us:>8.3f} {us / best[0]:>8.2f}")


def cpu_time(fn) -> float:
    """CPU seconds of one call (this process, every thread): what the load moves least."""
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def span(values: list[float]) -> str:
    return f"{min(values):.3f}-{max(values):.3f}"


def coal_trivial_call_us(rounds: int, calls: int = 2000) -> list[float]:
    """Coal's per-call floor from Python: ``coal.distance`` on two unit spheres 3 apart, in
    the same loop as the family's rows (request and result reused), us per call, per round."""
    import coal

    a, b = coal.Sphere(1.0), coal.Sphere(1.0)
    ta, tb = coal.Transform3s(np.eye(3), np.zeros(3)), coal.Transform3s(np.eye(3), np.ones(3))
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    pairs = [(0, 1)] * calls
    objs = [(a, ta), (b, tb)]

    def run():
        for ia, ib in pairs:
            res.clear()
            ga, tfa = objs[ia]
            gb, tfb = objs[ib]
            coal.distance(ga, tfa, gb, tfb, req, res)

    return [cpu_time(run) / calls * 1e6 for _ in range(rounds)]


def peer_runners(fcl, coal, shapes, poses, pairs, penetrating: bool):
    """The peers' loops over ``pairs`` (None when a peer is missing), per call from Python:
    fcl ``collide`` with one contact (depth) or ``distance``; coal ``distance`` (signed:
    EPA's depth when the shapes overlap), request and result reused."""
    run_fcl = run_coal = None
    if fcl is not None:
        objs = fcl_objects(shapes, poses)
        if penetrating:

            def run_fcl():
                for ia, ib in pairs:
                    req = fcl.CollisionRequest(enable_contact=True, num_max_contacts=1)
                    fcl.collide(objs[ia], objs[ib], req, fcl.CollisionResult())
        else:

            def run_fcl():
                for ia, ib in pairs:
                    fcl.distance(objs[ia], objs[ib], fcl.DistanceRequest(), fcl.DistanceResult())

    if coal is not None:
        objs_c = coal_objects(shapes, poses)
        req = coal.DistanceRequest()
        res_c = coal.DistanceResult()

        def run_coal():
            for ia, ib in pairs:
                res_c.clear()
                ga, ta = objs_c[ia]
                gb, tb = objs_c[ib]
                coal.distance(ga, ta, gb, tb, req, res_c)

    return run_fcl, run_coal


def family_accuracy(res, shapes, poses, pairs, label: str, k_acc: int) -> float:
    """Worst error of meshcol against the exact oracles (tests/oracles.py) on ``k_acc`` pairs:
    relative, absolute for touching pairs (about 0 either way)."""
    from oracles import polytope_distance, sat_depth, transform

    worst = 0.0
    for k in range(k_acc):
        ia, ib = pairs[k]
        wa, wb = transform(shapes[ia], poses[ia]), transform(shapes[ib], poses[ib])
        if label == "touching":
            worst = max(worst, abs(res.depth[k] - max(sat_depth(wa, wb), 0.0)))
        elif label == "penetrating":
            truth = max(sat_depth(wa, wb), 0.0)
            worst = max(worst, abs(res.depth[k] - truth) / max(truth, 1e-300))
        else:
            truth = polytope_distance(wa, wb)
            worst = max(worst, abs(res.distance[k] - truth) / max(truth, 1e-300))
    return worst


def family_row(args, fcl, coal, n: int, label: str) -> float:
    """One size and configuration: meshcol (one thread), fcl and coal timed in CPU time in
    ``args.rounds`` alternated rounds; prints ranges and the ratios of the best times. Size 0
    is the box-like family (``box_like``), printed as ``box``."""
    penetrating = label != "separated"
    boxes = n == 0
    cs, poses, pairs, shapes = make_case(n, args.pairs, label == "penetrating", n, boxes)
    if label == "touching":
        cs, poses, pairs, shapes = touching_case(cs, poses, pairs, shapes)
    query, fn = (
        ("penetration", signed_distance_batch) if penetrating else ("distance", distance_batch)
    )
    n_peer = min(args.peer_pairs, len(pairs))
    run_fcl, run_coal = peer_runners(fcl, coal, shapes, poses, pairs[:n_peer], penetrating)
    mc: list[float] = []
    fc: list[float] = []
    co: list[float] = []
    for _ in range(args.rounds):
        mc.append(cpu_time(lambda: fn(cs, poses, pairs, threads=1)) / len(pairs) * 1e6)
        if run_fcl is not None:
            fc.append(cpu_time(run_fcl) / n_peer * 1e6)
        if run_coal is not None:
            co.append(cpu_time(run_coal) / n_peer * 1e6)
    res = fn(cs, poses, pairs, threads=1)
    k_acc = min(args.accuracy_pairs, len(pairs)) if n <= 128 else 6
    worst = family_accuracy(res, shapes, poses, pairs, label, k_acc)
    nan = [float("nan")]
    fcl_ratio = min(fc or nan) / min(mc)
    coal_ratio = min(co or nan) / min(mc)
    size = "box" if boxes else str(n)
    print(
        f"{size:>5} {label:>11} {query:>11} {span(mc):>13} {span(fc or nan):>15} "
        f"{span(co or nan):>15} {fcl_ratio:>8.1f} {coal_ratio:>8.1f} {worst:>13.2e}"
    )
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=4000)
    parser.add_argument("--peer-pairs", type=int, default=1000, help="pairs timed for peers")
    parser.add_argument("--accuracy-pairs", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=5, help="alternated timing rounds")
    parser.add_argument("--unique-shapes", type=int, default=40000)
    parser.add_argument("--repeat", type=int, default=3, help="best of, unique-shape case")
    parser.add_argument("--only-unique", action="store_true", help="the cache case alone")
    parser.add_argument("--skip-unique", action="store_true", help="no cache case")
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64, 128, 256, 512])
    parser.add_argument(
        "--boxes", action="store_true", help="also the box-like family (cuboids and wedges)"
    )
    args = parser.parse_args()
    if args.only_unique:
        unique_case(args)
        return
    try:
        import fcl
    except ImportError:
        fcl = None
    try:
        import coal
    except ImportError:
        coal = None
    for name, module in (("python-fcl", fcl), ("coal", coal)):
        if module is None:
            print(f"{name}: skipped (not installed); its columns are nan")
    print(
        f"pairs per case: {args.pairs}; peers timed on {args.peer_pairs} pairs (per call from "
        f"Python); CPU time (time.process_time) in us a pair, min-max over {args.rounds} "
        "rounds that alternate meshcol (one thread), fcl and coal; ratios of the minima"
    )
    if coal is not None:
        floor = coal_trivial_call_us(args.rounds)
        print(f"coal per-call floor (two spheres, the same Python loop): {span(floor)} us")
    print(
        f"{'hull':>5} {'case':>11} {'query':>11} {'meshcol 1t':>13} {'fcl':>15} {'coal':>15} "
        f"{'fcl/mc':>8} {'coal/mc':>8} {'worst rel err':>13}"
    )
    worst_overall = 0.0
    for n in [*args.sizes, *([0] if args.boxes else [])]:
        for label in ("separated", "touching", "penetrating"):
            worst_overall = max(worst_overall, family_row(args, fcl, coal, n, label))
    print(f"worst error vs exact oracles (relative; absolute for touching): {worst_overall:.2e}")
    if not args.skip_unique:
        unique_case(args)


if __name__ == "__main__":
    main()
