"""Mesh files read at once and kept packed (``io.mesh_files``, ``mesh_read.read_meshes``): the
bodies each path maps to are those ``load_mesh`` reads from the file alone, the bulk reading of
lone objects is the per-body one, and a bad file among many is named as before."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.errors import InputFileError, InvalidMeshError
from meshcol.io.mesh_read import MeshFiles, load_mesh, lone_objects, read_meshes


def _obj(path, points, faces=((0, 1, 2), (0, 2, 3), (0, 3, 1), (1, 3, 2))) -> str:
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in points]
    lines += ["f " + " ".join(str(i + 1) for i in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")
    return os.fspath(path)


def _files(folder, n: int = 12) -> list[str]:
    rng = np.random.default_rng(11)
    folder.mkdir(exist_ok=True)
    return [
        _obj(folder / f"p{k:03d}.obj", rng.normal(size=(4, 3)) * 10.0 ** (k % 7)) for k in range(n)
    ]


def _same_bodies(got, want) -> None:
    assert [b.name for b in got] == [b.name for b in want]
    for a, b in zip(got, want):
        assert a.source == b.source
        assert a.vertices.tobytes() == b.vertices.tobytes()
        assert a.faces.dtype == b.faces.dtype and a.faces.tobytes() == b.faces.tobytes()
        np.testing.assert_array_equal(a.pose, b.pose)
        assert (a.parts, a.collider, a.primitive) == (b.parts, b.collider, b.primitive)


def test_packed_files_map_to_the_bodies_load_mesh_reads(tmp_path):
    paths = _files(tmp_path / "a")
    files = read_meshes([*paths, paths[3]], threads=2)  # a path twice: one entry
    assert files.packed is not None  # one object each: kept packed
    assert list(files) == paths and len(files) == len(paths)
    for path in paths:
        _same_bodies(files[path], load_mesh(path))
    assert files.get(os.fspath(tmp_path / "other.obj")) is None
    later = _obj(tmp_path / "later.obj", np.eye(4)[:, :3])
    files[later] = load_mesh(later)
    _same_bodies(files[later], load_mesh(later))
    assert len(files) == len(paths) + 1


def test_lone_objects_in_bulk_are_those_of_the_bodies(tmp_path):
    paths = _files(tmp_path / "a")
    two = tmp_path / "two.obj"
    two.write_text(
        "o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no y\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n"
    )
    keys = [paths[2], os.fspath(tmp_path / "missing.obj"), *paths, os.fspath(two)]
    packed = read_meshes(paths)
    packed[os.fspath(two)] = load_mesh(two)  # a file of two objects, added as bodies
    by_body = {path: load_mesh(path) for path in [*paths, os.fspath(two)]}
    every = lone_objects(read_meshes(paths), paths[::-1])  # every key packed: one pass
    assert every[0].all() and every[1].tobytes() == lone_objects(by_body, paths[::-1])[1].tobytes()
    for (v, f), body in zip(every[2], (load_mesh(p)[0] for p in paths[::-1])):  # type: ignore[misc]
        assert v.tobytes() == body.vertices.tobytes() and f.tobytes() == body.faces.tobytes()
    got, want = lone_objects(packed, keys), lone_objects(by_body, keys)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1].tobytes() == want[1].tobytes()
    assert got[0].tolist() == [True, False, *[True] * len(paths), False]
    assert got[1][2] == np.abs(load_mesh(paths[0])[0].vertices).max()
    for a, b in zip(got[2], want[2]):
        assert (a is None) == (b is None)
        if a is not None:
            assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes()
            assert a[0].flags.c_contiguous and a[1].flags.c_contiguous


def test_files_of_several_objects_are_not_packed(tmp_path):
    paths = _files(tmp_path / "a", 3)
    two = tmp_path / "two.obj"
    two.write_text(
        "o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no y\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n"
    )
    files = read_meshes([*paths, two])
    assert isinstance(files, MeshFiles) and files.packed is None
    _same_bodies(files[os.fspath(two)], load_mesh(two))


def test_one_bad_file_among_many_is_named(tmp_path):
    paths = _files(tmp_path / "a", 40)
    os.remove(paths[17])
    with pytest.raises(InputFileError, match="file not found") as info:
        read_meshes(paths)
    assert info.value.path == paths[17]
    paths = _files(tmp_path / "b", 40)
    with open(paths[29], "a") as f:
        f.write("f 1 2 99\n")
    with pytest.raises(InvalidMeshError) as broken:
        read_meshes(paths)
    assert broken.value.path == paths[29]


@pytest.mark.parametrize("fault", ["missing", "corrupt"])
def test_a_bad_file_in_a_manifest_of_many_is_one_line_exit_2_nothing_written(tmp_path, fault):
    paths = _files(tmp_path / "assets", 60)
    bad = paths[41]
    if fault == "missing":
        os.remove(bad)
    else:
        with open(bad, "a") as f:
            f.write("f 1 2 99\n")
    bodies = [
        {"name": f"b{k}", "mesh": f"assets/{os.path.basename(p)}", "position": [3.0 * k, 0, 0]}
        for k, p in enumerate(paths)
    ]
    manifest = tmp_path / "scene.json"
    manifest.write_text(json.dumps({"units": "m", "bodies": bodies}))
    report = tmp_path / "report.json"
    result = CliRunner().invoke(main, ["check", str(manifest), "--report", str(report)])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("meshcol: error: ")
    assert "body 'b41'" in lines[0] and "p041.obj" in lines[0]
    assert "Traceback" not in result.output
    assert not report.exists()


def test_the_cores_packing_is_the_files_objects_in_order_on_any_threads(tmp_path):
    """``read_mesh_files`` packs every object of every file on the core's threads: the same
    arrays on 1 and 3 threads, each object's arrays those of ``load_mesh``, each object's
    largest |coordinate| what a numpy reduction of its vertices gives (beyond the limit too),
    and a bad file among them gives no object and its message."""
    from meshcol._native import core

    paths = _files(tmp_path / "a", 30)
    two = tmp_path / "a" / "two.obj"
    two.write_text(
        "o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no y\nv 0 0 9e9\nv 1 0 1\nv 0 1 1\nf 4 5 6\n"
    )
    paths[7:7] = [os.fspath(two), os.fspath(tmp_path / "a" / "missing.obj")]
    cut = tmp_path / "a" / "cut.stl"  # parsed into a facet's second vertex, then refused
    cut.write_text(
        "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 nan\n"
    )
    formats = [0] * len(paths) + [1]
    paths.append(os.fspath(cut))
    one, three = (core.read_mesh_files(paths, formats, threads=t) for t in (1, 3))
    for a, b in zip(one, three):
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
        else:
            assert a == b
    vertices, faces, v_off, f_off, owner, _, status, errors, largest = one
    assert faces.dtype == np.int32  # packed narrow; a body's faces are int64 (below)
    assert status.tolist() == [0] * 8 + [1] + [0] * 23 + [4] and errors[8] == b"file not found"
    assert owner.max() < len(paths) - 1  # the refused file gives no object
    want = [(j, body) for j, p in enumerate(paths[:-1]) if j != 8 for body in load_mesh(p)]
    assert owner.tolist() == [j for j, _ in want] and len(v_off) == len(want) + 1
    for k, (_, body) in enumerate(want):
        assert vertices[v_off[k] : v_off[k + 1]].tobytes() == body.vertices.tobytes()
        assert faces[f_off[k] : f_off[k + 1]].astype(np.int64).tobytes() == body.faces.tobytes()
    reduced = np.maximum.reduceat(np.abs(vertices).max(axis=1), v_off[:-1])
    assert largest.tobytes() == reduced.tobytes() and largest.max() == 9e9
    two.write_text(two.read_text().replace("9e9", "-1e12"))  # beyond the limit: named
    del paths[8], paths[-1]
    with pytest.raises(InvalidMeshError, match=r"vertex 1 has coordinate -1e\+12") as big:
        read_meshes(paths)
    assert big.value.path == os.fspath(two)


def test_files_of_folders_in_any_order_are_each_their_own(tmp_path):
    """The core opens a file relative to its folder when the file before it was in the same
    folder: files of three folders interleaved (same names in each, a folder reached through
    ``..`` and through a symbolic link) each read as themselves, and a loop, a named pipe, a
    folder and a missing file among them say what they are."""
    from meshcol._native import core

    rng = np.random.default_rng(5)
    points = {}
    for folder in ("a", "b", "c"):
        (tmp_path / folder).mkdir()
        for k in range(4):
            path = tmp_path / folder / f"p{k}.obj"
            points[os.fspath(path)] = rng.normal(size=(4, 3))
            _obj(path, points[os.fspath(path)])
    os.symlink(tmp_path / "c", tmp_path / "link")
    os.symlink("loop.obj", tmp_path / "b" / "loop.obj")
    os.mkfifo(tmp_path / "b" / "pipe.obj")
    (tmp_path / "a" / "dir.obj").mkdir()
    t = os.fspath(tmp_path)
    order = [f"{t}/a/p0.obj", f"{t}/a/p1.obj", f"{t}/b/p1.obj", f"{t}/b/loop.obj"]
    order += [f"{t}/b/pipe.obj", f"{t}/a/../b/p2.obj", f"{t}/link/p3.obj", f"{t}/c/p3.obj"]
    order += [f"{t}/a/dir.obj", f"{t}/c/none.obj", f"{t}/a/p2.obj", f"{t}/b/p0.obj"]
    same = {f"{t}/a/../b/p2.obj": f"{t}/b/p2.obj", f"{t}/link/p3.obj": f"{t}/c/p3.obj"}
    for threads in (1, 2):
        vertices, _, v_off, _, owner, _, status, errors, _ = core.read_mesh_files(
            order, [0] * len(order), threads=threads
        )
        assert status.tolist() == [0, 0, 0, 3, 3, 0, 0, 0, 2, 1, 0, 0]
        assert (
            b"symbolic links" in errors[3] and errors[4] == b"is a named pipe, not a regular file"
        )
        assert errors[9] == b"file not found"
        for k, j in enumerate(owner.tolist()):
            want = points[same.get(order[j], order[j])]
            assert vertices[v_off[k] : v_off[k + 1]].tobytes() == want.tobytes()


def test_identities_of_files_of_folders_in_any_order_are_what_stat_gives(tmp_path, monkeypatch):
    """The core stats each path relative to the folder of the path before it when they share
    one: paths of three folders interleaved (a folder reached through ``..`` and through a
    symbolic link, a symbolic link to a file, a loop, a file used as a folder, a missing file
    and folder, a bare name, a trailing slash) give each what ``os.stat`` gives, on 1 and 2
    threads."""
    from meshcol._native import core

    for folder in ("a", "b", "c"):
        (tmp_path / folder).mkdir()
        for k in range(3):
            (tmp_path / folder / f"p{k}.obj").write_text(f"v {k} 0 0\n")
    os.symlink(tmp_path / "c", tmp_path / "link")
    os.symlink(tmp_path / "a" / "p1.obj", tmp_path / "b" / "to_a1.obj")
    os.symlink("loop.obj", tmp_path / "b" / "loop.obj")
    monkeypatch.chdir(tmp_path / "a")
    t = os.fspath(tmp_path)
    order = [f"{t}/a/p0.obj", f"{t}/a/p1.obj", f"{t}/b/p1.obj", f"{t}/b/to_a1.obj"]
    order += [f"{t}/b/loop.obj", f"{t}/a/../b/p2.obj", f"{t}/link/p2.obj", f"{t}/c/p2.obj"]
    order += [f"{t}/a/p0.obj/x", f"{t}/none/p0.obj", f"{t}/c/none.obj", "p2.obj", "../b/p0.obj"]
    order += [f"{t}/a/", f"{t}/a", "/", f"{t}/b/p0.obj", f"{t}/a/p2.obj"]
    want = []
    for path in order:
        try:
            info = os.stat(path)
        except OSError:
            want.append((0, 0, 0))
        else:
            want.append((info.st_dev, info.st_ino, 1))
    assert sum(found for _, _, found in want) == len(order) - 4  # loop, x, two missing
    for threads in (1, 2):
        device, inode, found = core.file_identities(order, threads=threads)
        assert list(zip(device.tolist(), inode.tolist(), found.tolist())) == want


def test_formats_found_from_the_ends_of_paths_are_splitexts():
    """The format of each path, found once per distinct end of the paths, is what
    ``mesh_format`` says of the path itself (None where it refuses it)."""
    from meshcol.io.mesh_formats import mesh_format
    from meshcol.io.mesh_read import _formats_of

    names = [
        ".obj",
        "a/.obj",
        "a..obj",
        "a.b/c",
        "a.OBJ",
        "x.stl",
        "dir.obj/file",
        "ab",
        ".",
        "a/b.c.d.obj",
        "a/b.ply",
        "...obj",
        "a/..obj",
        "a./obj",
        "x.glb",
        "y.gltf",
        "z.off",
        "q.fbx",
        "r.dae",
        "s.usd",
        "",
        "/",
        "a/",
        "a.obj/",
        "#.obj",
        "é.obj",
        "a b.Stl",
    ]
    folders = ["", "f/", "/abs/deep/folder.with.dots/", "x" * 40 + "/", "..", "a.obj/"]
    paths = [folder + name for folder in folders for name in names]
    paths += ["p" * k + ".obj" for k in range(20)] + [".o" * k for k in range(12)]

    def old(path):
        try:
            return mesh_format(path)
        except InputFileError:
            return None

    assert _formats_of(paths) == [old(p) for p in paths]
