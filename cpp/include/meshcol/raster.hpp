#pragma once
// The triangle fill of the snapshot pictures' rasterizer (meshcol/io/raster.py): each triangle,
// in the given order, depth tested against and written into an image and its depth buffer.
#include <cstddef>
#include <cstdint>

namespace meshcol {

/// An image and its depth buffer, both row-major and `height` x `width`: `depth` one double a
/// pixel (larger is nearer the viewer), `pixels` three bytes (RGB). Views, not owned.
struct RasterImage {
    double* depth = nullptr;
    std::uint8_t* pixels = nullptr;
    std::int64_t width = 0;
    std::int64_t height = 0;
};

/// Screen-space triangles to fill: corners (n, 3, 3) as (pixel x, pixel y down, depth), one RGB
/// colour each (n, 3), and each one's pixel box (n, 2) as `lo` = floor and `hi` = ceil of its
/// corners' smallest and largest x and y. Views, not owned.
struct RasterTriangles {
    const double* corners = nullptr;
    const std::uint8_t* colors = nullptr;
    const std::int64_t* lo = nullptr;
    const std::int64_t* hi = nullptr;
    std::size_t count = 0;
};

/// Fills triangles `order[0..k)` of `triangles` into `image`, one after the other: a pixel of a
/// triangle's box (clipped to the image) whose centre (x + 0.5, y + 0.5) has barycentric
/// weights all >= 0 takes the triangle's colour and depth when that depth is larger than the
/// buffer's (a later triangle of equal depth does not overwrite). The weights and the depth are
/// the numpy expressions of the former Python fill, in the same order of operations (no fused
/// multiply-add), so the image is the one it drew, bit for bit. A triangle of zero determinant
/// draws nothing. Throws std::invalid_argument when an index of `order` is out of [0, count).
void raster_fill_triangles(const RasterImage& image, const RasterTriangles& triangles,
                           const std::int64_t* order, std::size_t k);

}  // namespace meshcol
