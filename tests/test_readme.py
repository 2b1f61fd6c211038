"""The README's Python example runs as written (from the repository root)."""

from __future__ import annotations

import re

import pytest
from conftest import REPO


def test_readme_python_blocks_run(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    text = (REPO / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "README has no python example"
    monkeypatch.chdir(REPO)
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "2.0" in out


def test_readme_starts_with_the_two_commands() -> None:
    lines = (REPO / "README.md").read_text().splitlines()
    assert lines[2:6] == ["```", "make demo", "make test", "```"]


def test_readme_manifest_is_complete_and_loads(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The copy-paste manifest loads as written (from the repository root) and uses every
    field of the scene schema."""
    import json

    from meshcol.io.scene import SCHEMA_PATH, load_scene

    text = (REPO / "README.md").read_text()
    (block,) = re.findall(r"```json\n(.*?)```", text, flags=re.S)
    monkeypatch.chdir(REPO)
    manifest = tmp_path / "scene.json"
    manifest.write_text(block.replace('"samples/', f'"{REPO}/samples/'))
    scene = load_scene(manifest)
    assert len(scene.bodies) == 6 and scene.units == "m" and scene.duration == 0.5
    schema = json.loads(SCHEMA_PATH.read_text())
    document = json.loads(block)
    assert set(schema["properties"]) <= set(document)
    body_fields = set(schema["properties"]["bodies"]["items"]["properties"])
    used = set().union(*(b.keys() for b in document["bodies"]))
    assert body_fields <= used, f"README manifest lacks {sorted(body_fields - used)}"
    kinds = {b["primitive"]["type"] for b in document["bodies"] if "primitive" in b}
    assert kinds == {"sphere", "box", "capsule", "cylinder"}


def test_readme_has_a_ci_recipe() -> None:
    text = (REPO / "README.md").read_text()
    assert "## Your assets in CI" in text
    assert "--baseline" in text.split("## Your assets in CI")[1]


def test_readme_command_table_names_every_command() -> None:
    from meshcol.cli import COMMANDS

    text = (REPO / "README.md").read_text().split("## What it does")[1].split("\n\n##")[0]
    listed = set(re.findall(r"^\| `meshcol ([a-z-]+)`", text, flags=re.M))
    assert listed == set(COMMANDS), sorted(set(COMMANDS) ^ listed)
