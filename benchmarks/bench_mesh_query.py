"""Exact mesh-mesh queries: meshcol (MeshSet + mesh_distance_batch) vs python-fcl BVHModel.

Run: .venv/bin/python benchmarks/bench_mesh_query.py [--runs 3] [--coal] [--coal-only]

With --runs N the whole set runs N times (meshcol and fcl side by side in each) and a summary
gives each row's fcl/meshcol ratio as a range over the runs. The single-pair rows (distance,
intersects) time meshcol and fcl in alternating windows of at least a millisecond, best of 9
each, so that both sides see the same load on a shared machine.

Then the mesh penetration depth (mesh_penetration_depth_batch) against fcl.collide with
contacts (the deepest contact's penetration_depth), on overlapping and resting pairs. With
--depth-only just those rows (about 2 s): run this script with another checkout's interpreter
(its meshcol) in alternation with this one's for an A/B of the core, e.g.
``for i in 1 2 3; do for py in ../main/.venv/bin/python .venv/bin/python; do $py
benchmarks/bench_mesh_query.py --depth-only; done; done``.

Coal (issue 32, item 3): ``--coal`` adds a peer column, coal's ``BVHModelOBBRSS`` (``pip
install coal``, in the ``bench`` extra), on a real-mesh family from the corpus (torus,
fandisk, teapot, ballA), each against a randomly turned copy posed apart (a gap of half its
extent), near (5%), touching (1e-4) and overlapping; distance and intersection, single pair,
each side timed in alternating windows with meshcol; then a batch (60 posed copies of the
torus, every near pair: coal and fcl collide-then-distance loops). ``--coal-only`` runs just
that family. Rows print coal/meshcol and fcl/meshcol.

For each corpus mesh pair: hierarchy build time, one distance query, one collision query (meshcol
answers both with mesh_distance_batch, which also tests containment; fcl needs fcl.distance and
fcl.collide), and a batch of many posed pairs. The collision query is timed three ways on
meshcol's side: mesh_intersects_batch on one pair with its verdict read (``.intersecting[0]``,
as fcl's side reads ``is_collision`` of a new CollisionResult), MeshSet.intersects (the
single-pair call, at the set's poses, as fcl's objects hold theirs), and MeshSet.intersects
with b's pose passed per call (fcl: setTransform, then collide). Both run single-threaded unless stated; the
distances are compared (fcl is exact for separated meshes).
"""

from __future__ import annotations

import argparse
import os
import time
from collections import defaultdict
from pathlib import Path

import fcl
import numpy as np
import trimesh

import meshcol
from meshcol.collision.mesh_query import (
    MeshSet,
    mesh_distance_batch,
    mesh_intersects_batch,
    mesh_penetration_depth_batch,
)

CORPUS = Path(__file__).resolve().parents[1].parent / "shared" / "corpus" / "trimesh-models"


RATIOS: dict[str, list[float]] = defaultdict(list)  # row -> fcl/meshcol of each run


def row(name: str, ours: float, theirs: float, label: str = "fcl") -> None:
    """Prints one timed row (seconds) and records its ratio for the summary."""
    RATIOS[name if label == "fcl" else f"{name} [{label}]"].append(theirs / ours)
    peer = label.split()[0]
    print(
        f"  {name.split(': ', 1)[-1]:<22} meshcol {ours * 1e3:8.4f} ms   {label} {theirs * 1e3:8.4f} ms   "
        f"{peer}/meshcol {theirs / ours:6.2f}"
    )


def loops_for(fn) -> int:
    """How many calls of `fn` take at least a millisecond (a lone sub-microsecond call times
    the clock, not the call)."""
    loops = 1
    while True:
        t = time.perf_counter()
        for _ in range(loops):
            fn()
        if time.perf_counter() - t >= 1e-3:
            return loops
        loops *= 4


def window(fn, loops: int) -> float:
    t = time.perf_counter()
    for _ in range(loops):
        fn()
    return (time.perf_counter() - t) / loops


def best_of(fn, repeat: int = 5) -> float:
    """Fastest of `repeat` runs, seconds a call; calls under a millisecond run in loops of
    at least a millisecond."""
    loops = loops_for(fn)
    return min(window(fn, loops) for _ in range(repeat))


