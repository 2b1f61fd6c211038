// Widths of a polytope across many directions by support climbs on its edge graph
// (hull.hpp: `hull_widths`), for the thickness of a part (meshcol/collision/limits.py).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "climb.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"

namespace meshcol {

double width_projection(const Vec3& p, const Vec3& d) {
    return std::fma(d.z, p.z, std::fma(d.y, p.y, d.x * p.x));
}

namespace {

// The hull's edge graph as CSR lists (ascending, no repeats), from its triangles.
bool edge_graph(int n, const std::int64_t* faces, long long face_count,
                std::vector<std::int64_t>& offsets, std::vector<std::int32_t>& adjacency) {
    std::vector<std::int64_t> degree(static_cast<size_t>(n) + 1, 0);
    for (long long f = 0; f < 3 * face_count; ++f) {
        if (faces[f] < 0 || faces[f] >= n) return false;
        degree[static_cast<size_t>(faces[f])] += 2;  // two edges of its triangle a corner
    }
    offsets.assign(static_cast<size_t>(n) + 1, 0);
    for (int i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + degree[i];
    std::vector<std::int64_t> fill(offsets.begin(), offsets.end() - 1);
    adjacency.assign(static_cast<size_t>(offsets[n]), 0);
    for (long long f = 0; f < face_count; ++f) {
        const std::int64_t* t = faces + 3 * f;
        for (int k = 0; k < 3; ++k) {
            const std::int64_t a = t[k], b = t[(k + 1) % 3];
            adjacency[fill[a]++] = static_cast<std::int32_t>(b);
            adjacency[fill[b]++] = static_cast<std::int32_t>(a);
        }
    }
    // each edge of a closed triangulation is listed twice: keep one
    std::int64_t write = 0;
    std::int64_t begin = 0;
    for (int i = 0; i < n; ++i) {
        const std::int64_t end = offsets[i + 1];
        std::sort(adjacency.begin() + begin, adjacency.begin() + end);
        const auto last = std::unique(adjacency.begin() + begin, adjacency.begin() + end);
        const std::int64_t kept = last - (adjacency.begin() + begin);
        std::copy(adjacency.begin() + begin, last, adjacency.begin() + write);
        offsets[i] = write;
        write += kept;
        begin = end;
    }
    offsets[n] = write;
    adjacency.resize(static_cast<size_t>(write));
    return true;
}

// The largest `width_projection` of the vertices in `d` (`sign` 1), or minus the smallest
// (`sign` -1), from a climb started at `hint`; `hint` becomes the vertex of that value.
// After the climb (steepest ascent on `dot`, climb.hpp), a search reads every vertex joined
// to the top by vertices whose projections are within `slack` of the top's: with `slack` at
// least twice a projection's rounding error (and the hull's own departure from convexity),
// the vertex of the exact largest projection is in that set, since the vertices of a convex
// polytope above a level are connected in its edge graph.
double extreme(const ShapeView& s, const Vec3& d, double sign, double slack, int& hint,
               std::vector<std::int64_t>& seen, std::int64_t stamp,
               std::vector<std::int32_t>& stack) {
    const Vec3 up = sign * d;
    double top_dot;
    int top = climb::climb_start(s, up, hint, top_dot);
    for (int steps = 0; steps < s.vertex_count; ++steps) {
        const int next = climb::climb_step<false, false, 1>(s, up, top, top_dot);
        if (next < 0) break;
        top = next;
    }
    const double level = sign * width_projection(s.vertices[top], d) - slack;
    double best = level + slack;
    int best_vertex = top;
    stack.clear();
    stack.push_back(top);
    seen[top] = stamp;
    while (!stack.empty()) {
        const int u = stack.back();
        stack.pop_back();
        for (std::int64_t e = s.adjacency_offsets[u]; e < s.adjacency_offsets[u + 1]; ++e) {
            const int w = s.adjacency[e];
            if (seen[w] == stamp) continue;
            seen[w] = stamp;
            const double value = sign * width_projection(s.vertices[w], d);
            if (value < level) continue;
            stack.push_back(w);
            if (value > best || (value == best && w < best_vertex)) {
                best = value;
                best_vertex = w;
            }
        }
    }
    hint = best_vertex;
    return sign * best;
}

}  // namespace

bool hull_widths(const Vec3* vertices, int vertex_count, const std::int64_t* faces,
                 long long face_count, const Vec3* directions, long long count,
                 double* widths) {
    if (vertex_count < 1) return false;
    std::vector<std::int64_t> offsets;
    std::vector<std::int32_t> adjacency;
    if (!edge_graph(vertex_count, faces, face_count, offsets, adjacency)) return false;
    ShapeView s;
    s.vertices = vertices;
    s.vertex_count = vertex_count;
    s.adjacency_offsets = offsets.data();
    s.adjacency = adjacency.data();
    double reach = 0.0;  // the largest 1-norm of a vertex: the scale of a projection's rounding
    for (int i = 0; i < vertex_count; ++i) {
        const Vec3& p = vertices[i];
        reach = std::max(reach, std::abs(p.x) + std::abs(p.y) + std::abs(p.z));
    }
    std::vector<std::int64_t> seen(static_cast<size_t>(vertex_count), -1);
    std::vector<std::int32_t> stack;
    int high = -1, low = -1;
    for (long long i = 0; i < count; ++i) {
        const Vec3& d = directions[i];
        const double slack = defaults::width_plateau_relative * reach *
                             (std::abs(d.x) + std::abs(d.y) + std::abs(d.z));
        const double largest = extreme(s, d, 1.0, slack, high, seen, 2 * i, stack);
        const double smallest = extreme(s, d, -1.0, slack, low, seen, 2 * i + 1, stack);
        widths[i] = largest - smallest;
    }
    return true;
}

}  // namespace meshcol
