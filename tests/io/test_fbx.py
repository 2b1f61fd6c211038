"""FBX in: Blender's files read to Blender's own world vertices, every FBX transform against
the FBX SDK's formula, units and axes, parts, the same report as OBJ, and bad files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("ufbx", reason="reading FBX needs ufbx (pip install 'meshcol[fbx]')")

import meshcol
from meshcol.cli import main
from meshcol.io.collision_names import godot_hint
from meshcol.io.fbx import ignored, polygon_triangles, read_fbx
from meshcol.io.scene import load_inputs, load_scene

DATA = Path(__file__).resolve().parents[1] / "data" / "fbx"
FIXTURES = sorted(p.stem for p in DATA.glob("*.fbx"))


def _expected(stem: str) -> dict:
    return json.loads((DATA / f"{stem}.expected.json").read_text())


def _body_name(node: str) -> str:
    """The body name of a Blender object: a Godot hint (``Floor-col``) is cut off."""
    hint = godot_hint(node)
    return node if hint is None else hint.name


def _size(objects: dict) -> float:
    points = np.concatenate([np.asarray(o["vertices"]) for o in objects.values()])
    return float(np.ptp(points, axis=0).max())


def test_the_fixtures_cover_unit_scales_axes_and_hierarchies():
    settings = {stem: _expected(stem) for stem in FIXTURES}
    assert {s["unit_scale"] for s in settings.values()} >= {1.0, 0.25}
    assert {s["options"].get("axis_up", "Y") for s in settings.values()} >= {"Y", "Z", "-Y"}
    assert any(s["options"].get("global_scale") == 4.0 for s in settings.values())
    assert all(s["blender"].startswith("4.") for s in settings.values())
    # binary (Blender's) and ASCII (the same content, scripts/fbx_ascii.py) FBX
    kinds = {(DATA / f"{stem}.fbx").read_bytes()[:18] for stem in FIXTURES}
    assert kinds == {b"Kaydara FBX Binary", b"; FBX 7.4.0 projec"}


@pytest.mark.parametrize("stem", FIXTURES)
def test_vertices_land_where_blender_has_them(stem):
    """Every vertex meshcol reads is Blender's evaluated world vertex (in metres): to 1e-9 of
    the scene's size where the file holds Blender's transform exactly, to Blender's float32
    precision where Blender wrote a float32 rotation (its angles, its axis conversion)."""
    expected = {_body_name(k): v for k, v in _expected(stem)["objects"].items()}
    size = _size(expected)
    bodies = meshcol.load_mesh(DATA / f"{stem}.fbx", merge=False)
    assert sorted(b.name.split("/")[1] for b in bodies) == sorted(expected)
    for body in bodies:
        want = expected[body.name.split("/")[1]]
        got = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
        tolerance = 1e-9 if want["exact"] else 1e-6
        assert np.abs(got - np.asarray(want["vertices"])).max() <= tolerance * size, body.name
        triangles = sum(len(p) - 2 for p in want["polygons"])
        assert len(body.faces) == triangles


def test_exact_fixtures_are_compared_at_1e9():
    """The strict comparison is not vacuous: most objects are exact."""
    exact = [o["exact"] for stem in FIXTURES for o in _expected(stem)["objects"].values()]
    assert sum(exact) >= 30 and not all(exact)


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_units_are_metres_in_the_envelope():
    assert load_inputs([DATA / "level_quarter.fbx"]).units == "m"
    assert load_inputs([DATA / "level.obj"]).units is None
    assert load_inputs([DATA / "level.fbx", DATA / "level.obj"]).units is None
    for command in ("check", "inspect"):
        for jobs in ("1", "2"):  # in this process, and in worker processes
            result = _run(command, DATA / "level.fbx", "--jobs", jobs, "--format", "json")
            # The run's own message when it refused (one make test saw an empty stdout once).
            assert result.exit_code in (0, 1), (command, jobs, result.exit_code, result.output)
            if not isinstance(result.exception, (SystemExit, type(None))):  # CliRunner's catch
                raise result.exception
            report = json.loads(result.stdout)
            assert report["units"] == "m", (command, jobs)
            if command == "inspect":  # what FBX leaves out, noted
                assert len(report["warnings"]) == 1


def _fbx_matrix(translation, rotation, order="XYZ"):
    """The FBX SDK's matrix of a translation and an Euler rotation (degrees) in ``order``:
    the first axis of the order turns first."""
    turns = {axis: _axis_rotation(axis, angle) for axis, angle in zip("XYZ", np.radians(rotation))}
    m = np.eye(4)
    for axis in order:
        m = turns[axis] @ m
    m[:3, 3] = translation
    return m


def _axis_rotation(axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    i, j = {"X": (1, 2), "Y": (2, 0), "Z": (0, 1)}[axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def _translate(v):
    m = np.eye(4)
    m[:3, 3] = v
    return m


def _scale(v):
    return np.diag([*v, 1.0])


#: FBX's RotationOrder enum.
ORDERS = ("XYZ", "XZY", "YZX", "YXZ", "ZXY", "ZYX")


def _local(p):
    """The FBX SDK's local transform (FbxNode docs, "Computing the transformation matrix"):
    T * Roff * Rp * Rpre * R * Rpost^-1 * Rp^-1 * Soff * Sp * S * Sp^-1."""
    rotate = _fbx_matrix((0, 0, 0), p["Lcl Rotation"], ORDERS[p["RotationOrder"]])
    pre = _fbx_matrix((0, 0, 0), p["PreRotation"])
    post = _fbx_matrix((0, 0, 0), p["PostRotation"])
    return (
        _translate(p["Lcl Translation"])
        @ _translate(p["RotationOffset"])
        @ _translate(p["RotationPivot"])
        @ pre
        @ rotate
        @ np.linalg.inv(post)
        @ _translate(-np.asarray(p["RotationPivot"]))
        @ _translate(p["ScalingOffset"])
        @ _translate(p["ScalingPivot"])
        @ _scale(p["Lcl Scaling"])
        @ _translate(-np.asarray(p["ScalingPivot"]))
    )


def _geometric(p):
    return (
        _translate(p["GeometricTranslation"])
        @ _fbx_matrix((0, 0, 0), p["GeometricRotation"])
        @ _scale(p["GeometricScaling"])
    )


PARENT = {
    "Lcl Translation": (10, -20, 5),
    "Lcl Rotation": (15, -40, 70),
    "Lcl Scaling": (2, 2, 2),
    "RotationOrder": 5,
    "PreRotation": (-90, 0, 0),
    "PostRotation": (0, 0, 0),
    "RotationOffset": (0, 0, 0),
    "RotationPivot": (0, 0, 0),
    "ScalingOffset": (0, 0, 0),
    "ScalingPivot": (0, 0, 0),
    "GeometricTranslation": (0, 0, 0),
    "GeometricRotation": (0, 0, 0),
    "GeometricScaling": (1, 1, 1),
}
CHILD = {
    "Lcl Translation": (3, 4, -5),
    "Lcl Rotation": (33, 21, -57),
    "Lcl Scaling": (1.5, 0.5, 3),
    "RotationOrder": 4,
    "PreRotation": (10, 20, 30),
    "PostRotation": (-5, 45, 12),
    "RotationOffset": (1, 2, 3),
    "RotationPivot": (-2, 1, 0.5),
    "ScalingOffset": (0.25, -1, 2),
    "ScalingPivot": (1, 1, -3),
    "GeometricTranslation": (7, 0, -1),
    "GeometricRotation": (0, 90, 30),
    "GeometricScaling": (1, 2, 0.5),
}
CUBE = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)


def _properties(p):
    lines = []
    for name, value in p.items():
        if name == "RotationOrder":
            lines.append(f'P: "RotationOrder", "enum", "", "",{value}')
        else:
            kind = f'"{name}", ""' if "Lcl " in name else '"Vector3D", "Vector"'
            lines.append(f'P: "{name}", {kind}, "A",{",".join(map(str, value))}')
    lines.append('P: "RotationActive", "bool", "", "",1')
    return "\n\t\t\t".join(lines)


def _ascii_fbx(up_axis=1, unit=1.0):
    """An ASCII FBX 7.4 file: a parent node and a child with every transform property, the
    child's mesh a cube with a quad per side."""
    # right-handed: Y up, +Z front, +X right; Z up, -Y front, +X right
    front, front_sign = (2, 1) if up_axis == 1 else (1, -1)
    vertices = ",".join(f"{c:g}" for c in CUBE.reshape(-1))
    quads = "0,1,3,-3,4,6,7,-6,0,4,5,-2,2,3,7,-7,0,2,6,-5,1,5,7,-4"
    return f"""; FBX 7.4.0 project file
FBXHeaderExtension:  {{
\tFBXHeaderVersion: 1003
\tFBXVersion: 7400
}}
GlobalSettings:  {{
\tVersion: 1000
\tProperties70:  {{
\t\tP: "UpAxis", "int", "Integer", "",{up_axis}
\t\tP: "UpAxisSign", "int", "Integer", "",1
\t\tP: "FrontAxis", "int", "Integer", "",{front}
\t\tP: "FrontAxisSign", "int", "Integer", "",{front_sign}
\t\tP: "CoordAxis", "int", "Integer", "",0
\t\tP: "CoordAxisSign", "int", "Integer", "",1
\t\tP: "UnitScaleFactor", "double", "Number", "",{unit!r}
\t}}
}}
Objects:  {{
\tGeometry: 100, "Geometry::Box", "Mesh" {{
\t\tVertices: *24 {{
\t\t\ta: {vertices}
\t\t}}
\t\tPolygonVertexIndex: *24 {{
\t\t\ta: {quads}
\t\t}}
\t}}
\tModel: 200, "Model::Parent", "Null" {{
\t\tProperties70:  {{
\t\t\t{_properties(PARENT)}
\t\t}}
\t}}
\tModel: 300, "Model::Child", "Mesh" {{
\t\tProperties70:  {{
\t\t\t{_properties(CHILD)}
\t\t}}
\t}}
\tMaterial: 400, "Material::Paint", "" {{
\t}}
}}
Connections:  {{
\tC: "OO",200,0
\tC: "OO",300,200
\tC: "OO",100,300
\tC: "OO",400,300
}}
"""


