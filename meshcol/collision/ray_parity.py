"""Inside or outside a triangle mesh by ray parity, exactly.

The fallback inside test for a mesh whose faces cannot be wound consistently (a
non-orientable surface: its winding number means nothing): a point is inside when a ray from
it crosses the surface an odd number of times (the even-odd rule). That count is the same for
every ray that crosses only faces' interiors, when the faces close up modulo 2 (every edge used
by an even number of faces), whatever their winding; the core picks one such ray for every
point, and decides each crossing with exact signs, so the answer is exact. A point is left
undecided only where inside is not defined: on the surface, or for every point when the faces
do not close up (an open strip has no inside).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from meshcol._native import core
from meshcol.collision.arrays import as_mesh

__all__ = ["ray_parity"]


def ray_parity(points: Any, vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    """Whether each point is inside the mesh by the even-odd rule, and whether that is defined.

    Parameters
    ----------
    points : (k, 3) float
        Query points, in the mesh's frame.
    vertices : (n, 3) float
    faces : (m, 3) int
        Indices into ``vertices``; their winding does not matter.

    Returns
    -------
    inside, decided : (k,) bool, (k,) bool
        ``inside`` is meaningful where ``decided``. ``decided`` is False exactly for a point on
        a face (closed triangle), for a point with a NaN or infinite coordinate, and for every
        point when the faces are not closed modulo 2: some edge (its ends matched by their
        coordinates) is used by an odd number of faces, or a used vertex is not finite.

    Raises
    ------
    ValueError
        Wrong shapes, or a face index out of range.

    Notes
    -----
    In the C++ core, GIL released; brute force over the faces per point, bounding intervals
    first (the fallback is for the rare meshes that need it). The ray runs along +x from the
    point moved by (0, e, e^2), e infinitesimal (Simulation of Simplicity; Edelsbrunner and
    Muecke 1990): it meets no vertex or edge and lies in no face's plane, and starts in the
    same cell of space as the point itself when that is off the surface, so a ray through an
    edge, a vertex or along a face is never a special case. The crossings are exact orientation
    signs (orient2d of the yz projections, orient3d; Shewchuk 1997), the perturbation's terms
    comparisons of coordinates; whether the point is on a face is the core's exact
    triangle test. Nothing is rounded but the caller's transform into the mesh's frame.
    """
    p = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    v, f = as_mesh(vertices, faces)
    verdict = core.ray_parity(v, np.ascontiguousarray(f, dtype=np.int64), p)
    return verdict == 1, verdict >= 0
