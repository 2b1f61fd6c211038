"""Forward kinematics of robot descriptions, batched over joint configurations.

A configuration is one value per *free* joint of :class:`JointSpace` (URDF: revolute,
continuous and prismatic joints that mimic nothing; MJCF: hinge and slide joints that no
``<equality><joint>`` drives), in radians and metres. Fixed joints stay fixed, mimic joints and
equality-driven joints follow their leader, floating and planar URDF joints stay at identity and
MJCF free and ball joints keep their default (see :attr:`Kinematics.held`).

- URDF (:class:`UrdfKinematics`): the link transforms of ``n`` configurations at once, in numpy:
  one ``(n, 4, 4)`` product per joint, parents first (Rodrigues' formula for the rotations).
- MJCF (:class:`MjcfKinematics`): MuJoCo's own ``mj_kinematics`` per configuration, so that
  every joint type and every frame means what MuJoCo says.

:func:`meshcol.io.robot.load_robot_model` builds them from the parsed file (the one parse and
validation of robot descriptions, :mod:`meshcol.io.urdf` and :mod:`meshcol.io.mjcf`); :func:`adjacent_links` is the adjacency rule of MoveIt's
setup assistant on their link tree.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.errors import SceneError

__all__ = [
    "JointSpace",
    "Kinematics",
    "MjcfKinematics",
    "UrdfKinematics",
    "adjacent_links",
    "mjcf_followers",
    "apply_mjcf_followers",
]


@dataclass(frozen=True, eq=False)
class JointSpace:
    """The free joints of a robot, their sampling ranges and their default values.

    Attributes
    ----------
    names : tuple of str
        Free joints, in file order; column ``k`` of a configuration is joint ``names[k]``.
    lower, upper : (d,) float64
        Sampling range of each joint: its limits (continuous or unlimited revolute joints:
        ``[-pi, pi]``).
    default : (d,) float64
        The default configuration: the values given (``--joint``), else, as MoveIt's
        ``setToDefaultValues``, zero when zero is within the limits and the middle of the
        limits when it is not (URDF); MJCF: the configuration the model was read at (``qpos0``
        or its first keyframe, clamped to the limits, then the values given).
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    default: np.ndarray

    def __len__(self) -> int:
        return len(self.names)

    def sample(self, count: int, seed: int) -> np.ndarray:
        """``count`` configurations uniform within the ranges, (count, d) float64; the same
        seed gives the same configurations (NumPy's PCG64 generator)."""
        rng = np.random.default_rng(seed)
        unit = rng.random((count, len(self.names)))
        return self.lower + (self.upper - self.lower) * unit


class Kinematics:
    """Link poses of configurations: the interface of :class:`UrdfKinematics` and
    :class:`MjcfKinematics`.

    Attributes
    ----------
    name : str
        The robot's name (URDF ``<robot name>``, MJCF ``<mujoco model>``).
    links : tuple of str
        Every link (URDF) or body (MJCF, ``world`` first), in file order.
    edges : (e, 2) int64
        Parent and child link index of each joint (MJCF: each body and its parent, the world
        body's children left out, as MuJoCo filters contacts).
    space : JointSpace
    loaded : (d,) float64
        The configuration the description was read at (the scene's link poses).
    held : tuple of str
        Joints that are never sampled and not fixed (URDF floating and planar joints, MJCF
        free and ball joints and slide joints without a range, a floating base's translation):
        they keep their default, one line each for the report.
    """

    name: str
    links: tuple[str, ...]
    edges: np.ndarray
    space: JointSpace
    loaded: np.ndarray
    held: tuple[str, ...]

    def link_poses(self, configurations: Any) -> np.ndarray:  # pragma: no cover - interface
        """World-from-link poses, (n, len(links), 4, 4), of ``configurations`` (n, d)."""
        raise NotImplementedError


