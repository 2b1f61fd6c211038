// Inside or outside a mesh: the generalized winding number (Jacobson et al. 2013), its fast
// form with a guaranteed error (Barill et al. 2018), and for closed meshes the exact signed
// ray-crossing count.
#include <algorithm>
#include <cmath>
#include <vector>

#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"
#include "predicates.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// Signed solid angle of triangle t seen from `point` (van Oosterom and Strackee 1983:
// tan(omega / 2) = det / denominator); positive when the point is behind the triangle's
// counter-clockwise normal.
inline double triangle_solid_angle(const Vec3 t[3], const Vec3& point) {
    const Vec3 a = t[0] - point, b = t[1] - point, c = t[2] - point;
    const double la = norm(a), lb = norm(b), lc = norm(c);
    const double det = dot(a, cross(b, c));
    const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    return 2.0 * std::atan2(det, denominator);
}

// Signed number of crossings of the segment [p, q] with a closed mesh's triangles (the winding
// number of p when q is outside), with exact orientation signs, or 1 when p lies on the
// surface; false when the segment passes exactly through an edge or a vertex, so another
// direction must be tried.
bool signed_crossings(const MeshBvh& mesh, const Vec3& p, const Vec3& q, int* count) {
    using predicates::orient3d_sign;
    const Vec3 d = q - p;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    // The thread's stack, kept between calls: a depth query runs dozens of these tests, and
    // a fresh vector grew by reallocation in each.
    thread_local std::vector<std::int32_t> stack;
    stack.assign(1, 0);
    int total = 0;
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        if (!segment_may_meet_box(node, p, d)) continue;
        if (!node.is_leaf()) {
            stack.push_back(node.index);
            stack.push_back(id + 1);
            continue;
        }
        for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
            const Vec3* t = mesh.triangle(i);
            const int sp = orient3d_sign(t[0], t[1], t[2], p);
            const int sq = orient3d_sign(t[0], t[1], t[2], q);
            if (sp == 0) {
                // p on the surface belongs to the closed solid (a point of the other mesh's
                // surface lying on this one still bounds the depth); elsewhere on the plane
                // the segment only touches it at p.
                const Vec3 point[3] = {p, p, p};
                if (triangles_intersect(t, point, nullptr)) {
                    *count = 1;
                    return true;
                }
                continue;
            }
            // One side, or touching the plane only at q (outside the mesh's box): no crossing.
            if (sp * sq >= 0) continue;
            const int s0 = orient3d_sign(p, q, t[0], t[1]);
            const int s1 = orient3d_sign(p, q, t[1], t[2]);
            const int s2 = orient3d_sign(p, q, t[2], t[0]);
            if ((s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0)) {
                total += sp;
                continue;
            }
            if ((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0)) continue;  // misses
            if (s0 == 0 && s1 == 0 && s2 == 0) continue;  // degenerate triangle
            return false;  // through an edge or a vertex
        }
    }
    *count = total;
    return true;
}

// The order-2 far-field expansion of node `w` seen from `point`, and the bound of its
// remainder, both over 4 pi (winding-number units); false when the point is too near
// (distance to the centre at most twice the radius) or the figures are not finite.
// With v = center - point, rho = |v|: the solid angle of the node's triangles is the
// integral of (x - point) . n / |x - point|^3 over them; its Taylor expansion about the centre
// gives v . N / rho^3 (dipole) + (tr M - 3 v^T M v / rho^2) / rho^3 (first moment M), and the
// remainder is at most (1/2) (6 / (rho - radius)^4) radius^2 area.
inline bool far_field(const WindingNode& w, const Vec3& point, double* value, double* error) {
    const Vec3 v = w.center - point;
    const double rho2 = dot(v, v);
    if (!(rho2 > 4.0 * w.radius * w.radius)) return false;
    const double rho = std::sqrt(rho2);
    const double inv3 = 1.0 / (rho2 * rho);
    const double* m = w.moment;
    const double trace = m[0] + m[1] + m[2];
    const double vmv = v.x * v.x * m[0] + v.y * v.y * m[1] + v.z * v.z * m[2] +
                       2.0 * (v.x * v.y * m[3] + v.y * v.z * m[4] + v.z * v.x * m[5]);
    const double gap = rho - w.radius;
    const double gap2 = gap * gap;
    *value = (dot(v, w.dipole) + trace - 3.0 * vmv / rho2) * inv3 / (4.0 * kPi);
    *error = 3.0 * w.radius * w.radius * w.area / (gap2 * gap2) / (4.0 * kPi) * (1.0 + 1e-9);
    return std::isfinite(*value) && std::isfinite(*error);
}

