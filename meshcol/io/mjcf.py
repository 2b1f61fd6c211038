"""MJCF read as a scene by MuJoCo itself: one body per MuJoCo body with collision geoms.

The file is compiled by ``mujoco.MjModel.from_xml_path``, so defaults, classes and includes
mean what MuJoCo says; geom poses come from ``mj_kinematics`` at the configuration (``qpos0``,
or the first keyframe with ``keyframe``, then the joint values given; a joint coupled by
``<equality><joint>`` follows its polynomial, as a URDF mimic joint). A body's collision
geoms (``contype`` or ``conaffinity`` non-zero, or named by a ``<contact><pair>``) are its
parts; height fields are skipped. Spheres, capsules, cylinders, boxes and ellipsoids are exact
primitives.

A plane (``<geom type="plane">``) is what MuJoCo collides it as, the half-space below it (its
``size`` only draws it): with ``RobotOptions.half_spaces`` (``meshcol check``) each is a body
of its own, a static :class:`~meshcol.types.HalfSpace` named ``<body>/<geom>``, filtered as
``mj_collision`` filters it (:func:`_plane_exclusions`: never against a body welded to its
own, the bitmasks of the plane geom itself, ``<exclude>``, a ``<contact><pair>`` naming it
collided whatever else says); without, planes are left out (the other commands).

:func:`read_mjcf` is the reader :func:`meshcol.io.robot.load_robot_model` dispatches to.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from meshcol.errors import MissingDependencyError, SceneError
from meshcol.io.kinematics import (
    MjcfKinematics,
    apply_mjcf_followers,
    mjcf_followers,
)
from meshcol.io.links import (
    JOINT_TOLERANCE,
    CollisionElement,
    LinkElement,
    one_line,
    parts_body,
    primitive_body,
)
from meshcol.io.paths import confine_mjcf
from meshcol.types import (
    Body,
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    HalfSpace,
    PartFilter,
    Primitive,
    Scene,
    Sphere,
    unique_name,
)

if TYPE_CHECKING:
    from meshcol.io.robot import RobotOptions

__all__ = ["MjcfRead", "read_mjcf"]

#: Followers of ``<equality><joint>``: joint id -> (leader id or -1, polynomial).
Followers = dict[int, tuple[int, np.ndarray]]


class _Geom(NamedTuple):
    """A collision geom of the compiled model at the configuration."""

    name: str
    world: np.ndarray  # (4, 4) world from geom
    primitive: Primitive | None
    vertices: np.ndarray | None  # a mesh in the geom frame
    faces: np.ndarray | None
    geom_id: int


def read_mjcf(source: str, options: RobotOptions) -> MjcfRead:
    """An MJCF file compiled by MuJoCo once, at the options' configuration: its scenes of
    collision or visual geoms are made from it (:meth:`MjcfRead.scene`).

    Parameters
    ----------
    source : str
        The ``.xml`` (``<mujoco>`` root) or ``.mjcf`` file.
    options : RobotOptions
        Joint values, keyframe and adjacency (package folders do not apply: MuJoCo finds
        its assets).
    """
    mujoco = _import_mujoco(source)
    confine_mjcf(source)  # every included and asset file inside --root (io.paths)
    try:
        model = mujoco.MjModel.from_xml_path(source)
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others; its words
        raise SceneError(f"MuJoCo rejects it: {one_line(str(exc))}", source) from None
    data = mujoco.MjData(model)
    warnings = _configure(mujoco, model, data, options, source)
    mujoco.mj_kinematics(model, data)
    names = [
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        for b in range(model.nbody)
    ]
    return MjcfRead(mujoco, model, data, names, options, warnings, source)


class MjcfRead:
    """A compiled MJCF model at one configuration (:func:`read_mjcf`).

    Attributes
    ----------
    source : str
        The description's path.
    links : set of str
        Every body name.
    kinematics : MjcfKinematics
        The model's kinematics (link poses of any configuration).
    """

    def __init__(
        self,
        mujoco: Any,
        model: Any,
        data: Any,
        names: list[str],
        options: RobotOptions,
        warnings: list[str],
        source: str,
    ) -> None:
        self._mujoco, self._model, self._data, self._names = mujoco, model, data, names
        self._options, self._warnings, self.source = options, warnings, source
        self.links = set(names)
        self.kinematics = MjcfKinematics(model, np.array(data.qpos), source)

    def scene(self, visual: bool = False, sink: list[CollisionElement] | None = None) -> Scene:
        """The scene (body order; parent and child bodies excluded unless
        ``include_adjacent``, and the model's ``<contact><exclude>`` pairs). ``visual``: of
        the geoms that collide with nothing (``contype`` and ``conaffinity`` 0) instead of
        the colliding ones; ``sink`` filled with one
        :class:`~meshcol.io.links.CollisionElement` per body part."""
        model, names = self._model, self._names
        geoms = _geoms_by_body(self._mujoco, model, self._data, visual)
        bodies = _bodies(model, self._data, names, geoms, self.source, sink)
        overridden: list[tuple[str, str]] = []
        excluded = _exclusions(model, names, self._options.include_adjacent, overridden)
        planes: list[tuple[Body, int]] = []
        if self._options.half_spaces and not visual:
            planes = _planes(self._mujoco, model, self._data, names, bodies, self.source)
            bodies.extend(body for body, _ in planes)
            excluded.extend(_plane_exclusions(model, names, bodies, planes, overridden))
        return Scene(
            bodies=tuple(bodies),
            units="m",
            source=self.source,
            excluded_pairs=tuple(excluded),
            warnings=tuple(self._warnings),
            part_filter=None if visual else _part_filter(model, names, geoms, planes, overridden),
        )


def _import_mujoco(source: str) -> Any:
    try:
        import mujoco
    except ImportError:
        raise MissingDependencyError(
            "reading MJCF needs mujoco (pip install 'meshcol[robots]')", source
        ) from None
    return mujoco


# --- the configuration ------------------------------------------------------------------------


def _configure(mujoco: Any, model: Any, data: Any, options: RobotOptions, source: str) -> list[str]:
    """Set ``data.qpos`` to the configuration the scene is read at; the warnings it gave.

    ``qpos0`` (or the first keyframe), then the values given; a joint whose ``qpos0`` is
    outside its limits is set to their middle (not with a keyframe); followers of
    ``<equality><joint>`` are set from their leaders; then every value given must be within
    its joint's limits. A keyframe's own value outside them is kept with a warning: it is
    the model's data, and MuJoCo starts from it (Menagerie's tetheria hand is 0.0026 rad
    past a finger's limit in its keyframe)."""
    if options.keyframe:
        if model.nkey == 0:
            raise SceneError("--keyframe: the model has no <keyframe>", source)
        data.qpos[:] = model.key_qpos[0]
    else:
        data.qpos[:] = model.qpos0
    followers = mjcf_followers(model)
    given = _set_given(mujoco, model, data, options.joints, followers, source)
    warnings = [] if options.keyframe else _clamp_defaults(mujoco, model, data, given, followers)
    configuration = np.array(data.qpos, dtype=np.float64)[None]
    apply_mjcf_followers(model, configuration, followers)
    data.qpos[:] = configuration[0]
    kept = _check_limits(
        mujoco, model, data, followers, given if options.keyframe else None, source
    )
    return warnings + kept


def _scalar_joint(mujoco: Any, model: Any, jid: int) -> bool:
    """Hinge and slide joints: the ones that take one value."""
    scalar = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    return int(model.jnt_type[jid]) in scalar


def _joint_name(mujoco: Any, model: Any, jid: int) -> str:
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, jid) or f"#{jid}"


