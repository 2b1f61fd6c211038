"""The package's Python sources, read and parsed once a test run: the tests of the source's
own rules (the import layers, the size rules, who names the manifest extensions) share them.
Their files run on one worker (conftest.py's XDIST_GROUPS), so one worker parses the package
once, where each of these tests used to parse all of it (about 1 s each on a quiet machine).
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "meshcol"


@functools.cache
def sources() -> tuple[Path, ...]:
    """Every ``.py`` file of the package, sorted."""
    return tuple(sorted(PACKAGE.rglob("*.py")))


@functools.cache
def text(path: Path) -> str:
    """The source of ``path``."""
    return path.read_text(encoding="utf-8")


@functools.cache
def tree(path: Path) -> ast.Module:
    """The parsed source of ``path``. Callers only read it (it is shared)."""
    return ast.parse(text(path))