struct OpenNode {
    double error;
    double value;
    std::int32_t node;
    bool operator<(const OpenNode& o) const { return error < o.error; }
};

// The refinement behind fast_winding_number and winding_number_inside: far nodes in a max-heap
// by their bound, opened until `enough(value, error)`.
template <class Enough>
WindingEstimate refine_winding_number(const MeshBvh& mesh, const Vec3& point, Enough enough) {
    WindingEstimate out;
    if (!is_finite(point) || !mesh.valid()) {
        out.value = out.error = kNaN;
        return out;
    }
    const std::vector<BvhNode>& nodes = mesh.nodes();
    const std::vector<WindingNode>& far = mesh.winding_nodes();
    std::vector<OpenNode> heap;
    std::vector<std::int32_t> near;
    double exact = 0.0;  // solid angles summed exactly, steradians
    double approx = 0.0, error = 0.0;  // far-field sums, winding-number units
    // Adds node `id`: far, into the heap; near, its children (or its triangles, for a leaf).
    auto open = [&](std::int32_t id) {
        near.push_back(id);
        while (!near.empty()) {
            const std::int32_t k = near.back();
            near.pop_back();
            double value, bound;
            if (far_field(far[static_cast<size_t>(k)], point, &value, &bound)) {
                ++out.visits;
                approx += value;
                error += bound;
                heap.push_back({bound, value, k});
                std::push_heap(heap.begin(), heap.end());
                continue;
            }
            const BvhNode& node = nodes[static_cast<size_t>(k)];
            if (node.is_leaf()) {
                for (std::int32_t i = node.index; i < node.index + node.count; ++i)
                    exact += triangle_solid_angle(mesh.triangle(i), point);
                out.visits += node.count;
                continue;
            }
            near.push_back(node.index);
            near.push_back(k + 1);
        }
    };
    open(0);
    while (!heap.empty() && !enough(exact / (4.0 * kPi) + approx, error)) {
        std::pop_heap(heap.begin(), heap.end());
        const OpenNode top = heap.back();
        heap.pop_back();
        approx -= top.value;
        error -= top.error;
        const BvhNode& node = nodes[static_cast<size_t>(top.node)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i)
                exact += triangle_solid_angle(mesh.triangle(i), point);
            out.visits += node.count;
        } else {
            open(top.node + 1);
            open(node.index);
        }
    }
    if (heap.empty()) {
        // Every triangle summed: drop the residue the subtractions left.
        approx = 0.0;
        error = 0.0;
    }
    out.value = exact / (4.0 * kPi) + approx;
    // The running total of the bounds lost digits to the subtractions: recount it.
    if (!heap.empty()) {
        error = 0.0;
        for (const OpenNode& o : heap) error += o.error;
    }
    out.error = error;
    return out;
}

// Whether `p` (mesh's local frame) lies exactly on the surface: the exact test of
// triangles_intersect against the triangles of the boxes holding p (rounded outwards, so the
// box of a triangle holding p holds p).
bool on_surface(const MeshBvh& mesh, const Vec3& p) {
    const std::vector<BvhNode>& nodes = mesh.nodes();
    const Vec3 point[3] = {p, p, p};
    thread_local std::vector<std::int32_t> stack;  // kept between calls, as signed_crossings'
    stack.assign(1, 0);
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        if (!inside_box(node, p)) continue;
        if (!node.is_leaf()) {
            stack.push_back(node.index);
            stack.push_back(id + 1);
            continue;
        }
        for (std::int32_t i = node.index; i < node.index + node.count; ++i)
            if (triangles_intersect(mesh.triangle(i), point, nullptr)) return true;
    }
    return false;
}

}  // namespace

