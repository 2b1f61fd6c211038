"""The run index of ``meshcol ci`` (decomposition/result_cache.py) keeps one copy of the rules
its suites name (issue 31 item 3: at 12 kB a job, a 10,000-job index was 125 MB, read by
every warm run and written by every run that changed one file); read back, every summary is
what was stored."""

from __future__ import annotations

import copy

from meshcol.decomposition.result_cache import (
    FORMAT_VERSION,
    _index_name,
    read_index,
    store_index,
)


def _summary(i: int, rules: dict) -> dict:
    case = {"name": f"props/p{i}.obj::p{i}", "outcome": "passed", "rules": []}
    return {"exit_code": 0, "reads": [], "suite": {"cases": [case], "rules": rules}}


def test_the_index_stores_each_rules_table_once_and_reads_every_summary_back(tmp_path) -> None:
    rules = {f"MC{n}": {"id": f"MC{n}", "summary": "x" * 400} for n in range(100, 130)}
    other = {"MC401": {"id": "MC401", "summary": "not watertight"}}
    entries = {}
    for i in range(200):
        # fresh copies (a cold run) and shared objects (summaries read from the last index)
        table = other if i % 50 == 0 else (rules if i % 2 else copy.deepcopy(rules))
        entries[f"k{i}"] = (_summary(i, table), {f"props/p{i}.obj": f"d{i}"})
    entries["plain"] = ({"exit_code": 2, "error": "x"}, {})
    before = copy.deepcopy(entries)
    store_index("run", entries, {}, tmp_path)
    assert entries == before  # what the caller holds is untouched
    size = (tmp_path / _index_name("run")).stat().st_size
    assert size < 60_000  # 200 x 13 kB inline
    index = read_index("run", tmp_path)
    assert index["format"] == FORMAT_VERSION
    assert len(index["shared_rules"]) == 2
    for key, (summary, depends) in before.items():
        assert index["entries"][key] == {"summary": summary, "depends": depends}


def test_summaries_decode_when_read_and_unchanged_ones_are_written_back_as_read(
    tmp_path,
) -> None:
    from meshcol.decomposition.result_cache import Summary

    rules = {"MC401": {"id": "MC401", "summary": "not watertight"}}
    entries = {f"k{i}": (_summary(i, rules), {}) for i in range(3)}
    store_index("run", entries, {"/x/a.obj": [1, 2, 3, 4, 5, "d"]}, tmp_path)
    index = read_index("run", tmp_path)
    summary = index["entries"]["k1"]["summary"]
    assert isinstance(summary, Summary) and summary._value is None
    assert summary["exit_code"] == 0 and "error" not in summary
    assert summary._value is None  # the exit code and "no error" need no decoding
    assert summary["suite"]["rules"] == rules  # the shared copy, put back
    assert index["stats"] == {"/x/a.obj": [1, 2, 3, 4, 5, "d"]}
    # a run that reuses two summaries and drops one: their lines are the bytes read
    again = {key: (index["entries"][key]["summary"], {}) for key in ("k0", "k2")}
    store_index("run2", again, {}, tmp_path)
    first = (tmp_path / _index_name("run")).read_bytes().split(b"\n")
    second = (tmp_path / _index_name("run2")).read_bytes().split(b"\n")
    assert second[3:5] == [first[3], first[5]]
    reread = read_index("run2", tmp_path)
    assert reread["entries"]["k2"]["summary"] == _summary(2, rules)
    # a table no line refers to any more is not carried over
    fresh = {"k9": (_summary(9, {"MC1": {"id": "MC1"}}), {})}
    store_index("run3", fresh, {}, tmp_path)
    assert len(read_index("run3", tmp_path)["shared_rules"]) == 1


def test_a_cut_or_foreign_index_is_no_index(tmp_path) -> None:
    entries = {f"k{i}": (_summary(i, {}), {"a.obj": "d"}) for i in range(3)}
    store_index("run", entries, {}, tmp_path)
    path = tmp_path / _index_name("run")
    data = path.read_bytes()
    path.write_bytes(data[:-10])  # cut mid-line: no final newline
    assert read_index("run", tmp_path) == {}
    path.write_bytes(b'{"format": 2, "entries": {}}')  # the last layout
    assert read_index("run", tmp_path) == {}
    path.write_bytes(data.replace(b"\t", b" ", 1))
    assert read_index("run", tmp_path) == {}


def test_digests_of_plain_and_odd_spellings_of_a_path_are_one(tmp_path, monkeypatch) -> None:
    from meshcol.decomposition.result_cache import Digests

    (tmp_path / "props").mkdir()
    (tmp_path / "props" / "a.obj").write_text("v 0 0 0\n")
    digests = Digests(tmp_path)
    plain = digests("props/a.obj")
    assert digests("./props//a.obj") == plain == digests(str(tmp_path / "props" / "a.obj"))
    assert list(digests.stats()) == [str(tmp_path / "props" / "a.obj")]
    monkeypatch.chdir(tmp_path)
    relative = Digests(".")  # a relative folder: the same absolute keys
    assert relative("props/a.obj") == plain
    assert list(relative.stats()) == [str(tmp_path / "props" / "a.obj")]
