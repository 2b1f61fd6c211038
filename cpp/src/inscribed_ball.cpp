// The in-sphere of a polytope (inscribed_ball.hpp): the Chebyshev centre's linear programme
// (Boyd and Vandenberghe 2004, 8.5.1), maximise r subject to n_i . x + r <= -d_i, solved by
// the primal active-set method for inequality-form LPs (Nocedal and Wright 2006, 16.5;
// a simplex on the rows when four are active), with Bland's smallest-index rule for both the
// entering and the leaving row, so degenerate vertices (a cube's centre touches six planes)
// cannot cycle. Where the largest ball can slide (a box longer than wide, a plate), the
// centre is the lexicographic one: the planes it touches are held at their distance and the
// least distance to the others is maximised in turn, until it cannot slide (at most three
// more stages: each one fixes a direction), which is a function of the polytope alone.
#include "meshcol/inscribed_ball.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"

namespace meshcol {
namespace {

using Vec4 = std::array<double, 4>;

double dot4(const Vec4& a, const Vec4& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

// Distance from x to plane i (positive inside).
double distance(const double* planes, long long i, const Vec4& y) {
    const double* p = planes + 4 * i;
    return -p[3] - (p[0] * y[0] + p[1] * y[1] + p[2] * y[2]);
}

// The least distance from x to a plane: the radius of the largest ball centred at x.
double least_distance(const double* planes, long long count, const Vec4& y) {
    double least = std::numeric_limits<double>::infinity();
    for (long long i = 0; i < count; ++i) least = std::min(least, distance(planes, i, y));
    return least;
}

// One stage's linear programme: maximise s subject to, for a free plane,
// n_i . x + s <= -d_i - base (row (n_i, 1)), and for a held one n_i . x <= -d_i - level_i
// (row (n_i, 0)): stage 1 (nothing held, base 0) is the Chebyshev centre.
struct Stage {
    const double* planes;
    long long count;
    const std::vector<double>* level;  // NaN: free
    double base;
    bool first;  // stage 1: nothing held

    bool held(long long i) const { return !std::isnan((*level)[i]); }
    Vec4 row(long long i) const {
        const double* p = planes + 4 * i;
        return {p[0], p[1], p[2], held(i) ? 0.0 : 1.0};
    }
    double rhs(long long i) const { return -planes[4 * i + 3] - (held(i) ? (*level)[i] : base); }
};

// The active rows, an orthonormal basis q of their span (modified Gram-Schmidt, twice) and
// r[j][k] = q_k . a_j (lower triangular: a_j = sum_{k <= j} r[j][k] q_k).
struct Active {
    int count = 0;
    long long rows[4] = {0, 0, 0, 0};
    Vec4 q[4];
    double r[4][4] = {};

    bool factor(const Stage& lp) {
        for (int j = 0; j < count; ++j) {
            Vec4 v = lp.row(rows[j]);
            for (int pass = 0; pass < 2; ++pass)
                for (int k = 0; k < j; ++k) {
                    const double s = dot4(q[k], v);
                    for (int c = 0; c < 4; ++c) v[c] -= s * q[k][c];
                }
            const double length = std::sqrt(dot4(v, v));
            if (!(length > defaults::inscribed_ball_zero)) return false;
            for (int c = 0; c < 4; ++c) q[j][c] = v[c] / length;
        }
        for (int j = 0; j < count; ++j) {
            const Vec4 a = lp.row(rows[j]);
            for (int k = 0; k <= j; ++k) r[j][k] = dot4(q[k], a);
        }
        return true;
    }

    bool holds(long long i) const {
        for (int j = 0; j < count; ++j)
            if (rows[j] == i) return true;
        return false;
    }

    void remove(int slot) {
        for (int j = slot; j + 1 < count; ++j) rows[j] = rows[j + 1];
        --count;
    }
};

// Solves the four active rows as equalities (Gaussian elimination, partial pivoting): the
// vertex they meet at. False when the system is singular.
bool solve_vertex(const Stage& lp, const Active& active, Vec4& y) {
    double m[4][5];
    for (int j = 0; j < 4; ++j) {
        const Vec4 a = lp.row(active.rows[j]);
        for (int c = 0; c < 4; ++c) m[j][c] = a[c];
        m[j][4] = lp.rhs(active.rows[j]);
    }
    for (int c = 0; c < 4; ++c) {
        int pivot = c;
        for (int j = c + 1; j < 4; ++j)
            if (std::abs(m[j][c]) > std::abs(m[pivot][c])) pivot = j;
        if (!(std::abs(m[pivot][c]) > 0.0)) return false;
        for (int k = 0; k < 5; ++k) std::swap(m[c][k], m[pivot][k]);
        for (int j = c + 1; j < 4; ++j) {
            const double f = m[j][c] / m[c][c];
            for (int k = c; k < 5; ++k) m[j][k] -= f * m[c][k];
        }
    }
    for (int c = 3; c >= 0; --c) {
        double s = m[c][4];
        for (int k = c + 1; k < 4; ++k) s -= m[c][k] * y[k];
        y[c] = s / m[c][c];
    }
    return std::isfinite(y[0]) && std::isfinite(y[1]) && std::isfinite(y[2]) &&
           std::isfinite(y[3]);
}

// Index (slot) of the active row to drop, or -1 at the optimum: the multipliers solve
// sum_j lambda_j a_j = c (back substitution on r); Bland's rule drops the negative one of
// the smallest row index. `lambda` ((4,)) receives the multipliers.
int leaving_row(const Active& active, const Vec4& gamma, double* lambda) {
    for (int k = active.count - 1; k >= 0; --k) {
        double s = gamma[k];
        for (int j = k + 1; j < active.count; ++j) s -= lambda[j] * active.r[j][k];
        lambda[k] = s / active.r[k][k];
    }
    int slot = -1;
    for (int j = 0; j < active.count; ++j)
        if (lambda[j] < -defaults::inscribed_ball_zero &&
            (slot < 0 || active.rows[j] < active.rows[slot]))
            slot = j;
    return slot;
}

// One stage from the point x (feasible for the held planes): its status, the point reached
// (y[3] the stage's s), the steps taken, and at the optimum its active rows and their
// multipliers. The first stage also tries the vertex of its
// four active planes, solved at once, and keeps it when that is farther from every plane
// (each step rounds).
Status solve_stage(const Stage& lp, Vec4& y, int& steps, Active& optimum, double* lambda) {
    const Vec4 objective = {0.0, 0.0, 0.0, 1.0};
    Active active;
    active.count = 1;
    double least = std::numeric_limits<double>::infinity();
    for (long long i = 0; i < lp.count; ++i) {
        if (lp.held(i)) continue;
        const double slack = lp.rhs(i) - (lp.planes[4 * i] * y[0] + lp.planes[4 * i + 1] * y[1] +
                                          lp.planes[4 * i + 2] * y[2]);
        if (slack < least) least = slack, active.rows[0] = i;
    }
    if (!std::isfinite(least)) return Status::DEGENERATE;  // every plane held
    y[3] = least;
    const long long cap = 64 + defaults::inscribed_ball_steps_per_plane * lp.count;
    for (long long step = 0; step < cap; ++step, ++steps) {
        if (!active.factor(lp)) return Status::DEGENERATE;
        // the objective's part across the active rows, orthogonalised twice: the rates of
        // the active rows along it then stay at rounding however short it is
        Vec4 gamma{}, d = objective;
        for (int k = 0; k < active.count; ++k) {
            gamma[k] = dot4(active.q[k], objective);
            for (int c = 0; c < 4; ++c) d[c] -= gamma[k] * active.q[k][c];
        }
        for (int k = 0; k < active.count; ++k) {
            const double s = dot4(active.q[k], d);
            for (int c = 0; c < 4; ++c) d[c] -= s * active.q[k][c];
        }
        const double length = std::sqrt(dot4(d, d));
        if (length <= defaults::inscribed_ball_zero) {  // c is in the active rows' span
            const int slot = leaving_row(active, gamma, lambda);
            if (slot >= 0) {
                active.remove(slot);
                continue;
            }
            optimum = active;
            Vec4 vertex{};
            if (lp.first && active.count == 4 &&
                solve_vertex(lp, active, vertex) &&
                least_distance(lp.planes, lp.count, vertex) >
                    least_distance(lp.planes, lp.count, y))
                y = vertex;
            return Status::CONVERGED;
        }
        for (double& c : d) c /= length;
        long long entering = -1;
        double step_length = std::numeric_limits<double>::infinity();
        for (long long i = 0; i < lp.count; ++i) {
            if (active.holds(i)) continue;
            const Vec4 a = lp.row(i);
            const double rate = dot4(a, d);
            if (rate <= defaults::inscribed_ball_zero) continue;
            const double slack = std::max(lp.rhs(i) - dot4(a, y), 0.0);
            const double t = slack / rate;
            if (t < step_length) step_length = t, entering = i;  // ties: the smallest index
        }
        if (entering < 0) return Status::DEGENERATE;  // s grows without bound
        for (int c = 0; c < 4; ++c) y[c] += step_length * d[c];
        active.rows[active.count++] = entering;
    }
    return Status::MAX_ITERATIONS;
}

// Whether no direction u != 0 keeps every held plane at its distance or farther: the cone
// {u : n_i . u <= 0, i held} is {0}. Such a cone, when not {0}, holds a line (its normals
// span less than R^3) or an extreme ray on two of its planes, u = +-(n_i x n_j): both are
// tried.
bool cannot_slide(const std::vector<Vec3>& held) {
    const double zero = defaults::inscribed_ball_zero;
    bool spans = false;
    for (size_t i = 0; i < held.size(); ++i)
        for (size_t j = i + 1; j < held.size(); ++j) {
            Vec3 u = cross(held[i], held[j]);
            const double length = norm(u);
            if (!(length > zero)) continue;
            u = u / length;
            for (const Vec3& n : held) spans = spans || std::abs(dot(n, u)) > zero;
            for (const double sign : {1.0, -1.0}) {
                bool blocked = false;
                for (const Vec3& n : held) blocked = blocked || sign * dot(n, u) > zero;
                if (!blocked) return false;  // the ball slides along sign * u
            }
        }
    return spans;
}

bool finite_planes(const double* planes, long long count) {
    for (long long i = 0; i < 4 * count; ++i)
        if (!std::isfinite(planes[i])) return false;
    return true;
}

}  // namespace

InscribedBall inscribed_ball(const double* planes, long long count) {
    InscribedBall out;
    if (count < 1 || !finite_planes(planes, count)) {
        out.status = Status::INVALID_INPUT;
        return out;
    }
    std::vector<double> level(static_cast<size_t>(count),
                              std::numeric_limits<double>::quiet_NaN());
    std::vector<Vec3> held;
    Vec4 y = {0.0, 0.0, 0.0, 0.0};  // x = 0: feasible with s the least distance
    Stage lp{planes, count, &level, 0.0, true};
    for (int stage = 0; stage < defaults::inscribed_ball_max_stages; ++stage) {
        Active optimum;
        double lambda[4] = {0, 0, 0, 0};
        out.status = solve_stage(lp, y, out.steps, optimum, lambda);
        if (out.status != Status::CONVERGED) break;
        const double reached = lp.base + y[3];
        if (stage == 0 && !(reached > 0.0)) {  // empty or flat: no ball to centre
            out.status = Status::DEGENERATE;
            break;
        }
        // the free planes of positive multiplier are at `reached` in every optimum: held
        // there, the others may move away from it in the next stage (their least distance
        // maximised in turn); at least one is (the multipliers of free rows sum to 1)
        for (int j = 0; j < optimum.count; ++j) {
            const long long i = optimum.rows[j];
            if (lp.held(i) || !(lambda[j] > defaults::inscribed_ball_zero)) continue;
            level[static_cast<size_t>(i)] = reached;
            held.push_back({planes[4 * i], planes[4 * i + 1], planes[4 * i + 2]});
        }
        if (cannot_slide(held)) break;
        lp.base = reached;
        lp.first = false;
        out.status = Status::DEGENERATE;  // unless a later stage pins the centre
    }
    out.centre = {y[0], y[1], y[2]};
    const double least = least_distance(planes, count, y);
    out.radius = least > 0.0 ? least : 0.0;
    return out;
}

void inscribed_balls(const double* planes, const std::int64_t* offsets, long long polytopes,
                     int threads, InscribedBall* out) {
    const long long total = polytopes > 0 ? offsets[polytopes] : 0;
    // threads by planes: a thread is worth its start for a few thousand of them
    const long long per_polytope = std::max<long long>(total / std::max(polytopes, 1LL), 1);
    const int used = resolve_threads(
        threads, polytopes,
        std::max<long long>(1, defaults::inscribed_ball_min_planes_per_thread / per_polytope));
    parallel_for(polytopes, used, [&](long long begin, long long end) {
        for (long long h = begin; h < end; ++h)
            out[h] = inscribed_ball(planes + 4 * offsets[h], offsets[h + 1] - offsets[h]);
    });
}

}  // namespace meshcol
