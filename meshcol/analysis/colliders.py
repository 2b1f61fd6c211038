"""From bodies to colliders: the convex parts every analysis queries, built one way.

A body's collider is chosen by its collider kind (:data:`COLLIDER_KINDS`; a manifest body's
own ``shape`` overrides the run's default, and a primitive is always exact):

- ``hull``: the convex hull of its vertices;
- ``decomposed``: its ``UCX_<body>_NN`` parts when the input has them (Unreal's convention),
  else its convex decomposition (from the decompose cache, or computed now and cached);
- ``mesh``: its triangles, for the exact mesh queries. What stands for it in the convex
  queries is chosen by the caller (``mesh_parts``): its hull (check: broad phase and depth
  bound) or every triangle as a 3-vertex polytope (sweep: surface contact).

``check``, ``sweep`` and the exporters all call :func:`build_colliders`, so a body is the same
collider in each of them.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.collision.hull import FLAT_RELATIVE_TOLERANCE
from meshcol.collision.shapes import ConvexSet
from meshcol.types import Body

__all__ = [
    "COLLIDER_KINDS",
    "Colliders",
    "build_colliders",
    "convex_parts",
    "split_ucx",
    "triangle_parts",
]

#: Collider kinds a body can be checked as.
COLLIDER_KINDS = ("hull", "decomposed", "mesh")

_UCX = re.compile(r"^UCX_(?P<body>.+)_(?P<index>\d+)$")


@dataclass(frozen=True, eq=False)
class Colliders:
    """The convex parts of a list of bodies, packed for the native core.

    Attributes
    ----------
    bodies : tuple of Body
        The bodies, in input order, without the ``UCX_`` parts that became colliders.
    kinds : tuple of str
        Per body, what its parts are: ``primitive``, ``hull``, ``ucx``, ``decomposed`` or
        ``mesh``.
    shapes : ConvexSet
        Every part of every body, in each body's local frame; a body's parts are contiguous.
    part_body : (n_parts,) int64
        Body index of each part.
    part_index : (n_parts,) int64
        Index of each part within its body.
    body_part_offsets : (n_bodies + 1,) int64
        Body ``i`` owns parts ``body_part_offsets[i]:body_part_offsets[i + 1]``.
    """

    bodies: tuple[Body, ...]
    kinds: tuple[str, ...]
    shapes: ConvexSet
    part_body: np.ndarray
    part_index: np.ndarray
    body_part_offsets: np.ndarray

    def part_poses(self, end: bool = False) -> np.ndarray:
        """World-from-local pose of every part, (n_parts, 4, 4): its body's start pose, or
        its end pose (the start pose for a body that does not move)."""
        if not self.bodies:
            return np.zeros((0, 4, 4))
        poses = np.stack(
            [
                np.asarray(
                    b.end_pose if end and b.end_pose is not None else b.pose, dtype=np.float64
                )
                for b in self.bodies
            ]
        )
        return np.ascontiguousarray(poses[self.part_body])


def split_ucx(bodies: Sequence[Body]) -> tuple[list[Body], dict[str, list[Body]]]:
    """Separate ``UCX_<body>_NN`` collision parts from the bodies they belong to.

    Returns the other bodies, in order, and for each body name its UCX parts sorted by NN.
    A ``UCX_`` body whose owner is not in the input stays a body of its own.
    """
    names = {b.name for b in bodies}
    ucx: dict[str, list[Body]] = {}
    kept: list[Body] = []
    for body in bodies:
        head, _, last = body.name.rpartition("/")
        match = _UCX.match(last)
        if match:
            target = f"{head}/{match['body']}" if head else match["body"]
            if target in names:
                ucx.setdefault(target, []).append(body)
                continue
        kept.append(body)
    for parts in ucx.values():
        parts.sort(key=lambda b: int(_UCX.match(b.name.rpartition("/")[2])["index"]))  # type: ignore[index]
    return kept, ucx


def _in_owner_frame(owner: Body, parts: list[Body]) -> list[np.ndarray]:
    """UCX part vertices expressed in the owner's local frame."""
    inverse = np.linalg.inv(owner.pose)
    out = []
    for part in parts:
        m = inverse @ part.pose
        out.append(part.vertices @ m[:3, :3].T + m[:3, 3])
    return out


def _geometry_key(vertices: np.ndarray) -> bytes:
    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(vertices, dtype=np.float64).tobytes())
    return h.digest()


def convex_parts(mesh: Any, **options: Any) -> list[np.ndarray]:
    """Vertices of the convex parts of ``mesh`` (its frame), for collision queries.

    Taken from the cache when ``meshcol decompose`` (or an earlier call) stored them for the
    same geometry and options; otherwise decomposed now, without fidelity metrics, and cached.

    Parameters
    ----------
    mesh : Body, trimesh mesh or (vertices, faces)
    **options
        As :func:`meshcol.decomposition.decompose` (``engine``, ``threshold``,
        ``cache_dir``, ...).

    Returns
    -------
    list of (n_i, 3) float64
    """
    from meshcol.decomposition.decompose import cached_decomposition, decompose

    result = cached_decomposition(mesh, **options)
    if result is None:
        result = decompose(mesh, **{**options, "metrics": False})
    return [np.asarray(v, dtype=np.float64) for v, _ in result.parts]


