#pragma once
// The pieces the two halves of the mesh depth share: mesh_depth.cpp (the sample points, the
// point-to-surface distances, the search over points whose other mesh is open, the answer)
// and mesh_depth_closed.cpp (the search over points whose other mesh is closed: regions and
// branch and bound). Private to the core.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "meshcol/mesh_bvh.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "meshcol/vec.hpp"
#include "mesh_query_detail.hpp"

namespace meshcol::mesh_detail {

// A point of one mesh, in the other mesh's local frame, with its distance to that surface.
struct DepthCandidate {
    Vec3 point;
    double distance;
    int mesh;  // 0: a point of a (frame of b); 1: a point of b (frame of a); 2: a point of
               // neither surface that may lie inside both (frame of a)
    bool farther_is_a;  // mesh 2: a's surface is the farther one
};

// A point's side of a closed surface: outside, inside, or not known yet.
enum class Side : signed char { OUTSIDE, INSIDE, UNKNOWN };

// Balls that hold no point of one mesh's surface, each with the side of its centre: every
// point of such a ball is on that side (the winding number of a closed surface is constant
// off it). A point whose side an exact test found, at exact distance d from the surface,
// gives the ball of radius d less any rounding allowance. The latest balls are read first,
// the points of one crossing following each other.
class SideBalls {
public:
    /// Records the ball about `center` of radius `radius` (none when it is not positive).
    void add(const Vec3& center, double radius, Side side) {
        if (radius > 0.0) balls_.push_back({center, radius * radius, side});
    }

    /// The side of `p` when one of the latest `read` balls holds it, else UNKNOWN.
    Side side_of(const Vec3& p, size_t read) const {
        for (size_t k = balls_.size(), n = 0; k-- > 0 && n < read; ++n)
            if (squared_norm(p - balls_[k].center) < balls_[k].radius2) return balls_[k].side;
        return Side::UNKNOWN;
    }

private:
    struct Ball {
        Vec3 center;
        double radius2;  // squared radius
        Side side;
    };
    std::vector<Ball> balls_;
};

inline double longest_edge(const Vec3 t[3]) {
    return std::sqrt(std::fmax(squared_norm(t[1] - t[0]),
                               std::fmax(squared_norm(t[2] - t[1]), squared_norm(t[0] - t[2]))));
}

// Points off both surfaces near where they cross: from a shared point of each crossing
// triangle pair, steps into the wedge between the two triangles, against the sum of their
// unit normals, and from each triangle's centroid, steps against its own normal (each mesh's
// winding decides its normals: outward for outward-wound meshes, and the winding-number test
// sorts out the rest). Such a point p inside both solids bounds
// the minimum translation distance by max(dist(p, surface a), dist(p, surface b)), and it
// finds overlaps whose surface points all lie on the other surface (flush, coplanar faces).
// The crossing pairs that get wedge points: at most 256, evenly strided beyond (the vertices
// and edge cuts do most).
inline size_t wedge_stride(const std::vector<CrossingPair>& pairs) {
    constexpr size_t kMaxPairs = 256;
    return pairs.size() / kMaxPairs + 1;
}

// The midpoints of the pieces of [p, q] between the sorted parameters `cuts` (0 and 1 among
// them), passed to `add`.
template <class Add>
void add_pieces(const Vec3& p, const Vec3& q, std::vector<double>& cuts, Add add) {
    std::sort(cuts.begin(), cuts.end());
    for (size_t c = 0; c + 1 < cuts.size(); ++c)
        if (cuts[c + 1] > cuts[c]) add(p + (q - p) * (0.5 * (cuts[c] + cuts[c + 1])));
}

/// The wedge points of crossing pair k (mesh_depth.cpp), appended to `out`: three stepped
/// from each triangle's centroid (a's and b's in turn), then six from each of two shared
/// points, these left out when their steps (which bound their distances to both triangles)
/// cannot exceed `floor`.
void add_pair_wedge_points(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                           const std::vector<CrossingPair>& pairs, size_t k, std::vector<DepthCandidate>& out,
                           double floor = -kInf);

/// Whether wedge point k of a pair (add_pair_wedge_points' order) is one stepped from a's
/// centroid into a: of such a point the open question is its side of b.
inline bool wedge_point_from_a(size_t k) { return k < 6 && k % 2 == 0; }

/// A triangle (leaf order) of a mesh and a point's squared distance to it
/// (closest_point_on_triangle's): an upper bound of the point's squared distance to the
/// surface. None when `triangle` is negative.
struct DistanceSeed {
    std::int32_t triangle = -1;
    double squared = kInf;
};

/// The squared distance from `p` to triangle `i` of `mesh` as a seed.
inline DistanceSeed seed_of(const MeshBvh& mesh, std::int32_t i, const Vec3& p) {
    return {i, squared_norm(closest_point_on_triangle(p, mesh.triangle(i)) - p)};
}

/// Distance from `point` (mesh's local frame) to the surface when it exceeds `floor` (>= 0);
/// otherwise some value <= floor (mesh_depth.cpp). Writes the triangle (leaf order) at the
/// returned distance to `*triangle` when given. `seed`, when given, prunes the search
/// (the same answer above `floor`).
double distance_beyond(const MeshBvh& mesh, const Vec3& point, double floor, std::int32_t* triangle = nullptr,
                       const DistanceSeed& seed = DistanceSeed{});

/// An upper bound of the distance from `point` (mesh's local frame) to the surface, within
/// `slack` of it, stopped at a triangle within `floor` (mesh_depth.cpp).
/// `seed`, when given, is taken as the first triangle found.
double distance_within(const MeshBvh& mesh, const Vec3& point, double floor, double slack, std::int32_t* triangle,
                       const DistanceSeed& seed = DistanceSeed{});

/// Where the search over the points whose other mesh is closed left the depth.
struct ClosedDepth {
    double best = 0.0;   ///< the depth found, 0 when no point is inside
    bool have = false;   ///< a point inside was found
    DepthCandidate winner{};  ///< the deepest point found
    /// The other mesh's triangle (leaf order) nearest a vertex or edge winner, else -1.
    std::int32_t winner_triangle = -1;
    long long work = 0;   ///< triangle visits spent on inside tests
    bool running = true;  ///< false when the work cap stopped it (out.status says so)
};

/// The search over the points of each mesh whose other mesh is closed (mesh_depth_closed.cpp):
/// vertices, then the pieces of crossing triangles' edges and, when both are closed, the wedge
/// points of the crossing pairs. Counts its inside tests in `out.points_tested` and sets
/// `out.status` to MAX_ITERATIONS when the work cap stops it.
ClosedDepth search_closed_depth(const MeshBvh& a, const MeshBvh& b, const Relative& rel,
                                const TriangleMarks& marks_a, const TriangleMarks& marks_b,
                                const std::vector<CrossingPair>& crossing_pairs, MeshDepthOutput& out);

}  // namespace meshcol::mesh_detail
