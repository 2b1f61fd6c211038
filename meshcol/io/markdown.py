"""Markdown for a pull-request comment: what a change broke, per rule and per pair.

Written from a report's CI suite (:class:`meshcol.io.ci.CiSuite`), like JUnit and SARIF, so
every command that has one writes it (``--format markdown``). The comment is, in order:

1. the verdict line: ``### ❌ meshcol check: FAIL`` (or ``✅ ... PASS``) and the run's verdict;
2. with a ``--baseline``, how many failing cases are new and how many got worse;
3. a table per rule: failing cases (new, worse), spared by ``--ignore``, warnings;
4. a table of the failing cases, new first, then worse, each with its rule, the pair or asset,
   the file, the numbers (``depth 0.01 → 0.025 m``: the baseline's, then this run's) and a
   link to its snapshot (``--snapshots``); at most :data:`TABLE_ROWS` rows, then a line
   ``… and N more``;
5. unusable inputs, and the run's warnings (at most :data:`TABLE_ROWS` of each).

Cells are one line, with ``|``, backticks, ``<`` and ``>`` escaped, so that a body named like
Markdown or HTML cannot break the table or inject markup.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

from meshcol.io.ci import CiCase, CiSuite, number

__all__ = ["TABLE_ROWS", "dumps_markdown", "change"]

#: Most rows of a table before ``… and N more``: a PR comment stays readable (and under
#: GitHub's 65,536-character limit) whatever the run found.
TABLE_ROWS = 25
#: The numbers compared with the baseline, in the order shown.
NUMBERS = ("depth", "distance")

_SPECIAL = re.compile(r"([\\`*_\[\]|<>#])")


def _cell(text: Any) -> str:
    """One table cell: one line, Markdown's and HTML's special characters escaped."""
    return _SPECIAL.sub(r"\\\1", " ".join(str(text).split())) or " "


def _rule_label(rule_id: str, rules: Mapping[str, Mapping[str, Any]]) -> str:
    rule = rules.get(rule_id)
    return f"{rule_id} {rule['name']}" if rule else rule_id


def _case_rule(case: CiCase) -> str:
    return case.rules[0] if case.rules else (case.kind or case.outcome)


def change(case: CiCase) -> str:
    """``new`` (not in the baseline, or no baseline), ``worse`` (in it, and worse now)."""
    return "new" if case.before is None else "worse"


def _numbers(case: CiCase, units: str | None) -> str:
    """``depth 0.01 → 0.025 m`` per number the case has (the baseline's value first, ``—``
    where it had none); the status too when it changed; else the case's message."""
    before = case.before or {}
    parts = []
    if case.before is not None and before.get("status") and before.get("status") != case.kind:
        parts.append(f"{before['status']} → {case.kind}")
    deep = bool(case.numbers.get("depth") or before.get("depth"))
    for key in NUMBERS:
        after = case.numbers.get(key)
        old = before.get(key) if case.before is not None else None
        if after is None and old is None:
            continue
        if (key == "depth") != deep:  # a depth, or else the distance: the one that matters
            continue
        if case.before is None:
            parts.append(f"{key} {number(after, units)}")
        else:
            parts.append(f"{key} {number(old)} → {number(after, units)}")
    return "; ".join(parts) if parts else case.message


def _snapshot(case: CiCase) -> str:
    path = case.snapshot
    if not path:
        return " "
    return f"[png]({_link(path)})"


def _link(path: str) -> str:
    """A relative link target: spaces and parentheses escaped (``%20``), slashes kept."""
    return re.sub(r"[ ()<>]", lambda m: f"%{ord(m.group()):02X}", path.replace("\\", "/"))


def _more(count: int, what: str) -> list[str]:
    return ["", f"… and {count} more {what} (every one is in the report)"] if count > 0 else []


