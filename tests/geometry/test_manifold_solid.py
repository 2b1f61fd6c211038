"""meshcol's one way to build a manifold3d solid. manifold3d 3.5 reads memory it never wrote
while it checks a mesh whose edges do not pair up (valgrind: ``Impl::IsManifold``), and the
full suite segfaulted in session 15 on ``inspect`` of a cube with an extra face. Such meshes
never reach it; its verdict on them, NotManifold, is given without it."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshcol.geometry.topology as topology
from meshcol.analysis.geometry_cache import _manifold_status

manifold3d = pytest.importorskip("manifold3d")

CUBE = trimesh.creation.box()


def _status(vertices: np.ndarray, faces: np.ndarray) -> str:
    return str(topology.manifold_solid(vertices, faces).status().name)


@pytest.fixture
def given(monkeypatch) -> list[np.ndarray]:
    """The triangles each manifold3d.Mesh64 is built from."""
    seen: list[np.ndarray] = []
    real = manifold3d.Mesh64

    def recording(*args, **kwargs):
        seen.append(np.asarray(kwargs["tri_verts"]).reshape(-1, 3))
        return real(*args, **kwargs)

    monkeypatch.setattr(manifold3d, "Mesh64", recording)
    return seen


def test_faces_with_a_repeated_corner_never_reach_manifold3d(given) -> None:
    faces = np.vstack([CUBE.faces, [[0, 0, 1]], [[2, 3, 2]], [[4, 4, 4]]])
    assert _manifold_status(CUBE.vertices, faces) == "NoError"
    (tri,) = given
    assert np.array_equal(tri, CUBE.faces)


def test_a_mesh_whose_edges_do_not_pair_never_reaches_manifold3d(given) -> None:
    v = np.vstack([CUBE.vertices, [[0.5, -0.5, -0.5]]])
    for faces in (
        np.vstack([CUBE.faces, [[0, 4, 8]]]),  # a fin on the cube (the suite's segfault)
        CUBE.faces[:-1],  # open
        np.vstack([CUBE.faces[:-1], CUBE.faces[-1:, ::-1]]),  # one face flipped
        np.vstack([CUBE.faces, CUBE.faces[:1]]),  # a face twice
    ):
        assert _manifold_status(v, faces) == "NotManifold"
    assert all(len(tri) == 0 for tri in given) and len(given) == 4


def test_the_verdicts_on_meshes_whose_edges_pair_are_manifold3ds() -> None:
    v, f = CUBE.vertices, CUBE.faces
    assert _status(v, f) == "NoError"
    assert _status(v, np.vstack([f, [[1, 0, 0]]])) == "NoError"  # an extra sliver: left out
    assert _status(v, np.vstack([f, f[:, ::-1]])) == "NoError"  # doubled inside out: paired
    two = np.vstack([f, f + len(v)])
    assert _status(np.vstack([v, v + 0.25]), two) == "NoError"  # two overlapping cubes
    assert _status(v, np.array([[0, 0, 1]])) == "NotManifold"  # nothing left
    solid = topology.manifold_solid(v, f[:-1])
    assert solid.is_empty() and solid.status().name == "NotManifold"
