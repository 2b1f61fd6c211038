// The mesh penetration depth: a lower bound of the minimum translation distance, the largest
// distance to the other surface of a sampled point of one mesh inside the other (the
// definition is in mesh_query.hpp). This file makes the sample points, measures them, decides
// the points whose other mesh is open (deepest first, by the generalized winding number) and
// writes the answer; mesh_depth_closed.cpp searches the points whose other mesh is closed.
#include <algorithm>
#include <cmath>
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

void add_wedge_candidates(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                          const std::vector<CrossingPair>& pairs, std::vector<DepthCandidate>& out) {
    const size_t stride = wedge_stride(pairs);
    for (size_t k = 0; k < pairs.size(); k += stride) add_pair_wedge_points(a, b, rel, pairs, k, out);
}

// The midpoints of the pieces into which other's surface cuts the segment [p, q] (other's
// frame), passed to `add`; `cuts` is scratch space.
template <class Add>
void add_edge_pieces(const MeshBvh& other, const Vec3& p, const Vec3& q, std::vector<double>& cuts, Add add) {
    cuts.assign({0.0, 1.0});
    segment_crossings(other, p, q, cuts);
    add_pieces(p, q, cuts, add);
}

// Sample points of `self` (their frame mapped into `other`'s by `to_other`) that may lie
// inside `other`: vertices within other's root box, and midpoints of the pieces into which the
// other surface cuts the edges of self's crossing triangles.
template <class Map>
void add_candidates(const MeshBvh& self, const MeshBvh& other, const std::vector<char>& crossing,
                    Map to_other, int mesh, std::vector<DepthCandidate>& out) {
    const BvhNode& root = other.nodes()[0];
    auto add = [&](const Vec3& p) {
        if (inside_box(root, p)) out.push_back({p, 0.0, mesh, false});
    };
    for (const Vec3& v : self.vertices()) add(to_other(v));
    std::vector<double> cuts;
    for (std::int32_t i = 0; i < self.triangle_count(); ++i) {
        if (!crossing[static_cast<size_t>(i)]) continue;
        const Vec3* t = self.triangle(i);
        for (int k = 0; k < 3; ++k) {
            add_edge_pieces(other, to_other(t[k]), to_other(t[(k + 1) % 3]), cuts, add);
        }
    }
}

}  // namespace

