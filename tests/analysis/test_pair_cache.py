"""The per-pair cache of check (meshcol.analysis.pair_cache): a re-run after a body moved,
was reshaped, added or removed measures only the pairs it is in, and the report is the same
bytes as a cold run's."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.analysis.pair_cache import PairCache, select_rows
from meshcol.types import Body, Box, Scene

trimesh = pytest.importorskip("trimesh", reason="the scene's meshes are made with trimesh")


def pose(x: float, y: float, z: float, angle: float = 0.0) -> np.ndarray:
    t = np.eye(4)
    c, s = np.cos(angle), np.sin(angle)
    t[:2, :2] = [[c, -s], [s, c]]
    t[:3, 3] = (x, y, z)
    return t


def body(name: str, kind: int, at: np.ndarray, scale: float = 1.0) -> Body:
    """A body of one of four kinds: a convex blob (hull), a torus (mesh: concave, so a
    body can nest in its hole), a box primitive, an L of two boxes (decomposed as hull)."""
    if kind == 0:
        mesh = trimesh.creation.icosphere(subdivisions=1, radius=0.6 * scale)
        mesh.vertices *= (1.0, 0.8, 1.2)
        return Body(name, None, np.asarray(mesh.vertices), np.asarray(mesh.faces, np.int64), at)
    if kind == 1:
        mesh = trimesh.creation.torus(0.7 * scale, 0.25 * scale, major_sections=24)
        return Body(
            name,
            None,
            np.asarray(mesh.vertices),
            np.asarray(mesh.faces, np.int64),
            at,
            collider="mesh",
        )
    if kind == 2:
        size = (0.8 * scale, 0.5, 0.6)
        mesh = trimesh.creation.box(extents=size)
        return Body(
            name,
            None,
            np.asarray(mesh.vertices),
            np.asarray(mesh.faces, np.int64),
            at,
            primitive=Box(size),
        )
    first = trimesh.creation.box(extents=(1.0 * scale, 0.3, 0.3))
    second = trimesh.creation.box(extents=(0.3, 1.0 * scale, 0.3))
    second.apply_translation((0.35, 0.35, 0))
    mesh = trimesh.util.concatenate([first, second])
    return Body(name, None, np.asarray(mesh.vertices), np.asarray(mesh.faces, np.int64), at)


def scene(count: int = 28, seed: int = 7) -> list[Body]:
    """Bodies crowded in a small box: penetrating, touching, near and apart pairs."""
    rng = np.random.default_rng(seed)
    spots = rng.uniform(0, 3.2, size=(count, 3))
    turns = rng.uniform(0, np.pi, size=count)
    return [body(f"b{i:02d}", i % 4, pose(*spots[i], turns[i])) for i in range(count)]


OPTIONS = {"tolerance": 1e-6, "clearance": 0.05, "fail_on": "contact"}


def report_bytes(bodies: list[Body], pair_cache: PairCache | None = None) -> tuple[str, dict]:
    report = check_scene(Scene(tuple(bodies)), CheckOptions(**OPTIONS, pair_cache=pair_cache))
    data = json.loads(report.to_json())
    data["summary"]["seconds"] = data["summary"]["load_seconds"] = 0.0
    data["generated_at"] = None
    return json.dumps(data, sort_keys=True), data  # the report's bytes but the clock's


def pairs_with(data: dict, names: set[str]) -> int:
    return sum(p["body_a"] in names or p["body_b"] in names for p in data["pairs"])


def test_cached_pairs_give_the_cold_report_and_only_changed_bodies_are_measured(tmp_path):
    bodies = scene()
    cache = PairCache(tmp_path / "store", "level.json")
    cold, data = report_bytes(bodies)
    statuses = {p["status"] for p in data["pairs"]}
    assert {"penetrating", "separated"} <= statuses and len(data["pairs"]) > 40
    assert report_bytes(bodies, cache)[0] == cold
    assert cache.counts == {"hits": 0, "measured": len(data["pairs"])}
    assert report_bytes(bodies, cache)[0] == cold  # warm: every pair from the cache
    assert cache.counts == {"hits": len(data["pairs"]), "measured": 0}

    changed = list(bodies)
    moved, reshaped, removed = changed[3], changed[6], changed[9]
    changed[3] = dataclasses.replace(moved, pose=pose(1.6, 1.6, 1.6, 0.3))  # moved
    changed[6] = body(reshaped.name, 2, reshaped.pose, scale=1.5)  # another shape
    changed.remove(removed)
    changed.append(body("b99", 1, pose(1.5, 1.5, 1.4)))  # added, amid the crowd
    fresh, fresh_data = report_bytes(changed)
    assert report_bytes(changed, cache)[0] == fresh
    touched = pairs_with(fresh_data, {moved.name, reshaped.name, "b99"})
    assert touched > 3
    assert cache.counts == {"hits": len(fresh_data["pairs"]) - touched, "measured": touched}
    assert pairs_with(fresh_data, {removed.name}) == 0


def test_the_settings_and_a_broken_entry_are_misses(tmp_path):
    bodies = scene(16, seed=3)
    cache = PairCache(tmp_path / "store", "s")
    cold, data = report_bytes(bodies, cache)
    # another tolerance: every pair measured again (the margin picks the part pairs)
    other = CheckOptions(**{**OPTIONS, "tolerance": 1e-3}, pair_cache=cache)
    check_scene(Scene(tuple(bodies)), other)
    assert cache.counts["hits"] == 0
    entry = tmp_path / "store" / cache.entry
    for broken in (b"not an npz", entry.read_bytes()[:100]):
        entry.write_bytes(broken)
        assert report_bytes(bodies, cache)[0] == cold
        assert cache.counts == {"hits": 0, "measured": len(data["pairs"])}


def test_twin_bodies_share_one_key_and_the_entry_stays_readable(tmp_path):
    twin = body("a", 0, pose(0, 0, 0))
    bodies = [twin, dataclasses.replace(twin, name="b"), body("c", 2, pose(0.5, 0, 0))]
    cache = PairCache(tmp_path / "store", "twins")
    cold, data = report_bytes(bodies, cache)
    assert report_bytes(bodies, cache)[0] == cold
    assert cache.counts == {"hits": len(data["pairs"]), "measured": 0}


def test_select_rows_keeps_each_rows_part_pairs(tmp_path):
    from meshcol.analysis.colliders import build_colliders
    from meshcol.analysis.pairs import broad_phase, place

    placed = place(build_colliders(scene(12, seed=5), "hull"))
    table = broad_phase(placed, 0.05)
    rows = np.arange(0, len(table), 3)
    part = select_rows(table, rows)
    assert np.array_equal(part.body_a, table.body_a[rows])
    for new, old in enumerate(rows):
        mine = part.part_pairs[part.part_row == new]
        theirs = table.part_pairs[table.part_row == old]
        assert np.array_equal(mine, theirs)


def test_primitive_only_scenes_and_every_pose_change_are_keyed(tmp_path):
    """Bodies of primitives only (no hull vertices at all) are keyed too, and a turn as
    small as one ulp of the pose is another key."""
    bodies = [body(f"p{i}", 2, pose(0.6 * i, 0, 0)) for i in range(4)]
    cache = PairCache(tmp_path / "store", "boxes")
    cold, data = report_bytes(bodies, cache)
    assert report_bytes(bodies, cache)[0] == cold and cache.counts["measured"] == 0
    nudged = list(bodies)
    turned = pose(0.6, 0, 0)
    turned[0, 3] = np.nextafter(turned[0, 3], 1.0)
    nudged[1] = dataclasses.replace(bodies[1], pose=turned)
    assert report_bytes(nudged, cache)[0] == report_bytes(nudged)[0]
    assert cache.counts["measured"] == pairs_with(data, {"p1"}) > 0
