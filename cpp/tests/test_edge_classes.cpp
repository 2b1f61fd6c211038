// The edge-direction classes SAT computes when it first needs them (narrowphase.hpp:
// EdgeClasses): on threads that ask for the same shapes at once, every thread gets the classes
// computed alone, byte for byte; and SAT's work bound, deciding on lower bounds of the class
// counts, decides as it does with every shape's classes attached.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <thread>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/sat.hpp"

using namespace meshcol;

namespace {

std::uint64_t next(std::uint64_t& state) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return state >> 11;
}

double uniform(std::uint64_t& state) {  // in [-1, 1)
    return static_cast<double>(next(state)) * 0x1p-53 * 2.0 - 1.0;
}

// Shapes whose class counts span SAT's work bound: smooth hulls of 8 to 96 points (every
// point a vertex: the bound needs the classes of the small ones only), clouds, lattice points
// (parallel edges: fewer classes than edges), a polygon, a segment, a point.
struct Shapes {
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets{0};
    PackedPolytopes packed;

    explicit Shapes(int count) {
        std::uint64_t state = 5;
        for (int h = 0; h < count; ++h) {
            const int family = h % 6;
            const int n = family == 3 ? 12 : family == 4 ? 2 : family == 5 ? 1 : 8 + (h * 7) % 90;
            for (int i = 0; i < n; ++i) {
                Vec3 q{uniform(state), uniform(state), uniform(state)};
                if (family == 0 || family == 1) q = q / norm(q);
                if (family == 2) q = Vec3{std::floor(3 * q.x), std::floor(3 * q.y), std::floor(3 * q.z)};
                if (family == 3) q.z = 0.25 * q.x - 0.5 * q.y;
                points.push_back(q);
            }
            offsets.push_back(static_cast<std::int64_t>(points.size()));
        }
        packed = pack_polytopes(points.data(), offsets.data(), count, 1);
    }

    // Shape h's classes computed alone (what the packing stored before they were lazy).
    std::vector<double> alone(std::int64_t h) const {
        std::vector<double> out;
        const std::int64_t first = packed.edge_pair_offsets[h];
        edge_direction_classes(reinterpret_cast<const Vec3*>(packed.vertices.data()) +
                                   packed.offsets[h],
                               packed.edge_pairs.data() + 2 * first,
                               static_cast<size_t>(packed.edge_pair_offsets[h + 1] - first), out);
        return out;
    }
};

bool same_bytes(const double* a, const double* b, size_t count) {
    return count == 0 || std::memcmp(a, b, count * sizeof(double)) == 0;
}

}  // namespace

TEST_CASE("edge classes: threads asking for the same shapes at once get the classes alone") {
    const Shapes s(240);
    const auto h_count = s.packed.status.size();
    constexpr int kThreads = 4;
    // Round 0: every thread walks the shapes in the same order, started together, so they
    // meet each uncomputed shape at about the same moment; round 1: in different orders.
    for (int round = 0; round < 2; ++round) {
        fixtures::PolytopeSet fresh(s.packed);
        EdgeClasses& classes = fresh.classes;
        const ConvexSetView& set = fresh.view;
        std::vector<std::vector<EdgeClasses::List>> got(kThreads,
                                                        std::vector<EdgeClasses::List>(h_count));
        std::vector<std::vector<int>> bounds(kThreads, std::vector<int>(h_count, -1));
        auto wanted = [](size_t h, int t) { return 1 + static_cast<int>((h * 5 + 3 * t) % 40); };
        std::atomic<int> ready{0};
        std::vector<std::thread> threads;
        for (int t = 0; t < kThreads; ++t)
            threads.emplace_back([&, t]() {
                ready.fetch_add(1);
                while (ready.load() < kThreads) std::this_thread::yield();
                for (size_t k = 0; k < h_count; ++k) {
                    const size_t h = round == 0 ? k : (k * 7 + 61 * static_cast<size_t>(t)) % h_count;
                    // half the threads ask for the bound first (which may compute the classes)
                    if ((t + static_cast<int>(h)) % 2 == 0)
                        bounds[t][h] =
                            classes.lower_bound(set, static_cast<std::int64_t>(h), wanted(h, t));
                    got[t][h] = classes.get(set, static_cast<std::int64_t>(h));
                }
            });
        for (std::thread& t : threads) t.join();
        int checked = 0, bounded = 0;
        for (size_t h = 0; h < h_count; ++h) {
            const std::vector<double> want = s.alone(static_cast<std::int64_t>(h));
            const std::int64_t pairs = s.packed.edge_pair_offsets[h + 1] - s.packed.edge_pair_offsets[h];
            for (int t = 0; t < kThreads; ++t) {
                const EdgeClasses::List& l = got[t][h];
                // one list for every thread: the first published
                CHECK(l.directions == got[0][h].directions);
                REQUIRE(static_cast<size_t>(3 * l.count) == want.size());
                CHECK(same_bytes(reinterpret_cast<const double*>(l.directions), want.data(),
                                 want.size()));
                if (bounds[t][h] >= 0) {
                    // a bound, and at least the wanted count when the prefix holds it
                    const std::int64_t prefix = std::min<std::int64_t>(
                        pairs, std::max(wanted(h, t), defaults::sat_edge_class_prefix));
                    const std::int64_t first = s.packed.edge_pair_offsets[h];
                    const std::int64_t in_prefix = edge_direction_class_count(
                        reinterpret_cast<const Vec3*>(s.packed.vertices.data()) + s.packed.offsets[h],
                        s.packed.edge_pairs.data() + 2 * first, static_cast<size_t>(prefix));
                    CHECK(bounds[t][h] <= l.count);
                    CHECK(bounds[t][h] >= std::min<std::int64_t>(wanted(h, t), in_prefix));
                    if (4 * prefix >= 3 * pairs) CHECK_EQ(bounds[t][h], l.count);
                    bounded += bounds[t][h] < l.count;
                }
                ++checked;
            }
        }
        CHECK_EQ(checked, kThreads * static_cast<int>(h_count));
        CHECK(bounded > 0);  // the bound of a long edge list is below its count
        // All shapes at once, through the same cache: the concatenation of the lists alone.
        std::vector<std::int64_t> offsets;
        std::vector<double> directions;
        all_edge_classes(set, 2, offsets, directions);
        REQUIRE(offsets.size() == h_count + 1);
        for (size_t h = 0; h < h_count; ++h) {
            const std::vector<double> want = s.alone(static_cast<std::int64_t>(h));
            REQUIRE(static_cast<size_t>(3 * (offsets[h + 1] - offsets[h])) == want.size());
            CHECK(same_bytes(directions.data() + 3 * offsets[h], want.data(), want.size()));
        }
    }
}

