"""Enclosing primitive fits of a scene's bodies: ``meshcol fit`` and the ``fit`` collider.

Each body (each of its parts, for the collider) gets the sphere, box, capsule, cylinder or
ellipsoid of :mod:`meshcol.collision.fit` around its exact convex hull, which contains every
vertex and so the whole mesh. The report gives each fit's parameters and pose, its volume
against the mesh's and the hull's, and the largest gap: how far the primitive's surface
strays from the mesh: the largest distance from a sampled point of the primitive's surface
to the mesh's surface, over a grid of about :data:`GAP_SAMPLES` points that leaves no point
of the surface farther than ``sqrt(area / GAP_SAMPLES)`` from a sample
(:mod:`meshcol.collision.primitive_surface`), so a lower bound within that of the true
largest gap (the distance is 1-Lipschitz).

``auto`` fits four and takes the simplest primitive (in the order of
:data:`meshcol.collision.fit.AUTO_SHAPES`: never the ellipsoid, which not every engine has,
but for a body that is one, below) whose volume is within ``volume_tolerance`` of the hull's;
when none is, the body keeps its convex hull ("hull"), and the report says which primitive
came nearest.

A body that IS a primitive (``Body.primitive``, of positive volume) is fitted from its
parameters in closed form where one exists (:mod:`meshcol.collision.primitive_fit`: exact,
no tessellation, no margin), batched by kind; the other pairs (a capsule around a box, a
cylinder or an ellipsoid; a cylinder around a box or an ellipsoid) by the point-set fits
around a polytope that contains it. Its ``hull_volume`` is the primitive's own volume, its
largest gap measured to the exact primitive by support functions, and ``auto`` keeps it as
it is, an ellipsoid too (the input has one: the collider is exact).

Fits are written as Unreal's collision parts (``UBX_``, ``USP_``, ``UCP_``; a cylinder, an
ellipsoid or a hull, which Unreal has no primitive for, as a ``UCX_`` convex part), as meshes
that contain the primitive (:func:`meshcol.io.primitives.enclosing_primitive_mesh`), so the
file encloses what the fit encloses.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from meshcol.analysis.hull import MeshOutputReport
from meshcol.analysis.rules import robot_warnings
from meshcol.collision.fit import AUTO_SHAPES, FIT_SHAPES, PrimitiveFit, fit_batch
from meshcol.errors import InvalidMeshError
from meshcol.geometry.rotations import quaternion_from_matrix
from meshcol.io.robot import RobotOptions
from meshcol.io.scene import as_scene
from meshcol.types import Body, Box, Capsule, Cylinder, Ellipsoid, Sphere

__all__ = [
    "CSV_COLUMNS",
    "DEFAULT_VOLUME_TOLERANCE",
    "GAP_SAMPLES",
    "SHAPE_CHOICES",
    "UNREAL_PREFIX",
    "BodyFit",
    "FitReport",
    "fit",
    "fit_bodies",
    "fit_body",
    "fit_point_sets",
    "fit_points",
    "fit_row",
]

#: What ``meshcol fit --shape`` takes.
SHAPE_CHOICES = (*FIT_SHAPES, "auto")

#: ``auto`` takes a primitive whose volume is at most (1 + this) times the hull's.
DEFAULT_VOLUME_TOLERANCE = 0.15

#: Points sampled on a primitive's surface to measure its largest gap to the mesh (about:
#: the grid's spacing is sqrt(area / GAP_SAMPLES), 1.6% of sqrt(area), or the diameter over
#: GAP_SAMPLES when that is larger: a needle's).
GAP_SAMPLES = 4096

#: Bodies whose gaps are measured in one native call: their hierarchies (about 20 kB for a
#: prop of 40 triangles) live together, so 10,000 props at once took 200 MB more at peak.
_GAP_CHUNK = 2048

#: Unreal's name prefix of each collider a fit can become.
UNREAL_PREFIX = {
    "box": "UBX",
    "sphere": "USP",
    "capsule": "UCP",
    "cylinder": "UCX",
    "ellipsoid": "UCX",
    "hull": "UCX",
}

#: Columns of :meth:`FitReport.to_csv`, one row per body.
CSV_COLUMNS = (
    "name",
    "source",
    "shape",
    "simpler_primitive",
    "radius",
    "length",
    "size_x",
    "size_y",
    "size_z",
    "center_x",
    "center_y",
    "center_z",
    "qw",
    "qx",
    "qy",
    "qz",
    "volume",
    "hull_volume",
    "mesh_volume",
    "volume_ratio",
    "hull_ratio",
    "max_gap",
    "output",
    "units",
)


@dataclass(frozen=True)
class BodyFit:
    """The fits of one point set (a body or a part), in the frame of its points.

    Attributes
    ----------
    fits : dict of str to PrimitiveFit
        The primitives fitted (one, or the four of ``AUTO_SHAPES`` for ``auto``).
    chosen : str
        The shape taken: a key of ``fits``, or ``"hull"`` when ``auto`` found no primitive
        within the volume tolerance.
    hull_vertices, hull_faces : ndarray
        The exact convex hull the fits enclose.
    hull_volume : float
    """

    fits: dict[str, PrimitiveFit]
    chosen: str
    hull_vertices: np.ndarray
    hull_faces: np.ndarray
    hull_volume: float

    @property
    def primitive_fit(self) -> PrimitiveFit | None:
        """The chosen fit, None when the hull was kept."""
        return self.fits.get(self.chosen)


def fit_points(
    points: np.ndarray,
    shape: str = "auto",
    *,
    volume_tolerance: float = DEFAULT_VOLUME_TOLERANCE,
) -> BodyFit:
    """Fit ``shape`` (or every shape, for ``auto``) around points (n, 3), any frame.

    Raises
    ------
    InvalidMeshError
        The points have no hull (none, non-finite, or beyond the hull's coordinate range).
    ValueError
        An unknown shape or a negative tolerance.
    """
    result = fit_point_sets([points], shape, volume_tolerance=volume_tolerance)[0]
    if isinstance(result, InvalidMeshError):
        raise result
    return result


def fit_point_sets(
    point_sets: Sequence[np.ndarray],
    shape: str = "auto",
    *,
    volume_tolerance: float = DEFAULT_VOLUME_TOLERANCE,
    threads: int = 0,
) -> list[BodyFit | InvalidMeshError]:
    """:func:`fit_points` of many point sets in ONE native call (:func:`fit_batch`).

    Returns
    -------
    list of BodyFit or InvalidMeshError
        Per set, in order: its fits, or the error that set has no volume to enclose (no
        points, non-finite, collinear, one point): the caller names the body and raises.

    Raises
    ------
    ValueError
        An unknown shape, a negative tolerance, or a set that is not (n, 3).
    """
    if shape not in SHAPE_CHOICES:
        raise ValueError(f"shape must be one of {', '.join(SHAPE_CHOICES)}, got {shape!r}")
    if not volume_tolerance >= 0:
        raise ValueError(f"volume_tolerance must be >= 0, got {volume_tolerance}")
    sets = [np.ascontiguousarray(p, dtype=np.float64) for p in point_sets]
    batch = fit_batch(sets, AUTO_SHAPES if shape == "auto" else shape, threads=threads)
    out: list[BodyFit | InvalidMeshError] = []
    for h, points in enumerate(sets):
        dimension = int(batch.dimension[h])
        if dimension == 0:
            out.append(InvalidMeshError("all vertices coincide: there is no volume to enclose"))
            continue
        if dimension == 1:
            out.append(
                InvalidMeshError("all vertices are collinear: there is no volume to enclose")
            )
            continue
        if not batch.fitted(h):
            out.append(batch.error(h))
            continue
        vertex_index, faces = batch.hull(h)
        hull_vertices = points[vertex_index] + 0.0
        hull_volume = float(batch.hull_volume[h])
        fits = batch.fits(h)
        if shape == "auto":
            limit = (1.0 + volume_tolerance) * hull_volume
            chosen = next((n for n in AUTO_SHAPES if fits[n].volume <= limit), "hull")
            if dimension == 2:
                chosen = "box"  # a flat body: its box (as thin as the margin) is its collider
        else:
            chosen = shape
        out.append(BodyFit(fits, chosen, hull_vertices, faces.copy(), hull_volume))
    return out


def fit_body(
    body: Body, shape: str = "auto", volume_tolerance: float = DEFAULT_VOLUME_TOLERANCE
) -> tuple[BodyFit, float | None, float | None]:
    """Fit one body (:func:`fit_points` on its vertices), in the WORLD frame (its pose applied).

    Returns
    -------
    (BodyFit, float or None, float or None)
        The fits; the body's own volume (closed meshes and primitives; None otherwise); the
        largest gap from the chosen primitive's surface to the body (None when the hull was
        kept).

    Raises
    ------
    InvalidMeshError
        As :func:`fit_points` (the message does not name the body).
    """
    result = fit_bodies([body], shape, volume_tolerance)[0]
    if isinstance(result, InvalidMeshError):
        raise result
    return result


def fit_bodies(
    bodies: Sequence[Body],
    shape: str = "auto",
    volume_tolerance: float = DEFAULT_VOLUME_TOLERANCE,
    threads: int = 0,
) -> list[tuple[BodyFit, float | None, float | None] | InvalidMeshError]:
    """:func:`fit_body` of many bodies, the fits in ONE native call; per body its result
    or the error that it has no volume to enclose (the message does not name the body).

    A body that is a primitive of positive volume is fitted in closed form where one exists
    (:mod:`meshcol.collision.primitive_fit`, batched by kind, exact, no margin), its
    ``hull_volume`` the primitive's own volume; ``auto`` keeps it as it is (an ellipsoid
    too: volume ratio 1); its largest gap is to the exact primitive. The pairs without a
    closed form go to the point-set fits with the mesh bodies, around a polytope that
    contains the primitive (:func:`_fit_vertices`)."""
    from meshcol.collision.primitive_fit import (
        closed_form_fits,
        primitive_parameters,
        solid_primitives,
    )

    if shape not in SHAPE_CHOICES:
        raise ValueError(f"shape must be one of {', '.join(SHAPE_CHOICES)}, got {shape!r}")
    kind, params = primitive_parameters([b.primitive for b in bodies])
    solid = solid_primitives(kind, params)
    names = (*AUTO_SHAPES, "ellipsoid") if shape == "auto" else (shape,)
    closed = {name: closed_form_fits(kind, params, name) for name in names}
    needed = AUTO_SHAPES if shape == "auto" else (shape,)  # an ellipsoid's own is exact
    batch_index = np.flatnonzero(~np.logical_and.reduce([closed[n].exact for n in needed]))
    batched = fit_point_sets(
        [_fit_vertices(bodies[i]) for i in batch_index.tolist()],
        shape,
        volume_tolerance=volume_tolerance,
        threads=threads,
    )
    local: list[BodyFit | InvalidMeshError | None] = [None] * len(bodies)
    for i, batched_fit in zip(batch_index.tolist(), batched):
        local[i] = batched_fit
    for i in np.flatnonzero(solid).tolist():
        local[i] = _primitive_body_fit(bodies[i], i, closed, local[i], shape)
    gaps = _primitive_gaps(bodies, local, kind, params, solid)
    gaps.update(_mesh_gaps(bodies, local, gaps, threads))
    out: list[tuple[BodyFit, float | None, float | None] | InvalidMeshError] = []
    for i, (body, fitted) in enumerate(zip(bodies, local)):
        assert fitted is not None  # every body is batched or solid
        out.append(
            fitted
            if isinstance(fitted, InvalidMeshError)
            else _world_fit(body, fitted, gaps.get(i))
        )
    return out


def _primitive_body_fit(
    body: Body, i: int, closed: dict[str, Any], batched: Any, shape: str
) -> BodyFit:
    """The fits of primitive body ``i``: closed forms where they exist, else the point-set
    fit of ``batched``; auto keeps the primitive itself."""
    from meshcol.collision.fit import PrimitiveFit, primitive_from_params, primitive_volume

    assert body.primitive is not None
    own = type(body.primitive).__name__.lower()
    wanted: tuple[str, ...] = (shape,)
    if shape == "auto":  # the four candidates, and an ellipsoid's own kind
        wanted = (*AUTO_SHAPES, "ellipsoid") if own == "ellipsoid" else AUTO_SHAPES
    fits = {}
    for name in wanted:
        form = closed[name]
        if form.exact[i]:
            pose = np.eye(4)
            pose[:3, :3] = form.rotation[i]
            primitive = primitive_from_params(name, form.params[i])
            fits[name] = PrimitiveFit(primitive, pose, float(form.volume[i]), 0.0)
        else:
            fits[name] = batched.fits[name]
    chosen = own if shape == "auto" else shape
    if batched is None:
        hull_vertices, hull_faces = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    else:
        hull_vertices, hull_faces = batched.hull_vertices, batched.hull_faces
    return BodyFit(fits, chosen, hull_vertices, hull_faces, primitive_volume(body.primitive))


def _primitive_gaps(
    bodies: Sequence[Body],
    local: Sequence[Any],
    kind: np.ndarray,
    params: np.ndarray,
    solid: np.ndarray,
) -> dict[int, float]:
    """The largest gap of each solid primitive body's chosen fit, all in one batch of
    support functions (:func:`meshcol.collision.primitive_fit.largest_gaps`)."""
    from meshcol.collision.primitive_fit import largest_gaps, primitive_parameters

    index = [i for i in np.flatnonzero(solid).tolist() if local[i].primitive_fit is not None]
    if not index:
        return {}
    chosen = [local[i].primitive_fit for i in index]
    fit_kind, fit_params = primitive_parameters([f.primitive for f in chosen])
    poses = np.stack([f.pose for f in chosen])
    gaps = largest_gaps(kind[index], params[index], fit_kind, fit_params, poses)
    return dict(zip(index, gaps.tolist()))


def _world_fit(
    body: Body, local: BodyFit, gap: float | None
) -> tuple[BodyFit, float | None, float | None]:
    """One body's fits posed in the world, its own volume and its largest gap ``gap``."""
    from meshcol.collision.fit import primitive_volume
    from meshcol.geometry.topology import oriented_volume

    pose = np.asarray(body.pose, dtype=np.float64)
    world = BodyFit(
        {name: _world(f, pose) for name, f in local.fits.items()},
        local.chosen,
        local.hull_vertices @ pose[:3, :3].T + pose[:3, 3],
        local.hull_faces,
        local.hull_volume,
    )
    if body.primitive is None:
        oriented = oriented_volume(body.vertices, body.faces)
        volume = None if oriented is None else abs(oriented[0])
    else:
        volume = primitive_volume(body.primitive)
    return world, volume, gap


