"""The native reader of plain manifests (meshcol.io.scene_native; primitive bodies: issue 32
item 4, mesh bodies: item 5) against the Python reader it stands in for: on any bytes it
passes, Python's json module and the column check (meshcol.io.scene_columns.columns) pass the
same document as equal columns, to the bit; it passes every plain manifest; the scenes,
reports, mesh file lists and error lines of a load are the Python reader's."""

from __future__ import annotations

import contextlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from manifest_readers import python_reader
from test_scene_columns import ASSETS, describe, manifests

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.cli import main
from meshcol.errors import MeshcolError
from meshcol.io import scene_parse, scene_validate
from meshcol.io.paths import confined_to
from meshcol.io.scene import load_scene, manifest_mesh_files
from meshcol.io.scene_columns import Columns, columns
from meshcol.io.scene_native import native_columns, native_scene
from meshcol.io.scene_primitives import PrimitiveBodies

# --- columns ----------------------------------------------------------------------------------


def assert_same_columns(a: Columns, b: Columns) -> None:
    """Every field equal: lists item for item with their types, arrays to the bit."""
    for field in Columns.__dataclass_fields__:
        x, y = getattr(a, field), getattr(b, field)
        if isinstance(x, dict):
            assert x.keys() == y.keys(), field
            for key in x:
                assert_same_array(x[key], y[key], f"{field}.{key}")
        elif isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert_same_array(x, y, field)
        else:
            assert x == y and list(map(type, x or [])) == list(map(type, y or [])), field


def assert_same_array(x, y, what: str) -> None:
    assert (x.dtype, x.shape) == (y.dtype, y.shape), what
    assert x.tobytes() == y.tobytes(), what


