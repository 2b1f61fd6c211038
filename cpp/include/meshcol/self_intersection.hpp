#pragma once
/// Self-intersections of one triangle mesh: which pairs of its faces cross (`triangles_cross`),
/// found by streaming the face boxes' overlapping pairs (`sort_and_sweep_stream`) into the
/// exact test, so the memory held is the faces' and the crossing pairs kept, never every
/// candidate pair (a fan of n faces around one vertex has n^2 / 2), and with a work budget.

#include <cstdint>
#include <vector>

#include "meshcol/defaults.hpp"

namespace meshcol {

/// What the pass may spend and keep.
struct SelfIntersectionOptions {
    /// Work units spent at most (< 0: no budget): one per candidate pair, plus `slow_cost` per
    /// orientation its filter could not decide and `exact_cost` more per one evaluated
    /// exactly (predicates::work_counters), so the budget bounds the time, whatever the mesh.
    /// The candidates come in a fixed order (the sweep's blocks, which depend on the mesh
    /// alone) and each block's work is the same on any thread; past the budget the pass keeps
    /// the longest run of whole blocks within it and stops.
    std::int64_t max_work = defaults::self_intersection_max_work;
    std::int64_t slow_cost = defaults::self_intersection_slow_cost;    ///< units, >= 0
    std::int64_t exact_cost = defaults::self_intersection_exact_cost;  ///< units, >= 0
    /// Crossing pairs returned at most (< 0: all): the first found in the candidates' order.
    std::int64_t max_kept_pairs = defaults::self_intersection_max_kept_pairs;
    /// Candidate pairs per block of the sweep (>= 1).
    std::int64_t block_pairs = defaults::self_intersection_block_pairs;
    int threads = 0;  ///< <= 0: all cores
};

/// The crossing pairs of a mesh.
struct SelfIntersectionOutput {
    /// Crossing face pairs [i0, j0, i1, j1, ...], i < j, sorted; at most max_kept_pairs of them.
    std::vector<std::int64_t> pairs;
    std::int64_t crossing_count = 0;   ///< crossing pairs among the candidates decided (not capped)
    std::int64_t candidate_count = 0;  ///< candidate pairs decided
    std::int64_t work = 0;             ///< work units of the blocks counted (<= max_work)
    /// Every candidate pair was decided: crossing_count is the mesh's exact count. Otherwise
    /// it is a lower bound (and with 0 the verdict is undecided).
    bool complete = true;
};

/// The pairs of faces of a mesh that cross (`face_pair_crosses`: duplicates do not), decided
/// exactly. `vertices` (n, 3), `faces` (m, 3) indices into it, every index checked by the
/// caller and every coordinate finite. Candidates are the face pairs whose closed bounding
/// boxes overlap; each is decided as the sweep produces it, on `options.threads` threads. The
/// result does not depend on the number of threads.
SelfIntersectionOutput self_intersecting_pairs(const double* vertices, const std::int64_t* faces,
                                               std::int64_t face_count,
                                               const SelfIntersectionOptions& options = {});

}  // namespace meshcol
