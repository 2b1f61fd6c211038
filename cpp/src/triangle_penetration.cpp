// Penetration depth of two intersecting triangles by the separating axis theorem (triangle.hpp:
// triangle_penetration), the per-pair quantity of mesh_contacts.
//
// Two triangles are convex polytopes, so their minimum translation distance is the distance
// from the origin to the boundary of their Minkowski difference a - b, reached on its nearest
// facet. The facets of a - b are spanned by a face of one and a vertex of the other, or by an
// edge of each: their normals are the triangles' face normals and the edge-edge cross products
// (Gottschalk, Lin and Manocha 1996; Ericson 2004, 4.4 and 5.2.1). On any unit axis u the
// projections overlap by min(max_a - min_b, max_b - min_a), and moving b that far along u (or
// -u) separates the pair; the minimum over the candidates is the depth. A flat difference (a
// coplanar or degenerate pair) has depth 0, which the axes give too (its normal's overlap is
// 0), up to rounding: exact coplanarity is decided first with orient3d so that it is 0 exactly.
#include <cmath>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cstring>

#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"
#include "predicates.hpp"

namespace meshcol {
namespace {

using predicates::collinear;
using predicates::orient3d;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// c made safe to square (vec.hpp: safe_scaled), its largest component found by plain compares
// (std::fmax's NaN handling costs more, and an axis here is never NaN for a valid mesh). In
// range, c itself: projections on it as exact as on c, and most of an axis's cost saved.
// Out of range, the scaling is a call of its own, the in-range test told it is the likely
// way (without the hint GCC's code for the 11 axes grows by about 40 instructions a pair);
// a zero c is left as it is there (no scale to take: its overlap is then 0 / 0, NaN, which
// penetration passes over as no axis, so the axes need no test for zero).
#if defined(__GNUC__)
#define MESHCOL_LIKELY(x) __builtin_expect(static_cast<bool>(x), 1)
#else
#define MESHCOL_LIKELY(x) (x)
#endif
[[gnu::noinline]] Vec3 scaled_out_of_range(const Vec3& c, double m) { return m == 0.0 ? c : safe_scaled(c, m); }

inline Vec3 scaled(const Vec3& c) {
    const double ax = std::fabs(c.x), ay = std::fabs(c.y), az = std::fabs(c.z);
    const double m = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
    if (MESHCOL_LIKELY(m >= 0x1p-500 && m <= 0x1p500)) return c;
    return scaled_out_of_range(c, m);
}
#undef MESHCOL_LIKELY

Vec3 unit(const Vec3& c) {
    const Vec3 s = scaled(c);
    return s / norm(s);
}

// The overlap of the projections of a and b (corners already taken relative to a[0], once for
// all the axes: the same differences, so the same bits, as taking them on each axis) on the axis c
// (non-zero) and the unit direction to move b: +c (b's minimum up to a's maximum) or -c,
// whichever is shorter. The projections are on c itself, divided by its length once at the
// end: where they are exact (small integer corners, a touching pair's zero) the overlap is.
// The unit direction is left to the caller (three divisions), which needs it for the best axis
// only: u / length, negated when `down`.
struct Overlap {
    double depth, length;
    Vec3 u;
    bool down;
};

#if defined(__SSE2__)
// The corners of a and b relative to a[0] side by side, a's in lane 0 and b's in lane 1:
// x[k] = (a[k].x, b[k].x), and so y and z, so that one axis projects a corner of each at once.
struct CornerLanes {
    __m128d x[3], y[3], z[3];
    CornerLanes(const Vec3 a[3], const Vec3 b[3]) {
        for (int k = 0; k < 3; ++k) {
            x[k] = _mm_set_pd(b[k].x, a[k].x);
            y[k] = _mm_set_pd(b[k].y, a[k].y);
            z[k] = _mm_set_pd(b[k].z, a[k].z);
        }
    }
};

// overlap_on below with a's and b's projections in the two lanes: each lane's dot product is
// dot(u, corner)'s operations in its order, and _mm_min_pd(p, lo) is p < lo ? p : lo (max
// alike), the scalar form's compares, so every value is the same. `scale`: false where
// scaled(c) is known to be c (plain_range).
template <bool scale = true>
inline Overlap overlap_on(const Vec3& c, const CornerLanes& t) {
    const Vec3 u = scale ? scaled(c) : c;
    const __m128d ux = _mm_set1_pd(u.x), uy = _mm_set1_pd(u.y), uz = _mm_set1_pd(u.z);
    const auto project = [&](int k) {
        const __m128d xy = _mm_add_pd(_mm_mul_pd(ux, t.x[k]), _mm_mul_pd(uy, t.y[k]));
        return _mm_add_pd(xy, _mm_mul_pd(uz, t.z[k]));
    };
    const __m128d p0 = project(0), p1 = project(1), p2 = project(2);
    const __m128d lo = _mm_min_pd(p2, _mm_min_pd(p1, p0)), hi = _mm_max_pd(p2, _mm_max_pd(p1, p0));
    // up = a_hi - b_lo and down = b_hi - a_lo in one subtraction, lo's lanes swapped.
    const __m128d gaps = _mm_sub_pd(hi, _mm_shuffle_pd(lo, lo, 1));
    const double length = norm(u);
    const double up = _mm_cvtsd_f64(gaps), down = _mm_cvtsd_f64(_mm_unpackhi_pd(gaps, gaps));
    // The scalar form's choice as a select, not a branch (which way is about even on a
    // crossing pair's 11 axes: 5.8% of the listed moved torus query's CPU time,
    // benchmarks/RESULTS.md, session 31): the same quotient and direction.
    const bool flip = !(up <= down);
    return Overlap{(flip ? down : up) / length, length, u, flip};
}
#endif

// Whether every corner coordinate of a and b is 0 or of magnitude in [2^-198, 2^248]. Then each
// is a multiple of 2^-250 (a double of magnitude 2^-198 or more has an ulp of 2^-250 or more),
// and so is an edge's difference as rounded (exact below 2^-197, a multiple of its ulp above),
// at most 2^249; a product of two such is a multiple of 2^-500 at most 2^498, as rounded, and
// a cross product's component (a rounded difference of two) a multiple of 2^-500 at most 2^499.
// So every candidate axis (a face normal or an edge-edge cross product) is zero or has its
// largest component in [2^-500, 2^499]: scaled(c) is c for each, and the axes can skip it.
inline bool plain_range(const Vec3 a[3], const Vec3 b[3]) {
#if defined(__SSE2__)
    const __m128d sign = _mm_set1_pd(-0.0), low = _mm_set1_pd(0x1p-198), high = _mm_set1_pd(0x1p248);
    __m128d ok = _mm_cmpeq_pd(sign, sign);
    const auto take = [&](double x, double y) {
        const __m128d m = _mm_andnot_pd(sign, _mm_set_pd(y, x));
        ok = _mm_and_pd(ok, _mm_or_pd(_mm_cmpeq_pd(m, _mm_setzero_pd()),
                                      _mm_and_pd(_mm_cmpge_pd(m, low), _mm_cmple_pd(m, high))));
    };
    for (int k = 0; k < 3; ++k) {
        take(a[k].x, a[k].y);
        take(a[k].z, b[k].z);
        take(b[k].x, b[k].y);
    }
    return _mm_movemask_pd(ok) == 3;
#else
    bool ok = true;
    for (const Vec3* t : {a, b})
        for (int k = 0; k < 3; ++k)
            for (const double x : {t[k].x, t[k].y, t[k].z}) {
                const double m = std::fabs(x);
                ok = ok && (m == 0.0 || (m >= 0x1p-198 && m <= 0x1p248));
            }
    return ok;
#endif
}

// The scalar form: the projection where SSE2 is absent, and the reference the SSE2 form is
// checked against everywhere (mesh_detail::penetration_axis_forms_agree, a C++ test).
inline Overlap overlap_on(const Vec3& c, const Vec3 a[3], const Vec3 b[3]) {
    const Vec3 u = scaled(c);
    double a_lo = dot(u, a[0]), a_hi = a_lo;
    double b_lo = dot(u, b[0]), b_hi = b_lo;
    for (int k = 1; k < 3; ++k) {
        const double pa = dot(u, a[k]), pb = dot(u, b[k]);
        a_lo = pa < a_lo ? pa : a_lo;
        a_hi = pa > a_hi ? pa : a_hi;
        b_lo = pb < b_lo ? pb : b_lo;
        b_hi = pb > b_hi ? pb : b_hi;
    }
    const double length = norm(u);
    const double up = a_hi - b_lo, down = b_hi - a_lo;
    return up <= down ? Overlap{up / length, length, u, false} : Overlap{down / length, length, u, true};
}

// triangle_penetration without its points, its two kinds of pair each compiled alone (the
// general one skips the exact tests whose answers it knows; the other keeps its code as it was).
template <bool general>
TrianglePenetration penetration(const Vec3 a[3], const Vec3 b[3]) {
    TrianglePenetration out;
    out.normal = out.point_a = out.point_b = Vec3{kNaN, kNaN, kNaN};
    const Vec3 ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
    const Vec3 eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
    const Vec3 na = cross(ea[0], a[2] - a[0]), nb = cross(eb[0], b[2] - b[0]);
    const auto nonzero = [](const Vec3& v) { return v.x != 0.0 || v.y != 0.0 || v.z != 0.0; };
    // A triangle with collinear corners (exactly) has no plane; its rounded normal is no axis.
    // In a general pair neither is collinear (every orientation of its plane would be 0).
    const bool a_plane = nonzero(na) && (general || !collinear(a[0], a[1], a[2]));
    const bool b_plane = nonzero(nb) && (general || !collinear(b[0], b[1], b[2]));
    // Exactly coplanar: the difference is flat, the depth 0 (the orientation signs are exact,
    // as in triangles_intersect, where rounded axes would give a few ulps instead).
    const auto on_plane = [](const Vec3* t, const Vec3* other) {
        return orient3d(t[0], t[1], t[2], other[0]) == 0.0 && orient3d(t[0], t[1], t[2], other[1]) == 0.0 &&
               orient3d(t[0], t[1], t[2], other[2]) == 0.0;
    };
    const bool coplanar = !general && (a_plane ? on_plane(a, b) : (b_plane && on_plane(b, a)));
    if (coplanar) {
        out.depth = 0.0;
        out.axis = a_plane ? 0 : 1;
        out.normal = unit(out.axis == 0 ? na : nb);
    } else {
        double best = std::numeric_limits<double>::infinity();
        Overlap best_axis{};
        const Vec3 ra[3] = {a[0] - a[0], a[1] - a[0], a[2] - a[0]};
        const Vec3 rb[3] = {b[0] - a[0], b[1] - a[0], b[2] - a[0]};
#if defined(__SSE2__)
        const CornerLanes corners(ra, rb);
#endif
        // A zero axis (parallel edges) is none: its overlap is 0 / 0 (scaled leaves it zero),
        // NaN, never below `best`, so it is passed over without a test of its own.
        // The 11 axes in order, compiled twice: scaled where plain_range does not hold, left
        // out (the same axes) where it does.
        const auto all_axes = [&]([[maybe_unused]] auto scale) {
            const auto consider = [&](const Vec3& c, int axis) {
#if defined(__SSE2__)
                const Overlap o = overlap_on<decltype(scale)::value>(c, corners);
#else
                const Overlap o = overlap_on(c, ra, rb);
#endif
                if (o.depth < best) {
                    best = o.depth;
                    best_axis = o;
                    out.axis = axis;
                }
            };
            if (a_plane) consider(na, 0);
            if (b_plane) consider(nb, 1);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) consider(cross(ea[i], eb[j]), 2 + 3 * i + j);
        };
        if (plain_range(a, b)) {
            all_axes(std::false_type{});
        } else {
            all_axes(std::true_type{});
        }
        if (out.axis >= 0) out.normal = best_axis.down ? -best_axis.u / best_axis.length : best_axis.u / best_axis.length;
        // No axis: both are points or segments on one line, a flat difference.
        out.depth = out.axis < 0 ? 0.0 : (best > 0.0 ? best : 0.0);
    }
    return out;
}

}  // namespace