def _fit_vertices(body: Body) -> np.ndarray:
    """The points a body's fit must enclose, local frame: its vertices, or for a primitive
    body a tessellation that contains the primitive."""
    if body.primitive is not None:
        from meshcol.io.primitives import enclosing_primitive_mesh

        return enclosing_primitive_mesh(body.primitive)[0]
    return np.asarray(body.vertices, dtype=np.float64)


def _parameters(fit_: PrimitiveFit) -> dict[str, Any]:
    p = fit_.primitive
    return {
        "radius": p.radius if isinstance(p, (Sphere, Capsule, Cylinder)) else None,
        "length": p.length if isinstance(p, (Capsule, Cylinder)) else None,
        "size": _size(p),
        "center": [float(v) for v in fit_.pose[:3, 3]],
        "quaternion": quaternion_from_matrix(fit_.pose[:3, :3]),
    }


def _size(primitive: Any) -> list[float] | None:
    """The row's ``size``: a box's sides, an ellipsoid's full extents (twice its semi-axes)
    along its local axes; None for the round primitives."""
    if isinstance(primitive, Box):
        return list(primitive.size)
    if isinstance(primitive, Ellipsoid):
        return [2.0 * a for a in primitive.semi_axes]
    return None


def _mesh_gaps(
    bodies: Sequence[Body], local: Sequence[Any], known: dict[int, float], threads: int
) -> dict[int, float]:
    """The largest gap of each body's chosen fit not in ``known`` (a mesh body's): the largest
    distance from a node of a grid on the primitive's surface (:func:`surface_patches`, about
    :data:`GAP_SAMPLES` nodes, every surface point within ``sqrt(area / GAP_SAMPLES)`` of
    one) to the body's surface (its hull's, for a body without faces), in the fit's frame;
    every body's in one native call a chunk (:meth:`MeshSet.largest_distances_to_patches`)."""
    from meshcol.collision.mesh_query import MeshSet
    from meshcol.collision.primitive_fit import primitive_parameters
    from meshcol.collision.primitive_surface import surface_patches

    index = [
        i
        for i, fitted in enumerate(local)
        if i not in known
        and not isinstance(fitted, InvalidMeshError)
        and fitted.primitive_fit is not None
    ]
    if not index:
        return {}
    chosen = [local[i].primitive_fit for i in index]
    kind, params = primitive_parameters([f.primitive for f in chosen])
    meshes = []
    for i, f in zip(index, chosen):
        body, rotation, origin = bodies[i], f.pose[:3, :3], f.pose[:3, 3]
        if body.primitive is None and len(body.faces):
            vertices, faces = body.vertices, body.faces
        else:
            vertices, faces = local[i].hull_vertices, local[i].hull_faces
        meshes.append(((np.asarray(vertices, dtype=np.float64) - origin) @ rotation, faces))
    gaps = np.empty(len(index))
    for start in range(0, len(index), _GAP_CHUNK):  # one native call a chunk of bodies
        part = slice(start, start + _GAP_CHUNK)
        mesh_set = MeshSet.from_arrays(meshes[part], threads=threads, orient=False)
        patches = surface_patches(kind[part], params[part], GAP_SAMPLES)
        gaps[part] = mesh_set.largest_distances_to_patches(patches, threads=threads)[0]
    # NaN: no distance (an invalid mesh), 0 as before
    return dict(zip(index, np.where(np.isnan(gaps), 0.0, gaps).tolist()))


