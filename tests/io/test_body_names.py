"""Bodies of one file named by where they are (:mod:`meshcol.io.body_names`): the rule against
a brute-force reference, then a USD stage and glTF files as exporters write them (prims and
nodes of one name under different parents), their names in check's reports, in a
configuration's allow list, and through the mesh writers and back."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from gltf_documents import CUBE, cube_document
from hypothesis import given
from hypothesis import strategies as st

from meshcol.cli import main
from meshcol.io import body_names
from meshcol.io.body_names import file_body_names
from meshcol.io.mesh_read import load_mesh


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


# -- the rule ---------------------------------------------------------------------------------


def reference(stem: str, paths: list[tuple[str, ...]], limit: int = 15) -> list[str]:
    """The rule read literally, in O(n^2 d): a unique leaf is the name; else the shortest
    suffix (two names or more) that no other path ends with; else the whole path (its last
    ``limit`` ancestors); then ``#k`` in order for a name taken."""
    paths = [path[-limit - 1 :] for path in paths]
    out = []
    for i, path in enumerate(paths):
        others = [p for j, p in enumerate(paths) if j != i]
        where = path
        if any(p[-1] == path[-1] for p in others):
            for k in range(2, len(path) + 1):
                if all(p[-k:] != path[-k:] for p in others if len(p) >= k):
                    where = path[-k:]
                    break
        else:
            where = path[-1:]
        out.append(f"{stem}/" + "/".join(where))
    if len(paths) == 1:
        return [stem]
    used: set[str] = set()
    named = []
    for name in out:
        unique, k = name, 2
        while unique in used:
            unique, k = f"{name}#{k}", k + 1
        used.add(unique)
        named.append(unique)
    return named


def names_of(paths: list[tuple[str, ...]], stem: str = "level") -> list[str]:
    return file_body_names(stem, [p[-1] for p in paths], [p[:-1] for p in paths])


_PATHS = st.lists(
    st.lists(
        st.sampled_from(["World", "a", "b", "mesh", "geo", "x/y"]), min_size=1, max_size=4
    ).map(tuple),
    min_size=1,
    max_size=12,
)


@given(_PATHS)
def test_the_names_are_the_rule_read_literally(paths: list[tuple[str, ...]]) -> None:
    names = names_of(paths)
    assert names == reference("level", paths)
    assert len(set(names)) == len(names)


@given(_PATHS)
def test_deep_paths_are_cut_to_their_nearest_ancestors(paths: list[tuple[str, ...]]) -> None:
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(body_names, "MAX_ANCESTORS", 1)
        names = names_of(paths)
    assert names == reference("level", paths, limit=1)
    assert len(set(names)) == len(names)


def test_a_chain_of_one_name_makes_names_of_at_most_sixteen_parts() -> None:
    """A hostile chain of nodes all named ``mesh``: every path a suffix of the next, so each
    would be named whole (2,000 parts, and d * d suffixes each to count; the test's own paths
    are n * n / 2 names, so n stays 2,000, far past the 15 ancestors kept)."""
    paths = [("mesh",) * k for k in range(1, 2_001)]
    names = names_of(paths)
    assert len(set(names)) == len(names)
    assert max(n.split("#")[0].count("/") for n in names) == body_names.MAX_ANCESTORS + 1
    assert names[:2] == ["level/mesh", "level/mesh/mesh"]
    deep = "level" + "/mesh" * 16
    assert names[15] == deep and names[16] == f"{deep}#2" and names[-1] == f"{deep}#1985"


#: Paths of names without the separator: a name holding ``/`` can spell another path, and
#: the two then take ``#k`` in file order (the module's rules; ``test_known_names``).
_PLAIN_PATHS = st.lists(
    st.lists(
        st.sampled_from(["World", "a", "b", "mesh", "geo", "x", "y"]), min_size=1, max_size=4
    ).map(tuple),
    min_size=1,
    max_size=12,
)


@given(_PLAIN_PATHS, st.randoms(use_true_random=False))
def test_names_do_not_depend_on_the_order_of_distinct_paths(paths, random) -> None:
    paths = list(dict.fromkeys(paths))  # equal full paths take #k in order: left out here
    order = list(range(len(paths)))
    random.shuffle(order)
    names = dict(zip(paths, names_of(paths)))
    shuffled = [paths[k] for k in order]
    assert dict(zip(shuffled, names_of(shuffled))) == names


