"""``--to gltf-physics`` on an asset that already has colliders (:mod:`meshcol.io.gltf_physics_strip`):
the old colliders, KHR and OMI, are replaced by the new ones, made from the render meshes;
everything else in the asset stays; the output says what was replaced."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import test_gltf_physics as base
from test_gltf_physics import glb_document, khr_level, point_gap, run, write_glb

from meshcol.io.gltf_physics_write import physics_schema_problems
from meshcol.io.scene import load_inputs
from meshcol.types import Box

KHR, OMI = "KHR_physics_rigid_bodies", "OMI_physics_body"


@pytest.fixture
def asset(tmp_path: Path) -> Path:
    """test_gltf_physics's asset: two named mesh nodes, a box and a scaled ball."""
    return base.asset.__wrapped__(tmp_path)  # type: ignore[attr-defined]


def decorated(asset: Path, tmp_path: Path) -> Path:
    """The asset with what a studio's file carries besides meshes: extras on the document
    and a node, another extension, a material name."""
    document, binary = glb_document(asset)
    document["extras"] = {"studio": "props v3"}
    document["nodes"][0]["extras"] = {"lod": 0}
    document["nodes"][0].setdefault("extensions", {})["EXT_studio_tag"] = {"tag": "crate"}
    document.setdefault("extensionsUsed", []).append("EXT_studio_tag")
    path = tmp_path / "props.glb"
    write_glb(path, document, binary)
    return path


def test_fit_replaces_the_hulls_an_earlier_run_wrote(asset: Path, tmp_path: Path) -> None:
    from meshcol.analysis.fit import fit

    (tmp_path / "src").mkdir()
    source = decorated(asset, tmp_path / "src")
    first, second = tmp_path / "first", tmp_path / "second"
    assert run("hull", str(source), "--out-dir", str(first), "--to", "gltf-physics")[0] == 0
    code, stdout, stderr = run(
        "fit",
        str(first / "props.glb"),
        "--out-dir",
        str(second),
        "--to",
        "gltf-physics",
        "--shape",
        "box",
        "--format",
        "json",
        "--report",
        "-",
    )
    assert code == 0, stderr
    json.loads(stdout)
    assert stderr.endswith(
        f"written to {second / 'props.glb'} (replaced 2 KHR_physics_rigid_bodies and 2 "
        "OMI_physics_body collider(s) already in the asset)\n"
    ), stderr
    # the boxes are fitted to the render meshes, not to the hulls being replaced
    expected = fit([source], shape="box")
    want = {row["name"]: f.primitive_fit for row, f in zip(expected.bodies, expected.fits)}
    scene = load_inputs([second / "props.glb"])
    assert sorted(b.name for b in scene.bodies) == sorted(want)
    for body in scene.bodies:
        assert isinstance(body.primitive, Box) and body.parts == ()
        ref = want[body.name]
        assert body.primitive.size == pytest.approx(ref.primitive.size, rel=1e-12)
        assert body.pose[:3, 3] == pytest.approx(ref.pose[:3, 3], abs=1e-9)
    before, before_bin = glb_document(source)
    after, after_bin = glb_document(second / "props.glb")
    assert physics_schema_problems(after) == []
    # nothing of the hulls is left: no node, mesh, accessor or byte of theirs
    names = [n.get("name") for n in after["nodes"]]
    assert names == [n.get("name") for n in before["nodes"]] + [
        "crate_collider_00",
        "ball_collider_00",
    ]
    assert len(after["meshes"]) == len(before["meshes"])
    assert len(after["accessors"]) == len(before["accessors"])
    assert len(after_bin) <= len(before_bin) + 8
    assert len(after["extensions"]["OMI_physics_shape"]["shapes"]) == 2
    # and everything else is kept
    assert after["extras"] == {"studio": "props v3"}
    assert after["nodes"][0]["extras"] == {"lod": 0}
    assert after["nodes"][0]["extensions"]["EXT_studio_tag"] == {"tag": "crate"}
    assert "EXT_studio_tag" in after["extensionsUsed"]
    for key in ("materials", "meshes"):
        assert after.get(key) == before.get(key)


