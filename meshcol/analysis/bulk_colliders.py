"""The colliders of a scene of plain bodies, built as arrays: what the per-body builders of
:mod:`meshcol.analysis.colliders` give, bit for bit, without Python work per body beyond one
pass that reads its fields.

A scene qualifies when every body is one part (no ``Body.parts``) and either a primitive or a
mesh whose collider is its hull (kind ``hull``, or ``mesh`` when the caller's ``mesh_parts``
is ``hull``), and no body is an Unreal collision part (the caller's :func:`split_ucx` found
none): 100,000 unique assets from a manifest. Identical geometry is still packed once, in the
order the body loop meets it, by an exact comparison of the vertex bits (what the geometry key
compares) instead of a digest per body; every mesh hull comes from one batched core call
(:meth:`meshcol.collision.shapes.ConvexSet.from_point_slices`) over the packed vertices.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import attrgetter

import numpy as np

from meshcol.collision.point_sets import point_set_fingerprints
from meshcol.collision.shapes import ConvexSet, _item
from meshcol.io.column_bodies import MeshBodies
from meshcol.types import Body, HalfSpace
from meshcol.vocabulary import HALF_SPACE_COLLIDER

__all__ = ["bulk_colliders"]

_PARTS, _PRIMITIVE = attrgetter("parts"), attrgetter("primitive")
_COLLIDER, _VERTICES = attrgetter("collider"), attrgetter("vertices")


def bulk_colliders(
    bodies: Sequence[Body], kind: str, mesh_parts: str
) -> tuple[list[str], ConvexSet, np.ndarray] | None:
    """Per body its reported kind, the unique shapes in the order the body loop packs them,
    and each body's row among them; None when a body needs the per-body builders (several
    parts, a collider other than its hull) or the geometry does not pack as points.

    Parameters
    ----------
    bodies : sequence of Body
        After :func:`meshcol.analysis.colliders.split_ucx`, which found no ``UCX_`` part.
    kind : str
        The run's default collider kind.
    mesh_parts : {"hull", "triangles"}
        What stands for a ``mesh`` body (hull: its hull, as a ``hull`` body).
    """
    hulled = {"hull", "mesh"} if mesh_parts == "hull" else {"hull"}
    if isinstance(bodies, MeshBodies):
        return _mesh_columns(bodies, kind, hulled)
    # each field read for all bodies at once (a C loop each), then one pass where needed
    if any(map(_PARTS, bodies)):
        return None
    n = len(bodies)
    given = list(map(_PRIMITIVE, bodies))
    kinds = [collider or kind for collider in map(_COLLIDER, bodies)]
    first = np.arange(n, dtype=np.int64)  # the first body of the same shape
    if given.count(None) == n:  # no primitive: every body a mesh
        meshes, primitive_rows = list(range(n)), []
    else:
        primitive_rows = [i for i, p in enumerate(given) if p is not None]
        meshes = [i for i, p in enumerate(given) if p is None]
        primitives: dict[object, int] = {}
        for i in primitive_rows:
            kinds[i] = HALF_SPACE_COLLIDER if isinstance(given[i], HalfSpace) else "primitive"
            first[i] = primitives.setdefault(given[i], i)
    if not {kinds[i] for i in meshes} <= hulled:
        return None
    arrays = (
        [bodies[i].vertices for i in meshes] if primitive_rows else list(map(_VERTICES, bodies))
    )
    if len(set(map(id, arrays))) != len(arrays):
        # instances share their file's array: one comparison per array
        same_array: dict[int, int] = {}
        owners = [same_array.setdefault(id(v), i) for i, v in zip(meshes, arrays)]
        first[meshes] = owners
        kept = [k for k, (i, owner) in enumerate(zip(meshes, owners)) if owner == i]
        meshes, arrays = [meshes[k] for k in kept], [arrays[k] for k in kept]
    mesh_rows = np.asarray(meshes, dtype=np.int64)
    packed = _packed(arrays) if meshes else (np.zeros((0, 3)), np.zeros(1, dtype=np.int64))
    if packed is None:
        return None
    return _shapes(bodies, kinds, first, mesh_rows, *packed)


def _mesh_columns(
    bodies: MeshBodies, kind: str, hulled: set[str]
) -> tuple[list[str], ConvexSet, np.ndarray] | None:
    """:func:`bulk_colliders` of mesh bodies kept as columns: the same result from the
    packed arrays of their files, with no body made."""
    kinds = [collider or kind for collider in bodies.colliders]
    if not set(kinds) <= hulled:
        return None
    # the first body of each file (its bodies share its arrays), in body order
    files, owner = np.unique(bodies.mesh, return_index=True)
    first = owner[np.searchsorted(files, bodies.mesh)]
    mesh_rows = np.sort(owner)
    objects = bodies.objects[bodies.mesh[mesh_rows]]
    offsets = np.asarray(bodies.packed.v_off, dtype=np.int64)
    points, offsets = _gather(bodies.packed.vertices, offsets, objects)
    return _shapes(bodies, kinds, first, mesh_rows, points, offsets)


def _shapes(
    bodies: Sequence[Body],
    kinds: list[str],
    first: np.ndarray,
    mesh_rows: np.ndarray,
    points: np.ndarray,
    offsets: np.ndarray,
) -> tuple[list[str], ConvexSet, np.ndarray] | None:
    """The unique shapes and each body's row among them: ``first`` the first body of the
    same array (or primitive) of each body, ``mesh_rows`` the bodies that own their mesh
    arrays, ascending, and ``points``/``offsets`` those arrays packed in that order."""
    if len(mesh_rows):
        first_mesh = _first_equal(points, offsets)
        if first_mesh is None:
            return None
        first[mesh_rows] = mesh_rows[first_mesh]
        first = first[first]  # an instance's array owner may itself repeat an earlier mesh
    # pool rows in the order the body loop meets each shape first
    unique, rows = np.unique(first, return_inverse=True)
    is_mesh = np.zeros(len(bodies), dtype=bool)
    is_mesh[mesh_rows] = True
    shape_kinds = np.zeros(len(unique), dtype=np.int8)
    params = np.zeros((len(unique), 4))
    for row in np.flatnonzero(~is_mesh[unique]).tolist():
        primitive = bodies[int(unique[row])].primitive
        shape_kinds[row], params[row], _ = _item(primitive, f"shapes[{row}]")
    unique_meshes = np.searchsorted(mesh_rows, unique[is_mesh[unique]])
    points, offsets = _gather(points, offsets, unique_meshes)
    shapes = ConvexSet.from_point_slices(shape_kinds, params, points, offsets)
    return kinds, shapes, rows.astype(np.int64, copy=False)


def _packed(arrays: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """The point sets packed ((V, 3) float64 and offsets); None when they do not pack as
    (n, 3)."""
    try:
        points = np.ascontiguousarray(np.concatenate(arrays), dtype=np.float64)
    except ValueError:
        return None
    if points.ndim != 2 or points.shape[1] != 3:
        return None
    counts = np.fromiter((len(a) for a in arrays), dtype=np.int64, count=len(arrays))
    offsets = np.zeros(len(arrays) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return points, offsets


def _first_equal(points: np.ndarray, offsets: np.ndarray) -> np.ndarray | None:
    """For each point set packed in ``points`` ((V, 3) float64, C-contiguous) by
    ``offsets``, the index of the first one with the same float64 bits (itself when none);
    None when two sets of one fingerprint differ (the per-body path keys them)."""
    counts = np.diff(offsets)
    bits = points.reshape(-1).view(np.uint64)
    n = len(counts)
    # each vertex's coordinates' bits mixed, weighed by its place in its set, summed per set
    # (cpp/include/meshcol/point_sets.hpp), on the core's threads
    fingerprint = point_set_fingerprints(points, offsets)
    # sets in order of (count, fingerprint, index): the first of each run is the first set
    order = np.lexsort((np.arange(n), fingerprint, counts))
    starts = np.ones(n, dtype=bool)
    starts[1:] = (counts[order][1:] != counts[order][:-1]) | (
        fingerprint[order][1:] != fingerprint[order][:-1]
    )
    run = np.cumsum(starts) - 1
    first = np.empty(n, dtype=np.int64)
    first[order] = order[np.flatnonzero(starts)][run]
    if not _same_bits(bits, offsets, counts, first):
        return None  # two sets of one fingerprint differ: the per-body path keys them
    return first


def _same_bits(
    bits: np.ndarray, offsets: np.ndarray, counts: np.ndarray, first: np.ndarray
) -> bool:
    """Whether every set whose ``first`` is an earlier set has the same bits as that set."""
    repeat = np.flatnonzero(first != np.arange(len(first)))
    if not len(repeat):
        return True
    size = counts[repeat] * 3
    local = np.arange(int(size.sum())) - np.repeat(np.cumsum(size) - size, size)
    mine = np.repeat(offsets[repeat] * 3, size) + local
    theirs = np.repeat(offsets[first[repeat]] * 3, size) + local
    return bool(np.array_equal(bits[mine], bits[theirs]))


def _gather(
    points: np.ndarray, offsets: np.ndarray, sets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The point sets ``sets`` (indices) packed alone, in that order: as they are when they
    are all of them in order."""
    if np.array_equal(sets, np.arange(len(offsets) - 1)):
        return points, offsets
    counts = np.diff(offsets)[sets]
    out = np.zeros(len(sets) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    local = np.arange(int(out[-1])) - np.repeat(out[:-1], counts)
    return points[np.repeat(offsets[:-1][sets], counts) + local], out
