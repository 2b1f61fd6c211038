// Quickhull (hull.hpp): known hulls, the flatness rule's statuses, packing.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "quickhull_reference.hpp"
#include "hull_detail.hpp"
#include "hull_orientation.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/narrowphase.hpp"

using namespace meshcol;

namespace {

const double kPi = std::acos(-1.0);

Vec3 unit(const Vec3& v) { return v / norm(v); }

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

TEST_CASE("hull: widths by support climbs are the largest minus smallest projection, exactly") {
    // a cube of a grid (whole faces of coplanar vertices: ties) and a random round hull
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (int shape = 0; shape < 2; ++shape) {
        std::vector<Vec3> points;
        for (int i = 0; i < 600; ++i) {
            if (shape == 0)
                points.push_back({double(rng() % 5), double(rng() % 5), double(rng() % 5)});
            else
                points.push_back(unit({normal(rng), normal(rng), normal(rng)}) * 3.0 +
                                 Vec3{100.0, -20.0, 5.0});
        }
        const Hull h = exact_hull(points.data(), static_cast<long long>(points.size()));
        REQUIRE(h.status == HullStatus::OK);
        std::vector<Vec3> v;
        for (int i : h.vertices) v.push_back(points[i]);
        std::vector<std::int64_t> faces;
        for (const auto& t : h.faces) faces.insert(faces.end(), {t[0], t[1], t[2]});
        std::vector<Vec3> directions(h.face_normals);
        for (int i = 0; i < 200; ++i)
            directions.push_back(unit({normal(rng), normal(rng), normal(rng)}));
        std::vector<double> widths(directions.size());
        REQUIRE(hull_widths(v.data(), int(v.size()), faces.data(), (long long)h.faces.size(),
                            directions.data(), (long long)directions.size(), widths.data()));
        for (size_t i = 0; i < directions.size(); ++i) {
            double top = -INFINITY, bottom = INFINITY;
            for (const Vec3& p : v) {
                top = std::max(top, width_projection(p, directions[i]));
                bottom = std::min(bottom, width_projection(p, directions[i]));
            }
            CHECK_EQ(widths[i], top - bottom);
        }
    }
    std::vector<std::int64_t> bad = {0, 1, 9};
    Vec3 one{0.0, 0.0, 0.0}, axis{1.0, 0.0, 0.0};
    double w = 0.0;
    CHECK(!hull_widths(&one, 1, bad.data(), 1, &axis, 1, &w));
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
    // a cube has 6 planes, 12 true edges and 3 edge directions; a tetrahedron 4 planes and 6
    // edges of 6 directions
    CHECK_EQ(p.face_offsets[1] - p.face_offsets[0], std::int64_t{6});
    CHECK_EQ(p.edge_pair_offsets[1] - p.edge_pair_offsets[0], std::int64_t{12});
    CHECK_EQ(p.face_offsets[2] - p.face_offsets[1], std::int64_t{4});
    CHECK_EQ(p.edge_pair_offsets[2] - p.edge_pair_offsets[1], std::int64_t{6});
    const auto* vertices = reinterpret_cast<const Vec3*>(p.vertices.data());
    std::vector<double> cube, tetrahedron;
    CHECK_EQ(edge_direction_classes(vertices, p.edge_pairs.data(), 12, cube), std::int64_t{3});
    CHECK_EQ(edge_direction_classes(vertices + 8, p.edge_pairs.data() + 24, 6, tetrahedron),
             std::int64_t{6});
    CHECK_EQ(edge_direction_class_count(vertices, p.edge_pairs.data(), 12), std::int64_t{3});
    CHECK_EQ(edge_direction_class_count(vertices, p.edge_pairs.data(), 1), std::int64_t{1});
}

namespace {

// n points of shape `family` from a small linear congruential generator (deterministic on
// every platform): 0 on an ellipsoid (every point a vertex), 1 a Gaussian-like cloud, 2 a
// lattice (coplanar faces), 3 duplicates, 4 a flat set, 5 a NaN, 6 none.
std::vector<Vec3> family_points(int family, int n, std::uint64_t& state) {
    auto uniform = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1p-53 * 2.0 - 1.0;
    };
    std::vector<Vec3> p;
    if (family == 6) return p;
    for (int i = 0; i < n; ++i) {
        Vec3 q{uniform(), uniform(), uniform() + uniform()};
        if (family == 0) q = q / norm(q) * 1.3, q.y *= 0.6;
        if (family == 2) q = Vec3{std::floor(3 * q.x), std::floor(3 * q.y), std::floor(3 * q.z)};
        if (family == 3 && i % 3 == 2) q = p.back();
        if (family == 4) q.z = 0.25 * q.x - 0.5 * q.y;
        p.push_back(q);
    }
    if (family == 5) p[n / 2].y = std::numeric_limits<double>::quiet_NaN();
    return p;
}

// The same bytes (NaN coordinates of a shape kept as given compare equal).
using fixtures::same_bytes;

}  // namespace

