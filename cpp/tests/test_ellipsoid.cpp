// Ellipsoids (ShapeKind::ELLIPSOID): the support function, bounds and validity, and the pair
// and time-of-impact queries on answers known in closed form.
#include <cmath>
#include <limits>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/toi.hpp"

using namespace meshcol;
using fixtures::at;

namespace {

const double kPi = std::acos(-1.0);

// sum_i (p_i / a_i)^2: 1 on the surface.
double level(const Vec3& p, const ShapeView& e) {
    const double x = p.x / e.params[0], y = p.y / e.params[1], z = p.z / e.params[2];
    return x * x + y * y + z * z;
}

// A point of the surface at angles (theta, phi).
Vec3 surface_point(const ShapeView& e, double theta, double phi) {
    return {e.params[0] * std::sin(theta) * std::cos(phi), e.params[1] * std::sin(theta) * std::sin(phi),
            e.params[2] * std::cos(theta)};
}

// A rotation about the axis (x, y, z) (need not be unit) by `angle`, placed at `t`.
Pose turned(double x, double y, double z, double angle, const Vec3& t) {
    const double n = std::sqrt(x * x + y * y + z * z);
    x /= n, y /= n, z /= n;
    const double c = std::cos(angle), s = std::sin(angle), k = 1.0 - c;
    Pose p = at(t.x, t.y, t.z);
    const double r[3][3] = {{c + x * x * k, x * y * k - z * s, x * z * k + y * s},
                            {y * x * k + z * s, c + y * y * k, y * z * k - x * s},
                            {z * x * k - y * s, z * y * k + x * s, c + z * z * k}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) p.rotation.m[i][j] = r[i][j];
    return p;
}

}  // namespace

TEST_CASE("ellipsoid: the support lies on the surface and beats every sampled point") {
    const ShapeView e = fixtures::ellipsoid(0.5, 2.0, 1.25);
    fixtures::Uniform u{37};
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 d{u(), u(), u()};
        const SupportPoint s = support_core(e, d);
        CHECK_EQ(s.index, -1);
        CHECK_NEAR(level(s.point, e), 1.0, 1e-14);
        const double best = dot(s.point, d);
        bool beaten = false;
        for (int i = 0; i <= 40; ++i)
            for (int j = 0; j < 80; ++j)
                beaten = beaten || dot(surface_point(e, kPi * i / 40, 2 * kPi * j / 80), d) >
                                       best + 1e-14;
        CHECK(!beaten);
        CHECK(dot(support(e, d), d) == best);  // no margin
    }
}

TEST_CASE("ellipsoid: the support of a zero, huge or tiny direction") {
    const ShapeView e = fixtures::ellipsoid(3.0, 1.0, 2.0);
    const Vec3 zero = support_core(e, Vec3{}).point;
    CHECK(zero.x == 0.0 && zero.y == 0.0 && zero.z == 0.0);
    const Vec3 d{0.3, -0.7, 0.2};
    const Vec3 unit = support_core(e, d).point;
    for (double scale : {1e-300, 1e-200, 1e-160, 1e160, 1e200, 1e300}) {
        const Vec3 p = support_core(e, d * scale).point;
        CHECK_NEAR(p.x, unit.x, 1e-15);
        CHECK_NEAR(p.y, unit.y, 1e-15);
        CHECK_NEAR(p.z, unit.z, 1e-15);
    }
    // huge and tiny semi-axes: finite, on the surface
    for (double size : {1e-300, 1e-150, 1e150, 1e300}) {
        const ShapeView big = fixtures::ellipsoid(size, 0.5 * size, 2.0 * size);
        for (double scale : {1e-300, 1.0, 1e300}) {
            const Vec3 p = support_core(big, d * scale).point;
            REQUIRE(is_finite(p));
            CHECK_NEAR(level(p, big), 1.0, 1e-14);
        }
    }
    const Vec3 nan = support_core(e, Vec3{std::nan(""), 0.0, 0.0}).point;
    CHECK(is_finite(nan));
}

