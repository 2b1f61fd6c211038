// Exposes toi.hpp: batched time of impact over the arrays of a
// meshcol.collision.shapes.ConvexSet, its typed result, and the pose interpolation the motion
// model uses. The Python API is meshcol/collision/time_of_impact.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/toi.hpp"
#include "ndarray.hpp"
#include "packed_convex_set.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

/// The arrays of one time-of-impact batch, P entries each (P x 3 for vectors).
struct TimeOfImpactArrays {
    ArrayObject<Out<double, -1>> time_of_impact;
    ArrayObject<Out<double, -1, 3>> point;
    ArrayObject<Out<double, -1, 3>> normal;
    ArrayObject<Out<std::int32_t, -1>> iterations;
    ArrayObject<Out<std::int8_t, -1>> status;
};

/// The data of an optional (N, 3) array of the turns, checked to have `n` rows (null: absent).
const double* turn_rows(const std::optional<Points>& rows, size_t n, const char* name) {
    if (!rows) return nullptr;
    if (rows->shape(0) != n)
        throw std::invalid_argument(std::string(name) + " must be (" + std::to_string(n) +
                                    ", 3), got (" + std::to_string(rows->shape(0)) + ", 3)");
    return rows->data();
}

TimeOfImpactArrays time_of_impact_batch(const PackedConvexSet& set, Poses start_poses,
                                        Poses end_poses, Pairs pairs,
                                        std::optional<Points> rotations,
                                        std::optional<Points> pivots, double tolerance,
                                        int max_iterations, int threads) {
    set.check_poses(start_poses, "start_poses");
    set.check_poses(end_poses, "end_poses");
    const size_t h = start_poses.shape(0);
    const double* turns = turn_rows(rotations, h, "rotations");
    const double* centres = turn_rows(pivots, h, "pivots");
    set.check_pairs(pairs);
    if (!(tolerance > 0.0) || !std::isfinite(tolerance))
        throw std::invalid_argument("tolerance must be finite and > 0, got " +
                                    std::to_string(tolerance));
    if (max_iterations < 1)
        throw std::invalid_argument("max_iterations must be >= 1, got " +
                                    std::to_string(max_iterations));
    const long long p = static_cast<long long>(pairs.shape(0));
    const size_t n = static_cast<size_t>(p);
    auto toi = new_array<Out<double, -1>>({n});
    auto point = new_array<Out<double, -1, 3>>({n, 3});
    auto normal = new_array<Out<double, -1, 3>>({n, 3});
    auto iterations = new_array<Out<std::int32_t, -1>>({n});
    auto status = new_array<Out<std::int8_t, -1>>({n});
    meshcol::ToiBatchOutput out;
    out.toi = toi.data();
    out.point = point.data();
    out.normal = normal.data();
    out.iterations = iterations.data();
    out.status = status.data();
    meshcol::ToiOptions options;
    options.tolerance = tolerance;
    options.max_iterations = max_iterations;
    {
        nb::gil_scoped_release release;
        meshcol::run_toi_batch(set.view(), start_poses.data(), end_poses.data(), turns, centres,
                               pairs.data(), p, options, threads, out);
    }
    return TimeOfImpactArrays{toi.cast(), point.cast(), normal.cast(), iterations.cast(),
                              status.cast()};
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
    const auto ro = nb::rv_policy::automatic;
    nb::class_<TimeOfImpactArrays>(m, "TimeOfImpactArrays",
                                   "Arrays of a time_of_impact_batch, in pair order.")
        .def_prop_ro("time_of_impact",
                     [](const TimeOfImpactArrays& r) { return r.time_of_impact; }, ro,
                     "(P,) float64 fraction of the motion; NaN when SEPARATED or invalid")
        .def_prop_ro("point", [](const TimeOfImpactArrays& r) { return r.point; }, ro,
                     "(P, 3) float64, world")
        .def_prop_ro("normal", [](const TimeOfImpactArrays& r) { return r.normal; }, ro,
                     "(P, 3) float64, world, unit, a to b")
        .def_prop_ro("iterations", [](const TimeOfImpactArrays& r) { return r.iterations; },
                     ro, "(P,) int32")
        .def_prop_ro("status", [](const TimeOfImpactArrays& r) { return r.status; }, ro,
                     "(P,) int8 TimeOfImpactStatus codes");
    m.def("time_of_impact_batch", &time_of_impact_batch, "shapes"_a, "start_poses"_a,
          "end_poses"_a, "pairs"_a, "rotations"_a.none() = nb::none(),
          "pivots"_a.none() = nb::none(), "tolerance"_a = meshcol::defaults::toi_tolerance,
          "max_iterations"_a = meshcol::defaults::toi_max_iterations, "threads"_a = 0,
          "Time of impact of (P, 2) pairs of a PackedConvexSet's shapes moving from start_poses to "
          "end_poses ((H, 4, 4) each), turning by the world rotation vectors rotations (H, 3; "
          "None: the shortest rotation) about the world points pivots (H, 3; None: the local "
          "origins).");
    m.def("interpolate_poses", &interpolate_poses, "start_poses"_a, "end_poses"_a, "t"_a,
          "rotations"_a.none() = nb::none(), "pivots"_a.none() = nb::none(),
          "Poses (N, 4, 4) at times t (N,) of the motions start -> end (the pivot moves "
          "linearly, the body turns about it by the rotation vector, any angle).");
    m.def("shortest_rotations", &shortest_rotations, "start_poses"_a, "end_poses"_a,
          "World rotation vectors (N, 3), angle in [0, pi], of the shortest rotations taking "
          "each start pose's rotation to its end pose's.");
}
