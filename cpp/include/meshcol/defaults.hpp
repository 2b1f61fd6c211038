#pragma once
/// Every default and cap of the core, in one place (as coal's narrowphase_defaults.h).
/// Exposed to Python as `meshcol._core.defaults`.

namespace meshcol::defaults {

/// Relative tolerance of pose rigidity checks (orthonormality, determinant, last row).
constexpr double rigid_tolerance = 1e-6;

/// Batches smaller than this run on the calling thread: starting threads costs more.
constexpr long long min_pairs_per_thread = 64;

/// Polytopes with more vertices than this use hill climbing on their hull adjacency (with a
/// warm start) for support points; smaller ones scan every vertex.
constexpr int hill_climbing_min_vertices = 32;

/// GJK iteration cap. Polytopes end exactly (a support point repeats) long before it.
constexpr int gjk_max_iterations = 128;

/// GJK stops when v.v - v.w <= tolerance * v.v: the distance is then within this relative
/// error (van den Bergen 2003). Curved shapes (cylinders) converge to it; polytopes end
/// exactly.
constexpr double gjk_relative_tolerance = 1e-13;

/// Two shapes closer than this times the pair's length scale (bounding radii plus centre
/// distance) touch: distance 0, `intersects` true.
constexpr double contact_tolerance = 1e-14;

/// EPA expansion cap (iterations) and polytope size cap (vertices).
constexpr int epa_max_iterations = 250;
constexpr int epa_max_vertices = 256;

/// EPA stops when the support along the closest face's normal is within this relative
/// distance of the face: the depth is then within this relative error.
constexpr double epa_relative_tolerance = 1e-12;

/// The same for pairs with a cylinder (spheres and capsules are exact: EPA runs on their
/// cores): EPA converges only slowly on smooth surfaces.
constexpr double epa_curved_relative_tolerance = 1e-7;

/// Exact SAT runs (to verify or replace EPA) when (candidate axes) x (vertices of both
/// shapes) is at most this: boxes and small hulls.
constexpr long long sat_max_work = 40000;

/// Broad phase: fewer boxes than this run on the calling thread.
constexpr long long broadphase_min_boxes_per_thread = 20000;

/// Sort and sweep: grid cells on the two cross axes are at least this many median box
/// extents wide (wider cells duplicate fewer boxes, narrower ones prune more).
constexpr double sweep_cell_extent_ratio = 2.0;

/// Sort and sweep: at most this many grid cells per cross axis.
constexpr int sweep_max_cells_per_axis = 1024;

/// Sort and sweep: at least this many boxes per grid cell on average.
constexpr long long sweep_min_boxes_per_cell = 16;

/// Sort and sweep: the grid is coarsened until it holds at most this many box entries per
/// box (a box spanning several cells is entered in each).
constexpr double sweep_max_entries_per_box = 3.0;

/// Sort and sweep: no grid when the sweep axis alone leaves fewer candidates per box.
constexpr double sweep_min_candidates_for_grid = 16.0;

/// Incremental sweep: a cell's insertion sort gives up and sorts the cell afresh after this many
/// element moves per entry (large motions are not "nearly sorted").
constexpr long long sweep_max_shifts_per_box = 32;

/// Incremental sweep: a step where more than this fraction of the boxes left the grid cells
/// they spanned rebuilds the grid and sorts afresh (the motion was not small).
constexpr double sweep_max_cell_changes = 0.25;

/// AABB tree: bins of the binned SAH top-down build (Wald 2007; Box2D v3).
constexpr int tree_bin_count = 32;

/// AABB tree: a node whose children's heights differ by more than this is rebalanced by
/// height even when the area heuristic would not rotate (guards degenerate inputs such as
/// many identical boxes, where every area is equal).
constexpr int tree_max_height_imbalance = 2;

/// AABB tree: most objects one tree holds (ids are 32-bit).
constexpr long long tree_max_objects = 1000000000;
/// Time of impact: default absolute contact distance (world units). The sweep command scales
/// it to the scene instead (1e-6 x the scene's bounding diagonal) unless `--tolerance` is given.
constexpr double toi_tolerance = 1e-6;

/// Time of impact: cap on ray-cast or conservative-advancement steps per pair. A pair that
/// reaches it is FAILED with its last safe lower bound.
constexpr int toi_max_iterations = 1000;

/// Most triangles in one leaf of a mesh hierarchy (MeshBvh).
constexpr int mesh_bvh_leaf_size = 4;

/// Bins per axis of the binned surface area heuristic that builds a MeshBvh.
constexpr int mesh_bvh_bins = 16;

/// Mesh pairs cost far more than convex pairs: fewer of them justify a thread.
constexpr long long mesh_min_pairs_per_thread = 4;

/// A point is inside a closed mesh when |generalized winding number| >= this (Jacobson et al.
/// 2013): 1 inside, 0 outside, fractional near holes in the surface.
constexpr double winding_number_inside = 0.5;

}  // namespace meshcol::defaults
