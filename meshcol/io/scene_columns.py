"""The common scene manifest as columns: recognised column by column and built in bulk.

A manifest of 300,000 bodies is mostly bodies of one shape: a name, a mesh file, a position,
perhaps a rotation, a scale and a collider shape. :func:`columns` recognises such a document
in C loops over its columns (never Python per body) and returns its fields as arrays
(:class:`Columns`); anything it cannot pass that way (an unknown field, a number beyond a
double, any problem) it leaves to the body-by-body check of :mod:`meshcol.io.scene_validate`.
It passes only documents that check passes (``tests/test_scene_columns.py``).

:func:`bulk_bodies` then builds the static, unscaled bodies of one-object files together, to
the bit what the body loop of :mod:`meshcol.io.scene_bodies` builds.
"""

from __future__ import annotations

import collections
import dataclasses
import itertools
import math
import operator
import os
from collections.abc import MutableMapping, Sequence
from typing import Any

import numpy as np

from meshcol.io.column_bodies import MeshBodies
from meshcol.io.mesh_read import MAX_COORDINATE, MeshFiles, lone_objects
from meshcol.io.paths import joined_paths
from meshcol.io.scene_bodies import AXES
from meshcol.io.scene_primitives import PrimitiveBodies, primitive_of
from meshcol.io.scene_schema import (
    BODY_FIELDS,
    MAX_TURN,
    ORDERS,
    PRIMITIVE_KEYS,
    PRIMITIVE_TRIPLES,
    PRIMITIVE_TYPES,
    SHAPES,
    VECTOR_FIELDS,
    plain_top,
)
from meshcol.types import Body

__all__ = [
    "Columns",
    "bulk_bodies",
    "columns",
    "euler_matrices",
    "manifest_meshes",
    "mesh_bodies",
    "near_limits",
    "primitive_bodies",
    "quaternion_matrices",
]


@dataclasses.dataclass(frozen=True, eq=False)
class Columns:
    """The bodies of a plainly valid manifest as columns, index-aligned with its bodies (n):
    what the loader's bulk path and the magnitude check read instead of the bodies.

    Attributes
    ----------
    names, meshes, shapes : list
        Per body (``meshes[i]`` and ``shapes[i]`` None where absent).
    primitive, moving, scaled : (n,) bool
        A primitive body; one with an end pose or a velocity; one with a scale other than 1.
    primitive_type : (n,) int8
        The index of a primitive body's type in :data:`PRIMITIVE_TYPES`, -1 elsewhere.
    primitive_lengths : (n, 3) float64
        A primitive body's lengths as the manifest gives them: a box's size, a sphere's
        ``(radius, 0, 0)``, a capsule's or cylinder's ``(radius, length, 0)``, an
        ellipsoid's semi-axes; zeros elsewhere.
    vectors : dict of str to (n, 3) float64
        ``position``, ``end_position``, ``velocity``, ``angular_velocity``, zeros where
        absent; a field no body has is not in it.
    scale : (n, 3) float64 or None
        Ones where absent; None when no body has one.
    rotation : (n,) int8
        0 none, 1 quaternion, 2 Euler angles.
    quaternion : (nq, 4) float64
        The quaternions of the bodies with ``rotation == 1``, in order.
    euler, orders : (ne, 3) float64, list of str
        The angles and orders of the bodies with ``rotation == 2``, in order.
    """

    names: list[str]
    meshes: list[str | None]
    shapes: list[str | None]
    primitive: np.ndarray
    moving: np.ndarray
    scaled: np.ndarray
    vectors: dict[str, np.ndarray]
    scale: np.ndarray | None
    rotation: np.ndarray
    quaternion: np.ndarray
    euler: np.ndarray
    orders: list[str]
    primitive_type: np.ndarray
    primitive_lengths: np.ndarray


_NUMBER_TYPES = frozenset({int, float})
_QUATERNION_KEYS = frozenset({"quaternion"})
_EULER_KEYS = frozenset({"euler_deg", "order"})
_MOTION_FIELDS = ("end_position", "end_rotation", "velocity", "angular_velocity")


class _Unplain(Exception):
    """The document is not of the common shape: the body-by-body check decides."""


