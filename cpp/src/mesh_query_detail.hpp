#pragma once
// The pieces the mesh-pair queries share (mesh_distance.cpp, mesh_intersection.cpp,
// mesh_depth.cpp, mesh_depth_closed.cpp, mesh_winding.cpp): the relative frame of a pair, the
// bounds of node and triangle boxes, the point-to-node bound of the point searches, and the
// entry points one query file offers another. Private to the core.
//
// All the pair work happens in a's local frame: b's triangles are mapped there at the leaves,
// and node pairs are bounded by their oriented boxes (NodeObb: thin along the normal of a
// nearly flat patch, whatever the poses), whose separating-axis gaps bound the distance from
// below.

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/mesh_bvh.hpp"
#include "meshcol/vec.hpp"

namespace meshcol::mesh_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kPi = 3.14159265358979323846;

// Minimum and maximum without the NaN rules of std::fmin / std::fmax, which compilers do not
// inline (a library call each in the hottest loops); the bounds they feed are finite or +inf.
inline double min2(double x, double y) { return y < x ? y : x; }
inline double max2(double x, double y) { return y > x ? y : x; }
inline Vec3 min3(const Vec3& a, const Vec3& b) { return {min2(a.x, b.x), min2(a.y, b.y), min2(a.z, b.z)}; }
inline Vec3 max3(const Vec3& a, const Vec3& b) { return {max2(a.x, b.x), max2(a.y, b.y), max2(a.z, b.z)}; }

// The rigid map from b's local frame to a's local frame, and back.
struct Relative {
    Mat3 rotation;
    Mat3 abs_rotation;  // |rotation| element-wise, maps half extents to enclosing half extents
    Vec3 translation;
    // The first two rows of each column of rotation, (rotation.m[0][k], rotation.m[1][k]): a
    // column's pair side by side, for the box test's SSE2 lanes (mesh_intersection.cpp).
    double columns01[3][2];
    // The poses' rotations are equal, so `rotation` is the identity exactly (set below): b's
    // frame maps into a's by the translation alone (the contacts' axis-aligned descent).
    bool translation_only = false;
    // The frames are nearly aligned (b's boxes grow by under 5% when enclosed in a's frame):
    // the axis-aligned boxes are then nearly in a shared frame and bound tighter than the
    // oriented ones for nodes whose orientations differ.
    bool aligned = false;

    // Rounding allowance of a box bound: the oriented boxes are padded by 1e-12 of their own
    // coordinates only, while mapping b's boxes rounds at the scale of the translation too.
    // Every bound is lowered by this (about 500 ulps of the pair's largest length), so rounding
    // can only keep a node pair, never drop one.
    double slack = 0.0;

    Relative(const Pose& pose_a, const Pose& pose_b, const MeshBvh& a, const MeshBvh& b) {
        // Equal rotations give the identity exactly: R^T R rounds otherwise, and a copy of a
        // mesh at the same pose (a duplicated prop) would be moved off itself by that rounding,
        // so that the exact triangle tests could find its coincident surfaces apart.
        bool same_rotation = true;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                same_rotation = same_rotation && pose_a.rotation.m[i][j] == pose_b.rotation.m[i][j];
        translation_only = same_rotation;
        if (same_rotation) {
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) rotation.m[i][j] = i == j ? 1.0 : 0.0;
        } else {
            rotation = pose_a.rotation.transposed() * pose_b.rotation;
        }
        translation = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
        slack = 1e-13 * (max_abs(translation) + a.obb_reach() + b.obb_reach());
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) abs_rotation.m[i][j] = std::fabs(rotation.m[i][j]);
        for (int k = 0; k < 3; ++k) {
            columns01[k][0] = rotation.m[0][k];
            columns01[k][1] = rotation.m[1][k];
        }
        aligned = true;
        for (int i = 0; i < 3; ++i)
            aligned = aligned && abs_rotation.m[i][0] + abs_rotation.m[i][1] + abs_rotation.m[i][2] < 1.05;
    }
    Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
    Vec3 apply_inverse(const Vec3& p) const { return rotation.transpose_times(p - translation); }

    // A node box of b (in b's frame) mapped into a's frame and enclosed there: its centre and
    // half extents. enclose_in_b: a node box of a, into b's frame.
    std::pair<Vec3, Vec3> enclose_in_a(const BvhNode& node) const {
        const auto [centre, half] = centre_and_half(node);
        return {apply(centre), abs_rotation * half};
    }
    std::pair<Vec3, Vec3> enclose_in_b(const BvhNode& node) const {
        const auto [centre, half] = centre_and_half(node);
        return {apply_inverse(centre), abs_rotation.transpose_times(half)};
    }