TEST_CASE("hull: packing on threads equals packing one shape at a time, byte for byte") {
    // Shapes of every family, packed together on one thread, on two and three (chunks
    // committed in order: threads finish them out of order) and one by one: the same arrays.
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets = {0};
    std::uint64_t state = 7;
    for (int h = 0; h < 400; ++h) {
        const std::vector<Vec3> p = family_points(h % 7, 8 + (h * 13) % 90, state);
        points.insert(points.end(), p.begin(), p.end());
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    }
    const long long shapes = static_cast<long long>(offsets.size()) - 1;
    const PackedPolytopes one = pack_polytopes(points.data(), offsets.data(), shapes, 1);
    for (int threads : {2, 3}) {
        const PackedPolytopes two = pack_polytopes(points.data(), offsets.data(), shapes, threads);
        CHECK(fixtures::same_packing(one, two));
        CHECK(one.climb_list_offsets == two.climb_list_offsets);
        REQUIRE(one.climb_lists.size() == two.climb_lists.size());
        CHECK(same_bytes(one.climb_lists.data(), two.climb_lists.data(), one.climb_lists.size()));
    }
    CHECK(one.status[5] == HullStatus::NON_FINITE);
    CHECK(one.status[6] == HullStatus::EMPTY);
    for (long long h = 0; h < shapes; ++h) {
        const std::int64_t at[2] = {0, offsets[h + 1] - offsets[h]};
        const PackedPolytopes alone = pack_polytopes(points.data() + offsets[h], at, 1, 1);
        const auto v0 = one.offsets[h], v1 = one.offsets[h + 1];
        REQUIRE(alone.offsets[1] == v1 - v0);
        CHECK(alone.status[0] == one.status[h]);
        CHECK(same_bytes(alone.vertices.data(), one.vertices.data() + 3 * v0,
                         alone.vertices.size()));
        const auto a0 = one.adjacency_offsets[v0];
        for (std::int64_t k = 0; k <= v1 - v0; ++k)
            CHECK_EQ(alone.adjacency_offsets[k], one.adjacency_offsets[v0 + k] - a0);
        CHECK(same_bytes(alone.adjacency.data(), one.adjacency.data() + a0,
                         alone.adjacency.size()));
        const auto f0 = one.face_offsets[h], e0 = one.edge_pair_offsets[h];
        CHECK_EQ(alone.face_offsets[1], one.face_offsets[h + 1] - f0);
        CHECK_EQ(alone.edge_pair_offsets[1], one.edge_pair_offsets[h + 1] - e0);
        CHECK(same_bytes(alone.face_normals.data(), one.face_normals.data() + 3 * f0,
                         alone.face_normals.size()));
        CHECK(same_bytes(alone.edge_pairs.data(), one.edge_pairs.data() + 2 * e0,
                         alone.edge_pairs.size()));
    }
}