namespace mesh_detail {

// The wedge points of crossing pair k (add_wedge_candidates), appended to `out`.
void add_pair_wedge_points(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                           const std::vector<CrossingPair>& pairs, size_t k, std::vector<DepthCandidate>& out,
                           double floor) {
    {
        const CrossingPair& c = pairs[k];
        const Vec3* ta = a.triangle(c.a);
        const Vec3* tb_local = b.triangle(c.b);
        const Vec3 tb[3] = {rel.apply(tb_local[0]), rel.apply(tb_local[1]), rel.apply(tb_local[2])};
        const Vec3 na = cross(ta[1] - ta[0], ta[2] - ta[0]);
        const Vec3 nb = cross(tb[1] - tb[0], tb[2] - tb[0]);
        const double la = norm(na), lb = norm(nb);
        if (!(la > 0.0 && lb > 0.0)) return;
        const double h = std::fmin(longest_edge(ta), longest_edge(tb));
        const Vec3 centroid_a = (ta[0] + ta[1] + ta[2]) / 3.0;
        const Vec3 centroid_b = (tb[0] + tb[1] + tb[2]) / 3.0;
        for (double step : {0.5 * h, 0.125 * h, 0.03125 * h}) {
            // Each triangle's centroid, stepped into its own solid: finds coincident and
            // coplanar overlaps, whose shared points all lie on edges of both. a's and b's in
            // turn (wedge_point_from_a reads this order).
            out.push_back({centroid_a - na * (step / la), 0.0, 2, false});
            out.push_back({centroid_b - nb * (step / lb), 0.0, 2, false});
        }
        const Vec3 sum = na / la + nb / lb;
        const double ls = norm(sum);
        if (!(ls > 1e-6)) return;  // opposite normals: faces resting on each other
        // A shared point lies on both triangles, so a step of s from it is within s of both
        // (the relative 1e-9 covers the rounding): none can be deeper than the floor.
        if (!(0.5 * h * (1.0 + 1e-9) > floor)) return;
        // Shared points found from a's side and from b's, so that the samples do not depend on
        // the order of the pair.
        Vec3 witnesses[2];
        triangles_intersect(ta, tb, &witnesses[0]);
        witnesses[1] = witnesses[0];
        triangles_intersect(tb, ta, &witnesses[1]);
        const Vec3 inward = sum * (-1.0 / ls);
        for (const Vec3& witness : witnesses)
            for (double step : {0.5 * h, 0.125 * h, 0.03125 * h})
                out.push_back({witness + inward * step, 0.0, 2, false});
    }
}

// Distance from `point` (mesh's local frame) to the surface when it exceeds `floor`; otherwise
// some value <= floor: the branch and bound of closest_point, stopped at the first triangle
// within `floor` (such a point cannot raise a maximum that is already `floor`). Writes the
// triangle (leaf order) at the returned distance to `*triangle` when given.
//
// A `seed` (a triangle and the point's squared distance to it, as closest_point_on_triangle
// gives it) bounds the answer from above: boxes farther than it are not opened, and when it
// is within `floor` the search is not run. The triangles that can attain the minimum lie in
// boxes no farther than the seed, visited in the same order, so the distance and the triangle
// returned above `floor` are the unseeded search's, bit for bit.
double distance_beyond(const MeshBvh& mesh, const Vec3& point, double floor, std::int32_t* triangle, const DistanceSeed& seed) {
    const double floor2 = floor * floor;
    if (seed.triangle >= 0 && floor >= 0.0 && seed.squared <= floor2) {
        if (triangle != nullptr) *triangle = seed.triangle;
        return std::sqrt(seed.squared);
    }
    const std::vector<BvhNode>& nodes = mesh.nodes();
    const double limit2 = seed.triangle >= 0 ? seed.squared : kInf;
    double best2 = kInf;
    bool found = false;
    // The thread's stack, kept between calls: the depth search runs thousands of these, and
    // each allocated its own.
    thread_local std::vector<std::pair<std::int32_t, double>> stack;
    stack.assign(1, {0, point_node_squared_distance(mesh, 0, point)});
    while (!stack.empty()) {
        const auto [index, bound] = stack.back();
        stack.pop_back();
        if ((found && bound >= best2) || bound > limit2) continue;
        const BvhNode& node = nodes[static_cast<size_t>(index)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const double d2 = squared_norm(closest_point_on_triangle(point, mesh.triangle(i)) - point);
                if (!found || d2 < best2) {
                    best2 = d2;
                    found = true;
                    if (triangle != nullptr) *triangle = i;
                }
            }
            if (best2 <= floor2) break;
            continue;
        }
        push_children(mesh, index, point, found, best2, stack);
    }
    return std::sqrt(best2);
}

