"""Convex hulls of a scene's bodies, optionally within a vertex budget: ``meshcol hull``.

Each body's hull comes from :func:`meshcol.collision.hull.convex_hull` on its world vertices
(the scene transform applied, so exported colliders sit in place over the input); the meshes
are written through :func:`meshcol.io.mesh_write.write_meshes`, after every hull is computed,
so a bad body stops the run before any file is written.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from meshcol.errors import InvalidMeshError
from meshcol.io.mesh_write import MESH_OUTPUT_EXTENSIONS, MULTI_MESH_EXTENSIONS, safe_name
from meshcol.io.outputs import check_destinations
from meshcol.io.robot import RobotOptions
from meshcol.io.scene import as_scene
from meshcol.types import Body

__all__ = [
    "CSV_COLUMNS",
    "HullReport",
    "OutputDestinationError",
    "hull",
    "hull_row",
    "out_dir_paths",
    "target_hull",
    "target_limits",
]

#: Columns of :meth:`HullReport.to_csv`, one row per body.
CSV_COLUMNS = (
    "name",
    "source",
    "input_vertices",
    "input_faces",
    "hull_vertices",
    "hull_faces",
    "hull_volume",
    "hull_area",
    "mesh_volume",
    "volume_ratio",
    "flat",
    "max_vertices",
    "exact_hull_vertices",
    "exact_hull_faces",
    "exact_hull_volume",
    "added_volume",
    "added_volume_fraction",
    "max_distance",
    "output",
    "units",
)


#: What an inside-out mesh (negative signed volume) means for its hull.
INVERTED_NOTE = (
    "its faces point inward (negative mesh_volume); the hull does not depend on winding and is "
    "unaffected"
)


class OutputDestinationError(ValueError):
    """The hulls cannot go where they were asked to: several bodies for a single-mesh format.

    Attributes
    ----------
    output : str
        The requested file.
    bodies : int
        How many bodies the input has.
    """

    def __init__(self, output: str, bodies: int) -> None:
        self.output = output
        self.bodies = bodies
        super().__init__(
            f"{output}: {bodies} bodies need a file that holds several meshes "
            f"({', '.join(MULTI_MESH_EXTENSIONS)}) or out_dir"
        )


class MeshOutputReport:
    """What the reports of the commands that write meshes (:class:`HullReport`,
    :class:`meshcol.analysis.fit.FitReport`) share: where the meshes went in the settings, and
    the JSON report (the envelope, the summary, one entry per body and, for a robot rebuilt,
    what the description leaves out).

    A subclass is a frozen dataclass with these fields, and names its command in
    ``command`` and its options in ``settings``."""

    command: ClassVar[str]
    bodies: list[dict[str, Any]]
    output: str | None
    out_dir: str | None
    units: str | None
    warnings: tuple[str, ...]
    frame: str
    description: str | None
    to: str | None

    @property
    def summary(self) -> dict[str, Any]:
        raise NotImplementedError

    @property
    def settings(self) -> dict[str, Any]:
        raise NotImplementedError

    def destination_settings(self) -> dict[str, Any]:
        """The settings that say where the meshes went: frame, output, out_dir and, for a
        robot rebuilt, the description written and its format."""
        settings: dict[str, Any] = {
            "frame": self.frame,
            "output": self.output,
            "out_dir": self.out_dir,
        }
        if self.description is not None:
            settings.update(description=self.description, to=self.to)
        return settings

    @property
    def files_written(self) -> int:
        """How many mesh files the bodies went to (several bodies may share one)."""
        return len({row["output"] for row in self.bodies if row["output"] is not None})

    def case_name(self, row: dict[str, Any]) -> str:
        """A body's CI case name: ``FILE::BODY``, or the body's name alone without a file
        (the snapshots of its failures are named the same: :mod:`meshcol.analysis.snapshots`)."""
        return f"{row['source']}::{row['name']}" if row["source"] else str(row["name"])

    def to_dict(self) -> dict[str, Any]:
        """The JSON report: the common envelope, the summary and one entry per body."""
        from meshcol.io.report import envelope

        report = {
            **envelope(self.command, self.settings, self.units),
            "summary": self.summary,
            "bodies": self.bodies,
        }
        if self.description is not None:  # a robot rebuilt: what the description leaves out
            report["warnings"] = list(self.warnings)
        return report

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())


@dataclass(frozen=True)
class HullReport(MeshOutputReport):
    """What :func:`hull` computed and wrote.

    Attributes
    ----------
    bodies : list of dict
        Per body (:data:`CSV_COLUMNS` and ``note``): input and hull sizes, hull volume and
        area, mesh volume (closed meshes only), ``volume_ratio = mesh / hull volume``, ``flat``
        and, with a budget, ``added_volume``, ``added_volume_fraction``, ``max_distance``;
        ``output``, the file the hull went to (None when not written).
    hulls : tuple of HullResult
        The hulls, world frame, in the order of ``bodies``.
    max_vertices : int or None
        The vertex budget.
    output, out_dir : str or None
        Where the meshes went (one file, or one file per body in a folder).
    units : str or None
        The scene manifest's units.
    warnings : tuple of str
        One line per flat body (``FILE: body 'NAME' is flat: ...``).
    frame : {"world", "link"}
        Frame of the hulls: ``link`` for a robot rebuilt (:func:`meshcol.analysis.rebuild.rebuild_robot`).
    description, to : str or None
        The robot description written with the hulls, and its format.
    target : Target or None
        The engine profile every hull was fitted to (:mod:`meshcol.io.targets`); each row
        then has a ``target`` entry (limits met, what each cost, violations).
    """

    bodies: list[dict[str, Any]]
    hulls: tuple[Any, ...]
    max_vertices: int | None
    output: str | None
    out_dir: str | None
    units: str | None
    warnings: tuple[str, ...] = ()
    frame: str = "world"
    description: str | None = None
    to: str | None = None
    target: Any = None

    command: ClassVar[str] = "hull"

    @property
    def violations(self) -> list[tuple[str, Any]]:
        """``(body name, Violation)`` for every target limit a hull could not meet."""
        return [
            (row["name"], violation)
            for row, fit in zip(self.bodies, self.fits)
            if fit is not None
            for violation in fit.violations
        ]

    @property
    def fits(self) -> list[Any]:
        """The :class:`~meshcol.collision.target_fit.TargetFit` of each body (None without a
        target)."""
        return [h.target_fit for h in self.hulls]

    @property
    def exit_code(self) -> int:
        """1 when a hull misses a limit of ``target``; else 0 (unusable input raises)."""
        return 1 if self.violations else 0

    @property
    def summary(self) -> dict[str, Any]:
        """Counts: bodies, flat bodies, total hull vertices, files written."""
        summary = {
            "bodies": len(self.bodies),
            "flat": sum(1 for row in self.bodies if row["flat"]),
            "hull_vertices": sum(row["hull_vertices"] for row in self.bodies),
            "files_written": self.files_written,
        }
        if self.target is not None:
            summary["target_violations"] = len(self.violations)
        return summary

    @property
    def settings(self) -> dict[str, Any]:
        settings: dict[str, Any] = {
            "max_vertices": self.max_vertices,
            **self.destination_settings(),
        }
        if self.target is not None:
            settings["target"] = self.target.name
            settings["target_limits"] = dict(self.target.limits)
        return settings

    def to_csv(self) -> str:
        """One row per body (:data:`CSV_COLUMNS`)."""
        from meshcol.io.report import dumps_csv

        return dumps_csv([dict(row, units=self.units) for row in self.bodies], CSV_COLUMNS)

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one case per body
        (``FILE::BODY``) with the hull's size, volume and, with a budget, what the budget
        cost; a failure if a hull were over its vertex budget, or misses a limit of the
        ``--target`` (the rules it breaks, MC1xx/MC201, as the exit code counts them;
        unusable input stops the run before any report, so there are no error cases)."""
        from meshcol.analysis.rules import get_rule
        from meshcol.io.ci import CiCase, CiSuite, number

        units = self.units
        cases = []
        for row, fitted in zip(self.bodies, self.fits):
            missed = tuple(fitted.violations) if fitted is not None else ()
            message = (
                f"{row['hull_vertices']} vertices, {row['hull_faces']} faces, volume "
                f"{number(row['hull_volume'])}"
            )
            if row["volume_ratio"] is not None:
                message += f", mesh/hull volume {number(row['volume_ratio'])}"
            if row["flat"]:
                message += ", flat (a 2-D polygon)"
            over = row["max_vertices"] is not None and row["hull_vertices"] > row["max_vertices"]
            if row["max_vertices"] is not None:
                message += (
                    f"; budget {row['max_vertices']} (exact hull "
                    f"{row['exact_hull_vertices']}): added volume "
                    f"{number(row['added_volume_fraction'])} of the hull's, max distance "
                    f"{number(row['max_distance'], units)}"
                )
            if over:
                message = f"over the --max-vertices budget: {message}"
            if missed:
                past = "; ".join(f"{v.rule} {v.rule_name}: {v.message}" for v in missed)
                message = f"misses the target's limits: {past}; {message}"
            rules = tuple(dict.fromkeys(v.rule for v in missed))
            cases.append(
                CiCase(
                    name=self.case_name(row),
                    classname="meshcol.hull",
                    outcome="failure" if over or missed else "passed",
                    message=message,
                    file=row["source"],
                    kind="max-vertices" if over else (rules[0] if rules else None),
                    rules=rules,
                )
            )
        s = self.summary
        cited = sorted({rule for case in cases for rule in case.rules})
        return CiSuite(
            "hull",
            tuple(cases),
            self.settings,
            warnings=self.warnings,
            verdict=f"{s['bodies']} hulls, {s['hull_vertices']} vertices, {s['flat']} flat",
            units=units,
            rules={rule: get_rule(rule).to_dict() for rule in cited},
        )


