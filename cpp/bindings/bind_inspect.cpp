// Exposes the mesh health queries of triangle.hpp behind `meshcol inspect`: the exact crossing
// test of candidate face pairs (self-intersections). The Python wrapper in
// meshcol/collision/self_intersection.py checks shapes first with friendly messages.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "meshcol/triangle.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

void bind_inspect(nb::module_& m) {
    m.def(
        "face_pairs_cross",
        [](const Points& vertices, const Faces& faces, const Pairs& pairs, int threads) {
            const auto n_vertices = static_cast<std::int64_t>(vertices.shape(0));
            const auto n_faces = static_cast<std::int64_t>(faces.shape(0));
            const std::int64_t* f = faces.data();
            for (std::int64_t k = 0; k < 3 * n_faces; ++k)
                if (f[k] < 0 || f[k] >= n_vertices)
                    throw std::invalid_argument("face " + std::to_string(k / 3) +
                                                " has vertex index " + std::to_string(f[k]) +
                                                " out of range [0, " + std::to_string(n_vertices) +
                                                ")");
            const auto n_pairs = static_cast<long long>(pairs.shape(0));
            const std::int64_t* p = pairs.data();
            for (long long k = 0; k < 2 * n_pairs; ++k)
                if (p[k] < 0 || p[k] >= n_faces)
                    throw std::invalid_argument("pair " + std::to_string(k / 2) +
                                                " has face index " + std::to_string(p[k]) +
                                                " out of range [0, " + std::to_string(n_faces) +
                                                ")");
            auto crossing = new_array<Out<bool, -1>>({static_cast<size_t>(n_pairs)});
            {
                nb::gil_scoped_release release;
                meshcol::face_pairs_cross(vertices.data(), f, p, n_pairs,
                                          reinterpret_cast<std::uint8_t*>(crossing.data()),
                                          threads);
            }
            return crossing;
        },
        "vertices"_a, "faces"_a, "pairs"_a, "threads"_a = 0,
        "Per face pair (K,) bool: the open triangles share a point (exact).");
}
