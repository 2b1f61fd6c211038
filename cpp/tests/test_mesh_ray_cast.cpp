// Ray casts on meshes (mesh_query.hpp: mesh_ray_cast): known hits on boxes, shared edges and
// vertices, misses, the distance cap and invalid rays.
#include <cmath>
#include <limits>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/mesh_query.hpp"

using namespace meshcol;
using fixtures::at;

namespace {

MeshRayInput ray(const MeshBvh& mesh, const Pose& pose, const Vec3& origin, const Vec3& direction) {
    MeshRayInput in;
    in.mesh = &mesh;
    in.pose = pose;
    in.origin = origin;
    in.direction = direction;
    return in;
}

}  // namespace

TEST_CASE("ray cast: straight down onto a box's top face") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    const MeshRayOutput r = mesh_ray_cast(ray(cube, at(0, 0, 0), {0.1, 0.2, 3.0}, {0, 0, -2}));
    REQUIRE(r.status == Status::CONVERGED);
    REQUIRE(r.hit);
    CHECK_NEAR(r.distance, 2.5, 1e-15);
    CHECK_NEAR(r.point.z, 0.5, 1e-15);
    CHECK_NEAR(r.point.x, 0.1, 1e-15);
    CHECK_NEAR(r.normal.z, 1.0, 1e-15);  // outward
    CHECK(r.triangle == 2 || r.triangle == 3);  // the z = hi face
}

TEST_CASE("ray cast: a posed box, and a ray from inside sees the far face") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    const Pose pose = fixtures::turned_about_z(std::acos(-1.0) / 4, 10, 0, 0);
    // along -x towards the turned box: its vertical edge is sqrt(1/2) from its centre
    const MeshRayOutput r = mesh_ray_cast(ray(cube, pose, {20, 0, 0.1}, {-1, 0, 0}));
    REQUIRE(r.hit);
    CHECK_NEAR(r.distance, 10 - std::sqrt(0.5), 1e-12);
    const MeshRayOutput inside = mesh_ray_cast(ray(cube, at(0, 0, 0), {0, 0, 0}, {1, 0, 0}));
    REQUIRE(inside.hit);
    CHECK_NEAR(inside.distance, 0.5, 1e-15);
    CHECK_NEAR(inside.normal.x, 1.0, 1e-15);  // the face's own side: along the ray
}

TEST_CASE("ray cast: through a shared edge and a shared vertex it still hits") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    // the top face is split along a diagonal: a ray down that diagonal's line
    const MeshRayOutput edge = mesh_ray_cast(ray(cube, at(0, 0, 0), {0.25, 0.25, 2}, {0, 0, -1}));
    const MeshRayOutput other_diagonal = mesh_ray_cast(ray(cube, at(0, 0, 0), {0.25, -0.25, 2}, {0, 0, -1}));
    CHECK(edge.hit && other_diagonal.hit);
    CHECK_NEAR(edge.distance, 1.5, 1e-15);
    CHECK_NEAR(other_diagonal.distance, 1.5, 1e-15);
    // straight at a corner, along the diagonal
    const MeshRayOutput corner = mesh_ray_cast(ray(cube, at(0, 0, 0), {2.5, 2.5, 2.5}, {-1, -1, -1}));
    REQUIRE(corner.hit);
    CHECK_NEAR(corner.distance, std::sqrt(3.0) * 2.0, 1e-12);
}

TEST_CASE("ray cast: misses, the distance cap, the origin on the surface") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    const MeshRayOutput away = mesh_ray_cast(ray(cube, at(0, 0, 0), {0, 0, 3}, {0, 0, 1}));
    CHECK(!away.hit);
    CHECK(std::isinf(away.distance));
    CHECK(away.triangle == -1);
    CHECK(away.status == Status::CONVERGED);
    const MeshRayOutput beside = mesh_ray_cast(ray(cube, at(0, 0, 0), {0.6, 0, 3}, {0, 0, -1}));
    CHECK(!beside.hit);
    MeshRayInput short_ray = ray(cube, at(0, 0, 0), {0, 0, 3}, {0, 0, -1});
    short_ray.max_distance = 2.4;
    CHECK(!mesh_ray_cast(short_ray).hit);
    short_ray.max_distance = 2.5;  // exactly reaching the face counts
    CHECK(mesh_ray_cast(short_ray).hit);
    const MeshRayOutput from_surface = mesh_ray_cast(ray(cube, at(0, 0, 0), {0, 0, 0.5}, {0, 0, 1}));
    CHECK(from_surface.hit);
    CHECK_EQ(from_surface.distance, 0.0);
}

TEST_CASE("ray cast: invalid rays say so") {
    const MeshBvh cube = fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}).bvh();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK(mesh_ray_cast(ray(cube, at(0, 0, 0), {0, 0, 3}, {0, 0, 0})).status == Status::INVALID_INPUT);
    CHECK(mesh_ray_cast(ray(cube, at(0, 0, 0), {nan, 0, 3}, {0, 0, 1})).status == Status::INVALID_INPUT);
    MeshRayInput negative = ray(cube, at(0, 0, 0), {0, 0, 3}, {0, 0, -1});
    negative.max_distance = -1.0;
    const MeshRayOutput r = mesh_ray_cast(negative);
    CHECK(r.status == Status::INVALID_INPUT);
    CHECK(std::isnan(r.distance));
}
