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

namespace meshcol {

namespace {

// ---------------------------------------------------------------------------------------
// Exact orientation (Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast
// robust geometric predicates"): a floating-point filter with his static error bound, and an
// exact evaluation with expansion arithmetic when the filter cannot decide. Quickhull's
// topology (which faces a new point sees) is decided by this exact sign, so the polytope it
// builds is always convex and the horizon always one simple loop, whatever the degeneracy.

// Expansions live in fixed arrays on the stack (the largest here has 192 components; one
// spare slot because the merge below reads one past the end, as Shewchuk's code does).
constexpr int expansion_capacity = 256;

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
    // product is exact too and inlines.
    double ah, al, bh, bl;
    split(a, ah, al);
    split(b, bh, bl);
    y = al * bl - (((x - ah * bh) - al * bh) - ah * bl);
#endif
}

// h = e + f (Fast-Expansion-Sum with zero elimination); e and f non-overlapping, increasing
// magnitude, at least one component each. Returns the length of h.
int expansion_sum(const double* e, int en, const double* f, int fn, double* h) {
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
int scale_expansion(const double* e, int en, double b, double* h) {
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
int expansion_product(const double* e, int en, const double* f, int fn, double* h) {
    double part[expansion_capacity], acc[expansion_capacity];
    int n = scale_expansion(e, en, f[0], h);
    for (int i = 1; i < fn; ++i) {
        const int pn = scale_expansion(e, en, f[i], part);
        std::copy(h, h + n, acc);
        n = expansion_sum(acc, n, part, pn, h);
    }
    return n;
}

int difference(double a, double b, double* h) {
    double x, y;
    two_diff(a, b, x, y);
    int n = 0;
    if (y != 0.0) h[n++] = y;
    if (x != 0.0 || n == 0) h[n++] = x;
    return n;
}

int orientation_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
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
int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
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

// ---------------------------------------------------------------------------------------
// Quickhull (Barber, Dobkin and Huhdanpaa 1996): a starting tetrahedron, conflict lists (the
// points outside each face), and repeatedly the farthest point of a face's list: the faces it
// sees are removed and the horizon is coned to it. Points within `eps` of a face's plane are
// on the hull (qhull's coplanar points).

// A point waiting outside a face, with its coordinates: the conflict lists are scanned far
// more often than written, and a list of copies streams through the cache where a linked
// list of indices would miss on every point.
struct Conflict {
    Vec3 p;
    int index;
};

struct Face {
    int v[3];  // point indices, counter-clockwise seen from outside
    int n[3];  // neighbour across edge v[i] -> v[(i + 1) % 3]
    Vec3 normal;
    double offset = 0.0;  // dot(normal, x) - offset is the distance of x
    std::vector<Conflict> conflicts;  // the points outside this face (farther than eps)
    int furthest = -1;
    double furthest_distance = 0.0;
    unsigned visit = 0;
    bool visible = false;
    bool alive = false;
};

struct HorizonEdge {
    int a, b;      // the edge, as the visible face had it
    int outside;   // the non-visible face across it
    int slot;      // the edge index in `outside` that pointed to the visible face
};

struct Frame {
    int face, start, count, done;
};

struct Workspace {
    std::vector<Vec3> p;  // scaled points
    double eps = 0.0;
    std::vector<int> mark;  // per point: stamp of the horizon check
    std::vector<Face> faces;  // a pool: faces[0 .. face_count) are this hull's
    size_t face_count = 0;
    std::vector<int> free_faces, pending, visible, new_faces;
    std::vector<Conflict> orphans;
    std::vector<std::pair<int, int>> horizon;
    std::vector<HorizonEdge> edges;
    std::vector<Frame> dfs;
    unsigned stamp = 0;
    // scratch of the analysis and the packing, kept across shapes
    std::vector<int> all, real, local, keep, parent, id;
    std::vector<char> used;
    std::vector<std::int64_t> start;
    std::vector<long long> table;
    std::vector<Conflict> sorted;  // the input, sorted and without duplicates
    std::vector<Vec3> unique_points;
    std::vector<int> unique_index;
    std::vector<int> filtered, filter_extremes;  // interior_filter's
    std::vector<double> filter_planes;
};

// A triangulated 3-D hull: triangles of point indices and their neighbours.
struct Triangulation {
    std::vector<std::array<int, 3>> tri;
    std::vector<std::array<int, 3>> neighbor;
};

enum class Build { OK, DEGENERATE, FAILED };

double distance(const Face& f, const Vec3& x) { return dot(f.normal, x) - f.offset; }

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

// The outward normal (b - a) x (c - a), unnormalised, taken at the corner opposite the
// longest edge: its rounding error relative to its length is about one ulp over the sine of
// that corner's angle, small unless the triangle is a cap (three nearly collinear corners),
// which gets the compensated product.
Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
    {
        // Most triangles are well shaped at their first corner already.
        const Vec3 u = b - a, v = c - a;
        const Vec3 n = cross(u, v);
        if (16.0 * squared_norm(n) >= squared_norm(u) * squared_norm(v)) return n;
    }
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
    if (16.0 * squared_norm(n) >= squared_norm(u) * squared_norm(v)) return n;
    return accurate_cross(*o, *p, *q);
}

void set_plane(Workspace& w, Face& f) {
    const Vec3& a = w.p[f.v[0]];
    const Vec3 n = triangle_normal(a, w.p[f.v[1]], w.p[f.v[2]]);
    const double len = norm(n);
    f.normal = len > 0.0 ? n / len : Vec3{};
    f.offset = dot(f.normal, a);
}

int new_face(Workspace& w, int a, int b, int c) {
    int id;
    if (!w.free_faces.empty()) {
        id = w.free_faces.back();
        w.free_faces.pop_back();
    } else {
        // Slots past face_count keep their conflict lists' memory from earlier hulls.
        id = static_cast<int>(w.face_count++);
        if (w.faces.size() < w.face_count) w.faces.emplace_back();
    }
    Face& f = w.faces[id];
    f.v[0] = a;
    f.v[1] = b;
    f.v[2] = c;
    f.n[0] = f.n[1] = f.n[2] = -1;
    f.conflicts.clear();
    f.furthest = -1;
    f.furthest_distance = 0.0;
    f.visit = 0;
    f.visible = false;
    f.alive = true;
    set_plane(w, f);
    return id;
}

void add_conflict(Workspace& w, int face, const Conflict& c, double d) {
    Face& f = w.faces[face];
    f.conflicts.push_back(c);
    if (d > f.furthest_distance) {
        f.furthest_distance = d;
        f.furthest = c.index;
    }
}

// Assigns `q` to the first of `candidates` it is outside of (farther than eps); false when
// it is inside them all.
bool assign(Workspace& w, const Conflict& c, const std::vector<int>& candidates) {
    for (int f : candidates) {
        const double d = distance(w.faces[f], c.p);
        if (d > w.eps) {
            add_conflict(w, f, c, d);
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
                    if (g.v[k] == b && g.v[(k + 1) % 3] == a) f.n[e] = ids[j];
            }
        }
}

Build quickhull_points(Workspace& w, const std::vector<int>& subset, Triangulation& out) {
    const std::vector<Vec3>& p = w.p;
    w.face_count = 0;
    w.free_faces.clear();
    w.pending.clear();
    if (subset.size() < 4) return Build::DEGENERATE;
    // Starting tetrahedron: the farthest pair of the axis extremes, the point farthest from
    // their line, the point farthest from that plane.
    int extreme[6];
    for (int k = 0; k < 6; ++k) extreme[k] = subset[0];
    for (int i : subset)
        for (int k = 0; k < 3; ++k) {
            if (p[i][k] < p[extreme[2 * k]][k]) extreme[2 * k] = i;
            if (p[i][k] > p[extreme[2 * k + 1]][k]) extreme[2 * k + 1] = i;
        }
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
    if (d < 0 || best <= w.eps) return Build::DEGENERATE;
    const int o = orientation(p[a], p[b], p[c], p[d]);
    if (o == 0) return Build::DEGENERATE;
    if (o > 0) std::swap(b, c);  // d below abc: abc, adb, bdc, cda face outward
    int start[4] = {new_face(w, a, b, c), new_face(w, a, d, b), new_face(w, b, d, c),
                    new_face(w, c, d, a)};
    link_faces(w, start, 4);
    w.new_faces.assign(start, start + 4);
    for (int i : subset)
        if (i != a && i != b && i != c && i != d) assign(w, Conflict{p[i], i}, w.new_faces);
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
            const Face& f = w.faces[seed];
            if (orientation(p[f.v[0]], p[f.v[1]], p[f.v[2]], p[q]) <= 0) {
                // Farther than eps by the rounded plane but not outside exactly (a plane
                // rounded badly, never seen since planes are accurate): move the point to a
                // face it is outside of, or drop it when it is outside none.
                drop_conflict(w, seed, q);
                for (size_t g = 0; g < w.face_count; ++g) {
                    const Face& h = w.faces[g];
                    if (!h.alive || static_cast<int>(g) == seed) continue;
                    const double d = distance(h, p[q]);
                    if (d > w.eps && orientation(p[h.v[0]], p[h.v[1]], p[h.v[2]], p[q]) > 0) {
                        add_conflict(w, static_cast<int>(g), Conflict{p[q], q}, d);
                        w.pending.push_back(static_cast<int>(g));
                        break;
                    }
                }
                continue;
            }
        }
        // The faces q sees, depth first from the seed: the horizon comes out as a loop,
        // counter-clockwise seen from q (Gregorius 2014, "Implementing Quickhull").
        const unsigned stamp = ++w.stamp;
        w.visible.clear();
        w.horizon.clear();
        w.dfs.clear();
        w.faces[seed].visit = stamp;
        w.faces[seed].visible = true;
        w.visible.push_back(seed);
        w.dfs.push_back({seed, 0, 3, 0});
        while (!w.dfs.empty()) {
            Frame& fr = w.dfs.back();
            if (fr.done == fr.count) {
                w.dfs.pop_back();
                continue;
            }
            const int fi = fr.face;
            const int e = (fr.start + fr.done) % 3;
            ++fr.done;
            const int gi = w.faces[fi].n[e];
            Face& g = w.faces[gi];
            if (g.visit == stamp) {
                if (!g.visible) w.horizon.emplace_back(fi, e);
                continue;
            }
            g.visit = stamp;
            g.visible = orientation(p[g.v[0]], p[g.v[1]], p[g.v[2]], p[q]) > 0;
            if (!g.visible) {
                w.horizon.emplace_back(fi, e);
                continue;
            }
            w.visible.push_back(gi);
            int back = -1;
            for (int k = 0; k < 3; ++k)
                if (g.n[k] == fi) back = k;
            if (back < 0) return Build::FAILED;
            w.dfs.push_back({gi, (back + 1) % 3, 2, 0});
        }
        // The horizon must be one simple loop (exact orientations guarantee it).
        const size_t h = w.horizon.size();
        if (h < 3) return Build::FAILED;
        w.edges.resize(h);
        for (size_t k = 0; k < h; ++k) {
            const auto [fi, e] = w.horizon[k];
            const Face& f = w.faces[fi];
            HorizonEdge& he = w.edges[k];
            he.a = f.v[e];
            he.b = f.v[(e + 1) % 3];
            he.outside = f.n[e];
            he.slot = -1;
            const Face& g = w.faces[he.outside];
            for (int s = 0; s < 3; ++s)
                if (g.n[s] == fi && g.v[s] == he.b) he.slot = s;
            if (he.slot < 0) return Build::FAILED;
        }
        for (size_t k = 0; k < h; ++k) {
            if (w.edges[k].b != w.edges[(k + 1) % h].a) return Build::FAILED;
            if (w.mark[w.edges[k].a] == static_cast<int>(stamp)) return Build::FAILED;
            w.mark[w.edges[k].a] = static_cast<int>(stamp);
        }
        // The visible faces go; their points wait for the new faces.
        w.orphans.clear();
        for (int fi : w.visible) {
            Face& f = w.faces[fi];
            for (const Conflict& c : f.conflicts)
                if (c.index != q) w.orphans.push_back(c);
            f.alive = false;
            f.conflicts.clear();
            w.free_faces.push_back(fi);
        }
        w.new_faces.resize(h);
        for (size_t k = 0; k < h; ++k) {
            const HorizonEdge& he = w.edges[k];
            const int id = new_face(w, he.a, he.b, q);
            w.faces[id].n[0] = he.outside;
            w.faces[he.outside].n[he.slot] = id;
            w.new_faces[k] = id;
        }
        for (size_t k = 0; k < h; ++k) {
            Face& f = w.faces[w.new_faces[k]];
            f.n[1] = w.new_faces[(k + 1) % h];
            f.n[2] = w.new_faces[(k + h - 1) % h];
        }
        for (const Conflict& x : w.orphans) {
            if (assign(w, x, w.new_faces)) continue;
            // Outside no new face: then inside the new hull, unless outside a face of the
            // horizon (it had been listed on the first face it was outside of).
            for (const HorizonEdge& he : w.edges) {
                const double dx = distance(w.faces[he.outside], x.p);
                if (dx > w.eps) {
                    add_conflict(w, he.outside, x, dx);
                    w.pending.push_back(he.outside);
                    break;
                }
            }
        }
        for (int id : w.new_faces)
            if (!w.faces[id].conflicts.empty()) w.pending.push_back(id);
    }
    // Compact triangulation.
    std::vector<int>& index = w.id;
    index.assign(w.face_count, -1);
    int m = 0;
    for (size_t i = 0; i < w.face_count; ++i)
        if (w.faces[i].alive) index[i] = m++;
    out.tri.resize(m);
    out.neighbor.resize(m);
    for (size_t i = 0; i < w.face_count; ++i) {
        const Face& f = w.faces[i];
        if (!f.alive) continue;
        const int t = index[i];
        out.tri[t] = {f.v[0], f.v[1], f.v[2]};
        for (int e = 0; e < 3; ++e) {
            if (f.n[e] < 0 || !w.faces[f.n[e]].alive) return Build::FAILED;
            out.neighbor[t][e] = index[f.n[e]];
        }
    }
    return Build::OK;
}

