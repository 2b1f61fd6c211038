"""CPU time of each stage of one ``meshcol check`` (issue 32, items 4-5): where a big manifest's
time goes, from the command line, in one process.

Wraps the stage functions the command calls (the output guard's manifest read, the manifest's
document, validation and bodies, colliders, the broad, narrow, mesh and depth stages, the
report's rows and its writing) with ``time.process_time`` and ``time.perf_counter`` counters,
runs ``meshcol check`` with the given arguments, and prints each stage's CPU and wall seconds
(the imports first), the system CPU and minor page faults in it and the peak resident memory
after it, then the whole run's. The CPU time is the figure a loaded machine does not move;
the wall time says, on a quiet machine, which stages run on one core (wall = CPU) and which
on all of them (wall < CPU); the system time and the faults, what the kernel costs (opening
files, touching new memory), which other processes on the machine inflate.

Run: .venv/bin/python benchmarks/check_stages.py MANIFEST [meshcol check options]
     e.g. benchmarks/check_stages.py benchmarks/.cache/scale/primitives-spheres100000/scene.json
          --report /tmp/r.json --fail-on none --threads 1
"""

from __future__ import annotations

import importlib
import resource
import sys
import time
from collections.abc import Callable
from typing import Any

#: (module, function) of each stage, in the order a check meets them.
STAGES = [
    ("meshcol.io.outputs", "manifest_inputs"),
    ("meshcol.io.scene", "native_manifest"),
    ("meshcol.io.scene", "primitive_scene"),  # a --baseline's: native_scene since session 17
    ("meshcol.io.scene", "native_scene"),
    ("meshcol.io.scene_native", "read_mesh_names"),  # inside native_scene
    ("meshcol.io.scene_native", "bulk_bodies"),
    ("meshcol.io.scene", "read_document"),
    ("meshcol.io.scene", "validate"),
    ("meshcol.io.scene", "read_mesh_files"),
    ("meshcol.io.scene", "bulk_bodies"),
    ("meshcol.io.scene", "build_bodies"),
    ("meshcol.io.scene", "primitive_bodies"),
    ("meshcol.analysis.check", "primitive_colliders"),
    ("meshcol.analysis.check", "build_colliders"),
    ("meshcol.analysis.check", "place"),
    ("meshcol.analysis.check", "broad_phase"),
    ("meshcol.analysis.check", "convex_phase"),
    ("meshcol.analysis.check", "mesh_phase"),
    ("meshcol.analysis.check", "depth_bounds"),
    ("meshcol.analysis.check", "classify"),
    ("meshcol.analysis.check", "apply_policy"),
    ("meshcol.analysis.check", "check_report"),
    ("meshcol.io.formats", "write_report"),
]


def peak_mib() -> float:
    """This process's peak resident memory, MiB: the kernel's high-water mark of its memory
    (``VmHWM``), which starts again at exec, where ``ru_maxrss`` keeps the parent's when it
    was larger (a benchmark that ran this script after loading a 150 MB report read 1,359)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def timed(times: dict[str, list[float]], label: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` counting, into ``times[label]``: CPU seconds, wall seconds, system CPU seconds
    and minor page faults (each summed over its calls), and the peak resident MiB after it."""

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start, start_wall = time.process_time(), time.perf_counter()
        before = resource.getrusage(resource.RUSAGE_SELF)
        try:
            return fn(*args, **kwargs)
        finally:
            after = resource.getrusage(resource.RUSAGE_SELF)
            spent = times.setdefault(label, [0.0, 0.0, 0.0, 0.0, 0.0])
            spent[0] += time.process_time() - start
            spent[1] += time.perf_counter() - start_wall
            spent[2] += after.ru_stime - before.ru_stime
            spent[3] += after.ru_minflt - before.ru_minflt
            spent[4] = peak_mib()

    return wrapper


def main() -> None:
    start, start_wall = time.process_time(), time.perf_counter()
    import meshcol.cli

    imported = time.process_time() - start, time.perf_counter() - start_wall
    times: dict[str, list[float]] = {}
    for module_name, name in STAGES:
        module = importlib.import_module(module_name)
        if not hasattr(module, name):  # a stage an older build (a --baseline) does not have
            continue
        label = f"{module_name.rsplit('.', 1)[1]}.{name}"
        setattr(module, name, timed(times, label, getattr(module, name)))
    sys.argv = ["meshcol", "check", *sys.argv[1:]]
    code: Any = 0
    try:
        meshcol.cli.main()
    except SystemExit as exit_:
        code = exit_.code
    total, wall = time.process_time() - start, time.perf_counter() - start_wall
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print("stage CPU and wall seconds, the system CPU in it, its minor page faults and the peak")
    print("resident MiB after it (nested: read_document and below are inside manifest_inputs or")
    print("the load; the load's total is the report's load_seconds):")
    print(f"  {'':32s} {'CPU':>7} {'wall':>7} {'system':>7} {'faults':>8} {'peak':>6}")
    print(f"  {'imports (meshcol.cli)':32s} {imported[0]:7.2f} {imported[1]:7.2f}")
    for label, (seconds, elapsed, system, faults, peak) in times.items():
        print(
            f"  {label:32s} {seconds:7.2f} {elapsed:7.2f} {system:7.2f} {faults:8.0f} {peak:6.0f}"
        )
    print(
        f"whole run: {total:.2f} s CPU (user {usage.ru_utime:.2f}, system {usage.ru_stime:.2f}), "
        f"{wall:.2f} s wall, {usage.ru_minflt} minor page faults, peak "
        f"{peak_mib():.0f} MiB, exit {code}"
    )


if __name__ == "__main__":
    main()
