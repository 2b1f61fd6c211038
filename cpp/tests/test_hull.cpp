// Quickhull (hull.hpp): known hulls, the flatness rule's statuses, packing.
#include <cmath>
#include <limits>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/hull.hpp"

using namespace meshcol;

namespace {

const double kPi = std::acos(-1.0);

// Every face's plane has every vertex on its inner side (or on it).
bool faces_enclose(const Hull& h, const std::vector<Vec3>& points) {
    for (size_t f = 0; f < h.faces.size(); ++f)
        for (const Vec3& p : points)
            if (dot(h.face_normals[f], p) + h.face_offsets[f] > 1e-12) return false;
    return true;
}

}  // namespace

TEST_CASE("hull: a cube with interior points is its 8 corners") {
    std::vector<Vec3> points = fixtures::cube_corners(0.5);
    points.push_back({0.0, 0.0, 0.0});
    points.push_back({0.1, -0.2, 0.3});
    points.push_back({0.5, 0.0, 0.0});  // on a face: not a vertex
    const Hull h = exact_hull(points.data(), static_cast<long long>(points.size()));
    REQUIRE(h.status == HullStatus::OK);
    CHECK_EQ(h.dimension, 3);
    CHECK_EQ(h.vertices.size(), size_t{8});
    for (int v : h.vertices) CHECK(v < 8);
    CHECK_EQ(h.faces.size(), size_t{12});  // two triangles per square face
    CHECK_NEAR(h.volume, 1.0, 1e-14);
    CHECK_NEAR(h.area, 6.0, 1e-14);
    CHECK_NEAR(h.diagonal, std::sqrt(3.0), 1e-14);
    CHECK(faces_enclose(h, points));
}

TEST_CASE("hull: a tetrahedron") {
    const std::vector<Vec3> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const Hull h = exact_hull(points.data(), 4);
    REQUIRE(h.status == HullStatus::OK);
    CHECK_EQ(h.vertices.size(), size_t{4});
    CHECK_EQ(h.faces.size(), size_t{4});
    CHECK_NEAR(h.volume, 1.0 / 6.0, 1e-15);
    CHECK_NEAR(h.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-14);
    CHECK(faces_enclose(h, points));
    for (const Vec3& n : h.face_normals) CHECK_NEAR(norm(n), 1.0, 1e-15);
}

TEST_CASE("hull: points on a sphere are all vertices (V - E + F = 2)") {
    // a Fibonacci sphere: no four points coplanar, every point extreme
    const int n = 200;
    std::vector<Vec3> points;
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / n;
        const double r = std::sqrt(1.0 - z * z);
        points.push_back({r * std::cos(golden * i), r * std::sin(golden * i), z});
    }
    const Hull h = exact_hull(points.data(), n);
    REQUIRE(h.status == HullStatus::OK);
    CHECK_EQ(h.vertices.size(), size_t{200});
    CHECK_EQ(h.faces.size(), size_t{2 * 200 - 4});  // a triangulated sphere
    CHECK(h.volume < 4.0 / 3.0 * kPi && h.volume > 0.97 * 4.0 / 3.0 * kPi);
    CHECK(faces_enclose(h, points));
}

TEST_CASE("hull: flat, collinear, single-point and empty inputs say so") {
    const std::vector<Vec3> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
    const Hull flat = exact_hull(square.data(), 5);
    CHECK(flat.status == HullStatus::FLAT);
    CHECK_EQ(flat.dimension, 2);
    CHECK_EQ(flat.vertices.size(), size_t{4});  // the centre is not on the ring
    CHECK_NEAR(flat.area, 1.0, 1e-15);
    CHECK_EQ(flat.volume, 0.0);
    CHECK_NEAR(std::fabs(flat.normal.z), 1.0, 1e-15);

    const std::vector<Vec3> line = {{0, 0, 0}, {1, 1, 1}, {0.25, 0.25, 0.25}, {3, 3, 3}};
    const Hull segment = exact_hull(line.data(), 4);
    CHECK(segment.status == HullStatus::COLLINEAR);
    CHECK_EQ(segment.dimension, 1);
    CHECK_EQ(segment.vertices.size(), size_t{2});

    const std::vector<Vec3> same = {{2, 2, 2}, {2, 2, 2}, {2, 2, 2}};
    const Hull point = exact_hull(same.data(), 3);
    CHECK(point.status == HullStatus::SINGLE_POINT);
    CHECK_EQ(point.dimension, 0);

    CHECK(exact_hull(nullptr, 0).status == HullStatus::EMPTY);
}

TEST_CASE("hull: a nearly flat slab within the flatness rule is FLAT") {
    std::vector<Vec3> points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    points.push_back({0.5, 0.5, 1e-12});  // 1e-12 of a diagonal of 1.4: below 1e-9
    CHECK(exact_hull(points.data(), 5).status == HullStatus::FLAT);
    points.back().z = 1e-3;
    CHECK(exact_hull(points.data(), 5).status == HullStatus::OK);
}

TEST_CASE("hull: non-finite and huge coordinates are refused") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<Vec3> points = fixtures::cube_corners(1.0);
    points[3].y = nan;
    CHECK(exact_hull(points.data(), 8).status == HullStatus::NON_FINITE);
    points[3].y = 1e200;
    CHECK(exact_hull(points.data(), 8).status == HullStatus::OVERFLOW);
}

TEST_CASE("hull: pack_polytopes packs each shape's hull and features") {
    std::vector<Vec3> points = fixtures::cube_corners(1.0);
    points.push_back({0, 0, 0});                      // interior point of the cube
    const std::vector<Vec3> tetra = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    points.insert(points.end(), tetra.begin(), tetra.end());
    const std::int64_t offsets[3] = {0, 9, 13};
    const PackedPolytopes p = pack_polytopes(points.data(), offsets, 2, 1);
    REQUIRE(p.status.size() == 2);
    CHECK(p.status[0] == HullStatus::OK);
    CHECK(p.status[1] == HullStatus::OK);
    REQUIRE(p.offsets.size() == 3);
    CHECK_EQ(p.offsets[1] - p.offsets[0], std::int64_t{8});
    CHECK_EQ(p.offsets[2] - p.offsets[1], std::int64_t{4});
    // a cube has 6 planes and 3 edge directions; a tetrahedron 4 planes and 6 directions
    CHECK_EQ(p.face_offsets[1] - p.face_offsets[0], std::int64_t{6});
    CHECK_EQ(p.edge_offsets[1] - p.edge_offsets[0], std::int64_t{3});
    CHECK_EQ(p.face_offsets[2] - p.face_offsets[1], std::int64_t{4});
    CHECK_EQ(p.edge_offsets[2] - p.edge_offsets[1], std::int64_t{6});
}
