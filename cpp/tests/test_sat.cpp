// The SAT depth (sat.hpp): axes skipped by the inner-ball bound change no answer, bit for bit,
// against the plain loop that measures every axis (written out here as the reference).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/sat.hpp"

using namespace meshcol;

namespace {

// Every candidate axis measured, in the order and with the arithmetic of `sat_penetration`.
SatResult every_axis(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                     const Pose& pose_b) {
    SatResult res;
    const bool box_a = a.kind == ShapeKind::BOX, box_b = b.kind == ShapeKind::BOX;
    static const Vec3 faces[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0},
                                  {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    static const Vec3 edges[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const Vec3* fa = box_a ? faces : a.face_normals;
    const Vec3* fb = box_b ? faces : b.face_normals;
    const Vec3* ea = box_a ? edges : a.edge_directions;
    const Vec3* eb = box_b ? edges : b.edge_directions;
    const int nfa = box_a ? 6 : a.face_count, nfb = box_b ? 6 : b.face_count;
    const int nea = box_a ? 3 : a.edge_count, neb = box_b ? 3 : b.edge_count;
    res.ran = true;
    const Mat3 rot = pose_a.rotation.transposed() * pose_b.rotation;
    const Vec3 trans = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_axis{1.0, 0.0, 0.0};
    auto test = [&](const Vec3& n) {
        const Vec3 pa = support_core(a, n).point;
        const Vec3 pb = rot * support_core(b, rot.transpose_times(-n)).point + trans;
        const double overlap = dot(n, pa) - dot(n, pb);
        ++res.axes;
        if (overlap < best) {
            best = overlap;
            best_axis = n;
        }
    };
    for (int i = 0; i < nfa; ++i) test(fa[i]);
    for (int j = 0; j < nfb; ++j) test(-(rot * fb[j]));
    for (int i = 0; i < nea; ++i)
        for (int j = 0; j < neb; ++j) {
            const Vec3 c = cross(ea[i], rot * eb[j]);
            const double len = norm(c);
            if (!(len > defaults::sat_parallel_edge_sine)) continue;
            const Vec3 n = c / len;
            test(n);
            test(-n);
        }
    if (!std::isfinite(best)) {
        res.ran = false;
        return res;
    }
    res.separated = best < 0.0;
    res.depth = best < 0.0 ? 0.0 : best;
    res.normal = pose_a.rotate(best_axis);
    return res;
}

bool same_bits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

using Random = fixtures::Uniform;  // in [-1, 1)

Pose random_pose(Random& r, double spread) {
    // a rotation from a random unit quaternion, placed within `spread` of the origin
    double q[4];
    double len = 0.0;
    do {
        len = 0.0;
        for (double& c : q) {
            c = r();
            len += c * c;
        }
    } while (len < 1e-3);
    len = std::sqrt(len);
    const double w = q[0] / len, x = q[1] / len, y = q[2] / len, z = q[3] / len;
    Pose p;
    p.rotation.m[0][0] = 1 - 2 * (y * y + z * z);
    p.rotation.m[0][1] = 2 * (x * y - w * z);
    p.rotation.m[0][2] = 2 * (x * z + w * y);
    p.rotation.m[1][0] = 2 * (x * y + w * z);
    p.rotation.m[1][1] = 1 - 2 * (x * x + z * z);
    p.rotation.m[1][2] = 2 * (y * z - w * x);
    p.rotation.m[2][0] = 2 * (x * z - w * y);
    p.rotation.m[2][1] = 2 * (y * z + w * x);
    p.rotation.m[2][2] = 1 - 2 * (x * x + y * y);
    p.translation = Vec3{r(), r(), r()} * spread;
    return p;
}

}  // namespace

TEST_CASE("sat: the axes the inner balls skip change no answer, bit for bit") {
    // Point sets of the kinds SAT meets: points on an ellipsoid (every one on the hull), a
    // lattice box (coplanar faces, parallel edges, tied supports), an L-shaped prism, a flat
    // square (no inner ball: every axis measured) and a single point; at scales from 1e-6 to
    // 1e6, placed from deep inside each other to apart.
    Random r{20261205};
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets{0};
    auto add = [&](const std::vector<Vec3>& set) {
        points.insert(points.end(), set.begin(), set.end());
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    };
    for (int n : {6, 10, 16, 24}) {
        std::vector<Vec3> set;
        const Vec3 axes{0.4 + 0.4 * std::fabs(r()), 0.4 + 0.4 * std::fabs(r()),
                        0.4 + 0.4 * std::fabs(r())};
        for (int i = 0; i < n; ++i) {
            Vec3 p{r(), r(), r()};
            p = p / norm(p);
            set.push_back(Vec3{p.x * axes.x, p.y * axes.y, p.z * axes.z});
        }
        add(set);
    }
    {
        std::vector<Vec3> lattice;
        for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 2; ++y)
                for (int z = 0; z < 2; ++z) lattice.push_back(Vec3{0.3 * x - 0.3, 0.5 * y - 0.25, 0.4 * z - 0.2});
        add(lattice);
        std::vector<Vec3> l_prism;
        const double outline[6][2] = {{0, 0}, {1, 0}, {1, 0.25}, {0.25, 0.25}, {0.25, 1}, {0, 1}};
        for (double z : {-0.3, 0.3})
            for (const auto& xy : outline) l_prism.push_back(Vec3{xy[0] - 0.4, xy[1] - 0.4, z});
        add(l_prism);
        add({{-0.5, -0.5, 0.0}, {0.5, -0.5, 0.0}, {0.5, 0.5, 0.0}, {-0.5, 0.5, 0.0}});
        add({{0.1, 0.2, 0.3}});
    }
    const long long shapes = static_cast<long long>(offsets.size()) - 1;
    const std::vector<Vec3> kept = points;
    int compared = 0, deep = 0, with_arcs = 0;
    long long measured = 0, every = 0;
    for (double scale : {1.0, 1e-6, 1e6}) {
        std::vector<Vec3> scaled(kept.size());
        for (size_t i = 0; i < kept.size(); ++i) scaled[i] = kept[i] * scale;
        const PackedPolytopes p = pack_polytopes(scaled.data(), offsets.data(), shapes, 1);
        fixtures::PolytopeSet packed(p);
        const ConvexSetView& set = packed.view;
        // SAT gets the views whose edge classes it computes on first need; the reference the
        // same views with their classes attached.
        std::vector<ShapeView> views, whole;
        for (long long h = 0; h < shapes; ++h) views.push_back(set.shape(h));
        views.push_back(fixtures::box(0.3 * scale, 0.5 * scale, 0.2 * scale));
        for (ShapeView v : views) {
            attach_edges(v);
            whole.push_back(v);
        }
        for (int trial = 0; trial < 150; ++trial) {
            for (size_t i = 0; i < views.size(); ++i)
                for (size_t j = 0; j < views.size(); ++j) {
                    if (!has_sat_features(views[i]) || !has_sat_features(views[j])) continue;
                    const double spread = scale * (0.2 + 1.2 * (trial % 5) / 4.0);
                    const Pose pa = random_pose(r, spread), pb = random_pose(r, spread);
                    const SatResult want = every_axis(whole[i], pa, whole[j], pb);
                    const SatResult got = sat_penetration(views[i], pa, views[j], pb,
                                                          std::numeric_limits<long long>::max());
                    REQUIRE(got.ran == want.ran);
                    CHECK(got.separated == want.separated);
                    CHECK(same_bits(got.depth, want.depth));
                    CHECK(same_bits(got.normal.x, want.normal.x));
                    CHECK(same_bits(got.normal.y, want.normal.y));
                    CHECK(same_bits(got.normal.z, want.normal.z));
                    CHECK(got.axes <= want.axes);
                    measured += got.axes;
                    every += want.axes;
                    ++compared;
                    deep += want.ran && !want.separated;
                    with_arcs += whole[i].arcs != nullptr && whole[j].arcs != nullptr;
                }
        }
    }
    CHECK(compared > 10000);
    CHECK(deep > 1000);
    // The hulls of points on ellipsoids and the lattice box and prism have arcs on their Gauss
    // maps: SAT measures only the edge pairs whose arcs cross there (when that pays), with
    // the same answers.
    CHECK(with_arcs > 5000);
    // The bound does skip: most axes of these pairs are never measured (a plain loop again,
    // or a bound that skips nothing, fails here).
    CHECK(measured * 2 < every);
}

namespace {

// Unit vector along v.
Vec3 unit(const Vec3& v) { return v / norm(v); }

}  // namespace

TEST_CASE("sat: a cube's and a wedge's arcs join the normals of each edge's two faces") {
    std::vector<Vec3> points = fixtures::cube_corners(0.5);
    // A wedge: the prism over the triangle (0, 0), (1, 0), (0, 1), along z, turned a little.
    Random turns{7};
    const Pose turn = random_pose(turns, 0.0);
    for (const Vec3& p : std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}})
        points.push_back(turn.apply(p));
    const std::int64_t offsets[3] = {0, 8, 14};
    const PackedPolytopes p = pack_polytopes(points.data(), offsets, 2, 1);
    fixtures::PolytopeSet packed(p);
    for (int h = 0; h < 2; ++h) {
        ShapeView view = packed.view.shape(h);
        attach_edges(view);
        REQUIRE(view.arcs != nullptr);
        CHECK_EQ(view.arc_count, h == 0 ? 12 : 9);      // true edges
        CHECK_EQ(view.edge_count, h == 0 ? 3 : 4);      // their direction classes
        CHECK_EQ(view.face_count, h == 0 ? 6 : 5);
        for (int k = 0; k < view.arc_count; ++k) {
            const GaussArc& arc = view.arcs[k];
            REQUIRE(arc.direction_class >= 0);
            REQUIRE(arc.direction_class < view.edge_count);
            const Vec3 edge = view.edge_directions[arc.direction_class];
            REQUIRE(arc.face_a >= 0);
            REQUIRE(arc.face_a < view.face_count);
            REQUIRE(arc.face_b >= 0);
            REQUIRE(arc.face_b < view.face_count);
            const Vec3 normal_a = view.face_normals[arc.face_a];
            const Vec3 normal_b = view.face_normals[arc.face_b];
            // The two faces differ, both hold the edge (normals at right angles to it), and
            // the arc's circle has the edge's direction as its axis.
            CHECK(dot(normal_a, normal_b) < 0.99);
            CHECK(std::fabs(dot(normal_a, edge)) < 1e-12);
            CHECK(std::fabs(dot(normal_b, edge)) < 1e-12);
            CHECK(norm(cross(unit(cross(normal_b, normal_a)), edge)) < 1e-12);
        }
    }
}

