"""Files that are not files, and files that lie about themselves (issue #29, items 11, 12, 14,
17): every one is refused with one ``meshcol: error:`` line naming the file, exit 2, and never
blocks, reads forever or aborts.

A named pipe would block a reader forever: each pipe case runs with a watchdog that, if the
command has not finished after :data:`PATIENCE` seconds, opens the pipe's other end to release
the reader, and the test fails. A device that never ends (``/dev/zero``) would be read until
memory runs out: those cases run in a child process whose address space is capped.
"""

from __future__ import annotations

import base64
import json
import os
import re
import struct
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.errors import InputFileError

PATIENCE = 20.0  # seconds a pipe case may take before the watchdog releases it

TETRA_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes (POSIX)")


def _run(args: list[str], pipes: list[Path] = ()) -> tuple[object, bool]:
    """Run the command line in-process; returns the result and whether the watchdog had to
    release a pipe (the command blocked on it)."""
    done = threading.Event()
    released = []

    def watchdog() -> None:
        if done.wait(PATIENCE):
            return
        while not done.wait(0.2):  # a reader may open the pipe again: release it each time
            for pipe in pipes:  # a writer that closes at once: the blocked reader sees the end
                if _has_reader(pipe):
                    released.append(pipe)

    thread = threading.Thread(target=watchdog, daemon=True)
    thread.start()
    try:
        result = CliRunner().invoke(main, args)
    finally:
        done.set()
        thread.join()
    return result, bool(released)


def _has_reader(pipe: Path) -> bool:
    try:
        os.close(os.open(pipe, os.O_WRONLY | os.O_NONBLOCK))
        return True
    except OSError:  # ENXIO: nobody has it open for reading
        return False


def _one_line(result, pattern: str) -> None:
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert re.fullmatch(f"meshcol: error: {pattern}\n", result.stderr), result.stderr


def _pipe(folder: Path, name: str) -> Path:
    path = folder / name
    os.mkfifo(path)
    return path


