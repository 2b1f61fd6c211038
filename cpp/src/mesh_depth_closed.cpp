// The mesh depth over the points of a mesh whose other mesh is closed (mesh_depth.cpp holds
// the rest of the query): regions decided by one exact test each, then the deepest point by
// branch and bound.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <utility>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_depth.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// The region pass walks a mesh in one flat pass, every vertex then every triangle, instead of
// descending its hierarchy, when more than this share of its root box (mapped into the other
// mesh's frame and enclosed) lies in the other's root box: the descent would visit nearly
// every node anyway.
constexpr double kFlatPassShare = 0.5;
// After a descent, the vertices it found inside the other's box are decided in vertex order
// from their sorted list when they are fewer than 1 in this many of the mesh's vertices;
// otherwise a pass in order over every record is cheaper than the sort.
constexpr size_t kSortedVisitRatio = 8;

// What the depth search keeps of one mesh's vertices and nodes, reused by the searches on a
// thread: a record is current only when its stamp is the search's generation, so a search
// starts without a pass over the mesh (the MappedObbCache pattern of mesh_distance.cpp).
struct RegionScratch {
    struct Vertex {
        std::uint32_t stamp;
        std::int32_t parent;  // union-find of the regions
        Side side;            // the vertex's side of the other solid
        Side region;          // a root's: its region's side
        char in_box;          // inside the other's root box (mapped into its frame)
        char regular;         // a corner of a triangle that is not near the other surface
        char done;            // measured (or passed over) by the search
    };
    std::vector<Vertex> vertices;
    std::vector<std::uint32_t> live_stamp;  // a node holding a corner that may be inside
    std::uint32_t generation = 0;
    // Lists of this search: the vertices visited inside the box, the corners of regular
    // triangles outside it, the nodes visited (preorder), the descent's stack.
    std::vector<std::int32_t> in_box, outside, visited;
    std::vector<std::pair<std::int32_t, bool>> stack;  // a node, and whether it lies inside the box

    // Starts a search over a mesh of `vertex_count` vertices and `node_count` nodes.
    void start(size_t vertex_count, size_t node_count) {
        if (vertices.size() < vertex_count) vertices.resize(vertex_count, Vertex{});
        if (live_stamp.size() < node_count) live_stamp.resize(node_count, 0u);
        if (++generation == 0) {  // wrapped: every old stamp could read as current
            for (Vertex& v : vertices) v.stamp = 0;
            std::fill(live_stamp.begin(), live_stamp.end(), 0u);
            generation = 1;
        }
        in_box.clear();
        outside.clear();
        visited.clear();
    }
    bool live(std::int32_t id) const { return live_stamp[static_cast<size_t>(id)] == generation; }
};

// Where a node of one mesh lies against the other's root box.
enum class BoxOverlap { APART, PARTLY, INSIDE };

// The scratch of the thread's searches, one per mesh of the pair.
RegionScratch* thread_scratch() {
    thread_local RegionScratch scratch[2];
    return scratch;
}

// The depth search over the points of a mesh whose other mesh is closed. The winding number
// of a closed surface is constant along a path that does not meet it (Jacobson et al. 2013),
// so the vertices joined by edges of triangles that are not near the other surface (farther
// than the rounding allowance) form regions lying wholly inside or wholly outside: one exact
// test decides each region (none when a vertex lies outside the other's box), and only the
// vertices of near triangles are decided one by one. The largest distance among the inside
// points is then found by branch and bound, as a one-sided Hausdorff distance over a
// hierarchy: a node of a mesh's own hierarchy bounds the distances of its triangles' corners
// by the distance of its centre plus its radius (the distance to a surface is 1-Lipschitz),
// a piece of an edge of a crossing triangle by the distance of its ends to a triangle it
// crosses (the distance to a triangle is convex along a segment), a wedge point by its
// distances to the pair it steps in from; groups are opened highest bound first until no
// bound exceeds the best depth found. The answer is the maximum, over the same points as the
// per-point search, of the same distances: only its order of work differs.
class ClosedDepthSearch {
public:
    ClosedDepthSearch(const MeshBvh& a, const MeshBvh& b, const Relative& rel, MeshDepthOutput& out)
        : a_(a), b_(b), rel_(rel), out_(out), slack_(8.0 * rel.slack), scratch_(thread_scratch()) {}

