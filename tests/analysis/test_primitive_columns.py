"""A manifest of primitives kept as columns (issue 32, item 4): no Body or Primitive object per
body from the manifest to the report, and the same report, to the byte, as the bodies built
one by one (the object path) on manifests of every primitive type, turned by quaternions and
Euler angles, with collider shapes, excluded pairs and an ignore policy; bad values are the
same one-line errors."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st
from manifest_readers import python_reader

import meshcol.io.scene_validate as scene_validate
from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.analysis.colliders import build_colliders
from meshcol.analysis.primitive_colliders import primitive_colliders
from meshcol.cli import main
from meshcol.collision.shapes import ConvexSet, ShapeKind
from meshcol.errors import SceneError
from meshcol.io import scene_parse
from meshcol.io.column_bodies import body_names, vertex_counts
from meshcol.io.scene import load_scene
from meshcol.io.scene_primitives import PrimitiveBodies
from meshcol.types import Cylinder, primitive_vertex_count

KINDS = ("sphere", "box", "capsule", "cylinder", "ellipsoid")


def primitive(kind: str, r: float) -> dict:
    return {
        "sphere": {"type": "sphere", "radius": r},
        "box": {"type": "box", "size": [2 * r, 0.5, 0.7]},
        "capsule": {"type": "capsule", "radius": r / 2, "length": 0.5},
        "cylinder": {"type": "cylinder", "radius": r / 2, "length": 0.6},
        "ellipsoid": {"type": "ellipsoid", "semi_axes": [r, 0.3, 0.2]},
    }[kind]


def document(n: int = 64, seed: int = 3) -> dict:
    """Primitives of every type on a tight grid (touching, overlapping, apart, one inside
    another), turned by quaternions and Euler angles, some with a collider shape."""
    rng = np.random.default_rng(seed)
    bodies = []
    for i in range(n):
        kind = "ellipsoid" if i % 8 == 7 else KINDS[i % 4]
        body: dict = {
            "name": f"{kind}{i:03d}",
            "primitive": primitive(kind, float(rng.uniform(0.2, 0.45))),
            "position": [0.7 * (i % 5), 0.7 * (i // 5 % 4), 0.7 * (i // 20)],
        }
        if i % 3 == 0:
            body["rotation"] = {"quaternion": rng.normal(size=4).tolist()}
        elif i % 3 == 1:
            body["rotation"] = {"euler_deg": rng.uniform(-200, 200, 3).tolist(), "order": "zyx"}
        if i % 13 == 0:
            body["shape"] = "mesh"
        bodies.append(body)
    # a small ball inside a big one: the containment test reads two bodies' triangles
    bodies.append({"name": "big", "primitive": primitive("sphere", 1.0), "position": [9, 9, 9]})
    bodies.append({"name": "small", "primitive": primitive("sphere", 0.1), "position": [9, 9, 9]})
    return {"units": "m", "bodies": bodies}


def forget() -> None:
    """Drop the manifest read and assessed last (the next load reads and checks anew)."""
    scene_parse._READ.clear()
    scene_validate._LAST[:] = [object(), None, None]


def load_both(path: Path):
    """The scene as columns, and the scene built body by body (the columns switched off);
    both by the Python reader (tests/io/test_scene_native.py holds the native one to it)."""
    forget()
    with python_reader():
        columns = load_scene(path)
    original = scene_validate.columns
    forget()
    scene_validate.columns = lambda document: None
    try:
        with python_reader():
            objects = load_scene(path)
    finally:
        scene_validate.columns = original
        forget()
    return columns, objects


CLOCKS = re.compile(r'("generated_at"|"seconds"|"load_seconds"): [^,\n]*')


def report_text(scene, options: CheckOptions) -> str:
    return CLOCKS.sub(r"\1: 0", check_scene(scene, options).to_json())


def write(folder: Path, doc: dict) -> Path:
    path = folder / "scene.json"
    path.write_text(json.dumps(doc))
    return path


def test_a_manifest_of_primitives_is_checked_as_columns_to_the_same_bytes(tmp_path):
    columns, objects = load_both(write(tmp_path, document()))
    assert isinstance(columns.bodies, PrimitiveBodies)
    assert isinstance(objects.bodies, tuple)
    assert body_names(columns.bodies) == [b.name for b in objects.bodies]
    pairs = (("box001", "capsule002", "adjacent"), ("big", "small", "nested"))
    for options in (
        CheckOptions(),
        CheckOptions(clearance=0.3, tolerance=1e-3, ignore=("sphere000:*",)),
    ):
        for excluded in ((), pairs):
            a = dataclasses.replace(columns, excluded_pairs=excluded)
            b = dataclasses.replace(objects, excluded_pairs=excluded)
            text = report_text(a, options)
            assert text == report_text(b, options)
            report = json.loads(text)
            statuses = {p["status"] for p in report["pairs"]}
            assert {"penetrating", "separated"} <= statuses, statuses
            assert ("contained" in statuses) == (not excluded)  # big and small: excluded
            assert (report["summary"]["excluded_pairs"] > 0) == bool(excluded)
    # the check made no Body but the two it measured on their triangles (the nested pair)
    made = sorted(columns.bodies[i].name for i in columns.bodies._made)
    assert made == ["big", "small"]


def test_the_packed_colliders_are_the_object_paths_array_for_array(tmp_path):
    columns, objects = load_both(write(tmp_path, document()))
    fast = primitive_colliders(columns.bodies)
    slow = build_colliders(objects.bodies)
    assert fast is not None
    for name in (*ConvexSet._FIELDS, "hull_status"):
        x, y = getattr(fast.shapes, name), getattr(slow.shapes, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), name
    for name in ("part_body", "part_index", "body_part_offsets", "part_label"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name
    assert fast.kinds == slow.kinds and fast.warnings == slow.warnings
    assert fast.part_offsets is None and slow.part_offsets is None
    assert fast.part_poses().tobytes() == slow.part_poses().tobytes()
    assert fast.part_poses(end=True).tobytes() == slow.part_poses(end=True).tobytes()
    # bodies made on demand are the object path's, to the bit
    for i in (0, 1, 2, 3, 5, -1):
        x, y = columns.bodies[i], objects.bodies[i]
        assert (x.name, x.source, x.primitive, x.collider) == (
            y.name,
            y.source,
            y.primitive,
            y.collider,
        )
        assert x.pose.tobytes() == y.pose.tobytes() and x.end_pose is None
        assert x.vertices.tobytes() == y.vertices.tobytes()
    assert [b.name for b in columns.bodies[1:4]] == [b.name for b in objects.bodies[1:4]]
    with pytest.raises(IndexError):
        columns.bodies[len(objects.bodies)]


def test_vertex_counts_need_no_tessellation_within_the_regular_lengths(tmp_path):
    doc = document(8)
    doc["bodies"][0]["primitive"] = {"type": "cylinder", "radius": 1e-9, "length": 1}
    doc["bodies"][1]["primitive"] = {"type": "box", "size": [1e-4, 1, 1]}
    doc["bodies"][2]["primitive"] = {"type": "capsule", "radius": 1e-4, "length": 1e-4}
    columns, objects = load_both(write(tmp_path, doc))
    assert isinstance(columns.bodies, PrimitiveBodies)
    expected = [b.vertex_count for b in objects.bodies]
    assert vertex_counts(columns.bodies).tolist() == expected
    assert expected[0] == primitive_vertex_count(Cylinder(1e-9, 1.0)) == 2  # merged vertices
    assert not columns.bodies._made


@pytest.mark.parametrize(
    "change",
    [
        {"scale": 2.0},  # scaled: the body loop scales it
        {"end_position": [0, 0, 1]},  # moving
        {"scale": [1, 2, 1]},  # a box scaled along one axis
    ],
)
def test_other_manifests_take_the_object_path(tmp_path, change):
    doc = document(8)
    doc["bodies"][5].update(change)
    columns, objects = load_both(write(tmp_path, doc))
    assert isinstance(columns.bodies, tuple)
    options = CheckOptions(clearance=0.1)
    assert report_text(columns, options) == report_text(objects, options)


def test_a_repeated_name_is_the_body_loops_error(tmp_path):
    doc = document(8)
    doc["bodies"][4]["name"] = "box001"
    forget()
    with pytest.raises(SceneError, match="body 'box001': name used by an earlier body"):
        load_scene(write(tmp_path, doc))


def test_mesh_bodies_among_primitives_take_the_object_path(tmp_path):
    doc = document(8)
    (tmp_path / "tet.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    doc["bodies"].append({"name": "tet", "mesh": "tet.obj", "position": [0.2, 0.2, 0.2]})
    columns, objects = load_both(write(tmp_path, doc))
    assert isinstance(columns.bodies, tuple)
    assert report_text(columns, CheckOptions()) == report_text(objects, CheckOptions())


def test_unreal_collision_names_are_matched_by_the_object_path(tmp_path):
    doc = document(8)
    doc["bodies"][5]["name"] = "UCX_box001_00"
    columns, objects = load_both(write(tmp_path, doc))
    assert isinstance(columns.bodies, PrimitiveBodies)
    assert primitive_colliders(columns.bodies) is None
    assert report_text(columns, CheckOptions()) == report_text(objects, CheckOptions())


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"type": "sphere", "radius": -1}, "body 'sphere004': primitive.radius must be"),
        ({"type": "box", "size": [1, 0, 1]}, "body 'sphere004': primitive.size must be"),
        ({"type": "capsule", "radius": 1}, "body 'sphere004': missing field 'primitive.length'"),
        ({"type": "sphere", "radius": 2e10}, "body 'sphere004': primitive.radius 2e+10 is beyond"),
    ],
)
def test_bad_values_are_one_line_naming_the_file_and_the_body(tmp_path, spec, message):
    doc = document(8)
    doc["bodies"][4]["primitive"] = spec
    path = write(tmp_path, doc)
    forget()
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.output
    assert str(path) in lines[0] and message in lines[0], lines[0]


def test_a_zero_quaternion_is_an_error_naming_the_body(tmp_path):
    doc = document(8)
    doc["bodies"][6]["rotation"] = {"quaternion": [0, 0, 0, 0]}
    forget()
    result = CliRunner().invoke(main, ["check", str(write(tmp_path, doc))])
    assert result.exit_code == 2
    assert "body 'capsule006': rotation.quaternion must be non-zero" in result.stderr


def test_primitive_arrays_are_checked():
    with pytest.raises(ValueError, match="params must be"):
        ConvexSet.from_primitives([ShapeKind.SPHERE], np.zeros((2, 4)))
    with pytest.raises(ValueError, match="primitive shape kinds"):
        ConvexSet.from_primitives([ShapeKind.POLYTOPE], np.zeros((1, 4)))
    with pytest.raises(ValueError, match="finite"):
        ConvexSet.from_primitives([ShapeKind.BOX], [[1.0, np.nan, 1.0, 0.0]])
    shapes = ConvexSet.from_primitives([ShapeKind.CAPSULE], [[0.5, 1.0, 0.0, 0.0]])
    assert len(shapes) == 1 and shapes.primitive(0) is not None


lengths = st.floats(0.05, 1.5)
bodies_strategy = st.lists(
    st.tuples(
        st.sampled_from(KINDS),
        lengths,
        st.lists(st.floats(-2, 2), min_size=3, max_size=3),
        st.one_of(
            st.none(),
            st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
                lambda q: max(map(abs, q)) > 1e-3
            ),
        ),
    ),
    min_size=2,
    max_size=12,
)


@settings(max_examples=25, deadline=None)
@given(bodies_strategy, st.floats(0.0, 0.5))
def test_random_primitive_manifests_give_the_object_paths_report(tmp_path_factory, bodies, gap):
    doc = {"bodies": []}
    for i, (kind, r, position, quaternion) in enumerate(bodies):
        body: dict = {"name": f"b{i}", "primitive": primitive(kind, r), "position": position}
        if quaternion is not None:
            body["rotation"] = {"quaternion": quaternion}
        doc["bodies"].append(body)
    columns, objects = load_both(write(tmp_path_factory.mktemp("random"), doc))
    assert isinstance(columns.bodies, PrimitiveBodies)
    options = CheckOptions(clearance=gap)
    assert report_text(columns, options) == report_text(objects, options)


def test_bodies_of_one_part_pair_as_their_parts_do(tmp_path):
    from meshcol.analysis.pairs import broad_phase, place

    columns, _ = load_both(write(tmp_path, document()))
    placed = place(primitive_colliders(columns.bodies))
    margin = 0.2
    table = broad_phase(placed, margin, (("box001", "capsule002", "adjacent"),))
    lo, hi = placed.body_min - margin / 2, placed.body_max + margin / 2
    a, b = np.triu_indices(len(lo), 1)
    meet = np.all((lo[a] <= hi[b]) & (lo[b] <= hi[a]), axis=1)
    names = body_names(columns.bodies)
    excluded = {(names.index("box001"), names.index("capsule002"))}
    expected = [
        (i, j) for i, j in zip(a[meet].tolist(), b[meet].tolist()) if (i, j) not in excluded
    ]
    found = list(zip(table.body_a.tolist(), table.body_b.tolist()))
    assert sorted(found) == expected and len(found) > 50
    assert table.part_pairs.tolist() == [list(p) for p in found]  # each body's one part
    assert table.part_row.tolist() == list(range(len(found)))
    assert table.excluded_pairs == 1
