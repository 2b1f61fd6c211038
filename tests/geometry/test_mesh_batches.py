"""The batched mesh measures of inspect against the mesh-by-mesh code, to the last bit.

``mesh_topology_batch``, ``oriented_volume_batch`` and ``mass_properties_batch`` measure many
meshes in one pass (:mod:`meshcol.analysis.geometry_cache`'s ``measure_geometries``); every
report of ``meshcol inspect`` stays byte-identical only if each mesh's numbers are exactly
those of the single-mesh functions. The reference here is straightforward per-mesh code: the
single-mesh functions of :mod:`meshcol.geometry.topology` and :mod:`meshcol.geometry.mass`,
and plain Python loops over the edges for the counts. The meshes are dirty on purpose: random
faces (open, non-manifold, repeated corners, duplicates), closed ones flipped, doubled,
inconsistently wound, flat, collapsed to a point, far from the origin.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from meshcol.analysis.geometry_cache import LocalGeometry, measure_geometries
from meshcol.collision.mesh_topology import mesh_topology_batch
from meshcol.geometry.mass import mass_properties, mass_properties_batch
from meshcol.geometry.topology import oriented_volume, segment_sums

TETRA = np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]])
OCTA = np.array(
    [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
)


def dirty_mesh(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One random mesh of the kinds inspect must get right (see the module notes)."""
    kind = int(rng.integers(0, 7))
    scale = 10.0 ** rng.uniform(-3, 3)
    shift = rng.normal(size=3) * 10.0 ** rng.uniform(-2, 5)
    if kind == 0:  # random faces: open, non-manifold, repeated corners, duplicates
        n = int(rng.integers(3, 12))
        faces = rng.integers(0, n, size=(int(rng.integers(1, 30)), 3))
    else:
        base = TETRA if kind % 2 else OCTA
        n = int(base.max()) + 1
        faces = base.copy()
        if kind == 3:  # one face flipped: inconsistent winding
            faces[int(rng.integers(len(faces)))] = faces[int(rng.integers(len(faces)))][::-1]
        if kind == 4:  # duplicates and a fin
            faces = np.vstack([faces, faces[: int(rng.integers(1, 3))], [[0, 1, n - 1]]])
        if kind == 5:  # two copies, one inside out
            faces = np.vstack([faces, faces[:, ::-1] + n])
            n *= 2
        if rng.random() < 0.3:
            faces = faces[:, ::-1]
        faces = faces[rng.permutation(len(faces))]
    vertices = rng.normal(size=(n, 3)) * scale + shift
    if kind == 6:  # flat
        vertices[:, 2] = shift[2]
    if rng.random() < 0.05:  # collapsed to one point: no volume, no area
        vertices[:] = shift
    return np.ascontiguousarray(vertices), np.ascontiguousarray(faces, dtype=np.int64)


def reference_counts(faces: np.ndarray) -> dict[str, int | bool]:
    """The health counts of one mesh by plain loops over its faces and edges."""
    directed = [
        (int(f[i]), int(f[(i + 1) % 3])) for f in faces for i in range(3) if f[i] != f[(i + 1) % 3]
    ]
    uses = Counter(tuple(sorted(e)) for e in directed)
    forward = Counter(tuple(sorted(e)) for e in directed if e[0] < e[1])
    whole = [f for f in faces if len(set(f.tolist())) == 3]
    kept = [(int(f[i]), int(f[(i + 1) % 3])) for f in whole for i in range(3)]
    kept_balance = Counter()
    for a, b in kept:
        kept_balance[(min(a, b), max(a, b))] += 1 if a < b else -1
    boundary = sum(1 for c in uses.values() if c == 1)
    non_manifold = sum(1 for c in uses.values() if c > 2)
    inconsistent = sum(1 for e, c in uses.items() if c == 2 and forward[e] != 1)
    # connected pieces of the used vertices, by union-find
    parent: dict[int, int] = {}

    def root(v: int) -> int:
        while parent.setdefault(v, v) != v:
            v = parent[v]
        return v

    for f in faces.tolist():
        for v in f[1:]:
            parent[root(v)] = root(f[0])
    return {
        "boundary": boundary,
        "non_manifold": non_manifold,
        "inconsistent": inconsistent,
        "closed": bool(uses) and all(c == 2 for c in uses.values()) and inconsistent == 0,
        "balanced": bool(kept) and all(v == 0 for v in kept_balance.values()),
        "duplicates": len(faces) - len({tuple(sorted(f)) for f in faces.tolist()}),
        "components": len({root(v) for v in np.unique(faces).tolist()}),
    }


def meshes_of(seed: int, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [dirty_mesh(rng) for _ in range(count)]


@settings(max_examples=60)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 40))
def test_batched_topology_counts_are_each_meshs_own(seed: int, count: int) -> None:
    meshes = meshes_of(seed, count)
    batch = mesh_topology_batch([f for _, f in meshes], [len(v) for v, _ in meshes])
    for i, (_, faces) in enumerate(meshes):
        expected = reference_counts(faces)
        got = {
            "boundary": int(batch.boundary_edges[i]),
            "non_manifold": int(batch.non_manifold_edges[i]),
            "inconsistent": int(batch.inconsistent_edges[i]),
            "closed": bool(batch.closed[i]),
            "balanced": bool(batch.balanced[i]),
            "duplicates": int(batch.duplicate_faces[i]),
            "components": int(batch.components[i]),
        }
        assert got == expected, i
        assert np.array_equal(batch.used[i], np.unique(faces))
    assert batch.valid.all()