def best_of_alternated(ours, theirs, repeat: int = 9) -> tuple[float, float]:
    """Fastest of `repeat` runs of each, seconds a call, the two timed in alternating windows
    of at least a millisecond: on a shared machine both sides then see the same moments of
    load (timed one after the other, a burst of load on one side alone moves the ratio)."""
    loops_ours, loops_theirs = loops_for(ours), loops_for(theirs)
    t_ours, t_theirs = [], []
    for _ in range(repeat):
        t_ours.append(window(ours, loops_ours))
        t_theirs.append(window(theirs, loops_theirs))
    return min(t_ours), min(t_theirs)


def fcl_model(mesh: trimesh.Trimesh):
    m = fcl.BVHModel()
    m.beginModel(len(mesh.vertices), len(mesh.faces))
    m.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    m.endModel()
    return m


def pose(rotation=None, translation=(0, 0, 0)) -> np.ndarray:
    p = np.eye(4)
    if rotation is not None:
        p[:3, :3] = rotation
    p[:3, 3] = translation
    return p


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def case(name: str, a: trimesh.Trimesh, b: trimesh.Trimesh, pb: np.ndarray) -> None:
    build_meshcol = best_of(lambda: MeshSet.from_arrays([a, b], threads=1), 3)
    build_fcl = best_of(lambda: (fcl_model(a), fcl_model(b)), 3)
    meshes = MeshSet.from_arrays([a, b], np.stack([np.eye(4), pb]), threads=1)
    ma, mb = fcl_model(a), fcl_model(b)
    oa = fcl.CollisionObject(ma, fcl.Transform())
    ob = fcl.CollisionObject(mb, fcl.Transform(pb[:3, :3], pb[:3, 3]))
    pairs = np.array([[0, 1]])

    def fcl_distance():
        return fcl.distance(
            oa, ob, fcl.DistanceRequest(enable_nearest_points=True), fcl.DistanceResult()
        )

    def fcl_collide():
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, fcl.CollisionRequest(), res)
        return res.is_collision

    pose_b = np.ascontiguousarray(pb)
    transform_b = fcl.Transform(pb[:3, :3], pb[:3, 3])

    def fcl_collide_posed():
        ob.setTransform(transform_b)
        return fcl_collide()

    r = mesh_distance_batch(meshes, None, pairs, threads=1)
    d_fcl, hit_fcl = fcl_distance(), fcl_collide()
    assert meshes.intersects(0, 1) == hit_fcl == meshes.intersects(0, 1, None, pose_b)
    t_ours, t_fcl = best_of_alternated(
        lambda: mesh_distance_batch(meshes, None, pairs, threads=1), fcl_distance
    )
    # what a user calls: the batch, then its verdict read (fcl's side reads is_collision)
    t_ours_hit, t_fcl_hit = best_of_alternated(
        lambda: mesh_intersects_batch(meshes, None, pairs, threads=1).intersecting[0], fcl_collide
    )
    t_ours_pair, t_fcl_pair = best_of_alternated(lambda: meshes.intersects(0, 1), fcl_collide)
    t_ours_posed, t_fcl_posed = best_of_alternated(
        lambda: meshes.intersects(0, 1, None, pose_b), fcl_collide_posed
    )
    agree = (bool(r.intersecting[0]) == hit_fcl) and (
        hit_fcl or abs(r.distance[0] - d_fcl) <= 1e-9 * d_fcl
    )
    print(
        f"{name}: {len(a.faces)} + {len(b.faces)} faces, distance {r.distance[0]:.6g} "
        f"(fcl {d_fcl:.6g}, intersecting {bool(r.intersecting[0])}/{hit_fcl}, agree {agree})"
    )
    row(f"{name}: build", build_meshcol, build_fcl)
    row(f"{name}: distance", t_ours, t_fcl)
    row(f"{name}: intersects (batch)", t_ours_hit, t_fcl_hit)
    row(f"{name}: intersects (pair)", t_ours_pair, t_fcl_pair)
    row(f"{name}: intersects (posed)", t_ours_posed, t_fcl_posed)


