"""The report of ``meshcol sweep``: :class:`SweepReport` and its hits kept as columns,
:class:`SweepHits` (a sequence of :class:`SweepHit` made only when asked for), from which
every format is written: JSON through the core's row writer, CSV, and the CI suite behind
JUnit, GitHub, SARIF and markdown.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.io.report import round_significant, vector_columns
from meshcol.types import Body, Scene, TimeOfImpactStatus

__all__ = ["CSV_COLUMNS", "MOTION", "NamePairs", "SweepHit", "SweepHits", "SweepReport"]

#: The motion model, as the report states it.
MOTION = (
    "pivot (local origin unless given) moves linearly; constant angular velocity about it, "
    "the whole angle (shortest way to an end_rotation)"
)
#: Columns of :meth:`SweepReport.to_csv`, one row per pair (poses flattened row-major).
CSV_COLUMNS = (
    "body_a",
    "body_b",
    "part_a",
    "part_b",
    "status",
    "time_of_impact",
    "time",
    *vector_columns("point"),
    *vector_columns("normal"),
    "tunnelled",
    *vector_columns("pose_a", 16),
    *vector_columns("pose_b", 16),
    "iterations",
    "units",
)
#: Status names by value (the codes of the status column).
_STATUS_NAMES = [s.name for s in sorted(TimeOfImpactStatus, key=int)]


@dataclass(frozen=True)
class SweepHit:
    """One body pair that is not separated during the motion.

    Attributes
    ----------
    body_a, body_b : str
        Body names (``body_a`` comes first in the scene).
    part_a, part_b : str or None
        The parts of a body of several parts (``Body.parts``) that meet first; None for a
        body of one part.
    status : TimeOfImpactStatus
        ``HIT``, ``OVERLAPPED_AT_START`` or ``FAILED``.
    time_of_impact : float
        Fraction of the motion (for ``FAILED``: the last safe lower bound).
    time : float or None
        ``time_of_impact * duration`` in seconds, when the scene has a duration.
    point : (3,) float64
        World contact point at the time of impact.
    normal : (3,) float64
        World unit normal from a towards b at the time of impact.
    pose_a, pose_b : (4, 4) float64
        Both bodies' world-from-local poses at the time of impact.
    tunnelled : bool
        True for a hit that a discrete check at the start and end poses alone misses (the
        bodies overlap neither at the start nor at the end).
    iterations : int
        Steps of the pair query that decided the pair.
    """

    body_a: str
    body_b: str
    part_a: str | None
    part_b: str | None
    status: TimeOfImpactStatus
    time_of_impact: float
    time: float | None
    point: np.ndarray
    normal: np.ndarray
    pose_a: np.ndarray
    pose_b: np.ndarray
    tunnelled: bool
    iterations: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields (lists for arrays, the status by name), numbers rounded to 12
        significant digits (far below the tolerance) so reports compare across machines."""
        return {
            "body_a": self.body_a,
            "body_b": self.body_b,
            "part_a": self.part_a,
            "part_b": self.part_b,
            "status": self.status.name,
            "time_of_impact": _round(self.time_of_impact),
            "time": _round(self.time),
            "point": _round(self.point),
            "normal": _round(self.normal),
            "pose_a": _round(self.pose_a),
            "pose_b": _round(self.pose_b),
            "tunnelled": self.tunnelled,
            "iterations": self.iterations,
        }


def _round(value: Any) -> Any:
    """Floats (or nested arrays of them) to 12 significant digits, -0.0 as 0.0
    (:func:`~meshcol.io.report.round_significant`), as Python floats or nested lists."""
    if value is None:
        return None
    return round_significant(value).tolist()


def codes_of(values: Sequence[str | None]) -> tuple[np.ndarray, list[str]]:
    """Each value's code into a table of the distinct ones (first-seen order; None -1)."""
    table: dict[str | None, int] = {
        v: k for k, v in enumerate(v for v in dict.fromkeys(values) if v is not None)
    }
    table[None] = -1
    codes = np.fromiter(map(table.__getitem__, values), np.int64, len(values))
    return codes, [v for v in table if v is not None]