namespace mesh_detail {

// Whether `p` (mesh's local frame) is in the solid: |winding number| >= 1/2. For a closed
// mesh the winding number is the signed crossing count of a segment from p to beyond the
// mesh's box (BVH, exact signs, a few fixed directions in case one passes through an edge or
// a vertex), and a point exactly on the surface counts as in; otherwise, and if every
// direction is degenerate, the generalized winding number, with a point exactly on the
// surface counted in first as for a closed mesh (the sum is 1/2 on a smooth part of the
// surface, but the solid angles of two coplanar triangles seen from a point of their shared
// edge cancel to 0, so the two tests disagreed there and the depth of one pair depended on
// whether the other mesh was closed).
bool inside_mesh(const MeshBvh& mesh, const Vec3& p, long long* work) {
    if (mesh.closed()) {
        static constexpr Vec3 kDirections[] = {
            {0.5377304471659, 0.2845902536245, 0.7935981048671},
            {-0.6117145263523, 0.7219873914523, 0.3232414553322},
            {0.2174811052316, -0.8642151133311, 0.4536126398734},
            {-0.3902134117283, -0.4155247717421, -0.8216328740022},
            {0.8807432016934, -0.1179016743124, -0.4587332154410},
            {-0.0712387411032, 0.5932171148713, -0.8018427201121},
        };
        const BvhNode& root = mesh.nodes()[0];
        const Vec3 lo{root.lower[0], root.lower[1], root.lower[2]};
        const Vec3 hi{root.upper[0], root.upper[1], root.upper[2]};
        const double reach = 2.0 * (norm(hi - lo) + norm(p - (lo + hi) * 0.5)) + 1.0;
        // The direction that leaves the box soonest first (fewer nodes and triangles on its
        // way), then the others in order. The count is the winding number whichever
        // direction decides (an integer off a closed, consistently wound surface, constant
        // between its sheets), and a point on the surface is in whichever finds it.
        constexpr int kCount = sizeof(kDirections) / sizeof(kDirections[0]);
        int first = 0;
        double soonest = kInf;
        for (int i = 0; i < kCount; ++i) {
            double leave = kInf;
            for (int k = 0; k < 3; ++k) {
                const double d = kDirections[i][k];
                leave = min2(leave, ((d > 0.0 ? hi[k] : lo[k]) - p[k]) / d);
            }
            if (leave < soonest) {
                soonest = leave;
                first = i;
            }
        }
        for (int n = 0; n < kCount; ++n) {
            const Vec3& direction = kDirections[n == 0 ? first : (n <= first ? n - 1 : n)];
            int count = 0;
            *work += 64;  // about the cost of one segment query, in triangle visits
            if (signed_crossings(mesh, p, p + direction * reach, &count)) return count != 0;
        }
    }
    if (on_surface(mesh, p)) return true;
    return winding_number_inside(mesh, p, work);
}

}  // namespace mesh_detail

double winding_number(const MeshBvh& mesh, const Vec3& point) {
    double total = 0.0;
    const std::int32_t n = mesh.triangle_count();
    for (std::int32_t i = 0; i < n; ++i) total += triangle_solid_angle(mesh.triangle(i), point);
    return total / (4.0 * kPi);
}

WindingEstimate fast_winding_number(const MeshBvh& mesh, const Vec3& point, double max_error) {
    return refine_winding_number(mesh, point, [max_error](double, double error) { return error <= max_error; });
}

bool winding_number_inside(const MeshBvh& mesh, const Vec3& point, long long* work) {
    constexpr double threshold = defaults::winding_number_inside;
    // Decided once the interval [value - error, value + error] of the winding number clears
    // both thresholds +-0.5 by more than the rounding of the sums (1e-9, far above the
    // 1e-16 * F of a mesh's exact sum).
    const WindingEstimate w = refine_winding_number(mesh, point, [](double value, double error) {
        const double margin = std::fabs(std::fabs(value) - threshold);
        return margin > error + 1e-9;
    });
    if (work != nullptr) *work += w.visits;
    return std::fabs(w.value) >= threshold;
}

}  // namespace meshcol
