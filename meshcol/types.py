"""Types shared across meshcol: status enums and the body/scene containers.

Frames and signs, fixed once for the whole package:

- A body's ``vertices`` are in its local frame, with any scale already applied, so its
  ``pose`` is always rigid (rotation and translation only).
- ``pose`` maps local to world: ``world = R @ local + t`` (row-major 4x4).
- Every point a query or report returns is in the world frame.
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "Body",
    "Box",
    "Capsule",
    "Cylinder",
    "Ellipsoid",
    "HalfSpace",
    "PartFilter",
    "PartPrimitive",
    "Primitive",
    "Scene",
    "Sphere",
    "Spin",
    "Status",
    "TimeOfImpactStatus",
    "primitive_mesh",
    "primitive_reach",
    "primitive_vertex_count",
    "unique_name",
]


class Status(enum.IntEnum):
    """Outcome of a distance, penetration or intersection query.

    Mirrors ``Status`` in ``cpp/include/meshcol/status.hpp`` (bound as ``meshcol._core.Status``;
    ``tests/test_native.py`` checks names and values match).
    """

    CONVERGED = 0
    MAX_ITERATIONS = 1
    DEGENERATE = 2
    INVALID_INPUT = 3
    NOT_RUN = 4
    #: The answer is beyond the range of a double (two shapes near +-1e308): fields are inf or
    #: NaN, never a number taken for the answer.
    OUT_OF_RANGE = 5


class TimeOfImpactStatus(enum.IntEnum):
    """Outcome of a time-of-impact query.

    Mirrors ``TimeOfImpactStatus`` in ``cpp/include/meshcol/status.hpp`` (bound as
    ``meshcol._core.TimeOfImpactStatus``; ``tests/test_native.py`` checks they match).
    """

    HIT = 0
    SEPARATED = 1
    OVERLAPPED_AT_START = 2
    FAILED = 3
    INVALID_INPUT = 4


def _check_length(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"{name} must be finite and >= 0, got {value}")
    return value


@dataclass(frozen=True)
class Sphere:
    """Sphere centred on its local origin.

    Attributes
    ----------
    radius : float
    """

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))


@dataclass(frozen=True)
class Box:
    """Box centred on its local origin, axes along the local axes.

    Attributes
    ----------
    size : (3,) float
        FULL side lengths along local x, y, z.
    """

    size: tuple[float, float, float]

    def __post_init__(self) -> None:
        size = np.asarray(self.size, dtype=np.float64)
        if size.shape != (3,):
            raise ValueError(f"size must be (3,), got {size.shape}")
        object.__setattr__(self, "size", tuple(_check_length("size", s) for s in size))


@dataclass(frozen=True)
class Capsule:
    """Capsule: a segment along local z, centred, swept by a ball.

    Attributes
    ----------
    radius : float
    length : float
        Length of the cylindrical part (the segment), along local z.
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))
        object.__setattr__(self, "length", _check_length("length", self.length))