TEST_CASE("sat: shapes that touch get a depth of rounding size from the crossing arcs") {
    // Pairs of 8-point hulls moved along their normal until they touch: the smallest overlap
    // is about 0 (either sign), and the axes whose arcs do not cross, which SAT no longer
    // measures, tie with it within rounding at most.
    Random r{20261206};
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets{0};
    for (int s = 0; s < 24; ++s) {
        for (int i = 0; i < 8; ++i) {
            Vec3 q{r(), r(), r()};
            points.push_back(q / norm(q) * (0.6 + 0.2 * s / 24.0));
        }
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    }
    const PackedPolytopes p = pack_polytopes(points.data(), offsets.data(), 24, 1);
    fixtures::PolytopeSet packed(p);
    int touching = 0, gauss = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const int i = trial % 24, j = (trial * 7 + 3) % 24;
        ShapeView a = packed.view.shape(i), b = packed.view.shape(j);
        const Pose pa = random_pose(r, 2.0);
        Pose pb = random_pose(r, 2.0);
        const PairResult apart = query_pair(a, pa, b, pb, QueryKind::DISTANCE);
        if (!(apart.distance > 1e-3)) continue;
        pb.translation -= apart.normal * apart.distance;
        attach_edges(a);
        attach_edges(b);
        gauss += a.arcs != nullptr && b.arcs != nullptr;
        const SatResult got = sat_penetration(a, pa, b, pb);
        const SatResult want = every_axis(a, pa, b, pb);
        REQUIRE(got.ran);
        CHECK(got.depth <= 1e-13);
        CHECK(std::fabs(got.depth - want.depth) <= 1e-13);
        CHECK(got.axes < want.axes);
        ++touching;
    }
    CHECK(touching > 1500);
    CHECK_EQ(gauss, touching);
}
