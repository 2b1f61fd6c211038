"""Mesh health checks: topology, degeneracies, self-intersections and a guess at the units.

:func:`inspect_body` answers "is this mesh fit to be a collider?": is it closed, consistently
wound, free of degenerate, duplicate and non-manifold faces and of self-intersections, in one
piece, and plausibly in metres. :func:`health_findings` turns the answer into finding records
(MC401..MC409, and MC505 when the self-intersection test stopped at its budget).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from meshcol.analysis.geometry_cache import GeometryCache, measure_geometries
from meshcol.analysis.rules import Finding, get_rule
from meshcol.errors import InvalidMeshError
from meshcol.geometry.triangles import degenerate_faces
from meshcol.types import Body

__all__ = [
    "HEALTH_IDS",
    "Inspected",
    "MeshInspection",
    "RULES",
    "body_meshes",
    "guess_units",
    "health_findings",
    "inspect_body",
    "inspect_mesh",
    "inspect_meshes",
    "units_by_body",
]

#: The mesh-health findings of :func:`inspect_body`, by name (ids MC401..MC409 in
#: :mod:`meshcol.analysis.rules`, in this order, then ``undecided``, MC505: the
#: self-intersection test stopped at its work budget).
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
    "undecided",
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
    self_intersecting : bool or None
        Two faces cross: their open triangles share a point (see
        :mod:`meshcol.collision.self_intersection`; decided exactly). Faces that only touch,
        along shared vertices and edges or elsewhere, do not cross. None: undecided, the test
        stopped at its work budget
        (:data:`~meshcol.collision.self_intersection.MAX_WORK`) without finding a
        crossing (the ``undecided`` finding).
    self_intersecting_pairs : int
        Pairs of faces that cross (degenerate faces left out): exact, unless the
        ``undecided`` finding says the test stopped at its budget, where it is a lower bound.
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
    self_intersecting: bool | None
    self_intersecting_pairs: int
    manifold_status: str
    units_guess: str
    units_reason: str
    declared_units: str | None = None
    findings: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """Plain JSON-ready dictionary of every field (``dataclasses.asdict``'s value, without
        its deep copy of every scalar: a third of inspect's time on 100,000 bodies)."""
        out = {name: getattr(self, name) for name in _FIELDS}
        out["bounds"] = [list(corner) for corner in self.bounds]
        out["size"] = list(self.size)
        out["findings"] = list(self.findings)
        return out


_FIELDS = tuple(f.name for f in fields(MeshInspection))


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
    return inspect_mesh(body, declared_units, GeometryCache())


def inspect_mesh(
    body: Body, declared_units: str | None, geometries: GeometryCache
) -> MeshInspection:
    """:func:`inspect_body`, with what the mesh alone decides shared through ``geometries``
    by the bodies that instance it."""
    vertices, faces = _mesh_arrays(body)
    return _inspect_arrays(body, vertices, faces, declared_units, geometries)


def _inspect_arrays(
    body: Body,
    vertices: np.ndarray,
    faces: np.ndarray,
    declared_units: str | None,
    geometries: GeometryCache,
) -> MeshInspection:
    """:func:`inspect_mesh` of the body's checked arrays (:func:`_mesh_arrays`)."""
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

    # relative to the world diagonal, so a body's own: its rotation changes its bounding box
    degenerate = degenerate_faces(vertices, faces, diagonal, heights=mesh.heights)
    crossings = mesh.crossings(degenerate)
    units, reason = guess_units(float(size.max()))

    broken = {
        "not-watertight": not watertight,
        "self-intersecting": crossings.count > 0,
        "inconsistent-winding": not winding_consistent,
        "inverted": measured is not None and measured[1] < 0,
        "degenerate-faces": bool(degenerate.any()),
        "non-manifold": non_manifold > 0,
        "duplicate-faces": mesh.duplicates > 0,
        "multiple-components": mesh.components > 1,
        "suspect-units": _units_suspect(units, declared_units),
        "undecided": not crossings.complete,
    }
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
        self_intersecting=crossings.crossing,
        self_intersecting_pairs=crossings.count,
        manifold_status=mesh.manifold_status,
        units_guess=units,
        units_reason=reason,
        declared_units=declared_units,
        findings=[name for name in RULES if broken[name]],
    )


def _mesh_arrays(body: Body) -> tuple[np.ndarray, np.ndarray]:
    """The body's vertices (float64) and faces (int64); InvalidMeshError when it has no faces
    or a non-finite coordinate."""
    vertices = np.asarray(body.vertices, dtype=np.float64)
    faces = np.asarray(body.faces, dtype=np.int64)
    if len(faces) == 0:
        raise InvalidMeshError(f"body '{body.name}': mesh has no faces", body.source)
    if not np.isfinite(vertices).all():
        raise InvalidMeshError(
            f"body '{body.name}': vertices contain NaN or infinite coordinates", body.source
        )
    return vertices, faces


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
    extent = largest_extent
    if extent > IMPLAUSIBLE_EXTENT:
        return "unknown", f"largest extent {extent:.6g} units: over 10 m even in millimetres"
    if extent > MILLIMETRE_EXTENT:
        return (
            "mm",
            f"largest extent {extent:.6g} units: {extent / 1000:.3g} m in millimetres, "
            "over 100 m in metres",
        )
    if extent < TINY_EXTENT:
        return "unknown", f"largest extent {extent:.6g} units: under 1 cm in metres"
    return "m", f"largest extent {extent:.6g} units: a plausible size in metres"


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


