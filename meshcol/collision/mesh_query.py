"""Exact queries between triangle meshes: minimum distance, intersection, containment, depth.

A :class:`MeshSet` packs M triangle meshes and builds each one's bounding volume hierarchy once,
in the native core; every query on the set reuses them. Queries take one rigid pose per mesh and
a list of index pairs, run on several threads with the GIL released, and return one array per
field (:class:`MeshDistanceBatch`). :func:`mesh_distance` is the single-pair convenience form.

Frames and signs are the package's: vertices are in each mesh's local frame, poses map local to
world (``world = R @ local + t``, row-major 4x4), returned points are in the world frame, and
``distance >= 0``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_mesh, as_offsets, as_pairs, as_points, as_poses
from meshcol.collision.orientation import orient_consistently
from meshcol.geometry.topology import is_closed_manifold, manifold_solid
from meshcol.types import Body, Status

__all__ = [
    "MeshSet",
    "MeshDistanceBatch",
    "MeshDistanceResult",
    "MeshIntersectsBatch",
    "MeshDepthBatch",
    "mesh_distance",
    "mesh_distance_batch",
    "mesh_intersects_batch",
    "mesh_penetration_depth_batch",
    "mesh_intersection_volume",
]


def _mesh_parts(index: int, mesh: Any) -> tuple[Any, Any]:
    """The (vertices, faces) objects of one input mesh, as given (not yet checked)."""
    if isinstance(mesh, tuple | list) and len(mesh) == 2:
        return mesh[0], mesh[1]
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return mesh.vertices, mesh.faces
    raise ValueError(
        f"meshes[{index}] must be a (vertices, faces) pair or have .vertices and .faces"
    )


def _mesh_arrays(index: int, vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3) float64, faces (m, 3) int64) of one input mesh, checked."""
    try:
        vertices, faces = as_mesh(vertices, faces)
    except ValueError as error:
        raise ValueError(f"meshes[{index}]: {error}") from None
    if not np.issubdtype(faces.dtype, np.integer):
        raise ValueError(f"meshes[{index}]: faces must be integers, got {faces.dtype}")
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        bad = int(faces[(faces < 0) | (faces >= len(vertices))][0])
        raise ValueError(
            f"meshes[{index}]: face vertex index {bad} out of range [0, {len(vertices)})"
        )
    return vertices, faces


_INT64 = np.dtype(np.int64)


@dataclass(frozen=True)
class _Oriented:
    faces: np.ndarray
    reoriented: bool
    orientable: bool
    closed: bool


def _oriented(vertices: np.ndarray, faces: np.ndarray, orient: bool) -> _Oriented:
    """One mesh's faces wound consistently (when ``orient``) and its topology flags."""
    if len(faces) == 0:
        return _Oriented(faces, False, True, False)
    found = orient_consistently(vertices, faces)
    if not orient:
        return _Oriented(faces, False, found.orientable, found.closed)
    return _Oriented(found.faces, bool(found.flipped.any()), found.orientable, found.closed)


