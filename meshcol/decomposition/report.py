"""The report of a decomposition run (``meshcol decompose``, of files or of a robot's links):
per file, its bodies' parts, cache keys, fidelity and search; the CSV rows; the summary, the
exit code and the CI suite."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from meshcol.decomposition.search import within_max_hausdorff

__all__ = ["CSV_COLUMNS", "DecomposeReport", "body_report"]

#: Columns of :meth:`DecomposeReport.to_csv`: one row per body, and one per failed file.
CSV_COLUMNS = (
    "path",
    "body",
    "status",
    "message",
    "parts",
    "vertices_per_part",
    "mesh_volume",
    "union_volume",
    "volume_ratio",
    "hausdorff_mesh_to_parts",
    "hausdorff_parts_to_mesh",
    "uncovered_fraction",
    "tolerance",
    "mesh_is_solid",
    "repaired",
    "from_cache",
    "hausdorff_ok",
    "parts_ok",
    "search_met",
    "search_steps",
)


@dataclass(frozen=True)
class DecomposeReport:
    """What :func:`~meshcol.decomposition.batch.decompose_files` did.

    Attributes
    ----------
    files : list of dict
        Per input file: ``path``, ``status`` (``ok``, ``failed``, ``timeout``), ``message``,
        ``seconds`` and ``bodies`` (name, outputs relative to the output folder, cache key,
        from_cache, engine, engine_version, params, repaired, notes, metrics, hausdorff_ok).
    rows : list of dict
        The CSV rows (:data:`CSV_COLUMNS`).
    settings : dict
        The options of the run.
    units : str or None
        Always None for now: parts keep the coordinates (and units) of their input files.
    layout, fmt : str
        Files per body and their format (as :func:`~meshcol.decomposition.batch.decompose_files` took them).
    max_hausdorff : float or None
        Hausdorff limit that fails the run.
    max_parts : int or None
        Part limit that fails the run.
    """

    files: list[dict[str, Any]]
    rows: list[dict[str, Any]]
    settings: dict[str, Any]
    units: str | None = None
    layout: str = "parts"
    fmt: str = "obj"
    max_hausdorff: float | None = None
    max_parts: int | None = None

    @property
    def summary(self) -> dict[str, int]:
        """Counts: files by status, bodies, parts, bodies over ``max_hausdorff`` or
        ``max_parts`` and, with a target, bodies that miss one of its limits
        (``target_missed``)."""
        counts = {
            "files": len(self.files),
            "ok": sum(1 for f in self.files if f["status"] == "ok"),
            "failed": sum(1 for f in self.files if f["status"] == "failed"),
            "timeout": sum(1 for f in self.files if f["status"] == "timeout"),
            "bodies": sum(len(f["bodies"]) for f in self.files),
            "parts": sum(b["metrics"].get("parts", 0) for f in self.files for b in f["bodies"]),
            "hausdorff_exceeded": sum(
                not b["hausdorff_ok"] for f in self.files for b in f["bodies"]
            ),
            "parts_exceeded": sum(
                not b.get("parts_ok", True) for f in self.files for b in f["bodies"]
            ),
        }
        if "target" in self.settings:
            counts["target_missed"] = sum(
                not b.get("target_ok", True) for f in self.files for b in f["bodies"]
            )
        return counts

    @property
    def exit_code(self) -> int:
        """1 when a file failed or timed out, a body exceeds ``max_hausdorff`` or
        ``max_parts`` (a search that met neither) or misses a limit of its target; else 0."""
        s = self.summary
        exceeded = s["hausdorff_exceeded"] or s["parts_exceeded"] or s.get("target_missed", 0)
        return 1 if s["failed"] or s["timeout"] or exceeded else 0

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, then ``layout``, ``format`` and
        ``max_hausdorff`` (also in ``settings``; kept at the top level for existing readers),
        ``files`` and ``summary``."""
        from meshcol.io.report import envelope

        return {
            **envelope("decompose", self.settings, self.units),
            "layout": self.layout,
            "format": self.fmt,
            "max_hausdorff": self.max_hausdorff,
            "files": self.files,
            "summary": self.summary,
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def to_csv(self) -> str:
        from meshcol.io.report import dumps_csv

        columns = (*CSV_COLUMNS, "target_ok") if "target" in self.settings else CSV_COLUMNS
        return dumps_csv(self.rows, columns)

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``) with its parts and fidelity, a failure over ``max_hausdorff``; a file
        that failed is an error case, one that timed out a failure (both fail the run). A
        file's seconds are shared among its bodies."""
        from meshcol.io.ci import CiCase, CiSuite, number

        limit = self.max_hausdorff
        cases = []
        for f in self.files:
            path = f["path"]
            if f["status"] != "ok":
                cases.append(
                    CiCase(
                        name=path,
                        classname="meshcol.decompose",
                        outcome="error" if f["status"] == "failed" else "failure",
                        message=f"{f['status']}: {f['message']}",
                        file=path,
                        kind=f["status"],
                        time=f.get("seconds"),
                    )
                )
                continue
            share = (f.get("seconds") or 0.0) / max(len(f["bodies"]), 1)
            for body in f["bodies"]:
                m = body["metrics"]
                message = (
                    f"{m.get('parts', 0)} parts, volume ratio {number(m.get('volume_ratio'))}, "
                    f"Hausdorff mesh to parts {number(m.get('hausdorff_mesh_to_parts'))}, "
                    f"parts to mesh {number(m.get('hausdorff_parts_to_mesh'))}, uncovered "
                    f"{number(m.get('uncovered_fraction'))}"
                )
                ok = body["hausdorff_ok"]
                if not ok:
                    message += f" > --max-hausdorff {number(limit)}"
                cases.append(
                    CiCase(
                        name=f"{path}::{body['name']}",
                        classname="meshcol.decompose",
                        outcome="passed" if ok else "failure",
                        message=message,
                        file=path,
                        kind=None if ok else "max-hausdorff",
                        time=share,
                    )
                )
        s = self.summary
        verdict = f"{s['files']} files, {s['bodies']} bodies, {s['parts']} parts"
        for key, what in (("failed", "failed"), ("timeout", "timed out")):
            if s[key]:
                verdict += f", {s[key]} {what}"
        if s["hausdorff_exceeded"]:
            verdict += f", {s['hausdorff_exceeded']} over --max-hausdorff"
        return CiSuite(
            "decompose",
            tuple(cases),
            self.settings,
            seconds=sum(f.get("seconds") or 0.0 for f in self.files),
            verdict=verdict,
            units=self.units,
        )


