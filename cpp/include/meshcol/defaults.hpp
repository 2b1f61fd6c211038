#pragma once
/// Every default and cap of the core, in one place (as coal's narrowphase_defaults.h).
/// Exposed to Python as `meshcol._core.defaults`.

namespace meshcol::defaults {

/// Relative tolerance of pose rigidity checks (orthonormality, determinant, last row).
constexpr double rigid_tolerance = 1e-6;

/// Batches smaller than this run on the calling thread: starting threads costs more.
constexpr long long min_pairs_per_thread = 64;

/// AABBs and bounding radii of fewer shapes than this per thread run on the calling thread:
/// one shape costs about as little as one pair does, so more of them justify a thread.
constexpr long long min_shapes_per_thread = 256;

/// Point queries on a mesh (closest points): fewer points than this per thread run on the
/// calling thread (one point visits a few leaves, a fraction of a mesh pair's work).
constexpr long long min_points_per_thread = 64;

/// Exact triangle-pair crossing tests (self-intersections): fewer pairs than this per thread
/// run on the calling thread (a pair costs tens of nanoseconds, a thread far more).
constexpr long long triangle_min_pairs_per_thread = 4096;

/// Polytopes with more vertices than this use hill climbing on their hull adjacency (with a
/// warm start) for support points; smaller ones scan every vertex.
constexpr int hill_climbing_min_vertices = 32;

/// GJK iteration cap. Polytopes end exactly (a support point repeats) long before it.
constexpr int gjk_max_iterations = 128;

/// GJK (and EPA) support climbs start from the previous support points when the search
/// direction turned by less than the angle of this cosine (60 degrees) since the last call,
/// else from a few strided samples: a small turn keeps the previous vertex near the answer.
constexpr double support_warm_start_min_cosine = 0.5;

/// GJK treats a tetrahedron as flat when its volume is at most this times the cube of its
/// longest edge from the first vertex: about 100 ulps of relative rounding, below which the
/// face-side signs of the origin are noise.
constexpr double gjk_flat_tetrahedron_volume = 1e-14;

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

/// EPA also stops when that gap is within this fraction of the contact distance (contact
/// tolerance times the pair scale): an absolute floor for depths near zero, where the relative
/// test alone cannot be met.
constexpr double epa_absolute_tolerance_ratio = 1e-2;

/// Smallest squared edge length EPA divides by when it orients the normal of a flat
/// Minkowski difference (guards a division by zero; far below any real length squared).
constexpr double epa_min_squared_length = 1e-300;

/// The same for pairs with a cylinder (spheres and capsules are exact: EPA runs on their
/// cores): EPA converges only slowly on smooth surfaces.
constexpr double epa_curved_relative_tolerance = 1e-7;

/// Exact SAT runs (to verify or replace EPA) when (candidate axes) x (vertices of both
/// shapes) is at most this: boxes and small hulls.
constexpr long long sat_max_work = 40000;

/// SAT skips the cross product of two edge directions whose sine (the norm of the cross
/// product of unit vectors) is at most this: parallel edges span no face of their own, the
/// face normals cover them, and a normalised near-zero cross product is noise.
constexpr double sat_parallel_edge_sine = 1e-9;

/// EPA's depth agrees with exact SAT when they differ by at most this times the SAT depth
/// (or the contact distance, for shallow pairs); else SAT's depth and axis are taken. Loose
/// against EPA's 1e-12 tolerance so agreeing answers are never replaced for rounding.
constexpr double sat_agreement_relative_depth = 1e-9;

/// ... and their normals agree when 1 - cos(angle between them) is at most this (an angle of
/// about 4.5e-5 radians).
constexpr double sat_agreement_normal_cosine = 1e-9;

/// Broad phase: fewer boxes than this run on the calling thread.
constexpr long long broadphase_min_boxes_per_thread = 20000;

/// Sort and sweep: grid cells on the two cross axes are at least this many median box
/// extents wide (wider cells duplicate fewer boxes, narrower ones prune more).
constexpr double sort_and_sweep_cell_extent_ratio = 2.0;

/// Sort and sweep: at most this many grid cells per cross axis.
constexpr int sort_and_sweep_max_cells_per_axis = 1024;

/// Sort and sweep: at least this many boxes per grid cell on average.
constexpr long long sort_and_sweep_min_boxes_per_cell = 16;

/// Sort and sweep: the grid is coarsened until it holds at most this many box entries per
/// box (a box spanning several cells is entered in each).
constexpr double sort_and_sweep_max_entries_per_box = 3.0;

/// Sort and sweep: no grid when the sweep axis alone leaves fewer candidates per box.
constexpr double sort_and_sweep_min_candidates_for_grid = 16.0;

/// Incremental sort and sweep: a cell's insertion sort gives up and sorts the cell afresh after
/// this many element moves per entry (large motions are not "nearly sorted").
constexpr long long sort_and_sweep_max_shifts_per_box = 32;

/// Incremental sort and sweep: a step where more than this fraction of the boxes left the grid
/// cells they spanned rebuilds the grid and sorts afresh (the motion was not small).
constexpr double sort_and_sweep_max_cell_changes = 0.25;

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

/// Time of impact: fewer pairs than this per thread run on the calling thread. Advancement
/// can take many GJK calls per pair, so small chunks balance better than for static pairs.
constexpr long long toi_min_pairs_per_thread = 8;

/// Most triangles in one leaf of a mesh hierarchy (MeshBvh).
constexpr int mesh_bvh_leaf_size = 4;

/// Bins per axis of the binned surface area heuristic that builds a MeshBvh.
constexpr int mesh_bvh_bins = 16;

/// Mesh pairs cost far more than convex pairs: fewer of them justify a thread.
constexpr long long mesh_min_pairs_per_thread = 4;

/// A point is inside a closed mesh when |generalized winding number| >= this (Jacobson et al.
/// 2013): 1 inside, 0 outside, fractional near holes in the surface.
constexpr double winding_number_inside = 0.5;

/// Mesh penetration depth: most triangle visits spent on winding numbers for one pair (about
/// a second of work). A pair that reaches it is MAX_ITERATIONS with the depth of the points
/// decided so far (still a lower bound of the minimum translation distance).
constexpr long long mesh_depth_max_work = 200000000;

/// The flatness rule: points are flat (coplanar), collinear or one point when their width
/// across their best-fit plane (line) is at most this fraction of their bounding-box
/// diagonal (mirrored by `meshcol.collision.hull.FLAT_RELATIVE_TOLERANCE`).
constexpr double flat_relative_tolerance = 1e-9;

/// Quickhull's plane thickness, times the largest absolute coordinate: a point closer than
/// that to a face's plane is on it (about 45 ulps, the rounding of a plane distance; qhull's
/// coplanar tolerance is of the same order).
constexpr double hull_relative_tolerance = 1e-14;

/// Hulls of coordinates beyond this magnitude are refused (status OVERFLOW): their volumes
/// (products of three coordinates) and face normals' lengths would overflow doubles.
constexpr double hull_max_abs_coordinate = 1e100;

/// Quickhull reruns on the extreme vertices when a vertex turned out to lie on an edge or in
/// a face of its hull (coplanar ties); at most this many times.
constexpr int hull_max_reruns = 3;

/// A rerun checks that each vertex it leaves out is still inside (a point-plane test against
/// every face): it runs only while that costs at most this many tests.
constexpr double hull_max_rerun_work = 5e7;

/// Shapes per thread below which hull packing stays on the calling thread.
constexpr long long hull_min_shapes_per_thread = 16;
/// Points per thread below which the interior filter of one large hull input stays on the
/// calling thread (a million-point scan takes about 0.3 s; a thread costs about 50 us).
constexpr long long hull_min_filter_points_per_thread = 131072;

}  // namespace meshcol::defaults
