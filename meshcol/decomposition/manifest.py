"""The run manifest of ``meshcol decompose --run-manifest``: every file's state, as it goes.

A JSON file (``schemas/run_manifest.schema.json``) listing each input file with its state:
``pending``, ``done``, or ``failed`` (with the reason, and ``status`` ``failed`` or
``timeout``). It is rewritten atomically (:func:`meshcol.io.report.atomic_path`) when a file
finishes, at most every :data:`REWRITE_INTERVAL` seconds (a change that comes sooner is
written by a timer when the interval is up), and always when the run ends, however it ends
(an exception, Ctrl-C). The results themselves are
in the cache, stored before the manifest says ``done``: a driver killed outright loses at most
the last second of the manifest, never a finished file (the next run finds it in the cache).

``--resume`` reads the manifest back: files ``done`` are taken from the cache (no engine runs;
one whose entry has gone is decomposed again), files ``failed`` or ``pending`` run again. The
manifest keeps a fingerprint of the options that decide the decompositions (engine and its
parameters): resuming with other ones is an error, not a mixed run. The parts are written at
the end of each run, all together (as without a manifest), so the resumed run writes every
file's parts, to the output folder and in the layout and format it is given.
"""

from __future__ import annotations

import hashlib
import json
import os
import threading
import time
from collections.abc import Mapping
from typing import Any

from meshcol.errors import MeshcolError

__all__ = ["MANIFEST_FORMAT", "REWRITE_INTERVAL", "RunManifest", "fingerprint"]

#: Version of the manifest layout.
MANIFEST_FORMAT = 1
#: Seconds between two rewrites while files keep finishing (the last state is always written).
REWRITE_INTERVAL = 1.0


def fingerprint(settings: Mapping[str, Any]) -> str:
    """sha256 of the options that decide a run's results (JSON, keys sorted)."""
    return hashlib.sha256(json.dumps(dict(settings), sort_keys=True).encode()).hexdigest()


class RunManifest:
    """The states of a run's files, written to ``path`` as they change.

    Parameters
    ----------
    path : path
        The manifest file.
    settings : mapping
        The options that decide the results (their :func:`fingerprint` is kept).
    resume : bool
        Read ``path`` first (it must exist, with the same fingerprint); else start afresh.
    clock : callable
        Seconds (tests pass a fake clock).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        settings: Mapping[str, Any],
        *,
        resume: bool = False,
        clock: Any = time.monotonic,
    ) -> None:
        self.path = os.fspath(path)
        self.settings = dict(settings)
        self.fingerprint = fingerprint(settings)
        self.clock = clock
        self.files: dict[str, dict[str, Any]] = {}
        self.previous: dict[str, dict[str, Any]] = {}
        self._written_at: float | None = None
        self._dirty = False
        self._lock = threading.RLock()
        self._timer: threading.Timer | None = None
        if resume:
            self.previous = self._read()

    def _read(self) -> dict[str, dict[str, Any]]:
        try:
            with open(self.path, encoding="utf-8") as f:
                data = json.load(f)
        except FileNotFoundError:
            raise MeshcolError(
                "no run manifest to resume: run once without --resume first", self.path
            ) from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise MeshcolError(f"unreadable run manifest: {exc}", self.path) from None
        if (
            not isinstance(data, dict)
            or data.get("format") != MANIFEST_FORMAT
            or not isinstance(data.get("files"), list)
        ):
            raise MeshcolError("not a meshcol run manifest (format 1)", self.path)
        if data.get("fingerprint") != self.fingerprint:
            raise MeshcolError(
                "the run manifest was written by a run with another engine or other engine "
                "parameters: run without --resume, or with those options",
                self.path,
            )
        return {
            entry["path"]: entry
            for entry in data["files"]
            if isinstance(entry, dict) and isinstance(entry.get("path"), str)
        }

    def was_done(self, path: str) -> bool:
        """Whether a resumed manifest says ``path`` was done."""
        return self.previous.get(path, {}).get("state") == "done"

    def pending(self, path: str) -> None:
        """``path`` is part of the run (a resumed run keeps what it knew until it changes)."""
        with self._lock:
            if path not in self.files:
                before = self.previous.get(path)
                self.files[path] = dict(before) if before else {"path": path, "state": "pending"}
                self._dirty = True

    def finished(
        self, path: str, status: str, message: str | None = None, seconds: float = 0.0
    ) -> None:
        """Record an outcome (``ok``, ``failed``, ``timeout``) and rewrite when due."""
        entry: dict[str, Any] = {"path": path, "seconds": round(seconds, 3)}
        if status == "ok":
            entry["state"] = "done"
        else:
            entry.update(state="failed", status=status, reason=message)
        with self._lock:
            self.files[path] = entry
            self._dirty = True
            now = self.clock()
            if self._written_at is None or now - self._written_at >= REWRITE_INTERVAL:
                self.write()
            elif self._timer is None:
                self._timer = threading.Timer(
                    REWRITE_INTERVAL - (now - self._written_at), self._flush
                )
                self._timer.daemon = True
                self._timer.start()

    def _flush(self) -> None:
        with self._lock:
            self._timer = None
            try:
                self.write()
            except OSError:
                pass  # the next rewrite, or the last one, tries again (and reports)

    def counts(self) -> dict[str, int]:
        """Files by state."""
        counts = {"done": 0, "failed": 0, "pending": 0}
        for entry in self.files.values():
            counts[entry["state"]] = counts.get(entry["state"], 0) + 1
        return counts

    def write(self) -> None:
        """Rewrite the manifest now (atomically), if anything changed."""
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            if not self._dirty and self._written_at is not None:
                return
            self._write()

    def _write(self) -> None:
        from meshcol.io.report import atomic_path, dumps_json

        data = {
            "format": MANIFEST_FORMAT,
            "command": "decompose",
            "fingerprint": self.fingerprint,
            "settings": self.settings,
            "counts": self.counts(),
            "files": list(self.files.values()),
        }
        text = dumps_json(data)
        with atomic_path(self.path, staged=False) as tmp, open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        self._written_at = self.clock()
        self._dirty = False
