"""CI-native reports: JUnit XML and GitHub workflow commands, from one list of case records.

Every analysis report (check, sweep, inspect, hull, fit, decompose) describes its run as a
:class:`CiSuite` of neutral :class:`CiCase` records (``report.ci_suite()``): one case per body
or body pair, its outcome under the run's policy, a one-line message with the report's numbers,
the file it is about. This module renders that suite, and nothing else does:

- :func:`dumps_junit`: one ``<testsuite>`` per command run inside ``<testsuites>``, valid
  against the Jenkins xUnit plugin's ``junit-10.xsd`` (what Jenkins' ``junit`` step, dorny's
  test-reporter and mikepenz's action-junit-report read). That schema has no ``file``
  attribute on a test case, so the file is in the message and the details; cases are grouped
  by ``classname`` ``meshcol.COMMAND``.
- :func:`dumps_github`: ``::error file=PATH,title=...::MESSAGE`` per failure or error,
  ``::warning`` per warning, and a ``::notice`` summary, escaped by the runner's rules
  (:func:`escape_data`, :func:`escape_property`); paths relative to ``$GITHUB_WORKSPACE``
  (else the working folder). :func:`step_summary` is the Markdown table for
  ``$GITHUB_STEP_SUMMARY``.
"""

from __future__ import annotations

import math
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from meshcol.io.report import dumps_json

__all__ = [
    "OUTCOMES",
    "MAX_PASSED_CASES",
    "CiCase",
    "CiSuite",
    "dumps_junit",
    "dumps_github",
    "escape_data",
    "escape_property",
    "step_summary",
    "annotation_path",
    "number",
    "collapse_passed",
    "verdict_line",
]

#: Outcomes of a case, as JUnit has them.
OUTCOMES = ("passed", "failure", "error", "skipped")
#: Most passed cases of one kind written one by one; past this the passed cases of that kind
#: become one summary case (failures, errors and skipped cases are always written one by one),
#: so a 10,000-body scene's JUnit file stays a few megabytes that Jenkins loads in a second.
MAX_PASSED_CASES = 5000
#: Rows of failing cases in the GitHub step summary table.
SUMMARY_ROWS = 50


@dataclass(frozen=True)
class CiCase:
    """One test case: a body or a body pair of a report, judged by the run's policy.

    Attributes
    ----------
    name : str
        What the case is about, unique within its suite: ``crate <-> table``,
        ``props/crate.obj::crate``.
    classname : str
        Its group: ``meshcol.check``, ``meshcol.inspect``.
    outcome : str
        One of :data:`OUTCOMES`: ``failure`` (the policy fails on it), ``error`` (unusable
        input in a batch), ``skipped`` (ignored by the user's rules), else ``passed``.
    message : str
        One line with the report's numbers: ``penetrating: depth 0.0125, signed distance
        -0.0125``.
    file : str or None
        The file the case is about (as the report names it).
    kind : str or None
        The failure's type: the status, finding or limit (``penetrating``, ``not-watertight``,
        ``max-hausdorff``).
    details : str
        Further lines (``key: value``): the failure's text, or a passed case's output.
    time : float or None
        Seconds spent on the case, when the report measured them.
    warn : bool
        A passed case worth an annotation (a finding the policy does not fail on):
        ``::warning`` in the GitHub format.
    rules : tuple of str
        The ids of the registered rules the case breaks (:data:`CiSuite.rules`), the
        failing ones first (``("MC501",)``, ``("MC401", "MC405")``); empty when its kind is
        no registered rule (``max-hausdorff``) or nothing is broken.
    before : mapping or None
        The case as the ``--baseline`` report had it (``status``, ``depth``,
        ``distance``...), when there was a baseline and the case was in it.
    numbers : mapping
        The case's headline numbers by name (``depth``, ``distance``, ``signed_distance``),
        for summaries that compare them with ``before``.
    snapshot : str or None
        A picture of the case (``--snapshots``), as a link from the report.
    """

    name: str
    classname: str
    outcome: str = "passed"
    message: str = ""
    file: str | None = None
    kind: str | None = None
    details: str = ""
    time: float | None = None
    warn: bool = False
    rules: tuple[str, ...] = ()
    before: Mapping[str, Any] | None = None
    numbers: Mapping[str, Any] = field(default_factory=dict)
    snapshot: str | None = None

    def __post_init__(self) -> None:
        if self.outcome not in OUTCOMES:
            raise ValueError(f"outcome must be one of {', '.join(OUTCOMES)}, got {self.outcome!r}")


