"""The check report's rows written by the core straight into the report file (issue 32 items
4-5): the bytes of the text path, in blocks on the core's threads, and a write that fails
(a full disk, a closed pipe) leaves no report and no temporary file, and the error names the
report."""

from __future__ import annotations

import errno
import os
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol._native import core
from meshcol.cli import main
from meshcol.io import report as report_io
from meshcol.io.report import RowsPiece, dumps_rows

ROOT = Path(__file__).resolve().parents[2]
FULL = "/dev/full"
needs_full = pytest.mark.skipif(not os.path.exists(FULL), reason="needs /dev/full (Linux)")


def _columns(n: int, long_raw: int = 0) -> list[tuple]:
    """Columns of every kind; a raw entry of ``long_raw`` chars (used by row 1 only) makes a
    row's bound large, so that a few hundred short rows are many blocks of the file writer."""
    rng = np.random.default_rng(11)
    reals = rng.normal(size=n) * 10.0 ** rng.integers(-30, 30, size=n)
    reals[: min(n, 5)] = [np.nan, -np.inf, -0.0, 1e16, 5e-324][: min(n, 5)]
    vectors = rng.normal(size=(n, 3))
    if n > 2:
        vectors[2, 1] = np.nan
    raw = ["[]", "[\n        " + '"' + "x" * long_raw + '"' + "\n      ]"]
    raw_codes = rng.integers(-1, 1, n).astype(np.int64)  # the long entry in row 1 only
    raw_codes[1:2] = 1
    return [
        ("aabb", "box", rng.normal(size=(n, 6))),
        ("flag", "boolean", rng.random(n) < 0.5),
        ("index", "index", rng.integers(-2, 9, n).astype(np.int64)),
        ("integer", "integer", np.arange(n, dtype=np.int64) - 7),
        ("number", "number", reals),
        ("raw", "raw", raw_codes, raw),
        ("string", "string", rng.integers(-1, 3, n).astype(np.int64), ["a", 'q"\\', "\u2603 \n"]),
        ("vector", "vector", vectors),
    ]


@pytest.mark.parametrize(("n", "long_raw"), [(0, 0), (1, 0), (9, 0), (600, 100_000)])
def test_rows_written_into_a_file_are_the_rows_as_text(tmp_path: Path, n: int, long_raw: int):
    columns = _columns(n, long_raw)
    path = tmp_path / "rows.json"
    with open(path, "wb") as handle:
        handle.write(b"head ")
        handle.flush()
        core.write_rows(handle.fileno(), columns, n, 1)  # at the file's offset
        handle.seek(0, os.SEEK_END)
        handle.write(b" tail")
    text = path.read_text(encoding="ascii")
    assert text == "head " + dumps_rows(columns, n, 1) + " tail"
    assert "".join(RowsPiece(columns, n, 1).chunks()) == dumps_rows(columns, n, 1)


def test_the_file_writer_refuses_what_the_text_writer_refuses(tmp_path: Path) -> None:
    fd = os.open(tmp_path / "x", os.O_WRONLY | os.O_CREAT)
    try:
        with pytest.raises(ValueError, match="wrong type or shape"):
            core.write_rows(fd, [("x", "vector", np.zeros(3))], 3, 1)
        with pytest.raises(IndexError, match="past its table"):
            core.write_rows(fd, [("x", "string", np.array([1], dtype=np.int64), ["a"])], 1, 1)
    finally:
        os.close(fd)
    assert (tmp_path / "x").read_bytes() == b""  # nothing written before the columns checked


@needs_full
def test_a_full_disk_fails_the_file_writer_with_its_errno() -> None:
    fd = os.open(FULL, os.O_WRONLY)
    try:
        with pytest.raises(OSError) as failed:
            core.write_rows(fd, _columns(600, 100_000), 600, 1)  # many blocks, two threads
    finally:
        os.close(fd)
    assert failed.value.errno == errno.ENOSPC


def test_a_closed_pipe_fails_the_file_writer_and_stops_its_threads() -> None:
    read, write = os.pipe()
    os.close(read)  # every write now fails with EPIPE (Python ignores SIGPIPE)
    try:
        with pytest.raises(OSError) as failed:
            core.write_rows(write, _columns(600, 100_000), 600, 1)
    finally:
        os.close(write)
    assert failed.value.errno == errno.EPIPE


@needs_full
def test_a_report_whose_rows_cannot_be_written_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The core's write fails mid-report (the rows go to /dev/full in place of the temporary
    file): exit 2, one line naming the report, no report, no temporary file."""
    written = []

    def into_full(piece: RowsPiece, fd: int) -> None:
        os.write(fd, b"[")  # part of the report reached the temporary file
        full = os.open(FULL, os.O_WRONLY)
        try:
            core.write_rows(full, piece.columns, piece.count, piece.level)
        finally:
            os.close(full)
        written.append(piece)

    monkeypatch.setattr(RowsPiece, "write_into", into_full)
    monkeypatch.chdir(tmp_path)
    scene = str(ROOT / "samples/level/scene.json")
    result = CliRunner().invoke(main, ["check", scene, "--report", "r.json", "--fail-on", "none"])
    assert result.exit_code == 2, result.output
    assert re.fullmatch(r"meshcol: error: r\.json: No space left on device\n", result.stderr), (
        result.stderr
    )
    assert written == [] and sorted(os.listdir(tmp_path)) == []


def test_text_pieces_give_the_report_file_s_bytes(tmp_path: Path) -> None:
    from meshcol.analysis.check import check

    report = check([str(ROOT / "samples/level/scene.json")], clearance=0.5)
    pieces = list(report.json_pieces())
    assert any(isinstance(p, RowsPiece) for p in pieces)
    path = tmp_path / "r.json"
    report_io.emit(iter(pieces), str(path))
    assert path.read_text() == "".join(report_io.text_pieces(pieces)) == report.to_json()
