"""Robot descriptions (URDF, MJCF) read as scenes: one body per link, posed by forward kinematics.

A link is a :class:`~meshcol.types.Body` named after the link; its collision elements are its
parts, in file order, in the link's frame (each element's origin and mesh scale baked into its
vertices). A link whose only collision element is a box, sphere, cylinder or capsule stays that
exact primitive; a link of several elements has every primitive tessellated into its parts
(:mod:`meshcol.io.links`). Links without collision geometry are frames only, never bodies.

This module is the front door: the options (:class:`RobotOptions`, made and checked once,
passed explicitly to every loader and command), which reader a file goes to, and what every
description gets after its reader:

- URDF: :mod:`meshcol.io.urdf` (yourdfpy; forward kinematics of the joint tree here), mesh
  references by :mod:`meshcol.io.packages` (``package://``, ``ROS_PACKAGE_PATH``);
- MJCF: :mod:`meshcol.io.mjcf` (MuJoCo's compiler and ``mj_kinematics``);
- then every link's pose and coordinates are checked, and the self-collision exclusions travel
  with the scene (:attr:`Scene.excluded_pairs`): adjacent links (URDF: MoveIt's rule,
  :func:`meshcol.io.kinematics.adjacent_links`; MJCF: parent and child bodies, as MuJoCo
  filters them, and the model's ``<contact><exclude>`` pairs), unless ``include_adjacent``;
  and the ``<disable_collisions>`` pairs of an SRDF file (:func:`meshcol.io.srdf.read_srdf`).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import InputFileError, MeshcolError, SceneError
from meshcol.io.inputs import is_robot_file, root_tag
from meshcol.io.links import CollisionElement
from meshcol.io.report import read_json_file
from meshcol.io.safe_read import check_input, check_mjcf_files
from meshcol.types import Body, Scene, primitive_reach

if TYPE_CHECKING:
    from meshcol.io.kinematics import Kinematics

__all__ = [
    "CollisionElement",
    "RobotOptions",
    "is_robot_file",
    "RobotModel",
    "load_robot",
    "load_robot_model",
    "load_robot_views",
    "parse_joint_values",
    "parse_package_paths",
    "description_kind",
]


@dataclass(frozen=True)
class RobotOptions:
    """How to read a robot description: made and checked once, then passed explicitly
    (``robot_options=`` of :func:`meshcol.io.scene.load_inputs` and of every command's
    function; the options of the command line's ``--joint``, ``--srdf`` ...).

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
    half_spaces : bool
        MJCF: read each ``<geom type="plane">`` as a body of its own, a static
        :class:`~meshcol.types.HalfSpace` (``meshcol check``); left out by default (the
        commands that rebuild, fit, inspect or sweep colliders have nothing to do with one).

    Raises
    ------
    ValueError
        A joint name that is not a string or a value that is not a finite number, an empty
        package name or folder.
    TypeError
        ``keyframe``, ``include_adjacent`` or ``half_spaces`` not a bool.

    Notes
    -----
    ``joints`` and ``package_paths`` are read-only copies of the mappings given (joint
    values as floats): the options cannot change once made.
    """

    joints: Mapping[str, float] = field(default_factory=dict)
    keyframe: bool = False
    package_paths: Mapping[str, str] = field(default_factory=dict)
    srdf: str | None = None
    include_adjacent: bool = False
    half_spaces: bool = False

    def __post_init__(self) -> None:
        for flag in ("keyframe", "include_adjacent", "half_spaces"):
            if not isinstance(getattr(self, flag), bool):
                raise TypeError(f"{flag} must be True or False, got {getattr(self, flag)!r}")
        joints = MappingProxyType(_joint_values(self.joints))
        packages = MappingProxyType(_package_folders(self.package_paths))
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "package_paths", packages)
        if self.srdf is not None:
            object.__setattr__(self, "srdf", os.fspath(self.srdf))

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # The read-only mappings do not pickle: the options travel as the dicts they copy.
        fields = (dict(self.joints), self.keyframe, dict(self.package_paths), self.srdf)
        return (RobotOptions, (*fields, self.include_adjacent, self.half_spaces))


def _joint_values(joints: Mapping[str, Any]) -> dict[str, float]:
    values: dict[str, float] = {}
    for name, value in dict(joints).items():
        if not isinstance(name, str):
            raise ValueError(f"joint name must be a string, got {name!r}")
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(f"joint {name!r}: value must be a number, got {value!r}")
        if not math.isfinite(float(value)):
            raise ValueError(f"joint {name!r}: value must be finite, got {value!r}")
        values[name] = float(value)
    return values


def _package_folders(package_paths: Mapping[str, Any]) -> dict[str, str]:
    folders: dict[str, str] = {}
    for name, folder in dict(package_paths).items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"package name must be a non-empty string, got {name!r}")
        if not isinstance(folder, (str, os.PathLike)) or not os.fspath(folder):
            raise ValueError(f"package {name!r}: folder must be a non-empty path, got {folder!r}")
        folders[name] = os.fspath(folder)
    return folders


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


def parse_package_paths(assignments: Sequence[str] = ()) -> dict[str, str]:
    """Package folders from ``NAME=DIR`` strings (a later one for a name wins).

    Raises ValueError naming an assignment that is not ``NAME=DIR``."""
    folders: dict[str, str] = {}
    for item in assignments:
        name, sep, folder = item.partition("=")
        if not sep or not name or not folder:
            raise ValueError(f"must look like NAME=DIR, got {item!r}")
        folders[name] = folder
    return folders


def description_kind(path: str | os.PathLike[str]) -> str:
    """``"mjcf"`` or ``"urdf"``: how :func:`load_robot` reads the file."""
    source = os.fspath(path)
    root = root_tag(source)
    if root == "mujoco" or (Path(source).suffix.lower() == ".mjcf" and root != "robot"):
        return "mjcf"
    return "urdf"


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


#: The reader of each kind of description (:func:`description_kind`).
def _reader(kind: str) -> Any:
    """The reader of a description of ``kind``, imported when first needed: a command that
    reads no robot (a scene's check) never imports the URDF and MJCF readers."""
    if kind == "urdf":
        from meshcol.io.urdf import read_urdf

        return read_urdf
    from meshcol.io.mjcf import read_mjcf

    return read_mjcf


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
        Joint values, keyframe, package folders, SRDF, adjacency; default ``RobotOptions()``
        (every joint at its default, adjacent links excluded).
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
    options = RobotOptions() if options is None else options
    read = _read(path, options)
    return RobotModel(_scene(read, options, visual, elements), read.kinematics)


def load_robot_views(
    path: str | os.PathLike[str], options: RobotOptions | None = None
) -> tuple[Scene, Scene | MeshcolError]:
    """The robot's collision scene (:func:`load_robot`) and its visual one (``visual=True``)
    from one read of the description (an MJCF compiled once, a mesh file both use read
    once): ``meshcol inspect`` compares them. The visual scene is the error that stopped
    it when only it fails."""
    options = RobotOptions() if options is None else options
    read = _read(path, options)
    scene = _scene(read, options, False, None)
    try:
        return scene, _scene(read, options, True, None)
    except MeshcolError as error:
        return scene, error


def _read(path: str | os.PathLike[str], options: RobotOptions) -> Any:
    """The description parsed (URDF) or compiled (MJCF) at the options' configuration: a
    :class:`meshcol.io.urdf.UrdfRead` or :class:`meshcol.io.mjcf.MjcfRead`."""
    source = os.fspath(path)
    file = Path(source)
    if not file.exists():  # says which: not found, a link that dangles or loops
        check_input(source, "robot")
    if file.is_dir():
        raise InputFileError("is a directory, not a robot description", source)
    check_input(source, "robot")  # a regular file within the cap: never a pipe or a device
    kind = description_kind(source)
    if kind == "mjcf":
        check_mjcf_files(source)  # its includes and meshes, before MuJoCo opens them
    return _reader(kind)(source, options)


def _scene(
    read: Any, options: RobotOptions, visual: bool, elements: list[CollisionElement] | None
) -> Scene:
    """One scene of a read description (its collision or visual geometry), checked, with
    the exclusions of the reader and the SRDF."""
    source = read.source
    scene = read.scene(visual, elements)
    if not scene.bodies and not visual:
        scene = _without_colliders(scene, read.links, read.kinematics, source)
    for body in scene.bodies:
        _check_body(body, source)
    return _with_exclusions(scene, read.links, options.srdf)


#: The start of the warning a robot without collision geometry gets (rule MC506, whose
#: finding :func:`meshcol.analysis.rules.robot_findings` makes).
NO_COLLISION_GEOMETRY = "no link has collision geometry"


def _without_colliders(scene: Scene, links: set[str], kinematics: Any, source: str) -> Scene:
    """A robot whose links have no collision geometry (visual-only, as pybullet and MuJoCo
    load it): a scene of no bodies, with the warning that says so. A description with no
    link at all is broken, not empty (URDF: no ``<link>``, refused by its reader; MJCF: no
    body but the world and no geom)."""
    from meshcol.io.paths import display_path

    model = getattr(kinematics, "model", None)  # MJCF: MuJoCo's compiled model
    if model is not None and model.nbody <= 1 and model.ngeom == 0:
        raise SceneError("the model has no body and no geom", source)
    count = f"{len(links)} link(s), no <collision> element"
    if model is not None:
        count = f"{model.nbody - 1} body(ies), no geom that collides"
    warning = (
        f"{display_path(source)}: {NO_COLLISION_GEOMETRY} ({count}): nothing to check, "
        "and what is written of it has no collider (MC506 no-collision-geometry)"
    )
    return dataclasses.replace(scene, warnings=(*scene.warnings, warning))


def _check_body(body: Body, source: str) -> None:
    """A link's pose and world coordinates are finite and within the limit of every input."""
    from meshcol.io.mesh_read import MAX_COORDINATE, check_magnitude

    label = f"link {body.name!r}"
    primitive = body.primitive  # finite by construction: bounded without its tessellation
    if not np.all(np.isfinite(body.pose)) or (
        primitive is None and not np.all(np.isfinite(body.vertices))
    ):
        raise SceneError(f"{label}: pose or geometry is not finite (a NaN or inf origin?)", source)
    if primitive is not None and (
        primitive_reach(primitive) + float(np.abs(body.pose[:3, 3]).max()) <= MAX_COORDINATE
    ):
        return
    world = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
    try:
        check_magnitude(world, "world vertex", None)
    except MeshcolError as error:
        raise SceneError(f"{label}: {error.message}", source) from None


def _with_exclusions(scene: Scene, links: set[str], srdf: str | None) -> Scene:
    """The scene with its reader's exclusions and the SRDF's, each pair of bodies once
    (ordered by name, the first reason kept); an SRDF naming unknown links warns."""
    excluded = list(scene.excluded_pairs)
    warnings = list(scene.warnings)
    if srdf is not None:
        from meshcol.io.srdf import read_srdf

        srdf_pairs, unknown = read_srdf(srdf, links)
        excluded.extend(srdf_pairs)
        if unknown:
            warnings.append(
                f"{srdf}: <disable_collisions> names links the robot does not have, "
                f"ignored: {', '.join(repr(n) for n in unknown)}"
            )
    bodies = {body.name for body in scene.bodies}
    seen: set[tuple[str, str]] = set()
    kept = []
    for a, b, reason in excluded:
        key = (min(a, b), max(a, b))
        if a in bodies and b in bodies and a != b and key not in seen:
            seen.add(key)
            kept.append((key[0], key[1], reason))
    return dataclasses.replace(scene, excluded_pairs=tuple(kept), warnings=tuple(warnings))
