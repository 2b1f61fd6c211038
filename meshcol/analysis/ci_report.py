"""The report of ``meshcol ci``: every job's report, one verdict, one exit code.

A :class:`CiReport` has the methods the report format registry writes from
(:data:`meshcol.io.formats.FORMATS`: ``to_json``, ``ci_suite``), so ``meshcol ci`` writes
every registered format its report has the method for, a format added to the registry
included. Its CI suite is every job's cases in one suite (each case's file is the job's
input); its JSON is every job's own JSON report, untouched, under ``runs``.

Nothing in it says which job came from the cache: a run from the cache and a run from cold
give the same bytes.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from meshcol.errors import MeshcolError

if TYPE_CHECKING:
    from meshcol.analysis.ci import Job

__all__ = ["REPORT_KEYS", "CiReport", "CiRun"]

#: The keys of a job's result that the run index does not keep: its report, the report's
#: text and what its pictures need (``--snapshots``).
REPORT_KEYS = ("report", "report_text", "pictures")
#: A value in a report's JSON that stands for text put in after encoding (:func:`_fill`).
_SLOT = "\x00meshcol-slot-{}\x00"


def _plain(value: Any) -> Any:
    """``value`` as plain JSON values (through the one encoder: numpy numbers, tuples)."""
    from meshcol.io.report import dumps_json

    return json.loads(dumps_json(value, compact=True))


@dataclass(frozen=True)
class CiRun:
    """One job and its result: ``{"report", "suite", "exit_code", "reads"}`` or
    ``{"error"}``; from the cache's index the report is left out, and ``fetch`` reads it
    when a format needs it (the JSON report): a run that writes only CI formats never
    reads the reports of its unchanged jobs."""

    job: Job
    result: Mapping[str, Any]
    cached: bool = False
    fetch: Callable[[], dict[str, Any] | None] | None = None
    #: reads the report's JSON text kept with a cached entry (None: none kept)
    fetch_text: Callable[[], str | None] | None = None

    def report(self) -> Any:
        """The job's own JSON report (None for an error)."""
        if "error" in self.result:
            return None
        if "report" not in self.result and self.fetch is not None:
            entry = self.fetch()
            if entry is None:
                raise MeshcolError(
                    f"{self.job.path}: the cached {self.job.command} report is gone from the "
                    "result cache (run again, or with --no-cache)"
                )
            return entry["report"]
        return self.result["report"]

    def report_json(self) -> str:
        """The job's report as :func:`meshcol.io.report.dumps_json` writes it on its own,
        without the final newline (``null`` for an error): the text kept with a cached
        entry, else the report encoded."""
        from meshcol.io.report import dumps_json

        if "error" in self.result:
            return "null"
        text = self.result.get("report_text") if not self.cached else None
        if text is None and self.cached and self.fetch_text is not None:
            text = self.fetch_text()
        if text is None:
            text = dumps_json(self.report())
        return str(text).rstrip("\n")

    @staticmethod
    def result_of(report: Any) -> dict[str, Any]:
        """What ``meshcol ci`` keeps of a command's report (and caches): its JSON report
        (and its text, ``report_text``, as :meth:`report_json` gives it), its CI suite and
        its exit code, as JSON values."""
        from meshcol.io.report import dumps_json

        suite = report.ci_suite()
        fields = {f.name: getattr(suite, f.name) for f in dataclasses.fields(suite)}
        # one level deep: _plain's JSON round trip copies the values (asdict's deep copy
        # of 10,000 cases cost more than the check of a warm scene)
        names = [f.name for f in dataclasses.fields(suite.cases[0])] if suite.cases else []
        fields["cases"] = [{name: getattr(case, name) for name in names} for case in suite.cases]
        plain = json.loads(report.to_json())
        return {
            "report": plain,
            # encoded as a cold run's report encodes it: the cached text is the same bytes
            "report_text": dumps_json(plain),
            "suite": _plain(fields),
            "exit_code": int(report.exit_code),
        }

    @property
    def exit_code(self) -> int:
        return 2 if "error" in self.result else int(self.result["exit_code"])

    def to_dict(self) -> dict[str, Any]:
        return {
            "command": self.job.command,
            "input": self.job.path,
            "kind": self.job.kind.rstrip("s"),
            "sections": list(self.job.sections),
            "settings": dict(sorted(self.job.settings.items())),
            "exit_code": self.exit_code,
            "error": self.result.get("error"),
            "report": self.report(),
        }

    def cases(self) -> list[Any]:
        """The job's CI cases, each named with its file when its name does not say it."""
        from meshcol.io.ci import CiCase

        classname = f"meshcol.{self.job.command}"
        if "error" in self.result:
            message = self.result["error"]
            return [
                CiCase(
                    self.job.path,
                    classname,
                    "error",
                    message,
                    file=self.job.path,
                    kind="unusable-input",
                )
            ]
        out = []
        for case in self.result["suite"]["cases"]:
            name = case["name"]
            if self.job.path not in name:
                name = f"{self.job.path}::{name}"
            out.append(CiCase(**{**case, "name": name, "file": case["file"] or self.job.path}))
        return out