def out_dir_paths(out_dir: str | os.PathLike[str], names: Sequence[str]) -> list[str]:
    """``DIR/<name>.obj`` per body: names made file-safe (:func:`safe_name`) and unique
    (``-2``, ``-3``, ... on a clash, case-insensitively)."""
    paths, used = [], set()
    for name in names:
        safe = safe_name(name)
        candidate, k = safe, 2
        while candidate.lower() in used:
            candidate = f"{safe}-{k}"
            k += 1
        used.add(candidate.lower())
        paths.append(os.path.join(os.fspath(out_dir), candidate + ".obj"))
    return paths


def mesh_destinations(
    output: str | os.PathLike[str] | None, out_dir: str | os.PathLike[str] | None
) -> tuple[str | None, str | None]:
    """``output`` and ``out_dir`` as strings, checked: not both, a known mesh extension."""
    if output is not None and out_dir is not None:
        raise ValueError("give either output or out_dir, not both")
    output = None if output is None else os.fspath(output)
    out_dir = None if out_dir is None else os.fspath(out_dir)
    if output is not None:
        extension = os.path.splitext(output)[1].lower()
        if extension not in MESH_OUTPUT_EXTENSIONS:
            raise ValueError(
                f"unknown mesh extension {extension or '(none)'!r} in {output!r} "
                f"(expected {', '.join(MESH_OUTPUT_EXTENSIONS)})"
            )
    return output, out_dir


