"""Tests for meshcol.scene: manifests, poses, rotations, primitives, load_inputs, errors."""

from __future__ import annotations

import copy
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import meshcol
from meshcol.errors import InputFileError, InvalidMeshError, SceneError
from meshcol.io.scene import (
    SCHEMA_PATH,
    load_inputs,
    load_scene,
    rotation_from_euler,
    rotation_from_quaternion,
)

TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
TWO_TETS = (
    "o left\n"
    + TET
    + "o right\n"
    + "\n".join(
        f"v {2 + float(x)} {y} {z}"
        for x, y, z in (line.split()[1:] for line in TET.splitlines()[:4])
    )
    + "\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n"
)


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "tet.obj").write_text(TET)
    (tmp_path / "pair.obj").write_text(TWO_TETS)
    return tmp_path


def write(folder: Path, document, name: str = "scene.json") -> Path:
    path = folder / name
    path.write_text(document if isinstance(document, str) else json.dumps(document))
    return path


BASE = {
    "units": "mm",
    "duration": 0.5,
    "bodies": [
        {"name": "tet", "mesh": "tet.obj", "position": [1, 2, 3]},
        {"name": "ball", "primitive": {"type": "sphere", "radius": 0.5}},
    ],
}


# --- rotations --------------------------------------------------------------------------------


def test_quaternion_known_rotations():
    assert np.array_equal(rotation_from_quaternion([1, 0, 0, 0]), np.eye(3))
    half = math.sqrt(0.5)
    rz90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    assert np.allclose(rotation_from_quaternion([half, 0, 0, half]), rz90, atol=1e-15)
    # not normalised: same rotation
    assert np.allclose(rotation_from_quaternion([3, 0, 0, 3]), rz90, atol=1e-15)
    # 180 degrees about x
    assert np.allclose(rotation_from_quaternion([0, 1, 0, 0]), np.diag([1, -1, -1]))
    # 120 degrees about (1, 1, 1) permutes the axes x -> y -> z
    turn = rotation_from_quaternion([0.5, 0.5, 0.5, 0.5])
    assert np.allclose(turn, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-15)
    with pytest.raises(ValueError):
        rotation_from_quaternion([0, 0, 0, 0])


def test_euler_extrinsic_known_rotations():
    rx90 = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)
    rz90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=float)
    assert np.array_equal(rotation_from_euler([90, 0, 0], "xyz"), rx90)  # exact at 90 degrees
    assert np.array_equal(rotation_from_euler([0, 0, 90], "xyz"), rz90)
    # extrinsic: first x (about world x), then z (about world z)
    assert np.array_equal(rotation_from_euler([90, 0, 90], "xyz"), rz90 @ rx90)
    assert np.array_equal(rotation_from_euler([90, 90, 0], "zxy"), rx90 @ rz90)
    # proper Euler axes (zxz) and a general angle
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    rz30 = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    assert np.allclose(rotation_from_euler([30, 0, 30], "zxz"), rz30 @ rz30)
    with pytest.raises(ValueError):
        rotation_from_euler([0, 0, 0], "xyw")


def test_euler_matches_scipy_extrinsic():
    from scipy.spatial.transform import Rotation as rotation

    rng = np.random.default_rng(7)
    for order in ("xyz", "zyx", "yzx", "xzx", "zxz"):
        angles = rng.uniform(-180, 180, 3)
        expected = rotation.from_euler(order, angles, degrees=True).as_matrix()
        assert np.allclose(rotation_from_euler(angles, order), expected, atol=1e-14)


def test_quaternion_matches_scipy():
    from scipy.spatial.transform import Rotation as rotation

    rng = np.random.default_rng(3)
    for _ in range(5):
        w, x, y, z = rng.normal(size=4)
        expected = rotation.from_quat([x, y, z, w]).as_matrix()  # scipy is scalar last
        assert np.allclose(rotation_from_quaternion([w, x, y, z]), expected, atol=1e-14)


