"""The cap on candidate pairs (issue 29: "reads are capped" extended to the pairs a run
holds): a pile over ``--max-pairs`` is one line naming the scene and the count, exit 2, and
nothing written; under the cap the run is the same as without one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.analysis.check import check
from meshcol.analysis.check_policy import MAX_PAIRS, CheckOptions
from meshcol.cli import main
from meshcol.errors import TooManyPairsError

#: Spheres in one pile: every pair of them overlaps.
BODIES = 30
PAIRS = BODIES * (BODIES - 1) // 2


@pytest.fixture
def pile(tmp_path: Path) -> Path:
    rng = np.random.default_rng(29)
    centres = rng.uniform(-0.05, 0.05, size=(BODIES, 3)).round(6).tolist()
    bodies = [
        {"name": f"s{i:02d}", "primitive": {"type": "sphere", "radius": 0.2}, "position": c}
        for i, c in enumerate(centres)
    ]
    path = tmp_path / "pile.json"
    path.write_text(json.dumps({"bodies": bodies}))
    return path


def test_a_pile_over_the_cap_is_one_line_exit_2_and_nothing_written(pile: Path) -> None:
    report, page = pile.parent / "report.json", pile.parent / "page.html"
    args = ["check", str(pile), "--max-pairs", str(PAIRS - 1), "--report", str(report)]
    result = CliRunner().invoke(main, [*args, "--html", str(page)])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    # The sweep stops at the cap: it never holds a pile's pairs to count them all.
    assert str(pile) in lines[0] and f"more than {PAIRS - 1:,} candidate pairs" in lines[0]
    assert "--max-pairs" in lines[0] and f"{PAIRS - 1:,}" in lines[0]
    assert "Traceback" not in result.output
    assert not report.exists() and not page.exists()
    assert sorted(p.name for p in pile.parent.iterdir()) == ["pile.json"]


def test_a_pile_at_the_cap_is_checked_as_without_one(pile: Path) -> None:
    report = pile.parent / "report.json"
    args = ["check", str(pile), "--fail-on", "none", "--report", str(report)]
    result = CliRunner().invoke(main, [*args, "--max-pairs", str(PAIRS)])
    assert result.exit_code == 0, result.output
    capped = json.loads(report.read_text())
    assert capped["summary"]["candidate_pairs"] == PAIRS
    assert capped["summary"]["pairs_by_status"]["penetrating"] == PAIRS
    uncapped = check([str(pile)], fail_on="none", max_pairs=None)
    assert [p["depth"] for p in capped["pairs"]] == [p["depth"] for p in uncapped.pairs]


def test_the_api_refuses_a_pile_over_the_cap_naming_the_scene(pile: Path) -> None:
    with pytest.raises(
        TooManyPairsError, match="more than 10 candidate pairs among 30 bodies"
    ) as info:
        check([str(pile)], max_pairs=10)
    assert info.value.path == str(pile)
    assert CheckOptions().max_pairs == MAX_PAIRS
    with pytest.raises(ValueError, match="max_pairs must be an integer >= 0"):
        CheckOptions(max_pairs=-1)


def test_mesh_files_over_the_cap_are_named_by_their_first_file(tmp_path: Path) -> None:
    cube = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
    cube += "f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\n"
    cube += "f 3 4 8\nf 3 8 7\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n"
    paths = []
    for name in ("a", "b", "c"):
        (tmp_path / f"{name}.obj").write_text(cube)
        paths.append(str(tmp_path / f"{name}.obj"))
    with pytest.raises(
        TooManyPairsError, match="more than 2 candidate pairs among 3 bodies"
    ) as info:
        check(paths, max_pairs=2)
    assert info.value.path == f"{paths[0]} and 2 more"


def test_excluded_pairs_do_not_count_and_within_them_the_count_is_exact(pile: Path) -> None:
    from meshcol.analysis.colliders import build_colliders
    from meshcol.analysis.pairs import broad_phase, place
    from meshcol.io.scene import load_scene

    placed = place(build_colliders(load_scene(str(pile)).bodies, "hull"))
    excluded = [("s00", f"s{i:02d}", "test") for i in range(1, 6)]  # 5 of the 435 pairs
    table = broad_phase(placed, 0.0, excluded, max_pairs=PAIRS - 5)
    assert len(table.body_a) == PAIRS - 5 and table.excluded_pairs == 5
    # The sweep holds up to the cap plus one pair per exclusion (the most they can remove):
    # past that, "more than"; within it but past the cap after the exclusions, the count.
    with pytest.raises(TooManyPairsError, match=r"^more than 429 candidate pairs among 30"):
        broad_phase(placed, 0.0, excluded, max_pairs=PAIRS - 6)
    partly = excluded[:3] + [("s00", "nobody", "test"), ("nobody", "s01", "test")]
    with pytest.raises(TooManyPairsError, match=rf"^{PAIRS - 3:,} candidate pairs among 30"):
        broad_phase(placed, 0.0, partly, max_pairs=PAIRS - 5)
