// GJK distance, EPA and SAT penetration, and the pair query that combines them (gjk.hpp,
// epa.hpp, sat.hpp, narrowphase.hpp), on pairs whose answers are known in closed form.
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/epa.hpp"
#include "meshcol/gjk.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/sat.hpp"
#include "climb.hpp"

using namespace meshcol;
using fixtures::at;

TEST_CASE("gjk: unit boxes one apart along x") {
    const ShapeView a = fixtures::box(0.5, 0.5, 0.5), b = fixtures::box(0.5, 0.5, 0.5);
    const GjkResult r = gjk_distance(a, at(0, 0, 0), b, at(2, 0, 0));
    REQUIRE(r.status == Status::CONVERGED);
    CHECK(!r.overlap);
    CHECK_NEAR(r.distance, 1.0, 1e-12);
    CHECK_NEAR(r.point_a.x, 0.5, 1e-12);
    CHECK_NEAR(r.point_b.x, 1.5, 1e-12);
    CHECK_NEAR(r.normal.x, 1.0, 1e-12);
}

TEST_CASE("gjk: spheres and a sphere against a box, distances in closed form") {
    const ShapeView s = fixtures::sphere(1.0), t = fixtures::sphere(0.5);
    const GjkResult spheres = gjk_distance(s, at(0, 0, 0), t, at(3, 4, 0));
    REQUIRE(spheres.status == Status::CONVERGED);
    CHECK_NEAR(spheres.distance, 5.0 - 1.5, 1e-12);
    CHECK_NEAR(spheres.normal.x, 0.6, 1e-12);
    CHECK_NEAR(spheres.normal.y, 0.8, 1e-12);

    // a box's corner (1, 1, 1) towards a sphere centred on the diagonal
    const ShapeView b = fixtures::box(1, 1, 1);
    const GjkResult corner = gjk_distance(b, at(0, 0, 0), t, at(3, 3, 3));
    CHECK_NEAR(corner.distance, 2.0 * std::sqrt(3.0) - 0.5, 1e-12);
}

TEST_CASE("gjk: a rotated box, touching counts as overlap") {
    // a box turned 45 degrees about z reaches sqrt(2)/2 along x
    const ShapeView a = fixtures::box(0.5, 0.5, 0.5), b = fixtures::box(0.5, 0.5, 0.5);
    const double reach = std::sqrt(0.5);
    const GjkResult r = gjk_distance(a, fixtures::turned_about_z(std::acos(-1.0) / 4, 0, 0, 0), b,
                                     at(reach + 0.5 + 0.25, 0, 0));
    CHECK_NEAR(r.distance, 0.25, 1e-12);
    const GjkResult touching = gjk_distance(a, at(0, 0, 0), b, at(1, 0, 0));
    CHECK(touching.overlap);
    CHECK_EQ(touching.distance, 0.0);
}

TEST_CASE("epa: boxes overlapping by a quarter along x") {
    const ShapeView a = fixtures::box(0.5, 0.5, 0.5), b = fixtures::box(0.5, 0.5, 0.5);
    const PairResult r = query_pair(a, at(0, 0, 0), b, at(0.75, 0.1, 0.05), QueryKind::PENETRATION);
    REQUIRE(r.status == Status::CONVERGED);
    CHECK(r.intersects);
    CHECK_EQ(r.distance, 0.0);
    CHECK_NEAR(r.depth, 0.25, 1e-12);
    CHECK_NEAR(r.normal.x, 1.0, 1e-12);
    // moving b by depth * normal brings the pair to contact
    const Vec3 moved = Vec3{0.75, 0.1, 0.05} + r.depth * r.normal;
    const GjkResult after = gjk_distance(a, at(0, 0, 0), b, at(moved.x, moved.y, moved.z));
    CHECK_NEAR(after.distance, 0.0, 1e-12);
}

TEST_CASE("epa: spheres and capsules overlap by their radii") {
    const ShapeView s = fixtures::sphere(1.0);
    const PairResult spheres = query_pair(s, at(0, 0, 0), s, at(0, 1.5, 0), QueryKind::PENETRATION);
    REQUIRE(spheres.status == Status::CONVERGED);
    CHECK_NEAR(spheres.depth, 0.5, 1e-12);
    CHECK_NEAR(spheres.normal.y, 1.0, 1e-12);

    // capsules along z side by side: their segments are 1.0 apart, radii 0.75 each
    const ShapeView c = fixtures::capsule(0.75, 2.0);
    const PairResult capsules = query_pair(c, at(0, 0, 0), c, at(1.0, 0, 0.5), QueryKind::PENETRATION);
    CHECK_NEAR(capsules.depth, 0.5, 1e-12);
    const PairResult apart = query_pair(c, at(0, 0, 0), c, at(2.0, 0, 0), QueryKind::DISTANCE);
    CHECK_NEAR(apart.distance, 0.5, 1e-12);
}

