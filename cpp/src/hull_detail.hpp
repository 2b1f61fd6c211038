#pragma once
// What the three files of the exact hull share (hull.hpp is their public face): Quickhull's
// workspace and triangulation (quickhull.cpp builds them), and the analysis of one point set
// that turns them into a Hull (hull.cpp), which the packing of many (hull_packing.cpp) reuses.
// Private to the core.

#include <array>
#include <cstdint>
#include <vector>

#include "meshcol/hull.hpp"
#include "meshcol/vec.hpp"

namespace meshcol::hull_detail {

// A point waiting outside a face, with its coordinates: the conflict lists are scanned far
// more often than written, and a list of copies streams through the cache where a linked
// list of indices would miss on every point.
struct Conflict {
    Vec3 p;
    int index;
};

struct Face {
    int v[3];  // point indices, counter-clockwise seen from outside
    int n[3];  // neighbour across edge v[i] -> v[(i + 1) % 3]
    Vec3 normal;
    double offset = 0.0;  // dot(normal, x) - offset is the distance of x
    std::vector<Conflict> conflicts;  // the points outside this face (farther than eps)
    int furthest = -1;
    double furthest_distance = 0.0;
    unsigned visit = 0;
    bool visible = false;
    bool alive = false;
};

struct HorizonEdge {
    int a, b;      // the edge, as the visible face had it
    int outside;   // the non-visible face across it
    int slot;      // the edge index in `outside` that pointed to the visible face
};

struct Frame {
    int face, start, count, done;
};

struct Workspace {
    std::vector<Vec3> p;  // scaled points
    double eps = 0.0;
    std::vector<int> mark;  // per point: stamp of the horizon check
    std::vector<Face> faces;  // a pool: faces[0 .. face_count) are this hull's
    size_t face_count = 0;
    std::vector<int> free_faces, pending, visible, new_faces;
    std::vector<Conflict> orphans;
    std::vector<std::pair<int, int>> horizon;
    std::vector<HorizonEdge> edges;
    std::vector<Frame> dfs;
    unsigned stamp = 0;
    // scratch of the analysis and the packing, kept across shapes
    std::vector<int> all, real, local, keep, parent, id;
    std::vector<char> used;
    std::vector<std::int64_t> start;
    std::vector<long long> table;
    std::vector<Conflict> sorted;  // the input, sorted and without duplicates
    std::vector<Vec3> unique_points;
    std::vector<int> unique_index;
    std::vector<int> filtered, filter_extremes;  // interior_filter's
    std::vector<double> filter_planes;
};

// A triangulated 3-D hull: triangles of point indices and their neighbours.
struct Triangulation {
    std::vector<std::array<int, 3>> tri;
    std::vector<std::array<int, 3>> neighbor;
};

enum class Build { OK, DEGENERATE, FAILED };

/// The outward normal (b - a) x (c - a), unnormalised, accurate for thin triangles too
/// (quickhull.cpp).
Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c);

/// The 3-D hull of the points `subset` of w.p (quickhull.cpp): large inputs first lose their
/// clearly interior points (the interior filter), then Quickhull.
Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out);

// Plane of each triangle (scaled frame), coplanar groups and the number of edges between
// different planes at each point.
struct Planes {
    std::vector<Vec3> normal;
    std::vector<double> offset;
    std::vector<double> area2;  // twice the triangle's area
    std::vector<int> group;     // plane id per triangle
    int groups = 0;
};

// Everything one hull leaves behind, reused across the shapes of a batch (their capacity
// saves the allocations that otherwise cost as much as a small hull).
struct Analysis {
    Triangulation t, previous;
    Planes pl;
    Hull hull;

    void reset() {
        hull.status = HullStatus::EMPTY;
        hull.dimension = -1;
        hull.vertices.clear();
        hull.faces.clear();
        hull.face_normals.clear();
        hull.face_offsets.clear();
        hull.face_planes.clear();
        hull.plane_normals.clear();
        hull.normal = Vec3{};
        hull.volume = hull.area = hull.diagonal = 0.0;
    }
};

/// The hull of `points` into analysis.hull (and its triangulation and planes, 3-D) (hull.cpp).
void hull_with(const Vec3* points, long long n, Workspace& w, Analysis& analysis);

}  // namespace meshcol::hull_detail
