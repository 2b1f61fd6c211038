"""meshcol.io.outputs: output locations checked before a run, files written all or nothing."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from meshcol.errors import MeshcolError
from meshcol.io.outputs import check_outputs, same_file, staged_folder


def test_check_outputs_accepts_what_can_be_written(tmp_path) -> None:
    (tmp_path / "old.json").write_text("{}")
    check_outputs(
        files={"--report": tmp_path / "old.json", "--csv": tmp_path / "new.csv"},
        folders={"--out-dir": tmp_path / "a" / "b" / "c", "--cache-dir": tmp_path},
        inputs=[tmp_path / "in.obj"],
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.json"]  # nothing created


@pytest.mark.parametrize(
    ("files", "folders", "message"),
    [
        ({"--report": "missing/r.json"}, {}, "missing/r.json: folder missing does not exist"),
        ({"--report": "f/r.json"}, {}, "f/r.json: f is not a folder"),
        ({"--report": "d"}, {}, "d: is a folder, not a file"),
        ({}, {"--out-dir": "f"}, "f: is a file, not a folder"),
        ({}, {"--out-dir": "f/x/y"}, "f/x/y: cannot create the folder: f is not a folder"),
        ({"--report": "in.obj"}, {}, "in.obj: --report would overwrite the input"),
        ({"--report": "d/../in.obj"}, {}, "d/../in.obj: --report would overwrite the input"),
        ({"--report": "x"}, {"--out-dir": "./x"}, "./x: --report and --out-dir are the same file"),
    ],
)
def test_check_outputs_refuses_with_the_users_path(
    tmp_path, monkeypatch, files, folders, message
) -> None:
    monkeypatch.chdir(tmp_path)
    Path("f").write_text("a file")
    Path("d").mkdir()
    Path("in.obj").write_text("v 0 0 0\n")
    with pytest.raises(MeshcolError) as caught:
        check_outputs(files=files, folders=folders, inputs=["in.obj"])
    assert str(caught.value) == message


def test_check_outputs_names_the_other_inputs_a_run_reads(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("old.json").write_text("{}")
    with pytest.raises(MeshcolError) as caught:
        check_outputs(
            files={"--report": "old.json"},
            inputs=["scene.json"],
            named_inputs={"the --baseline": "old.json", "the --srdf": None},
        )
    assert str(caught.value) == "old.json: --report would overwrite the --baseline"


def test_a_file_inside_an_output_folder_of_the_run_needs_no_folder_yet(tmp_path, monkeypatch):
    """`hull x.obj --out-dir hulls --report hulls/r.json`: the run makes hulls/ first."""
    monkeypatch.chdir(tmp_path)
    check_outputs(files={"--report": "hulls/r.json"}, folders={"--out-dir": "hulls"})
    with pytest.raises(MeshcolError, match="folder hulls/deeper does not exist"):
        check_outputs(files={"--report": "hulls/deeper/r.json"}, folders={"--out-dir": "hulls"})
    assert list(tmp_path.iterdir()) == []


def test_a_device_is_checked_as_itself_not_its_folder(monkeypatch) -> None:
    """`--report /dev/null` is written into, never replaced: /dev need not be writable."""
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: p != "/dev" and real(p, mode))
    check_outputs(files={"--report": os.devnull, "--html": "-"})
    monkeypatch.setattr(os, "access", lambda p, mode: False)
    with pytest.raises(MeshcolError, match="cannot write to it"):
        check_outputs(files={"--report": os.devnull})


def test_same_file_follows_links(tmp_path) -> None:
    (tmp_path / "a").write_text("x")
    os.link(tmp_path / "a", tmp_path / "hard")
    (tmp_path / "soft").symlink_to(tmp_path / "a")
    assert same_file(tmp_path / "a", tmp_path / "hard")
    assert same_file(tmp_path / "soft", tmp_path / "a")
    assert same_file(tmp_path / "new", tmp_path / "sub" / ".." / "new")  # not there yet
    assert not same_file(tmp_path / "a", tmp_path / "b")


def test_staged_folder_moves_everything_or_nothing(tmp_path) -> None:
    out = tmp_path / "made" / "out"
    with staged_folder(out) as stage:
        for name in ("a.obj", "b.obj"):
            Path(stage, name).write_text(name)
        assert not (out / "a.obj").exists()  # nothing in place before the block ends
    assert sorted(p.name for p in out.iterdir()) == ["a.obj", "b.obj"]
    (out / "a.obj").write_text("kept")
    with pytest.raises(RuntimeError), staged_folder(out) as stage:
        Path(stage, "a.obj").write_text("new")
        raise RuntimeError("a failure half way")
    assert sorted(p.name for p in out.iterdir()) == ["a.obj", "b.obj"]
    assert (out / "a.obj").read_text() == "kept"
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path / "new" / "deep") as stage:
        Path(stage, "c.obj").write_text("c")
        raise KeyboardInterrupt
    assert not (tmp_path / "new").exists()  # the folders it made are gone too


def test_staged_folder_names_the_destination_in_errors(tmp_path) -> None:
    with pytest.raises(OSError) as caught, staged_folder(tmp_path / "out") as stage:
        raise OSError(28, "No space left on device", os.path.join(stage, "p.obj"))
    assert caught.value.filename == str(tmp_path / "out" / "p.obj")


def test_staged_folder_holds_signals_while_it_moves_files(tmp_path, monkeypatch) -> None:
    moved: list[str] = []
    real_replace = os.replace

    def replace_then_signal(src, dst):
        real_replace(src, dst)
        moved.append(os.path.basename(dst))
        if len(moved) == 1:
            signal.raise_signal(signal.SIGINT)  # Ctrl-C between the first and second move

    monkeypatch.setattr(os, "replace", replace_then_signal)
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path / "out") as stage:
        Path(stage, "a.obj").write_text("a")
        Path(stage, "b.obj").write_text("b")
    assert moved == ["a.obj", "b.obj"]  # delivered once both were in place
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.obj", "b.obj"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_atomic_write_errors_name_the_destination_not_the_temporary_file(
    tmp_path, monkeypatch
) -> None:
    from meshcol.io import report

    target = tmp_path / "missing" / "r.json"
    with pytest.raises(FileNotFoundError) as caught:
        report.atomic_write(target, "{}")
    assert caught.value.filename == str(target)

    def full_disk(src, dst):
        raise OSError(28, "No space left on device", src, None, dst)

    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(OSError) as caught:
        report.atomic_write(tmp_path / "r.json", "{}")
    assert caught.value.filename == str(tmp_path / "r.json")
    assert list(tmp_path.glob(".meshcol-*")) == []


def test_a_report_to_a_device_or_pipe_is_written_into_it_never_replacing_it(tmp_path) -> None:
    """`--report /dev/null` renamed the temporary file over /dev/null (as root it replaced the
    device with a regular file, for every program on the machine). A destination that is not
    a regular file is written into; tested on a named pipe, which a rename would replace too."""
    import stat
    import threading

    from meshcol.io.report import atomic_write

    pipe = tmp_path / "pipe.json"
    os.mkfifo(pipe)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(pipe.read_bytes()))
    reader.start()
    atomic_write(pipe, '{"ok": true}\n')
    reader.join(timeout=10)
    assert got == [b'{"ok": true}\n']
    assert stat.S_ISFIFO(os.stat(pipe).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.json"]


@pytest.mark.parametrize("spelling", ["gone.obj", "./gone.obj", "sub/../gone.obj", "link.json"])
def test_an_output_spelled_as_a_missing_input_is_refused(tmp_path, monkeypatch, spelling) -> None:
    """An input that does not exist, named by the output in another spelling (or reached by
    the output's dangling link), would be created by the run: refused as overwriting it."""
    from meshcol.io.outputs import check_destinations

    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.json").symlink_to(tmp_path / "gone.obj")  # dangling
    inputs = [("the input", "a.obj"), ("a mesh file of scene.json", "gone.obj")]
    with pytest.raises(MeshcolError, match=r"would overwrite a mesh file of scene\.json"):
        check_destinations(inputs, [("--report", spelling)])
    check_destinations(inputs, [("--report", "other.json")])  # another name: accepted


@pytest.mark.parametrize("count", [20, 300])
def test_an_output_that_is_any_input_is_found_among_many(tmp_path, count) -> None:
    """The inputs are stat'ed one by one (few) or at once in the core (many): an existing
    output that is an input by a hard link, a symbolic link or a name of undecodable bytes is
    named by the first input that is it; missing and odd inputs match nothing."""
    from meshcol.errors import OutputPathError
    from meshcol.io.outputs import STAT_IN_CORE, check_destinations

    assert 20 < STAT_IN_CORE < 300  # both ways are tested

    report = tmp_path / "report.json"
    report.write_text("{}")
    os.link(report, tmp_path / "hard.obj")
    (tmp_path / "soft.obj").symlink_to(report)
    odd = os.fsdecode(b"\xff\xfe.obj")  # surrogates: no UTF-8 text for the core
    os.link(report, os.path.join(tmp_path, odd))
    others = [("a mesh", str(tmp_path / f"m{i}.obj")) for i in range(count)]
    for _, path in others[:10]:
        Path(path).write_text("v 0 0 0\n")
    strange = [("a nul", "bad\x00.obj"), ("a gone one", str(tmp_path / "gone.obj"))]
    for linked, what in (("hard.obj", "the hard link"), ("soft.obj", "the link"), (odd, "odd")):
        inputs = [*strange, *others, (what, os.path.join(tmp_path, linked)), ("later", str(report))]
        with pytest.raises(OutputPathError, match=f"--report would overwrite {what}"):
            check_destinations(inputs, [("--report", report)])
    check_destinations([*strange, *others], [("--report", report)])  # none of them is it


def test_inputs_named_as_an_output_are_found_by_their_ends_as_one_by_one() -> None:
    """The guard's shortcut (:func:`meshcol.io.outputs._named`: a string test per input
    before the last name) finds what the last name of every input finds."""
    from meshcol.io.outputs import _last_name, _named

    paths = [
        "r.json",
        "a/r.json",
        "a/r.json/",
        "a/r.json/.",
        "r.json/x/..",
        "a/xr.json",
        "",
        ".",
        "..",
        "/",
        "a/b/../r.json",
        "R.JSON",
        "a/r.jsonx",
        "r.json/sub/",
    ]
    read = [(f"input {i}", p) for i, p in enumerate(paths)]
    for name in ("r.json", "x", "sub", "a", "b", ".", ""):
        assert _named(read, name) == [item for item in read if _last_name(item[1]) == name]
