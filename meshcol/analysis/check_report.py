"""The report of ``meshcol check``: :class:`CheckReport` (JSON, CSV, JUnit and GitHub through
its CI suite, the review page), and the last stage of a check, :func:`check_report`, which
turns the classified :class:`~meshcol.analysis.pairs.PairTable` into its rows.
"""

from __future__ import annotations

import itertools
import math
import operator
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any

import numpy as np

from meshcol.analysis.check_policy import CheckOptions
from meshcol.analysis.pairs import SEVERITY, PairTable, PlacedColliders
from meshcol.io.column_bodies import body_names, body_parts, body_sources, vertex_counts
from meshcol.io.paths import display_path, display_paths
from meshcol.io.report import RowsPiece, vector_columns
from meshcol.types import Scene
from meshcol.vocabulary import PAIR_STATUSES

__all__ = ["CSV_COLUMNS", "CheckReport", "ReportRows", "check_report", "name_ranks"]


class ReportRows(Sequence[dict]):
    """A report's rows (its ``pairs`` or ``bodies``) kept as columns: each row's dict is made
    only when a reader asks for rows (:meth:`rows`), and the JSON writer writes them from the
    columns (:func:`meshcol.io.report.dumps_rows`), so that a run of a million pairs holds
    arrays, not a million dicts.

    Parameters
    ----------
    count : int
        The number of rows.
    build : callable
        ``build(index)``: the dicts of the rows ``index`` ((k,) int64), in that order.
    columns : callable
        The columns for :func:`meshcol.io.report.dumps_rows`, in key order.
    """

    def __init__(
        self,
        count: int,
        build: Callable[[np.ndarray], list[dict]],
        columns: Callable[[], list[tuple]],
    ) -> None:
        self._count = count
        self._build = build
        self.columns = columns
        self._rows: list[dict] | None = None

    def rows(self, index: np.ndarray | None = None) -> list[dict]:
        """The dicts of the rows ``index`` (all when None; made once, then kept)."""
        if index is not None and self._rows is None:
            return self._build(np.asarray(index, dtype=np.int64))
        if self._rows is None:
            self._rows = self._build(np.arange(self._count, dtype=np.int64))
        return self._rows if index is None else [self._rows[i] for i in index.tolist()]

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, item: Any) -> Any:
        return self.rows()[item]

    def __iter__(self) -> Iterator[dict]:
        return iter(self.rows())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (list, ReportRows)):
            return self.rows() == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def tolist(self) -> list[dict]:
        """The rows as a list (what the JSON encoder asks of an object that is not one)."""
        return list(self.rows())

    def __repr__(self) -> str:
        return f"ReportRows({self._count} rows)"


