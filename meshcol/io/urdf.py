"""URDF read as a scene: one body per link, posed by forward kinematics of the joint tree.

The file is parsed strictly first (``lxml``: malformed XML is an error, never silently
repaired; what pybullet reads past is read so with a warning, :mod:`meshcol.io.urdf_lenient`),
then by ``yourdfpy`` for the model. Forward kinematics is computed here from the
joints (origin, axis, type, mimic; :class:`meshcol.io.kinematics.UrdfKinematics`), and joint
values are checked against the limits. URDF has no capsule, but many tools write
``<capsule radius length>``: it is read as one. Mesh references are resolved by
:mod:`meshcol.io.packages`; each mesh file is read once however many links use it.

:func:`read_urdf` is the reader :func:`meshcol.io.robot.load_robot_model` dispatches to.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import MeshcolError, MissingDependencyError, SceneError
from meshcol.io.kinematics import (
    UrdfKinematics,
    adjacent_links,
    default_joint_value,
)
from meshcol.io.links import (
    JOINT_TOLERANCE,
    CollisionElement,
    LinkElement,
    one_line,
    parts_body,
    primitive_body,
)
from meshcol.io.packages import PackageResolver
from meshcol.io.paths import confine
from meshcol.io.urdf_lenient import read_description_xml
from meshcol.types import Body, Box, Capsule, Cylinder, Primitive, Scene, Sphere

if TYPE_CHECKING:
    from meshcol.io.robot import RobotOptions

__all__ = ["UrdfRead", "read_urdf"]


def read_urdf(source: str, options: RobotOptions) -> UrdfRead:
    """A URDF file parsed once, at the options' joint values: its scenes of collision or
    visual elements are made from it (:meth:`UrdfRead.scene`).

    Parameters
    ----------
    source : str
        The ``.urdf`` (or ``.xml`` with a ``<robot>`` root) file.
    options : RobotOptions
        Joint values, package folders and adjacency (no keyframes: an error here).
    """
    yourdfpy, etree = _urdf_modules(source)
    warnings: list[str] = []
    root = _parse_strictly(source, warnings)  # xacro leftovers resolved, as pybullet reads
    if options.keyframe:
        raise SceneError("--keyframe: a URDF has no keyframes (MJCF only)", source)
    if root.find("link") is None:  # before yourdfpy, whose words would be "invalid URDF: 'name'"
        raise SceneError("the robot has no <link> element", source)
    if not root.get("name"):  # required by the format; pybullet does without it
        warnings.append("the <robot> element has no name: named after the file")
        root.set("name", Path(source).stem)
    capsules = _take_capsules(root, source)
    robot = _yourdfpy_robot(yourdfpy, etree, root, source)
    links = [link.name for link in robot.links]
    parent_joint = _joint_tree(robot, links, source)
    root_link = _root_link(parent_joint, links, source)
    joints = {joint.name: joint for joint in robot.joints}
    _drop_dangling_mimics(joints, warnings)
    values = _urdf_joint_values(joints, options.joints, source, warnings)
    _check_reached(robot.joints, parent_joint, links, root_link, source)
    kinematics = UrdfKinematics(
        robot.joints,
        links,
        root_link,
        lambda joint: _limits(joint, source),
        options.joints,
        values,
        source,
        name=robot.name or "",
    )
    return UrdfRead(robot, kinematics, parent_joint, capsules, options, warnings, source)


class UrdfRead:
    """A parsed URDF at one configuration (:func:`read_urdf`); its mesh files are read once
    for both of its scenes.

    Attributes
    ----------
    source : str
        The description's path.
    links : set of str
        Every link name.
    kinematics : UrdfKinematics
        The kinematics of the joint tree.
    """

    def __init__(
        self,
        robot: Any,
        kinematics: UrdfKinematics,
        parent_joint: dict[str, Any],
        capsules: dict[tuple[str, int], Capsule],
        options: RobotOptions,
        warnings: list[str],
        source: str,
    ) -> None:
        self._robot, self._parent_joint, self._capsules = robot, parent_joint, capsules
        self._options, self._warnings, self.source = options, warnings, source
        self.links = set(kinematics.links)
        self.kinematics = kinematics
        self._meshes = _LinkMeshes(PackageResolver(source, options.package_paths))

    def scene(self, visual: bool = False, sink: list[CollisionElement] | None = None) -> Scene:
        """The scene of the links' ``<collision>`` elements (``visual``: ``<visual>``), in
        link order, adjacent pairs excluded unless ``include_adjacent``; ``sink`` filled with
        one :class:`~meshcol.io.links.CollisionElement` per body part."""
        robot, source = self._robot, self.source
        link_poses = self.kinematics.link_poses(self.kinematics.loaded[None])[0]
        self._meshes.preload(_mesh_references(robot.links, visual))
        capsules = {} if visual else self._capsules  # the <collision> elements' capsules
        bodies = []
        for position, link in enumerate(robot.links):
            body = _link_body(
                link, link_poses[position], capsules, self._meshes, source, sink, visual
            )
            if body is not None:
                bodies.append(body)
        excluded: list[tuple[str, str, str]] = []
        if not self._options.include_adjacent:
            links = [link.name for link in robot.links]
            excluded = _adjacent_pairs(links, self._parent_joint, bodies)
        return Scene(
            bodies=tuple(bodies),
            units="m",
            source=source,
            excluded_pairs=tuple(excluded),
            warnings=tuple(self._warnings),
        )


# --- the file and its joint tree --------------------------------------------------------------


def _urdf_modules(source: str) -> tuple[Any, Any]:
    """``(yourdfpy, lxml.etree)``, or the install hint naming the one missing."""
    try:
        import yourdfpy
        from lxml import etree
    except ImportError as exc:
        raise MissingDependencyError(
            f"reading URDF needs yourdfpy and lxml ({exc.name} is not installed: "
            "pip install 'meshcol[robots]')",
            source,
        ) from None
    return yourdfpy, etree


def _parse_strictly(source: str, warnings: list[str]) -> Any:
    """The root element of a well-formed file whose root is ``<robot>`` (read as pybullet
    reads what it reads past, with warnings: :func:`read_description_xml`)."""
    root = read_description_xml(source, warnings, keep_blank_text=False)
    if root.tag != "robot":
        raise SceneError(f"not a URDF: the root element is <{root.tag}>, not <robot>", source)
    return root


def _yourdfpy_robot(yourdfpy: Any, etree: Any, root: Any, source: str) -> Any:
    """yourdfpy's model of the (capsule-free) tree, its errors as one line."""
    try:
        urdf = yourdfpy.URDF.load(
            io.BytesIO(etree.tostring(root)), build_scene_graph=False, load_meshes=False
        )
    except (ValueError, TypeError, KeyError, AttributeError, IndexError) as exc:
        raise SceneError(f"invalid URDF: {one_line(str(exc))}", source) from None
    return urdf.robot


