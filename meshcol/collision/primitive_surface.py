"""Points that cover the surfaces of primitives evenly, from their parameters, for many at once.

Each primitive (the ``kind`` and ``params`` arrays of
:func:`meshcol.collision.primitive_fit.primitive_parameters`, each in its own frame) is cut
into patches, each the image of a rectangle of parameters sampled on a regular grid: a box's
6 faces (flat), a sphere's or an ellipsoid's one patch of longitude and colatitude, a
capsule's side and two half balls, a cylinder's side and two disks (polar). Every patch map
``f(u, v)`` has its partial derivatives bounded, ``|df/du| <= L_u`` and ``|df/dv| <= L_v``
(flat: the edges; round: the largest semi-axis or radius), and its grid steps are chosen so
that ``L_u du <= h`` and ``L_v dv <= h``. A point of the surface is at most half a step
from a grid node along each parameter, so within ``h / 2 + h / 2 = h`` of a sample:

    every point of the surface is within ``spacing = sqrt(area / count)`` of a sample

(``area`` the primitive's surface area, Thomsen's approximation for an ellipsoid, which
only sets the density: the bound holds whatever ``h`` is; ``h`` is the primitive's diameter
over ``count`` when that is larger, for a needle or a primitive of no area, a segment). A
1-Lipschitz function of the point (its distance to a mesh) thus has its maximum over the samples within ``spacing`` of
its maximum over the surface, never above it. The number of samples is about ``count`` for a
box, about ``pi / 2`` times it for a sphere (a longitude grid crowds at the poles), at most a
few times it for a flat ellipsoid; never a random draw: the same parameters give the same
points. The patches are made here with numpy over all primitives at once (a few per
primitive); their nodes are made by the core (``patch_point``), which measures a mesh's
largest distance to them without making them all (:meth:`MeshSet.largest_distances_to_patches`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_offsets
from meshcol.collision.primitive_fit import BOX, CAPSULE, CYLINDER, ELLIPSOID, SPHERE

__all__ = ["SurfacePatches", "surface_areas", "surface_patches", "surface_samples"]

_FLAT, _CAP, _SIDE, _DISK = range(4)  # the core's PatchMap: plane, spheroid, side, disk


def surface_areas(kind: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Surface areas (N,) of primitives (``kind`` (N,), ``params`` (N, 3) as
    :func:`~meshcol.collision.primitive_fit.primitive_parameters`); an ellipsoid's by Knud
    Thomsen's formula (within 1.1%). 0 for a kind of -1."""
    kind = np.asarray(kind)
    p = np.asarray(params, dtype=np.float64).reshape(-1, 3)
    r, length = p[:, 0], p[:, 1]
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    e = 1.6075
    thomsen = ((x * y) ** e + (x * z) ** e + (y * z) ** e) / 3.0
    return np.select(
        [kind == SPHERE, kind == BOX, kind == CAPSULE, kind == CYLINDER, kind == ELLIPSOID],
        [
            4 * math.pi * r**2,
            2 * (x * y + y * z + z * x),
            2 * math.pi * r * length + 4 * math.pi * r**2,
            2 * math.pi * r * length + 2 * math.pi * r**2,
            4 * math.pi * thomsen ** (1 / e),
        ],
        0.0,
    )


@dataclass(frozen=True, eq=False)
class SurfacePatches:
    """The patches of N primitives' surfaces, in the arrays the core takes (``SurfacePatch``
    of ``cpp/include/meshcol/mesh_query.hpp``), each primitive's patches together.

    Attributes
    ----------
    map : (Q,) int8
        How each patch maps (u, v): 0 flat, 1 spheroid, 2 side, 3 disk.
    nodes : (Q, 2) int64
        Grid nodes along u and along v, >= 1.
    numbers : (Q, 13) float64
        The map's numbers (9), v0, v1 and the derivative bounds lu, lv.
    offsets : (N + 1,) int64
        Primitive ``i``'s patches are rows ``offsets[i]:offsets[i + 1]``.
    spacing : (N,) float64
        Every point of primitive ``i``'s surface is within this of a node of its grid.
    """

    map: np.ndarray
    nodes: np.ndarray
    numbers: np.ndarray
    offsets: np.ndarray
    spacing: np.ndarray

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """Every node: ``(points (P, 3), offsets (N + 1,))``, primitive ``i``'s nodes
        ``points[offsets[i]:offsets[i + 1]]``, patch after patch, row by row."""
        sizes = self.nodes[:, 0] * self.nodes[:, 1]
        per_patch = as_offsets(sizes)
        return core.patch_points(self.map, self.nodes, self.numbers), per_patch[self.offsets]


def surface_patches(kind: np.ndarray, params: np.ndarray, count: int) -> SurfacePatches:
    """The grid patches of each primitive's surface, about ``count`` nodes each.

    Parameters
    ----------
    kind : (N,) int
        :data:`meshcol.collision.fit.FIT_SHAPES` index of each primitive (none: -1, no patch).
    params : (N, 3) float
        Sphere radius; box sides; capsule and cylinder radius, length (along local z);
        ellipsoid semi-axes.
    count : int
        Nodes per primitive the spacing is set for, >= 1.
    """
    kind = np.asarray(kind, dtype=np.int64).reshape(-1)
    p = np.asarray(params, dtype=np.float64).reshape(-1, 3)
    # the diameter's share too: a primitive of no area (a segment) still gets nodes along it
    spacing = np.maximum(np.sqrt(surface_areas(kind, p) / count), _diameters(kind, p) / count)
    patches = _patches(kind, p)
    step = spacing[patches["body"]]
    safe = np.where(step > 0, step, np.inf)  # a point primitive: one node a patch
    n_u = np.where(
        patches["map"] == _FLAT,
        np.ceil(patches["lu"] / safe) + 1,
        np.maximum(np.ceil(2 * math.pi * patches["lu"] / safe), 1),
    )
    n_v = np.ceil(patches["lv"] * (patches["v1"] - patches["v0"]) / safe) + 1
    offsets = as_offsets(np.bincount(patches["body"], minlength=len(kind)))
    numbers = np.column_stack(
        [patches["g"], patches["v0"], patches["v1"], patches["lu"], patches["lv"]]
    )
    return SurfacePatches(
        patches["map"].astype(np.int8),
        np.ascontiguousarray(np.column_stack([n_u, n_v]), dtype=np.int64),
        np.ascontiguousarray(numbers),
        offsets,
        spacing,
    )


