#pragma once
/// Exact queries between two posed triangle meshes: minimum distance with closest points,
/// intersection, containment (one mesh inside the other), and a penetration depth that never
/// exceeds the minimum translation distance; and queries of one mesh: a point's closest
/// surface point, winding numbers, a ray's first hit. By concept in src/: mesh_distance.cpp,
/// mesh_intersection.cpp, mesh_winding.cpp, mesh_depth.cpp (+ mesh_depth_closed.cpp),
/// mesh_ray_cast.cpp.

#include <cstdint>
#include <limits>
#include <vector>

#include "meshcol/defaults.hpp"
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

/// Minimum distance between the surfaces of two meshes. First the intersection descent (as
/// mesh_intersects) looks for a crossing triangle pair. Without one, a pair whose hulls are
/// apart and whose hulls' closest points lie on the meshes is tried along the direction of the
/// hulls' distance (GJK on the vertices): only the triangles near each mesh's supporting plane
/// can beat the best pair found there, and when the bound proves it no other pair is measured.
/// Otherwise (or when that bound cannot decide), a simultaneous descent of
/// the hierarchies, nearest node pair first, prunes node pairs whose oriented-box distance
/// bound is no less than the best distance found (branch and bound, as Larsen et al. 1999 and
/// FCL's mesh distance), exact triangle-pair distance at the leaves. The distance is the
/// smallest triangle-pair distance bit for bit; of pairs tied at it, which one reports the
/// triangles and points is the search's choice. Then, when the surfaces do not
/// intersect, tests containment with the generalized winding number (winding_number_inside).
/// The caller checks that poses are rigid.
MeshDistanceOutput mesh_distance(const MeshDistanceInput& input);

/// Result of `mesh_penetration_depth`.
struct MeshDepthOutput {
    /// >= 0: the largest distance, to the other surface, of a sampled point of one mesh that
    /// lies inside the other (|winding number| >= defaults::winding_number_inside); 0 when no
    /// sampled point lies strictly inside. For closed meshes a lower bound of the minimum
    /// translation distance that separates them: a translation shorter than it leaves that
    /// point inside. NaN when invalid.
    double depth = 0.0;
    Vec3 point_a;  ///< world: the deepest point when it is a's, else its closest point on a
    Vec3 point_b;  ///< world: the deepest point when it is b's, else its closest point on b
    /// World unit vector from a towards b along which b leaves the deepest point behind
    /// (point_b - point_a = -depth * normal); NaN when depth is 0, a unit vector whenever it
    /// is not (also when a depth below the pose's rounding maps both points to one). A hint,
    /// not a guarantee that moving b by depth along it separates a non-convex pair.
    Vec3 normal;
    int deepest_mesh = -1;  ///< 0: the deepest point is a's (inside b); 1: b's; -1: none
    /// exact inside tests run. Closed other mesh: one per region of points and one per point
    /// measured deeper than the best depth found, unless a point tested before decides it
    /// (one nearer to it than that point is to the surface). Otherwise one per point.
    std::int64_t points_tested = 0;
    Status status = Status::NOT_RUN;  ///< CONVERGED, MAX_ITERATIONS (work cap), INVALID_INPUT
};

/// Penetration depth of two posed meshes, as a lower bound of the minimum translation
/// distance (the depth of `MeshDepthOutput`). The sampled points of each mesh are its vertices
/// and, on every edge of a triangle that crosses the other surface, the midpoints of the
/// pieces between consecutive crossings (so an edge through a thin wall counts even when both
/// its vertices are outside), and points stepped into the wedges of crossing triangle pairs.
/// Each point's distance to the other surface comes from that mesh's hierarchy
/// (`closest_point`). When the other mesh is closed, its points are decided by regions (the
/// vertices joined by edges of triangles clear of the other surface share a side, so one exact
/// ray-crossing test decides each region) and the largest distance is found by branch and
/// bound over the hierarchies (a node's corners are no farther than its centre's distance plus
/// its radius), so that most points are neither tested nor measured. Otherwise (an open or
/// non-manifold other mesh) points are decided deepest first by the generalized winding
/// number, until the first inside one; a point found outside proves every point closer to it
/// than its distance outside too. Either way the depth is the same maximum over the same
/// points. Pairs whose surfaces are disjoint still get the depth of the deepest vertex inside
/// (containment).
MeshDepthOutput mesh_penetration_depth(const MeshDistanceInput& input);