// The interior filter of a large input (Akl and Toussaint 1978): the hull of the points
// extreme along a spread of directions is inside the hull, so a point inside it by a clear
// margin is no vertex of the hull and never the furthest point of a face (some vertex of that
// inner hull lies farther along every normal), and dropping it changes nothing Quickhull picks:
// the same apexes in the same order, the same triangulation. Without it, such points ride
// on conflict lists until a late cone covers them, and each is then tested against every new
// face of that cone (a torus's 500,000 inner points against a cone of 2,000 faces: most of the
// build). Smaller inputs go unfiltered (the filter's own hull and scan would cost more than
// it saves).
constexpr size_t kFilterMinPoints = 4096;

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
    if (quickhull_points(w, extremes, inner) != Build::OK) {
        kept = subset;
        return;
    }
    // The inner hull's planes, structure of arrays for the scan.
    std::vector<double>& plane = w.filter_planes;
    plane.clear();
    for (size_t f = 0; f < w.face_count; ++f) {
        const Face& face = w.faces[f];
        if (!face.alive) continue;
        plane.insert(plane.end(), {face.normal.x, face.normal.y, face.normal.z, face.offset});
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

Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out) {
    if (subset.size() < kFilterMinPoints)
        return quickhull_points(w, subset, out);
    interior_filter(w, subset, w.filtered);
    return quickhull_points(w, w.filtered, out);
}

