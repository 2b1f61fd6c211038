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
from collections.abc import Mapping
from typing import Any

from meshcol._version import __version__
from meshcol.decomposition.cache import read_bytes, write_bytes

__all__ = ["FORMAT_VERSION", "Digests", "load_result", "result_key", "store_result"]

#: The version of the entries' layout (and of what ci keeps of a report); a new one misses.
FORMAT_VERSION = 1
_CHUNK = 1 << 20


class Digests:
    """Content digests (SHA-256) of files, each file read once per run; a missing or
    unreadable file's digest is ``missing``. Relative paths are from ``folder``."""

    def __init__(self, folder: str | os.PathLike[str] = ".") -> None:
        self.folder = os.fspath(folder)
        self._known: dict[str, str] = {}

    def __call__(self, path: str | os.PathLike[str]) -> str:
        key = os.path.realpath(os.path.join(self.folder, path))
        digest = self._known.get(key)
        if digest is None:
            digest = self._known[key] = _digest(key)
        return digest


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
