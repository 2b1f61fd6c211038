// Consistent winding of a mesh's components (orientation.hpp: orient_faces), the core of
// meshcol.geometry.topology.orient_consistently.
#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>
#include <tuple>
#include <vector>

#include "meshcol/orientation.hpp"
#include "meshcol/vec.hpp"
#include "ray_parity.hpp"

namespace meshcol {
namespace {

// The real half-edges (two different vertex indices) grouped by undirected edge: `order`
// holds half-edge ids (3 * face + corner) sorted by (low, high, id); `start` the first
// position of each edge in it, plus the end.
struct HalfEdges {
    std::vector<std::int64_t> order;
    std::vector<size_t> start;
    std::vector<std::int64_t> low, high;  // per half-edge id
    std::vector<std::uint8_t> forward;    // per half-edge id: low -> high

    explicit HalfEdges(const std::int64_t* faces, std::int64_t m)
        : low(static_cast<size_t>(3 * m)), high(static_cast<size_t>(3 * m)),
          forward(static_cast<size_t>(3 * m)) {
        std::int64_t top = -1;  // the largest low end
        for (std::int64_t h = 0; h < 3 * m; ++h) {
            const std::int64_t f = h / 3, k = h % 3;
            const std::int64_t a = faces[h], b = faces[3 * f + (k + 1) % 3];
            low[static_cast<size_t>(h)] = std::min(a, b);
            high[static_cast<size_t>(h)] = std::max(a, b);
            forward[static_cast<size_t>(h)] = a < b;
            if (a != b) top = std::max(top, low[static_cast<size_t>(h)]);
        }
        sort_by_ends(top + 1);
        for (size_t k = 0; k < order.size(); ++k) {
            const auto h = static_cast<size_t>(order[k]);
            if (k == 0 || low[h] != low[static_cast<size_t>(order[k - 1])] ||
                high[h] != high[static_cast<size_t>(order[k - 1])])
                start.push_back(k);
        }
        start.push_back(order.size());
    }

