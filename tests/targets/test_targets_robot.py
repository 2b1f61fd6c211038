"""``meshcol hull|decompose ROBOT --out-dir OUT --target NAME``: the rebuilt description is
read back by readers that are not meshcol's (yourdfpy for URDF, MuJoCo's compiler for MJCF),
every collider it names meets the profile's limits by an independent count
(tests/target_oracle.py, scipy's hull), hulls enclose their element's input mesh, and the
report carries each link part's target entry and validates against its schema."""

# The fixtures urdf, mjcf and panda come from test_robot_write (one copy); as test parameters they
# shadow the imported names, which is how pytest finds them.
# ruff: noqa: F811

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from conftest import FAST_DECOMPOSE
from target_oracle import encloses, missed
from test_fit_robot import urdf_input_meshes
from test_robot_write import mjcf, panda, run, urdf  # noqa: F401 - the fixtures

from meshcol.io.targets import load_target

yourdfpy = pytest.importorskip("yourdfpy")
mujoco = pytest.importorskip("mujoco")

SCHEMAS = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"
#: Coplanar within float32 rounding (MuJoCo compiles vertices to float32).
FLOAT32_PLANES = 1e-5
JOINTS = {"j1": 0.4, "j3": 0.01}


def validate(data: dict, command: str) -> None:
    schema = json.loads((SCHEMAS / f"{command}_report.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(data)


def decompose_to(urdf: Path, out: Path, report: Path, target: str, *extra: str):
    """``meshcol decompose URDF --out-dir OUT --target T --report R`` at the fast settings."""
    return run(
        "decompose",
        str(urdf),
        "--out-dir",
        str(out),
        "--target",
        target,
        *extra,
        "--report",
        str(report),
        *FAST_DECOMPOSE,
    )


def urdf_colliders(path: Path, cfg: dict) -> dict[str, list[np.ndarray]]:
    """World vertices of every collision mesh of a URDF, by link, as yourdfpy loads it."""
    import trimesh

    model = yourdfpy.URDF.load(str(path))
    model.update_cfg(cfg)
    out: dict[str, list[np.ndarray]] = {}
    for link in model.robot.links:
        for c in link.collisions:
            if c.geometry.mesh is None:
                continue
            file = model._filename_handler(c.geometry.mesh.filename)
            v = np.asarray(trimesh.load(str(file), force="mesh").vertices)
            world = model.get_transform(link.name) @ (
                c.origin if c.origin is not None else np.eye(4)
            )
            out.setdefault(link.name, []).append(v @ world[:3, :3].T + world[:3, 3])
    return out


def mjcf_colliders(path: Path) -> dict[str, list[np.ndarray]]:
    """Mesh collision geoms of an MJCF, by body, as MuJoCo compiles them (world frame)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    out: dict[str, list[np.ndarray]] = {}
    for g in range(model.ngeom):
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            continue
        m = model.geom_dataid[g]
        v = model.mesh_vert[model.mesh_vertadr[m] : model.mesh_vertadr[m] + model.mesh_vertnum[m]]
        rotation = data.geom_xmat[g].reshape(3, 3)
        body = model.body(model.geom_bodyid[g]).name
        out.setdefault(body, []).append(v @ rotation.T + data.geom_xpos[g])
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["physx-gpu", "unity"])
def test_hull_robot_target_meets_every_limit_and_encloses(urdf: Path, tmp_path: Path, name):
    out, report = tmp_path / "out", tmp_path / "hull.json"
    code, _, stderr = run(
        "hull", str(urdf), "--out-dir", str(out), "--target", name, "--report", str(report)
    )
    assert code == 0, stderr
    data = json.loads(report.read_text())
    validate(data, "hull")
    assert data["settings"]["target"] == name
    target = load_target(name)
    assert data["bodies"] and all(row["target"]["met"] for row in data["bodies"])
    for row in data["bodies"]:  # costs per link part, in the order applied, adding up
        costs = row["target"]["costs"]
        assert [c["order"] for c in costs] == list(range(len(costs)))
        assert sum(c["marginal_added_volume"] for c in costs) == pytest.approx(
            row["target"]["added_volume"], abs=1e-12
        )
    written = urdf_colliders(out / urdf.name, JOINTS)
    inputs = urdf_input_meshes(urdf, JOINTS)
    assert set(written) == set(inputs)
    for link, clouds in inputs.items():
        parts = written[link]
        assert missed(parts, target.limits) == set(), link
        for cloud in clouds:  # each element's hull holds its mesh
            assert any(encloses(p, cloud, tol=1e-6) for p in parts), link


@pytest.mark.slow
def test_hull_robot_target_to_mjcf_compiles_and_meets_limits(urdf: Path, tmp_path: Path):
    out = tmp_path / "out"
    code, _, stderr = run(
        "hull", str(urdf), "--out-dir", str(out), "--to", "mjcf", "--target", "physx-gpu"
    )
    assert code == 0, stderr
    (xml,) = out.glob("*.xml")
    colliders = mjcf_colliders(xml)
    assert colliders
    limits = load_target("physx-gpu").limits
    for body, parts in colliders.items():  # MuJoCo keeps float32 vertices
        assert missed(parts, limits, plane_tol=FLOAT32_PLANES) == set(), body


def test_hull_mjcf_robot_target(mjcf: Path, tmp_path: Path):
    out = tmp_path / "out"
    code, _, stderr = run("hull", str(mjcf), "--out-dir", str(out), "--target", "mujoco")
    assert code == 0, stderr
    colliders = mjcf_colliders(out / mjcf.name)
    assert colliders
    for body, parts in colliders.items():
        assert not missed(parts, load_target("mujoco").limits, plane_tol=FLOAT32_PLANES), body


@pytest.mark.slow
def test_decompose_robot_target_every_part_meets_the_limits(urdf: Path, tmp_path: Path):
    out, report = tmp_path / "out", tmp_path / "d.json"
    code, _, stderr = decompose_to(urdf, out, report, "physx-gpu", "--no-cache")
    assert code == 0, stderr
    data = json.loads(report.read_text())
    validate(data, "decompose")
    assert data["settings"]["target"] == "physx-gpu"
    bodies = data["files"][0]["bodies"]
    assert bodies and all(b["target_ok"] and b["target"]["name"] == "physx-gpu" for b in bodies)
    for b in bodies:
        costs = b["target"]["costs"]
        assert sum(c["marginal_added_volume"] for c in costs) == pytest.approx(
            b["target"]["added_volume"], abs=1e-12
        )
    limits = load_target("physx-gpu").limits
    written = urdf_colliders(out / urdf.name, JOINTS)
    assert set(written) == set(urdf_input_meshes(urdf, JOINTS))
    for link, parts in written.items():
        assert missed(parts, limits) == set(), link


def test_decompose_robot_target_that_cannot_be_met_names_the_rule(urdf: Path, tmp_path: Path):
    profile = tmp_path / "round.toml"
    profile.write_text('title = "Round"\n[limits]\nmax_oblong_ratio = 1.0\n')
    out, report = tmp_path / "out", tmp_path / "d.json"
    code, _, stderr = decompose_to(urdf, out, report, str(profile))
    assert code == 1, stderr
    assert "MC102 not-gpu-compatible-oblong" in stderr
    data = json.loads(report.read_text())
    validate(data, "decompose")
    assert not any(b["target_ok"] for b in data["files"][0]["bodies"])


@pytest.mark.slow
def test_decompose_robot_shares_max_hulls_among_an_elements_objects(urdf: Path, tmp_path: Path):
    # the arm's collision mesh file holds two objects: with max_hulls 2 each gets one part,
    # with max_hulls 1 the element cannot meet it (each object keeps a part): MC106
    for count, code_expected in ((2, 0), (1, 1)):
        profile = tmp_path / f"hulls{count}.toml"
        profile.write_text(f'title = "Hulls"\n[limits]\nmax_hulls = {count}\n')
        out, report = tmp_path / f"out{count}", tmp_path / f"d{count}.json"
        code, _, stderr = decompose_to(urdf, out, report, str(profile))
        assert code == code_expected, stderr
        data = json.loads(report.read_text())
        validate(data, "decompose")
        arm = [b for b in data["files"][0]["bodies"] if b["name"].startswith("arm/")]
        assert len(arm) == 2 and all(b["target"]["max_hulls_share"] == 1 for b in arm)
        written = urdf_colliders(out / urdf.name, JOINTS)
        assert len(written["arm"]) == 2
        if count == 1:
            assert "MC106 hull-count-over-limit" in stderr and "arm" in stderr
            assert arm[-1]["target_ok"] is False
        else:
            assert all(len(parts) <= count for parts in written.values())


@pytest.mark.slow
def test_panda_hulls_meet_physx_gpu_and_enclose_its_meshes(panda: Path, tmp_path: Path):
    out, report = tmp_path / "out", tmp_path / "hull.json"
    code, _, stderr = run(
        "hull", str(panda), "--out-dir", str(out), "--target", "physx-gpu", "--report", str(report)
    )
    assert code == 0, stderr
    validate(json.loads(report.read_text()), "hull")
    joints = {"panda_joint2": -0.5, "panda_joint4": -2.0, "panda_finger_joint1": 0.02}
    written = urdf_colliders(out / panda.name, joints)
    inputs = urdf_input_meshes(panda, joints)
    limits = load_target("physx-gpu").limits
    assert set(written) == set(inputs) and len(written) == 9
    for link, clouds in inputs.items():
        assert missed(written[link], limits) == set(), link
        for cloud in clouds:
            assert any(encloses(p, cloud, tol=1e-6) for p in written[link]), link
