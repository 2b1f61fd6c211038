// Exact orientation predicates (src/predicates.hpp) and the exact triangle tests built on them
// (triangle.hpp): the degenerate cases a floating-point determinant gets wrong.
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "check.hpp"
#include "meshcol/triangle.hpp"
#include "predicates.hpp"

using namespace meshcol;
using predicates::orient2d_sign;
using predicates::orient3d;
using predicates::orient3d_sign;

TEST_CASE("predicates: orient3d signs of plain tetrahedra") {
    const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    // Shewchuk's convention: positive when d is below the counter-clockwise plane abc
    CHECK_EQ(orient3d_sign(a, b, c, {0, 0, -1}), 1);
    CHECK_EQ(orient3d_sign(a, b, c, {0, 0, 1}), -1);
    CHECK_EQ(orient3d_sign(a, b, c, {0.3, 0.3, 0}), 0);
    CHECK_NEAR(orient3d(a, b, c, {0, 0, -1}), 1.0, 0.0);  // six times the volume 1/6
}

TEST_CASE("predicates: coplanar points off the axes are exactly coplanar") {
    // four points of the plane x + y + z = 1 whose coordinates are not representable sums:
    // a double determinant rounds to a few ulps either side, the exact one is 0
    const Vec3 a{0.1, 0.2, 0.7}, b{0.7, 0.1, 0.2}, c{0.2, 0.7, 0.1};
    const Vec3 d = a * 0.25 + b * 0.25 + c * 0.5;  // rounded: may leave the plane by an ulp
    const int sign = orient3d_sign(a, b, c, d);
    CHECK(sign >= -1 && sign <= 1);
    // exact zero for a point built exactly: the midpoint of two points with dyadic coordinates
    const Vec3 p{0.5, 0.25, 0.0}, q{0.25, 0.5, 0.0}, r{0.0, 0.0, 1.0};
    CHECK_EQ(orient3d_sign(p, q, r, (p + q) * 0.5), 0);
    CHECK_EQ(orient3d_sign(p, q, r, (p + r) * 0.5), 0);
}

TEST_CASE("predicates: a point an ulp off a plane gets its true side") {
    // the plane z = x through (0,0,0), (1,0,1), (0,1,0); points (x, 0, x +- ulp) near x = 1e3
    const Vec3 a{0, 0, 0}, b{1, 0, 1}, c{0, 1, 0};
    const double x = 1000.0;
    const double up = std::nextafter(x, 2 * x), down = std::nextafter(x, 0.0);
    const int above = orient3d_sign(a, b, c, {x, 0, up});
    const int below = orient3d_sign(a, b, c, {x, 0, down});
    CHECK_EQ(above, -below);
    CHECK(above != 0);
    CHECK_EQ(orient3d_sign(a, b, c, {x, 0, x}), 0);
}

TEST_CASE("predicates: orient2d on nearly collinear points (Shewchuk's example)") {
    // points on the line y = x, one nudged by an ulp: the double formula misjudges some, the
    // exact sign never does (antisymmetric under a swap, 0 only when truly collinear)
    const double base = 0.5;
    for (int i = 0; i < 64; ++i) {
        double px = base;
        for (int k = 0; k < i; ++k) px = std::nextafter(px, 1.0);
        const int s = orient2d_sign(px, 0.5, 12.0, 12.0, 24.0, 24.0);
        CHECK_EQ(s, -orient2d_sign(12.0, 12.0, px, 0.5, 24.0, 24.0));
        CHECK_EQ(s == 0, i == 0);
    }
}

TEST_CASE("predicates: denormal coordinates keep exact signs") {
    const double tiny = std::numeric_limits<double>::denorm_min();
    const Vec3 a{0, 0, 0}, b{tiny, 0, 0}, c{0, tiny, 0};
    CHECK_EQ(orient3d_sign(a, b, c, {0, 0, -tiny}), 1);
    CHECK_EQ(orient3d_sign(a, b, c, {0, 0, tiny}), -1);
    CHECK(predicates::collinear(a, b, {2 * tiny, 0, 0}));
    CHECK(!predicates::collinear(a, b, c));
}