TEST_CASE("narrow phase: intersects agrees with the distance") {
    const ShapeView a = fixtures::box(1, 1, 1), b = fixtures::sphere(0.5);
    CHECK(query_pair(a, at(0, 0, 0), b, at(1.4, 0, 0), QueryKind::INTERSECTS).intersects);
    CHECK(!query_pair(a, at(0, 0, 0), b, at(1.6, 0, 0), QueryKind::INTERSECTS).intersects);
}

TEST_CASE("sat: the exact depth of overlapping boxes and the separated verdict") {
    const ShapeView a = fixtures::box(1, 1, 1), b = fixtures::box(0.5, 0.5, 0.5);
    REQUIRE(has_sat_features(a));
    const SatResult deep = sat_penetration(a, at(0, 0, 0), b, at(0.2, 1.3, 0.1));
    REQUIRE(deep.ran);
    CHECK(!deep.separated);
    CHECK_NEAR(deep.depth, 0.2, 1e-12);  // 1.5 - 1.3 along y
    CHECK_NEAR(std::fabs(deep.normal.y), 1.0, 1e-12);
    const SatResult apart = sat_penetration(a, at(0, 0, 0), b, at(0, 0, 1.6));
    REQUIRE(apart.ran);
    CHECK(apart.separated);
    CHECK_EQ(apart.depth, 0.0);
}

TEST_CASE("sat: a turned box's edge sunk into a face") {
    // b turned 45 degrees about z and a sunk into a's +x face by 0.1 along x: b's vertical
    // edge reaches sqrt(2)/2 from its centre
    const ShapeView a = fixtures::box(1, 1, 1), b = fixtures::box(0.5, 0.5, 0.5);
    const double reach = std::sqrt(0.5);
    const SatResult r = sat_penetration(a, at(0, 0, 0), b,
                                        fixtures::turned_about_z(std::acos(-1.0) / 4, 1.0 + reach - 0.1, 0, 0));
    REQUIRE(r.ran);
    CHECK_NEAR(r.depth, 0.1, 1e-12);
    CHECK_NEAR(r.normal.x, 1.0, 1e-12);
}

TEST_CASE("narrow phase: a polytope from points equals the box it spans") {
    const std::vector<Vec3> corners = fixtures::cube_corners(0.5);
    const ShapeView poly = fixtures::polytope(corners), box = fixtures::box(0.5, 0.5, 0.5);
    const PairResult r = query_pair(poly, at(0, 0, 0), box, at(0, 0, 3), QueryKind::DISTANCE);
    CHECK_NEAR(r.distance, 2.0, 1e-12);
    CHECK_NEAR(r.normal.z, 1.0, 1e-12);
}

namespace {

// `count` row-major 4x4 identity poses from `poses` on (the rest of each left as it is).
void identity_poses(double* poses, int count) {
    for (int h = 0; h < count; ++h)
        for (int k = 0; k < 4; ++k) poses[16 * h + 5 * k] = 1.0;
}

}  // namespace

TEST_CASE("narrow phase: a batch sets each pair's status, a bad pose is INVALID_INPUT") {
    // two unit boxes and a sphere; no polytope vertices
    const std::int64_t offsets[4] = {0, 0, 0, 0};
    const std::int8_t kinds[3] = {static_cast<std::int8_t>(ShapeKind::BOX),
                                  static_cast<std::int8_t>(ShapeKind::BOX),
                                  static_cast<std::int8_t>(ShapeKind::SPHERE)};
    const double params[12] = {0.5, 0.5, 0.5, 0, 0.5, 0.5, 0.5, 0, 1.0, 0, 0, 0};
    const ConvexSetView set = fixtures::convex_set(offsets, kinds, params, 3);
    double poses[48] = {};
    identity_poses(poses, 3);
    poses[16 * 1 + 3] = 3.0;                                   // box 1 at x = 3
    poses[16 * 2 + 0] = 2.0;                                   // sphere 2: not rigid
    const std::int64_t pairs[4] = {0, 1, 0, 2};
    double distance[2];
    std::int8_t status[2];
    BatchOutput out;
    out.distance = distance;
    out.status = status;
    run_batch(set, poses, pairs, 2, QueryKind::DISTANCE, 1, out);
    CHECK(status[0] == static_cast<std::int8_t>(Status::CONVERGED));
    CHECK_NEAR(distance[0], 2.0, 1e-12);
    CHECK(status[1] == static_cast<std::int8_t>(Status::INVALID_INPUT));
    CHECK(std::isnan(distance[1]));
}

