// Static mesh hierarchy: top-down binned SAH build (Wald 2007, "On fast construction of
// SAH-based bounding volume hierarchies"), explicit work stack so deep trees cannot overflow the
// call stack, float boxes rounded outwards so they stay conservative.
#include "meshcol/mesh_bvh.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/defaults.hpp"
#include "meshcol/orientation.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The float next to a finite float `f` towards -infinity (`down`) or +infinity, as
// std::nextafter gives it, inlined: a step of one in the bits of its magnitude, and from a zero
// of either sign to the smallest denormal of the step's sign.
inline float step(float f, bool down) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    if ((bits & 0x7fffffffU) == 0) {
        bits = down ? 0x80000001U : 0x00000001U;
    } else {
        const bool negative = (bits >> 31) != 0;
        bits = negative == down ? bits + 1 : bits - 1;
    }
    std::memcpy(&f, &bits, sizeof(f));
    return f;
}

// Largest float <= x (never above it), so a float lower bound stays below the double.
float round_down(double x) {
    if (x > static_cast<double>(FLT_MAX)) return FLT_MAX;
    if (x < -static_cast<double>(FLT_MAX)) return -std::numeric_limits<float>::infinity();
    float f = static_cast<float>(x);
    if (static_cast<double>(f) > x) f = step(f, true);
    return f;
}

// Smallest float >= x.
float round_up(double x) {
    if (x > static_cast<double>(FLT_MAX)) return std::numeric_limits<float>::infinity();
    if (x < -static_cast<double>(FLT_MAX)) return -FLT_MAX;
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = step(f, false);
    return f;
}

// Componentwise minimum and maximum of finite (or infinite) coordinates, inlined: std::fmin
// and std::fmax are library calls for their NaN rules, which validated vertices do not need.
// Of equal coordinates (zeros of both signs) a's is kept. With SSE2, x and y in one register:
// `_mm_min_pd(b, a)` is b < a ? b : a per lane, `_mm_max_pd(b, a)` b > a ? b : a.
inline Vec3 min3(const Vec3& a, const Vec3& b) {
#if defined(__SSE2__)
    Vec3 r;
    _mm_storeu_pd(&r.x, _mm_min_pd(_mm_loadu_pd(&b.x), _mm_loadu_pd(&a.x)));
    r.z = b.z < a.z ? b.z : a.z;
    return r;
#else
    return {b.x < a.x ? b.x : a.x, b.y < a.y ? b.y : a.y, b.z < a.z ? b.z : a.z};
#endif
}
inline Vec3 max3(const Vec3& a, const Vec3& b) {
#if defined(__SSE2__)
    Vec3 r;
    _mm_storeu_pd(&r.x, _mm_max_pd(_mm_loadu_pd(&b.x), _mm_loadu_pd(&a.x)));
    r.z = b.z > a.z ? b.z : a.z;
    return r;
#else
    return {b.x > a.x ? b.x : a.x, b.y > a.y ? b.y : a.y, b.z > a.z ? b.z : a.z};
#endif
}

struct Box {
    Vec3 lower{kInf, kInf, kInf};
    Vec3 upper{-kInf, -kInf, -kInf};

    void grow(const Vec3& p) {
        lower = min3(lower, p);
        upper = max3(upper, p);
    }
    void grow(const Box& b) {
        lower = min3(lower, b.lower);
        upper = max3(upper, b.upper);
    }
    bool empty() const { return lower.x > upper.x; }
    // Half the surface area (the SAH only compares areas).
    double half_area() const {
        if (empty()) return 0.0;
        const Vec3 d = upper - lower;
        return d.x * d.y + d.y * d.z + d.z * d.x;
    }
};

// SAH bin of a centroid coordinate `c` in [lo, lo + extent] (extent > 0), always in
// [0, mesh_bvh_bins). Divides before scaling: kBins / extent overflows to inf for a denormal
// extent (vertices near 1e-310), and 0 * inf is NaN, whose conversion to int is undefined; an
// infinite extent (coordinates near the double range) puts everything in bin 0.
inline int bin_of(double c, double lo, double extent) {
    constexpr int kBins = defaults::mesh_bvh_bins;
    const double x = (c - lo) / extent * kBins;
    if (!(x > 0.0)) return 0;  // also NaN
    return x >= kBins - 1 ? kBins - 1 : static_cast<int>(x);
}

// bin_of along the three axes, into `bins` (z only when `binned_z`, else 0; x and y always, an
// axis of no extent giving some bin in range). With SSE2, without a branch: x and y in one
// register, each lane and z as bin_of computes them: `_mm_max_pd(x, 0)` is x > 0 ? x : 0 (0
// for NaN), then `_mm_min_pd(x, top)` is x < top ? x : top, and the truncation is the
// conversion's (and likewise the `_sd` forms for z).
inline void bins_of(const Vec3& c, const double lo[3], const double extent[3], bool binned_z, int bins[3]) {
#if defined(__SSE2__)
    constexpr int kBins = defaults::mesh_bvh_bins;
    const __m128d x = _mm_mul_pd(_mm_div_pd(_mm_sub_pd(_mm_loadu_pd(&c.x), _mm_loadu_pd(lo)), _mm_loadu_pd(extent)),
                                 _mm_set1_pd(kBins));
    const __m128i b = _mm_cvttpd_epi32(_mm_min_pd(_mm_max_pd(x, _mm_setzero_pd()), _mm_set1_pd(kBins - 1)));
    bins[0] = _mm_cvtsi128_si32(b);
    bins[1] = _mm_cvtsi128_si32(_mm_shuffle_epi32(b, 1));
    bins[2] = 0;
    if (binned_z) {
        const __m128d z = _mm_set_sd((c.z - lo[2]) / extent[2] * kBins);
        bins[2] = _mm_cvttsd_si32(_mm_min_sd(_mm_max_sd(z, _mm_setzero_pd()), _mm_set_sd(kBins - 1)));
    }
#else
    for (int axis = 0; axis < 2; ++axis) bins[axis] = extent[axis] > 0.0 ? bin_of(c[axis], lo[axis], extent[axis]) : 0;
    bins[2] = binned_z ? bin_of(c.z, lo[2], extent[2]) : 0;
#endif
}

