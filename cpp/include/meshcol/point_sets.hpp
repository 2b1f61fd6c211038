#pragma once
/// Fingerprints of packed point sets: what finds repeated geometry among 100,000 files' sets
/// in one pass (meshcol/analysis/bulk_colliders.py), a match then confirmed bit for bit.

#include <cstdint>

namespace meshcol {

/// The fingerprint of each of `sets` point sets packed in `points` (3 doubles a point), set
/// s being points [offsets[s], offsets[s + 1]). Each point's coordinates are read as their
/// 64-bit patterns x, y, z; with wrap-around (mod 2^64) arithmetic, the point mixes to
/// m = x * 0xBF58476D1CE4E5B9 + y * 0x94D049BB133111EB + z * 0xD6E8FEB86659FD93,
/// m ^= m >> 29, weighed by its place k in its set: m * (2k + 1); the set's fingerprint is the
/// sum over its points (0 for an empty set). On `threads` threads (0: all cores).
void point_set_fingerprints(const double* points, const std::int64_t* offsets,
                            std::int64_t sets, int threads, std::uint64_t* out);

}  // namespace meshcol