@dataclass(frozen=True, eq=False)
class MeshSet:
    """M triangle meshes packed in flat arrays, with their hierarchies built once.

    Build it with :meth:`from_arrays` or :meth:`from_bodies`; every query on it reuses the
    hierarchies (built in the native core, in parallel, when the set is created).

    Attributes
    ----------
    vertices : (V, 3) float64
        All meshes' vertices, each in its mesh's local frame; mesh ``i`` owns rows
        ``vertex_offsets[i]:vertex_offsets[i + 1]``.
    faces : (F, 3) int64
        All meshes' triangles; mesh ``i`` owns rows ``face_offsets[i]:face_offsets[i + 1]``,
        whose indices are local to its vertex block.
    vertex_offsets : (M + 1,) int64
    face_offsets : (M + 1,) int64
    poses : (M, 4, 4) float64
        Default world-from-local poses, used when a query passes ``poses=None``: identity from
        :meth:`from_arrays` unless given, each body's ``pose`` from :meth:`from_bodies`. Read
        (and checked for rigidity) by the core once, when the set is built: read-only, like
        every array of the set.
    valid : (M,) bool
        Whether each mesh is usable: finite vertices and at least one face. Pairs involving an
        invalid mesh report ``Status.INVALID_INPUT``.
    reoriented : (M,) bool
        Some faces of the mesh were reversed when the set was built
        (:func:`meshcol.collision.orientation.orient_consistently`: its winding was inconsistent,
        MC403); ``faces`` holds them as reversed, in input order.
    orientable : (M,) bool
        Every component of the mesh can be wound consistently. When False the winding number
        does not decide inside from outside (see :meth:`inside_decided`).
    closed : (M,) bool
        The mesh's faces (as reoriented) are balanced, every edge traversed as often each way
        (:func:`meshcol.geometry.topology.is_balanced`): closed and consistently wound, so
        the winding number decides inside from outside exactly.
    """

    vertices: np.ndarray
    faces: np.ndarray
    vertex_offsets: np.ndarray
    face_offsets: np.ndarray
    poses: np.ndarray
    valid: np.ndarray
    reoriented: np.ndarray
    orientable: np.ndarray
    closed: np.ndarray
    _handle: core.MeshBvhSet = field(repr=False)

    def __post_init__(self) -> None:
        # `intersects` of a set is the native method itself, bound here: it reads and converts
        # poses as the method below documents, and a call through a Python frame costs about a
        # tenth of a near pair's answer (the method stays as the class's documented form).
        object.__setattr__(self, "intersects", self._handle.intersects_pair)

    @classmethod
    def from_arrays(
        cls,
        meshes: Iterable[Any],
        poses: np.ndarray | None = None,
        *,
        threads: int = 0,
        orient: bool = True,
    ) -> MeshSet:
        """Pack meshes, wind each consistently, and build their hierarchies.

        Parameters
        ----------
        meshes : iterable of (vertices (n, 3), faces (m, 3)) pairs
            Or objects with ``.vertices`` and ``.faces`` (e.g. ``trimesh.Trimesh``), local frames.
        poses : (M, 4, 4) float, optional
            Default poses (identity when omitted).
        threads : int
            Build threads; 0 means all cores.
        orient : bool
            Reverse the faces of an inconsistently wound mesh so that each of its components
            is wound consistently, closed ones outward
            (:func:`meshcol.collision.orientation.orient_consistently`), before any inside test:
            the winding number of a mesh wound both ways at random means nothing. A mesh
            without inconsistent edges is kept as given. False keeps every mesh as given.

        Raises
        ------
        ValueError
            On malformed arrays or a face index out of range, naming the mesh (``meshes[3]: ...``).
        """
        # Checked and converted once per distinct pair of input arrays (a trimesh's vertices
        # convert to a new array object at each call): instances of one asset then share their
        # arrays. `parts` holds every input array, so no id is reused while these run.
        parts: list[tuple[Any, Any]] = []
        checked: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        for i, mesh in enumerate(meshes):
            v, f = _mesh_parts(i, mesh)
            parts.append((v, f))
            if (id(v), id(f)) not in checked:
                checked[(id(v), id(f))] = _mesh_arrays(i, v, f)
        arrays = [checked[(id(v), id(f))] for v, f in parts]
        # once per distinct mesh: instances of one asset share their arrays
        distinct: dict[tuple[int, int], _Oriented] = {}
        for v, f in arrays:
            if (id(v), id(f)) not in distinct:
                distinct[(id(v), id(f))] = _oriented(v, f, orient)
        oriented = [distinct[(id(v), id(f))] for v, f in arrays]
        arrays = [(v, o.faces) for (v, _), o in zip(arrays, oriented)]
        reoriented, orientable, closed = (
            np.array([bool(getattr(o, name)) for o in oriented], dtype=bool).reshape(-1)
            for name in ("reoriented", "orientable", "closed")
        )
        count = len(arrays)
        vertex_offsets = as_offsets([len(v) for v, _ in arrays])
        face_offsets = as_offsets([len(f) for _, f in arrays])
        vertices = (
            np.concatenate([v for v, _ in arrays]) if count else np.zeros((0, 3), dtype=np.float64)
        )
        faces = (
            np.concatenate([f for _, f in arrays]) if count else np.zeros((0, 3), dtype=np.int64)
        )
        vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        faces = np.ascontiguousarray(faces, dtype=np.int64)
        given = np.tile(np.eye(4), (count, 1, 1)) if poses is None else poses
        poses = np.ascontiguousarray(as_poses(given, count))
        handle = core.MeshBvhSet(vertices, faces, vertex_offsets, face_offsets, threads=threads)
        # Read and checked for rigidity once: queries with poses=None reuse the native copy
        # (the arrays are read-only, so it cannot go stale).
        handle.set_poses(poses)
        valid = np.array([handle.valid(i) for i in range(count)], dtype=bool)
        flags = (reoriented, orientable, closed)
        for array in (vertices, faces, vertex_offsets, face_offsets, poses, valid, *flags):
            array.flags.writeable = False
        return cls(
            vertices, faces, vertex_offsets, face_offsets, poses, valid, *flags, _handle=handle
        )

    @classmethod
    def from_bodies(cls, bodies: Sequence[Body], *, threads: int = 0) -> MeshSet:
        """Pack bodies' meshes (local frames); their ``pose`` become the default poses.

        A primitive body contributes its tessellation.
        """
        poses = np.array([np.asarray(b.pose, dtype=np.float64) for b in bodies]).reshape(-1, 4, 4)
        return cls.from_arrays([(b.vertices, b.faces) for b in bodies], poses, threads=threads)

    def __len__(self) -> int:
        return len(self.vertex_offsets) - 1

    @property
    def inside_decided(self) -> np.ndarray:
        """(M,) bool: the winding number decides inside from outside for each mesh: it is
        closed and consistently wound, as given or reoriented (``closed``). Containment and
        the depth's lower bound hold exactly against these; against any other mesh they rest
        on the winding number's tolerance of holes, or are undecided."""
        return self.closed.copy()

    def mesh(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (n, 3), faces (m, 3)) of mesh ``i``, local frame, indices local."""
        v0, v1 = self.vertex_offsets[i], self.vertex_offsets[i + 1]
        f0, f1 = self.face_offsets[i], self.face_offsets[i + 1]
        return self.vertices[v0:v1], self.faces[f0:f1]

    def intersects(self, i: int, j: int, pose_i: Any = None, pose_j: Any = None) -> bool:
        """Whether the surfaces of meshes ``i`` and ``j`` intersect (touching counts).

        The single-pair form of :func:`mesh_intersects_batch` (same verdicts), without its
        arrays: one native call that reads the set's default poses (or the (4, 4) ``pose_i``,
        ``pose_j`` given) and allocates nothing, for loops that ask about one pair at a time.

        Raises
        ------
        ValueError
            ``i`` or ``j`` out of range, a pose not (4, 4), or a pair without a verdict (the
            statuses :func:`mesh_intersects_batch` reports instead): a mesh that is not valid, a
            pose that is not rigid or not finite, lengths out of range.
        """
        return self._handle.intersects_pair(i, j, pose_i, pose_j)

    def validate(self) -> bool:
        """Check every hierarchy's invariants (boxes enclose contents, layout); for tests."""
        return bool(self._handle.validate())

    def winding_number(self, i: int, points: np.ndarray) -> np.ndarray:
        """Generalized winding numbers (n,) of ``points`` (n, 3), in mesh ``i``'s local frame.

        1 inside a closed outward-wound mesh, 0 outside (Jacobson et al. 2013).
        """
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        return self._handle.winding_number(i, points)

    def fast_winding_number(
        self, i: int, points: np.ndarray, max_error: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fast winding numbers of ``points`` (n, 3), mesh ``i``'s local frame, within a bound.

        The hierarchical evaluation of Barill et al. 2018 (order-2 far field) with a
        guaranteed error: returns ``(value (n,), error (n,), visits (n,) int64)`` with
        ``|value - winding_number| <= error <= max_error`` (up to rounding); ``max_error=0``
        sums every triangle. ``visits`` counts the nodes and triangles evaluated.
        """
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        return self._handle.fast_winding_number(i, points, float(max_error))

    def winding_number_inside(self, i: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Containment verdicts ``|winding_number| >= 0.5`` of ``points`` (n, 3) w.r.t. mesh ``i``.

        The fast winding number refined only until its error bound decides the comparison: the
        same verdicts as thresholding :meth:`winding_number`. Returns ``(inside (n,) bool,
        visits (n,) int64)``.
        """
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        return self._handle.winding_number_inside(i, points)

    def contains(self, i: int, points: np.ndarray) -> np.ndarray:
        """Whether each point (n, 3) is inside mesh ``i`` (local frame), (n,) bool.

        ``|winding number| >= defaults.winding_number_inside`` (either orientation); meaningful
        for a closed mesh. A non-finite point is not inside. Decided by the fast winding
        number, refined until its error bound settles the comparison (as
        :meth:`winding_number_inside`), so the verdicts are those of the exact sum.
        """
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        return self._handle.winding_number_inside(i, points)[0]

    def closest_points(
        self, i: int, points: Any, *, threads: int = 0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Exact distance from each point to mesh ``i``'s surface, and the closest points.

        Parameters
        ----------
        i : int
            Mesh index in [0, M).
        points : (n, 3) float
            Query points in mesh ``i``'s local frame.
        threads : int
            Worker threads; 0 means all cores.

        Returns
        -------
        distances : (n,) float64
            >= 0; NaN for a non-finite point, and for every point when mesh ``i`` is invalid.
        points : (n, 3) float64
            Closest surface points, mesh ``i``'s local frame (NaN where ``distances`` is).

        Raises
        ------
        ValueError
            ``points`` not (n, 3), or ``i`` out of range.

        Notes
        -----
        Depth-first branch and bound over the mesh's hierarchy, closer child first, pruning
        nodes whose oriented boxes are no closer than the best distance so far (a curved
        patch's box is a thin slab, tight even from deep inside); exact closest point on each
        triangle at the leaves by Voronoi regions (Ericson 2004, 5.1.5), degenerate triangles as
        their edges.
        """
        points = np.ascontiguousarray(as_points(points, "points"))
        distances, closest, _ = self._handle.closest_points(int(i), points, int(threads))
        return distances, closest

    def closest_faces(
        self, i: int, points: Any, *, threads: int = 0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`closest_points`, and the face of mesh ``i`` holding each closest point.

        Returns
        -------
        distances : (n,) float64
        points : (n, 3) float64
        faces : (n,) int64
            Index into mesh ``i``'s faces (input order); -1 where ``distances`` is NaN.
        """
        points = np.ascontiguousarray(as_points(points, "points"))
        distances, closest, faces = self._handle.closest_points(int(i), points, int(threads))
        return distances, closest, faces

    def largest_distances(
        self, points: Any, point_offsets: Any, meshes: Any = None, *, threads: int = 0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per item k, the largest distance from its block of points to its mesh's surface.

        ``points`` (P, 3): item ``k``'s are ``points[point_offsets[k]:point_offsets[k + 1]]``
        (offsets (K + 1,) from 0 to P), in the local frame of mesh ``meshes[k]`` (``meshes``
        (K,), default one item per mesh); ``threads`` over the items, 0 all cores.

        Returns ``(distances (K,), point (K,) int64, status (K,) int8)``: the largest of the
        block's :meth:`closest_points` distances bit for bit (non-finite points skipped),
        NaN for an invalid mesh (``Status.INVALID_INPUT``) or no finite point; the index in
        the block of a point at it (-1 where NaN). The max of the min in one native call:
        each point's branch and bound stops at the first triangle within the largest
        distance found so far for its item (it cannot raise it); a point beyond it runs the
        whole search, so the maximum is the unpruned one exactly.
        """
        points = np.ascontiguousarray(as_points(points, "points"))
        offsets = np.ascontiguousarray(point_offsets, dtype=np.int64).reshape(-1)
        index = _items(meshes, len(offsets) - 1)
        out = self._handle.largest_distance_batch(index, points, offsets, int(threads))
        return out["distance"], out["point"], out["status"]

    def largest_distances_to_patches(
        self, patches: Any, meshes: Any = None, *, threads: int = 0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`largest_distances` of the grid nodes of surface patches
        (:class:`meshcol.collision.primitive_surface.SurfacePatches`, item ``k`` its primitive
        ``k``'s), without making the points: a block of nodes whose centre is at distance d,
        every node within r of it, is skipped once the maximum is above d + r. The same
        maximum as :meth:`largest_distances` of ``patches.points()``; ``point`` a node at it.
        """
        index = _items(meshes, len(patches.offsets) - 1)
        out = self._handle.largest_distance_to_patches_batch(
            index, patches.map, patches.nodes, patches.numbers, patches.offsets, int(threads)
        )
        return out["distance"], out["point"], out["status"]


def _items(meshes: Any, count: int) -> np.ndarray:
    """The mesh of each of ``count`` items: ``meshes`` as int64, or one item per mesh."""
    index = np.arange(count) if meshes is None else meshes
    return np.ascontiguousarray(index, dtype=np.int64).reshape(-1)


@dataclass(frozen=True, eq=False)
class MeshDistanceBatch:
    """Results of :func:`mesh_distance_batch`, one entry per pair.

    Attributes
    ----------
    distance : (P,) float64
        Minimum distance between the two surfaces, >= 0; 0 when they intersect or touch; ``inf``
        when greater than ``max_distance``; NaN when the pair is invalid.
    point_a, point_b : (P, 3) float64
        Closest points on a and on b, world frame; when intersecting, both are one shared
        point; NaN when ``distance`` is inf or NaN.
    intersecting : (P,) bool
        The surfaces share a point (touching counts).
    a_inside_b, b_inside_a : (P,) bool
        The surfaces are disjoint and mesh a lies inside mesh b (resp. b inside a), by the
        generalized winding number of one vertex. Meaningful when the outer mesh is closed.
        Always False when ``intersecting``. Computed even when ``distance`` is inf.
    triangle_a, triangle_b : (P,) int64
        Faces (indices local to each mesh) holding ``point_a`` and ``point_b``; -1 when none.
    status : (P,) int8
        :class:`meshcol.types.Status`: ``CONVERGED``; ``INVALID_INPUT`` for a non-rigid or
        non-finite pose, a mesh with a non-finite vertex, or a mesh without faces;
        ``OUT_OF_RANGE`` (NaN distance) when the pair's lengths (centre distance, reach of the
        meshes) leave [2^-100, 2^100], where the float boxes and squared distances of the
        search are not exact enough.
    """

    distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    intersecting: np.ndarray
    a_inside_b: np.ndarray
    b_inside_a: np.ndarray
    triangle_a: np.ndarray
    triangle_b: np.ndarray
    status: np.ndarray

    def __len__(self) -> int:
        return len(self.distance)


@dataclass(frozen=True)
class MeshDistanceResult:
    """One pair's result of :func:`mesh_distance` (fields as in :class:`MeshDistanceBatch`)."""

    distance: float
    point_a: np.ndarray
    point_b: np.ndarray
    intersecting: bool
    a_inside_b: bool
    b_inside_a: bool
    triangle_a: int
    triangle_b: int
    status: Status


@dataclass(frozen=True, eq=False, slots=True)
class MeshIntersectsBatch:
    """Results of :func:`mesh_intersects_batch`: ``intersecting (P,) bool``, ``status (P,) int8``."""

    intersecting: np.ndarray
    status: np.ndarray

    def __len__(self) -> int:
        return len(self.intersecting)


def _pairs(pairs: Any, count: int) -> np.ndarray:
    """``pairs`` checked as :func:`as_pairs` does; a C-contiguous (P, 2) int64 array passes as
    it is (the core checks its range, with the same message), saving a query on one pair more
    than the query costs."""
    if (
        type(pairs) is np.ndarray
        and pairs.dtype is _INT64
        and pairs.ndim == 2
        and pairs.shape[1] == 2
        and pairs.flags.c_contiguous
    ):
        return pairs
    return as_pairs(pairs, count, "meshes")


def mesh_distance_batch(
    meshes: MeshSet,
    poses: np.ndarray | None,
    pairs: np.ndarray,
    *,
    threads: int = 0,
    max_distance: float = math.inf,
) -> MeshDistanceBatch:
    """Exact minimum distance, intersection and containment for pairs of posed meshes.

    Parameters
    ----------
    meshes : MeshSet
        The M meshes, hierarchies already built.
    poses : (M, 4, 4) float or None
        Rigid world-from-local pose per mesh (row-major); None uses ``meshes.poses``.
        A non-rigid or non-finite pose makes its pairs ``Status.INVALID_INPUT``.
    pairs : (P, 2) int
        Mesh indices (a, b) per query, in [0, M).
    threads : int
        Worker threads; 0 means all cores.
    max_distance : float
        Search radius, >= 0. Pairs farther apart than this stop as soon as that is proven and
        report ``distance = inf`` with NaN points and triangles -1 (still ``CONVERGED``;
        containment is still tested). Pairs within it get their exact distance.

    Returns
    -------
    MeshDistanceBatch

    Raises
    ------
    ValueError
        On malformed shapes, a pair index out of range, or a negative or NaN ``max_distance``.

    Notes
    -----
    Simultaneous depth-first descent of both hierarchies (axis-aligned boxes in each mesh's
    frame, b's boxes mapped into a's frame), closer child pair first, pruning pairs whose box
    distance cannot beat the best distance found (branch and bound; Larsen et al. 1999). At the
    leaves, an exact triangle-triangle intersection test (sign tests in the manner of Guigue
    and Devillers 2003), then the exact distance as the minimum over 9 edge pairs and 6
    vertex-face pairs (Ericson 2004, 5.1.9). The first intersecting pair ends the search.
    When the surfaces are disjoint, one vertex of each mesh decides containment by its
    generalized winding number w.r.t. the other (sum of signed solid angles by van Oosterom
    and Strackee 1983, over 4 pi; Jacobson et al. 2013): inside when ``|w| >= 0.5``, so a
    consistently inward-wound mesh also counts, and small holes are tolerated.
    """
    if not isinstance(meshes, MeshSet):
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}")
    max_distance = float(max_distance)
    if not max_distance >= 0.0:
        raise ValueError(f"max_distance must be >= 0, got {max_distance}")
    # As mesh_intersects_batch: poses and pairs already in the core's form are read in place by
    # one native call that builds the result (a one-pair batch then costs about the query);
    # anything else is None, converted and checked here, and asked again.
    handle = meshes._handle
    result = handle.distance_batch(poses, pairs, threads, max_distance, MeshDistanceBatch)
    if result is None:
        if poses is not None:
            poses = as_poses(poses, len(meshes))
        pairs = as_pairs(pairs, len(meshes), "meshes")
        result = handle.distance_batch(poses, pairs, threads, max_distance, MeshDistanceBatch)
        if result is None:  # as_poses and as_pairs give the core's form: never declined twice
            raise AssertionError("the core declined converted poses and pairs")
    return result


def mesh_intersects_batch(
    meshes: MeshSet,
    poses: np.ndarray | None,
    pairs: np.ndarray,
    *,
    threads: int = 0,
) -> MeshIntersectsBatch:
    """Whether the surfaces of pairs of posed meshes intersect (touching counts).

    Cheaper than :func:`mesh_distance_batch` when only the yes/no answer is needed: it descends
    only overlapping boxes and stops at the first intersecting triangle pair. It does not test
    containment. Parameters as in :func:`mesh_distance_batch`.
    """
    # Arrays already in the core's form (C-contiguous float64 poses, int64 pairs, or a list of
    # int pairs) are read in place by one native call that also builds the result: a one-pair
    # batch costs about as much as the single-pair call. Anything else is None, then converted
    # and checked here (the same messages) and asked again. The type of `meshes` is checked
    # only when the call fails: an isinstance first costs a twentieth of a one-pair batch that
    # its first boxes settle.
    try:
        result = meshes._handle.intersects_batch(poses, pairs, threads, MeshIntersectsBatch)
    except AttributeError:
        if isinstance(meshes, MeshSet):
            raise
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}") from None
    if result is None:
        if poses is not None:
            poses = as_poses(poses, len(meshes))
        pairs = as_pairs(pairs, len(meshes), "meshes")
        result = meshes._handle.intersects_batch(poses, pairs, threads, MeshIntersectsBatch)
        if result is None:  # as_poses and as_pairs give the core's form: never declined twice
            raise AssertionError("the core declined converted poses and pairs")
    return result


@dataclass(frozen=True, eq=False)
class MeshDepthBatch:
    """Results of :func:`mesh_penetration_depth_batch`, one entry per pair.

    Attributes
    ----------
    depth : (P,) float64
        >= 0: the largest distance, to the other surface, of a sampled point of one mesh that
        lies inside the other (see the Notes of :func:`mesh_penetration_depth_batch`); 0 when
        none does. For closed meshes a lower bound of the minimum translation distance that
        separates the pair. NaN when the pair is invalid.
    point_a, point_b : (P, 3) float64
        World frame: the deepest point and its closest point on the other surface (the one on
        a is ``point_a``); ``point_b - point_a == -depth * normal``. NaN when depth is 0.
    normal : (P, 3) float64
        Unit vector from a towards b along which b leaves the deepest point behind; NaN when
        depth is 0, a unit vector whenever it is not (also for a depth below the rounding of
        the poses, whose two points are then one world point). For a non-convex pair a hint,
        not a separating direction.
    deepest_mesh : (P,) int8
        0 when the deepest point is a's (inside b), 1 when it is b's, -1 when none is inside.
    points_tested : (P,) int64
        Exact inside tests run. When the other mesh is closed: one per region of points (see
        the Notes of :func:`mesh_penetration_depth_batch`) and one per point the search
        measures deeper than its best depth, unless a point tested before decides it (one
        nearer to it than that point is to the surface). Otherwise one per point.
    status : (P,) int8
        :class:`meshcol.types.Status`: ``CONVERGED``; ``MAX_ITERATIONS`` when the pair used
        ``defaults.mesh_depth_max_work`` triangle visits, or has more triangle pairs within
        rounding of each other than ``defaults.mesh_depth_max_near_pairs`` (depth is then
        that of the points decided, still a lower bound: 0 for the second);
        ``INVALID_INPUT`` as in :class:`MeshDistanceBatch`.
    """

    depth: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    deepest_mesh: np.ndarray
    points_tested: np.ndarray
    status: np.ndarray

    def __len__(self) -> int:
        return len(self.depth)


def mesh_penetration_depth_batch(
    meshes: MeshSet,
    poses: np.ndarray | None,
    pairs: np.ndarray,
    *,
    threads: int = 0,
) -> MeshDepthBatch:
    """Penetration depth of pairs of posed meshes, never more than the true one.

    Parameters as in :func:`mesh_distance_batch` (without ``max_distance``).

    Returns
    -------
    MeshDepthBatch

    Notes
    -----
    The depth of a pair is ``max over p of dist(p, other surface)``, p ranging over the sampled
    points of each mesh that lie inside the other: its vertices, and on each edge of a
    triangle that crosses the other surface, the midpoints of the pieces between consecutive
    crossings (an edge through a thin wall counts though both its vertices are outside).
    Inside means ``|generalized winding number| >= 0.5`` (Jacobson et al. 2013), as for
    containment. When the other mesh is closed, every translation of b shorter than
    ``dist(p, surface)`` leaves p inside, so the depth is a lower bound of the minimum
    translation distance: a resting contact has depth 0 however concave its bodies, and a
    reported depth is always at most the true one (exactly the true one for a box sunk into a
    box's face). Distances come from the other mesh's hierarchy (exact point-triangle
    distance). When the other mesh is closed, points are decided by regions (vertices joined
    by edges of triangles clear of the other surface lie on one side, so one exact test decides
    each region) and the largest distance is found by branch and bound over the hierarchies;
    otherwise points are decided deepest first, the first inside one ends the search, and a
    point found outside at distance d proves every point within d of it outside. Either way the
    depth is the same maximum over the same points.
    """
    if not isinstance(meshes, MeshSet):
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}")
    if poses is not None:
        poses = as_poses(poses, len(meshes))
    pairs = _pairs(pairs, len(meshes))
    return MeshDepthBatch(**meshes._handle.depth_batch(poses, pairs, threads=threads))


def mesh_intersection_volume(
    meshes: MeshSet, poses: np.ndarray | None, pairs: np.ndarray
) -> np.ndarray:
    """Volume of the intersection of pairs of posed closed meshes, (P,) float64.

    Parameters as in :func:`mesh_distance_batch`. NaN for a pair whose meshes are not both
    closed, consistently wound manifolds (:func:`meshcol.geometry.topology.is_closed_manifold`)
    that manifold3d accepts, or that is invalid.

    Notes
    -----
    manifold3d's boolean intersection (the Manifold library's robust mesh booleans) of the
    two meshes placed in the world frame, then its volume. One boolean per pair: meant for the
    few pairs that penetrate, not for all candidates.
    """
    import manifold3d

    if not isinstance(meshes, MeshSet):
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}")
    world = np.asarray(meshes.poses if poses is None else as_poses(poses, len(meshes)))
    pairs = as_pairs(pairs, len(meshes), "meshes")
    solids: dict[int, Any] = {}

    def solid(i: int) -> Any:
        if i not in solids:
            vertices, faces = meshes.mesh(i)
            made = None
            if meshes.valid[i] and np.all(np.isfinite(world[i])) and is_closed_manifold(faces):
                placed = vertices @ world[i][:3, :3].T + world[i][:3, 3]
                m = manifold_solid(placed, faces)
                if m.status() == manifold3d.Error.NoError:
                    made = m
            solids[i] = made
        return solids[i]

    volumes = np.full(len(pairs), np.nan)
    for k, (i, j) in enumerate(pairs.tolist()):  # a boolean per pair: few pairs by contract
        a, b = solid(i), solid(j)
        if a is not None and b is not None:
            volumes[k] = abs(float((a ^ b).volume()))
    return volumes


