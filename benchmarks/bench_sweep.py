"""Time of impact: meshcol vs python-fcl's continuousCollide on random convex hulls.

For 32, 128 and 512-vertex hulls, PAIRS random pairs move by pure translation (both bodies,
crossing the same region, so about half of them meet). Ground truth: the distance (meshcol's
GJK, exact on polytopes) at SAMPLES evenly spaced instants, then bisection between the last free
and the first touching sample. Reported per solver: misses (truth touches, solver says no
contact), false hits, the largest TOI error on the pairs both call hits, and the time per pair
(meshcol: batch on one thread, total / pairs; fcl: one Python call per pair, which includes
about a microsecond of call overhead). A second set adds random rotations (meshcol only: fcl's
motion models interpolate rotation differently, so its TOI is not comparable there).

Run: .venv/bin/python benchmarks/bench_sweep.py [--pairs 128] [--samples 1000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from meshcol import ConvexSet, distance_batch, interpolate_pose, time_of_impact_batch
from meshcol.types import TimeOfImpactStatus

TOLERANCE = 1e-6


def random_hull(rng, n):
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return p * rng.uniform(0.4, 1.0, size=3)


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def make_case(rng, n, rotate):
    verts = [random_hull(rng, n), random_hull(rng, n)]
    start = np.tile(np.eye(4), (2, 1, 1))
    start[:, :3, :3] = [random_rotation(rng), random_rotation(rng)]
    start[:, :3, 3] = rng.uniform(-3, 3, size=(2, 3))
    end = start.copy()
    end[:, :3, 3] = -start[:, :3, 3] + rng.normal(scale=0.8, size=(2, 3))
    if rotate:
        end[:, :3, :3] = [random_rotation(rng), random_rotation(rng)]
    return verts, start, end


def ground_truth(cs, start, end, samples):
    """First instant of contact (dense samples + bisection), or None."""
    pair = np.array([[0, 1]])

    def dist(t):
        return distance_batch(
            cs, interpolate_pose(start, end, np.full(2, t)), pair, threads=1
        ).distance[0]

    ts = np.linspace(0.0, 1.0, samples)
    prev = 0.0
    for t in ts:
        if dist(t) == 0.0:
            if t == 0.0:
                return 0.0
            lo, hi = prev, t
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if dist(mid) == 0.0 else (mid, hi)
            return hi
        prev = t
    return None


def fcl_convex(fcl, verts):
    from scipy.spatial import ConvexHull

    hull = ConvexHull(verts)
    faces = hull.simplices.copy()
    centre = verts.mean(axis=0)
    for k, f in enumerate(faces):
        n = np.cross(verts[f[1]] - verts[f[0]], verts[f[2]] - verts[f[0]])
        if n @ (verts[f[0]] - centre) < 0:
            faces[k] = f[[0, 2, 1]]
    flat = np.hstack([np.full((len(faces), 1), 3), faces]).ravel()
    return fcl.Convex(verts, len(faces), flat)


def summarise(name, hits, truth, tois, seconds):
    both = [(t, g) for t, g, h in zip(tois, truth, hits) if h and g is not None]
    misses = sum(1 for g, h in zip(truth, hits) if g is not None and not h)
    false_hits = sum(1 for g, h in zip(truth, hits) if g is None and h)
    err = max((abs(t - g) for t, g in both), default=float("nan"))
    late = max((t - g for t, g in both), default=float("nan"))
    return (
        f"  {name:<28} misses {misses:3d}  false hits {false_hits:3d}  "
        f"max |toi err| {err:9.2e}  max late {late:9.2e}  {seconds * 1e6:8.2f} us/pair"
    )


def run(n, pairs, samples, rotate, rng, fcl):
    cases = [make_case(rng, n, rotate) for _ in range(pairs)]
    sets = [ConvexSet.from_vertices(v) for v, _, _ in cases]
    truth = [ground_truth(cs, s, e, samples) for cs, (_, s, e) in zip(sets, cases)]
    truth = [None if t == 0.0 else t for t in truth]  # overlapping at start: not scored
    keep = [
        i for i, (cs, (_, s, e)) in enumerate(zip(sets, cases)) if ground_truth_start_free(cs, s)
    ]
    big = ConvexSet.concatenate(*[sets[i] for i in keep])
    start = np.concatenate([cases[i][1] for i in keep])
    end = np.concatenate([cases[i][2] for i in keep])
    idx = np.arange(2 * len(keep)).reshape(-1, 2)
    truth = [truth[i] for i in keep]
    t0 = time.perf_counter()
    repeat = 5
    for _ in range(repeat):
        r = time_of_impact_batch(big, start, end, idx, tolerance=TOLERANCE, threads=1)
    ours = (time.perf_counter() - t0) / repeat / len(keep)
    hits = [s == TimeOfImpactStatus.HIT for s in r.status]
    failed = int(np.sum(r.status == TimeOfImpactStatus.FAILED))
    print(
        f"{n}-vertex hulls, {'rotation + translation' if rotate else 'translation'}: "
        f"{len(keep)} pairs, {sum(t is not None for t in truth)} touch (ground truth: "
        f"{samples} samples + bisection)"
    )
    print(
        summarise("meshcol", hits, truth, list(r.time_of_impact), ours)
        + f"  failed {failed}  mean iterations {r.iterations.mean():.1f}"
    )
    if fcl is None or rotate:
        return ours, None
    objects = [(fcl_convex(fcl, cases[i][0][0]), fcl_convex(fcl, cases[i][0][1])) for i in keep]
    results = {}
    for label, solver in (
        ("fcl conservative advancement", fcl.CCDSolverType.CCDC_CONSERVATIVE_ADVANCEMENT),
        ("fcl naive", fcl.CCDSolverType.CCDC_NAIVE),
    ):
        req = fcl.ContinuousCollisionRequest(
            ccd_solver_type=solver, ccd_motion_type=fcl.CCDMotionType.CCDM_TRANS
        )
        calls = []
        for (ga, gb), i in zip(objects, keep):
            _, s, e = cases[i]
            oa = fcl.CollisionObject(ga, fcl.Transform(s[0, :3, :3], s[0, :3, 3]))
            ob = fcl.CollisionObject(gb, fcl.Transform(s[1, :3, :3], s[1, :3, 3]))
            calls.append(
                (
                    oa,
                    fcl.Transform(e[0, :3, :3], e[0, :3, 3]),
                    ob,
                    fcl.Transform(e[1, :3, :3], e[1, :3, 3]),
                )
            )
        hit, toi = [], []
        t0 = time.perf_counter()
        for oa, ea, ob, eb in calls:
            res = fcl.ContinuousCollisionResult()
            fcl.continuousCollide(oa, ea, ob, eb, req, res)
            hit.append(bool(res.is_collide))
            toi.append(res.time_of_contact)
        seconds = (time.perf_counter() - t0) / len(calls)
        results[label] = seconds
        print(summarise(label, hit, truth, toi, seconds))
    ca = results["fcl conservative advancement"]
    print(f"  speed-up vs fcl conservative advancement: {ca / ours:.1f}x")
    return ours, ca


def ground_truth_start_free(cs, start):
    return distance_batch(cs, start, np.array([[0, 1]]), threads=1).distance[0] > TOLERANCE


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=128)
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    try:
        import fcl
    except ImportError:
        fcl = None
        print("python-fcl not installed: meshcol only")
    rng = np.random.default_rng(args.seed)
    print(f"tolerance {TOLERANCE}, seed {args.seed}")
    for n in (32, 128, 512):
        run(n, args.pairs, args.samples, False, rng, fcl)
    for n in (32, 128, 512):
        run(n, args.pairs, args.samples, True, rng, fcl)


if __name__ == "__main__":
    main()
