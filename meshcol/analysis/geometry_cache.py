"""What a mesh decides in its own frame, measured once per unique geometry.

``meshcol inspect`` measures each body's mesh (:mod:`meshcol.analysis.health`) and its
collider against it (:mod:`meshcol.analysis.physics`). Bodies that instance one mesh (a level
of props) share one :class:`LocalGeometry` through a :class:`GeometryCache`, so a level of
instanced props is measured once per prop. Nothing here depends on a body's name, source, pose
or units; what does (bounds, size, which faces are degenerate and so which cross, the units
guess, every finding's names) each body computes itself.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from meshcol.collision.arrays import as_offsets
from meshcol.errors import InvalidMeshError
from meshcol.geometry.mass import MassProperties
from meshcol.geometry.topology import (
    component_count,
    duplicate_face_count,
    edge_table,
    is_balanced,
    manifold_solid,
    oriented_volume,
    oriented_volume_batch,
)
from meshcol.geometry.triangles import face_heights

if TYPE_CHECKING:
    from meshcol.collision.self_intersection import SelfIntersections

__all__ = ["GeometryCache", "LocalGeometry", "geometry_key", "measure_geometries"]


def geometry_key(vertices: np.ndarray, faces: np.ndarray | None = None) -> bytes:
    """Content key of a point set, or of a mesh when ``faces`` are given: equal keys, the same
    float64 vertices to the bit (and the same int64 faces), so what the geometry alone decides
    (a hull, a fit; inspect's health and local mass properties) is computed once per key, not
    per instance. A 128-bit blake2b digest; 0.0 and -0.0 differ, which only costs a second
    computation."""
    h = hashlib.blake2b(digest_size=16)
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    if faces is not None:
        # the vertex count first: one split only of the bytes into vertices and faces
        h.update(np.int64(len(v)).tobytes())
    h.update(v.tobytes())
    if faces is not None:
        h.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    return h.digest()


class LocalGeometry:
    """One mesh's vertices and faces (its local frame) and what they alone decide, each
    measured on first use."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.vertices = vertices
        self.faces = faces
        # crossing face pairs per degenerate-face mask (a mask follows the body's diagonal)
        self._crossings: dict[bytes, SelfIntersections] = {}

    @cached_property
    def used(self) -> np.ndarray:
        """(k,) int64: the vertices the faces use, ascending."""
        return np.unique(self.faces)

    @cached_property
    def heights(self) -> tuple[np.ndarray, np.ndarray]:
        """:func:`meshcol.geometry.triangles.face_heights`."""
        return face_heights(self.vertices, self.faces)

    @cached_property
    def edges(self) -> tuple[int, int, int]:
        """Boundary edges (one face), non-manifold edges (more than two), inconsistently
        wound edges."""
        _, counts, inconsistent = edge_table(self.faces)
        return int((counts == 1).sum()), int((counts > 2).sum()), int(inconsistent)

    @cached_property
    def oriented_volume(self) -> tuple[float, int] | None:
        """:func:`meshcol.geometry.topology.oriented_volume`."""
        return oriented_volume(self.vertices, self.faces)

    @cached_property
    def duplicates(self) -> int:
        """Faces on the same three vertices as an earlier face."""
        return duplicate_face_count(self.faces)

    @cached_property
    def components(self) -> int:
        """Connected pieces (faces linked through shared vertices)."""
        return component_count(self.faces, len(self.vertices))

    @cached_property
    def balanced(self) -> bool:
        """:func:`meshcol.geometry.topology.is_balanced` of the faces without a repeated
        corner (what :func:`~meshcol.geometry.topology.manifold_solid` gives manifold3d)."""
        faces = self.faces
        kept = (
            (faces[:, 0] != faces[:, 1])
            & (faces[:, 1] != faces[:, 2])
            & (faces[:, 0] != faces[:, 2])
        )
        return is_balanced(faces[kept])

    @cached_property
    def manifold_status(self) -> str:
        """manifold3d's verdict on the mesh (``NoError``, ``NotManifold``, ...)."""
        return _manifold_status(self.vertices, self.faces, self.balanced)

    @cached_property
    def hull_volume(self) -> float | None:
        """The volume of the vertices' exact hull; None when they have none."""
        from meshcol.collision.hull import exact_hull

        try:
            return exact_hull(self.vertices).volume
        except InvalidMeshError:
            return None

    @cached_property
    def mass(self) -> MassProperties:
        """:func:`meshcol.geometry.mass.mass_properties`, in the local frame."""
        from meshcol.geometry.mass import mass_properties

        return mass_properties(self.vertices, self.faces)

    def crossings(self, skip: np.ndarray) -> SelfIntersections:
        """The pairs of faces that cross, the faces of ``skip`` ((m,) bool) left out
        (:func:`meshcol.collision.self_intersection.self_intersections`: a count, and whether
        the work budget let every candidate pair be decided)."""
        key = skip.tobytes()
        found = self._crossings.get(key)
        if found is None:
            from meshcol.collision.self_intersection import self_intersections

            found = self._crossings[key] = self_intersections(self.vertices, self.faces, skip=skip)
        return found


class GeometryCache:
    """The :class:`LocalGeometry` of each mesh of one inspect run, shared by the bodies (and
    the health and physics phases) that use it: found by the arrays themselves first (a file's
    instances share their arrays), else by content
    (:func:`geometry_key`: the same bits), so each pair of
    arrays is hashed once."""

    def __init__(self) -> None:
        self._by_key: dict[bytes, LocalGeometry] = {}
        # id pair -> (geometry, vertices, faces): the arrays are held, so the ids stay theirs
        self._by_arrays: dict[tuple[int, int], tuple[LocalGeometry, np.ndarray, np.ndarray]] = {}

    def get(self, vertices: np.ndarray, faces: np.ndarray) -> LocalGeometry:
        """The geometry of these arrays, measured by whoever asked first."""
        seen = self._by_arrays.get((id(vertices), id(faces)))
        if seen is not None:
            return seen[0]
        key = geometry_key(vertices, faces)
        geometry = self._by_key.get(key)
        if geometry is None:
            geometry = self._by_key[key] = LocalGeometry(vertices, faces)
        self._by_arrays[id(vertices), id(faces)] = (geometry, vertices, faces)
        return geometry


def _manifold_status(vertices: np.ndarray, faces: np.ndarray, balanced: bool | None = None) -> str:
    status = manifold_solid(vertices, faces, balanced=balanced).status()
    return str(getattr(status, "name", status)).split(".")[-1]


def measure_geometries(geometries: Iterable[LocalGeometry], mass: bool = True) -> None:
    """Measure what the health checks (and, with ``mass``, the mass properties) read of each
    geometry, for all of them at once, where not measured yet.

    The values are those each :class:`LocalGeometry` property computes on first use, bit for
    bit (:func:`~meshcol.collision.mesh_topology.mesh_topology_batch`, in the core,
    :func:`~meshcol.geometry.topology.oriented_volume_batch`,
    :func:`~meshcol.geometry.mass.mass_properties_batch`; the face heights are per-face
    arithmetic, the same on the faces of all meshes one after the other): some fifty numpy
    calls per group of meshes instead of per mesh, which is most of ``inspect``'s time on a
    library of small props.
    """
    todo = [g for g in dict.fromkeys(geometries) if "edges" not in g.__dict__ and len(g.faces)]
    if todo:
        _measure_topology(todo)
    if mass:
        from meshcol.geometry.mass import mass_properties_batch

        weigh = [g for g in dict.fromkeys(geometries) if "mass" not in g.__dict__]
        for geometry, measured in zip(
            weigh, mass_properties_batch([(g.vertices, g.faces) for g in weigh])
        ):
            geometry.__dict__["mass"] = measured


def _measure_topology(todo: list[LocalGeometry]) -> None:
    """Fill the topology, face heights and oriented volume of each geometry (every one with
    faces; one a face of which names a vertex it lacks is left to its own properties)."""
    from meshcol.collision.mesh_topology import face_heights as native_face_heights
    from meshcol.collision.mesh_topology import mesh_topology_batch

    faces = [np.asarray(g.faces, dtype=np.int64) for g in todo]
    topology = mesh_topology_batch(faces, [len(g.vertices) for g in todo])
    if not topology.valid.all():
        keep = np.flatnonzero(topology.valid).tolist()
        todo, faces = [todo[i] for i in keep], [faces[i] for i in keep]
        topology = mesh_topology_batch(faces, [len(g.vertices) for g in todo])
    vertex_offsets = as_offsets([len(g.vertices) for g in todo])
    face_offsets = as_offsets([len(f) for f in faces])
    vertices = np.concatenate([np.asarray(g.vertices, dtype=np.float64) for g in todo])
    shift = np.repeat(vertex_offsets[:-1], np.diff(face_offsets))
    every = np.concatenate(faces) + shift[:, None]
    heights, repeated = native_face_heights(vertices, every)
    volumes = oriented_volume_batch(vertices, every, face_offsets, topology.closed)
    for i, geometry in enumerate(todo):
        lo, hi = int(face_offsets[i]), int(face_offsets[i + 1])
        geometry.__dict__.update(
            used=topology.used[i],
            heights=(heights[lo:hi], repeated[lo:hi]),
            edges=(
                int(topology.boundary_edges[i]),
                int(topology.non_manifold_edges[i]),
                int(topology.inconsistent_edges[i]),
            ),
            oriented_volume=volumes[i],
            duplicates=int(topology.duplicate_faces[i]),
            components=int(topology.components[i]),
            balanced=bool(topology.balanced[i]),
        )
