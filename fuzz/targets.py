"""Fuzz targets: the readers and the native core, each as ``one_input(data: bytes)``.

A target returns normally when meshcol handled the input, whatever the input was: loaded it,
or refused it with a :class:`meshcol.MeshcolError` (the errors the command line turns into a
one-line message and exit 2). Any other exception is a defect, and so is a crash or a hang of
the process: the fuzzer (``fuzz/run.py``, atheris) reports both.

Targets
-------
readers
    The first byte picks a format (OBJ, STL, PLY, OFF, GLB, glTF, JSON or TOML manifest, URDF);
    the rest is written to a file with that extension and loaded with ``load_mesh``,
    ``load_scene`` or ``load_robot``, as the command line does. (MJCF is left out: it is
    MuJoCo's compiler, a C library we call but do not own.)
convex
    Floats from the input (NaN, inf, denormals and huge values included) become two point
    clouds and two poses; the clouds are packed into a ``ConvexSet`` and every narrow-phase
    query runs on them, plus a time of impact. Each result must carry a status, and an OK
    status must come with finite numbers.
meshes
    Floats and indices from the input become two triangle meshes and poses; a ``MeshSet`` is
    built (BVHs in the core) and distance, intersection and contacts are queried.
manifest
    The input is a JSON manifest's bytes for the core's reader of plain manifests of mesh and
    primitive bodies (``meshcol.io.scene_native``), held to the Python reader: whatever it passes, Python's json
    module must decode and the column check pass, as equal columns to the bit.
"""

from __future__ import annotations

import json
import os
import struct
import sys
import tempfile
from pathlib import Path

import numpy as np

from meshcol.errors import MeshcolError
from meshcol.io.mesh_formats import MESH_EXTENSIONS

# Every mesh format of the registry, then the manifests and URDF (the first byte picks one).
FORMATS = (*MESH_EXTENSIONS, ".json", ".toml", ".urdf")
_MANIFESTS = {".json", ".toml"}

# One directory per process for the readers' files: a fixed name, so a manifest that refers
# to "a.obj" can find a mesh an earlier input wrote there.
_WORKDIR = Path(tempfile.mkdtemp(prefix="meshcol-fuzz-"))


def readers(data: bytes) -> None:
    from meshcol.io.mesh_read import load_mesh
    from meshcol.io.robot import load_robot
    from meshcol.io.scene import load_scene

    if not data:
        return
    suffix = FORMATS[data[0] % len(FORMATS)]
    path = _WORKDIR / f"input{suffix}"
    path.write_bytes(data[1:])
    try:
        if suffix in _MANIFESTS:
            load_scene(path)
        elif suffix == ".urdf":
            load_robot(path)
        else:
            load_mesh(path)
    except MeshcolError:
        pass
    except RecursionError as error:  # reported as a defect, with a short message
        raise AssertionError(f"RecursionError on {suffix}") from error


