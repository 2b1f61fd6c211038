#pragma once
/// The narrow phase over a packed set of convex shapes: per-pair queries (distance,
/// penetration, intersection) and their batched loops over (P, 2) index pairs.
///
/// Frames and signs: shapes in their local frames, poses world-from-local; every returned
/// point and normal is in the world frame; `distance >= 0`, `depth >= 0`; the normal is unit
/// and points from a to b; moving b by `depth * normal` brings the shapes to contact.

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "meshcol/shapes.hpp"
#include "meshcol/status.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

class EdgeClasses;

/// Non-owning view of a packed convex set (the arrays of the Python `ConvexSet`).
struct ConvexSetView {
    const double* vertices = nullptr;     ///< (V, 3) local frames
    std::int64_t vertex_count = 0;        ///< V
    const std::int64_t* offsets = nullptr;  ///< (H + 1,) shape h owns [offsets[h], offsets[h+1])
    std::int64_t shape_count = 0;         ///< H
    const std::int8_t* kinds = nullptr;   ///< (H,) `ShapeKind`
    const double* params = nullptr;       ///< (H, 4) see `ShapeKind`
    /// Optional (V + 1,) CSR offsets into `adjacency` ((K,) local vertex indices), or null.
    const std::int64_t* adjacency_offsets = nullptr;
    const std::int32_t* adjacency = nullptr;
    /// Optional, with the adjacency: (H + 1,) offsets into `climb_lists`, the fixed-stride
    /// lists (shapes.hpp: `ClimbList`) of every shape that has them: shape h's are
    /// [climb_list_offsets[h], climb_list_offsets[h + 1]), its vertex count of them or none.
    const std::int64_t* climb_list_offsets = nullptr;
    const ClimbList* climb_lists = nullptr;
    /// Optional SAT features: (H + 1,) offsets into (F, 3) unit face normals and (H + 1,)
    /// offsets into (P, 2) true edges (local vertex indices (from, to), `pack_polytopes`),
    /// or null; with them, the cache of the edges' direction classes.
    const std::int64_t* face_offsets = nullptr;
    const double* face_normals = nullptr;
    const std::int64_t* edge_pair_offsets = nullptr;
    const std::int32_t* edge_pairs = nullptr;
    EdgeClasses* edge_classes = nullptr;

    /// The view of shape `h` (0 <= h < H). Its edge directions are attached when SAT needs
    /// them (shapes.hpp: `attach_edges`), except for a shape without edges. `edge_classes`
    /// must be set when `edge_pairs` is.
    ShapeView shape(std::int64_t h) const;
};

/// Each polytope's edge-direction classes (SAT's edge axes: `edge_direction_classes` of its
/// vertices and true edges, the packing's classes to the bit), computed the first time a
/// query needs them and kept for the set's life: the shapes of a set never change (the
/// Python `ConvexSet` makes or copies its arrays and holds them read-only). One per set,
/// shared by every thread and batch. Thread-safe: threads that meet an uncomputed shape at
/// the same moment each compute it, the same classes, and the first to publish its list wins
/// (the others free theirs). A shape's entry is a pointer in a zeroed allocation, so shapes
/// never asked for cost no written memory (no page faults).
class EdgeClasses {
  public:
    explicit EdgeClasses(std::int64_t shape_count);
    ~EdgeClasses();
    EdgeClasses(const EdgeClasses&) = delete;
    EdgeClasses& operator=(const EdgeClasses&) = delete;

    /// Shape `h`'s classes: (count, 3) unit directions; and its true edges' arcs on the Gauss
    /// map (sat.hpp: `gauss_arcs`), or none (null) when they could not be found.
    struct List {
        const Vec3* directions = nullptr;
        int count = 0;
        const GaussArc* arcs = nullptr;
        int arc_count = 0;
    };

    /// Shape `h`'s classes of `set` (whose cache this is), computed on first use.
    List get(const ConvexSetView& set, std::int64_t h);

    /// A lower bound on shape `h`'s class count, at least `wanted` when the count is, found
    /// without computing them all where it can be: the classes of its first
    /// max(`wanted`, `defaults::sat_edge_class_prefix`) edges (the classes themselves, kept,
    /// when that is most of them). The largest bound found is kept like the classes;
    /// `wanted` 0 reads it (or the count) without computing anything.
    int lower_bound(const ConvexSetView& set, std::int64_t h, int wanted);

  private:
    struct Entry;
    std::int64_t shape_count_;
    std::atomic<Entry*>* entries_;   // (H,) null until computed
    std::atomic<int>* lower_;        // (H,) lower bound + 1; 0: not yet found
};

/// The fixed-stride neighbour lists (shapes.hpp: `ClimbList`) of a set's polytopes that climb,
/// made once from its adjacency: 16 bytes a vertex (32 above `kNarrowClimbVertices`), for
/// every shape whose lists fit (`make_climb_lists`); the others climb on the CSR arrays. The set's arrays must not change
/// while it is attached (the Python `ConvexSet` holds them read-only).
class ClimbLists {
  public:
    /// The lists of `set`'s shapes, made on `threads` threads (0: all cores).
    ClimbLists(const ConvexSetView& set, int threads);

    /// Points `set` (a view of the same arrays) at these lists.
    void attach(ConvexSetView& set) const;

