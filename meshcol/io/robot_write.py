"""Robot descriptions written back with rebuilt collision geometry (URDF, MJCF, GLB, USD).

The colliders come from :mod:`meshcol.analysis.rebuild` (hulls or convex decompositions of a
robot's collision elements); this module only writes them. Every collider mesh is in its
LINK frame (the element's ``<origin>`` and mesh scale baked into its vertices), one file per
part, ``OUT/<link>_NN.obj`` (:func:`meshcol.io.mesh_write.write_parts`), and the description
places it with an identity origin. Primitives (box, sphere, cylinder, capsule) are already
exact convex colliders: their elements are left as they are.

- ``urdf`` (URDF input): the input's XML tree is edited in place (lxml), so visual elements,
  inertials, joints, comments and unknown tags survive: each rebuilt ``<collision>`` keeps its
  name and attributes, loses its ``<origin>``, and its geometry becomes
  ``<mesh filename="<link>_NN.obj"/>`` (a decomposition of several parts repeats the element,
  ``NAME_NN``, once per part).
- ``mjcf``: MuJoCo's own model editor (``mujoco.MjSpec``) writes ``OUT/ROBOT.xml`` in the
  convention of MuJoCo Menagerie: visual geoms in group 2 with ``contype="0"
  conaffinity="0"``, collision geoms in group 3, one mesh asset per part. An MJCF input is
  edited as MuJoCo read it (defaults, classes and includes resolved by MuJoCo; comments do
  not survive MuJoCo's writer). A URDF input is first rewritten as above and then compiled by
  MuJoCo's URDF importer (bodies, joints, limits, inertials and mimic joints as MuJoCo reads
  them, ``fusestatic`` off so that every link stays a body); visual meshes MuJoCo cannot read
  (COLLADA) are converted to ``OUT/visual_<name>.obj``.
- ``glb``: one node per collider part (``<link>_NN``, primitives tessellated as
  ``<link>_<kind><element>``), in the world frame at the scene's joint configuration.
- ``usd``: ``usd-core`` (``pip install 'meshcol[usd]'``): one ``Xform`` per link with its world
  pose at the configuration; one ``Mesh`` per part with ``UsdPhysics.CollisionAPI`` and
  ``UsdPhysics.MeshCollisionAPI`` (approximation ``convexHull``: every part is convex), and
  primitives as ``Cube``/``Sphere``/``Cylinder``/``Capsule`` prims with ``CollisionAPI``.

Everything goes through :func:`meshcol.io.outputs.staged_folder`: the files of one run appear
together or not at all, and the MJCF is compiled by MuJoCo before anything is moved in place.
"""

from __future__ import annotations

import copy
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import MeshcolError, MissingDependencyError, SceneError
from meshcol.types import Box, Capsule, Cylinder, Primitive, Sphere

__all__ = [
    "OUTPUT_FORMATS",
    "Collider",
    "RobotColliders",
    "description_path",
    "write_robot",
]

#: What ``--to`` accepts.
OUTPUT_FORMATS = ("urdf", "mjcf", "glb", "usd")

_EXTENSION = {"urdf": ".urdf", "mjcf": ".xml", "glb": ".glb", "usd": ".usda"}

#: Mesh formats MuJoCo reads itself; other visual meshes are converted to OBJ.
_MUJOCO_MESH_FORMATS = (".stl", ".obj", ".msh")