TEST_CASE("hull: the packing's climb lists are those its adjacency makes, byte for byte") {
    // Every family at sizes on both sides of the climbing threshold and of the 8-bit lists'
    // (kNarrowClimbVertices: larger shapes keep 16-bit lists, two rows a vertex), and a
    // bipyramid whose apexes have 24 neighbours (no lists: its shape climbs on the CSR
    // arrays), on one thread and on two: the lists ClimbLists makes from the packed CSR
    // arrays, the same bytes.
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets = {0};
    std::uint64_t state = 11;
    std::int64_t smooth = 0;  // the list rows of the climbing ellipsoids (every point a vertex)
    for (int h = 0; h < 140; ++h) {
        const int n = 4 + (h * 29) % 300;
        const std::vector<Vec3> p = family_points(h % 7, n, state);
        if (h % 7 == 0 && n > defaults::hill_climbing_min_vertices) smooth += n * climb_rows(n);
        points.insert(points.end(), p.begin(), p.end());
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    }
    for (int i = 0; i < 24; ++i)
        points.push_back(Vec3{std::cos(2 * kPi * i / 24), std::sin(2 * kPi * i / 24), 0.0});
    points.push_back(Vec3{0.0, 0.0, 1.0});
    points.push_back(Vec3{0.0, 0.0, -1.0});
    offsets.push_back(static_cast<std::int64_t>(points.size()));
    const long long shapes = static_cast<long long>(offsets.size()) - 1;
    for (int threads : {1, 2}) {
        const PackedPolytopes packed = pack_polytopes(points.data(), offsets.data(), shapes, threads);
        fixtures::PolytopeSet set(packed);
        const ClimbLists made(set.view, 1);
        ConvexSetView from_csr = set.view;
        made.attach(from_csr);
        REQUIRE(packed.climb_list_offsets.size() == static_cast<size_t>(shapes + 1));
        REQUIRE(packed.climb_lists.size() == static_cast<size_t>(made.size()));
        std::int64_t climbing = 0;
        int wide = 0;  // hulls of more vertices than 8-bit entries index
        for (long long h = 0; h < shapes; ++h) {
            const std::int64_t count = packed.climb_list_offsets[h + 1] - packed.climb_list_offsets[h];
            const ShapeView s = from_csr.shape(h);
            CHECK((count > 0) == (s.climb_lists != nullptr));
            if (count == 0) continue;
            CHECK(count == s.vertex_count * climb_rows(s.vertex_count));
            wide += s.vertex_count > kNarrowClimbVertices;
            CHECK(climbs(s));
            climbing += count;
            CHECK(std::memcmp(packed.climb_lists.data() + packed.climb_list_offsets[h],
                              s.climb_lists, sizeof(ClimbList) * static_cast<size_t>(count)) == 0);
        }
        CHECK(climbing == made.size());
        CHECK(climbing >= smooth);  // lists for every smooth hull (and others)
        CHECK(smooth > 2000);
        CHECK(wide >= 2);
        // The bipyramid climbs but keeps no lists.
        CHECK(packed.offsets[shapes] - packed.offsets[shapes - 1] == 26);
        CHECK(packed.climb_list_offsets[shapes] == packed.climb_list_offsets[shapes - 1]);
    }
}

