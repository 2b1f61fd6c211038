// Mesh-mesh distance, intersection and containment on two MeshBvh hierarchies.
//
// All the work happens in a's local frame: b's triangles are mapped there at the leaves, and
// node pairs are bounded by their oriented boxes (NodeObb: thin along the normal of a nearly
// flat patch, whatever the poses), whose separating-axis gaps bound the distance from below. The distance search is a depth-first
// branch and bound over node pairs (Larsen, Gottschalk, Lin and Manocha 1999, "Fast proximity
// queries with swept sphere volumes"; FCL's MeshDistanceTraversalNode): the closer child pair is
// visited first so a good bound arrives early, and pairs whose box distance cannot beat the best
// distance so far are dropped.
#include "meshcol/mesh_query.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/triangle.hpp"
#include "rescale.hpp"
#include "predicates.hpp"

namespace meshcol {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// Signed solid angle of triangle t seen from `point` (van Oosterom and Strackee 1983:
// tan(omega / 2) = det / denominator); positive when the point is behind the triangle's
// counter-clockwise normal.
inline double triangle_solid_angle(const Vec3 t[3], const Vec3& point) {
    const Vec3 a = t[0] - point, b = t[1] - point, c = t[2] - point;
    const double la = norm(a), lb = norm(b), lc = norm(c);
    const double det = dot(a, cross(b, c));
    const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    return 2.0 * std::atan2(det, denominator);
}

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
        aligned = true;
        for (int i = 0; i < 3; ++i)
            aligned = aligned && abs_rotation.m[i][0] + abs_rotation.m[i][1] + abs_rotation.m[i][2] < 1.05;
    }
    Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
    Vec3 apply_inverse(const Vec3& p) const { return rotation.transpose_times(p - translation); }
};

// A lower bound of the squared distance between the oriented boxes of node a and node b: the
// largest of the gap of their projections on the line through the centres (a separating-axis
// candidate, Gottschalk, Lin and Manocha 1996) and the box distances in a's and in b's box
// frame (the nine edge-pair axes of the overlap test cost more than they prune here). The centre line comes first and needs no relative rotation of the boxes: when
// it alone reaches `enough2` (a bound that already prunes the pair), the rest is skipped.
inline double obb_squared_distance(const NodeObb& a, const NodeObb& b, const Relative& rel, double enough2) {
    const Vec3 d = rel.apply(b.center) - a.center;  // a's local frame
    const Vec3 t = a.axes * d;                      // a's box frame
    const Vec3 tb = b.axes * rel.rotation.transpose_times(d);  // b's box frame
    double best = 0.0;
    const double length2 = dot(d, d);
    if (length2 > 0.0) {
        const double length = std::sqrt(length2);
        const double reach = std::fabs(t.x) * a.half.x + std::fabs(t.y) * a.half.y + std::fabs(t.z) * a.half.z +
                             std::fabs(tb.x) * b.half.x + std::fabs(tb.y) * b.half.y + std::fabs(tb.z) * b.half.z;
        best = max2(0.0, length - reach / length - rel.slack);
        if (best > 0.0 && best * best >= enough2) return best * best;
    }
    double abs_c[3][3];  // |a_i . b_j|, both axes in a's local frame
    for (int j = 0; j < 3; ++j) {
        const Vec3 bj = rel.rotation * b.axes.row(j);
        for (int i = 0; i < 3; ++i) abs_c[i][j] = std::fabs(dot(a.axes.row(i), bj));
    }
    // In a's box frame, b's box lies in the axis-aligned box of half extents
    // sum_j |a_i . b_j| b.half_j about t: the distance between that box and a's box bounds the
    // distance from below (exactly the box distance when the boxes are aligned); likewise in
    // b's box frame.
    double in_a = 0.0, in_b = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double gap = std::fabs(t[i]) - a.half[i] -
                           (abs_c[i][0] * b.half.x + abs_c[i][1] * b.half.y + abs_c[i][2] * b.half.z) - rel.slack;
        if (gap > 0.0) in_a += gap * gap;
    }
    for (int j = 0; j < 3; ++j) {
        const double gap = std::fabs(tb[j]) - (a.half.x * abs_c[0][j] + a.half.y * abs_c[1][j] + a.half.z * abs_c[2][j]) -
                           b.half[j] - rel.slack;
        if (gap > 0.0) in_b += gap * gap;
    }
    return max2(best * best, max2(in_a, in_b));
}

