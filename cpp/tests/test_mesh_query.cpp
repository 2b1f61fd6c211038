// Mesh hierarchies and mesh-pair queries (mesh_bvh.hpp, mesh_query.hpp) on boxes whose
// distances, crossings, containment and depths are known.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/orientation.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"

using namespace meshcol;
using fixtures::at;

namespace {

MeshDistanceInput pair_of(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b) {
    MeshDistanceInput in;
    in.a = &a;
    in.b = &b;
    in.pose_a = pose_a;
    in.pose_b = pose_b;
    return in;
}

// The unit cube about the origin.
fixtures::TriangleMesh unit_cube() { return fixtures::box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}); }

}  // namespace

TEST_CASE("mesh bvh: a box mesh builds a valid, closed hierarchy") {
    const MeshBvh cube = unit_cube().bvh();
    REQUIRE(cube.valid());
    CHECK(cube.closed());
    CHECK(cube.validate());
    CHECK_EQ(cube.triangle_count(), 12);
    CHECK_EQ(cube.vertices().size(), size_t{8});

    fixtures::TriangleMesh open = unit_cube();
    open.faces.resize(open.faces.size() - 6);  // drop the x = hi face: a hole
    CHECK(!open.bvh().closed());

    fixtures::TriangleMesh broken = unit_cube();
    broken.vertices[4] = std::numeric_limits<double>::quiet_NaN();
    CHECK(!broken.bvh().valid());
}

namespace {

bool same_bits(double a, double b) {
    std::uint64_t x, y;
    std::memcpy(&x, &a, sizeof(x));
    std::memcpy(&y, &b, sizeof(y));
    return x == y;
}
bool same_bits(const Vec3& a, const Vec3& b) { return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z); }

}  // namespace

TEST_CASE("mesh bvh: oriented boxes and capsules are the all-corner and segment routines' bits") {
    // A bumpy sheet with coordinates of +0 and -0 (a projection's ties), some heights exactly
    // zero, and a few degenerate triangles (a repeated corner, three collinear corners).
    std::mt19937 rng(20);
    std::uniform_real_distribution<double> bump(-0.05, 0.05);
    fixtures::TriangleMesh sheet;
    const int side = 24;
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
            const double x = i == side / 2 ? (j % 2 ? -0.0 : 0.0) : (i - side / 2) * 0.1;
            const double y = j == side / 2 ? (i % 2 ? 0.0 : -0.0) : (j - side / 2) * 0.1;
            const double z = (i + j) % 5 == 0 ? ((i + j) % 2 ? -0.0 : 0.0) : bump(rng);
            sheet.vertices.insert(sheet.vertices.end(), {x, y, z});
        }
    for (int j = 0; j + 1 < side; ++j)
        for (int i = 0; i + 1 < side; ++i) {
            const std::int64_t v = j * side + i;
            sheet.faces.insert(sheet.faces.end(), {v, v + 1, v + side + 1, v, v + side + 1, v + side});
        }
    sheet.faces.insert(sheet.faces.end(), {0, 0, 1, 0, 1, 2});
    const MeshBvh mesh = sheet.bvh();
    REQUIRE(mesh.validate());

    // Each capsule: its spine the first longest edge, its radius (bits) and sliver flag from
    // segment_closest_points' distance of the opposite corner.
    for (std::int32_t i = 0; i < mesh.triangle_count(); ++i) {
        const Vec3* t = mesh.triangle(i);
        const TriangleCapsule& capsule = mesh.triangle_capsule(i);
        const std::int32_t e = capsule.edge;
        const double spine = squared_norm(t[(e + 1) % 3] - t[e]);
        for (std::int32_t k = 0; k < 3; ++k)
            CHECK(k < e ? squared_norm(t[(k + 1) % 3] - t[k]) < spine : squared_norm(t[(k + 1) % 3] - t[k]) <= spine);
        const Vec3& apex = t[(e + 2) % 3];
        const double h2 = segment_closest_points(apex, apex, t[e], t[(e + 1) % 3]).squared_distance;
        CHECK(same_bits(capsule.radius, std::sqrt(h2) * (1.0 + 1e-12)));
        CHECK_EQ(capsule.thin, 16.0 * h2 < spine);
    }

    // Each turned box: its extents are those of every corner of its node (in leaf order, the
    // first of equal values kept), not only of the distinct vertices the build projects.
    const std::vector<BvhNode>& nodes = mesh.nodes();
    std::int32_t turned = 0;
    for (size_t id = 0; id < nodes.size(); ++id) {
        const NodeObb& box = mesh.obbs()[id];
        if (box.axis_aligned) continue;
        ++turned;
        size_t first = id, last = id;
        while (!nodes[first].is_leaf()) ++first;
        while (!nodes[last].is_leaf()) last = static_cast<size_t>(nodes[last].index);
        const double inf = std::numeric_limits<double>::infinity();
        Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf}, low = lo, high = hi;
        for (std::int32_t i = nodes[first].index; i < nodes[last].index + nodes[last].count; ++i)
            for (int k = 0; k < 3; ++k) {
                const Vec3& c = mesh.triangle(i)[k];
                const Vec3 p = box.axes * c;
                for (int a = 0; a < 3; ++a) {
                    lo[a] = c[a] < lo[a] ? c[a] : lo[a];
                    hi[a] = c[a] > hi[a] ? c[a] : hi[a];
                    low[a] = p[a] < low[a] ? p[a] : low[a];
                    high[a] = p[a] > high[a] ? p[a] : high[a];
                }
            }
        const double pad = 1e-12 * std::fmax(max_abs(lo), max_abs(hi)) + 1e-300;
        CHECK(same_bits(box.half, (high * 0.5 - low * 0.5) + Vec3{pad, pad, pad}));
        CHECK(same_bits(box.center, box.axes.transpose_times(low * 0.5 + high * 0.5)));
    }
    CHECK(turned > 100);
}

TEST_CASE("mesh query: boxes one apart, rotated or not") {
    const MeshBvh cube = unit_cube().bvh();
    const MeshDistanceOutput r = mesh_distance(pair_of(cube, at(0, 0, 0), cube, at(2, 0.3, -0.1)));
    REQUIRE(r.status == Status::CONVERGED);
    CHECK_NEAR(r.distance, 1.0, 1e-12);
    CHECK(!r.intersecting);
    CHECK(!r.a_inside_b && !r.b_inside_a);
    CHECK_NEAR(r.point_a.x, 0.5, 1e-12);
    CHECK_NEAR(r.point_b.x, 1.5, 1e-12);
    CHECK(r.triangle_a >= 0 && r.triangle_b >= 0);

    // b turned 45 degrees about z: its vertical edge is sqrt(1/2) from its centre
    const double reach = std::sqrt(0.5);
    const MeshDistanceOutput turned = mesh_distance(
        pair_of(cube, at(0, 0, 0), cube, fixtures::turned_about_z(std::acos(-1.0) / 4, 0.5 + reach + 0.75, 0, 0)));
    CHECK_NEAR(turned.distance, 0.75, 1e-12);
    CHECK(!mesh_intersects(cube, at(0, 0, 0), cube, at(2, 0, 0)));
}

