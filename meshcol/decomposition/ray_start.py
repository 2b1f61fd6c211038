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
import os
import socket
import sys
import tempfile
from collections.abc import Iterator, Mapping
from typing import Any

__all__ = ["LIGHT_INIT", "OWN_CLUSTER", "light_head", "running_cluster"]

#: ``--ray-address`` meaning "start a Ray of this run's own" (Ray's own word for it), never
#: the running one :func:`running_cluster` would find.
OWN_CLUSTER = "local"

#: Object store of a local Ray of meshcol's own (bytes): Ray's minimum is 75 MiB; its default
#: (30% of the memory) only reserves what a run never fills.
OBJECT_STORE_BYTES = 256 * 1024 * 1024

#: ``ray.init`` keywords of a local Ray of meshcol's own, besides the cluster's size.
LIGHT_INIT: Mapping[str, Any] = {
    "include_dashboard": False,
    "object_store_memory": OBJECT_STORE_BYTES,
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


@contextlib.contextmanager
def light_head() -> Iterator[None]:
    """While ``ray.init`` starts a local Ray: without the autoscaler's monitor (a local
    cluster of a fixed size never scales) and the log monitor (``log_to_driver=False``: no
    worker log is streamed), two Python processes that import Ray on a machine whose cores
    the run needs. Ray's parameters are private and ``ray.init`` passes neither: the
    defaults are changed for the block; if their layout differs, Ray starts as usual."""
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

    def init(self: Any, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("no_monitor", True)
        if kwargs.get("include_log_monitor") is None:
            kwargs["include_log_monitor"] = False
        original(self, *args, **kwargs)

    parameter.RayParams.__init__ = init  # type: ignore[method-assign]
    try:
        yield
    finally:
        parameter.RayParams.__init__ = original  # type: ignore[method-assign]
