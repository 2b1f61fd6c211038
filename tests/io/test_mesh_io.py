"""Tests for meshcol.mesh_io: every format, multi-body files, scene-graph transforms, bad input."""

from __future__ import annotations

import base64
import json
import os
import re
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import meshcol
from meshcol.errors import InputFileError, InvalidMeshError
from meshcol.io.mesh_read import load_mesh, merge_vertices, split_rigid

# A unit cube, 8 positions, with per-face UVs: trimesh splits it along the UV seams.
CUBE_OBJ_WITH_UVS = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 1 0 0
vn 0 1 0
vn -1 0 0
f 1/1/1 4/4/1 3/3/1 2/2/1
f 5/1/2 6/2/2 7/3/2 8/4/2
f 1/1/3 2/2/3 6/3/3 5/4/3
f 2/1/4 3/2/4 7/3/4 6/4/4
f 3/1/5 4/2/5 8/3/5 7/4/5
f 4/1/6 1/2/6 5/3/6 8/4/6
"""

TWO_OBJECTS_OBJ = """\
o first
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
o second
v 2 0 0
v 3 0 0
v 2 1 0
v 2 0 1
f 5 7 6
f 5 6 8
f 5 8 7
f 6 7 8
"""


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Divergence theorem: sum of signed tetrahedra from the origin."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def is_closed(faces: np.ndarray) -> bool:
    """Every directed edge has exactly one opposite: closed and consistently wound."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    directed = {tuple(e) for e in edges.tolist()}
    return len(directed) == len(edges) and all((b, a) in directed for a, b in directed)


def is_watertight(faces: np.ndarray) -> bool:
    """Every undirected edge is shared by exactly two faces."""
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool((counts == 2).all())


def is_rigid(matrix: np.ndarray) -> bool:
    r = matrix[:3, :3]
    return (
        np.allclose(r.T @ r, np.eye(3), atol=1e-12)
        and np.isclose(np.linalg.det(r), 1.0)
        and np.array_equal(matrix[3], [0, 0, 0, 1])
    )


def write_box_glb(path: Path, matrices: list[np.ndarray]) -> None:
    """A GLB holding one unit box instanced at each matrix (any affine matrix)."""
    scene = trimesh.Scene()
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    for k, matrix in enumerate(matrices):
        scene.add_geometry(box, geom_name="box", node_name=f"node{k}", transform=matrix)
    path.write_bytes(trimesh.exchange.gltf.export_glb(scene))


# --- formats --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "vertices", "faces"),
    [
        ("fandisk.obj", 6475 - 3598, 5750),  # OBJ
        ("unit_cube.STL", 8, 12),  # binary STL
        ("tet.ply", 4, 4),  # PLY
        ("ballA.off", 1900, 3796),  # OFF
    ],
)
def test_single_body_formats(corpus, name, vertices, faces):
    path = corpus / "trimesh-models" / name
    bodies = load_mesh(path)
    assert len(bodies) == 1
    body = bodies[0]
    assert body.name == Path(name).stem
    assert body.source == os.fspath(path)
    assert body.vertices.shape == (vertices, 3) and body.vertices.dtype == np.float64
    assert body.faces.shape == (faces, 3) and body.faces.dtype == np.int64
    assert np.array_equal(body.pose, np.eye(4))
    assert body.end_pose is None and body.primitive is None


def test_closed_corpus_meshes_are_closed_after_merging(corpus):
    # binary STL stores three corners per triangle: only merging makes it watertight
    for name in ("unit_cube.STL", "unit_sphere.STL", "torus.STL", "tet.ply", "ballA.off"):
        body = load_mesh(corpus / "trimesh-models" / name)[0]
        assert is_closed(body.faces), name
        assert signed_volume(body.vertices, body.faces) > 0, name
    unmerged = load_mesh(corpus / "trimesh-models" / "unit_cube.STL", merge=False)[0]
    assert len(unmerged.vertices) == 36