# --- manifests that load ------------------------------------------------------------------------


def test_manifest_basics(folder):
    scene = load_scene(write(folder, BASE))
    assert scene.units == "mm" and scene.duration == 0.5
    assert scene.source == os.fspath(folder / "scene.json")
    tet, ball = scene.bodies
    assert tet.name == "tet" and tet.source == os.path.join(folder, "tet.obj")
    assert np.array_equal(tet.pose[:3, 3], [1, 2, 3])
    assert tet.end_pose is None and tet.primitive is None
    assert ball.primitive == meshcol.Sphere(0.5)
    assert np.linalg.norm(ball.vertices, axis=1) == pytest.approx(0.5)


def test_mesh_path_relative_to_manifest_and_source_as_given(folder, monkeypatch):
    (folder / "sub").mkdir()
    write(folder / "sub", {"bodies": [{"name": "t", "mesh": "../tet.obj"}]})
    monkeypatch.chdir(folder)
    scene = load_scene("sub/scene.json")
    assert scene.source == "sub/scene.json"
    assert scene.bodies[0].source == os.path.join("sub", "../tet.obj")
    assert scene.units is None and scene.duration is None


def test_pose_scale_and_rotation(folder):
    document = {
        "bodies": [
            {
                "name": "t",
                "mesh": "tet.obj",
                "position": [1, 0, 0],
                "scale": [2, 3, 4],
                "rotation": {"euler_deg": [0, 0, 90], "order": "xyz"},
            }
        ]
    }
    (body,) = load_scene(write(folder, document)).bodies
    assert np.array_equal(body.vertices.max(axis=0), [2, 3, 4])  # scale baked in
    rz90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=float)
    assert np.array_equal(body.pose[:3, :3], rz90)
    assert np.allclose(body.world_vertices()[1], [1, 2, 0])  # (2, 0, 0) turned to +y, moved


def test_multibody_mesh_gives_one_body_of_named_parts(folder):
    document = {
        "bodies": [
            {
                "name": "pair",
                "mesh": "pair.obj",
                "scale": 2,
                "position": [0, 0, 10],
                "shape": "hull",
            }
        ]
    }
    (body,) = load_scene(write(folder, document)).bodies
    assert body.name == "pair" and body.parts == ("left", "right")
    assert body.collider == "hull"
    (left_name, left_v, left_f), (right_name, right_v, right_f) = body.part_meshes()
    assert (left_name, right_name) == ("left", "right")
    assert np.allclose(right_v.min(axis=0) + [0, 0, 10], [4, 0, 10])
    assert len(left_f) + len(right_f) == len(body.faces)
    # the parts' world vertices are those of the file, scaled and placed
    plain = {b.name.split("/")[1]: b for b in meshcol.load_mesh(folder / "pair.obj")}
    assert np.allclose(np.sort(right_v, axis=0), np.sort(2 * plain["right"].vertices, axis=0))


def test_glb_parts_keep_their_node_transforms(corpus, tmp_path):
    nested = corpus / "trimesh-models" / "nested.glb"
    document = {
        "bodies": [
            {
                "name": "n",
                "mesh": os.fspath(nested),
                "scale": 2,
                "position": [1, 0, 0],
                "rotation": {"quaternion": [0.5, 0.5, 0.5, 0.5]},
            }
        ]
    }
    (body,) = load_scene(write(tmp_path, document)).bodies
    direct = meshcol.load_mesh(nested)
    assert body.parts == tuple(plain.name.split("/")[1] for plain in direct)
    turn = rotation_from_quaternion([0.5, 0.5, 0.5, 0.5])
    r = body.pose[:3, :3]
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(r), 1)
    world = body.world_vertices()
    for k, plain in enumerate(direct):
        faces = body.faces[body.part_faces[k] : body.part_faces[k + 1]]
        expected = 2 * plain.world_vertices() @ turn.T + [1, 0, 0]
        assert np.allclose(world[faces], expected[plain.faces], atol=1e-12)