TEST_CASE("hull: the flat Quickhull builds the reference's triangulation, bit for bit") {
    // quickhull_flat replays the reference's steps (quickhull_reference.hpp) on other
    // storage: the same triangles, neighbours, planes and edges, in the same order, on every
    // family (and on near-spheres whose faces' sides need the exact orientation).
    using hull_detail::Build;
    using hull_detail::Triangulation;
    std::uint64_t state = 19;
    int built = 0;
    for (int h = 0; h < 240; ++h) {
        const int family = h % 6;
        const int n = 4 + (h * 37) % 700;
        std::vector<Vec3> p = family_points(family == 5 ? 0 : family, n, state);
        if (family == 5)  // a sphere with noise near the plane filter's bound
            for (Vec3& q : p) q = q / norm(q) + Vec3{1e-14, -1e-14, 1e-14} * (q.x * 7.0 - q.y);
        hull_reference::Workspace w;
        double max_abs = 0.0;
        for (const Vec3& q : p) max_abs = std::max(max_abs, meshcol::max_abs(q));
        for (const Vec3& q : p) w.p.push_back(q / 2.0);  // into (-1, 1)^3, exactly
        w.eps = defaults::hull_relative_tolerance * max_abs / 2.0;
        w.mark.assign(p.size(), 0);
        std::vector<int> subset(p.size());
        for (size_t i = 0; i < subset.size(); ++i) subset[i] = static_cast<int>(i);
        Triangulation reference, flat;
        const Build a = hull_reference::quickhull(w, subset, reference);
        const Build b = hull_detail::quickhull_flat(w, subset, flat);
        CHECK(a == b);
        if (a != Build::OK || b != Build::OK) continue;
        ++built;
        CHECK(same_bytes(reference.tri, flat.tri));
        CHECK(same_bytes(reference.normal, flat.normal));
        CHECK(same_bytes(reference.offset, flat.offset));
        CHECK(same_bytes(reference.area2, flat.area2));
        CHECK(same_bytes(reference.edges, flat.edges));
    }
    CHECK(built >= 150);
}

TEST_CASE("hull: clearly solid axis extremes mean the flatness rule finds 3-D") {
    // hull_with skips the principal axes when four of the axis extremes are clearly solid:
    // on slabs from 1e-13 to 1e-3 of their size thick (the rule's bound, 1e-9 of the
    // diagonal, among them), turned at random, and on ellipsoids, the rule itself must then
    // find three dimensions. Both outcomes of the rule occur, and the shortcut is taken.
    std::uint64_t state = 23;
    auto uniform = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1p-53 * 2.0 - 1.0;
    };
    int solid = 0, flat = 0, decided_by_rule = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const int n = 4 + trial % 97;
        const double thickness = std::pow(10.0, -13.0 + 10.0 * (0.5 + 0.5 * uniform()));
        Vec3 q{uniform(), uniform(), uniform()};
        q = q / norm(q);
        const double turn = kPi * uniform();
        const Vec3 axis = q * std::sin(turn);
        const double c = std::cos(turn);
        std::vector<Vec3> p;
        for (int i = 0; i < n; ++i) {
            Vec3 x{uniform(), uniform(), thickness * uniform()};
            if (trial % 5 == 4) x = Vec3{uniform(), uniform(), uniform()} / 2.0;  // solid
            // Rodrigues' rotation about `axis` by twice `turn` (a unit quaternion's).
            const Vec3 t = cross(axis, x) * 2.0;
            x = x + t * c + cross(axis, t);
            x = x / 2.0;  // into (-1, 1)^3
            p.push_back(x);
        }
        Vec3 lo = p[0], hi = p[0], sum{};
        for (const Vec3& x : p) lo = component_min(lo, x), hi = component_max(hi, x), sum += x;
        const double diagonal = norm(hi - lo);
        const Vec3 centre = sum / static_cast<double>(n);
        Vec3 axes[3];
        hull_detail::principal_axes(p.data(), n, centre, axes);
        const int dim = hull_detail::flatness_dimension(p.data(), n, centre, axes, diagonal);
        std::vector<int> all(p.size());
        for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
        int extreme[6];
        hull_detail::axis_extremes(p, all, extreme);
        const bool clearly = hull_detail::clearly_solid_among(p.data(), extreme, 6, diagonal);
        CHECK(!clearly || dim == 3);
        solid += clearly ? 1 : 0;
        flat += dim < 3 ? 1 : 0;
        decided_by_rule += !clearly && dim == 3 ? 1 : 0;
    }
    CHECK(solid >= 200);
    CHECK(flat >= 100);
    CHECK(decided_by_rule >= 10);
}

