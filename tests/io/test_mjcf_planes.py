"""MJCF planes checked as half-spaces (``ShapeKind.HALFSPACE``, ``RobotOptions.half_spaces``).

Oracles: each shape's lowest point along the plane's normal in closed form (sphere, box,
capsule, cylinder, ellipsoid, a mesh's lowest vertex) against a tilted, offset plane, with the
body placed separated, touching and penetrating; the invariant that moving a body by t along
the normal changes its signed distance by t; and MuJoCo itself: ``mj_collision`` with the
planes' margins raised reports a contact ``dist`` for every plane pair it tests, which must
equal meshcol's signed distance, pair for pair, with the same pairs filtered out.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from strategies import rotation_from_quaternion

mujoco = pytest.importorskip("mujoco", reason="MuJoCo compiles the models (the test extras)")

from meshcol.analysis.check import check  # noqa: E402
from meshcol.collision.narrowphase import signed_distance_batch  # noqa: E402
from meshcol.collision.shapes import ConvexSet, ShapeKind  # noqa: E402
from meshcol.io.robot import RobotOptions, load_robot  # noqa: E402
from meshcol.types import Box, Capsule, Cylinder, Ellipsoid, HalfSpace, Sphere  # noqa: E402

#: A tilted, offset floor: its normal and a point of it.
NORMAL = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
ORIGIN = np.array([0.1, -0.2, 0.3])
#: An irregular polytope (a mesh asset), in its own frame.
MESH = np.array(
    [[0.1, 0.0, -0.2], [0.3, 0.1, 0.05], [-0.2, 0.25, 0.1], [0.0, -0.3, 0.2], [0.05, 0.05, 0.3]]
)


def _text(values) -> str:
    """Numbers as MJCF reads them, to the bit."""
    return " ".join(repr(float(v)) for v in np.ravel(values))


#: name -> (MJCF geom attributes, the lowest point's height below the centre along n, given
#: the body's rotation R): the closed forms of each shape's support in -n.
SHAPES = {
    "sphere": ('type="sphere" size="0.2"', lambda r: 0.2),
    "box": ('type="box" size="0.1 0.2 0.3"', lambda r: np.abs(r.T @ NORMAL) @ [0.1, 0.2, 0.3]),
    "capsule": (
        'type="capsule" size="0.1 0.25"',
        lambda r: 0.1 + 0.25 * abs(r[:, 2] @ NORMAL),
    ),
    "cylinder": (
        'type="cylinder" size="0.15 0.2"',
        lambda r: (
            0.15 * np.sqrt(max(0.0, 1 - (r[:, 2] @ NORMAL) ** 2)) + 0.2 * abs(r[:, 2] @ NORMAL)
        ),
    ),
    "ellipsoid": (
        'type="ellipsoid" size="0.1 0.2 0.3"',
        lambda r: np.linalg.norm((r.T @ NORMAL) * [0.1, 0.2, 0.3]),
    ),
    "mesh": ('type="mesh" mesh="rock"', lambda r: -min(MESH @ r.T @ NORMAL)),
}
QUAT = np.array([0.9, 0.2, -0.3, 0.25])


def _scene(tmp_path: Path, heights: dict[str, float], extra: str = "", contact: str = "") -> Path:
    """A plane and one free body per shape, each placed so that its lowest point lies
    ``heights[name]`` above the plane (closed form)."""
    rotation = rotation_from_quaternion(QUAT)
    bodies = []
    for k, (name, height) in enumerate(heights.items()):
        attributes, below = SHAPES[name]
        centre = ORIGIN + np.array([0.8 * k - 2.0, 0.5 * (k % 2), 0.0])
        centre = centre - (centre - ORIGIN) @ NORMAL * NORMAL  # on the plane
        centre = centre + (height + below(rotation)) * NORMAL
        bodies.append(
            f'<body name="{name}" pos="{_text(centre)}" '
            f'quat="{_text(QUAT)}"><freejoint/><geom {attributes}/></body>'
        )
    vertices = _text(MESH)
    xml = (
        f'<mujoco><asset><mesh name="rock" vertex="{vertices}"/></asset><worldbody>'
        f'<geom name="floor" type="plane" size="0 0 1" pos="{_text(ORIGIN)}" '
        f'zaxis="{_text(NORMAL)}"/>{extra}{"".join(bodies)}</worldbody>'
        f"<contact>{contact}</contact></mujoco>"
    )
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    return path


def _plane_rows(path: Path, **options) -> dict[str, dict]:
    report = check(str(path), clearance=10.0, **options).to_dict()
    return {
        (row["body_a"] if row["body_b"] == "world/floor" else row["body_b"]): row
        for row in report["pairs"]
        if "world/floor" in (row["body_a"], row["body_b"])
    }


@pytest.mark.parametrize("height", [0.05, 0.0, -0.03])
@pytest.mark.parametrize("shape", ["hull", "mesh"])
def test_every_shape_against_a_tilted_plane_is_its_lowest_point(tmp_path, height, shape) -> None:
    path = _scene(tmp_path, dict.fromkeys(SHAPES, height))
    rows = _plane_rows(path, collider=shape)
    assert set(rows) == set(SHAPES)
    for name, row in rows.items():
        # MuJoCo keeps a mesh's vertices in float32 (moved to its inertial frame first)
        exact = 1e-7 if name == "mesh" else 1e-12
        assert row["signed_distance"] == pytest.approx(height, abs=exact), name
        floor_is_a = row["body_a"] == "world/floor"
        point = np.array(row["point_b" if floor_is_a else "point_a"])
        foot = np.array(row["point_a" if floor_is_a else "point_b"])
        assert (point - ORIGIN) @ NORMAL == pytest.approx(height, abs=exact)
        assert (foot - ORIGIN) @ NORMAL == pytest.approx(0.0, abs=1e-12)
        expected = "separated" if height > 0.01 else ("contact" if height == 0 else "penetrating")
        if height > 0:
            expected = "clearance"
        assert row["status"] == expected, name
        if height < 0:
            assert row["depth"] == pytest.approx(-height, abs=exact)
            assert row["depth_upper"] == row["depth"]  # exact: the lowest point's depth


def test_the_plane_body_is_reported_as_a_plane(tmp_path) -> None:
    report = check(str(_scene(tmp_path, {"sphere": 0.5}))).to_dict()
    (floor,) = [b for b in report["bodies"] if b["name"] == "world/floor"]
    assert floor["collider"] == "plane"
    assert floor["aabb"] == [None, None]  # unbounded corners: null
    assert report["summary"]["candidate_pairs"] == 0  # 0.5 above, no clearance asked


def test_other_commands_leave_planes_out(tmp_path) -> None:
    path = _scene(tmp_path, {"sphere": 0.5})
    assert [b.name for b in load_robot(path).bodies] == ["sphere"]
    with_planes = load_robot(path, RobotOptions(half_spaces=True))
    assert [b.name for b in with_planes.bodies] == ["sphere", "world/floor"]
    assert isinstance(with_planes.bodies[1].primitive, HalfSpace)


_SHAPES = {
    "sphere": Sphere(0.3),
    "box": Box((0.2, 0.5, 0.7)),
    "capsule": Capsule(0.1, 0.4),
    "cylinder": Cylinder(0.2, 0.3),
    "ellipsoid": Ellipsoid((0.1, 0.3, 0.2)),
    "hull": MESH,
}
unit = st.floats(-1.0, 1.0)


@settings(max_examples=60, deadline=None)
@given(
    name=st.sampled_from(sorted(_SHAPES)),
    axis=st.tuples(unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.1),
    quat=st.tuples(unit, unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.1),
    where=st.tuples(unit, unit, unit),
    t=st.floats(-2.0, 2.0),
    plane_first=st.booleans(),
)
def test_moving_a_body_along_the_normal_moves_its_signed_distance(
    name, axis, quat, where, t, plane_first
) -> None:
    plane = np.eye(4)
    plane[:3, :3] = rotation_from_quaternion(np.array([0.8, *axis]))
    plane[:3, 3] = [0.2, -0.1, 0.05]
    n = plane[:3, 2]
    body = np.eye(4)
    body[:3, :3] = rotation_from_quaternion(np.array(quat))
    body[:3, 3] = where
    moved = body.copy()
    moved[:3, 3] += t * n
    shapes = ConvexSet.from_shapes([HalfSpace(), _SHAPES[name]])
    assert shapes.kinds[0] == ShapeKind.HALFSPACE
    pairs = np.array([[0, 1], [2, 3]]) if plane_first else np.array([[1, 0], [3, 2]])
    poses = np.stack([plane, body, plane, moved])
    found = signed_distance_batch(ConvexSet.concatenate(shapes, shapes), poses, pairs)
    assert found.signed_distance[1] - found.signed_distance[0] == pytest.approx(t, abs=1e-12)
    sign = 1.0 if plane_first else -1.0
    for k in range(2):
        if found.signed_distance[k] != 0.0:
            assert found.normal[k] @ n == pytest.approx(sign * np.sign(1.0), abs=1e-12)


# --- MuJoCo itself ---------------------------------------------------------------------------


def _mujoco_dists(path: Path, keyframe: bool = False) -> dict[str, float]:
    """body -> MuJoCo's smallest contact dist with the floor, every plane margin raised (the
    geom's, its body's compiled one, and a <pair>'s)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    if keyframe:
        data.qpos[:] = model.key_qpos[0]
    planes = np.flatnonzero(np.asarray(model.geom_type) == int(mujoco.mjtGeom.mjGEOM_PLANE))
    model.geom_margin[planes] = 100.0
    model.body_margin[np.asarray(model.geom_bodyid)[planes]] = 100.0
    model.pair_margin[np.isin(model.pair_geom1, planes) | np.isin(model.pair_geom2, planes)] = 100
    mujoco.mj_fwdPosition(model, data)
    out: dict[str, float] = {}
    for contact in data.contact[: data.ncon]:
        g1, g2 = int(contact.geom1), int(contact.geom2)
        if g2 in planes:
            g1, g2 = g2, g1
        if g1 not in planes:
            continue
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[g2]))
        out[body] = min(out.get(body, np.inf), float(contact.dist))
    return out


