"""The hand-written fast check of scene manifests (meshcol.io.scene._plainly_valid) against
JSON Schema: it may send a valid document to jsonschema, never pass an invalid one."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol.io.scene import (
    _BODY_FIELDS,
    _TOP_FIELDS,
    SCHEMA_PATH,
    _first_non_finite,
    _plainly_valid,
    _validator,
)


def schema_valid(document) -> bool:
    """What the slow path accepts: every number finite and no jsonschema error."""
    return _first_non_finite(document) is None and not list(_validator().iter_errors(document))


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
    {"type": st.sampled_from(["sphere", "box", "capsule", "cylinder", "cone", 3])},
    optional={
        "radius": numbers,
        "length": numbers,
        "size": st.lists(numbers, min_size=2, max_size=4),
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
def test_fast_check_passes_only_what_the_schema_passes(document):
    if _plainly_valid(document):
        assert schema_valid(document), document


@pytest.mark.slow
@pytest.mark.parametrize("field", sorted(near_valid) + ["colour"])
@given(data=st.data())
def test_fast_check_passes_no_body_with_one_bad_field(field, data):
    document = {"bodies": data.draw(st.lists(bodies(), min_size=1, max_size=2))}
    mutate(data.draw, document["bodies"][0], field)
    if _plainly_valid(document):
        assert schema_valid(document), document


@settings(max_examples=300)
@given(documents())
def test_fast_check_passes_the_valid_common_documents(document):
    # Where jsonschema accepts a document, so does the fast path: a valid manifest never pays
    # for jsonschema.
    if schema_valid(document):
        assert _plainly_valid(document), document


def test_fast_check_knows_only_fields_of_the_schema():
    schema = json.loads(SCHEMA_PATH.read_text())
    assert set(schema["properties"]) >= _TOP_FIELDS
    assert set(schema["properties"]["bodies"]["items"]["properties"]) >= _BODY_FIELDS


def test_a_typical_ten_thousand_body_manifest_takes_the_fast_path():
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