def _set_given(
    mujoco: Any,
    model: Any,
    data: Any,
    joints: Mapping[str, float],
    followers: Followers,
    source: str,
) -> set[int]:
    """Set the values given (each a hinge or slide joint that follows no other); their ids."""
    given: set[int] = set()
    for name, value in joints.items():
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0:
            raise SceneError(f"joint {name!r} does not exist", source)
        if not _scalar_joint(mujoco, model, jid):
            raise SceneError(
                f"joint {name!r} is a free or ball joint: only hinge and slide joints take a value",
                source,
            )
        if jid in followers:
            leader = followers[jid][0]
            leader_name = _joint_name(mujoco, model, leader) if leader >= 0 else "(none)"
            raise SceneError(
                f"joint {name!r} follows joint {leader_name!r}"
                " by an <equality><joint> constraint: set that one instead",
                source,
            )
        data.qpos[model.jnt_qposadr[jid]] = value
        given.add(jid)
    return given


def _clamp_defaults(
    mujoco: Any, model: Any, data: Any, given: set[int], followers: Followers
) -> list[str]:
    """Set each limited joint not given whose ``qpos0`` is outside its limits to their middle
    (MoveIt's default configuration, as URDF joints whose limits exclude zero); a warning
    for each."""
    warnings: list[str] = []
    for jid in range(model.njnt):
        if jid in given or jid in followers:
            continue
        if not model.jnt_limited[jid] or not _scalar_joint(mujoco, model, jid):
            continue
        lower, upper = (float(x) for x in model.jnt_range[jid])
        address = model.jnt_qposadr[jid]
        value = float(data.qpos[address])
        if not lower <= value <= upper:
            middle = 0.5 * (lower + upper)
            data.qpos[address] = middle
            name = _joint_name(mujoco, model, jid)
            warnings.append(
                f"joint {name!r}: qpos0 {value:g} is outside its limits "
                f"[{lower:g}, {upper:g}]; at their middle, {middle:g}, as MoveIt's default "
                f"configuration (give --joint {name}=VALUE to choose)"
            )
    return warnings


