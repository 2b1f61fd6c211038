"""SRDF written: the ``<disable_collisions>`` entries of a collision matrix.

The reader is :func:`meshcol.io.robot.load_robot` (``RobotOptions.srdf``), which takes the
``<disable_collisions link1 link2 reason>`` elements this module writes, as MoveIt does.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from xml.sax.saxutils import quoteattr

from meshcol.io.report import atomic_write

__all__ = ["SRDF_REASONS", "srdf_text", "write_srdf"]

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
