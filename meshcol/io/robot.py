"""Robot descriptions (URDF, MJCF) read as scenes: one body per link, posed by forward kinematics.

A link is a :class:`~meshcol.types.Body` named after the link; its collision elements are its
parts, in file order, in the link's frame (each element's origin and mesh scale baked into its
vertices). A link whose only collision element is a box, sphere, cylinder or capsule stays that
exact primitive (its body pose is the link pose times the element's origin); a link of several
elements has every primitive tessellated into its parts (:func:`meshcol.io.primitives.primitive_mesh`,
the tessellation manifests use), since a body of parts is a mesh. Links without collision
geometry are frames only, never bodies.

URDF is parsed by ``yourdfpy`` (on ``lxml``, after a strict XML parse so that malformed XML is an
error, never silently repaired); forward kinematics is computed here from the joints (origin,
axis, type, mimic), and joint values are checked against the limits. ``package://NAME/REST`` is
resolved, in order, through ``--package-path NAME=DIR``, the folders of ``ROS_PACKAGE_PATH``
(``ENTRY/NAME`` or an entry named ``NAME``), an ancestor folder of the description named
``NAME``, and an ancestor folder in which ``REST`` exists (a package checked out under another
name, as the ``example-robot-data`` layout is).

MJCF is compiled by MuJoCo itself (``mujoco.MjModel.from_xml_path``), so defaults, classes and
includes mean what MuJoCo says; geom poses come from ``mj_kinematics`` at the configuration
(``qpos0``, or the first keyframe with ``keyframe=True``, then the joint values given; a
joint coupled by ``<equality><joint>`` follows its polynomial, as a URDF mimic joint). A
MuJoCo body is a link; its collision geoms (``contype`` or ``conaffinity`` non-zero) are its
parts; planes and height fields are skipped (not solids), ellipsoids are tessellated.

Self-collision exclusions travel with the scene (:attr:`Scene.excluded_pairs`): adjacent links
(URDF: MoveIt's rule, :func:`meshcol.io.kinematics.adjacent_links`, joined by a joint or with
only links without geometry between them; MJCF: parent and child bodies, as MuJoCo filters
them, and the model's ``<contact><exclude>`` pairs), unless
``include_adjacent``; and the ``<disable_collisions>`` pairs of an SRDF file.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import io
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import InputFileError, MeshcolError, MissingDependencyError, SceneError
from meshcol.io.inputs import input_kind, root_tag
from meshcol.io.kinematics import (
    Kinematics,
    MjcfKinematics,
    UrdfKinematics,
    apply_mjcf_followers,
    mjcf_followers,
)
from meshcol.io.report import read_json_file
from meshcol.types import Body, Box, Capsule, Cylinder, Primitive, Scene, Sphere
from meshcol.vocabulary import ROBOT_EXTENSIONS

__all__ = [
    "ROBOT_EXTENSIONS",
    "CollisionElement",
    "RobotOptions",
    "is_robot_file",
    "RobotModel",
    "load_robot",
    "load_robot_model",
    "parse_joint_values",
    "resolve_mesh_reference",
    "robot_options",
    "current_robot_options",
    "description_kind",
]


_JOINT_TOLERANCE = 1e-9  # joint values this far outside a limit are taken as on it


@dataclass(frozen=True)
class RobotOptions:
    """How to read a robot description.

    Attributes
    ----------
    joints : mapping of str to float
        Joint values by name (radians, metres); unnamed joints keep the default.
    keyframe : bool
        MJCF: start from the model's first keyframe instead of ``qpos0``.
    package_paths : mapping of str to str
        ``package://NAME`` -> folder, before ``ROS_PACKAGE_PATH`` and the folder layout.
    srdf : str or None
        SRDF file whose ``<disable_collisions>`` pairs are excluded from self-collision.
    include_adjacent : bool
        Keep pairs of links joined by a joint (left out by default).
    """

    joints: Mapping[str, float] = field(default_factory=dict)
    keyframe: bool = False
    package_paths: Mapping[str, str] = field(default_factory=dict)
    srdf: str | None = None
    include_adjacent: bool = False


@dataclass(frozen=True, eq=False)
class CollisionElement:
    """The collision element (URDF ``<collision>``, MJCF collision geom) behind one part of a
    link's body, for writers that rebuild a description (:mod:`meshcol.io.robot_write`).

    Attributes
    ----------
    link : str
        The link (URDF) or body (MJCF) name, the :class:`~meshcol.types.Body` name.
    index : int
        URDF: position among the link's ``<collision>`` elements (file order); MJCF: the geom
        id in the compiled model.
    origin : (4, 4) float64
        The element's frame in the link frame (URDF ``<origin>``; MJCF the compiled geom pose).
    primitive : Primitive or None
        The exact shape, or None for a mesh.
    vertices : (n, 3) float64 or None
        A mesh element's vertices in the element's frame, its scale applied (one entry per
        object of a mesh file of several objects).
    faces : (m, 3) int64 or None
    """

    link: str
    index: int
    origin: np.ndarray
    primitive: Primitive | None
    vertices: np.ndarray | None
    faces: np.ndarray | None


_OPTIONS: contextvars.ContextVar[RobotOptions | None] = contextvars.ContextVar(
    "meshcol_robot_options", default=None
)


@contextlib.contextmanager
def robot_options(options: RobotOptions) -> Iterator[None]:
    """Within the block, robot files met by :func:`meshcol.io.scene.load_inputs` (and so by
    every command) are read with ``options``."""
    token = _OPTIONS.set(options)
    try:
        yield
    finally:
        _OPTIONS.reset(token)


def current_robot_options() -> RobotOptions:
    """The options set by the innermost :func:`robot_options` block (defaults outside)."""
    return _OPTIONS.get() or RobotOptions()


def parse_joint_values(
    assignments: Sequence[str] = (), joints_file: str | None = None
) -> dict[str, float]:
    """Joint values from a JSON file (``{"name": value}``) and ``name=value`` strings (which win).

    Raises SceneError (file problems, named) or ValueError (a malformed assignment)."""
    values: dict[str, float] = {}
    if joints_file is not None:
        document = read_json_file(joints_file, "joints file")
        if not isinstance(document, dict):
            raise SceneError('joints file must be an object {"joint name": value}', joints_file)
        for name, value in document.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise SceneError(f"joint {name!r}: value must be a number", joints_file)
            values[name] = _finite(float(value), name, joints_file)
    for item in assignments:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"joint value must look like NAME=VALUE, got {item!r}")
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"joint {name.strip()!r}: {text!r} is not a number") from None
        if not math.isfinite(value):
            raise ValueError(f"joint {name.strip()!r}: value must be finite, got {text!r}")
        values[name.strip()] = value
    return values


def _finite(value: float, name: str, source: str) -> float:
    if not math.isfinite(value):
        raise SceneError(f"joint {name!r}: value must be finite, got {value!r}", source)
    return value


def is_robot_file(path: str | os.PathLike[str]) -> bool:
    """True for a ``.urdf`` or ``.mjcf`` file, or an ``.xml`` file whose root is ``<mujoco>``
    (or ``<robot>``)."""
    return input_kind(path) == "robot"


def description_kind(path: str | os.PathLike[str]) -> str:
    """``"mjcf"`` or ``"urdf"``: how :func:`load_robot` reads the file."""
    source = os.fspath(path)
    root = _root_tag(source)
    if root == "mujoco" or (Path(source).suffix.lower() == ".mjcf" and root != "robot"):
        return "mjcf"
    return "urdf"


def _root_tag(path: str) -> str | None:
    """The root element's name, from the file's first few kilobytes (None if unreadable)."""
    return root_tag(path)


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A robot description read once: the scene at one configuration and its kinematics.

    Attributes
    ----------
    scene : Scene
        As :func:`load_robot` returns it.
    kinematics : meshcol.io.kinematics.Kinematics
        Link poses of any configuration (``kinematics.loaded``: the scene's).
    """

    scene: Scene
    kinematics: Kinematics


