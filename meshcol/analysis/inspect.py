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
from meshcol.geometry.topology import (
    component_count,
    duplicate_face_count,
    edge_table,
    oriented_volume,
)
from meshcol.geometry.triangles import degenerate_faces
from meshcol.io.report import vector_columns
from meshcol.types import Body

__all__ = [
    "InspectReport",
    "MeshInspection",
    "RULES",
    "inspect",
    "inspect_body",
    "guess_units",
]

#: ``--fail-on`` rules, each the name of a finding.
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
    measured = oriented_volume(vertices, faces) if watertight and winding_consistent else None
    volume = None if measured is None else measured[0]
    inverted = measured is not None and measured[1] < 0

    from meshcol.collision.self_intersection import self_intersecting_pairs

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
    if inverted:
        findings.append("inverted")
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

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``), a failure when it has a finding listed in ``fail_on`` (each
        finding with its measure: ``not-watertight (12 boundary edges)``), passed otherwise
        (other findings make it worth a warning); one error case per input that could not
        be inspected."""
        from meshcol.io.ci import CiCase, CiSuite, details

        cases = []
        for row in self.bodies:
            failed = row["failed_rules"]
            others = [rule for rule in row["findings"] if rule not in failed]
            if failed:
                message = ", ".join(_finding_text(rule, row) for rule in failed)
                if others:
                    message += "; also " + ", ".join(_finding_text(r, row) for r in others)
            elif others:
                message = "findings: " + ", ".join(_finding_text(r, row) for r in others)
            else:
                message = f"ok: {row['vertices']} vertices, {row['faces']} faces, watertight"
            cases.append(
                CiCase(
                    name=_case_name(row["source"], row["name"]),
                    classname="meshcol.inspect",
                    outcome="failure" if failed else "passed",
                    message=message,
                    file=row["source"],
                    kind=failed[0] if failed else None,
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
                    if failed
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
    fail_on: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    jobs: int = 1,
    timeout: float | None = None,
    executor: str = "local",
    ray_address: str | None = None,
) -> InspectReport:
    """Inspect every body of the inputs: is each mesh fit to be a collider?

    Parameters
    ----------
    inputs : path or sequence of paths
        Mesh files (every object, solid or mesh node is a body) or one scene manifest.
    fail_on : sequence of str
        Names of :data:`RULES` whose findings fail the run (:attr:`InspectReport.exit_code`).
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

    Returns
    -------
    InspectReport
        The same report whichever executor ran it.

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

    if executor != "ray" and ray_address is not None:
        raise ValueError("ray_address needs executor 'ray'")
    if jobs > 1 or timeout is not None or executor != "local":
        results, units = _inspect_tasks(
            inputs,
            skip,
            progress,
            jobs=jobs,
            timeout=timeout,
            executor=executor,
            address=ray_address,
        )
    elif _is_manifest(inputs):
        scene = load_scene(inputs[0])  # read whole: a manifest's problem stops the run
        # health per mesh: each part of a body is its own mesh
        bodies = [part for body in scene.bodies for part in body.part_bodies()]
        units = scene.units
    else:
        bodies = [b for _, file_bodies in iter_inputs(inputs, on_error=skip) for b in file_bodies]
        units = None
    if not (jobs > 1 or timeout is not None or executor != "local"):
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


def _inspect_file(
    task: tuple[str, list[Body] | None, str | None],
) -> tuple[list[tuple[str, Any]] | None, Exception | None]:
    """Worker entry of a parallel inspect: one file's ``(path, bodies, declared units)``
    (``bodies`` None: read the file here) to ``([(body name, MeshInspection or its
    InvalidMeshError)], None)``, or ``(None, the MeshcolError that made it unreadable)``."""
    from meshcol.errors import MeshcolError
    from meshcol.io.mesh_read import load_mesh

    path, bodies, units = task
    if bodies is None:
        try:
            bodies = load_mesh(path)
        except MeshcolError as error:
            return None, error
    out: list[tuple[str, Any]] = []
    for body in bodies:
        try:
            out.append((body.name, inspect_body(body, declared_units=units)))
        except InvalidMeshError as error:
            out.append((body.name, error))
    return out, None


def _inspect_tasks(
    inputs: list[Any],
    skip: Callable[..., None],
    progress: Callable[[str], None] | None,
    **run: Any,
) -> tuple[list[MeshInspection], str | None]:
    """The inspections of :func:`inspect` and the declared units, one executor task per
    file (a manifest's bodies grouped by mesh file): the same bodies, names (``unique_name``
    applied here, in input order), errors and order of errors as the sequential run
    (unreadable files first, then the bodies in order)."""
    import dataclasses

    from meshcol.decomposition.executor import run_each
    from meshcol.errors import MeshcolError
    from meshcol.io.robot import is_robot_file
    from meshcol.io.scene import iter_inputs, load_scene, unique_name

    units = None
    robot = len(inputs) == 1 and is_robot_file(inputs[0])
    if _is_manifest(inputs) or robot:
        # read whole on this process: a manifest's problem stops the run
        groups: dict[str, list[int]] = {}
        if robot:  # its links, as iter_inputs gives them
            parts = [body for _, bodies in iter_inputs(inputs) for body in bodies]
            source = os.fspath(inputs[0])
        else:
            scene = load_scene(inputs[0])
            units, source = scene.units, scene.source
            parts = [part for body in scene.bodies for part in body.part_bodies()]
        for k, part in enumerate(parts):
            groups.setdefault(part.source or source or part.name, []).append(k)
        tasks: list[tuple[str, list[Body] | None, str | None]] = [
            (path, [parts[k] for k in ks], units) for path, ks in groups.items()
        ]
        slots: list[list[int]] | None = list(groups.values())
        count = len(parts)
    else:
        tasks = [(os.fspath(path), None, None) for path in inputs]
        slots, count = None, 0
    outcomes: dict[int, Any] = {}
    for outcome in run_each(_inspect_file, tasks, **run):
        outcomes[outcome.index] = outcome
        if progress is not None:
            progress(f"inspect: {len(outcomes)}/{len(tasks)} files")
    # (source, name in its file, unique name, inspection or error) per body, in the
    # sequential run's order
    named: list[tuple[str, str, str, Any] | None] = [None] * count
    used: set[str] = set()
    for index, (path, _, _) in enumerate(tasks):
        outcome = outcomes[index]
        if outcome.status != "ok":
            skip(path, MeshcolError(outcome.message or outcome.status, path))
            continue
        found, error = outcome.value
        if error is not None:
            skip(path, error)
            continue
        if slots is not None:
            for k, (name, result) in zip(slots[index], found):
                named[k] = (path, name, name, result)
        else:
            named.extend((path, name, unique_name(name, used), result) for name, result in found)
    results = []
    for entry in named:
        if entry is None:  # its file's task failed
            continue
        path, original, name, result = entry
        if isinstance(result, MeshcolError):
            # raised before the body was renamed (``name#2``): its message names the body
            prefix = f"body '{original}': "
            if name != original and result.message.startswith(prefix):
                message = f"body '{name}': {result.message[len(prefix) :]}"
                result = type(result)(message, result.path)
            skip(result.path or path, result, name)
        else:
            results.append(
                result if result.name == name else dataclasses.replace(result, name=name)
            )
    return results, units


def _is_manifest(inputs: Sequence[Any]) -> bool:
    from meshcol.io.scene import MANIFEST_EXTENSIONS

    return len(inputs) == 1 and os.path.splitext(os.fspath(inputs[0]))[1].lower() in (
        MANIFEST_EXTENSIONS
    )