def _configurations(configurations: Any, d: int) -> np.ndarray:
    q = np.ascontiguousarray(configurations, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != d:
        raise ValueError(f"configurations must be (n, {d}), got {q.shape}")
    return q


class UrdfKinematics(Kinematics):
    """A URDF's joint tree, vectorised over configurations.

    Parameters
    ----------
    joints : sequence of yourdfpy joints
        Checked already (every link exists, one parent per link, no cycle).
    links : sequence of str
        Link names in file order.
    root : str
        The root link (world frame).
    limits : callable
        ``limits(joint)``: ``(lower, upper)`` of a revolute or prismatic joint, None without
        limits (:func:`meshcol.io.urdf._limits`).
    given : mapping of str to float
        Joint values the user gave: the default configuration there.
    loaded : mapping of str to float
        Joint values the description was read at (mimic joints included, ignored here).
    source : str
        The file, for messages.
    name : str
        The robot's name.
    """

    def __init__(
        self,
        joints: Sequence[Any],
        links: Sequence[str],
        root: str,
        limits: Callable[[Any], tuple[float, float] | None],
        given: Any,
        loaded: Any,
        source: str,
        name: str = "",
    ) -> None:
        self.name = name
        self.links = tuple(links)
        index = {link: i for i, link in enumerate(self.links)}
        self.root = index[root]
        free = [
            j for j in joints if j.type in ("revolute", "continuous", "prismatic") and not j.mimic
        ]
        # a prismatic joint without a finite range is not sampled: it keeps its value
        constant = {
            j.name: float(loaded.get(j.name, 0.0))
            for j in free
            if j.type == "prismatic" and not all(map(math.isfinite, limits(j) or (math.inf,)))
        }
        free = [j for j in free if j.name not in constant]
        self.space = _urdf_joint_space(free, limits, given, source)
        self.loaded = np.asarray([float(loaded.get(j.name, 0.0)) for j in free], np.float64)
        self.held = tuple(
            f"joint {j.name!r} is {j.type}: kept at identity"
            for j in joints
            if j.type in ("floating", "planar")
        ) + tuple(
            f"joint {name!r} is a prismatic joint without limits: kept at {value:g}"
            for name, value in constant.items()
        )
        column = {j.name: k for k, j in enumerate(free)}
        self._steps = [
            _urdf_step(j, index, column, source, constant) for j in _parents_first(joints, root)
        ]
        self.edges = np.array(
            [(index[j.parent], index[j.child]) for j in joints], dtype=np.int64
        ).reshape(-1, 2)

    def link_poses(self, configurations: Any) -> np.ndarray:
        """World-from-link poses (n, links, 4, 4) of ``configurations`` (n, d); links that
        no joint reaches from the root (none in a checked tree) stay at identity."""
        q = _configurations(configurations, len(self.space))
        n = len(q)
        poses = np.zeros((n, len(self.links), 4, 4))
        poses[:, :] = np.eye(4)
        for parent, child, origin, kind, axis, col, multiplier, offset in self._steps:
            frame = poses[:, parent] @ origin
            if kind == "fixed":
                poses[:, child] = frame
                continue
            value = np.full(n, offset) if col < 0 else multiplier * q[:, col] + offset
            motion = np.zeros((n, 4, 4))
            motion[:, 3, 3] = 1.0
            if kind == "prismatic":
                motion[:, :3, :3] = np.eye(3)
                motion[:, :3, 3] = value[:, None] * axis
            else:  # revolute, continuous: Rodrigues' rotation formula
                k = np.array(
                    [[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]]
                )
                motion[:, :3, :3] = (
                    np.eye(3)
                    + np.sin(value)[:, None, None] * k
                    + (1.0 - np.cos(value))[:, None, None] * (k @ k)
                )
            poses[:, child] = frame @ motion
        return poses


#: One joint of :class:`UrdfKinematics`, parents first: parent and child link index, the
#: joint origin (4, 4), its kind ("fixed", "revolute", "continuous", "prismatic"), its unit
#: axis, the configuration column it reads (-1: none) and the mimic multiplier and offset.
_Step = tuple[int, int, np.ndarray, str, np.ndarray, int, float, float]


def default_joint_value(lower: float, upper: float) -> float:
    """A joint's value in the default configuration, as MoveIt's ``setToDefaultValues``: zero,
    or the middle of limits that exclude zero (``check`` and ``collision-matrix`` alike)."""
    if lower <= 0.0 <= upper:
        return 0.0
    if not (math.isfinite(lower) and math.isfinite(upper)):
        return lower if math.isfinite(lower) else upper  # a half-open range: its one limit
    return 0.5 * (lower + upper)


def _urdf_joint_space(
    free: list[Any],
    limits: Callable[[Any], tuple[float, float] | None],
    given: Any,
    source: str,
) -> JointSpace:
    """The sampling ranges (continuous and unlimited revolute joints: ``[-pi, pi]``) and the
    default configuration (MoveIt's) of the free joints."""
    lower, upper, default = [], [], []
    for j in free:
        bounds = limits(j) if j.type != "continuous" else None
        if bounds is None or not all(math.isfinite(b) for b in bounds):
            bounds = (-math.pi, math.pi)  # prismatic joints without a range are held
        lower.append(bounds[0])
        upper.append(bounds[1])
        default.append(float(given[j.name]) if j.name in given else default_joint_value(*bounds))
    return JointSpace(
        tuple(j.name for j in free),
        np.asarray(lower, dtype=np.float64),
        np.asarray(upper, dtype=np.float64),
        np.asarray(default, dtype=np.float64),
    )


def _parents_first(joints: Sequence[Any], root: str) -> list[Any]:
    """The joints in a breadth-first walk from the root link."""
    children: dict[str, list[Any]] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    ordered: list[Any] = []
    frontier = [root]
    while frontier:
        below = []
        for link in frontier:
            for j in children.get(link, []):
                ordered.append(j)
                below.append(j.child)
        frontier = below
    return ordered


def _urdf_step(
    j: Any, index: dict[str, int], column: dict[str, int], source: str, constant: dict[str, float]
) -> _Step:
    """What :meth:`UrdfKinematics.link_poses` does for joint ``j`` (floating and planar
    joints held fixed; the axis made a unit vector; a mimic joint reads its leader's
    column; a held joint, or the mimic of one, its ``constant`` value)."""
    origin = np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=np.float64)
    axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.asarray(j.axis, float)
    kind = "fixed" if j.type in ("fixed", "floating", "planar") else j.type
    if kind != "fixed":
        norm = float(np.linalg.norm(axis))
        if not math.isfinite(norm) or norm == 0.0:
            raise SceneError(f"joint {j.name!r}: axis must be a finite non-zero vector", source)
        axis = axis / norm
    col, multiplier, offset = column.get(j.name, -1), 1.0, constant.get(j.name, 0.0)
    if j.mimic is not None and kind != "fixed":
        col = column.get(j.mimic.joint, -1)
        multiplier = 1.0 if j.mimic.multiplier is None else float(j.mimic.multiplier)
        offset = 0.0 if j.mimic.offset is None else float(j.mimic.offset)
        offset += multiplier * constant.get(j.mimic.joint, 0.0)
    return (index[j.parent], index[j.child], origin, kind, axis, col, multiplier, offset)


