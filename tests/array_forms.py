"""The forms an index array can reach the core in, shared by the batch tests that check every
form is read alike (in place where it already is the core's form, converted otherwise)."""

from __future__ import annotations

import numpy as np


def unaligned_copy(a: np.ndarray) -> np.ndarray:
    """A C-contiguous copy of ``a`` whose data sits one byte off its dtype's alignment."""
    raw = np.empty(a.nbytes + 1, dtype=np.uint8)
    out = raw[1:].view(a.dtype).reshape(a.shape)
    out[...] = a
    assert not out.flags.aligned and out.flags.c_contiguous
    return out


def pair_forms(pairs: np.ndarray) -> list:
    """``pairs`` (an (n, 2) int64 array) as arrays, read-only, lists, tuples, numpy scalars,
    int32, Fortran order, strided views, the other byte order, a subclass, unaligned data."""
    read_only = pairs.copy()
    read_only.flags.writeable = False
    n = len(pairs)
    return [
        pairs,
        read_only,
        pairs.tolist(),
        tuple(map(tuple, pairs.tolist())),
        [list(map(np.int64, row)) for row in pairs],  # numpy scalars: converted
        pairs.astype(np.int32),
        np.asfortranarray(pairs),
        np.ascontiguousarray(pairs.T).T,  # a strided view
        pairs.astype(pairs.dtype.newbyteorder()),  # non-native byte order: converted
        pairs.view(np.ma.MaskedArray),  # a subclass: not read from numpy's struct
        unaligned_copy(pairs),
        pairs.reshape(1, n, 2)[0],  # a C-contiguous view of another array
    ]