def body_report(
    path: str,
    name: str,
    outputs: list[str],
    d: Any,
    max_hausdorff: float | None,
    max_parts: int | None = None,
    search: Any = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """A decomposed body's entry in its file's ``bodies`` and its CSV row: the one layout of
    both, for files (:func:`~meshcol.decomposition.batch.decompose_files`) and robot links (``analysis.rebuild``).
    ``search``: the body's :class:`~meshcol.decomposition.search.SearchResult` (``d`` is its
    chosen step), or None."""
    metrics = d.metrics.to_dict() if d.metrics is not None else {}
    ok = within_max_hausdorff(metrics, max_hausdorff)
    parts_ok = max_parts is None or len(d.parts) <= max_parts
    body = {
        "name": name,
        "outputs": outputs,
        "cache_key": d.cache_key,
        "from_cache": d.from_cache,
        "engine": d.engine,
        "engine_version": d.engine_version,
        "params": dict(d.params),
        "repaired": d.repaired,
        "notes": list(d.notes),
        "metrics": metrics,
        "hausdorff_ok": ok,
        "parts_ok": parts_ok,
        "search": None if search is None else search.to_dict(),
    }
    row = {
        "path": path,
        "body": name,
        "status": "ok",
        **metrics,
        "repaired": d.repaired,
        "from_cache": d.from_cache,
        "hausdorff_ok": ok,
        "parts_ok": parts_ok,
        "search_met": None if search is None else search.met,
        "search_steps": None if search is None else len(search.steps),
    }
    return body, row