@dataclass(frozen=True)
class CiSuite:
    """One command run as a test suite.

    Attributes
    ----------
    command : str
        ``check``, ``sweep``, ``inspect``, ``hull``, ``fit`` or ``decompose``.
    cases : tuple of CiCase
    settings : mapping
        The run's settings (the JSON report's ``settings``), written as properties.
    seconds : float or None
        Time of the run; None: the sum of the cases' times.
    warnings : tuple of str
        The report's warnings (one line each).
    verdict : str
        The run's one-line verdict (``2 pairs violate --fail-on penetration``).
    units : str or None
        Length unit of the numbers.
    rules : mapping of str -> mapping
        The registered rules the command can report (``MC501`` -> the rule's fields as
        :meth:`meshcol.analysis.rules.Rule.to_dict` gives them), for formats that describe
        the rules they cite (SARIF).
    baseline : str or None
        The ``--baseline`` report the run compared with, as the user gave it.
    docs_url : str or None
        The docs' base URL from the configuration (``docs-url``), for the rules' links
        (SARIF ``helpUri``; ``$MESHCOL_DOCS_URL`` overrides it); None: not configured.
    """

    command: str
    cases: tuple[CiCase, ...]
    settings: Mapping[str, Any] = field(default_factory=dict)
    seconds: float | None = None
    warnings: tuple[str, ...] = ()
    verdict: str = ""
    units: str | None = None
    rules: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    baseline: str | None = None
    docs_url: str | None = None

    def count(self, outcome: str) -> int:
        return sum(1 for case in self.cases if case.outcome == outcome)

    @property
    def passed(self) -> bool:
        return not any(case.outcome in ("failure", "error") for case in self.cases)

    @property
    def time(self) -> float:
        if self.seconds is not None:
            return max(0.0, float(self.seconds))
        return sum(case.time or 0.0 for case in self.cases)


def number(value: Any, units: str | None = None) -> str:
    """A report number as messages write it: 6 significant digits, the unit after it,
    ``n/a`` for None or a non-finite value."""
    if value is None or isinstance(value, bool):
        return "n/a" if value is None else str(value).lower()
    value = float(value)
    if not math.isfinite(value):
        return "n/a"
    text = f"{value:.6g}"
    return f"{text} {units}" if units else text


def collapse_passed(
    cases: Sequence[CiCase], what: str, classname: str, limit: int = MAX_PASSED_CASES
) -> list[CiCase]:
    """``cases`` as they are when at most ``limit`` of them passed; else the failures, errors
    and skipped cases as they are and every passed case in one, ``what (N passed cases in
    one)``, that names the first and last of them (see :data:`MAX_PASSED_CASES`)."""
    passed = [case for case in cases if case.outcome == "passed"]
    if len(passed) <= limit:
        return list(cases)
    others = [case for case in cases if case.outcome != "passed"]
    seconds = [case.time for case in passed if case.time is not None]
    summary = CiCase(
        name=f"{what} ({len(passed)} passed cases in one)",
        classname=classname,
        message=f"{len(passed)} {what} passed; more than {limit}, written as one case "
        "(every one is in the JSON report)",
        details=f"first: {passed[0].name}\nlast: {passed[-1].name}",
        time=sum(seconds) if seconds else None,
    )
    return [*others, summary]


# ---------------------------------------------------------------------------------------------
# JUnit XML

# XML 1.0 characters (https://www.w3.org/TR/xml/#charsets): anything else (control characters,
# lone surrogates from undecodable file names, U+FFFE/U+FFFF) cannot be written, even escaped.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_text(text: Any) -> str:
    """``text`` as a string XML 1.0 can hold: characters it cannot are dropped (escaping
    ``<&"'`` is the serialiser's)."""
    return _NOT_XML.sub("", str(text))


def _seconds(value: float | None) -> str:
    """A time attribute (``SUREFIRE_TIME``: digits and a point, never an exponent)."""
    value = 0.0 if value is None or not math.isfinite(value) else max(0.0, float(value))
    return f"{value:.6f}"


