// The in-sphere (inscribed_ball.hpp): known balls of boxes and a regular tetrahedron, the
// statuses of unbounded, empty and non-finite polytopes, and the batch against singles.
#include <cmath>
#include <cstdint>
#include <vector>

#include "check.hpp"
#include "meshcol/inscribed_ball.hpp"

using namespace meshcol;

namespace {

// The six planes of the box [lo, hi] (unit normals, n . x + d <= 0 inside).
std::vector<double> box_planes(const Vec3& lo, const Vec3& hi) {
    return {1, 0, 0, -hi.x, -1, 0, 0, lo.x, 0, 1, 0, -hi.y,
            0, -1, 0, lo.y, 0, 0, 1, -hi.z, 0, 0, -1, lo.z};
}

}  // namespace

TEST_CASE("inscribed ball: a cube's ball is its centre and half its side") {
    // six planes touch the ball, which cannot slide: the one centre
    const auto planes = box_planes({-1, -1, -1}, {1, 1, 1});
    const InscribedBall b = inscribed_ball(planes.data(), 6);
    CHECK(b.status == Status::CONVERGED);
    CHECK(std::abs(b.radius - 1.0) < 1e-15);
    CHECK(std::abs(b.centre.x) + std::abs(b.centre.y) + std::abs(b.centre.z) < 1e-15);
}

TEST_CASE("inscribed ball: a box's ball has half its least side, at the box's centre") {
    // it could slide along the two longer sides: the lexicographic centre is the middle
    const auto planes = box_planes({10, 20, 30}, {12, 26, 31});
    const InscribedBall b = inscribed_ball(planes.data(), 6);
    CHECK(b.status == Status::CONVERGED);
    CHECK(std::abs(b.radius - 0.5) < 1e-14);
    CHECK(norm(b.centre - Vec3{11, 23, 30.5}) < 1e-13);
}

TEST_CASE("inscribed ball: a regular tetrahedron's ball is a quarter of its height") {
    // corners (1,1,1), (1,-1,-1), (-1,1,-1), (-1,-1,1): faces at distance 1/sqrt(3)
    const double s = 1.0 / std::sqrt(3.0);
    const std::vector<double> planes = {-s, -s, -s, -s, -s, s, s, -s,
                                        s,  -s, s,  -s, s,  s, -s, -s};
    const InscribedBall b = inscribed_ball(planes.data(), 4);
    CHECK(b.status == Status::CONVERGED);
    CHECK(std::abs(b.radius - s) < 1e-15);
    CHECK(std::abs(b.centre.x) + std::abs(b.centre.y) + std::abs(b.centre.z) < 1e-14);
}

TEST_CASE("inscribed ball: a tetrahedron's ball is 3 V / A, at its incentre") {
    // the incentre weighs each corner by the area of the face opposite it
    const Vec3 p[4] = {{0.3, -0.2, 0.1}, {2.0, 0.1, -0.4}, {0.5, 1.7, 0.2}, {0.4, 0.3, 1.9}};
    std::vector<double> planes;
    double area = 0.0, areas[4];
    Vec3 weighted{};
    for (int k = 0; k < 4; ++k) {  // face k is opposite corner k
        const Vec3 a = p[(k + 1) % 4], b = p[(k + 2) % 4], c = p[(k + 3) % 4];
        Vec3 n = cross(b - a, c - a);
        areas[k] = 0.5 * norm(n);
        n = n / norm(n);
        if (dot(n, p[k] - a) > 0) n = -n;  // outward: away from the opposite corner
        planes.insert(planes.end(), {n.x, n.y, n.z, -dot(n, a)});
        area += areas[k];
        weighted += p[k] * areas[k];
    }
    const double volume = std::abs(dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0]))) / 6.0;
    const InscribedBall b = inscribed_ball(planes.data(), 4);
    CHECK(b.status == Status::CONVERGED);
    CHECK(std::abs(b.radius - 3.0 * volume / area) < 1e-14);
    CHECK(norm(b.centre - weighted / area) < 1e-14);
}

TEST_CASE("inscribed ball: far from the origin, the radius keeps its digits") {
    const auto planes = box_planes({1e9, 1e9, 1e9}, {1e9 + 2, 1e9 + 4, 1e9 + 8});
    const InscribedBall b = inscribed_ball(planes.data(), 6);
    CHECK(b.status == Status::CONVERGED);
    CHECK(std::abs(b.radius - 1.0) < 1e-6);
    CHECK(norm(b.centre - Vec3{1e9 + 1, 1e9 + 2, 1e9 + 4}) < 1e-6);
}

TEST_CASE("inscribed ball: empty, unbounded and slab polytopes are DEGENERATE") {
    // x <= -1 and -x <= -1 (x >= 1): empty
    const std::vector<double> empty = {1, 0, 0, 1, -1, 0, 0, 1, 0, 1, 0, -1,
                                       0, -1, 0, -1, 0, 0, 1, -1, 0, 0, -1, -1};
    InscribedBall b = inscribed_ball(empty.data(), 6);
    CHECK(b.status == Status::DEGENERATE);
    CHECK(b.radius == 0.0);
    // a half-space holds balls of every radius; a slab's largest has half its width
    const std::vector<double> half = {1, 0, 0, -1};
    b = inscribed_ball(half.data(), 1);
    CHECK(b.status == Status::DEGENERATE);
    const std::vector<double> slab = {1, 0, 0, -1, -1, 0, 0, -1};
    b = inscribed_ball(slab.data(), 2);
    CHECK(b.status == Status::DEGENERATE);
    CHECK(std::abs(b.radius - 1.0) < 1e-15);
}

TEST_CASE("inscribed ball: no plane or a NaN is INVALID_INPUT") {
    std::vector<double> planes = box_planes({-1, -1, -1}, {1, 1, 1});
    CHECK(inscribed_ball(planes.data(), 0).status == Status::INVALID_INPUT);
    planes[5] = std::nan("");
    CHECK(inscribed_ball(planes.data(), 6).status == Status::INVALID_INPUT);
}

TEST_CASE("inscribed ball: a batch on threads is the loop of singles") {
    std::vector<double> planes;
    std::vector<std::int64_t> offsets = {0};
    for (int h = 0; h < 300; ++h) {
        const auto box = box_planes({0.1 * h, 0, -h * 0.01}, {0.1 * h + 1 + h, 2, 3});
        planes.insert(planes.end(), box.begin(), box.end());
        offsets.push_back(offsets.back() + 6);
    }
    std::vector<InscribedBall> out(300);
    inscribed_balls(planes.data(), offsets.data(), 300, 2, out.data());
    for (int h = 0; h < 300; ++h) {
        const InscribedBall one = inscribed_ball(planes.data() + 4 * offsets[h], 6);
        CHECK(out[h].status == one.status);
        CHECK(out[h].radius == one.radius);
        CHECK(out[h].centre.x == one.centre.x);
    }
}
