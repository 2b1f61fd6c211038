"""Which part pairs of the broad phase's body pairs may collide: a scene's
:class:`~meshcol.types.PartFilter` (an MJCF's ``contype``/``conaffinity`` and
``<contact><pair>``, geom by geom, as ``mj_collision`` filters them) over the part-pair
arrays, one array expression (a Python loop runs over bodies only)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from meshcol.types import PartFilter

__all__ = ["PartGeoms", "part_geoms"]


@dataclass(frozen=True, eq=False)
class PartGeoms:
    """A :class:`~meshcol.types.PartFilter` on the colliders' convex parts.

    Attributes
    ----------
    geom : (n_parts,) int64
        Each convex part's geom id; -1 for a part of a body the filter does not name.
    contype, conaffinity : (n_geoms,) int64
    explicit : (e,) int64
        The explicit geom pairs' keys, ``min * n_geoms + max``, sorted.
    explicit_only : (f,) int64
        The body pairs only explicit geom pairs collide in, ``min * n_bodies + max``.
    n_bodies : int
    """

    geom: np.ndarray
    contype: np.ndarray
    conaffinity: np.ndarray
    explicit: np.ndarray
    explicit_only: np.ndarray
    n_bodies: int

    def allowed(self, part_pairs: np.ndarray, part_body: np.ndarray) -> np.ndarray:
        """(m,) bool: the part pairs (rows of ``part_pairs``, two convex parts of two
        bodies) that may collide: a part of an unnamed body, an explicit geom pair, or masks
        that pass the bitmask rule in a body pair not among ``explicit_only``."""
        if len(self.contype) == 0:  # no geom: no body named
            return np.ones(len(part_pairs), dtype=bool)
        ga, gb = self.geom[part_pairs[:, 0]], self.geom[part_pairs[:, 1]]
        free = (ga < 0) | (gb < 0)
        ga, gb = np.maximum(ga, 0), np.maximum(gb, 0)
        passes = ((self.contype[ga] & self.conaffinity[gb]) != 0) | (
            (self.contype[gb] & self.conaffinity[ga]) != 0
        )
        if len(self.explicit_only):
            a, b = part_body[part_pairs[:, 0]], part_body[part_pairs[:, 1]]
            body_key = np.minimum(a, b) * self.n_bodies + np.maximum(a, b)
            passes &= ~np.isin(body_key, self.explicit_only)
        n = len(self.contype)
        explicit = np.isin(np.minimum(ga, gb) * n + np.maximum(ga, gb), self.explicit)
        return free | passes | explicit


def part_geoms(
    part_filter: PartFilter,
    names: Sequence[str],
    part_body: np.ndarray,
    part_label: np.ndarray,
) -> PartGeoms:
    """The filter on convex parts: ``names`` the colliders' body names, ``part_body`` and
    ``part_label`` each convex part's body and named part (-1: a body of one part), as
    :class:`~meshcol.analysis.colliders.Colliders` has them."""
    index = {name: i for i, name in enumerate(names)}
    starts = np.full(len(names), -1, dtype=np.int64)
    flat: list[int] = []
    for name, ids in part_filter.geoms:
        body = index.get(name)
        if body is not None and ids:
            starts[body] = len(flat)
            flat.extend(ids)
    table = np.asarray(flat + [-1], dtype=np.int64)  # the last: no geom
    first = starts[part_body]
    geom = table[np.where(first >= 0, first + np.maximum(part_label, 0), len(flat))]
    n_geoms = len(part_filter.contype)
    pairs = np.asarray(part_filter.explicit, dtype=np.int64).reshape(-1, 2)
    explicit = np.unique(pairs.min(axis=1) * n_geoms + pairs.max(axis=1))
    n = max(len(names), 1)
    ends = [(index[a], index[b]) for a, b in part_filter.explicit_only if a in index and b in index]
    only = np.asarray(ends, dtype=np.int64).reshape(-1, 2)
    return PartGeoms(
        geom=geom,
        contype=np.asarray(part_filter.contype, dtype=np.int64),
        conaffinity=np.asarray(part_filter.conaffinity, dtype=np.int64),
        explicit=explicit,
        explicit_only=np.unique(only.min(axis=1) * n + only.max(axis=1)),
        n_bodies=n,
    )
