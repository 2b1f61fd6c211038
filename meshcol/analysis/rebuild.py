"""Rebuilt collision geometry for robot descriptions: ``meshcol hull|decompose ROBOT --out-dir``.

A robot (URDF or MJCF, read by :func:`meshcol.io.robot.load_robot`) gets new colliders per
collision element, and the description is written back around them
(:func:`meshcol.io.robot_write.write_robot`):

- ``hull``: ONE collider per collision element: the convex hull (within ``max_vertices``,
  still enclosing) of the element's mesh, every object of a multi-object mesh file together;
- ``decompose``: the convex parts of each element's mesh (each object of a mesh file
  decomposed on its own, as ``meshcol check --shape decomposed`` does, so the two share
  cache entries), through the content cache and ``jobs`` worker processes, one mesh a task;
- ``fit``: ONE enclosing primitive per collision element (:func:`meshcol.analysis.fit.fit_body`:
  box, sphere, capsule, cylinder or ellipsoid, or the hull when ``auto`` finds none within its
  volume tolerance), written as the description's own primitive element (``<box>``,
  ``<sphere>``, ``<cylinder>``; MJCF geom types, the ellipsoid included) at its pose. URDF
  has no ellipsoid: ``--shape ellipsoid`` to a URDF is refused before any fit; nor a capsule:
  one is written as a cylinder and two spheres (``urdf_capsules="standard"``, the default) or
  as the ``<capsule>`` extension (``"extension"``: :func:`meshcol.io.urdf_write.urdf_text`).

Primitive elements (box, sphere, cylinder, capsule) are kept as they are: they are already
exact convex colliders (a URDF's ``<capsule>`` is written in the form ``urdf_capsules``
says). Colliders are computed in the link frame (the element's origin and mesh scale baked
in), so the description places them with an identity origin.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.decomposition.options import DecomposeOptions, RunOptions
from meshcol.errors import InvalidMeshError, MeshcolError
from meshcol.io.robot import RobotOptions
from meshcol.io.urdf_write import parse_xml
from meshcol.types import Body

__all__ = ["robot_colliders", "rebuild_hulls", "rebuild_decomposition", "rebuild_fits"]


def _load(path: str, robot_options: RobotOptions) -> tuple[Any, list[Any], str]:
    from meshcol.io.robot import description_kind, load_robot

    elements: list[Any] = []
    scene = load_robot(path, robot_options, elements=elements)
    return scene, elements, description_kind(path)


def _groups(elements: list[Any]) -> list[tuple[str, int, list[Any]]]:
    """Elements grouped by (link, collision element), in order."""
    groups: dict[tuple[str, int], list[Any]] = {}
    for e in elements:
        groups.setdefault((e.link, e.index), []).append(e)
    return [(link, index, members) for (link, index), members in groups.items()]


def _link_poses(scene: Any, elements: list[Any]) -> dict[str, np.ndarray]:
    first: dict[str, Any] = {}
    for e in elements:
        first.setdefault(e.link, e)
    poses = {}
    for body in scene.bodies:
        pose = np.asarray(body.pose, dtype=np.float64)
        if body.primitive is not None:  # a link of one primitive: the body sits at its origin
            pose = pose @ np.linalg.inv(np.asarray(first[body.name].origin, dtype=np.float64))
        poses[body.name] = pose
    return poses


def _link_frame(e: Any) -> np.ndarray:
    return e.vertices @ e.origin[:3, :3].T + e.origin[:3, 3]


def _element_names(path: str, kind: str) -> dict[tuple[str, int], str]:
    """URDF ``<collision name>`` per (link, element), for the report rows."""
    if kind != "urdf":
        return {}
    root = parse_xml(path).getroot()  # as the reader read it
    return {
        (link.get("name"), i): c.get("name") or ""
        for link in root.findall("link")
        for i, c in enumerate(link.findall("collision"))
    }


def _label(link: str, index: int, kind: str) -> str:
    return f"link {link!r}: {'collision' if kind == 'urdf' else 'geom'} {index}"


#: The ways of :func:`robot_colliders` to rebuild an element.
METHODS = ("hull", "decompose", "fit")


@dataclass(frozen=True)
class _Element:
    """A collision element to rebuild: its meshes in the link frame, one block per object of
    its mesh file, and the same as one Body."""

    link: str
    index: int
    name: str  #: URDF ``<collision name>``, or ""
    label: str  #: names the element in messages (``link 'hand': collision 0``)
    number: int  #: its place among every element of the robot (kept primitives included)
    blocks: list[tuple[np.ndarray, np.ndarray]]
    body: Body

    def entry(self, results: Any) -> dict[str, Any]:
        """Its entry in :func:`robot_colliders`' list."""
        return {
            "link": self.link,
            "index": self.index,
            "name": self.name,
            "results": results,
            "body": self.body,
        }


