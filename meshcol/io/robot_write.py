"""Robot descriptions written back with rebuilt collision geometry (URDF, MJCF, GLB, USD).

The colliders come from :mod:`meshcol.analysis.rebuild` (hulls or convex decompositions of a
robot's collision elements); this module only writes them. Every collider mesh is in its
LINK frame (the element's ``<origin>`` and mesh scale baked into its vertices), one file per
part, ``OUT/<link>_NN.obj`` (:func:`meshcol.io.mesh_write.write_parts`), and the description
places it with an identity origin. Primitives (box, sphere, cylinder, capsule) are already
exact convex colliders: their elements are left as they are.

One module per output format, this one dispatching (:func:`write_robot`):

- ``urdf`` (URDF input): the input's tree edited in place (:mod:`meshcol.io.urdf_write`);
- ``mjcf``: MuJoCo's model editor, in MuJoCo Menagerie's convention (:mod:`meshcol.io.mjcf_write`);
- ``glb``: one node per collider part (``<link>_NN``, primitives tessellated as
  ``<link>_<kind><element>``), in the world frame at the scene's joint configuration (here),
  under a root node that turns the robot's Z-up world into glTF's Y-up frame
  (:func:`meshcol.io.mesh_write.glb_bytes`, ``z_up``);
- ``usd``: one ``Xform`` per link, one collision prim per part (:mod:`meshcol.io.usd_write`).

Everything goes through :func:`meshcol.io.outputs.staged_folder`: the files of one run appear
together or not at all, and the MJCF is compiled by MuJoCo before anything is moved in place.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from meshcol.errors import SceneError
from meshcol.io.mjcf_write import mjcf_text
from meshcol.io.packages import resolve_mesh_reference
from meshcol.io.urdf_write import parse_xml, urdf_text
from meshcol.io.usd_write import require_usd, write_usd
from meshcol.types import Primitive

__all__ = [
    "OUTPUT_FORMATS",
    "Collider",
    "RobotColliders",
    "description_path",
    "output_warnings",
    "write_robot",
]

#: What ``--to`` accepts.
OUTPUT_FORMATS = ("urdf", "mjcf", "glb", "usd")

_EXTENSION = {"urdf": ".urdf", "mjcf": ".xml", "glb": ".glb", "usd": ".usda"}


@dataclass(frozen=True, eq=False)
class Collider:
    """The rebuilt geometry of one collision element.

    Attributes
    ----------
    link : str
        The link (URDF) or body (MJCF) it belongs to.
    index : int
        URDF: position among the link's ``<collision>`` elements; MJCF: the geom id.
    parts : tuple of ((n, 3) float64, (m, 3) int64)
        Convex parts in the LINK frame (one for a hull); empty for a kept primitive.
    primitive : Primitive or None
        A primitive: the element's own, kept as it is, or (``fitted``) one that replaces it.
    origin : (4, 4) float64
        The element's frame in the link frame (where the primitive sits).
    name : str
        The element's name (URDF ``name``, MJCF geom name), or ``""``.
    fitted : bool
        ``primitive`` is new (``meshcol fit``): the element's geometry becomes it, at
        ``origin``.
    """

    link: str
    index: int
    parts: tuple[tuple[np.ndarray, np.ndarray], ...]
    primitive: Primitive | None = None
    origin: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = ""
    fitted: bool = False

    @property
    def kept(self) -> bool:
        """The element is written back as it was read (a primitive of the input)."""
        return self.primitive is not None and not self.fitted


@dataclass(frozen=True, eq=False)
class RobotColliders:
    """A robot description and the colliders that replace its collision elements.

    Attributes
    ----------
    source : str
        The URDF or MJCF file.
    kind : {"urdf", "mjcf"}
        What ``source`` is.
    colliders : tuple of Collider
        In link order, then element order.
    link_poses : dict of str to (4, 4) float64
        World pose of each link with a collider, at the scene's joint configuration.
    package_paths : dict of str to str
        ``package://`` folders the description was read with (visual meshes of a URDF
        converted to MJCF are found through them).
    excluded_pairs : tuple of (str, str, str)
        The link pairs meshcol leaves out of self-collision (adjacent links, an SRDF's
        pairs, the MJCF's own filters; :attr:`meshcol.types.Scene.excluded_pairs`): an MJCF
        written gets a ``<contact><exclude>`` for each pair MuJoCo would not filter itself.
    warnings : tuple of str
        What reading the description warned of (:attr:`meshcol.types.Scene.warnings`: a
        robot with no collision geometry, MC506; xacro leftovers ...).
    """

    source: str
    kind: str
    colliders: tuple[Collider, ...]
    link_poses: dict[str, np.ndarray]
    package_paths: dict[str, str] = field(default_factory=dict)
    excluded_pairs: tuple[tuple[str, str, str], ...] = ()
    warnings: tuple[str, ...] = ()


def output_warnings(robot: RobotColliders, to: str) -> list[str]:
    """What the user of the description written in format ``to`` must know, one line each:
    the reading's warnings, then (URDF or MJCF written from a URDF) each visual whose mesh
    file is missing, which the description leaves out (:func:`meshcol.io.urdf_write.missing_visuals`)."""
    from meshcol.io.urdf_write import missing_visuals

    warnings = list(robot.warnings)
    if robot.kind == "urdf" and to in ("urdf", "mjcf"):
        written = "URDF" if to == "urdf" else "MJCF"
        warnings += [
            f"link {link!r}: visual mesh {reference!r} left out of the {written} written ({why})"
            for link, reference, why in missing_visuals(robot)
        ]
    return warnings


def description_path(
    source: str | os.PathLike[str], out_dir: str | os.PathLike[str], to: str
) -> str:
    """``OUT/<input stem>.<urdf|xml|glb|usda>``: where :func:`write_robot` puts the description."""
    if to not in OUTPUT_FORMATS:
        raise ValueError(f"unknown output format {to!r} (expected {', '.join(OUTPUT_FORMATS)})")
    return os.path.join(os.fspath(out_dir), Path(os.fspath(source)).stem + _EXTENSION[to])


def part_files(robot: RobotColliders) -> dict[int, list[str]]:
    """File name (in the output folder) of each part, by position of its collider in
    ``robot.colliders``: ``<link>_NN.obj``, numbered over the link's parts."""
    from meshcol.io.mesh_write import part_names, safe_name

    files: dict[int, list[str]] = {}
    by_link: dict[str, list[int]] = {}
    for i, c in enumerate(robot.colliders):
        if c.primitive is None:
            by_link.setdefault(c.link, []).append(i)
    owners: dict[str, str] = {}
    for link, members in by_link.items():
        safe = safe_name(link)
        if safe.lower() in owners:
            raise SceneError(
                f"links {owners[safe.lower()]!r} and {link!r} would write the same files "
                f"({safe}_NN.obj): rename one",
                robot.source,
            )
        owners[safe.lower()] = link
        count = sum(len(robot.colliders[i].parts) for i in members)
        names = iter(part_names(safe, count))
        for i in members:
            files[i] = [f"{next(names)}.obj" for _ in robot.colliders[i].parts]
    return files


def write_robot(
    robot: RobotColliders,
    out_dir: str | os.PathLike[str],
    to: str | None = None,
    protected: Sequence[tuple[str, str]] = (),
    urdf_capsules: str = "standard",
) -> list[str]:
    """Write the colliders and the description that uses them into ``out_dir``.

    Parameters
    ----------
    robot : RobotColliders
    out_dir : path
        Created if missing; the run's files appear in it together or not at all.
    to : {"urdf", "mjcf", "glb", "usd"}, optional
        Output format; default the input's (``urdf`` or ``mjcf``).
    protected : sequence of (description, path)
        Files that must not be replaced (the input and the meshes it references are always).
    urdf_capsules : {"standard", "extension"}
        How a URDF written holds a capsule (:data:`meshcol.vocabulary.URDF_CAPSULES`):
        a cylinder and two spheres, or the ``<capsule>`` element
        (:func:`meshcol.io.urdf_write.urdf_text`).

    Returns
    -------
    list of str
        The paths written: the description first, then the part meshes.

    Raises
    ------
    SceneError
        MJCF output from an MJCF/URDF that MuJoCo rejects once rebuilt (MuJoCo's message),
        URDF output from an MJCF input.
    MissingDependencyError
        ``mujoco`` (MJCF), ``lxml`` (URDF) or ``usd-core`` (USD) is not installed.
    OutputPathError
        An output would replace an input or a ``protected`` file (nothing is written).
    """
    from meshcol.io.mesh_write import write_meshes
    from meshcol.io.outputs import check_destinations, staged_folder
    from meshcol.io.report import atomic_write

    to = to or robot.kind
    if to == "urdf" and robot.kind != "urdf":
        raise SceneError("--to urdf needs a URDF input (MJCF to URDF is not written)", robot.source)
    if to == "usd":
        require_usd(robot.source)
    out_dir = os.fspath(out_dir)
    description = description_path(robot.source, out_dir, to)
    files = part_files(robot) if to in ("urdf", "mjcf") else {}
    planned = [("the description", description)] + [
        ("a collider mesh", os.path.join(out_dir, name))
        for names in files.values()
        for name in names
    ]
    inputs = [("the input", robot.source), *_referenced_files(robot), *protected]
    check_destinations(inputs, planned)

    with staged_folder(out_dir) as stage:
        target = os.path.join(stage, os.path.basename(description))
        for i, names in files.items():
            c = robot.colliders[i]
            for name, (vertices, faces) in zip(names, c.parts):
                write_meshes(os.path.join(stage, name), [(Path(name).stem, vertices, faces)])
        if to == "urdf":
            atomic_write(target, urdf_text(robot, files, {}, out_dir, capsules=urdf_capsules))
        elif to == "mjcf":
            atomic_write(target, mjcf_text(robot, files, stage, out_dir))
        elif to == "glb":
            write_meshes(target, _world_meshes(robot), z_up=True)
        else:
            write_usd(robot, part_labels(robot), target)
        written = sorted(os.listdir(stage))
    first = os.path.basename(description)
    return [description] + [os.path.join(out_dir, n) for n in written if n != first]


def _referenced_files(robot: RobotColliders) -> list[tuple[str, str]]:
    """Every mesh file the description names (URDF visual and collision meshes), resolved."""
    if robot.kind != "urdf":
        return []
    out = []
    for element in parse_xml(robot.source).getroot().iter("mesh"):
        reference = element.get("filename")
        if reference:
            path = resolve_mesh_reference(robot.source, reference, robot.package_paths)
            if path is not None:
                out.append((f"a mesh of {robot.source}", path))
    return out


# --- GLB --------------------------------------------------------------------------------------


def _primitive_label(collider: Collider) -> str:
    from meshcol.io.mesh_write import safe_name

    assert collider.primitive is not None
    return f"{safe_name(collider.link)}_{type(collider.primitive).__name__.lower()}{collider.index}"


def part_labels(robot: RobotColliders) -> list[list[str]]:
    """Node names of each collider's parts: ``<link>_NN`` (as the part files), primitives
    ``<link>_<kind><element>``."""
    files = part_files(robot)
    return [
        [_primitive_label(c)] if c.primitive is not None else [Path(n).stem for n in files[i]]
        for i, c in enumerate(robot.colliders)
    ]


def _world_meshes(robot: RobotColliders) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Every part (primitives tessellated) in the world frame, named as :func:`part_labels`."""
    from meshcol.io.primitives import primitive_mesh

    out = []
    for collider, labels in zip(robot.colliders, part_labels(robot)):
        pose = robot.link_poses[collider.link]
        if collider.primitive is not None:
            v, f = primitive_mesh(collider.primitive)
            meshes = [(v @ collider.origin[:3, :3].T + collider.origin[:3, 3], f)]
        else:
            meshes = list(collider.parts)
        for label, (v, f) in zip(labels, meshes):
            out.append((label, v @ pose[:3, :3].T + pose[:3, 3], f))
    return out
