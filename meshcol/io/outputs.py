"""Where a run's outputs go: checked before any work starts, written all or nothing.

A run that fails after an hour of work because its report folder is missing, or that replaces
one of its own inputs, is worse than one that refuses at once. Every command calls
:func:`check_outputs` before it computes anything: it checks every output location of the
run (an output file's folder exists and is writable, an output folder exists and is
writable or can be created) and, by :func:`check_destinations`, that no output is an input
and no two outputs are one file. :func:`staged_folder` writes a run's files into a hidden
folder inside the destination and moves them into place only when all are written (with
SIGINT and SIGTERM held for the moves), so a failed or interrupted run leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator, Mapping, Sequence

from meshcol.errors import MeshcolError, OutputPathError
from meshcol.io.paths import display_path
from meshcol.io.report import is_special_file
from meshcol.io.staging import OPEN_STAGES, active_batch, move_staged, signals_held

__all__ = [
    "check_destinations",
    "check_output_file",
    "check_output_folder",
    "check_outputs",
    "manifest_inputs",
    "same_file",
    "staged_folder",
]

PathLike = str | os.PathLike[str]


def _key(path: PathLike) -> str:
    return os.path.normcase(os.path.realpath(os.fspath(path)))


def same_file(a: PathLike, b: PathLike) -> bool:
    """True when ``a`` and ``b`` name one file, existing or not: their resolved paths
    (symbolic links followed, ``..`` removed, case folded where the platform folds it) are
    equal, or both exist and :func:`os.path.samefile` says so (hard links, case-insensitive
    file systems). ``-`` (stdout) is never a file."""
    if os.fspath(a) == "-" or os.fspath(b) == "-":
        return False
    if _key(a) == _key(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet): then they are not one file
        return False


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


def check_output_file(path: PathLike, made: Iterable[PathLike] = ()) -> None:
    """Raise :class:`MeshcolError` (naming ``path``) unless ``path`` can be written as a file.

    Its folder must exist (files are written in place, never with their folders created) and
    be writable, unless it is one of ``made``, the output folders the run makes before it
    writes the file (``--out-dir parts --report parts/r.json``; each is checked as a folder).
    ``path`` must not be a folder. A device or a pipe (``/dev/null``) needs only to be
    writable itself: reports are written into it.
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        raise MeshcolError("is a folder, not a file", path)
    if is_special_file(path):
        # written into, never replaced (io.report.atomic_path): its folder is not written
        if not os.access(path, os.W_OK):
            raise MeshcolError("cannot write to it (permission denied)", path)
        return
    folder = os.path.dirname(os.path.abspath(path))
    if _key(folder) in {_key(made_folder) for made_folder in made}:
        return
    if not os.path.exists(folder):
        ancestor = _existing_ancestor(folder)
        if not os.path.isdir(ancestor):
            raise MeshcolError(f"{display_path(ancestor)} is not a folder", path)
        raise MeshcolError(f"folder {display_path(folder)} does not exist", path)
    if not os.path.isdir(folder):
        raise MeshcolError(f"{display_path(folder)} is not a folder", path)
    if not _writable_folder(folder):
        raise MeshcolError(
            f"cannot write in folder {display_path(folder)} (permission denied)", path
        )


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
        raise MeshcolError(
            f"cannot create the folder: {display_path(ancestor)} is not a folder", path
        )
    if not _writable_folder(ancestor):
        raise MeshcolError(
            f"cannot create the folder: cannot write in {display_path(ancestor)} (permission denied)",
            path,
        )


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
    identities: _Identities | None = None
    for label, path in outputs:
        if path is None or os.fspath(path) == "-":
            continue
        path = os.fspath(path)
        # An output that does not exist yet is no existing input; one that exists is the same
        # file as an input exactly when their (device, inode) agree. One stat per input, in
        # the core's threads, not a realpath per (input, output): manifests name 100,000 meshes.
        try:
            st = os.stat(path)
        except OSError:
            st = None
        if st is not None:
            if identities is None:
                identities = _Identities([in_path for _, in_path in read])
            same = identities.first(st.st_dev, st.st_ino)
            if same is not None:
                raise OutputPathError(f"{label} would overwrite {read[same][0]}", path)
        # A missing input spelled as this output (reading it will fail anyway). Its resolved
        # path ends in its own last name (nothing of it exists to resolve), so only inputs
        # named as the output's resolved path ends are looked at: no lstat per input.
        name = os.path.normcase(os.path.basename(os.path.realpath(path)))
        for description, in_path in _named(read, name):
            if not os.path.lexists(in_path) and _key(path) == _key(in_path):
                raise OutputPathError(f"{label} would overwrite {description}", path)
        for out_label, out_path in written:
            if same_file(path, out_path):
                raise OutputPathError(f"{out_label} and {label} are the same file", path)
        written.append((label, path))


def _last_name(path: str) -> str:
    """``normcase(basename(normpath(path)))`` without the normpath where it changes nothing
    (a last name other than ``.``, ``..`` or empty): cheap for 100,000 inputs."""
    tail = os.path.basename(path)
    if tail in ("", ".", ".."):
        tail = os.path.basename(os.path.normpath(path))
    return os.path.normcase(tail)


