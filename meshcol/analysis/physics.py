"""Physics readiness: each body's collider against its visual mesh.

:func:`physics_readiness` builds each body's collider (the one every command builds,
:func:`meshcol.analysis.colliders.build_colliders`), gives it and the body's visual mesh mass
properties, and runs the physics rules over them, one named check per rule group:

- authored collision triangles: inside out (MC204), ``UCX_`` parts not convex (MC303);
- an engine target's limits on the convex parts (MC101..MC107, MC201);
- per collider body (:data:`BODY_CHECKS`): ``UCX_`` parts naming nothing (MC302), parts
  without ``UCX_`` parts in a ``UCX_`` input (MC301), flat convex parts (MC202) and tiny
  colliders (MC203), and the comparison with the visual mesh (:data:`COMPARISONS`: volume
  MC205, inertia MC207, centre of mass MC206; no area MC301);
- a robot's links with visual geometry and no collision element (MC301).

The collider's mass properties are each convex part's: its exact hull's (the core's) from
:func:`meshcol.geometry.mass.mass_properties` (signed tetrahedra), or its exact primitive's
(:func:`~meshcol.geometry.mass.primitive_mass_properties`), summed over the parts as engines sum
a body's shapes (overlaps count twice); a ``mesh`` collider is its triangles. A mesh's and a
convex part's properties in their own frame are computed once per unique geometry and moved by
each body's pose, as for a body alone: bodies that instance one prop cost one measurement.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.analysis.geometry_cache import GeometryCache
from meshcol.analysis.rules import Finding, finding
from meshcol.errors import InvalidMeshError
from meshcol.geometry.mass import MassProperties
from meshcol.types import Body
from meshcol.vocabulary import COLLIDER_KINDS

__all__ = [
    "BODY_CHECKS",
    "COMPARISONS",
    "PhysicsOptions",
    "UCX_CONVEX_FRACTION",
    "physics_readiness",
]

#: A UCX_ part whose volume is below this fraction of its hull's is not convex (MC303).
UCX_CONVEX_FRACTION = 0.99


@dataclass(frozen=True)
class PhysicsOptions:
    """How :func:`physics_readiness` builds colliders and what it tolerates.

    Attributes
    ----------
    shape : str
        The collider of each body (:data:`meshcol.vocabulary.COLLIDER_KINDS`, as
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
        """Raise ValueError naming the first option out of its range."""
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
        """The options as the report's ``settings`` list them."""
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


def physics_readiness(
    bodies: Sequence[Body],
    options: PhysicsOptions | None = None,
    *,
    visuals: dict[str, Body] | None = None,
    progress: Callable[[str], None] | None = None,
    units: str | None = None,
    _geometries: GeometryCache | None = None,
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
    """
    from meshcol.analysis.colliders import build_colliders, split_ucx

    options = options or PhysicsOptions()
    options.validate()
    # What a mesh or a convex part decides in its own frame, once per geometry: instances
    # share it and apply their own poses, in the order of operations of one body alone.
    # (inspect passes the ones its health phase measured: _geometries)
    geometries = _geometries if _geometries is not None else GeometryCache()
    findings = authored_mesh_findings(bodies, options, visuals is not None, geometries)
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
    run = _Readiness(
        options=options,
        colliders=colliders,
        geometries=geometries,
        visuals=visuals,
        input_names={body.name for body in bodies},
        ucx_owners=split_ucx(bodies)[1],
    )
    rows: list[dict[str, Any]] = []
    items = [_ColliderBody.of(run, index) for index in range(len(colliders.bodies))]
    _measure_all(run, items)
    found = [[f for check in BODY_CHECKS for f in check(item)] for item in items]
    _mass_rows(items)
    for item, item_findings in zip(items, found):
        findings.extend(item_findings)
        findings.extend(_comparisons(item))
        rows.append(item.row)
    if visuals is not None:
        findings.extend(_links_without_collision(visuals, colliders))
    return rows, findings


# ---------------------------------------------------------------------------------------------
# Authored collision triangles (MC204, MC303)


def authored_mesh_findings(
    bodies: Sequence[Body], options: PhysicsOptions, robot: bool, geometries: GeometryCache
) -> list[Finding]:
    """Authored collision triangles (``UCX_`` parts; a robot's collision meshes; every mesh
    under ``--shape mesh``) that are inside out (MC204) or, for ``UCX_`` parts, not convex
    (MC303)."""
    return [
        found
        for body in bodies
        for part_name, vertices, faces in body.part_meshes()
        for found in _authored_part(body, part_name, vertices, faces, options, robot, geometries)
    ]


def _authored_part(
    body: Body,
    part_name: str | None,
    vertices: np.ndarray,
    faces: np.ndarray,
    options: PhysicsOptions,
    robot: bool,
    geometries: GeometryCache,
) -> list[Finding]:
    from meshcol.analysis.colliders import _UCX

    own_name = part_name if part_name is not None else body.name.rpartition("/")[2]
    is_ucx = bool(_UCX.match(own_name))
    authored = is_ucx or (robot and body.primitive is None) or options.shape == "mesh"
    if not authored or body.primitive is not None:
        return []
    geometry = geometries.get(vertices, faces)
    measured = geometry.oriented_volume
    if measured is None:
        return []
    volume, orientation = measured
    if orientation < 0:
        what = "UCX_ part" if is_ucx else "collision mesh"
        message = f"{what} is inside out: volume {volume:.6g}"
        return [finding("MC204", body.name, part_name, volume, 0.0, message)]
    if orientation > 0 and is_ucx:
        return _ucx_not_convex(body.name, part_name, volume, geometry.hull_volume)
    return []


def _ucx_not_convex(
    body_name: str, part_name: str | None, volume: float, hull_volume: float | None
) -> list[Finding]:
    if hull_volume is None or not (hull_volume > 0 and volume / hull_volume < UCX_CONVEX_FRACTION):
        return []
    fraction = volume / hull_volume
    message = f"UCX_ part is not convex: {fraction:.1%} of its hull's volume"
    return [finding("MC303", body_name, part_name, fraction, UCX_CONVEX_FRACTION, message)]


# ---------------------------------------------------------------------------------------------
# Per collider body


@dataclass
class _Readiness:
    """One :func:`physics_readiness` run: what every body's checks read."""

    options: PhysicsOptions
    colliders: Any  # meshcol.analysis.colliders.Colliders
    geometries: GeometryCache
    visuals: dict[str, Body] | None
    input_names: set[str]
    ucx_owners: dict[str, Any]  # owner name -> its UCX_ parts (colliders.split_ucx)
    # convex part geometry key -> its hull's dimension and (mass, relative volume)
    hulls: dict[bytes, tuple[int, tuple[MassProperties, float] | None]] = field(
        default_factory=dict
    )
    # convex part (index in colliders) -> its geometry key, for the polytopes
    part_keys: dict[int, bytes] = field(default_factory=dict)


@dataclass
class _ColliderBody:
    """One collider body as the checks of :data:`BODY_CHECKS` see it, its report row filled
    in as they run."""

    run: _Readiness
    index: int
    body: Body
    kind: str
    parts: range  # its convex parts in run.colliders
    render_parts: list[str]  # its parts that are not UCX_ parts
    grouped: bool  # loose UCX_ parts naming nothing, grouped into a body of their own
    row: dict[str, Any]
    collider: MassProperties | None = None  # world frame, set by _collider_mass
    visual: MassProperties | None = None  # world frame, set by _visual_mass
    # (visual mesh closed, its world bounding-box diagonal): set by _visual_mass when the
    # collider is to be compared with it (_comparisons)
    compare: tuple[bool, float] | None = None
    moment_ratio: float | None = None  # set by _mass_rows (_moment_ratios)

    @classmethod
    def of(cls, run: _Readiness, index: int) -> _ColliderBody:
        from meshcol.analysis.colliders import _UCX

        body = run.colliders.bodies[index]
        offsets = run.colliders.body_part_offsets
        parts = range(int(offsets[index]), int(offsets[index + 1]))
        kind = run.colliders.kinds[index]
        return cls(
            run=run,
            index=index,
            body=body,
            kind=kind,
            parts=parts,
            render_parts=[name for name in body.parts if not _UCX.match(name)],
            grouped=body.name not in run.input_names,
            row={
                "body": body.name,
                "collider": kind,
                "convex_parts": len(parts),
                "visual_source": None,
                "comparison": None,
                "collider_mass": None,
                "visual_mass": None,
                "volume_ratio": None,
                "center_of_mass_offset": None,
                "inertia_ratio": None,
            },
        )


def _orphan_ucx_parts(item: _ColliderBody) -> list[Finding]:
    """MC302: ``UCX_`` parts that name no body or part."""
    from meshcol.analysis.colliders import _UCX

    body = item.body
    if item.grouped:
        orphans = list(body.parts)
    else:
        orphans = [
            name
            for name in body.parts
            if (match := _UCX.match(name))
            and match["body"] != body.name
            and match["body"] not in item.render_parts
        ]
    return [
        finding(
            "MC302",
            body.name,
            name,
            None,
            None,
            f"UCX_ part {name!r} names no body or part "
            f"{_UCX.match(name)['body']!r}: it collides for nothing",  # type: ignore[index]
        )
        for name in orphans
    ]


def _parts_without_ucx(item: _ColliderBody) -> list[Finding]:
    """MC301: in an input with ``UCX_`` colliders, a body (or a part) without any."""
    from meshcol.analysis.colliders import _UCX

    body = item.body
    if not item.run.ucx_owners or item.grouped or body.primitive is not None:
        return []
    owned = item.run.ucx_owners.get(body.name)
    if owned is None:
        message = (
            "the input has UCX_ colliders, this body has none: the engine makes "
            "its own collider, or none"
        )
        return [finding("MC301", body.name, None, 0, 1, message)]
    if owned.whole:
        return []
    covered = {label for label, _ in owned.parts}
    return [
        finding(
            "MC301",
            body.name,
            name,
            0,
            1,
            f"part {name!r} has no UCX_{name}_NN part while its body has UCX_ colliders",
        )
        for label, name in enumerate(body.parts)
        if label not in covered and not _UCX.match(name)
    ]


def _collider_mass(item: _ColliderBody) -> list[Finding]:
    """The collider's mass properties, part by part in the body frame, then in the world
    (``item.collider``); flat convex parts (MC202) and a tiny collider (MC203)."""
    from meshcol.geometry.mass import combine_mass_properties

    run, body = item.run, item.body
    findings: list[Finding] = []
    masses: list[MassProperties] = []
    if item.kind == "mesh":
        masses.append(run.geometries.get(body.vertices, body.faces).mass)
    for part in item.parts if item.kind != "mesh" else ():
        mass, flat = _part_mass(item, part)
        findings.extend(flat)
        if mass is not None:
            masses.append(mass)
    collider = combine_mass_properties(masses).transformed(body.pose) if masses else None
    item.collider = collider
    min_volume = run.options.min_volume
    if collider is not None and 0.0 < collider.volume < min_volume:
        message = f"collider volume {collider.volume:.3g} is below {min_volume:g}"
        findings.append(finding("MC203", body.name, None, collider.volume, min_volume, message))
    return findings


def _part_mass(item: _ColliderBody, part: int) -> tuple[MassProperties | None, list[Finding]]:
    """One convex part's mass properties in its body's frame (None when it has no volume)
    and its MC202 finding, if flat."""
    from meshcol.analysis.geometry_cache import geometry_key
    from meshcol.collision.shapes import ShapeKind
    from meshcol.geometry.mass import primitive_mass_properties

    run, body = item.run, item.body
    colliders, shapes = run.colliders, run.colliders.shapes
    label = int(colliders.part_label[part])
    part_name = body.parts[label] if label >= 0 else None
    findings: list[Finding] = []
    if int(shapes.kinds[part]) == ShapeKind.POLYTOPE:
        what = f"convex part {int(colliders.part_index[part])}" + (
            "" if part_name is None else f" of part {part_name!r}"
        )
        key = run.part_keys.get(part)
        if key is None:
            key = run.part_keys[part] = geometry_key(_part_points(run, part))
        measured_hull = run.hulls.get(key)
        if measured_hull is None:
            measured_hull = run.hulls[key] = _hull_mass(_part_points(run, part))
        dimension, solid = measured_hull
        min_relative = run.options.min_relative_volume
        if solid is None:
            shape_name = ("a point", "a segment", "flat")[dimension]
            message = f"{what} is {shape_name}: no volume"
            return None, [finding("MC202", body.name, part_name, 0.0, min_relative, message)]
        mass, relative = solid
        if relative < min_relative:
            message = (
                f"{what} is nearly flat: volume {mass.volume:.3g}, "
                f"{relative:.3g} of its diagonal cubed"
            )
            findings.append(finding("MC202", body.name, part_name, relative, min_relative, message))
    else:
        primitive = shapes.primitive(part)
        assert primitive is not None  # a part without vertices is a primitive
        mass = primitive_mass_properties(primitive)
    if colliders.part_offsets is not None:
        mass = mass.transformed(colliders.part_offsets[part])
    return mass, findings


def _part_points(run: _Readiness, part: int) -> np.ndarray:
    """A polytope part's points, in its body's frame (or its part offset's)."""
    shapes = run.colliders.shapes
    return shapes.vertices[int(shapes.offsets[part]) : int(shapes.offsets[part + 1])]


def _hull_mass(points: np.ndarray) -> tuple[int, tuple[MassProperties, float] | None]:
    """A convex part's hull dimension (0 when the points have no hull) and, in 3-D, its mass
    properties (the points' frame) and its volume over its diagonal cubed (MC202)."""
    from meshcol.geometry.mass import mass_properties

    dimension, hull = _solid_hull(points)
    if hull is None:
        return dimension, None
    mass = mass_properties(hull.vertices, hull.faces)
    return dimension, (mass, mass.volume / hull.diagonal**3)


def _solid_hull(points: np.ndarray) -> tuple[int, Any]:
    """The points' hull dimension (0 when they have none) and, in 3-D, their exact hull."""
    from meshcol.collision.hull import exact_hull

    try:
        hull = exact_hull(points)
    except InvalidMeshError:
        return 0, None
    return hull.dimension, (hull if hull.dimension == 3 else None)


def _measure_all(run: _Readiness, items: list[_ColliderBody]) -> None:
    """Measure, for all the bodies at once, what their checks read: each unique convex part's
    hull mass (``run.hulls``), each ``mesh`` collider's and each visual mesh's mass
    properties and topology (:func:`~meshcol.analysis.geometry_cache.measure_geometries`).
    The same numbers as measured one body at a time, in a few numpy calls per group of
    meshes of one face count."""
    from meshcol.analysis.geometry_cache import geometry_key, measure_geometries
    from meshcol.collision.shapes import ShapeKind
    from meshcol.geometry.mass import mass_properties_batch

    kinds = run.colliders.shapes.kinds
    solids: dict[bytes, Any] = {}
    meshes = []
    for item in items:
        if item.kind == "mesh":
            meshes.append(run.geometries.get(item.body.vertices, item.body.faces))
            continue
        for part in item.parts:
            if int(kinds[part]) != ShapeKind.POLYTOPE:
                continue
            points = _part_points(run, part)
            key = run.part_keys[part] = geometry_key(points)
            if key in run.hulls or key in solids:
                continue
            dimension, hull = _solid_hull(points)
            if hull is None:
                run.hulls[key] = (dimension, None)
            else:
                solids[key] = hull
    masses = mass_properties_batch([(hull.vertices, hull.faces) for hull in solids.values()])
    for (key, hull), mass in zip(solids.items(), masses):
        run.hulls[key] = (3, (mass, mass.volume / hull.diagonal**3))
    for item in items:
        visual_body = _visual_of(item)[0]
        if visual_body is not None and visual_body.primitive is None:
            meshes.append(run.geometries.get(visual_body.vertices, visual_body.faces))
    measure_geometries(meshes)


def _mass_rows(items: list[_ColliderBody]) -> None:
    """Each body's ``collider_mass`` and ``visual_mass`` in its row, from ``item.collider``
    and ``item.visual``: :func:`_mass_dicts` of all of them at once."""
    rows = _mass_dicts([m for item in items for m in (item.collider, item.visual)])
    pairs = list(zip(rows[0::2], rows[1::2]))
    for item, (collider, visual), ratio in zip(items, pairs, _moment_ratios(pairs)):
        item.row["collider_mass"] = collider
        item.row["visual_mass"] = visual
        item.moment_ratio = ratio


def _mass_dicts(masses: list[MassProperties | None]) -> list[dict[str, Any] | None]:
    """JSON-ready mass properties (non-finite numbers as None; None for None), the principal
    moments of all of them from one stacked ``eigvalsh`` (the same LAPACK call per matrix as
    :meth:`MassProperties.principal_inertia`)."""
    present = [m for m in masses if m is not None]
    if not present:
        return [None] * len(masses)
    vectors = np.zeros((len(present), 4, 3))
    vectors[:, 0] = np.stack([m.center_of_mass for m in present])
    vectors[:, 1] = np.stack([m.shell_center_of_mass for m in present])
    tensors = np.stack(
        [np.stack([m.inertia for m in present]), np.stack([m.shell_inertia for m in present])],
        axis=1,
    ).astype(np.float64, copy=False)
    finite = np.isfinite(tensors).all(axis=(2, 3))
    if finite.any():
        chosen = tensors[finite]
        vectors[:, 2:][finite] = np.linalg.eigvalsh(0.5 * (chosen + chosen.transpose(0, 2, 1)))
    vectors[:, 2:][~finite] = np.nan
    vector_ok: list[Any] = np.asarray(np.isfinite(vectors).all(axis=2)).tolist()
    tensor_ok: list[Any] = np.asarray(finite).tolist()
    vector_lists: list[Any] = vectors.tolist()
    tensor_lists: list[Any] = tensors.tolist()
    out: list[dict[str, Any] | None] = []
    k = 0
    for properties in masses:
        if properties is None:
            out.append(None)
            continue
        v, v_ok, t, t_ok = vector_lists[k], vector_ok[k], tensor_lists[k], tensor_ok[k]
        k += 1
        out.append(
            {
                "volume": properties.volume,
                "center_of_mass": v[0] if v_ok[0] else None,
                "inertia": t[0] if t_ok[0] else None,
                "principal_inertia": v[2] if v_ok[2] else None,
                "area": properties.area,
                "shell_center_of_mass": v[1] if v_ok[1] else None,
                "shell_inertia": t[1] if t_ok[1] else None,
                "shell_principal_inertia": v[3] if v_ok[3] else None,
            }
        )
    return out


# ---------------------------------------------------------------------------------------------
# The collider against the visual mesh (MC301, MC205, MC207, MC206)


@dataclass(frozen=True)
class _Comparison:
    """A collider and its body's visual mesh, world frame."""

    body: str
    collider: MassProperties
    visual: MassProperties
    collider_row: dict[str, Any]  # their _mass_dicts
    visual_row: dict[str, Any]
    solid: bool  # the visual mesh is closed and the collider has a volume: compare solids
    diagonal: float  # of the visual mesh's world bounding box
    moment_ratio: float | None  # of their principal moments per unit mass (_moment_ratios)


def _visual_mass(item: _ColliderBody) -> list[Finding]:
    """The visual mesh's mass properties (``item.visual``), and whether and how the collider
    is compared with it (``item.compare``); MC301 when the visual mesh has no area."""
    run, body = item.run, item.body
    visual_body, item.row["visual_source"] = _visual_of(item)
    collider = item.collider
    if visual_body is None or collider is None:
        return []
    geometry = run.geometries.get(visual_body.vertices, visual_body.faces)
    if visual_body.primitive is not None:
        from meshcol.geometry.mass import primitive_mass_properties

        visual = primitive_mass_properties(visual_body.primitive).transformed(visual_body.pose)
        closed = True
    else:
        measured = geometry.oriented_volume
        closed = measured is not None and measured[1] != 0
        visual = geometry.mass.transformed(visual_body.pose)
    item.visual = visual
    if visual.area == 0.0:
        message = "the body has no area (every face degenerate): nothing to collide with"
        return [finding("MC301", body.name, None, 0.0, 0.0, message)]
    world = visual_body.world_vertices()[geometry.used]
    item.compare = closed, float(np.linalg.norm(world.max(axis=0) - world.min(axis=0)))
    return []


def _comparisons(item: _ColliderBody) -> list[Finding]:
    """Each of :data:`COMPARISONS` of the collider with the visual mesh, into the row (its
    mass rows filled in: :func:`_mass_rows`)."""
    if item.compare is None or item.collider is None or item.visual is None:
        return []
    closed, diagonal = item.compare
    run, body = item.run, item.body
    item.row["comparison"] = "solid" if closed else "shell"
    comparison = _Comparison(
        body=body.name,
        collider=item.collider,
        visual=item.visual,
        collider_row=item.row["collider_mass"],
        visual_row=item.row["visual_mass"],
        solid=closed and item.collider.volume > 0,
        diagonal=diagonal,
        moment_ratio=item.moment_ratio,
    )
    findings = []
    for row_field, measure in COMPARISONS:
        value, found = measure(comparison, run.options)
        item.row[row_field] = value
        findings.extend(found)
    return findings


def _visual_of(item: _ColliderBody) -> tuple[Body | None, str | None]:
    """The body's visual mesh and where it comes from (the row's ``visual_source``)."""
    body, visuals = item.body, item.run.visuals
    if item.grouped or (body.parts and not item.render_parts):
        return None, None  # collision parts only: nothing to compare
    if visuals is not None:
        return visuals.get(body.name, body), "visual" if body.name in visuals else "collision"
    return body, "primitive" if body.primitive is not None else "mesh"


def _volume_ratio(c: _Comparison, options: PhysicsOptions) -> tuple[Any, list[Finding]]:
    """Collider volume over the visual mesh's; MC205 past ``volume_ratio`` either way."""
    if not c.solid:
        return None, []
    ratio = c.collider.volume / abs(c.visual.volume)
    if ratio > options.volume_ratio:
        limit = options.volume_ratio
    elif ratio < 1.0 / options.volume_ratio:
        limit = 1.0 / options.volume_ratio
    else:
        return ratio, []
    message = (
        f"collider volume {c.collider.volume:.4g} is {ratio:.3g} x the visual "
        f"mesh's {abs(c.visual.volume):.4g}"
    )
    return ratio, [finding("MC205", c.body, None, ratio, limit, message)]


def _inertia_ratio(c: _Comparison, options: PhysicsOptions) -> tuple[Any, list[Finding]]:
    """Largest ratio of matching principal moments per unit mass; MC207 past
    ``inertia_ratio``."""
    if not c.solid:
        return None, []
    ratio = c.moment_ratio
    if ratio is None or not ratio > options.inertia_ratio:
        return ratio, []
    message = f"principal moments of inertia per unit mass differ by up to {ratio:.3g} x"
    return ratio, [finding("MC207", c.body, None, ratio, options.inertia_ratio, message)]


def _center_of_mass_offset(c: _Comparison, options: PhysicsOptions) -> tuple[Any, list[Finding]]:
    """Distance between the centres of mass (solid, else shell) over the visual diagonal;
    MC206 past ``com_offset``."""
    if c.solid:
        a, b = c.collider.center_of_mass, c.visual.center_of_mass
    else:
        a, b = c.collider.shell_center_of_mass, c.visual.shell_center_of_mass
    if not (c.diagonal > 0 and np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return None, []
    distance = float(np.linalg.norm(a - b))
    offset = distance / c.diagonal
    if not offset > options.com_offset:
        return offset, []
    message = f"centre of mass {distance:.4g} from the visual mesh's ({offset:.1%} of its diagonal)"
    return offset, [finding("MC206", c.body, None, offset, options.com_offset, message)]


def _moment_ratios(pairs: list[tuple[Any, Any]]) -> list[float | None]:
    """Per pair of :func:`_mass_dicts` rows (collider, visual; None allowed): the largest
    ratio (>= 1) of the sorted principal moments per unit mass of the two solids, None when
    a volume is 0 or a moment not finite or not positive. One numpy pass over all the pairs;
    each pair's number is the one numpy gives it alone (elementwise, then a sort and a max
    of three)."""
    out: list[float | None] = [None] * len(pairs)
    index = [
        i
        for i, (a, b) in enumerate(pairs)
        if a is not None
        and b is not None
        and a["volume"] != 0
        and b["volume"] != 0
        and a["principal_inertia"] is not None  # not finite
        and b["principal_inertia"] is not None
    ]
    if not index:
        return out

    def per_mass(side: int) -> np.ndarray:
        moments = np.array([pairs[i][side]["principal_inertia"] for i in index], dtype=np.float64)
        volumes = np.array([pairs[i][side]["volume"] for i in index], dtype=np.float64)
        return moments / volumes[:, None]

    with np.errstate(all="ignore"):
        per_mass_a, per_mass_b = per_mass(0), per_mass(1)
        ok = np.isfinite(per_mass_a).all(axis=1) & np.isfinite(per_mass_b).all(axis=1)
        per_mass_a, per_mass_b = np.sort(np.abs(per_mass_a)), np.sort(np.abs(per_mass_b))
        ok &= (per_mass_a > 0).all(axis=1) & (per_mass_b > 0).all(axis=1)
        ratios = np.maximum(per_mass_a / per_mass_b, per_mass_b / per_mass_a).max(axis=1)
    for k, i in enumerate(index):
        if ok[k]:
            out[i] = float(ratios[k])
    return out


#: The measures of a collider against its visual mesh, in the order their findings are
#: listed: the row's field, and the function that measures (None: not measurable) and judges.
COMPARISONS: tuple[
    tuple[str, Callable[[_Comparison, PhysicsOptions], tuple[Any, list[Finding]]]], ...
] = (
    ("volume_ratio", _volume_ratio),
    ("inertia_ratio", _inertia_ratio),
    ("center_of_mass_offset", _center_of_mass_offset),
)

#: The checks of each collider body, in the order their findings are listed; each returns
#: its findings and fills its fields of the body's row; then, once the mass rows of every
#: body are filled in (:func:`_mass_rows`), :func:`_comparisons`.
BODY_CHECKS: tuple[Callable[[_ColliderBody], list[Finding]], ...] = (
    _orphan_ucx_parts,
    _parts_without_ucx,
    _collider_mass,
    _visual_mass,
)


def _links_without_collision(visuals: dict[str, Body], colliders: Any) -> list[Finding]:
    """MC301: a robot's links with visual geometry and no collision element."""
    links = {body.name for body in colliders.bodies}
    message = "link has visual geometry but no collision element"
    return [finding("MC301", name, None, 0, 1, message) for name in visuals if name not in links]