private:
    static std::pair<Vec3, Vec3> centre_and_half(const BvhNode& n) {
        const Vec3 lower{n.lower[0], n.lower[1], n.lower[2]}, upper{n.upper[0], n.upper[1], n.upper[2]};
        return {(lower + upper) * 0.5, (upper - lower) * 0.5};
    }
};

inline double node_size(const BvhNode& n) {
    return (static_cast<double>(n.upper[0]) - n.lower[0]) + (static_cast<double>(n.upper[1]) - n.lower[1]) +
           (static_cast<double>(n.upper[2]) - n.lower[2]);
}

struct TriangleBox {
    Vec3 lower, upper;
};

inline TriangleBox triangle_box(const Vec3 t[3]) {
    return {min3(t[0], min3(t[1], t[2])), max3(t[0], max3(t[1], t[2]))};
}

// Triangle i's box as MeshBvh keeps it (triangle_box of its corners, local frame, the same
// bits: MeshBvh::validate checks them).
inline TriangleBox stored_box(const MeshBvh& mesh, std::int32_t i) {
    const Vec3* bounds = mesh.triangle_bounds(i);
    return {bounds[0], bounds[1]};
}

inline double triangle_box_squared_distance(const TriangleBox& a, const TriangleBox& b) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double gap = a.lower[k] - b.upper[k];
        if (gap < 0.0) gap = b.lower[k] - a.upper[k];
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// The largest double whose square rounds to 0 (to nearest: a square at most 2^-1075, half the
// least subnormal, does; this is sqrt(2) 2^-538 rounded down, and the next double's square is
// 2^-1074): a gap g has g > 0.0 && g * g > 0.0 exactly when g > kTouchGap, one compare for two
// and a product (a C++ test checks both sides of it).
inline constexpr double kTouchGap = 0x1.6a09e667f3bccp-538;

// triangle_box_squared_distance(a, b) == 0.0, stopping at the first axis that decides: the
// sum is 0 exactly when every positive gap's square is (a sum of non-negative terms is 0 only
// when each is, and a positive square rounds to a positive sum or to inf), i.e. when no gap is
// above kTouchGap. The oriented descent's form; triangle_boxes_touch_at_once below is the
// same verdict for the axis-aligned descent.
inline bool triangle_boxes_touch(const TriangleBox& a, const TriangleBox& b) {
    for (int k = 0; k < 3; ++k) {
        double gap = a.lower[k] - b.upper[k];
        if (gap < 0.0) gap = b.lower[k] - a.upper[k];
        if (gap > kTouchGap) return false;
    }
    return true;
}

// The gap of the intervals [lower_a, upper_a] and [lower_b, upper_b] (finite, each lower <=
// upper) as triangle_boxes_touch takes it, with no branch: where lower_a - upper_b >= 0
// (lower_a >= upper_b, the sign of a rounded difference being exact), lower_b - upper_a <=
// upper_b - lower_a <= 0 and the larger is the first, as there; else the second is taken there,
// and the larger differs from it only when both are negative, below kTouchGap alike. So
// interval_gap(...) > kTouchGap is that test's verdict on the axis.
inline double interval_gap(double lower_a, double upper_a, double lower_b, double upper_b) {
    return max2(lower_a - upper_b, lower_b - upper_a);
}

// Whether boxes whose interval_gap on the three axes are x, y and z touch: none above
// kTouchGap, i.e. not the largest, one branch where an axis at a time takes three. Every
// axis-aligned box test of the contacts' descent ends here (triangle_boxes_touch_at_once, and
// on the nodes' floats aligned_boxes_touch and RefitB::touches, mesh_intersection.cpp).
inline bool gaps_touch(double x, double y, double z) { return !(max2(x, max2(y, z)) > kTouchGap); }

// triangle_boxes_touch's verdict for finite boxes in gaps_touch's one branch, where each of
// that test's three is taken about half the time on a pair of curved surfaces. A C++ test
// compares the two forms.
inline bool triangle_boxes_touch_at_once(const TriangleBox& a, const TriangleBox& b) {
    return gaps_touch(interval_gap(a.lower.x, a.upper.x, b.lower.x, b.upper.x),
                      interval_gap(a.lower.y, a.upper.y, b.lower.y, b.upper.y),
                      interval_gap(a.lower.z, a.upper.z, b.lower.z, b.upper.z));
}

