"""USD stages (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) read as scenes, with usd-core.

What one body is:

- a prim with ``UsdPhysics.RigidBodyAPI``, or an ``Xform`` that ``--to usd`` wrote for a link
  (custom data ``meshcol:link``, named after it): every collision prim under it is one of its
  parts;
- any other collision prim (``UsdPhysics.CollisionAPI``) is a static body of its own.

A body is named after its prim (``--to usd``'s link name; ``<instancer>_<k>`` for a point
instance) and, where several have one name (every prim ``mesh`` under its own ``Xform``), by
the end of its prim path that tells them apart (:mod:`meshcol.io.body_names`).

When the stage has no ``CollisionAPI`` at all, every ``Mesh`` and primitive prim is a body of
its own, as the objects of an OBJ file are (``purpose = "guide"`` prims skipped); when it has
some, geometry without ``CollisionAPI`` is render geometry and not read (a warning counts it).
Collision prims with ``physics:collisionEnabled = false`` are skipped (a warning counts them).

Values are read at the earliest time sample where an attribute has some (an animated
transform often has no default), else at its default. Geometry: ``UsdGeom.Mesh`` (polygons triangulated by :func:`meshcol.io.polygons.triangulate_faces`,
``holeIndices`` dropped, ``orientation = "leftHanded"`` winding reversed) and ``Cube``,
``Sphere``, ``Capsule``, ``Cylinder`` at their world transforms (``UsdGeom.XformCache``,
instance proxies of instanceable prims and references included, ``PointInstancer``
instances expanded). A body of one primitive prim stays that exact primitive when its
transform scales it into one (a box by any axis scale; a sphere uniformly; a capsule or
cylinder evenly across its axis); else, and in a body of several parts, the primitive is
tessellated (:func:`meshcol.io.links.parts_body`, as for robot links).

A body's collider (``Body.collider``) is its collision meshes' ``physics:approximation``
(``UsdPhysics.MeshCollisionAPI``): ``none`` is ``mesh`` (the triangles), ``convexHull`` is
``hull``, ``convexDecomposition`` is ``decomposed``, ``boundingSphere`` is ``sphere``,
``boundingCube`` is ``box``, ``meshSimplification`` is ``mesh`` (meshcol checks the exact
triangles an engine would simplify; a warning says so). A collision mesh without
``MeshCollisionAPI`` takes the schema's fallback, ``none``. Render-only bodies keep the run's
collider (``--shape``). Prims in a ``UsdPhysics.FilteredPairsAPI`` relationship become
excluded pairs (``Scene.excluded_pairs``), as do bodies whose collision groups
(``UsdPhysics.CollisionGroup``, ``physics:filteredGroups``) filter each other.

The scene frame: metres, Z up, right-handed. Every coordinate is multiplied by the stage's
``metersPerUnit`` (USD's fallback 0.01 when not authored, with a warning) and a Y-up stage is
turned +90 degrees about X (``y`` becomes ``z``); ``Scene.units`` is ``"m"``.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.body_names import MAX_ANCESTORS
from meshcol.io.physics_bodies import BodyGroup, FileScene, ShapeElement
from meshcol.types import Box, Capsule, Cylinder, Primitive, Sphere

__all__ = ["APPROXIMATIONS", "MAX_PRIMS", "USD_EXTENSIONS", "read_usd_scene"]

#: The file extensions of USD stages.
USD_EXTENSIONS = (".usd", ".usda", ".usdc", ".usdz")

#: ``physics:approximation`` (``UsdPhysics.MeshCollisionAPI``) to meshcol's collider kind.
APPROXIMATIONS = {
    "none": "mesh",
    "convexHull": "hull",
    "convexDecomposition": "decomposed",
    "boundingSphere": "sphere",
    "boundingCube": "box",
    "meshSimplification": "mesh",
}

#: Most prims (instance proxies and point instances included) one stage may hold: a bound
#: on the work a small hostile file (instancing, references) can ask for.
MAX_PRIMS = 1_000_000
#: Most triangles of all the stage's meshes together.
MAX_TRIANGLES = 50_000_000

_PRIMITIVE_TYPES = ("Cube", "Sphere", "Capsule", "Cylinder")


def read_usd_scene(file: Path, source: str) -> FileScene:
    """The bodies of a USD stage (one group each), its excluded pairs and warnings (see the
    module's notes); :func:`meshcol.io.mesh_read.load_file_scene` names and builds them.

    Raises
    ------
    InvalidMeshError
        A layer that cannot be read (garbage, truncated), a composition error (cyclic
        references or sublayers, missing layers), a mesh whose counts disagree or that
        indexes points it does not have, more than :data:`MAX_PRIMS` prims or
        :data:`MAX_TRIANGLES` triangles.
    """
    from pxr import UsdGeom

    from meshcol.io.usd_filters import excluded_pairs

    stage = _open_stage(file, source)
    frame, warnings = _stage_frame(stage, UsdGeom, source)
    reader = _Reader(stage, frame, source, warnings)
    reader.collect()
    groups = [g for g in reader.groups.values() if g.elements]
    excluded = excluded_pairs(stage, [g.key for g in groups])
    return FileScene(groups, excluded, "m", warnings)


def _usd_error(text: str) -> str:
    """A usd-core error as one line: the quoted message of its first error, else the text."""
    match = re.search(r": '(.+?)'(?:\s|$)", text, flags=re.S)
    line = match.group(1) if match else text
    return " ".join(line.split())


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """usd-core prints its warnings on the process's stderr (file descriptor 2); while a
    stage opens they go to a scratch file instead (the reader reports what matters itself)."""
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to guard
        yield
        return
    with tempfile.TemporaryFile() as scratch:
        os.dup2(scratch.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def _open_stage(file: Path, source: str) -> Any:
    from pxr import Tf, Usd

    with _quiet_stderr():
        try:
            stage = Usd.Stage.Open(str(file), Usd.Stage.LoadAll)
        except Tf.ErrorException as error:
            raise InvalidMeshError(
                f"cannot parse USD file: {_usd_error(str(error))}", source
            ) from None
        if stage is None:
            raise InvalidMeshError("cannot parse USD file: usd-core cannot open it", source)
        errors = stage.GetCompositionErrors() if hasattr(stage, "GetCompositionErrors") else []
    if errors:
        raise InvalidMeshError(f"cannot compose USD stage: {_usd_error(str(errors[0]))}", source)
    return stage


def _stage_frame(stage: Any, UsdGeom: Any, source: str) -> tuple[np.ndarray, list[str]]:
    """The (4, 4) map from the stage's frame to metres, Z up; warnings for fallbacks used."""
    warnings: list[str] = []
    if not stage.HasAuthoredMetadata("metersPerUnit"):
        warnings.append("metersPerUnit not authored: USD's fallback 0.01 (centimetres) used")
    if not stage.HasAuthoredMetadata("upAxis"):
        warnings.append("upAxis not authored: USD's fallback Y used")
    scale = float(UsdGeom.GetStageMetersPerUnit(stage))
    if not (np.isfinite(scale) and scale > 0):
        raise InvalidMeshError(
            f"cannot parse USD file: metersPerUnit is {scale!r} (expected a positive number)",
            source,
        )
    frame = np.eye(4) * scale
    frame[3, 3] = 1.0
    if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y:
        # +90 degrees about X: (x, y, z) -> (x, -z, y), so the stage's Y lands on Z
        frame = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]) @ frame
    return frame, warnings


