"""``meshcol fit`` of a manifest of primitive bodies: the closed forms, exact in the report
(no tessellation, no margin), the primitive's own volume as the hull's, ``auto`` keeping each
primitive as it is (an ellipsoid too), the gap to the exact primitive, and a manifest of
many primitives in one batch (:func:`meshcol.analysis.fit.fit_bodies` against its one-body
form)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.analysis.fit import fit_bodies, fit_body
from meshcol.cli import main
from meshcol.io.scene import load_scene

SCHEMA = Path(__file__).resolve().parents[2] / "meshcol" / "schemas" / "fit_report.schema.json"

BODIES = [
    {"name": "s", "primitive": {"type": "sphere", "radius": 0.5}},
    {
        "name": "e",
        "primitive": {"type": "ellipsoid", "semi_axes": [0.3, 0.2, 0.1]},
        "position": [1, 0, 0],
    },
    {"name": "b", "primitive": {"type": "box", "size": [1, 2, 3]}, "position": [3, 0, 0]},
]


def _fit(tmp_path: Path, shape: str, bodies=BODIES) -> dict:
    scene, report = tmp_path / "scene.json", tmp_path / f"{shape}.json"
    scene.write_text(json.dumps({"bodies": bodies}))
    result = CliRunner().invoke(
        main, ["fit", str(scene), "--shape", shape, "--format", "json", "--report", str(report)]
    )
    assert result.exit_code == 0, result.output
    data = json.loads(report.read_text())
    jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text())).validate(data)
    return {row["name"]: row for row in data["bodies"]} | {"summary": data["summary"]}


def test_closed_forms_are_exact_in_the_report(tmp_path: Path) -> None:
    sphere = _fit(tmp_path, "sphere")
    assert sphere["s"]["radius"] == 0.5 and sphere["s"]["max_gap"] == 0.0
    assert sphere["e"]["radius"] == 0.3
    assert sphere["b"]["radius"] == 0.5 * math.sqrt(14.0)
    assert sphere["b"]["center"] == [3.0, 0.0, 0.0]
    box = _fit(tmp_path, "box")
    assert box["s"]["size"] == [1.0, 1.0, 1.0]
    assert box["b"]["size"] == [1.0, 2.0, 3.0] and box["b"]["max_gap"] == 0.0
    assert box["e"]["size"] == [0.6, 0.4, 0.2]
    assert box["s"]["max_gap"] == pytest.approx(0.5 * (math.sqrt(3.0) - 1.0), rel=1e-12)
    ellipsoid = _fit(tmp_path, "ellipsoid")
    assert ellipsoid["e"]["size"] == [0.6, 0.4, 0.2] and ellipsoid["e"]["max_gap"] == 0.0
    assert ellipsoid["s"]["size"] == [1.0, 1.0, 1.0]
    assert ellipsoid["b"]["size"] == pytest.approx(np.sqrt(3.0) * np.array([3, 2, 1]), rel=1e-15)
    volumes = {"s": math.pi / 6.0, "e": 4.0 / 3.0 * math.pi * 0.006, "b": 6.0}
    for name, volume in volumes.items():
        assert sphere[name]["hull_volume"] == pytest.approx(volume, rel=1e-15)
        assert sphere[name]["mesh_volume"] == sphere[name]["hull_volume"]


def test_auto_keeps_each_primitive(tmp_path: Path) -> None:
    auto = _fit(tmp_path, "auto")
    assert [auto[n]["shape"] for n in "seb"] == ["sphere", "ellipsoid", "box"]
    assert auto["s"]["radius"] == 0.5
    assert auto["e"]["size"] == [0.6, 0.4, 0.2]
    for name in "seb":
        assert auto[name]["hull_ratio"] == 1.0 and auto[name]["volume_ratio"] == 1.0
        assert auto[name]["max_gap"] == 0.0
        assert set(auto[name]["candidates"]) == {"sphere", "capsule", "box", "cylinder"}
        assert auto[name]["simpler_primitive"] is False  # already a primitive: no advice
    assert auto["summary"]["simpler_primitive"] == 0
    assert auto["summary"]["shapes"] == {
        "sphere": 1,
        "capsule": 0,
        "box": 1,
        "cylinder": 0,
        "hull": 0,
        "ellipsoid": 1,
    }


def test_pairs_without_a_closed_form_keep_the_point_fit(tmp_path: Path) -> None:
    """A capsule around an ellipsoid: the point-set fit of the enclosing tessellation, which
    contains the ellipsoid; its gap is to the exact ellipsoid."""
    capsule = _fit(tmp_path, "capsule")
    assert capsule["s"]["radius"] == 0.5 and capsule["s"]["length"] == 0.0
    assert capsule["e"]["radius"] >= 0.2 and capsule["e"]["radius"] < 0.2 * 1.01
    cylinder = _fit(tmp_path, "cylinder")
    assert cylinder["s"]["radius"] == 0.5 and cylinder["s"]["length"] == 1.0
    assert cylinder["b"]["max_gap"] > 0


@pytest.mark.slow  # 3-8 s: the fast lane (make test-fast) stays under 40 s
def test_many_primitives_in_one_batch_match_one_by_one(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    kinds = ["sphere", "box", "capsule", "cylinder", "ellipsoid"]
    bodies = []
    for i in range(20):  # four of each kind: the batch groups by kind
        kind = kinds[i % 5]
        a, b, c = (float(v) for v in rng.uniform(0.1, 2.0, 3))
        primitive = {
            "sphere": {"type": "sphere", "radius": a},
            "box": {"type": "box", "size": [a, b, c]},
            "capsule": {"type": "capsule", "radius": a, "length": b},
            "cylinder": {"type": "cylinder", "radius": a, "length": b},
            "ellipsoid": {"type": "ellipsoid", "semi_axes": [a, b, c]},
        }[kind]
        bodies.append(
            {"name": f"p{i}", "primitive": primitive, "position": rng.normal(size=3).tolist()}
        )
    path = tmp_path / "many.json"
    path.write_text(json.dumps({"bodies": bodies}))
    scene = load_scene(path)
    for shape in ("sphere", "ellipsoid", "auto", "cylinder"):
        batch = fit_bodies(scene.bodies, shape)
        for body, (fits, volume, gap) in zip(scene.bodies, batch):  # type: ignore[misc]
            one, one_volume, one_gap = fit_body(body, shape)
            chosen, alone = fits.primitive_fit, one.primitive_fit
            assert chosen.primitive == alone.primitive and np.array_equal(chosen.pose, alone.pose)
            assert (volume, gap, fits.chosen) == (one_volume, one_gap, one.chosen)
