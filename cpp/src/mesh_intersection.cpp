// Whether two meshes' surfaces meet: a descent of the pair's overlapping oriented boxes to
// the exact triangle-pair tests (triangle.hpp), stopped at the first crossing pair, or run to
// the end to mark every crossing and near triangle (the depth query's start); and where a
// segment crosses a surface.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"
#include "predicates.hpp"
#include "rescale.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// Whether the oriented boxes a and b may overlap: no separating axis among those of
// obb_squared_distance (the same tests, each lowered by the same slack), stopping at the first
// that separates, and the centre line's tested without its square root and division
// (length - reach / length > slack as length^2 - reach > slack * length, squared); then the
// nine edge-pair axes.
// A box whose longest half extent is over three times its middle one (a needle, as the
// boxes of a tube's pieces): the one shape whose overlap the edge-pair axes decide where the
// face axes do not. For flat and round boxes they rarely separate and are not worth their cost.
inline bool elongated(const Vec3& half) {
    const double lo = min2(half.x, min2(half.y, half.z)), hi = max2(half.x, max2(half.y, half.z));
    const double mid = half.x + half.y + half.z - lo - hi;
    return hi > 3.0 * mid;
}

// How deep two boxes' projections on their centre line overlap: reach / length2 (above 1 when
// they overlap there), kept as the two numbers so that comparing two depths needs no division.
struct CentreLineDepth {
    double reach = 0.0, length2 = 0.0;
    bool deeper_than(const CentreLineDepth& o) const { return reach * o.length2 > o.reach * length2; }
};

// The nine edge-pair axes a_i x b_j (Gottschalk, Lin and Manocha 1996), in a's box frame (the
// caller tests them where either box is elongated): the projection of the centre line t
// against the two boxes' radii. c[i][j] = a_i . b_j. The axes are not unit (|a_i x b_j| <= 1),
// so a gap above slack is above slack * |axis| too; an axis that vanishes (parallel edges) has
// every term within rounding of 0 and separates nothing.
inline bool edge_axes_overlap(const Vec3& half_a, const Vec3& half_b, const Vec3& t,
                              const double (*c)[3], const double (*abs_c)[3], double slack) {
    for (int i = 0; i < 3; ++i) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j) {
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const double ra = half_a[i1] * abs_c[i2][j] + half_a[i2] * abs_c[i1][j];
            const double rb = half_b[j1] * abs_c[i][j2] + half_b[j2] * abs_c[i][j1];
            if (std::fabs(t[i2] * c[i1][j] - t[i1] * c[i2][j]) - ra - rb - slack > 0.0)
                return false;
        }
    }
    return true;
}

