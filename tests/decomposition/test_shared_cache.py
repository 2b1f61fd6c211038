"""The shared cache: fsspec URLs, atomic writes under concurrent writers, keys that survive
re-exports (OBJ, STL, PLY; float noise) through quantised canonical geometry."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import FAST_DECOMPOSE

from meshcol.decomposition import cache as decompose_cache
from meshcol.decomposition.batch import decompose_files
from meshcol.decomposition.canonical import QUANTUM_BITS, canonical_geometry, quantise
from meshcol.decomposition.decompose import decompose
from meshcol.errors import MissingDependencyError
from meshcol.io.mesh_read import load_mesh

FAST = {
    "threshold": 0.2,
    "resolution": 500,
    "engine_options": {"mcts_iterations": "20", "mcts_nodes": "8", "mcts_max_depth": "2"},
}


def _odd_mesh() -> trimesh.Trimesh:
    """A closed mesh whose coordinates are nowhere near round numbers."""
    mesh = trimesh.creation.icosphere(subdivisions=1, radius=0.37)
    mesh.apply_transform(
        trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3))
    )
    mesh.apply_translation([0.1234567, -0.0456789, 0.0333333])
    return mesh


def _write_obj_full_precision(mesh: trimesh.Trimesh, path: Path) -> None:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces.tolist()]
    path.write_text("\n".join(lines) + "\n")


def _key(path: Path) -> str:
    return json.dumps([a.tolist() for a in canonical_geometry(*_arrays(path))])


def _arrays(path: Path) -> tuple[np.ndarray, np.ndarray]:
    (body,) = load_mesh(path)
    return np.asarray(body.vertices), np.asarray(body.faces)


def test_obj_stl_and_ply_of_one_geometry_get_one_canonical_form(tmp_path) -> None:
    mesh = _odd_mesh()
    _write_obj_full_precision(mesh, tmp_path / "m.obj")
    mesh.export(tmp_path / "m.stl")  # float32, one vertex triple per triangle
    mesh.export(tmp_path / "m.ply")  # float64
    stl = trimesh.load(tmp_path / "m.stl", force="mesh", process=False)
    assert stl.vertices.dtype == np.float64 and not np.array_equal(
        np.unique(stl.vertices, axis=0), np.unique(mesh.vertices, axis=0)
    ), "the STL is float32: its coordinates differ from the float64 ones"
    assert _key(tmp_path / "m.obj") == _key(tmp_path / "m.stl") == _key(tmp_path / "m.ply")


@pytest.mark.slow
def test_the_three_exports_hit_one_cache_entry(tmp_path) -> None:
    mesh = _odd_mesh()
    _write_obj_full_precision(mesh, tmp_path / "m.obj")
    mesh.export(tmp_path / "n.stl")
    mesh.export(tmp_path / "p.ply")
    cache = tmp_path / "cache"
    reports = [
        decompose_files([tmp_path / name], tmp_path / f"out-{name}", cache_dir=cache, **FAST)
        for name in ("m.obj", "n.stl", "p.ply")
    ]
    bodies = [r.files[0]["bodies"][0] for r in reports]
    assert [b["from_cache"] for b in bodies] == [False, True, True]
    assert len({b["cache_key"] for b in bodies}) == 1
    assert len(list(cache.rglob("*.npz"))) == 1
    # The same parts, whichever file they came from (only the body's name differs).
    obj, stl = files_of(tmp_path / "out-m.obj"), files_of(tmp_path / "out-n.stl")
    assert [name.replace("n_", "m_") for name in stl] == list(obj)
    for a, b in zip(obj.values(), stl.values(), strict=True):
        assert a.replace(b"o m_", b"o n_") == b


def files_of(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_noise_below_the_step_keeps_the_form_and_above_it_changes_it() -> None:
    mesh = _odd_mesh()
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    step = 2.0 ** (np.ceil(np.log2(np.abs(v).max())) - QUANTUM_BITS)
    base = canonical_geometry(v, f)
    rng = np.random.default_rng(0)
    # Noise 1e-4 of a step: a coordinate changes cell only within 1e-4 steps of a boundary
    # (about 2e-4 of the coordinates; none here, checked for this seed).
    quiet = canonical_geometry(v + rng.uniform(-1e-4, 1e-4, v.shape) * step, f)
    assert all(np.array_equal(a, b) for a, b in zip(base, quiet, strict=True))
    loud = canonical_geometry(v + rng.uniform(-50, 50, v.shape) * step, f)
    assert not np.array_equal(base[0], loud[0])


def test_quantise_moves_coordinates_by_at_most_half_a_step_plus_float32() -> None:
    rng = np.random.default_rng(1)
    for scale in (1e-3, 1.0, 37.5, 4096.0, 1e6):
        v = rng.uniform(-scale, scale, (500, 3))
        q = quantise(v)
        step = 2.0 ** (np.ceil(np.log2(np.abs(v.astype(np.float32)).max())) - QUANTUM_BITS)
        assert np.abs(q - v).max() <= 0.5 * step + np.abs(v).max() * 2.0**-24
        assert np.array_equal(quantise(q), q)  # idempotent
        assert np.array_equal(quantise(v.astype(np.float32)), q)  # depends on float32 only
        assert not np.signbit(quantise(-np.zeros((1, 3)))).any()


def test_memory_url_cache_round_trip_and_corrupt_entry_is_a_miss(tmp_path) -> None:
    pytest.importorskip("fsspec")
    import fsspec

    url = "memory://meshcol-test-cache"
    mesh = trimesh.creation.box(extents=(1.0, 0.5, 0.25))
    first = decompose(mesh, cache_dir=url, **FAST)
    again = decompose(mesh, cache_dir=url, **FAST)
    assert not first.from_cache and again.from_cache
    assert [np.array_equal(a, b) for (a, _), (b, _) in zip(first.parts, again.parts, strict=True)]
    fs = fsspec.filesystem("memory")
    (entry,) = [p for p in fs.find("/meshcol-test-cache") if p.endswith(".npz")]
    data = fs.cat_file(entry)
    fs.pipe_file(entry, data[: len(data) // 2])
    assert decompose_cache.load(first.cache_key, url) is None
    fs.pipe_file(entry, data)
    assert decompose_cache.load(first.cache_key, url) is not None
    fs.rm("/meshcol-test-cache", recursive=True)


def test_file_url_is_the_folder(tmp_path) -> None:
    mesh = trimesh.creation.box(extents=(1.0, 0.5, 0.25))
    d = decompose(mesh, cache_dir=f"file://{tmp_path}", **FAST)
    assert decompose_cache.entry_path(d.cache_key, tmp_path).is_file()
    assert decompose_cache.load(d.cache_key, tmp_path) is not None


def test_a_url_cache_without_fsspec_names_the_package(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "fsspec", None)
    with pytest.raises(MissingDependencyError, match="pip install fsspec"):
        decompose_cache.load("ab" * 32, "s3://bucket/cache")


@pytest.mark.slow  # about 8 s: threads racing on one entry, in the full lane only
@pytest.mark.parametrize("where", ["folder", "memory"])
def test_concurrent_writers_and_readers_never_see_a_partial_entry(where, tmp_path) -> None:
    if where == "memory":
        pytest.importorskip("fsspec")
    root = str(tmp_path) if where == "folder" else "memory://meshcol-concurrent"
    d = decompose(trimesh.creation.box(extents=(1.0, 0.5, 0.25)), use_cache=False, **FAST)
    errors: list[str] = []
    seen: list[bool] = []
    stop = threading.Event()

    def write() -> None:
        for _ in range(30):
            decompose_cache.store(d, root)

    def read() -> None:
        while not stop.is_set():
            hit = decompose_cache.load(d.cache_key, root)
            if hit is None:
                continue
            seen.append(True)
            if not all(
                np.array_equal(a, b) for (a, _), (b, _) in zip(hit.parts, d.parts, strict=True)
            ):
                errors.append("different parts")

    readers = [threading.Thread(target=read) for _ in range(2)]
    writers = [threading.Thread(target=write) for _ in range(3)]
    for t in readers + writers:
        t.start()
    for t in writers:
        t.join()
    stop.set()
    for t in readers:
        t.join()
    assert errors == [] and seen
    if where == "folder":
        assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == [f"{d.cache_key}.npz"]


@pytest.mark.slow
def test_two_concurrent_runs_on_one_shared_cache_leave_valid_entries(tmp_path) -> None:
    shapes = {
        "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12),
        "box": trimesh.creation.box(extents=(2, 1, 1)),
        "capsule": trimesh.creation.capsule(height=1.0, radius=0.3, count=[12, 12]),
    }
    inputs = []
    for name, mesh in shapes.items():
        inputs.append(str(tmp_path / f"{name}.obj"))
        mesh.export(inputs[-1])
    cache = tmp_path / "cache"
    runs = [
        subprocess.Popen(
            [sys.executable, "-m", "meshcol", "decompose", *inputs, "-o", str(tmp_path / f"o{i}")]
            + ["--cache-dir", str(cache), *FAST_DECOMPOSE],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for i in range(2)
    ]
    outputs = [run.communicate(timeout=120) for run in runs]
    assert [run.returncode for run in runs] == [0, 0], outputs
    entries = sorted(p for p in cache.rglob("*") if p.is_file())
    assert len(entries) == 3 and all(p.suffix == ".npz" for p in entries)  # no temporary left
    for p in entries:
        assert decompose_cache.load(p.stem, cache) is not None
    assert files_of(tmp_path / "o0") == files_of(tmp_path / "o1")
    third = decompose_files(inputs, tmp_path / "o2", cache_dir=cache, **FAST)
    assert all(b["from_cache"] for f in third.files for b in f["bodies"])
    assert files_of(tmp_path / "o2") == files_of(tmp_path / "o0")