def test_ascii_stl_multibody(corpus):
    path = corpus / "trimesh-models" / "multibody.stl"
    assert path.read_bytes().startswith(b"solid")
    bodies = load_mesh(path)
    assert [b.name for b in bodies] == ["multibody/bodyB", "multibody/bodyA"]  # file order
    assert [len(b.faces) for b in bodies] == [12, 20]
    # closed (every edge has two faces) but, as in the file, not consistently wound
    assert all(is_watertight(b.faces) and not is_closed(b.faces) for b in bodies)


def test_obj_objects_are_bodies_in_file_order(tmp_path):
    path = tmp_path / "pair.obj"
    path.write_text(TWO_OBJECTS_OBJ)
    first, second = load_mesh(path)
    assert (first.name, second.name) == ("pair/first", "pair/second")
    assert np.allclose(first.vertices.min(axis=0), [0, 0, 0])
    assert np.allclose(second.vertices.min(axis=0), [2, 0, 0])
    assert len(first.vertices) == len(second.vertices) == 4  # unreferenced vertices dropped
    assert all(is_closed(b.faces) for b in (first, second))


def test_obj_groups_are_bodies_when_no_objects(tmp_path):
    path = tmp_path / "groups.obj"
    path.write_text(TWO_OBJECTS_OBJ.replace("o first", "g left").replace("o second", "g right"))
    assert [b.name for b in load_mesh(path)] == ["groups/left", "groups/right"]


def test_obj_faces_before_any_object_form_the_default_group(corpus):
    bodies = load_mesh(corpus / "trimesh-models" / "joined_tetrahedra.obj")
    assert [b.name for b in bodies] == ["joined_tetrahedra/default", "joined_tetrahedra/bottom"]
    assert all(len(b.vertices) == 4 and is_closed(b.faces) for b in bodies)


def test_pins_glb_seven_instances(corpus):
    bodies = load_mesh(corpus / "trimesh-models" / "pins.glb")
    assert len(bodies) == 7
    assert len({b.name for b in bodies}) == 7
    assert all(b.name.startswith("pins/") for b in bodies)
    assert sorted(len(b.faces) for b in bodies) == [314] * 6 + [1524]
    assert all(is_rigid(b.pose) for b in bodies)


def test_boolean_glb_28_bodies(corpus):
    bodies = load_mesh(corpus / "trimesh-models" / "boolean.glb")
    assert len(bodies) == 28
    assert len({b.name for b in bodies}) == 28


def world_points(bodies) -> np.ndarray:
    points = np.concatenate([b.world_vertices() for b in bodies])
    return np.unique(np.round(points, 9), axis=0)


def test_nested_glb_world_vertices_match_trimesh(corpus):
    path = corpus / "trimesh-models" / "nested.glb"
    bodies = load_mesh(path)
    assert [b.name for b in bodies] == [
        "nested/block03",
        "nested/block02",
        "nested/block01",
    ]  # file order
    assert all(is_rigid(b.pose) for b in bodies)
    reference = trimesh.load_scene(path, process=False).to_mesh()  # transforms composed
    expected = np.unique(np.round(np.asarray(reference.vertices), 9), axis=0)
    assert np.array_equal(world_points(bodies), expected)


def test_nested_glb_manual_composition(corpus):
    # compose the node chain by hand from the glTF JSON (no trimesh graph involved)
    path = corpus / "trimesh-models" / "nested.glb"
    data = path.read_bytes()
    length = struct.unpack("<I", data[12:16])[0]
    gltf = json.loads(data[20 : 20 + length])
    parent = {c: i for i, node in enumerate(gltf["nodes"]) for c in node.get("children", [])}

    def local(node):
        if "matrix" in node:
            return np.array(node["matrix"], dtype=float).reshape(4, 4).T
        x, y, z, w = node.get("rotation", [0, 0, 0, 1])
        r = np.array(trimesh.transformations.quaternion_matrix([w, x, y, z]))
        s = np.diag(node.get("scale", [1, 1, 1]) + [1])
        t = trimesh.transformations.translation_matrix(node.get("translation", [0, 0, 0]))
        return t @ r @ s

    bodies = {b.name.split("/")[1]: b for b in load_mesh(path)}
    for index, node in enumerate(gltf["nodes"]):
        if "mesh" not in node:
            continue
        matrix, k = np.eye(4), index
        while k is not None:
            matrix = local(gltf["nodes"][k]) @ matrix
            k = parent.get(k)
        body = bodies[node["name"]]
        # the loaded local vertices are the file's, stretched by the baked part
        rest = body.pose[:3, :3].T @ matrix[:3, :3]
        file_vertices = body.vertices @ np.linalg.inv(rest).T
        expected = file_vertices @ matrix[:3, :3].T + matrix[:3, 3]
        assert np.allclose(body.world_vertices(), expected, atol=1e-12)
        assert np.allclose(body.pose[:3, 3], matrix[:3, 3])


