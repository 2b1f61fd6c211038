"""``--ray-address`` to a separate cluster: a real ``ray start --head`` of one CPU on
127.0.0.1, outside this process, stopped at the end however the tests end.
decompose and inspect through it give the local run's outputs, byte for byte.

A module of its own: no Ray runs in this process meanwhile (tests/test_ray.py's local Ray is
stopped at the end of its module), so the runs join the cluster, then leave it.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

import pytest
import test_executor
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE
from test_executor import files, strip_progress

from meshcol.cli import main

meshes, batch = test_executor.meshes, test_executor.batch


# Ray 2.60's `ray start` authenticates clients with a token: the cluster and its drivers get
# the same one (as a user's shell would, with RAY_AUTH_MODE and the token set).
AUTH = {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}


#: Ray's fixed default ports in Linux's range of free ports (32768-60999): the dashboard
#: agent's HTTP port (ray_constants.DEFAULT_DASHBOARD_AGENT_LISTEN_PORT). A head given it as
#: its --port fails ("port number 52365 that is used by other components"), as `ray start`
#: did in a session-36 run of tests/test_ray_start.py.
RAY_DEFAULT_PORTS = frozenset({52365})


def _free_port() -> int:
    """A port free on 127.0.0.1 now, and none of Ray's own defaults."""
    while True:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port not in RAY_DEFAULT_PORTS:
            return port


