"""Every body pair of every wild MJCF scene with a plane, meshcol against MuJoCo itself.

For each scene of ``plane_wild.py``'s list: ``meshcol check SCENE [--keyframe] --clearance
1000`` (every pair within 1000 m a row), and MuJoCo at the configuration meshcol read it at,
with every ``geom_margin``, ``body_margin`` and ``pair_margin`` raised to 1000, so that
``mj_collision`` reports a contact for every geom pair its filters let through (bitmask,
welds, parents, ``<exclude>``, ``<pair>``). Each body pair's smallest contact ``dist`` is
compared with meshcol's signed distance of that pair. Scenes whose contacts overflow MuJoCo's
arena (its warning counter) are counted apart: their contact lists are incomplete.

    .venv/bin/python benchmarks/mjcf_pairs_wild.py [--meshcol M] [--only unitree_g1] [--show 10]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mujoco
import numpy as np
from plane_wild import MARGIN, _check, compiles, scenes

from meshcol.io.robot import RobotOptions, load_robot_model


def mujoco_body_pairs(path: Path, keyframe: bool) -> dict[frozenset, float] | None:
    """{body pair: MuJoCo's smallest contact dist}, bodies named as meshcol names them (a
    plane ``<body>/<geom>``); None when the contacts overflowed the arena."""
    robot = load_robot_model(path, RobotOptions(keyframe=keyframe, half_spaces=True))
    model = robot.kinematics.model
    data = mujoco.MjData(model)
    data.qpos[:] = robot.kinematics.qpos
    model.geom_margin[:] = MARGIN
    model.body_margin[:] = MARGIN
    model.pair_margin[:] = MARGIN
    mujoco.mj_fwdPosition(model, data)
    full = (mujoco.mjtWarning.mjWARN_CONTACTFULL, mujoco.mjtWarning.mjWARN_CNSTRFULL)
    if any(data.warning[int(w)].number for w in full):
        return None
    names = robot.kinematics.links
    plane = int(mujoco.mjtGeom.mjGEOM_PLANE)

    def body(g: int) -> str:
        owner = names[int(model.geom_bodyid[g])]
        if int(model.geom_type[g]) != plane:
            return owner
        return f"{owner}/{mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f'plane{g}'}"

    out: dict[frozenset, float] = {}
    for contact in data.contact[: data.ncon]:
        key = frozenset((body(int(contact.geom1)), body(int(contact.geom2))))
        out[key] = min(out.get(key, np.inf), float(contact.dist))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshcol", default=str(Path(sys.executable).parent / "meshcol"))
    parser.add_argument("--site", default=str(Path(np.__file__).parents[1]))
    parser.add_argument("--only", action="append", default=[], help="path holds this")
    parser.add_argument("--show", type=int, default=10, help="worst differences listed")
    args = parser.parse_args()
    site = Path(args.site)
    counts = dict(scenes=0, skipped=0, overflow=0, both=0, only_meshcol=0, only_mujoco=0)
    worst: list[tuple[float, str]] = []
    for path in scenes(site):
        if args.only and not any(part in str(path) for part in args.only):
            continue
        counts["scenes"] += 1
        keyframe = compiles(path) and mujoco.MjModel.from_xml_path(str(path)).nkey > 0
        run, report = _check(args.meshcol, path, keyframe)
        if run.returncode == 2 and keyframe:
            keyframe = False
            run, report = _check(args.meshcol, path, keyframe)
        if report is None:
            counts["skipped"] += 1
            continue
        theirs = mujoco_body_pairs(path, keyframe)
        if theirs is None:
            counts["overflow"] += 1
            continue
        ours = {
            frozenset((p["body_a"], p["body_b"])): p["signed_distance"] for p in report["pairs"]
        }
        counts["only_meshcol"] += len(set(ours) - set(theirs))
        counts["only_mujoco"] += len(set(theirs) - set(ours))
        for key in set(ours) & set(theirs):
            counts["both"] += 1
            name = f"{path.relative_to(site)}: {' <-> '.join(sorted(key))}"
            worst.append(
                (abs(ours[key] - theirs[key]), f"{name} {ours[key]:.9g} {theirs[key]:.9g}")
            )
    print(", ".join(f"{k} {v}" for k, v in counts.items()))
    for difference, line in sorted(worst, reverse=True)[: args.show]:
        print(f"  {difference:.3g}  {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