class _Table:
    """The bodies (dicts) of a manifest, read a field at a time."""

    def __init__(self, bodies: list) -> None:
        if set(map(type, bodies)) != {dict}:
            raise _Unplain
        layouts: dict[frozenset, int] = {}
        # counted by key tuple first (C loops; a frozenset a body costs twice as much)
        for ordered, count in collections.Counter(map(tuple, bodies)).items():
            layout = frozenset(ordered)
            layouts[layout] = layouts.get(layout, 0) + count
        for keys in layouts:
            if not keys <= BODY_FIELDS or "name" not in keys:
                raise _Unplain
            if ("mesh" in keys) == ("primitive" in keys):
                raise _Unplain
        self.bodies = bodies
        self.n = len(bodies)
        self.count = {f: sum(c for keys, c in layouts.items() if f in keys) for f in BODY_FIELDS}

    def column(self, field: str) -> tuple[list, np.ndarray | None]:
        """The values of the bodies that have ``field``, and which those are (None: all)."""
        if self.count[field] == self.n:
            return list(map(operator.itemgetter(field), self.bodies)), None
        there = list(map(operator.contains, self.bodies, itertools.repeat(field)))
        values = list(map(operator.itemgetter(field), itertools.compress(self.bodies, there)))
        return values, np.array(there, dtype=bool).reshape(self.n)

    def spread_list(self, values: list, mask: np.ndarray | None) -> list:
        """``values`` of the bodies ``mask`` selects at their places, None elsewhere."""
        if mask is None:
            return values
        found = iter(values)
        return [next(found) if there else None for there in mask.tolist()]

    def present(self, field: str) -> np.ndarray:
        """(n,) bool: the bodies that have ``field``."""
        if self.count[field] in (0, self.n):
            return np.full(self.n, self.count[field] == self.n)
        return self.column(field)[1]  # type: ignore[return-value]

    def strings(self, field: str, allowed: frozenset | None = None) -> list:
        """The non-empty strings of ``field`` (of ``allowed``), None where absent."""
        if not self.count[field]:
            return [None] * self.n
        values, mask = self.column(field)
        if set(map(type, values)) != {str} or "" in values:
            raise _Unplain
        if allowed is not None and not set(values) <= allowed:
            raise _Unplain
        return self.spread_list(values, mask)


def columns(document: Any) -> Columns | None:
    """The columns of ``document`` when it is plainly valid, checked column by column; None
    when it is not, or when this check cannot tell (then the body-by-body check of
    :mod:`meshcol.io.scene_validate` decides)."""
    if not plain_top(document):
        return None
    try:
        table = _Table(document["bodies"])
        names = table.strings("name")
        meshes = table.strings("mesh")
        primitive_type, primitive_lengths = _primitives(table)
        vectors = _vectors(table)
        rotation, quaternion, euler, orders = _rotations(table)
        scale, scaled = _scales(table)
        shapes = table.strings("shape", SHAPES)
    except _Unplain:
        return None
    moving = np.zeros(table.n, dtype=bool)
    for field in _MOTION_FIELDS:
        moving |= table.present(field)
    return Columns(
        names=names,
        meshes=meshes,
        shapes=shapes,
        primitive=table.present("primitive"),
        moving=moving,
        scaled=scaled,
        vectors=vectors,
        scale=scale,
        rotation=rotation,
        quaternion=quaternion,
        euler=euler,
        orders=orders,
        primitive_type=primitive_type,
        primitive_lengths=primitive_lengths,
    )


def _primitives(table: _Table) -> tuple[np.ndarray, np.ndarray]:
    """The primitive bodies' types and lengths (see :class:`Columns`), each checked as
    :func:`~meshcol.io.scene_schema.is_primitive` checks one, a type's bodies at a time."""
    kinds = np.full(table.n, -1, dtype=np.int8)
    lengths = np.zeros((table.n, 3))
    if not table.count["primitive"]:
        return kinds, lengths
    values, mask = table.column("primitive")
    if set(map(type, values)) != {dict}:
        raise _Unplain
    types = list(map(dict.get, values, itertools.repeat("type")))
    if set(map(type, types)) != {str} or not set(types) <= PRIMITIVE_KEYS.keys():
        raise _Unplain
    index = {kind: k for k, kind in enumerate(PRIMITIVE_TYPES)}
    given = np.fromiter(map(index.__getitem__, types), dtype=np.int8, count=len(types))
    rows = np.zeros((len(values), 3))
    for kind, fields in PRIMITIVE_KEYS.items():
        picked = np.flatnonzero(given == index[kind])
        group = values if len(picked) == len(values) else [values[i] for i in picked.tolist()]
        if not group:
            continue
        if set(map(len, group)) != {len(fields)}:  # with every field there: exactly them
            raise _Unplain
        try:
            if kind in PRIMITIVE_TRIPLES:
                field = PRIMITIVE_TRIPLES[kind]
                block, width = _rows(list(map(operator.itemgetter(field), group)), 3), 3
            else:
                block, width = np.zeros((len(group), 3)), 1 if kind == "sphere" else 2
                block[:, 0] = _numbers(list(map(operator.itemgetter("radius"), group)))
                if width == 2:
                    block[:, 1] = _numbers(list(map(operator.itemgetter("length"), group)))
        except KeyError:
            raise _Unplain from None
        if not (block[:, :width] > 0).all():
            raise _Unplain
        rows[picked] = block
    kinds = _spread(given.reshape(-1, 1), mask, table.n, -1).astype(np.int8).reshape(table.n)
    return kinds, _spread(rows, mask, table.n, 0.0)


