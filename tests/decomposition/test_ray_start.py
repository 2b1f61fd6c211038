"""Where the Ray executor's cluster comes from (issue 32 item 6): a running Ray is joined
(``RAY_ADDRESS``; the cluster ``ray start`` recorded in Ray's address file, if it answers),
else a light local Ray of the run's own starts (no autoscaler monitor, no log monitor, no
dashboard head, idle stand-ins for the raylet's agents, whose ports it is told).

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
from typing import Any

import numpy as np
import pytest
import test_executor
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE
from test_executor import files
from test_ray_cluster import _free_port

from meshcol.cli import main
from meshcol.decomposition import ray_start
from meshcol.decomposition.ray_start import running_cluster

meshes = test_executor.meshes


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
    port = _free_port()
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


def test_a_task_opens_in_the_worker_after_its_thread_settings(monkeypatch) -> None:
    """A cluster's task travels pickled and is opened once the run's thread settings are in
    the worker's environment (numpy's OpenBLAS reads them as it loads), not by a
    runtime_env (for which Ray starts new workers)."""
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    task = ("a.obj", [("body", np.arange(12.0).reshape(4, 3), np.array([[0, 1, 2]]))], None)
    payload = ray_start.task_payload(task)
    assert isinstance(payload, bytes)
    opened = ray_start.in_worker({"OMP_NUM_THREADS": "3"}, payload)
    assert os.environ["OMP_NUM_THREADS"] == "3"
    assert opened[0] == "a.obj" and opened[2] is None
    assert np.array_equal(opened[1][0][1], task[1][0][1])
    assert ray_start.in_worker({"OMP_NUM_THREADS": "4"}) is None
    assert os.environ["OMP_NUM_THREADS"] == "4"


def test_free_ports_are_distinct_and_bindable() -> None:
    ports = ray_start.free_ports(4)
    assert len(set(ports)) == 4 and all(p > 0 for p in ports)
    for port in ports:
        with socket.socket() as s:
            s.bind(("127.0.0.1", port))


def test_the_light_head_tells_the_raylet_its_agent_ports_and_idles_the_agents(
    monkeypatch,
) -> None:
    """In the block only: RayParams get free agent ports (the raylet then does not wait for
    the agents' port files), the dashboard head is not started, and the raylet's command
    gets the agents' listen port and an idle stand-in for each agent."""
    services = pytest.importorskip("ray._private.services", reason="Ray is not installed")
    from ray._private import parameter, ray_constants
    from ray._private.node import Node

    started: list[tuple[list[str], str]] = []
    monkeypatch.setattr(
        services,
        "start_ray_process",
        lambda command, kind, *a, **k: started.append((command, kind)),
    )
    api_server = Node.start_api_server
    agents = ["--dashboard_agent_command=python agent.py", "--runtime_env_agent_command=python x"]
    raylet = ["raylet", "--node_ip_address=127.0.0.1", *agents]
    with ray_start.light_head():
        params = parameter.RayParams(num_cpus=1)
        assert Node.start_api_server is not api_server
        assert Node.start_api_server(None, include_dashboard=False, raise_on_failure=False) is None
        services.start_ray_process(list(raylet), ray_constants.PROCESS_TYPE_RAYLET, True)
        services.start_ray_process(["gcs_server"], ray_constants.PROCESS_TYPE_GCS_SERVER, True)
    ports = [getattr(params, name) for name in ray_start.AGENT_PORTS]
    assert len(set(ports)) == 4 and all(p > 0 for p in ports)
    (command, _), (other, _) = started
    assert f"--dashboard_agent_listen_port={params.dashboard_agent_listen_port}" in command
    stand_ins = [a for a in command if a.startswith(ray_start.AGENT_COMMANDS)]
    assert len(stand_ins) == 2 and all("-S -c" in a and "agent.py" not in a for a in stand_ins)
    assert other == ["gcs_server"]
    # after the block, Ray as it was
    assert Node.start_api_server is api_server
    assert parameter.RayParams(num_cpus=1).metrics_agent_port is None


def _session_processes(sid: int) -> list[tuple[int, str]]:
    """(pid, command line) of every live process of session ``sid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            found.append((int(entry.name), cmdline))
    return found


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_one_off_on_a_light_ray_of_its_own_matches_the_local_pool(meshes, tmp_path) -> None:
    """``meshcol decompose --executor ray`` in a process of its own, nothing running to join:
    the outputs of the local pool, byte for byte; the Ray it started ran no dashboard head
    and no agent of Ray's (their stand-ins log nothing); and when the command exits, no
    process it started is left, not one (each of Ray's is in the command's session)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    args = [*map(str, meshes), "--no-cache", *FAST_DECOMPOSE, "--jobs", "2"]
    local = CliRunner().invoke(main, ["decompose", *args, "-o", str(tmp_path / "local")])
    assert local.exit_code == 0, local.output
    temp = tempfile.mkdtemp(prefix="mcl", dir="/tmp")  # Ray's socket paths stay short
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "meshcol", "decompose", *args, "-o", str(tmp_path / "ray")]
            + ["--executor", "ray"],
            env={**env, "RAY_TMPDIR": temp},
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        _, stderr = proc.communicate(timeout=240)
        left = _session_processes(proc.pid)  # as the command exits: nothing waited for
        assert proc.returncode == 0, stderr.decode()[-3000:]
        assert left == []
        assert files(tmp_path / "local") == files(tmp_path / "ray")
        logs = Path(temp) / "ray" / "session_latest" / "logs"
        assert (logs / "raylet.out").exists()
        names = {p.name for p in logs.iterdir()}
        assert not names & {"dashboard.log", "dashboard_agent.log", "runtime_env_agent.log"}
    finally:
        shutil.rmtree(temp, ignore_errors=True)


def test_a_reply_in_another_builds_form_is_a_failed_task_never_an_outcome() -> None:
    """A cluster installed apart from the run may run another meshcol build, whose worker
    answers in another form: an old driver took a new worker's steps for outcomes and passed
    a run of 0 bodies. The driver reads only its own form; anything else fails the task."""
    from types import SimpleNamespace

    from meshcol.decomposition.executor import RayExecutor
    from meshcol.decomposition.jobs import STEP

    class Ray:
        exceptions = SimpleNamespace(RayError=RuntimeError)

        @staticmethod
        def get(item: Any) -> Any:
            return item

    steps: list[Any] = []
    for replies, status in (
        ([(STEP, "s1"), ("done", ("ok", 7))], "ok"),
        ([("ok", 7)], "failed"),  # an outcome with no "done" tag
        ([(STEP, "s1"), "whatever"], "failed"),
        ([("done", "ok")], "failed"),
    ):
        generator = iter(replies)
        fake = SimpleNamespace(ray=Ray, _inflight={generator: (3, 0.0)}, on_step=None)
        fake.on_step = lambda index, snapshot: steps.append((index, snapshot))
        outcome = None
        while outcome is None:
            outcome = RayExecutor._next(fake, generator, 1.0)  # type: ignore[arg-type]
        assert outcome.index == 3 and outcome.status == status, (replies, outcome)
        if status == "ok":
            assert outcome.value == 7
        else:
            assert "another meshcol build" in outcome.message
        assert not fake._inflight
    assert steps == [(3, "s1"), (3, "s1")]
