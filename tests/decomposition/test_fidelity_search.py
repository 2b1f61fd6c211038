"""The fidelity search (``meshcol decompose --max-hausdorff/--max-parts``): its logic on a
model engine, then CoACD on small generated meshes and the corpus."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import main
from meshcol.decomposition import cache as decompose_cache
from meshcol.decomposition.result import Decomposition, Fidelity
from meshcol.decomposition.search import (
    SearchTarget,
    meets_target,
    run_search,
    search_target,
)

COACD = {"threshold": 0.05, "resolution": 2000}
VHACD = {"max_convex_hulls": 64, "resolution": 400000}


# ------------------------------------------------------------------ the search, model engine


def model(parts_of, hausdorff_of, calls: list | None = None):
    """An engine whose parts and Hausdorff distance are functions of (threshold or hulls,
    resolution): ``evaluate`` for :func:`run_search`."""

    def evaluate(threshold, hulls, resolution):
        x = threshold if threshold is not None else hulls
        if calls is not None:
            calls.append((threshold, hulls, resolution))
        n = int(parts_of(x, resolution))
        h = float(hausdorff_of(x, resolution))
        metrics = Fidelity(n, (8,) * n, 1.0, 1.0, 1.0, h, h / 2, 0.0, 0.01, 2000, True)
        cube = (np.eye(3), np.zeros((1, 3), dtype=np.int64))
        key = f"{threshold}-{hulls}-{resolution}"
        return Decomposition((cube,) * n, "coacd", "0", {}, key, metrics)

    return evaluate


def coacd_like(t, r):
    """Fewer parts as the threshold grows; Hausdorff ~ threshold, better at high resolution."""
    return max(1, round(0.6 / t))


def hausdorff_like(t, r):
    return 0.5 * t * (2000 / r) ** 0.5


def test_hausdorff_target_finds_the_coarsest_threshold_within_it() -> None:
    calls: list = []
    target = SearchTarget(max_hausdorff=0.1, max_steps=12, tolerance=0.05)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like, calls))
    assert result.met
    chosen = result.steps[result.chosen]
    # Within D = 0.1 needs threshold <= 0.2: the bracket 0.05 -> 0.1 -> 0.2 -> 0.4 (over), then
    # bisection converges on 0.2 from below.
    assert chosen.hausdorff() <= 0.1
    assert 0.19 <= chosen.threshold <= 0.2
    assert chosen.parts == 3  # 0.6 / 0.2
    assert [c[0] for c in calls[:4]] == [0.05, 0.1, 0.2, 0.4]
    # Fewest parts among the steps that meet D, and every step is recorded.
    meeting = [s for s in result.steps if s.meets]
    assert chosen.parts == min(s.parts for s in meeting)
    assert len(result.steps) == len(calls) <= 12
    assert result.stopped in ("tolerance", "steps")
    assert "step" in result.reason and "Hausdorff" in result.reason


def test_search_is_deterministic_and_reports_every_step() -> None:
    target = SearchTarget(max_hausdorff=0.02)
    a = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    b = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    clean = [{k: v for k, v in s.items() if k != "seconds"} for s in a.to_dict()["steps"]]
    assert clean == [{k: v for k, v in s.items() if k != "seconds"} for s in b.to_dict()["steps"]]
    # Start 0.05 misses 0.02 (0.025): finer, 0.025 meets, then bisection between them.
    assert [s["threshold"] for s in clean[:2]] == [0.05, 0.025]
    assert sum(s["chosen"] for s in clean) == 1
    assert clean[a.chosen]["meets"] and clean[a.chosen]["chosen"]
    assert len(a.steps) <= target.max_steps


def test_a_target_out_of_reach_raises_the_resolution_then_fails_with_the_best_step() -> None:
    calls: list = []
    target = SearchTarget(max_hausdorff=1e-4, max_steps=10)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like, calls))
    assert not result.met
    # Down to the finest threshold, then twice the resolution at it, then four times.
    assert [c[0] for c in calls] == [0.05, 0.025, 0.0125, 0.01, 0.01, 0.01]
    assert [c[2] for c in calls[-3:]] == [2000, 4000, 8000]
    best = result.steps[result.chosen]
    assert (best.threshold, best.resolution) == (0.01, 8000)
    assert result.stopped == "range"
    assert result.reason.startswith("no step met the target: best step 5 (threshold 0.01, ")
    assert "> max_hausdorff 0.0001" in result.reason


def test_resolution_raise_that_meets_the_target_is_searched_at_that_resolution() -> None:
    # Within 0.004 takes threshold <= 0.008 at resolution 2000 (out of range), 0.0113 at 4000.
    target = SearchTarget(max_hausdorff=0.004, max_steps=12)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    assert result.met
    chosen = result.steps[result.chosen]
    assert chosen.resolution == 4000 and chosen.hausdorff() <= 0.004
    assert all(s.resolution == 2000 for s in result.steps[:4])


def test_max_parts_alone_finds_the_best_fidelity_within_the_budget() -> None:
    target = SearchTarget(max_parts=4, max_steps=12)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    assert result.met
    chosen = result.steps[result.chosen]
    assert chosen.parts <= 4
    # The finest threshold with <= 4 parts is 0.6 / 4.5 = 0.133...: the smallest Hausdorff.
    assert chosen.threshold == pytest.approx(0.1333, abs=0.01)
    assert chosen.hausdorff() == min(s.hausdorff() for s in result.steps if s.meets)


def test_both_limits_and_a_budget_that_no_step_meets() -> None:
    # Within 0.05 needs threshold <= 0.1, hence >= 6 parts: 3 parts cannot meet both.
    target = SearchTarget(max_hausdorff=0.05, max_parts=3, max_steps=8)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    assert not result.met and all(not s.meets for s in result.steps)
    best = result.steps[result.chosen]
    assert "parts > max_parts 3" in result.reason or "> max_hausdorff" in result.reason
    assert best.describe() in result.reason


def test_one_part_within_the_target_stops_the_search() -> None:
    target = SearchTarget(max_hausdorff=10.0)
    result = run_search(target, "coacd", COACD, model(lambda t, r: 1, lambda t, r: 0.0))
    assert result.met and len(result.steps) == 1 and result.stopped == "one part"


def test_step_budget_is_kept() -> None:
    target = SearchTarget(max_hausdorff=0.1, max_steps=2)
    result = run_search(target, "coacd", COACD, model(coacd_like, hausdorff_like))
    assert len(result.steps) == 2 and result.stopped == "steps"


def test_vhacd_searches_the_hull_count() -> None:
    calls: list = []
    # Hausdorff 1 / hulls: within 0.1 takes 10 hulls or more; fewest parts = 10.
    target = SearchTarget(max_hausdorff=0.1, max_steps=12)
    result = run_search(target, "vhacd", VHACD, model(lambda h, r: h, lambda h, r: 1.0 / h, calls))
    assert result.met and result.axis == "max_hulls"
    chosen = result.steps[result.chosen]
    assert chosen.threshold is None and chosen.max_hulls == 10 and chosen.parts == 10
    assert [c[1] for c in calls[:4]] == [64, 32, 16, 8]


def test_nan_metrics_never_meet() -> None:
    target = SearchTarget(max_hausdorff=1.0, max_steps=3)
    result = run_search(target, "coacd", COACD, model(coacd_like, lambda t, r: math.nan))
    assert not result.met
    assert not meets_target({"parts": 1, "hausdorff_mesh_to_parts": math.nan}, 1.0, None)


def test_search_target_modes_and_bad_values() -> None:
    assert search_target(None, None) is None
    assert search_target(0.1, None, "off") is None
    assert search_target(0.1, 3) == SearchTarget(0.1, 3)
    with pytest.raises(ValueError, match="search must be one of auto, off"):
        search_target(0.1, None, "maybe")
    with pytest.raises(ValueError, match="search steps must be at least 1"):
        search_target(0.1, None, "auto", 0)
    with pytest.raises(ValueError, match="search tolerance must be finite and > 0"):
        search_target(0.1, None, "auto", 3, 0.0)
    with pytest.raises(ValueError, match="max_parts must be at least 1"):
        search_target(None, 0)


# ------------------------------------------------------------------ CoACD on generated meshes

FAST = FAST_DECOMPOSE  # --threshold 0.2 --resolution 500, few MCTS iterations


def _l_shape() -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=[(0, 0, 0), (2, 1, 1)]).union(
        trimesh.creation.box(bounds=[(0, 0, 0.5), (1, 1, 2)]), engine="manifold"
    )


def run(args: list[str]) -> tuple[int, str, str]:
    """``meshcol decompose ARGS`` with its report on stdout (``--report -`` unless given)."""
    report = [] if "--report" in args else ["--report", "-"]
    result = CliRunner().invoke(main, ["decompose", *args, *report])
    if result.exception and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result.exit_code, result.stdout, result.stderr


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.fixture(scope="module")
def l_shape(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("inputs") / "l_shape.obj"
    _l_shape().export(path)
    return path


@pytest.mark.slow
def test_search_meets_the_target_with_fewer_parts_and_caches_every_step(l_shape, tmp_path) -> None:
    cache = tmp_path / "cache"
    base = [str(l_shape), "--cache-dir", str(cache), *FAST]
    # The run's threshold (0.2) gives 2 parts, nothing sticking out.
    code, stdout, _ = run([*base, "-o", str(tmp_path / "plain")])
    plain = json.loads(stdout)["files"][0]["bodies"][0]
    assert code == 0 and plain["metrics"]["parts"] == 2 and plain["search"] is None
    # Within 0.6 one part does: the hull of the L (0.498 out of it, measured).
    code, stdout, stderr = run([*base, "-o", str(tmp_path / "a"), "--max-hausdorff", "0.6"])
    assert code == 0, stderr
    body = json.loads(stdout)["files"][0]["bodies"][0]
    search = body["search"]
    assert search["met"] and search["stopped"] == "one part"
    assert [s["threshold"] for s in search["steps"]] == [0.2, 0.4, 0.8]
    assert [s["parts"] for s in search["steps"]] == [2, 2, 1]
    chosen = search["steps"][search["chosen"]]
    assert chosen["chosen"] and chosen["threshold"] == 0.8
    assert body["metrics"]["parts"] == 1 < plain["metrics"]["parts"]
    assert body["metrics"]["hausdorff_parts_to_mesh"] == pytest.approx(0.5, abs=0.01)
    assert max(chosen["hausdorff_mesh_to_parts"], chosen["hausdorff_parts_to_mesh"]) <= 0.6
    assert body["cache_key"] == chosen["cache_key"]
    # The first step is the plain run's decomposition; every step is in the cache.
    assert search["steps"][0]["cache_key"] == plain["cache_key"]
    assert search["steps"][0]["from_cache"] and search["engine_calls"] == 2
    for s in search["steps"]:
        entry = decompose_cache.load(s["cache_key"], cache)
        assert entry is not None and len(entry.parts) == s["parts"]
    # Second run: every step from the cache, the same parts byte for byte.
    code, stdout, _ = run([*base, "-o", str(tmp_path / "b"), "--max-hausdorff", "0.6"])
    again = json.loads(stdout)["files"][0]["bodies"][0]["search"]
    assert code == 0 and again["engine_calls"] == 0
    assert all(s["from_cache"] for s in again["steps"])
    assert files(tmp_path / "a") == files(tmp_path / "b")


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_a_target_no_step_meets_fails_naming_the_best_step(l_shape, tmp_path) -> None:
    args = [str(l_shape), "--no-cache", "-o", str(tmp_path / "o"), *FAST]
    code, stdout, stderr = run([*args, "--max-hausdorff", "1e-9", "--search-steps", "2"])
    assert code == 1
    report = json.loads(stdout)
    body = report["files"][0]["bodies"][0]
    assert body["search"]["met"] is False and body["hausdorff_ok"] is False
    assert body["search"]["stopped"] == "steps" and len(body["search"]["steps"]) == 2
    assert report["summary"]["hausdorff_exceeded"] == 1
    assert "meshcol: target missed: " in stderr
    assert "no step met the target: best step" in stderr and "> max_hausdorff 1e-09" in stderr


def test_search_off_only_checks(l_shape, tmp_path) -> None:
    args = [str(l_shape), "--no-cache", "-o", str(tmp_path / "o"), *FAST]
    code, stdout, _ = run([*args, "--max-parts", "1", "--search", "off"])
    body = json.loads(stdout)["files"][0]["bodies"][0]
    assert code == 1 and body["search"] is None and body["parts_ok"] is False
    assert json.loads(stdout)["summary"]["parts_exceeded"] == 1


def test_robot_input_refuses_the_search(tmp_path) -> None:
    urdf = tmp_path / "r.urdf"
    urdf.write_text('<robot name="r"><link name="a"/></robot>\n')
    code, _, stderr = run([str(urdf), "-o", str(tmp_path / "o"), "--max-hausdorff", "0.1"])
    assert code == 2
    assert "fidelity search" in stderr and "--search off" in stderr


@pytest.mark.slow
def test_max_parts_alone_and_jobs_two_are_deterministic(tmp_path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    _l_shape().export(folder / "l.obj")
    # A second L, its long leg 3 and its short one standing at the end: six search steps of
    # 2 or 1 parts, as the first's. (A T, the block on the bar's middle, took CoACD three
    # times as long for five.)
    trimesh.creation.box(bounds=[(0, 0, 0), (3, 1, 1)]).union(
        trimesh.creation.box(bounds=[(0, 0, 0), (1, 1, 2)]), engine="manifold"
    ).export(folder / "step.obj")
    inputs = [str(folder / "l.obj"), str(folder / "step.obj")]
    reports = []
    for jobs in ("1", "2"):
        out = tmp_path / f"o{jobs}"
        code, stdout, stderr = run(
            [*inputs, "--no-cache", "-o", str(out), *FAST, "--max-parts", "1", "--jobs", jobs]
        )
        assert code == 0, stderr
        report = json.loads(stdout)
        steps = [
            [{k: v for k, v in s.items() if k != "seconds"} for s in b["search"]["steps"]]
            for f in report["files"]
            for b in f["bodies"]
        ]
        reports.append((steps, files(out)))
        for f in report["files"]:
            for b in f["bodies"]:
                assert b["metrics"]["parts"] == 1 and b["search"]["met"]
                meeting = [s for s in b["search"]["steps"] if s["meets"]]
                best = b["search"]["steps"][b["search"]["chosen"]]
                # The smallest Hausdorff among the steps with one part.
                h = [
                    max(s["hausdorff_mesh_to_parts"], s["hausdorff_parts_to_mesh"]) for s in meeting
                ]
                assert max(best["hausdorff_mesh_to_parts"], best["hausdorff_parts_to_mesh"]) == min(
                    h
                )
    assert reports[0] == reports[1]


@pytest.mark.slow
def test_a_longer_or_resumed_search_reuses_the_cached_steps(l_shape, tmp_path) -> None:
    cache = tmp_path / "cache"
    manifest = tmp_path / "run.json"
    base = [str(l_shape), "--cache-dir", str(cache), *FAST, "--max-hausdorff", "0.6"]
    code, stdout, _ = run([*base, "-o", str(tmp_path / "a"), "--search-steps", "2"])
    first = json.loads(stdout)["files"][0]["bodies"][0]["search"]
    assert code == 0 and first["stopped"] == "steps" and first["engine_calls"] == 2
    # The same search with a larger budget: its first two steps come from the cache.
    args = [*base, "-o", str(tmp_path / "b"), "--run-manifest", str(manifest)]
    code, stdout, _ = run(args)
    longer = json.loads(stdout)["files"][0]["bodies"][0]["search"]
    assert code == 0 and [s["from_cache"] for s in longer["steps"]] == [True, True, False]
    code, stdout, _ = run([*args, "--resume"])
    resumed = json.loads(stdout)["files"][0]["bodies"][0]["search"]
    assert code == 0 and resumed["engine_calls"] == 0
    assert [s["cache_key"] for s in resumed["steps"]] == [s["cache_key"] for s in longer["steps"]]
