#pragma once
// What the three files of the exact hull share (hull.hpp is their public face): Quickhull's
// workspace and triangulation (quickhull.cpp builds them), and the analysis of one point set
// that turns them into a Hull (hull.cpp), which the packing of many (hull_packing.cpp) reuses.
// Private to the core.

#include <array>
#include <cmath>
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
    double area2 = 0.0;   // the unnormalised normal's length: twice the area
    // The plane filter: a point's distance beyond it decides its side exactly (INFINITY:
    // never, the exact orientation decides).
    double filter = INFINITY;
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

// A face of the depth-first search for the faces a point sees: its next edge and how many
// edges are left.
struct Frame {
    int face, edge, left;
};

struct Workspace {
    std::vector<Vec3> p;  // scaled points
    double eps = 0.0;
    std::vector<int> mark;  // per point: stamp of the horizon check
    std::vector<Face> faces;  // a pool: faces[0 .. face_count) are this hull's
    size_t face_count = 0;
    std::vector<int> free_faces;  // the free slots: free_faces[0 .. free_top)
    size_t free_top = 0;
    std::vector<int> pending, visible, new_faces;
    std::vector<Conflict> orphans;
    std::vector<HorizonEdge> edges;
    std::vector<double> new_planes;  // the new faces' planes (nx, ny, nz, offset), packed
    std::vector<Frame> dfs;
    unsigned stamp = 0;
    // scratch of the analysis and the packing, kept across shapes
    std::vector<int> all, real, local, keep, parent, id, subset, removed, dropped;
    std::vector<double> largest;
    std::vector<char> used;
    std::vector<Conflict> sorted;  // the input, sorted and without duplicates
    std::vector<Vec3> unique_points;
    std::vector<int> unique_index;
    std::vector<int> filtered, filter_extremes;  // interior_filter's
    std::vector<double> filter_planes;
};

// A triangulated 3-D hull: triangles of point indices, their neighbours and their planes
// (unit normal, offset and twice the area, scaled frame, as Quickhull computed them).
// An edge of a triangulation, once: edge e of triangle i (from tri[i][e] to tri[i][e + 1]),
// whose neighbour j > i has it as its edge k (-1: no edge of j leads back to i).
struct TriangulationEdge {
    int i, e, j, k;
};

struct Triangulation {
    std::vector<std::array<int, 3>> tri;
    std::vector<std::array<int, 3>> neighbor;
    std::vector<Vec3> normal;
    std::vector<double> offset, area2;
    std::vector<TriangulationEdge> edges;  // in order of (i, e)
};

enum class Build { OK, DEGENERATE, FAILED };

/// triangle_normal's case of a sharp first corner (quickhull.cpp); `bounded` as there.
Vec3 triangle_normal_at_widest(const Vec3& a, const Vec3& b, const Vec3& c, bool& bounded);

/// The outward normal (b - a) x (c - a), unnormalised, accurate for thin triangles too: the
/// plain product when the corner at a is not sharp (the sine of its angle at least 1/4: within
/// a few ulps of the exact one), else taken at the widest corner or compensated. `bounded`
/// says the plain product was taken (at a or at the widest corner): then the unit normal's
/// direction is within 60 ulps of the exact one (the plane filter's premise, quickhull.cpp).
inline Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c, bool& bounded) {
    const Vec3 u = b - a, v = c - a;
    const Vec3 n = cross(u, v);
    if (16.0 * squared_norm(n) >= squared_norm(u) * squared_norm(v)) {
        bounded = true;
        return n;
    }
    return triangle_normal_at_widest(a, b, c, bounded);
}

/// The 3-D hull of the points `subset` of w.p (quickhull.cpp): large inputs first lose their
/// clearly interior points (the interior filter), then Quickhull.
Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out);

// The coplanar groups of a triangulation's triangles (their planes are the triangulation's).
struct Planes {
    std::vector<int> group;  // plane id per triangle
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
