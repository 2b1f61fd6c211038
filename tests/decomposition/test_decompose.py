"""meshcol.decompose: canonical geometry, parts, cache, fidelity metrics, engines."""

from __future__ import annotations

import dataclasses
import os
import pickle
import re
import shutil
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

import meshcol
from meshcol.decomposition import cache as decompose_cache
from meshcol.decomposition.canonical import cache_key, canonical_geometry, canonical_part
from meshcol.decomposition.decompose import cached_decomposition, decompose
from meshcol.decomposition.engines import resolve_params
from meshcol.decomposition.fidelity import (
    farthest_outside_solid,
    fidelity,
    points_to_parts,
    points_to_triangles,
)
from meshcol.decomposition.options import DecomposeOptions, RunOptions
from meshcol.decomposition.result import Decomposition
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import is_closed_manifold
from meshcol.geometry.triangles import point_triangle_distances

# Coarse CoACD settings: seconds, not minutes (the suite has a time budget).
FAST = {
    "threshold": 0.2,
    "resolution": 500,
    "engine_options": {"mcts_iterations": 20, "mcts_nodes": 8, "mcts_max_depth": 2},
}


def _torus() -> trimesh.Trimesh:
    return trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)


def _box(lo=(0, 0, 0), hi=(1, 1, 1)) -> tuple[np.ndarray, np.ndarray]:
    b = trimesh.creation.box(bounds=[lo, hi])
    return np.asarray(b.vertices), np.asarray(b.faces)


def _signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    t = v[f]
    return float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0)


def _inside_union(points: np.ndarray, parts, tol: float) -> np.ndarray:
    """Brute force: a point is covered when it is within tol of some part's halfspaces."""
    covered = np.zeros(len(points), dtype=bool)
    for v, _ in parts:
        eq = ConvexHull(v).equations
        covered |= (points @ eq[:, :3].T + eq[:, 3]).max(axis=1) <= tol
    return covered


# ---------------------------------------------------------------------------- canonical input


def test_canonical_geometry_merges_duplicates_known_cube() -> None:
    v, f = _box()
    soup_v = v[f].reshape(-1, 3)  # 36 vertices, one per corner of each triangle
    soup_f = np.arange(36).reshape(12, 3)
    cv, cf = canonical_geometry(soup_v, soup_f)
    assert cv.shape == (8, 3) and cf.shape == (12, 3)
    assert np.array_equal(cv, np.unique(v, axis=0))
    assert is_closed_manifold(cf)
    assert _signed_volume(cv, cf) == pytest.approx(1.0, abs=1e-12)


def test_canonical_geometry_ignores_vertex_and_face_order() -> None:
    m = _torus()
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(v))
    inverse = np.argsort(perm)
    f2 = inverse[f][rng.permutation(len(f))]
    f2 = np.roll(f2, 1, axis=1)  # same winding, another starting corner
    a, b = canonical_geometry(v, f), canonical_geometry(v[perm], f2)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    params = resolve_params(DecomposeOptions("coacd"))
    assert cache_key(*a, "coacd", "1", params) == cache_key(*b, "coacd", "1", params)
    assert cache_key(*a, "coacd", "1", params) != cache_key(*a, "coacd", "2", params)
    assert cache_key(*a, "coacd", "1", params) != cache_key(
        *a, "coacd", "1", resolve_params(DecomposeOptions("coacd", seed=1))
    )


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        (np.zeros((0, 3)), np.zeros((0, 3), dtype=int), "mesh has no faces"),
        (
            np.eye(3),
            np.array([[0, 1, 2]]),
            "mesh is flat (all vertices lie in one plane): it encloses no volume",
        ),
        (
            np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]], float),
            np.array([[0, 1, 2], [1, 4, 2]]),
            "mesh is flat (all vertices lie in one plane): it encloses no volume",
        ),
        (
            np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0], [0, 0, 1]]),
            np.array([[0, 1, 2], [0, 1, 3]]),
            "mesh has non-finite vertex coordinates",
        ),
        (np.eye(3), np.array([[0, 1, 5]]), "face indices out of range"),
        (np.eye(3), np.array([[0, 0, 1]]), "mesh has no faces with three distinct vertices"),
    ],
)
def test_canonical_geometry_rejects_unusable_meshes(vertices, faces, message) -> None:
    with pytest.raises(InvalidMeshError) as info:
        canonical_geometry(vertices, faces)
    assert str(info.value) == message


def test_is_closed_manifold() -> None:
    v, f = _box()
    assert is_closed_manifold(f)
    assert not is_closed_manifold(f[1:])  # a hole
    flipped = f.copy()
    flipped[0] = flipped[0][::-1]
    assert not is_closed_manifold(flipped)  # inconsistent winding
    assert is_closed_manifold(f[:, ::-1])  # inside out, but consistent
    assert not is_closed_manifold(np.vstack([f, f]))  # every edge four times
    assert not is_closed_manifold(np.vstack([f, f[:, ::-1]]))  # two directions, twice each
    assert not is_closed_manifold(np.vstack([f, f[:1]]))  # a repeated triangle
    assert not is_closed_manifold(np.vstack([f, f[:1, ::-1]]))  # a triangle and its back


