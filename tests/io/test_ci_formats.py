"""CI-native reports (meshcol.io.ci): JUnit XML parsed by junitparser and validated against
the JUnit schema, GitHub workflow commands unescaped as the runner does, on every command."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE
from hypothesis import given
from hypothesis import strategies as st

from meshcol.cli import main
from meshcol.io.ci import (
    MAX_PASSED_CASES,
    CiCase,
    CiSuite,
    annotation_path,
    collapse_passed,
    dumps_github,
    dumps_junit,
    escape_data,
    escape_property,
    step_summary,
)

junitparser = pytest.importorskip("junitparser")
etree = pytest.importorskip("lxml.etree")

SCHEMA = Path(__file__).resolve().parents[1] / "data" / "junit.xsd"


@pytest.fixture(scope="module")
def schema():
    return etree.XMLSchema(etree.parse(str(SCHEMA)))


def run(*args: str, env: dict | None = None) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args), env=env)
    return result.exit_code, result.stdout, result.stderr


def validate(text: str, schema) -> None:
    """``text`` is well-formed JUnit XML that the schema accepts."""
    document = etree.fromstring(text.encode("utf-8"))
    assert schema.validate(document), schema.error_log


def parse(text: str, tmp_path: Path):
    """The one suite of a JUnit document, read by junitparser (as a CI reporter reads it)."""
    path = tmp_path / "report.xml"
    path.write_text(text, encoding="utf-8")
    xml = junitparser.JUnitXml.fromfile(str(path))
    suites = list(xml) if isinstance(xml, junitparser.JUnitXml) else [xml]
    assert len(suites) == 1
    return suites[0]


def outcome(case) -> str:
    results = [type(r).__name__ for r in case.result]
    if "Failure" in results:
        return "failure"
    if "Error" in results:
        return "error"
    if "Skipped" in results:
        return "skipped"
    return "passed"


def normalised(text: str) -> str:
    """JUnit text with the run's times and meshcol's version made constant (golden files)."""
    from meshcol._version import __version__

    text = re.sub(r'time="[0-9.]+"', 'time="0"', text)
    return text.replace(f'value="{__version__}"', 'value="VERSION"')


# ---------------------------------------------------------------------------------------------
# Every command: parsed, valid, counts as the JSON report of the same run


def test_check_junit_counts_match_the_json_report(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    args = ["check", "samples/level/scene.json", "--fail-on", "contact"]
    code_json, out_json, _ = run(*args)
    code, out, _ = run(*args, "--format", "junit")
    assert code == code_json
    validate(out, schema)
    report = json.loads(out_json)
    suite = parse(out, tmp_path)
    cases = list(suite)
    assert suite.name == "meshcol check"
    assert suite.tests == len(cases) == report["summary"]["candidate_pairs"]
    assert suite.failures == report["summary"]["violations"] > 0
    assert suite.errors == 0
    by_pair = {f"{p['body_a']} <-> {p['body_b']}": p for p in report["pairs"]}
    assert {c.name for c in cases} == set(by_pair)
    for case in cases:
        pair = by_pair[case.name]
        assert case.classname == "meshcol.check"
        if pair["violation"]:
            assert outcome(case) == "failure"
            (failure,) = case.result
            assert failure.type == pair["status"]
            assert failure.message.startswith(pair["status"])
            assert "samples/level/scene.json" in failure.text
            if pair["status"] == "penetrating":
                assert f"depth {pair['depth']:.6g} m" in failure.message
        else:
            assert outcome(case) in ("passed", "skipped")
    properties = {p.name: p.value for p in suite.properties()}
    assert properties["meshcol.command"] == "check"
    assert properties["settings.fail_on"] == "contact"
    assert properties["units"] == "m"


def test_check_ignored_pairs_are_skipped(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    code_json, out_json, _ = run("check", "samples/level/scene.json", "--fail-on", "contact")
    violating = [p for p in json.loads(out_json)["pairs"] if p["violation"]]
    pair = violating[0]
    rule = f"{pair['body_a']}:{pair['body_b']}"
    code, out, _ = run(
        "check", "samples/level/scene.json", "--fail-on", "contact", "--ignore", rule,
        "--format", "junit",
    )  # fmt: skip
    validate(out, schema)
    suite = parse(out, tmp_path)
    assert suite.failures == len(violating) - 1
    assert suite.skipped == 1
    (case,) = [c for c in suite if outcome(c) == "skipped"]
    assert case.name == f"{pair['body_a']} <-> {pair['body_b']}"
    assert case.result[0].message.startswith("ignored by --ignore: ")
    assert code == (1 if len(violating) > 1 else 0)


@pytest.mark.slow
def test_inspect_junit_failures_are_the_fail_on_findings(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    args = ["inspect", "samples/level/scene.json", "--fail-on", "all"]
    code_json, out_json, _ = run(*args)
    code, out, _ = run(*args, "--report", str(tmp_path / "inspect.xml"))  # format from .xml
    assert code == code_json and out == ""
    text = (tmp_path / "inspect.xml").read_text(encoding="utf-8")
    validate(text, schema)
    report = json.loads(out_json)
    suite = parse(text, tmp_path)
    assert suite.tests == len(report["bodies"]) + len(report["errors"])
    assert suite.failures == report["summary"]["failed"]
    for case, body in zip(suite, report["bodies"]):
        assert case.name == f"{body['source']}::{body['name']}"
        assert outcome(case) == ("failure" if body["failed_rules"] else "passed")
        if body["failed_rules"]:
            assert case.result[0].type == body["failed_rules"][0]
            for rule in body["failed_rules"]:
                assert rule in case.result[0].message


def test_inspect_unreadable_file_is_an_error_case(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "broken.obj").write_text("v 0 0 0\nf 1 2 3\n")
    bowl = str(samples / "bowl" / "bowl.obj")
    code_json, out_json, _ = run("inspect", bowl, "broken.obj")
    code, out, _ = run("inspect", bowl, "broken.obj", "--format", "junit")
    assert code == code_json == 2
    validate(out, schema)
    suite = parse(out, tmp_path)
    errors = [c for c in suite if outcome(c) == "error"]
    assert suite.errors == len(errors) == len(json.loads(out_json)["errors"]) == 1
    assert errors[0].result[0].type == "unusable-input"
    assert "broken.obj" in errors[0].name


def test_sweep_junit_has_every_candidate_pair(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    code_json, out_json, _ = run("sweep", "samples/bullet/scene.json")
    code, out, _ = run("sweep", "samples/bullet/scene.json", "--format", "junit")
    assert code == code_json == 1
    validate(out, schema)
    report = json.loads(out_json)
    suite = parse(out, tmp_path)
    assert suite.tests == report["summary"]["candidate_pairs"]
    assert suite.failures == len(report["pairs"]) > 0
    failed = [c for c in suite if outcome(c) == "failure"]
    for case, pair in zip(failed, report["pairs"]):
        assert case.name == f"{pair['body_a']} <-> {pair['body_b']}"
        assert case.result[0].type == pair["status"]
        assert f"{pair['time_of_impact']:.6g}" in case.result[0].message
    code, out, _ = run(
        "sweep", "samples/bullet/scene.json", "--format", "junit", "--fail-on", "none"
    )
    assert code == 0
    assert parse(out, tmp_path).failures == 0


@pytest.mark.slow
def test_hull_and_fit_junit_one_passed_case_per_body(samples, schema, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    for command, extra in (("hull", ["--max-vertices", "16"]), ("fit", [])):
        args = [command, "samples/level/props/barrel.obj", "samples/bowl/bowl.obj", *extra]
        _, out_json, _ = run(*args)
        code, out, _ = run(*args, "--format", "junit")
        assert code == 0
        validate(out, schema)
        suite = parse(out, tmp_path)
        rows = json.loads(out_json)["bodies"]
        assert suite.tests == len(rows) and suite.failures == suite.errors == 0
        for case, row in zip(suite, rows):
            assert case.name == f"{row['source']}::{row['name']}"
            assert case.system_out
        if command == "hull":
            assert "budget 16" in next(iter(suite)).system_out


def test_hull_with_mesh_output_and_a_format_but_no_report_is_a_usage_error(samples, tmp_path):
    bowl = str(samples / "bowl" / "bowl.obj")
    for command in ("hull", "fit"):
        code, out, err = run(command, bowl, "-o", str(tmp_path / "h.obj"), "--format", "junit")
        assert (code, out) == (2, "")
        assert err == (
            "meshcol: error: --format junit: with -o/--out-dir no report is written unless "
            f"--report FILE (or --report - for stdout) says where (see 'meshcol {command} -h')\n"
        )
        assert not (tmp_path / "h.obj").exists()
    code, out, _ = run(
        "hull", bowl, "-o", str(tmp_path / "h.obj"), "--format", "junit", "--report", "-"
    )
    assert code == 0 and out.startswith("<?xml")


@pytest.mark.slow
def test_decompose_junit_fails_bodies_over_max_hausdorff(samples, schema, tmp_path):
    bullet = str(samples / "bullet" / "bullet.obj")
    wall = str(samples / "bullet" / "wall.obj")
    base = ["decompose", bullet, wall, "-o", str(tmp_path / "parts"), *FAST_DECOMPOSE]
    base += ["--cache-dir", str(tmp_path / "cache"), "--max-hausdorff", "1e-9"]
    base += ["--search-steps", "1"]  # one step misses 1e-9 as eight do (eight: 8x the time)
    base += ["--report", "-"]
    code_json, out_json, _ = run(*base)
    code, out, _ = run(*base, "--report-format", "junit")
    assert code == code_json == 1
    validate(out, schema)
    report = json.loads(out_json)
    suite = parse(out, tmp_path)
    assert suite.tests == report["summary"]["bodies"]
    assert suite.failures == report["summary"]["hausdorff_exceeded"] > 0
    case = next(c for c in suite if outcome(c) == "failure")
    assert case.result[0].type == "max-hausdorff"
    assert "> --max-hausdorff 1e-09" in case.result[0].message
    code, out, _ = run(*base, "--report-format", "github")
    assert code == 1
    assert out.count("::error file=") == suite.failures


def test_decompose_format_junit_names_the_report_option(samples, tmp_path):
    code, out, err = run(
        "decompose", str(samples / "bowl" / "bowl.obj"), "-o", str(tmp_path), "--format", "junit"
    )
    assert (code, out) == (2, "")
    assert err == (
        "meshcol: error: invalid value for '--format': 'junit' is a report format: decompose's "
        "--format is the parts' mesh format (obj, glb); give --report-format junit "
        "(see 'meshcol decompose -h')\n"
    )


def test_unknown_and_contradicting_formats_are_usage_errors(samples, tmp_path):
    bowl = str(samples / "bowl" / "bowl.obj")
    code, _, err = run("inspect", bowl, "--format", "yaml")
    assert (
        code == 2
        and "'yaml' is not one of 'json', 'csv', 'junit', 'github', 'tap', 'sarif', 'markdown'"
        in err
    )
    code, _, err = run("inspect", bowl, "--format", "github", "--report", str(tmp_path / "r.xml"))
    assert code == 2 and "is a .junit file: it cannot hold a github report" in err
    code, _, err = run("inspect", bowl, "--format", "junit", "--report", str(tmp_path / "r.json"))
    assert code == 2 and "it cannot hold a junit report" in err
    assert not list(tmp_path.iterdir())


def test_collision_matrix_refuses_a_junit_report(tmp_path):
    robot = tmp_path / "r.urdf"
    robot.write_text('<robot name="r"><link name="a"/></robot>')
    code, out, err = run("collision-matrix", str(robot), "--report", str(tmp_path / "m.xml"))
    assert (code, out) == (2, "")
    assert "would be a junit report: this command writes json or csv" in err


def test_golden_junit_check_and_inspect(samples, golden, schema, monkeypatch):
    monkeypatch.chdir(samples.parent)
    # a clearance band: failures, and passed pairs in contact, in the band and separated
    code, out, _ = run(
        "check", "samples/level/scene.json", "--clearance", "0.2", "--format", "junit"
    )
    assert code == 1
    validate(out, schema)
    golden("check_level.junit.xml", normalised(out))
    props = ["samples/level/props/table.obj", "samples/level/props/crate.obj"]
    code, out, _ = run("inspect", *props, "--fail-on", "self-intersecting", "--format", "junit")
    assert code == 1
    validate(out, schema)
    golden("inspect_props.junit.xml", normalised(out))


# ---------------------------------------------------------------------------------------------
# XML escaping


def test_names_with_markup_quotes_non_ascii_and_control_characters(schema, tmp_path):
    hostile = "a<b>&\"c'd é 漢 \x00\x01\x1b\ud800\ufffe end"
    suite = CiSuite(
        "check",
        (
            CiCase(hostile, "meshcol.check", "failure", hostile, file=hostile, kind=hostile),
            CiCase("ok", "meshcol.check", message="fine\tand\nmore"),
            CiCase("later", "meshcol.check", "skipped", "ignored"),
            CiCase("bad", "meshcol.check", "error", "unreadable"),
        ),
        {"ignore": [hostile], "tolerance": 1e-6},
        seconds=1.5,
        warnings=(hostile,),
    )
    text = dumps_junit(suite)
    validate(text, schema)
    parsed = parse(text, tmp_path)
    clean = "a<b>&\"c'd é 漢  end"
    cases = list(parsed)
    assert cases[0].name == clean
    assert cases[0].result[0].message == clean
    assert cases[0].result[0].type == clean
    assert (parsed.tests, parsed.failures, parsed.errors, parsed.skipped) == (4, 1, 1, 1)
    assert parsed.time == 1.5
    properties = {p.name: p.value for p in parsed.properties()}
    # JSON escapes the control characters (XML holds the escapes); the rest are dropped
    assert json.loads(properties["settings.ignore"]) == ["a<b>&\"c'd é 漢 \x00\x01\x1b end"]
    assert properties["settings.tolerance"] == "1e-06"


def test_many_passed_cases_become_one(schema, tmp_path):
    cases = [CiCase(f"p{i:05d}", "meshcol.check", message="separated") for i in range(6000)]
    cases[10] = CiCase("p00010", "meshcol.check", "failure", "penetrating")
    kept = collapse_passed(cases, "pairs", "meshcol.check")
    assert len(kept) == 2 and kept[0].outcome == "failure"
    assert kept[1].name == "pairs (5999 passed cases in one)"
    assert "first: p00000" in kept[1].details and "last: p05999" in kept[1].details
    assert collapse_passed(cases[:MAX_PASSED_CASES], "pairs", "x") == cases[:MAX_PASSED_CASES]
    text = dumps_junit(CiSuite("check", tuple(kept)))
    validate(text, schema)
    assert parse(text, tmp_path).tests == 2


# ---------------------------------------------------------------------------------------------
# GitHub workflow commands


def unescape_data(text: str) -> str:
    """The runner's unescaping of a command's message (actions/runner ``ActionCommand``)."""
    return text.replace("%0D", "\r").replace("%0A", "\n").replace("%25", "%")


def unescape_property(text: str) -> str:
    return (
        text.replace("%0D", "\r")
        .replace("%0A", "\n")
        .replace("%3A", ":")
        .replace("%2C", ",")
        .replace("%25", "%")
    )


COMMAND = re.compile(r"^::(error|warning|notice) ([^:]*)::(.*)$")


def parse_commands(text: str) -> list[tuple[str, dict[str, str], str]]:
    """Each line as the runner reads it: the command, its properties, its message."""
    out = []
    assert text.endswith("\n")
    for line in text[:-1].split("\n"):  # the runner reads lines ending at LF only
        match = COMMAND.match(line)
        assert match, line
        kind, props, message = match.groups()
        values = {}
        for item in props.split(","):
            key, _, value = item.partition("=")
            values[key] = unescape_property(value)
        out.append((kind, values, unescape_data(message)))
    return out


@given(st.text())
def test_escaping_round_trips_through_the_runners_unescaping(text: str) -> None:
    data = escape_data(text)
    prop = escape_property(text)
    assert "\n" not in data and "\r" not in data
    assert not set(prop) & set("\r\n:,")
    assert unescape_data(data) == text
    assert unescape_property(prop) == text


@given(st.text(min_size=1), st.text(), st.text(min_size=1))
def test_annotations_carry_any_name_message_and_file(name, message, file) -> None:
    suite = CiSuite("inspect", (CiCase(name, "meshcol.inspect", "failure", message, file=file),))
    (error, notice) = parse_commands(dumps_github(suite, workspace="/"))
    assert error[0] == "error"
    assert error[1]["title"] == f"meshcol inspect: {name}"
    assert error[2] == f"{message} ({file})"
    assert error[1]["file"] == annotation_path(file, "/")
    assert notice[0] == "notice" and notice[2].startswith("FAIL: 1 cases, 1 failures")


def test_github_annotations_of_check_name_the_file(samples, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    summary = tmp_path / "summary.md"
    summary.write_text("before\n")
    env = {"GITHUB_WORKSPACE": str(samples.parent), "GITHUB_STEP_SUMMARY": str(summary)}
    _, out_json, _ = run("check", "samples/level/scene.json", "--fail-on", "contact")
    code, out, _ = run(
        "check", str(samples / "level" / "scene.json"), "--fail-on", "contact",
        "--format", "github", env=env,
    )  # fmt: skip
    assert code == 1
    commands = parse_commands(out)
    violations = [p for p in json.loads(out_json)["pairs"] if p["violation"]]
    errors = [c for c in commands if c[0] == "error"]
    assert len(errors) == len(violations)
    for (_, props, message), pair in zip(errors, violations):
        assert props["file"] == "samples/level/scene.json"  # relative to GITHUB_WORKSPACE
        assert props["title"] == f"meshcol check: {pair['body_a']} <-> {pair['body_b']}"
        assert message.startswith(pair["status"])
    assert commands[-1][0] == "notice"
    assert commands[-1][2].startswith(f"FAIL: {len(json.loads(out_json)['pairs'])} cases")
    markdown = summary.read_text()
    assert markdown.startswith("before\n### meshcol check: FAIL")
    assert markdown.count("| failure |") == len(violations)


def test_github_warnings_for_findings_the_policy_does_not_fail_on(samples, monkeypatch):
    monkeypatch.chdir(samples.parent)
    props = ["samples/level/props/table.obj", "samples/level/props/crate.obj"]
    code, out, _ = run("inspect", *props, "--format", "github")
    _, out_json, _ = run("inspect", *props)
    assert code == 0
    commands = parse_commands(out)
    flagged = [b for b in json.loads(out_json)["bodies"] if b["findings"]]
    warnings = [c for c in commands if c[0] == "warning"]
    assert len(warnings) == len(flagged) == 1
    assert warnings[0][1]["file"] == "samples/level/props/table.obj"
    assert warnings[0][2].startswith("findings: self-intersecting (")
    assert not [c for c in commands if c[0] == "error"]
    assert commands[-1][2].startswith("PASS: ")


def test_annotation_paths_outside_the_workspace_stay_absolute(tmp_path) -> None:
    assert annotation_path(str(tmp_path / "a" / "b.obj"), str(tmp_path)) == "a/b.obj"
    assert annotation_path("/elsewhere/b.obj", str(tmp_path)) == "/elsewhere/b.obj"


def test_step_summary_cells_are_one_line_and_inert() -> None:
    case = CiCase("a|b", "meshcol.check", "failure", "x <script>\nnext", file="f|g.obj")
    text = step_summary(CiSuite("check", (case,)))
    row = text.splitlines()[-2]
    assert row == "| failure | a\\|b | f\\|g.obj | x &lt;script&gt; next |"


# ---------------------------------------------------------------------------------------------
# The registry of report formats (meshcol.io.formats): the one list the commands read


def test_every_format_is_one_registry_entry_that_writes_a_report(samples, monkeypatch):
    from meshcol.analysis.collision_matrix import CollisionMatrixReport
    from meshcol.analysis.inspect import inspect
    from meshcol.analysis.rules import RulesReport
    from meshcol.io.formats import FORMATS, REPORT_EXTENSIONS, formats_for, report_text

    assert all(
        f.extension is None or re.fullmatch(r"\.[a-z0-9]+", f.extension) for f in FORMATS.values()
    )
    assert len(REPORT_EXTENSIONS) == sum(f.extension is not None for f in FORMATS.values())
    assert formats_for(RulesReport) == formats_for(CollisionMatrixReport) == ("json", "csv")
    monkeypatch.chdir(samples.parent)
    report = inspect(["samples/bowl/bowl.obj"])
    assert formats_for(type(report)) == tuple(FORMATS)
    for name in FORMATS:
        assert report_text(report, name)  # every writer runs on a real report
    with pytest.raises(ValueError, match="report format must be one of json, csv"):
        report_text(report, "yaml")


def test_the_help_and_messages_list_the_registry():
    from meshcol.io.formats import describe_formats, report_format

    assert describe_formats() == (
        "json, csv, junit (JUnit XML for Jenkins and GitHub test reporters), github "
        "(workflow-command annotations), tap (Test Anything Protocol 14), sarif (SARIF "
        "2.1.0 for GitHub code scanning) or markdown (a pull-request comment: what is new or "
        "worse, per rule and per case).  [default: from the --report extension (.json, "
        ".csv, .xml, .tap, .sarif, .md), else json]"
    )
    assert report_format("out.XML", None) == "junit"
    assert report_format("-", None) == report_format(None, None) == "json"
    with pytest.raises(ValueError, match=r"unknown report extension '\.txt' in 'out\.txt'"):
        report_format("out.txt", None)


# ---------------------------------------------------------------------------------------------
# TAP (meshcol.io.tap): the format added by following the recipe in ARCHITECTURE.md

TAP_SUITE = CiSuite(
    command="check",
    cases=(
        CiCase("a <-> b", "meshcol.check", message="separated: distance 1 m"),
        CiCase(
            "crate #1 <-> c:\\table",
            "meshcol.check",
            outcome="failure",
            message="penetrating: depth 0.5 m",
            file="scene.json",
            kind="penetrating",
            details="depth: 0.5\nunits: m",
        ),
        CiCase("broken\nname \udcff", "meshcol.inspect", outcome="error", message="no faces"),
        CiCase("d <-> e", "meshcol.check", outcome="skipped", message="ignored by d* # e*"),
        CiCase("f.obj::f", "meshcol.inspect", message="open edges: 4", warn=True, file="f.obj"),
    ),
    warnings=("scene has no units",),
    verdict="1 pair violates --fail-on penetration",
)


def test_tap_is_exact_for_every_outcome():
    from meshcol.io.tap import dumps_tap

    assert dumps_tap(TAP_SUITE) == (
        "TAP version 14\n"
        "1..5\n"
        "ok 1 - a <-> b\n"
        "not ok 2 - crate \\#1 <-> c:\\\\table\n"
        "  ---\n"
        '  message: "penetrating: depth 0.5 m"\n'
        "  severity: fail\n"
        '  type: "penetrating"\n'
        '  file: "scene.json"\n'
        '  details: "depth: 0.5\\nunits: m"\n'
        "  ...\n"
        "not ok 3 - broken name  \n"
        "  ---\n"
        '  message: "no faces"\n'
        "  severity: error\n"
        "  ...\n"
        "ok 4 - d <-> e # SKIP ignored by d* \\# e*\n"
        "ok 5 - f.obj::f\n"
        "  ---\n"
        '  message: "open edges: 4"\n'
        "  severity: warning\n"
        '  file: "f.obj"\n'
        "  ...\n"
        "# warning: scene has no units\n"
        "# meshcol check: FAIL: 5 cases, 1 failures, 1 errors, 1 skipped (1 pair violates "
        "--fail-on penetration)\n"
    )
    assert dumps_tap(CiSuite("hull", ())) == (
        "TAP version 14\n1..0 # SKIP no cases to judge\n"
        "# meshcol hull: PASS: 0 cases, 0 failures, 0 errors, 0 skipped\n"
    )


def test_tap_diagnostics_are_yaml_with_the_case_fields():
    yaml = pytest.importorskip("yaml")
    from meshcol.io.tap import dumps_tap

    blocks = re.findall(r"^  ---\n(.*?)^  \.\.\.$", dumps_tap(TAP_SUITE), re.M | re.S)
    failure = yaml.safe_load(blocks[0])
    assert failure == {
        "message": "penetrating: depth 0.5 m",
        "severity": "fail",
        "type": "penetrating",
        "file": "scene.json",
        "details": "depth: 0.5\nunits: m",
    }
    assert [yaml.safe_load(b)["severity"] for b in blocks] == ["fail", "error", "warning"]


def test_tap_report_of_check_from_its_extension(samples, tmp_path, monkeypatch):
    monkeypatch.chdir(samples.parent)
    out = tmp_path / "check.tap"
    code, stdout, _ = run("check", "samples/bowl/scene.json", "--report", str(out))
    assert (code, stdout) == (1, "")
    lines = out.read_text().splitlines()
    assert lines[:3] == ["TAP version 14", "1..1", "not ok 1 - bowl <-> ball"]
    assert lines[-1].startswith("# meshcol check: FAIL: 1 cases, 1 failures")
    code, stdout, _ = run("inspect", "samples/bowl/bowl.obj", "--format", "tap")
    assert code == 0 and stdout.splitlines()[:3] == [
        "TAP version 14",
        "1..1",
        "ok 1 - samples/bowl/bowl.obj::bowl",
    ]


def test_check_target_findings_are_cases_as_the_exit_code_counts_them(
    samples, schema, tmp_path, monkeypatch
):
    # A check under --target fails on its bodies' limits (MC101...), which the CI suite left
    # out: JUnit listed every pair passed or failed while the run exited 1 on the findings.
    monkeypatch.chdir(samples.parent)
    args = ["check", "samples/level/scene.json", "--target", "physx-gpu"]
    code, out, _ = run(*args, "--report", "-")
    report = json.loads(out)
    failed = [f for f in report["findings"] if f["failed"]]
    assert code == 1 and len(failed) == report["summary"]["failed_findings"] >= 2
    code, out, _ = run(*args, "--format", "junit", "--report", "-")
    validate(out, schema)
    suite = parse(out, tmp_path)
    cases = {case.name: case for case in suite}
    for finding in failed:
        case = cases[f"{finding['body']}: {finding['rule']} {finding['name']}"]
        assert outcome(case) == "failure" and case.result[0].message == finding["message"]
    assert suite.failures == report["summary"]["violations"] + len(failed)
    code, out, _ = run(*args, "--format", "sarif", "--report", "-")
    results = json.loads(out)["runs"][0]["results"]
    assert sorted(r["ruleId"] for r in results if r["ruleId"] != "MC501") == sorted(
        f["rule"] for f in failed
    )
