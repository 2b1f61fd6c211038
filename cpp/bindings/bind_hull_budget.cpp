// Exposes hull_budget.hpp: the budgeted hull's cut loop over many bodies in one call, and the
// plane clip alone (for the tests' comparison with qhull). The Python API is
// meshcol/collision/hull_budget.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/hull_budget.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using Planes = In<double, -1, 4>;  ///< (P, 4) planes n . x <= offset as (n, offset)

void check_length(size_t n, size_t expected, const char* name) {
    if (n != expected)
        throw std::invalid_argument(std::string(name) + " must have " + std::to_string(expected) +
                                    " rows, got " + std::to_string(n));
}

}  // namespace

void bind_hull_budget(nb::module_& m) {
    m.def(
        "budget_hull_planes",
        [](Points hull_vertices, Index64 vertex_offsets, Triangles facets, Planes equations,
           Index64 facet_offsets, Planes starts, Index64 budgets, Index64 max_planes,
           Values converged_distances, Values merge_distances, int candidates, int threads) {
            const size_t b = vertex_offsets.shape(0) == 0 ? 0 : vertex_offsets.shape(0) - 1;
            if (vertex_offsets.shape(0) == 0)
                throw std::invalid_argument("vertex_offsets must be (B + 1,), got (0,)");
            check_offsets(vertex_offsets.data(), vertex_offsets.shape(0),
                          static_cast<std::int64_t>(hull_vertices.shape(0)), "vertex_offsets");
            check_length(facet_offsets.shape(0), b + 1, "facet_offsets");
            check_offsets(facet_offsets.data(), facet_offsets.shape(0),
                          static_cast<std::int64_t>(facets.shape(0)), "facet_offsets");
            check_length(equations.shape(0), facets.shape(0), "equations");
            check_length(starts.shape(0), 4 * b, "starts");
            check_length(budgets.shape(0), b, "budgets");
            check_length(max_planes.shape(0), b, "max_planes");
            check_length(converged_distances.shape(0), b, "converged_distances");
            check_length(merge_distances.shape(0), b, "merge_distances");
            for (size_t i = 0; i < b; ++i)
                if (budgets.data()[i] < 4 || budgets.data()[i] > 0x7fffffff)
                    throw std::invalid_argument("budgets must be in [4, 2**31)");
            std::vector<std::vector<double>> planes(b);
            std::vector<std::vector<meshcol::Vec3>> polytopes(b);
            std::vector<std::int8_t> status(b, 0);
            const auto* vertices = reinterpret_cast<const meshcol::Vec3*>(hull_vertices.data());
            const auto* corners = reinterpret_cast<const meshcol::Vec3*>(facets.data());
            {
                nb::gil_scoped_release release;
                const int t = meshcol::resolve_threads(threads, static_cast<long long>(b), 1);
                meshcol::parallel_for(static_cast<long long>(b), t, [&](long long lo, long long hi) {
                    for (long long i = lo; i < hi; ++i) {
                        meshcol::BudgetInput in;
                        const std::int64_t v0 = vertex_offsets.data()[i];
                        const std::int64_t f0 = facet_offsets.data()[i];
                        in.hull_vertices = vertices + v0;
                        in.hull_vertex_count = vertex_offsets.data()[i + 1] - v0;
                        in.facets = corners + 3 * f0;
                        in.equations = equations.data() + 4 * f0;
                        in.facet_count = facet_offsets.data()[i + 1] - f0;
                        in.start = starts.data() + 16 * i;
                        in.budget = static_cast<int>(budgets.data()[i]);
                        const std::int64_t mp = max_planes.data()[i];
                        in.max_planes = mp < 0 ? -1 : static_cast<int>(std::min<std::int64_t>(
                                                          mp, 0x7fffffff));
                        in.converged_distance = converged_distances.data()[i];
                        in.merge_distance = merge_distances.data()[i];
                        in.candidates = candidates;
                        status[i] = static_cast<std::int8_t>(
                            meshcol::budget_planes(in, planes[i], polytopes[i]));
                    }
                });
            }
            std::vector<std::int64_t> offsets(b + 1, 0);
            for (size_t i = 0; i < b; ++i)
                offsets[i + 1] = offsets[i] + static_cast<std::int64_t>(planes[i].size() / 4);
            std::vector<double> packed;
            packed.reserve(4 * static_cast<size_t>(offsets[b]));
            for (const auto& p : planes) packed.insert(packed.end(), p.begin(), p.end());
            const size_t total = static_cast<size_t>(offsets[b]);
            std::vector<std::int64_t> vertex_starts(b + 1, 0);
            for (size_t i = 0; i < b; ++i)
                vertex_starts[i + 1] =
                    vertex_starts[i] + static_cast<std::int64_t>(polytopes[i].size());
            std::vector<double> corners_out;
            corners_out.reserve(3 * static_cast<size_t>(vertex_starts[b]));
            for (const auto& p : polytopes)
                for (const meshcol::Vec3& v : p) corners_out.insert(corners_out.end(), {v.x, v.y, v.z});
            const size_t vertex_total = static_cast<size_t>(vertex_starts[b]);
            return std::make_tuple(
                vector_array<Out<double, -1, 4>>(std::move(packed), total, 4),
                vector_array<Out<std::int64_t, -1>>(std::move(offsets), b + 1, 0),
                vector_array<Out<double, -1, 3>>(std::move(corners_out), vertex_total, 3),
                vector_array<Out<std::int64_t, -1>>(std::move(vertex_starts), b + 1, 0),
                vector_array<Out<std::int8_t, -1>>(std::move(status), b, 0));
        },
        "hull_vertices"_a, "vertex_offsets"_a, "facets"_a, "equations"_a, "facet_offsets"_a,
        "starts"_a, "budgets"_a, "max_planes"_a, "converged_distances"_a, "merge_distances"_a,
        "candidates"_a, "threads"_a = 0,
        "The budgeted hull's cut loop for B bodies (body i: exact hull vertices "
        "hull_vertices[vertex_offsets[i]:vertex_offsets[i + 1]], facets (m, 3, 3) and their "
        "outward planes (m, 4) by facet_offsets, start tetrahedron starts[4i:4i + 4] as "
        "(n, offset), budgets, max_planes (-1: none), tolerances): (planes (P, 4) as "
        "(n, offset), plane_offsets (B + 1,), the final polytopes' vertices (V, 3) and "
        "polytope_offsets (B + 1,), status (B,): 0 ok, 1 a degenerate start).");

    m.def(
        "clip_planes",
        [](Planes planes, double merge_distance) {
            const size_t p = planes.shape(0);
            if (p < 4) throw std::invalid_argument("planes must be (P >= 4, 4), got fewer rows");
            if (p > 0x7fffffff) throw std::invalid_argument("too many planes");
            meshcol::PlanePolytope polytope, clipped;
            std::vector<int> source;
            bool ok;
            {
                nb::gil_scoped_release release;
                const double* d = planes.data();
                meshcol::Vec3 normals[4];
                double offsets[4];
                for (int k = 0; k < 4; ++k) {
                    normals[k] = {d[4 * k], d[4 * k + 1], d[4 * k + 2]};
                    offsets[k] = d[4 * k + 3];
                }
                ok = meshcol::tetrahedron_polytope(normals, offsets, polytope);
                std::vector<meshcol::Vec3> all(normals, normals + 4);
                for (size_t k = 4; ok && k < p; ++k) {
                    all.push_back({d[4 * k], d[4 * k + 1], d[4 * k + 2]});
                    ok = meshcol::clip_polytope(polytope, all, d[4 * k + 3], static_cast<int>(k),
                                                merge_distance, clipped, source);
                    std::swap(polytope, clipped);
                }
            }
            const size_t v = ok ? polytope.size() : 0;
            std::vector<double> flat;
            flat.reserve(3 * v);
            for (size_t i = 0; i < v; ++i)
                flat.insert(flat.end(), {polytope.vertices[i].x, polytope.vertices[i].y,
                                         polytope.vertices[i].z});
            return std::make_tuple(ok, vector_array<Out<double, -1, 3>>(std::move(flat), v, 3));
        },
        "planes"_a, "merge_distance"_a,
        "The polytope {x : n . x <= offset} of planes (P, 4) as (n, offset): the tetrahedron of "
        "the first four, clipped by each further plane in turn (near-duplicate vertices merged "
        "within merge_distance): (ok, vertices (V, 3)); ok False when a clip left nothing or "
        "the first four bound no tetrahedron.");
}
