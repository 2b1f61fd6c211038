"""Mesh health checks: topology, degeneracies, self-intersections and a guess at the units.

:func:`inspect_body` answers "is this mesh fit to be a collider?": is it closed, consistently
wound, free of degenerate, duplicate and non-manifold faces and of self-intersections, in one
piece, and plausibly in metres.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from meshcol.analysis.rules import Finding, get_rule
from meshcol.errors import InvalidMeshError
from meshcol.geometry.mass import MassProperties
from meshcol.geometry.topology import (
    component_count,
    duplicate_face_count,
    edge_table,
    oriented_volume,
)
from meshcol.geometry.triangles import degenerate_faces, face_heights
from meshcol.io.report import vector_columns
from meshcol.io.robot import RobotOptions
from meshcol.types import Body

__all__ = [
    "InspectReport",
    "MeshInspection",
    "RULES",
    "PhysicsOptions",
    "inspect",
    "inspect_body",
    "guess_units",
]

#: The mesh-health findings of :func:`inspect_body`, by name (ids MC401..MC409 in
#: :mod:`meshcol.analysis.rules`, in this order).
RULES: tuple[str, ...] = (
    "not-watertight",
    "self-intersecting",
    "inconsistent-winding",
    "inverted",
    "degenerate-faces",
    "non-manifold",
    "duplicate-faces",
    "multiple-components",
    "suspect-units",
)
#: The rule id of each mesh-health finding.
HEALTH_IDS = {name: get_rule(name).id for name in RULES}
#: Largest extent, in units, above which a body is probably in millimetres, not metres
#: (a 400-unit chair), and above which no unit makes it a plausible single asset.
MILLIMETRE_EXTENT = 100.0
IMPLAUSIBLE_EXTENT = 10_000.0
#: Below this largest extent a body in metres would be under a centimetre.
TINY_EXTENT = 0.01


@dataclass(frozen=True)
class MeshInspection:
    """Findings on one body's mesh.

    Attributes
    ----------
    name, source : str, str or None
        The body and the file it came from.
    vertices, faces : int
        Counts (after the loader merged duplicate vertices).
    components : int
        Connected pieces (faces linked through shared vertices).
    watertight : bool
        Every edge has exactly two faces.
    winding_consistent : bool
        Every edge shared by two faces is traversed in opposite directions by them.
    volume : float or None
        Signed volume (positive when the faces point outward), only when the mesh is
        watertight and consistently wound; None otherwise (it would mean nothing). A negative
        volume is the ``inverted`` finding: the mesh is inside out.
    bounds : (2, 3) list of float
        World-frame axis-aligned bounding box, ``[min, max]``.
    size : (3,) list of float
        ``max - min``.
    degenerate_faces : int
        Faces with repeated vertices or a height at most ``DEGENERATE_RELATIVE_HEIGHT`` of
        the bounding-box diagonal.
    duplicate_faces : int
        Faces on the same three vertices as an earlier face (either winding).
    boundary_edges, non_manifold_edges : int
        Edges with one face; edges with more than two faces.
    inconsistent_edges : int
        Edges with two faces that traverse them in the same direction.
    self_intersecting : bool
        Two faces cross: their open triangles share a point (see
        :mod:`meshcol.collision.self_intersection`; decided exactly). Faces that only touch,
        along shared vertices and edges or elsewhere, do not cross.
    self_intersecting_pairs : int
        Pairs of faces that cross (degenerate faces left out).
    manifold_status : str
        ``manifold3d.Manifold``'s verdict on the mesh (``NoError``, ``NotManifold``, ...).
    units_guess : str
        ``"m"``, ``"mm"`` or ``"unknown"`` (see :func:`guess_units`).
    units_reason : str
        Why.
    declared_units : str or None
        Units the scene declared, when it did.
    findings : list of str
        The rules of :data:`RULES` this mesh breaks.
    """

    name: str
    source: str | None
    vertices: int
    faces: int
    components: int
    watertight: bool
    winding_consistent: bool
    volume: float | None
    bounds: list
    size: list
    degenerate_faces: int
    duplicate_faces: int
    boundary_edges: int
    non_manifold_edges: int
    inconsistent_edges: int
    self_intersecting: bool
    self_intersecting_pairs: int
    manifold_status: str
    units_guess: str
    units_reason: str
    declared_units: str | None = None
    findings: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """Plain JSON-ready dictionary of every field."""
        return asdict(self)


def inspect_body(body: Body, declared_units: str | None = None) -> MeshInspection:
    """Inspect one body's mesh.

    Parameters
    ----------
    body : Body
        Its ``vertices`` (local frame) and ``faces``; the bounding box and unit guess use
        the world frame (``body.pose`` applied).
    declared_units : str, optional
        Units a scene manifest declared (``"m"``, ``"mm"``, ...): ``suspect-units`` then
        fires when the guess disagrees. Without it, anything but a metre-sized body is
        suspect.

    Returns
    -------
    MeshInspection

    Raises
    ------
    InvalidMeshError
        The body has no faces or non-finite coordinates.

    Notes
    -----
    Topology comes from the edge table: each undirected edge with its face count (1:
    boundary, 2: manifold, > 2: non-manifold) and, for two-face edges, whether the faces
    traverse it in opposite directions (consistent winding). The volume and orientation come
    from :func:`meshcol.geometry.topology.oriented_volume` (divergence theorem); a closed mesh
    whose faces point inward is ``inverted`` (``meshcol hull`` is unaffected and says so;
    ``meshcol decompose`` reverses its faces before the engine runs). manifold3d's
    ``Manifold(Mesh64)`` status is reported as a second opinion on the topology; manifold3d
    assumes (and does not check) that its input is free of self-intersections, so those come
    from :func:`meshcol.collision.self_intersection.self_intersecting_pairs`, in the core.
    """
    return _inspect_instance(body, declared_units, _Geometries())


class _Geometry:
    """One mesh's vertices and faces (its local frame) and what they alone decide, each
    measured on first use.

    The bodies that instance one mesh share one (:class:`_Geometries`), so a level of
    instanced props is measured once per prop. Nothing here depends on a body's name, source,
    pose or units; what does (bounds, size, which faces are degenerate and so which cross, the
    units guess, every finding's names) each body computes itself.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.vertices = vertices
        self.faces = faces
        # crossing face pairs per degenerate-face mask (a mask follows the body's diagonal)
        self._crossings: dict[bytes, int] = {}

    @cached_property
    def used(self) -> np.ndarray:
        """(k,) int64: the vertices the faces use, ascending."""
        return np.unique(self.faces)

    @cached_property
    def heights(self) -> tuple[np.ndarray, np.ndarray]:
        """:func:`meshcol.geometry.triangles.face_heights`."""
        return face_heights(self.vertices, self.faces)

    @cached_property
    def edges(self) -> tuple[int, int, int]:
        """Boundary edges (one face), non-manifold edges (more than two), inconsistently
        wound edges."""
        _, counts, inconsistent = edge_table(self.faces)
        return int((counts == 1).sum()), int((counts > 2).sum()), int(inconsistent)

    @cached_property
    def oriented_volume(self) -> tuple[float, int] | None:
        """:func:`meshcol.geometry.topology.oriented_volume`."""
        return oriented_volume(self.vertices, self.faces)

    @cached_property
    def duplicates(self) -> int:
        return duplicate_face_count(self.faces)

    @cached_property
    def components(self) -> int:
        return component_count(self.faces, len(self.vertices))

    @cached_property
    def manifold_status(self) -> str:
        return _manifold_status(self.vertices, self.faces)

    @cached_property
    def hull_volume(self) -> float | None:
        """The volume of the vertices' exact hull; None when they have none."""
        from meshcol.collision.hull import exact_hull

        try:
            return exact_hull(self.vertices).volume
        except InvalidMeshError:
            return None

    @cached_property
    def mass(self) -> MassProperties:
        """:func:`meshcol.geometry.mass.mass_properties`, in the local frame."""
        from meshcol.geometry.mass import mass_properties

        return mass_properties(self.vertices, self.faces)

    def crossings(self, skip: np.ndarray) -> int:
        """Pairs of faces that cross, the faces of ``skip`` ((m,) bool) left out."""
        key = skip.tobytes()
        count = self._crossings.get(key)
        if count is None:
            from meshcol.collision.self_intersection import self_intersecting_pairs

            pairs = self_intersecting_pairs(self.vertices, self.faces, skip=skip)
            count = self._crossings[key] = len(pairs)
        return count


class _Geometries:
    """The :class:`_Geometry` of each mesh of one inspect run, shared by the bodies (and the
    health and physics phases) that use it: found by the arrays themselves first (a file's
    instances share their arrays), else by content
    (:func:`meshcol.analysis.colliders._geometry_key`: the same bits), so each pair of
    arrays is hashed once."""

    def __init__(self) -> None:
        self._by_key: dict[bytes, _Geometry] = {}
        # id pair -> (geometry, vertices, faces): the arrays are held, so the ids stay theirs
        self._by_arrays: dict[tuple[int, int], tuple[_Geometry, np.ndarray, np.ndarray]] = {}

    def get(self, vertices: np.ndarray, faces: np.ndarray) -> _Geometry:
        seen = self._by_arrays.get((id(vertices), id(faces)))
        if seen is not None:
            return seen[0]
        from meshcol.analysis.colliders import _geometry_key

        key = _geometry_key(vertices, faces)
        geometry = self._by_key.get(key)
        if geometry is None:
            geometry = self._by_key[key] = _Geometry(vertices, faces)
        self._by_arrays[id(vertices), id(faces)] = (geometry, vertices, faces)
        return geometry


def _inspect_instance(
    body: Body, declared_units: str | None, geometries: _Geometries
) -> MeshInspection:
    """:func:`inspect_body`, with what the mesh alone decides shared through ``geometries``
    by the bodies that instance it."""
    vertices = np.asarray(body.vertices, dtype=np.float64)
    faces = np.asarray(body.faces, dtype=np.int64)
    if len(faces) == 0:
        raise InvalidMeshError(f"body '{body.name}': mesh has no faces", body.source)
    if not np.isfinite(vertices).all():
        raise InvalidMeshError(
            f"body '{body.name}': vertices contain NaN or infinite coordinates", body.source
        )
    mesh = geometries.get(vertices, faces)

    used = body.world_vertices()[mesh.used]
    lo, hi = used.min(axis=0), used.max(axis=0)
    size = hi - lo
    diagonal = float(np.linalg.norm(size))

    boundary, non_manifold, inconsistent = mesh.edges
    watertight = boundary == 0 and non_manifold == 0
    winding_consistent = inconsistent == 0
    measured = mesh.oriented_volume if watertight and winding_consistent else None
    volume = None if measured is None else measured[0]
    inverted = measured is not None and measured[1] < 0

    # relative to the world diagonal, so a body's own: its rotation changes its bounding box
    degenerate = degenerate_faces(vertices, faces, diagonal, heights=mesh.heights)
    crossings = mesh.crossings(degenerate)
    units, reason = guess_units(float(size.max()))

    findings = []
    if not watertight:
        findings.append("not-watertight")
    if crossings:
        findings.append("self-intersecting")
    if not winding_consistent:
        findings.append("inconsistent-winding")
    if inverted:
        findings.append("inverted")
    if degenerate.any():
        findings.append("degenerate-faces")
    if non_manifold:
        findings.append("non-manifold")
    if mesh.duplicates:
        findings.append("duplicate-faces")
    if mesh.components > 1:
        findings.append("multiple-components")
    if _units_suspect(units, declared_units):
        findings.append("suspect-units")

    return MeshInspection(
        name=body.name,
        source=body.source,
        vertices=len(vertices),
        faces=len(faces),
        components=mesh.components,
        watertight=watertight,
        winding_consistent=winding_consistent,
        volume=volume,
        bounds=[lo.tolist(), hi.tolist()],
        size=size.tolist(),
        degenerate_faces=int(degenerate.sum()),
        duplicate_faces=mesh.duplicates,
        boundary_edges=boundary,
        non_manifold_edges=non_manifold,
        inconsistent_edges=inconsistent,
        self_intersecting=bool(crossings),
        self_intersecting_pairs=crossings,
        manifold_status=mesh.manifold_status,
        units_guess=units,
        units_reason=reason,
        declared_units=declared_units,
        findings=findings,
    )


def guess_units(largest_extent: float) -> tuple[str, str]:
    """Guess a mesh's length unit from its largest extent.

    Parameters
    ----------
    largest_extent : float
        Largest side of the bounding box, in file units.

    Returns
    -------
    (units, reason) : (str, str)
        ``"m"``, ``"mm"`` or ``"unknown"``, and a one-line reason.

    Notes
    -----
    Assets are usually between a centimetre and a hundred metres. Between
    ``MILLIMETRE_EXTENT`` (100) and ``IMPLAUSIBLE_EXTENT`` (10,000) units, metres would make
    a stadium-sized prop while millimetres make a 0.1 to 10 m object: a 400-unit chair is
    millimetres. Centimetre files (Unreal) fall in the same band and are reported as
    millimetres: either way the file is not in metres, which is what the check is for.
    """
    e = largest_extent
    if e > IMPLAUSIBLE_EXTENT:
        return "unknown", f"largest extent {e:.6g} units: over 10 m even in millimetres"
    if e > MILLIMETRE_EXTENT:
        return (
            "mm",
            f"largest extent {e:.6g} units: {e / 1000:.3g} m in millimetres, over 100 m in metres",
        )
    if e < TINY_EXTENT:
        return "unknown", f"largest extent {e:.6g} units: under 1 cm in metres"
    return "m", f"largest extent {e:.6g} units: a plausible size in metres"


_UNIT_ALIASES = {
    "m": "m",
    "meter": "m",
    "meters": "m",
    "metre": "m",
    "metres": "m",
    "mm": "mm",
    "millimeter": "mm",
    "millimeters": "mm",
    "millimetre": "mm",
    "millimetres": "mm",
}


def _units_suspect(guess: str, declared: str | None) -> bool:
    if guess == "unknown":
        return True
    if declared is None:
        return guess != "m"
    declared_unit = _UNIT_ALIASES.get(declared.strip().lower())
    # a declared unit the heuristic does not know (cm, inch) cannot be contradicted
    return declared_unit is not None and declared_unit != guess


def _manifold_status(vertices: np.ndarray, faces: np.ndarray) -> str:
    import manifold3d

    mesh = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(vertices),
        tri_verts=np.ascontiguousarray(faces, dtype=np.uint64),
    )
    status = manifold3d.Manifold(mesh).status()
    return str(getattr(status, "name", status)).split(".")[-1]


