#include "meshcol/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <new>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/defaults.hpp"
#include "climb.hpp"

namespace meshcol {

namespace {

SupportPoint polytope_support(const ShapeView& s, const Vec3& d, int hint) {
    const Vec3* v = s.vertices;
    const int n = s.vertex_count;
    if (climbs(s)) {
        // Hill climbing on the hull's edge graph: a local maximum of a linear function over the
        // 1-skeleton of a convex polytope is global (Ericson 2004, sec. 9.5.4). Capped: on a
        // cap hit we fall back to the scan below.
        double best_dot;
        int best = climb::climb_start(s, d, hint, best_dot);
        bool up = true;
        if (s.climb_lists != nullptr && climb_rows(n) == 1)
            for (int step = 0; up && step < n; ++step)
                climb::advance<true, true, 1>(s, d, best, best_dot, up);
        else if (s.climb_lists != nullptr)
            for (int step = 0; up && step < n; ++step)
                climb::advance<true, true, 2>(s, d, best, best_dot, up);
        else
            for (int step = 0; up && step < n; ++step)
                climb::advance<true, false>(s, d, best, best_dot, up);
        if (!up) return {v[best], best};
    }
    const int best = climb::scan_support(v, n, d);
    return {v[best], best};
}

// Support point of the ellipsoid sum_i (x_i / a_i)^2 <= 1 in direction d: the image under
// x = A u (A = diag(a)) of the unit ball's support along A d, x_i = a_i^2 d_i / |A d| (the
// point whose normal, x_i / a_i^2, is parallel to d). Each coordinate is formed as
// a_i (a_i d_i / |A d|), a semi-axis times a number in [-1, 1], so it cannot overflow; when
// |A d|^2 leaves the range where squares are safe, d and then A d are scaled by their
// largest component first (the point does not depend on the length of d). A zero A d (a zero
// direction, or one along a zero semi-axis, where every point of the set is a support)
// gives the centre.
Vec3 ellipsoid_support(const double* a, const Vec3& d) {
    Vec3 u{a[0] * d.x, a[1] * d.y, a[2] * d.z};
    double n2 = squared_norm(u);
    if (!(n2 >= 0x1p-1000 && n2 <= 0x1p1000)) {
        const double largest = max_abs(d);
        if (!(largest > 0.0) || !std::isfinite(largest)) return Vec3{};
        const Vec3 e = d * (1.0 / largest);  // the largest component +-1
        u = Vec3{a[0] * e.x, a[1] * e.y, a[2] * e.z};
        const double most = max_abs(u);
        if (!(most > 0.0)) return Vec3{};
        u = u * (1.0 / most);  // the largest component +-1: |u|^2 in [1, 3]
        n2 = squared_norm(u);
    }
    const double inverse = 1.0 / std::sqrt(n2);
    return {a[0] * (u.x * inverse), a[1] * (u.y * inverse), a[2] * (u.z * inverse)};
}

// make_climb_lists' records of one width (`Record` a ClimbRecord), made in place in `out`'s
// rows; false when an index is not one of the shape's vertices.
template <class Record>
bool write_climb_lists(const ShapeView& s, ClimbList* out) {
    using Index = decltype(Record::count);
    constexpr int kRows = sizeof(Record) / sizeof(ClimbList);
    for (int i = 0; i < s.vertex_count; ++i) {
        const std::int64_t begin = s.adjacency_offsets[i], end = s.adjacency_offsets[i + 1];
        Record& list = *new (out + kRows * i) Record{};
        list.count = static_cast<Index>(end - begin);
        for (std::int64_t k = begin; k < end; ++k) {
            const std::int32_t j = s.adjacency[k];
            if (j < 0 || j >= s.vertex_count) return false;
            list.neighbours[k - begin] = static_cast<Index>(j);
        }
    }
    return true;
}

}  // namespace

bool make_climb_lists(const ShapeView& s, ClimbList* out) {
    if (s.vertices == nullptr || s.adjacency_offsets == nullptr || s.adjacency == nullptr)
        return false;
    std::int64_t longest = 0;
    for (int i = 0; i < s.vertex_count; ++i) {
        const std::int64_t begin = s.adjacency_offsets[i], end = s.adjacency_offsets[i + 1];
        if (end < begin) return false;
        longest = std::max(longest, end - begin);
    }
    if (!keeps_climb_lists(s.vertex_count, longest)) return false;
    return climb_rows(s.vertex_count) == 1 ? write_climb_lists<ClimbList>(s, out)
                                           : write_climb_lists<WideClimbList>(s, out);
}

bool scans(const ShapeView& s) {
    return s.kind == ShapeKind::POLYTOPE && s.vertices != nullptr && s.vertex_count > 0 &&
           !climbs(s);
}

bool climbs(const ShapeView& s) {
    return s.kind == ShapeKind::POLYTOPE && s.adjacency_offsets != nullptr &&
           s.vertex_count > defaults::hill_climbing_min_vertices;
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
        case ShapeKind::ELLIPSOID:
            return {ellipsoid_support(s.params, d), -1};
        case ShapeKind::HALFSPACE:
            break;  // unbounded: no support point
    }
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    return {Vec3{kNaN, kNaN, kNaN}, -1};
}

