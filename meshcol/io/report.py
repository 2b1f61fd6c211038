"""Writing reports and output files safely.

Every output goes to a temporary file in the destination folder and is renamed into place, so
an interrupted or failed run never leaves a half-written file behind.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import re
import stat
import sys
import tempfile
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from meshcol.errors import InputFileError
from meshcol.io.staging import batch_for, copy_into

__all__ = [
    "ENVELOPE_KEYS",
    "SCHEMA_VERSION",
    "atomic_path",
    "atomic_write",
    "is_special_file",
    "dumps_csv",
    "dumps_json",
    "dumps_rows",
    "document_pieces",
    "emit",
    "round_significant",
    "rows_chunks",
    "RowsPiece",
    "text_pieces",
    "envelope",
    "split_vectors",
    "vector_columns",
]

#: Version of the report layout shared by every command's JSON report (see
#: ``meshcol/schemas/*_report.schema.json``); raised when a field changes meaning or goes.
SCHEMA_VERSION = 1
#: The keys every report starts with, in the order :func:`envelope` gives them.
ENVELOPE_KEYS = ("schema_version", "tool", "command", "settings", "units")


def envelope(command: str, settings: Mapping[str, Any], units: str | None) -> dict[str, Any]:
    """The fields every JSON report starts with: one header for all five commands.

    Parameters
    ----------
    command : str
        ``check``, ``sweep``, ``decompose``, ``hull`` or ``inspect``; picks the report's schema
        (``meshcol/schemas/<command>_report.schema.json``).
    settings : mapping
        The options of the run, JSON-ready.
    units : str or None
        Length unit of every coordinate in the report (the scene manifest's, verbatim), None
        when the input does not say.

    Returns
    -------
    dict
        ``schema_version``, ``tool`` (``name``, ``version``), ``command``, ``settings``,
        ``units``: a new dict the caller extends with the command's own fields.
    """
    from meshcol._version import __version__

    return {
        "schema_version": SCHEMA_VERSION,
        "tool": {"name": "meshcol", "version": __version__},
        "command": command,
        "settings": dict(settings),
        "units": units,
    }


@contextlib.contextmanager
def atomic_path(
    path: str | os.PathLike[str], suffix: str | None = None, *, staged: bool = True
) -> Iterator[str]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` if the block succeeds.

    Inside a run's :func:`meshcol.io.staging.staged_outputs` (``staged``, the default) the
    finished file waits for the run's end and goes in place with every other output of the
    run, or not at all; ``staged=False`` puts it in place at once (the decomposition cache, the
    run manifest).

    The temporary file keeps ``path``'s extension (or ``suffix``) so writers that pick a format
    from the name still work. On any exception the temporary file is removed. A destination
    that exists and is not a regular file (``/dev/null``, a named pipe, a terminal) is never
    replaced: the finished file is copied into it instead, so ``--report /dev/null`` discards
    the report and leaves the device alone.
    """
    path = os.fspath(path)
    special = is_special_file(path)
    folder = tempfile.gettempdir() if special else os.path.dirname(os.path.abspath(path))
    ext = suffix if suffix is not None else os.path.splitext(path)[1]
    try:
        fd, tmp = tempfile.mkstemp(prefix=".meshcol-", suffix=ext, dir=folder)
    except OSError as exc:
        raise _as_user_path(exc, path) from None
    os.close(fd)
    # mkstemp creates the file 0600; give the result the mode a plain open() would.
    os.chmod(tmp, 0o666 & ~_umask())
    try:
        yield tmp
        batch = batch_for(path) if staged else None
        if batch is not None:
            batch.add_file(tmp, path, special)
        elif special:
            copy_into(tmp, path)
        else:
            os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and tmp in (exc.filename, exc.filename2):
            # the temporary name means nothing to the user: name the file they asked for
            raise _as_user_path(exc, path) from None
        raise


def is_special_file(path: str) -> bool:
    """An existing destination that is neither a regular file nor a folder (a device such as
    ``/dev/null``, a named pipe): written into, never replaced."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)


def _as_user_path(exc: OSError, path: str) -> OSError:
    """The same error, naming ``path`` (a destination the user typed) as its file."""
    strerror = exc.strerror or str(exc)
    if os.path.isdir(path):
        strerror = "is a directory"
    elif not os.path.isdir(os.path.dirname(os.path.abspath(path))):
        strerror = "cannot write: the folder does not exist"
    return OSError(exc.errno, strerror, path)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path: str | os.PathLike[str], data: str | bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    with atomic_path(path) as tmp:
        if isinstance(data, bytes):
            with open(tmp, "wb") as binary:
                binary.write(data)
        else:
            with open(tmp, "w", encoding="utf-8", newline="") as text:
                text.write(data)


# A bare NaN/Infinity token in two-space-indented JSON: alone on its line (an array item) or
# after '": ' at the end of its line (a field). A string cannot hold a raw newline, so neither
# form can occur inside one.
_NON_FINITE_TOKEN = re.compile(r'^( *|.*": )-?(?:NaN|Infinity)(,?)$', re.MULTILINE)


def _builtin(value: Any) -> Any:
    """What json cannot encode itself: numpy arrays and scalars, other mappings."""
    if isinstance(value, Mapping):
        return dict(value)
    if hasattr(value, "tolist"):
        return value.tolist()
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def read_json_file(path: str | os.PathLike[str], name: str, short: str | None = None) -> Any:
    """The parsed JSON document of a file the user named, or one line saying what is wrong.

    Parameters
    ----------
    path : str or path-like
    name : str
        What the file is, for messages: ``"baseline report"``, ``"joints file"``.
    short : str, optional
        The shorter name for content errors (``"baseline"``); ``name`` when omitted.

    Raises
    ------
    InputFileError
        Missing, unreadable, not UTF-8, not JSON (with line and column), or nested deeper than
        the decoder recurses.
    """
    from meshcol.io.safe_read import read_input

    short = short or name
    if not os.path.lexists(path):
        raise InputFileError(f"{name} not found", path)
    data = read_input(path, "json")  # a regular file within the cap: never a pipe or device
    try:
        return json.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise InputFileError(f"cannot read {name}: {exc}", path) from None
    except json.JSONDecodeError as exc:
        raise InputFileError(
            f"{short} is not valid JSON (line {exc.lineno} column {exc.colno})", path
        ) from None
    except RecursionError:
        raise InputFileError(f"{short} nests arrays and objects too deep", path) from None
    except ValueError as exc:  # an integer of thousands of digits
        raise InputFileError(
            f"{short} has a number too long to read ({str(exc).splitlines()[0][:120]})", path
        ) from None


def dumps_json(
    obj: Any,
    *,
    compact: bool = False,
    sort_keys: bool = True,
    ascii_only: bool = True,
    non_finite: str = "null",
) -> str:
    """The JSON text of ``obj``: the one JSON encoder of meshcol's outputs.

    Parameters
    ----------
    obj : JSON-ready value
        Dicts, lists, tuples, strings, numbers, None; numpy arrays and scalars and other
        mappings are converted (``tolist``, ``item``, ``dict``).
    compact : bool
        False (a report): two-space indent and a trailing newline. True (a value inside
        another format: a JUnit property, a review page's data): one line, ``,`` and ``:``
        without spaces, no newline.
    sort_keys : bool
        Keys sorted (every report: deterministic text); False keeps each mapping's order.
    ascii_only : bool
        Characters past ASCII as ``\\uXXXX`` escapes (True) or as they are.
    non_finite : {"null", "error"}
        NaN and infinities (which JSON has not) written as null, or refused (ValueError).

    Returns
    -------
    str

    Notes
    -----
    A report (the defaults) is exactly ``json.dumps(obj, sort_keys=True, indent=2)`` of the
    report with every non-finite number made null and numpy values made Python ones
    (``tests/test_report_json.py`` holds it to that), written faster: Python's C encoder
    cannot indent, and its indenting encoder costs about a microsecond per value, most of the
    time of writing a report of 10,000 pairs. So rows of one shape (a list of dicts with the
    same keys, the pairs and bodies of a report) are encoded column by column: every number
    of a column by the C encoder in one call, every string by the C string escape, then one
    format string per row. Keys must be strings (anything else is encoded by ``json``
    itself, as before).

    The core's encoder (``dumps_indented``: the same walk in C++, numbers by
    ``std::to_chars`` laid out as ``repr(float)``) writes a report when it can; it declines
    the rare documents it does not write exactly as ``json`` does (a key that is not a
    string, an int past 64 bits, a dict subclass, a string that is not UTF-8, deep nesting,
    an object ``json`` cannot encode), which take the Python path.

    Any other choice of options is ``json.dumps`` with them (non-finite numbers made null
    first, when so asked).
    """
    if non_finite not in ("null", "error"):
        raise ValueError(f"non_finite must be 'null' or 'error', got {non_finite!r}")
    if not compact and sort_keys and ascii_only and non_finite == "null":
        from meshcol._native import core

        native = core.dumps_indented(obj, _builtin)
        if native is not None:
            return str(native)
        return _dumps_json_python(obj)
    text = json.dumps(
        _nulled(obj) if non_finite == "null" else obj,
        indent=None if compact else 2,
        separators=(",", ":") if compact else None,
        sort_keys=sort_keys,
        ensure_ascii=ascii_only,
        allow_nan=False,
        default=_builtin,
    )
    return text if compact else text + "\n"


def dumps_rows(columns: list[tuple], count: int, level: int) -> str:
    """The JSON text of a list of ``count`` dicts of one set of keys held as columns, as
    :func:`dumps_json` writes it as a value at nesting ``level`` (a report's ``pairs``: 1):
    :func:`rows_chunks` joined."""
    return "".join(rows_chunks(columns, count, level))


def rows_chunks(columns: list[tuple], count: int, level: int) -> Iterator[str]:
    """:func:`dumps_rows`'s text in pieces of a bounded number of rows each, written from the
    columns by the core's row writer (``dumps_rows``: ``columns`` are its ``(key, kind,
    array[, table])`` in key order)."""
    if not count:
        yield "[]"
        return
    from meshcol._native import core

    yield "["
    for start in range(0, count, _ROWS_PER_CALL):
        stop = min(start + _ROWS_PER_CALL, count)
        if start:
            yield ","  # the core writes a list's first row without one
        window = [_column_window(column, start, stop) for column in columns]
        yield core.dumps_rows(window, stop - start, 0, stop - start, level)
    yield "\n" + "  " * level + "]"


#: Rows :func:`dumps_rows` has written per native call: a few megabytes of text, so that the
#: memory of one call's text is reused by the next (not mapped anew for each).
_ROWS_PER_CALL = 1 << 13


def _column_window(column: tuple, start: int, stop: int) -> tuple:
    """A column of the core's row writer cut to the rows ``start:stop``; a string column's
    table cut to the entries those rows use (the core escapes its whole table every call: the
    names of 1,000,000 bodies, for a window of a few thousand rows)."""
    key, kind, array, *rest = column
    part = array[start:stop]
    if not rest:
        return key, kind, part
    (table,) = rest
    if len(table) <= 2 * len(part):
        return key, kind, part, table
    import numpy as np

    used, codes = np.unique(part, return_inverse=True)
    if len(used) and used[0] < 0:  # -1 (null) stays -1
        used, codes = used[1:], codes - 1
    return key, kind, codes.astype(np.int64), [table[u] for u in used.tolist()]


def _nulled(value: Any) -> Any:
    """``value`` with every non-finite float (numpy's too) made None and numpy values made
    Python ones; keys and everything else as they are (``json`` encodes them)."""
    if isinstance(value, (str, int, type(None))):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _nulled(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_nulled(v) for v in value]
    if isinstance(value, Mapping) or hasattr(value, "tolist") or hasattr(value, "item"):
        return _nulled(_builtin(value))
    return value


def _dumps_json_python(obj: Any) -> str:
    """:func:`dumps_json` without the core: the column encoder, else ``json`` itself."""
    try:
        text = _value(obj, 0)
    except _Unusual:
        text = json.dumps(obj, sort_keys=True, indent=2, allow_nan=True, default=_builtin)
        if "NaN" in text or "Infinity" in text:
            text = _NON_FINITE_TOKEN.sub(r"\1null\2", text)
    return text + "\n"


class _Unusual(Exception):
    """A document the column encoder leaves to ``json`` (a key that is not a string)."""


#: Types whose JSON text the C encoder writes without quotes or commas.
_PLAIN = frozenset({type(None), bool, int, float})
#: Compact JSON of a list of plain values (the C encoder when Python has it).
_compact = json.JSONEncoder(allow_nan=True, check_circular=False, separators=(",", ":")).encode
_escape = json.encoder.encode_basestring_ascii
_NON_FINITE = frozenset({"NaN", "Infinity", "-Infinity"})


def _indent(level: int) -> str:
    return "\n" + "  " * level


def _value(o: Any, level: int) -> str:
    """The JSON text of ``o`` as ``json.dumps(indent=2)`` writes it at nesting ``level``
    (the same checks in the same order as ``json``'s encoder)."""
    if isinstance(o, str):
        return _escape(o)
    if o is None:
        return "null"
    if o is True:
        return "true"
    if o is False:
        return "false"
    if isinstance(o, int):
        return int.__repr__(o)
    if isinstance(o, float):
        return float.__repr__(o) if math.isfinite(o) else "null"
    if isinstance(o, (list, tuple)):
        if not o:
            return "[]"
        inner = _indent(level + 1)
        return "[" + inner + ("," + inner).join(_column(list(o), level + 1)) + _indent(level) + "]"
    if isinstance(o, dict):
        if not o:
            return "{}"
        if not all(isinstance(k, str) for k in o):
            raise _Unusual
        inner = _indent(level + 1)
        items = (_escape(k) + ": " + _value(v, level + 1) for k, v in sorted(o.items()))
        return "{" + inner + ("," + inner).join(items) + _indent(level) + "}"
    return _value(_builtin(o), level)


def _column(values: list, level: int) -> list[str]:
    """The JSON text of each of ``values``, each written at nesting ``level``: in bulk for
    plain numbers, strings, lists (their items as one column) and dicts of one set of keys
    (each key's values as one column); value by value otherwise."""
    types = set(map(type, values))
    if types <= _PLAIN:
        text = _compact(values)[1:-1]
        tokens = text.split(",")
        if "N" in text or "I" in text:  # NaN, Infinity, -Infinity: JSON has none of them
            tokens = ["null" if t in _NON_FINITE else t for t in tokens]
        return tokens
    if types == {str}:
        return list(map(_escape, values))
    if types <= {list, tuple, type(None)}:
        return _lists(values, level, type(None) in types)
    if types == {dict}:
        rows = _rows(values, level)
        if rows is not None:
            return rows
    return [_value(v, level) for v in values]


def _lists(values: list, level: int, with_none: bool) -> list[str]:
    """:func:`_column` of lists (and None): all their items encoded as one column."""
    lists = [v for v in values if v is not None] if with_none else values
    lengths = list(map(len, lists))
    items = _column([x for v in lists for x in v], level + 1)
    inner, close = _indent(level + 1), _indent(level) + "]"
    width = lengths[0] if lengths else 0
    if lengths.count(width) == len(lengths):
        if width == 0:
            out = ["[]"] * len(lists)
        else:
            template = "[" + inner + ("," + inner).join(["%s"] * width) + close
            out = [template % group for group in zip(*[iter(items)] * width)]
    else:
        out, start = [], 0
        for length in lengths:
            stop = start + length
            out.append(
                "[" + inner + ("," + inner).join(items[start:stop]) + close if length else "[]"
            )
            start = stop
    if not with_none:
        return out
    encoded = iter(out)
    return ["null" if v is None else next(encoded) for v in values]


def _rows(values: list[dict], level: int) -> list[str] | None:
    """:func:`_column` of dicts with one set of keys, or None when their keys differ."""
    keys = values[0].keys()
    if not keys or not all(v.keys() == keys for v in values):
        return None
    if not all(isinstance(k, str) for k in keys):
        raise _Unusual
    names = sorted(keys)
    columns = [_column([v[name] for v in values], level + 1) for name in names]
    inner = _indent(level + 1)
    fields = ("," + inner).join(_escape(name).replace("%", "%%") + ": %s" for name in names)
    template = "{" + inner + fields + _indent(level) + "}"
    return [template % row for row in zip(*columns)]


#: Column suffixes of a vector or matrix split over several CSV columns, by its length.
_SUFFIXES = {
    3: ("x", "y", "z"),
    16: tuple(f"{row}{column}" for row in range(4) for column in range(4)),
}


def vector_columns(name: str, size: int = 3) -> list[str]:
    """The CSV columns of a vector (``point_x``, ``point_y``, ``point_z``) or of a 4x4 pose,
    row-major (``pose_a_00`` ... ``pose_a_33``): the one CSV convention of every command."""
    return [f"{name}_{suffix}" for suffix in _SUFFIXES[size]]


def split_vectors(row: Mapping[str, Any], sizes: Mapping[str, int]) -> dict[str, Any]:
    """``row`` with each vector or matrix field of ``sizes`` spread over
    :func:`vector_columns` (a missing or None value gives empty cells)."""
    flat = dict(row)
    for name, size in sizes.items():
        value = flat.pop(name, None)
        if value is not None and size == 16:
            value = [x for line in value for x in line]
        values = [None] * size if value is None else list(value)
        flat.update(zip(vector_columns(name, size), values))
    return flat


def dumps_csv(rows: Sequence[Mapping[str, Any]], columns: Sequence[str]) -> str:
    """CSV text with a header row; one number per cell (vectors are split by
    :func:`split_vectors`), lists of names space-separated, None an empty cell."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        cells = []
        for c in columns:
            v = _nulled(row.get(c))
            if v is None:
                cells.append("")
            elif isinstance(v, list):
                cells.append(" ".join(repr(x) if isinstance(x, float) else str(x) for x in v))
            elif isinstance(v, float):
                cells.append(repr(v))
            else:
                cells.append(str(v))
        writer.writerow(cells)
    return buf.getvalue()


@dataclass(frozen=True)
class RowsPiece:
    """A list of rows held as columns, as one piece of a report's text (what a report's
    ``json_pieces`` yields between its strings): :func:`emit` has the core write it straight
    into the file (:meth:`write_into`); anywhere else it is its text, in bounded pieces
    (:meth:`chunks`). Either way the bytes of :func:`dumps_rows`.

    Attributes
    ----------
    columns : list of tuple
        The core's row writer's ``(key, kind, array[, table])``, in key order.
    count : int
        The number of rows.
    level : int
        The list's nesting in the document (a report's ``pairs``: 1).
    """

    columns: list[tuple]
    count: int
    level: int

    def chunks(self) -> Iterator[str]:
        """The text, a bounded number of rows a piece (:func:`rows_chunks`)."""
        return rows_chunks(self.columns, self.count, self.level)

    def write_into(self, fd: int) -> None:
        """Write the text to the open file ``fd`` at its offset: the rows are formatted on the
        core's threads and written a few megabytes at a time, with no Python string made."""
        from meshcol._native import core

        core.write_rows(fd, self.columns, self.count, self.level)