// triangle_box_squared_distance(a, b) with no branch: each axis's gap as interval_gap takes
// it (that function's gap wherever either is positive), less than 0 taken as 0, whose square
// adds a zero where that function adds nothing: the same sum, bit for bit (the partial sums are
// non-negative, and adding a zero to one leaves it). The depth marks' axis-aligned descent
// tests its boxes so, a test that goes either way: with it and the plane screen's at_once form
// the balls' query took 1% more instructions, about 3.5% fewer simulated branch mispredictions
// (cachegrind) and about 2% less CPU (benchmarks/RESULTS.md, session 34, depth23). A C++ test
// compares the two forms.
inline double boxes_squared_distance_at_once(const TriangleBox& a, const TriangleBox& b) {
    const double x = max2(interval_gap(a.lower.x, a.upper.x, b.lower.x, b.upper.x), 0.0);
    const double y = max2(interval_gap(a.lower.y, a.upper.y, b.lower.y, b.upper.y), 0.0);
    const double z = max2(interval_gap(a.lower.z, a.upper.z, b.lower.z, b.upper.z), 0.0);
    return (x * x + y * y) + z * z;
}

// b's leaf triangles mapped into a's frame, with their boxes.
struct MappedLeaf {
    // Left uninitialised (a union member without an initialiser): `load` writes the first
    // `count` entries before any is read (zeroing them all shows on a query that reaches a leaf).
    union {
        Vec3 corners[defaults::mesh_bvh_leaf_size][3];
    };
    union {
        TriangleBox boxes[defaults::mesh_bvh_leaf_size];
    };
    int count = 0;

    MappedLeaf() {}

    void load(const MeshBvh& mesh, const BvhNode& leaf, const Relative& rel) {
        count = leaf.count;
        for (int i = 0; i < count; ++i) {
            const Vec3* t = mesh.triangle(leaf.index + i);
            for (int k = 0; k < 3; ++k) corners[i][k] = rel.apply(t[k]);
            boxes[i] = triangle_box(corners[i]);
        }
    }
};

inline bool inside_box(const BvhNode& n, const Vec3& p) {
    for (int k = 0; k < 3; ++k)
        if (!(p[k] >= n.lower[k] && p[k] <= n.upper[k])) return false;
    return true;
}

// The parameters [enter, leave] of the line p + s d within node n's box grown by a relative
// margin (so rounding can only keep a box, never drop one), intersected with [lo, hi]; false
// when empty (the slab test, Kay and Kajiya 1986).
inline bool slab_interval(const BvhNode& n, const Vec3& p, const Vec3& d, double lo, double hi,
                          double* enter, double* leave) {
    for (int k = 0; k < 3; ++k) {
        const double margin = 1e-9 * (std::fabs(n.lower[k]) + std::fabs(n.upper[k])) + 1e-300;
        const double a = static_cast<double>(n.lower[k]) - margin;
        const double b = static_cast<double>(n.upper[k]) + margin;
        if (d[k] == 0.0) {
            if (p[k] < a || p[k] > b) return false;
            continue;
        }
        double s0 = (a - p[k]) / d[k], s1 = (b - p[k]) / d[k];
        if (s0 > s1) std::swap(s0, s1);
        if (s0 > lo) lo = s0;
        if (s1 < hi) hi = s1;
        if (lo > hi) return false;
    }
    *enter = lo;
    *leave = hi;
    return true;
}

// Whether the segment p + s d, s in [0, 1], may meet node n's (grown) box.
inline bool segment_may_meet_box(const BvhNode& n, const Vec3& p, const Vec3& d) {
    double enter = 0.0, leave = 1.0;
    return slab_interval(n, p, d, 0.0, 1.0, &enter, &leave);
}

// A triangle pair of a and b that intersect (touching counts), in leaf order.
struct CrossingPair {
    std::int32_t a, b;
};

// What the descent of the depth query learns about each mesh's triangles (leaf order). Only
// the two flags are kept per triangle of the mesh; the rest per near triangle, so that
// grouping the near pairs costs their number, not the mesh's size.
struct TriangleMarks {
    std::vector<char> crossing;  // intersects (touches) the other surface
    // A triangle within the other mesh's rounding allowance of its surface (every crossing
    // one too): its entry in `near_triangles`, else -1. A triangle not near is farther than
    // rel.slack from every triangle of the other mesh.
    std::vector<std::int32_t> near_slot;
    struct Near {
        std::int32_t partner;      // a triangle of the other mesh it crosses, else -1
        std::int32_t first, last;  // the triangles of the other mesh near it: others[first .. last)
    };
    std::vector<Near> near_triangles;  // in the order the descent first met them
    std::vector<std::int32_t> others;

