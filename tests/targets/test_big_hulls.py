"""Big hulls under a target: bounded work and memory whatever the exact hull's size.

A cone of many sections has one vertex (its apex) on as many polygons. Fitted to
``max_faces_per_vertex`` alone, the budget rounds used to ask the supporting-plane hull for
one polygon fewer than the exact hull (thousands of planes: a Menagerie part of 23,841
polygons ran for hours). Now at most ``MAX_PLANE_BUDGET`` planes, said in a note. And the
distance of thousands of points to a hull of thousands of facets goes by blocks of points,
to the same distances."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

import meshcol.collision.facet_distance as facet_distance
from meshcol.collision.hull import distance_to_hull, exact_hull
from meshcol.collision.limits import measure_parts
from meshcol.collision.target_fit import MAX_PLANE_BUDGET, fit_hull
from meshcol.io.targets import load_target

SECTIONS = 1200


def test_a_many_polygon_vertex_is_fitted_within_the_plane_cap(tmp_path: Path) -> None:
    cone = trimesh.creation.cone(radius=1.0, height=2.0, sections=SECTIONS)
    exact = exact_hull(cone.vertices)
    assert len(exact.faces) > 2 * MAX_PLANE_BUDGET  # the apex: about SECTIONS polygons
    path = tmp_path / "apex.toml"
    path.write_text('title = "apex"\nunits = "m"\n[limits]\nmax_faces_per_vertex = 32\n')
    fit = fit_hull(cone.vertices, load_target(str(path)))
    assert any(note.startswith(f"plane budget capped at {MAX_PLANE_BUDGET}") for note in fit.notes)
    measures = measure_parts(list(fit.parts))
    assert int(measures.max_faces_per_vertex[0]) <= 32
    # the part encloses the cone: every vertex inside it (within rounding)
    part = exact_hull(fit.parts[0][0])
    assert float(distance_to_hull(cone.vertices, part).max()) <= 1e-9


def test_distances_by_blocks_equal_one_product(monkeypatch) -> None:
    rng = np.random.default_rng(7)
    sphere = exact_hull(trimesh.creation.icosphere(subdivisions=3).vertices)
    points = rng.normal(size=(3000, 3)) * 1.5  # inside and outside
    whole = distance_to_hull(points, sphere)
    assert (whole > 0).any() and (whole == 0).any()
    monkeypatch.setattr(facet_distance, "PRODUCT_BLOCK", 10 * len(sphere.faces))  # 10 rows
    assert facet_distance.rows_per_block(len(sphere.faces)) == 10
    np.testing.assert_array_equal(distance_to_hull(points, sphere), whole)
