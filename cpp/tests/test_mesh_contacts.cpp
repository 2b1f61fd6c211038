// Mesh contacts (mesh_query.hpp: mesh_contacts) and the triangle-pair penetration under them
// (triangle.hpp: triangle_penetration): known depths, parallel edges, degenerate and coplanar
// triangles, the deepest of a mesh pair, the listed contacts and every status.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"

using namespace meshcol;
using fixtures::at;

namespace {

// A wide triangle in z = 0, counter-clockwise from above (normal +z).
const Vec3 kFloor[3] = {{-10, -10, 0}, {10, -10, 0}, {0, 10, 0}};

MeshContactsInput pair_of(const MeshBvh& a, const Pose& pose_a, const MeshBvh& b, const Pose& pose_b) {
    MeshContactsInput in;
    in.a = &a;
    in.b = &b;
    in.pose_a = pose_a;
    in.pose_b = pose_b;
    return in;
}

fixtures::TriangleMesh one_triangle(const Vec3 t[3]) {
    fixtures::TriangleMesh m;
    for (int k = 0; k < 3; ++k) m.vertices.insert(m.vertices.end(), {t[k].x, t[k].y, t[k].z});
    m.faces = {0, 1, 2};
    return m;
}

// A random triangle pair for the exactness tests: small integers in [-2, 2] (equal
// projections, ties) when `integers`, else reals in [-1, 1] times a scale of 2^-30 to 2^30,
// which it returns (1 for integers).
double random_pair(std::mt19937_64& rng, bool integers, Vec3 a[3], Vec3 b[3]) {
    std::uniform_real_distribution<double> real(-1.0, 1.0);
    std::uniform_int_distribution<int> small(-2, 2), decade(-30, 30);
    const double scale = integers ? 1.0 : std::ldexp(1.0, decade(rng));
    for (int c = 0; c < 3; ++c) {
        a[c] = integers ? Vec3{double(small(rng)), double(small(rng)), double(small(rng))}
                        : Vec3{real(rng), real(rng), real(rng)} * scale;
        b[c] = integers ? Vec3{double(small(rng)), double(small(rng)), double(small(rng))}
                        : Vec3{real(rng), real(rng), real(rng)} * scale;
    }
    return scale;
}

}  // namespace

TEST_CASE("triangle penetration: a spike through a floor leaves along the floor's normal") {
    // b pokes 0.3 below a; its horizontal edge is parallel to a's first edge (no axis)
    const Vec3 spike[3] = {{0, 0, -0.3}, {1, 0, 2}, {-1, 0, 2}};
    const TrianglePenetration p = triangle_penetration(kFloor, spike);
    CHECK_NEAR(p.depth, 0.3, 1e-15);
    CHECK_EQ(p.axis, 0);
    CHECK_NEAR(p.normal.z, 1.0, 1e-15);
    CHECK_NEAR(p.point_b.z, -0.3, 1e-15);  // b's deepest corner
    CHECK_NEAR(p.point_a.z, 0.0, 1e-15);   // where it meets a once moved
    CHECK_NEAR(p.point_a.x, 0.0, 1e-15);
    // the same pair seen from b: a moves down, along -z from b's side
    const TrianglePenetration q = triangle_penetration(spike, kFloor);
    CHECK_NEAR(q.depth, 0.3, 1e-15);
    CHECK_NEAR(q.normal.z, -1.0, 1e-15);
}

TEST_CASE("triangle penetration: an edge-edge axis is the minimum") {
    // Two thin triangles crossing as an X, each reaching 0.1 past the other's edge: the
    // shortest way out is across an edge pair, along z, not along either face normal.
    const Vec3 a[3] = {{-1, 0, 0}, {1, 0, 0}, {0, 0, -5}};    // in y = 0, top edge at z = 0
    const Vec3 b[3] = {{0, -1, -0.1}, {0, 1, -0.1}, {0, 0, 5}};  // in x = 0, bottom edge at z = -0.1
    const TrianglePenetration p = triangle_penetration(a, b);
    CHECK_NEAR(p.depth, 0.1, 1e-15);
    CHECK(p.axis >= 2);
    CHECK_NEAR(p.normal.z, 1.0, 1e-15);  // b moves up
    CHECK_NEAR(p.point_a.z, 0.0, 1e-15);
    CHECK_NEAR(p.point_b.z, -0.1, 1e-15);
    // moved by the depth and a hair they no longer meet; by less they still do
    const Vec3 up[3] = {b[0] + Vec3{0, 0, 0.1 + 1e-12}, b[1] + Vec3{0, 0, 0.1 + 1e-12}, b[2] + Vec3{0, 0, 0.1 + 1e-12}};
    CHECK(!triangles_intersect(a, up, nullptr));
    const Vec3 short_of[3] = {b[0] + Vec3{0, 0, 0.09}, b[1] + Vec3{0, 0, 0.09}, b[2] + Vec3{0, 0, 0.09}};
    CHECK(triangles_intersect(a, short_of, nullptr));
}

