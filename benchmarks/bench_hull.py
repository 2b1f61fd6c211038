"""Benchmark: packing convex hulls for the narrow phase, the core's Quickhull vs qhull.

``new`` is `ConvexSet.from_vertices` (every hull, its adjacency, face normals and edge
directions in one threaded native call). ``qhull`` is the packing meshcol had before issue 14,
kept here only to compare: per shape, qhull through scipy (`ConvexHull`), then
`np.unique`-style grouping of face normals and edge directions and the adjacency lists in
numpy (a copy of that code path for 3-D hulls, which is what these inputs are).

Cases: smooth hulls (issue 32): points on random ellipsoids (semi-axes 0.5-1.5, randomly
turned), every point a hull vertex, as decomposition parts, UCX parts and fitted capsules
are: 64 points a shape (``--shapes`` of them), 256 and 1,024 (the same number of points in
all: a quarter and a sixteenth as many shapes), from one (H, n, 3) array and from a list;
40,000 clouds of 64 Gaussian points (about 25 on the hull) (the old path is timed on ``--old-shapes`` of them
and reported per shape: 40,000 took 73.6 s); a UV sphere of 2 million triangles (708 x 708:
one hull of about a million vertices); and `check_scene` end to end on that sphere beside a
cube. Wall and CPU times are printed: on a shared machine the wall time includes waiting.

Peers, on the smooth hulls (``--sizes``, 16 to 1,024 points) and the clouds, one shape at a
time in the same run: qhull through scipy (`ConvexHull`: the hull alone), trimesh
(`trimesh.convex.convex_hull`: qhull plus its mesh) and coal (`coal.Convex.convexHull`,
qhull inside), each where installed; ratios are the peer's CPU time a shape over meshcol's
single-threaded one (`pack_hulls(..., threads=1)`: hulls, adjacency and SAT features).

A/B against another build (issue 32): ``--baseline OTHER_PYTHON`` runs the single-threaded
rows in a child process of each interpreter, alternated ``--rounds`` times, and prints CPU
ranges and whether the packed arrays of both builds are byte-identical on every family
(smooth hulls, clouds, and degenerate sets: 1e-12 noise on a sphere, lattice points with
coplanar faces, duplicates, a flat set, huge and tiny coordinates). The peers are timed in the
new build's child of every round on the first ``--peer-shapes`` shapes of the timed rows (0:
none), so their ratios come from the same runs.

Run:  .venv/bin/python benchmarks/bench_hull.py [--shapes 40000] [--old-shapes 2000]
      [--sphere-count 708] [--skip-old-mesh] [--sizes 16 64 256 1024] [--only-on-hull]
      [--peer-shapes 2000] [--baseline /work/base/.venv/bin/python --rounds 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import subprocess
import sys
import time

import numpy as np

# ---------------------------------------------------------------------------------------
# the packing before issue 14 (qhull through scipy, numpy per shape), for comparison only


def _legacy_unique_directions(d: np.ndarray, signed: bool) -> np.ndarray:
    d = d / np.linalg.norm(d, axis=1)[:, None]
    if not signed:
        key = np.where(np.abs(d) > 1e-12, d, 0.0)
        first = np.argmax(key != 0.0, axis=1)
        sign = np.sign(key[np.arange(len(d)), first])
        d = d * np.where(sign == 0.0, 1.0, sign)[:, None]
    keys = np.round(d, 12)
    order = np.lexsort(keys.T[::-1])
    ordered = keys[order]
    start = np.ones(len(order), dtype=bool)
    start[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    return np.ascontiguousarray(d[np.sort(order[start])])


def _legacy_unique_rows(a: np.ndarray) -> np.ndarray:
    order = np.lexsort(a.T[::-1])
    s = a[order]
    keep = np.ones(len(s), bool)
    keep[1:] = (s[1:] != s[:-1]).any(axis=1)
    return s[keep]


def legacy_pack(points: np.ndarray):
    """One 3-D shape as main packed it: (vertices, adjacency lists, faces, edges)."""
    from scipy.spatial import ConvexHull

    pts = _legacy_unique_rows(np.asarray(points, dtype=np.float64) + 0.0)
    centred = pts - pts.mean(axis=0)
    np.linalg.svd(centred, full_matrices=False)  # the flatness rule's principal widths
    hull = ConvexHull(pts)
    keep = hull.vertices
    remap = np.full(len(pts), -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    tri = remap[hull.simplices]
    verts = pts[keep]
    planes = np.round(hull.equations[:, :3], 12)
    tri_edges, real = [], []
    for j in range(3):
        tri_edges.append(tri[:, [(j + 1) % 3, (j + 2) % 3]])
        real.append(np.any(planes != planes[hull.neighbors[:, j]], axis=1))
    all_edges = np.concatenate(tri_edges)
    sat_edges = all_edges[np.concatenate(real)]
    faces = _legacy_unique_directions(hull.equations[:, :3], True)
    edges = _legacy_unique_directions(verts[sat_edges[:, 1]] - verts[sat_edges[:, 0]], False)
    e = _legacy_unique_rows(np.sort(all_edges, axis=1))
    both = np.concatenate([e, e[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    counts = np.bincount(both[:, 0], minlength=len(verts))
    lists = np.split(both[:, 1].astype(np.int32), np.cumsum(counts)[:-1])
    adjacency = [
        np.concatenate([a, np.full(-len(a) % 4, i, np.int32)]) for i, a in enumerate(lists)
    ]
    return verts, adjacency, faces, edges


# ---------------------------------------------------------------------------------------


def timed(fn, repeats: int = 1) -> tuple[float, float, object]:
    """Best wall time, the CPU time of that run (all threads: on a shared machine the wall
    time includes waiting for a core), and the result."""
    best, cpu, out = np.inf, np.inf, None
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        wall = time.perf_counter() - t
        if wall < best:
            best, cpu = wall, time.process_time() - c
    return best, cpu, out


def clouds_case(shapes: int, old_shapes: int) -> None:
    from meshcol import ConvexSet

    rng = np.random.default_rng(0)
    clouds = rng.normal(size=(shapes, 64, 3))
    as_list = list(clouds)
    new, new_cpu, cs = timed(lambda: ConvexSet.from_vertices(as_list), 3)
    new_array, array_cpu, _ = timed(lambda: ConvexSet.from_vertices(clouds), 3)
    old, old_cpu, _ = timed(lambda: [legacy_pack(c) for c in as_list[:old_shapes]])
    print(
        f"{shapes} clouds of 64 points, ConvexSet.from_vertices: {new:.3f} s wall "
        f"({new_cpu:.3f} s CPU) from a list of arrays, {new_array:.3f} s ({array_cpu:.3f} s CPU) "
        f"from an (H, 64, 3) array; {cs!r}"
    )
    one_cpu, _ = single_thread_cpu(clouds)
    print(f"  one thread {one_cpu / shapes * 1e6:.1f} us CPU a shape")
    peer_rows(clouds, one_cpu / shapes * 1e6, 2000)
    per_old, per_new = old / old_shapes, new / shapes
    per_old_cpu, per_new_cpu = old_cpu / old_shapes, new_cpu / shapes
    print(
        f"  qhull path on {old_shapes} of them: {old:.3f} s wall, {per_old * 1e6:.0f} us a shape "
        f"(x {shapes}: {per_old * shapes:.1f} s); new {per_new * 1e6:.1f} us a shape: "
        f"{per_old / per_new:.0f}x wall, {per_old_cpu / per_new_cpu:.0f}x CPU"
    )


def on_hull_points(rng: np.random.Generator, shapes: int, n: int) -> np.ndarray:
    """(shapes, n, 3) points on random ellipsoids, randomly turned: every point on the hull."""
    from scipy.spatial.transform import Rotation

    p = rng.normal(size=(shapes, n, 3))
    p /= np.linalg.norm(p, axis=2, keepdims=True)
    p *= rng.uniform(0.5, 1.5, size=(shapes, 1, 3))
    turn = Rotation.random(shapes, random_state=rng).as_matrix()
    return np.ascontiguousarray(np.einsum("hij,hnj->hni", turn, p))


def peers() -> dict[str, object]:
    """The hull functions of the peers that are installed: name -> f(points)."""
    found: dict[str, object] = {}
    from scipy.spatial import ConvexHull

    found["scipy qhull"] = ConvexHull
    try:
        import trimesh

        found["trimesh"] = trimesh.convex.convex_hull
    except ImportError:
        pass
    try:
        import coal

        def coal_hull(p: np.ndarray) -> object:
            v = coal.StdVec_Vec3s()
            v.extend(list(p))
            return coal.ConvexBase.convexHull(v, False, None)

        found["coal"] = coal_hull
    except ImportError:
        print("  (coal not installed: pip install meshcol[bench])")
    return found


def single_thread_cpu(points: np.ndarray, repeats: int = 3) -> tuple[float, object]:
    """Best CPU time of `pack_hulls(points, threads=1)` and its result."""
    from meshcol.collision.hull import pack_hulls

    best, out = np.inf, None
    for _ in range(repeats):
        c = time.process_time()
        out = pack_hulls(points, threads=1)
        best = min(best, time.process_time() - c)
    return best, out


def peer_rows(points: np.ndarray, ours_us: float, peer_shapes: int) -> None:
    if peer_shapes <= 0:  # --peer-shapes 0: meshcol's rows alone
        return
    for name, fn in peers().items():
        sample = points[: min(len(points), peer_shapes)]
        c = time.process_time()
        for p in sample:
            fn(p)  # type: ignore[operator]
        us = (time.process_time() - c) / len(sample) * 1e6
        print(f"  {name}: {us:.1f} us CPU a shape ({len(sample)} shapes): x{us / ours_us:.2f}")


def on_hull_case(shapes: int, sizes: list[int], peer_shapes: int) -> None:
    from meshcol import ConvexSet

    rng = np.random.default_rng(1)
    for n in sizes:
        count = max(1, shapes * 64 // n)
        points = on_hull_points(rng, count, n)
        as_list = list(points)
        array, array_cpu, cs = timed(lambda: ConvexSet.from_vertices(points), 3)
        listed, list_cpu, _ = timed(lambda: ConvexSet.from_vertices(as_list), 3)
        one_cpu, _ = single_thread_cpu(points)
        kept = len(cs.vertices) / (count * n)
        print(
            f"{count} smooth hulls of {n} points ({kept:.0%} on the hull), from one array: "
            f"{array:.3f} s wall ({array_cpu:.3f} s CPU), {array / count * 1e6:.1f} us a shape "
            f"({array_cpu / count * 1e6:.1f} us CPU); from a list {listed:.3f} s "
            f"({list_cpu:.3f} s CPU); one thread {one_cpu / count * 1e6:.1f} us CPU a shape"
        )
        peer_rows(points, one_cpu / count * 1e6, peer_shapes)


# ---------------------------------------------------------------------------------------
# A/B against another build: the same single-threaded rows in a child of each interpreter


def families(shapes: int, sizes: list[int]) -> list[tuple[str, np.ndarray]]:
    """Named (H, n, 3) inputs: the timed rows, then degenerate sets for the identity check."""
    rng = np.random.default_rng(1)
    rows = [(f"smooth {n}", on_hull_points(rng, max(1, shapes * 64 // n), n)) for n in sizes]
    rows.append(("clouds 64", rng.normal(size=(shapes, 64, 3))))
    few = max(1, shapes // 20)
    sphere = on_hull_points(rng, few, 64)
    rows.append(("sphere + 1e-12 noise", sphere + 1e-12 * rng.normal(size=sphere.shape)))
    rows.append(("lattice", np.floor(2.0 * rng.normal(size=(few, 64, 3)))))
    dup = rng.normal(size=(few, 64, 3))
    dup[:, 1::3] = dup[:, 0:-1:3]
    rows.append(("duplicates", dup))
    flat = rng.normal(size=(few, 64, 3))
    flat[..., 2] = 0.25 * flat[..., 0] - 0.5 * flat[..., 1]
    rows.append(("flat", flat))
    rows.append(("huge", sphere * 1e90))
    rows.append(("tiny", sphere * 1e-150))
    return rows


def digest(packed: object) -> str:
    """A hash of the packed arrays and of the edge classes, the same for a build that packs
    the classes and one that packs the edges and computes them (a ConvexSet's fields)."""
    from meshcol import ConvexSet

    h = hashlib.sha256()
    for field in dataclasses.fields(packed):  # type: ignore[arg-type]
        if not field.name.startswith("edge_"):
            h.update(np.ascontiguousarray(getattr(packed, field.name)).tobytes())
    count = len(packed.status)  # type: ignore[attr-defined]
    polytopes = np.arange(count, dtype=np.int64)
    cs = ConvexSet._assemble(np.zeros(count, np.int8), np.zeros((count, 4)), polytopes, packed)  # type: ignore[arg-type]
    h.update(cs.edge_offsets.tobytes())
    h.update(cs.edge_directions.tobytes())
    return h.hexdigest()[:16]


def peer_cpu(points: np.ndarray, peer_shapes: int) -> dict[str, float]:
    """CPU us a shape of each installed peer on the first `peer_shapes` shapes."""
    out = {}
    for name, fn in peers().items():
        sample = points[: min(len(points), peer_shapes)]
        c = time.process_time()
        for p in sample:
            fn(p)  # type: ignore[operator]
        out[name] = (time.process_time() - c) / len(sample) * 1e6
    return out


def worker(shapes: int, sizes: list[int], peer_shapes: int) -> None:
    """Prints {row: [CPU us a shape, digest of the packed arrays, {peer: CPU us a shape}]}
    as JSON (peers with --peer-shapes > 0, on the timed rows)."""
    out = {}
    for name, points in families(shapes, sizes):
        timed_row = name.startswith(("smooth", "clouds"))
        cpu, packed = single_thread_cpu(points, 3 if timed_row else 1)
        theirs = peer_cpu(points, peer_shapes) if timed_row and peer_shapes > 0 else {}
        out[name] = [cpu / len(points) * 1e6, digest(packed), theirs]
    print(json.dumps(out))


def ab_case(baseline: str, rounds: int, shapes: int, sizes: list[int], peer_shapes: int) -> None:
    """Old and new builds alternated, round by round; the peers are timed in the new build's
    child of each round, on the same shapes (their ratios are to the new build's time)."""
    runs: dict[str, list[dict[str, list]]] = {"old": [], "new": []}
    command = [__file__, "--worker", "--shapes", str(shapes), "--sizes", *map(str, sizes)]
    for r in range(rounds):
        order = [("old", baseline, 0), ("new", sys.executable, peer_shapes)]
        for label, python, theirs in order if r % 2 == 0 else order[::-1]:
            done = subprocess.run(
                [python, *command, "--peer-shapes", str(theirs)],
                capture_output=True,
                text=True,
                check=True,
            )
            runs[label].append(json.loads(done.stdout.splitlines()[-1]))
    print(f"A/B, {rounds} alternated rounds, one thread, CPU us a shape (old: {baseline}):")
    names = sorted({name for run in runs["new"] for row in run.values() for name in row[2]})
    head = "".join(f" {name} (x new) |" for name in names)
    print(f"| row | old | new | old / new | packed arrays |{head}")
    print("| --- | --- | --- | --- | --- |" + " --- |" * len(names))
    for row in runs["new"][0]:
        old = [run[row][0] for run in runs["old"]]
        new = [run[row][0] for run in runs["new"]]
        same = {run[row][1] for run in runs["old"] + runs["new"]}
        cells = ""
        for name in names:
            theirs = [
                (run[row][2][name], run[row][0]) for run in runs["new"] if name in run[row][2]
            ]
            if not theirs:
                cells += " |"
                continue
            us = [t for t, _ in theirs]
            ratio = [t / ours for t, ours in theirs]
            cells += f" {min(us):.1f}-{max(us):.1f} (x{min(ratio):.1f}-{max(ratio):.1f}) |"
        print(
            f"| {row} | {min(old):.1f}-{max(old):.1f} | {min(new):.1f}-{max(new):.1f} | "
            f"{min(old) / max(new):.2f}-{max(old) / min(new):.2f} | "
            f"{'identical' if len(same) == 1 else 'DIFFERENT'} |{cells}"
        )


def sphere(count: int):
    import trimesh

    mesh = trimesh.creation.uv_sphere(radius=1.0, count=[count, count])
    return np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64)


