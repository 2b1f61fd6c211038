"""COLLADA (.dae) as a command input (meshcol/io/dae.py): the unit's scale against the same
geometry in metres, nodes as bodies, the loader's one-line errors on hostile files (entity
bombs, external entities, zip archives, instance bombs), and a robot whose collision mesh is
in centimetres. Documents come from tests/dae_files.py's template.
"""

from __future__ import annotations

import io
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from dae_files import document, geometry, instance, node, placed_cube

from meshcol.cli import main
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import oriented_volume
from meshcol.io import dae
from meshcol.io.mesh_read import load_mesh

pytest.importorskip("collada", reason="COLLADA needs pycollada (pip install 'meshcol[robots]')")


def write(folder: Path, name: str, text: str | bytes) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


def world(bodies) -> np.ndarray:
    return np.concatenate([b.vertices @ b.pose[:3, :3].T + b.pose[:3, 3] for b in bodies])


def inspect_error(path: Path) -> str:
    """``meshcol inspect PATH``'s one error line, after checking it is a clean exit 2."""
    result = CliRunner().invoke(main, ["inspect", str(path)])
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"meshcol: error: {path}: "), lines[0]
    return lines[0].split(f"{path}: ", 1)[1]


# --- the unit ----------------------------------------------------------------------------


@pytest.mark.parametrize("meter", ["0.01", "0.0254", "1000"])
def test_the_unit_scales_vertices_and_translations_exactly(tmp_path, meter):
    reference = load_mesh(write(tmp_path, "m.dae", placed_cube()))[0]
    scaled = load_mesh(write(tmp_path, "u.dae", placed_cube(meter)))[0]
    factor = float(meter)
    # one multiplication per coordinate: the exact product of the metre reading
    np.testing.assert_array_equal(scaled.vertices, reference.vertices * factor)
    np.testing.assert_array_equal(scaled.pose[:3, 3], reference.pose[:3, 3] * factor)
    np.testing.assert_array_equal(scaled.pose[:3, :3], reference.pose[:3, :3])
    # and the metre reading is the file's: a cube of half side 50 at (10, 20, 30), turned
    np.testing.assert_allclose(reference.pose[:3, 3], [10, 20, 30])
    # pycollada reads single precision, as assimp (RViz) does: cos 90 degrees is -4.4e-8
    turn = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    np.testing.assert_allclose(reference.pose[:3, :3], turn, atol=1e-7)
    np.testing.assert_allclose(np.ptp(world([scaled]), axis=0), [100 * factor] * 3, rtol=1e-12)


def test_no_unit_is_metres_and_one_metre_changes_nothing(tmp_path):
    plain = load_mesh(write(tmp_path, "a.dae", placed_cube()))[0]
    metre = load_mesh(write(tmp_path, "b.dae", placed_cube("1")))[0]
    np.testing.assert_array_equal(plain.vertices, metre.vertices)
    np.testing.assert_array_equal(plain.pose, metre.pose)


def test_up_axis_is_not_applied_as_rviz(tmp_path):
    z_up = world(load_mesh(write(tmp_path, "z.dae", placed_cube(up_axis="Z_UP"))))
    y_up = world(load_mesh(write(tmp_path, "y.dae", placed_cube(up_axis="Y_UP"))))
    x_up = world(load_mesh(write(tmp_path, "x.dae", placed_cube(up_axis="X_UP"))))
    np.testing.assert_array_equal(z_up, y_up)
    np.testing.assert_array_equal(z_up, x_up)
    header = dae.read_header((tmp_path / "y.dae").read_bytes(), "y.dae")
    assert header == dae.DaeHeader(meter=1.0, up_axis="Y_UP")  # read, and left unapplied