TEST_CASE("mesh query: crossing boxes intersect; a box sunk into a face has that depth") {
    const MeshBvh cube = unit_cube().bvh();
    const Pose b = at(0.8, 0.1, 0.05);  // overlap 0.2 along x
    CHECK(mesh_intersects(cube, at(0, 0, 0), cube, b));
    const MeshDistanceOutput d = mesh_distance(pair_of(cube, at(0, 0, 0), cube, b));
    CHECK(d.intersecting);
    CHECK_EQ(d.distance, 0.0);
    const MeshDepthOutput crossing = mesh_penetration_depth(pair_of(cube, at(0, 0, 0), cube, b));
    REQUIRE(crossing.status == Status::CONVERGED);
    CHECK(crossing.depth > 0.0 && crossing.depth <= 0.2 + 1e-12);  // a lower bound of 0.2

    // the unit cube sunk 0.2 into the x = 2 face of a box of side 4: depth exactly 0.2, b
    // (the cube) leaves along +x
    const MeshBvh floor = fixtures::box_mesh({-2, -2, -2}, {2, 2, 2}).bvh();
    const MeshDepthOutput sunk = mesh_penetration_depth(pair_of(floor, at(0, 0, 0), cube, at(2.3, 0, 0)));
    REQUIRE(sunk.status == Status::CONVERGED);
    CHECK_NEAR(sunk.depth, 0.2, 1e-12);
    CHECK_NEAR(sunk.normal.x, 1.0, 1e-12);

    // touching faces: intersecting, depth 0 (a resting contact)
    const MeshDepthOutput resting = mesh_penetration_depth(pair_of(cube, at(0, 0, 0), cube, at(1, 0, 0)));
    CHECK(mesh_intersects(cube, at(0, 0, 0), cube, at(1, 0, 0)));
    CHECK_EQ(resting.depth, 0.0);
}

TEST_CASE("mesh query: a box inside a box is contained, with the depth of its deepest vertex") {
    const MeshBvh big = fixtures::box_mesh({-2, -2, -2}, {2, 2, 2}).bvh();
    const MeshBvh small = unit_cube().bvh();
    const MeshDistanceOutput r = mesh_distance(pair_of(small, at(0.5, 0, 0), big, at(0, 0, 0)));
    REQUIRE(r.status == Status::CONVERGED);
    CHECK(!r.intersecting);
    CHECK(r.a_inside_b);
    CHECK(!r.b_inside_a);
    CHECK_NEAR(r.distance, 1.0, 1e-12);  // small's x = 1 face to big's x = 2 face
    // depth: the small box's vertex farthest from big's surface, (0, +-0.5, +-0.5): 1.5 away
    const MeshDepthOutput depth = mesh_penetration_depth(pair_of(small, at(0.5, 0, 0), big, at(0, 0, 0)));
    CHECK_NEAR(depth.depth, 1.5, 1e-12);
    CHECK_EQ(depth.deepest_mesh, 0);
}

TEST_CASE("mesh query: winding numbers and closest points of a box") {
    const MeshBvh cube = unit_cube().bvh();
    CHECK_NEAR(winding_number(cube, {0.1, 0.2, -0.3}), 1.0, 1e-12);
    CHECK_NEAR(winding_number(cube, {3.0, 0.0, 0.0}), 0.0, 1e-12);
    CHECK(winding_number_inside(cube, {0.4, 0.4, 0.4}));
    CHECK(!winding_number_inside(cube, {0.6, 0.0, 0.0}));
    const WindingEstimate far = fast_winding_number(cube, {30.0, 1.0, 2.0}, 1e-6);
    CHECK(std::fabs(far.value) <= 1e-6 + far.error);
    const PointDistanceOutput c = closest_point(cube, {2.0, 0.1, 0.2});
    CHECK_NEAR(c.distance, 1.5, 1e-12);
    CHECK_NEAR(c.point.x, 0.5, 1e-12);
    CHECK(c.triangle >= 10);  // the x = hi face is triangles 10 and 11
}

TEST_CASE("mesh query: lengths out of range are refused, not guessed") {
    const MeshBvh cube = unit_cube().bvh();
    CHECK(mesh_pair_in_range(cube, at(0, 0, 0), cube, at(2, 0, 0)));
    CHECK(!mesh_pair_in_range(cube, at(0, 0, 0), cube, at(1e40, 0, 0)));
    const MeshDistanceOutput r = mesh_distance(pair_of(cube, at(0, 0, 0), cube, at(1e40, 0, 0)));
    CHECK(r.status == Status::OUT_OF_RANGE);
}

namespace {

// A closed tube about z of `sides` sides, radius r, from z = 0 to z = length, one ring of
// long side triangles (slivers when length >> r / sides) and fan caps.
fixtures::TriangleMesh tube(int sides, double r, double length) {
    fixtures::TriangleMesh m;
    const double kTwoPi = 6.283185307179586;
    for (int ring = 0; ring < 2; ++ring)
        for (int k = 0; k < sides; ++k)
            m.vertices.insert(m.vertices.end(), {r * std::cos(kTwoPi * k / sides), r * std::sin(kTwoPi * k / sides),
                                                 ring * length});
    const std::int64_t bottom = 2 * sides, top = 2 * sides + 1;
    m.vertices.insert(m.vertices.end(), {0.0, 0.0, 0.0, 0.0, 0.0, length});
    for (std::int64_t k = 0; k < sides; ++k) {
        const std::int64_t k1 = (k + 1) % sides;
        m.faces.insert(m.faces.end(), {k, k1, sides + k1, k, sides + k1, sides + k});
        m.faces.insert(m.faces.end(), {bottom, k1, k, top, sides + k, sides + k1});
    }
    return m;
}

// A rotation from four numbers in [-1, 1] (a quaternion, normalised).
Pose posed(double qw, double qx, double qy, double qz, const Vec3& t) {
    const double n = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
    qw /= n, qx /= n, qy /= n, qz /= n;
    Pose p;
    p.rotation.m[0][0] = 1 - 2 * (qy * qy + qz * qz), p.rotation.m[0][1] = 2 * (qx * qy - qz * qw),
    p.rotation.m[0][2] = 2 * (qx * qz + qy * qw);
    p.rotation.m[1][0] = 2 * (qx * qy + qz * qw), p.rotation.m[1][1] = 1 - 2 * (qx * qx + qz * qz),
    p.rotation.m[1][2] = 2 * (qy * qz - qx * qw);
    p.rotation.m[2][0] = 2 * (qx * qz - qy * qw), p.rotation.m[2][1] = 2 * (qy * qz + qx * qw),
    p.rotation.m[2][2] = 1 - 2 * (qx * qx + qy * qy);
    p.translation = t;
    return p;
}

}  // namespace