def python_side(data: bytes):
    """What the Python reader makes of ``data``: (columns or None, the document), or None
    when it is not UTF-8 JSON."""
    try:
        document = json.loads(data.decode("utf-8-sig"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    return columns(document), document


def assert_native_is_python(data: bytes) -> bool:
    """The native reader passes ``data`` only as the Python reader does: True when it did."""
    found = native_columns(data)
    if found is None:
        return False
    python = python_side(data)
    assert python is not None, data[:200]
    expected, document = python
    assert expected is not None, data[:200]
    assert_same_columns(found.columns, expected)
    for field in ("units", "duration"):
        value = getattr(found, field)
        assert (value, type(value)) == (document.get(field), type(document.get(field))), field
    return True


KINDS = {
    "sphere": '{"type": "sphere", "radius": %s}',
    "box": '{"size": [%s, 0.5, 2], "type": "box"}',
    "capsule": '{"type": "capsule", "length": 0.4, "radius": %s}',
    "cylinder": '{"radius": %s, "type": "cylinder", "length": 3}',
    "ellipsoid": '{"semi_axes": [0.5, %s, 2e-1], "type": "ellipsoid"}',
}
ORDERS = ["xyz", "zyx", "zxz", "yxy", "xzy", "yzx", "zyz", "xyx"]


def plain_text(n: int = 40) -> str:
    """A plain manifest of every type, rotation form, order and shape, numbers of every
    spelling."""
    spellings = ["0.25", "1", "2.5e-1", "1E0", "0.1000000000000000055511151231257827", "7"]
    bodies = []
    for i in range(n):
        kind = list(KINDS)[i % len(KINDS)]
        fields = [f'"name": "b{i}"', f'"primitive": {KINDS[kind] % spellings[i % 6]}']
        if i % 5:
            fields.append(f'"position": [{i}, -0, {spellings[(i + 1) % 6]}]')
        if i % 3 == 0:
            fields.append('"rotation": {"quaternion": [1, -0.0, 0.5e1, 3]}')
        elif i % 3 == 1:
            order = ORDERS[i % len(ORDERS)]
            fields.append(f'"rotation": {{"order": "{order}", "euler_deg": [90, -45.5, 1e2]}}')
        if i % 7 == 0:
            fields.append(f'"shape": "{["hull", "mesh", "decomposed"][i % 3]}"')
        bodies.append("{" + ", ".join(fields[::-1] if i % 2 else fields) + "}")
    return '{"units": "cm", "bodies": [\n' + ",\n".join(bodies) + '\n], "duration": 2}'


def test_a_plain_manifest_reads_to_the_python_readers_columns():
    assert assert_native_is_python(plain_text().encode())
    found = native_columns(plain_text().encode())
    assert found is not None and found.duration == 2 and type(found.duration) is int
    assert found.columns.shapes[0] == "hull" and found.columns.shapes[1] is None
    assert len(found.columns.orders) == len(found.columns.euler) > 0


@pytest.mark.parametrize(
    ("text", "passed"),
    [
        ('"position": [-0, 0, 0]', True),  # the integer 0: +0.0
        ('"position": [-0.0, -0e0, 0]', True),  # floats keep their sign
        ('"position": [123456789012345678901234567890, 1E+2, 5e-3]', True),
        ('"position": [0.30000000000000004441, 1.7976931348623157e308, 1]', True),
        ('"position": [1e400, 0, 0]', False),  # Python: inf, refused by the columns
        ('"position": [NaN, 0, 0]', False),
        ('"position": [-Infinity, 0, 0]', False),
        ('"position": [01, 0, 0]', False),
        ('"position": [1., 0, 0]', False),
        ('"position": [true, 0, 0]', False),
        ('"position": [1, 2]', False),
        ('"position": [1, 2, 3, 4]', False),
        ('"position": [1, 2, 3], "position": [4, 5, 6]', False),  # Python keeps the last
        ('"mesh": "a.obj"', False),
        ('"scale": 1', False),
        ('"velocity": [0, 0, 0]', False),
        ('"colour": "red"', False),
        ('"shape": "hull"', True),
        ('"shape": "convex"', False),
        ('"rotation": {"quaternion": [1, 0, 0]}', False),
        ('"rotation": {"quaternion": [1, 0, 0, 0], "order": "xyz"}', False),
        ('"rotation": {"euler_deg": [1, 0, 0]}', False),
        ('"rotation": {"euler_deg": [1, 0, 0], "order": "xyy"}', False),
        ('"rotation": {"quaternion": [0, 0, 0, 0]}', True),  # the loader refuses it, later
    ],
)
def test_each_field_passes_only_as_the_python_reader_does(text, passed):
    body = '{"name": "a", "primitive": {"type": "sphere", "radius": 1}, ' + text + "}"
    data = '{"bodies": [' + body + "]}"
    assert assert_native_is_python(data.encode()) == passed


@pytest.mark.parametrize(
    ("text", "passed"),
    [
        ('"mesh": "a.obj"', True),
        ('"mesh": "assets/a000001.obj", "shape": "hull", "position": [1, 2, 3]', True),
        ('"rotation": {"euler_deg": [0, 0, 90], "order": "xyz"}, "mesh": "a b.obj"', True),
        ('"mesh": "../outside/a.obj"', True),  # the loader confines it (--root)
        ('"mesh": "/abs/a.obj"', True),
        ('"mesh": "\\u00e9.obj"', False),  # an escape: left to Python
        ('"mesh": "a\\/b.obj"', False),
        ('"mesh": "a\\\\b.obj"', False),
        ('"mesh": ""', False),  # Python: "mesh must be a non-empty string"
        ('"mesh": 1', False),
        ('"mesh": null', False),
        ('"mesh": ["a.obj"]', False),
        ('"mesh": {}', False),
        ('"mesh": "a.obj", "mesh": "b.obj"', False),  # Python keeps the last
        ('"mesh": "a.obj", "primitive": {"type": "sphere", "radius": 1}', False),
        ('"primitive": {"type": "sphere", "radius": 1}, "mesh": "a.obj"', False),
        ('"mesh": "a.obj", "scale": 1', False),
        ('"mesh": "a.obj", "end_position": [0, 0, 0]', False),
        ('"mesh": "a.obj", "colour": "red"', False),
        ('"shape": "hull"', False),  # neither mesh nor primitive
    ],
)
def test_each_field_of_a_mesh_body_passes_only_as_the_python_reader_does(text, passed):
    data = '{"bodies": [{"name": "a", ' + text + "}]}"
    assert assert_native_is_python(data.encode()) == passed


def test_a_mesh_string_passes_as_its_utf8_bytes_only():
    for raw, passed in [
        (b"\xc3\xa9t\xc3\xa9.obj", True),
        (b"\xe6\xbc\xa2/\x7f.obj", True),  # DEL is no control character to JSON
        (b"a\x00.obj", False),  # a raw control character: Python's json refuses it
        (b"a\x1f.obj", False),
        (b"\xc3\x28.obj", False),  # not UTF-8
        (b"\xed\xa0\x80.obj", False),  # a surrogate
    ]:
        data = b'{"bodies": [{"name": "a", "mesh": "' + raw + b'"}]}'
        assert assert_native_is_python(data) == passed, raw


def test_a_mixed_manifest_reads_to_the_python_readers_columns():
    document = json.loads(plain_text(30))
    for i, body in enumerate(document["bodies"]):
        if i % 3 == 1:
            del body["primitive"]
            body["mesh"] = f"assets/a{i:06d}.obj"
    data = json.dumps(document, ensure_ascii=False).encode()
    assert assert_native_is_python(data)
    found = native_columns(data)
    assert found is not None
    assert found.columns.meshes[1] == "assets/a000001.obj" and found.columns.meshes[0] is None
    assert found.columns.primitive.tolist() == [i % 3 != 1 for i in range(30)]
    assert found.columns.primitive_type[1] == -1
    only_meshes = {"bodies": [b for b in document["bodies"] if "mesh" in b]}
    assert assert_native_is_python(json.dumps(only_meshes).encode())


@pytest.mark.parametrize(
    ("data", "passed"),
    [
        (b'\xef\xbb\xbf{"bodies": [B]}', True),  # a byte-order mark, dropped as utf-8-sig does
        (b'\xef\xbb\xbf\xef\xbb\xbf{"bodies": [B]}', False),
        (b' \t\r\n{"bodies": [B]} \n', True),
        (b'{"bodies": [B]} x', False),
        (b'{"bodies": [B],}', False),
        (b'{"bodies": []}', False),
        (b'{"bodies": [B], "units": ""}', False),
        (b'{"bodies": [B], "units": "\\u006d"}', False),  # escapes: left to Python
        (b'{"bodies": [B], "duration": 0}', False),
        (b'{"bodies": [B], "duration": 1e-1}', True),
        (b'{"bodies": [B], "extra": 1}', False),
        (b"[B]", False),
        (b'{"bodies": [B, B]}', True),  # a repeated name: columns; the loader refuses it
        (b'{"bodies": [{"name": "", "primitive": {"type": "sphere", "radius": 1}}]}', False),
        (b'{"bodies": [{"name": "\xc3\xa9t\xc3\xa9", "primitive": P}]}', True),
        (b'{"bodies": [{"name": "\xc3\x28", "primitive": P}]}', False),  # not UTF-8
        (b'{"bodies": [{"name": "\xed\xa0\x80", "primitive": P}]}', False),  # a surrogate
        (b'{"bodies": [{"name": "\xf4\x90\x80\x80", "primitive": P}]}', False),
        (b'{"bodies": [{"name": "a\tb", "primitive": P}]}', False),  # a raw control character
        (b'{"bodies": [{"name": "a", "primitive": {"type": "sphere", "radius": 0}}]}', False),
        (b'{"bodies": [{"name": "a", "primitive": {"type": "sphere"}}]}', False),
        (b'{"bodies": [{"name": "a", "primitive": {"type": "box", "radius": 1}}]}', False),
        (b'{"bodies": [{"name": "a", "primitive": {"type": "cone", "radius": 1}}]}', False),
        (b'{"bodies": [{"primitive": P}]}', False),
        (b'{"bodies": [{"name": "a", "primitive": P', False),  # cut short
    ],
)
def test_the_document_passes_only_as_the_python_reader_does(data, passed):
    primitive = b'{"type": "capsule", "radius": 0.5, "length": 1}'
    data = data.replace(b"B", b'{"name": "a", "primitive": P}').replace(b"P", primitive)
    assert assert_native_is_python(data) == passed


# --- hypothesis-made manifests: any spelling, the plain ones and the others -------------------

#: Spellings Python reads as finite numbers (every one the native reader must pass too).
plain_numbers = st.one_of(
    st.floats(-1e9, 1e9, allow_nan=False).map(repr),
    st.integers(-(10**9), 10**9).map(str),
    st.sampled_from(
        ["-0", "-0.0", "0e0", "1E2", "2.5e+3", "-1.5e-3", "123456789012345678901234567890"]
        + ["0.1000000000000000055511151231257827", "1.7976931348623157e308", "4e-320"]
    ),
)
#: And the others: any float or integer, out of range, not a number, not JSON.
numbers = st.one_of(
    plain_numbers,
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**400), 10**400).map(str),
    st.sampled_from(
        ["1e400", "1e-400", "5e-324", "NaN", "Infinity", "-Infinity", "01", "1.", ".5", "true"]
        + ['"1"', "null", "1_0", "+1", "-", "1e", "0x10", "[1]"]
    ),
)
positive_numbers = st.one_of(
    st.floats(1e-6, 1e6).map(repr), st.integers(1, 10**6).map(str), st.sampled_from(["2e-1"])
)