// With `overlap` set, writes the boxes' CentreLineDepth (zero for coincident centres); the
// ordered descent of mesh_intersects reads it.
//
// A box whose axes are the identity (NodeObb::axis_aligned, most boxes near the root) skips its
// products with them: the same values up to the sign of a zero, which every use below takes
// the absolute value of, multiplies into a term whose absolute value is taken, or compares
// with zero, so every decision is the same. Two such boxes read a_i . b_j and its absolute
// value from rel.rotation and rel.abs_rotation.
#if defined(__SSE2__)
// The same test with two of each three components in the lanes of an SSE2 register and the
// third alone: IEEE's operations round the same in a lane as alone, and each value below is
// formed by the operations of the scalar form (#else) in its order (products of two factors,
// sums left to right), so every value and decision is the scalar form's, in fewer
// instructions (408 to 369 a test on bench_mesh_query's balls, benchmarks/RESULTS.md, session
// 27). Lanes hold components 0 and 1 of a vector, or rows 0 and 1 of a column of
// a_i . b_j; no separating axis is tested before the others, as their order does not change
// the answer.
inline bool obb_overlap(const NodeObb& a, const NodeObb& b, const Relative& rel,
                        CentreLineDepth* overlap = nullptr) {
    const __m128d sign = _mm_set1_pd(-0.0);
    const auto vabs = [sign](__m128d v) { return _mm_andnot_pd(sign, v); };
    const auto lane0 = [](__m128d v) { return _mm_cvtsd_f64(v); };
    const auto lane1 = [](__m128d v) { return _mm_cvtsd_f64(_mm_unpackhi_pd(v, v)); };
    const auto both = [](double x) { return _mm_set1_pd(x); };
    const auto add = [](__m128d x, __m128d y) { return _mm_add_pd(x, y); };
    const auto mul = [](__m128d x, __m128d y) { return _mm_mul_pd(x, y); };
    // (m x + n y) + o z in the lanes.
    const auto combine = [&](__m128d m, __m128d n, __m128d o, double x, double y, double z) {
        return add(add(mul(m, both(x)), mul(n, both(y))), mul(o, both(z)));
    };
    // Columns k of matrix m's first two rows: (m[0][k], m[1][k]).
    const auto columns = [](const Mat3& m, __m128d col[3]) {
        const __m128d r0 = _mm_loadu_pd(m.m[0]), r1 = _mm_loadu_pd(m.m[1]);
        col[0] = _mm_unpacklo_pd(r0, r1);
        col[1] = _mm_unpackhi_pd(r0, r1);
        col[2] = _mm_set_pd(m.m[1][2], m.m[0][2]);
    };
    const double(*r)[3] = rel.rotation.m;
    __m128d rc[3];
    for (int k = 0; k < 3; ++k) rc[k] = _mm_loadu_pd(rel.columns01[k]);
    // d = rel.apply(b.center) - a.center, a's local frame
    const Vec3& bc = b.center;
    const __m128d mapped01 = add(combine(rc[0], rc[1], rc[2], bc.x, bc.y, bc.z),
                                 _mm_loadu_pd(&rel.translation.x));
    const __m128d d01 = _mm_sub_pd(mapped01, _mm_loadu_pd(&a.center.x));
    const double d2 =
        (((r[2][0] * bc.x + r[2][1] * bc.y) + r[2][2] * bc.z) + rel.translation.z) - a.center.z;
    const double d0 = lane0(d01), d1 = lane1(d01);
    // t = a.axes d (a's box frame)
    __m128d ac[3];
    if (!a.axis_aligned) columns(a.axes, ac);
    const double(*am)[3] = a.axes.m;
    const __m128d t01 = a.axis_aligned ? d01 : combine(ac[0], ac[1], ac[2], d0, d1, d2);
    const double t2 = a.axis_aligned ? d2 : (am[2][0] * d0 + am[2][1] * d1) + am[2][2] * d2;
    const __m128d square = mul(d01, d01);
    const double length2 = (lane0(square) + lane1(square)) + d2 * d2;
    // rotation^T d (b's local frame), then tb = b.axes of it (b's box frame)
    const __m128d e01 =
        combine(_mm_loadu_pd(r[0]), _mm_loadu_pd(r[1]), _mm_loadu_pd(r[2]), d0, d1, d2);
    const double e2 = (r[0][2] * d0 + r[1][2] * d1) + r[2][2] * d2;
    __m128d bcol[3];
    if (!b.axis_aligned) columns(b.axes, bcol);
    const double(*bm)[3] = b.axes.m;
    const double e0 = lane0(e01), e1 = lane1(e01);
    const __m128d tb01 = b.axis_aligned ? e01 : combine(bcol[0], bcol[1], bcol[2], e0, e1, e2);
    const double tb2 = b.axis_aligned ? e2 : (bm[2][0] * e0 + bm[2][1] * e1) + bm[2][2] * e2;
    const __m128d half_a01 = _mm_loadu_pd(&a.half.x), half_b01 = _mm_loadu_pd(&b.half.x);
    const __m128d abs_t01 = vabs(t01), abs_tb01 = vabs(tb01);
    if (length2 > 0.0) {
        const __m128d pa = mul(abs_t01, half_a01), pb = mul(abs_tb01, half_b01);
        const double reach = ((((lane0(pa) + lane1(pa)) + std::fabs(t2) * a.half.z) + lane0(pb)) +
                              lane1(pb)) +
                             std::fabs(tb2) * b.half.z;
        const double excess = length2 - reach;
        if (excess > 0.0 && excess * excess > rel.slack * rel.slack * length2) return false;
        if (overlap != nullptr) *overlap = CentreLineDepth{reach, length2};
    }
    // a_i . b_j: column j's rows 0 and 1 in cj[j], row 2 in c2[j] (rel.rotation's when both
    // boxes are axis-aligned; b_j = rel.rotation b.axes.row(j) in a's frame otherwise).
    __m128d cj[3];
    double c2[3];
    for (int j = 0; j < 3; ++j) {
        if (a.axis_aligned && b.axis_aligned) {
            cj[j] = rc[j];
            c2[j] = r[2][j];
            continue;
        }
        __m128d bj01 = rc[j];
        double bj2 = r[2][j];
        if (!b.axis_aligned) {
            bj01 = combine(rc[0], rc[1], rc[2], bm[j][0], bm[j][1], bm[j][2]);
            bj2 = (r[2][0] * bm[j][0] + r[2][1] * bm[j][1]) + r[2][2] * bm[j][2];
        }
        if (a.axis_aligned) {
            cj[j] = bj01;
            c2[j] = bj2;
            continue;
        }
        const double x = lane0(bj01), y = lane1(bj01);
        cj[j] = combine(ac[0], ac[1], ac[2], x, y, bj2);
        c2[j] = (am[2][0] * x + am[2][1] * y) + am[2][2] * bj2;
    }
    const __m128d abs0 = vabs(cj[0]), abs1 = vabs(cj[1]), abs2 = vabs(cj[2]);
    const double abs20 = std::fabs(c2[0]), abs21 = std::fabs(c2[1]), abs22 = std::fabs(c2[2]);
    const double slack = rel.slack;
    const __m128d slack01 = both(slack);
    // a's face axes 0 and 1 in the lanes, then 2
    const __m128d reach_a01 = combine(abs0, abs1, abs2, b.half.x, b.half.y, b.half.z);
    const __m128d gap_a01 =
        _mm_sub_pd(_mm_sub_pd(_mm_sub_pd(abs_t01, half_a01), reach_a01), slack01);
    const double gap_a2 = ((std::fabs(t2) - a.half.z) -
                           ((abs20 * b.half.x + abs21 * b.half.y) + abs22 * b.half.z)) -
                          slack;
    // b's face axes 0 and 1 in the lanes (rows of |a_i . b_j| for j = 0, 1), then 2
    const __m128d row0 = _mm_unpacklo_pd(abs0, abs1), row1 = _mm_unpackhi_pd(abs0, abs1);
    const __m128d row2 = _mm_set_pd(abs21, abs20);
    const __m128d reach_b01 = add(add(mul(both(a.half.x), row0), mul(both(a.half.y), row1)),
                                  mul(both(a.half.z), row2));
    const __m128d gap_b01 =
        _mm_sub_pd(_mm_sub_pd(_mm_sub_pd(abs_tb01, reach_b01), half_b01), slack01);
    const double reach_b2 =
        (a.half.x * lane0(abs2) + a.half.y * lane1(abs2)) + a.half.z * abs22;
    const double gap_b2 = ((std::fabs(tb2) - reach_b2) - b.half.z) - slack;
    const __m128d zero = _mm_setzero_pd();
    const __m128d apart = _mm_or_pd(_mm_cmpgt_pd(gap_a01, zero), _mm_cmpgt_pd(gap_b01, zero));
    if (_mm_movemask_pd(apart) != 0 || gap_a2 > 0.0 || gap_b2 > 0.0) return false;
    if (!elongated(a.half) && !elongated(b.half)) return true;
    double c[3][3], abs_c[3][3];
    for (int j = 0; j < 3; ++j) {
        c[0][j] = lane0(cj[j]);
        c[1][j] = lane1(cj[j]);
        c[2][j] = c2[j];
        for (int i = 0; i < 3; ++i) abs_c[i][j] = std::fabs(c[i][j]);
    }
    return edge_axes_overlap(a.half, b.half, Vec3{lane0(t01), lane1(t01), t2}, c, abs_c, slack);
}
#endif

// The scalar form: the test itself where SSE2 is absent, and the reference the SSE2 form is
// checked against everywhere (mesh_detail::box_test_forms_agree, a C++ test).
inline bool obb_overlap_scalar(const NodeObb& a, const NodeObb& b, const Relative& rel,
                               CentreLineDepth* overlap = nullptr) {
    const Vec3 d = rel.apply(b.center) - a.center;  // a's local frame
    const Vec3 t = a.axis_aligned ? d : a.axes * d;  // a's box frame
    const double length2 = dot(d, d);
    const Vec3 d_in_b = rel.rotation.transpose_times(d);
    const Vec3 tb = b.axis_aligned ? d_in_b : b.axes * d_in_b;  // b's box frame
    if (length2 > 0.0) {
        const double reach = std::fabs(t.x) * a.half.x + std::fabs(t.y) * a.half.y + std::fabs(t.z) * a.half.z +
                             std::fabs(tb.x) * b.half.x + std::fabs(tb.y) * b.half.y + std::fabs(tb.z) * b.half.z;
        const double excess = length2 - reach;
        if (excess > 0.0 && excess * excess > rel.slack * rel.slack * length2) return false;
        if (overlap != nullptr) *overlap = CentreLineDepth{reach, length2};
    }
    // a_i . b_j and its absolute value, both axes in a's local frame
    double product[3][3], abs_product[3][3];
    const double(*c)[3] = rel.rotation.m;
    const double(*abs_c)[3] = rel.abs_rotation.m;
    if (!a.axis_aligned || !b.axis_aligned) {
        for (int j = 0; j < 3; ++j) {
            const Vec3 bj = b.axis_aligned ? rel.rotation.column(j) : rel.rotation * b.axes.row(j);
            for (int i = 0; i < 3; ++i) {
                product[i][j] = a.axis_aligned ? bj[i] : dot(a.axes.row(i), bj);
                abs_product[i][j] = std::fabs(product[i][j]);
            }
        }
        c = product;
        abs_c = abs_product;
    }
    for (int i = 0; i < 3; ++i)
        if (std::fabs(t[i]) - a.half[i] - (abs_c[i][0] * b.half.x + abs_c[i][1] * b.half.y + abs_c[i][2] * b.half.z) -
                rel.slack > 0.0)
            return false;
    for (int j = 0; j < 3; ++j)
        if (std::fabs(tb[j]) - (a.half.x * abs_c[0][j] + a.half.y * abs_c[1][j] + a.half.z * abs_c[2][j]) - b.half[j] -
                rel.slack > 0.0)
            return false;
    return (!elongated(a.half) && !elongated(b.half)) ||
           edge_axes_overlap(a.half, b.half, t, c, abs_c, rel.slack);
}