def test_hull_again_reads_back_to_the_new_hulls_only(asset: Path, tmp_path: Path) -> None:
    from meshcol.analysis.hull import hull

    first, second = tmp_path / "first", tmp_path / "second"
    assert run("hull", str(asset), "--out-dir", str(first), "--to", "gltf-physics")[0] == 0
    code, _, stderr = run(
        "hull",
        str(first / "props.glb"),
        "--out-dir",
        str(second),
        "--to",
        "gltf-physics",
        "--max-vertices",
        "12",
    )
    assert code == 0, stderr
    expected = hull([asset], max_vertices=12)
    want = {row["name"]: h for row, h in zip(expected.bodies, expected.hulls)}
    scene = load_inputs([second / "props.glb"])
    assert sorted(b.name for b in scene.bodies) == sorted(want)
    for body in scene.bodies:
        points = want[body.name].vertices
        assert len(points) <= 12
        assert point_gap(body.world_vertices(), points) <= 1e-6 * float(np.ptp(points, 0).max())
    document, _ = glb_document(second / "props.glb")
    # 2 render meshes and the 2 new hulls; the first run's 2 hulls are gone
    assert len(document["meshes"]) == 4
    colliders = sorted(str(n.get("name")) for n in document["nodes"] if "_collider_" in n["name"])
    assert colliders == [
        "ball_collider_00",
        "ball_collider_00_geometry",
        "crate_collider_00",
        "crate_collider_00_geometry",
    ]


def test_bodies_triggers_and_filters_of_a_khr_asset_are_kept(tmp_path: Path) -> None:
    source = khr_level(tmp_path)
    out = tmp_path / "out"
    code, _, stderr = run("hull", str(source), "--out-dir", str(out), "--to", "gltf-physics")
    assert code == 0, stderr
    assert "(replaced 5 KHR_physics_rigid_bodies collider(s) already in the asset)" in stderr
    document, _ = glb_document(out / "level.glb")
    assert physics_schema_problems(document) == []
    nodes = {n["name"]: n for n in document["nodes"]}
    # the colliders' own nodes went; the body, its render node and the trigger stayed
    assert set(nodes) == {"cart", "bin", "zone", "bin_collider_00", "bin_collider_00_geometry"}
    cart = nodes["cart"]
    assert cart["extensions"][KHR] == {"motion": {"mass": 2}}
    assert [document["nodes"][c]["name"] for c in cart["children"]] == ["bin"]
    assert "extensions" not in nodes["bin"]  # its collider was itself: taken out
    trigger = nodes["zone"]["extensions"][KHR]["trigger"]["geometry"]["shape"]
    shapes = document["extensions"]["KHR_implicit_shapes"]["shapes"]
    assert shapes[trigger] == {"type": "box", "box": {"size": [1, 2, 3]}}
    assert "collisionFilters" in document["extensions"][KHR]
    scene = load_inputs([out / "level.glb"])
    (body,) = scene.bodies
    assert body.name == "level"
    assert body.collider == "hull"
    low, high = body.world_vertices().min(0), body.world_vertices().max(0)
    assert low == pytest.approx([1.5, -0.5, 4.5], abs=1e-6)  # the bin cube, nothing else
    assert high == pytest.approx([2.5, 0.5, 5.5], abs=1e-6)


def test_bodies_match_their_nodes_by_index_not_by_name(tmp_path: Path) -> None:
    """Two nodes named alike and two unnamed ones, each drawing the unit cube at its own x:
    every body's colliders go under its own node."""
    from test_gltf_physics import gltf_file

    xs = [0.0, 3.0, 6.0, 9.0]
    nodes = [
        {"name": "crate", "mesh": 0, "translation": [xs[0], 0, 0]},
        {"name": "crate", "mesh": 0, "translation": [xs[1], 0, 0]},
        {"mesh": 0, "translation": [xs[2], 0, 0]},
        {"mesh": 0, "translation": [xs[3], 0, 0]},
    ]
    source = gltf_file(tmp_path / "yard.gltf", nodes, {}, [], [3, 2, 1, 0])
    out = tmp_path / "out"
    code, _, stderr = run("hull", str(source), "--out-dir", str(out), "--to", "gltf-physics")
    assert code == 0, stderr
    document, _ = glb_document(out / "yard.glb")
    for k, x in enumerate(xs):
        (child,) = document["nodes"][k]["children"]
        collider = document["nodes"][child]
        assert collider["name"] == f"{nodes[k].get('name', f'node_{k}')}_collider_00"
        geometry = collider["extensions"][KHR]["collider"]["geometry"]["node"]
        matrix = np.asarray(document["nodes"][geometry].get("matrix", np.eye(4).ravel()))
        matrix = matrix.reshape(4, 4).T
        assert matrix[:3, 3] == pytest.approx([x, 0, 0])  # the hull sits where its cube is
    scene = load_inputs([out / "yard.glb"])
    centres = sorted(float(b.world_vertices().mean(0)[0]) for b in scene.bodies)
    assert centres == pytest.approx(xs, abs=1e-6)


