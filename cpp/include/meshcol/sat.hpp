#pragma once
/// Exact penetration depth of two polytopes (or boxes) by the separating axis theorem: the
/// minimum over the face normals of both shapes and the cross products of their edge
/// directions of the overlap along that axis (Ericson 2004, sec. 5.2.1; Gottschalk 1996).
/// Quadratic in the edge count, so only for shapes with few faces: EPA verification. Edge
/// axes that a bound from two inner balls shows cannot be the smallest are skipped, with the
/// same answer to the bit (sat.cpp).

#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// Result of `sat_penetration`.
struct SatResult {
    bool ran = false;        ///< false when a shape lacks SAT data or the work cap is exceeded
    bool separated = false;  ///< an axis with a positive gap exists (then `depth` is 0)
    double depth = 0.0;      ///< >= 0: the minimum overlap over all candidate axes
    Vec3 normal;             ///< world frame, unit, from a to b: moving b by depth * normal
                             ///< brings the shapes to contact
    int axes = 0;            ///< candidate axes measured (not those the bound skipped)
};

/// True when `shape` carries SAT data (a box, or a polytope with its features attached).
bool has_sat_features(const ShapeView& shape);

/// SAT depth of `a` at `pose_a` against `b` at `pose_b`. Runs when both shapes have SAT data
/// and (candidate axes) x (vertices of a + b) is at most `max_work`.
SatResult sat_penetration(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, long long max_work = defaults::sat_max_work);

}  // namespace meshcol