TEST_CASE("mesh query: the pruned distance search returns the brute-force minimum bit for bit") {
    // Slivers (the tube's sides are 40 times longer than wide) are where the capsule bound
    // prunes: every bound of the search must only drop triangle pairs that could not win, so
    // its distance is exactly the smallest of the same triangle-pair distances over all pairs,
    // measured in a's frame with b mapped there as the search maps it.
    const fixtures::TriangleMesh thin = tube(24, 0.05, 0.5);
    const MeshBvh mesh = thin.bvh();
    REQUIRE(mesh.validate());
    fixtures::Uniform uniform{12345};  // in [-1, 1)
    int disjoint = 0;
    for (int trial = 0; trial < 60; ++trial) {
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {uniform() * 0.1, 0.0, 0.0});
        // near (a few thousandths of the length apart) to well apart
        const double gap = trial % 3 == 0 ? 0.4 : 0.11 + 0.01 * std::fabs(uniform());
        const Pose pb = posed(uniform(), uniform(), uniform(), uniform(), {gap, uniform() * 0.05, 0.25 * uniform()});
        const MeshDistanceOutput r = mesh_distance(pair_of(mesh, pa, mesh, pb));
        REQUIRE(r.status == Status::CONVERGED);
        if (r.intersecting) continue;
        ++disjoint;
        const mesh_detail::Relative rel(pa, pb, mesh, mesh);
        double best = std::numeric_limits<double>::infinity();
        for (std::int32_t i = 0; i < mesh.triangle_count(); ++i)
            for (std::int32_t j = 0; j < mesh.triangle_count(); ++j) {
                const Vec3 tb[3] = {rel.apply(mesh.triangle(j)[0]), rel.apply(mesh.triangle(j)[1]),
                                    rel.apply(mesh.triangle(j)[2])};
                best = std::fmin(best, triangle_separated_squared_distance(mesh.triangle(i), tb, nullptr, nullptr));
            }
        CHECK_EQ(r.distance, std::sqrt(best));
    }
    CHECK(disjoint >= 30);
}

TEST_CASE("mesh query: the best pair's axis drops only pairs that cannot win, ties included") {
    // Tubes end to end, cap facing cap: the fan caps put 24 triangles around one vertex and the
    // caps are parallel planes when the tubes are aligned, so many triangle pairs tie at (or
    // come within rounding of) the distance, and the separating-axis bound along the best
    // pair's direction, taken in the middle of the search, sits at the distance for them. The
    // search must still return the smallest triangle-pair distance bit for bit, and the
    // triangles it reports must be at that distance.
    const fixtures::TriangleMesh m = tube(24, 0.05, 0.5);
    const MeshBvh mesh = m.bvh();
    REQUIRE(mesh.validate());
    std::vector<std::int32_t> leaf_of(static_cast<size_t>(mesh.triangle_count()));
    for (std::int32_t i = 0; i < mesh.triangle_count(); ++i) leaf_of[static_cast<size_t>(mesh.face_index(i))] = i;
    fixtures::Uniform uniform{99};  // in [-1, 1)
    for (int trial = 0; trial < 24; ++trial) {
        // Aligned (parallel caps, exact ties), slightly tilted, or turned about the axis.
        const double tilt = trial % 3 == 0 ? 0.0 : 0.02 * uniform();
        const double gap = 0.01 + 0.5 * std::fabs(uniform());
        const Pose pa = posed(1.0, 0.0, 0.0, trial % 2 ? 0.3 * uniform() : 0.0, {0.0, 0.0, 0.0});
        const Pose pb = posed(1.0, tilt, 0.0, trial % 2 ? 0.0 : 0.3 * uniform(),
                              {trial % 4 == 1 ? 0.01 : 0.0, 0.0, 0.5 + gap});
        const MeshDistanceOutput r = mesh_distance(pair_of(mesh, pa, mesh, pb));
        REQUIRE(r.status == Status::CONVERGED);
        REQUIRE(!r.intersecting);
        const mesh_detail::Relative rel(pa, pb, mesh, mesh);
        const auto pair_distance2 = [&](std::int32_t i, std::int32_t j) {
            const Vec3 tb[3] = {rel.apply(mesh.triangle(j)[0]), rel.apply(mesh.triangle(j)[1]),
                                rel.apply(mesh.triangle(j)[2])};
            return triangle_separated_squared_distance(mesh.triangle(i), tb, nullptr, nullptr);
        };
        double best = std::numeric_limits<double>::infinity();
        for (std::int32_t i = 0; i < mesh.triangle_count(); ++i)
            for (std::int32_t j = 0; j < mesh.triangle_count(); ++j) best = std::fmin(best, pair_distance2(i, j));
        CHECK_EQ(r.distance, std::sqrt(best));
        REQUIRE(r.triangle_a >= 0);
        REQUIRE(r.triangle_b >= 0);
        const std::int32_t ia = leaf_of[static_cast<size_t>(r.triangle_a)];
        const std::int32_t ib = leaf_of[static_cast<size_t>(r.triangle_b)];
        CHECK_EQ(pair_distance2(ia, ib), best);
    }
}

namespace {

// Appends mesh `part` to `whole` (a triangle soup: the distance queries need no closed mesh).
void append(fixtures::TriangleMesh& whole, const fixtures::TriangleMesh& part) {
    const auto base = static_cast<std::int64_t>(whole.vertices.size() / 3);
    whole.vertices.insert(whole.vertices.end(), part.vertices.begin(), part.vertices.end());
    for (const std::int64_t f : part.faces) whole.faces.push_back(base + f);
}

// A tray of three boxes, a floor between two low rims (the closest points of a mesh lying
// just over it are often on the floor, off the hull), and a flat 12 x 12 grid of 288
// coplanar triangles on a box (hundreds of triangles on one supporting plane).
fixtures::TriangleMesh tray() {
    fixtures::TriangleMesh m = fixtures::box_mesh({-0.5, -0.3, 0.0}, {0.5, 0.3, 0.1});
    append(m, fixtures::box_mesh({-0.5, -0.3, 0.1}, {-0.35, 0.3, 0.16}));
    append(m, fixtures::box_mesh({0.35, -0.3, 0.1}, {0.5, 0.3, 0.16}));
    return m;
}

// A tetrahedron whose apex (the origin) points down -z.
fixtures::TriangleMesh spike() {
    fixtures::TriangleMesh m;
    m.vertices = {0.0, 0.0, 0.0, 0.1, 0.0, 0.1, -0.05, 0.08, 0.1, -0.05, -0.08, 0.1};
    m.faces = {0, 2, 1, 0, 3, 2, 0, 1, 3, 1, 2, 3};
    return m;
}

fixtures::TriangleMesh gridded_slab() {
    fixtures::TriangleMesh m = fixtures::box_mesh({-0.3, -0.3, -0.1}, {0.3, 0.3, 0.0});
    const int n = 12;
    const auto base = static_cast<std::int64_t>(m.vertices.size() / 3);
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) m.vertices.insert(m.vertices.end(), {-0.3 + 0.6 * i / n, -0.3 + 0.6 * j / n, 0.0});
    for (std::int64_t i = 0; i < n; ++i)
        for (std::int64_t j = 0; j < n; ++j) {
            const std::int64_t c = base + i * (n + 1) + j;
            m.faces.insert(m.faces.end(), {c, c + n + 1, c + n + 2, c, c + n + 2, c + 1});
        }
    return m;
}

}  // namespace