#: Geom attributes a part's extra geoms take from the geom they replace (MJCF).
_GEOM_ATTRIBUTES = (
    "classname",
    "contype",
    "conaffinity",
    "condim",
    "friction",
    "solref",
    "solimp",
    "solmix",
    "margin",
    "gap",
    "priority",
    "rgba",
    "material",
    "density",
    "group",
)


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
    """

    source: str
    kind: str
    colliders: tuple[Collider, ...]
    link_poses: dict[str, np.ndarray]
    package_paths: dict[str, str] = field(default_factory=dict)


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
        _require_usd(robot.source)
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
            atomic_write(target, _urdf_text(robot, files, {}, out_dir))
        elif to == "mjcf":
            atomic_write(target, _mjcf_text(robot, files, stage, out_dir))
        elif to == "glb":
            write_meshes(target, _world_meshes(robot))
        else:
            _write_usd(robot, target)
        written = sorted(os.listdir(stage))
    first = os.path.basename(description)
    return [description] + [os.path.join(out_dir, n) for n in written if n != first]


def _require_usd(source: str) -> None:
    try:
        import pxr  # noqa: F401
    except ImportError:
        raise MissingDependencyError(
            "--to usd needs usd-core (pip install 'meshcol[usd]')", source
        ) from None


def _referenced_files(robot: RobotColliders) -> list[tuple[str, str]]:
    """Every mesh file the description names (URDF visual and collision meshes), resolved."""
    if robot.kind != "urdf":
        return []
    from meshcol.io.packages import resolve_mesh_reference

    out = []
    for element in _parse_xml(robot.source).getroot().iter("mesh"):
        reference = element.get("filename")
        if reference:
            path = resolve_mesh_reference(robot.source, reference, robot.package_paths)
            if path is not None:
                out.append((f"a mesh of {robot.source}", path))
    return out


def _parse_xml(source: str) -> Any:
    try:
        from lxml import etree
    except ImportError:
        raise MissingDependencyError(
            "writing URDF needs lxml (pip install 'meshcol[robots]')", source
        ) from None
    try:
        return etree.parse(source, etree.XMLParser(resolve_entities=False))
    except (etree.XMLSyntaxError, OSError) as exc:
        raise SceneError(f"cannot read the XML: {' '.join(str(exc).split())}", source) from None


# --- URDF -----------------------------------------------------------------------------------


def _urdf_text(
    robot: RobotColliders,
    files: dict[int, list[str]],
    prefix: dict[str, str],
    out_dir: str | None = None,
) -> str:
    """The input URDF with each rebuilt ``<collision>`` pointing at its part files
    (``prefix``: folder prepended to the part file names, for MuJoCo's importer). With
    ``out_dir``, the other relative mesh references (visuals) are made relative to it, so that
    they still name the input's files; ``package://`` and absolute references stay as written."""
    from lxml import etree

    tree = _parse_xml(robot.source)
    root = tree.getroot()
    if out_dir is not None:
        folder = os.path.dirname(os.path.abspath(robot.source))
        for mesh in root.iter("mesh"):
            reference = mesh.get("filename") or ""
            if reference and "://" not in reference and not os.path.isabs(reference):
                moved = os.path.relpath(os.path.join(folder, reference), os.path.abspath(out_dir))
                mesh.set("filename", Path(moved).as_posix())
    links = {link.get("name"): link for link in root.findall("link")}
    for i, collider in enumerate(robot.colliders):
        if collider.kept:
            continue
        link = links.get(collider.link)
        elements = link.findall("collision") if link is not None else []
        if collider.index >= len(elements):
            raise SceneError(
                f"link {collider.link!r}: collision {collider.index} is not in the file",
                robot.source,
            )
        element = elements[collider.index]
        if collider.fitted:
            _urdf_primitive(element, collider)
            continue
        name = element.get("name")
        names = files[i]
        previous = element
        for k, file in enumerate(names):
            target = element if k == 0 else copy.deepcopy(element)
            if k > 0:
                previous.addnext(target)
            previous = target
            if name and len(names) > 1:
                target.set("name", f"{name}_{k:02d}")
            geometry, tail = _cleared(target)
            mesh = etree.SubElement(geometry, "mesh")
            mesh.set("filename", prefix.get("collider", "") + file)
            mesh.tail = tail  # the indentation of the shape it replaces
    # The root's siblings (comments, processing instructions) on lines of their own, as read.
    siblings = [
        *reversed(list(root.itersiblings(preceding=True))),
        root,
        *root.itersiblings(),
    ]
    body = "\n".join(etree.tostring(e, encoding="unicode", with_tail=False) for e in siblings)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + body + "\n"


def _cleared(element: Any) -> tuple[Any, str | None]:
    """A ``<collision>`` element without its ``<origin>`` and shapes (comments stay): its
    ``<geometry>`` (made when missing) and the indentation the first shape had."""
    from lxml import etree

    for origin in element.findall("origin"):
        element.remove(origin)
    geometry = element.find("geometry")
    if geometry is None:
        geometry = etree.SubElement(element, "geometry")
    tail = None
    for child in list(geometry):
        if isinstance(child.tag, str):  # shapes go; comments stay
            tail = child.tail if tail is None else tail
            geometry.remove(child)
    return geometry, tail


def _format(values: Any) -> str:
    """Numbers as written in a URDF attribute: shortest round-trip text, rounding noise
    below 1e-15 (and -0) written as 0."""
    return " ".join(repr(float(v)) if abs(float(v)) >= 1e-15 else "0" for v in values)


def _urdf_primitive(element: Any, collider: Collider) -> None:
    """Make a ``<collision>`` element the fitted primitive at the collider's origin."""
    from lxml import etree

    from meshcol.geometry.rotations import rpy_from_matrix

    geometry, tail = _cleared(element)
    origin = etree.Element("origin")
    origin.set("xyz", _format(collider.origin[:3, 3]))
    origin.set("rpy", _format(rpy_from_matrix(collider.origin[:3, :3])))
    before = geometry.getprevious()
    origin.tail = before.tail if before is not None else element.text
    geometry.addprevious(origin)
    p = collider.primitive
    if isinstance(p, Box):
        shape = etree.SubElement(geometry, "box", size=_format(p.size))
    elif isinstance(p, Sphere):
        shape = etree.SubElement(geometry, "sphere", radius=_format([p.radius]))
    elif isinstance(p, Cylinder):
        shape = etree.SubElement(
            geometry, "cylinder", radius=_format([p.radius]), length=_format([p.length])
        )
    else:  # URDF has no capsule; this is the element MuJoCo's importer and meshcol read
        assert isinstance(p, Capsule)
        shape = etree.SubElement(
            geometry, "capsule", radius=_format([p.radius]), length=_format([p.length])
        )
    shape.tail = tail


# --- MJCF -----------------------------------------------------------------------------------


def _mujoco(source: str) -> Any:
    try:
        import mujoco
    except ImportError:
        raise MissingDependencyError(
            "writing MJCF needs mujoco (pip install 'meshcol[robots]')", source
        ) from None
    return mujoco


def _mjcf_text(robot: RobotColliders, files: dict[int, list[str]], stage: str, out_dir: str) -> str:
    """``OUT/ROBOT.xml`` in the Menagerie convention, compiled by MuJoCo before it is returned."""
    mujoco = _mujoco(robot.source)
    out_abs = os.path.abspath(out_dir)
    stage_abs = os.path.abspath(stage)
    new_assets: set[str] = set()
    exact: list[Any] = []  # fitted primitive geoms, written at full precision below
    if robot.kind == "urdf":
        spec = _spec_from_urdf(mujoco, robot, files, stage_abs)
        exact = _imported_primitives(mujoco, spec, robot)
        for geom in spec.geoms:
            if geom.contype == 0 and geom.conaffinity == 0:
                geom.group = 2  # MuJoCo's importer puts URDF visuals in group 1
            else:
                geom.group = 3
        new_assets = {Path(n).stem for names in files.values() for n in names}
    else:
        spec = _spec(mujoco, robot.source, lambda: mujoco.MjSpec.from_file(robot.source))
        _compile(mujoco, spec, robot.source)
        geoms = {geom.id: geom for geom in spec.geoms}
        rebuilt = [geoms[c.index] for c in robot.colliders if not c.kept]
        in_frame = _frame_inverses(mujoco, spec, robot.source, rebuilt)
        mesh_names = {m.name for m in spec.meshes}
        for i, collider in enumerate(robot.colliders):
            geom = geoms[collider.index]
            geom.group = 3
            if collider.kept:
                continue
            if collider.fitted:
                _mjcf_primitive(mujoco, geom, collider, in_frame.get(id(geom)))
                exact.append(geom)
                continue
            extra_mass = geom.mass / len(files[i]) if not np.isnan(geom.mass) else None
            for k, file in enumerate(files[i]):
                name = Path(file).stem
                while name in mesh_names:
                    name += "_"
                mesh_names.add(name)
                new_assets.add(name)
                spec.add_mesh(name=name, file=os.path.join(stage_abs, file))
                target = geom if k == 0 else geom.parent.add_geom()
                if k > 0:
                    for attribute in _GEOM_ATTRIBUTES:
                        setattr(target, attribute, getattr(geom, attribute))
                    if geom.name:
                        target.name = f"{geom.name}_{k:02d}"
                if extra_mass is not None:
                    target.mass = extra_mass
                target.type = mujoco.mjtGeom.mjGEOM_MESH
                target.meshname = name
                # The parts are in the body frame: no offset, no orientation of any kind
                # (an euler/axisangle/xyaxes/zaxis attribute overrides quat in MuJoCo).
                # A geom inside <frame> elements gets the inverse of their pose.
                pos, quat = in_frame.get(id(target), ([0.0] * 3, [1.0, 0.0, 0.0, 0.0]))
                target.pos = pos
                target.quat = quat
                target.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
                target.fromto = [np.nan] * 6
            if geom.name and len(files[i]) > 1:
                geom.name = f"{geom.name}_00"
        for geom in spec.geoms:
            if geom.contype == 0 and geom.conaffinity == 0:
                geom.group = 2
        used = {geom.meshname for geom in spec.geoms if geom.meshname}
        for mesh in list(spec.meshes):
            if mesh.name not in used and mesh.name not in new_assets:
                spec.delete(mesh)  # a collision mesh no geom uses any more
    # Files by absolute path for MuJoCo's check and writer, then relative to OUT in the text.
    _absolute_asset_files(spec, robot.source if robot.kind == "mjcf" else None)
    spec.meshdir = ""
    spec.texturedir = ""
    _compile(mujoco, spec, robot.source)
    markers = _mark(mujoco, spec, exact)
    try:
        text = spec.to_xml()
    except Exception as exc:  # noqa: BLE001 - as _spec
        raise SceneError(
            f"MuJoCo cannot write the rebuilt model: {' '.join(str(exc).split())}", robot.source
        ) from None
    return _relative_files(_exact_geoms(text, markers), stage_abs, out_abs)


def _imported_primitives(mujoco: Any, spec: Any, robot: RobotColliders) -> list[Any]:
    """The geoms MuJoCo's URDF importer made of the fitted primitives: on the link's body, of
    the primitive's type, size and position (the URDF carries them at full precision)."""
    types = {
        Box: mujoco.mjtGeom.mjGEOM_BOX,
        Sphere: mujoco.mjtGeom.mjGEOM_SPHERE,
        Cylinder: mujoco.mjtGeom.mjGEOM_CYLINDER,
        Capsule: mujoco.mjtGeom.mjGEOM_CAPSULE,
    }
    found, taken = [], set()
    for collider in robot.colliders:
        if not collider.fitted:
            continue
        want = types[type(collider.primitive)]
        for geom in spec.geoms:
            if (
                id(geom) not in taken
                and geom.type == want
                and geom.parent.name == collider.link
                and np.allclose(geom.pos, collider.origin[:3, 3], rtol=0, atol=1e-12)
            ):
                taken.add(id(geom))
                found.append(geom)
                break
    return found


def _mark(mujoco: Any, spec: Any, geoms: list[Any]) -> dict[str, tuple[bool, dict[str, str]]]:
    """Name each geom uniquely (its own name, or a marker that :func:`_exact_geoms` removes)
    and keep its size, pos and quat at full precision: MuJoCo writes numbers with 6
    significant digits, which can shrink a fitted primitive below what it must enclose."""
    taken = {g.name for g in spec.geoms if g.name}
    used = {mujoco.mjtGeom.mjGEOM_SPHERE: 1, mujoco.mjtGeom.mjGEOM_BOX: 3}
    markers: dict[str, tuple[bool, dict[str, str]]] = {}
    for k, geom in enumerate(geoms):
        own = bool(geom.name)
        if not own:
            name = f"meshcol_fit_{k}"
            while name in taken:
                name += "_"
            geom.name = name
            taken.add(name)
        size = np.asarray(geom.size, dtype=np.float64)[: used.get(geom.type, 2)]
        values = {"size": size, "pos": geom.pos, "quat": geom.quat}
        markers[geom.name] = (own, {key: _format(v) for key, v in values.items()})
    return markers


def _exact_geoms(text: str, markers: dict[str, tuple[bool, dict[str, str]]]) -> str:
    """MuJoCo's XML with the marked geoms' numbers as :func:`_mark` kept them."""
    if not markers:
        return text
    from lxml import etree

    root = etree.fromstring(text.encode("utf-8"))
    for geom in root.iter("geom"):
        entry = markers.get(geom.get("name") or "")
        if entry is None:
            continue
        own, attributes = entry
        for key, value in attributes.items():
            geom.set(key, value)
        for key in ("euler", "axisangle", "xyaxes", "zaxis", "fromto"):
            geom.attrib.pop(key, None)
        if not own:
            del geom.attrib["name"]
    return etree.tostring(root, encoding="unicode") + "\n"


def _mjcf_primitive(
    mujoco: Any, geom: Any, collider: Collider, frame: tuple[list[float], list[float]] | None
) -> None:
    """Make a geom the fitted primitive at the collider's origin (body frame; ``frame``: the
    (pos, quat) that cancels the ``<frame>`` elements around the geom)."""
    from meshcol.geometry.rotations import quaternion_from_matrix

    p = collider.primitive
    if isinstance(p, Box):
        geom.type = mujoco.mjtGeom.mjGEOM_BOX
        geom.size = [s / 2.0 for s in p.size]
    elif isinstance(p, Sphere):
        geom.type = mujoco.mjtGeom.mjGEOM_SPHERE
        geom.size = [p.radius, 0.0, 0.0]
    elif isinstance(p, Cylinder):
        geom.type = mujoco.mjtGeom.mjGEOM_CYLINDER
        geom.size = [p.radius, p.length / 2.0, 0.0]
    else:
        assert isinstance(p, Capsule)
        geom.type = mujoco.mjtGeom.mjGEOM_CAPSULE
        geom.size = [p.radius, p.length / 2.0, 0.0]
    geom.meshname = ""
    pos = np.asarray(collider.origin[:3, 3], dtype=np.float64)
    quat = np.asarray(quaternion_from_matrix(collider.origin[:3, :3]), dtype=np.float64)
    if frame is not None:  # the frames' inverse, then the fit: inverse * origin
        frame_pos, frame_quat = (np.asarray(v, dtype=np.float64) for v in frame)
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, frame_quat)
        pos = rotation.reshape(3, 3) @ pos + frame_pos
        composed = np.zeros(4)
        mujoco.mju_mulQuat(composed, frame_quat, quat)
        quat = composed
    geom.pos = pos.tolist()
    geom.quat = quat.tolist()
    geom.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    geom.fromto = [np.nan] * 6


