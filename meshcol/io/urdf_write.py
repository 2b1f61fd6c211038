"""URDF written back around rebuilt colliders: the input's XML tree edited in place (lxml).

Visual elements, inertials, joints, comments and unknown tags survive: each rebuilt
``<collision>`` keeps its name and attributes, loses its ``<origin>``, and its geometry becomes
``<mesh filename="<link>_NN.obj"/>`` (a decomposition of several parts repeats the element,
``NAME_NN``, once per part); a fitted primitive becomes the element's own ``<box>``,
``<sphere>`` or ``<cylinder>`` at its ``<origin>``. The format module of
:func:`meshcol.io.robot_write.write_robot`; MuJoCo's URDF importer reads this text too
(:mod:`meshcol.io.mjcf_write`).

URDF has no capsule. By default (``capsules="standard"``) each capsule, fitted or kept from
the input, is written as the same solid in elements every URDF reader knows: the element
repeated three times (``NAME_00``, ``NAME_01``, ``NAME_02`` when it has a name), a
``<cylinder>`` of the capsule's radius and length at its origin (the axis is z in both) and
a ``<sphere>`` of its radius at each end of the axis; urdfdom (robot_state_publisher, MoveIt,
RViz, Gazebo's import) and yourdfpy refuse ``<capsule>``. ``capsules="extension"`` writes
one ``<capsule radius length>`` instead, the element pybullet and MuJoCo's importer read as a
single exact shape (pybullet makes a URDF cylinder a polygonal hull inside it, unless loaded
with ``URDF_USE_IMPLICIT_CYLINDER``); the MJCF writer uses it, MuJoCo having capsules.
"""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from meshcol.errors import MissingDependencyError, SceneError
from meshcol.io.urdf_lenient import read_description_xml
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Sphere
from meshcol.vocabulary import URDF_CAPSULES

if TYPE_CHECKING:
    from meshcol.io.robot_write import Collider, RobotColliders

__all__ = ["format_numbers", "missing_visuals", "parse_xml", "urdf_text"]


def parse_xml(source: str) -> Any:
    """The description's XML tree (lxml), read as the reader reads it (what pybullet reads
    past repaired: the reader has warned of it), or one line saying why it cannot be read."""
    try:
        from lxml import etree
    except ImportError:
        raise MissingDependencyError(
            "writing URDF needs lxml (pip install 'meshcol[robots]')", source
        ) from None
    return etree.ElementTree(read_description_xml(source, []))


def urdf_text(
    robot: RobotColliders,
    files: dict[int, list[str]],
    prefix: dict[str, str],
    out_dir: str | None = None,
    ellipsoid_placeholders: bool = False,
    capsules: str = "standard",
) -> str:
    """The input URDF with each rebuilt ``<collision>`` pointing at its part files
    (``prefix``: folder prepended to the part file names, for MuJoCo's importer). With
    ``out_dir``, the other mesh references (visuals) are rewritten by
    :func:`_references_from` so that they name the input's files from there.

    URDF has no ellipsoid: a fitted one is refused (:func:`no_ellipsoid`), or with
    ``ellipsoid_placeholders`` (for MuJoCo's importer, whose geom is then made the
    ellipsoid) written as a ``<sphere>`` of its largest semi-axis at its origin.

    ``capsules`` (:data:`meshcol.vocabulary.URDF_CAPSULES`): ``standard`` writes every
    capsule, fitted or kept, as a cylinder and two spheres; ``extension`` as ``<capsule>``,
    kept capsules as the input wrote them; in both a capsule of length 0 is its sphere
    (:func:`_written_capsule`)."""
    from lxml import etree

    if capsules not in URDF_CAPSULES:
        raise ValueError(f"unknown capsule form {capsules!r} (expected {', '.join(URDF_CAPSULES)})")
    tree = parse_xml(robot.source)
    root = tree.getroot()
    if out_dir is not None:
        _references_from(root, robot, out_dir)
    # Each link's elements as read: an element repeated below does not move the next ones.
    read = {link.get("name"): link.findall("collision") for link in root.findall("link")}
    for i, collider in enumerate(robot.colliders):
        elements = read.get(collider.link, [])
        if collider.index >= len(elements):
            if collider.kept:
                continue
            raise SceneError(
                f"link {collider.link!r}: collision {collider.index} is not in the file",
                robot.source,
            )
        element = elements[collider.index]
        if collider.primitive is not None:
            if collider.fitted:
                _urdf_primitive(element, collider, robot.source, ellipsoid_placeholders)
            if isinstance(collider.primitive, Capsule):
                _written_capsule(element, collider.primitive, collider.origin, capsules)
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


