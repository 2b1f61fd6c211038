#pragma once
/// The in-sphere of a convex polytope given by its face planes: the largest ball inside
/// `{x : n_i . x + d_i <= 0}` (unit normals `n_i`), its centre the Chebyshev centre
/// (Boyd and Vandenberghe 2004, 8.5.1), a linear programme in 4 unknowns solved by a dense
/// active-set (simplex) method. For `meshcol.collision.limits`' oblong ratio and inradius.

#include <cstdint>

#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// One polytope's in-sphere.
struct InscribedBall {
    Vec3 centre;         ///< the Chebyshev centre (input frame); a best effort unless CONVERGED
    double radius = 0;   ///< the least distance from `centre` to a face plane, >= 0 (input
                         ///< units); 0 for an empty or flat polytope
    Status status = Status::NOT_RUN;  ///< CONVERGED: the centre (where the largest ball can
                                      ///< slide, the lexicographic one); DEGENERATE: radius
                                      ///< 0 (empty or flat), a slab, no largest ball
                                      ///< (unbounded), or still sliding after
                                      ///< `inscribed_ball_max_stages`: a best effort;
                                      ///< MAX_ITERATIONS: a stage hit the step cap;
                                      ///< INVALID_INPUT: no plane, or a NaN/inf
    int steps = 0;       ///< active-set steps taken (every stage)
};

/// The in-sphere of the polytope `{x : n_i . x + d_i <= 0}`, `planes` ((count, 4) row-major
/// rows `n_x, n_y, n_z, d`, unit normals). Maximises `r` subject to `n_i . x + r <= -d_i`
/// with `r` free, from `x = 0` (feasible with `r` the least `-d_i`): an empty polytope ends
/// with a negative `r`, reported as radius 0. Where the largest ball can slide (a box longer
/// than wide, a plate), the planes it touches are held and the least distance to the others
/// maximised in turn (the lexicographic Chebyshev centre), so that the centre, and the oblong
/// ratio read from it, are the polytope's own and not a solver's pick. The radius written is
/// the least distance from the centre to a plane (every plane read again), so the ball is
/// inside whatever the rounding of the steps. Thread-safe.
InscribedBall inscribed_ball(const double* planes, long long count);

/// `inscribed_ball` of `polytopes` polytopes, polytope h owning the rows
/// `planes[offsets[h]:offsets[h + 1]]`, written to `out` ((polytopes,)), on `threads`
/// threads (0: all). Offsets must be non-decreasing from 0 (checked by the caller).
void inscribed_balls(const double* planes, const std::int64_t* offsets, long long polytopes,
                     int threads, InscribedBall* out);

}  // namespace meshcol
