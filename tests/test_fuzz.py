"""The fuzz targets (fuzz/targets.py): every input that once broke meshcol, replayed, and a
short seeded fuzzing run per target (atheris), so a new crash fails the suite.

A regression input lives in ``fuzz/regressions/<target>/`` under a name that says what it
broke; ``make fuzz`` runs longer campaigns and writes new crashes to ``fuzz/crashes/``.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO

FUZZ = REPO / "fuzz"
TARGETS = ("readers", "convex", "meshes", "manifest")


def _targets_module():
    spec = importlib.util.spec_from_file_location("meshcol_fuzz_targets", FUZZ / "targets.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _regressions(target: str) -> list[Path]:
    return sorted((FUZZ / "regressions" / target).glob("*"))


@pytest.mark.parametrize(
    ("target", "path"),
    [(t, p) for t in TARGETS for p in _regressions(t)],
    ids=lambda value: value.name if isinstance(value, Path) else value,
)
def test_regression_input_is_handled(target: str, path: Path) -> None:
    # A crash kills the test process, an unexpected exception fails here: both are regressions.
    _targets_module().TARGETS[target](path.read_bytes())


def test_every_target_has_regressions_on_record() -> None:
    assert all(_regressions(t) for t in TARGETS)


@pytest.mark.parametrize("target", TARGETS)
def test_short_fuzzing_run_finds_nothing(target: str, tmp_path: Path) -> None:
    pytest.importorskip("atheris", reason="atheris is not installed (pip install atheris)")
    run = subprocess.run(
        [
            sys.executable,
            str(FUZZ / "run.py"),
            target,
            "--runs",
            "1500",
            "--seed",
            "1",
            "--artifacts",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    tail = "\n".join(run.stderr.splitlines()[-30:])
    assert run.returncode == 0, tail
    assert "Done 1500 runs" in run.stderr, tail
    assert not list(tmp_path.iterdir()), tail
