"""The sweep's first contact per body pair by segment operations
(``meshcol/analysis/sweep.py: first_contacts``) against the per-pair loop it replaced (kept
here as the oracle: a dict of lists by body pair, numpy per pair), on random part-pair tables;
the 12-significant-digit rounding of the core (``round_significant``) against Python's
``float(f"{v:.12g}") + 0.0``; the hits kept as columns against the hits made one by one."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from meshcol.analysis.sweep import SweepHit, SweepHits, SweepReport, first_contacts
from meshcol.errors import MeshcolError
from meshcol.io.report import dumps_json, round_significant
from meshcol.types import Body, Scene, TimeOfImpactStatus

S = TimeOfImpactStatus


def loop_first_contacts(body_pairs, status, fraction, at_start, at_end):
    """The selection of sweep's former ``_first_contacts``/``_first_contact`` (main 4faa8d9),
    pair by pair: ``[(pair, row or None, status, tunnelled)]`` in the order the table first
    names each pair; MeshcolError at the first pair with an invalid row."""
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (i, j) in enumerate(np.asarray(body_pairs).reshape(-1, 2).tolist()):
        groups.setdefault((i, j), []).append(k)
    out = []
    for pair, members in groups.items():
        ks = np.asarray(members)
        stat = status[ks]
        if np.any(stat == S.INVALID_INPUT):
            raise MeshcolError(f"bodies {pair}: invalid shape or pose")
        live = ks[stat != S.SEPARATED]
        if len(live) == 0:
            out.append((pair, None, S.SEPARATED, False))
            continue
        best = live[np.argmin(fraction[live])]
        best_status = S(int(status[best]))
        if np.any(stat == S.OVERLAPPED_AT_START):
            best = ks[np.argmax(stat == S.OVERLAPPED_AT_START)]
            best_status = S.OVERLAPPED_AT_START
        elif best_status == S.HIT:
            failed = live[status[live] == S.FAILED]
            if len(failed) and fraction[failed].min() < fraction[best]:
                best_status = S.FAILED
        tunnelled = best_status == S.HIT and not np.any(at_start[ks]) and not np.any(at_end[ks])
        out.append((pair, int(best), best_status, bool(tunnelled)))
    return out


@st.composite
def tables(draw, invalid: bool = False):
    """Part-pair tables: a few bodies (so several part pairs per body pair), fractions from a
    small set (ties), every status, NaN now and then."""
    count = draw(st.integers(0, 60))
    bodies = draw(st.integers(2, 6))
    statuses = [S.HIT, S.SEPARATED, S.OVERLAPPED_AT_START, S.FAILED]
    if invalid:
        statuses.append(S.INVALID_INPUT)
    pairs, status, fraction, start, end = [], [], [], [], []
    for _ in range(count):
        i = draw(st.integers(0, bodies - 2))
        pairs.append((i, draw(st.integers(i + 1, bodies - 1))))
        status.append(int(draw(st.sampled_from(statuses))))
        fraction.append(draw(st.sampled_from([0.0, 0.25, 0.5, 0.5, 0.75, 1.0, math.nan])))
        start.append(draw(st.booleans()))
        end.append(draw(st.booleans()))
    return (
        np.asarray(pairs, dtype=np.int64).reshape(-1, 2),
        np.asarray(status, dtype=np.int64),
        np.asarray(fraction, dtype=np.float64),
        np.asarray(start, dtype=bool),
        np.asarray(end, dtype=bool),
    )


def _as_list(first):
    return [
        (tuple(p), None if r < 0 else r, S(s), t)
        for p, r, s, t in zip(
            first.body_pairs.tolist(),
            first.row.tolist(),
            first.status.tolist(),
            first.tunnelled.tolist(),
        )
    ]


@given(tables())
def test_segment_selection_is_the_loop(table) -> None:
    first = first_contacts(*table)
    assert first.invalid == -1
    assert _as_list(first) == loop_first_contacts(*table)


@given(tables(invalid=True))
def test_invalid_rows_name_the_loop_pair(table) -> None:
    first = first_contacts(*table)
    try:
        expected = loop_first_contacts(*table)
    except MeshcolError as exc:
        assert first.invalid >= 0
        assert str(tuple(first.body_pairs[first.invalid].tolist())) in str(exc)
    else:
        assert first.invalid == -1 and _as_list(first) == expected


def test_hand_picked_tie_breaks() -> None:
    """Overlapping at the start wins over an earlier hit; a FAILED row earlier than the
    earliest HIT makes the pair FAILED; equal fractions keep the first row."""
    pairs = np.array([[0, 1], [0, 1], [0, 2], [0, 2], [1, 2], [1, 2], [0, 1]])
    status = np.array([S.HIT, S.OVERLAPPED_AT_START, S.HIT, S.FAILED, S.HIT, S.HIT, S.HIT])
    fraction = np.array([0.1, 0.0, 0.5, 0.25, 0.5, 0.5, 0.05])
    no = np.zeros(7, dtype=bool)
    first = first_contacts(pairs, status, fraction, no, no)
    assert _as_list(first) == [
        ((0, 1), 1, S.OVERLAPPED_AT_START, False),
        ((0, 2), 3, S.FAILED, False),
        ((1, 2), 4, S.HIT, True),
    ]
    assert _as_list(first) == loop_first_contacts(pairs, status, fraction, no, no)


EDGES = [
    0.0,
    -0.0,
    5e-324,
    -5e-324,
    2.2250738585072014e-308,
    2.225073858507201e-308,  # the largest subnormal
    1e308,
    -1e308,
    1.7976931348623157e308,
    0.5,
    2.5,
    1.0000000000005,
    1.0000000000015,
    0.1234567890125,
    -0.1234567890125,
    123456789012.5,
    9.9999999999995e-5,
    9.99999999999949e-5,
    1e16,
    1e-16,
    math.pi,
    -math.e,
]


def _python(v: float) -> float:
    return float(f"{v:.12g}") + 0.0


def test_rounding_matches_python_on_edges() -> None:
    values = np.array(EDGES)
    got = round_significant(values)
    want = [_python(v) for v in EDGES]
    assert [struct.pack("<d", v) for v in got.tolist()] == [struct.pack("<d", v) for v in want]


def test_rounding_keeps_non_finite_and_shape() -> None:
    values = np.array([[math.nan, math.inf], [-math.inf, -0.0]])
    got = round_significant(values)
    assert got.shape == (2, 2)
    assert math.isnan(got[0, 0]) and got[0, 1] == math.inf and got[1, 0] == -math.inf
    assert math.copysign(1.0, got[1, 1]) == 1.0


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_rounding_matches_python(value: float) -> None:
    (got,) = round_significant(np.array([value])).tolist()
    assert struct.pack("<d", got) == struct.pack("<d", _python(value))


@given(st.integers(0, (1 << 64) - 1))
def test_rounding_matches_python_on_any_bits(bits: int) -> None:
    (value,) = struct.unpack("<d", bits.to_bytes(8, "little"))
    if not math.isfinite(value):
        return
    (got,) = round_significant(np.array([value])).tolist()
    assert struct.pack("<d", got) == struct.pack("<d", _python(value))


def _hit(k: int, rng: np.random.Generator, parts: bool, time: bool) -> SweepHit:
    pose = np.eye(4)
    pose[:3, 3] = rng.normal(size=3) * 10.0 ** rng.integers(-8, 8)
    t = float(rng.random())
    return SweepHit(
        body_a=f"a{k % 3}",
        body_b=f"b{k}",
        part_a=f"p{k % 2}" if parts else None,
        part_b=None,
        status=S([S.HIT, S.OVERLAPPED_AT_START, S.FAILED][k % 3]),
        time_of_impact=t,
        time=t * 2.5 if time else None,
        point=rng.normal(size=3) * 1e-3,
        normal=np.array([-0.0, 1.0 / 3.0, math.nan if k == 4 else 0.5]),
        pose_a=pose,
        pose_b=np.eye(4) * -1.0,
        tunnelled=k % 2 == 0,
        iterations=k,
    )


@pytest.mark.parametrize("parts, time", [(False, False), (True, True)])
def test_columns_write_what_the_hits_write(parts: bool, time: bool) -> None:
    """A report of hits made one by one: its rows, JSON (through the core's row writer) and
    CSV from the columns are those of each hit's ``to_dict`` written by ``dumps_json`` and
    ``dumps_csv``, as the report wrote them before the columns."""
    from meshcol.io.report import dumps_csv, split_vectors

    rng = np.random.default_rng(3)
    hits = tuple(_hit(k, rng, parts, time) for k in range(7))
    body = Body("a0", None, np.eye(3), np.array([[0, 1, 2]]))
    scene = Scene(bodies=(body,), units="m", duration=2.5 if time else None)
    report = SweepReport(scene, scene.bodies, "hull", 1e-6, hits, 9, 12, (True,), "none")
    columns = SweepHits.of_hits(hits)
    assert dumps_json(columns.rows()) == dumps_json([h.to_dict() for h in hits])  # NaN: null
    assert report.to_json() == dumps_json(dict(report.to_dict(), pairs=[h.to_dict() for h in hits]))
    sizes = {"point": 3, "normal": 3, "pose_a": 16, "pose_b": 16}
    rows = [split_vectors(dict(h.to_dict(), units="m"), sizes) for h in hits]
    from meshcol.analysis.sweep import CSV_COLUMNS

    assert report.to_csv() == dumps_csv(rows, CSV_COLUMNS)
    assert columns == hits and list(columns) == list(hits) and columns[-1] is hits[-1]


def test_a_sweep_writes_from_columns_what_its_hits_write() -> None:
    """A sweep of 40 moving boxes (several hits, some overlapping at the start): its JSON
    (streamed through the core's row writer) and CSV are those its SweepHit objects write
    one by one, its hits sorted by names, its first contacts those of the loop."""
    import trimesh

    import meshcol
    from meshcol.analysis.sweep import CSV_COLUMNS
    from meshcol.io.report import dumps_csv, split_vectors

    rng = np.random.default_rng(7)
    box = trimesh.creation.box((0.5, 0.5, 0.5))
    bodies = []
    for k in range(40):
        start, end = np.eye(4), np.eye(4)
        start[:3, 3] = [k % 8, k // 8, 0.0] + rng.normal(0, 0.1, 3)
        end[:3, 3] = start[:3, 3] + rng.uniform(-1.5, 1.5, 3) * [1, 1, 0]
        name = f"b{(k * 17) % 40:02d}"  # names not in scene order
        bodies.append(Body(name, None, box.vertices, box.faces, start, end))
    report = meshcol.sweep(Scene(tuple(bodies), units="m", duration=2.0), fail_on="none")
    hits = list(report.hits)
    assert len(hits) >= 5 and [(h.body_a, h.body_b) for h in hits] == sorted(
        (h.body_a, h.body_b) for h in hits
    )
    whole = dict(report.to_dict(), pairs=[h.to_dict() for h in hits])
    assert report.to_json() == dumps_json(whole)
    sizes = {"point": 3, "normal": 3, "pose_a": 16, "pose_b": 16}
    rows = [split_vectors(dict(h.to_dict(), units="m"), sizes) for h in hits]
    assert report.to_csv() == dumps_csv(rows, CSV_COLUMNS)
    assert list(report.separated) == sorted(report.separated)
    assert len(report.separated) + len(hits) == report.candidate_pairs