#: The ends of a path whose last name :func:`_last_name` takes from ``normpath`` ("", ".",
#: "..").
_ODD_TAILS = (os.sep, os.altsep or os.sep, ".")


def _named(read: list[tuple[str, str]], name: str) -> list[tuple[str, str]]:
    """The inputs of ``read`` whose :func:`_last_name` is ``name``. Where case is kept
    (``normcase`` changes nothing), such a path ends with ``name`` or with one of
    :data:`_ODD_TAILS`, or is empty: one string test per input, :func:`_last_name` only on
    those."""
    if os.path.normcase("Aa") != "Aa":
        return [item for item in read if _last_name(item[1]) == name]
    ends = (name, *_ODD_TAILS)
    return [
        item
        for item in read
        if (not item[1] or item[1].endswith(ends)) and _last_name(item[1]) == name
    ]


#: Inputs from which on the guard stats them in the core's threads (numpy and the native
#: module loaded); fewer are stat'ed here, so that a warm ``meshcol ci`` imports neither.
STAT_IN_CORE = 256


class _Identities:
    """Device and inode of every input (symbolic links followed), stat'ed at once
    (:func:`meshcol.io.mesh_read.file_identities`) from :data:`STAT_IN_CORE` inputs on, one by
    one below; inputs that cannot be stat'ed match nothing."""

    def __init__(self, paths: list[str]) -> None:
        self.index: dict[tuple[int, int], int] | None = None
        if len(paths) < STAT_IN_CORE:
            self.index = {}
            for i, path in enumerate(paths):
                try:
                    info = os.stat(path)
                except (OSError, ValueError):
                    continue
                self.index.setdefault((info.st_dev, info.st_ino), i)
            return
        from meshcol.io.mesh_read import file_identities

        self.device, self.inode, self.found = file_identities(paths)

    def first(self, device: int, inode: int) -> int | None:
        """The index of the first input that is the file (``device``, ``inode``), or None."""
        if self.index is not None:
            return self.index.get((device, inode))
        import numpy as np

        hits = np.flatnonzero(
            (self.inode == np.uint64(inode))
            & (self.device == np.uint64(device))
            & (self.found != 0)
        )
        return int(hits[0]) if len(hits) else None


def manifest_inputs(paths: Iterable[PathLike]) -> list[tuple[str, str]]:
    """Every file a command's inputs read: the inputs and, for a scene manifest, its meshes.

    A manifest that cannot be parsed contributes only itself: loading it reports the problem.
    """
    from meshcol.io.inputs import is_manifest

    found: list[tuple[str, str]] = []
    for path in paths:
        path = os.fspath(path)
        found.append(("the input", path))
        if is_manifest(path):
            from meshcol.io.scene import manifest_mesh_files  # numpy: only for a manifest

            description = f"a mesh file of {path}"  # once, not once a mesh
            found.extend((description, mesh) for mesh in manifest_mesh_files(path))
    return found


def check_outputs(
    files: Mapping[str, PathLike | None] | None = None,
    folders: Mapping[str, PathLike | None] | None = None,
    inputs: Sequence[PathLike] = (),
    named_inputs: Mapping[str, PathLike | None] | None = None,
) -> None:
    """Check every output location of a run before the run starts: no output replaces an
    input (a manifest's mesh files included) or another output (:func:`check_destinations`),
    every output file's folder exists and is writable, every output folder is writable or
    can be created. Every command calls it first, so nothing of a run is computed for an
    output it cannot write.

    Parameters
    ----------
    files : mapping of label -> path or None
        Output files (``{"--report": "out/r.json"}``); None and ``"-"`` entries are skipped.
    folders : mapping of label -> path or None
        Output folders (``{"--out-dir": "parts", "--cache-dir": None}``), created if missing.
    inputs : sequence of paths
        The run's input files (``the input``; a manifest's meshes too).
    named_inputs : mapping of description -> path or None
        Other files the run reads, each with what it is to the user
        (``{"the --baseline": "old.json"}``); None entries are skipped.

    Raises
    ------
    MeshcolError
        Naming the path as given: a missing or unwritable folder, a folder given as a file
        (or the reverse), an output that is an input, or one path given as two outputs.

    Notes
    -----
    A file directly inside one of ``folders`` needs no existing folder: the run makes it
    before writing the file.
    """
    out_files = {label: os.fspath(p) for label, p in (files or {}).items() if p and p != "-"}
    out_folders = {label: os.fspath(p) for label, p in (folders or {}).items() if p}
    read = manifest_inputs(inputs)
    read += [(what, os.fspath(p)) for what, p in (named_inputs or {}).items() if p is not None]
    check_destinations(read, [*out_files.items(), *out_folders.items()])
    for path in out_files.values():
        check_output_file(path, made=out_folders.values())
    for path in out_folders.values():
        check_output_folder(path)


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
        OPEN_STAGES.add(stage)
        try:
            yield stage
        finally:
            OPEN_STAGES.discard(stage)
        batch = active_batch()
        if batch is not None:  # moved with the run's other outputs, at its end
            batch.add_folder(stage, folder, created)
        else:
            with signals_held():
                move_staged(stage, folder)
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
