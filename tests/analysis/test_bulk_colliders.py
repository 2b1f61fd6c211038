"""The colliders of plain bodies built as arrays (``analysis.bulk_colliders``) are those of the
per-body builders, to the bit: shapes, rows, kinds; and scenes they cannot take go to the
per-body builders."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import meshcol.analysis.bulk_colliders as bulk_module
import meshcol.analysis.colliders as colliders_module
from meshcol.analysis.bulk_colliders import bulk_colliders
from meshcol.analysis.colliders import Colliders, build_colliders
from meshcol.collision.shapes import ConvexSet
from meshcol.types import Body, Box, Capsule, Ellipsoid, Sphere


def _body(name: str, vertices, faces=None, **fields) -> Body:
    vertices = np.asarray(vertices)
    faces = np.zeros((1, 3), dtype=np.int64) if faces is None else faces
    return Body(name=name, source=None, vertices=vertices, faces=faces, pose=np.eye(4), **fields)


def _per_body(bodies, monkeypatch, **options) -> Colliders:
    with monkeypatch.context() as patch:
        patch.setattr(colliders_module, "bulk_colliders", lambda *args: None)
        return build_colliders(bodies, **options)


def _same(a: Colliders, b: Colliders) -> None:
    assert a.kinds == b.kinds
    assert a.bodies == b.bodies
    assert a.warnings == b.warnings
    for field in ("part_body", "part_index", "body_part_offsets", "part_label"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert (a.part_offsets is None) == (b.part_offsets is None)
    for name in (*ConvexSet._FIELDS, "hull_status"):  # every array of the packed set
        x, y = getattr(a.shapes, name), getattr(b.shapes, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name


def _scene() -> list[Body]:
    """Unique hulls, repeats by value and by array, primitives between them, a flat polygon,
    a point, NaN and -0.0 against 0.0, float32 vertices, a ``mesh`` body."""
    rng = np.random.default_rng(7)
    clouds = [rng.normal(size=(int(rng.integers(4, 40)), 3)) for _ in range(30)]
    shared = clouds[3]
    zero = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    negative_zero = zero.copy()
    negative_zero[0, 0] = -0.0
    bodies = [_body(f"c{i}", c) for i, c in enumerate(clouds)]
    bodies += [
        _body("copy-by-value", clouds[5].copy()),
        _body("shared-1", shared),
        Body.of_primitive("ball", None, Sphere(0.5)),
        _body("shared-2", shared),
        Body.of_primitive("crate", None, Box((1.0, 2.0, 3.0))),
        Body.of_primitive("ball-2", None, Sphere(0.5)),
        _body("flat", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
        _body("point", [[1.0, 2.0, 3.0]]),
        _body("nan", [[0, 0, 0], [1, 0, 0], [0, np.nan, 0], [0, 0, 1]]),
        _body("zero", zero),
        _body("negative-zero", negative_zero),
        _body("zero-again", zero.copy()),
        _body("single", clouds[8].astype(np.float32)),
        _body("mesh", clouds[9].copy(), collider="mesh"),
        Body.of_primitive("pill", None, Capsule(0.2, 1.0)),
        Body.of_primitive("egg", None, Ellipsoid((0.3, 0.2, 0.1))),
        _body("after-egg", clouds[11].copy()),
        Body.of_primitive("egg-2", None, Ellipsoid((0.3, 0.2, 0.1))),
        _body("last-copy", clouds[29].copy()),
    ]
    return bodies


@pytest.mark.parametrize("kind", ["hull", "mesh"])
def test_bulk_is_the_per_body_build(monkeypatch, kind):
    bodies = _scene()
    assert bulk_colliders(bodies, kind, "hull") is not None  # the bulk path is the one tested
    _same(build_colliders(bodies, kind), _per_body(bodies, monkeypatch, kind=kind))


def test_bulk_of_unique_meshes_only(monkeypatch):
    rng = np.random.default_rng(3)
    bodies = [_body(f"b{i}", rng.normal(size=(24, 3))) for i in range(200)]
    got = build_colliders(bodies)
    _same(got, _per_body(bodies, monkeypatch))
    assert len(got.shapes) == 200


def test_a_fingerprint_that_matches_different_sets_goes_to_the_per_body_build(monkeypatch):
    bodies = _scene()
    # every set of one size alike
    monkeypatch.setattr(
        bulk_module, "point_set_fingerprints", lambda p, o: np.zeros(len(o) - 1, np.uint64)
    )
    assert bulk_colliders(bodies, "hull", "hull") is None
    _same(build_colliders(bodies), _per_body(bodies, monkeypatch))


@pytest.mark.parametrize(
    "odd",
    [
        lambda bodies: [*bodies, _body("fitted", bodies[0].vertices.copy(), collider="fit")],
        lambda bodies: [*bodies, _body("surface", bodies[0].vertices.copy(), collider="mesh")],
    ],
    ids=["fit", "mesh-triangles"],
)
def test_bodies_the_bulk_cannot_take(odd):
    rng = np.random.default_rng(1)
    bodies = odd([_body(f"b{i}", rng.normal(size=(12, 3))) for i in range(3)])
    assert bulk_colliders(bodies, "hull", "triangles") is None


def test_a_body_of_parts_goes_to_the_per_body_build():
    rng = np.random.default_rng(2)
    plain = _body("plain", rng.normal(size=(8, 3)))
    parts = dataclasses.replace(
        _body("parts", rng.normal(size=(8, 3)), np.array([[0, 1, 2], [3, 4, 5]])),
        parts=("a", "b"),
        part_faces=np.array([0, 1, 2]),
    )
    assert bulk_colliders([plain, parts], "hull", "hull") is None


def _numpy_fingerprints(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The fingerprints as the bulk colliders computed them in numpy before the core did."""
    counts = np.diff(offsets)
    rows = points.reshape(-1).view(np.uint64).reshape(-1, 3)
    mixed = rows[:, 0] * np.uint64(0xBF58476D1CE4E5B9)
    mixed += rows[:, 1] * np.uint64(0x94D049BB133111EB)
    mixed += rows[:, 2] * np.uint64(0xD6E8FEB86659FD93)
    mixed ^= mixed >> np.uint64(29)
    place = np.arange(len(rows), dtype=np.uint64)
    place -= np.repeat(offsets[:-1].astype(np.uint64), counts)
    place <<= np.uint64(1)
    place += np.uint64(1)
    mixed *= place
    out = np.zeros(len(counts), dtype=np.uint64)
    filled = counts > 0
    if filled.any():
        out[filled] = np.add.reduceat(mixed, offsets[:-1][filled])
    return out


def test_the_cores_fingerprints_are_the_numpy_ones():
    from meshcol._native import core
    from meshcol.collision.point_sets import point_set_fingerprints

    rng = np.random.default_rng(8)
    counts = rng.integers(0, 70, size=3000)
    counts[:5] = 0  # empty sets, first and among the others
    counts[100:110] = 0
    offsets = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    points = rng.normal(size=(int(offsets[-1]), 3)) * 10.0 ** rng.integers(-300, 300, (1, 3))
    points[::7] = -0.0
    points[1::11] = np.nan
    points[2::13] = np.float32(1.0) / np.float32(3.0)
    got = point_set_fingerprints(points, offsets)
    assert (
        got.dtype == np.uint64 and got.tobytes() == _numpy_fingerprints(points, offsets).tobytes()
    )
    assert core.point_set_fingerprints(points, offsets, threads=1).tobytes() == got.tobytes()
    with pytest.raises(ValueError, match="offsets"):
        core.point_set_fingerprints(points, offsets[::-1].copy())