def test_known_names() -> None:
    paths = [
        ("World", "crate_01", "mesh"),
        ("World", "crate_02", "mesh"),
        ("World", "bay_1", "crate_01", "mesh"),
        ("World", "bay_2", "crate_01", "mesh"),
        ("World", "floor"),
        ("mesh",),  # a root prim: its whole path is a suffix of the others'
    ]
    assert names_of(paths) == [
        "level/World/crate_01/mesh",
        "level/crate_02/mesh",
        "level/bay_1/crate_01/mesh",
        "level/bay_2/crate_01/mesh",
        "level/floor",
        "level/mesh",
    ]
    # no hierarchy (OBJ), equal full paths (glTF siblings), one body: as before
    assert file_body_names("props", ["a", "a", "b"]) == ["props/a", "props/a#2", "props/b"]
    assert names_of([("p", "m"), ("p", "m"), ("q", "m")]) == [
        "level/p/m",
        "level/p/m#2",
        "level/q/m",
    ]
    assert names_of([("World", "crate", "mesh")]) == ["level"]
    # a name holding the separator can spell another body's path: #2 keeps them apart
    assert names_of([("a/b",), ("a", "b"), ("c", "b")]) == ["level/a/b", "level/a/b#2", "level/c/b"]


def test_ten_thousand_clashing_leaves_are_named_in_one_pass() -> None:
    paths = [("World", f"crate_{k:05d}", "mesh") for k in range(10_000)]
    names = names_of(paths)
    assert names[0] == "level/crate_00000/mesh" and names[-1] == "level/crate_09999/mesh"
    assert len(set(names)) == 10_000


# -- a USD stage as a DCC tool exports it ---------------------------------------------------

try:
    from pxr import Gf, Usd, UsdGeom
except ImportError:  # the rule's, glTF's and FBX's tests still run
    Gf = Usd = UsdGeom = None
needs_usd = pytest.mark.skipif(Usd is None, reason="usd-core is not installed (meshcol[usd])")

#: (prim path of the Xform, translation) of each body; the mesh prim is named last.
PLACED = [
    ("/World/crate_01/mesh", (0.0, 0.0, 0.0)),
    ("/World/crate_02/mesh", (0.5, 0.0, 0.0)),  # penetrates crate_01 by 0.5
    ("/World/crate_03/mesh", (5.0, 0.0, 0.0)),
    ("/World/bay_1/crate_01/mesh", (10.0, 0.0, 0.0)),
    ("/World/bay_2/crate_01/mesh", (10.0, 0.0, 0.75)),  # penetrates bay_1's by 0.25
    ("/World/floor", (0.0, 0.0, -3.0)),
    ("/World/barrel/geo", (20.0, 0.0, 0.0)),
]
NAMES = [
    "level/World/crate_01/mesh",
    "level/crate_02/mesh",
    "level/crate_03/mesh",
    "level/bay_1/crate_01/mesh",
    "level/bay_2/crate_01/mesh",
    "level/floor",  # unique leaves keep their name
    "level/geo",
]


def write_level(path: Path, placed: list = PLACED) -> Path:
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
    for prim_path, offset in placed:
        parent = prim_path.rsplit("/", 1)[0]
        if parent != "/World":
            UsdGeom.Xform.Define(stage, parent).AddTranslateOp().Set(Gf.Vec3d(*offset))
        mesh = UsdGeom.Mesh.Define(stage, prim_path)
        if parent == "/World":
            mesh.AddTranslateOp().Set(Gf.Vec3d(*offset))
        mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in CUBE.vertices.tolist()])
        mesh.CreateFaceVertexCountsAttr([3] * len(CUBE.faces))
        mesh.CreateFaceVertexIndicesAttr(CUBE.faces.ravel().tolist())
    stage.GetRootLayer().Save()
    return path


def penetrating(report: dict) -> set[frozenset[str]]:
    return {
        frozenset((p["body_a"], p["body_b"]))
        for p in report["pairs"]
        if p["status"] == "penetrating"
    }