TEST_CASE("narrow phase: radii kept between batches give each batch the same answers") {
    // Three cubes as polytopes, the third with a NaN corner: batches that share a ShapeRadii
    // (the second reads what the first checked, the NaN included) answer as a batch alone.
    const std::vector<Vec3> corners = fixtures::cube_corners(0.5);
    std::vector<double> vertices;
    for (int h = 0; h < 3; ++h)
        for (const Vec3& c : corners) vertices.insert(vertices.end(), {c.x, c.y, c.z});
    vertices[3 * 16 + 1] = std::nan("");
    const std::int64_t offsets[4] = {0, 8, 16, 24};
    const std::int8_t kinds[3] = {0, 0, 0};
    const double params[12] = {};
    const ConvexSetView set = fixtures::convex_set(offsets, kinds, params, 3, &vertices);
    double poses[48] = {};
    identity_poses(poses, 3);
    poses[16 * 1 + 3] = 0.75;  // cube 1 overlaps cube 0 by a quarter
    poses[16 * 2 + 3] = -3.0;
    const std::int64_t pairs[6] = {0, 1, 0, 2, 1, 0};
    double depth[3], alone[3];
    std::int8_t status[3], alone_status[3];
    BatchOutput out;
    out.depth = alone;
    out.status = alone_status;
    run_batch(set, poses, pairs, 3, QueryKind::PENETRATION, 1, out);
    CHECK_NEAR(alone[0], 0.25, 1e-12);
    CHECK(alone_status[1] == static_cast<std::int8_t>(Status::INVALID_INPUT));
    ShapeRadii radii(3);
    out.depth = depth;
    out.status = status;
    for (int batch = 0; batch < 2; ++batch) {
        run_batch(set, poses, pairs, 3, QueryKind::PENETRATION, 1, out, &radii);
        CHECK(depth[0] == alone[0]);
        CHECK(depth[2] == alone[2]);
        CHECK(std::isnan(depth[1]));
        for (int i = 0; i < 3; ++i) CHECK(status[i] == alone_status[i]);
    }
}

TEST_CASE("shapes: valid_bounding_radius is is_valid plus bounding_radius, bit for bit") {
    // Smooth hulls of every size class (the four-vertex loop and its tail), tiny and huge
    // coordinates (squares out of range: the careful path), and invalid data (NaN, inf).
    fixtures::Uniform uniform{12345};  // in [-1, 1)
    const double scales[] = {1.0, 1e-3, 1e3, 1e-160, 1e160, 1e300};
    for (int n : {1, 2, 3, 4, 5, 7, 8, 16, 33, 64, 255}) {
        for (double scale : scales) {
            std::vector<Vec3> v(static_cast<size_t>(n));
            for (Vec3& p : v) p = Vec3{uniform(), uniform(), uniform()} * scale;
            ShapeView s;
            s.vertices = v.data();
            s.vertex_count = n;
            CHECK(valid_bounding_radius(s) == bounding_radius(s));
            // Every coordinate of the first, a middle and the last vertex: both lanes of the
            // two-vertex SSE2 step and the scalar tail.
            for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL})
                for (int at : {0, n / 2, n - 1})
                    for (int coordinate = 0; coordinate < 3; ++coordinate) {
                        std::vector<Vec3> w = v;
                        w[static_cast<size_t>(at)][coordinate] = bad;
                        s.vertices = w.data();
                        CHECK(!is_valid(s));
                        CHECK(std::isnan(valid_bounding_radius(s)));
                    }
        }
    }
    ShapeView empty;
    CHECK(std::isnan(valid_bounding_radius(empty)));
    const ShapeView sphere = fixtures::sphere(2.5);
    CHECK(valid_bounding_radius(sphere) == 2.5);
    ShapeView bad_sphere = fixtures::sphere(-1.0);
    CHECK(std::isnan(valid_bounding_radius(bad_sphere)));
}

