"""One body is one body: parts of a manifest body, UCX matching, degenerate bodies.

The same collider rules in ``check`` and ``sweep`` (both build their colliders with
``analysis.colliders.build_colliders``).
"""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

import meshcol
from meshcol.analysis.colliders import build_colliders
from meshcol.cli import main
from meshcol.io.mesh_write import obj_text
from meshcol.io.scene import load_inputs
from meshcol.types import Body, PartPrimitive, Sphere, primitive_mesh


def _box(size, centre) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.box(extents=size)
    return np.asarray(mesh.vertices) + centre, np.asarray(mesh.faces)


def _write_obj(path, objects) -> str:
    path.write_text(obj_text([(name, v, f) for name, (v, f) in objects]))
    return os.fspath(path)


def _manifest(folder, bodies, **extra) -> str:
    path = folder / "scene.json"
    path.write_text(json.dumps({"units": "m", "bodies": bodies, **extra}))
    return os.fspath(path)


@pytest.fixture
def chair(tmp_path):
    """A chair of two parts that touch and overlap (a seat resting into its leg)."""
    return _write_obj(
        tmp_path / "chair.obj",
        [
            ("seat", _box((1, 1, 0.2), (0, 0, 1.0))),
            ("leg", _box((0.2, 0.2, 1.0), (0, 0, 0.45))),  # pokes 0.05 into the seat
        ],
    )


@pytest.mark.parametrize("shape", ["hull", "mesh"])
def test_parts_of_one_body_never_pair(tmp_path, chair, shape):
    scene = _manifest(
        tmp_path,
        [
            {"name": "chair", "mesh": "chair.obj"},
            {
                "name": "crate",
                "primitive": {"type": "box", "size": [0.5, 0.5, 0.5]},
                "position": [0.3, 0, 0.3],
            },  # into the leg (x in [0.05, 0.55] vs leg to 0.1)
        ],
    )
    report = meshcol.check([scene], collider=shape)
    assert [(p["body_a"], p["body_b"]) for p in report.pairs] == [("chair", "crate")]
    (pair,) = report.pairs
    assert (pair["part_a"], pair["part_b"]) == ("leg", None)
    assert pair["status"] == "penetrating"
    assert pair["depth"] == pytest.approx(0.05, abs=1e-9)
    (chair_row,) = [b for b in report.bodies if b["name"] == "chair"]
    assert chair_row["parts"] == ["seat", "leg"] and chair_row["convex_parts"] == 2
    assert report.summary["bodies"] == 2


def test_parts_of_one_body_without_neighbours_give_no_pair(tmp_path, chair):
    scene = _manifest(tmp_path, [{"name": "chair", "mesh": "chair.obj"}])
    for shape in ("hull", "mesh"):
        report = meshcol.check([scene], collider=shape)
        assert report.pairs == [] and report.passed


def test_loose_mesh_file_still_gives_one_body_per_object(chair):
    scene = load_inputs([chair])
    assert [b.name for b in scene.bodies] == ["chair/seat", "chair/leg"]
    assert all(b.parts == () for b in scene.bodies)
    report = meshcol.check([chair])
    assert [(p["body_a"], p["body_b"], p["status"]) for p in report.pairs] == [
        ("chair/seat", "chair/leg", "penetrating")
    ]


def test_glb_given_directly_gives_one_body_per_node(tmp_path):
    from meshcol.io.mesh_write import write_meshes

    path = tmp_path / "pair.glb"
    write_meshes(
        path, [("left", *_box((1, 1, 1), (0, 0, 0))), ("right", *_box((1, 1, 1), (0.9, 0, 0)))]
    )
    assert [b.name for b in load_inputs([path]).bodies] == ["pair/left", "pair/right"]
    # the same file as a manifest body is one body of two parts
    scene = _manifest(tmp_path, [{"name": "p", "mesh": "pair.glb"}])
    (body,) = load_inputs([scene]).bodies
    assert body.parts == ("left", "right")
    assert meshcol.check([scene]).pairs == []


