"""The tessellation of analytic primitives (manifest primitive bodies, robot links' parts).

Queries use a primitive exactly (``Body.primitive``); its triangles are for what needs a mesh:
reports, exporters, and the parts of a body that mixes primitives with meshes.
"""

from __future__ import annotations

import numpy as np

from meshcol.types import Box, Capsule, Primitive, Sphere

__all__ = ["primitive_mesh"]

_SPHERE_SUBDIVISIONS = 3  # icosphere: 642 vertices
_ROUND_SECTIONS = 32  # around the axis of capsules and cylinders


def primitive_mesh(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float64 and faces (m, 3) int64 of a primitive, centred, axis along z.

    Sphere: an icosphere of 642 vertices; capsule and cylinder: 32 sections around the axis;
    box: 8 vertices. The vertices lie on the surface (the polytope is inscribed)."""
    import trimesh

    if isinstance(primitive, Box):
        mesh = trimesh.creation.box(extents=np.asarray(primitive.size, dtype=np.float64))
    elif isinstance(primitive, Sphere):
        mesh = trimesh.creation.icosphere(
            subdivisions=_SPHERE_SUBDIVISIONS, radius=primitive.radius
        )
    elif isinstance(primitive, Capsule):
        mesh = trimesh.creation.capsule(
            height=primitive.length,
            radius=primitive.radius,
            count=[_ROUND_SECTIONS, _ROUND_SECTIONS],
        )
    else:
        mesh = trimesh.creation.cylinder(
            radius=primitive.radius, height=primitive.length, sections=_ROUND_SECTIONS
        )
    return (
        np.ascontiguousarray(mesh.vertices, dtype=np.float64),
        np.ascontiguousarray(mesh.faces, dtype=np.int64),
    )
