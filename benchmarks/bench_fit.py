"""Enclosing fits per body: the core (1 and 2 threads) against the Python fits it replaced
(tests/fit_oracle.py) and trimesh's peers (oriented_bounds for the box, minimum_nsphere for
the sphere), A/B alternated in one run, ranges over the repeats, volume ratios to the peers.
("all" is the four shapes the Python fits have, as before the ellipsoid.)

Then the ellipsoid row: every shape's time per set (1 thread, µs) on sets of 64 and 1,024
points that are ALL hull vertices (points on random ellipsoids' surfaces, the minimum
ellipsoid's worst case: every point may carry weight), and the ellipsoid's volume against
the sphere's and the box's; with --reference, against SciPy's SLSQP on the primal problem
(tests/collision/test_fit_ellipsoid.py's reference, made to enclose): how near the
certificate's 1 + 1e-6 the fits end; with --mujoco, against the ellipsoid MuJoCo's compiler
fits to the hull's mesh (a geom of type ellipsoid with a mesh: its inertia's, or with
``fitaabb`` its box's), which need not enclose: how far its points stray (the largest
Mahalanobis norm), how many do, and its volume once scaled to hold them, over ours.

    .venv/bin/python benchmarks/bench_fit.py --bodies 20 --points 300 --repeats 3
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _oracle():
    spec = importlib.util.spec_from_file_location("fit_oracle", ROOT / "tests" / "fit_oracle.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fit_oracle"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _clouds(count: int, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    return [rng.normal(size=(n, 3)) * rng.uniform(0.1, 2.0, 3) for _ in range(count)]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--bodies", type=int, default=20)
    parser.add_argument("--points", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ellipsoid-sets", type=int, default=20, help="sets per size")
    parser.add_argument("--reference", action="store_true", help="ellipsoids against SLSQP")
    parser.add_argument("--mujoco", action="store_true", help="against MuJoCo's fitted ellipsoid")
    args = parser.parse_args()
    import trimesh

    from meshcol.collision.fit import fit_batch
    from meshcol.collision.hull import exact_hull

    oracle = _oracle()
    sets = _clouds(args.bodies, args.points)
    hulls = [exact_hull(p) for p in sets]
    shapes = ("sphere", "box", "cylinder", "capsule", "all")
    times: dict[tuple[str, str], list[float]] = {}

    def timed(key: tuple[str, str], run) -> None:
        start = time.perf_counter()
        run()
        times.setdefault(key, []).append((time.perf_counter() - start) / len(sets) * 1e3)

    for _ in range(args.repeats):
        for shape in shapes:
            asked = oracle.FIT_SHAPES if shape == "all" else shape
            timed((shape, "core 1 thread"), lambda: fit_batch(sets, asked, threads=1))
            timed((shape, "core 2 threads"), lambda: fit_batch(sets, asked, threads=2))
            if shape == "all":
                timed(
                    (shape, "python"), lambda: [oracle.fit_all(h.vertices, h.faces) for h in hulls]
                )
            else:
                timed(
                    (shape, "python"),
                    lambda: [oracle.fit_primitive(shape, h.vertices, h.faces) for h in hulls],
                )
        timed(
            ("box", "trimesh oriented_bounds"),
            lambda: [trimesh.bounds.oriented_bounds(p) for p in sets],
        )
        timed(
            ("sphere", "trimesh minimum_nsphere"),
            lambda: [trimesh.nsphere.minimum_nsphere(p) for p in sets],
        )

    print(f"ms per body ({args.bodies} bodies of {args.points} points, {args.repeats} repeats)")
    for (shape, engine), values in times.items():
        print(f"  {shape:9s} {engine:26s} {min(values):9.3f} .. {max(values):9.3f}")
    core = fit_batch(sets, "all", threads=1)
    box = np.array([np.prod(trimesh.bounds.oriented_bounds(p)[1]) for p in sets])
    sphere = np.array(
        [4.0 / 3.0 * np.pi * trimesh.nsphere.minimum_nsphere(p)[1] ** 3 for p in sets]
    )
    for name, peer in (("box", box), ("sphere", sphere)):
        ratio = core.volume[:, core.shapes.index(name)] / peer
        print(f"  volume {name} core / trimesh: {ratio.min():.6f} .. {ratio.max():.6f}")
    _ellipsoid_row(args.ellipsoid_sets, args.repeats, args.reference, args.mujoco)


def _on_hull(count: int, n: int) -> list[np.ndarray]:
    """Sets of n points on random ellipsoids' surfaces (every point a hull vertex)."""
    rng = np.random.default_rng(1)
    sets = []
    for _ in range(count):
        d = rng.normal(size=(n, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        sets.append((d * rng.uniform(0.1, 2.0, 3)) @ q.T + rng.normal(size=3))
    return sets


def _slsqp():
    path = ROOT / "tests" / "collision" / "test_fit_ellipsoid.py"
    spec = importlib.util.spec_from_file_location("test_fit_ellipsoid", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module._slsqp


def _mujoco_ellipsoid(points: np.ndarray, aabb: bool) -> tuple[float, float, float]:
    """MuJoCo's ellipsoid fitted to the hull mesh of ``points``: (its volume, the largest
    Mahalanobis norm of a point, the fraction of points outside)."""
    import mujoco
    from scipy.spatial import ConvexHull

    spec = mujoco.MjSpec()
    spec.compiler.fitaabb = aabb
    mesh = spec.add_mesh()
    mesh.name = "hull"
    mesh.uservert = points.reshape(-1).tolist()
    mesh.userface = ConvexHull(points).simplices.reshape(-1).tolist()
    geom = spec.worldbody.add_geom()
    geom.type = mujoco.mjtGeom.mjGEOM_ELLIPSOID
    geom.meshname = "hull"
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    size = np.asarray(model.geom_size[0])
    local = (points - data.geom_xpos[0]) @ data.geom_xmat[0].reshape(3, 3)
    norms = np.linalg.norm(local / size, axis=1)
    return 4.0 / 3.0 * np.pi * float(np.prod(size)), float(norms.max()), float(np.mean(norms > 1))


def _ellipsoid_row(count: int, repeats: int, reference: bool, mujoco: bool) -> None:
    from meshcol.collision.fit import FIT_SHAPES, fit_batch
    from meshcol.collision.hull import exact_hull

    print(f"µs per set, 1 thread ({count} sets of all-on-hull points, {repeats} repeats)")
    for n in (64, 1024):
        sets = _on_hull(count, n)
        assert all(len(exact_hull(p).vertices) == n for p in sets)
        times: dict[str, list[float]] = {}
        for _ in range(repeats):
            # each includes the set's exact hull, as a run's does; the last, less the sphere's
            # time, is the ellipsoid's own
            for shape in (*FIT_SHAPES, ("sphere", "ellipsoid")):
                start = time.perf_counter()
                batch = fit_batch(sets, shape, threads=1)
                key = shape if isinstance(shape, str) else "sphere+ellipsoid"
                times.setdefault(key, []).append((time.perf_counter() - start) / count * 1e6)
                assert np.all(batch.status == 0)
        line = "  ".join(f"{s} {min(v):8.0f} .. {max(v):8.0f}" for s, v in times.items())
        print(f"  n={n:5d}  {line}")
        batch = fit_batch(sets, ("sphere", "box", "ellipsoid"), threads=1)
        for other in ("sphere", "box"):
            ratio = batch.volume[:, 2] / batch.volume[:, batch.shapes.index(other)]
            print(f"    volume ellipsoid / {other}: {ratio.min():.4f} .. {ratio.max():.4f}")
        if reference:
            slsqp = _slsqp()
            ratio = batch.volume[:, 2] / np.array([slsqp(p) for p in sets]) - 1.0
            print(f"    volume ellipsoid / SLSQP's - 1: {ratio.min():.2e} .. {ratio.max():.2e}")
        for aabb in (False, True) if mujoco else ():
            fits = np.array([_mujoco_ellipsoid(p, aabb) for p in sets])
            scaled = fits[:, 0] * fits[:, 1] ** 3 / batch.volume[:, 2]
            print(
                f"    MuJoCo's {'fitaabb' if aabb else 'inertia'} ellipsoid: largest norm "
                f"{fits[:, 1].min():.3f} .. {fits[:, 1].max():.3f}, points outside "
                f"{fits[:, 2].mean():.1%}, scaled to enclose / ours {scaled.min():.3f} .. "
                f"{scaled.max():.3f}"
            )


if __name__ == "__main__":
    main()