def _matrix(gf_matrix: Any) -> np.ndarray:
    """A ``Gf.Matrix4d`` (row vectors, ``p' = p M``) as meshcol's (4, 4) column convention."""
    return np.array(gf_matrix, dtype=np.float64).reshape(4, 4).T


class _Reader:
    """One walk over the stage: bodies and their elements, then the excluded pairs."""

    def __init__(self, stage: Any, frame: np.ndarray, source: str, warnings: list[str]) -> None:
        from pxr import Usd, UsdGeom

        self.stage, self.frame, self.source, self.warnings = stage, frame, source, warnings
        # the earliest time sample where there are some, else the default value: an exporter
        # that animates a transform often authors no default, which reads as the identity
        self.time = Usd.TimeCode.EarliestTime()
        self.cache = UsdGeom.XformCache(self.time)
        self.groups: dict[str, BodyGroup] = {}
        self.triangles = 0

    def error(self, problem: str) -> InvalidMeshError:
        return InvalidMeshError(problem, self.source)

    def world(self, prim: Any) -> np.ndarray:
        return self.frame @ _matrix(self.cache.GetLocalToWorldTransform(prim))

    def collect(self) -> None:
        from pxr import Usd, UsdGeom, UsdPhysics

        prims = []
        predicate = Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)
        for count, prim in enumerate(Usd.PrimRange.Stage(self.stage, predicate)):
            if count >= MAX_PRIMS:
                raise self.error(f"stage has more than {MAX_PRIMS} prims")
            prims.append(prim)
        self.physics = any(p.HasAPI(UsdPhysics.CollisionAPI) for p in prims)
        skipped_render = disabled = 0
        instancers = [p for p in prims if p.IsA(UsdGeom.PointInstancer)]
        prototypes = tuple(str(p.GetPath()) + "/" for p in instancers)
        for prim in prims:
            if prim.GetTypeName() not in ("Mesh", *_PRIMITIVE_TYPES):
                continue
            if str(prim.GetPath()).startswith(prototypes):
                continue  # a PointInstancer's prototype: read per instance
            state = self._collision_state(prim, UsdGeom, UsdPhysics)
            if state == "render":
                skipped_render += 1
            elif state == "disabled":
                disabled += 1
            elif state == "read":
                self._add(prim, self.world(prim))
        for instancer in instancers:
            self._instances(instancer, UsdGeom, UsdPhysics)
        if skipped_render:
            self.warnings.append(
                f"{skipped_render} prim(s) without UsdPhysics CollisionAPI not read (render "
                "geometry: the stage has collision prims)"
            )
        if disabled:
            self.warnings.append(
                f"{disabled} collision prim(s) with physics:collisionEnabled = false skipped"
            )

    def _collision_state(self, prim: Any, UsdGeom: Any, UsdPhysics: Any) -> str:
        """``read``, ``render`` (not collision geometry), ``disabled`` or ``guide``."""
        if not self.physics:
            purpose = UsdGeom.Imageable(prim).GetPurposeAttr().Get()
            return "guide" if purpose == UsdGeom.Tokens.guide else "read"
        if not prim.HasAPI(UsdPhysics.CollisionAPI):
            return "render"
        enabled = UsdPhysics.CollisionAPI(prim).GetCollisionEnabledAttr().Get()
        return "disabled" if enabled is False else "read"

    def _group_of(self, prim: Any) -> tuple[Any, str]:
        """The prim that is ``prim``'s body, and the body's name."""
        from pxr import UsdPhysics

        current = prim
        while current and not current.IsPseudoRoot():
            link = current.GetCustomDataByKey("meshcol:link")
            if isinstance(link, str) and link:
                return current, link
            if current.HasAPI(UsdPhysics.RigidBodyAPI):
                return current, current.GetName()
            current = current.GetParent()
        return prim, prim.GetName()

    def _add(self, prim: Any, world: np.ndarray, group_key: str | None = None) -> None:
        body_prim, name = self._group_of(prim)
        key = group_key or str(body_prim.GetPath())
        group = self.groups.get(key)
        if group is None:
            body_world = world if body_prim == prim else self.world(body_prim)
            above = _ancestors(body_prim)
            group = self.groups[key] = BodyGroup(key, name, body_world, ancestors=above)
        relative = str(prim.GetPath())[len(str(body_prim.GetPath())) :].lstrip("/")
        group.elements.append(self._element(prim, relative or prim.GetName(), world))

    def _element(self, prim: Any, name: str, world: np.ndarray) -> ShapeElement:
        from pxr import UsdGeom, UsdPhysics

        kind = prim.GetTypeName()
        if kind != "Mesh":
            axis = "Z"
            if kind in ("Capsule", "Cylinder"):
                axis = str(prim.GetAttribute("axis").Get(self.time) or "Z")
            primitive = _primitive(prim, kind, UsdGeom, self.time)
            return ShapeElement(name, world, primitive, None, None, None, axis)
        vertices, faces = self._mesh(UsdGeom.Mesh(prim), str(prim.GetPath()))
        collider = None
        if prim.HasAPI(UsdPhysics.CollisionAPI):
            token = "none"
            if prim.HasAPI(UsdPhysics.MeshCollisionAPI):
                token = str(UsdPhysics.MeshCollisionAPI(prim).GetApproximationAttr().Get())
            collider = APPROXIMATIONS.get(token)
            if collider is None:
                self.warnings.append(
                    f"{prim.GetPath()}: physics:approximation {token!r} is not one of "
                    f"UsdPhysics' ({', '.join(APPROXIMATIONS)}): read as none (the triangles)"
                )
                collider = "mesh"
            elif token == "meshSimplification":
                self.warnings.append(
                    f"{prim.GetPath()}: physics:approximation meshSimplification checked as "
                    "its exact triangles (an engine simplifies them)"
                )
        return ShapeElement(name, world, None, vertices, faces, collider)

    def _mesh(self, mesh: Any, where: str) -> tuple[np.ndarray, np.ndarray]:
        from pxr import UsdGeom

        from meshcol.io.polygons import PolygonError, TooManyTriangles, triangulate_faces

        points = np.asarray(mesh.GetPointsAttr().Get(self.time) or [], dtype=np.float64).reshape(
            -1, 3
        )
        counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(self.time) or [], dtype=np.int64)
        indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(self.time) or [], dtype=np.int64)
        holes = np.asarray(mesh.GetHoleIndicesAttr().Get(self.time) or [], dtype=np.int64)
        left = mesh.GetOrientationAttr().Get(self.time) == UsdGeom.Tokens.leftHanded
        try:
            faces = triangulate_faces(
                points,
                counts,
                indices,
                holes=holes,
                reverse=left,
                max_triangles=MAX_TRIANGLES - self.triangles,
            )
        except TooManyTriangles:
            raise self.error(f"stage has more than {MAX_TRIANGLES} triangles") from None
        except PolygonError as error:
            raise self.error(f"cannot parse USD file: {where}: {error}") from None
        self.triangles += len(faces)
        return points, faces

    def _instances(self, instancer: Any, UsdGeom: Any, UsdPhysics: Any) -> None:
        """Every instance of a ``PointInstancer``: its prototypes' geometry placed by the
        instance's transform, each instance a body (``<instancer>/<k>``)."""
        from pxr import Usd

        point = UsdGeom.PointInstancer(instancer)
        xforms = point.ComputeInstanceTransformsAtTime(self.time, self.time)
        targets = point.GetPrototypesRel().GetTargets()
        indices = np.asarray(point.GetProtoIndicesAttr().Get(self.time) or [], dtype=np.int64)
        if len(indices) > MAX_PRIMS:
            raise self.error(f"stage has more than {MAX_PRIMS} prims")
        base = self.world(instancer)
        predicate = Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)
        for k, (proto_index, xform) in enumerate(zip(indices.tolist(), xforms)):
            if not 0 <= proto_index < len(targets):
                raise self.error(
                    f"cannot parse USD file: {instancer.GetPath()}: protoIndices refers to "
                    f"prototype {proto_index}, but it has {len(targets)}"
                )
            root = self.stage.GetPrimAtPath(targets[proto_index])
            placed = base @ _matrix(xform)
            for prim in Usd.PrimRange(root, predicate):
                if prim.GetTypeName() not in ("Mesh", *_PRIMITIVE_TYPES):
                    continue
                if self._collision_state(prim, UsdGeom, UsdPhysics) != "read":
                    continue
                inside = _matrix(self.cache.ComputeRelativeTransform(prim, root.GetParent())[0])
                key = f"{instancer.GetPath()}/{k}"
                if key not in self.groups:
                    self.groups[key] = BodyGroup(
                        key, f"{instancer.GetName()}_{k}", placed, ancestors=_ancestors(instancer)
                    )
                world = placed @ inside
                name = str(prim.GetPath())[len(str(root.GetPath().GetParentPath())) :]
                self.groups[key].elements.append(self._element(prim, name.lstrip("/"), world))