def health_findings(result: MeshInspection, body: str, part: str | None) -> list[Finding]:
    """The mesh-health findings of one inspection as records (rules MC401..MC409).

    Parameters
    ----------
    result : MeshInspection
    body, part : str, str or None
        The names the records carry (a manifest body's part is inspected as its own mesh).
    """
    from meshcol.analysis.rules import finding

    extent = float(max(result.size))
    if extent > IMPLAUSIBLE_EXTENT:
        units_limit = IMPLAUSIBLE_EXTENT
    elif extent < TINY_EXTENT:
        units_limit = TINY_EXTENT
    else:
        units_limit = MILLIMETRE_EXTENT
    r = result
    measures: dict[str, tuple[Any, Any, str]] = {
        "not-watertight": (
            r.boundary_edges + r.non_manifold_edges,
            0,
            f"open: {r.boundary_edges} boundary and {r.non_manifold_edges} non-manifold edges",
        ),
        "self-intersecting": (
            r.self_intersecting_pairs,
            0,
            f"{r.self_intersecting_pairs} pairs of faces cross",
        ),
        "inconsistent-winding": (
            r.inconsistent_edges,
            0,
            f"{r.inconsistent_edges} edges traversed the same way by both their faces",
        ),
        "inverted": (r.volume, 0, f"inside out: volume {r.volume:.6g}" if r.volume else ""),
        "degenerate-faces": (r.degenerate_faces, 0, f"{r.degenerate_faces} degenerate faces"),
        "non-manifold": (r.non_manifold_edges, 0, f"{r.non_manifold_edges} edges with > 2 faces"),
        "duplicate-faces": (r.duplicate_faces, 0, f"{r.duplicate_faces} duplicate faces"),
        "multiple-components": (r.components, 1, f"{r.components} disconnected pieces"),
        "suspect-units": (extent, units_limit, r.units_reason),
    }
    return [finding(HEALTH_IDS[name], body, part, *measures[name]) for name in r.findings]


