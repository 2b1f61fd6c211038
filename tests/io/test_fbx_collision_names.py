"""Collision naming conventions in files: Unreal's UCX_/UBX_/USP_/UCP_ parts and Godot's
name hints, the same in FBX, OBJ and glTF."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import trimesh

import meshcol
from meshcol.analysis.check import check_scene
from meshcol.analysis.check_policy import CheckOptions
from meshcol.analysis.colliders import build_colliders
from meshcol.collision.fit import CONTAINMENT_MARGIN
from meshcol.collision.shapes import ShapeKind
from meshcol.io.collision_names import collision_part, godot_hint
from meshcol.types import Scene

DATA = Path(__file__).resolve().parents[1] / "data" / "fbx"


def test_unreal_names():
    assert collision_part("UBX_Crate_01").kind == "box"
    assert collision_part("USP_Ball_7").kind == "sphere"
    assert collision_part("UCP_Pill_01").kind == "capsule"
    part = collision_part("UCX_Big_Crate_12")
    assert (part.owner, part.index, part.kind) == ("Big_Crate", 12, "convex")
    for name in ("UCX_Crate", "ubx_Crate_01", "Crate", "UXX_Crate_01", "UBX__01"):
        assert collision_part(name) is None, name


def test_godot_hints():
    cases = {
        "Floor-col": ("Floor", "mesh"),
        "Floor-colonly": ("Floor", "mesh"),
        "Rock-convcol": ("Rock", "hull"),
        "Rock-convcolonly": ("Rock", "hull"),
        "Cart-rigid": ("Cart", None),
    }
    for name, (base, collider) in cases.items():
        hint = godot_hint(name)
        assert (hint.name, hint.collider) == (base, collider), name
    assert godot_hint("-col") is None and godot_hint("Rock-collar") is None


def _colliders(path, kind):
    return build_colliders(meshcol.load_mesh(path), kind)


def _primitives(colliders):
    """Per body name, the (kind, params) of each primitive part."""
    out = {}
    shapes = colliders.shapes
    for part, body in enumerate(colliders.part_body.tolist()):
        kind = ShapeKind(int(shapes.kinds[part]))
        if kind != ShapeKind.POLYTOPE:
            name = colliders.bodies[body].name.split("/")[1]
            out.setdefault(name, []).append((kind, shapes.params[part].tolist()))
    return out


pytest.importorskip("ufbx", reason="reading FBX needs ufbx (pip install 'meshcol[fbx]')")


@pytest.mark.parametrize("file", ["level.fbx", "level.obj", "level.glb"])
def test_decomposed_uses_unreal_parts_primitives_exact(file):
    colliders = _colliders(DATA / file, "decomposed")
    names = [b.name.split("/")[1] for b in colliders.bodies]
    hints = not file.endswith(".obj")  # Godot's hints: glTF and FBX
    floor = "Floor" if hints else "Floor-col"
    rock = "Rock" if hints else "Rock-convcolonly"
    assert names == ["Crate", "Ball", "Block", "Pill", floor, rock]  # parts are no bodies
    kinds = dict(zip(names, colliders.kinds))
    assert kinds["Crate"] == kinds["Ball"] == kinds["Block"] == kinds["Pill"] == "ucx"
    crate = names.index("Crate")
    offsets = colliders.body_part_offsets
    assert offsets[crate + 1] - offsets[crate] == 2  # UCX_Crate_01 and _02, as given
    primitives = _primitives(colliders)
    ((sphere, (radius, *_)),) = primitives["Ball"]
    assert sphere == ShapeKind.SPHERE and radius == pytest.approx(1.0, abs=1e-6)
    ((box, half),) = primitives["Block"]
    assert box == ShapeKind.BOX and np.allclose(half[:3], 0.5625, atol=1e-8)  # 1.125 / 2
    ((capsule, (radius, half_length, *_)),) = primitives["Pill"]
    assert capsule == ShapeKind.CAPSULE
    assert (radius, half_length) == pytest.approx((0.5, 0.5), abs=1e-6)


def test_a_ubx_part_changes_the_check_as_stated():
    """The UBX_ box is 1/8 larger than Block: under decomposed it sinks 0.0625 m into the
    floor (its hull here: ``Floor-col`` asks for triangles, which the mesh phase would take
    for Block too), which Block's own hull only touches."""
    bodies = [
        dataclasses.replace(b, collider=None) if b.name == "level/Floor" else b
        for b in meshcol.load_mesh(DATA / "level.fbx")
    ]
    scene = Scene(bodies=tuple(bodies), units="m", source=None)

    def pair(shape):
        report = check_scene(scene, CheckOptions(collider=shape))
        (found,) = [
            p for p in report.pairs if {p["body_a"], p["body_b"]} == {"level/Block", "level/Floor"}
        ]
        return found

    assert pair("hull")["status"] == "contact"
    decomposed = pair("decomposed")
    assert decomposed["status"] == "penetrating"
    # the box encloses the part with the fits' margin of 1e-9 of its extent (1.125 m)
    margin = CONTAINMENT_MARGIN * 1.125
    assert decomposed["depth"] == pytest.approx(0.0625 + margin, abs=1e-12)


def test_godot_hints_set_the_collider_in_fbx_and_glb(tmp_path):
    bodies = {b.name: b for b in meshcol.load_mesh(DATA / "level.fbx")}
    assert bodies["level/Floor"].collider == "mesh"
    assert bodies["level/Rock"].collider == "hull"
    assert bodies["level/Crate"].collider is None
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(), node_name="Crate-convcolonly", geom_name="a")
    scene.add_geometry(trimesh.creation.icosphere(), node_name="Cart-rigid", geom_name="b")
    path = tmp_path / "props.glb"
    scene.export(path)
    glb = {b.name: b.collider for b in meshcol.load_mesh(path)}
    assert glb == {"props/Crate": "hull", "props/Cart": None}
    # OBJ has no hints: Godot imports an OBJ as one mesh
    assert {b.name.split("/")[1] for b in meshcol.load_mesh(DATA / "level.obj")} >= {"Floor-col"}


def test_a_primitive_part_naming_nothing_is_warned_as_ucx_parts_are(tmp_path):
    path = tmp_path / "props.obj"
    box = trimesh.creation.box()
    lines = []
    for k, name in enumerate(("Crate", "UBX_Nothing_01")):
        lines.append(f"o {name}")
        lines += [f"v {x} {y} {z}" for x, y, z in box.vertices + [3 * k, 0, 0]]
        base = 1 + 8 * k
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in box.faces]
    path.write_text("\n".join(lines) + "\n")
    colliders = _colliders(path, "decomposed")
    (warning,) = colliders.warnings
    assert warning.startswith("'props/UBX_Nothing_01' name no body 'Nothing' in the inputs")
    (kind, half) = _primitives(colliders)["Nothing"][0]
    assert kind == ShapeKind.BOX and np.allclose(half[:3], 0.5)