def test_end_pose_from_end_position_and_rotation(folder):
    document = {
        "bodies": [
            {
                "name": "t",
                "mesh": "tet.obj",
                "position": [0, 0, 0],
                "end_position": [5, 0, 0],
                "end_rotation": {"quaternion": [0, 0, 0, 1]},
            }
        ]
    }
    (body,) = load_scene(write(folder, document)).bodies
    assert np.array_equal(body.pose, np.eye(4))
    expected = np.diag([-1.0, -1.0, 1.0, 1.0])  # half turn about z
    expected[0, 3] = 5.0
    assert np.allclose(body.end_pose, expected, atol=1e-15)


def test_end_pose_from_velocities(folder):
    document = {
        "duration": 0.5,
        "bodies": [
            {
                "name": "t",
                "mesh": "tet.obj",
                "position": [1, 0, 0],
                "rotation": {"euler_deg": [90, 0, 0], "order": "xyz"},
                "velocity": [2, 0, 0],
                "angular_velocity": [0, 0, math.pi],
            }
        ],
    }
    (body,) = load_scene(write(folder, document)).bodies
    assert np.allclose(body.end_pose[:3, 3], [2, 0, 0])
    # a quarter turn about world z after the start rotation (angular velocity in world frame)
    expected = rotation_from_euler([90, 0, 90], "xyz")
    assert np.allclose(body.end_pose[:3, :3], expected, atol=1e-15)
    only_linear = {
        "duration": 2.0,
        "bodies": [{"name": "t", "mesh": "tet.obj", "velocity": [0, 1, 0]}],
    }
    (body,) = load_scene(write(folder, only_linear)).bodies
    expected = np.eye(4)
    expected[1, 3] = 2.0
    assert np.array_equal(body.end_pose, expected)


@pytest.mark.parametrize(
    ("primitive", "scale", "expected", "extent"),
    [
        (
            {"type": "sphere", "radius": 1.5},
            None,
            meshcol.Sphere(1.5),
            [3, 3, 3],
        ),
        (
            {"type": "box", "size": [1, 2, 3]},
            [2, 1, 1],
            meshcol.Box((2.0, 2.0, 3.0)),
            [2, 2, 3],
        ),
        (
            {"type": "capsule", "radius": 0.5, "length": 2},
            2,
            meshcol.Capsule(1.0, 4.0),
            [2, 2, 6],
        ),
        (
            {"type": "cylinder", "radius": 0.5, "length": 2},
            None,
            meshcol.Cylinder(0.5, 2.0),
            [1, 1, 2],
        ),
        (  # along its axis: still a cylinder, exactly
            {"type": "cylinder", "radius": 0.5, "length": 2},
            [3, 3, 0.5],
            meshcol.Cylinder(1.5, 1.0),
            [3, 3, 1],
        ),
    ],
)
def test_primitives(folder, primitive, scale, expected, extent):
    spec = {"name": "p", "primitive": primitive}
    if scale is not None:
        spec["scale"] = scale
    (body,) = load_scene(write(folder, {"bodies": [spec]})).bodies
    assert body.primitive == expected
    assert np.allclose(body.vertices.max(axis=0) - body.vertices.min(axis=0), extent)
    assert np.allclose(body.vertices.max(axis=0), -body.vertices.min(axis=0))  # centred


def test_toml_manifest(folder):
    text = """
units = "m"
duration = 1.0

[[bodies]]
name = "tet"
mesh = "tet.obj"
position = [1.0, 2.0, 3.0]
rotation = { quaternion = [1, 0, 0, 0] }

[[bodies]]
name = "box"
primitive = { type = "box", size = [1, 1, 1] }
velocity = [0, 0, -1]
"""
    scene = load_scene(write(folder, text, "scene.toml"))
    assert scene.units == "m" and [b.name for b in scene.bodies] == ["tet", "box"]
    assert np.allclose(scene.bodies[1].end_pose[:3, 3], [0, 0, -1])


