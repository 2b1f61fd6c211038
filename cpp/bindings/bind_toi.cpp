// Exposes toi.hpp: batched time of impact over the arrays of a meshcol.query.ConvexSet, and the
// pose interpolation the motion model uses. The Python API is meshcol/sweep.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "meshcol/defaults.hpp"
#include "meshcol/toi.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

using Points = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using Params = nb::ndarray<const double, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;
using Index64 = nb::ndarray<const std::int64_t, nb::shape<-1>, nb::c_contig, nb::device::cpu>;
using Index32 = nb::ndarray<const std::int32_t, nb::shape<-1>, nb::c_contig, nb::device::cpu>;
using Kinds = nb::ndarray<const std::int8_t, nb::shape<-1>, nb::c_contig, nb::device::cpu>;
using Poses = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;
using Pairs = nb::ndarray<const std::int64_t, nb::shape<-1, 2>, nb::c_contig, nb::device::cpu>;
using Times = nb::ndarray<const double, nb::shape<-1>, nb::c_contig, nb::device::cpu>;

template <class T>
nb::ndarray<nb::numpy, T> new_array(std::initializer_list<size_t> shape) {
    size_t n = 1;
    for (size_t s : shape) n *= s;
    T* data = new T[n + 1];
    nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
    return nb::ndarray<nb::numpy, T>(data, shape, owner);
}

void check_offsets(const std::int64_t* off, size_t n, std::int64_t total, const char* name) {
    if (n == 0 || off[0] != 0 || off[n - 1] != total)
        throw std::invalid_argument(std::string(name) + " must start at 0 and end at " +
                                    std::to_string(total));
    for (size_t i = 1; i < n; ++i)
        if (off[i] < off[i - 1])
            throw std::invalid_argument(std::string(name) + " must be non-decreasing");
}

nb::dict time_of_impact_batch(Points vertices, Index64 offsets, Kinds kinds, Params params,
                              std::optional<Index64> adjacency_offsets,
                              std::optional<Index32> adjacency, Poses start_poses,
                              Poses end_poses, Pairs pairs, double tolerance, int max_iterations,
                              int threads) {
    const std::int64_t v = static_cast<std::int64_t>(vertices.shape(0));
    const std::int64_t h = static_cast<std::int64_t>(kinds.shape(0));
    if (static_cast<std::int64_t>(offsets.shape(0)) != h + 1)
        throw std::invalid_argument("offsets must be (H + 1,) with H = len(kinds)");
    if (static_cast<std::int64_t>(params.shape(0)) != h)
        throw std::invalid_argument("params must be (H, 4) with H = len(kinds)");
    check_offsets(offsets.data(), offsets.shape(0), v, "offsets");
    for (std::int64_t i = 0; i < h; ++i)
        if (kinds.data()[i] < 0 || kinds.data()[i] > 4)
            throw std::invalid_argument("kinds must be in 0..4, got " +
                                        std::to_string(int(kinds.data()[i])));
    for (const Poses* p : {&start_poses, &end_poses})
        if (static_cast<std::int64_t>(p->shape(0)) != h)
            throw std::invalid_argument(std::string(p == &start_poses ? "start" : "end") +
                                        "_poses must be (" + std::to_string(h) + ", 4, 4), got (" +
                                        std::to_string(p->shape(0)) + ", 4, 4)");
    if (!(tolerance > 0.0) || !std::isfinite(tolerance))
        throw std::invalid_argument("tolerance must be finite and > 0, got " +
                                    std::to_string(tolerance));
    if (max_iterations < 1)
        throw std::invalid_argument("max_iterations must be >= 1, got " +
                                    std::to_string(max_iterations));
    meshcol::ConvexSetView view;
    view.vertices = vertices.data();
    view.vertex_count = v;
    view.offsets = offsets.data();
    view.shape_count = h;
    view.kinds = kinds.data();
    view.params = params.data();
    if (adjacency_offsets.has_value() != adjacency.has_value())
        throw std::invalid_argument("adjacency_offsets and adjacency go together");
    if (adjacency_offsets) {
        const std::int64_t k = static_cast<std::int64_t>(adjacency->shape(0));
        if (static_cast<std::int64_t>(adjacency_offsets->shape(0)) != v + 1)
            throw std::invalid_argument("adjacency_offsets must be (V + 1,)");
        check_offsets(adjacency_offsets->data(), adjacency_offsets->shape(0), k,
                      "adjacency_offsets");
        for (std::int64_t s = 0; s < h; ++s) {
            const std::int64_t begin = offsets.data()[s], end = offsets.data()[s + 1];
            for (std::int64_t j = adjacency_offsets->data()[begin];
                 j < adjacency_offsets->data()[end]; ++j) {
                const std::int32_t n = adjacency->data()[j];
                if (n < 0 || n >= end - begin)
                    throw std::invalid_argument("adjacency holds an index out of range");
            }
        }
        view.adjacency_offsets = adjacency_offsets->data();
        view.adjacency = adjacency->data();
    }
    const long long p = static_cast<long long>(pairs.shape(0));
    const std::int64_t* idx = pairs.data();
    for (long long i = 0; i < 2 * p; ++i)
        if (idx[i] < 0 || idx[i] >= h)
            throw std::invalid_argument("pairs: index " + std::to_string(idx[i]) +
                                        " out of range for " + std::to_string(h) + " shapes");
    const size_t n = static_cast<size_t>(p);
    auto toi = new_array<double>({n});
    auto point = new_array<double>({n, 3});
    auto normal = new_array<double>({n, 3});
    auto iterations = new_array<std::int32_t>({n});
    auto status = new_array<std::int8_t>({n});
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
        meshcol::run_toi_batch(view, start_poses.data(), end_poses.data(), idx, p, options,
                               threads, out);
    }
    nb::dict d;
    d["toi"] = toi;
    d["point"] = point;
    d["normal"] = normal;
    d["iterations"] = iterations;
    d["status"] = status;
    return d;
}

nb::ndarray<nb::numpy, double> interpolate_poses(Poses start_poses, Poses end_poses, Times t) {
    const size_t n = start_poses.shape(0);
    if (end_poses.shape(0) != n || t.shape(0) != n)
        throw std::invalid_argument("start_poses, end_poses and t must have the same length");
    auto out = new_array<double>({n, 4, 4});
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
    m.def("time_of_impact_batch", &time_of_impact_batch, "vertices"_a, "offsets"_a, "kinds"_a,
          "params"_a, "adjacency_offsets"_a.none(), "adjacency"_a.none(), "start_poses"_a,
          "end_poses"_a, "pairs"_a, "tolerance"_a = meshcol::defaults::toi_tolerance,
          "max_iterations"_a = meshcol::defaults::toi_max_iterations, "threads"_a = 0,
          "Time of impact of (P, 2) pairs of packed convex shapes moving from start_poses to "
          "end_poses ((H, 4, 4) each); returns a dict of numpy arrays (toi, point, normal, "
          "iterations, status).");
    m.def("interpolate_poses", &interpolate_poses, "start_poses"_a, "end_poses"_a, "t"_a,
          "Poses (N, 4, 4) at times t (N,) of the motions start -> end (translation linear, "
          "rotation slerped about the local origin).");
}
