#pragma once
// The exact orientation test of Quickhull (quickhull.cpp) and the error-free transformations
// of its compensated cross product. Private to the core.
//
// Exact orientation (Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast
// robust geometric predicates"): a floating-point filter with his static error bound, and an
// exact evaluation with expansion arithmetic when the filter cannot decide. Quickhull's
// topology (which faces a new point sees) is decided by this exact sign, so the polytope it
// builds is always convex and the horizon always one simple loop, whatever the degeneracy.

#include <cmath>

#include "meshcol/vec.hpp"

namespace meshcol::hull_detail {

// Expansions live in fixed arrays on the stack (the largest here has 192 components; one
// spare slot because the merge below reads one past the end, as Shewchuk's code does).
inline constexpr int expansion_capacity = 256;

inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bv = x - a;
    const double av = x - bv;
    y = (a - av) + (b - bv);
}

inline void fast_two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    y = b - (x - a);
}

inline void two_diff(double a, double b, double& x, double& y) {
    x = a - b;
    const double bv = a - x;
    const double av = x + bv;
    y = (a - av) + (bv - b);
}

// a = hi + lo with each half fitting 26 bits (Dekker 1971), for an exact product without FMA.
inline void split(double a, double& hi, double& lo) {
    const double c = 134217729.0 * a;  // 2^27 + 1
    hi = c - (c - a);
    lo = a - hi;
}

inline void two_product(double a, double b, double& x, double& y) {
    x = a * b;
#if defined(__FMA__)
    y = std::fma(a, b, -x);
#else
    // Without hardware FMA (the default x86-64 target) std::fma is a library call: Dekker's
    // product is exact too and inlines, unless its partial products underflow (a product
    // under 2^-900): there the correctly rounded fma is the closer one (exact whenever the
    // error is a double at all).
    if (std::fabs(x) < 0x1p-900) {
        y = std::fma(a, b, -x);
        return;
    }
    double ah, al, bh, bl;
    split(a, ah, al);
    split(b, bh, bl);
    y = al * bl - (((x - ah * bh) - al * bh) - ah * bl);
#endif
}

// h = e + f (Fast-Expansion-Sum with zero elimination); e and f non-overlapping, increasing
// magnitude, at least one component each. Returns the length of h.
inline int expansion_sum(const double* e, int en, const double* f, int fn, double* h) {
    double q, qn, hh;
    double enow = e[0], fnow = f[0];
    int ei = 0, fi = 0, hi = 0;
    if ((fnow > enow) == (fnow > -enow)) {
        q = enow;
        enow = e[++ei];
    } else {
        q = fnow;
        fnow = f[++fi];
    }
    if (ei < en && fi < fn) {
        if ((fnow > enow) == (fnow > -enow)) {
            fast_two_sum(enow, q, qn, hh);
            enow = e[++ei];
        } else {
            fast_two_sum(fnow, q, qn, hh);
            fnow = f[++fi];
        }
        q = qn;
        if (hh != 0.0) h[hi++] = hh;
        while (ei < en && fi < fn) {
            if ((fnow > enow) == (fnow > -enow)) {
                two_sum(q, enow, qn, hh);
                enow = e[++ei];
            } else {
                two_sum(q, fnow, qn, hh);
                fnow = f[++fi];
            }
            q = qn;
            if (hh != 0.0) h[hi++] = hh;
        }
    }
    while (ei < en) {
        two_sum(q, enow, qn, hh);
        enow = e[++ei];
        q = qn;
        if (hh != 0.0) h[hi++] = hh;
    }
    while (fi < fn) {
        two_sum(q, fnow, qn, hh);
        fnow = f[++fi];
        q = qn;
        if (hh != 0.0) h[hi++] = hh;
    }
    if (q != 0.0 || hi == 0) h[hi++] = q;
    return hi;
}

// h = e * b (Scale-Expansion with zero elimination).
inline int scale_expansion(const double* e, int en, double b, double* h) {
    double q, t;
    int hi = 0;
    two_product(e[0], b, q, t);
    if (t != 0.0) h[hi++] = t;
    for (int i = 1; i < en; ++i) {
        double p1, p0, s, u;
        two_product(e[i], b, p1, p0);
        two_sum(q, p0, s, u);
        if (u != 0.0) h[hi++] = u;
        fast_two_sum(p1, s, q, u);
        if (u != 0.0) h[hi++] = u;
    }
    if (q != 0.0 || hi == 0) h[hi++] = q;
    return hi;
}

