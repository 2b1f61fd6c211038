"""The colliders of a manifest's primitive bodies kept as columns, packed from arrays.

:func:`meshcol.analysis.colliders.build_colliders` of a
:class:`~meshcol.io.scene_primitives.PrimitiveBodies` comes here: every body is one part, its
exact primitive, so the packed shapes are the columns' types and lengths turned into the
core's kinds and parameters (:meth:`ConvexSet.from_primitives`, one numpy pass), and the
parts' poses are the bodies' poses. No Body, Primitive or pool entry is made per body; the
result is the :class:`Colliders` the body-by-body build gives, array for array
(``tests/test_primitive_columns.py``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from meshcol.analysis.colliders import Colliders
from meshcol.collision.shapes import ConvexSet, ShapeKind
from meshcol.io.collision_names import UNREAL_PREFIXES
from meshcol.io.scene_primitives import PrimitiveBodies
from meshcol.io.scene_schema import PRIMITIVE_TYPES
from meshcol.types import Body

__all__ = ["primitive_colliders", "primitive_params"]

#: The core's shape kind of each manifest primitive type (index of :data:`PRIMITIVE_TYPES`).
_SHAPE_KINDS = np.array(
    [ShapeKind[name.upper()] for name in PRIMITIVE_TYPES], dtype=np.int8
).reshape(len(PRIMITIVE_TYPES))
_BOX = PRIMITIVE_TYPES.index("box")
_ELLIPSOID = PRIMITIVE_TYPES.index("ellipsoid")


def primitive_params(types: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The core's ``(kinds, params)`` of primitives given by their manifest type indices and
    lengths: a sphere ``(r, 0, 0, 0)``, a box its half sizes, a capsule or cylinder ``(r,
    length / 2, 0, 0)``, an ellipsoid its semi-axes, each the same float operation as the
    packing of one primitive."""
    kinds = _SHAPE_KINDS[types.astype(np.int64)]
    params = np.zeros((len(types), 4))
    params[:, 0] = lengths[:, 0]
    box = types == _BOX
    params[box, :3] = lengths[box] / 2.0
    ellipsoid = types == _ELLIPSOID
    params[ellipsoid, :3] = lengths[ellipsoid]
    round_ = (kinds == ShapeKind.CAPSULE) | (kinds == ShapeKind.CYLINDER)
    params[round_, 1] = lengths[round_, 1] / 2.0
    return kinds, params


def primitive_colliders(bodies: Sequence[Body]) -> Colliders | None:
    """The colliders of ``bodies`` when they are :class:`PrimitiveBodies`; None for other
    bodies, or when a name may be an Unreal collision part's (``UCX_``...: the body-by-body
    build matches them to their owners)."""
    if not isinstance(bodies, PrimitiveBodies):
        return None
    joined = "\n".join(bodies.names)
    if any(f"{prefix}_" in joined for prefix in UNREAL_PREFIXES):
        return None
    n = len(bodies)
    shapes = ConvexSet.from_primitives(*primitive_params(bodies.kinds, bodies.lengths))
    every = np.arange(n, dtype=np.int64)
    return Colliders(
        bodies,
        ("primitive",) * n,
        shapes,
        every,
        np.zeros(n, dtype=np.int64),
        np.arange(n + 1, dtype=np.int64),
        np.full(n, -1, dtype=np.int64),
    )
