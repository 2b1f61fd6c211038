"""USD stages read as scenes (:mod:`meshcol.io.usd_read`): files written here with usd-core.

Known answers first (a Y-up centimetre stage lands in metres, Z up), then the same scene as
an OBJ file giving the same inspect and check reports, the UsdPhysics approximations each
changing the collider, collision filters, instancing, ``--to usd``'s round trip, bad files.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, Sphere, primitive_mesh

pxr = pytest.importorskip("pxr")
from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics  # noqa: E402

CUBE_POINTS = [(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)]
# the unit cube's six quads, outward (right-handed) winding, indices into CUBE_POINTS
CUBE_QUADS = [
    (0, 1, 3, 2),
    (4, 6, 7, 5),
    (0, 4, 5, 1),
    (2, 3, 7, 6),
    (0, 2, 6, 4),
    (1, 5, 7, 3),
]


def point_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance from a point of either set to the nearest point of the other."""
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def new_stage(path: Path, up: str = "Z", meters: float | None = 1.0) -> Usd.Stage:
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up == "Y" else UsdGeom.Tokens.z)
    if meters is not None:
        UsdGeom.SetStageMetersPerUnit(stage, meters)
    return stage


def add_cube_mesh(
    stage: Usd.Stage, path: str, left_handed: bool = False, quads=CUBE_QUADS
) -> UsdGeom.Mesh:
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in CUBE_POINTS])
    faces = [q[::-1] for q in quads] if left_handed else quads
    mesh.CreateFaceVertexCountsAttr([len(q) for q in faces])
    mesh.CreateFaceVertexIndicesAttr([i for q in faces for i in q])
    if left_handed:
        mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    return mesh


def collision(prim, approximation: str | None = None):
    UsdPhysics.CollisionAPI.Apply(prim.GetPrim())
    if approximation is not None:
        UsdPhysics.MeshCollisionAPI.Apply(prim.GetPrim()).CreateApproximationAttr(approximation)
    return prim


def load(path: Path):
    from meshcol.io.scene import load_inputs

    return load_inputs([path])


# -- the frame: units and up axis ------------------------------------------------------------


def level(tmp_path: Path) -> tuple[Path, dict[str, np.ndarray]]:
    """A Y-up centimetre stage of two cube meshes under transformed Xforms (one left-handed),
    and the world vertices (metres, Z up) each must land on, computed here by hand."""
    path = tmp_path / "level.usda"
    stage = new_stage(path, up="Y", meters=0.01)
    world = UsdGeom.Xform.Define(stage, "/World")
    world.AddTranslateOp().Set(Gf.Vec3d(10.0, 20.0, 30.0))
    world.AddRotateYOp().Set(90.0)
    crate = add_cube_mesh(stage, "/World/crate")
    crate.AddScaleOp().Set(Gf.Vec3f(50.0, 100.0, 50.0))
    shelf = add_cube_mesh(stage, "/World/shelf", left_handed=True)
    shelf.AddTranslateOp().Set(Gf.Vec3d(0.0, 0.0, 200.0))
    shelf.AddScaleOp().Set(Gf.Vec3f(100.0, 100.0, 100.0))
    stage.GetRootLayer().Save()
    cube = np.array(CUBE_POINTS)
    turn_y = np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]])  # rotateY 90 (column vectors)
    y_to_z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])

    def place(local: np.ndarray) -> np.ndarray:
        stage_world = local @ turn_y.T + np.array([10.0, 20.0, 30.0])
        return 0.01 * stage_world @ y_to_z.T

    expected = {
        "crate": place(cube * [50.0, 100.0, 50.0]),
        "shelf": place(cube * 100.0 + [0.0, 0.0, 200.0]),
    }
    return path, expected


def test_y_up_centimetres_land_in_metres_z_up(tmp_path: Path) -> None:
    path, expected = level(tmp_path)
    scene = load(path)
    assert scene.units == "m"
    assert [b.name for b in scene.bodies] == ["level/crate", "level/shelf"]
    for body in scene.bodies:
        want = expected[body.name.split("/")[1]]
        got = body.world_vertices()
        assert got.shape == (8, 3) and len(body.faces) == 12
        assert point_gap(got, want) <= 1e-12
        # outward winding (the left-handed mesh reversed): positive signed volume
        tri = got[body.faces]
        volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
        assert volume > 0
    assert not any("metersPerUnit" in w for w in scene.warnings)


