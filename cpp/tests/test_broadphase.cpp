// Broad phase (broadphase.hpp): sort and sweep and the AABB tree against brute force.
#include <cstdint>
#include <mutex>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "check.hpp"
#include "meshcol/broadphase.hpp"

using namespace meshcol;

namespace {

struct Boxes {
    std::vector<double> lo, hi;
    std::int64_t size() const { return static_cast<std::int64_t>(lo.size() / 3); }
};

// n boxes of sizes up to `extent` in the cube [0, span]^3, seeded.
Boxes random_boxes(int n, double span, double extent, unsigned seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> position(0.0, span), size(0.0, extent);
    Boxes b;
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = position(random);
            b.lo.push_back(x);
            b.hi.push_back(x + size(random));
        }
    return b;
}

std::vector<std::int64_t> brute_force(const Boxes& b) {
    std::vector<std::int64_t> pairs;
    for (std::int64_t i = 0; i < b.size(); ++i)
        for (std::int64_t j = i + 1; j < b.size(); ++j) {
            bool overlap = true;
            for (int k = 0; k < 3; ++k)
                overlap = overlap && b.lo[3 * i + k] <= b.hi[3 * j + k] && b.lo[3 * j + k] <= b.hi[3 * i + k];
            if (overlap) pairs.insert(pairs.end(), {i, j});
        }
    return pairs;
}

std::vector<std::int64_t> from_keys(const std::vector<std::uint64_t>& keys) {
    std::vector<std::int64_t> pairs;
    for (const std::uint64_t key : keys)
        pairs.insert(pairs.end(), {static_cast<std::int64_t>(key >> 32), static_cast<std::int64_t>(key & 0xffffffffu)});
    return pairs;
}

}  // namespace

TEST_CASE("broad phase: sort and sweep finds exactly the brute-force pairs") {
    for (unsigned seed = 1; seed <= 5; ++seed) {
        const Boxes b = random_boxes(2000, 100.0, 4.0, seed);
        const std::vector<std::int64_t> expected = brute_force(b);
        CHECK(!expected.empty());
        for (int axis = -1; axis < 3; ++axis)
            CHECK(sort_and_sweep(b.lo.data(), b.hi.data(), b.size(), axis, 2) == expected);
    }
}

TEST_CASE("broad phase: touching boxes overlap, groups are never paired") {
    // three unit boxes in a row, each touching the next; 0 and 1 are one body
    const std::vector<double> lo = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    const std::vector<double> hi = {1, 1, 1, 2, 1, 1, 3, 1, 1};
    CHECK((sort_and_sweep(lo.data(), hi.data(), 3, -1, 1) == std::vector<std::int64_t>{0, 1, 1, 2}));
    const std::int64_t groups[3] = {7, 7, 8};
    CHECK((sort_and_sweep(lo.data(), hi.data(), 3, -1, 1, groups) == std::vector<std::int64_t>{1, 2}));
}

TEST_CASE("broad phase: a bad box is refused by name") {
    std::vector<double> lo = {0, 0, 0, 2, 0, 0}, hi = {1, 1, 1, 1, 1, 1};  // box 1: lo > hi
    CHECK_THROWS_AS(sort_and_sweep(lo.data(), hi.data(), 2, -1, 1), std::invalid_argument);
}

TEST_CASE("broad phase: incremental sort and sweep follows moving boxes") {
    Boxes b = random_boxes(1500, 60.0, 3.0, 11);
    SortAndSweep sweep(b.lo.data(), b.hi.data(), b.size(), -1, 2);
    CHECK(sweep.pairs() == brute_force(b));
    std::mt19937_64 random(12);
    std::uniform_real_distribution<double> step(-0.5, 0.5);
    for (int frame = 0; frame < 5; ++frame) {
        for (std::int64_t i = 0; i < b.size(); ++i)
            for (int k = 0; k < 3; ++k) {
                const double d = step(random);
                b.lo[3 * i + k] += d;
                b.hi[3 * i + k] += d;
            }
        CHECK(sweep.update(b.lo.data(), b.hi.data(), b.size()) == brute_force(b));
    }
}

TEST_CASE("broad phase: the AABB tree's pairs and queries, valid after edits") {
    const Boxes b = random_boxes(800, 40.0, 3.0, 21);
    AabbTree tree(0.1);
    tree.build(b.lo.data(), b.hi.data(), b.size(), 2);
    tree.validate();
    CHECK(from_keys(tree.query_pairs(2)) == brute_force(b));

    // move half the boxes, remove a few, insert them back: still exact and valid
    AabbTree edited(0.1);
    std::vector<std::int32_t> ids;
    for (std::int64_t i = 0; i < b.size(); ++i)
        ids.push_back(edited.insert({{b.lo[3 * i], b.lo[3 * i + 1], b.lo[3 * i + 2]},
                                     {b.hi[3 * i], b.hi[3 * i + 1], b.hi[3 * i + 2]}}));
    edited.validate();
    for (std::int64_t i = 0; i < b.size(); i += 2) edited.move(ids[static_cast<size_t>(i)], {{0, 0, 0}, {1, 1, 1}});
    for (std::int64_t i = 1; i < b.size(); i += 6) edited.remove(ids[static_cast<size_t>(i)]);  // odd ids
    edited.validate();
    edited.rebuild(2);
    edited.validate();
    const std::vector<std::int64_t> hits = edited.query({{0, 0, 0}, {1, 1, 1}});
    CHECK(hits.size() >= static_cast<size_t>(b.size() / 2));  // every moved box at least
}

