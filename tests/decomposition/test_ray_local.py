"""``--executor ray`` without an address: the run starts its own Ray on 127.0.0.1 and, on
Ctrl-C (SIGINT to the whole process group, as a terminal sends it), exits 130 and leaves no
Ray process behind: whether the signal comes while ``ray.init`` is still starting the local
Ray (it once crashed the process then, SIGSEGV at exit: see
``meshcol.decomposition.executor._signals_deferred``) or while a task runs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest


def _children(pid: int) -> list[tuple[int, str]]:
    """(pid, command line) of every process whose parent is ``pid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            found.append((int(entry.name), cmdline))
    return found


def _descendants(pid: int) -> list[tuple[int, str]]:
    found, todo = [], [pid]
    while todo:
        for child in _children(todo.pop()):
            found.append(child)
            todo.append(child[0])
    return found


def _alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("when", ["ray-init", "task-running"])
def test_ctrl_c_stops_the_local_ray_it_started(corpus, tmp_path, when) -> None:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    slow = corpus / "coacd-examples" / "Octocat-v2.obj"  # minutes with CoACD's defaults
    proc = subprocess.Popen(
        [sys.executable, "-m", "meshcol", "decompose", str(slow), "-o", str(tmp_path / "o")]
        + ["--no-cache", "--executor", "ray", "--jobs", "2", "--preprocess", "off"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        # ray-init: the raylet is up, ray.init has seconds to go (connecting, the workers);
        # task-running: a worker runs the file (its title is the task's function).
        wanted = "raylet/raylet" if when == "ray-init" else "ray::_ray_call"
        found: list[tuple[int, str]] = []
        deadline = time.monotonic() + 90
        while not found and time.monotonic() < deadline and proc.poll() is None:
            found = [c for c in _descendants(proc.pid) if wanted in c[1]]
            time.sleep(0.05)
        assert found, f"no {wanted} process started"
        raylet = [c for c in _children(proc.pid) if "raylet/raylet" in c[1]]
        assert "--node_ip_address=127.0.0.1" in raylet[0][1]
        ray_processes = [pid for pid, _ in _descendants(proc.pid)]
        os.killpg(proc.pid, signal.SIGINT)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, stderr
    assert stderr.decode().strip().splitlines()[-1] == "meshcol: interrupted"
    assert b"Traceback" not in stderr
    deadline = time.monotonic() + 30  # a bound, not a speed
    while any(_alive(p) for p in ray_processes) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert [p for p in ray_processes if _alive(p)] == []
    assert not (tmp_path / "o").exists()


_CLOSE_SCRIPT = """
import json, os, sys, time
sys.path.insert(0, {tests!r})
from test_ray_local import _descendants
from meshcol.decomposition.executor import RayExecutor

def noop(task):
    return task, os.nice(0)

executor = RayExecutor(noop, 2).start()
values = [o.value for o in executor.run(range(4))]
done = sorted(task for task, _ in values)
niceness = sorted({{nice for _, nice in values}})
before = [pid for pid, _ in _descendants(os.getpid())]
start = time.perf_counter()
executor.close()
seconds = time.perf_counter() - start
left = [pid for pid in before if os.path.exists(f"/proc/{{pid}}")]
print(json.dumps({{"done": done, "before": before, "left": left, "seconds": seconds,
                  "niceness": niceness, "own": os.nice(0)}}))
"""


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_closing_the_local_ray_stops_every_process_it_started() -> None:
    """``close()`` stops the raylet as Ray does and the others together (see
    ``executor._prompt_stop``): when it returns, no process of that Ray is left, not even a
    zombie (each was reaped)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    import json

    script = _CLOSE_SCRIPT.format(tests=str(Path(__file__).parent))
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["done"] == [0, 1, 2, 3]
    # Its workers run at the caller's niceness, not Ray's default of 15, which starves them
    # beside other CPU-bound work.
    assert result["niceness"] == [result["own"]]
    # The raylet, the GCS server, the monitors and the workers were all running.
    assert len(result["before"]) >= 5
    # Checked as close() returns, before this process's exit could clean anything up.
    assert result["left"] == []