    // Adds the points of mesh m (0: a's, in b's frame; 1: b's, in a's frame): its regions
    // decided, its root node and the edges of its crossing triangles queued. False when the
    // work cap stopped it. Only the part of the mesh that may reach the other's box is
    // visited (a descent of its own hierarchy), unless most of the mesh's box lies in it
    // (then a pass over all of it in order): every vertex outside that box is outside the
    // other solid, and the state of the vertices and nodes lives in the thread's scratch,
    // stamped per call, so that nothing is done over the rest of the mesh.
    bool add_mesh(int m, const TriangleMarks& marks) {
        marks_[m] = &marks;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const BvhNode& root = other.nodes()[0];
        const std::vector<Vec3>& vertices = self.vertices();
        const std::vector<BvhNode>& nodes = self.nodes();
        RegionScratch& s = scratch_[m];
        s.start(vertices.size(), nodes.size());
        // The vertex's record, made on its first visit: outside when outside the box (known
        // inside it when its node is, with room for the rounding of the map).
        auto fresh = [&](std::int32_t v, bool in_box) {
            return RegionScratch::Vertex{s.generation, v, in_box ? Side::UNKNOWN : Side::OUTSIDE, Side::UNKNOWN, in_box, 0, 0};
        };
        auto touch = [&](std::int32_t v, bool node_inside) -> RegionScratch::Vertex& {
            RegionScratch::Vertex& x = s.vertices[static_cast<size_t>(v)];
            if (x.stamp != s.generation) {
                const bool in_box = node_inside || inside_box(root, to_other(m, vertices[static_cast<size_t>(v)]));
                x = fresh(v, in_box);
                if (in_box) s.in_box.push_back(v);
            }
            return x;
        };
        auto find = [&s](std::int32_t v) {
            while (s.vertices[static_cast<size_t>(v)].parent != v) {
                RegionScratch::Vertex& x = s.vertices[static_cast<size_t>(v)];
                x.parent = s.vertices[static_cast<size_t>(x.parent)].parent;
                v = x.parent;
            }
            return v;
        };
        // Triangles wholly outside the box are left out: a region of the others reaches
        // outside through a triangle with a corner in the box, so the regions found are parts
        // of the true ones, each still on one side (a region's root is its least vertex,
        // whatever the order the triangles are joined in).
        auto join = [&](std::int32_t i, RegionScratch::Vertex* const* c) {
            if (marks.near(i) || !(c[0]->in_box || c[1]->in_box || c[2]->in_box)) return;
            const std::int32_t* t = self.triangle_vertices(i);
            for (int k = 0; k < 3; ++k) {
                if (!c[k]->regular && !c[k]->in_box) s.outside.push_back(t[k]);
                c[k]->regular = 1;
            }
            // The three corners joined, each then pointing at the root, so later finds are short.
            const std::int32_t x = find(t[0]), y = find(t[1]), z = find(t[2]);
            const std::int32_t r = std::min(x, std::min(y, z));
            s.vertices[static_cast<size_t>(x)].parent = s.vertices[static_cast<size_t>(y)].parent = r;
            s.vertices[static_cast<size_t>(z)].parent = r;
            c[0]->parent = c[1]->parent = c[2]->parent = r;
        };
        // When most of the mesh's box lies in the other's, nearly every node would be visited:
        // one pass in order over all the vertices, then all the triangles, is cheaper.
        const bool flat = mostly_inside(m, nodes[0], root);
        deep_ = deep_ || flat;
        if (flat) {
            for (size_t v = 0; v < vertices.size(); ++v)
                s.vertices[v] = fresh(static_cast<std::int32_t>(v), inside_box(root, to_other(m, vertices[v])));
            for (std::int32_t i = 0; i < self.triangle_count(); ++i) {
                const std::int32_t* t = self.triangle_vertices(i);
                RegionScratch::Vertex* c[3] = {&s.vertices[static_cast<size_t>(t[0])], &s.vertices[static_cast<size_t>(t[1])],
                                               &s.vertices[static_cast<size_t>(t[2])]};
                join(i, c);
            }
        } else {
            // A node whose box misses the other's box holds no corner in it; one whose box
            // lies inside it holds only corners inside, and its subtree is not tested again.
            s.stack.assign(1, {0, false});
            while (!s.stack.empty()) {
                const auto [id, known_inside] = s.stack.back();
                s.stack.pop_back();
                const BvhNode& node = nodes[static_cast<size_t>(id)];
                const BoxOverlap overlap = known_inside ? BoxOverlap::INSIDE : node_overlap(m, node, root);
                if (overlap == BoxOverlap::APART) continue;
                const bool inside = overlap == BoxOverlap::INSIDE;
                s.visited.push_back(id);
                if (!node.is_leaf()) {
                    s.stack.push_back({node.index, inside});
                    s.stack.push_back({id + 1, inside});
                    continue;
                }
                for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                    const std::int32_t* t = self.triangle_vertices(i);
                    RegionScratch::Vertex* c[3] = {&touch(t[0], inside), &touch(t[1], inside), &touch(t[2], inside)};
                    join(i, c);
                }
            }
        }
        // A region with a vertex outside the other's box is outside; otherwise one vertex
        // (off the surface by more than the rounding allowance) decides it, the first in
        // vertex order.
        for (const std::int32_t v : s.outside) s.vertices[static_cast<size_t>(find(v))].region = Side::OUTSIDE;
        auto decide = [&](std::int32_t v) {
            RegionScratch::Vertex& x = s.vertices[static_cast<size_t>(v)];
            if (!x.regular) return true;  // decided alone, when it matters
            Side& r = s.vertices[static_cast<size_t>(find(v))].region;
            if (r == Side::UNKNOWN) {
                if (!may_test()) return false;
                r = inside_mesh(other, to_other(m, vertices[static_cast<size_t>(v)]), &work_) ? Side::INSIDE : Side::OUTSIDE;
            }
            x.side = r;
            return true;
        };
        // In vertex order: the visited ones sorted, or every record read when most are inside.
        if (!flat && kSortedVisitRatio * s.in_box.size() < vertices.size()) {
            std::sort(s.in_box.begin(), s.in_box.end());
            for (const std::int32_t v : s.in_box)
                if (!decide(v)) return false;
        } else {
            for (size_t v = 0; v < vertices.size(); ++v) {
                const RegionScratch::Vertex& x = s.vertices[v];
                if (x.stamp == s.generation && x.in_box && !decide(static_cast<std::int32_t>(v))) return false;
            }
        }
        // Nodes holding a corner that may be inside: children before parents (ids and the
        // visit are in preorder), a node not visited holding none.
        auto mark_live = [&](std::int32_t id) {
            const BvhNode& node = nodes[static_cast<size_t>(id)];
            bool live = false;
            if (!node.is_leaf()) {
                live = s.live(id + 1) || s.live(node.index);
            } else {
                for (std::int32_t i = node.index; i < node.index + node.count && !live; ++i)
                    for (int k = 0; k < 3; ++k)
                        if (s.vertices[static_cast<size_t>(self.triangle_vertices(i)[k])].side != Side::OUTSIDE) live = true;
            }
            if (live) s.live_stamp[static_cast<size_t>(id)] = s.generation;
        };
        if (flat) {
            for (size_t n = nodes.size(); n-- > 0;) mark_live(static_cast<std::int32_t>(n));
        } else {
            for (size_t n = s.visited.size(); n-- > 0;) mark_live(s.visited[n]);
        }
        if (s.live(0)) refine_node({kInf, kNode, m, 0, 0});
        return true;
    }

    // Queues the edges of mesh m's crossing triangles, each bounded by its ends' distances to
    // a triangle that its triangle crosses (after the vertices: most are then within the best
    // depth already and never queued). The crossing triangles are read off the crossing
    // pairs, in triangle order, rather than off a pass over the whole mesh.
    void add_edges(int m, const std::vector<CrossingPair>& pairs) {
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const TriangleMarks& marks = *marks_[m];
        std::vector<std::int32_t>& crossing = crossing_;
        crossing.clear();
        for (const CrossingPair& pair : pairs) crossing.push_back(m == 0 ? pair.a : pair.b);
        std::sort(crossing.begin(), crossing.end());
        crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
        for (const std::int32_t i : crossing) {
            const std::int32_t partner = marks.near_entry(i).partner;
            const Vec3* t = self.triangle(i);
            const Vec3* tp = other.triangle(partner);
            double ends[3];
            for (int k = 0; k < 3; ++k) ends[k] = triangle_distance_of(to_other(m, t[k]), tp);
            for (int k = 0; k < 3; ++k) push({max2(ends[k], ends[(k + 1) % 3]) + slack_, kEdge, m, i, k});
        }
    }

    // Queues the wedge points (both meshes closed) of each crossing pair that gets them, made
    // when the pair comes up. A point's depth is at most its distances to the pair's two
    // triangles (each surface's distance is a minimum over its triangles), and every point
    // steps at most h / 2 (h: the shorter triangle's longest edge) off a point of both
    // triangles (a shared point: triangles_intersect's witnesses) or off one triangle's
    // centroid, whose distance to that triangle is 0: its depth is at most h / 2 plus the
    // larger distance of a centroid to the other triangle.
    void add_wedges(const std::vector<CrossingPair>& pairs) {
        pairs_ = &pairs;
        const size_t stride = wedge_stride(pairs);
        for (size_t k = 0; k < pairs.size(); k += stride) {
            const Vec3* ta = a_.triangle(pairs[k].a);
            const Vec3* tb_local = b_.triangle(pairs[k].b);
            const Vec3 tb[3] = {rel_.apply(tb_local[0]), rel_.apply(tb_local[1]), rel_.apply(tb_local[2])};
            const Vec3 centroid_a = (ta[0] + ta[1] + ta[2]) / 3.0;
            const Vec3 centroid_b = (tb[0] + tb[1] + tb[2]) / 3.0;
            const double reach = max2(triangle_distance_of(centroid_a, tb), triangle_distance_of(centroid_b, ta)) +
                                 0.5 * std::fmin(longest_edge(ta), longest_edge(tb));
            push({reach * (1.0 + 1e-9) + slack_, kWedge, 2, static_cast<std::int32_t>(k), 0});
        }
    }

    // Opens the queue highest bound first until no bound exceeds the best depth. False when
    // the work cap stopped it.
    bool run() {
        std::vector<double> cuts;
        while (!heap_.empty()) {
            std::pop_heap(heap_.begin(), heap_.end());
            const Entry e = heap_.back();
            heap_.pop_back();
            if (!(e.bound > best)) break;
            bool ok = true;
            if (e.kind == kNode) {
                // A leaf whose bound is already within twice its radius of the best depth has
                // its few corners measured directly (each search cut off at the best depth,
                // mostly at its first leaf): cheaper than refining a deep centre's bound.
                if (e.refined || direct_leaf(e)) {
                    ok = open_node(e);
                } else {
                    refine_node(e);
                }
            } else if (e.kind == kEdge) {
                const MeshBvh& self = e.mesh == 0 ? a_ : b_;
                const MeshBvh& other = e.mesh == 0 ? b_ : a_;
                const BvhNode& root = other.nodes()[0];
                const Vec3* t = self.triangle(e.index);
                std::int64_t piece = 0;
                // The triangles the edge meets are near its triangle (the marks' margin is far
                // above the rounding of the frames): the cuts of segment_crossings, found
                // among those alone.
                const Vec3 p = to_other(e.mesh, t[e.k]), q = to_other(e.mesh, t[(e.k + 1) % 3]);
                const TriangleMarks& marks = *marks_[e.mesh];
                const std::int32_t partner = marks.near_entry(e.index).partner;  // a seed of the pieces
                cuts.assign({0.0, 1.0});
                // A triangle whose box misses the segment's (compared exactly, on the same
                // coordinates) has no point in common with it: not a cut.
                const TriangleBox segment{min3(p, q), max3(p, q)};
                const auto [first, last] = marks.near_range(e.index);
                for (std::int32_t n = first; n < last; ++n) {
                    const Vec3* t = other.triangle(marks.others[static_cast<size_t>(n)]);
                    double cut = 0.0;
                    if (triangle_box_squared_distance(segment, triangle_box(t)) == 0.0 &&
                        segment_crosses_triangle(p, q, t, &cut))
                        cuts.push_back(cut);
                }
                add_pieces(p, q, cuts,
                                [&](const Vec3& p) {
                                    const Order order{e.mesh, 1, 3 * std::int64_t{e.index} + e.k, piece++};
                                    if (ok && inside_box(root, p))
                                        ok = try_point(e.mesh, p, Side::UNKNOWN, nullptr, order, {partner, kNaN});
                                });
            } else {
                wedges_.clear();
                const CrossingPair& pair = (*pairs_)[static_cast<size_t>(e.index)];
                // try_wedge skips a point whose distances to the pair's triangles are within
                // the best depth less the rounding allowance; so are shared points' steps (a
                // second allowance for the rounding of those points).
                add_pair_wedge_points(a_, b_, rel_, *pairs_, static_cast<size_t>(e.index), wedges_, best - 2.0 * slack_);
                for (size_t k = 0; k < wedges_.size() && ok; ++k)
                    ok = try_wedge(wedges_[k], pair, Order{2, e.index, static_cast<std::int64_t>(k), 0},
                                  wedge_point_from_a(k));
            }
            if (!ok) return false;
        }
        return true;
    }

    double best = 0.0;
    bool have = false;
    DepthCandidate winner{};
    // The other mesh's triangle (leaf order) nearest a vertex or edge winner, found by the
    // search that measured it (closest_point's, uncut), else -1.
    std::int32_t winner_triangle = -1;
    long long work() const { return work_; }

