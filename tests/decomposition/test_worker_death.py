"""Workers die with the process that started them (issue #29, item 15): a SIGKILL of a run
(nothing of it can clean up) must not leave its worker processes computing."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(
    not Path("/proc/self/stat").exists(), reason="reads the process table from /proc (Linux)"
)

# Two tasks that would take a minute each: the workers are busy when the run is killed.
_RUN = """
import sys, time
from meshcol.decomposition.jobs import run_tasks
for outcome in run_tasks(time.sleep, [60, 60], jobs=2):
    pass
"""


def _stat(pid: int) -> tuple[int, str] | None:
    """(parent pid, state) of a live process, None when it is gone or a zombie."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2 :].split()
    return (int(fields[1]), fields[0]) if fields[0] not in ("Z", "X") else None


def _descendants(root: int) -> set[int]:
    parents = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            info = _stat(int(entry))
            if info is not None:
                parents[int(entry)] = info[0]
    found, frontier = set(), {root}
    while frontier:
        frontier = {pid for pid, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def test_workers_end_when_the_run_is_killed() -> None:
    run = subprocess.Popen([sys.executable, "-c", _RUN], stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120  # a bound for a loaded machine, not a timing claim
        workers: set[int] = set()
        while time.monotonic() < deadline and len(workers) < 2:
            time.sleep(0.2)
            # the workers are the grandchildren (children of the fork server) of the run
            children = _descendants(run.pid)
            workers = {pid for pid in children if _stat(pid) and _stat(pid)[0] != run.pid}
        assert len(workers) >= 2, "the run never started its workers"
        time.sleep(0.5)  # both are inside their task now
    finally:
        run.send_signal(signal.SIGKILL)
        run.wait()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and any(_stat(pid) for pid in workers):
        time.sleep(0.2)
    left = [pid for pid in workers if _stat(pid)]
    for pid in left:  # leave nothing behind, whatever the outcome
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived the killed run by 30 s"
