"""What ``--snapshots DIR`` pictures, and the report that links to the pictures.

One picture per failing case of a run: per violating pair of ``check`` (the pair framed, its
witness points, normal and depth), per failing mesh of ``inspect`` (the mesh with its
findings drawn on it), per pair of ``sweep`` that hits (the two bodies at the time of impact,
the contact point and normal), per body of ``hull`` whose hull breaks its budget (over
``--max-vertices`` or a ``--target`` limit) and of ``fit`` whose primitive misses the
fidelity asked (its volume over the hull's by more than ``--volume-tolerance``): the mesh
with its collider's edges over it. The pictures are rows of the command's review page
(:mod:`meshcol.analysis.review`) drawn offscreen by :mod:`meshcol.io.snapshots`;
:class:`SnapshotReport` is the command's report with each case's picture attached to its CI
case (``CiCase.snapshot``), so that the Markdown summary links to it.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Any

from meshcol.io.snapshots import Shot, file_name, render_shots

__all__ = ["SnapshotReport", "pictures_data", "shots_of", "with_snapshots"]


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


def _sweep_shots(report: Any) -> list[tuple[str, Shot]]:
    """Per pair that fails ``--fail-on hit``: the two bodies at the time of impact (the
    page row's own poses), the contact point and normal."""
    from meshcol.io.ci import number
    from meshcol.types import TimeOfImpactStatus

    if report.exit_code == 0:
        return []
    shots: list[tuple[str, Shot]] = []
    for hit in sorted(report.hits, key=lambda h: h.time_of_impact):
        case = f"{hit.body_a} <-> {hit.body_b}"
        caption = f"{hit.status.name} at time of impact {number(hit.time_of_impact)}"
        if hit.status == TimeOfImpactStatus.OVERLAPPED_AT_START:
            caption = "OVERLAPPED_AT_START: the bodies overlap before they move"
        if hit.time is not None and hit.status != TimeOfImpactStatus.OVERLAPPED_AT_START:
            caption += f" (t = {number(hit.time, 's')})"
        shot = Shot((hit.body_a, hit.body_b), file_name(len(shots) + 1, case), case, caption)
        shots.append((case, shot))
    return shots


def _collider_shots(report: Any, failures: list[tuple[dict, str]]) -> list[tuple[str, Shot]]:
    """Per failing body of hull or fit (``(row, why)``): the mesh with its collider's edges
    over it (the page's ``hulls`` group)."""
    shots: list[tuple[str, Shot]] = []
    for row, why in failures:
        body = str(row["name"]).split("/")[0]
        case = report.case_name(row)  # the CI case the picture is linked from
        name = file_name(len(shots) + 1, case)
        shots.append((case, Shot((body,), name, case, why, outline="hulls")))
    return shots


def _hull_shots(report: Any) -> list[tuple[str, Shot]]:
    """Per body whose hull breaks its budget: over ``--max-vertices``, or past a limit of
    the ``--target`` it was fitted to (each violation in the caption)."""
    failures = []
    for row, fitted in zip(report.bodies, report.fits):
        why = [v.message for v in fitted.violations] if fitted is not None else []
        if row["max_vertices"] is not None and row["hull_vertices"] > row["max_vertices"]:
            why.insert(0, f"{row['hull_vertices']} vertices > budget {row['max_vertices']}")
        if why:
            failures.append((row, "; ".join(why)))
    return _collider_shots(report, failures)


def _fit_shots(report: Any) -> list[tuple[str, Shot]]:
    """Per body whose fitted primitive misses the fidelity asked for: its volume over the
    hull's by more than ``--volume-tolerance`` (a shape the user chose that fits badly)."""
    from meshcol.io.ci import number

    failures = []
    for row in report.bodies:
        ratio = row["hull_ratio"]
        if ratio is not None and ratio > 1.0 + report.volume_tolerance:
            why = (
                f"{row['shape']}: volume/hull {number(ratio)} > 1 + volume tolerance "
                f"{number(report.volume_tolerance)}"
            )
            failures.append((row, why))
    return _collider_shots(report, failures)


def shots_of(report: Any) -> list[tuple[str, Shot]]:
    """(CI case name, the picture to draw of it) per failing case of ``report``."""
    from meshcol.analysis.check_report import CheckReport
    from meshcol.analysis.fit import FitReport
    from meshcol.analysis.hull import HullReport
    from meshcol.analysis.inspect_report import InspectReport
    from meshcol.analysis.sweep import SweepReport

    kinds: list[tuple[type, Any]] = [
        (CheckReport, _check_shots),
        (InspectReport, _inspect_shots),
        (SweepReport, _sweep_shots),
        (HullReport, _hull_shots),
        (FitReport, _fit_shots),
    ]
    for kind, shots in kinds:
        if isinstance(report, kind):
            found: list[tuple[str, Shot]] = shots(report)
            return found
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


def _page(command: str, path: str, shape: str, report: Any, robot: Any) -> Any:
    """The review page of one input's ``command`` run, whose rows the pictures draw."""
    from meshcol.analysis import review

    if command == "check":
        return review.check_page(report, [path], shape, {}, robot)
    pages = {"inspect": review.inspect_page, "hull": review.hull_page, "fit": review.fit_page}
    return pages[command](report, [path], robot)


def pictures_data(command: str, path: str, shape: str, report: Any, robot: Any) -> dict:
    """What the pictures of a report's failing cases need, as JSON values: ``shots``
    (``[case, shot fields]`` per failing case, :func:`shots_of`; names are given when
    drawn) and ``page`` (:meth:`meshcol.io.snapshots.ShotPage.to_data` of its review page,
    None without a shot). For one input ``path`` of ``command`` (collider ``shape``, the
    robot's options ``robot``), where it ran: the review page reads the input."""
    from meshcol.io.snapshots import shot_page

    shots = shots_of(report)
    page = None
    if shots:
        page = shot_page(_page(command, path, shape, report, robot), [s for _, s in shots])
    listed = [
        [case, {"bodies": list(s.bodies), "title": s.title, "caption": s.caption,
                "outline": s.outline}]
        for case, s in shots
    ]  # fmt: skip
    return {"shots": listed, "page": None if page is None else page.to_data()}
