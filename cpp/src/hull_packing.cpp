// Many hulls packed in one call for a ConvexSet (hull.hpp: pack_polytopes): each shape's hull
// (hull.cpp) with its vertex adjacency for hill climbing and its face normals and edge
// directions for SAT, on threads, concatenated.
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "hull_detail.hpp"

namespace meshcol {
namespace {

using namespace hull_detail;

struct ShapePack {
    HullStatus status = HullStatus::EMPTY;
    std::vector<Vec3> vertices;
    std::vector<std::int64_t> adjacency_counts;  // per vertex
    std::vector<std::int32_t> adjacency;
    std::vector<Vec3> faces;
    std::vector<Vec3> edges;
};

// One direction per class: unit, rounded to 12 digits for grouping; unsigned classes get a
// canonical sign (the first component clearly non-zero positive). First occurrences kept,
// in input order (an open-addressing table of the rounded keys: linear in the count).
void unique_directions(std::vector<Vec3>& d, bool signed_classes, std::vector<long long>& table) {
    size_t size = 16;
    while (size < 2 * d.size()) size *= 2;
    table.assign(3 * size, LLONG_MIN);
    size_t kept = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        Vec3 v = d[i];
        const double len = norm(v);
        if (!(len > 0.0)) continue;
        v = v / len;
        if (!signed_classes) {
            double s = 0.0;
            for (int k = 0; k < 3 && s == 0.0; ++k)
                if (std::fabs(v[k]) > 1e-12) s = v[k] > 0.0 ? 1.0 : -1.0;
            if (s < 0.0) v = -v;
        }
        // floor(x + 0.5) inlines where llround is a libm call; ties may round either way
        // (as np.round's half-to-even does differently), which only splits a class in two.
        const long long key[3] = {static_cast<long long>(std::floor(v.x * 1e12 + 0.5)),
                                  static_cast<long long>(std::floor(v.y * 1e12 + 0.5)),
                                  static_cast<long long>(std::floor(v.z * 1e12 + 0.5))};
        std::uint64_t hash = 1469598103934665603ull;
        for (long long k : key) hash = (hash ^ static_cast<std::uint64_t>(k)) * 1099511628211ull;
        size_t slot = static_cast<size_t>(hash ^ (hash >> 29)) & (size - 1);
        bool fresh = true;
        for (;; slot = (slot + 1) & (size - 1)) {
            long long* cell = &table[3 * slot];
            if (cell[0] == LLONG_MIN) {
                cell[0] = key[0], cell[1] = key[1], cell[2] = key[2];
                break;
            }
            if (cell[0] == key[0] && cell[1] == key[1] && cell[2] == key[2]) {
                fresh = false;
                break;
            }
        }
        if (fresh) d[kept++] = v;
    }
    d.resize(kept);
}

// Neighbour lists of `count` vertices from undirected edges, ascending, padded with the
// vertex itself to a multiple of four (the climb's blocks: see climb.hpp).
void adjacency_from_edges(int count, const std::vector<std::pair<int, int>>& edges,
                          std::vector<std::int64_t>& start, ShapePack& out) {
    start.assign(static_cast<size_t>(count) + 1, 0);
    for (const auto& [a, b] : edges) ++start[a + 1], ++start[b + 1];
    for (int i = 0; i < count; ++i) start[i + 1] += start[i];
    std::vector<std::int32_t>& list = out.adjacency;
    // Each list padded to a multiple of four: room for the padding first.
    out.adjacency_counts.resize(static_cast<size_t>(count));
    std::int64_t total = 0;
    for (int i = 0; i < count; ++i) {
        const std::int64_t degree = start[i + 1] - start[i];
        out.adjacency_counts[i] = (degree + 3) / 4 * 4;
        total += out.adjacency_counts[i];
    }
    list.assign(static_cast<size_t>(total), 0);
    std::vector<std::int64_t> fill(static_cast<size_t>(count));
    std::int64_t at = 0;
    for (int i = 0; i < count; ++i) {
        fill[i] = at;
        at += out.adjacency_counts[i];
    }
    for (const auto& [a, b] : edges) list[fill[a]++] = b, list[fill[b]++] = a;
    at = 0;
    for (int i = 0; i < count; ++i) {
        const std::int64_t end = fill[i];
        std::sort(list.begin() + at, list.begin() + end);
        for (std::int64_t k = end; k < at + out.adjacency_counts[i]; ++k) list[k] = i;
        at += out.adjacency_counts[i];
    }
}

void pack_one(const Vec3* points, long long n, Workspace& w, Analysis& analysis,
              ShapePack& out) {
    hull_with(points, n, w, analysis);
    const Hull& hull = analysis.hull;
    const Triangulation& t = analysis.t;
    const Planes& pl = analysis.pl;
    out.status = hull.status;
    if (hull.dimension < 0) {
        // Kept as given: the core reports INVALID_INPUT for every pair that uses it.
        out.vertices.assign(points, points + std::max<long long>(n, 0));
        out.adjacency_counts.assign(out.vertices.size(), 0);
        return;
    }
    const Vec3 zero{0.0, 0.0, 0.0};
    for (int v : hull.vertices) out.vertices.push_back(points[v] + zero);  // -0.0 as 0.0
    const int k = static_cast<int>(hull.vertices.size());
    std::vector<std::pair<int, int>> edges;
    if (hull.dimension == 0) {
        out.adjacency_counts.assign(1, 0);
        return;
    }
    if (hull.dimension == 1) {
        edges.emplace_back(0, 1);
        adjacency_from_edges(2, edges, w.start, out);
        out.edges.push_back(points[hull.vertices[1]] - points[hull.vertices[0]]);
        unique_directions(out.edges, false, w.table);
        return;
    }
    if (hull.dimension == 2) {
        for (int i = 0; i < k; ++i) {
            edges.emplace_back(i, (i + 1) % k);
            out.edges.push_back(points[hull.vertices[(i + 1) % k]] - points[hull.vertices[i]]);
        }
        adjacency_from_edges(k, edges, w.start, out);
        out.faces = {hull.normal, -hull.normal};
        unique_directions(out.edges, false, w.table);
        return;
    }
    // 3-D: every triangulation edge drives hill climbing; edges between different planes
    // are the polytope's true edges (SAT).
    const size_t m = hull.faces.size();
    edges.reserve(3 * m / 2);
    for (size_t i = 0; i < m; ++i)
        for (int e = 0; e < 3; ++e) {
            const int j = t.neighbor[i][e];
            if (j < static_cast<int>(i)) continue;
            const int a = hull.faces[i][e], b = hull.faces[i][(e + 1) % 3];
            edges.emplace_back(a, b);
            if (pl.group[i] != pl.group[j])
                out.edges.push_back(points[hull.vertices[b]] - points[hull.vertices[a]]);
        }
    adjacency_from_edges(k, edges, w.start, out);
    out.faces = hull.plane_normals;
    unique_directions(out.faces, true, w.table);
    unique_directions(out.edges, false, w.table);
}


}  // namespace

