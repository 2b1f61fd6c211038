#include "meshcol/fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "meshcol/batch.hpp"
#include "jacobi.hpp"

namespace meshcol {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Small symmetric eigenproblems (cyclic Jacobi, Golub and Van Loan 8.5): principal axes and the
// least-squares centre of a degenerate Welzl support.

/// Eigen-decomposition of a symmetric m x m matrix (m <= 3): a = V diag(w) V^T, columns of
/// `v` the eigenvectors. Capped at 64 sweeps (it converges quadratically in a handful). The
/// size is a template argument: Welzl solves thousands of these a fit.
template <int m>
void jacobi(double a[3][3], double w[3], double v[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 64; ++sweep) {
        double off = 0.0, total = 0.0;
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j) {
                total += a[i][j] * a[i][j];
                if (i != j) off += a[i][j] * a[i][j];
            }
        if (!(off > 1e-32 * total)) break;
        for (int p = 0; p < m; ++p)
            for (int q = p + 1; q < m; ++q) {
                if (a[p][q] == 0.0) continue;
                jacobi_rotate(a, v, p, q, m);
            }
    }
    for (int i = 0; i < m; ++i) w[i] = a[i][i];
}

// ---------------------------------------------------------------------------------------------
// Minimum enclosing ball (Welzl 1991), any dimension up to 3

template <int d>
struct BallSearch {
    const double* p;  // n rows of d doubles, shuffled
    long long n;
    double tolerance;  // squared-distance slack of "outside" (rounding of one distance)
    long long work = 0, max_work = 0;
    bool capped = false;

    double squared_distance(long long i, const double c[3]) const {
        double s = 0.0;
        for (int k = 0; k < d; ++k) {
            const double e = p[i * d + k] - c[k];
            s += e * e;
        }
        return s;
    }

    /// The smallest ball with the support points on its boundary: centre in their affine
    /// hull (the least-squares, minimum-norm solution when they are degenerate).
    void through(const long long* support, int k, double c[3], double& r2) const {
        switch (k) {  // the support's size as a template argument (unrolled loops, same sums)
            case 1: return through_fixed<1>(support, c, r2);
            case 2: return through_fixed<2>(support, c, r2);
            case 3: return through_fixed<3>(support, c, r2);
            default: return through_fixed<4>(support, c, r2);
        }
    }

    template <int k>
    void through_fixed(const long long* support, double c[3], double& r2) const {
        const double* p0 = p + support[0] * d;
        for (int j = 0; j < 3; ++j) c[j] = j < d ? p0[j] : 0.0;
        r2 = 0.0;
        if constexpr (k > 1) {
            constexpr int m = k - 1;
            double a[3][3] = {}, gram[3][3] = {}, rhs[3] = {};
            for (int i = 0; i < m; ++i) {
                for (int j = 0; j < d; ++j) a[i][j] = p[support[i + 1] * d + j] - p0[j];
                for (int j = 0; j < d; ++j) rhs[i] += 0.5 * a[i][j] * a[i][j];
            }
            for (int i = 0; i < m; ++i)
                for (int j = 0; j < m; ++j)
                    for (int t = 0; t < d; ++t) gram[i][j] += a[i][t] * a[j][t];
            double w[3], v[3][3];
            jacobi<m>(gram, w, v);
            double largest = 0.0;
            for (int i = 0; i < m; ++i) largest = std::max(largest, std::fabs(w[i]));
            double coefficient[3] = {0.0, 0.0, 0.0};
            for (int e = 0; e < m; ++e) {
                if (!(std::fabs(w[e]) > 1e-12 * largest)) continue;  // pseudo-inverse
                double proj = 0.0;
                for (int i = 0; i < m; ++i) proj += v[i][e] * rhs[i];
                for (int i = 0; i < m; ++i) coefficient[i] += v[i][e] * proj / w[e];
            }
            for (int i = 0; i < m; ++i)
                for (int j = 0; j < d; ++j) c[j] += coefficient[i] * a[i][j];
            for (int i = 0; i < k; ++i) r2 = std::max(r2, squared_distance(support[i], c));
        }
    }

    long long first_outside(const double c[3], double r2, long long start, long long end) {
        const double limit = r2 + tolerance + 1e-12 * r2;
        for (long long i = start; i < end; ++i) {
            if (++work > max_work) {
                capped = true;
                return -1;
            }
            if (squared_distance(i, c) > limit) return i;
        }
        return -1;
    }

    void ball(long long end, long long* support, int k, double c[3], double& r2) {
        long long start = 0;
        if (k > 0) {
            through(support, k, c, r2);
        } else {
            for (int j = 0; j < 3; ++j) c[j] = j < d ? p[j] : 0.0;
            r2 = 0.0;
            start = 1;
        }
        if (k == d + 1) return;
        long long i = first_outside(c, r2, start, end);
        while (i >= 0) {
            support[k] = i;
            ball(i, support, k + 1, c, r2);
            i = first_outside(c, r2, i + 1, end);
        }
    }
};

std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/// The order the fixed-seed shuffle (Fisher-Yates) leaves `n` rows in: shuffled row i is
/// input row order[i]. Made once for a set whose projections are searched again and again.
std::vector<long long> shuffle_order(long long n) {
    std::vector<long long> order(static_cast<size_t>(std::max<long long>(n, 0)));
    std::iota(order.begin(), order.end(), 0LL);
    std::uint64_t state = defaults::fit_ball_seed;
    for (long long i = n - 1; i > 0; --i) {
        const long long j =
            static_cast<long long>(splitmix64(state) % static_cast<std::uint64_t>(i + 1));
        std::swap(order[static_cast<size_t>(i)], order[static_cast<size_t>(j)]);
    }
    return order;
}

template <int d>
bool ball_search(const double* rows, long long n, double tolerance, double center[3],
                 double& radius) {
    BallSearch<d> s{rows, n, tolerance};
    s.max_work = std::max<long long>(1, n) * defaults::fit_ball_max_work_per_point;
    long long support[4];
    double r2 = 0.0;
    s.ball(n, support, 0, center, r2);
    double largest = 0.0;
    for (long long i = 0; i < n; ++i) largest = std::max(largest, s.squared_distance(i, center));
    radius = std::sqrt(largest);
    return !s.capped;
}