def mesh_case(count: int, skip_old: bool) -> None:
    import trimesh

    from meshcol import ConvexSet
    from meshcol.analysis.check import check_scene
    from meshcol.types import Body, Scene

    v, f = sphere(count)
    print(f"UV sphere: {len(f)} triangles, {len(v)} vertices")
    new, new_cpu, cs = timed(lambda: ConvexSet.from_vertices([v]))
    print(
        f"  pack its hull: new {new:.2f} s wall, {new_cpu:.2f} s CPU ({len(cs.vertices)} vertices)"
    )
    if not skip_old:
        old, old_cpu, packed = timed(lambda: legacy_pack(v))
        print(
            f"  qhull path {old:.2f} s wall, {old_cpu:.2f} s CPU ({len(packed[0])} vertices): "
            f"{old / new:.1f}x wall, {old_cpu / new_cpu:.1f}x CPU"
        )
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    pose = np.eye(4)
    pose[0, 3] = 1.6
    bodies = (
        Body("sphere", None, v, f, np.eye(4)),
        Body("cube", None, np.asarray(box.vertices, float), np.asarray(box.faces), pose),
    )
    scene = Scene(bodies, units="m")
    total, total_cpu, report = timed(lambda: check_scene(scene))
    print(
        f"  check_scene, the sphere beside a cube (hull colliders): {total:.2f} s wall, "
        f"{total_cpu:.2f} s CPU, exit code {report.exit_code}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", type=int, default=40000)
    parser.add_argument("--old-shapes", type=int, default=2000)
    parser.add_argument("--peer-shapes", type=int, default=2000)
    parser.add_argument("--sphere-count", type=int, default=708)
    parser.add_argument("--skip-old-mesh", action="store_true")
    parser.add_argument(
        "--sizes", "--on-hull-sizes", type=int, nargs="*", default=[16, 64, 256, 1024]
    )
    parser.add_argument("--only-on-hull", action="store_true", help="the smooth hulls alone")
    parser.add_argument("--baseline", help="another build's python: A/B alternated rows")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.shapes, args.sizes, args.peer_shapes)
        return
    if args.baseline:
        ab_case(args.baseline, args.rounds, args.shapes, args.sizes, args.peer_shapes)
        return
    on_hull_case(args.shapes, args.sizes, args.peer_shapes)
    if args.only_on_hull:
        return
    clouds_case(args.shapes, args.old_shapes)
    mesh_case(args.sphere_count, args.skip_old_mesh)


if __name__ == "__main__":
    main()
