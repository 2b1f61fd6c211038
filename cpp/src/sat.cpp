#include "meshcol/sat.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/defaults.hpp"

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

// The index of the lowest set bit of a non-zero word.
int lowest_bit(std::uint64_t word) {
    int i = 0;
    while ((word & 1) == 0) {
        word >>= 1;
        ++i;
    }
    return i;
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

bool gauss_arcs(const Vec3* vertices, int vertex_count, const Vec3* face_normals, int face_count,
                const std::int32_t* pairs, const std::int32_t* class_of, size_t count,
                std::vector<GaussArc>& out) {
    // The faces through each vertex as the bits of a word (an edge's faces are then those of
    // both its ends). Beyond 64 faces, no arcs: SAT's work bound lets such a shape meet only
    // shapes of few edges, where the plain loop is cheap.
    if (vertex_count <= 0 || face_count <= 0 || face_count > 64) return false;
    double reach = 0.0;
    for (int v = 0; v < vertex_count; ++v)
        reach = std::max({reach, std::fabs(vertices[v].x), std::fabs(vertices[v].y),
                          std::fabs(vertices[v].z)});
    const double tolerance = defaults::sat_arc_plane_tolerance * reach;
    if (!(tolerance > 0.0) || !std::isfinite(tolerance)) return false;
    std::vector<std::uint64_t> faces_of(static_cast<size_t>(vertex_count), 0);
    std::vector<double> heights(static_cast<size_t>(vertex_count));
    for (int f = 0; f < face_count; ++f) {
        double top = -std::numeric_limits<double>::infinity();
        for (int v = 0; v < vertex_count; ++v) {
            heights[v] = dot(face_normals[f], vertices[v]);
            top = std::max(top, heights[v]);
        }
        const std::uint64_t bit = std::uint64_t{1} << f;
        for (int v = 0; v < vertex_count; ++v)
            if (heights[v] >= top - tolerance) faces_of[v] |= bit;
    }
    const size_t kept = out.size();
    out.reserve(kept + count);
    for (size_t e = 0; e < count; ++e) {
        std::uint64_t both = faces_of[pairs[2 * e]] & faces_of[pairs[2 * e + 1]];
        // Exactly two bits: clearing the lowest leaves one.
        const std::uint64_t rest = both & (both - 1);
        if (both == 0 || rest == 0 || (rest & (rest - 1)) != 0 || class_of[e] < 0) {
            out.resize(kept);
            return false;
        }
        GaussArc arc;
        arc.normal_a = face_normals[lowest_bit(both)];
        arc.normal_b = face_normals[lowest_bit(rest)];
        arc.plane = cross(arc.normal_b, arc.normal_a);
        arc.direction_class = class_of[e];
        out.push_back(arc);
    }
    return true;
}

namespace {

// `crossing_classes`' working arrays, kept by each thread.
struct CrossingScratch {
    std::vector<double> columns;  // b's arcs' ends, then the first test's values
    std::vector<Vec3> circles;    // b's arcs' circles
    std::vector<int> near;        // the arcs the first test keeps
    std::vector<int> found;       // the answer
};

// The axes of class pairs whose edges' arcs cross on the Gauss maps of a and of -b (in a's
// frame), or nearly: the axes that may be face normals of the Minkowski difference a - b
// (Gregorius, "The Separating Axis Test between convex polyhedra", GDC 2013). Each as
// 2 (i * (b's class count) + j) for the axis `Overlaps::edge_axis` of classes i and j, plus 1
// for its opposite: ascending (the plain loop's order), each once. Arcs AB and CD cross when
// C and D lie on opposite sides of AB's great circle, A and B on opposite sides of CD's, and
// the crossing is on the near side (CBA and BDC of one sign). A sign test decides only beyond
// `sat_arc_crossing_margin`.
const std::vector<int>& crossing_classes(const ShapeView& a, const ShapeView& b, const Mat3& rot) {
    // -b's arcs in a's frame: C and D the normals negated, the circle's normal kept (D x C =
    // R (v x u)); the ends as columns, so that the first test takes two arcs at a time (an
    // odd count's last twice: it is listed once more, and found once).
    const int count = b.arc_count, padded = count + (count & 1);
    // One lookup of the thread's scratch (in a shared library each names a call).
    thread_local CrossingScratch scratch;
    CrossingScratch& s = scratch;
    s.columns.resize(8 * static_cast<size_t>(padded));
    s.circles.resize(static_cast<size_t>(count));
    s.near.resize(static_cast<size_t>(padded));
    Vec3* const circles = s.circles.data();
    int* const near = s.near.data();
    std::vector<int>& found = s.found;
    double* const cx = s.columns.data();
    double* const cy = cx + padded;
    double* const cz = cy + padded;
    double* const dx = cz + padded;
    double* const dy = dx + padded;
    double* const dz = dy + padded;
    double* const cba = dz + padded;
    double* const dba = cba + padded;
    for (int k = 0; k < padded; ++k) {
        const GaussArc& arc = b.arcs[k < count ? k : count - 1];
        const Vec3 c = -(rot * arc.normal_a), d = -(rot * arc.normal_b);
        cx[k] = c.x, cy[k] = c.y, cz[k] = c.z;
        dx[k] = d.x, dy[k] = d.y, dz[k] = d.z;
        if (k < count) circles[k] = rot * arc.plane;
    }
    const double m = defaults::sat_arc_crossing_margin;
    const auto same_side = [m](double x, double y) {
        return (x > m && y > m) || (x < -m && y < -m);
    };
    found.clear();
    for (int i = 0; i < a.arc_count; ++i) {
        const GaussArc& ab = a.arcs[i];
        const Vec3 q = ab.plane;
        // The arcs with ends on both sides of AB's circle (or near it), listed without a
        // branch an arc.
        int listed = 0;
#if defined(__SSE2__)
        const __m128d qx = _mm_set1_pd(q.x), qy = _mm_set1_pd(q.y), qz = _mm_set1_pd(q.z);
        const __m128d above = _mm_set1_pd(m), below = _mm_set1_pd(-m);
        for (int k = 0; k < padded; k += 2) {
            const __m128d c = _mm_add_pd(
                _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(cx + k), qx), _mm_mul_pd(_mm_loadu_pd(cy + k), qy)),
                _mm_mul_pd(_mm_loadu_pd(cz + k), qz));
            const __m128d d = _mm_add_pd(
                _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(dx + k), qx), _mm_mul_pd(_mm_loadu_pd(dy + k), qy)),
                _mm_mul_pd(_mm_loadu_pd(dz + k), qz));
            _mm_storeu_pd(cba + k, c);
            _mm_storeu_pd(dba + k, d);
            const __m128d same = _mm_or_pd(
                _mm_and_pd(_mm_cmpgt_pd(c, above), _mm_cmpgt_pd(d, above)),
                _mm_and_pd(_mm_cmplt_pd(c, below), _mm_cmplt_pd(d, below)));
            const int mask = _mm_movemask_pd(same);
            near[listed] = k;
            listed += !(mask & 1);
            near[listed] = k + 1;
            listed += !(mask & 2);
        }