def _check_limits(
    mujoco: Any,
    model: Any,
    data: Any,
    followers: Followers,
    given: set[int] | None,
    source: str,
) -> list[str]:
    """Every limited hinge and slide joint's value is within its limits (a follower's too).
    ``given``: the joints given on a keyframe (None: no keyframe); a value outside its
    limits that the keyframe set (a joint not given, a follower of one) is a warning."""
    warnings: list[str] = []
    for jid in range(model.njnt):
        if not model.jnt_limited[jid] or not _scalar_joint(mujoco, model, jid):
            continue
        lower, upper = (float(x) for x in model.jnt_range[jid])
        value = float(data.qpos[model.jnt_qposadr[jid]])
        if lower - JOINT_TOLERANCE <= value <= upper + JOINT_TOLERANCE:
            continue
        leader = followers[jid][0] if jid in followers else -1
        name, limits = _joint_name(mujoco, model, jid), f"[{lower:g}, {upper:g}]"
        if given is not None and jid not in given and leader not in given:
            warnings.append(
                f"joint {name!r}: the keyframe's value {value:g} is outside its limits "
                f"{limits}; checked there, as MuJoCo starts from it"
            )
            continue
        how = f" (following {_joint_name(mujoco, model, leader)!r})" if leader >= 0 else ""
        raise SceneError(
            f"joint {name!r}: value {value:g}{how} outside its limits {limits}", source
        )
    return warnings


# --- geoms and bodies -------------------------------------------------------------------------


def _geoms_by_body(mujoco: Any, model: Any, data: Any, visual: bool) -> dict[int, list[_Geom]]:
    """The collision geoms (``visual``: the geoms that collide with nothing) of each body, at
    their world poses; planes, height fields and unknown types left out."""
    geom_type = {int(t): t.name for t in mujoco.mjtGeom.__members__.values()}
    colliders = set(_colliding_geoms(model).tolist())
    by_body: dict[int, list[_Geom]] = {}
    for g in range(model.ngeom):
        if (g not in colliders) != visual:
            continue
        shape = _geom_shape(model, g, geom_type.get(int(model.geom_type[g]), ""))
        if shape is None:
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
        world = np.eye(4)
        world[:3, :3] = np.asarray(data.geom_xmat[g], dtype=np.float64).reshape(3, 3)
        world[:3, 3] = data.geom_xpos[g]
        by_body.setdefault(int(model.geom_bodyid[g]), []).append(_Geom(name, world, *shape, g))
    return by_body


def _geom_shape(
    model: Any, g: int, kind: str
) -> tuple[Primitive | None, np.ndarray | None, np.ndarray | None] | None:
    """A geom's ``(primitive, vertices, faces)`` in its own frame; None for a geom that is
    not a solid meshcol reads (plane, height field, and types it does not know)."""
    size = model.geom_size[g]
    if kind == "mjGEOM_SPHERE":
        return Sphere(float(size[0])), None, None
    if kind == "mjGEOM_CAPSULE":
        return Capsule(float(size[0]), 2.0 * float(size[1])), None, None
    if kind == "mjGEOM_CYLINDER":
        return Cylinder(float(size[0]), 2.0 * float(size[1])), None, None
    if kind == "mjGEOM_BOX":
        return Box((2.0 * float(size[0]), 2.0 * float(size[1]), 2.0 * float(size[2]))), None, None
    if kind == "mjGEOM_ELLIPSOID":
        return Ellipsoid((float(size[0]), float(size[1]), float(size[2]))), None, None
    if kind == "mjGEOM_MESH":
        mesh = int(model.geom_dataid[g])
        v0, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        f0, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
        vertices = np.array(model.mesh_vert[v0 : v0 + nv], dtype=np.float64)
        return None, vertices, np.array(model.mesh_face[f0 : f0 + nf], dtype=np.int64)
    return None