TEST_CASE("shapes: prefetch reads only the shape's own data and changes no answer") {
    // A regular tetrahedron with its hull adjacency (each vertex's three neighbours padded
    // with itself to four), in arrays of exactly the shape's size: the sanitizer lane sees
    // any read past them. Every kind, no data, no adjacency and a shape over the cap too.
    const std::vector<Vec3> corners = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    const std::vector<std::int64_t> offsets = {0, 4, 8, 12, 16};
    const std::vector<std::int32_t> adjacency = {1, 2, 3, 0, 0, 2, 3, 1,
                                                 0, 1, 3, 2, 0, 1, 2, 3};
    ShapeView tetra = fixtures::polytope(corners);
    ShapeView climbing = tetra;
    climbing.adjacency_offsets = offsets.data();
    climbing.adjacency = adjacency.data();
    std::vector<Vec3> many(static_cast<size_t>(defaults::prefetch_max_vertices) + 1,
                           Vec3{0.5, 0.5, 0.5});
    const ShapeView over = fixtures::polytope(many);
    // A shape that climbs (more than hill_climbing_min_vertices), with CSR arrays of exactly
    // its size: prefetch reads the offsets' first and last entries and asks for the rest.
    const int n = defaults::hill_climbing_min_vertices + 8;
    std::vector<Vec3> ring(static_cast<size_t>(n));
    std::vector<std::int64_t> ring_offsets(static_cast<size_t>(n) + 1);
    std::vector<std::int32_t> ring_adjacency(4 * static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        ring[i] = Vec3{std::cos(0.1 * i), std::sin(0.1 * i), 0.01 * i};
        ring_offsets[i + 1] = 4 * (i + 1);
        for (int k = 0; k < 4; ++k) ring_adjacency[4 * i + k] = (i + k + 1) % n;
    }
    ShapeView large = fixtures::polytope(ring);
    large.adjacency_offsets = ring_offsets.data();
    large.adjacency = ring_adjacency.data();
    CHECK(climbs(large));
    for (const ShapeView& s : {ShapeView{}, fixtures::box(1, 2, 3), fixtures::sphere(1.0),
                               fixtures::capsule(0.5, 1.0), tetra, climbing, over, large})
        prefetch(s);
    // Overlapping tetrahedra: the view with adjacency (prefetched with it) and the one
    // without give the same answer.
    const PairResult with = query_pair(climbing, at(0, 0, 0), climbing, at(1.5, 0, 0),
                                       QueryKind::PENETRATION);
    const PairResult without =
        query_pair(tetra, at(0, 0, 0), tetra, at(1.5, 0, 0), QueryKind::PENETRATION);
    CHECK(with.status == Status::CONVERGED);
    CHECK(with.depth > 0.0);
    CHECK(with.depth == without.depth);
    CHECK(with.normal.x == without.normal.x);
}

TEST_CASE("shapes: the joint scan of two polytopes is two scans, bit for bit") {
    // Sizes on both sides of each other (the shared loop and either tail), vertices with
    // repeats (ties go to the first), and directions with NaN (no product wins: index 0).
    fixtures::Uniform uniform{777};  // in [-1, 1)
    const int sizes[] = {1, 2, 5, 16, 17, 31, 32};
    int pairs = 0;
    for (int na : sizes) {
        for (int nb : sizes) {
            std::vector<Vec3> va(static_cast<size_t>(na)), vb(static_cast<size_t>(nb));
            for (Vec3& p : va) p = Vec3{uniform(), uniform(), uniform()};
            for (Vec3& p : vb) p = Vec3{uniform(), uniform(), uniform()};
            if (na > 3) va[static_cast<size_t>(na - 1)] = va[1];  // a tie
            if (nb > 3) vb[static_cast<size_t>(nb - 2)] = vb[0];
            const ShapeView a = fixtures::polytope(va), b = fixtures::polytope(vb);
            CHECK(scans(a));
            CHECK(scans(b));
            for (int k = 0; k < 20; ++k) {
                Vec3 da{uniform(), uniform(), uniform()}, db{uniform(), uniform(), uniform()};
                if (k == 0) da = va[na > 3 ? 1 : 0];  // towards the repeated vertex
                if (k == 1) db = Vec3{std::nan(""), 0.0, 1.0};
                int ia = -1, ib = -1;
                climb::scan_pair(a.vertices, na, da, b.vertices, nb, db, ia, ib);
                CHECK(ia == support_core(a, da).index);
                CHECK(ib == support_core(b, db).index);
                ++pairs;
            }
            // The Minkowski difference's support through the joint scan.
            const Pose pb = fixtures::turned_about_z(0.7, 0.3, -0.2, 0.1);
            MinkowskiDifference md(a, at(0, 0, 0), b, pb, false);
            CHECK(md.scan_both);
            const Vec3 d{uniform(), uniform(), uniform()};
            const SimplexVertex w = md.support(d);
            const SupportPoint sa = support_core(a, d);
            const SupportPoint sb = support_core(b, pb.rotation.transpose_times(-d));
            CHECK(w.index_a == sa.index);
            CHECK(w.index_b == sb.index);
            CHECK(w.a.x == sa.point.x);
            CHECK(w.b.y == (pb.rotation * sb.point + pb.translation).y);
        }
    }
    CHECK(pairs == 7 * 7 * 20);
    // A box does not scan: the pair keeps the general path.
    std::vector<Vec3> one = {{0, 0, 0}};
    MinkowskiDifference mixed(fixtures::box(1, 1, 1), at(0, 0, 0), fixtures::polytope(one),
                              at(3, 0, 0), false);
    CHECK(!mixed.scan_both);
}