def _joint_tree(robot: Any, links: list[str], source: str) -> dict[str, Any]:
    """Each child link's joint, after checking that link and joint names are unique, that
    every joint joins links that exist and that no link has two parents."""
    link_set = set(links)
    if len(link_set) != len(links):
        duplicate = next(n for n in links if links.count(n) > 1)
        raise SceneError(f"link {duplicate!r}: name used by an earlier link", source)
    joint_names = [joint.name for joint in robot.joints]
    if len(set(joint_names)) != len(joint_names):
        duplicate = next(n for n in joint_names if joint_names.count(n) > 1)
        raise SceneError(f"joint {duplicate!r}: name used by an earlier joint", source)
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
    return parent_joint


def _root_link(parent_joint: dict[str, Any], links: list[str], source: str) -> str:
    """The one link without a parent joint."""
    if not links:
        raise SceneError("the robot has no <link> element", source)
    roots = [name for name in links if name not in parent_joint]
    if not roots:
        raise SceneError(f"joint cycle: {_cycle(parent_joint, links[0])} (no root link)", source)
    if len(roots) > 1:
        raise SceneError(
            f"several root links {', '.join(repr(r) for r in roots)}: a URDF is one tree", source
        )
    return roots[0]


def _check_reached(
    joints: list[Any], parent_joint: dict[str, Any], links: list[str], root: str, source: str
) -> None:
    """Every link is reached from the root (a cycle leaves links unreached)."""
    children: dict[str, list[Any]] = {}
    for joint in joints:
        children.setdefault(joint.parent, []).append(joint)
    reached = {root}
    stack = [root]
    while stack:
        for joint in children.get(stack.pop(), []):
            reached.add(joint.child)
            stack.append(joint.child)
    if len(reached) != len(links):
        stray = next(n for n in links if n not in reached)
        raise SceneError(f"joint cycle: {_cycle(parent_joint, stray)}", source)


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


def _adjacent_pairs(
    links: list[str], parent_joint: dict[str, Any], bodies: list[Body]
) -> list[tuple[str, str, str]]:
    """MoveIt's adjacency, the rule meshcol collision-matrix uses: links joined by a joint,
    or with only links without geometry between them."""
    index = {name: i for i, name in enumerate(links)}
    edges = np.array(
        [(index[joint.parent], index[child]) for child, joint in parent_joint.items()],
        dtype=np.int64,
    ).reshape(-1, 2)
    pairs = adjacent_links(links, edges, [body.name for body in bodies])
    return [(a, b, "adjacent") for a, b in pairs]