# the file's frame to meshcol's: Y up (+Z front, +X right) -> Z up (-Y front, +X right)
Y_UP_TO_Z_UP = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float)


@pytest.mark.parametrize(("up_axis", "unit"), [(1, 1.0), (2, 100.0), (1, 2.54)])
def test_every_fbx_transform_places_vertices_as_the_sdk_formula(tmp_path, up_axis, unit):
    """Translation, rotation in its order, pre/post rotation, offsets, pivots, scaling and the
    geometric transform, under a rotated and scaled parent, in centimetres, metres or inches,
    Y or Z up: the world vertices are the FBX SDK formula's (an independent oracle here),
    converted to metres and Z up."""
    file = tmp_path / "rig.fbx"
    file.write_text(_ascii_fbx(up_axis, unit))
    (body,) = meshcol.load_mesh(file, merge=False)
    got = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
    world = _local(PARENT) @ _local(CHILD) @ _geometric(CHILD)
    to_meshcol = np.diag([unit / 100] * 3 + [1.0])
    if up_axis == 1:
        to_meshcol = to_meshcol @ Y_UP_TO_Z_UP
    want = (to_meshcol @ world @ np.c_[CUBE, np.ones(8)].T).T[:, :3]
    size = np.ptp(want, axis=0).max()
    assert np.abs(got - want).max() <= 1e-9 * size
    assert len(body.faces) == 12  # six quads, fan-triangulated
    assert load_inputs([file]).units == "m"


