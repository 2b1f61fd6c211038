// Exposes narrowphase.hpp: the packed convex set (packed_convex_set.hpp), its batched queries
// and their typed results. The Python API is meshcol/collision/narrowphase.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "meshcol/narrowphase.hpp"
#include "call_args.hpp"
#include "ndarray.hpp"
#include "packed_convex_set.hpp"
#include "shape_pair.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using Column = Out<double, -1>;
using Rows = Out<double, -1, 3>;

/// The result layouts of `query_object`: the query kind run, and the fields of the Python
/// result class in its field order (meshcol/collision/narrowphase.py).
enum class Layout : int { DISTANCE = 0, PENETRATION = 1, INTERSECTS = 2, SIGNED_DISTANCE = 3 };

// The field names of the results of each layout, in field order (DistanceBatch and
// DistanceResult share theirs, and so on), interned once.
const std::array<PyObject*, 6>& distance_fields() {
    static const std::array<PyObject*, 6> names = {interned("distance"),   interned("point_a"),
                                                   interned("point_b"),    interned("normal"),
                                                   interned("iterations"), interned("status")};
    return names;
}

const std::array<PyObject*, 6>& penetration_fields() {
    static const std::array<PyObject*, 6> names = {interned("depth"),      interned("normal"),
                                                   interned("point_a"),    interned("point_b"),
                                                   interned("iterations"), interned("status")};
    return names;
}

const std::array<PyObject*, 8>& signed_distance_fields() {
    static const std::array<PyObject*, 8> names = {
        interned("signed_distance"), interned("distance"), interned("depth"),
        interned("normal"),          interned("point_a"),  interned("point_b"),
        interned("iterations"),      interned("status")};
    return names;
}

// One batched query as its Python result: `result_type(...)`, the DistanceBatch,
// PenetrationBatch, IntersectsBatch or SignedDistanceBatch of `layout`, its arrays made by numpy
// and filled in place. `poses` (None: identity) and `pairs` are plain objects, read in place
// when already in the core's form (a C-contiguous (H, 4, 4) float64 array; a (P, 2) int64 one
// or a list of int pairs); anything else makes the call return None, and the caller converts
// them (as_poses, as_pairs: their messages) and calls again. A batch of one pair costs its
// query, its arrays and the result object: no DLPack export and no Python frame.
nb::object query_object(const PackedConvexSet& set, int layout, nb::handle poses, nb::handle pairs,
                        int threads, nb::handle result_type) {
    if (layout < 0 || layout > 3)
        throw std::invalid_argument("layout must be 0..3, got " + std::to_string(layout));
    const auto form = static_cast<Layout>(layout);
    const std::int64_t h = set.size();
    Float64Arg pose_arg;  // the batch reads the poses in place
    if (!pose_arg.read(poses, {static_cast<Py_ssize_t>(h), 4, 4})) return nb::none();
    PairsArg in;
    if (!in.read(pairs.ptr())) return nb::none();
    set.check_pairs(in.data, in.count);
    const auto n = static_cast<size_t>(in.count);
    meshcol::BatchOutput out;
    NumpyColumns arrays;
    const size_t status_array = arrays.add(n, &out.status);
    const auto q = form == Layout::DISTANCE     ? meshcol::QueryKind::DISTANCE
                   : form == Layout::INTERSECTS ? meshcol::QueryKind::INTERSECTS
                                                : meshcol::QueryKind::PENETRATION;
    size_t hit = 0, distance = 0, depth = 0, normal = 0, point_a = 0, point_b = 0, iterations = 0,
           signed_distance = 0;
    if (form == Layout::INTERSECTS) {
        hit = arrays.add(n, &out.intersects);
    } else {
        normal = arrays.add(n, &out.normal, 3);
        point_a = arrays.add(n, &out.point_a, 3);
        point_b = arrays.add(n, &out.point_b, 3);
        iterations = arrays.add(n, &out.iterations);
        if (form != Layout::PENETRATION) distance = arrays.add(n, &out.distance);
        if (form != Layout::DISTANCE) depth = arrays.add(n, &out.depth);
    }
    double* sd = nullptr;
    if (form == Layout::SIGNED_DISTANCE) signed_distance = arrays.add(n, &sd);
    arrays.make();
    const auto run = [&] {
        meshcol::run_batch(set.view(), pose_arg.data(), in.data, in.count, q, threads, out, &set.radii());
        for (size_t k = 0; k < (sd != nullptr ? n : 0); ++k) sd[k] = out.distance[k] - out.depth[k];
    };
    if (in.count <= 1) {
        run();  // one pair: its query can cost less than releasing the GIL
    } else {
        in.pin();  // the batch reads the copy, never numpy's array, once the GIL is released
        pose_arg.pin();
        nb::gil_scoped_release release;
        run();
    }
    switch (form) {
        case Layout::DISTANCE: {
            const auto& names = distance_fields();
            static DataclassMaker<6> maker;
            return maker.make(result_type, names,
                              {arrays[distance], arrays[point_a], arrays[point_b], arrays[normal],
                               arrays[iterations], arrays[status_array]});
        }
        case Layout::PENETRATION: {
            const auto& names = penetration_fields();
            static DataclassMaker<6> maker;
            return maker.make(result_type, names,
                              {arrays[depth], arrays[normal], arrays[point_a], arrays[point_b], arrays[iterations],
                               arrays[status_array]});
        }
        case Layout::INTERSECTS: {
            static const std::array<PyObject*, 2> names = {interned("intersects"), interned("status")};
            static DataclassMaker<2> maker;
            return maker.make(result_type, names, {arrays[hit], arrays[status_array]});
        }
        default: {
            const auto& names = signed_distance_fields();
            static DataclassMaker<8> maker;
            return maker.make(result_type, names,
                              {arrays[signed_distance], arrays[distance], arrays[depth], arrays[normal],
                               arrays[point_a], arrays[point_b], arrays[iterations], arrays[status_array]});
        }
    }
}

