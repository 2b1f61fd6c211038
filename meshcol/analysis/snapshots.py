"""What ``--snapshots DIR`` pictures, and the report that links to the pictures.

One picture per failing case of a run: per violating pair of ``check`` (the pair framed, its
witness points, normal and depth), per failing mesh of ``inspect`` (the mesh with its
findings drawn on it). The pictures are rows of the command's review page
(:mod:`meshcol.analysis.review`) drawn offscreen by :mod:`meshcol.io.snapshots`;
:class:`SnapshotReport` is the command's report with each case's picture attached to its CI
case (``CiCase.snapshot``), so that the Markdown summary links to it.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Any

from meshcol.io.snapshots import Shot, file_name, render_shots

__all__ = ["SnapshotReport", "shots_of", "with_snapshots"]


def _check_shots(report: Any) -> list[tuple[str, Shot]]:
    from meshcol.analysis.check_policy import PAIR_RULES
    from meshcol.io.ci import number

    shots: list[tuple[str, Shot]] = []
    for pair in report.pairs:
        if not pair["violation"]:
            continue
        a, b = pair["body_a"], pair["body_b"]
        case = f"{a} <-> {b}"
        status = pair["status"]
        numbers = [f"depth {number(pair['depth'], report.units)}"] if pair["depth"] else []
        if pair["distance"] is not None and not pair["depth"]:
            numbers.append(f"distance {number(pair['distance'], report.units)}")
        caption = f"{PAIR_RULES.get(status, '')} {status}: " + ", ".join(numbers)
        shots.append((case, Shot((a, b), file_name(len(shots) + 1, case), case, caption)))
    return shots


def _inspect_shots(report: Any) -> list[tuple[str, Shot]]:
    from meshcol.analysis.inspect_report import _case_name

    shots: list[tuple[str, Shot]] = []
    for row in report.bodies:
        failed = row.get("failed_rules") or []
        if not failed:
            continue
        body = str(row["name"]).split("/")[0]
        case = _case_name(row["source"], row["name"])
        caption = "fails: " + ", ".join(failed)
        shots.append((case, Shot((body,), file_name(len(shots) + 1, case), case, caption)))
    return shots


def shots_of(report: Any) -> list[tuple[str, Shot]]:
    """(CI case name, the picture to draw of it) per failing case of ``report``."""
    from meshcol.analysis.check_report import CheckReport
    from meshcol.analysis.inspect_report import InspectReport

    if isinstance(report, CheckReport):
        return _check_shots(report)
    if isinstance(report, InspectReport):
        return _inspect_shots(report)
    return []


class SnapshotReport:
    """``report`` with a picture per failing case: every attribute is the report's, but
    :meth:`ci_suite` sets each case's ``snapshot`` (a link, as the Markdown shows it)."""

    def __init__(self, report: Any, links: dict[str, str]):
        self._report = report
        self.snapshots = dict(links)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._report, name)

    def ci_suite(self) -> Any:
        suite = self._report.ci_suite()
        cases = tuple(
            dataclasses.replace(case, snapshot=self.snapshots.get(case.name))
            for case in suite.cases
        )
        return dataclasses.replace(suite, cases=cases)


def with_snapshots(
    report: Any, page: Any, stage: str, folder: str, link_from: str | None
) -> SnapshotReport:
    """Draw the failing cases of ``report`` (rows of its review ``page``) into ``stage``, a
    folder whose files become ``folder``'s; links are relative to ``link_from`` (the
    report's folder; the working folder when None)."""
    shots = shots_of(report)
    written = render_shots(page, [shot for _, shot in shots], stage)
    base = os.path.abspath(link_from) if link_from else os.getcwd()
    links = {}
    for case, shot in shots:
        if shot.name in written:
            target = os.path.join(os.path.abspath(folder), shot.name)
            links[case] = os.path.relpath(target, base).replace(os.sep, "/")
    return SnapshotReport(report, links)
