// Exposes toi.hpp: batched time of impact over the arrays of a
// meshcol.collision.shapes.ConvexSet, its typed result, and the pose interpolation the motion
// model uses. The Python API is meshcol/collision/time_of_impact.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

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

TimeOfImpactArrays time_of_impact_batch(const PackedConvexSet& set, Poses start_poses,
                                        Poses end_poses, Pairs pairs, double tolerance,
                                        int max_iterations, int threads) {
    set.check_poses(start_poses, "start_poses");
    set.check_poses(end_poses, "end_poses");
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
        meshcol::run_toi_batch(set.view(), start_poses.data(), end_poses.data(), pairs.data(), p,
                               options, threads, out);
    }
    return TimeOfImpactArrays{toi.cast(), point.cast(), normal.cast(), iterations.cast(),
                              status.cast()};
}

Out<double, -1, 4, 4> interpolate_poses(Poses start_poses, Poses end_poses, Values t) {
    const size_t n = start_poses.shape(0);
    if (end_poses.shape(0) != n || t.shape(0) != n)
        throw std::invalid_argument("start_poses, end_poses and t must have the same length");
    auto out = new_array<Out<double, -1, 4, 4>>({n, 4, 4});
    double* o = out.data();
    for (size_t i = 0; i < n; ++i) {
        const double* m0 = start_poses.data() + 16 * i;
        const double* m1 = end_poses.data() + 16 * i;
        const double ti = t.data()[i];
        if (!meshcol::is_rigid_matrix4(m0, meshcol::defaults::rigid_tolerance) ||
            !meshcol::is_rigid_matrix4(m1, meshcol::defaults::rigid_tolerance) ||
            !std::isfinite(ti))
            throw std::invalid_argument("pose " + std::to_string(i) +
                                        ": start or end pose not rigid, or t not finite");
        const meshcol::Pose p = meshcol::interpolate_pose(meshcol::Pose::from_matrix4(m0),
                                                          meshcol::Pose::from_matrix4(m1), ti);
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
          "end_poses"_a, "pairs"_a, "tolerance"_a = meshcol::defaults::toi_tolerance,
          "max_iterations"_a = meshcol::defaults::toi_max_iterations, "threads"_a = 0,
          "Time of impact of (P, 2) pairs of a PackedConvexSet's shapes moving from start_poses to "
          "end_poses ((H, 4, 4) each).");
    m.def("interpolate_poses", &interpolate_poses, "start_poses"_a, "end_poses"_a, "t"_a,
          "Poses (N, 4, 4) at times t (N,) of the motions start -> end (translation linear, "
          "rotation slerped about the local origin).");
}
