#pragma once
/// Axis-aligned bounding boxes: the currency of the broad phase.
/// Intervals are closed: boxes that touch (share a face, edge or corner) overlap.

#include <algorithm>

#include "meshcol/vec.hpp"

namespace meshcol {

/// An axis-aligned box [lo, hi] (world frame). Valid when finite and lo <= hi per axis.
struct Aabb {
    Vec3 lo;  ///< minimum corner (world frame)
    Vec3 hi;  ///< maximum corner (world frame)
};

/// Smallest box holding both.
inline Aabb merge(const Aabb& a, const Aabb& b) {
    return {{std::min(a.lo.x, b.lo.x), std::min(a.lo.y, b.lo.y), std::min(a.lo.z, b.lo.z)},
            {std::max(a.hi.x, b.hi.x), std::max(a.hi.y, b.hi.y), std::max(a.hi.z, b.hi.z)}};
}

/// Closed-interval overlap test: touching boxes overlap.
inline bool overlaps(const Aabb& a, const Aabb& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
           a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

/// True when `inner` lies inside `outer` (boundaries included).
inline bool contains(const Aabb& outer, const Aabb& inner) {
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

/// Half the surface area: the cost measure of the surface area heuristic (SAH; MacDonald and
/// Booth 1990). Box2D uses the perimeter in 2D; this is its 3D analogue.
inline double half_area(const Aabb& a) {
    const double dx = a.hi.x - a.lo.x, dy = a.hi.y - a.lo.y, dz = a.hi.z - a.lo.z;
    return dx * dy + dy * dz + dz * dx;
}

/// The box grown by `margin` on every side.
inline Aabb inflate(const Aabb& a, double margin) {
    const Vec3 m{margin, margin, margin};
    return {a.lo - m, a.hi + m};
}

/// Centre of the box.
inline Vec3 center(const Aabb& a) { return (a.lo + a.hi) * 0.5; }

}  // namespace meshcol