// Plane of each triangle (scaled frame), coplanar groups and the number of edges between
// different planes at each point.
struct Planes {
    std::vector<Vec3> normal;
    std::vector<double> offset;
    std::vector<double> area2;  // twice the triangle's area
    std::vector<int> group;     // plane id per triangle
    int groups = 0;
};

// Everything one hull leaves behind, reused across the shapes of a batch (their capacity
// saves the allocations that otherwise cost as much as a small hull).
struct Analysis {
    Triangulation t, previous;
    Planes pl;
    Hull hull;

    void reset() {
        hull.status = HullStatus::EMPTY;
        hull.dimension = -1;
        hull.vertices.clear();
        hull.faces.clear();
        hull.face_normals.clear();
        hull.face_offsets.clear();
        hull.face_planes.clear();
        hull.plane_normals.clear();
        hull.normal = Vec3{};
        hull.volume = hull.area = hull.diagonal = 0.0;
    }
};

int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

void planes_of(Workspace& w, const Triangulation& t, Planes& out) {
    const size_t m = t.tri.size();
    out.normal.resize(m);
    out.offset.resize(m);
    out.area2.resize(m);
    for (size_t i = 0; i < m; ++i) {
        const Vec3& a = w.p[t.tri[i][0]];
        const Vec3 n = triangle_normal(a, w.p[t.tri[i][1]], w.p[t.tri[i][2]]);
        const double len = norm(n);
        out.area2[i] = len;
        out.normal[i] = len > 0.0 ? n / len : Vec3{};
        out.offset[i] = dot(out.normal[i], a);
    }
    // Neighbours are coplanar when each one's far corner lies within eps of the other's
    // plane; coplanar groups are the connected components (one plane, one SAT normal).
    std::vector<int>& parent = w.parent;
    parent.resize(m);
    std::iota(parent.begin(), parent.end(), 0);
    for (size_t i = 0; i < m; ++i)
        for (int e = 0; e < 3; ++e) {
            const int j = t.neighbor[i][e];
            if (j < static_cast<int>(i)) continue;
            const int far_i = t.tri[i][(e + 2) % 3];
            int far_j = -1;
            for (int k = 0; k < 3; ++k)
                if (t.neighbor[j][k] == static_cast<int>(i)) far_j = t.tri[j][(k + 2) % 3];
            if (far_j < 0) continue;
            const bool coplanar =
                std::fabs(dot(out.normal[i], w.p[far_j]) - out.offset[i]) <= w.eps &&
                std::fabs(dot(out.normal[j], w.p[far_i]) - out.offset[j]) <= w.eps;
            if (coplanar) parent[find_root(parent, j)] = find_root(parent, static_cast<int>(i));
        }
    out.group.assign(m, -1);
    std::vector<int>& id = w.id;
    id.assign(m, -1);
    out.groups = 0;
    for (size_t i = 0; i < m; ++i) {
        const int r = find_root(parent, static_cast<int>(i));
        if (id[r] < 0) id[r] = out.groups++;
        out.group[i] = id[r];
    }
}