/// Two meshes, their poses and the options of `mesh_contacts`.
struct MeshContactsInput {
    const MeshBvh* a = nullptr;  ///< first mesh (local frame)
    const MeshBvh* b = nullptr;  ///< second mesh (local frame)
    Pose pose_a;                 ///< world from a's local frame, rigid
    Pose pose_b;                 ///< world from b's local frame, rigid
    /// Every contact is listed (in `contacts`, when given) up to this many, >= 0; the count
    /// and the deepest contact are over all crossing pairs whatever it is.
    std::int64_t max_contacts = 0;
    /// Work cap: triangle pairs whose boxes touch (each tested exactly; those the descent
    /// reaches, all of them when the two rotations are equal), >= 0; past it the pair is
    /// MAX_ITERATIONS.
    long long max_work = defaults::mesh_contacts_max_work;
};

/// One crossing triangle pair and its own penetration (`triangle_penetration`), world frame.
struct MeshContact {
    double depth = 0.0;  ///< >= 0: the minimum translation that separates the two triangles
    /// World unit vector from a towards b: moving b by depth along it separates the two
    /// triangles (NaN only for two triangles degenerate to parallel segments or points)
    Vec3 normal;
    /// world: midway between the witness points of the pair (`triangle_penetration_points`:
    /// on the features the depth's axis names, a corner and its foot on a face or two edges'
    /// closest points). A touching pair (depth 0): the point the exact triangle test found the
    /// two share where the descent ran that test (a corner of one on the other's plane, save
    /// where one lies in a coordinate plane that the other only touches), else midway between
    /// the closest points of the features its axis names when they are within 1e-12 of the
    /// largest coordinate (`triangle_penetration_points`), else a shared point
    Vec3 point;
    /// >= 0: how far b's triangle reaches behind a's triangle's face, along a's unit face
    /// normal (p1 - p0) x (p2 - p0): max over b's corners q of n . (a's p0 - q). A translation
    /// that separates the two triangles (b moved by it along a's normal), not the shortest:
    /// the per-pair penetration_depth coal 3.0.3's mesh collide reports (measured on every
    /// contact of bench_mesh_query.py's depth rows, with a's face normal as its normal).
    /// 0 for a degenerate triangle of a.
    double face_depth = 0.0;
    std::int64_t triangle_a = -1;  ///< input face of a
    std::int64_t triangle_b = -1;  ///< input face of b
};

/// Result of `mesh_contacts`.
struct MeshContactsOutput {
    /// Crossing triangle pairs (the closed triangles share a point, touching counts), >= 0;
    /// with MAX_ITERATIONS, those found before the work cap (a lower bound).
    std::int64_t count = 0;
    /// The deepest crossing pair's penetration, >= 0 (ties: the lowest triangle_a, then
    /// triangle_b); 0 with NaN normal and point and -1 triangles when count is 0; NaN when
    /// invalid or out of range.
    double depth = 0.0;
    Vec3 normal;                   ///< as MeshContact::normal, of the deepest pair
    Vec3 point;                    ///< as MeshContact::point, of the deepest pair
    /// The largest MeshContact::face_depth over the crossing pairs (coal's deepest contact),
    /// 0 when count is 0, NaN when invalid or out of range.
    double face_depth = 0.0;
    std::int64_t triangle_a = -1;  ///< input face of a of the deepest pair, -1 when none
    std::int64_t triangle_b = -1;  ///< input face of b of the deepest pair, -1 when none
    /// CONVERGED; MAX_ITERATIONS when the triangle pairs whose boxes touch exceed max_work
    /// (count and the deepest are then of the pairs found); INVALID_INPUT for an invalid mesh
    /// or a negative max_contacts or max_work; OUT_OF_RANGE outside `mesh_pair_in_range`.
    Status status = Status::NOT_RUN;
};