TEST_CASE("shapes: climbs over fixed-stride lists are the CSR climbs, bit for bit") {
    // Hulls of points on ellipsoids (every point on the hull) of sizes on both sides of the
    // climbing threshold, of the neighbour prefetch's and of the 8-bit lists'
    // (kNarrowClimbVertices), so that the joint climbs below pair 8-bit with 16-bit lists
    // both ways round and 16-bit with 16-bit, and a cloud.
    fixtures::Uniform uniform{4242};
    const int sizes[] = {24, 40, 64, 150, 256, 300, 700, 120};
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets = {0};
    for (int n : sizes) {
        for (int i = 0; i < n; ++i) {
            Vec3 p{uniform(), uniform(), uniform()};
            const double r = norm(p);
            points.push_back(Vec3{p.x / r, 0.6 * p.y / r, 0.3 * p.z / r});
        }
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    }
    for (int i = 0; i < 100; ++i) points.push_back(Vec3{uniform(), uniform(), uniform()});
    offsets.push_back(static_cast<std::int64_t>(points.size()));
    const long long count = static_cast<long long>(offsets.size()) - 1;
    const PackedPolytopes packed = pack_polytopes(points.data(), offsets.data(), count, 1);
    fixtures::PolytopeSet csr(packed), listed(packed);
    const ClimbLists lists(listed.view, 1);
    lists.attach(listed.view);
    std::int64_t climbing = 0;
    for (long long h = 0; h < count; ++h) {
        const ShapeView a = csr.view.shape(h), b = listed.view.shape(h);
        CHECK(a.climb_lists == nullptr);
        CHECK((b.climb_lists != nullptr) == climbs(a));
        if (!climbs(a)) continue;
        climbing += a.vertex_count * climb_rows(a.vertex_count);
        for (int k = 0; k < 40; ++k) {
            const Vec3 d{uniform(), uniform(), uniform()};
            const int hint = k % 3 == 0 ? -1 : (k * 7) % a.vertex_count;
            const SupportPoint x = support_core(a, d, hint), y = support_core(b, d, hint);
            CHECK(x.index == y.index);
            CHECK(fixtures::same_bytes(&x.point, &y.point, 1));
        }
    }
    CHECK(lists.size() == climbing);
    CHECK(climbing >= 40 + 64 + 150 + 256 + 2 * (300 + 700) + 120);
    // Pairs through the Minkowski difference's joint climbs (over the lists; without them,
    // each shape's own climb): the same answers.
    for (long long h = 1; h + 1 < count; ++h) {
        const Pose pb = fixtures::turned_about_z(0.4 * h, 0.5, 0.2, -0.1);
        const ShapeView la = listed.view.shape(h), lb = listed.view.shape(h + 1);
        const ShapeView ca = csr.view.shape(h), cb = csr.view.shape(h + 1);
        CHECK(MinkowskiDifference(la, at(0, 0, 0), lb, pb, false).climb_lists_both ==
              (climbs(la) && climbs(lb)));
        CHECK(!MinkowskiDifference(ca, at(0, 0, 0), cb, pb, false).climb_lists_both);
        for (QueryKind kind : {QueryKind::PENETRATION, QueryKind::DISTANCE}) {
            const PairResult x = query_pair(csr.view.shape(h), at(0, 0, 0), csr.view.shape(h + 1),
                                            pb, kind);
            const PairResult y = query_pair(listed.view.shape(h), at(0, 0, 0),
                                            listed.view.shape(h + 1), pb, kind);
            CHECK(x.status == y.status);
            CHECK(fixtures::same_bytes(&x.depth, &y.depth, 1));
            CHECK(fixtures::same_bytes(&x.distance, &y.distance, 1));
            CHECK(fixtures::same_bytes(&x.normal, &y.normal, 1));
            CHECK(fixtures::same_bytes(&x.point_a, &y.point_a, 1));
        }
    }
}

