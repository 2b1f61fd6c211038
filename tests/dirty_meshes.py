"""Dirty hosts of our own making for the inside-test tests and benchmarks (issue 29): closed
concave meshes, their faces shuffled, a cube placed against them, checked."""

from __future__ import annotations

import manifold3d
import numpy as np
import trimesh

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.collision.mesh_query import MeshSet
from meshcol.types import Body, Scene


def _mesh(solid: manifold3d.Manifold) -> tuple[np.ndarray, np.ndarray]:
    m = solid.to_mesh64()
    return np.asarray(m.vert_properties)[:, :3].copy(), np.asarray(m.tri_verts, dtype=np.int64)


def airplane() -> tuple[np.ndarray, np.ndarray]:
    """A concave closed mesh about 1 m long: fuselage, wings, tail fin."""
    M = manifold3d.Manifold
    fuselage = M.cylinder(1.0, 0.06, 0.04, 32).rotate((0.0, 90.0, 0.0)).translate((-0.5, 0, 0))
    wings = M.cube((0.16, 0.9, 0.02)).translate((-0.1, -0.45, -0.01))
    fin = M.cube((0.1, 0.02, 0.2)).translate((0.35, -0.01, 0.0))
    return _mesh(fuselage + wings + fin)


def torus() -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.torus(major_radius=0.4, minor_radius=0.15, major_sections=48)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)


def blob() -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    v = np.asarray(mesh.vertices)
    v = v * (1.0 + 0.15 * np.sin(5 * v[:, [0]]) * np.cos(4 * v[:, [1]]))  # lumpy, star-shaped
    return v, np.asarray(mesh.faces, dtype=np.int64)


def moebius(width: float = 0.3, sections: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A Moebius strip of radius 1 about the origin: non-orientable, no winding decides it."""
    t = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), np.zeros(sections)], axis=1)
    half = width * np.stack(
        [np.cos(t / 2) * np.cos(t), np.cos(t / 2) * np.sin(t), np.sin(t / 2)], 1
    )
    faces = []
    for i in range(sections):
        j = (i + 1) % sections
        a, b, c, d = i, j, sections + i, sections + j
        if j == 0:  # the half twist joins the strip's two sides crossed
            b, d = d, b
        faces += [[a, b, c], [b, d, c]]
    return np.concatenate([ring + half, ring - half]), np.array(faces)


HOSTS = {"airplane": airplane, "torus": torus, "blob": blob}


def shuffled(faces: np.ndarray, seed: int = 0) -> np.ndarray:
    """Half the faces, at random, reversed."""
    flip = np.random.default_rng(seed).random(len(faces)) < 0.5
    return np.where(flip[:, None], faces[:, ::-1], faces)


def cube(size: float) -> tuple[np.ndarray, np.ndarray]:
    box = trimesh.creation.box(extents=(size, size, size))
    return np.asarray(box.vertices), np.asarray(box.faces, dtype=np.int64)


def at(offset) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = offset
    return pose


def check_pair(host, cube, pose, collider="mesh"):
    scene = Scene(
        (
            Body("host", None, host[0], host[1]),
            Body("cube", None, cube[0], cube[1], pose),
        )
    )
    return check_scene(scene, CheckOptions(collider=collider, clearance=0.01))


def on_top(host, gap: float, size: float) -> np.ndarray:
    """The pose of a cube of edge ``size`` whose bottom face lies ``gap`` above (negative:
    below) the interior of the host's highest upward face, parallel to it: the cube's
    footprint stays inside that one triangle, so the gap is exact."""
    v, f = host
    corners = v[f]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = np.linalg.norm(normals, axis=1)
    normals = normals / area[:, None]
    centre = corners.mean(axis=1)
    # the inradius of the face must hold the footprint (half diagonal) with room to spare
    edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).sum(axis=1)
    fits = (area / edges > 1.5 * size) & (normals[:, 2] > 0.7)
    k = int(np.flatnonzero(fits)[np.argmax(centre[fits, 2])])
    z = normals[k]
    x = np.cross(z, [0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.cross(z, [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([x, np.cross(z, x), z], axis=1)
    pose[:3, 3] = centre[k] + (gap + size / 2) * z
    return pose


def inner(host) -> np.ndarray:
    """A point well inside the host (a vertex pushed inward along -normal)."""
    v, f = host
    mesh = trimesh.Trimesh(v, f, process=False)
    probe = np.asarray(mesh.triangles_center) - 0.02 * np.asarray(mesh.face_normals)
    wn = MeshSet.from_arrays([host]).winding_number(0, probe)  # consistently wound: as given
    return probe[int(np.argmax(wn))]