#if !defined(__SSE2__)
inline bool obb_overlap(const NodeObb& a, const NodeObb& b, const Relative& rel, CentreLineDepth* overlap = nullptr) {
    return obb_overlap_scalar(a, b, rel, overlap);
}
#endif

// Whether the oriented boxes of node pair (a node, b node) may overlap (obb_overlap).
inline bool boxes_overlap(const MeshBvh& a, const MeshBvh& b, std::pair<std::int32_t, std::int32_t> pair,
                          const Relative& rel) {
    return obb_overlap(a.obbs()[static_cast<size_t>(pair.first)], b.obbs()[static_cast<size_t>(pair.second)], rel);
}

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
    int size() const { return size_; }
    void push(std::int32_t a, std::int32_t b) {
        if (size_ < kInline) {
            inline_[size_] = Item{a, b};
        } else {
            spill_.push_back(Item{a, b});
        }
        ++size_;
    }
    // push(a, b) if `keep`, with no branch on it while the pairs fit inline: the entry is
    // written either way and counted only if kept (the axis-aligned descent's child pairs,
    // whose box tests go either way).
    void push_if(std::int32_t a, std::int32_t b, bool keep) {
        if (size_ < kInline) {
            inline_[size_] = Item{a, b};
            size_ += keep;
        } else if (keep) {
            spill_.push_back(Item{a, b});
            ++size_;
        }
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
//
// With `ordered`, of two overlapping child pairs the one whose boxes overlap deeper along
// their centre line is descended first (mesh_intersects: a pair of surfaces that cross is
// proved so after fewer box tests); the set of pairs visited until a stop is otherwise the
// same, so a descent run to the end visits the same pairs, in another order.
//
// With `split_both` (not with `ordered`), a pair of internal nodes is split on both sides at
// once: its four child pairs are tested, where splitting the larger node and then each
// overlapping child pair's other node takes up to six tests to reach them. A descent run to
// the end then reaches every crossing triangle pair as before (every box holds its
// triangles), but through other node pairs, so the triangle pairs whose boxes touch can
// differ a little among those whose oriented node boxes only nearly meet (a child's box is
// not inside its parent's). The contacts' descent (for_each_crossing_pair) runs so. Given
// `rest`, it stops once it has split `splits_left` pairs so (four box tests each; without
// split_both, node pairs split on one side, two tests each): it then leaves the node pairs
// still to descend in *rest (the pair at hand among them) and returns false, for another
// descent to finish from there. Given `start`, it descends from the node
// pairs there (such a *rest) instead of from the roots: stopped and started so, it visits the
// triangle pairs it would have visited uninterrupted, in the same order.
// Not inlined (nor the axis-aligned descent below): for_each_crossing_pair instantiates three
// descents, and inlined there they took 0.1% to 1.7% more instructions on the contacts rows.
template <class Visit>
__attribute__((noinline)) bool for_each_touching_pair(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                                                      Visit visit, double margin2 = 0.0, bool ordered = false,
                                                      bool split_both = false,
                                                      long long splits_left = std::numeric_limits<long long>::max(),
                                                      NodePairStack* rest = nullptr,
                                                      const NodePairStack* start = nullptr) {
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    NodePairStack stack;
    if (start != nullptr) {
        stack = *start;
    } else {
        if (!boxes_overlap(a, b, {0, 0}, rel)) return false;
        stack.push(0, 0);
    }
    MappedLeaf leaf_b;
    std::int32_t loaded = -1;  // b's leaf in leaf_b
    while (!stack.empty()) {
        const auto [ia, ib] = stack.pop();
        const BvhNode& x = na[static_cast<size_t>(ia)];
        const BvhNode& y = nb[static_cast<size_t>(ib)];
        if (x.is_leaf() && y.is_leaf()) {
            // A descent meets b's leaf against a's sibling leaves in a row: mapped once.
            if (ib != loaded) {
                leaf_b.load(b, y, rel);
                loaded = ib;
            }
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const Vec3* ta = a.triangle(i);
                const TriangleBox box_a = stored_box(a, i);
                for (int j = 0; j < leaf_b.count; ++j)
                    if ((margin2 == 0.0
                             ? triangle_boxes_touch(box_a, leaf_b.boxes[j])
                             : triangle_box_squared_distance(box_a, leaf_b.boxes[j]) <= margin2) &&
                        visit(i, y.index + j, ta, leaf_b.corners[j]))
                        return true;
            }
            continue;
        }
        const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
        const std::pair<std::int32_t, std::int32_t> c1 = descend_a ? std::make_pair(ia + 1, ib) : std::make_pair(ia, ib + 1);
        const std::pair<std::int32_t, std::int32_t> c2 = descend_a ? std::make_pair(x.index, ib) : std::make_pair(ia, y.index);
        if (ordered) {
            CentreLineDepth deep1, deep2;
            const bool o1 = obb_overlap(a.obbs()[static_cast<size_t>(c1.first)], b.obbs()[static_cast<size_t>(c1.second)], rel, &deep1);
            const bool o2 = obb_overlap(a.obbs()[static_cast<size_t>(c2.first)], b.obbs()[static_cast<size_t>(c2.second)], rel, &deep2);
            if (o1 && o2 && deep2.deeper_than(deep1)) {
                stack.push(c1.first, c1.second);
                stack.push(c2.first, c2.second);
            } else {
                if (o2) stack.push(c2.first, c2.second);
                if (o1) stack.push(c1.first, c1.second);
            }
            continue;
        }
        if (split_both && !x.is_leaf() && !y.is_leaf()) {
            if (--splits_left < 0) {
                stack.push(ia, ib);
                *rest = stack;
                return false;
            }
            for (const std::int32_t child_a : {x.index, ia + 1})
                for (const std::int32_t child_b : {y.index, ib + 1})
                    if (boxes_overlap(a, b, {child_a, child_b}, rel)) stack.push(child_a, child_b);
            continue;
        }
        if (!split_both && rest != nullptr && --splits_left < 0) {
            stack.push(ia, ib);
            *rest = stack;
            return false;
        }
        if (boxes_overlap(a, b, c2, rel)) stack.push(c2.first, c2.second);
        if (boxes_overlap(a, b, c1, rel)) stack.push(c1.first, c1.second);
    }
    return false;
}

// Under rel.translation_only (equal rotations: Relative makes the rotation the identity,
// exactly), rel.apply(p) is p + translation rounded once per coordinate (1 p_k is p_k, a
// product with 0 is a zero, and adding a zero changes at most the sign of a zero), so adding
// the translation to b's node boxes, rounded the same way, bounds b's mapped corners:
// rounding is monotone, and a corner is inside its node's box.