// The non-empty bins of `count` (mesh_bvh_bins of them), in increasing order, into `used`;
// returns how many. With SSE2, four counts compared at once and the bits of the non-empty
// ones walked, rather than a test per bin: most nodes are small and fill few of the bins.
inline int used_bins(const std::int32_t* count, int* used) {
    constexpr int kBins = defaults::mesh_bvh_bins;
    int m = 0;
#if defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__))
    if constexpr (kBins % 4 == 0 && kBins < 32) {
        std::uint32_t empty = 0;
        for (int b = 0; b < kBins; b += 4) {
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(count + b));
            const int zero = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(c, _mm_setzero_si128())));
            empty |= static_cast<std::uint32_t>(zero) << b;
        }
        for (std::uint32_t full = ~empty & ((1U << kBins) - 1U); full != 0; full &= full - 1U)
            used[m++] = __builtin_ctz(full);
        return m;
    }
#endif
    for (int b = 0; b < kBins; ++b) {
        used[m] = b;
        m += count[b] > 0;
    }
    return m;
}

// A box kept with its lower corner negated, as the lanes (-lower.x, -lower.y), (upper.x,
// upper.y), (-lower.z, upper.z): growing it is one max a lane, where a Box takes a min and a
// max of each corner's x and y and two scalar steps for z. Negation is exact, so the corners
// are a Box's bits, zeros' signs too: `b > a` of the negated lower is `b < a` of the lower.
struct FlippedBox {
    double v[6] = {-kInf, -kInf, -kInf, -kInf, -kInf, -kInf};  // empty

    static FlippedBox of(const Box& b) {
        FlippedBox f;
        f.v[0] = -b.lower.x;
        f.v[1] = -b.lower.y;
        f.v[2] = b.upper.x;
        f.v[3] = b.upper.y;
        f.v[4] = -b.lower.z;
        f.v[5] = b.upper.z;
        return f;
    }
    Vec3 lower() const { return {-v[0], -v[1], -v[4]}; }
    Vec3 upper() const { return {v[2], v[3], v[5]}; }
    // The union, of equal coordinates this box's kept (Box::grow's choice).
    void grow(const FlippedBox& b) {
#if defined(__SSE2__)
        for (int k = 0; k < 6; k += 2)
            _mm_storeu_pd(v + k, _mm_max_pd(_mm_loadu_pd(b.v + k), _mm_loadu_pd(v + k)));
#else
        for (int k = 0; k < 6; ++k) v[k] = b.v[k] > v[k] ? b.v[k] : v[k];
#endif
    }
    // The union, of equal coordinates b's kept.
    void grow_last(const FlippedBox& b) {
#if defined(__SSE2__)
        for (int k = 0; k < 6; k += 2)
            _mm_storeu_pd(v + k, _mm_max_pd(_mm_loadu_pd(v + k), _mm_loadu_pd(b.v + k)));
#else
        for (int k = 0; k < 6; ++k) v[k] = v[k] > b.v[k] ? v[k] : b.v[k];
#endif
    }
    // Box::half_area, to the bit: upper - lower is upper + (-lower).
    double half_area() const {
        if (-v[0] > v[2]) return 0.0;  // empty
        const double dx = v[2] + v[0], dy = v[3] + v[1], dz = v[5] + v[4];
        return dx * dy + dy * dz + dz * dx;
    }
};

// One triangle's box and the centre of that box (the point the SAH bins), side by side.
struct TriangleBounds {
    FlippedBox box;
    Vec3 centroid;
};

// The bounds of a range of triangles: the union of their boxes and the bounds of their
// centroids.
struct RangeBounds {
    FlippedBox boxes;
    Box centroids;

    // Grown in the range's order, the first of equal coordinates kept (Box::grow), so a zero
    // keeps the sign the first triangle gives it.
    void add(const TriangleBounds& t) {
        boxes.grow(t.box);
        centroids.grow(t.centroid);
    }
    // Grown against the range's order, the last of equal coordinates kept: the same box, zeros
    // signed alike, as add() in order.
    void add_before(const TriangleBounds& t) {
        boxes.grow_last(t.box);
        take_lower(centroids.lower, t.centroid);
        take_upper(centroids.upper, t.centroid);
    }

private:
    // Of equal coordinates b's is kept. `_mm_min_pd(a, b)` is a < b ? a : b per lane, which
    // is b <= a ? b : a for coordinates that are not NaN (validated vertices).
    static void take_lower(Vec3& a, const Vec3& b) {
#if defined(__SSE2__)
        _mm_storeu_pd(&a.x, _mm_min_pd(_mm_loadu_pd(&a.x), _mm_loadu_pd(&b.x)));
        a.z = b.z <= a.z ? b.z : a.z;
#else
        a = {b.x <= a.x ? b.x : a.x, b.y <= a.y ? b.y : a.y, b.z <= a.z ? b.z : a.z};
#endif
    }
    static void take_upper(Vec3& a, const Vec3& b) {
#if defined(__SSE2__)
        _mm_storeu_pd(&a.x, _mm_max_pd(_mm_loadu_pd(&a.x), _mm_loadu_pd(&b.x)));
        a.z = b.z >= a.z ? b.z : a.z;
#else
        a = {b.x >= a.x ? b.x : a.x, b.y >= a.y ? b.y : a.y, b.z >= a.z ? b.z : a.z};
#endif
    }
};

