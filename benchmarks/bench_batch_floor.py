"""The per-call floor of a one-pair batch, piece by piece: what `bench_mesh_query.py`'s
``intersects (batch)`` row pays besides its query.

The row's set-up: a torus (``trimesh.creation.torus(1.0, 0.3)``, 8,700 faces) and a copy 5
apart, packed by ``MeshSet.from_arrays``; the pair is disjoint, settled by the root boxes. Each
piece is one lambda called in a Python loop, timed in CPU time (``time.process_time``) over
windows of ``--calls`` calls, the pieces alternated window by window, best of ``--windows``;
nanoseconds a call, the loop's own cost (an empty lambda) included in every figure and shown
as a row. Pieces:

- the row: ``mesh_intersects_batch(...).intersecting[0]``, and the batch call alone;
- the core call the batch makes (``MeshBvhSet.intersects_batch``, no Python frame);
- the same call declined at once (pairs in a form it does not read in place: it returns
  None), which is the method lookup, nanobind's dispatch and argument checks;
- a Python function of the same signature that returns None (the wrapper's frame);
- reading the verdict (``r.intersecting[0]``) and making the result dataclass from Python;
- the single-pair call ``MeshSet.intersects(0, 1)``;
- a one-pair ``mesh_distance_batch`` and a one-pair convex ``distance_batch`` (nine and six
  result arrays), and the intersects batch of the pair 100 times over (its result still one
  block of 200 bytes: that the block costs a batch of many pairs nothing);
- coal's ``collide`` of the two tori (``BVHModelOBBRSS``, request and result reused), when
  coal is installed: the peer of the row.

Run: .venv/bin/python benchmarks/bench_batch_floor.py [--calls 20000] [--windows 9]
A/B: .venv/bin/python benchmarks/with_other_meshcol.py /work/base22 benchmarks/bench_batch_floor.py
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from meshcol import ConvexSet, Sphere, distance_batch
from meshcol.collision.mesh_query import (
    MeshIntersectsBatch,
    MeshSet,
    mesh_distance_batch,
    mesh_intersects_batch,
)

try:
    import coal
except ImportError:  # the peer's row is left out
    coal = None


def shifted(x: float) -> np.ndarray:
    p = np.eye(4)
    p[0, 3] = x
    return p


def pieces() -> dict[str, Callable[[], Any]]:
    torus = trimesh.creation.torus(1.0, 0.3)
    meshes = MeshSet.from_arrays([torus, torus], np.stack([np.eye(4), shifted(5.0)]))
    pairs = np.array([[0, 1]])
    hundred = np.repeat(pairs, 100, axis=0)
    handle = meshes._handle
    result_type = MeshIntersectsBatch
    r = mesh_intersects_batch(meshes, None, pairs, threads=1)
    assert not r.intersecting[0] and r.status[0] == 0
    declined = ""  # a str is not a form of pairs the core reads in place
    assert handle.intersects_batch(None, declined, 1, result_type) is None
    intersecting, status = r.intersecting, r.status
    spheres = ConvexSet.from_shapes([Sphere(0.5), Sphere(0.5)])
    sphere_poses = np.stack([np.eye(4), shifted(3.0)])

    def same_signature(meshes: Any, poses: Any, pairs: Any, *, threads: int = 0) -> None:
        return None

    out: dict[str, Callable[[], Any]] = {
        "the row: batch, then verdict read": lambda: mesh_intersects_batch(
            meshes, None, pairs, threads=1
        ).intersecting[0],
        "the batch call": lambda: mesh_intersects_batch(meshes, None, pairs, threads=1),
        "its core call": lambda: handle.intersects_batch(None, pairs, 1, result_type),
        "the core call declined": lambda: handle.intersects_batch(None, declined, 1, result_type),
        "a Python frame of the same signature": lambda: same_signature(
            meshes, None, pairs, threads=1
        ),
        "the verdict read": lambda: r.intersecting[0],
        "the result dataclass made in Python": lambda: result_type(intersecting, status),
        "single pair: meshes.intersects(0, 1)": lambda: meshes.intersects(0, 1),
        "one-pair mesh_distance_batch (9 arrays)": lambda: mesh_distance_batch(
            meshes, None, pairs, threads=1
        ),
        "one-pair convex distance_batch (6 arrays)": lambda: distance_batch(
            spheres, sphere_poses, pairs, threads=1
        ),
        "the intersects batch of 100 pairs": lambda: mesh_intersects_batch(
            meshes, None, hundred, threads=1
        ),
        "the loop alone (an empty lambda)": lambda: None,
    }
    if coal is not None:
        model = coal.BVHModelOBBRSS()
        model.beginModel(len(torus.faces), len(torus.vertices))
        model.addVertices(np.asarray(torus.vertices, float))
        model.addTriangles(np.asarray(torus.faces, np.int64))
        model.endModel()
        ta, tb = coal.Transform3s(), coal.Transform3s()
        tb.setTranslation(np.array([5.0, 0.0, 0.0]))
        request, result = coal.CollisionRequest(), coal.CollisionResult()

        def coal_collide() -> bool:
            result.clear()
            return coal.collide(model, ta, model, tb, request, result) > 0

        assert not coal_collide()
        out["coal collide of the pair"] = coal_collide
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000, help="calls a window")
    parser.add_argument("--windows", type=int, default=9, help="windows a piece (best of)")
    args = parser.parse_args()
    fns = pieces()
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(args.windows):
        for name, fn in fns.items():
            start = time.process_time()
            for _ in range(args.calls):
                fn()
            best[name] = min(best[name], (time.process_time() - start) / args.calls * 1e9)
    print(f"CPU ns a call, best of {args.windows} windows of {args.calls}, load {os.getloadavg()}")
    for name, ns in best.items():
        print(f"  {name:44s} {ns:7.0f}")


if __name__ == "__main__":
    main()