TEST_CASE("mesh query: the hulls' supporting planes give the node-pair search's distance bit for bit") {
    // The search across the hulls (tried first on pairs whose hulls are apart) against the
    // node-pair search on the same pairs: a convex tube with fan caps (many pairs tied around
    // one vertex), a tray whose floor holds the closest points of a spike just over it (the
    // hulls' distance falls short of the meshes': no decision), and a slab with 288 coplanar
    // triangles on one face. Where it decides, the distance must be the node-pair search's bit
    // for bit, its triangles at that distance, and a max_distance below it must find nothing;
    // mesh_distance must give the same distance either way.
    const fixtures::TriangleMesh sources[4] = {tube(24, 0.05, 0.5), tray(), gridded_slab(), spike()};
    std::vector<MeshBvh> meshes;
    for (const auto& m : sources) meshes.push_back(m.bvh());
    fixtures::Uniform uniform{2024};  // in [-1, 1)
    int decided = 0, undecided = 0, tray_decided = 0, tray_refused = 0;
    for (int trial = 0; trial < 180; ++trial) {
        const MeshBvh& a = meshes[static_cast<size_t>(trial % 3)];
        // trial % 9 == 4: a is the tray, b the spike (placed over its floor below)
        const MeshBvh& b = meshes[trial % 9 == 4 ? 3 : static_cast<size_t>((trial / 3) % 3)];
        const double reach = 0.9 + 0.5 * std::fabs(uniform());  // centres 0.9-1.4 apart: near to well apart
        Vec3 dir{uniform(), uniform(), uniform()};
        dir = dir / norm(dir);
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {0.0, 0.0, 0.0});
        // Some pairs axis-aligned (exact ties between parallel faces), the rest turned.
        Pose pb = trial % 5 == 0 ? at(1.0 + 0.2 * std::fabs(uniform()), 0.0, 0.0)
                                 : posed(uniform(), uniform(), uniform(), uniform(), dir * reach);
        if (trial % 9 == 4) {
            // The spike just over the tray's rims, apex down: the hulls' distance is to the
            // hull's face over the floor, the meshes' (mostly) to the floor, off the hull.
            pb = posed(1.0, 0.1 * uniform(), 0.1 * uniform(), 0.3 * uniform(), {0.0, 0.0, 0.0});
            pb.translation = pa.apply(Vec3{0.15 * uniform(), 0.1 * uniform(), 0.165 + 0.03 * std::fabs(uniform())});
            pb.rotation = pa.rotation * pb.rotation;
        }
        const mesh_detail::Relative rel(pa, pb, a, b);
        const MeshDistanceOutput full = mesh_distance(pair_of(a, pa, b, pb));
        REQUIRE(full.status == Status::CONVERGED);
        if (full.intersecting) continue;
        const double inf = std::numeric_limits<double>::infinity();
        const mesh_detail::DisjointSearch slow = mesh_detail::distance_by_node_pairs(a, b, rel, inf);
        REQUIRE(slow.found);
        CHECK_EQ(full.distance, std::sqrt(slow.squared_distance));
        // As mesh_distance runs it (screened), and measuring every pair whose hulls are apart.
        for (const bool screen : {true, false}) {
            const mesh_detail::DisjointSearch fast = mesh_detail::distance_across_hulls(a, b, rel, inf, screen);
            const bool is_tray = &a == &meshes[1] || &b == &meshes[1];
            if (!fast.decided) {
                undecided += screen;
                tray_refused += !screen && is_tray && fast.found;  // measured, then not proven
                continue;
            }
            decided += screen;
            tray_decided += screen && is_tray;
            REQUIRE(fast.found);
            CHECK_EQ(fast.squared_distance, slow.squared_distance);
            const Vec3* source = b.triangle(fast.triangle_b);
            const Vec3 tb[3] = {rel.apply(source[0]), rel.apply(source[1]), rel.apply(source[2])};
            CHECK_EQ(triangle_separated_squared_distance(a.triangle(fast.triangle_a), tb, nullptr, nullptr),
                     fast.squared_distance);
            // max_distance: exactly the distance still finds it; below it nothing is found.
            const mesh_detail::DisjointSearch at_bound =
                mesh_detail::distance_across_hulls(a, b, rel, slow.squared_distance, screen);
            CHECK((!at_bound.decided || (at_bound.found && at_bound.squared_distance == slow.squared_distance)));
            const mesh_detail::DisjointSearch below =
                mesh_detail::distance_across_hulls(a, b, rel, 0.99 * slow.squared_distance, screen);
            CHECK((!below.decided || !below.found));
        }
        CHECK(!mesh_detail::distance_by_node_pairs(a, b, rel, 0.99 * slow.squared_distance).found);
    }
    CHECK(decided >= 60);
    CHECK(undecided >= 10);
    CHECK(tray_decided >= 5);
    // The spike over the tray's floor: its best pair at the planes is farther than the hulls'
    // distance, and the bound must refuse to decide (returning it would be a wrong distance).
    CHECK(tray_refused >= 5);
}

TEST_CASE("mesh bvh: closed means every edge pairs with one reversed twin, short lists or long") {
    fixtures::TriangleMesh flipped = unit_cube();
    std::swap(flipped.faces[1], flipped.faces[2]);  // one face wound the other way
    CHECK(!flipped.bvh().closed());
    fixtures::TriangleMesh doubled = unit_cube();
    doubled.faces.insert(doubled.faces.end(), {0, 2, 3, 3, 2, 0});  // a face and its reverse, again
    CHECK(!doubled.bvh().closed());
    // A tube of 100 sides: its cap centres have 100 out-edges each (the sorting path).
    CHECK(tube(100, 0.5, 1.0).bvh().closed());
    fixtures::TriangleMesh open_tube = tube(100, 0.5, 1.0);
    open_tube.faces.resize(open_tube.faces.size() - 3);  // one cap triangle gone
    CHECK(!open_tube.bvh().closed());
    CHECK(tube(24, 0.5, 1.0).bvh().closed());
}

namespace {

// The definition of closed_and_consistent by sorting: the directed edges (u != v), sorted, with
// no repeat, equal to the sorted reversed ones.
bool closed_by_sorting(const std::vector<std::int64_t>& faces) {
    std::vector<std::pair<std::int64_t, std::int64_t>> forward, backward;
    for (size_t f = 0; 3 * f < faces.size(); ++f)
        for (size_t k = 0; k < 3; ++k) {
            const std::int64_t u = faces[3 * f + k], v = faces[3 * f + (k + 1) % 3];
            if (u == v) continue;
            forward.push_back({u, v});
            backward.push_back({v, u});
        }
    if (forward.empty()) return false;
    std::sort(forward.begin(), forward.end());
    if (std::adjacent_find(forward.begin(), forward.end()) != forward.end()) return false;
    std::sort(backward.begin(), backward.end());
    return forward == backward;
}

}  // namespace

