"""Inconsistently wound hosts (issue 29, items 1 and 2).

Closed meshes whose faces were flipped at random (``inspect`` flags them MC403) are wound
consistently when the mesh set is built, so the winding-number inside test answers as for the
consistently wound surface. Each case is checked against an independent oracle: python-fcl's
distance for pairs apart, and the verdicts and numbers of the consistently wound copy (whose
winding number needs no orientation) for the others. Every depth lies in [depth,
depth_upper] around the minimum translation distance where it is known.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from dirty_meshes import HOSTS, at, blob, check_pair, cube, inner, moebius, on_top, shuffled

from meshcol.collision.mesh_query import MeshSet
from meshcol.collision.orientation import orient_consistently
from meshcol.geometry.topology import edge_table, is_balanced


def test_orientation_undoes_a_random_shuffle() -> None:
    for name, make in HOSTS.items():
        v, f = make()
        assert is_balanced(f), name
        dirty = shuffled(f)
        assert edge_table(dirty)[2] > 0  # inspect's MC403
        found = orient_consistently(v, dirty)
        assert found.orientable and found.closed, name
        # outward, as the consistently wound original (manifold3d winds outward)
        np.testing.assert_array_equal(found.faces, f, err_msg=name)
        inverted = orient_consistently(v, shuffled(f[:, ::-1], 1))
        np.testing.assert_array_equal(inverted.faces, f, err_msg=name)


def test_consistent_meshes_are_kept_as_given() -> None:
    v, f = blob()
    for faces in (f, f[:, ::-1]):  # inside out but consistent: the author's winding
        found = orient_consistently(v, faces)
        assert not found.flipped.any()
        assert found.faces is not None and np.array_equal(found.faces, faces)


def test_a_shell_keeps_its_cavity() -> None:
    outer = trimesh.creation.box(extents=(1, 1, 1))
    inner = trimesh.creation.box(extents=(0.8, 0.8, 0.8))
    v = np.concatenate([outer.vertices, inner.vertices])
    f = np.concatenate([outer.faces, inner.faces[:, ::-1] + len(outer.vertices)])
    found = orient_consistently(v, shuffled(f, 3))
    np.testing.assert_array_equal(found.faces, f)
    wn = MeshSet.from_arrays([(v, found.faces)]).winding_number(0, np.array([[0, 0, 0.0]]))
    assert abs(wn[0]) < 0.5  # the cavity is outside the solid


def test_a_moebius_strip_is_not_orientable() -> None:
    v, f = moebius(0.2)
    found = orient_consistently(v, shuffled(f))
    assert not found.orientable and not found.closed


def _fcl_distance(host, box, pose) -> float:
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(host[0]), len(host[1]))
    model.addSubModel(host[0], host[1])
    model.endModel()
    body = fcl.CollisionObject(model, fcl.Transform())
    edge = float(np.ptp(box[0], axis=0)[0])
    placed = fcl.CollisionObject(
        fcl.Box(edge, edge, edge), fcl.Transform(pose[:3, :3], pose[:3, 3])
    )
    return fcl.distance(body, placed, fcl.DistanceRequest(), fcl.DistanceResult())


@pytest.mark.parametrize("name", sorted(HOSTS))
@pytest.mark.parametrize("collider", ["mesh", "hull"])
def test_cube_above_a_shuffled_host_is_apart(name, collider) -> None:
    pytest.importorskip("fcl")
    host = HOSTS[name]()
    box = cube(0.005)
    pose = on_top(host, 0.004, 0.005)
    expected = _fcl_distance(host, box, pose)
    assert expected == pytest.approx(0.004, abs=1e-9)
    for faces in (shuffled(host[1]), host[1][:, ::-1]):
        (pair,) = check_pair((host[0], faces), box, pose, collider).pairs
        assert pair["status"] != "contained"
        if collider == "mesh":
            assert pair["status"] == "clearance"
            assert pair["distance"] == pytest.approx(expected, abs=1e-9)
            assert pair["depth"] == 0.0 and pair["depth_upper"] == 0.0


@pytest.mark.parametrize("name", sorted(HOSTS))
@pytest.mark.parametrize("collider", ["mesh", "hull"])
def test_cube_inside_a_shuffled_host_is_contained(name, collider) -> None:
    host = HOSTS[name]()
    box = cube(0.005)
    pose = at(inner(host))
    expected = check_pair(host, box, pose, collider).pairs[0]
    assert expected["status"] == "contained"
    for faces in (shuffled(host[1]), host[1][:, ::-1], shuffled(host[1][:, ::-1], 2)):
        (pair,) = check_pair((host[0], faces), box, pose, collider).pairs
        assert pair["status"] == "contained"
        assert pair["depth"] == pytest.approx(expected["depth"], rel=1e-9)
        assert pair["depth"] <= pair["depth_upper"]


@pytest.mark.parametrize("name", sorted(HOSTS))
def test_cube_pushed_1e7_into_a_shuffled_host_is_contact(name) -> None:
    host = HOSTS[name]()
    box = cube(0.005)
    pose = on_top(host, -1e-7, 0.005)
    for faces in (host[1], shuffled(host[1]), host[1][:, ::-1]):
        (pair,) = check_pair((host[0], faces), box, pose).pairs
        assert pair["status"] == "contact", name
        assert 0.0 <= pair["depth"] <= 1.0e-7 * (1 + 1e-6)
        assert pair["depth"] <= pair["depth_upper"]


def test_open_host_depth_stays_in_its_interval() -> None:
    """An open host (a box without its top face): the depth is never above depth_upper."""
    host = trimesh.creation.box(extents=(1, 1, 1))
    keep = np.asarray(host.face_normals)[:, 2] < 0.5
    v, f = np.asarray(host.vertices), np.asarray(host.faces)[keep]
    box = cube(0.2)
    for z in (0.45, 0.5 - 1e-7, 0.55, 0.0):
        for faces in (f, shuffled(f, 5)):
            (pair,) = check_pair((v, faces), box, at([0.2, 0.2, z])).pairs
            assert pair["depth"] <= pair["depth_upper"]


def test_mesh_set_flags_and_opt_out() -> None:
    v, f = blob()
    dirty = shuffled(f)
    oriented = MeshSet.from_arrays([(v, dirty), (v, f), (v, f[:-3])])
    assert oriented.reoriented.tolist() == [True, False, False]
    assert oriented.orientable.all()
    assert oriented.closed.tolist() == [True, True, False]
    assert oriented.inside_decided.tolist() == [True, True, False]
    np.testing.assert_array_equal(oriented.mesh(0)[1], f)
    kept = MeshSet.from_arrays([(v, dirty)], orient=False)
    np.testing.assert_array_equal(kept.mesh(0)[1], dirty)
    assert not kept.reoriented[0] and kept.orientable[0]
    # the consistently wound copy's verdicts, not the shuffled surface's
    probe = np.array([[0.0, 0.0, 0.0], [0.1, 0.05, -0.1], [2.0, 0.0, 0.0]])
    assert oriented.contains(0, probe).tolist() == [True, True, False]


def test_ray_parity_votes_and_abstains() -> None:
    from meshcol.collision.ray_parity import ray_parity

    outer = trimesh.creation.box(extents=(1, 1, 1))
    inner_box = trimesh.creation.box(extents=(0.8, 0.8, 0.8))
    v = np.concatenate([outer.vertices, inner_box.vertices])
    f = np.concatenate([outer.faces, inner_box.faces + len(outer.vertices)])  # winding unused
    points = np.array([[0.45, 0.0, 0.0], [0.0, 0.0, 0.0], [0.7, 0.0, 0.0], [0.5, 0.5, 0.5]])
    inside, decided = ray_parity(points, v, shuffled(f))
    assert decided[:3].all()
    assert inside[:3].tolist() == [True, False, False]  # the wall, the cavity, outside
    assert not decided[3]  # on a corner: every ray grazes, no vote


def test_undecided_pairs_reach_every_writer() -> None:
    """A box across a Moebius strip: no inside test decides, so the pair is undecided, with
    depth 0 (the only sure lower bound) and its depth_upper, in JSON, CSV and CI cases."""
    from meshcol.analysis.check import CheckOptions, check_scene
    from meshcol.types import Body, Scene

    v, f = moebius()
    box = cube(0.2)
    scene = Scene((Body("strip", None, v, f), Body("box", None, box[0], box[1], at([1, 0, 0]))))
    report = check_scene(scene, CheckOptions(collider="mesh", fail_on="contact"))
    (pair,) = report.pairs
    assert pair["status"] == "undecided"
    assert pair["depth"] == 0.0 and pair["depth_upper"] > 1e-6
    assert report.summary["pairs_by_status"]["undecided"] == 1
    assert report.exit_code == 1  # --fail-on contact fails on it
    header, row = report.to_csv().splitlines()[:2]
    assert "depth_upper" in header.split(",") and "undecided" in row.split(",")
    (case,) = report.ci_suite().cases
    assert case.kind == "undecided" and case.outcome == "failure"
    assert case.message.startswith("undecided: no inside test decides")
    lenient = check_scene(scene, CheckOptions(collider="mesh"))
    assert lenient.exit_code == 0  # --fail-on penetration does not
