// Exposes hull.hpp: the exact hull of one point set, and the hulls of many packed in one call.
// The Python API is meshcol/collision/hull.py (and ConvexSet in meshcol/collision/shapes.py).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/unique_ptr.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/inscribed_ball.hpp"
#include "ndarray.hpp"
#include "packed_convex_set.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

static_assert(sizeof(meshcol::Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

const meshcol::Vec3* as_vec3(const Points& points) {
    return reinterpret_cast<const meshcol::Vec3*>(points.data());
}

/// The packing's climb lists to numpy as (M, 16) uint8 rows (a `ClimbList` a row: its count,
/// then its 15 slots), without a copy: the vector's storage keeps the lists' 16-byte alignment.
auto climb_list_array(std::vector<meshcol::ClimbList>&& lists) {
    auto* heap = new std::vector<meshcol::ClimbList>(std::move(lists));
    if (heap->empty()) heap->reserve(1);  // a non-null, aligned data pointer even for 0 rows
    nb::capsule owner(heap, [](void* p) noexcept {
        delete static_cast<std::vector<meshcol::ClimbList>*>(p);
    });
    const size_t shape[2] = {heap->size(), kClimbRowBytes};
    return Out<meshcol::ClimbIndex, -1, kClimbRowBytes>(
        reinterpret_cast<meshcol::ClimbIndex*>(heap->data()), 2, shape, owner);
}

template <class T>
std::vector<T> flatten(const std::vector<meshcol::Vec3>& v) {
    std::vector<T> out;
    out.reserve(3 * v.size());
    for (const auto& x : v) out.insert(out.end(), {x.x, x.y, x.z});
    return out;
}

}  // namespace

void bind_hull(nb::module_& m) {
    using S = meshcol::HullStatus;
    nb::enum_<S>(m, "HullStatus", "What a point set's hull is (hull.hpp).")
        .value("OK", S::OK)
        .value("FLAT", S::FLAT)
        .value("COLLINEAR", S::COLLINEAR)
        .value("SINGLE_POINT", S::SINGLE_POINT)
        .value("EMPTY", S::EMPTY)
        .value("NON_FINITE", S::NON_FINITE)
        .value("OVERFLOW", S::OVERFLOW)
        .value("FAILED", S::FAILED);

    m.def(
        "exact_hull",
        [](Points points) {
            const long long n = static_cast<long long>(points.shape(0));
            meshcol::Hull h;
            {
                nb::gil_scoped_release release;
                h = meshcol::exact_hull(as_vec3(points), n);
            }
            const size_t k = h.vertices.size(), f = h.faces.size();
            const size_t planes = h.dimension == 3 ? f : 0;
            std::vector<std::int64_t> index(h.vertices.begin(), h.vertices.end());
            std::vector<std::int64_t> faces;
            faces.reserve(3 * f);
            for (const auto& t : h.faces) faces.insert(faces.end(), {t[0], t[1], t[2]});
            std::vector<double> equations;
            if (planes > 0) {
                equations.reserve(4 * f);
                for (size_t i = 0; i < planes; ++i) {
                    const auto& nrm = h.face_normals[i];
                    equations.insert(equations.end(), {nrm.x, nrm.y, nrm.z, h.face_offsets[i]});
                }
            }
            auto normal = new_array<Out<double, 3>>({3});
            normal.data()[0] = h.normal.x;
            normal.data()[1] = h.normal.y;
            normal.data()[2] = h.normal.z;
            return std::make_tuple(
                static_cast<int>(h.status), h.dimension,
                vector_array<Out<std::int64_t, -1>>(std::move(index), k, 0),
                vector_array<Out<std::int64_t, -1, 3>>(std::move(faces), f, 3),
                vector_array<Out<double, -1, 4>>(std::move(equations), planes, 4),
                normal, h.volume, h.area, h.diagonal);
        },
        "points"_a,
        "Exact convex hull of (n, 3) points: (status, dimension, vertex indices (k,), faces "
        "(m, 3) into the vertices, equations (m, 4), normal (3,), volume, area, diagonal).");

    m.def(
        "pack_polytopes",
        [](Points points, Index64 offsets, int threads) {
            const long long h =
                group_count(offsets.data(), offsets.shape(0),
                            static_cast<std::int64_t>(points.shape(0)), "offsets");
            meshcol::PackedPolytopes p;
            {
                nb::gil_scoped_release release;
                p = meshcol::pack_polytopes(as_vec3(points), offsets.data(), h, threads);
            }
            std::vector<std::int8_t> status(p.status.size());
            for (size_t i = 0; i < status.size(); ++i)
                status[i] = static_cast<std::int8_t>(p.status[i]);
            const size_t v = p.vertices.size() / 3, k = p.adjacency.size();
            const size_t f = p.face_normals.size() / 3, e = p.edge_pairs.size() / 2;
            const size_t hs = static_cast<size_t>(h);
            // The seal keeps the index arrays it vouches for (packed_convex_set.hpp).
            auto seal = std::make_unique<PackSeal>();
            seal->vertex_count = static_cast<std::int64_t>(v);
            seal->adjacency_count = static_cast<std::int64_t>(k);
            seal->edge_count = static_cast<std::int64_t>(e);
            seal->offsets = p.offsets;
            seal->edge_pair_offsets = p.edge_pair_offsets;
            seal->climb_list_offsets = p.climb_list_offsets;
            seal->climb_list_count = static_cast<std::int64_t>(p.climb_lists.size());
            auto adjacency_offsets =
                vector_array<Out<std::int64_t, -1>>(std::move(p.adjacency_offsets), v + 1, 0);
            auto adjacency = vector_array<Out<std::int32_t, -1>>(std::move(p.adjacency), k, 0);
            auto edge_pairs = vector_array<Out<std::int32_t, -1, 2>>(std::move(p.edge_pairs), e, 2);
            seal->adjacency_offsets_data = adjacency_offsets.data();
            seal->adjacency_data = adjacency.data();
            seal->edge_pairs_data = edge_pairs.data();
            auto climb_lists = climb_list_array(std::move(p.climb_lists));
            seal->climb_lists_data = climb_lists.data();
            // As Python objects (typed for the stub), so that the seal holds the very arrays.
            auto adjacency_offsets_object = adjacency_offsets.cast();
            auto adjacency_object = adjacency.cast();
            auto edge_pairs_object = edge_pairs.cast();
            auto climb_lists_object = climb_lists.cast();
            seal->adjacency_offsets = adjacency_offsets_object;
            seal->adjacency = adjacency_object;
            seal->edge_pairs = edge_pairs_object;
            seal->climb_lists = climb_lists_object;
            return std::make_tuple(
                vector_array<Out<std::int8_t, -1>>(std::move(status), hs, 0),
                vector_array<Out<double, -1, 3>>(std::move(p.vertices), v, 3),
                vector_array<Out<std::int64_t, -1>>(std::move(p.offsets), hs + 1, 0),
                adjacency_offsets_object, adjacency_object,
                vector_array<Out<std::int64_t, -1>>(std::move(p.face_offsets), hs + 1, 0),
                vector_array<Out<double, -1, 3>>(std::move(p.face_normals), f, 3),
                vector_array<Out<std::int64_t, -1>>(std::move(p.edge_pair_offsets), hs + 1, 0),
                edge_pairs_object,
                vector_array<Out<std::int64_t, -1>>(std::move(p.climb_list_offsets), hs + 1, 0),
                climb_lists_object, nb::cast(std::move(seal)));
        },
        "points"_a, "offsets"_a, "threads"_a = 0,
        "Hulls of H point sets (shape h owns points[offsets[h]:offsets[h + 1]]) packed for a "
        "ConvexSet: (status (H,), vertices, offsets, adjacency_offsets, adjacency, "
        "face_offsets, face_normals, edge_pair_offsets, edge_pairs, climb_list_offsets, "
        "climb_lists, seal); the seal, passed to PackedConvexSet with these arrays, spares it "
        "reading their indices again.");

    m.def(
        "inscribed_balls",
        [](Params planes, Index64 offsets, int threads) {
            const long long h =
                group_count(offsets.data(), offsets.shape(0),
                            static_cast<std::int64_t>(planes.shape(0)), "offsets");
            const size_t hs = static_cast<size_t>(h);
            auto status = new_array<Out<std::int8_t, -1>>({hs});
            auto centres = new_array<Out<double, -1, 3>>({hs, 3});
            auto radii = new_array<Out<double, -1>>({hs});
            {
                nb::gil_scoped_release release;
                std::vector<meshcol::InscribedBall> balls(hs);
                meshcol::inscribed_balls(planes.data(), offsets.data(), h, threads, balls.data());
                for (size_t i = 0; i < hs; ++i) {
                    status.data()[i] = static_cast<std::int8_t>(balls[i].status);
                    centres.data()[3 * i] = balls[i].centre.x;
                    centres.data()[3 * i + 1] = balls[i].centre.y;
                    centres.data()[3 * i + 2] = balls[i].centre.z;
                    radii.data()[i] = balls[i].radius;
                }
            }
            return std::make_tuple(status, centres, radii);
        },
        "planes"_a, "offsets"_a, "threads"_a = 0,
        "In-sphere of H polytopes {x : n . x + d <= 0}, polytope h owning the unit-normal "
        "planes (n_x, n_y, n_z, d) planes[offsets[h]:offsets[h + 1]] (P, 4): (status (H,) "
        "int8 Status codes, centres (H, 3), radii (H,)); the Chebyshev centre's linear "
        "programme by an active-set simplex (inscribed_ball.hpp).");

    m.def(
        "hull_widths",
        [](Points vertices, Faces faces, Points directions) {
            const size_t k = vertices.shape(0), count = directions.shape(0);
            if (k < 1 || k > 0x7fffffff)
                throw std::invalid_argument("vertices must be (k, 3) with 1 <= k < 2**31, got (" +
                                            std::to_string(k) + ", 3)");
            auto widths = new_array<Out<double, -1>>({count});
            bool ok;
            {
                nb::gil_scoped_release release;
                ok = meshcol::hull_widths(
                    as_vec3(vertices), static_cast<int>(k), faces.data(),
                    static_cast<long long>(faces.shape(0)),
                    reinterpret_cast<const meshcol::Vec3*>(directions.data()),
                    static_cast<long long>(count), widths.data());
            }
            if (!ok) throw std::invalid_argument("faces must index the vertices");
            return widths;
        },
        "vertices"_a, "faces"_a, "directions"_a,
        "Width of a 3-D polytope (vertices (k, 3), triangles faces (m, 3)) across each of the "
        "directions (n, 3): the largest minus the smallest vertex projection "
        "fma(d.z, p.z, fma(d.y, p.y, d.x * p.x)), by support climbs; (n,) float64.");

    m.def(
        "distances_to_facets",
        [](Points points, Triangles facets,
           nb::ndarray<const bool, nb::shape<-1, -1>, nb::c_contig, nb::device::cpu> in_front) {
            const size_t q = points.shape(0), f = facets.shape(0);
            if (in_front.shape(0) != q || in_front.shape(1) != f)
                throw std::invalid_argument(
                    "in_front must be (points, facets) = (" + std::to_string(q) + ", " +
                    std::to_string(f) + "), got (" + std::to_string(in_front.shape(0)) + ", " +
                    std::to_string(in_front.shape(1)) + ")");
            auto distances = new_array<Out<double, -1>>({q});
            auto closest = new_array<Out<double, -1, 3>>({q, 3});
            {
                nb::gil_scoped_release release;
                static_assert(sizeof(bool) == sizeof(std::uint8_t), "bool is one byte");
                meshcol::distances_to_facets(
                    as_vec3(points), static_cast<long long>(q),
                    reinterpret_cast<const meshcol::Vec3*>(facets.data()),
                    static_cast<long long>(f),
                    reinterpret_cast<const std::uint8_t*>(in_front.data()), distances.data(),
                    reinterpret_cast<meshcol::Vec3*>(closest.data()));
            }
            return std::make_tuple(distances, closest);
        },
        "points"_a, "facets"_a, "in_front"_a,
        "Distance (q,) and closest point (q, 3) from each point (q, 3) to a convex polytope, "
        "searching the facets (m, 3, 3) in_front (q, m) marks for it (none: 0 and the point "
        "itself); numpy's arithmetic of closest_points_on_triangles, step for step.");
}