def surface_samples(
    kind: np.ndarray, params: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nodes of :func:`surface_patches`: ``(points (P, 3), offsets (N + 1,), spacing
    (N,))``, primitive ``i``'s ``points[offsets[i]:offsets[i + 1]]``, its frame."""
    patches = surface_patches(kind, params, count)
    points, offsets = patches.points()
    return points, offsets, patches.spacing


def _diameters(kind: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The largest distance between two points of each primitive (0 for a kind of -1)."""
    r, length = p[:, 0], p[:, 1]
    return np.select(
        [kind == SPHERE, kind == BOX, kind == CAPSULE, kind == CYLINDER, kind == ELLIPSOID],
        [
            2 * r,
            np.linalg.norm(p, axis=1),
            length + 2 * r,
            np.hypot(length, 2 * r),
            2 * p.max(axis=1),
        ],
        0.0,
    )


def _patches(kind: np.ndarray, p: np.ndarray) -> dict[str, np.ndarray]:
    """Every primitive's patches, ordered by primitive: ``body``, ``map``, the bounds ``lu``,
    ``lv`` (flat: the edges' lengths and v in [0, 1]), ``v0``, ``v1``, and the map's
    numbers ``g`` (flat: origin, edge u, edge v; round: a, b, c, z0, and for a ball the local
    axis its map's z is, 2 unless a turned ellipsoid's)."""
    rows: list[tuple[np.ndarray, int, np.ndarray, np.ndarray, float, float, np.ndarray]] = []

    def add(
        body: np.ndarray,
        map_: int,
        lu: np.ndarray,
        lv: np.ndarray,
        v0: float,
        v1: float,
        g: np.ndarray,
    ) -> None:
        g9 = np.zeros((len(body), 9))
        g9[:, : g.shape[1]] = g
        rows.append((body, map_, lu, lv, v0, v1, g9))

    for is_ball in (SPHERE, ELLIPSOID):
        b = np.flatnonzero(kind == is_ball)
        # the largest semi-axis as the polar one (the grid's longitude steps then follow the
        # two others): local axis `polar` is the map's z, polar + 1 its x, polar + 2 its y
        polar = np.argmax(p[b], axis=1) if is_ball == ELLIPSOID else np.full(len(b), 2)
        axes = p[b[:, None], (polar[:, None] + [1, 2, 0]) % 3]
        if is_ball == SPHERE:
            axes = np.repeat(p[b, :1], 3, axis=1)
        round_ = np.column_stack([axes, np.zeros(len(b)), np.zeros(len(b)), polar])
        add(b, _CAP, axes[:, :2].max(axis=1), axes.max(axis=1), 0.0, math.pi, round_)
    for is_tube in (CAPSULE, CYLINDER):
        b = np.flatnonzero(kind == is_tube)
        r, half = p[b, 0], p[b, 1] / 2
        zero = np.zeros(len(b))
        add(b, _SIDE, r, half, -1.0, 1.0, np.column_stack([r, r, half, zero]))
        for sign, (v0, v1) in ((1.0, (0.0, math.pi / 2)), (-1.0, (math.pi / 2, math.pi))):
            if is_tube == CAPSULE:  # a half ball at each end
                g = np.column_stack([r, r, r, sign * half, zero, np.full(len(b), 2.0)])
                add(b, _CAP, r, r, v0, v1, g)
            else:  # a disk at each end, polar: radius v r
                add(b, _DISK, r, r, 0.0, 1.0, np.column_stack([r, r, zero, sign * half]))
    b = np.flatnonzero(kind == BOX)
    half = p[b] / 2
    for axis in range(3):
        u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
        for sign in (1.0, -1.0):
            origin = np.zeros((len(b), 3))
            origin[:, axis] = sign * half[:, axis]
            origin[:, u_axis] = -half[:, u_axis]
            origin[:, v_axis] = -half[:, v_axis]
            edge_u = np.zeros((len(b), 3))
            edge_u[:, u_axis] = p[b, u_axis]
            edge_v = np.zeros((len(b), 3))
            edge_v[:, v_axis] = p[b, v_axis]
            g = np.column_stack([origin, edge_u, edge_v])
            add(b, _FLAT, p[b, u_axis], p[b, v_axis], 0.0, 1.0, g)
    body = np.concatenate([r[0] for r in rows])
    order = np.argsort(body, kind="stable")
    out = {
        "body": body,
        "map": np.concatenate([np.full(len(r[0]), r[1]) for r in rows]),
        "lu": np.concatenate([r[2] for r in rows]),
        "lv": np.concatenate([r[3] for r in rows]),
        "v0": np.concatenate([np.full(len(r[0]), r[4]) for r in rows]),
        "v1": np.concatenate([np.full(len(r[0]), r[5]) for r in rows]),
        "g": np.concatenate([r[6] for r in rows]),
    }
    return {name: value[order] for name, value in out.items()}
