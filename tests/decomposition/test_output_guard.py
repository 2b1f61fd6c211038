"""``OutputGuard``: parts never replace a protected file (an input, a report), whichever of
the file and the body's pattern comes first; and a library of n files places each protected
file in or out of the output folder once (n resolved paths, not n x n: 300 files had spent
90,000 path resolutions, 8 of a cached run's 13 s)."""

from __future__ import annotations

import re

import pytest

from meshcol.decomposition.writing import OutputGuard, PartsLayout
from meshcol.errors import MeshcolError


def _counting_guard(tmp_path, protected):
    guard = OutputGuard(PartsLayout(str(tmp_path / "out")), protected)
    calls = []
    real = guard._same_file

    def same_file(a, b):
        calls.append(a)
        return real(a, b)

    guard._same_file = same_file
    return guard, calls


def test_each_protected_file_is_placed_once(tmp_path) -> None:
    (tmp_path / "out").mkdir()
    guard, calls = _counting_guard(tmp_path, [])
    for k in range(200):
        guard.protect(str(tmp_path / "in" / f"a{k}.obj"))
        guard.plan(f"a{k}", re.compile(rf"a{k}_\d+\.obj"))
        guard.protect(str(tmp_path / "in" / f"a{k}.obj"))  # again: already placed
    assert len(calls) == 200


@pytest.mark.parametrize("protect_first", [True, False])
def test_a_protected_file_in_the_output_folder_is_refused_either_way(tmp_path, protect_first):
    (tmp_path / "out").mkdir()
    guard, _ = _counting_guard(tmp_path, [str(tmp_path / "report.json")])
    inside = str(tmp_path / "out" / "cube_00.obj")
    steps = [
        lambda: guard.protect(inside),
        lambda: guard.plan("cube", re.compile(r"cube_\d+\.obj")),
    ]
    if not protect_first:
        steps.reverse()
    steps[0]()
    with pytest.raises(MeshcolError, match="the parts of body 'cube' would replace this file"):
        steps[1]()
    guard.plan("other", re.compile(r"other_\d+\.obj"))  # a pattern no protected file matches
