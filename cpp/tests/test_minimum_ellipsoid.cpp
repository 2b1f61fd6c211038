// The minimum-volume enclosing ellipsoid (fit.hpp: `minimum_ellipsoid`) on answers known in
// closed form: an ellipsoid with its John points, a segment, a point; and its certificate.
#include <cmath>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/fit.hpp"

using namespace meshcol;

namespace {

// |diag(1 / a) R^T (p - c)|: 1 on the ellipsoid's surface.
double level(const EllipsoidSearch& e, const Vec3& p) {
    const Vec3 l = e.rotation.transpose_times(p - e.center);
    double s = 0.0;
    for (int k = 0; k < 3; ++k) s += (l[k] / e.semi_axes[k]) * (l[k] / e.semi_axes[k]);
    return std::sqrt(s);
}

}  // namespace

TEST_CASE("minimum ellipsoid: points on an ellipsoid with its John points give that ellipsoid") {
    const double a[3] = {3.0, 1.0, 0.25};
    const Vec3 center{1.0, -2.0, 0.5};
    fixtures::Uniform u{11};
    std::vector<Vec3> points;
    for (int k = 0; k < 3; ++k)
        for (double sign : {1.0, -1.0}) {  // +-e_i: with weights 1/6 no smaller one holds them
            Vec3 p;
            p[k] = sign * a[k];
            points.push_back(p + center);
        }
    for (int i = 0; i < 200; ++i) {
        Vec3 d{u(), u(), u()};
        d = d / norm(d);
        points.push_back(Vec3{a[0] * d.x, a[1] * d.y, a[2] * d.z} + center);
    }
    const EllipsoidSearch e =
        minimum_ellipsoid(points.data(), static_cast<long long>(points.size()), 3, 1e-6, 100000);
    REQUIRE(e.converged);
    CHECK_EQ(e.dimension, 3);
    CHECK(e.ratio_bound <= 1.0 + 1e-6);
    const double volume = e.semi_axes[0] * e.semi_axes[1] * e.semi_axes[2];
    CHECK(volume >= a[0] * a[1] * a[2] * (1.0 - 1e-12));
    CHECK(volume <= a[0] * a[1] * a[2] * (1.0 + 1e-6));
    for (int k = 0; k < 3; ++k) CHECK_NEAR(e.semi_axes[k], a[k], 3e-3 * a[k]);
    CHECK_NEAR(norm(e.center - center), 0.0, 3e-3);
    double largest = 0.0;
    for (const Vec3& p : points) largest = std::max(largest, level(e, p));
    CHECK(largest <= 1.0 + 1e-12);
}

TEST_CASE("minimum ellipsoid: a segment and a point are exact, a plane's is flat") {
    const std::vector<Vec3> segment = {{0, 0, 0}, {1, 2, 2}, {0.5, 1, 1}, {3, 6, 6}};
    const EllipsoidSearch s = minimum_ellipsoid(segment.data(), 4, 1, 1e-6, 100000);
    CHECK_EQ(s.dimension, 1);
    CHECK_NEAR(s.semi_axes[0], 4.5, 1e-12);
    CHECK_EQ(s.semi_axes[1], 0.0);
    CHECK_NEAR(norm(s.center - Vec3{1.5, 3, 3}), 0.0, 1e-12);
    const std::vector<Vec3> point = {{1, 2, 3}, {1, 2, 3}};
    const EllipsoidSearch p = minimum_ellipsoid(point.data(), 2, 0, 1e-6, 100000);
    CHECK_EQ(p.dimension, 0);
    CHECK_EQ(p.semi_axes[0], 0.0);
    CHECK_EQ(norm(p.center - Vec3{1, 2, 3}), 0.0);
    // a square's corners: the circle through them, radius sqrt(2), no thickness
    const std::vector<Vec3> square = {{1, 1, 5}, {-1, 1, 5}, {-1, -1, 5}, {1, -1, 5}};
    const EllipsoidSearch q = minimum_ellipsoid(square.data(), 4, 2, 1e-6, 100000);
    CHECK_EQ(q.dimension, 2);
    CHECK_NEAR(q.semi_axes[0], std::sqrt(2.0), 1e-6);
    CHECK_NEAR(q.semi_axes[1], std::sqrt(2.0), 1e-6);
    CHECK_EQ(q.semi_axes[2], 0.0);
    CHECK_NEAR(std::fabs(q.rotation.column(2).z), 1.0, 1e-12);
}

TEST_CASE("minimum ellipsoid: the iteration cap leaves a valid certificate and status") {
    fixtures::Uniform u{5};
    std::vector<Vec3> points;
    for (int i = 0; i < 500; ++i) points.push_back({u() * 3.0, u(), u() * 0.1});
    const EllipsoidSearch capped = minimum_ellipsoid(points.data(), 500, 3, 1e-12, 3);
    CHECK(!capped.converged);
    CHECK(capped.iterations <= 3);
    CHECK(capped.ratio_bound >= 1.0);
    double largest = 0.0;
    for (const Vec3& p : points) largest = std::max(largest, level(capped, p));
    CHECK(largest <= 1.0 + 1e-12);  // scaled to hold every point, converged or not
    const EllipsoidSearch full = minimum_ellipsoid(points.data(), 500, 3, 1e-6, 100000);
    CHECK(full.converged);
    CHECK(full.semi_axes[0] * full.semi_axes[1] * full.semi_axes[2] <=
          capped.semi_axes[0] * capped.semi_axes[1] * capped.semi_axes[2]);
}

TEST_CASE("fit: the ellipsoid of a set holds every point, flat and collinear sets included") {
    const FitShape shapes[2] = {FitShape::ELLIPSOID, FitShape::SPHERE};
    fixtures::Uniform u{23};
    std::vector<Vec3> cloud, flat, line;
    for (int i = 0; i < 60; ++i) {
        cloud.push_back({2.0 * u() + 5.0, u(), 0.3 * u()});
        flat.push_back({u(), 2.0 * u(), 1.0});
        line.push_back(Vec3{1, 2, 2} * u());
    }
    for (const auto* set : {&cloud, &flat, &line}) {
        const FitSet s = fit_point_set(set->data(), static_cast<long long>(set->size()), shapes, 2);
        const PrimitiveFit& e = s.fits[0];
        REQUIRE(e.status == FitStatus::OK);
        CHECK(e.volume <= s.fits[1].volume);  // never more than the minimum sphere
        for (const Vec3& p : *set) {
            const Vec3 l = e.rotation.transpose_times(p - e.center);
            double k = 0.0;
            for (int j = 0; j < 3; ++j) k += (l[j] / e.params[j]) * (l[j] / e.params[j]);
            CHECK(k <= 1.0);
        }
    }
    const Vec3 bad[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, std::nan("")}};
    const FitSet s = fit_point_set(bad, 4, shapes, 1);
    CHECK(s.fits[0].status == FitStatus::INVALID_INPUT);
    CHECK(std::isnan(s.fits[0].params[0]));
}