@dataclass(frozen=True)
class CheckReport:
    """The outcome of a check: everything the JSON report holds.

    Attributes
    ----------
    bodies : list of dict
        Per body: name, file, collider, parts (names; empty for a body of one part),
        convex_parts, vertices, aabb (world ``[[min], [max]]``).
    pairs : list of dict
        Per candidate body pair, sorted by (body_a, body_b): body_a, body_b, part_a, part_b
        (the parts that come closest, None for a body of one part), status, distance, depth,
        signed_distance, normal, point_a, point_b, convex_part_a, convex_part_b, ignored,
        violation, query_failed, intersection_volume.
    summary : dict
        Counts, extremes, pass/fail and timings.
    settings : dict
        The options used.
    units : str or None
        From the manifest.
    warnings : list of str
        What the run could not do as asked (``UCX_`` parts naming nothing, flat bodies that
        could not be decomposed), one line each.
    findings : list of dict
        Finding records (:class:`meshcol.analysis.rules.Finding` fields and ``failed``):
        MC301 per body without a usable collider, and a target's limits per body and part. A
        pair's rule is its status (:data:`~meshcol.analysis.check_policy.PAIR_RULES`), in
        ``pairs``, not repeated here.
    table : PairTable or None
        The pairs as arrays, row ``i`` the pair ``pairs[i]`` (None for a report read back or
        made by hand).
    baseline : dict or None
        The ``--baseline`` report's pairs by sorted body names (``(a, b) -> pair``), for the
        summaries that show what got worse (None without a baseline).
    """

    bodies: Sequence[dict]
    pairs: Sequence[dict]
    summary: dict
    settings: dict
    units: str | None
    generated_at: str
    warnings: list[str] = field(default_factory=list)
    findings: list[dict] = field(default_factory=list)
    table: PairTable | None = field(default=None, repr=False, compare=False)
    baseline: dict | None = field(default=None, repr=False, compare=False)

    @property
    def passed(self) -> bool:
        return bool(self.summary["passed"])

    @property
    def exit_code(self) -> int:
        """0 when the policy passes, 1 when it is violated."""
        return 0 if self.passed else 1

    def to_dict(self) -> dict:
        """The JSON report: the common envelope, ``generated_at``, bodies, summary, pairs."""
        return {**self._document(), "bodies": list(self.bodies), "pairs": list(self.pairs)}

    def _document(self) -> dict:
        """:meth:`to_dict` with its rows as they are held (perhaps :class:`ReportRows`)."""
        from meshcol.io.report import envelope

        return {
            **envelope("check", self.settings, self.units),
            "generated_at": self.generated_at,
            "warnings": self.warnings,
            "bodies": self.bodies,
            "summary": self.summary,
            "pairs": self.pairs,
            "findings": self.findings,
        }

    def worst_pairs(self, count: int = 10) -> list[dict]:
        """Up to ``count`` pairs that are not separated, most penetrating (smallest signed
        distance) first, ties in report order (``heapq.nsmallest`` is ``sorted()[:count]``
        without sorting 100,000 pairs to print ten)."""
        import heapq

        if isinstance(self.pairs, ReportRows) and self.table is not None:
            return self.pairs.rows(_worst_rows(self.table, count))
        inf = float("inf")
        touching = (p for p in self.pairs if p["status"] != "separated")
        return heapq.nsmallest(
            count,
            touching,
            key=lambda p: inf if p["signed_distance"] is None else p["signed_distance"],
        )

    def to_json(self) -> str:
        """The JSON report (:meth:`json_chunks` joined)."""
        return "".join(self.json_chunks())

    def json_chunks(self) -> Iterator[str]:
        """The JSON report's text in pieces, in order (:meth:`json_pieces` as text): rows
        kept as columns are written a bounded number at a time; never the whole text in
        memory."""
        from meshcol.io.report import text_pieces

        return text_pieces(self.json_pieces())

    def json_pieces(self) -> Iterator[str | RowsPiece]:
        """The JSON report in pieces, in order: the text of the rest, and each list of rows
        kept as columns (:class:`ReportRows`) as a :class:`~meshcol.io.report.RowsPiece`
        between, which a file gets straight from the core's row writer
        (:func:`meshcol.io.report.emit`); the same bytes as the whole document encoded at
        once."""
        from meshcol.io.report import document_pieces

        document = self._document()
        streamed = [k for k in ("bodies", "pairs") if isinstance(document[k], ReportRows)]
        return document_pieces(document, streamed)

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per candidate pair
        (``body_a <-> body_b``): a failure when it violates ``--fail-on``, skipped when an
        ``--ignore`` rule spares a pair the policy would fail, else passed; the message has
        the status and its numbers. More than :data:`meshcol.io.ci.MAX_PASSED_CASES` passed
        pairs become one case. The file is the scene input, or body_a's file."""
        from meshcol.analysis.rules import command_rules
        from meshcol.io.ci import CiSuite, collapse_passed

        files = {b["name"]: b["file"] for b in self.bodies}
        inputs = self.settings.get("inputs") or []
        scene = inputs[0] if len(inputs) == 1 else None
        settings = self.settings
        fails = frozenset(settings["fail_on_rules"])  # a level's rules, or the rules listed
        old = self.baseline or {}
        cases = [_ci_case(p, files, scene, fails, settings, self.units, old) for p in self.pairs]
        cases += _finding_cases(self.findings, files, scene)
        s = self.summary
        verb = "violates" if s["violations"] == 1 else "violate"
        failed = s.get("failed_findings") or 0
        also = f"; {failed} body finding{'s' if failed != 1 else ''} fail" if failed else ""
        return CiSuite(
            "check",
            tuple(collapse_passed(cases, "pairs", "meshcol.check")),
            settings,
            seconds=(s["seconds"] or 0.0) + (s["load_seconds"] or 0.0),
            warnings=tuple(self.warnings),
            verdict=f"{s['violations']} of {s['candidate_pairs']} candidate pairs {verb} "
            f"--fail-on {settings['fail_on']}{also}",
            units=self.units,
            rules={rule.id: rule.to_dict() for rule in command_rules("check")},
            baseline=settings.get("baseline"),
        )

    def to_csv(self) -> str:
        from meshcol.io.report import dumps_csv, split_vectors

        sizes = {"normal": 3, "point_a": 3, "point_b": 3}
        rows = [split_vectors(dict(p, units=self.units), sizes) for p in self.pairs]
        return dumps_csv(rows, CSV_COLUMNS)


