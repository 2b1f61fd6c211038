"""meshcol.geometry.graph.connected_components gives scipy's result exactly: the count and the
labels (numbered by each component's smallest node), dtype included."""

from __future__ import annotations

import numpy as np
import pytest

from meshcol.geometry.graph import connected_components

scipy_sparse = pytest.importorskip("scipy.sparse")
csgraph = pytest.importorskip("scipy.sparse.csgraph")


def _scipy(n: int, edges: np.ndarray) -> tuple[int, np.ndarray]:
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    graph = scipy_sparse.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    return csgraph.connected_components(graph, directed=False)


def _same(n: int, edges: np.ndarray) -> None:
    count, labels = connected_components(n, edges)
    want_count, want_labels = _scipy(n, edges)
    assert count == want_count
    assert labels.dtype == want_labels.dtype
    np.testing.assert_array_equal(labels, want_labels)


def test_random_graphs_match_scipy() -> None:
    rng = np.random.default_rng(31)
    for _ in range(400):
        n = int(rng.integers(1, 120))
        k = int(rng.integers(0, 2 * n))
        _same(n, rng.integers(0, n, (k, 2)))


@pytest.mark.parametrize("n", [1, 2, 1000, 20_000])
def test_paths_and_stars_in_shuffled_order_match_scipy(n: int) -> None:
    rng = np.random.default_rng(n)
    order = rng.permutation(n)
    path = np.stack([order[:-1], order[1:]], axis=1)
    _same(n, path)
    _same(n, path[::-1, ::-1])
    _same(n, np.stack([np.full(n - 1, order[-1]), order[:-1]], axis=1))  # a star
    _same(n, path[rng.permutation(len(path))][: n // 2])  # pieces of the path


def test_isolated_nodes_self_loops_and_repeats() -> None:
    _same(5, np.zeros((0, 2), dtype=np.int64))
    _same(0, np.zeros((0, 2), dtype=np.int64))
    _same(4, np.array([[2, 2], [3, 1], [1, 3], [3, 1]]))


def test_mesh_pieces_counted_as_before() -> None:
    from meshcol.geometry.topology import component_count

    tetra = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    # two tetrahedra, an unused vertex between them: two pieces
    faces = np.concatenate([tetra, tetra + 5])
    assert component_count(faces, 9) == 2
    assert component_count(tetra, 4) == 1
