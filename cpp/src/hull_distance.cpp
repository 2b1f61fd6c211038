// Point-to-polytope distances over the facets a point lies in front of (hull.hpp:
// `distances_to_facets`), the inner loop of the budgeted hull (meshcol/collision/hull.py).
// Compiled without fused multiply-add (CMakeLists.txt): every operation rounds as numpy's do.
#include <cmath>
#include <cstdint>
#include <limits>

#include "meshcol/hull.hpp"

namespace meshcol {

namespace {

// numpy's einsum("ij,ij->i") of three terms: (x + z) + y.
inline double einsum_dot(const Vec3& u, const Vec3& v) {
    return (u.x * v.x + u.z * v.z) + u.y * v.y;
}

// numpy's nan_to_num: NaN to 0, infinities to the largest finite doubles.
inline double nan_to_num(double t) {
    if (std::isnan(t)) return 0.0;
    if (std::isinf(t))
        return t > 0 ? std::numeric_limits<double>::max() : -std::numeric_limits<double>::max();
    return t;
}

inline double squared_distance(const Vec3& q, const Vec3& p) {
    const Vec3 d = q - p;
    return (d.x * d.x + d.y * d.y) + d.z * d.z;  // numpy's sum over a row of three
}

// Ericson (2004) 5.1.5 as closest_points_on_triangles writes it: every region's point from
// the same expressions, the first of Ericson's early returns winning; a triangle whose face
// region gives a non-finite point falls back to its nearest corner (the first on ties).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = einsum_dot(ab, ap), d2 = einsum_dot(ac, ap);
    const Vec3 bp = p - b;
    const double d3 = einsum_dot(ab, bp), d4 = einsum_dot(ac, bp);
    const Vec3 cp = p - c;
    const double d5 = einsum_dot(ab, cp), d6 = einsum_dot(ac, cp);
    const double va = d3 * d6 - d5 * d4;
    const double vb = d5 * d2 - d1 * d6;
    const double vc = d1 * d4 - d3 * d2;
    Vec3 result;
    if (d1 <= 0 && d2 <= 0) {
        result = a;
    } else if (d3 >= 0 && d4 <= d3) {
        result = b;
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        result = a + nan_to_num(d1 / (d1 - d3)) * ab;
    } else if (d6 >= 0 && d5 <= d6) {
        result = c;
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        result = a + nan_to_num(d2 / (d2 - d6)) * ac;
    } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        result = b + nan_to_num((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    } else {
        const double denom = va + vb + vc;
        const double v = vb / denom, w = vc / denom;
        result = (a + v * ab) + w * ac;
    }
    if (is_finite(result)) return result;
    const Vec3* corners[3] = {&a, &b, &c};
    int nearest = 0;
    double best = squared_distance(a, p);
    for (int k = 1; k < 3; ++k) {
        const double d = squared_distance(*corners[k], p);
        if (d < best) {  // argmin: the first of equal ones (NaN never wins)
            best = d;
            nearest = k;
        }
    }
    return *corners[nearest];
}

}  // namespace

void distances_to_facets(const Vec3* points, long long count, const Vec3* facets,
                         long long facet_count, const std::uint8_t* in_front, double* distances,
                         Vec3* closest) {
    for (long long i = 0; i < count; ++i) {
        const Vec3& p = points[i];
        const std::uint8_t* row = in_front + i * facet_count;
        bool found = false;
        double best = 0.0;
        Vec3 best_point = p;
        for (long long f = 0; f < facet_count; ++f) {
            if (!row[f]) continue;
            const Vec3* t = facets + 3 * f;
            const Vec3 q = closest_on_triangle(p, t[0], t[1], t[2]);
            const double d2 = squared_distance(q, p);
            // the smallest, the first of equal ones (numpy's lexsort of (d2, point): NaN last)
            if (!found || d2 < best || (std::isnan(best) && !std::isnan(d2))) {
                found = true;
                best = d2;
                best_point = q;
            }
        }
        distances[i] = found ? std::sqrt(best) : 0.0;
        closest[i] = best_point;
    }
}

}  // namespace meshcol