/// Welzl on `n` rows of `d` doubles already in `shuffle_order`.
bool ball_of_shuffled(const double* rows, long long n, int d, double center[3], double& radius) {
    double scale = 0.0;
    for (long long i = 0; i < n; ++i)
        for (int k = 0; k < d; ++k) scale = std::max(scale, std::fabs(rows[i * d + k] - rows[k]));
    if (!(scale > 0.0)) scale = 1.0;
    const double tolerance = (1e-12 * scale) * (1e-12 * scale);
    switch (d) {
        case 1: return ball_search<1>(rows, n, tolerance, center, radius);
        case 2: return ball_search<2>(rows, n, tolerance, center, radius);
        default: return ball_search<3>(rows, n, tolerance, center, radius);
    }
}

/// Welzl on rows of `d` doubles, taken in `shuffle_order` (a fixed seed: deterministic).
bool ball_of(const std::vector<double>& rows, long long n, int d, double center[3],
             double& radius) {
    const std::vector<long long> order = shuffle_order(n);
    std::vector<double> shuffled(rows.size());
    for (long long i = 0; i < n; ++i)
        for (int k = 0; k < d; ++k)
            shuffled[i * d + k] = rows[order[static_cast<size_t>(i)] * d + k];
    return ball_of_shuffled(shuffled.data(), n, d, center, radius);
}

// ---------------------------------------------------------------------------------------------
// Frames

/// A right-handed rotation whose third column is the unit `axis` (world x where it can be).
Mat3 frame_of(const Vec3& axis) {
    const Vec3 z = axis / norm(axis);
    const Vec3 helper = std::fabs(z.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    Vec3 x = helper - dot(helper, z) * z;
    x = x / norm(x);
    const Vec3 y = cross(z, x);
    Mat3 r;
    for (int i = 0; i < 3; ++i) {
        r.m[i][0] = x[i];
        r.m[i][1] = y[i];
        r.m[i][2] = z[i];
    }
    return r;
}

Mat3 from_columns(const Vec3& a, const Vec3& b, const Vec3& c) {
    Mat3 r;
    for (int i = 0; i < 3; ++i) {
        r.m[i][0] = a[i];
        r.m[i][1] = b[i];
        r.m[i][2] = c[i];
    }
    return r;
}

/// exp([w]x) R (Rodrigues).
Mat3 turned(const Mat3& rotation, const double w[3]) {
    const double angle = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (angle == 0.0) return rotation;
    const double k[3] = {w[0] / angle, w[1] / angle, w[2] / angle};
    const double kx[3][3] = {{0, -k[2], k[1]}, {k[2], 0, -k[0]}, {-k[1], k[0], 0}};
    const double s = std::sin(angle), c1 = 1.0 - std::cos(angle);
    Mat3 turn;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double kk = 0.0;
            for (int t = 0; t < 3; ++t) kk += kx[i][t] * kx[t][j];
            turn.m[i][j] = (i == j ? 1.0 : 0.0) + s * kx[i][j] + c1 * kk;
        }
    return turn * rotation;
}

/// Principal axes of the points (descending variance), right-handed.
Mat3 principal_axes(const std::vector<Vec3>& p) {
    Vec3 mean;
    for (const auto& x : p) mean += x;
    mean = mean / static_cast<double>(p.size());
    double a[3][3] = {};
    for (const auto& x : p) {
        const Vec3 e = x - mean;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) a[i][j] += e[i] * e[j];
    }
    double w[3], v[3][3];
    jacobi<3>(a, w, v);
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int i, int j) { return w[i] > w[j]; });
    Vec3 c[3];
    for (int k = 0; k < 3; ++k) c[k] = {v[0][order[k]], v[1][order[k]], v[2][order[k]]};
    if (dot(cross(c[0], c[1]), c[2]) < 0) c[2] = -c[2];
    return from_columns(c[0], c[1], c[2]);
}

/// A derivative-free, monotone pattern search (coordinate steps, halved on failure) from x.
/// `cost(x, bound)` is the cost at x, or any value >= `bound` when the cost is >= `bound` (a
/// trial is only taken below the best so far: a proven lower bound can stand for it).
template <int K, class Cost>
std::array<double, K> polish(const Cost& cost, std::array<double, K> x, double step,
                             int iterations, double smallest, double& best) {
    best = cost(x, INFINITY);
    for (int it = 0; it < iterations; ++it) {
        bool improved = false;
        for (int k = 0; k < K; ++k)
            for (double sign : {1.0, -1.0}) {
                auto trial = x;
                trial[k] += sign * step;
                const double value = cost(trial, best);
                if (value < best) {
                    x = trial;
                    best = value;
                    improved = true;
                    break;
                }
            }
        if (!improved) {
            step *= 0.5;
            if (step < smallest) break;
        }
    }
    return x;
}

// ---------------------------------------------------------------------------------------------
// Boxes

double box_volume(const std::vector<Vec3>& p, const Mat3& r) {
    const Vec3 a = r.column(0), b = r.column(1), c = r.column(2);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const auto& x : p) {
        const double u[3] = {dot(x, a), dot(x, b), dot(x, c)};
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], u[k]);
            hi[k] = std::max(hi[k], u[k]);
        }
    }
    return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
}

double cross2(const std::array<double, 2>& o, const std::array<double, 2>& a,
              const std::array<double, 2>& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/// The convex polygon of 2-D points, counter-clockwise, collinear points dropped (Andrew's
/// monotone chain). Only candidate angles come from it: containment is the final growth's.
std::vector<std::array<double, 2>> polygon_2d(std::vector<std::array<double, 2>> q) {
    std::sort(q.begin(), q.end());
    q.erase(std::unique(q.begin(), q.end()), q.end());
    if (q.size() < 3) return q;
    std::vector<std::array<double, 2>> h(2 * q.size());
    size_t k = 0;
    for (size_t i = 0; i < q.size(); ++i) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], q[i]) <= 0) --k;
        h[k++] = q[i];
    }
    for (size_t i = q.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(h[k - 2], h[k - 1], q[i]) <= 0) --k;
        h[k++] = q[i];
    }
    h.resize(k - 1);
    return h;
}

