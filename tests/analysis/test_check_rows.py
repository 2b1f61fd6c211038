"""The check report's rows kept as columns (issue 32 item 4): the native row writer gives the
bytes the dict path gives, and the rows read as the dicts they stand for."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from meshcol.analysis.check import check
from meshcol.analysis.check_report import ReportRows
from meshcol.io.report import dumps_json, dumps_rows

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("n", [7, 8_700])  # 8,700: blocks of rows on the core's threads
def test_rows_from_columns_are_json_dumps_of_the_dicts(n: int, monkeypatch) -> None:
    import meshcol.io.report

    monkeypatch.setattr(meshcol.io.report, "_ROWS_PER_CALL", 8_300)  # and a second call
    rng = np.random.default_rng(3)
    reals = rng.normal(size=n) * 10.0 ** rng.integers(-30, 30, size=n)
    reals[:4] = [np.nan, np.inf, -0.0, 1e16]
    vectors = rng.normal(size=(n, 3))
    vectors[1, 2] = -np.inf
    box = rng.normal(size=(n, 6))
    box[2, 0] = np.nan
    codes = np.resize(np.array([0, 1, -1, 2, 0, 1, 2], dtype=np.int64), n)
    table = ["plain", 'quote " and \\ slash', "caf\u00e9 \u2603 \U0001f600 \n\t"]
    raw = ["[]", '[\n        "x"\n      ]']  # as written at nesting 3
    columns = [
        ("a box", "box", box),
        ("flag", "boolean", rng.random(n) < 0.5),
        ("index", "index", np.resize(np.array([-1, 0, 5, -3, 2, 1, 0], dtype=np.int64), n)),
        ("integer", "integer", np.arange(n, dtype=np.int64) - 3),
        ("number", "number", reals),
        ("raw", "raw", np.resize(np.array([0, 1, -1, 0, 1, 0, 1], dtype=np.int64), n), raw),
        ("string", "string", codes, table),
        ("vector", "vector", vectors),
    ]

    def finite(values: np.ndarray) -> list | None:
        return values.tolist() if np.isfinite(values).all() else None

    rows = [
        {
            "a box": [finite(box[i, :3]), finite(box[i, 3:])],
            "flag": bool(columns[1][2][i]),
            "index": None if columns[2][2][i] < 0 else int(columns[2][2][i]),
            "integer": i - 3,
            "number": float(reals[i]) if np.isfinite(reals[i]) else None,
            "raw": None if columns[5][2][i] < 0 else json.loads(raw[columns[5][2][i]]),
            "string": None if codes[i] < 0 else table[codes[i]],
            "vector": finite(vectors[i]),
        }
        for i in range(n)
    ]
    expected = json.dumps({"rows": rows}, sort_keys=True, indent=2)
    assert dumps_json({"rows": rows}) == expected + "\n"
    text = '{\n  "rows": ' + dumps_rows(columns, n, 1) + "\n}"
    assert text == expected
    assert dumps_rows(columns, 0, 1) == "[]"


def test_rows_written_in_windows_are_the_rows_written_at_once(monkeypatch) -> None:
    import meshcol.io.report as report

    rng = np.random.default_rng(5)
    n = 23
    names = [f"body {k} \u2603" for k in range(200)]  # far more names than a window uses
    codes = rng.integers(-1, len(names), n).astype(np.int64)
    columns = [
        ("name", "string", codes, names),
        ("number", "number", rng.normal(size=n)),
        ("other", "string", rng.integers(0, 3, n).astype(np.int64), ["a", "b", "c"]),
    ]
    rows = [
        {
            "name": None if codes[i] < 0 else names[codes[i]],
            "number": float(columns[1][2][i]),
            "other": "abc"[columns[2][2][i]],
        }
        for i in range(n)
    ]
    expected = json.dumps(rows, sort_keys=True, indent=2).replace("\n", "\n  ")
    whole = dumps_rows(columns, n, 1)
    assert whole == expected
    monkeypatch.setattr(report, "_ROWS_PER_CALL", 4)
    assert dumps_rows(columns, n, 1) == whole


def test_rows_refuse_a_column_of_the_wrong_shape() -> None:
    with pytest.raises(ValueError, match="wrong type or shape"):
        dumps_rows([("x", "vector", np.zeros(3))], 3, 1)
    with pytest.raises(ValueError, match="unknown column kind"):
        dumps_rows([("x", "text", np.zeros(3))], 3, 1)
    with pytest.raises(IndexError, match="past its table"):
        dumps_rows([("x", "string", np.array([1], dtype=np.int64), ["a"])], 1, 1)


@pytest.mark.parametrize(
    "inputs",
    [
        ["samples/level/scene.json"],
        ["samples/bowl/scene.json"],
        ["samples/bowl/ball.obj", "samples/bowl/bowl.obj"],
    ],
)
def test_a_check_report_from_columns_is_the_report_from_dicts(inputs: list[str]) -> None:
    report = check([str(ROOT / i) for i in inputs], clearance=0.5)
    assert isinstance(report.pairs, ReportRows) and isinstance(report.bodies, ReportRows)
    assert len(report.pairs) > 0
    # the dict path: every row made in Python, the whole document encoded as one value
    assert report.to_json() == dumps_json(report.to_dict())
    worst = report.worst_pairs(3)
    plain = [dict(p) for p in report.pairs]
    touching = [p for p in plain if p["status"] != "separated"]
    key = [float("inf") if p["signed_distance"] is None else p["signed_distance"] for p in touching]
    order = sorted(range(len(touching)), key=lambda i: key[i])[:3]
    assert worst == [touching[i] for i in order]
    assert report.pairs == plain and report.pairs[0] == plain[0]


def _cube_obj(centres: list[tuple[float, float, float]], names: list[str]) -> str:
    lines: list[str] = []
    for k, ((x, y, z), name) in enumerate(zip(centres, names)):
        lines.append(f"o {name}")
        for dx in (-0.5, 0.5):
            for dy in (-0.5, 0.5):
                for dz in (-0.5, 0.5):
                    lines.append(f"v {x + dx} {y + dy} {z + dz}")
        quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
        for quad in quads:
            a, b, c, d = (8 * k + i for i in quad)
            lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"]
    return "\n".join(lines) + "\n"


def test_named_parts_and_other_names_are_written_from_columns(tmp_path: Path) -> None:
    (tmp_path / "pair.obj").write_text(_cube_obj([(0, 0, 0), (3, 0, 0)], ["left", "r\u00e9ght"]))
    (tmp_path / "one.obj").write_text(_cube_obj([(0, 0, 0)], ["cube"]))
    bodies = [
        {"name": "tw\u00f6", "mesh": "pair.obj"},
        {"name": "near", "mesh": "one.obj", "position": [3.4, 0.2, 0.1]},
        {"name": "apart", "mesh": "one.obj", "position": [0.0, 5.0, 0.0]},
        {"name": "a ball", "primitive": {"type": "sphere", "radius": 0.6}, "position": [0, 0, 1]},
    ]
    (tmp_path / "scene.json").write_text(json.dumps({"bodies": bodies}))
    report = check([str(tmp_path / "scene.json")], clearance=3.0)
    assert isinstance(report.pairs, ReportRows)
    named = [p for p in report.pairs if p["part_a"] or p["part_b"]]
    assert named and any(b["parts"] for b in report.bodies)
    assert report.to_json() == dumps_json(report.to_dict())


def test_primitive_bodies_are_packed_in_one_pass_as_body_by_body() -> None:
    """``build_colliders`` of bodies that are all primitives (one pass) gives each body the
    parts the body-by-body loop gives it (that loop runs when one mesh body joins them)."""
    from meshcol.analysis.colliders import build_colliders
    from meshcol.types import Body, Box, Capsule, Cylinder, Sphere

    rng = np.random.default_rng(32)
    shapes = [Sphere(0.5), Box((1.0, 2.0, 0.5)), Capsule(0.2, 1.0), Cylinder(0.3, 0.4)]
    bodies = []
    for i in range(40):
        pose = np.eye(4)
        pose[:3, 3] = rng.normal(size=3)
        shape = shapes[i % 4] if i % 3 else Sphere(float(rng.uniform(0.1, 1.0)))
        bodies.append(Body.of_primitive(f"b{i}", "scene.json", shape, pose=pose))
    mesh = Body("mesh", "m.obj", np.eye(3), np.array([[0, 1, 2]]))
    one_pass = build_colliders(bodies)
    by_body = build_colliders([*bodies, mesh])
    n = len(bodies)
    assert one_pass.kinds == by_body.kinds[:n] == ("primitive",) * n
    for name in ("part_body", "part_index", "part_label"):
        assert np.array_equal(getattr(one_pass, name), getattr(by_body, name)[:n]), name
    assert np.array_equal(one_pass.body_part_offsets, by_body.body_part_offsets[: n + 1])
    poses = one_pass.part_poses()
    assert np.array_equal(poses, by_body.part_poses()[:n])
    mine, theirs = one_pass.shapes, by_body.shapes.take(np.arange(n))
    assert np.array_equal(mine.kinds, theirs.kinds)
    assert np.array_equal(mine.params, theirs.params)
    assert len(mine) == n


def test_the_json_report_is_written_in_pieces_and_never_half(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from meshcol.io import report as report_io
    from meshcol.io.formats import write_report

    report = check([str(ROOT / "samples/level/scene.json")], clearance=0.5)
    path = tmp_path / "report.json"
    write_report(report, "json", str(path))
    assert path.read_text() == report.to_json() == dumps_json(report.to_dict())

    def failing(piece: report_io.RowsPiece, fd: int) -> None:  # fails after a piece
        os.write(fd, b"[")
        raise MemoryError("no room for the rows")

    monkeypatch.setattr(report_io.RowsPiece, "write_into", failing)
    other = tmp_path / "other.json"
    with pytest.raises(MemoryError):
        write_report(report, "json", str(other))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]

    def failing_text(columns: list, count: int, level: int):  # the text path (stdout)
        yield "["
        raise MemoryError("no room for the rows")

    monkeypatch.setattr(report_io, "rows_chunks", failing_text)
    with pytest.raises(MemoryError):
        report.to_json()


def test_name_ranks_of_names_in_order_and_not() -> None:
    """Each body's place among the distinct names (names already in order take a shortcut)."""
    from meshcol.analysis.check_report import name_ranks

    rng = np.random.default_rng(7)
    cases = [[], ["a"], ["a", "b", "c"], ["a", "a", "b"], ["b", "a"], ["a", "b", "b", "c"]]
    cases += [sorted({str(x) for x in rng.integers(0, 50, 20)}) for _ in range(5)]
    cases += [[str(x) for x in rng.integers(0, 6, 12)] for _ in range(20)]
    for names in cases:
        distinct = sorted(set(names))
        assert name_ranks(names).tolist() == [distinct.index(n) for n in names], names