#: Columns of :meth:`CheckReport.to_csv`, one row per pair (vectors split, as every command).
CSV_COLUMNS = [
    "body_a",
    "body_b",
    "part_a",
    "part_b",
    "status",
    "distance",
    "depth",
    "depth_upper",
    "signed_distance",
    *vector_columns("normal"),
    *vector_columns("point_a"),
    *vector_columns("point_b"),
    "convex_part_a",
    "convex_part_b",
    "ignored",
    "violation",
    "query_failed",
    "intersection_volume",
    "units",
]


def _finding_cases(
    findings: list[dict], files: dict[str, str | None], scene: str | None
) -> list[Any]:
    """The CI cases of a check report's body findings (MC301, a target's limits): a failure
    when the finding fails the run, else a passed case worth a warning; so that JUnit, SARIF
    and the other CI formats carry what fails the run besides the pairs."""
    from meshcol.io.ci import CiCase, details

    cases: list[Any] = []
    names: set[str] = set()
    for finding in findings:
        body = finding["body"]
        part = "" if finding.get("part") is None else f" part {finding['part']}"
        name = f"{body}{part}: {finding['rule']} {finding['name']}"
        if name in names:  # one case per finding, each name unique in the suite
            name = f"{name} #{sum(n.startswith(name) for n in names) + 1}"
        names.add(name)
        numbers = {k: finding[k] for k in ("measured", "limit") if finding.get(k) is not None}
        cases.append(
            CiCase(
                name=name,
                classname="meshcol.check",
                outcome="failure" if finding["failed"] else "passed",
                message=finding["message"],
                file=scene or files.get(body),
                kind=finding["name"],
                details=details([("body", body), *numbers.items()]) if finding["failed"] else "",
                warn=not finding["failed"],
                rules=(finding["rule"],),
                numbers=numbers,
            )
        )
    return cases


