"""meshcol.io.mesh_formats: the one registry from a file extension to its reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from meshcol.errors import InputFileError, InvalidMeshError, MissingDependencyError
from meshcol.io import mesh_formats
from meshcol.io.mesh_formats import (
    FORMATS,
    MESH_EXTENSIONS,
    MeshFormat,
    check_file,
    mesh_format,
    read_natively,
)
from meshcol.io.mesh_read import load_mesh, load_meshes


def test_every_extension_is_lower_case_and_belongs_to_one_format():
    extensions = [e for fmt in FORMATS for e in fmt.extensions]
    assert len(extensions) == len(set(extensions))
    assert all(e.startswith(".") and e == e.lower() for e in extensions)
    assert all(fmt.name == fmt.name.lower() for fmt in FORMATS)
    # read by the core, or by Python (mesh nodes, or a whole scene: USD)
    assert all((fmt.read is None and fmt.scene is None) != (fmt.native is None) for fmt in FORMATS)


def test_the_commands_read_what_they_always_read():
    # the unknown-extension message lists these, in this order
    assert list(MESH_EXTENSIONS) == [
        *(".obj", ".stl", ".ply", ".off", ".glb", ".gltf", ".fbx", ".dae"),
        *(".usd", ".usda", ".usdc", ".usdz"),
    ]
    assert read_natively("a.OBJ") and read_natively("b.stl") and not read_natively("c.ply")
    assert not read_natively("d.dae") and not read_natively("noextension")


def test_collada_is_one_of_the_commands_inputs(tmp_path):
    # it was read for robot descriptions only (a load_mesh keyword), now by every command
    with pytest.raises(InputFileError, match=r"unknown mesh file extension '\.3ds' \(expected"):
        mesh_format("arm.3ds")
    assert mesh_format("arm.DAE").name == "dae" and mesh_format("arm.dae").units == "m"
    with pytest.raises(InputFileError, match="file not found"):
        check_file(str(tmp_path / "missing.dae"))


def test_a_format_that_needs_a_module_says_how_to_install_it(tmp_path, monkeypatch):
    path = tmp_path / "arm.dae"
    path.write_text("<COLLADA/>")
    monkeypatch.setattr(mesh_formats.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(MissingDependencyError, match="needs pycollada"):
        load_mesh(path)


def read_xyz(file: Path, source: str) -> list:
    """A toy format: one triangle per line of nine numbers."""
    rows = [line.split() for line in file.read_text().splitlines() if line.strip()]
    try:
        corners = np.array(rows, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        raise InvalidMeshError(
            "cannot parse XYZ file: expected nine numbers a line", source
        ) from None
    faces = np.arange(len(corners)).reshape(-1, 3)
    return [(file.stem, np.eye(4), corners, faces, ())] if len(faces) else []


def test_a_new_format_is_one_reader_and_one_entry(tmp_path, monkeypatch):
    # The recipe of ARCHITECTURE.md, done in a test: nothing but the entry is added.
    xyz = MeshFormat("xyz", (".xyz",), read=read_xyz)
    monkeypatch.setattr(mesh_formats, "_BY_EXTENSION", {**mesh_formats._BY_EXTENSION, ".xyz": xyz})
    path = tmp_path / "tri.xyz"
    path.write_text("0 0 0 1 0 0 0 1 0\n0 0 0 0 1 0 0 0 1\n")
    (body,) = load_mesh(path)
    assert body.name == "tri" and body.faces.shape == (2, 3)
    assert len(body.vertices) == 4  # merged by position, as every format
    assert [b.name for b in load_meshes([path])[0]] == ["tri"]
    (tmp_path / "empty.xyz").write_text("")
    with pytest.raises(InvalidMeshError, match="mesh has no faces"):
        load_mesh(tmp_path / "empty.xyz")
    (tmp_path / "bad.xyz").write_text("0 0 x\n")
    with pytest.raises(InvalidMeshError, match="cannot parse XYZ file"):
        load_mesh(tmp_path / "bad.xyz")


def test_off_reads_through_its_registry_entry(tmp_path):
    off = next(fmt for fmt in FORMATS if fmt.name == "off")
    path = tmp_path / "quad.off"
    path.write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    ((name, matrix, vertices, faces, ancestors),) = off.read(path, str(path))
    assert (
        name == "quad"
        and ancestors == ()
        and np.array_equal(matrix, np.eye(4))
        and faces.shape == (2, 3)
    )
    (body,) = load_mesh(path)
    assert body.faces.tolist() == faces.tolist()
