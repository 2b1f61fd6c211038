// The self-intersection pass of `meshcol inspect` (self_intersection.hpp).
//
// Collecting every pair of faces whose boxes overlap before testing them costs memory in the
// number of candidates, which is quadratic for a fan (a finely tessellated cylinder's caps:
// every face meets the centre) or a pile of faces through one point. So the sweep streams its
// candidates in blocks (sort_and_sweep_stream) and the thread that swept a block decides it at
// once (face_pair_crosses), keeping only the crossings: the memory is the faces' boxes and
// entries, a block per thread and the crossing pairs kept.
//
// The work budget is deterministic: blocks come in a fixed order that depends on the mesh
// alone, a block's work (its candidates, and the orientations of their tests that the filters
// could not decide, counted per thread by predicates::work_counters) is the same on any
// thread, and the pass counts the longest prefix of whole blocks whose work fits in the
// budget. Threads may run a block or two past it (they finish the blocks they took); those
// are left out, so the verdict, the counts and the pairs kept do not depend on the threads.
#include <algorithm>
#include <atomic>
#include <limits>
#include <mutex>

#include "meshcol/broadphase.hpp"
#include "meshcol/self_intersection.hpp"
#include "meshcol/triangle.hpp"
#include "predicates.hpp"

namespace meshcol {
namespace {

/// One block's tally.
struct BlockTally {
    std::int64_t block;       ///< the block's place in the sweep's order
    std::int64_t candidates;  ///< candidate pairs it held
    std::int64_t crossings;   ///< of which cross
    std::int64_t work;        ///< its work units
};

/// A crossing pair with its block: kept pairs are the first in (block, key) order, the order
/// the budget cuts in, so pruning to the first few never drops one a later cut would keep.
struct Crossing {
    std::int64_t block;
    std::uint64_t key;  ///< (i << 32) | j
    bool operator<(const Crossing& o) const { return block != o.block ? block < o.block : key < o.key; }
};

/// Keeps the first `keep` crossings in (block, key) order.
void keep_first(std::vector<Crossing>& crossings, size_t keep) {
    if (crossings.size() <= keep) return;
    std::nth_element(crossings.begin(), crossings.begin() + static_cast<std::ptrdiff_t>(keep), crossings.end());
    crossings.resize(keep);
}

/// The faces' closed bounding boxes as (m, 3) lo and hi arrays.
void face_boxes(const double* vertices, const std::int64_t* faces, std::int64_t m, std::vector<double>& lo,
                std::vector<double>& hi) {
    lo.resize(3 * static_cast<size_t>(m));
    hi.resize(3 * static_cast<size_t>(m));
    for (std::int64_t f = 0; f < m; ++f) {
        const double* a = vertices + 3 * faces[3 * f];
        const double* b = vertices + 3 * faces[3 * f + 1];
        const double* c = vertices + 3 * faces[3 * f + 2];
        for (int k = 0; k < 3; ++k) {
            lo[3 * f + k] = std::min(std::min(a[k], b[k]), c[k]);
            hi[3 * f + k] = std::max(std::max(a[k], b[k]), c[k]);
        }
    }
}

}  // namespace

SelfIntersectionOutput self_intersecting_pairs(const double* vertices, const std::int64_t* faces,
                                               std::int64_t face_count,
                                               const SelfIntersectionOptions& options) {
    SelfIntersectionOutput out;
    if (face_count < 2) return out;
    std::vector<double> lo, hi;
    face_boxes(vertices, faces, face_count, lo, hi);
    const std::int64_t budget = options.max_work;
    const size_t keep = options.max_kept_pairs < 0 ? std::numeric_limits<size_t>::max()
                                                   : static_cast<size_t>(options.max_kept_pairs);
    // With every pair kept (keep = SIZE_MAX) nothing is pruned: 2 * keep would wrap.
    const size_t max_pruned = (std::numeric_limits<size_t>::max() - 1024) / 2;
    std::atomic<std::int64_t> spent{0};
    std::mutex lock;
    std::vector<BlockTally> tallies;
    std::vector<Crossing> crossings;
    sort_and_sweep_stream(
        lo.data(), hi.data(), face_count, -1, options.threads, std::max<std::int64_t>(1, options.block_pairs),
        [&](std::int64_t block, const std::uint64_t* keys, std::int64_t count) {
            thread_local std::vector<std::uint64_t> found;
            found.clear();
            const predicates::WorkCounters before = predicates::work_counters;
            for (std::int64_t k = 0; k < count; ++k) {
                const std::uint64_t key = keys[k];
                if (face_pair_crosses(vertices, faces + 3 * static_cast<std::int64_t>(key >> 32),
                                      faces + 3 * static_cast<std::int64_t>(key & 0xFFFFFFFFu)))
                    found.push_back(key);
            }
            const auto crossed = static_cast<std::int64_t>(found.size());
            const predicates::WorkCounters& after = predicates::work_counters;
            const std::int64_t work = count + options.slow_cost * (after.slow - before.slow) +
                                      options.exact_cost * (after.exact - before.exact);
            if (found.size() > keep) {  // the first `keep` of this block in key order
                std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(keep), found.end());
                found.resize(keep);
            }
            {
                const std::lock_guard<std::mutex> hold(lock);
                tallies.push_back({block, count, crossed, work});
                // Past the pairs a cut could keep (the first `keep` of the blocks counted),
                // a block's crossings matter only for its tally.
                for (const std::uint64_t key : found) crossings.push_back({block, key});
                if (keep < max_pruned && crossings.size() > 2 * keep + 1024) keep_first(crossings, keep);
            }
            const std::int64_t total = spent.fetch_add(work) + work;
            return budget < 0 || total <= budget;
        });
    // The blocks consumed are a prefix of the order: count the longest run within the budget.
    std::sort(tallies.begin(), tallies.end(), [](const BlockTally& x, const BlockTally& y) { return x.block < y.block; });
    std::int64_t cut = std::numeric_limits<std::int64_t>::max();
    for (const BlockTally& t : tallies) {
        if (budget >= 0 && out.work + t.work > budget) {
            cut = t.block;
            out.complete = false;
            break;
        }
        out.candidate_count += t.candidates;
        out.work += t.work;
        out.crossing_count += t.crossings;
    }
    crossings.erase(std::remove_if(crossings.begin(), crossings.end(), [&](const Crossing& c) { return c.block >= cut; }),
                    crossings.end());
    keep_first(crossings, keep);
    std::vector<std::uint64_t> sorted(crossings.size());
    for (size_t q = 0; q < crossings.size(); ++q) sorted[q] = crossings[q].key;
    sort_pair_keys(sorted);
    out.pairs.resize(2 * sorted.size());
    for (size_t q = 0; q < sorted.size(); ++q) {
        out.pairs[2 * q] = static_cast<std::int64_t>(sorted[q] >> 32);
        out.pairs[2 * q + 1] = static_cast<std::int64_t>(sorted[q] & 0xFFFFFFFFu);
    }
    return out;
}

}  // namespace meshcol
