"""The core's triangle fill of the snapshot rasterizer (``raster_fill_triangles``) against the
numpy fill it replaced, kept here as the oracle: the same depth buffer and pixels, bit for bit,
on random scenes of overlapping, sliver, degenerate, off-screen and equal-depth triangles."""

from __future__ import annotations

import numpy as np
import pytest

from meshcol._native import core


def numpy_fill(depth, pixels, tri, color, lo, hi) -> None:
    """One triangle, as meshcol.io.raster's numpy fill drew it (edge functions over its box)."""
    h, w = depth.shape
    x0, y0 = max(int(lo[0]), 0), max(int(lo[1]), 0)
    x1, y1 = min(int(hi[0]), w - 1), min(int(hi[1]), h - 1)
    if x1 < x0 or y1 < y0:
        return
    xs = np.arange(x0, x1 + 1) + 0.5
    ys = np.arange(y0, y1 + 1)[:, None] + 0.5
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = tri
    det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    if det == 0:
        return
    with np.errstate(all="ignore"):
        w0 = ((bx - xs) * (cy - ys) - (by - ys) * (cx - xs)) / det
        w1 = ((cx - xs) * (ay - ys) - (cy - ys) * (ax - xs)) / det
        w2 = 1.0 - w0 - w1
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        z = w0 * az + w1 * bz + w2 * cz
        region = depth[y0 : y1 + 1, x0 : x1 + 1]
        nearer = inside & (z > region)
    region[nearer] = z[nearer]
    pixels[y0 : y1 + 1, x0 : x1 + 1][nearer] = color


def scene(rng: np.random.Generator, n: int, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """n screen triangles around a w x h image: most on it, some off it or across its edges,
    slivers, repeated corners (zero determinant) and copies at equal depth."""
    centres = rng.uniform([-0.2 * w, -0.2 * h, -1.0], [1.2 * w, 1.2 * h, 1.0], size=(n, 1, 3))
    size = rng.choice([0.3, 3.0, 30.0, 300.0], size=(n, 1, 1))
    corners = centres + rng.normal(size=(n, 3, 3)) * size * np.array([1.0, 1.0, 0.01])
    corners[::7, 2] = corners[::7, 1]  # degenerate: two equal corners
    corners[1::11, 2, :2] = corners[1::11, 0, :2] + 1e-9 * (
        corners[1::11, 1, :2] - corners[1::11, 0, :2]
    )
    corners[2::13] = corners[1::13]  # a copy at the same depth (the first drawn stays)
    corners[3::17, :, :2] = np.round(corners[3::17, :, :2]) + 0.5  # corners on pixel centres
    colors = rng.integers(0, 256, size=(n, 3), dtype=np.uint8)
    return corners, colors


@pytest.mark.parametrize("seed", range(4))
def test_the_core_fill_is_the_numpy_fill_bit_for_bit(seed) -> None:
    rng = np.random.default_rng(seed)
    w, h = 160, 120
    corners, colors = scene(rng, 400, w, h)
    lo = np.floor(corners[:, :, :2].min(axis=1)).astype(np.int64)
    hi = np.ceil(corners[:, :, :2].max(axis=1)).astype(np.int64)
    order = rng.permutation(len(corners))[: len(corners) - 20].astype(np.int64)
    depth = np.full((h, w), -np.inf)
    depth[::5] = rng.uniform(-1, 1, size=(len(depth[::5]), w))  # something already drawn
    pixels = np.full((h, w, 3), 255, dtype=np.uint8)
    want_depth, want_pixels = depth.copy(), pixels.copy()
    for k in order:
        numpy_fill(want_depth, want_pixels, corners[k], colors[k], lo[k], hi[k])
    core.raster_fill_triangles(depth, pixels, corners, colors, lo, hi, order)
    assert (want_pixels != 255).any() and np.isfinite(want_depth).sum() > 0.5 * w * h
    np.testing.assert_array_equal(depth.view(np.int64), want_depth.view(np.int64))
    np.testing.assert_array_equal(pixels, want_pixels)


def test_the_fill_refuses_bad_shapes_and_indices() -> None:
    depth = np.full((4, 5), -np.inf)
    pixels = np.zeros((4, 5, 3), dtype=np.uint8)
    tri = np.zeros((1, 3, 3))
    color = np.zeros((1, 3), dtype=np.uint8)
    box = np.zeros((1, 2), dtype=np.int64)
    with pytest.raises(ValueError, match="out of range for 1 triangles"):
        core.raster_fill_triangles(depth, pixels, tri, color, box, box, np.array([1]))
    with pytest.raises(ValueError, match=r"pixels must be \(H, W, 3\)"):
        core.raster_fill_triangles(depth, pixels[:3], tri, color, box, box, np.array([0]))
    with pytest.raises(ValueError, match="one row per triangle"):
        core.raster_fill_triangles(depth, pixels, tri, color[:0], box, box, np.array([0]))
    depth.flags.writeable = False
    with pytest.raises(TypeError):  # a read-only buffer is not written
        core.raster_fill_triangles(depth, pixels, tri, color, box, box, np.array([0]))
