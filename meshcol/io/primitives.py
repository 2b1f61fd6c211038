"""The tessellation of analytic primitives (manifest primitive bodies, robot links' parts).

Queries use a primitive exactly (``Body.primitive``); its triangles are for what needs a mesh:
the review page, exporters, mass properties of a mesh, and the parts of a body that mixes
primitives with meshes. :func:`primitive_mesh` (made in :mod:`meshcol.types`, where a primitive
body makes its tessellation on first use) caches one tessellation per distinct primitive.
:func:`written_primitive` is the one rule of what a rebuilt robot description holds for a
primitive, whatever its format.
"""

from __future__ import annotations

import numpy as np

from meshcol.types import Box, Capsule, Ellipsoid, HalfSpace, Primitive, Sphere, primitive_mesh

__all__ = ["enclosing_primitive_mesh", "primitive_mesh", "written_primitive"]


def _support(primitive: Primitive, directions: np.ndarray) -> np.ndarray:
    """The primitive's support function h(n) = max over the primitive of n . x, per unit
    direction (k, 3)."""
    n = directions
    if isinstance(primitive, HalfSpace):
        raise TypeError("a half-space is unbounded: no mesh encloses it")
    if isinstance(primitive, Sphere):
        return np.full(len(n), primitive.radius)
    if isinstance(primitive, Box):
        return np.abs(n) @ (0.5 * np.asarray(primitive.size))
    if isinstance(primitive, Ellipsoid):
        return np.linalg.norm(n * np.asarray(primitive.semi_axes), axis=1)
    half = 0.5 * primitive.length
    if isinstance(primitive, Capsule):
        return primitive.radius + half * np.abs(n[:, 2])
    return primitive.radius * np.hypot(n[:, 0], n[:, 1]) + half * np.abs(n[:, 2])


def enclosing_primitive_mesh(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    """A closed convex mesh that CONTAINS the primitive: :func:`primitive_mesh` scaled about
    the centre until every face plane clears the primitive (by its support function).

    The inscribed tessellation cuts inside a round primitive; a collider written to a file
    must not, or the file would no longer enclose what the fit enclosed. The scale is at most
    a few tenths of a percent for the tessellations used here (1.0 for a box)."""
    vertices, faces = primitive_mesh(primitive)
    if isinstance(primitive, Box):
        return vertices, faces
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 0
    normals = normals[keep] / length[keep, None]
    offsets = np.einsum("ij,ij->i", normals, tri[keep, 0])
    outward = offsets > 0
    need = _support(primitive, normals[outward]) / offsets[outward]
    scale = max(1.0, float(np.max(need))) * (1.0 + 1e-12) if len(need) else 1.0
    return vertices * scale, faces


def written_primitive(primitive: Primitive) -> Primitive:
    """The primitive a description written holds for ``primitive``: a capsule of length 0
    (under 1e-15, the writers' zero; the capsule fit of a ball) is its sphere, the same
    solid, for every format (MuJoCo refuses a capsule of half-length 0; a URDF's standard
    capsule would be a cylinder of length 0 between two equal spheres); any other as it is."""
    if isinstance(primitive, Capsule) and primitive.length < 1e-15:
        return Sphere(primitive.radius)
    return primitive
