"""``suspect-units`` of a body's parts (``health.units_by_body``): a part under a centimetre of
a body whose parts together are a plausible size is a detail (the Menagerie Panda's finger
pads, aloha's contact spheres), not a file in other units; a body tiny as a whole, a body of
one tiny mesh and a part too large keep the finding."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from meshcol.cli import main

pytest.importorskip("mujoco")

#: Box half-sizes in metres (MJCF: the file's unit is the metre).
MODEL = """<mujoco>
  <worldbody>
    <body name="finger" pos="0 0 0">
      <geom name="link" type="box" size="0.05 0.01 0.01"/>
      <geom name="pad" type="box" size="0.002 0.002 0.002" pos="0.05 0 0"/>
    </body>
    <body name="pads" pos="1 0 0">
      <geom name="pad_a" type="box" size="0.002 0.002 0.002"/>
      <geom name="pad_b" type="box" size="0.002 0.002 0.002" pos="0.004 0 0"/>
    </body>
    <body name="bead" pos="2 0 0">
      <geom name="bead" type="sphere" size="0.002"/>
    </body>
    <body name="slab" pos="3 0 0">
      <geom name="plate" type="box" size="0.05 0.05 0.01"/>
      <geom name="floor" type="box" size="80 0.01 0.01"/>
    </body>
  </worldbody>
</mujoco>
"""


def _suspect(tmp_path: Path, model: str) -> dict[str, bool]:
    path = tmp_path / "model.xml"
    path.write_text(model)
    report = tmp_path / "r.json"
    result = CliRunner().invoke(main, ["inspect", str(path), "--report", str(report)])
    assert result.exit_code in (0, 1), result.stderr
    rows = json.loads(report.read_text())
    flagged = {
        f["body"] + ("/" + f["part"] if f.get("part") else "")
        for f in rows["findings"]
        if f["name"] == "suspect-units"
    }
    names = [row["name"] for row in rows["bodies"]]
    assert flagged <= set(names)
    for row in rows["bodies"]:  # the row's findings and the records agree
        assert ("suspect-units" in row["findings"]) == (row["name"] in flagged)
    return {name: name in flagged for name in names}


def test_a_tiny_part_of_a_plausible_body_is_not_suspect(tmp_path: Path) -> None:
    suspect = _suspect(tmp_path, MODEL)
    assert suspect == {
        "finger/link": False,
        "finger/pad": False,  # 4 mm, on a 10 cm finger
        "pads/pad_a": True,  # the body is 8 mm as a whole
        "pads/pad_b": True,
        "bead": True,  # a body of one 4 mm mesh
        "slab/plate": False,
        "slab/floor": True,  # 160 m: too large, part or not
    }