// The distance between node a's axis-aligned box and the axis-aligned box (in a's frame)
// enclosing node b's: exact under pure translation, looser the more b is rotated.
inline double aabb_squared_distance(const BvhNode& na, const BvhNode& nb, const Relative& rel) {
    double d2 = 0.0;
    const Vec3 b_center = rel.apply(Vec3{0.5 * (static_cast<double>(nb.lower[0]) + nb.upper[0]),
                                         0.5 * (static_cast<double>(nb.lower[1]) + nb.upper[1]),
                                         0.5 * (static_cast<double>(nb.lower[2]) + nb.upper[2])});
    const Vec3 b_half = rel.abs_rotation * Vec3{0.5 * (static_cast<double>(nb.upper[0]) - nb.lower[0]),
                                                0.5 * (static_cast<double>(nb.upper[1]) - nb.lower[1]),
                                                0.5 * (static_cast<double>(nb.upper[2]) - nb.lower[2])};
    for (int k = 0; k < 3; ++k) {
        const double gap = max2(static_cast<double>(na.lower[k]) - (b_center[k] + b_half[k]),
                                (b_center[k] - b_half[k]) - static_cast<double>(na.upper[k])) - rel.slack;
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// Whether the oriented boxes a and b may overlap: no separating axis among those of
// obb_squared_distance (the same tests, each lowered by the same slack), stopping at the first
// that separates, and the centre line's tested without its square root and division
// (length - reach / length > slack as length^2 - reach > slack * length, squared).
inline bool obb_overlap(const NodeObb& a, const NodeObb& b, const Relative& rel) {
    const Vec3 d = rel.apply(b.center) - a.center;  // a's local frame
    const Vec3 t = a.axes * d;                      // a's box frame
    const double length2 = dot(d, d);
    const Vec3 tb = b.axes * rel.rotation.transpose_times(d);  // b's box frame
    if (length2 > 0.0) {
        const double reach = std::fabs(t.x) * a.half.x + std::fabs(t.y) * a.half.y + std::fabs(t.z) * a.half.z +
                             std::fabs(tb.x) * b.half.x + std::fabs(tb.y) * b.half.y + std::fabs(tb.z) * b.half.z;
        const double excess = length2 - reach;
        if (excess > 0.0 && excess * excess > rel.slack * rel.slack * length2) return false;
    }
    double abs_c[3][3];  // |a_i . b_j|, both axes in a's local frame
    for (int j = 0; j < 3; ++j) {
        const Vec3 bj = rel.rotation * b.axes.row(j);
        for (int i = 0; i < 3; ++i) abs_c[i][j] = std::fabs(dot(a.axes.row(i), bj));
    }
    for (int i = 0; i < 3; ++i)
        if (std::fabs(t[i]) - a.half[i] - (abs_c[i][0] * b.half.x + abs_c[i][1] * b.half.y + abs_c[i][2] * b.half.z) -
                rel.slack > 0.0)
            return false;
    for (int j = 0; j < 3; ++j)
        if (std::fabs(tb[j]) - (a.half.x * abs_c[0][j] + a.half.y * abs_c[1][j] + a.half.z * abs_c[2][j]) - b.half[j] -
                rel.slack > 0.0)
            return false;
    return true;
}

// Whether the oriented boxes of node pair (a node, b node) may overlap (obb_overlap).
inline bool boxes_overlap(const MeshBvh& a, const MeshBvh& b, std::pair<std::int32_t, std::int32_t> pair,
                          const Relative& rel) {
    return obb_overlap(a.obbs()[static_cast<size_t>(pair.first)], b.obbs()[static_cast<size_t>(pair.second)], rel);
}

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

inline double triangle_box_squared_distance(const TriangleBox& a, const TriangleBox& b) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double gap = a.lower[k] - b.upper[k];
        if (gap < 0.0) gap = b.lower[k] - a.upper[k];
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// Lower bound of the distance between triangles a and b from their projections on the line
// through their centroids (separating-axis bound): tight when the triangles are far apart
// relative to their size, where the box bound is loose. Returns a squared distance.
inline double triangle_axis_squared_distance(const Vec3 a[3], const Vec3 b[3]) {
    const Vec3 axis = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
    const double a_max = max2(dot(axis, a[0]), max2(dot(axis, a[1]), dot(axis, a[2])));
    const double b_min = min2(dot(axis, b[0]), min2(dot(axis, b[1]), dot(axis, b[2])));
    const double gap = b_min - a_max;
    return gap > 0.0 ? gap * gap / dot(axis, axis) : 0.0;
}

struct StackItem {
    std::int32_t a, b;
    double bound;  // squared box distance when pushed
};

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

struct SearchResult {
    bool found = false;         // a pair within the bound was found
    bool intersecting = false;  // a triangle pair intersects
    double squared_distance = kInf;
    Vec3 point_a, point_b;      // a's frame
    std::int32_t triangle_a = -1, triangle_b = -1;  // leaf order
};

// Branch and bound over node pairs. `bound2` is the squared max_distance.
SearchResult search_distance(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2) {
    SearchResult r;
    r.squared_distance = bound2;
    // A pair at exactly max_distance still counts, so before the first find the test is strict.
    auto pruned = [&r](double lb2) { return r.found ? lb2 >= r.squared_distance : lb2 > r.squared_distance; };
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    const std::vector<NodeObb>& oa = a.obbs();
    const std::vector<NodeObb>& ob = b.obbs();
    std::vector<StackItem> stack;
    stack.reserve(128);
    const double root2 = obb_squared_distance(oa[0], ob[0], rel, bound2);
    if (pruned(root2)) return r;
    stack.push_back({0, 0, root2});
    MappedLeaf leaf_b;
    while (!stack.empty()) {
        const StackItem item = stack.back();
        stack.pop_back();
        if (pruned(item.bound)) continue;
        const BvhNode& x = na[static_cast<size_t>(item.a)];
        const BvhNode& y = nb[static_cast<size_t>(item.b)];
        if (x.is_leaf() && y.is_leaf()) {
            leaf_b.load(b, y, rel);
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const Vec3* ta = a.triangle(i);
                const TriangleBox box_a = triangle_box(ta);
                for (int j = 0; j < leaf_b.count; ++j) {
                    const double lb2 = triangle_box_squared_distance(box_a, leaf_b.boxes[j]);
                    if (lb2 == 0.0) {
                        Vec3 w;
                        if (triangles_intersect(ta, leaf_b.corners[j], &w)) {
                            r.found = r.intersecting = true;
                            r.squared_distance = 0.0;
                            r.point_a = r.point_b = w;
                            r.triangle_a = i;
                            r.triangle_b = y.index + j;
                            return r;
                        }
                    }
                    if (pruned(lb2) || pruned(triangle_axis_squared_distance(ta, leaf_b.corners[j]))) continue;
                    Vec3 pa, pb;
                    const double d2 = triangle_separated_squared_distance(ta, leaf_b.corners[j], &pa, &pb);
                    if (!pruned(d2)) {
                        r.found = true;
                        r.squared_distance = d2;
                        r.point_a = pa;
                        r.point_b = pb;
                        r.triangle_a = i;
                        r.triangle_b = y.index + j;
                    }
                }
            }
            // Touching without a detected intersection (rounding): nothing can beat zero.
            if (r.found && r.squared_distance == 0.0) return r;
            continue;
        }
        // Descend the larger box (or the only internal one); push the farther child first so
        // the closer one is popped next.
        const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
        StackItem c1, c2;
        if (descend_a) {
            c1 = {item.a + 1, item.b, 0.0};
            c2 = {x.index, item.b, 0.0};
        } else {
            c1 = {item.a, item.b + 1, 0.0};
            c2 = {item.a, y.index, 0.0};
        }
        c1.bound = obb_squared_distance(oa[static_cast<size_t>(c1.a)], ob[static_cast<size_t>(c1.b)], rel, r.squared_distance);
        c2.bound = obb_squared_distance(oa[static_cast<size_t>(c2.a)], ob[static_cast<size_t>(c2.b)], rel, r.squared_distance);
        if (rel.aligned) {
            c1.bound = max2(c1.bound, aabb_squared_distance(na[static_cast<size_t>(c1.a)], nb[static_cast<size_t>(c1.b)], rel));
            c2.bound = max2(c2.bound, aabb_squared_distance(na[static_cast<size_t>(c2.a)], nb[static_cast<size_t>(c2.b)], rel));
        }
        if (c1.bound > c2.bound) std::swap(c1, c2);
        if (!pruned(c2.bound)) stack.push_back(c2);
        if (!pruned(c1.bound)) stack.push_back(c1);
    }
    return r;
}

bool inside_box(const BvhNode& n, const Vec3& p) {
    for (int k = 0; k < 3; ++k)
        if (!(p[k] >= n.lower[k] && p[k] <= n.upper[k])) return false;
    return true;
}

// Whether `point` (world frame) is inside `mesh` posed at `pose`.
bool point_inside(const MeshBvh& mesh, const Pose& pose, const Vec3& point) {
    const Vec3 local = pose.apply_inverse(point);
    if (!inside_box(mesh.nodes()[0], local)) return false;
    return winding_number_inside(mesh, local);
}

// Whether the segment p + s (q - p), s in [0, 1], may meet node n's box: the slab test on the
// box grown by a relative margin, so rounding can only keep a box, never drop one.
inline bool segment_may_meet_box(const BvhNode& n, const Vec3& p, const Vec3& d) {
    double lo = 0.0, hi = 1.0;
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
    return true;
}

// Signed number of crossings of the segment [p, q] with a closed mesh's triangles (the winding
// number of p when q is outside), with exact orientation signs, or 1 when p lies on the
// surface; false when the segment passes exactly through an edge or a vertex, so another
// direction must be tried.
bool signed_crossings(const MeshBvh& mesh, const Vec3& p, const Vec3& q, int* count) {
    using predicates::orient3d_sign;
    const Vec3 d = q - p;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    std::vector<std::int32_t> stack{0};
    int total = 0;
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        if (!segment_may_meet_box(node, p, d)) continue;
        if (!node.is_leaf()) {
            stack.push_back(node.index);
            stack.push_back(id + 1);
            continue;
        }
        for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
            const Vec3* t = mesh.triangle(i);
            const int sp = orient3d_sign(t[0], t[1], t[2], p);
            const int sq = orient3d_sign(t[0], t[1], t[2], q);
            if (sp == 0) {
                // p on the surface belongs to the closed solid (a point of the other mesh's
                // surface lying on this one still bounds the depth); elsewhere on the plane
                // the segment only touches it at p.
                const Vec3 point[3] = {p, p, p};
                if (triangles_intersect(t, point, nullptr)) {
                    *count = 1;
                    return true;
                }
                continue;
            }
            // One side, or touching the plane only at q (outside the mesh's box): no crossing.
            if (sp * sq >= 0) continue;
            const int s0 = orient3d_sign(p, q, t[0], t[1]);
            const int s1 = orient3d_sign(p, q, t[1], t[2]);
            const int s2 = orient3d_sign(p, q, t[2], t[0]);
            if ((s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0)) {
                total += sp;
                continue;
            }
            if ((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0)) continue;  // misses
            if (s0 == 0 && s1 == 0 && s2 == 0) continue;  // degenerate triangle
            return false;  // through an edge or a vertex
        }
    }
    *count = total;
    return true;
}

// Whether `p` (mesh's local frame) is in the solid: |winding number| >= 1/2. For a closed
// mesh the winding number is the signed crossing count of a segment from p to beyond the
// mesh's box (BVH, exact signs, a few fixed directions in case one passes through an edge or
// a vertex), and a point exactly on the surface counts as in; otherwise, and if every
// direction is degenerate, the generalized winding number (which is 1/2 on a smooth part of
// the surface, so counts it in too).
bool inside_mesh(const MeshBvh& mesh, const Vec3& p, long long* work) {
    if (mesh.closed()) {
        static constexpr Vec3 kDirections[] = {
            {0.5377304471659, 0.2845902536245, 0.7935981048671},
            {-0.6117145263523, 0.7219873914523, 0.3232414553322},
            {0.2174811052316, -0.8642151133311, 0.4536126398734},
            {-0.3902134117283, -0.4155247717421, -0.8216328740022},
            {0.8807432016934, -0.1179016743124, -0.4587332154410},
            {-0.0712387411032, 0.5932171148713, -0.8018427201121},
        };
        const BvhNode& root = mesh.nodes()[0];
        const Vec3 lo{root.lower[0], root.lower[1], root.lower[2]};
        const Vec3 hi{root.upper[0], root.upper[1], root.upper[2]};
        const double reach = 2.0 * (norm(hi - lo) + norm(p - (lo + hi) * 0.5)) + 1.0;
        for (const Vec3& direction : kDirections) {
            int count = 0;
            *work += 64;  // about the cost of one segment query, in triangle visits
            if (signed_crossings(mesh, p, p + direction * reach, &count)) return count != 0;
        }
    }
    return winding_number_inside(mesh, p, work);
}

