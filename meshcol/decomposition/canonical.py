"""Canonical forms: the input mesh and the parts, independent of vertex and face order, and
the content key of the cache.

The canonical input is quantised (:func:`quantise`), so that one geometry keeps one key
through re-exports: written as OBJ or PLY (float64, at least 9 significant digits) and as STL
(float32), it gets the same canonical vertices, hence the same key; and the engine runs on
the quantised vertices, so a cache entry is exactly what a fresh run on any input with that
key gives."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from meshcol.collision.hull import convex_hull, exact_hull
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import unique_rows

__all__ = [
    "CACHE_FORMAT",
    "as_mesh_arrays",
    "cache_key",
    "canonical_faces",
    "canonical_geometry",
    "canonical_part",
    "quantise",
]


# Bump when the cache entry layout or the canonicalisation of inputs or parts changes.
CACHE_FORMAT = 3

#: Canonical coordinates lie on a grid of ``2**-QUANTUM_BITS`` times the power of two at or
#: above the largest absolute coordinate (between 2**-20 and 2**-19 of it: about 1e-6).
QUANTUM_BITS = 20


def quantise(vertices: np.ndarray) -> np.ndarray:
    """Coordinates rounded to float32, then to the nearest point of a power-of-two grid.

    The grid step is ``2**(e - QUANTUM_BITS)``, where ``2**e`` is the smallest power of two at
    or above the largest absolute coordinate (after the float32 rounding): between ``2**-20``
    and ``2**-19`` of it. Each coordinate moves by at most half a step plus its float32
    rounding (under 1e-6 of the mesh's magnitude); every operation is exact in float64 beyond
    these two roundings, so the result depends only on the float32 values.

    Guarantees (for the cache key): inputs whose coordinates have equal float32 values get
    equal results, so float64 geometry and its float32 STL export always agree. Noise of
    size ``d`` smaller than the step changes a coordinate's result only if the coordinate
    lies within ``d`` of a cell boundary (half-way between two grid points), or moves the
    largest coordinate across a power of two: the chance of a different key is about
    ``2 * d / step`` per coordinate (never zero: any rounding has boundaries); two results
    that are equal come from inputs less than one step apart, coordinate by coordinate.
    """
    v32 = np.asarray(vertices, dtype=np.float64).astype(np.float32).astype(np.float64)
    if not np.isfinite(v32).all():
        raise InvalidMeshError("vertex coordinates overflow float32")
    scale = float(np.abs(v32).max()) if v32.size else 0.0
    if scale == 0.0:
        return v32 + 0.0
    mantissa, exponent = np.frexp(scale)  # scale = mantissa * 2**exponent, 0.5 <= mantissa < 1
    if mantissa == 0.5:
        exponent -= 1  # scale is a power of two: 2**e == scale
    step = np.ldexp(1.0, int(exponent) - QUANTUM_BITS)
    return np.rint(v32 / step) * step + 0.0  # + 0.0: -0.0 is 0.0


def as_mesh_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a Body, a trimesh.Trimesh or a (vertices, faces) pair."""
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        vertices, faces = mesh.vertices, mesh.faces
    elif isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices, faces = mesh
    else:
        raise TypeError("mesh must be a Body, a trimesh.Trimesh or a (vertices, faces) pair")
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidMeshError(f"vertices must be (n, 3), got {vertices.shape}")
    if faces.size == 0:
        raise InvalidMeshError("mesh has no faces")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidMeshError(f"faces must be (m, 3), got {faces.shape}")
    return vertices, faces.astype(np.int64, copy=False)


def canonical_geometry(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh in a canonical form that does not depend on vertex or face order.

    Coordinates are quantised (:func:`quantise`: float32, then a grid of about 1e-6 of the
    mesh's magnitude), vertices with equal quantised coordinates merged, unused vertices
    dropped, and the rest sorted lexicographically; each triangle is rotated so its
    smallest index comes first (winding kept), triangles that collapsed are dropped, duplicates
    removed, and triangles sorted.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    vertices : (k, 3) float64, C-contiguous
    faces : (l, 3) int64, C-contiguous

    Raises
    ------
    InvalidMeshError
        No faces, indices out of range, non-finite coordinates, or a flat mesh.
    """
    vertices, faces = as_mesh_arrays((vertices, faces))
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMeshError("face indices out of range")
    used = np.unique(faces)
    if not np.isfinite(vertices[used]).all():
        raise InvalidMeshError("mesh has non-finite vertex coordinates")
    unique, inverse = unique_rows(quantise(vertices[used]))
    remap = np.empty(len(vertices), dtype=np.int64)
    remap[used] = inverse
    f = remap[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    if len(f) == 0:
        raise InvalidMeshError("mesh has no faces with three distinct vertices")
    f = canonical_faces(f)
    # Vertices only referenced by dropped triangles go too.
    used = np.unique(f)
    if len(used) != len(unique):
        remap = np.full(len(unique), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        unique, f = unique[used], remap[f]
    if len(unique) < 4 or exact_hull(unique).dimension < 3:
        raise InvalidMeshError(
            "mesh is flat (all vertices lie in one plane): it encloses no volume"
        )
    return np.ascontiguousarray(unique), np.ascontiguousarray(f)


def canonical_faces(faces: np.ndarray) -> np.ndarray:
    """Triangles each rotated to start at its smallest index (winding kept), duplicates
    removed, sorted lexicographically: (l, 3) int64."""
    faces = np.asarray(faces, dtype=np.int64)
    shift = np.argmin(faces, axis=1)
    rows = np.arange(len(faces))[:, None]
    rotated, _ = unique_rows(faces[rows, (shift[:, None] + np.arange(3)) % 3])
    return rotated


def cache_key(
    vertices: np.ndarray, faces: np.ndarray, engine: str, version: str, params: Mapping[str, Any]
) -> str:
    """sha256 hex digest of canonical geometry, engine, engine version and parameters.

    ``vertices`` and ``faces`` must already be canonical (:func:`canonical_geometry`); their
    exact float64 and int64 little-endian bytes are hashed.
    """
    h = hashlib.sha256()
    header = {"format": CACHE_FORMAT, "engine": engine, "version": version, "params": dict(params)}
    h.update(json.dumps(header, sort_keys=True).encode())
    h.update(np.int64(len(vertices)).tobytes())
    h.update(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(faces, dtype="<i8").tobytes())
    return h.hexdigest()


def canonical_part(
    points: np.ndarray, budget: int | None
) -> tuple[np.ndarray, np.ndarray, float, bool] | None:
    """(vertices, faces, volume, reduced) of the hull of ``points``, or None when it is flat.

    The hull is :func:`meshcol.collision.hull.exact_hull` (vertices in lexicographic order);
    past ``budget`` vertices, the enclosing budgeted hull
    (:func:`meshcol.collision.hull.convex_hull`), and ``reduced`` is True. Each triangle starts
    at its smallest index (winding kept) and the triangles are sorted, so equal point sets give
    equal parts.
    """
    points = np.asarray(points, dtype=np.float64)
    if len(points) < 4 or not np.isfinite(points).all():
        return None
    hull = exact_hull(points)
    if hull.dimension < 3:
        return None
    vertices, faces, volume, reduced = hull.vertices, hull.faces.copy(), hull.volume, False
    if budget is not None and len(vertices) > budget:
        budgeted = convex_hull(vertices, max_vertices=budget)
        vertices, faces, volume, reduced = budgeted.vertices, budgeted.faces, budgeted.volume, True
    shift = np.argmin(faces, axis=1)
    faces = faces[np.arange(len(faces))[:, None], (shift[:, None] + np.arange(3)) % 3]
    faces = faces[np.lexsort(faces.T[::-1])]
    return np.ascontiguousarray(vertices), np.ascontiguousarray(faces), float(volume), reduced
