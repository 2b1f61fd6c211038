"""Hostile input on the command line (issue #13): never a traceback, never a destroyed input,
one ``meshcol: error:`` line and exit 2, and one voice for summaries.

Each row of :data:`CASES` is a command, the exit code it must give, a regular expression the
whole of stderr must match (one line), and files that must not exist afterwards. Every case
runs in a fresh folder holding :func:`_workspace`'s files, and every input file must be
byte-for-byte intact afterwards.
"""

from __future__ import annotations

import io
import json
import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import UNIT_CUBE_OBJ as CUBE_OBJ

from meshcol.cli import main
from meshcol.cli.common import Progress

DEEP = 5000  # nesting far beyond Python's recursion limit


def _scaled(factor: str) -> str:
    return "".join(
        " ".join(["v", *(f"{c}{factor}" for c in line.split()[1:])]) + "\n"
        if line.startswith("v ")
        else line + "\n"
        for line in CUBE_OBJ.splitlines()
    )


def _manifest(**body: object) -> str:
    moving = {"name": "b", "mesh": "cube.obj", "position": [3, 0, 0], **body}
    return json.dumps(
        {"units": "m", "duration": 1.0, "bodies": [{"name": "a", "mesh": "cube.obj"}, moving]}
    )


def _workspace(folder: Path) -> dict[str, bytes]:
    files = {
        "cube.obj": CUBE_OBJ,
        "other.obj": CUBE_OBJ,
        "huge.obj": _scaled("e300"),
        "scene.json": _manifest(),
        "motion.json": _manifest(velocity=[-5, 0, 0]),
        "deep.json": '{"bodies": ' + "[" * DEEP + "]" * DEEP + "}",
        "deep.toml": "bodies = " + "[" * DEEP + "]" * DEEP + "\n",
        "deep_baseline.json": '{"pairs": ' + "[" * DEEP + "]" * DEEP + "}",
        "huge_velocity.json": _manifest(velocity=[1e308, 0, 0]),
        "huge_spin.json": _manifest(angular_velocity=[1e300, 0, 0]),
        "huge_scale.json": _manifest(scale=1e300),
        "huge_position.json": _manifest(position=[1e200, 0, 0]),
        "base.json": json.dumps({"pairs": []}),
    }
    for name, text in files.items():
        (folder / name).write_text(text)
    return {name: (folder / name).read_bytes() for name in files}


ERR = r"meshcol: error: "
USAGE = r" \(see 'meshcol [a-z]+ -h'\)"