def missing_visuals(robot: RobotColliders) -> list[tuple[str, str, str]]:
    """``(link, reference, why)`` of every ``<visual>`` of a URDF whose mesh reference names
    no file (a package that is not found, a file that is not there): pybullet refuses a URDF
    with such a visual, so the URDF written leaves it out (:func:`urdf_text`). Collision
    meshes are never missing here: the robot could not be read without them."""
    return [(link, reference, why) for link, _, reference, why in _visuals_missing(robot)]


def _visuals_missing(robot: RobotColliders, root: Any = None) -> list[tuple[str, Any, str, str]]:
    """``(link, <visual> element, reference, why)`` of each visual of ``root`` (default: the
    description's tree) whose mesh names no file."""
    from meshcol.io.packages import PackageResolver
    from meshcol.io.paths import display_path

    root = parse_xml(robot.source).getroot() if root is None else root
    resolver = PackageResolver(robot.source, robot.package_paths)
    found = []
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            for mesh in visual.iter("mesh"):
                reference = mesh.get("filename") or ""
                path, why = resolver.resolve(reference) if reference else (None, "no filename")
                if path is not None and not os.path.isfile(path):
                    why = f"no file {display_path(os.path.normpath(path))}"
                if why is not None:
                    found.append((link.get("name") or "", visual, reference, why))
                    break
    return found


def _references_from(root: Any, robot: RobotColliders, out_dir: str) -> None:
    """Every relative, ``package://`` or ``file://`` mesh reference of ``root`` made a path
    relative to ``out_dir`` naming the file it resolved to (:mod:`meshcol.io.packages`, with
    the package folders the robot was read with): pybullet, yourdfpy and MuJoCo load the
    written URDF from the output folder without ROS. A ``<visual>`` whose mesh names no file
    is left out (:func:`missing_visuals`: pybullet refuses the URDF otherwise), with a
    comment in its place; an absolute reference stays as written."""
    from lxml import etree

    from meshcol.io.packages import resolve_mesh_reference

    for _, visual, reference, why in _visuals_missing(robot, root):
        text = f"meshcol: visual mesh {reference!r} left out ({why})".replace("--", "- -")
        note = etree.Comment(f" {text} ")
        note.tail = visual.tail
        visual.addprevious(note)
        visual.getparent().remove(visual)
    for mesh in root.iter("mesh"):
        reference = mesh.get("filename") or ""
        if not reference or os.path.isabs(reference):
            continue
        if "://" in reference and not reference.startswith(("package://", "file://")):
            continue
        path = resolve_mesh_reference(robot.source, reference, robot.package_paths)
        if path is None or ("://" in reference and not os.path.isfile(path)):
            continue
        moved = os.path.relpath(os.path.abspath(path), os.path.abspath(out_dir))
        mesh.set("filename", Path(moved).as_posix())


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


def format_numbers(values: Any) -> str:
    """Numbers as written in a URDF attribute: shortest round-trip text, rounding noise
    below 1e-15 (and -0) written as 0."""
    return " ".join(repr(float(v)) if abs(float(v)) >= 1e-15 else "0" for v in values)


def no_ellipsoid(source: str) -> SceneError:
    """The error of an ellipsoid collider for a URDF, which has no ellipsoid element (and no
    importer reads one): the fit goes to a format that has one, or is another shape."""
    return SceneError(
        "URDF has no ellipsoid: write the fits with --to mjcf, usd or glb, or fit another --shape",
        source,
    )


