// The largest distance from points to a mesh's surface (the max of the min, a one-sided
// Hausdorff distance): of a point set (largest_distance) and of the grid nodes of surface
// patches (largest_distance_to_patches, the gap of an enclosing primitive to its mesh).
// Both run closest_point's branch and bound stopped at the largest distance found
// (mesh_detail::distance_beyond, mesh_depth.cpp): a point found within it cannot raise it.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "meshcol/mesh_query.hpp"
#include "mesh_depth.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol {

using mesh_detail::kNaN;
using mesh_detail::kPi;

namespace {

// Adds one point's distance to a running maximum: a point that cannot raise it stops at the
// first triangle within it; one that does ran closest_point's whole search (its bits).
struct RunningMax {
    double best = kNaN;
    std::int64_t point = -1;

    void add(const MeshBvh& mesh, const Vec3& p, std::int64_t k) {
        const double floor = point >= 0 ? best : 0.0;  // 0 stops only a point on the surface
        const double d = mesh_detail::distance_beyond(mesh, p, floor);
        if (point < 0 || d > best) {
            best = d;
            point = k;
        }
    }
};

// A block of a patch's nodes: i in [i0, i1), j in [j0, j1).
struct Block {
    std::int64_t i0, i1, j0, j1;
};

constexpr std::int64_t kLeafNodes = 4;  // fastest of 1, 2, 4, 16, 64 on bench_scale's props

// A query's output before its search: distance NaN, INVALID_INPUT when the mesh is invalid.
LargestDistanceOutput unanswered(const MeshBvh& mesh) {
    LargestDistanceOutput out;
    out.distance = kNaN;
    if (!mesh.valid()) out.status = Status::INVALID_INPUT;
    return out;
}

}  // namespace

LargestDistanceOutput largest_distance(const MeshBvh& mesh, const Vec3* points, std::int64_t count) {
    LargestDistanceOutput out = unanswered(mesh);
    if (out.status == Status::INVALID_INPUT) return out;
    RunningMax max;
    for (std::int64_t k = 0; k < count; ++k)
        if (is_finite(points[k])) max.add(mesh, points[k], k);
    out.distance = max.best;
    out.point = max.point;
    out.status = Status::CONVERGED;
    return out;
}

Vec3 patch_point(const SurfacePatch& patch, std::int64_t i, std::int64_t j) {
    const double* g = patch.g;
    const double fv = static_cast<double>(j) / static_cast<double>(std::max<std::int64_t>(patch.n_v - 1, 1));
    if (patch.map == PatchMap::FLAT) {
        const double fu = static_cast<double>(i) / static_cast<double>(std::max<std::int64_t>(patch.n_u - 1, 1));
        return Vec3{g[0], g[1], g[2]} + Vec3{g[3], g[4], g[5]} * fu + Vec3{g[6], g[7], g[8]} * fv;
    }
    const double v = patch.v0 + (patch.v1 - patch.v0) * fv;
    const double u = static_cast<double>(i) * (2.0 * kPi / static_cast<double>(patch.n_u));
    double radial = v, height = g[3];
    if (patch.map == PatchMap::SPHEROID) {
        radial = std::sin(v);
        height = g[3] + g[2] * std::cos(v);
    } else if (patch.map == PatchMap::SIDE) {
        radial = 1.0;
        height = g[2] * v;
    }
    const Vec3 mapped{g[0] * radial * std::cos(u), g[1] * radial * std::sin(u), height};
    if (patch.map != PatchMap::SPHEROID) return mapped;
    // the map's z is the primitive's axis `polar`, its x the next axis, its y the one after
    const int polar = static_cast<int>(g[5]);
    Vec3 out;
    out[polar] = mapped.z;
    out[(polar + 1) % 3] = mapped.x;
    out[(polar + 2) % 3] = mapped.y;
    return out;
}

LargestDistanceOutput largest_distance_to_patches(const MeshBvh& mesh, const SurfacePatch* patches,
                                                  std::int64_t count) {
    LargestDistanceOutput out = unanswered(mesh);
    if (out.status == Status::INVALID_INPUT) return out;
    RunningMax max;
    std::vector<Block> stack;
    std::int64_t first = 0;  // the patch's first node in the nodes' count
    for (std::int64_t k = 0; k < count; first += patches[k].n_u * patches[k].n_v, ++k) {
        const SurfacePatch& patch = patches[k];
        // how far one node step along u, along v, can move the point
        const double step_u = patch.lu * (patch.map == PatchMap::FLAT
                                              ? 1.0 / static_cast<double>(std::max<std::int64_t>(patch.n_u - 1, 1))
                                              : 2.0 * kPi / static_cast<double>(patch.n_u));
        const double step_v =
            patch.lv * std::fabs(patch.v1 - patch.v0) / static_cast<double>(std::max<std::int64_t>(patch.n_v - 1, 1));
        const auto node = [&](std::int64_t i, std::int64_t j) { return first + i * patch.n_v + j; };
        stack.assign(1, Block{0, patch.n_u, 0, patch.n_v});
        while (!stack.empty()) {
            const Block b = stack.back();
            stack.pop_back();
            if ((b.i1 - b.i0) * (b.j1 - b.j0) <= kLeafNodes) {
                for (std::int64_t i = b.i0; i < b.i1; ++i)
                    for (std::int64_t j = b.j0; j < b.j1; ++j) {
                        const Vec3 p = patch_point(patch, i, j);
                        if (is_finite(p)) max.add(mesh, p, node(i, j));
                    }
                continue;
            }
            const std::int64_t ci = (b.i0 + b.i1 - 1) / 2, cj = (b.j0 + b.j1 - 1) / 2;
            const Vec3 c = patch_point(patch, ci, cj);
            // every node of the block is within `reach` of the centre node (the derivative
            // bounds along u then v), padded far beyond the rounding of points and distances
            double reach = step_u * static_cast<double>(std::max(ci - b.i0, b.i1 - 1 - ci)) +
                           step_v * static_cast<double>(std::max(cj - b.j0, b.j1 - 1 - cj));
            if (max.point >= 0 && is_finite(c)) {
                reach += 1e-9 * (reach + max.best + std::fabs(c.x) + std::fabs(c.y) + std::fabs(c.z));
                const double floor = std::max(max.best - reach, 0.0);
                const double d = mesh_detail::distance_beyond(mesh, c, floor);
                if (d <= floor && d + reach <= max.best) continue;  // no node of it rises above
                if (d > max.best) {  // above the floor: the exact distance
                    max.best = d;
                    max.point = node(ci, cj);
                }
            }
            // halve the block along its longer reach
            const bool along_u =
                b.j1 - b.j0 == 1 ||
                (b.i1 - b.i0 > 1 && step_u * static_cast<double>(b.i1 - b.i0) >= step_v * static_cast<double>(b.j1 - b.j0));
            if (along_u) {
                const std::int64_t mid = (b.i0 + b.i1) / 2;
                stack.push_back(Block{b.i0, mid, b.j0, b.j1});
                stack.push_back(Block{mid, b.i1, b.j0, b.j1});
            } else {
                const std::int64_t mid = (b.j0 + b.j1) / 2;
                stack.push_back(Block{b.i0, b.i1, b.j0, mid});
                stack.push_back(Block{b.i0, b.i1, mid, b.j1});
            }
        }
    }
    out.distance = max.best;
    out.point = max.point;
    out.status = Status::CONVERGED;
    return out;
}

}  // namespace meshcol
