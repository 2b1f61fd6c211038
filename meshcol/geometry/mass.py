"""Mass properties of triangle meshes: volume, centre of mass and inertia, solid and shell.

Density 1 throughout: the solid mass is the volume and the shell mass is the area, so a caller
multiplies by its density (kg/m^3 or kg/m^2). Inertia tensors are about the centre of mass,
in the frame of the vertices.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Primitive, Sphere

__all__ = [
    "MASS_BATCH_TRIANGLES",
    "MassProperties",
    "combine_mass_properties",
    "mass_properties",
    "mass_properties_batch",
    "primitive_mass_properties",
]


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Solid and shell mass properties of one mesh (density 1).

    Attributes
    ----------
    volume : float
        Signed volume: positive when the faces point outward, negative when the mesh is
        inside out. Meaningful for a closed, consistently wound mesh only.
    center_of_mass : (3,) float64
        Of the solid (NaN when the volume is 0).
    inertia : (3, 3) float64
        Of the solid about ``center_of_mass``, mass = ``volume`` (a negative volume gives a
        negative tensor: the sign of an inside-out mesh, as the volume's).
    area : float
        Surface area.
    shell_center_of_mass : (3,) float64
        Area-weighted centroid of the surface (NaN when the area is 0).
    shell_inertia : (3, 3) float64
        Of the surface as a thin shell of mass = ``area``, about ``shell_center_of_mass``.
    """

    volume: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    area: float
    shell_center_of_mass: np.ndarray
    shell_inertia: np.ndarray

    def principal_inertia(self, shell: bool = False) -> np.ndarray:
        """The principal moments (3,) of the solid (or shell) inertia, ascending."""
        tensor = self.shell_inertia if shell else self.inertia
        if not np.all(np.isfinite(tensor)):
            return np.full(3, np.nan)
        return np.linalg.eigvalsh(0.5 * (tensor + tensor.T))

    def transformed(self, pose: np.ndarray) -> MassProperties:
        """The same properties with the mesh moved by a rigid ``pose`` (4, 4)."""
        pose = np.asarray(pose, dtype=np.float64)
        r, t = pose[:3, :3], pose[:3, 3]
        return MassProperties(
            self.volume,
            r @ self.center_of_mass + t,
            r @ self.inertia @ r.T,
            self.area,
            r @ self.shell_center_of_mass + t,
            r @ self.shell_inertia @ r.T,
        )


def _tensor(second_moment: np.ndarray, mass: float, center: np.ndarray) -> np.ndarray:
    """Inertia about ``center`` from the second moment ``sum m x x^T`` about the origin."""
    covariance = second_moment - mass * np.outer(center, center)
    return np.trace(covariance) * np.eye(3) - covariance


