// Exposes narrowphase.hpp: the packed convex set (packed_convex_set.hpp), its batched queries
// and their typed results. The Python API is meshcol/collision/narrowphase.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "meshcol/narrowphase.hpp"
#include "ndarray.hpp"
#include "packed_convex_set.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using Column = Out<double, -1>;
using Rows = Out<double, -1, 3>;

/// The arrays of one batched query, P entries each (P x 3 for vectors); a field the query
/// kind does not compute is None.
struct QueryArrays {
    std::optional<ArrayObject<Column>> distance;
    std::optional<ArrayObject<Column>> depth;
    std::optional<ArrayObject<Rows>> normal;
    std::optional<ArrayObject<Rows>> point_a;
    std::optional<ArrayObject<Rows>> point_b;
    std::optional<ArrayObject<Out<std::int32_t, -1>>> iterations;
    ArrayObject<Out<std::int8_t, -1>> status;
    std::optional<ArrayObject<Out<bool, -1>>> intersects;
};

QueryArrays query(const PackedConvexSet& set, int kind, std::optional<Poses> poses, Pairs pairs,
                  int threads) {
    const double* pose_data = set.check_poses(poses);
    set.check_pairs(pairs);
    const long long p = static_cast<long long>(pairs.shape(0));
    const auto q = static_cast<meshcol::QueryKind>(kind);
    const size_t n = static_cast<size_t>(p);
    meshcol::BatchOutput out;
    auto status = new_array<Out<std::int8_t, -1>>({n});
    out.status = status.data();
    std::optional<Out<bool, -1>> hit;
    std::optional<Column> distance, depth;
    std::optional<Rows> normal, point_a, point_b;
    std::optional<Out<std::int32_t, -1>> iterations;
    if (q == meshcol::QueryKind::INTERSECTS) {
        hit = new_array<Out<bool, -1>>({n});
        out.intersects = hit->data();
    } else {
        distance = new_array<Column>({n});
        normal = new_array<Rows>({n, 3});
        point_a = new_array<Rows>({n, 3});
        point_b = new_array<Rows>({n, 3});
        iterations = new_array<Out<std::int32_t, -1>>({n});
        out.distance = distance->data();
        out.normal = normal->data();
        out.point_a = point_a->data();
        out.point_b = point_b->data();
        out.iterations = iterations->data();
        if (q == meshcol::QueryKind::PENETRATION) {
            depth = new_array<Column>({n});
            out.depth = depth->data();
        }
    }
    {
        nb::gil_scoped_release release;
        meshcol::run_batch(set.view(), pose_data, pairs.data(), p, q, threads, out, &set.radii());
    }
    auto held = [](auto& a) { return a ? std::optional(a->cast()) : std::nullopt; };
    return QueryArrays{held(distance), held(depth),      held(normal),  held(point_a),
                       held(point_b),  held(iterations), status.cast(), held(hit)};
}

std::pair<Rows, Rows> aabbs(const PackedConvexSet& set, std::optional<Poses> poses, int threads) {
    const double* pose_data = set.check_poses(poses);
    const size_t h = static_cast<size_t>(set.view().shape_count);
    auto lo = new_array<Rows>({h, 3}), hi = new_array<Rows>({h, 3});
    {
        nb::gil_scoped_release release;
        meshcol::world_aabbs(set.view(), pose_data, lo.data(), hi.data(), threads);
    }
    return {lo, hi};
}

std::pair<Out<std::int64_t, -1>, Rows> edge_classes(const PackedConvexSet& set, int threads) {
    std::vector<std::int64_t> offsets;
    std::vector<double> directions;
    {
        nb::gil_scoped_release release;
        meshcol::all_edge_classes(set.view(), threads, offsets, directions);
    }
    const size_t rows = offsets.size(), e = directions.size() / 3;
    return {vector_array<Out<std::int64_t, -1>>(std::move(offsets), rows, 0),
            vector_array<Rows>(std::move(directions), e, 3)};
}

Column bounding_radii(const PackedConvexSet& set, int threads) {
    const size_t h = static_cast<size_t>(set.view().shape_count);
    auto radii = new_array<Column>({h});
    {
        nb::gil_scoped_release release;
        meshcol::bounding_radii(set.view(), radii.data(), threads);
    }
    return radii;
}

}  // namespace

void bind_narrowphase(nb::module_& m) {
    // Fields are returned as they are (rv_policy::automatic): the arrays own their data.
    const auto ro = nb::rv_policy::automatic;
    nb::class_<QueryArrays>(m, "QueryArrays",
                            "Arrays of a PackedConvexSet.query batch, in pair order; None for "
                            "a field the query kind does not compute.")
        .def_prop_ro(
            "distance", [](const QueryArrays& r) { return r.distance; }, ro, "(P,) float64, >= 0")
        .def_prop_ro(
            "depth", [](const QueryArrays& r) { return r.depth; }, ro,
            "(P,) float64, >= 0 (penetration only)")
        .def_prop_ro(
            "normal", [](const QueryArrays& r) { return r.normal; }, ro,
            "(P, 3) float64, world, unit, a to b")
        .def_prop_ro(
            "point_a", [](const QueryArrays& r) { return r.point_a; }, ro, "(P, 3) float64, world")
        .def_prop_ro(
            "point_b", [](const QueryArrays& r) { return r.point_b; }, ro, "(P, 3) float64, world")
        .def_prop_ro(
            "iterations", [](const QueryArrays& r) { return r.iterations; }, ro, "(P,) int32")
        .def_prop_ro(
            "status", [](const QueryArrays& r) { return r.status; }, ro, "(P,) int8 Status codes")
        .def_prop_ro(
            "intersects", [](const QueryArrays& r) { return r.intersects; }, ro,
            "(P,) bool (intersects only)");

    nb::class_<PackedConvexSet>(m, "PackedConvexSet",
                                "Packed convex shapes (the arrays of meshcol.collision.shapes."
                                "ConvexSet).")
        .def(nb::init<Points, Index64, Kinds, Params, std::optional<Index64>,
                      std::optional<Index32>, std::optional<Index64>, std::optional<Points>,
                      std::optional<Index64>, std::optional<Pairs32>>(),
             "vertices"_a, "offsets"_a, "kinds"_a, "params"_a, "adjacency_offsets"_a.none(),
             "adjacency"_a.none(), "face_offsets"_a.none(), "face_normals"_a.none(),
             "edge_pair_offsets"_a.none(), "edge_pairs"_a.none())
        .def("__len__", &PackedConvexSet::size)
        .def("query", &query, "kind"_a, "poses"_a.none(), "pairs"_a, "threads"_a = 0,
             "Runs query kind (0 distance, 1 penetration, 2 intersects) on (P, 2) pairs.")
        .def("aabbs", &aabbs, "poses"_a.none(), "threads"_a = 0,
             "World AABBs (H, 3), (H, 3) under poses (None: identity).")
        .def("edge_classes", &edge_classes, "threads"_a = 0,
             "Every shape's edge-direction classes, each computed at most once in the set's "
             "life (SAT shares them): offsets (H + 1,) int64 and unit directions (E, 3).")
        .def("bounding_radii", &bounding_radii, "threads"_a = 0,
             "Radius (H,) of a ball about each shape's local origin holding the whole shape; "
             "NaN for an invalid shape.");
}