def _ci_case(
    pair: dict,
    files: dict[str, str | None],
    scene: str | None,
    fails: frozenset[str],
    settings: dict,
    units: str | None,
    baseline: dict | None = None,
) -> Any:
    """The CI case of one pair of a check report (``fails``: the rules that fail the run)."""
    from meshcol.analysis.check_policy import PAIR_RULES
    from meshcol.io.ci import CiCase, details, number

    status = pair["status"]
    a, b = pair["body_a"], pair["body_b"]
    if status == "separated":
        message = f"separated: distance {number(pair['distance'], units)}"
    elif status == "clearance":
        message = (
            f"clearance: distance {number(pair['distance'], units)} < --clearance "
            f"{number(settings['clearance'], units)}"
        )
    elif status == "contact":
        message = (
            f"contact: signed distance {number(pair['signed_distance'], units)} (tolerance "
            f"{number(settings['tolerance'], units)})"
        )
    elif status == "undecided":
        message = (
            "undecided: no inside test decides (a non-orientable mesh whose ray parity "
            f"splits); depth between {number(pair['depth'], units)} and "
            f"{number(pair['depth_upper'], units)}"
        )
    else:
        inside = "one body inside the other, " if status == "contained" else ""
        message = (
            f"{status}: {inside}depth {number(pair['depth'], units)} (at most "
            f"{number(pair['depth_upper'], units)}), signed distance "
            f"{number(pair['signed_distance'], units)}"
        )
        if pair["intersection_volume"] is not None:
            message += f", intersection volume {number(pair['intersection_volume'])}"
    if pair["query_failed"]:
        message += " (query failed: the numbers are not the answer)"
    outcome = "passed"
    if pair["violation"]:
        outcome = "failure"
        message += f" (--fail-on {settings['fail_on']})"
    elif PAIR_RULES.get(status) in fails:
        if pair["ignored"]:
            outcome = "skipped"
            message = f"ignored by --ignore: {message}"
        else:
            message += " (not worse than the --baseline)"
    text = ""
    if outcome != "passed":
        text = details(
            [
                ("body_a", f"{a} ({files.get(a)})" if files.get(a) else a),
                ("body_b", f"{b} ({files.get(b)})" if files.get(b) else b),
                ("part_a", pair["part_a"]),
                ("part_b", pair["part_b"]),
                ("distance", pair["distance"]),
                ("depth", pair["depth"]),
                ("depth_upper", pair["depth_upper"]),
                ("signed_distance", pair["signed_distance"]),
                ("intersection_volume", pair["intersection_volume"]),
                ("point_a", pair["point_a"]),
                ("point_b", pair["point_b"]),
                ("normal", pair["normal"]),
                ("units", units),
            ]
        )
    return CiCase(
        name=f"{a} <-> {b}",
        classname="meshcol.check",
        outcome=outcome,
        message=message,
        file=scene or files.get(a),
        kind=status,
        details=text,
        rules=(PAIR_RULES[status],) if status in PAIR_RULES else (),
        before=(baseline or {}).get(tuple(sorted((a, b)))),
        numbers={k: pair[k] for k in ("depth", "distance", "signed_distance")},
    )


# ---------------------------------------------------------------------------------------------
# The last stage: the table as the report's rows


def check_report(
    table: PairTable,
    placed: PlacedColliders,
    scene: Scene,
    options: CheckOptions,
    seconds: float,
    load_seconds: float | None,
) -> CheckReport:
    """The report of a classified table with its policy applied: the pairs as rows sorted by
    (body_a, body_b) names, the bodies, the findings, the summary and the settings. Pairs and
    bodies stay columns (:class:`ReportRows`) until a reader asks for their dicts."""
    colliders = placed.colliders
    names = body_names(colliders.bodies)
    rank = name_ranks(names)
    table = table.take(_report_order(table, rank))
    files = _files(colliders.bodies)
    findings = _findings(colliders, options, scene)
    return CheckReport(
        _body_rows(placed, files, rank),
        _pair_rows(table, colliders),
        _summary(table, len(names), findings, seconds, load_seconds),
        _settings(scene, options, colliders.bodies, files),
        scene.units,
        datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        [*scene.warnings, *colliders.warnings],
        findings,
        table,
        _baseline_pairs(options.baseline),
    )


def _files(bodies: Sequence[Any]) -> list[str | None]:
    """Each body's file as the report shows it, each distinct file made relative once (the
    100,000 primitives of a manifest share one)."""
    sources = body_sources(bodies)
    distinct = list(dict.fromkeys(sources))
    shown = dict(zip(distinct, display_paths(distinct, posix=True)))
    return [shown[source] for source in sources]


def _baseline_pairs(baseline: dict | None) -> dict | None:
    """The ``--baseline`` report's pairs by sorted body names (as the policy reads them)."""
    if baseline is None:
        return None
    return {tuple(sorted((p["body_a"], p["body_b"]))): p for p in baseline.get("pairs", [])}


def name_ranks(names: Sequence[str]) -> np.ndarray:
    """(n,) int64: each body's place in name order, equal names equal ranks: the order of
    a report's rows (check's pairs and bodies, sweep's hits)."""
    if all(map(operator.lt, names, itertools.islice(names, 1, None))):
        return np.arange(len(names), dtype=np.int64)  # in name order already (generated scenes)
    order = sorted(range(len(names)), key=names.__getitem__)
    rank = np.zeros(len(names), dtype=np.int64)
    if order:
        ordered = list(map(names.__getitem__, order))
        new = np.ones(len(order), dtype=np.int64)
        new[0] = 0
        new[1:] = list(map(operator.ne, ordered[1:], ordered[:-1]))
        rank[np.asarray(order, dtype=np.int64)] = np.cumsum(new)
    return rank