#else
        for (int k = 0; k < padded; ++k) {
            cba[k] = cx[k] * q.x + cy[k] * q.y + cz[k] * q.z;
            dba[k] = dx[k] * q.x + dy[k] * q.y + dz[k] * q.z;
            near[listed] = k;
            listed += !same_side(cba[k], dba[k]);
        }
#endif
        const int row = ab.direction_class * b.edge_count;
        const Vec3 middle = ab.normal_a + ab.normal_b;  // on AB's side of its circle's axis
        for (int l = 0; l < listed; ++l) {
            const int k = near[l] < count ? near[l] : count - 1;
            const double adc = dot(ab.normal_a, circles[k]), bdc = dot(ab.normal_b, circles[k]);
            if (same_side(adc, bdc) || same_side(cba[k], -bdc)) continue;
            // The crossing is the axis of the two classes (`Overlaps::edge_axis`) or its
            // opposite: the one on AB's side, whose angle to the arc's ends is below pi. Both
            // when that is near a tie.
            const int pair = row + b.arcs[k].direction_class;
            const Vec3 axis = cross(a.edge_directions[ab.direction_class],
                                    rot * b.edge_directions[b.arcs[k].direction_class]);
            const double side = dot(axis, middle), scale = m * norm(axis) * norm(middle);
            if (!(side < -scale)) found.push_back(2 * pair);
            if (!(side > scale)) found.push_back(2 * pair + 1);
        }
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
}

