// Quickhull on flat storage: the steps of quickhull.cpp's construction (the same starting
// tetrahedron, the same apex of the same face at every step, the same horizon walk, face
// slots and conflict assignments), so the same triangulation bit for bit, with less work a
// step. The faces are plain records in one array sized once per call; a face's conflict
// list is a chain of point indices through one per-point link array (appended in the same
// order as the list was), so a cone moves no point copies and keeps no per-face vectors.
//
// Quickhull: Barber, Dobkin and Huhdanpaa 1996; the horizon as one depth-first walk,
// Gregorius 2014, "Implementing Quickhull".
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hull_detail.hpp"
#include "hull_orientation.hpp"

namespace meshcol::hull_detail {
namespace {

constexpr int kNext[3] = {1, 2, 0};  // the edge after edge e of a face

// The step's state: raw pointers into the workspace's arrays, sized once per call.
struct Flat {
    const Vec3* p;
    double eps;
    FlatFace* faces;
    size_t face_count = 0;
    int* next;  // per point: the next point of its chain
    int* pending;  // the faces to visit, a stack: pending[0 .. top)
    size_t top = 0;
    std::vector<int>* free_faces;
    size_t free_top = 0;
    size_t points = 0;  // in the subset
};

inline double distance(const FlatFace& f, const Vec3& x) {
    return f.nx * x.x + f.ny * x.y + f.nz * x.z - f.offset;
}

inline void set_plane(FlatFace& f, const Vec3* p) {
    const Plane plane = face_plane(p[f.v[0]], p[f.v[1]], p[f.v[2]]);
    f.nx = plane.normal.x, f.ny = plane.normal.y, f.nz = plane.normal.z;
    f.offset = plane.offset;
    f.filter = plane.filter;
    f.area2 = plane.area2;
}

// A new face of corners a b c, without points and not yet visited; its plane is set apart
// (set_plane, set_planes_two).
inline void start_face(FlatFace& f, int a, int b, int c) {
    f.v[0] = a, f.v[1] = b, f.v[2] = c;
    f.head = f.tail = f.furthest = -1;
    f.furthest_distance = 0.0;
    f.visit = 0;
    f.visible = false;
    f.alive = true;
}

inline void init_face(Flat& s, int id, int a, int b, int c) {
    FlatFace& f = s.faces[id];
    start_face(f, a, b, c);
    set_plane(f, s.p);
}

// set_plane of two faces at once, face_plane's fast case in the two SSE2 lanes: a lane's
// IEEE operations are the scalar ones, in the same order, so the planes are the same bits; a
// face whose first corner is sharp takes set_plane (face_plane_at_widest). A cone's faces
// are independent: in lanes, their square roots and divisions overlap instead of queueing
// one face after the other (about a sixth of Quickhull's time was that chain).
#if defined(__SSE2__)
void set_planes_two(FlatFace& f, FlatFace& g, const Vec3* p) {
    const Vec3 &a0 = p[f.v[0]], &b0 = p[f.v[1]], &c0 = p[f.v[2]];
    const Vec3 &a1 = p[g.v[0]], &b1 = p[g.v[1]], &c1 = p[g.v[2]];
    const __m128d ax = _mm_set_pd(a1.x, a0.x), ay = _mm_set_pd(a1.y, a0.y),
                  az = _mm_set_pd(a1.z, a0.z);
    const __m128d ux = _mm_sub_pd(_mm_set_pd(b1.x, b0.x), ax),
                  uy = _mm_sub_pd(_mm_set_pd(b1.y, b0.y), ay),
                  uz = _mm_sub_pd(_mm_set_pd(b1.z, b0.z), az);
    const __m128d vx = _mm_sub_pd(_mm_set_pd(c1.x, c0.x), ax),
                  vy = _mm_sub_pd(_mm_set_pd(c1.y, c0.y), ay),
                  vz = _mm_sub_pd(_mm_set_pd(c1.z, c0.z), az);
    const __m128d nx = _mm_sub_pd(_mm_mul_pd(uy, vz), _mm_mul_pd(uz, vy));
    const __m128d ny = _mm_sub_pd(_mm_mul_pd(uz, vx), _mm_mul_pd(ux, vz));
    const __m128d nz = _mm_sub_pd(_mm_mul_pd(ux, vy), _mm_mul_pd(uy, vx));
    const __m128d nn =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx, nx), _mm_mul_pd(ny, ny)), _mm_mul_pd(nz, nz));
    const __m128d uu =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(ux, ux), _mm_mul_pd(uy, uy)), _mm_mul_pd(uz, uz));
    const __m128d vv =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(vx, vx), _mm_mul_pd(vy, vy)), _mm_mul_pd(vz, vz));
    // face_plane's test of the first corner, lane by lane (false for a NaN, as there).
    const int fast = _mm_movemask_pd(
        _mm_cmpge_pd(_mm_mul_pd(_mm_set1_pd(kSharpCorner), nn), _mm_mul_pd(uu, vv)));
    if (fast != 3) {
        if (!(fast & 1)) set_plane(f, p);
        if (!(fast & 2)) set_plane(g, p);
        if (fast == 0) return;
    }
    const __m128d len = _mm_sqrt_pd(nn);
    const __m128d positive = _mm_cmpgt_pd(len, _mm_setzero_pd());  // else a zero normal
    const __m128d mx = _mm_and_pd(positive, _mm_div_pd(nx, len));
    const __m128d my = _mm_and_pd(positive, _mm_div_pd(ny, len));
    const __m128d mz = _mm_and_pd(positive, _mm_div_pd(nz, len));
    const __m128d offset =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(mx, ax), _mm_mul_pd(my, ay)), _mm_mul_pd(mz, az));
    const __m128d bounded = _mm_cmpge_pd(len, _mm_set1_pd(kPlaneFilterMinLength));
    const __m128d filter = _mm_or_pd(_mm_and_pd(bounded, _mm_set1_pd(kPlaneFilter)),
                                     _mm_andnot_pd(bounded, _mm_set1_pd(INFINITY)));
    if (fast & 1) {
        _mm_storel_pd(&f.nx, mx), _mm_storel_pd(&f.ny, my), _mm_storel_pd(&f.nz, mz);
        _mm_storel_pd(&f.offset, offset), _mm_storel_pd(&f.filter, filter);
        _mm_storel_pd(&f.area2, len);
    }
    if (fast & 2) {
        _mm_storeh_pd(&g.nx, mx), _mm_storeh_pd(&g.ny, my), _mm_storeh_pd(&g.nz, mz);
        _mm_storeh_pd(&g.offset, offset), _mm_storeh_pd(&g.filter, filter);
        _mm_storeh_pd(&g.area2, len);
    }
}
#else
void set_planes_two(FlatFace& f, FlatFace& g, const Vec3* p) {
    set_plane(f, p);
    set_plane(g, p);
}
#endif

