"""Benchmark: ``meshcol hull SCENE --target PROFILE`` on the library-scale scenes, two builds.

For every packaged profile and scene size (the props of :mod:`bench_scale`, about 27
vertices each, ``benchmarks/.cache/scale/<n>/scene.json``), the wall time of the whole
command with the baseline build (``--baseline``, another venv's ``meshcol``) and this one,
alternated B A A B (``--repeats`` rounds; ``--order BA`` for one run of each), with the load average before each run: the
machine is shared, so read the ranges.

The last report of each side is then compared field by field (:func:`compare_reports`):
every number that differs is counted under its field's path (list indices left out), with
the largest relative difference; any other difference (a key, a length, a string, a null)
is counted as structural. The hulls each side wrote (``--output``, one OBJ of every body's
hull) are compared byte for byte (``hulls``: ``same``, or ``DIFFER`` with the objects that
differ and the largest coordinate difference, :func:`compare_hulls`). ``--compare-only``
compares the files ``--keep`` holds.

Run:  .venv/bin/python benchmarks/bench_target_scale.py --baseline ../base/.venv/bin/meshcol
      [--sizes 1000,10000] [--profiles physx,isaac] [--repeats 1] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
PROFILES = (
    "physx",
    "unity",
    "isaac",
    "physx-gpu",
    "mujoco",
    "bullet",
    "godot",
    "jolt",
    "unreal",
    "pybullet",
)


def scene(size: int) -> Path:
    """The cached scene of ``size`` props (made by :mod:`bench_scale` when missing)."""
    path = HERE / ".cache" / "scale" / str(size) / "scene.json"
    if not path.exists():
        sys.path.insert(0, str(HERE))
        from bench_scale import scene_folder

        scene_folder(size)
    return path


def run(meshcol: str, scene_path: Path, profile: str, report: Path) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of one ``meshcol hull --target`` run (bytecode
    written, as users run), its hulls written beside ``report`` (:func:`hulls_path`; both
    builds write them under one name, then renamed, so that the reports name the same file)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [meshcol, "hull", str(scene_path), "--target", profile, "--report", str(report)]
        + ["--output", str(report.parent / "hulls.obj")],
        check=True,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd=HERE.parent,
    )
    wall = time.perf_counter() - start
    (report.parent / "hulls.obj").replace(hulls_path(report))
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def hulls_path(report: Path) -> Path:
    """The OBJ of the hulls written with ``report``."""
    return report.with_suffix(".hulls.obj")


def _walk(a: Any, b: Any, path: str) -> Iterator[tuple[str, float | None]]:
    """``(path, relative difference or None for a structural one)`` of every leaf that
    differs."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            yield path + "{keys}", None
        for key in a.keys() & b.keys():
            yield from _walk(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            yield path + "[len]", None
        for x, y in zip(a, b, strict=False):
            yield from _walk(x, y, path + "[]")
    elif isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        if a != b:
            yield path, None
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if a != b:
            scale = max(abs(a), abs(b))
            yield path, (abs(a - b) / scale if math.isfinite(scale) and scale > 0 else None)
    elif a != b:
        yield path, None


def compare_reports(a: Path, b: Path) -> dict[str, tuple[int, float | None]]:
    """Field path -> (leaves that differ, largest relative difference; None: structural)."""
    found: dict[str, tuple[int, float | None]] = {}
    for path, rel in _walk(json.loads(a.read_text()), json.loads(b.read_text()), ""):
        count, worst = found.get(path, (0, 0.0))
        if rel is None or worst is None:
            found[path] = (count + 1, None)
        else:
            found[path] = (count + 1, max(worst, rel))
    return found


def _obj_vertices(path: Path) -> dict[str, list[str]]:
    """Per object (``o`` line) of an OBJ the lines of its vertices (its faces index the
    file's vertices, so a count that changes shifts every later object's faces)."""
    objects: dict[str, list[str]] = {}
    rows: list[str] = []
    for line in path.read_text().splitlines():
        if line.startswith("o "):
            rows = objects.setdefault(line[2:], [])
        elif line.startswith("v "):
            rows.append(line)
    return objects


def compare_hulls(a: Path, b: Path) -> str:
    """What differs between two OBJs of hulls: the objects whose vertices differ, those of
    them with another vertex count, and over the others the largest absolute and relative
    difference between a vertex and the nearest vertex of the other side."""
    if a.read_bytes() == b.read_bytes():
        return "same"
    left, right = _obj_vertices(a), _obj_vertices(b)
    if left.keys() != right.keys():
        return "DIFFER (objects)"
    changed = [name for name in left if left[name] != right[name]]
    counts = 0
    worst_abs = worst_rel = 0.0
    for name in changed:
        if len(left[name]) != len(right[name]):
            counts += 1
            continue
        u = np.array([r.split()[1:] for r in left[name]], dtype=np.float64)
        w = np.array([r.split()[1:] for r in right[name]], dtype=np.float64)
        nearest = np.linalg.norm(u[:, None] - w[None], axis=2).argmin(axis=1)
        gap = np.abs(u - w[nearest])
        worst_abs = max(worst_abs, float(gap.max()))
        worst_rel = max(worst_rel, float((gap / np.maximum(np.abs(u), 1e-300)).max()))
    if not changed:
        return "same vertices (faces renumbered)"
    return (
        f"DIFFER: {len(changed)} objects' vertices ({counts} with another count; the rest: "
        f"max abs {worst_abs:.1e}, max rel {worst_rel:.1e})"
    )


def _span(values: list[float]) -> str:
    return f"{min(values):.2f}-{max(values):.2f}" if values else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="the other build's meshcol")
    parser.add_argument("--this", default=str(Path(sys.executable).parent / "meshcol"))
    parser.add_argument("--sizes", default="1000,10000")
    parser.add_argument("--profiles", default=",".join(PROFILES))
    parser.add_argument("--repeats", type=int, default=1, help="rounds of --order")
    parser.add_argument(
        "--order", default="BAAB", help="the runs of a round: B the baseline, A this build"
    )
    parser.add_argument("--keep", default="", help="folder for both sides' reports")
    parser.add_argument("--compare-only", action="store_true")
    args = parser.parse_args()
    keep = Path(args.keep or tempfile.mkdtemp(prefix="bench_target_scale_"))
    keep.mkdir(parents=True, exist_ok=True)
    print(f"reports in {keep}")
    print("size   profile   base wall s  this wall s   base cpu s   this cpu s  load       fields")
    for size in (int(s) for s in args.sizes.split(",")):
        for profile in args.profiles.split(","):
            base_report = keep / f"base-{size}-{profile}.json"
            this_report = keep / f"this-{size}-{profile}.json"
            times: dict[str, list[float]] = {"base": [], "this": []}
            cpu: dict[str, list[float]] = {"base": [], "this": []}
            loads: list[float] = []
            if not args.compare_only:
                path = scene(size)
                for _ in range(args.repeats):
                    for side in ("base" if c == "B" else "this" for c in args.order):
                        exe = args.baseline if side == "base" else args.this
                        out = base_report if side == "base" else this_report
                        loads.append(os.getloadavg()[0])
                        wall, used = run(exe, path, profile, out)
                        times[side].append(wall)
                        cpu[side].append(used)
            fields = compare_reports(base_report, this_report)
            text = (
                ", ".join(
                    f"{name.rsplit('.', 1)[-1]} {count}x "
                    + ("structural" if rel is None else f"max rel {rel:.1e}")
                    for name, (count, rel) in sorted(fields.items())
                )
                or "byte-identical"
                if base_report.read_bytes() != this_report.read_bytes()
                else "byte-identical"
            )
            hulls = compare_hulls(hulls_path(base_report), hulls_path(this_report))
            print(
                f"{size:<6} {profile:<9} {_span(times['base']):>11}  {_span(times['this']):>11}"
                f"  {_span(cpu['base']):>11}  {_span(cpu['this']):>11}  {_span(loads):>9}  {text}"
                f", hulls {hulls}",
                flush=True,
            )


if __name__ == "__main__":
    main()