// One pair of shapes as its Python single-pair result (DistanceResult, PenetrationResult or
// SignedDistanceResult of `layout`; for INTERSECTS a bool, and `result_type` None), computed by the batch's own code on
// the two-shape set ConvexSet.from_shapes would pack (ShapePair), so it equals the batch's row
// to the bit: the shapes are primitives or (n, 3) float64 points (`kind_a`, `kind_b`: their
// ShapeKind), the poses read in place ((4, 4) float64, None: identity; both None: no poses, as
// the Python path passes them), the status enum's member taken from `statuses`. Returns None
// when a shape or pose is in another form, and for an INVALID_INPUT pair of INTERSECTS (a bool
// cannot carry it): the caller then takes the Python path, with its messages.
nb::object shape_pair_object(int layout, int kind_a, nb::handle a, int kind_b, nb::handle b,
                                 nb::handle pose_a, nb::handle pose_b, nb::handle result_type,
                                 nb::handle statuses) {
    if (layout < 0 || layout > 3)
        throw std::invalid_argument("layout must be 0..3, got " + std::to_string(layout));
    const auto form = static_cast<Layout>(layout);
    ShapePair shapes;
    if (!shapes.read(0, kind_a, a.ptr()) || !shapes.read(1, kind_b, b.ptr())) return nb::none();
    PairPoses poses;
    if (!poses.read(pose_a, pose_b)) return nb::none();
    const double* pose_data = pose_a.is_none() && pose_b.is_none() ? nullptr : poses.data();
    static constexpr std::int64_t pair[2] = {0, 1};
    meshcol::BatchOutput out;
    double distance = 0.0, depth = 0.0;
    std::int32_t iterations = 0;
    std::int8_t status = 0;
    bool hit = false;
    out.status = &status;
    NumpyColumns arrays;  // normal, point_a, point_b: (3,) each
    if (form == Layout::INTERSECTS) {
        out.intersects = &hit;
    } else {
        arrays.add(3, &out.normal);
        arrays.add(3, &out.point_a);
        arrays.add(3, &out.point_b);
        arrays.make();
        out.iterations = &iterations;
        out.distance = &distance;
        out.depth = &depth;
    }
    const nb::handle normal = arrays[0], point_a = arrays[1], point_b = arrays[2];
    const auto q = form == Layout::DISTANCE     ? meshcol::QueryKind::DISTANCE
                   : form == Layout::INTERSECTS ? meshcol::QueryKind::INTERSECTS
                                                : meshcol::QueryKind::PENETRATION;
    meshcol::run_batch(shapes.pack(), pose_data, pair, 1, q, 1, out);
    if (form == Layout::INTERSECTS) {
        if (status == static_cast<std::int8_t>(meshcol::Status::INVALID_INPUT)) return nb::none();
        return nb::bool_(hit);
    }
    const nb::handle member = status_member(statuses, status);
    const nb::object count = nb::int_(iterations);
    switch (form) {
        case Layout::DISTANCE: {
            const auto& names = distance_fields();
            static DataclassMaker<6> maker;
            return maker.make(result_type, names, {nb::float_(distance), point_a, point_b, normal, count, member});
        }
        case Layout::PENETRATION: {
            const auto& names = penetration_fields();
            static DataclassMaker<6> maker;
            return maker.make(result_type, names, {nb::float_(depth), normal, point_a, point_b, count, member});
        }
        default: {
            const auto& names = signed_distance_fields();
            static DataclassMaker<8> maker;
            return maker.make(result_type, names,
                              {nb::float_(distance - depth), nb::float_(distance), nb::float_(depth), normal,
                               point_a, point_b, count, member});
        }
    }
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

// The climb lists the core makes from the set's adjacency (`ClimbLists`, all cores), as new
// numpy arrays ((H + 1,) int64 offsets, (M, 16) uint8 rows); zeros and no rows when no shape
// has lists. Not attached to the set: what the packing writes, made another way.
std::pair<nb::object, nb::object> climb_arrays(const PackedConvexSet& set) {
    const size_t h = static_cast<size_t>(set.size());
    auto made = std::make_unique<meshcol::ClimbLists>(set.view(), 0);
    auto offsets = new_array<Out<std::int64_t, -1>>({h + 1});
    if (made->offsets() != nullptr)
        std::copy(made->offsets(), made->offsets() + h + 1, offsets.data());
    else
        std::fill(offsets.data(), offsets.data() + h + 1, std::int64_t{0});
    const auto* lists = made->lists();
    const size_t shape[2] = {static_cast<size_t>(made->size()), kClimbRowBytes};
    if (lists == nullptr) {
        auto none =
            new_array<Out<meshcol::ClimbIndex, -1, kClimbRowBytes>>({0, kClimbRowBytes});
        return {offsets.cast(), none.cast()};
    }
    nb::capsule owner(made.release(), [](void* p) noexcept {
        delete static_cast<meshcol::ClimbLists*>(p);
    });
    Out<meshcol::ClimbIndex, -1, kClimbRowBytes> rows(
        reinterpret_cast<meshcol::ClimbIndex*>(const_cast<meshcol::ClimbList*>(lists)), 2, shape,
        owner);
    return {offsets.cast(), rows.cast()};
}

}  // namespace