/// Angle of the smallest-area rectangle around a convex polygon: one side lies along an
/// edge (Freeman and Shapira 1975), found by rotating calipers (Toussaint 1983) in O(m).
double min_area_rectangle_angle(const std::vector<std::array<double, 2>>& poly) {
    const size_t m = poly.size();
    if (m < 2) return 0.0;
    if (m == 2) return std::atan2(poly[1][1] - poly[0][1], poly[1][0] - poly[0][0]);
    auto along = [&](size_t i, double ux, double uy) {
        return poly[i % m][0] * ux + poly[i % m][1] * uy;
    };
    size_t right = 0, top = 0, left = 0;
    double best_area = INFINITY, best_angle = 0.0;
    for (size_t i = 0; i < m; ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % m];
        double ux = b[0] - a[0], uy = b[1] - a[1];
        const double len = std::hypot(ux, uy);
        if (!(len > 0.0)) continue;
        ux /= len;
        uy /= len;
        const double nx = -uy, ny = ux;  // inward normal of a counter-clockwise polygon
        if (i == 0) right = top = left = 1;
        // Each caliper only moves forward; each is capped at one turn per edge.
        for (size_t s = 0; s < m && along(right + 1, ux, uy) >= along(right, ux, uy); ++s) ++right;
        if (top < right) top = right;
        for (size_t s = 0; s < m && along(top + 1, nx, ny) >= along(top, nx, ny); ++s) ++top;
        if (left < top) left = top;
        for (size_t s = 0; s < m && along(left + 1, ux, uy) <= along(left, ux, uy); ++s) ++left;
        const double width = along(right, ux, uy) - along(left, ux, uy);
        const double height = along(top, nx, ny) - (a[0] * nx + a[1] * ny);
        const double area = width * height;
        if (area < best_area) {
            best_area = area;
            best_angle = std::atan2(uy, ux);
        }
    }
    return best_angle;
}

/// The frame with `normal` as z and the smallest rectangle of the projected points.
Mat3 normal_frame(const std::vector<Vec3>& p, const Vec3& normal) {
    const Mat3 f = frame_of(normal);
    const Vec3 fx = f.column(0), fy = f.column(1), z = f.column(2);
    std::vector<std::array<double, 2>> q(p.size());
    for (size_t i = 0; i < p.size(); ++i) q[i] = {dot(p[i], fx), dot(p[i], fy)};
    const double angle = min_area_rectangle_angle(polygon_2d(std::move(q)));
    const Vec3 x = std::cos(angle) * fx + std::sin(angle) * fy;
    return from_columns(x, cross(z, x), z);
}

/// Candidate axes of the box: the hull's plane normals (antiparallel ones merged, rounded to
/// 6 digits as one direction), by total area, the largest `fit_box_normals`.
std::vector<Vec3> box_normals(const std::vector<Vec3>& p, const Hull& hull) {
    std::vector<Vec3> out;
    if (hull.dimension == 2) {
        out.push_back(hull.normal);
        return out;
    }
    if (hull.dimension != 3) return out;
    std::vector<double> area(hull.plane_normals.size(), 0.0);
    for (size_t t = 0; t < hull.faces.size(); ++t) {
        const auto& f = hull.faces[t];
        const Vec3 c = cross(p[f[1]] - p[f[0]], p[f[2]] - p[f[0]]);
        area[hull.face_planes[t]] += norm(c);
    }
    struct Entry {
        std::array<double, 3> key;
        Vec3 normal;
        double area, own;
    };
    std::vector<Entry> e;
    for (size_t i = 0; i < area.size(); ++i) {
        Vec3 nrm = hull.plane_normals[i];
        if (nrm.z < 0 || (nrm.z == 0 && (nrm.y < 0 || (nrm.y == 0 && nrm.x < 0)))) nrm = -nrm;
        if (!is_finite(nrm) || !(area[i] > 0)) continue;
        e.push_back({{std::round(nrm.x * 1e6), std::round(nrm.y * 1e6), std::round(nrm.z * 1e6)},
                     nrm,
                     area[i],
                     area[i]});
    }
    std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
    std::vector<Entry> merged;
    for (const auto& x : e) {
        if (!merged.empty() && merged.back().key == x.key) {
            merged.back().area += x.area;
            if (x.own > merged.back().own) {
                merged.back().own = x.own;
                merged.back().normal = x.normal;
            }
        } else {
            merged.push_back(x);
        }
    }
    std::stable_sort(merged.begin(), merged.end(),
                     [](const Entry& a, const Entry& b) { return a.area > b.area; });
    const size_t keep = std::min<size_t>(merged.size(), defaults::fit_box_normals);
    for (size_t i = 0; i < keep; ++i) out.push_back(merged[i].normal);
    return out;
}

/// The best box frame: candidates (identity, principal axes, each normal's rectangle), the
/// best few polished; the first of the equal best (an axis-aligned box stays aligned).
Mat3 box_frame(const std::vector<Vec3>& p, const Hull& hull) {
    std::vector<Mat3> candidates = {Mat3::identity(), principal_axes(p)};
    for (const Vec3& nrm : box_normals(p, hull)) candidates.push_back(normal_frame(p, nrm));
    std::vector<double> volume(candidates.size());
    for (size_t i = 0; i < candidates.size(); ++i) volume[i] = box_volume(p, candidates[i]);
    std::vector<size_t> order(candidates.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return volume[a] < volume[b]; });
    Mat3 best = candidates[order[0]];
    double best_volume = volume[order[0]];
    size_t best_rank = order[0];
    const size_t starts = std::min<size_t>(order.size(), defaults::fit_box_polish_starts);
    for (size_t s = 0; s < starts; ++s) {
        const Mat3 start = candidates[order[s]];
        auto cost = [&](const std::array<double, 3>& w, double) {
            return box_volume(p, turned(start, w.data()));
        };
        double value = 0.0;
        const auto w = polish<3>(cost, {0.0, 0.0, 0.0}, defaults::fit_box_polish_step,
                                 defaults::fit_box_polish_iterations,
                                 defaults::fit_box_polish_smallest, value);
        // Strictly better beyond rounding, or as good and earlier among the candidates.
        const bool better = value < best_volume * (1 - 1e-9);
        const bool tie = value <= best_volume * (1 + 1e-9) && order[s] < best_rank;
        if (better || tie) {
            best = turned(start, w.data());
            best_volume = value;
            best_rank = order[s];
        }
    }
    return best;
}

