// The exact hull of a point set (hull.hpp): screened, sorted and deduplicated, then by its
// dimension: Quickhull's triangulation (quickhull.cpp) with its coplanar planes merged, a
// 2-D hull by the monotone chain, a segment or a point.
#include <algorithm>
#include <array>
#include <climits>
#include <cstring>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "hull_detail.hpp"
#include "jacobi.hpp"

namespace meshcol {
namespace hull_detail {

void principal_axes(const Vec3* p, long long n, const Vec3& centre, Vec3 axes[3]) {
    // The covariance's six distinct sums (d[r] * d[c] and d[c] * d[r] are the same product,
    // added in the same order: the mirrored entries are the same bits).
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
    for (long long i = 0; i < n; ++i) {
        const Vec3 d = p[i] - centre;
        xx += d.x * d.x, xy += d.x * d.y, xz += d.x * d.z;
        yy += d.y * d.y, yz += d.y * d.z, zz += d.z * d.z;
    }
    double a[3][3] = {{xx, xy, xz}, {xy, yy, yz}, {xz, yz, zz}};
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = std::fabs(a[0][1]) + std::fabs(a[0][2]) + std::fabs(a[1][2]);
        const double diag = std::fabs(a[0][0]) + std::fabs(a[1][1]) + std::fabs(a[2][2]);
        if (off <= 1e-30 * diag || off == 0.0) break;
        for (int r = 0; r < 2; ++r)
            for (int c = r + 1; c < 3; ++c) {
                if (a[r][c] == 0.0) continue;
                jacobi_rotate(a, v, r, c, 3);
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

int flatness_dimension(const Vec3* p, long long n, const Vec3& centre, const Vec3 axes[3],
                       double diagonal) {
    // The three widths in one pass.
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (long long i = 0; i < n; ++i) {
        const Vec3 d = p[i] - centre;
        for (int k = 0; k < 3; ++k) {
            const double t = dot(d, axes[k]);
            low[k] = t < low[k] ? t : low[k];
            high[k] = t > high[k] ? t : high[k];
        }
    }
    int dim = 0;
    for (int k = 0; k < 3; ++k)
        if (high[k] - low[k] > defaults::flat_relative_tolerance * diagonal) ++dim;
    return dim;
}

// For a unit u along which the points span a width w, write each edge from the first corner
// as e_i = (e_i . u) u + f_i, f_i orthogonal to u, |e_i . u| <= w: the determinant is
// trilinear and vanishes on three vectors of a plane or on u twice, so |det| <= 3 w D^2 (D the
// points' diameter, at most the diagonal), and w >= |det| / (3 D^2). The margins: the points
// are scaled below 1, so det rounds by under 1e-13 and a rule's width (along axes of unit
// length within rounding) by under 1e-14; the factor 2 covers the rounded diagonal.
bool clearly_solid(const Vec3* p, const int corner[4], double diagonal) {
    const Vec3 a = p[corner[0]];
    const double det = dot(p[corner[1]] - a, cross(p[corner[2]] - a, p[corner[3]] - a));
    const double width = defaults::flat_relative_tolerance * diagonal + 1e-12;
    return std::fabs(det) > 2.0 * 3.0 * diagonal * diagonal * width + 1e-12;
}

bool clearly_solid_among(const Vec3* p, const int* candidate, int count, double diagonal) {
    for (int i = 0; i < count; ++i)
        for (int j = i + 1; j < count; ++j)
            for (int k = j + 1; k < count; ++k)
                for (int l = k + 1; l < count; ++l) {
                    const int corner[4] = {candidate[i], candidate[j], candidate[k], candidate[l]};
                    if (clearly_solid(p, corner, diagonal)) return true;
                }
    return false;
}

namespace {

int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

void planes_of(Workspace& w, const Triangulation& t, Planes& out) {
    const size_t m = t.tri.size();
    // The triangles' planes are Quickhull's (t.normal, t.offset, t.area2).
    // Neighbours are coplanar when each one's far corner lies within eps of the other's
    // plane; coplanar groups are the connected components (one plane, one SAT normal).
    // The union-find's parents are set up at the first merge (a smooth hull has none).
    std::vector<int>& parent = w.parent;
    constexpr int kFar[3] = {2, 0, 1};  // the corner opposite edge e
    bool merged = false;
    // Raw pointers: the merge's calls would otherwise make the loop reload every vector's.
    const std::array<int, 3>* tri = t.tri.data();
    const Vec3* normal = t.normal.data();
    const double* offset = t.offset.data();
    const Vec3* p = w.p.data();
    const double eps = w.eps;
    for (const TriangulationEdge& g : t.edges) {
        if (g.k < 0) continue;
        const int i = g.i, j = g.j;
        const int far_i = tri[i][kFar[g.e]], far_j = tri[j][kFar[g.k]];
        const bool coplanar = std::fabs(dot(normal[i], p[far_j]) - offset[i]) <= eps &&
                              std::fabs(dot(normal[j], p[far_i]) - offset[j]) <= eps;
        if (!coplanar) continue;
        if (!merged) {
            parent.resize(m);
            std::iota(parent.begin(), parent.end(), 0);
            merged = true;
        }
        parent[find_root(parent, j)] = find_root(parent, i);
    }
    out.group.resize(m);
    if (!merged) {  // every triangle its own plane (a smooth hull): the groups in order
        std::iota(out.group.begin(), out.group.end(), 0);
        out.groups = static_cast<int>(m);
        return;
    }
    std::vector<int>& id = w.id;
    id.assign(m, -1);
    out.groups = 0;
    for (size_t i = 0; i < m; ++i) {
        const int r = find_root(parent, static_cast<int>(i));
        if (id[r] < 0) id[r] = out.groups++;
        out.group[i] = id[r];
    }
}

bool lexicographic_less(const Vec3& a, const Vec3& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

#if defined(__SSE2__)
// count_below for the W points x[i .. i + W): each load of two x[j] compared with all W, in
// SSE2 lanes (a lane's compare is the scalar one). A true compare is all ones, -1:
// subtracted, it counts. W is a constant, so the loops over it unroll.
template <size_t W>
void count_below_block(const double* x, size_t n, size_t i, int* below) {
    const size_t pairs = n & ~size_t{1};
    __m128d at[W];
    __m128i count[W];
    for (size_t w = 0; w < W; ++w) {
        at[w] = _mm_set1_pd(x[i + w]);
        count[w] = _mm_setzero_si128();
    }
    for (size_t j = 0; j < pairs; j += 2) {
        const __m128d v = _mm_loadu_pd(x + j);
        for (size_t w = 0; w < W; ++w)
            count[w] = _mm_sub_epi64(count[w], _mm_castpd_si128(_mm_cmplt_pd(v, at[w])));
    }
    for (size_t w = 0; w < W; ++w) {
        std::int64_t lanes[2];
        _mm_storeu_si128(reinterpret_cast<__m128i*>(lanes), count[w]);
        std::int64_t total = lanes[0] + lanes[1];
        if (pairs < n) total += x[pairs] < x[i + w];
        below[i + w] = static_cast<int>(total);
    }
}
#endif

// How many of x[0 .. n) are below each x[i], into below[i]: every pair compared, four (then
// two) x[i] at a time (count_below_block), no branch on the data.
void count_below(const double* x, size_t n, int* below) {
    size_t i = 0;
#if defined(__SSE2__)
    for (; i + 3 < n; i += 4) count_below_block<4>(x, n, i, below);
    for (; i + 1 < n; i += 2) count_below_block<2>(x, n, i, below);
#endif
    for (; i < n; ++i) {
        int count = 0;
        for (size_t j = 0; j < n; ++j) count += x[j] < x[i];
        below[i] = count;
    }
}

// The keys w.sort_keys of the points (hull_with's: x's bits as an ordered integer, and the
// index), their x in w.sort_x, in the lexicographic order of the points (ties by index), a
// strict total order: any correct sort gives the one answer. Small sets by rank: each point's
// place is how many x are below its own (count_below), then each run of equal x, if any, by
// std::sort. std::sort alone mispredicts about one comparison in three (175 branches a
// 64-point set); the quadratic count costs less up to kRankSortMaxPoints points.
const SortKey* sort_points(const Vec3* points, Workspace& w) {
    std::vector<SortKey>& keys = w.sort_keys;
    const size_t n = keys.size();
    auto less = [points](const SortKey& a, const SortKey& b) {
        if (a.x != b.x) return a.x < b.x;
        const Vec3& p = points[a.index];
        const Vec3& q = points[b.index];
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return a.index < b.index;
    };
    if (n > kRankSortMaxPoints) {
        std::sort(keys.begin(), keys.end(), less);
        return keys.data();
    }
    int below[kRankSortMaxPoints], taken[kRankSortMaxPoints];
    count_below(w.sort_x.data(), n, below);
    std::fill(taken, taken + n, 0);
    std::vector<SortKey>& sorted = w.sorted_keys;
    sorted.resize(n);
    // Points of equal x share a count: they fill its run in index order (a count taken twice
    // says there is such a run; without one, the order is complete).
    int shared = 0;
    for (size_t i = 0; i < n; ++i) {
        const int place = below[i];
        shared |= taken[place];
        sorted[static_cast<size_t>(place + taken[place]++)] = keys[i];
    }
    if (shared == 0) return sorted.data();
    for (size_t first = 0; first + 1 < n;) {
        size_t last = first + 1;
        while (last < n && sorted[last].x == sorted[first].x) ++last;
        if (last - first > 1) std::sort(sorted.begin() + first, sorted.begin() + last, less);
        first = last;
    }
    return sorted.data();
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

// The points scaled by a power of two into (-1, 1)^3 (w.p) and what hull_with's pass that
// wrote them found: the scale's exponent, their bounding box and their sum.
struct Scaled {
    double max_abs = 0.0;  // of the points, before scaling
    int exponent = 0;
    Vec3 lo, hi, sum;  // scaled
    int extreme[6] = {0, 0, 0, 0, 0, 0};  // axis_extremes of all the points (the box's corners)
};

// The hull of points already checked finite and in range, w.p holding them scaled.
void compute(const Vec3* points, long long n, const Scaled& scaled, Workspace& w,
             Analysis& analysis) {
    Hull& hull = analysis.hull;
    const int exponent = scaled.exponent;
    const Vec3 lo = scaled.lo, hi = scaled.hi, sum = scaled.sum;
    w.eps = defaults::hull_relative_tolerance * std::ldexp(scaled.max_abs, -exponent);
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
    // The flatness rule: widths along the principal axes against the diagonal. The axes are
    // found when a rule needs them (the same bits whenever).
    const Vec3 centre = sum / static_cast<double>(n);
    Vec3 axes[3];
    bool have_axes = false;
    auto principal = [&]() {
        if (!have_axes) principal_axes(w.p.data(), n, centre, axes);
        have_axes = true;
    };
    // The axis extremes first, when Quickhull starts from them (the interior filter leaves
    // the input whole): when four of them are clearly solid, the rule can only find 3-D and
    // runs without the axes, and Quickhull's starting tetrahedron is found from them here.
    int extreme[6], start[4];
    bool solid = false;
    if (n >= 4 && static_cast<size_t>(n) < kFilterMinPoints) {
        std::copy(scaled.extreme, scaled.extreme + 6, extreme);  // axis_extremes(w.p, all)
        solid = clearly_solid_among(w.p.data(), extreme, 6, diagonal);
    }
    const bool started =
        solid && start_tetrahedron(w.p, w.eps, all, extreme, start) == Build::OK;
    int dim = 3;
    if (!solid) {
        principal();
        dim = flatness_dimension(w.p.data(), n, centre, axes, diagonal);
    }
    if (dim == 3) {
        Triangulation& t = analysis.t;
        Triangulation& previous = analysis.previous;
        Planes& pl = analysis.pl;
        std::vector<int>& subset = w.subset;
        subset = all;
        bool have = false, planes_current = false;
        std::vector<int>& removed = w.removed;  // the vertices a rerun leaves out
        std::vector<int>& dropped = w.dropped;
        removed.clear();
        for (int run = 0; run <= defaults::hull_max_reruns; ++run) {
            const Build b = quickhull(w, subset, t, run == 0 && started ? start : nullptr);
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
                        holds = dot(t.normal[i], w.p[removed[k]]) - t.offset[i] <= 4.0 * w.eps;
                if (!holds) {
                    t = previous;
                    planes_current = false;
                    break;
                }
            }
            have = true;
            // Every triangle its own plane (a smooth hull): every edge is between two planes,
            // and every vertex of a triangulated sphere has at least three edges, so none is
            // left out below.
            if (pl.groups == static_cast<int>(t.tri.size())) break;
            // A vertex with at most two edges between different planes lies on an edge or
            // in a face of its hull (a coplanar tie Quickhull took first): hull again
            // without those.
            std::vector<int>& real = w.real;
            std::vector<char>& used = w.used;
            real.assign(static_cast<size_t>(n), 0);
            used.assign(static_cast<size_t>(n), 0);
            for (const auto& tri : t.tri) used[tri[0]] = used[tri[1]] = used[tri[2]] = 1;
            for (const TriangulationEdge& g : t.edges) {
                const int between = pl.group[g.i] != pl.group[g.j];  // no branch: no pattern
                real[t.tri[g.i][g.e]] += between;
                real[t.tri[g.i][kNextCorner[g.e]]] += between;
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
            // The points are in lexicographic order: the used ones in index order are.
            std::vector<int>& verts = hull.vertices;
            std::vector<int>& local = w.local;
            local.assign(static_cast<size_t>(n), -1);
            for (const auto& tri : t.tri)
                for (int v : tri) local[v] = 0;
            verts.resize(static_cast<size_t>(n));
            int* vertex = verts.data();
            int k = 0;
            for (long long i = 0; i < n; ++i)
                if (local[i] == 0) {
                    local[i] = k;
                    vertex[k++] = static_cast<int>(i);
                }
            verts.resize(static_cast<size_t>(k));
            const size_t m = t.tri.size();
            if (analysis.geometry) {  // the packing reads t.tri through w.local instead
                hull.faces.resize(m);
                for (size_t i = 0; i < m; ++i) {
                    const auto& tri = t.tri[i];
                    hull.faces[i] = {local[tri[0]], local[tri[1]], local[tri[2]]};
                }
            }
            // Each plane's normal is that of its largest triangle; a plane per triangle
            // (groups in triangle order, planes_of) is the triangles' normals (which the
            // packing reads from t.normal).
            if (pl.groups == static_cast<int>(m)) {
                if (analysis.geometry) hull.plane_normals.assign(t.normal.begin(), t.normal.end());
            } else {
                hull.plane_normals.assign(static_cast<size_t>(pl.groups), Vec3{});
                std::vector<double>& largest = w.largest;
                largest.assign(static_cast<size_t>(pl.groups), -1.0);
                for (size_t i = 0; i < m; ++i) {
                    const int g = pl.group[i];
                    if (t.area2[i] > largest[g]) {
                        largest[g] = t.area2[i];
                        hull.plane_normals[g] = t.normal[i];
                    }
                }
            }
            hull.status = HullStatus::OK;
            hull.dimension = 3;
            if (!analysis.geometry) return;
            hull.face_normals.resize(m);
            hull.face_offsets.resize(m);
            hull.face_planes = pl.group;
            double volume = 0.0, area = 0.0;
            const Vec3 origin = w.p[verts[0]];
            for (size_t i = 0; i < m; ++i) {
                const auto& tri = t.tri[i];
                hull.face_normals[i] = t.normal[i];
                hull.face_offsets[i] = -dot(t.normal[i], points[tri[0]]);
                area += t.area2[i];
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
        principal();
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
        principal();
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

}  // namespace

// The hull of `points` into analysis.hull (and its triangulation and planes, 3-D).
void hull_with(const Vec3* points, long long n, Workspace& w, Analysis& analysis) {
    analysis.reset();
    Hull& hull = analysis.hull;
    if (n <= 0) {
        hull.status = HullStatus::EMPTY;
        return;
    }
    if (n > INT_MAX) {  // point indices are ints
        hull.status = HullStatus::FAILED;
        return;
    }
    // Sorted, without exact duplicates (-0.0 as 0.0), the points give the same hull in any
    // order: equal point sets, equal triangulations (decomposition parts rely on it).
    // Sorted as 16-byte keys: x as an integer of the same order (the sign bit flipped for
    // positive numbers, every bit for negative ones; -0.0 is 0.0 by then), ties by y, z and
    // index. A total order: any sort gives the order of the comparison of whole points.
    // The same pass screens the points (non-finite: no hull; beyond the largest coordinate:
    // none either) and finds their largest coordinate, the scale's.
    std::vector<SortKey>& keys = w.sort_keys;
    keys.resize(static_cast<size_t>(n));
    std::vector<double>& sort_x = w.sort_x;
    sort_x.resize(static_cast<size_t>(n));
    double* xs = sort_x.data();
    bool finite = true, huge = false;
    double largest = 0.0;
    for (long long i = 0; i < n; ++i) {
        const Vec3& q = points[i];
        finite &= is_finite(q);
        // std::max, not fmax (a libm call here): the same for finite coordinates, and a
        // non-finite one has no hull whatever m is.
        const double m = std::max(std::fabs(q.x), std::max(std::fabs(q.y), std::fabs(q.z)));
        huge |= m > defaults::hull_max_abs_coordinate;
        largest = m > largest ? m : largest;
        const double x = q.x + 0.0;
        xs[i] = x;
        std::uint64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        constexpr std::uint64_t sign = std::uint64_t{1} << 63;
        keys[i] = {(bits & sign) ? ~bits : (bits | sign), static_cast<int>(i)};
    }
    if (!finite || huge) {
        hull.status = finite ? HullStatus::OVERFLOW : HullStatus::NON_FINITE;
        return;
    }
    hull.status = HullStatus::OK;
    const SortKey* order = sort_points(points, w);
    // The unique points in order, and in the same pass scaled into w.p by a power of two
    // (exact: the hull of the scaled points is the hull of the points; a duplicate has the
    // largest coordinate of its twin), with their bounding box, the first point at each of
    // its sides (axis_extremes's answer) and their sum.
    Scaled scaled;
    scaled.max_abs = largest;
    if (largest > 0.0) std::frexp(largest, &scaled.exponent);
    const double to_unit = std::ldexp(1.0, -scaled.exponent);
    const auto count = static_cast<size_t>(n);
    if (w.unique_points.size() < count) w.unique_points.resize(count);
    if (w.unique_index.size() < count) w.unique_index.resize(count);
    if (w.p.size() < count) w.p.resize(count);
    Vec3* unique = w.unique_points.data();
    int* index = w.unique_index.data();
    Vec3* p = w.p.data();
    const Vec3 zero{0.0, 0.0, 0.0};
    Vec3 lo = (points[order[0].index] + zero) * to_unit, hi = lo, sum{};
    int* extreme = scaled.extreme;  // all 0: the first point
    size_t m = 0;
    for (size_t i = 0; i < count; ++i) {
        const int k = order[i].index;
        const Vec3 q = points[k] + zero;
        if (m > 0 && !lexicographic_less(unique[m - 1], q)) continue;
        unique[m] = q;
        index[m] = k;
        const Vec3 s = q * to_unit;
        p[m] = s;
        // The components by name (Vec3's operator[] selects among them with compares); a
        // strict compare keeps the first of equal extremes, as axis_extremes does.
        const int at = static_cast<int>(m);
        const bool below_x = s.x < lo.x, above_x = s.x > hi.x;
        const bool below_y = s.y < lo.y, above_y = s.y > hi.y;
        const bool below_z = s.z < lo.z, above_z = s.z > hi.z;
        lo.x = below_x ? s.x : lo.x, extreme[0] = below_x ? at : extreme[0];
        hi.x = above_x ? s.x : hi.x, extreme[1] = above_x ? at : extreme[1];
        lo.y = below_y ? s.y : lo.y, extreme[2] = below_y ? at : extreme[2];
        hi.y = above_y ? s.y : hi.y, extreme[3] = above_y ? at : extreme[3];
        lo.z = below_z ? s.z : lo.z, extreme[4] = below_z ? at : extreme[4];
        hi.z = above_z ? s.z : hi.z, extreme[5] = above_z ? at : extreme[5];
        sum += s;
        ++m;
    }
    w.unique_points.resize(m);
    w.unique_index.resize(m);
    w.p.resize(m);
    scaled.lo = lo, scaled.hi = hi, scaled.sum = sum;
    compute(unique, static_cast<long long>(m), scaled, w, analysis);
    for (int& v : hull.vertices) v = index[v];
}

}  // namespace hull_detail

using hull_detail::Analysis;
using hull_detail::Workspace;

Hull exact_hull(const Vec3* points, long long n) {
    Workspace w;
    Analysis analysis;
    hull_with(points, n, w, analysis);
    return std::move(analysis.hull);
}

}  // namespace meshcol