def _property_value(value: Any) -> str:
    if isinstance(value, str):
        return value
    # control characters come out as \u escapes, which XML holds
    return dumps_json(value, compact=True, ascii_only=False)


def _properties(suite: CiSuite) -> list[tuple[str, str]]:
    from meshcol._version import __version__

    rows = [
        ("meshcol.version", __version__),
        ("meshcol.command", suite.command),
    ]
    if suite.units is not None:
        rows.append(("units", suite.units))
    rows += [(f"settings.{k}", _property_value(v)) for k, v in sorted(suite.settings.items())]
    return rows


def dumps_junit(suite: CiSuite) -> str:
    """JUnit XML text of ``suite``: ``<testsuites>`` holding one ``<testsuite>``.

    The suite is ``meshcol COMMAND`` with ``tests``, ``failures``, ``errors``, ``skipped`` and
    ``time``, ``<properties>`` (meshcol's version, the command, ``settings.*`` of the run,
    values other than strings as compact JSON), one ``<testcase>`` per case (``<failure>``,
    ``<error>`` or ``<skipped>`` with the message and type; the details as its text, or as
    ``<system-out>`` of a passed case) and the warnings as the suite's ``<system-err>``.
    Characters XML cannot hold are dropped; ``<&"'`` are escaped. Valid against Jenkins'
    ``junit-10.xsd`` (``tests/data/junit-10.xsd``).
    """
    tests = len(suite.cases)
    counts = {outcome: suite.count(outcome) for outcome in OUTCOMES}
    time = _seconds(suite.time)
    root = ET.Element(
        "testsuites",
        {
            "name": "meshcol",
            "tests": str(tests),
            "failures": str(counts["failure"]),
            "errors": str(counts["error"]),
            "time": time,
        },
    )
    element = ET.SubElement(
        root,
        "testsuite",
        {
            "name": f"meshcol {suite.command}",
            "tests": str(tests),
            "failures": str(counts["failure"]),
            "errors": str(counts["error"]),
            "skipped": str(counts["skipped"]),
            "time": time,
        },
    )
    properties = ET.SubElement(element, "properties")
    for name, value in _properties(suite):
        ET.SubElement(properties, "property", {"name": xml_text(name), "value": xml_text(value)})
    for case in suite.cases:
        attributes = {"name": xml_text(case.name), "classname": xml_text(case.classname)}
        if case.time is not None:
            attributes["time"] = _seconds(case.time)
        testcase = ET.SubElement(element, "testcase", attributes)
        if case.outcome == "passed":
            output = "\n".join(line for line in (case.message, case.details) if line)
            if output:
                ET.SubElement(testcase, "system-out").text = xml_text(output)
            continue
        child = ET.SubElement(
            testcase,
            "failure" if case.outcome == "failure" else case.outcome,
            {"message": xml_text(case.message)},
        )
        if case.kind is not None and case.outcome != "skipped":
            child.set("type", xml_text(case.kind))
        text = "\n".join(line for line in (case.message, _file_line(case), case.details) if line)
        child.text = xml_text(text)
    if suite.warnings:
        ET.SubElement(element, "system-err").text = xml_text("\n".join(suite.warnings))
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def _file_line(case: CiCase) -> str:
    return "" if case.file is None else f"file: {case.file}"


# ---------------------------------------------------------------------------------------------
# GitHub workflow commands


def escape_data(text: str) -> str:
    """A workflow command's message, escaped as the runner unescapes it (``%``, CR, LF)."""
    return str(text).replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def escape_property(text: str) -> str:
    """A workflow command's property value (``file=``, ``title=``): :func:`escape_data` and
    ``:`` and ``,``, which end a value."""
    return escape_data(text).replace(":", "%3A").replace(",", "%2C")


def annotation_path(path: str, workspace: str | None = None) -> str:
    """``path`` relative to ``workspace`` (``$GITHUB_WORKSPACE`` if set, else the working
    folder) with ``/`` separators, as an annotation's ``file=``; a path outside it stays
    absolute."""
    base = workspace if workspace is not None else os.environ.get("GITHUB_WORKSPACE") or "."
    full = os.path.abspath(path)
    try:
        relative = os.path.relpath(full, os.path.abspath(base))
    except ValueError:  # another drive (Windows)
        relative = full
    if relative == ".." or relative.startswith(".." + os.sep) or os.path.isabs(relative):
        relative = full
    return relative.replace(os.sep, "/")


