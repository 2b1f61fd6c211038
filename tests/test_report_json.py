"""dumps_json writes exactly what copying the report through _finite_or_none and encoding it
wrote (the one-pass encoder must not change a byte of any report)."""

from __future__ import annotations

import json

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from meshcol.io.report import _finite_or_none, dumps_json

floats = st.floats(allow_nan=True, allow_infinity=True)
tricky_text = st.one_of(
    st.text(max_size=8),
    st.sampled_from(["NaN", '": NaN', 'a": NaN', "Infinity,", "-Infinity", "x\nNaN", " NaN"]),
)
leaves = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    floats,
    tricky_text,
    floats.map(np.float64),
    st.integers(-100, 100).map(np.int64),
    st.booleans().map(np.bool_),
    st.lists(floats, max_size=4).map(lambda v: np.array(v, dtype=np.float64)),
    st.lists(st.integers(-9, 9), max_size=4).map(lambda v: np.array(v, dtype=np.int32)),
)
values = st.recursive(
    leaves,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.lists(inner, max_size=3).map(tuple),
        st.dictionaries(tricky_text, inner, max_size=4),
    ),
    max_leaves=20,
)


# Rows of one shape, as reports hold them (pairs, bodies): the encoder writes them column by
# column, so they need their own cases (random dicts almost never share their keys).
row_keys = st.lists(tricky_text, min_size=1, max_size=4, unique=True)
vectors = st.one_of(st.none(), st.lists(floats, max_size=3), st.lists(st.integers(), max_size=3))
cells = st.one_of(leaves, vectors, st.lists(vectors, max_size=2).map(tuple), values)
tables = row_keys.flatmap(
    lambda keys: st.lists(st.fixed_dictionaries(dict.fromkeys(keys, cells)), min_size=1, max_size=6)
)
documents = st.one_of(values, tables, st.dictionaries(tricky_text, tables, max_size=3))


def reference(obj):
    return json.dumps(_finite_or_none(obj), sort_keys=True, indent=2, allow_nan=False) + "\n"


@given(documents)
def test_dumps_json_matches_the_two_pass_encoding(obj):
    assert dumps_json(obj) == reference(obj)


def test_dumps_json_writes_null_for_non_finite_fields_and_items():
    obj = {"d": float("nan"), "n": np.array([1.0, np.inf, -np.inf]), "s": "NaN", "k": [np.nan]}
    text = dumps_json(obj)
    assert json.loads(text) == {"d": None, "n": [1.0, None, None], "s": "NaN", "k": [None]}
    assert text == reference(obj)


def test_rows_of_one_shape_match_json_with_percent_keys_and_ragged_vectors():
    rows = [
        {"%s": 1.5, "v": [1.0, float("nan")], "w": None, "t": ("a", "b,c"), "%%": {"k": []}},
        {"%s": None, "v": [], "w": [[0.1, 2], []], "t": (), "%%": {"k": [np.inf]}},
        {"%s": -0.0, "v": [3], "w": [True, None], "t": ("\u00e9",), "%%": {"j": 1}},
    ]
    assert dumps_json({"rows": rows, "empty": [{}, {}]}) == reference(
        {"rows": rows, "empty": [{}, {}]}
    )


def test_non_string_keys_are_left_to_json():
    obj = [{1: "a"}, {1: "b"}]
    assert dumps_json(obj) == json.dumps(obj, sort_keys=True, indent=2) + "\n"
