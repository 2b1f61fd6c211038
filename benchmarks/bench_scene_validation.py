"""Scene manifest validation on the 300,000-body manifest (issue 28): jsonschema against the
hand-written validator meshcol keeps (:mod:`meshcol.io.scene_validate`).

The manifest is ``bench_scale.py``'s (instances of 16 assets, quaternion rotations), written
once into ``benchmarks/.cache/scale/instances300000``. Timed in one process, each stage
``--repeat`` times (min-max), the garbage collector paused as the loader pauses it:

- decoding (``scene_parse.read_document``, the JSON text to Python objects);
- the column check (``scene_columns.columns``): how the common manifest is validated;
- the body-by-body check (``scene_validate.first_problem``): how any other manifest is
  validated, and how a problem is found and worded;
- jsonschema's ``iter_errors`` on the same document (what main ee068ea ran for a manifest the
  hand-written check did not pass, and what it would cost as the only validator).

Run: .venv/bin/python benchmarks/bench_scene_validation.py [--bodies 300000] [--repeat 3]
     [--jsonschema-bodies 300000]   (0 skips jsonschema: about 0.5 ms a body)
"""

from __future__ import annotations

import argparse
import gc
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_scale


def timed(fn: Callable[[], object], repeat: int) -> tuple[object, str]:
    """``fn()``'s result, and its wall and CPU seconds over ``repeat`` runs (min-max): the
    machine may be shared, and CPU time is what the stage itself costs."""
    walls, cpus, result = [], [], None
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = fn()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    figures = f"{min(walls):7.3f}-{max(walls):7.3f} s wall, {min(cpus):7.3f}-{max(cpus):7.3f} s CPU"
    return result, figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=300_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--jsonschema-bodies", type=int, default=300_000)
    args = parser.parse_args()

    from meshcol.io import scene_parse
    from meshcol.io.scene_columns import columns
    from meshcol.io.scene_schema import SCHEMA_PATH
    from meshcol.io.scene_validate import first_problem

    manifest = str(bench_scale.instances_folder(args.bodies) / "scene.json")

    def decode() -> object:
        scene_parse._READ.clear()
        return scene_parse.read_document(manifest)[0]

    gc.disable()
    document, figures = timed(decode, args.repeat)
    assert isinstance(document, dict)
    n = len(document["bodies"])
    print(f"manifest: {manifest} ({n} bodies)")
    print(f"decoding (read_document)            {figures}")
    found, figures = timed(lambda: columns(document), args.repeat)
    print(f"column check (columns)              {figures}  passed: {found is not None}")
    problem, figures = timed(lambda: first_problem(document), args.repeat)
    print(f"body-by-body check (first_problem)  {figures}  problem: {problem}")
    if args.jsonschema_bodies:
        from importlib.metadata import version

        import jsonschema

        schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
        validator = jsonschema.validators.validator_for(schema)(schema)
        part = dict(document, bodies=document["bodies"][: args.jsonschema_bodies])
        wall, cpu = time.perf_counter(), time.process_time()
        errors = list(validator.iter_errors(part))
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        count = len(part["bodies"])
        print(
            f"jsonschema iter_errors ({count} bodies) {wall:8.3f} s wall, {cpu:8.3f} s CPU  "
            f"errors: {len(errors)}  ({cpu / count * 1e6:.0f} us CPU a body, jsonschema "
            f"{version('jsonschema')})"
        )


if __name__ == "__main__":
    main()