def robot_colliders(
    path: str | os.PathLike[str],
    method: str,
    *,
    max_vertices: int | None = None,
    options: DecomposeOptions | None = None,
    run: RunOptions | None = None,
    fit_options: Mapping[str, Any] | None = None,
    target: Any = None,
    progress: Callable[[str], None] | None = None,
    robot_options: RobotOptions | None = None,
) -> tuple[Any, list[dict[str, Any]]]:
    """The colliders of a robot description and what each came from.

    Parameters
    ----------
    path : path
        URDF or MJCF, read with ``robot_options``.
    method : {"hull", "decompose", "fit"}
    max_vertices : int, optional
        ``hull``: the vertex budget of each hull.
    options, run : DecomposeOptions, RunOptions, optional
        ``decompose``: the engine's options and where it runs
        (:func:`meshcol.decomposition.batch.decompose_meshes`).
    fit_options : mapping, optional
        ``fit``: ``shape`` and ``volume_tolerance`` of :func:`meshcol.analysis.fit.fit_body`.
    target : Target, optional
        ``hull`` and ``decompose``: an engine profile (:mod:`meshcol.io.targets`) every
        element's colliders are fitted to (:func:`meshcol.collision.target_fit.fit_parts`; the
        description is in metres). ``hull``: the tighter of ``max_vertices`` and the
        profile's budget. ``decompose``: each object of an element's mesh file is fitted
        on its own, an element of k objects giving each ``max_hulls // k`` parts so that
        the element meets ``max_hulls``; each entry then has ``targets``, one report
        entry per decomposition.
    progress : callable, optional
    robot_options : RobotOptions, optional
        How the description is read (:func:`meshcol.io.robot.load_robot`); its package
        folders also find the visual meshes a URDF written as MJCF keeps.

    Returns
    -------
    (RobotColliders, list of dict)
        The colliders, and per rebuilt element ``{"link", "index", "name", "results"}``
        (``results``: the :class:`~meshcol.collision.hull.HullResult`, the decompositions
        of its meshes, or ``(BodyFit, mesh volume, max gap)``; and ``body``: the element's
        link-frame mesh as a Body).

    Raises
    ------
    SceneError, InputFileError
        As :func:`meshcol.io.robot.load_robot`.
    InvalidMeshError
        An element with no hull (flat beyond repair, collinear), naming its link.
    """
    from meshcol.io.robot_write import RobotColliders

    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}")
    if target is not None and method == "fit":
        raise ValueError("a target applies to hull and decompose, not fit")
    hull_limits = _hull_limits(method, target, max_vertices)
    source = os.fspath(path)
    robot_options = RobotOptions() if robot_options is None else robot_options
    scene, elements, kind = _load(source, robot_options)
    groups = _groups(elements)
    kept, rebuilt = _elements(source, kind, groups)
    report = _Progress(progress, method, len(groups))
    if method == "fit":
        made = [_fit(element, fit_options, source, report) for element in rebuilt]
    elif method == "hull":
        made = [_hull(element, max_vertices, hull_limits, target, report) for element in rebuilt]
    else:
        made = _decompositions(rebuilt, options, run, target, source, progress)
    by_element = {(c.link, c.index): c for c in kept}
    by_element.update({(c.link, c.index): c for c, _ in made})
    robot = RobotColliders(
        source=source,
        kind=kind,
        colliders=tuple(by_element[(link, index)] for link, index, _ in groups),
        link_poses=_link_poses(scene, elements),
        package_paths=dict(robot_options.package_paths),
        excluded_pairs=tuple(scene.excluded_pairs),
        warnings=tuple(scene.warnings),
    )
    return robot, [entry for _, entry in made]


