"""The parts -> mesh Hausdorff distance is a proved upper bound (issue 29, item 3).

A sample of 2,000 points read up to 23% below a denser sampling, so ``--max-hausdorff`` could
pass a body over its limit. The figure is now a branch-and-bound maximum over the parts'
triangles of a 1-Lipschitz distance: checked against a dense oracle (the parts' surfaces
sampled at 40,000 points; on a real organic mesh in the slow lane, 250,000 under ``make test``
and 1,000,000 under the nightly profile), it is never
below it and not above it by more than 5% (the bound's 2% of what it measured, plus the
dense sample's own shortfall) plus 1e-4 of the diagonal.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from meshcol.collision.mesh_query import MeshSet
from meshcol.decomposition.fidelity import (
    BOUND_ABSOLUTE_FRACTION,
    SHARED_FACE_FRACTION,
    bounded_maximum,
    fidelity,
    points_to_parts,
    signed_distances_to_solid,
)
from meshcol.geometry.triangles import sample_surface

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "corpus" / "coacd-examples"
DENSE = 40_000
#: The dense oracle on the real mesh: a million points a part set under the nightly profile
#: (HYPOTHESIS_PROFILE=nightly, 45 s for the two sizes), a quarter of that otherwise (11 s).
#: Measured on Octocat, the 250,000-point figure is within 0.4% of the million-point one
#: (17.068 against 17.078 at one slab, 14.292 against 14.342 at four).
REAL_DENSE = 1_000_000 if os.environ.get("HYPOTHESIS_PROFILE") == "nightly" else 250_000
#: The reported bound is at most this factor of the dense figure (plus 1e-4 of the diagonal).
LOOSE = 1.05


def _octocat() -> trimesh.Trimesh:
    path = CORPUS / "Octocat-v2.obj"
    if not path.exists():
        pytest.skip(f"corpus mesh missing: {path}")
    mesh = trimesh.load(path, force="mesh", process=True)
    if not mesh.is_watertight:
        pytest.skip("the corpus mesh is not watertight")
    return mesh


def _parts(mesh: trimesh.Trimesh, k: int) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Hulls of ``k`` slabs of the mesh's vertices along its longest axis: convex parts
    that stick out of a concave mesh, as a coarse decomposition's do."""
    v = np.asarray(mesh.vertices)
    axis = int(np.argmax(np.ptp(v, axis=0)))
    edges = np.quantile(v[:, axis], np.linspace(0, 1, k + 1))
    parts = []
    for lo, hi in itertools.pairwise(edges):
        hull = trimesh.convex.convex_hull(v[(v[:, axis] >= lo) & (v[:, axis] <= hi)])
        parts.append((np.asarray(hull.vertices), np.asarray(hull.faces)))
    return tuple(parts)


def _dense(mesh, parts, count=DENSE, seed=1) -> float:
    """The largest distance to the mesh's solid of ``count`` points of the parts' surfaces on
    the boundary of their union (the same rule as the metric's)."""
    rng = np.random.default_rng(seed)
    areas = np.array([trimesh.Trimesh(v, f).area for v, f in parts])
    counts = np.maximum(1, np.round(count * areas / areas.sum()).astype(int))
    points = np.concatenate([sample_surface(v, f, int(c), rng) for (v, f), c in zip(parts, counts)])
    points = np.concatenate([points, *(v for v, _ in parts)])
    owner = np.concatenate(
        [
            np.repeat(np.arange(len(parts)), counts),
            *(np.full(len(v), i) for i, (v, _) in enumerate(parts)),
        ]
    )
    diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    if len(parts) > 1:
        shared = points_to_parts(points, parts, owner) <= SHARED_FACE_FRACTION * diagonal
        points = points[~shared]
    meshes = MeshSet.from_arrays([(mesh.vertices, mesh.faces)])
    return float(max(0.0, signed_distances_to_solid(points, meshes).max()))


def _check_bound(mesh: trimesh.Trimesh, parts, count: int) -> None:
    reported = fidelity(mesh.vertices, mesh.faces, parts, samples=200).hausdorff_parts_to_mesh
    dense = _dense(mesh, parts, count)
    diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    assert dense > 0.01 * diagonal  # the parts do stick out
    assert reported >= dense
    assert reported <= LOOSE * dense + BOUND_ABSOLUTE_FRACTION * diagonal


@pytest.mark.slow  # 3-8 s: the fast lane (make test-fast) stays under 40 s
def test_parts_to_mesh_bounds_a_dense_sampling() -> None:
    from dirty_meshes import torus

    mesh = trimesh.Trimesh(*torus(), process=False)
    _check_bound(mesh, _parts(mesh, 2), DENSE)


@pytest.mark.slow
@pytest.mark.parametrize("k", [1, 4])
def test_parts_to_mesh_bounds_a_dense_oracle_on_a_real_mesh(k) -> None:
    mesh = _octocat()
    _check_bound(mesh, _parts(mesh, k), REAL_DENSE)


def test_parts_equal_to_the_mesh_are_at_distance_0() -> None:
    """A convex mesh decomposed into itself: its faces lie on the surface, settled at once."""
    mesh = trimesh.creation.icosphere(subdivisions=2)
    parts = ((np.asarray(mesh.vertices), np.asarray(mesh.faces)),)
    reported = fidelity(mesh.vertices, mesh.faces, parts, samples=200).hausdorff_parts_to_mesh
    assert 0.0 <= reported <= 1e-12


def test_bounded_maximum_of_a_known_function() -> None:
    """The distance to a point over a unit square: its maximum is at a corner, exactly."""
    square = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    target = np.array([0.3, 0.2, 0.5])

    def value(points):
        return np.linalg.norm(points - target, axis=1)

    true = float(np.linalg.norm(np.array([1.0, 1.0, 0.0]) - target))
    upper, attained = bounded_maximum(square, value, lambda best: 1e-3)
    assert attained <= true <= upper <= true + 1e-3 + 1e-12


def test_bounded_maximum_past_its_budget_is_still_an_upper_bound() -> None:
    square = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)

    def value(points):
        return np.sin(9 * points[:, 0]) * 0.1 + points[:, 1]  # 1-Lipschitz enough (0.9 + 1)

    dense = np.random.default_rng(0).random((200_000, 2))
    dense = dense[dense.sum(axis=1) <= 1]
    true = float(value(np.c_[dense, np.zeros(len(dense))]).max())
    upper, _ = bounded_maximum(
        square, lambda p: value(p) / 2.0, lambda best: 0.0, max_evaluations=50
    )
    assert upper >= true / 2.0


def test_a_shuffled_mesh_is_measured_as_its_solid() -> None:
    """Half the faces reversed at random (MC403): the same figures as the wound mesh."""
    from dirty_meshes import shuffled

    mesh = trimesh.creation.icosphere(subdivisions=2)
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    hull = trimesh.convex.convex_hull(v[v[:, 0] >= 0] * 1.1)  # half of it, sticking out
    parts = ((np.asarray(hull.vertices), np.asarray(hull.faces)),)
    wound = fidelity(v, f, parts, samples=200)
    dirty = fidelity(v, shuffled(f), parts, samples=200)
    assert dirty.mesh_is_solid and wound.mesh_is_solid
    assert dirty.hausdorff_parts_to_mesh == wound.hausdorff_parts_to_mesh
    assert dirty.mesh_volume == pytest.approx(wound.mesh_volume, rel=1e-12)