def health_findings(result: MeshInspection, body: str, part: str | None) -> list[Finding]:
    """The mesh-health findings of one inspection as records (rules MC401..MC409, MC505).

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
    from meshcol.collision.self_intersection import MAX_WORK as budget

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
            f"{'at least ' if 'undecided' in r.findings else ''}"
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
        "undecided": (r.self_intersecting_pairs, budget, _undecided_message(r, budget)),
    }
    return [finding(HEALTH_IDS[name], body, part, *measures[name]) for name in r.findings]


def _undecided_message(result: MeshInspection, budget: int) -> str:
    """The ``undecided`` finding's line: what the self-intersection test could not decide."""
    stop = f"the self-intersection test stopped at its work budget ({budget:,} units)"
    if result.self_intersecting_pairs:
        return f"{stop}: at least {result.self_intersecting_pairs} pairs of faces cross"
    return f"{stop} with no crossing found: undecided"


# ---------------------------------------------------------------------------------------------
# Many meshes: each part of a body is its own mesh for the health rules

#: One inspected mesh: ``(body name, part name or None, the mesh, its inspection or the
#: InvalidMeshError that stopped it)``.
Inspected = tuple[str, str | None, Body, Any]


def body_meshes(bodies: Sequence[Body]) -> list[tuple[str, str | None, Body]]:
    """``(body name, part name or None, mesh)`` per mesh of the bodies: each part of a body
    is its own mesh for the health rules."""
    return [
        (body.name, name, part)
        for body in bodies
        for name, part in zip(body.parts or (None,), body.part_bodies())
    ]


def units_by_body(inspected: Sequence[Inspected]) -> list[Inspected]:
    """``inspected`` with ``suspect-units`` taken off the parts that only their own size makes
    suspect: a part under a centimetre (:data:`TINY_EXTENT`) of a body whose parts together
    are a plausible size in the declared units is a detail of that body (a finger pad, a
    screw head), not a file in other units. A body of one mesh, a body tiny as a whole and a
    part too large keep the finding; the part's ``units_guess`` and ``units_reason`` stay its
    own."""
    extents: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for body, part, _, outcome in inspected:
        if part is not None and isinstance(outcome, MeshInspection):
            lo, hi = np.asarray(outcome.bounds, dtype=np.float64)
            seen = extents.get(body)
            extents[body] = (
                (lo, hi) if seen is None else (np.minimum(seen[0], lo), np.maximum(seen[1], hi))
            )
    out = []
    for body, part, mesh, outcome in inspected:
        if (
            body in extents
            and isinstance(outcome, MeshInspection)
            and "suspect-units" in outcome.findings
            and max(outcome.size) < TINY_EXTENT
        ):
            lo, hi = extents[body]
            whole, _ = guess_units(float((hi - lo).max()))
            if not _units_suspect(whole, outcome.declared_units):
                kept = [name for name in outcome.findings if name != "suspect-units"]
                outcome = dataclasses.replace(outcome, findings=kept)
        out.append((body, part, mesh, outcome))
    return out


def inspect_meshes(
    meshes: Sequence[Body],
    units: str | None,
    progress: Callable[[str], None] | None = None,
    geometries: GeometryCache | None = None,
) -> list[MeshInspection | InvalidMeshError]:
    """:func:`inspect_body` of each mesh, or the InvalidMeshError that stopped it; what a
    mesh alone decides is measured once for all the meshes that instance it (a level's
    props), so the work follows the unique meshes, not the bodies, and for all the unique
    meshes at once (:func:`~meshcol.analysis.geometry_cache.measure_geometries`)."""
    geometries = geometries if geometries is not None else GeometryCache()
    checked: list[tuple[np.ndarray, np.ndarray] | InvalidMeshError] = []
    for mesh in meshes:
        try:
            checked.append(_mesh_arrays(mesh))
        except InvalidMeshError as error:
            checked.append(error)
    measure_geometries(
        [geometries.get(*arrays) for arrays in checked if not isinstance(arrays, Exception)],
        mass=False,
    )
    out: list[MeshInspection | InvalidMeshError] = []
    for done, (mesh, arrays) in enumerate(zip(meshes, checked), start=1):
        if isinstance(arrays, InvalidMeshError):
            out.append(arrays)
        else:
            out.append(_inspect_arrays(mesh, *arrays, units, geometries))
        if progress is not None:
            progress(f"inspect: {done}/{len(meshes)} bodies")
    return out