TEST_CASE("closed_and_consistent: the sorting definition's verdict on closed and broken meshes") {
    std::mt19937_64 random(32);
    const std::vector<fixtures::TriangleMesh> bases = {unit_cube(), tube(100, 0.5, 1.0), tube(7, 0.5, 1.0)};
    int closed = 0, not_closed = 0;
    for (int trial = 0; trial < 6000; ++trial) {
        std::vector<std::int64_t> faces;
        std::int64_t vertex_count = 0;
        if (trial % 3 == 2) {  // a small random soup, often closed (two faces back to back)
            vertex_count = 2 + static_cast<std::int64_t>(random() % 4);
            const int count = 1 + static_cast<int>(random() % 4);
            for (int f = 0; f < count; ++f) {
                std::int64_t c[3];
                for (auto& x : c) x = static_cast<std::int64_t>(random() % static_cast<std::uint64_t>(vertex_count));
                faces.insert(faces.end(), {c[0], c[1], c[2]});
                if (random() % 2) faces.insert(faces.end(), {c[0], c[2], c[1]});
            }
        } else {  // a closed mesh, then up to two changes
            const fixtures::TriangleMesh& base = bases[static_cast<size_t>(trial) % bases.size()];
            faces.assign(base.faces.begin(), base.faces.end());
            vertex_count = static_cast<std::int64_t>(base.vertices.size() / 3);
            const int changes = static_cast<int>(random() % 3);
            for (int c = 0; c < changes; ++c) {
                const size_t face_count = faces.size() / 3;
                const size_t f = static_cast<size_t>(random() % face_count);
                switch (random() % 6) {
                    case 0: std::swap(faces[3 * f + 1], faces[3 * f + 2]); break;  // wound the other way
                    case 1: faces.erase(faces.begin() + static_cast<std::ptrdiff_t>(3 * f), faces.begin() + static_cast<std::ptrdiff_t>(3 * f + 3)); break;
                    case 2: faces.insert(faces.end(), {faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]}); break;  // repeated
                    case 3: faces.insert(faces.end(), {faces[3 * f], faces[3 * f + 2], faces[3 * f + 1]}); break;  // its reverse
                    case 4: faces[3 * f + random() % 3] = static_cast<std::int64_t>(random() % static_cast<std::uint64_t>(vertex_count)); break;
                    default: {  // a degenerate face and its reverse
                        const std::int64_t u = faces[3 * f], v = faces[3 * f + 1];
                        faces.insert(faces.end(), {u, u, v, v, u, u});
                    }
                }
                if (faces.empty()) break;
            }
        }
        const bool expected = closed_by_sorting(faces);
        CHECK_EQ(closed_and_consistent(faces.data(), static_cast<std::int64_t>(faces.size() / 3), vertex_count), expected);
        // The 32-bit form (a hierarchy's compact corner indices) agrees.
        const std::vector<std::int32_t> narrow(faces.begin(), faces.end());
        CHECK_EQ(closed_and_consistent(narrow.data(), static_cast<std::int64_t>(narrow.size() / 3), vertex_count), expected);
        (expected ? closed : not_closed) += 1;
    }
    CHECK(closed > 1000);
    CHECK(not_closed > 1000);
}

TEST_CASE("triangle distance with a limit: the full distance bit for bit whenever it can count") {
    // The mesh distance search measures triangle pairs against the best distance so far
    // (triangle_separated_squared_distance_below): whenever the full 15-feature distance is at
    // most the limit, the value and both points must be the very same doubles; otherwise the
    // value must be above the limit (the search then drops the pair, as it drops the full one).
    fixtures::Uniform uniform{777};  // in [-1, 1)
    int counted = 0, skipped = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        Vec3 a[3], b[3];
        const double scale = trial % 4 == 0 ? 1e3 : 1.0;
        for (int k = 0; k < 3; ++k) a[k] = Vec3{uniform(), uniform(), uniform()} * scale;
        const Vec3 shift = Vec3{uniform(), uniform(), uniform()} * (scale * (trial % 2 == 0 ? 0.5 : 3.0));
        for (int k = 0; k < 3; ++k) b[k] = Vec3{uniform(), uniform(), uniform()} * scale + shift;
        if (trial % 5 == 1) a[2] = a[0] + (a[1] - a[0]) * 0.5 + Vec3{1e-9, 0, 0} * scale;  // a sliver
        if (trial % 5 == 2) b[1] = b[0] + (a[1] - a[0]) * 0.7 + Vec3{0, 1e-12, 0} * scale;  // nearly parallel edges
        if (trial % 7 == 3) b[2] = b[1];  // degenerate: a segment
        Vec3 fa, fb;
        const double full = triangle_separated_squared_distance(a, b, &fa, &fb);
        double largest = 0.0;
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) largest = std::fmax(largest, std::fmax(std::fabs(a[k][c]), std::fabs(b[k][c])));
        const double slack = 3e-14 * largest;  // the least the contract allows
        // limits below, at and above the full value, and far below it
        const double limits[4] = {full * (0.5 + 0.6 * std::fabs(uniform())), full, full * 1.5, full * 1e-4};
        for (const double limit : limits) {
            Vec3 pa, pb;
            const double below = triangle_separated_squared_distance_below(a, b, limit, slack, &pa, &pb);
            if (full <= limit) {
                ++counted;
                REQUIRE(below == full);
                REQUIRE((pa.x == fa.x && pa.y == fa.y && pa.z == fa.z));
                REQUIRE((pb.x == fb.x && pb.y == fb.y && pb.z == fb.z));
            } else {
                ++skipped;
                REQUIRE(below > limit);
            }
        }
    }
    CHECK(counted > 20000);
    CHECK(skipped > 20000);
}