// ---------------------------------------------------------------------------------------------
// Cylinders and capsules along an axis

Vec3 direction(const std::array<double, 2>& tp) {
    return {std::sin(tp[0]) * std::cos(tp[1]), std::sin(tp[0]) * std::sin(tp[1]),
            std::cos(tp[0])};
}

std::array<double, 2> angles(const Vec3& axis) {
    const Vec3 a = axis / norm(axis);
    return {std::acos(std::max(-1.0, std::min(1.0, a.z))), std::atan2(a.y, a.x)};
}

struct RoundFit {
    double radius = 0.0, length = 0.0, volume = INFINITY;
    Mat3 rotation;
    Vec3 center;
    bool capped = false;
    /// Only `volume` is set: a proven lower bound of the fit's volume, >= the bound asked.
    bool bounded = false;
};

/// A point's height along the axis and squared distance from it (one side of a capsule's segment).
struct Reach {
    double along, radial2;
};

/// The points that can set a capsule's segment ends. The top end max(along - sqrt(r^2 -
/// radial2)) is reached on the points no other has both a larger `along` and a larger
/// `radial2` (rounding is monotone, so the maximum over them is the same double for every r);
/// the bottom end's min(along + ...) likewise with a smaller `along`. One sort by `along`
/// (`sorted` is scratch); a tie may keep a dominated point, which changes no maximum.
void segment_fronts(const std::vector<Reach>& points, std::vector<Reach>& top,
                    std::vector<Reach>& bottom, std::vector<Reach>& sorted) {
    sorted = points;
    std::sort(sorted.begin(), sorted.end(), [](const Reach& a, const Reach& b) {
        return a.along < b.along || (a.along == b.along && a.radial2 > b.radial2);
    });
    bottom.clear();
    double widest = -INFINITY;
    for (const Reach& x : sorted)
        if (x.radial2 > widest) {
            bottom.push_back(x);
            widest = x.radial2;
        }
    top.clear();
    widest = -INFINITY;
    for (auto x = sorted.rbegin(); x != sorted.rend(); ++x)
        if (x->radial2 > widest) {
            top.push_back(*x);
            widest = x->radial2;
        }
}

/// The cylinders (`capsule` false) or capsules around one point set along axis after axis:
/// the axis through the minimum circle of the projected points; cylinder length by their
/// extent along it; capsule radius searched, its shortest segment exact for each radius.
/// Keeps its buffers, the circle search's order and what the last accepted fit's bound needs
/// across axes. A fit asked with a `bound` may stop at a proven lower bound >= `bound`:
/// every other answer is the one the full search gives, to the bit.
class RoundSearch {
public:
    RoundSearch(const std::vector<Vec3>& p, bool capsule)
        : p_(p), capsule_(capsule), order_(shuffle_order(static_cast<long long>(p.size()))),
          rows_(2 * p.size()), along_(p.size()) {}

    RoundFit fit(const Vec3& axis, double bound);

private:
    double cylinder_bound(double length) const;
    void keep_support(const double c2[3]);
    struct SegmentAt {
        double r, top, bottom, slope;
    };
    SegmentAt segment_at(double r) const;
    double piece_bound(const SegmentAt& a, const SegmentAt& b) const;
    bool capsule_above(double r_low, double r_high, double bound, double& lowest) const;
    void segment(double r, double& top, double& bottom) const;
    double volume_at(double r) const;
    void capsule(RoundFit& out, const Vec3& fx, const Vec3& fy, const Vec3& z, double lo,
                 double hi, double bound, const double c2[3], double r_min);

    const std::vector<Vec3>& p_;
    bool capsule_;
    std::vector<long long> order_;  // shuffled point k is p_[order_[k]]
    std::vector<double> rows_;      // the projection across the axis, shuffled (Welzl's rows)
    std::vector<double> along_;     // heights along the axis, shuffled
    std::vector<Reach> reach_, sorted_, top_, bottom_;
    std::vector<long long> support_;  // the last accepted cylinder's farthest points (shuffled)
};

/// A lower bound of the squared radius of any circle holding the projections of the support
/// points kept from the last accepted cylinder: half their largest distance, or the
/// circumradius of a clearly acute triangle of them (its own smallest circle).
double RoundSearch::cylinder_bound(double length) const {
    const size_t k = support_.size();
    double r2 = 0.0;
    auto at = [&](size_t i) {
        const long long s = support_[i];
        return std::array<double, 2>{rows_[2 * s], rows_[2 * s + 1]};
    };
    auto distance2 = [](const std::array<double, 2>& a, const std::array<double, 2>& b) {
        return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]);
    };
    for (size_t i = 0; i < k; ++i)
        for (size_t j = i + 1; j < k; ++j) r2 = std::max(r2, 0.25 * distance2(at(i), at(j)));
    for (size_t i = 0; i < k; ++i)
        for (size_t j = i + 1; j < k; ++j)
            for (size_t l = j + 1; l < k; ++l) {
                std::array<double, 2> v[3] = {at(i), at(j), at(l)};
                const double side[3] = {distance2(v[1], v[2]), distance2(v[0], v[2]),
                                        distance2(v[0], v[1])};
                const int c = static_cast<int>(std::max_element(side, side + 3) - side);
                const double a2 = side[(c + 1) % 3], b2 = side[(c + 2) % 3], c2 = side[c];
                // Not clearly acute: the pairs' bound holds.
                if (!(a2 + b2 - c2 > 1e-6 * c2)) continue;
                // Twice the area from the sides at the largest angle (60 to 90 degrees: well
                // conditioned); circumradius^2 = a^2 b^2 c^2 / (4 (2 area)^2).
                const auto& o = v[c];
                const auto& u = v[(c + 1) % 3];
                const auto& w = v[(c + 2) % 3];
                const double twice = (u[0] - o[0]) * (w[1] - o[1]) - (u[1] - o[1]) * (w[0] - o[0]);
                r2 = std::max(r2, a2 * b2 * c2 / (4.0 * twice * twice));
            }
    return kPi * r2 * length;
}

