#pragma once
/// GJK distance between two convex shapes (van den Bergen 2003), with a Voronoi-region
/// closest-point subalgorithm (Ericson 2004, sec. 5.1) instead of Johnson's determinants.
///
/// The query runs in shape a's local frame (shape b is mapped into it once), which keeps
/// coordinates small and the answer independent of where the pair sits in the world.

#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// One vertex of a GJK/EPA simplex: a point of the Minkowski difference a - b and the two
/// support points that produced it. All in shape a's local frame.
struct SimplexVertex {
    Vec3 w;          ///< a - b
    Vec3 a;          ///< support point of shape a
    Vec3 b;          ///< support point of shape b (mapped into a's frame)
    int index_a = -1;  ///< feature of a (`SupportPoint::index`), -1 when curved
    int index_b = -1;  ///< feature of b, -1 when curved
};

/// Up to four simplex vertices with the barycentric weights of the closest point.
struct Simplex {
    SimplexVertex vertices[4];
    double weights[4] = {0.0, 0.0, 0.0, 0.0};  ///< sum to 1 over the first `size` entries
    int size = 0;
};

/// The simplex's witness points: the sums of its vertices' points on a and on b, weighted by
/// `weights` (GJK's closest points; EPA's on a flat or touching simplex).
inline void weighted_points(const Simplex& s, Vec3& pa, Vec3& pb) {
    pa = Vec3{};
    pb = Vec3{};
    for (int i = 0; i < s.size; ++i) {
        pa += s.vertices[i].a * s.weights[i];
        pb += s.vertices[i].b * s.weights[i];
    }
}

/// The Minkowski difference a - b of two posed shapes, expressed in a's local frame.
struct MinkowskiDifference {
    const ShapeView* a = nullptr;
    const ShapeView* b = nullptr;
    Mat3 rotation_b;       ///< b local -> a local
    Vec3 translation_b;    ///< b's origin in a's local frame
    bool with_margins = false;  ///< include sphere/capsule radii (else: the cores only)
    int hint_a = -1;       ///< warm start for hill climbing on a
    int hint_b = -1;       ///< warm start for hill climbing on b
    bool climb_both = false;  ///< both shapes climb (`climbs`)
    /// Both shapes climb over fixed-stride lists (`ShapeView::climb_lists`): one joint climb
    /// per support (else each shape's own `support_core`).
    bool climb_lists_both = false;
    bool scan_both = false;   ///< both shapes scan (`scans`): one joint scan per support
    Vec3 last_direction;      ///< direction of the previous support call (zero: none)

    /// `radius_a` and `radius_b` are the shapes' `bounding_radius` when the caller has them
    /// (negative: computed here, O(vertices)).
    MinkowskiDifference(const ShapeView& shape_a, const Pose& pose_a, const ShapeView& shape_b,
                        const Pose& pose_b, bool margins, double radius_a = -1.0,
                        double radius_b = -1.0);

    /// Support point of a - b in `direction` (a's local frame, need not be unit). Climbs
    /// start from the previous support points when the direction turned less than about 60
    /// degrees since the last call, else from a few samples.
    SimplexVertex support(const Vec3& direction);

    /// The same, with the climbs starting from vertices `hint_a` and `hint_b` (negative:
    /// none), known to be near the answer whatever the last direction was.
    SimplexVertex support_from(const Vec3& direction, int hint_a, int hint_b);

    /// A length scale of the pair (bounding radii plus centre distance) for relative
    /// tolerances. Always > 0.
    double scale = 1.0;
};

/// Options of `gjk_distance` (defaults from defaults.hpp).
struct GjkOptions {
    int max_iterations = defaults::gjk_max_iterations;
    double relative_tolerance = defaults::gjk_relative_tolerance;  ///< on the distance
    double contact_tolerance = defaults::contact_tolerance;  ///< x pair scale: "touching"
    bool with_margins = true;    ///< false: distance between the cores (radii not added)
    bool stop_when_separated = false;  ///< early exit for `intersects`
};

/// Result of `gjk_distance` and `gjk_run`. The frame of the points and the normal depends on
/// which returned it: the world frame from `gjk_distance`, shape a's local frame from
/// `gjk_run` (its callers map them to the world).
struct GjkResult {
    Status status = Status::NOT_RUN;
    bool overlap = false;   ///< the (cores or full) shapes touch or overlap
    double distance = 0.0;  ///< >= 0; 0 when `overlap`
    Vec3 point_a;           ///< on a (a common point when overlapping); see above for the frame
    Vec3 point_b;           ///< on b; see above for the frame
    Vec3 normal;            ///< unit, from a to b; zero when `overlap`; see above for the frame
    int iterations = 0;
    Simplex simplex;        ///< final simplex (a's local frame), the start of EPA
    /// On an overlapping pair, the direction of the run's last support (a's frame, not unit;
    /// zero when none) when that support lay within the contact distance of the origin
    /// along it (as a rule, a vertex of a - b at the origin): the shapes overlap along it by
    /// at most that distance, so it is a contact normal (from a to b) and EPA need not run.
    /// `contact_support` is the support's dot with it.
    Vec3 contact_direction;
    double contact_support = 0.0;
};

/// GJK distance between `a` at `pose_a` and `b` at `pose_b`. Exact on polytopes (terminates
/// when a support point repeats) up to rounding; converges within `relative_tolerance` on
/// curved shapes. With `with_margins` the sphere and capsule radii are subtracted exactly
/// from the core distance. Shapes must be valid (`is_valid`) and poses rigid.
GjkResult gjk_distance(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, const GjkOptions& options = {});

/// Runs GJK on a prepared Minkowski difference (a's frame): the result's points and normal
/// stay in a's local frame, and its distance is that of the shapes `difference` describes
/// (the cores only unless `with_margins`). Used by the narrow phase (`query_pair`), whose
/// final simplex starts EPA; time of impact calls `gjk_distance`. `first`, when given, is
/// the support along `translation_b` (GJK's first) that the caller already asked
/// `difference` for, with no support call since.
GjkResult gjk_run(MinkowskiDifference& difference, const GjkOptions& options,
                  const SimplexVertex* first = nullptr);

/// Closest point of the simplex to the origin (Ericson 2004, sec. 5.1.2-5.1.6): shrinks
/// `simplex` to the smallest face holding it and sets its weights. Returns false when the
/// origin is inside a full (4-vertex) simplex, which is then left unchanged.
bool closest_point_on_simplex(Simplex& simplex, Vec3& closest);

}  // namespace meshcol
