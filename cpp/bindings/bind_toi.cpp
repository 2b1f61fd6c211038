// Exposes toi.hpp: batched time of impact over the arrays of a
// meshcol.collision.shapes.ConvexSet, its result object made natively, and the pose
// interpolation the motion model uses. The Python API is meshcol/collision/time_of_impact.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/toi.hpp"
#include "call_args.hpp"
#include "ndarray.hpp"
#include "packed_convex_set.hpp"
#include "shape_pair.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

/// The data of an optional (N, 3) array of the turns, checked to have `n` rows (null: absent).
const double* turn_rows(const std::optional<Points>& rows, size_t n, const char* name) {
    if (!rows) return nullptr;
    if (rows->shape(0) != n)
        throw std::invalid_argument(std::string(name) + " must be (" + std::to_string(n) +
                                    ", 3), got (" + std::to_string(rows->shape(0)) + ", 3)");
    return rows->data();
}

/// The options of a time-of-impact call, checked.
meshcol::ToiOptions toi_options(double tolerance, int max_iterations) {
    if (!(tolerance > 0.0) || !std::isfinite(tolerance))
        throw std::invalid_argument("tolerance must be finite and > 0, got " +
                                    std::to_string(tolerance));
    if (max_iterations < 1)
        throw std::invalid_argument("max_iterations must be >= 1, got " +
                                    std::to_string(max_iterations));
    meshcol::ToiOptions options;
    options.tolerance = tolerance;
    options.max_iterations = max_iterations;
    return options;
}

// One time-of-impact batch as `result_type(time_of_impact, point, normal, iterations, status)`
// (meshcol.collision.time_of_impact.TimeOfImpactBatch), made as query_object makes the narrow
// phase's batches: the poses ((H, 4, 4) float64), the turns and pivots ((H, 3) float64 or
// None) and the pairs are plain objects read in place when they are in the core's form;
// anything else makes the call return None, and the caller converts them (as_poses,
// as_vectors, as_pairs: their messages) and calls again. A batch of one pair thus costs its
// query, five numpy.empty calls and the result object.
nb::object time_of_impact_object(const PackedConvexSet& set, nb::handle start_poses,
                                 nb::handle end_poses, nb::handle pairs, nb::handle rotations,
                                 nb::handle pivots, double tolerance, int max_iterations,
                                 int threads, nb::handle result_type) {
    const meshcol::ToiOptions options = toi_options(tolerance, max_iterations);
    const auto h = static_cast<Py_ssize_t>(set.size());
    Float64Arg start, end, turns, centres;
    if (start_poses.is_none() || end_poses.is_none() || !start.read(start_poses, {h, 4, 4}) ||
        !end.read(end_poses, {h, 4, 4}) || !turns.read(rotations, {h, 3}) ||
        !centres.read(pivots, {h, 3}))
        return nb::none();
    PairsArg in;
    if (!in.read(pairs.ptr())) return nb::none();
    set.check_pairs(in.data, in.count);
    const auto n = static_cast<size_t>(in.count);
    meshcol::ToiBatchOutput out;
    NumpyColumns arrays;  // made in the order of `names`
    arrays.add(n, &out.toi);
    arrays.add(n, &out.point, 3);
    arrays.add(n, &out.normal, 3);
    arrays.add(n, &out.iterations);
    arrays.add(n, &out.status);
    arrays.make();
    const auto run = [&] {
        meshcol::run_toi_batch(set.view(), start.data(), end.data(), turns.data(), centres.data(),
                               in.data, in.count, options, threads, out);
    };
    if (in.count <= 1) {
        run();  // one pair: its query can cost less than releasing the GIL
    } else {
        in.pin();  // the batch reads copies or exported buffers once the GIL is released
        for (Float64Arg* arg : {&start, &end, &turns, &centres}) arg->pin();
        nb::gil_scoped_release release;
        run();
    }
    static const std::array<PyObject*, 5> names = {interned("time_of_impact"), interned("point"),
                                                   interned("normal"), interned("iterations"),
                                                   interned("status")};
    static DataclassMaker<5> maker;
    std::array<nb::handle, 5> values;
    for (size_t k = 0; k < 5; ++k) values[k] = arrays[k];
    return maker.make(result_type, names, values);
}