def test_a_rotation_order_is_not_ignored(tmp_path):
    """The oracle distinguishes the orders: ZXY and XYZ place the child differently."""
    a = _fbx_matrix((0, 0, 0), CHILD["Lcl Rotation"], "ZXY")
    b = _fbx_matrix((0, 0, 0), CHILD["Lcl Rotation"], "XYZ")
    assert np.abs(a - b).max() > 0.1


def test_materials_cameras_lights_and_animation_are_ignored_with_a_note():
    assert ignored(DATA / "level.fbx", "level.fbx") == [
        "1 material",
        "1 camera",
        "1 light",
        "1 animation stack",
    ]
    names = [b.name for b in meshcol.load_mesh(DATA / "level.fbx")]
    assert "level/Camera" not in names and "level/Sun" not in names
    result = _run("inspect", DATA / "level.fbx", "--format", "json")
    assert result.exit_code == 0
    (note,) = json.loads(result.stdout)["warnings"]
    assert note.endswith(
        ": not read (geometry only): 1 material, 1 camera, 1 light, 1 animation stack"
    )
    assert (
        json.loads(_run("inspect", DATA / "rig_yup.fbx", "--format", "json").stdout)["warnings"]
        == []
    )
    # check says it too, in its report's warnings
    result = _run("check", DATA / "level.fbx", "--format", "json", "--fail-on", "none")
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["warnings"] == [note]


def test_several_mesh_objects_are_the_parts_of_a_manifest_body(tmp_path):
    manifest = tmp_path / "scene.json"
    document = {"bodies": [{"name": "rig", "mesh": str(DATA / "rig_yup.fbx"), "shape": "hull"}]}
    manifest.write_text(json.dumps(document))
    (body,) = load_scene(manifest).bodies
    assert sorted(body.parts) == ["Bin", "Crate", "Shelf"]
    direct = {b.name.split("/")[1]: b for b in meshcol.load_mesh(DATA / "rig_yup.fbx")}
    for name, vertices, _ in body.part_meshes():
        plain = direct[name]
        world = plain.vertices @ plain.pose[:3, :3].T + plain.pose[:3, 3]
        mine = vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
        assert np.allclose(np.sort(mine, axis=0), np.sort(world, axis=0), atol=1e-12)


