"""The mesh stage of ``check``: pairs decided on the triangles, never on the hulls.

Rows of a :class:`~meshcol.analysis.pairs.PairTable` with a ``mesh`` body, and convex rows
that may nest, go to the exact triangle-mesh queries of :mod:`meshcol.collision.mesh_query`:
distance and containment (winding numbers), and for surfaces that touch, cross or nest the
mesh depth (a lower bound of the minimum translation distance) and, when penetrating, the
intersection volume (manifold3d). Runs after :func:`~meshcol.analysis.pairs.convex_phase`,
whose numbers it replaces on mesh rows.
"""

from __future__ import annotations

import dataclasses
import itertools
import operator
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.analysis.pairs import MEASURES, NO_ANSWER, PairTable, PlacedColliders
from meshcol.types import Status
from meshcol.vocabulary import HALF_SPACE_COLLIDER

__all__ = ["mesh_phase"]


def _exact_rows(
    table: PairTable, placed: PlacedColliders, tolerance: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(mesh, exact)`` row masks: rows with a ``mesh`` body, and those plus the convex rows
    that may nest (touching or overlapping, one body's box inside the other's). A row with a
    plane's half-space is neither: the convex phase measured it exactly (a mesh body's
    lowest point is its hull's), and a body below a floor is penetrating it, never nested.
    Nor is a ``partial`` row: its bodies' whole triangles hold parts it must not measure."""
    a, b = table.body_a, table.body_b
    kinds = placed.colliders.kinds  # compared in a C loop (a million bodies)
    mesh_bodies = np.fromiter(map(operator.eq, kinds, itertools.repeat("mesh")), bool, len(kinds))
    mesh = mesh_bodies[a] | mesh_bodies[b]
    lo, hi = placed.body_min, placed.body_max
    a_in_b = np.all((lo[a] >= lo[b]) & (hi[a] <= hi[b]), axis=1)
    b_in_a = np.all((lo[b] >= lo[a]) & (hi[b] <= hi[a]), axis=1)
    nested = (table.signed_distance <= tolerance) & ~mesh & (a_in_b | b_in_a)
    if table.partial.any():  # some part pairs filtered out: the allowed ones' answer stands
        mesh, nested = mesh & ~table.partial, nested & ~table.partial
    if HALF_SPACE_COLLIDER in kinds:
        plane = np.fromiter(
            map(operator.eq, kinds, itertools.repeat(HALF_SPACE_COLLIDER)), bool, len(kinds)
        )
        measured = ~(plane[a] | plane[b])
        mesh, nested = mesh & measured, nested & measured
    return mesh, mesh | nested


@dataclass(frozen=True, eq=False)
class _Surfaces:
    """The triangle meshes of the bodies some rows involve, at their poses."""

    meshes: Any  # meshcol.collision.mesh_query.MeshSet
    poses: np.ndarray
    local: np.ndarray  # body index -> mesh index (-1: not involved)

    @classmethod
    def of(cls, bodies: Sequence[Any], body_pairs: np.ndarray) -> _Surfaces:
        from meshcol.collision.mesh_query import MeshSet

        involved = np.unique(body_pairs.ravel())
        local = np.full(len(bodies), -1, dtype=np.int64)
        local[involved] = np.arange(len(involved))
        meshes = MeshSet.from_bodies([bodies[i] for i in involved])
        return cls(meshes, np.stack([bodies[i].pose for i in involved]), local)

    def pairs(self, table: PairTable, rows: np.ndarray) -> np.ndarray:
        """(len(rows), 2) mesh index pairs of ``rows``."""
        return self.local[table.body_pairs[rows]]


def _decided(surfaces: _Surfaces, pairs: np.ndarray) -> np.ndarray:
    """(len(pairs),) bool: both meshes of each pair are orientable, so the winding number
    (after :meth:`MeshSet.from_arrays` wound them consistently) decides inside tests."""
    orientable = surfaces.meshes.orientable
    return orientable[pairs[:, 0]] & orientable[pairs[:, 1]]


def _containment(
    found: Any, surfaces: _Surfaces, pairs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(contained, undecided)`` per pair: one mesh inside the other by the winding number,
    or, against a non-orientable mesh, by the exact even-odd rule
    (:func:`meshcol.collision.ray_parity.ray_parity`) of one vertex of the other mesh;
    undecided where that is not defined (the vertex on the surface, or a surface that does
    not close up). Surfaces that cross are never contained."""
    inside = (found.a_inside_b | found.b_inside_a) & ~found.intersecting
    unsure = np.zeros(len(pairs), dtype=bool)
    meshes = surfaces.meshes
    for k in np.flatnonzero(~_decided(surfaces, pairs) & ~found.intersecting).tolist():
        verdict, open_question = False, False
        for inner, outer in (pairs[k], pairs[k][::-1]):
            if meshes.orientable[outer]:
                verdict |= bool(
                    found.a_inside_b[k] if inner == pairs[k][0] else found.b_inside_a[k]
                )
                continue
            is_inside, decided = _parity_of_vertex(surfaces, int(inner), int(outer))
            verdict |= is_inside and decided
            open_question |= not decided
        inside[k] = verdict
        unsure[k] = open_question and not verdict
    return inside, unsure


def _parity_of_vertex(surfaces: _Surfaces, inner: int, outer: int) -> tuple[bool, bool]:
    """Ray parity of the first vertex of mesh ``inner`` against mesh ``outer``."""
    from meshcol.collision.ray_parity import ray_parity

    vertices, _ = surfaces.meshes.mesh(inner)
    world = surfaces.poses[inner] @ np.append(vertices[0], 1.0)
    local = np.linalg.solve(surfaces.poses[outer], world)[:3]
    outer_vertices, outer_faces = surfaces.meshes.mesh(outer)
    is_inside, decided = ray_parity(local[None], outer_vertices, outer_faces)
    return bool(is_inside[0]), bool(decided[0])


def _subset(batch: Any, mask: np.ndarray) -> Any:
    """The entries ``mask`` of a batch result (a dataclass of arrays)."""
    fields = dataclasses.fields(batch)
    return type(batch)(*(getattr(batch, f.name)[mask] for f in fields))


def mesh_phase(
    table: PairTable, placed: PlacedColliders, tolerance: float, threads: int = 0
) -> PairTable:
    """Exact triangle-mesh queries: rows with a ``mesh`` body, and containment of convex rows
    that may nest (judged on the real surfaces).

    A mesh row takes everything from the triangles, never from the hulls (a hull's depth
    calls a concave resting contact penetrating): apart, the exact distance and closest
    points; crossing, touching or nested, the mesh depth (a lower bound of the minimum
    translation distance) and, when penetrating deeper than ``tolerance``, the intersection
    volume. Only a body's box inside the other's can hold it, so only such convex rows are
    tested for containment.
    """
    if len(table) == 0:
        return table
    mesh, exact = _exact_rows(table, placed, tolerance)
    if not exact.any():
        return table
    from meshcol.collision.mesh_query import mesh_distance_batch

    rows = np.flatnonzero(exact)
    colliders = placed.colliders
    surfaces = _Surfaces.of(colliders.bodies, table.body_pairs[rows])
    pairs = surfaces.pairs(table, rows)
    found = mesh_distance_batch(surfaces.meshes, surfaces.poses, pairs, threads=threads)
    inside, unsure = _containment(found, surfaces, pairs)
    if not mesh[rows].any():  # convex rows that may nest, no mesh row: nothing else changes
        out = table.writable("contained", "undecided")
        out.contained[rows] = inside
        out.undecided[rows] = unsure
        return out
    out = table.writable(*MEASURES)
    out.contained[rows] = inside
    out.undecided[rows] = unsure
    mesh_rows = rows[mesh[rows]]
    on_mesh = _subset(found, mesh[rows])
    hit = on_mesh.intersecting | inside[mesh[rows]]
    _mesh_distances(out, mesh_rows, on_mesh, hit)
    if hit.any():
        _mesh_depths(out, mesh_rows[hit], _subset(on_mesh, hit), surfaces, tolerance, threads)
    # crossing a mesh no inside test decides: 0 is the only depth that is surely not too deep
    crossing = mesh_rows[on_mesh.intersecting & ~_decided(surfaces, pairs[mesh[rows]])]
    out.depth[crossing] = 0.0
    out.undecided[crossing] = True
    out.intersection_volume[crossing] = np.nan
    out.signed_distance[mesh_rows] = out.distance[mesh_rows] - out.depth[mesh_rows]
    out.part_a[mesh_rows] = -1
    out.part_b[mesh_rows] = -1
    # the parts holding the closest points (hull parts where the surfaces cross)
    tri_a, tri_b = on_mesh.triangle_a, on_mesh.triangle_b
    labels_a = colliders.face_labels(out.body_a[mesh_rows], tri_a)
    labels_b = colliders.face_labels(out.body_b[mesh_rows], tri_b)
    out.label_a[mesh_rows] = np.where(tri_a >= 0, labels_a, out.label_a[mesh_rows])
    out.label_b[mesh_rows] = np.where(tri_b >= 0, labels_b, out.label_b[mesh_rows])
    return out


def _mesh_distances(out: PairTable, rows: np.ndarray, found: Any, hit: np.ndarray) -> None:
    """Mesh rows from the exact distance: apart, the distance, closest points and the unit
    gap as normal; crossing, touching or nested (``hit``), distance 0."""
    out.distance[rows] = np.where(hit, 0.0, found.distance)
    out.depth[rows] = 0.0
    apart = rows[~hit]
    out.point_a[apart] = found.point_a[~hit]
    out.point_b[apart] = found.point_b[~hit]
    gap = found.point_b[~hit] - found.point_a[~hit]
    length = np.linalg.norm(gap, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out.normal[apart] = np.where(length > 0, gap / length, out.normal[apart])
    out.query_failed[rows] = np.isin(found.status, NO_ANSWER)


def _mesh_depths(
    out: PairTable,
    rows: np.ndarray,
    found: Any,
    surfaces: _Surfaces,
    tolerance: float,
    threads: int,
) -> None:
    """Mesh rows whose surfaces cross, touch or nest: the mesh depth and its points; touching
    without depth, the shared point and the normal of a's face there; penetrating, the
    intersection volume."""
    from meshcol.collision.mesh_query import mesh_intersection_volume, mesh_penetration_depth_batch

    pairs = surfaces.pairs(out, rows)
    depths = mesh_penetration_depth_batch(surfaces.meshes, surfaces.poses, pairs, threads=threads)
    deep = depths.depth > 0.0
    out.depth[rows] = np.where(np.isfinite(depths.depth), depths.depth, 0.0)
    out.point_a[rows[deep]] = depths.point_a[deep]
    out.point_b[rows[deep]] = depths.point_b[deep]
    out.normal[rows[deep]] = depths.normal[deep]
    touch = ~deep & found.intersecting
    out.point_a[rows[touch]] = found.point_a[touch]
    out.point_b[rows[touch]] = found.point_a[touch]
    out.normal[rows[touch]] = _face_normals(
        surfaces.meshes, pairs[touch, 0], found.triangle_a[touch], surfaces.poses
    )
    out.query_failed[rows] |= depths.status != int(Status.CONVERGED)
    penetrating = rows[deep & (out.depth[rows] > tolerance)]
    if len(penetrating):
        out.intersection_volume[penetrating] = mesh_intersection_volume(
            surfaces.meshes, surfaces.poses, surfaces.pairs(out, penetrating)
        )


def _face_normals(meshes: Any, mesh: np.ndarray, face: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """World unit normals (n, 3) of face ``face[k]`` of mesh ``mesh[k]`` (NaN when degenerate
    or when the face is -1)."""
    out = np.full((len(mesh), 3), np.nan)
    ok = face >= 0
    if not ok.any():
        return out
    rows = meshes.faces[meshes.face_offsets[mesh[ok]] + face[ok]]
    corners = meshes.vertices[meshes.vertex_offsets[mesh[ok], None] + rows]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    local = np.stack(
        [
            e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1],
            e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
            e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0],
        ],
        axis=1,
    )
    world = np.einsum("kij,kj->ki", poses[mesh[ok], :3, :3], local)
    length = np.linalg.norm(world, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out[ok] = np.where(length > 0, world / length, np.nan)
    return out