@needs_usd
def test_a_stage_of_repeated_prim_names_names_bodies_by_prim_path(tmp_path: Path) -> None:
    level = write_level(tmp_path / "level.usda")
    bodies = load_mesh(level)
    assert [b.name for b in bodies] == NAMES
    lows = [b.world_vertices().min(axis=0) for b in bodies]
    offsets = [np.asarray(offset) - 0.5 for _, offset in PLACED]
    np.testing.assert_allclose(lows, offsets, atol=1e-12)  # each name is its own prim's
    code, out, err = run("check", str(level), "--fail-on", "penetration", "--report", "-")
    assert code == 1, err
    report = json.loads(out)
    assert sorted(b["name"] for b in report["bodies"]) == sorted(NAMES)
    assert penetrating(report) == {
        frozenset(("level/World/crate_01/mesh", "level/crate_02/mesh")),
        frozenset(("level/bay_1/crate_01/mesh", "level/bay_2/crate_01/mesh")),
    }
    for fmt, text in (("github", "level/bay_2/crate_01/mesh"), ("sarif", "level/crate_02/mesh")):
        code, out, err = run("check", str(level), "--fail-on", "penetration", "--format", fmt)
        assert code == 1 and text in out, err
    code, out, _ = run("check", str(level), "--fail-on", "penetration", "--format", "junit")
    assert code == 1 and "level/World/crate_01/mesh" in out


@needs_usd
def test_an_allow_list_names_the_bodies_by_their_paths(tmp_path: Path, monkeypatch) -> None:
    write_level(tmp_path / "level.usda")
    monkeypatch.chdir(tmp_path)
    scenes = '[[scenes]]\npath = "level.usda"\ncheck = {{ fail-on = "penetration" }}\n{}'
    Path("meshcol.toml").write_text(scenes.format(""))
    code, _, err = run("ci", "--report", "failing.json")
    assert code == 1, err
    allow = (
        'ignore = [{ pair = "level/bay_*/crate_01/mesh:level/bay_*/crate_01/mesh", '
        'reason = "stacked" }, { pair = "level/crate_02/mesh:level/World/crate_01/mesh", '
        'reason = "nested on purpose" }]\n'
    )
    Path("meshcol.toml").write_text(scenes.format(allow))
    code, _, err = run("ci", "--report", "passing.json")
    assert code == 0, err
    (check,) = json.loads(Path("passing.json").read_text())["runs"]
    ignored = {
        frozenset((p["body_a"], p["body_b"])) for p in check["report"]["pairs"] if p["ignored"]
    }
    assert ignored == penetrating(check["report"])
    assert len(ignored) == 2


@needs_usd
def test_the_names_survive_the_mesh_writers(tmp_path: Path) -> None:
    level = write_level(tmp_path / "level.usda")
    for out in ("hulls.glb", "hulls.obj"):
        code, _, err = run("hull", str(level), "-o", str(tmp_path / out))
        assert code == 0, err
        # the names are the written objects' and nodes': they read back behind the new stem
        assert [b.name for b in load_mesh(tmp_path / out)] == [
            n.replace("level/", "hulls/level/", 1) for n in NAMES
        ]
    scene = trimesh.load_scene(tmp_path / "hulls.glb")  # another reader of the GLB
    assert set(NAMES) <= set(scene.graph.nodes)
    code, _, err = run("hull", str(level), "--out-dir", str(tmp_path / "parts"))
    assert code == 0, err
    files = sorted(p.name for p in (tmp_path / "parts").iterdir())
    assert "level_World_crate_01_mesh.obj" in files and "level_bay_2_crate_01_mesh.obj" in files
    assert len(files) == len(NAMES)


# -- glTF: nodes of one name under different parents --------------------------------------


SHELF = [
    {"name": "Shelf", "children": [1, 3, 5, 6]},
    {"name": "crate_01", "children": [2], "translation": [0, 0, 0]},
    {"name": "mesh", "mesh": 0},
    {"name": "crate_02", "children": [4], "translation": [0.5, 0, 0]},
    {"name": "mesh", "mesh": 0},
    {"name": "lid", "mesh": 0, "translation": [5, 0, 0]},
    {"name": "lid", "mesh": 0, "translation": [7, 0, 0]},  # a sibling of one name
]


def test_gltf_nodes_of_one_name_are_named_by_their_parents(tmp_path: Path) -> None:
    path = tmp_path / "shelf.gltf"
    path.write_text(json.dumps(cube_document(SHELF, [0])))
    names = ["shelf/crate_01/mesh", "shelf/crate_02/mesh", "shelf/Shelf/lid", "shelf/Shelf/lid#2"]
    assert sorted(b.name for b in load_mesh(path)) == sorted(names)
    by_name = {b.name: b.world_vertices().min(axis=0)[0] for b in load_mesh(path)}
    assert by_name["shelf/crate_02/mesh"] == pytest.approx(0.0)  # 0.5 - 0.5: its own node's
    assert by_name["shelf/Shelf/lid"] == pytest.approx(4.5)
    code, out, err = run("check", str(path), "--fail-on", "penetration", "--report", "-")
    assert code == 1, err
    assert penetrating(json.loads(out)) == {
        frozenset(("shelf/crate_01/mesh", "shelf/crate_02/mesh"))
    }


