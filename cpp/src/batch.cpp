#include "meshcol/batch.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace meshcol {

int hardware_threads() {
    // Read once: libstdc++ asks glibc's get_nprocs, which opens and reads
    // /sys/devices/system/cpu/online on every call (76 us a call on the project's VM), and
    // every batch whose caller leaves `threads` at 0 asks.
    static const int n = [] {
        const unsigned count = std::thread::hardware_concurrency();
        return count == 0 ? 1 : static_cast<int>(count);
    }();
    return n;
}

int resolve_threads(int requested, long long n, long long min_items) {
    int threads = requested <= 0 ? hardware_threads() : requested;
    const long long useful = std::max<long long>(1, n / std::max<long long>(1, min_items));
    return static_cast<int>(std::max<long long>(1, std::min<long long>(threads, useful)));
}

void parallel_for(long long n, int threads, const std::function<void(long long, long long)>& body) {
    if (n <= 0) return;
    if (threads <= 1) {
        body(0, n);
        return;
    }
    // Dynamic chunks, about 8 per thread: pairs differ a lot in cost (separated vs deep).
    const long long chunk = std::max<long long>(1, n / (static_cast<long long>(threads) * 8));
    std::atomic<long long> next{0};
    // An exception in any thread (std::bad_alloc when a result outgrows memory) stops the
    // others at their next chunk and is rethrown here once every thread has joined: a
    // joinable std::thread destroyed during unwinding would call std::terminate (abort,
    // exit 134) instead of reaching the binding, which turns it into a Python error.
    std::mutex failure_lock;
    std::exception_ptr failure;
    auto worker = [&]() {
        try {
            for (;;) {
                const long long begin = next.fetch_add(chunk);
                if (begin >= n) return;
                body(begin, std::min(n, begin + chunk));
            }
        } catch (...) {
            next.store(n);
            const std::lock_guard<std::mutex> hold(failure_lock);
            if (!failure) failure = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(static_cast<size_t>(threads - 1));
    try {
        for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    } catch (...) {  // a thread that cannot start: the started ones finish the work
        next.store(n);
        for (auto& t : pool) t.join();
        throw;
    }
    worker();
    for (auto& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
}

BatchShapes::BatchShapes(std::int64_t shape_count, const std::int64_t* pairs, long long pair_count)
    : pairs_(pairs) {
    const long long ends = 2 * pair_count;
    dense_ = ends * kSparseRatio >= shape_count;
    if (dense_) {
        slots_ = shape_count;
        used_.assign(static_cast<size_t>(shape_count), 0);
        for (long long e = 0; e < ends; ++e) used_[static_cast<size_t>(pairs[e])] = 1;
        return;
    }
    shapes_.assign(pairs, pairs + ends);
    std::sort(shapes_.begin(), shapes_.end());
    shapes_.erase(std::unique(shapes_.begin(), shapes_.end()), shapes_.end());
    slots_ = static_cast<std::int64_t>(shapes_.size());
    used_.assign(shapes_.size(), 1);
    ends_.resize(static_cast<size_t>(ends));
    for (long long e = 0; e < ends; ++e)
        ends_[static_cast<size_t>(e)] =
            std::lower_bound(shapes_.begin(), shapes_.end(), pairs[e]) - shapes_.begin();
}

}  // namespace meshcol
