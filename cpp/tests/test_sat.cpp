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

struct Random {
    std::uint64_t state;
    double uniform() {  // in [-1, 1)
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(state >> 11) * 0x1p-53 * 2.0 - 1.0;
    }
};

Pose random_pose(Random& r, double spread) {
    // a rotation from a random unit quaternion, placed within `spread` of the origin
    double q[4];
    double len = 0.0;
    do {
        len = 0.0;
        for (double& c : q) {
            c = r.uniform();
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
    p.translation = Vec3{r.uniform(), r.uniform(), r.uniform()} * spread;
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
        const Vec3 axes{0.4 + 0.4 * std::fabs(r.uniform()), 0.4 + 0.4 * std::fabs(r.uniform()),
                        0.4 + 0.4 * std::fabs(r.uniform())};
        for (int i = 0; i < n; ++i) {
            Vec3 p{r.uniform(), r.uniform(), r.uniform()};
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
    int compared = 0, deep = 0;
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
                }
        }
    }
    CHECK(compared > 10000);
    CHECK(deep > 1000);
    // The bound does skip: most axes of these pairs are never measured (a plain loop again,
    // or a bound that skips nothing, fails here).
    CHECK(measured * 2 < every);
}
