#pragma once
/// Every default and cap of the core, in one place (as coal's narrowphase_defaults.h).
/// Exposed to Python as `meshcol._core.defaults`.

namespace meshcol::defaults {

/// Relative tolerance of pose rigidity checks (orthonormality, determinant, last row).
constexpr double rigid_tolerance = 1e-6;

/// Batches smaller than this run on the calling thread: starting threads costs more.
constexpr long long min_pairs_per_thread = 64;

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
