"""Exact mesh-mesh queries: meshcol (MeshSet + mesh_distance_batch) vs coal BVHModelOBBRSS and
python-fcl BVHModel.

Run: .venv/bin/python benchmarks/bench_mesh_query.py [--runs 3] [--family-only]

coal (``pip install coal``, the ``bench`` extra) is a peer column when installed; without it
its columns are left out. Each peer is called from a Python loop, one call a pair, with its
geometry built once per mesh and its request objects reused (a result is cleared before each
call: coal and fcl keep the smaller distance of an uncleared result). With --runs N the whole
set runs N times and a summary gives each row's peer/meshcol ratio as a range over the runs.
The single-pair rows (distance, intersects) time meshcol and the peers in alternating windows
of at least a millisecond, best of 9 each, so that all sides see the same load on a shared
machine; the windows are timed in this process's CPU time (``MESHCOL_BENCH_CLOCK=wall`` for
wall time), which other processes inflate far less than wall time.

The real-mesh family (``family_rows``; alone with --family-only): for each of four corpus
meshes, 300 pairs of posed copies (random rotations, b moved along a random direction from
a's centre), in three configurations placed by bisection on the contact offset: ``near``
(gaps of 1-5% of the mesh's extent along the direction), ``touching`` (0-2% into each other:
the surfaces cross) and ``apart`` (30-100% of the extent). Per configuration: the distance
batch (meshcol one call on 300 pairs; the peers a loop of distance calls), the same as a loop
of one-pair meshcol calls, and the intersects batch (peers: collide); on ``touching`` also
the penetration depth batch (peers: collide with contacts, the deepest contact). Every row is
checked: distances agree with coal's to 1e-9 (relative) where the meshes are apart, and the
intersects verdicts agree with both peers.

Then the mesh penetration depth (mesh_penetration_depth_batch) against fcl.collide with
contacts (the deepest contact's penetration_depth), on overlapping and resting pairs. These
rows are NOT like for like (DEPTH_MEANING, printed with them): meshcol computes a bound of the
meshes' true penetration depth (the deepest sampled point of one mesh inside the other solid,
measured to the other surface: at most the minimum translation that separates closed meshes),
with a winding-number inside test per region of points; coal and fcl enumerate every crossing
triangle pair and report the deepest pair's own penetration (a local quantity of two
triangles: neither a bound of the meshes' depth nor zero for a resting contact). meshcol has
no query that gives the peers' quantity, so no like-for-like depth row exists; each depth row
prints both medians so the difference shows. coal signs a penetration negative: its depth is
read as the largest |penetration_depth| of the contacts. Beside each depth row (the single
ones and the family's), a like-for-like row (CONTACT_MEANING): mesh_contacts_batch with every
contact listed against the same collide with contacts; its answers are checked against coal's
in the run (the number of crossing triangle pairs, and the deepest contact: face_depth, the
per-pair quantity coal 3.0.3 reports, how far b's triangle reaches behind a's face along
a's normal; meshcol's own depth, the pair's minimum translation, is printed beside it). With
--depth-only just those rows and the family's depth rows (about 10 s): run this script with another checkout's interpreter
(its meshcol) in alternation with this one's for an A/B of the core, e.g.
``for i in 1 2 3; do for py in ../main/.venv/bin/python .venv/bin/python; do $py
benchmarks/bench_mesh_query.py --depth-only; done; done``.

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

try:
    import coal
except ImportError:  # an optional peer: its columns are left out
    coal = None

import meshcol
from meshcol.collision.mesh_query import (
    MeshSet,
    mesh_distance_batch,
    mesh_intersects_batch,
    mesh_penetration_depth_batch,
)

try:
    from meshcol.collision.contacts import mesh_contacts_batch
except ImportError:  # an older meshcol (an A/B run under another checkout): no contact rows
    mesh_contacts_batch = None

CORPUS = Path(__file__).resolve().parents[1].parent / "shared" / "corpus"
MODELS = CORPUS / "trimesh-models"
# The real-mesh family: closed corpus meshes of the sizes assets are made of.
FAMILY = (
    ("fandisk", MODELS / "fandisk.obj"),
    (
        "solo lower leg",
        CORPUS / "robots/solo_description/meshes/stl/with_foot/solo_lower_leg_left_side.stl",
    ),
    ("idler riser", MODELS / "idler_riser.STL"),
    ("panda link3", CORPUS / "robots/panda_description/meshes/collision/link3.stl"),
)

RATIOS: dict[tuple[str, str], list[float]] = defaultdict(list)  # (row, peer) -> peer/meshcol

# What the depth rows compare: two different quantities (see the module docstring).
DEPTH_MEANING = (
    "depth rows are not like for like: meshcol = the meshes' penetration depth (deepest "
    "sampled point inside the other solid, to its surface; a lower bound of the separating "
    "translation), coal/fcl = the deepest crossing triangle pair's own penetration (a local "
    "contact quantity)"
)
# What the contact rows compare: the same quantity (see the module docstring).
CONTACT_MEANING = (
    "contact depth rows are like for like: every crossing triangle pair listed with its own "
    "depth, as coal's collide with contacts; the deepest is mesh_contacts_batch's face_depth "
    "(how far b's triangle reaches behind a's face along a's normal, coal 3.0.3's per-pair "
    "penetration_depth), checked against coal's deepest contact and count in the run"
)


def row(name: str, ours: float, peers: dict[str, float]) -> None:
    """Prints one timed row (seconds a call) and records each peer's ratio for the summary."""
    cells = []
    for peer, theirs in peers.items():
        RATIOS[(name, peer)].append(theirs / ours)
        cells.append(f"{peer} {theirs * 1e3:9.4f} ms (x{theirs / ours:5.2f})")
    print(f"  {name.split(': ', 1)[-1]:<24} meshcol {ours * 1e3:9.4f} ms   " + "   ".join(cells))


