"""The per-pair cache of ``check``: a re-run measures only the pairs whose bodies changed.

``meshcol ci`` re-runs a scene's check when one of its files changed (a manifest's mesh, a
robot's link). The broad phase is cheap and runs again; the narrow phase (convex, mesh and
depth-bound stages, :func:`meshcol.analysis.check.narrow_phase`) runs only on the candidate
pairs this cache has no answer for. Each pair's answer is keyed by (:func:`pair_keys`):

- both bodies' geometry digests (:func:`body_digests`): the body's vertices and faces (or
  its primitive), its collider kind, its convex parts as built (vertices, kinds, parameters,
  offsets in the body) and its named parts' face ranges;
- both bodies' world poses (the parts' world poses, to the bit);
- the settings the narrow phase reads: the tolerance and the broad-phase margin (which part
  pairs are measured), in the pair's orientation (a normal points from ``a`` to ``b``);
- for a row the scene's part filter trimmed (``PairTable.partial``: an MJCF's geom
  filters), the part pairs it measures (their indices within the bodies): a change of
  ``contype``, ``conaffinity`` or ``<pair>`` leaves geometry and poses as they were;
- meshcol's version and :data:`FORMAT_VERSION`.

So a body that moved, was reshaped, added or removed changes the keys of exactly the pairs it
is in; every other pair's row comes back to the bit (the measured columns, as float64 and
int64 bytes), and the report is the same bytes as a cold run's.

The answers of one scene are one entry, ``results/pairs/<name>.npz``, in the result cache's
store (:mod:`meshcol.decomposition.result_cache`: a folder or an fsspec URL, atomic writes);
each run replaces it with the rows of its own table, so pairs that are gone drop out. An entry
that cannot be read, or whose arrays disagree in shape or type, is a miss for every pair.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol._version import __version__
from meshcol.analysis.pairs import MEASURES, PairTable, PlacedColliders

__all__ = ["FORMAT_VERSION", "PairCache", "body_digests", "pair_keys", "select_rows"]

#: The version of an entry's layout and of what a key covers; a new one misses.
FORMAT_VERSION = 1
#: The columns an entry keeps per pair: what the narrow-phase stages fill.
COLUMNS = (*MEASURES, "depth_upper")
#: Bytes of one pair key (a SHA-256 digest).
KEY_BYTES = 32


def body_digests(placed: PlacedColliders, bodies: np.ndarray) -> dict[int, bytes]:
    """``body index -> digest`` of the geometry and pose the narrow phase reads of each body
    in ``bodies`` (indices into ``placed.colliders.bodies``)."""
    colliders = placed.colliders
    shapes = colliders.shapes
    offsets = colliders.body_part_offsets.tolist()
    vertex_offsets = np.asarray(shapes.offsets, dtype=np.int64)
    # every part's rows as bytes, sliced per body without copies
    vertices = _rows(shapes.vertices, np.float64, 24)
    kinds = _rows(shapes.kinds, np.int8, 1)
    params = _rows(shapes.params, np.float64, 32)
    labels = _rows(colliders.part_label, np.int64, 8)
    poses = _rows(placed.part_poses, np.float64, 128)
    starts = vertex_offsets.tolist()
    out: dict[int, bytes] = {}
    for i in np.unique(bodies).tolist():
        body = colliders.bodies[i]
        first, last = offsets[i], offsets[i + 1]
        h = hashlib.blake2b(colliders.kinds[i].encode() + b"\0", digest_size=16)
        if body.primitive is not None:
            h.update(repr(body.primitive).encode() + b"\0")
        else:
            _update(h, body.vertices, np.float64)
            _update(h, body.faces, np.int64)
        if body.part_faces is not None:
            _update(h, body.part_faces, np.int64)
        _update(h, vertex_offsets[first : last + 1] - starts[first], np.int64)
        h.update(vertices[starts[first] : starts[last]])
        h.update(kinds[first:last])
        h.update(params[first:last])
        h.update(labels[first:last])
        h.update(poses[first:last])  # the pose, and part offsets
        out[i] = h.digest()
    return out


def _rows(array: Any, dtype: Any, width: int) -> memoryview:
    """``array`` as one byte row per item (``width`` bytes each), for slicing by item."""
    values = np.ascontiguousarray(array, dtype=dtype)
    if values.size == 0:
        return memoryview(b"")  # every slice of it is empty, as every body's rows are
    return values.reshape(-1).view(np.uint8).data.cast("B", (len(values), width))


def _update(h: Any, array: Any, dtype: Any) -> None:
    """Feed ``array`` to ``h`` with its shape first (one split only of the bytes)."""
    values = np.ascontiguousarray(array, dtype=dtype)
    h.update(np.asarray(values.shape, dtype=np.int64).tobytes())
    h.update(values.tobytes())


def pair_keys(table: PairTable, placed: PlacedColliders, settings: bytes) -> np.ndarray:
    """(k,) ``S32``: each row's key, SHA-256 of ``settings`` and the digests of body ``a``
    then body ``b`` (the orientation is part of the answer)."""
    digests = body_digests(placed, np.concatenate([table.body_a, table.body_b]))
    trimmed = _trimmed_parts(table, placed)
    keys = [
        hashlib.sha256(settings + digests[a] + digests[b] + trimmed.get(row, b"")).digest()
        for row, (a, b) in enumerate(zip(table.body_a.tolist(), table.body_b.tolist()))
    ]
    return np.array(keys, dtype=f"S{KEY_BYTES}") if keys else np.zeros(0, f"S{KEY_BYTES}")


def _trimmed_parts(table: PairTable, placed: PlacedColliders) -> dict[int, bytes]:
    """``row -> bytes`` of each ``partial`` row's part pairs (indices within their bodies,
    sorted), the part filter's choice, which geometry and poses do not fix."""
    rows = np.flatnonzero(table.partial)
    if len(rows) == 0:
        return {}
    index = placed.colliders.part_index
    mine = np.isin(table.part_row, rows)
    row, pairs = table.part_row[mine], index[table.part_pairs[mine]]
    order = np.lexsort((pairs[:, 1], pairs[:, 0], row))
    row, pairs = row[order], np.ascontiguousarray(pairs[order], dtype=np.int64)
    bounds = np.searchsorted(row, rows, side="left"), np.searchsorted(row, rows, side="right")
    return {
        r: b"partial\0" + pairs[start:end].tobytes()
        for r, start, end in zip(rows.tolist(), bounds[0].tolist(), bounds[1].tolist())
    }