// The time of impact of one pair of shapes as its Python single-pair result,
// `result_type(status, time_of_impact, point, normal, iterations)` (TimeOfImpactResult; None
// for the time when there is none), computed by the batch's own code on the two-shape set
// ConvexSet.from_shapes would pack (ShapePair), so it equals the batch's row to the bit. The
// shapes are primitives or (n, 3) float64 points (`kind_a`, `kind_b`: their ShapeKind), the
// poses read in place ((4, 4) float64, None: identity), each shape turning the shortest way
// about its origin; the status member is taken from `statuses`. Returns None when a shape or
// pose is in another form: the caller then takes the Python path, with its messages.
nb::object shape_pair_toi_object(int kind_a, nb::handle a, int kind_b, nb::handle b,
                                     nb::handle start_pose_a, nb::handle end_pose_a,
                                     nb::handle start_pose_b, nb::handle end_pose_b,
                                     double tolerance, int max_iterations,
                                     nb::handle result_type, nb::handle statuses) {
    const meshcol::ToiOptions options = toi_options(tolerance, max_iterations);
    ShapePair shapes;
    if (!shapes.read(0, kind_a, a.ptr()) || !shapes.read(1, kind_b, b.ptr())) return nb::none();
    PairPoses starts, ends;
    if (!starts.read(start_pose_a, start_pose_b) || !ends.read(end_pose_a, end_pose_b))
        return nb::none();
    static constexpr std::int64_t pair[2] = {0, 1};
    meshcol::ToiBatchOutput out;
    double toi = 0.0;
    std::int32_t iterations = 0;
    std::int8_t status = 0;
    out.toi = &toi;
    out.iterations = &iterations;
    out.status = &status;
    NumpyColumns arrays;
    arrays.add(3, &out.point);
    arrays.add(3, &out.normal);
    arrays.make();
    const nb::handle point = arrays[0], normal = arrays[1];
    meshcol::run_toi_batch(shapes.pack(), starts.data(), ends.data(), nullptr, nullptr, pair, 1,
                           options, 1, out);
    static const std::array<PyObject*, 5> names = {interned("status"), interned("time_of_impact"),
                                                   interned("point"), interned("normal"),
                                                   interned("iterations")};
    static DataclassMaker<5> maker;
    const nb::object fraction = std::isnan(toi) ? nb::none() : nb::object(nb::float_(toi));
    return maker.make(result_type, names,
                      {status_member(statuses, status), fraction, point, normal, nb::int_(iterations)});
}

Out<double, -1, 4, 4> interpolate_poses(Poses start_poses, Poses end_poses, Values t,
                                        std::optional<Points> rotations,
                                        std::optional<Points> pivots) {
    const size_t n = start_poses.shape(0);
    if (end_poses.shape(0) != n || t.shape(0) != n)
        throw std::invalid_argument("start_poses, end_poses and t must have the same length");
    const double* turns = turn_rows(rotations, n, "rotations");
    const double* centres = turn_rows(pivots, n, "pivots");
    std::vector<meshcol::Motion> motions(n);
    std::vector<char> ok(n, 0);
    meshcol::make_motions(static_cast<long long>(n), start_poses.data(), end_poses.data(), turns,
                          centres, motions.data(), ok.data());
    auto out = new_array<Out<double, -1, 4, 4>>({n, 4, 4});
    double* o = out.data();
    for (size_t i = 0; i < n; ++i) {
        const double ti = t.data()[i];
        if (!ok[i] || !std::isfinite(ti))
            throw std::invalid_argument(
                "pose " + std::to_string(i) +
                ": start or end pose not rigid, a turn that does not reach the end rotation, or "
                "t not finite");
        const meshcol::Pose p = motions[i].at(ti);
        double* m = o + 16 * i;
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) m[4 * r + c] = p.rotation.m[r][c];
            m[4 * r + 3] = p.translation[r];
        }
        m[12] = m[13] = m[14] = 0.0;
        m[15] = 1.0;
    }
    return out;
}

Out<double, -1, 3> shortest_rotations(Poses start_poses, Poses end_poses) {
    const size_t n = start_poses.shape(0);
    if (end_poses.shape(0) != n)
        throw std::invalid_argument("start_poses and end_poses must have the same length");
    auto out = new_array<Out<double, -1, 3>>({n, 3});
    for (size_t i = 0; i < n; ++i) {
        const meshcol::Pose p0 = meshcol::Pose::from_matrix4(start_poses.data() + 16 * i);
        const meshcol::Pose p1 = meshcol::Pose::from_matrix4(end_poses.data() + 16 * i);
        meshcol::store_row(out.data(), static_cast<long long>(i),
                           meshcol::shortest_rotation(p0.rotation, p1.rotation));
    }
    return out;
}

}  // namespace

void bind_toi(nb::module_& m) {
    m.def("shape_pair_toi_object", &shape_pair_toi_object, "kind_a"_a, "a"_a, "kind_b"_a,
          "b"_a, "start_pose_a"_a.none(), "end_pose_a"_a.none(), "start_pose_b"_a.none(),
          "end_pose_b"_a.none(), "tolerance"_a, "max_iterations"_a, "result_type"_a,
          "statuses"_a,
          "Time of impact of one pair of shapes (primitives, or (n, 3) points by their hull; "
          "each turning the shortest way about its origin) as result_type; None when a shape "
          "or pose is not in the core's form.");
    m.def("time_of_impact_object", &time_of_impact_object, "shapes"_a, "start_poses"_a.none(),
          "end_poses"_a.none(), "pairs"_a.none(), "rotations"_a.none(), "pivots"_a.none(),
          "tolerance"_a, "max_iterations"_a, "threads"_a, "result_type"_a,
          "Time of impact of the (P, 2) pairs of a PackedConvexSet's shapes moving from "
          "start_poses to end_poses ((H, 4, 4) each), turning by the world rotation vectors "
          "rotations (H, 3; None: the shortest rotation) about the world points pivots (H, 3; "
          "None: the local origins), as result_type; None when an argument is not in the core's "
          "form.");
    m.def("interpolate_poses", &interpolate_poses, "start_poses"_a, "end_poses"_a, "t"_a,
          "rotations"_a.none() = nb::none(), "pivots"_a.none() = nb::none(),
          "Poses (N, 4, 4) at times t (N,) of the motions start -> end (the pivot moves "
          "linearly, the body turns about it by the rotation vector, any angle).");
    m.def("shortest_rotations", &shortest_rotations, "start_poses"_a, "end_poses"_a,
          "World rotation vectors (N, 3), angle in [0, pi], of the shortest rotations taking "
          "each start pose's rotation to its end pose's.");
}
