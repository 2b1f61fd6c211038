"""meshcol check: known answers, samples, corpus against python-fcl, policy, reports, CLI."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol.analysis.check import CheckOptions, check, check_scene
from meshcol.analysis.check_report import CSV_COLUMNS
from meshcol.cli import main
from meshcol.io.scene import load_inputs

SCHEMA = Path(__file__).resolve().parents[2] / "meshcol" / "schemas" / "check_report.schema.json"


def write_manifest(
    folder: Path, bodies: list[dict], units: str = "m", name: str = "scene.json"
) -> Path:
    path = folder / name
    path.write_text(json.dumps({"units": units, "bodies": bodies}))
    return path


def box(name: str, size, position, **extra) -> dict:
    return {
        "name": name,
        "primitive": {"type": "box", "size": list(size)},
        "position": list(position),
        **extra,
    }


def pair(report, a: str, b: str) -> dict:
    for p in report.pairs:
        if {p["body_a"], p["body_b"]} == {a, b}:
            return p
    raise AssertionError(f"pair {a}-{b} not reported")


def write_box_obj(path: Path, lo, hi) -> None:
    import trimesh

    mesh = trimesh.creation.box(bounds=[lo, hi])
    mesh.export(path)


# ---------------------------------------------------------------------------------------------
# Known answers


def test_boxes_one_apart_are_separated_by_exactly_one(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (2, 0, 0))])
    report = check([m], clearance=2.0)
    p = pair(report, "a", "b")
    assert p["status"] == "clearance"
    assert p["distance"] == pytest.approx(1.0, abs=1e-12)
    assert p["depth"] == 0.0
    assert p["normal"] == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert p["point_a"][0] == pytest.approx(0.5, abs=1e-12)
    assert p["point_b"][0] == pytest.approx(1.5, abs=1e-12)
    assert report.passed


def test_far_pairs_are_not_candidates(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (5, 0, 0))])
    report = check([m], clearance=1.0)
    assert report.pairs == []
    assert report.summary["candidate_pairs"] == 0


def test_overlapping_boxes_penetrate_with_exact_depth_and_normal(tmp_path: Path) -> None:
    m = write_manifest(
        tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (0.75, 0.1, 0))]
    )
    report = check([m])
    p = pair(report, "a", "b")
    assert p["status"] == "penetrating"
    assert p["depth"] == pytest.approx(0.25, rel=1e-9)
    assert p["signed_distance"] == pytest.approx(-0.25, rel=1e-9)
    assert p["normal"] == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
    assert not report.passed and report.exit_code == 1


def test_touching_boxes_are_in_contact(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (1, 0.3, 0))])
    report = check([m])
    assert pair(report, "a", "b")["status"] == "contact"
    assert report.passed
    assert not check([m], fail_on="contact").passed


def test_box_inside_box_is_contained(tmp_path: Path) -> None:
    write_box_obj(tmp_path / "outer.obj", [-2, -2, -2], [2, 2, 2])
    write_box_obj(tmp_path / "inner.obj", [-0.5, -0.5, -0.5], [0.5, 0.5, 0.5])
    for shape in ("hull", "mesh"):
        report = check([tmp_path / "outer.obj", tmp_path / "inner.obj"], collider=shape)
        p = pair(report, "inner", "outer")
        assert p["status"] == "contained", shape
        assert not report.passed


def test_clearance_band_and_policy(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (1.5, 0, 0))])
    assert pair(check([m], clearance=1.0), "a", "b")["status"] == "clearance"
    assert check([m], clearance=1.0).passed
    assert not check([m], clearance=1.0, fail_on="clearance").passed
    assert check([m], clearance=0.4).pairs == []  # gap 0.5: outside the band, not a candidate
    assert pair(check([m], clearance=0.6), "a", "b")["status"] == "clearance"
    assert check([m], clearance=0.4, fail_on="clearance").passed


def test_ignore_globs_either_order(tmp_path: Path) -> None:
    m = write_manifest(
        tmp_path, [box("door_1", (1, 1, 1), (0, 0, 0)), box("frame_1", (1, 1, 1), (0.5, 0, 0))]
    )
    report = check([m], ignore=["frame*:door*"])
    p = pair(report, "door_1", "frame_1")
    assert p["status"] == "penetrating" and p["ignored"] and not p["violation"]
    assert report.passed
    assert not check([m], ignore=["frame*:window*"]).passed


def test_fail_on_none_always_passes(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (0.5, 0, 0))])
    assert check([m], fail_on="none").passed


def test_mixed_primitives(tmp_path: Path) -> None:
    m = write_manifest(
        tmp_path,
        [
            {"name": "ball", "primitive": {"type": "sphere", "radius": 1.0}, "position": [0, 0, 0]},
            {
                "name": "pill",
                "primitive": {"type": "capsule", "radius": 0.5, "length": 2.0},
                "position": [3, 0, 0],
            },
        ],
    )
    p = pair(check([m], clearance=2.0), "ball", "pill")
    assert p["distance"] == pytest.approx(1.5, abs=1e-9)


@settings(max_examples=25)
@given(
    st.lists(
        st.tuples(
            st.integers(-4, 4),
            st.integers(-4, 4),
            st.integers(0, 2),
            st.integers(1, 3),
            st.integers(1, 3),
            st.integers(1, 3),
        ),
        min_size=2,
        max_size=7,
        unique_by=lambda t: t[:3],
    )
)
def test_axis_aligned_boxes_match_exact_answers(boxes) -> None:
    """Every pair's distance/depth equals the exact axis-aligned answer; no pair is missed."""
    import trimesh

    from meshcol.types import Body, Box, Scene

    bodies = []
    lo, hi = [], []
    for i, (x, y, z, sx, sy, sz) in enumerate(boxes):
        c = np.array([x, y, z], float) * 0.5
        s = np.array([sx, sy, sz], float) * 0.5
        t = np.eye(4)
        t[:3, 3] = c
        mesh = trimesh.creation.box(extents=s)
        bodies.append(
            Body(
                f"b{i}",
                None,
                np.asarray(mesh.vertices),
                np.asarray(mesh.faces, np.int64),
                t,
                primitive=Box(tuple(s)),
            )
        )
        lo.append(c - s / 2)
        hi.append(c + s / 2)
    clearance = 0.75
    report = check_scene(Scene(tuple(bodies)), CheckOptions(clearance=clearance, tolerance=1e-9))
    got = {(p["body_a"], p["body_b"]): p for p in report.pairs}
    for i, j in itertools.combinations(range(len(bodies)), 2):
        gap = np.maximum(np.maximum(lo[i] - hi[j], lo[j] - hi[i]), 0.0)
        overlap = np.minimum(hi[i], hi[j]) - np.maximum(lo[i], lo[j])
        dist = float(np.linalg.norm(gap))
        key = (f"b{i}", f"b{j}")
        if dist > clearance + 1e-9:
            assert key not in got or got[key]["distance"] > clearance - 1e-9
            continue
        assert key in got, f"missed pair {key} at distance {dist}"
        p = got[key]
        if np.all(overlap > 0):
            # minimum translation distance: per axis, the shorter way out of the overlap
            depth = float(np.minimum(hi[i] - lo[j], hi[j] - lo[i]).min())
            assert p["depth"] == pytest.approx(depth, rel=1e-9, abs=1e-12)
        else:
            assert p["distance"] == pytest.approx(dist, rel=1e-9, abs=1e-12)


