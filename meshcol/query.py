"""Narrow phase: distance, penetration and intersection of convex shapes.

Frames and signs (fixed once, here, for every function of this module):

- Each shape is given in its own local frame; a pose is a rigid row-major 4x4 matrix mapping
  local to world (``world = R @ local + t``); ``None`` means identity.
- Every returned point and normal is in the world frame.
- ``distance >= 0`` (0 when the shapes touch or overlap); ``depth >= 0`` (0 when they are
  apart); ``signed_distance = distance - depth``.
- ``normal`` is a unit vector from shape ``a`` towards shape ``b``. When separated,
  ``point_b - point_a = distance * normal``; when overlapping, moving ``b`` by
  ``depth * normal`` brings the shapes into contact and ``point_a - point_b = depth * normal``
  (``point_a`` is the deepest point of ``a`` inside ``b`` and vice versa).
- Touching counts as intersecting. Two shapes closer than ``defaults.contact_tolerance``
  times the pair's length scale (bounding radii plus centre distance) touch.

Shapes are packed into a :class:`ConvexSet` (arrays, built once) and the ``*_batch`` functions
query (P, 2) index pairs in one native call (GIL released, threads over pairs). The
single-pair functions (:func:`distance`, ...) build a two-shape set and call the same code.

Notes
-----
Distance is GJK (van den Bergen 2003) with Ericson's (2004) Voronoi-region closest-point
subalgorithm, in shape ``a``'s frame, ending exactly on polytopes when a support point
repeats. Spheres and capsules are a point or segment swept by a radius, added exactly.
Penetration is EPA from GJK's final simplex with silhouette expansion (van den Bergen 2003),
verified, and replaced when they disagree, by an exact separating-axis test over face normals
and edge-edge cross products for boxes and small polytopes (Ericson 2004, sec. 5.2.1).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np

from meshcol.types import Body, Primitive, Status

__all__ = [
    "ShapeKind",
    "Sphere",
    "Box",
    "Capsule",
    "Cylinder",
    "ConvexSet",
    "DistanceBatch",
    "PenetrationBatch",
    "SignedDistanceBatch",
    "IntersectsBatch",
    "DistanceResult",
    "PenetrationResult",
    "SignedDistanceResult",
    "distance",
    "penetration",
    "intersects",
    "signed_distance",
    "distance_batch",
    "penetration_batch",
    "intersects_batch",
    "signed_distance_batch",
]


class ShapeKind(enum.IntEnum):
    """Kind of a packed shape (mirrors ``ShapeKind`` in ``shapes.hpp``)."""

    POLYTOPE = 0  #: convex hull of its vertices (a point, segment or polygon is valid)
    SPHERE = 1  #: params[0] radius
    BOX = 2  #: params[0:3] half extents
    CAPSULE = 3  #: params[0] radius, params[1] half length of the segment along local z
    CYLINDER = 4  #: params[0] radius, params[1] half length along local z


def _check_length(name: str, value: float) -> float:
    value = float(value)
    if not np.isfinite(value) or value < 0.0:
        raise ValueError(f"{name} must be finite and >= 0, got {value}")
    return value


@dataclass(frozen=True)
class Sphere:
    """Sphere centred on its local origin.

    Attributes
    ----------
    radius : float
    """

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))


@dataclass(frozen=True)
class Box:
    """Box centred on its local origin, axes along the local axes.

    Attributes
    ----------
    size : (3,) float
        FULL side lengths along local x, y, z.
    """

    size: tuple[float, float, float]

    def __post_init__(self) -> None:
        size = np.asarray(self.size, dtype=np.float64)
        if size.shape != (3,):
            raise ValueError(f"size must be (3,), got {size.shape}")
        object.__setattr__(
            self, "size", tuple(_check_length("size", s) for s in size)
        )


@dataclass(frozen=True)
class Capsule:
    """Capsule: a segment along local z, centred, swept by a ball.

    Attributes
    ----------
    radius : float
    length : float
        Length of the cylindrical part (the segment), along local z.
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))
        object.__setattr__(self, "length", _check_length("length", self.length))


