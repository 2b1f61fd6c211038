"""Convex shapes and the packed :class:`ConvexSet` the native narrow phase runs on.

A shape is a primitive (:class:`Sphere`, :class:`Box`, :class:`Capsule`, :class:`Cylinder`,
exact) or a polytope, the convex hull of points (:func:`meshcol.geometry.hull.exact_hull`).
Shapes live in their local frames; queries take one rigid world-from-local pose per shape.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.arrays import as_points, as_poses
from meshcol.geometry.hull import exact_hull
from meshcol.geometry.topology import unique_rows
from meshcol.types import Body, Box, Capsule, Cylinder, Sphere

__all__ = [
    "ShapeKind",
    "Sphere",
    "Box",
    "Capsule",
    "Cylinder",
    "ConvexSet",
    "as_convex_set",
    "pack_shape",
]


class ShapeKind(enum.IntEnum):
    """Kind of a packed shape.

    Mirrors ``ShapeKind`` in ``cpp/include/meshcol/shapes.hpp`` (bound as
    ``meshcol._core.ShapeKind``; ``tests/test_native.py`` checks they match).
    """

    POLYTOPE = 0  #: convex hull of its vertices (a point, segment or polygon is valid)
    SPHERE = 1  #: params[0] radius
    BOX = 2  #: params[0:3] half extents
    CAPSULE = 3  #: params[0] radius, params[1] half length of the segment along local z
    CYLINDER = 4  #: params[0] radius, params[1] half length along local z


@dataclass
class _Packed:
    """One shape before packing: hull vertices and the data the core uses."""

    kind: int
    params: np.ndarray  # (4,)
    vertices: np.ndarray  # (n, 3)
    adjacency: list[np.ndarray]  # per vertex: local neighbour indices
    faces: np.ndarray  # (f, 3) unit outward normals
    edges: np.ndarray  # (e, 3) unit edge directions (one per parallel class)


_EMPTY3 = np.zeros((0, 3))


def _unique_directions(d: np.ndarray, signed: bool) -> np.ndarray:
    """Unit directions, one per (anti)parallel class, rounded to 12 digits for grouping."""
    if len(d) == 0:
        return _EMPTY3
    d = d / np.linalg.norm(d, axis=1)[:, None]
    if not signed:
        # Canonical sign: the first component that is clearly non-zero is positive.
        key = np.where(np.abs(d) > 1e-12, d, 0.0)
        first = np.argmax(key != 0.0, axis=1)
        sign = np.sign(key[np.arange(len(d)), first])
        d = d * np.where(sign == 0.0, 1.0, sign)[:, None]
    keys = np.round(d, 12)
    # First occurrence of each distinct key, in input order (np.unique(axis=0,
    # return_index=True) gives the same, far slower on these small arrays).
    order = np.lexsort(keys.T[::-1])
    ordered = keys[order]
    start = np.ones(len(order), dtype=bool)
    start[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    return np.ascontiguousarray(d[np.sort(order[start])])


def _adjacency_from_edges(n: int, edges: np.ndarray) -> list[np.ndarray]:
    edges, _ = unique_rows(np.sort(edges, axis=1))
    both = np.concatenate([edges, edges[:, ::-1]])
    order = np.lexsort((both[:, 1], both[:, 0]))
    both = both[order]
    counts = np.bincount(both[:, 0], minlength=n)
    lists = np.split(both[:, 1].astype(np.int32), np.cumsum(counts)[:-1])
    # Padded with the vertex itself to a multiple of four: the climb's loop over a vertex's
    # neighbours then has few distinct trip counts, which the branch predictor learns.
    return [np.concatenate([a, np.full(-len(a) % 4, i, np.int32)]) for i, a in enumerate(lists)]


def _pack_polytope(points: Any) -> _Packed:
    """Hull vertices, adjacency and SAT features of a point set."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"vertices must be (n, 3), got {pts.shape}")
    params = np.zeros(4)
    if len(pts) == 0 or not np.all(np.isfinite(pts)):
        # Kept as given: the core reports INVALID_INPUT for every pair that uses it.
        return _Packed(0, params, np.ascontiguousarray(pts), [], _EMPTY3, _EMPTY3)
    hull = exact_hull(pts)
    verts = hull.vertices
    if hull.dimension == 0:
        return _Packed(0, params, verts, [np.zeros(0, np.int32)], _EMPTY3, _EMPTY3)
    if hull.dimension == 1:
        adj = [np.array([1], np.int32), np.array([0], np.int32)]
        edges = _unique_directions(verts[1:] - verts[:1], False)
        return _Packed(0, params, verts, adj, _EMPTY3, edges)
    if hull.dimension == 2:
        n = len(verts)
        loop = np.stack([np.arange(n), (np.arange(n) + 1) % n], axis=1)
        faces = np.stack([hull.normal, -hull.normal])
        edges = _unique_directions(verts[loop[:, 1]] - verts[loop[:, 0]], False)
        return _Packed(0, params, verts, _adjacency_from_edges(n, loop), faces, edges)
    tri = hull.faces
    planes = np.round(hull.equations[:, :3], 12)
    # Edges of the triangulation (all of them drive hill climbing); those between facets of
    # different planes are the polytope's true edges (SAT).
    tri_edges, real = [], []
    for j in range(3):
        tri_edges.append(tri[:, [(j + 1) % 3, (j + 2) % 3]])
        real.append(np.any(planes != planes[hull.neighbors[:, j]], axis=1))
    all_edges = np.concatenate(tri_edges)
    sat_edges = all_edges[np.concatenate(real)]
    faces = _unique_directions(hull.equations[:, :3], True)
    edges = _unique_directions(verts[sat_edges[:, 1]] - verts[sat_edges[:, 0]], False)
    return _Packed(0, params, verts, _adjacency_from_edges(len(verts), all_edges), faces, edges)