def test_samples_manifests_validate_against_the_published_schema(samples):
    import jsonschema

    schema = json.loads(SCHEMA_PATH.read_text())
    jsonschema.validators.validator_for(schema).check_schema(schema)
    for manifest in samples.glob("*/scene.json"):
        jsonschema.validate(json.loads(manifest.read_text()), schema)


def test_schema_documents_every_field():
    schema = json.loads(SCHEMA_PATH.read_text())
    body = schema["properties"]["bodies"]["items"]
    for name, field in [*schema["properties"].items(), *body["properties"].items()]:
        assert field.get("description"), name
    assert "EXTRINSIC" in body["properties"]["rotation"]["description"]


# --- manifest errors ------------------------------------------------------------------------------


def edit(change):
    document = copy.deepcopy(BASE)
    change(document)
    return document


TET_BODY = 0
BALL_BODY = 1
CAPSULE = {"type": "capsule", "radius": 1, "length": 2}
CYLINDER = {"type": "cylinder", "radius": 1, "length": 2}
EGG = {"type": "ellipsoid", "semi_axes": [1, 2, 3]}


def body(index, **fields):
    def change(document):
        document["bodies"][index].update(fields)

    return change


def drop(index, field):
    def change(document):
        del document["bodies"][index][field]

    return change


