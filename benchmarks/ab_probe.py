#!/usr/bin/env python3
"""A/B probe: the same public-API work timed in whichever meshcol this python imports.

Run it with two builds (for example two worktrees, each with its own .venv), alternating:
``for r in 1 2 3; do for d in OLD NEW; do (cd $d && .venv/bin/python /path/to/ab_probe.py); done; done``
from each repository root (it reads samples/). Prints one JSON line of best times.
"""

import json
import time

import numpy as np

import meshcol


def best(fn, n=5):
    ts = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return min(ts)


rng = np.random.default_rng(0)
clouds = [rng.normal(size=(64, 3)) for _ in range(2000)]
out = {}
out["pack_2000x64_s"] = best(lambda: meshcol.ConvexSet.from_vertices(clouds), 3)
cs = meshcol.ConvexSet.from_vertices(clouds[:256])
poses = np.tile(np.eye(4), (256, 1, 1))
poses[:, :3, 3] = rng.uniform(-1.5, 1.5, size=(256, 3))
pairs = rng.integers(0, 256, size=(4000, 2))
pairs = pairs[pairs[:, 0] != pairs[:, 1]]
out["distance_4000_us"] = (
    best(lambda: meshcol.distance_batch(cs, poses, pairs, threads=1), 7) / len(pairs) * 1e6
)
out["penetration_4000_us"] = (
    best(lambda: meshcol.penetration_batch(cs, poses, pairs, threads=1), 7) / len(pairs) * 1e6
)
scene = meshcol.load_inputs(["samples/level/scene.json"])
from importlib import import_module

try:
    check_scene = import_module("meshcol.analysis.check").check_scene
except ImportError:
    check_scene = import_module("meshcol.check").check_scene
out["check_level_s"] = best(lambda: check_scene(scene), 7)
out["sweep_bullet_s"] = best(lambda: meshcol.sweep("samples/bullet/scene.json"), 7)
bowl = meshcol.load_inputs(["samples/bowl/bowl.obj"]).bodies[0]
out["hull64_bowl_s"] = best(lambda: meshcol.convex_hull(bowl.vertices, max_vertices=64), 3)
print(json.dumps({k: round(v, 4) for k, v in out.items()}))