# ---------------------------------------------------------------------------------------------
# Physics readiness: the collider's mass properties against the visual mesh's


@dataclass(frozen=True)
class PhysicsOptions:
    """How :func:`physics_readiness` builds colliders and what it tolerates.

    Attributes
    ----------
    shape : str
        The collider of each body (:data:`meshcol.analysis.colliders.COLLIDER_KINDS`, as
        ``check --shape``; a manifest body's own ``shape`` wins).
    volume_ratio : float
        MC205 fires when collider volume / visual volume is above this or below its inverse.
    com_offset : float
        MC206 fires when the centres of mass are further apart than this fraction of the
        visual mesh's bounding-box diagonal.
    inertia_ratio : float
        MC207 fires when matching principal moments per unit mass differ by more than this
        factor.
    min_relative_volume : float
        MC202 fires for a convex part whose volume is below this fraction of the cube of
        its bounding-box diagonal (or that is flat by the flatness rule).
    min_volume : float
        MC203 fires for a collider of a positive volume below this (cubic units).
    decompose_options : dict
        For ``decomposed`` colliders (engine, cache_dir, ...).
    target : meshcol.io.targets.Target, optional
        An engine profile: the collider's convex parts are measured against its limits
        (:func:`meshcol.analysis.rules.target_findings`, MC101..MC107, MC201).
    """

    shape: str = "hull"
    volume_ratio: float = 2.0
    com_offset: float = 0.05
    inertia_ratio: float = 1.5
    min_relative_volume: float = 1e-6
    min_volume: float = 1e-15
    decompose_options: dict = field(default_factory=dict)
    target: Any = None

    def validate(self) -> None:
        from meshcol.analysis.colliders import COLLIDER_KINDS

        if self.shape not in COLLIDER_KINDS:
            raise ValueError(
                f"shape must be one of {', '.join(COLLIDER_KINDS)}, got {self.shape!r}"
            )
        for name in ("volume_ratio", "inertia_ratio"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 1.0):
                raise ValueError(f"{name} must be a finite number >= 1, got {value!r}")
        for name in ("com_offset", "min_relative_volume", "min_volume"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")

    def settings(self) -> dict[str, Any]:
        return {
            "shape": self.shape,
            "volume_ratio": self.volume_ratio,
            "com_offset": self.com_offset,
            "inertia_ratio": self.inertia_ratio,
            "min_relative_volume": self.min_relative_volume,
            "min_volume": self.min_volume,
            **(
                {}
                if self.target is None
                else {"target": self.target.name, "target_limits": dict(self.target.limits)}
            ),
        }


#: A UCX_ part whose volume is below this fraction of its hull's is not convex (MC303).
UCX_CONVEX_FRACTION = 0.99


def _mass_dict(p: MassProperties | None) -> dict[str, Any] | None:
    """JSON-ready mass properties (non-finite numbers as None)."""
    if p is None:
        return None

    def clean(a: np.ndarray) -> Any:
        a = np.asarray(a, dtype=np.float64)
        if not np.all(np.isfinite(a)):
            return None
        return a.tolist()

    return {
        "volume": p.volume,
        "center_of_mass": clean(p.center_of_mass),
        "inertia": clean(p.inertia),
        "principal_inertia": clean(p.principal_inertia()),
        "area": p.area,
        "shell_center_of_mass": clean(p.shell_center_of_mass),
        "shell_inertia": clean(p.shell_inertia),
        "shell_principal_inertia": clean(p.principal_inertia(shell=True)),
    }


def _moment_ratio(a: MassProperties, b: MassProperties) -> float | None:
    """Largest ratio (>= 1) of the sorted principal moments per unit mass of two solids."""
    if a.volume == 0 or b.volume == 0:
        return None
    pa = a.principal_inertia() / a.volume
    pb = b.principal_inertia() / b.volume
    if not (np.all(np.isfinite(pa)) and np.all(np.isfinite(pb))):
        return None
    pa, pb = np.sort(np.abs(pa)), np.sort(np.abs(pb))
    if np.any(pa <= 0) or np.any(pb <= 0):
        return None
    return float(np.max(np.maximum(pa / pb, pb / pa)))


def _hull_mass(points: np.ndarray) -> tuple[int, tuple[MassProperties, float] | None]:
    """A convex part's hull dimension (0 when the points have no hull) and, in 3-D, its mass
    properties (the points' frame) and its volume over its diagonal cubed (MC202)."""
    from meshcol.collision.hull import exact_hull
    from meshcol.geometry.mass import mass_properties

    try:
        hull = exact_hull(points)
    except InvalidMeshError:
        return 0, None
    if hull.dimension < 3:
        return hull.dimension, None
    mass = mass_properties(hull.vertices, hull.faces)
    return hull.dimension, (mass, mass.volume / hull.diagonal**3)


def physics_readiness(
    bodies: Sequence[Body],
    options: PhysicsOptions | None = None,
    *,
    visuals: dict[str, Body] | None = None,
    progress: Callable[[str], None] | None = None,
    units: str | None = None,
    _geometries: _Geometries | None = None,
) -> tuple[list[dict[str, Any]], list[Finding]]:
    """Each body's collider against its visual mesh: mass properties and their findings.

    Parameters
    ----------
    bodies : sequence of Body
        A scene's bodies, ``UCX_`` parts included (they become their owner's collider, as
        in check).
    options : PhysicsOptions, optional
    visuals : dict of str to Body, optional
        A robot's visual geometry per link (:func:`meshcol.io.robot.load_robot` with
        ``visual=True``); the bodies are then its links' collision geometry. Without it,
        a body's visual mesh is its own render geometry (its mesh, less its ``UCX_`` parts).
    units : str, optional
        The scene's units, for a ``target``'s lengths and volumes.

    Returns
    -------
    rows : list of dict
        Per collider body: ``body``, ``collider`` (kind), ``convex_parts``,
        ``visual_source`` (``visual``, ``mesh``, ``primitive``, ``collision`` for a robot
        link without visual geometry, None when there is none), ``comparison`` (``solid``
        when the visual mesh is closed, ``shell`` when it is open, None), ``collider_mass``
        and ``visual_mass`` (:class:`MassProperties` as a dict: world frame, about the
        centre of mass, density 1), ``volume_ratio``, ``center_of_mass_offset`` (over the
        visual bounding-box diagonal), ``inertia_ratio``.
    findings : list of Finding
        MC202..MC207 and MC301..MC303; with ``options.target``, MC101..MC107 and MC201
        first.

    Notes
    -----
    The collider is :func:`meshcol.analysis.colliders.build_colliders`'s, the one every
    command uses: each convex part's exact hull (the core's) or its exact primitive, its
    mass properties from :func:`meshcol.geometry.mass.mass_properties` (signed tetrahedra)
    or :func:`~meshcol.geometry.mass.primitive_mass_properties`, summed over the parts as
    engines sum a body's shapes (overlaps count twice). A ``mesh`` collider is its triangles.
    A mesh's and a convex part's properties in their own frame are computed once per unique
    geometry and moved by each body's pose, as for a body alone: bodies that instance one
    prop cost one measurement.
    """
    from meshcol.analysis.colliders import _UCX, _geometry_key, build_colliders, split_ucx
    from meshcol.analysis.rules import finding
    from meshcol.collision.shapes import ShapeKind
    from meshcol.geometry.mass import combine_mass_properties, primitive_mass_properties

    options = options or PhysicsOptions()
    options.validate()
    findings: list[Finding] = []
    robot = visuals is not None
    original = {b.name for b in bodies}
    # What a mesh or a convex part decides in its own frame, once per geometry: instances
    # share it and apply their own poses, in the order of operations of one body alone.
    # (inspect passes the ones its health phase measured: _geometries)
    geometries = _geometries if _geometries is not None else _Geometries()
    hulls: dict[bytes, tuple[int, tuple[MassProperties, float] | None]] = {}

    # Authored collision triangles: inside out (MC204), UCX parts not convex (MC303).
    for body in bodies:
        for name, v, f in body.part_meshes():
            own = name if name is not None else body.name.rpartition("/")[2]
            is_ucx = bool(_UCX.match(own))
            authored = is_ucx or (robot and body.primitive is None) or options.shape == "mesh"
            if not authored or body.primitive is not None:
                continue
            geometry = geometries.get(v, f)
            measured = geometry.oriented_volume
            if measured is None:
                continue
            volume, orientation = measured
            if orientation < 0:
                what = "UCX_ part" if is_ucx else "collision mesh"
                findings.append(
                    finding(
                        "MC204",
                        body.name,
                        name,
                        volume,
                        0.0,
                        f"{what} is inside out: volume {volume:.6g}",
                    )
                )
            elif orientation > 0 and is_ucx:
                hull_volume = geometry.hull_volume
                if hull_volume is None:
                    continue
                if hull_volume > 0 and volume / hull_volume < UCX_CONVEX_FRACTION:
                    fraction = volume / hull_volume
                    findings.append(
                        finding(
                            "MC303",
                            body.name,
                            name,
                            fraction,
                            UCX_CONVEX_FRACTION,
                            f"UCX_ part is not convex: {fraction:.1%} of its hull's volume",
                        )
                    )

    colliders = build_colliders(
        bodies,
        options.shape,
        mesh_parts="hull",
        decompose_options=options.decompose_options,
        progress=progress,
    )
    if options.target is not None:
        from meshcol.analysis.rules import target_findings

        findings.extend(target_findings(colliders, options.target, units))
    _, ucx, _ = split_ucx(bodies)
    shapes = colliders.shapes
    offsets = colliders.body_part_offsets
    rows: list[dict[str, Any]] = []
    for i, body in enumerate(colliders.bodies):
        kind = colliders.kinds[i]
        parts = range(int(offsets[i]), int(offsets[i + 1]))
        render = [n for n in body.parts if not _UCX.match(n)]
        grouped = body.name not in original  # loose UCX_ parts naming nothing
        orphans = (
            list(body.parts)
            if grouped
            else [
                n
                for n in body.parts
                if (m := _UCX.match(n)) and m["body"] != body.name and m["body"] not in render
            ]
        )
        for name in orphans:
            findings.append(
                finding(
                    "MC302",
                    body.name,
                    name,
                    None,
                    None,
                    f"UCX_ part {name!r} names no body or part "
                    f"{_UCX.match(name)['body']!r}: it collides for nothing",  # type: ignore[index]
                )
            )

        # MC301: a UCX scene's body (or part) without UCX_ parts
        if ucx and not grouped and body.primitive is None:
            owned = ucx.get(body.name)
            if owned is None:
                findings.append(
                    finding(
                        "MC301",
                        body.name,
                        None,
                        0,
                        1,
                        "the input has UCX_ colliders, this body has none: the engine makes "
                        "its own collider, or none",
                    )
                )
            elif not owned.whole:
                covered = {label for label, _ in owned.parts}
                for label, name in enumerate(body.parts):
                    if label not in covered and not _UCX.match(name):
                        findings.append(
                            finding(
                                "MC301",
                                body.name,
                                name,
                                0,
                                1,
                                f"part {name!r} has no UCX_{name}_NN part while its body has "
                                "UCX_ colliders",
                            )
                        )

        # the collider's mass properties, part by part, in the body frame
        masses = []
        if kind == "mesh":
            masses.append(geometries.get(body.vertices, body.faces).mass)
        for k in parts if kind != "mesh" else ():
            label = int(colliders.part_label[k])
            part_name = body.parts[label] if label >= 0 else None
            start, end = int(shapes.offsets[k]), int(shapes.offsets[k + 1])
            what = f"convex part {int(colliders.part_index[k])}" + (
                "" if part_name is None else f" of part {part_name!r}"
            )
            if int(shapes.kinds[k]) == ShapeKind.POLYTOPE:
                points = shapes.vertices[start:end]
                key = _geometry_key(points)
                measured_hull = hulls.get(key)
                if measured_hull is None:
                    measured_hull = hulls[key] = _hull_mass(points)
                dimension, solid = measured_hull
                if solid is None:
                    shape_name = ("a point", "a segment", "flat")[dimension]
                    findings.append(
                        finding(
                            "MC202",
                            body.name,
                            part_name,
                            0.0,
                            options.min_relative_volume,
                            f"{what} is {shape_name}: no volume",
                        )
                    )
                    continue
                mass, relative = solid
                if relative < options.min_relative_volume:
                    findings.append(
                        finding(
                            "MC202",
                            body.name,
                            part_name,
                            relative,
                            options.min_relative_volume,
                            f"{what} is nearly flat: volume {mass.volume:.3g}, "
                            f"{relative:.3g} of its diagonal cubed",
                        )
                    )
            else:
                primitive = shapes.primitive(k)
                assert primitive is not None  # a part without vertices is a primitive
                mass = primitive_mass_properties(primitive)
            if colliders.part_offsets is not None:
                mass = mass.transformed(colliders.part_offsets[k])
            masses.append(mass)
        collider = combine_mass_properties(masses).transformed(body.pose) if masses else None
        if collider is not None and 0.0 < collider.volume < options.min_volume:
            findings.append(
                finding(
                    "MC203",
                    body.name,
                    None,
                    collider.volume,
                    options.min_volume,
                    f"collider volume {collider.volume:.3g} is below {options.min_volume:g}",
                )
            )

        # the visual mesh
        visual_body: Body | None = body
        source: str | None = "primitive" if body.primitive is not None else "mesh"
        if robot:
            assert visuals is not None
            visual_body = visuals.get(body.name, body)
            source = "visual" if body.name in visuals else "collision"
        if grouped or (body.parts and not render):
            visual_body, source = None, None  # collision parts only: nothing to compare
        row: dict[str, Any] = {
            "body": body.name,
            "collider": kind,
            "convex_parts": len(parts),
            "visual_source": source,
            "comparison": None,
            "collider_mass": _mass_dict(collider),
            "visual_mass": None,
            "volume_ratio": None,
            "center_of_mass_offset": None,
            "inertia_ratio": None,
        }
        rows.append(row)
        if visual_body is None or collider is None:
            continue
        geometry = geometries.get(visual_body.vertices, visual_body.faces)
        if visual_body.primitive is not None:
            visual = primitive_mass_properties(visual_body.primitive).transformed(visual_body.pose)
            closed = True
        else:
            measured = geometry.oriented_volume
            closed = measured is not None and measured[1] != 0
            visual = geometry.mass.transformed(visual_body.pose)
        row["visual_mass"] = _mass_dict(visual)
        if visual.area == 0.0:
            findings.append(
                finding(
                    "MC301",
                    body.name,
                    None,
                    0.0,
                    0.0,
                    "the body has no area (every face degenerate): nothing to collide with",
                )
            )
            continue
        world = visual_body.world_vertices()[geometry.used]
        diagonal = float(np.linalg.norm(world.max(axis=0) - world.min(axis=0)))
        row["comparison"] = "solid" if closed else "shell"
        if closed and collider.volume > 0:
            ratio = collider.volume / abs(visual.volume)
            row["volume_ratio"] = ratio
            limit = (
                options.volume_ratio
                if ratio > options.volume_ratio
                else 1.0 / options.volume_ratio
                if ratio < 1.0 / options.volume_ratio
                else None
            )
            if limit is not None:
                findings.append(
                    finding(
                        "MC205",
                        body.name,
                        None,
                        ratio,
                        limit,
                        f"collider volume {collider.volume:.4g} is {ratio:.3g} x the visual "
                        f"mesh's {abs(visual.volume):.4g}",
                    )
                )
            inertia = _moment_ratio(collider, visual)
            row["inertia_ratio"] = inertia
            if inertia is not None and inertia > options.inertia_ratio:
                findings.append(
                    finding(
                        "MC207",
                        body.name,
                        None,
                        inertia,
                        options.inertia_ratio,
                        f"principal moments of inertia per unit mass differ by up to "
                        f"{inertia:.3g} x",
                    )
                )
        if closed and collider.volume > 0:
            a, b = collider.center_of_mass, visual.center_of_mass
        else:
            a, b = collider.shell_center_of_mass, visual.shell_center_of_mass
        if diagonal > 0 and np.all(np.isfinite(a)) and np.all(np.isfinite(b)):
            offset = float(np.linalg.norm(a - b)) / diagonal
            row["center_of_mass_offset"] = offset
            if offset > options.com_offset:
                findings.append(
                    finding(
                        "MC206",
                        body.name,
                        None,
                        offset,
                        options.com_offset,
                        f"centre of mass {float(np.linalg.norm(a - b)):.4g} from the visual "
                        f"mesh's ({offset:.1%} of its diagonal)",
                    )
                )

    if robot:
        assert visuals is not None
        links = {b.name for b in colliders.bodies}
        for name in visuals:
            if name not in links:
                findings.append(
                    finding(
                        "MC301",
                        name,
                        None,
                        0,
                        1,
                        "link has visual geometry but no collision element",
                    )
                )
    return rows, findings


# ---------------------------------------------------------------------------------------------
# The report behind ``meshcol inspect``

#: Columns of :meth:`InspectReport.to_csv`, one row per body.
CSV_COLUMNS = (
    "name",
    "source",
    "vertices",
    "faces",
    "components",
    "watertight",
    "winding_consistent",
    "volume",
    *vector_columns("bounds_min"),
    *vector_columns("bounds_max"),
    *vector_columns("size"),
    "degenerate_faces",
    "duplicate_faces",
    "boundary_edges",
    "non_manifold_edges",
    "inconsistent_edges",
    "self_intersecting",
    "self_intersecting_pairs",
    "manifold_status",
    "units_guess",
    "units_reason",
    "declared_units",
    "findings",
    "failed_rules",
    "units",
)


@dataclass(frozen=True)
class InspectReport:
    """What :func:`inspect` found: one :class:`MeshInspection` per body, the physics rows,
    every finding as a record, and the policy.

    Attributes
    ----------
    inspections : tuple of MeshInspection
        Per mesh, in input order.
    fail_on : tuple of str
        Rule ids (:mod:`meshcol.analysis.rules`) whose findings fail the run.
    units : str or None
        Units the scene manifest declared.
    errors : tuple of dict
        Inputs that could not be inspected, each ``{"source", "body", "message"}`` (``body``
        None for a file that could not be read); the others are still inspected.
    findings : tuple of Finding
        Every finding: mesh health per mesh, then physics readiness and colliders per body.
    physics : tuple of dict
        Per collider body (:func:`physics_readiness`).
    physics_options : PhysicsOptions
    warnings : tuple of str
        What the run could not do as asked (a robot's visual geometry that could not be read).
    """

    inspections: tuple[MeshInspection, ...]
    fail_on: tuple[str, ...] = ()
    units: str | None = None
    errors: tuple[dict[str, Any], ...] = ()
    findings: tuple[Finding, ...] = ()
    physics: tuple[dict[str, Any], ...] = ()
    physics_options: PhysicsOptions = field(default_factory=PhysicsOptions)
    warnings: tuple[str, ...] = ()

    @property
    def bodies(self) -> list[dict[str, Any]]:
        """Per mesh: every :class:`MeshInspection` field and ``failed_rules``, the findings
        (names) whose ids are listed in ``fail_on``."""
        failing = {name for name, rule in HEALTH_IDS.items() if rule in self.fail_on}
        rows = []
        for result in self.inspections:
            row = result.to_dict()
            row["failed_rules"] = [rule for rule in result.findings if rule in failing]
            rows.append(row)
        return rows

    @property
    def failed_findings(self) -> list[Finding]:
        """The findings whose rule is listed in ``fail_on``."""
        return [f for f in self.findings if f.rule in self.fail_on]

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The rows of :attr:`bodies` with a mesh-health finding listed in ``fail_on``."""
        return [row for row in self.bodies if row["failed_rules"]]

    @property
    def exit_code(self) -> int:
        """2 when an input could not be inspected, else 1 when a finding's rule is listed in
        ``fail_on``, else 0."""
        return 2 if self.errors else 1 if self.failed_findings else 0

    @property
    def summary(self) -> dict[str, Any]:
        """Counts: meshes, bodies with findings, failing bodies, findings per rule name."""
        from meshcol.analysis.rules import command_rules

        def label(f: Finding) -> str:
            return f.body if f.part is None else f"{f.body}/{f.part}"

        return {
            "bodies": len(self.inspections),
            "with_findings": len({label(f) for f in self.findings}),
            "failed": len({label(f) for f in self.failed_findings}),
            "errors": len(self.errors),
            "findings": {
                rule.name: sum(f.rule == rule.id for f in self.findings)
                for rule in command_rules("inspect")
            },
        }

    @property
    def settings(self) -> dict[str, Any]:
        from meshcol.analysis.rules import get_rule

        return {
            "fail_on": [get_rule(rule).name for rule in self.fail_on],
            "fail_on_rules": list(self.fail_on),
            "bounds_frame": "world",
            **self.physics_options.settings(),
        }

    def finding_rows(self) -> list[dict[str, Any]]:
        """Every finding as a dict, with ``failed`` (its rule is listed in ``fail_on``)."""
        return [dict(f.to_dict(), failed=f.rule in self.fail_on) for f in self.findings]

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, ``failed`` (the policy verdict), the
        summary, one entry per mesh, the physics rows and every finding."""
        from meshcol.io.report import envelope

        return {
            **envelope("inspect", self.settings, self.units),
            "failed": self.exit_code != 0,
            "summary": self.summary,
            "bodies": self.bodies,
            "physics": list(self.physics),
            "findings": self.finding_rows(),
            "warnings": list(self.warnings),
            "errors": list(self.errors),
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``), a failure when it has a finding listed in ``fail_on`` (each
        finding with its measure: ``not-watertight (12 boundary edges)``), passed otherwise
        (other findings make it worth a warning); one error case per input that could not
        be inspected."""
        from meshcol.io.ci import CiCase, CiSuite, details

        rows = self.bodies
        by_name = {row["name"]: row for row in rows}
        grouped: dict[str, list[Finding]] = {}
        for f in self.findings:  # each finding to its mesh's case, or a case of its own
            key = f.body if f.part is None else f"{f.body}/{f.part}"
            grouped.setdefault(key if key in by_name else f.body, []).append(f)
        sources = {row["name"].split("/")[0]: row["source"] for row in rows}

        def text(f: Finding, row: dict[str, Any] | None) -> str:
            if row is not None and f.rule in HEALTH_IDS.values():
                return _finding_text(f.name, row)
            where = "" if f.part is None or row is not None else f"part {f.part}: "
            return f"{f.rule} {f.name} ({where}{f.message})"

        cases = []
        keys = [row["name"] for row in rows] + [k for k in grouped if k not in by_name]
        for key in keys:
            row = by_name.get(key)
            found = grouped.get(key, [])
            failed = [f for f in found if f.rule in self.fail_on]
            others = [f for f in found if f.rule not in self.fail_on]
            if failed:
                message = ", ".join(text(f, row) for f in failed)
                if others:
                    message += "; also " + ", ".join(text(f, row) for f in others)
            elif others:
                message = "findings: " + ", ".join(text(f, row) for f in others)
            elif row is not None:
                message = f"ok: {row['vertices']} vertices, {row['faces']} faces, watertight"
            else:
                continue
            source = row["source"] if row is not None else sources.get(key)
            cases.append(
                CiCase(
                    name=_case_name(source, key),
                    classname="meshcol.inspect",
                    outcome="failure" if failed else "passed",
                    message=message,
                    file=source,
                    kind=failed[0].name if failed else None,
                    details=details(
                        (key, row[key])
                        for key in (
                            "vertices",
                            "faces",
                            "components",
                            "watertight",
                            "winding_consistent",
                            "volume",
                            "size",
                            "boundary_edges",
                            "non_manifold_edges",
                            "degenerate_faces",
                            "duplicate_faces",
                            "self_intersecting_pairs",
                            "units_guess",
                        )
                    )
                    if failed and row is not None
                    else "",
                    warn=bool(others) and not failed,
                )
            )
        for error in self.errors:
            cases.append(
                CiCase(
                    name=_case_name(error["source"], error["body"]),
                    classname="meshcol.inspect",
                    outcome="error",
                    message=error["message"],
                    file=error["source"] or None,
                    kind="unusable-input",
                )
            )
        s = self.summary
        verdict = f"{s['bodies']} bodies, {s['with_findings']} with findings"
        if self.fail_on:
            verdict += f", {s['failed']} failing --fail-on {','.join(self.fail_on)}"
        return CiSuite("inspect", tuple(cases), self.settings, verdict=verdict, units=self.units)

    def to_csv(self) -> str:
        """One row per body (:data:`CSV_COLUMNS`): bounds and size split into ``_x/_y/_z``
        columns, as every command's CSV; findings space-separated."""
        from meshcol.io.report import dumps_csv, split_vectors

        sizes = {"bounds_min": 3, "bounds_max": 3, "size": 3}
        flat = [
            split_vectors(
                dict(
                    row, bounds_min=row["bounds"][0], bounds_max=row["bounds"][1], units=self.units
                ),
                sizes,
            )
            for row in self.bodies
        ]
        return dumps_csv(flat, CSV_COLUMNS)


def _case_name(source: str | None, body: str | None) -> str:
    """``FILE::BODY`` (body names repeat across files), or whichever of the two is known."""
    if source and body:
        return f"{source}::{body}"
    return source or body or "(unnamed)"


def _finding_text(rule: str, row: dict[str, Any]) -> str:
    """A finding with what was measured: ``not-watertight (12 boundary edges)``."""
    measure = {
        "not-watertight": f"{row['boundary_edges']} boundary edges, "
        f"{row['non_manifold_edges']} non-manifold",
        "self-intersecting": f"{row['self_intersecting_pairs']} crossing face pairs",
        "inconsistent-winding": "neighbouring faces disagree on their winding",
        "inverted": f"volume {row['volume']:.6g}" if row["volume"] is not None else "inside out",
        "degenerate-faces": f"{row['degenerate_faces']} faces",
        "non-manifold": f"{row['non_manifold_edges']} edges with more than two faces",
        "duplicate-faces": f"{row['duplicate_faces']} faces",
        "multiple-components": f"{row['components']} components",
        "suspect-units": f"looks like {row['units_guess']}: {row['units_reason']}",
    }.get(rule)
    return rule if measure is None else f"{rule} ({measure})"


def inspect(
    inputs: Any,
    *,
    fail_on: Sequence[str] | str = (),
    physics: PhysicsOptions | None = None,
    progress: Callable[[str], None] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    executor: str = "local",
    ray_address: str | None = None,
    robot_options: RobotOptions | None = None,
) -> InspectReport:
    """Inspect every body of the inputs: is each mesh fit to be a collider, and is its
    collider fit for physics?

    Parameters
    ----------
    inputs : path or sequence of paths
        Mesh files (every object, solid or mesh node is a body), one scene manifest, or one
        robot description (URDF, MJCF: its links' collision geometry, against their visual
        geometry).
    fail_on : sequence of str or str
        Rule ids or names (``MC401``, ``not-watertight``, ``all``) whose findings fail the
        run (:attr:`InspectReport.exit_code`).
    physics : PhysicsOptions, optional
        The collider and the tolerances of the physics rules.
    progress : callable, optional
        Receives one line per body inspected (``inspect: 3/10 bodies``), or per file with
        an executor (``inspect: 3/10 files``).
    jobs : int
        Files inspected at once, each a task of its own (reading the file and inspecting its
        bodies) in a worker process or a Ray task; each task's native threads are its share
        of the cores (:func:`meshcol.decomposition.jobs.worker_env`). 1, without
        ``timeout`` or Ray: every body in this process, one after another.
    timeout : float, optional
        Seconds a file's task may take; it is then stopped (its worker killed) and the file
        is an entry of :attr:`InspectReport.errors`, as is a file whose worker died.
    executor : {"local", "ray"}
        Where the tasks run (:func:`meshcol.decomposition.executor.make_executor`).
    ray_address : str, optional
        The Ray cluster (default: a local Ray of ``jobs`` CPUs, stopped at the end).
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.robot.load_robot`).

    Returns
    -------
    InspectReport
        The same report whichever executor ran it.

    Raises
    ------
    UnknownRuleError
        An unknown rule in ``fail_on`` (a ValueError).
    MeshcolError
        A manifest that cannot be used, or inputs none of which could be inspected.

    Notes
    -----
    Each mesh goes through :func:`inspect_body` (a manifest body's parts one by one; its
    declared units are passed on, so ``suspect-units`` compares the guess with them), then
    each body through :func:`physics_readiness`. A batch keeps going: a mesh file that cannot
    be read, or a body that cannot be inspected (no faces), becomes an entry of
    :attr:`InspectReport.errors` and the run's exit code is 2; the other bodies are reported.
    What a mesh alone decides (its topology, crossings, manifold status) is measured once
    however many bodies instance it; what a body's pose decides (its bounds, its degenerate
    faces, its units guess) for each body, so the report is the one of each body alone.
    """
    from meshcol.analysis.rules import select_rules
    from meshcol.errors import MeshcolError
    from meshcol.io.inputs import is_robot_file
    from meshcol.io.robot import load_robot
    from meshcol.io.scene import iter_inputs, load_scene

    rules = select_rules(fail_on, "inspect")
    options = physics or PhysicsOptions()
    if not rules and options.target is not None:
        from meshcol.analysis.rules import TARGET_RULES

        rules = TARGET_RULES  # a target's limits fail the run unless --fail-on says otherwise
    options.validate()
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    inputs = list(inputs)
    errors: list[dict[str, Any]] = []
    first_error: list[MeshcolError] = []
    warnings: list[str] = []

    def skip(path: str, error: MeshcolError, body: str | None = None) -> None:
        first_error.append(error)
        errors.append({"source": path, "body": body, "message": error.message})

    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    in_tasks = jobs > 1 or timeout is not None or executor != "local"
    geometries = _Geometries()  # health and physics measure each mesh once between them
    visuals: dict[str, Body] | None = None
    units = None
    scene_bodies: list[Body] | None = None
    if _is_manifest(inputs):
        scene = load_scene(inputs[0])  # read whole: a manifest's problem stops the run
        scene_bodies = list(scene.bodies)
        units = scene.units
    elif len(inputs) == 1 and is_robot_file(inputs[0]):
        scene = load_robot(inputs[0], robot_options)
        scene_bodies = list(scene.bodies)
        units = scene.units
        try:
            visual_scene = load_robot(inputs[0], robot_options, visual=True)
            visuals = {b.name: b for b in visual_scene.bodies}
        except MeshcolError as error:
            visuals = {}
            warnings.append(
                f"visual geometry not read, links compared with their collision meshes: {error}"
            )
    elif not in_tasks:
        scene_bodies = [
            b for _, file_bodies in iter_inputs(inputs, on_error=skip) for b in file_bodies
        ]
    if in_tasks:
        scene_bodies, inspected = _inspect_tasks(
            inputs,
            scene_bodies,
            units,
            skip,
            progress,
            jobs=jobs,
            timeout=timeout,
            executor=executor,
            address=ray_address,
        )
    else:
        assert scene_bodies is not None
        meshes = _meshes(scene_bodies)
        outcomes = _inspect_meshes([part for _, _, part in meshes], units, progress, geometries)
        inspected = [
            (body_name, part_name, part, outcome)
            for (body_name, part_name, part), outcome in zip(meshes, outcomes)
        ]
    # health per mesh, in input order
    results = []
    findings: list[Finding] = []
    bad = set()
    for body_name, part_name, part, outcome in inspected:
        if isinstance(outcome, InvalidMeshError):
            skip(outcome.path or part.source or "", outcome, part.name)
            bad.add(body_name)
        else:
            results.append(outcome)
            findings.extend(health_findings(outcome, body_name, part_name))
    if not results and first_error:
        raise first_error[0]
    usable = [b for b in scene_bodies if b.name not in bad]
    rows, physics_findings = physics_readiness(
        usable, options, visuals=visuals, units=units, _geometries=geometries
    )
    findings.extend(physics_findings)
    return InspectReport(
        tuple(results),
        rules,
        units,
        tuple(errors),
        tuple(findings),
        tuple(rows),
        options,
        tuple(warnings),
    )


def _meshes(bodies: Sequence[Body]) -> list[tuple[str, str | None, Body]]:
    """``(body name, part name or None, mesh)`` per mesh of the bodies: each part of a body
    is its own mesh for the health rules."""
    return [
        (body.name, name, part)
        for body in bodies
        for name, part in zip(body.parts or (None,), body.part_bodies())
    ]


#: One inspected mesh: ``(body name, part name or None, the mesh, its inspection or the
#: InvalidMeshError that stopped it)``.
Inspected = tuple[str, str | None, Body, Any]


def _inspect_meshes(
    meshes: Sequence[Body],
    units: str | None,
    progress: Callable[[str], None] | None = None,
    geometries: _Geometries | None = None,
) -> list[MeshInspection | InvalidMeshError]:
    """:func:`inspect_body` of each mesh, or the InvalidMeshError that stopped it; what a
    mesh alone decides is measured once for all the meshes that instance it (a level's
    props), so the work follows the unique meshes, not the bodies."""
    geometries = geometries if geometries is not None else _Geometries()
    out: list[MeshInspection | InvalidMeshError] = []
    for done, mesh in enumerate(meshes, start=1):
        try:
            out.append(_inspect_instance(mesh, units, geometries))
        except InvalidMeshError as error:
            out.append(error)
        if progress is not None:
            progress(f"inspect: {done}/{len(meshes)} bodies")
    return out


def _inspect_file(
    task: tuple[str, list[Body] | None, str | None],
) -> tuple[tuple[list[Body] | None, list[Any]] | None, Exception | None]:
    """Worker entry of a parallel inspect: one file's ``(path, meshes, declared units)``
    (``meshes`` None: read the file here) to ``((bodies read here or None, [inspection or
    its InvalidMeshError per mesh]), None)``, or ``(None, the MeshcolError that made the
    file unreadable)``."""
    from meshcol.errors import MeshcolError
    from meshcol.io.mesh_read import load_mesh

    path, meshes, units = task
    bodies = None
    if meshes is None:
        try:
            bodies = load_mesh(path)
        except MeshcolError as error:
            return None, error
        meshes = [part for _, _, part in _meshes(bodies)]
    return (bodies, _inspect_meshes(meshes, units)), None


def _renamed(body: Body, name: str) -> Body:
    import dataclasses

    return body if body.name == name else dataclasses.replace(body, name=name)


def _inspect_tasks(
    inputs: list[Any],
    scene_bodies: list[Body] | None,
    units: str | None,
    skip: Callable[..., None],
    progress: Callable[[str], None] | None,
    **run: Any,
) -> tuple[list[Body], list[Inspected]]:
    """The inspections of :func:`inspect`, one executor task per file: a manifest's or a
    robot's meshes (``scene_bodies``, read here) grouped by mesh file, or each input file
    read in its task. Returns the bodies and their inspected meshes as the sequential run
    has them: the same names (``unique_name`` applied here, in input order), order and
    errors (an unreadable file's error first, in file order)."""
    import dataclasses

    from meshcol.decomposition.executor import run_each
    from meshcol.errors import MeshcolError
    from meshcol.io.scene import unique_name

    tasks: list[tuple[str, list[Body] | None, str | None]]
    if scene_bodies is not None:
        meshes = _meshes(scene_bodies)
        source = os.fspath(inputs[0])
        groups: dict[str, list[int]] = {}
        for k, (_, _, part) in enumerate(meshes):
            groups.setdefault(part.source or source or part.name, []).append(k)
        tasks = [(path, [meshes[k][2] for k in ks], units) for path, ks in groups.items()]
        slots = list(groups.values())
    else:
        tasks = [(os.fspath(path), None, None) for path in inputs]
    outcomes: dict[int, Any] = {}
    for outcome in run_each(_inspect_file, tasks, **run):
        outcomes[outcome.index] = outcome
        if progress is not None:
            progress(f"inspect: {len(outcomes)}/{len(tasks)} files")
    per_task: list[tuple[list[Body] | None, list[Any]] | None] = []
    for index, (path, _, _) in enumerate(tasks):
        outcome = outcomes[index]
        if outcome.status != "ok":
            skip(path, MeshcolError(outcome.message or outcome.status, path))
            per_task.append(None)
            continue
        value, error = outcome.value
        if error is not None:
            skip(path, error)
            per_task.append(None)
            continue
        per_task.append(value)
    if scene_bodies is not None:
        inspected: list[Inspected] = []
        found: dict[int, Any] = {}
        for ks, value in zip(slots, per_task):
            if value is not None:  # else its file's task failed, an error already
                found.update(zip(ks, value[1]))
        for k, (body_name, part_name, part) in enumerate(meshes):
            if k in found:
                inspected.append((body_name, part_name, part, found[k]))
        return scene_bodies, inspected
    bodies: list[Body] = []
    inspected = []
    used: set[str] = set()
    for value in per_task:
        if value is None:
            continue
        read, results = value
        assert read is not None
        originals: dict[str, str] = {}
        mine: list[Body] = []
        for body in read:
            body = _renamed(body, unique_name(body.name, used))
            originals[body.name] = read[len(mine)].name
            mine.append(body)
        bodies.extend(mine)
        for (body_name, part_name, part), result in zip(_meshes(mine), results):
            original = originals[body_name]
            if isinstance(result, MeshcolError):
                # raised before the body was renamed (``name#2``): its message names the mesh
                before = original + part.name[len(body_name) :]
                prefix = f"body '{before}': "
                if body_name != original and result.message.startswith(prefix):
                    message = f"body '{part.name}': {result.message[len(prefix) :]}"
                    result = type(result)(message, result.path)
            elif result.name != part.name:
                result = dataclasses.replace(result, name=part.name)
            inspected.append((body_name, part_name, part, result))
    return bodies, inspected


def _is_manifest(inputs: Sequence[Any]) -> bool:
    from meshcol.io.inputs import is_manifest

    return len(inputs) == 1 and is_manifest(inputs[0])
