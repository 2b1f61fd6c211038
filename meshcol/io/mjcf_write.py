"""MJCF written around rebuilt colliders by MuJoCo's own model editor (``mujoco.MjSpec``).

``OUT/ROBOT.xml`` follows the convention of MuJoCo Menagerie: visual geoms in group 2 with
``contype="0" conaffinity="0"``, collision geoms in group 3, one mesh asset per part. An MJCF
input is edited as MuJoCo read it (defaults, classes and includes resolved by MuJoCo; comments
do not survive MuJoCo's writer). A URDF input is first rewritten
(:func:`meshcol.io.urdf_write.urdf_text`) and then compiled by MuJoCo's URDF importer (bodies,
joints, limits, inertials and mimic joints as MuJoCo reads them, ``fusestatic`` off so that
every link stays a body); visual meshes MuJoCo cannot read (COLLADA) are converted to
``OUT/visual_<name>.obj``. The model is compiled by MuJoCo before the text is returned. The
format module of :func:`meshcol.io.robot_write.write_robot`.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import MeshcolError, MissingDependencyError, SceneError
from meshcol.io.packages import resolve_mesh_reference
from meshcol.io.urdf_write import format_numbers, urdf_text
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Sphere

if TYPE_CHECKING:
    from meshcol.io.robot_write import Collider, RobotColliders

__all__ = ["mjcf_text"]

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


def _mujoco(source: str) -> Any:
    try:
        import mujoco
    except ImportError:
        raise MissingDependencyError(
            "writing MJCF needs mujoco (pip install 'meshcol[robots]')", source
        ) from None
    return mujoco


def mjcf_text(robot: RobotColliders, files: dict[int, list[str]], stage: str, out_dir: str) -> str:
    """``OUT/ROBOT.xml`` in the Menagerie convention, compiled by MuJoCo before it is returned.

    ``files``: the part files of each rebuilt collider (by its position in
    ``robot.colliders``), written in ``stage`` and moved to ``out_dir`` afterwards."""
    mujoco = _mujoco(robot.source)
    stage_abs = os.path.abspath(stage)
    notes: list[str] = []
    if robot.kind == "urdf":
        spec, exact = _spec_of_urdf(mujoco, robot, files, stage_abs, notes)
    else:
        spec, exact = _spec_of_mjcf(mujoco, robot, files, stage_abs)
    # Files by absolute path for MuJoCo's check and writer, then relative to OUT in the text.
    _absolute_asset_files(spec, robot.source if robot.kind == "mjcf" else None)
    spec.meshdir = ""
    spec.texturedir = ""
    excludes = _add_excludes(spec, robot)
    bounds = _bound_inertia(mujoco, spec, robot.source)
    if excludes:
        notes.append(f"{excludes} <contact><exclude> pair(s) written: {_EXCLUDE_NOTE}")
    if bounds:
        notes.append(bounds)
    markers = _mark(mujoco, spec, exact)
    try:
        text = spec.to_xml()
    except Exception as exc:  # noqa: BLE001 - as _spec
        raise SceneError(
            f"MuJoCo cannot write the rebuilt model: {' '.join(str(exc).split())}", robot.source
        ) from None
    text = _relative_files(_exact_geoms(text, markers), stage_abs, os.path.abspath(out_dir))
    return _with_notes(text, notes, spec.compiler if bounds else None)


#: What the written ``<contact><exclude>`` elements are, for the note at the top of the file.
_EXCLUDE_NOTE = (
    "the link pairs meshcol leaves out of self-collision (adjacent links, SRDF pairs), so that "
    "MuJoCo leaves them out too (its own parent-child filter misses the child of a body "
    "welded to the world)"
)

#: Lower bounds MuJoCo's compiler puts on a moving body's mass (kg) and inertia (kg m^2)
#: when the model does not compile without them (``<compiler boundmass boundinertia>``).
BOUND_MASS = 1e-3
BOUND_INERTIA = 1e-6


def _add_excludes(spec: Any, robot: RobotColliders) -> int:
    """A ``<contact><exclude>`` for each pair meshcol excludes but MuJoCo's own filters (MJCF
    excludes, welds, contype/conaffinity) do not already cover; how many were added."""
    bodies = {body.name for body in spec.bodies}
    present = {tuple(sorted((e.bodyname1, e.bodyname2))) for e in spec.excludes}
    added = 0
    for a, b, reason in robot.excluded_pairs:
        key = tuple(sorted((a, b)))
        if reason.startswith("mjcf") or key in present or a not in bodies or b not in bodies:
            continue
        spec.add_exclude(bodyname1=key[0], bodyname2=key[1])
        present.add(key)
        added += 1
    return added


def _bound_inertia(mujoco: Any, spec: Any, source: str) -> str | None:
    """Compile; a model MuJoCo rejects for a body's mass or inertia (below ``mjMINVAL`` on a
    moving body, as a quadruped's motor links; breaking the triangle inequality; a full
    inertia that is not positive definite) is compiled again with MuJoCo's own remedies, as
    converters do: ``<compiler boundmass boundinertia balanceinertia>`` (:data:`BOUND_MASS`,
    :data:`BOUND_INERTIA`: lower bounds on every body's mass and inertia but the world's),
    and if that is not enough ``inertiafromgeom="true"`` (every inertia from the body's
    geoms); the note saying so."""
    why = _inertia_rejection(spec, source)
    if why is None:
        return None
    first, shells = why, _shell_inertias(mujoco, spec, source, why)
    if shells:
        why = _inertia_rejection(spec, source)
        shell = f'; mesh(es) {", ".join(repr(n) for n in shells)} with inertia="shell"'
        if why is None:
            return (
                f"MuJoCo rejected the model as written ({first}); compiled{shell[1:]} (a "
                "mesh too thin for a volume inertia, MuJoCo's advice), as converters do"
            )
    else:
        shell = ""
    from_geoms = _inertia_from_geoms(spec)
    spec.compiler.balanceinertia = True
    spec.compiler.boundmass = max(float(spec.compiler.boundmass), BOUND_MASS)
    spec.compiler.boundinertia = max(float(spec.compiler.boundinertia), BOUND_INERTIA)
    remedy = f'boundmass="{BOUND_MASS:g}" boundinertia="{BOUND_INERTIA:g}" balanceinertia="true"'
    if _inertia_rejection(spec, source) is not None:
        spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE
        remedy += ' inertiafromgeom="true"'
    _compile(mujoco, spec, source)
    geoms = (
        f"; the inertia of {', '.join(repr(name) for name in from_geoms)} (not positive "
        "definite) from its geoms"
        if from_geoms
        else ""
    )
    return (
        f"MuJoCo rejected the model as written ({first}); compiled with <compiler {remedy}> "
        f"(MuJoCo's remedies for the masses and inertias of bodies){geoms}{shell}, as "
        "converters do"
    )


def _shell_inertias(mujoco: Any, spec: Any, source: str, why: str | None) -> list[str]:
    """While MuJoCo rejects a mesh whose volume is too small for its inertia (a visual mesh
    of open or paper-thin surfaces), that mesh gets ``inertia="shell"``, as MuJoCo advises;
    the names of those meshes."""
    import re

    shells: list[str] = []
    while why is not None and "mesh volume is too small" in why:
        found = re.search(r"too small: (.+?) \. Try", why)
        mesh = spec.mesh(found.group(1)) if found else None
        if mesh is None or mesh.name in shells:
            break
        mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        shells.append(mesh.name)
        why = _inertia_rejection(spec, source)
    return shells


def _inertia_from_geoms(spec: Any) -> list[str]:
    """Bodies whose full inertia is not positive definite (MuJoCo refuses it before any
    bound applies) get their inertial from their geoms instead; their names."""
    names = []
    for body in spec.bodies:
        full = np.asarray(body.fullinertia, dtype=np.float64)
        if not body.explicitinertial or not np.all(np.isfinite(full)):
            continue
        matrix = np.array(
            [[full[0], full[3], full[4]], [full[3], full[1], full[5]], [full[4], full[5], full[2]]]
        )
        if np.linalg.eigvalsh(matrix).min() <= _MJMINVAL:  # MuJoCo's test of the eigenvalues
            body.explicitinertial = False
            body.fullinertia = [np.nan] * 6
            names.append(body.name)
    return names


#: MuJoCo's ``mjMINVAL``: its compiler refuses a full inertia with an eigenvalue at or below
#: it (pybullet_data's biped2d gives one of 2e-18, positive in numpy).
_MJMINVAL = 1e-15

#: Words of MuJoCo's compiler errors about a body's mass or inertia.
_INERTIA_ERRORS = ("mjMINVAL", "A + B >= C", "positive eigenvalues", "mesh volume is too small")


def _inertia_rejection(spec: Any, source: str) -> str | None:
    """None when the spec compiles; MuJoCo's words when it rejects a mass or inertia; any
    other rejection is a SceneError."""
    try:
        spec.compile()
        return None
    except Exception as exc:  # noqa: BLE001 - as _spec
        why = " ".join(str(exc).split())
    if not any(words in why for words in _INERTIA_ERRORS):
        raise SceneError(f"MuJoCo rejects the rebuilt model: {why}", source) from None
    return why


def _with_notes(text: str, notes: list[str], compiler: Any = None) -> str:
    """The XML with one comment per note after its root's opening tag ("meshcol: ..."), and
    with ``compiler``: the bounds :func:`_bound_inertia` set on ``<compiler>`` (MuJoCo's
    writer leaves ``balanceinertia`` out, and the file must compile as it did here)."""
    if not notes:
        return text
    from lxml import etree

    root = etree.fromstring(text.encode("utf-8"))
    if compiler is not None:
        element = root.find("compiler")
        if element is None:
            element = etree.Element("compiler")
            element.tail = "\n  "
            root.insert(0, element)
        element.set("boundmass", format_numbers([compiler.boundmass]))
        element.set("boundinertia", format_numbers([compiler.boundinertia]))
        element.set("balanceinertia", "true")
        if int(compiler.inertiafromgeom) == 1:  # mjINERTIAFROMGEOM_TRUE
            element.set("inertiafromgeom", "true")
    for k, note in enumerate(notes):
        comment = etree.Comment(f" meshcol: {note.replace('--', '- -')} ")
        comment.tail = "\n  "
        root.insert(k, comment)
    return etree.tostring(root, encoding="unicode") + "\n"


def _spec_of_urdf(
    mujoco: Any, robot: RobotColliders, files: dict[int, list[str]], stage: str, notes: list[str]
) -> tuple[Any, list[Any]]:
    """The rebuilt URDF as MuJoCo imports it, visual geoms in group 2 and collision geoms in
    group 3; and the geoms of its fitted primitives (written at full precision)."""
    spec = _spec_from_urdf(mujoco, robot, files, stage, notes)
    exact = _imported_primitives(mujoco, spec, robot)
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:
            geom.group = 2  # MuJoCo's importer puts URDF visuals in group 1
        else:
            geom.group = 3
    return spec, exact


def _spec_of_mjcf(
    mujoco: Any, robot: RobotColliders, files: dict[int, list[str]], stage: str
) -> tuple[Any, list[Any]]:
    """The input MJCF as MuJoCo read it, each rebuilt geom made its parts (or its fitted
    primitive), visual geoms in group 2 and collision geoms in group 3, collision meshes no
    geom uses any more deleted; and the geoms of the fitted primitives."""
    from meshcol.io.safe_read import check_mjcf_files

    check_mjcf_files(robot.source)  # its includes and assets, before MuJoCo opens them
    spec = _spec(mujoco, robot.source, lambda: mujoco.MjSpec.from_file(robot.source))
    _compile(mujoco, spec, robot.source)
    geoms = {geom.id: geom for geom in spec.geoms}
    colliding = {c.index for c in robot.colliders}
    # visual: colliding with nothing, and no collider (a geom of a <contact><pair> is one)
    visual = [
        geom
        for geom in spec.geoms
        if geom.contype == 0 and geom.conaffinity == 0 and geom.id not in colliding
    ]
    rebuilt = [geoms[c.index] for c in robot.colliders if not c.kept]
    in_frame = _frame_inverses(mujoco, spec, robot.source, rebuilt)
    mesh_names = {m.name for m in spec.meshes}
    new_assets: set[str] = set()
    exact: list[Any] = []
    for i, collider in enumerate(robot.colliders):
        geom = geoms[collider.index]
        geom.group = 3
        if collider.kept:
            continue
        if collider.fitted:
            _mjcf_primitive(mujoco, geom, collider, in_frame.get(id(geom)))
            exact.append(geom)
            continue
        added = _part_geoms(mujoco, spec, geom, files[i], stage, mesh_names, in_frame)
        new_assets.update(added)
    for geom in visual:
        geom.group = 2
    used = {geom.meshname for geom in spec.geoms if geom.meshname}
    for mesh in list(spec.meshes):
        if mesh.name not in used and mesh.name not in new_assets:
            spec.delete(mesh)  # a collision mesh no geom uses any more
    return spec, exact


def _part_geoms(
    mujoco: Any,
    spec: Any,
    geom: Any,
    part_files: list[str],
    stage: str,
    mesh_names: set[str],
    in_frame: dict[int, tuple[list[float], list[float]]],
) -> list[str]:
    """Make ``geom`` the first part's mesh geom and add one geom per further part (its
    attributes copied, ``NAME_NN``; the geom's mass shared out); the mesh assets added."""
    extra_mass = geom.mass / len(part_files) if not np.isnan(geom.mass) else None
    added = []
    for k, file in enumerate(part_files):
        name = Path(file).stem
        while name in mesh_names:
            name += "_"
        mesh_names.add(name)
        added.append(name)
        mesh = spec.add_mesh(name=name, file=os.path.join(stage, file))
        # The part file is in metres in the body frame: a <default><mesh scale refpos
        # refquat> of the input (Menagerie's op3 writes its STL in millimetres) must not
        # scale or move it (written only where the default differs).
        mesh.scale = [1.0, 1.0, 1.0]
        mesh.refpos = [0.0, 0.0, 0.0]
        mesh.refquat = [1.0, 0.0, 0.0, 0.0]
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
        # The parts are in the body frame: no offset, no orientation of any kind (an
        # euler/axisangle/xyaxes/zaxis attribute overrides quat in MuJoCo). A geom inside
        # <frame> elements gets the inverse of their pose.
        pos, quat = in_frame.get(id(target), ([0.0] * 3, [1.0, 0.0, 0.0, 0.0]))
        target.pos = pos
        target.quat = quat
        target.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
        target.fromto = [np.nan] * 6
    if geom.name and len(part_files) > 1:
        geom.name = f"{geom.name}_00"
    return added


