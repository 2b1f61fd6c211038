"""What kind of input a path is: a mesh file, a scene manifest or a robot description.

The one answer every command and loader asks for (:func:`input_kind`), by the file's
extension (:data:`meshcol.vocabulary.MANIFEST_EXTENSIONS`,
:data:`meshcol.vocabulary.ROBOT_EXTENSIONS`) and, for ``.xml``, the name of its root element
(``<mujoco>`` or ``<robot>``: a robot; anything else: not).
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

from meshcol.vocabulary import INPUT_KINDS, MANIFEST_EXTENSIONS, ROBOT_EXTENSIONS

__all__ = [
    "INPUT_KINDS",
    "input_kind",
    "is_manifest",
    "is_robot_file",
    "is_whole_scene",
    "root_tag",
]

PathLike = str | os.PathLike[str]

#: Root elements of the robot descriptions meshcol reads from an ``.xml`` file.
ROBOT_ROOTS = ("mujoco", "robot")


def input_kind(path: PathLike) -> str:
    """``"manifest"``, ``"robot"`` or ``"mesh"`` (one of :data:`INPUT_KINDS`): how ``path``
    is read.

    A ``.json`` or ``.toml`` file is a scene manifest; a ``.urdf`` or ``.mjcf`` file, or an
    ``.xml`` file whose root element is ``<mujoco>`` or ``<robot>``, a robot description;
    anything else a mesh file (the mesh reader says when it is not one). Only an ``.xml``
    file is opened (its first 64 KiB); one that cannot be read (a pipe, a link that loops) is
    a robot description, whose reader names the problem.
    """
    suffix = Path(os.fspath(path)).suffix.lower()
    if suffix in MANIFEST_EXTENSIONS:
        return "manifest"
    if suffix in ROBOT_EXTENSIONS and (suffix != ".xml" or _robot_root(path)):
        return "robot"
    return "mesh"


def _robot_root(path: PathLike) -> bool:
    """True when the existing file ``path``'s root element is a robot's, or the file cannot
    be read at all."""
    from meshcol.errors import InputFileError

    try:
        return _head_root(path) in ROBOT_ROOTS
    except InputFileError:
        return os.path.lexists(path)


def is_manifest(path: PathLike) -> bool:
    """True for a scene manifest (``.json``, ``.toml``): ``input_kind(path) == "manifest"``."""
    return input_kind(path) == "manifest"


def is_robot_file(path: PathLike) -> bool:
    """True for a robot description: ``input_kind(path) == "robot"``."""
    return input_kind(path) == "robot"


def is_whole_scene(inputs: Sequence[PathLike]) -> bool:
    """True when ``inputs`` are one manifest or one robot description: a scene read whole."""
    return len(inputs) == 1 and input_kind(inputs[0]) != "mesh"


def root_tag(path: PathLike) -> str | None:
    """The root element's name, from the file's first 64 KiB (None if unreadable)."""
    from meshcol.errors import InputFileError

    try:
        return _head_root(path)
    except InputFileError:
        return None


def _head_root(path: PathLike) -> str | None:
    """The root element's name from the file's first 64 KiB; InputFileError when unreadable."""
    from meshcol.io.safe_read import read_input

    # never blocks on a pipe, never reads a device
    head = read_input(path, "robot", limit=65536).decode("utf-8", errors="replace")
    head = re.sub(r"<\?.*?\?>|<!--.*?-->|<!DOCTYPE[^>]*>", "", head, flags=re.S)
    match = re.search(r"<\s*([A-Za-z_][\w.-]*)", head)
    return match.group(1) if match else None
