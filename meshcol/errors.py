"""Exceptions raised by meshcol.

Library code raises subclasses of :class:`MeshcolError`; the command line maps every one of
them, in one place (``meshcol/cli/__init__.py``), to a one-line message and exit code 2.
"""

from __future__ import annotations

import os
from typing import Any

__all__ = [
    "InputFileError",
    "InvalidMeshError",
    "MeshcolError",
    "MissingDependencyError",
    "OutputPathError",
    "SceneError",
    "TargetError",
]


class MeshcolError(Exception):
    """Base class of every error meshcol raises on purpose.

    Parameters
    ----------
    message : str
        What is wrong, in one line, without the file name.
    path : str or os.PathLike, optional
        The file at fault; it prefixes the message.
    """

    def __init__(self, message: str, path: str | os.PathLike[str] | None = None) -> None:
        self.message = message
        self.path = None if path is None else os.fspath(path)
        super().__init__(f"{self.path}: {message}" if self.path is not None else message)

    def __reduce__(self) -> tuple[Any, ...]:
        # Pickled as (message, path), not the joined text: an error raised in a worker
        # process (``--executor``) reaches the caller as it was raised.
        return (type(self), (self.message, self.path))


class InputFileError(MeshcolError, ValueError):
    """An input file is missing, unreadable, or of an unknown type."""


class InvalidMeshError(MeshcolError, ValueError):
    """A mesh is unusable: empty, non-finite, or otherwise broken."""


class SceneError(MeshcolError, ValueError):
    """A scene manifest is malformed or refers to something that does not exist."""


class MissingDependencyError(MeshcolError, ImportError):
    """An optional dependency needed for the requested feature is not installed."""


class OutputPathError(MeshcolError, ValueError):
    """An output would replace an input, or two outputs are one file: nothing is written."""


class TargetError(MeshcolError, ValueError):
    """An engine target profile is unknown, malformed, or has an unknown or ill-typed key."""


class TooManyPairsError(MeshcolError, ValueError):
    """A scene has more candidate pairs than a run may hold (``--max-pairs``): nothing is
    measured or written."""
