"""Mesh health checks: topology, volume, degeneracies, self-intersections, units."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol.analysis.inspect import RULES, guess_units, inspect_body
from meshcol.collision.self_intersection import self_intersecting_pairs
from meshcol.errors import InvalidMeshError
from meshcol.geometry.topology import closed_volume, orient_outward, oriented_volume
from meshcol.types import Body

CUBE_VERTICES = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
# outward-wound triangles of the unit cube (vertex index = 4x + 2y + z)
CUBE_FACES = np.array(
    [
        [0, 1, 3],
        [0, 3, 2],  # x = 0
        [4, 6, 7],
        [4, 7, 5],  # x = 1
        [0, 4, 5],
        [0, 5, 1],  # y = 0
        [2, 3, 7],
        [2, 7, 6],  # y = 1
        [0, 2, 6],
        [0, 6, 4],  # z = 0
        [1, 5, 7],
        [1, 7, 3],  # z = 1
    ]
)


def body(vertices, faces, name="b", pose=None) -> Body:
    kwargs = {} if pose is None else {"pose": pose}
    return Body(
        name=name,
        source="test.obj",
        vertices=np.asarray(vertices, float),
        faces=np.asarray(faces, np.int64),
        **kwargs,
    )


def two_cubes(offset) -> tuple[np.ndarray, np.ndarray]:
    return (
        np.vstack([CUBE_VERTICES, CUBE_VERTICES + offset]),
        np.vstack([CUBE_FACES, CUBE_FACES + 8]),
    )


def test_unit_cube_is_clean() -> None:
    r = inspect_body(body(CUBE_VERTICES, CUBE_FACES))
    assert (r.vertices, r.faces, r.components) == (8, 12, 1)
    assert r.watertight and r.winding_consistent
    assert r.volume == pytest.approx(1.0, abs=1e-15)
    assert r.bounds == [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]] and r.size == [1.0, 1.0, 1.0]
    assert (r.degenerate_faces, r.duplicate_faces, r.boundary_edges, r.non_manifold_edges) == (
        0,
        0,
        0,
        0,
    )
    assert not r.self_intersecting and r.self_intersecting_pairs == 0
    assert r.manifold_status == "NoError"
    assert r.units_guess == "m"
    assert r.findings == []


def test_inside_out_cube_is_inverted() -> None:
    r = inspect_body(body(CUBE_VERTICES, CUBE_FACES[:, ::-1]))
    assert r.watertight and r.winding_consistent and r.volume == pytest.approx(-1.0)
    assert r.findings == ["inverted"]
    assert not r.self_intersecting


@settings(max_examples=30)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1e-3, 1.0, 1e3]), st.sampled_from([0, 1e6]))
def test_inverted_is_the_sign_of_the_volume_wherever_the_mesh_is(seed, scale, far) -> None:
    # the hull of random points, outward, and inside out, moved by a random rigid motion far
    # from the origin: the orientation never changes
    from meshcol.collision.hull import exact_hull

    rng = np.random.default_rng(seed)
    hull = exact_hull(rng.normal(size=(30, 3)) * scale)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = hull.vertices @ rotation.T + far * rng.normal(size=3)
    outward = inspect_body(body(moved, hull.faces))
    inside_out = inspect_body(body(moved, hull.faces[:, ::-1]))
    assert "inverted" not in outward.findings and outward.volume > 0
    assert "inverted" in inside_out.findings and inside_out.volume < 0
    assert inside_out.volume == pytest.approx(-outward.volume, rel=1e-9)


def test_closed_mesh_without_volume_is_not_inverted() -> None:
    # a triangle and its back face: closed and consistently wound, volume 0, no orientation
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert oriented_volume(v, [[0, 1, 2], [0, 2, 1]]) == (0.0, 0)
    r = inspect_body(body(v, [[0, 1, 2], [0, 2, 1]]))
    assert r.volume == 0.0 and "inverted" not in r.findings
    # an open or inconsistently wound mesh has no volume and no orientation
    assert oriented_volume(CUBE_VERTICES, CUBE_FACES[:-1]) is None
    assert orient_outward(CUBE_VERTICES, CUBE_FACES[:-1])[1] is False


def test_orient_outward_reverses_an_inside_out_mesh_only() -> None:
    faces, flipped = orient_outward(CUBE_VERTICES, CUBE_FACES[:, ::-1])
    assert flipped and faces.tolist() == CUBE_FACES.tolist()
    faces, flipped = orient_outward(CUBE_VERTICES, CUBE_FACES)
    assert not flipped and faces.tolist() == CUBE_FACES.tolist()


def test_one_flipped_face_is_inconsistent_winding() -> None:
    faces = CUBE_FACES.copy()
    faces[0] = faces[0][::-1]
    r = inspect_body(body(CUBE_VERTICES, faces))
    assert r.watertight and not r.winding_consistent
    assert r.volume is None
    assert r.findings == ["inconsistent-winding"]
    assert r.manifold_status == "NotManifold"


def test_open_cube() -> None:
    r = inspect_body(body(CUBE_VERTICES, CUBE_FACES[:-2]))
    assert not r.watertight and r.boundary_edges == 4 and r.volume is None
    assert r.findings == ["not-watertight"]


def test_duplicate_face_is_duplicate_and_non_manifold() -> None:
    r = inspect_body(body(CUBE_VERTICES, np.vstack([CUBE_FACES, CUBE_FACES[:1]])))
    assert r.duplicate_faces == 1
    assert r.non_manifold_edges == 3
    assert not r.self_intersecting  # a duplicate is reported as such, not as a crossing
    assert r.findings == ["not-watertight", "non-manifold", "duplicate-faces"]


def test_degenerate_faces() -> None:
    vertices = np.vstack([CUBE_VERTICES, [[0.5, 0.0, 0.0]]])
    faces = np.vstack([CUBE_FACES, [[0, 0, 1]], [[0, 4, 8]]])  # repeated index; collinear
    r = inspect_body(body(vertices, faces))
    assert r.degenerate_faces == 2
    assert "degenerate-faces" in r.findings


def test_disjoint_cubes_are_two_clean_components() -> None:
    r = inspect_body(body(*two_cubes([2.0, 0.0, 0.0])))
    assert r.components == 2 and r.watertight
    assert r.volume == pytest.approx(2.0)
    assert not r.self_intersecting
    assert r.findings == ["multiple-components"]


def test_overlapping_cubes_self_intersect() -> None:
    vertices, faces = two_cubes([0.5, 0.5, 0.5])
    r = inspect_body(body(vertices, faces))
    assert r.self_intersecting and r.self_intersecting_pairs > 0
    pairs = self_intersecting_pairs(vertices, faces)
    # every crossing pair has one face from each cube: each cube alone is clean
    assert ((pairs[:, 0] < 12) & (pairs[:, 1] >= 12)).all()
    assert r.watertight  # closed and crossing: only the self-intersection test sees it
    assert "self-intersecting" in r.findings


def test_vertex_pushed_through_opposite_face_self_intersects() -> None:
    vertices = CUBE_VERTICES.copy()
    vertices[7] = [-0.5, 0.6, 0.4]  # corner (1, 1, 1) pushed through the x = 0 face
    r = inspect_body(body(vertices, CUBE_FACES))
    assert r.components == 1 and r.watertight
    assert r.self_intersecting


def test_coplanar_overlap_and_fold_over() -> None:
    # two overlapping triangles in z = 0 sharing no vertex
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 1, 0], [-1, 1, 0], [1, -1, 0]], float)
    assert self_intersecting_pairs(v, [[0, 1, 2], [3, 4, 5]]).tolist() == [[0, 1]]
    # folded over a shared edge: both triangles on the same side of it
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.8, 0]], float)
    assert self_intersecting_pairs(v, [[0, 1, 2], [1, 0, 3]]).tolist() == [[0, 1]]
    # unfolded: the other side of the edge: no crossing
    v[3] = [0.5, -0.8, 0.0]
    assert len(self_intersecting_pairs(v, [[0, 1, 2], [1, 0, 3]])) == 0


def test_touching_is_not_crossing() -> None:
    # a vertex of one triangle lies on the other (T-junction), and a shared vertex
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 0, 0], [1, 0, 1], [1, 1, 1]], float)
    assert len(self_intersecting_pairs(v, [[0, 1, 2], [3, 4, 5]])) == 0
    v2 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 1]], float)
    assert len(self_intersecting_pairs(v2, [[0, 1, 2], [0, 3, 4]])) == 0


def test_crossing_pairs_match_brute_force_on_random_soup() -> None:
    rng = np.random.default_rng(4)
    vertices = rng.uniform(0, 10, size=(150, 3))
    faces = np.arange(150).reshape(50, 3)
    fast = {tuple(p) for p in self_intersecting_pairs(vertices, faces).tolist()}
    from meshcol.collision.self_intersection import face_pairs_cross

    i, j = np.triu_indices(50, 1)
    hit = face_pairs_cross(vertices, faces, np.stack([i, j], axis=1))
    assert fast == set(zip(i[hit].tolist(), j[hit].tolist()))
    assert len(fast) > 0


def test_bounds_are_in_the_world_frame() -> None:
    transform = np.eye(4)
    transform[:3, 3] = [10.0, 0.0, -5.0]
    r = inspect_body(body(CUBE_VERTICES, CUBE_FACES, pose=transform))
    assert r.bounds == [[10.0, 0.0, -5.0], [11.0, 1.0, -4.0]]
    assert r.volume == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("extent", "units"),
    [
        (1.8, "m"),
        (0.02, "m"),
        (99.0, "m"),
        (400.0, "mm"),
        (9000.0, "mm"),
        (50000.0, "unknown"),
        (0.005, "unknown"),
    ],
)
def test_units_guess(extent: float, units: str) -> None:
    assert guess_units(extent)[0] == units


def test_units_reason_and_declared_units() -> None:
    assert guess_units(400.0) == (
        "mm",
        "largest extent 400 units: 0.4 m in millimetres, over 100 m in metres",
    )
    chair = CUBE_VERTICES * [450.0, 500.0, 900.0]
    assert inspect_body(body(chair, CUBE_FACES)).findings == ["suspect-units"]
    assert inspect_body(body(chair, CUBE_FACES), declared_units="mm").findings == []
    assert inspect_body(body(chair, CUBE_FACES), declared_units="millimetres").findings == []
    assert inspect_body(body(chair, CUBE_FACES), declared_units="m").findings == ["suspect-units"]


def test_closed_volume() -> None:
    assert closed_volume(CUBE_VERTICES * 2, CUBE_FACES) == pytest.approx(8.0)
    assert closed_volume(CUBE_VERTICES, CUBE_FACES[:-1]) is None


def test_rules_are_the_finding_names() -> None:
    vertices, faces = two_cubes([0.5, 0.5, 0.5])
    findings = inspect_body(body(vertices, faces)).findings
    assert set(findings) <= set(RULES)


def test_no_faces_and_non_finite_raise() -> None:
    with pytest.raises(InvalidMeshError, match=r"^test.obj: body 'b': mesh has no faces$"):
        inspect_body(body(CUBE_VERTICES, np.zeros((0, 3))))
    bad = CUBE_VERTICES.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InvalidMeshError, match="NaN or infinite"):
        inspect_body(body(bad, CUBE_FACES))


@pytest.mark.parametrize(
    "name",
    [
        "unit_sphere.STL",
        "torus.STL",
        "fandisk.obj",
        "featuretype.STL",
        "idler_riser.STL",
        "angle_block.STL",
        "ballA.off",
        "round.stl",
        "cylinder.stl",
        "busted.STL",
    ],
)
def test_closed_corpus_meshes_are_clean(corpus, name: str) -> None:
    from meshcol.io.mesh_read import load_mesh

    (b,) = load_mesh(corpus / "trimesh-models" / name)
    r = inspect_body(b)
    assert r.watertight and r.winding_consistent and r.components == 1
    assert r.volume > 0
    assert not r.self_intersecting, name
    assert r.manifold_status == "NoError"


def test_corpus_soup_and_open_meshes(corpus) -> None:
    from meshcol.io.mesh_read import load_mesh

    (soup,) = load_mesh(corpus / "trimesh-models" / "soup.stl")
    r = inspect_body(soup)
    assert not r.watertight and r.components == 100 and r.volume is None
    (shared,) = load_mesh(corpus / "trimesh-models" / "shared.STL")
    assert inspect_body(shared).non_manifold_edges > 0


@settings(max_examples=30)
@given(st.integers(0, 2**32 - 1))
def test_crossings_are_invariant_under_rigid_motion_and_face_order(seed: int) -> None:
    rng = np.random.default_rng(seed)
    vertices = rng.uniform(0, 10, size=(60, 3))
    faces = rng.integers(0, 60, size=(25, 3))
    faces = faces[
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    ]
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = vertices @ rotation.T + rng.normal(size=3) * 100
    order = rng.permutation(len(faces))
    base = {tuple(p) for p in self_intersecting_pairs(vertices, faces).tolist()}
    shuffled = {
        tuple(sorted((int(order[i]), int(order[j]))))
        for i, j in self_intersecting_pairs(moved, faces[order]).tolist()
    }
    assert base == shuffled


def test_inspect_report_applies_the_policy(tmp_path) -> None:
    from meshcol.analysis.inspect import InspectReport, inspect

    path = tmp_path / "open.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\n")
    report = inspect(path)
    assert isinstance(report, InspectReport)
    assert report.exit_code == 0 and report.failed == []
    assert "not-watertight" in report.inspections[0].findings
    strict = inspect([path], fail_on=["not-watertight"])
    assert strict.exit_code == 1
    assert strict.bodies[0]["failed_rules"] == ["not-watertight"]
    assert strict.summary["failed"] == 1 and strict.summary["findings"]["not-watertight"] == 1
    data = strict.to_dict()
    assert data["command"] == "inspect" and data["failed"] is True
    assert strict.to_csv().splitlines()[0].endswith(",findings,failed_rules,units")
    with pytest.raises(ValueError, match="unknown rule 'nope'"):
        inspect([path], fail_on=["nope"])


def dented_cube() -> tuple[np.ndarray, np.ndarray]:
    """The unit cube with its top face's centre pushed down to the middle: closed, outward,
    volume 5/6, its hull the unit cube."""
    top = [i for i, face in enumerate(CUBE_FACES) if set(face) <= {1, 3, 5, 7}]
    vertices = np.vstack([CUBE_VERTICES, [[0.5, 0.5, 0.5]]])
    fan = [[1, 5, 8], [5, 7, 8], [7, 3, 8], [3, 1, 8]]
    return vertices, np.vstack([np.delete(CUBE_FACES, top, axis=0), fan])


def test_physics_comparisons_are_the_known_ratios() -> None:
    import trimesh

    from meshcol.analysis.physics import PhysicsOptions, physics_readiness

    vertices, faces = dented_cube()
    rows, findings = physics_readiness(
        [body(vertices, faces)], PhysicsOptions(volume_ratio=1.1, inertia_ratio=1.0001)
    )
    (row,) = rows
    assert row["comparison"] == "solid" and row["convex_parts"] == 1
    assert row["volume_ratio"] == pytest.approx(1.2, rel=1e-12)  # the hull's 1 over 5/6
    # the inertia ratio against an independent oracle: trimesh's moments, per unit mass
    hull, dented = trimesh.Trimesh(CUBE_VERTICES, CUBE_FACES), trimesh.Trimesh(vertices, faces)
    moments = [
        np.sort(np.linalg.eigvalsh(mesh.moment_inertia)) / mesh.volume for mesh in (hull, dented)
    ]
    expected = float(np.max(np.maximum(moments[0] / moments[1], moments[1] / moments[0])))
    assert row["inertia_ratio"] == pytest.approx(expected, rel=1e-9)
    assert row["inertia_ratio"] > 1.0001
    # the dent moves the centre of mass down; the offset is over the visual diagonal, sqrt 3
    assert row["center_of_mass_offset"] == pytest.approx(
        np.linalg.norm(hull.center_mass - dented.center_mass) / np.sqrt(3), rel=1e-9
    )
    assert [(f.rule, f.limit) for f in findings] == [("MC205", 1.1), ("MC207", 1.0001)]
    # the principal moments the row reports are the ones the ratio used
    assert np.sort(row["collider_mass"]["principal_inertia"]) == pytest.approx(
        np.full(3, 1 / 6), rel=1e-12
    )


def test_physics_comparisons_of_a_box_with_its_own_hull_are_one() -> None:
    from meshcol.analysis.physics import physics_readiness

    stretched = CUBE_VERTICES * [1.0, 2.0, 4.0]
    rows, findings = physics_readiness([body(stretched, CUBE_FACES)])
    assert rows[0]["volume_ratio"] == pytest.approx(1.0, rel=1e-12)
    assert rows[0]["inertia_ratio"] == pytest.approx(1.0, rel=1e-12)
    assert rows[0]["center_of_mass_offset"] == pytest.approx(0.0, abs=1e-12)
    assert findings == []