def _report(path):
    return json.loads(_run("check", path, "--format", "json").stdout)


@pytest.mark.parametrize("other", ["level.obj", "level.glb"])
def test_check_of_the_fbx_is_the_check_of_the_same_scene_in_obj_and_glb(other):
    """Blender's level as FBX, as OBJ (its evaluated world vertices, full precision) and as
    Blender's own GLB: the same pairs (OBJ has no Godot hints: ``Floor-col`` is its name
    there), statuses and
    numbers to 1e-9 of the scene's size (witness points of faces in
    contact are not unique, so the distances stand for them), and the same inspection."""
    fbx, obj = _report(DATA / "level.fbx"), _report(DATA / other)
    size = _size(_expected("level")["objects"])
    for summary in (fbx["summary"], obj["summary"]):
        summary.pop("seconds"), summary.pop("load_seconds")
    assert fbx["summary"] == obj["summary"]
    assert len(fbx["pairs"]) == len(obj["pairs"]) > 0
    for a, b in zip(fbx["pairs"], obj["pairs"]):
        names = (_body_name(b["body_a"]), _body_name(b["body_b"]), b["status"])
        assert (a["body_a"], a["body_b"], a["status"]) == names
        for key in ("signed_distance", "distance", "depth"):
            assert abs(a[key] - b[key]) <= 1e-9 * size, key
    fbx_bodies = json.loads(_run("inspect", DATA / "level.fbx", "--format", "json").stdout)
    obj_bodies = json.loads(_run("inspect", DATA / other, "--format", "json").stdout)
    assert len(fbx_bodies["bodies"]) == len(obj_bodies["bodies"]) == 11
    for a, b in zip(fbx_bodies["bodies"], obj_bodies["bodies"]):
        assert (a["name"], a["faces"]) == (_body_name(b["name"]), b["faces"])
        assert a["watertight"] == b["watertight"]
        assert abs(a["volume"] - b["volume"]) <= 1e-9 * size**3
        assert np.abs(np.subtract(a["bounds"], b["bounds"])).max() <= 1e-9 * size


def test_polygons_are_split_as_off_does_points_and_lines_skipped():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    dart = np.array([[0, 0, 0], [2, 1, 0], [0, 2, 0], [0.5, 1, 0]], dtype=float)  # concave
    vertices = np.vstack([square, dart])
    begin, count = np.array([0, 4, 5, 7]), np.array([4, 1, 2, 4])
    indices = np.array([0, 1, 2, 3, 0, 0, 1, 4, 5, 6, 7])
    triangles = polygon_triangles(vertices, begin, count, indices)
    assert triangles[:2].tolist() == [[0, 1, 2], [0, 2, 3]]  # convex: a fan, as OBJ
    # the dart's two triangles cover its area, none outside it (a fan from 4 would not)
    area = 0.0
    for a, b, c in vertices[triangles[2:]]:
        area += np.linalg.norm(np.cross(b - a, c - a)) / 2
    assert len(triangles) == 4 and area == pytest.approx(1.5)


