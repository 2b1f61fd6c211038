#pragma once
// The exact orientation signs as the core first computed them (expansions in std::vector, one
// allocation per operation, no adaptive stage): the reference that test_predicates.cpp holds
// predicates.hpp's adaptive and stack-held evaluation to, sign for sign.
#include <algorithm>
#include <cmath>
#include <vector>

#include "meshcol/vec.hpp"

namespace meshcol::predicates_reference {

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

}  // namespace meshcol::predicates_reference
