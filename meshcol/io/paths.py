"""Paths as the user would type them: the one way meshcol displays a path.

Reports (a body's ``file``, a run's ``inputs``), messages on stderr (``written to parts/``) and
the errors about output locations all name a file relative to the working folder when it lies
inside it, and as given otherwise, so that a report read next to its inputs needs no
absolute paths and a message names what the user typed.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import overload

__all__ = ["display_path", "display_paths"]


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
    for path in paths:
        text = None if path is None else os.fspath(path)
        if text is None or not os.path.isabs(text):
            out.append(display_path(text, posix=posix))
            continue
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