// Principal axes of points (Jacobi eigenvectors of their covariance), largest spread first.
void principal_axes(const Vec3* p, const std::vector<int>& idx, const Vec3& centre, Vec3 axes[3]) {
    double a[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (int i : idx) {
        const Vec3 d = p[i] - centre;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) a[r][c] += d[r] * d[c];
    }
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = std::fabs(a[0][1]) + std::fabs(a[0][2]) + std::fabs(a[1][2]);
        const double diag = std::fabs(a[0][0]) + std::fabs(a[1][1]) + std::fabs(a[2][2]);
        if (off <= 1e-30 * diag || off == 0.0) break;
        for (int r = 0; r < 2; ++r)
            for (int c = r + 1; c < 3; ++c) {
                if (a[r][c] == 0.0) continue;
                // Classic Jacobi rotation zeroing a[r][c] (Golub and Van Loan, sec. 8.5).
                const double theta = (a[c][c] - a[r][r]) / (2.0 * a[r][c]);
                const double t = (theta >= 0 ? 1.0 : -1.0) /
                                 (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
                const double cs = 1.0 / std::sqrt(t * t + 1.0), sn = t * cs;
                for (int k = 0; k < 3; ++k) {
                    const double akr = a[k][r], akc = a[k][c];
                    a[k][r] = cs * akr - sn * akc;
                    a[k][c] = sn * akr + cs * akc;
                }
                for (int k = 0; k < 3; ++k) {
                    const double ark = a[r][k], ack = a[c][k];
                    a[r][k] = cs * ark - sn * ack;
                    a[c][k] = sn * ark + cs * ack;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkr = v[k][r], vkc = v[k][c];
                    v[k][r] = cs * vkr - sn * vkc;
                    v[k][c] = sn * vkr + cs * vkc;
                }
            }
    }
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int x, int y) { return a[x][x] > a[y][y]; });
    for (int k = 0; k < 3; ++k) {
        const int j = order[k];
        axes[k] = Vec3{v[0][j], v[1][j], v[2][j]};
        axes[k] = axes[k] / norm(axes[k]);
    }
}

