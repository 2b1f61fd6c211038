// Mesh-mesh distance and the closest point of a mesh to a point.
//
// The distance search is a best-first branch and bound over node pairs (Larsen, Gottschalk,
// Lin and Manocha 1999, "Fast proximity queries with swept sphere volumes", whose PQP keeps a
// priority queue of node pairs too): the pair with the smallest box distance is expanded next,
// so a good bound arrives early, and pairs whose box distance cannot beat the best distance so
// far are dropped. At the leaves, triangle pairs are dropped by boxes, planes and capsules
// before the exact triangle-pair distance. The pair is first tried for a crossing
// (mesh_intersection.cpp) and, when its surfaces are disjoint, for containment
// (mesh_winding.cpp). Pairs whose hulls are apart are first tried by their hulls' supporting
// planes (search_across_hulls), which measures only the triangle pairs at those planes and
// decides most pairs of meshes apart without a node pair.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "meshcol/gjk.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// A lower bound of the squared distance between the oriented boxes of node a and node b: the
// largest of the gap of their projections on the line through the centres (a separating-axis
// candidate, Gottschalk, Lin and Manocha 1996) and the box distances in a's and in b's box
// frame (the nine edge-pair axes of the overlap test cost more than they prune here). The centre line comes first and needs no relative rotation of the boxes: when
// it alone reaches `enough2` (a bound that already prunes the pair), the rest is skipped.
// Node b's oriented box mapped into a's frame: its centre and its axes (rel.apply(b.center),
// rel.rotation * b.axes.row(j)), what every bound of a pair with b computes first.
struct MappedObb {
    Vec3 center;
    Vec3 axes[3];

    void map(const NodeObb& b, const Relative& rel) {
        center = rel.apply(b.center);
        for (int j = 0; j < 3; ++j) axes[j] = rel.rotation * b.axes.row(j);
    }
};

// The mapped boxes of b's nodes for one search, each mapped when first asked for: a node of b
// meets several nodes of a (the search descends the larger box of a pair, so a node of b
// stays while a's side is split), and its mapping is about a third of a pair's bound. The
// same numbers as mapping it at each pair, so the bounds are unchanged bit for bit. Kept per
// thread between searches (a generation stamp marks the current search's entries); a mesh of
// more than kMaxNodes nodes maps at each pair instead, so the cache stays small (400 kB) and
// cheap to set up on a new thread: sized for a mesh of 42,000 nodes (the 84,000-face counter)
// the first search on a thread paid 5.6M instructions for it, 17 of its searches.
class MappedObbCache {
public:
    static constexpr size_t kMaxNodes = 1 << 12;

    // Starts a search over `mesh`'s nodes; false when the mesh is too large to cache.
    bool start(const MeshBvh& mesh) {
        const size_t n = mesh.nodes().size();
        if (n > kMaxNodes) return false;
        if (stamp_.size() < n) {
            stamp_.assign(n, 0);
            boxes_.resize(n);
            generation_ = 0;
        }
        if (++generation_ == 0) {  // wrapped: every old stamp could read as current
            std::fill(stamp_.begin(), stamp_.end(), 0u);
            generation_ = 1;
        }
        return true;
    }
    const MappedObb& get(std::int32_t id, const NodeObb& b, const Relative& rel) {
        const auto k = static_cast<size_t>(id);
        if (stamp_[k] != generation_) {
            boxes_[k].map(b, rel);
            stamp_[k] = generation_;
        }
        return boxes_[k];
    }

private:
    std::vector<MappedObb> boxes_;
    std::vector<std::uint32_t> stamp_;
    std::uint32_t generation_ = 0;
};