# ---------------------------------------------------------------------------------------------
# Samples


def test_ball_in_bowl_is_phantom_with_hull_only(samples: Path) -> None:
    scene = samples / "bowl" / "scene.json"
    hull = check([scene], collider="hull")
    assert [p["status"] for p in hull.pairs] == ["penetrating"]
    mesh = check([scene], collider="mesh")
    assert [p["status"] for p in mesh.pairs] in (["separated"], [])
    assert mesh.passed


@pytest.mark.slow
def test_ball_in_bowl_is_separated_when_decomposed(samples: Path, bowl_cache_home: Path) -> None:
    scene = samples / "bowl" / "scene.json"
    # default decomposition parameters, as `meshcol check --shape decomposed` uses them; the
    # run's cache, which the README tour's `meshcol decompose` of the bowl shares
    cache = bowl_cache_home / "meshcol" / "decompose"
    report = check([scene], collider="decomposed", decompose_options={"cache_dir": str(cache)})
    assert all(p["status"] in ("separated", "clearance") for p in report.pairs)
    assert report.passed


def test_level_finds_exactly_the_planted_interpenetrations(samples: Path) -> None:
    expected = json.loads((samples / "level" / "expected.json").read_text())
    report = check([samples / "level" / "scene.json"])
    planted = {tuple(sorted((e["a"], e["b"]))): e for e in expected["interpenetrations"]}
    found = {
        tuple(sorted((p["body_a"], p["body_b"]))): p
        for p in report.pairs
        if p["status"] in ("penetrating", "contained")
    }
    assert set(found) == set(planted)
    for key, e in planted.items():
        assert found[key]["depth"] == pytest.approx(e["depth"], rel=1e-9, abs=1e-12), key
    flagged = {tuple(sorted((p["body_a"], p["body_b"]))) for p in report.pairs if p["violation"]}
    assert flagged == set(planted)


