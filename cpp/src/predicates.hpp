#pragma once
// Exact orientation predicates (private to cpp/src): the sign of a 2x2 or 3x3 determinant of
// point differences, always right for finite double inputs whose products do not underflow.
//
// Each predicate first evaluates the determinant in double precision and returns it when its
// magnitude exceeds a bound on the rounding error (Shewchuk 1997, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates", the bounds ccwerrboundA and
// o3derrboundA). Otherwise it evaluates the determinant exactly with expansion arithmetic
// (Shewchuk 1997, sections 2.3-2.8: Two-Sum, Two-Product, expansion sums and scaling with zero
// elimination) and returns the most significant component, whose sign is the exact sign. The
// filter decides almost every call; the exact path runs for (nearly) degenerate inputs only.
//
// Signs follow the right-hand rule:
//   orient2d(a, b, c) > 0 when a, b, c turn counterclockwise (c left of the line a -> b);
//   orient3d(a, b, c, d) > 0 when d lies on the side that the normal (b - a) x (c - a) points
//   to, i.e. det[b - a, c - a, d - a] > 0 (the opposite sign of Shewchuk's orient3d).
// A zero is an exact zero: the points are collinear (coplanar).
#include <cmath>

#include "meshcol/vec.hpp"

namespace meshcol::predicates {

namespace detail {

/// Half an ulp of 1: the relative rounding error of one operation (round to nearest).
constexpr double epsilon = 0x1p-53;
/// Shewchuk's first-stage error bounds of orient2d and orient3d, relative to the permanent.
constexpr double orient2d_error_bound = (3.0 + 16.0 * epsilon) * epsilon;
constexpr double orient3d_error_bound = (7.0 + 56.0 * epsilon) * epsilon;

/// A nonoverlapping expansion: the exact sum of `size` doubles in increasing magnitude, zeros
/// eliminated (size 1 with a zero term is the number 0).
template <int N>
struct Expansion {
    int size = 0;
    double term[N];
    double sign() const { return term[size - 1]; }  ///< the largest term carries the sign
};

/// x + y == a + b exactly, x = fl(a + b) (Knuth's Two-Sum).
inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double b_virtual = x - a;
    const double a_virtual = x - b_virtual;
    y = (a - a_virtual) + (b - b_virtual);
}

/// x + y == a - b exactly, x = fl(a - b).
inline void two_diff(double a, double b, double& x, double& y) {
    x = a - b;
    const double b_virtual = a - x;
    const double a_virtual = x + b_virtual;
    y = (a - a_virtual) + (b_virtual - b);
}

/// x + y == a * b exactly, x = fl(a * b): the fused multiply-add rounds a * b - x once, and
/// that difference is representable (no reliance on compiler contraction settings).
inline void two_product(double a, double b, double& x, double& y) {
    x = a * b;
    y = std::fma(a, b, -x);
}

/// The exact difference a - b as an expansion of one or two terms.
inline Expansion<2> difference(double a, double b) {
    Expansion<2> out;
    double x, y;
    two_diff(a, b, x, y);
    if (y != 0.0) out.term[out.size++] = y;
    out.term[out.size++] = x;
    return out;
}

/// e + f (Shewchuk's fast expansion sum with zero elimination: merge by magnitude, then one
/// chain of Two-Sums; correct for nonoverlapping inputs under round-to-nearest-even).
template <int M, int N>
Expansion<M + N> sum(const Expansion<M>& e, const Expansion<N>& f) {
    double merged[M + N] = {};
    int i = 0, j = 0, k = 0;
    while (i < e.size && j < f.size)
        merged[k++] = std::fabs(e.term[i]) <= std::fabs(f.term[j]) ? e.term[i++] : f.term[j++];
    while (i < e.size) merged[k++] = e.term[i++];
    while (j < f.size) merged[k++] = f.term[j++];
    Expansion<M + N> out;
    double q = merged[0];
    for (int n = 1; n < k; ++n) {
        double next, tail;
        two_sum(q, merged[n], next, tail);
        if (tail != 0.0) out.term[out.size++] = tail;
        q = next;
    }
    if (q != 0.0 || out.size == 0) out.term[out.size++] = q;
    return out;
}

template <int N>
Expansion<N> negated(Expansion<N> e) {
    for (int i = 0; i < e.size; ++i) e.term[i] = -e.term[i];
    return e;
}

/// e * b (Shewchuk's scale expansion with zero elimination).
template <int N>
Expansion<2 * N> scaled(const Expansion<N>& e, double b) {
    Expansion<2 * N> out;
    double q, tail;
    two_product(e.term[0], b, q, tail);
    if (tail != 0.0) out.term[out.size++] = tail;
    for (int i = 1; i < e.size; ++i) {
        double high, low, partial;
        two_product(e.term[i], b, high, low);
        two_sum(q, low, partial, tail);
        if (tail != 0.0) out.term[out.size++] = tail;
        // |high| >= |partial|: Fast-Two-Sum
        q = high + partial;
        tail = partial - (q - high);
        if (tail != 0.0) out.term[out.size++] = tail;
    }
    if (q != 0.0 || out.size == 0) out.term[out.size++] = q;
    return out;
}

/// e * f, as the sum of e scaled by each term of f.
template <int M, int N>
Expansion<2 * M * N> product(const Expansion<M>& e, const Expansion<N>& f) {
    Expansion<2 * M * N> out;
    const Expansion<2 * M> first = scaled(e, f.term[0]);
    out.size = first.size;
    for (int i = 0; i < first.size; ++i) out.term[i] = first.term[i];
    for (int j = 1; j < f.size; ++j) {
        const Expansion<2 * M * N + 2 * M> total = sum(out, scaled(e, f.term[j]));
        // A sum has at most as many terms as its operands: after j + 1 scalings, 2 M (j + 1).
        out.size = total.size;
        for (int i = 0; i < total.size; ++i) out.term[i] = total.term[i];
    }
    return out;
}

/// Exact orient2d of the differences, Shewchuk's sign convention (and ours).
inline double orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
    const Expansion<2> acx = difference(ax, cx), acy = difference(ay, cy);
    const Expansion<2> bcx = difference(bx, cx), bcy = difference(by, cy);
    return sum(product(acx, bcy), negated(product(acy, bcx))).sign();
}

