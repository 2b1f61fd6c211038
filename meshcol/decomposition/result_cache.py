"""The result cache of ``meshcol ci``: what inspect, hull, fit and check reported for a file.

An entry is keyed by the command, its settings, meshcol's version and the content of the
file (:func:`result_key`); it holds the command's result (its JSON report and CI suite, a
JSON value) and the content digest of every other file the run read (a manifest's meshes,
a URDF's meshes, a glTF's buffers, a baseline, a target profile). A lookup is a hit only
when each of those files still has its digest, so a changed mesh recomputes every scene it
is in and nothing else.

Entries are ``results/<key[:2]>/<key>.json`` in the store of the decompose cache
(:mod:`meshcol.decomposition.cache`: a folder or an fsspec URL, atomic writes); an unreadable
entry, or one naming another key, is a miss.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Mapping
from typing import Any

from meshcol._version import __version__
from meshcol.decomposition.cache import read_bytes, write_bytes

__all__ = [
    "FORMAT_VERSION",
    "Digests",
    "load_index",
    "load_result",
    "read_index",
    "result_key",
    "store_index",
    "store_result",
]

#: The version of the entries' layout (and of what ci keeps of a report); a new one misses.
FORMAT_VERSION = 2  # 2: check suites carry body findings as cases
#: Seconds before an index was written within which a file's stat is not trusted.
RACY_SECONDS = 2.0
_CHUNK = 1 << 20


class Digests:
    """Content digests (SHA-256) of files, each file read once per run; a missing or
    unreadable file's digest is ``missing``. Relative paths are from ``folder``.

    ``stats`` (from the last run's index, :meth:`stats`) lets a file whose size, times,
    inode and device are those it had then keep its digest unread, as git's index does; a
    file changed less than :data:`RACY_SECONDS` before that index was written is read
    again (its time may not show a second change within the clock's step)."""

    def __init__(
        self,
        folder: str | os.PathLike[str] = ".",
        stats: Mapping[str, list[Any]] | None = None,
        written_ns: int = 0,
    ) -> None:
        self.folder = os.fspath(folder)
        self._known: dict[str, str] = {}
        self._stats: dict[str, list[Any]] = {}
        self._previous = dict(stats or {})
        self._racy_ns = written_ns - int(RACY_SECONDS * 1e9)

    def __call__(self, path: str | os.PathLike[str]) -> str:
        key = os.path.normpath(os.path.join(self.folder, path))
        digest = self._known.get(key)
        if digest is None:
            digest = self._known[key] = self._digest(key)
        return digest

    def _digest(self, path: str) -> str:
        try:
            st = os.stat(path)
        except OSError:
            return "missing"
        signature = [st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev]
        before = self._previous.get(path)
        if before is not None and before[:5] == signature and st.st_mtime_ns < self._racy_ns:
            digest: str = before[5]
        else:
            digest = _digest(path)
        self._stats[path] = [*signature, digest]
        return digest

    def stats(self) -> dict[str, list[Any]]:
        """``path -> [size, mtime_ns, ctime_ns, inode, device, digest]`` of every file
        digested so far (for the next run's index)."""
        return dict(self._stats)


def _digest(path: str) -> str:
    hasher = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            while chunk := f.read(_CHUNK):
                hasher.update(chunk)
    except OSError:
        return "missing"
    return hasher.hexdigest()


def result_key(command: str, settings: Mapping[str, Any], content: str) -> str:
    """The entry's key: SHA-256 of the command, its settings (canonical JSON), the file's
    content digest, meshcol's version and :data:`FORMAT_VERSION`."""
    text = json.dumps(
        {
            "command": command,
            "settings": settings,
            "content": content,
            "meshcol": __version__,
            "format": FORMAT_VERSION,
        },
        sort_keys=True,
        separators=(",", ":"),
        default=str,
    )
    return hashlib.sha256(text.encode()).hexdigest()


def _name(key: str) -> str:
    return f"results/{key[:2]}/{key}.json"


def load_result(
    key: str, digests: Digests, cache_dir: str | os.PathLike[str] | None = None
) -> Any | None:
    """The result stored under ``key`` when every file it read still has its digest;
    else None (absent, unreadable, another key's, or a dependency changed)."""
    data = read_bytes(_name(key), cache_dir)
    if data is None:
        return None
    try:
        entry = json.loads(data)
    except ValueError:
        return None
    if not isinstance(entry, dict) or entry.get("key") != key:
        return None
    depends = entry.get("depends", {})
    if any(digests(path) != digest for path, digest in depends.items()):
        return None
    return entry.get("result")


def store_result(
    key: str,
    result: Any,
    depends: Mapping[str, str],
    cache_dir: str | os.PathLike[str] | None = None,
) -> None:
    """Store ``result`` (a JSON value) under ``key`` with the digests of the files it read
    (``path -> digest``)."""
    entry = {"key": key, "depends": dict(sorted(depends.items())), "result": result}
    data = json.dumps(entry, sort_keys=True, separators=(",", ":"), allow_nan=True).encode()
    write_bytes(_name(key), data, cache_dir)


# --- the run index: what a run needs of each entry, in one object -------------------------------


def _index_name(name: str) -> str:
    return f"results/index/{hashlib.sha256(name.encode()).hexdigest()[:32]}.json"


def read_index(name: str, cache_dir: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """The index of the last run called ``name`` (a config file), as written by
    :func:`store_index`; empty when there is none or it is unreadable. One object instead
    of one per job: a warm run of 10,000 jobs reads it once."""
    data = read_bytes(_index_name(name), cache_dir)
    try:
        index = json.loads(data) if data is not None else {}
    except ValueError:
        return {}
    if not isinstance(index, dict) or index.get("format") != FORMAT_VERSION:
        return {}
    shared = index.get("shared_rules", {})
    for entry in index.get("entries", {}).values():
        suite = entry.get("summary", {}).get("suite")
        if isinstance(suite, dict) and isinstance(suite.get("rules"), str):
            suite["rules"] = shared.get(suite["rules"], {})
    return index


def _shared_rules(entries: dict[str, Any]) -> dict[str, Any]:
    """Each entry's ``suite.rules`` (the registry's rules its suite names, help text and all:
    12 kB, the same for nearly every job) replaced by a reference to one copy; the copies.
    An index of 10,000 jobs was 125 MB, all of it read by every warm run."""
    shared: dict[str, Any] = {}
    by_object: dict[int, str] = {}
    for entry in entries.values():
        suite = entry["summary"].get("suite") if isinstance(entry["summary"], dict) else None
        if not isinstance(suite, dict) or not isinstance(suite.get("rules"), dict):
            continue
        rules = suite["rules"]
        ref = by_object.get(id(rules))
        if ref is None:
            text = json.dumps(rules, sort_keys=True, separators=(",", ":"), allow_nan=True)
            ref = by_object[id(rules)] = hashlib.sha256(text.encode()).hexdigest()[:32]
            shared[ref] = rules
        entry["summary"] = {**entry["summary"], "suite": {**suite, "rules": ref}}
    return shared


def load_index(index: Mapping[str, Any], digests: Digests) -> dict[str, Any]:
    """``key -> summary`` of each entry of ``index`` whose files still have their digests
    (the summary: what a run keeps of a result but its report)."""
    return {
        key: entry["summary"]
        for key, entry in index.get("entries", {}).items()
        if all(digests(path) == digest for path, digest in entry["depends"].items())
    }


def store_index(
    name: str,
    entries: Mapping[str, tuple[Any, Mapping[str, str]]],
    stats: Mapping[str, list[Any]],
    cache_dir: str | os.PathLike[str] | None = None,
) -> None:
    """Write the index of a run: ``key -> (summary, depends)`` of every job it has a result
    for (it replaces the last one; two runs at once: the last write wins, and a job missing
    from it is only looked up entry by entry)."""
    listed = {
        key: {"summary": summary, "depends": dict(depends)}
        for key, (summary, depends) in entries.items()
    }
    index = {
        "format": FORMAT_VERSION,
        "written_ns": time.time_ns(),
        "stats": dict(stats),
        "shared_rules": _shared_rules(listed),
        "entries": listed,
    }
    data = json.dumps(index, sort_keys=True, separators=(",", ":"), allow_nan=True).encode()
    write_bytes(_index_name(name), data, cache_dir)
