// parallel_for (batch.hpp): an exception in any thread reaches the caller, never std::terminate;
// BatchShapes, and the batches that use it answering a pair the same whichever way it goes.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <new>
#include <random>
#include <stdexcept>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/batch.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/toi.hpp"

using namespace meshcol;

TEST_CASE("batch: an exception in a worker thread is rethrown to the caller") {
    for (int threads : {1, 2, 4}) {
        std::atomic<long long> done{0};
        CHECK_THROWS_AS(parallel_for(1000, threads,
                                     [&](long long begin, long long end) {
                                         if (begin <= 500 && 500 < end) throw std::bad_alloc();
                                         done += end - begin;
                                     }),
                        std::bad_alloc);
        CHECK(done.load() < 1000);
    }
}

TEST_CASE("batch: every item runs once when nothing throws") {
    std::atomic<long long> sum{0};
    parallel_for(10000, 4, [&](long long begin, long long end) {
        for (long long i = begin; i < end; ++i) sum += i;
    });
    CHECK_EQ(sum.load(), 10000LL * 9999 / 2);
}

TEST_CASE("batch shapes: dense slots are the shapes, sparse slots the distinct shapes named") {
    const std::int64_t pairs[6] = {7, 3, 3, 90, 5, 5};
    BatchShapes sparse(100, pairs, 3);  // 6 ends x 8 < 100
    REQUIRE(!sparse.dense());
    REQUIRE(sparse.size() == 4);
    const std::int64_t shapes[4] = {3, 5, 7, 90};
    const std::vector<char> named = sparse.take_used();
    REQUIRE(named.size() == 4);
    for (int k = 0; k < 4; ++k) {
        CHECK_EQ(sparse.shape(k), shapes[k]);
        CHECK(named[k] == 1);
    }
    for (int e = 0; e < 6; ++e) CHECK_EQ(sparse.shape(sparse.slot_of(e)), pairs[e]);
    // 4 ends x 8 >= 32 shapes: every shape a slot, the named ones marked.
    const std::int64_t few[4] = {7, 3, 3, 7};
    BatchShapes dense(32, few, 2);
    REQUIRE(dense.dense());
    REQUIRE(dense.size() == 32);
    for (int e = 0; e < 4; ++e) CHECK_EQ(dense.slot_of(e), few[e]);
    const std::vector<char> marked = dense.take_used();
    REQUIRE(marked.size() == 32);
    for (int h = 0; h < 32; ++h) CHECK(marked[h] == (h == 3 || h == 7 ? 1 : 0));
    CHECK(!BatchShapes(33, few, 2).dense());
    CHECK_EQ(BatchShapes(10, nullptr, 0).size(), 0);
}

namespace {

// 400 primitives (spheres, boxes, capsules, cylinders) scattered in a cube of side 6 under
// turned poses: shape 5 has a NaN radius and shape 11 a pose scaled by two. A batch of
// `few` pairs over them is sparse (BatchShapes), the same pairs followed by 40 more dense.
struct Scene {
    static constexpr int kShapes = 400;
    std::vector<std::int64_t> offsets = std::vector<std::int64_t>(kShapes + 1, 0);
    std::vector<std::int8_t> kinds;
    std::vector<double> params, start, end;
    std::vector<std::int64_t> pairs;
    long long few = 0;

    Scene() {
        std::mt19937_64 random(20261205);
        std::uniform_real_distribution<double> unit(-1.0, 1.0);
        for (int h = 0; h < kShapes; ++h) {
            kinds.push_back(static_cast<std::int8_t>(1 + h % 4));
            params.insert(params.end(), {0.3 + 0.2 * std::fabs(unit(random)),
                                         0.2 + 0.3 * std::fabs(unit(random)),
                                         0.2 + 0.3 * std::fabs(unit(random)), 0.0});
            for (std::vector<double>* poses : {&start, &end}) {
                const Vec3 axis{unit(random), unit(random), unit(random) + 1.5};
                const Mat3 r = axis_angle_matrix(axis / norm(axis), 3.0 * unit(random));
                const double t[3] = {3 * unit(random), 3 * unit(random), 3 * unit(random)};
                for (int i = 0; i < 3; ++i)
                    poses->insert(poses->end(), {r.m[i][0], r.m[i][1], r.m[i][2], t[i]});
                poses->insert(poses->end(), {0.0, 0.0, 0.0, 1.0});
            }
        }
        params[4 * 5] = std::nan("");
        for (int k = 0; k < 3; ++k) start[16 * 11 + 5 * k] *= 2.0;
        // Few pairs: repeats, a shape with itself, the bad shape and the bad pose.
        pairs = {0, 1, 1, 2, 2, 399, 5, 6, 11, 12, 7, 7, 30, 31, 31, 30, 200, 201, 0, 350};
        few = static_cast<long long>(pairs.size() / 2);
        for (int i = 0; i < 40; ++i)
            pairs.insert(pairs.end(), {static_cast<std::int64_t>(random() % kShapes),
                                       static_cast<std::int64_t>(random() % kShapes)});
    }