// A triangle pair of a and b that intersect (touching counts), in leaf order.
struct CrossingPair {
    std::int32_t a, b;
};
// A last-in first-out stack of node pairs held in the caller's frame up to 64 entries (a
// depth-first descent of two balanced hierarchies needs about their summed depths, 40 for a
// million triangles each) and in a vector beyond: a query that descends a few levels
// allocates nothing (a heap allocation costs as much as a root-box test).
class NodePairStack {
public:
    struct Item {
        std::int32_t a, b;
    };
    bool empty() const { return size_ == 0; }
    void push(std::int32_t a, std::int32_t b) {
        if (size_ < kInline) {
            inline_[size_] = Item{a, b};
        } else {
            spill_.push_back(Item{a, b});
        }
        ++size_;
    }
    Item pop() {
        --size_;
        if (size_ < kInline) return inline_[size_];
        const Item top = spill_.back();
        spill_.pop_back();
        return top;
    }

private:
    static constexpr int kInline = 64;
    Item inline_[kInline];
    std::vector<Item> spill_;
    int size_ = 0;
};

// The descent of overlapping oriented boxes shared by the intersection queries: calls
// `visit(i, j, ta, tb)` for each triangle pair (leaf order i of a, j of b; b's corners mapped
// into a's frame) whose boxes touch (are at most sqrt(margin2) apart), in depth-first order,
// until it returns true. Returns whether a visit stopped the descent.
template <class Visit>
bool for_each_touching_pair(const MeshBvh& a, const MeshBvh& b, const Relative& rel, Visit visit,
                            double margin2 = 0.0) {
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    if (!boxes_overlap(a, b, {0, 0}, rel)) return false;
    NodePairStack stack;
    stack.push(0, 0);
    MappedLeaf leaf_b;
    while (!stack.empty()) {
        const auto [ia, ib] = stack.pop();
        const BvhNode& x = na[static_cast<size_t>(ia)];
        const BvhNode& y = nb[static_cast<size_t>(ib)];
        if (x.is_leaf() && y.is_leaf()) {
            leaf_b.load(b, y, rel);
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const Vec3* ta = a.triangle(i);
                const TriangleBox box_a = triangle_box(ta);
                for (int j = 0; j < leaf_b.count; ++j)
                    if (triangle_box_squared_distance(box_a, leaf_b.boxes[j]) <= margin2 &&
                        visit(i, y.index + j, ta, leaf_b.corners[j]))
                        return true;
            }
            continue;
        }
        const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
        const std::pair<std::int32_t, std::int32_t> c1 = descend_a ? std::make_pair(ia + 1, ib) : std::make_pair(ia, ib + 1);
        const std::pair<std::int32_t, std::int32_t> c2 = descend_a ? std::make_pair(x.index, ib) : std::make_pair(ia, y.index);
        if (boxes_overlap(a, b, c2, rel)) stack.push(c2.first, c2.second);
        if (boxes_overlap(a, b, c1, rel)) stack.push(c1.first, c1.second);
    }
    return false;
}

// What the descent of the depth query learns about each mesh's triangles (leaf order).
struct TriangleMarks {
    std::vector<char> crossing;  // intersects (touches) the other surface
    // Within the other mesh's rounding allowance of its surface (every crossing one too): a
    // triangle not near is farther than rel.slack from every triangle of the other mesh.
    std::vector<char> near;
    std::vector<std::int32_t> partner;  // a triangle of the other mesh it crosses, else -1
    // The triangles of the other mesh near triangle i: others[first[i] .. first[i + 1]).
    std::vector<std::int32_t> first, others;
};

// The near pairs (index into a, index into b) grouped by `side`'s triangle.
void group_near_pairs(const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs, int side,
                      std::int32_t count, TriangleMarks& marks) {
    marks.first.assign(static_cast<size_t>(count) + 1, 0);
    for (const auto& pair : pairs) ++marks.first[static_cast<size_t>(side == 0 ? pair.first : pair.second) + 1];
    for (size_t i = 0; i < static_cast<size_t>(count); ++i) marks.first[i + 1] += marks.first[i];
    marks.others.resize(pairs.size());
    std::vector<std::int32_t> next(marks.first.begin(), marks.first.end() - 1);
    for (const auto& pair : pairs) {
        const auto [mine, theirs] = side == 0 ? pair : std::make_pair(pair.second, pair.first);
        marks.others[static_cast<size_t>(next[static_cast<size_t>(mine)]++)] = theirs;
    }
}

// The descent of mesh_intersects run to the end: the intersecting triangle pairs in descent
// order, and the marks of both meshes' triangles. Triangle pairs whose boxes are within
// rel.slack are visited too, to mark the near ones: the node bounds are lowered by rel.slack,
// so a triangle pair closer than that is never pruned.
void mark_crossing_triangles(const MeshBvh& a, const MeshBvh& b, const Relative& rel, TriangleMarks& in_a,
                             TriangleMarks& in_b, std::vector<CrossingPair>& pairs) {
    pairs.clear();
    for (auto [marks, mesh] : {std::make_pair(&in_a, &a), std::make_pair(&in_b, &b)}) {
        marks->crossing.assign(static_cast<size_t>(mesh->triangle_count()), 0);
        marks->near.assign(static_cast<size_t>(mesh->triangle_count()), 0);
        marks->partner.assign(static_cast<size_t>(mesh->triangle_count()), -1);
    }
    std::vector<std::pair<std::int32_t, std::int32_t>> near_pairs;
    for_each_touching_pair(
        a, b, rel,
        [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) {
            const auto si = static_cast<size_t>(i), sj = static_cast<size_t>(j);
            in_a.near[si] = in_b.near[sj] = 1;
            near_pairs.push_back({i, j});
            if (triangle_box_squared_distance(triangle_box(ta), triangle_box(tb)) == 0.0 &&
                triangles_intersect(ta, tb, nullptr)) {
                in_a.crossing[si] = in_b.crossing[sj] = 1;
                if (in_a.partner[si] < 0) in_a.partner[si] = j;
                if (in_b.partner[sj] < 0) in_b.partner[sj] = i;
                pairs.push_back({i, j});
            }
            return false;
        },
        rel.slack * rel.slack);
    group_near_pairs(near_pairs, 0, a.triangle_count(), in_a);
    group_near_pairs(near_pairs, 1, b.triangle_count(), in_b);
}

// Parameters along [p, q] (mesh's local frame) where the segment meets the mesh's surface in
// isolated points, appended to `out`.
void segment_crossings(const MeshBvh& mesh, const Vec3& p, const Vec3& q, std::vector<double>& out) {
    const Vec3 d = q - p;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        stack.pop_back();
        if (!segment_may_meet_box(node, p, d)) continue;
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                double s = 0.0;
                if (segment_crosses_triangle(p, q, mesh.triangle(i), &s)) out.push_back(s);
            }
            continue;
        }
        stack.push_back(node.index);
        stack.push_back(id + 1);
    }
}

// A point of one mesh, in the other mesh's local frame, with its distance to that surface.
struct DepthCandidate {
    Vec3 point;
    double distance;
    int mesh;  // 0: a point of a (frame of b); 1: a point of b (frame of a); 2: a point of
               // neither surface that may lie inside both (frame of a)
    bool farther_is_a;  // mesh 2: a's surface is the farther one
};

inline double longest_edge(const Vec3 t[3]) {
    return std::sqrt(std::fmax(squared_norm(t[1] - t[0]),
                               std::fmax(squared_norm(t[2] - t[1]), squared_norm(t[0] - t[2]))));
}

// Points off both surfaces near where they cross: from a shared point of each crossing
// triangle pair, steps into the wedge between the two triangles, against the sum of their
// unit normals, and from each triangle's centroid, steps against its own normal (each mesh's
// winding decides its normals: outward for outward-wound meshes, and the winding-number test
// sorts out the rest). Such a point p inside both solids bounds
// the minimum translation distance by max(dist(p, surface a), dist(p, surface b)), and it
// finds overlaps whose surface points all lie on the other surface (flush, coplanar faces).
// The crossing pairs that get wedge points: at most 256, evenly strided beyond (the vertices
// and edge cuts do most).
inline size_t wedge_stride(const std::vector<CrossingPair>& pairs) {
    constexpr size_t kMaxPairs = 256;
    return pairs.size() / kMaxPairs + 1;
}