def test_mirror_and_shear_are_baked_and_winding_kept_outward(tmp_path):
    shear = np.eye(4)
    shear[0, 1] = 0.5
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    rotation = trimesh.transformations.rotation_matrix(0.7, [1, 2, 3], point=[0.5, 0, 0])
    stretch = np.diag([2.0, 0.5, 3.0, 1.0])
    matrices = [rotation @ mirror, rotation @ shear @ stretch, rotation]
    matrices[0][:3, 3] += [4, 5, 6]
    path = tmp_path / "affine.glb"
    write_box_glb(path, matrices)
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    bodies = load_mesh(path)
    assert len(bodies) == 3
    for body, matrix in zip(bodies, matrices):
        assert is_rigid(body.pose)
        expected = np.asarray(box.vertices) @ matrix[:3, :3].T + matrix[:3, 3]
        got = body.world_vertices()
        assert np.allclose(
            np.unique(np.round(got, 9), axis=0), np.unique(np.round(expected, 9), axis=0)
        )
        assert is_closed(body.faces)
        volume = signed_volume(body.vertices, body.faces)
        assert volume == pytest.approx(6.0 * abs(np.linalg.det(matrix[:3, :3])), rel=1e-9)
    # the pure rotation is kept exactly, nothing baked
    assert np.array_equal(bodies[2].pose, matrices[2])


def test_gltf_with_external_buffer(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(extents=(1, 1, 1)), geom_name="box", node_name="b1")
    scene.add_geometry(
        trimesh.creation.icosphere(subdivisions=1),
        geom_name="ball",
        node_name="b2",
        transform=trimesh.transformations.translation_matrix([3, 0, 0]),
    )
    for name, blob in trimesh.exchange.gltf.export_gltf(scene).items():
        (tmp_path / name).write_bytes(blob)
    bodies = load_mesh(tmp_path / "model.gltf")
    assert [b.name for b in bodies] == ["model/b1", "model/b2"]
    assert np.allclose(bodies[1].pose[:3, 3], [3, 0, 0])
    (tmp_path / "gltf_buffer_0.bin").unlink()
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(tmp_path / "model.gltf")
    assert "not found" in str(info.value)


# --- merging ----------------------------------------------------------------------------------


def test_uv_seams_are_merged(tmp_path):
    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ_WITH_UVS)
    # The native reader reads positions only: UVs and normals never split a vertex
    assert len(load_mesh(path, merge=False)[0].vertices) == 8
    # and a duplicated position (what other exporters write at seams) merges back: the first
    # face uses a second copy of vertex 1, appended as vertex 9
    doubled = re.sub(r"(?m)^f 1(\S*) ", r"f 9\1 ", CUBE_OBJ_WITH_UVS, count=1) + "v 0 0 0\n"
    path.write_text(doubled)
    assert len(load_mesh(path, merge=False)[0].vertices) == 9
    body = load_mesh(path)[0]
    assert len(body.vertices) == 8 and len(body.faces) == 12
    assert is_closed(body.faces)
    assert signed_volume(body.vertices, body.faces) == pytest.approx(1.0)
    assert np.array_equal(body.vertices[0], [0, 0, 0])  # file order kept