/// The contacts of two posed meshes, the pairs coal's and FCL's mesh collide with contacts
/// list: every crossing triangle pair (the descent of mesh_intersects run to the end, the
/// same exact triangle test), each with its own penetration depth (`triangle_penetration`:
/// the separating axis theorem over the 11 axes of two triangles, the minimum translation
/// that separates them) and coal's per-pair depth (`face_depth`, a separating translation
/// along a's face normal, not the shortest). Not a depth of the meshes: a resting contact's pairs are
/// shallow however deep a mesh sinks, and a pair deep inside the other solid has none (see
/// `mesh_penetration_depth`). With `contacts`, it is cleared and gets every contact in order
/// of (triangle_a, triangle_b), the first `max_contacts` of them.
MeshContactsOutput mesh_contacts(const MeshContactsInput& input, std::vector<MeshContact>* contacts = nullptr);

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

/// Result of `largest_distance`.
struct LargestDistanceOutput {
    /// >= 0: the largest over the finite points of their distance to the surface, the same
    /// bits as the largest `closest_point(...).distance`; NaN when the mesh is invalid or no
    /// point is finite
    double distance = 0.0;
    std::int64_t point = -1;  ///< index of the first point at that distance, -1 when NaN
    Status status = Status::NOT_RUN;  ///< CONVERGED; INVALID_INPUT for an invalid mesh
};

/// The largest distance from `count` points (mesh local frame) to the mesh's surface: the
/// maximum of the minima (a one-sided Hausdorff distance from the points to the surface).
/// Each point runs closest_point's branch and bound, stopped as soon as it finds a triangle
/// within the largest distance found so far: that point cannot raise the maximum, and a
/// point that does raise it ran the whole search, so the result is the maximum of
/// closest_point's distances bit for bit (mesh_detail::distance_beyond). Non-finite points
/// are skipped.
LargestDistanceOutput largest_distance(const MeshBvh& mesh, const Vec3* points, std::int64_t count);

/// How a surface patch maps its parameters (u, v) to a point, in the primitive's frame.
enum class PatchMap : std::int8_t {
    FLAT = 0,      ///< origin + u edge_u + v edge_v, u and v in [0, 1] (a box's face)
    SPHEROID = 1,  ///< (a sin v cos u, b sin v sin u, z0 + c cos v), u a longitude (a ball, part of one)
    SIDE = 2,      ///< (a cos u, b sin u, c v) (a capsule's or cylinder's side, v in [-1, 1])
    DISK = 3,      ///< (a v cos u, b v sin u, z0) (a cylinder's end, v in [0, 1])
};