def _robot(folder: Path) -> None:
    (folder / "tetra.obj").write_text(TETRA_OBJ)
    (folder / "arm.urdf").write_text(
        '<robot name="arm"><link name="base"><collision><geometry><mesh filename="tetra.obj"/>'
        '</geometry></collision></link><link name="tip"><collision><origin xyz="3 0 0"/>'
        '<geometry><box size="1 1 1"/></geometry></collision></link><joint name="j" '
        'type="revolute"><parent link="base"/><child link="tip"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )


# ---------------------------------------------------------------------------------------------
# item 11: not a regular file


@pytest.mark.parametrize(
    ("setup", "args", "pattern"),
    [
        ("mesh", ["inspect", "f.obj"], r"f\.obj: is a named pipe, not a regular file"),
        ("mesh", ["hull", "f.obj"], r"f\.obj: is a named pipe, not a regular file"),
        ("gltf", ["inspect", "f.gltf"], r"f\.gltf: is a named pipe, not a regular file"),
        ("ply", ["inspect", "f.ply"], r"f\.ply: is a named pipe, not a regular file"),
        # inspect reads an FBX file twice (its bodies, then what it left out): both guarded
        ("fbx", ["inspect", "f.fbx"], r"f\.fbx: is a named pipe, not a regular file"),
        ("fbx", ["hull", "f.fbx"], r"f\.fbx: is a named pipe, not a regular file"),
        ("dae", ["inspect", "f.dae"], r"f\.dae: is a named pipe, not a regular file"),
        ("manifest", ["check", "f.json"], r"f\.json: is a named pipe, not a regular file"),
        (
            "manifest_mesh",
            ["check", "scene.json"],
            r"scene\.json: body 'b': mesh file 'f\.obj': is a named pipe, not a regular file",
        ),
        (
            "baseline",
            ["check", "tetra.obj", "--baseline", "f.json"],
            r"f\.json: is a named pipe, not a regular file",
        ),
        (
            "joints",
            ["check", "arm.urdf", "--joints", "f.json"],
            r".*f\.json: is a named pipe, not a regular file.*",
        ),
        ("urdf", ["check", "f.urdf"], r"f\.urdf: is a named pipe, not a regular file"),
        # an .xml file is a robot or not by its root element, which a pipe does not give
        ("xml", ["check", "f.xml"], r"f\.xml: is a named pipe, not a regular file"),
    ],
    ids=lambda v: v if isinstance(v, str) else None,
)
def test_a_named_pipe_is_refused_without_blocking(tmp_path, monkeypatch, setup, args, pattern):
    monkeypatch.chdir(tmp_path)
    _robot(tmp_path)
    pipes = []
    if setup == "mesh" or setup == "manifest_mesh":
        pipes.append(_pipe(tmp_path, "f.obj"))
    elif setup in ("gltf", "ply", "fbx", "dae"):
        pipes.append(_pipe(tmp_path, f"f.{setup}"))
    elif setup in ("manifest", "baseline", "joints"):
        pipes.append(_pipe(tmp_path, "f.json"))
    elif setup in ("urdf", "xml"):
        pipes.append(_pipe(tmp_path, f"f.{setup}"))
    if setup == "manifest_mesh":
        (tmp_path / "scene.json").write_text(
            json.dumps(
                {"bodies": [{"name": "a", "mesh": "tetra.obj"}, {"name": "b", "mesh": "f.obj"}]}
            )
        )
    result, blocked = _run(args, pipes)
    assert not blocked, f"{' '.join(args)} blocked on a named pipe"
    _one_line(result, pattern)


def test_an_mjcf_include_that_is_a_pipe_is_refused(tmp_path, monkeypatch):
    pytest.importorskip("mujoco", reason="MJCF is compiled by MuJoCo")
    monkeypatch.chdir(tmp_path)
    pipe = _pipe(tmp_path, "part.xml")
    (tmp_path / "model.xml").write_text(
        '<mujoco><include file="part.xml"/><worldbody><body><geom type="box" size="1 1 1"/>'
        "</body></worldbody></mujoco>"
    )
    result, blocked = _run(["check", "model.xml"], [pipe])
    assert not blocked, "an MJCF include that is a named pipe blocked the reader"
    _one_line(result, r"part\.xml: is a named pipe, not a regular file")


@pytest.mark.parametrize(
    ("command", "name"),
    [
        ("inspect", "loop.obj"),
        ("check", "loop.urdf"),  # a robot description, a manifest: the same words
        ("check", "loop.xml"),
        ("check", "loop.json"),
    ],
)
def test_symbolic_link_loop_is_named(tmp_path, monkeypatch, command, name):
    monkeypatch.chdir(tmp_path)
    os.symlink(name, name)
    result, _ = _run([command, name])
    _one_line(result, rf"{re.escape(name)}: cannot read file: Too many levels of symbolic links")


def _capped_child(args: list[str], folder: Path) -> subprocess.CompletedProcess:
    """The command line in a child process of at most 2 GiB of address space (a reader of
    ``/dev/zero`` fails there instead of taking the machine's memory). Under AddressSanitizer
    (``make test-sanitize``) no cap: ASan reserves terabytes of shadow address space at
    start-up, and its own allocator stops a runaway read instead (the process aborts)."""
    import resource

    sanitized = "libasan" in os.environ.get("LD_PRELOAD", "")

    def cap() -> None:
        limit = 2 << 30
        if not sanitized:
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return subprocess.run(
        [sys.executable, "-m", "meshcol", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=cap,
        env={**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"},
    )


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_endless_devices_are_never_read(tmp_path):
    """``--baseline /dev/zero``, ``--joints /dev/zero`` and ``/dev/zero`` under a mesh name:
    refused before a byte is read (main read until MemoryError: a traceback, exit 1)."""
    _robot(tmp_path)
    os.symlink("/dev/zero", tmp_path / "zero.obj")
    os.symlink("/dev/urandom", tmp_path / "noise.stl")
    cases = [
        (
            ["check", "tetra.obj", "--baseline", "/dev/zero"],
            r"/dev/zero: is a device, not a regular file",
        ),
        (
            ["check", "arm.urdf", "--joints", "/dev/zero"],
            r".*/dev/zero: is a device, not a regular file.*",
        ),
        (["inspect", "zero.obj", "noise.stl"], r"zero\.obj: is a device, not a regular file"),
        (["inspect", "noise.stl"], r"noise\.stl: is a device, not a regular file"),
    ]
    for args, pattern in cases:
        done = _capped_child(args, tmp_path)
        assert done.returncode == 2, (args, done.stderr[-500:])
        assert re.fullmatch(f"meshcol: error: {pattern}\n", done.stderr), (args, done.stderr)


def test_the_guarded_read_caps_every_kind(tmp_path):
    """A sparse file larger than its kind's cap is refused by its size, before it is read."""
    from meshcol.io.safe_read import MAX_BYTES, check_input, read_input

    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(MAX_BYTES["json"] + 1)
    with pytest.raises(InputFileError, match=r"JSON file is 1 GiB, over the limit of 1 GiB"):
        read_input(big, "json")
    with pytest.raises(InputFileError, match="over the limit"):
        check_input(big, "robot")
    assert read_input(big, "json", limit=4) == b"\0" * 4  # a head is always within the cap
    mesh = tmp_path / "big.stl"
    with open(mesh, "wb") as f:
        f.truncate(MAX_BYTES["mesh"] + 1)
    result, _ = _run(["inspect", str(mesh)])
    _one_line(result, r".*big\.stl: mesh file is 4 GiB, over the limit of 4 GiB")


def test_the_core_cap_is_the_python_cap():
    from meshcol._native import core
    from meshcol.io.safe_read import MAX_BYTES

    assert core.defaults.max_mesh_file_bytes == MAX_BYTES["mesh"]


# ---------------------------------------------------------------------------------------------
# items 12 and 14: files that lie about themselves

_TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
_TETRA_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.uint32)
_BLOB = _TETRA_V.tobytes() + _TETRA_F.tobytes()


def _gltf(uri: str | None = None, **extra: object) -> dict:
    data = "data:application/octet-stream;base64," + base64.b64encode(_BLOB).decode()
    document = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(_BLOB), **({"uri": uri or data} if uri != "" else {})}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5125, "count": 12, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    document.update(extra)
    return document


def _glb(total_delta: int = 0, bin_delta: int = 0) -> bytes:
    text = json.dumps(_gltf(uri="")).encode()
    text += b" " * (-len(text) % 4)
    body = _BLOB + b"\0" * (-len(_BLOB) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    chunks += struct.pack("<I4s", len(body) + bin_delta, b"BIN\0") + body
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks) + total_delta) + chunks


