"""The one check of the run keywords of the public functions (``jobs``, ``timeout``,
``threads``), apart from the executors: ``check`` and ``inspect`` check them before any work
without importing the worker pool or Ray's code (a check that decomposes nothing never
needs them)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["check_run"]


def check_run(jobs: Any, timeout: Any = None, threads: Any = 0) -> None:
    """Raise ValueError, as the command line refuses them, for ``jobs`` below 1, a
    ``timeout`` that is not a finite number above 0, or ``threads`` below 0 (0: all cores):
    the one check of the public functions' run keywords (``check``, ``inspect``)."""
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be an integer of at least 1, got {jobs!r}")
    if timeout is not None and (
        isinstance(timeout, bool)
        or not isinstance(timeout, (int, float))
        or not math.isfinite(timeout)
        or timeout <= 0
    ):
        raise ValueError(f"timeout must be a finite number of seconds above 0, got {timeout!r}")
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 0:
        raise ValueError(
            f"threads must be an integer of at least 0 (0: all cores), got {threads!r}"
        )