@pytest.mark.parametrize(
    ("document", "message"),
    [
        (edit(body(TET_BODY, postion=[1, 2, 3])), "body 'tet': unknown field 'postion'"),
        (
            edit(body(TET_BODY, position=[1, 2])),
            "body 'tet': position must be an array of 3 numbers",
        ),
        (edit(body(TET_BODY, position="up")), "body 'tet': position must be an array of 3 numbers"),
        (
            edit(body(TET_BODY, position=[1, "2", 3])),
            "body 'tet': position must be an array of 3 numbers",
        ),
        (edit(body(TET_BODY, mesh="missing.obj")), "body 'tet': mesh file 'missing.obj' not found"),
        (edit(drop(TET_BODY, "name")), "bodies[0]: missing field 'name'"),
        (edit(drop(TET_BODY, "mesh")), "body 'tet': needs exactly one of 'mesh' or 'primitive'"),
        (
            edit(body(TET_BODY, primitive={"type": "sphere", "radius": 1})),
            "body 'tet': needs exactly one of 'mesh' or 'primitive'",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "sphere", "radius": 1, "size": [1, 1, 1]})),
            "body 'ball': unknown field 'primitive.size'",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "cone", "radius": 1})),
            "body 'ball': primitive.type must be one of sphere, box, capsule, cylinder, ellipsoid",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "capsule", "radius": 1})),
            "body 'ball': missing field 'primitive.length'",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "sphere", "radius": -1})),
            "body 'ball': primitive.radius must be a positive number",
        ),
        (
            edit(body(BALL_BODY, primitive=CAPSULE, scale=[1, 2, 1])),
            "body 'ball': a capsule takes a uniform scale only",
        ),
        (
            edit(body(BALL_BODY, primitive=CYLINDER, scale=[1, 2, 1])),
            "body 'ball': a cylinder takes the same scale in x and y only",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "ellipsoid", "semi_axes": [1, 0, 1]})),
            "body 'ball': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "ellipsoid", "semi_axes": [1, -2, 1]})),
            "body 'ball': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "ellipsoid", "semi_axes": [1, 2]})),
            "body 'ball': primitive.semi_axes must be an array of 3 positive numbers",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "ellipsoid"})),
            "body 'ball': missing field 'primitive.semi_axes'",
        ),
        (
            edit(body(BALL_BODY, primitive={"type": "ellipsoid", "radius": 1})),
            "body 'ball': unknown field 'primitive.radius'",
        ),
        (
            edit(body(BALL_BODY, primitive={**EGG, "size": [1, 1, 1]})),
            "body 'ball': unknown field 'primitive.size'",
        ),
        (
            edit(body(TET_BODY, rotation={"quaternion": [0, 0, 0, 0]})),
            "body 'tet': rotation.quaternion must be non-zero",
        ),
        (
            edit(body(TET_BODY, rotation={"quaternion": [1, 0, 0]})),
            "body 'tet': rotation.quaternion must be an array of 4 numbers [w, x, y, z]",
        ),
        (
            edit(body(TET_BODY, rotation={"euler_deg": [0, 0, 0]})),
            "body 'tet': missing field 'rotation.order'",
        ),
        (
            edit(body(TET_BODY, rotation={"euler_deg": [0, 0, 0], "order": "XYZ"})),
            "body 'tet': rotation.order must be a string of three axes such as xyz, zyx or zxz",
        ),
        (
            edit(body(TET_BODY, end_rotation={"angles": [0, 0, 0]})),
            "body 'tet': end_rotation must be {\"quaternion\": [w, x, y, z]} or "
            '{"euler_deg": [a, b, c], "order": "xyz"}',
        ),
        (
            edit(body(TET_BODY, scale=0)),
            "body 'tet': scale must be a positive number or an array of 3 positive numbers",
        ),
        (
            edit(body(TET_BODY, shape="convex")),
            "body 'tet': shape must be one of hull, decomposed, mesh",
        ),
        (edit(body(BALL_BODY, name="tet")), "body 'tet': name used by an earlier body"),
        (
            edit(body(TET_BODY, velocity=[1, 0, 0], end_position=[1, 0, 0])),
            "body 'tet': give the end pose either as end_position/end_rotation or as "
            "velocity/angular_velocity, not both",
        ),
        (
            edit(lambda d: (d.pop("duration"), d["bodies"][0].update(angular_velocity=[0, 0, 1]))),
            "body 'tet': angular_velocity needs the manifest's 'duration'",
        ),
        (edit(lambda d: d.update(unit="m")), "unknown field 'unit'"),
        (edit(lambda d: d.update(units=3)), "units must be a non-empty string"),
        (edit(lambda d: d.update(duration=-1)), "duration must be a positive number (seconds)"),
        (edit(lambda d: d.pop("bodies")), "missing field 'bodies'"),
        (edit(lambda d: d.update(bodies=[])), "bodies must be a non-empty array of bodies"),
        (edit(lambda d: d.update(bodies=[3])), "bodies[0] must be an object (a table in TOML)"),
        (
            edit(lambda d: d["bodies"].append({"name": 7, "mesh": "tet.obj"})),
            "bodies[2]: name must be a non-empty string",
        ),
        ([], "manifest must be an object (a table in TOML)"),
        (
            '{"units": "m",\n "bodies": [\n  {"name": "a",\n      "mesh" "x"}]}',
            "invalid JSON at line 4 column 14: Expecting ':' delimiter",
        ),
        (
            '{"bodies": [{"name": "a", "position": [NaN, 0, 0], "mesh": "tet.obj"}]}',
            "body 'a': position must be finite",
        ),
        (
            '{"bodies": [{"name": "a", "mesh": "bad.foo"}]}',
            "body 'a': mesh file 'bad.foo' not found",
        ),
    ],
)
def test_manifest_errors(folder, document, message):
    path = write(folder, document)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert str(info.value) == f"{path}: {message}"
    assert info.value.path == os.fspath(path)


def test_broken_mesh_in_manifest(folder):
    (folder / "empty.obj").write_text("")
    (folder / "bad.foo").write_text("x")
    path = write(folder, {"bodies": [{"name": "e", "mesh": "empty.obj"}]})
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.message == "body 'e': mesh file 'empty.obj': mesh has no faces"
    path = write(folder, {"bodies": [{"name": "f", "mesh": "bad.foo"}]})
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.message == (
        "body 'f': mesh file 'bad.foo': unknown mesh file extension '.foo' "
        "(expected .obj, .stl, .ply, .off, .glb, .gltf, .fbx, .dae, .usd, .usda, .usdc, .usdz)"
    )


