#include "meshcol/sat.hpp"

#include <cmath>
#include <limits>

#include "meshcol/defaults.hpp"

namespace meshcol {

namespace {

const Vec3 kBoxFaces[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const Vec3 kBoxEdges[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

struct Features {
    const Vec3* faces;
    int face_count;
    const Vec3* edges;
    int edge_count;
    int vertices;  // support cost
};

Features features_of(const ShapeView& s) {
    if (s.kind == ShapeKind::BOX) return {kBoxFaces, 6, kBoxEdges, 3, 1};
    return {s.face_normals, s.face_count, s.edge_directions, s.edge_count, s.vertex_count};
}

}  // namespace

bool has_sat_features(const ShapeView& s) {
    // A polytope's features are attached by the caller; a point has none and needs none.
    return s.kind == ShapeKind::BOX ||
           (s.kind == ShapeKind::POLYTOPE && (s.has_features || s.vertex_count == 1));
}

// The Minkowski difference a - b of two polytopes has as face normals the face normals of a,
// minus those of b, and +-(e_a x e_b) for edge directions e_a, e_b: the smallest support value
// over these axes is the exact depth (the distance from the origin to the boundary), since any
// unit axis n gives an upper bound h(n) >= depth.
SatResult sat_penetration(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, long long max_work) {
    SatResult res;
    if (!has_sat_features(a) || !has_sat_features(b)) return res;
    const Features fa = features_of(a), fb = features_of(b);
    const long long axes = static_cast<long long>(fa.face_count) + fb.face_count +
                           2LL * fa.edge_count * fb.edge_count;
    if (axes * (fa.vertices + fb.vertices) > max_work) return res;
    res.ran = true;
    // Work in a's frame: b's rotation and origin mapped into it.
    const Mat3 rot = pose_a.rotation.transposed() * pose_b.rotation;
    const Vec3 trans = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_axis{1.0, 0.0, 0.0};
    auto test = [&](const Vec3& n) {
        // Overlap along n: h_a(n) + h_b(-n), with b's support taken in b's frame.
        const Vec3 pa = support_core(a, n).point;
        const Vec3 pb = rot * support_core(b, rot.transpose_times(-n)).point + trans;
        const double overlap = dot(n, pa) - dot(n, pb);
        ++res.axes;
        if (overlap < best) {
            best = overlap;
            best_axis = n;
        }
    };
    for (int i = 0; i < fa.face_count; ++i) test(fa.faces[i]);
    for (int j = 0; j < fb.face_count; ++j) test(-(rot * fb.faces[j]));
    for (int i = 0; i < fa.edge_count; ++i) {
        for (int j = 0; j < fb.edge_count; ++j) {
            const Vec3 c = cross(fa.edges[i], rot * fb.edges[j]);
            const double len = norm(c);
            // Parallel edges span no face of their own: the face normals cover it.
            if (!(len > defaults::sat_parallel_edge_sine)) continue;
            const Vec3 n = c / len;
            test(n);
            test(-n);
        }
    }
    if (!std::isfinite(best)) {
        res.ran = false;
        return res;
    }
    if (best < 0.0) {
        res.separated = true;
        res.depth = 0.0;
    } else {
        res.depth = best;
    }
    res.normal = pose_a.rotate(best_axis);
    return res;
}

}  // namespace meshcol
