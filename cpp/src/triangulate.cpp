// Polygon faces split into triangles (triangulate.hpp). The arithmetic follows the numpy
// splitter it replaced operation for operation (sums in numpy's pairwise order, the same
// comparisons, so NaN goes the same way), so that every reader's triangles stay bit-identical.
// This file is compiled with -ffp-contract=off: a fused multiply-add would round differently.
#include "meshcol/triangulate.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace meshcol {
namespace {

using UV = std::array<double, 2>;

/// numpy's pairwise sum of `n` values (`at(i)`), as np.sum(axis=-1) adds a contiguous row:
/// sequential from -0.0 below 8, eight accumulators up to 128, halves (multiples of 8) above;
/// the reduction then adds it to the identity 0.0.
template <class At>
double pairwise(const At& at, std::size_t begin, std::size_t n) {
    if (n < 8) {
        double res = -0.0;
        for (std::size_t i = 0; i < n; ++i) res += at(begin + i);
        return res;
    }
    if (n <= 128) {
        double r[8];
        for (std::size_t j = 0; j < 8; ++j) r[j] = at(begin + j);
        std::size_t i = 8;
        for (; i < n - (n % 8); i += 8)
            for (std::size_t j = 0; j < 8; ++j) r[j] += at(begin + i + j);
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; ++i) res += at(begin + i);
        return res;
    }
    std::size_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise(at, begin, n2) + pairwise(at, begin + n2, n - n2);
}

template <class At>
double numpy_sum(const At& at, std::size_t n) {
    return 0.0 + pairwise(at, 0, n);
}

/// The axis of the largest |normal| component, as np.argmax(np.abs(normal)): the first
/// largest, the first NaN if there is one. The plane's coordinates drop it.
int dominant_axis(const double normal[3]) {
    int axis = 0;
    double best = std::fabs(normal[0]);
    if (std::isnan(best)) return 0;
    for (int c = 1; c < 3; ++c) {
        const double v = std::fabs(normal[c]);
        if (std::isnan(v)) return c;
        if (v > best) best = v, axis = c;
    }
    return axis;
}

/// The face's corners in the plane of its Newell normal, the dominant axis dropped and the
/// second coordinate flipped when that normal component is negative (so a counter-clockwise
/// turn about the normal is positive).
void plane_coordinates(const double* vertices, const std::int64_t* corner, std::size_t k,
                       std::vector<UV>& uv, std::vector<double>& scratch) {
    auto p = [&](std::size_t i, int axis) { return vertices[3 * corner[i] + axis]; };
    scratch.resize(k);
    double normal[3];
    for (int c = 0; c < 3; ++c) {
        const int a = (c + 1) % 3, b = (c + 2) % 3;
        for (std::size_t i = 0; i < k; ++i) {
            const std::size_t j = i + 1 == k ? 0 : i + 1;
            scratch[i] = (p(i, a) - p(j, a)) * (p(i, b) + p(j, b));
        }
        normal[c] = numpy_sum([&](std::size_t i) { return scratch[i]; }, k);
    }
    const int axis = dominant_axis(normal);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double sign = normal[axis] < 0 ? -1.0 : 1.0;
    uv.resize(k);
    for (std::size_t i = 0; i < k; ++i) uv[i] = {p(i, u), p(i, v) * sign};
}

/// plane_coordinates and convex for a quad (most faces of most meshes), without the buffers:
/// the same operations in the same order.
bool convex_quad(const double* vertices, const std::int64_t* corner) {
    const double* p[4] = {vertices + 3 * corner[0], vertices + 3 * corner[1],
                          vertices + 3 * corner[2], vertices + 3 * corner[3]};
    double normal[3];
    for (int c = 0; c < 3; ++c) {
        const int a = (c + 1) % 3, b = (c + 2) % 3;
        double sum = -0.0;  // pairwise below 8 values: in order from -0.0
        for (int i = 0; i < 4; ++i) {
            const double* q = p[(i + 1) & 3];
            sum += (p[i][a] - q[a]) * (p[i][b] + q[b]);
        }
        normal[c] = 0.0 + sum;
    }
    const int axis = dominant_axis(normal);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double sign = normal[axis] < 0 ? -1.0 : 1.0;
    double x[4], y[4];
    for (int i = 0; i < 4; ++i) x[i] = p[i][u], y[i] = p[i][v] * sign;
    for (int i = 0; i < 4; ++i) {
        const int next = (i + 1) & 3, prev = (i + 3) & 3;
        const double e0 = x[next] - x[i], e1 = y[next] - y[i];
        const double p0 = x[i] - x[prev], p1 = y[i] - y[prev];
        if (!(p0 * e1 - p1 * e0 > 0)) return false;
    }
    return true;
}

/// Strictly convex and simple: every turn to the left, one full turn in all.
bool convex(const std::vector<UV>& uv, std::vector<double>& angles) {
    const std::size_t k = uv.size();
    angles.resize(k);
    bool left = true;
    for (std::size_t i = 0; i < k; ++i) {
        const std::size_t next = i + 1 == k ? 0 : i + 1, prev = i == 0 ? k - 1 : i - 1;
        const double e0 = uv[next][0] - uv[i][0], e1 = uv[next][1] - uv[i][1];
        const double p0 = uv[i][0] - uv[prev][0], p1 = uv[i][1] - uv[prev][1];
        const double turn = p0 * e1 - p1 * e0;
        left = left && turn > 0;
        if (k > 4) {
            const double dot = 0.0 + ((-0.0 + p0 * e0) + p1 * e1);
            angles[i] = std::atan2(turn, dot);
        }
    }
    // k left turns each under half a turn add up to less than k/2 turns: for k <= 4 that is
    // one turn exactly (a pentagram's two need k >= 5), so the sum needs no check.
    if (!left || k <= 4) return left;
    const double total = numpy_sum([&](std::size_t i) { return angles[i]; }, k);
    return std::fabs(total - 2 * 3.141592653589793) < 1e-6;  // 3.14...: np.pi
}