def check_body_count(output: str | None, bodies: int) -> None:
    """:class:`OutputDestinationError` for several bodies in a single-mesh output format."""
    if (
        output is not None
        and bodies > 1
        and os.path.splitext(output)[1].lower() not in MULTI_MESH_EXTENSIONS
    ):
        raise OutputDestinationError(output, bodies)


def write_body_meshes(
    bodies: Sequence[Body],
    meshes: Sequence[tuple[str, Any, Any]],
    output: str | None,
    out_dir: str | None,
    reserved: Sequence[tuple[str, str | os.PathLike[str] | None]] = (),
) -> list[str | None]:
    """Write one named mesh per body (``(name, vertices, faces)``, world frame) to ``output``
    or to ``out_dir/<body>.obj`` (:func:`out_dir_paths`), after checking that no file would
    replace an input mesh or a ``reserved`` file. Returns where each body's mesh went."""
    from meshcol.io.mesh_write import write_meshes

    names = [b.name for b in bodies]
    planned = [("output", output)] if output is not None else []
    if out_dir is not None:
        planned = [("--out-dir file", path) for path in out_dir_paths(out_dir, names)]
    sources = {b.source for b in bodies if b.source is not None}
    check_destinations(
        [("an input mesh", source) for source in sorted(sources)], [*planned, *reserved]
    )
    if output is not None:
        write_meshes(output, list(meshes))
        return [output] * len(bodies)
    if out_dir is not None:
        from meshcol.io.outputs import staged_folder

        paths = out_dir_paths(out_dir, names)
        with staged_folder(out_dir) as stage:  # every hull, or none (and no folder)
            for path, mesh in zip(paths, meshes):
                write_meshes(os.path.join(stage, os.path.basename(path)), [mesh])
        return list(paths)
    return [None] * len(bodies)


