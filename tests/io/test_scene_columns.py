"""The manifest's column path (meshcol.io.scene_columns: validation, the magnitude check and
the bodies built in bulk) against the body-by-body path it stands in for: the same bodies to
the bit, the same first error, never a document the body-by-body check refuses."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from manifest_readers import python_reader
from test_scene_validation import bodies as valid_bodies
from test_scene_validation import documents, mutate, near_valid

from meshcol.errors import MeshcolError
from meshcol.io import scene_parse, scene_validate
from meshcol.io.scene import load_scene, rotation_from_euler, rotation_from_quaternion
from meshcol.io.scene_columns import columns as _columns
from meshcol.io.scene_columns import euler_matrices as _euler_matrices
from meshcol.io.scene_columns import quaternion_matrices as _quaternion_matrices
from meshcol.io.scene_validate import first_problem


def _plainly_valid_by_body(document) -> bool:
    return first_problem(document) is None


# --- validation -------------------------------------------------------------------------------


@given(documents())
def test_columns_pass_only_what_the_body_by_body_check_passes(document):
    if _columns(document) is not None:
        assert _plainly_valid_by_body(document), document


@given(data=st.data())
def test_columns_pass_no_body_with_one_bad_field(data):
    document = {"bodies": data.draw(st.lists(valid_bodies(), min_size=1, max_size=3))}
    field = data.draw(st.sampled_from(sorted(near_valid) + ["colour"]))
    mutate(data.draw, document["bodies"][-1], field)
    if _columns(document) is not None:
        assert _plainly_valid_by_body(document), document


@pytest.mark.slow
@given(st.lists(valid_bodies(), min_size=1, max_size=4))
def test_columns_pass_every_valid_body_of_ordinary_numbers(bodies):
    document = {"bodies": bodies}
    assert _plainly_valid_by_body(document)
    assert _columns(document) is not None, document


def test_numbers_beyond_a_double_are_left_to_the_body_by_body_check():
    document = {"bodies": [{"name": "a", "mesh": "a.obj", "position": [2**1100, 0, 0]}]}
    assert _columns(document) is None
    assert _plainly_valid_by_body(document)  # valid; the magnitude check refuses it later


# --- rotations in bulk ------------------------------------------------------------------------

quaternions = st.lists(
    st.one_of(
        st.floats(-1e300, 1e300, allow_nan=False),
        st.sampled_from([0.0, -0.0, 1.0, 0.5, 1e-300, 5e-324, 1e308, -1e308]),
        st.integers(-3, 3),
    ),
    min_size=4,
    max_size=4,
).filter(lambda q: any(q))


@given(st.lists(quaternions, min_size=1, max_size=8))
def test_quaternions_in_bulk_are_the_same_bits(rows):
    bulk = _quaternion_matrices(np.array(rows, dtype=np.float64))
    for row, matrix in zip(rows, bulk):
        assert matrix.tobytes() == rotation_from_quaternion(row).tobytes()


angles = st.one_of(
    st.floats(-1e4, 1e4, allow_nan=False),
    st.sampled_from([0, 90, -90, 180, 270, 360, -720, 45, 1e-300]),
)
orders = st.sampled_from(["xyz", "zyx", "zxz", "yxy", "xzy", "yzx", "zyz"])


@given(st.lists(st.tuples(st.lists(angles, min_size=3, max_size=3), orders), min_size=1))
def test_euler_angles_in_bulk_are_the_same_bits(rows):
    bulk = _euler_matrices(np.array([a for a, _ in rows], dtype=np.float64), [o for _, o in rows])
    for (row, order), matrix in zip(rows, bulk):
        assert matrix.tobytes() == rotation_from_euler(row, order).tobytes()


# --- the whole load ---------------------------------------------------------------------------

TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
ASSETS = {
    "tet.obj": TET,
    "far.obj": TET.replace("v 1 0 0", "v 6e9 0 0"),  # within the limit alone, not moved far
    "pair.obj": "o left\n" + TET + "o right\nv 2 0 0\nv 3 0 0\nv 2 1 0\nv 2 0 1\n"
    "f 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n",
    "broken.obj": "v 0 0 0\nf 1 2 3\n",
}
MESHES = [*ASSETS, "missing.obj"]


def load_both(folder: Path, document) -> tuple:
    """What load_scene gives (bodies, or the error line) with the column path and without."""
    path = folder / "scene.json"
    path.write_text(json.dumps(document))
    out = []
    for columns in (_columns, lambda document: None):
        forget()
        scene_validate.columns = columns
        try:
            with python_reader():  # the native reader: tests/io/test_scene_native.py
                out.append(describe(load_scene(path)))
        except MeshcolError as error:
            out.append(str(error))
        finally:
            scene_validate.columns = _columns
    forget()
    return tuple(out)


def forget() -> None:
    """Drop the manifest read and assessed last (so the next load reads and checks anew)."""
    scene_parse._READ.clear()
    scene_validate._LAST[:] = [object(), None, None]


def describe(scene) -> list:
    def bits(a):
        return None if a is None else (a.dtype.str, a.shape, a.tobytes())

    return [
        (
            b.name,
            b.source,
            bits(b.vertices),
            bits(b.faces),
            bits(b.pose),
            bits(b.end_pose),
            None if b.spin is None else (bits(b.spin.rotation), bits(b.spin.pivot)),
            repr(b.primitive),
            b.collider,
            b.parts,
            bits(b.part_faces),
        )
        for b in scene.bodies
    ]


@pytest.fixture(scope="module")
def assets(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("columns")
    for name, text in ASSETS.items():
        (folder / name).write_text(text)
    return folder


numbers = st.one_of(
    st.integers(-5, 5),
    st.floats(-50, 50, allow_nan=False),
    st.sampled_from([6e9, -1e10, 1e10 + 1, 2e10, 1e-11, 0.0]),
)
vector = st.lists(numbers, min_size=3, max_size=3)
rotation = st.one_of(
    st.fixed_dictionaries({"quaternion": st.lists(numbers, min_size=4, max_size=4)}),
    st.fixed_dictionaries(
        {"euler_deg": st.lists(numbers, min_size=3, max_size=3), "order": orders}
    ),
)
positive = st.one_of(st.sampled_from([1, 1.0, 2, 0.5, 1e-11, 3e9]), st.floats(0.01, 10))
optional = {
    "position": vector,
    "rotation": rotation,
    "scale": st.one_of(positive, st.lists(positive, min_size=3, max_size=3)),
    "end_position": vector,
    "velocity": vector,
    "angular_velocity": vector,
    "end_rotation": rotation,
    "shape": st.sampled_from(["hull", "mesh", "decomposed"]),
}


primitives = st.one_of(
    st.fixed_dictionaries({"type": st.just("sphere"), "radius": positive}),
    st.fixed_dictionaries(
        {"type": st.just("box"), "size": st.lists(positive, min_size=3, max_size=3)}
    ),
    st.fixed_dictionaries(
        {"type": st.sampled_from(["capsule", "cylinder"]), "radius": positive, "length": positive}
    ),
    st.fixed_dictionaries(
        {"type": st.just("ellipsoid"), "semi_axes": st.lists(positive, min_size=3, max_size=3)}
    ),
)


@st.composite
def manifests(draw):
    names = st.sampled_from(["a", "b", "c", "d", "e", "f", "g", "h"])
    bodies = []
    for _ in range(draw(st.integers(1, 8))):
        body = {"name": draw(names)}
        if draw(st.integers(0, 5)):
            body["mesh"] = draw(st.sampled_from(MESHES[:1] * 4 + MESHES))
        else:
            body["primitive"] = draw(primitives)
        for field in draw(st.sets(st.sampled_from(sorted(optional)), max_size=3)):
            body[field] = draw(optional[field])
        bodies.append(body)
    document = {"bodies": bodies}
    if draw(st.booleans()):
        document["duration"] = draw(st.sampled_from([1, 0.5, 1e6]))
    return document


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(manifests())
def test_the_column_path_loads_what_the_body_by_body_path_loads(assets, document):
    with_columns, without = load_both(assets, document)
    assert with_columns == without


def test_a_large_manifest_loads_the_same_either_way(assets):
    rng = np.random.default_rng(7)
    bodies = []
    for i in range(600):
        body = {"name": f"b{i}", "mesh": ["tet.obj", "pair.obj", "far.obj"][i % 3]}
        if i % 4 == 0:
            body["rotation"] = {"quaternion": rng.normal(size=4).tolist()}
        elif i % 4 == 1:
            body["rotation"] = {"euler_deg": rng.uniform(-400, 400, 3).tolist(), "order": "zxz"}
        elif i % 4 == 2:
            body["rotation"] = {"euler_deg": [90, 0, -180], "order": "xyz"}
        body["position"] = rng.uniform(-100, 100, 3).tolist()
        if i % 7 == 0:
            body["scale"] = [1, 2, 1]
        bodies.append(body)
    with_columns, without = load_both(assets, {"bodies": bodies})
    assert isinstance(with_columns, list) and len(with_columns) == 600
    assert with_columns == without


def test_the_first_error_in_manifest_order_is_the_one_reported(assets):
    bodies = [{"name": f"b{i}", "mesh": "tet.obj", "position": [i, 0, 0]} for i in range(50)]
    bodies[30]["rotation"] = {"quaternion": [0, 0, 0, 0]}
    bodies[40]["name"] = "b3"
    with_columns, without = load_both(assets, {"bodies": bodies})
    assert with_columns == without
    assert with_columns.endswith("body 'b30': rotation.quaternion must be non-zero")
    bodies[30]["rotation"] = {"quaternion": [1, 0, 0, 0]}
    bodies[20]["mesh"] = "far.obj"
    bodies[20]["position"] = [6e9, 0, 0]
    with_columns, without = load_both(assets, {"bodies": bodies})
    assert with_columns == without
    assert "body 'b20'" in with_columns and "limit" in with_columns
    bodies[20]["position"] = [0, 0, 0]
    with_columns, without = load_both(assets, {"bodies": bodies})
    assert with_columns == without
    assert with_columns.endswith("body 'b3': name used by an earlier body")


@pytest.mark.parametrize(
    "primitive",
    [
        {"type": "sphere", "radius": 2},
        {"type": "box", "size": [1, 2.5, 3]},
        {"type": "capsule", "radius": 0.5, "length": 1},
        {"type": "cylinder", "radius": 0.5, "length": 1e-300},
        {"type": "sphere", "radius": 0},
        {"type": "sphere", "radius": -1.0},
        {"type": "sphere", "radius": True},
        {"type": "sphere", "radius": "1"},
        {"type": "sphere", "radius": float("nan")},
        {"type": "sphere", "radius": 10**400},
        {"type": "sphere", "radius": 1, "length": 1},
        {"type": "sphere", "size": 1},
        {"type": "capsule", "radius": 1},
        {"type": "capsule", "radius": 1, "size": 1},
        {"type": "cylinder", "radius": 1, "length": 0},
        {"type": "ellipsoid", "semi_axes": [0.5, 2, 1e-300]},
        {"type": "ellipsoid", "semi_axes": [1, 0, 1]},
        {"type": "ellipsoid", "semi_axes": [1, 2]},
        {"type": "ellipsoid", "semi_axes": [1, 2, True]},
        {"type": "ellipsoid", "size": [1, 2, 3]},
        {"type": "ellipsoid", "semi_axes": [1, 2, 3], "radius": 1},
        {"type": "box", "semi_axes": [1, 2, 3]},
        {"type": "box", "size": [1, 2]},
        {"type": "box", "size": [1, 0, 2]},
        {"type": "box", "size": [1, 2, False]},
        {"type": "box", "size": (1, 2, 3)},
        {"type": "cone", "radius": 1},
        {"type": 1, "radius": 1},
        {"radius": 1},
        [1, 2, 3],
    ],
)
def test_the_columns_take_a_primitive_exactly_when_the_body_check_does(primitive) -> None:
    from meshcol.io.scene_columns import columns
    from meshcol.io.scene_schema import PRIMITIVE_TYPES, is_primitive

    good = {"type": "box", "size": [1.0, 2.0, 3.0]}
    document = {
        "bodies": [
            {"name": "a", "primitive": {"type": "sphere", "radius": 0.5}},
            {"name": "b", "primitive": primitive, "position": [1, 2, 3]},
            {"name": "c", "primitive": good},
        ]
    }
    found = columns(document)
    plain = is_primitive(primitive) and abs(primitive.get("radius", 1)) < 1e300
    assert (found is not None) == plain
    if found is not None:
        p = primitive
        triple = {"box": "size", "ellipsoid": "semi_axes"}.get(p["type"])
        row = p[triple] if triple else [p["radius"], p.get("length", 0.0), 0.0]
        assert found.primitive_lengths.tolist() == [[0.5, 0, 0], row, [1.0, 2.0, 3.0]]
        assert found.primitive_type.tolist() == [
            PRIMITIVE_TYPES.index(t) for t in ("sphere", p["type"], "box")
        ]