    size_t edge_count() const { return start.size() - 1; }

private:
    // `order`: the real half-edges by (low, high, id). A counting sort by the low end (ids
    // stay increasing within a low end), then each low end's few half-edges by the high end,
    // stably: a vertex is the low end of a handful of edges, so this is linear where one
    // comparison sort of every half-edge was most of orient_faces' time.
    void sort_by_ends(std::int64_t vertex_count) {
        const auto n = static_cast<std::int64_t>(low.size());
        std::vector<size_t> first(static_cast<size_t>(vertex_count) + 1, 0);
        for (std::int64_t h = 0; h < n; ++h)
            if (low[static_cast<size_t>(h)] != high[static_cast<size_t>(h)]) ++first[static_cast<size_t>(low[static_cast<size_t>(h)]) + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());
        order.resize(first.back());
        std::vector<size_t> next(first.begin(), first.end() - 1);
        for (std::int64_t h = 0; h < n; ++h)
            if (low[static_cast<size_t>(h)] != high[static_cast<size_t>(h)]) order[next[static_cast<size_t>(low[static_cast<size_t>(h)])]++] = h;
        constexpr size_t kInsertion = 32;  // longer runs (a fan of many faces) go to std::sort
        const auto by_high = [this](std::int64_t i, std::int64_t j) {
            const auto u = static_cast<size_t>(i), v = static_cast<size_t>(j);
            return std::tie(high[u], i) < std::tie(high[v], j);
        };
        for (size_t v = 0; v + 1 < first.size(); ++v) {
            const auto begin = order.begin() + static_cast<std::ptrdiff_t>(first[v]);
            const auto end = order.begin() + static_cast<std::ptrdiff_t>(first[v + 1]);
            if (static_cast<size_t>(end - begin) > kInsertion) {
                std::sort(begin, end, by_high);
                continue;
            }
            for (auto i = begin + (begin != end); i < end; ++i)
                for (auto j = i; j != begin && by_high(*j, *(j - 1)); --j) std::iter_swap(j, j - 1);
        }
    }
};

// A link of the face graph: two faces sharing a manifold edge, and whether they traverse it the
// same way (one of them must then be reversed).
struct Link {
    std::int64_t from, to;
    std::uint8_t same;
    size_t edge;
};

// Every edge traversed as often each way, the faces reversed where `flipped`.
bool balanced(const HalfEdges& h, const std::vector<std::uint8_t>& flipped) {
    if (h.order.empty()) return false;
    for (size_t e = 0; e < h.edge_count(); ++e) {
        long long balance = 0;
        for (size_t k = h.start[e]; k < h.start[e + 1]; ++k) {
            const auto id = static_cast<size_t>(h.order[k]);
            balance += (h.forward[id] != flipped[id / 3]) ? 1 : -1;
        }
        if (balance != 0) return false;
    }
    return true;
}

// Labels of the components of the face graph (in order of their lowest face, as scipy's
// connected_components numbers them) and the flips of one breadth-first search from every
// component's lowest face at once, neighbours in increasing index (scipy's
// breadth_first_order from a virtual root above those faces).
void search(std::int64_t m, const std::vector<Link>& links, std::vector<std::int64_t>* label,
            std::vector<std::uint8_t>* flipped) {
    // CSR adjacency, one link per ordered face pair: the one of the lowest edge.
    std::vector<Link> both;
    both.reserve(2 * links.size());
    for (const Link& l : links) {
        both.push_back(l);
        both.push_back({l.to, l.from, l.same, l.edge});
    }
    std::sort(both.begin(), both.end(), [](const Link& a, const Link& b) {
        return std::tie(a.from, a.to, a.edge) < std::tie(b.from, b.to, b.edge);
    });
    both.erase(std::unique(both.begin(), both.end(),
                           [](const Link& a, const Link& b) { return a.from == b.from && a.to == b.to; }),
               both.end());
    std::vector<size_t> row(static_cast<size_t>(m) + 1, 0);
    for (const Link& l : both) ++row[static_cast<size_t>(l.from) + 1];
    std::partial_sum(row.begin(), row.end(), row.begin());

    label->assign(static_cast<size_t>(m), -1);
    std::vector<std::int64_t> roots;
    std::vector<std::int64_t> stack;
    for (std::int64_t f = 0; f < m; ++f) {
        if ((*label)[static_cast<size_t>(f)] >= 0) continue;
        const auto id = static_cast<std::int64_t>(roots.size());
        roots.push_back(f);
        (*label)[static_cast<size_t>(f)] = id;
        stack.assign(1, f);
        while (!stack.empty()) {
            const auto u = static_cast<size_t>(stack.back());
            stack.pop_back();
            for (size_t k = row[u]; k < row[u + 1]; ++k) {
                const auto v = static_cast<size_t>(both[k].to);
                if ((*label)[v] < 0) {
                    (*label)[v] = id;
                    stack.push_back(both[k].to);
                }
            }
        }
    }
    flipped->assign(static_cast<size_t>(m), 0);
    std::vector<std::uint8_t> seen(static_cast<size_t>(m), 0);
    std::deque<std::int64_t> queue(roots.begin(), roots.end());
    for (const std::int64_t r : roots) seen[static_cast<size_t>(r)] = 1;
    while (!queue.empty()) {
        const auto u = static_cast<size_t>(queue.front());
        queue.pop_front();
        for (size_t k = row[u]; k < row[u + 1]; ++k) {
            const auto v = static_cast<size_t>(both[k].to);
            if (seen[v]) continue;
            seen[v] = 1;
            (*flipped)[v] = (*flipped)[u] ^ both[k].same;
            queue.push_back(both[k].to);
        }
    }
}

// The centre of the vertices' bounding box (NaN if any coordinate is NaN, as numpy's min).
Vec3 box_centre(const double* vertices, std::int64_t n) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    bool nan = false;
    for (std::int64_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = vertices[3 * i + k];
            nan |= std::isnan(x);
            lo[k] = std::min(lo[k], x);
            hi[k] = std::max(hi[k], x);
        }
    if (nan) return {std::nan(""), std::nan(""), std::nan("")};
    return (lo + hi) / 2.0;
}

inline Vec3 corner(const double* vertices, const std::int64_t* faces, std::int64_t f, int k,
                   bool reversed) {
    const std::int64_t i = faces[3 * f + (reversed ? 2 - k : k)];
    return {vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
}

}  // namespace

namespace {

// Every directed edge (u, v), u != v, appears once and so does (v, u). With each vertex's
// out-edges and in-edges (both by a counting sort): no vertex has an out-edge twice, and each
// in-edge (w, u) of a vertex u has its reverse among u's out-edges, marked by a stamp per
// vertex. Then (u, v) has its reverse, as u is an in-edge of v. Linear, whatever the degrees,
// and every test agrees on a closed mesh, so its branches are predicted. Face indices are
// Index, kept as Vertex (which holds vertex_count), edge offsets as Offset (which holds 3
// face_count): 32 bits where they fit, half the memory of 64.
template <class Index, class Vertex, class Offset>
bool closed_and_consistent_as(const Index* faces, std::int64_t face_count, std::int64_t vertex_count) {
    const auto n = static_cast<size_t>(vertex_count);
    std::vector<Offset> out_first(n + 1, 0), in_first(n + 1, 0);
    Offset edges = 0;
    for (std::int64_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const auto u = static_cast<Vertex>(faces[3 * f + k]), v = static_cast<Vertex>(faces[3 * f + (k + 1) % 3]);
            if (u == v) continue;
            ++out_first[static_cast<size_t>(u) + 1];
            ++in_first[static_cast<size_t>(v) + 1];
            ++edges;
        }
    if (edges == 0) return false;
    for (size_t i = 0; i < n; ++i) {
        out_first[i + 1] += out_first[i];
        in_first[i + 1] += in_first[i];
    }
    std::vector<Vertex> out_to(static_cast<size_t>(edges)), in_from(static_cast<size_t>(edges));
    std::vector<Offset> out_next(out_first.begin(), out_first.end() - 1), in_next(in_first.begin(), in_first.end() - 1);
    for (std::int64_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const auto u = static_cast<Vertex>(faces[3 * f + k]), v = static_cast<Vertex>(faces[3 * f + (k + 1) % 3]);
            if (u == v) continue;
            out_to[static_cast<size_t>(out_next[static_cast<size_t>(u)]++)] = v;
            in_from[static_cast<size_t>(in_next[static_cast<size_t>(v)]++)] = u;
        }
    std::vector<Vertex> stamp(n, -1);  // stamp[v] == u: (u, v) is an edge
    for (size_t u = 0; u < n; ++u) {
        const auto mark = static_cast<Vertex>(u);
        for (Offset e = out_first[u]; e < out_first[u + 1]; ++e) {
            Vertex& s = stamp[static_cast<size_t>(out_to[static_cast<size_t>(e)])];
            if (s == mark) return false;  // (u, v) repeated
            s = mark;
        }
        for (Offset e = in_first[u]; e < in_first[u + 1]; ++e)
            if (stamp[static_cast<size_t>(in_from[static_cast<size_t>(e)])] != mark) return false;  // (w, u) without (u, w)
    }
    return true;
}

}  // namespace

bool closed_and_consistent(const std::int64_t* faces, std::int64_t face_count, std::int64_t vertex_count) {
    constexpr std::int64_t kNarrow = std::numeric_limits<std::int32_t>::max();
    if (vertex_count <= kNarrow && 3 * face_count <= kNarrow)
        return closed_and_consistent_as<std::int64_t, std::int32_t, std::int32_t>(faces, face_count, vertex_count);
    return closed_and_consistent_as<std::int64_t, std::int64_t, std::int64_t>(faces, face_count, vertex_count);
}

bool closed_and_consistent(const std::int32_t* faces, std::int64_t face_count, std::int64_t vertex_count) {
    if (3 * face_count <= std::numeric_limits<std::int32_t>::max())
        return closed_and_consistent_as<std::int32_t, std::int32_t, std::int32_t>(faces, face_count, vertex_count);
    return closed_and_consistent_as<std::int32_t, std::int32_t, std::int64_t>(faces, face_count, vertex_count);
}

FaceOrientation orient_faces(const double* vertices, std::int64_t vertex_count,
                             const std::int64_t* faces, std::int64_t m,
                             int nesting_max_components, double flat_volume) {
    FaceOrientation out;
    out.flipped.assign(static_cast<size_t>(m), 0);
    // The common case, closed and consistently wound, decided without sorting the half-edges:
    // every edge then has one half-edge each way, so no manifold edge disagrees (the faces
    // are kept as given, below) and every edge is balanced.
    if (closed_and_consistent(faces, m, vertex_count)) {
        out.balanced = true;
        return out;
    }
    const HalfEdges h(faces, m);
    std::vector<Link> links;
    bool inconsistent = false;
    for (size_t e = 0; e < h.edge_count(); ++e) {
        if (h.start[e + 1] - h.start[e] != 2) continue;
        const std::int64_t a = h.order[h.start[e]], b = h.order[h.start[e] + 1];
        const std::uint8_t same = h.forward[static_cast<size_t>(a)] == h.forward[static_cast<size_t>(b)];
        inconsistent |= same != 0;
        if (a / 3 != b / 3) links.push_back({a / 3, b / 3, same, e});
    }
    if (!inconsistent) {  // the author's winding, either way round
        out.balanced = balanced(h, out.flipped);
        return out;
    }
    std::vector<std::int64_t> label;
    search(m, links, &label, &out.flipped);
    for (const Link& l : links)
        if ((out.flipped[static_cast<size_t>(l.from)] ^ out.flipped[static_cast<size_t>(l.to)]) != l.same)
            out.orientable = false;

    // Closed components: each of their edges used by exactly two of their faces.
    const size_t count = static_cast<size_t>(*std::max_element(label.begin(), label.end())) + 1;
    std::vector<std::uint8_t> open(count, 0);
    std::vector<std::int64_t> owners;
    for (size_t e = 0; e < h.edge_count(); ++e) {
        owners.clear();
        for (size_t k = h.start[e]; k < h.start[e + 1]; ++k)
            owners.push_back(label[static_cast<size_t>(h.order[k] / 3)]);
        std::sort(owners.begin(), owners.end());
        for (size_t k = 0; k < owners.size();) {
            size_t end = k;
            while (end < owners.size() && owners[end] == owners[k]) ++end;
            if (end - k != 2) open[static_cast<size_t>(owners[k])] = 1;
            k = end;
        }
    }
    // Outward: the signed volume of each closed component, cones from the box centre.
    const Vec3 centre = box_centre(vertices, vertex_count);
    std::vector<double> volume(count, 0.0), magnitude(count, 0.0);
    for (std::int64_t f = 0; f < m; ++f) {
        const bool r = out.flipped[static_cast<size_t>(f)] != 0;
        const Vec3 p = corner(vertices, faces, f, 0, r) - centre;
        const Vec3 q = corner(vertices, faces, f, 1, r) - centre;
        const Vec3 s = corner(vertices, faces, f, 2, r) - centre;
        const double cone = dot(p, cross(q, s)) / 6.0;
        volume[static_cast<size_t>(label[static_cast<size_t>(f)])] += cone;
        magnitude[static_cast<size_t>(label[static_cast<size_t>(f)])] += std::fabs(cone);
    }
    // A flat component (its volume within the rounding of its cones) has no outward: kept.
    for (std::int64_t f = 0; f < m; ++f) {
        const auto c = static_cast<size_t>(label[static_cast<size_t>(f)]);
        if (!open[c] && volume[c] < -flat_volume * magnitude[c]) out.flipped[static_cast<size_t>(f)] ^= 1;
    }
    // Nesting: a closed component inside an odd number of the others is a cavity's wall.
    std::vector<std::int64_t> shut;
    for (size_t c = 0; c < count; ++c)
        if (!open[c]) shut.push_back(static_cast<std::int64_t>(c));
    if (shut.size() > 1 && shut.size() <= static_cast<size_t>(std::max(nesting_max_components, 0))) {
        std::vector<std::int64_t> closed_faces, tags;
        std::vector<std::int64_t> first(count, -1);
        for (std::int64_t f = 0; f < m; ++f) {
            const std::int64_t c = label[static_cast<size_t>(f)];
            if (open[static_cast<size_t>(c)]) continue;
            closed_faces.push_back(f);
            tags.push_back(c);
            if (first[static_cast<size_t>(c)] < 0) first[static_cast<size_t>(c)] = f;
        }
        const parity_detail::ParityFaces all(vertices, faces, closed_faces, tags);
        std::vector<std::uint8_t> turn(count, 0);
        for (const std::int64_t c : shut) {
            const std::int64_t f = first[static_cast<size_t>(c)];
            const bool r = out.flipped[static_cast<size_t>(f)] != 0;
            // numpy's mean of the three corners: ((a + b) + c) / 3
            const Vec3 probe = (corner(vertices, faces, f, 0, r) + corner(vertices, faces, f, 1, r) +
                                corner(vertices, faces, f, 2, r)) /
                               3.0;
            turn[static_cast<size_t>(c)] = all.classify(probe, c) == Parity::inside;
        }
        for (std::int64_t f = 0; f < m; ++f)
            out.flipped[static_cast<size_t>(f)] ^= turn[static_cast<size_t>(label[static_cast<size_t>(f)])];
    }
    out.balanced = balanced(h, out.flipped);
    return out;
}

}  // namespace meshcol