// The wedge points of crossing pair k (add_wedge_candidates), appended to `out`.
void add_pair_wedge_points(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                           const std::vector<CrossingPair>& pairs, size_t k, std::vector<DepthCandidate>& out) {
    {
        const CrossingPair& c = pairs[k];
        const Vec3* ta = a.triangle(c.a);
        const Vec3* tb_local = b.triangle(c.b);
        const Vec3 tb[3] = {rel.apply(tb_local[0]), rel.apply(tb_local[1]), rel.apply(tb_local[2])};
        // Shared points found from a's side and from b's, so that the samples do not depend on
        // the order of the pair.
        Vec3 witnesses[2];
        triangles_intersect(ta, tb, &witnesses[0]);
        witnesses[1] = witnesses[0];
        triangles_intersect(tb, ta, &witnesses[1]);
        const Vec3 na = cross(ta[1] - ta[0], ta[2] - ta[0]);
        const Vec3 nb = cross(tb[1] - tb[0], tb[2] - tb[0]);
        const double la = norm(na), lb = norm(nb);
        if (!(la > 0.0 && lb > 0.0)) return;
        const double h = std::fmin(longest_edge(ta), longest_edge(tb));
        const Vec3 centroid_a = (ta[0] + ta[1] + ta[2]) / 3.0;
        const Vec3 centroid_b = (tb[0] + tb[1] + tb[2]) / 3.0;
        for (double step : {0.5 * h, 0.125 * h, 0.03125 * h}) {
            // Each triangle's centroid, stepped into its own solid: finds coincident and
            // coplanar overlaps, whose shared points all lie on edges of both.
            out.push_back({centroid_a - na * (step / la), 0.0, 2, false});
            out.push_back({centroid_b - nb * (step / lb), 0.0, 2, false});
        }
        const Vec3 sum = na / la + nb / lb;
        const double ls = norm(sum);
        if (!(ls > 1e-6)) return;  // opposite normals: faces resting on each other
        const Vec3 inward = sum * (-1.0 / ls);
        for (const Vec3& witness : witnesses)
            for (double step : {0.5 * h, 0.125 * h, 0.03125 * h})
                out.push_back({witness + inward * step, 0.0, 2, false});
    }
}

void add_wedge_candidates(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                          const std::vector<CrossingPair>& pairs, std::vector<DepthCandidate>& out) {
    const size_t stride = wedge_stride(pairs);
    for (size_t k = 0; k < pairs.size(); k += stride) add_pair_wedge_points(a, b, rel, pairs, k, out);
}

// The midpoints of the pieces of [p, q] between the sorted parameters `cuts` (0 and 1 among
// them), passed to `add`.
template <class Add>
void add_pieces(const Vec3& p, const Vec3& q, std::vector<double>& cuts, Add add) {
    std::sort(cuts.begin(), cuts.end());
    for (size_t c = 0; c + 1 < cuts.size(); ++c)
        if (cuts[c + 1] > cuts[c]) add(p + (q - p) * (0.5 * (cuts[c] + cuts[c + 1])));
}

// The midpoints of the pieces into which other's surface cuts the segment [p, q] (other's
// frame), passed to `add`; `cuts` is scratch space.
template <class Add>
void add_edge_pieces(const MeshBvh& other, const Vec3& p, const Vec3& q, std::vector<double>& cuts, Add add) {
    cuts.assign({0.0, 1.0});
    segment_crossings(other, p, q, cuts);
    add_pieces(p, q, cuts, add);
}

// Sample points of `self` (their frame mapped into `other`'s by `to_other`) that may lie
// inside `other`: vertices within other's root box, and midpoints of the pieces into which the
// other surface cuts the edges of self's crossing triangles.
template <class Map>
void add_candidates(const MeshBvh& self, const MeshBvh& other, const std::vector<char>& crossing,
                    Map to_other, int mesh, std::vector<DepthCandidate>& out) {
    const BvhNode& root = other.nodes()[0];
    auto add = [&](const Vec3& p) {
        if (inside_box(root, p)) out.push_back({p, 0.0, mesh, false});
    };
    for (const Vec3& v : self.vertices()) add(to_other(v));
    std::vector<double> cuts;
    for (std::int32_t i = 0; i < self.triangle_count(); ++i) {
        if (!crossing[static_cast<size_t>(i)]) continue;
        const Vec3* t = self.triangle(i);
        for (int k = 0; k < 3; ++k) {
            add_edge_pieces(other, to_other(t[k]), to_other(t[(k + 1) % 3]), cuts, add);
        }
    }
}

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

}  // namespace

PointDistanceOutput closest_point(const MeshBvh& mesh, const Vec3& point) {
    PointDistanceOutput out;
    if (!mesh.valid() || !is_finite(point)) {
        out.distance = kNaN;
        out.point = Vec3{kNaN, kNaN, kNaN};
        return out;
    }
    const std::vector<BvhNode>& nodes = mesh.nodes();
    double best2 = kInf;
    std::int32_t best_triangle = -1;
    Vec3 best_point;
    std::vector<std::pair<std::int32_t, double>> stack;
    stack.reserve(64);
    stack.push_back({0, point_node_squared_distance(mesh, 0, point)});
    while (!stack.empty()) {
        const auto [index, bound] = stack.back();
        stack.pop_back();
        // Until a first triangle is measured nothing is pruned (an overflowing inf bound).
        const bool found = best_triangle >= 0;
        if (found && bound >= best2) continue;
        const BvhNode& node = nodes[static_cast<size_t>(index)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const Vec3 q = closest_point_on_triangle(point, mesh.triangle(i));
                const double d2 = squared_norm(q - point);
                if (best_triangle < 0 || d2 < best2) {
                    best2 = d2;
                    best_point = q;
                    best_triangle = i;
                }
            }
            continue;
        }
        push_children(mesh, index, point, found, best2, stack);
    }
    out.distance = std::sqrt(best2);
    out.point = best_point;
    out.triangle = mesh.face_index(best_triangle);
    return out;
}

double winding_number(const MeshBvh& mesh, const Vec3& point) {
    double total = 0.0;
    const std::int32_t n = mesh.triangle_count();
    for (std::int32_t i = 0; i < n; ++i) total += triangle_solid_angle(mesh.triangle(i), point);
    return total / (4.0 * kPi);
}

namespace {

// The order-2 far-field expansion of node `w` seen from `point`, and the bound of its
// remainder, both over 4 pi (winding-number units); false when the point is too near
// (distance to the centre at most twice the radius) or the figures are not finite.
// With v = center - point, rho = |v|: the solid angle of the node's triangles is the
// integral of (x - point) . n / |x - point|^3 over them; its Taylor expansion about the centre
// gives v . N / rho^3 (dipole) + (tr M - 3 v^T M v / rho^2) / rho^3 (first moment M), and the
// remainder is at most (1/2) (6 / (rho - radius)^4) radius^2 area.
inline bool far_field(const WindingNode& w, const Vec3& point, double* value, double* error) {
    const Vec3 v = w.center - point;
    const double rho2 = dot(v, v);
    if (!(rho2 > 4.0 * w.radius * w.radius)) return false;
    const double rho = std::sqrt(rho2);
    const double inv3 = 1.0 / (rho2 * rho);
    const double* m = w.moment;
    const double trace = m[0] + m[1] + m[2];
    const double vmv = v.x * v.x * m[0] + v.y * v.y * m[1] + v.z * v.z * m[2] +
                       2.0 * (v.x * v.y * m[3] + v.y * v.z * m[4] + v.z * v.x * m[5]);
    const double gap = rho - w.radius;
    const double gap2 = gap * gap;
    *value = (dot(v, w.dipole) + trace - 3.0 * vmv / rho2) * inv3 / (4.0 * kPi);
    *error = 3.0 * w.radius * w.radius * w.area / (gap2 * gap2) / (4.0 * kPi) * (1.0 + 1e-9);
    return std::isfinite(*value) && std::isfinite(*error);
}

struct OpenNode {
    double error;
    double value;
    std::int32_t node;
    bool operator<(const OpenNode& o) const { return error < o.error; }
};

// The refinement behind fast_winding_number and winding_number_inside: far nodes in a max-heap
// by their bound, opened until `enough(value, error)`.
template <class Enough>
WindingEstimate refine_winding_number(const MeshBvh& mesh, const Vec3& point, Enough enough) {
    WindingEstimate out;
    if (!is_finite(point) || !mesh.valid()) {
        out.value = out.error = kNaN;
        return out;
    }
    const std::vector<BvhNode>& nodes = mesh.nodes();
    const std::vector<WindingNode>& far = mesh.winding_nodes();
    std::vector<OpenNode> heap;
    std::vector<std::int32_t> near;
    double exact = 0.0;  // solid angles summed exactly, steradians
    double approx = 0.0, error = 0.0;  // far-field sums, winding-number units
    // Adds node `id`: far, into the heap; near, its children (or its triangles, for a leaf).
    auto open = [&](std::int32_t id) {
        near.push_back(id);
        while (!near.empty()) {
            const std::int32_t k = near.back();
            near.pop_back();
            double value, bound;
            if (far_field(far[static_cast<size_t>(k)], point, &value, &bound)) {
                ++out.visits;
                approx += value;
                error += bound;
                heap.push_back({bound, value, k});
                std::push_heap(heap.begin(), heap.end());
                continue;
            }
            const BvhNode& node = nodes[static_cast<size_t>(k)];
            if (node.is_leaf()) {
                for (std::int32_t i = node.index; i < node.index + node.count; ++i)
                    exact += triangle_solid_angle(mesh.triangle(i), point);
                out.visits += node.count;
                continue;
            }
            near.push_back(node.index);
            near.push_back(k + 1);
        }
    };
    open(0);
    while (!heap.empty() && !enough(exact / (4.0 * kPi) + approx, error)) {
        std::pop_heap(heap.begin(), heap.end());
        const OpenNode top = heap.back();
        heap.pop_back();
        approx -= top.value;
        error -= top.error;
        const BvhNode& node = nodes[static_cast<size_t>(top.node)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i)
                exact += triangle_solid_angle(mesh.triangle(i), point);
            out.visits += node.count;
        } else {
            open(top.node + 1);
            open(node.index);
        }
    }
    if (heap.empty()) {
        // Every triangle summed: drop the residue the subtractions left.
        approx = 0.0;
        error = 0.0;
    }
    out.value = exact / (4.0 * kPi) + approx;
    // The running total of the bounds lost digits to the subtractions: recount it.
    if (!heap.empty()) {
        error = 0.0;
        for (const OpenNode& o : heap) error += o.error;
    }
    out.error = error;
    return out;
}

}  // namespace

