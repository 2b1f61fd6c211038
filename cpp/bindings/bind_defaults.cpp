// Exposes defaults.hpp and the thread helpers.
#include <nanobind/nanobind.h>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"

namespace nb = nanobind;

void bind_defaults(nb::module_& m) {
    nb::module_ d = m.def_submodule("defaults", "Defaults and caps of the core (cpp/include/meshcol/defaults.hpp).");
    d.attr("rigid_tolerance") = meshcol::defaults::rigid_tolerance;
    d.attr("min_pairs_per_thread") = meshcol::defaults::min_pairs_per_thread;
    d.attr("mesh_bvh_leaf_size") = meshcol::defaults::mesh_bvh_leaf_size;
    d.attr("mesh_bvh_bins") = meshcol::defaults::mesh_bvh_bins;
    d.attr("mesh_min_pairs_per_thread") = meshcol::defaults::mesh_min_pairs_per_thread;
    d.attr("winding_number_inside") = meshcol::defaults::winding_number_inside;
    m.def("hardware_threads", &meshcol::hardware_threads, "Number of hardware threads (at least 1).");
}
