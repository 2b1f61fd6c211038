// Exposes defaults.hpp and the thread helpers.
#include <nanobind/nanobind.h>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"

namespace nb = nanobind;

void bind_defaults(nb::module_& m) {
    nb::module_ d = m.def_submodule("defaults", "Defaults and caps of the core (cpp/include/meshcol/defaults.hpp).");
    d.attr("rigid_tolerance") = meshcol::defaults::rigid_tolerance;
    d.attr("min_pairs_per_thread") = meshcol::defaults::min_pairs_per_thread;
    d.attr("hill_climbing_min_vertices") = meshcol::defaults::hill_climbing_min_vertices;
    d.attr("gjk_max_iterations") = meshcol::defaults::gjk_max_iterations;
    d.attr("gjk_relative_tolerance") = meshcol::defaults::gjk_relative_tolerance;
    d.attr("contact_tolerance") = meshcol::defaults::contact_tolerance;
    d.attr("epa_max_iterations") = meshcol::defaults::epa_max_iterations;
    d.attr("epa_max_vertices") = meshcol::defaults::epa_max_vertices;
    d.attr("epa_relative_tolerance") = meshcol::defaults::epa_relative_tolerance;
    d.attr("epa_curved_relative_tolerance") = meshcol::defaults::epa_curved_relative_tolerance;
    d.attr("sat_max_work") = meshcol::defaults::sat_max_work;
    d.attr("broadphase_min_boxes_per_thread") = meshcol::defaults::broadphase_min_boxes_per_thread;
    d.attr("sweep_cell_extent_ratio") = meshcol::defaults::sweep_cell_extent_ratio;
    d.attr("sweep_max_cells_per_axis") = meshcol::defaults::sweep_max_cells_per_axis;
    d.attr("sweep_min_boxes_per_cell") = meshcol::defaults::sweep_min_boxes_per_cell;
    d.attr("sweep_max_entries_per_box") = meshcol::defaults::sweep_max_entries_per_box;
    d.attr("sweep_min_candidates_for_grid") = meshcol::defaults::sweep_min_candidates_for_grid;
    d.attr("sweep_max_shifts_per_box") = meshcol::defaults::sweep_max_shifts_per_box;
    d.attr("sweep_max_cell_changes") = meshcol::defaults::sweep_max_cell_changes;
    d.attr("tree_bin_count") = meshcol::defaults::tree_bin_count;
    d.attr("tree_max_height_imbalance") = meshcol::defaults::tree_max_height_imbalance;
    d.attr("tree_max_objects") = meshcol::defaults::tree_max_objects;
    d.attr("toi_tolerance") = meshcol::defaults::toi_tolerance;
    d.attr("toi_max_iterations") = meshcol::defaults::toi_max_iterations;
    d.attr("mesh_bvh_leaf_size") = meshcol::defaults::mesh_bvh_leaf_size;
    d.attr("mesh_bvh_bins") = meshcol::defaults::mesh_bvh_bins;
    d.attr("mesh_min_pairs_per_thread") = meshcol::defaults::mesh_min_pairs_per_thread;
    d.attr("winding_number_inside") = meshcol::defaults::winding_number_inside;
    m.def("hardware_threads", &meshcol::hardware_threads, "Number of hardware threads (at least 1).");
}
