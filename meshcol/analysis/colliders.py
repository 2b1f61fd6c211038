"""From bodies to colliders: the convex parts every analysis queries, built one way.

A body's collider is chosen by its collider kind (:data:`COLLIDER_KINDS`; a manifest body's
own ``shape`` overrides the run's default, and a primitive, a body or a part of one, is always
exact), part by part for a body of several parts (``Body.parts``):

- ``hull``: the convex hull of each of its parts;
- ``decomposed``: each part's ``UCX_<part>_NN`` collision parts when the input has them
  (Unreal's convention), else the part's convex decomposition (from the decompose cache, or
  computed now and cached);
- ``fit``: each part's enclosing primitive (:mod:`meshcol.analysis.fit`, ``auto``: the
  simplest primitive within the volume tolerance of its hull, else the hull), queried exactly
  as a primitive, placed in the body by its own pose (``Colliders.part_offsets``);
- ``box``, ``sphere``: each part's enclosing oriented box or minimum sphere, always that
  primitive (an engine's simple colliders; USD's ``boundingCube``, ``boundingSphere``);
- ``mesh``: its triangles, for the exact mesh queries. What stands for it in the convex
  queries is chosen by the caller (``mesh_parts``): its parts' hulls (check: broad phase and
  depth bound) or every triangle as a 3-vertex polytope (sweep: surface contact).

``UCX_<name>_NN`` parts (see :func:`split_ucx` for the matching) are collision geometry, not
render geometry: matched to their owner they leave the body's mesh. A ``UCX_`` part that names
nothing in the input is kept as geometry and a warning names it; loose ones from one file that
name the same owner become one body of parts (``<file>/<owner>``), so the convex parts of one
decomposition are never checked against each other. Under ``decomposed``, every ``UCX_`` part
is used as given. ``UBX_``, ``USP_`` and ``UCP_`` parts (a box, a sphere, a capsule:
:mod:`meshcol.io.collision_names`, the conventions shared by every format) are matched the
same way and, under ``decomposed``, become the enclosing primitive of their vertices, exact.

Degenerate geometry follows one rule everywhere: a body or part whose points are flat,
collinear or a single point (:attr:`meshcol.collision.hull.ExactHull.dimension`) is its hull,
the polygon, segment or point it is, never dropped; under ``decomposed`` (which needs a volume)
that is said in a warning.

``check``, ``sweep`` and the exporters all call :func:`build_colliders`, so a body is the same
collider in each of them.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from itertools import chain
from typing import Any

import numpy as np

from meshcol.analysis.bulk_colliders import bulk_colliders
from meshcol.analysis.geometry_cache import geometry_key
from meshcol.analysis.triangle_parts import _triangle_parts, triangle_parts
from meshcol.collision.hull import exact_hull
from meshcol.collision.shapes import ConvexSet
from meshcol.errors import InvalidMeshError
from meshcol.io.collision_names import UNREAL_PREFIXES, collision_part
from meshcol.io.column_bodies import ColumnBodies, MeshBodies, body_names
from meshcol.types import Body, HalfSpace, unique_name
from meshcol.vocabulary import COLLIDER_KINDS, HALF_SPACE_COLLIDER

__all__ = [
    "COLLIDER_KINDS",
    "Colliders",
    "build_colliders",
    "convex_parts",
    "split_ucx",
    "triangle_parts",
]


_UCX = re.compile(r"^UCX_(?P<body>.+)_(?P<index>\d+)$")  # convex parts only (MC303)


@dataclass(frozen=True, eq=False)
class Colliders:
    """The convex parts of a list of bodies, packed for the native core.

    Attributes
    ----------
    bodies : sequence of Body
        The bodies, in input order, without the ``UCX_`` parts that became colliders (a body
        of several parts loses its matched ``UCX_`` parts; ``UCX_`` parts naming no body
        become bodies of their own, after the others).
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
    part_label : (n_parts,) int64
        Which of its body's named parts (``Body.parts``) each convex part stands for; -1 for
        a body of one part.
    warnings : tuple of str
        One line per ``UCX_`` part naming nothing, and per flat body that could not be
        decomposed.
    part_offsets : (n_parts, 4, 4) float64 or None
        Pose of each part in its body's frame, when some part is not at the body's origin
        (a ``fit`` primitive, a part that is a primitive); None when every part is.
    """

    bodies: Sequence[Body]
    kinds: tuple[str, ...]
    shapes: ConvexSet
    part_body: np.ndarray
    part_index: np.ndarray
    body_part_offsets: np.ndarray
    part_label: np.ndarray
    warnings: tuple[str, ...] = ()
    part_offsets: np.ndarray | None = None

    def part_poses(self, end: bool = False) -> np.ndarray:
        """World-from-local pose of every part, (n_parts, 4, 4): its body's start pose, or
        its end pose (the start pose for a body that does not move)."""
        if not self.bodies:
            return np.zeros((0, 4, 4))
        if isinstance(self.bodies, ColumnBodies):  # no body moves: the poses column
            if self.part_offsets is None and np.array_equal(
                self.part_body, np.arange(len(self.bodies))
            ):  # a part per body: a read-only view (128 MB at 1,000,000 bodies, not copied)
                view = self.bodies.poses.view()
                view.flags.writeable = False
                return view
            poses = self.bodies.poses[self.part_body]
            return poses @ self.part_offsets if self.part_offsets is not None else poses
        poses = np.stack(
            [
                np.asarray(
                    b.end_pose if end and b.end_pose is not None else b.pose, dtype=np.float64
                )
                for b in self.bodies
            ]
        )
        poses = poses[self.part_body]
        if self.part_offsets is not None:
            poses = poses @ self.part_offsets
        return np.ascontiguousarray(poses)

    def part_names(self, bodies: Any, labels: Any) -> list[str | None]:
        """Names of the parts ``labels`` of ``bodies`` (None for -1: a body of one part)."""
        return [
            self.bodies[b].parts[label] if label >= 0 else None
            for b, label in zip(np.asarray(bodies).tolist(), np.asarray(labels).tolist())
        ]

    def face_labels(self, bodies: Any, faces: Any) -> np.ndarray:
        """The part label of triangle ``faces[k]`` of body ``bodies[k]`` (-1 for a body of
        one part or a face index < 0)."""
        bodies = np.asarray(bodies, dtype=np.int64)
        faces = np.asarray(faces, dtype=np.int64)
        labels = np.full(len(bodies), -1, dtype=np.int64)
        for b in np.unique(bodies).tolist():
            body = self.bodies[b]
            if not body.parts:
                continue
            assert body.part_faces is not None
            mine = (bodies == b) & (faces >= 0)
            labels[mine] = np.searchsorted(body.part_faces, faces[mine], side="right") - 1
        return labels


@dataclass(frozen=True)
class _Ucx:
    """Unreal collision parts of one body (``UCX_``, ``UBX_``, ``USP_``, ``UCP_``):
    ``(label, vertices in the owner's frame)`` each, and each one's kind
    (:data:`meshcol.io.collision_names.UNREAL_PREFIXES`), in the same order."""

    parts: list[tuple[int, np.ndarray]]
    whole: bool  # they stand for the whole body (its own name, or a loose owner)
    kinds: list[str] = dataclasses.field(default_factory=list)

    def add(self, label: int, vertices: np.ndarray, kind: str) -> None:
        self.parts.append((label, vertices))
        self.kinds.append(kind)

    def sort(self) -> None:
        """In ``NN`` order (the labels hold it until then)."""
        order = sorted(range(len(self.parts)), key=lambda k: self.parts[k][0])
        self.parts[:] = [self.parts[k] for k in order]
        self.kinds[:] = [self.kinds[k] for k in order]


def _ucx_index(name: str) -> int:
    part = collision_part(name)
    return part.index if part is not None else -1


def _restrict(body: Body, keep: list[int]) -> Body:
    """The body with only the parts ``keep`` (in order); one part left keeps its name."""
    assert body.part_faces is not None
    meshes = body.part_meshes()
    vertices, faces, counts, base = [], [], [], 0
    for k in keep:
        _, v, f = meshes[k]
        vertices.append(v)
        faces.append(f + base)
        counts.append(len(f))
        base += len(v)
    return dataclasses.replace(
        body,
        vertices=np.ascontiguousarray(np.concatenate(vertices)),
        faces=np.ascontiguousarray(np.concatenate(faces)),
        parts=tuple(body.parts[k] for k in keep),
        part_faces=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        part_primitives=tuple(body.part_primitives[k] for k in keep)
        if body.part_primitives
        else (),
    )


def split_ucx(bodies: Sequence[Body]) -> tuple[Sequence[Body], dict[str, _Ucx], list[str]]:
    """Separate ``UCX_<owner>_NN`` collision parts from the bodies they belong to.

    Matching, for a part of a body of several parts (a manifest body): the part named
    ``<owner>`` of the same body, or the body itself when ``<owner>`` is its name. For a loose
    body ``<file>/UCX_<owner>_NN`` or ``UCX_<owner>_NN``: the body ``<file>/<owner>`` (the
    same file, Unreal's convention), else a body named ``<owner>`` (``meshcol decompose
    --layout ucx`` output given beside its source).

    Returns
    -------
    bodies : sequence of Body
        The bodies without their matched ``UCX_`` parts, in order (column bodies as they
        are when no name is a ``UCX_`` part's: they have no parts); loose ``UCX_`` bodies that
        match nothing become one body of parts per owner name they give (``<file>/<owner>``),
        after the others; a ``UCX_`` part of a body that matches nothing stays a part of it.
    ucx : dict
        Per body name, its ``UCX_`` parts sorted by ``NN``.
    warnings : list of str
        One line per owner name that matched nothing.
    """
    joined = "\n".join(body_names(bodies))  # one search, not a match per body
    if not any(f"{p}_" in joined for p in UNREAL_PREFIXES):
        if isinstance(bodies, ColumnBodies):
            return bodies, {}, []
        if not any(b.parts for b in bodies):
            return list(bodies), {}, []
    names = dict.fromkeys((b.name for b in bodies), 2)
    by_name = {b.name: b for b in bodies}
    ucx: dict[str, _Ucx] = {}
    orphans: dict[str, list[Body]] = {}
    warnings: list[str] = []
    kept: list[Body] = []
    for body in bodies:
        if body.parts:
            kept.append(_split_body_ucx(body, ucx, warnings))
            continue
        head, _, last = body.name.rpartition("/")
        match = collision_part(last)
        if match is None:
            kept.append(body)
            continue
        same_file = f"{head}/{match.owner}" if head else match.owner
        target = same_file if same_file in names else match.owner
        if target in names and collision_part(target.rpartition("/")[2]) is None:
            entry = ucx.setdefault(target, _Ucx([], True))
            (local,) = _in_owner_frame(by_name[target], [body])
            entry.add(match.index, local, match.kind)
            continue
        orphans.setdefault(same_file, []).append(body)
    for entry in ucx.values():
        entry.sort()
        if entry.whole:
            entry.parts[:] = [(-1, v) for _, v in entry.parts]
    for owner_name, parts in orphans.items():
        parts.sort(key=lambda b: _ucx_index(b.name.rpartition("/")[2]))
        name = unique_name(owner_name, names)
        listed = _listing([b.name for b in parts])
        warnings.append(
            f"{listed} name no body {owner_name.rpartition('/')[2]!r} in the inputs: checked as "
            f"one body {name!r} of {len(parts)} part(s)"
        )
        kept.append(_group(name, parts))
    return kept, ucx, warnings


def _split_body_ucx(body: Body, ucx: dict[str, _Ucx], warnings: list[str]) -> Body:
    """Strip the matched ``UCX_`` parts of a body of several parts (see :func:`split_ucx`)."""
    render = [k for k, name in enumerate(body.parts) if collision_part(name) is None]
    index = {body.parts[k]: k for k in render}
    matched: list[tuple[int, int, int]] = []  # (part, owner part or -1 for the body, NN)
    unmatched: list[int] = []
    for k, name in enumerate(body.parts):
        match = collision_part(name)
        if match is None:
            continue
        if match.owner in index:
            matched.append((k, index[match.owner], match.index))
        elif match.owner == body.name:
            matched.append((k, -1, match.index))
        else:
            unmatched.append(k)
    if unmatched and render:
        warnings.append(
            f"body {body.name!r}: {_listing([body.parts[k] for k in unmatched])} name no part "
            f"of it (its parts: {_listing([body.parts[k] for k in render])}): kept as parts of "
            "their own"
        )
    if not matched:
        return body
    keep = sorted(render + unmatched)
    if not keep:
        # only collision parts: they are the body's geometry too
        keep = sorted(k for k, _, _ in matched)
    kept = _restrict(body, keep) if keep != list(range(len(body.parts))) else body
    meshes = body.part_meshes()
    new_index = {k: i for i, k in enumerate(keep)}
    whole = any(owner < 0 for _, owner, _ in matched)
    parts = sorted(
        ((-1 if whole else new_index[owner], nn, k) for k, owner, nn in matched),
        key=lambda item: (item[0], item[1]),
    )
    entry = ucx[body.name] = _Ucx([], whole)
    for label, _, k in parts:
        kind = collision_part(body.parts[k])
        entry.add(label, meshes[k][1], kind.kind if kind is not None else "convex")
    return kept


def _group(name: str, parts: list[Body]) -> Body:
    """One body of the given loose bodies as its parts (the first one's frame and pose)."""
    first = parts[0]
    local = _in_owner_frame(first, parts)
    vertices, faces, counts, base = [], [], [], 0
    for body, v in zip(parts, local):
        vertices.append(v)
        faces.append(np.asarray(body.faces, dtype=np.int64) + base)
        counts.append(len(body.faces))
        base += len(v)
    return Body(
        name=name,
        source=first.source,
        vertices=np.ascontiguousarray(np.concatenate(vertices)),
        faces=np.ascontiguousarray(np.concatenate(faces)),
        pose=first.pose,
        end_pose=first.end_pose,
        collider=first.collider,
        parts=tuple(b.name.rpartition("/")[2] for b in parts),
        part_faces=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
    )


def _listing(names: list[str]) -> str:
    """``'A', 'B' and 'C'`` or ``'A' ... 'Z' (50 parts)``, for warnings."""
    if len(names) > 3:
        return f"{names[0]!r} ... {names[-1]!r} ({len(names)} parts)"
    quoted = [repr(n) for n in names]
    return quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " and " + quoted[-1]


def _flat(vertices: np.ndarray) -> bool:
    """Whether points are flat, collinear or one point (the flatness rule); points without a
    hull (none, NaN) count as flat: their shape is packed as given."""
    try:
        return exact_hull(vertices).dimension < 3
    except InvalidMeshError:
        return True


def _in_owner_frame(owner: Body, parts: list[Body]) -> list[np.ndarray]:
    """UCX part vertices expressed in the owner's local frame."""
    inverse = np.linalg.inv(owner.pose)
    out = []
    for part in parts:
        m = inverse @ part.pose
        out.append(part.vertices @ m[:3, :3].T + m[:3, 3])
    return out


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


#: Collider kinds whose parts are enclosing primitives, and the fit each asks for
#: (:func:`meshcol.analysis.fit.fit_point_sets`): ``fit`` the simplest within the volume
#: tolerance (else the hull), ``box`` and ``sphere`` always that primitive.
FIT_KIND_SHAPES = {"fit": "auto", "box": "box", "sphere": "sphere"}


def _fits_of(
    bodies: Sequence[Body], kind: str, report: Callable[[str], None]
) -> dict[tuple[str, bytes], Any]:
    """The fit of every unique, non-flat part of the bodies whose kind is one of
    :data:`FIT_KIND_SHAPES`, one native call per fit shape: (shape, geometry key) -> the chosen
    PrimitiveFit, or None when the hull was kept."""
    wanted: dict[str, dict[bytes, tuple[np.ndarray, str]]] = {}
    for body in bodies:
        shape = FIT_KIND_SHAPES.get(body.collider or kind)
        if body.primitive is not None or shape is None:
            continue
        sets = wanted.setdefault(shape, {})
        for _, name, v, _ in _part_meshes(body):
            key = geometry_key(v)
            if key not in sets and not _flat(v):
                sets[key] = (v, f"body {body.name!r}" + ("" if name is None else f" part {name!r}"))
    if not wanted:
        return {}
    from meshcol.analysis.fit import fit_point_sets  # only when a body is fitted

    out: dict[tuple[str, bytes], Any] = {}
    for shape, sets in wanted.items():
        report(f"enclosing primitives of {len(sets)} unique parts")
        results = fit_point_sets([v for v, _ in sets.values()], shape)
        for (key, (_, what)), result in zip(sets.items(), results):
            if isinstance(result, InvalidMeshError):
                raise InvalidMeshError(f"{what}: {result.message}")
            out[(shape, key)] = result.primitive_fit
    return out


def build_colliders(
    bodies: Sequence[Body],
    kind: str = "hull",
    *,
    mesh_parts: str = "hull",
    decompose_options: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    decompose: Callable[..., list[np.ndarray]] | None = None,
) -> Colliders:
    """The colliders of ``bodies`` (see the module docstring for the kinds).

    Parameters
    ----------
    bodies : sequence of Body
        A scene's bodies, ``UCX_`` parts included (they become their owner's parts).
    kind : str
        Default collider kind (:data:`meshcol.vocabulary.COLLIDER_KINDS`); a body's own
        ``shape`` overrides it.
    mesh_parts : {"hull", "triangles"}
        What stands for a ``mesh`` body in the convex queries.
    decompose_options : dict, optional
        Options of :func:`convex_parts` for ``decomposed`` bodies.
    progress : callable, optional
        Receives one-line progress messages.
    decompose : callable, optional
        Stands for :func:`convex_parts` (same arguments and result): parts computed
        elsewhere (``check``'s per-file tasks), looked up first.

    Returns
    -------
    Colliders

    Notes
    -----
    Identical geometry is packed once and replicated (:meth:`ConvexSet.take`), so a level of
    instanced props costs one hull per unique prop. Each kind's parts come from its builder in
    :data:`_BUILDERS` (one entry per collider kind).
    """
    if kind not in COLLIDER_KINDS:
        raise ValueError(f"collider must be one of {', '.join(COLLIDER_KINDS)}, got {kind!r}")
    if mesh_parts not in ("hull", "triangles"):
        raise ValueError(f"mesh_parts must be hull or triangles, got {mesh_parts!r}")
    kept, ucx, warnings = split_ucx(bodies)
    meshes = isinstance(kept, MeshBodies) or any(body.primitive is None for body in kept)
    bulk = bulk_colliders(kept, kind, mesh_parts) if meshes and not ucx else None
    if bulk is not None:  # plain bodies: built as arrays (meshcol.analysis.bulk_colliders)
        return _Pool().of_bulk(kept, warnings, *bulk)
    report = progress or (lambda message: None)
    build = _Build(
        kind=kind,
        mesh_parts=mesh_parts,
        ucx=ucx,
        warnings=warnings,
        report=report,
        parts_of=convex_parts if decompose is None else decompose,
        decompose_options=dict(decompose_options or {}),
        fits=_fits_of(kept, kind, report),
    )
    if not ucx and not meshes:
        return build.pool.of_primitives(kept, warnings)
    for body_number, body in enumerate(kept):
        block = _Block(body_number)
        if body.primitive is not None:
            block.put(build.pool.add(("primitive", body.primitive), body.primitive), -1)
            body_kind = "primitive"
            if isinstance(body.primitive, HalfSpace):
                body_kind = HALF_SPACE_COLLIDER
        else:
            body_kind = _BUILDERS[body.collider or kind](build, body, block)
            if body.part_primitives and all(body.part_primitives) and block.triangles < 0:
                body_kind = "primitive"  # every part an exact primitive (_part_meshes)
        build.pool.close(block, body_kind)
    return build.pool.colliders(kept, warnings)


@dataclass
class _Block:
    """The parts of one body being built: rows of single shapes in the pool and their part
    labels, or a triangle set (``triangles`` >= 0, its index)."""

    body_number: int
    singles: list[int] = dataclasses.field(default_factory=list)
    labels: list[int] = dataclasses.field(default_factory=list)
    triangles: int = -1

    def put(self, row: int, label: int) -> None:
        self.singles.append(row)
        self.labels.append(label)


class _Pool:
    """Unique single shapes (packed together in one call) and per-body triangle sets; each
    body's parts are a block of rows, single shapes first in the pool, triangles after."""

    def __init__(self) -> None:
        self.unique: list[Any] = []
        self.unique_index: dict[Any, int] = {}
        self.triangle_sets: list[ConvexSet] = []
        self.triangle_labels: list[np.ndarray] = []
        self.blocks: list[_Block] = []
        self.kinds: list[str] = []
        # the pose in its body of each single part that is not at the body's origin: (body, k)
        self.part_poses: dict[tuple[int, int], np.ndarray] = {}

    def add(self, key: Any, shape: Any) -> int:
        """The row of the unique shape ``key``, packed the first time it is seen."""
        row = self.unique_index.get(key)
        if row is None:
            row = len(self.unique)
            self.unique.append(shape)
            self.unique_index[key] = row
        return row

    def hull(self, vertices: np.ndarray) -> int:
        return self.add(("hull", geometry_key(vertices)), vertices)

    def part(self, vertices: np.ndarray) -> int:
        return self.add(("part", geometry_key(vertices)), vertices)

    def add_triangles(self, body: Body, block: _Block) -> None:
        """Every triangle of ``body`` as a part (one triangle set)."""
        block.triangles = len(self.triangle_sets)
        triangles, order = _triangle_parts(body)
        self.triangle_sets.append(triangles)
        if body.parts:
            assert body.part_faces is not None
            face_label = np.repeat(
                np.arange(len(body.parts), dtype=np.int64), np.diff(body.part_faces)
            )
            self.triangle_labels.append(face_label[order])
        else:
            self.triangle_labels.append(np.full(len(order), -1, dtype=np.int64))

    def close(self, block: _Block, kind: str) -> None:
        self.kinds.append(kind)
        self.blocks.append(block)

    def _rows(self, single: ConvexSet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pool row and part label of every part, and the part count of every body."""
        blocks = self.blocks
        if not self.triangle_sets:  # single shapes only: three flat passes
            rows = np.fromiter(chain.from_iterable(b.singles for b in blocks), dtype=np.int64)
            labels = np.fromiter(chain.from_iterable(b.labels for b in blocks), dtype=np.int64)
            counts = np.fromiter((len(b.singles) for b in blocks), np.int64, count=len(blocks))
            return rows, labels, counts
        set_start = np.cumsum([len(single)] + [len(s) for s in self.triangle_sets])
        rows_per_body = [
            np.asarray(b.singles, dtype=np.int64)
            if b.triangles < 0
            else set_start[b.triangles]
            + np.arange(len(self.triangle_sets[b.triangles]), dtype=np.int64)
            for b in blocks
        ]
        labels_per_body = [
            np.asarray(b.labels, dtype=np.int64)
            if b.triangles < 0
            else self.triangle_labels[b.triangles]
            for b in blocks
        ]
        counts = np.asarray([len(r) for r in rows_per_body], dtype=np.int64)
        return np.concatenate(rows_per_body), np.concatenate(labels_per_body), counts

    def of_primitives(self, bodies: Sequence[Body], warnings: list[str]) -> Colliders:
        """The packed :class:`Colliders` of bodies that are all primitives (each one part, its
        exact primitive): what a block per body gives, in one pass over them."""
        index = self.unique_index
        keys = (index.setdefault(("primitive", b.primitive), len(index)) for b in bodies)
        rows = np.fromiter(keys, dtype=np.int64, count=len(bodies))
        self.unique = [key[1] for key in index]
        self.kinds = ["primitive"] * len(bodies)
        if any(isinstance(shape, HalfSpace) for shape in self.unique):  # a plane's body
            self.kinds = [
                HALF_SPACE_COLLIDER if isinstance(b.primitive, HalfSpace) else "primitive"
                for b in bodies
            ]
        ones = np.ones(len(bodies), dtype=np.int64)
        return self.colliders(bodies, warnings, (rows, -ones, ones))

    def of_bulk(
        self,
        bodies: Sequence[Body],
        warnings: list[str],
        kinds: list[str],
        shapes: ConvexSet,
        rows: Any,
    ) -> Colliders:
        """The packed :class:`Colliders` of one-part bodies whose unique shapes are packed
        already (:func:`meshcol.analysis.bulk_colliders.bulk_colliders`): ``rows`` their row
        of each body, ``kinds`` the kind of each."""
        self.kinds = kinds
        ones = np.ones(len(bodies), dtype=np.int64)
        return self.colliders(bodies, warnings, (rows, -ones, ones), shapes)

    def colliders(
        self, bodies: Sequence[Body], warnings: list[str], parts: Any = None, single: Any = None
    ) -> Colliders:
        """The packed :class:`Colliders` of every closed block (or of ``parts``: the pool
        row and label of every part and each body's part count, given; and of ``single``,
        the unique shapes packed already)."""
        single = ConvexSet.from_shapes(self.unique) if single is None else single
        pool = ConvexSet.concatenate(single, *self.triangle_sets) if self.triangle_sets else single
        rows, part_label, counts = self._rows(single) if parts is None else parts
        offsets = np.zeros(len(bodies) + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        part_body = np.repeat(np.arange(len(bodies), dtype=np.int64), counts)
        part_offsets = None
        if self.part_poses:
            part_offsets = np.tile(np.eye(4), (len(rows), 1, 1))
            for (body_number, k), pose in self.part_poses.items():
                part_offsets[offsets[body_number] + k] = pose
        return Colliders(
            bodies if isinstance(bodies, ColumnBodies) else tuple(bodies),
            tuple(self.kinds),
            # every part its own unique shape, in pool order (a scene of unique assets): as is
            pool if np.array_equal(rows, np.arange(len(pool.kinds))) else pool.take(rows),
            part_body,
            np.arange(len(rows), dtype=np.int64) - offsets[part_body],
            offsets,
            part_label,
            tuple(warnings),
            part_offsets,
        )


@dataclass
class _Build:
    """What every collider builder shares during one :func:`build_colliders` call."""

    kind: str
    mesh_parts: str
    ucx: dict[str, _Ucx]
    warnings: list[str]
    report: Callable[[str], None]
    parts_of: Callable[..., list[np.ndarray]]
    decompose_options: dict[str, Any]
    fits: dict[tuple[str, bytes], Any]  # (shape, geometry key) -> its fit: fitted once
    pool: _Pool = dataclasses.field(default_factory=_Pool)


def _part_meshes(
    body: Body, build: _Build | None = None, block: _Block | None = None
) -> Iterator[tuple[int, str | None, np.ndarray, np.ndarray]]:
    """(label, name for messages, vertices, faces) of each part, one unlabelled part (-1) for
    a body of one part. A part that is a primitive (``Body.part_primitives``) is exact
    whatever the kind, as a primitive body is: it goes into ``block`` as that primitive,
    placed by its pose, in its turn (none without a block), instead of being yielded."""
    exact = body.part_primitives or (None,) * len(body.parts or (0,))
    for k, ((name, v, f), part) in enumerate(zip(body.part_meshes(), exact)):
        if part is None:
            yield k if body.parts else -1, name, v, f
        elif build is not None and block is not None:
            build.pool.part_poses[(block.body_number, len(block.singles))] = part.pose
            block.put(build.pool.add(("primitive", part.primitive), part.primitive), k)


def _hull_parts(build: _Build, body: Body, block: _Block) -> str:
    """``hull``: the convex hull of each part."""
    for label, _, vertices, _ in _part_meshes(body, build, block):
        block.put(build.pool.hull(vertices), label)
    return "hull"


def _mesh_parts(build: _Build, body: Body, block: _Block) -> str:
    """``mesh``: its triangles, or its parts' hulls, as the caller's ``mesh_parts`` says."""
    if build.mesh_parts == "triangles":
        build.pool.add_triangles(body, block)
    else:
        _hull_parts(build, body, block)
    return "mesh"


def _fitted_parts(build: _Build, body: Body, block: _Block, kind: str = "fit") -> str:
    """``fit``, ``box``, ``sphere``: each part's enclosing primitive (the fit of
    :data:`FIT_KIND_SHAPES`), placed by its pose; a flat part, or one whose fit kept the hull,
    is its hull."""
    shape = FIT_KIND_SHAPES[kind]
    for label, _, vertices, _ in _part_meshes(body, build, block):
        chosen = None if _flat(vertices) else build.fits[(shape, geometry_key(vertices))]
        if chosen is None:  # flat: its polygon (a primitive would add a thickness)
            block.put(build.pool.hull(vertices), label)
            continue
        build.pool.part_poses[(block.body_number, len(block.singles))] = chosen.pose
        block.put(build.pool.add(("fit", chosen.primitive), chosen.primitive), label)
    return kind


def _decomposed_parts(build: _Build, body: Body, block: _Block) -> str:
    """``decomposed``: the body's matched ``UCX_`` parts, any part named ``UCX_`` as given,
    a flat part's hull (with a warning), and the convex decomposition of every other part.
    A body whose parts all came from ``UCX_`` geometry is of kind ``ucx``."""
    own = build.ucx.get(body.name)
    covered = set() if own is None else {label for label, _ in own.parts}
    for (label, vertices), kind in zip(own.parts, own.kinds) if own is not None else ():
        _collision_part(build, block, label, vertices, kind)
    decomposed, names = False, []
    for label, name, vertices, faces in _part_meshes(body, build, block):
        names.append(name)
        if own is not None and (own.whole or label in covered):
            continue  # its UCX parts stand for it
        named = collision_part(name) if name is not None else None
        if named is not None:  # convex (or a primitive) by convention: as given
            _collision_part(build, block, label, vertices, named.kind)
            continue
        if _flat(vertices):
            what = f"body {body.name!r}" + ("" if name is None else f" part {name!r}")
            build.warnings.append(
                f"{what}: flat (no volume to decompose): its hull is used, the "
                "polygon, segment or point it is"
            )
            block.put(build.pool.hull(vertices), label)
            continue
        build.report(f"convex parts of {body.name}" + ("" if name is None else f"/{name}"))
        decomposed = True
        for part in build.parts_of((vertices, faces), **build.decompose_options):
            block.put(build.pool.part(part), label)
    all_ucx = all(n is not None and collision_part(n) is not None for n in names)
    return "ucx" if not decomposed and (own is not None or all_ucx) else "decomposed"


def _collision_part(
    build: _Build, block: _Block, label: int, vertices: np.ndarray, kind: str
) -> None:
    """An Unreal collision part as the engine takes it: a ``UCX_`` part as given (convex by
    convention), a ``UBX_``, ``USP_`` or ``UCP_`` part as the box, sphere or capsule that
    encloses it (queried exactly, placed by its pose); a flat one as the polygon it is."""
    if kind == "convex" or _flat(vertices):
        block.put(build.pool.part(vertices), label)
        return
    from meshcol.analysis.fit import fit_point_sets  # only when a file has such parts

    (result,) = fit_point_sets([vertices], kind)
    chosen = None if isinstance(result, InvalidMeshError) else result.primitive_fit
    if chosen is None:
        block.put(build.pool.part(vertices), label)
        return
    build.pool.part_poses[(block.body_number, len(block.singles))] = chosen.pose
    block.put(build.pool.add(("fit", chosen.primitive), chosen.primitive), label)


#: The builder of each collider kind: (build, body, block) -> the kind the body is reported
#: as. A new collider kind is a word in :data:`meshcol.vocabulary.COLLIDER_KINDS` and an entry
#: here (ARCHITECTURE.md, "Add a collider kind").
_BUILDERS: dict[str, Callable[[_Build, Body, _Block], str]] = {
    "hull": _hull_parts,
    "decomposed": _decomposed_parts,
    "mesh": _mesh_parts,
    "fit": _fitted_parts,
    "box": functools.partial(_fitted_parts, kind="box"),
    "sphere": functools.partial(_fitted_parts, kind="sphere"),
}
if set(_BUILDERS) != set(COLLIDER_KINDS):  # pragma: no cover - caught by importing the module
    raise ImportError(f"collider builders {sorted(_BUILDERS)} != kinds {COLLIDER_KINDS}")