// A box whose axes are the identity (NodeObb::axis_aligned) skips its products with them, as
// mesh_intersection.cpp's obb_overlap does: the same values up to the sign of a zero, and
// every one is used through its absolute value, so the bound is the same bit for bit.
inline double obb_squared_distance(const NodeObb& a, const NodeObb& b, const MappedObb& mapped, const Relative& rel,
                                   double enough2) {
    const Vec3 d = mapped.center - a.center;  // a's local frame
    const Vec3 t = a.axis_aligned ? d : a.axes * d;  // a's box frame
    const Vec3 d_in_b = rel.rotation.transpose_times(d);
    const Vec3 tb = b.axis_aligned ? d_in_b : b.axes * d_in_b;  // b's box frame
    double best = 0.0;
    const double length2 = dot(d, d);
    if (length2 > 0.0) {
        const double length = std::sqrt(length2);
        const double reach = std::fabs(t.x) * a.half.x + std::fabs(t.y) * a.half.y + std::fabs(t.z) * a.half.z +
                             std::fabs(tb.x) * b.half.x + std::fabs(tb.y) * b.half.y + std::fabs(tb.z) * b.half.z;
        best = max2(0.0, length - reach / length - rel.slack);
        if (best > 0.0 && best * best >= enough2) return best * best;
    }
    double product[3][3];  // |a_i . b_j|, both axes in a's local frame
    const double(*abs_c)[3] = rel.abs_rotation.m;
    if (!a.axis_aligned || !b.axis_aligned) {
        for (int j = 0; j < 3; ++j) {
            const Vec3& bj = mapped.axes[j];
            for (int i = 0; i < 3; ++i) product[i][j] = std::fabs(a.axis_aligned ? bj[i] : dot(a.axes.row(i), bj));
        }
        abs_c = product;
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
// The largest projection on `n` of a point of the oriented box (box and n in one frame): the
// box's support height along n, as the hierarchy descents along a direction bound a node.
inline double obb_top(const NodeObb& box, const Vec3& n) {
    return dot(box.center, n) + box.half.x * std::fabs(dot(box.axes.row(0), n)) +
           box.half.y * std::fabs(dot(box.axes.row(1), n)) + box.half.z * std::fabs(dot(box.axes.row(2), n));
}

inline double aabb_squared_distance(const BvhNode& na, const BvhNode& nb, const Relative& rel) {
    double d2 = 0.0;
    const auto [b_center, b_half] = rel.enclose_in_a(nb);
    for (int k = 0; k < 3; ++k) {
        const double gap = max2(static_cast<double>(na.lower[k]) - (b_center[k] + b_half[k]),
                                (b_center[k] - b_half[k]) - static_cast<double>(na.upper[k])) - rel.slack;
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// Lower bound of the distance between the boxes of triangles a and b, each axis's gap lowered
// by `slack` (the pair's rounding allowance): with u the lowered gaps and g the box gaps,
// |g|^2 >= |u|^2 + 2 slack sum(u) + slack^2 >= (|u| + slack)^2, so the bound is at most the
// box distance less `slack`, and the rounding of the triangle distance (far under `slack`)
// can never take a pair it drops below the bound. Unlowered, a face-to-face pair whose box
// gap is its distance was dropped when its computed distance rounded a few ulps under the
// box's (parallel caps: the search missed the smallest pair by 3 ulps). Returns a squared
// distance.
inline double triangle_box_lowered_squared_distance(const TriangleBox& a, const TriangleBox& b, double slack) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double gap = max2(a.lower[k] - b.upper[k], b.lower[k] - a.upper[k]) - slack;
        if (gap > 0.0) d2 += gap * gap;
    }
    return d2;
}

// Lower bound of the distance between triangles a and b from their projections on the line
// through their centroids (separating-axis bound): tight when the triangles are far apart
// relative to their size, where the box bound is loose. The gap is lowered by `slack`, as
// the box bound's. Returns a squared distance.
inline double triangle_axis_squared_distance(const Vec3 a[3], const Vec3 b[3], double slack) {
    const Vec3 axis = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
    const double a_max = max2(dot(axis, a[0]), max2(dot(axis, a[1]), dot(axis, a[2])));
    const double b_min = min2(dot(axis, b[0]), min2(dot(axis, b[1]), dot(axis, b[2])));
    const double gap = b_min - a_max;
    if (!(gap > 0.0)) return 0.0;
    const double lowered = gap / std::sqrt(dot(axis, axis)) - slack;
    return lowered > 0.0 ? lowered * lowered : 0.0;
}

// Lower bound of the distance between triangles a and b from their planes (unit normals na
// and nb, zero for a degenerate triangle): when b lies wholly on one side of a's plane, at
// least h from it, no point of a (in that plane) is nearer than h; likewise a and b's plane.
// For two patches facing each other across a gap (the pairs a near query measures) this is
// nearly the distance, where the boxes of slanted triangles and the centroid line prune
// little. Each gap is lowered by `slack` (the pair's rounding allowance, far above the
// rounding of these dot products and of the unit normals) so that rounding can only keep a
// pair. Returns a squared distance.
inline double plane_gap(const Vec3& n, const Vec3& origin, const Vec3 t[3], double slack) {
    const double s0 = dot(n, t[0] - origin), s1 = dot(n, t[1] - origin), s2 = dot(n, t[2] - origin);
    const double low = min2(s0, min2(s1, s2)), high = max2(s0, max2(s1, s2));
    const double gap = (low > 0.0 ? low : (high < 0.0 ? -high : 0.0)) - slack;
    return gap > 0.0 ? gap * gap : 0.0;
}

inline double triangle_plane_squared_distance(const Vec3 a[3], const Vec3& na, const Vec3 b[3], const Vec3& nb,
                                              double slack) {
    return max2(plane_gap(na, a[0], b, slack), plane_gap(nb, b[0], a, slack));
}

// Lower bound of the distance between triangles a and b from their capsules (MeshBvh's
// TriangleCapsule: the longest edge swept by a ball reaching the third corner): the distance
// between the two spine segments less both radii. For slivers, whose boxes, centroid line and
// planes bound poorly, it is nearly the distance. Lowered by `slack` (the pair's rounding
// allowance, far above the rounding of the segment distance and of the mapped corners) so that
// rounding can only keep a pair; a NaN (overflow) adds nothing. Returns a squared distance.
inline double triangle_capsule_squared_distance(const Vec3 a[3], const TriangleCapsule& ca, const Vec3 b[3],
                                                const TriangleCapsule& cb, double slack) {
    const SegmentClosestPoints s =
        segment_closest_points(a[ca.edge], a[(ca.edge + 1) % 3], b[cb.edge], b[(cb.edge + 1) % 3]);
    const double gap = std::sqrt(s.squared_distance) - ca.radius - cb.radius - slack;
    return gap > 0.0 ? gap * gap : 0.0;
}

// A separating-axis bound along the direction of the best pair so far (from its point on a
// to its point on b, a's frame): for any unit n the distance between two sets is at least
// min over the second of n . y less max over the first of n . x. Near the end of a search n is
// (nearly) the normal of the closest pair's separating plane, which supports both meshes where
// they are locally convex there, so every node or triangle pair beside the closest features
// projects past the gap and is dropped, where the boxes, centroid lines and planes (whose
// bounds fall short of the distance by a share of the pieces' sizes) keep the pairs around the
// closest vertex that are within a few percent of it (meshes far apart: those were most of the
// triangle pairs measured). Each gap is lowered by the pair's rounding allowance `slack`, far
// above the rounding of these dot products (the boxes are padded for theirs, MeshBvh), so that
// rounding can only keep a pair. Inactive (bounds of 0) until a first pair is measured.
class WitnessAxis {
public:
    bool active() const { return active_; }
    void set(const Vec3& point_a, const Vec3& point_b, const Relative& rel) {
        const Vec3 d = point_b - point_a;
        const double length = norm(d);
        active_ = length > 0.0 && std::isfinite(length);
        if (!active_) return;
        n_ = d / length;
        n_b_ = rel.rotation.transpose_times(n_);
        offset_ = dot(rel.translation, n_);
        slack_ = rel.slack;
    }
    // Squared gap between node a's oriented box and node b's (b's local frame) along n.
    double nodes(const NodeObb& a, const NodeObb& b) const {
        const double a_high = dot(a.center, n_) + reach(a, n_);
        const double b_low = dot(b.center, n_b_) + offset_ - reach(b, n_b_);
        return squared_gap(b_low - a_high);
    }
    // Squared gap between triangle a and triangle b (both in a's frame) along n.
    double triangles(const Vec3 a[3], const Vec3 b[3]) const {
        const double a_high = max2(dot(a[0], n_), max2(dot(a[1], n_), dot(a[2], n_)));
        const double b_low = min2(dot(b[0], n_), min2(dot(b[1], n_), dot(b[2], n_)));
        return squared_gap(b_low - a_high);
    }

private:
    // Half the width of a box's projection on unit n (box frame axes in the frame of n).
    static double reach(const NodeObb& box, const Vec3& n) {
        return box.half.x * std::fabs(dot(box.axes.row(0), n)) + box.half.y * std::fabs(dot(box.axes.row(1), n)) +
               box.half.z * std::fabs(dot(box.axes.row(2), n));
    }
    double squared_gap(double gap) const {
        const double lowered = gap - slack_;
        return lowered > 0.0 ? lowered * lowered : 0.0;  // also NaN (an overflow): no bound
    }
    bool active_ = false;
    Vec3 n_, n_b_;  // unit, a's frame; the same in b's frame
    double offset_ = 0.0;  // translation . n: b's points at y (b's frame) project at y . n_b + offset
    double slack_ = 0.0;
};

// Whether the bounds of a triangle pair (a's triangle i with corners ta and box box_a; b's
// triangle j, its corners tb and box box_b mapped into a's frame) drop it: its box, centroid
// line and plane bounds, and its capsule bound when one is a sliver, each tested by `pruned`.
template <class Pruned>
inline bool triangle_pair_dropped(const MeshBvh& a, std::int32_t i, const Vec3 ta[3], const TriangleBox& box_a,
                                  const MeshBvh& b, std::int32_t j, const Vec3 tb[3], const TriangleBox& box_b,
                                  const Relative& rel, const Pruned& pruned) {
    return pruned(triangle_box_lowered_squared_distance(box_a, box_b, rel.slack)) ||
           pruned(triangle_axis_squared_distance(ta, tb, rel.slack)) ||
           pruned(triangle_plane_squared_distance(ta, a.triangle_normal(i), tb, rel.rotation * b.triangle_normal(j),
                                                  rel.slack)) ||
           ((a.triangle_capsule(i).thin || b.triangle_capsule(j).thin) &&
            pruned(triangle_capsule_squared_distance(ta, a.triangle_capsule(i), tb, b.triangle_capsule(j), rel.slack)));
}

struct StackItem {
    std::int32_t a, b;
    double bound;  // squared box distance when pushed
};

struct SearchResult {
    bool found = false;         // a pair within the bound was found
    bool intersecting = false;  // a triangle pair intersects
    double squared_distance = kInf;
    Vec3 point_a, point_b;      // a's frame
    std::int32_t triangle_a = -1, triangle_b = -1;  // leaf order
};

// Branch and bound over node pairs. `bound2` is the squared max_distance. `start` (leaf
// order, a < 0: none) is a triangle pair measured first: its distance, when within the bound,
// is the first best and its direction the first axis, so that the search prunes from its
// first node pairs (a pair whose boxes touch: near the closest pair when the meshes are near).
SearchResult search_distance(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2,
                             CrossingPair start) {
    SearchResult r;
    r.squared_distance = bound2;
    // A pair at exactly max_distance still counts, so before the first find the test is strict.
    auto pruned = [&r](double lb2) { return r.found ? lb2 >= r.squared_distance : lb2 > r.squared_distance; };
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    const std::vector<NodeObb>& oa = a.obbs();
    const std::vector<NodeObb>& ob = b.obbs();
    // Best first: a min-heap of node pairs by bound, so leaves are measured in the order of
    // their bounds and the best distance falls to (nearly) its final value before most of the
    // pairs are reached (a depth-first descent measures 2-4x as many triangle pairs).
    std::vector<StackItem> heap;
    heap.reserve(128);
    const auto farther = [](const StackItem& p, const StackItem& q) { return p.bound > q.bound; };
    const auto push = [&](const StackItem& item) {
        heap.push_back(item);
        std::push_heap(heap.begin(), heap.end(), farther);
    };
    thread_local MappedObbCache cache;
    const bool cached = cache.start(b);
    MappedObb scratch;
    // b's node j mapped into a's frame: from the cache, or mapped here for a large mesh.
    const auto mapped = [&](std::int32_t j) -> const MappedObb& {
        if (cached) return cache.get(j, ob[static_cast<size_t>(j)], rel);
        scratch.map(ob[static_cast<size_t>(j)], rel);
        return scratch;
    };
    const double root2 = obb_squared_distance(oa[0], ob[0], mapped(0), rel, bound2);
    if (pruned(root2)) return r;
    MappedLeaf leaf_b;
    WitnessAxis axis;
    if (start.a >= 0) {
        // As the leaves measure it (b's corners mapped one by one, the full distance): the
        // same number that pair gives wherever it is measured.
        const Vec3* source = b.triangle(start.b);
        const Vec3 tb[3] = {rel.apply(source[0]), rel.apply(source[1]), rel.apply(source[2])};
        Vec3 pa, pb;
        const double d2 = triangle_separated_squared_distance(a.triangle(start.a), tb, &pa, &pb);
        if (d2 <= bound2) {
            r.found = true;
            r.squared_distance = d2;
            r.point_a = pa;
            r.point_b = pb;
            r.triangle_a = start.a;
            r.triangle_b = start.b;
            axis.set(pa, pb, rel);
        }
    }
    // The pair at hand: popped from the heap, or the nearer child of the last one when it is
    // no farther than the heap's nearest (what the heap would give back, without the push and
    // the pop).
    StackItem item{0, 0, root2};
    bool held = true;
    while (held || !heap.empty()) {
        if (!held) {
            std::pop_heap(heap.begin(), heap.end(), farther);
            item = heap.back();
            heap.pop_back();
        }
        // Every pair left is at least as far: done.
        if (pruned(item.bound)) break;
        // A pair from the heap, pushed before the best pair's direction was known (or moved),
        // may be dropped by it now (a held pair's bound has just been taken with it).
        if (!held && axis.active() &&
            pruned(axis.nodes(oa[static_cast<size_t>(item.a)], ob[static_cast<size_t>(item.b)])))
            continue;
        held = false;
        const BvhNode& x = na[static_cast<size_t>(item.a)];
        const BvhNode& y = nb[static_cast<size_t>(item.b)];
        if (x.is_leaf() && y.is_leaf()) {
            leaf_b.load(b, y, rel);
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const Vec3* ta = a.triangle(i);
                const TriangleBox box_a = triangle_box(ta);
                for (int j = 0; j < leaf_b.count; ++j) {
                    // The surfaces are disjoint (first_crossing found no crossing pair among
                    // those whose boxes touch, which are all that can cross): measure only.
                    if ((axis.active() && pruned(axis.triangles(ta, leaf_b.corners[j]))) ||
                        triangle_pair_dropped(a, i, ta, box_a, b, y.index + j, leaf_b.corners[j], leaf_b.boxes[j],
                                              rel, pruned))
                        continue;
                    Vec3 pa, pb;
                    // Bit for bit the full triangle distance whenever it can count (at most the
                    // best so far). Where the leaf pair's bound is well under the best (patches
                    // facing across a gap, slanted slivers), most of its edge pairs are farther
                    // than the best and are skipped by their lines' distance; where it is near
                    // it (meshes far apart: the pairs measured are all about as far) that test
                    // would prune little and is left out.
                    const bool loose = item.bound < 0.5 * r.squared_distance;
                    const double d2 = triangle_separated_squared_distance_below(
                        ta, leaf_b.corners[j], loose ? r.squared_distance : kInf, loose ? rel.slack : 0.0, &pa, &pb);
                    if (!pruned(d2)) {
                        r.found = true;
                        r.squared_distance = d2;
                        r.point_a = pa;
                        r.point_b = pb;
                        r.triangle_a = i;
                        r.triangle_b = y.index + j;
                        axis.set(pa, pb, rel);
                    }
                }
            }
            // Touching (a distance that rounds to zero): nothing can beat zero.
            if (r.found && r.squared_distance == 0.0) return r;
            continue;
        }
        // Descend the larger box (or the only internal one).
        const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
        StackItem c1, c2;
        if (descend_a) {
            c1 = {item.a + 1, item.b, 0.0};
            c2 = {x.index, item.b, 0.0};
        } else {
            c1 = {item.a, item.b + 1, 0.0};
            c2 = {item.a, y.index, 0.0};
        }
        // The best pair's axis first: where it drops a pair the box bound is not needed.
        for (StackItem* c : {&c1, &c2}) {
            const NodeObb& box_a = oa[static_cast<size_t>(c->a)];
            const NodeObb& box_b = ob[static_cast<size_t>(c->b)];
            c->bound = axis.active() ? axis.nodes(box_a, box_b) : 0.0;
            if (!pruned(c->bound))
                c->bound = max2(c->bound, obb_squared_distance(box_a, box_b, mapped(c->b), rel, r.squared_distance));
        }
        if (rel.aligned) {
            c1.bound = max2(c1.bound, aabb_squared_distance(na[static_cast<size_t>(c1.a)], nb[static_cast<size_t>(c1.b)], rel));
            c2.bound = max2(c2.bound, aabb_squared_distance(na[static_cast<size_t>(c2.a)], nb[static_cast<size_t>(c2.b)], rel));
        }
        if (c1.bound > c2.bound) std::swap(c1, c2);
        if (!pruned(c2.bound)) push(c2);
        if (!pruned(c1.bound)) {
            if (heap.empty() || c1.bound <= heap.front().bound) {
                item = c1;
                held = true;
            } else {
                push(c1);
            }
        }
    }
    return r;
}

// The search of a pair whose hulls are apart (meshes apart by a share of their size, the
// pairs a scene's near-phase hands over most often): any unit direction n bounds every
// triangle pair from below by the gap of their projections on it, and that gap splits into
// g + s_a + s_b, g the gap between the meshes' extreme projections and s_a (s_b) how far the
// triangle of a (of b) falls short of its mesh's extreme. Along the direction of the hulls'
// distance (GJK on the vertices) g is the hulls' distance, at most the meshes'; where the
// meshes' closest points lie on their hulls (their usual place when apart) it is the distance
// itself, and only the triangles within best - g of their mesh's supporting plane (those
// around the closest features) can hold a pair that beats the best: each mesh's are found by
// a descent of its own hierarchy, and only their pairs are bounded and measured. No node pair
// is visited. Each pair's gap is lowered by the pair's rounding allowance, as every bound of
// search_distance, and the triangle distances are the ones search_distance measures, so the
// distance is the same, bit for bit.
class HullPlanes {
public:
    // A triangle (leaf order) and how far its projection falls short of the mesh's extreme.
    struct Candidate {
        std::int32_t triangle;
        double high;  // the largest projection of its corners on the direction
    };

    // Triangles of `mesh` whose largest corner projection on `n` is within `reach` of the
    // mesh's largest, into `out` (nearest the extreme first); returns that largest, or NaN
    // when there are more than `limit` of them. A descent of the hierarchy, larger box
    // projection first, dropping nodes whose oriented box ends short of the largest found
    // less `reach`.
    static double collect(const MeshBvh& mesh, const Vec3& n, double reach, size_t limit,
                          std::vector<Candidate>& out, std::vector<std::int32_t>& stack) {
        const std::vector<BvhNode>& nodes = mesh.nodes();
        const std::vector<NodeObb>& boxes = mesh.obbs();
        const auto top = [&](std::int32_t id) {
            return obb_top(boxes[static_cast<size_t>(id)], n);
        };
        out.clear();
        stack.clear();
        stack.push_back(0);
        double high = -kInf;
        while (!stack.empty()) {
            const std::int32_t id = stack.back();
            stack.pop_back();
            const BvhNode& node = nodes[static_cast<size_t>(id)];
            if (node.is_leaf()) {
                for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                    const Vec3* t = mesh.triangle(i);
                    const double p = max2(dot(t[0], n), max2(dot(t[1], n), dot(t[2], n)));
                    high = max2(high, p);
                    if (p >= high - reach) out.push_back({i, p});
                }
                if (out.size() > limit) {
                    const double floor = high - reach;
                    out.erase(std::remove_if(out.begin(), out.end(),
                                             [floor](const Candidate& c) { return c.high < floor; }),
                              out.end());
                    if (out.size() > limit) return kNaN;
                }
                continue;
            }
            const std::int32_t left = id + 1, right = node.index;
            const double tl = top(left), tr = top(right);
            // The boxes are padded for the rounding of these projections (MeshBvh): a node
            // that ends short holds no corner above its end.
            const bool keep_l = tl >= high - reach, keep_r = tr >= high - reach;
            if (tl >= tr) {
                if (keep_r) stack.push_back(right);
                if (keep_l) stack.push_back(left);
            } else {
                if (keep_l) stack.push_back(left);
                if (keep_r) stack.push_back(right);
            }
        }
        const double floor = high - reach;
        out.erase(std::remove_if(out.begin(), out.end(), [floor](const Candidate& c) { return c.high < floor; }),
                  out.end());
        std::sort(out.begin(), out.end(), [](const Candidate& p, const Candidate& q) {
            return p.high > q.high || (p.high == q.high && p.triangle < q.triangle);
        });
        return high;
    }
};