def test_part_names_do_not_clash_with_body_names(folder):
    document = {
        "bodies": [{"name": "pair/left", "mesh": "tet.obj"}, {"name": "pair", "mesh": "pair.obj"}]
    }
    bodies = load_scene(write(folder, document)).bodies
    assert [(b.name, b.parts) for b in bodies] == [("pair/left", ()), ("pair", ("left", "right"))]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            'units = "m"\n[[bodies]]\nname = "a"\nmesh = tet.obj\n',
            "invalid TOML: Invalid value (at line 4, column 8)",
        ),
        (
            '[[bodies]]\nname = "a"\nmesh = "tet.obj"\nposition = [1.0, 2.0, inf]\n',
            "body 'a': position must be finite",
        ),
        (
            '[[bodies]]\nname = "a"\nmesh = "tet.obj"\nposition = [1.0, 2.0]\n',
            "body 'a': position must be an array of 3 numbers",
        ),
    ],
)
def test_toml_errors(folder, text, message):
    path = write(folder, text, "scene.toml")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.message == message


def test_manifest_file_errors(tmp_path):
    with pytest.raises(InputFileError, match="file not found"):
        load_scene(tmp_path / "nope.json")
    with pytest.raises(InputFileError, match="is a directory, not a scene manifest"):
        (tmp_path / "dir.json").mkdir()
        load_scene(tmp_path / "dir.json")
    (tmp_path / "scene.yaml").write_text("bodies: []")
    with pytest.raises(InputFileError) as info:
        load_scene(tmp_path / "scene.yaml")
    assert info.value.message == "unknown scene manifest extension '.yaml' (expected .json, .toml)"


# --- load_inputs -------------------------------------------------------------------------------------


def test_load_inputs_manifest_alone(folder):
    scene = load_inputs([write(folder, BASE)])
    assert [b.name for b in scene.bodies] == ["tet", "ball"] and scene.units == "mm"


def test_load_inputs_mesh_files(folder, corpus):
    (folder / "other").mkdir()
    (folder / "other" / "tet.obj").write_text(TET)
    pins = corpus / "trimesh-models" / "pins.glb"
    scene = load_inputs(
        [folder / "tet.obj", folder / "pair.obj", pins, folder / "other" / "tet.obj"]
    )
    names = [b.name for b in scene.bodies]
    assert names[:3] == ["tet", "pair/left", "pair/right"]
    assert len(names) == 11 and names[-1] == "tet#2"
    assert len(set(names)) == len(names)
    assert scene.units is None and scene.source is None
    assert scene.bodies[-1].source == os.fspath(folder / "other" / "tet.obj")
    single = load_inputs([str(pins)])
    assert single.source == str(pins) and len(single.bodies) == 7


def test_load_inputs_errors(folder):
    with pytest.raises(InputFileError, match=r"^no input files given$"):
        load_inputs([])
    manifest = write(folder, BASE)
    with pytest.raises(SceneError) as info:
        load_inputs([folder / "tet.obj", manifest])
    assert str(info.value) == (
        f"{manifest}: a scene manifest cannot be combined with other inputs: give it alone"
    )
    with pytest.raises(InputFileError, match="file not found"):
        load_inputs([folder / "tet.obj", folder / "missing.stl"])
    (folder / "empty.stl").write_text("solid e\nendsolid e\n")
    with pytest.raises(InvalidMeshError, match="mesh has no faces"):
        load_inputs([folder / "empty.stl"])


def test_exported_from_package():
    assert meshcol.load_scene is load_scene and meshcol.load_inputs is load_inputs