def test_merge_vertices_keeps_degenerate_faces():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0], [9, 9, 9]], dtype=float)
    faces = np.array([[0, 1, 3], [0, 1, 2]])
    merged, new_faces = merge_vertices(vertices, faces)
    assert merged.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    assert new_faces.tolist() == [[0, 1, 2], [0, 1, 1]]


@pytest.mark.slow
def test_merge_vertices_of_a_large_soup_numbers_in_first_occurrence_order():
    """A soup of 240,000 corners over 9,000 positions, with unused vertices between them: the
    core's table (presized, probed in prefetched blocks) numbers the merged positions in the
    order of their first use, as a sort-based reference does."""
    rng = np.random.default_rng(4)
    positions = rng.integers(-5000, 5000, size=(9000, 3)) / 1e3 + 0.25e-9  # no rounding ties
    corners = rng.integers(0, 9000, size=240_000)
    vertices = np.vstack([positions[corners], rng.normal(size=(1000, 3)) + 50.0])
    order = rng.permutation(len(vertices))  # the unused 1,000 rows land among the corners
    vertices = vertices[order]
    faces = np.argsort(order)[:240_000].reshape(-1, 3)
    merged, new_faces = merge_vertices(vertices, faces)
    # reference: the used rows in row order, keyed as the core keys them (8 decimals)
    used = np.unique(faces)
    keys = np.rint(vertices[used] * 1e8 - 1e-6)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    remap = np.full(len(vertices), -1)
    remap[used] = rank[inverse.ravel()]
    assert len(merged) == len(np.unique(corners))
    assert np.array_equal(merged, vertices[used][np.sort(first)])
    assert np.array_equal(new_faces, remap[faces])