def load_robot(
    path: str | os.PathLike[str],
    options: RobotOptions | None = None,
    *,
    elements: list[CollisionElement] | None = None,
    visual: bool = False,
) -> Scene:
    """Read a URDF or MJCF file as a scene: one body per link with collision geometry.

    Parameters
    ----------
    path : str or path-like
        ``.urdf``, ``.mjcf``, or ``.xml`` (URDF ``<robot>`` or MJCF ``<mujoco>``).
    options : RobotOptions, optional
        Joint values, keyframe, package folders, SRDF, adjacency; defaults to
        :func:`current_robot_options`.
    elements : list, optional
        Filled with one :class:`CollisionElement` per body part, in body then part order (a
        link of one part, a primitive body included, has one).
    visual : bool
        Read the links' visual geometry instead (URDF ``<visual>``; MJCF geoms that collide
        with nothing, ``contype`` and ``conaffinity`` 0), posed the same way: what a link
        looks like, for comparing with its collider (``meshcol inspect``). A link without
        visual geometry is no body; a robot without any gives a scene of no bodies.

    Returns
    -------
    Scene
        ``bodies`` in link order (file order for URDF, body order for MJCF),
        ``source = path``, ``units = "m"``, ``excluded_pairs`` the self-collision exclusions.

    Raises
    ------
    InputFileError
        Missing or unreadable file.
    MissingDependencyError
        yourdfpy (URDF) or mujoco (MJCF) not installed (``pip install 'meshcol[robots]'``).
    SceneError
        Anything wrong in the description, one line naming the link or joint (MuJoCo's own
        message for an MJCF it rejects).
    """
    return load_robot_model(path, options, elements=elements, visual=visual).scene