def batch_case(mesh: trimesh.Trimesh, count: int, rng) -> None:
    """`count` posed copies of one mesh in a loose cluster, all pairs whose world AABBs are
    within one extent (as a broad phase would hand over)."""
    extent = float(mesh.extents.max())
    poses = np.stack(
        [pose(random_rotation(rng), rng.uniform(0, 4 * extent, 3)) for _ in range(count)]
    )
    meshes = MeshSet.from_arrays([mesh] * count, poses)
    centres = poses[:, :3, 3]
    ii, jj = np.triu_indices(count, 1)
    near = np.linalg.norm(centres[ii] - centres[jj], axis=1) < 2 * extent
    pairs = np.c_[ii[near], jj[near]]
    model = fcl_model(mesh)
    objects = [fcl.CollisionObject(model, fcl.Transform(p[:3, :3], p[:3, 3])) for p in poses]

    def fcl_loop():
        out = np.empty(len(pairs))
        for k, (i, j) in enumerate(pairs):
            res = fcl.CollisionResult()
            fcl.collide(objects[i], objects[j], fcl.CollisionRequest(), res)
            out[k] = (
                0.0
                if res.is_collision
                else fcl.distance(
                    objects[i], objects[j], fcl.DistanceRequest(), fcl.DistanceResult()
                )
            )
        return out

    d_fcl = fcl_loop()
    r = mesh_distance_batch(meshes, None, pairs, threads=1)
    ok = np.isclose(r.distance, d_fcl, rtol=1e-9, atol=0)
    t1 = best_of(lambda: mesh_distance_batch(meshes, None, pairs, threads=1), 3)
    t2 = best_of(lambda: mesh_distance_batch(meshes, None, pairs, threads=0), 3)
    tf = best_of(fcl_loop, 2)
    print(
        f"batch: {count} posed copies of {len(mesh.faces)} faces, {len(pairs)} near pairs "
        f"({int(r.intersecting.sum())} intersecting), distances agree with fcl on {int(ok.sum())}/{len(pairs)}"
    )
    print(f"  meshcol all threads {t2 * 1e3:8.2f} ms")
    row("batch: 1 thread", t1, tf, "fcl collide+distance loop")


def depth_case(name: str, a: trimesh.Trimesh, b: trimesh.Trimesh, pb: np.ndarray) -> None:
    meshes = MeshSet.from_arrays([a, b], np.stack([np.eye(4), pb]), threads=1)
    pairs = np.array([[0, 1]])
    oa = fcl.CollisionObject(fcl_model(a), fcl.Transform())
    ob = fcl.CollisionObject(fcl_model(b), fcl.Transform(pb[:3, :3], pb[:3, 3]))

    def fcl_depth():
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, fcl.CollisionRequest(num_max_contacts=100000, enable_contact=True), res)
        return max((c.penetration_depth for c in res.contacts), default=0.0)

    r = mesh_penetration_depth_batch(meshes, None, pairs, threads=1)
    t_ours, t_fcl = best_of_alternated(
        lambda: mesh_penetration_depth_batch(meshes, None, pairs, threads=1), fcl_depth, 5
    )
    print(
        f"depth {name}: {len(a.faces)} + {len(b.faces)} faces, meshcol depth {r.depth[0]:.6g} "
        f"({int(r.points_tested[0])} exact inside tests), fcl deepest contact {fcl_depth():.6g}"
    )
    row(f"depth {name}: depth", t_ours, t_fcl, "fcl collide+contacts")


def coal_model(mesh: trimesh.Trimesh):
    import coal

    m = coal.BVHModelOBBRSS()
    m.beginModel(len(mesh.faces), len(mesh.vertices))
    m.addVertices(np.asarray(mesh.vertices, dtype=np.float64))
    m.addTriangles(np.asarray(mesh.faces, dtype=np.int64))
    m.endModel()
    return m


