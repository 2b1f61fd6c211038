"""The import rules of ARCHITECTURE.md, checked on the source: layers, the native boundary, no
cycles.

Every ``import`` and ``from ... import`` in every module counts, at module level or inside a
function (a lazy import is still a dependency); ``if TYPE_CHECKING:`` blocks do not.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest
from package_source import PACKAGE, sources, tree

#: layer -> layers it must never import (see ARCHITECTURE.md)
FORBIDDEN: dict[str, set[str]] = {
    "geometry": {"io", "collision", "decomposition", "analysis", "cli", "_native"},
    "io": {"collision", "decomposition", "analysis", "cli"},
    "collision": {"io", "decomposition", "analysis", "cli"},
    "decomposition": {"analysis", "cli", "_native"},
    "analysis": {"cli", "_native"},
    "cli": {"_native", "geometry", "collision"},
    "types": {"io", "collision", "decomposition", "analysis", "cli", "geometry", "_native"},
    "errors": {"io", "collision", "decomposition", "analysis", "cli", "geometry", "_native"},
    "vocabulary": {
        "io",
        "collision",
        "decomposition",
        "analysis",
        "cli",
        "geometry",
        "_native",
        "types",
        "errors",
    },
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(path: Path) -> set[str]:
    """Every meshcol module ``path`` imports (``from meshcol import x`` names ``meshcol.x``
    when x is a module, else ``meshcol``)."""
    found: set[str] = set()
    skip: set[int] = set()
    nodes = list(ast.walk(tree(path)))
    for node in nodes:
        if isinstance(node, ast.If) and _is_type_checking(node):
            skip.update(id(n) for child in node.body for n in ast.walk(child))
    for node in nodes:
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "meshcol")
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "meshcol":
                continue
            for alias in node.names:
                candidate = f"{node.module}.{alias.name}"
                found.add(candidate if candidate in MODULES else node.module)
    return found


MODULES: dict[str, Path] = {_module_name(p): p for p in sources()}
MODULES["meshcol._core"] = PACKAGE / "_core"  # the extension: no source to parse


#: The modules with a source to parse.
SOURCES = sorted(name for name, path in MODULES.items() if path.suffix == ".py")


@functools.cache
def graph() -> dict[str, set[str]]:
    """Module -> the meshcol modules it imports. Parsed on first use, not at import: every
    xdist worker collects this file, and only the one that runs its tests (one worker:
    conftest.py's XDIST_GROUPS) parses the package."""
    return {name: _imports(MODULES[name]) for name in SOURCES}


def _layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_the_graph_is_not_empty() -> None:
    # A broken walker would pass every rule below: make sure it sees the known edges.
    assert "meshcol.collision.shapes" in graph()["meshcol.collision.narrowphase"]
    assert "meshcol._native" in graph()["meshcol.collision.mesh_query"]
    assert len(graph()) > 30


@pytest.mark.parametrize("module", SOURCES)
def test_layer_rules(module: str) -> None:
    forbidden = FORBIDDEN.get(_layer(module) or "", set())
    bad = sorted(m for m in graph()[module] if _layer(m) in forbidden)
    assert not bad, f"{module} imports {bad}: see the import rules in ARCHITECTURE.md"


def test_only_the_native_module_imports_the_core() -> None:
    importers = sorted(m for m, deps in graph().items() if "meshcol._core" in deps)
    assert importers == ["meshcol._native"]


def test_only_collision_the_mesh_readers_and_the_report_writer_use_the_native_module() -> None:
    users = sorted(m for m, deps in graph().items() if "meshcol._native" in deps)
    io_users = {"meshcol.io.mesh_read", "meshcol.io.polygons", "meshcol.io.report"}
    io_users.add("meshcol.io.scene_native")  # the manifest reader
    io_users.add("meshcol.io.raster")  # the snapshot pictures' triangle fill
    assert users and all(_layer(m) == "collision" or m in io_users for m in users), users


def test_no_import_cycles() -> None:
    # The package root re-exports everything lazily and is imported first by every module;
    # edges into it are not dependencies of the layers.
    imports = graph()
    edges = {
        m: {d for d in deps if d != "meshcol" and d in imports}
        for m, deps in imports.items()
        if m != "meshcol"
    }
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt) :] + [nxt]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(edges):
        if node not in state:
            visit(node)


def test_the_walker_sees_lazy_imports_and_skips_type_checking(tmp_path: Path) -> None:
    source = tmp_path / "probe.py"
    source.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from meshcol.analysis.check import CheckReport\n"
        "def f():\n"
        "    from meshcol.collision.shapes import ConvexSet\n"
        "    import meshcol.io.scene\n"
    )
    assert _imports(source) == {"meshcol.collision.shapes", "meshcol.io.scene"}


@pytest.mark.slow
def test_one_hull_mechanism() -> None:
    """Convex hulls come from the core's Quickhull only (ARCHITECTURE.md, one mechanism per
    job): no module builds one with scipy's qhull, and only ``collision.hull`` defines the
    hull functions every other module calls."""
    qhull_users, definers = [], []
    for name in SOURCES:
        for node in ast.walk(tree(MODULES[name])):
            if (
                isinstance(node, ast.ImportFrom)
                and (node.module or "").startswith("scipy")
                and any(a.name in {"ConvexHull", "Delaunay"} for a in node.names)
            ):
                qhull_users.append(name)
            if isinstance(node, ast.FunctionDef) and node.name in {"exact_hull", "convex_hull"}:
                definers.append(name)
    assert qhull_users == []
    assert sorted(set(definers)) == ["meshcol.collision.hull"]