def test_textured_files_load_without_pillow(corpus, tmp_path):
    # a glTF with a texture (garbage image bytes: never decoded without Pillow)
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)
    indices = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint16)
    blob = positions.tobytes() + uvs.tobytes() + indices.tobytes()
    uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    gltf = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "quad"}],
        "meshes": [
            {
                "primitives": [
                    {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}
                ]
            }
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(b"\x89PNGjunk").decode()}],
        "buffers": [{"byteLength": len(blob), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 4,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            },
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    textured = tmp_path / "textured.gltf"
    textured.write_text(json.dumps(gltf))
    files = [
        corpus / "trimesh-models" / "wallhole.obj",
        corpus / "trimesh-models" / "plane.ply",
        textured,
    ]
    script = textwrap.dedent("""
        import sys
        sys.modules["PIL"] = None  # any `import PIL...` now raises ImportError
        from meshcol.io.mesh_read import load_mesh
        for path in sys.argv[1:]:
            body, = load_mesh(path)
            print(body.name, len(body.vertices), len(body.faces))
        assert sys.modules["PIL"] is None
    """)
    result = subprocess.run(
        [sys.executable, "-c", script, *map(str, files)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:3] == ["wallhole 35 66", "plane 4 2", "textured 4 2"]


# --- awkward meshes that must load -----------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "faces"),
    [
        ("nancolor.obj", 12),
        ("soup.stl", 100),
        ("notenoughindices.obj", 1),
        ("shared.STL", 24),
        ("teapot.stl", 894),
    ],
)
def test_awkward_meshes_load(corpus, name, faces):
    (body,) = load_mesh(corpus / "trimesh-models" / name)
    assert len(body.faces) == faces
    assert np.isfinite(body.vertices).all()


def test_source_is_the_path_as_given(corpus, monkeypatch):
    monkeypatch.chdir(corpus / "trimesh-models")
    assert load_mesh("tet.ply")[0].source == "tet.ply"
    assert load_mesh(Path("tet.ply"))[0].source == "tet.ply"


def test_exported_from_package():
    assert meshcol.load_mesh is load_mesh


# --- bad input ----------------------------------------------------------------------------------

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@pytest.mark.parametrize(
    ("file_name", "content", "error", "message"),
    [
        ("missing.obj", None, InputFileError, "file not found"),
        (
            "mesh.xyz",
            TRIANGLE,
            InputFileError,
            "unknown mesh file extension '.xyz' "
            "(expected .obj, .stl, .ply, .off, .glb, .gltf, .fbx, .dae, .usd, .usda, .usdc, .usdz)",
        ),
        (
            "noext",
            TRIANGLE,
            InputFileError,
            "unknown mesh file extension '(none)' "
            "(expected .obj, .stl, .ply, .off, .glb, .gltf, .fbx, .dae, .usd, .usda, .usdc, .usdz)",
        ),
        ("empty.obj", "", InvalidMeshError, "mesh has no faces"),
        ("points.obj", "v 0 0 0\nv 1 0 0\n", InvalidMeshError, "mesh has no faces"),
        (
            "nan.obj",
            TRIANGLE.replace("v 1 0 0", "v nan 0 0"),
            InvalidMeshError,
            "cannot parse OBJ file: line 2: non-finite vertex coordinate",
        ),
        (
            "inf.obj",
            TRIANGLE.replace("v 1 0 0", "v 1 inf 0"),
            InvalidMeshError,
            "cannot parse OBJ file: line 2: non-finite vertex coordinate",
        ),
        (
            "index.obj",
            TRIANGLE.replace("f 1 2 3", "f 1 2 9"),
            InvalidMeshError,
            "cannot parse OBJ file: line 4: face index 9 but the file has 3 vertices",
        ),
        (
            "text.stl",
            "hello",
            InvalidMeshError,
            "cannot parse STL file: neither binary STL (size does not match the triangle count) "
            "nor ASCII STL (no 'solid' line)",
        ),
        (
            "bad.gltf",
            '{"asset": {"version": "2.0"}, "meshes": [',
            InvalidMeshError,
            "cannot parse GLTF file: invalid JSON at line 1 column 42: Expecting value",
        ),
        (
            "bad.off",
            "OFF\n3 1 0\n0 0 0\n1 0 0\n",
            InvalidMeshError,
            "cannot parse OFF file: line 2: the header announces 3 vertices and 1 faces but only 2 lines follow",
        ),
    ],
)
def test_bad_input(tmp_path, file_name, content, error, message):
    path = tmp_path / file_name
    if content is not None:
        path.write_text(content)
    with pytest.raises(error) as info:
        load_mesh(path)
    assert info.value.message == message
    assert info.value.path == os.fspath(path)
    assert str(info.value) == f"{path}: {message}"
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            b"garbage\x00\x01\x02",
            "cannot parse GLB file: no glTF binary header",
        ),
    ],
)
def test_corrupt_binary_glb(tmp_path, content, message):
    path = tmp_path / "bad.glb"
    path.write_bytes(content)
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == message


def test_truncated_binary_stl(corpus, tmp_path):
    path = tmp_path / "truncated.stl"
    path.write_bytes((corpus / "trimesh-models" / "unit_cube.STL").read_bytes()[:120])
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == (
        "cannot parse STL file: neither binary STL (size does not match the triangle count) "
        "nor ASCII text"
    )


@pytest.mark.parametrize("name", ["empty.obj", "empty.stl"])
def test_corpus_empty_files(corpus, name):
    path = corpus / "trimesh-models" / name
    with pytest.raises(InvalidMeshError, match=r"^.*: mesh has no faces$"):
        load_mesh(path)


def test_directory(tmp_path):
    folder = tmp_path / "folder.obj"
    folder.mkdir()
    with pytest.raises(InputFileError) as info:
        load_mesh(folder)
    assert info.value.message == "is a directory, not a mesh file"


def test_unreadable_file(tmp_path, monkeypatch):
    path = tmp_path / "locked.obj"
    path.write_text(TRIANGLE)
    real_open = open

    def refusing_open(file, *args, **kwargs):
        if os.fspath(file) == os.fspath(path):
            raise PermissionError(13, "Permission denied")
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr("builtins.open", refusing_open)
    with pytest.raises(InputFileError) as info:
        load_mesh(path)
    assert info.value.message == "cannot read file: Permission denied"


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root reads any file")
def test_unreadable_file_by_permissions(tmp_path):
    path = tmp_path / "locked.obj"
    path.write_text(TRIANGLE)
    path.chmod(0)
    with pytest.raises(InputFileError, match="cannot read file: Permission denied"):
        load_mesh(path)


