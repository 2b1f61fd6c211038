// Exposes manifest_read.hpp: a plain JSON manifest of mesh and primitive bodies read into
// columns.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "meshcol/manifest_read.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using Codes = Out<std::int8_t, -1>;
using Rows3 = Out<double, -1, 3>;
using Rows4 = Out<double, -1, 4>;

std::optional<nb::dict> read_manifest(nb::bytes data, std::vector<std::string> types,
                         std::vector<int> type_fields, std::vector<std::string> orders,
                         std::vector<std::string> shapes) {
    const meshcol::ManifestWords words{std::move(types), std::move(type_fields),
                                       std::move(orders), std::move(shapes)};
    const std::string_view text(data.c_str(), data.size());
    meshcol::ManifestColumns found;
    {
        nb::gil_scoped_release release;
        found = meshcol::read_plain_manifest(text, words);
    }
    if (!found.plain) return std::nullopt;
    const size_t n = found.names.size();
    nb::list names;
    for (const std::string_view name : found.names) names.append(nb::str(name.data(), name.size()));
    nb::object meshes = nb::none();  // no mesh body: None, not n of them
    if (found.mesh_count > 0) {
        nb::list listed;
        for (const std::string_view mesh : found.meshes)
            listed.append(mesh.empty() ? nb::object(nb::none())
                                       : nb::object(nb::str(mesh.data(), mesh.size())));
        meshes = listed;
    }
    nb::dict out;
    out["names"] = names;
    out["meshes"] = meshes;
    out["units"] = found.has_units ? nb::object(nb::str(found.units.data(), found.units.size()))
                                   : nb::none();
    out["duration"] = found.has_duration
                          ? nb::object(nb::str(found.duration.data(), found.duration.size()))
                          : nb::none();
    const size_t nq = found.quaternions.size() / 4, ne = found.euler.size() / 3;
    out["kinds"] = vector_array<Codes>(std::move(found.kinds), n, 0);
    out["lengths"] = vector_array<Rows3>(std::move(found.lengths), n, 3);
    out["positions"] = vector_array<Rows3>(std::move(found.positions), n, 3);
    out["position_count"] = found.position_count;
    out["rotation"] = vector_array<Codes>(std::move(found.rotation), n, 0);
    out["quaternions"] = vector_array<Rows4>(std::move(found.quaternions), nq, 4);
    out["euler"] = vector_array<Rows3>(std::move(found.euler), ne, 3);
    out["orders"] = vector_array<Codes>(std::move(found.orders), ne, 0);
    out["shapes"] = vector_array<Codes>(std::move(found.shapes), n, 0);
    return out;
}

}  // namespace

void bind_manifest(nb::module_& m) {
    m.def("read_plain_manifest", &read_manifest, "data"_a, "types"_a, "type_fields"_a,
          "orders"_a, "shapes"_a,
          "Reads a plain JSON manifest of static mesh and primitive bodies into columns; None "
          "for any other document (Python's reader decides). Returns a dict: names (list of "
          "str), meshes (list of str, None for a primitive body; None when no body has a "
          "mesh), units and duration (str as written, or None), kinds (int8: index into types, "
          "-1 for a mesh body), rotation and shapes (int8 codes, shapes indexing shapes with "
          "-1 where absent), lengths (zeros for a mesh body) and positions (N, 3), "
          "position_count, quaternions (NQ, 4), euler (NE, 3) and orders (NE,) of the bodies "
          "so rotated, in order. type_fields: per type, its fields besides type (bits: 1 "
          "radius, 2 length, 4 size, 8 semi_axes).");
}