# ---------------------------------------------------------------------------- parameters


def test_resolve_params_auto_preprocess_and_budgets() -> None:
    assert resolve_params(DecomposeOptions("coacd"), closed=True)["preprocess_mode"] == "off"
    assert resolve_params(DecomposeOptions("coacd"), closed=False)["preprocess_mode"] == "on"
    on = DecomposeOptions("coacd", preprocess="on")
    assert resolve_params(on, closed=True)["preprocess_mode"] == "on"
    p = resolve_params(
        DecomposeOptions(
            "coacd", max_hulls=5, max_vertices=12, engine_options={"mcts_nodes": "7", "pca": "true"}
        )
    )
    assert (p["max_convex_hull"], p["decimate"], p["max_ch_vertex"], p["mcts_nodes"], p["pca"]) == (
        5,
        True,
        12,
        7,
        True,
    )
    q = resolve_params(DecomposeOptions("vhacd", max_hulls=5, max_vertices=12, resolution=10000))
    assert (q["max_convex_hulls"], q["max_num_vertices_per_ch"], q["resolution"]) == (5, 12, 10000)


@pytest.mark.parametrize(
    ("engine", "kwargs", "message"),
    [
        ("bullet", {}, "unknown engine 'bullet': choose one of coacd, vhacd"),
        (
            "coacd",
            {"engine_options": {"bogus": 1}},
            "unknown coacd option 'bogus': known options are ",
        ),
        (
            "coacd",
            {"engine_options": {"mcts_nodes": "many"}},
            "coacd option 'mcts_nodes' must be int, got 'many'",
        ),
        ("coacd", {"max_vertices": 3}, "max_vertices must be at least 4, got 3"),
        ("coacd", {"threshold": 0.0}, "threshold must be in (0, 1], got 0.0"),
        ("vhacd", {"threshold": 0.1}, "threshold applies to the coacd engine only"),
        ("coacd", {"preprocess": "maybe"}, "preprocess must be auto, on or off, got 'maybe'"),
    ],
)
def test_decompose_options_are_validated_when_made(engine, kwargs, message) -> None:
    with pytest.raises(ValueError) as info:
        DecomposeOptions(engine, **kwargs)
    assert str(info.value).startswith(message)
    # the public entries build them from their keywords, with the same message
    with pytest.raises(ValueError) as info:
        decompose(_torus(), engine=engine, use_cache=False, **kwargs)
    assert str(info.value).startswith(message)


# ------------------------------------------------------------------------------------ options

#: Cache keys of a 1 x 2 x 3 box that meshcol ee068ea computed (engine version "1.0.14"): a
#: cache made before the options were typed must still hit.
KNOWN_KEYS = [
    (
        "coacd",
        {
            "threshold": 0.2,
            "resolution": 500,
            "engine_options": {"mcts_iterations": "20", "pca": "true"},
        },
        "0393821af0d64e96938eebbd4ee3fa58c217e66d4b283a9f49d7f51902a309a8",
    ),
    (
        "coacd",
        {"max_hulls": 4, "max_vertices": 16, "preprocess": "on", "seed": 3},
        "afd792079538368d824c5178515376d4244342c948a859d10481a3a37e9d589a",
    ),
    (
        "vhacd",
        {"max_hulls": 8, "resolution": 10000, "engine_options": {"fill_mode": "raycast"}},
        "b1fb19967e21f24892df85264fdc1d94f5dac6c5525b86b5e429b528ae6f43f5",
    ),
]


@pytest.mark.parametrize(("engine", "fields", "key"), KNOWN_KEYS)
def test_cache_keys_are_those_of_earlier_runs(engine, fields, key) -> None:
    m = trimesh.creation.box(extents=(1, 2, 3))
    v, f = canonical_geometry(np.asarray(m.vertices), np.asarray(m.faces))
    params = resolve_params(DecomposeOptions(engine, **fields), closed=True)
    assert cache_key(v, f, engine, "1.0.14", params) == key


def test_run_manifest_fingerprint_is_that_of_earlier_runs() -> None:
    from meshcol.decomposition.manifest import fingerprint

    options = DecomposeOptions(
        threshold=0.2, resolution=500, engine_options={"mcts_iterations": "20"}
    )
    assert fingerprint(options.result_settings()) == (
        "6fdcba180d35e412cbe9842971add4b33278d901956875bcde1118b9a042380a"
    )
    searching = dataclasses.replace(options, max_hausdorff=0.05, search_steps=4)
    assert fingerprint(searching.result_settings()) == (
        "3db7bb6e62c4ec7271de8aa927d5e88afb078960ab360e61e3d86a42ee3ef765"
    )
    assert DecomposeOptions(max_hausdorff=0.05, search="off").search_target() is None