// Meshes of at most this many vertices (both) are tried (search_across_hulls): the support
// function of the hulls' GJK scans every vertex, which for larger meshes costs more than the
// node-pair search saves where it succeeds.
constexpr size_t kHullScanVertices = 1024;
// Meshes this small are tried whatever their root boxes say (worth_hulls).
constexpr size_t kHullSmallVertices = 256;

// The distance between the hulls of a and b, both in a's frame: the unit direction from a
// towards b and the closest points on the two hulls (a guess of where the meshes' closest
// triangles lie; any direction bounds, so rounding costs candidates, never an answer).
struct HullWitness {
    Vec3 normal, point_a, point_b;
    double distance = 0.0;
};

// The vertex of `mesh` farthest along `d` (local frame), by a descent of the hierarchy that
// skips the nodes whose oriented box ends short of the best corner so far: the support
// function of a large mesh's hull at a few dozen nodes, where a scan reads every vertex.
Vec3 mesh_support(const MeshBvh& mesh, const Vec3& d, std::vector<std::pair<std::int32_t, double>>& stack) {
    const std::vector<BvhNode>& nodes = mesh.nodes();
    const std::vector<NodeObb>& boxes = mesh.obbs();
    const auto top = [&](std::int32_t id) { return obb_top(boxes[static_cast<size_t>(id)], d); };
    double best = -kInf;
    Vec3 point = mesh.triangle(0)[0];
    stack.clear();
    stack.push_back({0, kInf});
    while (!stack.empty()) {
        const auto [id, bound] = stack.back();
        stack.pop_back();
        if (bound <= best) continue;
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const Vec3* t = mesh.triangle(i);
                for (int k = 0; k < 3; ++k) {
                    const double p = dot(t[k], d);
                    if (p > best) {
                        best = p;
                        point = t[k];
                    }
                }
            }
            continue;
        }
        std::pair<std::int32_t, double> near{id + 1, top(id + 1)}, far{node.index, top(node.index)};
        if (near.second < far.second) std::swap(near, far);
        if (far.second > best) stack.push_back(far);
        if (near.second > best) stack.push_back(near);
    }
    return point;
}