TEST_CASE("hull: every point of an ellipsoid is a vertex, every vertex list sorted and padded") {
    std::uint64_t state = 11;
    const std::vector<Vec3> p = family_points(0, 64, state);
    const std::int64_t at[2] = {0, 64};
    const PackedPolytopes packed = pack_polytopes(p.data(), at, 1, 1);
    REQUIRE(packed.status[0] == HullStatus::OK);
    CHECK_EQ(packed.offsets[1], std::int64_t{64});
    // Euler: 64 vertices in general position, 124 triangles, each its own plane; 186 edges.
    CHECK_EQ(packed.face_offsets[1], std::int64_t{124});
    CHECK_EQ(packed.edge_pair_offsets[1], std::int64_t{186});
    std::vector<double> classes;
    CHECK_EQ(edge_direction_classes(reinterpret_cast<const Vec3*>(packed.vertices.data()),
                                    packed.edge_pairs.data(), 186, classes),
             std::int64_t{186});
    std::int64_t degrees = 0;
    for (int v = 0; v < 64; ++v) {
        const auto b = packed.adjacency_offsets[v], e = packed.adjacency_offsets[v + 1];
        CHECK_EQ((e - b) % 4, std::int64_t{0});
        for (auto k = b + 1; k < e; ++k)
            CHECK(packed.adjacency[k - 1] <= packed.adjacency[k] || packed.adjacency[k] == v);
        for (auto k = b; k < e; ++k) degrees += packed.adjacency[k] != v ? 1 : 0;
    }
    CHECK_EQ(degrees, std::int64_t{2 * 186});
}

TEST_CASE("hull: the plane filter decides a side only as the exact orientation does") {
    // Quickhull's faces decide which side a point is on by the plane distance when it is
    // beyond the face's filter (a proved bound), else by the exact orientation: the two must
    // agree everywhere, most of all just beyond the bound and on thin triangles.
    using hull_detail::face_plane;
    using hull_detail::orientation;
    using hull_detail::plane_side;
    std::uint64_t state = 5;
    auto uniform = [&]() {  // in [0, 1)
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1p-53;
    };
    auto coordinate = [&]() { return 1.8 * uniform() - 0.9; };
    auto point = [&]() { return Vec3{coordinate(), coordinate(), coordinate()}; };
    long long decided = 0, exact = 0, wrong = 0, unfiltered = 0;
    for (int trial = 0; trial < 6000; ++trial) {
        const Vec3 a = point(), b = point();
        // Every other triangle thin: c within 1e-3 .. 1e-9 of the line ab.
        const Vec3 c = trial % 2 == 0 ? point()
                                      : a + (b - a) * uniform() +
                                            point() * std::ldexp(1.0, -10 - trial % 21);
        const hull_detail::Plane pl = face_plane(a, b, c);
        unfiltered += std::isinf(pl.filter) ? 1 : 0;
        for (int k = 0; k < 24; ++k) {
            // Heights from 2^-30 down to 2^-53 (the bound is 1e-13, about 2^-43), both sides.
            const double s = uniform(), t = uniform() * (1.0 - s);
            const double height = (k % 2 == 0 ? 1.0 : -1.0) * std::ldexp(1.0 + uniform(), -30 - k);
            const Vec3 x = a + (b - a) * s + (c - a) * t + pl.normal * height;
            const int side = plane_side(pl.normal, pl.offset, pl.filter, a, b, c, x);
            wrong += side != orientation(a, b, c, x) ? 1 : 0;
            const double d = dot(pl.normal, x) - pl.offset;
            (std::fabs(d) > pl.filter ? decided : exact) += 1;
        }
    }
    CHECK_EQ(wrong, 0LL);
    // Both ways were taken, many times (the test is not vacuous).
    CHECK(decided > 30000);
    CHECK(exact > 30000);
    CHECK(unfiltered < 6000);
}