CASES = [
    # item 4: an output onto an input, or two outputs that are one file
    ("hull cube.obj -o cube.obj", 2, ERR + r"cube\.obj: -o would overwrite the input", []),
    ("hull cube.obj -o ./cube.obj", 2, ERR + r"\./cube\.obj: -o would overwrite the input", []),
    (
        "inspect cube.obj --report cube.obj",
        2,
        ERR + r"cube\.obj: --report would overwrite the input",
        [],
    ),
    (
        "check scene.json --report scene.json",
        2,
        ERR + r"scene\.json: --report would overwrite the input",
        [],
    ),
    (
        "check scene.json --format json --report cube.obj",
        2,
        ERR + r"cube\.obj: --report would overwrite a mesh file of scene\.json",
        [],
    ),
    (
        "check scene.json --baseline base.json --report base.json",
        2,
        ERR + r"base\.json: --report would overwrite the --baseline",
        [],
    ),
    (
        "sweep motion.json --report motion.json",
        2,
        ERR + r"motion\.json: --report would overwrite the input",
        [],
    ),
    (
        "hull cube.obj -o out.obj --format json --report out.obj",
        2,
        ERR + r"out\.obj: -o and --report are the same file",
        ["out.obj"],
    ),
    (
        "hull cube.obj other.obj --out-dir .",
        2,
        ERR + r"\./cube\.obj: --out-dir file would overwrite an input mesh",
        [],
    ),
    (
        "hull cube.obj --out-dir hulls --format json --report hulls/cube.obj",
        2,
        ERR
        + r"hulls/cube\.obj: --report and --out-dir file are the same file|"
        + ERR
        + r"hulls/cube\.obj: --out-dir file and --report are the same file",
        ["hulls/cube.obj"],
    ),
    # item 5: tracebacks become one line
    (
        "check deep.json --report r.json",
        2,
        ERR + r"deep\.json: manifest nests arrays and objects more than 32 deep \(line 1\)",
        ["r.json"],
    ),
    (
        "check deep.toml --report r.json",
        2,
        ERR + r"deep\.toml: manifest nests arrays and objects more than 32 deep \(line 1\)",
        ["r.json"],
    ),
    (
        "check scene.json --baseline deep_baseline.json --report r.json",
        2,
        ERR + r"deep_baseline\.json: baseline nests arrays and objects too deep$",
        ["r.json"],
    ),
    (
        "inspect huge.obj --report r.json",
        2,
        ERR + r"huge\.obj: vertex 2 has coordinate 1e\+300, beyond the limit of \+/-1e\+10",
        ["r.json"],
    ),
    (
        "check huge.obj --report r.json",
        2,
        ERR + r"huge\.obj: vertex 2 has coordinate 1e\+300, beyond the limit of \+/-1e\+10",
        ["r.json"],
    ),
    *[
        (
            f"check scene.json --{flag} {value} --report r.json",
            2,
            ERR + rf"invalid value for '--{flag}': '{value}' is not a finite number" + USAGE,
            ["r.json"],
        )
        for flag in ("tolerance", "clearance")
        for value in ("nan", "inf", "1e309")
    ],
    (
        "sweep motion.json --tolerance nan --report r.json",
        2,
        ERR + r"invalid value for '--tolerance': 'nan' is not a finite number" + USAGE,
        ["r.json"],
    ),
    (
        "sweep huge_spin.json --report r.json",
        2,
        ERR + r"huge_spin\.json: body 'b': angular_velocity x duration is 1e\+300 rad, beyond "
        r"the limit of 1e\+06 rad \(angular_velocity \[1e\+300, 0, 0\], duration 1 s\) \(line 1\)",
        ["r.json"],
    ),
    # item 9: the message names the value at fault, the manifest and the body
    (
        "sweep huge_velocity.json --report r.json",
        2,
        ERR + r"huge_velocity\.json: body 'b': velocity x duration is 1e\+308, beyond the "
        r"limit of 1e\+10 \(velocity \[1e\+308, 0, 0\], duration 1 s\) \(line 1\)",
        ["r.json"],
    ),
    (
        "hull huge_scale.json --report r.json",
        2,
        ERR + r"huge_scale\.json: body 'b': scale 1e\+300 is beyond the limit of \+/-1e\+10 "
        r"\(line 1\)",
        ["r.json"],
    ),
    (
        "check huge_position.json --report r.json",
        2,
        ERR + r"huge_position\.json: body 'b': position 1e\+200 is beyond the limit of "
        r"\+/-1e\+10 \(line 1\)",
        ["r.json"],
    ),
    (
        "inspect cube.obj --report missing/r.json",
        2,
        ERR + r"missing/r\.json: folder missing does not exist",
        ["missing"],
    ),
    # item 10: click's usage errors as one line with the prefix
    (
        "hull cube.obj --max-vertices 3",
        2,
        ERR + r"invalid value for '--max-vertices': 3 is not in the range x>=4" + USAGE,
        [],
    ),
    (
        "decompose cube.obj -o parts --jobs 0",
        2,
        ERR + r"invalid value for '--jobs' / '-j': 0 is not in the range x>=1" + USAGE,
        ["parts"],
    ),
    (
        "inspect cube.obj --format xml",
        2,
        ERR + r"invalid value for '--format': 'xml' is not one of 'json', 'csv', 'junit', "
        r"'github', 'tap', 'sarif', 'markdown'" + USAGE,
        [],
    ),
    (
        "inspect cube.obj --report out.txt",
        2,
        ERR + r"invalid value for '--report': unknown report extension '\.txt' in 'out\.txt': "
        r"expected \.json, \.csv, \.xml, \.tap, \.sarif or \.md \(or give --format "
        r"json\|csv\|junit\|github\|tap\|sarif\|markdown\)" + USAGE,
        ["out.txt"],
    ),
    (
        "check scene.json --format csv --report out.json",
        2,
        ERR + r"invalid value for '--report': 'out\.json' is a \.json file: it cannot hold a "
        r"csv report" + USAGE,
        ["out.json"],
    ),
    (
        "decompose cube.obj -o parts --report out.txt",
        2,
        ERR + r"invalid value for '--report': unknown report extension '\.txt' in 'out\.txt': "
        r"expected \.json, \.csv, \.xml, \.tap, \.sarif or \.md \(or give --report-format "
        r"json\|csv\|junit\|github\|tap\|sarif\|markdown\)" + USAGE,
        ["parts", "out.txt"],
    ),
    ("check", 2, ERR + r"missing argument 'INPUT\.\.\.'" + USAGE, []),
    ("sweep motion.json --bogus", 2, ERR + r"no such option '--bogus'" + USAGE, []),
    ("frobnicate", 2, ERR + r"no such command 'frobnicate' \(see 'meshcol -h'\)", []),
    (
        "hull cube.obj -o a.obj --out-dir d",
        2,
        ERR + r"give either -o/--output or --out-dir, not both" + USAGE,
        ["a.obj", "d"],
    ),
]