WindingEstimate fast_winding_number(const MeshBvh& mesh, const Vec3& point, double max_error) {
    return refine_winding_number(mesh, point, [max_error](double, double error) { return error <= max_error; });
}

bool winding_number_inside(const MeshBvh& mesh, const Vec3& point, long long* work) {
    constexpr double threshold = defaults::winding_number_inside;
    // Decided once the interval [value - error, value + error] of the winding number clears
    // both thresholds +-0.5 by more than the rounding of the sums (1e-9, far above the
    // 1e-16 * F of a mesh's exact sum).
    const WindingEstimate w = refine_winding_number(mesh, point, [](double value, double error) {
        const double margin = std::fabs(std::fabs(value) - threshold);
        return margin > error + 1e-9;
    });
    if (work != nullptr) *work += w.visits;
    return std::fabs(w.value) >= threshold;
}

bool mesh_intersects(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b) {
    return for_each_touching_pair(a, b, Relative(pose_a, pose_b, a, b), [](std::int32_t, std::int32_t, const Vec3* ta, const Vec3* tb) {
        return triangles_intersect(ta, tb, nullptr);
    });
}

bool mesh_pair_in_range(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b,
                        const Pose& pose_b) {
    // The reach of each mesh about its origin (the far corner of its root box), kept at build.
    double half = 0.5 * max2(a.box_reach(), b.box_reach());
    rescale::reach(half, pose_a.translation, pose_b.translation);
    return std::isfinite(half) && (half == 0.0 || (2.0 * half >= rescale::kSafeLow &&
                                                   2.0 * half <= rescale::kSafeHigh));
}

MeshDistanceOutput mesh_distance(const MeshDistanceInput& input) {
    MeshDistanceOutput out;
    const Vec3 nan3{kNaN, kNaN, kNaN};
    if (input.a == nullptr || input.b == nullptr || !input.a->valid() || !input.b->valid() ||
        !(input.max_distance >= 0.0)) {
        out.distance = kNaN;
        out.point_a = out.point_b = nan3;
        out.status = Status::INVALID_INPUT;
        return out;
    }
    if (!mesh_pair_in_range(*input.a, input.pose_a, *input.b, input.pose_b)) {
        out.distance = kNaN;
        out.point_a = out.point_b = nan3;
        out.status = Status::OUT_OF_RANGE;
        return out;
    }
    const MeshBvh& a = *input.a;
    const MeshBvh& b = *input.b;
    const Relative rel(input.pose_a, input.pose_b, *input.a, *input.b);
    const double bound2 = input.max_distance * input.max_distance;
    // Crossing surfaces are found sooner by the intersection descent, which tests triangle
    // pairs whose boxes touch and measures nothing, than by the distance search, which measures
    // every near triangle pair on its way to the first crossing one.
    SearchResult r;
    const bool crossed = for_each_touching_pair(a, b, rel, [&r](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) {
        Vec3 w;
        if (!triangles_intersect(ta, tb, &w)) return false;
        r.found = r.intersecting = true;
        r.squared_distance = 0.0;
        r.point_a = r.point_b = w;
        r.triangle_a = i;
        r.triangle_b = j;
        return true;
    });
    if (!crossed) r = search_distance(a, b, rel, bound2);
    if (r.found) {
        out.distance = std::sqrt(r.squared_distance);
        out.point_a = input.pose_a.apply(r.point_a);
        out.point_b = r.intersecting ? out.point_a : input.pose_a.apply(r.point_b);
        out.intersecting = r.intersecting || r.squared_distance == 0.0;
        out.triangle_a = a.face_index(r.triangle_a);
        out.triangle_b = b.face_index(r.triangle_b);
    } else {
        out.distance = kInf;
        out.point_a = out.point_b = nan3;
    }
    // Nothing found within an infinite radius: the squared distances overflowed (coordinates
    // beyond about 1e154); the distance is only known to be huge.
    const bool overflowed = !std::isfinite(out.distance) && std::isinf(input.max_distance);
    if (!out.intersecting) {
        // Disjoint surfaces: each mesh is wholly inside or wholly outside the other, so one
        // vertex decides (Jacobson et al. 2013). Its distance to the other surface is at least
        // `distance` > 0, which keeps the winding number away from its jump.
        out.a_inside_b = point_inside(b, input.pose_b, input.pose_a.apply(a.triangle(0)[0]));
        out.b_inside_a = point_inside(a, input.pose_a, input.pose_b.apply(b.triangle(0)[0]));
    }
    out.status = overflowed ? Status::DEGENERATE : Status::CONVERGED;
    return out;
}

namespace {

// Distance from `point` (mesh's local frame) to the surface when it exceeds `floor`; otherwise
// some value <= floor: the branch and bound of closest_point, stopped at the first triangle
// within `floor` (such a point cannot raise a maximum that is already `floor`). Writes the
// triangle (leaf order) at the returned distance to `*triangle` when given.
double distance_beyond(const MeshBvh& mesh, const Vec3& point, double floor, std::int32_t* triangle = nullptr) {
    const double floor2 = floor * floor;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    double best2 = kInf;
    bool found = false;
    std::vector<std::pair<std::int32_t, double>> stack;
    stack.reserve(64);
    stack.push_back({0, point_node_squared_distance(mesh, 0, point)});
    while (!stack.empty()) {
        const auto [index, bound] = stack.back();
        stack.pop_back();
        if (found && bound >= best2) continue;
        const BvhNode& node = nodes[static_cast<size_t>(index)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const double d2 = squared_norm(closest_point_on_triangle(point, mesh.triangle(i)) - point);
                if (!found || d2 < best2) {
                    best2 = d2;
                    found = true;
                    if (triangle != nullptr) *triangle = i;
                }
            }
            if (best2 <= floor2) break;
            continue;
        }
        push_children(mesh, index, point, found, best2, stack);
    }
    return std::sqrt(best2);
}

// An upper bound of the distance from `point` (mesh's local frame) to the surface, within
// `slack` of it: the branch and bound of distance_beyond with boxes pruned once they cannot
// beat the best distance found by more than `slack`, stopped as it at a triangle within
// `floor`. Writes the triangle (leaf order) at the returned distance to `*triangle`.
double distance_within(const MeshBvh& mesh, const Vec3& point, double floor, double slack, std::int32_t* triangle) {
    const double floor2 = floor * floor;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    double best = kInf, prune2 = kInf;
    bool found = false;
    std::vector<std::pair<std::int32_t, double>> stack;
    stack.reserve(64);
    stack.push_back({0, point_node_squared_distance(mesh, 0, point)});
    while (!stack.empty()) {
        const auto [index, bound] = stack.back();
        stack.pop_back();
        if (found && bound >= prune2) continue;
        const BvhNode& node = nodes[static_cast<size_t>(index)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const double d2 = squared_norm(closest_point_on_triangle(point, mesh.triangle(i)) - point);
                if (!found || d2 < best * best) {
                    best = std::sqrt(d2);
                    const double reach = max2(0.0, best - slack);
                    prune2 = reach * reach;
                    found = true;
                    *triangle = i;
                }
            }
            if (best * best <= floor2) break;
            continue;
        }
        push_children(mesh, index, point, found, prune2, stack);
    }
    return best;
}