def _bodies(
    model: Any,
    data: Any,
    names: list[str],
    geoms: dict[int, list[_Geom]],
    source: str,
    sink: list[CollisionElement] | None,
) -> list[Body]:
    """One body per MuJoCo body with geoms: a primitive at the geom's world pose when it has
    one primitive geom, else a body of parts in the body frame."""
    bodies = []
    for b in range(model.nbody):
        body_geoms = geoms.get(b)
        if not body_geoms:
            continue
        body_pose = np.eye(4)
        body_pose[:3, :3] = np.asarray(data.xmat[b], dtype=np.float64).reshape(3, 3)
        body_pose[:3, 3] = data.xpos[b]
        inverse = np.linalg.inv(body_pose)
        local = [LinkElement(geom.name, inverse @ geom.world, *geom[2:5]) for geom in body_geoms]
        if sink is not None:
            sink.extend(
                CollisionElement(names[b], geom.geom_id, *element[1:])
                for geom, element in zip(body_geoms, local)
            )
        only = body_geoms[0]
        if len(body_geoms) == 1 and only.primitive is not None:
            bodies.append(primitive_body(names[b], source, only.primitive, only.world))
        else:
            bodies.append(parts_body(names[b], source, body_pose, local))
    return bodies


def _exclusions(
    model: Any,
    names: list[str],
    include_adjacent: bool,
    overridden: list[tuple[str, str]] | None = None,
) -> list[tuple[str, str, str]]:
    """The body pairs MuJoCo never collides (``mj_collision``'s filters), each with its reason:

    - ``adjacent``: parent and child bodies (never the world body's children), unless
      ``include_adjacent``;
    - ``mjcf <exclude>``: the model's ``<contact><exclude>`` pairs;
    - ``mjcf welded``: bodies welded together (the same ``body_weldid``: no joint between
      them), which MuJoCo never tests against each other;
    - ``mjcf contype/conaffinity``: bodies no geom pair of which passes MuJoCo's bitmask rule
      (``contype_a & conaffinity_b || contype_b & conaffinity_a``, after the compiler resolved
      defaults and classes), unless a ``<contact><pair>`` names two of their geoms.

    A pair a ``<contact><pair>`` brings back goes to ``overridden`` (once): only its explicit
    geom pairs collide there (:func:`_part_filter`).
    """
    excluded: list[tuple[str, str, str]] = []
    if not include_adjacent:
        for b in range(1, model.nbody):
            parent = int(model.body_parentid[b])
            if parent != 0:  # MuJoCo never filters contacts with the world body
                excluded.append((names[parent], names[b], "adjacent"))
    for signature in model.exclude_signature:
        a, b = int(signature) >> 16, int(signature) & 0xFFFF
        excluded.append((names[a], names[b], "mjcf <exclude>"))
    excluded.extend(_filtered_pairs(model, names))
    # An explicit <contact><pair> is collided whatever else says (parent and child, <exclude>).
    explicit = {frozenset((names[a], names[b])) for a, b in _explicit_body_pairs(model)}
    if overridden is not None:
        back = {frozenset(pair[:2]) for pair in excluded} & explicit
        overridden.extend(sorted((min(pair), max(pair)) for pair in back))
    return [pair for pair in excluded if frozenset(pair[:2]) not in explicit]


def _explicit_body_pairs(model: Any) -> set[tuple[int, int]]:
    """The body pairs of the model's ``<contact><pair>`` elements, (smaller id, larger)."""
    geom_body = np.asarray(model.geom_bodyid, dtype=np.int64)
    return {
        (min(int(geom_body[g1]), int(geom_body[g2])), max(int(geom_body[g1]), int(geom_body[g2])))
        for g1, g2 in zip(model.pair_geom1, model.pair_geom2)
    }