@dataclass(frozen=True)
class Cylinder:
    """Solid cylinder along local z, centred.

    Attributes
    ----------
    radius : float
    length : float
        Full length along local z.
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))
        object.__setattr__(self, "length", _check_length("length", self.length))


# ---------------------------------------------------------------------------------------------
# Packing


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
    _, index = np.unique(np.round(d, 12), axis=0, return_index=True)
    return np.ascontiguousarray(d[np.sort(index)])


def _adjacency_from_edges(n: int, edges: np.ndarray) -> list[np.ndarray]:
    edges = np.unique(np.sort(edges, axis=1), axis=0)
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
    pts = np.unique(pts, axis=0)
    if len(pts) == 1:
        return _Packed(0, params, pts, [np.zeros(0, np.int32)], _EMPTY3, _EMPTY3)
    centre = pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(pts - centre, full_matrices=False)
    extent = sv[0]
    if len(sv) < 3 or sv[1] <= 1e-12 * extent:
        # Segment: its two extreme points along the principal direction.
        t = (pts - centre) @ vt[0]
        ends = pts[[np.argmin(t), np.argmax(t)]]
        adj = [np.array([1], np.int32), np.array([0], np.int32)]
        return _Packed(0, params, ends, adj, _EMPTY3, _unique_directions(ends[1:] - ends[:1], False))
    from scipy.spatial import ConvexHull, QhullError

    if sv[2] <= 1e-12 * extent:
        # Polygon: a 2D hull in the plane of the two principal directions.
        uv = (pts - centre) @ vt[:2].T
        try:
            hull2 = ConvexHull(uv)
        except QhullError:
            return _Packed(0, params, pts, [], _EMPTY3, _EMPTY3)
        ring = hull2.vertices  # counter-clockwise order
        verts = pts[ring]
        n = len(verts)
        loop = np.stack([np.arange(n), (np.arange(n) + 1) % n], axis=1)
        normal = np.cross(vt[0], vt[1])
        faces = np.stack([normal, -normal]) / np.linalg.norm(normal)
        edges = _unique_directions(verts[loop[:, 1]] - verts[loop[:, 0]], False)
        return _Packed(0, params, verts, _adjacency_from_edges(n, loop), faces, edges)
    try:
        hull = ConvexHull(pts)
    except QhullError:
        return _Packed(0, params, pts, [], _EMPTY3, _EMPTY3)
    keep = hull.vertices
    remap = np.full(len(pts), -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    verts = np.ascontiguousarray(pts[keep])
    tri = remap[hull.simplices]
    planes = np.round(hull.equations[:, :3], 12)
    # Edges of the triangulation (all of them drive hill climbing); those between facets of
    # different planes are the polytope's true edges (SAT).
    tri_edges, real = [], []
    for j in range(3):
        e = tri[:, [(j + 1) % 3, (j + 2) % 3]]
        tri_edges.append(e)
        neighbour = hull.neighbors[:, j]
        real.append(np.any(planes != planes[neighbour], axis=1))
    tri_edges = np.concatenate(tri_edges)
    real = np.concatenate(real)
    sat_edges = tri_edges[real]
    faces = _unique_directions(hull.equations[:, :3], True)
    edges = _unique_directions(verts[sat_edges[:, 1]] - verts[sat_edges[:, 0]], False)
    adjacency = _adjacency_from_edges(len(verts), tri_edges)
    return _Packed(0, params, verts, adjacency, faces, edges)


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


def _from_primitive_record(p: Primitive) -> Sphere | Box | Capsule | Cylinder:
    if p.kind == "sphere":
        return Sphere(p.radius)
    if p.kind == "box":
        return Box(tuple(p.size))
    if p.kind == "capsule":
        return Capsule(p.radius, p.length)
    if p.kind == "cylinder":
        return Cylinder(p.radius, p.length)
    raise ValueError(f"unknown primitive kind {p.kind!r}")


_PRIMITIVES = (Sphere, Box, Capsule, Cylinder)


def _pack_any(shape: Any, name: str) -> _Packed:
    """Packs a primitive, a Primitive record, a Body, a trimesh mesh or an (n, 3) array."""
    if isinstance(shape, _PRIMITIVES):
        return _pack_primitive(shape)
    if isinstance(shape, Primitive):
        return _pack_primitive(_from_primitive_record(shape))
    if isinstance(shape, Body):
        if shape.primitive is not None:
            return _pack_primitive(_from_primitive_record(shape.primitive))
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
        "vertices", "offsets", "kinds", "params", "adjacency_offsets", "adjacency",
        "face_offsets", "face_normals", "edge_offsets", "edge_directions",
    )

    def __init__(self, **arrays: np.ndarray) -> None:
        from meshcol import _core

        for name in self._FIELDS:
            setattr(self, name, _readonly(arrays[name]))
        self._core = _core.PackedConvexSet(
            self.vertices, self.offsets, self.kinds, self.params,
            self.adjacency_offsets, self.adjacency,
            self.face_offsets, self.face_normals, self.edge_offsets, self.edge_directions,
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
            [_pack_polytope(_as_points(v, f"vertex_lists[{i}]")) for i, v in enumerate(vertex_lists)]
        )

    @classmethod
    def from_shapes(cls, shapes: Sequence[Any]) -> ConvexSet:
        """Primitives (:class:`Sphere`, :class:`Box`, :class:`Capsule`, :class:`Cylinder`)
        and (n, 3) point arrays (convex hulls), in any mix."""
        return cls._from_packed([_pack_any(s, f"shapes[{i}]") for i, s in enumerate(shapes)])

    @classmethod
    def from_meshes(cls, meshes: Sequence[Any]) -> ConvexSet:
        """Convex hulls of ``trimesh.Trimesh`` meshes or :class:`meshcol.types.Body`
        objects, in their local frames (a Body with a primitive uses the primitive)."""
        return cls._from_packed([_pack_any(m, f"meshes[{i}]") for i, m in enumerate(meshes)])

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
        return self._core.aabbs(_as_poses(poses, len(self)), int(threads))


def _as_points(v: Any, name: str) -> np.ndarray:
    arr = np.asarray(v, dtype=np.float64)
    if arr.ndim == 1 and arr.shape == (3,):
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be (n, 3), got {arr.shape}")
    return arr


def _as_poses(poses: Any, h: int) -> np.ndarray | None:
    if poses is None:
        return None
    arr = np.ascontiguousarray(poses, dtype=np.float64)
    if arr.shape != (h, 4, 4):
        raise ValueError(f"poses must be ({h}, 4, 4), got {arr.shape}")
    return arr


def _as_pairs(pairs: Any, h: int, items: str = "shapes") -> np.ndarray:
    """``pairs`` as a C-contiguous (P, 2) int64 array of indices below ``h`` (the ``items``,
    named in the error), or ValueError."""
    arr = np.asarray(pairs)
    if arr.size == 0:
        arr = arr.reshape(-1, 2) if arr.ndim == 2 or arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"pairs must be (P, 2), got {arr.shape}")
    if arr.size and arr.dtype.kind not in "iu":
        raise ValueError(f"pairs must hold integer indices, got dtype {arr.dtype}")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    if arr.size and (arr.min() < 0 or arr.max() >= h):
        bad = arr[(arr < 0) | (arr >= h)][0]
        raise ValueError(f"pairs: index {bad} out of range for {h} {items}")
    return arr


def _as_set(shapes: Any) -> ConvexSet:
    if not isinstance(shapes, ConvexSet):
        raise ValueError(f"shapes must be a ConvexSet, got {type(shapes).__name__}")
    return shapes


# ---------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class DistanceBatch:
    """Per-pair distances, in pair order.

    Attributes
    ----------
    distance : (P,) float64
        >= 0; 0 for touching or overlapping pairs.
    point_a, point_b : (P, 3) float64
        World closest points (a common point when overlapping).
    normal : (P, 3) float64
        World unit normal from a to b; zero for overlapping pairs.
    iterations : (P,) int32
    status : (P,) int8
        :class:`meshcol.types.Status` values.
    """

    distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class PenetrationBatch:
    """Per-pair penetration, in pair order.

    Attributes
    ----------
    depth : (P,) float64
        >= 0; 0 for separated pairs.
    normal : (P, 3) float64
        World unit normal from a to b: moving b by ``depth * normal`` brings the pair into
        contact (for separated pairs: the direction of the closest points).
    point_a, point_b : (P, 3) float64
        World witness points, ``point_a - point_b = depth * normal`` (closest points when
        separated).
    iterations : (P,) int32
    status : (P,) int8
    """

    depth: np.ndarray
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class SignedDistanceBatch:
    """Per-pair signed distance (``distance - depth``) with both parts, in pair order.

    Fields as in :class:`DistanceBatch` and :class:`PenetrationBatch`; ``point_a``,
    ``point_b`` and ``normal`` are closest points when separated and witness points when
    overlapping.
    """

    signed_distance: np.ndarray
    distance: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class IntersectsBatch:
    """Per-pair intersection test (touching counts), in pair order.

    Attributes
    ----------
    intersects : (P,) bool
    status : (P,) int8
    """

    intersects: np.ndarray
    status: np.ndarray


@dataclass(frozen=True)
class DistanceResult:
    """Distance between two shapes (see the module docstring for frames and signs)."""

    distance: float
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    iterations: int
    status: Status


@dataclass(frozen=True)
class PenetrationResult:
    """Penetration of two shapes (see the module docstring for frames and signs)."""

    depth: float
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: int
    status: Status


@dataclass(frozen=True)
class SignedDistanceResult:
    """Signed distance ``distance - depth`` of two shapes, with both parts."""

    signed_distance: float
    distance: float
    depth: float
    normal: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    iterations: int
    status: Status


# ---------------------------------------------------------------------------------------------
# Batched queries

_DISTANCE, _PENETRATION, _INTERSECTS = 0, 1, 2


def _run(kind: int, shapes: Any, poses: Any, pairs: Any, threads: int) -> dict[str, np.ndarray]:
    cs = _as_set(shapes)
    h = len(cs)
    return cs._core.query(kind, _as_poses(poses, h), _as_pairs(pairs, h), int(threads))


def distance_batch(shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0) -> DistanceBatch:
    """Distance between the shapes of each pair (GJK).

    Parameters
    ----------
    shapes : ConvexSet
    poses : (H, 4, 4) float or None
        Rigid world-from-local poses, row-major (None: identity).
    pairs : (P, 2) int
        Indices into ``shapes``.
    threads : int
        Worker threads; 0 uses all cores.

    Returns
    -------
    DistanceBatch
        One array per field, in pair order; a pair whose shape or pose is invalid (NaN/inf,
        empty, non-rigid) gets ``Status.INVALID_INPUT`` and NaN fields.

    Raises
    ------
    ValueError
        Wrong array shapes, non-integer pairs or an index out of range.
    """
    r = _run(_DISTANCE, shapes, poses, pairs, threads)
    return DistanceBatch(r["distance"], r["point_a"], r["point_b"], r["normal"],
                         r["iterations"], r["status"])


def penetration_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> PenetrationBatch:
    """Penetration depth of each pair (GJK, then EPA and exact SAT where overlapping).

    Parameters and errors as :func:`distance_batch`. Separated pairs get ``depth = 0`` and
    their closest points.
    """
    r = _run(_PENETRATION, shapes, poses, pairs, threads)
    return PenetrationBatch(r["depth"], r["normal"], r["point_a"], r["point_b"],
                            r["iterations"], r["status"])


def signed_distance_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> SignedDistanceBatch:
    """Signed distance ``distance - depth`` of each pair: GJK for all, EPA (+ exact SAT for
    small polytopes) only for the overlapping ones.

    Parameters and errors as :func:`distance_batch`.
    """
    r = _run(_PENETRATION, shapes, poses, pairs, threads)
    return SignedDistanceBatch(r["distance"] - r["depth"], r["distance"], r["depth"],
                               r["normal"], r["point_a"], r["point_b"], r["iterations"],
                               r["status"])


def intersects_batch(
    shapes: ConvexSet, poses: Any, pairs: Any, *, threads: int = 0
) -> IntersectsBatch:
    """Whether each pair touches or overlaps (boolean GJK with early exit).

    Parameters and errors as :func:`distance_batch`; invalid pairs give ``False`` with
    ``Status.INVALID_INPUT``.
    """
    r = _run(_INTERSECTS, shapes, poses, pairs, threads)
    return IntersectsBatch(r["intersects"], r["status"])


# ---------------------------------------------------------------------------------------------
# Single pairs

_PAIR = np.array([[0, 1]], dtype=np.int64)


def _pair_set(a: Any, b: Any, pose_a: Any, pose_b: Any) -> tuple[ConvexSet, np.ndarray | None]:
    cs = ConvexSet._from_packed([_pack_any(a, "a"), _pack_any(b, "b")])
    if pose_a is None and pose_b is None:
        return cs, None
    poses = []
    for name, pose in (("pose_a", pose_a), ("pose_b", pose_b)):
        m = np.eye(4) if pose is None else np.asarray(pose, dtype=np.float64)
        if m.shape != (4, 4):
            raise ValueError(f"{name} must be (4, 4), got {m.shape}")
        poses.append(m)
    return cs, np.stack(poses)


def distance(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> DistanceResult:
    """Distance between two convex shapes.

    Parameters
    ----------
    a, b : Sphere, Box, Capsule, Cylinder, trimesh.Trimesh, Body or (n, 3) float
        Shapes in their local frames (meshes and point sets by their convex hull).
    pose_a, pose_b : (4, 4) float or None
        Rigid world-from-local poses (None: identity).

    Returns
    -------
    DistanceResult
        See :class:`DistanceBatch` for the fields.
    """
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    r = distance_batch(cs, poses, _PAIR, threads=1)
    return DistanceResult(float(r.distance[0]), r.point_a[0], r.point_b[0], r.normal[0],
                          int(r.iterations[0]), Status(int(r.status[0])))


def penetration(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> PenetrationResult:
    """Penetration depth of two convex shapes (0 when apart); arguments as :func:`distance`."""
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    r = penetration_batch(cs, poses, _PAIR, threads=1)
    return PenetrationResult(float(r.depth[0]), r.normal[0], r.point_a[0], r.point_b[0],
                             int(r.iterations[0]), Status(int(r.status[0])))


def signed_distance(
    a: Any, b: Any, pose_a: Any = None, pose_b: Any = None
) -> SignedDistanceResult:
    """Signed distance (distance - depth) of two convex shapes; arguments as
    :func:`distance`."""
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    r = signed_distance_batch(cs, poses, _PAIR, threads=1)
    return SignedDistanceResult(float(r.signed_distance[0]), float(r.distance[0]),
                                float(r.depth[0]), r.normal[0], r.point_a[0], r.point_b[0],
                                int(r.iterations[0]), Status(int(r.status[0])))


def intersects(a: Any, b: Any, pose_a: Any = None, pose_b: Any = None) -> bool:
    """True when two convex shapes touch or overlap; arguments as :func:`distance`.

    Raises
    ------
    ValueError
        Also for invalid data (NaN/inf, an empty shape, a non-rigid pose): a bool cannot
        carry a status (the batch form reports ``Status.INVALID_INPUT`` instead).
    """
    cs, poses = _pair_set(a, b, pose_a, pose_b)
    r = intersects_batch(cs, poses, _PAIR, threads=1)
    if r.status[0] == Status.INVALID_INPUT:
        raise ValueError("a, b, pose_a or pose_b: NaN/inf coordinates, an empty shape or a "
                         "non-rigid pose")
    return bool(r.intersects[0])