// Appends point x, at distance d, to f's chain (quickhull.cpp's add_conflict).
inline void add_conflict(Flat& s, FlatFace& f, int x, double d) {
    if (f.head < 0)
        f.head = x;
    else
        s.next[f.tail] = x;
    f.tail = x;
    s.next[x] = -1;
    if (d > f.furthest_distance) {
        f.furthest_distance = d;
        f.furthest = x;
    }
}

// quickhull.cpp's reassign_furthest: q leaves the seed's chain (it is not outside the seed
// exactly), the seed's furthest point is found again, and q joins the first live face, in
// slot order, that it is outside of, or is dropped.
void reassign_furthest(Flat& s, int seed, int q) {
    FlatFace& f = s.faces[seed];
    int previous = -1;
    for (int x = f.head; x >= 0; previous = x, x = s.next[x]) {
        if (x != q) continue;
        if (previous < 0)
            f.head = s.next[x];
        else
            s.next[previous] = s.next[x];
        if (f.tail == x) f.tail = previous;
        break;
    }
    f.furthest = -1;
    f.furthest_distance = 0.0;
    for (int x = f.head; x >= 0; x = s.next[x]) {
        const double d = distance(f, s.p[x]);
        if (d > f.furthest_distance || f.furthest < 0) {
            f.furthest_distance = d;
            f.furthest = x;
        }
    }
    for (size_t g = 0; g < s.face_count; ++g) {
        FlatFace& h = s.faces[g];
        if (!h.alive || static_cast<int>(g) == seed) continue;
        const double d = distance(h, s.p[q]);
        if (d > s.eps && orientation(s.p[h.v[0]], s.p[h.v[1]], s.p[h.v[2]], s.p[q]) > 0) {
            add_conflict(s, h, q, d);
            s.pending[s.top++] = static_cast<int>(g);
            return;
        }
    }
}