private:
    // A point's place in the per-point search's order: mesh (0, 1, 2: wedges), then its
    // vertices before its edge pieces (0, 1), then vertex, 3 * triangle + edge, or wedge
    // point, then the piece along the edge.
    struct Order {
        std::int64_t mesh, group, index, piece;
        bool operator<(const Order& o) const {
            return std::tie(mesh, group, index, piece) < std::tie(o.mesh, o.group, o.index, o.piece);
        }
    };
    static constexpr int kNode = 0, kEdge = 1, kWedge = 2;
    struct Entry {
        double bound;  // no point of the group is farther than this from the other surface
        int kind, mesh;
        std::int32_t index;  // node, triangle (leaf order) or crossing pair (wedge points)
        int k;               // edge k of the triangle
        // A node: a triangle of the other mesh (leaf order) near it, and whether `bound` comes
        // from its centre's distance (else from its distance to `near`, a looser bound).
        std::int32_t near = -1;
        bool refined = false;
        bool operator<(const Entry& o) const { return bound < o.bound; }
    };

    Vec3 to_other(int m, const Vec3& p) const { return m == 0 ? rel_.apply_inverse(p) : rel_.apply(p); }

    // Mesh m's node box mapped into the other's frame and enclosed there: its centre and its
    // half extents.
    std::pair<Vec3, Vec3> mapped_box(int m, const BvhNode& node) const {
        return m == 0 ? rel_.enclose_in_b(node) : rel_.enclose_in_a(node);
    }

    // Where mesh m's node lies against `box` (the other's root) once to_other maps it: its
    // box mapped into the other's frame and enclosed there, with a margin of a relative 1e-9
    // and the rounding allowance of the map, so that rounding can only make it PARTLY: APART
    // when no point of it maps into the box, INSIDE when every point does.
    BoxOverlap node_overlap(int m, const BvhNode& node, const BvhNode& box) const {
        const auto [center, reach] = mapped_box(m, node);
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
            const double pad = slack_ + 1e-9 * (std::fabs(center[k]) + reach[k] + std::fabs(box.lower[k]) +
                                                std::fabs(box.upper[k]));
            const double low = center[k] - reach[k], high = center[k] + reach[k];
            if (high + pad < box.lower[k] || low - pad > box.upper[k]) return BoxOverlap::APART;
            inside = inside && low - pad >= box.lower[k] && high + pad <= box.upper[k];
        }
        return inside ? BoxOverlap::INSIDE : BoxOverlap::PARTLY;
    }

    // Whether over half the volume of mesh m's node, its box mapped and enclosed, lies in
    // `box` (the other's root): the descent would then visit nearly every node.
    bool mostly_inside(int m, const BvhNode& node, const BvhNode& box) const {
        const auto [center, reach] = mapped_box(m, node);
        double share = 1.0;
        for (int k = 0; k < 3; ++k) {
            const double low = center[k] - reach[k], high = center[k] + reach[k];
            const double common = min2(high, box.upper[k]) - max2(low, box.lower[k]);
            share *= high > low ? max2(0.0, common) / (high - low) : (low >= box.lower[k] && high <= box.upper[k] ? 1.0 : 0.0);
        }
        return share > kFlatPassShare;
    }

    static double triangle_distance_of(const Vec3& p, const Vec3* t) {
        return std::sqrt(squared_norm(closest_point_on_triangle(p, t) - p));
    }

    void push(const Entry& e) {
        if (!(e.bound > best)) return;
        heap_.push_back(e);
        std::push_heap(heap_.begin(), heap_.end());
    }

    // Child `id` of mesh m's node whose other-mesh triangle is `near`: first bounded by its
    // centre's distance to that triangle, plus its radius (refined when it comes up).
    void push_node(int m, std::int32_t id, std::int32_t near) {
        if (!scratch_[m].live(id)) return;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const WindingNode& w = self.winding_nodes()[static_cast<size_t>(id)];
        const double d = triangle_distance_of(to_other(m, w.center), other.triangle(near));
        push({d + w.radius + slack_, kNode, m, id, 0, near, false});
    }

    // The node bounded by its centre's distance to the other surface (a search cut off once
    // the bound cannot beat the best) plus its radius, queued again.
    void refine_node(const Entry& e) {
        const MeshBvh& self = e.mesh == 0 ? a_ : b_;
        const MeshBvh& other = e.mesh == 0 ? b_ : a_;
        const WindingNode& w = self.winding_nodes()[static_cast<size_t>(e.index)];
        const double floor = best - w.radius - slack_;
        std::int32_t near = 0;
        const Vec3 center = to_other(e.mesh, w.center);
        // The parent's triangle, when known, starts the search (a bound to prune with), which
        // then stops within half the node's radius of the distance. Where a mesh lies mostly
        // in the other's box (the flat pass: a deep overlap, most nodes opened) the search
        // runs unseeded to within the whole radius and the parent's triangle is taken when
        // nearer: there the seeded bounds cost more searches than they saved (the torus moved
        // 30%: 18.65M -> 18.82M instructions), elsewhere they save them (fandisk touching
        // 1.50M -> 1.44M a pair, the torus on the floor 11.8M -> 10.6M).
        double d;
        if (!deep_) {
            const DistanceSeed seed = e.near >= 0 ? seed_of(other, e.near, center) : DistanceSeed{};
            d = distance_within(other, center, max2(0.0, floor), 0.5 * w.radius, &near, seed);
        } else {
            d = distance_within(other, center, max2(0.0, floor), w.radius, &near);
            if (e.near >= 0) {  // the parent's triangle may be nearer than the one found
                const double parent = triangle_distance_of(center, other.triangle(e.near));
                if (parent < d) {
                    d = parent;
                    near = e.near;
                }
            }
        }
        if (d <= floor) return;
        push({d + w.radius + slack_, kNode, e.mesh, e.index, 0, near, true});
    }

    bool direct_leaf(const Entry& e) const {
        const MeshBvh& self = e.mesh == 0 ? a_ : b_;
        const auto id = static_cast<size_t>(e.index);
        return self.nodes()[id].is_leaf() && have && e.bound <= best + 2.0 * self.winding_nodes()[id].radius;
    }

    bool open_node(const Entry& e) {
        const int m = e.mesh;
        const MeshBvh& self = m == 0 ? a_ : b_;
        const MeshBvh& other = m == 0 ? b_ : a_;
        const BvhNode& node = self.nodes()[static_cast<size_t>(e.index)];
        if (!node.is_leaf()) {
            push_node(m, e.index + 1, e.near);
            push_node(m, node.index, e.near);
            return true;
        }
        for (std::int32_t i = node.index; i < node.index + node.count; ++i)
            for (int k = 0; k < 3; ++k) {
                const std::int32_t v = self.triangle_vertices(i)[k];
                // A corner of a live leaf: visited by add_mesh, so its record is current.
                RegionScratch::Vertex& vertex = scratch_[m].vertices[static_cast<size_t>(v)];
                if (vertex.done) continue;
                vertex.done = 1;
                Side& side = vertex.side;
                if (side == Side::OUTSIDE) continue;
                const Vec3 p = to_other(m, self.vertices()[static_cast<size_t>(v)]);
                // Bounded by the node's triangle and by the triangles near its own; a point at
                // distance 0 from one (on the surface: the search would find 0) gives nothing.
                // The nearest of them seeds the point's distance search.
                DistanceSeed seed = seed_of(other, e.near, p);
                const TriangleMarks& marks = *marks_[m];
                const auto [first, last] = marks.near_range(i);
                for (std::int32_t n = first; n < last && seed.squared > 0.0; ++n) {
                    const DistanceSeed next = seed_of(other, marks.others[static_cast<size_t>(n)], p);
                    if (next.squared < seed.squared) seed = next;
                }
                const double bound = std::sqrt(seed.squared);
                if (bound == 0.0 || !(bound + slack_ > best)) continue;
                if (!try_point(m, p, side, &side, Order{m, 0, v, 0}, seed)) return false;
            }
        return true;
    }

    // Whether a point at distance d, `order` in the per-point search, would have replaced the
    // best there: deeper, or as deep and sampled before it (so that the deepest point, and
    // thus the witnesses, are the same whatever the order of work). A distance equal to the
    // best that came from a search cut off at it (at most the best) is measured in full.
    template <class Full>
    bool beats(double& d, const Order& order, Full full) const {
        if (d > best) return true;
        if (!(have && d == best && order < winner_order_)) return false;
        d = full();
        return d == best;
    }

    // A point of mesh m (other's frame) whose side is `known` (UNKNOWN: an exact test, its
    // verdict stored in `*store` when given): the new best when inside and deeper. `seed`, a
    // triangle of the other mesh near p and p's squared distance to it (NaN: not measured
    // yet), bounds p's distance searches.
    bool try_point(int m, const Vec3& p, Side known, Side* store, const Order& order, DistanceSeed seed) {
        const MeshBvh& other = m == 0 ? b_ : a_;
        if (known == Side::UNKNOWN) {  // a recorded ball may say outside before any measuring
            known = recorded_side(m == 0 ? 1 : 0, p);
            if (known == Side::OUTSIDE) {
                if (store != nullptr) *store = known;
                return true;
            }
        }
        if (std::isnan(seed.squared)) seed = seed_of(other, seed.triangle, p);
        std::int32_t triangle = -1;
        double d = distance_beyond(other, p, best, &triangle, seed);
        if (!beats(d, order, [&] { return distance_beyond(other, p, 0.0, &triangle, seed); })) return true;
        if (known == Side::UNKNOWN) {
            // d is p's exact distance to other's surface here (beats measured it in full)
            if (!may_test()) return false;
            known = inside_mesh(other, p, &work_) ? Side::INSIDE : Side::OUTSIDE;
            record_side(m == 0 ? 1 : 0, p, d, known);
            if (store != nullptr) *store = known;
        }
        if (known == Side::INSIDE) {
            best = d;
            winner = {p, d, m, false};
            winner_triangle = triangle;
            winner_order_ = order;
            have = true;
        }
        return true;
    }

    // A wedge point of crossing pair `pair`: the new best when inside both and deeper.
    // `b_first`: a point stepped from a's centroid into a, whose side of b is the open
    // question (most such points are outside b): b is tested first.
    bool try_wedge(DepthCandidate& c, const CrossingPair& pair, const Order& order, bool b_first) {
        // Outside a closed mesh's box is outside it (the test's verdict, without its work).
        const Vec3 in_b = rel_.apply_inverse(c.point);
        if (!inside_box(a_.nodes()[0], c.point) || !inside_box(b_.nodes()[0], in_b)) return true;
        // Its distances to the pair's own two triangles bound its depth from above (each
        // surface's distance is a minimum over its triangles, these among them): a point that
        // cannot reach the best depth is not measured. Most are, as the points step off the
        // pair's shared points by at most half the shorter triangle's longest edge.
        // The two seed the point's distance searches.
        const DistanceSeed seed_a = seed_of(a_, pair.a, c.point), seed_b = seed_of(b_, pair.b, in_b);
        const double own = max2(std::sqrt(seed_a.squared), std::sqrt(seed_b.squared));
        if (!(own + slack_ > best)) return true;
        // A point a recorded ball puts outside either solid is not measured.
        Side side_a = recorded_side(0, c.point);
        if (side_a == Side::OUTSIDE) return true;
        Side side_b = recorded_side(1, in_b);
        if (side_b == Side::OUTSIDE) return true;
        // Each distance is exact when above the floor of its search (then a ball free of
        // that surface, recorded with the point's side of it).
        double da = 0.0, db = 0.0, floor_used = 0.0;
        bool have_db = false;
        auto measure = [&](double floor) {
            floor_used = floor;
            da = distance_beyond(a_, c.point, floor, nullptr, seed_a);
            db = distance_beyond(b_, in_b, floor, nullptr, seed_b);
            have_db = true;
            c.farther_is_a = da >= db;
            return std::fmax(da, db);
        };
        // The point's distance to b, measured when needed (as measure(best) would): a point
        // whose distance to a exceeds the best beats it whatever that distance, which then
        // matters only for a point inside a.
        auto measure_b = [&] {
            if (have_db) return;
            db = distance_beyond(b_, in_b, floor_used, nullptr, seed_b);
            have_db = true;
            c.farther_is_a = da >= db;
            c.distance = std::fmax(da, db);
        };
        floor_used = best;
        da = distance_beyond(a_, c.point, best, nullptr, seed_a);
        if (!(da > best)) {
            measure_b();
            if (!beats(c.distance, order, [&] { return measure(0.0); })) return true;
        }
        // Sides not known yet are tested (one count for the point), the second only when the
        // first says inside.
        if (side_a == Side::UNKNOWN || side_b == Side::UNKNOWN) {
            if (!may_test()) return false;
            auto test_a = [&] {
                side_a = inside_mesh(a_, c.point, &work_) ? Side::INSIDE : Side::OUTSIDE;
                if (da > floor_used) record_side(0, c.point, da, side_a);
            };
            auto test_b = [&] {
                measure_b();
                side_b = inside_mesh(b_, in_b, &work_) ? Side::INSIDE : Side::OUTSIDE;
                if (db > floor_used) record_side(1, in_b, db, side_b);
            };
            if (b_first) {
                if (side_b == Side::UNKNOWN) test_b();
                if (side_b == Side::INSIDE && side_a == Side::UNKNOWN) test_a();
            } else {
                if (side_a == Side::UNKNOWN) test_a();
                if (side_a == Side::INSIDE && side_b == Side::UNKNOWN) test_b();
            }
        }
        if (side_a == Side::INSIDE && side_b == Side::INSIDE) {
            measure_b();
            best = c.distance;
            winner = c;
            winner_triangle = -1;
            winner_order_ = order;
            have = true;
        }
        return true;
    }

    // The side of solid x (0: a, 1: b) of a point p (x's frame) that a recorded ball gives.
    Side recorded_side(int x, const Vec3& p) const { return balls_[x].side_of(p, kBallsRead); }

    // Records that p (x's frame), at exact distance d from x's surface, is on `side` of it:
    // the ball about p of radius d less the rounding allowance holds no surface of x.
    void record_side(int x, const Vec3& p, double d, Side side) { balls_[x].add(p, d - slack_, side); }

    // Counts one exact inside test, or stops at the work cap.
    bool may_test() {
        if (work_ > defaults::mesh_depth_max_work) {
            out_.status = Status::MAX_ITERATIONS;
            return false;
        }
        ++out_.points_tested;
        return true;
    }

    const MeshBvh& a_;
    const MeshBvh& b_;
    const Relative& rel_;
    MeshDepthOutput& out_;
    double slack_;  // allowance for rounding in the distance bounds (absolute)
    bool deep_ = false;  // a mesh took the flat region pass: most of its box lies in the other's
    long long work_ = 0;
    // The state of each mesh's vertices and nodes, in the thread's scratch (thread_local:
    // the batch runs pairs on threads), valid for this search only.
    RegionScratch* scratch_;
    const TriangleMarks* marks_[2] = {nullptr, nullptr};
    const std::vector<CrossingPair>* pairs_ = nullptr;
    std::vector<DepthCandidate> wedges_;  // scratch: one pair's wedge points
    // Points whose side of solid x (0: a, 1: b) an exact test found, with a ball about each
    // that holds no surface of x (x's frame).
    static constexpr size_t kBallsRead = 64;
    SideBalls balls_[2];
    std::vector<std::int32_t> crossing_;  // scratch of add_edges
    std::vector<Entry> heap_;
    Order winner_order_{};
};

}  // namespace

namespace mesh_detail {

ClosedDepth search_closed_depth(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                                const TriangleMarks& marks_a, const TriangleMarks& marks_b,
                                const std::vector<CrossingPair>& crossing_pairs, MeshDepthOutput& out) {
    ClosedDepthSearch search(a, b, rel, out);
    const bool closed_other[2] = {b.closed(), a.closed()};
    bool running = true;
    for (int m = 0; m < 2 && running; ++m)
        if (closed_other[m]) running = search.add_mesh(m, m == 0 ? marks_a : marks_b);
    if (running) running = search.run();  // the vertices first: a best depth to prune with
    for (int m = 0; m < 2 && running; ++m)
        if (closed_other[m]) search.add_edges(m, crossing_pairs);
    if (running && a.closed() && b.closed()) search.add_wedges(crossing_pairs);
    if (running) running = search.run();
    ClosedDepth found;
    found.best = search.best;
    found.have = search.have;
    found.winner = search.winner;
    found.winner_triangle = search.winner_triangle;
    found.work = search.work();
    found.running = running;
    return found;
}

}  // namespace mesh_detail
}  // namespace meshcol