// The depth search over the points of a mesh whose other mesh is closed. The winding number
// of a closed surface is constant along a path that does not meet it (Jacobson et al. 2013),
// so the vertices joined by edges of triangles that are not near the other surface (farther
// than the rounding allowance) form regions lying wholly inside or wholly outside: one exact
// test decides each region (none when a vertex lies outside the other's box), and only the
// vertices of near triangles are decided one by one. The largest distance among the inside
// points is then found by branch and bound, as a one-sided Hausdorff distance over a
// hierarchy: a node of a mesh's own hierarchy bounds the distances of its triangles' corners
// by the distance of its centre plus its radius (the distance to a surface is 1-Lipschitz),
// a piece of an edge of a crossing triangle by the distance of its ends to a triangle it
// crosses (the distance to a triangle is convex along a segment), a wedge point by its
// distances to the pair it steps in from; groups are opened highest bound first until no
// bound exceeds the best depth found. The answer is the maximum, over the same points as the
// per-point search, of the same distances: only its order of work differs.
class ClosedDepthSearch {
public:
    ClosedDepthSearch(const MeshBvh& a, const MeshBvh& b, const Relative& rel, MeshDepthOutput& out)
        : a_(a), b_(b), rel_(rel), out_(out), slack_(8.0 * rel.slack) {}

    // Adds the points of mesh m (0: a's, in b's frame; 1: b's, in a's frame): its regions
    // decided, its root node and the edges of its crossing triangles queued. False when the
    // work cap stopped it.
    bool add_mesh(int m, const TriangleMarks& marks) {
        marks_[m] = &marks;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const BvhNode& root = other.nodes()[0];
        const std::vector<Vec3>& vertices = self.vertices();
        const size_t vertex_count = vertices.size();
        std::vector<Side>& side = side_[m];
        side.assign(vertex_count, Side::UNKNOWN);
        done_[m].assign(vertex_count, 0);
        std::vector<char> in_box(vertex_count), regular(vertex_count, 0);
        std::vector<std::int32_t> parent(vertex_count);
        for (size_t v = 0; v < vertex_count; ++v) {
            in_box[v] = inside_box(root, to_other(m, vertices[v]));
            parent[v] = static_cast<std::int32_t>(v);
        }
        auto find = [&parent](std::int32_t v) {
            while (parent[static_cast<size_t>(v)] != v) {
                parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
                v = parent[static_cast<size_t>(v)];
            }
            return v;
        };
        // Triangles wholly outside the box are left out: a region of the others reaches
        // outside through a triangle with a corner in the box, so the regions found are parts
        // of the true ones, each still on one side.
        for (std::int32_t i = 0; i < self.triangle_count(); ++i) {
            if (marks.near[static_cast<size_t>(i)]) continue;
            const std::int32_t* t = self.triangle_vertices(i);
            if (!in_box[static_cast<size_t>(t[0])] && !in_box[static_cast<size_t>(t[1])] && !in_box[static_cast<size_t>(t[2])])
                continue;
            regular[static_cast<size_t>(t[0])] = regular[static_cast<size_t>(t[1])] = regular[static_cast<size_t>(t[2])] = 1;
            for (int k = 0; k < 2; ++k) {  // two edges join the three corners
                const std::int32_t x = find(t[k]), y = find(t[k + 1]);
                if (x != y) parent[static_cast<size_t>(std::max(x, y))] = std::min(x, y);
            }
        }
        // A region with a vertex outside the other's box is outside; otherwise one vertex
        // (off the surface by more than the rounding allowance) decides it.
        std::vector<Side> region(vertex_count, Side::UNKNOWN);
        for (size_t v = 0; v < vertex_count; ++v)
            if (regular[v] && !in_box[v]) region[static_cast<size_t>(find(static_cast<std::int32_t>(v)))] = Side::OUTSIDE;
        for (size_t v = 0; v < vertex_count; ++v) {
            if (!in_box[v]) {
                side[v] = Side::OUTSIDE;
                continue;
            }
            if (!regular[v]) continue;  // decided alone, when it matters
            Side& r = region[static_cast<size_t>(find(static_cast<std::int32_t>(v)))];
            if (r == Side::UNKNOWN) {
                if (!may_test()) return false;
                r = inside_mesh(other, to_other(m, vertices[v]), &work_) ? Side::INSIDE : Side::OUTSIDE;
            }
            side[v] = r;
        }
        // Nodes holding a corner that may be inside.
        const std::vector<BvhNode>& nodes = self.nodes();
        std::vector<char>& live = live_[m];
        live.assign(nodes.size(), 0);
        for (size_t id = nodes.size(); id-- > 0;) {
            const BvhNode& node = nodes[id];
            if (!node.is_leaf()) {
                live[id] = live[id + 1] || live[static_cast<size_t>(node.index)];
                continue;
            }
            for (std::int32_t i = node.index; i < node.index + node.count && !live[id]; ++i)
                for (int k = 0; k < 3; ++k)
                    if (side[static_cast<size_t>(self.triangle_vertices(i)[k])] != Side::OUTSIDE) live[id] = 1;
        }
        if (live[0]) refine_node({kInf, kNode, m, 0, 0});
        return true;
    }

    // Queues the edges of mesh m's crossing triangles, each bounded by its ends' distances to
    // a triangle that its triangle crosses (after the vertices: most are then within the best
    // depth already and never queued).
    void add_edges(int m) {
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const TriangleMarks& marks = *marks_[m];
        for (std::int32_t i = 0; i < self.triangle_count(); ++i) {
            const std::int32_t partner = marks.partner[static_cast<size_t>(i)];
            if (!marks.crossing[static_cast<size_t>(i)] || partner < 0) continue;
            const Vec3* t = self.triangle(i);
            const Vec3* tp = other.triangle(partner);
            double ends[3];
            for (int k = 0; k < 3; ++k) ends[k] = triangle_distance_of(to_other(m, t[k]), tp);
            for (int k = 0; k < 3; ++k) push({max2(ends[k], ends[(k + 1) % 3]) + slack_, kEdge, m, i, k});
        }
    }

    // Queues the wedge points (both meshes closed) of each crossing pair that gets them, made
    // when the pair comes up. Every one lies within the pair's reach of a's centroid q: a
    // step of at most h / 2 from q, b's centroid or a shared point, which lies on an edge of
    // one of the triangles (triangles_intersect's witnesses), so no farther from q than their
    // farthest corner. Its depth is then at most q's distances to the two triangles plus that.
    void add_wedges(const std::vector<CrossingPair>& pairs) {
        pairs_ = &pairs;
        const size_t stride = wedge_stride(pairs);
        for (size_t k = 0; k < pairs.size(); k += stride) {
            const Vec3* ta = a_.triangle(pairs[k].a);
            const Vec3* tb_local = b_.triangle(pairs[k].b);
            const Vec3 tb[3] = {rel_.apply(tb_local[0]), rel_.apply(tb_local[1]), rel_.apply(tb_local[2])};
            const Vec3 q = (ta[0] + ta[1] + ta[2]) / 3.0;
            double reach = norm((tb[0] + tb[1] + tb[2]) / 3.0 - q);
            for (int i = 0; i < 3; ++i) reach = max2(reach, max2(norm(ta[i] - q), norm(tb[i] - q)));
            reach += 0.5 * std::fmin(longest_edge(ta), longest_edge(tb));
            const double da = triangle_distance_of(q, ta);
            const double db = triangle_distance_of(rel_.apply_inverse(q), tb_local);
            push({max2(da, db) + reach * (1.0 + 1e-9) + slack_, kWedge, 2, static_cast<std::int32_t>(k), 0});
        }
    }