def _world(fit_: PrimitiveFit, pose: np.ndarray) -> PrimitiveFit:
    return PrimitiveFit(fit_.primitive, pose @ fit_.pose, fit_.volume, fit_.excess)


@dataclass(frozen=True)
class FitReport(MeshOutputReport):
    """What :func:`fit` computed and wrote.

    Attributes
    ----------
    bodies : list of dict
        Per body: the chosen shape and its parameters (world frame), volumes and ratios, the
        largest gap, every candidate (for ``auto``), the file it went to.
    fits : tuple of BodyFit
        The fits, world frame, in the order of ``bodies``.
    shape : str
    volume_tolerance : float
    output, out_dir : str or None
    units : str or None
    warnings : tuple of str
    frame : {"world", "link"}
        ``link`` for a robot description rebuilt with ``out_dir`` (each fit in its link's
        frame, one row per collision element).
    description, to : str or None
        The robot description written with the fits, and its format.
    """

    bodies: list[dict[str, Any]]
    fits: tuple[BodyFit, ...]
    shape: str
    volume_tolerance: float
    output: str | None
    out_dir: str | None
    units: str | None
    warnings: tuple[str, ...] = ()
    frame: str = "world"
    description: str | None = None
    to: str | None = None

    command: ClassVar[str] = "fit"

    @property
    def exit_code(self) -> int:
        """Always 0: fit has no policy (unusable input raises instead)."""
        return 0

    @property
    def summary(self) -> dict[str, Any]:
        shapes = [row["shape"] for row in self.bodies]
        # the ellipsoid is counted when asked for or kept (auto takes one only when the
        # body is one)
        ellipsoid = self.shape == "ellipsoid" or "ellipsoid" in shapes
        names = (*AUTO_SHAPES, "hull") + (("ellipsoid",) if ellipsoid else ())
        return {
            "bodies": len(self.bodies),
            "shapes": {name: shapes.count(name) for name in names},
            "simpler_primitive": sum(1 for row in self.bodies if row["simpler_primitive"]),
            "files_written": self.files_written,
        }

    @property
    def settings(self) -> dict[str, Any]:
        return {
            "shape": self.shape,
            "volume_tolerance": self.volume_tolerance,
            "gap_samples": GAP_SAMPLES,
            **self.destination_settings(),
        }

    def ci_suite(self) -> Any:
        """The run as a CI suite (:class:`meshcol.io.ci.CiSuite`): one passed case per body
        (``FILE::BODY``) with the primitive, its size, volume ratios and largest gap (a fit
        always contains the mesh; unusable input stops the run before any report); a
        warning (``volume-tolerance``) when the primitive's volume is over the hull's by more
        than the volume tolerance (a shape chosen with ``--shape`` that fits loosely)."""
        from meshcol.io.ci import CiCase, CiSuite, number

        units = self.units
        cases = []
        for row in self.bodies:
            shape = row["shape"]
            parts = [shape]
            if row["radius"] is not None:
                parts.append(f"radius {number(row['radius'], units)}")
            if row["length"] is not None:
                parts.append(f"length {number(row['length'], units)}")
            if row["size"] is not None and row["radius"] is None:
                parts.append("size " + " x ".join(number(v) for v in row["size"]))
            parts.append(f"volume {number(row['volume'])}")
            if row["volume_ratio"] is not None:
                parts.append(f"volume/mesh {number(row['volume_ratio'])}")
            if row["hull_ratio"] is not None:
                parts.append(f"volume/hull {number(row['hull_ratio'])}")
            if row["max_gap"] is not None:
                parts.append(f"max gap {number(row['max_gap'], units)}")
            message = ", ".join(parts)
            if row["simpler_primitive"]:
                message += " (could use a simpler primitive than the hull)"
            loose = row["hull_ratio"] is not None and row["hull_ratio"] > 1 + self.volume_tolerance
            if loose:
                message += f"; over the hull's volume by more than {number(self.volume_tolerance)}"
            cases.append(
                CiCase(
                    name=self.case_name(row),
                    classname="meshcol.fit",
                    message=message,
                    file=row["source"],
                    kind="volume-tolerance" if loose else None,
                    warn=loose,
                )
            )
        s = self.summary
        shapes = ", ".join(f"{count} {name}" for name, count in s["shapes"].items() if count)
        return CiSuite(
            "fit",
            tuple(cases),
            self.settings,
            warnings=self.warnings,
            verdict=f"{s['bodies']} bodies ({shapes or 'none'})",
            units=units,
        )

    def to_csv(self) -> str:
        """One row per body (:data:`CSV_COLUMNS`)."""
        from meshcol.io.report import dumps_csv

        rows = []
        for row in self.bodies:
            size = row["size"] or [None, None, None]
            center = row["center"] or [None, None, None]
            quaternion = row["quaternion"] or [None, None, None, None]
            rows.append(
                {
                    **row,
                    "size_x": size[0],
                    "size_y": size[1],
                    "size_z": size[2],
                    "center_x": center[0],
                    "center_y": center[1],
                    "center_z": center[2],
                    "qw": quaternion[0],
                    "qx": quaternion[1],
                    "qy": quaternion[2],
                    "qz": quaternion[3],
                    "units": self.units,
                }
            )
        return dumps_csv(rows, CSV_COLUMNS)


