"""What a decomposition is: its parts, its fidelity metrics and how it was made."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Decomposition", "Fidelity"]


@dataclass(frozen=True)
class Fidelity:
    """How faithfully the parts approximate the mesh.

    Attributes
    ----------
    parts : int
        Number of convex parts.
    vertices_per_part : tuple of int
        Hull vertex count of each part, in part order.
    mesh_volume : float or None
        Volume of the mesh (manifold3d; None when the mesh does not bound a volume).
    union_volume : float
        Volume of the union of the parts (manifold3d boolean union of the part hulls).
    volume_ratio : float or None
        ``union_volume / mesh_volume``.
    hausdorff_mesh_to_parts : float
        Largest distance from a sampled point of the mesh surface (or a mesh vertex) to the
        union of the parts, 0 inside a part (:func:`meshcol.collision.narrowphase.
        distance_batch`): how far the parts fall short of the mesh.
    hausdorff_parts_to_mesh : float
        Largest distance from a sampled point (or vertex) of the boundary of the union of the
        parts to the mesh: to its solid (0 inside) when ``mesh_is_solid``, else to its surface.
        How far the parts stick out; cuts and gaps between parts inside the mesh count 0
        (:func:`meshcol.decomposition.fidelity.fidelity` has the definitions).
    uncovered_fraction : float
        Fraction of the sampled mesh surface points farther than ``tolerance`` from the union.
    tolerance : float
        Coverage tolerance, in mesh units.
    samples : int
        Points sampled on the mesh surface (the parts get as many).
    mesh_is_solid : bool
        The mesh is closed and consistently wound
        (:func:`meshcol.geometry.topology.is_closed_manifold`), so it bounds a solid.
    """

    parts: int
    vertices_per_part: tuple[int, ...]
    mesh_volume: float | None
    union_volume: float
    volume_ratio: float | None
    hausdorff_mesh_to_parts: float
    hausdorff_parts_to_mesh: float
    uncovered_fraction: float
    tolerance: float
    samples: int
    mesh_is_solid: bool

    def to_dict(self) -> dict[str, Any]:
        return {
            "parts": self.parts,
            "vertices_per_part": list(self.vertices_per_part),
            "mesh_volume": self.mesh_volume,
            "union_volume": self.union_volume,
            "volume_ratio": self.volume_ratio,
            "hausdorff_mesh_to_parts": self.hausdorff_mesh_to_parts,
            "hausdorff_parts_to_mesh": self.hausdorff_parts_to_mesh,
            "uncovered_fraction": self.uncovered_fraction,
            "tolerance": self.tolerance,
            "samples": self.samples,
            "mesh_is_solid": self.mesh_is_solid,
        }


@dataclass(frozen=True, eq=False)
class Decomposition:
    """A convex decomposition of one mesh.

    Attributes
    ----------
    parts : tuple of ((n_i, 3) float64, (m_i, 3) int64)
        Convex parts as (vertices, faces), in the input's frame; each part is its own convex
        hull with outward-oriented triangles. Sorted by centroid (x, y, z), then volume.
    engine : str
        ``"coacd"`` or ``"vhacd"``.
    engine_version : str
        Installed version of the engine's package.
    params : dict
        The engine parameters used, after defaults and ``auto`` were resolved.
    cache_key : str
        sha256 hex digest of the canonical geometry, engine, engine version and parameters.
    metrics : Fidelity or None
        Fidelity metrics, unless they were turned off.
    repaired : bool
        True when the input was not a closed, consistently oriented manifold and the engine's
        preprocessing rebuilt it (CoACD ``preprocess_mode="on"``).
    notes : tuple of str
        Remarks for the report (repairs, dropped flat parts, vertex budgets enforced).
    from_cache : bool
        True when this result was read from the cache.
    """

    parts: tuple[tuple[np.ndarray, np.ndarray], ...]
    engine: str
    engine_version: str
    params: Mapping[str, Any]
    cache_key: str
    metrics: Fidelity | None = None
    repaired: bool = False
    notes: tuple[str, ...] = ()
    from_cache: bool = field(default=False, compare=False)

    def meshes(self) -> list[Any]:
        """The parts as ``trimesh.Trimesh`` objects."""
        import trimesh

        return [trimesh.Trimesh(v, f, process=False) for v, f in self.parts]