namespace {

// A hint to fetch the cache lines of [begin, end) (a no-op where the compiler has no hint).
void prefetch_bytes(const void* begin, const void* end) {
#if defined(__GNUC__) || defined(__clang__)
    constexpr std::ptrdiff_t kLine = 64;
    const char* p = static_cast<const char*>(begin);
    const char* e = static_cast<const char*>(end);
    // Four lines a trip: a 256-vertex shape is about 250 lines, asked for on every query.
    for (; e - p > 3 * kLine; p += 4 * kLine) {
        __builtin_prefetch(p);
        __builtin_prefetch(p + kLine);
        __builtin_prefetch(p + 2 * kLine);
        __builtin_prefetch(p + 3 * kLine);
    }
    for (; p < e; p += kLine) __builtin_prefetch(p);
#else
    (void)begin;
    (void)end;
#endif
}

}  // namespace

void read_vertices(const ShapeView& s) {
    if (!climbs(s) || s.vertices == nullptr) return;
    const double* begin = &s.vertices[0].x;
    const double* end = begin + 3 * static_cast<std::ptrdiff_t>(s.vertex_count);
    double sum = 0.0;
    for (const double* p = begin; p < end; p += 8) sum += *p;  // about one load a line
    if (s.climb_lists != nullptr) {
        // The fixed-stride lists too, one load a line: a climb's next list is then near
        // (a cold 256-vertex pair waited on them in half its support time).
        const auto* bytes = reinterpret_cast<const unsigned char*>(s.climb_lists);
        const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(sizeof(ClimbList)) *
                                    s.vertex_count * climb_rows(s.vertex_count);
        std::uint32_t counts = 0;
        for (std::ptrdiff_t k = 0; k < size; k += 64) counts += bytes[k];
        sum += counts;
    }
#if defined(__GNUC__) || defined(__clang__)
    asm volatile("" ::"g"(sum));  // the sum is wanted, so the loads stay
#else
    volatile double sink = sum;
    (void)sink;
#endif
}

