"""All the outputs of a run written together, or none: the one staged commit of every command.

Every output is first written whole to a temporary file beside its destination
(:func:`meshcol.io.report.atomic_path`) or into a hidden folder inside it
(:func:`meshcol.io.outputs.staged_folder`). Outside a run, each is put in place as soon as it
is written. Inside :func:`staged_outputs` (the command line opens one around every command),
each is only registered with the run's :class:`OutputBatch`, and when the run ends:

1. every output into a device or a pipe (``--report /dev/null``) is copied into it: the one
   step that can fail for lack of room (``/dev/full``) or a closed reader;
2. then every file is renamed into place and every staged folder's files moved (renames on
   one file system), with SIGINT and SIGTERM held until the last one.

A failure in step 1, or a run that fails (an exception: bad input, a report that cannot be
written, an interruption), removes every temporary file and staged folder, and the folders
the run created for them: the report, the parts of ``decompose`` and the hull of ``hull -o``
appear together or not at all. The error names the file the user asked for.

Writes that must land at once whatever the run does (the decomposition cache, the run
manifest that ``--resume`` reads) pass ``staged=False`` to ``atomic_path``.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

__all__ = [
    "OutputBatch",
    "active_batch",
    "batch_for",
    "commit_outputs",
    "once_written",
    "signals_held",
    "staged_outputs",
    "written_path",
]


@dataclass
class OutputBatch:
    """The outputs of one run, written but not yet in place.

    Attributes
    ----------
    files : list of (temporary, destination, special)
        Files renamed onto (or, ``special``, copied into) their destination at commit.
    folders : list of (stage, folder, created)
        Hidden folders whose files move into ``folder`` at commit; ``created`` are the
        folders made for them (deepest first), removed when the run fails.
    """

    files: list[tuple[str, str, bool]] = field(default_factory=list)
    folders: list[tuple[str, str, list[str]]] = field(default_factory=list)
    #: Done once the outputs are in place (a message saying where one went).
    after: list[Callable[[], None]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def add_file(self, tmp: str, path: str, special: bool) -> None:
        with self.lock:
            self.files.append((tmp, path, special))

    def add_folder(self, stage: str, folder: str, created: list[str]) -> None:
        with self.lock:
            self.folders.append((stage, folder, created))

    def commit(self) -> None:
        """Put every output in place (devices and pipes first: the step that can fail), or,
        when one cannot be written, none (the error names its destination)."""
        try:
            for tmp, path, special in self.files:
                if special:
                    copy_into(tmp, path)
        except BaseException:
            self.discard()
            raise
        with signals_held():
            for tmp, path, special in self.files:
                if special:
                    with contextlib.suppress(FileNotFoundError):
                        os.unlink(tmp)
                else:
                    os.replace(tmp, path)
            for stage, folder, _ in self.folders:
                move_staged(stage, folder)
        self.files.clear()
        self.folders.clear()
        after, self.after = self.after, []
        for step in after:
            step()

    def discard(self) -> None:
        """Remove every temporary file and staged folder, and the folders made for them."""
        for tmp, _, _ in self.files:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        for stage, _, created in self.folders:
            shutil.rmtree(stage, ignore_errors=True)
            for path in created:  # deepest first
                with contextlib.suppress(OSError):
                    os.rmdir(path)
        self.files.clear()
        self.folders.clear()
        self.after.clear()


_BATCHES: list[OutputBatch] = []
#: Hidden folders of :func:`meshcol.io.outputs.staged_folder` being filled: a file written
#: into one is in place at once (the folder is the unit that waits; a rebuilt MJCF is compiled
#: from it).
OPEN_STAGES: set[str] = set()


def active_batch() -> OutputBatch | None:
    """The batch of the run under way (the innermost :func:`staged_outputs`), or None."""
    return _BATCHES[-1] if _BATCHES else None


def batch_for(path: str) -> OutputBatch | None:
    """The batch a file written to ``path`` waits in: None outside a run, or inside a staged
    folder being filled."""
    batch = active_batch()
    if batch is None or os.path.dirname(os.path.abspath(path)) in OPEN_STAGES:
        return None
    return batch


def written_path(path: str) -> str:
    """Where an output of the run under way is now: its temporary file or its file in a staged
    folder while the run's outputs wait (a later step reads what an earlier one wrote, as
    ``decompose --to gltf-physics`` reads its parts), else ``path`` itself."""
    batch = active_batch()
    if batch is None:
        return path
    target = os.path.abspath(path)
    with batch.lock:
        for tmp, destination, _ in batch.files:
            if os.path.abspath(destination) == target:
                return tmp
        for stage, folder, _ in batch.folders:
            inside = os.path.relpath(target, os.path.abspath(folder))
            if not inside.startswith(os.pardir):
                staged = os.path.join(stage, inside)
                if os.path.exists(staged):
                    return staged
    return path


def commit_outputs() -> None:
    """Put the outputs written so far in place now (a command does it before its verdict, so
    that a verdict never precedes an output that failed); later ones are staged again."""
    batch = active_batch()
    if batch is not None:
        batch.commit()


def once_written(step: Callable[[], None]) -> None:
    """Run ``step`` once the run's outputs are in place (at once outside a run)."""
    batch = active_batch()
    if batch is None:
        step()
    else:
        batch.after.append(step)


@contextlib.contextmanager
def staged_outputs() -> Iterator[OutputBatch]:
    """Hold every output written in the block and commit them together at its end.

    The block ending normally, or by ``SystemExit`` (a command that decided its exit code
    after writing its outputs: exit 1 for a policy violation), commits; any other exception
    discards them all.
    """
    import click

    batch = OutputBatch()
    _BATCHES.append(batch)
    try:
        yield batch
    except (SystemExit, click.exceptions.Exit):
        _BATCHES.remove(batch)
        batch.commit()
        raise
    except BaseException:
        _BATCHES.remove(batch)
        batch.discard()
        raise
    _BATCHES.remove(batch)
    batch.commit()


def copy_into(tmp: str, path: str) -> None:
    """Copy the finished file ``tmp`` into the device or pipe ``path`` (never replaced), then
    remove ``tmp``; an error names ``path``."""
    try:
        with open(tmp, "rb") as source, open(path, "wb") as target:
            shutil.copyfileobj(source, target)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), path) from None
    os.unlink(tmp)


def move_staged(stage: str, folder: str) -> None:
    """Move the files of the hidden folder ``stage`` into ``folder`` and remove it."""
    for name in sorted(os.listdir(stage)):
        os.replace(os.path.join(stage, name), os.path.join(folder, name))
    os.rmdir(stage)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
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
