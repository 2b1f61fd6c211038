"""The size rules of ARCHITECTURE.md, checked on the source (issue 28): no Python file over 800
lines, no block over cyclomatic complexity 25 (radon's measure), at most 10 functions over 80
lines, and those only where they are flat sequences of calls.

Radon is a test dependency; a checkout without it skips the complexity rule with the reason.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from package_source import PACKAGE, sources, text, tree

MAX_FILE_LINES = 800
MAX_COMPLEXITY = 25
LONG_FUNCTION_LINES = 80
MAX_LONG_FUNCTIONS = 10


def _functions(path: Path) -> list[tuple[str, int]]:
    """Every function of ``path`` as (qualified name, length in lines)."""
    found: list[tuple[str, int]] = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                found.append((name, (child.end_lineno or child.lineno) - child.lineno + 1))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")

    visit(tree(path), "")
    return found


def long_functions() -> list[str]:
    """Functions over LONG_FUNCTION_LINES lines, as ``path:name (lines)``."""
    rows = []
    for path in sources():
        for name, lines in _functions(path):
            if lines > LONG_FUNCTION_LINES:
                rows.append(f"{path.relative_to(PACKAGE.parent)}:{name} ({lines})")
    return rows


def test_no_python_file_is_over_800_lines() -> None:
    over = [
        f"{path.relative_to(PACKAGE.parent)} ({n})"
        for path in sources()
        if (n := len(text(path).splitlines())) > MAX_FILE_LINES
    ]
    assert not over, f"files over {MAX_FILE_LINES} lines: {over}"


def test_at_most_ten_functions_are_over_80_lines() -> None:
    rows = long_functions()
    assert len(rows) <= MAX_LONG_FUNCTIONS, "\n".join(rows)


def test_no_block_is_above_complexity_25() -> None:
    radon = pytest.importorskip("radon.complexity", reason="radon measures complexity")
    over = []
    for path in sources():
        for block in radon.cc_visit_ast(tree(path)):
            if block.complexity > MAX_COMPLEXITY:
                over.append(
                    f"{path.relative_to(PACKAGE.parent)}:{block.fullname} ({block.complexity})"
                )
    assert not over, "\n".join(over)


if __name__ == "__main__":  # a report for whoever splits the next function
    import sys

    for row in long_functions():
        print(row)
    sys.exit(0)