def _pose_of(mesh: Any, pose: np.ndarray | None) -> np.ndarray:
    if pose is not None:
        return np.asarray(pose, dtype=np.float64)
    if isinstance(mesh, Body):
        return np.asarray(mesh.pose, dtype=np.float64)
    return np.eye(4)


def mesh_distance(
    a: Any,
    b: Any,
    pose_a: np.ndarray | None = None,
    pose_b: np.ndarray | None = None,
    *,
    max_distance: float = math.inf,
) -> MeshDistanceResult:
    """Exact minimum distance, intersection and containment of two posed triangle meshes.

    Parameters
    ----------
    a, b : (vertices (n, 3), faces (m, 3)) pairs, or objects with ``.vertices`` and ``.faces``
        Local frames (a :class:`meshcol.types.Body` or a ``trimesh.Trimesh`` works).
    pose_a, pose_b : (4, 4) float, optional
        Rigid world-from-local poses; default the body's ``pose`` for a Body, else identity.
    max_distance : float
        As in :func:`mesh_distance_batch`.

    Returns
    -------
    MeshDistanceResult

    Notes
    -----
    Builds a two-mesh :class:`MeshSet` and runs :func:`mesh_distance_batch`; for many queries
    on the same meshes build the set once instead.
    """
    poses = np.stack([_pose_of(a, pose_a), _pose_of(b, pose_b)])
    if poses.shape != (2, 4, 4):
        raise ValueError(f"pose_a and pose_b must be (4, 4), got {poses.shape[1:]}")
    meshes = MeshSet.from_arrays([a, b], poses, threads=1)
    r = mesh_distance_batch(meshes, None, np.array([[0, 1]]), threads=1, max_distance=max_distance)
    return MeshDistanceResult(
        distance=float(r.distance[0]),
        point_a=r.point_a[0],
        point_b=r.point_b[0],
        intersecting=bool(r.intersecting[0]),
        a_inside_b=bool(r.a_inside_b[0]),
        b_inside_a=bool(r.b_inside_a[0]),
        triangle_a=int(r.triangle_a[0]),
        triangle_b=int(r.triangle_b[0]),
        status=Status(int(r.status[0])),
    )
