#pragma once
/// Time of impact (continuous collision) of two convex shapes, each in rigid motion.
///
/// Motion. Each body moves over t in [0, 1] by a screw about a moving pivot: the pivot (a world
/// point, the body's local origin unless given) moves linearly, c(t) = c0 + t v, and the body
/// turns about it at constant angular velocity w = angle k (k a fixed world axis, `angle` >= 0
/// radians of ANY size: several turns are several turns):
///   R(t) = Rot(k, angle t) R0,    T(t) = c(t) + Rot(k, angle t) (T0 - c0).
/// A point of the body at x moves with velocity v + w x (x - c(t)). A motion is built either
/// from a start and an end pose alone (the SHORTEST rotation from R0 to R1, angle in [0, pi],
/// pivot at the local origin) or from the start pose, the end pose and the turn as a world
/// rotation vector angle k (any angle, which must turn R0 into R1) with an optional pivot.
/// `Motion::at` is this motion.
///
/// Contact and tolerance. `tolerance` is an absolute distance (world units). The shapes are in
/// contact when their distance is at most `tolerance`. Guarantees, per status:
/// - HIT: the distance at `toi` is <= tolerance, and `toi` is a lower bound of the first instant
///   of touching (distance 0) when there is one: the shapes do not touch on [0, toi).
/// - SEPARATED: the distance stays above tolerance / 2 at every instant of [0, 1]; a pair that
///   touches during the motion is never SEPARATED. (A closest approach between tolerance / 2
///   and tolerance may be reported either way.)
/// - OVERLAPPED_AT_START: the distance at t = 0 is <= tolerance; toi = 0.
/// - FAILED: the iteration cap was reached; `toi` is the last safe lower bound (no contact before
///   it), `point` and `normal` the closest points' midpoint and direction there.
/// - INVALID_INPUT: a bad shape, a non-rigid pose, a turn that does not take the start
///   rotation to the end rotation, or lengths beyond a double (a path or a radius over DBL_MAX,
///   a tolerance under 2^-1074 of the pair's extent); every field is NaN.
///
/// Range. A pair whose lengths leave [2^-100, 2^100] is moved and scaled by a power of two
/// (exact) before the query and back after it, as in the narrow phase (src/rescale.hpp): the
/// answer is the same at 1e-300 or 1e300 as at 1.
///
/// Algorithms, chosen per pair:
/// - two spheres that do not turn about an off-centre pivot: closed form (the centre distance
///   is a quadratic in t; rotation cannot move a sphere about its own centre);
/// - translation only (neither body turns, or the one that turns is a sphere about its
///   centre): the GJK ray cast on the Minkowski difference (van den Bergen 2004, "Ray casting
///   against general convex objects with application to continuous collision detection"), with
///   the radii of spheres and capsules as margins (as Box2D's b2ShapeCast). Exact up to the
///   tolerance;
/// - otherwise: conservative advancement (Mirtich 1996; Zhang et al. 2006) with a rigorous bound
///   on how fast the separating slab can close: relative linear speed of the pivots along the
///   normal plus, per body, angle x |normal x axis| x lever arm (the largest distance of a point
///   from the axis line through the pivot; a swept ball's radius adds nothing), for the whole
///   angle, so a spin of several turns is bounded as one. The step aims at distance
///   tolerance / 2, so SEPARATED is never reported for a touching pair.

#include <cstdint>

#include "meshcol/defaults.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// A body's motion over t in [0, 1] (see the file comment), precomputed.
struct Motion {
    Pose start;              ///< world-from-local at t = 0
    Pose end;                ///< world-from-local at t = 1 (as given)
    Vec3 pivot;              ///< world, the point the body turns about, at t = 0
    Vec3 velocity;           ///< world, displacement of the pivot over the motion
    Vec3 axis_world{1, 0, 0};  ///< unit rotation axis in the world (fixed during the motion)
    double angle = 0;        ///< radians turned over the whole motion, >= 0, any size
    double pivot_offset = 0;  ///< |T0 - pivot|: how far the local origin is from the pivot

    /// The motion between two rigid poses by the shortest rotation (angle in [0, pi]), about
    /// the local origin.
    Motion(const Pose& start_pose, const Pose& end_pose);
    Motion() = default;

