#pragma once
/// Time of impact (continuous collision) of two convex shapes moving between two poses.
///
/// Motion. Each body moves from its start pose to its end pose over t in [0, 1]. Its reference
/// point is its LOCAL ORIGIN: the origin's world position moves linearly, T(t) = T0 + t (T1 - T0),
/// and the body turns about it at constant angular velocity from R0 to R1 (slerp of the relative
/// rotation R0^T R1, shortest way, angle in [0, pi]): R(t) = R0 exp(t log(R0^T R1)). The rotation
/// axis is fixed in the world, so a point at local p moves with velocity
/// v + w x R(t) p, |w| = angle. `interpolate_pose` is this motion.
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
/// - INVALID_INPUT: a bad shape or a non-rigid pose; every field is NaN.
///
/// Algorithms, chosen per pair:
/// - two spheres: closed form (the centre distance is a quadratic in t; rotation cannot move a
///   sphere about its own centre);
/// - translation only (neither body turns, or the one that turns is a sphere): the GJK ray cast
///   on the Minkowski difference (van den Bergen 2004, "Ray casting against general convex
///   objects with application to continuous collision detection"), with the radii of spheres and
///   capsules as margins (as Box2D's b2ShapeCast). Exact up to the tolerance;
/// - otherwise: conservative advancement (Mirtich 1996; Zhang et al. 2006) with a rigorous bound
///   on how fast the separating slab can close: relative linear speed along the normal plus, per
///   body, angle x |normal x axis| x bounding radius about the reference point. The step aims at
///   distance tolerance / 2, so SEPARATED is never reported for a touching pair.

#include <cstdint>

#include "meshcol/defaults.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// A body's motion from `start` to `end` over t in [0, 1] (see the file comment), precomputed.
struct Motion {
    Pose start;        ///< world-from-local at t = 0
    Pose end;          ///< world-from-local at t = 1
    Vec3 velocity;     ///< world, T1 - T0 (displacement of the local origin over the motion)
    Vec3 axis_local;   ///< unit rotation axis in the body's start frame (x when angle is 0)
    Vec3 axis_world;   ///< unit rotation axis in the world (fixed during the motion)
    double angle = 0;  ///< radians in [0, pi] turned over the whole motion

    /// Builds the motion between two rigid poses.
    Motion(const Pose& start_pose, const Pose& end_pose);
    Motion() = default;

    /// The pose at time t (t in [0, 1]; t = 1 gives `end` up to rounding).
    Pose at(double t) const;
};

/// The pose at time t of the motion from `start` to `end` (see the file comment).
Pose interpolate_pose(const Pose& start, const Pose& end, double t);

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
/// `end_poses[h]` ((H, 4, 4) row-major each), on `threads` threads (0: all cores). Pairs with a
/// bad shape or pose get `TimeOfImpactStatus::INVALID_INPUT` and NaN fields. Indices must be
/// in range.
void run_toi_batch(const ConvexSetView& set, const double* start_poses, const double* end_poses,
                   const std::int64_t* pairs, long long pair_count, const ToiOptions& options,
                   int threads, const ToiBatchOutput& out);

}  // namespace meshcol