def array(draw, items, size: int) -> str:
    return "[" + ", ".join(draw(items) for _ in range(size)) + "]"


@st.composite
def strings(draw, plain: bool) -> str:
    text = draw(st.text(min_size=1, max_size=6))
    if plain:
        return json.dumps(
            draw(st.from_regex(r"[a-z0-9_\-:é漢]{1,8}", fullmatch=True)), ensure_ascii=False
        )
    return json.dumps(text, ensure_ascii=draw(st.booleans()))


@st.composite
def primitive_text(draw, plain: bool) -> str:
    kind = draw(st.sampled_from(["sphere", "box", "capsule", "cylinder", "ellipsoid"]))
    value = positive_numbers if plain else st.one_of(positive_numbers, numbers)
    fields = {"type": f'"{kind}"'}
    if kind == "box":
        fields["size"] = array(draw, value, 3)
    elif kind == "ellipsoid":
        fields["semi_axes"] = array(draw, value, 3)
    else:
        fields["radius"] = draw(value)
    if kind in ("capsule", "cylinder"):
        fields["length"] = draw(value)
    if not plain and draw(st.integers(0, 5)) == 0:
        field = draw(st.sampled_from(["type", "radius", "length", "size", "semi_axes", "height"]))
        fields[field] = draw(st.sampled_from(["1", "[1, 1, 1]"]))
    items = list(fields.items())
    items = draw(st.permutations(items))
    return "{" + ", ".join(f'"{k}": {v}' for k, v in items) + "}"