# The clock of every timed window: this process's CPU time (every call here runs on one
# thread), which the other processes of a loaded machine do not inflate the way they inflate
# wall time. MESHCOL_BENCH_CLOCK=wall times wall-clock instead.
clock = time.perf_counter if os.environ.get("MESHCOL_BENCH_CLOCK") == "wall" else time.process_time


def loops_for(fn) -> int:
    """How many calls of `fn` take at least a millisecond (a lone sub-microsecond call times
    the clock, not the call)."""
    loops = 1
    while True:
        t = clock()
        for _ in range(loops):
            fn()
        if clock() - t >= 1e-3:
            return loops
        loops *= 4


def window(fn, loops: int) -> float:
    t = clock()
    for _ in range(loops):
        fn()
    return (clock() - t) / loops


def best_of(fn, repeat: int = 5) -> float:
    """Fastest of `repeat` runs, seconds a call; calls under a millisecond run in loops of
    at least a millisecond."""
    loops = loops_for(fn)
    return min(window(fn, loops) for _ in range(repeat))


def best_of_alternated(*fns, repeat: int = 9) -> list[float]:
    """Fastest of `repeat` runs of each, seconds a call, the functions timed in turn in
    windows of at least a millisecond: on a shared machine all sides then see the same moments
    of load (timed one after the other, a burst of load on one side alone moves the ratio)."""
    loops = [loops_for(fn) for fn in fns]
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for fn, n, t in zip(fns, loops, times):
            t.append(window(fn, n))
    return [min(t) for t in times]


def peers_of(t_fcl: float, t_coal: float | None) -> dict[str, float]:
    """The peer columns of one row: coal first when installed."""
    return ({"coal": t_coal} if t_coal is not None else {}) | {"fcl": t_fcl}


def fcl_model(mesh: trimesh.Trimesh):
    m = fcl.BVHModel()
    m.beginModel(len(mesh.vertices), len(mesh.faces))
    m.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
    m.endModel()
    return m


def coal_model(mesh: trimesh.Trimesh):
    """coal's BVHModelOBBRSS of one mesh (its fastest hierarchy for distance)."""
    m = coal.BVHModelOBBRSS()
    m.beginModel(len(mesh.faces), len(mesh.vertices))
    m.addVertices(np.asarray(mesh.vertices, float))
    m.addTriangles(np.asarray(mesh.faces, np.int64))
    m.endModel()
    return m