void prefetch(const ShapeView& s) {
    // Only shapes that climb: a scan reads its vertices in order, which the hardware's own
    // prefetcher follows, and never reads the adjacency.
    if (!climbs(s) || s.vertices == nullptr || s.adjacency == nullptr ||
        s.vertex_count > defaults::prefetch_max_vertices)
        return;
    const int n = s.vertex_count;
    prefetch_bytes(s.vertices, s.vertices + n);
    if (s.climb_lists != nullptr) {
        // Fixed-stride lists need no offsets; as below, the small shapes' lists too.
        if (n < defaults::climb_prefetch_min_vertices)
            prefetch_bytes(s.climb_lists, s.climb_lists + n * climb_rows(n));
        return;
    }
    prefetch_bytes(s.adjacency_offsets, s.adjacency_offsets + n + 1);
    // The neighbour lists (half the shape's lines) only where the climbs do not ask for
    // each list they read themselves (`climb::climb_step`): asked for twice, they cost a
    // pair in a set the cache holds more than they save (256 vertices, driver A/B: 25% of
    // a separated pair's time, 5% of a penetrating one's).
    if (n < defaults::climb_prefetch_min_vertices)
        prefetch_bytes(s.adjacency + s.adjacency_offsets[0],
                       s.adjacency + s.adjacency_offsets[n]);
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
        case ShapeKind::ELLIPSOID:
            hi = {s.params[0], s.params[1], s.params[2]};
            break;
        case ShapeKind::HALFSPACE: {
            constexpr double kInf = std::numeric_limits<double>::infinity();
            lo = {-kInf, -kInf, -kInf};
            hi = {kInf, kInf, 0.0};
            return;
        }
    }
    lo = -hi;
}

void world_aabb(const ShapeView& s, const Pose& pose, Vec3& lo, Vec3& hi) {
    if (s.kind == ShapeKind::HALFSPACE) {
        // Unbounded along every world axis but the one its normal is exactly (a floor whose
        // normal is +z bounds z from above at its height; a tilted one bounds nothing).
        constexpr double kInf = std::numeric_limits<double>::infinity();
        const Vec3 n = pose.rotation.column(2);
        for (int k = 0; k < 3; ++k) {
            lo[k] = -kInf;
            hi[k] = kInf;
            const bool alone = n[(k + 1) % 3] == 0.0 && n[(k + 2) % 3] == 0.0;
            if (alone && n[k] > 0.0) hi[k] = pose.translation[k];
            if (alone && n[k] < 0.0) lo[k] = pose.translation[k];
        }
        return;
    }
    if (s.kind == ShapeKind::POLYTOPE) {
        lo = hi = pose.apply(s.vertices[0]);
        for (int i = 1; i < s.vertex_count; ++i) {
            const Vec3 p = pose.apply(s.vertices[i]);
            lo = component_min(lo, p);
            hi = component_max(hi, p);
        }
        return;
    }
    if (s.kind == ShapeKind::ELLIPSOID) {
        // The ellipsoid R A B + t (B the unit ball) reaches |A R^T e_k| along world axis k:
        // sqrt(sum_j (R_kj a_j)^2), formed without overflow.
        for (int k = 0; k < 3; ++k) {
            const Vec3 row = pose.rotation.row(k);
            const double half =
                safe_norm(Vec3{row.x * s.params[0], row.y * s.params[1], row.z * s.params[2]});
            hi[k] = pose.translation[k] + half;
            lo[k] = pose.translation[k] - half;
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
            if (r2 >= 0x1p-1000 && r2 <= 0x1p1000) return std::sqrt(r2);
            // Squares out of range (coordinates beyond about 1e150 or below 1e-150).
            double r = 0.0;
            for (int i = 0; i < s.vertex_count; ++i) r = std::fmax(r, safe_norm(s.vertices[i]));
            return r;
        }
        case ShapeKind::SPHERE:
            return s.params[0];
        case ShapeKind::BOX:
            return safe_norm(Vec3{s.params[0], s.params[1], s.params[2]});
        case ShapeKind::CAPSULE:
            return s.params[0] + s.params[1];
        case ShapeKind::CYLINDER:
            return std::hypot(s.params[0], s.params[1]);
        case ShapeKind::ELLIPSOID:
            return std::fmax(s.params[0], std::fmax(s.params[1], s.params[2]));
        case ShapeKind::HALFSPACE:
            return std::numeric_limits<double>::infinity();
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
        case ShapeKind::ELLIPSOID:
            return s.params[0] >= 0.0 && s.params[1] >= 0.0 && s.params[2] >= 0.0;
        case ShapeKind::CAPSULE:
        case ShapeKind::CYLINDER:
            return s.params[0] >= 0.0 && s.params[1] >= 0.0;
        case ShapeKind::HALFSPACE:
            return true;
    }
    return false;
}

