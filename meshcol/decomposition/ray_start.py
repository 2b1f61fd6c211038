"""Where the Ray executor's cluster comes from, and how a local one starts light (issue 32,
item 6: a one-off ``--executor ray`` on a few files paid about 3.5 s of Ray start-up).

- :func:`running_cluster`: a Ray already running to join, meshcol starting nothing: the
  cluster of ``RAY_ADDRESS``, else the one ``ray start`` left running on this machine
  (Ray's address file, as ``ray.init()`` finds it), if its GCS answers. Keeping a Ray up
  between commands is the user's opt-in: ``ray start --head`` (README, "Ray").
- :data:`LIGHT_INIT` and :func:`light_head`: a local Ray of its own, started with only what
  a run uses: no dashboard, no autoscaler monitor, no log monitor (the run does not stream
  its workers' logs), a small object store (results are reports and part arrays, fetched as
  they complete).

``RayExecutor`` (:mod:`meshcol.decomposition.executor`) uses both; nothing here imports Ray
before a Ray executor starts.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import pickle
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Mapping
from typing import Any

__all__ = [
    "LIGHT_INIT",
    "OWN_CLUSTER",
    "in_worker",
    "light_head",
    "node_manager_address",
    "prestart_workers",
    "running_cluster",
    "task_payload",
]

#: ``--ray-address`` meaning "start a Ray of this run's own" (Ray's own word for it), never
#: the running one :func:`running_cluster` would find.
OWN_CLUSTER = "local"

#: Object store of a local Ray of meshcol's own (bytes): Ray's minimum is 75 MiB; its default
#: (30% of the memory) only reserves what a run never fills.
OBJECT_STORE_BYTES = 256 * 1024 * 1024

#: ``ray.init`` keywords of a local Ray of meshcol's own, besides the cluster's size. Ray
#: starts its workers at niceness 15 (``worker_niceness``): beside other CPU-bound work, a CI
#: runner's other jobs, each then gets a few percent of a core (1.6% measured beside four
#: busy loops on 2 cores), where the local pool's workers run at the caller's niceness. A
#: Ray of meshcol's own runs its workers at the caller's niceness too.
LIGHT_INIT: Mapping[str, Any] = {
    "include_dashboard": False,
    "object_store_memory": OBJECT_STORE_BYTES,
    "_system_config": {"worker_niceness": 0},
}

#: Seconds to wait for a running cluster's GCS to accept a connection.
ANSWER_SECONDS = 0.5


def running_cluster(
    environ: Mapping[str, str] | None = None, address_file: str | None = None
) -> str | None:
    """The address of a running Ray to join instead of starting one, or None.

    ``RAY_ADDRESS`` when set (as ``ray.init()`` reads it); else the address in Ray's
    address file (``/tmp/ray/ray_current_cluster``, written by ``ray start``) when it names
    this machine and its GCS accepts a connection within :data:`ANSWER_SECONDS` (a file
    left by a cluster that died is ignored, where ``ray.init`` would retry for minutes).
    """
    environ = os.environ if environ is None else environ
    named = environ.get("RAY_ADDRESS", "").strip()
    if named:
        return named
    if address_file is None:
        address_file = _address_file()
    try:
        with open(address_file, encoding="utf-8") as f:
            address = f.read(200).strip()
    except (OSError, UnicodeDecodeError):
        return None
    host, _, port = address.rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or not _is_this_machine(host):
        return None
    try:
        with socket.create_connection((host, int(port)), timeout=ANSWER_SECONDS):
            pass
    except (OSError, ValueError):
        return None
    return address


def _address_file() -> str:
    """Ray's address file, where ``ray start`` records its cluster: Ray's default temp folder
    (``ray._common.utils.get_default_system_temp_dir``, mirrored here so that finding it
    imports no Ray): ``RAY_TMPDIR``, else ``TMPDIR`` on Linux, else ``/tmp``."""
    folder = os.environ.get("RAY_TMPDIR")
    if folder is None and sys.platform.startswith("linux"):
        folder = os.environ.get("TMPDIR")
    if folder is None:
        unix = sys.platform.startswith(("linux", "darwin"))
        folder = os.path.join(os.sep, "tmp") if unix else tempfile.gettempdir()
    return os.path.join(folder, "ray", "ray_current_cluster")


def _is_this_machine(host: str) -> bool:
    """Whether ``host`` is an address of this machine (a socket can bind to it)."""
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError):
        return False
    for family, kind, proto, _, address in infos:
        try:
            with socket.socket(family, kind, proto) as probe:
                probe.bind((address[0], 0))
            return True
        except OSError:
            continue
    return False


#: RayParams fields of a light head's agent ports: set, the raylet starts at once; left at 0,
#: it waits (blocking) until each agent has imported Ray, bound a port and written it in a
#: file (``WaitForPersistedPort``): a second or more on two busy cores, before any worker.
AGENT_PORTS = (
    "metrics_agent_port",
    "metrics_export_port",
    "dashboard_agent_listen_port",
    "runtime_env_agent_port",
)


@contextlib.contextmanager
def light_head() -> Iterator[None]:
    """While ``ray.init`` starts a local Ray, what a one-off run on this machine does not use
    is left out, and what it waits for is not waited for:

    - the autoscaler's monitor (a local cluster of a fixed size never scales) and the log
      monitor (``log_to_driver=False``: no worker log is streamed): two Python processes that
      import Ray;
    - the dashboard's head process (its API server: jobs, state, metrics pages), which Ray
      starts even with ``include_dashboard=False`` and which ``ray.init`` waits for before it
      starts the raylet;
    - the raylet's wait for its two agents (:data:`AGENT_PORTS`: free ports are given them).

    Ray's parameters and node are private and ``ray.init`` passes none of this: Ray's
    defaults are changed for the block only; a part whose layout differs is left as Ray has
    it (Ray then starts as usual)."""
    ports = dict(zip(AGENT_PORTS, free_ports(len(AGENT_PORTS)), strict=True))
    with contextlib.ExitStack() as stack:
        stack.enter_context(_light_params(ports))
        stack.enter_context(_no_api_server())
        stack.enter_context(_light_raylet(ports["dashboard_agent_listen_port"]))
        yield


@contextlib.contextmanager
def _light_params(ports: Mapping[str, int]) -> Iterator[None]:
    try:
        from ray._private import parameter

        original = parameter.RayParams.__init__
        fields = original.__code__.co_varnames
    except (ImportError, AttributeError):
        yield
        return
    if "no_monitor" not in fields or "include_log_monitor" not in fields:
        yield
        return
    known = all(name in fields for name in AGENT_PORTS)

    def init(self: Any, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("no_monitor", True)
        if kwargs.get("include_log_monitor") is None:
            kwargs["include_log_monitor"] = False
        if known and all(not kwargs.get(name) for name in AGENT_PORTS):
            kwargs.update(ports)
        original(self, *args, **kwargs)

    parameter.RayParams.__init__ = init  # type: ignore[method-assign]
    try:
        yield
    finally:
        parameter.RayParams.__init__ = original  # type: ignore[method-assign]


@contextlib.contextmanager
def _no_api_server() -> Iterator[None]:
    try:
        from ray._private.node import Node

        original = Node.start_api_server
    except (ImportError, AttributeError):
        yield
        return

    def skipped(self: Any, *args: Any, **kwargs: Any) -> None:
        return None

    Node.start_api_server = skipped  # type: ignore[method-assign]
    try:
        yield
    finally:
        Node.start_api_server = original  # type: ignore[method-assign]


#: What stands in for the raylet's two agents in a light head (see :func:`_light_raylet`): a
#: Python without site packages that waits, as Ray's agents do, until the raylet is gone (EOF
#: on the pipe the raylet gives it as stdin; else its parent's exit) or it is stopped.
IDLE_AGENT = (
    "import os, stat, sys, time\n"
    "parent = os.getppid()\n"
    "if stat.S_ISFIFO(os.fstat(0).st_mode):\n"
    "    sys.stdin.buffer.read()\n"
    "else:\n"
    "    while os.getppid() == parent:\n"
    "        time.sleep(1)\n"
)

#: The raylet's flags of its agents' commands.
AGENT_COMMANDS = ("--dashboard_agent_command=", "--runtime_env_agent_command=")


@contextlib.contextmanager
def _light_raylet(port: int) -> Iterator[None]:
    """The raylet of a light head: told the dashboard agent's listen port (Ray gives it to
    the agent only, and the raylet, told nothing, waits for the agent's port file), with an
    idle process (:data:`IDLE_AGENT`) for each of its agents. Ray's dashboard agent (metrics,
    logs and stats for the dashboard) and runtime-env agent (the environments of tasks that
    name one: meshcol's tasks in a Ray of their own inherit the run's environment) are Python
    processes that import Ray, about a second of CPU together, while the workers start."""
    try:
        from ray._private import ray_constants, services

        original = services.start_ray_process
        raylet = ray_constants.PROCESS_TYPE_RAYLET
    except (ImportError, AttributeError):
        yield
        return
    flag = "--dashboard_agent_listen_port"
    idle = subprocess.list2cmdline([sys.executable, "-S", "-c", IDLE_AGENT])

    def start(command: list[str], process_type: str, *args: Any, **kwargs: Any) -> Any:
        if process_type == raylet and not any(a.startswith(flag) for a in command):
            command = [*command, f"{flag}={port}"]
            command = [
                next((f"{name}{idle}" for name in AGENT_COMMANDS if a.startswith(name)), a)
                for a in command
            ]
        return original(command, process_type, *args, **kwargs)

    services.start_ray_process = start
    try:
        yield
    finally:
        services.start_ray_process = original


def free_ports(count: int, host: str = "127.0.0.1") -> list[int]:
    """``count`` distinct ports free on ``host`` now (bound together, then released)."""
    with contextlib.ExitStack() as stack:
        sockets = [stack.enter_context(socket.socket()) for _ in range(count)]
        for each in sockets:
            each.bind((host, 0))
        return [each.getsockname()[1] for each in sockets]


def task_payload(task: Any) -> bytes:
    """A task as it goes to a cluster's worker: pickled here, opened by :func:`in_worker` once
    the thread settings are in place (opening it imports numpy, whose OpenBLAS sizes its
    thread pool from the environment only then)."""
    return pickle.dumps(task, protocol=pickle.HIGHEST_PROTOCOL)


def in_worker(env: Mapping[str, str], payload: bytes | None = None) -> Any:
    """In a cluster's worker, before the task: the thread settings of ``env`` (the local
    pool's, :func:`~meshcol.decomposition.jobs.worker_env`) set in its environment, where the
    engine's OpenMP runtime and numpy read them as they load; then the task of ``payload``.

    Instead of a ``runtime_env``, for which Ray starts new workers (a Python process that
    imports Ray: about a second each on two cores), never the idle ones a ``ray start``
    cluster keeps ready. A worker serves one job (one run), so the settings are this run's."""
    os.environ.update(env)
    return None if payload is None else pickle.loads(payload)


