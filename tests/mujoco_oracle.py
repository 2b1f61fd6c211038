"""MuJoCo as the oracle of what meshcol measures on MJCF robots: each body's collision geoms,
the least ``mj_geomDistance`` between two bodies' geoms, and collision-matrix's samples drawn
again. Shared by tests/io/test_mjcf_oracle.py, tests/analysis/test_collision_matrix_oracle.py
and benchmarks/robots_oracle.py; MuJoCo is imported by the callers (a test skips without it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from meshcol.io.kinematics import apply_mjcf_followers, mjcf_followers
from meshcol.io.mjcf import read_mjcf
from meshcol.io.robot import RobotOptions


def collision_geoms(mujoco: Any, model: Any) -> dict[str, list[int]]:
    """Body name -> its collision geoms as meshcol reads them (``contype`` or ``conaffinity``
    non-zero; no planes or height fields: not solids)."""
    solid = (np.asarray(model.geom_contype) != 0) | (np.asarray(model.geom_conaffinity) != 0)
    skip = {int(mujoco.mjtGeom.mjGEOM_PLANE), int(mujoco.mjtGeom.mjGEOM_HFIELD)}
    geoms: dict[str, list[int]] = {}
    for g in range(model.ngeom):
        if solid[g] and int(model.geom_type[g]) not in skip:
            body = int(model.geom_bodyid[g])
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body{body}"
            geoms.setdefault(name, []).append(g)
    return geoms


def has_ellipsoid(mujoco: Any, model: Any, geoms: list[int]) -> bool:
    ellipsoid = int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)
    return any(int(model.geom_type[g]) == ellipsoid for g in geoms)


def least_distance(
    mujoco: Any, model: Any, data: Any, a: list[int], b: list[int], most: float = 100.0
) -> float:
    """The least signed ``mj_geomDistance`` between geoms ``a`` and ``b`` (capped at ``most``)."""
    return min(mujoco.mj_geomDistance(model, data, x, y, most, None) for x in a for y in b)


def check_qpos(path: Path, options: RobotOptions | None = None) -> np.ndarray:
    """The configuration check reads the robot at (followers applied)."""
    kinematics = read_mjcf(str(path), options or RobotOptions()).kinematics
    return np.asarray(kinematics.qpos)


def matrix_qpos(mujoco: Any, model: Any, path: Path, report: dict) -> np.ndarray:
    """(samples, nq): collision-matrix's configurations, from its report's joints and settings
    (``JointSpace.sample``: PCG64 from the seed, ``lower + (upper - lower) * random((n, d))``),
    over the configuration check reads, followers applied."""
    joints = report["joints"]
    lower = np.array([j["lower"] for j in joints], dtype=np.float64)
    upper = np.array([j["upper"] for j in joints], dtype=np.float64)
    samples = int(report["settings"]["samples"])
    rng = np.random.default_rng(report["settings"]["seed"])
    q = lower + (upper - lower) * rng.random((samples, len(joints)))
    joint = mujoco.mjtObj.mjOBJ_JOINT
    adrs = [model.jnt_qposadr[mujoco.mj_name2id(model, joint, j["name"])] for j in joints]
    qpos = np.repeat(check_qpos(path)[None], samples, axis=0)
    qpos[:, adrs] = q
    apply_mjcf_followers(model, qpos, mjcf_followers(model))
    return qpos
