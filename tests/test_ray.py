"""The Ray executor: a real local Ray cluster (127.0.0.1, 2 CPUs), started once for the module.

Outputs identical to the local pool; a worker killed by its pid fails only its file; a task
that sleeps forever is cancelled by force at its timeout; without Ray, ``--executor ray``
exits 2 with a one-line hint.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest
import trimesh
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import main

# Engine options of FAST_DECOMPOSE, for decompose_files.
FAST = {
    "threshold": 0.2,
    "resolution": 500,
    "engine_options": {"mcts_iterations": "20", "mcts_nodes": "8", "mcts_max_depth": "2"},
}


@pytest.fixture(scope="module")
def ray_cluster():
    """A local Ray of 2 CPUs on 127.0.0.1 for the whole module, shut down at its end."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'meshcol[ray]')")
    ray.init(
        address="local",
        num_cpus=2,
        include_dashboard=False,
        _node_ip_address="127.0.0.1",
        log_to_driver=False,
        logging_level="ERROR",
    )
    # The task functions below are sent by value: the workers cannot import this module.
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        yield ray
    finally:
        ray.shutdown()


@pytest.fixture(scope="module")
def meshes(tmp_path_factory) -> list[Path]:
    folder = tmp_path_factory.mktemp("ray-inputs")
    shapes = {
        "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12),
        "box": trimesh.creation.box(extents=(2, 1, 1)),
        "l_shape": trimesh.creation.box(bounds=[(0, 0, 0), (2, 1, 1)]).union(
            trimesh.creation.box(bounds=[(0, 0, 0.5), (1, 1, 2)]), engine="manifold"
        ),
    }
    paths = []
    for name, mesh in shapes.items():
        paths.append(folder / f"{name}.obj")
        mesh.export(paths[-1])
    return paths


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


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
    args = [*map(str, meshes), "--no-cache", *FAST_DECOMPOSE, "--jobs", "2"]
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
    start = time.perf_counter()
    with RayExecutor(_sleep_or_record, 2, timeout=3) as executor:
        outcomes = {o.index: o for o in executor.run([("forever", str(pid_file)), ("s", 0.1)])}
    elapsed = time.perf_counter() - start
    assert outcomes[0].status == "timeout"
    assert outcomes[0].message == "timed out after 3 s"
    assert outcomes[1].status == "ok"
    assert elapsed < 30
    # The cancel was forced: the worker process that slept is gone.
    pid = int(pid_file.read_text())
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and _alive(pid):
        time.sleep(0.1)
    assert not _alive(pid)


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


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie is dead too
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except OSError:
        return True


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