def document_pieces(document: dict[str, Any], streamed: Sequence[str]) -> Iterator[str | RowsPiece]:
    """A report's JSON (:func:`dumps_json` of ``document``) in pieces, in order: the text of
    the rest, and the value of each top-level key of ``streamed`` (rows kept as columns: an
    object with ``columns()`` for the core's row writer and a length) as a
    :class:`RowsPiece` between, which a file gets straight from the core's row writer
    (:func:`emit`); the same bytes as the whole document encoded at once."""
    document = dict(document)
    markers = {}
    for key in streamed:
        rows = document[key]
        document[key] = marker = f"\x00meshcol rows: {key}\x00"
        markers[f'\n  "{key}": {dumps_json(marker)[:-1]},'] = (key, rows)
    text = dumps_json(document)
    start = 0
    for line, (key, rows) in sorted(markers.items(), key=lambda item: text.find(item[0])):
        at = text.find(line, start)
        if at < 0:  # cannot happen: a top-level key's line is unique
            raise AssertionError(f"report text lost its {key}")
        yield text[start:at] + f'\n  "{key}": '
        yield RowsPiece(rows.columns(), len(rows), 1)
        yield ","
        start = at + len(line)
    yield text[start:]


def round_significant(values: Any, digits: int = 12) -> Any:
    """``float(f"{v:.{digits}g}") + 0.0`` of every number of ``values`` (an array of any
    shape, as float64; non-finite values as they are, -0.0 as 0.0), by the core in one call:
    the rounding of the numbers a report compares across machines (a sweep's 12 digits)."""
    import numpy as np

    from meshcol._native import core

    array = np.asarray(values, dtype=np.float64)
    flat = np.ascontiguousarray(array.reshape(-1))
    return np.asarray(core.round_significant(flat, digits)).reshape(array.shape)