def load_robot_model(
    path: str | os.PathLike[str],
    options: RobotOptions | None = None,
    *,
    elements: list[CollisionElement] | None = None,
    visual: bool = False,
) -> RobotModel:
    """:func:`load_robot`, with the robot's kinematics (batched link poses of configurations,
    :mod:`meshcol.io.kinematics`) for commands that move the links."""
    options = options or current_robot_options()
    source = os.fspath(path)
    file = Path(source)
    if not file.exists():
        raise InputFileError("file not found", source)
    if file.is_dir():
        raise InputFileError("is a directory, not a robot description", source)
    root = _root_tag(source)
    if root == "mujoco" or (file.suffix.lower() == ".mjcf" and root != "robot"):
        scene, links, kinematics = _load_mjcf(source, options, elements, visual)
    else:
        scene, links, kinematics = _load_urdf(source, options, elements, visual)
    if not scene.bodies and not visual:
        raise SceneError(
            f"no link has collision geometry ({len(links)} link(s), no <collision> element "
            "or collision geom)",
            source,
        )
    for body in scene.bodies:
        _check_body(body, source)
    excluded = list(scene.excluded_pairs)
    warnings = list(scene.warnings)
    if options.srdf is not None:
        srdf_pairs, unknown = _read_srdf(options.srdf, links)
        excluded.extend(srdf_pairs)
        if unknown:
            warnings.append(
                f"{options.srdf}: <disable_collisions> names links the robot does not have, "
                f"ignored: {', '.join(repr(n) for n in unknown)}"
            )
    bodies = {b.name for b in scene.bodies}
    seen: set[tuple[str, str]] = set()
    kept = []
    for a, b, reason in excluded:
        key = (min(a, b), max(a, b))
        if a in bodies and b in bodies and a != b and key not in seen:
            seen.add(key)
            kept.append((key[0], key[1], reason))
    scene = dataclasses.replace(scene, excluded_pairs=tuple(kept), warnings=tuple(warnings))
    return RobotModel(scene, kinematics)


def _check_body(body: Body, source: str) -> None:
    """A link's pose and world coordinates are finite and within the limit of every input."""
    from meshcol.io.mesh_read import check_magnitude

    label = f"link {body.name!r}"
    if not np.all(np.isfinite(body.pose)) or not np.all(np.isfinite(body.vertices)):
        raise SceneError(f"{label}: pose or geometry is not finite (a NaN or inf origin?)", source)
    world = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
    try:
        check_magnitude(world, "world vertex", None)
    except MeshcolError as error:
        raise SceneError(f"{label}: {error.message}", source) from None


# --- URDF -----------------------------------------------------------------------------------


def _load_urdf(
    source: str,
    options: RobotOptions,
    sink: list[CollisionElement] | None = None,
    visual: bool = False,
) -> tuple[Scene, set[str], Kinematics]:
    try:
        import yourdfpy
        from lxml import etree
    except ImportError as exc:
        raise MissingDependencyError(
            f"reading URDF needs yourdfpy and lxml ({exc.name} is not installed: "
            "pip install 'meshcol[robots]')",
            source,
        ) from None
    try:
        tree = etree.parse(source, etree.XMLParser(remove_blank_text=True, resolve_entities=False))
    except etree.XMLSyntaxError as exc:
        raise SceneError(f"malformed XML: {_one_line(str(exc))}", source) from None
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc}", source) from None
    root = tree.getroot()
    if root.tag != "robot":
        raise SceneError(f"not a URDF: the root element is <{root.tag}>, not <robot>", source)
    if options.keyframe:
        raise SceneError("--keyframe: a URDF has no keyframes (MJCF only)", source)
    capsules = {} if visual else _take_capsules(root, source)
    try:
        urdf = yourdfpy.URDF.load(
            io.BytesIO(etree.tostring(root)), build_scene_graph=False, load_meshes=False
        )
    except (ValueError, TypeError, KeyError, AttributeError, IndexError) as exc:
        raise SceneError(f"invalid URDF: {_one_line(str(exc))}", source) from None
    robot = urdf.robot
    links = [link.name for link in robot.links]
    link_set = set(links)
    if len(link_set) != len(links):
        dup = next(n for n in links if links.count(n) > 1)
        raise SceneError(f"link {dup!r}: name used by an earlier link", source)
    joints = {j.name: j for j in robot.joints}
    if len(joints) != len(robot.joints):
        dup = next(j.name for j in robot.joints if sum(k.name == j.name for k in robot.joints) > 1)
        raise SceneError(f"joint {dup!r}: name used by an earlier joint", source)
    parent_joint: dict[str, Any] = {}
    for joint in robot.joints:
        for role in ("parent", "child"):
            if getattr(joint, role) not in link_set:
                raise SceneError(
                    f"joint {joint.name!r}: {role} link {getattr(joint, role)!r} does not exist",
                    source,
                )
        if joint.child in parent_joint:
            raise SceneError(
                f"link {joint.child!r} is the child of two joints, "
                f"{parent_joint[joint.child].name!r} and {joint.name!r}",
                source,
            )
        parent_joint[joint.child] = joint
    roots = [n for n in links if n not in parent_joint]
    if not roots:
        raise SceneError(f"joint cycle: {_cycle(parent_joint, links[0])} (no root link)", source)
    if len(roots) > 1:
        raise SceneError(
            f"several root links {', '.join(repr(r) for r in roots)}: a URDF is one tree", source
        )
    warnings: list[str] = []
    values = _urdf_joint_values(joints, options.joints, source, warnings)

    # Forward kinematics, parents first (a cycle leaves links unreached).
    children: dict[str, list[Any]] = {}
    for joint in robot.joints:
        children.setdefault(joint.parent, []).append(joint)
    reached = {roots[0]}
    stack = [roots[0]]
    while stack:
        for joint in children.get(stack.pop(), []):
            reached.add(joint.child)
            stack.append(joint.child)
    if len(reached) != len(links):
        stray = next(n for n in links if n not in reached)
        raise SceneError(f"joint cycle: {_cycle(parent_joint, stray)}", source)
    kinematics = UrdfKinematics(
        robot.joints,
        links,
        roots[0],
        lambda j: _limits(j, source),
        options.joints,
        values,
        source,
        name=robot.name or "",
    )
    link_poses = kinematics.link_poses(kinematics.loaded[None])[0]
    poses = {name: link_poses[i] for i, name in enumerate(links)}

    resolver = _PackageResolver(source, options.package_paths)
    resolver.preload(
        collision.geometry.mesh.filename
        for link in robot.links
        for collision in (link.visuals if visual else link.collisions)
        if collision.geometry is not None and collision.geometry.mesh is not None
    )
    bodies = []
    for link in robot.links:
        body = _urdf_link_body(
            link, poses[link.name], capsules, resolver, source, sink, visual=visual
        )
        if body is not None:
            bodies.append(body)

    # Adjacency: MoveIt's rule, the one meshcol collision-matrix uses (links joined by a
    # joint, or with only links without geometry between them).
    excluded: list[tuple[str, str, str]] = []
    if not options.include_adjacent:
        from meshcol.io.kinematics import adjacent_links

        index = {name: i for i, name in enumerate(links)}
        edges = np.array(
            [(index[j.parent], index[child]) for child, j in parent_joint.items()],
            dtype=np.int64,
        ).reshape(-1, 2)
        excluded = [
            (a, b, "adjacent") for a, b in adjacent_links(links, edges, [b.name for b in bodies])
        ]
    scene = Scene(
        bodies=tuple(bodies),
        units="m",
        source=source,
        excluded_pairs=tuple(excluded),
        warnings=tuple(warnings),
    )
    return scene, link_set, kinematics


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _cycle(parent_joint: dict[str, Any], start: str) -> str:
    """The joints of the cycle reached from ``start`` going up, as ``'a' -> 'b' -> 'a'``."""
    path: list[str] = []
    seen: dict[str, int] = {}
    link = start
    while link in parent_joint and link not in seen:
        seen[link] = len(path)
        path.append(parent_joint[link].name)
        link = parent_joint[link].parent
    loop = path[seen.get(link, 0) :]
    return " -> ".join(repr(j) for j in [*loop, loop[0]]) if loop else repr(start)


