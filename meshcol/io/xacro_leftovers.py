"""Xacro leftovers in a URDF: ``$(optenv ...)``, ``$(env ...)``, ``${...}`` not expanded.

A URDF exported without running xacro keeps substitution arguments in its attributes;
pybullet loads such a robot (its parser reads what it cannot parse as its default), yourdfpy
refuses it. Here every such attribute is named in a warning and read as follows:

1. ``$(optenv NAME DEFAULT)`` and ``$(env NAME)`` are what xacro makes of them (the
   environment variable, else the default given); the attribute is read with them replaced
   when nothing else is left to expand;
2. otherwise (``${expression}``, ``$(find ...)``, an unset ``$(env ...)``) the attribute is
   dropped where URDF gives it a default (an origin's ``xyz``/``rpy``: zero, an axis: ``1 0 0``,
   joint limits, dynamics, calibration, safety controller, mimic factors, mass and inertia,
   mesh scale: the loader's default, as pybullet and yourdfpy read a missing attribute);
3. an attribute without a default (a mesh file name, a box size, a link or joint name...) is
   an error naming it: run xacro first.
"""

from __future__ import annotations

import os
import re
from typing import Any

from meshcol.errors import SceneError

__all__ = ["resolve_xacro_leftovers"]

#: ``$(command args)`` and ``${expression}``.
_SUBSTITUTION = re.compile(r"\$\((?P<command>[A-Za-z_]+)(?P<args>[^)]*)\)|\$\{[^}]*\}")

#: The attributes URDF gives a default, by element: what a loader reads when one is missing.
_DEFAULTS: dict[str, dict[str, str]] = {
    "origin": {"xyz": "0 0 0", "rpy": "0 0 0"},
    "axis": {"xyz": "1 0 0"},
    "limit": {
        "lower": "none (unlimited here)",
        "upper": "none (unlimited here)",
        "effort": "none",
        "velocity": "none",
    },
    "dynamics": {"damping": "0", "friction": "0"},
    "calibration": {"rising": "none", "falling": "none"},
    "safety_controller": {
        "soft_lower_limit": "0",
        "soft_upper_limit": "0",
        "k_position": "0",
        "k_velocity": "none",
    },
    "mimic": {"multiplier": "1", "offset": "0"},
    "mass": {"value": "0"},
    "inertia": dict.fromkeys(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), "0"),
    "mesh": {"scale": "1 1 1"},
    "color": {"rgba": "none"},
    "texture": {"filename": "none"},
}


def resolve_xacro_leftovers(root: Any, source: str, warnings: list[str]) -> None:
    """Resolve, drop (with the URDF default) or refuse every attribute of ``root`` (an lxml
    element, changed in place) that still holds a xacro substitution; one warning each.

    Raises
    ------
    SceneError
        An attribute without a default holds a substitution that cannot be resolved."""
    for element in root.iter():
        if not isinstance(element.tag, str):
            continue  # comments and processing instructions
        for attribute, value in list(element.attrib.items()):
            if "$(" not in value and "${" not in value:
                continue
            where = f"{_owner(element)}<{element.tag} {attribute}={value!r}>"
            resolved = _substitute(value)
            if resolved is not None:
                element.set(attribute, resolved)
                warnings.append(
                    f"{where}: xacro leftover, read as {resolved!r} (as xacro resolves it)"
                )
                continue
            default = _DEFAULTS.get(element.tag, {}).get(attribute)
            if default is None:
                raise SceneError(
                    f"{where}: xacro leftover with no default to fall back on (run xacro first)",
                    source,
                )
            del element.attrib[attribute]
            warnings.append(
                f"{where}: xacro leftover not expanded; the URDF default ({default}) used, "
                "as pybullet and yourdfpy read a missing attribute (run xacro to expand it)"
            )


def _owner(element: Any) -> str:
    """``link 'NAME': `` or ``joint 'NAME': `` of the element's nearest named ancestor."""
    for ancestor in [element, *element.iterancestors()]:
        if ancestor.tag in ("link", "joint") and ancestor is not element:
            return f"{ancestor.tag} {ancestor.get('name')!r}: "
    return ""


def _substitute(value: str) -> str | None:
    """``value`` with its ``$(optenv)``/``$(env)`` replaced as xacro would; None when a
    substitution is left that cannot be resolved here."""
    unresolved = False

    def replace(match: re.Match[str]) -> str:
        nonlocal unresolved
        command = match.group("command")
        words = (match.group("args") or "").split()
        if command == "optenv" and words:
            return os.environ.get(words[0], " ".join(words[1:]))
        if command == "env" and len(words) == 1 and words[0] in os.environ:
            return os.environ[words[0]]
        unresolved = True
        return match.group(0)

    resolved = _SUBSTITUTION.sub(replace, value)
    return None if unresolved or "$(" in resolved or "${" in resolved else resolved
