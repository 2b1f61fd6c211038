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
