"""How a report shows a file's path: relative to the working folder when the file is inside
it, else as given; forward slashes either way (reports compare across machines).

Shared by every command's report (``check``'s bodies, inputs and baseline,
``collision-matrix``'s input).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

__all__ = ["display_path", "display_paths"]


def display_path(path: str | None) -> str | None:
    """``path`` as a report shows it: an absolute path inside the working folder made relative
    to it, any other path as given; ``/`` separators; None stays None."""
    if path is None:
        return None
    if os.path.isabs(path):
        rel = os.path.relpath(path)
        if not rel.startswith(".."):
            return rel.replace(os.sep, "/")
    return str(path).replace(os.sep, "/")


def display_paths(paths: Sequence[str | None]) -> list[str | None]:
    """:func:`display_path` of each path, the folder of an absolute one made relative once (not
    once a body: ``os.path.relpath`` costs 20 us, and a scene can hold 100,000 bodies)."""
    folders: dict[str, str] = {}
    out: list[str | None] = []
    for path in paths:
        if path is None or not os.path.isabs(path):
            out.append(display_path(path))
            continue
        folder, name = os.path.split(path)
        if folder not in folders:
            folders[folder] = os.path.relpath(folder)
        inside = folders[folder]
        if name in ("", ".", ".."):
            out.append(display_path(path))
        elif inside.startswith(".."):
            # outside the working folder: kept absolute, as display_path keeps it
            # (relpath(path) is relpath(folder) and the name, so it starts with ".." too)
            out.append(path.replace(os.sep, "/"))
        else:
            # the working folder contains the file's folder, so relpath(path) is relpath(folder)
            # followed by the name
            out.append((name if inside == "." else os.path.join(inside, name)).replace(os.sep, "/"))
    return out