# --- joints -----------------------------------------------------------------------------------


def _limits(joint: Any, source: str) -> tuple[float, float] | None:
    """A revolute or prismatic joint's ``[lower, upper]``; None for a joint without limits."""
    limit = joint.limit
    if joint.type not in ("revolute", "prismatic") or limit is None:
        return None
    lower = -math.inf if limit.lower is None else float(limit.lower)
    upper = math.inf if limit.upper is None else float(limit.upper)
    if math.isnan(lower) or math.isnan(upper):
        raise SceneError(f"joint {joint.name!r}: limit is not a number (nan)", source)
    if lower > upper:
        raise SceneError(
            f"joint {joint.name!r}: lower limit {lower:g} is above upper limit {upper:g}", source
        )
    return lower, upper


def _urdf_joint_values(
    joints: dict[str, Any], given: Mapping[str, float], source: str, warnings: list[str]
) -> dict[str, float]:
    """Every joint's value: given, else the default configuration of MoveIt's
    ``setToDefaultValues`` (zero, or the middle of limits that exclude zero, with a warning;
    the one :mod:`meshcol.analysis.collision_matrix` uses), mimic joints from their master;
    checked against the limits."""
    values = _given_values(joints, given, source)
    for name, joint in joints.items():
        limits = _limits(joint, source)
        if name in values or joint.mimic is not None or limits is None:
            continue
        if not limits[0] <= 0.0 <= limits[1]:
            middle = default_joint_value(*limits)
            values[name] = middle
            warnings.append(
                f"joint {name!r}: zero is outside its limits [{limits[0]:g}, {limits[1]:g}]; "
                f"at their middle, {middle:g}, as MoveIt's default configuration "
                f"(give --joint {name}=VALUE to choose)"
            )
    _mimic_values(joints, values, source)
    for name, value in values.items():
        joint = joints[name]
        limits = _limits(joint, source)
        if limits is None:
            continue
        lower, upper = limits
        if not lower - JOINT_TOLERANCE <= value <= upper + JOINT_TOLERANCE:
            how = f" (mimicking {joint.mimic.joint!r})" if joint.mimic is not None else ""
            raise SceneError(
                f"joint {name!r}: value {value:g}{how} outside its limits [{lower:g}, {upper:g}]",
                source,
            )
    return values


def _given_values(
    joints: dict[str, Any], given: Mapping[str, float], source: str
) -> dict[str, float]:
    """The values given, each for a joint that exists and takes one."""
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
    return values


def _drop_dangling_mimics(joints: dict[str, Any], warnings: list[str]) -> None:
    """A ``<mimic>`` naming a joint that does not exist is ignored, with a warning, as
    pybullet (which never reads mimics) and yourdfpy (whose validation only logs it) load
    such a robot: the joint then moves on its own (its default value, or ``--joint``)."""
    for name, joint in joints.items():
        if joint.mimic is not None and joint.mimic.joint not in joints:
            warnings.append(
                f"joint {name!r} mimics joint {joint.mimic.joint!r}, which does not exist: "
                "the mimic is ignored (as pybullet and yourdfpy do), the joint moves on its own"
            )
            joint.mimic = None


def _mimic_values(joints: dict[str, Any], values: dict[str, float], source: str) -> None:
    """Each mimic joint's value from its master's (in place): ``multiplier * q + offset``."""
    for name, joint in joints.items():
        if joint.mimic is None:
            continue
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


# --- links ------------------------------------------------------------------------------------


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


def _mesh_references(links: list[Any], visual: bool) -> Iterable[str]:
    """The mesh file references of every link's collision (or visual) elements."""
    return (
        element.geometry.mesh.filename
        for link in links
        for element in (link.visuals if visual else link.collisions)
        if element.geometry is not None and element.geometry.mesh is not None
    )


def _link_body(
    link: Any,
    pose: np.ndarray,
    capsules: dict[tuple[str, int], Capsule],
    meshes: _LinkMeshes,
    source: str,
    sink: list[CollisionElement] | None = None,
    visual: bool = False,
) -> Body | None:
    """The link's body at ``pose`` (world from link), None for a link without geometry."""
    elements: list[LinkElement] = []
    indices: list[int] = []  # the <collision> element of each entry of elements
    role = "visual" if visual else "collision"
    for index, element in enumerate(link.visuals if visual else link.collisions):
        found = _link_elements(link.name, index, element, capsules, meshes, role, source)
        elements.extend(found)
        indices.extend([index] * len(found))
    if not elements:
        return None
    if sink is not None:
        sink.extend(
            CollisionElement(link.name, index, e.origin, e.primitive, e.vertices, e.faces)
            for index, e in zip(indices, elements)
        )
    only = elements[0]
    if len(elements) == 1 and only.primitive is not None:
        return primitive_body(link.name, source, only.primitive, pose @ only.origin)
    return parts_body(link.name, source, pose, elements)


