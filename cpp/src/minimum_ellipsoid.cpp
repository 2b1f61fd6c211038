// The minimum-volume enclosing ellipsoid of a point set (fit.hpp: `minimum_ellipsoid`).
//
// Khachiyan's first-order method (Khachiyan 1996) with the Kumar-Yildirim start (Kumar and
// Yildirim 2005) and the Todd-Yildirim drop ("away") steps (Todd and Yildirim 2007; the
// WA-TY method of Ahipasaoglu, Sun and Todd 2008), on the points lifted to (y, 1). The
// points are first mapped by an affine map to a box of half-width 1 along their principal
// axes (the problem is affine-equivariant, so the answer maps back exactly, and the
// iteration sees a well-conditioned set however thin the input is).
//
// Stopping rule: a certificate, not an iteration count. For any weights u on the simplex,
// with c(u) = sum u_i y_i and S(u) = sum u_i (y_i - c)(y_i - c)^T, the ellipsoid
// {(y - c)^T S^-1 (y - c) <= k2}, k2 = max_i (y_i - c)^T S^-1 (y_i - c), holds every point, and
// weak duality (Todd 2016, "Minimum-Volume Ellipsoids", ch. 2) bounds the minimum volume from
// below by that of {(y - c)^T S^-1 (y - c) <= d}: the ratio of the two volumes is
// (k2 / d)^(d / 2). The iteration stops once that ratio is within 1 + tolerance.

#include <algorithm>
#include <cmath>
#include <vector>

#include "meshcol/fit.hpp"
#include "jacobi.hpp"

namespace meshcol {

namespace {

/// Eigen-decomposition of a symmetric positive semi-definite 3 x 3 matrix, a = V diag(w) V^T,
/// by cyclic Jacobi with a RELATIVE stopping rule (|a_pq| <= 1e-16 sqrt(a_pp a_qq)): for a
/// matrix D B D with B well conditioned it gives even the smallest eigenvalues to high
/// relative accuracy (Demmel and Veselic 1992), which the ellipsoid of a thin set needs.
void relative_jacobi(double a[3][3], double w[3], double v[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 64; ++sweep) {
        bool rotated = false;
        for (int p = 0; p < 3; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (!(std::fabs(a[p][q]) > 1e-16 * std::sqrt(std::fabs(a[p][p] * a[q][q]))))
                    continue;
                rotated = true;
                jacobi_rotate(a, v, p, q, 3);
            }
        if (!rotated) break;
    }
    for (int i = 0; i < 3; ++i) w[i] = a[i][i];
}

/// The inverse of a symmetric positive definite m x m matrix (m <= 4) by Cholesky; false
/// when a pivot is not positive (the weights' points do not span the space).
bool invert_spd(int m, const double a[4][4], double inverse[4][4]) {
    double l[4][4] = {};
    for (int j = 0; j < m; ++j) {
        double d = a[j][j];
        for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
        if (!(d > 0.0)) return false;
        l[j][j] = std::sqrt(d);
        for (int i = j + 1; i < m; ++i) {
            double s = a[i][j];
            for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
            l[i][j] = s / l[j][j];
        }
    }
    // L^-1 column by column, then inverse = L^-T L^-1.
    double li[4][4] = {};
    for (int c = 0; c < m; ++c) {
        for (int i = 0; i < m; ++i) {
            double s = i == c ? 1.0 : 0.0;
            for (int k = 0; k < i; ++k) s -= l[i][k] * li[k][c];
            li[i][c] = s / l[i][i];
        }
    }
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            double s = 0.0;
            for (int k = std::max(i, j); k < m; ++k) s += li[k][i] * li[k][j];
            inverse[i][j] = s;
        }
    return true;
}

/// Khachiyan's iteration on n points y (rows of d doubles, 2 <= d <= 3, spanning R^d).
struct Khachiyan {
    const std::vector<double>& y;
    long long n;
    int d;
    std::vector<double> u, big_m;  // weights; M_i = q_i^T X^-1 q_i, q_i = (y_i, 1)
    double x_inverse[4][4] = {};

    double q(long long i, int k) const { return k < d ? y[static_cast<size_t>(i * d + k)] : 1.0; }

    /// X = sum u_i q_i q_i^T, its inverse and every M_i afresh; false when X is singular.
    bool refresh() {
        const int m = d + 1;
        double x[4][4] = {};
        for (long long i = 0; i < n; ++i) {
            const double w = u[static_cast<size_t>(i)];
            if (w == 0.0) continue;
            for (int r = 0; r < m; ++r)
                for (int c = 0; c <= r; ++c) x[r][c] += w * q(i, r) * q(i, c);
        }
        for (int r = 0; r < m; ++r)
            for (int c = r + 1; c < m; ++c) x[r][c] = x[c][r];
        if (!invert_spd(m, x, x_inverse)) return false;
        for (long long i = 0; i < n; ++i) big_m[static_cast<size_t>(i)] = quadratic(i, i);
        return true;
    }