def test_animated_transforms_read_at_their_first_sample(tmp_path: Path) -> None:
    path = tmp_path / "anim.usda"
    stage = new_stage(path)
    mesh = add_cube_mesh(stage, "/cube")
    op = mesh.AddTranslateOp()
    op.Set(Gf.Vec3d(1.0, 2.0, 3.0), 10.0)  # time samples only, no default
    op.Set(Gf.Vec3d(9.0, 9.0, 9.0), 20.0)
    stage.GetRootLayer().Save()
    low = load(path).bodies[0].world_vertices().min(axis=0)
    assert low == pytest.approx([1.0, 2.0, 3.0], abs=1e-15)


def test_unauthored_units_take_usds_fallbacks_and_say_so(tmp_path: Path) -> None:
    path = tmp_path / "bare.usda"
    stage = Usd.Stage.CreateNew(str(path))
    add_cube_mesh(stage, "/cube")
    stage.GetRootLayer().Save()
    scene = load(path)
    extent = np.ptp(scene.bodies[0].world_vertices(), axis=0)
    assert extent == pytest.approx([0.01, 0.01, 0.01], abs=1e-15)
    assert any("metersPerUnit not authored" in w for w in scene.warnings)
    assert any("upAxis not authored" in w for w in scene.warnings)


def write_obj(path: Path, meshes: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    lines, base = [], 1
    for name, (vertices, faces) in meshes.items():
        lines.append(f"o {name}")
        lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in faces.tolist()]
        base += len(vertices)
    path.write_text("\n".join(lines) + "\n")


