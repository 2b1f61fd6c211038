"""Mesh references of robot descriptions to files: ``package://``, ``file://``, relative, absolute.

``package://NAME/REST`` is resolved, in order, through:

1. the folders given for ``NAME`` (``--package-path NAME=DIR``);
2. the folders of ``ROS_PACKAGE_PATH`` (``ENTRY/NAME``, an entry named ``NAME``, or a folder
   ``NAME`` holding a ``package.xml`` a few levels below an entry);
3. an ancestor folder of the description named ``NAME`` (the description inside its package);
4. ``FOLDER/NAME/REST`` for the description's folder and then each of its ancestors, nearest
   first: a folder ``NAME`` beside the description, as pybullet's URDF importer finds it (the
   reference without ``package://``, relative to the description's folder), or beside an
   ancestor (the same rule a folder up at a time). ``package://meshes/base.stl`` is so
   ``meshes/base.stl`` beside the file, and ``package://wheel.obj`` (no REST, a form pybullet
   and Genesis read) the file ``wheel.obj`` beside it;
5. ``FOLDER/REST`` for the description's folder and its ancestors: yourdfpy's
   ``filename_handler_magic`` (``package://NAME/`` dropped, the rest relative to the folder
   and to each of its parents), which finds a package checked out under another name, as the
   ``example-robot-data`` layout is.

Rules 4 and 5 take the first file that exists. A relative reference is relative to the
description's folder.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

__all__ = ["PackageResolver", "resolve_mesh_reference"]

#: How deep below a ROS_PACKAGE_PATH entry a package folder is looked for (``src/repo/pkg``).
_PACKAGE_SEARCH_DEPTH = 3


class PackageResolver:
    """The mesh references of one description to files.

    Parameters
    ----------
    source : str
        The description (relative references and the ancestor folders start at its folder).
    package_paths : mapping of str to str
        ``package://NAME`` -> folder, before ``ROS_PACKAGE_PATH`` and the folder layout.
    """

    def __init__(self, source: str, package_paths: Mapping[str, str]) -> None:
        self.folder = Path(source).resolve().parent
        self.package_paths = dict(package_paths)
        self.ros_entries = [
            entry for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if entry
        ]

    def resolve(self, reference: str) -> tuple[str | None, str | None]:
        """``(path, None)``, or ``(None, why)`` for a package that cannot be found."""
        if reference.startswith("file://"):
            return reference[len("file://") :], None
        if not reference.startswith("package://"):
            path = Path(reference)
            return os.fspath(path if path.is_absolute() else self.folder / path), None
        name, _, rest = reference[len("package://") :].partition("/")
        if name in self.package_paths:
            return os.path.join(self.package_paths[name], rest), None
        for entry in self.ros_entries:
            found = _find_package(Path(entry), name)
            if found is not None:
                return os.fspath(found / rest), None
        ancestors = [self.folder, *self.folder.parents]
        for folder in ancestors:
            if name and folder.name == name:
                return os.fspath(folder / rest), None
        for folder in ancestors:
            # without a REST, pybullet's reading is the file NAME itself (Genesis's wheel.urdf
            # names its mesh ``package://wheel.obj``, beside the file)
            candidate = folder / name / rest if rest else folder / name
            if name and candidate.is_file():
                return os.fspath(candidate), None
        for folder in ancestors:
            if rest and (folder / rest).is_file():
                return os.fspath(folder / rest), None
        return None, (
            f"unknown package {name!r} (give --package-path {name}=DIR or set ROS_PACKAGE_PATH)"
        )


def resolve_mesh_reference(
    source: str | os.PathLike[str], reference: str, package_paths: Mapping[str, str] = {}
) -> str | None:
    """The file a description's mesh reference (``package://``, ``file://``, relative or
    absolute) names, as :func:`meshcol.io.robot.load_robot` resolves it; None for an unknown
    package."""
    path, _ = PackageResolver(os.fspath(source), package_paths).resolve(reference)
    return None if path is None else os.path.normpath(path)


def _find_package(entry: Path, name: str) -> Path | None:
    """The folder of package ``name`` under a ROS_PACKAGE_PATH entry: the entry itself, or a
    folder ``name`` holding a ``package.xml`` at most a few levels down (breadth first)."""
    if entry.name == name and entry.is_dir():
        return entry
    if (entry / name).is_dir():
        return entry / name
    level = [entry]
    for _ in range(_PACKAGE_SEARCH_DEPTH):
        below = []
        for folder in level:
            try:
                children = sorted(p for p in folder.iterdir() if p.is_dir())
            except OSError:
                continue
            for child in children:
                if child.name == name and (child / "package.xml").is_file():
                    return child
                if not child.name.startswith("."):
                    below.append(child)
        level = below
    return None