def coal_transform(p: np.ndarray):
    return coal.Transform3s(np.ascontiguousarray(p[:3, :3]), np.ascontiguousarray(p[:3, 3]))


class CoalPair:
    """One pair's coal geometry and transforms, with request and result objects reused."""

    def __init__(self, ma, mb, pa: np.ndarray, pb: np.ndarray) -> None:
        self.ma, self.mb = ma, mb
        self.ta, self.tb = coal_transform(pa), coal_transform(pb)
        self.dreq, self.dres = coal.DistanceRequest(), coal.DistanceResult()
        self.creq, self.cres = coal.CollisionRequest(), coal.CollisionResult()

    def distance(self) -> float:
        self.dres.clear()
        return coal.distance(self.ma, self.ta, self.mb, self.tb, self.dreq, self.dres)

    def collide(self) -> bool:
        self.cres.clear()
        return coal.collide(self.ma, self.ta, self.mb, self.tb, self.creq, self.cres) > 0


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
    build_coal = best_of(lambda: (coal_model(a), coal_model(b)), 3) if coal else None
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
    fns_d = [lambda: mesh_distance_batch(meshes, None, pairs, threads=1), fcl_distance]
    # what a user calls: the batch, then its verdict read (fcl's side reads is_collision)
    fns_hit = [
        lambda: mesh_intersects_batch(meshes, None, pairs, threads=1).intersecting[0],
        fcl_collide,
    ]
    fns_pair = [lambda: meshes.intersects(0, 1), fcl_collide]
    fns_posed = [lambda: meshes.intersects(0, 1, None, pose_b), fcl_collide_posed]
    d_coal = None
    if coal:
        cp = CoalPair(coal_model(a), coal_model(b), np.eye(4), pb)
        d_coal = cp.distance()
        assert cp.collide() == hit_fcl
        coal_tb = coal_transform(pb)

        def coal_collide_posed():
            cp.tb = coal_tb  # coal takes the transform per call: the pose is passed
            return cp.collide()

        for fns, extra in (
            (fns_d, cp.distance),
            (fns_hit, cp.collide),
            (fns_pair, cp.collide),
            (fns_posed, coal_collide_posed),
        ):
            fns.append(extra)
    times = [best_of_alternated(*fns) for fns in (fns_d, fns_hit, fns_pair, fns_posed)]
    agree = (bool(r.intersecting[0]) == hit_fcl) and (
        hit_fcl or abs(r.distance[0] - d_fcl) <= 1e-9 * d_fcl
    )
    if d_coal is not None:
        agree = agree and (hit_fcl or abs(r.distance[0] - d_coal) <= 1e-9 * d_coal)
    print(
        f"{name}: {len(a.faces)} + {len(b.faces)} faces, distance {r.distance[0]:.6g} "
        f"(fcl {d_fcl:.6g}, coal {d_coal if d_coal is None else f'{d_coal:.6g}'}, "
        f"intersecting {bool(r.intersecting[0])}/{hit_fcl}, agree {agree})"
    )
    row(f"{name}: build", build_meshcol, peers_of(build_fcl, build_coal))
    for label, t in zip(
        ("distance", "intersects (batch)", "intersects (pair)", "intersects (posed)"), times
    ):
        row(f"{name}: {label}", t[0], peers_of(t[1], t[2] if coal else None))


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

    def coal_loop():
        cm = coal_models[0]
        out = np.empty(len(pairs))
        for k, (i, j) in enumerate(pairs):
            cres.clear()
            if coal.collide(cm, transforms[i], cm, transforms[j], creq, cres):
                out[k] = 0.0
            else:
                dres.clear()
                out[k] = coal.distance(cm, transforms[i], cm, transforms[j], dreq, dres)
        return out

    d_fcl = fcl_loop()
    r = mesh_distance_batch(meshes, None, pairs, threads=1)
    ok = np.isclose(r.distance, d_fcl, rtol=1e-9, atol=0)
    t1 = best_of(lambda: mesh_distance_batch(meshes, None, pairs, threads=1), 3)
    t2 = best_of(lambda: mesh_distance_batch(meshes, None, pairs, threads=0), 3)
    tf = best_of(fcl_loop, 2)
    tc = None
    agree_coal = ""
    if coal:
        coal_models = [coal_model(mesh)]
        transforms = [coal_transform(p) for p in poses]
        creq, cres = coal.CollisionRequest(), coal.CollisionResult()
        dreq, dres = coal.DistanceRequest(), coal.DistanceResult()
        ok_coal = np.isclose(r.distance, coal_loop(), rtol=1e-9, atol=0)
        agree_coal = f", with coal on {int(ok_coal.sum())}/{len(pairs)}"
        tc = best_of(coal_loop, 2)
    print(
        f"batch: {count} posed copies of {len(mesh.faces)} faces, {len(pairs)} near pairs "
        f"({int(r.intersecting.sum())} intersecting), distances agree with fcl on "
        f"{int(ok.sum())}/{len(pairs)}{agree_coal}"
    )
    print(f"  meshcol all threads {t2 * 1e3:8.2f} ms")
    row("batch: 1 thread (peers: collide, then distance)", t1, peers_of(tf, tc))


