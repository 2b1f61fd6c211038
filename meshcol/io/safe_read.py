"""The one guarded way to read an input file: regular files only, never blocking, capped.

Every reader of a file the user names goes through here: mesh files (the core's OBJ and STL
readers are given only files that :func:`check_input` passed), scene manifests, ``--baseline``
and ``--joints`` JSON, robot descriptions and their includes, glTF buffers. What is refused is
one :class:`meshcol.errors.InputFileError` naming the file (exit 2 on the command line):

- anything that is not a regular file: a named pipe (which would block forever), a device
  (``/dev/zero`` reads forever), a socket, a folder, a symbolic link that loops or dangles;
- a file larger than the cap of its kind (:data:`MAX_BYTES`), read or not: a sparse file of a
  terabyte is refused before a byte of it is read.

Files are opened with ``O_NONBLOCK`` and checked with ``fstat`` on the open descriptor before
a byte is read, so a pipe put in place of a file between a check and the read cannot block.
At most the cap plus one byte is ever read, whatever the file grows to meanwhile.
"""

from __future__ import annotations

import os
import stat
from typing import BinaryIO, Literal

from meshcol.errors import InputFileError

__all__ = [
    "MAX_BYTES",
    "InputKind",
    "check_input",
    "file_kind",
    "read_input",
    "check_mjcf_files",
    "refuse_special",
]

#: What a file is read as; each kind has its cap in :data:`MAX_BYTES`.
InputKind = Literal["mesh", "manifest", "json", "robot", "buffer", "texture"]

_GIB = 1 << 30
_MIB = 1 << 20

#: Largest file read, by kind, in bytes. Each is far above what the format holds in practice,
#: and low enough that one file cannot take the machine's memory:
#:
#: - ``mesh`` (OBJ, STL, PLY, OFF, glTF JSON, GLB): 4 GiB, the largest GLB the format can
#:   express (its length field is 32 bits); 80 million triangles of binary STL;
#: - ``buffer`` (a glTF file's external ``.bin``): 4 GiB, as GLB;
#: - ``manifest`` (scene JSON/TOML): 1 GiB (a 300,000-body manifest is about 60 MB);
#: - ``json`` (``--baseline`` reports, ``--joints`` files): 1 GiB (a check report of
#:   100,000 pairs is about 150 MB; a joints file is a few hundred bytes);
#: - ``robot`` (URDF, MJCF and its ``<include>`` files, SRDF, xacro leftovers): 256 MiB (the
#:   largest descriptions of the public collections are a few MB);
#: - ``texture`` (an MJCF ``<texture>``'s PNG or custom files, which MuJoCo's compiler decodes):
#:   1 GiB (a 16384 x 16384 RGBA image uncompressed).
MAX_BYTES: dict[str, int] = {
    "mesh": 4 * _GIB,
    "buffer": 4 * _GIB,
    "manifest": _GIB,
    "json": _GIB,
    "robot": 256 * _MIB,
    "texture": _GIB,
}

_WHAT = {
    "mesh": "mesh file",
    "buffer": "glTF buffer",
    "manifest": "scene manifest",
    "json": "JSON file",
    "robot": "robot description",
    "texture": "texture",
}


def file_kind(mode: int) -> str:
    """What a file of ``mode`` (``st_mode``) is, in words: ``a named pipe``, ``a device``..."""
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _refuse_stat(info: os.stat_result, kind: str, source: str) -> None:
    if not stat.S_ISREG(info.st_mode):
        what = file_kind(info.st_mode)
        raise InputFileError(f"is {what}, not a regular file", source)
    cap = MAX_BYTES[kind]
    if info.st_size > cap:
        raise InputFileError(
            f"{_WHAT[kind]} is {_size(info.st_size)}, over the limit of {_size(cap)}", source
        )


def _os_error(error: OSError, source: str) -> InputFileError:
    if isinstance(error, IsADirectoryError):
        return InputFileError("is a folder, not a regular file", source)
    if isinstance(error, FileNotFoundError):
        if os.path.islink(source):
            return InputFileError("symbolic link to a missing file", source)
        return InputFileError("file not found", source)
    return InputFileError(f"cannot read file: {error.strerror or error}", source)


def _nonblocking(path: str, flags: int) -> int:
    """``open``'s opener: never wait (for a pipe's writer) and never take a terminal."""
    extra = getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    return os.open(path, flags | extra)


def _open_checked(source: str, kind: str, capped: bool = True) -> tuple[BinaryIO, os.stat_result]:
    """``source`` open for reading (never blocking) once ``fstat`` on it says it is a regular
    file within the cap of ``kind`` (``capped``); the caller closes it."""
    try:
        f = open(source, "rb", buffering=0, opener=_nonblocking)  # noqa: SIM115 - returned
    except OSError as error:
        raise _os_error(error, source) from None
    try:
        info = os.fstat(f.fileno())
        if capped:
            _refuse_stat(info, kind, source)
        elif not stat.S_ISREG(info.st_mode):
            raise InputFileError(f"is {file_kind(info.st_mode)}, not a regular file", source)
    except BaseException as error:
        f.close()
        if isinstance(error, OSError):
            raise _os_error(error, source) from None
        raise
    return f, info


