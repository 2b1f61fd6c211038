"""dumps_json writes exactly what copying the report through _finite_or_none and encoding it
wrote (the one-pass encoder must not change a byte of any report): the core's encoder, and the
Python column encoder it falls back to; and the core's float text is repr(float)'s."""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Mapping

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from meshcol._native import core
from meshcol.io.report import _builtin, _dumps_json_python, dumps_json

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


def _finite_or_none(value):
    """The report as the two-pass encoding copied it: non-finite numbers None, numpy values
    Python ones, keys strings (JSON has no NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Mapping):
        return {str(k): _finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_none(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        return _finite_or_none(value.tolist())
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        return _finite_or_none(value.item())
    return value


def reference(obj):
    return json.dumps(_finite_or_none(obj), sort_keys=True, indent=2, allow_nan=False) + "\n"


@given(documents)
def test_dumps_json_matches_the_two_pass_encoding(obj):
    assert dumps_json(obj) == reference(obj)


@given(documents)
def test_the_python_fallback_matches_the_two_pass_encoding(obj):
    assert _dumps_json_python(obj) == reference(obj)


#: Floats whose text is easy to get wrong: the fixed/exponent switch at 1e-4 and 1e16, the
#: shortest digits (0.1 + 0.2), subnormals, the extremes, signed zero, integral values,
#: 17-digit values, three-digit exponents.
AWKWARD = [
    0.0, -0.0, 1.0, -1.0, 3.0, 1e-5, 1e-4, 0.0001234, 9.999999999999999e-05, 1e15, 1e16,
    9999999999999998.0, 1.2345678901234567e16, 123456789012345678.0, 1e22, 1e23, 0.1, 0.2,
    0.1 + 0.2, 1 / 3, 2 / 3, 5e-324, -5e-324, 2.2250738585072014e-308, 2.225073858507201e-308,
    1.7976931348623157e308, -1.7976931348623157e308, 1e300, 1e-300, 1.5e-7, 4.35, 0.5,
    2.0**53, 2.0**53 + 2, 2.0**-1074 * 3, 100.0, 1e-10, 123.456, math.pi, -math.e,
    float("nan"), float("inf"), float("-inf"),
]  # fmt: skip


def test_the_core_float_text_is_repr_on_awkward_values():
    assert core.float_reprs(np.array(AWKWARD)) == [repr(x) for x in AWKWARD]


@given(st.integers(0, 2**64 - 1))
def test_the_core_float_text_is_repr_on_every_bit_pattern(bits):
    (x,) = struct.unpack("<d", struct.pack("<Q", bits))
    assert core.float_reprs(np.array([x])) == [repr(x)]


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)))
def test_the_core_float_text_is_repr(values):
    assert core.float_reprs(np.array(values, dtype=np.float64)) == list(map(repr, values))


def test_awkward_floats_in_a_report_match_json():
    doc = {"values": AWKWARD, "rows": [{"x": x, "v": [x, -x]} for x in AWKWARD]}
    assert dumps_json(doc) == reference(doc)


class _Items(dict):
    def items(self):  # json's Python path sorts these; the core declines dict subclasses
        return sorted(super().items(), reverse=True)


class _Cycle:
    def tolist(self):
        return self  # never becomes plain: Python's encoder recurses until it gives up


@pytest.mark.parametrize(
    "doc",
    [
        {1: "a"},
        [{"k": 2**70}, {"k": -(2**64)}],
        _Items(b=1, a=2),
        {"s": "lone \ud800 surrogate"},
        {"deep": json.loads("[" * 450 + "]" * 450)},
    ],
    ids=["int key", "big int", "dict subclass", "lone surrogate", "deep"],
)
def test_documents_the_core_declines_go_to_python_and_match(doc):
    assert core.dumps_indented(doc, _builtin) is None
    assert dumps_json(doc) == _dumps_json_python(doc)


def test_what_neither_encoder_can_write_raises_as_before():
    with pytest.raises(TypeError, match="set is not JSON serializable"):
        dumps_json({"a": {1, 2}})
    with pytest.raises(RecursionError):
        dumps_json([_Cycle()])
    cyclic: list = []
    cyclic.append(cyclic)
    with pytest.raises((RecursionError, ValueError)):
        dumps_json(cyclic)


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


def test_an_error_other_than_not_serialisable_is_raised_once_never_swallowed() -> None:
    """A conversion that fails with anything but TypeError (an interrupt, a memory error)
    propagates from the core's encoder as it is: it is not taken for "not serialisable" and
    retried by the Python encoder (which, on a second call that happened to succeed, wrote a
    report after an interrupt)."""
    calls = []

    class Flaky:
        def tolist(self):
            calls.append(1)
            if len(calls) == 1:
                raise KeyboardInterrupt
            return [1.0]

    with pytest.raises(KeyboardInterrupt):
        dumps_json({"a": Flaky()})
    assert calls == [1]

    class Opaque:
        pass

    with pytest.raises(TypeError, match="Opaque is not JSON serializable"):
        dumps_json({"a": Opaque()})


# The same encoder for JSON inside other outputs (a JUnit property, the review page's data):
# one line, and the options that differ between them.


@given(documents)
def test_compact_text_is_the_two_pass_encoding_on_one_line(obj):
    expected = json.dumps(_finite_or_none(obj), sort_keys=True, separators=(",", ":"))
    assert dumps_json(obj, compact=True) == expected
    assert json.loads(dumps_json(obj, compact=True)) == json.loads(dumps_json(obj))


def test_the_options_that_differ_between_outputs():
    doc = {"b": "\u00e9", "a": [1.5, float("nan"), np.float32(np.inf)], "c": np.arange(2)}
    assert dumps_json(doc, compact=True) == '{"a":[1.5,null,null],"b":"\\u00e9","c":[0,1]}'
    assert dumps_json(doc, compact=True, ascii_only=False, sort_keys=False) == (
        '{"b":"\u00e9","a":[1.5,null,null],"c":[0,1]}'
    )
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        dumps_json(doc, compact=True, non_finite="error")
    plain = {"z": [1, 2.5, "x"], "a": None}
    assert dumps_json(plain, compact=True, sort_keys=False, non_finite="error") == json.dumps(
        plain, separators=(",", ":"), allow_nan=False
    )
    assert dumps_json(plain, sort_keys=False) == json.dumps(plain, indent=2) + "\n"
    with pytest.raises(ValueError, match="non_finite must be 'null' or 'error'"):
        dumps_json(plain, non_finite="nan")