def _colliding_geoms(model: Any) -> np.ndarray:
    """The geoms MuJoCo may collide: ``contype`` or ``conaffinity`` non-zero, or named by a
    ``<contact><pair>`` (an explicit pair collides whatever its geoms' bitmasks: Menagerie's
    humanoids give every geom ``contype="0" conaffinity="0"`` and list the pairs)."""
    contype = np.asarray(model.geom_contype, dtype=np.int64)
    conaffinity = np.asarray(model.geom_conaffinity, dtype=np.int64)
    colliding = (contype != 0) | (conaffinity != 0)
    paired = np.concatenate([np.asarray(model.pair_geom1), np.asarray(model.pair_geom2)])
    colliding[paired.astype(np.int64)] = True
    return np.flatnonzero(colliding)


def _plane_geoms(model: Any) -> np.ndarray:
    """The ids of the model's colliding plane geoms (:func:`_colliding_geoms`), in order."""
    import mujoco

    colliding = _colliding_geoms(model)
    types = np.asarray(model.geom_type, dtype=np.int64)[colliding]
    return colliding[types == int(mujoco.mjtGeom.mjGEOM_PLANE)]


def _planes(
    mujoco: Any, model: Any, data: Any, names: list[str], bodies: list[Body], source: str
) -> list[tuple[Body, int]]:
    """Each colliding plane geom as a :class:`~meshcol.types.HalfSpace` body at its world
    pose, named ``<body>/<geom>`` (``<body>/plane<id>`` when unnamed; ``#2``... when taken),
    with its geom id. The patch drawn is MuJoCo's ``size`` doubled, or twice the model's
    extent (``stat.extent``) along a side whose size is 0 (drawn infinite by MuJoCo)."""
    used: dict[str, int] = {}
    for body in bodies:
        unique_name(body.name, used)
    extent = 2.0 * float(model.stat.extent)
    planes = []
    for g in _plane_geoms(model).tolist():
        geom = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"plane{g}"
        name = unique_name(f"{names[int(model.geom_bodyid[g])]}/{geom}", used)
        world = np.eye(4)
        world[:3, :3] = np.asarray(data.geom_xmat[g], dtype=np.float64).reshape(3, 3)
        world[:3, 3] = data.geom_xpos[g]
        x, y = (float(v) for v in model.geom_size[g][:2])
        patch = (2.0 * x if x > 0.0 else extent, 2.0 * y if y > 0.0 else extent)
        planes.append((Body.of_primitive(name, source, HalfSpace(patch), pose=world), g))
    return planes


def _plane_exclusions(
    model: Any,
    names: list[str],
    bodies: list[Body],
    planes: list[tuple[Body, int]],
    overridden: list[tuple[str, str]] | None = None,
) -> list[tuple[str, str, str]]:
    """The pairs of each plane body (:func:`_planes`) with every other body that
    ``mj_collision`` never tests, with their reasons, as :func:`_exclusions` words them:
    ``mjcf welded`` (a body welded to the plane's own, the world's when static: MuJoCo never
    collides two static geoms; every other plane), ``mjcf contype/conaffinity`` (the plane
    geom's own masks against the OR of the body's), ``mjcf <exclude>`` (the plane's body and
    the other), ``adjacent`` never (a plane lives in a static body, MuJoCo's own rule), and
    none for a body a ``<contact><pair>`` pairs with the plane geom (to ``overridden`` when
    a filter would have left it out, as :func:`_exclusions` does)."""
    contype = np.asarray(model.geom_contype, dtype=np.int64)
    conaffinity = np.asarray(model.geom_conaffinity, dtype=np.int64)
    geom_body = np.asarray(model.geom_bodyid, dtype=np.int64)
    weld = np.asarray(model.body_weldid, dtype=np.int64)
    solids = np.setdiff1d(_colliding_geoms(model), _plane_geoms(model))
    mj_body = {name: b for b, name in enumerate(names)}
    excluded_bodies = {
        frozenset((int(sig) >> 16, int(sig) & 0xFFFF)) for sig in model.exclude_signature
    }
    explicit = {frozenset((int(g1), int(g2))) for g1, g2 in zip(model.pair_geom1, model.pair_geom2)}
    plane_ids = {body.name: g for body, g in planes}
    excluded: list[tuple[str, str, str]] = []
    for plane, g in planes:
        home = int(geom_body[g])
        for other in bodies:
            if other.name == plane.name:
                continue
            if other.name in plane_ids:
                excluded.append((plane.name, other.name, "mjcf welded"))
                continue
            b = mj_body[other.name]
            own = solids[geom_body[solids] == b]
            reason = None
            if weld[b] == weld[home]:
                reason = "mjcf welded"
            elif not (
                (contype[g] & np.bitwise_or.reduce(conaffinity[own], initial=0))
                or (conaffinity[g] & np.bitwise_or.reduce(contype[own], initial=0))
            ):
                reason = "mjcf contype/conaffinity"
            elif frozenset((home, b)) in excluded_bodies:
                reason = "mjcf <exclude>"
            if any(frozenset((g, int(h))) in explicit for h in own.tolist()):
                if reason is not None and overridden is not None:
                    overridden.append((plane.name, other.name))
            elif reason is not None:
                excluded.append((plane.name, other.name, reason))
    return excluded


