"""The one path display (meshcol.io.paths): relative inside the working folder, as given
outside it; in bulk exactly as one by one."""

from __future__ import annotations

import os

from meshcol.io.paths import display_path, display_paths


def test_display_paths_are_those_of_display_path_one_by_one(tmp_path, monkeypatch):
    inner = tmp_path / "work" / "level"
    inner.mkdir(parents=True)
    monkeypatch.chdir(tmp_path / "work")
    paths = [
        None,
        "rel/a.obj",
        str(inner / "a.obj"),
        str(inner / "b.obj"),
        str(tmp_path / "work" / "c.obj"),
        str(tmp_path / "outside.obj"),
        str(tmp_path / "work" / "level" / ".." / "d.obj"),
        str(tmp_path / "work" / "level" / ".."),
        "/",
    ]
    for posix in (False, True):
        assert display_paths(paths, posix=posix) == [display_path(p, posix=posix) for p in paths]
    assert display_paths(paths, posix=True)[2:5] == ["level/a.obj", "level/b.obj", "c.obj"]


def test_display_path_is_relative_inside_the_working_folder_only(tmp_path, monkeypatch):
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    assert display_path(tmp_path / "work" / "parts") == "parts"
    assert display_path(str(tmp_path / "work")) == "."
    assert display_path(str(tmp_path / "other.obj")) == str(tmp_path / "other.obj")
    assert display_path("../other.obj") == "../other.obj"  # relative paths are kept as typed
    assert display_path("a/./b.obj") == "a/./b.obj"
    assert display_path(None) is None


def test_posix_paths_use_forward_slashes(monkeypatch):
    monkeypatch.setattr(os, "sep", "\\")
    assert display_path("props\\crate.obj", posix=True) == "props/crate.obj"
    assert display_path("props\\crate.obj") == "props\\crate.obj"
