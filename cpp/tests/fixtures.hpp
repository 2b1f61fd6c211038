#pragma once
/// Shapes, poses and meshes with known answers, shared by the test files.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "meshcol/hull.hpp"
#include "meshcol/mesh_bvh.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol::fixtures {

/// A seeded stream of doubles in [-1, 1): a 64-bit linear congruential generator (Knuth's
/// MMIX constants), its top 53 bits scaled. The tests' random poses and points, the same
/// sequence on every platform and standard library.
struct Uniform {
    std::uint64_t state;
    double operator()() {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(state >> 11) * 0x1p-52 - 1.0;
    }
};

/// The same bytes: answers compared bit for bit (NaNs of the same pattern compare equal).
template <class T>
bool same_bytes(const T* a, const T* b, size_t count) {
    return count == 0 || std::memcmp(a, b, count * sizeof(T)) == 0;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && same_bytes(a.data(), b.data(), a.size());
}

inline Pose at(double x, double y, double z) {
    Pose p;
    p.translation = {x, y, z};
    return p;
}

/// Rotation by `angle` radians in the plane of axes `i` and `j` (from i towards j), placed
/// at (x, y, z).
inline Pose turned(int i, int j, double angle, double x, double y, double z) {
    Pose p = at(x, y, z);
    const double c = std::cos(angle), s = std::sin(angle);
    p.rotation.m[i][i] = c;
    p.rotation.m[i][j] = -s;
    p.rotation.m[j][i] = s;
    p.rotation.m[j][j] = c;
    return p;
}

/// Rotation by `angle` radians about z, placed at (x, y, z).
inline Pose turned_about_z(double angle, double x, double y, double z) {
    return turned(0, 1, angle, x, y, z);
}

/// Rotation by `angle` radians about x, placed at (x, y, z): its local +z is
/// (0, -sin, cos).
inline Pose turned_about_x(double angle, double x, double y, double z) {
    return turned(1, 2, angle, x, y, z);
}

inline ShapeView box(double hx, double hy, double hz) {
    ShapeView v;
    v.kind = ShapeKind::BOX;
    v.params[0] = hx;
    v.params[1] = hy;
    v.params[2] = hz;
    return v;
}

inline ShapeView sphere(double radius) {
    ShapeView v;
    v.kind = ShapeKind::SPHERE;
    v.params[0] = radius;
    return v;
}

inline ShapeView capsule(double radius, double half_length) {
    ShapeView v;
    v.kind = ShapeKind::CAPSULE;
    v.params[0] = radius;
    v.params[1] = half_length;
    return v;
}

inline ShapeView ellipsoid(double a, double b, double c) {
    ShapeView v;
    v.kind = ShapeKind::ELLIPSOID;
    v.params[0] = a;
    v.params[1] = b;
    v.params[2] = c;
    return v;
}

/// The eight corners of the box [-h, h]^3 (x fastest).
inline std::vector<Vec3> cube_corners(double h) {
    std::vector<Vec3> corners;
    for (int k = 0; k < 8; ++k)
        corners.push_back({(k & 1) ? h : -h, (k & 2) ? h : -h, (k & 4) ? h : -h});
    return corners;
}

/// A polytope view of `points` (no adjacency, no SAT features); `points` must outlive it.
inline ShapeView polytope(const std::vector<Vec3>& points) {
    ShapeView v;
    v.kind = ShapeKind::POLYTOPE;
    v.vertices = points.data();
    v.vertex_count = static_cast<int>(points.size());
    return v;
}

/// Bisects [lo, hi] `steps` times towards where `side(s, &agree)` changes value (`low` is its
/// value at lo, another than at hi), for the tests that compare two forms of a computation at
/// the flip points of its decision: whether the forms agreed at every probe.
template <class Side>
bool bisect_agreeing(Side side, double lo, double hi, bool low, int steps) {
    bool all = true;
    for (int step = 0; step < steps; ++step) {
        const double mid = 0.5 * (lo + hi);
        bool agree = false;
        (side(mid, &agree) == low ? lo : hi) = mid;
        all = all && agree;
    }
    return all;
}