def mjcf_followers(model: Any) -> dict[int, tuple[int, np.ndarray]]:
    """``<equality><joint joint1 joint2 polycoef>`` constraints active at start: joint1 follows
    joint2 (-1 for none) by the polynomial (5 coefficients, constant first), as a URDF mimic."""
    import mujoco

    followers: dict[int, tuple[int, np.ndarray]] = {}
    for e in range(model.neq):
        if int(model.eq_type[e]) != int(mujoco.mjtEq.mjEQ_JOINT) or not model.eq_active0[e]:
            continue
        followers[int(model.eq_obj1id[e])] = (
            int(model.eq_obj2id[e]),
            np.array(model.eq_data[e][:5], dtype=np.float64),
        )
    return followers


def apply_mjcf_followers(
    model: Any, qpos: np.ndarray, followers: dict[int, tuple[int, np.ndarray]]
) -> None:
    """Set each follower's ``qpos`` (rows of ``qpos``, (n, nq), in place) from its leader:
    ``q1 = q1_0 + poly(q2 - q2_0)`` about ``qpos0``, as MuJoCo's joint equality."""
    for follower, (leader, coefficients) in followers.items():
        ref1 = float(model.qpos0[model.jnt_qposadr[follower]])
        x = np.zeros(len(qpos))
        if leader >= 0:
            adr = model.jnt_qposadr[leader]
            x = qpos[:, adr] - model.qpos0[adr]
        qpos[:, model.jnt_qposadr[follower]] = ref1 + np.polyval(coefficients[::-1], x)