// An upper bound of the distance from `point` (mesh's local frame) to the surface, within
// `slack` of it: the branch and bound of distance_beyond with boxes pruned once they cannot
// beat the best distance found by more than `slack`, stopped as it at a triangle within
// `floor`. Writes the triangle (leaf order) at the returned distance to `*triangle`. A `seed`
// starts it as a triangle found first (its distance sqrt(seed.squared)).
double distance_within(const MeshBvh& mesh, const Vec3& point, double floor, double slack, std::int32_t* triangle,
                       const DistanceSeed& seed) {
    const double floor2 = floor * floor;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    double best = kInf, prune2 = kInf;
    bool found = false;
    if (seed.triangle >= 0) {
        best = std::sqrt(seed.squared);
        const double reach = max2(0.0, best - slack);
        prune2 = reach * reach;
        found = true;
        *triangle = seed.triangle;
        if (best * best <= floor2) return best;
    }
    thread_local std::vector<std::pair<std::int32_t, double>> stack;  // kept, as distance_beyond's
    stack.assign(1, {0, point_node_squared_distance(mesh, 0, point)});
    while (!stack.empty()) {
        const auto [index, bound] = stack.back();
        stack.pop_back();
        if (found && bound >= prune2) continue;
        const BvhNode& node = nodes[static_cast<size_t>(index)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                const double d2 = squared_norm(closest_point_on_triangle(point, mesh.triangle(i)) - point);
                if (!found || d2 < best * best) {
                    best = std::sqrt(d2);
                    const double reach = max2(0.0, best - slack);
                    prune2 = reach * reach;
                    found = true;
                    *triangle = i;
                }
            }
            if (best * best <= floor2) break;
            continue;
        }
        push_children(mesh, index, point, found, prune2, stack);
    }
    return best;
}

}  // namespace mesh_detail