def _ratio(volume: float, reference: float | None) -> float | None:
    return None if reference is None or reference <= 0 else volume / reference


def fit_row(
    body: Body,
    result: BodyFit,
    mesh_volume: float | None,
    gap: float | None,
    destination: str | None,
    shape: str,
) -> dict[str, Any]:
    """The report row of one body's fit (``result`` in the frame the row is given in)."""
    chosen = result.primitive_fit
    candidates = None
    if shape == "auto":
        candidates = {
            name: {
                "volume": f.volume,
                "hull_ratio": _ratio(f.volume, result.hull_volume),
            }
            for name, f in result.fits.items()
            if name in AUTO_SHAPES  # an ellipsoid body's own ellipsoid is no candidate
        }
    if chosen is None:
        parameters: dict[str, Any] = {
            "radius": None,
            "length": None,
            "size": None,
            "center": None,
            "quaternion": None,
        }
        volume = result.hull_volume
    else:
        parameters = _parameters(chosen)
        volume = chosen.volume
    return {
        "name": body.name,
        "source": body.source,
        "shape": result.chosen,
        "simpler_primitive": shape == "auto" and chosen is not None and body.primitive is None,
        **parameters,
        "volume": volume,
        "hull_volume": result.hull_volume,
        "mesh_volume": mesh_volume,
        "volume_ratio": _ratio(volume, mesh_volume),
        "hull_ratio": _ratio(volume, result.hull_volume),
        "max_gap": gap,
        "candidates": candidates,
        "output": destination,
    }