@pytest.mark.parametrize(
    ("name", "content", "pattern"),
    [
        (
            "remote.gltf",
            json.dumps(_gltf(uri="https://example.com/tetra.bin")),
            r"remote\.gltf: cannot parse GLTF file: buffer 0 has uri "
            r"'https://example\.com/tetra\.bin': https: URIs are not read \(only files beside "
            r"the mesh file\)",
        ),
        (
            "absolute.gltf",
            json.dumps(_gltf(uri="/tmp/tetra.bin")),
            r"absolute\.gltf: cannot parse GLTF file: buffer 0 has uri '/tmp/tetra\.bin': "
            r"absolute paths are not read \(only files beside the mesh file\)",
        ),
        (
            "draco.gltf",
            json.dumps(
                _gltf(
                    extensionsUsed=["KHR_draco_mesh_compression"],
                    extensionsRequired=["KHR_draco_mesh_compression"],
                )
            ),
            r"draco\.gltf: cannot parse GLTF file: it requires KHR_draco_mesh_compression "
            r"\(Draco mesh compression\), which meshcol does not decode: export it uncompressed",
        ),
        (
            "meshopt.gltf",
            json.dumps(
                _gltf(
                    extensionsUsed=["EXT_meshopt_compression"],
                    extensionsRequired=["EXT_meshopt_compression"],
                )
            ),
            r"meshopt\.gltf: cannot parse GLTF file: it requires EXT_meshopt_compression "
            r"\(meshopt compression\), which meshcol does not decode: export it uncompressed",
        ),
        (
            "deep.gltf",
            '{"asset": ' + "[" * 200_000 + "]" * 200_000 + "}",
            r"deep\.gltf: cannot parse GLTF file: its JSON nests arrays and objects too deep",
        ),
        (
            "scaled.gltf",
            json.dumps(_gltf(nodes=[{"mesh": 0, "scale": [1e300, 1, 1]}])),
            r"scaled\.gltf: scene graph transform has scale 1e\+300, beyond the limit of 1e\+10",
        ),
        (
            "cut.stl",
            "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
            "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 1\nvertex 1 0 1\n",
            r"cut\.stl: cannot parse STL file: line 10: the file ends inside this facet's loop "
            r"\(cut short\?\)",
        ),
    ],
    ids=lambda v: v if isinstance(v, str) and v.endswith(("gltf", "stl")) else None,
)
def test_lying_mesh_files_are_refused(tmp_path, monkeypatch, name, content, pattern):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tetra.bin").write_bytes(_BLOB)  # a local file of the remote buffer's name
    (tmp_path / name).write_text(content)
    result, _ = _run(["inspect", name])
    _one_line(result, pattern)