def hull(
    inputs: Any,
    *,
    max_vertices: int | None = None,
    output: str | os.PathLike[str] | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    warn: Callable[[str], None] | None = None,
    reserved: Sequence[tuple[str, str | os.PathLike[str] | None]] = (),
    progress: Callable[[str], None] | None = None,
    target: Any = None,
    robot_options: RobotOptions | None = None,
) -> HullReport:
    """Convex hull of each body, in the world frame, optionally within a vertex budget.

    Parameters
    ----------
    inputs : Scene, sequence of Body, or path(s) of meshes / one scene manifest
        The bodies; each body's pose is applied to its vertices.
    max_vertices : int, optional
        At most this many vertices per hull (>= 4); the hull still contains every input
        vertex (faces are grown outward, never pulled in).
    output : path, optional
        Write every hull to this file (format from the extension, one named object or node
        per body; several bodies need ``.obj`` or ``.glb``).
    out_dir : path, optional
        Write ``out_dir/<body>.obj`` per body (see :func:`out_dir_paths`); created if missing.
    warn : callable, optional
        Receives one line per flat or inside-out body as it is found (also kept in
        ``warnings``).
    reserved : sequence of (label, path)
        Other files the caller will write (``("--report", "r.json")``): no hull may go there.
    progress : callable, optional
        Receives one line per hull computed (``hull: 3/10 bodies``).
    target : Target, optional
        An engine profile (:func:`meshcol.io.targets.load_target`): every hull meets all
        its limits (:func:`meshcol.collision.target_fit.fit_hull`) and still encloses the body;
        a ``max_vertices`` tighter than the profile's vertex budget wins, a looser one is
        ignored (the tighter of the two always applies). ``min_thickness`` and
        ``min_volume`` are converted from metres to the scene's ``units`` (else the
        profile's). A limit that cannot be met is reported, never hidden: the row's
        ``target.violations`` (rule ids MC1xx/MC201) and ``exit_code`` 1.
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.load_inputs`).

    Returns
    -------
    HullReport

    Raises
    ------
    ValueError
        Both ``output`` and ``out_dir``, or an unknown output extension.
    OutputDestinationError
        Several bodies for a single-mesh output format.
    InvalidMeshError
        A body has no hull (collinear or single-point input, non-finite coordinates, or
        coordinates beyond :data:`meshcol.collision.hull.MAX_ABS_COORDINATE`).
    OutputPathError
        A hull file would replace an input mesh or a ``reserved`` file (nothing is written).

    Notes
    -----
    Hulls by :func:`meshcol.collision.hull.convex_hull` (Quickhull, Barber, Dobkin and
    Huhdanpaa 1996, in the core; the budget by outward face growth). Mesh volumes by
    :func:`meshcol.geometry.topology.oriented_volume` (closed meshes only). An inside-out
    mesh (negative volume, the ``inverted`` finding of ``meshcol inspect``) gets the same hull
    as the outward one, since a hull depends on the vertices only; its row says so in
    ``note`` and a warning goes out.
    """
    output, out_dir = mesh_destinations(output, out_dir)
    scene = as_scene(inputs, robot_options)
    bodies = scene.bodies
    check_body_count(output, len(bodies))
    # Compute everything first: a bad body stops the run before any file is written.
    hulls, volumes, warnings = _body_hulls(scene, max_vertices, target, warn, progress)
    destinations = write_body_meshes(
        bodies,
        [(b.name, h.vertices, h.faces) for b, h in zip(bodies, hulls)],
        output,
        out_dir,
        reserved,
    )
    rows = [
        hull_row(body, result, volume, destination)
        for body, result, volume, destination in zip(bodies, hulls, volumes, destinations)
    ]
    if target is not None:
        for row, result in zip(rows, hulls):
            row["target"] = {"name": target.name, **result.target_fit.to_dict()}
    return HullReport(
        rows,
        tuple(hulls),
        max_vertices,
        output,
        out_dir,
        scene.units,
        tuple(warnings),
        target=target,
    )