double cross(const UV& o, const UV& a, const UV& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/// Ear clipping in the plane: appends (k - 2) triangles of corner positions 0..k-1.
void ear_clip(const std::vector<UV>& uv, std::vector<std::size_t>& remaining,
              std::vector<std::array<std::size_t, 3>>& triangles) {
    const std::size_t k = uv.size();
    remaining.resize(k);
    for (std::size_t i = 0; i < k; ++i) remaining[i] = i;
    triangles.clear();
    while (remaining.size() > 3) {
        const std::size_t n = remaining.size();
        bool clipped = false;
        for (std::size_t e = 0; e < n && !clipped; ++e) {
            const std::size_t i = remaining[e == 0 ? n - 1 : e - 1], j = remaining[e],
                              m = remaining[(e + 1) % n];
            const UV &a = uv[i], &b = uv[j], &c = uv[m];
            if (cross(a, b, c) <= 0) continue;  // a reflex or flat corner is not an ear
            bool inside = false;
            for (const std::size_t r : remaining) {
                if (r == i || r == j || r == m) continue;
                const UV& q = uv[r];
                if (cross(a, b, q) >= 0 && cross(b, c, q) >= 0 && cross(c, a, q) >= 0) {
                    inside = true;
                    break;
                }
            }
            if (!inside) {
                triangles.push_back({i, j, m});
                remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(e));
                clipped = true;
            }
        }
        if (!clipped) break;  // no ear: no area (or not simple); fan what is left
    }
    for (std::size_t t = 1; t + 1 < remaining.size(); ++t)
        triangles.push_back({remaining[0], remaining[t], remaining[t + 1]});
}

/// Checks counts and indices; returns the number of triangles.
std::size_t check(const PolygonMesh& mesh, const std::vector<char>& skip) {
    std::uint64_t total = 0;  // saturates: counts near 2^63 each cannot wrap it to a match
    std::size_t triangles = 0;
    for (std::size_t f = 0; f < mesh.n_faces; ++f) {
        const std::int64_t k = mesh.counts[f];
        if (k < 0)
            throw std::invalid_argument("face " + std::to_string(f) +
                                        " has a negative vertex count (" + std::to_string(k) +
                                        ")");
        const std::uint64_t add = static_cast<std::uint64_t>(k);
        total = total > UINT64_MAX - add ? UINT64_MAX : total + add;
        if (k >= 3 && !skip[f]) triangles += static_cast<std::size_t>(k - 2);
    }
    if (total != mesh.n_indices)
        throw std::invalid_argument(
            "face vertex counts add up to " +
            (total == UINT64_MAX ? std::string("more than 2^64") : std::to_string(total)) +
            ", but there are " + std::to_string(mesh.n_indices) + " face vertex indices");
    for (std::size_t i = 0; i < mesh.n_indices; ++i) {
        const std::int64_t index = mesh.indices[i];
        if (index < 0 || static_cast<std::uint64_t>(index) >= mesh.n_vertices)
            throw std::invalid_argument("face vertex index " + std::to_string(index) +
                                        " refers to a point the mesh does not have (" +
                                        std::to_string(mesh.n_vertices) + " points)");
    }
    return triangles;
}

}  // namespace

std::vector<std::int64_t> triangulate_polygons(const PolygonMesh& mesh,
                                               const TriangulateOptions& options) {
    std::vector<char> skip(mesh.n_faces, 0);
    for (const std::int64_t h : options.holes)
        if (h >= 0 && static_cast<std::uint64_t>(h) < mesh.n_faces) skip[static_cast<std::size_t>(h)] = 1;
    const std::size_t triangles = check(mesh, skip);
    if (options.max_triangles >= 0 && triangles > static_cast<std::uint64_t>(options.max_triangles))
        throw std::overflow_error("more than " + std::to_string(options.max_triangles) +
                                  " triangles");
    std::vector<std::int64_t> out(3 * triangles);
    std::int64_t* o = out.data();
    std::vector<UV> uv;
    std::vector<double> scratch;
    std::vector<std::size_t> remaining;
    std::vector<std::array<std::size_t, 3>> clipped;
    const int first = options.reverse ? 2 : 0;
    auto emit = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
        o[first] = a;
        o[1] = b;
        o[2 - first] = c;
        o += 3;
    };
    std::size_t start = 0;
    for (std::size_t f = 0; f < mesh.n_faces; start += static_cast<std::size_t>(mesh.counts[f]), ++f) {
        const std::size_t k = static_cast<std::size_t>(mesh.counts[f]);
        if (k < 3 || skip[f]) continue;
        const std::int64_t* corner = mesh.indices + start;
        if (k == 3) {
            emit(corner[0], corner[1], corner[2]);
            continue;
        }
        if (k == 4 && convex_quad(mesh.vertices, corner)) {
            emit(corner[0], corner[1], corner[2]);
            emit(corner[0], corner[2], corner[3]);
            continue;
        }
        plane_coordinates(mesh.vertices, corner, k, uv, scratch);
        if (k != 4 && convex(uv, scratch)) {
            for (std::size_t t = 1; t + 1 < k; ++t) emit(corner[0], corner[t], corner[t + 1]);
            continue;
        }
        ear_clip(uv, remaining, clipped);
        for (const auto& [a, b, c] : clipped) emit(corner[a], corner[b], corner[c]);
    }
    return out;
}

}  // namespace meshcol