def _command(kind: str, message: str, *, file: str | None, title: str) -> str:
    props = []
    if file is not None:
        props.append(f"file={escape_property(file)}")
    props.append(f"title={escape_property(title)}")
    return f"::{kind} {','.join(props)}::{escape_data(message)}"


def verdict_line(suite: CiSuite) -> str:
    """``PASS: 6 cases, 0 failures, 0 errors, 0 skipped`` and the report's verdict after it
    in parentheses: the last line of every CI format."""
    counts = {outcome: suite.count(outcome) for outcome in OUTCOMES}
    state = "PASS" if suite.passed else "FAIL"
    text = (
        f"{state}: {len(suite.cases)} cases, {counts['failure']} failures, {counts['error']} "
        f"errors, {counts['skipped']} skipped"
    )
    return f"{text} ({suite.verdict})" if suite.verdict else text


def dumps_github(suite: CiSuite, workspace: str | None = None) -> str:
    """GitHub workflow commands for ``suite``: one ``::error`` per failure or error case,
    ``::warning`` per case worth one and per report warning, then a ``::notice`` with the
    verdict and the counts. Each names its file (:func:`annotation_path`) and a title
    ``meshcol COMMAND: CASE``."""
    lines = []
    for case in suite.cases:
        if case.outcome in ("failure", "error"):
            kind = "error"
        elif case.warn:
            kind = "warning"
        else:
            continue
        file = None if case.file is None else annotation_path(case.file, workspace)
        message = case.message if case.file is None else f"{case.message} ({case.file})"
        lines.append(
            _command(kind, message, file=file, title=f"meshcol {suite.command}: {case.name}")
        )
    for warning in suite.warnings:
        lines.append(_command("warning", warning, file=None, title=f"meshcol {suite.command}"))
    lines.append(
        _command("notice", verdict_line(suite), file=None, title=f"meshcol {suite.command}")
    )
    return "\n".join(lines) + "\n"


def _cell(text: str) -> str:
    """A Markdown table cell: one line, ``|`` escaped, HTML inert."""
    text = " ".join(str(text).split())
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("|", "\\|")


def step_summary(suite: CiSuite, rows: int = SUMMARY_ROWS) -> str:
    """Markdown for ``$GITHUB_STEP_SUMMARY``: the verdict, the counts and the first ``rows``
    failing cases (outcome, case, file, message)."""
    counts = {outcome: suite.count(outcome) for outcome in OUTCOMES}
    lines = [
        f"### meshcol {suite.command}: {'PASS' if suite.passed else 'FAIL'}",
        "",
        "| cases | passed | failures | errors | skipped |",
        "| ---: | ---: | ---: | ---: | ---: |",
        f"| {len(suite.cases)} | {counts['passed']} | {counts['failure']} | {counts['error']} "
        f"| {counts['skipped']} |",
    ]
    bad = [case for case in suite.cases if case.outcome in ("failure", "error")]
    if bad:
        lines += ["", "| outcome | case | file | message |", "| --- | --- | --- | --- |"]
        for case in bad[:rows]:
            lines.append(
                f"| {case.outcome} | {_cell(case.name)} | {_cell(case.file or '')} | "
                f"{_cell(case.message)} |"
            )
        if len(bad) > rows:
            lines.append(f"\n{len(bad) - rows} more (every case is in the report)")
    return "\n".join(lines) + "\n\n"


def write_step_summary(suite: CiSuite) -> bool:
    """Append :func:`step_summary` to ``$GITHUB_STEP_SUMMARY`` when it is set; True if so."""
    path = os.environ.get("GITHUB_STEP_SUMMARY")
    if not path:
        return False
    with open(path, "a", encoding="utf-8") as f:
        f.write(step_summary(suite))
    return True


def details(pairs: Iterable[tuple[str, Any]]) -> str:
    """``key: value`` lines of the values that are not None (lists space-separated)."""
    lines = []
    for key, value in pairs:
        if value is None:
            continue
        if isinstance(value, (list, tuple)):
            value = " ".join(number(v) if isinstance(v, float) else str(v) for v in value)
        elif isinstance(value, float):
            value = number(value)
        lines.append(f"{key}: {value}")
    return "\n".join(lines)
