#pragma once
/// Exact queries on one pair of triangles: closest points and intersection.
///
/// A triangle is three points `t[0], t[1], t[2]` in the caller's frame; both triangles of a
/// query must be in the same frame. Degenerate triangles (collinear or repeated vertices) are
/// accepted: they behave as the segment or point they are.

#include <cstdint>

#include "meshcol/vec.hpp"

namespace meshcol {

/// Closest points of two segments [p1, q1] and [p2, q2].
struct SegmentClosestPoints {
    double squared_distance;  ///< >= 0, squared length of point_b - point_a
    Vec3 point_a;             ///< on [p1, q1]
    Vec3 point_b;             ///< on [p2, q2]
};

/// Closest points of two segments (Ericson 2004, 5.1.9); degenerate segments are points.
SegmentClosestPoints segment_closest_points(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                            const Vec3& q2);

/// Closest point of triangle `t` to `p` by Voronoi regions (Ericson 2004, 5.1.5); a
/// degenerate triangle (zero normal) is its three edges.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3 t[3]);

/// Whether two closed triangles share at least one point (touching counts), exactly.
///
/// Non-coplanar triangles intersect exactly when an edge of one meets the other; coplanar ones
/// when an edge of one meets the other in their plane or one contains the other. The tests are
/// sign tests on orientation determinants (as Guigue and Devillers 2003), each sign exact for
/// every finite input (Shewchuk's filtered predicates with an exact fallback), so the answer
/// is exact. When the triangles intersect and `witness` is not null, writes a point they share
/// (up to rounding).
bool triangles_intersect(const Vec3 a[3], const Vec3 b[3], Vec3* witness);

/// Whether the closed segment [p, q] meets the closed triangle `t` in exactly one point, i.e.
/// crosses or touches it without lying in its plane (exact signs, as `triangles_intersect`).
/// A degenerate triangle, or a segment in the triangle's plane, never counts. On success
/// writes the parameter s in [0, 1] of the meeting point p + s (q - p) (up to rounding).
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3 t[3], double* parameter);

/// Squared distance between two triangles, as the minimum over the 9 edge-edge pairs and the 6
/// vertex-face pairs (Ericson 2004, 5.1.9 and 5.1.5); writes the closest points. This is the
/// exact distance when the triangles do not intersect, and an upper bound otherwise (call
/// `triangles_intersect` first).
double triangle_separated_squared_distance(const Vec3 a[3], const Vec3 b[3], Vec3* point_a,
                                           Vec3* point_b);

/// `triangle_separated_squared_distance` with early outs against `limit2`: bit for bit the same
/// value and points whenever that value is at most `limit2`; otherwise some value above
/// `limit2` (the points then mean nothing). An edge pair or vertex-face pair is skipped when a
/// lower bound of its distance, less `slack`, is above the smaller of sqrt(limit2) and the
/// best distance so far. `slack` must be at least 3e-14 of the largest coordinate magnitude
/// of the six corners: it covers the rounding of the edge-line bound, under 2e-14 of it (a
/// mesh pair's allowance, 1e-13 of the translation and both oriented-box reaches, is at
/// least 5.7e-14 of it).
double triangle_separated_squared_distance_below(const Vec3 a[3], const Vec3 b[3], double limit2, double slack,
                                                 Vec3* point_a, Vec3* point_b);

/// One feature pair of `triangle_separated_squared_distance`, alone, by the search's very
/// expressions (so the value and points it computes for that pair): `feature` 3 i + j is edge i
/// of a against edge j of b (edge k joins corners k and k + 1), 9 + i corner i of a against b's
/// face, 12 + j corner j of b against a's face. Writes the closest points and returns their
/// squared distance; a corner whose projection falls outside the face, or a degenerate face,
/// gives +inf and writes nothing.
double triangle_feature_squared_distance(const Vec3 a[3], const Vec3 b[3], int feature, Vec3* point_a,
                                         Vec3* point_b);

/// Distance between two triangles and their closest points.
struct TriangleDistanceOutput {
    double distance = 0.0;      ///< >= 0; 0 when they intersect (or, rounded, closer than ~1e-16)
    Vec3 point_a;               ///< on triangle a, caller's frame
    Vec3 point_b;               ///< on triangle b, caller's frame; equals point_a when intersecting
    bool intersecting = false;  ///< the closed triangles share a point (exact)
};

/// Exact distance between two triangles: `triangles_intersect`, then the 15 feature pairs.
TriangleDistanceOutput triangle_distance(const Vec3 a[3], const Vec3 b[3]);

