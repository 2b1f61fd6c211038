"""Loader robustness: OFF by its spec, OBJ face indices, encodings, BOMs, glTF references.

Every bad file is refused with one line naming the file (and the line of the file where there
is one), exit 2 through the CLI, never a traceback.
"""

from __future__ import annotations

import json
import math
import os
import re

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given
from hypothesis import strategies as st

from meshcol.cli import main
from meshcol.errors import InvalidMeshError
from meshcol.io.mesh_read import load_mesh
from meshcol.io.off import read_off, triangulate_polygons
from meshcol.io.scene import load_scene

CUBE_VERTICES = """\
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
"""
# outward quads of the unit cube
CUBE_QUADS = """\
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
"""


def volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Signed volume enclosed by triangles (divergence theorem)."""
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6)


def _cli(*args: str):
    return CliRunner().invoke(main, list(args))


def _load_one(path) -> tuple[np.ndarray, np.ndarray]:
    (body,) = load_mesh(path, merge=False)
    return body.vertices, body.faces


def _one_error_line(result, path) -> str:
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"meshcol: error: {path}: "), lines[0]
    assert "Traceback" not in result.output
    return lines[0]


# --- OFF -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "header",
    [
        "OFF\n8 6 12\n",
        "OFF 8 6 12\n",  # counts on the keyword line
        "# made by hand\nOFF # comment\n\n8 6 12 # counts\n",
        "8 6 12\n",  # the keyword is optional
    ],
)
def test_off_quads_are_triangulated(tmp_path, header):
    path = tmp_path / "cube.off"
    path.write_text(header + CUBE_VERTICES + CUBE_QUADS)
    vertices, faces = _load_one(path)
    assert faces.shape == (12, 3)
    assert volume(vertices, faces) == pytest.approx(1.0, abs=1e-12)


def test_off_with_colours_normals_and_texture_coordinates(tmp_path):
    # STCNOFF: each vertex line is x y z, nx ny nz, r g b a, s t; faces carry a colour
    vertex_lines = [
        " ".join(line.split() + ["0", "0", "1", "0.5", "0.5", "0.5", "1", "0.1", "0.2"])
        for line in CUBE_VERTICES.splitlines()
    ]
    face_lines = [line + " 255 0 0" for line in CUBE_QUADS.splitlines()]
    path = tmp_path / "cube.off"
    path.write_text("STCNOFF\n8 6 0\n" + "\n".join(vertex_lines + face_lines) + "\n")
    vertices, faces = _load_one(path)
    assert np.array_equal(vertices, np.loadtxt(CUBE_VERTICES.splitlines()))
    assert volume(vertices, faces) == pytest.approx(1.0, abs=1e-12)


def test_off_mixed_polygons_keep_every_face_and_the_volume(tmp_path):
    # a unit cube whose top is a pentagon and a triangle, whose bottom is one quad
    path = tmp_path / "mixed.off"
    path.write_text(
        "OFF\n9 7 0\n"
        + CUBE_VERTICES
        + "0.5 1 1\n"
        + "4 0 3 2 1\n"
        + "5 4 5 6 8 7\n"  # top: pentagon through the mid-point of the back edge
        + "4 0 1 5 4\n4 1 2 6 5\n"
        + "5 2 3 7 8 6\n"  # back: pentagon (with a flat corner at 8)
        + "4 3 0 4 7\n"
        + "3 7 8 8\n"  # a degenerate triangle is still a face
    )
    vertices, faces = _load_one(path)
    assert len(faces) == 2 + 3 + 2 + 2 + 3 + 2 + 1
    assert volume(vertices, faces) == pytest.approx(1.0, abs=1e-12)


def test_off_non_convex_polygon_is_ear_clipped(tmp_path):
    # an L-shaped hexagon: a fan from corner 0 would put a triangle outside it
    path = tmp_path / "l.off"
    path.write_text("OFF\n6 1 0\n0 0 0\n2 0 0\n2 1 0\n1 1 0\n1 2 0\n0 2 0\n6 1 2 3 4 5 0\n")
    vertices, faces = _load_one(path)
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(cross[:, 2] > 0)  # every triangle keeps the polygon's winding
    assert 0.5 * cross[:, 2].sum() == pytest.approx(3.0)  # and they tile it: area 3
    centroids = tri.mean(axis=1)
    assert not np.any((centroids[:, 0] > 1) & (centroids[:, 1] > 1))  # none in the notch


def test_homogeneous_off_is_divided_by_w(tmp_path):
    rows = [" ".join(line.split() + ["2"]) for line in CUBE_VERTICES.splitlines()]
    lines = [" ".join(str(2 * float(x)) for x in row.split()[:3]) + " 2" for row in rows]
    path = tmp_path / "cube4.off"
    path.write_text("4OFF\n8 6 0\n" + "\n".join(lines) + "\n" + CUBE_QUADS)
    vertices, faces = _load_one(path)
    assert np.array_equal(vertices, np.loadtxt(CUBE_VERTICES.splitlines()))
    # nOFF with dimension 3 (and its homogeneous form) reads the same
    path.write_text("4nOFF 3\n8 6 0\n" + "\n".join(lines) + "\n" + CUBE_QUADS)
    assert np.array_equal(_load_one(path)[0], vertices)
    path.write_text("nOFF\n3\n8 6 0\n" + CUBE_VERTICES + CUBE_QUADS)
    assert np.array_equal(_load_one(path)[0], vertices)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            "nOFF 4\n3 1 0\n0 0 0 0\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
            "cannot parse OFF file: line 1: 4-dimensional OFF is not supported (only 3-D "
            "coordinates)",
        ),
        (
            "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 0\n3 0 1 2\n",
            "cannot parse OFF file: line 5: vertex 2 has w = 0 (a point at infinity)",
        ),
        (
            "4OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
            "cannot parse OFF file: line 3: vertex 0 has 3 coordinates, expected 4",
        ),
        (
            "OFF BINARY\n",
            "cannot parse OFF file: line 1: binary OFF is not supported (convert it to text OFF)",
        ),
        (
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
            "cannot parse OFF file: line 6: face 0: vertex index 3 is out of range (the file "
            "has 3 vertices, indexed from 0)",
        ),
        (
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n",
            "cannot parse OFF file: line 6: face 0 announces 4 corners but lists 3",
        ),
        (
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n",
            "cannot parse OFF file: line 6: face 0 has 2 corners (a face needs at least 3)",
        ),
        (
            "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n",
            "cannot parse OFF file: line 4: vertex 1: expected numbers, got '1 x 0'",
        ),
        (
            "XOFF\n3 1 0\n",
            "cannot parse OFF file: line 1: unknown OFF header keyword 'XOFF'",
        ),
        ("", "cannot parse OFF file: the file is empty"),
    ],
)
def test_bad_off_is_refused_with_its_line(tmp_path, content, message):
    path = tmp_path / "bad.off"
    path.write_text(content)
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == message
    assert str(info.value) == f"{path}: {message}"
    line = _one_error_line(_cli("inspect", str(path)), path)
    assert line == f"meshcol: error: {path}: {message}"


# Simple polygons with a known area: star-shaped around the origin (radii > 0, angles sorted).
@given(
    st.lists(
        st.tuples(
            st.floats(0.1, 10.0),
            st.floats(0.0, 2 * math.pi, exclude_max=True),
        ),
        min_size=3,
        max_size=12,
        unique_by=lambda rt: round(rt[1], 3),
    ),
    st.booleans(),
)
def test_triangulation_tiles_any_simple_polygon(points, clockwise):
    points = sorted(points, key=lambda rt: rt[1])
    angles = np.array([t for _, t in points])
    # star-shaped about the origin only if no gap between consecutive angles reaches pi
    gaps = np.diff(np.concatenate([angles, [angles[0] + 2 * math.pi]]))
    if gaps.max() >= math.pi - 1e-3:
        return
    xy = np.array([[r * math.cos(t), r * math.sin(t)] for r, t in points])
    if clockwise:
        xy = xy[::-1]
    x, y = xy[:, 0], xy[:, 1]
    signed = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))  # shoelace
    vertices = np.column_stack([xy, np.zeros(len(xy))])
    # the same polygon tilted in 3-D: the plane of its Newell normal is found
    tilt = np.array([[1, 0, 0], [0, 0.6, -0.8], [0, 0.8, 0.6]])
    vertices = vertices @ tilt.T
    n = len(xy)
    triangles = triangulate_polygons(vertices, np.arange(n), np.array([n]))
    assert triangles.shape == (n - 2, 3)
    tri = vertices[triangles] @ tilt  # back to the plane z = 0
    cross = (tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1]) - (
        tri[:, 1, 1] - tri[:, 0, 1]
    ) * (tri[:, 2, 0] - tri[:, 0, 0])
    # the triangles tile the polygon: their signed areas add up to its area, none turns back
    assert 0.5 * cross.sum() == pytest.approx(signed, rel=1e-9, abs=1e-9)
    assert np.all(np.sign(cross) * np.sign(signed) >= -1e-9 * abs(signed))
    assert 0.5 * np.abs(cross).sum() == pytest.approx(abs(signed), rel=1e-9, abs=1e-9)


def test_read_off_keeps_face_order():
    data = b"OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n3 0 1 4\n4 0 1 2 3\n"
    _, faces = read_off(data, "x.off")
    assert faces.tolist() == [[0, 1, 4], [0, 1, 2], [0, 2, 3]]


# --- OBJ face indices ----------------------------------------------------------------------

TETRA_VERTICES = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"


@pytest.mark.parametrize(
    ("faces", "message"),
    [
        (
            "f 1 2 3\nf 0 1 2\n",
            "cannot parse OBJ file: line 6: face index 0 (OBJ indices start at 1)",
        ),
        (
            "f 1 2 99\n",
            "cannot parse OBJ file: line 5: face index 99 but the file has 4 vertices",
        ),
        (
            "f 1/1/1 2/1/1 0/1/1\n",
            "cannot parse OBJ file: line 5: face index 0 (OBJ indices start at 1)",
        ),
        (
            "f -1 -2 -5\n",
            "cannot parse OBJ file: line 5: relative face index -5 but only 4 vertices precede it",
        ),
        (
            "f 1 2 x\n",
            "cannot parse OBJ file: line 5: face vertex 'x' is not an index",
        ),
    ],
)
def test_bad_obj_face_index_names_the_line(tmp_path, faces, message):
    path = tmp_path / "bad.obj"
    path.write_text(TETRA_VERTICES + faces)
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == message
    line = _one_error_line(_cli("inspect", str(path)), path)
    assert line == f"meshcol: error: {path}: {message}"


def test_obj_negative_relative_indices_are_valid(tmp_path):
    path = tmp_path / "relative.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"  # the three vertices so far
        "v 0 0 1\nf 1 2 -1\nf 1 -2/1 -1\n"  # -1 is now vertex 4
    )
    vertices, faces = _load_one(path)
    got = {tuple(sorted(map(tuple, vertices[f].tolist()))) for f in faces}
    assert got == {
        ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
        ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
        ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    }


# --- encodings -------------------------------------------------------------------------------


def test_latin1_comment_loads_in_every_text_format(tmp_path):
    obj = tmp_path / "latin.obj"
    obj.write_bytes(b"# caf\xe9 cr\xe8me\n" + TETRA_VERTICES.encode() + b"f 1 3 2\nf 1 2 4\n")
    assert len(_load_one(obj)[1]) == 2
    off = tmp_path / "latin.off"
    off.write_bytes(b"OFF # caf\xe9\n" + b"8 6 0\n" + (CUBE_VERTICES + CUBE_QUADS).encode())
    assert len(_load_one(off)[1]) == 12
    stl = tmp_path / "latin.stl"
    stl.write_bytes(
        b"solid caf\xe9\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
        b"vertex 0 1 0\nendloop\nendfacet\nendsolid\n"
    )
    assert len(_load_one(stl)[1]) == 1
    ply = tmp_path / "latin.ply"
    ply.write_bytes(
        b"ply\nformat ascii 1.0\ncomment caf\xe9\nelement vertex 3\nproperty float x\n"
        b"property float y\nproperty float z\nelement face 1\n"
        b"property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    )
    assert len(_load_one(ply)[1]) == 1
    for path in (obj, off, stl, ply):
        assert _cli("inspect", str(path), "--report", os.devnull).exit_code == 0


def test_latin1_object_name_is_kept(tmp_path):
    path = tmp_path / "names.obj"
    path.write_bytes(b"o caf\xe9\n" + TETRA_VERTICES.encode() + b"f 1 2 3\no b\nf 1 2 4\n")
    assert [b.name for b in load_mesh(path)] == ["names/café", "names/b"]


@pytest.mark.parametrize("suffix", [".obj", ".off", ".stl", ".ply"])
def test_random_bytes_are_one_line_exit_2(tmp_path, suffix):
    path = tmp_path / f"noise{suffix}"
    path.write_bytes(np.random.default_rng(7).integers(0, 256, 3000, dtype=np.uint8).tobytes())
    with pytest.raises(InvalidMeshError):
        load_mesh(path)
    _one_error_line(_cli("inspect", str(path)), path)
    _one_error_line(_cli("check", str(path)), path)


def test_manifest_with_byte_order_mark(tmp_path):
    (tmp_path / "tetra.obj").write_text(TETRA_VERTICES + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    manifest = {"bodies": [{"name": "t", "mesh": "tetra.obj"}]}
    path = tmp_path / "scene.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(manifest).encode())
    assert [b.name for b in load_scene(path).bodies] == ["t"]
    toml = tmp_path / "scene.toml"
    toml.write_bytes(b"\xef\xbb\xbf" + b'[[bodies]]\nname = "t"\nmesh = "tetra.obj"\n')
    assert [b.name for b in load_scene(toml).bodies] == ["t"]
    assert _cli("check", str(path), "--report", os.devnull).exit_code == 0


# --- glTF references ---------------------------------------------------------------------


def _gltf(tmp_path, edit) -> str:
    import base64

    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    indices = np.array([0, 1, 2], np.uint32).tobytes()
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 3,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            },
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12},
        ],
        "buffers": [
            {
                "byteLength": 48,
                "uri": "data:application/octet-stream;base64,"
                + base64.b64encode(vertices + indices).decode(),
            }
        ],
    }
    edit(document)
    path = tmp_path / "scene.gltf"
    path.write_text(json.dumps(document))
    return str(path)


def test_good_gltf_loads(tmp_path):
    (body,) = load_mesh(_gltf(tmp_path, lambda d: None))
    assert body.faces.shape == (1, 3)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda d: d["meshes"][0]["primitives"][0].__setitem__("indices", 7),
            "mesh 0 primitive 0 indices refers to accessor 7, but the file has 2 accessors",
        ),
        (
            # -1 would silently take the last accessor
            lambda d: d["meshes"][0]["primitives"][0]["attributes"].__setitem__("POSITION", -1),
            "mesh 0 primitive 0 POSITION refers to accessor -1, but the file has 2 accessors",
        ),
        (
            lambda d: d["nodes"][0].__setitem__("mesh", 3),
            "node 0 refers to mesh 3, but the file has 1 meshes",
        ),
        (
            lambda d: d["accessors"][0].__setitem__("bufferView", 9),
            "accessor 0 refers to bufferView 9, but the file has 2 bufferViews",
        ),
        (
            lambda d: d["buffers"][0].pop("uri"),
            "buffer 0 has no uri (only the first buffer of a GLB file may be its binary chunk)",
        ),
        (
            lambda d: d["accessors"][1].__setitem__("componentType", 1),
            "accessor 1 has componentType 1 (expected one of 5120, 5121, 5122, 5123, 5125, 5126)",
        ),
        (
            lambda d: d.pop("accessors"),
            "mesh 0 primitive 0 POSITION refers to accessor 0, but the file has 0 accessors",
        ),
    ],
)
def test_gltf_bad_reference_is_one_line(tmp_path, edit, message):
    path = _gltf(tmp_path, edit)
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == f"cannot parse GLTF file: {message}"
    _one_error_line(_cli("inspect", path), path)


# --- dependency ranges ---------------------------------------------------------------------


def test_every_runtime_dependency_has_a_lower_bound_that_is_installed_or_newer():
    """`make test-lowest` pins the lower bounds `.ci/lowest_constraints.py` derives; each must
    exist for every dependency, and the installed versions must lie in the ranges."""
    import importlib.metadata
    import importlib.util
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    spec = importlib.util.spec_from_file_location("lowest", root / ".ci" / "lowest_constraints.py")
    assert spec is not None and spec.loader is not None
    lowest = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(lowest)
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib
    project = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    pins = lowest.lowest_constraints(project["dependencies"])
    assert len(pins) == len(project["dependencies"])
    with pytest.raises(ValueError, match="without a lower bound"):
        lowest.lowest_constraints(["numpy"])

    def version_tuple(text: str) -> tuple[int, ...]:
        return tuple(int(part) for part in re.findall(r"\d+", text)[:3])

    for pin in pins:
        requirement, _, marker = pin.partition(";")
        if marker and "python_version < '3.11'" in marker and sys.version_info >= (3, 11):
            continue
        name, low = requirement.strip().split("==")
        low = low.removesuffix(".*")
        installed = importlib.metadata.version(name)
        assert version_tuple(installed) >= version_tuple(low), (name, installed, low)


def test_non_utf8_bad_token_is_one_line(tmp_path):
    # the native reader's message quotes the token: its bytes are not UTF-8
    path = tmp_path / "bad.obj"
    path.write_bytes(TETRA_VERTICES.encode() + b"f 1 2 caf\xe9\n")
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == "cannot parse OBJ file: line 5: face vertex 'café' is not an index"
    _one_error_line(_cli("inspect", str(path)), path)
