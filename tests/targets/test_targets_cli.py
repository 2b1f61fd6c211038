"""``hull --target`` and ``decompose --target`` from the command line: the reports validate
against their schemas, the written colliders meet every limit (counted here, independently of
meshcol.collision.limits) and still hold every input vertex (scipy's hull equations)."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE
from scipy.spatial import ConvexHull

from meshcol.cli import main

SCHEMAS = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"


def run(*args: str):
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def validate(data: dict, command: str) -> None:
    schema = json.loads((SCHEMAS / f"{command}_report.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(data)


def planes(vertices: np.ndarray) -> int:
    """Distinct face planes of a convex part (coplanar triangles merged), brute force."""
    hull = ConvexHull(vertices)
    eq = hull.equations
    distinct: list[np.ndarray] = []
    for e in eq:
        if not any(np.allclose(e, other, atol=1e-9) for other in distinct):
            distinct.append(e)
    return len(distinct)


def encloses(part: np.ndarray, points: np.ndarray, tol: float = 1e-9) -> bool:
    eq = ConvexHull(part).equations
    return bool((points @ eq[:, :3].T + eq[:, 3]).max() <= tol * np.ptp(points, axis=0).max())


@pytest.fixture
def sphere(tmp_path: Path) -> Path:
    path = tmp_path / "ball.obj"
    trimesh.creation.icosphere(4, 0.5).export(path)
    return path


def test_hull_target_physx_gpu_meets_every_limit_and_encloses(sphere: Path, tmp_path: Path):
    out, report = tmp_path / "hull.obj", tmp_path / "hull.json"
    code, _, stderr = run(
        "hull", str(sphere), "--target", "physx-gpu", "-o", str(out), "--report", str(report)
    )
    assert code == 0, stderr
    data = json.loads(report.read_text())
    validate(data, "hull")
    assert data["settings"]["target"] == "physx-gpu"
    (body,) = data["bodies"]
    assert body["target"]["met"] and body["target"]["violations"] == []
    assert {c["rule"] for c in body["target"]["costs"]} >= {"MC101", "MC103", "MC105"}
    hull = trimesh.load(out, force="mesh")
    assert len(hull.vertices) <= 64
    assert planes(np.asarray(hull.vertices)) <= 64
    assert encloses(np.asarray(hull.vertices), np.asarray(trimesh.load(sphere).vertices))


def test_hull_target_that_cannot_be_met_exits_1_with_the_rule_id(sphere: Path, tmp_path: Path):
    profile = tmp_path / "tiny.toml"
    # a tetrahedron's largest extent is at least 3 times its in-sphere radius
    profile.write_text('title = "Tiny"\n[limits]\nmax_hull_vertices = 4\nmax_oblong_ratio = 2\n')
    report = tmp_path / "hull.json"
    code, _, stderr = run("hull", str(sphere), "--target", str(profile), "--report", str(report))
    assert code == 1, stderr
    assert "MC102 not-gpu-compatible-oblong" in stderr
    data = json.loads(report.read_text())
    validate(data, "hull")
    assert data["bodies"][0]["target"]["met"] is False
    assert [v["rule"] for v in data["bodies"][0]["target"]["violations"]] == ["MC102"]
    assert data["summary"]["target_violations"] >= 1


def test_unknown_target_is_exit_2(sphere: Path):
    code, _, stderr = run("hull", str(sphere), "--target", "no-such-engine")
    assert code == 2
    assert "no-such-engine" in stderr and "Traceback" not in stderr


@pytest.mark.slow
def test_decompose_target_meets_the_hull_count_and_validates(tmp_path: Path, samples: Path):
    out, report = tmp_path / "parts", tmp_path / "d.json"
    code, _, stderr = run(
        "decompose",
        str(samples / "bowl" / "bowl.obj"),
        "-o",
        str(out),
        "--target",
        "physx-gpu",
        "--no-cache",
        "--report",
        str(report),
        *FAST_DECOMPOSE,
    )
    assert code == 0, stderr
    data = json.loads(report.read_text())
    validate(data, "decompose")
    (body,) = data["files"][0]["bodies"]
    assert body["target_ok"] is True
    parts = [np.asarray(trimesh.load(p, force="mesh").vertices) for p in sorted(out.iterdir())]
    assert parts and all(len(v) <= 64 for v in parts)
    assert all(planes(v) <= 64 for v in parts)