// `climb::scan_support` to the bit (the first vertex of the largest dot), with selects in
// place of branches: SAT's axes point anywhere, so which vertex leads is a coin toss that a
// branch predictor loses.
inline int first_max(const Vec3* v, int n, const Vec3& d) {
    int best = 0;
    double top = dot(v[0], d);
    for (int i = 1; i < n; ++i) {
        const double x = dot(v[i], d);
        const bool higher = x > top;
        top = higher ? x : top;
        best = higher ? i : best;
    }
    return best;
}

// The overlap of a and b along axes of a's frame, h_a(n) + h_b(-n), and the smallest so far:
// an axis replaces it only when strictly below, so the answer is the first smallest axis.
struct Overlaps {
    const ShapeView& a;
    const ShapeView& b;
    Mat3 rot;    // b's rotation in a's frame
    Vec3 trans;  // b's origin in a's frame
    bool scan_both;
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_axis{1.0, 0.0, 0.0};
    Vec3 pa, pb_local;  // the supports of the last axis tested, pb_local in b's frame
    int axes = 0;

    Overlaps(const ShapeView& a_, const Pose& pose_a, const ShapeView& b_, const Pose& pose_b)
        : a(a_),
          b(b_),
          rot(pose_a.rotation.transposed() * pose_b.rotation),
          trans(pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation)),
          // Two polytopes that scan their vertices scan them with selects (`first_max`, the
          // same supports as their support functions').
          scan_both(scans(a_) && scans(b_)) {}

    void test(const Vec3& n) {
        // b's support taken in b's frame.
        const Vec3 nb = rot.transpose_times(-n);
        if (scan_both) {
            pa = a.vertices[first_max(a.vertices, a.vertex_count, n)];
            pb_local = b.vertices[first_max(b.vertices, b.vertex_count, nb)];
        } else {
            pa = support_core(a, n).point;
            pb_local = support_core(b, nb).point;
        }
        const Vec3 pb = rot * pb_local + trans;
        const double overlap = dot(n, pa) - dot(n, pb);
        ++axes;
        if (overlap < best) {
            best = overlap;
            best_axis = n;
        }
    }

    // The axis of edge directions e_a and e_b (b's frame), or false for parallel ones: they
    // span no face of their own, the face normals cover it.
    bool edge_axis(const Vec3& edge_a, const Vec3& edge_b, Vec3& n) const {
        const Vec3 c = cross(edge_a, rot * edge_b);
        const double len = norm(c);
        if (!(len > defaults::sat_parallel_edge_sine)) return false;
        n = c / len;
        return true;
    }

    SatResult result(const Pose& pose_a) const {
        SatResult res;
        res.axes = axes;
        if (!std::isfinite(best)) return res;
        res.ran = true;
        if (best < 0.0) {
            res.separated = true;
            res.depth = 0.0;
        } else {
            res.depth = best;
        }
        res.normal = pose_a.rotate(best_axis);
        return res;
    }
};

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
SatResult sat_every_edge_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                              const Pose& pose_b) {
    const Features fa = features_of(a), fb = features_of(b);
    Overlaps o(a, pose_a, b, pose_b);
    Vec3 middle_a, middle_b;
    double reach_a, reach_b;
    middle_and_reach(a, middle_a, reach_a);
    middle_and_reach(b, middle_b, reach_b);
    // The inner balls' radii, from below: each face test's support point is a vertex, so its
    // height over the middle is at most the face plane's.
    double radius_a = fa.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    double radius_b = fb.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    for (int i = 0; i < fa.face_count; ++i) {
        o.test(fa.faces[i]);
        radius_a = std::fmin(radius_a, dot(fa.faces[i], o.pa - middle_a));
    }
    for (int j = 0; j < fb.face_count; ++j) {
        o.test(-(o.rot * fb.faces[j]));
        radius_b = std::fmin(radius_b, dot(fb.faces[j], o.pb_local - middle_b));
    }
    const double slack =
        1e-12 * (reach_a + reach_b + norm(o.trans) + norm(middle_a) + norm(middle_b));
    // Without a ball on both sides (a flat or degenerate shape, a NaN), every axis is measured.
    const bool bounded = radius_a > slack && radius_b > slack && std::isfinite(slack);
    const Vec3 apart = middle_a - (o.rot * middle_b + o.trans);
    const double inner = radius_a + radius_b;
    for (int i = 0; i < fa.edge_count; ++i) {
        for (int j = 0; j < fb.edge_count; ++j) {
            Vec3 n;
            if (!o.edge_axis(fa.edges[i], fb.edges[j], n)) continue;
            if (!bounded) {
                o.test(n);
                o.test(-n);
                continue;
            }
            const double along = dot(n, apart);
            if (!(along + inner > o.best + slack)) o.test(n);
            if (!(inner - along > o.best + slack)) o.test(-n);
        }
    }
    return o.result(pose_a);
}