def _hull_limits(method: str, target: Any, max_vertices: int | None) -> dict[str, Any] | None:
    """``hull`` with a target: its limits with ``max_vertices`` applied."""
    from meshcol.analysis.hull import target_limits

    if target is None or method != "hull":
        return None
    return target_limits(target, max_vertices)


def _elements(
    source: str, kind: str, groups: list[tuple[str, int, list[Any]]]
) -> tuple[list[Any], list[_Element]]:
    """The colliders of the primitive elements (kept as they are, being exact), and the
    elements to rebuild."""
    from meshcol.io.robot_write import Collider

    names = _element_names(source, kind)
    kept: list[Any] = []
    rebuilt: list[_Element] = []
    for number, (link, index, members) in enumerate(groups):
        name = names.get((link, index), "")
        first = members[0]
        if first.primitive is not None:
            kept.append(Collider(link, index, (), first.primitive, first.origin, name))
            continue
        blocks = [(_link_frame(e), np.asarray(e.faces, dtype=np.int64)) for e in members]
        body = _element_body(link, index, source, blocks)
        label = _label(link, index, kind)
        rebuilt.append(_Element(link, index, name, label, number, blocks, body))
    return kept, rebuilt


class _Progress:
    """``hull: 3/9 collision elements`` as each element starts."""

    def __init__(self, progress: Callable[[str], None] | None, method: str, total: int) -> None:
        self.progress, self.method, self.total = progress, method, total

    def __call__(self, element: _Element) -> None:
        if self.progress is not None:
            self.progress(f"{self.method}: {element.number + 1}/{self.total} collision elements")


def _fit(
    element: _Element, fit_options: Mapping[str, Any] | None, source: str, report: _Progress
) -> tuple[Any, dict[str, Any]]:
    """One enclosing primitive for the element (or its hull, when ``auto`` kept it)."""
    from meshcol.analysis.fit import fit_body
    from meshcol.io.primitives import written_primitive
    from meshcol.io.robot_write import Collider

    report(element)
    try:
        fitted = fit_body(element.body, **dict(fit_options or {}))
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{element.label}: {exc.message}", source) from None
    chosen = fitted[0].primitive_fit
    link, index, name = element.link, element.index, element.name
    if chosen is None:  # auto kept the hull
        hull = ((fitted[0].hull_vertices, fitted[0].hull_faces),)
        collider = Collider(link, index, hull, None, np.eye(4), name)
    else:
        solid = written_primitive(chosen.primitive)  # the report keeps the fit itself
        collider = Collider(link, index, (), solid, chosen.pose, name, fitted=True)
    return collider, element.entry(fitted)


def _hull(
    element: _Element,
    max_vertices: int | None,
    limits: dict[str, Any] | None,
    target: Any,
    report: _Progress,
) -> tuple[Any, dict[str, Any]]:
    """The element's hull: within ``max_vertices``, or fitted to the target's limits."""
    from meshcol.analysis.hull import target_hull
    from meshcol.collision.hull import convex_hull
    from meshcol.io.robot_write import Collider

    report(element)
    vertices = element.body.vertices
    try:
        if limits is None:
            result = convex_hull(vertices, max_vertices=max_vertices)
        else:
            result = target_hull(vertices, limits, target.length_scale("m"))
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{element.label}: {exc.message}", element.body.source) from None
    collider = Collider(element.link, element.index, ((result.vertices, result.faces),), None)
    return collider, element.entry(result)