namespace mesh_detail {

bool penetration_axis_forms_agree(const Vec3 a[3], const Vec3 b[3], bool* down) {
    // The corners relative to a[0] and the 11 candidate axes, as penetration forms them.
    const Vec3 ra[3] = {a[0] - a[0], a[1] - a[0], a[2] - a[0]};
    const Vec3 rb[3] = {b[0] - a[0], b[1] - a[0], b[2] - a[0]};
    const Vec3 ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
    const Vec3 eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
    Vec3 axes[11] = {cross(ea[0], a[2] - a[0]), cross(eb[0], b[2] - b[0])};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) axes[2 + 3 * i + j] = cross(ea[i], eb[j]);
#if defined(__SSE2__)
    const CornerLanes lanes(ra, rb);
#endif
    const auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof(double)) == 0; };
    [[maybe_unused]] const bool in_range = plain_range(a, b);
    bool agree = true;
    *down = false;
    for (int k = 0; k < 11; ++k) {
        const Vec3& c = axes[k];
        if (c.x == 0.0 && c.y == 0.0 && c.z == 0.0) continue;  // penetration skips it
        const Overlap plain = overlap_on(c, ra, rb);
#if defined(__SSE2__)
        const Overlap fast = overlap_on(c, lanes);
        // Where plain_range holds, the form that leaves scaled out, too.
        const Overlap unscaled = in_range ? overlap_on<false>(c, lanes) : fast;
#else
        const Overlap fast = plain, unscaled = plain;
#endif
        if (k == 0) *down = plain.down;
        for (const Overlap* o : {&fast, &unscaled})
            agree = agree && o->down == plain.down && same(o->depth, plain.depth) && same(o->length, plain.length) &&
                    same(o->u.x, plain.u.x) && same(o->u.y, plain.u.y) && same(o->u.z, plain.u.z);
    }
    return agree;
}

}  // namespace mesh_detail

