#pragma once
/// Exact convex hulls of point sets (Quickhull) and the packed polytope data the narrow phase
/// runs on (vertices, hull adjacency for hill climbing, face normals and true edges for SAT),
/// batched over shapes.
///
/// Every hull of meshcol comes from `exact_hull`: collision shapes, `meshcol hull`, the
/// budgeted hull's exact start and decomposition parts.

#include <array>
#include <cstdint>
#include <vector>

#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// What a point set's hull is. Mirrored by `meshcol.collision.hull.HullStatus`: never renumber.
enum class HullStatus : std::int8_t {
    OK = 0,             ///< a 3-D polytope
    FLAT = 1,           ///< coplanar points (flatness rule): a convex polygon
    COLLINEAR = 2,      ///< collinear points: a segment
    SINGLE_POINT = 3,   ///< all points coincide (within the flatness rule): one point
    EMPTY = 4,          ///< no points: no hull
    NON_FINITE = 5,     ///< a NaN or infinite coordinate: no hull
    OVERFLOW = 6,       ///< a coordinate beyond `defaults::hull_max_abs_coordinate`: no hull
    FAILED = 7,         ///< the construction's own consistency check failed (never seen),
                        ///< or more than 2^31 - 1 points
};

/// The exact convex hull of a point set, in the dimension the flatness rule gives it.
struct Hull {
    HullStatus status = HullStatus::EMPTY;
    int dimension = -1;  ///< 3, 2, 1, 0; -1 when there is no hull (EMPTY, NON_FINITE, ...)
    /// Indices of the input points that are the hull's vertices. 3-D: in lexicographic order
    /// of their coordinates; 2-D: the polygon's ring, counter-clockwise about `normal`; 1-D:
    /// the segment's two ends; 0-D: the lexicographically smallest point.
    std::vector<int> vertices;
    /// 3-D: triangles indexing `vertices`, counter-clockwise seen from outside. 2-D: a fan
    /// of the ring (one side). Empty otherwise.
    std::vector<std::array<int, 3>> faces;
    /// 3-D: each triangle's outward unit normal and offset (n . x + offset = 0), input frame.
    std::vector<Vec3> face_normals;
    std::vector<double> face_offsets;
    /// 3-D: the plane of each triangle: coplanar neighbours (within the tolerance) share one.
    std::vector<int> face_planes;
    /// 3-D: the outward unit normal of each plane (that of its largest triangle).
    std::vector<Vec3> plane_normals;
    Vec3 normal;            ///< 2-D: unit normal of the polygon's plane; zero otherwise
    double volume = 0.0;    ///< enclosed volume (0 below 3-D), input units cubed
    double area = 0.0;      ///< surface area; 2-D: the polygon's area (one side)
    double diagonal = 0.0;  ///< bounding-box diagonal of the input points
};

/// The exact convex hull of `n` points (Quickhull, Barber, Dobkin and Huhdanpaa 1996).
/// Never throws for bad points: the status says why there is no hull.
Hull exact_hull(const Vec3* points, long long n);

/// Packed polytope data of many point sets, concatenated (the arrays of a Python ConvexSet
/// minus kinds and params).
struct PackedPolytopes {
    std::vector<HullStatus> status;            ///< (H,) per shape
    std::vector<double> vertices;              ///< (V, 3) hull vertices, input frames
    std::vector<std::int64_t> offsets;         ///< (H + 1,)
    std::vector<std::int64_t> adjacency_offsets;  ///< (V + 1,)
    std::vector<std::int32_t> adjacency;       ///< (K,) local neighbour indices, padded
    std::vector<std::int64_t> face_offsets;    ///< (H + 1,)
    std::vector<double> face_normals;          ///< (F, 3) outward unit normals, one per plane
    std::vector<std::int64_t> edge_pair_offsets;  ///< (H + 1,)
    /// (P, 2) the true edges as local vertex index pairs (from, to), in the order their
    /// directions are grouped (`edge_direction_classes`)
    std::vector<std::int32_t> edge_pairs;
    /// (H + 1,) offsets into `climb_lists`: shape h's are [climb_list_offsets[h],
    /// climb_list_offsets[h + 1]), one a vertex for a shape that climbs (more than
    /// `defaults::hill_climbing_min_vertices` vertices) and whose lists fit (`make_climb_lists`),
    /// else none
    std::vector<std::int64_t> climb_list_offsets;
    /// The adjacency lists of those shapes at a fixed stride (shapes.hpp: `ClimbList`), written
    /// with them: what `make_climb_lists` makes of each shape's CSR lists, byte for byte
    std::vector<ClimbList> climb_lists;
};

