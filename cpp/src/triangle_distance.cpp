// Triangle-triangle distance and intersection.
//
// Distance: for two triangles that do not intersect, the closest pair of points is attained on
// an edge of each (9 segment pairs) or at a vertex of one and the interior of the other (6
// vertex-face pairs); Ericson 2004, 5.1.9. Intersection: sign tests on orientation determinants
// in the manner of Guigue and Devillers 2003 (edge-against-triangle formulation, which also
// covers the coplanar and degenerate cases), every sign exact (predicates.hpp: Shewchuk's
// filtered predicates with an exact expansion fallback), so the yes/no answer is exact for
// every finite input; only the witness point is rounded.
#include "meshcol/triangle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "predicates.hpp"

namespace meshcol {
namespace {

inline double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

using predicates::orient3d_sign;

// Largest component of |n|: the axis dropped when projecting a plane with normal n to 2D.
inline int dominant_axis(const Vec3& n) {
    const double ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    if (ax >= ay && ax >= az) return 0;
    return ay >= az ? 1 : 2;
}

struct Vec2 {
    double x, y;
};

inline Vec2 project(const Vec3& p, int drop) {
    switch (drop) {
        case 0: return {p.y, p.z};
        case 1: return {p.z, p.x};
        default: return {p.x, p.y};
    }
}

// Exact sign of twice the signed area of (a, b, c): > 0 counter-clockwise.
inline int orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
    return predicates::orient2d_sign(a.x, a.y, b.x, b.y, c.x, c.y);
}

// The same area in floating point, for witness points only (never for a decision).
inline double area2d(const Vec2& a, const Vec2& b, const Vec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

inline bool same_sign_or_zero(int a, int b, int c) {
    return (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0);
}

inline bool all_strictly_same_side(const int s[3]) {
    return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

// 2D point in closed triangle (t0, t1, t2) of non-zero area.
inline bool point_in_triangle_2d(const Vec2& p, const Vec2& t0, const Vec2& t1, const Vec2& t2) {
    return same_sign_or_zero(orient2d(t0, t1, p), orient2d(t1, t2, p), orient2d(t2, t0, p));
}

// Whether closed 2D segments [p, q] and [a, b] meet (exact); on success writes the parameter
// along [p, q] of a common point (up to rounding).
bool segments_meet_2d(const Vec2& p, const Vec2& q, const Vec2& a, const Vec2& b, double* s) {
    const int o1 = orient2d(p, q, a), o2 = orient2d(p, q, b);
    if (o1 * o2 > 0) return false;
    const int o3 = orient2d(a, b, p), o4 = orient2d(a, b, q);
    if (o3 * o4 > 0) return false;
    if (o1 == 0 && o2 == 0) {
        // Collinear (or points): compare intervals along the axis of larger spread, where the
        // common line is not perpendicular (coordinate comparisons are exact).
        const double dx = std::max({p.x, q.x, a.x, b.x}) - std::min({p.x, q.x, a.x, b.x});
        const double dy = std::max({p.y, q.y, a.y, b.y}) - std::min({p.y, q.y, a.y, b.y});
        const bool use_x = dx >= dy;
        const double p0 = use_x ? p.x : p.y, p1 = use_x ? q.x : q.y;
        const double a0 = use_x ? a.x : a.y, a1 = use_x ? b.x : b.y;
        const double lo = std::max(std::min(p0, p1), std::min(a0, a1));
        const double hi = std::min(std::max(p0, p1), std::max(a0, a1));
        if (lo > hi) return false;
        *s = p1 != p0 ? clamp01((lo - p0) / (p1 - p0)) : 0.0;
        return true;
    }
    const double a3 = area2d(a, b, p), a4 = area2d(a, b, q);
    *s = a3 != a4 ? clamp01(a3 / (a3 - a4)) : 0.0;
    return true;
}

// A coordinate plane on which triangle t projects to a non-degenerate triangle (exactly), or
// -1 when t is collinear. Tries the dominant axis of its normal first.
int projection_axis(const Vec3 t[3]) {
    const int first = dominant_axis(cross(t[1] - t[0], t[2] - t[0]));
    for (int k = 0; k < 3; ++k) {
        const int drop = (first + k) % 3;
        if (orient2d(project(t[0], drop), project(t[1], drop), project(t[2], drop)) != 0) return drop;
    }
    return -1;
}

// Segment [p, q] against triangle t, all in one plane; `drop` is an axis on which t projects
// to a non-degenerate triangle.
bool segment_triangle_coplanar(const Vec3& p, const Vec3& q, const Vec3 t[3], int drop,
                               Vec3* witness) {
    const Vec2 p2 = project(p, drop), q2 = project(q, drop);
    const Vec2 t0 = project(t[0], drop), t1 = project(t[1], drop), t2 = project(t[2], drop);
    if (point_in_triangle_2d(p2, t0, t1, t2)) {
        if (witness) *witness = p;
        return true;
    }
    const Vec2 tt[3] = {t0, t1, t2};
    for (int i = 0; i < 3; ++i) {
        double s = 0.0;
        if (segments_meet_2d(p2, q2, tt[i], tt[(i + 1) % 3], &s)) {
            if (witness) *witness = p + (q - p) * s;
            return true;
        }
    }
    return false;
}

// Segment [p, q] with exact plane sides sp, sq w.r.t. triangle t (non-degenerate, projecting
// well on `drop`) against triangle t.
bool segment_triangle(const Vec3& p, const Vec3& q, int sp, int sq, const Vec3 t[3], int drop,
                      Vec3* witness) {
    if (sp * sq > 0) return false;
    if (sp == 0 && sq == 0) return segment_triangle_coplanar(p, q, t, drop, witness);
    // The segment meets the plane in one point; it lies in the closed triangle iff the line
    // pq passes through it: the three orientations of pq with the edges agree (Pluecker
    // coordinates, as Guigue and Devillers 2003), exactly.
    const int s0 = orient3d_sign(p, q, t[0], t[1]);
    const int s1 = orient3d_sign(p, q, t[1], t[2]);
    const int s2 = orient3d_sign(p, q, t[2], t[0]);
    if (!same_sign_or_zero(s0, s1, s2)) return false;
    if (witness) {
        const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
        const double dp = dot(p - t[0], n), dq = dot(q - t[0], n);
        const double s = sp == 0 ? 0.0 : (sq == 0 ? 1.0 : (dp != dq ? clamp01(dp / (dp - dq)) : 0.0));
        *witness = p + (q - p) * s;
    }
    return true;
}

// Triangles a (any) and b (non-degenerate, projecting well on `drop`) in one plane.
bool coplanar_triangles_intersect(const Vec3 a[3], const Vec3 b[3], int drop, Vec3* witness) {
    for (int i = 0; i < 3; ++i)
        if (segment_triangle_coplanar(a[i], a[(i + 1) % 3], b, drop, witness)) return true;
    // No edge of a meets b: they intersect only if b lies inside a.
    const Vec2 a0 = project(a[0], drop), a1 = project(a[1], drop), a2 = project(a[2], drop);
    if (orient2d(a0, a1, a2) != 0 && point_in_triangle_2d(project(b[0], drop), a0, a1, a2)) {
        if (witness) *witness = b[0];
        return true;
    }
    return false;
}

// Triangle a against triangle b, b non-degenerate (projecting well on drop_b; drop_a likewise
// for a unless a is degenerate).
bool triangles_intersect_nondegenerate_b(const Vec3 a[3], const Vec3 b[3], int drop_a, int drop_b,
                                         Vec3* witness) {
    const bool a_degenerate = drop_a < 0;
    int da[3];
    for (int i = 0; i < 3; ++i) da[i] = orient3d_sign(b[0], b[1], b[2], a[i]);
    if (all_strictly_same_side(da)) return false;
    if (da[0] == 0 && da[1] == 0 && da[2] == 0)
        return coplanar_triangles_intersect(a, b, drop_b, witness);
    int db[3] = {0, 0, 0};
    if (!a_degenerate) {
        for (int i = 0; i < 3; ++i) db[i] = orient3d_sign(a[0], a[1], a[2], b[i]);
        if (all_strictly_same_side(db)) return false;
    }
    // Non-coplanar triangles meet along a segment whose ends lie on edges: some edge of one
    // triangle meets the other.
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        if (segment_triangle(a[i], a[j], da[i], da[j], b, drop_b, witness)) return true;
    }
    if (a_degenerate) return false;  // a is a segment: its edges were the whole of it
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        if (segment_triangle(b[i], b[j], db[i], db[j], a, drop_a, witness)) return true;
    }
    return false;
}

// Whether two 3D segments (possibly points) meet, exactly: they must be coplanar, and then
// they meet iff their projections on all three coordinate planes meet (at least one of those
// projections is one-to-one on their common plane or line).
bool segments_meet_3d(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, Vec3* witness) {
    if (orient3d_sign(p, q, a, b) != 0) return false;
    double s = 0.0;
    for (int drop = 0; drop < 3; ++drop)
        if (!segments_meet_2d(project(p, drop), project(q, drop), project(a, drop), project(b, drop), &s))
            return false;
    if (witness) *witness = segment_closest_points(p, q, a, b).point_a;
    return true;
}

}  // namespace

