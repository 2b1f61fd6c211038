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

Library rows (``--library N [N ...]``): ``meshcol sweep`` of a moving version of bench_scale's
N-prop scene (:func:`moving_scene`), the baseline build (``--baseline``, the lead's unchanged
meshcol) and this one alternating (B A A B), CPU seconds, wall and peak RSS of each process and
whether their JSON reports are byte-identical; then this build's stages in one process
(CPU seconds: load and colliders, broad phase, the core's time of impact and overlap tests,
the first contact per body pair, the JSON report written).

    .venv/bin/python benchmarks/bench_sweep.py --library 10000 100000 \
        --baseline /work/base41/.venv/bin/meshcol
"""

from __future__ import annotations

import argparse
import itertools
import json
import random
import sys
import tempfile
import time
from pathlib import Path

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


#: The sizes whose moving scenes draw from one ``random.seed(1)`` stream, in this order
#: (three draws a body), as the lead made ``moving.json`` of 1,000 and 10,000 props.
MOVING_SIZES = (1000, 10000, 100000)


def moving_scene(n: int) -> Path:
    """``benchmarks/.cache/scale/<n>/moving.json``: bench_scale's N-prop scene, every body
    with ``velocity`` [U(-2, 2), U(-2, 2), 0] and ``angular_velocity`` [0, 0, U(-3, 3)],
    ``duration`` 1.0 (``random.seed(1)``, drawn for the sizes of :data:`MOVING_SIZES` in
    turn); written once."""
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_scale import scene_folder

    path = scene_folder(n) / "moving.json"
    if path.exists():
        return path
    rng = random.Random(1)
    for size in MOVING_SIZES:
        draws = [(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-3, 3)) for _ in range(size)]
        if size == n:
            break
    else:
        raise SystemExit(f"--library sizes are {MOVING_SIZES}")
    scene = json.loads((path.parent / "scene.json").read_text())
    for body, (vx, vy, w) in zip(scene["bodies"], draws):
        body["velocity"] = [vx, vy, 0]
        body["angular_velocity"] = [0, 0, w]
    scene["duration"] = 1.0
    path.with_suffix(".tmp").write_text(json.dumps(scene))
    path.with_suffix(".tmp").rename(path)
    return path


def library_rows(sizes: list[int], baseline: str | None, rounds: int) -> None:
    """The library rows: base and new ``meshcol sweep`` alternating, then the new stages."""
    import os

    sys.path.insert(0, str(Path(__file__).parent))
    from bench_scale import LAST_CPU, timed

    new = str(Path(sys.executable).parent / "meshcol")
    sides = [("new", new)] + ([("base", baseline)] if baseline else [])
    print(f"load {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            moving = moving_scene(n)
            figures: dict[str, list[tuple[float, float, float]]] = {name: [] for name, _ in sides}
            order = [sides[-1], sides[0], sides[0], sides[-1]] * max(1, rounds // 2)
            for name, program in order:
                report = Path(tmp) / f"{name}.json"
                code, wall, rss = timed(
                    [program, "sweep", str(moving), "--report", str(report), "--fail-on", "none"]
                )
                if code != 0:
                    raise SystemExit(f"{name}: meshcol sweep exit {code}")
                figures[name].append((LAST_CPU[0], wall, rss))
            print(f"moving {n}-prop scene ({moving}), load {os.getloadavg()[0]:.2f}:")
            for name, rows in figures.items():
                cpu, wall, rss = zip(*rows)
                print(
                    f"  {name:<4} CPU {min(cpu):6.2f}-{max(cpu):6.2f} s  wall {min(wall):6.2f}-"
                    f"{max(wall):6.2f} s  peak RSS {max(rss):7.0f} MiB  ({len(rows)} runs)"
                )
            if baseline:
                same = (Path(tmp) / "new.json").read_bytes() == (
                    Path(tmp) / "base.json"
                ).read_bytes()
                print(f"  JSON reports byte-identical: {same}")
            print(f"  stages (this build, one process): {sweep_stages(moving, Path(tmp))}")


def sweep_stages(moving: Path, tmp: Path) -> str:
    """CPU seconds of the stages of :func:`meshcol.analysis.sweep.sweep` in this process, and
    of writing its JSON report (the garbage collector at the command line's threshold)."""
    import gc

    from meshcol.cli import GC_THRESHOLD

    gc.set_threshold(GC_THRESHOLD, *gc.get_threshold()[1:])
    from meshcol.analysis import sweep as sw
    from meshcol.analysis.colliders import build_colliders
    from meshcol.io.formats import write_report

    marks = [("start", time.process_time())]

    def mark(name: str) -> None:
        marks.append((name, time.process_time()))

    scene = sw._moving_scene(str(moving), "hull", "none")
    colliders = build_colliders(scene.bodies, "hull", mesh_parts="triangles")
    motion = sw._Motion.of(colliders)
    mark("load+colliders")
    lo, hi, tol = sw._swept_boxes(colliders, motion, scene, None, 0)
    pairs = sw._candidates(lo, hi, tol, colliders.part_body, motion.moving)
    mark("broad")
    contacts = sw._Contacts.of(colliders, motion, pairs, tol, None, 0)
    mark("time of impact+overlaps")
    hits, separated, count = sw._first_contacts(colliders, motion, pairs, contacts, scene)
    mark("first contacts")
    report = sw.SweepReport(
        scene,
        tuple(colliders.bodies),
        "hull",
        tol,
        hits,
        count,
        len(pairs),
        tuple(bool(m) for m in motion.moving),
        "none",
        colliders.warnings,
        separated,
    )
    write_report(report, "json", str(tmp / "stages.json"))
    mark("JSON report")
    steps = [f"{b[0]} {b[1] - a[1]:.2f}" for a, b in itertools.pairwise(marks)]
    return (
        ", ".join(steps)
        + f" s CPU; {len(pairs)} part pairs, {count} candidate pairs, {len(hits)} hits"
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=128)
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--library", type=int, nargs="+", metavar="N", default=None)
    parser.add_argument("--baseline", default=None, help="the baseline build's meshcol")
    parser.add_argument("--rounds", type=int, default=2, help="library runs per side")
    args = parser.parse_args()
    if args.library:
        library_rows(args.library, args.baseline, args.rounds)
        return
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
