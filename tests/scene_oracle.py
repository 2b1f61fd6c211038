"""The scene manifest's validation as main ee068ea did it, by jsonschema: the oracle that the
hand-written validator (meshcol.io.scene_validate) is held to, message for message.

``schema_message`` is the old ``_validate`` (a non-finite number first, then jsonschema's
errors, the first in document order worded by ``_message``), kept verbatim so the tests compare
the new validator's every message with the one users saw before it.
"""

from __future__ import annotations

import json
from functools import lru_cache
from typing import Any

from meshcol.io.scene_parse import first_non_finite
from meshcol.io.scene_schema import EXPECTED, SCHEMA_PATH


@lru_cache(maxsize=1)
def validator():
    import jsonschema

    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def schema_valid(document: Any) -> bool:
    """What jsonschema accepts with every number finite."""
    return first_non_finite(document) is None and not list(validator().iter_errors(document))


def schema_message(document: Any) -> str | None:
    """The message meshcol gave for ``document`` when jsonschema decided: a non-finite number
    (the first, in document order), else jsonschema's first error, worded; None when valid."""
    where = first_non_finite(document)
    if where is not None:
        return f"{_describe(document, where)} must be finite"
    errors = list(validator().iter_errors(document))
    if not errors:
        return None
    # report the first problem in document order; missing/unknown fields before wrong values
    priority = {"additionalProperties": 0, "required": 1}

    def key(error):
        path = [(0, p, "") if isinstance(p, int) else (1, 0, p) for p in error.absolute_path]
        return (path, priority.get(error.validator, 2))

    error = min(errors, key=key)
    return _message(document, error)


def _message(document: Any, error) -> str:
    path = list(error.absolute_path)
    branch = _rotation_branch(error)
    if branch is not None:
        return _message(document, branch)
    if error.validator == "additionalProperties":
        allowed = set(error.schema.get("properties", {}))
        extra = sorted(set(error.instance) - allowed)
        names = ", ".join(repr(_join(path[_field_start(path) :], name)) for name in extra)
        noun = "field" if len(extra) == 1 else "fields"
        return _prefixed(document, path, f"unknown {noun} {names}")
    if error.validator == "required":
        missing = [name for name in error.validator_value if name not in error.instance]
        return _prefixed(
            document, path, f"missing field {_join(path[_field_start(path) :], missing[0])!r}"
        )
    if not path:
        return "manifest must be an object (a table in TOML)"
    if path == ["bodies", path[-1]] and isinstance(path[-1], int):
        if error.validator == "oneOf":
            return f"{_body_label(document, path[1])}: needs exactly one of 'mesh' or 'primitive'"
        return f"bodies[{path[1]}] must be an object (a table in TOML)"
    return f"{_describe(document, path)} must be {_expected(path)}"


def _rotation_branch(error):
    """For a rotation of a recognisable form, the error inside that form (e.g. a bad order)."""
    if error.validator != "oneOf" or not isinstance(error.instance, dict):
        return None
    if "quaternion" in error.instance:
        form = 0
    elif "euler_deg" in error.instance:
        form = 1
    else:
        return None
    inner = [
        e for e in error.context if e.relative_schema_path and e.relative_schema_path[0] == form
    ]
    if not inner:
        return None
    priority = {"additionalProperties": 0, "required": 1}
    return min(inner, key=lambda e: (len(e.absolute_path), priority.get(e.validator, 2)))


def _field_start(path: list) -> int:
    return 2 if len(path) >= 2 and path[0] == "bodies" and isinstance(path[1], int) else 0


def _join(fields: list, name: str | None = None) -> str:
    parts = [str(p) for p in fields if not isinstance(p, int)]
    if name is not None:
        parts.append(name)
    return ".".join(parts)


def _body_label(document: Any, index: int) -> str:
    try:
        name = document["bodies"][index]["name"]
    except (KeyError, IndexError, TypeError):
        name = None
    return f"body {name!r}" if isinstance(name, str) and name else f"bodies[{index}]"


def _prefixed(document: Any, path: list, message: str) -> str:
    start = _field_start(path)
    if start:
        return f"{_body_label(document, path[1])}: {message}"
    return message


def _describe(document: Any, path: list) -> str:
    """``body 'ball': position`` or ``duration``, for a path into the document."""
    start = _field_start(path)
    field = _join(path[start:]) or _join(path)
    if start:
        return f"{_body_label(document, path[1])}: {field}"
    return field


def _expected(path: list) -> str:
    names = [p for p in path if isinstance(p, str)]
    return EXPECTED.get(names[-1], "valid") if names else "valid"
