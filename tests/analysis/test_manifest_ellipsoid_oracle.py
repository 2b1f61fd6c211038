"""A manifest's ellipsoids against two oracles: MuJoCo's ``mj_geomDistance`` on the same bodies
written as an MJCF model (its own parser, poses and convex solver), and meshcol's reading of
that MJCF file (``tests/io/test_mjcf_oracle.py`` holds it to MuJoCo on robots).

Each manifest holds ellipsoids among spheres, boxes, capsules and cylinders, turned by
quaternions and by Euler angles (MuJoCo turns them by its own ``eulerseq="XYZ"``, the world
axes, as the manifest's order says); the scaled one also has spheres under an uneven scale
(MJCF: the ellipsoid of the scaled semi-axes) and scaled ellipsoids. The plain one takes the
columns path (``PrimitiveBodies``), the scaled one the body loop.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mujoco_oracle import collision_geoms, least_distance

from meshcol.analysis.check import check_scene
from meshcol.analysis.check_policy import CheckOptions
from meshcol.io.robot import RobotOptions, load_robot
from meshcol.io.scene import load_scene
from meshcol.io.scene_primitives import PrimitiveBodies

mujoco = pytest.importorskip("mujoco", reason="the oracle is MuJoCo (pip install meshcol[robots])")

KINDS = ("ellipsoid", "sphere", "ellipsoid", "box", "ellipsoid", "capsule", "cylinder")


def bodies(seed: int, n: int, scaled: bool) -> list[tuple[dict, str]]:
    """``n`` manifest bodies with the MJCF ``<geom>`` attributes that state each (``type`` and
    ``size``), in a cube 1.6 wide: most pairs apart, some crossing."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        kind = KINDS[i % len(KINDS)]
        axes = rng.uniform(0.05, 0.35, 3)
        body: dict = {"name": f"{kind}{i}", "position": rng.uniform(-0.8, 0.8, 3).tolist()}
        scale = rng.uniform(0.5, 1.5, 3) if scaled and kind in ("sphere", "ellipsoid") else None
        if kind == "ellipsoid":
            body["primitive"] = {"type": "ellipsoid", "semi_axes": axes.tolist()}
            size = axes if scale is None else axes * scale
            geom = ("ellipsoid", size)
        elif kind == "sphere":
            body["primitive"] = {"type": "sphere", "radius": float(axes[0])}
            geom = ("sphere", axes[:1]) if scale is None else ("ellipsoid", axes[0] * scale)
        elif kind == "box":
            body["primitive"] = {"type": "box", "size": (2 * axes).tolist()}
            geom = ("box", axes)
        else:
            body["primitive"] = {"type": kind, "radius": float(axes[0]), "length": 2 * axes[1]}
            geom = (kind, axes[:2])
        if scale is not None:
            body["scale"] = scale.tolist()
        attributes = f'type="{geom[0]}" size="{" ".join(map(repr, map(float, geom[1])))}"'
        if i % 3 == 0:
            quaternion = rng.normal(size=4)
            body["rotation"] = {"quaternion": quaternion.tolist()}
            attributes += f' quat="{" ".join(map(repr, quaternion.tolist()))}"'
        elif i % 3 == 1:
            angles = rng.uniform(-180, 180, 3)
            body["rotation"] = {"euler_deg": angles.tolist(), "order": "xyz"}
            attributes += f' euler="{" ".join(map(repr, angles.tolist()))}"'
        out.append((body, attributes))
    return out


def write(folder: Path, seed: int, n: int, scaled: bool) -> tuple[Path, Path]:
    """The manifest and the MJCF model of the same bodies (each a free body at its pose)."""
    made = bodies(seed, n, scaled)
    manifest = folder / "scene.json"
    manifest.write_text(json.dumps({"units": "m", "bodies": [body for body, _ in made]}))
    lines = ['<mujoco model="manifest">', '  <compiler angle="degree" eulerseq="XYZ"/>']
    lines.append("  <worldbody>")
    for body, attributes in made:
        position = " ".join(map(repr, body["position"]))
        lines.append(f'    <body name="{body["name"]}" pos="{position}">')
        lines.append(f"      <freejoint/><geom {attributes}/>")
        lines.append("    </body>")
    lines += ["  </worldbody>", "</mujoco>"]
    model = folder / "scene.xml"
    model.write_text("\n".join(lines) + "\n")
    return manifest, model


def mujoco_distances(model_path: Path) -> dict[tuple[str, str], float]:
    """Per body pair (names, sorted): MuJoCo's least signed distance between their geoms."""
    model = mujoco.MjModel.from_xml_path(str(model_path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    by_body = collision_geoms(mujoco, model)
    names = sorted(by_body)
    return {
        (a, b): least_distance(mujoco, model, data, by_body[a], by_body[b])
        for i, a in enumerate(names)
        for b in names[i + 1 :]
    }


def distances(report) -> dict[tuple[str, str], float]:
    return {tuple(sorted((p["body_a"], p["body_b"]))): p["signed_distance"] for p in report.pairs}


@pytest.mark.parametrize("scaled", [False, True], ids=["columns", "scaled"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_manifests_ellipsoids_measure_as_mujoco_and_the_mjcf_file(tmp_path, seed, scaled):
    manifest, model = write(tmp_path, seed, 21, scaled)
    scene = load_scene(manifest)
    assert isinstance(scene.bodies, PrimitiveBodies) != scaled
    options = CheckOptions(clearance=100.0)
    report = check_scene(scene, options)
    measured = distances(report)
    assert len(measured) == 21 * 20 // 2
    by_body = {b["name"]: b for b in report.bodies}
    assert {b["collider"] for b in by_body.values()} == {"primitive"}
    # meshcol's own reading of the MJCF file: the same exact shapes at MuJoCo's poses; a depth
    # within EPA's tolerance on curved shapes (1e-7 relative)
    robot = check_scene(load_robot(model, RobotOptions()), options)
    from_mjcf = distances(robot)
    assert from_mjcf.keys() == measured.keys()
    for pair, distance in measured.items():
        tolerance = 1e-9 if distance >= 0.0 else 1e-6
        assert abs(distance - from_mjcf[pair]) <= tolerance, (pair, distance, from_mjcf[pair])
    # MuJoCo: separated pairs to 1e-9 m; a crossing pair by its sign only (MuJoCo's depth is
    # its contact solver's, not the translation that separates the shapes)
    oracle = mujoco_distances(model)
    separated = crossing = with_ellipsoid = 0
    for pair, distance in measured.items():
        expected = oracle[pair]
        if expected >= 0.0 and distance >= 0.0:
            assert abs(distance - expected) <= 1e-9, (pair, distance, expected)
            separated += 1
            with_ellipsoid += any(name.startswith("ellipsoid") for name in pair)
        else:
            assert (distance < -1e-9) == (expected < -1e-9), (pair, distance, expected)
            crossing += 1
    assert separated >= 150 and with_ellipsoid >= 90 and crossing >= 1, (
        separated,
        with_ellipsoid,
        crossing,
    )