// hull_direction for large meshes: GJK (van den Bergen 2003) with mesh_support as the support
// functions, Ericson's closest point of the simplex (closest_point_on_simplex).
bool hull_direction_by_descent(const MeshBvh& a, const MeshBvh& b, const Relative& rel, HullWitness& out) {
    thread_local std::vector<std::pair<std::int32_t, double>> stack;
    const auto support = [&](const Vec3& d) {
        SimplexVertex v;
        v.a = mesh_support(a, d, stack);
        v.b = rel.apply(mesh_support(b, rel.rotation.transpose_times(-d), stack));
        v.w = v.a - v.b;
        return v;
    };
    Simplex s;
    s.vertices[0] = support(squared_norm(rel.translation) > 0.0 ? rel.translation : Vec3{1.0, 0.0, 0.0});
    s.weights[0] = 1.0;
    s.size = 1;
    Vec3 v = s.vertices[0].w;
    double vv = squared_norm(v);
    for (int it = 0; it < defaults::gjk_max_iterations && vv > 0.0; ++it) {
        const SimplexVertex w = support(-v);
        bool repeated = false;
        for (int i = 0; i < s.size; ++i)
            repeated = repeated || (squared_norm(s.vertices[i].w - w.w) == 0.0);
        if (repeated || vv - dot(v, w.w) <= defaults::gjk_relative_tolerance * vv) break;
        s.vertices[s.size++] = w;
        Vec3 closest;
        if (!closest_point_on_simplex(s, closest)) return false;  // the origin is inside: they meet
        const double cc = squared_norm(closest);
        if (!(cc < vv)) break;
        v = closest;
        vv = cc;
    }
    if (!(vv > 0.0)) return false;
    out.distance = std::sqrt(vv);
    out.normal = v * (-1.0 / out.distance);
    out.point_a = out.point_b = Vec3{};
    for (int i = 0; i < s.size; ++i) {
        out.point_a += s.vertices[i].a * s.weights[i];
        out.point_b += s.vertices[i].b * s.weights[i];
    }
    return is_finite(out.normal);
}