def _relative_files(text: str, stage: str, out_dir: str) -> str:
    """MuJoCo's XML with every asset file relative to the output folder (the stage's files
    by name: they move into it)."""
    from lxml import etree

    root = etree.fromstring(text.encode("utf-8"))
    for element in root.iter("mesh", "hfield", "texture", "skin"):
        file = element.get("file")
        if not file or not os.path.isabs(file):
            continue
        if os.path.dirname(file) == stage:
            element.set("file", os.path.basename(file))
        else:
            element.set("file", Path(os.path.relpath(file, out_dir)).as_posix())
    return etree.tostring(root, encoding="unicode") + "\n"


def _frame_inverses(
    mujoco: Any, spec: Any, source: str, geoms: list[Any]
) -> dict[int, tuple[list[float], list[float]]]:
    """For each geom placed inside ``<frame>`` elements, the (pos, quat) that cancels the
    frames' pose in the body frame, keyed by ``id(geom)``: a probe sphere at the frame's
    origin is compiled, and its compiled pose is the frames' pose (what MuJoCo makes of
    nested frames and their orientation attributes)."""
    framed = [g for g in geoms if g.frame is not None]
    if not framed:
        return {}
    probes = []
    for geom in framed:
        probe = geom.parent.add_geom()
        probe.type = mujoco.mjtGeom.mjGEOM_SPHERE
        probe.size = [1.0, 0.0, 0.0]
        probe.contype = probe.conaffinity = 0
        probe.set_frame(geom.frame)
        probes.append(probe)
    model = _compile(mujoco, spec, source)
    out: dict[int, tuple[list[float], list[float]]] = {}
    for geom, probe in zip(framed, probes):
        pos = np.array(model.geom_pos[probe.id], dtype=np.float64)
        quat = np.array(model.geom_quat[probe.id], dtype=np.float64)
        conjugate = quat * np.array([1.0, -1.0, -1.0, -1.0])
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, quat)
        inverse_pos = -(rotation.reshape(3, 3).T @ pos)
        out[id(geom)] = (inverse_pos.tolist(), conjugate.tolist())
    for probe in probes:
        spec.delete(probe)
    return out