    // Opens the queue highest bound first until no bound exceeds the best depth. False when
    // the work cap stopped it.
    bool run() {
        std::vector<double> cuts;
        while (!heap_.empty()) {
            std::pop_heap(heap_.begin(), heap_.end());
            const Entry e = heap_.back();
            heap_.pop_back();
            if (!(e.bound > best)) break;
            bool ok = true;
            if (e.kind == kNode) {
                // A leaf whose bound is already within twice its radius of the best depth has
                // its few corners measured directly (each search cut off at the best depth,
                // mostly at its first leaf): cheaper than refining a deep centre's bound.
                if (e.refined || direct_leaf(e)) {
                    ok = open_node(e);
                } else {
                    refine_node(e);
                }
            } else if (e.kind == kEdge) {
                const MeshBvh& self = e.mesh == 0 ? a_ : b_;
                const MeshBvh& other = e.mesh == 0 ? b_ : a_;
                const BvhNode& root = other.nodes()[0];
                const Vec3* t = self.triangle(e.index);
                std::int64_t piece = 0;
                // The triangles the edge meets are near its triangle (the marks' margin is far
                // above the rounding of the frames): the cuts of segment_crossings, found
                // among those alone.
                const Vec3 p = to_other(e.mesh, t[e.k]), q = to_other(e.mesh, t[(e.k + 1) % 3]);
                const TriangleMarks& marks = *marks_[e.mesh];
                cuts.assign({0.0, 1.0});
                for (std::int32_t n = marks.first[static_cast<size_t>(e.index)]; n < marks.first[static_cast<size_t>(e.index) + 1]; ++n) {
                    double cut = 0.0;
                    if (segment_crosses_triangle(p, q, other.triangle(marks.others[static_cast<size_t>(n)]), &cut))
                        cuts.push_back(cut);
                }
                add_pieces(p, q, cuts,
                                [&](const Vec3& p) {
                                    const Order order{e.mesh, 1, 3 * std::int64_t{e.index} + e.k, piece++};
                                    if (ok && inside_box(root, p)) ok = try_point(e.mesh, p, Side::UNKNOWN, nullptr, order);
                                });
            } else {
                wedges_.clear();
                add_pair_wedge_points(a_, b_, rel_, *pairs_, static_cast<size_t>(e.index), wedges_);
                for (size_t k = 0; k < wedges_.size() && ok; ++k)
                    ok = try_wedge(wedges_[k], Order{2, e.index, static_cast<std::int64_t>(k), 0});
            }
            if (!ok) return false;
        }
        return true;
    }

    double best = 0.0;
    bool have = false;
    DepthCandidate winner{};
    // The other mesh's triangle (leaf order) nearest a vertex or edge winner, found by the
    // search that measured it (closest_point's, uncut), else -1.
    std::int32_t winner_triangle = -1;
    long long work() const { return work_; }

private:
    enum class Side : signed char { OUTSIDE, INSIDE, UNKNOWN };
    // A point's place in the per-point search's order: mesh (0, 1, 2: wedges), then its
    // vertices before its edge pieces (0, 1), then vertex, 3 * triangle + edge, or wedge
    // point, then the piece along the edge.
    struct Order {
        std::int64_t mesh, group, index, piece;
        bool operator<(const Order& o) const {
            return std::tie(mesh, group, index, piece) < std::tie(o.mesh, o.group, o.index, o.piece);
        }
    };
    static constexpr int kNode = 0, kEdge = 1, kWedge = 2;
    struct Entry {
        double bound;  // no point of the group is farther than this from the other surface
        int kind, mesh;
        std::int32_t index;  // node, triangle (leaf order) or crossing pair (wedge points)
        int k;               // edge k of the triangle
        // A node: a triangle of the other mesh (leaf order) near it, and whether `bound` comes
        // from its centre's distance (else from its distance to `near`, a looser bound).
        std::int32_t near = -1;
        bool refined = false;
        bool operator<(const Entry& o) const { return bound < o.bound; }
    };

    Vec3 to_other(int m, const Vec3& p) const { return m == 0 ? rel_.apply_inverse(p) : rel_.apply(p); }

    static double triangle_distance_of(const Vec3& p, const Vec3* t) {
        return std::sqrt(squared_norm(closest_point_on_triangle(p, t) - p));
    }

    void push(const Entry& e) {
        if (!(e.bound > best)) return;
        heap_.push_back(e);
        std::push_heap(heap_.begin(), heap_.end());
    }

    // Child `id` of mesh m's node whose other-mesh triangle is `near`: first bounded by its
    // centre's distance to that triangle, plus its radius (refined when it comes up).
    void push_node(int m, std::int32_t id, std::int32_t near) {
        if (!live_[m][static_cast<size_t>(id)]) return;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const WindingNode& w = self.winding_nodes()[static_cast<size_t>(id)];
        const double d = triangle_distance_of(to_other(m, w.center), other.triangle(near));
        push({d + w.radius + slack_, kNode, m, id, 0, near, false});
    }

    // The node bounded by its centre's distance to the other surface (a search cut off once
    // the bound cannot beat the best) plus its radius, queued again.
    void refine_node(const Entry& e) {
        const MeshBvh& self = e.mesh == 0 ? a_ : b_;
        const MeshBvh& other = e.mesh == 0 ? b_ : a_;
        const WindingNode& w = self.winding_nodes()[static_cast<size_t>(e.index)];
        const double floor = best - w.radius - slack_;
        std::int32_t near = 0;
        const Vec3 center = to_other(e.mesh, w.center);
        double d = distance_within(other, center, max2(0.0, floor), w.radius, &near);
        if (e.near >= 0) {  // the parent's triangle may be nearer than the one found
            const double parent = triangle_distance_of(center, other.triangle(e.near));
            if (parent < d) {
                d = parent;
                near = e.near;
            }
        }
        if (d <= floor) return;
        push({d + w.radius + slack_, kNode, e.mesh, e.index, 0, near, true});
    }

    bool direct_leaf(const Entry& e) const {
        const MeshBvh& self = e.mesh == 0 ? a_ : b_;
        const auto id = static_cast<size_t>(e.index);
        return self.nodes()[id].is_leaf() && have && e.bound <= best + 2.0 * self.winding_nodes()[id].radius;
    }

    bool open_node(const Entry& e) {
        const int m = e.mesh;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const BvhNode& node = self.nodes()[static_cast<size_t>(e.index)];
        if (!node.is_leaf()) {
            push_node(m, e.index + 1, e.near);
            push_node(m, node.index, e.near);
            return true;
        }
        const Vec3* near = other.triangle(e.near);
        for (std::int32_t i = node.index; i < node.index + node.count; ++i)
            for (int k = 0; k < 3; ++k) {
                const std::int32_t v = self.triangle_vertices(i)[k];
                char& done = done_[m][static_cast<size_t>(v)];
                if (done) continue;
                done = 1;
                Side& side = side_[m][static_cast<size_t>(v)];
                if (side == Side::OUTSIDE) continue;
                const Vec3 p = to_other(m, self.vertices()[static_cast<size_t>(v)]);
                // Bounded by the node's triangle and by the triangles near its own; a point at
                // distance 0 from one (on the surface: the search would find 0) gives nothing.
                double bound = triangle_distance_of(p, near);
                const TriangleMarks& marks = *marks_[m];
                for (std::int32_t n = marks.first[static_cast<size_t>(i)]; n < marks.first[static_cast<size_t>(i) + 1] && bound > 0.0; ++n)
                    bound = min2(bound, triangle_distance_of(p, other.triangle(marks.others[static_cast<size_t>(n)])));
                if (bound == 0.0 || !(bound + slack_ > best)) continue;
                if (!try_point(m, p, side, &side, Order{m, 0, v, 0})) return false;
            }
        return true;
    }

    // Whether a point at distance d, `order` in the per-point search, would have replaced the
    // best there: deeper, or as deep and sampled before it (so that the deepest point, and
    // thus the witnesses, are the same whatever the order of work). A distance equal to the
    // best that came from a search cut off at it (at most the best) is measured in full.
    template <class Full>
    bool beats(double& d, const Order& order, Full full) const {
        if (d > best) return true;
        if (!(have && d == best && order < winner_order_)) return false;
        d = full();
        return d == best;
    }

    // A point of mesh m (other's frame) whose side is `known` (UNKNOWN: an exact test, its
    // verdict stored in `*store` when given): the new best when inside and deeper.
    bool try_point(int m, const Vec3& p, Side known, Side* store, const Order& order) {
        const MeshBvh& other = m == 0 ? b_ : a_;
        std::int32_t triangle = -1;
        double d = distance_beyond(other, p, best, &triangle);
        if (!beats(d, order, [&] { return distance_beyond(other, p, 0.0, &triangle); })) return true;
        if (known == Side::UNKNOWN) {
            if (!may_test()) return false;
            known = inside_mesh(other, p, &work_) ? Side::INSIDE : Side::OUTSIDE;
            if (store != nullptr) *store = known;
        }
        if (known == Side::INSIDE) {
            best = d;
            winner = {p, d, m, false};
            winner_triangle = triangle;
            winner_order_ = order;
            have = true;
        }
        return true;
    }

