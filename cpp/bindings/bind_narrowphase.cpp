// Exposes narrowphase.hpp: the packed convex set (packed_convex_set.hpp) and its batched
// queries. The Python API is meshcol/query.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "meshcol/defaults.hpp"
#include "meshcol/narrowphase.hpp"
#include "packed_convex_set.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

nb::dict query(const PackedConvexSet& set, int kind, std::optional<Poses> poses, Pairs pairs,
               int threads) {
    const double* pose_data = set.check_poses(poses);
    set.check_pairs(pairs);
    const long long p = static_cast<long long>(pairs.shape(0));
    const std::int64_t* idx = pairs.data();
    const auto q = static_cast<meshcol::QueryKind>(kind);
    nb::dict d;
    meshcol::BatchOutput out;
    const size_t n = static_cast<size_t>(p);
    auto status = new_array<std::int8_t>({n});
    out.status = status.data();
    d["status"] = status;
    if (q == meshcol::QueryKind::INTERSECTS) {
        auto hit = new_array<bool>({n});
        out.intersects = hit.data();
        d["intersects"] = hit;
    } else {
        auto distance = new_array<double>({n}), normal = new_array<double>({n, 3}),
             pa = new_array<double>({n, 3}), pb = new_array<double>({n, 3});
        auto iterations = new_array<std::int32_t>({n});
        out.distance = distance.data();
        out.normal = normal.data();
        out.point_a = pa.data();
        out.point_b = pb.data();
        out.iterations = iterations.data();
        d["distance"] = distance;
        d["normal"] = normal;
        d["point_a"] = pa;
        d["point_b"] = pb;
        d["iterations"] = iterations;
        if (q == meshcol::QueryKind::PENETRATION) {
            auto depth = new_array<double>({n});
            out.depth = depth.data();
            d["depth"] = depth;
        }
    }
    {
        nb::gil_scoped_release release;
        meshcol::run_batch(set.view(), pose_data, idx, p, q, threads, out);
    }
    return d;
}

nb::tuple aabbs(const PackedConvexSet& set, std::optional<Poses> poses, int threads) {
    const double* pose_data = set.check_poses(poses);
    const size_t h = static_cast<size_t>(set.view().shape_count);
    auto lo = new_array<double>({h, 3}), hi = new_array<double>({h, 3});
    {
        nb::gil_scoped_release release;
        meshcol::world_aabbs(set.view(), pose_data, lo.data(), hi.data(), threads);
    }
    return nb::make_tuple(lo, hi);
}

}  // namespace

void bind_narrowphase(nb::module_& m) {
    nb::class_<PackedConvexSet>(m, "PackedConvexSet",
                                "Packed convex shapes (the arrays of meshcol.query.ConvexSet).")
        .def(nb::init<Points, Index64, Kinds, Params, std::optional<Index64>,
                      std::optional<Index32>, std::optional<Index64>, std::optional<Points>,
                      std::optional<Index64>, std::optional<Points>>(),
             "vertices"_a, "offsets"_a, "kinds"_a, "params"_a, "adjacency_offsets"_a.none(),
             "adjacency"_a.none(), "face_offsets"_a.none(), "face_normals"_a.none(),
             "edge_offsets"_a.none(), "edge_directions"_a.none())
        .def("__len__", &PackedConvexSet::size)
        .def("query", &query, "kind"_a, "poses"_a.none(), "pairs"_a,
             "threads"_a = 0,
             "Runs query kind (0 distance, 1 penetration, 2 intersects) on (P, 2) pairs; "
             "returns a dict of numpy arrays.")
        .def("aabbs", &aabbs, "poses"_a.none(), "threads"_a = 0,
             "World AABBs (H, 3), (H, 3) under poses (None: identity).");
}