def _spec(mujoco: Any, source: str, make: Any) -> Any:
    try:
        return make()
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others; its words
        raise SceneError(f"MuJoCo rejects it: {' '.join(str(exc).split())}", source) from None


def _compile(mujoco: Any, spec: Any, source: str) -> Any:
    try:
        return spec.compile()
    except Exception as exc:  # noqa: BLE001 - as _spec
        raise SceneError(
            f"MuJoCo rejects the rebuilt model: {' '.join(str(exc).split())}", source
        ) from None


def _absolute_asset_files(spec: Any, mjcf: str | None) -> None:
    """Each mesh, height field and texture file by its absolute path."""
    base = spec.modelfiledir or (os.path.dirname(os.path.abspath(mjcf)) if mjcf else "")
    for assets, folder in (
        (spec.meshes, spec.meshdir),
        (spec.hfields, spec.meshdir),
        (spec.textures, spec.texturedir),
    ):
        for asset in assets:
            file = getattr(asset, "file", "")
            if not file:
                continue
            path = file if os.path.isabs(file) else os.path.join(base, folder or "", file)
            asset.file = os.path.abspath(path)


def _spec_from_urdf(
    mujoco: Any, robot: RobotColliders, files: dict[int, list[str]], stage: str
) -> Any:
    """MuJoCo's URDF importer on the rebuilt URDF: every mesh by absolute path, COLLADA and
    other visual meshes MuJoCo does not read converted to OBJ in the stage."""
    from lxml import etree

    from meshcol.io.packages import resolve_mesh_reference

    text = _urdf_text(robot, files, {"collider": stage + os.sep})
    root = etree.fromstring(text.encode("utf-8"))
    converted: dict[str, str] = {}
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            for mesh in visual.iter("mesh"):
                reference = mesh.get("filename") or ""
                path = resolve_mesh_reference(robot.source, reference, robot.package_paths)
                if path is None or not os.path.isfile(path):
                    raise SceneError(
                        f"link {link.get('name')!r}: visual mesh {reference!r} not found",
                        robot.source,
                    )
                if Path(path).suffix.lower() not in _MUJOCO_MESH_FORMATS:
                    path = converted.get(path) or _convert_visual(path, stage, converted, robot)
                mesh.set("filename", path)
    extension = root.find("mujoco")
    if extension is None:
        extension = etree.SubElement(root, "mujoco")
    compiler = extension.find("compiler")
    if compiler is None:
        compiler = etree.SubElement(extension, "compiler")
    # Keep visuals, every link a body, file paths as written.
    compiler.set("discardvisual", "false")
    compiler.set("fusestatic", "false")
    compiler.set("strippath", "false")
    xml = etree.tostring(root, encoding="unicode")
    return _spec(mujoco, robot.source, lambda: mujoco.MjSpec.from_string(xml))