__attribute__((noinline)) int exact_side(const Vec3* p, const FlatFace& g, const Vec3& x) {
    return orientation(p[g.v[0]], p[g.v[1]], p[g.v[2]], x);
}

// quickhull.cpp's find_horizon on flat faces: the visible faces into w.visible and the
// horizon loop into w.edges, in the same order.
bool find_horizon(Flat& s, Workspace& w, int seed, int q, unsigned stamp) {
    const size_t room = s.face_count + 1;
    if (w.dfs.size() < room) w.dfs.resize(2 * room);
    if (w.visible.size() < room) w.visible.resize(2 * room);
    if (w.edges.size() < 3 * room) w.edges.resize(6 * room);
    FlatFace* faces = s.faces;
    Frame* stack = w.dfs.data();
    int* visible = w.visible.data();
    HorizonEdge* edges = w.edges.data();
    const Vec3 x = s.p[q];
    size_t nv = 0, ne = 0;
    faces[seed].visit = stamp;
    faces[seed].visible = true;
    visible[nv++] = seed;
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
        const FlatFace& f = faces[fi];
        const int gi = f.n[e];
        FlatFace& g = faces[gi];
        if (g.visit != stamp) {
            g.visit = stamp;
            const double d = distance(g, x);
            g.visible = d > g.filter || (!(d < -g.filter) && exact_side(s.p, g, x) > 0);
            if (g.visible) {
                visible[nv++] = gi;
                const int back = f.s[e];
                stack[top++] = {fi, next, left};
                fi = gi, next = kNext[back], left = 2;
                continue;
            }
        } else if (g.visible) {
            continue;
        }
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
    // One simple loop: each edge ends where the next begins (the last where the first does),
    // and no vertex begins two edges. Checked without a branch an edge (a broken loop is rare).
    int* mark = w.mark.data();
    const int current = static_cast<int>(stamp);
    int broken = edges[h - 1].b ^ edges[0].a;
    int a = edges[0].a;
    for (size_t k = 1; k < h; ++k) {
        const int next = edges[k].a;
        broken |= (edges[k - 1].b ^ next) | (mark[a] == current);
        mark[a] = current;
        a = next;
    }
    broken |= mark[a] == current;
    mark[a] = current;
    return broken == 0;
}

