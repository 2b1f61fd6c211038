#pragma once
/// The budgeted hull's cut loop (`meshcol.collision.hull._simplify` in 3-D): a polytope of
/// supporting planes of an exact hull, cut where it is farthest from the hull while its vertex
/// count stays within a budget. The polytope is kept as its vertices and the planes through
/// each (a vertex/plane incidence structure), so a cut is a clip, O(vertices), not a new
/// half-space intersection of every plane so far.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "meshcol/vec.hpp"

namespace meshcol {

/// A convex polytope as vertices and, per vertex, the ids of the planes through it
/// (ascending, at least three), packed: vertex i's planes are
/// `plane_ids[plane_offsets[i]:plane_offsets[i + 1]]`. The caller's frame and units.
struct PlanePolytope {
    std::vector<Vec3> vertices;       ///< the vertices
    std::vector<int> plane_offsets;   ///< (vertices + 1,) into `plane_ids`
    std::vector<int> plane_ids;       ///< the planes through each vertex, ascending

    std::size_t size() const { return vertices.size(); }
    void clear() {
        vertices.clear();
        plane_offsets.assign(1, 0);
        plane_ids.clear();
    }
};

/// The tetrahedron of four planes `normals[k] . x <= offsets[k]` (plane ids 0..3): corner k
/// on every plane but k (Cramer's rule). False when the planes bound no tetrahedron (a corner
/// not finite).
bool tetrahedron_polytope(const Vec3 normals[4], const double offsets[4], PlanePolytope& out);

/// `in` clipped by the half-space `normals[plane] . x <= offset` (`normals`: the unit
/// normals of planes 0..`plane`, by id; `plane` above every id in `in`). Vertices on the plane
/// (within 128 rounding errors of the largest coordinate) stay and gain it; vertices beyond
/// it are cut off, each edge from a kept vertex to a cut one (two vertices on two common
/// planes that are not parallel) giving a new vertex where it crosses the plane. A new
/// vertex closer than `merge_distance` to another is merged with it (one per cluster, the
/// farthest from the centroid of all, with the union of their planes), as
/// `meshcol.collision.hull._merge_close` merges qhull's vertices. `source` receives, per
/// vertex of `out`, the vertex of `in` it is (-1: new). False when nothing is left.
bool clip_polytope(const PlanePolytope& in, const std::vector<Vec3>& normals, double offset,
                   int plane, double merge_distance, PlanePolytope& out,
                   std::vector<int>& source);

/// One body of `budget_planes`: the exact hull's vertices and facets, its budgets and
/// tolerances (input units).
struct BudgetInput {
    const Vec3* hull_vertices = nullptr;  ///< (hull_vertex_count,) exact hull vertices
    long long hull_vertex_count = 0;
    const Vec3* facets = nullptr;         ///< (facet_count, 3) corners of its triangles
    const double* equations = nullptr;    ///< (facet_count, 4) outward planes n . x + c = 0
    long long facet_count = 0;
    const double* start = nullptr;        ///< (4, 4) the start tetrahedron's planes (n, offset)
    int budget = 4;                       ///< at most this many vertices
    int max_planes = -1;                  ///< at most this many planes (-1: no limit)
    double converged_distance = 0.0;      ///< stop once every vertex is this close to the hull
    double merge_distance = 0.0;          ///< vertices closer than this are one
    int candidates = 8;                   ///< farthest vertices tried per step
};

/// What `budget_planes` did for one body.
enum class BudgetStatus : std::int8_t {
    OK = 0,      ///< the planes of a polytope within the budgets
    FAILED = 1,  ///< the start tetrahedron was degenerate: no planes (the caller falls back)
};

/// The loop of `meshcol.collision.hull._simplify` for one body: from the start tetrahedron,
/// repeatedly cut the farthest vertex from the hull (exact distances over the facets it lies
/// in front of) by the supporting plane normal to it at its closest point, keeping a cut
/// when the clipped polytope has at most `budget` vertices (else the next farthest, up to
/// `candidates`), until no cut fits, the planes reach `max_planes` or every vertex is within
/// `converged_distance`. Appends the accepted planes (n, offset), start planes first, to
/// `planes`, and the final polytope's vertices (the clips' own, at most `budget`; empty when
/// FAILED) to `vertices`. Thread-safe.
BudgetStatus budget_planes(const BudgetInput& input, std::vector<double>& planes,
                           std::vector<Vec3>& vertices);

}  // namespace meshcol