// segment_closest_points(p, p, a, b).squared_distance, inlined and step for step: the first
// segment's direction is zero (p - p, p finite), so it is Ericson's degenerate case, t =
// clamp01(f / e) (or 0 for a = b), and its closest point is p, bar the sign of a zero, which
// the square drops. The capsules' call was 2.5% of a build.
inline double point_segment_squared_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 d = b - a, r = p - a;
    const double e = dot(d, d), f = dot(d, r);
    double t = 0.0;
    if (e != 0.0) {
        const double x = f / e;
        t = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    }
    return squared_norm((a + d * t) - p);
}

struct BuildTask {
    std::int32_t begin, end;
    std::int32_t patch;  // node whose right-child index is this task's node, or -1
    bool known;          // `bounds` holds the range's bounds (the parent's split grew them)
    RangeBounds bounds;
};

// Hoare's two-ended partition as libstdc++'s std::partition (bidirectional form) leaves it,
// so the leaf order does not depend on the standard library: the triangles of order[begin,
// end) for which `left` holds first, then each side's bounds. Hoare's scans swap the k-th
// triangle from the front that belongs right with the k-th from the back that belongs left,
// for every right one before `mid` (the count of left ones past begin), the same number as
// the left ones from `mid` on; the rest stay. That permutation is made here without a branch
// on the test (whose outcome a scan mispredicts about once in two triangles): the outcomes
// into `side`, the misplaced positions listed into `misplaced` (the front's at [begin, mid),
// the back's at [mid, end)), then the swaps. The left side's bounds grow front to back, the
// right side's back to front, keeping the last of equal coordinates (add_before), as Hoare's
// scans grow them, each triangle as it settles. Returns mid, the first index of the right
// side.
template <class Left>
std::int32_t partition_triangles(std::vector<std::int32_t>& order, std::int32_t begin, std::int32_t end,
                                 const std::vector<TriangleBounds>& triangles, Left left, RangeBounds& left_bounds,
                                 RangeBounds& right_bounds, std::uint8_t* side, std::int32_t* misplaced) {
    std::int32_t* o = order.data();
    std::int32_t lefts = 0;
    for (std::int32_t i = begin; i < end; ++i) {
        const bool l = left(o[i]);
        side[i] = static_cast<std::uint8_t>(l);
        lefts += l;
    }
    const std::int32_t mid = begin + lefts;
    std::int32_t front = begin;  // misplaced[begin, front): right ones before mid, in order
    for (std::int32_t i = begin; i < mid; ++i) {
        misplaced[front] = i;
        front += side[i] ^ 1;
    }
    std::int32_t back = mid;  // misplaced[mid, back): left ones from mid on, from the back
    for (std::int32_t i = end; i-- > mid;) {
        misplaced[back] = i;
        back += side[i];
    }
    for (std::int32_t k = 0; k < front - begin; ++k)
        std::swap(o[misplaced[begin + k]], o[misplaced[mid + k]]);
    const auto bounds = [&](std::int32_t f) -> const TriangleBounds& { return triangles[static_cast<size_t>(f)]; };
    for (std::int32_t i = begin; i < mid; ++i) left_bounds.add(bounds(o[i]));
    for (std::int32_t i = end; i-- > mid;) right_bounds.add_before(bounds(o[i]));
    return mid;
}

}  // namespace

