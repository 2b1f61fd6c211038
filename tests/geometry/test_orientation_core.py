"""The core's orientation (``orient_faces``, behind
:func:`meshcol.collision.orientation.orient_consistently`) against the Python version it
replaced (tests/geometry/orientation_reference.py): the same faces, flips and flags on
shuffled, flipped, nested, open, non-manifold and non-orientable meshes (issue 29)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from dirty_meshes import HOSTS, moebius, shuffled
from orientation_reference import reference_orientation

from meshcol.collision.orientation import orient_consistently


def _join(*meshes: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    offsets = np.cumsum([0] + [len(v) for v, _ in meshes[:-1]])
    v = np.concatenate([v for v, _ in meshes])
    f = np.concatenate([f + o for (_, f), o in zip(meshes, offsets)])
    return v, f


def _box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    box = trimesh.creation.box(bounds=[lo, hi])
    return np.asarray(box.vertices), np.asarray(box.faces, dtype=np.int64)


def _cases():
    for name, make in HOSTS.items():
        v, f = make()
        for seed in range(3):
            yield f"{name}/shuffled{seed}", v, shuffled(f, seed)
        yield f"{name}/inside-out-shuffled", v, shuffled(f[:, ::-1], 9)
        yield f"{name}/open-shuffled", v, shuffled(f[: len(f) - 7], 2)
    # nested shells: a box, its cavity, an island in the cavity, a box beside
    nested = _join(
        _box((0, 0, 0), (1, 1, 1)),
        _box((0.2, 0.2, 0.2), (0.8, 0.8, 0.8)),
        _box((0.4, 0.4, 0.4), (0.6, 0.6, 0.6)),
        _box((2, 0, 0), (3, 1, 1)),
    )
    for seed in range(3):
        yield f"nested/shuffled{seed}", nested[0], shuffled(nested[1], seed)
    v, f = moebius(0.2)
    yield "moebius", v, shuffled(f, 1)
    # a Moebius strip beside a shuffled box (one non-orientable, one closed component)
    v, f = _join(moebius(0.2), _box((3, 3, 3), (4, 4, 4)))
    yield "moebius+box", v, shuffled(f, 5)
    # non-manifold: two boxes sharing an edge's vertices (an edge of four faces)
    box = _box((0, 0, 0), (1, 1, 1))
    twin = (box[0] + [1, 1, 0], box[1])
    v, f = _join(box, twin)
    yield "edge-shared", v, shuffled(f, 6)
    # random soups: triangles on few vertices, so that edges are shared 1, 2, 3+ times (no
    # collapsed faces: a centroid on a collapsed face of another component is on its surface,
    # where the core's exact test leaves a component outward and the winding number of the
    # Python version gave whatever it rounded to)
    rng = np.random.default_rng(29)
    for k in range(6):
        v = rng.normal(size=(12, 3))
        f = np.array([rng.choice(12, 3, replace=False) for _ in range(40)])
        yield f"soup{k}", v, f


def test_the_core_orients_as_the_python_version() -> None:
    for name, v, f in _cases():
        _same(name, v, f)


def _same(name: str, v: np.ndarray, f: np.ndarray) -> None:
    found = orient_consistently(v, f)
    expected = reference_orientation(v, f)
    np.testing.assert_array_equal(found.faces, expected.faces, err_msg=name)
    np.testing.assert_array_equal(found.flipped, expected.flipped, err_msg=name)
    assert found.orientable == expected.orientable, name
    assert found.closed == expected.closed, name


def test_the_nested_shells_come_out_outward_inward_outward() -> None:
    outer, cavity, island = (
        _box((0, 0, 0), (1, 1, 1)),
        _box((0.2, 0.2, 0.2), (0.8, 0.8, 0.8)),
        _box((0.4, 0.4, 0.4), (0.6, 0.6, 0.6)),
    )
    v, f = _join(outer, (cavity[0], cavity[1][:, ::-1]), island)
    found = orient_consistently(v, shuffled(f, 11))
    np.testing.assert_array_equal(found.faces, f)
    assert found.orientable and found.closed


def test_bad_indices_are_refused() -> None:
    v, f = _box((0, 0, 0), (1, 1, 1))
    with pytest.raises(ValueError, match="out of range"):
        orient_consistently(v, np.concatenate([f, [[0, 1, 99]]]))
    assert orient_consistently(v, np.zeros((0, 3), dtype=np.int64)).faces.shape == (0, 3)
