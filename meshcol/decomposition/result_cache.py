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
from meshcol.decomposition.cache import local_folder, read_bytes, write_bytes

__all__ = [
    "FORMAT_VERSION",
    "Digests",
    "load_index",
    "load_result",
    "load_text",
    "read_index",
    "result_key",
    "store_index",
    "store_result",
    "Summary",
]

#: The version of the entries' layout (and of what ci keeps of a report); a new one misses.
FORMAT_VERSION = 3  # 2: check suites carry body findings as cases; 3: bodies named by path
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
        self._prefix = os.path.normpath(os.path.abspath(self.folder)) + os.sep
        if self._prefix == os.sep * 2:
            self._prefix = os.sep
        self._known: dict[str, str] = {}
        self._stats: dict[str, list[Any]] = {}
        self._previous: Mapping[str, list[Any]] = stats or {}
        self._racy_ns = written_ns - int(RACY_SECONDS * 1e9)

    def __call__(self, path: str | os.PathLike[str]) -> str:
        if isinstance(path, str) and _plain(path):
            key = self._prefix + path  # what normpath would give, for 10,000 paths at once
        else:
            key = os.path.normpath(os.path.join(self._prefix, path))
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


def _plain(path: str) -> bool:
    """Whether ``path`` is relative and already normal (``props/a.obj``: no ``.``, ``..`` or
    empty part), so that joining it to a normal folder needs no ``normpath``; parts that start
    with a dot go the long way."""
    return (
        os.sep == "/"
        and path != ""
        and path[0] != "/"
        and path[-1] != "/"
        and "//" not in path
        and "/." not in "/" + path
    )


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
    text: str | None = None,
) -> None:
    """Store ``result`` (a JSON value) under ``key`` with the digests of the files it read
    (``path -> digest``); and ``text``, the report as its JSON file has it, when given
    (:func:`load_text`), first: an entry read is never one whose text is still to come."""
    if text is not None:
        write_bytes(_text_name(key), text.encode(), cache_dir)
    entry = {"key": key, "depends": dict(sorted(depends.items())), "result": result}
    data = json.dumps(entry, sort_keys=True, separators=(",", ":"), allow_nan=True).encode()
    write_bytes(_name(key), data, cache_dir)


def _text_name(key: str) -> str:
    return f"results/{key[:2]}/{key}.report.json"


def _read_local(path: str) -> bytes | None:
    """A local entry's bytes through the guarded read (:func:`meshcol.io.safe_read.
    read_input`: a regular file under the cap), None when it is absent or not one."""
    from meshcol.errors import MeshcolError
    from meshcol.io.safe_read import read_input

    try:
        return read_input(path, "mesh")
    except (OSError, MeshcolError):
        return None


def load_text(key: str, cache_dir: str | os.PathLike[str] | None = None) -> str | None:
    """The report text stored with the entry ``key`` (:func:`store_result`), None when
    there is none (an entry of an older build) or it is unreadable. A report of 10,000 cached
    jobs is these texts joined: nothing decoded, nothing encoded again. The caller has
    checked the entry (its index line or :func:`load_result`)."""
    local = local_folder(cache_dir) if cache_dir is not None else None
    if local is not None:
        data = _read_local(os.path.join(local, _text_name(key)))  # as read_bytes, no pathlib
    else:
        data = read_bytes(_text_name(key), cache_dir)
    if data is None:
        return None
    try:
        return data.decode("ascii")  # the report's JSON escapes every other character
    except UnicodeDecodeError:
        return None


# --- the run index: what a run needs of each entry, in one object -------------------------------

#: The version of the run index's layout (apart from the entries'): a file of another is no index.
INDEX_FORMAT = 3
_INDEX_MAGIC = b"meshcol-ci-index"


def _index_name(name: str) -> str:
    return f"results/index/{hashlib.sha256(name.encode()).hexdigest()[:32]}.idx"


class Summary(Mapping[str, Any]):
    """A result's summary as the run index keeps it: its exit code, and its JSON text, decoded
    the first time anything else of it is read (a warm run that writes no report reads only
    exit codes, so 10,000 summaries cost 10,000 strings, not 10,000 object trees). Its text
    is written back as it was read (:func:`store_index`): an unchanged job is never encoded
    again. Equal to the dict it decodes to."""

    __slots__ = ("_rules", "_value", "exit_code", "text")

    def __init__(self, exit_code: int, text: str, rules: Mapping[str, Any]) -> None:
        self.exit_code = exit_code
        self.text = text  # compact JSON; ``suite.rules``, if any, a reference into ``rules``
        self._rules = rules
        self._value: dict[str, Any] | None = None

    def value(self) -> dict[str, Any]:
        if self._value is None:
            value = json.loads(self.text)
            suite = value.get("suite")
            if isinstance(suite, dict) and isinstance(suite.get("rules"), str):
                suite["rules"] = self._rules.get(suite["rules"], {})
            self._value = value
        return self._value

    def __getitem__(self, key: str) -> Any:
        if key == "exit_code":
            return self.exit_code
        if key == "error" and self.exit_code != 2:
            raise KeyError(key)  # as __contains__: no decoding to learn it
        return self.value()[key]

    def __contains__(self, key: object) -> bool:
        if key == "exit_code":
            return True
        if key == "error" and self.exit_code != 2:
            return False  # a failed run's summary has its error; no other has one
        if key in ("report", "report_text", "pictures"):
            return False  # a summary is what a run keeps of a result but its report
        return key in self.value()

    def __iter__(self) -> Any:
        return iter(self.value())

    def __len__(self) -> int:
        return len(self.value())