def test_level_golden_report(samples: Path, golden, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(samples.parent)
    report = check(["samples/level/scene.json"])
    data = report.to_dict()
    data["generated_at"] = "<generated_at>"
    data["summary"]["seconds"] = 0.0
    data["summary"]["load_seconds"] = 0.0
    data["tool"]["version"] = "<version>"
    _round_floats(data)
    golden("check_level.json", json.dumps(data, sort_keys=True, indent=2) + "\n")


def _round_floats(obj):
    """Round floats to 9 significant digits so golden files survive last-bit differences."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            obj[k] = _round_floats(v)
    elif isinstance(obj, list):
        return [_round_floats(v) for v in obj]
    elif isinstance(obj, float):
        return float(f"{obj:.9g}") + 0.0
    return obj


def test_report_matches_schema(samples: Path) -> None:
    import jsonschema

    schema = json.loads(SCHEMA.read_text())
    data = json.loads(check([samples / "level" / "scene.json"], clearance=0.05).to_json())
    jsonschema.validate(data, schema)


# ---------------------------------------------------------------------------------------------
# Corpus, compared with python-fcl


def _fcl_mesh_distance(body_a, body_b) -> float:
    fcl = pytest.importorskip("fcl")

    def obj(body):
        model = fcl.BVHModel()
        model.beginModel(len(body.vertices), len(body.faces))
        model.addSubModel(body.world_vertices(), body.faces.astype(np.int32))
        model.endModel()
        return fcl.CollisionObject(model, fcl.Transform())

    request = fcl.DistanceRequest(enable_nearest_points=True)
    return fcl.distance(obj(body_a), obj(body_b), request, fcl.DistanceResult())


def test_corpus_balls_overlap(corpus: Path) -> None:
    d = corpus / "trimesh-models"
    for shape in ("hull", "mesh"):
        report = check([d / "ballA.off", d / "ballB.off"], collider=shape)
        assert [p["status"] for p in report.pairs] == ["penetrating"], shape


@pytest.mark.parametrize("name", ["pins.glb", "boolean.glb"])
def test_corpus_scene_distances_match_fcl(corpus: Path, name: str) -> None:
    path = corpus / "trimesh-models" / name
    scene = load_inputs([path])
    bodies = {b.name: b for b in scene.bodies}
    report = check_scene(scene, CheckOptions(collider="mesh", clearance=1e9))
    n = len(scene.bodies)
    assert len(report.pairs) == n * (n - 1) // 2  # the huge clearance makes every pair a candidate
    compared = 0
    for p in report.pairs:
        if p["status"] in ("penetrating", "contained", "contact"):
            continue
        expected = _fcl_mesh_distance(bodies[p["body_a"]], bodies[p["body_b"]])
        assert p["distance"] == pytest.approx(expected, rel=1e-6, abs=1e-9), (
            p["body_a"],
            p["body_b"],
        )
        compared += 1
    assert compared > 0


# ---------------------------------------------------------------------------------------------
# Baseline


def test_baseline_fails_only_new_or_worse_pairs(tmp_path: Path) -> None:
    bodies = [
        box("a", (1, 1, 1), (0, 0, 0)),
        box("b", (1, 1, 1), (0.8, 0, 0)),
        box("c", (1, 1, 1), (5, 0, 0)),
    ]
    m = write_manifest(tmp_path, bodies)
    first = check([m])
    assert not first.passed
    old = tmp_path / "old.json"
    old.write_text(first.to_json())
    assert check([m], baseline=str(old)).passed  # same penetration: not new, not worse
    deeper = write_manifest(
        tmp_path, [bodies[0], box("b", (1, 1, 1), (0.6, 0, 0)), bodies[2]], name="deeper.json"
    )
    assert not check([deeper], baseline=str(old)).passed
    new = write_manifest(
        tmp_path, [bodies[0], bodies[1], box("c", (1, 1, 1), (-0.9, 0, 0))], name="new.json"
    )
    report = check([new], baseline=str(old))
    assert not report.passed
    assert {(p["body_a"], p["body_b"]) for p in report.pairs if p["violation"]} == {("a", "c")}
    better = write_manifest(
        tmp_path, [bodies[0], box("b", (1, 1, 1), (0.9, 0, 0)), bodies[2]], name="better.json"
    )
    assert check([better], baseline=str(old)).passed


# ---------------------------------------------------------------------------------------------
# CLI


def run(args, **kw):
    return CliRunner().invoke(main, args, **kw)


def test_cli_exit_codes_and_reports(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (0.5, 0, 0))])
    out = tmp_path / "r.json"
    result = run(["check", str(m), "--report", str(out)])
    assert result.exit_code == 1, result.output
    assert result.stdout == ""
    assert (
        result.stderr.splitlines()[-1]
        == "meshcol: check: FAIL: 1 pair violates --fail-on penetration"
    )
    data = json.loads(out.read_text())
    assert data["summary"]["passed"] is False and data["units"] == "m"
    assert run(["check", str(m), "--fail-on", "none"]).exit_code == 0
    csv_out = tmp_path / "r.csv"
    assert run(["check", str(m), "--report", str(csv_out)]).exit_code == 1
    lines = csv_out.read_text().splitlines()
    assert lines[0].split(",") == CSV_COLUMNS
    assert lines[1].startswith("a,b,,,penetrating,")


def test_cli_report_to_stdout_keeps_summary_on_stderr(tmp_path: Path) -> None:
    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (3, 0, 0))])
    for args in ([], ["--report", "-"]):
        result = run(["check", str(m), *args])
        assert result.exit_code == 0
        data = json.loads(result.stdout)
        assert data["summary"]["candidate_pairs"] == 0
        assert result.stderr.splitlines()[-1] == (
            "meshcol: check: PASS: no pair violates --fail-on penetration"
        )


@pytest.mark.parametrize(
    "args, message",
    [
        (["missing.json"], "meshcol: error: missing.json:"),
        (
            ["scene.json", "--ignore", "nocolon"],
            "meshcol: error: invalid value for '--ignore': ignore rule must look like A:B",
        ),
        (["scene.json", "--tolerance", "-1"], "meshcol: error: invalid value for '--tolerance'"),
        (
            ["scene.json", "--baseline", "nothere.json"],
            "meshcol: error: nothere.json: baseline report not found",
        ),
    ],
)
def test_cli_bad_input_exits_2(tmp_path: Path, monkeypatch, args, message) -> None:
    monkeypatch.chdir(tmp_path)
    write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0))])
    result = run(["check", *args, "--report", "out.json"])
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "out.json").exists()


def test_cli_bad_baseline_content(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0))])
    Path("old.json").write_text("{not json")
    result = run(["check", "scene.json", "--baseline", "old.json"])
    assert result.exit_code == 2
    assert result.output.strip().endswith(
        "meshcol: error: old.json: baseline is not valid JSON (line 1 column 2)"
    )


def test_ucx_parts_are_used_as_given(tmp_path: Path) -> None:
    """A UCX part wider than its render mesh decides the collision under --shape decomposed."""
    import trimesh

    scene = trimesh.Scene()
    scene.add_geometry(
        trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), node_name="crate", geom_name="crate"
    )
    scene.add_geometry(
        trimesh.creation.box(bounds=[[0, 0, 0], [1.5, 1, 1]]),
        node_name="UCX_crate_00",
        geom_name="UCX_crate_00",
    )
    scene.add_geometry(
        trimesh.creation.box(bounds=[[1.25, 0, 0], [2, 1, 1]]), node_name="wall", geom_name="wall"
    )
    path = tmp_path / "crate.glb"
    scene.export(path)
    report = check([path], collider="decomposed")
    names = {b["name"] for b in report.bodies}
    assert not any("UCX" in n for n in names)
    crate = next(b for b in report.bodies if b["name"].endswith("crate"))
    assert crate["collider"] == "ucx"
    p = report.pairs[0]
    assert p["status"] == "penetrating"
    assert p["depth"] == pytest.approx(0.25, rel=1e-9)
    # with hulls the UCX part is ignored: crate [0, 1] and wall [1.25, 2] are 0.25 apart
    hull = check([path], collider="hull", clearance=0.5)
    assert [(p["status"], p["distance"]) for p in hull.pairs] == [
        ("clearance", pytest.approx(0.25))
    ]


def test_cli_choices_are_the_library_constants() -> None:
    from meshcol.analysis.check import FAIL_ON
    from meshcol.analysis.colliders import COLLIDER_KINDS
    from meshcol.cli.check import FAIL_ON_CHOICES, SHAPE_CHOICES

    assert tuple(FAIL_ON) == FAIL_ON_CHOICES
    assert SHAPE_CHOICES is COLLIDER_KINDS


def test_cli_runs_the_library_check(tmp_path: Path, monkeypatch) -> None:
    """The command parses, calls meshcol.analysis.check.check and prints: nothing else."""
    import meshcol.analysis.check as library

    m = write_manifest(tmp_path, [box("a", (1, 1, 1), (0, 0, 0)), box("b", (1, 1, 1), (0.5, 0, 0))])
    calls = []
    real = library.check

    def spy(inputs, **options):
        calls.append((list(inputs), options))
        return real(inputs, **options)

    monkeypatch.setattr(library, "check", spy)
    result = run(["check", str(m), "--clearance", "0.1", "--ignore", "x:y", "--report", "-"])
    assert result.exit_code == 1
    ((inputs, options),) = calls
    assert inputs == [str(m)]
    assert options["clearance"] == 0.1 and options["ignore"] == ("x:y",)
    assert options["collider"] == "hull" and options["baseline"] is None
    assert json.loads(result.stdout)["command"] == "check"


@pytest.mark.parametrize("scale", ["1e-320", "[1, 1e-310, 1]", "5e-324"])
def test_denormal_scale_is_a_one_line_error_not_a_crash(tmp_path: Path, scale: str) -> None:
    """`"scale": 1e-320` made `meshcol check` exit 139 (issue 13): the baked vertices were
    denormal and the mesh hierarchy's SAH binning crashed on them (fixed in the core, see
    test_mesh_query's denormal test). The manifest's magnitude check refuses such a scale with
    exit 2 and one line naming the manifest and body.
    A child process, so that a crash fails the test instead of killing the session."""
    import subprocess
    import sys

    import trimesh

    trimesh.creation.box().export(tmp_path / "box.obj")
    body = '{"name": "a", "mesh": "box.obj", "scale": ' + scale + "}"
    (tmp_path / "scene.json").write_text(
        '{"bodies": [' + body + ', {"name": "b", "mesh": "box.obj"}]}'
    )
    for shape in ("hull", "mesh"):
        out = subprocess.run(
            [sys.executable, "-m", "meshcol", "check", "scene.json", "--shape", shape],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            timeout=300,
        )
        assert out.returncode == 2, (out.returncode, out.stderr[-2000:])
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1
        assert lines[0].startswith("meshcol: error: scene.json: body 'a': scale ")
        assert "is below the limit of 1e-10" in lines[0]


@given(
    st.lists(
        st.tuples(
            st.sampled_from(["separated", "contact", "penetrating", "contained"]),
            st.one_of(st.none(), st.sampled_from([-1.0, -0.5, 0.0]), st.floats(-2, 2)),
        ),
        max_size=40,
    ),
    st.integers(0, 12),
)
def test_worst_pairs_are_the_sorted_touching_pairs_ties_in_report_order(rows, count):
    from meshcol.analysis.check import CheckReport

    pairs = [{"id": i, "status": s, "signed_distance": d} for i, (s, d) in enumerate(rows)]
    report = CheckReport([], pairs, {}, {}, None, "")
    touching = [p for p in pairs if p["status"] != "separated"]
    expected = sorted(
        touching,
        key=lambda p: p["signed_distance"] if p["signed_distance"] is not None else float("inf"),
    )[:count]
    assert report.worst_pairs(count) == expected