def _rows(values: list, width: int) -> np.ndarray:
    """``values``, lists of ``width`` finite JSON numbers each, as (len, width) float64
    (bool is not a number; an integer beyond a double is left to the body-by-body check)."""
    if not values:
        return np.zeros((0, width))
    if set(map(type, values)) != {list} or set(map(len, values)) != {width}:
        raise _Unplain
    if not set(map(type, itertools.chain.from_iterable(values))) <= _NUMBER_TYPES:
        raise _Unplain
    try:
        rows = np.array(values, dtype=np.float64).reshape(-1, width)
    except OverflowError:
        raise _Unplain from None
    if not np.isfinite(rows).all():
        raise _Unplain
    return rows


def _numbers(values: list) -> np.ndarray:
    """``values``, finite JSON numbers, as (len,) float64 (as :func:`_rows` takes them)."""
    if not set(map(type, values)) <= _NUMBER_TYPES:
        raise _Unplain
    try:
        numbers = np.array(values, dtype=np.float64).reshape(len(values))
    except OverflowError:
        raise _Unplain from None
    if not np.isfinite(numbers).all():
        raise _Unplain
    return numbers


def _spread(rows: np.ndarray, mask: np.ndarray | None, n: int, fill: float) -> np.ndarray:
    """Rows of the bodies ``mask`` selects (all when None) in an (n, width) array."""
    if mask is None:
        return rows
    out = np.full((n, rows.shape[1]), fill)
    out[mask] = rows
    return out


def _vectors(table: _Table) -> dict[str, np.ndarray]:
    vectors = {}
    for field in VECTOR_FIELDS:
        if table.count[field]:
            values, mask = table.column(field)
            vectors[field] = _spread(_rows(values, 3), mask, table.n, 0.0)
    return vectors


def _rotations(table: _Table) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """``rotation``'s kinds, quaternions, angles and orders (``end_rotation`` checked)."""
    n = table.n
    rotation = np.zeros(n, dtype=np.int8)
    quaternion, euler, orders = np.zeros((0, 4)), np.zeros((0, 3)), []
    for field in ("rotation", "end_rotation"):
        if not table.count[field]:
            continue
        values, mask = table.column(field)
        if set(map(type, values)) != {dict}:
            raise _Unplain
        is_quaternion = [r.keys() == _QUATERNION_KEYS for r in values]
        if not all(q or r.keys() == _EULER_KEYS for q, r in zip(is_quaternion, values)):
            raise _Unplain
        q_rows = _rows([r["quaternion"] for r in values if len(r) == 1], 4)
        e_values = [r for r in values if len(r) == 2]
        e_rows = _rows([r["euler_deg"] for r in e_values], 3)
        e_orders = [r["order"] for r in e_values]
        if not set(map(type, e_orders)) <= {str} or not set(e_orders) <= ORDERS:
            raise _Unplain
        if field == "rotation":
            kinds = np.where(np.array(is_quaternion, dtype=bool), 1, 2).astype(np.int8)
            rotation = _spread(kinds.reshape(-1, 1), mask, n, 0).astype(np.int8).reshape(n)
            quaternion, euler, orders = q_rows, e_rows, e_orders
    return rotation, quaternion, euler, orders