def depth_case(name: str, a: trimesh.Trimesh, b: trimesh.Trimesh, pb: np.ndarray) -> None:
    meshes = MeshSet.from_arrays([a, b], np.stack([np.eye(4), pb]), threads=1)
    pairs = np.array([[0, 1]])
    oa = fcl.CollisionObject(fcl_model(a), fcl.Transform())
    ob = fcl.CollisionObject(fcl_model(b), fcl.Transform(pb[:3, :3], pb[:3, 3]))

    def fcl_depth():
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, fcl.CollisionRequest(num_max_contacts=100000, enable_contact=True), res)
        return max((c.penetration_depth for c in res.contacts), default=0.0)

    fns = [lambda: mesh_penetration_depth_batch(meshes, None, pairs, threads=1), fcl_depth]
    coal_text = ""
    if coal:
        cp = CoalPair(coal_model(a), coal_model(b), np.eye(4), pb)
        cp.creq = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 100000)

        def coal_depth():
            cp.collide()
            return max((abs(c.penetration_depth) for c in cp.cres.getContacts()), default=0.0)

        fns.append(coal_depth)
        coal_text = f", coal deepest contact {coal_depth():.6g}"
    r = mesh_penetration_depth_batch(meshes, None, pairs, threads=1)
    times = best_of_alternated(*fns, repeat=5)
    print(
        f"depth {name}: {len(a.faces)} + {len(b.faces)} faces, meshcol depth {r.depth[0]:.6g} "
        f"({int(r.points_tested[0])} exact inside tests), fcl deepest contact {fcl_depth():.6g}"
        f"{coal_text}"
    )
    row(
        f"depth {name}: depth, not like for like (peers: collide+contacts)",
        times[0],
        peers_of(times[1], times[2] if coal else None),
    )
    if mesh_contacts_batch is not None:
        contact_case(name, meshes, pairs, oa, ob, cp if coal else None)