def coal_pair(name: str, mesh: trimesh.Trimesh, pb: np.ndarray) -> None:
    """One pair of the coal family: meshcol against coal and fcl, distance and intersects."""
    import coal

    meshes = MeshSet.from_arrays([mesh, mesh], np.stack([np.eye(4), pb]), threads=1)
    pairs = np.array([[0, 1]])
    model = coal_model(mesh)
    ta, tb = coal.Transform3s(), coal.Transform3s(pb[:3, :3].copy(), pb[:3, 3].copy())
    oa = fcl.CollisionObject(fcl_model(mesh), fcl.Transform())
    ob = fcl.CollisionObject(fcl_model(mesh), fcl.Transform(pb[:3, :3], pb[:3, 3]))

    def coal_distance():
        res = coal.DistanceResult()
        coal.distance(model, ta, model, tb, coal.DistanceRequest(), res)
        return res.min_distance

    def coal_collide():
        res = coal.CollisionResult()
        coal.collide(model, ta, model, tb, coal.CollisionRequest(), res)
        return res.isCollision()

    def fcl_distance():
        return fcl.distance(oa, ob, fcl.DistanceRequest(), fcl.DistanceResult())

    def fcl_collide():
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, fcl.CollisionRequest(), res)
        return res.is_collision

    def ours_distance():
        return mesh_distance_batch(meshes, None, pairs, threads=1)

    def ours_collide():
        return mesh_intersects_batch(meshes, None, pairs, threads=1).intersecting[0]

    r = ours_distance()
    print(
        f"{name}: {len(mesh.faces)} faces; meshcol distance {r.distance[0]:.6g} "
        f"(intersecting {bool(r.intersecting[0])}), coal {coal_distance():.6g} "
        f"(collide {coal_collide()}), fcl {fcl_distance():.6g} (collide {fcl_collide()})"
    )
    for query, ours, peers in (
        ("distance", ours_distance, (("coal", coal_distance), ("fcl", fcl_distance))),
        ("intersects", ours_collide, (("coal", coal_collide), ("fcl", fcl_collide))),
    ):
        for label, theirs in peers:
            t_ours, t_theirs = best_of_alternated(ours, theirs)
            row(f"{name}: {query}", t_ours, t_theirs, label)


def coal_batch(mesh: trimesh.Trimesh, count: int, rng) -> None:
    """``count`` posed copies in a loose cluster, every near pair: meshcol's batch (one
    thread) against coal's and fcl's collide-then-distance loops."""
    import coal

    extent = float(mesh.extents.max())
    poses = np.stack(
        [pose(random_rotation(rng), rng.uniform(0, 4 * extent, 3)) for _ in range(count)]
    )
    meshes = MeshSet.from_arrays([mesh] * count, poses)
    ii, jj = np.triu_indices(count, 1)
    near = np.linalg.norm(poses[ii, :3, 3] - poses[jj, :3, 3], axis=1) < 2 * extent
    pairs = np.c_[ii[near], jj[near]]
    model = coal_model(mesh)
    transforms = [coal.Transform3s(p[:3, :3].copy(), p[:3, 3].copy()) for p in poses]

    def coal_loop():
        out = np.empty(len(pairs))
        for k, (i, j) in enumerate(pairs.tolist()):
            res = coal.CollisionResult()
            coal.collide(model, transforms[i], model, transforms[j], coal.CollisionRequest(), res)
            if res.isCollision():
                out[k] = 0.0
                continue
            dres = coal.DistanceResult()
            coal.distance(model, transforms[i], model, transforms[j], coal.DistanceRequest(), dres)
            out[k] = dres.min_distance
        return out

    d_coal = coal_loop()
    r = mesh_distance_batch(meshes, None, pairs, threads=1)
    ok = np.isclose(r.distance, d_coal, rtol=1e-9, atol=1e-12)
    t1 = best_of(lambda: mesh_distance_batch(meshes, None, pairs, threads=1), 3)
    tc = best_of(coal_loop, 2)
    print(
        f"coal batch: {count} posed copies of {len(mesh.faces)} faces, {len(pairs)} near pairs, "
        f"distances agree with coal on {int(ok.sum())}/{len(pairs)}"
    )
    row("coal batch: 1 thread", t1, tc, "coal collide+distance loop")