void bind_narrowphase(nb::module_& m) {
    m.def("shape_pair_object", &shape_pair_object, "layout"_a, "kind_a"_a, "a"_a,
          "kind_b"_a, "b"_a, "pose_a"_a.none(), "pose_b"_a.none(), "result_type"_a.none(), "statuses"_a,
          "One pair of shapes (primitives, or (n, 3) points by their hull; kind_a, kind_b their "
          "ShapeKind) as its single-pair result (layout as query_object; for intersects a "
          "bool); None when a shape or pose is not in the core's form, or for an invalid "
          "intersects pair.");
    nb::class_<PackSeal>(m, "PackSeal",
                         "pack_polytopes' word for its own index arrays (PackedConvexSet "
                         "skips reading them again when handed them in its layout).");
    nb::class_<PackedConvexSet>(m, "PackedConvexSet",
                                "Packed convex shapes (the arrays of meshcol.collision.shapes."
                                "ConvexSet).")
        .def(nb::init<Points, Index64, Kinds, Params, std::optional<Index64>,
                      std::optional<Index32>, std::optional<Index64>, std::optional<Points>,
                      std::optional<Index64>, std::optional<Pairs32>, const PackSeal*,
                      std::optional<Index64>, std::optional<ClimbRecords>>(),
             "vertices"_a, "offsets"_a, "kinds"_a, "params"_a, "adjacency_offsets"_a.none(),
             "adjacency"_a.none(), "face_offsets"_a.none(), "face_normals"_a.none(),
             "edge_pair_offsets"_a.none(), "edge_pairs"_a.none(), "seal"_a.none() = nb::none(),
             "climb_list_offsets"_a.none() = nb::none(), "climb_lists"_a.none() = nb::none())
        .def("__len__", &PackedConvexSet::size)
        .def_prop_ro("sealed", &PackedConvexSet::sealed,
                     "Whether the seal vouched for the index arrays (not read again).")
        .def("query_object", &query_object, "layout"_a, "poses"_a.none(), "pairs"_a.none(),
             "threads"_a, "result_type"_a,
             "One batch as result_type (layout 0 distance, 1 penetration, 2 intersects, 3 "
             "signed distance); None when poses or pairs are not in the core's form.")
        .def("climb_arrays", &climb_arrays,
             "The climb lists the core makes from the set's adjacency, as new arrays (not "
             "the set's): offsets (H + 1,) int64 and (M, 16) uint8 rows (count, then 15 "
             "neighbour slots).")
        .def("aabbs", &aabbs, "poses"_a.none(), "threads"_a = 0,
             "World AABBs (H, 3), (H, 3) under poses (None: identity).")
        .def("edge_classes", &edge_classes, "threads"_a = 0,
             "Every shape's edge-direction classes, each computed at most once in the set's "
             "life (SAT shares them): offsets (H + 1,) int64 and unit directions (E, 3).")
        .def("bounding_radii", &bounding_radii, "threads"_a = 0,
             "Radius (H,) of a ball about each shape's local origin holding the whole shape; "
             "NaN for an invalid shape.");
}