class _Floats:
    """Reads float64 values and small integers from the fuzzer's bytes, in order."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.at = 0

    def byte(self) -> int:
        if self.at >= len(self.data):
            return 0
        value = self.data[self.at]
        self.at += 1
        return value

    def floats(self, count: int) -> np.ndarray:
        out = np.zeros(count)
        for i in range(count):
            kind = self.byte()
            if kind < 192:  # mostly small, ordinary numbers, so queries get past validation
                out[i] = (kind - 96) / 16.0
            elif self.at + 8 <= len(self.data):
                (out[i],) = struct.unpack_from("<d", self.data, self.at)
                self.at += 8
        return out

    def pose(self) -> np.ndarray:
        pose = np.eye(4)
        if self.byte() & 1:
            q = self.floats(4)
            norm = float(np.sqrt(np.sum(q * q))) if np.all(np.isfinite(q)) else 0.0
            if norm > 1e-6 and np.isfinite(norm):
                w, x, y, z = q / norm
                pose[:3, :3] = [
                    [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                    [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
                ]
        pose[:3, 3] = self.floats(3)
        return pose


def _check_statuses(batch: object, good: int, *fields: str) -> None:
    """Every result whose status is ``good`` carries finite numbers in ``fields``."""
    status = np.asarray(batch.status)  # type: ignore[attr-defined]
    ok = status == good
    for name in fields:
        values = np.asarray(getattr(batch, name), dtype=np.float64)
        values = values.reshape(len(status), -1)
        bad = ok & ~np.all(np.isfinite(values), axis=1)
        if bad.any():
            raise AssertionError(f"status {good} with a non-finite {name}: {values[bad][0]}")


def convex(data: bytes) -> None:
    from meshcol.collision.narrowphase import (
        distance_batch,
        intersects_batch,
        penetration_batch,
        signed_distance_batch,
    )
    from meshcol.collision.shapes import ConvexSet
    from meshcol.collision.time_of_impact import time_of_impact_batch
    from meshcol.types import Status, TimeOfImpactStatus

    reader = _Floats(data)
    clouds = []
    for _ in range(2):
        count = reader.byte() % 40
        clouds.append(reader.floats(3 * count).reshape(count, 3))
    poses = np.stack([reader.pose(), reader.pose()])
    try:
        shapes = ConvexSet.from_vertices(clouds)
    except MeshcolError:
        return
    pairs = np.array([[0, 1], [1, 0], [0, 0]])
    ok = int(Status.CONVERGED)
    _check_statuses(distance_batch(shapes, poses, pairs, threads=1), ok, "distance", "point_a")
    _check_statuses(penetration_batch(shapes, poses, pairs, threads=1), ok, "depth", "normal")
    _check_statuses(signed_distance_batch(shapes, poses, pairs, threads=1), ok, "signed_distance")
    intersects_batch(shapes, poses, pairs, threads=1)
    end_poses = np.stack([reader.pose(), reader.pose()])
    toi = time_of_impact_batch(shapes, poses, end_poses, pairs, threads=1)
    _check_statuses(toi, int(TimeOfImpactStatus.HIT), "time_of_impact", "point", "normal")


def meshes(data: bytes) -> None:
    from meshcol.collision.contacts import mesh_contacts_batch
    from meshcol.collision.mesh_query import MeshSet, mesh_distance_batch, mesh_intersects_batch
    from meshcol.types import Status

    reader = _Floats(data)
    arrays = []
    for _ in range(2):
        count = 1 + reader.byte() % 24
        vertices = reader.floats(3 * count).reshape(count, 3)
        faces = np.array(
            [[reader.byte() % count for _ in range(3)] for _ in range(reader.byte() % 32)],
            dtype=np.int64,
        ).reshape(-1, 3)
        arrays.append((vertices, faces))
    poses = np.stack([reader.pose(), reader.pose()])
    try:
        mesh_set = MeshSet.from_arrays(arrays, poses, threads=1)
    except MeshcolError:
        return
    pairs = np.array([[0, 1], [1, 0], [0, 0]])
    ok = int(Status.CONVERGED)
    _check_statuses(mesh_distance_batch(mesh_set, poses, pairs, threads=1), ok, "distance")
    mesh_intersects_batch(mesh_set, poses, pairs, threads=1)
    contacts = mesh_contacts_batch(mesh_set, poses, pairs, max_contacts=8, threads=1)
    _check_statuses(contacts, ok, "depth", "face_depth")
    if np.any(contacts.contact_depth < 0) or not np.all(np.isfinite(contacts.contact_point)):
        raise AssertionError("a listed contact with a negative depth or a non-finite point")


def manifest(data: bytes) -> None:
    from meshcol.io.scene_columns import columns
    from meshcol.io.scene_native import native_columns

    found = native_columns(data)
    if found is None:
        return
    document = json.loads(data.decode("utf-8-sig"))  # it passed: Python must read it too
    expected = columns(document)
    if expected is None:
        raise AssertionError("the native reader passed a manifest the column check refuses")
    for field in expected.__dataclass_fields__:
        if not _same(getattr(found.columns, field), getattr(expected, field)):
            raise AssertionError(f"the native reader's {field} differs from the column check's")
    for field in ("units", "duration"):
        value, wanted = getattr(found, field), document.get(field)
        if (value, type(value)) != (wanted, type(wanted)):
            raise AssertionError(f"the native reader's {field} differs from the document's")


def _same(a: object, b: object) -> bool:
    """Equal to the bit: arrays by dtype, shape and bytes; dicts and lists item for item."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (
            isinstance(a, np.ndarray)
            and isinstance(b, np.ndarray)
            and (a.dtype, a.shape) == (b.dtype, b.shape)
            and a.tobytes() == b.tobytes()
        )
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


TARGETS = {"readers": readers, "convex": convex, "meshes": meshes, "manifest": manifest}


def replay(target: str, paths: list[Path]) -> None:
    """Run ``target`` on each file in ``paths`` (the regression inputs), in this process."""
    one_input = TARGETS[target]
    for path in paths:
        one_input(path.read_bytes())


if __name__ == "__main__":  # python fuzz/targets.py TARGET FILE...: replay inputs
    replay(sys.argv[1], [Path(p) for p in sys.argv[2:]])
    print(f"{len(sys.argv) - 2} inputs handled", file=sys.stderr)
    os._exit(0)