TrianglePenetration triangle_penetration(const Vec3 a[3], const Vec3 b[3], bool points, bool general) {
    TrianglePenetration out = general ? penetration<true>(a, b) : penetration<false>(a, b);
    if (points) triangle_penetration_points(a, b, out);
    return out;
}

namespace {

// The feature pair (`triangle_feature_squared_distance`'s numbering) that the axis of `p`, a
// `triangle_penetration(a, b, false)` of the same triangles, names: on a's normal b's corner
// least along `p.normal` (the first of equal ones) against a's face, on b's normal a's corner
// greatest along it against b's face, on an edge pair's cross product those two edges; -1
// when `p.axis` is -1. `triangle_penetration_points` starts from it.
int triangle_penetration_feature(const Vec3 a[3], const Vec3 b[3], const TrianglePenetration& p) {
    if (p.axis < 0) return -1;
    if (p.axis >= 2) return p.axis - 2;
    // b's corner deepest along a's normal (its least projection: b moves along the normal) on
    // a's face, or a's deepest along b's normal (its greatest) on b's face.
    const Vec3* t = p.axis == 0 ? b : a;
    const double sense = p.axis == 0 ? 1.0 : -1.0;  // least along the normal, or greatest
    int deepest = 0;
    double extreme = sense * dot(p.normal, t[0]);
    for (int k = 1; k < 3; ++k) {
        const double s = sense * dot(p.normal, t[k]);
        if (s < extreme) {
            extreme = s;
            deepest = k;
        }
    }
    return (p.axis == 0 ? 12 : 9) + deepest;
}

// The largest coordinate magnitude of a's and c's corners. Plain compares: a NaN corner is
// passed over (and its NaN distances then fail any limit made of this).
double largest_magnitude(const Vec3 a[3], const Vec3 c[3]) {
    double reach = 0.0;
    for (int k = 0; k < 3; ++k)
        for (const Vec3* v : {&a[k], &c[k]})
            for (const double x : {std::fabs(v->x), std::fabs(v->y), std::fabs(v->z)})
                reach = x > reach ? x : reach;
    return reach;
}

// The closest points of the feature pair of a and c that p's axis names (b's feature is c's,
// c being b or b moved), when they meet within 1e-12 of `reach`: true, with them in *point_a
// and *on_c.
bool axis_feature_points(const Vec3 a[3], const Vec3 b[3], const Vec3 c[3], const TrianglePenetration& p,
                         double reach, Vec3* point_a, Vec3* on_c) {
    const int feature = triangle_penetration_feature(a, b, p);
    if (feature < 0) return false;
    const double tight = 1e-12 * reach;
    return triangle_feature_squared_distance(a, c, feature, point_a, on_c) <= tight * tight;
}

}  // namespace