def _scales(table: _Table) -> tuple[np.ndarray | None, np.ndarray]:
    """The (n, 3) scales (None when no body has one) and which bodies are scaled."""
    if not table.count["scale"]:
        return None, np.zeros(table.n, dtype=bool)
    values, mask = table.column("scale")
    if not set(map(type, values)) <= {int, float, list}:
        raise _Unplain
    is_list = [type(v) is list for v in values]
    uniform = [v for v, listed in zip(values, is_list) if not listed]
    try:
        factors = np.array(uniform, dtype=np.float64)
    except OverflowError:
        raise _Unplain from None
    rows = _rows([v for v in values if type(v) is list], 3)
    if not (np.isfinite(factors).all() and (factors > 0).all() and (rows > 0).all()):
        raise _Unplain
    given = np.empty((len(values), 3))
    listed = np.array(is_list, dtype=bool).reshape(len(values))
    given[listed] = rows
    given[~listed] = factors[:, None]
    scale = _spread(given, mask, table.n, 1.0)
    return scale, (scale != 1.0).any(axis=1)


def near_limits(found: Columns, duration: float | None) -> np.ndarray:
    """(n,) bool: the bodies the magnitude check must look at one by one: every body with a
    value (a primitive's lengths included) within a factor of two of a limit (a margin, so
    rounding an integer to a double never hides one beyond it)."""
    near = np.zeros(len(found.names), dtype=bool)
    lengths = [
        found.vectors.get("position"),
        found.vectors.get("end_position"),
        found.scale,
        found.primitive_lengths,
    ]
    for values in lengths:
        if values is not None:
            near |= (np.abs(values) >= 0.5 * MAX_COORDINATE).any(axis=1)
    if found.scale is not None:
        near |= (found.scale <= 2.0 / MAX_COORDINATE).any(axis=1)
    if duration is not None:
        with np.errstate(over="ignore"):
            for name, limit in (("velocity", MAX_COORDINATE), ("angular_velocity", MAX_TURN)):
                values = found.vectors.get(name)
                if values is not None:
                    near |= np.abs(values).max(axis=1) * float(duration) >= 0.5 * limit
    return near


# --- bodies in bulk ------------------------------------------------------------------------------


def bulk_bodies(found: Columns, source: str, files: MutableMapping[str, list[Body]]) -> list | None:
    """The manifest's common bodies, built together: index-aligned with its bodies, a Body
    for each static, unscaled mesh body whose file holds one object without a transform, and
    each static, unscaled primitive body, whose world coordinates are plainly within the
    limit; None for the others (built one by one). None in all when names repeat (the body
    loop says which).

    Each body is what the body loop would build, to the bit: the same rotation arithmetic
    (:func:`quaternion_matrices`, :func:`euler_matrices`), the same vertex and face arrays
    of its file (a primitive: the same primitive, its tessellation left to its first use),
    the same bound of its world coordinates as its world check.
    """
    names = found.names
    n = len(names)
    if len(set(names)) != n:
        return None
    paths, arrays, reaches, slot = _plain_objects(found, source, files)
    # each body's mesh among the files' (the last slot, inf reach, for a primitive)
    mesh_of = np.fromiter(map(slot.__getitem__, found.meshes), dtype=np.int64, count=n)
    common, poses = _common(found, reaches[mesh_of])
    out: list[Body | None] = [None] * n
    shapes = found.shapes
    kinds, lengths = found.primitive_type.tolist(), found.primitive_lengths.tolist()
    plain = Body.plain
    primitive = found.primitive
    pose_of = list(poses)  # one view per body, made in one C loop
    for i in np.flatnonzero(common & primitive).tolist():
        primitive_i = primitive_of(kinds[i], lengths[i])
        out[i] = plain(names[i], source, None, None, pose_of[i], primitive_i, shapes[i])
    rows = np.flatnonzero(common & ~primitive)
    for i, k in zip(rows.tolist(), mesh_of[rows].tolist()):
        vertices, faces = arrays[k]  # a common body's file is lone
        out[i] = plain(names[i], paths[k], vertices, faces, pose_of[i], None, shapes[i])
    return out


