"""Values that used to crash a command with a traceback (exit 1) or were accepted silently
(issue #29, item 12): each is one ``meshcol: error:`` line and exit 2, or, where it has a
meaning, runs; the public functions refuse what the command line refuses."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

import meshcol
from meshcol.cli import main

TETRA_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
_ARM = (
    '<robot name="arm"><link name="a"><collision><geometry><box size="1 1 1"/></geometry>'
    '</collision></link><link name="b"><collision><origin xyz="3 0 0"/><geometry><box '
    'size="1 1 1"/></geometry></collision></link><joint name="j" type="revolute"><parent '
    'link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="{lower}" upper="1" '
    'effort="1" velocity="1"/></joint></robot>'
)
USAGE = r" \(see 'meshcol [a-z-]+ -h'\)"


@pytest.fixture()
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.obj").write_text(TETRA_OBJ)
    (tmp_path / "empty.urdf").write_text('<robot name="empty"></robot>')
    (tmp_path / "nan.urdf").write_text(_ARM.format(lower="nan"))
    return tmp_path


@pytest.mark.parametrize(
    ("args", "pattern"),
    [
        (
            ["fit", "t.obj", "--volume-tolerance", "nan"],
            r"invalid value for '--volume-tolerance': 'nan' is not a finite number" + USAGE,
        ),
        *[
            (
                [command, "empty.urdf"],
                r"empty\.urdf: the robot has no <link> element",
            )
            for command in ("check", "collision-matrix", "inspect", "hull", "fit")
        ],
        (["check", "nan.urdf"], r"nan\.urdf: joint 'j': limit is not a number \(nan\)"),
        (
            ["collision-matrix", "nan.urdf", "--samples", "1000000000000"],
            r"invalid value for '--samples': 1000000000000 is more than the 10,000,000 "
            r"samples one run can hold" + USAGE,
        ),
        (
            ["decompose", "t.obj", "-o", "parts", "-E", "mcts_iterations=-5"],
            r"invalid value for '--engine-option': coacd option 'mcts_iterations' must be "
            r">= 1, got -5" + USAGE,
        ),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else None,
)
def test_bad_values_are_one_line(folder, args, pattern) -> None:
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert re.fullmatch(f"meshcol: error: {pattern}\n", result.stderr), result.stderr
    assert not (folder / "parts").exists()


def test_a_huge_timeout_means_no_limit(folder) -> None:
    """``--timeout 1e308`` overflowed the wait on the workers (OverflowError, exit 1)."""
    result = CliRunner().invoke(main, ["inspect", "t.obj", "--timeout", "1e308"])
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[-1] == "meshcol: inspect: PASS: 1 body, 0 with findings"


@pytest.mark.parametrize(
    ("function", "keywords", "message"),
    [
        (meshcol.check, {"jobs": 0}, "jobs must be an integer of at least 1, got 0"),
        (meshcol.check, {"threads": -1}, r"threads must be an integer of at least 0"),
        (meshcol.check, {"timeout": float("nan")}, "timeout must be a finite number"),
        (meshcol.inspect, {"jobs": 0}, "jobs must be an integer of at least 1, got 0"),
    ],
)
def test_the_api_refuses_what_the_command_line_refuses(folder, function, keywords, message):
    with pytest.raises(ValueError, match=message):
        function(["t.obj"], **keywords)


def test_running_out_of_memory_is_one_line(folder, monkeypatch) -> None:
    """A result larger than memory (the core's pair list of 100,000 overlapping bodies raises
    std::bad_alloc, which its thread pool now rethrows as MemoryError instead of aborting)
    is one line and exit 2, not a traceback."""
    import meshcol.analysis.check as check_module

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(check_module, "check_scene", exhausted)
    result = CliRunner().invoke(main, ["check", "t.obj"])
    assert result.exit_code == 2, result.output
    assert result.stderr == (
        "meshcol: error: out of memory: the input needs more memory than this machine has\n"
    )