def triangle_parts(body: Body) -> ConvexSet:
    """Every triangle of a body's mesh as a convex part (local frame).

    A triangle with an area is a 3-vertex polytope; one that is collinear or a point by the
    flatness rule (:data:`meshcol.collision.hull.FLAT_RELATIVE_TOLERANCE`, relative to its own
    size) is packed as the segment or point it is, so no triangle is ever dropped.
    """
    tri = np.asarray(body.vertices, dtype=np.float64)[np.asarray(body.faces, dtype=np.int64)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    longest = np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2).max(axis=1) if len(tri) else area2
    with np.errstate(invalid="ignore", divide="ignore"):
        height = np.where(longest > 0, area2 / longest, 0.0)
    keep = np.isfinite(height) & (height > FLAT_RELATIVE_TOLERANCE * longest)
    flat = ConvexSet.from_vertices(list(tri[~keep])) if np.any(~keep) else None
    tri, n, area2 = tri[keep], n[keep], area2[keep]
    t = len(tri)
    unit = n / area2[:, None] if t else np.zeros((0, 3))
    edges = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    edges = edges / np.linalg.norm(edges, axis=2, keepdims=True) if t else np.zeros((0, 3, 3))
    step3 = np.arange(t + 1, dtype=np.int64) * 3
    local = np.array([[1, 2], [0, 2], [0, 1]], dtype=np.int32)
    solid = ConvexSet(
        vertices=tri.reshape(-1, 3),
        offsets=step3,
        kinds=np.zeros(t, np.int8),
        params=np.zeros((t, 4)),
        adjacency_offsets=np.arange(3 * t + 1, dtype=np.int64) * 2,
        adjacency=np.tile(local.reshape(-1), t),
        face_offsets=np.arange(t + 1, dtype=np.int64) * 2,
        face_normals=np.stack([unit, -unit], axis=1).reshape(-1, 3),
        edge_offsets=step3,
        edge_directions=edges.reshape(-1, 3),
    )
    return solid if flat is None else ConvexSet.concatenate(solid, flat)


def _constant(value: Any) -> Callable[[], Any]:
    """A function returning ``value``: packs a unique shape only when it is first seen."""
    return lambda: value


def build_colliders(
    bodies: Sequence[Body],
    kind: str = "hull",
    *,
    mesh_parts: str = "hull",
    decompose_options: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Colliders:
    """The colliders of ``bodies`` (see the module docstring for the kinds).

    Parameters
    ----------
    bodies : sequence of Body
        A scene's bodies, ``UCX_`` parts included (they become their owner's parts).
    kind : {"hull", "decomposed", "mesh"}
        Default collider kind; a body's own ``shape`` overrides it.
    mesh_parts : {"hull", "triangles"}
        What stands for a ``mesh`` body in the convex queries.
    decompose_options : dict, optional
        Options of :func:`convex_parts` for ``decomposed`` bodies.
    progress : callable, optional
        Receives one-line progress messages.

    Returns
    -------
    Colliders

    Notes
    -----
    Identical geometry is packed once and replicated (:meth:`ConvexSet.take`), so a level of
    instanced props costs one hull per unique prop.
    """
    if kind not in COLLIDER_KINDS:
        raise ValueError(f"collider must be one of {', '.join(COLLIDER_KINDS)}, got {kind!r}")
    if mesh_parts not in ("hull", "triangles"):
        raise ValueError(f"mesh_parts must be hull or triangles, got {mesh_parts!r}")
    options = dict(decompose_options or {})
    report = progress or (lambda message: None)
    kept, ucx = split_ucx(bodies)

    # Unique single shapes (packed together in one call) and per-body triangle sets; each
    # body's parts are a block of rows, single shapes first in the pool, triangles after.
    unique: list[Any] = []
    unique_index: dict[Any, int] = {}
    triangle_sets: list[ConvexSet] = []
    blocks: list[tuple[int, list[int]]] = []  # (triangle set index or -1, unique indices)
    kinds: list[str] = []

    def add(key: Any, make: Callable[[], Any]) -> int:
        idx = unique_index.get(key)
        if idx is None:
            idx = len(unique)
            unique.append(make())
            unique_index[key] = idx
        return idx

    for body in kept:
        body_kind = body.collider or kind
        singles: list[int] = []
        triangles = -1
        if body.primitive is not None:
            body_kind = "primitive"
            singles.append(add(("primitive", body.primitive), _constant(body.primitive)))
        elif body_kind == "decomposed" and body.name in ucx:
            body_kind = "ucx"
            for p in _in_owner_frame(body, ucx[body.name]):
                singles.append(add(("part", _geometry_key(p)), _constant(p)))
        elif body_kind == "decomposed":
            report(f"convex parts of {body.name}")
            for p in convex_parts(body, **options):
                singles.append(add(("part", _geometry_key(p)), _constant(p)))
        elif body_kind == "mesh" and mesh_parts == "triangles":
            triangles = len(triangle_sets)
            triangle_sets.append(triangle_parts(body))
        else:
            singles.append(add(("hull", _geometry_key(body.vertices)), _constant(body.vertices)))
        kinds.append(body_kind)
        blocks.append((triangles, singles))

    single = ConvexSet.from_shapes(unique)
    pool = ConvexSet.concatenate(single, *triangle_sets) if triangle_sets else single
    set_start = np.cumsum([len(single)] + [len(s) for s in triangle_sets])
    rows_per_body = [
        np.asarray(singles, dtype=np.int64)
        if tri < 0
        else set_start[tri] + np.arange(len(triangle_sets[tri]), dtype=np.int64)
        for tri, singles in blocks
    ]
    rows = np.concatenate(rows_per_body) if rows_per_body else np.zeros(0, np.int64)
    counts = np.asarray([len(r) for r in rows_per_body], dtype=np.int64)
    offsets = np.zeros(len(kept) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    part_body = np.repeat(np.arange(len(kept), dtype=np.int64), counts)
    part_index = np.arange(len(rows), dtype=np.int64) - offsets[part_body]
    return Colliders(tuple(kept), tuple(kinds), pool.take(rows), part_body, part_index, offsets)