def numbers(value, path=""):
    """Every number of a report with where it is (names and strings compared apart)."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield from numbers(item, f"{path}.{key}")
    elif isinstance(value, list):
        for k, item in enumerate(value):
            yield from numbers(item, f"{path}[{k}]")
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield path, float(value)


def assert_same_report(usd: dict, obj: dict, size: float, skip: tuple[str, ...]) -> None:
    a, b = dict(numbers(usd)), dict(numbers(obj))
    a = {k: v for k, v in a.items() if not any(word in k for word in skip)}
    b = {k: v for k, v in b.items() if not any(word in k for word in skip)}
    assert a.keys() == b.keys()
    for key in a:
        assert a[key] == pytest.approx(b[key], abs=1e-9 * size, rel=1e-9), key


@pytest.mark.parametrize("command", ["inspect", "check"])
def test_inspect_and_check_match_the_same_scene_as_obj(tmp_path: Path, command: str) -> None:
    path, _ = level(tmp_path)
    scene = load(path)
    obj = tmp_path / "level.obj"
    write_obj(obj, {b.name.split("/")[1]: (b.world_vertices(), b.faces) for b in scene.bodies})
    code_usd, out_usd, err = run(command, str(path), "--format", "json")
    assert code_usd in (0, 1), err
    code_obj, out_obj, _ = run(command, str(obj), "--format", "json")
    assert code_usd == code_obj
    usd, ref = json.loads(out_usd), json.loads(out_obj)
    assert usd["units"] == "m" and ref["units"] is None
    names = lambda report: json.dumps(report, sort_keys=True).count("level/")
    assert names(usd) == names(ref) > 0
    size = float(np.ptp(np.concatenate([b.world_vertices() for b in scene.bodies]), axis=0).max())
    assert_same_report(usd, ref, size, skip=(".tool", "timing", "seconds"))


# -- primitives ------------------------------------------------------------------------------


def test_primitives_stay_exact_under_their_transforms(tmp_path: Path) -> None:
    path = tmp_path / "prims.usda"
    stage = new_stage(path)
    cube = collision(UsdGeom.Cube.Define(stage, "/box"))
    cube.CreateSizeAttr(2.0)
    cube.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    cube.AddScaleOp().Set(Gf.Vec3f(1.0, 2.0, 3.0))
    ball = collision(UsdGeom.Sphere.Define(stage, "/ball"))
    ball.CreateRadiusAttr(0.5)
    ball.AddScaleOp().Set(Gf.Vec3f(2.0, 2.0, 2.0))
    pill = collision(UsdGeom.Capsule.Define(stage, "/pill"))
    pill.CreateRadiusAttr(0.1)
    pill.CreateHeightAttr(0.4)
    pill.CreateAxisAttr(UsdGeom.Tokens.x)
    can = collision(UsdGeom.Cylinder.Define(stage, "/can"))
    can.CreateRadiusAttr(0.2)
    can.CreateHeightAttr(0.6)
    can.CreateAxisAttr(UsdGeom.Tokens.y)
    egg = collision(UsdGeom.Sphere.Define(stage, "/egg"))
    egg.AddScaleOp().Set(Gf.Vec3f(1.0, 1.0, 2.0))
    stage.GetRootLayer().Save()
    bodies = {b.name.split("/")[1]: b for b in load(path).bodies}
    assert bodies["box"].primitive == Box((2.0, 4.0, 6.0))
    assert bodies["box"].pose[:3, 3] == pytest.approx([1, 2, 3], abs=1e-15)
    assert bodies["ball"].primitive == Sphere(1.0)
    assert bodies["pill"].primitive == Capsule(0.1, 0.4)
    assert bodies["pill"].pose[:3, 2] == pytest.approx([1, 0, 0], abs=1e-15)  # axis x
    assert bodies["can"].primitive == Cylinder(0.2, 0.6)
    assert bodies["can"].pose[:3, 2] == pytest.approx([0, 1, 0], abs=1e-15)  # axis y
    # a squashed sphere is an ellipsoid, exact; its tessellation stretched as before
    assert bodies["egg"].primitive == Ellipsoid((1.0, 1.0, 2.0))
    assert np.ptp(bodies["egg"].world_vertices(), axis=0) == pytest.approx([2, 2, 4], rel=1e-2)


# -- UsdPhysics: approximations, disabled prims, filters, rigid bodies -------------------------


APPROXIMATION_KINDS = {
    "none": "mesh",
    "convexHull": "hull",
    "convexDecomposition": "decomposed",
    "boundingSphere": "sphere",
    "boundingCube": "box",
    "meshSimplification": "mesh",
}


def test_approximations_decide_each_bodys_collider(tmp_path: Path) -> None:
    from meshcol.analysis.colliders import build_colliders

    path = tmp_path / "approx.usda"
    stage = new_stage(path)
    # an L of two cubes: its hull, box and sphere differ from its triangles
    quads = CUBE_QUADS
    for k, token in enumerate(APPROXIMATION_KINDS):
        mesh = collision(add_cube_mesh(stage, f"/m_{token}", quads=quads), token)
        mesh.AddTranslateOp().Set(Gf.Vec3d(3.0 * k, 0, 0))
        mesh.AddRotateZOp().Set(30.0)
    plain = collision(add_cube_mesh(stage, "/plain"))
    plain.AddTranslateOp().Set(Gf.Vec3d(0, 5, 0))
    stage.GetRootLayer().Save()
    scene = load(path)
    kinds = {b.name.split("/")[1]: b.collider for b in scene.bodies}
    assert kinds == {**{f"m_{t}": k for t, k in APPROXIMATION_KINDS.items()}, "plain": "mesh"}
    assert any("meshSimplification" in w for w in scene.warnings)
    colliders = build_colliders([b for b in scene.bodies if b.collider != "decomposed"], "hull")
    built = dict(zip((b.name.split("/")[1] for b in colliders.bodies), colliders.kinds))
    assert built["m_convexHull"] == "hull"
    assert built["m_none"] == "mesh"
    assert built["m_boundingSphere"] == "sphere"
    assert built["m_boundingCube"] == "box"


def test_disabled_and_render_prims_are_not_bodies(tmp_path: Path) -> None:
    path = tmp_path / "physics.usda"
    stage = new_stage(path)
    collision(add_cube_mesh(stage, "/kept"), "convexHull")
    off = collision(add_cube_mesh(stage, "/off"), "convexHull")
    UsdPhysics.CollisionAPI(off.GetPrim()).CreateCollisionEnabledAttr(False)
    add_cube_mesh(stage, "/render_only")
    stage.GetRootLayer().Save()
    scene = load(path)
    assert [b.name for b in scene.bodies] == ["physics"]
    assert any("collisionEnabled = false" in w for w in scene.warnings)
    assert any("render geometry" in w for w in scene.warnings)


def test_rigid_bodies_are_bodies_of_parts_and_filters_exclude_pairs(tmp_path: Path) -> None:
    path = tmp_path / "rig.usda"
    stage = new_stage(path)
    for name in ("cart", "lid", "wheel"):
        body = UsdGeom.Xform.Define(stage, f"/World/{name}")
        UsdPhysics.RigidBodyAPI.Apply(body.GetPrim())
    for part in ("a", "b"):
        mesh = collision(add_cube_mesh(stage, f"/World/cart/{part}"), "convexHull")
        mesh.AddTranslateOp().Set(Gf.Vec3d(2.0 if part == "b" else 0.0, 0, 0))
    collision(add_cube_mesh(stage, "/World/lid/shell"), "convexHull")
    collision(UsdGeom.Sphere.Define(stage, "/World/wheel/tyre"))
    UsdPhysics.FilteredPairsAPI.Apply(
        stage.GetPrimAtPath("/World/cart")
    ).CreateFilteredPairsRel().AddTarget("/World/lid/shell")
    group = UsdPhysics.CollisionGroup.Define(stage, "/World/group")
    group.GetCollidersCollectionAPI().CreateIncludesRel().AddTarget("/World/wheel")
    group.GetCollidersCollectionAPI().CreateIncludesRel().AddTarget("/World/cart")
    group.CreateFilteredGroupsRel().AddTarget("/World/group")
    stage.GetRootLayer().Save()
    scene = load(path)
    bodies = {b.name: b for b in scene.bodies}
    assert list(bodies) == ["rig/cart", "rig/lid", "rig/wheel"]
    assert bodies["rig/cart"].parts == ("a", "b")
    assert bodies["rig/wheel"].primitive == Sphere(1.0)
    pairs = {(a, b): reason for a, b, reason in scene.excluded_pairs}
    assert set(pairs) == {("rig/cart", "rig/lid"), ("rig/cart", "rig/wheel")}
    assert "FilteredPairsAPI" in pairs[("rig/cart", "rig/lid")]
    assert "CollisionGroup" in pairs[("rig/cart", "rig/wheel")]
    code, out, _ = run("check", str(path), "--format", "json")
    report = json.loads(out)
    assert code in (0, 1)
    checked = {(p["body_a"], p["body_b"]) for p in report["pairs"]}
    assert not checked & set(pairs)
    listed = report["settings"]["excluded_pairs"]
    assert {(p["body_a"], p["body_b"]) for p in listed} == set(pairs)


@pytest.mark.slow  # worker processes start
def test_check_in_workers_keeps_the_stages_filters(tmp_path: Path) -> None:
    test_rigid_bodies_are_bodies_of_parts_and_filters_exclude_pairs(tmp_path)
    path = tmp_path / "rig.usda"
    one = json.loads(run("check", str(path), "--format", "json")[1])
    code, out, _ = run("check", str(path), "--format", "json", "--jobs", "2")
    assert code in (0, 1)
    assert json.loads(out)["settings"]["excluded_pairs"] == one["settings"]["excluded_pairs"] != []


# -- composition: references, instancing, point instancers, usdz, usdc ----------------------


def test_references_instances_and_point_instancers(tmp_path: Path) -> None:
    asset = tmp_path / "asset.usda"
    part = new_stage(asset)
    root = UsdGeom.Xform.Define(part, "/Asset")
    part.SetDefaultPrim(root.GetPrim())
    add_cube_mesh(part, "/Asset/geo")
    part.GetRootLayer().Save()
    path = tmp_path / "yard.usdc"
    stage = new_stage(path)
    for k in range(2):
        prim = stage.DefinePrim(f"/copy{k}")
        prim.GetReferences().AddReference(str(asset))
        prim.SetInstanceable(k == 1)
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(5.0 * k, 0, 0))
    points = UsdGeom.PointInstancer.Define(stage, "/scatter")
    proto = stage.DefinePrim("/scatter/protos/rock")
    proto.GetReferences().AddReference(str(asset))
    points.CreatePrototypesRel().AddTarget(proto.GetPath())
    points.CreateProtoIndicesAttr([0, 0, 0])
    points.CreatePositionsAttr([Gf.Vec3f(0, 10, 0), Gf.Vec3f(0, 20, 0), Gf.Vec3f(0, 30, 0)])
    stage.GetRootLayer().Save()
    scene = load(path)
    names = [b.name for b in scene.bodies]
    # the two references' prims are both /copyK/geo: named by the prim path (instance proxies too)
    assert names == [
        "yard/copy0/geo",
        "yard/copy1/geo",
        "yard/scatter_0",
        "yard/scatter_1",
        "yard/scatter_2",
    ]
    lows = [b.world_vertices().min(axis=0).tolist() for b in scene.bodies]
    assert lows == [[0, 0, 0], [5, 0, 0], [0, 10, 0], [0, 20, 0], [0, 30, 0]]


def test_usdz_reads_like_its_layer(tmp_path: Path) -> None:
    path, _ = level(tmp_path)
    usdz = tmp_path / "level.usdz"
    from pxr import UsdUtils

    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(path)), str(usdz))
    a, b = load(path), load(usdz)
    assert [x.name for x in a.bodies] == [x.name for x in b.bodies]
    for x, y in zip(a.bodies, b.bodies):
        assert np.array_equal(x.world_vertices(), y.world_vertices())


# -- the round trip of --to usd --------------------------------------------------------------


def test_hull_to_usd_reads_back_to_the_same_colliders(tmp_path: Path) -> None:
    pytest.importorskip("yourdfpy")
    import test_robot_write as rw

    from meshcol.analysis.colliders import build_colliders

    urdf = rw.urdf.__wrapped__(tmp_path)  # type: ignore[attr-defined]
    out = tmp_path / "out"
    code, _, err = run("hull", str(urdf), "--out-dir", str(out), "--to", "usd", "--joint", "j1=0.3")
    assert code == 0, err
    robot, expected = rw.computed(urdf, joints={"j1": 0.3})
    scene = load(out / "small.usda")
    assert scene.units == "m" and scene.warnings == ()
    bodies = {b.name.split("/")[1]: b for b in scene.bodies}
    assert set(bodies) == set(expected) | {c.link for c in robot.colliders if c.primitive}
    colliders = build_colliders(list(scene.bodies), "hull")
    poses = colliders.part_poses()
    for k, name in enumerate(b.name.split("/")[1] for b in colliders.bodies):
        own = robot.colliders[[c.link for c in robot.colliders].index(name)]
        start, stop = colliders.body_part_offsets[k : k + 2]
        if own.primitive is not None:
            assert colliders.bodies[k].primitive == own.primitive
            continue
        assert colliders.kinds[k] == "hull"
        for j, want in zip(range(start, stop), expected[name]):
            shapes = colliders.shapes
            local = shapes.vertices[shapes.offsets[j] : shapes.offsets[j + 1]]
            if shapes.kinds[j] != 0:  # the box element, read back exact: its corners
                exact = colliders.bodies[k].part_primitives[colliders.part_label[j]]
                assert shapes.kinds[j] == 2 and isinstance(exact.primitive, Box)
                np.testing.assert_allclose(exact.primitive.size, (0.05, 0.06, 0.07), atol=1e-7)
                local = primitive_mesh(exact.primitive)[0]
            world = local @ poses[j][:3, :3].T + poses[j][:3, 3]
            assert rw.same_points(want, world, 1e-6)


# -- bad files: one line, exit 2 -------------------------------------------------------------


def bad_files(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    path, _ = level(tmp_path)
    crate = tmp_path / "good.usdc"
    Sdf.Layer.FindOrOpen(str(path)).Export(str(crate))
    truncated = tmp_path / "truncated.usdc"
    truncated.write_bytes(crate.read_bytes()[: crate.stat().st_size // 2])
    garbage = tmp_path / "garbage.usda"
    garbage.write_text("def Mesh {{{ nonsense\n")
    a, b = tmp_path / "a.usda", tmp_path / "b.usda"
    a.write_text("#usda 1.0\n(\n    subLayers = [@b.usda@]\n)\n")
    b.write_text("#usda 1.0\n(\n    subLayers = [@a.usda@]\n)\n")
    loop = tmp_path / "loop.usda"
    loop.write_text('#usda 1.0\ndef Xform "A" (references = @loop.usda@</A>) {}\n')
    counts = tmp_path / "counts.usda"
    counts.write_text(
        '#usda 1.0\ndef Mesh "m" {\n  point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n'
        "  int[] faceVertexCounts = [2000000000]\n  int[] faceVertexIndices = [0, 1, 2]\n}\n"
    )
    index = tmp_path / "index.usda"
    index.write_text(
        '#usda 1.0\ndef Mesh "m" {\n  point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n'
        "  int[] faceVertexCounts = [3]\n  int[] faceVertexIndices = [0, 1, 7]\n}\n"
    )
    negative = tmp_path / "negative.usda"
    negative.write_text(
        '#usda 1.0\ndef Mesh "m" {\n  point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n'
        "  int[] faceVertexCounts = [3, -3, 3]\n  int[] faceVertexIndices = [0, 1, 2]\n}\n"
    )
    short = tmp_path / "short.usda"
    short.write_text(
        '#usda 1.0\ndef Mesh "m" {\n  point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n'
        "  int[] faceVertexCounts = [4]\n  int[] faceVertexIndices = [0, 1, 2, 0, 1]\n}\n"
    )
    empty = tmp_path / "empty.usda"
    empty.write_text('#usda 1.0\ndef Xform "nothing" {}\n')
    return {
        "truncated": (truncated, "cannot parse USD file: "),
        "garbage": (garbage, "cannot parse USD file: "),
        "sublayers": (a, "cannot compose USD stage: Sublayer hierarchy"),
        "references": (loop, "cannot compose USD stage: Cycle detected"),
        "counts": (counts, "face vertex counts add up to 2000000000, but there are 3 face vertex"),
        "index": (index, "face vertex index 7 refers to a point the mesh does not have"),
        "negative": (negative, "/m: face 1 has a negative vertex count (-3)"),
        "short": (short, "/m: face vertex counts add up to 4, but there are 5 face vertex"),
        "empty": (empty, "mesh has no faces"),
    }


@pytest.mark.parametrize(
    "case",
    [
        "truncated",
        "garbage",
        "sublayers",
        "references",
        "counts",
        "index",
        "negative",
        "short",
        "empty",
    ],
)
def test_bad_usd_exits_2_with_one_line(tmp_path: Path, case: str) -> None:
    path, words = bad_files(tmp_path)[case]
    for command in ("check", "inspect", "hull"):
        args = [command, str(path)] + (["--format", "json"] if command != "hull" else [])
        code, _, stderr = run(*args)
        if command == "inspect" and code == 1:  # inspect reports an unreadable file
            continue
        assert code == 2, (command, stderr)
        assert stderr.startswith(f"meshcol: error: {path}: ") and stderr.count("\n") == 1
        assert words in stderr


@pytest.mark.slow
def test_decompose_to_usd_reads_back_to_the_same_parts(tmp_path: Path) -> None:
    pytest.importorskip("yourdfpy")
    import test_robot_write as rw

    urdf = rw.urdf.__wrapped__(tmp_path)  # type: ignore[attr-defined]
    out = tmp_path / "out"
    code, _, err = run(
        "decompose",
        str(urdf),
        "--out-dir",
        str(out),
        "--to",
        "usd",
        "--cache-dir",
        str(tmp_path / "cache"),
    )
    assert code == 0, err
    from meshcol.decomposition.options import RunOptions

    cache = RunOptions(cache_dir=str(tmp_path / "cache"))
    robot, expected = rw.computed(urdf, "decompose", run=cache)
    scene = load(out / "small.usda")
    bodies = {b.name.split("/")[1]: b for b in scene.bodies}
    for link, parts in expected.items():
        body = bodies[link]
        assert body.collider == "hull"
        got = [m[1] @ body.pose[:3, :3].T + body.pose[:3, 3] for m in body.part_meshes()]
        meshes = [m for m in got if len(m)]
        for want in parts:
            assert any(rw.same_points(want, mine, 1e-6) for mine in meshes)
