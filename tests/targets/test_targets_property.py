"""Every packaged profile, on random, flat, needle and duplicate-point clouds: the hull
meets every limit by an independent count (tests/target_oracle.py), or says which it could
not meet by rule id; it always encloses the input; the marginal costs sum to the total.
Also: corpus meshes per profile, a user profile file equal to a packaged one, and limits
that cannot be met (exit 2 for an impossible profile, a finding with the rule id for one
the input cannot meet)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from target_oracle import encloses, missed

from meshcol.cli import main
from meshcol.collision.limits import RULES
from meshcol.collision.target_fit import fit_hull
from meshcol.io.targets import TARGETS_DIR, load_target, target_names

PROFILES = target_names()


def run(*args: str):
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def _cloud(kind: str, seed: int, n: int, scale: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if kind == "random":
        points = rng.normal(size=(n, 3)) * rng.uniform(0.2, 1.0, size=3)
    elif kind == "flat":  # a plate: coplanar points
        points = np.column_stack([rng.uniform(-1, 1, (n, 2)), np.zeros(n)])
    elif kind == "needle":  # a long thin cloud: oblong, thin
        t = rng.uniform(-1, 1, n)
        points = np.column_stack([t, 1e-3 * rng.normal(size=(n, 2))])
    else:  # duplicates: every point three times, a sphere's worth of them
        base = rng.normal(size=(n, 3))
        base /= np.linalg.norm(base, axis=1, keepdims=True)
        points = np.repeat(base, 3, axis=0)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return (points @ rotation.T) * scale + rng.uniform(-1, 1, 3)


def check_fit(points: np.ndarray, name: str) -> None:
    target = load_target(name)
    scale = target.length_scale()
    fit = fit_hull(points, target, scale)
    ((vertices, _),) = fit.parts
    assert encloses(vertices, points, tol=1e-8), f"{name}: the hull lost an input point"
    counted = missed([vertices], target.limits, scale)
    reported = {v.limit for v in fit.violations}
    if fit.met:
        assert counted == set(), f"{name}: met, but counted {counted}"
    else:
        # what is reported is real, and carries its rule id and a one-line message
        assert reported and counted <= reported, (name, counted, reported)
        for v in fit.violations:
            assert v.rule == RULES[v.limit][0] and "\n" not in v.message
    marginal = sum(c.marginal_added_volume for c in fit.costs)
    assert marginal == pytest.approx(fit.added_volume, rel=1e-9, abs=1e-12)
    assert [c.order for c in fit.costs] == list(range(len(fit.costs)))


@pytest.mark.parametrize("name", PROFILES)
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kind=st.sampled_from(["random", "flat", "needle", "duplicates"]),
    seed=st.integers(0, 2**31),
    n=st.integers(8, 300),
    scale=st.sampled_from([0.01, 0.3, 2.0]),
)
def test_every_profile_meets_its_limits_or_says_which(name, kind, seed, n, scale) -> None:
    check_fit(_cloud(kind, seed, n, scale), name)


@pytest.mark.slow
@pytest.mark.parametrize("name", PROFILES)
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kind=st.sampled_from(["random", "flat", "needle", "duplicates"]),
    seed=st.integers(0, 2**31),
    n=st.integers(4, 2000),
    scale=st.floats(1e-3, 10.0),
)
def test_every_profile_property_long(name, kind, seed, n, scale) -> None:
    check_fit(_cloud(kind, seed, n, scale), name)


CORPUS_MESHES = [
    "trimesh-models/featuretype.STL",
    "trimesh-models/soup.stl",
    "trimesh-models/fandisk.obj",
    "trimesh-models/teapot.stl",
]


def _corpus_mesh(corpus: Path, rel: str) -> np.ndarray:
    path = corpus / rel
    if not path.is_file():
        pytest.skip(f"corpus mesh {rel} not present")
    return np.asarray(trimesh.load(path, force="mesh").vertices, dtype=np.float64)


@pytest.mark.slow  # each case is quick (< 0.3 s), all 40 together are not
@pytest.mark.parametrize("rel", CORPUS_MESHES)
@pytest.mark.parametrize("name", PROFILES)
def test_corpus_meshes_meet_every_profile(corpus: Path, rel: str, name: str) -> None:
    points = _corpus_mesh(corpus, rel)
    target = load_target(name)
    fit = fit_hull(points, target, target.length_scale("m"))
    assert fit.met, [v.message for v in fit.violations]
    ((vertices, _),) = fit.parts
    assert missed([vertices], target.limits, target.length_scale("m")) == set()
    assert encloses(vertices, points, tol=1e-8)


@pytest.mark.slow
def test_a_user_profile_file_works_as_the_packaged_one(tmp_path: Path) -> None:
    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(2, 0.5).export(ball)
    mine = tmp_path / "my_engine.toml"
    text = (TARGETS_DIR / "physx-gpu.toml").read_text()
    mine.write_text(text.replace('name = "physx-gpu"', 'name = "my_engine"'))
    reports = {}
    for label, target in (("packaged", "physx-gpu"), ("user", str(mine))):
        out, report = tmp_path / f"{label}.obj", tmp_path / f"{label}.json"
        code, _, stderr = run(
            "hull", str(ball), "--target", target, "-o", str(out), "--report", str(report)
        )
        assert code == 0, stderr
        reports[label] = json.loads(report.read_text())
        reports[label]["hull"] = np.asarray(trimesh.load(out, force="mesh").vertices)
    packaged, user = reports["packaged"], reports["user"]
    assert user["settings"]["target_limits"] == packaged["settings"]["target_limits"]
    assert np.array_equal(user["hull"], packaged["hull"])
    strip = ("name",)
    p, u = packaged["bodies"][0]["target"], user["bodies"][0]["target"]
    assert {k: v for k, v in p.items() if k not in strip} == {
        k: v for k, v in u.items() if k not in strip
    }
    assert u["name"] == "my_engine"


def test_an_impossible_profile_is_exit_2_in_one_line(tmp_path: Path) -> None:
    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(2, 0.5).export(ball)
    bad = tmp_path / "bad.toml"
    bad.write_text('title = "Bad"\n[limits]\nmax_hull_vertices = 3\n')
    code, _, stderr = run("hull", str(ball), "--target", str(bad))
    assert code == 2
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "max_hull_vertices" in lines[0] and "bad.toml" in lines[0]
    assert "Traceback" not in stderr


@pytest.mark.slow
def test_a_limit_the_input_cannot_meet_is_a_finding_with_its_rule_id(tmp_path: Path) -> None:
    # no polytope reaches the in-sphere ratio 1 (only a ball does): MC102 on any input
    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(2, 0.5).export(ball)
    profile = tmp_path / "round.toml"
    profile.write_text('title = "Round"\n[limits]\nmax_oblong_ratio = 1.0\n')
    code, _, stderr = run("hull", str(ball), "--target", str(profile))
    assert code == 1
    (line,) = [x for x in stderr.splitlines() if "MC102" in x]
    assert "not-gpu-compatible-oblong" in line and "max_oblong_ratio" in line


def test_marginal_costs_sum_and_standalone_costs_are_kept() -> None:
    # a thin plate with many points: thickness growth and a vertex budget both cost volume
    rng = np.random.default_rng(3)
    plate = np.column_stack([rng.uniform(-1, 1, (400, 2)), 0.001 * rng.uniform(-1, 1, 400)])
    fit = fit_hull(plate, {"min_thickness": 0.05, "max_hull_vertices": 12})
    assert fit.met
    by = {c.limit: c for c in fit.costs}
    assert [c.limit for c in fit.costs] == ["min_thickness", "max_hull_vertices"]
    assert sum(c.marginal_added_volume for c in fit.costs) == pytest.approx(fit.added_volume)
    assert by["max_hull_vertices"].cumulative_added_volume == pytest.approx(fit.added_volume)
    # standalone: each limit alone; they overlap, so they need not add up to the total
    assert by["min_thickness"].standalone_added_volume > 0
    assert by["max_hull_vertices"].standalone_added_volume > 0
    assert by["min_thickness"].marginal_added_volume == pytest.approx(
        by["min_thickness"].standalone_added_volume
    )
    assert by["max_hull_vertices"].cumulative_max_distance == pytest.approx(fit.max_distance)
