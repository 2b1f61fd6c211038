// Exposes triangulate.hpp: polygon faces split into triangles, a whole mesh per call.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "meshcol/triangulate.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

auto triangulate(Points vertices, Index64 counts, Index64 indices, Index64 holes, bool reverse,
                 std::int64_t max_triangles) {
    meshcol::PolygonMesh mesh{vertices.data(), vertices.shape(0), counts.data(), counts.shape(0),
                              indices.data(), indices.shape(0)};
    meshcol::TriangulateOptions options;
    options.holes.assign(holes.data(), holes.data() + holes.shape(0));
    options.reverse = reverse;
    options.max_triangles = max_triangles;
    std::vector<std::int64_t> faces;
    {
        nb::gil_scoped_release release;
        faces = meshcol::triangulate_polygons(mesh, options);
    }
    const size_t rows = faces.size() / 3;
    return vector_array<Out<std::int64_t, -1, 3>>(std::move(faces), rows, 3);
}

}  // namespace

void bind_triangulate(nb::module_& m) {
    m.def("triangulate_polygons", &triangulate, "vertices"_a, "counts"_a, "indices"_a, "holes"_a,
          "reverse"_a = false, "max_triangles"_a = -1,
          "Splits polygon faces (counts (F,) corners each, indices (sum(counts),) into vertices "
          "(V, 3)) into triangles (T, 3) int64 in face order: convex faces fanned from their first "
          "corner, others ear clipped in the plane of their Newell normal. Faces of fewer than 3 "
          "corners and the faces in holes give none; reverse flips each triangle's winding. "
          "Raises ValueError on a negative count, counts not adding up to len(indices), an index "
          "out of range, or more than max_triangles (>= 0) triangles.");
}