@st.composite
def mesh_text(draw, plain: bool) -> str:
    """A mesh body's ``mesh``: a file name as written (plain: no escapes), or a near miss."""
    name = draw(st.from_regex(r"(\.\./|/)?[a-z0-9_ é漢/.\-]{0,10}\.(obj|stl|glb)", fullmatch=True))
    if plain:
        return json.dumps(name, ensure_ascii=False)
    return draw(
        st.one_of(
            st.just(json.dumps(name, ensure_ascii=False)),
            st.just(json.dumps(name, ensure_ascii=True)),  # escapes where not ASCII
            strings(False),
            st.sampled_from(['""', '"a\\u002eobj"', '"a\\/b.obj"', "1", "null", '["a.obj"]']),
        )
    )


@st.composite
def body_text(draw, plain: bool) -> str:
    plain = plain or draw(st.integers(0, 3)) > 0  # most bodies of a spoilt manifest are plain
    value = plain_numbers if plain else st.one_of(plain_numbers, numbers)
    fields = [("name", draw(strings(plain)))]
    if draw(st.integers(0, 2)) == 0:  # a mesh body, one in three
        fields.append(("mesh", draw(mesh_text(plain))))
    else:
        fields.append(("primitive", draw(primitive_text(plain))))
    if draw(st.booleans()):
        fields.append(("position", array(draw, value, 3)))
    form = draw(st.integers(0, 2))
    if form == 1:
        fields.append(("rotation", '{"quaternion": ' + array(draw, value, 4) + "}"))
    elif form == 2:
        order = draw(st.sampled_from(ORDERS if plain else [*ORDERS, "xx", "XYZ"]))
        angles = array(draw, value, 3)
        fields.append(("rotation", f'{{"euler_deg": {angles}, "order": "{order}"}}'))
    if draw(st.booleans()):
        fields.append(("shape", draw(st.sampled_from(['"hull"', '"mesh"', '"decomposed"']))))
    if not plain:
        for _ in range(draw(st.integers(0, 2))):
            key = draw(
                st.sampled_from(
                    ["name", "position", "mesh", "scale", "velocity", "shape", "x", "primitive"]
                )
            )
            fields.append((key, draw(st.sampled_from(['"a"', "[1, 2, 3]", "1", "{}", '"a.obj"']))))
    fields = draw(st.permutations(fields))
    space = draw(st.sampled_from(["", " ", "\n  ", "\t"]))
    return "{" + f",{space}".join(f'"{k}":{space}{v}' for k, v in fields) + "}"