# -- Godot hints beside the physics extensions (meshcol.io.gltf_godot) -----------------------


def hinted_level(tmp_path: Path) -> Path:
    from test_gltf_physics import gltf_file

    shapes = {"shapes": [{"type": "box", "box": {"size": [1, 2, 3]}}]}
    nodes = [
        {
            "name": "Crate-convcol",
            "mesh": 0,
            "extensions": {KHR: {"collider": {"geometry": {"shape": 0}}}},
        },
        {
            "name": "Barrel-convcol",
            "mesh": 0,
            "translation": [3, 0, 0],
            "extensions": {KHR: {"collider": {"geometry": {"node": 1, "convexHull": True}}}},
        },
        {"name": "Floor-col", "mesh": 0, "translation": [6, 0, 0]},
        {"name": "Rock-convcolonly", "mesh": 0, "translation": [9, 0, 0]},
        {"name": "Deco", "mesh": 0, "translation": [12, 0, 0]},
        {
            "name": "Cart",
            "translation": [0, 5, 0],
            "children": [6],
            "extensions": {KHR: {"motion": {}}},
        },
        {"name": "Wheel-convcol", "mesh": 0},
    ]
    used = [KHR, "KHR_implicit_shapes"]
    return gltf_file(
        tmp_path / "hinted.gltf", nodes, {"KHR_implicit_shapes": shapes}, used, [0, 1, 2, 3, 4, 5]
    )


def test_physics_extensions_win_and_hints_apply_to_nodes_without_them(tmp_path: Path) -> None:
    scene = load_inputs([hinted_level(tmp_path)])
    bodies = {b.name: b for b in scene.bodies}
    assert set(bodies) == {
        "hinted/Crate",
        "hinted/Barrel",
        "hinted/Floor",
        "hinted/Rock",
        "hinted/Cart",
    }
    # explicit physics wins: the box, not -convcol's hull; the disagreement is said
    assert bodies["hinted/Crate"].primitive == Box((1.0, 2.0, 3.0))
    assert (
        "node 'Crate-convcol': its physics extension's collider (box) is read, not the Godot "
        "hint -convcol (hull)"
    ) in scene.warnings
    # agreeing: a convex-hull collider under -convcol, no warning about it
    assert bodies["hinted/Barrel"].collider == "hull"
    assert not any("Barrel" in w for w in scene.warnings)
    # no physics of their own: the hint decides, as in a file without extensions
    assert bodies["hinted/Floor"].collider == "mesh"
    assert bodies["hinted/Rock"].collider == "hull"
    assert float(bodies["hinted/Floor"].world_vertices()[:, 0].mean()) == pytest.approx(6.0)
    # a hinted mesh inside a rigid body is that body's shape
    assert float(bodies["hinted/Cart"].world_vertices()[:, 1].mean()) == pytest.approx(5.0)
    assert bodies["hinted/Cart"].collider == "hull"
    # Deco has neither: render geometry, counted
    assert any("1 mesh node(s) with no collider of their own" in w for w in scene.warnings)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda d: d.update(extensions=[]), "'extensions' is not an object"),
        (
            lambda d: d["nodes"][5]["extensions"][KHR]["trigger"].update(geometry=7),
            "its physics extensions break their schema: /nodes/5/extensions/",
        ),
        (lambda d: d["scenes"][0].update(nodes=3), "scene 0 nodes is not an array"),
        (lambda d: d["nodes"][2].update(children=1.5), "node 2 children is not an array"),
        (lambda d: d["nodes"][2].update(children=[0]), "node 0's parents form a cycle"),
    ],
)
def test_a_broken_asset_to_rewrite_exits_2_with_one_line(tmp_path: Path, change, words) -> None:
    path = khr_level(tmp_path)
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))
    code, _, stderr = run(
        "hull", str(path), "--out-dir", str(tmp_path / "o"), "--to", "gltf-physics"
    )
    assert code == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"meshcol: error: {path}: cannot parse GLTF file: ")
    assert words in stderr
    assert not (tmp_path / "o" / "level.glb").exists()
