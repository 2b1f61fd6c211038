#pragma once
/// Enclosing primitives of point sets (sphere, capsule, box, cylinder), batched over sets.
///
/// Every fit starts from the set's exact hull (`exact_hull`), searches on its vertices in
/// normalised coordinates, and is then grown by the largest excess of ANY input point,
/// evaluated in the fit's own frame in the input's coordinates, plus
/// `defaults::fit_containment_margin` times the points' extent: every point is inside.

#include <cstdint>
#include <vector>

#include "meshcol/hull.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

namespace defaults {

/// Relative margin (times the points' extent, at least 1e-6 of their largest coordinate)
/// every fit keeps beyond its farthest point. Mirrored by `CONTAINMENT_MARGIN` in Python.
constexpr double fit_containment_margin = 1e-9;

/// How many hull plane normals (the largest by area, antiparallel planes merged) the box
/// search tries as an axis.
constexpr int fit_box_normals = 200;

/// The fixed seed of Welzl's shuffle: the same ball every run, for any thread count.
constexpr std::uint64_t fit_ball_seed = 0x6D657368;

/// Welzl's algorithm stops (status MAX_ITERATIONS, the ball still grown to hold every
/// point) after this many point tests per point: its expected work is linear, its worst
/// case is not.
constexpr long long fit_ball_max_work_per_point = 4096;

/// The box's local search over rotations (a pattern search on a rotation vector): first
/// step (radians), most sweeps, smallest step. The best this many candidate frames are
/// polished.
constexpr double fit_box_polish_step = 0.05;
constexpr int fit_box_polish_iterations = 200;
constexpr double fit_box_polish_smallest = 1e-7;
constexpr int fit_box_polish_starts = 3;

/// The cylinder's and capsule's local search over axes (pattern search on the axis's polar
/// angles): first step, most sweeps, smallest step, and how many candidate axes it starts
/// from (the best by volume).
constexpr double fit_axis_polish_step = 0.05;
constexpr int fit_axis_polish_iterations = 100;
constexpr double fit_axis_polish_smallest = 1e-5;
constexpr int fit_axis_polish_starts = 3;

/// The capsule's radius search for one axis: a grid of this many radii, then golden-section
/// steps around its best.
constexpr int fit_capsule_radius_grid = 33;
constexpr int fit_capsule_golden_steps = 40;

/// Sets per thread below which fits stay on the calling thread (one set is milliseconds).
constexpr long long fit_min_sets_per_thread = 1;

}  // namespace defaults

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
