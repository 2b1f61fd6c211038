"""A run's outputs are written together or not at all (issue #29, item 13): a report that
cannot be written (``/dev/full``) leaves no mesh, part or page of the run behind, and the one
error line names the file."""

from __future__ import annotations

import importlib.util
import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import main

TETRA_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
FULL = "/dev/full"

pytestmark = pytest.mark.skipif(not os.path.exists(FULL), reason="needs /dev/full (Linux)")


def _leftovers(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.name != "t.obj")


def _failed_on_full(result) -> None:
    assert result.exit_code == 2, result.output
    assert re.fullmatch(r"meshcol: error: /dev/full: No space left on device\n", result.stderr), (
        result.stderr
    )


@pytest.mark.parametrize(
    "args",
    [
        ["hull", "t.obj", "-o", "h.obj", "--report", FULL],
        ["hull", "t.obj", "--out-dir", "hulls", "--report", FULL],
        ["fit", "t.obj", "-o", "f.obj", "--report", FULL],
        ["decompose", "t.obj", "-o", "parts", "--no-cache", "--report", FULL, *FAST_DECOMPOSE],
    ],
    ids=["hull -o", "hull --out-dir", "fit -o", "decompose -o"],
)
def test_a_failed_report_leaves_no_mesh(tmp_path, monkeypatch, args) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.obj").write_text(TETRA_OBJ)
    result = CliRunner().invoke(main, args)
    _failed_on_full(result)
    assert _leftovers(tmp_path) == []


@pytest.mark.skipif(importlib.util.find_spec("meshcat") is None, reason="needs meshcol[review]")
@pytest.mark.parametrize("command", ["check", "inspect"])
def test_a_failed_page_leaves_no_report(tmp_path, monkeypatch, command) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.obj").write_text(TETRA_OBJ)
    result = CliRunner().invoke(main, [command, "t.obj", "--report", "r.json", "--html", FULL])
    _failed_on_full(result)
    assert _leftovers(tmp_path) == []


def test_outputs_land_together_when_every_one_is_written(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.obj").write_text(TETRA_OBJ)
    result = CliRunner().invoke(main, ["hull", "t.obj", "-o", "h.obj", "--report", "r.json"])
    assert result.exit_code == 0, result.output
    assert _leftovers(tmp_path) == ["h.obj", "r.json"]
    assert result.stderr.splitlines()[-1].startswith("meshcol: hull: PASS")


# ---------------------------------------------------------------------------------------------
# item 17: off a terminal, a slow failure says one line


def test_progress_is_silent_off_a_terminal_unless_asked(monkeypatch) -> None:
    """The command line's progress (stderr, the default stream) prints nothing when stderr is
    a pipe or a log, so a slow run that fails says only its error; ``MESHCOL_PROGRESS=1``
    brings the lines back for CI logs."""
    import io
    import sys
    import time

    from meshcol.cli.common import Progress

    for wanted, expect_lines in (("", False), ("1", True)):
        monkeypatch.setenv("MESHCOL_PROGRESS", wanted)
        stream = io.StringIO()
        monkeypatch.setattr(sys, "stderr", stream)
        progress = Progress(delay=0.0, interval=0.05, command="decompose", heartbeat=True)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and not (stream.getvalue() if expect_lines else False):
            time.sleep(0.05)
            if not expect_lines and time.monotonic() > deadline - 9.5:
                break
        progress("decompose: 1/2 files")
        progress.done()
        assert bool(stream.getvalue()) == expect_lines, (wanted, stream.getvalue())