def _take_capsules(root: Any, source: str) -> dict[tuple[str, int], Capsule]:
    """URDF has no capsule; many tools write ``<capsule radius length>``. Read them here and
    stand a sphere in for yourdfpy (replaced by the capsule afterwards)."""
    capsules: dict[tuple[str, int], Capsule] = {}
    for link in root.iter("link"):
        for index, collision in enumerate(link.findall("collision")):
            geometry = collision.find("geometry")
            shape = geometry.find("capsule") if geometry is not None else None
            if shape is None:
                continue
            label = f"link {link.get('name')!r}: collision {index} capsule"
            radius = _positive(shape.get("radius"), f"{label} radius", source)
            length = _positive(shape.get("length"), f"{label} length", source, allow_zero=True)
            capsules[(link.get("name"), index)] = Capsule(radius, length)
            shape.tag = "sphere"
    return capsules


def _positive(text: str | None, label: str, source: str, allow_zero: bool = False) -> float:
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise SceneError(f"{label} must be a positive number, got {text!r}", source)
    return value


def _limits(joint: Any, source: str) -> tuple[float, float] | None:
    """A revolute or prismatic joint's ``[lower, upper]``; None for a joint without limits."""
    limit = joint.limit
    if joint.type not in ("revolute", "prismatic") or limit is None:
        return None
    lower = -math.inf if limit.lower is None else float(limit.lower)
    upper = math.inf if limit.upper is None else float(limit.upper)
    if lower > upper:
        raise SceneError(
            f"joint {joint.name!r}: lower limit {lower:g} is above upper limit {upper:g}", source
        )
    return lower, upper