def _rule_table(suite: CiSuite, failing: Sequence[CiCase], baseline: bool) -> list[str]:
    counts: dict[str, dict[str, int]] = {}
    for case in suite.cases:
        if case.outcome == "error":
            continue
        key = _case_rule(case)
        row = counts.setdefault(key, {"failing": 0, "new": 0, "worse": 0, "ignored": 0, "warn": 0})
        if case.outcome == "failure":
            row["failing"] += 1
            row[change(case)] += 1
        elif case.outcome == "skipped":
            row["ignored"] += 1
        elif case.warn:
            row["warn"] += 1
    rows = {k: v for k, v in counts.items() if any(v.values())}
    if not rows:
        return []
    header = ["rule", "failing", *(["new", "worse"] if baseline else []), "ignored", "warnings"]
    lines = ["", "| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    order = sorted(rows, key=lambda k: (-rows[k]["failing"], k))
    for key in order[:TABLE_ROWS]:
        row = rows[key]
        cells = [_cell(_rule_label(key, suite.rules)), str(row["failing"])]
        if baseline:
            cells += [str(row["new"]), str(row["worse"])]
        cells += [str(row["ignored"]), str(row["warn"])]
        lines.append("| " + " | ".join(cells) + " |")
    return lines + _more(len(order) - TABLE_ROWS, "rules")


def _case_table(suite: CiSuite, failing: Sequence[CiCase], baseline: bool) -> list[str]:
    if not failing:
        return []
    what = "pair" if suite.command in ("check", "sweep") else "asset"
    before = " (before → after)" if baseline else ""
    header = ["", "rule", what, "file", f"numbers{before}", "snapshot"]
    lines = ["", "| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    for case in failing[:TABLE_ROWS]:
        cells = [
            change(case) if baseline else "fails",
            _rule_label(_case_rule(case), suite.rules),
            case.name,
            case.file or "",
            _numbers(case, suite.units),
        ]
        lines.append("| " + " | ".join(_cell(c) for c in cells) + f" | {_snapshot(case)} |")
    return lines + _more(len(failing) - TABLE_ROWS, f"failing {what}s")


def _pictured_warnings(suite: CiSuite) -> list[str]:
    """Warned cases that have a snapshot (``fit``'s loose primitives): a table of their
    pictures, so that every picture ``--snapshots`` drew is linked from the comment."""
    pictured = [c for c in suite.cases if c.warn and c.outcome != "failure" and c.snapshot]
    if not pictured:
        return []
    what = "pair" if suite.command in ("check", "sweep") else "asset"
    lines = ["", f"| | rule | {what} | file | snapshot |", "| --- | --- | --- | --- | --- |"]
    for case in pictured[:TABLE_ROWS]:
        cells = ["warns", _rule_label(_case_rule(case), suite.rules), case.name, case.file or ""]
        lines.append("| " + " | ".join(_cell(c) for c in cells) + f" | {_snapshot(case)} |")
    return lines + _more(len(pictured) - TABLE_ROWS, f"pictured {what}s")


def dumps_markdown(suite: CiSuite) -> str:
    """The pull-request comment of ``suite`` (see the module's notes)."""
    failing = [case for case in suite.cases if case.outcome == "failure"]
    baseline = suite.baseline is not None
    if baseline:  # new first, then worse: what the change broke first
        failing.sort(key=lambda case: change(case) != "new")
    errors = [case for case in suite.cases if case.outcome == "error"]
    ok = suite.passed
    mark = "✅" if ok else "❌"
    lines = [f"### {mark} meshcol {suite.command}: {'PASS' if ok else 'FAIL'}"]
    if suite.verdict:
        lines += ["", _cell(suite.verdict)]
    if baseline:
        new = sum(change(case) == "new" for case in failing)
        lines += [
            "",
            f"Against the baseline {_cell(suite.baseline)}: {new} new, {len(failing) - new} worse.",
        ]
    lines += _rule_table(suite, failing, baseline)
    lines += _case_table(suite, failing, baseline)
    lines += _pictured_warnings(suite)
    if errors:
        lines += ["", "Inputs that could not be used:", ""]
        lines += [f"- {_cell(c.file or c.name)}: {_cell(c.message)}" for c in errors[:TABLE_ROWS]]
        lines += _more(len(errors) - TABLE_ROWS, "inputs")
    if suite.warnings:
        lines += ["", "Warnings:", ""]
        lines += [f"- {_cell(w)}" for w in suite.warnings[:TABLE_ROWS]]
        lines += _more(len(suite.warnings) - TABLE_ROWS, "warnings")
    return "\n".join(lines) + "\n"
