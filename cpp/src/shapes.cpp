#include "meshcol/shapes.hpp"

#include <cmath>

#include "meshcol/defaults.hpp"

namespace meshcol {

namespace {

// Index of the vertex maximising dot(v[i], d), the first one on ties.
int scan_support(const Vec3* v, int n, const Vec3& d) {
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

// Forced inlining: as plain functions shared by two callers, GCC stops inlining them and the
// climbs slow down by a tenth.
#if defined(__GNUC__) || defined(__clang__)
#define MESHCOL_CLIMB_INLINE inline __attribute__((always_inline))
#else
#define MESHCOL_CLIMB_INLINE inline
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
    const int stride = n / 8;
    for (int i = stride / 2; i < n; i += stride) {
        const double di = dot(v[i], d);
        if (di > best_dot) {
            best_dot = di;
            best = i;
        }
    }
    return best;
}

// One step of steepest ascent from `best`: the best neighbour strictly above `best_dot`
// (first in list order on ties), or -1 at a local (hence global) maximum.
MESHCOL_CLIMB_INLINE int climb_step(const ShapeView& s, const Vec3& d, int best,
                                    double& best_dot) {
    const Vec3* v = s.vertices;
    int next = -1;
    const std::int64_t begin = s.adjacency_offsets[best];
    const std::int64_t end = s.adjacency_offsets[best + 1];
    // Blocks of four (meshcol pads each list with the vertex itself to a multiple of four),
    // then any remainder (lists packed by other means).
    std::int64_t k = begin;
    for (; k + 3 < end; k += 4) {
        for (int l = 0; l < 4; ++l) {
            const int j = s.adjacency[k + l];
            const double dj = dot(v[j], d);
            if (dj > best_dot) {
                best_dot = dj;
                next = j;
            }
        }
    }
    for (; k < end; ++k) {
        const int j = s.adjacency[k];
        const double dj = dot(v[j], d);
        if (dj > best_dot) {
            best_dot = dj;
            next = j;
        }
    }
    return next;
}

SupportPoint polytope_support(const ShapeView& s, const Vec3& d, int hint) {
    const Vec3* v = s.vertices;
    const int n = s.vertex_count;
    if (s.adjacency_offsets != nullptr && n > defaults::hill_climbing_min_vertices) {
        // Hill climbing on the hull's edge graph: a local maximum of a linear function over the
        // 1-skeleton of a convex polytope is global (Ericson 2004, sec. 9.5.4). Capped: on a
        // cap hit we fall back to the scan below.
        double best_dot;
        int best = climb_start(s, d, hint, best_dot);
        for (int step = 0; step < n; ++step) {
            const int next = climb_step(s, d, best, best_dot);
            if (next < 0) return {v[best], best};
            best = next;
        }
    }
    const int best = scan_support(v, n, d);
    return {v[best], best};
}

}  // namespace

bool climbs(const ShapeView& s) {
    return s.kind == ShapeKind::POLYTOPE && s.adjacency_offsets != nullptr &&
           s.vertex_count > defaults::hill_climbing_min_vertices;
}

void climb_pair(const ShapeView& a, const Vec3& da, int hint_a, const ShapeView& b,
                const Vec3& db, int hint_b, SupportPoint& out_a, SupportPoint& out_b) {
    // Both climbs advance in one loop: each step is a chain of dependent loads and compares,
    // and two independent chains side by side keep the core busy while either waits.
    double dot_a, dot_b;
    int best_a = climb_start(a, da, hint_a, dot_a);
    int best_b = climb_start(b, db, hint_b, dot_b);
    // Both take a step every round (one that has arrived repeats its last, finding nothing
    // better): the only data-dependent branch is the end of the loop.
    bool up_a = true, up_b = true;
    const int cap = a.vertex_count + b.vertex_count;
    for (int step = 0; step < cap && (up_a || up_b); ++step) {
        const int next_a = climb_step(a, da, best_a, dot_a);
        const int next_b = climb_step(b, db, best_b, dot_b);
        up_a = next_a >= 0;
        up_b = next_b >= 0;
        best_a = up_a ? next_a : best_a;
        best_b = up_b ? next_b : best_b;
    }
    // A capped climb (never seen: the edge graph is finite and every step goes up) falls
    // back to the scan.
    if (up_a) best_a = scan_support(a.vertices, a.vertex_count, da);
    if (up_b) best_b = scan_support(b.vertices, b.vertex_count, db);
    out_a = {a.vertices[best_a], best_a};
    out_b = {b.vertices[best_b], best_b};
}

SupportPoint support_core(const ShapeView& s, const Vec3& d, int hint) {
    switch (s.kind) {
        case ShapeKind::POLYTOPE:
            return polytope_support(s, d, hint);
        case ShapeKind::SPHERE:
            return {Vec3{0.0, 0.0, 0.0}, 0};
        case ShapeKind::BOX: {
            // Ties (d component == 0) pick the + side: a fixed choice keeps the corner code
            // stable so GJK recognises a repeated support point exactly.
            const Vec3 p{d.x >= 0.0 ? s.params[0] : -s.params[0],
                         d.y >= 0.0 ? s.params[1] : -s.params[1],
                         d.z >= 0.0 ? s.params[2] : -s.params[2]};
            return {p, (d.x >= 0.0 ? 1 : 0) | (d.y >= 0.0 ? 2 : 0) | (d.z >= 0.0 ? 4 : 0)};
        }
        case ShapeKind::CAPSULE:
            return d.z >= 0.0 ? SupportPoint{Vec3{0.0, 0.0, s.params[1]}, 1}
                              : SupportPoint{Vec3{0.0, 0.0, -s.params[1]}, 0};
        case ShapeKind::CYLINDER: {
            const double r = s.params[0], h = s.params[1];
            const double z = d.z >= 0.0 ? h : -h;
            const double planar = std::sqrt(d.x * d.x + d.y * d.y);
            if (planar <= 1e-300) return {Vec3{0.0, 0.0, z}, -1};
            return {Vec3{r * d.x / planar, r * d.y / planar, z}, -1};
        }
    }
    return {Vec3{}, -1};
}

Vec3 support(const ShapeView& s, const Vec3& d) {
    Vec3 p = support_core(s, d).point;
    const double m = margin(s);
    if (m > 0.0) {
        const double n = norm(d);
        if (n > 0.0) p += d * (m / n);
    }
    return p;
}

void local_aabb(const ShapeView& s, Vec3& lo, Vec3& hi) {
    const double m = margin(s);
    switch (s.kind) {
        case ShapeKind::POLYTOPE:
            lo = hi = s.vertices[0];
            for (int i = 1; i < s.vertex_count; ++i) {
                lo = component_min(lo, s.vertices[i]);
                hi = component_max(hi, s.vertices[i]);
            }
            return;
        case ShapeKind::SPHERE:
            hi = {m, m, m};
            break;
        case ShapeKind::BOX:
            hi = {s.params[0], s.params[1], s.params[2]};
            break;
        case ShapeKind::CAPSULE:
            hi = {m, m, s.params[1] + m};
            break;
        case ShapeKind::CYLINDER:
            hi = {s.params[0], s.params[0], s.params[1]};
            break;
    }
    lo = -hi;
}

void world_aabb(const ShapeView& s, const Pose& pose, Vec3& lo, Vec3& hi) {
    if (s.kind == ShapeKind::POLYTOPE) {
        lo = hi = pose.apply(s.vertices[0]);
        for (int i = 1; i < s.vertex_count; ++i) {
            const Vec3 p = pose.apply(s.vertices[i]);
            lo = component_min(lo, p);
            hi = component_max(hi, p);
        }
        return;
    }
    // Exact extents: the support in +-world axis e_k is pose.apply(support(R^T e_k)).
    for (int k = 0; k < 3; ++k) {
        const Vec3 axis = pose.rotation.row(k);  // R^T e_k
        hi[k] = dot(axis, support(s, axis)) + pose.translation[k];
        lo[k] = dot(axis, support(s, -axis)) + pose.translation[k];
    }
}

double bounding_radius(const ShapeView& s) {
    switch (s.kind) {
        case ShapeKind::POLYTOPE: {
            double r2 = 0.0;
            for (int i = 0; i < s.vertex_count; ++i) r2 = std::fmax(r2, squared_norm(s.vertices[i]));
            return std::sqrt(r2);
        }
        case ShapeKind::SPHERE:
            return s.params[0];
        case ShapeKind::BOX:
            return norm(Vec3{s.params[0], s.params[1], s.params[2]});
        case ShapeKind::CAPSULE:
            return s.params[0] + s.params[1];
        case ShapeKind::CYLINDER:
            return std::hypot(s.params[0], s.params[1]);
    }
    return 0.0;
}

bool is_valid(const ShapeView& s) {
    for (double p : s.params)
        if (!std::isfinite(p)) return false;
    switch (s.kind) {
        case ShapeKind::POLYTOPE:
            if (s.vertex_count <= 0 || s.vertices == nullptr) return false;
            for (int i = 0; i < s.vertex_count; ++i)
                if (!is_finite(s.vertices[i])) return false;
            return true;
        case ShapeKind::SPHERE:
            return s.params[0] >= 0.0;
        case ShapeKind::BOX:
            return s.params[0] >= 0.0 && s.params[1] >= 0.0 && s.params[2] >= 0.0;
        case ShapeKind::CAPSULE:
        case ShapeKind::CYLINDER:
            return s.params[0] >= 0.0 && s.params[1] >= 0.0;
    }
    return false;
}

}  // namespace meshcol