// Node y's box moved by `shift` (the box of its corners mapped, by the argument above).
inline TriangleBox moved_box(const BvhNode& y, const Vec3& shift) {
    TriangleBox box;
    for (int k = 0; k < 3; ++k) {
        box.lower[k] = static_cast<double>(y.lower[k]) + shift[k];
        box.upper[k] = static_cast<double>(y.upper[k]) + shift[k];
    }
    return box;
}

// Node x's box (its floats, exactly).
inline TriangleBox node_box(const BvhNode& x) {
    return {{x.lower[0], x.lower[1], x.lower[2]}, {x.upper[0], x.upper[1], x.upper[2]}};
}

// Whether node x of a and node y of b (moved by `shift`, a's frame) may hold a triangle pair
// whose boxes touch (triangle_boxes_touch): false only when a gap along an axis is positive
// with a positive square (gap > kTouchGap). A triangle box lies inside its node's box, and the
// differences round monotonically, so a triangle pair's gap there is at least the nodes' gap:
// that pair's boxes do not touch either.
// The test is triangle_boxes_touch_at_once's (interval_gap, gaps_touch: mesh_query_detail.hpp),
// as is RefitB::touches' below, on the nodes' floats converted where they are read.
inline bool aligned_boxes_touch(const BvhNode& x, const BvhNode& y, const Vec3& shift) {
    double gap[3];
    for (int k = 0; k < 3; ++k) {
        const double lower_b = static_cast<double>(y.lower[k]) + shift[k];
        const double upper_b = static_cast<double>(y.upper[k]) + shift[k];
        gap[k] = interval_gap(x.lower[k], x.upper[k], lower_b, upper_b);
    }
    return gaps_touch(gap[0], gap[1], gap[2]);
}

// b's boxes in a's frame under rel.translation_only: its node boxes and triangle boxes as
// built, moved by the translation; a triangle's corners mapped (rel.apply) once a triangle of a
// touches its box. Held by value (pointers and the shift), so that a descent keeps them in
// registers.
struct MovedB {
    const BvhNode* nodes;
    const MeshBvh* b;
    const Relative* rel;
    Vec3 shift;
    MovedB(const MeshBvh& mesh, const Relative& r)
        : nodes(mesh.nodes().data()), b(&mesh), rel(&r), shift(r.translation) {}
    bool touches(const BvhNode& x, std::int32_t ib) const { return aligned_boxes_touch(x, nodes[ib], shift); }
    // Node ib's box in a's frame.
    TriangleBox box(std::int32_t ib) const { return moved_box(nodes[ib], shift); }
    // Triangle t's box in a's frame; its corners are mapped later (map) when wanted: false.
    bool load(std::int32_t t, TriangleBox* box, Vec3*) const {
        const TriangleBox local = stored_box(*b, t);
        *box = {local.lower + shift, local.upper + shift};
        return false;
    }
    void map(std::int32_t t, Vec3* corners) const {
        const Vec3* c = b->triangle(t);
        for (int k = 0; k < 3; ++k) corners[k] = rel->apply(c[k]);
    }
};

// The box tests of a turned pair's oriented descent after which mesh_contacts refits b in a's
// frame, at the least (for_each_crossing_pair): the benchmark's family rows take at most 1,104
// a query, and below this a mesh's slanted patches, not the refit, decide (the 300-face Panda
// link is looser by axis-aligned boxes on 206 of its 300 touching pairs).
constexpr long long kRefitBoxTests = 1024;

// At most this many node pairs left to descend when the refit point comes: the oriented
// descent goes on instead (a query near its end: the refit's 70 instructions a face of b would
// not pay). On bench_mesh_query's fandisk rows 3 of 300 queries reach 1,024 box tests with 1
// to 4 pairs left and end soon after; the turned torus has more left (benchmarks/RESULTS.md,
// session 30, branch contact20).
constexpr int kResumePairs = 4;

// b's vertices mapped into a's frame (rel.apply, as the leaves map a triangle's corners, so
// every corner has the same bits) and its nodes' axis-aligned boxes refitted over them there:
// the tight boxes of b's tree topology in a's frame, made once a query (O(vertices + nodes) of
// b). RefitB reads them.
struct RefitBoxes {
    std::vector<Vec3> vertices;
    std::vector<TriangleBox> boxes;
    RefitBoxes(const MeshBvh& b, const Relative& rel) {
        const std::vector<Vec3>& local = b.vertices();
        vertices.resize(local.size());
        for (size_t v = 0; v < local.size(); ++v) vertices[v] = rel.apply(local[v]);
        const std::vector<BvhNode>& nodes = b.nodes();
        boxes.resize(nodes.size());
        // Depth-first order: both children of a node come after it.
        for (size_t id = nodes.size(); id-- > 0;) {
            const BvhNode& n = nodes[id];
            if (!n.is_leaf()) {
                const TriangleBox& l = boxes[id + 1];
                const TriangleBox& r = boxes[static_cast<size_t>(n.index)];
                boxes[id] = {min3(l.lower, r.lower), max3(l.upper, r.upper)};
                continue;
            }
            const std::int32_t* v = b.triangle_vertices(n.index);
            TriangleBox box{vertices[static_cast<size_t>(v[0])], vertices[static_cast<size_t>(v[0])]};
            for (std::int32_t k = 1; k < 3 * n.count; ++k) {
                const Vec3& p = vertices[static_cast<size_t>(v[k])];
                box = {min3(box.lower, p), max3(box.upper, p)};
            }
            boxes[id] = box;
        }
    }
};

// b's boxes in a's frame for a turned pair: RefitBoxes' node boxes, and a triangle's corners
// (its mapped vertices) and their box.
struct RefitB {
    const TriangleBox* boxes;
    const Vec3* vertices;
    const MeshBvh* b;
    RefitB(const RefitBoxes& refit, const MeshBvh& mesh)
        : boxes(refit.boxes.data()), vertices(refit.vertices.data()), b(&mesh) {}
    // aligned_boxes_touch's test, on refitted boxes (the same gap logic: see there).
    bool touches(const BvhNode& x, std::int32_t ib) const {
        const TriangleBox& y = boxes[ib];
        double gap[3];
        for (int k = 0; k < 3; ++k) gap[k] = interval_gap(x.lower[k], x.upper[k], y.lower[k], y.upper[k]);
        return gaps_touch(gap[0], gap[1], gap[2]);
    }
    TriangleBox box(std::int32_t ib) const { return boxes[ib]; }
    bool load(std::int32_t t, TriangleBox* box, Vec3* corners) const {
        map(t, corners);
        *box = triangle_box(corners);
        return true;
    }
    void map(std::int32_t t, Vec3* corners) const {
        const std::int32_t* v = b->triangle_vertices(t);
        for (int k = 0; k < 3; ++k) corners[k] = vertices[v[k]];
    }
};

