// The largest distance from points to a mesh (mesh_query.hpp: largest_distance and its grid
// form largest_distance_to_patches): the maximum of closest_point's distances, bit for bit,
// however the search is pruned, and a box around a box whose gap is known.
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/mesh_query.hpp"

using namespace meshcol;

namespace {

// The 6 faces of a box of sides `size` centred on the origin, n x n nodes each.
std::vector<SurfacePatch> box_patches(const Vec3& size, std::int64_t n) {
    std::vector<SurfacePatch> out;
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {1.0, -1.0}) {
            SurfacePatch p;
            p.n_u = p.n_v = n;
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            p.g[axis] = sign * size[axis] / 2;
            p.g[u] = -size[u] / 2;
            p.g[v] = -size[v] / 2;
            p.g[3 + u] = size[u];
            p.g[6 + v] = size[v];
            p.lu = size[u];
            p.lv = size[v];
            out.push_back(p);
        }
    return out;
}

double largest_closest(const MeshBvh& mesh, const std::vector<Vec3>& points) {
    double best = -1.0;
    for (const Vec3& p : points) best = std::fmax(best, closest_point(mesh, p).distance);
    return best;
}

}  // namespace

TEST_CASE("largest distance: the maximum of closest_point over the points, bit for bit") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal(0.0, 2.0);
    for (int round = 0; round < 20; ++round) {
        std::vector<Vec3> points(static_cast<size_t>(1 + round * 13));
        for (Vec3& p : points) p = Vec3{normal(rng), normal(rng), normal(rng)};
        const LargestDistanceOutput r = largest_distance(cube, points.data(), static_cast<std::int64_t>(points.size()));
        REQUIRE(r.status == Status::CONVERGED);
        CHECK_EQ(r.distance, largest_closest(cube, points));
        CHECK_EQ(closest_point(cube, points[static_cast<size_t>(r.point)]).distance, r.distance);
    }
    const LargestDistanceOutput none = largest_distance(MeshBvh(), nullptr, 0);
    CHECK(none.status == Status::INVALID_INPUT && std::isnan(none.distance) && none.point == -1);
}

TEST_CASE("largest distance: a box's grid around a cube, by blocks, strays corner to corner") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    for (const std::int64_t n : {1, 2, 7, 40}) {
        const std::vector<SurfacePatch> patches = box_patches({3.0, 2.0, 1.5}, n);
        std::vector<Vec3> nodes;
        for (const SurfacePatch& p : patches)
            for (std::int64_t i = 0; i < p.n_u; ++i)
                for (std::int64_t j = 0; j < p.n_v; ++j) nodes.push_back(patch_point(p, i, j));
        const LargestDistanceOutput r =
            largest_distance_to_patches(cube, patches.data(), static_cast<std::int64_t>(patches.size()));
        REQUIRE(r.status == Status::CONVERGED);
        CHECK_EQ(r.distance, largest_closest(cube, nodes));
        CHECK_EQ(closest_point(cube, nodes[static_cast<size_t>(r.point)]).distance, r.distance);
        if (n >= 2) CHECK_NEAR(r.distance, std::sqrt(1.0 + 0.25 + 0.0625), 1e-12);  // (1.5, 1, 0.75) - 0.5
    }
}