// The direction of the distance between the hulls of a and b (b mapped into a's frame by
// rel): the narrow phase's GJK on the two vertex sets (its support scans them). False when
// the hulls meet. Any unit direction bounds the pairs (HullPlanes), so its rounding only
// costs candidates, never an answer.
bool hull_direction(const MeshBvh& a, const MeshBvh& b, const Relative& rel, HullWitness& out) {
    if (a.vertices().size() > kHullScanVertices || b.vertices().size() > kHullScanVertices)
        return hull_direction_by_descent(a, b, rel, out);
    ShapeView shape_a, shape_b;
    shape_a.vertices = a.vertices().data();
    shape_a.vertex_count = static_cast<int>(a.vertices().size());
    shape_b.vertices = b.vertices().data();
    shape_b.vertex_count = static_cast<int>(b.vertices().size());
    // b's pose in a's frame: the difference maps it with rel's own numbers (times identity).
    Pose relative;
    relative.rotation = rel.rotation;
    relative.translation = rel.translation;
    MinkowskiDifference difference(shape_a, Pose{}, shape_b, relative, false, a.box_reach(), b.box_reach());
    GjkOptions options;
    options.with_margins = false;
    const GjkResult hulls = gjk_run(difference, options);
    if (hulls.overlap || !(hulls.distance > 0.0) || !is_finite(hulls.normal)) return false;
    out.normal = hulls.normal;
    out.distance = hulls.distance;
    out.point_a = hulls.point_a;
    out.point_b = hulls.point_b;
    return true;
}