def test_reports_say_metres(tmp_path):
    import json

    path = write(tmp_path, "cm.dae", placed_cube("0.01"))
    result = CliRunner().invoke(main, ["inspect", str(path), "--format", "json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["units"] == "m"
    (body,) = report["bodies"]
    assert body["size"] == pytest.approx([1.0, 1.0, 1.0], rel=1e-12)
    assert body["declared_units"] == "m" and body["units_guess"] == "m"


@pytest.mark.parametrize("meter", ["0", "-0.01", "nan", "inf", "-inf", "one", ""])
def test_a_unit_that_is_not_a_length_is_one_line(tmp_path, meter):
    path = write(tmp_path, "bad.dae", placed_cube(meter))
    assert inspect_error(path) == (
        f"cannot parse DAE file: <unit meter={meter!r}> is not a positive finite length"
    )


def test_without_pycollada_the_command_says_how_to_install_it(tmp_path, monkeypatch):
    from meshcol.io import mesh_formats

    path = write(tmp_path, "arm.dae", placed_cube())
    monkeypatch.setattr(mesh_formats.importlib.util, "find_spec", lambda name: None)
    assert inspect_error(path) == (
        "reading COLLADA (.dae) needs pycollada: pip install 'meshcol[robots]'"
    )


# --- nodes and primitives ----------------------------------------------------------------


@pytest.mark.parametrize("primitive", ["triangles", "polylist", "polygons"])
def test_every_polygon_primitive_is_the_same_closed_cube(tmp_path, primitive):
    text = document(node("box", instance("cube")), geometry("cube", 0.5, primitive))
    (body,) = load_mesh(write(tmp_path, f"{primitive}.dae", text))
    assert body.name == primitive and len(body.faces) == 12 and len(body.vertices) == 8
    assert oriented_volume(body.vertices, body.faces) == (pytest.approx(1.0, abs=1e-12), 1)


def test_nodes_are_bodies_named_by_node_unique_and_stable(tmp_path):
    geometries = geometry("cube", 0.5) + geometry("edges", 0.5, "lines")
    nodes = (
        node("arm", instance("cube"), "<translate>0 0 1</translate>")
        + node("arm", instance("cube"), "<translate>0 0 2</translate>")
        + node(None, instance("cube"), "<translate>0 0 3</translate>", node_id="only_id")
        # a node of no geometry whose child has some, two geometries in one node, lines alone
        + node("base", node("tip", instance("cube")), "<translate>5 0 0</translate>")
        + node("pair", instance("cube") + instance("cube"))
        + node("wire", instance("edges"))
    )
    path = write(tmp_path, "robot.dae", document(nodes, geometries))
    bodies = load_mesh(path)
    names = [b.name for b in bodies]
    assert names == ["robot/arm", "robot/arm#2", "robot/only_id", "robot/tip", "robot/pair"]
    assert names == [b.name for b in load_mesh(path)]
    np.testing.assert_allclose([b.pose[2, 3] for b in bodies[:3]], [1, 2, 3])
    np.testing.assert_allclose(bodies[3].pose[:3, 3], [5, 0, 0])  # the parent's transform
    assert len(bodies[4].faces) == 24  # both geometries, one body


def test_instance_node_places_a_library_node_each_time(tmp_path):
    library = node("part", instance("cube"), node_id="part")
    nodes = node("left", '<instance_node url="#part"/>', "<translate>-2 0 0</translate>") + node(
        "right", '<instance_node url="#part"/>', "<translate>2 0 0</translate>"
    )
    text = document(nodes, geometry("cube", 0.5), library_nodes=library)
    bodies = load_mesh(write(tmp_path, "two.dae", text))
    # one library node instanced under two nodes: named by the instancing node
    assert [b.name for b in bodies] == ["two/left/part", "two/right/part"]
    np.testing.assert_allclose([b.pose[0, 3] for b in bodies], [-2, 2])


def test_a_missing_material_keeps_the_geometry(tmp_path):
    # Blender wrote anymal_foot.dae so: pycollada drops an instance_geometry whose material
    # is not in the library, RViz (assimp) shows it
    text = document(node("foot", instance("cube", material="absent")), geometry("cube", 0.5))
    (body,) = load_mesh(write(tmp_path, "foot.dae", text))
    assert len(body.faces) == 12


# --- bad and hostile files ---------------------------------------------------------------

_LAUGHS = (
    '<?xml version="1.0"?>\n<!DOCTYPE COLLADA [\n<!ENTITY l0 "lol">\n'
    + "".join(f'<!ENTITY l{k} "{f"&l{k - 1};" * 10}">\n' for k in range(1, 10))
    + "]>\n"
)


def _bomb() -> str:
    """A billion laughs: 10^9 bytes from 1 kB, in a node's name."""
    return _LAUGHS + document(node("&l9;", instance("cube")), geometry("cube", 0.5), prolog="")


def _external(secret: Path) -> str:
    prolog = f'<?xml version="1.0"?>\n<!DOCTYPE COLLADA [<!ENTITY x SYSTEM "file://{secret}">]>\n'
    return prolog + document(node("&x;", instance("cube")), geometry("cube", 0.5), prolog="")


_DOCTYPE = (
    "cannot parse DAE file: a DOCTYPE is not read (entity declarations could expand or read files)"
)


@pytest.mark.parametrize("encoding", ["utf-8", "utf-16"])
def test_an_entity_bomb_is_refused_before_it_is_parsed(tmp_path, monkeypatch, encoding):
    text = _bomb()
    if encoding == "utf-16":  # the scan reads the document's own encoding
        text = text.replace('<?xml version="1.0"?>', '<?xml version="1.0" encoding="utf-16"?>')
    path = write(tmp_path, "bomb.dae", text.encode(encoding))
    assert inspect_error(path) == _DOCTYPE

    def never(*args):
        raise AssertionError("the document reached pycollada")

    monkeypatch.setattr(dae, "_document", never)
    with pytest.raises(InvalidMeshError, match="DOCTYPE"):
        load_mesh(path)  # modules imported, caches warm: what follows is the read alone
    tracemalloc.start()
    with pytest.raises(InvalidMeshError, match="DOCTYPE"):
        load_mesh(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    # the guarded read's 1 MiB buffer and little else: the laughs expanded are 1 GB, their
    # second-last layer 100 MB
    assert peak < 4_000_000


def test_an_external_entity_reads_no_file(tmp_path):
    secret = write(tmp_path, "secret.txt", "password-42")
    result = CliRunner().invoke(main, ["inspect", str(write(tmp_path, "x.dae", _external(secret)))])
    assert result.exit_code == 2 and "password-42" not in result.output
    assert inspect_error(tmp_path / "x.dae") == _DOCTYPE


def _zipped() -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("model.dae", placed_cube())
    return buffer.getvalue()


def _deep(levels: int) -> str:
    inner = instance("cube")
    for k in range(levels):
        inner = node(f"n{k}", inner)
    return document(inner, geometry("cube", 0.5))


@pytest.mark.parametrize(
    "content, message",
    [
        (b"", "cannot parse DAE file: XML: no element found (line 1)"),
        (placed_cube()[:130].encode(), "cannot parse DAE file: XML: unclosed token (line 3)"),
        (
            placed_cube()[:-400].encode(),
            "cannot parse DAE file: XML Parsing Error: Premature end of data in tag p line 4, "
            "line 4, column 647 (<string>, line 4)",
        ),
        (
            b"\x00\x01binary noise",
            "cannot parse DAE file: XML: not well-formed (invalid token) (line 1)",
        ),
        (b"<mesh><v/></mesh>", "cannot parse DAE file: the root element is <mesh>, not <COLLADA>"),
        (
            _zipped(),
            "cannot parse DAE file: a zip archive (zipped COLLADA is not read; unzip the .dae)",
        ),
        (document("", "").encode(), "mesh has no faces"),
        (
            document(node("wire", instance("e")), geometry("e", 1, "lines")).encode(),
            "mesh has no faces",
        ),
        (
            document(node("ghost", instance("missing")), "").encode(),
            "cannot parse DAE file: Geometry #missing not found in library",
        ),
        (
            document(node("ghost", '<instance_node url="#missing"/>'), "").encode(),
            "cannot parse DAE file: Node #missing not found in library",
        ),
        (
            placed_cube().replace("-50.0", "nan", 1).encode(),
            "mesh has non-finite vertex coordinates",
        ),
        (
            placed_cube().replace("<p>0 1 3", "<p>0 1 9", 1).encode(),
            "cannot parse DAE file: Indexes (maxindex=9) for source 'cube-pos' (len=8) go beyond the limits of the source",
        ),
        (
            _deep(3000).encode(),
            "cannot parse DAE file: XML Parsing Error: Excessive depth in document: 2048, use XML_PARSE_HUGE option, line 6, column 38876 (<string>, line 6)",
        ),
        (_deep(1000).encode(), "cannot parse DAE file: elements nested too deeply"),
    ],
    ids=[
        "empty",
        "cut-in-asset",
        "truncated",
        "binary",
        "not-collada",
        "zip",
        "no-scene",
        "lines-only",
        "missing-geometry",
        "missing-node",
        "nan",
        "index-out-of-range",
        "too-deep",
        "deeper-than-python",
    ],
)
def test_a_bad_dae_is_one_line_naming_the_file(tmp_path, content, message):
    assert inspect_error(write(tmp_path, "bad.dae", content)) == message


def test_an_instance_bomb_stops_at_the_node_limit(tmp_path, monkeypatch):
    # each node instances the one before twice: 2^40 cubes from 40 lines
    library = node("n0", instance("cube"), node_id="n0") + "".join(
        node(f"n{k}", f'<instance_node url="#n{k - 1}"/>' * 2, node_id=f"n{k}")
        for k in range(1, 41)
    )
    text = document(
        node("top", '<instance_node url="#n40"/>'), geometry("cube", 0.5), library_nodes=library
    )
    path = write(tmp_path, "nodes.dae", text)
    monkeypatch.setattr(dae, "MAX_NODE_VISITS", 1000)  # the same check, sooner
    assert inspect_error(path) == "cannot parse DAE file: the scene expands to over 1,000 nodes"
    monkeypatch.setattr(dae, "MAX_NODE_VISITS", 10**9)
    monkeypatch.setattr(dae, "MAX_VERTICES", 800)
    assert inspect_error(path) == "cannot parse DAE file: the scene expands to over 800 vertices"


def test_images_are_never_opened(tmp_path):
    # an image the document names (a texture) is not read at all: geometry only
    text = placed_cube().replace(
        "<library_geometries>",
        '<library_images><image id="i"><init_from>/etc/shadow</init_from></image>'
        '<image id="j"><init_from>http://example.com/t.png</init_from></image>'
        "</library_images><library_geometries>",
    )
    (body,) = load_mesh(write(tmp_path, "textured.dae", text))
    assert len(body.faces) == 12


# --- a robot ----------------------------------------------------------------------------


def test_a_urdf_collision_mesh_in_centimetres_is_posed_at_its_size(tmp_path):
    pytest.importorskip("yourdfpy", reason="URDF reading needs yourdfpy")
    from meshcol.io.robot import load_robot

    write(tmp_path, "meshes/cube_cm.dae", placed_cube("0.01"))  # a 1 m cube at (0.1, 0.2, 0.3)
    urdf = (
        '<?xml version="1.0"?>\n<robot name="r">\n'
        '<link name="base"><collision><origin xyz="0 0 2"/><geometry>'
        '<mesh filename="meshes/cube_cm.dae"/></geometry></collision></link>\n'
        '<link name="arm"><collision><origin xyz="0 0 0.5"/><geometry>'
        '<mesh filename="meshes/cube_cm.dae" scale="0.5 0.5 0.5"/></geometry></collision></link>\n'
        '<joint name="j" type="fixed"><parent link="base"/><child link="arm"/>'
        '<origin xyz="3 0 0"/></joint>\n</robot>\n'
    )
    scene = load_robot(write(tmp_path, "r.urdf", urdf))
    base, arm = scene.bodies
    points = world([base])
    np.testing.assert_allclose(points.min(axis=0), [-0.4, -0.3, 1.8], atol=1e-12)
    np.testing.assert_allclose(points.max(axis=0), [0.6, 0.7, 2.8], atol=1e-12)
    points = world([arm])  # the URDF's scale on top of the unit: a 0.5 m cube
    np.testing.assert_allclose(points.min(axis=0), [2.8, -0.15, 0.4], atol=1e-12)
    np.testing.assert_allclose(points.max(axis=0), [3.3, 0.35, 0.9], atol=1e-12)
    result = CliRunner().invoke(main, ["check", str(tmp_path / "r.urdf")])
    assert result.exit_code == 0, result.output  # 2.2 m apart in x: no pair touches


def test_a_manifest_places_centimetre_dae_bodies_in_metres(tmp_path):
    import json

    write(tmp_path, "cm.dae", placed_cube("0.01"))  # a 1 m cube
    bodies = [
        {"name": "a", "mesh": "cm.dae"},
        {"name": "b", "mesh": "cm.dae", "position": [1.5, 0, 0]},
    ]
    scene = write(tmp_path, "scene.json", json.dumps({"units": "m", "bodies": bodies}))
    result = CliRunner().invoke(main, ["check", str(scene), "--format", "json", "--clearance", "1"])
    assert result.exit_code == 0, result.output
    (pair,) = json.loads(result.stdout)["pairs"]
    assert pair["distance"] == pytest.approx(0.5, abs=1e-12) and pair["status"] == "clearance"