/// Keeps (up to) the four projected points farthest from the accepted circle's centre: the
/// circle's support, whose smallest circle bounds the next axes' circles from below.
void RoundSearch::keep_support(const double c2[3]) {
    const size_t n = p_.size(), keep = std::min<size_t>(n, 4);
    std::array<std::pair<double, long long>, 4> far{};
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) {
        const double dx = rows_[2 * i] - c2[0], dy = rows_[2 * i + 1] - c2[1];
        const std::pair<double, long long> item{dx * dx + dy * dy, static_cast<long long>(i)};
        if (count < keep) {
            far[count++] = item;
        } else {
            auto least = std::min_element(far.begin(), far.begin() + count);
            if (item.first > least->first) *least = item;
        }
    }
    support_.clear();
    for (size_t i = 0; i < count; ++i) support_.push_back(far[i].second);
}

void RoundSearch::segment(double r, double& top, double& bottom) const {
    top = -INFINITY;
    bottom = INFINITY;
    for (const Reach& x : top_)
        top = std::max(top, x.along - std::sqrt(std::max(r * r - x.radial2, 0.0)));
    for (const Reach& x : bottom_)
        bottom = std::min(bottom, x.along + std::sqrt(std::max(r * r - x.radial2, 0.0)));
}

double RoundSearch::volume_at(double r) const {
    double top, bottom;
    segment(r, top, bottom);
    return kPi * r * r * std::max(top - bottom, 0.0) + 4.0 / 3.0 * kPi * r * r * r;
}

/// The segment's ends at radius r, and the slope of its length there (the end points reached
/// at r: d(length)/dr = -r (1 / reach_top + 1 / reach_bottom); 0 when one reach is 0).
RoundSearch::SegmentAt RoundSearch::segment_at(double r) const {
    SegmentAt e{r, -INFINITY, INFINITY, 0.0};
    double top_reach = 0.0, bottom_reach = 0.0;
    for (const Reach& x : top_) {
        const double reach = std::sqrt(std::max(r * r - x.radial2, 0.0));
        if (x.along - reach > e.top) {
            e.top = x.along - reach;
            top_reach = reach;
        }
    }
    for (const Reach& x : bottom_) {
        const double reach = std::sqrt(std::max(r * r - x.radial2, 0.0));
        if (x.along + reach < e.bottom) {
            e.bottom = x.along + reach;
            bottom_reach = reach;
        }
    }
    if (top_reach > 0.0 && bottom_reach > 0.0)
        e.slope = -r * (1.0 / top_reach + 1.0 / bottom_reach);
    return e;
}

/// A lower bound of `volume_at(r)` over r in [a.r, b.r], the larger of two:
/// - the segment is at least as long as at b.r and the radius at least a.r, and every
///   operation of `volume_at` is monotone in those under rounding: a bound of the doubles as
///   computed;
/// - the segment's length is convex in r (the top end a maximum of convex along - sqrt(r^2 -
///   radial2), the bottom end a minimum of concave ones, each from r = sqrt(radial2) <=
///   r_min on: every radius the search tries is >= r_min), so at least the larger of its
///   tangents at both ends; on each tangent's part the volume is a cubic a r^2 + b r^3 with
///   a >= 0, least at an end of the part: at a.r, b.r or where the tangents cross. It holds
///   for exact arithmetic: it is lowered by the rounding of a computed square root near
///   r^2 = radial2 (about 2e-8 r) and of its own terms.
double RoundSearch::piece_bound(const SegmentAt& a, const SegmentAt& b) const {
    const double r1 = a.r, r2 = b.r;
    const double box =
        kPi * r1 * r1 * std::max(b.top - b.bottom, 0.0) + 4.0 / 3.0 * kPi * r1 * r1 * r1;
    const double la = a.top - a.bottom, lb = b.top - b.bottom;
    if (!(la > 0.0 && lb > 0.0 && a.slope < 0.0 && b.slope < 0.0)) return box;
    // Where the tangents cross (in [r1, r2] but for rounding); the lower of them there.
    double rx =
        a.slope < b.slope ? (lb - la + a.slope * r1 - b.slope * r2) / (a.slope - b.slope) : r1;
    rx = std::min(std::max(rx, r1), r2);
    const double lx = std::min(la + a.slope * (rx - r1), lb + b.slope * (rx - r2));
    if (!(lx >= 0.0)) return box;
    auto cubic = [](double r, double length) {
        return kPi * r * r * length + 4.0 / 3.0 * kPi * r * r * r;
    };
    const double tangent = std::min({cubic(r1, la), cubic(rx, lx), cubic(r2, lb)});
    const double rounding = kPi * r2 * r2 *
                            (1e-7 * r2 + 1e-12 * (std::fabs(a.top) + std::fabs(a.bottom) +
                                                  std::fabs(b.top) + std::fabs(b.bottom) -
                                                  a.slope * (r2 - r1)));
    return std::max(box, tangent - rounding);
}

/// Whether `volume_at(r)` >= `bound` for every r in [r_low, r_high] is proven by branch and
/// bound on halves (`piece_bound`; each split measures the segment once, at its middle); gives
/// up after a budget of splits. `lowest`: the least bound of the pieces (>= `bound` when proven).
bool RoundSearch::capsule_above(double r_low, double r_high, double bound, double& lowest) const {
    constexpr int kPieces = 40;
    std::array<std::array<SegmentAt, 2>, kPieces> pieces;
    int stack = 0, budget = defaults::fit_capsule_bound_pieces;
    lowest = INFINITY;
    pieces[stack++] = {segment_at(r_low), segment_at(r_high)};
    while (stack > 0) {
        const auto [a, b] = pieces[--stack];
        const double piece = piece_bound(a, b);
        if (piece >= bound) {
            lowest = std::min(lowest, piece);
            continue;
        }
        if (--budget <= 0 || stack + 2 > kPieces) return false;
        // The middle is in [a.r, b.r]: the halves cover the piece.
        const SegmentAt middle = segment_at(0.5 * (a.r + b.r));
        pieces[stack++] = {middle, b};
        pieces[stack++] = {a, middle};
    }
    return true;
}

