"""The Ray executor: a real local Ray cluster (127.0.0.1, 2 CPUs), started once for the module.

Outputs identical to the local pool; a worker killed by its pid fails only its file; a task
that sleeps forever is cancelled by force at its timeout; a task's engine steps reach the
driver; without Ray, ``--executor ray`` exits 2 with a one-line hint.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest
import test_executor
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE
from test_executor import (
    CHECK,
    alive,
    cache_entries,
    files,
    linux_only,
    run_killing,
    strip_progress,
    untimed,
)

from meshcol.cli import main
from meshcol.decomposition.steps import stage

# The inputs of tests/test_executor.py (fixtures), for the same scenarios on Ray.
meshes, batch, stall = test_executor.meshes, test_executor.batch, test_executor.stall

# Engine options of FAST_DECOMPOSE, for decompose_files.
FAST = {
    "threshold": 0.2,
    "resolution": 500,
    "engine_options": {"mcts_iterations": "20", "mcts_nodes": "8", "mcts_max_depth": "2"},
}


@pytest.fixture(scope="module")
def ray_cluster():
    """A local Ray of 2 CPUs on 127.0.0.1 for the whole module, shut down at its end, its
    workers at the caller's niceness as in a Ray of meshcol's own (at Ray's default of 15 the
    stalled tasks below, beside other CPU-bound work, never got a second of CPU in a minute)."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    from meshcol.decomposition.ray_start import LIGHT_INIT

    ray.init(
        address="local",
        num_cpus=2,
        include_dashboard=False,
        _node_ip_address="127.0.0.1",
        log_to_driver=False,
        logging_level="ERROR",
        _system_config=dict(LIGHT_INIT["_system_config"]),
    )
    # The task functions below are sent by value: the workers cannot import this module.
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        yield ray
    finally:
        ray.shutdown()


def _sleep_or_record(task):
    kind, arg = task
    if kind == "pid":  # write this worker's pid, then hang until killed
        Path(arg).write_text(str(os.getpid()))
        time.sleep(600)
    if kind == "forever":
        Path(arg).write_text(str(os.getpid()))
        while True:
            time.sleep(1)
    time.sleep(arg)
    return os.getpid()


@pytest.mark.slow
def test_ray_outputs_are_byte_identical_to_the_local_pool(ray_cluster, meshes, tmp_path) -> None:
    args = [*map(str, meshes), "--no-cache", *FAST_DECOMPOSE, "--jobs", "2", "--report", "-"]
    runner = CliRunner()
    local = runner.invoke(main, ["decompose", *args, "-o", str(tmp_path / "local")])
    remote = runner.invoke(
        main, ["decompose", *args, "-o", str(tmp_path / "ray"), "--executor", "ray"]
    )
    assert local.exit_code == remote.exit_code == 0, remote.stderr
    assert files(tmp_path / "local") == files(tmp_path / "ray")
    assert len(files(tmp_path / "ray")) >= 3

    def strip(report: dict) -> list[dict]:
        return [{k: v for k, v in f.items() if k != "seconds"} for f in report["files"]]

    a, b = json.loads(local.stdout), json.loads(remote.stdout)
    assert strip(a) == strip(b)
    assert a["settings"]["executor"] == "local" and b["settings"]["executor"] == "ray"


@pytest.mark.slow
def test_a_killed_worker_fails_only_its_task(ray_cluster, tmp_path) -> None:
    from meshcol.decomposition.executor import RayExecutor

    pid_file = tmp_path / "pid"

    def kill_when_started() -> None:
        deadline = time.monotonic() + 30
        while not pid_file.exists() or not pid_file.read_text():
            if time.monotonic() > deadline:
                return
            time.sleep(0.05)
        os.kill(int(pid_file.read_text()), signal.SIGKILL)

    killer = threading.Thread(target=kill_when_started)
    killer.start()
    tasks = [("sleep", 0.2), ("pid", str(pid_file)), ("sleep", 0.1), ("sleep", 0.3)]
    with RayExecutor(_sleep_or_record, 2, timeout=60) as executor:
        outcomes = {o.index: o for o in executor.run(tasks)}
    killer.join()
    assert sorted(outcomes) == [0, 1, 2, 3]
    assert pid_file.read_text(), outcomes[1].message
    assert outcomes[1].status == "failed"
    assert "worker process died" in outcomes[1].message
    assert [outcomes[i].status for i in (0, 2, 3)] == ["ok", "ok", "ok"]