def select_rows(table: PairTable, rows: np.ndarray) -> PairTable:
    """The rows ``rows`` (sorted indices) of ``table``, with their part pairs (renumbered)."""
    keep = np.zeros(len(table), dtype=bool)
    keep[rows] = True
    new_row = np.cumsum(keep) - 1
    parts = keep[table.part_row]
    columns = {
        f.name: getattr(table, f.name)[rows]
        for f in dataclasses.fields(table)
        if f.name not in ("part_pairs", "part_row", "excluded_pairs")
    }
    return dataclasses.replace(
        table,
        part_pairs=table.part_pairs[parts],
        part_row=new_row[table.part_row[parts]],
        **columns,
    )


@dataclass(frozen=True)
class PairCache:
    """Where one scene's pair answers live: the store (a folder, an fsspec URL, or None for
    the user cache) and the scene's name in it (its path and the job's settings, as
    ``meshcol ci`` gives them). ``counts`` says, after :meth:`measure`, how many rows came
    from the cache (``hits``) and how many were measured (``measured``)."""

    cache_dir: str | os.PathLike[str] | None
    name: str
    counts: dict[str, int] = field(default_factory=dict, compare=False, repr=False)

    @property
    def entry(self) -> str:
        digest = hashlib.sha256(self.name.encode("utf-8", "surrogatepass")).hexdigest()
        return f"results/pairs/{digest[:2]}/{digest}.npz"

    def measure(
        self,
        table: PairTable,
        placed: PlacedColliders,
        tolerance: float,
        margin: float,
        stages: Callable[[PairTable], PairTable],
    ) -> PairTable:
        """``stages(table)`` (the narrow phase), run only on the rows the cache has no
        answer for; the others' measured columns come from the cache. The entry is then
        replaced by this table's rows."""
        settings = (
            np.array([tolerance, margin, FORMAT_VERSION], dtype=np.float64).tobytes()
            + __version__.encode()
        )
        keys = pair_keys(table, placed, settings)
        known = self._load()
        found = np.array([known.get(bytes(k), -1) for k in keys.tolist()], dtype=np.int64)
        hit = found >= 0
        missing = np.flatnonzero(~hit)
        measured = stages(select_rows(table, missing)) if len(missing) else None
        if measured is None and not hit.any():
            measured = stages(table)  # an empty table: the stages say what its columns are
            missing = np.arange(len(table))
        columns: dict[str, Any] = {}
        for name in COLUMNS:
            column = getattr(table, name).copy()
            if measured is not None:
                column[missing] = getattr(measured, name)
            if hit.any():
                column[hit] = known.column(name)[found[hit]]
            columns[name] = column
        out = dataclasses.replace(table, **columns)
        self.counts.update(hits=int(hit.sum()), measured=len(table) - int(hit.sum()))
        unique, first = np.unique(keys, return_index=True)  # twin bodies: one key, one answer
        if len(missing) or len(known) != len(unique):
            self._store(unique, {name: getattr(out, name)[first] for name in COLUMNS})
        return out

    def _load(self) -> _Entry:
        from meshcol.decomposition.cache import read_bytes

        data = read_bytes(self.entry, self.cache_dir)
        return _Entry.read(data)

    def _store(self, keys: np.ndarray, columns: dict[str, Any]) -> None:
        from meshcol.decomposition.cache import write_bytes

        buffer = io.BytesIO()
        np.savez(buffer, keys=keys, **columns)
        write_bytes(self.entry, buffer.getvalue(), self.cache_dir)


class _Entry:
    """A stored entry: the row of each key and the columns, checked on reading."""

    def __init__(self, keys: np.ndarray, columns: dict[str, np.ndarray]) -> None:
        self.rows = {bytes(k): i for i, k in enumerate(keys.tolist())}
        self.columns = columns

    def __len__(self) -> int:
        return len(self.rows)

    def get(self, key: bytes, default: int) -> int:
        return self.rows.get(key, default)

    def column(self, name: str) -> np.ndarray:
        return self.columns[name]

    @classmethod
    def read(cls, data: bytes | None) -> _Entry:
        empty = cls(np.zeros(0, f"S{KEY_BYTES}"), {})
        if data is None:
            return empty
        reference = PairTable.of_candidates(
            np.zeros((1, 2), np.int64), np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
        )
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as stored:
                keys = stored["keys"]
                columns = {name: stored[name] for name in COLUMNS}
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return empty
        if keys.dtype != np.dtype(f"S{KEY_BYTES}") or keys.ndim != 1:
            return empty
        for name, values in columns.items():
            like = getattr(reference, name)
            if values.dtype != like.dtype or values.shape[1:] != like.shape[1:]:
                return empty
            if len(values) != len(keys):
                return empty
        if len(set(keys.tolist())) != len(keys):
            return empty
        return cls(keys, columns)
