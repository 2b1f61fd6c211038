"""``meshcol ci --snapshots DIR``: one picture per failing case of every job, as its command
draws them (:mod:`meshcol.analysis.snapshots`), linked from the run's Markdown.

A picture is drawn from what the job computed: a failing job run with ``--snapshots`` keeps,
with its result, its failing cases' shots and the part of its review page they draw
(:func:`meshcol.analysis.snapshots.pictures_data`, a :class:`meshcol.io.snapshots.ShotPage`
as JSON values), and the
result cache keeps them in its entry; so a run whose failing jobs come from the cache draws
their pictures without running them again (:func:`meshcol.analysis.ci.run_ci` runs a cached
failing job again only when its entry has none, from a run without ``--snapshots``). The
pictures are files of one folder, named by the job's input and the case
(``001-levels-level-scene.json-crate_01-crate_02.png``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from meshcol.analysis.ci_report import CiReport, CiRun
from meshcol.analysis.snapshots import SnapshotReport
from meshcol.io.snapshots import Shot, ShotPage, file_name, render_shots

__all__ = ["ci_snapshots", "pictures_of"]


def pictures_of(run: CiRun) -> Mapping[str, Any] | None:
    """The run's :func:`~meshcol.analysis.snapshots.pictures_data`: its result's, else its cache entry's; None when
    neither has any."""
    result = run.result
    data = result.get("pictures") if isinstance(result, dict) else None
    if data is None and run.cached and run.fetch is not None:
        entry = run.fetch()
        data = None if entry is None else entry.get("pictures")
    return data


def ci_snapshots(
    result: CiReport, stage: str, target: str, link_from: str | None
) -> SnapshotReport:
    """Draw the failing cases of every failing job of ``result`` into ``stage`` (a folder
    whose files become ``target``'s) from their pictures' data (:func:`pictures_of`); the
    report whose CI cases link to them, relative to ``link_from`` (the Markdown's folder;
    the working folder when None)."""
    base = os.path.abspath(link_from) if link_from else os.getcwd()
    links: dict[str, str] = {}
    count = 0
    for run in result.runs:
        if run.exit_code != 1:
            continue
        job = run.job
        data = pictures_of(run)
        if data is None or data["page"] is None:
            continue
        shots = []
        for case, fields in data["shots"]:
            count += 1
            name = file_name(count, case if job.path in case else f"{job.path}-{case}")
            shot = Shot(
                tuple(fields["bodies"]), name, fields["title"], fields["caption"], fields["outline"]
            )
            shots.append((case, shot))
        page = ShotPage.from_data(data["page"])
        written = render_shots(page, [s for _, s in shots], stage)
        for case, shot in shots:
            if shot.name not in written:
                continue
            named = case if job.path in case else f"{job.path}::{case}"
            picture = os.path.join(os.path.abspath(target), shot.name)
            links[named] = os.path.relpath(picture, base).replace(os.sep, "/")
    return SnapshotReport(result, links)