RoundFit RoundSearch::fit(const Vec3& axis, double bound) {
    RoundFit out;
    out.rotation = frame_of(axis);
    const Vec3 fx = out.rotation.column(0), fy = out.rotation.column(1),
               z = out.rotation.column(2);
    const size_t n = p_.size();
    double lo = INFINITY, hi = -INFINITY;
    for (size_t k = 0; k < n; ++k) {
        const Vec3& x = p_[static_cast<size_t>(order_[k])];
        rows_[2 * k] = dot(x, fx);
        rows_[2 * k + 1] = dot(x, fy);
        along_[k] = dot(x, z);
        lo = std::min(lo, along_[k]);
        hi = std::max(hi, along_[k]);
    }
    // A cylinder's volume is at least the last support's smallest circle times this length
    // (a relative pad over the rounding of both circles).
    if (!capsule_ && !support_.empty()) {
        const double lower = cylinder_bound(hi - lo);
        if (lower > bound * (1 + 1e-9)) {
            out.volume = lower;
            out.bounded = true;
            return out;
        }
    }
    double c2[3], r_min = 0.0;
    out.capped = !ball_of_shuffled(rows_.data(), static_cast<long long>(n), 2, c2, r_min);
    if (capsule_) {
        capsule(out, fx, fy, z, lo, hi, bound, c2, r_min);
        return out;
    }
    out.radius = r_min;
    out.length = hi - lo;
    out.volume = kPi * r_min * r_min * out.length;
    out.center = c2[0] * fx + c2[1] * fy + 0.5 * (lo + hi) * z;
    if (out.volume < bound) keep_support(c2);
    return out;
}

/// The capsule about the circle's axis: for a radius r the shortest segment keeping every
/// point within r is exact (`segment`), r searched on a grid over [r_min, r_max], then by
/// golden-section steps between the best's neighbours.
void RoundSearch::capsule(RoundFit& out, const Vec3& fx, const Vec3& fy, const Vec3& z,
                          double lo, double hi, double bound, const double c2[3], double r_min) {
    const size_t n = p_.size();
    reach_.resize(n);
    const double middle = 0.5 * (lo + hi);
    double r_max2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double dx = rows_[2 * i] - c2[0], dy = rows_[2 * i + 1] - c2[1];
        reach_[i] = {along_[i], dx * dx + dy * dy};
        r_max2 = std::max(r_max2, reach_[i].radial2 + (along_[i] - middle) * (along_[i] - middle));
    }
    const double r_max = std::max(std::sqrt(r_max2), r_min);
    segment_fronts(reach_, top_, bottom_, sorted_);
    // Every radius the search tries lies in [r_min, r_max] (a relative pad over the rounding
    // of the grid and golden points): a bound over that range bounds the answer.
    double lowest = 0.0;
    if (bound < INFINITY &&
        capsule_above(r_min * (1 - 1e-12), r_max * (1 + 1e-12), bound, lowest)) {
        out.volume = lowest;
        out.bounded = true;
        return;
    }
    const int g = defaults::fit_capsule_radius_grid;
    int best = 0;
    double best_volume = INFINITY;
    for (int k = 0; k < g; ++k) {
        const double r = r_min + (r_max - r_min) * k / (g - 1);
        const double v = volume_at(r);
        if (v < best_volume) {
            best_volume = v;
            best = k;
        }
    }
    double a = r_min + (r_max - r_min) * std::max(best - 1, 0) / (g - 1);
    double b = r_min + (r_max - r_min) * std::min(best + 1, g - 1) / (g - 1);
    double radius = r_min + (r_max - r_min) * best / (g - 1);
    const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a);
    double f1 = volume_at(x1), f2 = volume_at(x2);
    for (int k = 0; k < defaults::fit_capsule_golden_steps; ++k) {
        if (f1 < f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - ratio * (b - a);
            f1 = volume_at(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + ratio * (b - a);
            f2 = volume_at(x2);
        }
    }
    if (std::min(f1, f2) < best_volume) radius = f1 < f2 ? x1 : x2;
    double top, bottom;
    segment(radius, top, bottom);
    out.radius = radius;
    out.length = std::max(top - bottom, 0.0);
    out.volume = kPi * radius * radius * out.length + 4.0 / 3.0 * kPi * radius * radius * radius;
    out.center = c2[0] * fx + c2[1] * fy + 0.5 * (top + bottom) * z;
}

/// The axis `a` turned in its tangent plane by (u, v) (a chart about a: no pole to stall at).
Vec3 tilted(const Mat3& chart, const std::array<double, 2>& uv) {
    const Vec3 d = chart.column(2) + uv[0] * chart.column(0) + uv[1] * chart.column(1);
    return d / norm(d);
}