TEST_CASE("predicates: triangles touching at a vertex or an edge intersect, exactly") {
    const Vec3 t[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const Vec3 at_vertex[3] = {{1, 0, 0}, {2, 0, 1}, {2, 1, -1}};
    CHECK(triangles_intersect(t, at_vertex, nullptr));
    CHECK(!triangles_cross(t, at_vertex));
    const Vec3 apart[3] = {{1, std::nextafter(0.0, 1.0), 0}, {2, 0, 1}, {2, 1, 1}};
    CHECK(!triangles_intersect(t, apart, nullptr) || triangles_intersect(t, apart, nullptr));
    // coplanar, overlapping with positive area: they cross
    const Vec3 shifted[3] = {{0.25, 0.25, 0}, {1.25, 0.25, 0}, {0.25, 1.25, 0}};
    CHECK(triangles_cross(t, shifted));
    // a degenerate (collinear) triangle crosses nothing
    const Vec3 flat[3] = {{0.1, 0.1, -1}, {0.1, 0.1, 0}, {0.1, 0.1, 1}};
    CHECK(!triangles_cross(t, flat));
    const TriangleDistanceOutput d = triangle_distance(t, at_vertex);
    CHECK(d.intersecting);
    CHECK_EQ(d.distance, 0.0);
}

TEST_CASE("predicates: a segment through a triangle's edge crosses it") {
    const Vec3 t[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    double s = -1.0;
    CHECK(segment_crosses_triangle({0.5, 0, -1}, {0.5, 0, 3}, t, &s));  // through the edge y = 0
    CHECK_NEAR(s, 0.25, 1e-15);
    CHECK(!segment_crosses_triangle({0.6, 0.6, -1}, {0.6, 0.6, 1}, t, nullptr));  // beside it
    CHECK(!segment_crosses_triangle({-1, 0.2, 0}, {2, 0.2, 0}, t, nullptr));  // in its plane
}

namespace {

/// Points near one plane through `origin` (spanned by u and v, rounded to doubles: seldom
/// exactly coplanar), some exactly symmetric about the origin (d and -d: exact zeros), the
/// cases that leave the filter undecided and reach the adaptive stages.
std::vector<Vec3> near_plane_points(std::uint64_t seed, const Vec3& origin, double scale) {
    std::uint64_t state = seed;
    const auto uniform = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1p-53 * 2.0 - 1.0;
    };
    const Vec3 u{0.36, 0.48, 0.8}, v{-0.8, 0.6, 0.0};
    std::vector<Vec3> points;
    for (int k = 0; k < 24; ++k) {
        const Vec3 p = origin + (u * uniform() + v * uniform()) * scale;
        points.push_back(p);
        points.push_back(origin * 2.0 - p);  // its mirror through the origin
    }
    for (int k = 0; k < 8; ++k) points.push_back(origin + Vec3{uniform(), uniform(), uniform()} * (1e-12 * scale));
    return points;
}

}  // namespace

TEST_CASE("predicates: adaptive orient3d and orient2d agree with the allocating exact evaluation") {
    // the allocating evaluation (differences from d, products by fma, grow-expansion sums)
    // is a second route to the exact sign, independent of the stack-held one and the stages
    namespace ref = predicates::detail;
    long long checked = 0, zeros = 0;
    for (const double scale : {1.0, 1e-3, 1e6})
        for (const Vec3 origin : {Vec3{0, 0, 0}, Vec3{0.3, -0.7, 0.1}, Vec3{1e3, 2e3, -5e2}}) {
            const std::vector<Vec3> p = near_plane_points(static_cast<std::uint64_t>(scale * 7 + origin.x), origin, scale);
            const auto n = static_cast<int>(p.size());
            for (int i = 0; i < n; i += 3)
                for (int j = 1; j < n; j += 5)
                    for (int k = 2; k < n; k += 7)
                        for (int l = 0; l < n; l += 2) {
                            const int sign = orient3d_sign(p[i], p[j], p[k], p[l]);
                            const double expected = ref::orient3d_expansions(p[i], p[j], p[k], p[l]);
                            CHECK_EQ(sign, static_cast<int>(expected));
                            const int sign2 = orient2d_sign(p[i].x, p[i].y, p[j].x, p[j].y, p[l].x, p[l].y);
                            CHECK_EQ(sign2, static_cast<int>(ref::orient2d_expansions(p[i].x, p[i].y, p[j].x, p[j].y,
                                                                                p[l].x, p[l].y)));
                            ++checked;
                            zeros += sign == 0;
                        }
        }
    CHECK(checked > 100000);
    CHECK(zeros > 1000);  // the mirrored points give exact zeros: the last stage is reached
}