MeshBvh::MeshBvh(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                 std::int64_t face_count) {
    if (vertex_count < 0 || face_count < 0) throw std::invalid_argument("negative mesh size");
    if (face_count > std::numeric_limits<std::int32_t>::max() / 2)
        throw std::invalid_argument("mesh has too many faces (" + std::to_string(face_count) + ")");
    for (std::int64_t f = 0; f < 3 * face_count; ++f)
        if (faces[f] < 0 || faces[f] >= vertex_count)
            throw std::invalid_argument("face " + std::to_string(f / 3) + " has vertex index " +
                                        std::to_string(faces[f]) + " out of range [0, " +
                                        std::to_string(vertex_count) + ")");
    for (std::int64_t i = 0; i < 3 * vertex_count; ++i)
        if (!std::isfinite(vertices[i])) return;  // not valid(): queries report INVALID_INPUT
    if (face_count == 0) return;

    const auto n = static_cast<std::int32_t>(face_count);
    auto vertex = [&](std::int64_t i) {
        return Vec3{vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
    };
    std::vector<TriangleBounds> triangles(static_cast<size_t>(n));
    RangeBounds root;
    for (std::int32_t f = 0; f < n; ++f) {
        TriangleBounds& t = triangles[static_cast<size_t>(f)];
        Box box;
        for (int k = 0; k < 3; ++k) box.grow(vertex(faces[3 * f + k]));
        t.box = FlippedBox::of(box);
        t.centroid = (box.lower + box.upper) * 0.5;
        root.add(t);
    }
    std::vector<std::int32_t> order(static_cast<size_t>(n));
    for (std::int32_t f = 0; f < n; ++f) order[static_cast<size_t>(f)] = f;

    constexpr int kBins = defaults::mesh_bvh_bins;
    constexpr int kLeaf = defaults::mesh_bvh_leaf_size;
    static_assert(kBins >= 2 && kBins <= 256, "a bin number is kept in a byte");
    nodes_.reserve(static_cast<size_t>(2 * (n / kLeaf + 1)));
    std::vector<BuildTask> stack{{0, n, -1, true, root}};
    // Each triangle's bin along each axis, written by its node's binning and read by the split.
    std::vector<std::uint8_t> bin_index(3 * static_cast<size_t>(n));
    // The partition's scratch: each triangle's side, and the positions it swaps.
    std::vector<std::uint8_t> side(static_cast<size_t>(n));
    std::vector<std::int32_t> misplaced(static_cast<size_t>(n));
    // Empty between nodes: a node empties the bins it filled once it has read them.
    FlippedBox bin_box[3][kBins];
    std::int32_t bin_count[3][kBins] = {};
    int used[kBins];  // the non-empty bins of one axis, in order
    double right_area[kBins];
    std::int32_t right_count[kBins];

    while (!stack.empty()) {
        BuildTask task = stack.back();
        stack.pop_back();
        const auto id = static_cast<std::int32_t>(nodes_.size());
        if (task.patch >= 0) nodes_[static_cast<size_t>(task.patch)].index = id;
        if (!task.known)
            for (std::int32_t i = task.begin; i < task.end; ++i)
                task.bounds.add(triangles[static_cast<size_t>(order[static_cast<size_t>(i)])]);
        BvhNode node{};
        {
            const Vec3 lower = task.bounds.boxes.lower(), upper = task.bounds.boxes.upper();
            for (int k = 0; k < 3; ++k) {
                node.lower[k] = round_down(lower[k]);
                node.upper[k] = round_up(upper[k]);
            }
        }
        const std::int32_t count = task.end - task.begin;
        if (count <= kLeaf) {
            node.index = task.begin;
            node.count = count;
            nodes_.push_back(node);
            continue;
        }
        // Best binned SAH split over the three axes, binned in one pass. Only the non-empty
        // bins are swept: a split after an empty bin costs what the split after the non-empty
        // bin before it costs, and the first of equal costs is kept, so the split chosen is
        // the one a sweep over every bin chooses.
        double lo[3], extent[3];
        bool binned[3];
        for (int axis = 0; axis < 3; ++axis) {
            lo[axis] = task.bounds.centroids.lower[axis];
            extent[axis] = task.bounds.centroids.upper[axis] - lo[axis];
            binned[axis] = extent[axis] > 0.0;
        }
        // `every` (all three axes binned, the usual case) drops the per-axis test.
        const auto bin_range = [&](auto every) {
            for (std::int32_t i = task.begin; i < task.end; ++i) {
                const std::int32_t f = order[static_cast<size_t>(i)];
                const TriangleBounds& t = triangles[static_cast<size_t>(f)];
                int bins[3];
                bins_of(t.centroid, lo, extent, binned[2], bins);
                for (int axis = 0; axis < 3; ++axis) {
                    if (!every && !binned[axis]) continue;
                    const int b = bins[axis];
                    bin_index[3 * static_cast<size_t>(f) + static_cast<size_t>(axis)] = static_cast<std::uint8_t>(b);
                    bin_box[axis][b].grow(t.box);
                    ++bin_count[axis][b];
                }
            }
        };
        if (binned[0] && binned[1] && binned[2])
            bin_range(std::true_type{});
        else
            bin_range(std::false_type{});
        double best_cost = kInf;
        int best_axis = -1, best_bin = -1;
        for (int axis = 0; axis < 3; ++axis) {
            if (!binned[axis]) continue;
            const int m = used_bins(bin_count[axis], used);
            FlippedBox right;
            std::int32_t right_n = 0;
            for (int k = m - 1; k > 0; --k) {
                right.grow(bin_box[axis][used[k]]);
                right_n += bin_count[axis][used[k]];
                right_area[k] = right.half_area();
                right_count[k] = right_n;
            }
            FlippedBox left;
            std::int32_t left_n = 0;
            for (int k = 0; k + 1 < m; ++k) {
                left.grow(bin_box[axis][used[k]]);
                left_n += bin_count[axis][used[k]];
                const double cost = left_n * left.half_area() + right_count[k + 1] * right_area[k + 1];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bin = used[k];
                }
            }
            for (int k = 0; k < m; ++k) {
                bin_box[axis][used[k]] = FlippedBox{};
                bin_count[axis][used[k]] = 0;
            }
        }
        std::int32_t mid = task.begin + count / 2;
        BuildTask left_task{task.begin, mid, -1, false, RangeBounds{}};
        BuildTask right_task{mid, task.end, id, false, RangeBounds{}};
        if (best_axis >= 0) {
            const size_t axis = static_cast<size_t>(best_axis);
            RangeBounds left_bounds, right_bounds;
            const std::int32_t m = partition_triangles(
                order, task.begin, task.end, triangles,
                [&](std::int32_t f) { return bin_index[3 * static_cast<size_t>(f) + axis] <= best_bin; },
                left_bounds, right_bounds, side.data(), misplaced.data());
            if (m > task.begin && m < task.end) {
                mid = m;
                left_task = {task.begin, mid, -1, true, left_bounds};
                right_task = {mid, task.end, id, true, right_bounds};
            }
        }
        // Otherwise all centroids coincide: any split is as good, halve by count.
        node.index = -1;
        node.count = 0;
        nodes_.push_back(node);
        stack.push_back(right_task);
        stack.push_back(left_task);
    }

    corners_.resize(3 * static_cast<size_t>(n));
    face_index_.resize(static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const std::int32_t f = order[static_cast<size_t>(i)];
        face_index_[static_cast<size_t>(i)] = f;
        for (int k = 0; k < 3; ++k) corners_[3 * static_cast<size_t>(i) + k] = vertex(faces[3 * f + k]);
    }
    normals_.resize(static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const Vec3* t = triangle(i);
        const Vec3 normal = cross(t[1] - t[0], t[2] - t[0]);
        const double length = norm(normal);
        // Zero for a degenerate triangle, and for one whose normal under- or overflows.
        normals_[static_cast<size_t>(i)] = length > 0.0 && std::isfinite(length) ? normal / length : Vec3{0.0, 0.0, 0.0};
    }
    // Each triangle's box (mesh_detail::triangle_box, the descents' own), kept: the descents
    // test a triangle of a against b's leaf box and b's triangles at every leaf pair that
    // reaches it, and forming the box there was about 3% of bench_mesh_query's balls and torus
    // contact rows (benchmarks/RESULTS.md, session 30). 48 bytes a triangle.
    bounds_.resize(2 * static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const mesh_detail::TriangleBox box = mesh_detail::triangle_box(triangle(i));
        bounds_[2 * static_cast<size_t>(i)] = box.lower;
        bounds_[2 * static_cast<size_t>(i) + 1] = box.upper;
    }
    capsules_.resize(static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const Vec3* t = triangle(i);
        std::int32_t edge = 0;
        double longest = -1.0;
        for (std::int32_t k = 0; k < 3; ++k) {
            const double length2 = squared_norm(t[(k + 1) % 3] - t[k]);
            if (length2 > longest) {
                longest = length2;
                edge = k;
            }
        }
        const Vec3& p = t[(edge + 2) % 3];
        const double h2 = point_segment_squared_distance(p, t[edge], t[(edge + 1) % 3]);
        // Rounded up well past the rounding of the square root and of the closest point; an
        // overflow (coordinates beyond 1e154) gives inf, a bound that prunes nothing.
        double radius = std::sqrt(h2) * (1.0 + 1e-12);
        if (!(radius >= 0.0)) radius = kInf;  // NaN
        capsules_[static_cast<size_t>(i)] = {radius, edge, 16.0 * h2 < longest};
    }
    // Used vertices renumbered in input order (-1: unused), for the triangles' corner indices.
    std::vector<std::int32_t> compact(static_cast<size_t>(vertex_count), -1);
    for (std::int64_t k = 0; k < 3 * face_count; ++k) compact[static_cast<size_t>(faces[k])] = 0;
    for (std::int64_t v = 0; v < vertex_count; ++v)
        if (compact[static_cast<size_t>(v)] == 0) {
            compact[static_cast<size_t>(v)] = static_cast<std::int32_t>(vertices_.size());
            vertices_.push_back(vertex(v));
        }
    corner_vertices_.resize(3 * static_cast<size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) {
        const std::int64_t f = face_index_[static_cast<size_t>(i)];
        for (int k = 0; k < 3; ++k)
            corner_vertices_[3 * static_cast<size_t>(i) + k] = compact[static_cast<size_t>(faces[3 * f + k])];
    }
    build_winding_nodes();
    build_obbs();
    {
        const BvhNode& root = nodes_.front();
        Vec3 corner;
        for (int k = 0; k < 3; ++k)
            corner[k] = std::fmax(std::fabs(double(root.lower[k])), std::fabs(double(root.upper[k])));
        box_reach_ = safe_norm(corner);
        const NodeObb& obb = obbs_.front();
        obb_reach_ = max_abs(obb.center) + max_abs(obb.half);
    }
    // Of the compact corner indices, 32 bits: the same directed edges, each vertex renamed
    // once (unused vertices carry none), so the same verdict as of the faces given.
    closed_ = closed_and_consistent(corner_vertices_.data(), n, static_cast<std::int64_t>(vertices_.size()));
}