def check_input(path: str | os.PathLike[str], kind: InputKind = "mesh") -> os.stat_result:
    """The file's ``stat``, once it is known to be a readable regular file within the cap of
    ``kind``: for readers that open the file by name themselves (MuJoCo's compiler, lxml,
    trimesh's COLLADA reader). Raises :class:`InputFileError` naming the file otherwise."""
    source = os.fspath(path)
    f, info = _open_checked(source, kind)
    f.close()
    return info


def read_input(
    path: str | os.PathLike[str], kind: InputKind = "mesh", limit: int | None = None
) -> bytes:
    """The bytes of the file at ``path``, read without blocking and capped.

    Parameters
    ----------
    path : str or path-like
        Named as given in every message.
    kind : str
        What the file is (:data:`InputKind`): picks its cap in :data:`MAX_BYTES`.
    limit : int, optional
        Read only the first ``limit`` bytes (a file's head: the root element of an XML file);
        the file may then be larger than its cap.

    Raises
    ------
    InputFileError
        Missing, unreadable, not a regular file, or over its kind's cap.
    """
    source = os.fspath(path)
    opened, info = _open_checked(source, kind, capped=limit is None)
    cap = MAX_BYTES[kind] if limit is None else limit
    try:
        with opened as f:
            data = _read_upto(f, min(info.st_size, cap) + 1, cap + 1 if limit is None else cap)
    except OSError as error:
        raise _os_error(error, source) from None
    if limit is None and len(data) > cap:  # it grew while read
        raise InputFileError(f"{_WHAT[kind]} is over the limit of {_size(cap)}", source)
    return data


def _read_upto(f: BinaryIO, first: int, most: int) -> bytes:
    """At most ``most`` bytes of ``f``: ``first`` (the size ``fstat`` gave, plus one) in one
    read, then what a growing file adds, a chunk at a time."""
    parts = [f.read(min(first, most))]
    total = len(parts[0])
    while total < most:
        chunk = f.read(min(1 << 20, most - total))
        if not chunk:
            break
        parts.append(chunk)
        total += len(chunk)
    return b"".join(parts) if len(parts) > 1 else parts[0]


def refuse_special(path: str | os.PathLike[str], kind: InputKind = "robot") -> None:
    """:func:`check_input` for a file that another reader will open and whose absence it
    reports in its own words (MuJoCo's includes and meshes): a missing file passes."""
    source = os.fspath(path)
    if os.path.lexists(source) and not os.path.isdir(source):
        check_input(source, kind)
    elif os.path.isdir(source):
        raise InputFileError("is a folder, not a regular file", source)


def _size(count: int) -> str:
    """``4 GiB``, ``256 MiB``, ``1.5 TiB``: a byte count in binary units."""
    value = float(count)
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if value < 1024 or unit == "TiB":
            return f"{value:.3g} {unit}" if unit != "bytes" else f"{count} bytes"
        value /= 1024
    return f"{count} bytes"


#: MJCF asset elements and their file attributes (a cube map's six faces too), with the
#: compiler directory each is found under (``assetdir`` when that one is not set).
_MJCF_FILES = {
    "mesh": (("file",), "meshdir"),
    "hfield": (("file",), "meshdir"),
    "skin": (("file",), "meshdir"),
    "texture": (
        ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"),
        "texturedir",
    ),
}


def check_mjcf_files(source: str) -> None:
    """Refuse, before MuJoCo's compiler opens them, the files an MJCF model names that are not
    regular files or are over their cap: its ``<include file>`` (relative to the main file's
    folder, as MuJoCo resolves them, nested includes too), its ``<mesh>``, ``<hfield>`` and
    ``<skin>`` files (under ``<compiler meshdir>`` or ``assetdir``) and its ``<texture>`` files,
    a cube map's six too (under ``texturedir`` or ``assetdir``). A missing file is left to
    MuJoCo's own message; a file that does not parse too."""
    from lxml import etree

    folder = os.path.dirname(source)  # paths as the user would type them, for messages
    parser = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=False)
    pending, seen = [source], set[str]()
    dirs: dict[str, str] = {}
    assets: list[tuple[str, str]] = []  # (file, its compiler directory's key)
    while pending and len(seen) < 1000:
        path = pending.pop()
        if path in seen:
            continue
        seen.add(path)
        refuse_special(path, "robot")
        if not os.path.isfile(path):
            continue
        try:
            root = etree.fromstring(read_input(path, "robot"), parser)
        except etree.XMLSyntaxError:
            continue  # MuJoCo says what is wrong with it
        for element in root.iter("include", "compiler", *_MJCF_FILES):
            if element.tag == "compiler":
                for key in ("assetdir", "meshdir", "texturedir"):
                    if element.get(key) and key not in dirs:
                        dirs[key] = element.get(key, "")
            elif element.tag == "include":
                if element.get("file"):
                    pending.append(os.path.join(folder, element.get("file")))
            else:
                names, key = _MJCF_FILES[element.tag]
                assets += [(element.get(a), key) for a in names if element.get(a)]
    for file, key in assets:
        sub = dirs.get(key) or dirs.get("assetdir") or ""
        refuse_special(
            os.path.join(folder, sub, file), "texture" if key == "texturedir" else "mesh"
        )