TEST_CASE("hull: any input order and either zero give the same hull (the sort is total)") {
    // Cube corners and octahedron tips, with repeated x and (x, y), -0.0 and 0.0 spellings of
    // one point and exact duplicates: every permutation gives the same vertex coordinates in
    // lexicographic order, each vertex the first index of its point, and the same faces.
    std::vector<Vec3> points = fixtures::cube_corners(1.0);
    const double tips[][3] = {{1.5, 0.0, 0.0},  {1.5, -0.0, -0.0}, {-1.5, 0.0, -0.0},
                              {0.0, 1.5, 0.0},  {-0.0, 1.5, 0.0},  {0.0, -1.5, 0.0},
                              {0.0, 0.0, 1.5},  {-0.0, -0.0, 1.5}, {0.0, 0.0, -1.5},
                              {0.25, 0.0, 0.0}, {0.0, 0.0, 0.0},   {-0.0, -0.0, -0.0}};
    for (const auto& t : tips) points.push_back({t[0], t[1], t[2]});
    points.push_back(points[3]);
    points.push_back(points[0]);
    const auto n = static_cast<long long>(points.size());
    auto coordinates = [](const Vec3& p) { return Vec3{p.x + 0.0, p.y + 0.0, p.z + 0.0}; };
    auto same_point = [](const Vec3& a, const Vec3& b) {
        return a.x == b.x && a.y == b.y && a.z == b.z;
    };
    const Hull first = exact_hull(points.data(), n);
    REQUIRE(first.status == HullStatus::OK);
    CHECK_EQ(first.vertices.size(), size_t{14});
    std::uint64_t state = 12345;
    for (int round = 0; round < 40; ++round) {
        std::vector<int> order(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) order[i] = i;
        for (long long i = n - 1; i > 0; --i) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            std::swap(order[i], order[(state >> 33) % static_cast<std::uint64_t>(i + 1)]);
        }
        std::vector<Vec3> shuffled(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) shuffled[i] = points[order[i]];
        const Hull h = exact_hull(shuffled.data(), n);
        REQUIRE(h.vertices.size() == first.vertices.size());
        REQUIRE(h.faces.size() == first.faces.size());
        for (size_t v = 0; v < h.vertices.size(); ++v) {
            const Vec3 p = coordinates(shuffled[h.vertices[v]]);
            const Vec3 expected = coordinates(points[first.vertices[v]]);
            CHECK(std::memcmp(&p, &expected, sizeof p) == 0);
            if (v > 0) {
                const Vec3 q = coordinates(shuffled[h.vertices[v - 1]]);
                CHECK((q.x < p.x) || (q.x == p.x && (q.y < p.y || (q.y == p.y && q.z < p.z))));
            }
            // The first index (in the shuffled input) of the equal points.
            for (int i = 0; i < h.vertices[v]; ++i) CHECK(!same_point(shuffled[i], p));
        }
        for (size_t f = 0; f < h.faces.size(); ++f)
            for (int c = 0; c < 3; ++c) CHECK_EQ(h.faces[f][c], first.faces[f][c]);
    }
}