@dataclass(frozen=True)
class Cylinder:
    """Solid cylinder along local z, centred.

    Attributes
    ----------
    radius : float
    length : float
        Full length along local z.
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _check_length("radius", self.radius))
        object.__setattr__(self, "length", _check_length("length", self.length))


@dataclass(frozen=True)
class Ellipsoid:
    """Solid ellipsoid centred on its local origin, axes along the local axes (MJCF's
    ``type="ellipsoid"``).

    Attributes
    ----------
    semi_axes : (3,) float
        Semi-axes (HALF lengths) along local x, y, z. A zero semi-axis makes a flat ellipse,
        still a convex set, queried exactly.
    """

    semi_axes: tuple[float, float, float]

    def __post_init__(self) -> None:
        axes = np.asarray(self.semi_axes, dtype=np.float64)
        if axes.shape != (3,):
            raise ValueError(f"semi_axes must be (3,), got {axes.shape}")
        object.__setattr__(self, "semi_axes", tuple(_check_length("semi_axes", a) for a in axes))


@dataclass(frozen=True)
class HalfSpace:
    """The half-space ``z <= 0`` of its local frame: an MJCF ``<geom type="plane">``, which
    MuJoCo collides as the solid below the plane (its top face, normal local +z).

    Unbounded: queries measure it exactly (a body's lowest point along the normal,
    ``meshcol._core``'s ``half_space_pair``), never by its tessellation, which is only the
    finite patch drawn for it (review pages).

    Attributes
    ----------
    patch : (2,) float
        FULL side lengths along local x and y of the patch drawn for it (MuJoCo's ``size``
        doubled, or twice the model's extent where the size is 0, drawn infinite by MuJoCo).
        Not part of the collision shape.
    """

    patch: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        patch = np.asarray(self.patch, dtype=np.float64)
        if patch.shape != (2,):
            raise ValueError(f"patch must be (2,), got {patch.shape}")
        object.__setattr__(self, "patch", tuple(_check_length("patch", s) for s in patch))


#: An analytic shape, used exactly by every query (a manifest's ``primitive`` becomes one;
#: an MJCF plane is a :class:`HalfSpace`, read by ``check`` alone).
Primitive = Sphere | Box | Capsule | Cylinder | Ellipsoid | HalfSpace


_SPHERE_SUBDIVISIONS = 3  # icosphere: 642 vertices
_ROUND_SECTIONS = 32  # around the axis of capsules and cylinders


def primitive_mesh(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float64 and faces (m, 3) int64 of a primitive, centred, axis along z:
    made once per distinct primitive (the last 1,024 kept), the caller's own copies.

    Sphere: an icosphere of 642 vertices; ellipsoid: the unit sphere's icosphere scaled by the
    semi-axes; capsule and cylinder: 32 sections around the axis; box: 8 vertices. The
    vertices lie on the surface (the polytope is inscribed). Queries never need it (they use
    the primitive exactly): it is for what draws or exports triangles."""
    vertices, faces = _tessellation(primitive)
    return vertices.copy(), faces.copy()


@functools.lru_cache(maxsize=1024)
def _tessellation(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    """:func:`primitive_mesh`, cached, read-only."""
    import trimesh

    if isinstance(primitive, Ellipsoid):
        # The unit sphere's vertices times the semi-axes, its faces (what the MJCF reader
        # made of an ellipsoid geom before ellipsoids were exact).
        unit, faces = _tessellation(Sphere(1.0))
        vertices = unit * np.asarray(primitive.semi_axes, dtype=np.float64)
        vertices.flags.writeable = False
        return vertices, faces
    if isinstance(primitive, HalfSpace):  # the patch drawn: two triangles facing +z
        x, y = 0.5 * primitive.patch[0], 0.5 * primitive.patch[1]
        vertices = np.array([[-x, -y, 0.0], [x, -y, 0.0], [x, y, 0.0], [-x, y, 0.0]])
        faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
        vertices.flags.writeable = False
        faces.flags.writeable = False
        return vertices, faces
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
    vertices = np.array(mesh.vertices, dtype=np.float64, order="C")
    faces = np.array(mesh.faces, dtype=np.int64, order="C")
    vertices.flags.writeable = False
    faces.flags.writeable = False
    return vertices, faces


def primitive_reach(primitive: Primitive) -> float:
    """A bound, a little over, of the distance from a primitive's centre to any of its points
    (and so to any vertex of its inscribed tessellation): a world-coordinate check's reach
    without the tessellation."""
    if isinstance(primitive, Sphere):
        reach = primitive.radius
    elif isinstance(primitive, Box):
        reach = 0.5 * math.hypot(*primitive.size)
    elif isinstance(primitive, Capsule):
        reach = primitive.radius + 0.5 * primitive.length
    elif isinstance(primitive, Ellipsoid):
        reach = max(primitive.semi_axes)
    elif isinstance(primitive, HalfSpace):  # its patch's (the half-space is unbounded)
        reach = 0.5 * math.hypot(*primitive.patch)
    else:
        reach = math.hypot(primitive.radius, 0.5 * primitive.length)
    return reach * (1.0 + 1e-12)


#: The lengths within which a primitive's tessellation has the vertex count of every other of
#: its type (trimesh merges the vertices of tinier or more elongated ones), and those counts;
#: ``tests/test_primitive_bodies.py`` checks both against the tessellation.
REGULAR_LENGTHS = (1e-2, 1e5)
REGULAR_VERTEX_COUNTS: dict[type, int] = {
    Sphere: 642,
    Box: 8,
    Capsule: 1026,
    Cylinder: 66,
    Ellipsoid: 642,
    HalfSpace: 4,
}


def primitive_vertex_count(primitive: Primitive) -> int:
    """``len(primitive_mesh(primitive)[0])``, without tessellating a primitive whose lengths
    are all within :data:`REGULAR_LENGTHS`."""
    low, high = REGULAR_LENGTHS
    if isinstance(primitive, Sphere):
        regular = low <= primitive.radius <= high
    elif isinstance(primitive, Box):
        x, y, z = primitive.size
        regular = low <= x <= high and low <= y <= high and low <= z <= high
    elif isinstance(primitive, Ellipsoid | HalfSpace):  # never merged
        return REGULAR_VERTEX_COUNTS[type(primitive)]
    else:
        regular = low <= primitive.radius <= high and low <= primitive.length <= high
    if regular:
        return REGULAR_VERTEX_COUNTS[type(primitive)]
    return len(primitive_mesh(primitive)[0])


@dataclass(frozen=True, eq=False)
class Spin:
    """How a body turns over its motion, when that is not the shortest rotation.

    A body with an end pose and no spin turns the shortest way from its start to its end
    rotation (at most half a turn) about its local origin. A spin gives the turn itself: the
    body turns at constant angular velocity by ``|rotation|`` radians (any size: several turns
    are several turns) about the world axis ``rotation / |rotation|``, about ``pivot``, while
    the pivot moves linearly (see :mod:`meshcol.collision.time_of_impact`).

    Attributes
    ----------
    rotation : (3,) float64 or None
        World rotation vector of the whole motion: axis x angle in radians
        (``angular_velocity * duration`` for a manifest body). None: the shortest rotation from
        the pose to the end pose (at most half a turn), about ``pivot``.
    pivot : (3,) float64 or None
        World point the body turns about, at the start; None: the body's local origin. (The
        sub-bodies of a multi-node mesh file turn about the manifest body's origin, so that
        they move as one rigid body.)
    """

    rotation: np.ndarray | None
    pivot: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.rotation is not None:
            rotation = np.array(self.rotation, dtype=np.float64)
            if rotation.shape != (3,) or not np.all(np.isfinite(rotation)):
                raise ValueError(f"rotation must be 3 finite numbers, got {self.rotation!r}")
            object.__setattr__(self, "rotation", rotation)
        if self.pivot is not None:
            pivot = np.array(self.pivot, dtype=np.float64)
            if pivot.shape != (3,) or not np.all(np.isfinite(pivot)):
                raise ValueError(f"pivot must be 3 finite numbers, got {self.pivot!r}")
            object.__setattr__(self, "pivot", pivot)

    @property
    def angle(self) -> float | None:
        """Radians turned over the whole motion (>= 0); None for the shortest rotation."""
        return None if self.rotation is None else float(np.linalg.norm(self.rotation))

    def matrix(self) -> np.ndarray:
        """The (3, 3) rotation of the whole turn (Rodrigues' formula): R_end = matrix @ R_start.

        Raises ValueError for the shortest rotation (``rotation`` None), which only the end
        pose knows."""
        if self.rotation is None:
            raise ValueError("a spin without a rotation turns the shortest way to the end pose")
        angle = float(np.linalg.norm(self.rotation))
        if angle == 0.0:
            return np.eye(3)
        k = self.rotation / angle
        cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * (cross @ cross)


#: How far (per matrix entry) a spin's turn may miss the end rotation it claims to reach.
SPIN_ROTATION_TOLERANCE = 1e-6


class PartPrimitive(NamedTuple):
    """A part of a body that is an analytic shape (:attr:`Body.part_primitives`)."""

    primitive: Primitive
    pose: np.ndarray  # (4, 4) rigid: the body's frame from the primitive's own


@dataclass(frozen=True, eq=False)
class Body:
    """One rigid body: a triangle mesh (or primitive) and its pose.

    Attributes
    ----------
    name : str
        Unique within its scene.
    source : str or None
        The file it came from, as given by the user (relative paths stay relative).
    vertices : (n, 3) float64
        Local frame, scale applied.
    faces : (m, 3) int64
        Triangles, indices into ``vertices``. For a primitive, a tessellation
        (:func:`primitive_mesh`): given None, it is made on first use, once per distinct
        primitive (shared, read-only), so a body that nothing draws or exports is never
        tessellated; :attr:`vertex_count` knows its size without making it.
    pose : (4, 4) float64
        Rigid world-from-local pose at the start (and only) instant.
    end_pose : (4, 4) float64 or None
        Rigid pose at the end of the motion, for continuous collision.
    spin : Spin or None
        How the body turns from ``pose`` to ``end_pose`` (any angle, about a pivot); None: the
        shortest rotation about its local origin. Needs ``end_pose``, whose rotation the spin
        must reach (ValueError otherwise).
    primitive : Primitive or None
        Set when the body is an analytic shape; queries then use it exactly.
    collider : str or None
        Per-body collider kind, the manifest field ``shape`` (``hull``, ``decomposed``, ``mesh``).
    parts : tuple of str
        Names of the body's parts when it is made of several (the objects or nodes of a
        manifest body's mesh file, in file order); empty for a body of one part. Parts of one
        body are never paired with each other; reports name them (``part_a``, ``part_b``).
    part_faces : (len(parts) + 1,) int64 or None
        Part ``i`` is ``faces[part_faces[i]:part_faces[i + 1]]``; None when ``parts`` is
        empty.
    part_primitives : tuple of PartPrimitive or None
        Per part, when some part is an analytic shape (a robot link's box, sphere, cylinder
        or capsule element): that shape and its pose in the body's frame, which queries use
        exactly (its triangles in ``faces`` are its tessellation, for outputs); None for a
        mesh part. Empty when no part is one.
    """

    name: str
    source: str | None
    vertices: np.ndarray
    faces: np.ndarray
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))
    end_pose: np.ndarray | None = None
    primitive: Primitive | None = None
    collider: str | None = None
    parts: tuple[str, ...] = ()
    part_faces: np.ndarray | None = None
    spin: Spin | None = None
    part_primitives: tuple[PartPrimitive | None, ...] = ()

    def __post_init__(self) -> None:
        # the common body (one part, no spin) skips both calls: a scene can hold 300,000
        if self.parts or self.part_faces is not None or self.part_primitives:
            self._check_parts()
        if self.spin is not None:
            self._check_spin()

    def _check_parts(self) -> None:
        if self.parts:
            offsets = np.asarray(self.part_faces, dtype=np.int64)
            if (
                offsets.shape != (len(self.parts) + 1,)
                or offsets[0] != 0
                or offsets[-1] != len(self.faces)
                or np.any(np.diff(offsets) < 0)
            ):
                raise ValueError(
                    f"body {self.name!r}: part_faces must be {len(self.parts) + 1} "
                    f"non-decreasing offsets from 0 to {len(self.faces)}"
                )
            object.__setattr__(self, "part_faces", offsets)
        elif self.part_faces is not None:
            raise ValueError(f"body {self.name!r}: part_faces given without parts")
        if self.part_primitives and len(self.part_primitives) != len(self.parts):
            raise ValueError(
                f"body {self.name!r}: part_primitives must have one entry per part "
                f"({len(self.parts)}), got {len(self.part_primitives)}"
            )

    def part_meshes(self) -> list[tuple[str | None, np.ndarray, np.ndarray]]:
        """``(name, vertices, faces)`` of each part, local frame, faces indexing the part's
        own vertices; one ``(None, vertices, faces)`` for a body of one part."""
        if not self.parts:
            return [(None, self.vertices, self.faces)]
        assert self.part_faces is not None
        out: list[tuple[str | None, np.ndarray, np.ndarray]] = []
        for name, start, stop in zip(self.parts, self.part_faces[:-1], self.part_faces[1:]):
            faces = self.faces[start:stop]
            used, inverse = np.unique(faces, return_inverse=True)
            out.append((name, self.vertices[used], inverse.reshape(-1, 3).astype(np.int64)))
        return out

    def part_bodies(self) -> list[Body]:
        """One body per part, named ``<body>/<part>``, with this body's pose (the body itself
        when it has one part): for what is judged per mesh (inspect's health, decompose's
        inputs), where a body's parts are separate meshes."""
        if not self.parts:
            return [self]
        return [
            Body(
                name=f"{self.name}/{name}",
                source=self.source,
                vertices=np.ascontiguousarray(vertices),
                faces=np.ascontiguousarray(faces),
                pose=self.pose,
                end_pose=self.end_pose,
                collider=self.collider,
            )
            for name, vertices, faces in self.part_meshes()
        ]

    def _check_spin(self) -> None:
        if self.spin is None:
            return
        if self.end_pose is None:
            raise ValueError(f"body {self.name!r}: a spin needs an end pose")
        if self.spin.rotation is None:
            return
        reached = self.spin.matrix() @ np.asarray(self.pose, dtype=np.float64)[:3, :3]
        miss = np.abs(reached - np.asarray(self.end_pose, dtype=np.float64)[:3, :3]).max()
        if not miss <= SPIN_ROTATION_TOLERANCE:
            raise ValueError(
                f"body {self.name!r}: the spin does not turn the pose into the end pose "
                f"(off by {miss:.3g})"
            )

    @classmethod
    def of_primitive(
        cls, name: str, source: str | None, primitive: Primitive, **fields: Any
    ) -> Body:
        """A primitive body whose tessellation is made on first use of ``vertices`` or
        ``faces`` (never, when nothing draws or exports it); ``fields`` as the constructor's."""
        return cls(name, source, _UNMADE, _UNMADE, primitive=primitive, **fields)

    @classmethod
    def plain(
        cls,
        name: str,
        source: str | None,
        vertices: Any,
        faces: Any,
        pose: np.ndarray,
        primitive: Primitive | None = None,
        collider: str | None = None,
    ) -> Body:
        """``Body(name, source, vertices, faces, pose, primitive=primitive,
        collider=collider)``, the common body (one part, no motion), made without the frozen
        constructor's per-field calls: a loader builds 1,000,000 of them. ``vertices`` and
        ``faces`` None with a primitive: made on first use, as :meth:`of_primitive`."""
        body = object.__new__(cls)
        body.__dict__.update(
            name=name,
            source=source,
            vertices=vertices,
            faces=faces,
            pose=pose,
            end_pose=None,
            primitive=primitive,
            collider=collider,
            parts=(),
            part_faces=None,
            spin=None,
            part_primitives=(),
        )
        return body

    @property
    def vertex_count(self) -> int:
        """``len(self.vertices)``, without tessellating a primitive body for it."""
        made = self.__dict__["vertices"]
        if made is None and self.primitive is not None:
            return primitive_vertex_count(self.primitive)
        return len(self.vertices)

    def world_vertices(self, end: bool = False) -> np.ndarray:
        """Vertices in the world frame, (n, 3) float64, at the start (or end) pose."""
        m = self.end_pose if end and self.end_pose is not None else self.pose
        return self.vertices @ m[:3, :3].T + m[:3, 3]


#: What :meth:`Body.of_primitive` gives for the tessellation it leaves unmade.
_UNMADE: Any = None


class _Tessellation:
    """``Body.vertices`` and ``Body.faces``: as given; for a primitive body given None (see
    :meth:`Body.of_primitive`), its shared tessellation (:func:`primitive_mesh`), made on the
    first read. A data descriptor, so the frozen dataclass's ``__init__`` stores through it
    and a plain assignment still raises."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __get__(self, body: Body | None, owner: type | None = None) -> Any:
        if body is None:
            return self
        value = body.__dict__[self.name]
        if value is None and body.primitive is not None:
            body.__dict__["vertices"], body.__dict__["faces"] = primitive_mesh(body.primitive)
            value = body.__dict__[self.name]
        return value

    def __set__(self, body: Body, value: Any) -> None:
        body.__dict__[self.name] = value


# installed after the dataclass is made, so that it sees two plain fields without defaults
for _name in ("vertices", "faces"):
    setattr(Body, _name, _Tessellation(_name))


@dataclass(frozen=True)
class PartFilter:
    """Which part pairs of two bodies may collide, geom by geom, as MuJoCo filters them
    (an MJCF's ``contype``/``conaffinity`` and ``<contact><pair>``; :mod:`meshcol.io.mjcf`).

    Two parts collide when they are an explicit pair, or when their masks pass the bitmask
    rule (``contype_1 & conaffinity_2 || contype_2 & conaffinity_1``) and their bodies are
    not one of ``explicit_only``. Bodies it does not name are not filtered.

    Attributes
    ----------
    geoms : tuple of (str, tuple of int)
        Per body name, the geom id of each named part (``Body.parts`` order; one for a body
        of one part).
    contype, conaffinity : tuple of int
        Per geom id, its masks.
    explicit : tuple of (int, int)
        The geom pairs ``<contact><pair>`` names: collided whatever their masks.
    explicit_only : tuple of (str, str)
        Body pairs whose geoms collide only as explicit pairs (welded, parent and child,
        ``<exclude>``: filters a ``<pair>`` overrides for its own two geoms only).
    """

    geoms: tuple[tuple[str, tuple[int, ...]], ...]
    contype: tuple[int, ...]
    conaffinity: tuple[int, ...]
    explicit: tuple[tuple[int, int], ...] = ()
    explicit_only: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True, eq=False)
class Scene:
    """Bodies to analyse together.

    Attributes
    ----------
    bodies : sequence of Body
        In input order; names are unique. A tuple, or for a manifest of static primitives
        only a :class:`meshcol.io.scene_primitives.PrimitiveBodies` (its bodies as columns,
        each Body made when indexed).
    units : str or None
        Length unit declared by the manifest (reported back verbatim), or None.
    source : str or None
        Manifest or scene file, when there was one.
    duration : float or None
        Seconds the start-to-end motion takes, when the manifest gives one.
    excluded_pairs : tuple of (str, str, str)
        Body pairs never checked against each other, ``(body_a, body_b, reason)`` with
        ``body_a < body_b``: a robot's adjacent links and SRDF ``<disable_collisions>``
        (:mod:`meshcol.io.robot`). Empty for manifests and mesh files.
    warnings : tuple of str
        What reading the scene could not do as asked, one line each (reports repeat them).
    part_filter : PartFilter or None
        Which part pairs of a measured body pair may collide (an MJCF's geom filters);
        None: every one.
    """

    bodies: Sequence[Body]
    units: str | None = None
    source: str | None = None
    duration: float | None = None
    excluded_pairs: tuple[tuple[str, str, str], ...] = ()
    warnings: tuple[str, ...] = ()
    part_filter: PartFilter | None = None


def unique_name(name: str, used: dict[str, int]) -> str:
    """``name``, or ``name#2``, ``name#3``... when taken: the first not in ``used``, which
    records it. The one rule for the names of bodies (of several files, of a file's nodes and
    groups) and of a body's parts.

    ``used`` maps each name to the suffix to try next for it, so ``n`` bodies of one name
    cost ``n`` steps, not ``n * n / 2`` (a USD stage of 10,000 prims named ``mesh`` spent
    17 s here).
    """
    if name not in used:
        used[name] = 2
        return name
    k = used[name]
    while f"{name}#{k}" in used:
        k += 1
    unique = f"{name}#{k}"
    used[name] = k + 1
    used[unique] = 2
    return unique
