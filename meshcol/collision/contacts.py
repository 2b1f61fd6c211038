"""Contacts between triangle meshes: every crossing triangle pair and its own penetration.

The pairs a physics or planning pipeline reads from coal's or FCL's mesh ``collide`` with
contacts: for each pair of posed meshes of a :class:`meshcol.collision.mesh_query.MeshSet`,
the triangle pairs whose closed triangles meet, each with the minimum translation that
separates the two triangles (its depth), a unit normal, a point, and coal's own per-pair depth
beside it (``face_depth``: along a's face normal, not the shortest); per mesh pair their number and the deepest
(:class:`MeshContactsBatch`), and on request every contact, flat, with per-pair offsets. This
is not the meshes' penetration depth (:func:`meshcol.collision.mesh_query.
mesh_penetration_depth_batch`): a triangle pair's depth is local to the two triangles.

Frames and signs are the package's: points and normals in the world frame, ``depth >= 0``,
the normal from a towards b (the direction to move b to separate the two triangles).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_pairs, as_poses
from meshcol.collision.mesh_query import MeshSet

__all__ = ["MeshContactsBatch", "mesh_contacts_batch"]


@dataclass(frozen=True, eq=False)
class MeshContactsBatch:
    """Results of :func:`mesh_contacts_batch`: the deepest contact of each pair, and the
    listed contacts of all pairs (flat, pair k's at ``contact_offsets[k]:contact_offsets[k + 1]``).

    Attributes
    ----------
    count : (P,) int64
        Crossing triangle pairs (the closed triangles share a point; touching counts), >= 0.
        With ``MAX_ITERATIONS``, those found before the work cap.
    depth : (P,) float64
        >= 0: the deepest crossing pair's own penetration depth (the minimum translation that
        separates its two triangles); 0 when count is 0; NaN when the pair is invalid or out
        of range. Of equal depths, the lowest ``triangle_a``, then ``triangle_b``, wins.
    normal : (P, 3) float64
        World unit vector from a towards b: moving b by ``depth`` along it separates the
        deepest pair's two triangles (not, in general, the meshes). NaN when count is 0 (and
        for two triangles degenerate to parallel segments or points).
    point : (P, 3) float64
        World frame: midway between the deepest pair's witness points (b's point deepest past
        a, and where it meets a once b is moved by ``depth * normal``; on the features the
        depth's axis names, see :func:`mesh_contacts_batch`); NaN when count is 0.
    face_depth : (P,) float64
        >= 0: the largest, over the crossing pairs, of how far b's triangle reaches behind a's
        triangle's face along a's unit face normal, ``(p1 - p0) x (p2 - p0)`` normalised:
        ``max over b's corners q of n . (p0 - q)``. It separates the two triangles when b
        moves by it along a's normal, but is not the shortest such move, and it depends on
        a's winding: the per-pair ``penetration_depth`` coal 3.0.3's mesh ``collide`` reports
        (measured: see ``benchmarks/RESULTS.md``), so ``face_depth`` is coal's deepest
        contact. 0 when count is 0; NaN when the pair is invalid or out of range.
    triangle_a, triangle_b : (P,) int64
        The deepest pair's faces (indices local to each mesh); -1 when count is 0.
    status : (P,) int8
        :class:`meshcol.types.Status`: ``CONVERGED``; ``MAX_ITERATIONS`` when the triangle pairs
        whose boxes touch exceed ``max_work`` (count and the deepest are of the pairs found);
        ``INVALID_INPUT`` for a mesh that is not valid or a pose that is not rigid or finite;
        ``OUT_OF_RANGE`` for a pair beyond the range of the exact search.
    contact_offsets : (P + 1,) int64
        Pair k's listed contacts are rows ``contact_offsets[k]:contact_offsets[k + 1]`` of the
        ``contact_`` arrays: ``min(count[k], max_contacts)`` of them (none with
        ``max_contacts=0``), in order of (triangle_a, triangle_b).
    contact_depth : (C,) float64
        Each listed contact's depth, as ``depth``.
    contact_normal, contact_point : (C, 3) float64
        Each listed contact's normal and point, as ``normal`` and ``point``.
    contact_face_depth : (C,) float64
        Each listed contact's face depth, as ``face_depth`` for its one pair.
    contact_triangle_a, contact_triangle_b : (C,) int64
        Each listed contact's faces.
    """

    count: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    point: np.ndarray
    face_depth: np.ndarray
    triangle_a: np.ndarray
    triangle_b: np.ndarray
    status: np.ndarray
    contact_offsets: np.ndarray
    contact_depth: np.ndarray
    contact_normal: np.ndarray
    contact_point: np.ndarray
    contact_face_depth: np.ndarray
    contact_triangle_a: np.ndarray
    contact_triangle_b: np.ndarray

    def __len__(self) -> int:
        return len(self.count)


def mesh_contacts_batch(
    meshes: MeshSet,
    poses: np.ndarray | None,
    pairs: np.ndarray,
    *,
    max_contacts: int = 0,
    threads: int = 0,
    max_work: int = core.defaults.mesh_contacts_max_work,
) -> MeshContactsBatch:
    """Every crossing triangle pair of pairs of posed meshes, with its penetration depth.

    Parameters
    ----------
    meshes : MeshSet
        The M meshes, hierarchies already built.
    poses : (M, 4, 4) float or None
        Rigid world-from-local pose per mesh (row-major); None uses ``meshes.poses``. A
        non-rigid or non-finite pose makes its pairs ``Status.INVALID_INPUT``.
    pairs : (P, 2) int
        Mesh indices (a, b) per query, in [0, M).
    max_contacts : int
        List up to this many contacts a pair (>= 0), in order of (triangle_a, triangle_b);
        0 lists none. The count and the deepest are over every crossing pair regardless.
    threads : int
        Worker threads; 0 means all cores.
    max_work : int
        Work cap a pair (>= 0): triangle pairs whose boxes touch, each tested exactly (those
        the descent reaches; all of them when the two poses' rotations are equal).

    Returns
    -------
    MeshContactsBatch

    Raises
    ------
    ValueError
        On malformed shapes, a pair index out of range, or a negative ``max_contacts`` or
        ``max_work``.

    Notes
    -----
    The crossing pairs are those of :func:`meshcol.collision.mesh_query.mesh_intersects_batch`'s
    descent run to the end: overlapping oriented boxes of both hierarchies (when the two
    poses' rotations are equal, axis-aligned boxes in a's frame, b's moved by the
    translation; a dense turned pair finishes by axis-aligned boxes of b refitted in a's
    frame), then the exact triangle-triangle test (orientation signs, Guigue and Devillers 2003). Each pair's depth is
    the separating axis theorem's over the two face normals and the nine edge-edge cross
    products (Gottschalk, Lin and Manocha 1996; Ericson 2004, 4.4): the facets of the two
    triangles' Minkowski difference have normals among these, so the minimum overlap is the
    minimum translation distance (coal 3.0.3 reports another per-pair quantity instead, the
    ``face_depth`` above, never smaller up to rounding). A parallel
    edge pair or a degenerate triangle's normal is no axis; exactly coplanar triangles have
    depth 0 (orient3d). The contact point is midway between the witness points, the closest
    points of the two triangles once b is moved by ``depth * normal`` to touch a, taken on the
    features the depth's axis names: for a face normal, the other triangle's corner deepest
    along it (the first of equally deep corners) and its foot on the face; for an edge pair's
    cross product, the closest points of the two edges. Where those are not within 1e-12 of
    the largest coordinate of each other (the corner's foot falls outside the face, or the two
    edges do not meet: an axis tied with another up to rounding), the closest points over all
    15 feature pairs (Ericson 2004, 5.1.9). Where equally close points form a segment or
    polygon (parallel faces or edges), the point is thus one of them, chosen by the axis. A
    touching pair's (depth 0): where the descent ran the exact test on it (a corner of one on
    the other's plane, save where one lies in a coordinate plane the other only touches) the
    point that test found both share; else midway between the closest points of the features
    its axis names (b not moved) if within 1e-12 of the largest coordinate, else a shared point.
    """
    if not isinstance(meshes, MeshSet):
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}")
    max_contacts, max_work = int(max_contacts), int(max_work)
    if max_contacts < 0:
        raise ValueError(f"max_contacts must be >= 0, got {max_contacts}")
    if max_work < 0:
        raise ValueError(f"max_work must be >= 0, got {max_work}")
    if poses is not None:
        poses = as_poses(poses, len(meshes))
    pairs = as_pairs(pairs, len(meshes), "meshes")
    columns = meshes._handle.contacts_batch(
        poses, pairs, threads=threads, max_contacts=max_contacts, max_work=max_work
    )
    return MeshContactsBatch(**columns)
