#pragma once
/// Running a loop body over [0, n) on several threads, for the batched queries.

#include <cstddef>
#include <functional>

namespace meshcol {

/// Number of hardware threads (at least 1).
int hardware_threads();

/// Resolves a user's `threads` option: 0 or negative means all cores; never more than the
/// work can use (`n / min_items` chunks).
int resolve_threads(int requested, long long n, long long min_items);

/// Calls `body(begin, end)` over disjoint chunks covering [0, n) on `threads` threads (the
/// calling thread takes part). Chunks are handed out dynamically so uneven pairs balance.
/// `body` must not throw.
void parallel_for(long long n, int threads, const std::function<void(long long, long long)>& body);

}  // namespace meshcol