@dataclass(frozen=True, eq=False)
class SweepHits(Sequence[SweepHit]):
    """The hits of a sweep as columns, row ``k`` the ``k``-th :class:`SweepHit` (made when
    asked for, then kept); the report writers read the columns.

    Attributes
    ----------
    names : list of str
        Body names, the table of ``body_a`` and ``body_b``.
    body_a, body_b : (k,) int64
        Indices into ``names``.
    parts : list of str
        Part names, the table of ``part_a`` and ``part_b`` (-1: None).
    part_a, part_b : (k,) int64
    status : (k,) int64
        :class:`~meshcol.types.TimeOfImpactStatus` values.
    time_of_impact : (k,) float64
    time : (k,) float64 or None
        ``time_of_impact * duration`` in seconds; None when the scene has no duration.
    point, normal : (k, 3) float64
    pose_a, pose_b : (k, 4, 4) float64
    tunnelled : (k,) bool
    iterations : (k,) int64
    """

    names: list[str]
    body_a: np.ndarray
    body_b: np.ndarray
    parts: list[str]
    part_a: np.ndarray
    part_b: np.ndarray
    status: np.ndarray
    time_of_impact: np.ndarray
    time: np.ndarray | None
    point: np.ndarray
    normal: np.ndarray
    pose_a: np.ndarray
    pose_b: np.ndarray
    tunnelled: np.ndarray
    iterations: np.ndarray
    _made: dict = field(default_factory=dict, repr=False)

    @classmethod
    def of_hits(cls, hits: Sequence[SweepHit]) -> SweepHits:
        """The columns of hits made one by one (a report made by hand)."""
        if isinstance(hits, SweepHits):
            return hits
        codes, names = codes_of([n for h in hits for n in (h.body_a, h.body_b)])
        part_codes, parts = codes_of([n for h in hits for n in (h.part_a, h.part_b)])
        time = None  # (a time missing from some hits only: NaN, written as null)
        if any(h.time is not None for h in hits):
            time = np.array([np.nan if h.time is None else h.time for h in hits], np.float64)
        made = cls(
            names,
            codes[0::2],
            codes[1::2],
            parts,
            part_codes[0::2],
            part_codes[1::2],
            np.array([int(h.status) for h in hits], dtype=np.int64),
            np.array([h.time_of_impact for h in hits], dtype=np.float64),
            time,
            _stack([h.point for h in hits], (3,)),
            _stack([h.normal for h in hits], (3,)),
            _stack([h.pose_a for h in hits], (4, 4)),
            _stack([h.pose_b for h in hits], (4, 4)),
            np.array([bool(h.tunnelled) for h in hits], dtype=bool),
            np.array([int(h.iterations) for h in hits], dtype=np.int64),
        )
        made._made.update(enumerate(hits))
        return made

    def __len__(self) -> int:
        return len(self.status)

    def __getitem__(self, item: Any) -> Any:
        if isinstance(item, slice):
            return tuple(self[k] for k in range(*item.indices(len(self))))
        k = int(item)
        if k < 0:
            k += len(self)
        if not 0 <= k < len(self):
            raise IndexError("hit index out of range")
        hit = self._made.get(k)
        if hit is None:
            hit = self._made[k] = self._hit(k)
        return hit

    def __iter__(self) -> Iterator[SweepHit]:
        return (self[k] for k in range(len(self)))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (tuple, list, SweepHits)):
            return tuple(self) == tuple(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"SweepHits({len(self)} hits)"

    def _hit(self, k: int) -> SweepHit:
        time = self.time
        part_a, part_b = int(self.part_a[k]), int(self.part_b[k])
        return SweepHit(
            body_a=self.names[int(self.body_a[k])],
            body_b=self.names[int(self.body_b[k])],
            part_a=None if part_a < 0 else self.parts[part_a],
            part_b=None if part_b < 0 else self.parts[part_b],
            status=TimeOfImpactStatus(int(self.status[k])),
            time_of_impact=float(self.time_of_impact[k]),
            time=None if time is None else float(time[k]),
            point=self.point[k].copy(),
            normal=self.normal[k].copy(),
            pose_a=self.pose_a[k].copy(),
            pose_b=self.pose_b[k].copy(),
            tunnelled=bool(self.tunnelled[k]),
            iterations=int(self.iterations[k]),
        )

    def counts(self) -> np.ndarray:
        """Hits by status value (an array indexed by :class:`TimeOfImpactStatus`)."""
        return np.bincount(self.status, minlength=len(_STATUS_NAMES))

    def rounded(self) -> dict[str, np.ndarray]:
        """The float columns rounded to 12 significant digits (``time``: NaN without a
        duration), as the reports write them; made once."""
        done = self._made.get("rounded")
        if done is None:
            k = len(self)
            time = self.time
            values = np.concatenate(
                [
                    self.time_of_impact,
                    np.full(k, np.nan) if time is None else time,
                    self.point.reshape(-1),
                    self.normal.reshape(-1),
                    self.pose_a.reshape(-1),
                    self.pose_b.reshape(-1),
                ]
            )
            parts = np.split(round_significant(values), np.cumsum([k, k, 3 * k, 3 * k, 16 * k]))
            done = dict(
                zip(
                    ("time_of_impact", "time", "point", "normal", "pose_a", "pose_b"),
                    (
                        parts[0],
                        parts[1],
                        parts[2].reshape(k, 3),
                        parts[3].reshape(k, 3),
                        parts[4].reshape(k, 16),
                        parts[5].reshape(k, 16),
                    ),
                )
            )
            self._made["rounded"] = done
        return done

    def json_columns(self) -> list[tuple]:
        """The rows of :meth:`SweepHit.to_dict` as the core's row writer's columns, in key
        order (:func:`meshcol.io.report.dumps_rows`)."""
        r = self.rounded()
        statuses = np.ascontiguousarray(self.status, dtype=np.int64)
        return [
            ("body_a", "string", _whole(self.body_a), self.names),
            ("body_b", "string", _whole(self.body_b), self.names),
            ("iterations", "integer", _whole(self.iterations)),
            ("normal", "numbers3", r["normal"]),
            ("part_a", "string", _whole(self.part_a), self.parts),
            ("part_b", "string", _whole(self.part_b), self.parts),
            ("point", "numbers3", r["point"]),
            ("pose_a", "matrix4", r["pose_a"]),
            ("pose_b", "matrix4", r["pose_b"]),
            ("status", "string", statuses, _STATUS_NAMES),
            ("time", "number", r["time"]),
            ("time_of_impact", "number", r["time_of_impact"]),
            ("tunnelled", "boolean", np.ascontiguousarray(self.tunnelled, dtype=bool)),
        ]

    def rows(self, index: np.ndarray | None = None) -> list[dict[str, Any]]:
        """:meth:`SweepHit.to_dict` of the rows ``index`` (all when None), from the columns."""
        rows = np.arange(len(self)) if index is None else np.asarray(index, dtype=np.int64)
        r = self.rounded()
        time = None if self.time is None else r["time"][rows].tolist()
        names, parts = self.names, self.parts
        return [
            {
                "body_a": names[a],
                "body_b": names[b],
                "part_a": None if pa < 0 else parts[pa],
                "part_b": None if pb < 0 else parts[pb],
                "status": _STATUS_NAMES[s],
                "time_of_impact": t,
                "time": None if time is None else time[n],
                "point": point,
                "normal": normal,
                "pose_a": [pose_a[0:4], pose_a[4:8], pose_a[8:12], pose_a[12:16]],
                "pose_b": [pose_b[0:4], pose_b[4:8], pose_b[8:12], pose_b[12:16]],
                "tunnelled": tunnelled,
                "iterations": iterations,
            }
            for n, (
                a,
                b,
                pa,
                pb,
                s,
                t,
                point,
                normal,
                pose_a,
                pose_b,
                tunnelled,
                iterations,
            ) in enumerate(
                zip(
                    self.body_a[rows].tolist(),
                    self.body_b[rows].tolist(),
                    self.part_a[rows].tolist(),
                    self.part_b[rows].tolist(),
                    self.status[rows].tolist(),
                    r["time_of_impact"][rows].tolist(),
                    r["point"][rows].tolist(),
                    r["normal"][rows].tolist(),
                    r["pose_a"][rows].tolist(),
                    r["pose_b"][rows].tolist(),
                    self.tunnelled[rows].tolist(),
                    self.iterations[rows].tolist(),
                )
            )
        ]

    def csv_text(self, units: str | None) -> str:
        """:data:`CSV_COLUMNS` text (:func:`meshcol.io.report.dumps_csv`'s cells: floats as
        ``repr``, non-finite and None empty), written column by column."""
        r = self.rounded()
        names, parts = self.names, self.parts
        empty = ""
        columns = [
            [names[i] for i in self.body_a.tolist()],
            [names[i] for i in self.body_b.tolist()],
            [empty if i < 0 else parts[i] for i in self.part_a.tolist()],
            [empty if i < 0 else parts[i] for i in self.part_b.tolist()],
            [_STATUS_NAMES[s] for s in self.status.tolist()],
            _float_cells(r["time_of_impact"]),
            _float_cells(r["time"]),
            *(_float_cells(c) for c in r["point"].T),
            *(_float_cells(c) for c in r["normal"].T),
            [str(v) for v in self.tunnelled.tolist()],
            *(_float_cells(c) for c in r["pose_a"].T),
            *(_float_cells(c) for c in r["pose_b"].T),
            [str(v) for v in self.iterations.tolist()],
            [empty if units is None else str(units)] * len(self),
        ]
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        writer.writerows(zip(*columns))
        return buf.getvalue()

    def first(self, count: int) -> list[SweepHit]:
        """Up to ``count`` hits, the undecided (``FAILED``) first, then by time of impact, ties
        in report order."""
        key = self.status != TimeOfImpactStatus.FAILED
        order = np.lexsort((self.time_of_impact, key))[:count]
        return [self[k] for k in order.tolist()]


@dataclass(frozen=True, eq=False)
class NamePairs(Sequence[tuple[str, str]]):
    """Pairs of body names held as indices into ``names`` (a sweep's 60,000 separated
    pairs: no tuple made until one is read)."""

    names: list[str]
    a: np.ndarray
    b: np.ndarray

    def __len__(self) -> int:
        return len(self.a)

    def __getitem__(self, item: Any) -> Any:
        if isinstance(item, slice):
            return tuple(self[k] for k in range(*item.indices(len(self))))
        return self.names[int(self.a[item])], self.names[int(self.b[item])]

    def __iter__(self) -> Iterator[tuple[str, str]]:
        names = self.names
        return ((names[i], names[j]) for i, j in zip(self.a.tolist(), self.b.tolist()))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (tuple, list, NamePairs)):
            return tuple(self) == tuple(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"NamePairs({len(self)} pairs)"


def _stack(arrays: Sequence[Any], shape: tuple[int, ...]) -> np.ndarray:
    if not arrays:
        return np.zeros((0, *shape), dtype=np.float64)
    return np.stack([np.asarray(a, dtype=np.float64).reshape(shape) for a in arrays])


def _whole(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.int64)


def _float_cells(values: np.ndarray) -> list[str]:
    """CSV cells of floats: ``repr``, a non-finite one empty."""
    cells = list(map(float.__repr__, values.tolist()))
    for k in np.flatnonzero(~np.isfinite(values)).tolist():
        cells[k] = ""
    return cells


@dataclass(frozen=True)
class SweepReport:
    """What :func:`meshcol.analysis.sweep.sweep` found.

    Attributes
    ----------
    scene : Scene
    bodies : tuple of Body
        The scene's bodies less the ``UCX_`` parts that became colliders.
    collider : str
        Default collider kind (``hull``, ``decomposed`` or ``mesh``).
    tolerance : float
        Contact distance used (world units).
    hits : sequence of SweepHit
        Every body pair that is not ``SEPARATED``, sorted by (body_a, body_b) names: a sweep's
        are :class:`SweepHits` (columns; each hit made when read).
    candidate_pairs : int
        Body pairs whose swept bounds overlap (the pairs the narrow phase ran on).
    part_pairs : int
        Pairs of convex parts the narrow phase ran on.
    moving : tuple of bool
        Per body of ``bodies``: whether it moves.
    fail_on : str
        ``hit`` (any pair that is not separated fails the run) or ``none``.
    separated : sequence of (str, str)
        The candidate body pairs (moving, swept bounds overlapping) that stay separated, as
        ``(body_a, body_b)`` names, sorted (a sweep's are :class:`NamePairs`).
    """

    scene: Scene
    bodies: tuple[Body, ...]
    collider: str
    tolerance: float
    hits: Sequence[SweepHit]
    candidate_pairs: int
    part_pairs: int
    moving: tuple[bool, ...] = field(default=())
    fail_on: str = "hit"
    warnings: tuple[str, ...] = ()
    separated: Sequence[tuple[str, str]] = ()

    @property
    def columns(self) -> SweepHits:
        """The hits as columns (:class:`SweepHits`; made from hits given one by one)."""
        return SweepHits.of_hits(self.hits)

    @property
    def failed(self) -> bool:
        """True when any pair hits, overlaps at the start or could not be decided."""
        return len(self.hits) > 0

    @property
    def exit_code(self) -> int:
        """1 when ``fail_on`` is ``hit`` and a pair is not separated, else 0."""
        return 1 if self.fail_on == "hit" and self.failed else 0

    @property
    def summary(self) -> dict[str, int]:
        """Counts: bodies, moving bodies, candidate and part pairs, hits by status."""
        hits = self.columns
        count = hits.counts().tolist()
        return {
            "bodies": len(self.bodies),
            "moving_bodies": int(sum(self.moving)),
            "candidate_pairs": self.candidate_pairs,
            "part_pairs": self.part_pairs,
            "hits": count[TimeOfImpactStatus.HIT],
            "tunnelled": int(np.count_nonzero(hits.tunnelled)),
            "overlapped_at_start": count[TimeOfImpactStatus.OVERLAPPED_AT_START],
            "failed": count[TimeOfImpactStatus.FAILED],
        }

    @property
    def settings(self) -> dict[str, Any]:
        """The options of the run, as the report states them."""
        return {
            "shape": self.collider,
            "tolerance": float(f"{self.tolerance:.12g}"),
            "fail_on": self.fail_on,
            "motion": MOTION,
            "frame": "world",
        }

    def _document(self, pairs: Any) -> dict[str, Any]:
        from meshcol.io.report import envelope

        return {
            **envelope("sweep", self.settings, self.scene.units),
            "failed": self.exit_code == 1,
            "warnings": list(self.warnings),
            "duration": self.scene.duration,
            "bodies": [
                {"name": b.name, "source": b.source, "parts": list(b.parts), "moving": m}
                for b, m in zip(self.bodies, self.moving)
            ],
            "summary": self.summary,
            "pairs": pairs,
        }

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, ``failed`` (the policy verdict), duration,
        bodies, summary and one entry per pair that is not separated."""
        return self._document(self.columns.rows())

    def json_pieces(self) -> Iterator[Any]:
        """The JSON report in pieces (:func:`meshcol.io.report.document_pieces`): the pairs
        from their columns by the core's row writer."""
        from meshcol.analysis.check_report import ReportRows
        from meshcol.io.report import document_pieces

        hits = self.columns
        pairs = ReportRows(len(hits), hits.rows, hits.json_columns)
        return document_pieces(self._document(pairs), ["pairs"])

    def to_json(self) -> str:
        from meshcol.io.report import text_pieces

        return "".join(text_pieces(self.json_pieces()))

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per candidate
        pair (``body_a <-> body_b``); a pair that hits, overlaps at the start or cannot be
        decided is a failure under ``--fail-on hit`` (a warning under ``none``), with its
        time of impact, point and normal; the pairs that stay separated pass."""
        from meshcol.io.ci import CiCase, CiSuite, collapse_passed

        source = self.scene.source
        cases = _hit_cases(self.columns, self.fail_on == "hit", source, self.scene.units)
        for a, b in self.separated:
            cases.append(
                CiCase(
                    name=f"{a} <-> {b}",
                    classname="meshcol.sweep",
                    message="separated during the whole motion",
                    file=source,
                )
            )
        cases.sort(key=lambda case: case.name)
        s = self.summary
        return CiSuite(
            "sweep",
            tuple(collapse_passed(cases, "pairs", "meshcol.sweep")),
            self.settings,
            warnings=tuple(self.warnings),
            verdict=f"{s['hits']} hits, {s['overlapped_at_start']} overlapped at start, "
            f"{s['failed']} undecided of {s['candidate_pairs']} candidate pairs",
            units=self.scene.units,
        )

    def to_csv(self) -> str:
        """One row per pair (:data:`CSV_COLUMNS`): vectors split into ``_x/_y/_z`` columns,
        poses into 16 columns ``_00`` ... ``_33`` (row-major), as every command's CSV."""
        return self.columns.csv_text(self.scene.units)


def _hit_cases(hits: SweepHits, fail: bool, source: str | None, units: str | None) -> list:
    """The CI cases of the hits (:meth:`SweepReport.ci_suite`), from the columns."""
    from meshcol.io.ci import CiCase, details, number

    r = hits.rounded()
    names, parts = hits.names, hits.parts
    times = [None] * len(hits) if hits.time is None else hits.time.tolist()
    overlapped = TimeOfImpactStatus.OVERLAPPED_AT_START
    cases = []
    for a, b, pa, pb, status, t, time, tunnelled, point, normal, iterations in zip(
        hits.body_a.tolist(),
        hits.body_b.tolist(),
        hits.part_a.tolist(),
        hits.part_b.tolist(),
        hits.status.tolist(),
        hits.time_of_impact.tolist(),
        times,
        hits.tunnelled.tolist(),
        r["point"].tolist(),
        r["normal"].tolist(),
        hits.iterations.tolist(),
    ):
        if status == TimeOfImpactStatus.HIT:
            message = f"HIT at time of impact {number(t)}"
        elif status == overlapped:
            message = "OVERLAPPED_AT_START: the bodies overlap before they move"
        else:
            message = f"FAILED: undecided, no contact before time of impact {number(t)}"
        if time is not None and status != overlapped:
            message += f" (t = {number(time, 's')})"
        if tunnelled:
            message += ", tunnelled (missed at the start and end poses)"
        part_a = None if pa < 0 else parts[pa]
        part_b = None if pb < 0 else parts[pb]
        cases.append(
            CiCase(
                name=f"{names[a]} <-> {names[b]}",
                classname="meshcol.sweep",
                outcome="failure" if fail else "passed",
                message=message,
                file=source,
                kind=_STATUS_NAMES[status],
                details=details(
                    [
                        ("part_a", part_a),
                        ("part_b", part_b),
                        ("point", point),
                        ("normal", normal),
                        ("iterations", iterations),
                        ("units", units),
                    ]
                )
                if fail
                else "",
                warn=not fail,
            )
        )
    return cases