// for_each_touching_pair (no margin, split on both sides) by axis-aligned boxes in a's frame:
// a's as built, b's as `b_in_a` gives them (MovedB under rel.translation_only, RefitB for a
// turned pair), a few compares a test where the oriented boxes take about 160 instructions,
// from the node pairs on `stack` (whose boxes may touch). It visits every triangle pair under
// them whose boxes touch (each once; b's corners mapped by rel.apply as there), a superset of
// the pairs the oriented descent visits, which misses only pairs whose node boxes are apart
// and so cannot meet: the crossing pairs are the same, in another order.
// With `plain_order` (the depth query's marks), it descends as the plain oriented descent
// does (for_each_touching_pair neither ordered nor split on both sides: the larger node of a
// pair split, the pairs under its first child first), so that it meets the pairs that both
// visit in that descent's order, and compares the boxes within sqrt(margin2) (their
// triangle_box_squared_distance, as for_each_touching_pair with a margin, formed without a
// branch by boxes_squared_distance_at_once): every triangle pair whose boxes are that close
// is visited. A triangle's box lies in its node's, and the
// moved and refitted boxes round monotonically, so a node pair's squared distance is at most
// that of each triangle pair under it: no pair within the margin is pruned.
template <bool plain_order = false, class BInA, class Visit>
__attribute__((noinline)) bool for_each_touching_pair_aligned(const MeshBvh& a, const MeshBvh& b, const BInA b_in_a,
                                                              Visit visit, NodePairStack& stack,
                                                              double margin2 = 0.0) {
    const std::vector<BvhNode>& na = a.nodes();
    const std::vector<BvhNode>& nb = b.nodes();
    // b's leaf in reach: its triangles' boxes in a's frame (b_in_a.load), and their corners
    // mapped, at the latest once a triangle of a touches that box.
    struct {
        TriangleBox boxes[defaults::mesh_bvh_leaf_size];
        Vec3 corners[defaults::mesh_bvh_leaf_size][3];
        bool mapped[defaults::mesh_bvh_leaf_size];
    } leaf_b;
    std::int32_t loaded = -1;  // b's leaf in leaf_b
    while (!stack.empty()) {
        const auto [ia, ib] = stack.pop();
        const BvhNode& x = na[static_cast<size_t>(ia)];
        const BvhNode& y = nb[static_cast<size_t>(ib)];
        if (x.is_leaf() && y.is_leaf()) {
            // b's leaf box holds its triangles' boxes: a triangle of a whose box does not
            // touch it touches none of them.
            const TriangleBox box_y = b_in_a.box(ib);
            const auto boxes_meet = [margin2](const TriangleBox& p, const TriangleBox& q) {
                if constexpr (plain_order) return boxes_squared_distance_at_once(p, q) <= margin2;
                return triangle_boxes_touch_at_once(p, q);
            };
            for (std::int32_t i = x.index; i < x.index + x.count; ++i) {
                const TriangleBox box_a = stored_box(a, i);
                if (!boxes_meet(box_a, box_y)) continue;
                const Vec3* ta = a.triangle(i);
                if (ib != loaded) {
                    for (int j = 0; j < y.count; ++j)
                        leaf_b.mapped[j] = b_in_a.load(y.index + j, &leaf_b.boxes[j], leaf_b.corners[j]);
                    loaded = ib;
                }
                // The triangles of b's leaf whose boxes touch box_a, as bits (leaf_size <= 32),
                // visited in order: one branch a visit, not one a box test.
                static_assert(defaults::mesh_bvh_leaf_size <= 32, "a leaf's triangles as the bits of an unsigned");
                unsigned touching = 0;
                for (int j = 0; j < y.count; ++j)
                    touching |= static_cast<unsigned>(boxes_meet(box_a, leaf_b.boxes[j])) << j;
                for (; touching != 0; touching &= touching - 1) {
                    const int j = __builtin_ctz(touching);
                    if (!leaf_b.mapped[j]) {
                        b_in_a.map(y.index + j, leaf_b.corners[j]);
                        leaf_b.mapped[j] = true;
                    }
                    if (visit(i, y.index + j, ta, leaf_b.corners[j])) return true;
                }
            }
            continue;
        }
        if constexpr (plain_order) {
            const bool descend_a = !x.is_leaf() && (y.is_leaf() || node_size(x) >= node_size(y));
            const auto near = [&](std::int32_t child_a, std::int32_t child_b) {
                return boxes_squared_distance_at_once(node_box(na[static_cast<size_t>(child_a)]), b_in_a.box(child_b)) <=
                       margin2;
            };
            const std::int32_t first_a = descend_a ? ia + 1 : ia, first_b = descend_a ? ib : ib + 1;
            const std::int32_t second_a = descend_a ? x.index : ia, second_b = descend_a ? ib : y.index;
            stack.push_if(second_a, second_b, near(second_a, second_b));
            stack.push_if(first_a, first_b, near(first_a, first_b));
            continue;
        }
        const std::int32_t a_children[2] = {x.is_leaf() ? ia : x.index, x.is_leaf() ? -1 : ia + 1};
        const std::int32_t b_children[2] = {y.is_leaf() ? ib : y.index, y.is_leaf() ? -1 : ib + 1};
        // b's children outermost: the pairs of one child of b come off the stack in a row, so
        // its leaves, once reached, are mapped once for a's sibling leaves.
        for (const std::int32_t child_b : b_children) {
            if (child_b < 0) continue;
            for (const std::int32_t child_a : a_children)
                if (child_a >= 0) stack.push_if(child_a, child_b, b_in_a.touches(na[static_cast<size_t>(child_a)], child_b));
        }
    }
    return false;
}

// Whether triangle i of a and triangle j of b (corners ta, and tb mapped into a's frame) lie
// strictly apart across either one's plane: all three corners of one more than rel.slack
// (the pair's rounding allowance, far above the rounding of these dot products, of the unit
// normals and of the mapping) to the same side of the other's plane. Such a pair cannot
// meet, so the exact test would say no: it is skipped, a dozen multiplications against the
// exact predicates of triangles_intersect. A degenerate triangle (zero normal) separates
// nothing.
// `at_once`: each plane's three sides formed and compared together, one branch for six
// (the contacts' axis-aligned descent, where a pair's outcome is about as likely either way);
// else each corner's side only while the ones before it agree. The same verdicts.
template <bool at_once = false>
inline bool planes_separate(const MeshBvh& a, std::int32_t i, const Vec3* ta, const MeshBvh& b, std::int32_t j,
                            const Vec3* tb, const Relative& rel) {
    const auto apart = [&rel](const Vec3& n, const Vec3& origin, const Vec3* t) -> bool {
        const double s0 = dot(n, t[0] - origin);
        if constexpr (at_once) {
            const double s1 = dot(n, t[1] - origin), s2 = dot(n, t[2] - origin);
            return (min2(s0, min2(s1, s2)) > rel.slack) | (max2(s0, max2(s1, s2)) < -rel.slack);
        }
        if (s0 > rel.slack) return dot(n, t[1] - origin) > rel.slack && dot(n, t[2] - origin) > rel.slack;
        if (s0 < -rel.slack) return dot(n, t[1] - origin) < -rel.slack && dot(n, t[2] - origin) < -rel.slack;
        return false;
    };
    if (apart(a.triangle_normal(i), ta[0], tb)) return true;
    // Under rel.translation_only the rotation is the identity, exactly: its product with b's
    // normal is that normal but for the sign of a zero component (1 x + 0 y + 0 z), which
    // changes no comparison with +-rel.slack (a signed zero product adds as a zero).
    const Vec3& normal_b = b.triangle_normal(j);
    return apart(rel.translation_only ? normal_b : rel.rotation * normal_b, tb[0], ta);
}