TEST_CASE("mesh query: the ordered crossing descent gives every pair the brute-force verdict") {
    // mesh_intersects descends the deeper-overlapping child pair first: the verdict must still
    // be that of all triangle pairs (b mapped into a's frame as the queries map it), and that
    // of the distance query's crossing descent, which keeps the unordered order.
    const fixtures::TriangleMesh thin = tube(16, 0.1, 0.5);
    const MeshBvh mesh = thin.bvh();
    fixtures::Uniform uniform{4242};  // in [-1, 1)
    int crossing = 0, apart = 0;
    for (int trial = 0; trial < 120; ++trial) {
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {0.0, 0.0, 0.0});
        const double reach = 0.05 + 0.3 * std::fabs(uniform());
        const Pose pb = posed(uniform(), uniform(), uniform(), uniform(), {reach, 0.1 * uniform(), 0.1 * uniform()});
        const mesh_detail::Relative rel(pa, pb, mesh, mesh);
        bool brute = false;
        for (std::int32_t i = 0; i < mesh.triangle_count() && !brute; ++i)
            for (std::int32_t j = 0; j < mesh.triangle_count() && !brute; ++j) {
                const Vec3 tb[3] = {rel.apply(mesh.triangle(j)[0]), rel.apply(mesh.triangle(j)[1]),
                                    rel.apply(mesh.triangle(j)[2])};
                brute = triangles_intersect(mesh.triangle(i), tb, nullptr);
            }
        std::int32_t ta = -1, tb = -1;
        Vec3 witness;
        CHECK_EQ(mesh_intersects(mesh, pa, mesh, pb), brute);
        CHECK_EQ(mesh_detail::first_crossing(mesh, mesh, rel, &ta, &tb, &witness), brute);
        (brute ? crossing : apart) += 1;
    }
    CHECK(crossing >= 20);
    CHECK(apart >= 20);
}

TEST_CASE("mesh query: the descents' triangle test gives triangles_intersect's verdict") {
    // Small integer corners put many corners exactly on the other's plane and many pairs
    // exactly touching (the verdicts the quick path must leave to triangles_intersect or decide
    // with closed segments); random reals exercise the quick path on nearly every pair; a
    // triangle in a coordinate plane with the other's corners on it, or a unit to either side,
    // the flush pairs (a point or an edge on a floor, in or out of its triangle).
    std::mt19937_64 rng(11);
    std::uniform_int_distribution<int> small(-3, 3), side(-1, 1);
    std::uniform_real_distribution<double> real(-1.0, 1.0);
    int meets = 0;
    for (int k = 0; k < 300000; ++k) {
        Vec3 a[3], b[3];
        const int axis = (k / 3) % 3;  // the flush pairs' plane: x, y and z in turn
        const double level = small(rng);
        for (int c = 0; c < 3; ++c) {
            if (k % 3 == 0) {
                a[c] = {double(small(rng)), double(small(rng)), double(small(rng))};
                b[c] = {double(small(rng)), double(small(rng)), double(small(rng))};
            } else if (k % 3 == 1) {
                a[c] = {real(rng), real(rng), real(rng)};
                b[c] = {real(rng), real(rng), real(rng)};
            } else {
                a[c] = {double(small(rng)), double(small(rng)), double(small(rng))};
                b[c] = {double(small(rng)), double(small(rng)), double(small(rng))};
                a[c][axis] = level;
                b[c][axis] = level + side(rng);
            }
        }
        const bool expected = triangles_intersect(a, b, nullptr);
        meets += expected;
        CHECK(mesh_detail::triangles_meet(a, b) == expected);
        CHECK(mesh_detail::triangles_meet(b, a) == expected);
    }
    CHECK(meets > 20000);
}

TEST_CASE("mesh query: the box test's SSE2 form gives the scalar form's verdicts and depths") {
    // The descents run the SSE2 form of the oriented-box test where the build has SSE2, the
    // scalar form elsewhere: both must decide alike, to the bit of the centre-line depth that
    // orders mesh_intersects' descent. Random boxes (axis-aligned or turned, cubes or slabs, so
    // that the edge axes run), random relative poses, and each pair's translation bisected to
    // where the verdict flips, where a rounding difference would show.
    const MeshBvh mesh = unit_cube().bvh();
    fixtures::Uniform uniform{977};  // in [-1, 1)
    const auto box = [&](bool turned) {
        NodeObb o;
        o.center = {uniform(), uniform(), uniform()};
        const double slab = std::fabs(uniform()) < 0.5 ? 0.01 : 1.0;  // elongated or not
        o.half = {0.1 + std::fabs(uniform()), 0.1 + std::fabs(uniform()), slab * (0.1 + std::fabs(uniform()))};
        o.axis_aligned = !turned;
        if (turned) o.axes = posed(uniform(), uniform(), uniform(), uniform(), {0.0, 0.0, 0.0}).rotation;
        return o;
    };
    int overlapping = 0, apart = 0, flips = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const NodeObb a = box(trial % 4 >= 2), b = box(trial % 2 == 1);
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {uniform(), uniform(), uniform()});
        const Vec3 direction{uniform(), uniform(), uniform()};
        const auto verdict_at = [&](double s, bool* agree) {
            const Pose pb = posed(uniform(), 0.3, -0.2, 0.1, pa.translation + direction * s);
            bool verdict = false;
            *agree = mesh_detail::box_test_forms_agree(a, b, mesh_detail::Relative(pa, pb, mesh, mesh), &verdict);
            return verdict;
        };
        bool agree = false;
        const double lo = 0.0, hi = 8.0;
        const bool near = verdict_at(lo, &agree);
        CHECK(agree);
        const bool far = verdict_at(hi, &agree);
        CHECK(agree);
        (near ? overlapping : apart) += 1;
        (far ? overlapping : apart) += 1;
        if (near == far) continue;
        ++flips;
        CHECK(fixtures::bisect_agreeing(verdict_at, lo, hi, near, 60));  // to the flip point
    }
    CHECK(overlapping > 1000);
    CHECK(apart > 1000);
    CHECK(flips > 1000);
}

namespace {

// A torus about z of major radius 1 and minor radius `minor`, `around` x `across` quads of two
// triangles each.
fixtures::TriangleMesh torus(int around, int across, double minor) {
    fixtures::TriangleMesh m;
    const double kTwoPi = 6.283185307179586;
    for (int i = 0; i < around; ++i)
        for (int j = 0; j < across; ++j) {
            const double u = kTwoPi * i / around, v = kTwoPi * j / across;
            const double ring = 1.0 + minor * std::cos(v);
            m.vertices.insert(m.vertices.end(), {ring * std::cos(u), ring * std::sin(u), minor * std::sin(v)});
        }
    for (std::int64_t i = 0; i < around; ++i)
        for (std::int64_t j = 0; j < across; ++j) {
            const std::int64_t i1 = (i + 1) % around, j1 = (j + 1) % across;
            const std::int64_t p = i * across + j, q = i1 * across + j, r = i1 * across + j1, s = i * across + j1;
            m.faces.insert(m.faces.end(), {p, q, r, p, r, s});
        }
    return m;
}

// Two boxes whose bounds on each axis are two draws of `pick`, the smaller the lower.
template <class Pick>
std::pair<mesh_detail::TriangleBox, mesh_detail::TriangleBox> random_boxes(Pick& pick) {
    mesh_detail::TriangleBox a, b;
    for (int k = 0; k < 3; ++k) {
        for (mesh_detail::TriangleBox* box : {&a, &b}) {
            const double p = pick(), q = pick();
            box->lower[k] = q < p ? q : p;
            box->upper[k] = q < p ? p : q;
        }
    }
    return {a, b};
}

// The crossing pairs of for_each_crossing_pair (leaf order, sorted) and its work count.
std::pair<std::vector<std::pair<std::int32_t, std::int32_t>>, long long> crossing_pairs(
    const MeshBvh& a, const MeshBvh& b, const mesh_detail::Relative& rel, long long refit_after) {
    std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
    long long work = 0;
    const bool capped = mesh_detail::for_each_crossing_pair(
        a, b, rel, std::numeric_limits<long long>::max(), &work, false,
        [&pairs](std::int32_t i, std::int32_t j, const Vec3*, const Vec3*, const Vec3&, bool) {
            pairs.push_back({i, j});
            return false;
        },
        refit_after);
    CHECK(!capped);
    std::sort(pairs.begin(), pairs.end());
    return {pairs, work};
}

}  // namespace

