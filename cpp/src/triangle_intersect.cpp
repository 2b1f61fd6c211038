// Exact crossing test of two triangles, the self-intersection verdict of `meshcol inspect`.
//
// Two triangles cross when their relative interiors (the open triangles) share a point. Every
// decision is the sign of an orientation determinant of input points (predicates.hpp: filtered,
// exact fallback), so the verdict is exact: no tolerance, no snapping.
//
// Non-coplanar pairs follow the interval formulation of Moller 1997 and Guigue and Devillers
// 2003. An open triangle meets the other's plane only if its vertices lie strictly on both
// sides; it then meets it in an open segment of the line L where the planes cross, and the
// open triangles share a point exactly when their two segments on L overlap in more than a
// point. Endpoints are never computed: an endpoint is where an edge (u, w) of one triangle (u
// on the positive side of the other's plane or on it, w strictly negative) meets that plane,
// and for endpoints p of (u, w) on the plane of A and r of (x, y) on the plane of B,
// sign(orient3d(u, w, x, y)) is the sign of the order of p and r along L (the tetrahedron's
// volume is invariant as u, x slide along their lines to p, r, and equals (t(r) - t(p)) times
// det[w - u, n_A x n_B, y - x], which is negative for such edges).
//
// Coplanar pairs overlap with positive area unless a line through an edge of one weakly
// separates them (the separating axis theorem for convex polygons, with touching counted as
// separated), tested with orient2d in a coordinate plane onto which they project one-to-one.
//
// Shared vertices and edges need no special case: they lie on the boundaries of both
// triangles, and the predicates give exact zeros for repeated points, so adjacent faces cross
// only if they meet beyond what they share.
#include <cstdint>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/triangle.hpp"
#include "predicates.hpp"

namespace meshcol {
namespace {

using predicates::orient2d;
using predicates::sign_of;

/// The right-hand orientation, det[b - a, c - a, d - a]: > 0 when d lies on the side that
/// (b - a) x (c - a) points to (the opposite of Shewchuk's orient3d in predicates.hpp).
double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return -predicates::orient3d(a, b, c, d);
}

struct Point2 {
    double x, y;
};

// p with coordinate `axis` dropped (a projection onto a coordinate plane).
inline Point2 drop_axis(const Vec3& p, int axis) {
    switch (axis) {
        case 0:
            return {p.y, p.z};
        case 1:
            return {p.z, p.x};
        default:
            return {p.x, p.y};
    }
}

inline int orientation(const Point2& a, const Point2& b, const Point2& c) {
    return sign_of(orient2d(a.x, a.y, b.x, b.y, c.x, c.y));
}

// Whether a line through an edge of t (orientation `turn` = +1 or -1) has every vertex of
// `other` on its closed outer side. Edge i joins t[i] and t[i + 1]; edge `skip` is not tried.
bool edge_separates(const Point2 t[3], int turn, const Point2 other[3], int skip = -1) {
    for (int i = 0; i < 3; ++i) {
        if (i == skip) continue;
        const Point2& p = t[i];
        const Point2& q = t[(i + 1) % 3];
        bool all_outside = true;
        for (int j = 0; j < 3 && all_outside; ++j)
            all_outside = orientation(p, q, other[j]) * turn <= 0;
        if (all_outside) return true;
    }
    return false;
}

// Coplanar triangles: positive-area overlap of their interiors. Edges `skip_a` of a and
// `skip_b` of b are not tried as separating lines (see face_pair_crosses: they cannot be).
bool coplanar_cross(const Vec3 a[3], const Vec3 b[3], int skip_a = -1, int skip_b = -1) {
    // Any coordinate plane onto which a projects with non-zero area maps the common plane
    // one-to-one, so orientations there are the 3-D ones up to one common sign.
    for (int axis = 0; axis < 3; ++axis) {
        const Point2 pa[3] = {drop_axis(a[0], axis), drop_axis(a[1], axis), drop_axis(a[2], axis)};
        const int turn_a = orientation(pa[0], pa[1], pa[2]);
        if (turn_a == 0) continue;
        const Point2 pb[3] = {drop_axis(b[0], axis), drop_axis(b[1], axis), drop_axis(b[2], axis)};
        const int turn_b = orientation(pb[0], pb[1], pb[2]);
        if (turn_b == 0) return false;  // b is a segment or a point: no interior
        return !edge_separates(pa, turn_a, pb, skip_a) && !edge_separates(pb, turn_b, pa, skip_b);
    }
    return false;  // a is a segment or a point
}

// An edge (u, w) of a triangle with u on the positive side of the other triangle's plane or on
// it, w strictly on the negative side: its meeting point with that plane ends the segment.
struct Endpoint {
    Vec3 u, w;
};

// The two endpoints of the segment where triangle t (vertex sides s, with both signs present)
// meets the other's plane: at each edge with sides of opposite signs, and at each vertex on
// the plane (paired with a vertex on the negative side).
int segment_ends(const Vec3 t[3], const int s[3], Endpoint out[2]) {
    int negative = 0;
    for (int i = 0; i < 3; ++i)
        if (s[i] < 0) negative = i;
    int n = 0;
    for (int i = 0; i < 3 && n < 2; ++i) {
        const int j = (i + 1) % 3;
        if (s[i] == 0)
            out[n++] = {t[i], t[negative]};
        else if (s[i] * s[j] < 0)
            out[n++] = s[i] > 0 ? Endpoint{t[i], t[j]} : Endpoint{t[j], t[i]};
    }
    return n;
}

inline bool straddles(const int s[3]) {
    const bool positive = s[0] > 0 || s[1] > 0 || s[2] > 0;
    const bool negative = s[0] < 0 || s[1] < 0 || s[2] < 0;
    return positive && negative;
}

// triangles_cross once the sides of b's vertices w.r.t. a's plane are known, not all zero.
// Bit i of `on_b`: a[i] is one of b's corners, so its side is 0 without a determinant.
bool cross_given_sides(const Vec3 a[3], const Vec3 b[3], const int side_b[3], int on_b = 0) {
    if (!straddles(side_b)) return false;
    int side_a[3];
    for (int i = 0; i < 3; ++i) side_a[i] = on_b >> i & 1 ? 0 : sign_of(orient3d(b[0], b[1], b[2], a[i]));
    if (!straddles(side_a)) return false;  // including a degenerate b (all zero)
    Endpoint ends_b[2], ends_a[2];
    if (segment_ends(b, side_b, ends_b) != 2 || segment_ends(a, side_a, ends_a) != 2)
        return false;  // unreachable when both straddle
    // Order of each end of b's segment against each end of a's: the open segments overlap
    // unless one lies entirely at or before the other along L.
    bool b_not_after = true, b_not_before = true;
    for (const Endpoint& p : ends_b)
        for (const Endpoint& r : ends_a) {
            const int order = sign_of(orient3d(p.u, p.w, r.u, r.w));
            b_not_after = b_not_after && order <= 0;
            b_not_before = b_not_before && order >= 0;
        }
    return !b_not_after && !b_not_before;
}

inline bool distinct(const std::int64_t* f) {
    return f[0] != f[1] && f[1] != f[2] && f[0] != f[2];
}

}  // namespace

