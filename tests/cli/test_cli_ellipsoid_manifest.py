"""A manifest's ellipsoids through every command that reads manifests: known distances and
times of impact, exit codes, and the one-line errors of bad values."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from meshcol.cli import main

EGG = {"type": "ellipsoid", "semi_axes": [0.3, 0.2, 0.1]}
BALL = {"type": "sphere", "radius": 0.2}


def write(folder: Path, bodies: list[dict], **top) -> Path:
    path = folder / "scene.json"
    path.write_text(json.dumps({"units": "m", **top, "bodies": bodies}))
    return path


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def pairs(result) -> dict[frozenset, dict]:
    """The report's pairs by their two names (in either order)."""
    report = json.loads(result.stdout)
    return {frozenset((p["body_a"], p["body_b"])): p for p in report["pairs"]}


def test_check_measures_the_true_surface_and_exits_by_the_policy(tmp_path):
    # the egg's semi-axes along x, y, z: a ball 0.7 away along x is 0.2 off, along y 0.3
    bodies = [
        {"name": "egg", "primitive": EGG},
        {"name": "east", "primitive": BALL, "position": [0.7, 0, 0]},
        {"name": "north", "primitive": BALL, "position": [0, 0.7, 0]},
        {"name": "up", "primitive": BALL, "position": [0, 0, 0.25]},
    ]
    path = write(tmp_path, bodies)
    result = run("check", str(path), "--report", "-", "--clearance", "1")
    assert result.exit_code == 1, result.stderr  # 'up' is 0.05 into the egg
    found = pairs(result)
    assert found[frozenset(("egg", "east"))]["signed_distance"] == pytest.approx(0.2, abs=1e-12)
    assert found[frozenset(("egg", "north"))]["signed_distance"] == pytest.approx(0.3, abs=1e-12)
    assert found[frozenset(("egg", "up"))]["status"] == "penetrating"
    assert found[frozenset(("egg", "up"))]["signed_distance"] == pytest.approx(-0.05, abs=1e-9)
    del bodies[3]
    result = run("check", str(write(tmp_path, bodies)), "--report", "-")
    assert result.exit_code == 0, result.stderr
    report = json.loads(result.stdout)
    egg = next(b for b in report["bodies"] if b["name"] == "egg")
    assert egg["collider"] == "primitive" and egg["vertices"] == 642
    assert egg["aabb"] == [[-0.3, -0.2, -0.1], [0.3, 0.2, 0.1]]


def test_a_sphere_scaled_unevenly_is_the_exact_ellipsoid(tmp_path):
    bodies = [
        {"name": "egg", "primitive": {"type": "sphere", "radius": 0.1}, "scale": [3, 2, 1]},
        {"name": "egg2", "primitive": EGG, "scale": [1, 2, 3], "position": [0, 0, 2]},
        {"name": "east", "primitive": BALL, "position": [0.7, 0, 0]},
        {"name": "north", "primitive": BALL, "position": [0, 0.7, 2]},
    ]
    result = run("check", str(write(tmp_path, bodies)), "--report", "-", "--clearance", "3")
    assert result.exit_code == 0, result.stderr
    found = pairs(result)
    assert found[frozenset(("egg", "east"))]["signed_distance"] == pytest.approx(0.2, abs=1e-12)
    # egg2: semi-axes 0.3, 0.4, 0.3, so 'north' (0.7 along y) is 0.1 off
    assert found[frozenset(("egg2", "north"))]["signed_distance"] == pytest.approx(0.1, abs=1e-12)
    # egg (top at z = 0.1) and egg2 (bottom at z = 2 - 0.3)
    assert found[frozenset(("egg", "egg2"))]["signed_distance"] == pytest.approx(1.6, abs=1e-12)


