"""The committed stub of the native module, ``meshcol/_core.pyi``, is what stubgen makes now.

mypy reads the stub to check every call into the core, so a binding changed without
``make stubs`` would let mypy pass on signatures that no longer exist.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

import meshcol

STUB = Path(meshcol.__file__).resolve().parent / "_core.pyi"


def test_the_committed_core_stub_is_current(tmp_path: Path) -> None:
    if importlib.util.find_spec("nanobind") is None:
        pytest.skip("nanobind (a build dependency) is not installed: no stubgen to compare with")
    fresh = tmp_path / "_core.pyi"
    subprocess.run(
        [sys.executable, "-m", "nanobind.stubgen", "-q", "-m", "meshcol._core", "-o", str(fresh)],
        check=True,
    )
    assert STUB.is_file(), f"{STUB} is missing: run `make stubs` and commit it"
    assert fresh.read_text(encoding="utf-8") == STUB.read_text(encoding="utf-8"), (
        "meshcol/_core.pyi is stale (a binding changed): run `make stubs` and commit the stub"
    )


def test_the_stub_types_the_defaults() -> None:
    # `defaults` is a class of constants (not a submodule), so the one-file stub types each.
    text = STUB.read_text(encoding="utf-8")
    assert "class defaults:" in text
    assert "    rigid_tolerance: float = " in text
    assert "    toi_max_iterations: int = " in text