TEST_CASE("ellipsoid: a zero semi-axis is a flat ellipse, all zero a point") {
    const ShapeView flat = fixtures::ellipsoid(2.0, 1.0, 0.0);
    CHECK(is_valid(flat));
    const Vec3 up = support_core(flat, Vec3{0.0, 0.0, 1.0}).point;  // every point is a support
    CHECK(up.x == 0.0 && up.y == 0.0 && up.z == 0.0);
    const Vec3 side = support_core(flat, Vec3{1.0, 1.0, 1.0}).point;
    CHECK_EQ(side.z, 0.0);
    CHECK_NEAR(side.x * side.x / 4.0 + side.y * side.y, 1.0, 1e-15);
    // a sphere 0.5 above the disc's centre: 0.25 away; beside its rim along x: known too
    const ShapeView ball = fixtures::sphere(0.25);
    const PairResult above = query_pair(flat, at(0, 0, 0), ball, at(0.3, 0.2, 0.5), QueryKind::DISTANCE);
    REQUIRE(above.status == Status::CONVERGED);
    CHECK_NEAR(above.distance, 0.25, 1e-12);
    const PairResult rim = query_pair(flat, at(0, 0, 0), ball, at(3.0, 0, 0), QueryKind::DISTANCE);
    CHECK_NEAR(rim.distance, 0.75, 1e-12);
    const ShapeView point = fixtures::ellipsoid(0.0, 0.0, 0.0);
    CHECK(is_valid(point));
    CHECK_EQ(bounding_radius(point), 0.0);
    const PairResult p = query_pair(point, at(0, 0, 0), ball, at(0, 3, 4), QueryKind::DISTANCE);
    CHECK_NEAR(p.distance, 4.75, 1e-12);
}

TEST_CASE("ellipsoid: bounds, radius and validity") {
    const ShapeView e = fixtures::ellipsoid(0.5, 2.0, 1.25);
    Vec3 lo, hi;
    local_aabb(e, lo, hi);
    CHECK(hi.x == 0.5 && hi.y == 2.0 && hi.z == 1.25 && lo.x == -0.5 && lo.y == -2.0 && lo.z == -1.25);
    CHECK_EQ(bounding_radius(e), 2.0);
    CHECK_EQ(valid_bounding_radius(e), 2.0);
    fixtures::Uniform u{5};
    for (int trial = 0; trial < 50; ++trial) {
        const Pose pose = turned(u(), u(), u(), 3.0 * u(), Vec3{u(), u(), u()});
        world_aabb(e, pose, lo, hi);
        for (int k = 0; k < 3; ++k) {
            // exact: the world support along +-e_k reaches the box's faces
            Vec3 axis{};
            axis[k] = 1.0;
            const Vec3 local = pose.rotation.row(k);
            const double far = pose.apply(support(e, local))[k], near = pose.apply(support(e, -local))[k];
            CHECK_NEAR(hi[k], far, 1e-14);
            CHECK_NEAR(lo[k], near, 1e-14);
        }
        // and holds every surface point
        bool inside = true;
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; j < 40; ++j) {
                const Vec3 p = pose.apply(surface_point(e, kPi * i / 20, 2 * kPi * j / 40));
                for (int k = 0; k < 3; ++k) inside = inside && p[k] <= hi[k] + 1e-15 && p[k] >= lo[k] - 1e-15;
            }
        CHECK(inside);
    }
    CHECK(!is_valid(fixtures::ellipsoid(1.0, -1.0, 1.0)));
    CHECK(!is_valid(fixtures::ellipsoid(1.0, 1.0, std::numeric_limits<double>::infinity())));
    CHECK(!is_valid(fixtures::ellipsoid(std::nan(""), 1.0, 1.0)));
    CHECK(std::isnan(valid_bounding_radius(fixtures::ellipsoid(1.0, -1.0, 1.0))));
}

