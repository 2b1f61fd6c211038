"""``meshcol ci``'s run settings from the configuration: ``jobs`` (``-j`` over it) and
``docs-url`` (``$MESHCOL_DOCS_URL`` over it, the SARIF rules' ``helpUri``), each shown by
``meshcol config`` with its origin."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from click.testing import CliRunner

from meshcol.analysis import ci as ci_module
from meshcol.analysis.rules import RULES
from meshcol.cli import main

SARIF_SCHEMA = Path(__file__).resolve().parents[1] / "data" / "sarif-2.1.0.json"
RULES_PAGE = Path(__file__).resolve().parents[2] / "docs" / "rules.md"


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def box(name: str, open_top: bool = False) -> str:
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    corners += [(x, y, 1) for x, y, _ in corners]
    faces = [(1, 3, 2), (1, 4, 3), (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6)]
    faces += [(3, 4, 8), (3, 8, 7), (4, 1, 5), (4, 5, 8)]
    faces += [] if open_top else [(5, 6, 7), (5, 7, 8)]
    lines = [f"o {name}"] + [f"v {x} {y} {z}" for x, y, z in corners]
    return "\n".join(lines + [f"f {a} {b} {c}" for a, b, c in faces]) + "\n"


@pytest.fixture
def repo(tmp_path, monkeypatch):
    monkeypatch.delenv("MESHCOL_DOCS_URL", raising=False)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "props").mkdir()
    (tmp_path / "props" / "open.obj").write_text(box("open", open_top=True))
    (tmp_path / "props" / "closed.obj").write_text(box("closed"))
    (tmp_path / "meshcol.toml").write_text(
        '# run settings\njobs = 2\ndocs-url = "https://docs.example.org/meshcol/docs/"\n\n'
        '[[assets]]\nglob = "props/*.obj"\ninspect = { fail-on = ["not-watertight"] }\n'
    )
    return tmp_path


@pytest.fixture
def seen_jobs(monkeypatch):
    """The ``jobs`` each run_ci call got (the real run_ci still runs)."""
    seen: list[int] = []
    real = ci_module.run_ci

    def spy(*args, **kwargs):
        seen.append(kwargs["jobs"])
        return real(*args, **kwargs)

    monkeypatch.setattr(ci_module, "run_ci", spy)
    return seen


def test_the_config_jobs_key_is_read_and_the_flag_overrides_it(repo, seen_jobs):
    code, _, err = run("ci", "--no-cache")
    assert code == 1, err
    code, _, err = run("ci", "--no-cache", "-j", "1")
    assert code == 1, err
    (repo / "meshcol.toml").write_text(
        (repo / "meshcol.toml").read_text().replace("jobs = 2\n", "")
    )
    code, _, err = run("ci", "--no-cache")
    assert code == 1, err
    assert seen_jobs == [2, 1, 1]


def test_config_shows_each_run_setting_and_its_origin(repo, monkeypatch):
    code, out, err = run("config")
    assert code == 0, err

    def origin(text: str, key: str) -> tuple[str, str]:
        [line] = [x for x in text.splitlines() if x.strip().startswith(key + " ")]
        value, where = line.split(key, 1)[1].rsplit("# ", 1)
        return value.strip(), where

    assert origin(out, "jobs") == ("2", "meshcol.toml:2")
    assert origin(out, "docs-url") == ('"https://docs.example.org/meshcol/docs/"', "meshcol.toml:3")
    assert origin(out, "cache-dir") == ("null", "default")
    _, out, _ = run("config", "-j", "3")
    assert origin(out, "jobs") == ("3", "flag -j")
    monkeypatch.setenv("MESHCOL_DOCS_URL", "https://mirror.example.org/docs/")
    code, out, _ = run("config", "--format", "json")
    settings = json.loads(out)["run"]
    assert settings["docs-url"] == {
        "value": "https://mirror.example.org/docs/",
        "from": "env MESHCOL_DOCS_URL",
    }
    assert settings["jobs"] == {"value": 2, "from": "meshcol.toml:2"}
    (repo / "meshcol.toml").write_text("jobs = 0\n")
    code, _, err = run("config")
    assert code == 2
    assert "meshcol.toml:1: jobs: must be >= 1, got 0" in err


def sarif_of(*args: str) -> dict:
    code, out, err = run(*args)
    assert code == 1, err
    log = json.loads(out)
    schema = json.loads(SARIF_SCHEMA.read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    errors = list(cls(schema, format_checker=cls.FORMAT_CHECKER).iter_errors(log))
    assert not errors, errors[0].message
    (sarif_run,) = log["runs"]
    return sarif_run


def anchors() -> set[str]:
    text = RULES_PAGE.read_text(encoding="utf-8")
    return {line[len('<a id="') : -len('"></a>')] for line in text.splitlines() if "<a id=" in line}


def test_the_rules_page_has_one_anchor_per_rule_id():
    assert anchors() == {rule.id.lower() for rule in RULES}


def test_help_uri_points_into_the_rules_page_under_the_configured_base(repo, monkeypatch):
    driver = sarif_of("ci", "--no-cache", "--output", "sarif=-")["tool"]["driver"]
    base = "https://docs.example.org/meshcol/docs/"
    assert driver["informationUri"] == base
    registered = [rule for rule in driver["rules"] if rule["id"].startswith("MC")]
    assert registered
    for rule in registered:
        page, _, anchor = rule["helpUri"].partition("#")
        assert page == base + "rules.md"
        assert anchor == rule["id"].lower() and anchor in anchors()
        assert f"See [{rule['id']}]({rule['helpUri']})." in rule["help"]["markdown"]
    # the environment wins over the file; a base naming the page itself is the page
    monkeypatch.setenv("MESHCOL_DOCS_URL", "https://mirror.example.org/meshcol/rules.html")
    driver = sarif_of("ci", "--no-cache", "--output", "sarif=-")["tool"]["driver"]
    uris = {rule["helpUri"] for rule in driver["rules"] if rule["id"].startswith("MC")}
    assert uris == {
        f"https://mirror.example.org/meshcol/rules.html#{rule['id'].lower()}"
        for rule in driver["rules"]
        if rule["id"].startswith("MC")
    }


def test_no_base_no_link_to_a_made_up_host(repo):
    (repo / "meshcol.toml").write_text(
        '[[assets]]\nglob = "props/*.obj"\ninspect = { fail-on = ["not-watertight"] }\n'
    )
    for args in (("ci", "--no-cache", "--output", "sarif=-"), ("inspect", "props/open.obj")):
        more = () if args[0] == "ci" else ("--fail-on", "not-watertight", "--format", "sarif")
        sarif_run = sarif_of(*args, *more)
        driver = sarif_run["tool"]["driver"]
        assert "informationUri" not in driver
        assert driver["rules"]
        for rule in driver["rules"]:
            assert "helpUri" not in rule
            if rule["id"].startswith("MC"):
                assert "Fix:" in rule["help"]["text"]  # the help is embedded
                assert "http" not in json.dumps(rule)
        assert sarif_run["results"][0]["ruleId"] == "MC401"
