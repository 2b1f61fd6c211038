"""Primitive bodies are never tessellated for queries (issue 32): a manifest or robot of
primitives is checked without one triangle, gives the report a tessellated scene gives, and
makes the tessellation only when something reads it, once per distinct primitive."""

from __future__ import annotations

import dataclasses
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

import meshcol.types as types
from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.io.primitives import primitive_mesh
from meshcol.io.scene import load_inputs
from meshcol.types import (
    REGULAR_LENGTHS,
    REGULAR_VERTEX_COUNTS,
    Body,
    Box,
    Capsule,
    Cylinder,
    Sphere,
    primitive_vertex_count,
)

URDF = """<robot name="r">
<link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="arm">
  <collision><origin xyz="0 0 0.5"/><geometry><cylinder radius="0.05" length="1"/></geometry>
  </collision>
</link>
<link name="tip"><collision><geometry><sphere radius="0.3"/></geometry></collision></link>
<joint name="shoulder" type="revolute">
  <parent link="base"/><child link="arm"/>
  <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/>
</joint>
<joint name="end" type="fixed">
  <parent link="arm"/><child link="tip"/><origin xyz="0 0 1.1"/>
</joint>
</robot>
"""


def manifest(folder: Path, n: int = 60) -> Path:
    """Primitives of every type on a tight grid (many touching and overlapping), some turned,
    scaled, moving or given a collider shape, so that the bulk path and the body loop both
    build some."""
    rng = np.random.default_rng(3)
    bodies = []
    for i in range(n):
        kind = "ellipsoid" if i % 9 == 4 else ("sphere", "box", "capsule", "cylinder")[i % 4]
        r = float(rng.uniform(0.2, 0.45))
        primitive = {
            "sphere": {"type": "sphere", "radius": r},
            "box": {"type": "box", "size": [2 * r, 0.5, 0.7]},
            "capsule": {"type": "capsule", "radius": r / 2, "length": 0.5},
            "cylinder": {"type": "cylinder", "radius": r / 2, "length": 0.6},
            "ellipsoid": {"type": "ellipsoid", "semi_axes": [r, 0.3, 0.2]},
        }[kind]
        body: dict = {
            "name": f"{kind}{i}",
            "primitive": primitive,
            "position": [0.7 * (i % 5), 0.7 * (i // 5 % 4), 0.7 * (i // 20)],
        }
        if i % 3 == 0:
            body["rotation"] = {"quaternion": rng.normal(size=4).tolist()}
        if i % 7 == 0:
            body["scale"] = 1.5
        elif i % 8 == 0 or (kind == "ellipsoid" and i % 3 == 1):
            body["scale"] = [1.2, 0.8, 1.0]  # a sphere so scaled is an ellipsoid
        if i % 11 == 0:
            body["end_position"] = [0.7 * (i % 5) + 0.3, 0.0, 0.0]
        if i % 13 == 0:
            body["shape"] = "mesh"
        bodies.append(body)
    path = folder / "primitives.json"
    path.write_text(json.dumps({"units": "m", "duration": 1.0, "bodies": bodies}))
    return path


def tessellated(body: Body) -> Body:
    """The body with its tessellation made and given, as every primitive body was before."""
    return dataclasses.replace(body, vertices=body.vertices, faces=body.faces)


def no_tessellation(primitive):
    raise AssertionError(f"{primitive!r} tessellated")


def comparable(report) -> tuple:
    return report.bodies, report.pairs, report.summary | {"seconds": None}, report.warnings


@pytest.mark.parametrize("kind", ["manifest", "robot"])
def test_a_scene_of_primitives_is_checked_without_a_triangle(tmp_path, monkeypatch, kind):
    if kind == "manifest":
        path = manifest(tmp_path)
    else:
        path = tmp_path / "robot.urdf"
        path.write_text(URDF)
    options = CheckOptions(clearance=0.05)
    eager = load_inputs([path])
    eager_report = check_scene(
        dataclasses.replace(eager, bodies=tuple(tessellated(b) for b in eager.bodies)), options
    )
    types._tessellation.cache_clear()
    monkeypatch.setattr(types, "_tessellation", no_tessellation)
    scene = load_inputs([path])
    assert all(b.primitive is not None for b in scene.bodies)
    lazy_report = check_scene(scene, options)
    assert comparable(lazy_report) == comparable(eager_report)
    if kind == "manifest":  # the pairs' statuses all come out: nothing compared is empty
        statuses = {p["status"] for p in lazy_report.pairs}
        assert {"penetrating", "separated"} <= statuses, statuses
    else:
        assert [b["vertices"] for b in lazy_report.bodies] == [66, 8, 642]  # arm, base, tip


def test_the_tessellation_is_made_on_first_read_once_per_distinct_primitive():
    types._tessellation.cache_clear()
    bodies = [Body.of_primitive(f"b{i}", None, Capsule(0.5, 2.0)) for i in range(5)]
    other = Body.of_primitive("other", None, Sphere(1.0), pose=np.eye(4))
    assert types._tessellation.cache_info().misses == 0
    assert bodies[0].vertex_count == 1026  # known without tessellating
    assert types._tessellation.cache_info().misses == 0
    faces = bodies[0].faces  # the first read makes both arrays
    assert types._tessellation.cache_info().misses == 1
    v, f = primitive_mesh(Capsule(0.5, 2.0))
    assert np.array_equal(bodies[0].vertices, v) and np.array_equal(faces, f)
    for body in bodies[1:]:
        assert np.array_equal(body.vertices, v)
    assert types._tessellation.cache_info().misses == 1
    assert len(other.vertices) == other.vertex_count == 642
    assert types._tessellation.cache_info().misses == 2
    # each reader owns its arrays: writing one leaves the others and the cache as they were
    bodies[1].vertices[0] = 99.0
    assert np.array_equal(bodies[2].vertices, v)
    assert np.array_equal(primitive_mesh(Capsule(0.5, 2.0))[0], v)
    # frozen still, and a pickled body stays unmade until read
    with pytest.raises(dataclasses.FrozenInstanceError):
        bodies[3].vertices = v  # type: ignore[misc]
    fresh = Body.of_primitive("fresh", None, Box((1.0, 2.0, 3.0)))
    copy = pickle.loads(pickle.dumps(fresh))
    assert copy.__dict__["vertices"] is None
    assert np.array_equal(copy.vertices, primitive_mesh(Box((1.0, 2.0, 3.0)))[0])
    # a mesh body is as given
    mesh = Body("m", None, v, f)
    assert mesh.vertices is v and mesh.vertex_count == len(v)


def test_vertex_counts_are_the_tessellations_within_the_regular_lengths():
    rng = np.random.default_rng(11)
    low, high = REGULAR_LENGTHS
    edges = [low, high, 1.0]
    for k in range(40):
        a, b, c = (
            (edges[k % 3], edges[(k + 1) % 3], edges[(k + 2) % 3])
            if k < 6
            else np.exp(rng.uniform(np.log(low), np.log(high), 3)).tolist()
        )
        for primitive in (Sphere(a), Box((a, b, c)), Capsule(a, b), Cylinder(a, b)):
            count = len(primitive_mesh(primitive)[0])
            assert count == REGULAR_VERTEX_COUNTS[type(primitive)], primitive
            assert primitive_vertex_count(primitive) == count
    # beyond them the count is the tessellation's own (merged vertices and all)
    for primitive in (Capsule(1e-4, 1e-4), Cylinder(1e-9, 1.0), Capsule(1.0, 0.0)):
        assert primitive_vertex_count(primitive) == len(primitive_mesh(primitive)[0])