def test_sweep_names_the_part_hit_and_never_pairs_parts(tmp_path, chair):
    scene = _manifest(
        tmp_path,
        [
            {"name": "chair", "mesh": "chair.obj"},
            {
                "name": "ball",
                "primitive": {"type": "sphere", "radius": 0.1},
                "position": [-3, 0, 0.3],
                "end_position": [3, 0, 0.3],
            },
        ],
    )
    for shape in ("hull", "mesh"):
        report = meshcol.sweep(scene, collider=shape)
        assert [(h.body_a, h.body_b, h.part_a, h.part_b) for h in report.hits] == [
            ("chair", "ball", "leg", None)
        ], shape
        # the leg's face at x = -0.1 is met when the ball's centre is at x = -0.2
        assert report.hits[0].time_of_impact == pytest.approx(2.8 / 6, abs=1e-5)
        assert report.to_dict()["pairs"][0]["part_a"] == "leg"


def test_many_parts_one_body_no_self_pairs_even_with_many_parts(tmp_path):
    # a 40-part asset whose parts all touch: no pair at all, and the collider keeps every part
    parts = [(f"slab{k:02d}", _box((1, 1, 0.1), (0, 0, 0.1 * k))) for k in range(40)]
    _write_obj(tmp_path / "stack.obj", parts)
    scene = _manifest(tmp_path, [{"name": "stack", "mesh": "stack.obj"}])
    colliders = build_colliders(load_inputs([scene]).bodies, "hull")
    assert len(colliders.bodies) == 1 and len(colliders.part_body) == 40
    assert colliders.part_label.tolist() == list(range(40))
    assert meshcol.check([scene]).pairs == []


# --- UCX ----------------------------------------------------------------------------------


def _ucx_parts(owner: str, count: int):
    # touching convex slabs, as a decomposition gives: adjacent parts overlap slightly
    return [(f"UCX_{owner}_{k:02d}", _box((1, 1, 0.26), (0, 0, 0.25 * k))) for k in range(count)]


def test_ucx_output_alone_is_one_body_with_a_warning(tmp_path):
    path = _write_obj(tmp_path / "bowl_ucx.obj", _ucx_parts("bowl", 5))
    report = meshcol.check([path], collider="decomposed")
    assert report.pairs == [] and report.passed  # parts of one decomposition never pair
    assert [b["name"] for b in report.bodies] == ["bowl_ucx/bowl"]
    assert report.bodies[0]["collider"] == "ucx" and report.bodies[0]["convex_parts"] == 5
    assert report.warnings == [
        "'bowl_ucx/UCX_bowl_00' ... 'bowl_ucx/UCX_bowl_04' (5 parts) name no body 'bowl' in "
        "the inputs: checked as one body 'bowl_ucx/bowl' of 5 part(s)"
    ]
    sweep = _manifest(
        tmp_path,
        [
            {"name": "b", "mesh": "bowl_ucx.obj"},
            {
                "name": "ball",
                "primitive": {"type": "sphere", "radius": 0.1},
                "position": [-3, 0, 0.5],
                "end_position": [3, 0, 0.5],
            },
        ],
    )
    swept = meshcol.sweep(sweep, collider="decomposed")
    assert [(h.body_a, h.body_b) for h in swept.hits] == [("b", "ball")]


def test_ucx_output_beside_its_source_is_its_collider(tmp_path):
    source = _write_obj(tmp_path / "bowl.obj", [("bowl", _box((1, 1, 1.3), (0, 0, 0.5)))])
    ucx = _write_obj(tmp_path / "bowl_ucx.obj", _ucx_parts("bowl", 5))
    report = meshcol.check([source, ucx], collider="decomposed")
    assert report.warnings == []
    assert [(b["name"], b["collider"], b["convex_parts"]) for b in report.bodies] == [
        ("bowl", "ucx", 5)
    ]
    assert report.pairs == []