def _urdf_joint_values(
    joints: dict[str, Any], given: Mapping[str, float], source: str, warnings: list[str]
) -> dict[str, float]:
    """Every joint's value: given, else zero (the limit nearest zero when zero is outside the
    limits, with a warning), mimic joints from their master; checked against the limits."""
    values: dict[str, float] = {}
    for name, value in given.items():
        joint = joints.get(name)
        if joint is None:
            raise SceneError(f"joint {name!r} does not exist", source)
        if joint.type == "fixed":
            raise SceneError(f"joint {name!r} is fixed: it takes no value", source)
        if joint.type in ("floating", "planar"):
            raise SceneError(
                f"joint {name!r} is {joint.type}: only revolute, continuous and prismatic "
                "joints take a value",
                source,
            )
        if joint.mimic is not None:
            raise SceneError(
                f"joint {name!r} mimics joint {joint.mimic.joint!r}: set that one instead", source
            )
        values[name] = float(value)
    for name, joint in joints.items():
        limits = _limits(joint, source)
        if name in values or joint.mimic is not None or limits is None:
            continue
        nearest = min(max(0.0, limits[0]), limits[1])
        if nearest != 0.0:
            values[name] = nearest
            warnings.append(
                f"joint {name!r}: zero is outside its limits [{limits[0]:g}, {limits[1]:g}]; "
                f"at {nearest:g} (give --joint {name}=VALUE to choose)"
            )
    for name, joint in joints.items():
        if joint.mimic is not None:
            master = joints.get(joint.mimic.joint)
            if master is None:
                raise SceneError(
                    f"joint {name!r} mimics joint {joint.mimic.joint!r}, which does not exist",
                    source,
                )
            if master.mimic is not None:
                raise SceneError(
                    f"joint {name!r} mimics joint {master.name!r}, which mimics another: "
                    "mimic chains are not supported",
                    source,
                )
            multiplier = 1.0 if joint.mimic.multiplier is None else joint.mimic.multiplier
            offset = 0.0 if joint.mimic.offset is None else joint.mimic.offset
            values[name] = multiplier * values.get(master.name, 0.0) + offset
    for name, value in values.items():
        joint = joints[name]
        limits = _limits(joint, source)
        if limits is None:
            continue
        lower, upper = limits
        if not lower - _JOINT_TOLERANCE <= value <= upper + _JOINT_TOLERANCE:
            how = f" (mimicking {joint.mimic.joint!r})" if joint.mimic is not None else ""
            raise SceneError(
                f"joint {name!r}: value {value:g}{how} outside its limits [{lower:g}, {upper:g}]",
                source,
            )
    return values


def _origin(matrix: np.ndarray | None) -> np.ndarray:
    return np.eye(4) if matrix is None else np.asarray(matrix, dtype=np.float64)


class _PackageResolver:
    """``package://``, ``file://``, absolute and relative mesh references to files."""

    def __init__(self, source: str, package_paths: Mapping[str, str]) -> None:
        self.folder = Path(source).resolve().parent
        self.package_paths = dict(package_paths)
        self.ros = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
        self.meshes: dict[str, list[Body]] = {}  # each mesh file read once, however many links

    def preload(self, references: Iterable[str]) -> None:
        """Read the OBJ and STL files of ``references`` at once, in parallel (the core's
        readers); a file that fails is left for :func:`_read_mesh` to name with its link."""
        from meshcol.io.mesh_read import load_meshes

        paths = []
        for reference in references:
            path, _ = self.resolve(reference)
            if path is None or Path(path).suffix.lower() not in (".obj", ".stl"):
                continue
            key = os.path.normpath(path)
            if key not in paths and Path(key).is_file():
                paths.append(key)
        if not paths:
            return
        try:
            loaded = load_meshes(list[str | os.PathLike[str]](paths))
        except MeshcolError:
            return
        self.meshes.update(zip(paths, loaded))

    def resolve(self, reference: str) -> tuple[str | None, str | None]:
        """``(path, None)``, or ``(None, why)`` for a package that cannot be found."""
        if reference.startswith("file://"):
            return reference[len("file://") :], None
        if not reference.startswith("package://"):
            path = Path(reference)
            return os.fspath(path if path.is_absolute() else self.folder / path), None
        name, _, rest = reference[len("package://") :].partition("/")
        if name in self.package_paths:
            return os.path.join(self.package_paths[name], rest), None
        for entry in self.ros:
            found = _find_package(Path(entry), name)
            if found is not None:
                return os.fspath(found / rest), None
        ancestors = [self.folder, *self.folder.parents]
        for folder in ancestors:
            if folder.name == name:
                return os.fspath(folder / rest), None
        for folder in ancestors:
            if rest and (folder / rest).is_file():
                return os.fspath(folder / rest), None
        return None, (
            f"unknown package {name!r} (give --package-path {name}=DIR or set ROS_PACKAGE_PATH)"
        )


def resolve_mesh_reference(
    source: str | os.PathLike[str], reference: str, package_paths: Mapping[str, str] = {}
) -> str | None:
    """The file a description's mesh reference (``package://``, ``file://``, relative or
    absolute) names, as :func:`load_robot` resolves it; None for an unknown package."""
    path, _ = _PackageResolver(os.fspath(source), package_paths).resolve(reference)
    return None if path is None else os.path.normpath(path)


#: How deep below a ROS_PACKAGE_PATH entry a package folder is looked for (``src/repo/pkg``).
_PACKAGE_SEARCH_DEPTH = 3


def _find_package(entry: Path, name: str) -> Path | None:
    """The folder of package ``name`` under a ROS_PACKAGE_PATH entry: the entry itself, or a
    folder ``name`` holding a ``package.xml`` at most a few levels down (breadth first)."""
    if entry.name == name and entry.is_dir():
        return entry
    if (entry / name).is_dir():
        return entry / name
    level = [entry]
    for _ in range(_PACKAGE_SEARCH_DEPTH):
        below = []
        for folder in level:
            try:
                children = sorted(p for p in folder.iterdir() if p.is_dir())
            except OSError:
                continue
            for child in children:
                if child.name == name and (child / "package.xml").is_file():
                    return child
                if not child.name.startswith("."):
                    below.append(child)
        level = below
    return None


