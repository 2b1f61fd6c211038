// parallel_for (batch.hpp): an exception in any thread reaches the caller, never std::terminate.
#include <atomic>
#include <new>
#include <stdexcept>

#include "check.hpp"
#include "meshcol/batch.hpp"

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
