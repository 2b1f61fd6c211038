// Exposes the mesh health queries of triangle.hpp and self_intersection.hpp behind `meshcol
// inspect`: the exact crossing test of candidate face pairs, and the streamed self-intersection
// pass with its work budget. The Python wrapper in
// meshcol/collision/self_intersection.py checks shapes first with friendly messages.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "meshcol/self_intersection.hpp"
#include "meshcol/triangle.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using PairsOut = Out<std::int64_t, -1, 2>;

/// Throws std::invalid_argument naming the first face with a vertex index out of range.
void check_faces(const Points& vertices, const Faces& faces) {
    const auto n_vertices = static_cast<std::int64_t>(vertices.shape(0));
    const auto n_faces = static_cast<std::int64_t>(faces.shape(0));
    const std::int64_t* f = faces.data();
    for (std::int64_t k = 0; k < 3 * n_faces; ++k)
        if (f[k] < 0 || f[k] >= n_vertices)
            throw std::invalid_argument("face " + std::to_string(k / 3) + " has vertex index " +
                                        std::to_string(f[k]) + " out of range [0, " +
                                        std::to_string(n_vertices) + ")");
}

}  // namespace

void bind_inspect(nb::module_& m) {
    m.def(
        "self_intersecting_pairs",
        [](const Points& vertices, const Faces& faces, std::int64_t max_candidate_pairs,
           std::int64_t max_kept_pairs, std::int64_t block_pairs, int threads) {
            check_faces(vertices, faces);
            if (block_pairs < 1)
                throw std::invalid_argument("block_pairs must be >= 1, got " + std::to_string(block_pairs));
            const auto n_faces = static_cast<std::int64_t>(faces.shape(0));
            meshcol::SelfIntersectionOptions options;
            options.max_candidate_pairs = max_candidate_pairs;
            options.max_kept_pairs = max_kept_pairs;
            options.block_pairs = block_pairs;
            options.threads = threads;
            meshcol::SelfIntersectionOutput found;
            {
                nb::gil_scoped_release release;
                found = meshcol::self_intersecting_pairs(vertices.data(), faces.data(), n_faces, options);
            }
            const size_t k = found.pairs.size() / 2;
            return std::make_tuple(vector_array<PairsOut>(std::move(found.pairs), k, 2), found.crossing_count,
                                   found.candidate_count, found.complete);
        },
        "vertices"_a, "faces"_a,
        "max_candidate_pairs"_a = meshcol::defaults::self_intersection_max_candidate_pairs,
        "max_kept_pairs"_a = meshcol::defaults::self_intersection_max_kept_pairs,
        "block_pairs"_a = meshcol::defaults::self_intersection_block_pairs, "threads"_a = 0,
        "Crossing face pairs of a mesh, streamed from the sweep of the face boxes into the exact "
        "test: (pairs (K, 2) int64 i < j sorted, at most max_kept_pairs (< 0: all); crossing "
        "count; candidate pairs decided; complete). At most max_candidate_pairs (< 0: no "
        "budget) candidates are decided: past it complete is False and the count a lower bound.");
    m.def(
        "face_pairs_cross",
        [](const Points& vertices, const Faces& faces, const Pairs& pairs, int threads) {
            check_faces(vertices, faces);
            const auto n_faces = static_cast<std::int64_t>(faces.shape(0));
            const std::int64_t* f = faces.data();
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