def _imported_primitives(mujoco: Any, spec: Any, robot: RobotColliders) -> list[Any]:
    """The geoms MuJoCo's URDF importer made of the fitted primitives: on the link's body, of
    the primitive's type, at its position (the URDF carries it at full precision). A fitted
    ellipsoid came as its placeholder sphere (URDF has none), told from a sphere of the
    description's at the same place by its radius: its geom is made the ellipsoid here."""
    types = {
        Box: mujoco.mjtGeom.mjGEOM_BOX,
        Sphere: mujoco.mjtGeom.mjGEOM_SPHERE,
        Cylinder: mujoco.mjtGeom.mjGEOM_CYLINDER,
        Capsule: mujoco.mjtGeom.mjGEOM_CAPSULE,
        Ellipsoid: mujoco.mjtGeom.mjGEOM_ELLIPSOID,
    }
    found, taken = [], set()
    for collider in robot.colliders:
        if not collider.fitted:
            continue
        primitive = collider.primitive
        want = types[type(primitive)]
        # an ellipsoid's URDF placeholder is a sphere
        written = mujoco.mjtGeom.mjGEOM_SPHERE if isinstance(primitive, Ellipsoid) else want
        for geom in spec.geoms:
            if (
                id(geom) not in taken
                and geom.type == written
                and geom.parent.name == collider.link
                and np.allclose(geom.pos, collider.origin[:3, 3], rtol=0, atol=1e-12)
                and (not isinstance(primitive, Ellipsoid) or _placeholder_of(geom, primitive))
            ):
                if isinstance(primitive, Ellipsoid):
                    geom.type = want
                    geom.size = list(primitive.semi_axes)
                taken.add(id(geom))
                found.append(geom)
                break
    return found


