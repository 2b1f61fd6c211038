"""Mass properties (meshcol.geometry.mass): analytic shapes, trimesh, parts and frames."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshcol.geometry.mass import (
    combine_mass_properties,
    mass_properties,
    primitive_mass_properties,
)
from meshcol.types import Box, Capsule, Cylinder, Sphere


def _props(mesh: trimesh.Trimesh):
    return mass_properties(mesh.vertices, mesh.faces)


def test_box_is_exact() -> None:
    a, b, c = 2.0, 3.0, 5.0
    mesh = trimesh.creation.box(extents=(a, b, c))
    mesh.apply_translation((10.0, -4.0, 7.0))
    p = _props(mesh)
    v = a * b * c
    assert p.volume == pytest.approx(v, rel=1e-12)
    assert p.center_of_mass == pytest.approx([10.0, -4.0, 7.0], abs=1e-12)
    expected = np.diag([v * (b * b + c * c), v * (a * a + c * c), v * (a * a + b * b)]) / 12
    assert p.inertia == pytest.approx(expected, rel=1e-12, abs=1e-9)
    assert p.area == pytest.approx(2 * (a * b + b * c + a * c), rel=1e-12)
    # the box's shell equals the analytic plates
    analytic = primitive_mass_properties(Box((a, b, c)))
    assert p.shell_inertia == pytest.approx(analytic.shell_inertia, rel=1e-12, abs=1e-9)
    assert analytic.inertia == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("mesh", "primitive", "rel"),
    [
        (trimesh.creation.icosphere(subdivisions=6, radius=0.7), Sphere(0.7), 4e-4),
        (trimesh.creation.cylinder(radius=0.4, height=2.0, sections=512), Cylinder(0.4, 2.0), 1e-4),
        (
            trimesh.creation.capsule(height=1.5, radius=0.3, count=[256, 256]),
            Capsule(0.3, 1.5),
            1e-3,
        ),
    ],
    ids=["sphere", "cylinder", "capsule"],
)
def test_fine_tessellations_converge_to_the_closed_forms(mesh, primitive, rel) -> None:
    p = _props(mesh)
    exact = primitive_mass_properties(primitive)
    assert p.volume == pytest.approx(exact.volume, rel=rel)
    assert p.area == pytest.approx(exact.area, rel=rel)
    assert np.linalg.norm(p.center_of_mass) < 1e-9
    assert p.principal_inertia() == pytest.approx(exact.principal_inertia(), rel=rel)
    assert p.principal_inertia(shell=True) == pytest.approx(
        exact.principal_inertia(shell=True), rel=rel
    )


def test_sphere_closed_forms() -> None:
    """Textbook values for r = 2 (density 1), none taken from the result: V = 32 pi / 3,
    A = 16 pi, solid I = 2/5 V r^2 = 256 pi / 15, shell I = 2/3 A r^2 = 128 pi / 3."""
    exact = primitive_mass_properties(Sphere(2.0))
    assert exact.volume == pytest.approx(32 * np.pi / 3)
    assert exact.area == pytest.approx(16 * np.pi)
    np.testing.assert_allclose(exact.inertia, np.eye(3) * 256 * np.pi / 15, atol=1e-12)
    np.testing.assert_allclose(exact.shell_inertia, np.eye(3) * 128 * np.pi / 3, atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_matches_trimesh_on_random_convex_meshes(seed: int) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(60, 3)) * [1.0, 2.0, 0.5] + rng.normal(size=3) * 100
    mesh = trimesh.convex.convex_hull(points)
    p = _props(mesh)
    reference = mesh.mass_properties  # density 1: mass = volume, inertia about the COM
    assert p.volume == pytest.approx(reference["volume"], rel=1e-9)
    assert p.center_of_mass == pytest.approx(reference["center_mass"], rel=1e-9, abs=1e-9)
    assert p.inertia == pytest.approx(reference["inertia"], rel=1e-7, abs=1e-9)


def test_matches_trimesh_on_a_concave_mesh(samples) -> None:
    mesh = trimesh.load(samples / "bowl" / "bowl.obj", force="mesh")
    p = _props(mesh)
    reference = mesh.mass_properties
    assert p.volume == pytest.approx(reference["volume"], rel=1e-9)
    assert p.center_of_mass == pytest.approx(reference["center_mass"], abs=1e-9)
    assert p.inertia == pytest.approx(reference["inertia"], rel=1e-7, abs=1e-10)


def test_inside_out_mesh_has_negative_volume_and_the_same_centre() -> None:
    mesh = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    mesh.apply_translation((1.0, 1.0, 1.0))
    p = _props(mesh)
    q = mass_properties(mesh.vertices, mesh.faces[:, ::-1])
    assert q.volume == pytest.approx(-p.volume)
    assert q.center_of_mass == pytest.approx(p.center_of_mass)
    assert q.inertia == pytest.approx(-p.inertia)


def test_combined_parts_equal_the_whole() -> None:
    left = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    left.apply_translation((-0.5, 0.0, 0.0))
    right = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    right.apply_translation((0.5, 0.0, 0.0))
    whole = primitive_mass_properties(Box((2.0, 1.0, 1.0)))
    combined = combine_mass_properties([_props(left), _props(right)])
    assert combined.volume == pytest.approx(whole.volume)
    assert combined.center_of_mass == pytest.approx([0, 0, 0], abs=1e-12)
    assert combined.inertia == pytest.approx(whole.inertia, abs=1e-12)


def test_transformed_equals_the_moved_mesh() -> None:
    mesh = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    pose = trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3))
    pose[:3, 3] = (4.0, 5.0, 6.0)
    moved = mesh.copy()
    moved.apply_transform(pose)
    assert _props(mesh).transformed(pose).inertia == pytest.approx(_props(moved).inertia)
    assert _props(mesh).transformed(pose).center_of_mass == pytest.approx(
        _props(moved).center_of_mass
    )


def test_flat_mesh_has_no_solid_values_but_a_shell() -> None:
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 1]])
    p = mass_properties(vertices, faces)
    assert p.volume == 0.0 and np.isnan(p.center_of_mass).all()
    assert p.area == pytest.approx(1.0)
    assert p.shell_center_of_mass == pytest.approx([1 / 3, 1 / 3, 0])


@pytest.mark.parametrize(
    "primitive", [Sphere(0.7), Box((0.5, 1.0, 2.0)), Capsule(0.3, 1.5), Cylinder(0.4, 2.0)]
)
def test_primitive_volumes_agree_with_the_fit_module(primitive) -> None:
    """geometry.mass sits below collision.fit, so each has its own primitive volume: they
    must stay equal (inspect's physics rows and fit's volume ratios use one each)."""
    from meshcol.collision.fit import primitive_volume

    assert primitive_mass_properties(primitive).volume == pytest.approx(
        primitive_volume(primitive), rel=1e-12
    )
