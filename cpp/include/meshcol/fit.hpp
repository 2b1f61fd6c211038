#pragma once
/// Enclosing primitives of point sets (sphere, capsule, box, cylinder), batched over sets.
///
/// Every fit starts from the set's exact hull (`exact_hull`), searches on its vertices in
/// normalised coordinates, and is then grown by the largest excess of ANY input point,
/// evaluated in the fit's own frame in the input's coordinates, plus
/// `defaults::fit_containment_margin` times the points' extent: every point is inside.

#include <cstdint>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// The primitives a fit makes, in the order of Python's `FIT_SHAPES` (never renumber).
enum class FitShape : std::int8_t { SPHERE = 0, CAPSULE = 1, BOX = 2, CYLINDER = 3 };

/// Outcome of one fit. Mirrored by `meshcol.collision.fit.FitStatus`: never renumber.
enum class FitStatus : std::int8_t {
    OK = 0,              ///< fitted; contains every point
    MAX_ITERATIONS = 1,  ///< fitted and contains every point, but a search cap was hit
    INVALID_INPUT = 2,   ///< no hull (empty, NaN/inf, overflow: `FitResult::hull_status`)
    FAILED = 3,          ///< the fit's numbers were not finite (never seen): no fit
};

/// One enclosing primitive, in the frame of the input points: `point = R local + center`.
struct PrimitiveFit {
    FitStatus status = FitStatus::INVALID_INPUT;
    /// sphere: radius; box: full sizes along local x, y, z; capsule: radius, segment length;
    /// cylinder: radius, length (capsule and cylinder along local z). NaN without a fit.
    double params[3] = {0.0, 0.0, 0.0};
    Mat3 rotation;   ///< local to input frame (columns: local axes)
    Vec3 center;     ///< input frame
    double volume = 0.0;
    double excess = 0.0;  ///< farthest point outside the searched primitive before growing (>= 0)
};

/// The hull and the fits of one point set.
struct FitSet {
    Hull hull;                       ///< the exact hull the fits start from
    std::vector<PrimitiveFit> fits;  ///< one per requested shape, in request order
};

/// The smallest ball holding `n` points of dimension `dimension` (1 to 3; `points` holds n
/// rows of `dimension` doubles): Welzl (1991), iterative, in a fixed pseudo-random order.
/// The radius is the exact largest distance from the centre. Returns false when the work
/// cap stopped the search (the radius still holds every point).
bool minimum_ball(const double* points, long long n, int dimension, double center[3],
                  double& radius);

/// Fits `shape_count` shapes to one set of `n` points.
FitSet fit_point_set(const Vec3* points, long long n, const FitShape* shapes, int shape_count);

/// Fits to H sets (set h owns `points[offsets[h] .. offsets[h + 1])`) on `threads` threads
/// (0: all cores). Deterministic: a set's fits do not depend on the batch or the threads.
std::vector<FitSet> fit_point_sets(const Vec3* points, const std::int64_t* offsets,
                                   long long sets, const FitShape* shapes, int shape_count,
                                   int threads);

}  // namespace meshcol