def _placeholder_of(geom: Any, ellipsoid: Ellipsoid) -> bool:
    """Whether a sphere geom is the placeholder of ``ellipsoid`` (its largest semi-axis as
    the radius, the URDF's own number): not a sphere the description had at the same place."""
    return bool(np.isclose(geom.size[0], max(ellipsoid.semi_axes), rtol=1e-12, atol=0))


def _mark(mujoco: Any, spec: Any, geoms: list[Any]) -> dict[str, tuple[bool, dict[str, str]]]:
    """Name each geom uniquely (its own name, or a marker that :func:`_exact_geoms` removes)
    and keep its size, pos and quat at full precision: MuJoCo writes numbers with 6
    significant digits, which can shrink a fitted primitive below what it must enclose."""
    taken = {g.name for g in spec.geoms if g.name}
    used = {
        mujoco.mjtGeom.mjGEOM_SPHERE: 1,
        mujoco.mjtGeom.mjGEOM_BOX: 3,
        mujoco.mjtGeom.mjGEOM_ELLIPSOID: 3,
    }
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
        exact = {key: format_numbers(v) for key, v in values.items()}
        if geom.classname is not None and geom.classname.geom.meshname:
            # its class names a mesh (Menagerie's leap_hand: <default class="tip"><geom
            # mesh="tip">): the primitive must not inherit it, which MuJoCo fits the
            # primitive to, or refuses once that mesh asset is gone
            exact["mesh"] = ""
        markers[geom.name] = (own, exact)
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
    elif isinstance(p, Ellipsoid):
        geom.type = mujoco.mjtGeom.mjGEOM_ELLIPSOID
        geom.size = list(p.semi_axes)
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
    """Each mesh, height field, texture and skin file by its absolute path."""
    base = spec.modelfiledir or (os.path.dirname(os.path.abspath(mjcf)) if mjcf else "")
    for assets, folder in (
        (spec.meshes, spec.meshdir),
        (spec.hfields, spec.meshdir),
        (spec.textures, spec.texturedir),
        (spec.skins, spec.meshdir),
    ):
        for asset in assets:
            file = getattr(asset, "file", "")
            if not file:
                continue
            path = file if os.path.isabs(file) else os.path.join(base, folder or "", file)
            if not os.path.isfile(path) and os.path.isfile(os.path.join(base, file)):
                path = os.path.join(base, file)  # a skin MuJoCo found beside the model
            asset.file = os.path.abspath(path)


