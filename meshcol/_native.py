"""The one import of the native core, ``meshcol._core`` (C++17, built by scikit-build-core).

Every other module reaches the core through this one, so there is a single place where the
extension loads and where its enums are checked against the Python ones.
"""

from __future__ import annotations

from meshcol import _core as core

defaults = core.defaults

__all__ = ["core", "defaults"]