bool lexicographic_less(const Vec3& a, const Vec3& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

// The 2-D hull in the plane of axes[0], axes[1]: Andrew's monotone chain, points within
// eps of a chord dropped. Returns the ring counter-clockwise (about axes[0] x axes[1]).
std::vector<int> polygon(const Workspace& w, const std::vector<int>& idx, const Vec3& centre,
                         const Vec3 axes[3], double& area) {
    const size_t n = idx.size();
    std::vector<std::pair<double, double>> uv(w.p.size());
    for (int i : idx) {
        const Vec3 d = w.p[i] - centre;
        uv[i] = {dot(d, axes[0]), dot(d, axes[1])};
    }
    std::vector<int> order(idx);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return uv[a] < uv[b]; });
    auto turns_left = [&](int o, int a, int b) {
        const double ax = uv[a].first - uv[o].first, ay = uv[a].second - uv[o].second;
        const double bx = uv[b].first - uv[o].first, by = uv[b].second - uv[o].second;
        const double c = ax * by - ay * bx;  // |ob| times the height of a over the chord ob
        return c > w.eps * std::sqrt(bx * bx + by * by);
    };
    std::vector<int> ring;
    ring.reserve(2 * n);
    for (size_t k = 0; k < n; ++k) {
        while (ring.size() >= 2 && !turns_left(ring[ring.size() - 2], ring.back(), order[k]))
            ring.pop_back();
        ring.push_back(order[k]);
    }
    const size_t lower = ring.size() + 1;
    for (size_t k = n - 1; k-- > 0;) {
        while (ring.size() >= lower && !turns_left(ring[ring.size() - 2], ring.back(), order[k]))
            ring.pop_back();
        ring.push_back(order[k]);
    }
    ring.pop_back();  // the first point again
    area = 0.0;
    for (size_t k = 0; k < ring.size(); ++k) {
        const auto& s = uv[ring[k]];
        const auto& t = uv[ring[(k + 1) % ring.size()]];
        area += s.first * t.second - s.second * t.first;
    }
    area *= 0.5;
    return ring;
}

