#pragma once
/// EPA penetration depth (van den Bergen 2003, sec. 4.3.9; Montaut et al. 2022 for the
/// tolerances): grows GJK's final simplex into a polytope inside the Minkowski difference,
/// replacing every face the new support point sees by a fan over the silhouette (horizon).

#include "meshcol/defaults.hpp"
#include "meshcol/gjk.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// Options of `epa_penetration` (defaults from defaults.hpp).
struct EpaOptions {
    int max_iterations = defaults::epa_max_iterations;
    double relative_tolerance = defaults::epa_relative_tolerance;  ///< on the depth
    double contact_tolerance = defaults::contact_tolerance;  ///< x pair scale
};

/// Result of `epa_penetration`. Frame: as the Minkowski difference (shape a's local frame).
struct EpaResult {
    Status status = Status::NOT_RUN;
    double depth = 0.0;  ///< >= 0; moving b by depth * normal brings the shapes to contact
    Vec3 normal;         ///< unit, from a to b
    Vec3 point_a;        ///< deepest point of a inside b
    Vec3 point_b;        ///< deepest point of b inside a; point_a - point_b = depth * normal
    int iterations = 0;
};

/// EPA on `difference` (built with margins) starting from `simplex`, a simplex of GJK that
/// touches or contains the origin. Frame: shape a's local frame. A touching pair (a face of
/// the simplex through the origin, up to the contact distance) first gets a few candidate
/// normals, each checked by one support; the first along which the shapes overlap by at most
/// the contact distance is the answer (depth that overlap, at least 0), without expansion.
EpaResult epa_penetration(MinkowskiDifference& difference, const Simplex& simplex,
                          const EpaOptions& options = {});

/// EPA on a deep pair without GJK: `first` is the support of `difference` along the centre
/// line (`translation_b`, as GJK's first), past the origin. Starts from supports around the
/// centre line; status NOT_RUN (and nothing else set) when they do not hold the origin clear
/// of the contact distance, and the caller then runs GJK and `epa_penetration`. Frame: shape
/// a's local frame. The iterations count the start's six supports.
EpaResult epa_penetration_deep(MinkowskiDifference& difference, const SimplexVertex& first,
                               const EpaOptions& options = {});

}  // namespace meshcol
