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

double distance(const Face& f, const Vec3& x) { return dot(f.plane.normal, x) - f.plane.offset; }

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

// The normal of a triangle whose first corner is sharp (triangle_normal's slow case), taken
// at the corner opposite the longest edge: its rounding error relative to its length is about
// one ulp over the sine of that corner's angle, small unless the triangle is a cap (three
// nearly collinear corners), which gets the compensated product.
Vec3 triangle_normal_at_widest(const Vec3& a, const Vec3& b, const Vec3& c, bool& bounded) {
    const double ab = squared_norm(b - a), bc = squared_norm(c - b), ca = squared_norm(a - c);
    const Vec3 *o = &a, *p = &b, *q = &c;  // o: the corner; o p q counter-clockwise
    if (ab >= bc && ab >= ca)
        o = &c, p = &a, q = &b;
    else if (bc >= ca)
        o = &a, p = &b, q = &c;
    else
        o = &b, p = &c, q = &a;
    const Vec3 u = *p - *o, v = *q - *o;
    const Vec3 n = cross(u, v);
    // sin(angle) >= 1/4: the plain product is within a few ulps of the exact one.
    bounded = 16.0 * squared_norm(n) >= squared_norm(u) * squared_norm(v);
    if (bounded) return n;
    return accurate_cross(*o, *p, *q);
}

Plane face_plane_at_widest(const Vec3& a, const Vec3& b, const Vec3& c) {
    bool bounded = false;
    const Vec3 n = triangle_normal_at_widest(a, b, c, bounded);
    return plane_of_normal(n, bounded, a);
}