namespace {

// unique_directions as main ccdc8db wrote it (scalar, integer keys, a linear search for the
// classes): the reference the packing's two-lane version must equal bit for bit.
std::vector<double> reference_unique_directions(const std::vector<Vec3>& d, bool signed_classes) {
    auto floor_to_integer = [](double x) {
        const auto t = static_cast<long long>(x);
        return t - (static_cast<double>(t) > x ? 1 : 0);
    };
    std::vector<std::array<long long, 3>> keys;
    std::vector<double> out;
    for (const Vec3& v : d) {
        double x = v.x, y = v.y, z = v.z;
        const double len = std::sqrt(x * x + y * y + z * z);
        if (!(len > 0.0)) continue;
        x = x / len, y = y / len, z = z / len;
        if (!signed_classes) {
            const double lead = std::fabs(x) > 1e-12 ? x : (std::fabs(y) > 1e-12 ? y : z);
            if (lead < 0.0 && std::fabs(lead) > 1e-12) x = -x, y = -y, z = -z;
        }
        const std::array<long long, 3> k = {floor_to_integer(x * 1e12 + 0.5),
                                             floor_to_integer(y * 1e12 + 0.5),
                                             floor_to_integer(z * 1e12 + 0.5)};
        bool fresh = true;
        for (const auto& seen : keys) fresh = fresh && seen != k;
        if (!fresh) continue;
        keys.push_back(k);
        out.insert(out.end(), {x, y, z});
    }
    return out;
}

}  // namespace

TEST_CASE("hull: the packing's direction classes equal the scalar ones bit for bit") {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> g;
    std::uniform_int_distribution<int> pick(0, 11);
    // Components that stress the keys and the sign rule: exact halves of the 1e-12 grid
    // (x * 1e12 + 0.5 an integer: rint's ties), values at and beside +-1e-12, zeros of both
    // signs, exact binary fractions, denormal-sized and huge vectors, and near-repeats (one
    // ulp or 1e-13 apart) so that classes merge.
    auto component = [&]() {
        switch (pick(rng)) {
            case 0: return 0.0;
            case 1: return -0.0;
            case 2: return 1e-12 * (g(rng) > 0 ? 1 : -1);
            case 3: return std::nextafter(1e-12, g(rng) > 0 ? 1.0 : 0.0) * (g(rng) > 0 ? 1 : -1);
            case 4: return std::ldexp(std::floor(g(rng) * 64), -6);
            case 5: return (std::floor(g(rng) * 1e6) + 0.5) * 1e-12;
            default: return g(rng);
        }
    };
    // Unit vectors whose small component is exactly at or one ulp beside 1e-12 (the sign
    // rule's threshold): s^2 + 1 rounds to 1, so the length is exactly 1.
    std::vector<Vec3> edge_cases;
    for (double s : {1e-12, std::nextafter(1e-12, 0.0), std::nextafter(1e-12, 1.0)})
        for (double a : {s, -s})
            for (double b : {1.0, -1.0})
                edge_cases.insert(edge_cases.end(), {{a, 0.0, b}, {a, b, 0.0}, {0.0, a, b},
                                                     {-0.0, a, b}, {a, -0.0, b}, {a, a, b}});
    for (bool signed_classes : {true, false}) {
        const std::vector<double> want = reference_unique_directions(edge_cases, signed_classes);
        const std::vector<double> got =
            hull_detail::unique_directions_of(edge_cases.data(), edge_cases.size(), signed_classes);
        CHECK(got.size() == want.size() &&
              std::memcmp(got.data(), want.data(), 8 * got.size()) == 0);
    }
    for (int round = 0; round < 400; ++round) {
        std::vector<Vec3> d;
        const int n = 1 + round % 37;
        for (int i = 0; i < n; ++i) {
            Vec3 v{component(), component(), component()};
            const int scale = pick(rng);
            if (scale == 0) v = v * 1e-160;
            if (scale == 1) v = v * 1e95;
            d.push_back(v);
            if (pick(rng) < 3) d.push_back(d.back() * -1.0);
            if (pick(rng) < 3) {
                const Vec3 w = d.back();
                d.push_back({std::nextafter(w.x, 2.0), w.y, w.z + 1e-13});
            }
        }
        for (bool signed_classes : {true, false}) {
            const std::vector<double> want = reference_unique_directions(d, signed_classes);
            const std::vector<double> got =
                hull_detail::unique_directions_of(d.data(), d.size(), signed_classes);
            CHECK(got.size() == want.size());
            CHECK(got.size() == want.size() &&
                  std::memcmp(got.data(), want.data(), 8 * got.size()) == 0);
        }
    }
}
