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
        [](const Points& vertices, const Faces& faces, std::int64_t max_work, std::int64_t slow_cost,
           std::int64_t exact_cost, std::int64_t max_kept_pairs, std::int64_t block_pairs, int threads) {
            check_faces(vertices, faces);
            if (block_pairs < 1)
                throw std::invalid_argument("block_pairs must be >= 1, got " + std::to_string(block_pairs));
            if (slow_cost < 0 || exact_cost < 0)
                throw std::invalid_argument("slow_cost and exact_cost must be >= 0");
            const auto n_faces = static_cast<std::int64_t>(faces.shape(0));
            meshcol::SelfIntersectionOptions options;
            options.max_work = max_work;
            options.slow_cost = slow_cost;
            options.exact_cost = exact_cost;
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
                                   found.candidate_count, found.work, found.complete);
        },
        "vertices"_a, "faces"_a, "max_work"_a = meshcol::defaults::self_intersection_max_work,
        "slow_cost"_a = meshcol::defaults::self_intersection_slow_cost,
        "exact_cost"_a = meshcol::defaults::self_intersection_exact_cost,
        "max_kept_pairs"_a = meshcol::defaults::self_intersection_max_kept_pairs,
        "block_pairs"_a = meshcol::defaults::self_intersection_block_pairs, "threads"_a = 0,
        "Crossing face pairs of a mesh, streamed from the sweep of the face boxes into the exact "
        "test: (pairs (K, 2) int64 i < j sorted, at most max_kept_pairs (< 0: all); crossing "
        "count; candidate pairs decided; work units spent; complete). At most max_work (< 0: no "
        "budget) units are spent (one per candidate, slow_cost per orientation past its filter, "
        "exact_cost more per exact one): past it complete is False and the count a lower bound.");
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