// quickhull.cpp's cone: the visible faces die (their slots to the free list), the horizon is
// coned to q in slots taken from that list, and the visible faces' points, chain after chain,
// go to the first new face they are outside of, else to a horizon face, else nowhere.
void cone(Flat& s, Workspace& w, int q) {
    const size_t visible = w.visible_count;
    // Room on the stack for a face per point moved and per new face.
    const size_t pushes = s.top + w.edge_count + s.points;
    if (w.pending.size() < pushes) {
        w.pending.resize(2 * pushes);
        s.pending = w.pending.data();
    }
    std::vector<int>& free_list = *s.free_faces;
    if (free_list.size() < s.free_top + visible + 1) free_list.resize(2 * (s.free_top + visible + 1));
    // The visible faces' chains joined into one, in their order (each tail linked to the next
    // head), walked below as one loop: a loop a chain mispredicted its exit at every chain.
    int orphans = -1, last = -1;
    for (size_t v = 0; v < visible; ++v) {
        const int fi = w.visible[v];
        FlatFace& f = s.faces[fi];
        if (f.head >= 0) {
            (last >= 0 ? s.next[last] : orphans) = f.head;
            last = f.tail;
        }
        f.alive = false;
        free_list[s.free_top++] = fi;
    }
    const size_t h = w.edge_count;
    if (s.face_count + h > w.flat_faces.size()) {  // never below 3 n + 8 slots, in practice
        w.flat_faces.resize(2 * (s.face_count + h));
        s.faces = w.flat_faces.data();
    }
    if (w.new_faces.size() < h) w.new_faces.resize(2 * h);
    int* ids = w.new_faces.data();
    // Slots: the free list from its end, then fresh ones (quickhull.cpp's allocate_faces).
    {
        const size_t reused = std::min(s.free_top, h);
        for (size_t k = 0; k < reused; ++k) ids[k] = free_list[s.free_top - 1 - k];
        int fresh = static_cast<int>(s.face_count);
        for (size_t k = reused; k < h; ++k) ids[k] = fresh++;
        s.free_top -= reused;
        s.face_count = static_cast<size_t>(fresh);
    }
    const HorizonEdge* __restrict edges = w.edges.data();
    FlatFace* __restrict faces = s.faces;
    int previous = ids[h - 1];
    for (size_t k = 0; k < h; ++k) {
        const HorizonEdge he = edges[k];
        const int id = ids[k];
        const int following = ids[k + 1 < h ? k + 1 : 0];
        FlatFace& f = faces[id];
        start_face(f, he.a, he.b, q);
        f.n[0] = he.outside, f.n[1] = following, f.n[2] = previous;
        f.s[0] = he.slot, f.s[1] = 2, f.s[2] = 1;
        faces[he.outside].n[he.slot] = id;
        faces[he.outside].s[he.slot] = 0;
        // The planes of each pair of new faces as its second one is made (in this loop: a
        // loop of their own would add an exit that mispredicts as the horizon's length varies).
        if (k & 1) set_planes_two(faces[previous], f, s.p);
        previous = id;
    }
    if (h & 1) set_plane(faces[ids[h - 1]], s.p);
    const double eps = s.eps;
    int* __restrict next = s.next;
    const Vec3* __restrict p = s.p;
    int* __restrict pending = s.pending;
    size_t top = s.top;
    // The new faces that get points, as bits (a cone of at most 64 faces: nearly all), pushed
    // below in cone order by their bits instead of a test of every new face.
    const bool few = h <= 64;
    std::uint64_t got = 0;
    for (int x = orphans, after; x >= 0; x = after) {
        after = next[x];  // read before x joins another chain
        if (x == q) continue;
        const Vec3 px = p[x];
        size_t k = 0;
        double d = 0.0;
        for (; k < h; ++k) {
            const FlatFace& e = faces[ids[k]];
            d = (e.nx * px.x + e.ny * px.y + e.nz * px.z) - e.offset;
            if (d > eps) break;
        }
        if (k < h) {
            add_conflict(s, faces[ids[k]], x, d);
            got |= std::uint64_t{1} << (k & 63);
            continue;
        }
        for (size_t k2 = 0; k2 < h; ++k2) {
            FlatFace& outside = faces[edges[k2].outside];
            const double dx = distance(outside, px);
            if (dx > eps) {
                add_conflict(s, outside, x, dx);
                pending[top++] = edges[k2].outside;
                break;
            }
        }
    }
    if (few) {
        for (; got != 0; got &= got - 1) pending[top++] = ids[__builtin_ctzll(got)];
    } else {
        for (size_t k = 0; k < h; ++k)
            if (faces[ids[k]].head >= 0) pending[top++] = ids[k];
    }
    s.top = top;
}

}  // namespace