    ConvexSetView view() const {
        return fixtures::convex_set(offsets.data(), kinds.data(), params.data(), kShapes);
    }
    long long all() const { return static_cast<long long>(pairs.size() / 2); }
};

// The first `count` rows of two arrays of `width` values a row are equal bit for bit.
template <typename T>
bool same_rows(const std::vector<T>& a, const std::vector<T>& b, long long count, int width) {
    return std::memcmp(a.data(), b.data(), sizeof(T) * static_cast<size_t>(count * width)) == 0;
}

}  // namespace

TEST_CASE("batch shapes: a pair's narrow-phase row is the same in a sparse and a dense batch") {
    const Scene scene;
    REQUIRE(!BatchShapes(Scene::kShapes, scene.pairs.data(), scene.few).dense());
    REQUIRE(BatchShapes(Scene::kShapes, scene.pairs.data(), scene.all()).dense());
    for (QueryKind kind : {QueryKind::DISTANCE, QueryKind::PENETRATION}) {
        for (const double* poses : {scene.start.data(), static_cast<const double*>(nullptr)}) {
            struct Rows {
                std::vector<double> distance, depth, normal, point_a, point_b;
                std::vector<std::int32_t> iterations;
                std::vector<std::int8_t> status;
            } rows[2];
            for (int r = 0; r < 2; ++r) {
                const long long count = r == 0 ? scene.few : scene.all();
                Rows& x = rows[r];
                x.distance.resize(count), x.depth.resize(count), x.iterations.resize(count);
                x.status.resize(count), x.normal.resize(3 * count);
                x.point_a.resize(3 * count), x.point_b.resize(3 * count);
                BatchOutput out;
                out.distance = x.distance.data(), out.depth = x.depth.data();
                out.normal = x.normal.data(), out.point_a = x.point_a.data();
                out.point_b = x.point_b.data(), out.iterations = x.iterations.data();
                out.status = x.status.data();
                run_batch(scene.view(), poses, scene.pairs.data(), count, kind, 2, out);
            }
            const long long n = scene.few;
            CHECK(same_rows(rows[0].distance, rows[1].distance, n, 1));
            CHECK(same_rows(rows[0].depth, rows[1].depth, n, 1));
            CHECK(same_rows(rows[0].normal, rows[1].normal, n, 3));
            CHECK(same_rows(rows[0].point_a, rows[1].point_a, n, 3));
            CHECK(same_rows(rows[0].point_b, rows[1].point_b, n, 3));
            CHECK(same_rows(rows[0].iterations, rows[1].iterations, n, 1));
            CHECK(same_rows(rows[0].status, rows[1].status, n, 1));
            // The bad shape's pair, and the bad pose's when there are poses, are invalid.
            const auto invalid = static_cast<std::int8_t>(Status::INVALID_INPUT);
            CHECK(rows[0].status[3] == invalid);
            CHECK((rows[0].status[4] == invalid) == (poses != nullptr));
            CHECK(rows[0].status[0] != invalid);
        }
    }
}

TEST_CASE("batch shapes: a pair's time of impact is the same in a sparse and a dense batch") {
    const Scene scene;
    for (const bool turns : {false, true}) {
        // Turns given: each shape's shortest rotation, about a point beside its origin.
        std::vector<double> rotations, pivots;
        for (int h = 0; h < Scene::kShapes; ++h) {
            Mat3 r0, r1;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    r0.m[i][j] = scene.start[16 * h + 4 * i + j];
                    r1.m[i][j] = scene.end[16 * h + 4 * i + j];
                }
            const Vec3 turn = shortest_rotation(r0, r1);
            rotations.insert(rotations.end(), {turn.x, turn.y, turn.z});
            pivots.insert(pivots.end(), {scene.start[16 * h + 3] + 0.5, scene.start[16 * h + 7],
                                         scene.start[16 * h + 11]});
        }
        struct Rows {
            std::vector<double> toi, point, normal;
            std::vector<std::int32_t> iterations;
            std::vector<std::int8_t> status;
        } rows[2];
        for (int r = 0; r < 2; ++r) {
            const long long count = r == 0 ? scene.few : scene.all();
            Rows& x = rows[r];
            x.toi.resize(count), x.iterations.resize(count), x.status.resize(count);
            x.point.resize(3 * count), x.normal.resize(3 * count);
            ToiBatchOutput out;
            out.toi = x.toi.data(), out.point = x.point.data(), out.normal = x.normal.data();
            out.iterations = x.iterations.data(), out.status = x.status.data();
            run_toi_batch(scene.view(), scene.start.data(), scene.end.data(),
                          turns ? rotations.data() : nullptr, turns ? pivots.data() : nullptr,
                          scene.pairs.data(), count, ToiOptions{}, 2, out);
        }
        const long long n = scene.few;
        CHECK(same_rows(rows[0].toi, rows[1].toi, n, 1));
        CHECK(same_rows(rows[0].point, rows[1].point, n, 3));
        CHECK(same_rows(rows[0].normal, rows[1].normal, n, 3));
        CHECK(same_rows(rows[0].iterations, rows[1].iterations, n, 1));
        CHECK(same_rows(rows[0].status, rows[1].status, n, 1));
        const auto invalid = static_cast<std::int8_t>(TimeOfImpactStatus::INVALID_INPUT);
        CHECK(rows[0].status[3] == invalid);
        CHECK(rows[0].status[4] == invalid);
        CHECK(rows[0].status[0] != invalid);
    }
}
