"""The Makefile's pytest lanes fail, never hang, when a worker dies: in session 15 a segfault
in manifold3d killed an xdist worker, and the restarted run waited forever at 99% for the
tests the dead worker held (``--dist loadgroup``), until CI's cap."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

MAKEFILE = Path(__file__).resolve().parents[1] / "Makefile"

CRASHING = """
import os, signal, time
import pytest

@pytest.mark.parametrize("i", range(40))
def test_one_of_many(i):
    time.sleep(0.02)
    if i == 5:
        os.kill(os.getpid(), signal.SIGSEGV)
"""


@pytest.mark.slow  # starts two xdist workers (3-4 s); the full lane runs it
def test_a_crashed_worker_fails_the_lanes_run(tmp_path: Path) -> None:
    pytest.importorskip("xdist")
    flags = re.search(r"^XDIST := (.*)$", MAKEFILE.read_text(), re.M)
    assert flags, "the Makefile's XDIST line"
    (tmp_path / "test_crashing.py").write_text(CRASHING)
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"]
    command += shlex.split(flags.group(1)) + ["-c", str(tmp_path / "pytest.ini"), str(tmp_path)]
    try:
        done = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:  # the hang this guards against
        pytest.fail("pytest with the Makefile's XDIST flags hung after a worker crashed")
    assert done.returncode == 1, done.stdout[-2000:]
    assert "crashed while running" in done.stdout