    /// q_i^T X^-1 q_j.
    double quadratic(long long i, long long j) const {
        const int m = d + 1;
        double s = 0.0;
        for (int r = 0; r < m; ++r) {
            double row = 0.0;
            for (int c = 0; c < m; ++c) row += x_inverse[r][c] * q(j, c);
            s += q(i, r) * row;
        }
        return s;
    }

    /// u <- (1 - tau) u + tau e_j (tau < 0: an away step from j), X^-1 and M by
    /// Sherman-Morrison: X' = (1 - tau) X + tau q_j q_j^T.
    void step(long long j, double tau) {
        const int m = d + 1;
        const double kappa = big_m[static_cast<size_t>(j)];
        double w[4] = {};
        for (int r = 0; r < m; ++r)
            for (int c = 0; c < m; ++c) w[r] += x_inverse[r][c] * q(j, c);
        const double keep = 1.0 - tau, denominator = keep + tau * kappa;
        for (long long i = 0; i < n; ++i) {
            double wq = 0.0;
            for (int r = 0; r < m; ++r) wq += w[r] * q(i, r);
            double& mi = big_m[static_cast<size_t>(i)];
            mi = (mi - tau * wq * wq / denominator) / keep;
        }
        for (int r = 0; r < m; ++r)
            for (int c = 0; c < m; ++c)
                x_inverse[r][c] = (x_inverse[r][c] - tau * w[r] * w[c] / denominator) / keep;
        for (double& x : u) x *= keep;
        u[static_cast<size_t>(j)] += tau;
    }
};

/// Kumar and Yildirim's start (the extreme points along each axis of the whitened set), or
/// uniform weights when those do not span R^d.
void start(Khachiyan& k) {
    std::fill(k.u.begin(), k.u.end(), 0.0);
    for (int axis = 0; axis < k.d; ++axis) {
        long long lo = 0, hi = 0;
        for (long long i = 1; i < k.n; ++i) {
            if (k.q(i, axis) < k.q(lo, axis)) lo = i;
            if (k.q(i, axis) > k.q(hi, axis)) hi = i;
        }
        k.u[static_cast<size_t>(lo)] += 1.0;
        k.u[static_cast<size_t>(hi)] += 1.0;
    }
    for (double& x : k.u) x /= 2.0 * k.d;
    if (k.refresh()) return;
    std::fill(k.u.begin(), k.u.end(), 1.0 / static_cast<double>(k.n));
    k.refresh();
}

/// The largest (y_i - c)^T S^-1 (y_i - c) of the current weights (from fresh M_i = 1 + that).
double largest_distance(const Khachiyan& k) {
    return *std::max_element(k.big_m.begin(), k.big_m.end()) - 1.0;
}

/// Runs the iteration to the certificate (or the cap); returns whether it converged.
bool iterate(Khachiyan& k, double tolerance, int max_iterations, int& iterations) {
    const double m = k.d + 1.0;
    const double goal = k.d * std::pow(1.0 + tolerance, 2.0 / k.d);  // (k2 / d)^(d/2) <= 1 + tol
    constexpr int kRefresh = 64;  // X^-1 and M afresh this often: the rank-one updates drift
    for (iterations = 0; iterations < max_iterations; ++iterations) {
        if (iterations % kRefresh == 0 && !k.refresh()) return false;
        long long up = 0, down = -1;
        for (long long i = 0; i < k.n; ++i) {
            const size_t s = static_cast<size_t>(i);
            if (k.big_m[s] > k.big_m[static_cast<size_t>(up)]) up = i;
            if (k.u[s] > 0.0 && (down < 0 || k.big_m[s] < k.big_m[static_cast<size_t>(down)]))
                down = i;
        }
        const double kappa_up = k.big_m[static_cast<size_t>(up)];
        if (kappa_up - 1.0 <= goal) {
            if (iterations % kRefresh == 0) return true;  // M is fresh: the certificate holds
            if (!k.refresh()) return false;
            if (largest_distance(k) <= goal) return true;
            continue;
        }
        const double kappa_down = k.big_m[static_cast<size_t>(down)];
        if (kappa_up / m - 1.0 >= 1.0 - kappa_down / m || !(kappa_down > 1.0)) {
            k.step(up, (kappa_up - m) / (m * (kappa_up - 1.0)));
        } else {
            const double weight = k.u[static_cast<size_t>(down)];
            const double tau = std::min((m - kappa_down) / (m * (kappa_down - 1.0)),
                                        weight / (1.0 - weight));
            k.step(down, -tau);
            if (tau == weight / (1.0 - weight)) k.u[static_cast<size_t>(down)] = 0.0;  // dropped
        }
    }
    return k.refresh() && largest_distance(k) <= goal;
}

/// Principal axes of the points (columns, descending variance, right-handed) and their mean.
Mat3 principal_frame(const Vec3* p, long long n, Vec3& mean) {
    mean = Vec3{};
    for (long long i = 0; i < n; ++i) mean += p[i];
    mean = mean / static_cast<double>(n);
    double a[3][3] = {};
    for (long long i = 0; i < n; ++i) {
        const Vec3 e = p[i] - mean;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) a[r][c] += e[r] * e[c];
    }
    double w[3], v[3][3];
    relative_jacobi(a, w, v);
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int i, int j) { return w[i] > w[j]; });
    Mat3 r;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) r.m[k][c] = v[k][order[c]];
    if (dot(cross(r.column(0), r.column(1)), r.column(2)) < 0)
        for (int k = 0; k < 3; ++k) r.m[k][2] = -r.m[k][2];
    return r;
}

}  // namespace

