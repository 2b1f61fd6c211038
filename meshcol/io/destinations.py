"""Output destinations that would destroy data: an output onto an input, two outputs one file.

Every command that writes files calls :func:`check_destinations` before it writes anything
(``hull``, ``inspect``, ``check`` and ``sweep`` from their command-line entry points, and
:func:`meshcol.analysis.hull.hull` again for its per-body files), so ``meshcol hull cube.obj
-o cube.obj`` is exit 2 with the input intact rather than a silent overwrite.

Two paths are the same file when their resolved paths (symbolic links followed, ``..``
removed, case folded where the platform folds it) are equal, or when both exist and
:func:`os.path.samefile` says so (hard links, case-insensitive file systems). ``-`` (stdout)
is never a file.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from meshcol.errors import OutputPathError

__all__ = ["check_destinations", "manifest_inputs", "same_file"]

PathLike = str | os.PathLike[str]


def _key(path: PathLike) -> str:
    return os.path.normcase(os.path.realpath(os.fspath(path)))


def same_file(a: PathLike, b: PathLike) -> bool:
    """True when ``a`` and ``b`` name one file (see the module notes)."""
    if _key(a) == _key(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet): then they are not one file
        return False


def check_destinations(
    inputs: Iterable[tuple[str, PathLike]], outputs: Iterable[tuple[str, PathLike | None]]
) -> None:
    """Raise when an output would replace an input, or two outputs are one file.

    Parameters
    ----------
    inputs : iterable of (description, path)
        What the run reads, each with what it is to the user (``"the input"``, ``"the
        --baseline"``, ``"a mesh file of scene.json"``).
    outputs : iterable of (label, path or None)
        What the run writes, each with its option (``"-o"``, ``"--report"``); None and
        ``"-"`` (stdout) are skipped.

    Raises
    ------
    OutputPathError
        ``cube.obj: -o would overwrite the input`` or ``out.obj: -o and --report are the same
        file``, naming the path as the user typed it.
    """
    read = [(label, os.fspath(path)) for label, path in inputs]
    written: list[tuple[str, str]] = []
    for label, path in outputs:
        if path is None or os.fspath(path) == "-":
            continue
        path = os.fspath(path)
        for description, in_path in read:
            if same_file(path, in_path):
                raise OutputPathError(f"{label} would overwrite {description}", path)
        for out_label, out_path in written:
            if same_file(path, out_path):
                raise OutputPathError(f"{out_label} and {label} are the same file", path)
        written.append((label, path))


def manifest_inputs(paths: Iterable[PathLike]) -> list[tuple[str, str]]:
    """Every file a command's inputs read: the inputs and, for a scene manifest, its meshes.

    A manifest that cannot be parsed contributes only itself: loading it reports the problem.
    """
    from meshcol.io.scene import MANIFEST_EXTENSIONS, manifest_mesh_files

    found: list[tuple[str, str]] = []
    for path in paths:
        path = os.fspath(path)
        found.append(("the input", path))
        if Path(path).suffix.lower() in MANIFEST_EXTENSIONS:
            found.extend((f"a mesh file of {path}", mesh) for mesh in manifest_mesh_files(path))
    return found
