#pragma once
// Robust geometric predicates: orientation signs that are exact for every finite double input.
//
// Each predicate first evaluates its determinant in double precision and accepts the sign when
// the value exceeds Shewchuk's forward error bound (Shewchuk 1997, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates", bounds ccwerrboundA and
// o3derrboundA); otherwise it evaluates the determinant exactly with floating-point expansions
// (two-sum, fma-based two-product, grow and scale expansion with zero elimination; same paper,
// sections 2.5-2.7) and returns a value of the exact sign. Inputs whose coordinates are all
// tiny (denormal) are scaled by a power of two before the exact evaluation (scaling is exact),
// so the error terms do not underflow. Only the sign of a returned value is meaningful.
//
// Private to the core (header-only); the one copy, shared by the triangle tests of
// triangle_distance.cpp, the mesh queries (mesh_*.cpp) and triangle_intersect.cpp (inspect's
// crossings).
//
// Sign conventions: orient2d(a, b, c) > 0 when a, b, c turn counterclockwise; orient3d is
// Shewchuk's, det[a - d, b - d, c - d], > 0 when d lies on the side that (b - a) x (c - a)
// points away from (callers wanting the right-hand sign negate it).

#include <algorithm>
#include <cmath>
#include <vector>

#include "hull_orientation.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {
namespace predicates {

/// The calling thread's count of evaluations the floating-point filter could not decide: a
/// measure of work for callers that budget it (the self-intersection pass), since such an
/// evaluation costs 5 to 30 times a filtered one. Read the difference around the work.
struct WorkCounters {
    long long slow = 0;   ///< evaluations past the filter (the adaptive stages or exact)
    long long exact = 0;  ///< of which evaluated exactly (the costliest)
};
inline thread_local WorkCounters work_counters;

namespace detail {

constexpr double kEpsilon = 1.1102230246251565e-16;  // 2^-53, half an ulp of 1
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

// The exact evaluation with std::vector expansions (one allocation per operation): the one the
// core used alone before the stack-held one below, kept for coordinates in the underflow
// range (clear_of_underflow false). There neither is exact for every input (a product's
// rounding error under 2^-1074 is lost, even by fma), and this one's verdicts are those the
// tests have long pinned (tests/collision/test_self_intersection.py's rational oracle).
// A nonoverlapping expansion, components in increasing magnitude, zeros removed.
using Expansion = std::vector<double>;

inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bv = x - a;
    const double av = x - bv;
    y = (a - av) + (b - bv);
}

inline Expansion difference(double a, double b) {
    const double x = a - b;
    const double bv = a - x;
    const double av = x + bv;
    const double y = (a - av) + (bv - b);
    Expansion e;
    if (y != 0.0) e.push_back(y);
    if (x != 0.0) e.push_back(x);
    return e;
}

// e + b (Shewchuk's GROW-EXPANSION with zero elimination).
inline Expansion grow(const Expansion& e, double b) {
    Expansion h;
    h.reserve(e.size() + 1);
    double q = b;
    for (double component : e) {
        double sum, error;
        two_sum(q, component, sum, error);
        if (error != 0.0) h.push_back(error);
        q = sum;
    }
    if (q != 0.0 || h.empty()) h.push_back(q);
    return h;
}

inline Expansion add(const Expansion& e, const Expansion& f) {
    Expansion h = e;
    for (double component : f) h = grow(h, component);
    return h;
}

inline Expansion negate(Expansion e) {
    for (double& component : e) component = -component;
    return e;
}

// e * b (Shewchuk's SCALE-EXPANSION with zero elimination; fma gives the exact product error).
inline Expansion scale(const Expansion& e, double b) {
    Expansion h;
    if (e.empty() || b == 0.0) return h;
    h.reserve(2 * e.size());
    double q = e[0] * b;
    double low = std::fma(e[0], b, -q);
    if (low != 0.0) h.push_back(low);
    for (size_t i = 1; i < e.size(); ++i) {
        const double product = e[i] * b;
        const double product_low = std::fma(e[i], b, -product);
        double sum, error;
        two_sum(q, product_low, sum, error);
        if (error != 0.0) h.push_back(error);
        two_sum(product, sum, q, error);
        if (error != 0.0) h.push_back(error);
    }
    if (q != 0.0) h.push_back(q);
    return h;
}

inline Expansion multiply(const Expansion& e, const Expansion& f) {
    Expansion h;
    for (double component : f) h = add(h, scale(e, component));
    return h;
}

// The sign of an expansion is the sign of its largest (last) component.
inline double sign_of(const Expansion& e) {
    for (auto it = e.rbegin(); it != e.rend(); ++it)
        if (*it != 0.0) return *it > 0.0 ? 1.0 : -1.0;
    return 0.0;
}

// The power of two (its exponent) that brings the largest magnitude `m` near 1 when it is tiny,
// so that products of differences stay clear of the denormal range; 0 otherwise. Applied by
// std::ldexp to each coordinate, which is exact: a factor 2^k itself overflows for the
// denormal m (k > 1023), where multiplying by it would turn every coordinate into inf or NaN.
inline int rescale_exponent(double m) {
    if (!(m > 0.0) || m >= 0x1p-400) return 0;
    int exponent = 0;
    std::frexp(m, &exponent);
    return -exponent;
}

inline double orient2d_expansions(double ax, double ay, double bx, double by, double cx, double cy) {
    const double m = std::max({std::fabs(ax), std::fabs(ay), std::fabs(bx), std::fabs(by),
                               std::fabs(cx), std::fabs(cy)});
    if (const int k = rescale_exponent(m); k != 0)
        for (double* x : {&ax, &ay, &bx, &by, &cx, &cy}) *x = std::ldexp(*x, k);
    const Expansion acx = difference(ax, cx), acy = difference(ay, cy);
    const Expansion bcx = difference(bx, cx), bcy = difference(by, cy);
    return sign_of(add(multiply(acx, bcy), negate(multiply(acy, bcx))));
}

inline double orient3d_expansions(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    double m = 0.0;
    for (const Vec3* p : {&a, &b, &c, &d})
        m = std::max({m, std::fabs(p->x), std::fabs(p->y), std::fabs(p->z)});
    if (const int k = rescale_exponent(m); k != 0)
        for (Vec3* p : {&a, &b, &c, &d}) *p = {std::ldexp(p->x, k), std::ldexp(p->y, k), std::ldexp(p->z, k)};
    const Expansion adx = difference(a.x, d.x), ady = difference(a.y, d.y), adz = difference(a.z, d.z);
    const Expansion bdx = difference(b.x, d.x), bdy = difference(b.y, d.y), bdz = difference(b.z, d.z);
    const Expansion cdx = difference(c.x, d.x), cdy = difference(c.y, d.y), cdz = difference(c.z, d.z);
    const Expansion m_bc = add(multiply(bdx, cdy), negate(multiply(cdx, bdy)));
    const Expansion m_ca = add(multiply(cdx, ady), negate(multiply(adx, cdy)));
    const Expansion m_ab = add(multiply(adx, bdy), negate(multiply(bdx, ady)));
    return sign_of(add(add(multiply(adz, m_bc), multiply(bdz, m_ca)), multiply(cdz, m_ab)));
}

// The exact evaluations of coordinates clear of underflow use the stack-held expansion
// arithmetic of hull_orientation.hpp (Shewchuk's Fast-Expansion-Sum and Scale-Expansion with
// zero elimination): no allocation, which a pile of exactly degenerate faces (inspect's worst
// case) calls millions of times.
inline double orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
    namespace h = hull_detail;
    const double m = std::max({std::fabs(ax), std::fabs(ay), std::fabs(bx), std::fabs(by),
                               std::fabs(cx), std::fabs(cy)});
    if (const int k = rescale_exponent(m); k != 0)
        for (double* x : {&ax, &ay, &bx, &by, &cx, &cy}) *x = std::ldexp(*x, k);
    // Two slots per difference, plus the spare one the merge reads past the end.
    double acx[3], acy[3], bcx[3], bcy[3], left[16], right[16], det[32];
    const int nacx = h::difference(ax, cx, acx), nacy = h::difference(ay, cy, acy);
    const int nbcx = h::difference(bx, cx, bcx), nbcy = h::difference(by, cy, bcy);
    const int nl = h::expansion_product(acx, nacx, bcy, nbcy, left);
    const int nr = h::expansion_product(acy, nacy, bcx, nbcx, right);
    for (int l = 0; l < nr; ++l) right[l] = -right[l];
    const int n = h::expansion_sum(left, nl, right, nr, det);
    for (int l = n - 1; l >= 0; --l)
        if (det[l] != 0.0) return det[l] > 0.0 ? 1.0 : -1.0;
    return 0.0;
}