@pytest.mark.slow
def test_a_timeout_cancels_a_task_that_sleeps_forever(ray_cluster, tmp_path) -> None:
    from meshcol.decomposition.executor import RayExecutor

    pid_file = tmp_path / "pid"
    # The timeout counts from submission, a new worker's start-up included (seconds on a
    # loaded machine): both CPUs free again after the tests before (a bounded wait), two
    # workers warmed, and a timeout above a loaded start-up, so that only the endless task
    # times out.
    deadline = time.monotonic() + 60
    while ray_cluster.available_resources().get("CPU", 0) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert ray_cluster.available_resources().get("CPU", 0) == 2, ray_cluster.available_resources()
    with RayExecutor(_sleep_or_record, 2) as executor:
        assert [o.status for o in executor.run([("s", 0.5), ("s", 0.5)])] == ["ok", "ok"]
    start = time.perf_counter()
    with RayExecutor(_sleep_or_record, 2, timeout=15) as executor:
        outcomes = {o.index: o for o in executor.run([("forever", str(pid_file)), ("s", 0.1)])}
    elapsed = time.perf_counter() - start
    assert outcomes[0].status == "timeout"
    assert outcomes[0].message == "timed out after 15 s"
    assert outcomes[1].status == "ok", (outcomes[1], ray_cluster.available_resources())
    assert elapsed < 60  # a bound, not a speed: the endless task did not run on
    # The cancel was forced: the worker process that slept is gone.
    pid = int(pid_file.read_text())
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and alive(pid):
        time.sleep(0.1)
    assert not alive(pid)


@pytest.mark.slow
def test_engine_threads_are_set_per_task(ray_cluster) -> None:
    from meshcol.decomposition.executor import RayExecutor
    from meshcol.decomposition.jobs import worker_env

    with RayExecutor(_environment, 2) as executor:
        (outcome,) = list(executor.run([None]))
    expected = worker_env(2)
    assert outcome.status == "ok"
    assert {k: outcome.value.get(k) for k in expected} == expected


def _environment(_):
    return dict(os.environ)


def _stepping(count: int) -> int:
    with stage("fake step", count) as steps:
        for _ in range(count):
            steps.advance()
    return count


@pytest.mark.slow
def test_ray_tasks_report_their_steps_to_the_driver(ray_cluster) -> None:
    """On Ray the task is a Ray generator: its steps reach ``on_step`` before its outcome
    (tests/test_step_progress.py has the local pool's and the progress line's tests)."""
    from meshcol.decomposition.executor import RayExecutor

    seen: list[tuple[int, object]] = []
    with RayExecutor(_stepping, 1, timeout=120) as executor:
        executor.on_step = lambda index, snapshot: seen.append((index, snapshot))
        outcomes = list(executor.run([3]))
    assert [(o.status, o.value) for o in outcomes] == [("ok", 3)]
    assert (0, (("fake step", 1, 3, False, None),)) in seen
    assert seen[-1] == (0, ())  # the stage ended before the outcome came