def test_options_are_frozen_and_travel_to_workers() -> None:
    options = DecomposeOptions(threshold=0.1, engine_options={"mcts_nodes": "7"})
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.threshold = 0.2  # type: ignore[misc]
    with pytest.raises(TypeError):
        options.engine_options["mcts_nodes"] = "8"  # type: ignore[index]
    again = pickle.loads(pickle.dumps(options))
    assert again == options and hash(again) == hash(options)
    assert dict(again.engine_options) == {"mcts_nodes": "7"}
    assert DecomposeOptions.given(options) is options
    assert DecomposeOptions.given(options, seed=2).seed == 2
    assert DecomposeOptions.given(None, seed=2) == DecomposeOptions(seed=2)


def test_options_aimed_at_a_target() -> None:
    from meshcol.io.targets import Target

    target = Target("t", "", "m", {"max_hulls": 4, "max_hull_vertices": 32})
    aimed = DecomposeOptions(max_hulls=6, max_vertices=64).aimed_at(target)
    # the hull count goes to the engine's own parameter (excess parts merged, never dropped)
    assert (aimed.max_hulls, aimed.max_vertices) == (None, 32)
    assert dict(aimed.engine_options) == {"max_convex_hull": 4}
    given = DecomposeOptions("vhacd", engine_options={"max_convex_hulls": "3"}).aimed_at(target)
    assert dict(given.engine_options) == {"max_convex_hulls": 3}


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"jobs": 0}, "jobs must be at least 1, got 0"),
        ({"use_cache": False, "cache_dir": "c"}, "cache_dir needs use_cache"),
        ({"ray_address": "auto"}, "ray_address needs executor 'ray'"),
    ],
)
def test_run_options_are_validated_when_made(fields, message) -> None:
    with pytest.raises(ValueError, match=message):
        RunOptions(**fields)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"max_vertices": 3, "use_cache": False}, "max_vertices must be at least 4, got 3"),
        ({"engine": "vhacd", "threshold": 0.1}, "threshold applies to the coacd engine only"),
        ({"layout": "ucx", "fmt": "glb"}, "layout 'ucx' writes OBJ only, not glb"),
        ({"resume": True}, "resume needs run_manifest"),
        ({"run_manifest": "m.json", "use_cache": False}, "run_manifest needs the cache"),
        ({"cache_dir": "c", "use_cache": False}, "cache_dir needs use_cache"),
        ({"max_parts": 0}, "max_parts must be at least 1, got 0"),
    ],
)
def test_decompose_files_refuses_bad_options_before_any_work(tmp_path, fields, message) -> None:
    from meshcol.decomposition.batch import decompose_files

    mesh = tmp_path / "torus.obj"
    _torus().export(mesh)
    with pytest.raises(ValueError, match=re.escape(message)):
        decompose_files([mesh], tmp_path / "out", **fields)
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- canonical parts


def test_canonical_part_is_the_outward_hull_in_lexicographic_order() -> None:
    rng = np.random.default_rng(0)
    v, _ = _box()
    points = np.concatenate([v, rng.random((50, 3)) * 0.8 + 0.1])[rng.permutation(58)]
    pv, pf, volume, reduced = canonical_part(points, None)
    assert np.array_equal(pv, np.unique(v, axis=0))
    assert len(pf) == 12 and not reduced
    assert volume == pytest.approx(1.0, abs=1e-12)
    assert _signed_volume(pv, pf) == pytest.approx(1.0, abs=1e-12)  # outward triangles
    again = canonical_part(points[::-1], None)
    assert np.array_equal(again[0], pv) and np.array_equal(again[1], pf)


def test_canonical_part_enforces_vertex_budget_enclosing() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=3)
    points = np.asarray(sphere.vertices)  # 642 points on the unit sphere
    pv, pf, volume, reduced = canonical_part(points, 20)
    assert reduced and len(pv) <= 20
    # The budgeted part is meshcol's one budgeted hull: it still encloses every input point.
    eq = ConvexHull(pv).equations
    assert (points @ eq[:, :3].T + eq[:, 3]).max() <= 1e-9
    assert ConvexHull(points).volume < volume < 2.0 * ConvexHull(points).volume
    assert _signed_volume(pv, pf) == pytest.approx(volume, rel=1e-9)


def test_canonical_part_of_flat_points_is_none() -> None:
    assert canonical_part(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]), None) is None
    assert canonical_part(np.zeros((3, 3)), None) is None


# ---------------------------------------------------------------------------- distances


def test_point_triangle_distance_known_regions() -> None:
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    cases = {  # point -> distance: face, three vertices, three edges
        (0.2, 0.2, 2.0): 2.0,
        (-1.0, -1.0, 0.0): np.sqrt(2),
        (2.0, 0.0, 0.0): 1.0,
        (0.0, 3.0, 0.0): 2.0,
        (0.5, -2.0, 0.0): 2.0,
        (-3.0, 0.5, 0.0): 3.0,
        (1.0, 1.0, 0.0): np.sqrt(2) / 2,
    }
    for point, expected in cases.items():
        d = point_triangle_distances(np.array([point]), tri)
        assert d[0] == pytest.approx(expected, abs=1e-12), point