def contact_case(name, meshes, pairs, oa, ob, cp) -> None:
    """The like-for-like row of one depth case: meshcol's contacts (every crossing pair
    listed, as the peers' contacts are) against collide with contacts, answers checked
    against coal's: the count of crossing pairs and the deepest contact's depth."""
    fcl_req = fcl.CollisionRequest(num_max_contacts=100000, enable_contact=True)

    def ours():
        return mesh_contacts_batch(meshes, None, pairs, max_contacts=100000, threads=1)

    def fcl_contacts():
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, fcl_req, res)
        return res.contacts

    fns = [ours, fcl_contacts]
    r = ours()
    check = ""
    if cp is not None:

        def coal_contacts():
            cp.collide()
            return cp.cres.getContacts()

        fns.append(coal_contacts)
        theirs = coal_contacts()
        deepest = max((abs(c.penetration_depth) for c in theirs), default=0.0)
        same = abs(r.face_depth[0] - deepest) <= 1e-9 * max(deepest, 1e-300)
        check = (
            f", coal {len(theirs)} pairs, deepest {deepest:.9g} "
            f"({'agrees' if same else 'DISAGREES'})"
        )
    times = best_of_alternated(*fns, repeat=5)
    # fcl lists a contact for each point where two triangles cross (up to two a pair), so
    # its contacts are counted with the triangle pairs they come from
    listed = fcl_contacts()
    fcl_pairs = {(c.b1, c.b2) for c in listed}
    same_pairs = fcl_pairs == set(zip(r.contact_triangle_a.tolist(), r.contact_triangle_b.tolist()))
    print(
        f"contacts {name}: meshcol {int(r.count[0])} crossing pairs, deepest "
        f"{r.face_depth[0]:.9g} (minimum translation {r.depth[0]:.6g}), fcl "
        f"{len(listed)} contacts in {len(fcl_pairs)} pairs "
        f"({'the same pairs' if same_pairs else 'OTHER PAIRS'}){check}"
    )
    row(
        f"depth {name}: contact depth (like for like)",
        times[0],
        peers_of(times[1], times[2] if cp is not None else None),
    )


