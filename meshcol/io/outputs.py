"""Where a run's outputs go: checked before any work starts, written all or nothing.

A run that fails after an hour of work because its report folder is missing, or that replaces
one of its own inputs, is worse than one that refuses at once. :func:`check_outputs` checks
every output location of a run before it starts: an output file's folder exists and is
writable, an output folder exists and is writable or can be created, no output is an input,
and no two outputs are one file. :func:`staged_folder` writes a run's files into a hidden
folder inside the destination and moves them into place only when all are written (with
SIGINT and SIGTERM held for the moves), so a failed or interrupted run leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator, Mapping, Sequence

from meshcol.errors import MeshcolError

__all__ = [
    "check_output_file",
    "check_output_folder",
    "check_outputs",
    "same_file",
    "staged_folder",
]

PathLike = str | os.PathLike[str]


def _identity(path: PathLike) -> tuple[int, int] | str:
    """What makes two paths one file: device and inode when it exists, else the real path."""
    try:
        st = os.stat(path)
    except OSError:
        return os.path.normcase(os.path.realpath(path))
    return (st.st_dev, st.st_ino)


def same_file(a: PathLike, b: PathLike) -> bool:
    """True when ``a`` and ``b`` name one file (links and relative paths resolved), existing
    or not."""
    return _identity(a) == _identity(b)


def _writable_folder(folder: str) -> bool:
    return os.access(folder, os.W_OK | os.X_OK)


def _existing_ancestor(path: str) -> str:
    """The nearest existing ancestor of ``path`` (``path`` itself when it exists)."""
    current = os.path.abspath(path)
    while not os.path.lexists(current):
        parent = os.path.dirname(current)
        if parent == current:
            break
        current = parent
    return current


def _shown(path: str) -> str:
    """A folder as the user would recognise it: relative to the working folder when inside."""
    relative = os.path.relpath(path)
    return path if relative.startswith(os.pardir) else relative


def check_output_file(path: PathLike) -> None:
    """Raise :class:`MeshcolError` (naming ``path``) unless ``path`` can be written as a file.

    Its folder must exist (files are written in place, never with their folders created) and
    be writable, and ``path`` must not be a folder.
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        raise MeshcolError("is a folder, not a file", path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.exists(folder):
        ancestor = _existing_ancestor(folder)
        if not os.path.isdir(ancestor):
            raise MeshcolError(f"{_shown(ancestor)} is not a folder", path)
        raise MeshcolError(f"folder {_shown(folder)} does not exist", path)
    if not os.path.isdir(folder):
        raise MeshcolError(f"{_shown(folder)} is not a folder", path)
    if not _writable_folder(folder):
        raise MeshcolError(f"cannot write in folder {_shown(folder)} (permission denied)", path)


def check_output_folder(path: PathLike) -> None:
    """Raise :class:`MeshcolError` (naming ``path``) unless ``path`` is a writable folder or can
    be created (its nearest existing ancestor is a writable folder)."""
    path = os.fspath(path)
    if os.path.exists(path):
        if not os.path.isdir(path):
            raise MeshcolError("is a file, not a folder", path)
        if not _writable_folder(path):
            raise MeshcolError("cannot write in this folder (permission denied)", path)
        return
    ancestor = _existing_ancestor(path)
    if not os.path.isdir(ancestor):
        raise MeshcolError(f"cannot create the folder: {_shown(ancestor)} is not a folder", path)
    if not _writable_folder(ancestor):
        raise MeshcolError(
            f"cannot create the folder: cannot write in {_shown(ancestor)} (permission denied)",
            path,
        )


def check_outputs(
    files: Mapping[str, PathLike | None] | None = None,
    folders: Mapping[str, PathLike | None] | None = None,
    inputs: Sequence[PathLike] = (),
) -> None:
    """Check every output location of a run before the run starts.

    Parameters
    ----------
    files : mapping of label -> path or None
        Output files (``{"--report": "out/r.json"}``); None entries are skipped.
    folders : mapping of label -> path or None
        Output folders (``{"--out-dir": "parts", "--cache-dir": None}``), created if missing.
    inputs : sequence of paths
        The run's input files: no output may be one of them.

    Raises
    ------
    MeshcolError
        Naming the path as given: a missing or unwritable folder, a folder given as a file
        (or the reverse), an output that is an input, or one path given as two outputs.
    """
    outputs = [(label, os.fspath(p), "file") for label, p in (files or {}).items() if p]
    outputs += [(label, os.fspath(p), "folder") for label, p in (folders or {}).items() if p]
    for label, path, kind in outputs:
        for source in inputs:
            if same_file(path, source):
                raise MeshcolError(f"{label} would replace this input", path)
        (check_output_file if kind == "file" else check_output_folder)(path)
    for i, (label, path, _) in enumerate(outputs):
        for other, other_path, _ in outputs[i + 1 :]:
            if same_file(path, other_path):
                raise MeshcolError(f"given as both {label} and {other}", path)


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM for the block (delivered when it ends), in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    wanted = [signal.SIGINT, *([signal.SIGTERM] if hasattr(signal, "SIGTERM") else [])]
    # A handler not installed from Python (getsignal None) could not be put back: leave it.
    wanted = [s for s in wanted if signal.getsignal(s) is not None]
    previous = {s: signal.signal(s, lambda signum, frame: held.append(signum)) for s in wanted}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for number in dict.fromkeys(held):
            signal.raise_signal(number)


@contextlib.contextmanager
def staged_folder(folder: PathLike) -> Iterator[str]:
    """Yield a hidden folder inside ``folder``; when the block succeeds, move its files into
    ``folder``; otherwise remove them, and the folders this created.

    ``folder`` (and its missing parents) is created first. Each move is an ``os.replace``
    on one file system, and SIGINT and SIGTERM wait until the moves are done, so the files
    of a run appear together or not at all. Files only (the writers put no folder in it).
    """
    folder = os.path.abspath(os.fspath(folder))
    created = []
    current = folder
    while not os.path.lexists(current):
        created.append(current)
        current = os.path.dirname(current)
    os.makedirs(folder, exist_ok=True)
    stage = None
    try:
        stage = tempfile.mkdtemp(prefix=".meshcol-", dir=folder)
        yield stage
        with _signals_held():
            for name in sorted(os.listdir(stage)):
                os.replace(os.path.join(stage, name), os.path.join(folder, name))
            os.rmdir(stage)
    except BaseException as exc:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        for path in created:  # deepest first
            with contextlib.suppress(OSError):
                os.rmdir(path)
        failed = getattr(exc, "filename", None)
        if (
            stage is not None
            and isinstance(exc, OSError)
            and isinstance(failed, str)
            and os.path.dirname(os.path.abspath(failed)) == stage
        ):
            # Name the file the user asked for, never the hidden folder.
            where = os.path.join(folder, os.path.basename(failed))
            raise type(exc)(exc.errno, exc.strerror, where) from None
        raise
