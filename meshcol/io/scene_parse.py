"""Reading a scene manifest's text: the file checked, JSON or TOML decoded, nesting bounded.

What comes out is the document as the decoder made it (dicts, lists, strings, numbers), not
yet validated (:mod:`meshcol.io.scene_validate` does that). Every problem is one
:class:`meshcol.errors.InputFileError` (the file) or :class:`meshcol.errors.SceneError` (its
text) naming the manifest.
"""

from __future__ import annotations

import contextlib
import gc
import json
import math
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from meshcol.errors import InputFileError, SceneError
from meshcol.io.inputs import is_manifest
from meshcol.io.safe_read import check_input, read_input

__all__ = [
    "KEPT_OF_DOCUMENTS",
    "MAX_NESTING",
    "children",
    "collector_paused",
    "first_non_finite",
    "forget_documents",
    "nesting",
    "read_document",
    "too_deep",
]

#: Deepest nesting of arrays and objects a manifest may have (a real one has four levels).
MAX_NESTING = 32


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector off for the block (back on after, if it was on).

    Decoding and loading a manifest make millions of objects and free none: each collection
    the allocations trigger walks them all for nothing (a 300,000-body manifest decoded in
    3.5 s with it, 1.2-2.1 s without). What they make has no cycles; reference counting frees
    it as before. ``check`` pauses it the same way while it packs colliders and builds its
    report rows (hundreds of thousands of dicts and lists at 100,000 bodies).
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def read_document(source: str) -> tuple[Any, str]:
    """The decoded document of the manifest ``source`` and its text.

    The last manifest read is kept (by absolute path and bytes): a run reads its manifest
    twice (the output check, then the loading) and decodes it once.

    Raises
    ------
    InputFileError
        Missing, a directory, not ``.json``/``.toml``, unreadable.
    SceneError
        Not UTF-8, or invalid JSON or TOML (the line and column in the message).
    """
    file = Path(source)
    _check_manifest_file(file, source)
    data = read_input(source, "manifest")
    key = os.path.abspath(source)
    cached = _READ.get(key)
    if cached is not None and cached[0] == data:
        return cached[1], cached[2]  # the same bytes decoded a moment ago
    try:
        text = data.decode("utf-8-sig")  # a byte-order mark, as some editors write, is dropped
    except UnicodeDecodeError:
        raise SceneError("manifest is not UTF-8 text", source) from None
    with collector_paused():
        document = _decode(file, text, source)
        _to_oldest_generation()
    _READ.clear()  # one manifest kept: a run reads its manifest twice, never many
    _READ[key] = (data, document, text)
    return document, text


# The last manifest read, by absolute path: its bytes, its document (never modified by the
# readers) and its text.
_READ: dict[str, tuple[bytes, Any, str]] = {}


def forget_documents() -> None:
    """Drop the manifest kept by :func:`read_document`, once a run has loaded its scene: the
    decoded document of 1,000,000 bodies holds about a gigabyte that nothing reads again
    (a later read decodes it anew), and what was kept of it (:data:`KEPT_OF_DOCUMENTS`)."""
    _READ.clear()
    for forget in KEPT_OF_DOCUMENTS:
        forget()


#: How to drop what a reader keeps of the last document (its columns, its first problem):
#: :func:`forget_documents` calls each.
KEPT_OF_DOCUMENTS: list[Callable[[], None]] = []


def _to_oldest_generation() -> None:
    """Every object the collector tracks moved to its oldest generation at once (frozen and
    thawed: ``gc.unfreeze`` puts them there), so that the young collections that follow never
    walk a decoded document's million objects (each one walked them all before they aged);
    not when the program keeps objects frozen of its own."""
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()


def _check_manifest_file(file: Path, source: str) -> None:
    if not file.exists():  # says which: not found, a link that dangles or loops
        check_input(source, "manifest")
    if file.is_dir():
        raise InputFileError("is a directory, not a scene manifest", source)
    if not is_manifest(file):
        raise InputFileError(
            f"unknown scene manifest extension {file.suffix or '(none)'!r} (expected .json, .toml)",
            source,
        )


def _decode(file: Path, text: str, source: str) -> Any:
    """The parsed JSON or TOML document; syntax errors and runaway nesting as SceneError."""
    if file.suffix.lower() == ".toml":
        if sys.version_info >= (3, 11):
            import tomllib
        else:
            import tomli as tomllib
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            raise SceneError(f"invalid TOML: {str(error).splitlines()[0]}", source) from None
        except RecursionError:
            raise SceneError(too_deep(text), source) from None
        except ValueError as error:  # an integer of thousands of digits
            raise SceneError(_number_problem(error), source) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise SceneError(
            f"invalid JSON at line {error.lineno} column {error.colno}: {error.msg}", source
        ) from None
    except RecursionError:
        raise SceneError(too_deep(text), source) from None
    except ValueError as error:  # an integer of thousands of digits
        raise SceneError(_number_problem(error), source) from None


def _number_problem(error: ValueError) -> str:
    """Python's refusal of an integer longer than ``sys.get_int_max_str_digits()`` digits
    (4,300 by default), as one line."""
    return f"a number is too long to read ({str(error).splitlines()[0][:120]})"


def too_deep(text: str, openers: str = "[{") -> str:
    """The message for a document nested beyond :data:`MAX_NESTING`: where the nesting passes
    it (brackets inside strings are counted too: a bound, not a parse)."""
    depth = 0
    for line_number, line in enumerate(text.splitlines(), start=1):
        for char in line:
            depth += char in openers
            depth -= char in "]}"
            if depth > MAX_NESTING:
                return (
                    f"manifest nests arrays and objects more than {MAX_NESTING} deep "
                    f"(line {line_number})"
                )
    return f"manifest nests arrays and objects more than {MAX_NESTING} deep"


def children(value: Any) -> Iterator[tuple[Any, Any]]:
    """``(key, child)`` of an object or ``(index, child)`` of an array; nothing for a scalar."""
    if isinstance(value, dict):
        return iter(value.items())
    if isinstance(value, list):
        return enumerate(value)
    return iter(())


def nesting(document: Any) -> int:
    """Depth of arrays and objects (0 for a scalar), without recursion; a depth beyond
    :data:`MAX_NESTING` is not explored further."""
    deepest, stack = 0, [(document, 0)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            deepest = max(deepest, depth + 1)
            if depth + 1 <= MAX_NESTING:
                stack.extend((child, depth + 1) for _, child in children(value))
    return deepest


def first_non_finite(document: Any) -> list | None:
    """Path to the first NaN or infinity in document order, or None."""
    stack: list[tuple[Any, list]] = [(document, [])]
    while stack:
        value, path = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            return path
        stack.extend(reversed([(item, [*path, key]) for key, item in children(value)]))
    return None