// The pairs of candidates measured: at most this many (else the node-pair search).
constexpr size_t kHullPairCap = 4096;

// The hull-plane search (HullPlanes) of a pair search_distance would search: true with `r`
// set when it decided the distance (the same number search_distance gives), false when it
// cannot (the hulls meet, the candidates are too many, or the best pair at the planes is
// farther than the hulls' distance by more than the planes' reach: the closest points lie off
// the hulls), `r` then holding the best pair found, if any (a start for the search). With
// `screen`, a pair whose hulls' closest points are not on both meshes is given up before any
// triangle is measured (the planes then cannot decide it).
bool search_across_hulls(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2, SearchResult& r,
                         bool screen = true) {
    r = SearchResult{};
    r.squared_distance = bound2;
    HullWitness hulls;
    if (!hull_direction(a, b, rel, hulls)) return false;
    const Vec3 n = hulls.normal;  // a's frame, unit, from a towards b
    // The meshes' closest points are the hulls' only where the hulls' lie on the meshes: when
    // either is off its mesh (a hull face over a concave region) the planes cannot decide,
    // and the node-pair search is cheaper on its own.
    const double off = 1e-9 * (hulls.distance + a.box_reach() + b.box_reach());
    if (screen && (closest_point(a, hulls.point_a).distance > off ||
                   closest_point(b, rel.apply_inverse(hulls.point_b)).distance > off))
        return false;
    const Vec3 n_b = rel.rotation.transpose_times(-n);  // b's frame: b's lowest points are its highest on n_b
    const double offset = dot(rel.translation, n);  // y (b's frame) projects on n at offset - y . n_b
    thread_local std::vector<HullPlanes::Candidate> in_a, in_b;
    thread_local std::vector<std::int32_t> stack;
    thread_local std::vector<Vec3> corners_b;  // the candidates of b mapped into a's frame, 3 each
    thread_local std::vector<TriangleBox> boxes_b;
    // The triangles at the supporting planes, within rounding of the hulls' distance. The gap
    // of a pair is offset - high_b - high_a (less the allowance): rounding moves these sums by
    // far under the allowance (the gap a node pair's axis bound takes, WitnessAxis).
    const double reach = 4.0 * rel.slack + 1e-9 * hulls.distance;
    const double high_a = HullPlanes::collect(a, n, reach, kHullPairCap, in_a, stack);
    const double high_b = HullPlanes::collect(b, n_b, reach, kHullPairCap, in_b, stack);
    const double gap = offset - high_b - high_a;
    if (!(gap > 0.0)) return false;  // also NaN: too many candidates
    // Every pair is beyond max_distance (as search_distance finds: nothing within it).
    if (gap - rel.slack > 0.0 && (gap - rel.slack) * (gap - rel.slack) > bound2) return true;
    if (in_a.size() * in_b.size() > kHullPairCap) return false;
    corners_b.resize(3 * in_b.size());
    boxes_b.resize(in_b.size());
    for (size_t j = 0; j < in_b.size(); ++j) {
        const Vec3* source = b.triangle(in_b[j].triangle);
        for (int k = 0; k < 3; ++k) corners_b[3 * j + static_cast<size_t>(k)] = rel.apply(source[k]);
        boxes_b[j] = triangle_box(&corners_b[3 * j]);
    }
    auto pruned = [&r](double lb2) { return r.found ? lb2 >= r.squared_distance : lb2 > r.squared_distance; };
    const auto measure = [&](std::int32_t i, const Vec3* ta, std::int32_t j, const Vec3* tb) {
        Vec3 pa, pb;
        const double d2 = r.found ? triangle_separated_squared_distance_below(ta, tb, r.squared_distance, rel.slack,
                                                                              &pa, &pb)
                                  : triangle_separated_squared_distance(ta, tb, &pa, &pb);
        if (pruned(d2)) return;
        r.found = true;
        r.squared_distance = d2;
        r.point_a = pa;
        r.point_b = pb;
        r.triangle_a = i;
        r.triangle_b = j;
    };
    // The pair nearest the hulls' closest points first: where those lie on the meshes it is
    // (nearly) the answer, and its distance then drops the others by their boxes (a flat side
    // holds hundreds of candidates at the plane).
    const auto nearest = [](const TriangleBox& box, const Vec3& p) {
        return squared_norm(max3(box.lower - p, max3(p - box.upper, Vec3{})));
    };
    size_t seed_a = 0, seed_b = 0;
    double best_a = kInf, best_b = kInf;
    for (size_t i = 0; i < in_a.size(); ++i) {
        const double d2 = nearest(triangle_box(a.triangle(in_a[i].triangle)), hulls.point_a);
        if (d2 < best_a) best_a = d2, seed_a = i;
    }
    for (size_t j = 0; j < in_b.size(); ++j) {
        const double d2 = nearest(boxes_b[j], hulls.point_b);
        if (d2 < best_b) best_b = d2, seed_b = j;
    }
    measure(in_a[seed_a].triangle, a.triangle(in_a[seed_a].triangle), in_b[seed_b].triangle,
            &corners_b[3 * seed_b]);
    for (const HullPlanes::Candidate& ca : in_a) {
        const Vec3* ta = a.triangle(ca.triangle);
        const TriangleBox box_a = triangle_box(ta);
        for (size_t j = 0; j < in_b.size(); ++j) {
            const HullPlanes::Candidate& cb = in_b[j];
            const double lowered = offset - cb.high - ca.high - rel.slack;
            // b's candidates fall further short in their order: the rest of the row too.
            if (lowered > 0.0 && pruned(lowered * lowered)) break;
            const Vec3* tb = &corners_b[3 * j];
            if (!triangle_pair_dropped(a, ca.triangle, ta, box_a, b, cb.triangle, tb, boxes_b[j], rel, pruned))
                measure(ca.triangle, ta, cb.triangle, tb);
        }
    }
    // Beyond max_distance or nothing within it: the node-pair search decides.
    if (!r.found) return false;
    // Every pair left out has a triangle farther than `reach` short of its plane: its bound
    // is above gap + reach less the allowance, so it cannot beat the best when the best is
    // at most that (with a margin for the rounding of this sum).
    const double needed = std::sqrt(r.squared_distance) - gap + rel.slack;
    return needed * (1.0 + 1e-9) + rel.slack <= reach;
}