void triangle_penetration_points(const Vec3 a[3], const Vec3 b[3], TrianglePenetration& p) {
    if (p.depth == 0.0) {
        // Touching: the axis's features, when they meet (a few hundred instructions), else the
        // exact test's shared point (about 1,500).
        if (axis_feature_points(a, b, b, p, largest_magnitude(a, b), &p.point_a, &p.point_b)) return;
        Vec3 shared;
        if (!triangles_intersect(a, b, &shared)) {
            // Not intersecting after all (a caller's misuse): the closest points.
            triangle_separated_squared_distance(a, b, &p.point_a, &p.point_b);
            return;
        }
        p.point_a = p.point_b = shared;
        return;
    }
    const Vec3 shift = p.normal * p.depth;
    const Vec3 moved[3] = {b[0] + shift, b[1] + shift, b[2] + shift};
    Vec3 on_moved;
    const double reach = largest_magnitude(a, moved);
    // a and b moved by the depth touch, up to the rounding of the depth and the move (a few
    // ulps of the coordinates): first the feature pair the axis names; then the search limited
    // to 1e-10 of the largest coordinate, which gives the same value and points
    // (triangle.hpp: triangle_separated_squared_distance_below, its slack above the 3e-14 it
    // needs) and skips the feature pairs that cannot be the closest; should the pair be
    // farther than that after all, the full search.
    if (!axis_feature_points(a, b, moved, p, reach, &p.point_a, &on_moved)) {
        const double limit = 1e-10 * reach;
        const double found2 = triangle_separated_squared_distance_below(a, moved, limit * limit, 4e-14 * reach,
                                                                        &p.point_a, &on_moved);
        if (!(found2 <= limit * limit)) triangle_separated_squared_distance(a, moved, &p.point_a, &on_moved);
    }
    p.point_b = on_moved - shift;
}

}  // namespace meshcol