def _convert_visual(path: str, stage: str, converted: dict[str, str], robot: RobotColliders) -> str:
    """A visual mesh MuJoCo cannot read, as one OBJ in the stage (``visual_<stem>.obj``)."""
    from meshcol.io.mesh_read import load_mesh
    from meshcol.io.mesh_write import safe_name, write_meshes

    try:
        bodies = load_mesh(path, collada=True)
    except MeshcolError as error:
        raise SceneError(f"visual mesh {path}: {error.message}", robot.source) from None
    vertices, faces, base = [], [], 0
    for body in bodies:
        vertices.append(body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3])
        faces.append(body.faces + base)
        base += len(body.vertices)
    stem = f"visual_{safe_name(Path(path).stem)}"
    name, k = stem, 2
    taken = {os.path.basename(p) for p in converted.values()}
    while f"{name}.obj" in taken:
        name, k = f"{stem}-{k}", k + 1
    target = os.path.join(stage, f"{name}.obj")
    write_meshes(target, [(name, np.concatenate(vertices), np.concatenate(faces))])
    converted[path] = target
    return target


# --- GLB and USD ----------------------------------------------------------------------------


def _primitive_label(collider: Collider) -> str:
    from meshcol.io.mesh_write import safe_name

    assert collider.primitive is not None
    return f"{safe_name(collider.link)}_{type(collider.primitive).__name__.lower()}{collider.index}"