TEST_CASE("triangle penetration: coplanar triangles have depth 0 exactly") {
    const Vec3 b[3] = {{0, 0, 0}, {20, 0, 0}, {0, 20, 0}};
    const TrianglePenetration p = triangle_penetration(kFloor, b);
    CHECK_EQ(p.depth, 0.0);
    CHECK_EQ(p.axis, 0);
    CHECK_NEAR(std::fabs(p.normal.z), 1.0, 1e-15);
    CHECK_EQ(p.point_a.z, 0.0);  // a shared point
    // tilted out of every coordinate plane, still exactly coplanar (integer corners on x + y + z = 0)
    const Vec3 c[3] = {{1, -1, 0}, {0, 1, -1}, {-1, 0, 1}};
    const Vec3 d[3] = {{2, -1, -1}, {-1, 2, -1}, {-1, -1, 2}};
    CHECK_EQ(triangle_penetration(c, d).depth, 0.0);
}

TEST_CASE("triangle penetration: degenerate triangles are the segment or point they are") {
    // a needle (repeated corner) through the floor: out along +z by 0.3
    const Vec3 needle[3] = {{0, 0, -0.3}, {0, 0, 2}, {0, 0, 2}};
    const TrianglePenetration p = triangle_penetration(kFloor, needle);
    CHECK_NEAR(p.depth, 0.3, 1e-15);
    CHECK_EQ(p.axis, 0);
    // collinear corners, not repeated: the same segment
    const Vec3 collinear[3] = {{0, 0, -0.3}, {0, 0, 0.7}, {0, 0, 2}};
    CHECK_NEAR(triangle_penetration(kFloor, collinear).depth, 0.3, 1e-15);
    // the floor degenerate instead: b's plane decides
    CHECK_NEAR(triangle_penetration(needle, kFloor).depth, 0.3, 1e-15);
    // two crossing segments: a flat difference, depth 0 along their cross product
    const Vec3 s[3] = {{-1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    const Vec3 t[3] = {{0, -1, 0}, {0, 1, 0}, {0, 1, 0}};
    const TrianglePenetration st = triangle_penetration(s, t);
    CHECK_EQ(st.depth, 0.0);
    CHECK_NEAR(std::fabs(st.normal.z), 1.0, 1e-15);
    // overlapping collinear segments and a point on a segment: no axis at all
    const Vec3 u[3] = {{-2, 0, 0}, {0.5, 0, 0}, {0.5, 0, 0}};
    const TrianglePenetration su = triangle_penetration(s, u);
    CHECK_EQ(su.depth, 0.0);
    CHECK_EQ(su.axis, -1);
    CHECK(std::isnan(su.normal.x));
    const Vec3 point[3] = {{0.25, 0, 0}, {0.25, 0, 0}, {0.25, 0, 0}};
    CHECK_EQ(triangle_penetration(s, point).depth, 0.0);
}

TEST_CASE("mesh contacts: one triangle pair is one contact, in the world frame") {
    const Vec3 spike[3] = {{0, 0, -0.3}, {1, 0, 2}, {-1, 0, 2}};
    const MeshBvh floor = one_triangle(kFloor).bvh(), b = one_triangle(spike).bvh();
    // both turned a quarter about z and moved: the answer turns with them
    const double quarter = std::acos(-1.0) / 2;
    const MeshContactsOutput r =
        mesh_contacts(pair_of(floor, fixtures::turned_about_z(quarter, 5, 0, 1), b, fixtures::turned_about_z(quarter, 5, 0, 1)));
    REQUIRE(r.status == Status::CONVERGED);
    CHECK_EQ(r.count, 1);
    CHECK_NEAR(r.depth, 0.3, 1e-14);
    CHECK_NEAR(r.normal.z, 1.0, 1e-14);
    CHECK_NEAR(r.point.x, 5.0, 1e-14);
    CHECK_NEAR(r.point.z, 1.0 - 0.15, 1e-14);  // midway between the witness points
    CHECK_EQ(r.triangle_a, 0);
    CHECK_EQ(r.triangle_b, 0);
}

TEST_CASE("mesh contacts: a bar through a box's face, 0.1 deep") {
    // the bar's end is 0.1 inside the box and its sides cross the box's x = 1 face only
    const MeshBvh box = fixtures::box_mesh({-1, -1, -1}, {1, 1, 1}).bvh();
    const MeshBvh bar = fixtures::box_mesh({0.9, -0.5, -0.5}, {3, 0.5, 0.5}).bvh();
    MeshContactsInput in = pair_of(box, at(0, 0, 0), bar, at(0, 0, 0));
    in.max_contacts = 1000;
    std::vector<MeshContact> all;
    const MeshContactsOutput r = mesh_contacts(in, &all);
    REQUIRE(r.status == Status::CONVERGED);
    CHECK(r.count > 0);
    CHECK_NEAR(r.depth, 0.1, 1e-14);
    CHECK_NEAR(r.normal.x, 1.0, 1e-14);  // the bar leaves along +x
    CHECK(r.triangle_a == 10 || r.triangle_a == 11);  // the box's x = hi face
    REQUIRE(static_cast<std::int64_t>(all.size()) == r.count);
    for (size_t k = 0; k < all.size(); ++k) {
        CHECK(all[k].triangle_a == 10 || all[k].triangle_a == 11);
        CHECK(all[k].depth <= r.depth);
        CHECK(all[k].depth >= 0.0);
        CHECK_NEAR(all[k].point.x, 1.0, 0.1);
        if (k > 0)
            CHECK(all[k - 1].triangle_a < all[k].triangle_a ||
                  (all[k - 1].triangle_a == all[k].triangle_a && all[k - 1].triangle_b < all[k].triangle_b));
    }
    // the first few only, the count and the deepest unchanged
    in.max_contacts = 2;
    const MeshContactsOutput few = mesh_contacts(in, &all);
    CHECK_EQ(all.size(), size_t{2});
    CHECK_EQ(few.count, r.count);
    CHECK_EQ(few.depth, r.depth);
    CHECK_EQ(few.triangle_b, r.triangle_b);
}

TEST_CASE("mesh contacts: apart, nested and touching meshes") {
    const MeshBvh box = fixtures::box_mesh({-1, -1, -1}, {1, 1, 1}).bvh();
    const MeshBvh small = fixtures::box_mesh({-0.2, -0.2, -0.2}, {0.2, 0.2, 0.2}).bvh();
    for (const Pose& pose : {at(5, 0, 0), at(0, 0, 0)}) {  // apart, then nested: no crossing pair
        const MeshContactsOutput r = mesh_contacts(pair_of(box, at(0, 0, 0), small, pose));
        CHECK(r.status == Status::CONVERGED);
        CHECK_EQ(r.count, 0);
        CHECK_EQ(r.depth, 0.0);
        CHECK(std::isnan(r.normal.x) && std::isnan(r.point.x));
        CHECK_EQ(r.triangle_a, -1);
    }
    // resting face to face: the touching pairs count, each 0 deep
    const MeshContactsOutput rest = mesh_contacts(pair_of(box, at(0, 0, 0), box, at(0, 0, 2)));
    CHECK(rest.status == Status::CONVERGED);
    CHECK(rest.count > 0);
    CHECK_EQ(rest.depth, 0.0);
    CHECK_NEAR(std::fabs(rest.normal.z), 1.0, 1e-15);
}

TEST_CASE("mesh contacts: every status") {
    const MeshBvh box = fixtures::box_mesh({-1, -1, -1}, {1, 1, 1}).bvh();
    const MeshBvh empty;
    const MeshContactsOutput invalid = mesh_contacts(pair_of(box, at(0, 0, 0), empty, at(0, 0, 0)));
    CHECK(invalid.status == Status::INVALID_INPUT);
    CHECK(std::isnan(invalid.depth));
    MeshContactsInput negative = pair_of(box, at(0, 0, 0), box, at(0, 0, 0));
    negative.max_contacts = -1;
    CHECK(mesh_contacts(negative).status == Status::INVALID_INPUT);
    const MeshContactsOutput far = mesh_contacts(pair_of(box, at(0, 0, 0), box, at(1e40, 0, 0)));
    CHECK(far.status == Status::OUT_OF_RANGE);
    CHECK(std::isnan(far.depth));
    MeshContactsInput capped = pair_of(box, at(0, 0, 0), box, at(0.5, 0.25, 0.125));
    const MeshContactsOutput whole = mesh_contacts(capped);
    CHECK(whole.status == Status::CONVERGED);
    capped.max_work = 3;
    const MeshContactsOutput part = mesh_contacts(capped);
    CHECK(part.status == Status::MAX_ITERATIONS);
    CHECK(part.count <= whole.count);
    CHECK(part.count <= 3);
}

TEST_CASE("triangle penetration: a general pair gives the same answer told it is general") {
    // Random real corners put no corner on another plane (with probability 1): the
    // general form skips the coplanarity and degeneracy tests and must give the same bits.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> real(-1.0, 1.0);
    int checked = 0;
    for (int k = 0; k < 20000; ++k) {
        Vec3 a[3], b[3];
        for (int c = 0; c < 3; ++c) {
            a[c] = {real(rng), real(rng), real(rng)};
            b[c] = {real(rng), real(rng), real(rng)};
        }
        if (!triangles_intersect(a, b, nullptr)) continue;
        ++checked;
        const TrianglePenetration full = triangle_penetration(a, b, true, false);
        const TrianglePenetration general = triangle_penetration(a, b, true, true);
        CHECK(general.depth == full.depth);
        CHECK(general.axis == full.axis);
        CHECK(general.normal.x == full.normal.x && general.normal.y == full.normal.y &&
              general.normal.z == full.normal.z);
        CHECK(general.point_a.x == full.point_a.x && general.point_a.y == full.point_a.y &&
              general.point_a.z == full.point_a.z);
        CHECK(general.point_b.x == full.point_b.x && general.point_b.y == full.point_b.y &&
              general.point_b.z == full.point_b.z);
    }
    CHECK(checked > 1000);
}

TEST_CASE("triangle penetration: the SSE2 projection gives the scalar form's overlaps") {
    // The contacts run the SSE2 form of the penetration's projection where the build has SSE2,
    // the scalar form elsewhere: every axis's overlap must be the same bits in both. Random
    // real pairs over many scales, small-integer pairs (equal projections: the min and max
    // ties), and each real pair's b moved along a's normal to where the scalar form's
    // direction on that axis flips (up == down), where a rounding difference would show.
    std::mt19937_64 rng(29);
    int flips = 0, pairs = 0;
    for (int trial = 0; trial < 6000; ++trial) {
        Vec3 a[3], b[3];
        const bool integers = trial % 3 == 0;
        const double scale = random_pair(rng, integers, a, b);
        bool down = false;
        CHECK(mesh_detail::penetration_axis_forms_agree(a, b, &down));
        CHECK(mesh_detail::penetration_axis_forms_agree(b, a, &down));
        ++pairs;
        if (integers) continue;
        // b moved by s times a's normal: `down` on that axis flips once as s grows.
        const Vec3 n = cross(a[1] - a[0], a[2] - a[0]);
        const auto down_at = [&](double s, bool* agree) {
            const Vec3 moved[3] = {b[0] + n * s, b[1] + n * s, b[2] + n * s};
            bool d = false;
            *agree = mesh_detail::penetration_axis_forms_agree(a, moved, &d);
            return d;
        };
        const double reach = 4.0 * scale / std::max(norm(n), 1e-300);
        const double lo = -reach, hi = reach;
        bool agree = false;
        const bool low = down_at(lo, &agree);
        CHECK(agree);
        const bool high = down_at(hi, &agree);
        CHECK(agree);
        if (low == high) continue;
        ++flips;
        CHECK(fixtures::bisect_agreeing(down_at, lo, hi, low, 64));  // to the flip point
    }
    CHECK(pairs == 6000);
    CHECK(flips > 2000);
}

TEST_CASE("triangle distance: one feature pair alone is the search's value and points for it") {
    // triangle_feature_squared_distance runs one of the search's 15 feature pairs by its own
    // expressions: the first least over the 15 (a corner outside the face is none) is the full
    // search's answer, value and points to the bit. Random pairs over many scales, small
    // integers (ties between features), and the witness points of intersecting pairs (b moved
    // by the depth: the features touch, the case the contacts take them from).
    std::mt19937_64 rng(31);
    const auto same = [](const Vec3& p, const Vec3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; };
    int fast = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        Vec3 a[3], b[3];
        random_pair(rng, trial % 3 == 0, a, b);
        Vec3 pa, pb;
        const double whole = triangle_separated_squared_distance(a, b, &pa, &pb);
        double least = std::numeric_limits<double>::infinity();
        Vec3 la = a[0], lb = b[0];
        for (int feature = 0; feature < 15; ++feature) {
            Vec3 qa, qb;
            const double d2 = triangle_feature_squared_distance(a, b, feature, &qa, &qb);
            if (d2 < least) {
                least = d2;
                la = qa;
                lb = qb;
            }
        }
        CHECK(least == whole);
        CHECK(same(la, pa) && same(lb, pb));
        if (!triangles_intersect(a, b, nullptr)) continue;
        // The witness points: on their triangles, depth * normal apart.
        const TrianglePenetration p = triangle_penetration(a, b, true);
        if (!(p.depth > 0.0)) continue;
        double reach = 0.0;
        for (int c = 0; c < 3; ++c)
            reach = std::max({reach, std::fabs(a[c].x), std::fabs(a[c].y), std::fabs(a[c].z), std::fabs(b[c].x),
                              std::fabs(b[c].y), std::fabs(b[c].z)});
        const double gap = norm(p.point_a - p.point_b - p.normal * p.depth);
        fast += gap <= 1e-12 * reach;
        CHECK(norm(closest_point_on_triangle(p.point_a, a) - p.point_a) <= 1e-12 * reach);
        CHECK(norm(closest_point_on_triangle(p.point_b, b) - p.point_b) <= 1e-12 * reach);
    }
    CHECK(fast > 500);
}
