"""--format markdown (meshcol.io.markdown): the pull-request comment, exact on a small suite,
capped, inert on hostile names, and against a real --baseline."""

from __future__ import annotations

import json
import re
from pathlib import Path

from click.testing import CliRunner

from meshcol.analysis.rules import RULES
from meshcol.cli import main
from meshcol.io.ci import CiCase, CiSuite
from meshcol.io.markdown import TABLE_ROWS, dumps_markdown

CHECK_RULES = {r.id: r.to_dict() for r in RULES if "check" in r.commands}


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def pair(name: str, outcome: str = "failure", **fields: object) -> CiCase:
    base: dict = dict(classname="meshcol.check", outcome=outcome, file="level.json",
                      kind="penetrating", rules=("MC501",))  # fmt: skip
    base.update(fields)
    return CiCase(name, **base)


def test_markdown_is_exact_with_a_baseline():
    suite = CiSuite(
        "check",
        (
            pair("crate <-> table", message="penetrating: depth 0.02 m",
                 numbers={"depth": 0.02, "distance": 0.0},
                 before={"status": "penetrating", "depth": 0.01, "distance": 0.0},
                 snapshot="shots/001-crate--table.png"),
            pair("door <-> frame", message="contact", kind="contact", rules=("MC503",),
                 numbers={"depth": 0.0, "distance": 0.0}),
            pair("lamp <-> desk", outcome="skipped", message="ignored by --ignore: x"),
            pair("cup <-> desk", outcome="passed", message="separated", kind="separated",
                 rules=()),
            pair("broken", outcome="error", message="cannot parse OBJ", kind="unusable-input",
                 rules=(), file="broken.obj"),
        ),
        verdict="2 of 4 candidate pairs violate --fail-on contact",
        units="m",
        rules=CHECK_RULES,
        baseline="release/check.json",
        warnings=("a UCX_ part names no body",),
    )  # fmt: skip
    assert dumps_markdown(suite) == (
        "### ❌ meshcol check: FAIL\n"
        "\n"
        "2 of 4 candidate pairs violate --fail-on contact\n"
        "\n"
        "Against the baseline release/check.json: 1 new, 1 worse.\n"
        "\n"
        "| rule | failing | new | worse | ignored | warnings |\n"
        "| --- | --- | --- | --- | --- | --- |\n"
        "| MC501 penetrating | 1 | 0 | 1 | 1 | 0 |\n"
        "| MC503 contact | 1 | 1 | 0 | 0 | 0 |\n"
        "\n"
        "|  | rule | pair | file | numbers (before → after) | snapshot |\n"
        "| --- | --- | --- | --- | --- | --- |\n"
        "| new | MC503 contact | door \\<-\\> frame | level.json | distance 0 m |   |\n"
        "| worse | MC501 penetrating | crate \\<-\\> table | level.json | depth 0.01 → 0.02 m "
        "| [png](shots/001-crate--table.png) |\n"
        "\n"
        "Inputs that could not be used:\n"
        "\n"
        "- broken.obj: cannot parse OBJ\n"
        "\n"
        "Warnings:\n"
        "\n"
        "- a UCX\\_ part names no body\n"
    )


def test_a_passing_run_is_one_verdict_and_no_table():
    suite = CiSuite("inspect", (CiCase("a.obj::a", "meshcol.inspect", message="ok"),),
                    verdict="1 bodies, 0 with findings")  # fmt: skip
    assert dumps_markdown(suite) == ("### ✅ meshcol inspect: PASS\n\n1 bodies, 0 with findings\n")


def test_long_runs_are_capped_with_and_n_more():
    cases = tuple(pair(f"b{k:03d} <-> c", numbers={"depth": 0.1}) for k in range(TABLE_ROWS + 7))
    text = dumps_markdown(CiSuite("check", cases, rules=CHECK_RULES))
    rows = [line for line in text.splitlines() if line.startswith("| fails |")]
    assert len(rows) == TABLE_ROWS
    assert text.rstrip().endswith("… and 7 more failing pairs (every one is in the report)")
    assert "| MC501 penetrating | 32 | 0 | 0 |" in text


def test_hostile_names_cannot_break_the_table_or_inject_markup():
    name = "a|b <img src=x onerror=alert(1)> [link](http://x) `code`\nsecond line"
    text = dumps_markdown(CiSuite("check", (pair(name, file="x|y.json"),), rules=CHECK_RULES))
    (row,) = [line for line in text.splitlines() if line.startswith("| fails |")]
    assert len(re.findall(r"(?<!\\)\|", row)) == 7  # six cells: seven unescaped bars
    for special in "<>[]`":  # HTML, links and code spans: every one escaped
        assert not re.search(rf"(?<!\\)\{special}", text), special
    assert "second line" in row  # one line


def test_check_markdown_against_a_real_baseline(samples, tmp_path, monkeypatch):
    """A PR-like change: against last release's report, one pair got deeper and one is new;
    the comment names both with their numbers, and the pairs as they were do not fail."""
    monkeypatch.chdir(samples.parent)
    scene = "samples/level/scene.json"
    report = json.loads(run("check", scene, "--fail-on", "contact")[1])
    failing = [p for p in report["pairs"] if p["violation"]]
    deep = next(p for p in failing if p["status"] == "penetrating")
    gone = next(p for p in failing if p is not deep)
    old = dict(report)
    old["pairs"] = [
        dict(p, depth=p["depth"] / 2) if p is deep else p for p in report["pairs"] if p is not gone
    ]
    baseline = tmp_path / "release.json"
    baseline.write_text(json.dumps(old))
    out = tmp_path / "comment.md"
    code, _, _ = run(
        "check", scene, "--fail-on", "contact", "--baseline", str(baseline), "--report", str(out)
    )  # fmt: skip  (the format from .md)
    assert code == 1
    text = out.read_text(encoding="utf-8")
    assert text.startswith("### ❌ meshcol check: FAIL\n")
    assert "1 new, 1 worse." in text
    escaped = {p["body_a"]: p["body_a"].replace("_", "\\_") for p in (deep, gone)}
    deep_row = next(line for line in text.splitlines() if escaped[deep["body_a"]] in line)
    assert deep_row.startswith("| worse | MC501 penetrating |")
    assert f"depth {deep['depth'] / 2:.6g} → {deep['depth']:.6g} m" in deep_row
    gone_row = next(line for line in text.splitlines() if escaped[gone["body_a"]] in line)
    assert gone_row.startswith("| new |")
    assert len([line for line in text.splitlines() if line.startswith("| new |")]) == 1
    assert Path(out).stat().st_size < 65536  # under GitHub's comment limit