def _urdf_link_body(
    link: Any,
    pose: np.ndarray,
    capsules: dict[tuple[str, int], Capsule],
    resolver: _PackageResolver,
    source: str,
    sink: list[CollisionElement] | None = None,
    visual: bool = False,
) -> Body | None:
    elements: list[tuple[str, np.ndarray, Primitive | None, np.ndarray | None, np.ndarray | None]]
    elements = []
    indices: list[int] = []  # the <collision> element of each entry of elements
    role = "visual" if visual else "collision"
    for index, collision in enumerate(link.visuals if visual else link.collisions):
        label = f"link {link.name!r}"
        origin = _origin(collision.origin)
        geometry = collision.geometry
        name = collision.name or None
        primitive: Primitive | None = None
        if (link.name, index) in capsules:
            primitive = capsules[(link.name, index)]
        elif geometry is None:
            raise SceneError(f"{label}: {role} {index} has no geometry", source)
        elif geometry.box is not None:
            size = np.asarray(geometry.box.size, dtype=np.float64).reshape(-1)
            primitive = _primitive(Box, (tuple(size),), label, "box size", source)
        elif geometry.sphere is not None:
            primitive = _primitive(
                Sphere, (geometry.sphere.radius,), label, "sphere radius", source
            )
        elif geometry.cylinder is not None:
            shape = geometry.cylinder
            primitive = _primitive(
                Cylinder, (shape.radius, shape.length), label, "cylinder", source
            )
        if primitive is not None:
            kind = type(primitive).__name__.lower()
            elements.append((name or f"{kind}{index}", origin, primitive, None, None))
            indices.append(index)
            continue
        if geometry.mesh is None:
            raise SceneError(f"{label}: {role} {index} has no shape", source)
        reference = geometry.mesh.filename
        path, why = resolver.resolve(reference)
        if path is None:
            raise SceneError(f"{label}: mesh {reference!r}: {why}", source)
        scale = _mesh_scale(geometry.mesh.scale, label, source)
        for sub_name, vertices, faces in _read_mesh(path, reference, label, source, resolver):
            stretched = vertices * scale
            if np.prod(scale) < 0:
                faces = faces[:, ::-1]
            stem = name or Path(reference).name
            elements.append(
                (stem if sub_name is None else f"{stem}/{sub_name}", origin, None, stretched, faces)
            )
            indices.append(index)
    if not elements:
        return None
    if sink is not None:
        sink.extend(
            CollisionElement(link.name, i, o, p, v, f)
            for i, (_, o, p, v, f) in zip(indices, elements)
        )
    if len(elements) == 1 and elements[0][2] is not None:
        _, origin, primitive, _, _ = elements[0]
        assert primitive is not None
        vertices, faces = _tessellate(primitive)
        return Body(
            name=link.name,
            source=source,
            vertices=vertices,
            faces=faces,
            pose=pose @ origin,
            primitive=primitive,
        )
    return _parts_body(link.name, source, pose, elements)


def _primitive(make: Any, args: tuple, label: str, what: str, source: str) -> Primitive:
    try:
        primitive = make(*args)
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{label}: {what}: {exc}", source) from None
    sizes = (
        primitive.size
        if isinstance(primitive, Box)
        else (primitive.radius,)
        if isinstance(primitive, Sphere)
        else (primitive.radius, primitive.length)
    )
    if not all(s > 0 for s in sizes):
        raise SceneError(f"{label}: {what} must be positive, got {sizes}", source)
    return primitive


def _mesh_scale(scale: Any, label: str, source: str) -> np.ndarray:
    if scale is None:
        return np.ones(3)
    values = np.asarray(scale, dtype=np.float64).reshape(-1)
    if values.size == 1:
        values = np.full(3, values[0])
    if values.size != 3 or not np.all(np.isfinite(values)) or np.any(values == 0):
        raise SceneError(
            f"{label}: mesh scale must be 1 or 3 finite non-zero numbers, got {scale!r}", source
        )
    return values


def _read_mesh(
    path: str, reference: str, label: str, source: str, resolver: _PackageResolver
) -> list[tuple[str | None, np.ndarray, np.ndarray]]:
    """A mesh file's objects, each in the file's frame: ``(object name or None, v, f)``."""
    from meshcol.io.mesh_read import load_mesh

    if not Path(path).is_file():
        raise SceneError(f"{label}: mesh file {reference!r} not found (looked at {path})", source)
    key = os.path.normpath(path)
    loaded = resolver.meshes.get(key)
    if loaded is None:
        try:
            loaded = load_mesh(path, collada=True)
        except MeshcolError as error:
            raise SceneError(f"{label}: mesh {reference!r}: {error.message}", source) from None
        resolver.meshes[key] = loaded
    out = []
    for body in loaded:
        vertices = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
        sub = body.name.split("/", 1)[1] if len(loaded) > 1 else None
        out.append((sub, vertices, body.faces))
    return out


def _tessellate(primitive: Primitive) -> tuple[np.ndarray, np.ndarray]:
    from meshcol.io.primitives import primitive_mesh

    return primitive_mesh(primitive)