TEST_CASE("shapes: a list too long for a fixed-stride record leaves its shape on CSR") {
    // Two rings that climb; the second's vertex 3 has 16 neighbours (more than
    // kClimbListSlots): it keeps no lists, the first keeps its own, and both climb alike.
    const int n = defaults::hill_climbing_min_vertices + 8;
    std::vector<double> vertices;
    std::vector<std::int64_t> adjacency_offsets = {0};
    std::vector<std::int32_t> adjacency;
    for (int shape = 0; shape < 2; ++shape)
        for (int i = 0; i < n; ++i) {
            vertices.insert(vertices.end(), {std::cos(0.1 * i), std::sin(0.1 * i), 0.01 * i});
            const int entries = shape == 1 && i == 3 ? 16 : 4;
            for (int k = 0; k < entries; ++k) adjacency.push_back((i + k % 4 + 1) % n);
            adjacency_offsets.push_back(static_cast<std::int64_t>(adjacency.size()));
        }
    const std::vector<std::int64_t> offsets = {0, n, 2 * n};
    const std::vector<std::int8_t> kinds = {0, 0};
    const std::vector<double> params(8, 0.0);
    ConvexSetView set = fixtures::convex_set(offsets.data(), kinds.data(), params.data(), 2,
                                             &vertices);
    set.adjacency_offsets = adjacency_offsets.data();
    set.adjacency = adjacency.data();
    std::vector<ClimbList> out(static_cast<size_t>(n));
    CHECK(make_climb_lists(set.shape(0), out.data()));
    CHECK(!make_climb_lists(set.shape(1), out.data()));
    const ClimbLists lists(set, 1);
    CHECK(lists.size() == n);
    ConvexSetView listed = set;
    lists.attach(listed);
    CHECK(listed.shape(0).climb_lists != nullptr);
    CHECK(listed.shape(1).climb_lists == nullptr);
    CHECK(listed.shape(0).climb_lists[5].count == 4);
    CHECK(listed.shape(0).climb_lists[5].neighbours[0] == 6);
    fixtures::Uniform uniform{99};
    for (int k = 0; k < 30; ++k) {
        const Vec3 d{uniform(), uniform(), uniform()};
        CHECK(support_core(set.shape(0), d, k % n).index ==
              support_core(listed.shape(0), d, k % n).index);
    }
}

namespace {

// Two 64-point ellipsoid hulls (every point on the hull, as the benchmark's smooth family)
// with their hull adjacency, so that both climb: the deep start's case.
struct SmoothPair {
    PackedPolytopes packed;
    ShapeView a, b;

    // `n` points a shape; `jitter`: each lattice point moved by up to this many times its
    // spacing along z and around, by a fixed pseudo-random amount (0: the regular lattice).
    explicit SmoothPair(int n = 64, double jitter = 0.0) {
        std::vector<Vec3> points;
        const auto noise = [](int i) {  // in [-0.5, 0.5)
            const double x = std::sin(12.9898 * i + 78.233) * 43758.5453;
            return x - std::floor(x) - 0.5;
        };
        for (int s = 0; s < 2; ++s) {
            const Vec3 axes = s == 0 ? Vec3{1.2, 0.9, 0.75} : Vec3{0.8, 1.1, 1.3};
            for (int i = 0; i < n; ++i) {
                // A Fibonacci lattice on the unit sphere, stretched.
                const double step = 2.0 * i + 1.0 + 2.0 * jitter * noise(2 * i + 200 * s);
                const double z = std::fmax(-1.0, std::fmin(1.0, 1.0 - step / n));
                const double r = std::sqrt(1.0 - z * z);
                const double t = 2.399963229728653 * i + s + jitter * noise(2 * i + 1 + 200 * s);
                points.push_back({axes.x * r * std::cos(t), axes.y * r * std::sin(t), axes.z * z});
            }
        }
        const std::int64_t offsets[3] = {0, n, 2 * n};
        packed = pack_polytopes(points.data(), offsets, 2, 1);
        a = view(0);
        b = view(1);
    }

