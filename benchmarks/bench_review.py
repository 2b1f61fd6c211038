"""Review pages (``--html``): size and write time on samples/level, against trimesh's
``scene_to_html`` (the same meshes as one GLB in trimesh's bundled three.js page, no colliders,
no table) as the peer. Rounds alternate meshcol and the peer; ranges are min-max.

    .venv/bin/python benchmarks/bench_review.py [--rounds 7]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LEVEL = ROOT / "samples" / "level" / "scene.json"


def meshcol_page(out: str) -> tuple[float, float, int]:
    """Seconds to build and write the check page (the check itself excluded), seconds of the
    whole ``meshcol check --html`` command, page bytes."""
    from meshcol.analysis.check import check
    from meshcol.analysis.review import check_page
    from meshcol.io.review import write_review

    inputs = [str(LEVEL)]
    report = check(inputs)
    start = time.perf_counter()
    size = write_review(out, check_page(report, inputs, "hull", {}))
    page_seconds = time.perf_counter() - start
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "meshcol", "check", *inputs, "--report", os.devnull, "--html", out],
        capture_output=True,
        check=False,
    )
    return page_seconds, time.perf_counter() - start, size


def trimesh_page(out: str) -> tuple[float, int]:
    import trimesh
    import trimesh.viewer.notebook as notebook

    from meshcol.io.scene import load_inputs

    scene = load_inputs([str(LEVEL)])
    start = time.perf_counter()
    ts = trimesh.Scene()
    for body in scene.bodies:
        ts.add_geometry(
            trimesh.Trimesh(body.vertices, body.faces, process=False), transform=body.pose
        )
    text = notebook.scene_to_html(ts)
    Path(out).write_text(text)
    return time.perf_counter() - start, len(text.encode())


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=7)
    rounds = parser.parse_args().rounds
    page_t, cli_t, peer_t = [], [], []
    size = peer_size = 0
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(rounds):
            a, b, size = meshcol_page(os.path.join(folder, "meshcol.html"))
            page_t.append(a)
            cli_t.append(b)
            c, peer_size = trimesh_page(os.path.join(folder, "trimesh.html"))
            peer_t.append(c)

    def rng(values: list[float]) -> str:
        v = np.asarray(values) * 1000
        return f"{v.min():.0f}-{v.max():.0f} ms (median {np.median(v):.0f})"

    print(f"samples/level (25 bodies), {rounds} alternated rounds")
    print(f"meshcol page build + write : {rng(page_t)}, {size / 1e6:.2f} MB")
    print(f"meshcol check --html (CLI) : {rng(cli_t)}")
    print(f"trimesh scene_to_html      : {rng(peer_t)}, {peer_size / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
