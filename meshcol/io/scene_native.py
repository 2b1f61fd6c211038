"""A JSON manifest of static mesh and primitive bodies read natively, straight into columns.

Decoding a manifest of 1,000,000 primitive bodies with Python's json module makes a million
dicts (1.8 s) that :func:`meshcol.io.scene_columns.columns` then reads field by field (1.2 s);
one of 100,000 mesh bodies, 0.27 s and 0.2 s. The core reads the common shape of such a
manifest from its bytes into the same columns (``read_plain_manifest``,
``cpp/src/manifest_read.cpp``: 0.3 s for the million, no object per body but its name and
mesh). It only passes over documents, never rejects one: anything outside that shape (a
moving or scaled body, an escape in a string, a duplicate key, a syntax error...) returns None
here and the manifest takes the one reader and validation of :mod:`meshcol.io.scene_parse`
and :mod:`meshcol.io.scene_validate`, with their messages. What it passes, :func:`columns` of
the decoded document passes too, as equal columns to the bit
(``tests/io/test_scene_native.py``, with hypothesis-made manifests; the fuzz target
``manifest``).

:func:`native_scene` is the loader's fast path, taken when no value is near a limit (else
the body-by-body magnitude check, which needs the decoded document, decides): a manifest of
primitives whose bodies stay columns (:func:`meshcol.io.scene_columns.primitive_bodies`), or
one whose every body :func:`meshcol.io.scene_columns.bulk_bodies` builds from its columns and
its mesh files (read as :func:`meshcol.io.scene_bodies.read_mesh_files` reads them: confined
to the root, all at once). Else the loader takes the Python reader, with the files and the
bulk bodies made here (the same it would make).
"""

from __future__ import annotations

import itertools
import json
import operator
import os
from collections.abc import MutableMapping
from typing import Any, NamedTuple

import numpy as np

from meshcol.errors import MeshcolError
from meshcol.io.safe_read import read_input
from meshcol.io.scene_bodies import read_mesh_names
from meshcol.io.scene_columns import (
    Columns,
    bulk_bodies,
    manifest_meshes,
    mesh_bodies,
    near_limits,
    primitive_bodies,
)
from meshcol.io.scene_parse import KEPT_OF_DOCUMENTS
from meshcol.io.scene_schema import (
    ORDERS,
    PRIMITIVE_FIELDS,
    PRIMITIVE_KEYS,
    PRIMITIVE_TYPES,
    SHAPES,
    TOP_FIELDS,
    VECTOR_FIELDS,
)
from meshcol.types import Body, Scene

__all__ = [
    "NativeManifest",
    "NativeScene",
    "native_columns",
    "native_manifest",
    "native_scene",
]

#: The fields the core knows a primitive by, each a bit of its ``type_fields``.
_FIELD_BITS = {"radius": 1, "length": 2, "size": 4, "semi_axes": 8}
_ORDER_WORDS = sorted(ORDERS)
_SHAPE_WORDS = sorted(SHAPES)
_WORDS = (
    list(PRIMITIVE_TYPES),
    [sum(_FIELD_BITS[f] for f in PRIMITIVE_KEYS[t] - {"type"}) for t in PRIMITIVE_TYPES],
    _ORDER_WORDS,
    _SHAPE_WORDS,
)
# The core reads exactly these fields; a field added to the schema must be taught to it first.
if {"type", *_FIELD_BITS} != PRIMITIVE_FIELDS or {"units", "duration", "bodies"} != TOP_FIELDS:
    raise ImportError("the native manifest reader does not know every field of the schema")
if VECTOR_FIELDS[0] != "position":  # pragma: no cover - the schema's first vector field
    raise ImportError("the native manifest reader reads position as the first vector field")


class NativeManifest(NamedTuple):
    """A plain manifest read natively: its columns, ``units`` and ``duration`` as the decoded
    document gives them (None where absent; the duration an int when written as one)."""

    columns: Columns
    units: str | None
    duration: int | float | None