def _pack_primitive(shape: Any) -> _Packed:
    params = np.zeros(4)
    if isinstance(shape, Sphere):
        kind, params[0] = ShapeKind.SPHERE, shape.radius
    elif isinstance(shape, Box):
        kind, params[:3] = ShapeKind.BOX, np.asarray(shape.size) / 2.0
    elif isinstance(shape, Capsule):
        kind, params[:2] = ShapeKind.CAPSULE, (shape.radius, shape.length / 2.0)
    elif isinstance(shape, Cylinder):
        kind, params[:2] = ShapeKind.CYLINDER, (shape.radius, shape.length / 2.0)
    else:  # pragma: no cover - callers dispatch
        raise TypeError(type(shape).__name__)
    return _Packed(int(kind), params, _EMPTY3, [], _EMPTY3, _EMPTY3)


_PRIMITIVES = (Sphere, Box, Capsule, Cylinder)


def pack_shape(shape: Any, name: str) -> _Packed:
    """Packs a primitive, a Body, a trimesh mesh or an (n, 3) array."""
    if isinstance(shape, _PRIMITIVES):
        return _pack_primitive(shape)
    if isinstance(shape, Body):
        if shape.primitive is not None:
            return _pack_primitive(shape.primitive)
        return _pack_polytope(shape.vertices)
    if hasattr(shape, "vertices") and hasattr(shape, "faces"):  # trimesh.Trimesh and alike
        return _pack_polytope(np.asarray(shape.vertices))
    try:
        arr = np.asarray(shape, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a Sphere, Box, Capsule, Cylinder, mesh or (n, 3) array, "
            f"got {type(shape).__name__}"
        ) from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be (n, 3), got {arr.shape}")
    return _pack_polytope(arr)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