    /// Rows held (`ClimbList`s: a row a vertex of the shapes that have lists, two a vertex
    /// above `kNarrowClimbVertices` vertices).
    std::int64_t size() const { return offsets_.empty() ? 0 : offsets_.back(); }
    /// The (H + 1,) offsets (`ConvexSetView::climb_list_offsets`) and the `size()` lists;
    /// both null when no shape has lists.
    const std::int64_t* offsets() const { return offsets_.empty() ? nullptr : offsets_.data(); }
    const ClimbList* lists() const { return lists_.get(); }

  private:
    std::vector<std::int64_t> offsets_;  // (H + 1,), or empty when no shape has lists
    std::unique_ptr<ClimbList[]> lists_;
};

/// What a pair query computes.
enum class QueryKind : std::int8_t {
    DISTANCE = 0,     ///< GJK only: distance (0 when overlapping) and closest points
    PENETRATION = 1,  ///< GJK, then EPA (+ SAT) for overlapping pairs: distance and depth
    INTERSECTS = 2,   ///< boolean GJK with early exit
};

/// Everything a pair query can report. Unset fields hold 0.
struct PairResult {
    Status status = Status::NOT_RUN;
    bool intersects = false;  ///< touching counts
    double distance = 0.0;    ///< >= 0, 0 when intersecting
    double depth = 0.0;       ///< >= 0, 0 when separated (PENETRATION only)
    Vec3 normal;              ///< world, unit, a to b (zero for an overlap under DISTANCE)
    Vec3 point_a;             ///< world: closest point (separated) or deepest point (overlap)
    Vec3 point_b;             ///< world
    int iterations = 0;       ///< GJK plus EPA iterations
};

/// A pair with a half-space (`ShapeKind::HALFSPACE`, either side), measured exactly without
/// GJK: the other shape's support point against the plane's normal n (world) is its lowest
/// point, and its height n.(x - plane point) the signed distance (Ericson 2004, 5.2.3: a
/// convex shape against a plane). `point_b` (of the other shape) is that support point,
/// `point_a` its foot on the plane; the normal is n, or -n when the half-space is `b`. Two
/// half-spaces: `Status::DEGENERATE`, NaN fields (MuJoCo never collides static geoms).
/// `query_pair` sends every such pair here.
PairResult half_space_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                           const Pose& pose_b, QueryKind kind);

/// One pair query. Shapes must be valid and poses rigid (the batch checks both).
/// `radius_a`/`radius_b`: the shapes' `bounding_radius` if known (negative: computed).
PairResult query_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                      const Pose& pose_b, QueryKind kind, double radius_a = -1.0,
                      double radius_b = -1.0);

/// Output arrays of a batch (null pointers are skipped): P entries, or P x 3 for vectors.
struct BatchOutput {
    double* distance = nullptr;
    double* depth = nullptr;
    double* normal = nullptr;
    double* point_a = nullptr;
    double* point_b = nullptr;
    std::int32_t* iterations = nullptr;
    std::int8_t* status = nullptr;
    bool* intersects = nullptr;
};

/// Each shape's `valid_bounding_radius` (NaN: not a valid shape), computed by the first batch
/// that uses the shape and kept for the batches after it: a set's shapes do not change between
/// queries, only the poses do (the Python `ConvexSet` makes or copies its arrays and holds
/// them read-only). One per set, shared by every thread and batch: threads that meet an
/// unchecked shape at the same moment both compute it, the same value, so relaxed atomics
/// suffice.
class ShapeRadii {
  public:
    explicit ShapeRadii(std::int64_t shape_count);

    /// Shape `h`'s checked radius, computed on first use.
    double get(const ConvexSetView& set, std::int64_t h) {
        double r = radius_[h].load(std::memory_order_relaxed);
        if (r == kUnchecked) {
            r = valid_bounding_radius(set.shape(h));
            radius_[h].store(r, std::memory_order_relaxed);
        }
        return r;
    }

  private:
    static constexpr double kUnchecked = -1.0;  // a radius is >= 0 or NaN
    std::unique_ptr<std::atomic<double>[]> radius_;
};

/// Runs `kind` on every pair (P, 2) of `set` under `poses` ((H, 4, 4) row-major, or null for
/// identity) on `threads` threads (0: all cores). Pairs with a bad shape or pose get
/// `Status::INVALID_INPUT` and NaN fields. Pair indices must be in range (callers check).
/// `radii`: the set's checked radii kept between batches (null: checked for this batch only).
void run_batch(const ConvexSetView& set, const double* poses, const std::int64_t* pairs,
               long long pair_count, QueryKind kind, int threads, const BatchOutput& out,
               ShapeRadii* radii = nullptr);

/// World AABBs (H, 3) + (H, 3) of every shape under `poses` (null: identity). A bad shape or
/// pose gives NaN bounds.
void world_aabbs(const ConvexSetView& set, const double* poses, double* aabb_min,
                 double* aabb_max, int threads);

/// Every shape's edge-direction classes through the set's cache (`set.edge_classes`; each
/// computed at most once in the set's life) on `threads` threads: (H + 1,) offsets into
/// `offsets` and the (E, 3) unit directions into `directions`, concatenated in shape order
/// (a shape without true edges, or a set without features, has none).
void all_edge_classes(const ConvexSetView& set, int threads, std::vector<std::int64_t>& offsets,
                      std::vector<double>& directions);

/// Radius (H,) of a ball about each shape's local origin holding the whole shape
/// (`bounding_radius`); NaN for a shape that is not `is_valid`.
void bounding_radii(const ConvexSetView& set, double* radii, int threads);

}  // namespace meshcol