@pytest.mark.parametrize("height", [0.05, -0.03])
def test_mujoco_measures_every_plane_pair_as_meshcol(tmp_path, height) -> None:
    path = _scene(tmp_path, dict.fromkeys(SHAPES, height))
    theirs = _mujoco_dists(path)
    ours = {name: row["signed_distance"] for name, row in _plane_rows(path).items()}
    assert set(ours) == set(theirs)
    for name in SHAPES:
        # MuJoCo collides an ellipsoid with a plane by its general convex solver
        tolerance = 1e-6 if name == "ellipsoid" else 1e-12
        assert ours[name] == pytest.approx(theirs[name], abs=tolerance), name


def test_filters_are_mujocos(tmp_path) -> None:
    """contype/conaffinity, <exclude>, an explicit <pair>, static bodies and other world
    geoms: the plane pairs meshcol measures are the ones mj_collision tests."""
    extra = (
        '<body name="table" pos="3 3 0.2"><geom type="box" size="0.2 0.2 0.2"/></body>'
        '<geom name="post" type="box" size="0.1 0.1 0.1" pos="-3 -3 0.5"/>'
    )
    heights = {"sphere": 0.1, "box": -0.01, "capsule": 0.2, "cylinder": 0.0}
    path = _scene(tmp_path, heights, extra=extra)
    text = path.read_text()
    text = text.replace(
        'type="box" size="0.1 0.2 0.3"', 'type="box" size="0.1 0.2 0.3" contype="2" conaffinity="0"'
    )
    text = text.replace(
        'type="sphere" size="0.2"', 'type="sphere" size="0.2" contype="0" conaffinity="0"'
    )
    text = text.replace(
        "<contact></contact>",
        '<contact><exclude body1="world" body2="capsule"/>'
        '<pair geom1="floor" geom2="sph"/></contact>',
    )
    text = text.replace('type="sphere"', 'name="sph" type="sphere"')
    path.write_text(text)
    theirs = _mujoco_dists(path)
    ours = {name: row["signed_distance"] for name, row in _plane_rows(path).items()}
    assert set(ours) == set(theirs) == {"sphere", "cylinder"}
    for name, value in theirs.items():
        assert ours[name] == pytest.approx(value, abs=1e-12)
    scene = load_robot(path, RobotOptions(half_spaces=True))
    reasons = {frozenset((a, b)): why for a, b, why in scene.excluded_pairs}
    assert reasons[frozenset(("world/floor", "box"))] == "mjcf contype/conaffinity"
    assert reasons[frozenset(("world/floor", "capsule"))] == "mjcf <exclude>"
    assert reasons[frozenset(("world/floor", "table"))] == "mjcf welded"
    assert reasons[frozenset(("world/floor", "world"))] == "mjcf welded"