@st.composite
def manifest_bytes(draw, plain: bool) -> bytes:
    bodies = [draw(body_text(plain)) for _ in range(draw(st.integers(1, 4)))]
    top = [("bodies", "[" + ", ".join(bodies) + "]")]
    if draw(st.booleans()):
        top.append(("units", draw(strings(plain))))
    if draw(st.booleans()):
        top.append(("duration", draw(positive_numbers if plain else numbers)))
    top = draw(st.permutations(top))
    text = "{" + ", ".join(f'"{k}": {v}' for k, v in top) + "}"
    data = text.encode()
    if draw(st.booleans()):
        data = b"\xef\xbb\xbf" + data
    if not plain and draw(st.integers(0, 3)) == 0:  # a byte changed: syntax, encoding
        at = draw(st.integers(0, len(data) - 1))
        data = data[:at] + bytes([draw(st.integers(0, 255))]) + data[at + 1 :]
    return data


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(manifest_bytes(plain=False))
def test_the_native_reader_passes_only_what_the_python_reader_passes_as_equal_columns(data):
    assert_native_is_python(data)


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(manifest_bytes(plain=True))
def test_the_native_reader_passes_every_plain_manifest(data):
    assert assert_native_is_python(data), data


# --- the load ---------------------------------------------------------------------------------

CLOCKS = re.compile(r'("generated_at"|"seconds"|"load_seconds"): [^,\n]*')


def forget() -> None:
    scene_parse.forget_documents()
    scene_validate._LAST[:] = [object(), None, None]


def load_twice(path: Path):
    """The scene or error line by the native reader, and by the Python reader."""
    out = []
    for python in (False, True):
        forget()
        try:
            if python:
                with python_reader():
                    out.append(load_scene(path))
            else:
                out.append(load_scene(path))
        except MeshcolError as error:
            out.append(str(error))
    forget()
    return out


def bits(bodies: PrimitiveBodies) -> list:
    return [
        (a.dtype.str, a.shape, a.tobytes()) for a in (bodies.kinds, bodies.lengths, bodies.poses)
    ] + [bodies.names, bodies.colliders, bodies.source]