// The largest |coordinate| of a polytope's vertices.
double reach_of(const ShapeView& s) {
    double reach = 0.0;
    for (int i = 0; i < s.vertex_count; ++i)
        reach = std::fmax(reach, std::fmax(std::fabs(s.vertices[i].x),
                                           std::fmax(std::fabs(s.vertices[i].y),
                                                     std::fabs(s.vertices[i].z))));
    return reach;
}

// Two polytopes with arcs on their Gauss maps: the face normals of both, then the axes of the
// edge pairs whose arcs cross (Gregorius 2013), in the plain loop's order. Two polytopes
// overlap exactly when every face normal of their Minkowski difference shows an overlap, and
// the smallest is the depth: the axes of edge pairs whose arcs do not cross are above it, or
// tie with it within rounding when the shapes touch at a vertex or an edge of the difference
// (the depth is then 0 by rounding, and any of those axes a normal). Clearly apart, the plain
// loop's answer may be any axis: then false, and the plain loop answers.
bool sat_crossing_edge_pairs(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                             const Pose& pose_b, SatResult& res) {
    Overlaps o(a, pose_a, b, pose_b);
    for (int i = 0; i < a.face_count; ++i) o.test(a.face_normals[i]);
    for (int j = 0; j < b.face_count; ++j) o.test(-(o.rot * b.face_normals[j]));
    for (const int signed_pair : crossing_classes(a, b, o.rot)) {
        const int k = signed_pair / 2;
        Vec3 n;
        if (!o.edge_axis(a.edge_directions[k / b.edge_count],
                         b.edge_directions[k % b.edge_count], n))
            continue;
        o.test(signed_pair % 2 == 0 ? n : -n);
    }
    const double slack = 1e-12 * (reach_of(a) + reach_of(b) + norm(o.trans));
    if (!(o.best >= -slack) || !std::isfinite(o.best)) return false;
    res = o.result(pose_a);
    return true;
}

// Both shapes have SAT data, and each its edge directions attached unless the other has no
// edges (then E_a E_b = 0 and the edge loop is empty: they would not be read).
SatResult sat_attached(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, long long max_work) {
    const Features fa = features_of(a), fb = features_of(b);
    if (work(fa, fa.edge_count, fb, fb.edge_count) > max_work) return SatResult{};
    // The arcs pay where edge pairs are many and the test of an arc pair costs a fraction of
    // measuring an axis: 8-point hulls, not boxes and wedges (few classes of parallel edges).
    SatResult res;
    if (a.arcs != nullptr && b.arcs != nullptr && a.edge_count > 0 && b.edge_count > 0 &&
        2LL * a.edge_count * b.edge_count * (a.vertex_count + b.vertex_count) >=
            defaults::sat_arc_pair_cost * a.arc_count * b.arc_count &&
        sat_crossing_edge_pairs(a, pose_a, b, pose_b, res))
        return res;
    return sat_every_edge_pair(a, pose_a, b, pose_b);
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