namespace {

constexpr int kNext[3] = {1, 2, 0};  // the edge after edge e of a face

void set_plane(Workspace& w, Face& f) {
    f.plane = face_plane(w.p[f.v[0]], w.p[f.v[1]], w.p[f.v[2]]);
}

// The side of p[q] from face f: +1 outside, -1 inside, 0 on its plane, exactly.
int side(const Workspace& w, const Face& f, int q) {
    const Plane& pl = f.plane;
    return plane_side(pl.normal, pl.offset, pl.filter, w.p[f.v[0]], w.p[f.v[1]], w.p[f.v[2]],
                      w.p[q]);
}

// The exact side of x from face g (its orientation), for the points its plane filter leaves
// undecided.
__attribute__((noinline)) int exact_side(const std::vector<Vec3>& p, const Face& g, const Vec3& x) {
    return orientation(p[g.v[0]], p[g.v[1]], p[g.v[2]], x);
}

// Face `id` as the triangle a b c (counter-clockwise from outside), alive, no neighbours
// linked, no points.
inline void init_face(Workspace& w, int id, int a, int b, int c) {
    Face& f = w.faces[id];
    f.v[0] = a;
    f.v[1] = b;
    f.v[2] = c;
    f.n[0] = f.n[1] = f.n[2] = -1;
    f.conflicts.clear();  // slots past face_count keep their lists' memory from earlier hulls
    f.furthest = -1;
    f.furthest_distance = 0.0;
    f.visit = 0;
    f.visible = false;
    f.alive = true;
    set_plane(w, f);
}

// The slots of `count` new faces into `ids`: the free list from its end, then fresh slots
// (taken in this order, whether one face or a cone of them is made).
void allocate_faces(Workspace& w, size_t count, int* ids) {
    const size_t top = w.free_top;
    const size_t reused = std::min(top, count);
    const int* free_list = w.free_faces.data();
    for (size_t k = 0; k < reused; ++k) ids[k] = free_list[top - 1 - k];
    int fresh = static_cast<int>(w.face_count);
    for (size_t k = reused; k < count; ++k) ids[k] = fresh++;
    w.free_top = top - reused;
    w.face_count = static_cast<size_t>(fresh);
    if (w.faces.size() < w.face_count) w.faces.resize(w.face_count);
}

int new_face(Workspace& w, int a, int b, int c) {
    int id;
    allocate_faces(w, 1, &id);
    init_face(w, id, a, b, c);
    return id;
}

void add_conflict(Face& f, const Conflict& c, double d) {
    f.conflicts.push_back(c);
    if (d > f.furthest_distance) {
        f.furthest_distance = d;
        f.furthest = c.index;
    }
}

// Assigns `c` to the first of `candidates` it is outside of (farther than eps); false when
// it is inside them all.
bool assign(Workspace& w, const Conflict& c, const int* candidates, int count) {
    for (int k = 0; k < count; ++k) {
        const int f = candidates[k];
        const double d = distance(w.faces[f], c.p);
        if (d > w.eps) {
            add_conflict(w.faces[f], c, d);
            return true;
        }
    }
    return false;
}

// Removes `q` from face f's conflict list (it turned out not to see f) and refreshes the
// furthest point.
void drop_conflict(Workspace& w, int face, int q) {
    Face& f = w.faces[face];
    auto& list = f.conflicts;
    list.erase(std::remove_if(list.begin(), list.end(),
                              [q](const Conflict& c) { return c.index == q; }),
               list.end());
    f.furthest = -1;
    f.furthest_distance = 0.0;
    for (const Conflict& c : list) {
        const double d = distance(f, c.p);
        if (d > f.furthest_distance || f.furthest < 0) {
            f.furthest_distance = d;
            f.furthest = c.index;
        }
    }
}

// Links the neighbours of the starting tetrahedron's four faces (matching reversed edges).
void link_faces(Workspace& w, const int* ids, int count) {
    for (int i = 0; i < count; ++i)
        for (int e = 0; e < 3; ++e) {
            Face& f = w.faces[ids[i]];
            const int a = f.v[e], b = f.v[(e + 1) % 3];
            for (int j = 0; j < count; ++j) {
                if (j == i) continue;
                const Face& g = w.faces[ids[j]];
                for (int k = 0; k < 3; ++k)
                    if (g.v[k] == b && g.v[(k + 1) % 3] == a) f.n[e] = ids[j], f.s[e] = k;
            }
        }
}

// The furthest point q of face `seed` is not outside it exactly (a plane rounded badly, never
// seen since planes are accurate): moves q to a face it is outside of, or drops it when it is
// outside none.
void reassign_furthest(Workspace& w, int seed, int q) {
    const std::vector<Vec3>& p = w.p;
    drop_conflict(w, seed, q);
    for (size_t g = 0; g < w.face_count; ++g) {
        Face& h = w.faces[g];
        if (!h.alive || static_cast<int>(g) == seed) continue;
        const double d = distance(h, p[q]);
        if (d > w.eps && orientation(p[h.v[0]], p[h.v[1]], p[h.v[2]], p[q]) > 0) {
            add_conflict(h, Conflict{p[q], q}, d);
            w.pending.push_back(static_cast<int>(g));
            return;
        }
    }
}

// The faces q sees, depth first from the seed, into w.visible, and the horizon edges in
// order, into w.edges: the horizon comes out as a loop, counter-clockwise seen from q
// (Gregorius 2014, "Implementing Quickhull"). False when the horizon is not one simple loop
// (exact orientations guarantee it is).
bool find_horizon(Workspace& w, int seed, int q, unsigned stamp) {
    // Raw arrays with room for every face (each enters the stack and the visible list at
    // most once, and gives at most three horizon edges): no capacity check per entry.
    const size_t room = w.face_count + 1;
    if (w.dfs.size() < room) w.dfs.resize(2 * room);
    if (w.visible.size() < room) w.visible.resize(2 * room);
    if (w.edges.size() < 3 * room) w.edges.resize(6 * room);
    Face* faces = w.faces.data();
    Frame* stack = w.dfs.data();
    int* visible = w.visible.data();
    HorizonEdge* edges = w.edges.data();
    const std::vector<Vec3>& p = w.p;
    const Vec3 x = p[q];
    size_t nv = 0, ne = 0;
    faces[seed].visit = stamp;
    faces[seed].visible = true;
    visible[nv++] = seed;
    // The current face, its next edge and how many are left, in registers; the stack holds
    // the faces below it.
    int top = 0;
    int fi = seed, next = 0, left = 3;
    for (;;) {
        if (left == 0) {
            if (top == 0) break;
            const Frame& below = stack[--top];
            fi = below.face, next = below.edge, left = below.left;
            continue;
        }
        const int e = next;
        next = kNext[e];
        --left;
        const Face& f = faces[fi];
        const int gi = f.n[e];
        Face& g = faces[gi];
        if (g.visit != stamp) {
            g.visit = stamp;
            // The plane filter inline, the exact orientation out of line (inlined, its
            // registers spilled the loop's).
            const Plane& pl = g.plane;
            const double d = dot(pl.normal, x) - pl.offset;
            g.visible = d > pl.filter || (!(d < -pl.filter) && exact_side(p, g, x) > 0);
            if (g.visible) {
                visible[nv++] = gi;
                const int back = f.s[e];  // g's edge back to f
                stack[top++] = {fi, next, left};
                fi = gi, next = kNext[back], left = 2;
                continue;
            }
        } else if (g.visible) {
            continue;
        }
        // A horizon edge, from the visible f to the non-visible g, with g's edge back.
        HorizonEdge& he = edges[ne++];
        he.a = f.v[e];
        he.b = f.v[kNext[e]];
        he.outside = gi;
        he.slot = f.s[e];
    }
    w.visible_count = nv;
    w.edge_count = ne;
    const size_t h = ne;
    if (h < 3) return false;
    int* mark = w.mark.data();
    const int current = static_cast<int>(stamp);
    for (size_t k = 0; k < h; ++k) {
        const HorizonEdge& next = edges[k + 1 < h ? k + 1 : 0];
        if (edges[k].b != next.a) return false;
        if (mark[edges[k].a] == current) return false;
        mark[edges[k].a] = current;
    }
    return true;
}

// Cones the horizon (w.edges) to q in place of the visible faces, whose points are reassigned
// to the new faces (or, outside none of them, to a face of the horizon).
void cone(Workspace& w, int q) {
    // The visible faces go; their points wait for the new faces.
    w.orphans.clear();
    const size_t visible = w.visible_count;
    if (w.free_faces.size() < w.free_top + visible + 1)
        w.free_faces.resize(w.free_top + visible + 1);
    for (size_t v = 0; v < visible; ++v) {
        const int fi = w.visible[v];
        Face& f = w.faces[fi];
        for (const Conflict& c : f.conflicts)
            if (c.index != q) w.orphans.push_back(c);
        f.alive = false;
        f.conflicts.clear();
        w.free_faces[w.free_top++] = fi;
    }
    const size_t h = w.edge_count;
    // Grown only (a resize that grows fills with zeros, every step).
    if (w.new_faces.size() < h) w.new_faces.resize(h);
    if (w.new_planes.size() < 4 * h) w.new_planes.resize(4 * h);
    int* ids = w.new_faces.data();
    allocate_faces(w, h, ids);
    for (size_t k = 0; k < h; ++k) {
        const HorizonEdge& he = w.edges[k];
        const int id = ids[k];
        init_face(w, id, he.a, he.b, q);
        Face& f = w.faces[id];
        f.n[0] = he.outside;
        f.n[1] = ids[k + 1 < h ? k + 1 : 0];
        f.n[2] = ids[k > 0 ? k - 1 : h - 1];
        f.s[0] = he.slot, f.s[1] = 2, f.s[2] = 1;  // the cone's next face leads back by its edge 2
        Face& outside = w.faces[he.outside];
        outside.n[he.slot] = id;
        outside.s[he.slot] = 0;
        double* plane = &w.new_planes[4 * k];
        plane[0] = f.plane.normal.x, plane[1] = f.plane.normal.y, plane[2] = f.plane.normal.z;
        plane[3] = f.plane.offset;
    }
    const double* planes = w.new_planes.data();
    const double eps = w.eps;
    for (const Conflict& x : w.orphans) {
        // The first new face x is outside of (distance as `distance` computes it).
        size_t k = 0;
        double d = 0.0;
        for (; k < h; ++k) {
            const double* e = planes + 4 * k;
            d = (e[0] * x.p.x + e[1] * x.p.y + e[2] * x.p.z) - e[3];
            if (d > eps) break;
        }
        if (k < h) {
            add_conflict(w.faces[w.new_faces[k]], x, d);
            continue;
        }
        // Outside no new face: then inside the new hull, unless outside a face of the
        // horizon (it had been listed on the first face it was outside of).
        for (size_t k2 = 0; k2 < h; ++k2) {
            const HorizonEdge& he = w.edges[k2];
            const double dx = distance(w.faces[he.outside], x.p);
            if (dx > eps) {
                add_conflict(w.faces[he.outside], x, dx);
                w.pending.push_back(he.outside);
                break;
            }
        }
    }
    for (size_t k = 0; k < h; ++k)
        if (!w.faces[w.new_faces[k]].conflicts.empty()) w.pending.push_back(w.new_faces[k]);
}

}  // namespace

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