    ShapeView view(int h) const {
        ShapeView v;
        v.kind = ShapeKind::POLYTOPE;
        v.vertices = reinterpret_cast<const Vec3*>(packed.vertices.data()) + packed.offsets[h];
        v.vertex_count = static_cast<int>(packed.offsets[h + 1] - packed.offsets[h]);
        v.adjacency_offsets = packed.adjacency_offsets.data() + packed.offsets[h];
        v.adjacency = packed.adjacency.data();
        return v;
    }
};

}  // namespace

TEST_CASE("epa: the deep start gives the depth that GJK's simplex gives") {
    const SmoothPair pair;
    REQUIRE(climbs(pair.a) && climbs(pair.b));
    int deep = 0;
    for (int k = 0; k < 24; ++k) {
        // b turned and moved around a, 0.6 to 1.7 apart: from deep to barely overlapping.
        const Pose pose_b = fixtures::turned_about_z(0.7 * k, 0.6 + 0.05 * k,
                                                     0.3 * std::sin(1.3 * k), 0.2 * std::cos(k));
        MinkowskiDifference md(pair.a, at(0, 0, 0), pair.b, pose_b, false);
        const SimplexVertex first = md.support(md.translation_b);
        const EpaResult started = epa_penetration_deep(md, first);
        MinkowskiDifference plain(pair.a, at(0, 0, 0), pair.b, pose_b, false);
        const GjkResult g = gjk_run(plain, GjkOptions{});
        REQUIRE(g.overlap);
        const EpaResult reference = epa_penetration(plain, g.simplex);
        REQUIRE(reference.status == Status::CONVERGED);
        if (started.status == Status::NOT_RUN) continue;
        ++deep;
        CHECK(started.status == Status::CONVERGED);
        // The same face of a - b, found from another polytope: equal to rounding.
        CHECK_NEAR(started.depth, reference.depth, 1e-14 * reference.depth);
        CHECK(dot(started.normal, reference.normal) >= 1.0 - 1e-14);
        CHECK_NEAR(norm(started.point_a - started.point_b), started.depth, 1e-13);
    }
    // Most of these pairs are deep enough to start there.
    CHECK(deep >= 12);
}

TEST_CASE("epa: the deep start's octahedron and the tetrahedron it falls back to agree with GJK") {
    // The deep start begins from the octahedron of its six supports when that is their hull,
    // else from a tetrahedron of them with the other two ring points added (on coarse hulls
    // two ring points are often one vertex). 300 poses of b, turned about two axes and moved
    // around a, from deep to barely overlapping, on irregular 32-point hulls: when this test
    // was written, 282 started deep, 38 of them from the tetrahedron (a print in
    // `epa_penetration_deep` showed it). Every deep start must give GJK and EPA's depth.
    const SmoothPair pair(32, 0.9);
    int deep = 0;
    for (int k = 0; k < 300; ++k) {
        const double apart = 0.5 + 1.3 * (0.618034 * k - std::floor(0.618034 * k));
        const double up = std::sin(0.7 * k), around = 0.37 * k;
        const double flat = std::sqrt(1.0 - up * up);
        Pose pose_b = fixtures::turned_about_z(0.29 * k, apart * flat * std::cos(around),
                                               apart * flat * std::sin(around), apart * up);
        const double c = std::cos(0.53 * k), s = std::sin(0.53 * k);
        Mat3 tilt;  // about x
        tilt.m[1][1] = c;
        tilt.m[1][2] = -s;
        tilt.m[2][1] = s;
        tilt.m[2][2] = c;
        pose_b.rotation = pose_b.rotation * tilt;
        MinkowskiDifference md(pair.a, at(0, 0, 0), pair.b, pose_b, false);
        const SimplexVertex first = md.support(md.translation_b);
        const EpaResult started = epa_penetration_deep(md, first);
        if (started.status == Status::NOT_RUN) continue;
        ++deep;
        MinkowskiDifference plain(pair.a, at(0, 0, 0), pair.b, pose_b, false);
        const GjkResult g = gjk_run(plain, GjkOptions{});
        REQUIRE(g.overlap);
        const EpaResult reference = epa_penetration(plain, g.simplex);
        REQUIRE(reference.status == Status::CONVERGED);
        CHECK(started.status == Status::CONVERGED);
        CHECK_NEAR(started.depth, reference.depth, 1e-14 * reference.depth);
        CHECK(dot(started.normal, reference.normal) >= 1.0 - 1e-14);
        CHECK_NEAR(norm(started.point_a - started.point_b), started.depth, 1e-13);
    }
    CHECK(deep >= 150);
}