def coal_rows() -> None:
    rng = np.random.default_rng(32)
    load = lambda name: trimesh.load(CORPUS / name, force="mesh")
    for file in ("torus.STL", "fandisk.obj", "teapot.stl", "ballA.off"):
        mesh = load(file)
        mesh.apply_translation(-mesh.bounds.mean(axis=0))
        e = float(mesh.extents.max())
        turn = random_rotation(rng)
        near = pose(turn, (1.05 * e, 0.0, 0.0))
        # touching: the near copy moved by its closest points' gap, so that they meet
        meshes = MeshSet.from_arrays([mesh, mesh], np.stack([np.eye(4), near]), threads=1)
        closest = mesh_distance_batch(meshes, None, np.array([[0, 1]]), threads=1)
        touching = near.copy()
        touching[:3, 3] += closest.point_a[0] - closest.point_b[0]
        for label, posed in (
            ("apart", pose(turn, (1.5 * e, 0.0, 0.0))),
            ("near", near),
            ("touching", touching),
            ("overlapping", pose(turn, (0.6 * e, 0.0, 0.0))),
        ):
            coal_pair(f"{file} {label}", mesh, posed)
    coal_batch(load("torus.STL"), 60, rng)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=1, help="repeat the whole set (ranges)")
    parser.add_argument("--depth-only", action="store_true", help="only the depth rows")
    parser.add_argument("--coal", action="store_true", help="the coal family too")
    parser.add_argument("--coal-only", action="store_true", help="only the coal family")
    args = parser.parse_args()
    print(f"meshcol from {Path(meshcol.__file__).resolve().parent}, load average {os.getloadavg()}")
    for run in range(args.runs):
        if args.runs > 1:
            print(f"== run {run + 1} of {args.runs}")
        if args.coal_only:
            coal_rows()
        elif args.depth_only:
            depth_rows()
        else:
            one_run()
            depth_rows()
            if args.coal:
                coal_rows()
    if args.runs > 1:
        print(f"\npeer/meshcol over {args.runs} runs (min-max):")
        for name, ratios in RATIOS.items():
            print(f"  {name:<60} {min(ratios):6.2f} - {max(ratios):6.2f}")


def one_run() -> None:
    rng = np.random.default_rng(1)
    load = lambda name: trimesh.load(CORPUS / name, force="mesh")
    torus, fandisk = load("torus.STL"), load("fandisk.obj")
    counter = load("counter.unitsmm.STL")
    ball_a, ball_b = load("ballA.off"), load("ballB.off")
    e = float(torus.extents[0])
    case(
        "torus vs translated torus (gap 5% of extent)",
        torus,
        torus,
        pose(translation=(1.05 * e, 0, 0)),
    )
    case(
        "torus vs rotated torus (near)",
        torus,
        torus,
        pose(random_rotation(rng), (0.9 * e, 0.3 * e, 0.1 * e)),
    )
    e = float(fandisk.extents[0])
    case(
        "fandisk vs rotated fandisk (near)",
        fandisk,
        fandisk,
        pose(random_rotation(rng), (1.1 * e, 0, 0)),
    )
    e = float(counter.extents[0])
    case("counter vs copy at a 1 mm gap", counter, counter, pose(translation=(e + 1.0, 0, 0)))
    case("ballA vs ballB (overlapping)", ball_a, ball_b, np.eye(4))
    batch_case(load("torus.STL"), 60, rng)


def depth_rows() -> None:
    load = lambda name: trimesh.load(CORPUS / name, force="mesh")
    torus = load("torus.STL")
    ball_a, ball_b = load("ballA.off"), load("ballB.off")
    depth_case("ballA vs ballB (overlapping)", ball_a, ball_b, np.eye(4))
    e = float(torus.extents[0])
    depth_case("torus vs copy moved 30%", torus, torus, pose(translation=(0.3 * e, 0.01 * e, 0)))
    floor = trimesh.creation.box(bounds=[[-3 * e, -3 * e, -e], [3 * e, 3 * e, 0]])
    for _ in range(5):
        floor = floor.subdivide()
    depth_case(
        "torus resting on a 12,288-face floor",
        floor,
        torus,
        pose(translation=(0, 0, -float(torus.bounds[0][2]))),
    )


if __name__ == "__main__":
    main()