# --- split_rigid ----------------------------------------------------------------------------------


def test_split_rigid_identity_and_rotation_pass_through():
    rigid, linear = split_rigid(np.eye(4))
    assert linear is None and np.array_equal(rigid, np.eye(4))
    rotation = trimesh.transformations.rotation_matrix(1.1, [0, 1, 1], point=[1, 2, 3])
    rigid, linear = split_rigid(rotation)
    assert linear is None and np.array_equal(rigid, rotation)


def test_split_rigid_mirror_goes_into_the_baked_part():
    matrix = trimesh.transformations.rotation_matrix(0.3, [1, 0, 0]) @ np.diag([2, -3, 4, 1])
    rigid, linear = split_rigid(matrix)
    assert is_rigid(rigid)
    assert np.allclose(rigid[:3, :3] @ linear, matrix[:3, :3])
    assert np.allclose(linear, linear.T)
    assert np.linalg.det(linear) == pytest.approx(-24.0)


def test_split_rigid_rejects_zero_scale():
    with pytest.raises(InvalidMeshError, match="singular"):
        split_rigid(np.diag([1.0, 0.0, 1.0, 1.0]))


# --- the native readers against trimesh's -------------------------------------------------------


def _canonical(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Triangles as sorted rows of corner coordinates, each rotated to start at its least corner
    (winding kept): equal for equal geometry whatever the vertex and face order."""
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)].reshape(-1, 3, 3)
    rows = np.arange(len(corners))
    # The first least corner in (x, y, z) order: a corner replaces the best so far only when
    # strictly less, as min() then tuple.index() pick it.
    first = np.zeros(len(corners), dtype=np.intp)
    for k in (1, 2):
        a, b = corners[:, k], corners[rows, first]
        less = (a[:, 0] < b[:, 0]) | (a[:, 0] == b[:, 0]) & (
            (a[:, 1] < b[:, 1]) | (a[:, 1] == b[:, 1]) & (a[:, 2] < b[:, 2])
        )
        first = np.where(less, k, first)
    rotated = corners[rows[:, None], (first[:, None] + np.arange(3)) % 3].reshape(-1, 9)
    # Rows in lexicographic order of their nine coordinates (a stable sort, as sorted()).
    return rotated[np.lexsort(rotated.T[::-1])].reshape(-1, 3, 3)


def _trimesh_geometry(path: Path) -> list[np.ndarray]:
    """The oracle: trimesh's own OBJ/STL readers, each geometry merged as meshcol merges."""
    options: dict = {"process": False}
    if path.suffix.lower() == ".obj":
        has_objects = re.search(rb"^\s*o\s", path.read_bytes(), flags=re.MULTILINE) is not None
        options.update(
            skip_materials=True,
            group_material=False,
            split_objects=True,
            split_groups=not has_objects,
        )
    scene = trimesh.load_scene(str(path), **options)
    out = []
    for node in scene.graph.nodes_geometry:
        _, name = scene.graph[node]
        geometry = scene.geometry[name]
        if getattr(geometry, "faces", None) is None or len(geometry.faces) == 0:
            continue
        out.append(_canonical(*merge_vertices(geometry.vertices, geometry.faces)))
    return sorted(out, key=lambda c: (len(c), c.tobytes()))


def _native_files(root: Path) -> list[Path]:
    return sorted(
        p for p in root.rglob("*") if p.suffix.lower() in (".obj", ".stl") and p.is_file()
    )


def test_native_readers_give_trimeshs_geometry_on_the_corpus_and_samples(corpus):
    compared = 0
    for path in _native_files(corpus) + _native_files(Path(__file__).parents[2] / "samples"):
        try:
            expected = _trimesh_geometry(path)
        except Exception:  # noqa: BLE001 - trimesh cannot read it; meshcol's error tests cover it
            continue
        try:
            bodies = load_mesh(path)
        except InvalidMeshError:
            assert not expected, f"{path}: meshcol refuses a file trimesh reads"
            continue
        got = sorted(
            (_canonical(b.vertices, b.faces) for b in bodies), key=lambda c: (len(c), c.tobytes())
        )
        assert len(got) == len(expected), path
        for g, e in zip(got, expected):
            np.testing.assert_array_equal(g, e, err_msg=str(path))
        compared += 1
    assert compared >= 40


def test_native_obj_reader_rules(tmp_path):
    path = tmp_path / "rules.obj"
    path.write_bytes(
        b"# caf\xe9 au lait: a Latin-1 comment\n"
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv +0.5 0.5 \\\n 1e0\n"
        b"o quad\nf 1/1 2/2 3/3 4/4\n"
        b"o pentagon_relative\nf -5 -4 -3 -2 -1\n"
        b"o line_only\nf 1 2\nl 1 2\n"
    )
    bodies = load_mesh(path)
    assert [b.name for b in bodies] == ["rules/quad", "rules/pentagon_relative"]
    assert len(bodies[0].faces) == 2 and len(bodies[1].faces) == 3
    assert bodies[1].vertices.tolist()[-1] == [0.5, 0.5, 1.0]  # the continued line
    np.testing.assert_allclose(
        _canonical(bodies[0].vertices, bodies[0].faces),
        _canonical(
            np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]), [[0, 1, 2], [0, 2, 3]]
        ),
    )


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: face index 0 (OBJ indices start at 1)"),
        (
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
            "line 4: relative face index -4 but only 3 vertices precede it",
        ),
        (b"v 0 0 0\nv 1 0 0\n\nf 1 2 99\n", "line 4: face index 99 but the file has 2 vertices"),
        (b"v 0 0\nf 1 1 1\n", "line 1: a vertex needs three coordinates"),
        (b"v 0 0 zero\nf 1 1 1\n", "line 1: vertex coordinate 'zero' is not a number"),
        (b"v 0 0 1e999\nf 1 1 1\n", "line 1: vertex coordinate '1e999' is not a number"),
        (b"v 0 0 0\nf 1 x/2 3\n", "line 2: face vertex 'x/2' is not an index"),
        (b"v 0 0 0\nf 1 a 3\n", "line 2: face vertex 'a' is not an index"),
    ],
)
def test_native_obj_reader_errors_name_the_line(tmp_path, content, message):
    path = tmp_path / "bad.obj"
    path.write_bytes(content)
    with pytest.raises(InvalidMeshError) as info:
        load_mesh(path)
    assert info.value.message == f"cannot parse OBJ file: {message}"
    assert info.value.path == str(path)