def centred(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A copy with its box centre at the origin (the copies are moved from their centres)."""
    out = mesh.copy()
    out.apply_translation(-mesh.bounds.mean(axis=0))
    return out


def contact_offsets(mesh: trimesh.Trimesh, rotations: np.ndarray, directions: np.ndarray):
    """For each pair (a at rotations[k, 0] about the origin, b at rotations[k, 1] moved by
    s * directions[k]): the smallest s > 0 beyond which the two never meet, approached from
    outside by conservative advancement (moving b by less than the distance cannot make the
    surfaces meet), to within 1e-7 of the extent."""
    count = len(rotations)
    reach = float(np.linalg.norm(mesh.vertices, axis=1).max())
    extent = float(mesh.extents.max())
    s = np.full(count, 2.0 * reach * 1.01)
    poses = np.tile(np.eye(4), (2 * count, 1, 1))
    poses[0::2, :3, :3] = rotations[:, 0]
    poses[1::2, :3, :3] = rotations[:, 1]
    meshes = MeshSet.from_arrays([mesh] * (2 * count), poses.copy(), threads=0)
    pairs = np.arange(2 * count, dtype=np.int64).reshape(count, 2)
    todo = np.arange(count)
    for _ in range(200):
        poses[1::2, :3, 3] = s[:, None] * directions
        d = mesh_distance_batch(meshes, poses, pairs[todo], threads=0).distance
        assert np.all(d > 0), "conservative advancement reached a contact"
        s[todo] -= d
        todo = todo[d > 1e-7 * extent]
        if len(todo) == 0:
            break
    return s, extent


def family_sets(mesh: trimesh.Trimesh, count: int, rng):
    """The three configurations of one mesh: name -> (count, 2, 4, 4) poses."""
    rotations = np.stack(
        [np.stack([random_rotation(rng), random_rotation(rng)]) for _ in range(count)]
    )
    directions = rng.normal(size=(count, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    s, extent = contact_offsets(mesh, rotations, directions)
    out = {}
    for config, lo, hi in (("near", 0.01, 0.05), ("touching", -0.02, -0.002), ("apart", 0.3, 1.0)):
        offset = s + rng.uniform(lo, hi, count) * extent
        poses = np.tile(np.eye(4), (count, 2, 1, 1))
        poses[:, :, :3, :3] = rotations
        poses[:, 1, :3, 3] = offset[:, None] * directions
        out[config] = poses
    return out


def family_config(name: str, mesh: trimesh.Trimesh, config: str, pair_poses: np.ndarray) -> None:
    """The rows of one mesh in one configuration: 300 pairs, the same for every library."""
    count = len(pair_poses)
    flat = np.ascontiguousarray(pair_poses.reshape(2 * count, 4, 4))
    meshes = MeshSet.from_arrays([mesh] * (2 * count), flat, threads=1)
    pairs = np.arange(2 * count, dtype=np.int64).reshape(count, 2)
    one_pair = [np.ascontiguousarray(pairs[k : k + 1]) for k in range(count)]
    model = fcl_model(mesh)
    objects = [fcl.CollisionObject(model, fcl.Transform(p[:3, :3], p[:3, 3])) for p in flat]
    fcl_dreq, fcl_creq = fcl.DistanceRequest(), fcl.CollisionRequest()

    def fcl_distances():
        return [
            fcl.distance(objects[i], objects[j], fcl_dreq, fcl.DistanceResult())
            for i, j in pairs.tolist()
        ]

    def fcl_collides():
        out = []
        for i, j in pairs.tolist():
            res = fcl.CollisionResult()
            fcl.collide(objects[i], objects[j], fcl_creq, res)
            out.append(res.is_collision)
        return out

    def ours_pair_distances():
        return [mesh_distance_batch(meshes, None, p, threads=1).distance[0] for p in one_pair]

    def ours_pair_intersects():
        return [meshes.intersects(i, j) for i, j in pairs.tolist()]

    r = mesh_distance_batch(meshes, None, pairs, threads=1)
    hit = mesh_intersects_batch(meshes, None, pairs, threads=1).intersecting
    assert np.array_equal(hit, r.intersecting)
    assert np.array_equal(hit, np.array(fcl_collides())), "intersects disagree with fcl"
    rows = {
        "distance (batch)": [
            lambda: mesh_distance_batch(meshes, None, pairs, threads=1),
            fcl_distances,
        ],
        "distance (pair loop)": [ours_pair_distances, fcl_distances],
        "intersects (batch)": [
            lambda: mesh_intersects_batch(meshes, None, pairs, threads=1),
            fcl_collides,
        ],
        "intersects (pair loop)": [ours_pair_intersects, fcl_collides],
    }
    agree = ""
    if coal:
        cm = coal_model(mesh)
        tfs = [coal_transform(p) for p in flat]
        dreq, dres = coal.DistanceRequest(), coal.DistanceResult()
        creq, cres = coal.CollisionRequest(), coal.CollisionResult()

        def coal_distances():
            out = []
            for i, j in pairs.tolist():
                dres.clear()
                out.append(coal.distance(cm, tfs[i], cm, tfs[j], dreq, dres))
            return out

        def coal_collides():
            out = []
            for i, j in pairs.tolist():
                cres.clear()
                out.append(coal.collide(cm, tfs[i], cm, tfs[j], creq, cres) > 0)
            return out

        assert np.array_equal(hit, np.array(coal_collides())), "intersects disagree with coal"
        d_coal = np.array(coal_distances())
        apart = ~hit
        close = np.abs(r.distance[apart] - d_coal[apart]) <= 1e-9 * d_coal[apart]
        agree = f", distances agree with coal's on {int(close.sum())}/{int(apart.sum())} apart"
        for key, fn in zip(rows, (coal_distances, coal_distances, coal_collides, coal_collides)):
            rows[key].append(fn)
    print(
        f"{name} ({len(mesh.faces)} faces), {config}: {count} pairs, {int(hit.sum())} "
        f"intersecting, distance {np.median(r.distance):.4g} median of "
        f"{float(mesh.extents.max()):.4g} extent{agree}"
    )
    for key, fns in rows.items():
        times = best_of_alternated(*fns, repeat=3)
        row(
            f"{name} {config}: {key}",
            times[0] / count,
            peers_of(times[1] / count, times[2] / count if coal else None),
        )
    if config == "touching":
        family_depth(name, mesh, meshes, pairs, flat, objects)


def family_depth(name, mesh, meshes, pairs, flat, objects) -> None:
    """The depth row of the touching configuration (peers: collide with contacts, the deepest
    contact's depth, per pair)."""
    count = len(pairs)
    fcl_req = fcl.CollisionRequest(num_max_contacts=100000, enable_contact=True)

    def fcl_depths():
        out = []
        for i, j in pairs.tolist():
            res = fcl.CollisionResult()
            fcl.collide(objects[i], objects[j], fcl_req, res)
            out.append(max((c.penetration_depth for c in res.contacts), default=0.0))
        return out

    fns = [lambda: mesh_penetration_depth_batch(meshes, None, pairs, threads=1), fcl_depths]
    if coal:
        cm = coal_model(mesh)
        tfs = [coal_transform(p) for p in flat]
        creq = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 100000)
        cres = coal.CollisionResult()

        def coal_depths():
            out = []
            for i, j in pairs.tolist():
                cres.clear()
                coal.collide(cm, tfs[i], cm, tfs[j], creq, cres)
                out.append(max((abs(c.penetration_depth) for c in cres.getContacts()), default=0.0))
            return out

        fns.append(coal_depths)
    times = best_of_alternated(*fns, repeat=3)
    ours = mesh_penetration_depth_batch(meshes, None, pairs, threads=1).depth
    theirs = fns[2]() if coal else fns[1]()
    print(
        f"  depth, not like for like: meshcol mesh depth median {np.median(ours):.4g} "
        f"(max {np.max(ours):.4g}), {'coal' if coal else 'fcl'} deepest triangle-pair contact "
        f"median {np.median(theirs):.4g} (max {np.max(theirs):.4g})"
    )
    row(
        f"{name} touching: depth, not like for like (batch; peers: contacts)",
        times[0] / count,
        peers_of(times[1] / count, times[2] / count if coal else None),
    )
    if mesh_contacts_batch is not None:
        family_contacts(name, mesh, meshes, pairs, flat, objects)


def family_contacts(name, mesh, meshes, pairs, flat, objects) -> None:
    """The like-for-like contact row of the touching configuration: meshcol's contacts batch
    (every crossing pair listed) against collide with contacts per pair, the count and the
    deepest of every pair checked against coal's."""
    count = len(pairs)
    fcl_req = fcl.CollisionRequest(num_max_contacts=100000, enable_contact=True)

    def ours():
        return mesh_contacts_batch(meshes, None, pairs, max_contacts=100000, threads=1)

    def fcl_contacts():
        out = []
        for i, j in pairs.tolist():
            res = fcl.CollisionResult()
            fcl.collide(objects[i], objects[j], fcl_req, res)
            out.append(res.contacts)
        return out

    fns = [ours, fcl_contacts]
    r = ours()
    check = ""
    if coal:
        cm = coal_model(mesh)
        tfs = [coal_transform(p) for p in flat]
        creq = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 100000)
        cres = coal.CollisionResult()

        def coal_contacts():
            out = []
            for i, j in pairs.tolist():
                cres.clear()
                coal.collide(cm, tfs[i], cm, tfs[j], creq, cres)
                out.append(cres.getContacts())
            return out

        fns.append(coal_contacts)
        # read each pair's contacts before the next clear() (the list is the result's own)
        counts, deepest = np.zeros(count, dtype=np.int64), np.zeros(count)
        for k, (i, j) in enumerate(pairs.tolist()):
            cres.clear()
            coal.collide(cm, tfs[i], cm, tfs[j], creq, cres)
            contacts = cres.getContacts()
            counts[k] = len(contacts)
            deepest[k] = max((abs(c.penetration_depth) for c in contacts), default=0.0)
        same = np.abs(r.face_depth - deepest) <= 1e-9 * np.maximum(deepest, 1e-300)
        check = (
            f"; with coal: counts equal on {int((counts == r.count).sum())}/{count} (coal "
            f"{int((counts - r.count).sum())} more in all), deepest agrees on "
            f"{int(same.sum())}/{count}"
        )
    times = best_of_alternated(*fns, repeat=3)
    print(
        f"  contacts, like for like: meshcol {int(r.count.sum())} crossing pairs over {count} "
        f"pairs{check}"
    )
    row(
        f"{name} touching: contact depth (like for like; batch)",
        times[0] / count,
        peers_of(times[1] / count, times[2] / count if coal else None),
    )


