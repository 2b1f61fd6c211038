"""Mesh health checks: topology, degeneracies, self-intersections and a guess at the units.

:func:`inspect_body` answers "is this mesh fit to be a collider?": is it closed, consistently
wound, free of degenerate, duplicate and non-manifold faces and of self-intersections, in one
piece, and plausibly in metres.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import component_count, duplicate_face_count, edge_table
from meshcol.geometry.triangles import degenerate_faces
from meshcol.io.report import vector_columns
from meshcol.types import Body

__all__ = [
    "InspectReport",
    "MeshInspection",
    "RULES",
    "inspect",
    "inspect_body",
    "self_intersecting_pairs",
    "guess_units",
]

#: ``--fail-on`` rules, each the name of a finding.
RULES: tuple[str, ...] = (
    "not-watertight",
    "self-intersecting",
    "inconsistent-winding",
    "degenerate-faces",
    "non-manifold",
    "duplicate-faces",
    "multiple-components",
    "suspect-units",
)
#: Self-intersection tests treat distances up to this fraction of the diagonal as contact,
#: not crossing: faces that merely touch (shared vertices, T-junctions) are not reported.
CROSSING_RELATIVE_TOLERANCE = 1e-10
#: Largest extent, in units, above which a body is probably in millimetres, not metres
#: (a 400-unit chair), and above which no unit makes it a plausible single asset.
MILLIMETRE_EXTENT = 100.0
IMPLAUSIBLE_EXTENT = 10_000.0
#: Below this largest extent a body in metres would be under a centimetre.
TINY_EXTENT = 0.01
#: Candidate pairs are tested in chunks of this many, to bound memory.
PAIR_CHUNK = 200_000


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
        watertight and consistently wound; None otherwise (it would mean nothing).
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
    self_intersecting : bool
        Two non-adjacent parts of the surface cross each other.
    self_intersecting_pairs : int
        Pairs of faces that cross.
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
    traverse it in opposite directions (consistent winding). The volume is the divergence
    theorem sum over the triangles. manifold3d's ``Manifold(Mesh64)`` status is reported as
    a second opinion on the topology; manifold3d assumes (and does not check) that its input
    is free of self-intersections, so those come from :func:`self_intersecting_pairs`.
    """
    vertices = np.asarray(body.vertices, dtype=np.float64)
    faces = np.asarray(body.faces, dtype=np.int64)
    if len(faces) == 0:
        raise InvalidMeshError(f"body '{body.name}': mesh has no faces", body.source)
    if not np.isfinite(vertices).all():
        raise InvalidMeshError(
            f"body '{body.name}': vertices contain NaN or infinite coordinates", body.source
        )

    world = body.world_vertices()
    used = world[np.unique(faces)]
    lo, hi = used.min(axis=0), used.max(axis=0)
    size = hi - lo
    diagonal = float(np.linalg.norm(size))

    edges, counts, inconsistent = edge_table(faces)
    boundary = int((counts == 1).sum())
    non_manifold = int((counts > 2).sum())
    watertight = boundary == 0 and non_manifold == 0
    winding_consistent = inconsistent == 0
    volume = None
    if watertight and winding_consistent:
        tri = vertices[faces]
        volume = float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)

    degenerate = degenerate_faces(vertices, faces, diagonal)
    pairs = self_intersecting_pairs(vertices, faces, skip=degenerate)
    units, reason = guess_units(float(size.max()))

    findings = []
    if not watertight:
        findings.append("not-watertight")
    if len(pairs):
        findings.append("self-intersecting")
    if not winding_consistent:
        findings.append("inconsistent-winding")
    if degenerate.any():
        findings.append("degenerate-faces")
    if non_manifold:
        findings.append("non-manifold")
    duplicates = duplicate_face_count(faces)
    if duplicates:
        findings.append("duplicate-faces")
    components = component_count(faces, len(vertices))
    if components > 1:
        findings.append("multiple-components")
    if _units_suspect(units, declared_units):
        findings.append("suspect-units")

    return MeshInspection(
        name=body.name,
        source=body.source,
        vertices=len(vertices),
        faces=len(faces),
        components=components,
        watertight=watertight,
        winding_consistent=winding_consistent,
        volume=volume,
        bounds=[lo.tolist(), hi.tolist()],
        size=size.tolist(),
        degenerate_faces=int(degenerate.sum()),
        duplicate_faces=duplicates,
        boundary_edges=boundary,
        non_manifold_edges=non_manifold,
        self_intersecting=bool(len(pairs)),
        self_intersecting_pairs=len(pairs),
        manifold_status=_manifold_status(vertices, faces),
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


# ---------------------------------------------------------------------------------------
# self-intersection


def self_intersecting_pairs(
    vertices: np.ndarray, faces: np.ndarray, skip: np.ndarray | None = None
) -> np.ndarray:
    """Pairs of faces of a mesh that cross each other.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    skip : (m,) bool, optional
        Faces to leave out (degenerate faces have no plane to cross).

    Returns
    -------
    (k, 2) int64
        Face index pairs ``i < j``, sorted.

    Notes
    -----
    Candidate pairs are the faces whose bounding boxes overlap (the native sort and sweep).
    Two triangles in different planes cross
    when they share a segment of positive length (Moller's interval test, Moller 1997):
    meeting at one point (shared vertex, T-junction) or along their shared edge is not a
    crossing. Coplanar triangles cross when two edges cross properly or a vertex lies
    strictly inside the other. Distances within ``CROSSING_RELATIVE_TOLERANCE`` of the
    diagonal count as contact. Faces on the same three vertices are
    duplicates (reported apart), not crossings.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    keep = np.ones(len(faces), bool) if skip is None else ~np.asarray(skip, bool)
    index = np.nonzero(keep)[0]
    if len(index) < 2:
        return np.zeros((0, 2), np.int64)
    tri = vertices[faces[index]]
    diagonal = float(np.linalg.norm(np.ptp(tri.reshape(-1, 3), axis=0)))
    tolerance = CROSSING_RELATIVE_TOLERANCE * diagonal
    found = []
    for i, j in _candidate_pairs(tri):
        fi, fj = faces[index[i]], faces[index[j]]
        shared = (fi[:, :, None] == fj[:, None, :]).any(axis=2).sum(axis=1)
        distinct = shared < 3
        i, j, shared = i[distinct], j[distinct], shared[distinct]
        hit = _triangles_cross(tri[i], tri[j], shared, tolerance)
        found.append(np.stack([index[i[hit]], index[j[hit]]], axis=1))
    pairs = np.concatenate(found) if found else np.zeros((0, 2), np.int64)
    pairs = np.sort(pairs, axis=1)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def _candidate_pairs(tri: np.ndarray):
    """Yield chunks (i, j), i < j, of faces whose bounding boxes overlap (touching counts).

    The native sort and sweep (:func:`meshcol.collision.broadphase.sort_and_sweep`) finds
    them; they are handed out ``PAIR_CHUNK`` at a time to bound the memory of the tests.
    """
    from meshcol.collision.broadphase import sort_and_sweep

    pairs = sort_and_sweep(tri.min(axis=1), tri.max(axis=1))
    for start in range(0, len(pairs), PAIR_CHUNK):
        chunk = pairs[start : start + PAIR_CHUNK]
        yield chunk[:, 0], chunk[:, 1]


def _triangles_cross(
    t1: np.ndarray, t2: np.ndarray, shared: np.ndarray, tolerance: float
) -> np.ndarray:
    """Crossing test of triangle pairs (k, 3, 3) x (k, 3, 3) sharing ``shared`` vertices.

    Non-coplanar pairs: Moller's interval test (Moller 1997). Both triangles meet the line
    where their planes cross in an interval; they cross when the intervals overlap over
    more than ``tolerance``. A single common point (a shared vertex, a vertex on the other
    triangle, a T-junction) is a touch, and two faces sharing an edge meet only along it.
    """
    n1 = np.cross(t1[:, 1] - t1[:, 0], t1[:, 2] - t1[:, 0])
    n2 = np.cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0])
    n1 /= np.linalg.norm(n1, axis=1)[:, None]
    n2 /= np.linalg.norm(n2, axis=1)[:, None]
    # signed distances of each triangle's vertices to the other's plane, snapped to 0
    d2 = np.einsum("kij,kj->ki", t2 - t1[:, :1], n1)
    d1 = np.einsum("kij,kj->ki", t1 - t2[:, :1], n2)
    d2[np.abs(d2) <= tolerance] = 0.0
    d1[np.abs(d1) <= tolerance] = 0.0
    coplanar = (d2 == 0).all(axis=1) & (d1 == 0).all(axis=1)
    straddle = ~(
        (d2 > 0).all(axis=1) | (d2 < 0).all(axis=1) | (d1 > 0).all(axis=1) | (d1 < 0).all(axis=1)
    )
    hit = np.zeros(len(t1), bool)
    general = np.nonzero(~coplanar & straddle & (shared < 2))[0]
    if len(general):
        line = np.cross(n1[general], n2[general])
        length = np.linalg.norm(line, axis=1)
        ok = length > 0
        general, line = general[ok], line[ok] / length[ok][:, None]
        lo1, hi1 = _interval(t1[general], d1[general], line)
        lo2, hi2 = _interval(t2[general], d2[general], line)
        hit[general] = np.minimum(hi1, hi2) - np.maximum(lo1, lo2) > tolerance
    if coplanar.any():
        c = np.nonzero(coplanar)[0]
        hit[c] = _coplanar_overlap(t1[c], t2[c], n1[c], tolerance)
    return hit


def _interval(tri: np.ndarray, distance: np.ndarray, line: np.ndarray):
    """Extent along ``line`` of where a triangle meets a plane (its vertices' ``distance``)."""
    along = np.einsum("kij,kj->ki", tri, line)
    points = np.full((len(tri), 6), np.nan)
    for i in range(3):
        j = (i + 1) % 3
        on_plane = distance[:, i] == 0
        points[on_plane, i] = along[on_plane, i]
        crosses = distance[:, i] * distance[:, j] < 0
        di, dj = distance[crosses, i], distance[crosses, j]
        ai, aj = along[crosses, i], along[crosses, j]
        points[crosses, 3 + i] = ai + (aj - ai) * di / (di - dj)
    # a straddling triangle always meets the plane, so no row is all NaN
    return np.nanmin(points, axis=1), np.nanmax(points, axis=1)


def _coplanar_overlap(t1, t2, normal, tolerance):
    """Coplanar triangles overlap: edges cross properly or a vertex is strictly inside."""
    axis = np.abs(normal).argmax(axis=1)
    keep = np.array([[1, 2], [0, 2], [0, 1]])[axis]
    rows = np.arange(len(t1))[:, None, None]
    a2 = t1[rows, np.arange(3)[None, :, None], keep[:, None, :]]
    b2 = t2[rows, np.arange(3)[None, :, None], keep[:, None, :]]
    scale = np.abs(normal[np.arange(len(t1)), axis])  # projection shrinks distances by this

    def orient(a, b, c):
        return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])

    def strict(a, b, c):
        """Sign of orient(a, b, c), 0 within tolerance of the line ab."""
        value = orient(a, b, c)
        limit = tolerance * scale * np.linalg.norm(b - a, axis=1)
        return np.where(value > limit, 1, np.where(value < -limit, -1, 0))

    hit = np.zeros(len(t1), bool)
    for e in range(3):
        p, q = a2[:, e], a2[:, (e + 1) % 3]
        for f in range(3):
            r, s = b2[:, f], b2[:, (f + 1) % 3]
            hit |= (strict(p, q, r) * strict(p, q, s) < 0) & (strict(r, s, p) * strict(r, s, q) < 0)
    for inner, outer in ((a2, b2), (b2, a2)):
        winding = np.sign(orient(outer[:, 0], outer[:, 1], outer[:, 2]))
        for v in range(3):
            inside = np.ones(len(t1), bool)
            for e in range(3):
                inside &= strict(outer[:, e], outer[:, (e + 1) % 3], inner[:, v]) * winding > 0
            hit |= inside
    return hit


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
    """What :func:`inspect` found: one :class:`MeshInspection` per body and the policy.

    Attributes
    ----------
    inspections : tuple of MeshInspection
        Per body, in input order.
    fail_on : tuple of str
        The :data:`RULES` whose findings fail the run.
    units : str or None
        Units the scene manifest declared.
    errors : tuple of dict
        Inputs that could not be inspected, each ``{"source", "body", "message"}`` (``body``
        None for a file that could not be read); the others are still inspected.
    """

    inspections: tuple[MeshInspection, ...]
    fail_on: tuple[str, ...] = ()
    units: str | None = None
    errors: tuple[dict[str, Any], ...] = ()

    @property
    def bodies(self) -> list[dict[str, Any]]:
        """Per body: every :class:`MeshInspection` field and ``failed_rules``, the findings
        listed in ``fail_on``."""
        rows = []
        for result in self.inspections:
            row = result.to_dict()
            row["failed_rules"] = [rule for rule in result.findings if rule in self.fail_on]
            rows.append(row)
        return rows

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The rows of :attr:`bodies` with a finding listed in ``fail_on``."""
        return [row for row in self.bodies if row["failed_rules"]]

    @property
    def exit_code(self) -> int:
        """2 when an input could not be inspected, else 1 when a body has a finding listed in
        ``fail_on``, else 0."""
        return 2 if self.errors else 1 if self.failed else 0

    @property
    def summary(self) -> dict[str, Any]:
        """Counts: bodies, bodies with findings, failing bodies, bodies per finding."""
        return {
            "bodies": len(self.inspections),
            "with_findings": sum(1 for r in self.inspections if r.findings),
            "failed": len(self.failed),
            "errors": len(self.errors),
            "findings": {rule: sum(rule in r.findings for r in self.inspections) for rule in RULES},
        }

    @property
    def settings(self) -> dict[str, Any]:
        return {"fail_on": list(self.fail_on), "bounds_frame": "world"}

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, ``failed`` (the policy verdict), the
        summary and one entry per body."""
        from meshcol.io.report import envelope

        return {
            **envelope("inspect", self.settings, self.units),
            "failed": self.exit_code != 0,
            "summary": self.summary,
            "bodies": self.bodies,
            "errors": list(self.errors),
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

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


def inspect(
    inputs: Any,
    *,
    fail_on: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
) -> InspectReport:
    """Inspect every body of the inputs: is each mesh fit to be a collider?

    Parameters
    ----------
    inputs : path or sequence of paths
        Mesh files (every object, solid or mesh node is a body) or one scene manifest.
    fail_on : sequence of str
        Names of :data:`RULES` whose findings fail the run (:attr:`InspectReport.exit_code`).
    progress : callable, optional
        Receives one line per body inspected (``inspect: 3/10 bodies``).

    Returns
    -------
    InspectReport

    Raises
    ------
    ValueError
        An unknown rule in ``fail_on``.
    MeshcolError
        A manifest that cannot be used, or inputs none of which could be inspected.

    Notes
    -----
    Each body goes through :func:`inspect_body`; a manifest's declared units are passed on,
    so ``suspect-units`` compares the guess with them. A batch keeps going: a mesh file that
    cannot be read, or a body that cannot be inspected (no faces), becomes an entry of
    :attr:`InspectReport.errors` and the run's exit code is 2; the other bodies are reported.
    """
    from meshcol.errors import MeshcolError
    from meshcol.io.scene import iter_inputs, load_scene

    unknown = [rule for rule in fail_on if rule not in RULES]
    if unknown:
        raise ValueError(f"unknown rule {unknown[0]!r} (valid rules: {', '.join(RULES)})")
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    inputs = list(inputs)
    errors: list[dict[str, Any]] = []
    first_error: list[MeshcolError] = []

    def skip(path: str, error: MeshcolError, body: str | None = None) -> None:
        first_error.append(error)
        errors.append({"source": path, "body": body, "message": error.message})

    if _is_manifest(inputs):
        scene = load_scene(inputs[0])  # read whole: a manifest's problem stops the run
        # health per mesh: each part of a body is its own mesh
        bodies = [part for body in scene.bodies for part in body.part_bodies()]
        units = scene.units
    else:
        bodies = [b for _, file_bodies in iter_inputs(inputs, on_error=skip) for b in file_bodies]
        units = None
    results = []
    for done, body in enumerate(bodies, start=1):
        try:
            results.append(inspect_body(body, declared_units=units))
        except InvalidMeshError as error:
            skip(error.path or body.source or "", error, body.name)
        if progress is not None:
            progress(f"inspect: {done}/{len(bodies)} bodies")
    if not results and first_error:
        raise first_error[0]
    return InspectReport(tuple(results), tuple(dict.fromkeys(fail_on)), units, tuple(errors))


def _is_manifest(inputs: Sequence[Any]) -> bool:
    from meshcol.io.scene import MANIFEST_EXTENSIONS

    return len(inputs) == 1 and os.path.splitext(os.fspath(inputs[0]))[1].lower() in (
        MANIFEST_EXTENSIONS
    )
