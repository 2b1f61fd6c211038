"""The topology of many meshes at once, in the core: what ``meshcol inspect``'s health checks
count of each mesh (edges by their number of faces, winding, closedness, balance, duplicate
faces, connected pieces, used vertices); and the face heights its degenerate-face rule reads.

One native call for a whole library of meshes, threads over meshes: each mesh's few dozen to
few thousand edges are sorted where they sit in cache, instead of numpy sorting the edges of
every mesh together. Integer counts only, the numbers of the single-mesh functions of
:mod:`meshcol.geometry.topology` (``tests/geometry/test_mesh_batches.py`` compares them with a
plain per-mesh reference on random dirty meshes).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_offsets

__all__ = ["MeshTopologyBatch", "face_heights", "mesh_topology_batch"]


@dataclass(frozen=True, eq=False)
class MeshTopologyBatch:
    """The topology of many meshes, one entry per mesh (:func:`mesh_topology_batch`).

    Attributes
    ----------
    boundary_edges, non_manifold_edges, inconsistent_edges : (n,) int64
        :func:`~meshcol.geometry.topology.edge_table`'s counts: edges with one face, with more
        than two, with two that traverse them the same way.
    closed : (n,) bool
        :func:`~meshcol.geometry.topology.is_closed_manifold`.
    balanced : (n,) bool
        :func:`~meshcol.geometry.topology.is_balanced` of the faces without a repeated corner
        (what :func:`~meshcol.geometry.topology.manifold_solid` gives manifold3d).
    duplicate_faces : (n,) int64
        :func:`~meshcol.geometry.topology.duplicate_face_count`.
    components : (n,) int64
        :func:`~meshcol.geometry.topology.component_count`.
    used : list of (k_i,) int64
        Each mesh's used vertices, ascending (``np.unique(faces)``).
    valid : (n,) bool
        False for a mesh a face of which names a vertex it does not have: nothing of it was
        counted (its entries are 0).
    """

    boundary_edges: np.ndarray
    non_manifold_edges: np.ndarray
    inconsistent_edges: np.ndarray
    closed: np.ndarray
    balanced: np.ndarray
    duplicate_faces: np.ndarray
    components: np.ndarray
    used: list
    valid: np.ndarray


def mesh_topology_batch(
    faces: Sequence[np.ndarray], vertex_counts: Sequence[int], *, threads: int = 0
) -> MeshTopologyBatch:
    """Edge counts, closedness, balance, duplicates, pieces and used vertices of many meshes.

    Parameters
    ----------
    faces : sequence of (m_i, 3) int
        Each mesh's faces, indices into its own vertices.
    vertex_counts : sequence of int
        Each mesh's vertex count.
    threads : int
        Threads over meshes (0: every core).

    Returns
    -------
    MeshTopologyBatch

    Notes
    -----
    Per mesh, in the core (``cpp/src/mesh_topology.cpp``, GIL released): its directed edges
    (collapsed ones left out) sorted by undirected key give each edge's face count and the
    balance of its directions, over all faces and over those without a repeated corner; its
    faces with sorted corners, sorted, give the duplicates; a union-find over the edges 0-1
    and 1-2 of each face, the pieces of the used vertices.
    """
    n = len(faces)
    arrays = [np.asarray(f, dtype=np.int64).reshape(-1, 3) for f in faces]
    face_offsets = as_offsets([len(f) for f in arrays])
    vertex_offsets = as_offsets([int(c) for c in vertex_counts])
    if len(vertex_offsets) != n + 1:
        raise ValueError(
            f"vertex_counts must have one count per mesh ({n}), got {len(vertex_offsets) - 1}"
        )
    every = np.ascontiguousarray(np.concatenate(arrays) if n else np.zeros((0, 3), np.int64))
    counts, closed, balanced, used_flags, status = core.mesh_topology_batch(
        every, face_offsets, vertex_offsets, threads
    )
    used_all = np.flatnonzero(used_flags)
    cuts = np.searchsorted(used_all, vertex_offsets)
    used = [used_all[cuts[i] : cuts[i + 1]] - vertex_offsets[i] for i in range(n)]
    return MeshTopologyBatch(
        boundary_edges=counts[:, 0],
        non_manifold_edges=counts[:, 1],
        inconsistent_edges=counts[:, 2],
        closed=closed,
        balanced=balanced,
        duplicate_faces=counts[:, 3],
        components=counts[:, 4],
        used=used,
        valid=status == 0,
    )


def face_heights(
    vertices: np.ndarray, faces: np.ndarray, *, threads: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`meshcol.geometry.triangles.face_heights` in the core, to the bit.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        Indices into ``vertices`` (every mesh of a batch, one after the other, its indices
        shifted by the vertices before it).
    threads : int
        Threads over faces (0: every core).

    Returns
    -------
    heights : (m,) float64
        Each face's height on its longest edge (0 when that edge has length 0).
    repeated : (m,) bool
        The face names one vertex twice.

    Notes
    -----
    The numpy function's arithmetic in its order (``cpp/src/mesh_topology.cpp``, no fused
    multiply-add): the cross product of two edges, each norm summed x, y, z, NaN winning the
    longest edge; ``tests/geometry/test_mesh_batches.py`` compares the bits.
    """
    return core.face_heights(
        np.ascontiguousarray(vertices, dtype=np.float64),
        np.ascontiguousarray(faces, dtype=np.int64),
        threads,
    )