@pytest.mark.parametrize(("command", "code", "stderr", "absent"), CASES, ids=[c[0] for c in CASES])
def test_hostile_command(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, command, code, stderr, absent
) -> None:
    monkeypatch.chdir(tmp_path)
    before = _workspace(tmp_path)
    result = CliRunner().invoke(main, command.split())
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    assert re.fullmatch(f"(?:{stderr})\n", result.stderr), result.stderr
    for name in absent:
        assert not (tmp_path / name).exists(), name
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data, f"{name} was changed"
    assert not list(tmp_path.glob("**/.meshcol-*")), "a temporary file was left behind"


def test_hull_through_a_symbolic_link_is_refused(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    os.symlink("cube.obj", "link.obj")
    result = CliRunner().invoke(main, ["hull", "link.obj", "-o", "cube.obj"])
    assert result.exit_code == 2
    assert result.stderr == "meshcol: error: cube.obj: -o would overwrite the input\n"
    assert (tmp_path / "cube.obj").read_text() == CUBE_OBJ


def test_hard_link_is_the_same_file(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    os.link("cube.obj", "twin.obj")
    result = CliRunner().invoke(main, ["hull", "cube.obj", "-o", "twin.obj"])
    assert result.exit_code == 2
    assert result.stderr == "meshcol: error: twin.obj: -o would overwrite the input\n"


def test_huge_quaternion_is_a_rotation_not_zero(tmp_path: Path) -> None:
    """A quaternion of 1e308 components is finite and non-zero: it means the same rotation as
    its normalised form (the norm used to overflow and the message said 'must not be zero')."""
    import numpy as np

    from meshcol.io.scene import rotation_from_quaternion

    big = rotation_from_quaternion([1e308, 1e308, 0, 0])
    np.testing.assert_allclose(big, rotation_from_quaternion([1, 1, 0, 0]), atol=1e-15)
    np.testing.assert_allclose(big[1:, 1:], [[0, -1], [1, 0]], atol=1e-15)
    with pytest.raises(ValueError, match="non-zero"):
        rotation_from_quaternion([0, 0, 0, 0])


def test_coordinates_at_the_limit_are_accepted(tmp_path: Path, monkeypatch) -> None:
    """1e9 is within the limit: the cube is read, inspected and its volume exact."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "big.obj").write_text(_scaled("e9"))
    result = CliRunner().invoke(main, ["inspect", "big.obj"])
    assert result.exit_code == 0, result.output
    (body,) = json.loads(result.stdout)["bodies"]
    assert body["volume"] == pytest.approx(1e27) and body["watertight"]


# ---------------------------------------------------------------------------------------------
# item 8: a batch keeps going


def test_inspect_batch_reports_the_healthy_files_and_exits_2(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    (tmp_path / "garbage.obj").write_text("not a mesh\n")
    result = CliRunner().invoke(
        main, ["inspect", "cube.obj", "garbage.obj", "huge.obj", "other.obj", "--report", "r.json"]
    )
    assert result.exit_code == 2, result.output
    report = json.loads((tmp_path / "r.json").read_text())
    assert [b["name"] for b in report["bodies"]] == ["cube", "other"]
    assert report["errors"] == [
        {"source": "garbage.obj", "body": None, "message": "mesh has no faces"},
        {
            "source": "huge.obj",
            "body": None,
            "message": "vertex 2 has coordinate 1e+300, beyond the limit of +/-1e+10",
        },
    ]
    assert report["failed"] is True and report["summary"]["errors"] == 2
    lines = result.stderr.splitlines()
    assert "meshcol: error: garbage.obj: mesh has no faces" in lines
    assert lines[-1] == "meshcol: inspect: FAIL: 2 bodies, 0 with findings, 2 inputs not inspected"


def test_inspect_with_no_readable_file_writes_no_report(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "garbage.obj").write_text("not a mesh\n")
    result = CliRunner().invoke(main, ["inspect", "garbage.obj", "--report", "r.json"])
    assert result.exit_code == 2
    assert result.stderr == "meshcol: error: garbage.obj: mesh has no faces\n"
    assert not (tmp_path / "r.json").exists()


# ---------------------------------------------------------------------------------------------
# item 12: one summary voice


@pytest.mark.parametrize(
    ("command", "last_line"),
    [
        ("check scene.json", r"meshcol: check: PASS: no pair violates --fail-on penetration"),
        ("sweep motion.json", r"meshcol: sweep: FAIL: 1 pair touches during the motion"),
        ("inspect cube.obj", r"meshcol: inspect: PASS: 1 body, 0 with findings"),
        ("hull cube.obj other.obj", r"meshcol: hull: PASS: 2 hulls, 16 vertices"),
        (
            "hull cube.obj -o h.obj",
            r"meshcol: hull: PASS: 1 hull, 8 vertices, written to h\.obj",
        ),
    ],
)
def test_every_command_ends_with_one_verdict_line(
    tmp_path: Path, monkeypatch, command: str, last_line: str
) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    result = CliRunner().invoke(main, command.split())
    assert result.exit_code in (0, 1), result.output
    assert re.fullmatch(last_line, result.stderr.splitlines()[-1]), result.stderr


def test_decompose_ends_with_a_verdict_line(tmp_path: Path, monkeypatch) -> None:
    from conftest import FAST_DECOMPOSE

    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    result = CliRunner().invoke(
        main, ["decompose", "cube.obj", "-o", "parts", "--no-cache", *FAST_DECOMPOSE]
    )
    assert result.exit_code == 0, result.output
    assert re.fullmatch(
        r"meshcol: decompose: PASS: 1 file, 1 body, \d+ parts?", result.stderr.splitlines()[-1]
    )


def test_check_table_says_how_many_more(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    boxes = [
        {
            "name": f"box{i:02d}",
            "primitive": {"type": "box", "size": [1, 1, 1]},
            "position": [i, 0, 0],
        }
        for i in range(15)
    ]
    (tmp_path / "row.json").write_text(json.dumps({"bodies": boxes}))
    result = CliRunner().invoke(main, ["check", "row.json"])
    lines = result.stderr.splitlines()
    assert "  ... 4 more (every pair is in the report)" in lines
    assert lines[0].startswith("meshcol: check: 15 bodies, 14 candidate pairs (")


def test_help_lists_whole_descriptions_and_every_default() -> None:
    from meshcol.cli import COMMANDS

    top = CliRunner().invoke(main, ["-h"]).output
    assert "..." not in top.split("Commands:")[1]
    assert "meshcol check" in top.split("Options:")[0]
    for name in COMMANDS:
        command = main.get_command(None, name)  # type: ignore[arg-type]
        for option in command.params:
            if not isinstance(option, __import__("click").Option) or option.is_flag:
                continue
            text = option.help or ""
            assert option.show_default or "[default:" in text or option.required, (
                name,
                option.name,
            )


# ---------------------------------------------------------------------------------------------
# item 13: progress


class _Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_progress_off_a_terminal_prints_a_line_every_few_seconds() -> None:
    stream, clock = io.StringIO(), _Clock()
    progress = Progress(stream, clock=clock)
    for second in range(0, 30):
        clock.now = float(second)
        progress(f"inspect: {second + 1}/30 bodies")
    progress.done()
    lines = stream.getvalue().splitlines()
    # nothing in the first 5 s, then one line every 5 s: at 5, 10, 15, 20, 25 s
    assert len(lines) == 5
    assert lines[0] == "meshcol: inspect: 6/30 bodies (5 s elapsed, about 20 s left)"
    assert lines[-1].startswith("meshcol: inspect: 26/30 bodies (25 s elapsed")


def test_progress_on_a_terminal_is_a_live_bar() -> None:
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    stream, clock = Terminal(), _Clock()
    progress = Progress(stream, clock=clock)
    progress("hull: 1/4 bodies")  # before the delay: nothing
    clock.now = 6.0
    progress("hull: 2/4 bodies")
    clock.now = 6.5
    progress("hull: 3/4 bodies")
    progress.done()
    text = stream.getvalue()
    assert text.startswith("\r\033[Kmeshcol: hull: 2/4 bodies [##########..........] (6 s elapsed")
    assert "3/4 bodies [###############.....] (6 s elapsed, about 2 s left)" in text
    assert text.endswith("\r\033[K")


def test_short_runs_print_no_progress(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    result = CliRunner().invoke(main, ["inspect", "cube.obj", "other.obj"])
    assert not any("bodies (" in line for line in result.stderr.splitlines())


# ---------------------------------------------------------------------------------------------
# item 14: one CSV convention


@pytest.mark.parametrize(
    "command",
    ["check scene.json", "sweep motion.json", "inspect cube.obj", "hull cube.obj"],
)
def test_csv_has_one_number_per_cell_and_units(tmp_path: Path, monkeypatch, command) -> None:
    import csv

    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    CliRunner().invoke(main, [*command.split(), "--report", "r.csv"])
    rows = list(csv.DictReader((tmp_path / "r.csv").open()))
    header = (tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert "units" in header
    for row in rows:
        for column, cell in row.items():
            if column in ("findings", "failed_rules", "units_reason", "note"):
                continue
            assert " " not in cell, (column, cell)
    if command.startswith("sweep"):
        assert {"point_x", "normal_z", "pose_a_00", "pose_b_33"} <= set(header)
        assert rows and rows[0]["units"] == "m"
    if command.startswith("inspect"):
        assert {"bounds_min_x", "bounds_max_z", "size_y"} <= set(header)


def test_progress_heartbeat_shows_a_long_silent_step() -> None:
    """A step that sends no message for longer than the interval (one 26 s file) still
    prints lines: the heartbeat repeats the last message."""
    import time

    stream = io.StringIO()
    progress = Progress(stream, delay=0.2, interval=0.2, command="decompose", heartbeat=True)
    deadline = time.monotonic() + 30  # a bound: a loaded machine starves the timer thread
    while len(stream.getvalue().splitlines()) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    progress.done()
    lines = stream.getvalue().splitlines()
    assert len(lines) >= 2
    assert all(line.startswith("meshcol: decompose: working (") for line in lines)
    after = stream.getvalue()
    time.sleep(0.3)
    assert stream.getvalue() == after  # stopped


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        (
            "tall.json",
            '{\n  "duration": 1,\n  "bodies": [\n    {"name": "a", "mesh": "cube.obj"},\n'
            '    {\n      "name": "b",\n      "mesh": "cube.obj",\n'
            '      "angular_velocity": [0, 0, 1],\n      "velocity": [1e308, 0, 0]\n    }\n  ]\n}\n',
            "body 'b': velocity x duration is 1e+308, beyond the limit of 1e+10 "
            "(velocity [1e+308, 0, 0], duration 1 s) (line 9)",
        ),
        (
            "tall.toml",
            '[[bodies]]\nname = "a"\nmesh = "cube.obj"\n[[bodies]]\nmesh = "cube.obj"\n'
            'position = [1e20, 0, 0]\nname = "b"\n',
            "body 'b': position 1e+20 is beyond the limit of +/-1e+10 (line 6)",
        ),
    ],
)
def test_magnitude_errors_name_the_line(tmp_path: Path, monkeypatch, name, text, message) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    (tmp_path / name).write_text(text)
    result = CliRunner().invoke(main, ["check", name])
    assert result.exit_code == 2
    assert result.stderr == f"meshcol: error: {name}: {message}\n"


def _typed_options() -> list[tuple[str, str]]:
    """(command, option) for every option whose type rejects the word 'bogus'."""
    import click

    from meshcol.cli import COMMANDS
    from meshcol.cli.common import FiniteFloat

    found = []
    for name in sorted(COMMANDS):
        command = main.get_command(None, name)  # type: ignore[arg-type]
        for option in command.params:
            if isinstance(option, click.Option) and not option.is_flag:
                kinds = (click.Choice, click.types._NumberParamTypeBase, FiniteFloat)
                if isinstance(option.type, kinds):
                    found.append((name, max(option.opts, key=len)))
    return found


@pytest.mark.parametrize(("command", "option"), _typed_options())
def test_every_bad_option_value_is_one_line(tmp_path: Path, monkeypatch, command, option) -> None:
    monkeypatch.chdir(tmp_path)
    _workspace(tmp_path)
    extra = ["-o", "parts"] if command == "decompose" and option not in ("-o", "--out-dir") else []
    result = CliRunner().invoke(main, [command, "cube.obj", *extra, option, "bogus"])
    assert result.exit_code == 2, result.output
    assert re.fullmatch(
        rf"meshcol: error: invalid value for '[^']*{re.escape(option)}'[^\n]*"
        rf" \(see 'meshcol {command} -h'\)\n",
        result.stderr,
    ), result.stderr
    assert not (tmp_path / "parts").exists()