def test_points_to_triangles_pruning_equals_brute_force() -> None:
    m = _torus()
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    points = np.random.default_rng(1).uniform(-1.6, 1.6, (300, 3))
    brute = np.array(
        [point_triangle_distances(np.repeat(p[None], len(f), 0), v[f]).min() for p in points]
    )
    assert np.allclose(points_to_triangles(points, v, f), brute, atol=1e-12)


def test_points_to_triangles_agrees_with_mesh_query() -> None:
    from meshcol.collision import mesh_query

    m = _torus()
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    points = np.random.default_rng(4).uniform(-1.6, 1.6, (100, 3))
    # A point is a degenerate one-triangle mesh for the BVH-pair distance.
    meshes = mesh_query.MeshSet.from_arrays(
        [(v, f)] + [(np.repeat(p[None], 3, 0), [[0, 1, 2]]) for p in points]
    )
    pairs = np.stack([np.arange(1, 101), np.zeros(100, dtype=np.int64)], axis=1)
    expected = mesh_query.mesh_distance_batch(meshes, None, pairs).distance
    assert np.allclose(points_to_triangles(points, v, f), expected, rtol=0, atol=1e-12)


def test_points_to_parts_known_distances() -> None:
    parts = (_box((0, 0, 0), (1, 1, 1)), _box((3, 0, 0), (4, 1, 1)))
    points = np.array(
        [[0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [1.5, 0.5, 0.5], [0.5, 0.5, 3.0], [5.0, 2.0, 1.0]]
    )
    d = points_to_parts(points, parts)
    assert d == pytest.approx([0.0, 1.0, 0.5, 2.0, np.sqrt(2)], abs=1e-6)
    owner = np.array([0, 0, 1, 0, 1])  # exclude the owner part
    d = points_to_parts(points, parts, owner)
    assert d == pytest.approx([2.5, 1.0, 0.5, np.sqrt(2.5**2 + 2**2), np.sqrt(17)], abs=1e-6)


# ---------------------------------------------------------------------------- fidelity


def test_fidelity_of_the_mesh_itself_is_perfect() -> None:
    v, f = canonical_geometry(*_box())
    m = fidelity(v, f, ((v, f),), samples=500)
    assert (m.parts, m.vertices_per_part) == (1, (8,))
    assert m.mesh_volume == pytest.approx(1.0, abs=1e-12)
    assert m.union_volume == pytest.approx(1.0, abs=1e-12)
    assert m.hausdorff_mesh_to_parts == pytest.approx(0.0, abs=1e-6)
    assert m.hausdorff_parts_to_mesh == pytest.approx(0.0, abs=1e-12)
    assert m.uncovered_fraction == 0.0
    assert m.tolerance == pytest.approx(0.01 * np.sqrt(3))


def test_fidelity_two_halves_share_a_cut_and_half_misses() -> None:
    v, f = canonical_geometry(*_box())
    halves = (_box((0, 0, 0), (0.5, 1, 1)), _box((0.5, 0, 0), (1, 1, 1)))
    m = fidelity(v, f, halves, samples=500)
    # The cut at x = 0.5 is shared: it is not boundary of the union, so parts -> mesh is 0.
    assert m.hausdorff_parts_to_mesh == pytest.approx(0.0, abs=1e-12)
    assert m.hausdorff_mesh_to_parts == pytest.approx(0.0, abs=1e-6)
    assert m.union_volume == pytest.approx(1.0, abs=1e-9)
    assert m.mesh_is_solid
    half = fidelity(v, f, halves[:1], samples=2000, tolerance=0.01)
    assert half.hausdorff_mesh_to_parts == pytest.approx(0.5, abs=1e-6)  # the corners at x = 1
    # The half lies inside the cube: nothing of it sticks out (its face x = 0.5 is inside the
    # solid); what it misses is the other direction's business.
    assert half.hausdorff_parts_to_mesh == pytest.approx(0.0, abs=1e-12)
    assert half.volume_ratio == pytest.approx(0.5, abs=1e-9)
    # Uncovered: the face x = 1 and the x > 0.51 halves of four faces: (1 + 4 * 0.49) / 6.
    assert half.uncovered_fraction == pytest.approx((1 + 4 * 0.49) / 6, abs=0.04)


def _parts(*boxes) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    return tuple(canonical_part(_box(lo, hi)[0], None)[:2] for lo, hi in boxes)


def _cube_in_three(gap: float) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """The cube [-20, 20]^3 as three slabs along x, slits ``2 * gap`` wide between them."""
    a, b = -20 / 3, 20 / 3
    return _parts(
        ((-20, -20, -20), (a - gap, 20, 20)),
        ((a + gap, -20, -20), (b - gap, 20, 20)),
        ((b + gap, -20, -20), (20, 20, 20)),
    )


@pytest.mark.parametrize("gap", [0.003, 0.05])
def test_fidelity_cut_faces_inside_the_mesh_do_not_count(gap) -> None:
    # Regression (#12): a 40-unit cube as three boxes covering 99.97% of it reported a
    # parts -> mesh Hausdorff of 9.95 (13.3 here): the faces of the slits, deep inside the cube.
    v, f = canonical_geometry(*_box((-20, -20, -20), (20, 20, 20)))
    m = fidelity(v, f, _cube_in_three(gap))
    assert m.volume_ratio == pytest.approx(1 - 4 * gap / 40, rel=1e-12)  # 0.9997 for 0.003
    assert m.mesh_is_solid
    assert m.hausdorff_parts_to_mesh <= 1e-9  # nothing sticks out
    assert m.hausdorff_mesh_to_parts <= gap + 1e-9  # the mesh's strips over the slits


def test_fidelity_part_sticking_out_reports_its_height() -> None:
    v, f = canonical_geometry(*_box((-20, -20, -20), (20, 20, 20)))
    tiles = _cube_in_three(0.0)
    # A slab 5 beyond the face x = 20: every point of its face x = 25 is 5 from the cube.
    out_x = fidelity(v, f, tiles + _parts(((15, -5, -5), (25, 5, 5))))
    assert out_x.hausdorff_parts_to_mesh == pytest.approx(5.0, abs=1e-9)
    assert out_x.hausdorff_mesh_to_parts == pytest.approx(0.0, abs=1e-9)
    # Beyond a corner: the farthest point is the corner (25, 25, 25), 5 * sqrt(3) away.
    corner = fidelity(v, f, tiles + _parts(((15, 15, 15), (25, 25, 25))))
    assert corner.hausdorff_parts_to_mesh == pytest.approx(5.0 * np.sqrt(3.0), abs=1e-9)
    # Alone, sticking out of a hole it does not fill: both directions see it.
    alone = fidelity(v, f, _parts(((-20, -20, -20), (20, 20, 10)), ((-5, -5, 10), (5, 5, 30))))
    assert alone.hausdorff_parts_to_mesh == pytest.approx(10.0, abs=1e-9)
    assert alone.hausdorff_mesh_to_parts == pytest.approx(10.0, abs=1e-6)  # the top, 10 above


def _torus_solid_distance(points: np.ndarray, major: float, minor: float) -> np.ndarray:
    """Distance from points to the solid torus (analytic; 0 inside)."""
    ring = np.hypot(np.hypot(points[:, 0], points[:, 1]) - major, points[:, 2])
    return np.maximum(ring - minor, 0.0)


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_fidelity_torus_wedges_with_gaps_report_how_far_they_stick_out() -> None:
    # Regression (#12): a torus whose parts lie within 0.8% of its surface reported 10.7%.
    # Twelve wedges, each the hull of 9 rings of the mesh, the end rings turned 1e-3 rad
    # inwards, so that the wedges do not touch (as CoACD's parts do not): their end discs are
    # cut faces inside the torus, not shared with a neighbour.
    major, minor, sections = 1.0, 0.3, 96
    mesh = trimesh.creation.torus(major, minor, major_sections=sections, minor_sections=32)
    v, f = canonical_geometry(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    diag = float(np.linalg.norm(np.ptp(v, axis=0)))
    angle = np.arctan2(v[:, 1], v[:, 0]) % (2 * np.pi)
    ring = np.round(angle / (2 * np.pi / sections)).astype(int) % sections
    parts = []
    for k in range(12):
        rings = [(8 * k + j) % sections for j in range(9)]
        chosen = v[np.isin(ring, rings)]
        a = np.arctan2(chosen[:, 1], chosen[:, 0])
        r = np.hypot(chosen[:, 0], chosen[:, 1])
        lo, hi = 2 * np.pi * 8 * k / sections, 2 * np.pi * (8 * k + 8) / sections
        a = np.unwrap(a - lo) + lo
        a = np.where(np.isclose(a, lo), lo + 1e-3, np.where(np.isclose(a, hi), hi - 1e-3, a))
        turned = np.column_stack([r * np.cos(a), r * np.sin(a), chosen[:, 2]])
        parts.append(canonical_part(turned, None)[:2])
    parts = tuple(parts)
    # The oracle: the analytic solid torus, on dense samples of every part surface (a cut
    # face inside the torus is 0 there, as on the boundary of the union).
    rng = np.random.default_rng(7)
    dense = np.concatenate(
        [
            trimesh.sample.sample_surface(
                trimesh.Trimesh(pv, pf), 20000, seed=rng.integers(1 << 30)
            )[0]
            for pv, pf in parts
        ]
    )
    oracle = float(_torus_solid_distance(dense, major, minor).max())
    # The inner faces span 30 degrees of the hole: they sag 0.7 (1 - cos 15) = 0.0239 into it.
    assert oracle == pytest.approx(0.7 * (1 - np.cos(np.pi / 12)), rel=0.05)
    assert oracle / diag < 0.008  # the parts lie within 0.8% of the surface
    m = fidelity(v, f, parts)
    assert m.mesh_is_solid
    assert m.hausdorff_parts_to_mesh / diag <= 0.01
    # The mesh's own polygon sag (inscribed in the analytic torus) bounds the difference.
    mesh_sag = (major + minor) * (1 - np.cos(np.pi / sections)) + minor * (1 - np.cos(np.pi / 32))
    assert 0.8 * oracle <= m.hausdorff_parts_to_mesh <= oracle + mesh_sag
    assert m.hausdorff_mesh_to_parts <= 2e-3  # the 1e-3 rad gaps, at radius at most 1.3


def test_fidelity_of_an_open_mesh_measures_to_its_surface() -> None:
    # A box without its top is no solid: parts -> mesh measures to the surface that is there.
    v, f = _box()
    top = np.all(v[f][:, :, 2] == 1.0, axis=1)
    v, f = canonical_geometry(v, f[~top])
    m = fidelity(v, f, _parts(((0, 0, 0), (1, 1, 1))), samples=4000)
    assert not m.mesh_is_solid
    # The middle of the missing top is 0.5 from the walls; the samples come close to it.
    assert 0.45 < m.hausdorff_parts_to_mesh <= 0.5 + 1e-12


@pytest.mark.parametrize("seed", range(5))
def test_farthest_outside_solid_equals_brute_force(seed) -> None:
    from meshcol.collision.mesh_query import MeshSet

    torus = _torus()
    v, f = canonical_geometry(np.asarray(torus.vertices), np.asarray(torus.faces))
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1.4, 1.4, size=(3000, 3)) * [1, 1, 0.4]
    # Points near edges and corners too (their closest feature is not a face's inside).
    near = v[rng.integers(len(v), size=500)] + rng.normal(scale=0.02, size=(500, 3))
    points = np.concatenate([points, near])
    inverted = (v, f[:, ::-1])  # consistently wound the other way round: the same solid
    for mesh in ((v, f), inverted):
        meshes = MeshSet.from_arrays([mesh])
        distances, _ = meshes.closest_points(0, points)
        inside = np.abs(meshes.winding_number(0, points)) >= 0.5
        outside = float(np.where(inside, 0.0, distances).max())
        assert farthest_outside_solid(points, meshes) == outside
        # Only the points inside, then those plus the nearest outside ones: the search has
        # to go past every inside point.
        assert farthest_outside_solid(points[inside], meshes) == 0.0
        few = inside | (distances <= np.quantile(distances[~inside], 0.05))
        expected = float(np.where(inside, 0.0, distances)[few].max())
        assert farthest_outside_solid(points[few], meshes) == expected


def test_stale_cached_metrics_are_measured_again_without_the_engine(tmp_path, monkeypatch) -> None:
    import json
    import zipfile

    from meshcol.decomposition import decompose as decompose_module

    v, f = _box()
    d = decompose((v, f), cache_dir=str(tmp_path), **FAST)
    path = decompose_cache.entry_path(d.cache_key, tmp_path)
    with np.load(path) as z:
        arrays = dict(z)
    header = json.loads(bytes(arrays["header"]).decode())
    header.pop("metrics_version")  # an entry written before the metrics changed meaning
    del header["metrics"]["mesh_is_solid"]
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(path, **arrays)
    assert zipfile.is_zipfile(path)
    stale = decompose_cache.load(d.cache_key, tmp_path)
    assert stale is not None and stale.metrics is None and len(stale.parts) == len(d.parts)

    def no_engine(*args, **kwargs):
        raise AssertionError("the engine ran for a cached decomposition")

    monkeypatch.setattr(decompose_module, "run_engine", no_engine)
    again = decompose((v, f), cache_dir=str(tmp_path), **FAST)
    assert again.from_cache and again.metrics == d.metrics
    assert decompose_cache.load(d.cache_key, tmp_path).metrics == d.metrics


# ---------------------------------------------------------------------------- decompose


@pytest.fixture(scope="module")
def torus_result(tmp_path_factory) -> tuple[Decomposition, float, Path]:
    cache = tmp_path_factory.mktemp("cache")
    start = time.perf_counter()
    d = decompose(_torus(), cache_dir=str(cache), **FAST)
    return d, time.perf_counter() - start, cache


def test_parts_are_convex_and_cover_the_torus(torus_result) -> None:
    d, _, _ = torus_result
    m = _torus()
    assert 2 <= len(d.parts) == d.metrics.parts
    for v, f in d.parts:
        hull = ConvexHull(v)
        assert len(hull.vertices) == len(v)  # every vertex is a hull vertex
        assert _signed_volume(v, f) == pytest.approx(hull.volume, rel=1e-9)  # faces = its hull
    points = trimesh.sample.sample_surface(m, 1000, seed=5)[0]
    tol = 0.01 * np.linalg.norm(np.ptp(m.vertices, axis=0))
    assert _inside_union(points, d.parts, tol).mean() >= 0.99
    assert d.metrics.uncovered_fraction <= 0.01
    assert d.metrics.volume_ratio >= 0.98
    assert d.metrics.hausdorff_mesh_to_parts < 0.1
    assert not d.repaired and d.notes == ()
    centroids = [tuple(v.mean(axis=0)) for v, _ in d.parts]
    assert centroids == sorted(centroids)


def test_decompose_is_deterministic_and_independent_of_input_order(torus_result) -> None:
    d, _, _ = torus_result
    m = _torus()
    perm = np.random.default_rng(2).permutation(len(m.vertices))
    shuffled = (np.asarray(m.vertices)[perm], np.argsort(perm)[np.asarray(m.faces)])
    again = decompose(shuffled, use_cache=False, metrics=False, **FAST)
    assert again.cache_key == d.cache_key
    assert len(again.parts) == len(d.parts)
    for (v1, f1), (v2, f2) in zip(again.parts, d.parts):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)


