// The tests' reference Quickhull (quickhull_reference.hpp): the core's construction before
// quickhull_flat, unchanged but for its place.
#include "quickhull_reference.hpp"

#include <algorithm>
#include <vector>

#include "hull_orientation.hpp"

namespace meshcol::hull_reference {

using hull_detail::Build;
using hull_detail::face_plane;
using hull_detail::HorizonEdge;
using hull_detail::orientation;
using hull_detail::plane_side;
using hull_detail::Frame;
using hull_detail::Plane;
using hull_detail::start_tetrahedron;
using hull_detail::Triangulation;
using hull_detail::TriangulationEdge;

namespace {

double distance(const Face& f, const Vec3& x) { return dot(f.plane.normal, x) - f.plane.offset; }


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

}  // namespace

Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out) {
    return quickhull_points(w, subset, out);
}

}  // namespace meshcol::hull_reference