// Whether the pair is worth trying by its hulls (search_across_hulls) before the node-pair
// search: its root oriented boxes are apart by a tenth of the smaller box's half diagonal,
// where the hulls are usually apart too (nearer, on the family's near sets, the attempts cost
// fandisk and the idler riser 4-7% more instructions); or both meshes are small enough
// (kHullSmallVertices) for the attempt to cost little when it fails. Near pairs of larger
// meshes (whose hulls mostly meet, or whose closest points lie in a concave region) go
// straight to the search.
bool worth_hulls(const MeshBvh& a, const MeshBvh& b, const Relative& rel) {
    if (a.vertices().size() <= kHullSmallVertices && b.vertices().size() <= kHullSmallVertices) return true;
    MappedObb root_b;
    root_b.map(b.obbs()[0], rel);
    const double gap = 0.1 * min2(norm(a.obbs()[0].half), norm(b.obbs()[0].half));
    return obb_squared_distance(a.obbs()[0], b.obbs()[0], root_b, rel, gap * gap) > gap * gap;
}

// Whether `point` (world frame) is inside `mesh` posed at `pose`.
bool point_inside(const MeshBvh& mesh, const Pose& pose, const Vec3& point) {
    const Vec3 local = pose.apply_inverse(point);
    if (!inside_box(mesh.nodes()[0], local)) return false;
    return winding_number_inside(mesh, local);
}

}  // namespace

