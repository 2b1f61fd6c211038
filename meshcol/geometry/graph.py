"""Connected components of an undirected graph given as an edge list: numpy only.

The one connected-components of the package (mesh pieces, coplanar polygons, merged hull
points, the face graph of orientation). It gives scipy's ``connected_components(graph,
directed=False)`` result exactly (the count, and labels numbered in the order of each
component's smallest node), without importing scipy: a one-file ``inspect`` (the asset that
changed in a ``meshcol ci`` run) would otherwise spend most of its time importing
``scipy.sparse``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["connected_components"]


def connected_components(node_count: int, edges: np.ndarray) -> tuple[int, np.ndarray]:
    """Components of the undirected graph on ``node_count`` nodes with ``edges``.

    Parameters
    ----------
    node_count : int
        Nodes ``0 .. node_count - 1`` (nodes on no edge are components of their own).
    edges : (k, 2) int
        Node pairs, either order, repeats and self-loops allowed.

    Returns
    -------
    count : int
        The number of components.
    labels : (node_count,) int32
        Each node's component, ``0 .. count - 1`` in the order of each component's smallest
        node (scipy's labels, dtype included).

    Notes
    -----
    Union by the smaller label with full path compression, vectorised: each round hooks the
    root of every edge's larger end onto the smaller root (``np.minimum.at``, so concurrent
    hooks onto one root keep the smallest), then jumps pointers until every node points at a
    root. A node's pointer never increases and every round with an edge across two roots
    lowers one, so the rounds end; the roots are then each component's smallest node.
    """
    pairs = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    parent = np.arange(node_count, dtype=np.int64)
    a, b = pairs[:, 0], pairs[:, 1]
    while len(a):
        root_a, root_b = parent[a], parent[b]
        apart = root_a != root_b
        if not apart.any():
            break
        a, b, root_a, root_b = a[apart], b[apart], root_a[apart], root_b[apart]
        np.minimum.at(parent, np.maximum(root_a, root_b), np.minimum(root_a, root_b))
        while True:
            up = parent[parent]
            if np.array_equal(up, parent):
                break
            parent = up
    roots, labels = np.unique(parent, return_inverse=True)
    dtype = np.int32 if node_count < 2**31 else np.int64
    return len(roots), labels.reshape(-1).astype(dtype)