TEST_CASE("ellipsoid: distance to a box face and to a sphere, in closed form") {
    // turned by phi about z, the ellipsoid reaches sqrt((a cos)^2 + (b sin)^2) along x
    const double a = 0.5, b = 2.0, c = 1.25;
    const ShapeView e = fixtures::ellipsoid(a, b, c), box = fixtures::box(1.0, 5.0, 5.0);
    for (double phi : {0.0, 0.3, 1.0, kPi / 2}) {
        const double reach = std::hypot(a * std::cos(phi), b * std::sin(phi));
        const PairResult r = query_pair(e, fixtures::turned_about_z(phi, 0, 0, 0), box,
                                        at(4.0, 0.1, -0.2), QueryKind::DISTANCE);
        REQUIRE(r.status == Status::CONVERGED);
        CHECK_NEAR(r.distance, 3.0 - reach, 1e-12);
        CHECK_NEAR(r.normal.x, 1.0, 1e-7);
        // sunk into the face by 0.1: the depth is that, along the face normal
        const PairResult deep = query_pair(e, fixtures::turned_about_z(phi, 0, 0, 0), box,
                                           at(1.0 + reach - 0.1, 0.1, -0.2), QueryKind::PENETRATION);
        REQUIRE(deep.status == Status::CONVERGED);
        CHECK_NEAR(deep.depth, 0.1, 1e-7);
        CHECK_NEAR(deep.normal.x, 1.0, 1e-6);
    }
    // a sphere-shaped ellipsoid answers as the sphere does
    const ShapeView round = fixtures::ellipsoid(0.75, 0.75, 0.75), ball = fixtures::sphere(0.75);
    const ShapeView other = fixtures::sphere(0.5);
    fixtures::Uniform u{11};
    for (int trial = 0; trial < 50; ++trial) {
        const Pose pb = at(2.0 * u(), 2.0 * u(), 2.0 * u());
        const Pose pa = turned(u(), u(), u(), 3.0 * u(), Vec3{0.1 * u(), 0.1 * u(), 0.1 * u()});
        const PairResult e1 = query_pair(round, pa, other, pb, QueryKind::PENETRATION);
        const PairResult s1 = query_pair(ball, pa, other, pb, QueryKind::PENETRATION);
        REQUIRE(e1.status == Status::CONVERGED);
        CHECK_NEAR(e1.distance, s1.distance, 1e-12);
        CHECK_NEAR(e1.depth, s1.depth, 1e-7 * 1.25);
    }
}

TEST_CASE("toi: an ellipsoid sliding into a box face (closed form)") {
    // semi-axis 0.5 along x: the ellipsoid from x = 5 to x = -5 meets the face x = 1 when its
    // centre is at 1.5, t = 0.35
    const ShapeView e = fixtures::ellipsoid(0.5, 2.0, 1.25), box = fixtures::box(1.0, 5.0, 5.0);
    ToiOptions options;
    options.tolerance = 1e-6;
    const ToiResult r = time_of_impact(box, Motion(at(0, 0, 0), at(0, 0, 0)), e,
                                       Motion(at(5, 0.3, 0.1), at(-5, 0.3, 0.1)), options);
    REQUIRE(r.status == TimeOfImpactStatus::HIT);
    CHECK(r.toi <= 0.35 + 1e-12);
    CHECK(r.toi >= 0.35 - options.tolerance / 10.0 - 1e-12);
    // turning about its centre a quarter turn while it slides: its reach along x grows from
    // 0.5 to 2 (sqrt((a cos)^2 + (b sin)^2) at angle pi t / 2), and contact comes when
    // 4 - 10 t equals it (bisected here: t is about 0.3)
    const ToiResult turning = time_of_impact(box, Motion(at(0, 0, 0), at(0, 0, 0)), e,
                                             Motion(at(5, 0, 0), fixtures::turned_about_z(kPi / 2, -5, 0, 0)),
                                             options);
    double lo = 0.0, hi = 0.35;
    for (int step = 0; step < 200; ++step) {
        const double t = 0.5 * (lo + hi), angle = kPi / 2 * t;
        (4.0 - 10.0 * t > std::hypot(0.5 * std::cos(angle), 2.0 * std::sin(angle)) ? lo : hi) = t;
    }
    REQUIRE(turning.status == TimeOfImpactStatus::HIT);
    CHECK(turning.toi <= lo + 1e-12);
    CHECK(turning.toi >= lo - options.tolerance / 10.0 - 1e-12);
}
