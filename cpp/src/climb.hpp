#pragma once
/// Hill climbing on a polytope's edge graph for support points: the shared inner loops of
/// `support_core` (shapes.cpp) and of the Minkowski difference's support (gjk.cpp), inline in
/// both so the climbs' results stay in registers. Private to the core's sources.

#include <cstdint>

#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {
namespace climb {

// Index of the vertex maximising dot(v[i], d), the first one on ties.
inline int scan_support(const Vec3* v, int n, const Vec3& d) {
    int best = 0;
    double best_dot = dot(v[0], d);
    for (int i = 1; i < n; ++i) {
        const double di = dot(v[i], d);
        if (di > best_dot) {
            best_dot = di;
            best = i;
        }
    }
    return best;
}

// `scan_support` of two shapes at once (a in `da`, b in `db`): the two chains of compares
// side by side in one loop, as `climb_pair` runs two climbs. Same answers as two scans.
inline void scan_pair(const Vec3* va, int na, const Vec3& da, const Vec3* vb, int nb,
                      const Vec3& db, int& out_a, int& out_b) {
    int best_a = 0, best_b = 0;
    double top_a = dot(va[0], da), top_b = dot(vb[0], db);
    const int n = na < nb ? na : nb;
    int i = 1;
    for (; i < n; ++i) {
        const double xa = dot(va[i], da), xb = dot(vb[i], db);
        if (xa > top_a) {
            top_a = xa;
            best_a = i;
        }
        if (xb > top_b) {
            top_b = xb;
            best_b = i;
        }
    }
    for (int k = i; k < na; ++k) {
        const double xa = dot(va[k], da);
        if (xa > top_a) {
            top_a = xa;
            best_a = k;
        }
    }
    for (int k = i; k < nb; ++k) {
        const double xb = dot(vb[k], db);
        if (xb > top_b) {
            top_b = xb;
            best_b = k;
        }
    }
    out_a = best_a;
    out_b = best_b;
}

// Forced inlining: as plain functions shared by two callers, GCC stops inlining them and the
// climbs slow down by a tenth.
#if defined(__GNUC__) || defined(__clang__)
#define MESHCOL_CLIMB_INLINE inline __attribute__((always_inline))
#define MESHCOL_CLIMB_PREFETCH(address) __builtin_prefetch(address)
#define MESHCOL_CLIMB_OPAQUE(value) asm("" : "+r"(value))
#else
#define MESHCOL_CLIMB_OPAQUE(value) ((void)0)
#define MESHCOL_CLIMB_INLINE inline
#define MESHCOL_CLIMB_PREFETCH(address) ((void)(address))
#endif

// The climb's start: the hint when valid (a previous support point of this shape, when the
// direction turned little), else the best of a few strided samples, so the climb starts near
// the top and takes few dependent (latency-bound) steps.
MESHCOL_CLIMB_INLINE int climb_start(const ShapeView& s, const Vec3& d, int hint,
                                     double& best_dot) {
    const Vec3* v = s.vertices;
    const int n = s.vertex_count;
    if (hint >= 0 && hint < n) {
        best_dot = dot(v[hint], d);
        return hint;
    }
    int best = 0;
    best_dot = dot(v[0], d);
    const int stride = n >= 8 ? n / 8 : 1;
    for (int i = stride / 2; i < n; i += stride) {
        const double di = dot(v[i], d);
        if (di > best_dot) {
            best_dot = di;
            best = i;
        }
    }
    return best;
}

// The best of the neighbours `list[0 .. count)` of a climb's vertex strictly above `best_dot`
// (first in list order on ties), or -1. Blocks of four (meshcol pads each list with the vertex
// itself to a multiple of four, so the trip count is predictable), then any remainder (lists
// packed by other means). The body is written out twice on purpose: shared through a lambda,
// GCC's code for it ran 2% slower (A/B, 64-vertex penetration). With `kPrefetch`, asks for
// each neighbour's own list (in `s.climb_lists` with `kLists`, `kRows` rows a list, else in
// its CSR arrays) as it is read (`climb_step`).
template <bool kPrefetch, bool kLists, int kRows, class Index>
MESHCOL_CLIMB_INLINE int best_neighbour(const ShapeView& s, const Vec3& d, const Index* list,
                                        int count, double& best_dot) {
    const Vec3* v = s.vertices;
    int next = -1;
    int k = 0;
    for (; k + 3 < count; k += 4) {
        for (int l = 0; l < 4; ++l) {
            std::ptrdiff_t j = list[k + l];
            // An index read from 8 or 16 bits made GCC branch on the compare below instead of
            // selecting (1.4 times the time of a 256-vertex penetration); hidden from it
            // this way, it selects as for 32 bits.
            MESHCOL_CLIMB_OPAQUE(j);
            if constexpr (kPrefetch && kLists) MESHCOL_CLIMB_PREFETCH(s.climb_lists + kRows * j);
            if constexpr (kPrefetch && !kLists)
                MESHCOL_CLIMB_PREFETCH(s.adjacency + s.adjacency_offsets[j]);
            const double dj = dot(v[j], d);
            if (dj > best_dot) {
                best_dot = dj;
                next = static_cast<int>(j);
            }
        }
    }
    for (; k < count; ++k) {
        const int j = list[k];
        const double dj = dot(v[j], d);
        if (dj > best_dot) {
            best_dot = dj;
            next = j;
        }
    }
    return next;
}

// One step of steepest ascent from `best`: the best neighbour strictly above `best_dot`
// (first in list order on ties), or -1 at a local (hence global) maximum. `kLists`: the
// neighbours from the shape's fixed-stride `climb_lists` (non-null), else from its CSR arrays;
// the same lists in the same order, so the same steps. `kPrefetch`: ask for each neighbour's
// own list as it is read: the next step's list is then in the nearest cache whichever
// neighbour wins, and the step waits on one load fewer (at 256 vertices a shape, a fifth of a
// deep pair's time; the same answers). A fixed-stride list's address needs no load, a CSR
// list's needs the neighbour's offset. `kRows`: the rows of a list (shapes.hpp: `climb_rows`,
// 1 for 8-bit lists, 2 for 16-bit ones).
template <bool kPrefetch = true, bool kLists = false, int kRows = 1>
MESHCOL_CLIMB_INLINE int climb_step(const ShapeView& s, const Vec3& d, int best,
                                    double& best_dot) {
    if constexpr (kLists && kRows == 2) {
        const WideClimbList& at = reinterpret_cast<const WideClimbList*>(s.climb_lists)[best];
        return best_neighbour<kPrefetch, true, 2>(s, d, at.neighbours, at.count, best_dot);
    } else if constexpr (kLists) {
        const ClimbList& at = s.climb_lists[best];
        return best_neighbour<kPrefetch, true, 1>(s, d, at.neighbours, at.count, best_dot);
    } else {
        const std::int64_t begin = s.adjacency_offsets[best];
        const std::int64_t end = s.adjacency_offsets[best + 1];
        return best_neighbour<kPrefetch, false, 1>(s, d, s.adjacency + begin,
                                                   static_cast<int>(end - begin), best_dot);
    }
}

// A climb's step from `best` when still going up: `best` moves, or `up` turns false at the
// top.
template <bool kPrefetch = true, bool kLists = false, int kRows = 1>
MESHCOL_CLIMB_INLINE void advance(const ShapeView& s, const Vec3& d, int& best, double& best_dot,
                                  bool& up) {
    const int next = climb_step<kPrefetch, kLists, kRows>(s, d, best, best_dot);
    up = next >= 0;
    best = up ? next : best;
}

// `climb_pair`'s body, with or without the neighbour lists' prefetch, over lists of `kRowsA`
// and `kRowsB` rows (`climb_rows`).
template <bool kPrefetch, int kRowsA, int kRowsB>
MESHCOL_CLIMB_INLINE void climb_pair_with(const ShapeView& a, const Vec3& da, int hint_a,
                                          const ShapeView& b, const Vec3& db, int hint_b,
                                          SupportPoint& out_a, SupportPoint& out_b) {
    // Both climbs advance in one loop: each step is a chain of dependent loads and compares,
    // and two independent chains side by side keep the core busy while either waits.
    double dot_a, dot_b;
    int best_a = climb_start(a, da, hint_a, dot_a);
    int best_b = climb_start(b, db, hint_b, dot_b);
    // Side by side while both go up, then the one still climbing alone. Capped at a
    // shape's vertex count (every step goes up, so never reached).
    bool up_a = true, up_b = true;
    int steps_a = 0, steps_b = 0;
    while (up_a && up_b && steps_a < a.vertex_count) {
        advance<kPrefetch, true, kRowsA>(a, da, best_a, dot_a, up_a);
        advance<kPrefetch, true, kRowsB>(b, db, best_b, dot_b, up_b);
        ++steps_a;
        ++steps_b;
    }
    for (; up_a && steps_a < a.vertex_count; ++steps_a)
        advance<kPrefetch, true, kRowsA>(a, da, best_a, dot_a, up_a);
    for (; up_b && steps_b < b.vertex_count; ++steps_b)
        advance<kPrefetch, true, kRowsB>(b, db, best_b, dot_b, up_b);
    // A capped climb (never seen: the edge graph is finite and every step goes up) falls
    // back to the scan.
    if (up_a) best_a = scan_support(a.vertices, a.vertex_count, da);
    if (up_b) best_b = scan_support(b.vertices, b.vertex_count, db);
    out_a = {a.vertices[best_a], best_a};
    out_b = {b.vertices[best_b], best_b};
}

/// `support_core` of two climbing shapes with fixed-stride lists at once (`climbs` true and
/// `climb_lists` set for both): a in `da` from `hint_a`, b in `db` from `hint_b` (negative:
/// no hint). Same answers as two calls, faster. The neighbour lists are prefetched only when a
/// shape has at least `defaults::climb_prefetch_min_vertices` vertices: a smaller one's lists
/// are already near (`prefetch` asked for the whole shape), and the prefetch would cost two
/// instructions a neighbour for nothing. A shape of more than `kNarrowClimbVertices` vertices
/// reads 16-bit lists of two rows (always with the prefetch: it has enough vertices).
MESHCOL_CLIMB_INLINE void climb_pair(const ShapeView& a, const Vec3& da, int hint_a,
                                     const ShapeView& b, const Vec3& db, int hint_b,
                                     SupportPoint& out_a, SupportPoint& out_b) {
    static_assert(defaults::climb_prefetch_min_vertices <= kNarrowClimbVertices,
                  "shapes without the prefetch keep 8-bit lists");
    const bool wide_a = climb_rows(a.vertex_count) == 2;
    const bool wide_b = climb_rows(b.vertex_count) == 2;
    if (wide_a && wide_b)
        climb_pair_with<true, 2, 2>(a, da, hint_a, b, db, hint_b, out_a, out_b);
    else if (wide_a)
        climb_pair_with<true, 2, 1>(a, da, hint_a, b, db, hint_b, out_a, out_b);
    else if (wide_b)
        climb_pair_with<true, 1, 2>(a, da, hint_a, b, db, hint_b, out_a, out_b);
    else if (a.vertex_count >= defaults::climb_prefetch_min_vertices ||
             b.vertex_count >= defaults::climb_prefetch_min_vertices)
        climb_pair_with<true, 1, 1>(a, da, hint_a, b, db, hint_b, out_a, out_b);
    else
        climb_pair_with<false, 1, 1>(a, da, hint_a, b, db, hint_b, out_a, out_b);
}

}  // namespace climb
}  // namespace meshcol
