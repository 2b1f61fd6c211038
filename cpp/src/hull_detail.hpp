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

// A point's place in the lexicographic order (hull.cpp): its x as an integer of the same
// order, and its index.
struct SortKey {
    std::uint64_t x;
    int index;
};

/// A triangle's plane as Quickhull keeps it: the unit normal, the offset (n . x - offset is
/// the distance of x), twice the area, and the plane filter: a distance beyond it decides
/// the side of a point exactly (INFINITY: never; the bound is proved beside face_plane).
struct Plane {
    Vec3 normal;
    double offset = 0.0, area2 = 0.0, filter = INFINITY;
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

// A face of Quickhull (quickhull_flat.cpp): its triangle, neighbours and plane, and the points
// outside it as a chain through the workspace's per-point links.
struct alignas(128) FlatFace {
    double nx, ny, nz, offset;  // the plane's unit normal and offset (Plane's)
    double filter, area2;       // and its filter and twice the area
    double furthest_distance;
    int v[3];  // point indices, counter-clockwise seen from outside
    int n[3];  // neighbour across edge v[i] -> v[(i + 1) % 3]
    int s[3];  // the edge of n[i] that leads back here (its twin)
    int head, tail;  // the chain of points outside this face (farther than eps), -1 for none
    int furthest;
    unsigned visit;
    bool visible, alive;
};

// An edge of a triangulation, once: edge e of triangle i (from tri[i][e] to tri[i][e + 1]),
// whose neighbour j > i has it as its edge k (-1: no edge of j leads back to i).
struct TriangulationEdge {
    int i, e, j, k;
};

struct Workspace {
    std::vector<Vec3> p;  // scaled points
    double eps = 0.0;
    std::vector<int> mark;  // per point: stamp of the horizon check
    std::vector<int> free_faces;  // the free slots
    std::vector<int> pending, new_faces;
    std::vector<int> visible;  // find_horizon's visible faces: visible[0 .. visible_count)
    std::vector<HorizonEdge> edges;  // and its horizon: edges[0 .. edge_count)
    size_t visible_count = 0, edge_count = 0;
    std::vector<Frame> dfs;
    unsigned stamp = 0;
    // scratch of the analysis and the packing, kept across shapes
    std::vector<int> all, real, local, keep, parent, id, subset, removed, dropped;
    std::vector<double> largest;
    std::vector<char> used;
    std::vector<SortKey> sort_keys;  // hull_with's sort of the input: the keys,
    std::vector<double> sort_x;      // their x (-0.0 as 0.0),
    std::vector<SortKey> sorted_keys;  // and the keys in order (a small input's)
    std::vector<Vec3> unique_points;
    std::vector<int> unique_index;
    std::vector<int> filtered, filter_extremes;  // interior_filter's
    std::vector<double> filter_planes;
    // the flat construction's (quickhull_flat.cpp)
    std::vector<FlatFace> flat_faces;
    std::vector<int> next_point;  // per point: the next point of its face's chain, -1 at the end
    std::vector<TriangulationEdge> edge_scratch;  // the compaction's edges before their count
};

// The corner after corner e of a triangle (a table: `e == 2 ? 0 : e + 1` compiles to a branch
// that mispredicts when e follows no pattern).
inline constexpr int kNextCorner[3] = {1, 2, 0};

// A triangulated 3-D hull: triangles of point indices, their planes (unit normal, offset and
// twice the area, scaled frame, as Quickhull computed them), and each edge once with the
// triangles on either side.
struct Triangulation {
    std::vector<std::array<int, 3>> tri;
    std::vector<Vec3> normal;
    std::vector<double> offset, area2;
    std::vector<TriangulationEdge> edges;  // in order of (i, e)
};

enum class Build { OK, DEGENERATE, FAILED };

/// The plane of the counter-clockwise triangle a b c, points scaled into (-1, 1)^3.
///
/// Its normal is the outward (b - a) x (c - a), accurate for thin triangles too: the plain
/// product when the corner at a is not sharp (the sine of its angle at least 1/4: within a few
/// ulps of the exact one), else taken at the widest corner or compensated
/// (face_plane_at_widest). When the plain product was taken (at a or at the widest corner),
/// the unit normal's direction is within 60 ulps of the exact one: the plane filter's premise.
///
/// The plane filter (Shewchuk's static filter, on the plane): the side of x decided by its
// plane distance d = fl(fl(n . x) - offset) when |d| > kPlaneFilter, by the exact orientation
// otherwise. The bound, for points scaled into (-1, 1)^3 and eps = 2^-53:
// - the plain product n' = fl(u') x fl(v') of a corner whose rounded edges pass
//   16 |n'|^2 >= |u'|^2 |v'|^2 (so |n'| >= |u| |v| / 4 up to a few eps) is within
//   4.01 eps sqrt(3) |u| |v| <= 28.1 eps |n'| of the exact N = u x v (each component of a
//   2 x 2 minor: two rounded differences, a product, a difference: four roundings);
// - the unit normal n = fl(n' / fl(sqrt(fl(n' . n')))) is within 3.6 eps of n'/|n'|, and
//   n'/|n'| within 2 x 28.1 eps of N/|N|: |n - N/|N|| <= 60 eps;
// - fl(n . x) and offset = fl(n . a) are within gamma_3 |n|_1 < 5.8e-16 of n . x and n . a;
// - so d / (1 + eps) is within 60 eps |x - a| + 1.16e-15 < 4.8e-14 of N/|N| . (x - a), whose
//   sign is the orientation's (|x - a| < 2 sqrt(3)): |d| > 1e-13 decides it.
// A normal taken by the compensated product, or of length below 1e-140 (where the squares of
// the test may lose their relative accuracy to underflow), gets no filter.
// The bound above, the shortest normal that gets it, and the test of a corner that is not
// sharp (kSharpCorner |n|^2 >= |u|^2 |v|^2: the sine of its angle at least 1/4), shared by
// face_plane, face_plane_at_widest (quickhull.cpp) and the two-lane form (quickhull_flat.cpp).
constexpr double kPlaneFilter = 1e-13;
constexpr double kPlaneFilterMinLength = 1e-140;
constexpr double kSharpCorner = 16.0;

inline Plane plane_of_normal(const Vec3& n, bool bounded, const Vec3& a) {
    const double len = norm(n);
    Plane plane;
    plane.normal = len > 0.0 ? n / len : Vec3{};
    plane.offset = dot(plane.normal, a);
    plane.area2 = len;
    plane.filter = bounded && len >= kPlaneFilterMinLength ? kPlaneFilter : INFINITY;
    return plane;
}

/// face_plane's case of a sharp first corner (quickhull.cpp), out of line: `uu` and `vv` are
/// the squared lengths of b - a and c - a, which face_plane's test has just computed.
Plane face_plane_at_widest(const Vec3& a, const Vec3& b, const Vec3& c, double uu, double vv);

inline Plane face_plane(const Vec3& a, const Vec3& b, const Vec3& c) {
    // The fast case in scalars (a Vec3 passed by reference with a flag spilled it to memory).
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double nn = nx * nx + ny * ny + nz * nz;
    const double uu = ux * ux + uy * uy + uz * uz, vv = vx * vx + vy * vy + vz * vz;
    if (!(kSharpCorner * nn >= uu * vv)) return face_plane_at_widest(a, b, c, uu, vv);
    constexpr double kPlaneFilter = 1e-13;
    // nn is a sum of squares: never negative, so the square root needs no errno path.
    const double len = __builtin_sqrt(nn);
    Plane plane;
    if (len > 0.0) {
        plane.normal = Vec3{nx / len, ny / len, nz / len};
    } else {
        plane.normal = Vec3{};
    }
    plane.offset = plane.normal.x * a.x + plane.normal.y * a.y + plane.normal.z * a.z;
    plane.area2 = len;
    plane.filter = len >= 1e-140 ? kPlaneFilter : INFINITY;
    return plane;
}

/// The first point of `subset` of least and of greatest x, y and z, into extreme[0 .. 6) in
/// that order (quickhull.cpp).
void axis_extremes(const std::vector<Vec3>& p, const std::vector<int>& subset, int extreme[6]);

/// The starting tetrahedron of `subset` (quickhull.cpp): corner[0 .. 4) with the faces
/// (0 1 2), (0 3 1), (1 3 2) and (2 3 0) outward, or DEGENERATE; from the subset's
/// axis_extremes when given.
Build start_tetrahedron(const std::vector<Vec3>& p, double eps, const std::vector<int>& subset,
                        const int extreme[6], int corner[4]);
Build start_tetrahedron(const std::vector<Vec3>& p, double eps, const std::vector<int>& subset,
                        int corner[4]);

/// Quickhull of the points `subset` of w.p on flat storage (quickhull_flat.cpp): the same
/// steps, triangulation and result as the construction it replaced, which the C++ tests keep
/// as their reference (cpp/tests/quickhull_reference.hpp).
/// `start`, when given, is start_tetrahedron's answer for this subset (not computed again).
Build quickhull_flat(Workspace& w, const std::vector<int>& subset, Triangulation& out,
                     const int* start = nullptr);

/// The principal axes of p[0 .. n) about `centre` (Jacobi eigenvectors of their covariance),
/// unit, largest spread first (hull.cpp).
void principal_axes(const Vec3* p, long long n, const Vec3& centre, Vec3 axes[3]);

/// The flatness rule (hull.cpp): how many of the widths of p[0 .. n) along `axes` (the
/// principal axes about `centre`) exceed flat_relative_tolerance times the box's `diagonal`.
int flatness_dimension(const Vec3* p, long long n, const Vec3& centre, const Vec3 axes[3],
                       double diagonal);

/// Whether points scaled into (-1, 1)^3, whose box has this `diagonal`, among them the
/// tetrahedron of p[corner[0 .. 4)], are clearly 3-D by the flatness rule (flatness_dimension
/// 3 whatever its axes), from the tetrahedron's determinant alone (hull.cpp).
bool clearly_solid(const Vec3* p, const int corner[4], double diagonal);

/// Whether some four of p[candidate[0 .. count)] are clearly_solid (hull.cpp).
bool clearly_solid_among(const Vec3* p, const int* candidate, int count, double diagonal);

/// Inputs of at most this many points are sorted by rank (hull.cpp's sort_points): below
/// it the quadratic count of the x below each point costs less than std::sort's
/// mispredicted comparisons (the sort alone, Gaussian points, session 24: 0.58 against
/// 1.7 us at 64 points, 4.8 against 6.3 at 192, 8.3 against 8.9 at 256; a run of equal x
/// then costs its std::sort on top, which the lower bound keeps small).
inline constexpr size_t kRankSortMaxPoints = 192;

/// Inputs of at least this many points first lose their clearly interior points
/// (quickhull.cpp's interior filter).
inline constexpr size_t kFilterMinPoints = 4096;

/// The 3-D hull of the points `subset` of w.p (quickhull.cpp): large inputs first lose their
/// clearly interior points (the interior filter), then Quickhull. `start` as quickhull_flat's,
/// for a subset that the filter leaves whole (below kFilterMinPoints points).
Build quickhull(Workspace& w, const std::vector<int>& subset, Triangulation& out,
                const int* start = nullptr);

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
    /// Whether a 3-D hull gets its faces, its per-face normals, offsets and planes, its volume
    /// and its area (pack_polytopes turns this off: it reads none of them, and takes the faces
    /// from t.tri through Workspace::local, each point's vertex index). Without it, a hull
    /// whose every triangle is its own plane leaves plane_normals empty: they are t.normal.
    bool geometry = true;

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

/// The packing's one direction per class of `count` directions (hull_packing.cpp), flat
/// (x, y, z) triples: for the tests.
std::vector<double> unique_directions_of(const Vec3* d, size_t count, bool signed_classes);

}  // namespace meshcol::hull_detail
