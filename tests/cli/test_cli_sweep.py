"""The scene sweep: Python API (meshcol.sweep) and the `meshcol sweep` command."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

import meshcol
from meshcol import ConvexSet
from meshcol.cli import main
from meshcol.collision.time_of_impact import interpolate_pose, swept_aabbs
from meshcol.errors import SceneError
from meshcol.types import Body, Box, Scene, TimeOfImpactStatus


def pose(position=(0.0, 0.0, 0.0), angle_z=0.0) -> np.ndarray:
    m = np.eye(4)
    c, s = np.cos(angle_z), np.sin(angle_z)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:3, 3] = position
    return m


def mesh_body(name, mesh, start, end=None) -> Body:
    return Body(name, f"{name}.obj", np.asarray(mesh.vertices), np.asarray(mesh.faces), start, end)


def bullet_and_wall(end_x=1.0) -> Scene:
    """A 2 cm bullet crossing a 2 cm wall at x = 0 in one step (as samples/bullet)."""
    wall = mesh_body("wall", trimesh.creation.box((0.02, 2.0, 2.0)), pose((0, 0, 1)))
    bullet = mesh_body(
        "bullet", trimesh.creation.icosphere(2, radius=0.01), pose((-1, 0, 1)), pose((end_x, 0, 1))
    )
    return Scene((wall, bullet), units="m", duration=0.01)


# ---------------------------------------------------------------------------------------------
# Python API


def test_bullet_through_wall_is_a_tunnelled_hit():
    report = meshcol.sweep(bullet_and_wall())
    assert report.summary["hits"] == 1 and report.summary["tunnelled"] == 1
    (hit,) = report.hits
    assert (hit.body_a, hit.body_b, hit.status) == ("wall", "bullet", TimeOfImpactStatus.HIT)
    # Contact when the bullet's centre is at x = -0.02 (its vertices reach 0.01).
    assert hit.time_of_impact == pytest.approx(0.98 / 2.0, abs=1e-5) and hit.time_of_impact <= 0.49
    assert hit.time == pytest.approx(hit.time_of_impact * 0.01)
    np.testing.assert_allclose(hit.normal, [-1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(hit.pose_b[:3, 3], [-1 + 2 * hit.time_of_impact, 0, 1], atol=1e-12)
    np.testing.assert_allclose(hit.pose_a, pose((0, 0, 1)), atol=0)
    assert hit.point[0] == pytest.approx(-0.01, abs=1e-5)


def test_hit_that_ends_inside_is_not_tunnelled():
    report = meshcol.sweep(bullet_and_wall(end_x=0.0))
    (hit,) = report.hits
    assert hit.status == TimeOfImpactStatus.HIT and not hit.tunnelled


def test_mesh_mode_sweeps_triangles():
    report = meshcol.sweep(bullet_and_wall(), collider="mesh")
    (hit,) = report.hits
    assert hit.status == TimeOfImpactStatus.HIT and hit.tunnelled
    assert hit.time_of_impact == pytest.approx(0.49, abs=1e-5)
    assert report.part_pairs > 100  # triangle pairs, not hulls


def test_mesh_mode_differs_from_hull_for_a_concave_body():
    # A ball passing through the opening of a U: the hull is hit, the mesh is not.
    u = trimesh.util.concatenate(
        [
            trimesh.creation.box((0.2, 2, 2)).apply_translation((-0.9, 0, 0)),
            trimesh.creation.box((0.2, 2, 2)).apply_translation((0.9, 0, 0)),
            trimesh.creation.box((2, 2, 0.2)).apply_translation((0, 0, -0.9)),
        ]
    )
    scene = Scene(
        (
            mesh_body("u", u, pose()),
            mesh_body(
                "ball",
                trimesh.creation.icosphere(2, radius=0.3),
                pose((0, -3, 0.2)),
                pose((0, 3, 0.2)),
            ),
        )
    )
    assert meshcol.sweep(scene, collider="hull").hits[0].status == TimeOfImpactStatus.HIT
    assert meshcol.sweep(scene, collider="mesh").hits == ()


def test_bar_rotating_past_box_in_a_scene():
    bar = Body(
        "bar",
        None,
        np.zeros((0, 3)),
        np.zeros((0, 3), np.int64),
        pose(),
        pose(angle_z=np.pi / 2),
        primitive=Box((4.0, 0.2, 0.2)),
    )
    near = Body(
        "near",
        None,
        np.zeros((0, 3)),
        np.zeros((0, 3), np.int64),
        pose((1.5, 1.5, 0)),
        primitive=Box((0.5, 0.5, 0.5)),
    )
    far = Body(
        "far",
        None,
        np.zeros((0, 3)),
        np.zeros((0, 3), np.int64),
        pose((2.05, 2.05, 0)),
        primitive=Box((0.5, 0.5, 0.5)),
    )
    report = meshcol.sweep(Scene((bar, near, far)), tolerance=1e-7)
    assert [(h.body_a, h.body_b, h.status, h.tunnelled) for h in report.hits] == [
        ("bar", "near", TimeOfImpactStatus.HIT, True)
    ]
    hit = report.hits[0]
    expected = interpolate_pose(pose(), pose(angle_z=np.pi / 2), hit.time_of_impact)
    np.testing.assert_allclose(hit.pose_a, expected, atol=1e-15)
    d = meshcol.distance(
        meshcol.Box((4.0, 0.2, 0.2)), meshcol.Box((0.5, 0.5, 0.5)), hit.pose_a, hit.pose_b
    ).distance
    assert d <= 1e-7
    # The far box is a broad-phase candidate (bounds overlap) that the narrow phase clears.
    assert report.candidate_pairs == 2


def test_swept_bounds_hold_the_rotating_body():
    cs = ConvexSet.from_shapes([meshcol.Box((4.0, 0.2, 0.2))])
    start, end = pose()[None], pose((1, 0, 0), np.radians(170))[None]
    lo, hi = swept_aabbs(cs, start, end)
    for t in np.linspace(0, 1, 101):
        a, b = cs.aabbs(interpolate_pose(start, end, np.array([t])))
        assert np.all(a >= lo - 1e-12) and np.all(b <= hi + 1e-12)
    # The union of the start and end boxes alone would not (the bar across y halfway).
    a0, b0 = cs.aabbs(start)
    a1, b1 = cs.aabbs(end)
    a, b = cs.aabbs(interpolate_pose(start, end, np.array([0.5])))
    assert np.any(b > np.maximum(b0, b1) + 0.1)


def test_static_pairs_are_skipped_and_nothing_moving_is_an_error():
    box = trimesh.creation.box((1, 1, 1))
    a, b = mesh_body("a", box, pose()), mesh_body("b", box, pose((0.5, 0, 0)))
    c = mesh_body("c", box, pose((5, 0, 0)), pose((6, 0, 0)))
    assert meshcol.sweep(Scene((a, b, c))).hits == ()  # a-b overlap but never move
    with pytest.raises(SceneError, match="no body has an end pose or a velocity"):
        meshcol.sweep(Scene((a, b), source="scene.json"))


# ---------------------------------------------------------------------------------------------
# Command line (needs the manifest loader, meshcol.scene)


def _write_manifest(tmp_path, bodies, **extra):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps({"bodies": bodies, **extra}))
    return path


BAR_SCENE = [
    {
        "name": "bar",
        "primitive": {"type": "box", "size": [4, 0.2, 0.2]},
        "angular_velocity": [0, 0, 1.5707963267948966],
    },
    {
        "name": "block",
        "primitive": {"type": "box", "size": [0.5, 0.5, 0.5]},
        "position": [1.5, 1.5, 0],
    },
]


def test_cli_rotating_bar_hits_and_exits_1(tmp_path):
    path = _write_manifest(tmp_path, BAR_SCENE, duration=2.0, units="m")
    result = CliRunner().invoke(main, ["sweep", str(path), "--tolerance", "1e-7"])
    assert result.exit_code == 1, result.output
    report = json.loads(result.stdout)
    assert report["command"] == "sweep" and report["schema_version"] == 1
    assert report["settings"]["tolerance"] == 1e-7 and report["failed"] is True
    (pair,) = report["pairs"]
    assert (pair["body_a"], pair["body_b"], pair["status"], pair["tunnelled"]) == (
        "bar",
        "block",
        "HIT",
        True,
    )
    assert pair["time"] == pytest.approx(2.0 * pair["time_of_impact"])
    assert report["summary"]["hits"] == 1 and report["units"] == "m"
    assert f"meshcol: fail: {path}: 'bar' and 'block': HIT at time of impact" in result.stderr


def test_cli_fail_on_none_and_csv_report(tmp_path):
    path = _write_manifest(tmp_path, BAR_SCENE, duration=2.0)
    out = tmp_path / "sweep.csv"
    result = CliRunner().invoke(
        main, ["sweep", str(path), "--report", str(out), "--fail-on", "none", "--threads", "1"]
    )
    assert result.exit_code == 0, result.output
    lines = out.read_text().splitlines()
    from meshcol.analysis.sweep import CSV_COLUMNS

    assert lines[0].split(",") == list(CSV_COLUMNS)
    assert lines[0].startswith(
        "body_a,body_b,part_a,part_b,status,time_of_impact,time,point_x,point_y,point_z,normal_x,"
    )
    assert ",pose_a_00,pose_a_01," in lines[0] and lines[0].endswith(",pose_b_33,iterations,units")
    assert lines[1].startswith("bar,block,,,HIT,") and len(lines) == 2
    assert "1 hit (1 tunnelled)" in result.stderr
    assert result.stderr.splitlines()[-1] == (
        "meshcol: sweep: PASS: 1 pair touches during the motion (--fail-on none)"
    )
    assert not list(tmp_path.glob(".meshcol-*"))  # no temporary left behind


def test_cli_manifest_without_motion_exits_2(tmp_path):
    path = _write_manifest(tmp_path, [BAR_SCENE[1]])
    result = CliRunner().invoke(main, ["sweep", str(path)])
    assert result.exit_code == 2
    assert result.stderr == (
        f"meshcol: error: {path}: no body has an end pose or a velocity: "
        "nothing moves, nothing to sweep\n"
    )


def test_cli_bad_tolerance_is_a_usage_error(tmp_path):
    result = CliRunner().invoke(main, ["sweep", "scene.json", "--tolerance", "-1"])
    assert result.exit_code == 2
    assert result.stderr == (
        "meshcol: error: invalid value for '--tolerance': -1.0 is not in the range x>0 "
        "(see 'meshcol sweep -h')\n"
    )


def test_cli_bullet_sample_golden(samples, golden, monkeypatch):
    if not (samples / "bullet" / "scene.json").is_file():
        pytest.skip("samples/bullet not present")
    monkeypatch.chdir(samples.parent)
    result = CliRunner().invoke(main, ["sweep", "samples/bullet/scene.json", "--fail-on", "none"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    (pair,) = report["pairs"]
    assert pair["status"] == "HIT" and pair["tunnelled"] is True
    golden("sweep_bullet.json", result.stdout)


def test_sweep_decomposed_uses_the_decompose_cache(tmp_path, samples) -> None:
    """--shape decomposed: parts come from the cache `meshcol decompose` fills (or are made)."""
    scene = samples / "bullet" / "scene.json"
    cache = tmp_path / "cache"
    runner = CliRunner()
    out = tmp_path / "parts"
    made = runner.invoke(
        main,
        [
            "decompose",
            str(samples / "bullet" / "wall.obj"),
            "-o",
            str(out),
            "--cache-dir",
            str(cache),
            "--report",
            str(tmp_path / "d.json"),
        ],
    )
    assert made.exit_code == 0, made.output
    result = runner.invoke(
        main,
        [
            "sweep",
            str(scene),
            "--shape",
            "decomposed",
            "--cache-dir",
            str(cache),
            "--report",
            str(tmp_path / "s.json"),
        ],
    )
    assert result.exit_code == 1, result.output
    data = json.loads((tmp_path / "s.json").read_text())
    [hit] = data["pairs"]
    assert hit["status"] == "HIT" and hit["tunnelled"]
    hull = json.loads(runner.invoke(main, ["sweep", str(scene), "--report", "-"]).stdout)
    assert hit["time_of_impact"] == pytest.approx(
        hull["pairs"][0]["time_of_impact"], abs=1e-6
    )  # convex wall: same parts


def test_cli_summary_lists_the_earliest_ten_contacts_and_counts_the_rest(tmp_path):
    """A library-size sweep prints a summary, not a line per pair: the first ten contacts by
    time of impact (a pair overlapping at the start, time 0, first), then how many more the
    report holds."""
    wall = {
        "name": "wall",
        "primitive": {"type": "box", "size": [0.2, 40, 1]},
        "position": [5, 0, 0],
    }
    resting = {
        "name": "resting",  # inside the wall from the start
        "primitive": {"type": "sphere", "radius": 0.5},
        "position": [5, 15, 0],
        "velocity": [0, 0, 0.01],
    }
    # ball i, 4.4 from the wall's face, reaches it at 4.4 / (1.25 + 0.25 i) s
    balls = [
        {
            "name": f"ball{i:02d}",
            "primitive": {"type": "sphere", "radius": 0.5},
            "position": [0, 2 * i - 13, 0],
            "velocity": [1.25 + 0.25 * i, 0, 0],
        }
        for i in range(13)
    ]
    path = _write_manifest(tmp_path, [wall, resting, *balls], duration=4.0)
    out = tmp_path / "sweep.json"
    result = CliRunner().invoke(main, ["sweep", str(path), "--report", str(out)])
    assert result.exit_code == 1, result.output
    assert len(json.loads(out.read_text())["pairs"]) == 14  # every contact is in the report
    lines = [line for line in result.stderr.splitlines() if line.startswith("meshcol: fail:")]
    assert len(lines) == 10
    assert "'wall' and 'resting': OVERLAPPED_AT_START" in lines[0]
    for line, i in zip(lines[1:], range(12, 3, -1), strict=True):
        assert f"'wall' and 'ball{i:02d}': HIT" in line
    assert "  ... 4 more (every pair is in the report)" in result.stderr.splitlines()