def test_native_stl_reader(tmp_path):
    ascii_stl = tmp_path / "two.stl"
    facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 {z}\nvertex 1 0 {z}\nvertex 0 1 {z}\nendloop\nendfacet\n"
    ascii_stl.write_text(
        f"solid a\n{facet.format(z=0)}endsolid a\nsolid b\n{facet.format(z=1)}endsolid b\n"
    )
    assert [b.name for b in load_mesh(ascii_stl)] == ["two/a", "two/b"]
    broken = tmp_path / "broken.stl"
    broken.write_text(
        "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"
    )
    with pytest.raises(InvalidMeshError, match=r"line 6: a facet has 2 vertices, not 3"):
        load_mesh(broken)
    binary = tmp_path / "nan.stl"
    record = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, float("nan"), 1, 0, 0)
    binary.write_bytes(b"\0" * 80 + struct.pack("<I", 1) + record)
    with pytest.raises(InvalidMeshError, match="triangle 0 has a non-finite vertex coordinate"):
        load_mesh(binary)


def test_load_meshes_equals_load_mesh_per_file_and_reports_the_first_failure(corpus, tmp_path):
    files = _native_files(corpus / "robots") + sorted((corpus / "trimesh-models").glob("*.ply"))
    files = [f for f in files if f.stat().st_size > 0]
    batched = meshcol.io.mesh_read.load_meshes(files, threads=2)
    assert len(batched) == len(files)
    for path, bodies in zip(files, batched):
        single = load_mesh(path)
        assert [b.name for b in bodies] == [b.name for b in single]
        for a, b in zip(bodies, single):
            np.testing.assert_array_equal(a.vertices, b.vertices)
            np.testing.assert_array_equal(a.faces, b.faces)
    missing = tmp_path / "missing.stl"
    with pytest.raises(InputFileError, match="file not found") as info:
        meshcol.io.mesh_read.load_meshes([files[0], missing, files[1]])
    assert info.value.path == str(missing)
    (tmp_path / "folder.obj").mkdir()
    with pytest.raises(InputFileError, match="is a directory"):
        meshcol.io.mesh_read.load_meshes([tmp_path / "folder.obj"])


