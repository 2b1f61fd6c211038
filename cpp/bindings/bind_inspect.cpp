// Exposes the mesh health queries of triangle.hpp, self_intersection.hpp and mesh_topology.hpp
// behind `meshcol inspect`: the exact crossing test of candidate face pairs, the streamed
// self-intersection pass with its work budget, and the topology counts of many meshes. The Python wrapper in
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

#include "meshcol/mesh_topology.hpp"
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
        "mesh_topology_batch",
        [](const Faces& faces, const Index64& face_offsets, const Index64& vertex_offsets, int threads) {
            if (face_offsets.shape(0) < 1 || vertex_offsets.shape(0) != face_offsets.shape(0))
                throw std::invalid_argument(
                    "face_offsets and vertex_offsets must both be (n + 1,), got (" +
                    std::to_string(face_offsets.shape(0)) + ",) and (" +
                    std::to_string(vertex_offsets.shape(0)) + ",)");
            const size_t n = face_offsets.shape(0) - 1;
            check_offsets(face_offsets.data(), n + 1, static_cast<std::int64_t>(faces.shape(0)),
                          "face_offsets");
            const std::int64_t vertex_total = vertex_offsets.data()[n];
            check_offsets(vertex_offsets.data(), n + 1, vertex_total, "vertex_offsets");
            std::vector<meshcol::MeshTopology> found(n);
            auto used = new_array<Out<bool, -1>>({static_cast<size_t>(vertex_total)});
            {
                nb::gil_scoped_release release;
                meshcol::mesh_topology_batch(faces.data(), face_offsets.data(), vertex_offsets.data(),
                                             static_cast<std::int64_t>(n), found.data(),
                                             reinterpret_cast<std::uint8_t*>(used.data()), threads);
            }
            auto counts = new_array<Out<std::int64_t, -1, 5>>({n, 5});
            auto closed = new_array<Out<bool, -1>>({n});
            auto balanced = new_array<Out<bool, -1>>({n});
            auto status = new_array<Out<std::int8_t, -1>>({n});
            for (size_t i = 0; i < n; ++i) {
                const auto& t = found[i];
                std::int64_t* row = counts.data() + 5 * i;
                row[0] = t.boundary_edges;
                row[1] = t.non_manifold_edges;
                row[2] = t.inconsistent_edges;
                row[3] = t.duplicate_faces;
                row[4] = t.components;
                closed.data()[i] = t.closed;
                balanced.data()[i] = t.balanced;
                status.data()[i] = static_cast<std::int8_t>(t.status);
            }
            return std::make_tuple(counts, closed, balanced, used, status);
        },
        "faces"_a, "face_offsets"_a, "vertex_offsets"_a, "threads"_a = 0,
        "Topology of each mesh of a batch (mesh i: faces[face_offsets[i]:face_offsets[i + 1]], "
        "indices into its own vertices, vertex_offsets[i + 1] - vertex_offsets[i] of them): "
        "(counts (n, 5) int64: boundary, non-manifold and inconsistently wound edges, duplicate "
        "faces, connected pieces; closed (n,) bool; balanced (n,) bool, of the faces without a "
        "repeated corner; used (V,) bool per vertex; status (n,) int8, 1 when a face index is "
        "out of its mesh's range and nothing was counted).");
    m.def(
        "face_heights",
        [](const Points& vertices, const Faces& faces, int threads) {
            check_faces(vertices, faces);
            const size_t n = faces.shape(0);
            auto heights = new_array<Out<double, -1>>({n});
            auto repeated = new_array<Out<bool, -1>>({n});
            {
                nb::gil_scoped_release release;
                meshcol::face_heights(vertices.data(), faces.data(), static_cast<std::int64_t>(n),
                                      heights.data(), reinterpret_cast<std::uint8_t*>(repeated.data()),
                                      threads);
            }
            return std::make_tuple(heights, repeated);
        },
        "vertices"_a, "faces"_a, "threads"_a = 0,
        "Per face: (height on its longest edge (F,) float64, 0 when that edge has length 0; "
        "names a vertex twice (F,) bool), the bits of numpy's face_heights.");
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