namespace {

// Adds the first moment of area vector `a` at offset `g` from the centre (a (g)^T, symmetric
// part) to `m`.
void add_moment(double m[6], const Vec3& a, const Vec3& g) {
    m[0] += a.x * g.x;
    m[1] += a.y * g.y;
    m[2] += a.z * g.z;
    m[3] += 0.5 * (a.x * g.y + a.y * g.x);
    m[4] += 0.5 * (a.y * g.z + a.z * g.y);
    m[5] += 0.5 * (a.z * g.x + a.x * g.z);
}

// The sums over corners p of pu = (p - center) . u and pv = (p - center) . v: of pu, pv, pu^2,
// pv^2 and pu pv, each added in the corners' order.
struct TangentMoments {
    double mu = 0.0, mv = 0.0, cuu = 0.0, cvv = 0.0, cuv = 0.0;
};

TangentMoments tangent_moments(const Vec3* corner, std::int32_t count, const Vec3& center, const Vec3& u,
                               const Vec3& v) {
    TangentMoments m;
#if defined(__SSE2__)
    // pu in the low lane and pv in the high one, each computed as dot() computes it,
    // ((x ux + y uy) + z uz), and each sum a chain of its own in the corners' order: the same
    // bits as the scalar loop below, in fewer instructions.
    const __m128d ux = _mm_set_pd(v.x, u.x), uy = _mm_set_pd(v.y, u.y), uz = _mm_set_pd(v.z, u.z);
    const __m128d cxy = _mm_loadu_pd(&center.x);
    __m128d sum = _mm_setzero_pd(), squares = _mm_setzero_pd();
    double cuv = 0.0;
    for (std::int32_t i = 0; i < count; ++i) {
        const double* q = &corner[i].x;
        const __m128d pxy = _mm_sub_pd(_mm_loadu_pd(q), cxy);
        const double pz = q[2] - center.z;
        const __m128d uv = _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_unpacklo_pd(pxy, pxy), ux),
                                                 _mm_mul_pd(_mm_unpackhi_pd(pxy, pxy), uy)),
                                      _mm_mul_pd(_mm_set1_pd(pz), uz));
        sum = _mm_add_pd(sum, uv);
        squares = _mm_add_pd(squares, _mm_mul_pd(uv, uv));
        cuv += _mm_cvtsd_f64(uv) * _mm_cvtsd_f64(_mm_unpackhi_pd(uv, uv));
    }
    double lanes[2];
    _mm_storeu_pd(lanes, sum);
    m.mu = lanes[0];
    m.mv = lanes[1];
    _mm_storeu_pd(lanes, squares);
    m.cuu = lanes[0];
    m.cvv = lanes[1];
    m.cuv = cuv;
#else
    for (std::int32_t i = 0; i < count; ++i) {
        const Vec3 p = corner[i] - center;
        const double pu = dot(p, u), pv = dot(p, v);
        m.mu += pu;
        m.mv += pv;
        m.cuu += pu * pu;
        m.cvv += pv * pv;
        m.cuv += pu * pv;
    }
#endif
    return m;
}