// The hull of points already checked finite and in range.
void compute(const Vec3* points, long long n, Workspace& w, Analysis& analysis) {
    Hull& hull = analysis.hull;
    double max_abs = 0.0;
    for (long long i = 0; i < n; ++i) {
        const Vec3& q = points[i];
        const double m = std::max(std::fabs(q.x), std::max(std::fabs(q.y), std::fabs(q.z)));
        max_abs = m > max_abs ? m : max_abs;
    }
    // A power of two scales exactly: the hull of the scaled points is the hull of the points.
    int exponent = 0;
    if (max_abs > 0.0) std::frexp(max_abs, &exponent);
    const double to_unit = std::ldexp(1.0, -exponent);
    w.p.resize(static_cast<size_t>(n));
    Vec3 lo = points[0] * to_unit, hi = lo, sum{};
    for (long long i = 0; i < n; ++i) {
        const Vec3 q = points[i] * to_unit;
        w.p[i] = q;
        for (int k = 0; k < 3; ++k) {
            lo[k] = q[k] < lo[k] ? q[k] : lo[k];
            hi[k] = q[k] > hi[k] ? q[k] : hi[k];
        }
        sum += q;
    }
    w.eps = defaults::hull_relative_tolerance * std::ldexp(max_abs, -exponent);
    w.mark.assign(static_cast<size_t>(n), 0);
    w.stamp = 0;
    const double diagonal = norm(hi - lo);
    hull.diagonal = std::ldexp(diagonal, exponent);
    std::vector<int>& all = w.all;
    all.resize(static_cast<size_t>(n));
    std::iota(all.begin(), all.end(), 0);
    auto smallest = [&]() {
        int best = 0;
        for (long long i = 1; i < n; ++i)
            if (lexicographic_less(points[i], points[best])) best = static_cast<int>(i);
        return best;
    };
    if (!(diagonal > 0.0)) {
        hull.status = HullStatus::SINGLE_POINT;
        hull.dimension = 0;
        hull.vertices = {smallest()};
        return;
    }
    // The flatness rule: widths along the principal axes against the diagonal.
    const Vec3 centre = sum / static_cast<double>(n);
    Vec3 axes[3];
    principal_axes(w.p.data(), all, centre, axes);
    int dim = 0;
    for (int k = 0; k < 3; ++k) {
        double a = INFINITY, b = -INFINITY;
        for (long long i = 0; i < n; ++i) {
            const double t = dot(w.p[i] - centre, axes[k]);
            a = t < a ? t : a;
            b = t > b ? t : b;
        }
        if (b - a > defaults::flat_relative_tolerance * diagonal) ++dim;
    }
    if (dim == 3) {
        Triangulation& t = analysis.t;
        Triangulation& previous = analysis.previous;
        Planes& pl = analysis.pl;
        std::vector<int> subset = all;
        bool have = false, planes_current = false;
        std::vector<int> removed, dropped;  // the vertices a rerun leaves out
        for (int run = 0; run <= defaults::hull_max_reruns; ++run) {
            const Build b = quickhull(w, subset, t);
            if (b == Build::FAILED && !have) {
                hull.status = HullStatus::FAILED;
                hull.dimension = -1;
                return;
            }
            if (b != Build::OK) {  // a rerun that failed: the previous hull stands
                t = previous;
                planes_current = false;
                break;
            }
            planes_of(w, t, pl);
            planes_current = true;
            if (have) {
                // The rerun must still hold every vertex it left out (within a few eps): else
                // one was a true corner flagged through a chain of nearly coplanar faces, and
                // the previous hull stands.
                bool holds = true;
                for (size_t k = 0; holds && k < removed.size(); ++k)
                    for (size_t i = 0; holds && i < t.tri.size(); ++i)
                        holds = dot(pl.normal[i], w.p[removed[k]]) - pl.offset[i] <= 4.0 * w.eps;
                if (!holds) {
                    t = previous;
                    planes_current = false;
                    break;
                }
            }
            have = true;
            // A vertex with at most two edges between different planes lies on an edge or
            // in a face of its hull (a coplanar tie Quickhull took first): hull again
            // without those.
            std::vector<int>& real = w.real;
            std::vector<char>& used = w.used;
            real.assign(static_cast<size_t>(n), 0);
            used.assign(static_cast<size_t>(n), 0);
            for (size_t i = 0; i < t.tri.size(); ++i)
                for (int e = 0; e < 3; ++e) {
                    used[t.tri[i][e]] = 1;
                    const int j = t.neighbor[i][e];
                    if (j > static_cast<int>(i) && pl.group[i] != pl.group[j]) {
                        ++real[t.tri[i][e]];
                        ++real[t.tri[i][(e + 1) % 3]];
                    }
                }
            std::vector<int>& keep = w.keep;
            keep.clear();
            dropped.clear();
            for (long long i = 0; i < n; ++i) {
                if (!used[i]) continue;
                if (real[i] <= 2)
                    dropped.push_back(static_cast<int>(i));
                else
                    keep.push_back(static_cast<int>(i));
            }
            // The check above costs (left out) x (faces): past a cap the hull stays as is
            // (valid, with a few extra vertices on its edges or faces).
            const double work = static_cast<double>(dropped.size()) * 2.0 *
                                static_cast<double>(keep.size());
            if (dropped.empty() || run == defaults::hull_max_reruns ||
                work > defaults::hull_max_rerun_work)
                break;
            previous = t;
            subset.swap(keep);
            removed.swap(dropped);
        }
        if (have) {
            if (!planes_current) planes_of(w, t, pl);
            // Vertices in lexicographic order.
            std::vector<int> verts;
            std::vector<int>& local = w.local;
            local.assign(static_cast<size_t>(n), -1);
            for (const auto& tri : t.tri)
                for (int v : tri)
                    if (local[v] < 0) local[v] = 0, verts.push_back(v);
            std::sort(verts.begin(), verts.end());  // the points are in lexicographic order
            for (size_t k = 0; k < verts.size(); ++k) local[verts[k]] = static_cast<int>(k);
            hull.status = HullStatus::OK;
            hull.dimension = 3;
            hull.vertices = verts;
            const size_t m = t.tri.size();
            hull.faces.resize(m);
            hull.face_normals.resize(m);
            hull.face_offsets.resize(m);
            hull.face_planes = pl.group;
            hull.plane_normals.assign(static_cast<size_t>(pl.groups), Vec3{});
            std::vector<double> largest(static_cast<size_t>(pl.groups), -1.0);
            double volume = 0.0, area = 0.0;
            const Vec3 origin = w.p[verts[0]];
            for (size_t i = 0; i < m; ++i) {
                const auto& tri = t.tri[i];
                hull.faces[i] = {local[tri[0]], local[tri[1]], local[tri[2]]};
                hull.face_normals[i] = pl.normal[i];
                hull.face_offsets[i] = -dot(pl.normal[i], points[tri[0]]);
                const int g = pl.group[i];
                if (pl.area2[i] > largest[g]) {
                    largest[g] = pl.area2[i];
                    hull.plane_normals[g] = pl.normal[i];
                }
                area += pl.area2[i];
                volume += dot(w.p[tri[0]] - origin,
                              cross(w.p[tri[1]] - origin, w.p[tri[2]] - origin));
            }
            hull.volume = std::ldexp(volume / 6.0, 3 * exponent);
            hull.area = std::ldexp(area / 2.0, 2 * exponent);
            return;
        }
        dim = 2;
    }
    if (dim == 2) {
        double area = 0.0;
        std::vector<int> ring = polygon(w, all, centre, axes, area);
        if (ring.size() >= 3) {
            hull.status = HullStatus::FLAT;
            hull.dimension = 2;
            hull.vertices = ring;
            for (int k = 1; k + 1 < static_cast<int>(ring.size()); ++k)
                hull.faces.push_back({0, k, k + 1});
            const Vec3 normal = cross(axes[0], axes[1]);
            hull.normal = normal / norm(normal);
            hull.area = std::ldexp(area, 2 * exponent);
            return;
        }
        dim = 1;
    }
    if (dim == 1) {
        int a = 0, b = 0;
        double ta = INFINITY, tb = -INFINITY;
        for (long long i = 0; i < n; ++i) {
            const double t = dot(w.p[i] - centre, axes[0]);
            if (t < ta) ta = t, a = static_cast<int>(i);
            if (t > tb) tb = t, b = static_cast<int>(i);
        }
        hull.status = HullStatus::COLLINEAR;
        hull.dimension = 1;
        hull.vertices = {a, b};
        return;
    }
    hull.status = HullStatus::SINGLE_POINT;
    hull.dimension = 0;
    hull.vertices = {smallest()};
}

// Status of points that have no hull at all, or OK when they can have one.
HullStatus screen(const Vec3* points, long long n) {
    if (n <= 0) return HullStatus::EMPTY;
    if (n > INT_MAX) return HullStatus::FAILED;  // point indices are ints
    bool huge = false;
    for (long long i = 0; i < n; ++i) {
        if (!is_finite(points[i])) return HullStatus::NON_FINITE;
        huge = huge || meshcol::max_abs(points[i]) > defaults::hull_max_abs_coordinate;
    }
    return huge ? HullStatus::OVERFLOW : HullStatus::OK;
}

