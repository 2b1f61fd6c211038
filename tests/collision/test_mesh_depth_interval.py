"""Depth as an interval (issue 29, item 2): ``depth <= minimum translation distance <=
depth_upper`` on pairs whose minimum translation distance is known in closed form.

The mesh depth is a lower bound (0.29 of the true value on a thin wall); ``depth_upper`` is
the penetration depth of convex sets enclosing the two bodies, which bounds it from above.
Both are checked against the analytic minimum translation distance of boxes sunk into boxes,
spheres, and a cube across the wall of a thin-walled box, under several collider kinds, and
on open hosts, whose mesh depth used to exceed the hulls'.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.types import Body, Scene

SLACK = 1e-8  # rounding, and the margin (about 1e-9) by which a fitted primitive encloses


def _body(name: str, mesh: trimesh.Trimesh, offset=(0.0, 0.0, 0.0)) -> Body:
    pose = np.eye(4)
    pose[:3, 3] = offset
    return Body(name, None, np.asarray(mesh.vertices), np.asarray(mesh.faces), pose)


def _pair(a: Body, b: Body, collider: str = "mesh") -> dict:
    (pair,) = check_scene(Scene((a, b)), CheckOptions(collider=collider, clearance=0.01)).pairs
    return pair


def _box(extents) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents)


def _shell(size: float, wall: float) -> trimesh.Trimesh:
    """A closed box with a closed cavity: the outer faces outward, the inner inward."""
    outer, inner = _box((size,) * 3), _box((size - 2 * wall,) * 3)
    vertices = np.concatenate([outer.vertices, inner.vertices])
    faces = np.concatenate([outer.faces, inner.faces[:, ::-1] + len(outer.vertices)])
    return trimesh.Trimesh(vertices, faces, process=False)


def _holds(pair: dict, true: float) -> None:
    assert pair["depth"] <= true + SLACK, pair
    assert pair["depth_upper"] >= true - SLACK, pair
    assert pair["depth"] <= pair["depth_upper"]


# (name, body a, body b, minimum translation distance)
CASES = [
    (
        "box sunk 0.1 into a box",
        _body("a", _box((1, 1, 1))),
        _body("b", _box((0.5, 0.5, 0.5)), (0, 0, 0.65)),
        0.1,
    ),
    (
        "boxes crossed 0.3",
        _body("a", _box((1, 1, 1))),
        _body("b", _box((2, 0.2, 0.2)), (0, 0, 0.5)),
        0.1,
    ),
    (
        "box deep in a box",
        _body("a", _box((1, 1, 1))),
        _body("b", _box((0.2, 0.2, 0.2)), (0.1, 0, 0)),
        0.5,
    ),
    (
        "cube across a thin wall",
        _body("a", _shell(1.0, 0.02)),
        _body("b", _box((0.1, 0.1, 0.1)), (0.49, 0, 0)),
        0.06,
    ),
    (
        "cube in a wall's cavity side",
        _body("a", _shell(1.0, 0.02)),
        _body("b", _box((0.1, 0.1, 0.1)), (0.45, 0, 0)),
        0.02,
    ),
    (
        "cube in the cavity",
        _body("a", _shell(1.0, 0.02)),
        _body("b", _box((0.1, 0.1, 0.1)), (0.2, 0, 0)),
        0.0,
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("collider", ["mesh", "hull", "box"])
def test_depth_interval_holds_the_true_value(case, collider) -> None:
    name, a, b, true = case
    if collider != "mesh" and ("wall" in name or "cavity" in name):
        true = None  # a hull fills the cavity: another collider, another true value
    pair = _pair(a, b, collider)
    if true is None:
        assert pair["depth"] <= pair["depth_upper"]
        return
    _holds(pair, true)


def test_single_convex_parts_have_a_point_interval() -> None:
    pair = _pair(
        _body("a", _box((1, 1, 1))), _body("b", _box((0.5, 0.5, 0.5)), (0, 0, 0.65)), "box"
    )
    assert pair["depth"] == pytest.approx(0.1, abs=SLACK)
    assert pair["depth_upper"] == pair["depth"]


def test_spheres_interval() -> None:
    """Two spheres of radius 0.5 whose centres are 0.8 apart: the minimum translation
    distance is 0.2 (under ``sphere`` each is its exact minimum sphere)."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    pair = _pair(_body("a", ball), _body("b", ball, (0.8, 0, 0)), "sphere")
    _holds(pair, 0.2)
    assert pair["depth_upper"] == pytest.approx(0.2, abs=SLACK)
    # as meshes: the true value is the polyhedra's, between 0.2 - sag and 0.2
    mesh_pair = _pair(_body("a", ball), _body("b", ball, (0.8, 0, 0)))
    sag = 0.5 * (1 - np.cos(np.pi / 40))
    assert 0.2 - 2 * sag - SLACK <= mesh_pair["depth_upper"]
    assert mesh_pair["depth"] <= mesh_pair["depth_upper"]


def test_apart_pairs_have_no_depth() -> None:
    pair = _pair(_body("a", _box((1, 1, 1))), _body("b", _box((1, 1, 1)), (0, 0, 1.0 + 1e-3)))
    assert pair["depth"] == 0.0 and pair["depth_upper"] == 0.0


@pytest.mark.parametrize("z", [0.0, 0.3, 0.45, 0.5 - 1e-7, 0.55])
def test_open_host_interval(z) -> None:
    """A box without its top face (open), a cube crossing it or in its opening: whatever the
    mesh depth of an open surface means, it never exceeds the hulls' depth."""
    host = _box((1, 1, 1))
    keep = np.asarray(host.face_normals)[:, 2] < 0.5
    open_box = trimesh.Trimesh(host.vertices, np.asarray(host.faces)[keep], process=False)
    pair = _pair(_body("a", open_box), _body("b", _box((0.2, 0.2, 0.2)), (0.35, 0.2, z)))
    assert pair["depth"] <= pair["depth_upper"]
    assert np.isfinite(pair["depth_upper"])