// The componentwise extremes of axes * p over the points p = point[index[i]], i in [0, count)
// (as min3 and max3 take them: the first of equal values kept).
void projection_extremes(const Vec3* point, const std::int32_t* index, std::int32_t count, const Mat3& axes,
                         Vec3& low, Vec3& high) {
#if defined(__SSE2__)
    // Rows 0 and 1 in the two lanes, each computed as Mat3 * Vec3 computes it,
    // ((m0 x + m1 y) + m2 z), row 2 scalar. `_mm_min_pd(p, low)` is p < low ? p : low per
    // lane, min3's choice (and max3's likewise).
    const __m128d c0 = _mm_set_pd(axes.m[1][0], axes.m[0][0]);
    const __m128d c1 = _mm_set_pd(axes.m[1][1], axes.m[0][1]);
    const __m128d c2 = _mm_set_pd(axes.m[1][2], axes.m[0][2]);
    __m128d low01 = _mm_set1_pd(kInf), high01 = _mm_set1_pd(-kInf);
    double low2 = kInf, high2 = -kInf;
    for (std::int32_t i = 0; i < count; ++i) {
        const double* q = &point[index[i]].x;
        const __m128d x = _mm_set1_pd(q[0]), y = _mm_set1_pd(q[1]), z = _mm_set1_pd(q[2]);
        const __m128d p01 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(c0, x), _mm_mul_pd(c1, y)), _mm_mul_pd(c2, z));
        const double p2 = axes.m[2][0] * q[0] + axes.m[2][1] * q[1] + axes.m[2][2] * q[2];
        low01 = _mm_min_pd(p01, low01);
        high01 = _mm_max_pd(p01, high01);
        low2 = p2 < low2 ? p2 : low2;
        high2 = p2 > high2 ? p2 : high2;
    }
    double lanes[2];
    _mm_storeu_pd(lanes, low01);
    low = {lanes[0], lanes[1], low2};
    _mm_storeu_pd(lanes, high01);
    high = {lanes[0], lanes[1], high2};
#else
    low = {kInf, kInf, kInf};
    high = {-kInf, -kInf, -kInf};
    for (std::int32_t i = 0; i < count; ++i) {
        const Vec3 p = axes * point[index[i]];
        low = min3(low, p);
        high = max3(high, p);
    }
#endif
}

}  // namespace

// Children follow their parent in depth-first order, so a reverse sweep meets every child
// before its parent. A leaf's radius is exact; an internal node's is the smaller of two valid
// bounds: the children's spheres seen from the centre, and the farthest corner of the box.
// A child's moment moves to the parent's centre by the parallel-axis shift
// M + N (c_child - c)^T.
void MeshBvh::build_winding_nodes() {
    winding_nodes_.assign(nodes_.size(), WindingNode{});
    for (size_t id = nodes_.size(); id-- > 0;) {
        const BvhNode& node = nodes_[id];
        WindingNode& w = winding_nodes_[id];
        const Vec3 lo{node.lower[0], node.lower[1], node.lower[2]};
        const Vec3 hi{node.upper[0], node.upper[1], node.upper[2]};
        const Vec3 box_center = (lo + hi) * 0.5;
        if (node.is_leaf()) {
            Vec3 weighted{0.0, 0.0, 0.0};
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const Vec3* t = triangle(i);
                const Vec3 area_vector = cross(t[1] - t[0], t[2] - t[0]) * 0.5;
                const double area = norm(area_vector);
                w.dipole += area_vector;
                w.area += area;
                weighted += (t[0] + t[1] + t[2]) * (area / 3.0);
            }
            w.center = w.area > 0.0 ? weighted / w.area : box_center;
            if (!is_finite(w.center)) {
                // Zero or overflowing areas, or float boxes beyond the float range: the mean
                // of the corners (divided first, so it cannot overflow).
                w.center = Vec3{0.0, 0.0, 0.0};
                const double share = 1.0 / (3.0 * node.count);
                for (std::int32_t i = node.index; i < node.index + node.count; ++i)
                    for (int k = 0; k < 3; ++k) w.center += triangle(i)[k] * share;
            }
            if (!std::isfinite(w.area) || !is_finite(w.dipole)) {
                // Coordinates beyond about 1e154 overflow the areas: such a node is never
                // approximated (an infinite area makes its error bound infinite).
                w.area = kInf;
                w.dipole = Vec3{0.0, 0.0, 0.0};
            }
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const Vec3* t = triangle(i);
                add_moment(w.moment, cross(t[1] - t[0], t[2] - t[0]) * 0.5, (t[0] + t[1] + t[2]) / 3.0 - w.center);
                for (int k = 0; k < 3; ++k) w.radius = std::fmax(w.radius, norm(t[k] - w.center));
            }
            continue;
        }
        const WindingNode& l = winding_nodes_[id + 1];
        const WindingNode& r = winding_nodes_[static_cast<size_t>(node.index)];
        w.dipole = l.dipole + r.dipole;
        w.area = l.area + r.area;
        w.center = w.area > 0.0 ? (l.center * l.area + r.center * r.area) / w.area : box_center;
        if (!is_finite(w.center)) w.center = l.center * 0.5 + r.center * 0.5;
        if (!std::isfinite(w.area) || !is_finite(w.dipole)) {
            w.area = kInf;
            w.dipole = Vec3{0.0, 0.0, 0.0};
        }
        for (const WindingNode* child : {&l, &r}) {
            for (int k = 0; k < 6; ++k) w.moment[k] += child->moment[k];
            add_moment(w.moment, child->dipole, child->center - w.center);
        }
        const double from_children = std::fmax(norm(l.center - w.center) + l.radius, norm(r.center - w.center) + r.radius);
        const Vec3 far_corner{std::fmax(hi.x - w.center.x, w.center.x - lo.x), std::fmax(hi.y - w.center.y, w.center.y - lo.y),
                              std::fmax(hi.z - w.center.z, w.center.z - lo.z)};
        w.radius = std::fmin(from_children, norm(far_corner));
    }
}

std::pair<std::int32_t, std::int32_t> MeshBvh::triangle_range(std::int32_t id) const {
    // In depth-first order a node's triangles run from its leftmost leaf to its rightmost one.
    size_t first = static_cast<size_t>(id), last = static_cast<size_t>(id);
    while (!nodes_[first].is_leaf()) ++first;
    while (!nodes_[last].is_leaf()) last = static_cast<size_t>(nodes_[last].index);
    return {nodes_[first].index, nodes_[last].index + nodes_[last].count};
}