TEST_CASE("edge classes: SAT's work bound decides on lower bounds as on the classes") {
    // Every pair of shapes (and a box) under the default work bound: SAT on views whose
    // classes it computes when the bound needs them against views with them attached. The
    // same verdict (ran or not) and the same answer bits; and the classes of shapes whose
    // pairs never run stay uncomputed for the most part.
    const Shapes s(120);
    fixtures::PolytopeSet lazy_set(s.packed), attached(s.packed);
    EdgeClasses& classes = lazy_set.classes;
    const ConvexSetView& set = lazy_set.view;
    EdgeClasses& attached_classes = attached.classes;
    const ConvexSetView& attached_set = attached.view;
    std::vector<ShapeView> lazy, whole;
    for (std::int64_t h = 0; h < set.shape_count; ++h) {
        lazy.push_back(set.shape(h));
        ShapeView w = attached_set.shape(h);
        attach_edges(w);
        whole.push_back(w);
    }
    lazy.push_back(fixtures::box(0.3, 0.5, 0.2));
    whole.push_back(lazy.back());
    Pose pose_b;
    pose_b.translation = Vec3{0.1, -0.05, 0.02};
    int ran = 0, skipped = 0;
    auto compare = [&](size_t i, size_t j) {
        const SatResult want = sat_penetration(whole[i], Pose{}, whole[j], pose_b);
        const SatResult got = sat_penetration(lazy[i], Pose{}, lazy[j], pose_b);
        REQUIRE(got.ran == want.ran);
        CHECK(got.separated == want.separated);
        CHECK_EQ(got.axes, want.axes);
        CHECK(std::memcmp(&got.depth, &want.depth, sizeof got.depth) == 0);
        CHECK(std::memcmp(&got.normal, &want.normal, sizeof got.normal) == 0);
        ran += want.ran;
        skipped += !want.ran && has_sat_features(whole[i]) && has_sat_features(whole[j]);
    };
    // First the pairs of smooth hulls, clouds, lattices and points (families 0, 1, 2, 5). Their
    // smooth hulls of 64 points and more meet none whose SAT runs with them: the bound (its
    // prefix, or a point's lack of edges) settled their pairs, and their classes were never
    // computed (lower_bound of a computed shape is its count; of an uncomputed one, with more
    // edges than the prefix, at most the prefix).
    const size_t box = lazy.size() - 1;
    auto first = [](size_t h) { return h % 6 < 3 || h % 6 == 5; };
    for (size_t i = 0; i < box; ++i)
        for (size_t j = 0; j < box; ++j)
            if (first(i) && first(j)) compare(i, j);
    int smooth = 0, uncomputed = 0;
    for (std::int64_t h = 0; h < set.shape_count; ++h) {
        if (h % 6 > 1 || s.packed.offsets[h + 1] - s.packed.offsets[h] < 64) continue;
        ++smooth;
        uncomputed += classes.lower_bound(set, h, 1) < attached_classes.get(attached_set, h).count;
    }
    CHECK(smooth > 5);
    CHECK_EQ(uncomputed, smooth);
    // Then the rest: segments (SAT runs with a 64-point hull), polygons and a box.
    for (size_t i = 0; i < lazy.size(); ++i)
        for (size_t j = 0; j < lazy.size(); ++j)
            if (!first(i) || !first(j)) compare(i, j);
    CHECK(ran > 1000);
    CHECK(skipped > 1000);
}