def _filtered_pairs(model: Any, names: list[str]) -> list[tuple[str, str, str]]:
    """Body pairs MuJoCo's weld and bitmask filters leave untested, in body order (a pair a
    ``<contact><pair>`` names among them too: :func:`_exclusions` takes those out of every
    kind of exclusion at once).

    Two bodies' geoms pass the bitmask test when some geom's ``contype`` shares a bit with
    some geom's ``conaffinity`` of the other body, that is when the OR of one body's
    ``contype`` shares a bit with the OR of the other's ``conaffinity``: each body is one
    pair of masks, and each body's row of pairs one array expression (a loop over pairs
    took 15 s for a bin of 2,000 free bodies)."""
    contype = np.asarray(model.geom_contype, dtype=np.int64)
    conaffinity = np.asarray(model.geom_conaffinity, dtype=np.int64)
    colliding = np.setdiff1d(_colliding_geoms(model), _plane_geoms(model))  # planes: bodies
    geom_body = np.asarray(model.geom_bodyid, dtype=np.int64)[colliding]
    bodies = np.unique(geom_body)
    row = np.searchsorted(bodies, geom_body)
    body_contype = np.zeros(len(bodies), dtype=np.int64)
    body_conaffinity = np.zeros(len(bodies), dtype=np.int64)
    np.bitwise_or.at(body_contype, row, contype[colliding])
    np.bitwise_or.at(body_conaffinity, row, conaffinity[colliding])
    weld = np.asarray(model.body_weldid, dtype=np.int64)[bodies]
    pairs: list[tuple[str, str, str]] = []
    for i, a in enumerate(bodies.tolist()):
        later = slice(i + 1, None)
        welded = weld[later] == weld[i]
        passes = ((body_contype[i] & body_conaffinity[later]) != 0) | (
            (body_contype[later] & body_conaffinity[i]) != 0
        )
        for k in np.flatnonzero(welded | ~passes).tolist():
            reason = "mjcf welded" if welded[k] else "mjcf contype/conaffinity"
            pairs.append((names[a], names[int(bodies[i + 1 + k])], reason))
    return pairs


def _part_filter(
    model: Any,
    names: list[str],
    geoms: dict[int, list[_Geom]],
    planes: list[tuple[Body, int]],
    overridden: list[tuple[str, str]],
) -> PartFilter:
    """The scene's per-geom filter (:class:`~meshcol.types.PartFilter`): each body's parts'
    geom ids (a plane's body its plane geom), every geom's masks, the explicit geom pairs,
    and the body pairs only those collide in (``overridden``). Within a measured body pair,
    MuJoCo tests a geom pair only when its masks pass or a ``<pair>`` names it: a body's
    other geoms are not measured against a geom it pairs with (unitree_g1's knee braces
    against the floor paired with its shin)."""
    owned = [(names[b], tuple(geom.geom_id for geom in geoms[b])) for b in sorted(geoms)]
    owned.extend((body.name, (g,)) for body, g in planes)
    return PartFilter(
        geoms=tuple(owned),
        contype=tuple(int(v) for v in model.geom_contype),
        conaffinity=tuple(int(v) for v in model.geom_conaffinity),
        explicit=tuple((int(a), int(b)) for a, b in zip(model.pair_geom1, model.pair_geom2)),
        explicit_only=tuple(overridden),
    )
