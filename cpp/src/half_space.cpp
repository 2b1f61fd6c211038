// A convex shape against a half-space (an MJCF plane): exact, no GJK on an unbounded support.
// The half-space is z <= 0 of its frame; with n its world normal (the frame's z axis) and p
// its origin, a point x is n.(x - p) above it. A convex shape's lowest point along n is its
// support point in -n, so its signed distance to the half-space is that point's height
// (Ericson 2004, 5.2.3): separated above 0, touching at 0, penetrating below by -height, the
// minimum translation distance (moving the shape by that along n separates it, and no shorter
// move does: every point of the shape must end above the plane).

#include <cmath>
#include <limits>
#include <utility>

#include "meshcol/narrowphase.hpp"

namespace meshcol {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

PairResult failed(Status status) {
    PairResult r;
    r.status = status;
    r.distance = r.depth = kNaN;
    r.normal = r.point_a = r.point_b = Vec3{kNaN, kNaN, kNaN};
    return r;
}

// `plane` is the half-space, `other` the shape: the result oriented from the plane to it.
PairResult below_plane(const Pose& plane, const ShapeView& other, const Pose& pose, QueryKind kind) {
    const Vec3 n = plane.rotation.column(2);
    // The support in -n, in the other shape's frame; its height measured from the plane's
    // origin through the difference of the translations (no large world coordinates summed).
    const Vec3 lowest = pose.rotate_inverse(-n);
    const Vec3 local = support(other, lowest);
    const Vec3 offset = pose.rotate(local);
    const double height = dot(n, pose.translation - plane.translation) + dot(n, offset);
    PairResult r;
    r.status = Status::CONVERGED;
    r.point_b = pose.translation + offset;
    r.point_a = r.point_b - n * height;
    r.normal = n;
    r.intersects = height <= 0.0;
    r.distance = std::fmax(0.0, height);
    if (kind == QueryKind::PENETRATION) r.depth = std::fmax(0.0, -height);
    else if (kind == QueryKind::DISTANCE && r.intersects) r.normal = Vec3{};
    if (!std::isfinite(height) || !is_finite(r.point_a) || !is_finite(r.point_b))
        return failed(Status::OUT_OF_RANGE);
    return r;
}

}  // namespace

PairResult half_space_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                           const Pose& pose_b, QueryKind kind) {
    const bool plane_a = a.kind == ShapeKind::HALFSPACE, plane_b = b.kind == ShapeKind::HALFSPACE;
    if (plane_a && plane_b) return failed(Status::DEGENERATE);
    if (plane_a) return below_plane(pose_a, b, pose_b, kind);
    PairResult r = below_plane(pose_b, a, pose_a, kind);
    std::swap(r.point_a, r.point_b);
    r.normal = -r.normal;
    return r;
}

}  // namespace meshcol
