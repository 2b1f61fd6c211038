"""USD written around rebuilt colliders (``usd-core``, ``pip install 'meshcol[usd]'``).

One ``Xform`` per link with its world pose at the joint configuration; one ``Mesh`` per part
with ``UsdPhysics.CollisionAPI`` and ``UsdPhysics.MeshCollisionAPI`` (approximation
``convexHull``: every part is convex), and primitives as ``Cube``/``Sphere``/``Cylinder``/
``Capsule`` prims with ``CollisionAPI`` (USD has no ellipsoid: one is written as its
tessellation, a convex ``Mesh``); Z up, metres. The format module of
:func:`meshcol.io.robot_write.write_robot`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from meshcol.errors import MissingDependencyError
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Sphere

if TYPE_CHECKING:
    from meshcol.io.robot_write import Collider, RobotColliders

__all__ = ["require_usd", "write_usd"]


def require_usd(source: str) -> None:
    """usd-core is installed, or the install hint (before any work)."""
    try:
        import pxr  # noqa: F401
    except ImportError:
        raise MissingDependencyError(
            "--to usd needs usd-core (pip install 'meshcol[usd]')", source
        ) from None


def _usd_name(name: str) -> str:
    """A valid USD prim name: letters, digits and ``_``, not starting with a digit."""
    cleaned = re.sub(r"\W", "_", name, flags=re.ASCII) or "_"
    return "_" + cleaned if cleaned[0].isdigit() else cleaned


def write_usd(robot: RobotColliders, labels: list[list[str]], path: str) -> None:
    """One Xform per link (world pose), one collision prim per part, as a ``.usda`` file
    (``labels``: the prim names of each collider's parts)."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    from meshcol.io.report import atomic_path

    with atomic_path(path) as tmp:
        stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        root = UsdGeom.Xform.Define(stage, Sdf.Path("/" + _usd_name(Path(robot.source).stem)))
        stage.SetDefaultPrim(root.GetPrim())
        links: dict[str, Any] = {}
        for collider, names in zip(robot.colliders, labels):
            xform = links.get(collider.link)
            if xform is None:
                xform = UsdGeom.Xform.Define(
                    stage, root.GetPath().AppendChild(_unique(links, _usd_name(collider.link)))
                )
                xform.AddTransformOp().Set(_usd_matrix(Gf, robot.link_poses[collider.link]))
                xform.GetPrim().SetCustomDataByKey("meshcol:link", collider.link)
                links[collider.link] = xform
            parent = xform.GetPath()
            parts = list(zip(names, collider.parts))
            if isinstance(collider.primitive, Ellipsoid):
                parts = [(names[0], _ellipsoid_part(collider))]
            elif collider.primitive is not None:
                prim = _usd_primitive(
                    stage, UsdGeom, Gf, parent.AppendChild(_usd_name(names[0])), collider
                )
                UsdPhysics.CollisionAPI.Apply(prim)
                continue
            for label, (v, f) in parts:
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


def _ellipsoid_part(collider: Collider) -> tuple[np.ndarray, np.ndarray]:
    """An ellipsoid collider's tessellation in the link frame (USD has no ellipsoid prim):
    the description's own ellipsoid inscribed, as read; a fitted one (``meshcol fit``) by
    the mesh that contains it, so that the file encloses what the fit enclosed."""
    from meshcol.io.primitives import enclosing_primitive_mesh, primitive_mesh

    assert collider.primitive is not None
    tessellate = enclosing_primitive_mesh if collider.fitted else primitive_mesh
    vertices, faces = tessellate(collider.primitive)
    origin = collider.origin
    return vertices @ origin[:3, :3].T + origin[:3, 3], faces


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