// h = e * f, f short (the sum of e scaled by each component of f).
inline int expansion_product(const double* e, int en, const double* f, int fn, double* h) {
    double part[expansion_capacity], acc[expansion_capacity];
    int n = scale_expansion(e, en, f[0], h);
    for (int i = 1; i < fn; ++i) {
        const int pn = scale_expansion(e, en, f[i], part);
        std::copy(h, h + n, acc);
        n = expansion_sum(acc, n, part, pn, h);
    }
    return n;
}

inline int difference(double a, double b, double* h) {
    double x, y;
    two_diff(a, b, x, y);
    int n = 0;
    if (y != 0.0) h[n++] = y;
    if (x != 0.0 || n == 0) h[n++] = x;
    return n;
}

inline int orientation_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
    double u[3][3], v[3][3], w[3][3];
    int un[3], vn[3], wn[3];
    for (int k = 0; k < 3; ++k) {
        un[k] = difference(b[k], a[k], u[k]);
        vn[k] = difference(c[k], a[k], v[k]);
        wn[k] = difference(p[k], a[k], w[k]);
    }
    // det = sum over k of u_k * (v x w)_k, each minor v_i w_j - v_j w_i exact.
    double term[3][expansion_capacity];
    int tn[3];
    const int pairs[3][2] = {{1, 2}, {2, 0}, {0, 1}};
    for (int k = 0; k < 3; ++k) {
        const int i = pairs[k][0], j = pairs[k][1];
        double x[16], y[16], minor[expansion_capacity];
        const int xn = expansion_product(v[i], vn[i], w[j], wn[j], x);
        int yn = expansion_product(v[j], vn[j], w[i], wn[i], y);
        for (int l = 0; l < yn; ++l) y[l] = -y[l];
        const int mn = expansion_sum(x, xn, y, yn, minor);
        tn[k] = expansion_product(minor, mn, u[k], un[k], term[k]);
    }
    double s01[expansion_capacity], det[expansion_capacity];
    const int n01 = expansion_sum(term[0], tn[0], term[1], tn[1], s01);
    const int n = expansion_sum(s01, n01, term[2], tn[2], det);
    for (int l = n - 1; l >= 0; --l)
        if (det[l] != 0.0) return det[l] > 0.0 ? 1 : -1;
    return 0;
}

// Sign of (b - a) x (c - a) . (p - a): +1 when p is on the side that the counter-clockwise
// triangle abc faces, 0 when coplanar (exactly).
inline int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = p.x - a.x, wy = p.y - a.y, wz = p.z - a.z;
    const double m1 = vy * wz, m2 = vz * wy, m3 = vz * wx, m4 = vx * wz, m5 = vx * wy,
                 m6 = vy * wx;
    const double det = ux * (m1 - m2) + uy * (m3 - m4) + uz * (m5 - m6);
    const double permanent = std::fabs(ux) * (std::fabs(m1) + std::fabs(m2)) +
                             std::fabs(uy) * (std::fabs(m3) + std::fabs(m4)) +
                             std::fabs(uz) * (std::fabs(m5) + std::fabs(m6));
    // Shewchuk's o3derrboundA, (7 + 56 eps) eps: the same triple product of rounded
    // differences as his orient3d.
    const double bound = 7.7715611723761027e-16 * permanent;
    if (det > bound) return 1;
    if (-det > bound) return -1;
    return orientation_exact(a, b, c, p);
}

// The side of x from the plane of the counter-clockwise triangle a b c whose unit normal,
// offset and filter face_plane gave (hull_detail.hpp): +1 outside, -1 inside, 0 on it,
// exactly: the plane distance decides beyond the filter, the orientation otherwise.
inline int plane_side(const Vec3& normal, double offset, double filter, const Vec3& a,
                      const Vec3& b, const Vec3& c, const Vec3& x) {
    const double d = dot(normal, x) - offset;
    if (d > filter) return 1;
    if (d < -filter) return -1;
    return orientation(a, b, c, x);
}

}  // namespace meshcol::hull_detail