inline double orient3d_exact(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    double m = 0.0;
    for (const Vec3* p : {&a, &b, &c, &d})
        m = std::max({m, std::fabs(p->x), std::fabs(p->y), std::fabs(p->z)});
    if (const int k = rescale_exponent(m); k != 0)
        for (Vec3* p : {&a, &b, &c, &d}) *p = {std::ldexp(p->x, k), std::ldexp(p->y, k), std::ldexp(p->z, k)};
    // Shewchuk's orient3d is det[a - d, b - d, c - d], the opposite sign of the right-hand
    // (b - a) x (c - a) . (d - a) that hull_orientation.hpp evaluates.
    return -static_cast<double>(hull_detail::orientation_exact(a, b, c, d));
}

// Whether every coordinate is 0 or at least 2^-200 in magnitude: then every difference, tail,
// product and partial product of the adaptive stages is a multiple of 2^-756 or more (at least
// 2^-252 per difference), so no error-free step underflows and the stages are exact where
// Shewchuk's analysis assumes it (it ignores underflow). Tinier coordinates go to the
// allocating evaluation above.
inline bool clear_of_underflow(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    for (const Vec3* p : {&a, &b, &c, &d})
        for (int k = 0; k < 3; ++k) {
            const double x = std::fabs((*p)[k]);
            if (x != 0.0 && x < 0x1p-200) return false;
        }
    return true;
}

