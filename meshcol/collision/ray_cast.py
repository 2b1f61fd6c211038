"""Rays against triangle meshes: where each ray first meets a mesh's surface, in the core.

A ray starts at a world point and runs along a world direction, up to ``max_distance``; it is
cast against one mesh of a :class:`meshcol.collision.mesh_query.MeshSet`, whose hierarchies
are built once for every query of the set. What asset tools ask of it: where a prop dropped
straight down lands on a floor or a shelf (cast down from its lowest points), whether two
points see each other past the level's meshes (a ray with ``max_distance`` their distance),
which face is under a cursor or a sensor's beam. Rays run on several threads with the GIL
released and come back as one array per field (:class:`MeshRayCastBatch`).

Frames and signs are the package's: origins, directions and the returned points and normals
are in the world frame, each mesh posed by its world-from-local pose, and ``distance >= 0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.arrays import as_points, as_poses
from meshcol.collision.mesh_query import MeshSet

__all__ = ["MeshRayCastBatch", "mesh_ray_cast_batch"]


@dataclass(frozen=True, eq=False)
class MeshRayCastBatch:
    """Results of :func:`mesh_ray_cast_batch`, one entry per ray.

    Attributes
    ----------
    hit : (R,) bool
        The ray meets the mesh's surface within ``max_distance``.
    distance : (R,) float64
        >= 0: distance from the origin to the first hit along the ray (world units; the
        direction's length does not matter); inf without a hit; NaN for an invalid ray.
    point : (R, 3) float64
        World frame: the first hit, ``origin + distance * direction / |direction|``; NaN
        without a hit.
    normal : (R, 3) float64
        World frame: the unit normal of the face hit, on its counter-clockwise side (outward
        for an outward-wound mesh; a ray leaving a closed mesh from inside sees it pointing
        along the ray). NaN without a hit.
    triangle : (R,) int64
        The face hit (index local to its mesh); -1 without a hit.
    status : (R,) int8
        :class:`meshcol.types.Status`: ``CONVERGED``; ``INVALID_INPUT`` for a mesh that is not
        valid, a pose that is not rigid or finite, or a non-finite origin or a zero or
        non-finite direction.
    """

    hit: np.ndarray
    distance: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    triangle: np.ndarray
    status: np.ndarray

    def __len__(self) -> int:
        return len(self.hit)


def mesh_ray_cast_batch(
    meshes: MeshSet,
    mesh_indices: Any,
    origins: Any,
    directions: Any,
    *,
    poses: np.ndarray | None = None,
    max_distance: float = math.inf,
    threads: int = 0,
) -> MeshRayCastBatch:
    """First hit of each ray on the surface of one mesh of a set.

    Parameters
    ----------
    meshes : MeshSet
        The M meshes, hierarchies already built.
    mesh_indices : (R,) int
        The mesh each ray is cast against, in [0, M) (one int: every ray against that mesh).
    origins : (R, 3) float
        World frame: where each ray starts.
    directions : (R, 3) float
        World frame: along what each ray runs (any non-zero length).
    poses : (M, 4, 4) float or None
        Rigid world-from-local pose per mesh (row-major); None uses ``meshes.poses``.
    max_distance : float
        Only hits at most this far from the origin count, >= 0 (world units).
    threads : int
        Worker threads; 0 means all cores.

    Returns
    -------
    MeshRayCastBatch

    Raises
    ------
    ValueError
        On malformed shapes, a mesh index out of range or a negative or NaN ``max_distance``.

    Notes
    -----
    Each ray is clipped to its mesh's root box and the hierarchy descended nearer box first
    (the slab test, Ericson 2004, 5.3.3), boxes the ray enters beyond the nearest hit found
    pruned. At the leaves the exact segment-triangle test decides each hit by orientation
    signs (Shewchuk's filtered predicates with an exact fallback), so a ray through an edge or
    a vertex shared by two faces never passes between them; only the hit's distance is
    rounded. An origin on the surface hits at distance 0; a ray lying in a face's plane does
    not hit that face (its neighbours' edges catch it). Of hits at the same distance, the
    lowest face wins.
    """
    if not isinstance(meshes, MeshSet):
        raise TypeError(f"meshes must be a MeshSet, got {type(meshes).__name__}")
    origins = np.ascontiguousarray(as_points(origins, "origins"))
    directions = np.ascontiguousarray(as_points(directions, "directions"))
    if directions.shape != origins.shape:
        raise ValueError(f"directions must be {origins.shape} like origins, got {directions.shape}")
    indices = _mesh_indices(mesh_indices, len(origins))
    if poses is not None:
        poses = as_poses(poses, len(meshes))
    max_distance = float(max_distance)
    if not max_distance >= 0.0:
        raise ValueError(f"max_distance must be >= 0, got {max_distance}")
    columns = meshes._handle.ray_cast_batch(
        indices, origins, directions, poses, max_distance=max_distance, threads=threads
    )
    return MeshRayCastBatch(**columns)


def _mesh_indices(mesh_indices: Any, rays: int) -> np.ndarray:
    """``mesh_indices`` as a C-contiguous (R,) int64 array (one int: every ray); the core
    checks their range."""
    indices = np.asarray(mesh_indices)
    if indices.size and indices.dtype.kind not in "iu":
        raise ValueError(f"mesh_indices must hold integer indices, got dtype {indices.dtype}")
    if indices.ndim == 0:
        indices = np.full(rays, indices, dtype=np.int64)
    if indices.shape != (rays,):
        raise ValueError(f"mesh_indices must be ({rays},) or one index, got {indices.shape}")
    return np.ascontiguousarray(indices, dtype=np.int64)
