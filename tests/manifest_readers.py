"""Switches for the tests that compare the manifest's readers: the native reader of plain
manifests (meshcol.io.scene_native) off, so a load takes the Python reader (the
columns of meshcol.io.scene_columns, or the body loop when those are off too)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import meshcol.io.scene as scene


@contextlib.contextmanager
def python_reader() -> Iterator[None]:
    """Within the block, ``load_scene`` and ``manifest_mesh_files`` never read natively."""
    saved = scene.native_scene, scene.native_manifest
    scene.native_scene = lambda source: None  # type: ignore[assignment]
    scene.native_manifest = lambda source: None  # type: ignore[assignment]
    try:
        yield
    finally:
        scene.native_scene, scene.native_manifest = saved
