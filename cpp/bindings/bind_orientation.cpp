// Binds orientation.hpp: orient_faces (meshcol.geometry.topology.orient_consistently) and the
// exact ray_parity (meshcol.geometry.ray_parity). The Python wrappers check shapes first with
// friendly messages; these check the indices.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "meshcol/orientation.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

void check_faces(const Points& vertices, const Faces& faces) {
    const auto n = static_cast<std::int64_t>(vertices.shape(0));
    const std::int64_t* f = faces.data();
    for (std::int64_t k = 0; k < 3 * static_cast<std::int64_t>(faces.shape(0)); ++k)
        if (f[k] < 0 || f[k] >= n)
            throw std::invalid_argument("face " + std::to_string(k / 3) + " has vertex index " +
                                        std::to_string(f[k]) + " out of range [0, " +
                                        std::to_string(n) + ")");
}

}  // namespace

void bind_orientation(nb::module_& m) {
    m.def(
        "ray_parity",
        [](const Points& vertices, const Faces& faces, const Points& points) {
            check_faces(vertices, faces);
            const size_t n = points.shape(0);
            auto out = new_array<Out<std::int8_t, -1>>({n});
            {
                nb::gil_scoped_release release;
                meshcol::ray_parity(vertices.data(), static_cast<std::int64_t>(vertices.shape(0)),
                                    faces.data(), static_cast<std::int64_t>(faces.shape(0)),
                                    points.data(), static_cast<std::int64_t>(n),
                                    reinterpret_cast<meshcol::Parity*>(out.data()));
            }
            return out;
        },
        "vertices"_a, "faces"_a, "points"_a,
        "Per point (N,) int8: 1 inside, 0 outside by the even-odd rule (exact), -1 undecided "
        "(on the surface, or the faces are not closed modulo 2).");
    m.def(
        "orient_faces",
        [](const Points& vertices, const Faces& faces, int nesting_max_components,
           double flat_volume) {
            check_faces(vertices, faces);
            meshcol::FaceOrientation found;
            {
                nb::gil_scoped_release release;
                found = meshcol::orient_faces(vertices.data(),
                                              static_cast<std::int64_t>(vertices.shape(0)),
                                              faces.data(), static_cast<std::int64_t>(faces.shape(0)),
                                              nesting_max_components, flat_volume);
            }
            const size_t k = found.flipped.size();
            auto flipped = new_array<Out<bool, -1>>({k});
            if (k > 0) std::memcpy(flipped.data(), found.flipped.data(), k);
            return std::make_tuple(flipped, found.orientable, found.balanced);
        },
        "vertices"_a, "faces"_a, "nesting_max_components"_a, "flat_volume"_a,
        "(flipped (M,) bool, orientable, balanced): each component wound consistently, closed "
        "ones outward (inward for a cavity's wall).");
}