def _spec_from_urdf(
    mujoco: Any, robot: RobotColliders, files: dict[int, list[str]], stage: str, notes: list[str]
) -> Any:
    """MuJoCo's URDF importer on the rebuilt URDF: every mesh by absolute path, COLLADA and
    other visual meshes MuJoCo does not read converted to OBJ in the stage; a visual mesh
    that is not found or has no triangles to convert (a COLLADA of lines only) is left out,
    with a note."""
    from lxml import etree

    text = urdf_text(
        robot,
        files,
        {"collider": stage + os.sep},
        ellipsoid_placeholders=True,
        capsules="extension",  # MuJoCo reads it: a capsule geom, not three
    )
    root = etree.fromstring(text.encode("utf-8"))
    converted: dict[str, str] = {}
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            empty = _empty_primitive(visual)
            if empty is not None:  # MuJoCo refuses a geom of size 0: nothing to draw either
                link.remove(visual)
                notes.append(f"link {link.get('name')!r}: visual {empty} left out")
                continue
            for mesh in visual.iter("mesh"):
                reference = mesh.get("filename") or ""
                path = resolve_mesh_reference(robot.source, reference, robot.package_paths)
                try:
                    if path is None or not os.path.isfile(path):
                        raise SceneError("not found", robot.source)
                    suffix = Path(path).suffix.lower()
                    if suffix not in _MUJOCO_MESH_FORMATS or (
                        suffix == ".obj" and (path in converted or _obj_normals_incomplete(path))
                    ):
                        if suffix == ".obj" and path not in converted:
                            notes.append(
                                f"link {link.get('name')!r}: visual mesh {reference!r} "
                                "converted (faces without normals beside faces with them, "
                                "which MuJoCo's OBJ reader refuses)"
                            )
                        path = converted.get(path) or _convert_visual(path, stage, converted)
                except MeshcolError as error:
                    link.remove(visual)  # what a link looks like: no collider depends on it
                    notes.append(
                        f"link {link.get('name')!r}: visual mesh {reference!r} left out "
                        f"({error.message})"
                    )
                    break
                mesh.set("filename", path)
    _ball_ranges(root, notes)
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