SegmentClosestPoints segment_closest_points(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                            const Vec3& q2) {
    // Ericson 2004, 5.1.9 (ClosestPtSegmentSegment), with exact zero tests for degenerate
    // segments: a tiny but non-zero length is still a valid segment.
    const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0.0, t = 0.0;
    if (a == 0.0 && e == 0.0) {
        s = t = 0.0;
    } else if (a == 0.0) {
        t = clamp01(f / e);
    } else {
        const double c = dot(d1, r);
        if (e == 0.0) {
            s = clamp01(-c / a);
        } else {
            const double b = dot(d1, d2);
            const double denom = a * e - b * b;  // >= 0; 0 when parallel
            s = denom > 0.0 ? clamp01((b * f - c * e) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = clamp01((b - c) / a);
            }
        }
    }
    SegmentClosestPoints out;
    out.point_a = p1 + d1 * s;
    out.point_b = p2 + d2 * t;
    out.squared_distance = squared_norm(out.point_b - out.point_a);
    return out;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3 t[3]) {
    const Vec3 a = t[0], b = t[1], c = t[2];
    const Vec3 ab = b - a, ac = c - a;
    const Vec3 n = cross(ab, ac);
    if (!(dot(n, n) > 0.0)) {
        // Degenerate (collinear or repeated corners): the triangle is its edges.
        Vec3 best = a;
        double best2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            const SegmentClosestPoints s = segment_closest_points(p, p, t[i], t[(i + 1) % 3]);
            if (s.squared_distance < best2) {
                best2 = s.squared_distance;
                best = s.point_b;
            }
        }
        return best;
    }
    const Vec3 ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    // Face region: the plane projection, more accurate than a barycentric sum far from the
    // triangle (as GJK's closest_triangle).
    return p - n * (dot(ap, n) / dot(n, n));
}