@pytest.mark.parametrize(
    ("primitive", "extra", "message"),
    [
        (
            {"type": "ellipsoid", "semi_axes": [0.3, 0, 0.1]},
            {},
            "body 'egg': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        (
            {"type": "ellipsoid", "semi_axes": [0.3, -0.2, 0.1]},
            {},
            "body 'egg': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        (
            {"type": "ellipsoid", "semi_axes": [0.3, 0.2]},
            {},
            "body 'egg': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        ({"type": "ellipsoid"}, {}, "body 'egg': missing field 'primitive.semi_axes'"),
        (
            {"type": "ellipsoid", "radius": 0.3},
            {},
            "body 'egg': unknown field 'primitive.radius'",
        ),
        (
            {"type": "ellipsoid", "semi_axes": [0.3, 2e10, 0.1]},
            {},
            "body 'egg': primitive.semi_axes 2e+10 is beyond the limit of +/-1e+10 (line 1)",
        ),
        (
            {"type": "capsule", "radius": 0.1, "length": 1},
            {"scale": [1, 2, 1]},
            "body 'egg': a capsule takes a uniform scale only",
        ),
        (
            {"type": "cylinder", "radius": 0.1, "length": 1},
            {"scale": [2, 1, 1]},
            "body 'egg': a cylinder takes the same scale in x and y only",
        ),
    ],
)
def test_bad_ellipsoids_and_scales_are_one_line_and_exit_2(tmp_path, primitive, extra, message):
    path = write(tmp_path, [{"name": "egg", "primitive": primitive, **extra}])
    for command in ("check", "inspect", "hull"):
        result = run(command, str(path))
        assert result.exit_code == 2, (command, result.output)
        assert result.stderr == f"meshcol: error: {path}: {message}\n", command


@pytest.mark.slow  # 3-8 s: the fast lane (make test-fast) stays under 40 s
def test_every_command_that_reads_manifests_takes_ellipsoids(tmp_path):
    bodies = [
        {"name": "egg", "primitive": EGG, "rotation": {"euler_deg": [0, 0, 90], "order": "xyz"}},
        {"name": "ball", "primitive": {"type": "sphere", "radius": 0.1}, "scale": [1, 2, 1]},
        {"name": "box", "primitive": {"type": "box", "size": [0.2, 0.2, 0.2]}},
    ]
    bodies[1]["position"], bodies[2]["position"] = [0, 0.8, 0], [1, 0, 0]
    path = write(tmp_path, bodies)
    out = tmp_path / "out"
    out.mkdir()
    page = run(
        "check", str(path), "--html", str(out / "page.html"), "--report", "-", "--clearance", "1"
    )
    assert page.exit_code == 0, page.stderr
    assert (out / "page.html").stat().st_size > 0
    # the egg turned a quarter about z: semi-axis 0.3 along y; the ball's 0.2 along y
    found = pairs(page)
    assert found[frozenset(("ball", "egg"))]["signed_distance"] == pytest.approx(0.3, abs=1e-12)
    inspect = run("inspect", str(path), "--report", "-")
    assert inspect.exit_code == 0, inspect.stderr
    assert [b["name"] for b in json.loads(inspect.stdout)["bodies"]] == ["egg", "ball", "box"]
    fit = run("fit", str(path), "--report", "-")
    assert fit.exit_code == 0, fit.stderr
    rows = {row["name"]: row for row in json.loads(fit.stdout)["bodies"]}
    # the egg's own volume, from its closed form (4/3 pi a b c)
    assert rows["egg"]["mesh_volume"] == pytest.approx(4 / 3 * 3.141592653589793 * 0.006)
    hull = run("hull", str(path), "-o", str(out / "hulls.glb"))
    assert hull.exit_code == 0 and (out / "hulls.glb").stat().st_size > 0, hull.stderr
    decompose = run("decompose", str(path), "--out-dir", str(out / "parts"))
    assert decompose.exit_code == 0, decompose.stderr
    assert sorted(p.name for p in (out / "parts").iterdir()) == [
        "ball_00.obj",
        "box_00.obj",
        "egg_00.obj",
    ]


def test_sweep_finds_an_ellipsoids_first_contact(tmp_path):
    bodies = [
        {"name": "egg", "primitive": EGG, "position": [-2, 0, 0], "velocity": [4, 0, 0]},
        {"name": "wall", "primitive": {"type": "box", "size": [0.02, 2, 2]}},
    ]
    result = run("sweep", str(write(tmp_path, bodies, duration=1)), "--report", "-")
    assert result.exit_code == 1, result.stderr  # it tunnels through the wall
    (hit,) = json.loads(result.stdout)["pairs"]
    # the egg's front (x = -2 + 0.3) reaches the wall's face (x = -0.01) after 1.69 / 4 s
    assert hit["status"] == "HIT"
    assert hit["time_of_impact"] == pytest.approx(1.69 / 4, abs=1e-5)
