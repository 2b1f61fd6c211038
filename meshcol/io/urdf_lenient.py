"""What pybullet reads past in a URDF, read as pybullet reads it, with a warning each.

pybullet_data, the collection pybullet ships, holds robots that a strict parser refuses and
that pybullet loads: minitaur, quadruped, bike and table_square declare XML version "0.0";
biped2d and diff_ring have blank lines before their XML declaration; humanoid.urdf ends in a
NUL byte; cube_no_rotation gives ``lower="1" upper="-1"``, Bullet's way of saying "no limit";
racecar_differential gives a mesh ``scale="1 1 1 1"``; bike writes ``xyz="0.07, 0, -0.69"`` and
biped2d ``lower="-1.57."`` (pybullet reads a number's leading digits). Each is read as follows,
and named in a warning (nothing is repaired silently):

1. the text, only when the strict parse fails (:func:`lenient_text`): leading whitespace
   before ``<?xml``, a declared version other than 1.0, and NUL bytes or whitespace after
   the root element; anything else stays an error;
2. the tree (:func:`relax_tree`): a number of a numeric attribute followed by other
   characters (``0.07,``) is its leading number; a ``<limit>`` whose lower bound is above its
   upper bound loses both (no limits, as URDF2Bullet skips such a limit); a mesh ``scale``,
   an ``xyz`` or an ``rpy`` of more than three numbers keeps the first three (microtaur's
   ``rpy="0 1.57079 0 0"``); a joint's second ``<axis>`` (or origin, limit...) is left out,
   pybullet reading the first (spirit40newer's ``RL_lower_joint``).
"""

from __future__ import annotations

import re
from typing import Any

__all__ = ["lenient_text", "read_description_xml", "relax_tree"]

#: The attributes URDF reads as numbers (one or several, space-separated).
NUMERIC_ATTRIBUTES = frozenset(
    [
        "xyz",
        "rpy",
        "lower",
        "upper",
        "effort",
        "velocity",
        "scale",
        "size",
        "radius",
        "length",
        "value",
        "ixx",
        "ixy",
        "ixz",
        "iyy",
        "iyz",
        "izz",
        "multiplier",
        "offset",
        "damping",
        "friction",
        "soft_lower_limit",
        "soft_upper_limit",
        "k_position",
        "k_velocity",
        "rising",
        "falling",
    ]
)
#: A joint's children that URDF has at most once; pybullet reads the first of several
#: (tinyxml's ``FirstChildElement``), MuJoCo's importer refuses a repeated one.
_JOINT_SINGLETONS = (
    "origin",
    "parent",
    "child",
    "axis",
    "limit",
    "dynamics",
    "calibration",
    "mimic",
    "safety_controller",
)

#: A number and what follows it in one space-separated token.
_LEADING_NUMBER = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)(.+)$")

#: The XML declaration, its version attribute captured.
_DECLARATION = re.compile(rb"^<\?xml\s+version\s*=\s*([\"'])(?P<version>[^\"']*)\1")


def read_description_xml(source: str, warnings: list[str], *, keep_blank_text: bool = True) -> Any:
    """The root element (lxml) of a robot description, by the guarded read. A URDF (a
    ``<robot>`` root) has its xacro leftovers resolved (:mod:`meshcol.io.xacro_leftovers`) and
    is read as pybullet reads it where a strict parse refuses it or its values
    (:func:`lenient_text`, :func:`relax_tree`), with warnings; the one reading of the reader
    and of the writers that rewrite the file, which so write what the reader read.

    Raises
    ------
    SceneError
        The file is not well-formed XML (and not only for what pybullet reads past)."""
    from lxml import etree

    from meshcol.errors import SceneError
    from meshcol.io.safe_read import read_input

    data = read_input(source, "robot")  # the guarded read: never a pipe or a device, capped
    parser = etree.XMLParser(remove_blank_text=not keep_blank_text, resolve_entities=False)
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        repaired = lenient_text(data, warnings)
        try:
            root = None if repaired is None else etree.fromstring(repaired, parser)
        except etree.XMLSyntaxError:
            root = None
        if root is None:
            raise SceneError(f"malformed XML: {' '.join(str(exc).split())}", source) from None
    if root.tag == "robot":
        from meshcol.io.xacro_leftovers import resolve_xacro_leftovers

        resolve_xacro_leftovers(root, source, warnings)
        relax_tree(root, warnings)
    return root


