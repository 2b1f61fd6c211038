"""Bodies of one name named by their path (session 42): the naming rule alone, and ``meshcol
hull`` of a USD stage of N prims all named ``mesh`` (``/World/crate_NNNNN/mesh``, a cube
each, as DCC exporters write them) by one or more meshcol executables, alternated.

    .venv/bin/python benchmarks/bench_body_names.py [--prims 10000] [--rounds 2]
        [--meshcol /work/base42/.venv/bin/meshcol --meshcol .venv/bin/meshcol]

The stage is written once with usd-core into ``benchmarks/.cache/names``. Each executable
runs in a fresh child under ``env -u PYTHONDONTWRITEBYTECODE``; the child's wall and CPU
(user + system) time and peak memory are printed per run, with the load average.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import time
import timeit
from pathlib import Path

CACHE = Path(__file__).resolve().parent / ".cache" / "names"


def crate_stage(prims: int) -> Path:
    """The stage of ``prims`` cubes named ``mesh``, each under its own ``Xform``."""
    from pxr import Gf, Usd, UsdGeom, Vt

    path = CACHE / f"crates{prims}.usdc"
    if path.exists():
        return path
    CACHE.mkdir(parents=True, exist_ok=True)
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
    points = Vt.Vec3fArray([Gf.Vec3f(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    counts, indices = Vt.IntArray([4] * 6), Vt.IntArray([i for q in quads for i in q])
    for k in range(prims):
        xform = UsdGeom.Xform.Define(stage, f"/World/crate_{k:05d}")
        xform.AddTranslateOp().Set(Gf.Vec3d(2.0 * (k % 100), 2.0 * (k // 100), 0.0))
        mesh = UsdGeom.Mesh.Define(stage, f"/World/crate_{k:05d}/mesh")
        mesh.CreatePointsAttr(points)
        mesh.CreateFaceVertexCountsAttr(counts)
        mesh.CreateFaceVertexIndicesAttr(indices)
    stage.GetRootLayer().Save()
    return path


def time_rule(bodies: int) -> float:
    """Seconds (best of 5) :func:`meshcol.io.body_names.file_body_names` takes for ``bodies``
    bodies named ``mesh`` under ``World/crate_<k>``."""
    from meshcol.io.body_names import file_body_names

    leaves = ["mesh"] * bodies
    ancestors = [("World", f"crate_{k:06d}") for k in range(bodies)]
    return min(
        timeit.repeat(lambda: file_body_names("level", leaves, ancestors), number=1, repeat=5)
    )


def run_hull(exe: str, stage: Path, report: Path) -> tuple[float, float, float]:
    """Wall and CPU seconds and peak MB of ``exe hull stage --report report`` in a child."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [exe, "hull", str(stage), "--report", str(report)], env=env, check=True, capture_output=True
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu, after.ru_maxrss / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--prims", type=int, default=10_000)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--meshcol", action="append", default=[], help="an executable (repeat)")
    args = parser.parse_args()
    for bodies in (10_000, 100_000):
        print(f"file_body_names, {bodies:,} bodies of one leaf: {time_rule(bodies) * 1e3:.1f} ms")
    stage = crate_stage(args.prims)
    executables = args.meshcol
    for r in range(args.rounds):  # A B, then B A: each side first once
        for exe in executables if r % 2 == 0 else executables[::-1]:
            load = os.getloadavg()[0]
            wall, cpu, peak = run_hull(exe, stage, CACHE / "hull.json")
            # peak: the largest child so far (ru_maxrss of all children), an upper bound
            print(f"{exe}: {wall:.2f} s wall, {cpu:.2f} s CPU, <= {peak:.0f} MB, load {load:.1f}")


if __name__ == "__main__":
    main()
