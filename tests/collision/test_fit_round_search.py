"""The cylinder and capsule fits bit for bit as the search before its lower bounds.

The axis polish of both fits turns a trial axis down without fitting it when a lower bound
proves it no better than the best so far (``cpp/src/fit.cpp``, ``RoundSearch``): a wrong
bound would turn down a better axis and change the fit. The fits of seeded point sets of
several kinds are compared with those of main a83d55a, which fitted every trial in full
(``tests/data/fit_round_a83d55a.json``, written by this module run as a script with that
build's interpreter).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from meshcol.collision.fit import fit_batch

RECORD = Path(__file__).parents[1] / "data" / "fit_round_a83d55a.json"
SHAPES = ("capsule", "cylinder")


def point_sets() -> list[np.ndarray]:
    """Seeded sets: blobs, box corners with noise, rods, discs, and a few duplicated points."""
    sets = []
    for seed in range(48):
        rng = np.random.default_rng(seed)
        kind = seed % 6
        n = int(rng.integers(8, 60))
        if kind == 0:  # a blob
            points = rng.normal(size=(n, 3))
        elif kind == 1:  # a box's corners, stretched and turned, with noise
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            points = corners * rng.uniform(0.2, 2.0, size=3) + rng.normal(scale=0.01, size=(8, 3))
        elif kind == 2:  # a rod
            points = rng.normal(size=(n, 3)) * [0.1, 0.15, 2.0]
        elif kind == 3:  # a disc
            points = rng.normal(size=(n, 3)) * [1.0, 1.2, 0.05]
        elif kind == 4:  # points on a sphere
            points = rng.normal(size=(n, 3))
            points /= np.linalg.norm(points, axis=1, keepdims=True)
        else:  # a prism of a random polygon, with repeated points
            angles = np.sort(rng.uniform(0, 2 * np.pi, size=7))
            ring = np.column_stack([np.cos(angles), np.sin(angles)])
            points = np.vstack([np.column_stack([ring, np.full(7, h)]) for h in (-0.7, 0.7)])
            points = np.vstack([points, points[:3]])
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        sets.append(points @ (q * np.sign(np.diag(r))).T + rng.normal(size=3))
    return sets


def fitted() -> dict[str, list[str]]:
    """Each shape's parameters, pose and volume of every set, as exact hex floats."""
    batch = fit_batch(point_sets(), SHAPES, threads=1)
    out = {}
    for k, shape in enumerate(SHAPES):
        values = np.concatenate(
            [batch.params[:, k].reshape(-1), batch.poses[:, k].reshape(-1), batch.volume[:, k]]
        )
        out[shape] = [float(v).hex() for v in values]
    return out


def test_the_round_fits_equal_the_full_search_bit_for_bit():
    recorded = json.loads(RECORD.read_text())
    now = fitted()
    for shape in SHAPES:
        assert now[shape] == recorded[shape], shape


if __name__ == "__main__":  # with main a83d55a's interpreter: write the record
    RECORD.write_text(json.dumps(fitted(), indent=0) + "\n")
    sys.exit(0)
