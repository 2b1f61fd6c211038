// Quickhull on exact orientation signs, and the interior filter that lightens large inputs;
// hull.cpp turns the triangulation into a Hull.
//
// Quickhull (Barber, Dobkin and Huhdanpaa 1996): a starting tetrahedron, conflict lists (the
// points outside each face), and repeatedly the farthest point of a face's list: the faces it
// sees are removed and the horizon is coned to it. Points within `eps` of a face's plane are
// on the hull (qhull's coplanar points).
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "hull_detail.hpp"
#include "hull_orientation.hpp"

namespace meshcol {
namespace hull_detail {
namespace {

// (b - a) x (c - a) to about one rounding per component: the differences kept exactly
// (two_diff) and each 2 x 2 minor accumulated in double-double (Ogita, Rump and Oishi 2005).
// A plain cross product loses the normal of a thin triangle to cancellation (its error grows
// as one over the triangle's smallest angle), and with it the distances of the points that
// Quickhull assigns to the face.
Vec3 accurate_cross(const Vec3& a, const Vec3& b, const Vec3& c) {
    double uh[3], ul[3], vh[3], vl[3];
    for (int k = 0; k < 3; ++k) {
        two_diff(b[k], a[k], uh[k], ul[k]);
        two_diff(c[k], a[k], vh[k], vl[k]);
    }
    auto minor = [&](int i, int j) {
        double ph, pl, qh, ql, sh, sl;
        two_product(uh[i], vh[j], ph, pl);
        two_product(uh[j], vh[i], qh, ql);
        two_diff(ph, qh, sh, sl);
        const double small = (sl + (pl - ql)) + (uh[i] * vl[j] + ul[i] * vh[j]) -
                             (uh[j] * vl[i] + ul[j] * vh[i]) + (ul[i] * vl[j] - ul[j] * vl[i]);
        return sh + small;
    };
    return {minor(1, 2), minor(2, 0), minor(0, 1)};
}


}  // namespace

// face_plane's case of a sharp first corner: the normal taken at the corner opposite the
// longest edge, whose rounding error relative to its length is about one ulp over the sine of
// that corner's angle, small unless the triangle is a cap (three nearly collinear corners),
// which gets the compensated product. face_plane has computed the squared lengths ab of b - a
// and ca of c - a (a - c's, the same bits), so only bc is new; at the corner a the plain
// product is face_plane's own, which failed the test: the compensated one, unbounded.
Plane face_plane_at_widest(const Vec3& a, const Vec3& b, const Vec3& c, double ab, double ca) {
    const double bc = squared_norm(c - b);
    double uu, vv;
    const Vec3 *o, *p, *q;  // o: the corner; o p q counter-clockwise
    if (ab >= bc && ab >= ca) {
        o = &c, p = &a, q = &b;
        uu = ca, vv = bc;
    } else if (bc >= ca) {
        return plane_of_normal(accurate_cross(a, b, c), false, a);
    } else {
        o = &b, p = &c, q = &a;
        uu = bc, vv = ab;
    }
    const Vec3 u = *p - *o, v = *q - *o;
    const Vec3 n = cross(u, v);
    // sin(angle) >= 1/4: the plain product is within a few ulps of the exact one.
    const bool bounded = kSharpCorner * squared_norm(n) >= uu * vv;
    return plane_of_normal(bounded ? n : accurate_cross(*o, *p, *q), bounded, a);
}

// The first point of `subset` of least and of greatest x, y and z, into extreme[0 .. 6) in
// that order (the components by name: Vec3's operator[] selects among them with compares).
void axis_extremes(const std::vector<Vec3>& p, const std::vector<int>& subset, int extreme[6]) {
    const Vec3* first = &p[subset[0]];
    const Vec3 *low_x = first, *high_x = first, *low_y = first, *high_y = first;
    const Vec3 *low_z = first, *high_z = first;
    for (int i : subset) {
        const Vec3* q = &p[i];
        low_x = q->x < low_x->x ? q : low_x;
        high_x = q->x > high_x->x ? q : high_x;
        low_y = q->y < low_y->y ? q : low_y;
        high_y = q->y > high_y->y ? q : high_y;
        low_z = q->z < low_z->z ? q : low_z;
        high_z = q->z > high_z->z ? q : high_z;
    }
    const Vec3* base = p.data();
    const Vec3* found[6] = {low_x, high_x, low_y, high_y, low_z, high_z};
    for (int k = 0; k < 6; ++k) extreme[k] = static_cast<int>(found[k] - base);
}

// The starting tetrahedron of `subset`, from its axis extremes: the farthest pair of them,
// the point farthest from their line, the point farthest from that plane; into
// corner[0 .. 4) so that (0 1 2), (0 3 1), (1 3 2) and (2 3 0) face outward. DEGENERATE when
// the points span no tetrahedron (by more than eps).
Build start_tetrahedron(const std::vector<Vec3>& p, double eps, const std::vector<int>& subset,
                        const int extreme[6], int corner[4]) {
    int a = extreme[0], b = extreme[1];
    double best = -1.0;
    for (int i = 0; i < 6; ++i)
        for (int j = i + 1; j < 6; ++j) {
            const double d = squared_norm(p[extreme[i]] - p[extreme[j]]);
            if (d > best) best = d, a = extreme[i], b = extreme[j];
        }
    if (!(best > 0.0)) return Build::DEGENERATE;
    const Vec3 ab = p[b] - p[a];
    int c = -1;
    best = 0.0;
    for (int i : subset) {
        const double d = squared_norm(cross(p[i] - p[a], ab));
        if (d > best) best = d, c = i;
    }
    if (c < 0) return Build::DEGENERATE;
    Vec3 n = cross(ab, p[c] - p[a]);
    n = n / norm(n);
    int d = -1;
    best = 0.0;
    for (int i : subset) {
        const double h = std::fabs(dot(n, p[i] - p[a]));
        if (h > best) best = h, d = i;
    }
    if (d < 0 || best <= eps) return Build::DEGENERATE;
    const int o = orientation(p[a], p[b], p[c], p[d]);
    if (o == 0) return Build::DEGENERATE;
    if (o > 0) std::swap(b, c);  // d below abc: abc, adb, bdc, cda face outward
    corner[0] = a, corner[1] = b, corner[2] = c, corner[3] = d;
    return Build::OK;
}

Build start_tetrahedron(const std::vector<Vec3>& p, double eps, const std::vector<int>& subset,
                        int corner[4]) {
    int extreme[6];
    axis_extremes(p, subset, extreme);
    return start_tetrahedron(p, eps, subset, extreme, corner);
}

namespace {

// The interior filter of a large input (Akl and Toussaint 1978): the hull of the points
// extreme along a spread of directions is inside the hull, so a point inside it by a clear
// margin is no vertex of the hull and never the furthest point of a face (some vertex of that
// inner hull lies farther along every normal), and dropping it changes nothing Quickhull picks:
// the same apexes in the same order, the same triangulation. Without it, such points ride
// on conflict lists until a late cone covers them, and each is then tested against every new
// face of that cone (a torus's 500,000 inner points against a cone of 2,000 faces: most of the
// build). Smaller inputs (below kFilterMinPoints) go unfiltered (the filter's own hull and
// scan would cost more than it saves).

void interior_filter(Workspace& w, const std::vector<int>& subset, std::vector<int>& kept) {
    constexpr int directions = 128;
    const std::vector<Vec3>& p = w.p;
    std::vector<int>& extremes = w.filter_extremes;
    extremes.clear();
    // Both scans below are split into chunks of consecutive points on threads (one large
    // input, such as a 2-million-triangle mesh, leaves the other cores idle otherwise), each
    // chunk's answer kept apart and combined in chunk order: the result is the sequential one.
    const auto n = static_cast<long long>(subset.size());
    const int threads = resolve_threads(0, n, defaults::hull_min_filter_points_per_thread);
    const long long chunks = threads <= 1 ? 1 : 4LL * threads;
    const long long per_chunk = (n + chunks - 1) / chunks;
    auto chunk_range = [&](long long c) {
        return std::make_pair(std::min(n, c * per_chunk), std::min(n, (c + 1) * per_chunk));
    };
    // Directions on a Fibonacci sphere; the extreme point along each (first of ties), the
    // directions as a structure of arrays. GCC 12 does not vectorise this scan (it keeps the
    // two selects as branches, "control flow in loop"), with int or 64-bit indices alike.
    const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
    double dx[directions], dy[directions], dz[directions];
    for (int k = 0; k < directions; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / directions;
        const double r = std::sqrt(1.0 - z * z);
        dx[k] = r * std::cos(golden * k);
        dy[k] = r * std::sin(golden * k);
        dz[k] = z;
    }
    struct Extremes {
        double best[directions];
        int arg[directions];
    };
    std::vector<Extremes> found(static_cast<size_t>(chunks));
    parallel_for(chunks, threads, [&](long long first, long long last) {
        for (long long c = first; c < last; ++c) {
            Extremes& e = found[static_cast<size_t>(c)];
            for (int k = 0; k < directions; ++k) {
                e.best[k] = -INFINITY;
                e.arg[k] = subset[0];
            }
            const auto [begin, end] = chunk_range(c);
            for (long long j = begin; j < end; ++j) {
                const int i = subset[static_cast<size_t>(j)];
                const double x = p[i].x, y = p[i].y, z = p[i].z;
                for (int k = 0; k < directions; ++k) {
                    const double d = dx[k] * x + dy[k] * y + dz[k] * z;
                    const bool better = d > e.best[k];
                    e.best[k] = better ? d : e.best[k];
                    e.arg[k] = better ? i : e.arg[k];
                }
            }
        }
    });
    Extremes all = found[0];
    for (size_t c = 1; c < found.size(); ++c)
        for (int k = 0; k < directions; ++k)
            if (found[c].best[k] > all.best[k]) {
                all.best[k] = found[c].best[k];
                all.arg[k] = found[c].arg[k];
            }
    extremes.assign(all.arg, all.arg + directions);
    std::sort(extremes.begin(), extremes.end());
    extremes.erase(std::unique(extremes.begin(), extremes.end()), extremes.end());
    kept.clear();
    Triangulation inner;
    if (quickhull_flat(w, extremes, inner) != Build::OK) {
        kept = subset;
        return;
    }
    // The inner hull's planes (its faces' in slot order, as Quickhull keeps them), packed for
    // the scan.
    std::vector<double>& plane = w.filter_planes;
    plane.clear();
    for (size_t f = 0; f < inner.normal.size(); ++f) {
        const Vec3& n = inner.normal[f];
        plane.insert(plane.end(), {n.x, n.y, n.z, inner.offset[f]});
    }
    const size_t planes = plane.size() / 4;
    // Inside by this much (the points are scaled to at most 1): far above the rounding of a
    // plane distance (about 1e-16) and above eps, so a point dropped is truly interior.
    const double margin = 1e-9 + 4.0 * w.eps;
    std::vector<std::vector<int>> outside(static_cast<size_t>(chunks));
    parallel_for(chunks, threads, [&](long long first, long long last) {
        for (long long c = first; c < last; ++c) {
            std::vector<int>& out = chunks == 1 ? kept : outside[static_cast<size_t>(c)];
            size_t hint = 0;  // consecutive points are often near one another: the last plane first
            const auto [begin, end] = chunk_range(c);
            for (long long j = begin; j < end; ++j) {
                const int i = subset[static_cast<size_t>(j)];
                const Vec3& q = p[i];
                const double* h = &plane[4 * hint];
                if (h[0] * q.x + h[1] * q.y + h[2] * q.z - h[3] > -margin) {
                    out.push_back(i);
                    continue;
                }
                bool inside = true;
                for (size_t f = 0; f < planes; ++f) {
                    const double* e = &plane[4 * f];
                    if (e[0] * q.x + e[1] * q.y + e[2] * q.z - e[3] > -margin) {
                        inside = false;
                        hint = f;
                        break;
                    }
                }
                if (!inside) out.push_back(i);
            }
        }
    });
    if (chunks > 1)
        for (const std::vector<int>& out : outside) kept.insert(kept.end(), out.begin(), out.end());
}

}  // namespace

Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out,
                const int* start) {
    if (subset.size() < kFilterMinPoints)
        return quickhull_flat(w, subset, out, start);
    interior_filter(w, subset, w.filtered);
    return quickhull_flat(w, w.filtered, out);
}

}  // namespace hull_detail
}  // namespace meshcol