def _report_order(table: PairTable, rank: np.ndarray) -> np.ndarray:
    """The rows sorted by (body_a, body_b) names, ties in table order."""
    return np.lexsort((rank[table.body_b], rank[table.body_a])).astype(np.int64)


def _worst_rows(table: PairTable, count: int) -> np.ndarray:
    """The rows of :meth:`CheckReport.worst_pairs`: up to ``count`` rows that are not
    separated, smallest signed distance first (non-finite last), ties in row order."""
    rows = np.flatnonzero(table.status != SEVERITY["separated"])
    key = table.signed_distance[rows]
    key = np.where(np.isfinite(key), key, np.inf)
    return rows[np.lexsort((rows, key))[:count]]


def _pair_rows(table: PairTable, colliders: Any) -> ReportRows:
    """The report's ``pairs``: the rows of ``table`` as :class:`ReportRows`."""

    def build(index: np.ndarray) -> list[dict]:
        return pair_rows(table, colliders, index)

    def columns() -> list[tuple]:
        return _pair_columns(table, colliders)

    return ReportRows(len(table), build, columns)


def _pair_columns(table: PairTable, colliders: Any) -> list[tuple]:
    """The columns of :func:`pair_rows`, for the native row writer, in key order."""
    names = body_names(colliders.bodies)

    def part(bodies: np.ndarray, labels: np.ndarray) -> tuple:
        if not (labels >= 0).any():
            return np.full(len(labels), -1, dtype=np.int64), []
        found = colliders.part_names(bodies, labels)
        table_of = {name: k for k, name in enumerate(dict.fromkeys(n for n in found if n))}
        codes = [-1 if n is None else table_of[n] for n in found]
        return np.asarray(codes, dtype=np.int64), list(table_of)

    def real(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=np.float64)

    def whole(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=np.int64)

    def flag(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=bool)

    columns = [
        ("body_a", "string", whole(table.body_a), names),
        ("body_b", "string", whole(table.body_b), names),
        ("convex_part_a", "index", whole(table.part_a)),
        ("convex_part_b", "index", whole(table.part_b)),
        ("depth", "number", real(table.depth)),
        ("depth_upper", "number", real(table.depth_upper)),
        ("distance", "number", real(table.distance)),
        ("ignored", "boolean", flag(table.ignored)),
        ("intersection_volume", "number", real(table.intersection_volume)),
        ("normal", "vector", real(table.normal)),
        ("part_a", "string", *part(table.body_a, table.label_a)),
        ("part_b", "string", *part(table.body_b, table.label_b)),
        ("point_a", "vector", real(table.point_a)),
        ("point_b", "vector", real(table.point_b)),
        ("query_failed", "boolean", flag(table.query_failed)),
        ("signed_distance", "number", real(table.signed_distance)),
        ("status", "string", whole(table.status), list(PAIR_STATUSES)),
        ("violation", "boolean", flag(table.violation)),
    ]
    return columns


def pair_rows(table: PairTable, colliders: Any, index: np.ndarray | None = None) -> list[dict]:
    """One dict per row (the report's ``pairs``), in table order (the rows ``index`` only,
    when given); non-finite numbers as None, parts by name. Columns are converted once, then
    zipped (no per-pair numpy calls)."""
    names = body_names(colliders.bodies)
    rows = slice(None) if index is None else index
    a, b = table.body_a[rows], table.body_b[rows]
    columns = zip(
        a.tolist(),
        b.tolist(),
        table.status[rows].tolist(),
        _nums(table.distance[rows]),
        _nums(table.depth[rows]),
        _nums(table.depth_upper[rows]),
        _nums(table.signed_distance[rows]),
        _vecs(table.normal[rows]),
        _vecs(table.point_a[rows]),
        _vecs(table.point_b[rows]),
        table.part_a[rows].tolist(),
        table.part_b[rows].tolist(),
        colliders.part_names(a, table.label_a[rows]),
        colliders.part_names(b, table.label_b[rows]),
        table.ignored[rows].tolist(),
        table.violation[rows].tolist(),
        table.query_failed[rows].tolist(),
        _nums(table.intersection_volume[rows]),
    )
    return [
        {
            "body_a": names[ia],
            "body_b": names[ib],
            "part_a": name_a,
            "part_b": name_b,
            "status": PAIR_STATUSES[status],
            "distance": distance,
            "depth": depth,
            "depth_upper": depth_upper,
            "signed_distance": signed,
            "normal": normal,
            "point_a": point_a,
            "point_b": point_b,
            "convex_part_a": part_a if part_a >= 0 else None,
            "convex_part_b": part_b if part_b >= 0 else None,
            "ignored": ignored,
            "violation": violation,
            "query_failed": failed,
            "intersection_volume": volume,
        }
        for (
            ia,
            ib,
            status,
            distance,
            depth,
            depth_upper,
            signed,
            normal,
            point_a,
            point_b,
            part_a,
            part_b,
            name_a,
            name_b,
            ignored,
            violation,
            failed,
            volume,
        ) in columns
    ]