def mesh_bodies(
    found: Columns, source: str, files: MutableMapping[str, list[Body]]
) -> MeshBodies | None:
    """The manifest's bodies as :class:`MeshBodies` (no Python object per body) when every
    one is a mesh body that :func:`bulk_bodies` would build from a file the core read and
    packed, and names are unique; else None (the bodies are built as objects)."""
    n = len(found.names)
    if not n or found.primitive.any() or not isinstance(files, MeshFiles) or None in found.meshes:
        return None
    paths, keys, slot = _mesh_slots(found, source)
    objects = files.packed_positions(keys)
    if objects is None or files.packed is None or len(set(found.names)) != n:
        return None
    mesh = np.fromiter(map(slot.__getitem__, found.meshes), dtype=np.int64, count=n)
    # the reach of the world check, as _plain_objects gives it for a packed file
    common, poses = _common(found, (files.packed.largest()[objects] * _REACH)[mesh])
    if not common.all():
        return None
    return MeshBodies(found.names, paths, mesh, objects, files.packed, poses, found.shapes)


def primitive_bodies(found: Columns, source: str) -> PrimitiveBodies | None:
    """The manifest's bodies as :class:`PrimitiveBodies` (no Python object per body) when
    every one is a primitive that :func:`bulk_bodies` would build and names are unique;
    else None (the bodies are built as objects)."""
    n = len(found.names)
    if not n or not found.primitive.all() or len(set(found.names)) != n:
        return None
    common, poses = _common(found, np.full(n, np.inf))
    if not common.all():
        return None
    kinds = np.ascontiguousarray(found.primitive_type, dtype=np.int8)
    lengths = np.ascontiguousarray(found.primitive_lengths, dtype=np.float64)
    return PrimitiveBodies(found.names, source, kinds, lengths, poses, found.shapes)


def _common(found: Columns, reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n,) bool: the bodies :func:`bulk_bodies` builds (static, unscaled, a nonzero
    quaternion, plainly within the limit: ``reach`` bounds a mesh body's |v|, a primitive's
    is its own); and every body's (n, 4, 4) start pose."""
    n = len(found.names)
    primitive = found.primitive
    reach[primitive] = _primitive_reach(found.primitive_type, found.primitive_lengths)[primitive]
    position = found.vectors.get("position", np.zeros((n, 3)))
    common = ~found.moving & ~found.scaled
    common &= reach + np.abs(position).max(axis=1, initial=0.0) <= MAX_COORDINATE
    return common, _poses(found, position, common)


