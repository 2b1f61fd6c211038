"""Paths as the user would type them: the one way meshcol displays a path.

Reports (a body's ``file``, a run's ``inputs``), messages on stderr (``written to parts/``) and
the errors about output locations all name a file relative to the working folder when it lies
inside it, and as given otherwise, so that a report read next to its inputs needs no
absolute paths and a message names what the user typed.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Iterator, Sequence
from contextvars import ContextVar
from typing import Any, overload
from urllib.parse import unquote

from meshcol.errors import InputFileError

__all__ = [
    "ROOT_ENV",
    "OutsideRootError",
    "confine",
    "confine_all",
    "confine_mjcf",
    "confine_uris",
    "confined_to",
    "current_root",
    "display_path",
    "display_paths",
    "joined_paths",
    "recording_reads",
]


@overload
def display_path(path: str | os.PathLike[str], *, posix: bool = False) -> str: ...


@overload
def display_path(path: None, *, posix: bool = False) -> None: ...


def display_path(path: str | os.PathLike[str] | None, *, posix: bool = False) -> str | None:
    """``path`` relative to the working folder when it is absolute and inside it, else as
    given (None stays None).

    Parameters
    ----------
    path : str, path-like or None
    posix : bool
        Write ``/`` between names whatever the platform's separator (the paths inside
        reports, which must read the same everywhere); otherwise the platform's (messages).

    Returns
    -------
    str or None

    Notes
    -----
    A relative path is never rewritten (``../x.obj`` stays so); an absolute path outside the
    working folder stays absolute.
    """
    if path is None:
        return None
    text = os.fspath(path)
    if os.path.isabs(text):
        relative = os.path.relpath(text)
        if not relative.startswith(".."):
            text = relative
    return text.replace(os.sep, "/") if posix else text


def display_paths(
    paths: Iterable[str | os.PathLike[str] | None], *, posix: bool = False
) -> list[str | None]:
    """:func:`display_path` of each of ``paths``, in bulk: the folder of an absolute path is
    made relative once, not once per file (``os.path.relpath`` costs about 20 us, and a scene
    can name 100,000 files)."""
    folders: dict[str, str] = {}
    out: list[str | None] = []
    slash = os.sep == "/"  # posixpath's isabs and split of a plain path, as string methods
    for path in paths:
        text = path if type(path) is str else None if path is None else os.fspath(path)
        if text is None:
            out.append(None)
            continue
        if not (text[:1] == "/" if slash else os.path.isabs(text)):
            # relative: never rewritten, as display_path keeps it (a manifest's 100,000 mesh
            # paths are usually relative: no call per path)
            out.append(text.replace(os.sep, "/") if posix and not slash else text)
            continue
        folder, _, name = text.rpartition("/") if slash else ("", "", "")
        if not folder or folder[-1] == "/":  # the root, a doubled slash, or not posix
            folder, name = os.path.split(text)
        if folder not in folders:
            folders[folder] = os.path.relpath(folder)
        inside = folders[folder]
        if name in ("", ".", ".."):
            out.append(display_path(text, posix=posix))
            continue
        if inside.startswith(".."):
            # outside the working folder: kept absolute, as display_path keeps it (relpath of
            # the path is relpath of its folder and the name, so it starts with ".." too)
            shown = text
        else:
            # the working folder contains the file's folder, so relpath(path) is
            # relpath(folder) followed by the name
            shown = name if inside == "." else os.path.join(inside, name)
        out.append(shown.replace(os.sep, "/") if posix else shown)
    return out


def joined_paths(folder: str, names: Sequence[str], *, normalise: bool = False) -> list[str]:
    """``os.path.join(folder, name)`` of each of ``names`` (``os.path.normpath`` of it with
    ``normalise``), in bulk: a plain relative name (no empty, ``.`` or ``..`` part, no name
    starting with a dot) under a normal folder is joined with one concatenation, the same
    text (a manifest names 100,000 mesh files; join and normpath cost about 1 us each)."""
    plain_folder = os.sep == "/" and (
        not folder or (folder not in ("/", ".") and os.path.normpath(folder) == folder)
    )
    prefix = f"{folder}/" if folder else ""
    if plain_folder and names and _all_plain("\n".join(names), len(names)):
        return [prefix + name for name in names]
    out = []
    for name in names:
        if (
            plain_folder
            and name
            and name[0] not in "/."
            and "/." not in name
            and "//" not in name
            and name[-1] != "/"
        ):
            out.append(prefix + name)
        elif normalise:
            out.append(os.path.normpath(os.path.join(folder, name)))
        else:
            out.append(os.path.join(folder, name))
    return out


def _all_plain(joined: str, count: int) -> bool:
    """Whether each of ``count`` names joined by newlines is a plain relative name (as the
    loop of :func:`joined_paths` tests one), in a few scans of the joined text."""
    return (
        joined.count("\n") == count - 1  # no name holds a newline of its own
        and joined[:1] not in ("", "\n", "/", ".")  # the first name empty, absolute, dotted
        and joined[-1] not in ("\n", "/")  # the last name empty, or a folder
        and not any(mark in joined for mark in ("\n\n", "\n/", "\n.", "/\n", "/.", "//"))
    )


# --- the root every path a file names must stay inside (untrusted inputs) ----------------------

#: The environment variable that carries the root to worker processes (and lets a user set it).
ROOT_ENV = "MESHCOL_ROOT"
_ROOT: ContextVar[str | None] = ContextVar("meshcol_root", default=None)
_READS: ContextVar[set[str] | None] = ContextVar("meshcol_reads", default=None)


class OutsideRootError(InputFileError):
    """A file names a path that resolves outside the root (``--root``, ``meshcol ci``)."""


def current_root() -> str | None:
    """The root paths named by files must resolve inside (real path), or None: no limit.
    Set by :func:`confined_to`, else by ``$MESHCOL_ROOT``."""
    root = _ROOT.get()
    if root is None:
        env = os.environ.get(ROOT_ENV)
        root = os.path.realpath(env) if env else None
    return root


@contextlib.contextmanager
def confined_to(root: str | os.PathLike[str] | None) -> Iterator[None]:
    """Within the block every path a file names must resolve inside ``root`` (None: no
    limit); nested blocks replace it."""
    token = _ROOT.set(None if root is None else os.path.realpath(root))
    try:
        yield
    finally:
        _ROOT.reset(token)


@contextlib.contextmanager
def recording_reads() -> Iterator[set[str]]:
    """Collect, in the set yielded, the real path of every file a file names that
    :func:`confine` lets through during the block (what a scene depends on)."""
    reads: set[str] = set()
    token = _READS.set(reads)
    try:
        yield reads
    finally:
        _READS.reset(token)


def confine_all(
    paths: Sequence[str], source: str | os.PathLike[str], references: Sequence[str]
) -> list[str]:
    """:func:`confine` of each of ``paths`` (``references[i]`` naming ``paths[i]`` in the
    error), in bulk: nothing done per path when there is no root to check and no read to
    record (the common run)."""
    if current_root() is None and _READS.get() is None:
        return list(paths)
    return [confine(path, source, reference) for path, reference in zip(paths, references)]


@overload
def confine(path: str, source: str | os.PathLike[str], reference: str | None = None) -> str: ...


@overload
def confine(path: None, source: str | os.PathLike[str], reference: str | None = None) -> None: ...


def confine(
    path: str | None, source: str | os.PathLike[str], reference: str | None = None
) -> str | None:
    """``path``, a file that ``source`` names (a manifest's mesh, a URDF's mesh, a glTF
    buffer, an MJCF include), as it was; the one check that it lies inside the root.

    The path is resolved first (symlinks followed, ``..`` collapsed): a link inside the root
    that points out of it is outside. With no root (:func:`current_root`) every path passes.

    Raises
    ------
    OutsideRootError
        ``source: path 'REFERENCE' resolves outside the root ROOT (to REAL)``: the path
        leaves the root.
    """
    if path is None:
        return None
    reads = _READS.get()
    root = current_root()
    if root is None and reads is None:
        return path  # nothing to check or record: no realpath (25 us each, 100,000 meshes)
    if "\x00" in path:
        return path  # names no file, inside the root or out: the read says "not found"
    real = os.path.realpath(path)
    if reads is not None:
        reads.add(real)
    if root is None or real == root or real.startswith(root.rstrip(os.sep) + os.sep):
        return path
    named = path if reference is None else reference
    raise OutsideRootError(
        f"path {named!r} resolves outside the root {display_path(root)} (to {real})",
        display_path(source),
    )


def confine_uris(document: Any, source: str | os.PathLike[str]) -> None:
    """:func:`confine` every external ``uri`` of a glTF document's buffers and images
    (``data:`` URIs are inline; other schemes are never fetched and refused under a root)."""
    folder = os.path.dirname(os.fspath(source))
    for name in ("buffers", "images"):
        items = document.get(name) if isinstance(document, dict) else None
        for item in items if isinstance(items, list) else []:
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            target = unquote(uri)
            if "://" in target and current_root() is not None:
                raise OutsideRootError(f"{name[:-1]} uri {uri!r} is not a file", source)
            confine(os.path.join(folder, target), source, uri)


def confine_mjcf(source: str | os.PathLike[str]) -> None:
    """:func:`confine` every file an MJCF file names (``<include file>``, followed; assets'
    ``file`` under the compiler's ``meshdir``, ``texturedir`` or ``assetdir``), before MuJoCo's
    compiler reads them. Does nothing without a root; a file that does not parse is left for
    the compiler to name."""
    if current_root() is None:
        return
    import xml.etree.ElementTree as ET

    from meshcol.io.safe_read import read_input

    pending, seen = [os.fspath(source)], set()
    dirs: dict[str, str] = {}
    while pending:
        file = pending.pop()
        if file in seen:
            continue
        seen.add(file)
        if not os.path.isfile(file):
            continue  # missing: the compiler names it
        try:  # the guarded read: never a pipe or a device, capped
            tree = ET.ElementTree(ET.fromstring(read_input(file, "robot")))
        except ET.ParseError:
            continue
        folder = os.path.dirname(os.fspath(source))  # MuJoCo: paths from the main file's folder
        for compiler in tree.iter("compiler"):
            for key in ("assetdir", "meshdir", "texturedir"):
                if compiler.get(key):
                    dirs[key] = compiler.get(key, "")
        for element in tree.iter():
            name = element.get("file")
            if name is None:
                continue
            if element.tag == "include":
                pending.append(confine(os.path.join(folder, name), file, name))
                continue
            sub = dirs.get("texturedir" if element.tag == "texture" else "meshdir")
            sub = sub or dirs.get("assetdir", "")
            confine(os.path.join(folder, sub, name), file, name)