def _body_rows(
    placed: PlacedColliders, files: Sequence[str | None], rank: np.ndarray
) -> ReportRows:
    """The report's ``bodies``, sorted by name (:func:`body_rows`), as :class:`ReportRows`."""
    order = np.argsort(rank, kind="stable")

    def build(index: np.ndarray) -> list[dict]:
        return body_rows(placed, files, order[index])

    def columns() -> list[tuple]:
        return _body_columns(placed, files, order)

    return ReportRows(len(order), build, columns)


def body_rows(
    placed: PlacedColliders, files: Sequence[str | None], index: np.ndarray
) -> list[dict]:
    """One dict per body ``index`` (in that order): file, collider kind, parts, box."""
    colliders = placed.colliders
    part_counts = np.diff(colliders.body_part_offsets)[index].tolist()
    picked = index.tolist()
    bodies = [colliders.bodies[i] for i in picked]
    return [
        {
            "name": body.name,
            "file": file,
            "collider": kind,
            "parts": list(body.parts),
            "convex_parts": parts,
            "vertices": body.vertex_count,
            "aabb": [lo, hi],
        }
        for body, file, kind, parts, lo, hi in zip(
            bodies,
            [files[i] for i in picked],
            [colliders.kinds[i] for i in picked],
            part_counts,
            _vecs(placed.body_min[index]),
            _vecs(placed.body_max[index]),
        )
    ]


def _body_columns(
    placed: PlacedColliders, files: Sequence[str | None], order: np.ndarray
) -> list[tuple]:
    """The columns of :func:`body_rows` of every body in ``order``, in key order."""
    from meshcol.io.report import dumps_json

    colliders = placed.colliders
    names = body_names(colliders.bodies)
    order = np.ascontiguousarray(order, dtype=np.int64)

    def codes(values: Sequence[Any]) -> tuple[np.ndarray, list]:
        """Each body's code into a table of the distinct values (in body order, None -1),
        then taken in report order: no list of a million values made in that order."""
        distinct = [v for v in dict.fromkeys(values) if v is not None]
        table: dict[Any, int] = {v: k for k, v in enumerate(distinct)}
        table[None] = -1
        found = np.fromiter(map(table.__getitem__, values), dtype=np.int64, count=len(values))
        return found[order], distinct

    parts, part_texts = codes(body_parts(colliders.bodies, range(len(names))))
    indent = "\n" + "  " * 3
    box = np.concatenate([placed.body_min[order], placed.body_max[order]], axis=1)
    return [
        ("aabb", "box", np.ascontiguousarray(box, dtype=np.float64)),
        ("collider", "string", *codes(colliders.kinds)),
        ("convex_parts", "integer", np.diff(colliders.body_part_offsets)[order]),
        ("file", "string", *codes(files)),
        ("name", "string", order, names),
        (
            "parts",
            "raw",
            parts,
            [dumps_json(list(p))[:-1].replace("\n", indent) for p in part_texts],
        ),
        ("vertices", "integer", vertex_counts(colliders.bodies, order)),
    ]