bool triangles_cross(const Vec3 a[3], const Vec3 b[3]) {
    int side_b[3];  // sides of b's vertices w.r.t. a's plane
    for (int j = 0; j < 3; ++j) side_b[j] = sign_of(orient3d(a[0], a[1], a[2], b[j]));
    if (side_b[0] == 0 && side_b[1] == 0 && side_b[2] == 0)
        return coplanar_cross(a, b);  // also a degenerate a: every point is "on its plane"
    return cross_given_sides(a, b, side_b);
}

bool face_pair_crosses(const double* vertices, const std::int64_t* fa, const std::int64_t* fb) {
    const auto corner = [&](std::int64_t index) {
        const double* p = vertices + 3 * index;
        return Vec3{p[0], p[1], p[2]};
    };
    int shared = 0, ia = -1, ib = -1;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (fa[i] == fb[j]) ++shared, ia = i, ib = j;
    if (shared >= 3) return false;  // the same three vertices: a duplicate face, not a crossing
    const Vec3 a[3] = {corner(fa[0]), corner(fa[1]), corner(fa[2])};
    const Vec3 b[3] = {corner(fb[0]), corner(fb[1]), corner(fb[2])};
    if (shared == 0 || !distinct(fa) || !distinct(fb)) return triangles_cross(a, b);
    // A shared vertex is the same point in both: orient3d of a's corners and it is exactly 0,
    // so b's sides need only its other corners (the sign is the same under a's cyclic order).
    int side_b[3];
    for (int j = 0; j < 3; ++j)
        side_b[j] = fb[j] == fa[0] || fb[j] == fa[1] || fb[j] == fa[2] ? 0 : sign_of(orient3d(a[0], a[1], a[2], b[j]));
    const bool coplanar = side_b[0] == 0 && side_b[1] == 0 && side_b[2] == 0;
    // A shared edge: b's third corner off a's plane leaves b's sides without both signs, which
    // triangles_cross answers "no" (the triangles meet only on the line of the edge).
    if (!coplanar) {
        int on_b = 0;  // a's corners that are b's: exactly on b's plane
        for (int i = 0; i < 3; ++i) on_b |= (fa[i] == fb[0] || fa[i] == fb[1] || fa[i] == fb[2]) << i;
        return cross_given_sides(a, b, side_b, on_b);
    }
    if (shared == 2) return coplanar_cross(a, b);
    // One shared vertex u, coplanar (a fan's faces): the edge of a opposite u (edge ia + 1)
    // has u strictly inside a's side (a's turn), and u is a corner of b, so it never
    // separates; the same for b's edge ib + 1. Only the edges through u are tried.
    return coplanar_cross(a, b, (ia + 1) % 3, (ib + 1) % 3);
}

void face_pairs_cross(const double* vertices, const std::int64_t* faces, const std::int64_t* pairs,
                      long long pair_count, std::uint8_t* crossing, int threads) {
    const auto corner = [&](std::int64_t index) {
        const double* p = vertices + 3 * index;
        return Vec3{p[0], p[1], p[2]};
    };
    const int workers =
        resolve_threads(threads, pair_count, defaults::triangle_min_pairs_per_thread);
    parallel_for(pair_count, workers, [&](long long begin, long long end) {
        for (long long k = begin; k < end; ++k) {
            const std::int64_t* fa = faces + 3 * pairs[2 * k];
            const std::int64_t* fb = faces + 3 * pairs[2 * k + 1];
            int shared = 0;
            for (int i = 0; i < 3; ++i)
                shared += (fa[i] == fb[0]) + (fa[i] == fb[1]) + (fa[i] == fb[2]);
            if (shared >= 3) {  // the same three vertices: a duplicate face, not a crossing
                crossing[k] = 0;
                continue;
            }
            const Vec3 a[3] = {corner(fa[0]), corner(fa[1]), corner(fa[2])};
            const Vec3 b[3] = {corner(fb[0]), corner(fb[1]), corner(fb[2])};
            crossing[k] = triangles_cross(a, b) ? 1 : 0;
        }
    });
}

}  // namespace meshcol