double triangle_separated_squared_distance(const Vec3 a[3], const Vec3 b[3], Vec3* point_a,
                                           Vec3* point_b) {
    return triangle_separated_squared_distance_below(a, b, std::numeric_limits<double>::infinity(), 0.0, point_a,
                                                     point_b);
}

double triangle_separated_squared_distance_below(const Vec3 a[3], const Vec3 b[3], double limit2, double slack,
                                                 Vec3* point_a, Vec3* point_b) {
    // The 9 edge pairs in the order of segment_closest_points(a[i], a[i + 1], b[j], b[j + 1]),
    // with its very expressions (so its very roundings) and the per-edge terms computed once.
    // A pair is skipped when the distance between the two edges' lines, less `slack`, is above
    // min(limit, best so far): its computed distance (that of two rounded points on the edges,
    // at least the exact edge distance less far under `slack`) would be above it too, so it
    // could neither be the minimum nor tie it. Likewise a vertex-face pair by its plane
    // distance. With limit2 = inf and slack = 0 nothing is skipped.
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_a = a[0], best_b = b[0];
    const Vec3 da[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
    const Vec3 db[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
    const double la[3] = {dot(da[0], da[0]), dot(da[1], da[1]), dot(da[2], da[2])};
    const double lb[3] = {dot(db[0], db[0]), dot(db[1], db[1]), dot(db[2], db[2])};
    const bool filter = limit2 < std::numeric_limits<double>::infinity();
    // The reach below which a pair may still beat min(limit, best), squared, with the slack.
    auto reach2 = [&]() {
        const double r = std::sqrt(best < limit2 ? best : limit2) + slack;
        return r * r * (1.0 + 1e-9);
    };
    double within2 = filter ? reach2() : 0.0;
    for (int i = 0; i < 3; ++i) {
        const Vec3& p1 = a[i];
        const Vec3& d1 = da[i];
        const double sa = la[i];
        for (int j = 0; j < 3; ++j) {
            const Vec3& p2 = b[j];
            const Vec3& d2 = db[j];
            const Vec3 r = p1 - p2;
            if (filter) {
                // The distance between the lines: |r . (d1 x d2)| / |d1 x d2|.
                // Only for edges at least 5.7 degrees from parallel (|d1 x d2|^2 >= 1e-2
                // |d1|^2 |d2|^2): the rounding of d1 x d2, relative to its length, grows as
                // 1 / sin of the angle; here the bound's error is under 40 ulps of |r| (9e-15
                // |r|, |r| at most twice the largest coordinate), under `slack` (at least 3e-14
                // of the largest coordinate, triangle.hpp).
                const Vec3 n = cross(d1, d2);
                const double rn = dot(r, n), nn = dot(n, n);
                if (nn > 1e-2 * sa * lb[j] && rn * rn > within2 * nn) continue;
            }
            const double e = lb[j], f = dot(d2, r);
            double s = 0.0, t = 0.0;
            if (sa == 0.0 && e == 0.0) {
                s = t = 0.0;
            } else if (sa == 0.0) {
                t = clamp01(f / e);
            } else {
                const double c = dot(d1, r);
                if (e == 0.0) {
                    s = clamp01(-c / sa);
                } else {
                    const double bb = dot(d1, d2);
                    const double denom = sa * e - bb * bb;
                    s = denom > 0.0 ? clamp01((bb * f - c * e) / denom) : 0.0;
                    t = (bb * s + f) / e;
                    if (t < 0.0) {
                        t = 0.0;
                        s = clamp01(-c / sa);
                    } else if (t > 1.0) {
                        t = 1.0;
                        s = clamp01((bb - c) / sa);
                    }
                }
            }
            const Vec3 qa = p1 + d1 * s;
            const Vec3 qb = p2 + d2 * t;
            const double d2ist = squared_norm(qb - qa);
            if (d2ist < best) {
                best = d2ist;
                best_a = qa;
                best_b = qb;
                if (filter) within2 = reach2();
            }
        }
    }
    // Vertex-face: only a vertex whose projection falls inside the other triangle can beat the
    // edge pairs (otherwise the closest point of the face is on its boundary, already covered).
    // Degenerate faces (zero normal) have no interior and are skipped.
    for (int side = 0; side < 2; ++side) {
        const Vec3* face = side == 0 ? b : a;
        const Vec3* verts = side == 0 ? a : b;
        const Vec3 e0 = face[1] - face[0], e1 = face[2] - face[1], e2 = face[0] - face[2];
        const Vec3 n = cross(e0, face[2] - face[0]);
        const double nn = dot(n, n);
        if (!(nn > 0.0)) continue;
        for (int i = 0; i < 3; ++i) {
            const Vec3& p = verts[i];
            const double h = dot(p - face[0], n);
            if (filter && h * h > within2 * nn) continue;
            if (dot(cross(e0, p - face[0]), n) < 0.0 || dot(cross(e1, p - face[1]), n) < 0.0 ||
                dot(cross(e2, p - face[2]), n) < 0.0)
                continue;
            const Vec3 q = p - n * (h / nn);
            const double d2 = squared_norm(p - q);
            if (d2 < best) {
                best = d2;
                best_a = side == 0 ? p : q;
                best_b = side == 0 ? q : p;
                if (filter) within2 = reach2();
            }
        }
    }
    if (point_a) *point_a = best_a;
    if (point_b) *point_b = best_b;
    return best;
}

double triangle_feature_squared_distance(const Vec3 a[3], const Vec3 b[3], int feature, Vec3* point_a,
                                         Vec3* point_b) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    if (feature < 9) {
        // The search's edge pair is segment_closest_points's expressions, operation for operation.
        const int i = feature / 3, j = feature % 3;
        const SegmentClosestPoints s = segment_closest_points(a[i], a[i == 2 ? 0 : i + 1], b[j], b[j == 2 ? 0 : j + 1]);
        *point_a = s.point_a;
        *point_b = s.point_b;
        return s.squared_distance;
    }
    // A vertex-face pair: the search's values (its edges, normal, height, inside tests, foot).
    const bool on_b = feature < 12;  // a's corner against b's face, else b's corner against a's
    const Vec3* face = on_b ? b : a;
    const Vec3& p = on_b ? a[feature - 9] : b[feature - 12];
    const Vec3 n = cross(face[1] - face[0], face[2] - face[0]);
    const double nn = dot(n, n);
    if (!(nn > 0.0)) return kInf;
    for (int k = 0; k < 3; ++k)
        if (dot(cross(face[k == 2 ? 0 : k + 1] - face[k], p - face[k]), n) < 0.0) return kInf;
    const Vec3 q = p - n * (dot(p - face[0], n) / nn);
    *point_a = on_b ? p : q;
    *point_b = on_b ? q : p;
    return squared_norm(p - q);
}

bool triangles_intersect(const Vec3 a[3], const Vec3 b[3], Vec3* witness) {
    const int drop_a = projection_axis(a);
    const int drop_b = projection_axis(b);
    if (drop_a < 0 && drop_b < 0) {
        // Two segments (or points): they meet iff some pair of edges meets.
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (segments_meet_3d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], witness)) return true;
        return false;
    }
    if (drop_b < 0) return triangles_intersect_nondegenerate_b(b, a, drop_b, drop_a, witness);
    return triangles_intersect_nondegenerate_b(a, b, drop_a, drop_b, witness);
}

bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3 t[3], double* parameter) {
    const int sp = orient3d_sign(t[0], t[1], t[2], p);
    const int sq = orient3d_sign(t[0], t[1], t[2], q);
    if (sp * sq > 0 || (sp == 0 && sq == 0)) return false;  // one side, or in the plane
    if (projection_axis(t) < 0) return false;              // degenerate triangle
    const int s0 = orient3d_sign(p, q, t[0], t[1]);
    const int s1 = orient3d_sign(p, q, t[1], t[2]);
    const int s2 = orient3d_sign(p, q, t[2], t[0]);
    if (!same_sign_or_zero(s0, s1, s2)) return false;
    if (parameter) {
        const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
        const double dp = dot(p - t[0], n), dq = dot(q - t[0], n);
        *parameter = sp == 0 ? 0.0 : (sq == 0 ? 1.0 : (dp != dq ? clamp01(dp / (dp - dq)) : 0.0));
    }
    return true;
}

TriangleDistanceOutput triangle_distance(const Vec3 a[3], const Vec3 b[3]) {
    TriangleDistanceOutput out;
    Vec3 w;
    if (triangles_intersect(a, b, &w)) {
        out.distance = 0.0;
        out.point_a = out.point_b = w;
        out.intersecting = true;
        return out;
    }
    // Disjoint (exactly): a distance below rounding may still come out as 0.
    const double d2 = triangle_separated_squared_distance(a, b, &out.point_a, &out.point_b);
    out.distance = std::sqrt(d2);
    out.intersecting = false;
    return out;
}

}  // namespace meshcol
