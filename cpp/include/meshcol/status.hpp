#pragma once
/// Per-query outcome codes, mirrored one to one by the Python enums in `meshcol/types.py`.
/// The numeric values are part of the binary interface: never renumber.

#include <cstdint>

namespace meshcol {

/// Outcome of a distance, penetration or intersection query on one pair.
enum class Status : std::int8_t {
    CONVERGED = 0,       ///< the answer meets the tolerance
    MAX_ITERATIONS = 1,  ///< the iteration cap was hit; fields hold the best bound found
    DEGENERATE = 2,      ///< numerical trouble (e.g. a flat simplex); fields are a best effort
    INVALID_INPUT = 3,   ///< NaN/inf coordinates, an empty shape or a non-rigid pose
    NOT_RUN = 4,         ///< the query did not run for this pair
    OUT_OF_RANGE = 5,    ///< the answer (a distance or point) is beyond the range of a double
};

/// Outcome of a time-of-impact query on one pair.
enum class TimeOfImpactStatus : std::int8_t {
    HIT = 0,                  ///< first contact at `toi` in [0, 1]
    SEPARATED = 1,            ///< no contact during the whole motion
    OVERLAPPED_AT_START = 2,  ///< already touching or overlapping at t = 0
    FAILED = 3,               ///< iteration cap hit; `toi` is a safe lower bound
    INVALID_INPUT = 4,        ///< NaN/inf coordinates, an empty shape, a non-rigid pose, a
                              ///< turn that misses the end rotation, or lengths over DBL_MAX
};

}  // namespace meshcol