/// Exact Shewchuk orient3d, det[a - d, b - d, c - d].
inline double orient3d_exact_shewchuk(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const Expansion<2> adx = difference(a.x, d.x), ady = difference(a.y, d.y),
                       adz = difference(a.z, d.z);
    const Expansion<2> bdx = difference(b.x, d.x), bdy = difference(b.y, d.y),
                       bdz = difference(b.z, d.z);
    const Expansion<2> cdx = difference(c.x, d.x), cdy = difference(c.y, d.y),
                       cdz = difference(c.z, d.z);
    const auto bc = sum(product(bdx, cdy), negated(product(cdx, bdy)));
    const auto ca = sum(product(cdx, ady), negated(product(adx, cdy)));
    const auto ab = sum(product(adx, bdy), negated(product(bdx, ady)));
    return sum(sum(product(adz, bc), product(bdz, ca)), product(cdz, ab)).sign();
}

inline bool same(const Vec3& p, const Vec3& q) {
    return p.x == q.x && p.y == q.y && p.z == q.z;
}

}  // namespace detail

/// Twice the signed area of the 2-D triangle (a, b, c), with its exact sign: > 0
/// counterclockwise, < 0 clockwise, 0 collinear.
inline double orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const double left = (ax - cx) * (by - cy);
    const double right = (ay - cy) * (bx - cx);
    const double det = left - right;
    double permanent;
    if (left > 0.0) {
        if (right <= 0.0) return det;
        permanent = left + right;
    } else if (left < 0.0) {
        if (right >= 0.0) return det;
        permanent = -left - right;
    } else {
        return det;  // left is an exact zero (a factor is), so det = -right has the exact sign
    }
    if (det >= detail::orient2d_error_bound * permanent ||
        -det >= detail::orient2d_error_bound * permanent)
        return det;
    if ((ax == bx && ay == by) || (bx == cx && by == cy)) return 0.0;  // repeated point
    return detail::orient2d_exact(ax, ay, bx, by, cx, cy);
}

/// Six times the signed volume of the tetrahedron (a, b, c, d), with its exact sign:
/// > 0 when d is on the side of the plane (a, b, c) that (b - a) x (c - a) points to.
inline double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    // Shewchuk's orient3d is det[a - d, b - d, c - d] = -det[b - a, c - a, d - a].
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
    const double bound = detail::orient3d_error_bound * permanent;
    if (det > bound || -det > bound) return -det;
    // Every product is an exact zero (a zero factor): so is the determinant.
    if (permanent == 0.0) return 0.0;
    // A repeated point (shared mesh vertices) makes the determinant an exact zero.
    if (detail::same(a, b) || detail::same(a, c) || detail::same(b, c)) return 0.0;
    return -detail::orient3d_exact_shewchuk(a, b, c, d);
}

/// -1, 0 or +1.
inline int sign_of(double x) {
    return (x > 0.0) - (x < 0.0);
}

}  // namespace meshcol::predicates
