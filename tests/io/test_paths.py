"""The one path display (meshcol.io.paths): relative inside the working folder, as given
outside it; in bulk exactly as one by one."""

from __future__ import annotations

import os
import random
from pathlib import Path

import numpy as np
import pytest

from meshcol.io.paths import (
    OutsideRootError,
    confine_all,
    confined_to,
    display_path,
    display_paths,
    joined_paths,
    recording_reads,
)


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
        "/c.obj",
        str(inner) + "//e.obj",
        str(inner) + "/",
        tmp_path / "work" / "f.obj",
        "",
        "../up.obj",
        Path("rel") / "b.obj",
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


def test_joined_paths_are_join_and_normpath_of_each():
    rng = np.random.default_rng(5)
    parts = ["a", "b.obj", ".", "..", "", ".hidden", "x y", "c..obj", "é"]
    names = ["/abs/m.obj", "a//b.obj", "a/", "./a.obj", "../a.obj", "a/./b", "a/../b", "."]
    names += ["/".join(rng.choice(parts, size=rng.integers(1, 4))) for _ in range(400)]
    folders = ["", "/", "/x/y", "x", "x/", "./x", "x/../y", "//x", "x//y", "/x/./y", "."]
    for folder in folders:
        assert joined_paths(folder, names) == [os.path.join(folder, n) for n in names]
        assert joined_paths(folder, names, normalise=True) == [
            os.path.normpath(os.path.join(folder, n)) for n in names
        ]


def test_joined_paths_of_short_lists_are_join_and_normpath_of_each():
    # lists of a few names: most are all plain (the one concatenation for the whole list),
    # and the others differ from that by one name (empty, absolute, dotted, a folder, a
    # newline in a name, a doubled slash...), where the text of the joined names must tell
    pick = random.Random(7)
    parts = ["", "a", "b.obj", "/", ".", "..", "\n", "//", "/.", "x/y", "é", " "]
    plain = 0
    for folder in ["", "d", "/abs/d", "d/", ".", "/"]:
        for _ in range(1500):
            names = [
                "".join(pick.choices(parts, k=pick.randint(0, 3)))
                for _ in range(pick.randint(0, 4))
            ]
            joined = [os.path.join(folder, n) for n in names]
            assert joined_paths(folder, names) == joined
            assert joined_paths(folder, names, normalise=True) == list(
                map(os.path.normpath, joined)
            )
            plain += bool(names) and all(
                n and n[0] not in "/.\n" and "/." not in n and "//" not in n and n[-1] != "/"
                for n in names
            )
    assert plain > 300  # the lists the one concatenation joins


def test_confine_all_is_confine_of_each(tmp_path):
    inside = tmp_path / "root"
    inside.mkdir()
    (inside / "a.obj").write_text("")
    paths = [str(inside / "a.obj"), str(inside / "missing.obj")]
    assert confine_all(paths, "scene.json", ["a.obj", "missing.obj"]) == paths
    with confined_to(inside):
        assert confine_all(paths, "scene.json", ["a.obj", "missing.obj"]) == paths
        with pytest.raises(OutsideRootError, match=r"path '\.\./b\.obj' resolves outside the root"):
            confine_all([*paths, str(tmp_path / "b.obj")], "s.json", ["a", "m", "../b.obj"])
    with recording_reads() as reads:
        confine_all(paths, "scene.json", ["a.obj", "missing.obj"])
    assert reads == {os.path.realpath(p) for p in paths}
