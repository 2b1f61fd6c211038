// Exposes raster.hpp: the snapshot rasterizer's triangle fill, into numpy image buffers in place.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "meshcol/raster.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

void fill_triangles(InOut<double, -1, -1> depth, InOut<std::uint8_t, -1, -1, 3> pixels, Triangles corners,
                    In<std::uint8_t, -1, 3> colors, In<std::int64_t, -1, 2> lo, In<std::int64_t, -1, 2> hi,
                    Index64 order) {
    if (pixels.shape(0) != depth.shape(0) || pixels.shape(1) != depth.shape(1))
        throw std::invalid_argument("pixels must be (H, W, 3) for a depth buffer of (H, W) = (" +
                                    std::to_string(depth.shape(0)) + ", " + std::to_string(depth.shape(1)) +
                                    ")");
    const size_t n = corners.shape(0);
    if (colors.shape(0) != n || lo.shape(0) != n || hi.shape(0) != n)
        throw std::invalid_argument("corners, colors, lo and hi must have one row per triangle, got " +
                                    std::to_string(n) + ", " + std::to_string(colors.shape(0)) + ", " +
                                    std::to_string(lo.shape(0)) + " and " + std::to_string(hi.shape(0)));
    meshcol::RasterImage image;
    image.depth = depth.data();
    image.pixels = pixels.data();
    image.height = static_cast<std::int64_t>(depth.shape(0));
    image.width = static_cast<std::int64_t>(depth.shape(1));
    meshcol::RasterTriangles triangles;
    triangles.corners = corners.data();
    triangles.colors = colors.data();
    triangles.lo = lo.data();
    triangles.hi = hi.data();
    triangles.count = n;
    nb::gil_scoped_release release;
    meshcol::raster_fill_triangles(image, triangles, order.data(), order.shape(0));
}

}  // namespace

void bind_raster(nb::module_& m) {
    m.def("raster_fill_triangles", &fill_triangles, "depth"_a, "pixels"_a, "corners"_a, "colors"_a, "lo"_a,
          "hi"_a, "order"_a,
          "Fills screen triangles corners (N, 3, 3) (pixel x, pixel y down, depth), colours (N, 3) "
          "uint8, pixel boxes lo and hi (N, 2) int64 (floor and ceil of the corners' x and y), in "
          "place into depth (H, W) float64 and pixels (H, W, 3) uint8, triangle order[0], order[1], "
          "...: a pixel whose centre the triangle covers takes its colour and depth when nearer (a "
          "larger depth) than the buffer's. Raises ValueError on mismatched shapes or an index of "
          "order out of range.");
}