def _body_hulls(
    scene: Any,
    max_vertices: int | None,
    target: Any,
    warn: Callable[[str], None] | None,
    progress: Callable[[str], None] | None,
) -> tuple[list[Any], list[tuple[float, int] | None], list[str]]:
    """The hull of every body of ``scene`` (within the budget or the target's limits), the
    mesh volume of each (None when not closed), and the warnings (flat, inside-out bodies),
    each also given to ``warn`` as it is found."""
    from meshcol.analysis.rules import robot_warnings
    from meshcol.geometry.topology import oriented_volume

    limits = None if target is None else target_limits(target, max_vertices)
    length_scale = 1.0 if target is None else float(target.length_scale(scene.units))
    hulls, volumes, warnings = [], [], []

    def say(message: str) -> None:
        warnings.append(message)
        if warn is not None:
            warn(message)

    for empty in robot_warnings(scene):  # a robot with no collision geometry (MC506)
        say(empty)
    if limits is None:
        made = iter(_budget_hulls(scene.bodies, max_vertices, progress))
    else:
        made = _target_hulls(scene.bodies, limits, length_scale)
    for done, body in enumerate(scene.bodies, start=1):
        if limits is not None and progress is not None:
            progress(f"hull: {done}/{len(scene.bodies)} bodies")
        hulls.append(next(made))
        if isinstance(hulls[-1], InvalidMeshError):
            raise _body_error(body, hulls[-1]) from hulls[-1]
        if hulls[done - 1].flat:
            say(f"{body.source}: body '{body.name}' is flat: the hull is a 2-D polygon")
        volumes.append(oriented_volume(body.vertices, body.faces))
        if volumes[-1] is not None and volumes[-1][1] < 0:
            say(f"{body.source}: body '{body.name}' is inside out: {INVERTED_NOTE}")
    return hulls, volumes, warnings


def _body_error(body: Body, exc: InvalidMeshError) -> InvalidMeshError:
    return InvalidMeshError(f"body '{body.name}': {exc.message}", body.source)


def _budget_hulls(
    bodies: Sequence[Body], max_vertices: int | None, progress: Callable[[str], None] | None
) -> list[Any]:
    """:func:`meshcol.collision.hull.convex_hull` of every body's world vertices, the budget
    loops of all in one native call (threads over bodies); the first body without a hull
    raises, named."""
    from meshcol.collision.hull import exact_hull, hull_within_budget, hulls_within_budgets

    exacts = []
    for done, body in enumerate(bodies, start=1):
        if progress is not None:
            progress(f"hull: {done}/{len(bodies)} bodies")
        try:
            exacts.append(exact_hull(body.world_vertices()))
            if exacts[-1].dimension < 2:
                hull_within_budget(exacts[-1], max_vertices)  # raises: no meaningful hull
        except InvalidMeshError as exc:
            raise _body_error(body, exc) from exc
    results = hulls_within_budgets(exacts, [(max_vertices, None)] * len(exacts))
    for body, result in zip(bodies, results, strict=True):
        if isinstance(result, InvalidMeshError):  # a budget loop failed (never seen)
            raise _body_error(body, result) from result
    return results


#: Bodies whose target fits run side by side (:func:`_target_hulls`), their hulls and
#: measures asked for in one batch a round.
FIT_BATCH = 512


