"""Make the FBX test fixtures with Blender (``bpy``), and what Blender says their vertices are.

Run with a Python that has ``bpy`` (``make fbx-fixtures`` installs it into ``.venv-bpy``):

    .venv-bpy/bin/python scripts/make_fbx_fixtures.py tests/data/fbx

One scene, ``level``, is built and exported as binary FBX at several unit scales and axis
settings; for each file, ``<file>.expected.json`` holds Blender's own evaluated world vertices
of every mesh object, in metres, in Blender's frame (right-handed, Z up: meshcol's FBX frame),
and ``level.obj`` the same scene in OBJ, written here at full precision (Blender's OBJ exporter
rounds to 6 decimals), and ``level.glb`` as Blender's glTF exporter writes it (Z up kept),
for the same-report tests.

``level`` and ``rig_yup`` are also written as ASCII FBX (``scripts/fbx_ascii.py``: Blender
writes binary only), with the same expectations. Two scenes. ``level``: render meshes with Unreal collision parts (``UCX_Crate_01``/``_02``,
``UBX_Block_01``, ``USP_Ball_01``, ``UCP_Pill_01``), Godot hints (``Floor-col``,
``Rock-convcolonly``), a material, a camera, a light and an animation (which meshcol
ignores), translated and non-uniformly scaled by dyadic numbers, so that Blender's float32
data is exact and the comparison holds to 1e-9 of the scene's size. ``rig``: parenting three
deep with rotations in four orders; Blender keeps angles as float32 radians (and writes its
axis conversion as such a rotation), so those vertices are what Blender shows to its own
float32 precision only (the JSON marks each object ``exact`` or not).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import bpy
import numpy as np
from fbx_ascii import to_ascii

R90 = math.pi / 2

#: Fixtures also written as ASCII FBX (scripts/fbx_ascii.py).
ASCII = ("level", "rig_yup")
ZUP = {"axis_forward": "Y", "axis_up": "Z"}  # Blender's own frame: no axis conversion
#: (file stem, scene, export options, scene unit scale): the settings the fixtures cover.
EXPORTS = (
    ("level", "level", ZUP, 1.0),
    ("level_quarter", "level", ZUP, 0.25),  # scene unit: 0.25 m per Blender unit
    (
        "level_global4",
        "level",
        ZUP | {"global_scale": 4.0, "apply_scale_options": "FBX_SCALE_ALL"},
        1.0,
    ),
    ("level_yup", "level", {}, 1.0),  # Blender's defaults: -Z forward, Y up, cm in FBX
    ("rig_yup", "rig", {}, 1.0),
    ("rig_xfwd", "rig", {"axis_forward": "X", "axis_up": "-Y"}, 1.0),
)


def _mesh_object(
    name: str,
    build,
    location=(0, 0, 0),
    rotation=(0, 0, 0),
    scale=(1, 1, 1),
    order="XYZ",
    parent=None,
):
    import bmesh  # importable once bpy is

    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    build(bm)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.rotation_mode = order
    obj.location, obj.rotation_euler, obj.scale = location, rotation, scale
    if parent is not None:
        obj.parent = parent
    return obj


def _box(lo=(-1, -1, -1), hi=(1, 1, 1)):
    def build(bm):
        corners = [
            bm.verts.new((x, y, z))
            for x in (lo[0], hi[0])
            for y in (lo[1], hi[1])
            for z in (lo[2], hi[2])
        ]
        for f in (
            (0, 1, 3, 2),
            (4, 6, 7, 5),
            (0, 4, 5, 1),
            (2, 3, 7, 6),
            (0, 2, 6, 4),
            (1, 5, 7, 3),
        ):
            bm.faces.new([corners[i] for i in f])

    return build


def _sphere(radius=1.0, subdivisions=2):
    def build(bm):
        import bmesh

        bmesh.ops.create_icosphere(bm, subdivisions=subdivisions, radius=radius)

    return build


def _capsule(radius=0.5, half=0.5):
    """A UV sphere cut at the equator, each half moved along z by +/- ``half``."""

    def build(bm):
        import bmesh

        bmesh.ops.create_uvsphere(bm, u_segments=8, v_segments=8, radius=radius)
        for v in bm.verts:
            v.co.z += half if v.co.z > 1e-6 else (-half if v.co.z < -1e-6 else 0.0)

    return build


def build_scene(kind: str) -> None:
    """``level``: meshes, collision parts and Godot hints, translated and scaled only;
    ``rig``: a hierarchy three deep with rotations in four orders (Blender keeps angles in
    float32, so its rotations are exact to about 1e-7 only)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if kind == "rig":
        rack = bpy.data.objects.new("Rack", None)
        scene.collection.objects.link(rack)
        rack.rotation_mode = "YXZ"
        rack.location, rack.rotation_euler, rack.scale = (0, 4, 0), (0, R90, R90), (2, 2, 2)
        shelf = _mesh_object(
            "Shelf",
            _box((-1, -0.5, -0.125), (1, 0.5, 0.125)),
            location=(1, 0, 0.5),
            rotation=(0, 0, 2 * R90),
            order="ZYX",
            parent=rack,
        )
        _mesh_object(
            "Bin",
            _box((-0.25, -0.25, 0), (0.25, 0.25, 0.5)),
            location=(0.5, 0, 0.125),
            rotation=(R90, 0, 0),
            order="XZY",
            parent=shelf,
        )
        _mesh_object(
            "Crate",
            _box(),
            location=(4, 0, 1),
            rotation=(R90, 0, R90),
            scale=(1, 0.5, 0.25),
            order="ZXY",
        )
        bpy.context.view_layer.update()
        return
    crate = dict(location=(4, 0, 1), scale=(1, 0.5, 0.25))
    material = bpy.data.materials.new("Wood")
    obj = _mesh_object("Crate", _box(), **crate)
    obj.data.materials.append(material)
    _mesh_object("UCX_Crate_01", _box((-1, -1, -1), (0, 1, 1)), **crate)
    _mesh_object("UCX_Crate_02", _box((0, -1, -1), (1, 1, 1)), **crate)
    ball = _mesh_object("Ball", _sphere(1.0, 2), location=(-4, 0, 1))
    _mesh_object("USP_Ball_01", _sphere(1.0, 1), location=(-4, 0, 1))
    _mesh_object("Block", _box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)), location=(0, -4, 0.5))
    _mesh_object(
        "UBX_Block_01",
        _box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)),
        location=(0, -4, 0.5),
        scale=(1.125, 1.125, 1.125),
    )
    _mesh_object("Pill", _capsule(), location=(-4, -4, 1))
    _mesh_object("UCP_Pill_01", _capsule(0.5, 0.5), location=(-4, -4, 1))
    _mesh_object("Floor-col", _box((-8, -8, -0.25), (8, 8, 0)))
    _mesh_object("Rock-convcolonly", _sphere(0.5, 1), location=(0, 0, 4))
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (0, -10, 4)
    light = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", type="SUN"))
    scene.collection.objects.link(light)
    light.location = (0, 0, 10)
    scene.frame_set(1)
    ball.keyframe_insert("location", frame=1)
    ball.keyframe_insert("location", frame=20)  # at rest: the same location
    bpy.context.view_layer.update()


