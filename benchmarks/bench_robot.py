"""Benchmark: `meshcol collision-matrix` on a robot vs a python-fcl loop over the same pairs.

meshcol: :func:`meshcol.analysis.collision_matrix.collision_matrix` end to end (reading the
URDF, building the hulls, the default configuration and every sample), with its own time per
configuration (link poses + broad and narrow phase, from the report).

python-fcl, as a user would write the loop: one ``fcl.CollisionObject`` per convex part (the
same hulls as ``fcl.Convex``, the same primitives as fcl primitives), and per configuration
every part's transform set and ``fcl.collide`` called on every part pair of every link pair that
meshcol measures (all but the adjacent ones; stopping at a link pair's first contact; no
broad phase: MoveIt's FCL manager prunes with one, so this is the loop, not MoveIt). Its link
poses come from meshcol's batched kinematics, outside its timing (which favours the peer).
Both answer "does this link pair collide at this configuration"; the run checks that they
agree on the configurations both measured.

The machine may be shared: rounds alternate meshcol and fcl, and ranges are printed.

Run:  .venv/bin/python benchmarks/bench_robot.py [--robot PANDA.urdf] [--samples 10000]
      [--fcl-samples 1000] [--rounds 3] [--threads 2]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

PANDA = (
    Path(__file__).resolve().parents[2]
    / "shared"
    / "corpus"
    / "robots"
    / "panda_description"
    / "urdf"
    / "panda.urdf"
)


def fcl_objects(colliders):
    """One fcl collision object per convex part of ``colliders``, in part order."""
    import fcl

    from meshcol.collision.hull import exact_hull
    from meshcol.collision.shapes import ShapeKind

    shapes = colliders.shapes
    objects = []
    for h in range(len(shapes)):
        kind = int(shapes.kinds[h])
        p = shapes.params[h]
        if kind == ShapeKind.SPHERE:
            geometry = fcl.Sphere(p[0])
        elif kind == ShapeKind.BOX:
            geometry = fcl.Box(*(2.0 * p[:3]))
        elif kind == ShapeKind.CAPSULE:
            geometry = fcl.Capsule(p[0], 2.0 * p[1])
        elif kind == ShapeKind.CYLINDER:
            geometry = fcl.Cylinder(p[0], 2.0 * p[1])
        else:
            hull = exact_hull(shapes.vertices[shapes.offsets[h] : shapes.offsets[h + 1]])
            faces = np.hstack([np.full((len(hull.faces), 1), 3), hull.faces]).ravel()
            geometry = fcl.Convex(hull.vertices, len(hull.faces), faces)
        objects.append(fcl.CollisionObject(geometry, fcl.Transform()))
    return objects


def fcl_loop(objects, part_poses, part_pairs, pair_of, n_pairs):
    """(configurations, link pairs) bool by one fcl.collide per part pair, and the seconds."""
    import fcl

    request = fcl.CollisionRequest()
    out = np.zeros((len(part_poses), n_pairs), dtype=bool)
    began = time.perf_counter()
    for c, poses in enumerate(part_poses):
        for obj, pose in zip(objects, poses):
            obj.setTransform(fcl.Transform(pose[:3, :3], pose[:3, 3]))
        row = out[c]
        for (a, b), k in zip(part_pairs, pair_of):
            if row[k]:
                continue  # the link pair already collides here
            if fcl.collide(objects[a], objects[b], request, fcl.CollisionResult()):
                row[k] = True
    return out, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robot", type=Path, default=PANDA)
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--fcl-samples", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    from meshcol.analysis.colliders import build_colliders
    from meshcol.analysis.collision_matrix import _Sampler, collision_matrix
    from meshcol.io.kinematics import adjacent_links
    from meshcol.io.robot import load_robot_model

    try:
        import fcl  # noqa: F401
    except ImportError:
        fcl_ok = False
    else:
        fcl_ok = True

    # The peer's inputs: meshcol's colliders and link poses of the same configurations.
    model = load_robot_model(args.robot)
    kin = model.kinematics
    colliders = build_colliders(model.scene.bodies, "hull")
    index = {n: i for i, n in enumerate(kin.links)}
    body_link = np.array([index[b.name] for b in colliders.bodies])
    loaded = kin.link_poses(kin.loaded[None])[0]
    offsets = np.linalg.inv(loaded[body_link]) @ np.stack([b.pose for b in colliders.bodies])
    q = kin.space.sample(args.samples, args.seed)[: args.fcl_samples]
    part_poses = (kin.link_poses(q)[:, body_link] @ offsets)[:, colliders.part_body]
    # the link pairs meshcol measures: every pair but the adjacent ones (never checked)
    names = [b.name for b in colliders.bodies]
    adjacent = set(adjacent_links(kin.links, kin.edges, names))
    i, j = np.triu_indices(len(names), k=1)
    skip = np.array([tuple(sorted((names[a], names[b]))) in adjacent for a, b in zip(i, j)])
    sampler = _Sampler(
        kin, colliders, body_link, offsets, 0.0, min(len(q), 256), args.threads, skip
    )
    part_pairs = sampler.index.part_pairs
    pair_of = np.repeat(np.arange(len(sampler.pairs)), sampler.index.sizes)
    part_pairs, pair_of = part_pairs[~skip[pair_of]], pair_of[~skip[pair_of]]
    objects = fcl_objects(colliders) if fcl_ok else []

    print(
        f"robot {args.robot.name}: {len(colliders.bodies)} links with geometry, "
        f"{len(sampler.pairs)} link pairs ({int(skip.sum())} adjacent, not measured), "
        f"{len(colliders.part_body)} convex parts, {len(part_pairs)} part pairs measured; "
        f"{args.threads} threads"
    )
    ours_total, ours_per, peer_per = [], [], []
    for _ in range(args.rounds):
        began = time.perf_counter()
        report = collision_matrix(
            args.robot, samples=args.samples, seed=args.seed, threads=args.threads
        )
        ours_total.append(time.perf_counter() - began)
        ours_per.append(report.summary["seconds_per_configuration"])
        if fcl_ok:
            peer, seconds = fcl_loop(objects, part_poses, part_pairs, pair_of, len(sampler.pairs))
            peer_per.append(seconds / len(q))
    print(
        f"meshcol collision-matrix, {args.samples} samples: {min(ours_total):.3f}-"
        f"{max(ours_total):.3f} s end to end; {min(ours_per) * 1e6:.1f}-"
        f"{max(ours_per) * 1e6:.1f} us per configuration"
    )
    if fcl_ok:
        ours = sampler.collide(q)
        disagree = int(np.count_nonzero(ours != peer))
        print(
            f"python-fcl loop, {len(q)} samples: {min(peer_per) * 1e6:.1f}-"
            f"{max(peer_per) * 1e6:.1f} us per configuration "
            f"({min(peer_per) / max(ours_per):.0f}-{max(peer_per) / min(ours_per):.0f}x meshcol); "
            f"{disagree} of {ours.size} (configuration, link pair) answers differ"
        )
    else:
        print("python-fcl not installed: peer skipped")


if __name__ == "__main__":
    main()
