// The snapshot rasterizer's triangle fill (raster.hpp): Pineda's edge functions over each
// triangle's pixel box, as meshcol/io/raster.py wrote them in numpy, one triangle at a time.
#include "meshcol/raster.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace meshcol {

namespace {

void fill_one(const RasterImage& image, const double* t, const std::uint8_t* color, std::int64_t lo_x,
              std::int64_t lo_y, std::int64_t hi_x, std::int64_t hi_y) {
    const std::int64_t x0 = std::max<std::int64_t>(lo_x, 0), y0 = std::max<std::int64_t>(lo_y, 0);
    const std::int64_t x1 = std::min<std::int64_t>(hi_x, image.width - 1);
    const std::int64_t y1 = std::min<std::int64_t>(hi_y, image.height - 1);
    if (x1 < x0 || y1 < y0) return;
    const double ax = t[0], ay = t[1], az = t[2], bx = t[3], by = t[4], bz = t[5];
    const double cx = t[6], cy = t[7], cz = t[8];
    const double det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
    if (det == 0) return;
    for (std::int64_t py = y0; py <= y1; ++py) {
        const double y = static_cast<double>(py) + 0.5;
        double* depth = image.depth + py * image.width;
        std::uint8_t* pixels = image.pixels + 3 * py * image.width;
        for (std::int64_t px = x0; px <= x1; ++px) {
            const double x = static_cast<double>(px) + 0.5;
            const double w0 = ((bx - x) * (cy - y) - (by - y) * (cx - x)) / det;
            const double w1 = ((cx - x) * (ay - y) - (cy - y) * (ax - x)) / det;
            const double w2 = 1.0 - w0 - w1;
            if (!(w0 >= 0 && w1 >= 0 && w2 >= 0)) continue;
            const double z = w0 * az + w1 * bz + w2 * cz;
            if (!(z > depth[px])) continue;
            depth[px] = z;
            pixels[3 * px] = color[0];
            pixels[3 * px + 1] = color[1];
            pixels[3 * px + 2] = color[2];
        }
    }
}

}  // namespace

void raster_fill_triangles(const RasterImage& image, const RasterTriangles& triangles,
                           const std::int64_t* order, std::size_t k) {
    const auto n = static_cast<std::int64_t>(triangles.count);
    for (std::size_t i = 0; i < k; ++i)
        if (order[i] < 0 || order[i] >= n)
            throw std::invalid_argument("order: triangle " + std::to_string(order[i]) + " out of range for " +
                                        std::to_string(n) + " triangles");
    for (std::size_t i = 0; i < k; ++i) {
        const auto t = static_cast<std::size_t>(order[i]);
        fill_one(image, triangles.corners + 9 * t, triangles.colors + 3 * t, triangles.lo[2 * t],
                 triangles.lo[2 * t + 1], triangles.hi[2 * t], triangles.hi[2 * t + 1]);
    }
}

}  // namespace meshcol
