"""glTF physics both ways (:mod:`meshcol.io.gltf_physics`, :mod:`meshcol.io.gltf_physics_write`).

Written: ``hull`` and ``fit`` with ``--to gltf-physics`` read back to the same colliders, each
extension on its own (Khronos and OMI), against our schemas and the Khronos validator (when
``make gltf-validator`` installed it). Read: hand-written KHR and OMI files, their bodies,
primitives, triggers, planes and collision filters; broken ones exit 2 with one line.
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from gltf_documents import cube_document

from meshcol.analysis.colliders import build_colliders
from meshcol.cli import main
from meshcol.io.gltf_physics_write import physics_schema_problems
from meshcol.io.scene import load_inputs
from meshcol.types import Box, Capsule, Cylinder, Sphere

ROOT = Path(__file__).resolve().parents[2]


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture
def asset(tmp_path: Path) -> Path:
    """A GLB of two named mesh nodes: a box turned and moved, a scaled ball."""
    scene = trimesh.Scene()
    turn = trimesh.transformations.rotation_matrix(0.4, [0, 0, 1])
    turn[:3, 3] = [0.5, -1.0, 0.25]
    scene.add_geometry(trimesh.creation.box(extents=[1, 2, 3]), "crate", "crate", transform=turn)
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    scene.add_geometry(ball, "ball", "ball", transform=np.diag([2.0, 2.0, 2.0, 1.0]) @ np.eye(4))
    path = tmp_path / "props.glb"
    scene.export(path)
    return path


def glb_document(path: Path) -> tuple[dict, bytes]:
    data = path.read_bytes()
    length = struct.unpack("<I", data[12:16])[0]
    document = json.loads(data[20 : 20 + length])
    start = 20 + length
    size = struct.unpack("<I", data[start : start + 4])[0]
    return document, data[start + 8 : start + 8 + size]


def write_glb(path: Path, document: dict, binary: bytes) -> None:
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\x00" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    chunks += struct.pack("<I4s", len(binary), b"BIN\x00") + binary
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def only(path: Path, keep: str, out: Path) -> Path:
    """The GLB at ``path`` with one extension family kept (``KHR`` or ``OMI``)."""
    document, binary = glb_document(path)
    drop = ("OMI_",) if keep == "KHR" else ("KHR_",)
    document["extensionsUsed"] = [e for e in document["extensionsUsed"] if not e.startswith(drop)]
    for holder in [document, *document["nodes"]]:
        extensions = holder.get("extensions", {})
        for name in [n for n in extensions if n.startswith(drop)]:
            del extensions[name]
    write_glb(out, document, binary)
    return out


def point_gap(a: np.ndarray, b: np.ndarray) -> float:
    from scipy.spatial import cKDTree

    return float(max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max()))


# -- written, then read back -----------------------------------------------------------------


def test_hull_to_gltf_physics_reads_back_the_same_hulls(asset: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, stdout, stderr = run("hull", str(asset), "--out-dir", str(out), "--to", "gltf-physics")
    assert code == 0, stderr
    assert stderr.endswith(f"written to {out / 'props.glb'}\n")
    from meshcol.analysis.hull import hull

    expected = {row["name"]: h for row, h in zip(hull([asset]).bodies, hull([asset]).hulls)}
    written = out / "props.glb"
    for path in (
        written,
        only(written, "KHR", tmp_path / "k.glb"),
        only(written, "OMI", tmp_path / "o.glb"),
    ):
        scene = load_inputs([path])
        names = [b.name.replace(path.stem, "props") for b in scene.bodies]
        assert sorted(names) == sorted(expected) and scene.units == "m"
        assert scene.warnings == ()
        for name, body in zip(names, scene.bodies):
            assert body.collider == "hull"
            want = expected[name].vertices
            size = float(np.ptp(want, axis=0).max())
            assert point_gap(body.world_vertices(), want) <= 1e-6 * size  # float32 storage
    document, _ = glb_document(written)
    assert physics_schema_problems(document) == []
    # the asset itself is kept: its two render meshes are still drawn by the same nodes
    assert [n.get("mesh") for n in document["nodes"] if n.get("name") in ("crate", "ball")] == [
        0,
        1,
    ]


@pytest.mark.parametrize("shape", ["box", "sphere", "capsule", "cylinder"])
def test_fit_to_gltf_physics_reads_back_exact_primitives(
    asset: Path, tmp_path: Path, shape: str
) -> None:
    from meshcol.analysis.fit import fit

    out = tmp_path / "out"
    code, _, stderr = run(
        "fit", str(asset), "--out-dir", str(out), "--to", "gltf-physics", "--shape", shape
    )
    assert code == 0, stderr
    report = fit([asset], shape=shape)
    expected = {row["name"]: f.primitive_fit for row, f in zip(report.bodies, report.fits)}
    for family in ("KHR", "OMI"):
        scene = load_inputs([only(out / "props.glb", family, tmp_path / f"{family}.glb")])
        for body in scene.bodies:
            want = expected[body.name.replace(family, "props")]
            kind = {"box": Box, "sphere": Sphere, "capsule": Capsule, "cylinder": Cylinder}
            assert isinstance(body.primitive, kind[shape])
            got = np.asarray(list(body.primitive.__dict__.values()), dtype=float).ravel()
            ref = np.asarray(list(want.primitive.__dict__.values()), dtype=float).ravel()
            assert got == pytest.approx(ref, rel=1e-12, abs=1e-12)
            if shape != "sphere":  # a sphere's rotation is free
                assert body.pose == pytest.approx(want.pose, abs=1e-9)
            assert body.pose[:3, 3] == pytest.approx(want.pose[:3, 3], abs=1e-9)


def test_the_khronos_validator_finds_no_error(asset: Path, tmp_path: Path) -> None:
    node = shutil.which("node")
    modules = Path(os.environ.get("MESHCOL_NODE_MODULES", ROOT / ".venv" / "node" / "node_modules"))
    if node is None or not (modules / "gltf-validator").is_dir():
        pytest.skip("the Khronos glTF validator is not installed (make gltf-validator)")
    out = tmp_path / "out"
    assert run("hull", str(asset), "--out-dir", str(out), "--to", "gltf-physics")[0] == 0
    assert run("fit", str(asset), "--out-dir", str(tmp_path / "f"), "--to", "gltf-physics")[0] == 0
    # the hulls replaced by fits (the old colliders, their nodes, meshes and bytes taken out)
    again = (
        "fit",
        str(out / "props.glb"),
        "--out-dir",
        str(tmp_path / "r"),
        "--to",
        "gltf-physics",
    )
    assert run(*again)[0] == 0
    script = (
        "const v = require('gltf-validator'); const fs = require('fs');"
        "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[1])))"
        ".then(r => console.log(JSON.stringify(r.issues)))"
        ".catch(e => { console.error(String(e)); process.exit(3); });"
    )
    for path in (out / "props.glb", tmp_path / "f" / "props.glb", tmp_path / "r" / "props.glb"):
        done = subprocess.run(
            [node, "-e", script, str(path)],
            env={**os.environ, "NODE_PATH": str(modules)},
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
        )
        issues = json.loads(done.stdout)
        assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
        ours = [m for m in issues["messages"] if m["code"] != "UNSUPPORTED_EXTENSION"]
        # the validator cannot read the physics extensions; nothing else of ours is flagged
        # but the collision meshes' nodes, kept out of every scene so they are never drawn
        assert {m["code"] for m in ours} <= {"UNUSED_OBJECT", "BUFFER_VIEW_TARGET_MISSING"}


def test_the_schemas_catch_what_the_specifications_forbid() -> None:
    good = {
        "extensions": {
            "KHR_implicit_shapes": {"shapes": [{"type": "sphere", "sphere": {"radius": 1}}]},
            "KHR_physics_rigid_bodies": {"collisionFilters": [{"collisionSystems": ["a"]}]},
        },
        "nodes": [
            {"extensions": {"KHR_physics_rigid_bodies": {"collider": {"geometry": {"shape": 0}}}}}
        ],
    }
    assert physics_schema_problems(good) == []
    bad = json.loads(json.dumps(good))
    bad["extensions"]["KHR_implicit_shapes"]["shapes"][0]["box"] = {"size": [1, 1, 1]}
    bad["extensions"]["KHR_physics_rigid_bodies"]["collisionFilters"][0].update(
        collideWithSystems=["b"], notCollideWithSystems=["c"]
    )
    bad["nodes"][0]["extensions"]["KHR_physics_rigid_bodies"]["collider"]["geometry"]["node"] = 1
    bad["nodes"].append({"extensions": {"OMI_physics_body": {"motion": {"type": "flying"}}}})
    problems = physics_schema_problems(bad)
    pointers = sorted(p.split(":")[0] for p in problems)
    assert pointers == [
        "/extensions/KHR_implicit_shapes/shapes/0",
        "/extensions/KHR_physics_rigid_bodies/collisionFilters/0",
        "/nodes/0/extensions/KHR_physics_rigid_bodies/collider/geometry",
        "/nodes/1/extensions/OMI_physics_body/motion/type",
    ]


# -- hand-written files ----------------------------------------------------------------------


def gltf_file(path: Path, nodes: list, extensions: dict, used: list, scene_nodes: list) -> Path:
    """A .gltf whose one mesh (a unit cube, data URI) nodes may use."""
    document = cube_document(nodes, scene_nodes, extensions=extensions, used=used)
    path.write_text(json.dumps(document))
    return path


def khr_level(tmp_path: Path) -> Path:
    khr = "KHR_physics_rigid_bodies"
    nodes = [
        {
            "name": "cart",
            "translation": [0, 0, 5],
            "children": [1, 2],
            "extensions": {khr: {"motion": {"mass": 2}}},
        },
        {
            "name": "chassis",
            "extensions": {khr: {"collider": {"geometry": {"shape": 0}, "collisionFilter": 0}}},
        },
        {
            "name": "bin",
            "mesh": 0,
            "translation": [2, 0, 0],
            "extensions": {khr: {"collider": {"geometry": {"node": 2}, "collisionFilter": 0}}},
        },
        {"name": "floor", "extensions": {khr: {"collider": {"geometry": {"shape": 1}}}}},
        {
            "name": "pole",
            "rotation": [0, 0, 0.7071067811865476, 0.7071067811865476],
            "extensions": {khr: {"collider": {"geometry": {"shape": 2}, "collisionFilter": 1}}},
        },
        {"name": "zone", "extensions": {khr: {"trigger": {"geometry": {"shape": 0}}}}},
        {"name": "ground", "extensions": {khr: {"collider": {"geometry": {"shape": 3}}}}},
    ]
    extensions = {
        "KHR_implicit_shapes": {
            "shapes": [
                {"type": "box", "box": {"size": [1, 2, 3]}},
                {"type": "sphere", "sphere": {"radius": 0.5}},
                {
                    "type": "capsule",
                    "capsule": {"height": 2, "radiusTop": 0.25, "radiusBottom": 0.25},
                },
                {"type": "plane", "plane": {}},
            ]
        },
        khr: {
            "collisionFilters": [
                {"collisionSystems": ["cart"], "notCollideWithSystems": ["pole"]},
                {"collisionSystems": ["pole"], "notCollideWithSystems": ["cart"]},
            ]
        },
    }
    used = [khr, "KHR_implicit_shapes"]
    return gltf_file(tmp_path / "level.gltf", nodes, extensions, used, [0, 3, 4, 5, 6])


def test_khronos_bodies_shapes_triggers_and_filters(tmp_path: Path) -> None:
    path = khr_level(tmp_path)
    assert physics_schema_problems(json.loads(path.read_text())) == []
    scene = load_inputs([path])
    bodies = {b.name: b for b in scene.bodies}
    assert list(bodies) == ["level/cart", "level/floor", "level/pole", "level/ground"][:3]
    cart = bodies["level/cart"]
    assert cart.parts == ("chassis", "bin") and cart.collider == "mesh"
    assert cart.pose[:3, 3] == pytest.approx([0, 0, 5])
    lows = cart.world_vertices().min(axis=0)
    assert lows == pytest.approx([-0.5, -1.0, 3.5])  # the box; the bin cube is at x = 2
    # the box shape stays exact for the queries beside the bin's mesh (its triangles drawn)
    chassis, bin_ = cart.part_primitives
    assert chassis.primitive == Box((1.0, 2.0, 3.0)) and bin_ is None
    np.testing.assert_array_equal(chassis.pose, np.eye(4))
    colliders = build_colliders([cart], "mesh")
    assert colliders.shapes.kinds.tolist() == [2, 0] and colliders.part_label.tolist() == [0, 1]
    assert bodies["level/floor"].primitive == Sphere(0.5)
    pole = bodies["level/pole"]
    assert pole.primitive == Capsule(0.25, 2.0)
    # capsule along the node's Y, the node turned 90 degrees about z: along world -x
    assert np.abs(pole.pose[:3, 2]) == pytest.approx([1, 0, 0], abs=1e-12)
    assert scene.excluded_pairs == (
        ("level/cart", "level/pole", "KHR_physics_rigid_bodies collision filters"),
    )
    assert any("1 trigger(s) not checked" in w for w in scene.warnings)
    assert any("1 plane collider(s)" in w for w in scene.warnings)


def test_omi_bodies_as_godot_writes_them(tmp_path: Path) -> None:
    omi = "OMI_physics_body"
    nodes = [
        {
            "name": "Ramp",
            "mesh": 0,
            "extensions": {omi: {"motion": {"type": "static"}}},
            "children": [1],
        },
        {"name": "RampShape", "extensions": {omi: {"collider": {"shape": 0}}}},
        {
            "name": "Player",
            "translation": [0, 3, 0],
            "children": [2 + 1],
            "extensions": {omi: {"motion": {"type": "dynamic", "mass": 80}}},
        },
        {"name": "PlayerShape", "extensions": {omi: {"collider": {"shape": 1}}}},
        {"name": "Goal", "extensions": {omi: {"trigger": {"shape": 2}}}},
    ]
    extensions = {
        "OMI_physics_shape": {
            "shapes": [
                {"type": "trimesh", "trimesh": {"mesh": 0}},
                {
                    "type": "capsule",
                    "capsule": {"height": 1.0, "radiusTop": 0.3, "radiusBottom": 0.3},
                },
                {"type": "box", "box": {}},
            ]
        }
    }
    used = [omi, "OMI_physics_shape"]
    path = gltf_file(tmp_path / "godot.gltf", nodes, extensions, used, [0, 2, 4])
    assert physics_schema_problems(json.loads(path.read_text())) == []
    scene = load_inputs([path])
    bodies = {b.name: b for b in scene.bodies}
    assert list(bodies) == ["godot/Ramp", "godot/Player"]
    assert bodies["godot/Ramp"].collider == "mesh" and len(bodies["godot/Ramp"].faces) == 12
    player = bodies["godot/Player"]
    assert player.primitive == Capsule(0.3, 1.0)
    assert player.pose[:3, 2] == pytest.approx([0, 1, 0]) and player.pose[1, 3] == 3
    assert scene.warnings == ("1 trigger(s) not checked (triggers are not solid)",)


def test_omis_earlier_draft_as_godot_4_1_writes_it(tmp_path: Path) -> None:
    # omigroup/gltf-extensions, OMI_physics_body/examples/complex/static_with_trigger.gltf
    document = {
        "asset": {"version": "2.0"},
        "extensions": {
            "OMI_physics_shape": {
                "shapes": [
                    {"size": [1, 1, 1], "type": "box"},
                    {"radius": 2, "type": "sphere"},
                ]
            }
        },
        "extensionsUsed": ["OMI_physics_body", "OMI_physics_shape"],
        "nodes": [
            {
                "children": [1, 2],
                "extensions": {"OMI_physics_body": {"type": "static"}},
                "name": "StaticBox",
            },
            {"extensions": {"OMI_physics_shape": {"shape": 0}}, "name": "StaticShape"},
            {
                "children": [3],
                "extensions": {"OMI_physics_body": {"type": "trigger"}},
                "name": "TriggerBody",
            },
            {"extensions": {"OMI_physics_shape": {"shape": 1}}, "name": "TriggerShape"},
        ],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
    }
    path = tmp_path / "static_with_trigger.gltf"
    path.write_text(json.dumps(document))
    scene = load_inputs([path])
    assert [b.name for b in scene.bodies] == ["static_with_trigger"]
    assert scene.bodies[0].primitive == Box((1.0, 1.0, 1.0))
    assert scene.warnings == ("1 trigger(s) not checked (triggers are not solid)",)


def test_a_gltf_without_physics_reads_as_before(asset: Path) -> None:
    from meshcol.io.gltf import read_glb

    scene = load_inputs([asset])
    assert scene.units is None and scene.warnings == () and scene.excluded_pairs == ()
    assert [b.name for b in scene.bodies] == ["props/crate", "props/ball"]
    assert len(read_glb(asset, str(asset))) == 2


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (
            lambda d: d["nodes"][3]["extensions"]["KHR_physics_rigid_bodies"]["collider"][
                "geometry"
            ].update(shape=9),
            "node 3 collider geometry refers to shapes 9, but there are 4",
        ),
        (
            lambda d: d["accessors"][0].update(count=800),
            "accessor 0 reads past its bufferView or buffer",
        ),
        (lambda d: d["nodes"][1].update(children=[0]), "node 0's parents form a cycle"),
        (
            lambda d: d["meshes"][0]["primitives"][0].update(
                extensions={"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {}}}
            ),
            "mesh 0 primitive 0 is compressed (KHR_draco_mesh_compression), which meshcol does",
        ),
        (
            lambda d: d["extensions"]["KHR_implicit_shapes"]["shapes"][1].update(type="torus"),
            "has shape type 'torus', which meshcol does not read",
        ),
    ],
)
def test_broken_physics_exits_2_with_one_line(tmp_path: Path, change, words: str) -> None:
    path = khr_level(tmp_path)
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))
    code, _, stderr = run("check", str(path))
    assert code == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"meshcol: error: {path}: cannot parse GLTF file: ")
    assert words in stderr


@pytest.mark.slow  # CoACD on two meshes: about 5 s on a loaded machine
def test_decompose_to_gltf_physics_reads_back_its_parts(asset: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, stdout, stderr = run(
        "decompose",
        str(asset),
        "--out-dir",
        str(out),
        "--to",
        "gltf-physics",
        "--cache-dir",
        str(tmp_path / "cache"),
        "--report",
        "-",
    )
    assert code == 0, stderr
    report = json.loads(stdout)
    assert report["settings"]["to"] == "gltf-physics"
    assert report["settings"]["description"] == str(out / "props.glb")
    scene = load_inputs([out / "props.glb"])
    by_name = {b.name: b for b in scene.bodies}
    for body in report["files"][0]["bodies"]:
        read = by_name[body["name"]]
        assert read.collider == "hull"
        parts = [load_inputs([out / name]).bodies[0].world_vertices() for name in body["outputs"]]
        got = [m[1] @ read.pose[:3, :3].T + read.pose[:3, 3] for m in read.part_meshes()]
        assert len(got) == len(parts)
        for want, mine in zip(parts, got):
            assert point_gap(mine, want) <= 1e-6 * float(np.ptp(want, axis=0).max())
    # again on what it wrote: the render meshes decomposed again (the cache hits), the parts
    # replace the old ones, the report says so
    again = tmp_path / "again"
    code, stdout, stderr = run(
        "decompose",
        str(out / "props.glb"),
        "--out-dir",
        str(again),
        "--to",
        "gltf-physics",
        "--cache-dir",
        str(tmp_path / "cache"),
        "--report",
        "-",
    )
    assert code == 0, stderr
    settings = json.loads(stdout)["settings"]
    n = sum(len(body["outputs"]) for body in report["files"][0]["bodies"])
    assert settings["replaced"] == (
        f"replaced {n} KHR_physics_rigid_bodies and {n} OMI_physics_body collider(s) already "
        "in the asset"
    )
    rewritten = {b.name: b for b in load_inputs([again / "props.glb"]).bodies}
    assert {n: len(b.part_meshes()) for n, b in rewritten.items()} == {
        n: len(b.part_meshes()) for n, b in by_name.items()
    }
    usage = run("decompose", str(asset), str(asset), "--out-dir", str(out), "--to", "gltf-physics")
    assert usage[0] == 2 and "--to gltf-physics needs one glTF/GLB asset and --out-dir" in usage[2]


def test_collision_filters_as_the_khronos_filter_sample_sets_them(tmp_path: Path) -> None:
    # the scenario of glTF_Physics' RigidBodies_CollisionFilter_01: two dynamic balls of one
    # system that never collide with each other, one of them not with the static floor either
    khr = "KHR_physics_rigid_bodies"

    def body(x: float, y: float, shape: int, filter_index: int, dynamic: bool) -> dict:
        ext: dict = {"collider": {"geometry": {"shape": shape}, "collisionFilter": filter_index}}
        if dynamic:
            ext["motion"] = {}
        return {"translation": [x, y, 0.0], "extensions": {khr: ext}}

    document = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_implicit_shapes", khr],
        "nodes": [body(-5, 5, 0, 0, True), body(5, 5, 0, 1, True), body(0, -0.5, 1, 2, False)],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "extensions": {
            "KHR_implicit_shapes": {
                "shapes": [
                    {"type": "sphere", "sphere": {"radius": 1.0}},
                    {"type": "box", "box": {"size": [15.0, 1.0, 15.0]}},
                ]
            },
            khr: {
                "collisionFilters": [
                    {"collisionSystems": ["Dynamic"], "notCollideWithSystems": ["Dynamic"]},
                    {"collisionSystems": ["Dynamic"], "notCollideWithSystems": ["Static"]},
                    {"collisionSystems": ["Static"]},
                ]
            },
        },
    }
    assert physics_schema_problems(document) == []
    path = tmp_path / "filters.gltf"
    path.write_text(json.dumps(document))
    scene = load_inputs([path])
    assert [b.primitive for b in scene.bodies] == [Sphere(1.0), Sphere(1.0), Box((15.0, 1.0, 15.0))]
    assert [(a, b) for a, b, _ in scene.excluded_pairs] == [
        ("filters/node_0", "filters/node_1"),
        ("filters/node_1", "filters/node_2"),
    ]