def test_a_plain_manifest_loads_to_the_python_readers_scene_and_report(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(plain_text(24))
    native, python = load_twice(path)
    assert isinstance(native.bodies, PrimitiveBodies) and isinstance(python.bodies, PrimitiveBodies)
    assert bits(native.bodies) == bits(python.bodies)
    assert (native.units, native.duration, native.source) == (
        python.units,
        python.duration,
        python.source,
    )
    options = CheckOptions(clearance=0.2)
    report = [CLOCKS.sub("", check_scene(s, options).to_json()) for s in (native, python)]
    assert report[0] == report[1] and '"penetrating"' in report[0]
    assert manifest_mesh_files(path) == []


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"name": "b0"}, "body 'b0': name used by an earlier body"),
        ({"rotation": {"quaternion": [0, 0, 0, 0]}}, "rotation.quaternion must be non-zero"),
        ({"position": [2e10, 0, 0]}, "position 2e+10 is beyond the limit"),
        ({"primitive": {"type": "sphere", "radius": 2e10}}, "primitive.radius 2e+10 is beyond"),
        ({"primitive": {"type": "sphere", "radius": 6e9}}, None),  # near the limit: loads
        ({"primitive": {"type": "sphere", "radius": 4e9}}, None),
    ],
)
def test_what_the_native_reader_passes_but_the_loader_refuses_is_the_same_error(
    tmp_path, change, message
):
    document = json.loads(plain_text(8))
    document["bodies"][3].update(change)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document))
    assert native_columns(path.read_bytes()) is not None
    native, python = load_twice(path)
    if message is None:
        assert bits(native.bodies) == bits(python.bodies)
        return
    assert native == python and message in native, native


def test_a_bad_manifest_is_one_line_naming_the_file_and_the_body(tmp_path):
    document = json.loads(plain_text(8))
    document["bodies"][5]["position"] = [1, "2", 3]
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document))
    forget()
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.output
    assert str(path) in lines[0] and "body 'b5': position must be an array of 3" in lines[0]


# --- mesh bodies: the load --------------------------------------------------------------------


def load_readers(path: Path) -> list:
    """Of the native reader, then the Python reader: the scene (its bodies to the bit) or the
    error line, and the mesh files of the manifest (or the error line)."""
    out = []
    for python in (False, True):
        with python_reader() if python else contextlib.nullcontext():
            forget()
            try:
                loaded: Any = describe(load_scene(path))
            except MeshcolError as error:
                loaded = str(error)
            forget()
            try:
                files: Any = manifest_mesh_files(path)
            except MeshcolError as error:
                files = str(error)
        out.append((loaded, files))
    forget()
    return out


@pytest.fixture(scope="module")
def mesh_assets(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("native") / "scene"
    folder.mkdir()
    for name, text in ASSETS.items():
        (folder / name).write_text(text)
    (folder / "big.obj").write_text(ASSETS["tet.obj"].replace("v 0 0 1", "v 0 0 250.5"))
    (folder.parent / "outside.obj").write_text(ASSETS["tet.obj"])
    return folder


def natively_read(document: dict) -> dict:
    """``document`` with unique names and no field the native reader passes over (scale,
    motion): mostly read natively, its bodies all built in bulk or some one by one."""
    for i, body in enumerate(document["bodies"]):
        body["name"] += str(i)
        for field in ("scale", "end_position", "end_rotation", "velocity", "angular_velocity"):
            body.pop(field, None)
    return document


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture], deadline=None)
@given(st.one_of(manifests(), manifests().map(natively_read)))
def test_a_manifest_of_mesh_bodies_loads_as_the_python_reader_loads_it(mesh_assets, document):
    path = mesh_assets / "scene.json"
    path.write_text(json.dumps(document))
    native, python = load_readers(path)
    assert native == python


