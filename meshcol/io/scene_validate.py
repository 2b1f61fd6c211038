"""The one validation of a scene manifest: its structure (``schemas/scene.schema.json``) and
its magnitudes, each problem one :class:`meshcol.errors.SceneError` line naming the manifest,
the body and the field.

The common manifest passes column by column (:func:`meshcol.io.scene_columns.columns`, C loops
over 300,000 bodies); any other document is checked body by body here, by the same rules
(:mod:`meshcol.io.scene_schema`), and its first problem worded. "First" is JSON Schema's order
as meshcol has always reported it: problems of the manifest itself (unknown fields, then a
missing ``bodies``), then the first body with a problem (its unknown fields, a missing
``name``, then "exactly one of mesh or primitive", then its fields by name), then
``duration``, then ``units``. Before any of them: a document nested too deep, then the first
non-finite number. ``tests/test_scene_validation.py`` holds every message to the one
jsonschema words on generated documents.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from meshcol.errors import SceneError
from meshcol.io.mesh_read import MAX_COORDINATE
from meshcol.io.scene_columns import Columns, columns, near_limits
from meshcol.io.scene_parse import (
    KEPT_OF_DOCUMENTS,
    MAX_NESTING,
    first_non_finite,
    nesting,
    too_deep,
)
from meshcol.io.scene_schema import (
    BODY_FIELDS,
    EXPECTED,
    MAX_TURN,
    ORDERS,
    PRIMITIVE_FIELDS,
    PRIMITIVE_KEYS,
    PRIMITIVE_REQUIRED,
    PRIMITIVE_TYPES,
    ROTATION_FIELDS,
    SHAPES,
    TOP_FIELDS,
    VECTOR_FIELDS,
    is_numbers,
    is_positive,
    is_primitive,
    is_rotation,
    is_scale,
)

__all__ = ["check_magnitudes", "check_nesting", "document_columns", "first_problem", "validate"]

# How problems at one place rank (JSON Schema's validators as meshcol orders them).
_UNKNOWN, _MISSING, _OTHER = 0, 1, 2

#: A problem: the path to the value (keys and indices), its rank there, its message.
Problem = tuple[list, int, str]


def _non_empty_string(x: Any) -> bool:
    return type(x) is str and bool(x)


def _is_vector(x: Any) -> bool:
    return is_numbers(x, 3)


def _is_shape(x: Any) -> bool:
    return type(x) is str and x in SHAPES


#: The rule of each body field: what its value must be.
FIELD_RULES: dict[str, Callable[[Any], bool]] = {
    "name": _non_empty_string,
    "mesh": _non_empty_string,
    "primitive": is_primitive,
    **dict.fromkeys(VECTOR_FIELDS, _is_vector),
    **dict.fromkeys(ROTATION_FIELDS, is_rotation),
    "scale": is_scale,
    "shape": _is_shape,
}
if FIELD_RULES.keys() != BODY_FIELDS:  # pragma: no cover - a field added to the schema alone
    raise ImportError(f"scene fields without a rule: {sorted(BODY_FIELDS ^ FIELD_RULES.keys())}")


def validate(document: Any, text: str, source: str) -> Columns | None:
    """Raise SceneError for the first problem of ``document`` (the manifest ``source``, whose
    text is ``text``); else its columns (None: it takes the body-by-body path)."""
    found, problem = _assess(document)
    if problem is None:
        return found
    check_nesting(document, text, source)
    where = first_non_finite(document)
    if where is not None:
        raise SceneError(f"{describe(document, where)} must be finite", source)
    raise SceneError(problem, source)


def check_nesting(document: Any, text: str, source: str) -> None:
    """Raise SceneError when an invalid ``document`` nests deeper than :data:`MAX_NESTING`
    (a valid one is at most five levels deep: only another needs the walk)."""
    if _assess(document)[1] is not None and nesting(document) > MAX_NESTING:
        raise SceneError(too_deep(text), source)


def document_columns(document: Any) -> Columns | None:
    """The columns of a plainly valid ``document`` (:func:`validate`'s), else None; assessed
    once per document."""
    return _assess(document)[0]


# The last document assessed (by identity), its columns and its first problem: the output
# check and the loading of one run both ask.
_LAST: list[Any] = [object(), None, None]
KEPT_OF_DOCUMENTS.append(lambda: _LAST.__setitem__(slice(None), [object(), None, None]))


def _assess(document: Any) -> tuple[Columns | None, str | None]:
    if _LAST[0] is not document:
        found = columns(document)
        _LAST[:] = [document, found, None if found is not None else first_problem(document)]
    return _LAST[1], _LAST[2]


def first_problem(document: Any) -> str | None:
    """The message of the first problem of ``document``'s structure, or None when it is valid
    under the scene schema with every number finite."""
    problems = _top_problems(document)
    if not problems:
        return None
    # first by path (indices before names, names alphabetically), then by rank; ties: the
    # first found
    return min(problems, key=lambda p: ([_step(s) for s in p[0]], p[1]))[2]


def _step(part: int | str) -> tuple[int, int, str]:
    return (0, part, "") if isinstance(part, int) else (1, 0, part)


def _top_problems(document: Any) -> list[Problem]:
    if type(document) is not dict:
        return [([], _OTHER, "manifest must be an object (a table in TOML)")]
    problems: list[Problem] = []
    if "bodies" in document:
        problems += _bodies_problems(document)
    else:
        problems.append(([], _MISSING, "missing field 'bodies'"))
    if "duration" in document and not is_positive(document["duration"]):
        problems.append((["duration"], _OTHER, f"duration must be {EXPECTED['duration']}"))
    if "units" in document and not _non_empty_string(document["units"]):
        problems.append((["units"], _OTHER, f"units must be {EXPECTED['units']}"))
    extra = sorted(set(document) - TOP_FIELDS)
    if extra:
        problems.append(([], _UNKNOWN, _unknown(extra, [])))
    return problems


def _bodies_problems(document: dict) -> list[Problem]:
    """The problems of the first body that has any (every later one ranks after them)."""
    bodies = document["bodies"]
    if type(bodies) is not list or not bodies:
        return [(["bodies"], _OTHER, f"bodies must be {EXPECTED['bodies']}")]
    for index, body in enumerate(bodies):
        if not _valid_body(body):
            return list(_body_problems(document, index, body))
    return []


def _valid_body(body: Any) -> bool:
    if type(body) is not dict or not body.keys() <= BODY_FIELDS or "name" not in body:
        return False
    if ("mesh" in body) == ("primitive" in body):
        return False
    return all(FIELD_RULES[field](value) for field, value in body.items())


def _body_problems(document: dict, index: int, body: Any) -> Iterator[Problem]:
    path = ["bodies", index]
    if type(body) is not dict:
        yield path, _OTHER, f"bodies[{index}] must be an object (a table in TOML)"
        return
    label = body_label(document, index)
    for field, value in body.items():
        if field in FIELD_RULES and not FIELD_RULES[field](value):
            yield from _field_problems(field, value, [*path, field], label)
    if "name" not in body:
        yield path, _MISSING, f"{label}: missing field 'name'"
    extra = sorted(set(body) - BODY_FIELDS)
    if extra:
        yield path, _UNKNOWN, f"{label}: {_unknown(extra, [])}"
    if ("mesh" in body) == ("primitive" in body):
        yield path, _OTHER, f"{label}: needs exactly one of 'mesh' or 'primitive'"


def _field_problems(field: str, value: Any, path: list, label: str) -> Iterator[Problem]:
    if field == "primitive":
        yield from _primitive_problems(value, path, label)
    elif field in ROTATION_FIELDS:
        yield path, _OTHER, _rotation_message(value, field, label)
    else:
        yield path, _OTHER, f"{label}: {field} must be {EXPECTED[field]}"


def _primitive_problems(primitive: Any, path: list, label: str) -> Iterator[Problem]:
    """A primitive's problems, in the order JSON Schema finds them: its fields' values, a
    missing or unknown field, then the fields its type requires or forbids."""
    if type(primitive) is not dict:
        yield path, _OTHER, f"{label}: primitive must be {EXPECTED['primitive']}"
        return
    checks = {"type": lambda t: t in PRIMITIVE_TYPES, "radius": is_positive}
    checks.update(size=_is_positive_triple, length=is_positive, semi_axes=_is_positive_triple)
    for field, check in checks.items():
        if field in primitive and not check(primitive[field]):
            yield [*path, field], _OTHER, f"{label}: primitive.{field} must be {EXPECTED[field]}"
    if "type" not in primitive:
        yield path, _MISSING, f"{label}: missing field 'primitive.type'"
    extra = sorted(set(primitive) - PRIMITIVE_FIELDS)
    if extra:
        yield path, _UNKNOWN, f"{label}: {_unknown(extra, ['primitive'])}"
    kind = primitive.get("type")
    for known, fields in PRIMITIVE_KEYS.items():
        if "type" not in primitive or type(kind) is not str or kind != known:
            continue
        missing = [name for name in PRIMITIVE_REQUIRED[known] if name not in primitive]
        if missing:
            yield path, _MISSING, f"{label}: missing field 'primitive.{missing[0]}'"
        extra = sorted(set(primitive) - fields)
        if extra:
            yield path, _UNKNOWN, f"{label}: {_unknown(extra, ['primitive'])}"


def _is_positive_triple(x: Any) -> bool:
    return is_numbers(x, 3, positive=True)


def _rotation_message(rotation: Any, field: str, label: str) -> str:
    """The message of a rotation that is neither form: of the form its keys choose (a
    quaternion first), the problem nearest the rotation; else what a rotation is."""
    if type(rotation) is not dict or not ({"quaternion", "euler_deg"} & rotation.keys()):
        return f"{label}: {field} must be {EXPECTED[field]}"
    allowed: tuple[str, ...]
    if "quaternion" in rotation:
        allowed, arrays = ("quaternion",), {"quaternion": 4}
    else:
        allowed, arrays = ("euler_deg", "order"), {"euler_deg": 3}
    inner: list[tuple[int, int, str]] = []  # (depth below the rotation, rank, message)
    for name, size in arrays.items():
        value = rotation.get(name)
        if name in rotation and not is_numbers(value, size):
            depth = 2 if type(value) is list and len(value) == size else 1
            inner.append((depth, _OTHER, f"{label}: {field}.{name} must be {EXPECTED[name]}"))
    if "order" in allowed and "order" in rotation and not _is_order(rotation["order"]):
        inner.append((1, _OTHER, f"{label}: {field}.order must be {EXPECTED['order']}"))
    missing = [name for name in allowed if name not in rotation]
    if missing:
        inner.append((0, _MISSING, f"{label}: missing field '{field}.{missing[0]}'"))
    extra = sorted(set(rotation) - set(allowed))
    if extra:
        inner.append((0, _UNKNOWN, f"{label}: {_unknown(extra, [field])}"))
    return min(inner, key=lambda p: (p[0], p[1]))[2]


def _is_order(x: Any) -> bool:
    return type(x) is str and x in ORDERS


def _unknown(extra: Sequence[str], fields: list[str]) -> str:
    names = ", ".join(repr(".".join([*fields, name])) for name in extra)
    return f"unknown {'field' if len(extra) == 1 else 'fields'} {names}"


def describe(document: Any, path: list) -> str:
    """``body 'ball': position`` or ``duration``, for a path into the document."""
    in_body = len(path) >= 2 and path[0] == "bodies" and isinstance(path[1], int)
    fields = ".".join(str(p) for p in (path[2:] if in_body else path) if not isinstance(p, int))
    if in_body:
        return f"{body_label(document, path[1])}: {fields or 'bodies'}"
    return fields


def body_label(document: Any, index: int) -> str:
    """``body 'ball'``, or ``bodies[3]`` for a body without a usable name."""
    try:
        name = document["bodies"][index]["name"]
    except (KeyError, IndexError, TypeError):
        name = None
    return f"body {name!r}" if isinstance(name, str) and name else f"bodies[{index}]"


# --- magnitudes ---------------------------------------------------------------------------------

#: Manifest fields that are lengths or positions (checked against MAX_COORDINATE).
_LENGTH_FIELDS = ("position", "end_position", "scale")
_PRIMITIVE_FIELDS = ("size", "radius", "length", "semi_axes")


def check_magnitudes(document: dict, source: str, found: Columns | None = None) -> None:
    """Every length, position and motion of a valid manifest within the limits meshcol
    computes with: one line naming the body, the field, the value and its line.

    With the manifest's columns (``found``), only the bodies a vectorised pass finds near a
    limit (or primitive: their sizes are not in the columns) are checked one by one, in order:
    the same first error, without 300,000 bodies of Python."""
    duration = document.get("duration")
    indices: Sequence[int] = range(len(document["bodies"]))
    if found is not None:
        indices = near_limits(found, duration).nonzero()[0].tolist()
    for index in indices:
        spec = document["bodies"][index]
        problem = _length_problem(spec) or _scale_problem(spec) or _motion_problem(spec, duration)
        if problem is not None:
            message, field = problem
            label = body_label(document, index)
            raise _at_line(f"{label}: {message}", source, spec["name"], field)


def _length_problem(spec: dict) -> tuple[str, str] | None:
    """A length or position beyond :data:`MAX_COORDINATE`: ``(message, field)``."""
    fields = [(name, spec.get(name)) for name in _LENGTH_FIELDS]
    primitive = spec.get("primitive", {})
    fields += [(f"primitive.{name}", primitive.get(name)) for name in _PRIMITIVE_FIELDS]
    for name, value in fields:
        values = value if isinstance(value, list) else [] if value is None else [value]
        for v in values:
            if abs(v) > MAX_COORDINATE:
                return f"{name} {v:.6g} is beyond the limit of +/-{MAX_COORDINATE:g}", name
    return None


def _scale_problem(spec: dict) -> tuple[str, str] | None:
    """A scale so small the body would collapse to a point."""
    if "scale" not in spec:
        return None
    scales = spec["scale"] if isinstance(spec["scale"], list) else [spec["scale"]]
    for value in scales:
        if 0 < value < 1.0 / MAX_COORDINATE:
            return (
                f"scale {value:.6g} is below the limit of {1.0 / MAX_COORDINATE:g}: the body "
                "would collapse to a point",
                "scale",
            )
    return None


def _motion_problem(spec: dict, duration: float | None) -> tuple[str, str] | None:
    """A velocity or angular velocity that moves the body too far over the duration."""
    if duration is None:
        return None
    for name, limit, unit in (
        ("velocity", MAX_COORDINATE, ""),
        ("angular_velocity", MAX_TURN, " rad"),
    ):
        value = spec.get(name)
        if value is None:
            continue
        motion = max(abs(v) for v in value) * duration  # Python floats: inf, never an error
        if motion > limit:
            return (
                f"{name} x duration is {motion:.6g}{unit}, beyond the limit of {limit:g}{unit} "
                f"({name} {_numbers(value)}, duration {duration:g} s)",
                name,
            )
    return None


def _at_line(message: str, source: str, body: str, field: str) -> SceneError:
    """``message`` with `` (line N)``, the line of ``field`` in the body named ``body``."""
    line = _line_of(source, body, field.split(".")[-1])
    return SceneError(message if line is None else f"{message} (line {line})", source)


def _line_of(source: str, body: str, field: str) -> int | None:
    """1-based line of ``field`` within the body named ``body`` (JSON or TOML text): the
    first after the body's name line, before the next body's; else the last before it."""
    try:
        lines = Path(source).read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    names = re.compile(r"""["']?\bname["']?\s*[:=]\s*["']([^"']*)["']""")
    key = re.compile(r"""(?:^|[\s{,"'])""" + re.escape(field) + r"""["']?\s*[:=]""")
    starts = [(i, m.group(1)) for i, text in enumerate(lines) for m in names.finditer(text)]
    for k, (start, name) in enumerate(starts):
        if name != body:
            continue
        end = starts[k + 1][0] if k + 1 < len(starts) else len(lines)
        begin = starts[k - 1][0] + 1 if k > 0 else 0
        after = [i for i in range(start, max(end, start + 1)) if key.search(lines[i])]
        before = [i for i in range(begin, start) if key.search(lines[i])]
        found = after[:1] or before[-1:]
        return (found[0] if found else start) + 1
    return None


def _numbers(values: list) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"