    bool near(std::int32_t i) const { return near_slot[static_cast<size_t>(i)] >= 0; }
    /// Triangle i's entry; i must be near.
    const Near& near_entry(std::int32_t i) const {
        return near_triangles[static_cast<size_t>(near_slot[static_cast<size_t>(i)])];
    }
    /// The triangles of the other mesh near triangle i: others[first .. last), empty when not near.
    std::pair<std::int32_t, std::int32_t> near_range(std::int32_t i) const {
        const std::int32_t slot = near_slot[static_cast<size_t>(i)];
        if (slot < 0) return {0, 0};
        const Near& n = near_triangles[static_cast<size_t>(slot)];
        return {n.first, n.last};
    }
};

// Lower bound of the squared distance from `point` to the triangles of node `id`: the distance
// to its oriented box. A patch's box is a thin slab along its mean normal, so from a point
// deep inside a closed mesh (the depth query's points) the bound is nearly the distance itself,
// where the axis-aligned box of a slanted patch reaches far towards the point and prunes
// little. The box is padded by 1e-12 of its coordinates (MeshBvh::build_obbs), above the
// rounding of the projections here for any point within reach of it; a far point's rounding,
// relative to its distance, is covered by lowering the bound by a relative 1e-9. A projection
// that overflows gives NaN, which adds nothing: the bound only falls.
inline double point_node_squared_distance(const MeshBvh& mesh, std::int32_t id, const Vec3& point) {
    const NodeObb& box = mesh.obbs()[static_cast<size_t>(id)];
    const Vec3 local = box.axes * (point - box.center);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double gap = std::fabs(local[k]) - box.half[k];
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2 * (1.0 - 1e-9);
}

// The child step of the point-to-mesh branch and bound (closest_point, distance_beyond): the
// children of internal node `index` with their box distances to `point`, pushed farther first
// so that the closer one is searched next; once a triangle was measured (`found`), only those
// closer than `best2`.
inline void push_children(const MeshBvh& mesh, std::int32_t index, const Vec3& point, bool found, double best2,
                          std::vector<std::pair<std::int32_t, double>>& stack) {
    const auto child = [&](std::int32_t i) { return std::make_pair(i, point_node_squared_distance(mesh, i, point)); };
    std::pair<std::int32_t, double> near = child(index + 1), far = child(mesh.nodes()[static_cast<size_t>(index)].index);
    if (near.second > far.second) std::swap(near, far);
    if (!found || far.second < best2) stack.push_back(far);
    if (!found || near.second < best2) stack.push_back(near);
}

// Entry points of one query file for the others.

/// Whether `p` (mesh's local frame) is in the solid: |winding number| >= 1/2, exactly for a
/// closed mesh (mesh_winding.cpp). Adds the work done to `*work`.
bool inside_mesh(const MeshBvh& mesh, const Vec3& p, long long* work);

/// The first intersecting triangle pair (leaf order) of the descent of mesh_intersects and a
/// point they share (a's frame); false when the surfaces do not meet (mesh_intersection.cpp).
/// `touching`, when given with a < 0, gets the first triangle pair whose boxes touch (a near
/// pair for the distance search to start from), left as it is when there is none.
bool first_crossing(const MeshBvh& a, const MeshBvh& b, const Relative& rel, std::int32_t* triangle_a,
                    std::int32_t* triangle_b, Vec3* witness, CrossingPair* touching = nullptr);

/// How mark_crossing_triangles finds its triangle pairs: by the contacts' faster descents made
/// to keep the plain oriented descent's order (kFast, the query's), or by that descent itself
/// (kPlain, for a test to compare with).
enum class MarkDescent { kFast, kPlain };

/// The descent of mesh_intersects run to the end: the intersecting triangle pairs in descent
/// order, and the marks of both meshes' triangles (mesh_intersection.cpp). Both forms of
/// `descent` give the same crossing pairs in the same order, the same crossing marks and
/// partners; their near triangles differ only among pairs farther apart than rel.slack.
/// False, the marks unfinished, when more than `max_near_pairs` triangle pairs are near.
bool mark_crossing_triangles(const MeshBvh& a, const MeshBvh& b, const Relative& rel, TriangleMarks& in_a,
                             TriangleMarks& in_b, std::vector<CrossingPair>& pairs,
                             MarkDescent descent = MarkDescent::kFast,
                             long long max_near_pairs = defaults::mesh_depth_max_near_pairs);

