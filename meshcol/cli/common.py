"""Pieces shared by the commands: report options and a progress line."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any

import click


def report_options(
    default: str = "the report on stdout",
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--report FILE`` (``-`` for stdout) and ``--format json|csv`` (parameter ``fmt``).

    Parameters
    ----------
    default : str
        Where the report goes without ``--report``, for the help text.
    """

    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        func = click.option(
            "--format",
            "fmt",
            type=click.Choice(["json", "csv"]),
            default=None,
            help="Report format (default: from the --report extension, else json).",
        )(func)
        func = click.option(
            "--report",
            type=click.Path(dir_okay=False, allow_dash=True),
            default=None,
            metavar="FILE",
            help=f"Write the report to FILE ('-': stdout). Default: {default}.",
        )(func)
        return func

    return decorate


class Progress:
    """Progress messages on stderr, shown only on a terminal and only after one second.

    Parameters
    ----------
    stream : file, optional
        Defaults to ``sys.stderr``.
    delay : float
        Seconds before the first message is shown.
    """

    def __init__(self, stream: Any = None, delay: float = 1.0) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.delay = delay
        self.shown = False

    def message(self, text: str) -> None:
        if not self.enabled or time.perf_counter() - self.start < self.delay:
            return
        self.stream.write(f"\r\033[K{text}")
        self.stream.flush()
        self.shown = True

    def done(self) -> None:
        if self.shown:
            self.stream.write("\r\033[K")
            self.stream.flush()