def test_a_node_of_several_primitives_is_one_body_named_the_same_every_read(
    tmp_path: Path,
) -> None:
    """trimesh names each primitive's frame ``<node>_<random hash>``: bodies were named so,
    a different name each read (and --to gltf-physics could not find them again). A node is
    one object: its primitives (material groups) are one body, never a pair of their own,
    and the body keeps its name through --to gltf-physics."""
    nodes = [
        {"name": "rack", "mesh": 1, "translation": [0, 2, 0]},
        {"name": "bin", "mesh": 0, "translation": [3, 0, 0]},
    ]
    path = tmp_path / "rack.gltf"
    path.write_text(json.dumps(cube_document(nodes, [0, 1], primitives=2)))
    first, again = ([b.name for b in load_mesh(path)] for _ in range(2))
    assert first == again
    assert first == ["rack/rack", "rack/bin"]  # the document's node order
    rack = load_mesh(path)[0]
    assert len(rack.faces) == 24  # both primitives (their equal corners merged on reading)
    world = rack.world_vertices()  # in the node's frame: the unit cube moved up by 2
    np.testing.assert_allclose(
        [world.min(axis=0), world.max(axis=0)], [[-0.5, 1.5, -0.5], [0.5, 2.5, 0.5]]
    )
    code, out, err = run("check", str(path), "--report", "-")
    assert code == 0 and penetrating(json.loads(out)) == set(), err  # the two cubes: one body
    # --to gltf-physics finds each body's node again by its name (it could not: exit 2)
    code, _, err = run(
        "hull", str(path), "--out-dir", str(tmp_path / "out"), "--to", "gltf-physics"
    )
    assert code == 0, err
    assert sorted(b.name for b in load_mesh(tmp_path / "out" / "rack.glb")) == [
        "rack/bin",
        "rack/rack",
    ]


def test_the_fbx_reader_gives_each_nodes_ancestors() -> None:
    pytest.importorskip("ufbx")
    from meshcol.io.fbx import read_fbx

    rig = Path(__file__).parent.parent / "data" / "fbx" / "rig_yup.fbx"
    nodes = read_fbx(rig, str(rig))
    assert [(node[0], node[4]) for node in nodes] == [
        ("Crate", ()),
        ("Shelf", ("Rack",)),
        ("Bin", ("Rack", "Shelf")),
    ]


def test_gltf_physics_bodies_of_one_name_are_named_by_their_parents(tmp_path: Path) -> None:
    khr = "KHR_physics_rigid_bodies"
    collider = {khr: {"collider": {"geometry": {"node": 2}}}}
    nodes = [
        {"name": "bay_1", "children": [1]},
        {"name": "crate", "extensions": {khr: {"motion": {}}}, "children": [2]},
        {"name": "hull", "mesh": 0, "extensions": collider},
        {"name": "bay_2", "children": [4], "translation": [0.5, 0, 0]},
        {"name": "crate", "extensions": {khr: {"motion": {}}}, "children": [5]},
        {"name": "hull", "mesh": 0, "extensions": {khr: {"collider": {"geometry": {"node": 5}}}}},
    ]
    document = cube_document(nodes, [0, 3])
    document["extensionsUsed"] = [khr]
    path = tmp_path / "bays.gltf"
    path.write_text(json.dumps(document))
    code, out, err = run("check", str(path), "--fail-on", "penetration", "--report", "-")
    assert code == 1, err
    assert penetrating(json.loads(out)) == {frozenset(("bays/bay_1/crate", "bays/bay_2/crate"))}


@needs_usd
def test_every_permutation_of_a_file_names_each_prim_alike(tmp_path: Path) -> None:
    """The names of the stage's bodies whatever order its prims are written in."""
    expected = dict(zip((p for p, _ in PLACED), NAMES))
    rng = np.random.default_rng(0)
    for k in range(8):
        placed = [PLACED[i] for i in rng.permutation(len(PLACED))]
        (tmp_path / str(k)).mkdir()
        path = write_level(tmp_path / str(k) / "level.usda", placed)
        named = {b.name: b.world_vertices().min(axis=0) for b in load_mesh(path)}
        assert set(named) == set(expected.values())
        for prim_path, offset in placed:
            np.testing.assert_allclose(named[expected[prim_path]], np.asarray(offset) - 0.5)


