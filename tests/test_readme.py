"""The README's Python example runs as written (from the repository root)."""

from __future__ import annotations

import re
from pathlib import Path

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
    assert len(scene.bodies) == 7 and scene.units == "m" and scene.duration == 0.5
    schema = json.loads(SCHEMA_PATH.read_text())
    document = json.loads(block)
    assert set(schema["properties"]) <= set(document)
    body_fields = set(schema["properties"]["bodies"]["items"]["properties"])
    used = set().union(*(b.keys() for b in document["bodies"]))
    assert body_fields <= used, f"README manifest lacks {sorted(body_fields - used)}"
    kinds = {b["primitive"]["type"] for b in document["bodies"] if "primitive" in b}
    assert kinds == {"sphere", "box", "capsule", "cylinder", "ellipsoid"}


def test_readme_has_a_ci_recipe() -> None:
    text = (REPO / "README.md").read_text()
    assert "## Your assets in CI" in text
    assert "--baseline" in text.split("## Your assets in CI")[1]


def test_readme_command_table_names_every_command() -> None:
    from meshcol.cli import COMMANDS

    text = (REPO / "README.md").read_text().split("## What it does")[1].split("\n\n##")[0]
    rows = re.findall(r"^\| `meshcol ([a-z-]+)`", text, flags=re.M)
    assert set(rows) == set(COMMANDS), sorted(set(COMMANDS) ^ set(rows))
    assert len(rows) == len(set(rows)), sorted(row for row in rows if rows.count(row) > 1)


#: Lines of a live progress display (a slow run on a loaded machine prints them): not part of
#: what the tour shows.
_PROGRESS = re.compile(r"^meshcol: [a-z-]+: .*\(\d[^)]* elapsed[^)]*\)$")


def _tour() -> list[tuple[str, list[str]]]:
    """``(command, the lines the README shows it printing)`` for every ``$`` line of the
    README's tour (from "A short tour" to "Scene manifests")."""
    text = (REPO / "README.md").read_text().split("## A short tour")[1].split("## Scene")[0]
    steps: list[tuple[str, list[str]]] = []
    for block in re.findall(r"```\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            if line.startswith("$ "):
                steps.append((line[2:], []))
            elif steps:
                steps[-1][1].append(line)
    return steps


def _untimed(line: str) -> str:
    """Timings and CoACD's part count (its version's) aside."""
    line = re.sub(r"\(\d+\.\d+ s check, \d+\.\d+ s load\)", "(T)", line)
    return re.sub(r"\d+ parts$", "N parts", line)


@pytest.mark.slow
def test_every_tour_line_runs_as_printed(tmp_path: Path, bowl_cache_home: Path) -> None:
    """Issue 29 item 18: the tour's commands run from the repository root as printed (here a
    copy of its samples, so the outputs land in a temporary folder) and print what the
    README shows. The decompose cache is the run's own, not the user's: the bowl's parts
    (CoACD's defaults) are in it when the ball-in-bowl check ran first (the line prints the
    same from a cold or a warm cache)."""
    import os
    import shutil
    import subprocess
    import sys

    steps = _tour()
    assert len(steps) >= 6 and all(command.startswith("meshcol ") for command, _ in steps)
    shutil.copytree(REPO / "samples", tmp_path / "samples")
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    env["XDG_CACHE_HOME"] = str(bowl_cache_home)
    for command, shown in steps:
        done = subprocess.run(
            ["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True, text=True
        )
        assert done.returncode in (0, 1), (command, done.stderr)
        printed = [line for line in done.stderr.splitlines() if not _PROGRESS.match(line)]
        if shown:  # a line shown without its output is only run
            assert [_untimed(x) for x in printed] == [_untimed(x) for x in shown], command