def family_rows(count: int = 300, depth_only: bool = False) -> None:
    """Every row of the family, or (depth_only) only the depth row of each touching set."""
    print(DEPTH_MEANING)
    print(CONTACT_MEANING)
    rng = np.random.default_rng(7)
    for name, path in FAMILY:
        if not path.exists():
            print(f"{name}: {path} missing, skipped")
            continue
        mesh = centred(trimesh.load(path, force="mesh"))
        for config, pair_poses in family_sets(mesh, count, rng).items():
            if not depth_only:
                family_config(name, mesh, config, pair_poses)
            elif config == "touching":
                flat = np.ascontiguousarray(pair_poses.reshape(-1, 4, 4))
                meshes = MeshSet.from_arrays([mesh] * len(flat), flat, threads=1)
                pairs = np.arange(len(flat), dtype=np.int64).reshape(-1, 2)
                model = fcl_model(mesh)
                objects = [
                    fcl.CollisionObject(model, fcl.Transform(p[:3, :3], p[:3, 3])) for p in flat
                ]
                family_depth(name, mesh, meshes, pairs, flat, objects)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=1, help="repeat the whole set (ranges)")
    parser.add_argument(
        "--depth-only", action="store_true", help="only the depth rows (with the family's)"
    )
    parser.add_argument("--family-only", action="store_true", help="only the real-mesh family")
    parser.add_argument("--pairs", type=int, default=300, help="pairs a family configuration")
    args = parser.parse_args()
    print(
        f"meshcol from {Path(meshcol.__file__).resolve().parent}, "
        f"coal {getattr(coal, '__version__', 'not installed')}, "
        f"load average {os.getloadavg()}"
    )
    for run in range(args.runs):
        if args.runs > 1:
            print(f"== run {run + 1} of {args.runs}")
        if not args.family_only:
            if not args.depth_only:
                one_run()
            depth_rows()
        family_rows(args.pairs, depth_only=args.depth_only)
    if args.runs > 1:
        print(f"\npeer/meshcol over {args.runs} runs (min-max):")
        for (name, peer), ratios in RATIOS.items():
            print(f"  {name:<64} {peer:<5} {min(ratios):6.2f} - {max(ratios):6.2f}")


