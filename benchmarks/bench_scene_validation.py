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


def timed(fn: Callable[[], object], repeat: int) -> tuple[object, float, float]:
    """``fn()``'s result and its fastest and slowest wall time over ``repeat`` runs."""
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, min(times), max(times)


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
    document, low, high = timed(decode, args.repeat)
    assert isinstance(document, dict)
    n = len(document["bodies"])
    print(f"manifest: {manifest} ({n} bodies)")
    print(f"decoding (read_document)            {low:8.3f} - {high:8.3f} s")
    found, low, high = timed(lambda: columns(document), args.repeat)
    print(
        f"column check (columns)              {low:8.3f} - {high:8.3f} s  passed: {found is not None}"
    )
    problem, low, high = timed(lambda: first_problem(document), args.repeat)
    print(f"body-by-body check (first_problem)  {low:8.3f} - {high:8.3f} s  problem: {problem}")
    if args.jsonschema_bodies:
        import jsonschema

        schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
        validator = jsonschema.validators.validator_for(schema)(schema)
        part = dict(document, bodies=document["bodies"][: args.jsonschema_bodies])
        start = time.perf_counter()
        errors = list(validator.iter_errors(part))
        elapsed = time.perf_counter() - start
        count = len(part["bodies"])
        print(
            f"jsonschema iter_errors ({count} bodies) {elapsed:8.3f} s  errors: {len(errors)}  "
            f"({elapsed / count * 1e6:.0f} us a body, jsonschema {jsonschema.__version__})"
        )


if __name__ == "__main__":
    main()
