"""Pieces shared by the commands: report options, checked numbers, output paths, progress."""

from __future__ import annotations

import contextlib
import math
import os
import re
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

import click

from meshcol.vocabulary import COLLIDER_KINDS

if TYPE_CHECKING:
    from meshcol.io.robot import RobotOptions

#: Seconds of work before a progress line appears (on a terminal or not).
PROGRESS_DELAY = 5.0
#: Seconds between progress lines when stderr is not a terminal (CI logs).
PROGRESS_INTERVAL = 5.0


class FiniteFloat(click.ParamType):
    """A finite number (never nan, inf or an overflow such as 1e309), within optional bounds.

    Parameters
    ----------
    min : float, optional
        Smallest value allowed (``min_open``: excluded).
    max : float, optional
        Largest value allowed (``max_open``: excluded).
    """

    name = "float"

    def __init__(
        self,
        min: float | None = None,
        max: float | None = None,
        min_open: bool = False,
        max_open: bool = False,
    ) -> None:
        self.min, self.max, self.min_open, self.max_open = min, max, min_open, max_open

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, float) and math.isfinite(value):
            number = value
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number", param, ctx)
            if not math.isfinite(number):
                self.fail(f"{value!r} is not a finite number", param, ctx)
        low = self.min is not None and (number <= self.min if self.min_open else number < self.min)
        high = self.max is not None and (number >= self.max if self.max_open else number > self.max)
        if low or high:
            self.fail(f"{number} is not in the range {self._range()}", param, ctx)
        return number

    def _range(self) -> str:
        """As click's ranges: ``x>=0``, ``x>0``, ``0<x<=1``."""
        low = "<" if self.min_open else "<="
        high = "<" if self.max_open else "<="
        if self.max is None:
            return f"x{'>' if self.min_open else '>='}{self.min:g}" if self.min is not None else "x"
        if self.min is None:
            return f"x{high}{self.max:g}"
        return f"{self.min:g}{low}x{high}{self.max:g}"

    def __repr__(self) -> str:
        return f"FiniteFloat({self._range()})"


