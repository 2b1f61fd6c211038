// The contacts of two posed meshes (mesh_query.hpp: mesh_contacts): every crossing triangle
// pair, as mesh_intersects finds the first one, each with its own penetration depth by the
// separating axis theorem (triangle_penetration.cpp), and beside it coal's per-pair quantity
// (face_depth: how far b's triangle reaches behind a's face, which coal 3.0.3 reports).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "mesh_query_detail.hpp"
#include "radix_sort.hpp"

namespace meshcol {
using namespace mesh_detail;
namespace {

// A crossing pair found by the descent: leaf-order triangles, input faces, its depths, the
// normal of its penetration and the exact test's shared point (a's frame; NaN unless the
// contacts are listed), kept so that a listed contact needs only its witness points, and a
// touching one (depth 0) not even those.
struct Found {
    double depth, face_depth;
    std::int64_t face_a, face_b;
    std::int32_t i, j;
    Vec3 normal, shared;
    int axis;  // triangle_penetration's axis of the depth
};

// Deeper first; of equal depths the lower (face_a, face_b).
bool deeper(const Found& x, const Found& y) {
    if (x.depth != y.depth) return x.depth > y.depth;
    return std::tie(x.face_a, x.face_b) < std::tie(y.face_a, y.face_b);
}

// A found pair to list, with its triangle of b as the descent mapped it into a's frame.
struct Listed {
    Found found;
    Vec3 tb[3];
};

// The contact of pair `f` in the world frame, tb its triangle of b mapped into a's frame as
// the descent mapped it (the same bits, so the points are those of the depth's triangles). A
// depth-0 pair keeps the point the descent's exact test shared, when it kept one; any other
// pair's points are triangle_penetration_points' (for a touching pair its axis's features
// when they meet, else a shared point: on bench_mesh_query's torus moved 30%, 348 of the 394
// touching pairs without a kept point take the features; benchmarks/RESULTS.md, session 30).
MeshContact contact_of(const Found& f, const Vec3* tb, const MeshBvh& a, const Pose& pose_a) {
    const Vec3* ta = a.triangle(f.i);
    TrianglePenetration p;
    p.depth = f.depth;
    p.normal = f.normal;
    p.axis = f.axis;
    if (f.depth == 0.0 && !std::isnan(f.shared.x)) {
        p.point_a = p.point_b = f.shared;
    } else {
        triangle_penetration_points(ta, tb, p);
    }
    MeshContact c;
    c.depth = p.depth;
    c.normal = pose_a.rotate(p.normal);
    c.point = pose_a.apply((p.point_a + p.point_b) * 0.5);
    c.face_depth = f.face_depth;
    c.triangle_a = f.face_a;
    c.triangle_b = f.face_b;
    return c;
}

// How far triangle tb (a's frame) reaches behind triangle i of a along its unit normal.
double face_depth(const MeshBvh& a, std::int32_t i, const Vec3* ta, const Vec3* tb) {
    const Vec3& n = a.triangle_normal(i);
    double deepest = 0.0;
    for (int k = 0; k < 3; ++k) deepest = max2(deepest, dot(n, ta[0] - tb[k]));
    return deepest;
}

// A listed pair's sort key, (face_a, face_b) as one number, beside its place in `found`.
struct Key {
    std::uint64_t faces;
    size_t at;
};

// `keys` in increasing order of `faces` (all distinct, so the order is the one std::sort
// gives): from kRadixKeys keys on by the core's radix sort, a byte a digit (four passes for
// two meshes below 65,536 faces), whose compares do not branch where a comparison sort's go
// either way at random (std::sort's took about 10,000 mispredictions of callgrind's model for
// the moved torus's 1,555 pairs); below it, std::sort.
constexpr size_t kRadixKeys = 256;

void sort_keys(std::vector<Key>& keys) {
    if (keys.size() < kRadixKeys) {
        std::sort(keys.begin(), keys.end(), [](const Key& x, const Key& y) { return x.faces < y.faces; });
        return;
    }
    lsd_radix_sort<8>(keys, [](const Key& k) { return k.faces; });
}

}  // namespace

MeshContactsOutput mesh_contacts(const MeshContactsInput& input, std::vector<MeshContact>* contacts) {
    MeshContactsOutput out;
    out.normal = out.point = Vec3{kNaN, kNaN, kNaN};
    if (contacts != nullptr) contacts->clear();
    if (input.a == nullptr || input.b == nullptr || !input.a->valid() || !input.b->valid() ||
        input.max_contacts < 0 || input.max_work < 0) {
        out.depth = out.face_depth = kNaN;
        out.status = Status::INVALID_INPUT;
        return out;
    }
    const MeshBvh& a = *input.a;
    const MeshBvh& b = *input.b;
    if (!mesh_pair_in_range(a, input.pose_a, b, input.pose_b)) {
        out.depth = out.face_depth = kNaN;
        out.status = Status::OUT_OF_RANGE;
        return out;
    }
    const Relative rel(input.pose_a, input.pose_b, a, b);
    const bool listed = contacts != nullptr && input.max_contacts > 0;
    std::vector<Listed> found;
    Found best{-1.0, 0.0, -1, -1, -1, -1, Vec3{}, Vec3{kNaN, kNaN, kNaN}, -1};
    long long work = 0;
    const bool capped = for_each_crossing_pair(
        a, b, rel, input.max_work, &work, listed,
        [&](std::int32_t i, std::int32_t j, const Vec3* ta, const Vec3* tb, const Vec3& shared, bool general) {
            ++out.count;
            const TrianglePenetration p = triangle_penetration(ta, tb, false, general);
            const Found f{p.depth, face_depth(a, i, ta, tb), a.face_index(i), b.face_index(j), i, j, p.normal, shared, p.axis};
            if (best.i < 0 || deeper(f, best)) best = f;
            out.face_depth = max2(out.face_depth, f.face_depth);
            if (listed) found.push_back(Listed{f, {tb[0], tb[1], tb[2]}});
            return false;
        });
    out.status = capped ? Status::MAX_ITERATIONS : Status::CONVERGED;
    if (best.i < 0) {
        out.depth = 0.0;
        return out;
    }
    const Vec3* local_b = b.triangle(best.j);
    const Vec3 best_b[3] = {rel.apply(local_b[0]), rel.apply(local_b[1]), rel.apply(local_b[2])};
    const MeshContact deepest = contact_of(best, best_b, a, input.pose_a);
    out.depth = deepest.depth;
    out.normal = deepest.normal;
    out.point = deepest.point;
    out.triangle_a = deepest.triangle_a;
    out.triangle_b = deepest.triangle_b;
    if (listed) {
        // In order of (face_a, face_b), each pair once: sorted as one key each (a face index is
        // below 2^31, MeshBvh's limit) beside its place in `found`, not the 88-byte entries.
        std::vector<Key> order(found.size());
        for (size_t k = 0; k < found.size(); ++k)
            order[k] = Key{static_cast<std::uint64_t>(found[k].found.face_a) << 32 |
                               static_cast<std::uint64_t>(found[k].found.face_b),
                           k};
        sort_keys(order);
        const auto kept = static_cast<size_t>(std::min<std::int64_t>(input.max_contacts, out.count));
        contacts->reserve(kept);
        for (size_t k = 0; k < kept; ++k) {
            const Listed& l = found[order[k].at];
            contacts->push_back(contact_of(l.found, l.tb, a, input.pose_a));
        }
    }
    return out;
}

}  // namespace meshcol