def _target_hulls(bodies: Any, limits: dict, length_scale: float) -> Iterator[Any]:
    """:func:`target_hull` of each body's world vertices, in order (or the
    :class:`InvalidMeshError` of a body without one), made :data:`FIT_BATCH` bodies at a
    time by :func:`meshcol.collision.target_fit.fit_hulls`."""
    from meshcol.collision.target_fit import fit_caches, fit_hulls

    for start in range(0, len(bodies), FIT_BATCH):
        chunk = range(start, min(start + FIT_BATCH, len(bodies)))
        points = [bodies[i].world_vertices() for i in chunk]
        caches = fit_caches(points, limits)
        fits = fit_hulls(points, limits, length_scale, caches)
        for pts, cache, fit in zip(points, caches, fits, strict=True):
            if isinstance(fit, InvalidMeshError):
                yield fit
            else:
                yield _target_result(pts, limits, fit, cache)


def target_limits(target: Any, max_vertices: int | None) -> dict[str, Any]:
    """A target's limits with ``--max-vertices`` applied: the tighter vertex count wins."""
    limits = dict(target.limits)
    if max_vertices is not None:
        limits["max_hull_vertices"] = min(
            int(max_vertices), int(limits.get("max_hull_vertices", max_vertices))
        )
    return limits


def target_hull(points: Any, limits: dict, length_scale: float, cache: Any = None) -> Any:
    """The hull of ``points`` fitted to ``limits``, as a :class:`HullResult` (its exact-hull
    fields from the input) that also carries the fit (``target_fit``); ``cache``: the
    points' :class:`~meshcol.collision.fit_cache.FitCache`, made already."""
    from meshcol.collision.target_fit import FitCache, fit_hull

    cache = FitCache() if cache is None else cache
    return _target_result(points, limits, fit_hull(points, limits, length_scale, cache), cache)


def _target_result(points: Any, limits: dict, fit: Any, cache: Any) -> Any:
    """:func:`target_hull`'s result of the fit ``fit`` of ``points`` (its cache ``cache``)."""
    from meshcol.collision.hull import HullResult
    from meshcol.collision.limits import budget_vertices

    vertices, faces = fit.parts[0]
    exact = cache.exact(points)
    out = cache.exact(vertices)
    flat = out.dimension < 3
    exact_volume = exact.volume if exact.dimension == 3 else 0.0
    result = HullResult(
        vertices=vertices,
        faces=faces,
        volume=out.volume if not flat else 0.0,
        area=out.area,
        flat=flat,
        exact_vertex_count=len(exact.vertices),
        exact_face_count=len(exact.faces),
        exact_volume=exact_volume,
        max_vertices=budget_vertices(limits),
        added_volume=fit.added_volume,
        added_volume_fraction=fit.added_volume / exact_volume if exact_volume > 0 else None,
        max_distance=fit.max_distance,
        target_fit=fit,
    )
    return result


def hull_row(
    body: Body, result: Any, volume: tuple[float, int] | None, destination: str | None
) -> dict:
    """One report row (:data:`CSV_COLUMNS` and ``note``) for a body and its hull."""
    budget = result.max_vertices is not None or result.target_fit is not None
    mesh_volume = None if volume is None else volume[0]
    ratio = None
    if mesh_volume is not None and result.volume > 0:
        ratio = abs(mesh_volume) / result.volume
    note = None
    if result.flat:
        note = "coplanar input: the hull is a 2-D polygon (volume 0)"
    elif volume is not None and volume[1] < 0:
        note = f"inside-out mesh: {INVERTED_NOTE}"
    return {
        "name": body.name,
        "source": body.source,
        "input_vertices": len(body.vertices),
        "input_faces": len(body.faces),
        "hull_vertices": len(result.vertices),
        "hull_faces": len(result.faces),
        "hull_volume": result.volume,
        "hull_area": result.area,
        "mesh_volume": mesh_volume,
        "volume_ratio": ratio,
        "flat": result.flat,
        "note": note,
        "max_vertices": result.max_vertices,
        "exact_hull_vertices": result.exact_vertex_count,
        "exact_hull_faces": result.exact_face_count,
        "exact_hull_volume": result.exact_volume,
        "added_volume": result.added_volume if budget else None,
        "added_volume_fraction": result.added_volume_fraction if budget else None,
        "max_distance": result.max_distance if budget else None,
        "output": destination,
    }
