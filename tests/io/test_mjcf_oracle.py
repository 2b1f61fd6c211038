"""Check's distances on MJCF robots against MuJoCo's own (``mj_geomDistance``), geom by geom.

MuJoCo reads the same file and places the same geoms; for every pair of bodies check
reports, the oracle is the least ``mj_geomDistance`` over their collision geoms (MuJoCo's
analytic sphere, capsule and box distances, its convex solver for cylinders, ellipsoids and
meshes, the latter on its own hull of each mesh). Separated pairs must agree to 1e-9 m
(MuJoCo's convex solver agrees with meshcol's exact ellipsoids to about 1e-11 m on
dm_control's dog, quadruped, fish and humanoid_CMU). Penetrating pairs must agree on the sign
only: MuJoCo's depths are its contact solver's, not the translation that separates them (a
box around a rail capsule in dm_control's cartpole: MuJoCo -0.02, the true depth 0.1).

This oracle found the links of several primitive geoms tessellated for queries (session 37):
gymnasium's humanoid was 1.5e-4 m off; and the ellipsoids, read as tessellations until then,
up to 7.5e-4 m off (dm_control's quadruped).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mujoco_oracle import check_qpos, collision_geoms, has_ellipsoid, least_distance
from wild_collections import collection_file

from meshcol.analysis.check import check_scene
from meshcol.analysis.check_policy import CheckOptions
from meshcol.io.robot import RobotOptions, load_robot

mujoco = pytest.importorskip(
    "mujoco", reason="MJCF reading needs mujoco (pip install meshcol[robots])"
)

#: Our own model: three links of several primitive geoms each (capsules by fromto, spheres,
#: boxes and cylinders turned by Euler angles), on hinges with limits.
PARTS = Path(__file__).resolve().parents[1] / "data" / "mjcf_parts.xml"
#: And one of ellipsoids: alone on a link, beside other primitives, and a flat one.
ELLIPSOIDS = Path(__file__).resolve().parents[1] / "data" / "mjcf_ellipsoids.xml"


def mujoco_distances(path: Path, qpos: np.ndarray) -> dict[tuple[str, str], tuple[float, bool]]:
    """Per body pair (names, sorted): the least ``mj_geomDistance`` over their collision geoms
    (``tests/mujoco_oracle.py``), and whether an ellipsoid is among them."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    by_body = collision_geoms(mujoco, model)
    out = {}
    names = sorted(by_body)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            distance = least_distance(mujoco, model, data, by_body[a], by_body[b])
            out[(a, b)] = (distance, has_ellipsoid(mujoco, model, by_body[a] + by_body[b]))
    return out


def compare(path: Path, options: RobotOptions) -> tuple[int, int, int]:
    """Check's pairs of the robot against MuJoCo's distances: (separated pairs compared,
    penetrating pairs compared, separated pairs with an ellipsoid among them)."""
    scene = load_robot(path, options)
    report = check_scene(scene, CheckOptions(clearance=100.0))
    qpos = check_qpos(path, options)
    oracle = mujoco_distances(path, qpos)
    separated = penetrating = ellipsoids = 0
    for pair in report.pairs:
        a, b = sorted((pair["body_a"], pair["body_b"]))
        expected, ellipsoid = oracle[(a, b)]
        measured = pair["signed_distance"]
        if expected >= 0.0 and measured >= 0.0:
            assert abs(measured - expected) <= 1e-9, (a, b, measured, expected)
            separated += 1
            ellipsoids += ellipsoid
        else:
            assert (measured < -1e-9) == (expected < -1e-9), (a, b, measured, expected)
            penetrating += 1
    return separated, penetrating, ellipsoids


def test_links_of_several_primitive_geoms_match_mujoco_in_many_poses():
    rng = np.random.default_rng(37)
    joints = ("shoulder", "elbow", "hip", "ankle", "hip2", "ankle2")
    limits = {"elbow": 2.0}
    separated = penetrating = 0
    for _ in range(12):
        values = {j: float(rng.uniform(-1, 1) * limits.get(j, 1.0)) for j in joints}
        s, p, _ = compare(PARTS, RobotOptions(joints=values))
        separated += s
        penetrating += p
    assert separated >= 150 and penetrating >= 1, (separated, penetrating)


def test_ellipsoid_geoms_match_mujoco_in_many_poses():
    """Every body of the model has an ellipsoid: read as tessellations, they were up to about
    1e-3 m off here."""
    rng = np.random.default_rng(32)
    joints = {"neck": 0.8, "shoulder": 1.0, "elbow": 1.5, "shoulder2": 1.0, "wag": 1.2}
    separated = penetrating = ellipsoids = 0
    for _ in range(16):
        values = {j: float(rng.uniform(-1, 1) * limit) for j, limit in joints.items()}
        s, p, e = compare(ELLIPSOIDS, RobotOptions(joints=values))
        separated += s
        penetrating += p
        ellipsoids += e
    assert ellipsoids >= 150 and ellipsoids == separated, (separated, ellipsoids, penetrating)


@pytest.mark.parametrize(
    "package, parts, minimum, with_ellipsoid",
    [
        ("gymnasium", ("envs", "mujoco", "assets", "humanoid.xml"), 60, 0),
        ("gymnasium", ("envs", "mujoco", "assets", "humanoidstandup.xml"), 60, 0),
        ("dm_control", ("suite", "humanoid.xml"), 100, 0),
        ("dm_control", ("suite", "manipulator.xml"), 60, 0),
        ("dm_control", ("suite", "quadruped.xml"), 130, 13),
        ("dm_control", ("suite", "dog.xml"), 1500, 140),
        ("dm_control", ("suite", "fish.xml"), 11, 11),
        ("dm_control", ("suite", "humanoid_CMU.xml"), 420, 50),
    ],
)
def test_collection_robots_match_mujoco(package, parts, minimum, with_ellipsoid):
    separated, _, ellipsoids = compare(collection_file(package, *parts), RobotOptions())
    assert separated >= minimum and ellipsoids >= with_ellipsoid, (separated, ellipsoids)