def world_vertices(scale: float, converted: bool) -> dict[str, dict]:
    """Every mesh object's evaluated vertices in the world, in metres (x ``scale``), its
    polygons, and whether the file holds its transform exactly (``exact``: no rotation in it
    or its parents, and no axis conversion, which Blender writes as a float32 rotation)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    out = {}
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        local = np.array([tuple(v.co) for v in mesh.vertices], dtype=np.float64)
        matrix = np.array(evaluated.matrix_world, dtype=np.float64)
        world = (local @ matrix[:3, :3].T + matrix[:3, 3]) * scale
        chain, rotated = obj, converted
        while chain is not None:
            rotated = rotated or any(abs(a) > 0 for a in chain.rotation_euler)
            chain = chain.parent
        out[obj.name] = {
            "exact": not rotated,
            "vertices": world.tolist(),
            "polygons": [list(p.vertices) for p in mesh.polygons],
        }
        evaluated.to_mesh_clear()
    return out


def write_obj(path: Path, objects: dict[str, dict]) -> None:
    """The scene as OBJ, world coordinates at full precision, polygons as Blender has them."""
    lines, base = [], 1
    for name, data in objects.items():
        lines.append(f"o {name}")
        lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in data["vertices"]]
        lines += ["f " + " ".join(str(base + i) for i in p) for p in data["polygons"]]
        base += len(data["vertices"])
    path.write_text("\n".join(lines) + "\n")


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for stem, kind, options, unit in EXPORTS:
        build_scene(kind)
        bpy.context.scene.unit_settings.scale_length = unit
        bpy.context.view_layer.update()
        path = out / f"{stem}.fbx"
        bpy.ops.export_scene.fbx(filepath=str(path), **options)
        converted = (options.get("axis_forward"), options.get("axis_up")) != ("Y", "Z")
        expected = world_vertices(unit * options.get("global_scale", 1.0), converted)
        (out / f"{stem}.expected.json").write_text(
            json.dumps(
                {
                    "blender": bpy.app.version_string,
                    "options": options,
                    "unit_scale": unit,
                    "objects": expected,
                }
            )
            + "\n"
        )
        if stem in ASCII:  # Blender writes binary only: the same content as ASCII FBX
            (out / f"{stem}_ascii.fbx").write_text(to_ascii(path.read_bytes()))
            (out / f"{stem}_ascii.expected.json").write_text(
                (out / f"{stem}.expected.json").read_text()
            )
        if stem == "level":
            write_obj(out / "level.obj", expected)
            bpy.ops.export_scene.gltf(
                filepath=str(out / "level.glb"),
                export_format="GLB",
                export_yup=False,
                export_materials="NONE",
                export_animations=False,
                export_cameras=False,
                export_lights=False,
            )
        print(f"wrote {path}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/fbx"))