double valid_bounding_radius(const ShapeView& s) {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    const auto careful = [&s] { return is_valid(s) ? bounding_radius(s) : kNaN; };
    if (s.kind != ShapeKind::POLYTOPE || s.vertex_count <= 0 || s.vertices == nullptr)
        return careful();
    for (double p : s.params)
        if (!std::isfinite(p)) return kNaN;
    // One pass: the largest squared norm, and the sum of them, which is finite only when
    // every coordinate is (an infinity or a NaN makes its square so) and no square
    // overflows; otherwise the careful path decides. Four independent chains each (a max is
    // exact, so the order does not change it: `bounding_radius`'s answer, bit for bit).
    const Vec3* v = s.vertices;
    const int n = s.vertex_count;
    double r[4] = {0.0, 0.0, 0.0, 0.0}, sum[4] = {0.0, 0.0, 0.0, 0.0};
    int i = 0;
#if defined(__SSE2__)
    // Two vertices (six coordinates, three loads) at a time, their squares regrouped as
    // (x0, x1), (y0, y1), (z0, z1) so each lane sums (x x + y y) + z z, `squared_norm`'s
    // order: the same squared norms bit for bit, in half the instructions. `_mm_max_pd(q, r)`
    // is q > r ? q : r per lane, as below.
    {
        const double* c = &v[0].x;
        __m128d r01 = _mm_setzero_pd(), r23 = _mm_setzero_pd();
        __m128d s01 = _mm_setzero_pd(), s23 = _mm_setzero_pd();
        const auto squares = [c](int k) {
            const __m128d a = _mm_loadu_pd(c + 3 * k);      // x0 y0
            const __m128d b = _mm_loadu_pd(c + 3 * k + 2);  // z0 x1
            const __m128d d = _mm_loadu_pd(c + 3 * k + 4);  // y1 z1
            const __m128d aa = _mm_mul_pd(a, a), bb = _mm_mul_pd(b, b), dd = _mm_mul_pd(d, d);
            const __m128d xs = _mm_shuffle_pd(aa, bb, 2), ys = _mm_shuffle_pd(aa, dd, 1);
            const __m128d zs = _mm_shuffle_pd(bb, dd, 2);
            return _mm_add_pd(_mm_add_pd(xs, ys), zs);
        };
        for (; i + 3 < n; i += 4) {
            const __m128d q01 = squares(i), q23 = squares(i + 2);
            r01 = _mm_max_pd(q01, r01);
            r23 = _mm_max_pd(q23, r23);
            s01 = _mm_add_pd(s01, q01);
            s23 = _mm_add_pd(s23, q23);
        }
        _mm_storeu_pd(r, r01);
        _mm_storeu_pd(r + 2, r23);
        _mm_storeu_pd(sum, s01);
        _mm_storeu_pd(sum + 2, s23);
    }
#else
    for (; i + 3 < n; i += 4)
        for (int l = 0; l < 4; ++l) {
            const double q = squared_norm(v[i + l]);
            r[l] = q > r[l] ? q : r[l];
            sum[l] += q;
        }
#endif
    for (; i < n; ++i) {
        const double q = squared_norm(v[i]);
        r[0] = q > r[0] ? q : r[0];
        sum[0] += q;
    }
    const double total = (sum[0] + sum[1]) + (sum[2] + sum[3]);
    const double r2 = std::fmax(std::fmax(r[0], r[1]), std::fmax(r[2], r[3]));
    if (std::isfinite(total) && r2 >= 0x1p-1000 && r2 <= 0x1p1000) return std::sqrt(r2);
    return careful();
}

}  // namespace meshcol