def _ancestors(prim: Any) -> tuple[str, ...]:
    """The names of the prims above ``prim``, from the root down (``/World/crate_01/mesh``:
    ``("World", "crate_01")``), the nearest :data:`~meshcol.io.body_names.MAX_ANCESTORS`."""
    parent = str(prim.GetPath().GetParentPath())
    return tuple(parent.strip("/").split("/")[-MAX_ANCESTORS:]) if parent != "/" else ()


def _primitive(prim: Any, kind: str, UsdGeom: Any, time: Any) -> Primitive:
    """The primitive of a ``Cube``, ``Sphere``, ``Capsule`` or ``Cylinder`` prim in its own
    frame, axis along z (an X or Y axis is turned onto z by :func:`_axis_turn`)."""
    if kind == "Cube":
        size = float(UsdGeom.Cube(prim).GetSizeAttr().Get(time))
        return Box((abs(size),) * 3)
    if kind == "Sphere":
        return Sphere(abs(float(UsdGeom.Sphere(prim).GetRadiusAttr().Get(time))))
    schema = UsdGeom.Capsule(prim) if kind == "Capsule" else UsdGeom.Cylinder(prim)
    radius = abs(float(schema.GetRadiusAttr().Get(time)))
    height = abs(float(schema.GetHeightAttr().Get(time)))
    return Capsule(radius, height) if kind == "Capsule" else Cylinder(radius, height)