// The verdict of triangles_intersect(ta, tb, nullptr) in the one case, the commonest, where no
// corner of either triangle lies on the other's plane (all six orientation signs non-zero),
// else kUndecided (a corner on a plane: coplanar, touching at a corner, degenerate; the
// caller runs triangles_intersect). Then both triangles are proper (a degenerate one has
// every sign of the other's corners 0), and unless one lies on one side of the other's plane
// each meets that plane in a closed segment of the line L where the planes cross, between the
// points where its two edges with corners on both sides cross it; the triangles meet exactly
// when the two segments overlap (touching counts), which two orientations of corners decide
// (Guigue and Devillers 2003, in quick_verdict; triangles_cross, triangle_intersect.cpp, orders
// the four crossing points along L instead, up to four orientations). Every sign is exact
// (predicates.hpp), so the verdict is triangles_intersect's: eight orientations at most, where
// that test's edge-against-triangle form takes up to 24 and two projection axes.
// kMeet: a general pair (no corner on the other's plane) that meets; kTouch: one that meets
// with a corner on the other's plane, decided by flush_verdict.
enum class Verdict { kApart, kMeet, kTouch, kUndecided };

// The coordinate in which triangle t's corners are equal (it lies in a coordinate plane), else
// -1: plain compares, as few as a triangle that is not flat needs.
inline int flat_axis(const Vec3* t) {
    if (t[1].x == t[0].x && t[2].x == t[0].x) return 0;
    if (t[1].y == t[0].y && t[2].y == t[0].y) return 1;
    if (t[1].z == t[0].z && t[2].z == t[0].z) return 2;
    return -1;
}

// Where `plane`'s triangle lies in a coordinate plane x_k = c (a floor's, a box's face) and a
// corner of t lies on it (exactly: orient3d's column of differences is 0 there, and so is its
// sign): true, with the verdict in *v. If t's other corners lie strictly on one side, t meets
// the plane in the hull of its corners there (a point or a segment), and the triangles meet iff
// that hull meets `plane`'s triangle: a question in the coordinate plane, decided by the exact
// orient2d of the two other coordinates (a point is apart when strictly outside an edge's line;
// a segment when both ends are, or when the three corners are strictly on one side of its line:
// the separating axis theorem for convex polygons). kUndecided when t crosses the plane there,
// lies in it, or `plane`'s triangle is degenerate. False (no verdict) when no corner of t is on
// it. k: the coordinate, flat_axis(plane).
bool flush_verdict(const Vec3* plane, int k, const Vec3* t, Verdict* v) {
    const double c = plane[0][k];
    const Vec3* on[3];
    int count = 0, above = 0, below = 0;
    for (int j = 0; j < 3; ++j) {
        if (t[j][k] == c) {
            on[count++] = &t[j];
        } else {
            (t[j][k] > c ? above : below) += 1;
        }
    }
    if (count == 0) return false;
    *v = Verdict::kUndecided;
    if (count == 3 || (above > 0 && below > 0)) return true;
    const int x = k == 2 ? 0 : k + 1, y = k == 0 ? 2 : k - 1;
    const auto turn = [x, y](const Vec3& p, const Vec3& q, const Vec3& r) {
        return predicates::orient2d_sign(p[x], p[y], q[x], q[y], r[x], r[y]);
    };
    const int sense = turn(plane[0], plane[1], plane[2]);
    if (sense == 0) return true;
    const Vec3& p = *on[0];
    const Vec3& q = *on[count - 1];
    for (int i = 0; i < 3; ++i) {
        const Vec3& e0 = plane[i];
        const Vec3& e1 = plane[i == 2 ? 0 : i + 1];
        if (turn(e0, e1, p) * sense < 0 && (count == 1 || turn(e0, e1, q) * sense < 0)) {
            *v = Verdict::kApart;
            return true;
        }
    }
    if (count == 2) {
        const int s0 = turn(p, q, plane[0]);
        if (s0 != 0 && turn(p, q, plane[1]) == s0 && turn(p, q, plane[2]) == s0) {
            *v = Verdict::kApart;
            return true;
        }
    }
    *v = Verdict::kTouch;
    return true;
}

// The right-hand sides (Shewchuk's orient3d negated, exactly) of t's corners to plane's
// plane, left at the first 0: false there. -orient3d(p0, p1, p2, q) is the determinant of the
// rows q - p0, p1 - p0, p2 - p0, so its expansion along the first row, (q - p0) . n with
// n = (p1 - p0) x (p2 - p0), shares n between the three corners. That expansion has the shape
// of Shewchuk's (a row of rounded differences times the 2x2 minors of the other two, each a
// difference of rounded products), so his forward error bound holds with the permanent formed
// alike, and a value above it has the exact sign; else orient3d_sign decides (its own filter,
// then the exact evaluation).
inline bool plane_sides(const Vec3* plane, const Vec3* t, int s[3]) {
    const Vec3 e1 = plane[1] - plane[0], e2 = plane[2] - plane[0];
    const double yz = e1.y * e2.z, zy = e1.z * e2.y, zx = e1.z * e2.x, xz = e1.x * e2.z;
    const double xy = e1.x * e2.y, yx = e1.y * e2.x;
    const Vec3 n{yz - zy, zx - xz, xy - yx};
    const Vec3 minor{std::fabs(yz) + std::fabs(zy), std::fabs(zx) + std::fabs(xz),
                     std::fabs(xy) + std::fabs(yx)};
    for (int k = 0; k < 3; ++k) {
        const Vec3 f = t[k] - plane[0];
        const double det = f.x * n.x + f.y * n.y + f.z * n.z;
        const double permanent =
            std::fabs(f.x) * minor.x + std::fabs(f.y) * minor.y + std::fabs(f.z) * minor.z;
        const double bound = predicates::detail::kOrient3dBound * permanent;
        // |det| > bound, not det > bound || -det > bound: the same verdict (NaN fails both),
        // in one branch that is seldom wrong, where det's sign made the first go either way.
        if (std::fabs(det) > bound && permanent > 0x1p-900) {
            s[k] = det > 0.0 ? 1 : -1;
        } else if ((s[k] = -predicates::orient3d_sign(plane[0], plane[1], plane[2], t[k])) == 0) {
            return false;
        }
    }
    return true;
}

