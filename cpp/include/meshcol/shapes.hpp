#pragma once
/// Convex shapes as the narrow phase sees them: a non-owning view per shape and its support
/// function, kept apart from GJK/EPA as coal does (support_functions.h).
///
/// Every shape lives in its own local frame; a `Pose` maps it to the world. Spheres and capsules
/// are handled as a *core* (a point, a segment) swept by a *margin* (the radius), so GJK on the
/// cores is exact and the radius is added afterwards (van den Bergen 2003, sec. 4.3.8).

#include <cstdint>

#include "meshcol/defaults.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

struct ConvexSetView;
struct GaussArc;

/// Neighbour slots of a climb list.
constexpr int kClimbListSlots = 15;

/// One vertex's hull neighbours at a fixed stride, as hill climbing reads them: vertex i's
/// list is the i-th record, so a climb step finds it (and asks for each neighbour's own list)
/// without reading CSR offsets first. The CSR list's entries, in its order (padding
/// included), as local indices of `Index` (`make_climb_lists`): climbs over either give the
/// same answers.
template <class Index>
struct alignas(16) ClimbRecord {
    Index count = 0;                          ///< entries of `neighbours` in use
    Index neighbours[kClimbListSlots] = {};  ///< local vertex indices
};

/// A polytope of at most `kNarrowClimbVertices` vertices (the engines' hull budgets: PhysX and
/// the engines built on it cap a convex hull at 255) keeps 8-bit lists, one 16-byte row a
/// vertex; a larger one 16-bit lists (`WideClimbList`), two rows a vertex. A set's lists are
/// rows of `ClimbList` either way.
using ClimbList = ClimbRecord<std::uint8_t>;
using WideClimbList = ClimbRecord<std::uint16_t>;
using ClimbIndex = std::uint8_t;  // the rows' element type, as numpy holds them
static_assert(sizeof(ClimbList) == 16, "four lists a cache line");
static_assert(sizeof(WideClimbList) == 2 * sizeof(ClimbList), "a wide list is two rows");
constexpr std::int64_t kNarrowClimbVertices = 256;

/// Rows of `ClimbList` each vertex's list takes in a polytope of `vertex_count` vertices.
inline std::int64_t climb_rows(std::int64_t vertex_count) {
    return vertex_count <= kNarrowClimbVertices ? 1 : 2;
}

/// Whether a polytope of `vertex_count` vertices whose longest CSR neighbour list (padding
/// included) holds `longest` entries keeps `ClimbList`s: it climbs (more than
/// `defaults::hill_climbing_min_vertices` vertices), every list fits a record's slots and
/// every index its 16 bits. The one rule of the hull packing and `make_climb_lists`; a shape
/// that keeps none climbs on the CSR arrays.
inline bool keeps_climb_lists(std::int64_t vertex_count, std::int64_t longest) {
    return vertex_count > defaults::hill_climbing_min_vertices && vertex_count <= 0x10000 &&
           longest <= kClimbListSlots;
}

/// Kind of a shape. The numeric values are part of the binary interface (mirrored by the
/// Python `meshcol.collision.shapes.ShapeKind`; tests/test_native.py checks it): never renumber.
enum class ShapeKind : std::int8_t {
    POLYTOPE = 0,  ///< convex hull of `vertices` (a point, segment and polygon are valid)
    SPHERE = 1,    ///< params[0] = radius, centred on the origin
    BOX = 2,       ///< params[0..2] = half extents along local x, y, z, centred
    CAPSULE = 3,   ///< params[0] = radius, params[1] = half length of the segment along z
    CYLINDER = 4,  ///< params[0] = radius, params[1] = half length along z, centred
    /// params[0..2] = semi-axes along local x, y, z, centred. A zero semi-axis is a flat
    /// ellipse (a disc when the other two are equal), two zeros a segment, three a point:
    /// each is still a convex set, queried exactly.
    ELLIPSOID = 5,
    /// The half-space z <= 0 of its frame (an MJCF plane: the floor is its top face, the
    /// solid below it); params[0..1] the half sides of the patch drawn for it, not read by any
    /// query. Unbounded: no support point, an unbounded box
    /// (`world_aabb`: infinite sides but the one its normal bounds when it is a world axis),
    /// an infinite bounding radius; the narrow phase measures it apart (`half_space_pair`,
    /// narrowphase.hpp), never by GJK or EPA.
    HALFSPACE = 6,
};

/// Non-owning view of one convex shape (local frame). Polytope data belong to the caller.
struct ShapeView {
    ShapeKind kind = ShapeKind::POLYTOPE;
    const Vec3* vertices = nullptr;  ///< polytope vertices, local frame
    int vertex_count = 0;            ///< number of `vertices`
    /// Optional hull adjacency for hill climbing (CSR): the neighbours of vertex i are
    /// `adjacency[adjacency_offsets[i] .. adjacency_offsets[i + 1])`, local vertex indices.
    /// Null when absent: the support function then scans every vertex.
    const std::int64_t* adjacency_offsets = nullptr;
    const std::int32_t* adjacency = nullptr;
    /// Optional, with the adjacency: the same lists as `vertex_count` fixed-stride records
    /// (`climb_rows(vertex_count)` rows each: a `ClimbList`, or a `WideClimbList` over two
    /// rows), which the climbs then read instead. Null: the climbs read the CSR arrays.
    const ClimbList* climb_lists = nullptr;
    /// Optional data for exact SAT (polytopes and boxes): outward unit face normals and unit
    /// edge directions (one per parallel class, sign arbitrary), local frame.
    bool has_features = false;  ///< true when the two arrays below describe the polytope
    const Vec3* face_normals = nullptr;
    int face_count = 0;
    const Vec3* edge_directions = nullptr;
    int edge_count = 0;
    /// Optional, with the edge directions: every true edge's arc on the Gauss map (sat.hpp),
    /// its class an index into `edge_directions`. Null: SAT measures every edge pair's axis.
    const GaussArc* arcs = nullptr;
    int arc_count = 0;
    /// Set when the edge directions are not attached yet: the shape is shape `set_index` of
    /// `set`, whose classes are computed on first use (narrowphase.hpp: `attach_edges`), and
    /// `edge_directions`/`edge_count` stay null/0 until then. Null: they are complete.
    const ConvexSetView* set = nullptr;
    std::int64_t set_index = -1;
    double params[4] = {0.0, 0.0, 0.0, 0.0};  ///< see `ShapeKind`
};

