// Time of impact (toi.hpp): motions with known first contact, and the other statuses.
#include <cmath>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/toi.hpp"

using namespace meshcol;
using fixtures::at;

namespace {

const double kPi = std::acos(-1.0);

// The contract of HIT: within tolerance of contact at toi, and no earlier than the true time.
void check_hit(const ToiResult& r, double true_time, double tolerance, double speed) {
    REQUIRE(r.status == TimeOfImpactStatus::HIT);
    CHECK(r.toi <= true_time + 1e-12);
    CHECK(r.toi >= true_time - tolerance / speed - 1e-12);  // at most a tolerance short of it
}

}  // namespace

TEST_CASE("toi: two spheres closing head on (closed form)") {
    // unit spheres, b from x = 10 to x = -10: centres 2 apart at x = 2, t = 8 / 20
    const ShapeView s = fixtures::sphere(1.0);
    const Motion still(at(0, 0, 0), at(0, 0, 0));
    const Motion moving(at(10, 0, 0), at(-10, 0, 0));
    ToiOptions options;
    options.tolerance = 1e-6;
    const ToiResult r = time_of_impact(s, still, s, moving, options);
    check_hit(r, 0.4, options.tolerance, 20.0);
    CHECK_NEAR(r.normal.x, 1.0, 1e-9);
    CHECK_NEAR(r.point.x, 1.0, 1e-5);
}

TEST_CASE("toi: a box sliding into a box (ray cast)") {
    // half extents 0.5: faces meet when the centres are 1 apart, b from 5 to -5 hits at t = 0.4
    const ShapeView a = fixtures::box(0.5, 0.5, 0.5), b = fixtures::box(0.5, 0.5, 0.5);
    ToiOptions options;
    options.tolerance = 1e-6;
    const ToiResult r =
        time_of_impact(a, Motion(at(0, 0, 0), at(0, 0, 0)), b, Motion(at(5, 0.2, 0), at(-5, 0.2, 0)), options);
    check_hit(r, 0.4, options.tolerance, 10.0);
    CHECK_NEAR(r.normal.x, 1.0, 1e-9);
}

TEST_CASE("toi: a turning bar sweeps into a box (conservative advancement)") {
    // A bar of half length 2 along x, half width 0.05, turns a quarter turn about z at the
    // origin; the box [-0.5, 0.5] x [1, 2] stands still. The bar's right half sweeps up and its
    // top face (y' = 0.05 in the bar's frame) first meets the box's corner (0.5, 1): in the
    // bar's frame that corner has y' = cos t - 0.5 sin t, so the contact angle solves
    // cos t - 0.5 sin t = 0.05 (the bar's end, at radius 2, passes x = 0.5 far from the box).
    const ShapeView bar = fixtures::box(2.0, 0.05, 0.05), block = fixtures::box(0.5, 0.5, 0.5);
    double lo = 0.0, hi = kPi / 2;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::cos(mid) - 0.5 * std::sin(mid) > 0.05 ? lo : hi) = mid;
    }
    const double contact_time = lo / (kPi / 2);
    ToiOptions options;
    options.tolerance = 1e-6;
    const Motion turning(at(0, 0, 0), fixtures::turned_about_z(kPi / 2, 0, 0, 0));
    const Motion still(at(0, 1.5, 0), at(0, 1.5, 0));
    const ToiResult r = time_of_impact(bar, turning, block, still, options);
    // the gap closes at more than 1 per unit of t there (the corner is 1.1 from the axis)
    check_hit(r, contact_time, options.tolerance, 1.0);
    CHECK_NEAR(r.point.x, 0.5, 1e-4);
    CHECK_NEAR(r.point.y, 1.0, 1e-4);
}

TEST_CASE("toi: separated all along, and overlapping at the start") {
    const ShapeView s = fixtures::sphere(1.0);
    const ToiResult missed =
        time_of_impact(s, Motion(at(0, 0, 0), at(0, 0, 0)), s, Motion(at(10, 3, 0), at(-10, 3, 0)));
    CHECK(missed.status == TimeOfImpactStatus::SEPARATED);
    CHECK(std::isnan(missed.toi));
    const ToiResult overlapped =
        time_of_impact(s, Motion(at(0, 0, 0), at(0, 0, 0)), s, Motion(at(1.5, 0, 0), at(5, 0, 0)));
    CHECK(overlapped.status == TimeOfImpactStatus::OVERLAPPED_AT_START);
    CHECK_EQ(overlapped.toi, 0.0);
}

TEST_CASE("toi: a motion evaluates its screw, shortest rotation included") {
    const Pose end = fixtures::turned_about_z(kPi / 2, 4, 0, 0);
    const Motion m(at(0, 0, 0), end);
    CHECK_NEAR(m.angle, kPi / 2, 1e-15);
    const Pose half = m.at(0.5);
    CHECK_NEAR(half.translation.x, 2.0, 1e-15);
    CHECK_NEAR(half.rotation.m[1][0], std::sin(kPi / 4), 1e-15);
    const Vec3 turn = shortest_rotation(Mat3::identity(), end.rotation);
    CHECK_NEAR(turn.z, kPi / 2, 1e-15);
}