def _parts_body(
    name: str,
    source: str,
    pose: np.ndarray,
    elements: list[tuple[str, np.ndarray, Primitive | None, np.ndarray | None, np.ndarray | None]],
) -> Body:
    """One body of parts in the link frame: every element's origin (and tessellation) baked."""
    blocks_v, blocks_f, counts, names = [], [], [], []
    base = 0
    used: set[str] = set()
    for part, origin, primitive, vertices, faces in elements:
        if primitive is not None:
            vertices, faces = _tessellate(primitive)
        assert vertices is not None and faces is not None
        blocks_v.append(vertices @ origin[:3, :3].T + origin[:3, 3])
        blocks_f.append(faces + base)
        counts.append(len(faces))
        base += len(vertices)
        unique, k = part, 2
        while unique in used:
            unique = f"{part}#{k}"
            k += 1
        used.add(unique)
        names.append(unique)
    if len(elements) == 1:
        return Body(
            name=name,
            source=source,
            vertices=np.ascontiguousarray(blocks_v[0]),
            faces=np.ascontiguousarray(blocks_f[0], dtype=np.int64),
            pose=pose,
        )
    return Body(
        name=name,
        source=source,
        vertices=np.ascontiguousarray(np.concatenate(blocks_v)),
        faces=np.ascontiguousarray(np.concatenate(blocks_f), dtype=np.int64),
        pose=pose,
        parts=tuple(names),
        part_faces=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
    )


# --- MJCF -----------------------------------------------------------------------------------