def _summary(
    table: PairTable,
    bodies: int,
    findings: Sequence[dict],
    seconds: float,
    load_seconds: float | None,
) -> dict:
    """Counts per status, extremes, the verdict and timings."""
    status = table.status
    by_status = {s: int(np.count_nonzero(status == SEVERITY[s])) for s in PAIR_STATUSES}
    finite_distance = table.distance[np.isfinite(table.distance)]
    return {
        "bodies": bodies,
        "candidate_pairs": len(table),
        "pairs_by_status": by_status,
        "ignored_pairs": int(np.count_nonzero(table.ignored)),
        "excluded_pairs": table.excluded_pairs,
        "failed_queries": int(np.count_nonzero(table.query_failed)),
        "min_distance": _num(finite_distance.min()) if len(finite_distance) else None,
        "max_depth": _num(table.depth.max()) if len(table) else None,
        "violations": int(np.count_nonzero(table.violation)),
        "failed_findings": sum(f["failed"] for f in findings),
        "passed": not any(f["failed"] for f in findings) and not bool(table.violation.any()),
        "seconds": round(seconds, 6),
        "load_seconds": None if load_seconds is None else round(load_seconds, 6),
    }


def _settings(
    scene: Scene,
    options: CheckOptions,
    bodies: Sequence[Any],
    files: Sequence[str | None],
) -> dict:
    """The options used, as the report states them."""
    settings = {
        "collider": options.collider,
        "tolerance": options.tolerance,
        "clearance": options.clearance,
        "fail_on": options.fail_on,
        "fail_on_rules": list(options.fail_rules),
        "ignore": list(options.ignore),
        "baseline": display_path(options.baseline_source, posix=True),
        "excluded_pairs": [
            {"body_a": a, "body_b": b, "reason": reason} for a, b, reason in scene.excluded_pairs
        ],
        "inputs": [display_path(scene.source, posix=True)]
        if scene.source
        else sorted({file or "" for file, body in zip(files, bodies) if body.source}),
    }
    if options.target is not None:
        settings["target"] = options.target.name
        settings["target_limits"] = dict(options.target.limits)
    return settings


def _findings(colliders: Any, options: CheckOptions, scene: Scene) -> list[dict]:
    """Body finding records, each with ``failed`` (its rule fails the run): MC506 for a
    robot with no collision geometry (:func:`meshcol.analysis.rules.robot_findings`), MC301
    per body without a usable collider (every convex part a segment or a point: no area),
    then a target's limits (:func:`meshcol.analysis.rules.target_findings`). Pairs are not
    repeated here: a pair's status is its rule (:data:`PAIR_RULES`, ``meshcol rules``)."""
    from meshcol.analysis.rules import finding, robot_findings, target_findings
    from meshcol.collision.hull import HullStatus

    units = scene.units
    records = robot_findings(scene)
    status = colliders.shapes.hull_status  # (np.isin sorts a million statuses for two values)
    no_area = (status == HullStatus.COLLINEAR) | (status == HullStatus.SINGLE_POINT)
    no_area &= colliders.shapes.kinds == 0  # polytopes
    counts = np.diff(colliders.body_part_offsets)
    starts = colliders.body_part_offsets[:-1]
    if len(no_area) and len(starts):
        flat_parts = np.add.reduceat(no_area.astype(np.int64), starts)
        for b in np.flatnonzero((flat_parts == counts) & (counts > 0)).tolist():
            records.append(
                finding(
                    "MC301",
                    colliders.bodies[b].name,
                    None,
                    0.0,
                    0.0,
                    "no area: the collider is a segment or a point (every face degenerate)",
                )
            )
    if options.target is not None:
        records.extend(target_findings(colliders, options.target, units))
    return [dict(f.to_dict(), failed=f.rule in options.fail_rules) for f in records]


def _nums(values: np.ndarray) -> list[float | None]:
    """Floats as a list, non-finite ones as None."""
    return [v if math.isfinite(v) else None for v in values.tolist()]


def _vecs(values: np.ndarray) -> list[list[float] | None]:
    """Rows of 3-vectors as lists, rows with a non-finite entry as None."""
    finite = np.all(np.isfinite(values), axis=1).tolist()
    return [row if ok else None for row, ok in zip(values.tolist(), finite)]


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None
