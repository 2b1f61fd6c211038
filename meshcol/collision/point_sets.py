"""Fingerprints of packed point sets: how 100,000 bodies' vertex sets are told apart in one
pass (:mod:`meshcol.analysis.bulk_colliders`), a match then confirmed bit for bit."""

from __future__ import annotations

import numpy as np

__all__ = ["point_set_fingerprints"]


def point_set_fingerprints(points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(n,) uint64: the fingerprint of each of the n sets packed in ``points`` ((V, 3)
    float64, C-contiguous), set s being rows ``offsets[s]:offsets[s + 1]``, computed by the
    core on its threads in one pass (``cpp/include/meshcol/point_sets.hpp``): each point's
    three coordinates' bits mixed, weighed by its place in its set, summed (mod 2^64). Equal
    sets (the same bits) have equal fingerprints; unequal ones almost never do."""
    from meshcol._native import core

    return core.point_set_fingerprints(points, np.ascontiguousarray(offsets, dtype=np.int64))
