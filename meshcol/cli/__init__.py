"""The ``meshcol`` command: a click group whose subcommands load on demand.

Errors are mapped to exit codes here and nowhere else:

- 0: ran and passed; 1: ran and found what the policy fails on;
- 2: a usage error or unusable input, reported as one line on stderr
  (``meshcol: error: FILE: problem``), with a traceback only under ``--debug``. click's own
  usage errors (unknown option, bad value, missing argument) get the same prefix and one
  line, never click's multi-line block.
- 130: interrupted (SIGINT, Ctrl-C); 143: terminated (SIGTERM). Both unwind the command
  (temporary files removed, worker processes stopped) before exiting, as a signal's default
  action would not.
"""

from __future__ import annotations

import contextlib
import importlib
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from typing import Any, NoReturn

import click

from meshcol._version import __version__
from meshcol.errors import MeshcolError

# command name -> "module:function". Modules import heavy dependencies inside the command
# function, never at module level, so `meshcol --help` stays fast.
COMMANDS: dict[str, str] = {
    "decompose": "meshcol.cli.decompose:decompose_command",
    "hull": "meshcol.cli.hull:hull",
    "fit": "meshcol.cli.fit:fit",
    "inspect": "meshcol.cli.inspect:inspect",
    "sweep": "meshcol.cli.sweep:sweep",
    "check": "meshcol.cli.check:check",
    "collision-matrix": "meshcol.cli.collision_matrix:collision_matrix",
    "targets": "meshcol.cli.targets:targets",
    "rules": "meshcol.cli.rules:rules",
    "ci": "meshcol.cli.ci:ci",
    "config": "meshcol.cli.config:config_command",
}

CONTEXT_SETTINGS = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


#: Young objects allocated between two cyclic collections while a command runs (Python's
#: default is 700): a run builds hundreds of thousands of long-lived containers (a report's
#: rows) and makes little cyclic garbage, and every default-rate collection walks them all,
#: 10-15% of ``check`` on 10,000 bodies.
GC_THRESHOLD = 100_000


@contextlib.contextmanager
def _collect_less_often() -> Iterator[None]:
    """The cyclic garbage collector at :data:`GC_THRESHOLD` for the block, then as it was."""
    import gc

    before = gc.get_threshold()
    gc.set_threshold(GC_THRESHOLD, *before[1:])
    try:
        yield
    finally:
        gc.set_threshold(*before)


class MeshcolGroup(click.Group):
    """A group that imports each subcommand on first use and maps errors to exit codes."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        target = COMMANDS.get(cmd_name)
        if target is None:
            return None
        module_name, attr = target.split(":")
        return getattr(importlib.import_module(module_name), attr)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list, each with its whole one-line description (never cut off)."""
        rows = []
        for name in self.list_commands(ctx):
            command = self.get_command(ctx, name)
            if command is not None and not command.hidden:
                rows.append((name, command.get_short_help_str(limit=1000)))
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        """Run the command line; usage errors become one ``meshcol: error:`` line, exit 2."""
        run = super().main
        if not standalone_mode:
            return run(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            with _collect_less_often():
                code = run(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.ClickException as exc:
            fail(usage_message(exc))
        except click.Abort:
            click.echo("meshcol: interrupted", err=True)
            sys.exit(130)
        # Without standalone mode click returns the command's value, or the code of an
        # explicit exit (--help, --version, ctx.exit(1)).
        sys.exit(code if isinstance(code, int) else 0)

    def invoke(self, ctx: click.Context) -> Any:
        debug = bool(ctx.params.get("debug"))
        from meshcol.io.staging import staged_outputs

        try:
            # every output of the command goes in place together at its end, or none does
            with _sigterm_raises(), staged_outputs():
                return super().invoke(ctx)
        except MeshcolError as exc:
            if debug:
                raise
            fail(str(exc))
        except OSError as exc:
            # Output folder missing, disk full, permission denied: unusable, not a crash.
            if debug:
                raise
            where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
            fail(f"{where}{exc.strerror or exc}")
        except MemoryError:
            # a result larger than memory (millions of overlapping pairs): unusable input
            if debug:
                raise
            fail("out of memory: the input needs more memory than this machine has")
        except KeyboardInterrupt:
            click.echo("meshcol: interrupted", err=True)
            sys.exit(130)
        except Terminated:
            click.echo("meshcol: terminated", err=True)
            sys.exit(143)


class Terminated(BaseException):
    """SIGTERM, raised in the main thread (like KeyboardInterrupt for SIGINT) so that the
    command unwinds: ``finally`` blocks and atomic writes clean up, workers are stopped."""


def _raise_terminated(signum: int, frame: Any) -> None:
    raise Terminated


@contextlib.contextmanager
def _sigterm_raises() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` during the block (main thread only; then restored)."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def usage_message(exc: click.ClickException) -> str:
    """click's error as one line: ``invalid value for '--jobs': 0 is not in the range x>=1
    (see 'meshcol decompose -h')``."""
    text = " ".join(exc.format_message().split()).rstrip(".")
    if text[:2].istitle() and not text[:2].isupper():
        text = text[0].lower() + text[1:]
    ctx = getattr(exc, "ctx", None)
    if ctx is not None:
        command = " ".join(["meshcol", *ctx.command_path.split()[1:]])
        text += f" (see '{command} -h')"
    return text


def fail(message: str) -> NoReturn:
    """Print ``meshcol: error: MESSAGE`` on stderr and exit 2."""
    click.echo(f"meshcol: error: {message}", err=True)
    sys.exit(2)


@click.group(cls=MeshcolGroup, context_settings=CONTEXT_SETTINGS)
@click.version_option(__version__, "--version", prog_name="meshcol")
@click.option("--debug", is_flag=True, help="Show full tracebacks on errors.")
@click.option(
    "--root",
    type=click.Path(file_okay=False, exists=True),
    default=None,
    metavar="DIR",
    help="Every path an input names (manifest meshes, URDF package:// and relative paths, "
    "glTF buffers, MJCF includes) must resolve inside DIR, symlinks followed; else exit 2 "
    "(also $MESHCOL_ROOT; 'meshcol ci' sets it to the repository).  [default: no limit]",
)
def main(debug: bool, root: str | None) -> None:
    """Mesh collision analysis for asset pipelines.

    \b
    Examples:
      meshcol check level/scene.json --report level.json     the main job: every pair
      meshcol check level.json --baseline last.json          fail only on what got worse
      meshcol inspect props/*.obj --fail-on not-watertight
      meshcol hull chair.obj --max-vertices 64 -o chair_hull.obj
      meshcol COMMAND -h      help and examples for one command
    """
    if root is not None:
        _set_root(root)


def _set_root(root: str) -> None:
    """``$MESHCOL_ROOT`` for the command and its worker processes, as it was afterwards."""
    import os

    from meshcol.io.paths import ROOT_ENV

    previous = os.environ.get(ROOT_ENV)
    os.environ[ROOT_ENV] = os.path.realpath(root)

    def restore() -> None:
        if previous is None:
            os.environ.pop(ROOT_ENV, None)
        else:
            os.environ[ROOT_ENV] = previous

    click.get_current_context().call_on_close(restore)