PackedPolytopes pack_polytopes(const Vec3* points, const std::int64_t* offsets, long long shapes,
                               int threads) {
    std::vector<ShapePack> packs(static_cast<size_t>(std::max<long long>(shapes, 0)));
    const int t = resolve_threads(threads, shapes, defaults::hull_min_shapes_per_thread);
    parallel_for(shapes, t, [&](long long begin, long long end) {
        Workspace w;
        Analysis analysis;
        for (long long h = begin; h < end; ++h)
            pack_one(points + offsets[h], offsets[h + 1] - offsets[h], w, analysis, packs[h]);
    });
    PackedPolytopes out;
    out.status.resize(packs.size());
    out.offsets.assign(1, 0);
    out.face_offsets.assign(1, 0);
    out.edge_offsets.assign(1, 0);
    out.adjacency_offsets.assign(1, 0);
    size_t v = 0, a = 0, f = 0, e = 0;
    for (const ShapePack& s : packs) {
        v += s.vertices.size();
        a += s.adjacency.size();
        f += s.faces.size();
        e += s.edges.size();
    }
    out.vertices.reserve(3 * v);
    out.adjacency.reserve(a);
    out.adjacency_offsets.reserve(v + 1);
    out.face_normals.reserve(3 * f);
    out.edge_directions.reserve(3 * e);
    auto put = [](std::vector<double>& dst, const std::vector<Vec3>& src) {
        for (const Vec3& x : src) dst.insert(dst.end(), {x.x, x.y, x.z});
    };
    for (size_t h = 0; h < packs.size(); ++h) {
        const ShapePack& s = packs[h];
        out.status[h] = s.status;
        put(out.vertices, s.vertices);
        out.offsets.push_back(out.offsets.back() + static_cast<std::int64_t>(s.vertices.size()));
        for (std::int64_t c : s.adjacency_counts)
            out.adjacency_offsets.push_back(out.adjacency_offsets.back() + c);
        out.adjacency.insert(out.adjacency.end(), s.adjacency.begin(), s.adjacency.end());
        put(out.face_normals, s.faces);
        out.face_offsets.push_back(out.face_offsets.back() +
                                   static_cast<std::int64_t>(s.faces.size()));
        put(out.edge_directions, s.edges);
        out.edge_offsets.push_back(out.edge_offsets.back() +
                                   static_cast<std::int64_t>(s.edges.size()));
    }
    return out;
}

}  // namespace meshcol
