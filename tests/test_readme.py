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
