"""The JSON report of ``meshcol ci`` joined from each job's report text (issue 31: a cached
report of 10,000 jobs cost 3.5-4 s of CPU decoding every entry and encoding it again): the
same bytes as encoding the whole report, cold, from the run index, from the entries one by
one, and for an entry of an older build that kept no text."""

from __future__ import annotations

import pytest
from ci_repo import make_repo

from meshcol.analysis.ci import run_ci
from meshcol.io.config import load_config
from meshcol.io.report import dumps_json

pytest.importorskip("yourdfpy", reason="the test repository's robot needs yourdfpy")


def _both(report) -> str:
    joined = report.to_json()
    assert joined == dumps_json(report.to_dict())  # the long way: every value encoded
    return joined


def test_joined_report_is_the_encoded_report_cold_cached_and_from_old_entries(
    tmp_path, monkeypatch
) -> None:
    root = make_repo(tmp_path / "repo")
    (root / "props" / "soft" / "broken.obj").write_text("v 0 0\nf 1 2 9\n")  # an error job
    monkeypatch.chdir(root)
    config = load_config(root / "meshcol.toml")
    cache = tmp_path / "cache"
    cold = run_ci(config, cache_dir=cache)
    assert {run.exit_code for run in cold.runs} == {0, 1, 2}
    assert not any(run.cached for run in cold.runs)
    reference = _both(cold)

    warm = run_ci(config, cache_dir=cache)  # every job from the run index, texts joined
    assert sum(run.cached for run in warm.runs) == len(warm.runs) - 2  # the broken file's
    assert _both(warm) == reference

    texts = sorted(cache.glob("results/*/*.report.json"))
    assert len(texts) == len(warm.runs) - 2
    texts[0].unlink()  # an entry an older build wrote: no text, its report encoded
    for index in (cache / "results" / "index").iterdir():
        index.unlink()  # and every entry read one by one
    again = run_ci(config, cache_dir=cache)
    assert _both(again) == reference