def _ball_ranges(root: Any, notes: list[str]) -> None:
    """A spherical joint's ``<limit>`` whose lower bound is not 0 loses its bounds, with a
    note. MuJoCo's importer makes ``lower upper`` a ball joint's range, which MuJoCo bounds
    by one angle (``0 r``) and refuses otherwise; pybullet reads the same attributes as
    swing ranges about two axes, ``twist`` the third (``btMultiBodySphericalJointLimit``),
    which MuJoCo cannot state: the ball is written unlimited."""
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if joint.get("type") != "spherical" or limit is None:
            continue
        lower = limit.get("lower")
        if lower is None or float(lower) == 0.0:
            continue
        bounds = f"lower {lower}, upper {limit.get('upper')}"
        for name in ("lower", "upper"):
            limit.attrib.pop(name, None)
        notes.append(
            f"joint {joint.get('name')!r}: spherical limits ({bounds}) have no MuJoCo form "
            "(a ball joint's range is one angle from 0): the ball joint is unlimited"
        )


def _obj_normals_incomplete(path: str) -> bool:
    """Whether an OBJ file has normals (``vn``) and a face corner without a normal index:
    MuJoCo's reader refuses it ("mesh_facenormal normal index out of bounds";
    pybullet_data's table_square), where pybullet and trimesh compute the missing normals."""
    from meshcol.io.safe_read import read_input

    data = read_input(path)
    if not re.search(rb"^[ \t]*vn[ \t]", data, re.MULTILINE):
        return False
    for face in re.finditer(rb"^[ \t]*f[ \t]+([^\r\n#]*)", data, re.MULTILINE):
        if any(corner.count(b"/") != 2 or corner.endswith(b"/") for corner in face[1].split()):
            return True
    return False


def _empty_primitive(visual: Any) -> str | None:
    """``"sphere of radius 0"`` and the like for a visual primitive with a size that is not
    positive (pybullet_data's laikago_toes draws each toe as a sphere of radius 0); None
    otherwise."""
    for shape, names in (("sphere", ("radius",)), ("cylinder", ("radius", "length"))):
        for element in visual.iter(shape):
            for name in names:
                if _not_positive(element.get(name)):
                    return f"{shape} of {name} {element.get(name)}"
    for element in visual.iter("box"):
        if any(_not_positive(x) for x in (element.get("size") or "").split()):
            return f"box of size {element.get('size')!r}"
    return None


def _not_positive(text: str | None) -> bool:
    try:
        return text is not None and not float(text) > 0.0
    except ValueError:
        return False  # not a number: the importer says so


def _convert_visual(path: str, stage: str, converted: dict[str, str]) -> str:
    """A visual mesh MuJoCo cannot read, as one OBJ in the stage (``visual_<stem>.obj``);
    the reader's error (MeshcolError) for a file it cannot read."""
    from meshcol.io.mesh_read import load_mesh
    from meshcol.io.mesh_write import safe_name, write_meshes

    bodies = load_mesh(path)
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
