"""``meshcol fit`` of a manifest of primitive bodies (issue 32 item 4 follow-up): the time of
:func:`meshcol.analysis.fit.fit` per shape on ``bench_scale.primitives_folder(N,
"ellipsoids")`` (spheres, boxes, capsules, cylinders and ellipsoids in turn, a third of them
rotated), the manifest loaded once beforehand and not timed. Run it with each build's Python
for an A/B (the closed forms against the tessellation they replaced):

    .venv/bin/python benchmarks/bench_fit_primitives.py --bodies 100000
    ../base/.venv/bin/python benchmarks/bench_fit_primitives.py --bodies 100000
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import primitives_folder


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--bodies", type=int, default=100_000)
    parser.add_argument("--shapes", default="sphere,box,ellipsoid,cylinder,auto")
    args = parser.parse_args()
    import meshcol
    from meshcol.analysis.fit import fit
    from meshcol.io.scene import load_scene

    scene = load_scene(primitives_folder(args.bodies, "ellipsoids") / "scene.json")
    print(f"meshcol {meshcol.__file__}: {len(scene.bodies)} primitive bodies")
    _closed_forms([b.primitive for b in scene.bodies])
    for shape in args.shapes.split(","):
        start = time.perf_counter()
        report = fit(scene, shape=shape)
        seconds = time.perf_counter() - start
        volume = sum(row["volume"] for row in report.bodies)
        shapes = {k: v for k, v in report.summary["shapes"].items() if v}
        print(f"  {shape:9s} {seconds:8.3f} s  total volume {volume:.6f}  {shapes}")


def _closed_forms(primitives: list) -> None:
    """The batch alone (this build's closed forms, when it has them): the sphere's, box's
    and ellipsoid's closed forms and the largest gaps of the box around each (a search),
    on arrays of parameters."""
    import numpy as np

    try:
        from meshcol.collision.primitive_fit import (
            closed_form_fits,
            largest_gaps,
            primitive_parameters,
        )
    except ImportError:
        return
    start = time.perf_counter()
    kind, params = primitive_parameters(primitives)
    middle = time.perf_counter()
    forms = [closed_form_fits(kind, params, s) for s in ("sphere", "box", "ellipsoid")]
    fitted = time.perf_counter()
    box = forms[1]  # the box's gaps are searched (the sphere's are closed forms)
    poses = np.broadcast_to(np.eye(4), (len(kind), 4, 4))
    largest_gaps(kind, params, np.full_like(kind, 2), box.params, poses)
    end = time.perf_counter()
    print(
        f"  batch: parameters {middle - start:.3f} s, sphere+box+ellipsoid closed forms "
        f"{fitted - middle:.3f} s, box gaps {end - fitted:.3f} s"
    )


if __name__ == "__main__":
    main()