TEST_CASE("mesh query: kTouchGap is the largest gap whose square rounds to 0") {
    // The box tests read gap > kTouchGap for gap > 0.0 && gap * gap > 0.0 (mesh_query_detail.hpp).
    volatile double gap = mesh_detail::kTouchGap;
    CHECK(gap > 0.0);
    CHECK(gap * gap == 0.0);
    gap = std::nextafter(mesh_detail::kTouchGap, 1.0);
    CHECK(gap * gap > 0.0);
    for (const double g : {0.0, -0.0, -1.0, 0x1p-600, 0x1p-537, 1e-300, 1.0, std::numeric_limits<double>::infinity()}) {
        volatile double v = g;
        CHECK_EQ(v > 0.0 && v * v > 0.0, v > mesh_detail::kTouchGap);
    }
}

TEST_CASE("mesh query: the one-branch box test gives the three-branch test's verdicts") {
    // triangle_boxes_touch_at_once (the contacts' axis-aligned descent) against
    // triangle_boxes_touch, on boxes whose bounds are drawn from values that make the gaps
    // zero, signed zeros, kTouchGap and its neighbours, tiny and large.
    const double g = mesh_detail::kTouchGap;
    const double values[] = {-1.0, -0.5, -g, -0.0, 0.0, g, std::nextafter(g, 1.0), 0x1p-537, 1e-300, 0.5, 1.0,
                             std::nextafter(1.0, 2.0)};
    constexpr int kValues = sizeof(values) / sizeof(values[0]);
    fixtures::Uniform uniform{4141};  // in [-1, 1)
    const auto pick = [&] { return values[static_cast<int>((uniform() + 1.0) * 0.5 * kValues) % kValues]; };
    int touching = 0, apart = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const auto [a, b] = random_boxes(pick);
        const bool expected = mesh_detail::triangle_boxes_touch(a, b);
        CHECK_EQ(mesh_detail::triangle_boxes_touch_at_once(a, b), expected);
        (expected ? touching : apart) += 1;
    }
    CHECK(touching > 1000);
    CHECK(apart > 1000);
}

TEST_CASE("mesh query: a turned pair's refitted descent lists every crossing pair") {
    // The contacts' descent of a turned pair finishes by axis-aligned boxes of b refitted in
    // a's frame once it is dense: from the root, mid-way (its own choice) and never, it must
    // list the crossing pairs of all triangle pairs whose boxes touch (b's corners mapped as
    // the queries map them), and from the root count every such pair as work.
    const auto brute_force = [](const MeshBvh& a, const MeshBvh& b, const mesh_detail::Relative& rel) {
        std::vector<mesh_detail::TriangleBox> boxes_b;
        std::vector<std::array<Vec3, 3>> mapped;
        for (std::int32_t j = 0; j < b.triangle_count(); ++j) {
            mapped.push_back({rel.apply(b.triangle(j)[0]), rel.apply(b.triangle(j)[1]), rel.apply(b.triangle(j)[2])});
            boxes_b.push_back(mesh_detail::triangle_box(mapped.back().data()));
        }
        std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
        long long touching = 0;
        for (std::int32_t i = 0; i < a.triangle_count(); ++i) {
            const mesh_detail::TriangleBox box_a = mesh_detail::triangle_box(a.triangle(i));
            for (std::int32_t j = 0; j < b.triangle_count(); ++j) {
                if (!mesh_detail::triangle_boxes_touch(box_a, boxes_b[static_cast<size_t>(j)])) continue;
                ++touching;
                if (triangles_intersect(a.triangle(i), mapped[static_cast<size_t>(j)].data(), nullptr))
                    pairs.push_back({i, j});
            }
        }
        return std::make_pair(pairs, touching);
    };
    const MeshBvh ring = torus(64, 32, 0.3).bvh();
    fixtures::Uniform uniform{2929};  // in [-1, 1)
    int switched = 0;
    for (int trial = 0; trial < 4; ++trial) {
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {0.0, 0.0, 0.0});
        const Vec3 shift{0.3 * uniform(), 0.3 * uniform(), 0.1 * uniform()};
        const Pose pb = posed(uniform(), uniform(), uniform(), uniform(), shift);
        const mesh_detail::Relative rel(pa, pb, ring, ring);
        REQUIRE(!rel.translation_only);
        const auto [expected, touching] = brute_force(ring, ring, rel);
        CHECK(expected.size() >= 200);
        const auto [from_root, work_root] = crossing_pairs(ring, ring, rel, 0);
        const auto [chosen, work_chosen] = crossing_pairs(ring, ring, rel, -1);
        const auto [never, work_never] = crossing_pairs(ring, ring, rel, std::numeric_limits<long long>::max());
        CHECK(from_root == expected);
        CHECK(chosen == expected);
        CHECK(never == expected);
        CHECK_EQ(work_root, touching);
        CHECK(work_never <= touching);
        switched += work_chosen != work_never;
    }
    CHECK(switched >= 2);  // the descent's own choice refits these dense pairs mid-way
    // A box turned a quarter about z (an exact rotation) resting flush on another: every gap
    // at the shared face is exactly 0, and the refitted boxes must keep those pairs.
    const MeshBvh base = fixtures::box_mesh({0, 0, 0}, {2, 2, 1}).bvh();
    const MeshBvh top = fixtures::box_mesh({0.25, -1.5, 0}, {1.75, -0.5, 1}).bvh();
    Pose quarter;
    quarter.rotation.m[0][0] = 0.0, quarter.rotation.m[0][1] = -1.0, quarter.rotation.m[0][2] = 0.0;
    quarter.rotation.m[1][0] = 1.0, quarter.rotation.m[1][1] = 0.0, quarter.rotation.m[1][2] = 0.0;
    quarter.rotation.m[2][0] = 0.0, quarter.rotation.m[2][1] = 0.0, quarter.rotation.m[2][2] = 1.0;
    quarter.translation = {0.0, 0.0, 1.0};
    const mesh_detail::Relative flush(at(0, 0, 0), quarter, base, top);
    REQUIRE(!flush.translation_only);
    const auto [expected, touching] = brute_force(base, top, flush);
    CHECK(expected.size() >= 8);
    const auto [from_root, work_root] = crossing_pairs(base, top, flush, 0);
    CHECK(from_root == expected);
    CHECK_EQ(work_root, touching);
    CHECK(crossing_pairs(base, top, flush, std::numeric_limits<long long>::max()).first == expected);
}