/// Penetration of two intersecting triangles: the minimum translation of b that separates them
/// (leaves them touching), as a convex pair's penetration depth.
struct TrianglePenetration {
    double depth = 0.0;  ///< >= 0, caller's units; 0 for coplanar (and flat) pairs
    /// Unit, caller's frame: the direction to move b by `depth` to separate it from a (from a
    /// towards b). NaN when no candidate axis exists (both triangles degenerate to parallel
    /// segments or points: then depth is 0).
    Vec3 normal;
    /// Witness points, caller's frame (only with `points`): point_a on a and point_b on b with
    /// point_a - point_b = depth * normal up to rounding (b's point deepest past a, and where
    /// it meets a once b is moved); one shared point when depth is 0. NaN without `points`.
    /// They are the closest points of a and of b moved by depth * normal on the features the
    /// minimum's axis names (`triangle_penetration_points`).
    Vec3 point_a, point_b;
    /// The axis of the minimum: 0 a's face normal, 1 b's, 2 + 3 i + j the cross product of
    /// edge i of a (corners i, i + 1) and edge j of b; -1 when there is none.
    int axis = -1;
};

/// Penetration depth of two triangles that intersect (`triangles_intersect`), exactly as the
/// separating axis theorem gives it for two convex polytopes: the minimum, over the candidate
/// axes (the two face normals and the nine edge-edge cross products, Gottschalk, Lin and
/// Manocha 1996; Ericson 2004, 4.4), of the smaller of the two overlaps of the projections.
/// The facets of the Minkowski difference a - b have normals among these axes, and the
/// nearest facet to the origin gives the minimum translation distance; an axis that is not a
/// facet normal only bounds it from above, so the minimum over all is the depth (up to the
/// rounding of the projections). A zero cross product (parallel edges) or a zero face normal
/// (a degenerate triangle) is no axis. Exactly coplanar triangles (orient3d) have depth 0 and
/// a's normal (b's when a is degenerate). For triangles that do not intersect the result
/// means nothing. With `points`, the witness points (the closest points of a and of b moved
/// by depth * normal, Ericson 2004, 5.1.9). `general`: the caller has found (exactly) that no
/// corner of either triangle lies on the other's plane, so neither is degenerate nor are they
/// coplanar; those tests are then skipped (the same answer).
TrianglePenetration triangle_penetration(const Vec3 a[3], const Vec3 b[3], bool points = true,
                                         bool general = false);

/// The witness points of `p`, a `triangle_penetration(a, b, false)` of the same triangles (its
/// depth, normal and axis): what `points` adds, for a caller that keeps the penetration and
/// wants the points of some pairs only. b is moved by depth * normal (not at all for depth 0),
/// to touch a, and the points are the closest points of the feature pair the axis names
/// (`triangle_feature_squared_distance`): on a face normal, the other triangle's corner
/// deepest along it (the first of equally deep corners) and its foot on the face; on an edge
/// pair's cross product, the closest points of the two edges. Where
/// that pair is not within 1e-12 of the largest coordinate magnitude (its corner's foot falls
/// outside the face, or the edges do not meet: an axis tied with another up to rounding): for
/// depth 0 a point the two share (`triangles_intersect`), else the closest points of a and
/// moved b over all 15 feature pairs (Ericson 2004, 5.1.9). point_b is the point on moved b
/// moved back.
void triangle_penetration_points(const Vec3 a[3], const Vec3 b[3], TrianglePenetration& p);

/// Whether two triangles cross: their relative interiors (the open triangles) share a point.
///
/// Non-coplanar triangles cross when they meet along a segment through both interiors;
/// coplanar ones when they overlap with positive area. Meeting only at points or along
/// boundaries (a shared vertex or edge, a vertex or edge touching the other triangle) is not
/// a crossing, and a degenerate triangle (collinear or repeated corners) crosses nothing. The
/// verdict is exact for finite inputs (orientation signs by filtered predicates with an exact
/// fallback, Shewchuk 1997); no tolerance is involved.
bool triangles_cross(const Vec3 a[3], const Vec3 b[3]);

/// Whether faces `fa` and `fb` (three vertex indices each into `vertices`, (n, 3)) of one mesh
/// cross: false for a duplicate face (the same three indices), else `triangles_cross` of their
/// corners, the same verdict on every pair, found faster when the faces share vertex indices
/// (most of the candidates of a fan of faces around one vertex): a shared vertex lies exactly
/// on the other face's plane without an orientation determinant (whose exact evaluation is
/// the slow one), and coplanar faces sharing one vertex try only the edges through it as
/// separating lines (the opposite edges have the shared vertex strictly inside).
bool face_pair_crosses(const double* vertices, const std::int64_t* fa, const std::int64_t* fb);

/// `triangles_cross` for each pair (pairs[2k], pairs[2k + 1]) of faces of one mesh, written to
/// crossing[k] (1 or 0); a pair of faces on the same three vertex indices (a duplicate face)
/// does not cross. `vertices` is (n, 3), `faces` (m, 3) indices into it, `pairs` (k, 2)
/// indices into `faces`; the caller checks every index. Runs on `threads` threads (0: all).
void face_pairs_cross(const double* vertices, const std::int64_t* faces,
                      const std::int64_t* pairs, long long pair_count, std::uint8_t* crossing,
                      int threads);

}  // namespace meshcol