def _bad_files(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    level = (DATA / "level.fbx").read_bytes()
    files = {}

    def put(name, data, message):
        path = tmp_path / f"{name}.fbx"
        path.write_bytes(data)
        files[name] = (path, message)

    put("truncated", level[:3000], "truncated: record 'GlobalSettings' ends at byte")
    put("garbage", bytes(range(256)) * 4, "not an FBX file")
    put("empty", b"", "empty file")
    put("obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not an FBX file")
    text = _ascii_fbx()
    cyclic = text.replace('C: "OO",200,0', 'C: "OO",200,300')
    put("cyclic", cyclic.encode(), "cyclic node hierarchy")
    at = level.index(b"Vertices") + 9  # the array's element count, then its encoding
    huge = level[:at] + (0xFFFFFFFF).to_bytes(4, "little") + level[at + 4 :]
    put("huge", huge, "out of memory")
    return files


def test_bad_fbx_files_exit_2_with_one_line(tmp_path):
    for name, (path, message) in _bad_files(tmp_path).items():
        for command in ("inspect", "check", "hull"):
            result = _run(command, path)
            assert result.exit_code == 2, (name, command, result.output)
            err = result.stderr.strip()
            assert len(err.splitlines()) == 1, (name, err)
            assert str(path) in err and "cannot parse FBX file" in err, err
            assert message.lower() in err.lower(), (name, err)


def test_read_fbx_returns_parents_before_children():
    names = [node[0] for node in read_fbx(DATA / "rig_yup.fbx", "rig_yup.fbx")]
    assert names.index("Shelf") < names.index("Bin") and len(names) == 3


def test_without_ufbx_the_message_says_what_to_install(monkeypatch):
    from meshcol.io import mesh_formats

    monkeypatch.setattr(mesh_formats.importlib.util, "find_spec", lambda name: None)
    result = _run("inspect", DATA / "level.fbx")
    assert result.exit_code == 2
    assert "reading FBX (.fbx) needs ufbx: pip install 'meshcol[fbx]'" in result.stderr


def test_a_huge_declared_count_allocates_nothing(tmp_path):
    """ASCII arrays are read by their content, never by their declared count."""
    path = tmp_path / "count.fbx"
    path.write_text(_ascii_fbx().replace("Vertices: *24", "Vertices: *99999999999"))
    (body,) = meshcol.load_mesh(path)
    assert len(body.vertices) == 8


@pytest.mark.parametrize(
    "command",
    [
        ("hull", "-o", "{out}/hull.obj"),
        ("fit", "-o", "{out}/fit.obj"),
        ("decompose", "-o", "{out}/parts", "--max-hulls", "2"),
        ("check", "--html", "{out}/review.html"),
    ],
)
def test_every_command_takes_fbx(tmp_path, command):
    name, *options = command
    result = _run(name, DATA / "rig_yup.fbx", *[o.format(out=tmp_path) for o in options])
    assert result.exit_code in (0, 1), result.output
    assert any(tmp_path.iterdir())


def _deep_fbx(depth: int) -> str:
    """The transform test's file with a chain of ``depth`` empty nodes above the parent."""
    text = _ascii_fbx()
    models = "".join(f'\tModel: {1000 + k}, "Model::N{k}", "Null" {{\n\t}}\n' for k in range(depth))
    links = "".join(f'\tC: "OO",{1000 + k},{1000 + k - 1 if k else 0}\n' for k in range(depth))
    text = text.replace("Objects:  {\n", "Objects:  {\n" + models)
    return text.replace('\tC: "OO",200,0\n', links + f'\tC: "OO",200,{1000 + depth - 1}\n')


def test_limits_on_depth_and_corners(tmp_path, monkeypatch):
    from meshcol.io import fbx

    deep = tmp_path / "deep.fbx"
    deep.write_text(_deep_fbx(fbx.MAX_NODE_DEPTH + 10))
    result = _run("inspect", deep)
    assert result.exit_code == 2
    assert "cannot parse FBX file: node depth limit exceeded" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    shallow = tmp_path / "shallow.fbx"
    shallow.write_text(_deep_fbx(20))
    assert len(meshcol.load_mesh(shallow)) == 1
    monkeypatch.setattr(fbx, "MAX_INDICES", 100)
    with pytest.raises(meshcol.errors.InvalidMeshError, match="over 100 polygon-vertex"):
        meshcol.load_mesh(DATA / "level.fbx")


#: Two accesses of one ufbx element and one name dropped, then the other used: with ufbx
#: 0.0.5 alone the object is freed under the remaining name (its bindings hand out the cached
#: object without a new reference).
_TWICE = """
import sys
from pathlib import Path
from meshcol.io.fbx import _kept, _load
keep = _kept if sys.argv[2] == "kept" else (lambda element: element)
file = Path(sys.argv[1])
scene = _load(file, str(file))
first = keep(scene.nodes[1])
again = keep(scene.nodes[1])
del again
churn = [[k] for k in range(200_000)]  # reuse the freed memory, if it was freed
print(first.name)
del first  # the elements before their scene, as read_fbx's extraction drops them
scene.free()
del scene
print("freed")
"""


def test_ufbx_elements_keep_the_reference_ufbx_does_not_add():
    # Workers of the suite segfaulted at random in scene.free() (session 18): each element
    # read through ufbx left its object a reference short, so the element cache the scene's
    # context frees held freed memory. In a child process, since it crashes without _kept.
    import subprocess
    import sys

    run = [sys.executable, "-c", _TWICE, str(DATA / "level.fbx")]
    kept = subprocess.run([*run, "kept"], capture_output=True, text=True, timeout=120)
    assert kept.returncode == 0, kept.stderr
    name, freed = kept.stdout.split()  # the node's name, read after the other was dropped
    assert name and freed == "freed"
    bare = subprocess.run([*run, "bare"], capture_output=True, text=True, timeout=120)
    assert bare.returncode != 0 or bare.stdout != kept.stdout, (
        "ufbx now adds the reference itself: _kept would leak one per access"
    )
