"""Fits run side by side (:func:`fit_hulls`, what ``hull --target`` runs: every round's hulls
and measures in one batch) give what each fit gives alone (:func:`fit_hull`, a fresh cache,
nothing batched): the same parts to the bit, the same measures, costs, violations and
notes, for every profile, on random scenes of random, flat, needle, duplicate-point and
one-vertex-over clouds; a body without a fit keeps its own error, in its place."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from meshcol.cli import main
from meshcol.collision.fit_cache import FitCache
from meshcol.collision.limits import budget_vertices
from meshcol.collision.target_fit import fit_hull, fit_hulls
from meshcol.errors import InvalidMeshError
from meshcol.io.targets import load_target, target_names

PROFILES = target_names()
KINDS = ["random", "flat", "needle", "duplicates", "over", "small"]


def _cloud(kind: str, seed: int, budget: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(8, 200))
    if kind == "random":
        points = rng.normal(size=(n, 3)) * rng.uniform(0.2, 1.0, size=3)
    elif kind == "flat":  # coplanar: a 2-D hull
        points = np.column_stack([rng.uniform(-1, 1, (n, 2)), np.zeros(n)])
    elif kind == "needle":  # long and thin: oblong, thin, a ratio the budget may not meet
        t = rng.uniform(-1, 1, n)
        points = np.column_stack([t, 1e-3 * rng.normal(size=(n, 2))])
    elif kind == "duplicates":
        base = rng.normal(size=(n, 3))
        points = np.repeat(base / np.linalg.norm(base, axis=1, keepdims=True), 3, axis=0)
    elif kind == "over":  # points on a sphere: every one a hull vertex, one over the budget
        base = rng.normal(size=(budget + 1, 3))
        points = base / np.linalg.norm(base, axis=1, keepdims=True)
    else:  # a few millimetres: thickness and volume limits grow it
        points = rng.normal(size=(n, 3)) * 1e-3
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return points @ rotation.T + rng.uniform(-1, 1, 3)


def _same(batched, alone) -> None:
    """The two fits are the same, to the bit."""
    assert len(batched.parts) == len(alone.parts)
    for (v1, f1), (v2, f2) in zip(batched.parts, alone.parts, strict=True):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)
    # repr-exact floats (NaN and infinities included) in the report's own form
    assert json.dumps(batched.to_dict()) == json.dumps(alone.to_dict())


@pytest.mark.parametrize("name", PROFILES)
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kinds=st.lists(st.sampled_from(KINDS), min_size=1, max_size=6),
    seed=st.integers(0, 2**31),
)
def test_batched_fits_are_the_fits_one_by_one(name: str, kinds: list[str], seed: int) -> None:
    target = load_target(name)
    scale = target.length_scale()
    budget = budget_vertices(target.limits) or 64
    clouds = [_cloud(kind, seed + n, budget) for n, kind in enumerate(kinds)]
    batched = fit_hulls(clouds, target, scale)
    for points, fit in zip(clouds, batched, strict=True):
        _same(fit, fit_hull(points, target, scale, FitCache()))


def test_a_body_without_a_fit_keeps_its_error_in_its_place() -> None:
    target = load_target("godot")  # no thickness or volume to grow a segment by
    rng = np.random.default_rng(3)
    good = rng.normal(size=(80, 3))
    line = np.outer(np.linspace(0, 1, 7), [1.0, 2.0, 3.0])
    point = np.ones((5, 3))
    fits = fit_hulls([good, line, point, good * 2], target, 1.0)
    for bad, fit in ((line, fits[1]), (point, fits[2])):
        assert isinstance(fit, InvalidMeshError)
        with pytest.raises(InvalidMeshError) as alone:
            fit_hull(bad, target, 1.0)
        assert fit.message == alone.value.message
        assert fit.message == "all vertices are collinear or coincide: there is no meaningful hull"
    _same(fits[0], fit_hull(good, target, 1.0))
    _same(fits[3], fit_hull(good * 2, target, 1.0))


def test_one_vertex_over_is_cut_flat_is_kept_and_a_needle_is_thickened() -> None:
    target = load_target("isaac")
    rng = np.random.default_rng(11)
    over = rng.normal(size=(65, 3))
    over /= np.linalg.norm(over, axis=1, keepdims=True)
    flat = np.column_stack([rng.uniform(-1, 1, (40, 2)), np.zeros(40)])
    needle = np.column_stack([rng.uniform(-1, 1, 60), 1e-4 * rng.normal(size=(60, 2))])
    fits = fit_hulls([over, flat, needle], target, 1.0)
    assert len(fits[0].parts[0][0]) <= 64 and fits[0].met
    assert fits[1].added_volume > 0  # given a thickness, then fitted
    # isaac's max_oblong_ratio 100: the needle (1e-4 thick) is thickened to it, and says so
    assert fits[2].met and not fits[2].violations
    assert any(n.startswith("thickened by") and "max_oblong_ratio" in n for n in fits[2].notes)
    for points, fit in zip([over, flat, needle], fits, strict=True):
        _same(fit, fit_hull(points, target, 1.0, FitCache()))


def test_a_budget_that_cannot_be_met_is_reported_for_each_body_as_alone() -> None:
    # four vertices cannot have an oblong ratio under 3 (a regular tetrahedron's)
    limits = {"max_hull_vertices": 4, "max_oblong_ratio": 2.0}
    rng = np.random.default_rng(11)
    clouds = [rng.normal(size=(50, 3)), rng.normal(size=(90, 3)) * [3.0, 1.0, 0.2]]
    clouds.append(np.column_stack([rng.uniform(-1, 1, (30, 2)), np.zeros(30)]))
    for points, fit in zip(clouds, fit_hulls(clouds, limits), strict=True):
        assert [v.limit for v in fit.violations] == ["max_oblong_ratio"]
        assert fit.notes[-1].startswith("max_oblong_ratio 2 not reached")
        assert len(fit.parts[0][0]) == 4
        _same(fit, fit_hull(points, limits, 1.0, FitCache()))


def test_hull_target_names_the_first_body_without_a_fit(tmp_path) -> None:
    rng = np.random.default_rng(5)
    bodies = []
    for name, points in (
        ("ok", rng.normal(size=(30, 3))),
        ("line", np.outer(np.linspace(0, 1, 6), [1.0, 0.5, 0.25])),
        ("point", np.ones((4, 3))),
    ):
        mesh = tmp_path / f"{name}.obj"
        lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in points]
        lines += [f"f {i + 1} {i + 2} {i + 3}" for i in range(len(points) - 2)]
        mesh.write_text("\n".join(lines) + "\n")
        bodies.append({"name": name, "mesh": str(mesh)})
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"bodies": bodies}))
    result = CliRunner().invoke(main, ["hull", str(scene), "--target", "godot"])
    assert result.exit_code == 2
    assert "body 'line': all vertices are collinear or coincide" in result.stderr
    assert "\n" not in result.stderr.strip()
