#include "meshcol/sat.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "meshcol/defaults.hpp"
#include "climb.hpp"

namespace meshcol {

namespace {

const Vec3 kBoxFaces[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const Vec3 kBoxEdges[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

struct Features {
    const Vec3* faces;
    int face_count;
    const Vec3* edges;
    int edge_count;
    int vertices;  // support cost
};

Features features_of(const ShapeView& s) {
    if (s.kind == ShapeKind::BOX) return {kBoxFaces, 6, kBoxEdges, 3, 1};
    return {s.face_normals, s.face_count, s.edge_directions, s.edge_count, s.vertex_count};
}

// A point of the shape's own frame to measure an inner ball from (the middle of its vertices'
// bounds; a box's centre), and the largest |coordinate| of its vertices (the scale of the
// rounding in its support values).
void middle_and_reach(const ShapeView& s, Vec3& middle, double& reach) {
    if (s.kind == ShapeKind::BOX) {
        middle = Vec3{};
        reach = std::fmax(std::fabs(s.params[0]), std::fmax(std::fabs(s.params[1]), std::fabs(s.params[2])));
        return;
    }
    Vec3 lo = s.vertices[0], hi = s.vertices[0];
    for (int i = 1; i < s.vertex_count; ++i) {
        lo = component_min(lo, s.vertices[i]);
        hi = component_max(hi, s.vertices[i]);
    }
    middle = (lo + hi) * 0.5;
    reach = std::fmax(std::fmax(std::fabs(lo.x), std::fabs(hi.x)),
                      std::fmax(std::fmax(std::fabs(lo.y), std::fabs(hi.y)),
                                std::fmax(std::fabs(lo.z), std::fabs(hi.z))));
}

// SAT's work on shapes of these features with `ea` and `eb` edge classes: (candidate axes) x
// (vertices of both), what max_work bounds.
long long work(const Features& fa, long long ea, const Features& fb, long long eb) {
    const long long axes = static_cast<long long>(fa.face_count) + fb.face_count + 2LL * ea * eb;
    return axes * (fa.vertices + fb.vertices);
}

}  // namespace

bool has_sat_features(const ShapeView& s) {
    // A polytope's features are attached by the caller; a point has none and needs none.
    return s.kind == ShapeKind::BOX ||
           (s.kind == ShapeKind::POLYTOPE && (s.has_features || s.vertex_count == 1));
}

namespace {

// The Minkowski difference a - b of two polytopes has as face normals the face normals of a,
// minus those of b, and +-(e_a x e_b) for edge directions e_a, e_b: the smallest support value
// over these axes is the exact depth (the distance from the origin to the boundary), since any
// unit axis n gives an upper bound h(n) >= depth.
//
// Most edge axes cannot be that smallest one, and the loop skips them unmeasured, with the
// same answer to the bit: every axis is still taken in the same order and replaces the best
// only when strictly below it, and an axis is skipped only when it provably is not below the
// best so far. The bound: a holds the ball of radius r_a about a point c_a (r_a the smallest
// gap between c_a and a's face planes, measured in the face tests that come first), b likewise,
// so the overlap along a unit n is at least n . (c_a - c_b) + r_a + r_b. An axis whose bound
// exceeds the best by more than the rounding of either side (`slack`, a millionth of a
// millionth of the coordinates, where rounding is a few parts in 1e16) would not replace it.
//
// Both shapes have SAT data, and each its edge directions attached unless the other has no
// edges (then E_a E_b = 0 and the edge loop is empty: they would not be read).
SatResult sat_attached(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, long long max_work) {
    SatResult res;
    const Features fa = features_of(a), fb = features_of(b);
    if (work(fa, fa.edge_count, fb, fb.edge_count) > max_work) return res;
    res.ran = true;
    // Work in a's frame: b's rotation and origin mapped into it.
    const Mat3 rot = pose_a.rotation.transposed() * pose_b.rotation;
    const Vec3 trans = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_axis{1.0, 0.0, 0.0};
    Vec3 pa, pb_local;  // the supports of the last axis tested, pb_local in b's frame
    // Two polytopes that scan their vertices scan them side by side (the same answers).
    const bool scan_both = scans(a) && scans(b);
    auto test = [&](const Vec3& n) {
        // Overlap along n: h_a(n) + h_b(-n), with b's support taken in b's frame.
        const Vec3 nb = rot.transpose_times(-n);
        if (scan_both) {
            int ia, ib;
            climb::scan_pair(a.vertices, a.vertex_count, n, b.vertices, b.vertex_count, nb, ia, ib);
            pa = a.vertices[ia];
            pb_local = b.vertices[ib];
        } else {
            pa = support_core(a, n).point;
            pb_local = support_core(b, nb).point;
        }
        const Vec3 pb = rot * pb_local + trans;
        const double overlap = dot(n, pa) - dot(n, pb);
        ++res.axes;
        if (overlap < best) {
            best = overlap;
            best_axis = n;
        }
    };
    Vec3 middle_a, middle_b;
    double reach_a, reach_b;
    middle_and_reach(a, middle_a, reach_a);
    middle_and_reach(b, middle_b, reach_b);
    // The inner balls' radii, from below: each face test's support point is a vertex, so its
    // height over the middle is at most the face plane's.
    double radius_a = fa.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    double radius_b = fb.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    for (int i = 0; i < fa.face_count; ++i) {
        test(fa.faces[i]);
        radius_a = std::fmin(radius_a, dot(fa.faces[i], pa - middle_a));
    }
    for (int j = 0; j < fb.face_count; ++j) {
        test(-(rot * fb.faces[j]));
        radius_b = std::fmin(radius_b, dot(fb.faces[j], pb_local - middle_b));
    }
    const double slack = 1e-12 * (reach_a + reach_b + norm(trans) + norm(middle_a) + norm(middle_b));
    // Without a ball on both sides (a flat or degenerate shape, a NaN), every axis is measured.
    const bool bounded = radius_a > slack && radius_b > slack && std::isfinite(slack);
    const Vec3 apart = middle_a - (rot * middle_b + trans);
    const double inner = radius_a + radius_b;
    for (int i = 0; i < fa.edge_count; ++i) {
        for (int j = 0; j < fb.edge_count; ++j) {
            const Vec3 c = cross(fa.edges[i], rot * fb.edges[j]);
            const double len = norm(c);
            // Parallel edges span no face of their own: the face normals cover it.
            if (!(len > defaults::sat_parallel_edge_sine)) continue;
            const Vec3 n = c / len;
            if (!bounded) {
                test(n);
                test(-n);
                continue;
            }
            const double along = dot(n, apart);
            if (!(along + inner > best + slack)) test(n);
            if (!(inner - along > best + slack)) test(-n);
        }
    }
    if (!std::isfinite(best)) {
        res.ran = false;
        return res;
    }
    if (best < 0.0) {
        res.separated = true;
        res.depth = 0.0;
    } else {
        res.depth = best;
    }
    res.normal = pose_a.rotate(best_axis);
    return res;
}

}  // namespace

// A polytope whose edge classes are computed on first use (ShapeView::set) gets them attached
// only when the work bound may let SAT run and its partner may have edges. The work
// (F_a + F_b + 2 E_a E_b)(V_a + V_b) only grows with the class counts: when it is above
// max_work with lower bounds of the counts (0, then the classes of a prefix of the edges, as
// long as the pair needs: EdgeClasses::lower_bound), it is above with the counts themselves,
// and SAT returns unrun, as it would with the classes attached. Against a partner without
// edges a shape's count adds nothing to the work, and its directions are never read.
SatResult sat_penetration(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, long long max_work) {
    if (!has_sat_features(a) || !has_sat_features(b)) return SatResult{};
    if (a.set == nullptr && b.set == nullptr) return sat_attached(a, pose_a, b, pose_b, max_work);
    const Features fa = features_of(a), fb = features_of(b);
    if (work(fa, fa.edge_count, fb, fb.edge_count) > max_work) return SatResult{};
    // The bounds (or counts) earlier pairs found, read without computing: they settle most
    // pairs of shapes met before.
    if (work(fa, a.set != nullptr ? edge_count_lower_bound(a, 0) : fa.edge_count, fb,
             b.set != nullptr ? edge_count_lower_bound(b, 0) : fb.edge_count) > max_work)
        return SatResult{};
    // Classes are at most the true edges: when the work with those counts is within the cap,
    // SAT runs. Else the counts that would put the work above the cap: against a known count,
    // the fewest such; both unknown, the fewest that do so on both sides alike (0: the count
    // adds nothing to the work, the partner having no edges).
    const int upper_a = a.set != nullptr ? edge_count_upper_bound(a) : fa.edge_count;
    const int upper_b = b.set != nullptr ? edge_count_upper_bound(b) : fb.edge_count;
    if (work(fa, upper_a, fb, upper_b) > max_work) {
        long long wanted_a = 0, wanted_b = 0;
        const long long vertices = std::max(fa.vertices + fb.vertices, 1);
        if (a.set != nullptr && b.set != nullptr) {
            const long long spare = max_work / vertices - fa.face_count - fb.face_count;
            auto both = static_cast<long long>(
                std::sqrt(0.5 * static_cast<double>(std::max(spare, 0LL))));
            const long long most = std::max(upper_a, upper_b);  // the work is above the cap there
            while (both < most && work(fa, both, fb, both) <= max_work) ++both;
            wanted_a = wanted_b = both;
        } else if (a.set != nullptr && fb.edge_count > 0) {
            wanted_a = (max_work - work(fa, 0, fb, 0)) / (2LL * fb.edge_count * vertices) + 1;
        } else if (b.set != nullptr && fa.edge_count > 0) {
            wanted_b = (max_work - work(fa, 0, fb, 0)) / (2LL * fa.edge_count * vertices) + 1;
        }
        const auto bound = [](const ShapeView& s, long long wanted, int upper) {
            if (wanted == 0) return 0;
            return edge_count_lower_bound(s, static_cast<int>(std::min<long long>(wanted, upper)));
        };
        const int lower_a = a.set != nullptr ? bound(a, wanted_a, upper_a) : fa.edge_count;
        const int lower_b = b.set != nullptr ? bound(b, wanted_b, upper_b) : fb.edge_count;
        if (work(fa, lower_a, fb, lower_b) > max_work) return SatResult{};
    }
    ShapeView whole_a = a, whole_b = b;
    if (b.set != nullptr || fb.edge_count > 0) attach_edges(whole_a);
    if (features_of(whole_a).edge_count > 0) attach_edges(whole_b);
    return sat_attached(whole_a, pose_a, whole_b, pose_b, max_work);
}

}  // namespace meshcol
