// Half-spaces (ShapeKind::HALFSPACE, an MJCF plane): bounds, validity, and the pair query on
// answers known in closed form, with the half-space on either side of the pair.
#include <cmath>
#include <limits>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/shapes.hpp"

using namespace meshcol;
using fixtures::at;
using fixtures::turned_about_x;

namespace {

ShapeView half_space() {
    ShapeView s;
    s.kind = ShapeKind::HALFSPACE;
    return s;
}

}  // namespace

TEST_CASE("half-space: valid, unbounded, its box bounded only along an axis normal") {
    const ShapeView h = half_space();
    CHECK(is_valid(h));
    CHECK(std::isinf(bounding_radius(h)));
    Vec3 lo, hi;
    world_aabb(h, at(1.0, 2.0, 0.25), lo, hi);
    CHECK_EQ(hi.z, 0.25);
    CHECK(std::isinf(lo.x) && std::isinf(hi.x) && std::isinf(lo.y) && std::isinf(hi.y));
    CHECK(std::isinf(lo.z) && lo.z < 0.0);
    world_aabb(h, turned_about_x(0.3, 0, 0, 0), lo, hi);
    CHECK(std::isinf(hi.z) && std::isinf(hi.y) && std::isinf(lo.z));
    CHECK(std::isnan(support_core(h, Vec3{0, 0, 1}).point.x));
}

TEST_CASE("half-space: a sphere above, touching and below a floor") {
    const ShapeView h = half_space(), ball = fixtures::sphere(0.5);
    for (double z : {2.0, 0.5, 0.2, -3.0}) {
        const PairResult r = query_pair(h, at(0, 0, 0), ball, at(0.3, -0.7, z), QueryKind::PENETRATION);
        CHECK(r.status == Status::CONVERGED);
        CHECK_NEAR(r.distance - r.depth, z - 0.5, 1e-15);
        CHECK_NEAR(r.point_b.z, z - 0.5, 1e-15);
        CHECK_NEAR(r.point_a.z, 0.0, 1e-15);
        CHECK_NEAR(r.point_a.x, 0.3, 1e-15);
        CHECK_NEAR(r.normal.z, 1.0, 0.0);
        CHECK_EQ(r.intersects, z <= 0.5);
    }
}

TEST_CASE("half-space: a turned box against a tilted plane, either order") {
    const double angle = 0.4;
    const Pose plane = turned_about_x(angle, 0.0, 1.0, -0.5);
    const Vec3 n{0.0, -std::sin(angle), std::cos(angle)};
    const ShapeView box = fixtures::box(0.5, 0.25, 1.0);
    const Pose pose = fixtures::turned_about_z(0.7, 0.2, 0.3, 0.4);
    // the lowest corner along n, by brute force over the eight corners
    double lowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 8; ++i) {
        const Vec3 corner{(i & 1 ? 0.5 : -0.5), (i & 2 ? 0.25 : -0.25), (i & 4 ? 1.0 : -1.0)};
        lowest = std::fmin(lowest, dot(n, pose.apply(corner) - plane.translation));
    }
    const PairResult r = query_pair(half_space(), plane, box, pose, QueryKind::PENETRATION);
    CHECK_NEAR(r.distance - r.depth, lowest, 1e-14);
    CHECK_NEAR(dot(n, r.point_b - plane.translation), lowest, 1e-14);
    CHECK_NEAR(dot(n, r.point_a - plane.translation), 0.0, 1e-14);
    const PairResult s = query_pair(box, pose, half_space(), plane, QueryKind::PENETRATION);
    CHECK_NEAR(s.distance - s.depth, lowest, 1e-14);
    CHECK_NEAR(s.normal.y, -n.y, 1e-15);
    CHECK_NEAR(s.point_a.x, r.point_b.x, 0.0);
    CHECK_NEAR(s.point_b.x, r.point_a.x, 0.0);
}

TEST_CASE("half-space: two half-spaces are degenerate, never measured") {
    const PairResult r = query_pair(half_space(), at(0, 0, 0), half_space(), at(0, 0, 1),
                                    QueryKind::PENETRATION);
    CHECK(r.status == Status::DEGENERATE);
    CHECK(std::isnan(r.distance));
}
