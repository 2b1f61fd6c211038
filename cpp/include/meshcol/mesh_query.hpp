#pragma once
/// Exact queries between two posed triangle meshes: minimum distance with closest points,
/// intersection, and containment (one mesh inside the other).

#include <cstdint>
#include <limits>

#include "meshcol/mesh_bvh.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// Two meshes, their poses and the query options.
struct MeshDistanceInput {
    const MeshBvh* a = nullptr;  ///< first mesh (local frame)
    const MeshBvh* b = nullptr;  ///< second mesh (local frame)
    Pose pose_a;                 ///< world from a's local frame, rigid
    Pose pose_b;                 ///< world from b's local frame, rigid
    /// Only distances <= max_distance are resolved; a pair farther apart reports
    /// `distance = inf` (and NaN points) without finding its closest points. Must be >= 0.
    double max_distance = std::numeric_limits<double>::infinity();
};

/// Result of `mesh_distance`.
struct MeshDistanceOutput {
    double distance = 0.0;  ///< >= 0; 0 when intersecting; inf when > max_distance; NaN when invalid
    Vec3 point_a;           ///< closest point on a, world frame (a shared point when intersecting)
    Vec3 point_b;           ///< closest point on b, world frame (equals point_a when intersecting)
    bool intersecting = false;  ///< the surfaces share a point (touching counts)
    /// a lies inside b: the surfaces do not intersect and a vertex of a has
    /// |winding number| >= defaults::winding_number_inside w.r.t. b. Meaningful for closed b.
    bool a_inside_b = false;
    bool b_inside_a = false;        ///< as a_inside_b, with a and b swapped
    std::int64_t triangle_a = -1;   ///< input face of a holding point_a, -1 when not found
    std::int64_t triangle_b = -1;   ///< input face of b holding point_b, -1 when not found
    Status status = Status::NOT_RUN;  ///< CONVERGED; INVALID_INPUT for an invalid mesh;
                                      ///< OUT_OF_RANGE (NaN fields) outside `mesh_pair_in_range`
};

/// Whether the lengths of a mesh pair (the centre distance and the meshes' reach about their
/// origins) are within [2^-100, 2^100], where the float boxes and the squared distances of the
/// search are exact enough. Pairs outside get Status::OUT_OF_RANGE, never a number.
bool mesh_pair_in_range(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b);

/// Minimum distance between the surfaces of two meshes by simultaneous descent of their
/// hierarchies, closer child first, pruning node pairs whose box distance is no less than the
/// best distance found (branch and bound, as Larsen et al. 1999 and FCL's mesh distance), exact
/// triangle-pair distance at the leaves; stops at the first intersecting triangle pair. Then,
/// when the surfaces do not intersect, tests containment with the generalized winding number.
/// The caller checks that poses are rigid.
MeshDistanceOutput mesh_distance(const MeshDistanceInput& input);

/// Whether the surfaces intersect (touching counts): descends only overlapping boxes, stops at
/// the first intersecting triangle pair. Both meshes must be valid.
bool mesh_intersects(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b);

/// Closest point of a mesh's surface to a point.
struct PointDistanceOutput {
    double distance = 0.0;       ///< >= 0; NaN when the point or the mesh is invalid
    Vec3 point;                  ///< closest surface point, mesh local frame (NaN when invalid)
    std::int64_t triangle = -1;  ///< input face holding `point`, -1 when invalid
};

/// Exact distance from `point` (mesh local frame) to the mesh's surface: depth-first branch and
/// bound over the hierarchy, closer child first, pruning boxes no closer than the best
/// distance found, exact point-triangle distance at the leaves (Ericson 2004, 5.1.5).
/// A non-finite point or an invalid mesh gives NaN.
PointDistanceOutput closest_point(const MeshBvh& mesh, const Vec3& point);

/// Generalized winding number of `point` (mesh's local frame) w.r.t. the mesh: the sum of the
/// signed solid angles of its triangles over 4 pi (Jacobson et al. 2013; solid angles by van
/// Oosterom and Strackee 1983). 1 inside a closed outward-wound mesh, 0 outside, -1 inside an
/// inward-wound one. Undefined on the surface.
double winding_number(const MeshBvh& mesh, const Vec3& point);

}  // namespace meshcol