namespace mesh_detail {

DisjointSearch distance_across_hulls(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2,
                                     bool screen) {
    SearchResult r;
    DisjointSearch out;
    out.decided = search_across_hulls(a, b, rel, bound2, r, screen);
    out.found = r.found;
    out.squared_distance = r.squared_distance;
    out.triangle_a = r.triangle_a;
    out.triangle_b = r.triangle_b;
    return out;
}

DisjointSearch distance_by_node_pairs(const MeshBvh& a, const MeshBvh& b, const Relative& rel, double bound2) {
    const SearchResult r = search_distance(a, b, rel, bound2, CrossingPair{-1, -1});
    return {true, r.found, r.squared_distance, r.triangle_a, r.triangle_b};
}

}  // namespace mesh_detail

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
    CrossingPair touching{-1, -1};
    if (first_crossing(a, b, rel, &r.triangle_a, &r.triangle_b, &r.point_a, &touching)) {
        r.found = r.intersecting = true;
        r.squared_distance = 0.0;
        r.point_b = r.point_a;
    } else if (touching.a >= 0 || !worth_hulls(a, b, rel) ||
               !search_across_hulls(a, b, rel, bound2, r)) {
        // Triangle boxes that touch, or root boxes that meet: the meshes are near, where their
        // hulls (nearly always) meet. Else the hulls' attempt failed, and its best pair (if
        // any) starts the search.
        if (touching.a < 0 && r.found) touching = CrossingPair{r.triangle_a, r.triangle_b};
        r = search_distance(a, b, rel, bound2, touching);
    }
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

}  // namespace meshcol