def _decompositions(
    rebuilt: list[_Element],
    options: DecomposeOptions | None,
    run: RunOptions | None,
    target: Any,
    source: str,
    progress: Callable[[str], None] | None,
) -> list[tuple[Any, dict[str, Any]]]:
    """The convex parts of every element: each object of its mesh file decomposed on its
    own, all of them in one run (:func:`meshcol.decomposition.batch.decompose_meshes`), then
    fitted to the target."""
    from meshcol.io.robot_write import Collider

    meshes: list[tuple[str, np.ndarray, np.ndarray]] = []
    owners: list[int] = []  # the element of each entry of meshes
    for number, element in enumerate(rebuilt):
        single = len(element.blocks) == 1
        for k, (v, f) in enumerate(element.blocks):
            meshes.append((element.label if single else f"{element.label} object {k}", v, f))
            owners.append(number)
    entries = [element.entry([]) for element in rebuilt]
    parts: list[list[tuple[np.ndarray, np.ndarray]]] = [[] for _ in rebuilt]
    if target is not None:
        for entry in entries:
            entry["targets"] = []
    decompositions = _decompose_meshes(meshes, options, run, source, progress) if meshes else []
    objects = {owner: owners.count(owner) for owner in set(owners)}
    for owner, decomposition, (label, v, f) in zip(owners, decompositions, meshes):
        if target is not None:
            decomposition, fitted = _element_target(
                target, decomposition, v, f, objects[owner], label, source
            )
            entries[owner]["targets"].append(fitted)
        parts[owner].extend(decomposition.parts)
        entries[owner]["results"].append(decomposition)
    if meshes and target is not None and "max_hulls" in target.limits:
        for entry in entries:
            _element_hull_count(entry, int(target.limits["max_hulls"]))
    return [
        (
            Collider(element.link, element.index, tuple(parts[k]), None, np.eye(4), element.name),
            entries[k],
        )
        for k, element in enumerate(rebuilt)
    ]


def _decompose_meshes(
    meshes: list[tuple[str, np.ndarray, np.ndarray]],
    options: DecomposeOptions | None,
    run: RunOptions | None,
    source: str,
    progress: Callable[[str], None] | None,
) -> list[Any]:
    """:func:`meshcol.decomposition.batch.decompose_meshes`, its errors naming the robot."""
    from meshcol.decomposition.batch import decompose_meshes

    try:
        return decompose_meshes(meshes, options, run, progress=progress)
    except MeshcolError as exc:
        if exc.path is not None:
            raise
        raise type(exc)(exc.message, source) from None