/// A closed, outward-wound triangle mesh: vertices (3 per vertex) and faces (3 per triangle).
struct TriangleMesh {
    std::vector<double> vertices;
    std::vector<std::int64_t> faces;

    MeshBvh bvh() const {
        return MeshBvh(vertices.data(), static_cast<std::int64_t>(vertices.size() / 3), faces.data(),
                       static_cast<std::int64_t>(faces.size() / 3));
    }
};

/// The box [lo, hi] as 12 outward-wound triangles.
inline TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi) {
    TriangleMesh m;
    for (int k = 0; k < 8; ++k) {
        m.vertices.push_back((k & 1) ? hi.x : lo.x);
        m.vertices.push_back((k & 2) ? hi.y : lo.y);
        m.vertices.push_back((k & 4) ? hi.z : lo.z);
    }
    // corner k has bit 0 = x, bit 1 = y, bit 2 = z; each face counter-clockwise from outside
    const std::int64_t quads[6][4] = {
        {0, 2, 3, 1},  // z = lo
        {4, 5, 7, 6},  // z = hi
        {0, 1, 5, 4},  // y = lo
        {2, 6, 7, 3},  // y = hi
        {0, 4, 6, 2},  // x = lo
        {1, 3, 7, 5},  // x = hi
    };
    for (const auto& q : quads) m.faces.insert(m.faces.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    return m;
}

/// Whether two packings (`pack_polytopes`) hold the same arrays, byte for byte.
inline bool same_packing(const PackedPolytopes& a, const PackedPolytopes& b) {
    return same_bytes(a.status, b.status) && same_bytes(a.vertices, b.vertices) &&
           same_bytes(a.offsets, b.offsets) && same_bytes(a.adjacency_offsets, b.adjacency_offsets) &&
           same_bytes(a.adjacency, b.adjacency) && same_bytes(a.face_offsets, b.face_offsets) &&
           same_bytes(a.face_normals, b.face_normals) &&
           same_bytes(a.edge_pair_offsets, b.edge_pair_offsets) && same_bytes(a.edge_pairs, b.edge_pairs);
}

/// A set of polytopes over packed hulls (`pack_polytopes`' arrays, which the caller keeps),
/// with its own kinds, params and edge-class cache (not copied: the view points to them).
struct PolytopeSet {
    std::vector<std::int8_t> kinds;
    std::vector<double> params;
    EdgeClasses classes;
    ConvexSetView view;

    explicit PolytopeSet(const PackedPolytopes& p)
        : kinds(p.status.size(), static_cast<std::int8_t>(ShapeKind::POLYTOPE)),
          params(4 * p.status.size(), 0.0), classes(static_cast<std::int64_t>(p.status.size())) {
        view.vertices = p.vertices.data();
        view.vertex_count = static_cast<std::int64_t>(p.vertices.size() / 3);
        view.offsets = p.offsets.data();
        view.shape_count = static_cast<std::int64_t>(p.status.size());
        view.kinds = kinds.data();
        view.params = params.data();
        view.adjacency_offsets = p.adjacency_offsets.data();
        view.adjacency = p.adjacency.data();
        view.face_offsets = p.face_offsets.data();
        view.face_normals = p.face_normals.data();
        view.edge_pair_offsets = p.edge_pair_offsets.data();
        view.edge_pairs = p.edge_pairs.data();
        view.edge_classes = &classes;
    }
    PolytopeSet(const PolytopeSet&) = delete;
    PolytopeSet& operator=(const PolytopeSet&) = delete;
};

/// A packed set of `count` shapes over the caller's arrays (`vertices` (V, 3) flat, or null for
/// primitives only), with no adjacency or SAT features.
inline ConvexSetView convex_set(const std::int64_t* offsets, const std::int8_t* kinds,
                                const double* params, std::int64_t count,
                                const std::vector<double>* vertices = nullptr) {
    ConvexSetView set;
    if (vertices != nullptr) {
        set.vertices = vertices->data();
        set.vertex_count = static_cast<std::int64_t>(vertices->size() / 3);
    }
    set.offsets = offsets;
    set.shape_count = count;
    set.kinds = kinds;
    set.params = params;
    return set;
}

}  // namespace meshcol::fixtures
