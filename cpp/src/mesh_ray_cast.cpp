// The first hit of a ray on a mesh's surface: the ray is clipped to the root box, the
// hierarchy descended nearer box first (Ericson 2004, 5.3.3 for the slab test; boxes grown by
// a relative margin so rounding never drops one), and each leaf triangle decided by the exact
// segment-triangle test of triangle.hpp (orientation signs by Shewchuk's predicates), so that
// a ray through an edge or a vertex shared by two triangles never passes between them.
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// The nearest hit on the segment [p, q] (mesh's local frame) as its parameter s in [0, 1]
// and the triangle (leaf order): the lowest s, then the lowest input face; false for none.
bool nearest_crossing(const MeshBvh& mesh, const Vec3& p, const Vec3& q, double* parameter, std::int32_t* triangle) {
    const Vec3 d = q - p;
    const std::vector<BvhNode>& nodes = mesh.nodes();
    double best = std::numeric_limits<double>::infinity();
    std::int32_t best_triangle = -1;
    std::vector<std::pair<std::int32_t, double>> stack;  // node, parameter where the box starts
    double enter = 0.0, leave = 0.0;
    if (!slab_interval(nodes[0], p, d, 0.0, 1.0, &enter, &leave)) return false;
    stack.push_back({0, enter});
    while (!stack.empty()) {
        const auto [id, start] = stack.back();
        stack.pop_back();
        if (start > best) continue;  // ties stay: a lower face at the same parameter wins
        const BvhNode& node = nodes[static_cast<size_t>(id)];
        if (node.is_leaf()) {
            for (std::int32_t i = node.index; i < node.index + node.count; ++i) {
                double s = 0.0;
                if (!segment_crosses_triangle(p, q, mesh.triangle(i), &s)) continue;
                if (s < best || (s == best && best_triangle >= 0 && mesh.face_index(i) < mesh.face_index(best_triangle))) {
                    best = s;
                    best_triangle = i;
                }
            }
            continue;
        }
        // The nearer child is searched first: pushed last.
        std::pair<std::int32_t, double> children[2];
        int count = 0;
        for (const std::int32_t child : {id + 1, node.index})
            if (slab_interval(nodes[static_cast<size_t>(child)], p, d, 0.0, 1.0, &enter, &leave) && enter <= best)
                children[count++] = {child, enter};
        if (count == 2 && children[0].second < children[1].second) std::swap(children[0], children[1]);
        for (int c = 0; c < count; ++c) stack.push_back(children[c]);
    }
    if (best_triangle < 0) return false;
    *parameter = best;
    *triangle = best_triangle;
    return true;
}

}  // namespace

MeshRayOutput mesh_ray_cast(const MeshRayInput& input) {
    MeshRayOutput out;
    const Vec3 nan3{kNaN, kNaN, kNaN};
    out.point = out.normal = nan3;
    const double length = safe_norm(input.direction);
    if (input.mesh == nullptr || !input.mesh->valid() || !is_finite(input.origin) ||
        !is_finite(input.direction) || !(length > 0.0) || !(input.max_distance >= 0.0)) {
        out.distance = kNaN;
        out.status = Status::INVALID_INPUT;
        return out;
    }
    out.status = Status::CONVERGED;
    out.distance = kInf;
    const MeshBvh& mesh = *input.mesh;
    const Vec3 unit = input.direction / length;
    // The ray in the mesh's frame, clipped to the root box (and to max_distance): a finite
    // segment [p, q] whatever the distances.
    const Vec3 origin = input.pose.apply_inverse(input.origin);
    const Vec3 direction = input.pose.rotate_inverse(unit);
    double enter = 0.0, leave = 0.0;
    if (!slab_interval(mesh.nodes()[0], origin, direction, 0.0, input.max_distance, &enter, &leave)) return out;
    const Vec3 p = origin + direction * enter, q = origin + direction * leave;
    double s = 0.0;
    std::int32_t triangle = -1;
    if (!nearest_crossing(mesh, p, q, &s, &triangle)) return out;
    const double distance = enter + (leave - enter) * s;
    if (!(distance <= input.max_distance)) return out;  // the clipped end rounded past it
    const Vec3* t = mesh.triangle(triangle);
    const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    out.hit = true;
    out.distance = distance;
    out.point = input.origin + unit * distance;
    out.normal = input.pose.rotate(n / safe_norm(n));
    out.triangle = mesh.face_index(triangle);
    return out;
}

}  // namespace meshcol