def test_inside_out_input_is_decomposed_outward(torus_result, tmp_path) -> None:
    # CoACD decomposes an inverted mesh badly (other parts, a negative volume ratio): the
    # faces are reversed first, so the parts and metrics are the outward torus's, with a note.
    d, _, _ = torus_result
    m = _torus()
    inside_out = (np.asarray(m.vertices), np.asarray(m.faces)[:, ::-1])
    flipped = decompose(inside_out, cache_dir=str(tmp_path / "cache"), **FAST)
    assert flipped.notes == (
        "input is inside out (negative volume): decomposed with its faces reversed",
    )
    assert flipped.cache_key != d.cache_key  # the entry's note is true of its own input
    assert len(flipped.parts) == len(d.parts)
    for (v1, f1), (v2, f2) in zip(flipped.parts, d.parts):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)
    assert flipped.metrics.mesh_volume == pytest.approx(d.metrics.mesh_volume, rel=1e-12)
    assert flipped.metrics.volume_ratio == pytest.approx(d.metrics.volume_ratio, rel=1e-12)
    looked_up = cached_decomposition(inside_out, cache_dir=str(tmp_path / "cache"), **FAST)
    assert looked_up is not None and looked_up.notes == flipped.notes


def test_cache_hit_is_fast_and_equal(torus_result) -> None:
    d, miss_seconds, cache = torus_result
    start = time.perf_counter()
    hit = decompose(_torus(), cache_dir=str(cache), **FAST)
    hit_seconds = time.perf_counter() - start
    assert hit.from_cache and not d.from_cache
    assert hit_seconds < miss_seconds / 5
    assert hit.metrics == d.metrics and hit.params == d.params and hit.notes == d.notes
    for (v1, f1), (v2, f2) in zip(hit.parts, d.parts):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)
    looked_up = cached_decomposition(_torus(), cache_dir=str(cache), **FAST)
    assert looked_up is not None and looked_up.cache_key == d.cache_key
    assert cached_decomposition(_torus(), cache_dir=str(cache), seed=1, **FAST) is None
    assert meshcol.cached_decomposition is cached_decomposition