TEST_CASE("mesh query: the depth's marks stop past their cap of near pairs") {
    // Flush faces: every gap between the two boxes' facing triangles is exactly 0, so their
    // pairs are near. Marked in full, `others` holds each near pair once per side; a cap of
    // exactly that many keeps the marks, one fewer stops them (and the depth query then
    // answers MAX_ITERATIONS, mesh_depth.cpp).
    const MeshBvh base = fixtures::box_mesh({0, 0, 0}, {2, 2, 1}).bvh();
    const MeshBvh top = fixtures::box_mesh({0.25, 0.5, 1}, {1.75, 1.5, 2}).bvh();
    const mesh_detail::Relative rel(at(0, 0, 0), at(0, 0, 0), base, top);
    for (const auto descent : {mesh_detail::MarkDescent::kFast, mesh_detail::MarkDescent::kPlain}) {
        mesh_detail::TriangleMarks in_a, in_b;
        std::vector<mesh_detail::CrossingPair> pairs;
        REQUIRE(mesh_detail::mark_crossing_triangles(base, top, rel, in_a, in_b, pairs, descent));
        const auto near = static_cast<long long>(in_a.others.size());
        REQUIRE(near >= 2);
        CHECK_EQ(static_cast<long long>(in_b.others.size()), near);
        CHECK(mesh_detail::mark_crossing_triangles(base, top, rel, in_a, in_b, pairs, descent, near));
        CHECK(!mesh_detail::mark_crossing_triangles(base, top, rel, in_a, in_b, pairs, descent, near - 1));
        CHECK(!mesh_detail::mark_crossing_triangles(base, top, rel, in_a, in_b, pairs, descent, 0));
    }
}

TEST_CASE("mesh query: the depth's marks by the fast descents are the plain descent's") {
    // mark_crossing_triangles finds its pairs by the contacts' descents (axis-aligned boxes
    // under a translation, refitted ones for a dense turned pair) and puts them in the plain
    // oriented descent's order: the crossing pairs must be that descent's in its order, with
    // the same crossing marks and partners; the near pairs may differ only among those whose
    // boxes are within rel.slack, and under a translation hold the plain descent's.
    const MeshBvh ring = torus(64, 32, 0.3).bvh();
    const MeshBvh base = fixtures::box_mesh({0, 0, 0}, {2, 2, 1}).bvh();
    const MeshBvh top = fixtures::box_mesh({0.25, 0.5, 1}, {1.75, 1.5, 2}).bvh();
    fixtures::Uniform uniform{3131};  // in [-1, 1)
    struct Case {
        const MeshBvh *a, *b;
        Pose pa, pb;
    };
    std::vector<Case> cases;
    for (int trial = 0; trial < 6; ++trial) {
        const Pose pa = posed(uniform(), uniform(), uniform(), uniform(), {0.0, 0.0, 0.0});
        const Vec3 shift{0.3 * uniform(), 0.3 * uniform(), 0.1 * uniform()};
        Pose moved = pa;
        moved.translation = shift;
        cases.push_back({&ring, &ring, pa, moved});  // translated
        cases.push_back({&ring, &ring, pa, posed(uniform(), uniform(), uniform(), uniform(), shift)});  // turned
    }
    cases.push_back({&base, &top, at(0, 0, 0), at(0, 0, 0)});  // flush faces: every gap exactly 0
    cases.push_back({&ring, &ring, at(0, 0, 0), at(0, 0, 0)});  // coincident surfaces
    int translated = 0, crossing = 0;
    for (const Case& c : cases) {
        const mesh_detail::Relative rel(c.pa, c.pb, *c.a, *c.b);
        mesh_detail::TriangleMarks fast_a, fast_b, plain_a, plain_b;
        std::vector<mesh_detail::CrossingPair> fast, plain;
        mesh_detail::mark_crossing_triangles(*c.a, *c.b, rel, fast_a, fast_b, fast);
        mesh_detail::mark_crossing_triangles(*c.a, *c.b, rel, plain_a, plain_b, plain,
                                             mesh_detail::MarkDescent::kPlain);
        REQUIRE(fast.size() == plain.size());
        for (size_t k = 0; k < fast.size(); ++k) {
            CHECK_EQ(fast[k].a, plain[k].a);
            CHECK_EQ(fast[k].b, plain[k].b);
        }
        crossing += fast.size() >= 8;
        translated += rel.translation_only;
        for (const auto& [f, p, mesh] : {std::make_tuple(&fast_a, &plain_a, c.a), std::make_tuple(&fast_b, &plain_b, c.b)}) {
            CHECK(f->crossing == p->crossing);
            for (std::int32_t i = 0; i < mesh->triangle_count(); ++i) {
                if (p->crossing[static_cast<size_t>(i)]) CHECK_EQ(f->near_entry(i).partner, p->near_entry(i).partner);
                if (rel.translation_only && p->near(i)) {
                    REQUIRE(f->near(i));
                    const auto [pf, pl] = p->near_range(i);
                    const auto [ff, fl] = f->near_range(i);
                    std::vector<std::int32_t> fast_others(f->others.begin() + ff, f->others.begin() + fl);
                    for (std::int32_t n = pf; n < pl; ++n)
                        CHECK(std::find(fast_others.begin(), fast_others.end(), p->others[static_cast<size_t>(n)]) !=
                              fast_others.end());
                }
            }
        }
    }
    CHECK(translated == 8);
    CHECK(crossing >= 12);
}

TEST_CASE("mesh query: the one-branch squared box distance is the branching one's, bit for bit") {
    // boxes_squared_distance_at_once (the depth marks' axis-aligned descent) against
    // triangle_box_squared_distance, on boxes whose bounds make gaps of zero, signed zeros,
    // kTouchGap, tiny, large and ordinary sizes, compared as bytes.
    const double g = mesh_detail::kTouchGap;
    const double values[] = {-1.0, -0.5, -g, -0.0, 0.0, g, 0x1p-537, 1e-300, 1e-13, 0.3, 0.5, 1.0,
                             std::nextafter(1.0, 2.0), 1e150};
    constexpr int kValues = sizeof(values) / sizeof(values[0]);
    fixtures::Uniform uniform{5353};  // in [-1, 1)
    const auto pick = [&] {
        const double v = values[static_cast<int>((uniform() + 1.0) * 0.5 * kValues) % kValues];
        return uniform() < 0.0 ? v : v * (1.0 + uniform());  // exact values, and values near them
    };
    int within = 0, apart = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const auto [a, b] = random_boxes(pick);
        const double expected = mesh_detail::triangle_box_squared_distance(a, b);
        const double got = mesh_detail::boxes_squared_distance_at_once(a, b);
        CHECK(std::memcmp(&expected, &got, sizeof(double)) == 0);
        (expected == 0.0 ? within : apart) += 1;
    }
    CHECK(within > 1000);
    CHECK(apart > 1000);
}
