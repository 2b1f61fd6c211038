"""Every file a robot reader opens goes through the guarded read (issue 29 item 11, the
leftovers of session 12): MJCF textures (a cube map's faces too), the URDF itself, its SRDF.
A named pipe, a device or an oversized file is one line naming it, exit 2, and nothing
blocks; a well-formed texture still compiles."""

from __future__ import annotations

import os
import struct
import zlib
from pathlib import Path

import pytest
from test_hostile_reads import _one_line, _pipe, _robot, _run

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes (POSIX)")

BOX = '<worldbody><body><geom type="box" size="1 1 1"/></body></worldbody>'


def _png(path: Path, size: int = 4) -> None:
    """A valid RGB PNG of ``size`` x ``size`` grey pixels."""
    raw = b"".join(b"\0" + b"\x80" * 3 * size for _ in range(size))

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


def _model(folder: Path, texture: str, compiler: str = "") -> None:
    (folder / "model.xml").write_text(
        f"<mujoco>{compiler}<asset>{texture}"
        '<material name="m" texture="t"/></asset>'
        '<worldbody><body><geom type="box" size="1 1 1" material="m"/></body>'
        "</worldbody></mujoco>"
    )


@pytest.fixture
def mujoco():
    return pytest.importorskip("mujoco", reason="MJCF is compiled by MuJoCo")


def test_a_texture_that_reads_well_still_compiles(tmp_path, monkeypatch, mujoco) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tex").mkdir()
    _png(tmp_path / "tex" / "grey.png")
    _model(
        tmp_path,
        '<texture name="t" type="2d" file="grey.png"/>',
        '<compiler texturedir="tex"/>',
    )
    result, _ = _run(["inspect", "model.xml"])
    assert result.exit_code == 0, result.stderr


@pytest.mark.parametrize(
    ("texture", "compiler", "name"),
    [
        ('<texture name="t" type="2d" file="tex.png"/>', "", "tex.png"),
        ('<texture name="t" type="2d" file="tex.png"/>', '<compiler texturedir="t"/>', "t/tex.png"),
        (
            '<texture name="t" type="cube" fileright="tex.png" fileleft="g.png" fileup="g.png" '
            'filedown="g.png" filefront="g.png" fileback="g.png"/>',
            '<compiler assetdir="a"/>',
            "a/tex.png",
        ),
    ],
    ids=["file", "texturedir", "cube-face-assetdir"],
)
def test_a_texture_that_is_a_pipe_is_refused(
    tmp_path, monkeypatch, mujoco, texture, compiler, name
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).parent.mkdir(exist_ok=True)
    for folder in {(tmp_path / name).parent}:
        _png(folder / "g.png")
    pipe = _pipe(tmp_path, name)
    _model(tmp_path, texture, compiler)
    result, blocked = _run(["check", "model.xml"], [pipe])
    assert not blocked, "an MJCF texture that is a named pipe blocked the reader"
    _one_line(result, f"{name}: is a named pipe, not a regular file".replace(".", r"\."))


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_a_texture_that_is_a_device_is_refused(tmp_path, monkeypatch, mujoco) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tex.png").symlink_to("/dev/zero")
    _model(tmp_path, '<texture name="t" type="2d" file="tex.png"/>')
    result, _ = _run(["inspect", "model.xml"])
    _one_line(result, r"tex\.png: is a device, not a regular file")


def test_an_oversized_texture_is_refused_unread(tmp_path, monkeypatch, mujoco) -> None:
    from meshcol.io.safe_read import MAX_BYTES

    monkeypatch.chdir(tmp_path)
    with open(tmp_path / "tex.png", "wb") as f:  # sparse: no disk is used
        f.truncate(MAX_BYTES["texture"] + 1)
    _model(tmp_path, '<texture name="t" type="2d" file="tex.png"/>')
    result, _ = _run(["inspect", "model.xml"])
    _one_line(result, r"tex\.png: texture is 1 GiB, over the limit of 1 GiB")


def test_an_srdf_that_is_a_pipe_is_refused(tmp_path, monkeypatch) -> None:
    pytest.importorskip("yourdfpy", reason="URDF is read by yourdfpy")
    monkeypatch.chdir(tmp_path)
    _robot(tmp_path)
    pipe = _pipe(tmp_path, "arm.srdf")
    result, blocked = _run(["check", "arm.urdf", "--srdf", "arm.srdf"], [pipe])
    assert not blocked, "an SRDF that is a named pipe blocked the reader"
    _one_line(result, r"arm\.srdf: is a named pipe, not a regular file")