def node_manager_address(ray: Any) -> str | None:
    """``host:port`` of the raylet of this driver's node in a joined cluster, or None (Ray
    Client, a node not found, another layout of Ray's node table)."""
    try:
        node_id = ray.get_runtime_context().get_node_id()
        for node in ray.nodes():
            if node.get("NodeID") == node_id and node.get("Alive"):
                return f"{node['NodeManagerAddress']}:{node['NodeManagerPort']}"
    except Exception:  # noqa: BLE001 - only a speed-up hangs on it: none is asked for
        return None
    return None


def prestart_workers(address: str, count: int, seconds: float = 1.0) -> bool:
    """Ask the raylet at ``address`` to start ``count`` idle Python workers for no job in
    particular (as ``ray start`` does when it starts), so that the next run finds workers
    that have imported Ray waiting (as this run did), instead of starting its own: workers
    serve one job and end with it. The raylet starts at most as many as it has free CPUs,
    and Ray's idle-worker rules apply to them (kept up to the node's free CPUs).

    Returns whether the raylet accepted; nothing is waited for but its answer (at most
    ``seconds``). Ray's gRPC layer is private: any other layout returns False."""
    try:
        from ray._private.grpc_utils import init_grpc_channel

        messages: Any = importlib.import_module("ray.core.generated.node_manager_pb2")
        service: Any = importlib.import_module("ray.core.generated.node_manager_pb2_grpc")
        request = messages.PrestartWorkersRequest(language="PYTHON", num_workers=count)
        request.runtime_env_info.serialized_runtime_env = "{}"  # none: the tasks' default
        channel = init_grpc_channel(address)
        try:
            service.NodeManagerServiceStub(channel).PrestartWorkers(request, timeout=seconds)
        finally:
            channel.close()
    except Exception:  # noqa: BLE001 - a speed-up for the next run only
        return False
    return True
