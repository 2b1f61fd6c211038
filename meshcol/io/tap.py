"""TAP, the Test Anything Protocol (version 14), of a command's CI suite.

TAP is the plain-text test stream that Perl's ``prove``, node-tap and the ``tap-*`` reporters,
Jenkins' TAP plugin and many shell-based pipelines read (https://testanything.org,
``tap-version-14-specification``). One test point per case of the report's
:class:`~meshcol.io.ci.CiSuite`, numbered from 1 after the plan:

- ``ok N - NAME`` for a passed case, ``not ok N - NAME`` for a failure or an error,
  ``ok N - NAME # SKIP MESSAGE`` for a case the user's rules ignore;
- after a failure, an error or a case worth a warning, a YAML block (two spaces in, between
  ``---`` and ``...``) with its ``message``, ``severity`` (``fail``, ``error`` or
  ``warning``), ``type``, ``file`` and ``details``, each value a double-quoted scalar
  (JSON's string escapes are YAML's);
- the report's warnings and the verdict as ``#`` comment lines at the end.

A name or message is kept on its line: line breaks and other control characters become
spaces, and ``\\`` and ``#`` are escaped as TAP 14 says (``#`` would start a directive).
"""

from __future__ import annotations

import re

from meshcol.io.ci import CiCase, CiSuite, verdict_line
from meshcol.io.report import dumps_json

__all__ = ["dumps_tap"]

#: Characters a TAP line cannot hold: control characters (tab aside) and lone surrogates
#: (undecodable file names), which no UTF-8 text can.
_NOT_LINE = re.compile("[\x00-\x08\x0a-\x1f\x7f\ud800-\udfff]")
#: A failure's or an error's YAML ``severity``.
_SEVERITY = {"failure": "fail", "error": "error"}


def _line(text: str) -> str:
    """``text`` on one TAP line: control characters as spaces, ``\\`` and ``#`` escaped."""
    return _NOT_LINE.sub(" ", str(text)).replace("\\", "\\\\").replace("#", "\\#")


def _comment(text: str) -> str:
    """``text`` as a comment line (``#`` needs no escape there)."""
    return "# " + _NOT_LINE.sub(" ", str(text))


def _test_point(number: int, case: CiCase) -> str:
    state = "not ok" if case.outcome in ("failure", "error") else "ok"
    line = f"{state} {number} - {_line(case.name)}"
    if case.outcome == "skipped":
        line += f" # SKIP {_line(case.message)}" if case.message else " # SKIP"
    return line


def _diagnostics(case: CiCase) -> list[str]:
    """The YAML block after a failure, an error or a case worth a warning; none otherwise."""
    severity = _SEVERITY.get(case.outcome, "warning" if case.warn else None)
    if severity is None:
        return []
    lines = ["  ---"]
    if case.message:
        lines.append(f"  message: {dumps_json(case.message, compact=True)}")
    lines.append(f"  severity: {severity}")
    for key, value in (("type", case.kind), ("file", case.file), ("details", case.details)):
        if value:
            lines.append(f"  {key}: {dumps_json(value, compact=True)}")
    return [*lines, "  ..."]


def dumps_tap(suite: CiSuite) -> str:
    """TAP 14 text of ``suite``: the version line, the plan ``1..N``, one test point per case
    (with a YAML block after each failure, error and warned case), the report's warnings and
    the verdict as comments. A suite of no case is a plan of ``1..0 # SKIP`` (TAP's "nothing
    to test")."""
    plan = f"1..{len(suite.cases)}" if suite.cases else "1..0 # SKIP no cases to judge"
    lines = ["TAP version 14", plan]
    for number, case in enumerate(suite.cases, start=1):
        lines.append(_test_point(number, case))
        lines += _diagnostics(case)
    lines += [_comment(f"warning: {warning}") for warning in suite.warnings]
    lines.append(_comment(f"meshcol {suite.command}: {verdict_line(suite)}"))
    return "\n".join(lines) + "\n"
