"""The report behind ``meshcol inspect``: :class:`InspectReport`, its rows, its CI suite and
its JSON and CSV forms."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from meshcol.analysis.health import HEALTH_IDS, MeshInspection
from meshcol.analysis.physics import PhysicsOptions
from meshcol.analysis.rules import Finding
from meshcol.io.report import vector_columns

__all__ = ["CSV_COLUMNS", "InspectReport"]

#: Columns of :meth:`InspectReport.to_csv`, one row per body.
CSV_COLUMNS = (
    "name",
    "source",
    "vertices",
    "faces",
    "components",
    "watertight",
    "winding_consistent",
    "volume",
    *vector_columns("bounds_min"),
    *vector_columns("bounds_max"),
    *vector_columns("size"),
    "degenerate_faces",
    "duplicate_faces",
    "boundary_edges",
    "non_manifold_edges",
    "inconsistent_edges",
    "self_intersecting",
    "self_intersecting_pairs",
    "manifold_status",
    "units_guess",
    "units_reason",
    "declared_units",
    "findings",
    "failed_rules",
    "units",
)

#: The fields of a mesh's row a failing CI case lists in its details.
CI_DETAIL_FIELDS = (
    "vertices",
    "faces",
    "components",
    "watertight",
    "winding_consistent",
    "volume",
    "size",
    "boundary_edges",
    "non_manifold_edges",
    "degenerate_faces",
    "duplicate_faces",
    "self_intersecting_pairs",
    "units_guess",
)


@dataclass(frozen=True)
class InspectReport:
    """What :func:`meshcol.analysis.inspect.inspect` found: one :class:`MeshInspection` per
    body, the physics rows, every finding as a record, and the policy.

    Attributes
    ----------
    inspections : tuple of MeshInspection
        Per mesh, in input order.
    fail_on : tuple of str
        Rule ids (:mod:`meshcol.analysis.rules`) whose findings fail the run.
    units : str or None
        Units the scene manifest declared.
    errors : tuple of dict
        Inputs that could not be inspected, each ``{"source", "body", "message"}`` (``body``
        None for a file that could not be read); the others are still inspected.
    findings : tuple of Finding
        Every finding: mesh health per mesh, then physics readiness and colliders per body.
    physics : tuple of dict
        Per collider body (:func:`meshcol.analysis.physics.physics_readiness`).
    physics_options : PhysicsOptions
    warnings : tuple of str
        What the run could not do as asked (a robot's visual geometry that could not be read).
    """

    inspections: tuple[MeshInspection, ...]
    fail_on: tuple[str, ...] = ()
    units: str | None = None
    errors: tuple[dict[str, Any], ...] = ()
    findings: tuple[Finding, ...] = ()
    physics: tuple[dict[str, Any], ...] = ()
    physics_options: PhysicsOptions = field(default_factory=PhysicsOptions)
    warnings: tuple[str, ...] = ()

    @property
    def bodies(self) -> list[dict[str, Any]]:
        """Per mesh: every :class:`MeshInspection` field and ``failed_rules``, the findings
        (names) whose ids are listed in ``fail_on``."""
        failing = {name for name, rule in HEALTH_IDS.items() if rule in self.fail_on}
        rows = []
        for result in self.inspections:
            row = result.to_dict()
            row["failed_rules"] = [rule for rule in result.findings if rule in failing]
            rows.append(row)
        return rows

    @property
    def failed_findings(self) -> list[Finding]:
        """The findings whose rule is listed in ``fail_on``."""
        return [f for f in self.findings if f.rule in self.fail_on]

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The rows of :attr:`bodies` with a mesh-health finding listed in ``fail_on``."""
        return [row for row in self.bodies if row["failed_rules"]]

    @property
    def exit_code(self) -> int:
        """2 when an input could not be inspected, else 1 when a finding's rule is listed in
        ``fail_on``, else 0."""
        return 2 if self.errors else 1 if self.failed_findings else 0

    @property
    def summary(self) -> dict[str, Any]:
        """Counts: meshes, bodies with findings, failing bodies, findings per rule name."""
        from meshcol.analysis.rules import command_rules

        return {
            "bodies": len(self.inspections),
            "with_findings": len({_label(f) for f in self.findings}),
            "failed": len({_label(f) for f in self.failed_findings}),
            "errors": len(self.errors),
            "findings": {
                rule.name: sum(f.rule == rule.id for f in self.findings)
                for rule in command_rules("inspect")
            },
        }

    @property
    def settings(self) -> dict[str, Any]:
        from meshcol.analysis.rules import get_rule

        return {
            "fail_on": [get_rule(rule).name for rule in self.fail_on],
            "fail_on_rules": list(self.fail_on),
            "bounds_frame": "world",
            **self.physics_options.settings(),
        }

    @cached_property
    def mesh_sources(self) -> dict[str, str | None]:
        """The file of each inspected mesh, by name."""
        return {result.name: result.source for result in self.inspections}

    def source_of(self, found: Finding) -> str | None:
        """The file of a finding's mesh (its part's, else its body's), when inspected."""
        sources = self.mesh_sources
        return sources.get(f"{found.body}/{found.part}") or sources.get(found.body)

    def finding_rows(self) -> list[dict[str, Any]]:
        """Every finding as a dict, with ``failed`` (its rule is listed in ``fail_on``)."""
        return [dict(f.to_dict(), failed=f.rule in self.fail_on) for f in self.findings]

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, ``failed`` (the policy verdict), the
        summary, one entry per mesh, the physics rows and every finding."""
        from meshcol.io.report import envelope

        return {
            **envelope("inspect", self.settings, self.units),
            "failed": self.exit_code != 0,
            "summary": self.summary,
            "bodies": self.bodies,
            "physics": list(self.physics),
            "findings": self.finding_rows(),
            "warnings": list(self.warnings),
            "errors": list(self.errors),
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``), a failure when it has a finding listed in ``fail_on`` (each
        finding with its measure: ``not-watertight (12 boundary edges)``), passed otherwise
        (other findings make it worth a warning); one error case per input that could not
        be inspected."""
        from meshcol.analysis.rules import command_rules
        from meshcol.io.ci import CiSuite

        rows = self.bodies
        by_name = {row["name"]: row for row in rows}
        by_case = _findings_by_case(self.findings, by_name)
        sources = {row["name"].split("/")[0]: row["source"] for row in rows}
        keys = [row["name"] for row in rows] + [key for key in by_case if key not in by_name]
        cases = []
        for key in keys:
            case = self._body_case(key, by_name.get(key), by_case.get(key, []), sources)
            if case is not None:
                cases.append(case)
        cases += [_error_case(error) for error in self.errors]
        return CiSuite(
            "inspect",
            tuple(cases),
            self.settings,
            verdict=self._ci_verdict(),
            units=self.units,
            rules={rule.id: rule.to_dict() for rule in command_rules("inspect")},
        )

    def _body_case(
        self,
        key: str,
        row: dict[str, Any] | None,
        found: list[Finding],
        sources: dict[str, str | None],
    ) -> Any:
        """The CI case of one mesh (``row``) or of findings on no inspected mesh; None when
        there is nothing to say."""
        from meshcol.io.ci import CiCase, details

        failed = [f for f in found if f.rule in self.fail_on]
        others = [f for f in found if f.rule not in self.fail_on]
        message = _case_message(failed, others, row)
        if message is None:
            return None
        source = row["source"] if row is not None else sources.get(key)
        return CiCase(
            name=_case_name(source, key),
            classname="meshcol.inspect",
            outcome="failure" if failed else "passed",
            message=message,
            file=source,
            kind=failed[0].name if failed else None,
            details=details((name, row[name]) for name in CI_DETAIL_FIELDS)
            if failed and row is not None
            else "",
            warn=bool(others) and not failed,
            rules=tuple(dict.fromkeys(f.rule for f in [*failed, *others])),
        )

    def _ci_verdict(self) -> str:
        counts = self.summary
        verdict = f"{counts['bodies']} bodies, {counts['with_findings']} with findings"
        if self.fail_on:
            verdict += f", {counts['failed']} failing --fail-on {','.join(self.fail_on)}"
        return verdict

    def to_csv(self) -> str:
        """One row per body (:data:`CSV_COLUMNS`): bounds and size split into ``_x/_y/_z``
        columns, as every command's CSV; findings space-separated."""
        from meshcol.io.report import dumps_csv, split_vectors

        sizes = {"bounds_min": 3, "bounds_max": 3, "size": 3}
        flat = [
            split_vectors(
                dict(
                    row, bounds_min=row["bounds"][0], bounds_max=row["bounds"][1], units=self.units
                ),
                sizes,
            )
            for row in self.bodies
        ]
        return dumps_csv(flat, CSV_COLUMNS)


def _label(found: Finding) -> str:
    """``BODY`` or ``BODY/PART``: the mesh a finding is on."""
    return found.body if found.part is None else f"{found.body}/{found.part}"


def _findings_by_case(
    findings: Iterable[Finding], by_name: dict[str, Any]
) -> dict[str, list[Finding]]:
    """Each finding to its mesh's case, else to its body's (a case of its own when no mesh of
    that name was inspected)."""
    grouped: dict[str, list[Finding]] = {}
    for found in findings:
        key = _label(found)
        grouped.setdefault(key if key in by_name else found.body, []).append(found)
    return grouped


def _case_message(
    failed: list[Finding], others: list[Finding], row: dict[str, Any] | None
) -> str | None:
    """A CI case's message: its failing findings, then the others; ``ok`` for a clean mesh."""
    if failed:
        message = ", ".join(_finding_label(f, row) for f in failed)
        if others:
            message += "; also " + ", ".join(_finding_label(f, row) for f in others)
        return message
    if others:
        return "findings: " + ", ".join(_finding_label(f, row) for f in others)
    if row is not None:
        return f"ok: {row['vertices']} vertices, {row['faces']} faces, watertight"
    return None


def _finding_label(found: Finding, row: dict[str, Any] | None) -> str:
    """A finding in a CI message: a mesh-health one with what was measured on the mesh,
    the others with their rule id and message."""
    if row is not None and found.rule in HEALTH_IDS.values():
        return _finding_text(found.name, row)
    where = "" if found.part is None or row is not None else f"part {found.part}: "
    return f"{found.rule} {found.name} ({where}{found.message})"


def _error_case(error: dict[str, Any]) -> Any:
    """The CI case of an input that could not be inspected."""
    from meshcol.io.ci import CiCase

    return CiCase(
        name=_case_name(error["source"], error["body"]),
        classname="meshcol.inspect",
        outcome="error",
        message=error["message"],
        file=error["source"] or None,
        kind="unusable-input",
    )


def _case_name(source: str | None, body: str | None) -> str:
    """``FILE::BODY`` (body names repeat across files), or whichever of the two is known."""
    if source and body:
        return f"{source}::{body}"
    return source or body or "(unnamed)"


def _finding_text(rule: str, row: dict[str, Any]) -> str:
    """A finding with what was measured: ``not-watertight (12 boundary edges)``."""
    measure = {
        "not-watertight": f"{row['boundary_edges']} boundary edges, "
        f"{row['non_manifold_edges']} non-manifold",
        "self-intersecting": f"{'at least ' if 'undecided' in row['findings'] else ''}"
        f"{row['self_intersecting_pairs']} crossing face pairs",
        "inconsistent-winding": "neighbouring faces disagree on their winding",
        "inverted": f"volume {row['volume']:.6g}" if row["volume"] is not None else "inside out",
        "degenerate-faces": f"{row['degenerate_faces']} faces",
        "non-manifold": f"{row['non_manifold_edges']} edges with more than two faces",
        "duplicate-faces": f"{row['duplicate_faces']} faces",
        "multiple-components": f"{row['components']} components",
        "suspect-units": f"looks like {row['units_guess']}: {row['units_reason']}",
        "undecided": "self-intersection test stopped at its budget, "
        + (
            f"at least {row['self_intersecting_pairs']} crossing face pairs"
            if row["self_intersecting_pairs"]
            else "no crossing found"
        ),
    }.get(rule)
    return rule if measure is None else f"{rule} ({measure})"