def mass_properties(vertices: np.ndarray, faces: np.ndarray) -> MassProperties:
    """Volume, centre of mass and inertia of a triangle mesh, as a solid and as a shell.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        Triangles; the solid values are exact for a closed, consistently wound mesh (they
        are then independent of where the mesh sits), the shell values for any mesh.

    Returns
    -------
    MassProperties

    Notes
    -----
    Solid: the mesh is a sum of signed tetrahedra ``(o, a, b, c)`` from the centre ``o`` of
    its bounding box (divergence theorem); each contributes its volume
    ``det[a - o, b - o, c - o] / 6``, its centroid and its second moment
    ``V / 20 (sum_i v_i v_i^T + s s^T)`` with ``s = sum_i v_i`` over its four vertices
    (Tonon 2004, "Explicit exact formulas for the 3-D tetrahedron inertia tensor"). Shell:
    each triangle's area, centroid and second moment ``A / 12 (sum_i v_i v_i^T + s s^T)``
    over its three vertices. Inertia follows from the second moment about the centre of
    mass, ``I = tr(C) 1 - C``. Vectorised over faces; the apex near the mesh keeps the
    rounding error near machine precision of the mesh's size wherever it sits.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if len(faces) == 0:
        nan = np.full(3, np.nan)
        return MassProperties(0.0, nan, np.full((3, 3), np.nan), 0.0, nan, np.full((3, 3), np.nan))
    used = vertices[np.unique(faces)]
    origin = 0.5 * (used.min(axis=0) + used.max(axis=0))
    tri = vertices[faces] - origin  # (m, 3, 3): corner k of face i
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    s = a + b + c
    corners = np.einsum("mki,mkj->mij", tri, tri)  # sum over the corners of v v^T
    sums = np.einsum("mi,mj->mij", s, s)

    # solid: tetrahedra (0, a, b, c); the apex adds nothing to either sum
    six_volumes = np.einsum("mi,mi->m", a, np.cross(b, c))
    volume = float(six_volumes.sum() / 6.0)
    second = np.einsum("m,mij->ij", six_volumes, corners + sums) / 120.0
    if volume != 0.0:
        center = (six_volumes @ s) / (24.0 * volume)
        inertia = _tensor(second, volume, center)
    else:
        center = np.full(3, np.nan)
        inertia = np.full((3, 3), np.nan)

    # shell: triangles
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    area = float(areas.sum())
    if area > 0.0:
        shell_center = (areas @ s) / (3.0 * area)
        shell_second = np.einsum("m,mij->ij", areas, corners + sums) / 12.0
        shell_inertia = _tensor(shell_second, area, shell_center)
    else:
        shell_center = np.full(3, np.nan)
        shell_inertia = np.full((3, 3), np.nan)
    return MassProperties(
        volume, center + origin, inertia, area, shell_center + origin, shell_inertia
    )


def mass_properties_batch(
    meshes: Sequence[tuple[np.ndarray, np.ndarray]],
) -> list[MassProperties]:
    """:func:`mass_properties` of many meshes, bit for bit, at the cost of a few numpy calls
    per group of meshes with as many faces instead of some forty per mesh.

    Parameters
    ----------
    meshes : sequence of ((n_i, 3) float, (m_i, 3) int)
        Each mesh's vertices and faces.

    Returns
    -------
    list of MassProperties
        One per mesh, in order: equal to :func:`mass_properties` of it to the last bit.

    Notes
    -----
    The meshes with ``m`` faces are stacked into one ``(k, m, 3, 3)`` array of triangles and
    :func:`mass_properties`' formulas run with that leading axis. Every per-face step is the
    same operation on the same numbers, and every reduction over a mesh's faces runs along
    the last axis (numpy's pairwise sum per row, one BLAS product per stacked matrix), in the
    order the single-mesh code uses: ``tests/geometry/test_mesh_batches.py`` compares the bits.
    A mesh alone of its face count (a big one) takes :func:`mass_properties` itself; at most
    :data:`MASS_BATCH_TRIANGLES` triangles are stacked at once (bounded memory).
    """
    if not meshes:
        return []
    out: list[MassProperties | None] = [None] * len(meshes)
    counts = np.fromiter((len(faces) for _, faces in meshes), dtype=np.int64, count=len(meshes))
    for chunk in _stacks(counts):
        if len(chunk) == 1 or counts[chunk[0]] == 0:
            for index in chunk.tolist():
                out[index] = mass_properties(*meshes[index])
            continue
        triangles = np.stack(
            [
                np.asarray(meshes[index][0], dtype=np.float64)[
                    np.asarray(meshes[index][1], dtype=np.int64)
                ]
                for index in chunk.tolist()
            ]
        )
        for index, properties in zip(chunk.tolist(), _stacked_mass_properties(triangles)):
            out[index] = properties
    return out  # type: ignore[return-value]


#: At most this many triangles are stacked at once by :func:`mass_properties_batch` (the
#: meshes of one face count beyond it go in several stacks): each of its temporaries is then
#: at most some 20 MB, whatever the library's size.
MASS_BATCH_TRIANGLES = 1 << 18


def _stacks(counts: np.ndarray) -> list[np.ndarray]:
    """Mesh indices in stacks of one face count each, of at most
    :data:`MASS_BATCH_TRIANGLES` triangles (or one mesh)."""
    order = np.argsort(counts, kind="stable")
    starts = np.flatnonzero(np.diff(counts[order], prepend=-1))
    stacks: list[np.ndarray] = []
    for group in np.split(order, starts[1:]):
        step = max(1, MASS_BATCH_TRIANGLES // max(int(counts[group[0]]), 1))
        stacks.extend(group[start : start + step] for start in range(0, len(group), step))
    return stacks


def _stacked_tensor(second: np.ndarray, mass: np.ndarray, center: np.ndarray) -> np.ndarray:
    """:func:`_tensor` of each of a stack: (k, 3, 3), (k,), (k, 3)."""
    covariance = second - mass[:, None, None] * (center[:, :, None] * center[:, None, :])
    return np.trace(covariance, axis1=1, axis2=2)[:, None, None] * np.eye(3) - covariance


def _stacked_mass_properties(triangles: np.ndarray) -> list[MassProperties]:
    """:func:`mass_properties` of each mesh of a stack of triangles (k, m, 3, 3), m > 0."""
    k = len(triangles)
    corners_all = triangles.reshape(k, -1, 3)
    origin = 0.5 * (corners_all.min(axis=1) + corners_all.max(axis=1))
    tri = triangles - origin[:, None, None, :]
    a, b, c = tri[:, :, 0], tri[:, :, 1], tri[:, :, 2]
    s = a + b + c
    corners = np.einsum("nmki,nmkj->nmij", tri, tri)
    sums = np.einsum("nmi,nmj->nmij", s, s)
    moments = corners + sums

    six_volumes = np.einsum("nmi,nmi->nm", a, np.cross(b, c))
    volume = six_volumes.sum(axis=1) / 6.0
    second = np.einsum("nm,nmij->nij", six_volumes, moments) / 120.0
    solid = volume != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        center = (six_volumes[:, None, :] @ s)[:, 0] / (24.0 * volume)[:, None]
        inertia = _stacked_tensor(second, volume, center)
    center[~solid] = np.nan
    inertia[~solid] = np.nan

    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=-1)
    area = areas.sum(axis=1)
    shell = area > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        shell_center = (areas[:, None, :] @ s)[:, 0] / (3.0 * area)[:, None]
        shell_second = np.einsum("nm,nmij->nij", areas, moments) / 12.0
        shell_inertia = _stacked_tensor(shell_second, area, shell_center)
    shell_center[~shell] = np.nan
    shell_inertia[~shell] = np.nan
    center += origin
    shell_center += origin
    return [
        MassProperties(
            float(volume[i]),
            center[i],
            inertia[i],
            float(area[i]),
            shell_center[i],
            shell_inertia[i],
        )
        for i in range(k)
    ]


def combine_mass_properties(parts: Sequence[MassProperties]) -> MassProperties:
    """The mass properties of several parts taken together (density 1).

    Parameters
    ----------
    parts : sequence of MassProperties
        In one frame. Overlapping parts count twice where they overlap, as physics engines
        sum the masses of a body's shapes.

    Returns
    -------
    MassProperties
        Volumes and areas add; centres of mass are the weighted means; inertia tensors are
        moved to the common centre by the parallel-axis theorem (Steiner) and added. Parts
        without a volume (or an area) add nothing to the solid (or shell) values.
    """
    if len(parts) == 1:
        return parts[0]

    def merge(weights, centers, tensors):
        weights = np.asarray(weights, dtype=np.float64)
        keep = (weights != 0) & np.all(np.isfinite(centers), axis=1)
        total = float(weights[keep].sum())
        if not keep.any() or total == 0.0:
            return total, np.full(3, np.nan), np.full((3, 3), np.nan)
        w, c, t = weights[keep], centers[keep], tensors[keep]
        center = (w @ c) / total
        d = c - center
        shift = np.einsum("k,ki,kj->ij", w, d, d)
        steiner = np.trace(shift) * np.eye(3) - shift
        return total, center, t.sum(axis=0) + steiner

    volume, center, inertia = merge(
        [p.volume for p in parts],
        np.array([p.center_of_mass for p in parts]).reshape(-1, 3),
        np.array([p.inertia for p in parts]).reshape(-1, 3, 3),
    )
    area, shell_center, shell_inertia = merge(
        [p.area for p in parts],
        np.array([p.shell_center_of_mass for p in parts]).reshape(-1, 3),
        np.array([p.shell_inertia for p in parts]).reshape(-1, 3, 3),
    )
    return MassProperties(volume, center, inertia, area, shell_center, shell_inertia)


#: Quadrature of an ellipsoid's shell moments: Gauss-Legendre nodes in cos(polar angle) on
#: each half, equally spaced azimuths (the trapezoid rule, spectrally accurate for a periodic
#: integrand). tests/geometry/test_mass_ellipsoid.py measures its accuracy.
_ELLIPSOID_NODES, _ELLIPSOID_AZIMUTHS = 128, 256


@functools.lru_cache(maxsize=1)
def _ellipsoid_rule() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(cos polar angle (n, 1), its weights (n, 1), cos azimuth (1, m), sin azimuth (1, m)).

    The nodes are in the polar angle (theta in [0, pi/2] and [pi/2, pi]), where the features
    of a long ellipsoid near its poles are wider than in cos(theta); du = sin(theta) dtheta."""
    nodes, weights = np.polynomial.legendre.leggauss(_ELLIPSOID_NODES)
    theta = np.concatenate([(nodes + 1.0) * (np.pi / 4.0), (nodes + 3.0) * (np.pi / 4.0)])
    u = np.cos(theta)[:, None]
    w = (np.concatenate([weights, weights]) * np.sin(theta) * (np.pi / 4.0))[:, None] * (
        2.0 * np.pi / _ELLIPSOID_AZIMUTHS
    )
    phi = np.arange(_ELLIPSOID_AZIMUTHS) * (2.0 * np.pi / _ELLIPSOID_AZIMUTHS)
    return u, w, np.cos(phi)[None, :], np.sin(phi)[None, :]


def _ellipsoid_surface(semi_axes: Sequence[float]) -> tuple[float, np.ndarray]:
    """Area and second moments (integrals of x^2, y^2, z^2 over the surface) of the ellipsoid
    surface with these semi-axes; both sides of a flat one."""
    from scipy.special import elliprg

    axes = np.asarray(semi_axes, dtype=np.float64)
    a, b, c = axes
    # Carlson's symmetric form (Carlson 1995; DLMF 19.33.1), exact also for a flat ellipse.
    area = 4.0 * np.pi * float(elliprg((b * c) ** 2, (a * c) ** 2, (a * b) ** 2))
    if np.any(axes == 0.0):  # a flat ellipse, both sides: 2 (pi a b) a^2 / 4 about its centre
        flat = np.argmin(axes)
        u_axis, w_axis = (k for k in range(3) if k != flat)
        moments = np.zeros(3)
        plate = np.pi * axes[u_axis] * axes[w_axis]
        moments[u_axis] = plate * axes[u_axis] ** 2 / 2.0
        moments[w_axis] = plate * axes[w_axis] ** 2 / 2.0
        return area, moments
    # The polar axis is the semi-axis farthest (in ratio) from the middle one: a long
    # (prolate) or short (oblate) axis, whose near-singular parts of the integrand, at the
    # poles or the equator, the Gauss nodes crowd; the azimuth then runs over the two closer
    # axes.
    middle = np.median(axes)
    polar = int(np.argmax(np.abs(np.log(axes / middle))))
    x_axis, y_axis = (k for k in range(3) if k != polar)
    a, b, c = axes[x_axis], axes[y_axis], axes[polar]
    u, w, cos_phi, sin_phi = _ellipsoid_rule()
    sin2 = np.maximum(1.0 - u * u, 0.0)
    # x = (a s cos phi, b s sin phi, c u), s = sqrt(1 - u^2): dA = |x_u x x_phi| du dphi
    element = w * np.sqrt(
        sin2 * ((b * c * cos_phi) ** 2 + (a * c * sin_phi) ** 2) + (a * b * u) ** 2
    )
    moments = np.empty(3)
    moments[x_axis] = (element * (a * a * sin2 * cos_phi**2)).sum()
    moments[y_axis] = (element * (b * b * sin2 * sin_phi**2)).sum()
    moments[polar] = (element * (c * c * u * u)).sum()
    return area, moments


def _ellipsoid_mass(primitive: Ellipsoid) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(volume, area, solid principal moments, shell principal moments) of an ellipsoid."""
    axes = np.asarray(primitive.semi_axes, dtype=np.float64)
    volume = 4.0 / 3.0 * np.pi * float(np.prod(axes))
    sq = axes**2
    solid = volume * (sq.sum() - sq) / 5.0
    area, second = _ellipsoid_surface(primitive.semi_axes)
    return volume, area, solid, second.sum() - second


def primitive_mass_properties(primitive: Primitive) -> MassProperties:
    """Exact mass properties of a primitive, centred at the origin, axis along z (density 1).

    Parameters
    ----------
    primitive : Sphere, Box, Capsule, Cylinder or Ellipsoid

    Returns
    -------
    MassProperties

    Notes
    -----
    Closed forms: solid ball ``2/5 m r^2``; box ``m (b^2 + c^2) / 12``; cylinder ``m r^2 / 2``
    about its axis and ``m (3 r^2 + h^2) / 12`` across; capsule, its cylinder plus two
    hemispheres moved by the parallel-axis theorem from their own centres of mass
    (``3 r / 8`` from the flat face); ellipsoid ``m (b^2 + c^2) / 5``. Shells: a spherical
    shell ``2/3 A r^2``; a box's six plates; a cylinder's side ``A r^2`` (axis) and
    ``A (r^2 / 2 + h^2 / 12)`` (across) and its two discs; a capsule's side and two hemispherical shells (``r / 2`` from the flat
    face). An ellipsoid's area is Carlson's elliptic integral ``4 pi R_G(b^2 c^2, a^2 c^2,
    a^2 b^2)``; its shell moments, which have no such form in scipy, a product quadrature over
    the surface (a flat one's, both sides of its ellipse, in closed form).
    """
    zero = np.zeros(3)
    if isinstance(primitive, Sphere):
        r = primitive.radius
        volume = 4.0 / 3.0 * np.pi * r**3
        area = 4.0 * np.pi * r**2
        solid = np.full(3, 0.4 * volume * r**2)
        shell = np.full(3, 2.0 / 3.0 * area * r**2)
    elif isinstance(primitive, Box):
        size = np.asarray(primitive.size, dtype=np.float64)
        volume = float(np.prod(size))
        sq = size**2
        solid = volume * (sq.sum() - sq) / 12.0
        shell = np.zeros(3)
        area = 0.0
        for axis in range(3):  # the two plates normal to this axis
            u, w = [k for k in range(3) if k != axis]
            plate = size[u] * size[w]
            area += 2.0 * plate
            moments = np.zeros(3)  # of one plate about the box centre
            moments[axis] = plate * (sq[u] + sq[w]) / 12.0
            moments[u] = plate * (sq[w] / 12.0 + sq[axis] / 4.0)
            moments[w] = plate * (sq[u] / 12.0 + sq[axis] / 4.0)
            shell += 2.0 * moments
    elif isinstance(primitive, Ellipsoid):
        volume, area, solid, shell = _ellipsoid_mass(primitive)
    elif isinstance(primitive, (Cylinder, Capsule)):
        r, h = primitive.radius, primitive.length
        cylinder = np.pi * r**2 * h
        side = 2.0 * np.pi * r * h
        axial = 0.5 * cylinder * r**2
        across = cylinder * (3.0 * r**2 + h**2) / 12.0
        shell_axial = side * r**2
        shell_across = side * (0.5 * r**2 + h**2 / 12.0)
        if isinstance(primitive, Cylinder):
            disc = np.pi * r**2  # each of the two caps
            volume, area = cylinder, side + 2.0 * disc
            shell_axial += 2.0 * disc * r**2 / 2.0
            shell_across += 2.0 * disc * (r**2 / 4.0 + h**2 / 4.0)
        else:
            ball = 4.0 / 3.0 * np.pi * r**3  # the two hemispheres
            sphere = 4.0 * np.pi * r**2
            volume, area = cylinder + ball, side + sphere
            axial += 0.4 * ball * r**2
            across += ball * (0.4 * r**2 + 3.0 * h * r / 8.0 + h**2 / 4.0)
            shell_axial += 2.0 / 3.0 * sphere * r**2
            shell_across += sphere * (2.0 * r**2 / 3.0 + h * r / 2.0 + h**2 / 4.0)
        solid = np.array([across, across, axial])
        shell = np.array([shell_across, shell_across, shell_axial])
    else:
        raise TypeError(f"not a primitive: {type(primitive).__name__}")
    return MassProperties(float(volume), zero, np.diag(solid), float(area), zero, np.diag(shell))