def _fit_mesh(name: str, result: Any) -> tuple[str, np.ndarray, np.ndarray]:
    """The mesh written for one body's fit, named by Unreal's convention (``UBX_<body>_00``
    and alike): the chosen primitive tessellated and placed, or the hull it kept."""
    from meshcol.io.primitives import enclosing_primitive_mesh

    part_name = f"{UNREAL_PREFIX[result.chosen]}_{name}_00"
    chosen = result.primitive_fit
    if chosen is None:
        return part_name, result.hull_vertices, result.hull_faces
    vertices, faces = enclosing_primitive_mesh(chosen.primitive)
    return part_name, vertices @ chosen.pose[:3, :3].T + chosen.pose[:3, 3], faces


def _fit_meshes(bodies: Sequence[Body], results: Sequence[BodyFit], written: bool) -> list[Any]:
    """:func:`_fit_mesh` of each body, made only when ``written`` (a manifest may hold a
    million primitives)."""
    if not written:
        return []
    return [_fit_mesh(body.name, result) for body, result in zip(bodies, results)]


def fit(
    inputs: Any,
    *,
    shape: str = "auto",
    volume_tolerance: float = DEFAULT_VOLUME_TOLERANCE,
    output: str | os.PathLike[str] | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    reserved: Sequence[tuple[str, str | os.PathLike[str] | None]] = (),
    progress: Callable[[str], None] | None = None,
    robot_options: RobotOptions | None = None,
) -> FitReport:
    """An enclosing primitive around each body, in the world frame.

    Parameters
    ----------
    inputs : Scene, sequence of Body, or path(s) of meshes / one scene manifest
    shape : {"sphere", "capsule", "box", "cylinder", "ellipsoid", "auto"}
        The primitive; ``auto`` fits the four of ``AUTO_SHAPES`` and takes the simplest
        within ``volume_tolerance`` of the hull's volume (else the hull).
    volume_tolerance : float
        For ``auto``: a primitive is taken when its volume is at most (1 + this) times the
        hull's.
    output : path, optional
        Write every fit to this file (``.obj``, ``.glb``: one named object per body, Unreal's
        ``UBX_<body>_00`` and alike; one body: any mesh format).
    out_dir : path, optional
        Write ``out_dir/<body>.obj`` per body.
    reserved : sequence of (label, path)
        Other files the caller will write: no fit may go there.
    progress : callable, optional
        One line when the fits start (every body's in one native call).
    robot_options : RobotOptions, optional
        How a robot description is read (:func:`meshcol.io.scene.load_inputs`).

    Returns
    -------
    FitReport

    Raises
    ------
    InvalidMeshError
        A body has no hull (collinear or single-point input, non-finite coordinates).
    OutputDestinationError
        Several bodies for a single-mesh output format.
    OutputPathError
        A file would replace an input or a ``reserved`` file (nothing is written).
    """
    from meshcol.analysis.hull import check_body_count, mesh_destinations, write_body_meshes

    if shape not in SHAPE_CHOICES:
        raise ValueError(f"shape must be one of {', '.join(SHAPE_CHOICES)}, got {shape!r}")
    output, out_dir = mesh_destinations(output, out_dir)
    scene = as_scene(inputs, robot_options)
    bodies = scene.bodies
    check_body_count(output, len(bodies))

    # Everything is computed before anything is written: a bad body stops the run first.
    # The fits of every body in one native call; then the first body without a fit stops it.
    if progress is not None:
        progress(f"fit: {len(bodies)} bodies")
    results, rows_input = [], []
    for body, fitted in zip(bodies, fit_bodies(bodies, shape, volume_tolerance)):
        if isinstance(fitted, InvalidMeshError):
            raise InvalidMeshError(f"body '{body.name}': {fitted.message}", body.source)
        world, volume, gap = fitted
        results.append(world)
        rows_input.append((body, world, volume, gap))

    parts = _fit_meshes(bodies, results, output is not None or out_dir is not None)
    destinations = write_body_meshes(bodies, parts, output, out_dir, reserved)

    rows = [
        fit_row(body, result, volume, gap, destination, shape)
        for (body, result, volume, gap), destination in zip(rows_input, destinations)
    ]
    warnings = robot_warnings(scene)  # a robot with no collision geometry: nothing to fit
    return FitReport(
        rows, tuple(results), shape, float(volume_tolerance), output, out_dir, scene.units, warnings
    )