inline Verdict quick_verdict(const Vec3* a, const Vec3* b) {
    using predicates::orient3d_sign;
    int sb[3], sa[3];
    Verdict flush;
    const int flat_a = flat_axis(a);
    if (flat_a >= 0 && flush_verdict(a, flat_a, b, &flush)) return flush;
    if (!plane_sides(a, b, sb)) return Verdict::kUndecided;
    if (sb[0] == sb[1] && sb[1] == sb[2]) return Verdict::kApart;
    const int flat_b = flat_axis(b);
    if (flat_b >= 0 && flush_verdict(b, flat_b, a, &flush)) return flush;
    if (!plane_sides(b, a, sa)) return Verdict::kUndecided;
    if (sa[0] == sa[1] && sa[1] == sa[2]) return Verdict::kApart;
    // Guigue and Devillers 2003 (their test for triangles whose planes cross): each triangle's
    // corners turned (circularly, which keeps its orientation) so that the first, p, is the
    // one alone on its side of the other's plane; q and r of the other triangle swapped where
    // p lies on the negative side, which reverses that triangle's plane; then the triangles
    // meet iff [p1, q1, p2, q2] <= 0 and [p1, r1, r2, p2] <= 0, [.] their bracket, which is
    // -orient3d. Two exact signs where the four crossing orders took up to four (all four
    // for every pair apart along the planes' line): the same verdicts.
    const auto lone = [](const int s[3]) { return s[0] == s[1] ? 2 : (s[0] == s[2] ? 1 : 0); };
    const int i = lone(sa), j = lone(sb);
    const Vec3* q1 = &a[i == 2 ? 0 : i + 1];
    const Vec3* r1 = &a[i == 0 ? 2 : i - 1];
    const Vec3* q2 = &b[j == 2 ? 0 : j + 1];
    const Vec3* r2 = &b[j == 0 ? 2 : j - 1];
    if (sa[i] < 0) std::swap(q2, r2);
    if (sb[j] < 0) std::swap(q1, r1);
    if (orient3d_sign(a[i], *q1, b[j], *q2) < 0 || orient3d_sign(a[i], *r1, *r2, b[j]) < 0)
        return Verdict::kApart;
    return Verdict::kMeet;
}

// Whether triangles ta and tb (one frame) share a point: triangles_intersect(ta, tb, nullptr),
// by quick_verdict where that decides.
inline bool meet(const Vec3* ta, const Vec3* tb) {
    const Verdict v = quick_verdict(ta, tb);
    return v == Verdict::kUndecided ? triangles_intersect(ta, tb, nullptr) : v != Verdict::kApart;
}

// The near pairs (index into a, index into b) grouped by `side`'s triangle: a counting sort
// over its near triangles (whose `last` holds their count on entry), each group in the order
// of the pairs.
void group_near_pairs(const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs, int side,
                      TriangleMarks& marks) {
    std::int32_t next = 0;
    for (TriangleMarks::Near& n : marks.near_triangles) {
        n.first = next;
        next += n.last;
        n.last = n.first;
    }
    marks.others.resize(pairs.size());
    for (const auto& pair : pairs) {
        const auto [mine, theirs] = side == 0 ? pair : std::make_pair(pair.second, pair.first);
        const auto slot = static_cast<size_t>(marks.near_slot[static_cast<size_t>(mine)]);
        marks.others[static_cast<size_t>(marks.near_triangles[slot].last++)] = theirs;
    }
}

// The triangle pairs of mark_crossing_triangles' descent (for_each_touching_pair run to the
// end with the margin rel.slack), visited in its order by the contacts' faster descents
// (for_each_crossing_pair's), each made to split as it does (plain_order): under
// rel.translation_only by axis-aligned boxes in a's frame (MovedB); for a turned pair by the
// oriented boxes, and for a dense one (past for_each_crossing_pair's number of box tests and
// with more than kResumePairs node pairs left) by b's boxes refitted in a's frame (RefitB) from
// the node pairs left. Each visits every triangle pair whose boxes are within rel.slack and
// that can be within it (the node bounds are lowered by it, and a triangle's box lies in its
// node's), so the crossing pairs are that descent's, in its order; the other pairs visited
// differ only among those farther apart than rel.slack, the pairs that both visit in the
// same order.
template <class Visit>
void for_each_near_pair_in_order(const MeshBvh& a, const MeshBvh& b, const Relative& rel, Visit visit) {
    const double margin2 = rel.slack * rel.slack;
    NodePairStack rest;
    if (rel.translation_only) {
        const MovedB moved(b, rel);
        if (triangle_box_squared_distance(node_box(a.nodes()[0]), moved.box(0)) > margin2) return;
        rest.push(0, 0);
        for_each_touching_pair_aligned<true>(a, b, moved, visit, rest, margin2);
        return;
    }
    // Two box tests a split where for_each_crossing_pair's take four.
    const long long refit_after = std::max(kRefitBoxTests, static_cast<long long>(b.nodes().size() / 4));
    if (for_each_touching_pair(a, b, rel, visit, margin2, false, false, refit_after / 2, &rest) || rest.empty())
        return;
    if (rest.size() <= kResumePairs) {
        for_each_touching_pair(a, b, rel, visit, margin2, false, false, std::numeric_limits<long long>::max(), nullptr,
                               &rest);
        return;
    }
    const RefitBoxes refit(b, rel);
    for_each_touching_pair_aligned<true>(a, b, RefitB(refit, b), visit, rest, margin2);
}

}  // namespace

