"""Report formats: one registry from a format's name to its writer and its file extension.

Every command that writes a report (``--format``, decompose's ``--report-format``, the
``--report`` file's extension) reads this registry and nothing else: the choices, the help
text, which extension implies which format, which formats a report can be written in, and
the writing itself. A format is one :class:`ReportFormat` entry in :data:`FORMATS`; its
writer takes what one method of the report returns (``source``): the report's own JSON or
CSV text, or its CI suite (:meth:`ci_suite`, neutral :class:`meshcol.io.ci.CiCase`
records), so that a CI format is written for every command at once.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from meshcol.io import ci, markdown, sarif, tap
from meshcol.io.report import emit

__all__ = [
    "FORMATS",
    "REPORT_EXTENSIONS",
    "REPORT_FORMATS",
    "ReportFormat",
    "describe_formats",
    "formats_for",
    "report_format",
    "report_text",
    "write_report",
]


@dataclass(frozen=True)
class ReportFormat:
    """One way to write a command's report.

    Attributes
    ----------
    name : str
        The ``--format`` value.
    extension : str or None
        The ``--report`` extension that implies it (``.json``), lower case; None when no
        file name says it (``github``: workflow commands are read from the log).
    source : str
        The report's method whose result ``render`` takes: ``to_json`` and ``to_csv`` give
        the text itself, ``ci_suite`` the run as a :class:`meshcol.io.ci.CiSuite`. A report
        without that method cannot be written in this format (:func:`formats_for`).
    render : callable
        That result to the text written.
    note : str
        A few words for the help text (``JUnit XML for Jenkins ...``); empty when the name
        says it all.
    after : callable or None
        Called with the same result once the text is written (``github`` appends its
        Markdown summary to ``$GITHUB_STEP_SUMMARY``).
    stream : str or None
        A report method giving the same text in pieces (``json_pieces``: strings and
        :class:`~meshcol.io.report.RowsPiece`), which :func:`write_report` writes one after
        another when the report has it (a check report of a million pairs is never one
        string: its rows go from the core's row writer into the file).
    """

    name: str
    extension: str | None
    source: str
    render: Callable[[Any], str]
    note: str = ""
    after: Callable[[Any], object] | None = None
    stream: str | None = None


#: Every report format, in the order help texts and messages list them.
FORMATS: dict[str, ReportFormat] = {
    entry.name: entry
    for entry in (
        ReportFormat("json", ".json", "to_json", str, stream="json_pieces"),
        ReportFormat("csv", ".csv", "to_csv", str),
        ReportFormat(
            "junit",
            ".xml",
            "ci_suite",
            ci.dumps_junit,
            note="JUnit XML for Jenkins and GitHub test reporters",
        ),
        ReportFormat(
            "github",
            None,
            "ci_suite",
            ci.dumps_github,
            note="workflow-command annotations",
            after=ci.write_step_summary,
        ),
        ReportFormat(
            "tap",
            ".tap",
            "ci_suite",
            tap.dumps_tap,
            note="Test Anything Protocol 14",
        ),
        ReportFormat(
            "sarif",
            ".sarif",
            "ci_suite",
            sarif.dumps_sarif,
            note="SARIF 2.1.0 for GitHub code scanning",
        ),
        ReportFormat(
            "markdown",
            ".md",
            "ci_suite",
            markdown.dumps_markdown,
            note="a pull-request comment: what is new or worse, per rule and per case",
        ),
    )
}
#: The format names (``--format`` choices).
REPORT_FORMATS = tuple(FORMATS)
#: Report file extensions and the format each means.
REPORT_EXTENSIONS = {f.extension: f.name for f in FORMATS.values() if f.extension is not None}


def _either(items: Sequence[str]) -> str:
    """``a, b or c``."""
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} or {items[-1]}"


def describe_formats(formats: Sequence[str] | None = None) -> str:
    """The formats for a help text: ``json, csv, junit (JUnit XML for ...) or github (...)``,
    then the default: ``[default: from the --report extension (.json, ...), else json]``.
    ``formats``: only those (default every one)."""
    chosen = [f for f in FORMATS.values() if formats is None or f.name in formats]
    names = [f"{f.name} ({f.note})" if f.note else f.name for f in chosen]
    extensions = ", ".join(
        e for e, name in REPORT_EXTENSIONS.items() if name in (formats or FORMATS)
    )
    return f"{_either(names)}.  [default: from the --report extension ({extensions}), else json]"


def formats_for(report_type: type) -> tuple[str, ...]:
    """The formats a report of ``report_type`` can be written in: those whose ``source``
    method it has (the rules registry has no CI suite: JSON and CSV only)."""
    return tuple(f.name for f in FORMATS.values() if callable(getattr(report_type, f.source, None)))


def report_format(path: str | None, fmt: str | None) -> str:
    """The report format: ``fmt`` if given, else from ``path``'s extension, else ``json``.

    Raises
    ------
    ValueError
        ``path`` has an extension no format has (:data:`REPORT_EXTENSIONS`) and no ``fmt``
        says what to write (``out.txt`` never silently gets JSON), or ``fmt`` contradicts it
        (``--format csv`` with ``out.json``, ``--format github`` with ``out.xml``).
    """
    extension = os.path.splitext(path)[1].lower() if path and path != "-" else ""
    implied = REPORT_EXTENSIONS.get(extension)
    if fmt:
        fmt = fmt.lower()
        if implied is not None and implied != fmt:
            raise ValueError(f"{path!r} is a .{implied} file: it cannot hold a {fmt} report")
        return fmt
    if extension and implied is None:
        raise ValueError(
            f"unknown report extension {extension!r} in {path!r}: expected "
            f"{_either(list(REPORT_EXTENSIONS))}"
        )
    return implied or "json"


def _entry(fmt: str) -> ReportFormat:
    try:
        return FORMATS[fmt]
    except KeyError:
        raise ValueError(
            f"report format must be one of {', '.join(REPORT_FORMATS)}, got {fmt!r}"
        ) from None


def report_text(report: Any, fmt: str) -> str:
    """The text of a command's report in ``fmt`` (one of :data:`REPORT_FORMATS`)."""
    entry = _entry(fmt)
    return entry.render(getattr(report, entry.source)())


def write_report(report: Any, fmt: str, output: str | os.PathLike[str] | None) -> None:
    """Write ``report`` in ``fmt`` to ``output`` atomically (stdout for None or ``-``), then
    run the format's ``after`` (``github``: the step summary, when
    ``$GITHUB_STEP_SUMMARY`` is set)."""
    entry = _entry(fmt)
    pieces = getattr(report, entry.stream, None) if entry.stream else None
    if pieces is not None and entry.after is None:
        emit(pieces(), output)
        return
    source = getattr(report, entry.source)()
    emit(entry.render(source), output)
    if entry.after is not None:
        entry.after(source)