Build quickhull_flat(Workspace& w, const std::vector<int>& subset, Triangulation& out,
                     const int* start) {
    const std::vector<Vec3>& points = w.p;
    if (subset.size() < 4) return Build::DEGENERATE;
    int corner[4];
    if (start != nullptr) {
        std::copy(start, start + 4, corner);
    } else {
        const Build started = start_tetrahedron(points, w.eps, subset, corner);
        if (started != Build::OK) return started;
    }
    // Room for every slot Quickhull can hold: the live faces (at most 2 n - 4) and a cone (at
    // most n faces) at once; grown on the way if ever short.
    const size_t room = 3 * subset.size() + 8;
    if (w.flat_faces.size() < room) w.flat_faces.resize(room);
    if (w.next_point.size() < points.size()) w.next_point.resize(points.size());
    if (w.free_faces.size() < 16) w.free_faces.resize(16);
    Flat s;
    s.p = points.data();
    s.eps = w.eps;
    s.faces = w.flat_faces.data();
    s.next = w.next_point.data();
    s.points = subset.size();
    if (w.pending.size() < 2 * s.points + 8) w.pending.resize(2 * s.points + 8);
    s.pending = w.pending.data();
    s.free_faces = &w.free_faces;
    const int a = corner[0], b = corner[1], c = corner[2], d = corner[3];
    const int tetra[4][3] = {{a, b, c}, {a, d, b}, {b, d, c}, {c, d, a}};
    for (int i = 0; i < 4; ++i) init_face(s, i, tetra[i][0], tetra[i][1], tetra[i][2]);
    s.face_count = 4;
    // The tetrahedron's neighbours (quickhull.cpp's link_faces).
    for (int i = 0; i < 4; ++i)
        for (int e = 0; e < 3; ++e) {
            FlatFace& f = s.faces[i];
            const int from = f.v[e], to = f.v[kNext[e]];
            for (int j = 0; j < 4; ++j) {
                if (j == i) continue;
                const FlatFace& g = s.faces[j];
                for (int k = 0; k < 3; ++k)
                    if (g.v[k] == to && g.v[kNext[k]] == from) f.n[e] = j, f.s[e] = k;
            }
        }
    for (int i : subset) {
        if (i == a || i == b || i == c || i == d) continue;
        const Vec3& x = s.p[i];
        for (int f = 0; f < 4; ++f) {
            const double dist = distance(s.faces[f], x);
            if (dist > s.eps) {
                add_conflict(s, s.faces[f], i, dist);
                break;
            }
        }
    }
    for (int f = 0; f < 4; ++f)
        if (s.faces[f].head >= 0) s.pending[s.top++] = f;

    const long long cap = static_cast<long long>(subset.size()) + 16;
    for (long long step = 0; s.top > 0; ++step) {
        if (step > 4 * cap) return Build::FAILED;
        const int seed = s.pending[s.top - 1];
        FlatFace& f = s.faces[seed];
        if (!f.alive || f.head < 0) {
            --s.top;
            continue;
        }
        const int q = f.furthest;
        if (plane_side(Vec3{f.nx, f.ny, f.nz}, f.offset, f.filter, s.p[f.v[0]], s.p[f.v[1]],
                       s.p[f.v[2]], s.p[q]) <= 0) {
            if (w.pending.size() < s.top + 1) {
                w.pending.resize(2 * (s.top + 1));
                s.pending = w.pending.data();
            }
            reassign_furthest(s, seed, q);
            continue;
        }
        if (!find_horizon(s, w, seed, q, ++w.stamp)) return Build::FAILED;
        cone(s, w, q);
    }
    // The compact triangulation, as quickhull.cpp writes it.
    const auto slots = static_cast<unsigned>(s.face_count);
    std::vector<int>& index = w.id;
    index.assign(s.face_count, -1);
    int m = 0;
    const FlatFace* faces = s.faces;
    for (size_t i = 0; i < s.face_count; ++i)
        if (faces[i].alive) index[i] = m++;
    out.tri.resize(m);
    out.normal.resize(m);
    out.offset.resize(m);
    out.area2.resize(m);
    // The edges into scratch that only grows, then copied: out.edges shrinks to the count,
    // and growing it again for the next hull would zero what is about to be written.
    if (w.edge_scratch.size() < 3 * static_cast<size_t>(m)) w.edge_scratch.resize(3 * static_cast<size_t>(m));
    TriangulationEdge* edges = w.edge_scratch.data();
    // The arrays through raw pointers (the stores below would otherwise reload each vector's).
    std::array<int, 3>* tri = out.tri.data();
    Vec3* normal = out.normal.data();
    double* offset = out.offset.data();
    double* area2 = out.area2.data();
    const int* slot_index = index.data();
    size_t count = 0;
    int t = 0;  // the triangle of the next live face
    for (size_t i = 0; i < s.face_count; ++i) {
        const FlatFace& f = faces[i];
        if (!f.alive) continue;
        tri[t] = {f.v[0], f.v[1], f.v[2]};
        normal[t] = Vec3{f.nx, f.ny, f.nz};
        offset[t] = f.offset;
        area2[t] = f.area2;
        for (int e = 0; e < 3; ++e) {
            const int g = f.n[e];
            if (static_cast<unsigned>(g) >= slots || slot_index[g] < 0) return Build::FAILED;
            const int j = slot_index[g];
            TriangulationEdge& edge = edges[count];
            edge.i = t, edge.e = e, edge.j = j, edge.k = f.s[e];
            count += j > t;
        }
        ++t;
    }
    out.edges.assign(edges, edges + count);
    return Build::OK;
}

}  // namespace meshcol::hull_detail