def test_executor_ray_without_ray_exits_2_with_a_hint(meshes, tmp_path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    result = CliRunner().invoke(
        main,
        ["decompose", str(meshes[1]), "-o", str(tmp_path / "o"), "--executor", "ray"],
    )
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert lines == ["meshcol: error: --executor ray needs Ray: pip install 'meshcol[ray]'"]
    assert not (tmp_path / "o").exists()


def test_ray_address_needs_the_ray_executor(meshes, tmp_path) -> None:
    result = CliRunner().invoke(
        main, ["decompose", str(meshes[1]), "-o", str(tmp_path / "o"), "--ray-address", "auto"]
    )
    assert result.exit_code == 2
    assert "--ray-address needs --executor ray" in result.stderr


def test_importing_meshcol_and_help_load_no_ray() -> None:
    import subprocess

    code = (
        "import sys, meshcol, meshcol.cli\n"
        "from click.testing import CliRunner\n"
        "assert CliRunner().invoke(meshcol.cli.main, ['decompose', '--help']).exit_code == 0\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('ray', 'fsspec')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# --------------------------------------------------------------------------------------------
# inspect and check over many inputs: one task per file


def _inspect(args: list[str]):
    return CliRunner().invoke(main, ["inspect", *args])


def _pid_recorded(fn: Any, path: str, record: Path) -> Any:
    """``fn`` (a task function) that first writes its worker's pid to ``record`` when its
    task is ``path``'s, then runs as it is: which Ray worker runs that task."""

    def recorded(task: Any) -> Any:
        if task[0] == path:
            partial = record.with_suffix(".partial")
            partial.write_text(str(os.getpid()))
            partial.replace(record)
        return fn(task)

    return recorded


def _recorded_pid(record: Path) -> int | None:
    return int(record.read_text()) if record.exists() else None


@pytest.mark.slow
def test_inspect_on_ray_is_byte_identical_to_the_local_run(ray_cluster, batch) -> None:
    local = _inspect(batch)
    remote = _inspect([*batch, "--executor", "ray", "--jobs", "2"])
    assert local.exit_code == remote.exit_code == 2  # empty.obj is not inspected
    assert remote.stdout == local.stdout
    assert strip_progress(remote.stderr) == strip_progress(local.stderr)
    report = json.loads(remote.stdout)
    names = [b["name"] for b in report["bodies"]]
    assert names[:3] == ["torus", "box", "l_shape"] and "l_shape#2" in names
    assert [e["source"] for e in report["errors"]] == [batch[3]]


@pytest.mark.slow
def test_an_inspect_timeout_fails_only_its_file(ray_cluster, batch, stall) -> None:
    """A file whose task computes for many seconds (:func:`test_executor.stall`) is
    cancelled by force at the timeout; the other files are reported."""
    # The timeout counts from a task's submission, a new worker's start-up included (these
    # tasks' thread settings are a runtime_env of their own on this Ray: new workers, seconds
    # each on a loaded machine): warm two up first, so that only the stalled task times out.
    # The stalled file takes a warm worker about 4 s (it did not time out at 4 s once the
    # workers ran at the caller's niceness, not Ray's 15); the others take milliseconds.
    warm = _inspect([batch[0], batch[1], "--executor", "ray"])
    assert warm.exit_code == 0, warm.stderr
    start = time.perf_counter()
    result = _inspect([batch[0], str(stall), batch[1], "--executor", "ray", "--timeout", "2"])
    assert time.perf_counter() - start < 60
    assert result.exit_code == 2, result.stderr
    report = json.loads(result.stdout)
    assert [b["name"] for b in report["bodies"]] == ["torus", "box"]
    assert report["errors"] == [
        {"source": str(stall), "body": None, "message": "timed out after 2 s"}
    ]
    assert f"meshcol: error: {stall}: timed out after 2 s" in result.stderr


@pytest.mark.slow
def test_check_decomposed_on_ray_matches_the_local_run(ray_cluster, batch, tmp_path) -> None:
    """The per-file work (reading, the decompositions through the cache) on Ray, the pairs
    on the driver: the report of the sequential run, timings and time stamp aside."""
    inputs = [batch[1], batch[2], batch[4], batch[5]]  # box, l_shape, l_shape#2, pair.glb
    common = ["check", *inputs, "--shape", "decomposed", "--threshold", "0.2", "--fail-on", "none"]
    runner = CliRunner()
    local = runner.invoke(main, [*common, "--cache-dir", str(tmp_path / "c1")])
    remote = runner.invoke(
        main, [*common, "--cache-dir", str(tmp_path / "c2"), "--executor", "ray", "-j", "2"]
    )
    assert local.exit_code == remote.exit_code == 0, remote.stderr
    a, b = json.loads(local.stdout), json.loads(remote.stdout)
    assert untimed(a) == untimed(b)
    assert len(a["pairs"]) >= 3
    # The tasks filled the cache as the local run did: the same entries.
    assert sorted(p.name for p in (tmp_path / "c1").rglob("*") if p.is_file()) == sorted(
        p.name for p in (tmp_path / "c2").rglob("*") if p.is_file()
    )


def test_check_ray_address_needs_the_ray_executor(meshes) -> None:
    for command in ("check", "inspect"):
        result = CliRunner().invoke(main, [command, str(meshes[1]), "--ray-address", "auto"])
        assert result.exit_code == 2
        assert "--ray-address needs --executor ray" in result.stderr


def test_inspect_and_check_on_ray_without_ray_exit_2_with_a_hint(meshes, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)
    for command in ("check", "inspect"):
        result = CliRunner().invoke(main, [command, str(meshes[1]), "--executor", "ray"])
        assert result.exit_code == 2
        assert result.stderr.strip().splitlines() == [
            "meshcol: error: --executor ray needs Ray: pip install 'meshcol[ray]'"
        ]


@pytest.mark.slow
@linux_only
def test_a_killed_ray_worker_fails_only_its_inspect_file(
    ray_cluster, batch, stall, tmp_path, monkeypatch
) -> None:
    """Six files on Ray: the worker computing the third is killed by its pid mid-task; that
    file is an error of the report, the others are the in-process run's bodies."""
    from meshcol.analysis import inspect_tasks

    record = tmp_path / "pid"
    monkeypatch.setattr(
        inspect_tasks,
        "_inspect_file",
        _pid_recorded(inspect_tasks._inspect_file, str(stall), record),
    )
    inputs = [*batch[:2], str(stall), *batch[2:3], *batch[5:]]
    result, pid = run_killing(
        lambda: _recorded_pid(record),
        ["inspect", *inputs, "--executor", "ray", "-j", "2", "--timeout", "60"],
    )
    assert not alive(pid)
    assert result.exit_code == 2, result.stderr
    monkeypatch.undo()
    report = json.loads(result.stdout)
    assert report["bodies"] == json.loads(_inspect([*batch[:3], *batch[5:]]).stdout)["bodies"]
    ((error),) = report["errors"]
    assert error["source"] == str(stall) and error["body"] is None
    assert error["message"].startswith("worker process died ("), error
    assert f"meshcol: error: {stall}: worker process died (" in result.stderr


@pytest.mark.slow
@linux_only
def test_a_killed_ray_worker_fails_only_its_check_file(
    ray_cluster, batch, stall, tmp_path, monkeypatch
) -> None:
    """The other files' tasks finish (the cache holds what a clean run of them leaves); the
    run names the file whose worker died and writes no report."""
    from meshcol.analysis import check

    record = tmp_path / "pid"
    monkeypatch.setattr(check, "_check_file", _pid_recorded(check._check_file, str(stall), record))
    others = [batch[1], batch[2], batch[4], batch[5]]
    out = tmp_path / "report.json"
    result, pid = run_killing(
        lambda: _recorded_pid(record),
        ["check", *others[:2], str(stall), *others[2:], *CHECK, "--executor", "ray", "-j", "2"]
        + ["--timeout", "60", "--cache-dir", str(tmp_path / "c1"), "--report", str(out)],
    )
    assert not alive(pid)
    assert result.exit_code == 2
    monkeypatch.undo()
    # (Ray's own message about the dead worker may come on stderr too, before or after)
    expected = f"meshcol: error: {stall}: its task failed: worker process died ("
    assert any(line.startswith(expected) for line in result.stderr.splitlines()), result.stderr
    assert not out.exists()
    clean = CliRunner().invoke(
        main, ["check", *others, *CHECK, "--cache-dir", str(tmp_path / "c2")]
    )
    assert clean.exit_code == 0, clean.stderr
    assert cache_entries(tmp_path / "c1") == cache_entries(tmp_path / "c2") != []
