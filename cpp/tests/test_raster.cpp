// The snapshot rasterizer's fill (raster.hpp): which pixels a triangle covers, depth testing
// (nearer wins, an equal depth keeps the first), clipping to the image, degenerate triangles
// and the refusal of an index out of range. Python's tests/io/test_raster_fill.py checks it
// bit for bit against the numpy fill it replaced.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "check.hpp"
#include "meshcol/raster.hpp"

using namespace meshcol;

namespace {

struct Image {
    std::int64_t width, height;
    std::vector<double> depth;
    std::vector<std::uint8_t> pixels;
    Image(std::int64_t w, std::int64_t h)
        : width(w), height(h), depth(static_cast<size_t>(w * h), -std::numeric_limits<double>::infinity()),
          pixels(static_cast<size_t>(3 * w * h), 255) {}
    RasterImage view() { return RasterImage{depth.data(), pixels.data(), width, height}; }
    std::uint8_t red(std::int64_t x, std::int64_t y) const { return pixels[static_cast<size_t>(3 * (y * width + x))]; }
    int count(std::uint8_t r) const {
        int n = 0;
        for (std::int64_t i = 0; i < width * height; ++i) n += pixels[static_cast<size_t>(3 * i)] == r;
        return n;
    }
};

// Triangles with their pixel boxes (floor and ceil of the corners' x and y), as raster.py
// passes them.
struct Tris {
    std::vector<double> corners;
    std::vector<std::uint8_t> colors;
    std::vector<std::int64_t> lo, hi;
    void add(std::vector<double> c, std::uint8_t red) {
        double min_x = c[0], max_x = c[0], min_y = c[1], max_y = c[1];
        for (int k = 1; k < 3; ++k) {
            min_x = std::min(min_x, c[3 * k]), max_x = std::max(max_x, c[3 * k]);
            min_y = std::min(min_y, c[3 * k + 1]), max_y = std::max(max_y, c[3 * k + 1]);
        }
        corners.insert(corners.end(), c.begin(), c.end());
        colors.insert(colors.end(), {red, 0, 0});
        lo.insert(lo.end(), {static_cast<std::int64_t>(std::floor(min_x)), static_cast<std::int64_t>(std::floor(min_y))});
        hi.insert(hi.end(), {static_cast<std::int64_t>(std::ceil(max_x)), static_cast<std::int64_t>(std::ceil(max_y))});
    }
    RasterTriangles view() const { return RasterTriangles{corners.data(), colors.data(), lo.data(), hi.data(), colors.size() / 3}; }
};

}  // namespace

TEST_CASE("raster: a half square covers the pixel centres below its diagonal") {
    Image image(4, 4);
    Tris tris;
    tris.add({0, 0, 1, 4, 0, 1, 0, 4, 1}, 10);  // x + y <= 4: centres (x + 0.5) + (y + 0.5) <= 4
    const std::vector<std::int64_t> order{0};
    raster_fill_triangles(image.view(), tris.view(), order.data(), order.size());
    for (std::int64_t y = 0; y < 4; ++y)
        for (std::int64_t x = 0; x < 4; ++x) CHECK_EQ(image.red(x, y) == 10, x + y + 1 <= 4);
    CHECK_EQ(image.depth[0], 1.0);
}

TEST_CASE("raster: the nearer triangle wins whatever the order; an equal depth keeps the first") {
    Image image(8, 8);
    Tris tris;
    tris.add({-1, -1, 0.5, 20, -1, 0.5, -1, 20, 0.5}, 1);  // covers the image, depth 0.5
    tris.add({-1, -1, 0.2, 20, -1, 0.2, -1, 20, 0.2}, 2);  // behind it
    tris.add({-1, -1, 0.5, 20, -1, 0.5, -1, 20, 0.5}, 3);  // the same depth
    tris.add({-1, -1, 0.9, 20, -1, 0.9, -1, 20, 0.9}, 4);  // in front
    const std::vector<std::int64_t> first{0, 1, 2};
    raster_fill_triangles(image.view(), tris.view(), first.data(), first.size());
    CHECK_EQ(image.count(1), 64);
    const std::vector<std::int64_t> last{3};
    raster_fill_triangles(image.view(), tris.view(), last.data(), last.size());
    CHECK_EQ(image.count(4), 64);
    CHECK_NEAR(image.depth[63], 0.9, 1e-15);
}

TEST_CASE("raster: boxes are clipped to the image; degenerate and outside triangles draw nothing") {
    Image image(5, 3);
    Tris tris;
    tris.add({-100, -100, 0, 300, -100, 0, -100, 300, 0}, 7);  // far larger than the image
    tris.add({1, 1, 1, 3, 3, 1, 1, 1, 1}, 8);                  // two equal corners: no area
    tris.add({50, 50, 1, 60, 50, 1, 50, 60, 1}, 9);            // wholly outside
    const std::vector<std::int64_t> order{1, 2, 0};
    raster_fill_triangles(image.view(), tris.view(), order.data(), order.size());
    CHECK_EQ(image.count(7), 15);
    CHECK_EQ(image.count(8) + image.count(9), 0);
}

TEST_CASE("raster: an index of the order out of range is refused before anything is drawn") {
    Image image(2, 2);
    Tris tris;
    tris.add({0, 0, 1, 2, 0, 1, 0, 2, 1}, 5);
    const std::vector<std::int64_t> order{0, 1};
    CHECK_THROWS_AS(raster_fill_triangles(image.view(), tris.view(), order.data(), order.size()),
                    std::invalid_argument);
    CHECK_EQ(image.count(5), 0);
    const std::vector<std::int64_t> negative{-1};
    CHECK_THROWS_AS(raster_fill_triangles(image.view(), tris.view(), negative.data(), negative.size()),
                    std::invalid_argument);
}