def test_cache_hit_with_other_sampling_measures_again_without_the_engine(
    torus_result, tmp_path
) -> None:
    d, _, cache = torus_result
    shutil.copytree(cache, tmp_path / "cache")
    hit = decompose(_torus(), cache_dir=str(tmp_path / "cache"), samples=300, **FAST)
    assert hit.from_cache and hit.metrics.samples == 300 and d.metrics.samples == 2000
    assert all(np.array_equal(a[0], b[0]) for a, b in zip(hit.parts, d.parts))
    again = decompose(_torus(), cache_dir=str(tmp_path / "cache"), samples=300, **FAST)
    assert again.metrics == hit.metrics


def test_cache_write_interrupted_before_rename_leaves_nothing(
    torus_result, tmp_path, monkeypatch
) -> None:
    d, _, _ = torus_result

    def broken_replace(src, dst):
        raise KeyboardInterrupt  # as if the run were stopped between write and rename

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(KeyboardInterrupt):
        decompose_cache.store(d, tmp_path)
    monkeypatch.undo()
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == []
    assert decompose_cache.load(d.cache_key, tmp_path) is None


def test_cache_ignores_corrupt_entries(torus_result, tmp_path) -> None:
    d, _, _ = torus_result
    path = decompose_cache.store(d, tmp_path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    assert decompose_cache.load(d.cache_key, tmp_path) is None
    path.write_bytes(data)
    assert decompose_cache.load(d.cache_key, tmp_path) is not None


def test_default_cache_dir_follows_xdg(monkeypatch, tmp_path) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert decompose_cache.default_cache_dir() == tmp_path / "meshcol" / "decompose"


@pytest.mark.slow
def test_vertex_and_hull_budgets_are_respected() -> None:
    d = decompose(_torus(), max_vertices=8, max_hulls=3, use_cache=False, metrics=False, **FAST)
    assert 1 <= len(d.parts) <= 3
    assert max(len(v) for v, _ in d.parts) <= 8


def test_vhacd_engine_budgets() -> None:
    pytest.importorskip("vhacdx")
    d = decompose(
        _torus(),
        engine="vhacd",
        max_hulls=12,
        max_vertices=40,
        resolution=50000,
        use_cache=False,
        samples=500,
    )
    assert d.engine == "vhacd" and 1 <= len(d.parts) <= 12
    assert max(len(v) for v, _ in d.parts) <= 40
    assert d.metrics.uncovered_fraction < 0.1


def test_decompose_rejects_flat_mesh() -> None:
    with pytest.raises(InvalidMeshError, match="mesh is flat"):
        decompose(trimesh.creation.box(extents=(1, 1, 0)), use_cache=False)


def test_decompose_accepts_a_body() -> None:
    v, f = _box()
    body = meshcol.Body("box", None, v * 2.0, f)
    d = decompose(body, use_cache=False, **FAST)
    assert len(d.parts) == 1
    assert d.metrics.volume_ratio == pytest.approx(1.0, abs=1e-6)


def test_bottle_soup_is_repaired(corpus) -> None:
    bottle = trimesh.load(corpus / "coacd-examples" / "Bottle.obj", force="mesh")
    d = decompose(
        bottle,
        threshold=0.3,
        resolution=300,
        use_cache=False,
        samples=500,
        engine_options={
            "preprocess_resolution": 20,
            "mcts_iterations": 10,
            "mcts_nodes": 4,
            "mcts_max_depth": 1,
        },
    )
    assert d.repaired and d.params["preprocess_mode"] == "on"
    assert (
        d.notes[0]
        == "input is not a closed manifold: CoACD's preprocessing rebuilt it before decomposing"
    )
    assert d.metrics.mesh_volume is None  # a triangle soup bounds no volume


def _engine_of_boxes(count: int):
    """A stand-in engine that returns ``count`` unit boxes in a row (overshooting any hull
    count below it), as (vertices, faces) pairs like CoACD's."""

    def run(engine, vertices, faces, params):
        return [_box((i * 1.5, 0, 0), (i * 1.5 + 1.0 + 0.1 * i, 1, 1)) for i in range(count)]

    return run


def test_parts_over_max_hulls_are_merged_never_dropped(monkeypatch) -> None:
    """An engine that returns more parts than ``max_hulls`` gets them merged (each merged
    part the hull of those it replaces), so every point the engine's parts covered is still
    covered: a dropped part would leave a hole in the collision geometry."""
    from meshcol.decomposition import decompose as decompose_module

    engine_parts = _engine_of_boxes(5)(None, None, None, None)
    monkeypatch.setattr(decompose_module, "run_engine", _engine_of_boxes(5))
    v, f = _box((0, 0, 0), (7.5, 1, 1))
    d = decompose((v, f), max_hulls=2, use_cache=False, metrics=False)
    assert len(d.parts) == 2
    corners = np.vstack([pv for pv, _ in engine_parts])
    assert _inside_union(corners, d.parts, 1e-9).all()
    assert any("returned 5 parts: merged into 2 (max_hulls" in note for note in d.notes)
    # The cheapest merges join neighbours: no box is merged with a far one over a near one.
    spans = sorted((pv[:, 0].min(), pv[:, 0].max()) for pv, _ in d.parts)
    assert spans[0][1] < spans[1][0]
    # Within the vertex budget as every part (an 8-corner hull of two boxes has 8 vertices;
    # max_vertices=6 makes the budgeted, still enclosing, hull).
    budgeted = decompose((v, f), max_hulls=2, max_vertices=6, use_cache=False, metrics=False)
    assert max(len(pv) for pv, _ in budgeted.parts) <= 6
    assert _inside_union(corners, budgeted.parts, 1e-9).all()


def test_a_cache_entry_that_dropped_parts_is_decomposed_again(monkeypatch, tmp_path) -> None:
    """An entry stored by an earlier meshcol that kept only the largest parts over max_hulls
    (its note says so) is a miss: the body is decomposed again, with its parts merged."""
    import dataclasses

    from meshcol.decomposition import decompose as decompose_module

    monkeypatch.setattr(decompose_module, "run_engine", _engine_of_boxes(4))
    v, f = _box((0, 0, 0), (6.0, 1, 1))
    fresh = decompose((v, f), max_hulls=2, cache_dir=str(tmp_path), metrics=False)
    old = dataclasses.replace(
        fresh,
        parts=fresh.parts[:1],
        notes=("coacd returned 4 parts: kept the 2 largest (max_hulls)",),
    )
    decompose_cache.store(old, tmp_path)
    assert len(decompose_cache.load(fresh.cache_key, tmp_path).parts) == 1
    again = decompose((v, f), max_hulls=2, cache_dir=str(tmp_path), metrics=False)
    assert not again.from_cache and len(again.parts) == 2
    assert again.notes == fresh.notes
