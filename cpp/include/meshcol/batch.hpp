#pragma once
/// Running a loop body over [0, n) on several threads, for the batched queries, and the
/// shapes a batch of pairs uses.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace meshcol {

/// Number of hardware threads (at least 1), read once per process.
int hardware_threads();

/// Resolves a user's `threads` option: 0 or negative means all cores; never more than the
/// work can use (`n / min_items` chunks).
int resolve_threads(int requested, long long n, long long min_items);

/// Calls `body(begin, end)` over disjoint chunks covering [0, n) on `threads` threads (the
/// calling thread takes part). Chunks are handed out dynamically so uneven pairs balance.
/// `body` must not throw.
void parallel_for(long long n, int threads, const std::function<void(long long, long long)>& body);

/// The shapes that a batch of (P, 2) pairs over a set of `shape_count` shapes uses, as slots
/// of the batch's per-shape state (checked poses, motions, flags). When the pairs name a good
/// share of the set, every shape is a slot (slot = shape index) and `take_used` marks the ones
/// named. When they name few (2P * kSparseRatio < shape_count), the slots are only the
/// distinct shapes named, ascending: a few pairs on a set of a million shapes then cost what
/// those pairs need, not a pass over the whole set. Either way a pair's results do not depend
/// on which it is. Pair indices must be in range.
class BatchShapes {
  public:
    /// The sparse case holds at most one slot for this many shapes of the set.
    static constexpr long long kSparseRatio = 8;

    BatchShapes(std::int64_t shape_count, const std::int64_t* pairs, long long pair_count);

    /// Number of slots.
    std::int64_t size() const { return slots_; }
    /// The shape of `slot`.
    std::int64_t shape(std::int64_t slot) const { return dense() ? slot : shapes_[slot]; }
    /// The slot of pair end `end` (pair i's shapes are ends 2i and 2i + 1).
    std::int64_t slot_of(long long end) const { return dense() ? pairs_[end] : ends_[end]; }
    /// Per slot, 1 when a pair names its shape (every slot of a sparse batch): handed over,
    /// not copied, as the batch's own per-slot flags (empty after the first call).
    std::vector<char> take_used() { return std::move(used_); }
    bool dense() const { return dense_; }

  private:
    const std::int64_t* pairs_;
    bool dense_ = true;
    std::int64_t slots_ = 0;
    std::vector<std::int64_t> shapes_;  // sparse: shape of each slot, ascending
    std::vector<std::int64_t> ends_;    // sparse: slot of each pair end
    std::vector<char> used_;
};

}  // namespace meshcol
