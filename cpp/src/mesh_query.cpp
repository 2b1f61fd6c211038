// Mesh-mesh distance, intersection and containment on two MeshBvh hierarchies.
//
// All the work happens in a's local frame: b's boxes are mapped there as the axis-aligned box
// enclosing the rotated box (a valid, if looser, lower bound under rotation; exact under pure
// translation), b's triangles are mapped at the leaves. The distance search is a depth-first
// branch and bound over node pairs (Larsen, Gottschalk, Lin and Manocha 1999, "Fast proximity
// queries with swept sphere volumes"; FCL's MeshDistanceTraversalNode): the closer child pair is
// visited first so a good bound arrives early, and pairs whose box distance cannot beat the best
// distance so far are dropped.
#include "meshcol/mesh_query.hpp"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/triangle.hpp"
#include "rescale.hpp"

namespace meshcol {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// The rigid map from b's local frame to a's local frame, and back.
struct Relative {
    Mat3 rotation;
    Mat3 abs_rotation;  // |rotation| element-wise, maps half extents to enclosing half extents
    Vec3 translation;

    Relative(const Pose& pose_a, const Pose& pose_b) {
        rotation = pose_a.rotation.transposed() * pose_b.rotation;
        translation = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) abs_rotation.m[i][j] = std::fabs(rotation.m[i][j]);
    }
    Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
    Vec3 apply_inverse(const Vec3& p) const { return rotation.transpose_times(p - translation); }
};

struct CenteredBox {
    Vec3 center, half;
};

inline CenteredBox centered(const BvhNode& n) {
    const Vec3 lo{n.lower[0], n.lower[1], n.lower[2]};
    const Vec3 hi{n.upper[0], n.upper[1], n.upper[2]};
    return {(lo + hi) * 0.5, (hi - lo) * 0.5};
}

inline double squared_gap(const Vec3& c1, const Vec3& h1, const Vec3& c2, const Vec3& h2) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double gap = std::fabs(c1[k] - c2[k]) - h1[k] - h2[k];
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// A lower bound of the squared distance between any triangle under node a and any under node b,
// the largest of three valid ones: the box distance in a's frame (b's box replaced by the
// axis-aligned box enclosing it there), the same in b's frame, and the gap of the two boxes'
// projections on the line through their centres (a separating-axis bound, Gottschalk et al.
// 1996). Under pure translation the first is the exact box distance; under rotation the first
// two can be loose by up to a factor sqrt(3), while the third tends to the box distance as the
// boxes get farther apart relative to their size.
inline double box_squared_distance(const BvhNode& na, const BvhNode& nb, const Relative& rel) {
    const CenteredBox a = centered(na);
    const CenteredBox b = centered(nb);
    const Vec3 b_center = rel.apply(b.center);
    const double in_a = squared_gap(a.center, a.half, b_center, rel.abs_rotation * b.half);
    const double in_b = squared_gap(rel.apply_inverse(a.center), rel.abs_rotation.transpose_times(a.half),
                                    b.center, b.half);
    double best = std::fmax(in_a, in_b);
    const Vec3 axis = b_center - a.center;  // a's frame
    const double length = norm(axis);
    if (length > 0.0) {
        const Vec3 axis_b = rel.rotation.transpose_times(axis);  // b's frame
        const double reach = (std::fabs(axis.x) * a.half.x + std::fabs(axis.y) * a.half.y + std::fabs(axis.z) * a.half.z +
                              std::fabs(axis_b.x) * b.half.x + std::fabs(axis_b.y) * b.half.y + std::fabs(axis_b.z) * b.half.z) / length;
        const double gap = length - reach;
        if (gap > 0.0) best = std::fmax(best, gap * gap);
    }
    return best;
}

inline double node_size(const BvhNode& n) {
    return (static_cast<double>(n.upper[0]) - n.lower[0]) + (static_cast<double>(n.upper[1]) - n.lower[1]) +
           (static_cast<double>(n.upper[2]) - n.lower[2]);
}

struct TriangleBox {
    Vec3 lower, upper;
};

inline TriangleBox triangle_box(const Vec3 t[3]) {
    return {component_min(t[0], component_min(t[1], t[2])), component_max(t[0], component_max(t[1], t[2]))};
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
    const double a_max = std::fmax(dot(axis, a[0]), std::fmax(dot(axis, a[1]), dot(axis, a[2])));
    const double b_min = std::fmin(dot(axis, b[0]), std::fmin(dot(axis, b[1]), dot(axis, b[2])));
    const double gap = b_min - a_max;
    return gap > 0.0 ? gap * gap / dot(axis, axis) : 0.0;
}

struct StackItem {
    std::int32_t a, b;
    double bound;  // squared box distance when pushed
};