def test_load_meshes_plain_scene_pass_builds_what_the_general_loop_builds(tmp_path):
    # Files of one object each take a flat pass; one file of two objects among them sends
    # the whole batch through the general loop: both must build the same bodies.
    rng = np.random.default_rng(7)
    singles = []
    for k, name in enumerate(["a.obj", "b.c.obj", ".hidden.obj", "e.stl"]):
        path = tmp_path / name
        points = rng.normal(size=(6, 3)) + k
        if name.endswith(".stl"):
            trimesh.Trimesh(points, [[0, 1, 2], [2, 3, 4], [4, 5, 0]], process=False).export(path)
        else:
            lines = [f"v {x} {y} {z}" for x, y, z in points] + ["f 1 2 3", "f 3 4 5", "f 5 6 1"]
            path.write_text("\n".join(lines) + "\n")
        singles.append(path)
    two = tmp_path / "two.obj"
    two.write_text(
        "o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no y\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n"
    )
    plain = meshcol.io.mesh_read.load_meshes(singles)
    general = meshcol.io.mesh_read.load_meshes([*singles, two])
    assert [b.name for b in general[-1]] == ["two/x", "two/y"]
    for fast, slow in zip(plain, general[:-1]):
        assert len(fast) == len(slow) == 1
        (a,), (b,) = fast, slow
        assert (a.name, a.source) == (b.name, b.source)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_array_equal(a.pose, np.eye(4))
    assert [b[0].name for b in plain] == ["a", "b.c", ".hidden", "e"]
    assert len({id(b[0].pose) for b in plain}) == len(plain)  # each body its own pose


@pytest.mark.parametrize(
    "source", ["a/b.obj", ".obj", "a/b.tar.obj", "b", "a/.x.obj", "a/b.", "x/..obj", "/x/y.stl"]
)
def test_stem_is_paths_stem(source):
    assert meshcol.io.mesh_read._stem(source) == Path(source).stem


@pytest.mark.slow
@settings(max_examples=40)
@given(
    vertices=arrays(
        np.float64,
        st.tuples(st.integers(3, 30), st.just(3)),
        elements=st.integers(-(10**6), 10**6).map(lambda k: k / 64),
    ),
    data=st.data(),
)
def test_obj_and_stl_round_trip(tmp_path_factory, vertices, data):
    from meshcol.io.mesh_write import write_meshes

    faces = data.draw(
        arrays(
            np.int64,
            st.tuples(st.integers(1, 40), st.just(3)),
            elements=st.integers(0, len(vertices) - 1),
        )
    )
    # On a 1/64 grid (exact in float32, STL's precision) no two distinct coordinates merge.
    folder = tmp_path_factory.mktemp("round")
    expected = _canonical(*merge_vertices(vertices, faces))
    for suffix in (".obj", ".stl"):
        path = folder / f"mesh{suffix}"
        write_meshes(path, [("mesh", vertices, faces)])
        (body,) = load_mesh(path)
        np.testing.assert_array_equal(_canonical(body.vertices, body.faces), expected)