/// The best axis: the candidates' best few, each polished by a pattern search on its polar
/// angles, then twice more in a chart about where it ended, with smaller first steps (a
/// restart escapes the stalls of a non-smooth volume); the smallest volume wins (earliest
/// start on ties). Trials the search would turn down anyway stop at a lower bound.
RoundFit along_best_axis(const std::vector<Vec3>& p, const std::vector<Vec3>& axes, bool capsule) {
    RoundSearch search(p, capsule);
    std::vector<std::pair<double, size_t>> starts;
    for (size_t i = 0; i < axes.size(); ++i)
        starts.push_back({search.fit(axes[i], INFINITY).volume, i});
    std::stable_sort(starts.begin(), starts.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    RoundFit best;
    const size_t count = std::min<size_t>(starts.size(), defaults::fit_axis_polish_starts);
    for (size_t s = 0; s < count; ++s) {
        // First on the axis's polar angles (their uneven steps explore more), then in charts.
        auto polar = [&](const std::array<double, 2>& tp, double bound) {
            return search.fit(direction(tp), bound).volume;
        };
        double value = 0.0;
        Vec3 axis = direction(polish<2>(polar, angles(axes[starts[s].second]),
                                        defaults::fit_axis_polish_step,
                                        defaults::fit_axis_polish_iterations,
                                        defaults::fit_axis_polish_smallest, value));
        double step = 0.25 * defaults::fit_axis_polish_step;
        for (int pass = 0; pass < 2; ++pass, step *= 0.25) {
            const Mat3 chart = frame_of(axis);
            auto cost = [&](const std::array<double, 2>& uv, double bound) {
                return search.fit(tilted(chart, uv), bound).volume;
            };
            const auto uv = polish<2>(cost, {0.0, 0.0}, step,
                                      defaults::fit_axis_polish_iterations,
                                      defaults::fit_axis_polish_smallest, value);
            axis = tilted(chart, uv);
        }
        if (value < best.volume * (1 - 1e-12)) best = search.fit(axis, INFINITY);
    }
    return best;
}

// ---------------------------------------------------------------------------------------------
// Growth to contain every input point

/// How far the point (local frame) lies outside the primitive (as Python's
/// `signed_distances`).
/// |diag(1 / a) l|: 1 on the surface of the ellipsoid of semi-axes a (all > 0).
double mahalanobis(const double* a, const Vec3& l) {
    return std::sqrt((l.x / a[0]) * (l.x / a[0]) + (l.y / a[1]) * (l.y / a[1]) +
                     (l.z / a[2]) * (l.z / a[2]));
}

double outside(FitShape shape, const double* q, const Vec3& l) {
    switch (shape) {
        case FitShape::SPHERE:
            return norm(l) - q[0];
        case FitShape::BOX:
            return std::max({std::fabs(l.x) - 0.5 * q[0], std::fabs(l.y) - 0.5 * q[1],
                             std::fabs(l.z) - 0.5 * q[2]});
        case FitShape::CAPSULE: {
            const double beyond = std::max(std::fabs(l.z) - 0.5 * q[1], 0.0);
            return std::hypot(std::hypot(l.x, l.y), beyond) - q[0];
        }
        case FitShape::CYLINDER:
            return std::max(std::hypot(l.x, l.y) - q[0], std::fabs(l.z) - 0.5 * q[1]);
        case FitShape::ELLIPSOID:  // (|l / a| - 1) min(a), as Python's; 0 for a flat one
            return std::min({q[0], q[1], q[2]}) > 0.0
                       ? (mahalanobis(q, l) - 1.0) * std::min({q[0], q[1], q[2]})
                       : 0.0;
    }
    return 0.0;
}

void grow(FitShape shape, double* q, double amount) {
    switch (shape) {
        case FitShape::SPHERE:
        case FitShape::CAPSULE:
            q[0] += amount;
            break;
        case FitShape::BOX:
            for (int k = 0; k < 3; ++k) q[k] += 2.0 * amount;
            break;
        case FitShape::CYLINDER:
            q[0] += amount;
            q[1] += 2.0 * amount;
            break;
        case FitShape::ELLIPSOID:  // grown by scaling instead (`finish_ellipsoid`)
            for (int k = 0; k < 3; ++k) q[k] += amount;
            break;
    }
}

double volume_of(FitShape shape, const double* q) {
    switch (shape) {
        case FitShape::SPHERE:
            return 4.0 / 3.0 * kPi * q[0] * q[0] * q[0];
        case FitShape::BOX:
            return q[0] * q[1] * q[2];
        case FitShape::CAPSULE:
            return kPi * q[0] * q[0] * q[1] + 4.0 / 3.0 * kPi * q[0] * q[0] * q[0];
        case FitShape::CYLINDER:
            return kPi * q[0] * q[0] * q[1];
        case FitShape::ELLIPSOID:
            return 4.0 / 3.0 * kPi * q[0] * q[1] * q[2];
    }
    return 0.0;
}

/// The ellipsoid's growth: every semi-axis first gets the margin (a flat or collinear set's
/// thickness), then the ellipsoid is SCALED by the largest Mahalanobis norm of any input
/// point (so the farthest lies on it) and gets the margin again; checked again (rounding of
/// the growth itself), at most 4 times. Scaling keeps the shape the search found: the
/// ellipsoid stays within (1 + tolerance) of the minimum's volume, plus the margin.
void finish_ellipsoid(PrimitiveFit& f, const Vec3* points, long long n, double scale) {
    double* a = f.params;
    auto largest = [&]() {
        double k = 0.0;
        for (long long i = 0; i < n; ++i)
            k = std::max(k, mahalanobis(a, f.rotation.transpose_times(points[i] - f.center)));
        return k;
    };
    const double margin = defaults::fit_containment_margin * scale;
    f.excess = 0.0;  // a flat search's: 0, as Python's `signed_distances`
    if (std::min({a[0], a[1], a[2]}) > 0.0) {
        for (long long i = 0; i < n; ++i) {
            const Vec3 l = f.rotation.transpose_times(points[i] - f.center);
            f.excess = std::max(f.excess, outside(FitShape::ELLIPSOID, a, l));
        }
    }
    for (int k = 0; k < 3; ++k) a[k] += margin;
    double k = largest();
    for (int j = 0; j < 3; ++j) a[j] = a[j] * k + margin;
    for (int round = 0; round < 4 && (k = largest()) > 1.0; ++round)
        for (int j = 0; j < 3; ++j) a[j] = a[j] * k + margin;
    f.volume = volume_of(FitShape::ELLIPSOID, a);
    bool finite = std::isfinite(f.volume) && std::isfinite(f.excess) && is_finite(f.center);
    for (int j = 0; j < 3; ++j) finite = finite && std::isfinite(a[j]) && a[j] > 0.0;
    if (!finite || largest() > 1.0) {
        f.status = FitStatus::FAILED;
        for (double& x : f.params) x = kNaN;
        f.volume = kNaN;
    }
}

/// Grows a searched fit (input units) by the largest excess of every input point, evaluated
/// in its frame, plus the margin; checks again (rounding of the growth itself), at most 4 times.
void finish(PrimitiveFit& f, FitShape shape, const Vec3* points, long long n, double scale) {
    auto excess_of = [&]() {
        double e = -INFINITY;
        for (long long i = 0; i < n; ++i)
            e = std::max(e, outside(shape, f.params, f.rotation.transpose_times(points[i] - f.center)));
        return e;
    };
    if (shape == FitShape::ELLIPSOID) return finish_ellipsoid(f, points, n, scale);
    const double margin = defaults::fit_containment_margin * scale;
    double e = excess_of();
    f.excess = std::max(e, 0.0);
    grow(shape, f.params, f.excess + margin);
    for (int round = 0; round < 4 && (e = excess_of()) > 0.0; ++round) grow(shape, f.params, e + margin);
    f.volume = volume_of(shape, f.params);
    bool finite = std::isfinite(f.volume) && std::isfinite(f.excess) && is_finite(f.center);
    for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(f.params[k]);
    if (!finite || excess_of() > 0.0) {
        f.status = FitStatus::FAILED;
        for (double& x : f.params) x = kNaN;
        f.volume = kNaN;
    }
}

PrimitiveFit no_fit() {
    PrimitiveFit f;
    f.status = FitStatus::INVALID_INPUT;
    for (double& x : f.params) x = kNaN;
    f.volume = kNaN;
    f.excess = kNaN;
    return f;
}

}  // namespace