def read_index(name: str, cache_dir: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """The index of the last run called ``name`` (a config file), as written by
    :func:`store_index`: ``format``, ``written_ns``, ``stats`` (``path -> [size, mtime_ns,
    ctime_ns, inode, device, digest]``), ``shared_rules`` and ``entries`` (``key ->
    {"summary": Summary, "depends": {path: digest}}``); empty when there is none or it is
    unreadable. One file instead of one per job, each job one line whose summary is decoded
    only when read (:class:`Summary`): a warm run of 10,000 jobs reads it in milliseconds."""
    data = read_bytes(_index_name(name), cache_dir)
    try:
        return _parse_index(data) if data is not None else {}
    except (ValueError, TypeError, IndexError, AttributeError):
        return {}


def _parse_index(data: bytes) -> dict[str, Any]:
    lines = data.split(b"\n")
    if len(lines) < 3 or lines[0] != b"%s %d" % (_INDEX_MAGIC, INDEX_FORMAT) or lines[-1]:
        return {}  # another layout, or cut short (the last line ends with a newline)
    header = json.loads(lines[1])
    if not isinstance(header, dict) or header.get("format") != FORMAT_VERSION:
        return {}
    rules = header["shared_rules"]
    stats = {row[0]: row[1:] for row in json.loads(lines[2])}
    entries: dict[str, Any] = {}
    for line in lines[3:-1]:
        key, code, depends, summary = line.decode().split("\t", 3)
        entries[key] = {
            "summary": Summary(int(code), summary, rules),
            "depends": {} if depends == "{}" else json.loads(depends),
        }
    return {
        "format": header["format"],
        "written_ns": int(header["written_ns"]),
        "stats": stats,
        "shared_rules": rules,
        "entries": entries,
    }


def _compact(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=True)


class _SharedRules:
    """Each summary's ``suite.rules`` (the registry's rules its suite names, help text and
    all: 12 kB, the same for nearly every job) as a reference to one copy, and the copies.
    An index of 10,000 jobs was 125 MB, all of it read by every warm run."""

    def __init__(self) -> None:
        self.copies: dict[str, Any] = {}
        self._by_object: dict[int, str] = {}
        self._read: dict[int, Mapping[str, Any]] = {}  # the copies of the indexes read

    def text(self, summary: Any) -> str:
        """The summary's line text (a :class:`Summary`'s own, whose reference stays)."""
        if isinstance(summary, Summary):
            self._read.setdefault(id(summary._rules), summary._rules)
            return summary.text
        suite = summary.get("suite") if isinstance(summary, dict) else None
        if not isinstance(suite, dict) or not isinstance(suite.get("rules"), dict):
            return _compact(summary)
        rules = suite["rules"]
        ref = self._by_object.get(id(rules))
        if ref is None:
            ref = hashlib.sha256(_compact(rules).encode()).hexdigest()[:32]
            self._by_object[id(rules)] = ref
            self.copies[ref] = rules
        return _compact({**summary, "suite": {**suite, "rules": ref}})

    def used(self, text: str) -> dict[str, Any]:
        """The copies ``text`` (every line) refers to: those of the new summaries, and of the
        indexes read those still referred to (one search per copy, not per line)."""
        used = dict(self.copies)
        for rules in self._read.values():
            for ref, table in rules.items():
                if ref not in used and f'"rules":"{ref}"' in text:
                    used[ref] = table
        return used


def load_index(index: Mapping[str, Any], digests: Digests) -> dict[str, Any]:
    """``key -> summary`` of each entry of ``index`` whose files still have their digests
    (the summary: what a run keeps of a result but its report)."""
    return {
        key: entry["summary"]
        for key, entry in index.get("entries", {}).items()
        if not entry["depends"]
        or all(digests(path) == digest for path, digest in entry["depends"].items())
    }


def store_index(
    name: str,
    entries: Mapping[str, tuple[Any, Mapping[str, str]]],
    stats: Mapping[str, list[Any]],
    cache_dir: str | os.PathLike[str] | None = None,
) -> None:
    """Write the index of a run: ``key -> (summary, depends)`` of every job it has a result
    for (it replaces the last one; two runs at once: the last write wins, and a job missing
    from it is only looked up entry by entry). A summary is a dict, or the :class:`Summary`
    read from the last index, whose text is written as it is."""
    shared = _SharedRules()
    lines = [
        "\t".join(
            (
                key,
                str(int(summary["exit_code"])),
                _compact(dict(depends)) if depends else "{}",
                shared.text(summary),
            )
        )
        for key, (summary, depends) in entries.items()
    ]
    body = "\n".join([*lines, ""])
    header = {
        "format": FORMAT_VERSION,
        "written_ns": time.time_ns(),
        "shared_rules": shared.used(body),
    }
    rows = [[path, *row] for path, row in stats.items()]
    text = "\n".join([_compact(header), _compact(rows), body])
    data = b"%s %d\n" % (_INDEX_MAGIC, INDEX_FORMAT) + text.encode()
    write_bytes(_index_name(name), data, cache_dir)