// b's leaf triangles mapped into a's frame, with their boxes.
struct MappedLeaf {
    Vec3 corners[defaults::mesh_bvh_leaf_size][3];
    TriangleBox boxes[defaults::mesh_bvh_leaf_size];
    int count = 0;

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
    std::vector<StackItem> stack;
    stack.reserve(128);
    const double root2 = box_squared_distance(na[0], nb[0], rel);
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
        c1.bound = box_squared_distance(na[static_cast<size_t>(c1.a)], nb[static_cast<size_t>(c1.b)], rel);
        c2.bound = box_squared_distance(na[static_cast<size_t>(c2.a)], nb[static_cast<size_t>(c2.b)], rel);
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
    return std::fabs(winding_number(mesh, local)) >= defaults::winding_number_inside;
}

// Squared distance from p to node n's box.
inline double point_box_squared_distance(const BvhNode& n, const Vec3& p) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double gap = static_cast<double>(n.lower[k]) - p[k];
        if (gap < 0.0) gap = p[k] - static_cast<double>(n.upper[k]);
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
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
    stack.push_back({0, point_box_squared_distance(nodes[0], point)});
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
        // Push the farther child first so the closer one is searched next.
        const auto child = [&](std::int32_t i) {
            return std::make_pair(i, point_box_squared_distance(nodes[static_cast<size_t>(i)], point));
        };
        std::pair<std::int32_t, double> near = child(index + 1), far = child(node.index);
        if (near.second > far.second) std::swap(near, far);
        if (!found || far.second < best2) stack.push_back(far);
        if (!found || near.second < best2) stack.push_back(near);
    }
    out.distance = std::sqrt(best2);
    out.point = best_point;
    out.triangle = mesh.face_index(best_triangle);
    return out;
}

double winding_number(const MeshBvh& mesh, const Vec3& point) {
    double total = 0.0;
    const std::int32_t n = mesh.triangle_count();
    for (std::int32_t i = 0; i < n; ++i) {
        const Vec3* t = mesh.triangle(i);
        const Vec3 a = t[0] - point, b = t[1] - point, c = t[2] - point;
        const double la = norm(a), lb = norm(b), lc = norm(c);
        // van Oosterom and Strackee 1983: tan(omega / 2) = det / denominator.
        const double det = dot(a, cross(b, c));
        const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        total += 2.0 * std::atan2(det, denominator);
    }
    return total / (4.0 * kPi);
}

bool mesh_intersects(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b) {
    const Relative rel(pose_a, pose_b);
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    if (box_squared_distance(na[0], nb[0], rel) > 0.0) return false;
    std::vector<std::pair<std::int32_t, std::int32_t>> stack{{0, 0}};
    MappedLeaf leaf_b;
    while (!stack.empty()) {
        const auto [ia, ib] = stack.back();
        stack.pop_back();
        const BvhNode& x = na[static_cast<size_t>(ia)];
        const BvhNode& y = nb[static_cast<size_t>(ib)];
        if (x.is_leaf() && y.is_leaf()) {
            leaf_b.load(b, y, rel);
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const Vec3* ta = a.triangle(i);
                const TriangleBox box_a = triangle_box(ta);
                for (int j = 0; j < leaf_b.count; ++j)
                    if (triangle_box_squared_distance(box_a, leaf_b.boxes[j]) == 0.0 &&
                        triangles_intersect(ta, leaf_b.corners[j], nullptr))
                        return true;
            }
            continue;
        }
        const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
        const std::pair<std::int32_t, std::int32_t> c1 = descend_a ? std::make_pair(ia + 1, ib) : std::make_pair(ia, ib + 1);
        const std::pair<std::int32_t, std::int32_t> c2 = descend_a ? std::make_pair(x.index, ib) : std::make_pair(ia, y.index);
        if (box_squared_distance(na[static_cast<size_t>(c2.first)], nb[static_cast<size_t>(c2.second)], rel) == 0.0)
            stack.push_back(c2);
        if (box_squared_distance(na[static_cast<size_t>(c1.first)], nb[static_cast<size_t>(c1.second)], rel) == 0.0)
            stack.push_back(c1);
    }
    return false;
}

bool mesh_pair_in_range(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b,
                        const Pose& pose_b) {
    // The reach of a mesh about its origin: the far corner of its root box.
    auto reach = [](const MeshBvh& m) {
        const BvhNode& root = m.nodes().front();
        Vec3 corner;
        for (int k = 0; k < 3; ++k)
            corner[k] = std::fmax(std::fabs(double(root.lower[k])), std::fabs(double(root.upper[k])));
        return safe_norm(corner);
    };
    double half = 0.5 * std::fmax(reach(a), reach(b));
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
    const Relative rel(input.pose_a, input.pose_b);
    const double bound2 = input.max_distance * input.max_distance;
    const SearchResult r = search_distance(a, b, rel, bound2);
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
    if (!out.intersecting) {
        // Disjoint surfaces: each mesh is wholly inside or wholly outside the other, so one
        // vertex decides (Jacobson et al. 2013). Its distance to the other surface is at least
        // `distance` > 0, which keeps the winding number away from its jump.
        out.a_inside_b = point_inside(b, input.pose_b, input.pose_a.apply(a.triangle(0)[0]));
        out.b_inside_a = point_inside(a, input.pose_a, input.pose_b.apply(b.triangle(0)[0]));
    }
    out.status = Status::CONVERGED;
    return out;
}

}  // namespace meshcol
