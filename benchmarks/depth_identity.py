"""Every answer of mesh_penetration_depth_batch over bench_mesh_query.py's pairs and a corpus
of posed test pairs, written to a file, and two such files compared (the identity check of a
change to the depth search, run under two checkouts' interpreters).

Run: PYTHON benchmarks/depth_identity.py write OUT.npz
     .venv/bin/python benchmarks/depth_identity.py compare A.npz B.npz

With another checkout's core: ``.venv/bin/python benchmarks/with_other_meshcol.py CHECKOUT
benchmarks/depth_identity.py write OUT.npz``. The pairs: the family of bench_mesh_query.py
(four corpus meshes, 300 pairs in each of near, touching and apart, seed 7), its three
single-pair depth rows, the four concave hosts of tests/collision/test_mesh_depth.py with
their cubes at resting and sunk offsets under random rigid motions, each host against a moved
and turned copy of itself, and overlapping primitives (spheres, boxes, tori, cylinders, some
made open by a stray triangle so that the open path runs). ``compare`` says, per group, whether
depth, both points, normal, deepest mesh and status are the same bits, and the total inside
tests (points_tested) of each file.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "collision"))

FIELDS = ("depth", "point_a", "point_b", "normal", "deepest_mesh", "status")


def _groups():
    """(name, meshes as (vertices, faces), poses (n, 4, 4), pairs (P, 2))."""
    import bench_mesh_query as bench
    import test_mesh_depth as hosts

    rng = np.random.default_rng(7)
    for name, path in bench.FAMILY:
        mesh = bench.centred(trimesh.load(path, force="mesh"))
        for config, poses in bench.family_sets(mesh, 300, rng).items():
            flat = poses.reshape(-1, 4, 4)
            pairs = np.arange(len(flat)).reshape(-1, 2)
            yield f"{name} {config}", [mesh] * len(flat), flat, pairs
    for name, (a, b, pb) in bench.single_depth_rows().items():
        yield name, [a, b], np.stack([np.eye(4), pb]), np.array([[0, 1], [1, 0]])

    rng = np.random.default_rng(11)
    for name, (host, cube) in sorted(hosts.HOSTS.items()):
        meshes, poses = [], []
        for offset in (0.0, 1e-9, -1e-9, -1e-7, -1e-3, -0.02, -0.1):
            for _ in range(6):
                motion = hosts._pose(bench.random_rotation(rng), rng.normal(size=3))
                meshes += [host, cube]
                poses += [motion, motion @ hosts._pose(translation=(0.0, 0.0, offset))]
        for _ in range(20):  # the host against a moved, turned copy
            shift = rng.normal(size=3) * 0.1 * float(host.extents.max())
            meshes += [host, host]
            poses += [
                np.eye(4),
                hosts._pose(bench.random_rotation(rng) if rng.random() < 0.5 else None, shift),
            ]
        pairs = np.arange(len(meshes)).reshape(-1, 2)
        yield f"host {name}", meshes, np.stack(poses), pairs

    prims = {
        "sphere": trimesh.creation.icosphere(3),
        "box": trimesh.creation.box(extents=[1.0, 0.6, 0.3]),
        "torus": trimesh.creation.torus(1.0, 0.3, 48, 24),
        "cylinder": trimesh.creation.cylinder(0.5, 1.5, sections=40),
    }
    names = sorted(prims)
    for open_b in (False, True):
        meshes, poses = [], []
        for _ in range(200):
            a, b = prims[names[rng.integers(4)]], prims[names[rng.integers(4)]]
            if open_b:
                v, f = hosts._open_copy(b)
                b = trimesh.Trimesh(v, f, process=False)
            shift = rng.normal(size=3) * 0.5
            if rng.random() < 0.3:  # axis-aligned, flush-prone
                pose_b = hosts._pose(None, np.round(shift, 1))
            else:
                pose_b = hosts._pose(bench.random_rotation(rng), shift)
            meshes += [a, b]
            poses += [hosts._pose(bench.random_rotation(rng)), pose_b]
        yield (
            f"primitives{' (b open)' if open_b else ''}",
            meshes,
            np.stack(poses),
            np.arange(400).reshape(-1, 2),
        )


def write(out: str) -> None:
    from meshcol.collision.mesh_query import MeshSet, mesh_penetration_depth_batch

    arrays = {}
    for name, meshes, poses, pairs in _groups():
        arrays_in = [
            (np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces)) for m in meshes
        ]
        ms = MeshSet.from_arrays(
            arrays_in, np.ascontiguousarray(poses, dtype=np.float64), threads=1
        )
        r = mesh_penetration_depth_batch(
            ms, None, np.ascontiguousarray(pairs, dtype=np.int64), threads=1
        )
        for field in (*FIELDS, "points_tested"):
            arrays[f"{name}|{field}"] = np.asarray(getattr(r, field))
        print(f"{name}: {len(pairs)} pairs", flush=True)
    np.savez(out, **arrays)


def compare(a_path: str, b_path: str) -> int:
    a, b = np.load(a_path), np.load(b_path)
    groups = sorted({key.split("|")[0] for key in a.files})
    bad = 0
    for name in groups:
        same = all(a[f"{name}|{f}"].tobytes() == b[f"{name}|{f}"].tobytes() for f in FIELDS)
        bad += not same
        ta, tb = int(a[f"{name}|points_tested"].sum()), int(b[f"{name}|points_tested"].sum())
        count = len(a[f"{name}|depth"])
        print(
            f"{name}: {count} pairs, answers {'identical' if same else 'DIFFER'}, inside tests {ta} -> {tb}"
        )
    return 1 if bad else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    verbs.add_parser("write", help="write every answer to OUT.npz").add_argument("out")
    both = verbs.add_parser("compare", help="compare two written files")
    both.add_argument("a")
    both.add_argument("b")
    args = parser.parse_args()
    if args.verb == "write":
        write(args.out)
        return 0
    return compare(args.a, args.b)


if __name__ == "__main__":
    raise SystemExit(main())
