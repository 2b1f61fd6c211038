"""meshcol: mesh collision analysis for asset pipelines.

The public API is re-exported here and imported lazily, so ``import meshcol`` (and the
command line's ``--help``) stays fast: numpy, trimesh, scipy and the native core load on
first use (``tests/test_imports.py`` holds it).

Frames and signs are fixed once for the whole package: every point is in the world frame;
``distance >= 0``; penetration ``depth >= 0``; ``signed_distance = distance - depth``; a
``normal`` is a unit vector pointing from shape ``a`` towards shape ``b``.
"""

from __future__ import annotations

import importlib
from typing import Any

from meshcol._version import __version__
from meshcol.errors import (
    InputFileError,
    InvalidMeshError,
    MeshcolError,
    MissingDependencyError,
    SceneError,
)

# public name -> module that defines it (imported on first use)
_LAZY: dict[str, str] = {
    # bodies, scenes and statuses (meshcol.types imports numpy)
    "Body": "meshcol.types",
    "Box": "meshcol.types",
    "Capsule": "meshcol.types",
    "Cylinder": "meshcol.types",
    "Ellipsoid": "meshcol.types",
    "Primitive": "meshcol.types",
    "Scene": "meshcol.types",
    "Sphere": "meshcol.types",
    "Spin": "meshcol.types",
    "Status": "meshcol.types",
    "TimeOfImpactStatus": "meshcol.types",
    # mesh and scene loading, writing
    "load_mesh": "meshcol.io.mesh_read",
    "load_scene": "meshcol.io.scene",
    "load_inputs": "meshcol.io.scene",
    "load_robot": "meshcol.io.robot",
    "load_robot_model": "meshcol.io.robot",
    "RobotOptions": "meshcol.io.robot",
    "write_meshes": "meshcol.io.mesh_write",
    # hulls and inspection
    "convex_hull": "meshcol.collision.hull",
    "HullResult": "meshcol.collision.hull",
    "hull": "meshcol.analysis.hull",
    "HullReport": "meshcol.analysis.hull",
    "inspect": "meshcol.analysis.inspect",
    "InspectReport": "meshcol.analysis.inspect",
    "inspect_body": "meshcol.analysis.inspect",
    "MeshInspection": "meshcol.analysis.inspect",
    # convex decomposition
    "decompose": "meshcol.decomposition.decompose",
    "cached_decomposition": "meshcol.decomposition.decompose",
    "decompose_files": "meshcol.decomposition.batch",
    "DecomposeOptions": "meshcol.decomposition.options",
    "RunOptions": "meshcol.decomposition.options",
    "DecomposeReport": "meshcol.decomposition.report",
    "Decomposition": "meshcol.decomposition.result",
    "Fidelity": "meshcol.decomposition.result",
    # shapes and the narrow phase
    "ConvexSet": "meshcol.collision.shapes",
    "ShapeKind": "meshcol.collision.shapes",
    "DistanceResult": "meshcol.collision.narrowphase",
    "PenetrationResult": "meshcol.collision.narrowphase",
    "SignedDistanceResult": "meshcol.collision.narrowphase",
    "DistanceBatch": "meshcol.collision.narrowphase",
    "PenetrationBatch": "meshcol.collision.narrowphase",
    "SignedDistanceBatch": "meshcol.collision.narrowphase",
    "IntersectsBatch": "meshcol.collision.narrowphase",
    "distance": "meshcol.collision.narrowphase",
    "penetration": "meshcol.collision.narrowphase",
    "intersects": "meshcol.collision.narrowphase",
    "signed_distance": "meshcol.collision.narrowphase",
    "distance_batch": "meshcol.collision.narrowphase",
    "penetration_batch": "meshcol.collision.narrowphase",
    "intersects_batch": "meshcol.collision.narrowphase",
    "signed_distance_batch": "meshcol.collision.narrowphase",
    # continuous collision
    "TimeOfImpactResult": "meshcol.collision.time_of_impact",
    "TimeOfImpactBatch": "meshcol.collision.time_of_impact",
    "interpolate_pose": "meshcol.collision.time_of_impact",
    "shortest_rotation": "meshcol.collision.time_of_impact",
    "time_of_impact": "meshcol.collision.time_of_impact",
    "time_of_impact_batch": "meshcol.collision.time_of_impact",
    # exact triangle-mesh queries
    "MeshSet": "meshcol.collision.mesh_query",
    "MeshDistanceBatch": "meshcol.collision.mesh_query",
    "MeshDistanceResult": "meshcol.collision.mesh_query",
    "MeshIntersectsBatch": "meshcol.collision.mesh_query",
    "mesh_distance": "meshcol.collision.mesh_query",
    "mesh_distance_batch": "meshcol.collision.mesh_query",
    "mesh_intersects_batch": "meshcol.collision.mesh_query",
    "MeshDepthBatch": "meshcol.collision.mesh_query",
    "mesh_penetration_depth_batch": "meshcol.collision.mesh_query",
    "mesh_intersection_volume": "meshcol.collision.mesh_query",
    "MeshContactsBatch": "meshcol.collision.contacts",
    "mesh_contacts_batch": "meshcol.collision.contacts",
    "MeshRayCastBatch": "meshcol.collision.ray_cast",
    "mesh_ray_cast_batch": "meshcol.collision.ray_cast",
    # broad phase
    "sort_and_sweep": "meshcol.collision.broadphase",
    "SortAndSweep": "meshcol.collision.broadphase",
    "AabbTree": "meshcol.collision.broadphase",
    "brute_force_pairs": "meshcol.collision.broadphase",
    # analyses
    "Colliders": "meshcol.analysis.colliders",
    "build_colliders": "meshcol.analysis.colliders",
    "check": "meshcol.analysis.check",
    "collision_matrix": "meshcol.analysis.collision_matrix",
    "CollisionMatrixReport": "meshcol.analysis.collision_matrix",
    "check_scene": "meshcol.analysis.check",
    "CheckOptions": "meshcol.analysis.check",
    "CheckReport": "meshcol.analysis.check",
    "sweep": "meshcol.analysis.sweep",
    "SweepReport": "meshcol.analysis.sweep",
    "SweepHit": "meshcol.analysis.sweep",
}

__all__ = [
    "__version__",
    "MeshcolError",
    "InputFileError",
    "InvalidMeshError",
    "SceneError",
    "MissingDependencyError",
    *_LAZY,
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'meshcol' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