def one_run() -> None:
    rng = np.random.default_rng(1)
    load = lambda name: trimesh.load(MODELS / name, force="mesh")
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


def single_depth_rows() -> dict[str, tuple[trimesh.Trimesh, trimesh.Trimesh, np.ndarray]]:
    """The four single-pair depth rows: name -> (mesh a, mesh b, b's pose; a at the origin).
    Shared with depth_identity.py and mesh_query_driver/dump_depth_rows.py. The first three
    pairs have equal rotations (b only moved), a case the contacts query descends by
    axis-aligned boxes; the turned torus is the same dense overlap with b turned 20 degrees
    about an oblique axis through its centre, which takes the oriented descent."""
    load = lambda name: trimesh.load(MODELS / name, force="mesh")
    torus = load("torus.STL")
    e = float(torus.extents[0])
    floor = trimesh.creation.box(bounds=[[-3 * e, -3 * e, -e], [3 * e, 3 * e, 0]])
    for _ in range(5):
        floor = floor.subdivide()
    return {
        "ballA vs ballB (overlapping)": (load("ballA.off"), load("ballB.off"), np.eye(4)),
        "torus vs copy moved 30%": (torus, torus, pose(translation=(0.3 * e, 0.01 * e, 0))),
        "torus resting on a 12,288-face floor": (
            floor,
            torus,
            pose(translation=(0, 0, -float(torus.bounds[0][2]))),
        ),
        "torus vs turned copy moved 30%": (
            torus,
            torus,
            pose(
                trimesh.transformations.rotation_matrix(np.radians(20.0), [1.0, 2.0, 3.0])[:3, :3],
                (0.3 * e, 0.01 * e, 0),
            ),
        ),
    }


def depth_rows() -> None:
    print(DEPTH_MEANING)
    print(CONTACT_MEANING)
    for name, (a, b, pose_b) in single_depth_rows().items():
        depth_case(name, a, b, pose_b)


if __name__ == "__main__":
    main()