// Shewchuk's orient3dadapt before its last stage: the determinant of the rounded differences
// evaluated exactly (stage B), then corrected by the differences' rounding errors to first
// order (stage C), each accepted past its error bound (o3derrboundB, o3derrboundC and
// resulterrbound of the paper); the exact evaluation only when neither decides. Near-coplanar
// points that are not exactly coplanar (the faces of a fan in general position) stop at C.
// `permanent` is the filter's; the coordinates are clear of underflow (clear_of_underflow).
inline double orient3d_adaptive(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                double permanent) {
    namespace h = hull_detail;
    const double adx = a.x - d.x, ady = a.y - d.y, adz = a.z - d.z;
    const double bdx = b.x - d.x, bdy = b.y - d.y, bdz = b.z - d.z;
    const double cdx = c.x - d.x, cdy = c.y - d.y, cdz = c.z - d.z;
    // minor = p * q - r * s of doubles, exactly (at most 4 components, one spare slot).
    const auto minor = [](double p, double q, double r, double s, double* out) {
        double x[3], y[3];
        h::two_product(p, q, x[1], x[0]);
        h::two_product(r, s, y[1], y[0]);
        y[0] = -y[0], y[1] = -y[1];
        return h::expansion_sum(x, 2, y, 2, out);
    };
    double bc[5], ca[5], ab[5], adet[9], bdet[9], cdet[9], abdet[17], fin[25];
    const int nbc = minor(bdx, cdy, cdx, bdy, bc);
    const int nca = minor(cdx, ady, adx, cdy, ca);
    const int nab = minor(adx, bdy, bdx, ady, ab);
    const int na = h::scale_expansion(bc, nbc, adz, adet);
    const int nb = h::scale_expansion(ca, nca, bdz, bdet);
    const int nc = h::scale_expansion(ab, nab, cdz, cdet);
    const int nabd = h::expansion_sum(adet, na, bdet, nb, abdet);
    const int nfin = h::expansion_sum(abdet, nabd, cdet, nc, fin);
    double det = 0.0;
    for (int l = 0; l < nfin; ++l) det += fin[l];
    const double bound_b = (3.0 + 28.0 * kEpsilon) * kEpsilon * permanent;
    if (det >= bound_b || -det >= bound_b) return det;
    const auto tail = [](double p, double q, double rounded) {
        const double bv = p - rounded;
        const double av = rounded + bv;
        return (p - av) + (bv - q);
    };
    const double adxt = tail(a.x, d.x, adx), adyt = tail(a.y, d.y, ady), adzt = tail(a.z, d.z, adz);
    const double bdxt = tail(b.x, d.x, bdx), bdyt = tail(b.y, d.y, bdy), bdzt = tail(b.z, d.z, bdz);
    const double cdxt = tail(c.x, d.x, cdx), cdyt = tail(c.y, d.y, cdy), cdzt = tail(c.z, d.z, cdz);
    if (adxt == 0.0 && adyt == 0.0 && adzt == 0.0 && bdxt == 0.0 && bdyt == 0.0 && bdzt == 0.0 &&
        cdxt == 0.0 && cdyt == 0.0 && cdzt == 0.0)
        return det;  // the differences were exact: stage B's value is the determinant
    const double bound_c = (26.0 + 288.0 * kEpsilon) * kEpsilon * kEpsilon * permanent +
                           (3.0 + 8.0 * kEpsilon) * kEpsilon * std::fabs(det);
    det += (adz * ((bdx * cdyt + cdy * bdxt) - (bdy * cdxt + cdx * bdyt)) + adzt * (bdx * cdy - bdy * cdx)) +
           (bdz * ((cdx * adyt + ady * cdxt) - (cdy * adxt + adx * cdyt)) + bdzt * (cdx * ady - cdy * adx)) +
           (cdz * ((adx * bdyt + bdy * adxt) - (ady * bdxt + bdx * adyt)) + cdzt * (adx * bdy - ady * bdx));
    if (det >= bound_c || -det >= bound_c) return det;
    ++work_counters.exact;
    return orient3d_exact(a, b, c, d);
}

}  // namespace detail