class MjcfKinematics(Kinematics):
    """A compiled MuJoCo model; poses by ``mj_kinematics``, one configuration at a time.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : (nq,) float
        The configuration the model was read at (every joint, followers applied).
    source : str
        The file, for messages.
    """

    def __init__(self, model: Any, qpos: np.ndarray, source: str) -> None:
        import mujoco

        self.model = model
        self.qpos = np.array(qpos, dtype=np.float64)
        self.followers = mjcf_followers(model)
        self.name = bytes(model.names).split(b"\0", 1)[0].decode("utf-8", "replace")
        obj = mujoco.mjtObj
        self.links = tuple(
            mujoco.mj_id2name(model, obj.mjOBJ_BODY, b) or f"body{b}" for b in range(model.nbody)
        )
        hinge, slide = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)
        names, lower, upper, adrs, held = [], [], [], [], []
        for jid in range(model.njnt):
            name = mujoco.mj_id2name(model, obj.mjOBJ_JOINT, jid) or f"#{jid}"
            kind = int(model.jnt_type[jid])
            if kind not in (hinge, slide):
                what = "free" if kind == int(mujoco.mjtJoint.mjJNT_FREE) else "ball"
                held.append(f"joint {name!r} is a {what} joint: kept at its default")
                continue
            if jid in self.followers:
                continue
            if model.jnt_limited[jid]:
                lo, hi = (float(x) for x in model.jnt_range[jid])
            elif kind == hinge:
                lo, hi = -math.pi, math.pi
            else:  # a floating base's translation (rootx of a planar walker): not sampled
                held.append(f"joint {name!r} is a slide joint without a range: kept at its default")
                continue
            names.append(name)
            lower.append(lo)
            upper.append(hi)
            adrs.append(int(model.jnt_qposadr[jid]))
        self._adrs = np.asarray(adrs, dtype=np.int64)
        self.loaded = self.qpos[self._adrs]
        self.space = JointSpace(
            tuple(names),
            np.asarray(lower, dtype=np.float64),
            np.asarray(upper, dtype=np.float64),
            self.loaded.copy(),
        )
        self.held = tuple(held)
        parents = np.asarray(model.body_parentid, dtype=np.int64)
        bodies = np.arange(1, model.nbody, dtype=np.int64)
        keep = parents[bodies] != 0
        self.edges = np.stack([parents[bodies][keep], bodies[keep]], axis=1).reshape(-1, 2)

    def link_poses(self, configurations: Any) -> np.ndarray:
        """World-from-body poses (n, nbody, 4, 4) of ``configurations`` (n, d), by
        ``mj_kinematics`` on one MjData (the world body at identity)."""
        import mujoco

        q = _configurations(configurations, len(self.space))
        model = self.model
        qpos = np.repeat(self.qpos[None], len(q), axis=0)
        qpos[:, self._adrs] = q
        apply_mjcf_followers(model, qpos, self.followers)
        data = mujoco.MjData(model)
        poses = np.zeros((len(q), model.nbody, 4, 4))
        poses[:, :, 3, 3] = 1.0
        for i in range(len(q)):
            data.qpos[:] = qpos[i]
            mujoco.mj_kinematics(model, data)
            poses[i, :, :3, :3] = data.xmat.reshape(-1, 3, 3)
            poses[i, :, :3, 3] = data.xpos
        return poses


def adjacent_links(
    links: Sequence[str], edges: np.ndarray, with_geometry: Iterable[str]
) -> list[tuple[str, str]]:
    """Pairs of links with geometry that MoveIt's setup assistant calls adjacent.

    Two links are adjacent when a joint joins them, or when links without geometry alone lie
    between them: every link without geometry makes its neighbours adjacent to each other,
    repeatedly (the connection graph of MoveIt's ``computeConnectionGraph``), so the parent and
    the children of a bare frame link, and the children of a bare root, are adjacent.

    Returns
    -------
    list of (str, str)
        Sorted pairs, each ordered by name.
    """
    geometry = set(with_geometry)
    neighbours: dict[int, set[int]] = {i: set() for i in range(len(links))}
    for a, b in np.asarray(edges, dtype=np.int64).reshape(-1, 2).tolist():
        neighbours[a].add(b)
        neighbours[b].add(a)
    changed = True
    while changed:
        changed = False
        for i, around in neighbours.items():
            if links[i] in geometry:
                continue
            for a in around:
                for b in around:
                    if a != b and b not in neighbours[a]:
                        neighbours[a].add(b)
                        changed = True
    pairs = {
        tuple(sorted((links[i], links[j])))
        for i, around in neighbours.items()
        for j in around
        if links[i] in geometry and links[j] in geometry and i != j
    }
    return sorted(pairs)  # type: ignore[arg-type]