def test_ucx_parts_in_a_manifest_body(tmp_path):
    _write_obj(
        tmp_path / "crate.obj",
        [("crate", _box((1, 1, 1), (0, 0, 0)))] + _ucx_parts("crate", 2) + _ucx_parts("lid", 1),
    )
    scene = _manifest(
        tmp_path,
        [
            {"name": "c", "mesh": "crate.obj"},
            {
                "name": "ball",
                "primitive": {"type": "sphere", "radius": 0.2},
                "position": [0.6, 0, 0],
            },
        ],
    )
    report = meshcol.check([scene], collider="decomposed")
    assert report.warnings == [
        "body 'c': 'UCX_lid_00' name no part of it (its parts: 'crate'): kept as parts of their own"
    ]
    (row,) = [b for b in report.bodies if b["name"] == "c"]
    # the matched UCX parts left the render geometry; the unmatched one stayed a part
    assert row["parts"] == ["crate", "UCX_lid_00"] and row["convex_parts"] == 3
    (pair,) = report.pairs
    assert (pair["body_a"], pair["part_a"], pair["status"]) == ("c", "crate", "penetrating")
    assert (pair["body_b"], pair["part_b"]) == ("ball", None)


# --- degenerate bodies: the same in check and sweep -------------------------------------------


@pytest.fixture
def stick(tmp_path):
    """A body made only of zero-area triangles (collinear corners), and a wall it crosses."""
    (tmp_path / "stick.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n")
    _write_obj(tmp_path / "wall.obj", [("wall", _box((0.2, 4, 4), (0, 0, 0)))])
    return tmp_path


