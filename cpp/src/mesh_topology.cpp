// Per-mesh topology counts of a batch of meshes: each mesh's directed edges sorted by their
// undirected key (a few dozen to a few thousand entries, in cache), its sorted faces for the
// duplicates, and a union-find over its vertices for the pieces. The numpy reference is
// meshcol/geometry/topology.py (edge_table, is_closed_manifold, is_balanced,
// duplicate_face_count, component_count); tests/geometry/test_mesh_batches.py compares them.
#include "meshcol/mesh_topology.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "meshcol/batch.hpp"

namespace meshcol {

namespace {

/// One directed edge of a face, keyed by its undirected vertex pair.
struct EdgeUse {
    std::int64_t low;
    std::int64_t high;
    int direction;  // +1 low -> high, -1 high -> low
    bool whole;     // its face has three different corners
};

/// Scratch space reused across the meshes of one chunk.
struct Scratch {
    std::vector<EdgeUse> edges;
    std::vector<std::array<std::int64_t, 3>> sorted_faces;
    std::vector<std::int64_t> parent;
};

std::int64_t find_root(std::vector<std::int64_t>& parent, std::int64_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];  // path halving
        v = parent[v];
    }
    return v;
}

void count_edges(Scratch& s, MeshTopology& t) {
    std::sort(s.edges.begin(), s.edges.end(), [](const EdgeUse& a, const EdgeUse& b) {
        return a.low != b.low ? a.low < b.low : a.high < b.high;
    });
    std::int64_t edge_count = 0, kept_edges = 0, unbalanced = 0;
    for (size_t begin = 0; begin < s.edges.size();) {
        size_t end = begin;
        std::int64_t balance = 0, kept_balance = 0, kept = 0;
        while (end < s.edges.size() && s.edges[end].low == s.edges[begin].low &&
               s.edges[end].high == s.edges[begin].high) {
            balance += s.edges[end].direction;
            if (s.edges[end].whole) {
                kept_balance += s.edges[end].direction;
                ++kept;
            }
            ++end;
        }
        const auto count = static_cast<std::int64_t>(end - begin);
        ++edge_count;
        if (count == 1) ++t.boundary_edges;
        if (count > 2) ++t.non_manifold_edges;
        if (count == 2 && balance != 0) ++t.inconsistent_edges;
        if (kept > 0) {
            ++kept_edges;
            if (kept_balance != 0) ++unbalanced;
        }
        begin = end;
    }
    t.closed = edge_count > 0 && t.boundary_edges == 0 && t.non_manifold_edges == 0 &&
               t.inconsistent_edges == 0;
    t.balanced = kept_edges > 0 && unbalanced == 0;
}

void measure_mesh(const std::int64_t* f, std::int64_t face_count, std::int64_t vertex_count,
                  std::uint8_t* used, Scratch& s, MeshTopology& t) {
    t = MeshTopology{};
    std::fill(used, used + vertex_count, std::uint8_t{0});
    for (std::int64_t k = 0; k < 3 * face_count; ++k) {
        if (f[k] < 0 || f[k] >= vertex_count) {
            t.status = MeshTopologyStatus::INDEX_OUT_OF_RANGE;
            return;
        }
    }
    s.edges.clear();
    s.sorted_faces.clear();
    s.parent.resize(static_cast<size_t>(vertex_count));
    for (std::int64_t v = 0; v < vertex_count; ++v) s.parent[v] = v;
    for (std::int64_t i = 0; i < face_count; ++i) {
        const std::int64_t a = f[3 * i], b = f[3 * i + 1], c = f[3 * i + 2];
        const bool whole = a != b && b != c && a != c;
        const std::int64_t corners[3][2] = {{a, b}, {b, c}, {c, a}};
        for (const auto& e : corners) {
            if (e[0] == e[1]) continue;
            s.edges.push_back({std::min(e[0], e[1]), std::max(e[0], e[1]), e[0] < e[1] ? 1 : -1, whole});
        }
        std::array<std::int64_t, 3> sorted{a, b, c};
        std::sort(sorted.begin(), sorted.end());
        s.sorted_faces.push_back(sorted);
        used[a] = used[b] = used[c] = 1;
        // the pieces follow edges 0-1 and 1-2 of each face (numpy's component_count)
        s.parent[find_root(s.parent, b)] = find_root(s.parent, a);
        s.parent[find_root(s.parent, c)] = find_root(s.parent, b);
    }
    count_edges(s, t);
    std::sort(s.sorted_faces.begin(), s.sorted_faces.end());
    for (size_t i = 1; i < s.sorted_faces.size(); ++i)
        if (s.sorted_faces[i] == s.sorted_faces[i - 1]) ++t.duplicate_faces;
    for (std::int64_t v = 0; v < vertex_count; ++v)
        if (used[v] && find_root(s.parent, v) == v) ++t.components;
}

}  // namespace

void mesh_topology_batch(const std::int64_t* faces, const std::int64_t* face_offsets,
                         const std::int64_t* vertex_offsets, std::int64_t mesh_count,
                         MeshTopology* out, std::uint8_t* used, int threads) {
    const std::int64_t total_faces = mesh_count > 0 ? face_offsets[mesh_count] : 0;
    // a chunk of meshes should hold some thousands of faces to be worth a thread
    const long long per_mesh = mesh_count > 0 ? std::max<long long>(1, total_faces / mesh_count) : 1;
    const int used_threads = resolve_threads(threads, mesh_count, std::max<long long>(1, 4096 / per_mesh));
    parallel_for(mesh_count, used_threads, [&](long long begin, long long end) {
        Scratch scratch;
        for (long long i = begin; i < end; ++i) {
            const std::int64_t v0 = vertex_offsets[i];
            measure_mesh(faces + 3 * face_offsets[i], face_offsets[i + 1] - face_offsets[i],
                         vertex_offsets[i + 1] - v0, used + v0, scratch, out[i]);
        }
    });
}

namespace {

/// sqrt((x^2 + y^2) + z^2): numpy's norm along an axis of three, summed in order.
double norm3(double x, double y, double z) {
    double sum = x * x;
    sum += y * y;
    sum += z * z;
    return std::sqrt(sum);
}

}  // namespace

void face_heights(const double* vertices, const std::int64_t* faces, std::int64_t n_faces,
                  double* heights, std::uint8_t* repeated, int threads) {
    parallel_for(n_faces, resolve_threads(threads, n_faces, 65536), [&](long long begin, long long end) {
        for (long long i = begin; i < end; ++i) {
            const std::int64_t* f = faces + 3 * i;
            const double* a = vertices + 3 * f[0];
            const double* b = vertices + 3 * f[1];
            const double* c = vertices + 3 * f[2];
            const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const double twice_area = norm3(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                            u[0] * v[1] - u[1] * v[0]);
            // corner k minus corner k + 1, as numpy's tri - tri[:, [1, 2, 0]]
            const double lengths[3] = {norm3(a[0] - b[0], a[1] - b[1], a[2] - b[2]),
                                       norm3(b[0] - c[0], b[1] - c[1], b[2] - c[2]),
                                       norm3(c[0] - a[0], c[1] - a[1], c[2] - a[2])};
            double longest = lengths[0];
            for (double length : {lengths[1], lengths[2]})  // numpy's max: NaN wins
                longest = (std::isnan(longest) || std::isnan(length)) ? NAN : std::max(longest, length);
            heights[i] = longest > 0 ? twice_area / longest : 0.0;
            repeated[i] = f[0] == f[1] || f[1] == f[2] || f[2] == f[0];
        }
    });
}

}  // namespace meshcol