/// Twice the signed area of the 2D triangle (a, b, c): > 0 when counter-clockwise, 0 exactly
/// when collinear. Exact sign for finite inputs.
inline double orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const double left = (ax - cx) * (by - cy);
    const double right = (ay - cy) * (bx - cx);
    const double det = left - right;
    const double permanent = std::fabs(left) + std::fabs(right);
    const double bound = detail::kOrient2dBound * permanent;
    // The bound assumes no underflow: a permanent in the denormal range goes exact.
    if ((det > bound || -det > bound) && permanent > 0x1p-900) return det;
    if (!std::isfinite(det)) return det;  // non-finite input: no meaningful sign
    // Three points on one axis-parallel line are collinear: a column of the determinant is
    // exactly zero (the difference of two doubles is zero only when they are equal). Common in
    // axis-aligned contacts, where the filter cannot decide; it saves the exact evaluation.
    if ((ax == cx && bx == cx) || (ay == cy && by == cy)) return 0.0;
    // A repeated point (two faces' shared vertex) makes a row of the determinant zero.
    if ((ax == cx && ay == cy) || (bx == cx && by == cy) || (ax == bx && ay == by)) return 0.0;
    ++work_counters.slow;
    ++work_counters.exact;
    const auto clear = [](double x) { return x == 0.0 || std::fabs(x) >= 0x1p-200; };
    if (clear(ax) && clear(ay) && clear(bx) && clear(by) && clear(cx) && clear(cy))
        return detail::orient2d_exact(ax, ay, bx, by, cx, cy);
    return detail::orient2d_expansions(ax, ay, bx, by, cx, cy);
}

/// dot(a - d, cross(b - d, c - d)): six times the signed volume of the tetrahedron (a, b, c, d);
/// > 0 when d lies below the plane through a, b, c seen counter-clockwise from above (Shewchuk's
/// convention), 0 exactly when the four points are coplanar. Exact sign for finite inputs.
inline double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const double adx = a.x - d.x, ady = a.y - d.y, adz = a.z - d.z;
    const double bdx = b.x - d.x, bdy = b.y - d.y, bdz = b.z - d.z;
    const double cdx = c.x - d.x, cdy = c.y - d.y, cdz = c.z - d.z;
    const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    const double cdxady = cdx * ady, adxcdy = adx * cdy;
    const double adxbdy = adx * bdy, bdxady = bdx * ady;
    const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
    const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                             (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                             (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
    const double bound = detail::kOrient3dBound * permanent;
    // The bound assumes no underflow: a permanent in the denormal range goes exact.
    if ((det > bound || -det > bound) && permanent > 0x1p-900) return det;
    if (!std::isfinite(det)) return det;
    // Four points on one axis-parallel plane are coplanar (a column is exactly zero), as in
    // orient2d: the flush faces of axis-aligned contacts, decided without the exact evaluation.
    if ((adx == 0.0 && bdx == 0.0 && cdx == 0.0) || (ady == 0.0 && bdy == 0.0 && cdy == 0.0) ||
        (adz == 0.0 && bdz == 0.0 && cdz == 0.0))
        return 0.0;
    // A repeated point (faces that share a vertex) makes the determinant exactly zero too.
    if ((adx == 0.0 && ady == 0.0 && adz == 0.0) || (bdx == 0.0 && bdy == 0.0 && bdz == 0.0) ||
        (cdx == 0.0 && cdy == 0.0 && cdz == 0.0) || (a.x == b.x && a.y == b.y && a.z == b.z) ||
        (a.x == c.x && a.y == c.y && a.z == c.z) || (b.x == c.x && b.y == c.y && b.z == c.z))
        return 0.0;
    ++work_counters.slow;
    if (detail::clear_of_underflow(a, b, c, d)) return detail::orient3d_adaptive(a, b, c, d, permanent);
    ++work_counters.exact;
    return detail::orient3d_expansions(a, b, c, d);
}

/// -1, 0 or +1.
inline int sign_of(double x) {
    return (x > 0.0) - (x < 0.0);
}

/// -1, 0 or +1: the exact sign of `orient3d`.
inline int orient3d_sign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const double v = orient3d(a, b, c, d);
    return (v > 0.0) - (v < 0.0);
}

/// -1, 0 or +1: the exact sign of `orient2d`.
inline int orient2d_sign(double ax, double ay, double bx, double by, double cx, double cy) {
    const double v = orient2d(ax, ay, bx, by, cx, cy);
    return (v > 0.0) - (v < 0.0);
}

/// Whether three points are collinear (or repeated), exactly: every coordinate-plane
/// projection of the triangle has zero area.
inline bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
    return orient2d(a.x, a.y, b.x, b.y, c.x, c.y) == 0.0 &&
           orient2d(a.y, a.z, b.y, b.z, c.y, c.z) == 0.0 &&
           orient2d(a.z, a.x, b.z, b.x, c.z, c.x) == 0.0;
}

}  // namespace predicates
}  // namespace meshcol