def _link_elements(
    link: str,
    index: int,
    element: Any,
    capsules: dict[tuple[str, int], Capsule],
    meshes: _LinkMeshes,
    role: str,
    source: str,
) -> list[LinkElement]:
    """One ``<collision>`` (or ``<visual>``) element: a primitive, or one entry per object
    of its mesh file (scaled; faces turned when the scale mirrors)."""
    label = f"link {link!r}"
    origin = np.eye(4) if element.origin is None else np.asarray(element.origin, dtype=np.float64)
    name = element.name or None
    primitive = _element_primitive(link, index, element.geometry, capsules, label, role, source)
    if primitive is not None:
        kind = type(primitive).__name__.lower()
        return [LinkElement(name or f"{kind}{index}", origin, primitive, None, None)]
    mesh = element.geometry.mesh
    if mesh is None:
        raise SceneError(f"{label}: {role} {index} has no shape", source)
    reference = mesh.filename
    path, why = meshes.resolver.resolve(reference)
    path = confine(path, source, reference)  # inside --root (meshcol.io.paths)
    if path is None:
        raise SceneError(f"{label}: mesh {reference!r}: {why}", source)
    scale = _mesh_scale(mesh.scale, label, source)
    stem = name or Path(reference).name
    found = []
    for object_name, vertices, faces in meshes.read(path, reference, label, source):
        if np.prod(scale) < 0:
            faces = faces[:, ::-1]
        part = stem if object_name is None else f"{stem}/{object_name}"
        found.append(LinkElement(part, origin, None, vertices * scale, faces))
    return found


def _element_primitive(
    link: str,
    index: int,
    geometry: Any,
    capsules: dict[tuple[str, int], Capsule],
    label: str,
    role: str,
    source: str,
) -> Primitive | None:
    """The element's box, sphere, cylinder or capsule; None for a mesh."""
    if (link, index) in capsules:
        return capsules[(link, index)]
    if geometry is None:
        raise SceneError(f"{label}: {role} {index} has no geometry", source)
    if geometry.box is not None:
        size = np.asarray(geometry.box.size, dtype=np.float64).reshape(-1)
        return _primitive(Box, (tuple(size),), label, "box size", source)
    if geometry.sphere is not None:
        return _primitive(Sphere, (geometry.sphere.radius,), label, "sphere radius", source)
    if geometry.cylinder is not None:
        shape = geometry.cylinder
        return _primitive(Cylinder, (shape.radius, shape.length), label, "cylinder", source)
    return None


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


class _LinkMeshes:
    """The mesh files of one description, each read once however many links use it."""

    def __init__(self, resolver: PackageResolver) -> None:
        self.resolver = resolver
        self.loaded: dict[str, list[Body]] = {}  # by normalised path

    def preload(self, references: Iterable[str]) -> None:
        """Read the OBJ and STL files of ``references`` not read yet at once, in parallel
        (the core's readers); a file that fails is left for :meth:`read` to name with its
        link."""
        from meshcol.io.mesh_formats import read_natively
        from meshcol.io.mesh_read import load_meshes

        paths = []
        for reference in references:
            path, _ = self.resolver.resolve(reference)
            if path is None or not read_natively(path):
                continue
            key = os.path.normpath(path)
            if key not in self.loaded and key not in paths and Path(key).is_file():
                paths.append(key)
        if not paths:
            return
        try:
            loaded = load_meshes(list[str | os.PathLike[str]](paths))
        except MeshcolError:
            return
        self.loaded.update(zip(paths, loaded))

    def read(
        self, path: str, reference: str, label: str, source: str
    ) -> list[tuple[str | None, np.ndarray, np.ndarray]]:
        """A mesh file's objects, each in the file's frame: ``(object name or None, v, f)``."""
        from meshcol.io.mesh_read import load_mesh

        if not Path(path).is_file():
            raise SceneError(
                f"{label}: mesh file {reference!r} not found (looked at {path})", source
            )
        key = os.path.normpath(path)
        loaded = self.loaded.get(key)
        if loaded is None:
            try:
                loaded = load_mesh(path)
            except MeshcolError as error:
                raise SceneError(f"{label}: mesh {reference!r}: {error.message}", source) from None
            self.loaded[key] = loaded
        objects = []
        for body in loaded:
            vertices = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
            object_name = body.name.split("/", 1)[1] if len(loaded) > 1 else None
            objects.append((object_name, vertices, body.faces))
        return objects