/// Hulls of H point sets (shape h owns `points[offsets[h] .. offsets[h + 1])`), packed in one
/// pass on `threads` threads (0: all cores). A shape without a hull (EMPTY, NON_FINITE,
/// OVERFLOW, FAILED) keeps its points as given with empty adjacency lists and no features:
/// queries report INVALID_INPUT for no points or NaN, and scan the points of the others
/// (their support is the hull's; the queries rescale far coordinates themselves).
///
/// Per shape: 3-D, the hull's vertices (lexicographic order), the neighbours of each vertex
/// in the triangulation (ascending, padded with the vertex itself to a multiple of four),
/// one normal per plane and the true edges (triangulation edges between different planes);
/// 2-D, the ring, its two neighbours per vertex, the plane's two normals and the ring's edges;
/// 1-D, both ends and the segment; 0-D, the point. The edges' direction classes are not
/// packed: SAT computes a shape's when it first needs them (`edge_direction_classes`).
PackedPolytopes pack_polytopes(const Vec3* points, const std::int64_t* offsets, long long shapes,
                               int threads);

/// One unit direction per class of parallel edges of a polytope, from its `vertices` (local
/// frame) and its true edges `pairs` ((count, 2) local vertex indices, as `pack_polytopes`
/// lists them), appended to `out` as (x, y, z) triples; returns how many. Each edge's
/// direction is `vertices[to] - vertices[from]`; the unit vectors are grouped by their
/// components rounded to 12 digits, with a canonical sign (the first component clearly
/// non-zero positive), first occurrences kept in edge order. Edges of zero or NaN length have
/// no class. Thread-safe. With `class_of` ((count,)), each edge's class there (its index in
/// the list appended, counted from the call's first; -1 for an edge without one).
std::int64_t edge_direction_classes(const Vec3* vertices, const std::int32_t* pairs,
                                    size_t count, std::vector<double>& out,
                                    std::int32_t* class_of = nullptr);

/// The number of classes `edge_direction_classes` finds among the first `count` edges: a lower
/// bound on the whole list's (a prefix has no class the list lacks). Thread-safe.
std::int64_t edge_direction_class_count(const Vec3* vertices, const std::int32_t* pairs,
                                        size_t count);

/// The width of a 3-D polytope across each of `count` directions: its largest minus its
/// smallest vertex projection, each projection the correctly rounded chain
/// `fma(d.z, p.z, fma(d.y, p.y, d.x * p.x))` (`width_projection`), the order a fused
/// matrix product takes. `faces` ((face_count, 3) indices of `vertices`) is the hull's
/// triangulation, whose edges the supports climb. Writes `widths` ((count,)) and returns
/// true; false (`widths` unset) when an index is out of range or `vertex_count` < 1.
///
/// Each support climbs the edge graph from the previous direction's (steepest ascent, as
/// `support_core`), then reads every vertex joined to the top by vertices projecting within
/// `defaults::width_plateau_relative` of it: the exact largest projection of a convex
/// polytope is in that connected set whatever the rounding, so each width is the same double
/// as the maximum and minimum over all vertices (`width_projection` on each). Thread-safe.
bool hull_widths(const Vec3* vertices, int vertex_count, const std::int64_t* faces,
                 long long face_count, const Vec3* directions, long long count,
                 double* widths);

/// The projection `hull_widths` measures: `fma(d.z, p.z, fma(d.y, p.y, d.x * p.x))`.
double width_projection(const Vec3& p, const Vec3& d);

/// Distance from each of `count` points to a convex polytope, searching for each point the
/// facets `in_front` marks: `facets` ((facet_count, 3) corners a triangle), `in_front`
/// ((count, facet_count), row-major, nonzero: search). Writes the smallest distance to a
/// marked facet and its closest point (a point with no marked facet: 0 and the point itself).
/// The closest point on a triangle is Ericson's (2004, 5.1.5) with numpy's arithmetic, step
/// for step, as `meshcol.geometry.triangles.closest_points_on_triangles` takes it (each
/// three-term dot product summed as einsum does, (x + z) + y; a tie goes to the first
/// facet): the same doubles as the budget loop's numpy code. Thread-safe.
void distances_to_facets(const Vec3* points, long long count, const Vec3* facets,
                         long long facet_count, const std::uint8_t* in_front, double* distances,
                         Vec3* closest);

}  // namespace meshcol