Build quickhull_points(Workspace& w, const std::vector<int>& subset, Triangulation& out) {
    const std::vector<Vec3>& p = w.p;
    w.face_count = 0;
    w.free_top = 0;
    if (w.free_faces.empty()) w.free_faces.resize(16);
    w.pending.clear();
    if (subset.size() < 4) return Build::DEGENERATE;
    int corner[4];
    const Build started = start_tetrahedron(p, w.eps, subset, corner);
    if (started != Build::OK) return started;
    const int a = corner[0], b = corner[1], c = corner[2], d = corner[3];
    int start[4] = {new_face(w, a, b, c), new_face(w, a, d, b), new_face(w, b, d, c),
                    new_face(w, c, d, a)};
    link_faces(w, start, 4);
    for (int i : subset)
        if (i != a && i != b && i != c && i != d) assign(w, Conflict{p[i], i}, start, 4);
    for (int f : start)
        if (!w.faces[f].conflicts.empty()) w.pending.push_back(f);

    // Each step puts one point on the hull or drops it: the cap is never reached.
    const long long cap = static_cast<long long>(subset.size()) + 16;
    for (long long step = 0; !w.pending.empty(); ++step) {
        if (step > 4 * cap) return Build::FAILED;
        const int seed = w.pending.back();
        if (!w.faces[seed].alive || w.faces[seed].conflicts.empty()) {
            w.pending.pop_back();
            continue;
        }
        const int q = w.faces[seed].furthest;
        {
            if (side(w, w.faces[seed], q) <= 0) {
                reassign_furthest(w, seed, q);
                continue;
            }
        }
        if (!find_horizon(w, seed, q, ++w.stamp)) return Build::FAILED;
        cone(w, q);
    }
    // Compact triangulation, and each edge once, from its lower triangle, with its slot in
    // the other: written always and kept by a count (which side is lower follows no pattern a
    // branch could predict), in one pass.
    const auto slots = static_cast<unsigned>(w.face_count);
    std::vector<int>& index = w.id;
    index.assign(w.face_count, -1);
    int m = 0;
    const Face* faces = w.faces.data();
    for (size_t i = 0; i < w.face_count; ++i)
        if (faces[i].alive) index[i] = m++;
    out.tri.resize(m);
    out.normal.resize(m);
    out.offset.resize(m);
    out.area2.resize(m);
    out.edges.resize(3 * static_cast<size_t>(m));
    TriangulationEdge* edges = out.edges.data();
    size_t count = 0;
    for (size_t i = 0; i < w.face_count; ++i) {
        const Face& f = faces[i];
        if (!f.alive) continue;
        const int t = index[i];
        out.tri[t] = {f.v[0], f.v[1], f.v[2]};
        out.normal[t] = f.plane.normal;
        out.offset[t] = f.plane.offset;
        out.area2[t] = f.plane.area2;
        for (int e = 0; e < 3; ++e) {
            // A dead or missing neighbour has no index (the slots are below face_count).
            const int g = f.n[e];
            if (static_cast<unsigned>(g) >= slots || index[g] < 0) return Build::FAILED;
            const int j = index[g];
            // The neighbour's edge that leads back (the compacted list's too, the index
            // being one to one).
            edges[count] = {t, e, j, f.s[e]};
            count += j > t;
        }
    }
    out.edges.resize(count);
    return Build::OK;
}

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

Build quickhull_reference(Workspace& w, const std::vector<int>& subset, Triangulation& out) {
    return quickhull_points(w, subset, out);
}

Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out,
                const int* start) {
    if (subset.size() < kFilterMinPoints)
        return quickhull_flat(w, subset, out, start);
    interior_filter(w, subset, w.filtered);
    return quickhull_flat(w, w.filtered, out);
}

}  // namespace hull_detail
}  // namespace meshcol