def lenient_text(data: bytes, warnings: list[str]) -> bytes | None:
    """``data`` with what pybullet reads past taken away, a warning for each; None when
    nothing of that kind is there (the strict parser's error stands)."""
    text = data
    start = len(text) - len(text.lstrip())
    if start and text[start:].startswith(b"<?xml"):
        text = text[start:]
        warnings.append("blank lines before the XML declaration: read from the declaration on")
    declared = _DECLARATION.match(text)
    if declared and declared["version"] != b"1.0":
        version = declared["version"].decode("ascii", "replace")
        text = text[: declared.start("version")] + b"1.0" + text[declared.end("version") :]
        warnings.append(f"the XML declaration gives version {version!r}: read as XML 1.0")
    end = text.rstrip(b" \t\r\n\0")
    if len(end) < len(text) and b"\0" in text[len(end) :]:
        text = end
        warnings.append("NUL bytes after the root element: left out")
    return text if text != data else None


def relax_tree(root: Any, warnings: list[str]) -> None:
    """Numbers followed by other characters, read as their leading number; joint limits
    whose lower bound is above the upper one, dropped; scales, positions and angles of more
    than three numbers, cut to three; a joint's repeated elements, the first kept; in place,
    a warning for each."""
    for element in root.iter():
        if isinstance(element.tag, str):  # not a comment
            _leading_numbers(element, warnings)
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        lower, upper = _number(limit, "lower"), _number(limit, "upper")
        if lower is not None and upper is not None and lower > upper:
            del limit.attrib["lower"], limit.attrib["upper"]
            warnings.append(
                f"joint {joint.get('name')!r}: lower limit {lower:g} is above upper limit "
                f"{upper:g}, Bullet's way of saying none: read without limits"
            )
    for element in root.iter("mesh", "origin", "axis"):
        for name in ("scale", "xyz", "rpy"):
            numbers = (element.get(name) or "").split()
            if len(numbers) > 3:
                element.set(name, " ".join(numbers[:3]))
                warnings.append(
                    f"{_place(element)}: {name} {' '.join(numbers)!r} has {len(numbers)} "
                    "numbers: the first three are read"
                )
    for joint in root.iter("joint"):
        for tag in _JOINT_SINGLETONS:
            repeated = joint.findall(tag)[1:]
            for element in repeated:
                joint.remove(element)
            if repeated:
                warnings.append(
                    f"joint {joint.get('name')!r}: {len(repeated) + 1} <{tag}> elements: "
                    "the first is read"
                )


def _place(element: Any) -> str:
    """Where an element is, for a warning: a mesh by its file, else the element and the name
    of the link or joint it is in."""
    if element.tag == "mesh":
        return f"mesh {element.get('filename')!r}"
    if element.tag in ("link", "joint"):
        return f"{element.tag} {element.get('name')!r}"
    owner = next(element.iterancestors("link", "joint"), None)
    if owner is None:
        return f"<{element.tag}>"
    return f"<{element.tag}> of {owner.tag} {owner.get('name')!r}"


def _leading_numbers(element: Any, warnings: list[str]) -> None:
    """Each numeric attribute of ``element`` whose tokens are numbers with trailing
    characters, read as those numbers (a token that starts with no number is left to the
    loader, which says what it is)."""
    for name, text in element.attrib.items():
        if name not in NUMERIC_ATTRIBUTES or "$" in text:  # xacro leftovers: their own reader
            continue
        tokens = text.split()
        fixed = []
        for token in tokens:
            match = _LEADING_NUMBER.match(token)
            fixed.append(token if match is None or _is_number(token) else match[1])
        if fixed != tokens:
            read = " ".join(fixed)
            element.set(name, read)
            warnings.append(
                f"{_place(element)}: {name}={text!r} read as {read!r} "
                "(the numbers, as pybullet reads them)"
            )


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _number(element: Any, name: str) -> float | None:
    """An attribute as a number; None when the element or the attribute is missing, or the
    text is no number (the loader then says so)."""
    if element is None or element.get(name) is None:
        return None
    try:
        return float(element.get(name))
    except ValueError:
        return None