def _urdf_primitive(element: Any, collider: Collider, source: str, placeholder: bool) -> None:
    """Make a ``<collision>`` element the fitted primitive at the collider's origin (an
    ellipsoid: refused, or its ``placeholder`` sphere)."""
    from lxml import etree

    if isinstance(collider.primitive, Ellipsoid) and not placeholder:
        raise no_ellipsoid(source)

    from meshcol.geometry.rotations import rpy_from_matrix

    geometry, tail = _cleared(element)
    origin = etree.Element("origin")
    origin.set("xyz", format_numbers(collider.origin[:3, 3]))
    origin.set("rpy", format_numbers(rpy_from_matrix(collider.origin[:3, :3])))
    before = geometry.getprevious()
    origin.tail = before.tail if before is not None else element.text
    geometry.addprevious(origin)
    p = collider.primitive
    if isinstance(p, Ellipsoid):
        shape = etree.SubElement(geometry, "sphere", radius=format_numbers([max(p.semi_axes)]))
    elif isinstance(p, Box):
        shape = etree.SubElement(geometry, "box", size=format_numbers(p.size))
    elif isinstance(p, Sphere):
        shape = etree.SubElement(geometry, "sphere", radius=format_numbers([p.radius]))
    elif isinstance(p, Cylinder):
        shape = etree.SubElement(
            geometry,
            "cylinder",
            radius=format_numbers([p.radius]),
            length=format_numbers([p.length]),
        )
    else:  # the extension pybullet, MuJoCo's importer and meshcol read (_written_capsule)
        assert isinstance(p, Capsule)
        shape = etree.SubElement(
            geometry,
            "capsule",
            radius=format_numbers([p.radius]),
            length=format_numbers([p.length]),
        )
    shape.tail = tail


def _written_capsule(element: Any, capsule: Capsule, origin: Any, form: str) -> None:
    """Write a ``<collision>`` element holding ``<capsule>`` (at ``origin``, the capsule's
    frame in the link frame, its axis z) in the ``form`` of :func:`urdf_text`.

    ``standard``: the same solid in standard URDF, the element itself a ``<cylinder>`` of the
    capsule's radius and length (the attributes' text as it was), then two copies of it, each
    a ``<sphere>`` of that radius at one end of the axis (``origin`` +- length/2 along its z;
    the orientation kept, a sphere has none to lose). A named element's three become
    ``NAME_00`` (the cylinder), ``NAME_01`` and ``NAME_02`` (the spheres at -z and +z), as
    the parts of a decomposition are named. ``extension``: the element as it is. In both, a
    capsule of length 0 (:func:`meshcol.io.primitives.written_primitive`) is its sphere, one
    element (MuJoCo's importer refuses a capsule of length 0)."""
    import numpy as np

    from meshcol.io.primitives import written_primitive

    shape = element.find("geometry/capsule")
    if shape is None:  # not a capsule in the file (refused by the reader before this)
        return
    if isinstance(written_primitive(capsule), Sphere):
        shape.tag = "sphere"
        shape.attrib.pop("length", None)
        return
    if form == "extension":
        return
    shape.tag = "cylinder"
    pose = np.asarray(origin, dtype=np.float64)
    name = element.get("name")
    before = element.getprevious()
    indent = before.tail if before is not None else element.getparent().text
    previous, tail = element, element.tail
    for k, sign in enumerate((-1.0, 1.0), start=1):
        end = copy.deepcopy(element)
        previous.tail = indent  # each on a line of its own, as the element was
        previous.addnext(end)
        previous = end
        end.tail = tail
        if name:
            end.set("name", f"{name}_{k:02d}")
        ball = end.find("geometry/cylinder")
        ball.tag = "sphere"
        ball.attrib.pop("length")
        at = end.find("origin")
        if at is None:  # the capsule sat at the link's origin
            from lxml import etree

            at = etree.Element("origin")
            at.tail = end.text
            end.insert(0, at)
        at.set("xyz", format_numbers(pose[:3, 3] + sign * 0.5 * capsule.length * pose[:3, 2]))
    if name:
        element.set("name", f"{name}_00")