namespace mesh_detail {

bool triangles_meet(const Vec3* ta, const Vec3* tb) { return meet(ta, tb); }

bool box_test_forms_agree(const NodeObb& a, const NodeObb& b, const Relative& rel, bool* verdict) {
    // Filled alike where neither form writes (a pair apart on the centre line, or centres
    // that coincide); compared as bytes, so that -0.0 and 0.0 or two NaNs would differ.
    CentreLineDepth fast{-1.0, -1.0}, plain{-1.0, -1.0};
    *verdict = obb_overlap(a, b, rel, &fast);
    return *verdict == obb_overlap_scalar(a, b, rel, &plain) &&
           std::memcmp(&fast.reach, &plain.reach, sizeof(double)) == 0 &&
           std::memcmp(&fast.length2, &plain.length2, sizeof(double)) == 0;
}

bool first_crossing(const MeshBvh& a, const MeshBvh& b, const Relative& rel, std::int32_t* triangle_a,
                    std::int32_t* triangle_b, Vec3* witness, CrossingPair* touching) {
    return for_each_touching_pair(a, b, rel, [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) {
        if (touching != nullptr && touching->a < 0) *touching = CrossingPair{i, j};
        Vec3 w;
        if (planes_separate(a, i, ta, b, j, tb, rel) || quick_verdict(ta, tb) == Verdict::kApart ||
            !triangles_intersect(ta, tb, &w))
            return false;
        *witness = w;
        *triangle_a = i;
        *triangle_b = j;
        return true;
    });
}

// The descent of mesh_intersects run to the end: the intersecting triangle pairs in descent
// order, and the marks of both meshes' triangles. Triangle pairs whose boxes are within
// rel.slack are visited too, to mark the near ones: the node bounds are lowered by rel.slack,
// so a triangle pair closer than that is never pruned. A pair that planes_separate puts
// strictly apart (farther than rel.slack across a plane) is neither crossing nor near: its
// triangles then stay in the region pass's joins (mesh_depth_closed.cpp), whose vertices are
// decided a region at a time (on the benchmark's touching family 1-8% fewer inside tests,
// on panda link3's near poses 175 -> 19). It runs by the contacts' faster descents made to keep its
// order (for_each_near_pair_in_order): the same crossing pairs in the same order.
bool mark_crossing_triangles(const MeshBvh& a, const MeshBvh& b, const Relative& rel, TriangleMarks& in_a,
                             TriangleMarks& in_b, std::vector<CrossingPair>& pairs, MarkDescent descent,
                             long long max_near_pairs) {
    pairs.clear();
    for (auto [marks, mesh] : {std::make_pair(&in_a, &a), std::make_pair(&in_b, &b)}) {
        marks->crossing.assign(static_cast<size_t>(mesh->triangle_count()), 0);
        marks->near_slot.assign(static_cast<size_t>(mesh->triangle_count()), -1);
        marks->near_triangles.clear();
    }
    // Triangle i's entry, made on its first near pair, with its pairs counted in `last`.
    const auto entry = [](TriangleMarks& marks, size_t i) -> TriangleMarks::Near& {
        std::int32_t& slot = marks.near_slot[i];
        if (slot < 0) {
            slot = static_cast<std::int32_t>(marks.near_triangles.size());
            marks.near_triangles.push_back({-1, 0, 0});
        }
        TriangleMarks::Near& n = marks.near_triangles[static_cast<size_t>(slot)];
        ++n.last;
        return n;
    };
    std::vector<std::pair<std::int32_t, std::int32_t>> near_pairs;
    bool capped = false;
    const auto mark = [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) {
        if (planes_separate<true>(a, i, ta, b, j, tb, rel)) return false;
        // A stop the descents obey (a visit that returns true ends them).
        if (static_cast<long long>(near_pairs.size()) >= max_near_pairs) return capped = true;
        const auto si = static_cast<size_t>(i), sj = static_cast<size_t>(j);
        TriangleMarks::Near& near_a = entry(in_a, si);
        TriangleMarks::Near& near_b = entry(in_b, sj);
        near_pairs.push_back({i, j});
        if (triangle_box_squared_distance(triangle_box(ta), triangle_box(tb)) == 0.0 && meet(ta, tb)) {
            in_a.crossing[si] = in_b.crossing[sj] = 1;
            if (near_a.partner < 0) near_a.partner = j;
            if (near_b.partner < 0) near_b.partner = i;
            pairs.push_back({i, j});
        }
        return false;
    };
    if (descent == MarkDescent::kPlain) {
        for_each_touching_pair(a, b, rel, mark, rel.slack * rel.slack);
    } else {
        for_each_near_pair_in_order(a, b, rel, mark);
    }
    if (capped) return false;
    group_near_pairs(near_pairs, 0, in_a);
    group_near_pairs(near_pairs, 1, in_b);
    return true;
}

// The descent of mesh_intersects to the end for mesh_contacts: the same box tests, plane
// screen and exact triangle test, no marks kept; internal node pairs split on both sides
// (split_both: a twelfth fewer box tests on the contacts rows). Under rel.translation_only, by
// axis-aligned boxes instead (for_each_touching_pair_aligned with MovedB: the same crossing
// pairs, about a fifth fewer instructions on bench_mesh_query's balls and torus rows,
// benchmarks/RESULTS.md, session 28). A turned pair starts with the oriented boxes, which
// their axis-aligned enclosures in a's frame would loosen (+9% to +295% on the benchmark's
// family rows, the same place); a dense one (more box tests than refit_after, by default
// the greater of kRefitBoxTests and a quarter of b's node count, and then more than
// kResumePairs node pairs left) finishes by axis-aligned boxes over b's vertices mapped into
// a's frame (RefitB), which costs about 70 instructions a face of b and then about a quarter
// of an oriented test per node pair (benchmarks/RESULTS.md, session 29: the turned torus row
// 22% fewer instructions when refitted from the root, the family rows 1.2 to 4.2 times more,
// their slanted patches' boxes being far looser; session 30, contact20: a quarter of b's
// nodes, where it was half, 6% fewer on the turned torus). With kResumePairs or fewer pairs
// left the oriented descent finishes from them (the default only: a refit_after given is
// obeyed as it is).
bool for_each_crossing_pair(
    const MeshBvh& a, const MeshBvh& b, const Relative& rel, long long max_work, long long* work, bool witnesses,
    const std::function<bool(std::int32_t, std::int32_t, const Vec3*, const Vec3*, const Vec3&, bool)>& visit,
    long long refit_after) {
    static const Vec3 kNoPoint{kNaN, kNaN, kNaN};
    bool capped = false;
    // Inlined into each of the three descents, as the compiler did into the two before the
    // refit: a call a visited pair took 0.3% to 3% more instructions on the contacts rows.
    // `at_once`: the plane screen's form (planes_separate), true in the axis-aligned descents.
    const auto crossing_by = [&](auto at_once) {
        return [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) __attribute__((always_inline)) {
            if (++*work > max_work) return capped = true;
            if (planes_separate<decltype(at_once)::value>(a, i, ta, b, j, tb, rel)) return false;
            // The quick verdict where it decides (no shared point: a caller that wants one asks
            // triangles_intersect again), else the full test, with its point when asked.
            const Verdict v = quick_verdict(ta, tb);
            if (v != Verdict::kUndecided)
                return v != Verdict::kApart && visit(i, j, ta, tb, kNoPoint, v == Verdict::kMeet);
            if (!witnesses) return triangles_intersect(ta, tb, nullptr) && visit(i, j, ta, tb, kNoPoint, false);
            Vec3 shared;
            return triangles_intersect(ta, tb, &shared) && visit(i, j, ta, tb, shared, false);
        };
    };
    const auto crossing = crossing_by(std::false_type{});
    const auto crossing_at_once = crossing_by(std::true_type{});
    NodePairStack rest;
    if (rel.translation_only) {
        const MovedB moved(b, rel);
        if (!moved.touches(a.nodes()[0], 0)) return false;
        rest.push(0, 0);
        for_each_touching_pair_aligned(a, b, moved, crossing_at_once, rest);
        return capped;
    }
    const bool own_choice = refit_after < 0;
    if (own_choice) refit_after = std::max(kRefitBoxTests, static_cast<long long>(b.nodes().size() / 4));
    if (!for_each_touching_pair(a, b, rel, crossing, 0.0, false, true, refit_after / 4, &rest) && !rest.empty()) {
        if (own_choice && rest.size() <= kResumePairs) {
            for_each_touching_pair(a, b, rel, crossing, 0.0, false, true, std::numeric_limits<long long>::max(),
                                   nullptr, &rest);
            return capped;
        }
        const RefitBoxes refit(b, rel);
        for_each_touching_pair_aligned(a, b, RefitB(refit, b), crossing_at_once, rest);
    }
    return capped;
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

}  // namespace mesh_detail

bool mesh_intersects(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b) {
    const Relative rel(pose_a, pose_b, a, b);
    return for_each_touching_pair(
        a, b, rel,
        [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb) {
            return !planes_separate(a, i, ta, b, j, tb, rel) && meet(ta, tb);
        },
        0.0, true);
}

bool mesh_pair_in_range(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b,
                        const Pose& pose_b) {
    // The reach of each mesh about its origin (the far corner of its root box), kept at build.
    double half = 0.5 * max2(a.box_reach(), b.box_reach());
    rescale::reach(half, pose_a.translation, pose_b.translation);
    return std::isfinite(half) && (half == 0.0 || (2.0 * half >= rescale::kSafeLow &&
                                                   2.0 * half <= rescale::kSafeHigh));
}

}  // namespace meshcol