// The hull of `points` into analysis.hull (and its triangulation and planes, 3-D).
void hull_with(const Vec3* points, long long n, Workspace& w, Analysis& analysis) {
    analysis.reset();
    Hull& hull = analysis.hull;
    hull.status = screen(points, n);
    if (hull.status != HullStatus::OK) return;
    // Sorted, without exact duplicates (-0.0 as 0.0), the points give the same hull in any
    // order: equal point sets, equal triangulations (decomposition parts rely on it).
    std::vector<Conflict>& sorted = w.sorted;
    sorted.resize(static_cast<size_t>(n));
    const Vec3 zero{0.0, 0.0, 0.0};
    for (long long i = 0; i < n; ++i) sorted[i] = {points[i] + zero, static_cast<int>(i)};
    std::sort(sorted.begin(), sorted.end(), [](const Conflict& a, const Conflict& b) {
        return lexicographic_less(a.p, b.p) ||
               (!lexicographic_less(b.p, a.p) && a.index < b.index);
    });
    w.unique_points.clear();
    w.unique_index.clear();
    for (long long i = 0; i < n; ++i) {
        if (i > 0 && !lexicographic_less(sorted[i - 1].p, sorted[i].p)) continue;
        w.unique_points.push_back(sorted[i].p);
        w.unique_index.push_back(sorted[i].index);
    }
    compute(w.unique_points.data(), static_cast<long long>(w.unique_points.size()), w, analysis);
    for (int& v : hull.vertices) v = w.unique_index[v];
}

// ---------------------------------------------------------------------------------------
// Packing

struct ShapePack {
    HullStatus status = HullStatus::EMPTY;
    std::vector<Vec3> vertices;
    std::vector<std::int64_t> adjacency_counts;  // per vertex
    std::vector<std::int32_t> adjacency;
    std::vector<Vec3> faces;
    std::vector<Vec3> edges;
};

// One direction per class: unit, rounded to 12 digits for grouping; unsigned classes get a
// canonical sign (the first component clearly non-zero positive). First occurrences kept,
// in input order (an open-addressing table of the rounded keys: linear in the count).
void unique_directions(std::vector<Vec3>& d, bool signed_classes, std::vector<long long>& table) {
    size_t size = 16;
    while (size < 2 * d.size()) size *= 2;
    table.assign(3 * size, LLONG_MIN);
    size_t kept = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        Vec3 v = d[i];
        const double len = norm(v);
        if (!(len > 0.0)) continue;
        v = v / len;
        if (!signed_classes) {
            double s = 0.0;
            for (int k = 0; k < 3 && s == 0.0; ++k)
                if (std::fabs(v[k]) > 1e-12) s = v[k] > 0.0 ? 1.0 : -1.0;
            if (s < 0.0) v = -v;
        }
        // floor(x + 0.5) inlines where llround is a libm call; ties may round either way
        // (as np.round's half-to-even does differently), which only splits a class in two.
        const long long key[3] = {static_cast<long long>(std::floor(v.x * 1e12 + 0.5)),
                                  static_cast<long long>(std::floor(v.y * 1e12 + 0.5)),
                                  static_cast<long long>(std::floor(v.z * 1e12 + 0.5))};
        std::uint64_t hash = 1469598103934665603ull;
        for (long long k : key) hash = (hash ^ static_cast<std::uint64_t>(k)) * 1099511628211ull;
        size_t slot = static_cast<size_t>(hash ^ (hash >> 29)) & (size - 1);
        bool fresh = true;
        for (;; slot = (slot + 1) & (size - 1)) {
            long long* cell = &table[3 * slot];
            if (cell[0] == LLONG_MIN) {
                cell[0] = key[0], cell[1] = key[1], cell[2] = key[2];
                break;
            }
            if (cell[0] == key[0] && cell[1] == key[1] && cell[2] == key[2]) {
                fresh = false;
                break;
            }
        }
        if (fresh) d[kept++] = v;
    }
    d.resize(kept);
}

// Neighbour lists of `count` vertices from undirected edges, ascending, padded with the
// vertex itself to a multiple of four (the climb's blocks: see climb.hpp).
void adjacency_from_edges(int count, const std::vector<std::pair<int, int>>& edges,
                          std::vector<std::int64_t>& start, ShapePack& out) {
    start.assign(static_cast<size_t>(count) + 1, 0);
    for (const auto& [a, b] : edges) ++start[a + 1], ++start[b + 1];
    for (int i = 0; i < count; ++i) start[i + 1] += start[i];
    std::vector<std::int32_t>& list = out.adjacency;
    // Each list padded to a multiple of four: room for the padding first.
    out.adjacency_counts.resize(static_cast<size_t>(count));
    std::int64_t total = 0;
    for (int i = 0; i < count; ++i) {
        const std::int64_t degree = start[i + 1] - start[i];
        out.adjacency_counts[i] = (degree + 3) / 4 * 4;
        total += out.adjacency_counts[i];
    }
    list.assign(static_cast<size_t>(total), 0);
    std::vector<std::int64_t> fill(static_cast<size_t>(count));
    std::int64_t at = 0;
    for (int i = 0; i < count; ++i) {
        fill[i] = at;
        at += out.adjacency_counts[i];
    }
    for (const auto& [a, b] : edges) list[fill[a]++] = b, list[fill[b]++] = a;
    at = 0;
    for (int i = 0; i < count; ++i) {
        const std::int64_t end = fill[i];
        std::sort(list.begin() + at, list.begin() + end);
        for (std::int64_t k = end; k < at + out.adjacency_counts[i]; ++k) list[k] = i;
        at += out.adjacency_counts[i];
    }
}