# -- the robot writers: link names of the same shape ----------------------------------------

ROBOT = """<robot name="shelf">
  <link name="level/World/crate_01/mesh"><collision>
    <geometry><mesh filename="box.obj"/></geometry></collision></link>
  <link name="level/crate_02/mesh"><collision><origin xyz="0.5 0 0"/>
    <geometry><mesh filename="box.obj"/></geometry></collision></link>
  <link name="level/bay_1/crate_01/mesh"><collision><origin xyz="3 0 0"/>
    <geometry><box size="1 1 1"/></geometry></collision></link>
  <joint name="turn" type="revolute">
    <parent link="level/World/crate_01/mesh"/><child link="level/crate_02/mesh"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="weld" type="fixed">
    <parent link="level/World/crate_01/mesh"/><child link="level/bay_1/crate_01/mesh"/></joint>
</robot>
"""
LINKS = ["level/World/crate_01/mesh", "level/crate_02/mesh", "level/bay_1/crate_01/mesh"]


@needs_usd
def test_names_of_this_shape_survive_every_robot_writer_and_its_consumer(tmp_path: Path) -> None:
    """Link names holding ``/`` (as these body names do) through --to urdf, mjcf, usd and
    collision-matrix's SRDF, each read by the tool that consumes it."""
    mujoco = pytest.importorskip("mujoco")
    yourdfpy = pytest.importorskip("yourdfpy")
    CUBE.export(tmp_path / "box.obj")
    robot = tmp_path / "shelf.urdf"
    robot.write_text(ROBOT)
    for to in ("urdf", "mjcf", "usd"):
        code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / to), "--to", to)
        assert code == 0, err
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "mjcf" / "shelf.xml"))
    assert [model.body(i).name for i in range(1, model.nbody)] == LINKS
    assert list(yourdfpy.URDF.load(str(tmp_path / "urdf" / "shelf.urdf")).link_map) == LINKS
    stage = Usd.Stage.Open(str(tmp_path / "usd" / "shelf.usda"))
    prims = [p for p in stage.Traverse() if p.GetCustomDataByKey("meshcol:link")]
    assert [p.GetName() for p in prims] == [n.replace("/", "_") for n in LINKS]  # valid names
    assert [p.GetCustomDataByKey("meshcol:link") for p in prims] == LINKS
    assert [b.name for b in load_mesh(tmp_path / "usd" / "shelf.usda")] == [
        f"shelf/{n}" for n in LINKS
    ]
    srdf = tmp_path / "shelf.srdf"
    code, _, err = run("collision-matrix", str(robot), "--samples", "20", "-o", str(srdf))
    assert code == 0, err
    assert 'link1="level/bay_1/crate_01/mesh" link2="level/crate_02/mesh"' in srdf.read_text()
    code, out, err = run("check", str(robot), "--srdf", str(srdf), "--report", "-")
    assert code == 0, err
    excluded = json.loads(out)["settings"]["excluded_pairs"]
    assert {"body_a": LINKS[2], "body_b": LINKS[1], "reason": "srdf: Never"} in excluded


def test_pybullet_loads_the_written_urdf(tmp_path: Path) -> None:
    pybullet = pytest.importorskip("pybullet")
    CUBE.export(tmp_path / "box.obj")
    robot = tmp_path / "shelf.urdf"
    robot.write_text(ROBOT)
    code, _, err = run("hull", str(robot), "--out-dir", str(tmp_path / "out"), "--to", "urdf")
    assert code == 0, err
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(tmp_path / "out" / "shelf.urdf"), physicsClientId=client)
        links = [
            pybullet.getJointInfo(body, j, physicsClientId=client)[12].decode()
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))
        ]
        base = pybullet.getBodyInfo(body, physicsClientId=client)[0].decode()
    finally:
        pybullet.disconnect(client)
    assert [base, *links] == LINKS


def test_a_deep_gltf_chain_is_named_by_its_nearest_nodes(tmp_path: Path) -> None:
    nodes = [{"name": "mesh", "mesh": 0, "children": [k + 1]} for k in range(29)]
    path = tmp_path / "chain.gltf"
    path.write_text(json.dumps(cube_document([*nodes, {"name": "mesh", "mesh": 0}], [0])))
    names = [b.name for b in load_mesh(path)]
    deep = "chain" + "/mesh" * 16
    assert names[:2] == ["chain/mesh", "chain/mesh/mesh"]
    assert names[15:17] == [deep, f"{deep}#2"] and names[-1] == f"{deep}#15"