def test_a_mesh_naming_a_vertex_it_lacks_is_left_to_itself() -> None:
    """The core counts nothing of it (and says so); the others are counted as ever, and
    measure_geometries leaves its properties to be measured alone."""
    rng = np.random.default_rng(6)
    good = dirty_mesh(rng)
    bad = (np.zeros((3, 3)), np.array([[0, 1, 3]]))
    batch = mesh_topology_batch([good[1], bad[1], good[1]], [len(good[0]), 3, len(good[0])])
    assert batch.valid.tolist() == [True, False, True]
    assert batch.boundary_edges[1] == 0 and len(batch.used[1]) == 0
    assert (
        batch.boundary_edges[0] == batch.boundary_edges[2] == reference_counts(good[1])["boundary"]
    )
    geometries = [LocalGeometry(*good), LocalGeometry(*bad)]
    measure_geometries(geometries, mass=False)
    assert "edges" in geometries[0].__dict__ and "edges" not in geometries[1].__dict__
    assert mesh_topology_batch([], []).valid.shape == (0,)


def _same(a: object, b: object) -> bool:
    """Equal to the bit: NaN where NaN, the same sign of zero."""
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return x.shape == y.shape and bool(
        np.array_equal(x.view(np.int64), y.view(np.int64))
        or (np.array_equal(x, y, equal_nan=True) and np.array_equal(np.signbit(x), np.signbit(y)))
    )


MASS_FIELDS = ("volume", "center_of_mass", "inertia", "area")
SHELL_FIELDS = ("shell_center_of_mass", "shell_inertia")


@settings(max_examples=60)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 40))
def test_batched_mass_properties_are_each_meshs_bits(seed: int, count: int) -> None:
    meshes = meshes_of(seed, count)
    for (vertices, faces), got in zip(meshes, mass_properties_batch(meshes)):
        expected = mass_properties(vertices, faces)
        for name in MASS_FIELDS + SHELL_FIELDS:
            assert _same(getattr(got, name), getattr(expected, name)), name


def test_batched_mass_properties_of_many_equal_face_counts_and_none() -> None:
    """Large groups (the stacked path) and a mesh without faces (NaN, as one alone)."""
    rng = np.random.default_rng(3)
    meshes = [
        (rng.normal(size=(40, 3)) * 5.0 + 1e4, rng.integers(0, 40, (300, 3))) for _ in range(9)
    ]
    meshes.append((rng.normal(size=(4, 3)), np.zeros((0, 3), np.int64)))
    for (vertices, faces), got in zip(meshes, mass_properties_batch(meshes)):
        expected = mass_properties(vertices, faces)
        for name in MASS_FIELDS + SHELL_FIELDS:
            assert _same(getattr(got, name), getattr(expected, name)), name
    assert mass_properties_batch([]) == []


def test_stacks_past_the_triangle_bound_give_the_same_bits(monkeypatch) -> None:
    """A face count's meshes split into several stacks (bounded memory): the same numbers."""
    import meshcol.geometry.mass as mass_module

    meshes = meshes_of(10, 40)
    expected = mass_properties_batch(meshes)
    monkeypatch.setattr(mass_module, "MASS_BATCH_TRIANGLES", 20)
    assert max(len(s) for s in mass_module._stacks(np.array([12] * 9))) == 1
    assert [len(s) for s in mass_module._stacks(np.array([4] * 11))] == [5, 5, 1]
    for got, want in zip(mass_properties_batch(meshes), expected):
        for name in MASS_FIELDS + SHELL_FIELDS:
            assert _same(getattr(got, name), getattr(want, name)), name


def test_segment_sums_are_numpys_sum_of_each_segment() -> None:
    rng = np.random.default_rng(4)
    lengths = rng.integers(0, 300, 200)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    values = rng.normal(size=int(offsets[-1])) * 10.0 ** rng.uniform(-8, 8, int(offsets[-1]))
    sums = segment_sums(values, offsets)
    for i in range(len(lengths)):
        assert _same(sums[i], values[offsets[i] : offsets[i + 1]].sum())