    bool try_wedge(DepthCandidate& c, const Order& order) {
        // Outside a closed mesh's box is outside it (the test's verdict, without its work).
        const Vec3 in_b = rel_.apply_inverse(c.point);
        if (!inside_box(a_.nodes()[0], c.point) || !inside_box(b_.nodes()[0], in_b)) return true;
        auto measure = [&](double floor) {
            const double da = distance_beyond(a_, c.point, floor);
            const double db = distance_beyond(b_, rel_.apply_inverse(c.point), floor);
            c.farther_is_a = da >= db;
            return std::fmax(da, db);
        };
        c.distance = measure(best);
        if (!beats(c.distance, order, [&] { return measure(0.0); })) return true;
        if (!may_test()) return false;
        if (inside_mesh(a_, c.point, &work_) && inside_mesh(b_, in_b, &work_)) {
            best = c.distance;
            winner = c;
            winner_triangle = -1;
            winner_order_ = order;
            have = true;
        }
        return true;
    }

    // Counts one exact inside test, or stops at the work cap.
    bool may_test() {
        if (work_ > defaults::mesh_depth_max_work) {
            out_.status = Status::MAX_ITERATIONS;
            return false;
        }
        ++out_.points_tested;
        return true;
    }

    const MeshBvh& a_;
    const MeshBvh& b_;
    const Relative& rel_;
    MeshDepthOutput& out_;
    double slack_;  // allowance for rounding in the distance bounds (absolute)
    long long work_ = 0;
    std::vector<Side> side_[2];
    std::vector<char> done_[2];
    std::vector<char> live_[2];
    const TriangleMarks* marks_[2] = {nullptr, nullptr};
    const std::vector<CrossingPair>* pairs_ = nullptr;
    std::vector<DepthCandidate> wedges_;  // scratch: one pair's wedge points
    std::vector<Entry> heap_;
    Order winner_order_{};
};

}  // namespace

MeshDepthOutput mesh_penetration_depth(const MeshDistanceInput& input) {
    MeshDepthOutput out;
    const Vec3 nan3{kNaN, kNaN, kNaN};
    out.point_a = out.point_b = out.normal = nan3;
    if (input.a == nullptr || input.b == nullptr || !input.a->valid() || !input.b->valid()) {
        out.depth = kNaN;
        out.status = Status::INVALID_INPUT;
        return out;
    }
    const MeshBvh& a = *input.a;
    const MeshBvh& b = *input.b;
    const Relative rel(input.pose_a, input.pose_b, *input.a, *input.b);  // b's frame -> a's frame
    TriangleMarks marks_a, marks_b;
    std::vector<CrossingPair> crossing_pairs;
    mark_crossing_triangles(a, b, rel, marks_a, marks_b, crossing_pairs);

    // The points of a mesh whose other mesh is closed: regions and branch and bound.
    out.status = Status::CONVERGED;
    ClosedDepthSearch search(a, b, rel, out);
    const bool closed_other[2] = {b.closed(), a.closed()};
    bool running = true;
    for (int m = 0; m < 2 && running; ++m)
        if (closed_other[m]) running = search.add_mesh(m, m == 0 ? marks_a : marks_b);
    if (running) running = search.run();  // the vertices first: a best depth to prune with
    for (int m = 0; m < 2 && running; ++m)
        if (closed_other[m]) search.add_edges(m);
    const bool wedges_closed = a.closed() && b.closed();
    if (running && wedges_closed) search.add_wedges(crossing_pairs);
    if (running) running = search.run();
    double best = search.best;
    bool have = search.have;
    DepthCandidate winner = search.winner;
    std::int32_t winner_triangle = search.winner_triangle;
    long long work = search.work();

    // Open meshes: the generalized winding number costs a pass over the triangles, so the
    // distances come first and the points are decided deepest first, the first inside one
    // ending the search; a point found outside at distance d proves every point within d of
    // it outside (that ball holds no surface), which skips most of a cluster.
    std::vector<DepthCandidate> undecided;
    if (running) {
        if (!closed_other[0])
            add_candidates(a, b, marks_a.crossing, [&](const Vec3& p) { return rel.apply_inverse(p); }, 0, undecided);
        if (!closed_other[1])
            add_candidates(b, a, marks_b.crossing, [&](const Vec3& p) { return rel.apply(p); }, 1, undecided);
        if (!wedges_closed) add_wedge_candidates(a, b, rel, crossing_pairs, undecided);
    }
    auto inside = [&](const DepthCandidate& c) {
        if (c.mesh == 0) return inside_mesh(b, c.point, &work);
        if (c.mesh == 1) return inside_mesh(a, c.point, &work);
        return inside_mesh(a, c.point, &work) && inside_mesh(b, rel.apply_inverse(c.point), &work);
    };
    // The depth a candidate gives (exact when it exceeds `floor`): its distance to the other
    // surface; for a wedge point, to the farther of the two (`farther_is_a`).
    auto measure = [&](DepthCandidate& c, double floor) {
        if (c.mesh < 2) {
            c.distance = distance_beyond(c.mesh == 0 ? b : a, c.point, floor);
            return;
        }
        const double da = distance_beyond(a, c.point, floor);
        const double db = distance_beyond(b, rel.apply_inverse(c.point), floor);
        c.distance = std::fmax(da, db);
        c.farther_is_a = da >= db;
    };
    if (out.status == Status::CONVERGED && !undecided.empty()) {
        for (DepthCandidate& c : undecided) measure(c, best);
        undecided.erase(std::remove_if(undecided.begin(), undecided.end(),
                                       [best](const DepthCandidate& c) { return !(c.distance > best); }),
                        undecided.end());
        std::sort(undecided.begin(), undecided.end(),
                  [](const DepthCandidate& x, const DepthCandidate& y) { return x.distance > y.distance; });
        std::vector<std::pair<Vec3, double>> outside[2];
        constexpr size_t kBallsChecked = 256;
        for (const DepthCandidate& c : undecided) {
            if (c.mesh < 2) {
                const auto& balls = outside[c.mesh];
                bool known_outside = false;
                for (size_t k = balls.size(); k-- > 0 && balls.size() - k <= kBallsChecked;)
                    if (squared_norm(c.point - balls[k].first) < balls[k].second * balls[k].second) {
                        known_outside = true;
                        break;
                    }
                if (known_outside) continue;
            }
            if (work > defaults::mesh_depth_max_work) {
                out.status = Status::MAX_ITERATIONS;
                break;
            }
            ++out.points_tested;
            if (inside(c)) {
                best = c.distance;
                winner = c;
                winner_triangle = -1;
                have = true;
                break;
            }
            if (c.mesh < 2) outside[c.mesh].push_back({c.point, c.distance});
        }
    }
    if (!have) return out;

    // The deepest point and its closest surface point as (point_a, point_b): a's point inside
    // b, b's point inside a, or a point inside both with the farther surface's closest point
    // (b moves along point_a - point_b to leave it behind).
    out.depth = best;
    Vec3 deep, surface;
    Vec3 deep_local, surface_local;  // the same two points in the frame of `frame`
    const Pose* frame;
    bool deep_is_a;
    // The nearest point of the winner's triangle when the search kept it: closest_point's
    // answer (the same search to the end), without searching again.
    auto nearest = [&](const MeshBvh& mesh) {
        return winner_triangle >= 0 ? closest_point_on_triangle(winner.point, mesh.triangle(winner_triangle))
                                    : closest_point(mesh, winner.point).point;
    };
    deep_local = winner.point;
    if (winner.mesh == 0) {
        frame = &input.pose_b;
        surface_local = nearest(b);
        deep_is_a = true;
    } else if (winner.mesh == 1) {
        frame = &input.pose_a;
        surface_local = nearest(a);
        deep_is_a = false;
    } else {
        frame = &input.pose_a;
        surface_local = winner.farther_is_a ? closest_point(a, winner.point).point
                                            : rel.apply(closest_point(b, rel.apply_inverse(winner.point)).point);
        deep_is_a = !winner.farther_is_a;  // the surface point is on the farther mesh
    }
    deep = frame->apply(deep_local);
    surface = frame->apply(surface_local);
    out.deepest_mesh = deep_is_a ? 0 : 1;
    out.point_a = deep_is_a ? deep : surface;
    out.point_b = deep_is_a ? surface : deep;
    const Vec3 gap = out.point_a - out.point_b;
    const double length = norm(gap);
    if (length > 0.0 && std::isfinite(length)) {
        out.normal = gap / length;
    } else {
        // A depth below the rounding of the pose (a resting contact: 1e-15 deep at coordinates
        // of 1e3) maps both points to the same world point. The direction is still known in the
        // local frame, where the two points differ by the depth: turned into the world frame.
        const Vec3 local_gap = deep_is_a ? deep_local - surface_local : surface_local - deep_local;
        const double local_length = norm(local_gap);
        if (local_length > 0.0) out.normal = frame->rotate(local_gap / local_length);
    }
    return out;
}

}  // namespace meshcol