def report_options(
    default: str = "the report on stdout",
    formats: Sequence[str] | None = None,
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--report FILE`` (``-`` for stdout) and ``--format FORMAT`` (parameter ``fmt``;
    the choices and their help from :data:`meshcol.io.formats.FORMATS`).

    Parameters
    ----------
    default : str
        Where the report goes without ``--report``, for the help text.
    formats : sequence of str, optional
        The formats the command writes (:func:`meshcol.io.formats.formats_for` of its
        report), when not every one: ``--help`` lists only those.
    """

    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        from meshcol.io.formats import REPORT_FORMATS, describe_formats

        choices = list(formats or REPORT_FORMATS)
        func = click.option(
            "--format",
            "fmt",
            type=click.Choice(choices),
            default=None,
            help=f"Report format: {describe_formats(choices)}",
        )(func)
        func = click.option(
            "--report",
            type=click.Path(dir_okay=False, allow_dash=True),
            default=None,
            metavar="FILE",
            help=f"Write the report to FILE ('-': stdout).  [default: {default}]",
        )(func)
        return func

    return decorate


def report_format(
    report: str | None,
    fmt: str | None,
    format_option: bool = True,
    option: str = "--format",
    formats: Sequence[str] | None = None,
) -> str:
    """The report's format, or a usage error for an unknown ``--report`` extension or a
    ``--format`` that contradicts it (``--report out.txt`` never silently writes JSON).
    ``format_option``: the command has ``option`` (the message suggests it); ``formats``:
    the formats the command writes (default every one,
    :data:`meshcol.io.formats.REPORT_FORMATS`; :func:`meshcol.io.formats.formats_for`)."""
    from meshcol.io.formats import REPORT_FORMATS
    from meshcol.io.formats import report_format as pick

    formats = tuple(formats or REPORT_FORMATS)
    try:
        chosen = pick(report, fmt)
    except ValueError as exc:
        hint = f" (or give {option} {'|'.join(formats)})" if format_option and fmt is None else ""
        raise click.BadParameter(f"{exc}{hint}", param_hint="'--report'") from None
    if chosen not in formats:
        raise click.BadParameter(
            f"{report!r} would be a {chosen} report: this command writes {' or '.join(formats)}",
            param_hint="'--report'",
        )
    return chosen


def no_report_with_meshes(fmt: str | None, report: str | None, meshes: bool) -> None:
    """A usage error for ``--format`` when the command writes meshes (``-o``, ``--out-dir``)
    and so, without ``--report``, no report at all: the format would silently do nothing."""
    if fmt is not None and report is None and meshes:
        raise click.UsageError(
            f"--format {fmt}: with -o/--out-dir no report is written unless --report FILE "
            "(or --report - for stdout) says where"
        )


def emit_report(result: Any, fmt: str, report: str | None) -> None:
    """Write ``result``'s report in ``fmt`` to ``report`` (stdout for None or ``-``)
    atomically, and what the format does after (:func:`meshcol.io.formats.write_report`)."""
    from meshcol.io.formats import write_report

    write_report(result, fmt, report)


_COUNT = re.compile(r"(\d+)/(\d+)")


class Progress:
    """The one progress display of every command: a callable that takes the library's
    one-line messages (``decompose: 3/10 files``, ``inspect: 12/40 bodies``).

    On a terminal the latest message is redrawn in place, with elapsed time and, for a
    message that counts ``N/M``, a bar and an estimate of the time left. On anything else
    (CI logs, pipes) a plain line is printed every :data:`PROGRESS_INTERVAL` seconds. Both
    start only after :data:`PROGRESS_DELAY` seconds, so short runs print nothing extra. A
    heartbeat thread repeats the latest message while the library is busy between two
    messages (a single 26 s file still shows that the run is alive).

    Off a terminal, the command line's progress (``stream`` left to its default) is silent
    unless the environment sets ``MESHCOL_PROGRESS=1``: a CI log then gets its lines, and
    otherwise a slow run that fails says one line, its error, on stderr.

    Parameters
    ----------
    stream : file, optional
        Defaults to ``sys.stderr`` (silent off a terminal without ``MESHCOL_PROGRESS=1``).
    delay, interval : float
        Seconds before the first message, and between lines off a terminal.
    clock : callable, optional
        Returns seconds (tests pass a fake clock).
    command : str, optional
        The command, prefixed to messages that do not start with it (``meshcol: check: ...``);
        the heartbeat says ``COMMAND: working`` before the first message.
    heartbeat : bool
        Start the heartbeat thread (off for a fake clock).
    """

    def __init__(
        self,
        stream: Any = None,
        delay: float = PROGRESS_DELAY,
        interval: float = PROGRESS_INTERVAL,
        clock: Callable[[], float] = time.perf_counter,
        command: str | None = None,
        heartbeat: bool = False,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.live = bool(getattr(self.stream, "isatty", lambda: False)())
        # stderr that is no terminal (a pipe, a log): no lines unless asked for
        self.silent = stream is None and not self.live and not progress_requested()
        self.clock = clock
        self.start = clock()
        self.delay = delay
        self.interval = interval
        self.last_line: float | None = None
        self.command = command
        self.last_text = None if command is None else "working"
        self.shown = False
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if heartbeat:
            self._thread = threading.Thread(target=self._beat, name="meshcol-progress", daemon=True)
            self._thread.start()

    def __call__(self, text: str) -> None:
        self.message(text)

    def _beat(self) -> None:
        period = min(self.interval, 1.0)
        while not self._stop.wait(period):
            if self.last_text is not None:
                self.message(self.last_text)

    def message(self, text: str) -> None:
        """Show ``text`` (redrawn on a terminal, a line every few seconds elsewhere)."""
        with self._lock:
            self.last_text = text
            now = self.clock()
            elapsed = now - self.start
            if elapsed < self.delay or self._stop.is_set() or self.silent:
                return
            if (
                not self.live
                and self.last_line is not None
                and now - self.last_line < self.interval
            ):
                return
            prefix = "meshcol: "
            if self.command is not None and not text.startswith(f"{self.command}:"):
                prefix += f"{self.command}: "
            line = f"{prefix}{text}{self._status(text, elapsed)}"
            if self.live:
                self.stream.write(f"\r\033[K{line}")
            else:
                self.stream.write(line + "\n")
                self.last_line = now
            self.stream.flush()
            self.shown = True

    def _status(self, text: str, elapsed: float) -> str:
        match = _COUNT.search(text)
        status = f" ({_duration(elapsed)} elapsed"
        time_left = getattr(text, "time_left", None)
        if time_left is not None:
            # the engine's own steps (meshcol.decomposition.steps): a number only once a
            # finished step justifies one, counted down at each redraw
            left = time_left()
            if left is not None:  # (a budget's steps are counted whole: the text says "at most")
                status += f", about {_duration(left[0])} left"
            match = None
        if match is not None:
            done, total = int(match.group(1)), int(match.group(2))
            if 0 < done < total:
                status += f", about {_duration(elapsed * (total - done) / done)} left"
            if self.live and total > 0:
                filled = round(20 * min(done, total) / total)
                status = f" [{'#' * filled}{'.' * (20 - filled)}]" + status
        return status + ")"

    def done(self) -> None:
        """Stop the heartbeat and clear the live line (off a terminal the lines stay)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            if self.shown and self.live:
                self.stream.write("\r\033[K")
                self.stream.flush()


def progress_requested() -> bool:
    """True when the environment asks for progress lines off a terminal
    (``MESHCOL_PROGRESS=1``, for CI logs)."""
    return os.environ.get("MESHCOL_PROGRESS", "").strip().lower() in ("1", "true", "yes", "on")


def _duration(seconds: float) -> str:
    seconds = max(0, round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    minutes, seconds = divmod(seconds, 60)
    if minutes < 60:
        return f"{minutes} min {seconds:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


def plural(count: int, noun: str, plural_form: str | None = None) -> str:
    """``1 body``, ``2 bodies``, ``0 pairs``."""
    if count == 1:
        return f"{count} {noun}"
    if plural_form is None:
        plural_form = (
            noun[:-1] + "ies" if noun.endswith("y") and noun[-2:-1] not in "aeiou" else noun + "s"
        )
    return f"{count} {plural_form}"


#: Rows of a summary table on stderr (the most penetrating pairs, the earliest contacts, the
#: pairs still checked): every row is in the report, the summary shows the first ones.
TABLE_ROWS = 10


def rows_left(shown: int, total: int) -> list[str]:
    """The line under a summary table that shows ``shown`` of ``total`` pairs, none when it
    shows them all."""
    if total <= shown:
        return []
    return [f"  ... {total - shown} more (every pair is in the report)"]


def verdict(command: str, passed: bool, detail: str) -> str:
    """The last summary line of every command: ``meshcol: check: PASS: ...`` or
    ``meshcol: check: FAIL: ...``."""
    return f"meshcol: {command}: {'PASS' if passed else 'FAIL'}: {detail}"


#: The robot flags of every command that takes a scene, in --help order.
_ROBOT_FLAGS = (
    click.option(
        "--joint",
        multiple=True,
        metavar="NAME=VALUE",
        help="Robot: one joint value (wins over --joints); repeatable.  [default: the default "
        "configuration, as MoveIt's: zero, or the middle of limits that exclude zero (MJCF: "
        "qpos0, or that middle when qpos0 is outside the limits); the same for every command]",
    ),
    click.option(
        "--joints",
        "joints_file",
        type=click.Path(dir_okay=False),
        default=None,
        metavar="FILE.json",
        help='Robot: joint values {"name": value} (radians, metres).  [default: none, every '
        "joint at the default configuration]",
    ),
    click.option(
        "--keyframe",
        is_flag=True,
        help="Robot (MJCF): start from the model's first keyframe instead of qpos0.",
    ),
    click.option(
        "--package-path",
        multiple=True,
        metavar="NAME=DIR",
        help="Robot: folder of package NAME for package:// URIs (before ROS_PACKAGE_PATH "
        "and the folders around the file); repeatable.  [default: none]",
    ),
)
#: The self-collision flags of the commands that check a robot's pairs.
_EXCLUSION_FLAGS = (
    click.option(
        "--srdf",
        type=click.Path(dir_okay=False),
        default=None,
        metavar="FILE",
        help="Robot: leave out the <disable_collisions> link pairs of this SRDF file.  "
        "[default: none, only adjacent links are left out]",
    ),
    click.option(
        "--include-adjacent",
        is_flag=True,
        help="Robot: also check pairs of links joined by a joint (left out by default).",
    ),
)


def robot_options(exclusions: bool = False) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add the options of a robot description input (URDF, MJCF) to a command that takes a
    scene: ``--joint NAME=VALUE`` (repeatable), ``--joints FILE.json``, ``--keyframe``,
    ``--package-path NAME=DIR`` (repeatable) and, with ``exclusions``, ``--srdf FILE`` and
    ``--include-adjacent``. The command gets them as one parameter, ``robot_options`` (a
    :class:`meshcol.io.robot.RobotOptions`), to pass to the library; they do nothing for
    other inputs, and a warning on stderr says so when some were given."""
    import functools

    flags = _ROBOT_FLAGS + (_EXCLUSION_FLAGS if exclusions else ())

    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(func)
        def run(*args: Any, **kwargs: Any) -> Any:
            made = _make_robot_options(
                kwargs.pop("joint"),
                kwargs.pop("joints_file"),
                kwargs.pop("keyframe"),
                kwargs.pop("package_path"),
                kwargs.pop("srdf", None),
                kwargs.pop("include_adjacent", False),
            )
            _warn_unused_robot_flags(made, kwargs.get("inputs") or [kwargs.get("manifest")])
            return func(*args, robot_options=made, **kwargs)

        wrapped: Callable[..., Any] = run
        for flag in reversed(flags):
            wrapped = flag(wrapped)
        return wrapped

    return decorate


def _warn_unused_robot_flags(options: RobotOptions, inputs: Sequence[Any]) -> None:
    """A warning on stderr naming the robot flags given when no input is a robot description
    (they would be ignored without a word)."""
    from meshcol.errors import MeshcolError
    from meshcol.io.inputs import is_robot_file

    given = [
        flag
        for flag, used in (
            ("--joint/--joints", bool(options.joints)),
            ("--keyframe", options.keyframe),
            ("--package-path", bool(options.package_paths)),
            ("--srdf", options.srdf is not None),
            ("--include-adjacent", options.include_adjacent),
        )
        if used
    ]
    paths = [path for path in inputs if path]
    if not given or not paths:
        return
    try:
        if any(is_robot_file(path) for path in paths):
            return
    except MeshcolError:
        return  # the command names what is wrong with its inputs
    click.echo(
        f"meshcol: warning: {', '.join(given)}: for a robot description (URDF, MJCF); no "
        "input is one, so ignored",
        err=True,
    )


def _make_robot_options(
    joint: tuple[str, ...],
    joints_file: str | None,
    keyframe: bool,
    package_path: tuple[str, ...],
    srdf: str | None,
    include_adjacent: bool,
) -> RobotOptions:
    """The RobotOptions of the flags; a malformed ``--joint`` or ``--package-path`` is a
    usage error naming the flag."""
    from meshcol.io.robot import RobotOptions, parse_joint_values, parse_package_paths

    try:
        joints = parse_joint_values(joint, joints_file)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--joint'") from None
    try:
        packages = parse_package_paths(package_path)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--package-path'") from None
    return RobotOptions(joints, keyframe, packages, srdf, include_adjacent)


def collider_option(
    help: str, choices: Sequence[str] = COLLIDER_KINDS
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--shape`` (parameter ``shape``): the collider of each body, one of ``choices``
    (:data:`meshcol.vocabulary.COLLIDER_KINDS`, or a command's subset), ``hull`` by default."""
    return click.option(
        "--shape",
        type=click.Choice(choices),
        default="hull",
        show_default=True,
        help=help,
    )


def target_option(help: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--target NAME|FILE.toml`` (parameter ``target``): an engine profile
    (:func:`meshcol.io.targets.load_target`), loaded before any work; an unknown name or a
    malformed file exits 2 with one line naming it."""

    def load(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
        if value is None:
            return None
        from meshcol.io.targets import load_target

        return load_target(value)

    return click.option(
        "--target",
        "target",
        metavar="NAME|FILE.toml",
        default=None,
        callback=load,
        help=help + "  [default: no target]",
    )


def html_option(func: Callable[..., Any]) -> Callable[..., Any]:
    """Add ``--html FILE``: the run's review page (:mod:`meshcol.io.review`). Without the
    viewer (``meshcol[review]``) the command exits 2 before any work, with the hint."""

    def ready(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
        if value is not None:
            from meshcol.io.review import viewer_script

            viewer_script()  # MissingDependencyError: exit 2, one line
        return value

    return click.option(
        "--html",
        type=click.Path(dir_okay=False),
        default=None,
        metavar="FILE",
        callback=ready,
        expose_value=True,
        help="Also write a self-contained 3D review page (offline HTML) to FILE; needs "
        "meshcol[review].  [default: none]",
    )(func)


def render_html(path: str | None, build: Callable[[], Any]) -> str | None:
    """The review page's HTML (``build()`` returns a :class:`meshcol.io.review.ReviewPage`),
    or None when ``path`` is None. Called before any output is written, so that a page over
    its limits (:class:`meshcol.io.review.ReviewTooLargeError`, exit 2) leaves no report."""
    if path is None:
        return None
    return str(build().to_html())


def write_html(path: str | None, text: str | None) -> None:
    """Write the page :func:`render_html` made to ``path`` atomically; says where on stderr."""
    if path is None or text is None:
        return
    from meshcol.io.paths import display_path
    from meshcol.io.report import atomic_write
    from meshcol.io.staging import once_written

    atomic_write(path, text)
    size = len(text.encode("utf-8"))
    once_written(
        lambda: click.echo(
            f"meshcol: review page: {display_path(path)} ({size / 1e6:.1f} MB)", err=True
        )
    )


def finish_outputs() -> None:
    """Put every output of the command in place, together, before its summary and verdict: a
    report, page or mesh that cannot be written (``--report /dev/full``) leaves none of the
    others and exits 2 naming it (:mod:`meshcol.io.staging`)."""
    from meshcol.io.staging import commit_outputs

    commit_outputs()


def snapshots_option(func: Callable[..., Any]) -> Callable[..., Any]:
    """Add ``--snapshots DIR``: one PNG per violation (:mod:`meshcol.io.snapshots`), linked
    from the Markdown report. Without Pillow (``meshcol[snapshots]``) the command exits 2
    before any work, with the hint."""

    def ready(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
        if value is not None:
            from meshcol.io.snapshots import pillow

            pillow()  # MissingDependencyError: exit 2, one line
        return value

    return click.option(
        "--snapshots",
        type=click.Path(file_okay=False),
        default=None,
        metavar="DIR",
        callback=ready,
        help="Also draw one PNG per violation into DIR (offscreen: the bodies framed, "
        "witness points, normal, depth), written with the report or not at all, and linked "
        "from --format markdown; needs meshcol[snapshots].  [default: none]",
    )(func)


@contextlib.contextmanager
def snapshots_written(
    result: Any, folder: str | None, report: str | None, build_page: Callable[[], Any]
) -> Iterator[Any]:
    """Yield the report to write: ``result`` itself, or with ``--snapshots`` the report
    whose CI cases link to their pictures, drawn into a staged folder that becomes
    ``folder`` only when the block (writing the report) succeeds
    (:func:`meshcol.io.outputs.staged_folder`): the pictures and the report appear together
    or not at all."""
    if folder is None:
        yield result
        return
    from meshcol.analysis.snapshots import with_snapshots
    from meshcol.io.outputs import staged_folder
    from meshcol.io.paths import display_path

    link_from = os.path.dirname(os.path.abspath(report)) if report and report != "-" else None
    with staged_folder(folder) as stage:
        written = with_snapshots(result, build_page(), stage, folder, link_from)
        yield written
    count = len(written.snapshots)
    click.echo(f"meshcol: snapshots: {count} in {display_path(folder)}", err=True)


def write_outputs(
    result: Any,
    build_page: Callable[[], Any],
    fmt: str,
    report: str | None,
    html: str | None,
    snapshots: str | None,
    emit: bool = True,
) -> None:
    """Every output of a run that writes a report, put in place together
    (:func:`finish_outputs`): the ``--html`` page rendered first (:func:`render_html`: a page
    over its limits leaves nothing), the report with its ``--snapshots``
    (:func:`snapshots_written`; no report when ``emit`` is False, as for meshes written
    without ``--report``), then the page."""
    page = render_html(html, build_page)
    with snapshots_written(result, snapshots, report, build_page) as written:
        if emit:
            emit_report(written, fmt, report)
    write_html(html, page)
    finish_outputs()


def executor_options() -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--executor local|ray`` and ``--ray-address ADDR`` (parameters ``executor`` and
    ``ray_address``): where a command's per-file tasks run
    (:mod:`meshcol.decomposition.executor`). ``--ray-address`` without ``--executor ray`` is
    a usage error."""

    def check_address(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
        if value is not None and ctx.params.get("executor", "local") != "ray":
            raise click.UsageError("--ray-address needs --executor ray", ctx=ctx)
        return value

    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        func = click.option(
            "--ray-address",
            default=None,
            metavar="ADDR",
            callback=check_address,
            help="Ray cluster to run on (ray://HOST:10001, HOST:6379, auto; local: a Ray "
            "of this run's own).  [default: $RAY_ADDRESS, else the Ray that 'ray start' left "
            "running on this machine, else a local Ray of --jobs CPUs on 127.0.0.1, stopped "
            "at the end]",
        )(func)
        func = click.option(
            "--executor",
            type=click.Choice(["local", "ray"]),
            default="local",
            show_default=True,
            is_eager=True,
            help="Where files are processed: local worker processes, or one Ray task per "
            "file (needs meshcol[ray]).",
        )(func)
        return func

    return decorate


def jobs_option(
    help_text: str, default: int | None = 1
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--jobs N`` / ``-j N`` (at least 1): files processed at once, one task each.
    ``default`` None: the command takes its default from elsewhere (the configuration's
    ``jobs``) and says so in ``help_text``."""
    return click.option(
        "--jobs",
        "-j",
        type=click.IntRange(min=1),
        default=default,
        show_default=default is not None,
        help=help_text,
    )


def timeout_option(
    help_text: str = "Seconds allowed per file; a file over it is stopped and reported.  "
    "[default: no limit]",
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--timeout SECONDS`` (> 0): the limit of one file's task."""
    return click.option(
        "--timeout", type=FiniteFloat(0, min_open=True), default=None, help=help_text
    )


def threads_option(
    help_text: str = "Threads for the native queries (0: all cores).",
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--threads N`` (0: all cores), the one definition of every command's option."""
    return click.option(
        "--threads", type=click.IntRange(min=0), default=0, show_default=True, help=help_text
    )


def engine_option(help_text: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--engine coacd|vhacd`` for the decompositions a command computes itself."""
    from meshcol.decomposition.engines import ENGINES

    return click.option(
        "--engine", type=click.Choice(ENGINES), default="coacd", show_default=True, help=help_text
    )


def cache_dir_option(
    help_text: str = "Decompose cache folder.  [default: the user cache, as 'meshcol decompose']",
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--cache-dir DIR``, the decompose cache a command reads (and fills)."""
    return click.option(
        "--cache-dir", type=click.Path(file_okay=False), default=None, help=help_text
    )


def to_option(what: str, gltf: bool = False) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Add ``--to urdf|mjcf|glb|usd`` (parameter ``to``): the format of a rebuilt robot
    description written with ``what`` (hull, decompose, fit); with ``gltf``, also
    ``gltf-physics`` (a glTF/GLB asset written back with its colliders)."""
    choices = ["urdf", "mjcf", "glb", "usd"] + (["gltf-physics"] if gltf else [])
    extra = (
        "; a glTF/GLB asset with --to gltf-physics: OUT/<asset>.glb, the asset with its "
        "colliders (KHR_physics_rigid_bodies and OMI_physics_body)"
        if gltf
        else ""
    )
    return click.option(
        "--to",
        "to",
        type=click.Choice(choices),
        default=None,
        help=f"Robot input (URDF, MJCF) with --out-dir: the format of the description written "
        f"with {what}, OUT/<robot>.urdf|.xml|.glb|.usda (usd needs meshcol[usd]){extra}.  "
        "[default: the input's]",
    )


def mesh_outputs(
    inputs: Sequence[str],
    output: str | None,
    out_dir: str | None,
    to: str | None,
    fmt: str | None,
    report: str | None,
) -> bool:
    """The usage checks of a command that writes meshes (hull, fit): ``-o`` or ``--out-dir``,
    a known mesh extension, ``--to`` only for a robot, a report format only with a report.
    Returns whether the run rebuilds one robot description (``--out-dir`` and a URDF/MJCF)."""
    from meshcol.io.inputs import is_robot_file
    from meshcol.io.mesh_write import MESH_OUTPUT_EXTENSIONS

    if output and out_dir:
        raise click.UsageError("give either -o/--output or --out-dir, not both")
    if output:
        extension = os.path.splitext(output)[1].lower()
        if extension not in MESH_OUTPUT_EXTENSIONS:
            raise click.BadParameter(
                f"unknown mesh extension {extension or '(none)'!r} in {output!r} "
                f"(expected {', '.join(MESH_OUTPUT_EXTENSIONS)})",
                param_hint="'-o' / '--output'",
            )
    if to == "gltf-physics":
        from meshcol.analysis.gltf_rebuild import is_gltf

        if out_dir is None or len(inputs) != 1 or not is_gltf(inputs[0]):
            raise click.UsageError("--to gltf-physics needs one glTF/GLB asset and --out-dir")
        no_report_with_meshes(fmt, report, True)
        return True
    robot = out_dir is not None and len(inputs) == 1 and is_robot_file(inputs[0])
    if to is not None and not robot:
        raise click.UsageError("--to needs one robot description (URDF, MJCF) and --out-dir")
    no_report_with_meshes(fmt, report, bool(output or out_dir))
    return robot
