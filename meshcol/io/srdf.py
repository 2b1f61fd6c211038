"""SRDF read and written: the ``<disable_collisions>`` entries of a collision matrix.

:func:`read_srdf` gives the pairs :func:`meshcol.io.robot.load_robot` leaves out of
self-collision (``RobotOptions.srdf``), as MoveIt does; :func:`write_srdf` writes the entries
of ``meshcol collision-matrix``, which the reader takes back.
"""

from __future__ import annotations

import os
from collections.abc import Iterable

from meshcol.errors import InputFileError, SceneError
from meshcol.io.report import atomic_write

__all__ = ["SRDF_REASONS", "read_srdf", "srdf_text", "write_srdf"]

#: Reasons MoveIt's setup assistant writes, in its precedence order.
SRDF_REASONS = ("Adjacent", "Default", "Always", "Never")


def srdf_text(robot: str, pairs: Iterable[tuple[str, str, str]], comment: str | None = None) -> str:
    """An SRDF document of ``<disable_collisions>`` entries.

    Parameters
    ----------
    robot : str
        The robot's name (``<robot name=...>``: the URDF's).
    pairs : iterable of (link1, link2, reason)
        Written in the order given (sort them for a stable file).
    comment : str, optional
        One line written as an XML comment under the root (how the matrix was computed).

    Returns
    -------
    str
        UTF-8 XML text with a trailing newline.
    """
    from xml.sax.saxutils import quoteattr  # urllib, email, http: only when writing

    lines = ['<?xml version="1.0" encoding="UTF-8"?>', f"<robot name={quoteattr(robot)}>"]
    if comment:
        lines.append(f"    <!-- {comment.replace('--', '- -')} -->")
    for a, b, reason in pairs:
        lines.append(
            f"    <disable_collisions link1={quoteattr(a)} link2={quoteattr(b)} "
            f"reason={quoteattr(reason)}/>"
        )
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def write_srdf(
    path: str | os.PathLike[str],
    robot: str,
    pairs: Iterable[tuple[str, str, str]],
    comment: str | None = None,
) -> None:
    """Write :func:`srdf_text` to ``path`` atomically (a temporary file renamed into place)."""
    atomic_write(path, srdf_text(robot, pairs, comment))


def read_srdf(path: str, links: set[str]) -> tuple[list[tuple[str, str, str]], list[str]]:
    """The ``<disable_collisions>`` pairs of an SRDF file.

    Parameters
    ----------
    path : str
    links : set of str
        The robot's links: pairs naming another link are left out.

    Returns
    -------
    (list of (link1, link2, reason), list of str)
        The pairs (reason ``srdf: <reason>``, ``srdf: disabled`` without one) in file order,
        and the unknown link names they named, each once.

    Raises
    ------
    InputFileError
        The file is missing or unreadable.
    SceneError
        Malformed XML, or a ``<disable_collisions>`` without ``link1`` and ``link2``.
    """
    from lxml import etree

    if not os.path.lexists(path):
        raise InputFileError("SRDF file not found", path)
    from meshcol.io.safe_read import read_input

    data = read_input(path, "robot")  # the guarded read: never a pipe or a device, capped
    try:
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False))
    except etree.XMLSyntaxError as exc:
        raise SceneError(f"malformed XML: {' '.join(str(exc).split())}", path) from None
    pairs: list[tuple[str, str, str]] = []
    unknown: list[str] = []
    for element in root.iter("disable_collisions"):
        a, b = element.get("link1"), element.get("link2")
        if not a or not b:
            raise SceneError(
                f"line {element.sourceline}: <disable_collisions> needs link1 and link2", path
            )
        missing = [n for n in (a, b) if n not in links]
        if missing:
            unknown.extend(n for n in missing if n not in unknown)
            continue
        pairs.append((a, b, f"srdf: {element.get('reason') or 'disabled'}"))
    return pairs, unknown