@dataclass(frozen=True)
class CiReport:
    """The run: its jobs in plan order (file, then command), the config, the root."""

    runs: tuple[CiRun, ...]
    config: str | os.PathLike[str]
    root: str | os.PathLike[str]
    changed_since: str | None = None
    skipped: int = 0
    #: the configuration's ``docs-url`` (the rules' links in SARIF); not in the JSON report
    docs_url: str | None = None

    @functools.cached_property
    def exit_codes(self) -> list[int]:
        """Each run's exit code, in order (each read once: 10,000 of them)."""
        return [run.exit_code for run in self.runs]

    @functools.cached_property
    def exit_code(self) -> int:
        """2 when a job could not run (unusable input, a path outside the root), else 1
        when a job's policy fails, else 0."""
        codes = set(self.exit_codes)
        return 2 if 2 in codes else (1 if 1 in codes else 0)

    @property
    def cached(self) -> int:
        """Jobs whose result came from the cache (for the summary line; not in the report)."""
        return sum(run.cached for run in self.runs)

    @property
    def errors(self) -> list[str]:
        return [run.result["error"] for run in self.runs if "error" in run.result]

    @functools.cached_property
    def summary(self) -> dict[str, Any]:
        codes = self.exit_codes
        by_command: dict[str, int] = {}
        for run in self.runs:
            by_command[run.job.command] = by_command.get(run.job.command, 0) + 1
        return {
            "jobs": len(self.runs),
            "jobs_by_command": by_command,
            "inputs": len({run.job.path for run in self.runs}),
            "skipped_unchanged": self.skipped,
            "passed": codes.count(0),
            "failed": codes.count(1),
            "errors": codes.count(2),
            "exit_code": self.exit_code,
        }

    def to_dict(self, runs: bool = True) -> dict[str, Any]:
        """The JSON report; paths relative to the config's folder, as every job's input is
        (the same bytes wherever the repository is checked out). ``runs=False``: without
        the runs (:meth:`to_json` puts them in)."""
        from meshcol.io.report import envelope

        out = {**envelope("ci", self.settings, None), "summary": self.summary}
        if runs:
            out["runs"] = [run.to_dict() for run in self.runs]
        return out

    @property
    def settings(self) -> dict[str, Any]:
        folder = os.path.dirname(os.fspath(self.config))
        return {
            "config": os.path.basename(os.fspath(self.config)),
            "root": os.path.relpath(self.root, folder).replace(os.sep, "/"),
            "changed_since": self.changed_since,
        }

    def to_csv(self) -> str:
        """One row per job: command, input, kind, exit code, error, its report's verdict."""
        from meshcol.io.report import dumps_csv

        rows = [
            {
                "command": run.job.command,
                "input": run.job.path,
                "kind": run.job.kind.rstrip("s"),
                "exit_code": run.exit_code,
                "error": run.result.get("error"),
                "verdict": run.result.get("suite", {}).get("verdict"),
            }
            for run in self.runs
        ]
        return dumps_csv(rows, ("command", "input", "kind", "exit_code", "error", "verdict"))

    def to_json(self) -> str:
        """:meth:`to_dict` as :func:`meshcol.io.report.dumps_json` writes it, the same bytes,
        but each job's report put in as text (:meth:`CiRun.report_json`: for a cached job
        the text its entry keeps) and the fields of jobs that share their settings encoded
        once: a report of 10,000 cached jobs is joined, not decoded and encoded again."""
        from meshcol.io.report import dumps_json

        head = {**self.to_dict(runs=False), "runs": _SLOT.format("runs")}
        text = dumps_json(head)
        slot = json.dumps(_SLOT.format("runs"))
        if text.count(slot) != 1:
            return dumps_json(self.to_dict())  # a setting spelled like the slot: the long way
        templates: dict[tuple[Any, ...], list[str]] = {}
        items = []
        for run, code in zip(self.runs, self.exit_codes):
            job = run.job
            memo = (job.command, job.kind, job.sections, id(job.settings))
            parts = templates.get(memo)
            if parts is None:
                parts = templates[memo] = _run_template(run)
            values = {
                "error": json.dumps(run.result.get("error")),
                "exit_code": str(code),
                "input": json.dumps(job.path),
                "report": run.report_json().replace("\n", "\n" + " " * 6),
            }
            items.append("".join(values[p[1:]] if p[:1] == "\x00" else p for p in parts))
        runs = "[\n" + ",\n".join(items) + "\n  ]" if items else "[]"
        return text.replace(slot, runs)

    def verdict(self) -> str:
        s = self.summary
        text = (
            f"{s['jobs']} jobs on {s['inputs']} files: {s['failed']} failing, {s['errors']} errors"
        )
        if self.changed_since is not None:
            text += f" ({s['skipped_unchanged']} unchanged since {self.changed_since} not run)"
        return text

    def ci_suite(self) -> Any:
        """Every job's cases in one suite (command ``ci``)."""
        from meshcol.io.ci import CiSuite

        cases = [case for run in self.runs for case in run.cases()]
        warnings = tuple(
            warning
            for run in self.runs
            if "suite" in run.result
            for warning in run.result["suite"]["warnings"]
        )
        # the registered rules every job's command can report (SARIF describes them)
        rules = {
            rule_id: rule
            for run in self.runs
            if "suite" in run.result
            for rule_id, rule in (run.result["suite"].get("rules") or {}).items()
        }
        return CiSuite(
            "ci",
            tuple(cases),
            self.settings,
            warnings=warnings,
            verdict=self.verdict(),
            rules=dict(sorted(rules.items())),
            docs_url=self.docs_url,
        )


def _run_template(run: CiRun) -> list[str]:
    """The text of ``run.to_dict()`` in a report's ``runs`` (indented by 4), cut at the
    fields that differ between jobs of one settings: ``["...", "\\x00input", "...", ...]``,
    each ``\\x00``-led part the name of the field whose JSON goes there."""
    from meshcol.io.report import dumps_json

    fields = ("error", "exit_code", "input", "report")
    job = run.job
    value = {
        "command": job.command,
        "kind": job.kind.rstrip("s"),
        "sections": list(job.sections),
        "settings": dict(sorted(job.settings.items())),
        **{name: _SLOT.format(name) for name in fields},
    }
    text = "    " + dumps_json(value).rstrip("\n").replace("\n", "\n    ")
    parts = [text]
    for name in fields:
        head, _, tail = parts.pop().partition(json.dumps(_SLOT.format(name)))
        parts += [head, "\x00" + name, tail]
    return parts
