// Exposes fit.hpp: enclosing primitives of many point sets in one call, and the minimum ball.
// The Python API is meshcol/collision/fit.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "meshcol/fit.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

void bind_fit(nb::module_& m) {
    namespace d = meshcol::defaults;
    using S = meshcol::FitStatus;
    nb::enum_<S>(m, "FitStatus", "Outcome of one enclosing fit (fit.hpp).")
        .value("OK", S::OK)
        .value("MAX_ITERATIONS", S::MAX_ITERATIONS)
        .value("INVALID_INPUT", S::INVALID_INPUT)
        .value("FAILED", S::FAILED);

    m.def(
        "minimum_ball",
        [](In<double, -1, -1> points) {
            const long long n = static_cast<long long>(points.shape(0));
            const int dim = static_cast<int>(points.shape(1));
            if (n == 0) throw std::invalid_argument("no points");
            if (dim < 1 || dim > 3)
                throw std::invalid_argument("points must be (n, d) with 1 <= d <= 3");
            double center[3], radius = 0.0;
            bool converged;
            {
                nb::gil_scoped_release release;
                converged = meshcol::minimum_ball(points.data(), n, dim, center, radius);
            }
            auto c = new_array<Out<double, -1>>({static_cast<size_t>(dim)});
            for (int k = 0; k < dim; ++k) c.data()[k] = center[k];
            return std::make_tuple(c, radius, converged);
        },
        "points"_a,
        "Smallest ball of (n, d) points, d <= 3 (Welzl): (centre (d,), radius, converged).");

    m.def(
        "fit_primitives",
        [](Points points, Index64 offsets, In<std::int8_t, -1> shapes, int threads) {
            const long long h =
                group_count(offsets.data(), offsets.shape(0),
                            static_cast<std::int64_t>(points.shape(0)), "offsets");
            const int k = static_cast<int>(shapes.shape(0));
            std::vector<meshcol::FitShape> kinds(static_cast<size_t>(k));
            for (int i = 0; i < k; ++i) {
                const std::int8_t s = shapes.data()[i];
                if (s < 0 || s > 4) throw std::invalid_argument("shapes must be codes 0 to 4");
                kinds[static_cast<size_t>(i)] = static_cast<meshcol::FitShape>(s);
            }
            std::vector<meshcol::FitSet> sets;
            {
                nb::gil_scoped_release release;
                sets = meshcol::fit_point_sets(
                    reinterpret_cast<const meshcol::Vec3*>(points.data()), offsets.data(), h,
                    kinds.data(), k, threads);
            }
            const size_t hs = static_cast<size_t>(h), ks = static_cast<size_t>(k);
            std::vector<std::int8_t> hull_status(hs), dimension(hs), status(hs * ks);
            std::vector<double> params(hs * ks * 3), poses(hs * ks * 16), volume(hs * ks),
                excess(hs * ks), hull_volume(hs);
            std::vector<std::int64_t> vertex_offsets(hs + 1, 0), face_offsets(hs + 1, 0);
            std::vector<std::int64_t> vertices, faces;
            for (size_t i = 0; i < hs; ++i) {
                const auto& s = sets[i];
                hull_status[i] = static_cast<std::int8_t>(s.hull.status);
                dimension[i] = static_cast<std::int8_t>(s.hull.dimension);
                hull_volume[i] = s.hull.volume;
                for (int v : s.hull.vertices) vertices.push_back(v);
                for (const auto& f : s.hull.faces) faces.insert(faces.end(), {f[0], f[1], f[2]});
                vertex_offsets[i + 1] = static_cast<std::int64_t>(vertices.size());
                face_offsets[i + 1] = static_cast<std::int64_t>(faces.size() / 3);
                for (size_t j = 0; j < ks; ++j) {
                    const auto& f = s.fits[j];
                    const size_t at = i * ks + j;
                    status[at] = static_cast<std::int8_t>(f.status);
                    for (int c = 0; c < 3; ++c) params[3 * at + c] = f.params[c];
                    double* pose = &poses[16 * at];
                    for (int r = 0; r < 3; ++r) {
                        for (int c = 0; c < 3; ++c) pose[4 * r + c] = f.rotation.m[r][c];
                        pose[4 * r + 3] = f.center[r];
                    }
                    pose[12] = pose[13] = pose[14] = 0.0;
                    pose[15] = 1.0;
                    volume[at] = f.volume;
                    excess[at] = f.excess;
                }
            }
            const size_t nv = vertices.size(), nf = faces.size() / 3;
            using O3 = nb::ndarray<nb::numpy, double, nb::shape<-1, -1, 3>, nb::c_contig>;
            using O44 = nb::ndarray<nb::numpy, double, nb::shape<-1, -1, 4, 4>, nb::c_contig>;
            auto* pv = new std::vector<double>(std::move(params));
            nb::capsule po(pv, [](void* p) noexcept { delete static_cast<std::vector<double>*>(p); });
            auto* qv = new std::vector<double>(std::move(poses));
            nb::capsule qo(qv, [](void* p) noexcept { delete static_cast<std::vector<double>*>(p); });
            if (pv->empty()) pv->reserve(1);
            if (qv->empty()) qv->reserve(1);
            const size_t pshape[3] = {hs, ks, 3}, qshape[4] = {hs, ks, 4, 4};
            return std::make_tuple(
                vector_array<Out<std::int8_t, -1>>(std::move(hull_status), hs, 0),
                vector_array<Out<std::int8_t, -1>>(std::move(dimension), hs, 0),
                vector_array<Out<double, -1>>(std::move(hull_volume), hs, 0),
                vector_array<Out<std::int64_t, -1>>(std::move(vertex_offsets), hs + 1, 0),
                vector_array<Out<std::int64_t, -1>>(std::move(vertices), nv, 0),
                vector_array<Out<std::int64_t, -1>>(std::move(face_offsets), hs + 1, 0),
                vector_array<Out<std::int64_t, -1, 3>>(std::move(faces), nf, 3),
                vector_array<Out<std::int8_t, -1, -1>>(std::move(status), hs, ks),
                O3(pv->data(), 3, pshape, po), O44(qv->data(), 4, qshape, qo),
                vector_array<Out<double, -1, -1>>(std::move(volume), hs, ks),
                vector_array<Out<double, -1, -1>>(std::move(excess), hs, ks));
        },
        "points"_a, "offsets"_a, "shapes"_a, "threads"_a = 0,
        "Enclosing primitives of H point sets (set h owns points[offsets[h]:offsets[h + 1]]), "
        "shapes (K,) codes (0 sphere, 1 capsule, 2 box, 3 cylinder, 4 ellipsoid): "
        "(hull_status (H,), dimension (H,), hull_volume (H,), hull_vertex_offsets (H + 1,), "
        "hull_vertices (V,) indices into each set, hull_face_offsets (H + 1,), hull_faces (F, 3) into each set's "
        "hull vertices, status (H, K), params (H, K, 3), poses (H, K, 4, 4), volume (H, K), "
        "excess (H, K)).");
}