def native_columns(data: bytes) -> NativeManifest | None:
    """The columns of the manifest bytes ``data`` when the core reads them as a plain manifest
    of mesh and primitive bodies, equal to :func:`meshcol.io.scene_columns.columns` of the
    decoded document; else None (the document takes the Python reader)."""
    from meshcol._native import core

    found = core.read_plain_manifest(data, *_WORDS)
    if found is None:
        return None
    names: list[str] = found["names"]
    n = len(names)
    kinds, meshes = found["kinds"], found["meshes"]
    shape_codes = found["shapes"]
    if (shape_codes < 0).all():
        shapes: list[str | None] = [None] * n
    else:  # code -1 picks the last entry, None
        shapes = np.array([*_SHAPE_WORDS, None], dtype=object)[shape_codes].tolist()
    orders = np.array(_ORDER_WORDS, dtype=object)[found["orders"]].tolist()
    columns = Columns(
        names=names,
        meshes=[None] * n if meshes is None else meshes,
        shapes=shapes,
        primitive=np.ones(n, dtype=bool) if meshes is None else kinds >= 0,
        moving=np.zeros(n, dtype=bool),
        scaled=np.zeros(n, dtype=bool),
        vectors={"position": found["positions"]} if found["position_count"] else {},
        scale=None,
        rotation=found["rotation"],
        quaternion=found["quaternions"],
        euler=found["euler"],
        orders=orders,
        primitive_type=kinds,
        primitive_lengths=found["lengths"],
    )
    duration = found["duration"]
    return NativeManifest(
        columns, found["units"], None if duration is None else json.loads(duration)
    )


def native_manifest(source: str) -> NativeManifest | None:
    """:func:`native_columns` of the JSON manifest ``source`` (read capped, as every manifest
    is); None for any other file or one that cannot be read (the Python reader says why).
    The last one read is kept (by absolute path and bytes): a run asks twice (the output
    check, then the loading)."""
    if not source.lower().endswith(".json") or not os.path.isfile(source):
        return None
    try:
        data = read_input(source, "manifest")
    except MeshcolError:
        return None
    key = os.path.abspath(source)
    if _KEPT[:2] == [key, data]:
        return _KEPT[2]
    found = native_columns(data)
    _KEPT[:] = [key, data, found]
    return found


# The last manifest read natively: its absolute path, its bytes and what it gave (emptied by
# forget_documents: a list's own clear, no function of this module in check's walk).
_KEPT: list[Any] = []
KEPT_OF_DOCUMENTS.append(_KEPT.clear)


class NativeScene(NamedTuple):
    """What the native read of a manifest made: its scene when every body is built from the
    columns (else None), and the mesh files and bulk bodies made on the way (None when none
    were: a manifest of primitives), for the Python reader to take up."""

    scene: Scene | None
    files: MutableMapping[str, list[Body]] | None
    bulk: list | None


def native_scene(source: str) -> NativeScene | None:
    """The scene of the manifest ``source`` when the core reads it as a plain manifest with
    every value plainly within its limit, and every body is built from its columns: the scene
    the Python reader makes of it. Else None, or the files and bulk bodies made before it was
    found short: the manifest takes that reader.

    Raises
    ------
    OutsideRootError
        A mesh path resolves outside the root (:func:`meshcol.io.paths.confine_all`): the
        Python reader's first error too, at the same point (the validation and the magnitude
        check before it pass any manifest read here).
    """
    found = native_manifest(source)
    if found is None or near_limits(found.columns, found.duration).any():
        return None
    columns = found.columns
    bodies = primitive_bodies(columns, source)
    if bodies is not None:
        scene = Scene(bodies=bodies, units=found.units, source=source, duration=found.duration)
        return NativeScene(scene, None, None)
    if columns.primitive.all():  # primitives refused by the body loop (a name twice...)
        return None
    files = read_mesh_names(manifest_meshes(columns), source)
    meshes = mesh_bodies(columns, source, files)
    if meshes is not None:  # every body a static mesh body of a packed file: columns
        scene = Scene(bodies=meshes, units=found.units, source=source, duration=found.duration)
        return NativeScene(scene, files, None)
    bulk = bulk_bodies(columns, source, files)
    if bulk is None or any(map(operator.is_, bulk, itertools.repeat(None))):
        return NativeScene(None, files, bulk)  # some bodies built one by one: the document
    scene = Scene(bodies=tuple(bulk), units=found.units, source=source, duration=found.duration)
    return NativeScene(scene, files, bulk)