def _primitive_reach(kinds: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """A bound of |v| over each primitive (the radius of a ball about its origin that holds
    it, and so its inscribed tessellation), a little over: the world check's reach."""
    radius, length = lengths[:, 0], lengths[:, 1]
    box = 0.5 * np.sqrt((lengths * lengths).sum(axis=1))
    reach = np.select(
        [kinds == _SPHERE, kinds == _BOX, kinds == _CAPSULE, kinds == _ELLIPSOID],
        [radius, box, radius + 0.5 * length, lengths.max(axis=1)],
        np.hypot(radius, 0.5 * length),
    )
    return reach * (1.0 + 1e-12)


_SPHERE, _BOX, _CAPSULE, _ELLIPSOID = (
    PRIMITIVE_TYPES.index(k) for k in ("sphere", "box", "capsule", "ellipsoid")
)


def manifest_meshes(found: Columns) -> list[str]:
    """The mesh names of a manifest's columns, each once, in order of first use."""
    if found.primitive.all():
        return []
    return [mesh for mesh in dict.fromkeys(found.meshes) if mesh is not None]


def _plain_objects(
    found: Columns, source: str, files: MutableMapping[str, list[Body]]
) -> tuple[list[str], list[Any], np.ndarray, dict[str | None, int]]:
    """Of each mesh name, in order of first use: its path, ``(vertices, faces)`` of its
    file's one object without a transform (None: the body loop builds its bodies), and the
    reach of the world check, sqrt(3) max |v| (inf for the others); one more reach, inf, for
    no mesh; and each name's place among them (None's is the last). Per file, but in one
    numpy pass for all (:func:`meshcol.io.mesh_read.lone_objects`)."""
    paths, keys, slot = _mesh_slots(found, source)
    lone, largest, arrays = lone_objects(files, keys)
    reaches = np.full(len(keys) + 1, math.inf)
    reaches[:-1][lone] = largest[lone] * _REACH
    return paths, arrays, reaches, slot


#: A bound of |v| over a file's vertices turned by any rotation, from their largest |coordinate|.
_REACH = math.sqrt(3.0)


def _mesh_slots(found: Columns, source: str) -> tuple[list[str], list[str], dict[str | None, int]]:
    """Of each mesh name, in order of first use: its path as the body loop joins it (a body's
    ``source``) and as its file is keyed (normalised); and each name's place among them
    (None's, for no mesh, after them)."""
    folder = os.path.dirname(source)
    meshes = manifest_meshes(found)
    slot: dict[str | None, int] = dict(zip(meshes, range(len(meshes))))
    slot[None] = len(meshes)
    return joined_paths(folder, meshes), joined_paths(folder, meshes, normalise=True), slot


def _poses(found: Columns, position: np.ndarray, common: np.ndarray) -> np.ndarray:
    """(n, 4, 4) start poses of the columns' bodies; a body with a zero quaternion leaves
    ``common`` (the body loop says what is wrong with it)."""
    n = len(found.names)
    poses = np.zeros((n, 4, 4))
    # identity rotations (the pose's own 1 too), by flat columns: poses[:, k, k] is a fancy
    # index numpy takes 0.5 s over a million poses, four column writes 0.04 s
    poses.reshape(n, 16)[:, [0, 5, 10, 15]] = 1.0
    quaternion = found.rotation == 1
    if quaternion.any():
        q = found.quaternion
        nonzero = np.abs(q).max(axis=1) > 0
        rows = np.flatnonzero(quaternion)
        common[rows[~nonzero]] = False
        poses[rows[nonzero], :3, :3] = quaternion_matrices(q[nonzero])
    euler = found.rotation == 2
    if euler.any():
        poses[np.flatnonzero(euler), :3, :3] = euler_matrices(found.euler, found.orders)
    poses[:, :3, 3] = position
    return poses


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """:func:`meshcol.io.scene_bodies.rotation_from_quaternion` of each row of ``q`` ((n, 4)
    float64, finite, none zero): (n, 3, 3), by the same operations in the same order, so to
    the same bits."""
    q = q / np.abs(q).max(axis=1, keepdims=True)
    norm = np.sqrt(q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3])
    w, x, y, z = (q[:, k] / norm for k in range(4))
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - w * z)
    out[:, 0, 2] = 2 * (x * z + w * y)
    out[:, 1, 0] = 2 * (x * y + w * z)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - w * x)
    out[:, 2, 0] = 2 * (x * z - w * y)
    out[:, 2, 1] = 2 * (y * z + w * x)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out


_QUARTER_COS = np.array([1.0, 0.0, -1.0, 0.0])
_QUARTER_SIN = np.array([0.0, 1.0, 0.0, -1.0])


def euler_matrices(angles_deg: np.ndarray, orders: Sequence[str]) -> np.ndarray:
    """:func:`meshcol.io.scene_bodies.rotation_from_euler` of each row of ``angles_deg``
    ((n, 3) float64) in its order: (n, 3, 3), the same axis rotations (math's cos and sin,
    exact at right angles) multiplied in the same order by one stacked matmul per axis, so to
    the same bits."""
    n = len(orders)
    rows = np.arange(n)
    matrix = np.tile(np.eye(3), (n, 1, 1))
    others = np.array([(1, 2), (2, 0), (0, 1)])
    by_order = {order: [AXES[letter] for letter in order] for order in set(orders)}
    axes = np.array([by_order[order] for order in orders], dtype=np.int64).reshape(n, 3)
    for step in range(3):
        axis = axes[:, step]
        # the exact cosine and sine of each angle: math.radians is one product by pi / 180
        angle = angles_deg[:, step] * (math.pi / 180.0)
        quarter = angle / (math.pi / 2)
        exact = quarter == np.round(quarter)
        # round(quarter) % 4 of an integral quarter, exactly at any size (fmod is exact)
        turns = np.mod(np.where(exact, quarter, 0.0), 4.0).astype(np.int64)
        c, s = _QUARTER_COS[turns], _QUARTER_SIN[turns]
        other = angle[~exact].tolist()
        c[~exact] = list(map(math.cos, other))  # math's, not numpy's: the same bits as one body
        s[~exact] = list(map(math.sin, other))
        i, j = others[axis].T
        turn = np.zeros((n, 3, 3))
        turn[rows, axis, axis] = 1.0
        turn[rows, i, i] = c
        turn[rows, j, j] = c
        turn[rows, i, j] = -s
        turn[rows, j, i] = s
        matrix = np.matmul(turn, matrix)
    return matrix