TEST_CASE("epa: the deep start leaves touching and separated pairs to GJK, untouched") {
    const SmoothPair pair;
    // The same shapes without adjacency scan: they never try the deep start.
    ShapeView scan_a = pair.a, scan_b = pair.b;
    scan_a.adjacency_offsets = scan_b.adjacency_offsets = nullptr;
    scan_a.adjacency = scan_b.adjacency = nullptr;
    REQUIRE(scans(scan_a) && scans(scan_b));
    for (const double x : {1.9, 2.0, 2.2, 3.5}) {
        const Pose pose_b = fixtures::turned_about_z(0.4, x, 0.1, -0.05);
        MinkowskiDifference md(pair.a, at(0, 0, 0), pair.b, pose_b, false);
        const SimplexVertex first = md.support(md.translation_b);
        CHECK(epa_penetration_deep(md, first).status == Status::NOT_RUN);
        // After a failed attempt the query goes on as GJK would have: the same answer as
        // the scanning shapes', bit for bit (the supports have no ties).
        const PairResult climbed =
            query_pair(pair.a, at(0, 0, 0), pair.b, pose_b, QueryKind::PENETRATION);
        const PairResult scanned =
            query_pair(scan_a, at(0, 0, 0), scan_b, pose_b, QueryKind::PENETRATION);
        CHECK_EQ(climbed.distance, scanned.distance);
        CHECK_EQ(climbed.depth, scanned.depth);
        CHECK_EQ(climbed.iterations, scanned.iterations);
        CHECK_EQ(climbed.normal.x, scanned.normal.x);
        CHECK_EQ(climbed.point_a.y, scanned.point_a.y);
    }
}

// The plain definition is_rigid_matrix4 shortens (every entry finite, every entry of R R^T):
// the same verdict on rigid poses, on poses perturbed about the tolerance, and with an
// infinity, a NaN or an odd value in any entry.
namespace {
bool rigid_by_definition(const double* m, double tolerance) {
    for (int i = 0; i < 16; ++i)
        if (!std::isfinite(m[i])) return false;
    if (std::fabs(m[12]) > tolerance || std::fabs(m[13]) > tolerance || std::fabs(m[14]) > tolerance ||
        std::fabs(m[15] - 1.0) > tolerance)
        return false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d = 0.0;
            for (int k = 0; k < 3; ++k) d += m[i * 4 + k] * m[j * 4 + k];
            if (std::fabs(d - (i == j ? 1.0 : 0.0)) > tolerance) return false;
        }
    const Vec3 r0{m[0], m[1], m[2]}, r1{m[4], m[5], m[6]}, r2{m[8], m[9], m[10]};
    return dot(cross(r0, r1), r2) > 0.0;
}
}  // namespace

TEST_CASE("is_rigid_matrix4: the plain definition's verdict, rigid, perturbed and broken") {
    const double tolerance = defaults::rigid_tolerance;
    const double inf = std::numeric_limits<double>::infinity();
    const double specials[] = {0.0, -0.0, 1.0, -1.0, tolerance, -tolerance, 1.0 + 0.5 * tolerance,
                               1.0 - 2.0 * tolerance, 1e300, -1e300, inf, -inf,
                               std::numeric_limits<double>::quiet_NaN(), 1e-300};
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::normal_distribution<double> normal;
    int rigid = 0, not_rigid = 0;
    for (int n = 0; n < 200000; ++n) {
        // a random rotation (unit quaternion) and translation
        double q[4], length = 0.0;
        for (double& x : q) {
            x = normal(rng);
            length += x * x;
        }
        length = std::sqrt(length);
        for (double& x : q) x /= length;
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        double m[16] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y), 3.0 * unit(rng),
                        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x), 3.0 * unit(rng),
                        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y), 3.0 * unit(rng),
                        0.0, 0.0, 0.0, 1.0};
        switch (n % 6) {
            case 0: break;
            case 1: m[rng() % 16] += 2.0 * tolerance * unit(rng); break;
            case 2: for (double& v : m) v += tolerance * unit(rng); break;
            case 3: m[rng() % 16] = specials[rng() % std::size(specials)]; break;
            case 4:
                for (double& v : m)
                    if (rng() % 5 == 0) v = specials[rng() % std::size(specials)];
                break;
            default:  // a reflection
                for (int k = 0; k < 3; ++k) m[4 + k] = -m[4 + k];
        }
        const bool expected = rigid_by_definition(m, tolerance);
        CHECK_EQ(is_rigid_matrix4(m, tolerance), expected);
        (expected ? rigid : not_rigid) += 1;
    }
    CHECK(rigid > 50000);
    CHECK(not_rigid > 50000);
}
