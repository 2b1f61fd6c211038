"""``meshcol ci`` over a repository of assets: the same findings as the equivalent flags per
folder, one verdict, every format, a result cache by content, ``--changed-since``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from ci_repo import box_obj, commit, make_repo
from click.testing import CliRunner

from meshcol.cli import main

SCHEMAS = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"

pytest.importorskip("yourdfpy", reason="the test repository's robot needs yourdfpy")


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture
def repo(tmp_path, monkeypatch):
    root = make_repo(tmp_path / "repo")
    monkeypatch.chdir(root)
    return root


def findings(report: dict) -> list[tuple]:
    return sorted((f["rule"], f["body"], f.get("part"), f["failed"]) for f in report["findings"])


def pairs(report: dict) -> list[tuple]:
    return sorted(
        (p["body_a"], p["body_b"], p["status"], p["violation"], p["ignored"])
        for p in report["pairs"]
    )


def runs_of(report: dict, command: str, prefix: str) -> list[dict]:
    return [r for r in report["runs"] if r["command"] == command and r["input"].startswith(prefix)]


def flags_report(*args: str) -> tuple[int, dict]:
    code, out, err = run(*args, "--report", "-")
    assert code in (0, 1), err
    return code, json.loads(out)


def test_ci_gives_the_findings_of_the_flags_per_folder(repo, tmp_path):
    code, _, err = run("ci", "--report", "ci.json", "--cache-dir", str(tmp_path / "cache"))
    assert code == 1, err  # the hard open prop and the level's penetrations fail
    report = json.loads((repo / "ci.json").read_text())
    assert report["summary"]["exit_code"] == 1
    assert report["summary"]["jobs_by_command"] == {"check": 2, "hull": 4, "inspect": 4}

    # props/hard: inspect --fail-on not-watertight (MC402 is ignored with a reason)
    hard = runs_of(report, "inspect", "props/hard/")
    expected_code, expected = flags_report(
        "inspect", "props/hard/closed.obj", "props/hard/open.obj", "--fail-on", "not-watertight"
    )
    got = sorted(f for r in hard for f in findings(r["report"]))
    assert got == findings(expected) and expected_code == 1
    assert any(rule == "MC401" and failed for rule, _, _, failed in got)
    assert [r["exit_code"] for r in hard] == [0, 1]

    # props/soft: inspect reports only
    soft = runs_of(report, "inspect", "props/soft/")
    _, expected = flags_report("inspect", "props/soft/closed.obj", "props/soft/open.obj")
    assert sorted(f for r in soft for f in findings(r["report"])) == findings(expected)
    assert [r["exit_code"] for r in soft] == [0, 0]

    # every prop: hull --max-vertices 16
    hulls = runs_of(report, "hull", "props/")
    props = sorted(r["input"] for r in hulls)
    _, expected = flags_report("hull", *props, "--max-vertices", "16")
    rows = sorted(
        (row["source"], row["hull_vertices"], row["hull_volume"])
        for r in hulls
        for row in r["report"]["bodies"]
    )
    assert rows == sorted(
        (row["source"], row["hull_vertices"], row["hull_volume"]) for row in expected["bodies"]
    )

    # the level: check --fail-on penetration --ignore crate_06:crate_07
    [level] = runs_of(report, "check", "levels/")
    _, expected = flags_report(
        "check",
        "levels/level/scene.json",
        "--fail-on",
        "penetration",
        "--ignore",
        "crate_06:crate_07",
    )
    assert pairs(level["report"]) == pairs(expected)
    assert level["exit_code"] == 1
    assert any(p[4] for p in pairs(expected))  # the ignored pair is marked so

    # the robot: check --fail-on contact --joint j1=0.5
    [robot] = runs_of(report, "check", "robots/")
    robot_code, expected = flags_report(
        "check", "robots/arm/arm.urdf", "--fail-on", "contact", "--joint", "j1=0.5"
    )
    assert pairs(robot["report"]) == pairs(expected)
    assert robot["exit_code"] == robot_code
    assert "meshcol: ci: FAIL:" in err.splitlines()[-1]


def test_every_format_at_once(repo, tmp_path):
    from meshcol.analysis.ci_report import CiReport
    from meshcol.io.formats import FORMATS, formats_for

    code, out, err = run("ci", "--outputs", "out", "--junit", "ci.xml", "--github", "--no-cache")
    assert code == 1, err
    written = sorted(p.name for p in (repo / "out").iterdir())
    expected = sorted(
        f"meshcol-ci{FORMATS[name].extension}"
        for name in formats_for(CiReport)
        if FORMATS[name].extension is not None
    )
    assert written == expected and "meshcol-ci.json" in written
    junit = (repo / "ci.xml").read_text()
    assert "props/hard/open.obj" in junit and "<failure" in junit
    assert "::error file=props/hard/open.obj" in out
    assert (repo / "out" / "meshcol-ci.xml").read_text() == junit


def test_cache_recomputes_the_changed_asset_and_its_scenes_only(repo, tmp_path):
    cache = str(tmp_path / "cache")
    code, cold, err = run("ci", "--report", "-", "--cache-dir", cache)
    assert code == 1 and "0 jobs from the cache" in err, err
    code, warm, err = run("ci", "--report", "-", "--cache-dir", cache)
    assert warm == cold and "10 jobs from the cache" in err, err

    # a prop changes: its inspect and hull run again, nothing else
    (repo / "props" / "soft" / "open.obj").write_text(box_obj(2.0, True, name="open"))
    code, changed, err = run("ci", "--report", "-", "--cache-dir", cache)
    assert "8 jobs from the cache" in err, err
    # a mesh of the level changes: the level's check runs again (every pair it is in)
    (repo / "levels" / "level" / "props" / "ball.obj").write_text(box_obj(0.5, name="ball"))
    code, _, err = run("ci", "--report", "-", "--cache-dir", cache)
    assert "9 jobs from the cache" in err, err
    # a robot link's mesh: the robot's check
    (repo / "robots" / "arm" / "meshes" / "upper.obj").write_text(box_obj(0.25, name="upper"))
    code, _, err = run("ci", "--report", "-", "--cache-dir", cache)
    assert "9 jobs from the cache" in err, err
    # and a cold run of the final state gives the cached run's bytes
    code, cached, _ = run("ci", "--report", "-", "--cache-dir", cache)
    code, fresh, _ = run("ci", "--report", "-", "--no-cache")
    assert without_times(json.loads(cached)) == without_times(json.loads(fresh))


def without_times(value):
    """A report without its measured times (which no two computations share)."""
    if isinstance(value, dict):
        return {
            k: without_times(v)
            for k, v in value.items()
            if "seconds" not in k and k not in ("time", "generated_at")
        }
    if isinstance(value, list):
        return [without_times(v) for v in value]
    return value


@pytest.mark.skipif(shutil.which("git") is None, reason="--changed-since needs git")
def test_changed_since_runs_what_a_commit_touched(tmp_path, monkeypatch):
    root = make_repo(tmp_path / "repo", git=True)
    monkeypatch.chdir(root)
    cache = str(tmp_path / "cache")
    assert run("ci", "--cache-dir", cache, "-j", "2")[0] == 1  # the workers store the results
    (root / "props" / "hard" / "closed.obj").write_text(box_obj(3.0, name="closed"))
    (root / "levels" / "level" / "props" / "pillar.obj").write_text(box_obj(0.3, name="pillar"))
    commit(root, "two assets")
    code, out, err = run("ci", "--changed-since", "HEAD~1", "--report", "-", "--cache-dir", cache)
    report = json.loads(out)
    ran = sorted((r["command"], r["input"]) for r in report["runs"])
    assert ran == [
        ("check", "levels/level/scene.json"),
        ("hull", "props/hard/closed.obj"),
        ("inspect", "props/hard/closed.obj"),
    ]
    assert (
        report["summary"]["skipped_unchanged"] == 7
        and report["settings"]["changed_since"] == "HEAD~1"
    )
    assert code == 1  # the level still penetrates
    # the index it wrote keeps the jobs it left out: the next run reads none one by one
    index = Path(cache) / "results" / "index"
    (written,) = index.iterdir()
    lines = written.read_bytes().split(b"\n")
    assert len(lines) - 4 == 10  # magic, header, stats, one line per job, the final newline
    assert all(b'"report"' not in line for line in lines[3:])
    # the same selection from the run index (read above) and from the entries one by one
    shutil.rmtree(index)
    _, again, _ = run("ci", "--changed-since", "HEAD~1", "--report", "-", "--cache-dir", cache)
    assert sorted((r["command"], r["input"]) for r in json.loads(again)["runs"]) == ran
    (written,) = index.iterdir()  # from entries read one by one: summaries without reports
    lines = written.read_bytes().split(b"\n")
    assert len(lines) - 4 == 10 and all(b'"report"' not in line for line in lines[3:])
    # without the cache a scene's meshes are unknown: every scene runs, no asset unchanged
    _, cold, _ = run("ci", "--changed-since", "HEAD~1", "--report", "-", "--no-cache")
    assert sorted((r["command"], r["input"]) for r in json.loads(cold)["runs"]) == sorted(
        [*ran, ("check", "robots/arm/arm.urdf")]
    )
    code, _, err = run("ci", "--changed-since", "no-such-ref")
    assert code == 2 and "--changed-since no-such-ref" in err


def test_bad_config_is_one_line_with_key_and_line(repo):
    (repo / "meshcol.toml").write_text(
        '[[assets]]\nglob = "props/**/*.obj"\ninspect = { fail-on = ["no-such-rule"] }\n'
    )
    code, _, err = run("ci")
    assert code == 2
    [line] = err.strip().splitlines()
    assert line.startswith(f"meshcol: error: {repo / 'meshcol.toml'}:3: inspect.fail-on: ")
    assert "unknown rule 'no-such-rule'" in line


def test_config_command_shows_each_setting_and_its_origin(repo):
    code, out, err = run("config", "props/hard/open.obj", "--set", "check.clearance=0.5")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == "config: meshcol.toml"
    assert (
        "props/hard/open.obj: asset (assets[0] (meshcol.toml:4), assets[1] (meshcol.toml:10))"
        in out
    )
    assert "  commands: inspect, hull" in out

    def origin(key: str) -> str:
        [line] = [x for x in lines if x.strip().startswith(key + " ")]
        return line.rsplit("# ", 1)[1]

    assert origin("inspect.fail-on") == "meshcol.toml:12"
    assert origin("hull.max-vertices") == "meshcol.toml:8"
    assert origin("check.clearance") == "flag --set check.clearance=0.5"
    assert origin("inspect.com-offset") == "default"
    code, out, _ = run("config", "levels/level/scene.json", "--format", "json", "--shape", "mesh")
    [scene] = json.loads(out)["files"]
    assert scene["kind"] == "scene" and scene["commands"] == ["check"]
    assert scene["settings"]["shape"] == {"value": "mesh", "from": "flag --shape"}
    code, _, err = run("config", "--shape", "cube")
    assert code == 2 and "'--shape': shape: must be one of" in err


def test_no_config_is_a_usage_error(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run("ci")
    assert code == 2 and "no meshcol.toml" in err


def test_pyproject_table(tmp_path, monkeypatch):
    root = make_repo(tmp_path / "repo")
    text = (root / "meshcol.toml").read_text()
    (root / "meshcol.toml").unlink()
    text = text.replace("[[assets]]", "[[tool.meshcol.assets]]").replace(
        "[[scenes]]", "[[tool.meshcol.scenes]]"
    )
    (root / "pyproject.toml").write_text("[tool.meshcol]\n" + text)
    (root / "sub").mkdir()
    monkeypatch.chdir(root / "sub")
    code, out, err = run("ci", "--report", "-", "--no-cache")
    assert code == 1, err
    assert json.loads(out)["settings"]["config"] == "pyproject.toml"
    assert json.loads(out)["settings"]["root"] == "."


def test_the_pool_gives_the_report_of_one_process(repo, tmp_path):
    code, one, err = run("ci", "--report", "-", "--no-cache")
    assert code == 1, err
    code, pool, err = run("ci", "--report", "-", "--no-cache", "-j", "2")
    assert code == 1, err
    assert without_times(json.loads(pool)) == without_times(json.loads(one))


def golden_text(report: dict) -> str:
    """The report with versions, times and timestamps out, floats to 9 digits (below 1e-12:
    summation noise, 0), sorted keys."""

    def clean(value, key=""):
        if isinstance(value, dict):
            return {k: clean(v, k) for k, v in value.items()}
        if isinstance(value, list):
            return [clean(v) for v in value]
        if key == "version" or key == "generated_at":
            return f"<{key}>"
        if isinstance(value, float):
            if "seconds" in key:
                return 0.0
            return 0.0 if abs(value) < 1e-12 else float(f"{value:.9g}") + 0.0
        return value

    return json.dumps(clean(report), sort_keys=True, indent=2) + "\n"


def test_ci_golden_and_schema(samples, golden, tmp_path, monkeypatch):
    jsonschema = pytest.importorskip("jsonschema", reason="the schema oracle needs jsonschema")
    repo = tmp_path / "bowl"
    shutil.copytree(samples / "bowl", repo)
    (repo / "meshcol.toml").write_text(
        '[[assets]]\nglob = "*.obj"\nhull = { max-vertices = 16 }\n\n'
        '[[scenes]]\npath = "scene.json"\n'
    )
    monkeypatch.chdir(repo)
    code, out, err = run("ci", "--report", "-", "--no-cache")
    assert code == 1, err  # the ball rests in the bowl: penetrating by the hull
    report = json.loads(out)
    assert [(r["command"], r["input"], r["exit_code"]) for r in report["runs"]] == [
        ("hull", "ball.obj", 0),  # a section naming a command runs only it
        ("hull", "bowl.obj", 0),
        ("check", "scene.json", 1),
    ]
    schema = json.loads((SCHEMAS / "ci_report.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(report)
    golden("ci_bowl.json", golden_text(report))
    code, out, _ = run("ci", "--no-cache", "--outputs", "out")
    rows = (repo / "out" / "meshcol-ci.csv").read_text().splitlines()
    assert rows[0] == "command,input,kind,exit_code,error,verdict" and len(rows) == 4