/// Whether two triangles (one frame) share a point: triangles_intersect(ta, tb, nullptr), the
/// same exact verdict, decided by the order of the two planes' crossings along their common
/// line where no corner lies on the other's plane (mesh_intersection.cpp; the descents' test).
bool triangles_meet(const Vec3* ta, const Vec3* tb);

/// Whether the box test of the descents (SSE2 lanes where built with SSE2) gives the scalar
/// form's verdict, written to `*verdict`, and the same centre-line depth bits, for the boxes
/// of a's node and b's node under `rel` (mesh_intersection.cpp; for a C++ test: the scalar form
/// is the only one built without SSE2).
bool box_test_forms_agree(const NodeObb& a, const NodeObb& b, const Relative& rel, bool* verdict);

/// Whether the SSE2 form of triangle_penetration's projection (a's and b's corners in the two
/// lanes, where built with SSE2) gives the scalar form's overlap, to the bit, on each of the
/// pair's 11 candidate axes (triangle_penetration.cpp; for a C++ test: the scalar form is the
/// only one built without SSE2). `*down`: the direction the scalar form picks on a's normal.
bool penetration_axis_forms_agree(const Vec3 a[3], const Vec3 b[3], bool* down);

/// The descent of mesh_intersects run to the end, its internal node pairs split on both sides
/// (mesh_intersection.cpp, for_each_touching_pair's split_both; by axis-aligned boxes in a's
/// frame when the poses' rotations are equal, rel.translation_only:
/// for_each_touching_pair_aligned, which reaches every triangle pair whose boxes touch):
/// calls `visit(i, j, ta, tb, shared)` for every intersecting triangle pair (leaf order; b's
/// corners mapped into a's frame), by the same exact verdict (triangles_meet), in descent order; with `witnesses`,
/// `shared` is the point triangles_intersect(ta, tb, &shared) gives where the descent ran that
/// test (a pair with a corner on the other's plane: every touching pair), else NaN; `general`
/// says that no corner of either lies on the other's plane (exactly: triangle_penetration's
/// `general`). Counts the triangle pairs whose boxes touch in `*work` and stops once it is above
/// `max_work`: returns whether it stopped there. `visit` returning true stops the descent too
/// (then the return is false). A turned pair's descent finishes by axis-aligned boxes of b
/// refitted in a's frame once it has made more than `refit_after` oriented box tests (negative:
/// the descent's own choice, by the size of b, and not when few node pairs are then left; 0:
/// from the root): the same crossing pairs, and
/// every triangle pair whose boxes touch under the node pairs it reaches so counts in `*work`.
bool for_each_crossing_pair(
    const MeshBvh& a, const MeshBvh& b, const Relative& rel, long long max_work, long long* work, bool witnesses,
    const std::function<bool(std::int32_t, std::int32_t, const Vec3*, const Vec3*, const Vec3&, bool)>& visit,
    long long refit_after = -1);

/// Parameters along [p, q] (mesh's local frame) where the segment meets the mesh's surface in
/// isolated points, appended to `out` (mesh_intersection.cpp).
void segment_crossings(const MeshBvh& mesh, const Vec3& p, const Vec3& q, std::vector<double>& out);

/// One of mesh_distance's searches of a pair whose surfaces are disjoint, alone (for tests):
/// whether it decided the pair, and then its answer (leaf-order triangles; squared distance
/// bound2 and found false when nothing is within bound2, the squared max_distance).
struct DisjointSearch {
    bool decided = false;
    bool found = false;
    double squared_distance = kInf;
    std::int32_t triangle_a = -1, triangle_b = -1;
};

/// The search by the hulls' supporting planes (mesh_distance.cpp), tried first on pairs whose
/// hulls are apart; undecided when the hulls meet, the candidates are too many or the best
/// pair at the planes cannot be proven the nearest. `screen`: as mesh_distance runs it, giving
/// up at once when the hulls' closest points are not on the meshes; without, it measures the
/// candidates of every such pair too (for tests of the bound that decides).
DisjointSearch distance_across_hulls(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2,
                                     bool screen = true);

/// The best-first node-pair search (mesh_distance.cpp), from no start pair: always decides.
DisjointSearch distance_by_node_pairs(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2);

}  // namespace meshcol::mesh_detail