def _element_target(
    target: Any,
    d: Any,
    vertices: np.ndarray,
    faces: np.ndarray,
    objects: int,
    label: str,
    source: str,
) -> tuple[Any, dict[str, Any]]:
    """One object's decomposition fitted to ``target`` (metres): an element of ``objects``
    objects gives each ``max_hulls // objects`` parts (at least 1), so the element's
    colliders together stay within ``max_hulls`` whenever ``objects <= max_hulls``."""
    import dataclasses

    from meshcol.decomposition.target import apply_target

    share = target
    count = target.limits.get("max_hulls")
    if count is not None and objects > 1:
        limits = dict(target.limits)
        limits["max_hulls"] = max(int(count) // objects, 1)
        share = dataclasses.replace(target, limits=limits)
    try:
        fitted, entry = apply_target(share, d, vertices, faces, "m")
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{label}: {exc.message}", source) from None
    if share is not target:
        entry["max_hulls_share"] = share.limits["max_hulls"]
    return fitted, entry


def _element_hull_count(row: dict[str, Any], limit: int) -> None:
    """An element of more objects than ``max_hulls`` allows (each object has at least one
    part) misses the limit as a whole: its last object's entry gets the MC106 violation."""
    from meshcol.collision.limits import Violation

    entries = row.get("targets") or []
    total = sum(len(d.parts) for d in row["results"])
    if not entries or total <= limit:
        return
    v = Violation("max_hulls", None, float(total), float(limit)).to_dict()
    v["message"] = (
        f"the collision element: {total} parts > max_hulls {limit} "
        f"(its {len(entries)} mesh objects are decomposed one by one)"
    )
    entries[-1]["violations"].append(v)
    entries[-1]["met"] = False


def _element_body(
    link: str, index: int, source: str, blocks: list[tuple[np.ndarray, np.ndarray]]
) -> Body:
    vertices, faces, base = [], [], 0
    for v, f in blocks:
        vertices.append(v)
        faces.append(f + base)
        base += len(v)
    return Body(
        name=f"{link}/{index}",
        source=source,
        vertices=np.ascontiguousarray(np.concatenate(vertices)),
        faces=np.ascontiguousarray(np.concatenate(faces)),
    )


def rebuild_hulls(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    to: str | None = None,
    max_vertices: int | None = None,
    reserved: tuple[tuple[str, str], ...] = (),
    warn: Callable[[str], None] | None = None,
    progress: Callable[[str], None] | None = None,
    target: Any = None,
    robot_options: RobotOptions | None = None,
    urdf_capsules: str = "standard",
) -> Any:
    """``meshcol hull ROBOT --out-dir OUT``: one hull per collision element, and the description.

    With ``target`` every element's hull meets the profile's limits and still encloses the
    element's mesh; each row then has ``target`` (met, costs, violations), as
    :func:`meshcol.analysis.hull.hull` rows do.

    Returns
    -------
    HullReport
        One row per rebuilt element (``name`` ``<link>/<element>``, ``output`` the file of its
        hull), ``frame="link"``, ``description`` the file written.
    """
    from meshcol.analysis.hull import HullReport, hull_row
    from meshcol.geometry.topology import oriented_volume
    from meshcol.io.robot_write import write_robot

    robot, info = robot_colliders(
        path,
        "hull",
        max_vertices=max_vertices,
        target=target,
        progress=progress,
        robot_options=robot_options,
    )
    to = to or robot.kind
    written = write_robot(robot, out_dir, to, protected=reserved, urdf_capsules=urdf_capsules)
    destination = _destinations(robot, to, out_dir, written)
    rows, hulls, warnings = [], [], _warned(robot, to, warn)
    for entry in info:
        body, result = entry["body"], entry["results"]
        volume = oriented_volume(body.vertices, body.faces)
        rows.append(hull_row(body, result, volume, destination(entry)))
        if target is not None:
            rows[-1]["target"] = {"name": target.name, **result.target_fit.to_dict()}
        hulls.append(result)
        if result.flat:
            message = f"{robot.source}: {_label(entry['link'], entry['index'], robot.kind)} is flat: the hull is a 2-D polygon"
            warnings.append(message)
            if warn is not None:
                warn(message)
    return HullReport(
        rows,
        tuple(hulls),
        max_vertices,
        **_rebuilt_report_fields(robot, out_dir, to, warnings),
        target=target,
    )


def rebuild_decomposition(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    options: DecomposeOptions | None = None,
    run: RunOptions | None = None,
    *,
    to: str | None = None,
    reserved: tuple[tuple[str, str], ...] = (),
    progress: Callable[[str], None] | None = None,
    target: Any = None,
    robot_options: RobotOptions | None = None,
    warn: Callable[[str], None] | None = None,
    urdf_capsules: str = "standard",
) -> Any:
    """``meshcol decompose ROBOT --out-dir OUT``: the convex parts of every collision element
    and the description that uses them.

    ``options.max_hausdorff`` is checked on every body (the search does not apply to a
    robot). With ``target`` the engine aims at the profile (its vertex budget and hull count,
    :meth:`~meshcol.decomposition.options.DecomposeOptions.aimed_at`) and every element's
    parts are then fitted to all its limits (:func:`robot_colliders`); each body has
    ``target`` and ``target_ok`` as :func:`~meshcol.decomposition.batch.decompose_files`
    bodies do.

    Returns
    -------
    DecomposeReport
        One file entry (the description), one body per rebuilt element (``<link>/<element>``,
        its part files, cache keys and metrics); ``frame="link"`` in the settings.
    """
    from meshcol.decomposition.report import DecomposeReport
    from meshcol.io.robot_write import description_path, write_robot

    start = time.perf_counter()
    options = options or DecomposeOptions()
    run = run or RunOptions()
    settings = _decomposition_settings(options, run, target)
    aimed = options if target is None else options.aimed_at(target)
    robot, info = robot_colliders(
        path,
        "decompose",
        options=aimed,
        run=run,
        target=target,
        progress=progress,
        robot_options=robot_options,
    )
    to = to or robot.kind
    write_robot(robot, out_dir, to, protected=reserved, urdf_capsules=urdf_capsules)
    warnings = _warned(robot, to, warn)
    description = description_path(robot.source, out_dir, to)
    bodies, rows = _decomposed_bodies(robot, info, to, description, options, target)
    entry_file = {
        "path": robot.source,
        "status": "ok",
        "message": "; ".join(warnings) or None,  # the reading's and the writing's warnings
        "bodies": bodies,
        "seconds": round(time.perf_counter() - start, 3),
    }
    settings.update(out_dir=os.fspath(out_dir), frame="link", description=description, to=to)
    return DecomposeReport([entry_file], rows, settings, "m", "parts", "obj", options.max_hausdorff)


def _decomposition_settings(
    options: DecomposeOptions, run: RunOptions, target: Any
) -> dict[str, Any]:
    """The report's settings of a robot's decomposition: the engine's options as given, the
    run's, and no search (parts in one layout, as OBJ)."""
    settings = {
        **options.report_settings(),
        **run.settings(),
        "layout": "parts",
        "format": "obj",
        "max_hausdorff": options.max_hausdorff,
        "max_parts": None,
        "search": options.search,
        "search_steps": None,
        "search_tolerance": None,
    }
    if target is not None:
        settings.update(target=target.name, target_limits=dict(target.limits))
    return settings


def _decomposed_bodies(
    robot: Any,
    info: list[dict[str, Any]],
    to: str,
    description: str,
    options: DecomposeOptions,
    target: Any,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """One report body and CSV row per decomposed mesh of every element
    (``<link>/<element>``, and ``/<object>`` for an element of several objects)."""
    from meshcol.decomposition.report import body_report
    from meshcol.io.robot_write import part_files

    files = part_files(robot) if to in ("urdf", "mjcf") else {}
    at = {(c.link, c.index): i for i, c in enumerate(robot.colliders)}
    bodies, rows = [], []
    for entry in info:
        outputs = files.get(at[(entry["link"], entry["index"])], [os.path.basename(description)])
        for k, d in enumerate(entry["results"]):
            name = f"{entry['link']}/{entry['index']}"
            if len(entry["results"]) > 1:
                name += f"/{k}"
            body, row = body_report(robot.source, name, outputs, d, options.max_hausdorff)
            if target is not None:
                body["target"] = entry["targets"][k]
                body["target_ok"] = body["target"]["met"]
                row["target_ok"] = body["target"]["met"]
            bodies.append(body)
            rows.append(row)
    return bodies, rows


def rebuild_fits(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    to: str | None = None,
    shape: str = "auto",
    volume_tolerance: float | None = None,
    reserved: tuple[tuple[str, str], ...] = (),
    progress: Callable[[str], None] | None = None,
    robot_options: RobotOptions | None = None,
    warn: Callable[[str], None] | None = None,
    urdf_capsules: str = "standard",
) -> Any:
    """``meshcol fit ROBOT --out-dir OUT``: one enclosing primitive per collision element,
    written into the description as its own primitive element.

    Returns
    -------
    FitReport
        One row per rebuilt element (``name`` ``<link>/<element>``, parameters in the link
        frame, ``output`` the description, or the hull's file when ``auto`` kept a hull),
        ``frame="link"``, ``description`` the file written.
    """
    from meshcol.analysis.fit import DEFAULT_VOLUME_TOLERANCE, FitReport, fit_row
    from meshcol.io.robot import description_kind
    from meshcol.io.robot_write import write_robot

    tolerance = DEFAULT_VOLUME_TOLERANCE if volume_tolerance is None else float(volume_tolerance)
    if shape == "ellipsoid" and (to or description_kind(path)) == "urdf":
        from meshcol.io.urdf_write import no_ellipsoid

        raise no_ellipsoid(os.fspath(path))  # before any fit: URDF cannot take one
    robot, info = robot_colliders(
        path,
        "fit",
        fit_options={"shape": shape, "volume_tolerance": tolerance},
        progress=progress,
        robot_options=robot_options,
    )
    to = to or robot.kind
    written = write_robot(robot, out_dir, to, protected=reserved, urdf_capsules=urdf_capsules)
    warnings = _warned(robot, to, warn)
    destination = _destinations(robot, to, out_dir, written)
    rows, fits = [], []
    for entry in info:
        result, volume, gap = entry["results"]
        rows.append(fit_row(entry["body"], result, volume, gap, destination(entry), shape))
        fits.append(result)
    return FitReport(
        rows,
        tuple(fits),
        shape,
        tolerance,
        **_rebuilt_report_fields(robot, out_dir, to, warnings),
    )


def _destinations(
    robot: Any, to: str, out_dir: str | os.PathLike[str], written: list[str]
) -> Callable[[dict[str, Any]], str]:
    """Where each rebuilt element's collider went (``entry`` of :func:`robot_colliders`): its
    own part file in ``out_dir`` (URDF and MJCF name one per mesh element), else the first
    file written (the description itself, or a scene of every collider)."""
    from meshcol.io.robot_write import part_files

    files = part_files(robot) if to in ("urdf", "mjcf") else {}
    at = {(c.link, c.index): i for i, c in enumerate(robot.colliders)}

    def destination(entry: dict[str, Any]) -> str:
        names = files.get(at[(entry["link"], entry["index"])])
        return os.path.join(os.fspath(out_dir), names[0]) if names else written[0]

    return destination


def _rebuilt_report_fields(
    robot: Any, out_dir: str | os.PathLike[str], to: str, warnings: list[str]
) -> dict[str, Any]:
    """The fields of a mesh-writing report (:class:`~meshcol.analysis.hull.MeshOutputReport`)
    for a robot rebuilt: no ``-o`` file, the folder, metres, the link frame and the
    description written."""
    from meshcol.io.robot_write import description_path

    return {
        "output": None,
        "out_dir": os.fspath(out_dir),
        "units": "m",
        "warnings": tuple(warnings),
        "frame": "link",
        "description": description_path(robot.source, out_dir, to),
        "to": to,
    }


def _warned(robot: Any, to: str, warn: Callable[[str], None] | None) -> list[str]:
    """The warnings of the description written (:func:`meshcol.io.robot_write.output_warnings`:
    the reading's, MC506 for a robot with no collision geometry, visuals left out), each
    given to ``warn`` (the command line prints them)."""
    from meshcol.io.robot_write import output_warnings

    warnings = output_warnings(robot, to)
    for message in warnings:
        if warn is not None:
            warn(message)
    return warnings