class ConvexSet:
    """A packed set of H convex shapes, each in its local frame.

    Attributes (read-only numpy arrays)
    -----------------------------------
    vertices : (V, 3) float64
        Hull vertices of the polytopes, local frames; shape h owns
        ``vertices[offsets[h]:offsets[h + 1]]`` (primitives own none).
    offsets : (H + 1,) int64
    kinds : (H,) int8
        :class:`ShapeKind` of each shape.
    params : (H, 4) float64
        Sphere ``[radius]``; box ``[hx, hy, hz]`` half extents; capsule
        ``[radius, half_length]``; cylinder ``[radius, half_length]`` (along local z).
    adjacency_offsets : (V + 1,) int64, adjacency : (K,) int32
        Hull vertex adjacency (CSR): the neighbours of vertex ``i`` (global row) are the
        local indices ``adjacency[adjacency_offsets[i]:adjacency_offsets[i + 1]]``, padded
        with ``i`` itself to a multiple of four entries (the core's hill climbing then runs
        in fixed blocks of four; a vertex never beats itself).
    face_offsets : (H + 1,) int64, face_normals : (F, 3) float64
        Outward unit face normals (one per plane) of each polytope, for exact SAT.
    edge_offsets : (H + 1,) int64, edge_directions : (E, 3) float64
        Unit edge directions (one per parallel class) of each polytope, for exact SAT.

    Notes
    -----
    Build with :meth:`from_vertices`, :meth:`from_shapes`, :meth:`from_meshes` or
    :meth:`concatenate`. Polytope vertices are reduced to the convex hull's vertices
    (qhull); flat inputs (a point, a segment, a polygon) are valid shapes. A shape with
    NaN/inf coordinates or no vertices is kept: queries report ``Status.INVALID_INPUT`` for
    its pairs.
    """

    _FIELDS = (
        "vertices",
        "offsets",
        "kinds",
        "params",
        "adjacency_offsets",
        "adjacency",
        "face_offsets",
        "face_normals",
        "edge_offsets",
        "edge_directions",
    )

    vertices: np.ndarray
    offsets: np.ndarray
    kinds: np.ndarray
    params: np.ndarray
    adjacency_offsets: np.ndarray
    adjacency: np.ndarray
    face_offsets: np.ndarray
    face_normals: np.ndarray
    edge_offsets: np.ndarray
    edge_directions: np.ndarray

    def __init__(self, **arrays: np.ndarray) -> None:
        from meshcol._native import core

        for name in self._FIELDS:
            setattr(self, name, _readonly(arrays[name]))
        self._core = core.PackedConvexSet(
            self.vertices,
            self.offsets,
            self.kinds,
            self.params,
            self.adjacency_offsets,
            self.adjacency,
            self.face_offsets,
            self.face_normals,
            self.edge_offsets,
            self.edge_directions,
        )

    def __len__(self) -> int:
        return len(self.kinds)

    def __repr__(self) -> str:
        return f"ConvexSet({len(self)} shapes, {len(self.vertices)} vertices)"

    @classmethod
    def _from_packed(cls, packed: Sequence[_Packed]) -> ConvexSet:
        def offsets(counts: Iterable[int]) -> np.ndarray:
            return np.concatenate([[0], np.cumsum(list(counts), dtype=np.int64)]).astype(np.int64)

        def stack(items: list[np.ndarray]) -> np.ndarray:
            return np.concatenate(items).astype(np.float64) if items else _EMPTY3.copy()

        adjacency_lists = [
            (a if len(a) else [np.zeros(0, np.int32)] * len(p.vertices))
            for p, a in ((p, p.adjacency) for p in packed)
        ]
        flat = [x for lst in adjacency_lists for x in lst]
        return cls(
            vertices=stack([p.vertices.reshape(-1, 3) for p in packed]),
            offsets=offsets(len(p.vertices) for p in packed),
            kinds=np.array([p.kind for p in packed], dtype=np.int8),
            params=np.array([p.params for p in packed], dtype=np.float64).reshape(-1, 4),
            adjacency_offsets=offsets(len(x) for x in flat),
            adjacency=(np.concatenate(flat).astype(np.int32) if flat else np.zeros(0, np.int32)),
            face_offsets=offsets(len(p.faces) for p in packed),
            face_normals=stack([p.faces for p in packed]),
            edge_offsets=offsets(len(p.edges) for p in packed),
            edge_directions=stack([p.edges for p in packed]),
        )

    @classmethod
    def from_vertices(cls, vertex_lists: Sequence[Any]) -> ConvexSet:
        """Convex hulls of point sets.

        Parameters
        ----------
        vertex_lists : sequence of (n_i, 3) float
            Points of each shape in its local frame (a point, segment and polygon are
            valid).
        """
        return cls._from_packed(
            [_pack_polytope(as_points(v, f"vertex_lists[{i}]")) for i, v in enumerate(vertex_lists)]
        )

    @classmethod
    def from_shapes(cls, shapes: Sequence[Any], names: Sequence[str] | None = None) -> ConvexSet:
        """Primitives (:class:`Sphere`, :class:`Box`, :class:`Capsule`, :class:`Cylinder`),
        :class:`meshcol.types.Body` objects, meshes and (n, 3) point arrays (convex hulls), in
        any mix; ``names`` (default ``shapes[i]``) name them in errors."""
        labels = names if names is not None else [f"shapes[{i}]" for i in range(len(shapes))]
        return cls._from_packed([pack_shape(s, n) for s, n in zip(shapes, labels)])

    @classmethod
    def from_meshes(cls, meshes: Sequence[Any]) -> ConvexSet:
        """Convex hulls of ``trimesh.Trimesh`` meshes or :class:`meshcol.types.Body`
        objects, in their local frames (a Body with a primitive uses the primitive)."""
        return cls._from_packed([pack_shape(m, f"meshes[{i}]") for i, m in enumerate(meshes)])

    @classmethod
    def concatenate(cls, *sets: ConvexSet) -> ConvexSet:
        """One set holding the shapes of ``sets`` in order."""
        if not sets:
            return cls._from_packed([])

        def offsets(name: str, sizes: str) -> np.ndarray:
            parts, base = [np.zeros(1, np.int64)], 0
            for s in sets:
                o = getattr(s, name)
                parts.append(o[1:] + base)
                base += len(getattr(s, sizes))
            return np.concatenate(parts)

        return cls(
            vertices=np.concatenate([s.vertices for s in sets]),
            offsets=offsets("offsets", "vertices"),
            kinds=np.concatenate([s.kinds for s in sets]),
            params=np.concatenate([s.params for s in sets]),
            adjacency_offsets=offsets("adjacency_offsets", "adjacency"),
            adjacency=np.concatenate([s.adjacency for s in sets]),
            face_offsets=offsets("face_offsets", "face_normals"),
            face_normals=np.concatenate([s.face_normals for s in sets]),
            edge_offsets=offsets("edge_offsets", "edge_directions"),
            edge_directions=np.concatenate([s.edge_directions for s in sets]),
        )

    def take(self, indices: Any) -> ConvexSet:
        """A set of the shapes at ``indices`` (repeats allowed), in that order.

        Packing is vectorised, so replicating a few unique hulls into many instances (a level's
        props) costs no per-shape Python work and no hull computation.

        Parameters
        ----------
        indices : (K,) int
            Shape indices into this set.
        """
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        if len(idx) and (idx.min() < 0 or idx.max() >= len(self)):
            raise ValueError(f"indices must be in [0, {len(self)}), got {idx.min()}..{idx.max()}")

        def blocks(offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            # rows of the contiguous blocks [offsets[h], offsets[h + 1]) for h in idx
            starts = offsets[idx]
            lengths = offsets[idx + 1] - starts
            new_offsets = np.zeros(len(idx) + 1, dtype=np.int64)
            np.cumsum(lengths, out=new_offsets[1:])
            rows = np.repeat(starts - new_offsets[:-1], lengths)
            rows += np.arange(new_offsets[-1], dtype=np.int64)
            return new_offsets, rows

        offsets, vertex_rows = blocks(self.offsets)
        # A shape's adjacency lists are one block too: its vertices' lists, in vertex order.
        _, adjacency_rows = blocks(self.adjacency_offsets[self.offsets])
        adjacency_offsets = np.zeros(len(vertex_rows) + 1, dtype=np.int64)
        np.cumsum(np.diff(self.adjacency_offsets)[vertex_rows], out=adjacency_offsets[1:])
        face_offsets, face_rows = blocks(self.face_offsets)
        edge_offsets, edge_rows = blocks(self.edge_offsets)
        return ConvexSet(
            vertices=self.vertices[vertex_rows],
            offsets=offsets,
            kinds=self.kinds[idx],
            params=self.params[idx],
            adjacency_offsets=adjacency_offsets,
            adjacency=self.adjacency[adjacency_rows],
            face_offsets=face_offsets,
            face_normals=self.face_normals[face_rows],
            edge_offsets=edge_offsets,
            edge_directions=self.edge_directions[edge_rows],
        )

    def aabbs(self, poses: Any = None, *, threads: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounding boxes.

        Parameters
        ----------
        poses : (H, 4, 4) float or None
            Rigid world-from-local poses (None: identity).

        Returns
        -------
        aabb_min, aabb_max : (H, 3) float64
            World frame; NaN rows for a shape or pose that is invalid.
        """
        return self._core.aabbs(as_poses(poses, len(self)), int(threads))


def as_convex_set(shapes: Any) -> ConvexSet:
    """``shapes`` itself when it is a ConvexSet, else TypeError (the wrong container)."""
    if not isinstance(shapes, ConvexSet):
        raise TypeError(f"shapes must be a ConvexSet, got {type(shapes).__name__}")
    return shapes
