"""The one validator of scene manifests (meshcol.io.scene_validate) against JSON Schema: it
passes exactly what jsonschema passes (every number finite), and words every problem as
meshcol did when jsonschema decided (tests/scene_oracle.py, main ee068ea's code)."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scene_oracle import schema_message, schema_valid

from meshcol.errors import SceneError
from meshcol.io.scene_columns import columns
from meshcol.io.scene_schema import BODY_FIELDS, SCHEMA_PATH, SHAPES, TOP_FIELDS
from meshcol.io.scene_validate import first_problem, validate
from meshcol.vocabulary import SCENE_SHAPES


def _plainly_valid(document) -> bool:
    return first_problem(document) is None


def message(document) -> str | None:
    """What loading ``document`` says about it (None: valid)."""
    try:
        validate(document, "", "scene.json")
    except SceneError as error:
        return error.message
    return None


numbers = st.one_of(
    st.integers(-5, 5),
    st.floats(-5, 5, allow_nan=False),
    st.sampled_from([0, 0.0, -0.0, 1e300, math.inf, -math.inf, math.nan]),
)
json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), numbers, st.text(max_size=4)),
    lambda inner: st.one_of(
        st.lists(inner, max_size=5), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=8,
)
orders = st.sampled_from(["xyz", "zyx", "zxz", "xxy", "XYZ", ""])
rotations = st.one_of(
    st.fixed_dictionaries({"quaternion": st.lists(numbers, min_size=3, max_size=5)}),
    st.fixed_dictionaries(
        {"euler_deg": st.lists(numbers, min_size=2, max_size=4), "order": orders}
    ),
    st.fixed_dictionaries(
        {"quaternion": st.lists(numbers, min_size=4, max_size=4)},
        optional={"order": orders, "euler_deg": st.lists(numbers, min_size=3, max_size=3)},
    ),
)
primitives = st.fixed_dictionaries(
    {"type": st.sampled_from(["sphere", "box", "capsule", "cylinder", "ellipsoid", "cone", 3])},
    optional={
        "radius": numbers,
        "length": numbers,
        "size": st.lists(numbers, min_size=2, max_size=4),
        "semi_axes": st.lists(numbers, min_size=2, max_size=4),
    },
)
vectors = st.lists(numbers, min_size=2, max_size=4)
near_valid = {
    "name": st.one_of(st.text(max_size=3), st.integers()),
    "mesh": st.one_of(st.text(max_size=3), st.none()),
    "primitive": primitives,
    "position": vectors,
    "end_position": vectors,
    "velocity": vectors,
    "angular_velocity": vectors,
    "rotation": rotations,
    "end_rotation": rotations,
    "scale": st.one_of(numbers, st.lists(numbers, min_size=2, max_size=4)),
    "shape": st.sampled_from(["hull", "decomposed", "mesh", "convex", 1]),
}


valid_numbers = st.one_of(st.integers(-5, 5), st.floats(-5, 5, allow_nan=False))
positive = st.one_of(st.integers(1, 5), st.floats(1e-3, 5))
valid_rotations = st.one_of(
    st.fixed_dictionaries({"quaternion": st.lists(valid_numbers, min_size=4, max_size=4)}),
    st.fixed_dictionaries(
        {
            "euler_deg": st.lists(valid_numbers, min_size=3, max_size=3),
            "order": st.sampled_from(["xyz", "zyx", "zxz", "yzy"]),
        }
    ),
)
valid_vectors = st.lists(valid_numbers, min_size=3, max_size=3)
valid = {
    "position": valid_vectors,
    "end_position": valid_vectors,
    "velocity": valid_vectors,
    "angular_velocity": valid_vectors,
    "rotation": valid_rotations,
    "end_rotation": valid_rotations,
    "scale": st.one_of(positive, st.lists(positive, min_size=3, max_size=3)),
    "shape": st.sampled_from(["hull", "decomposed", "mesh"]),
}
valid_primitives = st.one_of(
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
def bodies(draw):
    """A valid body."""
    body = {"name": draw(st.text(min_size=1, max_size=3))}
    if draw(st.booleans()):
        body["mesh"] = draw(st.text(min_size=1, max_size=3))
    else:
        body["primitive"] = draw(valid_primitives)
    for field in sorted(draw(st.sets(st.sampled_from(sorted(valid)), max_size=4))):
        body[field] = draw(valid[field])
    return body


def mutate(draw, body, field=None):
    """One field of ``body`` replaced, added or removed."""
    if field is None:
        field = draw(st.sampled_from(sorted(near_valid) + ["colour"]))
    how = draw(st.integers(0, 3))
    if how == 0:
        body.pop(field, None)
    elif how == 1 or field == "colour":
        body[field] = draw(json_values)
    else:
        body[field] = draw(near_valid[field])


@st.composite
def documents(draw):
    document = {
        "bodies": draw(st.lists(bodies(), min_size=0 if draw(st.booleans()) else 1, max_size=3))
    }
    if draw(st.booleans()):
        document["units"] = draw(st.sampled_from(["m", "mm", "", 3]))
    if draw(st.booleans()):
        document["duration"] = draw(numbers)
    if document["bodies"] and draw(st.integers(0, 3)):
        mutate(draw, draw(st.sampled_from(document["bodies"])))
    if draw(st.integers(0, 9)) == 0:
        document[draw(st.text(max_size=3))] = draw(json_values)
    if draw(st.integers(0, 19)) == 0:
        return draw(json_values)
    return document


@given(documents())
def test_validation_passes_only_what_the_schema_passes(document):
    if _plainly_valid(document):
        assert schema_valid(document), document


@settings(max_examples=400)
@given(documents())
def test_every_message_is_the_one_jsonschema_gave(document):
    assert message(document) == schema_message(document), document


@pytest.mark.slow
@settings(max_examples=60)
@pytest.mark.parametrize("field", sorted(near_valid) + ["colour"])
@given(data=st.data())
def test_every_message_about_one_bad_field_is_the_one_jsonschema_gave(field, data):
    document = {"bodies": data.draw(st.lists(bodies(), min_size=1, max_size=2))}
    mutate(data.draw, document["bodies"][-1], field)
    if data.draw(st.booleans()):
        mutate(data.draw, document["bodies"][0])
    assert message(document) == schema_message(document), document


@pytest.mark.slow
@pytest.mark.parametrize("field", sorted(near_valid) + ["colour"])
@given(data=st.data())
def test_validation_passes_no_body_with_one_bad_field(field, data):
    document = {"bodies": data.draw(st.lists(bodies(), min_size=1, max_size=2))}
    mutate(data.draw, document["bodies"][0], field)
    if _plainly_valid(document):
        assert schema_valid(document), document


@settings(max_examples=300)
@given(documents())
def test_validation_passes_the_valid_documents(document):
    # Where jsonschema accepts a document, so does the validator.
    if schema_valid(document):
        assert _plainly_valid(document), document


def test_the_validator_knows_the_fields_of_the_schema():
    schema = json.loads(SCHEMA_PATH.read_text())
    assert set(schema["properties"]) == TOP_FIELDS
    assert set(schema["properties"]["bodies"]["items"]["properties"]) == BODY_FIELDS
    assert set(SCENE_SHAPES) == SHAPES


def test_a_typical_ten_thousand_body_manifest_is_valid():
    bodies = [
        {
            "name": f"prop{i}",
            "mesh": f"assets/a{i}.obj",
            "position": [i * 1.5, 0.0, 0.8],
            "rotation": {"euler_deg": [0.0, 0.0, 12.5], "order": "xyz"},
            "scale": [1, 2, 1.5],
            "shape": "hull",
        }
        for i in range(10_000)
    ]
    bodies.append({"name": "ball", "primitive": {"type": "sphere", "radius": 0.5}})
    document = {"units": "m", "bodies": bodies}
    assert _plainly_valid(document)
    assert columns(document) is not None  # the fast path: column by column
    bodies[5000]["position"] = [0.0, 0.0]
    assert not _plainly_valid(document)


@pytest.mark.parametrize(
    ("suffix", "text"),
    [
        (".json", '{"bodies": [{"name": "a", "mesh": "t.obj", "position": [0, 1e999, 0]}]}'),
        (".json", '{"bodies": [{"name": "a", "mesh": "t.obj", "position": [0, -1E+400, 0]}]}'),
        (".json", '{"bodies": [{"name": "a", "mesh": "t.obj", "position": [0, 0, -Infinity]}]}'),
        (
            ".json",
            '{"bodies": [{"name": "a", "mesh": "t.obj", "position": [0, 0, ' + "9" * 400 + ".5]}]}",
        ),
        (".toml", '[[bodies]]\nname = "a"\nmesh = "t.obj"\nposition = [0.0, 1e400, 0.0]\n'),
        (".toml", '[[bodies]]\nname = "a"\nmesh = "t.obj"\nposition = [0.0, -nan, 0.0]\n'),
        (
            ".toml",
            '[[bodies]]\nname = "a"\nmesh = "t.obj"\nposition = [0.0, '
            + "_".join(["999"] * 120)
            + ".0, 0.0]\n",
        ),
    ],
)
def test_every_spelling_of_a_non_finite_number_is_found(tmp_path, suffix, text):
    # Each spelling that parses to inf or nan is found (by the fast check's finiteness rule,
    # then the walk that names the field).
    from meshcol.errors import SceneError
    from meshcol.io.scene import load_scene

    path = tmp_path / f"scene{suffix}"
    path.write_text(text)
    with pytest.raises(SceneError, match="body 'a': position must be finite"):
        load_scene(path)


@pytest.mark.parametrize(
    "document",
    [
        None,
        [],
        {},
        {"bodies": [], "colour": 1},
        {"bodies": [3]},
        {"bodies": [{"name": "a", "mesh": "m"}, "b"], "units": ""},
        {"bodies": [{"mesh": "m", "primitive": {"type": "sphere", "radius": 1}}]},
        {"bodies": [{"name": "a", "mesh": "m", "colour": 1, "position": [0]}]},
        {"bodies": [{"name": "a", "primitive": {"type": "cone", "radius": -1}}]},
        {"bodies": [{"name": "a", "primitive": {"type": "sphere", "radius": 1, "size": [1]}}]},
        {"bodies": [{"name": "a", "primitive": {"type": "sphere", "foo": 1, "size": [1]}}]},
        {"bodies": [{"name": "a", "primitive": {"type": "capsule"}}]},
        {"bodies": [{"name": "a", "primitive": {"radius": 1}}]},
        {"bodies": [{"name": "a", "primitive": [1]}]},
        {"bodies": [{"name": "a", "mesh": "m", "rotation": {"euler_deg": [1, "a", 3]}}]},
        {
            "bodies": [
                {"name": "a", "mesh": "m", "rotation": {"euler_deg": [1, "a", 3], "order": "q"}}
            ]
        },
        {"bodies": [{"name": "a", "mesh": "m", "rotation": {"euler_deg": [1, 2], "order": 5}}]},
        {"bodies": [{"name": "a", "mesh": "m", "rotation": {"quaternion": [1], "order": "x"}}]},
        {"bodies": [{"name": "a", "mesh": "m", "end_rotation": {"axis": [1, 0, 0]}}]},
        {"bodies": [{"name": "a", "mesh": "m", "scale": {"quaternion": [1, 0, 0, 0]}}]},
        {"bodies": [{"name": "a", "mesh": "m", "scale": [1, 0, 1], "shape": "convex"}]},
        {"bodies": [{"name": "", "mesh": ""}], "duration": 0},
        {"bodies": [{"name": True, "mesh": "m", "velocity": [1, 2, True]}]},
        {"bodies": [{"name": "a", "mesh": "m"}], "duration": float("nan"), "units": 3},
    ],
)
def test_messages_of_chosen_documents_are_the_ones_jsonschema_gave(document):
    assert message(document) == schema_message(document)