TEST_CASE("broad phase: a cap on pairs stops the sweep, exactly at the count") {
    // A pile (every box overlaps every other: one grid cell, n(n-1)/2 pairs) and a scatter.
    Boxes pile;
    for (int i = 0; i < 400; ++i)
        for (int k = 0; k < 3; ++k) {
            pile.lo.push_back(0.001 * i);
            pile.hi.push_back(1.0 + 0.001 * i);
        }
    const Boxes scatter = random_boxes(2000, 100.0, 4.0, 7);
    for (const Boxes* b : {static_cast<const Boxes*>(&pile), &scatter}) {
        const std::vector<std::int64_t> all = brute_force(*b);
        const std::int64_t count = static_cast<std::int64_t>(all.size() / 2);
        for (int threads : {1, 2}) {
            bool exceeded = true;
            // At the count: every pair, not exceeded.
            CHECK(sort_and_sweep(b->lo.data(), b->hi.data(), b->size(), -1, threads, nullptr, count,
                                 &exceeded) == all);
            CHECK(!exceeded);
            // One under: stopped, no pairs.
            const std::vector<std::int64_t> none =
                sort_and_sweep(b->lo.data(), b->hi.data(), b->size(), -1, threads, nullptr, count - 1, &exceeded);
            CHECK(exceeded);
            CHECK(none.empty());
            // A cap of 0 on a scene with pairs.
            sort_and_sweep(b->lo.data(), b->hi.data(), b->size(), -1, threads, nullptr, 0, &exceeded);
            CHECK(exceeded);
        }
    }
    CHECK(brute_force(pile).size() / 2 == 400 * 399 / 2);
}

TEST_CASE("broad phase: the streamed sweep hands out brute force's pairs in a prefix of blocks") {
    // a pile of large boxes (one crowded cell, split into many blocks) and a spread cloud
    for (const auto& [n, extent] : {std::pair<int, double>{300, 60.0}, std::pair<int, double>{3000, 3.0}}) {
        const Boxes b = random_boxes(n, 100.0, extent, 11u);
        const std::vector<std::int64_t> expected = brute_force(b);
        for (const int threads : {1, 2})
            for (const std::int64_t block_pairs : {std::int64_t{1}, std::int64_t{50}, std::int64_t{65536}}) {
                std::mutex lock;
                std::vector<std::vector<std::uint64_t>> blocks;
                const std::int64_t count = sort_and_sweep_stream(
                    b.lo.data(), b.hi.data(), b.size(), -1, threads, block_pairs,
                    [&](std::int64_t block, const std::uint64_t* keys, std::int64_t k) {
                        const std::lock_guard<std::mutex> hold(lock);
                        if (static_cast<std::int64_t>(blocks.size()) <= block) blocks.resize(block + 1);
                        blocks[block].assign(keys, keys + k);
                        return true;
                    });
                CHECK_EQ(static_cast<std::int64_t>(blocks.size()), count);
                std::vector<std::uint64_t> keys;
                for (const auto& block : blocks) keys.insert(keys.end(), block.begin(), block.end());
                sort_pair_keys(keys);
                std::vector<std::int64_t> pairs;
                for (const std::uint64_t key : keys)
                    pairs.insert(pairs.end(), {static_cast<std::int64_t>(key >> 32),
                                               static_cast<std::int64_t>(key & 0xFFFFFFFFu)});
                CHECK(pairs == expected);
                // stopping at a block: the blocks consumed are a prefix of the order
                std::vector<char> seen(static_cast<size_t>(count), 0);
                const std::int64_t stop_at = count / 3;
                sort_and_sweep_stream(b.lo.data(), b.hi.data(), b.size(), -1, threads, block_pairs,
                                      [&](std::int64_t block, const std::uint64_t*, std::int64_t) {
                                          const std::lock_guard<std::mutex> hold(lock);
                                          seen[static_cast<size_t>(block)] = 1;
                                          return block != stop_at;
                                      });
                std::int64_t prefix = 0;
                while (prefix < count && seen[static_cast<size_t>(prefix)]) ++prefix;
                CHECK(prefix > stop_at);
                for (std::int64_t k = prefix; k < count; ++k) CHECK(!seen[static_cast<size_t>(k)]);
                if (block_pairs == 1) CHECK(count > 100);
            }
    }
}
