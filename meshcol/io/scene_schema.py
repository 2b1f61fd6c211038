"""The scene manifest's fields and the kind of value each takes: the rules of
``meshcol/schemas/scene.schema.json``, read from that file, as predicates.

The field names, the primitive types and their fields, the rotation orders and the collider
shapes come from the schema file itself (one source: a field added there is a field known
here, and :mod:`meshcol.io.scene_validate` refuses to import until it has a rule). What each
kind of value must be (a non-empty string, three finite numbers, a rotation...) is written
here once, as predicates that the body-by-body check (:mod:`meshcol.io.scene_validate`) and
the column-by-column one (:mod:`meshcol.io.scene_columns`) share.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

__all__ = [
    "BODY_FIELDS",
    "EXPECTED",
    "MAX_TURN",
    "ORDERS",
    "PRIMITIVE_FIELDS",
    "PRIMITIVE_KEYS",
    "PRIMITIVE_REQUIRED",
    "PRIMITIVE_TRIPLES",
    "PRIMITIVE_TYPES",
    "ROTATION_FIELDS",
    "SCHEMA_PATH",
    "SHAPES",
    "TOP_FIELDS",
    "VECTOR_FIELDS",
    "is_number",
    "is_numbers",
    "is_positive",
    "is_primitive",
    "is_rotation",
    "is_scale",
    "plain_top",
]

#: The JSON Schema of a manifest.
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schemas" / "scene.schema.json"

_SCHEMA = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
_BODY = _SCHEMA["properties"]["bodies"]["items"]
_PRIMITIVE = _BODY["properties"]["primitive"]
_EULER = _BODY["properties"]["rotation"]["oneOf"][1]

#: The manifest's own fields.
TOP_FIELDS = frozenset(_SCHEMA["properties"])
#: A body's fields.
BODY_FIELDS = frozenset(_BODY["properties"])
#: A primitive's ``type`` values, in the schema's order.
PRIMITIVE_TYPES = tuple(_PRIMITIVE["properties"]["type"]["enum"])
#: Every field a primitive of any type may have.
PRIMITIVE_FIELDS = frozenset(_PRIMITIVE["properties"])
#: The fields of each primitive type (exactly these), and the ones it requires, in order.
PRIMITIVE_KEYS = {
    rule["if"]["properties"]["type"]["const"]: frozenset(rule["then"]["properties"])
    for rule in _PRIMITIVE["allOf"]
}
PRIMITIVE_REQUIRED = {
    rule["if"]["properties"]["type"]["const"]: tuple(rule["then"]["required"])
    for rule in _PRIMITIVE["allOf"]
}
#: The primitive types given by one array of three positive numbers (a box's ``size``, an
#: ellipsoid's ``semi_axes``), and that field.
PRIMITIVE_TRIPLES = {
    kind: field
    for kind, fields in PRIMITIVE_REQUIRED.items()
    for field in fields
    if _PRIMITIVE["properties"][field].get("type") == "array"
}
#: Axis orders of Euler angles.
ORDERS = frozenset(_EULER["properties"]["order"]["enum"])
#: Collider shapes a body may ask for.
SHAPES = frozenset(_BODY["properties"]["shape"]["enum"])
#: Fields that are three numbers, and fields that are rotations.
VECTOR_FIELDS = ("position", "end_position", "velocity", "angular_velocity")
ROTATION_FIELDS = ("rotation", "end_rotation")

#: Largest turn, in radians, a body may make over the motion (angular_velocity x duration):
#: 160,000 revolutions; beyond, sin and cos of the angle carry no precision.
MAX_TURN = 1e6

#: What a wrongly typed field should have been, by field name (the last name in its path).
EXPECTED = {
    "bodies": "a non-empty array of bodies",
    "units": "a non-empty string",
    "duration": "a positive number (seconds)",
    "name": "a non-empty string",
    "mesh": "a non-empty string (a file path)",
    "primitive": 'an object with a "type" (sphere, box, capsule, cylinder or ellipsoid)',
    "type": "one of sphere, box, capsule, cylinder, ellipsoid",
    "radius": "a positive number",
    "length": "a positive number",
    "size": "an array of 3 positive numbers",
    "semi_axes": "an array of 3 positive numbers",
    "position": "an array of 3 numbers",
    "end_position": "an array of 3 numbers",
    "velocity": "an array of 3 numbers",
    "angular_velocity": "an array of 3 numbers (rad/s)",
    "rotation": '{"quaternion": [w, x, y, z]} or {"euler_deg": [a, b, c], "order": "xyz"}',
    "end_rotation": '{"quaternion": [w, x, y, z]} or {"euler_deg": [a, b, c], "order": "xyz"}',
    "quaternion": "an array of 4 numbers [w, x, y, z]",
    "euler_deg": "an array of 3 numbers (degrees)",
    "order": "a string of three axes such as xyz, zyx or zxz",
    "scale": "a positive number or an array of 3 positive numbers",
    "shape": "one of hull, decomposed, mesh",
}


def is_number(x: Any) -> bool:
    """A finite JSON number (bool is not one; non-finite ones fail elsewhere, with a message)."""
    return type(x) is int or (type(x) is float and math.isfinite(x))


def is_positive(x: Any) -> bool:
    """A finite JSON number above zero."""
    return is_number(x) and x > 0


def is_numbers(x: Any, n: int, positive: bool = False) -> bool:
    """An array of ``n`` finite numbers (each above zero when ``positive``)."""
    if type(x) is not list or len(x) != n:
        return False
    return all(is_number(v) and (not positive or v > 0) for v in x)


def is_rotation(r: Any) -> bool:
    """``{"quaternion": [4 numbers]}`` or ``{"euler_deg": [3 numbers], "order": "xyz"}``."""
    if type(r) is not dict:
        return False
    if len(r) == 1:
        return is_numbers(r.get("quaternion"), 4)
    order = r.get("order")
    return (
        len(r) == 2
        and is_numbers(r.get("euler_deg"), 3)
        and type(order) is str
        and (order in ORDERS)
    )


def is_scale(x: Any) -> bool:
    """A positive number or an array of three."""
    return is_positive(x) or is_numbers(x, 3, positive=True)


def is_primitive(p: Any) -> bool:
    """A primitive of a known type with exactly its fields, each as its type wants it."""
    if type(p) is not dict:
        return False
    kind = p.get("type")
    fields = PRIMITIVE_KEYS.get(kind) if type(kind) is str else None
    if fields is None or p.keys() != fields:
        return False
    if kind in PRIMITIVE_TRIPLES:
        return is_numbers(p[PRIMITIVE_TRIPLES[kind]], 3, positive=True)
    if not is_positive(p["radius"]):
        return False
    return kind == "sphere" or is_positive(p["length"])


def plain_top(document: Any) -> bool:
    """The manifest's own fields (not its bodies') as the schema wants them."""
    if type(document) is not dict or not document.keys() <= TOP_FIELDS:
        return False
    units = document.get("units", "m")
    duration = document.get("duration", 1.0)
    bodies = document.get("bodies")
    if type(units) is not str or not units:
        return False
    if not is_positive(duration):
        return False
    return type(bodies) is list and bool(bodies)