def test_a_uniform_huge_scale_is_not_called_zero(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "big.gltf").write_text(json.dumps(_gltf(nodes=[{"mesh": 0, "scale": [1e300] * 3}])))
    result, _ = _run(["check", "big.gltf"])
    _one_line(
        result, r"big\.gltf: scene graph transform has scale 1e\+300, beyond the limit of 1e\+10"
    )


@pytest.mark.parametrize(
    ("total", "chunk", "pattern"),
    [
        (8, 0, r"its header says \d+ bytes, the file has \d+"),
        (-8, 0, r"its header says \d+ bytes, the file has \d+"),
        (0, 64, r"the chunk at byte \d+ says \d+ bytes, past the end of the file"),
    ],
)
def test_wrong_glb_lengths_are_refused(tmp_path, monkeypatch, total, chunk, pattern):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.glb").write_bytes(_glb(total, chunk))
    result, _ = _run(["inspect", "t.glb"])
    _one_line(result, r"t\.glb: cannot parse GLB file: " + pattern)


def test_a_well_formed_glb_and_local_buffer_still_load(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.glb").write_bytes(_glb())
    (tmp_path / "tetra bin.bin").write_bytes(_BLOB)
    (tmp_path / "local.gltf").write_text(json.dumps(_gltf(uri="tetra%20bin.bin")))
    for name in ("t.glb", "local.gltf"):
        result, _ = _run(["inspect", name])
        assert result.exit_code == 0, result.output
        (body,) = json.loads(result.stdout)["bodies"]
        assert body["volume"] == pytest.approx(1 / 6)


def test_a_buffer_that_is_a_pipe_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    pipe = _pipe(tmp_path, "tetra.bin")
    (tmp_path / "piped.gltf").write_text(json.dumps(_gltf(uri="tetra.bin")))
    result, blocked = _run(["inspect", "piped.gltf"], [pipe])
    assert not blocked
    _one_line(result, r"tetra\.bin: is a named pipe, not a regular file")


@pytest.mark.parametrize("kind", ["manifest", "baseline"])
def test_a_number_of_5000_digits_is_one_line(tmp_path, monkeypatch, kind):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tetra.obj").write_text(TETRA_OBJ)
    digits = "1" * 5000
    if kind == "manifest":
        (tmp_path / "m.json").write_text(
            '{"bodies": [{"name": "a", "mesh": "tetra.obj", "position": [' + digits + ", 0, 0]}]}"
        )
        args, pattern = ["check", "m.json"], r"m\.json: a number is too long to read \(.*\)"
    else:
        (tmp_path / "m.json").write_text('{"pairs": [' + digits + "]}")
        args = ["check", "tetra.obj", "--baseline", "m.json"]
        pattern = r"m\.json: baseline has a number too long to read \(.*\)"
    result, _ = _run(args)
    _one_line(result, pattern)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_fifo_planted_in_the_cache_is_a_miss_not_a_read_that_blocks(tmp_path) -> None:
    # The decomposition cache (a shared folder) read its entries with a plain read: a FIFO
    # under an entry's name blocked the run for ever. It is now a miss, as a corrupt entry is.
    import threading

    from meshcol.decomposition import cache

    key = "ab" + "0" * 62
    folder = tmp_path / "cache" / key[:2]
    folder.mkdir(parents=True)
    os.mkfifo(folder / f"{key}.npz")
    found: list = []
    reader = threading.Thread(target=lambda: found.append(cache.load(key, tmp_path / "cache")))
    reader.daemon = True
    reader.start()
    reader.join(timeout=20)
    assert not reader.is_alive(), "reading a FIFO in the cache blocked"
    assert found == [None]