def _part_labels(robot: RobotColliders) -> list[list[str]]:
    """Node names of each collider's parts: ``<link>_NN`` (as the part files), primitives
    ``<link>_<kind><element>``."""
    files = part_files(robot)
    return [
        [_primitive_label(c)] if c.primitive is not None else [Path(n).stem for n in files[i]]
        for i, c in enumerate(robot.colliders)
    ]


def _world_meshes(robot: RobotColliders) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Every part (primitives tessellated) in the world frame, named as :func:`_part_labels`."""
    from meshcol.io.primitives import primitive_mesh

    out = []
    for collider, labels in zip(robot.colliders, _part_labels(robot)):
        pose = robot.link_poses[collider.link]
        if collider.primitive is not None:
            v, f = primitive_mesh(collider.primitive)
            meshes = [(v @ collider.origin[:3, :3].T + collider.origin[:3, 3], f)]
        else:
            meshes = list(collider.parts)
        for label, (v, f) in zip(labels, meshes):
            out.append((label, v @ pose[:3, :3].T + pose[:3, 3], f))
    return out


def _usd_name(name: str) -> str:
    """A valid USD prim name: letters, digits and ``_``, not starting with a digit."""
    cleaned = re.sub(r"\W", "_", name, flags=re.ASCII) or "_"
    return "_" + cleaned if cleaned[0].isdigit() else cleaned


def _write_usd(robot: RobotColliders, path: str) -> None:
    """One Xform per link (world pose), one collision prim per part, as a ``.usda`` file."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    from meshcol.io.report import atomic_path

    with atomic_path(path) as tmp:
        stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        root = UsdGeom.Xform.Define(stage, Sdf.Path("/" + _usd_name(Path(robot.source).stem)))
        stage.SetDefaultPrim(root.GetPrim())
        links: dict[str, Any] = {}
        for collider, labels in zip(robot.colliders, _part_labels(robot)):
            xform = links.get(collider.link)
            if xform is None:
                xform = UsdGeom.Xform.Define(
                    stage, root.GetPath().AppendChild(_unique(links, _usd_name(collider.link)))
                )
                xform.AddTransformOp().Set(_usd_matrix(Gf, robot.link_poses[collider.link]))
                xform.GetPrim().SetCustomDataByKey("meshcol:link", collider.link)
                links[collider.link] = xform
            parent = xform.GetPath()
            if collider.primitive is not None:
                prim = _usd_primitive(stage, UsdGeom, Gf, parent.AppendChild(labels[0]), collider)
                UsdPhysics.CollisionAPI.Apply(prim)
                continue
            for label, (v, f) in zip(labels, collider.parts):
                mesh = UsdGeom.Mesh.Define(stage, parent.AppendChild(_usd_name(label)))
                mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in np.asarray(v, dtype=float).tolist()])
                mesh.CreateFaceVertexCountsAttr([3] * len(f))
                mesh.CreateFaceVertexIndicesAttr(np.asarray(f, dtype=int).reshape(-1).tolist())
                mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
                prim = mesh.GetPrim()
                UsdPhysics.CollisionAPI.Apply(prim)
                UsdPhysics.MeshCollisionAPI.Apply(prim).CreateApproximationAttr(
                    UsdPhysics.Tokens.convexHull
                )
        stage.GetRootLayer().Export(tmp, args={"format": "usda"})


