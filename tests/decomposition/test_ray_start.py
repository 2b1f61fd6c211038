"""Where the Ray executor's cluster comes from (issue 32 item 6): a running Ray is joined
(``RAY_ADDRESS``; the cluster ``ray start`` recorded in Ray's address file, if it answers),
else a light local Ray of the run's own starts (no autoscaler monitor, no log monitor).

The address-file checks need no Ray; the two tests that start one (``ray start --head`` on
127.0.0.1 in a temp folder of its own, and a light local Ray) are slow and skip without it.
"""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from meshcol.decomposition import ray_start
from meshcol.decomposition.ray_start import running_cluster


def _address_file(folder: Path, address: str) -> str:
    path = folder / "ray" / "ray_current_cluster"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(address)
    return str(path)


def test_ray_address_is_joined_as_ray_init_reads_it(tmp_path) -> None:
    missing = str(tmp_path / "none")
    assert running_cluster({"RAY_ADDRESS": "ray://head:10001"}, missing) == "ray://head:10001"
    assert running_cluster({"RAY_ADDRESS": "  "}, missing) is None
    assert running_cluster({}, missing) is None


def test_a_recorded_cluster_is_joined_only_if_it_answers_on_this_machine(tmp_path) -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        live = _address_file(tmp_path / "live", f"127.0.0.1:{port}")
        assert running_cluster({}, live) == f"127.0.0.1:{port}"
    # the cluster died and left its file: ignored, where ray.init would retry for minutes
    assert running_cluster({}, live) is None
    # another machine's address (TEST-NET-1), garbage, an empty file: a Ray of our own
    for text in ("192.0.2.1:6379", "not an address", "127.0.0.1:", ""):
        assert running_cluster({}, _address_file(tmp_path / "other", text)) is None, text


def test_the_address_file_is_where_ray_keeps_it(monkeypatch, tmp_path) -> None:
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path))
    assert ray_start._address_file() == str(tmp_path / "ray" / "ray_current_cluster")
    monkeypatch.delenv("RAY_TMPDIR")
    monkeypatch.delenv("TMPDIR", raising=False)
    if sys.platform.startswith("linux"):
        assert ray_start._address_file() == "/tmp/ray/ray_current_cluster"
    utils = pytest.importorskip("ray._common.utils", reason="Ray is not installed")
    assert ray_start._address_file() == utils.get_ray_address_file(None)


def test_the_light_head_leaves_out_both_monitors_for_the_block_only() -> None:
    parameter = pytest.importorskip("ray._private.parameter", reason="Ray is not installed")
    with ray_start.light_head():
        params = parameter.RayParams(num_cpus=1)
        asked = parameter.RayParams(include_log_monitor=True)
    assert params.no_monitor is True and params.include_log_monitor is False
    assert asked.include_log_monitor is True  # what a caller asks for stays
    after = parameter.RayParams(num_cpus=1)
    assert after.no_monitor is False and after.include_log_monitor is None


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Ray's address file, /proc")
def test_a_light_local_ray_runs_tasks_without_the_monitors() -> None:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    from ray._private import ray_constants
    from ray._private import worker as ray_worker

    from meshcol.decomposition.executor import RayExecutor

    # a builtin task: Ray's workers import no test module
    with RayExecutor(abs, 1, address="local") as executor:
        outcomes = list(executor.run([-1, -2, 3]))
        started = set(ray_worker._global_node.all_processes)
    assert sorted(o.value for o in outcomes) == [1, 2, 3], outcomes
    assert ray_constants.PROCESS_TYPE_RAYLET in started
    assert ray_constants.PROCESS_TYPE_MONITOR not in started
    assert ray_constants.PROCESS_TYPE_LOG_MONITOR not in started


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Ray's address file, /proc")
def test_a_ray_start_cluster_is_joined_and_outlives_the_run(monkeypatch, tmp_path) -> None:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    ray_cli = shutil.which("ray", path=os.path.dirname(sys.executable)) or shutil.which("ray")
    if ray_cli is None:
        pytest.skip("the ray command is not installed (pip install 'meshcol[ray]')")
    # RAY_TMPDIR: the cluster's address file in a folder of its own (Ray's socket paths must
    # stay under 108 bytes); the token: Ray 2.60's `ray start` authenticates its drivers.
    temp = tempfile.mkdtemp(prefix="mcj", dir="/tmp")
    # RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0: the address file says 127.0.0.1, where the cluster
    # is (else Ray records this machine's network address, where its raylet is not).
    env = {"RAY_TMPDIR": temp, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}
    env["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = [ray_cli, "start", "--head", f"--port={port}", "--num-cpus=1"]
    start += ["--node-ip-address=127.0.0.1", "--include-dashboard=false"]
    proc = subprocess.Popen(
        start, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out, _ = proc.communicate(timeout=180)
        assert proc.returncode == 0, out.decode()
        address = running_cluster()
        assert address == f"127.0.0.1:{port}"
        # the run in a process of its own (no Ray imported before: as a user runs it)
        code = (
            "from meshcol.decomposition.executor import RayExecutor\n"
            "with RayExecutor(abs, 2) as executor:\n"  # no address: the running one
            "    values = sorted(o.value for o in executor.run([-4, 5]))\n"
            "    print(executor.address, executor.slots)\n"
            "    print(values)\n"
        )
        run = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, timeout=240
        )
        assert run.returncode == 0, run.stderr[-3000:]
        # joined, with the cluster's one CPU (not the two asked for)
        assert run.stdout.splitlines() == [f"{address} 1", "[4, 5]"]
        # the run left; the cluster it did not start still answers
        assert running_cluster() == address
    finally:
        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(proc.pid, sig)
            except ProcessLookupError:
                break
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                continue
        shutil.rmtree(temp, ignore_errors=True)
