"""``meshcol fit --shape ellipsoid`` on meshes: the report (JSON against its schema, CSV,
markdown), the Unreal part (a ``UCX_`` convex mesh that contains the ellipsoid) and what
stays as it was (``auto`` never takes an ellipsoid)."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial import ConvexHull

from meshcol.cli import main
from meshcol.io.mesh_read import load_mesh

SCHEMA = Path(__file__).resolve().parents[2] / "meshcol" / "schemas" / "fit_report.schema.json"


def _run(*args: str):
    return CliRunner().invoke(main, list(args))


def _vertices(path: Path) -> np.ndarray:
    return np.concatenate([b.world_vertices() for b in load_mesh(path)])


def test_ellipsoid_report_and_unreal_part(samples: Path, tmp_path: Path) -> None:
    props = samples / "level" / "props"
    meshes = [props / "barrel.obj", props / "crate_long.obj"]
    out, report = tmp_path / "colliders.obj", tmp_path / "fits.json"
    result = _run(
        "fit", *map(str, meshes), "--shape", "ellipsoid", "-o", str(out), "--report", str(report)
    )
    assert result.exit_code == 0, result.output
    data = json.loads(report.read_text())
    jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text())).validate(data)
    assert data["settings"]["shape"] == "ellipsoid"
    assert data["summary"]["shapes"] == {
        "sphere": 0,
        "capsule": 0,
        "box": 0,
        "cylinder": 0,
        "hull": 0,
        "ellipsoid": 2,
    }
    parts: dict[str, list] = {}  # the OBJ's objects and their vertices
    for line in out.read_text().splitlines():
        if line.startswith("o "):
            name = line.split()[1]
            parts[name] = []
        elif line.startswith("v "):
            parts[name].append([float(v) for v in line.split()[1:4]])
    assert set(parts) == {"UCX_barrel_00", "UCX_crate_long_00"}
    for row, mesh in zip(data["bodies"], meshes):
        assert row["shape"] == "ellipsoid" and row["radius"] is None and row["length"] is None
        semi = np.asarray(row["size"]) / 2.0
        assert row["volume"] == pytest.approx(4.0 / 3.0 * np.pi * np.prod(semi), rel=1e-12)
        assert row["hull_ratio"] >= 1.0 and row["max_gap"] > 0.0
        # every vertex inside the reported ellipsoid (world frame), and inside the part written
        points = _vertices(mesh)
        w, x, y, z = row["quaternion"]
        rotation = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        local = (points - row["center"]) @ rotation
        assert np.max(np.linalg.norm(local / semi, axis=1)) <= 1.0 + 1e-12
        equations = ConvexHull(parts[f"UCX_{row['name']}_00"]).equations
        assert np.max(points @ equations[:, :3].T + equations[:, 3]) <= 1e-12
    assert "2 bodies (2 ellipsoid)" in result.stderr


def test_ellipsoid_csv_and_markdown(samples: Path) -> None:
    barrel = str(samples / "level" / "props" / "barrel.obj")
    result = _run("fit", barrel, "--shape", "ellipsoid", "--format", "csv")
    assert result.exit_code == 0, result.output
    header, row = result.stdout.strip().splitlines()
    values = dict(zip(header.split(","), row.split(",")))
    assert values["shape"] == "ellipsoid" and values["radius"] == ""
    sizes = sorted(float(values[k]) for k in ("size_x", "size_y", "size_z"))
    assert sizes[0] > 0.0
    result = _run("fit", barrel, "--shape", "ellipsoid", "--format", "markdown")
    assert result.exit_code == 0, result.output
    assert "1 bodies (1 ellipsoid)" in result.stdout


def test_auto_never_takes_an_ellipsoid(tmp_path: Path) -> None:
    from meshcol.analysis.fit import fit_points
    from meshcol.io.primitives import primitive_mesh
    from meshcol.types import Ellipsoid

    # an ellipsoid's own tessellation: its ellipsoid would be within any tolerance
    v, _ = primitive_mesh(Ellipsoid((2.0, 1.0, 0.5)))
    result = fit_points(v, volume_tolerance=0.3)
    assert set(result.fits) == {"sphere", "capsule", "box", "cylinder"}
    assert result.chosen in ("capsule", "box", "cylinder", "hull")
    assert fit_points(v, "ellipsoid").fits["ellipsoid"].volume <= 4.0 / 3.0 * np.pi * 1.0001