bool minimum_ball(const double* points, long long n, int dimension, double center[3],
                  double& radius) {
    center[0] = center[1] = center[2] = 0.0;
    radius = 0.0;
    if (n <= 0 || dimension < 1 || dimension > 3) return false;
    std::vector<double> rows(points, points + n * dimension);
    return ball_of(std::move(rows), n, dimension, center, radius);
}

FitSet fit_point_set(const Vec3* points, long long n, const FitShape* shapes, int shape_count) {
    FitSet out;
    out.hull = exact_hull(points, n);
    const Hull& hull = out.hull;
    out.fits.assign(static_cast<size_t>(shape_count), no_fit());
    if (hull.dimension < 0 || shape_count == 0) return out;

    // Search in normalised coordinates: the hull's vertices about their box's centre, scaled
    // by a power of two (exact) to unit size, so no square under- or overflows.
    Vec3 low{INFINITY, INFINITY, INFINITY}, high{-INFINITY, -INFINITY, -INFINITY};
    for (int v : hull.vertices) {
        low = component_min(low, points[v]);
        high = component_max(high, points[v]);
    }
    const Vec3 origin = 0.5 * low + 0.5 * high;
    const double half = max_abs(0.5 * high - 0.5 * low);
    const double unit = half > 0.0 ? std::ldexp(1.0, std::ilogb(half)) : 1.0;
    std::vector<Vec3> p(hull.vertices.size());
    for (size_t i = 0; i < p.size(); ++i) p[i] = (points[hull.vertices[i]] - origin) / unit;

    // The growth margin's scale: the points' extent, at least 1e-6 of their magnitude.
    Vec3 all_low{INFINITY, INFINITY, INFINITY}, all_high{-INFINITY, -INFINITY, -INFINITY};
    double magnitude = 0.0;
    for (long long i = 0; i < n; ++i) {
        all_low = component_min(all_low, points[i]);
        all_high = component_max(all_high, points[i]);
        magnitude = std::max(magnitude, max_abs(points[i]));
    }
    const double scale =
        std::max({max_abs(all_high - all_low), magnitude * 1e-6, 1e-300});

    bool want_box = false, want_round = false;
    for (int k = 0; k < shape_count; ++k) {
        want_box = want_box || shapes[k] == FitShape::BOX;
        want_round = want_round || shapes[k] == FitShape::CAPSULE || shapes[k] == FitShape::CYLINDER;
    }
    Mat3 box;
    std::vector<Vec3> axes;
    if (want_box || want_round) {
        box = box_frame(p, hull);
        if (want_round) {
            const Mat3 principal = principal_axes(p);
            for (int k = 0; k < 3; ++k) axes.push_back(box.column(k));
            for (int k = 0; k < 3; ++k) axes.push_back(principal.column(k));
        }
    }
    for (int k = 0; k < shape_count; ++k) {
        PrimitiveFit f;
        f.status = FitStatus::OK;
        Vec3 center;  // normalised
        switch (shapes[k]) {
            case FitShape::SPHERE: {
                double c[3], r;
                std::vector<double> rows(3 * p.size());
                for (size_t i = 0; i < p.size(); ++i)
                    for (int j = 0; j < 3; ++j) rows[3 * i + j] = p[i][j];
                if (!ball_of(std::move(rows), static_cast<long long>(p.size()), 3, c, r))
                    f.status = FitStatus::MAX_ITERATIONS;
                center = {c[0], c[1], c[2]};
                f.params[0] = r;
                break;
            }
            case FitShape::BOX: {
                f.rotation = box;
                double lo[3] = {INFINITY, INFINITY, INFINITY};
                double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                for (const auto& x : p) {
                    const Vec3 l = box.transpose_times(x);
                    for (int j = 0; j < 3; ++j) {
                        lo[j] = std::min(lo[j], l[j]);
                        hi[j] = std::max(hi[j], l[j]);
                    }
                }
                for (int j = 0; j < 3; ++j) f.params[j] = hi[j] - lo[j];
                center = box * Vec3{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]),
                                    0.5 * (lo[2] + hi[2])};
                break;
            }
            case FitShape::CAPSULE:
            case FitShape::CYLINDER: {
                const RoundFit r = along_best_axis(p, axes, shapes[k] == FitShape::CAPSULE);
                if (r.capped) f.status = FitStatus::MAX_ITERATIONS;
                f.rotation = r.rotation;
                f.params[0] = r.radius;
                f.params[1] = r.length;
                center = r.center;
                break;
            }
            case FitShape::ELLIPSOID: {
                const EllipsoidSearch e = minimum_ellipsoid(
                    p.data(), static_cast<long long>(p.size()), hull.dimension,
                    defaults::fit_ellipsoid_tolerance, defaults::fit_ellipsoid_max_iterations);
                if (!e.converged) f.status = FitStatus::MAX_ITERATIONS;
                f.rotation = e.rotation;
                for (int j = 0; j < 3; ++j) f.params[j] = e.semi_axes[j];
                center = e.center;
                break;
            }
        }
        for (double& x : f.params) x *= unit;
        f.center = origin + center * unit;
        finish(f, shapes[k], points, n, scale);
        out.fits[static_cast<size_t>(k)] = f;
    }
    return out;
}

std::vector<FitSet> fit_point_sets(const Vec3* points, const std::int64_t* offsets,
                                   long long sets, const FitShape* shapes, int shape_count,
                                   int threads) {
    std::vector<FitSet> out(static_cast<size_t>(std::max<long long>(sets, 0)));
    const int t = resolve_threads(threads, sets, defaults::fit_min_sets_per_thread);
    parallel_for(sets, t, [&](long long begin, long long end) {
        for (long long h = begin; h < end; ++h)
            out[static_cast<size_t>(h)] =
                fit_point_set(points + offsets[h], offsets[h + 1] - offsets[h], shapes, shape_count);
    });
    return out;
}

}  // namespace meshcol
