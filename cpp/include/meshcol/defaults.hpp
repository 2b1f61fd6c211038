#pragma once
/// Every default and cap of the core, in one place (as coal's narrowphase_defaults.h).
/// Exposed to Python as `meshcol._core.defaults`.

namespace meshcol::defaults {

/// Relative tolerance of pose rigidity checks (orthonormality, determinant, last row).
constexpr double rigid_tolerance = 1e-6;

/// Batches smaller than this run on the calling thread: starting threads costs more.
constexpr long long min_pairs_per_thread = 64;

}  // namespace meshcol::defaults
