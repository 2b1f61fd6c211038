"""``meshcol fit``'s largest gap of a mesh body in the report: a lower bound within the grid's
spacing of the exact gap (:mod:`meshcol.collision.primitive_surface`), whatever the body's
pose, and 0 for a box around a box."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import centred_cube_obj

from meshcol.analysis.fit import GAP_SAMPLES
from meshcol.cli import main

CUBE_OBJ = centred_cube_obj(1)


def _rows(tmp_path: Path, shape: str) -> dict[str, dict]:
    (tmp_path / "cube.obj").write_text(CUBE_OBJ + "\n")
    turned = {"euler_deg": [30, -50, 70], "order": "xyz"}
    bodies = [
        {"name": "still", "mesh": "cube.obj"},
        {"name": "turned", "mesh": "cube.obj", "position": [5, -2, 1], "rotation": turned},
    ]
    scene, report = tmp_path / "scene.json", tmp_path / "fit.json"
    scene.write_text(json.dumps({"bodies": bodies}))
    result = CliRunner().invoke(
        main, ["fit", str(scene), "--shape", shape, "--format", "json", "--report", str(report)]
    )
    assert result.exit_code == 0, result.output
    return {row["name"]: row for row in json.loads(report.read_text())["bodies"]}


@pytest.mark.parametrize("name", ["still", "turned"])
def test_sphere_around_a_cube_strays_by_radius_minus_one(tmp_path: Path, name: str) -> None:
    row = _rows(tmp_path, "sphere")[name]
    radius = row["radius"]  # sqrt(3) and the fit's margin: the cube's corners are on it
    assert radius == pytest.approx(math.sqrt(3.0), rel=1e-6)
    spacing = math.sqrt(4 * math.pi * radius**2 / GAP_SAMPLES)
    exact = radius - 1.0  # from the sphere's points on the face normals to the faces
    assert exact - spacing <= row["max_gap"] <= exact + 1e-9


@pytest.mark.parametrize("name", ["still", "turned"])
def test_box_around_a_cube_has_no_gap(tmp_path: Path, name: str) -> None:
    row = _rows(tmp_path, "box")[name]
    assert row["max_gap"] == pytest.approx(0.0, abs=1e-6)  # the fit's margin at most