def _unique(taken: dict[str, Any], name: str) -> str:
    used = {str(x.GetPath().name) for x in taken.values()}
    candidate, k = name, 2
    while candidate in used:
        candidate, k = f"{name}_{k}", k + 1
    return candidate


def _usd_matrix(Gf: Any, pose: np.ndarray) -> Any:
    # USD multiplies row vectors (p' = p M): the transpose of meshcol's column convention.
    return Gf.Matrix4d(*np.asarray(pose, dtype=float).T.reshape(-1).tolist())


def _usd_primitive(stage: Any, UsdGeom: Any, Gf: Any, path: Any, collider: Collider) -> Any:
    p = collider.primitive
    if isinstance(p, Box):
        gprim = UsdGeom.Cube.Define(stage, path)
        gprim.CreateSizeAttr(1.0)
    elif isinstance(p, Sphere):
        gprim = UsdGeom.Sphere.Define(stage, path)
        gprim.CreateRadiusAttr(p.radius)
    elif isinstance(p, Cylinder):
        gprim = UsdGeom.Cylinder.Define(stage, path)
        gprim.CreateRadiusAttr(p.radius)
        gprim.CreateHeightAttr(p.length)
        gprim.CreateAxisAttr(UsdGeom.Tokens.z)
    else:
        assert isinstance(p, Capsule)
        gprim = UsdGeom.Capsule.Define(stage, path)
        gprim.CreateRadiusAttr(p.radius)
        gprim.CreateHeightAttr(p.length)  # USD: the length of the cylindrical part
        gprim.CreateAxisAttr(UsdGeom.Tokens.z)
    gprim.AddTransformOp().Set(_usd_matrix(Gf, collider.origin))
    if isinstance(p, Box):
        gprim.AddScaleOp().Set(Gf.Vec3f(*p.size))
    return gprim.GetPrim()