// Per node: axes from the mean normal (the dipole) and, in the tangent plane, the principal
// directions of the corners (a 2x2 eigenproblem in closed form); extents by projecting the
// node's distinct vertices. The axis-aligned box is kept when it is no larger (by volume), as
// for a node whose normals cancel.
//
// The nodes are fitted children first (a reverse sweep of the depth-first order), each
// node's distinct vertices (corner_vertices_, each once, in the order of its corners' first
// appearance) made from its children's: the left child's list, then the right child's
// vertices the left one lacks. The lists live on a stack: a reverse depth-first sweep finishes
// a node's right subtree, then its left one, so the left child's list is on top, the right
// child's under it. The extremes of the projections over those vertices are the extremes over
// the corners, bit for bit: a vertex projects alike at each of its corners, and the first
// corner that reaches an extreme is its vertex's first appearance (so even of a +0 and a -0
// the same one is kept). A closed mesh has about half as many vertices as triangles, so a
// node projects about a sixth of its corners, its rim counted in (the corner passes were 16%
// of a build: benchmarks/RESULTS.md, session 30, branch bvh20).
void MeshBvh::build_obbs() {
    obbs_.assign(nodes_.size(), NodeObb{});
    // The exact (double) axis-aligned boxes, children before parents.
    std::vector<Box> exact(nodes_.size());
    // The stack of lists, one after another, and where each starts: at most the corners of
    // disjoint subtrees, so 3n entries; `merged` is a node's list while it is made. The
    // tests of `seen` pick an entry by advancing past it or not (no branch to mispredict).
    std::vector<std::int32_t> distinct(corner_vertices_.size()), merged(corner_vertices_.size());
    std::vector<std::int32_t> list_start;
    size_t top = 0;
    // seen[v] == node: v is already on that node's list.
    std::vector<std::int32_t> seen(vertices_.size(), -1);
    for (size_t id = nodes_.size(); id-- > 0;) {
        const BvhNode& node = nodes_[id];
        const auto mark = static_cast<std::int32_t>(id);
        if (node.is_leaf()) {
            for (std::int32_t t = node.index; t < node.index + node.count; ++t)
                for (int k = 0; k < 3; ++k) exact[id].grow(triangle(t)[k]);
            list_start.push_back(static_cast<std::int32_t>(top));
            const std::int32_t* corner = triangle_vertices(node.index);
            for (std::int32_t k = 0; k < 3 * node.count; ++k) {
                const std::int32_t v = corner[k];
                distinct[top] = v;
                top += seen[static_cast<size_t>(v)] != mark;
                seen[static_cast<size_t>(v)] = mark;
            }
        } else {
            exact[id].grow(exact[id + 1]);
            exact[id].grow(exact[static_cast<size_t>(node.index)]);
            const auto left = static_cast<size_t>(list_start.back());
            list_start.pop_back();
            const auto right = static_cast<size_t>(list_start.back());
            size_t m = 0;
            for (size_t k = left; k < top; ++k) {
                const std::int32_t v = distinct[k];
                seen[static_cast<size_t>(v)] = mark;
                merged[m++] = v;
            }
            for (size_t k = right; k < left; ++k) {
                const std::int32_t v = distinct[k];
                merged[m] = v;
                m += seen[static_cast<size_t>(v)] != mark;
            }
            for (size_t k = 0; k < m; ++k) distinct[right + k] = merged[k];
            top = right + m;
        }
        NodeObb& box = obbs_[id];
        const Vec3 lo = exact[id].lower, hi = exact[id].upper;
        const double scale = std::fmax(max_abs(lo), max_abs(hi));
        // Rounding of the projections here and of the bounds that use them: a relative pad.
        const double pad = 1e-12 * scale + 1e-300;
        box.axes = Mat3::identity();
        box.center = lo * 0.5 + hi * 0.5;
        box.half = (hi * 0.5 - lo * 0.5) + Vec3{pad, pad, pad};
        const WindingNode& w = winding_nodes_[id];
        const double dipole = norm(w.dipole);
        if (!(dipole > 0.5 * w.area)) continue;
        const Vec3 n = w.dipole / dipole;
        const Vec3 helper = std::fabs(n.x) <= std::fabs(n.y) && std::fabs(n.x) <= std::fabs(n.z)
                                ? Vec3{1, 0, 0}
                                : (std::fabs(n.y) <= std::fabs(n.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
        Vec3 u = cross(n, helper);
        u = u / norm(u);
        Vec3 v = cross(n, u);
        const auto [begin, end] = triangle_range(static_cast<std::int32_t>(id));
        const std::int32_t corners = 3 * (end - begin);
        const TangentMoments t = tangent_moments(triangle(begin), corners, w.center, u, v);
        const double count = corners;
        const double mu = t.mu / count, mv = t.mv / count;
        const double cuu = t.cuu / count - mu * mu;
        const double cvv = t.cvv / count - mv * mv;
        const double cuv = t.cuv / count - mu * mv;
        double angle = 0.5 * std::atan2(2.0 * cuv, cuu - cvv);
        if (!std::isfinite(angle)) angle = 0.0;  // squares beyond the double range
        const double c = std::cos(angle), s = std::sin(angle);
        const Vec3 u2 = u * c + v * s;
        v = cross(n, u2);
        u = u2;
        Mat3 axes;
        for (int k = 0; k < 3; ++k) {
            axes.m[0][k] = n[k];
            axes.m[1][k] = u[k];
            axes.m[2][k] = v[k];
        }
        Vec3 low, high;
        const std::int32_t* list = distinct.data() + list_start.back();
        projection_extremes(vertices_.data(), list, static_cast<std::int32_t>(top) - list_start.back(), axes, low, high);
        const Vec3 half = (high * 0.5 - low * 0.5) + Vec3{pad, pad, pad};
        if (half.x * half.y * half.z < box.half.x * box.half.y * box.half.z) {
            box.axis_aligned = false;
            box.axes = axes;
            box.center = axes.transpose_times(low * 0.5 + high * 0.5);
            box.half = half;
        }
    }
}

namespace {
bool same_point(const Vec3& p, const Vec3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; }
}  // namespace

bool MeshBvh::validate() const {
    if (nodes_.empty()) return corners_.empty() && face_index_.empty();
    const std::int32_t n = triangle_count();
    if (corners_.size() != 3 * static_cast<size_t>(n) || corner_vertices_.size() != corners_.size()) return false;
    for (size_t k = 0; k < corners_.size(); ++k) {
        const std::int32_t v = corner_vertices_[k];
        if (v < 0 || static_cast<size_t>(v) >= vertices_.size() || !same_point(vertices_[static_cast<size_t>(v)], corners_[k]))
            return false;
    }
    // Every triangle's kept box is the descents' box of its corners, to the bit.
    if (bounds_.size() != 2 * static_cast<size_t>(n)) return false;
    for (std::int32_t i = 0; i < n; ++i) {
        const mesh_detail::TriangleBox box = mesh_detail::triangle_box(triangle(i));
        const Vec3* kept = triangle_bounds(i);
        if (std::memcmp(&box.lower, &kept[0], sizeof(Vec3)) != 0 || std::memcmp(&box.upper, &kept[1], sizeof(Vec3)) != 0)
            return false;
    }
    if (capsules_.size() != static_cast<size_t>(n)) return false;
    for (std::int32_t i = 0; i < n; ++i) {
        // Every corner within the capsule's radius of its spine (the spine's own ends at 0).
        const TriangleCapsule& c = capsules_[static_cast<size_t>(i)];
        if (c.edge < 0 || c.edge > 2 || !(c.radius >= 0.0)) return false;
        if (c.radius == kInf) continue;  // overflowing lengths: a capsule that bounds nothing
        const Vec3* t = triangle(i);
        const Vec3& p = t[(c.edge + 2) % 3];
        if (!(std::sqrt(segment_closest_points(p, p, t[c.edge], t[(c.edge + 1) % 3]).squared_distance) <= c.radius))
            return false;
    }
    std::vector<char> seen(static_cast<size_t>(n), 0);
    for (std::int32_t i = 0; i < n; ++i) {
        const std::int64_t f = face_index_[static_cast<size_t>(i)];
        if (f < 0 || f >= n || seen[static_cast<size_t>(f)]) return false;
        seen[static_cast<size_t>(f)] = 1;
    }
    auto contains = [](const BvhNode& box, const float lo[3], const float hi[3]) {
        for (int k = 0; k < 3; ++k)
            if (lo[k] < box.lower[k] || hi[k] > box.upper[k]) return false;
        return true;
    };
    // Walk depth-first: leaves must cover [0, n) in order, children must follow the layout.
    std::int32_t next_triangle = 0;
    std::vector<std::int32_t> stack{0};
    std::int32_t visited = 0;
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        if (id < 0 || id >= static_cast<std::int32_t>(nodes_.size())) return false;
        ++visited;
        const BvhNode& node = nodes_[static_cast<size_t>(id)];
        for (int k = 0; k < 3; ++k)
            if (!(node.lower[k] <= node.upper[k])) return false;
        if (node.is_leaf()) {
            if (node.count > defaults::mesh_bvh_leaf_size || node.index != next_triangle) return false;
            for (std::int32_t t = node.index; t < node.index + node.count; ++t)
                for (int c = 0; c < 3; ++c) {
                    const Vec3& p = corners_[3 * static_cast<size_t>(t) + c];
                    for (int k = 0; k < 3; ++k)
                        if (p[k] < node.lower[k] || p[k] > node.upper[k]) return false;
                }
            next_triangle += node.count;
            continue;
        }
        if (node.count != 0 || node.index <= id + 1) return false;
        const std::int32_t left = id + 1, right = node.index;
        if (right >= static_cast<std::int32_t>(nodes_.size())) return false;
        const BvhNode& l = nodes_[static_cast<size_t>(left)];
        const BvhNode& r = nodes_[static_cast<size_t>(right)];
        if (!contains(node, l.lower, l.upper) || !contains(node, r.lower, r.upper)) return false;
        stack.push_back(right);
        stack.push_back(left);
    }
    if (next_triangle != n || visited != static_cast<std::int32_t>(nodes_.size())) return false;
    // Far-field data: every corner under a node within its radius (a relative slack for the
    // rounding of the distances), areas adding up.
    if (winding_nodes_.size() != nodes_.size() || obbs_.size() != nodes_.size()) return false;
    for (size_t id = 0; id < nodes_.size(); ++id) {
        const WindingNode& w = winding_nodes_[id];
        if (!(w.radius >= 0.0) || !(w.area >= 0.0) || !(norm(w.dipole) <= w.area * (1.0 + 1e-12) + 1e-300)) return false;
        const NodeObb& box = obbs_[id];
        // The pair tests skip the products with an axis-aligned box's axes: they must be the
        // identity, exactly.
        if (box.axis_aligned)
            for (int i = 0; i < 3; ++i)
                for (int k = 0; k < 3; ++k)
                    if (box.axes.m[i][k] != (i == k ? 1.0 : 0.0)) return false;
        const auto [begin, end] = triangle_range(static_cast<std::int32_t>(id));
        for (std::int32_t t = begin; t < end; ++t)
            for (int c = 0; c < 3; ++c) {
                const Vec3& p = corners_[3 * static_cast<size_t>(t) + c];
                if (norm(p - w.center) > w.radius * (1.0 + 1e-12)) return false;
                const Vec3 local = box.axes * (p - box.center);
                for (int k = 0; k < 3; ++k)
                    if (!(std::fabs(local[k]) <= box.half[k])) return false;
            }
    }
    return true;
}

}  // namespace meshcol