@pytest.fixture(scope="module")
def ray_head():
    """``ray start --head`` of one CPU on 127.0.0.1; its address. Stopped at the end.

    Not by ``ray stop``, which stops every Ray on the machine (other test runs' too): the
    cluster is started in a process group of its own, which every process of it (the GCS,
    the raylet, its workers) inherits, and that group is stopped (SIGTERM, then SIGKILL)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    ray_cli = shutil.which("ray", path=os.path.dirname(sys.executable)) or shutil.which("ray")
    if ray_cli is None:
        pytest.skip("the ray command is not installed (pip install 'meshcol[ray]')")
    port = _free_port()
    # A short temp folder of its own (Ray's socket paths must stay under 108 bytes).
    temp = tempfile.mkdtemp(prefix="mcr", dir="/tmp")
    start = [ray_cli, "start", "--head", f"--port={port}", "--num-cpus=1"]
    start += ["--node-ip-address=127.0.0.1", "--include-dashboard=false", f"--temp-dir={temp}"]
    proc = subprocess.Popen(
        start,
        env={**os.environ, **AUTH},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:
        out, _ = proc.communicate(timeout=120)
        assert proc.returncode == 0, out.decode()
        yield f"127.0.0.1:{port}"
    finally:
        _stop_group(proc.pid)
        shutil.rmtree(temp, ignore_errors=True)


def _stop_group(pgid: int) -> None:
    # The GCS server took all of a 10 s SIGTERM grace (12 s of teardown): 2 s, then SIGKILL.
    for sig, wait in ((signal.SIGTERM, 2.0), (signal.SIGKILL, 10.0)):
        try:
            os.killpg(pgid, sig)
        except ProcessLookupError:
            return
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            try:
                os.killpg(pgid, 0)
            except ProcessLookupError:
                return
            time.sleep(0.1)


def _inspect(args: list[str]):
    return CliRunner().invoke(main, ["inspect", *args])


def _meshcol(args: list[str]) -> subprocess.CompletedProcess:
    """``meshcol args`` in a process of its own (no Ray imported before: as a user runs it),
    bounded: joining a cluster that does not answer retries for minutes."""
    return subprocess.run(
        [sys.executable, "-m", "meshcol", *args],
        capture_output=True,
        text=True,
        timeout=240,
        env={**os.environ, **AUTH},
    )


@pytest.mark.slow
def test_decompose_and_inspect_through_ray_address_match_local(
    meshes, batch, ray_head, tmp_path
) -> None:
    args = [*map(str, meshes), "--no-cache", *FAST_DECOMPOSE, "--jobs", "2"]
    local = CliRunner().invoke(main, ["decompose", *args, "-o", str(tmp_path / "local")])
    remote = _meshcol(
        ["decompose", *args, "-o", str(tmp_path / "cluster")]
        + ["--executor", "ray", "--ray-address", ray_head]
    )
    assert local.exit_code == remote.returncode == 0, remote.stderr
    assert files(tmp_path / "local") == files(tmp_path / "cluster")
    assert len(files(tmp_path / "cluster")) >= 3

    inspect_local = _inspect(batch)
    inspect_remote = _meshcol(["inspect", *batch, "--executor", "ray", "--ray-address", ray_head])
    assert inspect_local.exit_code == inspect_remote.returncode == 2  # empty.obj
    assert inspect_remote.stdout == inspect_local.stdout
    assert strip_progress(inspect_remote.stderr) == strip_progress(inspect_local.stderr)


@pytest.mark.slow
def test_joining_a_loopback_cluster_after_ray_was_imported(meshes, ray_head, tmp_path) -> None:
    """In a process that imported Ray before (a library user's): the executor still joins
    the cluster at 127.0.0.1 (Ray would rewrite it to the machine's network address)."""
    code = (
        "import sys, ray\n"
        "from meshcol.decomposition.executor import RayExecutor\n"
        "with RayExecutor(len, 1, address=sys.argv[1]) as ex:\n"
        "    print([o.value for o in ex.run(['ab', 'cde'])])\n"
        "print(ray.is_initialized())\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, ray_head],
        capture_output=True,
        text=True,
        timeout=240,
        env={**os.environ, **AUTH},
    )
    assert out.returncode == 0, out.stderr
    values, initialized = out.stdout.strip().splitlines()
    assert sorted(eval(values)) == [2, 3]
    assert initialized == "False"  # the executor left the cluster (the cluster stays up)


@pytest.mark.slow
def test_the_cluster_is_stopped_by_its_process_group(ray_head) -> None:
    """What the fixture relies on: the cluster's processes are in the group of ``ray start``
    (so stopping that group stops the cluster, and nothing else)."""
    port = ray_head.rsplit(":", 1)[1]
    groups = set()
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmdline = f.read().decode(errors="replace")
            with open(f"/proc/{entry}/stat") as f:
                pgid = int(f.read().rsplit(")", 1)[1].split()[2])
        except OSError:
            continue
        if "gcs_server" in cmdline and f"--gcs_server_port={port}" in cmdline.replace("\0", " "):
            groups.add(pgid)
    assert len(groups) == 1


def _idle_workers(port: str) -> set[int]:
    """The idle Python workers (``ray::IDLE``) of the raylet of the cluster at ``port``."""
    raylets, idle = set(), {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmdline = f.read().decode(errors="replace").replace("\0", " ")
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        # the GCS's host: 127.0.0.1, or this machine's address (Ray's multi-machine default)
        if "raylet/raylet" in cmdline and re.search(rf"--gcs-address=\S+:{port} ", cmdline):
            raylets.add(int(entry))
        elif cmdline.startswith("ray::IDLE") and fields[0] != "Z":
            idle[int(entry)] = int(fields[1])
    return {pid for pid, parent in idle.items() if parent in raylets}


def _wait_for(what, seconds: float = 90.0):
    deadline = time.monotonic() + seconds  # a bound, not a speed
    while not (found := what()) and time.monotonic() < deadline:
        time.sleep(0.2)
    return found


_WORKER_PIDS = """
import os, sys
from meshcol.decomposition.executor import RayExecutor

def where(_):
    return os.getpid(), os.environ.get("OMP_NUM_THREADS"), os.environ.get("OPENBLAS_NUM_THREADS")

with RayExecutor(where, 1, address=sys.argv[1]) as executor:
    print(sorted({o.value for o in executor.run(range(3))}))
"""


def _where(address: str) -> list[tuple[int, str, str]]:
    """(worker pid, OMP_NUM_THREADS, OPENBLAS_NUM_THREADS) of the tasks of a run on the
    cluster at ``address``, in a process of its own."""
    out = subprocess.run(
        [sys.executable, "-c", _WORKER_PIDS, address],
        capture_output=True,
        text=True,
        timeout=240,
        env={**os.environ, **AUTH},
    )
    assert out.returncode == 0, out.stderr[-3000:]
    return eval(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_joined_run_takes_the_idle_workers_and_leaves_idle_ones(ray_head) -> None:
    """A run on a cluster has its tasks run by the idle workers the cluster keeps (no
    runtime_env, for which Ray would start new ones), with the local pool's thread settings
    set in them; its job's workers end with it, and the raylet is asked for idle workers
    again, which the next run finds."""
    pytest.importorskip("grpc", reason="grpcio is not installed (pip install 'meshcol[ray]')")
    port = ray_head.rsplit(":", 1)[1]
    _where(ray_head)  # whatever the cluster had: it leaves idle workers
    before = _wait_for(lambda: _idle_workers(port))
    assert before, "no idle worker was started for the next run"
    seen = _where(ray_head)
    assert {pid for pid, _, _ in seen} <= before  # no worker started for the run
    assert {(omp, blas) for _, omp, blas in seen} == {("2", "1")}  # jobs == the cluster's CPUs
    assert _wait_for(lambda: _idle_workers(port) - before), "no idle worker for the next run"