    /// The motion from `start_pose` to `end_pose` turning by the world rotation vector
    /// `rotation` (axis x angle, any angle) about the world point `pivot` (at t = 0). Returns
    /// false, leaving `out` unspecified, when the rotation vector is not finite or does not
    /// turn the start rotation into the end rotation within `tolerance` (per matrix entry).
    static bool from_turn(const Pose& start_pose, const Pose& end_pose, const Vec3& rotation,
                          const Vec3& pivot, double tolerance, Motion& out);

    /// The pose at time t (t = 0 gives `start`, t = 1 gives `end`; any t evaluates the screw).
    Pose at(double t) const;
};

/// Rotation by `angle` radians about the unit `axis` (Rodrigues' formula).
Mat3 axis_angle_matrix(const Vec3& axis, double angle);

/// The world rotation vector (axis x angle, angle in [0, pi]) of the shortest rotation taking
/// `start` to `end`: end = Rot(rotation) start.
Vec3 shortest_rotation(const Mat3& start, const Mat3& end);

/// The motion of one shape from its row-major 4 x 4 `start_pose` and `end_pose`, its turn's
/// world rotation vector `rotation` (3, null: the shortest rotation) and world `pivot` (3,
/// null: the local origin). False for a non-rigid pose or a turn that does not reach the end
/// rotation (defaults::rigid_tolerance).
bool make_motion(const double* start_pose, const double* end_pose, const double* rotation,
                 const double* pivot, Motion& motion);

/// The motions of H shapes from row-major (H, 4, 4) `start_poses` and `end_poses`; `rotations`
/// (H, 3) world rotation vectors of the turns and `pivots` (H, 3) world points, each null for
/// the shortest rotation and the local origin. `ok[h]` is 0 for a non-rigid pose or a turn
/// that does not reach the end rotation (defaults::rigid_tolerance).
void make_motions(long long count, const double* start_poses, const double* end_poses,
                  const double* rotations, const double* pivots, Motion* motions, char* ok);

/// Options of `time_of_impact` (defaults from defaults.hpp).
struct ToiOptions {
    double tolerance = defaults::toi_tolerance;            ///< absolute contact distance, > 0
    int max_iterations = defaults::toi_max_iterations;     ///< cap on advancement/cast steps
};

/// Result of `time_of_impact`. Fields are NaN where they have no meaning (see TimeOfImpactStatus).
struct ToiResult {
    TimeOfImpactStatus status = TimeOfImpactStatus::FAILED;
    double toi = 0.0;  ///< fraction of the motion in [0, 1]; NaN when SEPARATED
    Vec3 point;        ///< world, midpoint of the closest points at `toi`
    Vec3 normal;       ///< world, unit, from a to b at `toi` (zero when overlapping)
    int iterations = 0;  ///< cast or advancement steps (GJK calls for advancement)
};

/// Time of impact of shape `a` moving by `motion_a` and `b` moving by `motion_b`. Shapes must
/// be valid (`is_valid`); `options.tolerance` must be > 0 and finite.
ToiResult time_of_impact(const ShapeView& a, const Motion& motion_a, const ShapeView& b,
                         const Motion& motion_b, const ToiOptions& options = {});

/// Output arrays of `run_toi_batch` (P entries, or P x 3 for vectors; null pointers skipped).
struct ToiBatchOutput {
    double* toi = nullptr;
    double* point = nullptr;
    double* normal = nullptr;
    std::int32_t* iterations = nullptr;
    std::int8_t* status = nullptr;
};

/// Time of impact of every pair (P, 2) of `set`, shape h moving from `start_poses[h]` to
/// `end_poses[h]` ((H, 4, 4) row-major each), turning by `rotations[h]` about `pivots[h]`
/// ((H, 3) each, null: shortest rotation, local origin; see `make_motions`), on `threads`
/// threads (0: all cores). Pairs with a bad shape, pose or turn get
/// `TimeOfImpactStatus::INVALID_INPUT` and NaN fields. Indices must be in range.
void run_toi_batch(const ConvexSetView& set, const double* start_poses, const double* end_poses,
                   const double* rotations, const double* pivots, const std::int64_t* pairs,
                   long long pair_count, const ToiOptions& options, int threads,
                   const ToiBatchOutput& out);

}  // namespace meshcol