def test_a_keyframe_puts_the_feet_on_the_floor(tmp_path) -> None:
    path = _scene(tmp_path, {"sphere": 0.5, "box": 0.5})
    text = path.read_text()
    qpos = mujoco.MjModel.from_xml_path(str(path)).qpos0.copy()
    qpos[2] -= 0.5 / NORMAL[2]  # the sphere straight down: 0.5 along z, 0.5 n_z along n
    text = text.replace("</mujoco>", f'<keyframe><key qpos="{_text(qpos)}"/></keyframe></mujoco>')
    path.write_text(text)
    ours = {
        name: row["signed_distance"]
        for name, row in _plane_rows(path, robot_options=RobotOptions(keyframe=True)).items()
    }
    assert ours["sphere"] == pytest.approx(0.5 - 0.5, abs=1e-12)
    assert ours == pytest.approx(_mujoco_dists(path, keyframe=True), abs=1e-12)


def test_reports_of_every_format_take_a_plane(tmp_path) -> None:
    from meshcol.io.formats import FORMATS, write_report

    path = _scene(tmp_path, {"sphere": -0.02, "box": 0.0})
    report = check(str(path))
    for name in FORMATS:
        out = tmp_path / f"report.{name}"
        write_report(report, name, str(out))
        assert out.stat().st_size > 0, name
    data = json.loads(report.to_json())
    assert {row["status"] for row in data["pairs"]} == {"penetrating", "contact"}
    jsonschema = pytest.importorskip("jsonschema")
    schema = (
        Path(__file__).resolve().parents[2] / "meshcol" / "schemas" / "check_report.schema.json"
    )
    jsonschema.validate(data, json.loads(schema.read_text()))