EllipsoidSearch minimum_ellipsoid(const Vec3* points, long long n, int dimension,
                                  double tolerance, int max_iterations) {
    EllipsoidSearch out;
    if (n <= 0) return out;
    // The affine map: principal axes, each coordinate about its mid-range over its half-range.
    Vec3 mean;
    const Mat3 axes = principal_frame(points, n, mean);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (long long i = 0; i < n; ++i) {
        const Vec3 l = axes.transpose_times(points[i] - mean);
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], l[k]);
            hi[k] = std::max(hi[k], l[k]);
        }
    }
    double mid[3], half[3];
    for (int k = 0; k < 3; ++k) {
        mid[k] = 0.5 * (lo[k] + hi[k]);
        half[k] = 0.5 * (hi[k] - lo[k]);
    }
    // The set's dimension: at most the hull's; an axis whose extent is rounding (1e-12 of
    // the largest) is flat (its semi-axis 0: the caller's margin gives the thickness).
    int d = 0;
    while (d < std::min(dimension, 3) && half[d] > 1e-12 * half[0]) ++d;
    out.dimension = d;

    double shape[3][3] = {};  // D S_y D: the ellipsoid's matrix in the principal frame
    double center[3] = {mid[0], mid[1], mid[2]};
    if (d == 1) {  // a segment: exact
        shape[0][0] = half[0] * half[0];
    } else if (d >= 2) {
        std::vector<double> y(static_cast<size_t>(n * d));
        for (long long i = 0; i < n; ++i) {
            const Vec3 l = axes.transpose_times(points[i] - mean);
            for (int k = 0; k < d; ++k)
                y[static_cast<size_t>(i * d + k)] = (l[k] - mid[k]) / half[k];
        }
        Khachiyan k{y, n, d, std::vector<double>(static_cast<size_t>(n)),
                    std::vector<double>(static_cast<size_t>(n))};
        start(k);
        out.converged = iterate(k, tolerance, max_iterations, out.iterations);
        // c and S of the final weights (directly, not through X^-1), k2 from them.
        double c[3] = {}, s[4][4] = {}, s_inverse[4][4];
        for (long long i = 0; i < n; ++i)
            for (int r = 0; r < d; ++r) c[r] += k.u[static_cast<size_t>(i)] * k.q(i, r);
        for (long long i = 0; i < n; ++i) {
            const double w = k.u[static_cast<size_t>(i)];
            for (int r = 0; r < d; ++r)
                for (int t = 0; t < d; ++t) s[r][t] += w * (k.q(i, r) - c[r]) * (k.q(i, t) - c[t]);
        }
        if (!invert_spd(d, s, s_inverse)) {  // never for a spanning set: the box instead
            for (int r = 0; r < d; ++r) shape[r][r] = d * half[r] * half[r];
            out.converged = false;
            out.ratio_bound = INFINITY;
        } else {
            double k2 = 0.0;
            for (long long i = 0; i < n; ++i) {
                double e = 0.0;
                for (int r = 0; r < d; ++r)
                    for (int t = 0; t < d; ++t)
                        e += (k.q(i, r) - c[r]) * s_inverse[r][t] * (k.q(i, t) - c[t]);
                k2 = std::max(k2, e);
            }
            out.ratio_bound = std::pow(k2 / d, 0.5 * d);
            for (int r = 0; r < d; ++r) {
                center[r] = mid[r] + half[r] * c[r];
                for (int t = 0; t < d; ++t) shape[r][t] = half[r] * (k2 * s[r][t]) * half[t];
            }
        }
    }
    if (d < 2) {
        out.converged = true;
        out.ratio_bound = 1.0;
    }
    double w[3], v[3][3];
    relative_jacobi(shape, w, v);
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int i, int j) { return w[i] > w[j]; });
    Mat3 local;  // the ellipsoid's axes in the principal frame
    for (int c = 0; c < 3; ++c) {
        out.semi_axes[c] = std::sqrt(std::max(w[order[c]], 0.0));
        for (int k = 0; k < 3; ++k) local.m[k][c] = v[k][order[c]];
    }
    out.rotation = axes * local;
    if (dot(cross(out.rotation.column(0), out.rotation.column(1)), out.rotation.column(2)) < 0)
        for (int k = 0; k < 3; ++k) out.rotation.m[k][2] = -out.rotation.m[k][2];
    out.center = mean + axes * Vec3{center[0], center[1], center[2]};
    return out;
}

}  // namespace meshcol
