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

#include "meshcol/vec.hpp"

namespace meshcol {
namespace predicates {

namespace detail {

constexpr double kEpsilon = 1.1102230246251565e-16;  // 2^-53, half an ulp of 1
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

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

inline double orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
    const double m = std::max({std::fabs(ax), std::fabs(ay), std::fabs(bx), std::fabs(by),
                               std::fabs(cx), std::fabs(cy)});
    if (const int k = rescale_exponent(m); k != 0)
        for (double* x : {&ax, &ay, &bx, &by, &cx, &cy}) *x = std::ldexp(*x, k);
    const Expansion acx = difference(ax, cx), acy = difference(ay, cy);
    const Expansion bcx = difference(bx, cx), bcy = difference(by, cy);
    return sign_of(add(multiply(acx, bcy), negate(multiply(acy, bcx))));
}

inline double orient3d_exact(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
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
    return detail::orient2d_exact(ax, ay, bx, by, cx, cy);
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
    return detail::orient3d_exact(a, b, c, d);
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
