"""meshcol: mesh collision analysis for asset pipelines.

The public API is re-exported here and imported lazily, so ``import meshcol`` (and the
command line's ``--help``) stays fast: trimesh, scipy and the native core load on first use.

Frames and signs are fixed once for the whole package: every point is in the world frame;
``distance >= 0``; penetration ``depth >= 0``; ``signed_distance = distance - depth``; a
``normal`` is a unit vector pointing from shape ``a`` towards shape ``b``.
"""

from __future__ import annotations

import importlib
from typing import Any

from meshcol.errors import (
    InputFileError,
    InvalidMeshError,
    MeshcolError,
    MissingDependencyError,
    SceneError,
)
from meshcol.types import Body, Primitive, Scene, Status, ToiStatus

__version__ = "0.1.0"

# public name -> module that defines it
_LAZY: dict[str, str] = {
    # mesh and scene loading
    "load_mesh": "meshcol.mesh_io",
    "load_scene": "meshcol.scene",
    "load_inputs": "meshcol.scene",
    # hulls and inspection
    "convex_hull": "meshcol.hulls",
    "HullResult": "meshcol.hulls",
    "inspect_body": "meshcol.inspect",
    "MeshInspection": "meshcol.inspect",
    # convex decomposition
    "decompose": "meshcol.decompose",
    "Decomposition": "meshcol.decompose",
    "cached_decomposition": "meshcol.decompose",
    # narrow phase
    "ConvexSet": "meshcol.query",
    "Sphere": "meshcol.query",
    "Box": "meshcol.query",
    "Capsule": "meshcol.query",
    "Cylinder": "meshcol.query",
    "DistanceResult": "meshcol.query",
    "PenetrationResult": "meshcol.query",
    "distance": "meshcol.query",
    "penetration": "meshcol.query",
    "intersects": "meshcol.query",
    "signed_distance": "meshcol.query",
    "distance_batch": "meshcol.query",
    "penetration_batch": "meshcol.query",
    "intersects_batch": "meshcol.query",
    "signed_distance_batch": "meshcol.query",
    "ShapeKind": "meshcol.query",
    "SignedDistanceResult": "meshcol.query",
    "DistanceBatch": "meshcol.query",
    "PenetrationBatch": "meshcol.query",
    "SignedDistanceBatch": "meshcol.query",
    "IntersectsBatch": "meshcol.query",
    # continuous collision
    "TimeOfImpactResult": "meshcol.sweep",
    "TimeOfImpactBatch": "meshcol.sweep",
    "SweepReport": "meshcol.sweep",
    "SweepHit": "meshcol.sweep",
    "interpolate_pose": "meshcol.sweep",
    "time_of_impact": "meshcol.sweep",
    "time_of_impact_batch": "meshcol.sweep",
    # exact triangle-mesh queries
    "MeshSet": "meshcol.mesh_query",
    "MeshDistanceBatch": "meshcol.mesh_query",
    "MeshDistanceResult": "meshcol.mesh_query",
    "MeshIntersectsBatch": "meshcol.mesh_query",
    "mesh_distance": "meshcol.mesh_query",
    "mesh_distance_batch": "meshcol.mesh_query",
    "mesh_intersects_batch": "meshcol.mesh_query",
    # scene checks
    "CheckOptions": "meshcol.check",
    "CheckReport": "meshcol.check",
    # broad phase
    "sort_and_sweep": "meshcol.broadphase",
    "SweepAndPrune": "meshcol.broadphase",
    "AabbTree": "meshcol.broadphase",
    "brute_force_pairs": "meshcol.broadphase",
}

__all__ = [
    "__version__",
    "MeshcolError",
    "InputFileError",
    "InvalidMeshError",
    "SceneError",
    "MissingDependencyError",
    "Body",
    "Primitive",
    "Scene",
    "Status",
    "ToiStatus",
    "check",
    "sweep",
    *_LAZY,
]


# `check` and `sweep` name both a submodule and its main function. The submodules are light
# (numpy only), so import them now and bind the functions afterwards: `meshcol.check(...)`
# then works whatever else was imported first (a later `import meshcol.check` finds the module
# in sys.modules and leaves the package attribute alone).
from meshcol.check import check  # noqa: E402
from meshcol.sweep import sweep  # noqa: E402


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'meshcol' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
