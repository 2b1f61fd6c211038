"""``meshcol ci``: every configured inspect, hull, fit and check of a repository, one verdict."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from typing import Any

import click

from meshcol.cli.common import Progress, jobs_option, plural, snapshots_option, verdict
from meshcol.cli.config import settings_options

#: The file name of each format under ``--outputs DIR`` (its extension from the registry).
OUTPUT_STEM = "meshcol-ci"


def _parse_outputs(
    ctx: click.Context, param: click.Parameter, value: tuple[str, ...]
) -> tuple[tuple[str, str], ...]:
    from meshcol.analysis.ci_report import CiReport
    from meshcol.io.formats import formats_for

    names = formats_for(CiReport)
    out = []
    for item in value:
        name, sep, file = item.partition("=")
        if not sep or not file or name not in names:
            raise click.BadParameter(
                f"{item!r}: expected FORMAT=FILE with FORMAT one of {', '.join(names)}", ctx, param
            )
        out.append((name, file))
    return tuple(out)


def output_files(
    report: str | None,
    junit: str | None,
    github: bool,
    outputs: tuple[tuple[str, str], ...],
    out_dir: str | None,
) -> list[tuple[str, str | None]]:
    """``(format, file)`` of every output asked for (None: stdout): ``--report`` (JSON),
    ``--junit``, ``--github`` (stdout), each ``--output FORMAT=FILE`` and, with ``--outputs
    DIR``, every format of the registry the report can be written in that has a file
    extension (:func:`meshcol.io.formats.formats_for`), as ``DIR/meshcol-ci<ext>``."""
    from meshcol.analysis.ci_report import CiReport
    from meshcol.io.formats import FORMATS, formats_for

    files: list[tuple[str, str | None]] = []
    if report is not None:
        files.append(("json", None if report == "-" else report))
    if junit is not None:
        files.append(("junit", junit))
    files += list(outputs)
    if out_dir is not None:
        for name in formats_for(CiReport):
            extension = FORMATS[name].extension
            if extension is not None:
                files.append((name, os.path.join(out_dir, OUTPUT_STEM + extension)))
    if github:
        files.append(("github", None))
    return files


@click.command(
    "ci", short_help="Every configured check of a repository: one verdict, every format."
)
@settings_options
@click.option(
    "--root",
    type=click.Path(file_okay=False, exists=True),
    default=None,
    metavar="DIR",
    help="Every path a file names (manifest meshes, URDF package:// and relative paths, "
    "glTF buffers, MJCF includes) must resolve inside DIR, symlinks followed; else exit 2.  "
    "[default: the config's root, else the git repository's top folder, else the config's "
    "folder]",
)
@click.option(
    "--changed-since",
    metavar="REF",
    default=None,
    help="Run only what changed since the git REF (git diff --name-only REF, and untracked "
    "files): the assets changed and the scenes that read a changed file.  [default: all]",
)
@click.option(
    "--cache-dir",
    default=None,
    metavar="DIR|URL",
    help="Result cache (a folder or an fsspec URL; the store of the decompose cache).  "
    "[default: the config's cache-dir, else the user cache]",
)
@click.option("--no-cache", is_flag=True, help="Neither read nor write the result cache.")
@jobs_option(
    "Jobs run at once, each a task in a worker process (1: all in this process).  "
    "[default: the config's jobs, else 1]",
    default=None,
)
@click.option(
    "--report",
    type=click.Path(dir_okay=False, allow_dash=True),
    default=None,
    metavar="FILE",
    help="The JSON report (every job's report; '-': stdout).  [default: none]",
)
@click.option(
    "--junit",
    type=click.Path(dir_okay=False),
    default=None,
    metavar="FILE",
    help="JUnit XML of every job.  [default: none]",
)
@click.option("--github", is_flag=True, help="GitHub workflow annotations on stdout.")
@click.option(
    "--output",
    "outputs",
    multiple=True,
    metavar="FORMAT=FILE",
    callback=_parse_outputs,
    help="One more output in any report format (meshcol's registry); repeatable.  [default: none]",
)
@click.option(
    "--outputs",
    "out_dir",
    type=click.Path(file_okay=False),
    default=None,
    metavar="DIR",
    help="Every report format with a file extension, as DIR/meshcol-ci.EXT.  [default: none]",
)
@snapshots_option
def ci(
    config: Any,
    overrides: dict,
    root: str | None,
    changed_since: str | None,
    cache_dir: str | None,
    no_cache: bool,
    jobs: int | None,
    report: str | None,
    junit: str | None,
    github: bool,
    outputs: tuple[tuple[str, str], ...],
    out_dir: str | None,
    snapshots: str | None,
) -> None:
    """Run every inspect, hull, fit and check the configuration asks for, over the
    repository, as one job: one verdict, one exit code, every output at once.

    The configuration (meshcol.toml, or [tool.meshcol] in pyproject.toml, found from the
    working folder upwards; 'meshcol config' shows it) says which files are assets (per-glob
    sections: the commands, collider, target, tolerances, fail-on rules, ignored rules or
    pairs with a reason, the baseline) and which are scenes (manifests, levels, robots).
    Flags (--set, --shape, --target) override it.

    Each job's result is cached by its file's content, the files it read, its settings and
    meshcol's version (the decompose cache's store): a re-run after one asset changed runs
    that asset and the scenes that read it, nothing else; the report is the same bytes as a
    cold run's. Paths named by files must stay inside --root. Exit 0 when every job passes,
    1 when one fails its policy, 2 when an input is unusable or names a path outside the
    root.

    \b
    Examples:
      meshcol ci --report ci.json --junit ci.xml --github
      meshcol ci --changed-since origin/main --outputs reports/
      meshcol ci -j 2 --cache-dir s3://bucket/meshcol-cache
      meshcol ci --set shape=decomposed --set check.clearance=0.01
      meshcol ci --output markdown=pr/comment.md --snapshots pr/
    """
    from meshcol.analysis.ci import changed_files, repository_root, run_ci
    from meshcol.io.config import run_settings
    from meshcol.io.formats import write_report
    from meshcol.io.outputs import check_outputs

    workers = run_settings(config, {"jobs": (jobs, "flag -j")})["jobs"][0]

    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
    files = output_files(report, junit, github, outputs, out_dir)
    named = {f"--output {fmt}": file for fmt, file in files if file is not None}
    check_outputs(files=named, folders={"--outputs": out_dir, "--snapshots": snapshots})
    changed = None if changed_since is None else changed_files(config.folder, changed_since)
    if root is None and config.data.get("root") is None:
        root = repository_root(config.folder)
    progress = Progress(command="ci", heartbeat=True)
    try:
        result = run_ci(
            config,
            overrides=overrides,
            root=root,
            changed=changed,
            changed_since=changed_since,
            cache_dir=cache_dir,
            use_cache=not no_cache,
            jobs=workers,
            progress=progress,
            snapshots=snapshots is not None,
        )
    finally:
        progress.done()
    with _with_snapshots(result, snapshots, files) as written:
        for fmt, file in files:
            write_report(written, fmt, file)
    for run, code in zip(result.runs, result.exit_codes):
        if code == 1:
            click.echo(f"meshcol: fail: {run.job.label}: {_run_verdict(run)}", err=True)
    for error in result.errors:
        click.echo(f"meshcol: error: {error}", err=True)
    detail = result.verdict() + f"; {plural(result.cached, 'job')} from the cache"
    click.echo(verdict("ci", result.exit_code == 0, detail), err=True)
    sys.exit(result.exit_code)


@contextlib.contextmanager
def _with_snapshots(
    result: Any, folder: str | None, files: list[tuple[str, str | None]]
) -> Iterator[Any]:
    """The report to write: ``result``, or with ``--snapshots`` the report whose cases link
    to their pictures, drawn into a staged folder that becomes ``folder`` with the reports
    written in the block, or not at all. Links are relative to the Markdown output's
    folder (the working folder when it goes to stdout or is not asked for)."""
    if folder is None:
        yield result
        return
    from meshcol.analysis.ci_snapshots import ci_snapshots
    from meshcol.io.outputs import staged_folder
    from meshcol.io.paths import display_path

    markdown = [file for fmt, file in files if fmt == "markdown" and file is not None]
    link_from = os.path.dirname(os.path.abspath(markdown[0])) if markdown else None
    with staged_folder(folder) as stage:
        written = ci_snapshots(result, stage, folder, link_from)
        yield written
    count = len(written.snapshots)
    click.echo(f"meshcol: snapshots: {count} in {display_path(folder)}", err=True)


def _run_verdict(run: Any) -> str:
    return str(run.result.get("suite", {}).get("verdict") or "fails its policy")