@settings(max_examples=40, deadline=None)
@given(
    boxes=st.lists(
        st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-5, 5), st.floats(0, 2)),
        min_size=1,
        max_size=12,
    ),
    unbounded=st.lists(st.tuples(st.integers(0, 11), st.integers(0, 5)), max_size=3),
    margin=st.floats(0.0, 1.0),
    grouped=st.booleans(),
)
def test_unbounded_boxes_pair_as_brute_force(boxes, unbounded, margin, grouped) -> None:
    """The sweep with unbounded boxes beside it (half-spaces') == every pair whose grown
    intervals meet, in the sweep's lexicographic order, groups never paired."""
    from meshcol.analysis.pairs import overlapping_pairs

    lo = np.array([[x - s, y - s, z - s] for x, y, z, s in boxes])
    hi = np.array([[x + s, y + s, z + s] for x, y, z, s in boxes])
    for index, sides in unbounded:  # a box made unbounded on some of its sides
        if index < len(boxes):
            lo[index, : sides % 3 + 1] = -np.inf
            if sides > 2:
                hi[index, 2] = np.inf
    groups = np.arange(len(boxes)) // 2 if grouped else None
    found = overlapping_pairs(lo, hi, margin, groups=groups)
    expected = [
        (i, j)
        for i in range(len(boxes))
        for j in range(i + 1, len(boxes))
        if np.all(
            (lo[i] - margin / 2 <= hi[j] + margin / 2) & (lo[j] - margin / 2 <= hi[i] + margin / 2)
        )
        and (groups is None or groups[i] != groups[j])
    ]
    assert sorted(map(tuple, found.tolist())) == expected
    if groups is None:
        assert found.tolist() == [list(p) for p in expected]  # sorted as the sweep sorts


def test_review_page_draws_the_floor_as_a_patch(tmp_path) -> None:
    from meshcol.analysis.review import check_page

    path = _scene(tmp_path, {"sphere": -0.02})
    page = check_page(check(str(path)), [str(path)], "hull", {})
    floor = [m for m in page.meshes() if m.get("name") == "world/floor"]
    assert floor and "world/floor" in page.to_html()
    body = load_robot(path, RobotOptions(half_spaces=True)).bodies[1]
    assert body.name == "world/floor" and len(body.vertices) == 4 and len(body.faces) == 2
    extent = 2.0 * float(mujoco.MjModel.from_xml_path(str(path)).stat.extent)
    assert body.primitive == HalfSpace((extent, extent))  # size 0: twice the model's extent
