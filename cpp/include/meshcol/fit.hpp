#pragma once
/// Enclosing primitives of point sets (sphere, capsule, box, cylinder, ellipsoid), batched
/// over sets.
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
enum class FitShape : std::int8_t { SPHERE = 0, CAPSULE = 1, BOX = 2, CYLINDER = 3, ELLIPSOID = 4 };

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
    /// cylinder: radius, length (capsule and cylinder along local z); ellipsoid: semi-axes
    /// along local x, y, z. NaN without a fit.
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

/// What `minimum_ellipsoid` found: an ellipsoid `{x : |diag(1 / semi_axes) R^T (x - center)|
/// <= 1}` that holds every point (up to the rounding of its evaluation).
struct EllipsoidSearch {
    Vec3 center;    ///< the points' frame
    Mat3 rotation;  ///< columns: the ellipsoid's axes (right-handed)
    /// Along the columns of `rotation`, descending, >= 0 (0 across a flat or collinear set).
    double semi_axes[3] = {0.0, 0.0, 0.0};
    int dimension = -1;        ///< the set's affine dimension the search ran in (0 to 3)
    double ratio_bound = 1.0;  ///< certified: volume (in `dimension`) <= this x the minimum
    int iterations = 0;        ///< Khachiyan steps taken
    bool converged = false;    ///< `ratio_bound` <= 1 + tolerance (false: the cap stopped it)
};

/// The minimum-volume enclosing ellipsoid of `n` points (all of them searched: pass a
/// hull's vertices), in their affine hull of dimension at most `dimension` (a flat set's
/// ellipsoid is flat): Khachiyan's method with Kumar-Yildirim's start and Todd-Yildirim's
/// drop steps, until the dual bound certifies a volume within (1 + `tolerance`) of the
/// minimum, or `max_iterations` steps. A segment (dimension 1) and a point are exact.
EllipsoidSearch minimum_ellipsoid(const Vec3* points, long long n, int dimension,
                                  double tolerance, int max_iterations);

/// Fits `shape_count` shapes to one set of `n` points.
FitSet fit_point_set(const Vec3* points, long long n, const FitShape* shapes, int shape_count);

/// Fits to H sets (set h owns `points[offsets[h] .. offsets[h + 1])`) on `threads` threads
/// (0: all cores). Deterministic: a set's fits do not depend on the batch or the threads.
std::vector<FitSet> fit_point_sets(const Vec3* points, const std::int64_t* offsets,
                                   long long sets, const FitShape* shapes, int shape_count,
                                   int threads);

}  // namespace meshcol