def test_a_large_mixed_manifest_is_read_natively_to_the_python_readers_scene(mesh_assets):
    rng = np.random.default_rng(5)
    bodies: list[dict[str, Any]] = []
    for i in range(300):
        body: dict[str, Any] = {"name": f"b{i}", "position": rng.uniform(-50, 50, 3).tolist()}
        if i % 5 == 4:
            body["primitive"] = {"type": "capsule", "radius": 0.5, "length": 1.5}
        else:
            body["mesh"] = ["tet.obj", "big.obj"][i % 2]
        if i % 3 == 0:
            body["rotation"] = {"quaternion": rng.normal(size=4).tolist()}
        elif i % 3 == 1:
            body["rotation"] = {"euler_deg": rng.uniform(-400, 400, 3).tolist(), "order": "zxz"}
        if i % 7 == 0:
            body["shape"] = "hull"
        bodies.append(body)
    path = mesh_assets / "scene.json"
    path.write_text(json.dumps({"units": "m", "bodies": bodies}))
    forget()
    found = native_scene(str(path))
    assert found is not None and found.scene is not None  # no document decoded
    assert len(found.scene.bodies) == 300
    native, python = load_readers(path)
    assert native == python and isinstance(native[0], list)
    assert native[1] == [str(mesh_assets / "tet.obj"), str(mesh_assets / "big.obj")]
    reports = []
    for reader in (contextlib.nullcontext, python_reader):
        forget()
        with reader():
            scene = load_scene(path)
        reports.append(CLOCKS.sub("", check_scene(scene, CheckOptions()).to_json()))
    forget()
    assert reports[0] == reports[1]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"mesh": "pair.obj"}, None),  # two objects: that body built one by one
        ({"mesh": "missing.obj"}, "body 'b3': mesh file 'missing.obj' not found"),
        ({"mesh": "broken.obj"}, "body 'b3': mesh file 'broken.obj'"),
        ({"mesh": "notes.txt"}, "body 'b3': mesh file 'notes.txt'"),
        ({"name": "b1"}, "body 'b1': name used by an earlier body"),
        ({"rotation": {"quaternion": [0, 0, 0, 0]}}, "rotation.quaternion must be non-zero"),
        ({"mesh": "far.obj", "position": [6e9, 0, 0]}, "body 'b3'"),  # near the limit
        ({"position": [2e10, 0, 0]}, "position 2e+10 is beyond the limit"),
        ({"mesh": "../outside.obj"}, None),  # no root: read
    ],
)
def test_a_mesh_manifest_the_loader_refuses_or_builds_body_by_body_is_the_same(
    mesh_assets, change, message
):
    bodies = [{"name": f"b{i}", "mesh": "tet.obj", "position": [3 * i, 0, 0]} for i in range(6)]
    bodies[3].update(change)
    path = mesh_assets / "scene.json"
    path.write_text(json.dumps({"bodies": bodies}))
    assert native_columns(path.read_bytes()) is not None
    native, python = load_readers(path)
    assert native == python
    if message is None:
        assert isinstance(native[0], list)
    else:
        assert message in native[0], native


def test_a_mesh_outside_the_root_is_the_python_readers_error(mesh_assets):
    bodies = [{"name": "a", "mesh": "tet.obj"}, {"name": "b", "mesh": "../outside.obj"}]
    path = mesh_assets / "scene.json"
    path.write_text(json.dumps({"bodies": bodies}))
    assert native_columns(path.read_bytes()) is not None
    with confined_to(mesh_assets):
        native, python = load_readers(path)
    assert native == python
    assert "path '../outside.obj' resolves outside the root" in native[0]
    assert native[1] == native[0]  # the mesh file list refuses it the same way
    with confined_to(mesh_assets.parent):
        native, python = load_readers(path)
    assert native == python and isinstance(native[0], list)


def test_a_mesh_manifest_near_miss_gives_the_python_readers_error(mesh_assets):
    for body, message in [
        ('{"name": "a", "mesh": ""}', "body 'a': mesh must be a non-empty string"),
        ('{"name": "a", "mesh": 1}', "body 'a': mesh must be a non-empty string"),
        ('{"name": "a", "mesh": "tet.obj", "primitive": {"type": "sphere", "radius": 1}}', None),
        ('{"name": "a", "mesh": "tet.obj", "mesh": "nothing.obj"}', "'nothing.obj' not found"),
        ('{"name": "a", "mesh": "t\\u0065t.obj"}', ""),  # an escape: read by Python, loads
    ]:
        path = mesh_assets / "scene.json"
        path.write_text('{"bodies": [' + body + "]}")
        assert native_columns(path.read_bytes()) is None, body
        native, python = load_readers(path)
        assert native == python, body
        if message is None:
            assert "needs exactly one of 'mesh' or 'primitive'" in native[0], native
        elif message:
            assert message in native[0], native
        else:
            assert isinstance(native[0], list)