def _load_mjcf(
    source: str,
    options: RobotOptions,
    sink: list[CollisionElement] | None = None,
    visual: bool = False,
) -> tuple[Scene, set[str], Kinematics]:
    try:
        import mujoco
    except ImportError:
        raise MissingDependencyError(
            "reading MJCF needs mujoco (pip install 'meshcol[robots]')", source
        ) from None
    try:
        model = mujoco.MjModel.from_xml_path(source)
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others; its words
        raise SceneError(f"MuJoCo rejects it: {_one_line(str(exc))}", source) from None
    data = mujoco.MjData(model)
    if options.keyframe:
        if model.nkey == 0:
            raise SceneError("--keyframe: the model has no <keyframe>", source)
        data.qpos[:] = model.key_qpos[0]
    else:
        data.qpos[:] = model.qpos0
    obj = mujoco.mjtObj
    scalar_joints = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))

    def joint_name(jid: int) -> str:
        return mujoco.mj_id2name(model, obj.mjOBJ_JOINT, jid) or f"#{jid}"

    # <equality><joint joint1 joint2 polycoef>: joint1 follows joint2, as a URDF mimic joint
    followers = mjcf_followers(model)
    given: set[int] = set()
    for name, value in options.joints.items():
        jid = mujoco.mj_name2id(model, obj.mjOBJ_JOINT, name)
        if jid < 0:
            raise SceneError(f"joint {name!r} does not exist", source)
        if int(model.jnt_type[jid]) not in scalar_joints:
            raise SceneError(
                f"joint {name!r} is a free or ball joint: only hinge and slide joints take a value",
                source,
            )
        if jid in followers:
            master = followers[jid][0]
            raise SceneError(
                f"joint {name!r} follows joint {joint_name(master) if master >= 0 else '(none)'!r}"
                " by an <equality><joint> constraint: set that one instead",
                source,
            )
        data.qpos[model.jnt_qposadr[jid]] = value
        given.add(jid)
    warnings: list[str] = []
    for jid in range(model.njnt):
        if jid in given or jid in followers or options.keyframe:
            continue
        if not model.jnt_limited[jid] or int(model.jnt_type[jid]) not in scalar_joints:
            continue
        lower, upper = (float(x) for x in model.jnt_range[jid])
        adr = model.jnt_qposadr[jid]
        value = float(data.qpos[adr])
        nearest = min(max(value, lower), upper)
        if nearest != value:
            data.qpos[adr] = nearest
            warnings.append(
                f"joint {joint_name(jid)!r}: qpos0 {value:g} is outside its limits "
                f"[{lower:g}, {upper:g}]; at {nearest:g} (give --joint "
                f"{joint_name(jid)}=VALUE to choose)"
            )
    qpos = np.array(data.qpos, dtype=np.float64)[None]
    apply_mjcf_followers(model, qpos, followers)
    data.qpos[:] = qpos[0]
    for jid in range(model.njnt):
        if not model.jnt_limited[jid] or int(model.jnt_type[jid]) not in scalar_joints:
            continue
        lower, upper = (float(x) for x in model.jnt_range[jid])
        value = float(data.qpos[model.jnt_qposadr[jid]])
        if not lower - _JOINT_TOLERANCE <= value <= upper + _JOINT_TOLERANCE:
            how = ""
            if jid in followers and followers[jid][0] >= 0:
                how = f" (following {joint_name(followers[jid][0])!r})"
            raise SceneError(
                f"joint {joint_name(jid)!r}: value {value:g}{how} outside its limits "
                f"[{lower:g}, {upper:g}]",
                source,
            )
    mujoco.mj_kinematics(model, data)

    names = [mujoco.mj_id2name(model, obj.mjOBJ_BODY, b) or f"body{b}" for b in range(model.nbody)]
    geom_type = {int(t): t.name for t in mujoco.mjtGeom.__members__.values()}
    per_body: dict[int, list] = {}
    for g in range(model.ngeom):
        if (model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0) != visual:
            continue  # collision geoms (or, for visual, the geoms that collide with nothing)
        kind = geom_type.get(int(model.geom_type[g]), "")
        if kind in ("mjGEOM_PLANE", "mjGEOM_HFIELD"):
            continue
        b = int(model.geom_bodyid[g])
        size = model.geom_size[g]
        primitive: Primitive | None = None
        vertices = faces = None
        if kind == "mjGEOM_SPHERE":
            primitive = Sphere(float(size[0]))
        elif kind == "mjGEOM_CAPSULE":
            primitive = Capsule(float(size[0]), 2.0 * float(size[1]))
        elif kind == "mjGEOM_CYLINDER":
            primitive = Cylinder(float(size[0]), 2.0 * float(size[1]))
        elif kind == "mjGEOM_BOX":
            primitive = Box((2.0 * float(size[0]), 2.0 * float(size[1]), 2.0 * float(size[2])))
        elif kind == "mjGEOM_ELLIPSOID":
            vertices, faces = _tessellate(Sphere(1.0))
            vertices = vertices * np.asarray(size[:3], dtype=np.float64)
        elif kind == "mjGEOM_MESH":
            m = int(model.geom_dataid[g])
            v0, nv = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
            f0, nf = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
            vertices = np.array(model.mesh_vert[v0 : v0 + nv], dtype=np.float64)
            faces = np.array(model.mesh_face[f0 : f0 + nf], dtype=np.int64)
        else:
            continue
        gname = mujoco.mj_id2name(model, obj.mjOBJ_GEOM, g) or f"geom{g}"
        world = np.eye(4)
        world[:3, :3] = np.asarray(data.geom_xmat[g], dtype=np.float64).reshape(3, 3)
        world[:3, 3] = data.geom_xpos[g]
        per_body.setdefault(b, []).append((gname, world, primitive, vertices, faces, g))

    bodies = []
    for b in range(model.nbody):
        elements = per_body.get(b)
        if not elements:
            continue
        body_pose = np.eye(4)
        body_pose[:3, :3] = np.asarray(data.xmat[b], dtype=np.float64).reshape(3, 3)
        body_pose[:3, 3] = data.xpos[b]
        inverse = np.linalg.inv(body_pose)
        if sink is not None:
            sink.extend(
                CollisionElement(names[b], g, inverse @ w, p, v, f) for _, w, p, v, f, g in elements
            )
        if len(elements) == 1 and elements[0][2] is not None:
            gname, world, primitive, _, _, _ = elements[0]
            vertices, faces = _tessellate(primitive)
            bodies.append(
                Body(
                    name=names[b],
                    source=source,
                    vertices=vertices,
                    faces=faces,
                    pose=world,
                    primitive=primitive,
                )
            )
            continue
        local = [(n, inverse @ w, p, v, f) for n, w, p, v, f, _ in elements]
        bodies.append(_parts_body(names[b], source, body_pose, local))

    excluded: list[tuple[str, str, str]] = []
    if not options.include_adjacent:
        for b in range(1, model.nbody):
            parent = int(model.body_parentid[b])
            if parent != 0:  # MuJoCo never filters contacts with the world body
                excluded.append((names[parent], names[b], "adjacent"))
    for signature in model.exclude_signature:
        a, b = int(signature) >> 16, int(signature) & 0xFFFF
        excluded.append((names[a], names[b], "mjcf <exclude>"))
    scene = Scene(
        bodies=tuple(bodies),
        units="m",
        source=source,
        excluded_pairs=tuple(excluded),
        warnings=tuple(warnings),
    )
    return scene, set(names), MjcfKinematics(model, np.array(data.qpos), source)


# --- SRDF -----------------------------------------------------------------------------------


def _read_srdf(path: str, links: set[str]) -> tuple[list[tuple[str, str, str]], list[str]]:
    """``<disable_collisions>`` pairs (reason ``srdf: <reason>``) and the unknown link names."""
    from lxml import etree

    if not Path(path).is_file():
        raise InputFileError("SRDF file not found", path)
    try:
        root = etree.parse(path, etree.XMLParser(resolve_entities=False)).getroot()
    except etree.XMLSyntaxError as exc:
        raise SceneError(f"malformed XML: {_one_line(str(exc))}", path) from None
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc}", path) from None
    pairs: list[tuple[str, str, str]] = []
    unknown: list[str] = []
    for element in root.iter("disable_collisions"):
        a, b = element.get("link1"), element.get("link2")
        if not a or not b:
            raise SceneError(
                f"line {element.sourceline}: <disable_collisions> needs link1 and link2", path
            )
        missing = [n for n in (a, b) if n not in links]
        if missing:
            unknown.extend(n for n in missing if n not in unknown)
            continue
        pairs.append((a, b, f"srdf: {element.get('reason') or 'disabled'}"))
    return pairs, unknown
