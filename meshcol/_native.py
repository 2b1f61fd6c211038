"""The one import of the native core, ``meshcol._core`` (C++17, built by scikit-build-core).

Every other module reaches the core through this one, so there is a single place where the
extension loads. The core binds its enums (``core.Status``, ``core.TimeOfImpactStatus``,
``core.ShapeKind``); ``tests/test_native.py`` checks that the Python IntEnums of
:mod:`meshcol.types` and :mod:`meshcol.collision.shapes` match them exactly.
"""

from __future__ import annotations

from meshcol import _core as core

defaults = core.defaults

__all__ = ["core", "defaults"]