MeshDepthOutput mesh_penetration_depth(const MeshDistanceInput& input) {
    MeshDepthOutput out;
    const Vec3 nan3{kNaN, kNaN, kNaN};
    out.point_a = out.point_b = out.normal = nan3;
    if (input.a == nullptr || input.b == nullptr || !input.a->valid() || !input.b->valid()) {
        out.depth = kNaN;
        out.status = Status::INVALID_INPUT;
        return out;
    }
    const MeshBvh& a = *input.a;
    const MeshBvh& b = *input.b;
    const Relative rel(input.pose_a, input.pose_b, *input.a, *input.b);  // b's frame -> a's frame
    TriangleMarks marks_a, marks_b;
    std::vector<CrossingPair> crossing_pairs;
    if (!mark_crossing_triangles(a, b, rel, marks_a, marks_b, crossing_pairs)) {
        out.status = Status::MAX_ITERATIONS;  // too many near pairs to mark: nothing decided
        return out;
    }

    // The points of a mesh whose other mesh is closed: regions and branch and bound.
    out.status = Status::CONVERGED;
    const ClosedDepth closed = search_closed_depth(a, b, rel, marks_a, marks_b, crossing_pairs, out);
    const bool closed_other[2] = {b.closed(), a.closed()};
    const bool wedges_closed = a.closed() && b.closed();
    const bool running = closed.running;
    double best = closed.best;
    bool have = closed.have;
    DepthCandidate winner = closed.winner;
    std::int32_t winner_triangle = closed.winner_triangle;
    long long work = closed.work;

    // Open meshes: the generalized winding number costs a pass over the triangles, so the
    // distances come first and the points are decided deepest first, the first inside one
    // ending the search; a point found outside at distance d proves every point within d of
    // it outside (that ball holds no surface), which skips most of a cluster.
    std::vector<DepthCandidate> undecided;
    if (running) {
        if (!closed_other[0])
            add_candidates(a, b, marks_a.crossing, [&](const Vec3& p) { return rel.apply_inverse(p); }, 0, undecided);
        if (!closed_other[1])
            add_candidates(b, a, marks_b.crossing, [&](const Vec3& p) { return rel.apply(p); }, 1, undecided);
        if (!wedges_closed) add_wedge_candidates(a, b, rel, crossing_pairs, undecided);
    }
    auto inside = [&](const DepthCandidate& c) {
        if (c.mesh == 0) return inside_mesh(b, c.point, &work);
        if (c.mesh == 1) return inside_mesh(a, c.point, &work);
        return inside_mesh(a, c.point, &work) && inside_mesh(b, rel.apply_inverse(c.point), &work);
    };
    // The depth a candidate gives (exact when it exceeds `floor`): its distance to the other
    // surface; for a wedge point, to the farther of the two (`farther_is_a`).
    auto measure = [&](DepthCandidate& c, double floor) {
        if (c.mesh < 2) {
            c.distance = distance_beyond(c.mesh == 0 ? b : a, c.point, floor);
            return;
        }
        const double da = distance_beyond(a, c.point, floor);
        const double db = distance_beyond(b, rel.apply_inverse(c.point), floor);
        c.distance = std::fmax(da, db);
        c.farther_is_a = da >= db;
    };
    if (out.status == Status::CONVERGED && !undecided.empty()) {
        for (DepthCandidate& c : undecided) measure(c, best);
        undecided.erase(std::remove_if(undecided.begin(), undecided.end(),
                                       [best](const DepthCandidate& c) { return !(c.distance > best); }),
                        undecided.end());
        std::sort(undecided.begin(), undecided.end(),
                  [](const DepthCandidate& x, const DepthCandidate& y) { return x.distance > y.distance; });
        SideBalls outside[2];
        constexpr size_t kBallsChecked = 256;
        for (const DepthCandidate& c : undecided) {
            if (c.mesh < 2 && outside[c.mesh].side_of(c.point, kBallsChecked) == Side::OUTSIDE) continue;
            if (work > defaults::mesh_depth_max_work) {
                out.status = Status::MAX_ITERATIONS;
                break;
            }
            ++out.points_tested;
            if (inside(c)) {
                best = c.distance;
                winner = c;
                winner_triangle = -1;
                have = true;
                break;
            }
            if (c.mesh < 2) outside[c.mesh].add(c.point, c.distance, Side::OUTSIDE);
        }
    }
    if (!have) return out;

    // The deepest point and its closest surface point as (point_a, point_b): a's point inside
    // b, b's point inside a, or a point inside both with the farther surface's closest point
    // (b moves along point_a - point_b to leave it behind).
    out.depth = best;
    Vec3 deep, surface;
    Vec3 deep_local, surface_local;  // the same two points in the frame of `frame`
    const Pose* frame;
    bool deep_is_a;
    // The nearest point of the winner's triangle when the search kept it: closest_point's
    // answer (the same search to the end), without searching again.
    auto nearest = [&](const MeshBvh& mesh) {
        return winner_triangle >= 0 ? closest_point_on_triangle(winner.point, mesh.triangle(winner_triangle))
                                    : closest_point(mesh, winner.point).point;
    };
    deep_local = winner.point;
    if (winner.mesh == 0) {
        frame = &input.pose_b;
        surface_local = nearest(b);
        deep_is_a = true;
    } else if (winner.mesh == 1) {
        frame = &input.pose_a;
        surface_local = nearest(a);
        deep_is_a = false;
    } else {
        frame = &input.pose_a;
        surface_local = winner.farther_is_a ? closest_point(a, winner.point).point
                                            : rel.apply(closest_point(b, rel.apply_inverse(winner.point)).point);
        deep_is_a = !winner.farther_is_a;  // the surface point is on the farther mesh
    }
    deep = frame->apply(deep_local);
    surface = frame->apply(surface_local);
    out.deepest_mesh = deep_is_a ? 0 : 1;
    out.point_a = deep_is_a ? deep : surface;
    out.point_b = deep_is_a ? surface : deep;
    const Vec3 gap = out.point_a - out.point_b;
    const double length = norm(gap);
    if (length > 0.0 && std::isfinite(length)) {
        out.normal = gap / length;
    } else {
        // A depth below the rounding of the pose (a resting contact: 1e-15 deep at coordinates
        // of 1e3) maps both points to the same world point. The direction is still known in the
        // local frame, where the two points differ by the depth: turned into the world frame.
        const Vec3 local_gap = deep_is_a ? deep_local - surface_local : surface_local - deep_local;
        const double local_length = norm(local_gap);
        if (local_length > 0.0) out.normal = frame->rotate(local_gap / local_length);
    }
    return out;
}

}  // namespace meshcol