def text_pieces(pieces: Iterable[str | RowsPiece]) -> Iterator[str]:
    """``pieces`` as text only: each :class:`RowsPiece` as its chunks."""
    for piece in pieces:
        if isinstance(piece, str):
            yield piece
        else:
            yield from piece.chunks()


def emit(text: str | Iterable[str | RowsPiece], output: str | os.PathLike[str] | None) -> None:
    """Write report text (or its pieces, in order: to a file never joined whole; a
    :class:`RowsPiece` written by the core) to ``output`` atomically, or to stdout when
    ``output`` is None or '-'."""
    pieces = [text] if isinstance(text, str) else text
    if output is None or os.fspath(output) == "-":
        # made whole first: a failure while making it leaves nothing on stdout
        sys.stdout.write(text if isinstance(text, str) else "".join(text_pieces(pieces)))
        sys.stdout.flush()
        return
    with atomic_path(output) as tmp:
        fd = os.open(tmp, os.O_WRONLY | os.O_TRUNC | getattr(os, "O_BINARY", 0))
        try:
            for piece in pieces:
                if isinstance(piece, str):
                    _write_all(fd, piece.encode("utf-8"))
                else:
                    piece.write_into(fd)
        except OSError as exc:
            if exc.filename is None:  # named as the temporary file: atomic_path names output
                raise OSError(exc.errno, exc.strerror or str(exc), tmp) from None
            raise
        finally:
            os.close(fd)


def _write_all(fd: int, data: bytes) -> None:
    """``os.write`` until all of ``data`` is written (a write may take only part of it)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]
