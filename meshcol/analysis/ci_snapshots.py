"""``meshcol ci --snapshots DIR``: one picture per failing case of every job, as its command
draws them (:mod:`meshcol.analysis.snapshots`), linked from the run's Markdown.

A job's result may come from the result cache, which keeps its JSON report, not the report
object a picture is drawn from; so each failing job (exit 1) runs again here, in this process,
confined to the root like the run's own jobs (a check's pairs come from the per-pair cache,
:mod:`meshcol.analysis.pair_cache`, so this costs its broad phase). Only failing jobs run:
a passing job has nothing to picture. The pictures are files of one folder, named by the
job's input and the case (``001-levels-level-scene.json-crate_01-crate_02.png``).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from typing import Any

from meshcol.analysis.ci import Job, _execute, _robot, _working_folder
from meshcol.analysis.ci_report import CiReport
from meshcol.analysis.snapshots import SnapshotReport, shots_of
from meshcol.io.snapshots import file_name, render_shots

__all__ = ["ci_snapshots"]


def _page(job: Job, report: Any, folder: str) -> Any:
    """The review page of the job's command, whose rows the pictures draw."""
    from meshcol.analysis import review

    robot = _robot(job.settings, folder)
    inputs = [job.path]
    if job.command == "check":
        return review.check_page(report, inputs, job.settings["shape"], {}, robot)
    pages: dict[str, Callable[..., Any]] = {
        "inspect": review.inspect_page,
        "hull": review.hull_page,
        "fit": review.fit_page,
    }
    return pages[job.command](report, inputs, robot)


def ci_snapshots(
    result: CiReport,
    folder: str,
    stage: str,
    target: str,
    link_from: str | None,
    pair_cache: Callable[[Job], Any] = lambda job: None,
) -> SnapshotReport:
    """Draw the failing cases of every failing job of ``result`` into ``stage`` (a folder
    whose files become ``target``'s); the report whose CI cases link to them, relative to
    ``link_from`` (the Markdown's folder; the working folder when None).

    ``folder`` is the configuration's folder (job inputs are relative to it); ``pair_cache``
    gives a check job its pair cache (:meth:`meshcol.analysis.ci._Results.pair_cache`).
    """
    from meshcol.io.paths import confined_to

    base = os.path.abspath(link_from) if link_from else os.getcwd()
    links: dict[str, str] = {}
    count = 0
    root = os.fspath(result.root)
    for run in result.runs:
        if run.exit_code != 1:
            continue
        job = run.job
        with _working_folder(folder), confined_to(root):
            report = _execute(job, folder, pair_cache(job))
            shots = []
            for case, shot in shots_of(report):
                count += 1
                name = file_name(count, case if job.path in case else f"{job.path}-{case}")
                shots.append((case, dataclasses.replace(shot, name=name)))
            written = render_shots(_page(job, report, folder), [s for _, s in shots], stage)
        for case, shot in shots:
            if shot.name not in written:
                continue
            named = case if job.path in case else f"{job.path}::{case}"
            picture = os.path.join(os.path.abspath(target), shot.name)
            links[named] = os.path.relpath(picture, base).replace(os.sep, "/")
    return SnapshotReport(result, links)