/// A patch of a primitive's surface sampled on a grid of n_u x n_v nodes: u at i / (n_u - 1)
/// (FLAT) or the longitude 2 pi i / n_u (round, periodic), v at v0 + (v1 - v0) j / (n_v - 1).
/// |df/du| <= lu and |df/dv| <= lv over the patch, so two nodes (i, j), (i', j') are at most
/// lu |u - u'| + lv |v - v'| apart, which bounds how far a distance can rise within a block.
struct SurfacePatch {
    PatchMap map = PatchMap::FLAT;
    std::int64_t n_u = 1, n_v = 1;  ///< nodes along u and v, >= 1
    /// FLAT: origin (0-2), edge_u (3-5), edge_v (6-8). Round: a, b, c, z0 (0-3) and, for a
    /// SPHEROID, the primitive's axis its map's z is (5: 2 unless a turned ellipsoid's; the
    /// map's x is the axis after it, its y the one after that)
    double g[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    double v0 = 0.0, v1 = 1.0;
    double lu = 0.0, lv = 0.0;  ///< the derivative bounds
};

/// Node (i, j) of a patch (0 <= i < n_u, 0 <= j < n_v), the primitive's frame.
Vec3 patch_point(const SurfacePatch& patch, std::int64_t i, std::int64_t j);

/// `largest_distance` of the nodes of `count` patches (their grid points, patch_point), by
/// blocks: a block of nodes whose centre node is at distance d, its nodes within r of it (the
/// derivative bounds), cannot raise a maximum that is already above d + r (the distance is
/// 1-Lipschitz), so it is skipped after one search (stopped at that floor); the others are
/// halved, and blocks of at most 4 nodes measure every node as largest_distance does. The
/// result is the maximum over every node, as largest_distance of the same points; `point`
/// counts the nodes patch after patch, row by row (i, then j), and names a node at the maximum.
LargestDistanceOutput largest_distance_to_patches(const MeshBvh& mesh, const SurfacePatch* patches,
                                                  std::int64_t count);

/// A ray against a posed mesh.
struct MeshRayInput {
    const MeshBvh* mesh = nullptr;  ///< the mesh (local frame)
    Pose pose;                      ///< world from the mesh's local frame, rigid
    Vec3 origin;                    ///< world frame: where the ray starts
    Vec3 direction;                 ///< world frame: along what it runs (finite, non-zero)
    /// Only hits at most this far from the origin count (world units). Must be >= 0.
    double max_distance = std::numeric_limits<double>::infinity();
};

/// Result of `mesh_ray_cast`.
struct MeshRayOutput {
    bool hit = false;  ///< the ray meets the surface within max_distance
    /// >= 0: from the origin to the first hit along the ray (world units); inf without a hit;
    /// NaN when invalid
    double distance = 0.0;
    Vec3 point;  ///< world: the first hit, origin + distance * unit direction; NaN without one
    /// World unit normal of the face hit on its counter-clockwise side (outward for an
    /// outward-wound mesh); NaN without a hit
    Vec3 normal;
    std::int64_t triangle = -1;       ///< input face hit, -1 without a hit
    Status status = Status::NOT_RUN;  ///< CONVERGED; INVALID_INPUT (mesh, origin, direction,
                                      ///< max_distance). The caller checks that the pose is rigid.
};

/// The first hit of a ray on a mesh's surface. The ray is clipped to the root box and the
/// hierarchy descended nearer box first, pruning boxes it enters beyond the nearest hit; at the
/// leaves the exact segment-triangle test (`segment_crosses_triangle`: orientation signs) decides
/// each hit, so a ray through an edge or a vertex shared by two faces never passes between them;
/// only the distance is rounded. An origin on the surface hits at distance 0; a ray lying in a
/// face's plane does not hit that face (its neighbours' edges catch it). Of hits at the same
/// distance, the lowest input face wins.
MeshRayOutput mesh_ray_cast(const MeshRayInput& input);

/// Generalized winding number of `point` (mesh's local frame) w.r.t. the mesh: the sum of the
/// signed solid angles of its triangles over 4 pi (Jacobson et al. 2013; solid angles by van
/// Oosterom and Strackee 1983). 1 inside a closed outward-wound mesh, 0 outside, -1 inside an
/// inward-wound one. Undefined on the surface.
double winding_number(const MeshBvh& mesh, const Vec3& point);

/// A winding number known to within `error`: |value - winding_number| <= error, up to rounding.
struct WindingEstimate {
    double value = 0.0;
    double error = 0.0;         ///< >= 0; 0 when every triangle was summed exactly
    std::int64_t visits = 0;    ///< nodes approximated plus triangles summed (the work done)
};

/// Fast winding number (Barill et al. 2018) with a guaranteed error: the hierarchy's nodes far
/// from `point` (distance from their centre above twice their radius) contribute their order-2
/// far-field expansion, each with a rigorous bound of its Taylor remainder (the third
/// directional derivative of 1/|x| is at most 6/|x|^4, as Legendre polynomials are at most 1:
/// 3 radius^2 area / (4 pi (d - radius)^4)); nodes nearer are opened, leaves summed exactly
/// (as winding_number). Then the node with the largest bound is opened until the total bound is
/// at most `max_error` (0: the exact sum). A non-finite point gives NaN.
WindingEstimate fast_winding_number(const MeshBvh& mesh, const Vec3& point, double max_error);

/// Whether |winding_number(mesh, point)| >= defaults::winding_number_inside, by the fast
/// winding number refined only until its bound decides that comparison (opening nodes largest
/// bound first, down to the exact sum when the value sits within rounding of the threshold):
/// the verdict of the O(F) sum at a fraction of its cost off the surface. Adds the nodes and
/// triangles visited to `*work` when given.
bool winding_number_inside(const MeshBvh& mesh, const Vec3& point, long long* work = nullptr);

}  // namespace meshcol