/// Attaches the edge directions of a shape whose classes are computed on first use
/// (`ShapeView::set`): reads them from its set's cache, computing them the first time
/// (narrowphase.cpp); a no-op for a shape whose directions are complete.
void attach_edges(ShapeView& shape);

/// A lower bound on a polytope's edge-class count: `edge_count` when its directions are
/// complete, else from its set's cache without computing them all where it can (at least
/// `wanted` when the count is: see narrowphase.hpp, `EdgeClasses::lower_bound`).
int edge_count_lower_bound(const ShapeView& shape, int wanted);

/// An upper bound on a polytope's edge-class count: `edge_count` when its directions are
/// complete, else its number of true edges.
int edge_count_upper_bound(const ShapeView& shape);

/// A support point of a shape's core with the feature that produced it.
struct SupportPoint {
    Vec3 point;     ///< local frame
    int index = -1; ///< vertex index (polytope), corner code (box, segment end), -1 when curved
};

/// Radius swept around the core: sphere and capsule radius, 0 for the other kinds.
inline double margin(const ShapeView& shape) {
    return (shape.kind == ShapeKind::SPHERE || shape.kind == ShapeKind::CAPSULE) ? shape.params[0]
                                                                                 : 0.0;
}

/// Support point of the shape's core in `direction` (local frame, need not be unit): a point
/// of the core maximising dot(point, direction); NaN for a half-space (it has none). `hint` is a warm-start vertex for hill
/// climbing on polytopes with adjacency (pass -1 when none).
SupportPoint support_core(const ShapeView& shape, const Vec3& direction, int hint = -1);

/// Writes a polytope's CSR adjacency as `vertex_count` records to `out`
/// (`vertex_count * climb_rows(vertex_count)` rows: `ClimbList`s, or `WideClimbList`s) and
/// returns true; returns false (`out` then unusable) when the shape keeps no lists
/// (`keeps_climb_lists`) or an index is not one of its vertices.
bool make_climb_lists(const ShapeView& shape, ClimbList* out);

/// True when `support_core` of this shape climbs its hull's edge graph (a polytope with
/// adjacency and more than `defaults::hill_climbing_min_vertices` vertices).
bool climbs(const ShapeView& shape);

/// True when `support_core` of this shape scans all its vertices: a polytope with vertices
/// that does not climb.
bool scans(const ShapeView& shape);

/// Reads the vertices (and the fixed-stride lists, when it has them) of a polytope that
/// `climbs` in order, about one load a cache line, and does nothing for other shapes: the batches do it on a shape's first pair in each batch,
/// since the shape's check (which reads them too) runs only in the first batch on a set. The
/// hardware prefetcher follows the loads in order, and the climbs' scattered reads then find
/// the vertices in cache, which `prefetch` instructions of the same lines did not bring about
/// as well. No effect on any result.
void read_vertices(const ShapeView& shape);

/// Asks the memory system for the data hill climbing reads (the vertices and hull adjacency of
/// a polytope that `climbs`, when it has at most `defaults::prefetch_max_vertices` vertices)
/// ahead of a query: no effect on any result, only on how long the climbs wait. The neighbour
/// lists are left out from `defaults::climb_prefetch_min_vertices` vertices on, where the
/// climbs ask for each list they read themselves.
void prefetch(const ShapeView& shape);

/// Support point of the full shape (core plus margin) in `direction` (local frame).
Vec3 support(const ShapeView& shape, const Vec3& direction);

/// Local axis-aligned bounding box of the full shape: (min, max).
void local_aabb(const ShapeView& shape, Vec3& aabb_min, Vec3& aabb_max);

/// World AABB of the full shape under `pose` (exact for boxes, spheres, capsules, cylinders
/// and ellipsoids; tight for polytopes: computed from the rotated vertices).
void world_aabb(const ShapeView& shape, const Pose& pose, Vec3& aabb_min, Vec3& aabb_max);

/// Radius of a ball centred on the local origin that holds the whole shape.
double bounding_radius(const ShapeView& shape);

/// True when the shape has usable data: finite vertices and parameters, at least one vertex
/// for a polytope, non-negative radii and extents.
bool is_valid(const ShapeView& shape);

/// `bounding_radius` of a shape that `is_valid`, else NaN: the same numbers from one tight
/// pass over a polytope's vertices (the batches check every shape a pair uses, and in
/// broad-phase output a shape is in only a few pairs, so the check costs as much as a query).
double valid_bounding_radius(const ShapeView& shape);

/// A triangle as a three-vertex polytope (for exact mesh queries). `vertices` must outlive it.
inline ShapeView triangle_view(const Vec3* vertices) {
    ShapeView v;
    v.kind = ShapeKind::POLYTOPE;
    v.vertices = vertices;
    v.vertex_count = 3;
    return v;
}

}  // namespace meshcol