void pack_one(const Vec3* points, long long n, Workspace& w, Analysis& analysis,
              ShapePack& out) {
    hull_with(points, n, w, analysis);
    const Hull& hull = analysis.hull;
    const Triangulation& t = analysis.t;
    const Planes& pl = analysis.pl;
    out.status = hull.status;
    if (hull.dimension < 0) {
        // Kept as given: the core reports INVALID_INPUT for every pair that uses it.
        out.vertices.assign(points, points + std::max<long long>(n, 0));
        out.adjacency_counts.assign(out.vertices.size(), 0);
        return;
    }
    const Vec3 zero{0.0, 0.0, 0.0};
    for (int v : hull.vertices) out.vertices.push_back(points[v] + zero);  // -0.0 as 0.0
    const int k = static_cast<int>(hull.vertices.size());
    std::vector<std::pair<int, int>> edges;
    if (hull.dimension == 0) {
        out.adjacency_counts.assign(1, 0);
        return;
    }
    if (hull.dimension == 1) {
        edges.emplace_back(0, 1);
        adjacency_from_edges(2, edges, w.start, out);
        out.edges.push_back(points[hull.vertices[1]] - points[hull.vertices[0]]);
        unique_directions(out.edges, false, w.table);
        return;
    }
    if (hull.dimension == 2) {
        for (int i = 0; i < k; ++i) {
            edges.emplace_back(i, (i + 1) % k);
            out.edges.push_back(points[hull.vertices[(i + 1) % k]] - points[hull.vertices[i]]);
        }
        adjacency_from_edges(k, edges, w.start, out);
        out.faces = {hull.normal, -hull.normal};
        unique_directions(out.edges, false, w.table);
        return;
    }
    // 3-D: every triangulation edge drives hill climbing; edges between different planes
    // are the polytope's true edges (SAT).
    const size_t m = hull.faces.size();
    edges.reserve(3 * m / 2);
    for (size_t i = 0; i < m; ++i)
        for (int e = 0; e < 3; ++e) {
            const int j = t.neighbor[i][e];
            if (j < static_cast<int>(i)) continue;
            const int a = hull.faces[i][e], b = hull.faces[i][(e + 1) % 3];
            edges.emplace_back(a, b);
            if (pl.group[i] != pl.group[j])
                out.edges.push_back(points[hull.vertices[b]] - points[hull.vertices[a]]);
        }
    adjacency_from_edges(k, edges, w.start, out);
    out.faces = hull.plane_normals;
    unique_directions(out.faces, true, w.table);
    unique_directions(out.edges, false, w.table);
}

}  // namespace

Hull exact_hull(const Vec3* points, long long n) {
    Workspace w;
    Analysis analysis;
    hull_with(points, n, w, analysis);
    return std::move(analysis.hull);
}

PackedPolytopes pack_polytopes(const Vec3* points, const std::int64_t* offsets, long long shapes,
                               int threads) {
    std::vector<ShapePack> packs(static_cast<size_t>(std::max<long long>(shapes, 0)));
    const int t = resolve_threads(threads, shapes, defaults::hull_min_shapes_per_thread);
    parallel_for(shapes, t, [&](long long begin, long long end) {
        Workspace w;
        Analysis analysis;
        for (long long h = begin; h < end; ++h)
            pack_one(points + offsets[h], offsets[h + 1] - offsets[h], w, analysis, packs[h]);
    });
    PackedPolytopes out;
    out.status.resize(packs.size());
    out.offsets.assign(1, 0);
    out.face_offsets.assign(1, 0);
    out.edge_offsets.assign(1, 0);
    out.adjacency_offsets.assign(1, 0);
    size_t v = 0, a = 0, f = 0, e = 0;
    for (const ShapePack& s : packs) {
        v += s.vertices.size();
        a += s.adjacency.size();
        f += s.faces.size();
        e += s.edges.size();
    }
    out.vertices.reserve(3 * v);
    out.adjacency.reserve(a);
    out.adjacency_offsets.reserve(v + 1);
    out.face_normals.reserve(3 * f);
    out.edge_directions.reserve(3 * e);
    auto put = [](std::vector<double>& dst, const std::vector<Vec3>& src) {
        for (const Vec3& x : src) dst.insert(dst.end(), {x.x, x.y, x.z});
    };
    for (size_t h = 0; h < packs.size(); ++h) {
        const ShapePack& s = packs[h];
        out.status[h] = s.status;
        put(out.vertices, s.vertices);
        out.offsets.push_back(out.offsets.back() + static_cast<std::int64_t>(s.vertices.size()));
        for (std::int64_t c : s.adjacency_counts)
            out.adjacency_offsets.push_back(out.adjacency_offsets.back() + c);
        out.adjacency.insert(out.adjacency.end(), s.adjacency.begin(), s.adjacency.end());
        put(out.face_normals, s.faces);
        out.face_offsets.push_back(out.face_offsets.back() +
                                   static_cast<std::int64_t>(s.faces.size()));
        put(out.edge_directions, s.edges);
        out.edge_offsets.push_back(out.edge_offsets.back() +
                                   static_cast<std::int64_t>(s.edges.size()));
    }
    return out;
}

}  // namespace meshcol
