// Exposes defaults.hpp, the status enums (status.hpp, shapes.hpp) and the thread helpers.
#include <nanobind/nanobind.h>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"

namespace nb = nanobind;

namespace {
// The namespace meshcol._core.defaults: a class holding the constants as class attributes,
// not a submodule, so that the stub of meshcol._core (nanobind's stubgen, one file) types
// each of them.
struct Defaults {};
}  // namespace

void bind_defaults(nb::module_& m) {
    namespace d = meshcol::defaults;
    nb::class_<Defaults> s(m, "defaults",
                           "Defaults and caps of the core (cpp/include/meshcol/defaults.hpp).");
    s.attr("rigid_tolerance") = d::rigid_tolerance;
    s.attr("min_pairs_per_thread") = d::min_pairs_per_thread;
    s.attr("min_shapes_per_thread") = d::min_shapes_per_thread;
    s.attr("min_points_per_thread") = d::min_points_per_thread;
    s.attr("triangle_min_pairs_per_thread") = d::triangle_min_pairs_per_thread;
    s.attr("hill_climbing_min_vertices") = d::hill_climbing_min_vertices;
    s.attr("gjk_max_iterations") = d::gjk_max_iterations;
    s.attr("support_warm_start_min_cosine") = d::support_warm_start_min_cosine;
    s.attr("gjk_flat_tetrahedron_volume") = d::gjk_flat_tetrahedron_volume;
    s.attr("gjk_relative_tolerance") = d::gjk_relative_tolerance;
    s.attr("contact_tolerance") = d::contact_tolerance;
    s.attr("epa_max_iterations") = d::epa_max_iterations;
    s.attr("epa_max_vertices") = d::epa_max_vertices;
    s.attr("epa_relative_tolerance") = d::epa_relative_tolerance;
    s.attr("epa_absolute_tolerance_ratio") = d::epa_absolute_tolerance_ratio;
    s.attr("epa_min_squared_length") = d::epa_min_squared_length;
    s.attr("epa_curved_relative_tolerance") = d::epa_curved_relative_tolerance;
    s.attr("sat_max_work") = d::sat_max_work;
    s.attr("sat_parallel_edge_sine") = d::sat_parallel_edge_sine;
    s.attr("sat_agreement_relative_depth") = d::sat_agreement_relative_depth;
    s.attr("sat_agreement_normal_cosine") = d::sat_agreement_normal_cosine;
    s.attr("broadphase_min_boxes_per_thread") = d::broadphase_min_boxes_per_thread;
    s.attr("sort_and_sweep_cell_extent_ratio") = d::sort_and_sweep_cell_extent_ratio;
    s.attr("sort_and_sweep_max_cells_per_axis") = d::sort_and_sweep_max_cells_per_axis;
    s.attr("sort_and_sweep_min_boxes_per_cell") = d::sort_and_sweep_min_boxes_per_cell;
    s.attr("sort_and_sweep_max_entries_per_box") = d::sort_and_sweep_max_entries_per_box;
    s.attr("sort_and_sweep_min_candidates_for_grid") = d::sort_and_sweep_min_candidates_for_grid;
    s.attr("sort_and_sweep_max_shifts_per_box") = d::sort_and_sweep_max_shifts_per_box;
    s.attr("sort_and_sweep_max_cell_changes") = d::sort_and_sweep_max_cell_changes;
    s.attr("tree_bin_count") = d::tree_bin_count;
    s.attr("tree_max_height_imbalance") = d::tree_max_height_imbalance;
    s.attr("tree_max_objects") = d::tree_max_objects;
    s.attr("toi_tolerance") = d::toi_tolerance;
    s.attr("toi_max_iterations") = d::toi_max_iterations;
    s.attr("toi_min_pairs_per_thread") = d::toi_min_pairs_per_thread;
    s.attr("mesh_bvh_leaf_size") = d::mesh_bvh_leaf_size;
    s.attr("mesh_bvh_bins") = d::mesh_bvh_bins;
    s.attr("mesh_min_pairs_per_thread") = d::mesh_min_pairs_per_thread;
    s.attr("winding_number_inside") = d::winding_number_inside;
    s.attr("mesh_depth_max_work") = d::mesh_depth_max_work;
    m.def("hardware_threads", &meshcol::hardware_threads,
          "Number of hardware threads (at least 1).");

    // The enums the Python ones in meshcol/types.py and meshcol/collision/shapes.py mirror
    // (tests/test_native.py checks they match).
    nb::enum_<meshcol::Status>(m, "Status", "Outcome of a pair query (status.hpp).")
        .value("CONVERGED", meshcol::Status::CONVERGED)
        .value("MAX_ITERATIONS", meshcol::Status::MAX_ITERATIONS)
        .value("DEGENERATE", meshcol::Status::DEGENERATE)
        .value("INVALID_INPUT", meshcol::Status::INVALID_INPUT)
        .value("NOT_RUN", meshcol::Status::NOT_RUN)
        .value("OUT_OF_RANGE", meshcol::Status::OUT_OF_RANGE);
    using T = meshcol::TimeOfImpactStatus;
    nb::enum_<T>(m, "TimeOfImpactStatus", "Outcome of a time-of-impact query (status.hpp).")
        .value("HIT", T::HIT)
        .value("SEPARATED", T::SEPARATED)
        .value("OVERLAPPED_AT_START", T::OVERLAPPED_AT_START)
        .value("FAILED", T::FAILED)
        .value("INVALID_INPUT", T::INVALID_INPUT);
    using K = meshcol::ShapeKind;
    nb::enum_<K>(m, "ShapeKind", "Kind of a packed convex shape (shapes.hpp).")
        .value("POLYTOPE", K::POLYTOPE)
        .value("SPHERE", K::SPHERE)
        .value("BOX", K::BOX)
        .value("CAPSULE", K::CAPSULE)
        .value("CYLINDER", K::CYLINDER);
}