@settings(max_examples=40)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 30))
def test_measured_geometries_equal_each_one_measured_alone(seed: int, count: int) -> None:
    """What inspect reads of each geometry (counts, heights, volume and orientation, used
    vertices, manifold3d's status, mass) after one batched measure, against each alone."""
    meshes = meshes_of(seed, count)
    batched = [LocalGeometry(v, f) for v, f in meshes]
    alone = [LocalGeometry(v, f) for v, f in meshes]
    measure_geometries(batched)
    for a, b in zip(batched, alone):
        assert a.edges == b.edges and a.duplicates == b.duplicates
        assert a.components == b.components and a.balanced == b.balanced
        assert a.manifold_status == b.manifold_status
        assert np.array_equal(a.used, b.used) and a.used.dtype == b.used.dtype
        assert all(_same(x, y) for x, y in zip(a.heights, b.heights))
        measured, expected = a.oriented_volume, oriented_volume(b.vertices, b.faces)
        assert (measured is None) == (expected is None)
        if expected is not None:
            assert _same(measured[0], expected[0]) and measured[1] == expected[1]
        for name in MASS_FIELDS + SHELL_FIELDS:
            assert _same(getattr(a.mass, name), getattr(b.mass, name)), name


def test_mass_rows_are_each_bodys_own() -> None:
    """physics' mass rows, made for all bodies at once, against each body's made alone
    (``principal_inertia`` and a finiteness check per field), None and NaN included."""
    from meshcol.analysis.physics import _mass_dicts

    def alone(p):
        def clean(values):
            values = np.asarray(values, dtype=np.float64)
            return values.tolist() if np.all(np.isfinite(values)) else None

        return {
            "volume": p.volume,
            "center_of_mass": clean(p.center_of_mass),
            "inertia": clean(p.inertia),
            "principal_inertia": clean(p.principal_inertia()),
            "area": p.area,
            "shell_center_of_mass": clean(p.shell_center_of_mass),
            "shell_inertia": clean(p.shell_inertia),
            "shell_principal_inertia": clean(p.principal_inertia(shell=True)),
        }

    masses = [mass_properties(v, f) for v, f in meshes_of(5, 60)]
    masses[3:3] = [None, None]
    rows = _mass_dicts(masses)
    for p, row in zip(masses, rows):
        assert row == (None if p is None else alone(p))
        if p is not None:
            assert repr(row) == repr(alone(p))  # the same floats, -0.0 and all
    assert any(row is not None and row["principal_inertia"] is None for row in rows)
    assert _mass_dicts([None]) == [None]


def test_native_face_heights_are_numpys_bits() -> None:
    """The core's face heights against numpy's face_heights: random, tiny, huge and far
    triangles, slivers, repeated corners, zero-length edges and NaN corners."""
    from meshcol.collision.mesh_topology import face_heights as native_face_heights
    from meshcol.geometry.triangles import face_heights

    rng = np.random.default_rng(8)
    n = 20_000
    vertices = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-8, 8, (n, 1)) + rng.normal(
        size=(n, 3)
    ) * 10.0 ** rng.uniform(-3, 6, (n, 1))
    vertices[:50] = vertices[50:100]  # coincident corners
    vertices[100:110] = np.nan
    faces = rng.integers(0, n, size=(60_000, 3))
    faces[:200, 1] = faces[:200, 0]  # repeated corners
    faces[200:400] = rng.integers(0, 110, size=(200, 3))  # coincident and NaN corners
    slivers = np.column_stack([faces[400:600, 0], faces[400:600, 0] + 1, faces[400:600, 0] + 2])
    vertices[slivers[:, 2] % n] = 0.5 * (vertices[slivers[:, 0] % n] + vertices[slivers[:, 1] % n])
    faces[400:600] = slivers % n
    expected = face_heights(vertices, faces)
    got = native_face_heights(vertices, faces)
    assert _same(got[0], expected[0])
    assert np.array_equal(got[1], expected[1])


def test_moment_ratios_are_each_pairs_own() -> None:
    """physics' moment ratios of all pairs at once against the pair alone (the old per-body
    code), with zero volumes, inside-out solids, NaN and missing rows among them."""
    from meshcol.analysis.physics import _mass_dicts, _moment_ratios

    def alone(a, b):
        if a is None or b is None or a["volume"] == 0 or b["volume"] == 0:
            return None
        if a["principal_inertia"] is None or b["principal_inertia"] is None:
            return None
        per_mass_a = np.asarray(a["principal_inertia"], dtype=np.float64) / a["volume"]
        per_mass_b = np.asarray(b["principal_inertia"], dtype=np.float64) / b["volume"]
        if not (np.all(np.isfinite(per_mass_a)) and np.all(np.isfinite(per_mass_b))):
            return None
        per_mass_a, per_mass_b = np.sort(np.abs(per_mass_a)), np.sort(np.abs(per_mass_b))
        if np.any(per_mass_a <= 0) or np.any(per_mass_b <= 0):
            return None
        return float(np.max(np.maximum(per_mass_a / per_mass_b, per_mass_b / per_mass_a)))

    rows = _mass_dicts([mass_properties(v, f) for v, f in meshes_of(9, 120)])
    rows[5] = None
    pairs = list(zip(rows[0::2], rows[1::2]))
    pairs.append((rows[0], rows[0]))  # equal: ratio 1
    got = _moment_ratios(pairs)
    expected = [alone(a, b) for a, b in pairs]
    assert repr(got) == repr(expected)
    assert got[-1] == 1.0 and any(r is None for r in got) and sum(r is not None for r in got) > 5