def _body_with_exact_parts(name="crate", ucx=True) -> Body:
    """A body of a box mesh ``crate``, its ``UCX_crate_00`` part (optional) and ``ball``, a
    sphere of radius 0.25 at (2, 0, 0) given exact (``Body.part_primitives``) beside its
    tessellation."""
    crate = _box((1, 1, 1), (0, 0, 0))
    hull = _box((1.1, 1.1, 1.1), (0, 0, 0))
    ball_v, ball_f = primitive_mesh(Sphere(0.25))
    blocks = (
        [crate, hull, (ball_v + (2, 0, 0), ball_f)]
        if ucx
        else [crate, (ball_v + (2, 0, 0), ball_f)]
    )
    names = ("crate", "UCX_crate_00", "ball") if ucx else ("crate", "ball")
    vertices, faces, counts, base = [], [], [], 0
    for v, f in blocks:
        vertices.append(v)
        faces.append(f + base)
        counts.append(len(f))
        base += len(v)
    exact = PartPrimitive(
        Sphere(0.25), np.array([[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    )
    return Body(
        name,
        None,
        np.concatenate(vertices),
        np.concatenate(faces),
        parts=names,
        part_faces=np.concatenate([[0], np.cumsum(counts)]),
        part_primitives=(None, None, exact) if ucx else (None, exact),
    )


@pytest.mark.parametrize("kind", ["hull", "decomposed", "fit", "box", "sphere", "mesh"])
def test_a_primitive_part_is_exact_in_its_turn_beside_ucx_parts(kind):
    """``UCX_`` matching drops a part and keeps each remaining part's primitive with it; the
    sphere is the exact primitive, placed by its pose, after the crate's collider."""
    body = _body_with_exact_parts()
    probe = Body.of_primitive("probe", None, Sphere(0.5), pose=np.eye(4))
    colliders = build_colliders([body, probe], kind)
    start, stop = colliders.body_part_offsets[:2]
    labels = colliders.part_label[start:stop].tolist()
    assert colliders.bodies[0].parts == ("crate", "ball")  # the UCX part became the crate's
    assert labels[-1] == 1 and labels[:-1] == [0] * (len(labels) - 1)
    ball = stop - 1
    assert colliders.shapes.kinds[ball] == 1 and colliders.shapes.params[ball][0] == 0.25
    np.testing.assert_array_equal(colliders.part_poses()[ball][:3, 3], (2, 0, 0))
    if kind == "decomposed":
        assert colliders.kinds[0] == "ucx" and stop - start == 2


def test_part_primitives_must_match_the_parts():
    body = _body_with_exact_parts(ucx=False)
    with pytest.raises(ValueError, match="one entry per part"):
        dataclasses.replace(body, part_primitives=body.part_primitives[:1])
    with pytest.raises(ValueError, match="one entry per part"):
        Body("x", None, body.vertices, body.faces, part_primitives=body.part_primitives)


@pytest.mark.parametrize("shape", ["hull", "mesh", "decomposed"])
def test_zero_area_body_is_seen_by_check_and_sweep(stick, shape):
    static = _manifest(
        stick,
        [
            {"name": "wall", "mesh": "wall.obj"},
            {"name": "stick", "mesh": "stick.obj", "position": [-1, 0, 0]},
        ],
    )
    report = meshcol.check([static], collider=shape)
    assert [(p["body_a"], p["body_b"], p["status"]) for p in report.pairs] == [
        ("wall", "stick", "penetrating")
    ]
    moving = _manifest(
        stick,
        [
            {"name": "wall", "mesh": "wall.obj"},
            {
                "name": "stick",
                "mesh": "stick.obj",
                "position": [-6, 0, 0],
                "end_position": [6, 0, 0],
            },
        ],
    )
    swept = meshcol.sweep(moving, collider=shape)
    assert [(h.body_a, h.body_b, h.status.name) for h in swept.hits] == [("wall", "stick", "HIT")]
    # the stick's tip (x = 2 local) meets the wall's face x = -0.1 first
    assert swept.hits[0].time_of_impact == pytest.approx((6 - 2 - 0.1) / 12, abs=1e-5)
    flat_warning = (
        "body 'stick': flat (no volume to decompose): its hull is used, the polygon, segment "
        "or point it is"
    )
    expected = [flat_warning] if shape == "decomposed" else []
    assert report.warnings == expected and list(swept.warnings) == expected


def test_cli_prints_warnings_on_stderr(tmp_path):
    path = _write_obj(tmp_path / "bowl_ucx.obj", _ucx_parts("bowl", 2))
    result = CliRunner().invoke(
        main, ["check", path, "--shape", "decomposed", "--report", os.devnull]
    )
    assert result.exit_code == 0, result.output
    assert (
        "meshcol: warning: 'bowl_ucx/UCX_bowl_00' and 'bowl_ucx/UCX_bowl_01' name no body "
        "'bowl' in the inputs: checked as one body 'bowl_ucx/bowl' of 2 part(s)"
    ) in result.stderr.splitlines()


# --- per-mesh commands: inspect and decompose see each part --------------------------------


def test_inspect_judges_each_part_of_a_body(tmp_path, chair):
    from meshcol.analysis.inspect import inspect

    scene = _manifest(tmp_path, [{"name": "chair", "mesh": "chair.obj"}])
    report = inspect([scene])
    rows = {r["name"]: r for r in report.to_dict()["bodies"]}
    # the seat and the leg overlap: two healthy meshes, not one self-intersecting one
    assert sorted(rows) == ["chair/leg", "chair/seat"]


def test_decompose_then_check_reuses_the_cache_part_by_part(tmp_path, chair, monkeypatch):
    from meshcol.decomposition import decompose as decompose_module
    from meshcol.decomposition.batch import decompose_files

    scene = _manifest(tmp_path, [{"name": "chair", "mesh": "chair.obj", "scale": 2}])
    options = dict(
        threshold=0.2,
        resolution=500,
        engine_options={"mcts_iterations": 20, "mcts_nodes": 8, "mcts_max_depth": 2},
    )
    cache = tmp_path / "cache"
    decompose_files([scene], tmp_path / "out", cache_dir=cache, **options)

    def no_engine(*args, **kwargs):
        raise AssertionError("check decomposed again what decompose had cached")

    monkeypatch.setattr(decompose_module, "decompose", no_engine)
    report = meshcol.check(
        [scene], collider="decomposed", decompose_options={"cache_dir": str(cache), **options}
    )
    assert report.bodies[0]["collider"] == "decomposed" and report.pairs == []
