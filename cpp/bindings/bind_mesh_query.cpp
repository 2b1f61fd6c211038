// Exposes mesh_bvh.hpp and mesh_query.hpp: a set of mesh hierarchies built once, and batched
// mesh-pair and ray queries over it. A batched query kind is its output struct's columns (one
// list, columns.hpp) and one function that makes each item's output.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/typing.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/mesh_bvh.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/triangle.hpp"
#include "call_args.hpp"
#include "columns.hpp"
#include "ndarray.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace meshcol::bindings;

namespace {

using meshcol::Vec3;

/// The hierarchies of M meshes, packed as in meshcol.mesh_query.MeshSet, and the set's default
/// poses, read and checked for rigidity once (`set_poses`) so that a query without poses reads
/// no array.
/// The hierarchies of a set, one per distinct mesh: meshes whose vertex and face blocks are
/// the same bytes (instances of one asset) share one hierarchy, built once (the build is
/// deterministic, so a copy's own would be the same, bit for bit). Shared read-only across
/// threads (MeshBvh is immutable).
class SharedHierarchies {
public:
    const meshcol::MeshBvh& operator[](size_t i) const { return built_[which_[i]]; }
    size_t size() const { return which_.size(); }
    size_t distinct() const { return built_.size(); }
    std::vector<meshcol::MeshBvh>::const_iterator begin() const { return built_.begin(); }
    std::vector<meshcol::MeshBvh>::const_iterator end() const { return built_.end(); }

    /// Groups the m meshes (vertex rows vo[i]..vo[i + 1] of v, face rows fo[i]..fo[i + 1] of
    /// f) by their bytes and builds each distinct one on `threads` threads.
    void build(const double* v, const std::int64_t* vo, const std::int64_t* f, const std::int64_t* fo, long long m,
               int threads) {
        which_.assign(static_cast<size_t>(m), 0);
        std::vector<long long> first;  // the mesh each distinct hierarchy is built from
        // Candidates by a cheap key (the block sizes and a few leading values), then compared
        // whole: a lookup is one memcmp per earlier distinct mesh of the same key.
        std::unordered_map<std::uint64_t, std::vector<size_t>> by_key;
        const auto same = [&](long long i, long long j) {
            const std::int64_t nv = vo[i + 1] - vo[i], nf = fo[i + 1] - fo[i];
            return nv == vo[j + 1] - vo[j] && nf == fo[j + 1] - fo[j] &&
                   std::memcmp(v + 3 * vo[i], v + 3 * vo[j], sizeof(double) * 3 * static_cast<size_t>(nv)) == 0 &&
                   std::memcmp(f + 3 * fo[i], f + 3 * fo[j], sizeof(std::int64_t) * 3 * static_cast<size_t>(nf)) == 0;
        };
        for (long long i = 0; i < m; ++i) {
            const std::int64_t nv = vo[i + 1] - vo[i], nf = fo[i + 1] - fo[i];
            std::uint64_t key = static_cast<std::uint64_t>(nv) * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint64_t>(nf);
            const std::int64_t sample = std::min<std::int64_t>(3 * nv, 12);
            for (std::int64_t k = 0; k < sample; ++k) {
                std::uint64_t bits;
                std::memcpy(&bits, v + 3 * vo[i] + k, sizeof(bits));
                key = (key ^ bits) * 0x100000001B3ULL;
            }
            std::vector<size_t>& bucket = by_key[key];
            size_t found = first.size();
            for (const size_t d : bucket)
                if (same(i, first[d])) {
                    found = d;
                    break;
                }
            if (found == first.size()) {
                bucket.push_back(found);
                first.push_back(i);
            }
            which_[static_cast<size_t>(i)] = found;
        }
        built_.resize(first.size());
        const auto n = static_cast<long long>(first.size());
        meshcol::parallel_for(n, meshcol::resolve_threads(threads, n, 1), [&](long long begin, long long end) {
            for (long long d = begin; d < end; ++d) {
                const long long i = first[static_cast<size_t>(d)];
                built_[static_cast<size_t>(d)] =
                    meshcol::MeshBvh(v + 3 * vo[i], vo[i + 1] - vo[i], f + 3 * fo[i], fo[i + 1] - fo[i]);
            }
        });
    }

private:
    std::vector<meshcol::MeshBvh> built_;
    std::vector<size_t> which_;  // mesh -> its hierarchy in built_
};

struct MeshBvhSet {
    SharedHierarchies meshes;
    std::vector<meshcol::Pose> poses;  // default world-from-local poses (identity until set)
    std::vector<char> rigid;           // poses[i] is rigid and finite

    const meshcol::MeshBvh& at(std::int64_t i) const {
        if (i < 0 || i >= static_cast<std::int64_t>(meshes.size()))
            throw std::invalid_argument("mesh index " + std::to_string(i) + " out of range [0, " +
                                        std::to_string(meshes.size()) + ")");
        return meshes[static_cast<size_t>(i)];
    }
};

void build_set(MeshBvhSet* self, Points vertices, Faces faces, Index64 vertex_offsets,
               Index64 face_offsets, int threads) {
    const size_t m1 = vertex_offsets.shape(0);
    if (m1 == 0 || face_offsets.shape(0) != m1)
        throw std::invalid_argument("vertex_offsets and face_offsets must both be (M + 1,), got (" +
                                    std::to_string(m1) + ",) and (" +
                                    std::to_string(face_offsets.shape(0)) + ",)");
    const std::int64_t* vo = vertex_offsets.data();
    const std::int64_t* fo = face_offsets.data();
    check_offsets(vo, m1, static_cast<std::int64_t>(vertices.shape(0)), "vertex_offsets");
    check_offsets(fo, m1, static_cast<std::int64_t>(faces.shape(0)), "face_offsets");
    const auto m = static_cast<long long>(m1 - 1);
    const double* v = vertices.data();
    const std::int64_t* f = faces.data();
    // Index checks first, on this thread, so the parallel build cannot throw.
    for (long long i = 0; i < m; ++i) {
        const std::int64_t nv = vo[i + 1] - vo[i];
        for (std::int64_t k = 3 * fo[i]; k < 3 * fo[i + 1]; ++k)
            if (f[k] < 0 || f[k] >= nv)
                throw std::invalid_argument("mesh " + std::to_string(i) + ": face " +
                                            std::to_string(k / 3 - fo[i]) + " has vertex index " +
                                            std::to_string(f[k]) + " out of range [0, " +
                                            std::to_string(nv) + ")");
        if (fo[i + 1] - fo[i] > std::numeric_limits<std::int32_t>::max() / 2)
            throw std::invalid_argument("mesh " + std::to_string(i) + " has too many faces");
    }
    new (self) MeshBvhSet();
    meshcol::Pose identity;
    identity.rotation = meshcol::Mat3::identity();
    self->poses.assign(static_cast<size_t>(m), identity);
    self->rigid.assign(static_cast<size_t>(m), 1);
    nb::gil_scoped_release release;
    self->meshes.build(v, vo, f, fo, m, threads);
}

// The poses of a query: the set's defaults, or the call's (M, 4, 4) matrices, each read and
// checked for rigidity where a pair or a ray uses it: a batch of a few pairs on a set of many
// meshes reads those few, not every pose. A matrix is copied before it is checked, so the pose
// used is the one checked even if its memory changes meanwhile.
struct PosedMeshes {
    const MeshBvhSet* set = nullptr;
    const double* matrices = nullptr;  // null: the set's poses

    /// The pose of mesh i into `pose`, and whether it is rigid and finite.
    bool pose(size_t i, meshcol::Pose& pose) const {
        if (matrices == nullptr) {
            pose = set->poses[i];
            return set->rigid[i] != 0;
        }
        double m[16];
        std::memcpy(m, matrices + 16 * i, sizeof m);
        pose = meshcol::Pose::from_matrix4(m);
        return meshcol::is_rigid_matrix4(m, meshcol::defaults::rigid_tolerance);
    }
};

// The poses of a query and its pairs, range-checked on this thread so that the parallel loop
// cannot throw.
struct PosedPairs : PosedMeshes {
    const std::int64_t* pairs = nullptr;
    long long count = 0;

    // The meshes and poses of pair k into a query's input (any with a, b, pose_a, pose_b),
    // and whether both poses are rigid.
    template <class Input>
    bool input(const MeshBvhSet& set, long long k, Input& q) const {
        const auto i = static_cast<size_t>(pairs[2 * k]), j = static_cast<size_t>(pairs[2 * k + 1]);
        q.a = &set.meshes[i];
        q.b = &set.meshes[j];
        const bool rigid_a = pose(i, q.pose_a);
        return pose(j, q.pose_b) && rigid_a;
    }
};

void check_pairs(const std::int64_t* pairs, long long count, size_t m) {
    for (long long k = 0; k < 2 * count; ++k)
        if (pairs[k] < 0 || pairs[k] >= static_cast<std::int64_t>(m))
            throw std::invalid_argument("pairs: index " + std::to_string(pairs[k]) +
                                        " out of range for " + std::to_string(m) + " meshes");
}

void read_poses(const MeshBvhSet& set, const std::optional<Poses>& poses, PosedMeshes& out) {
    const size_t m = set.meshes.size();
    out.set = &set;
    if (poses) {
        if (poses->shape(0) != m)
            throw std::invalid_argument("poses must be (" + std::to_string(m) + ", 4, 4), got (" +
                                        std::to_string(poses->shape(0)) + ", 4, 4)");
        out.matrices = poses->data();
    }
}

PosedPairs read_pairs(const MeshBvhSet& set, const std::optional<Poses>& poses, const Pairs& pairs) {
    const size_t m = set.meshes.size();
    PosedPairs out;
    read_poses(set, poses, out);
    out.pairs = pairs.data();
    out.count = static_cast<long long>(pairs.shape(0));
    check_pairs(out.pairs, out.count, m);
    return out;
}

// The intersection verdict of one posed pair and its status (shared by the batch and the
// single-pair entry, so the two cannot disagree).
inline meshcol::Status intersects_one(const meshcol::MeshBvh& a, const meshcol::Pose& pose_a, bool rigid_a,
                                      const meshcol::MeshBvh& b, const meshcol::Pose& pose_b, bool rigid_b,
                                      bool* intersecting) {
    *intersecting = false;
    if (!a.valid() || !b.valid() || !rigid_a || !rigid_b) return meshcol::Status::INVALID_INPUT;
    if (!meshcol::mesh_pair_in_range(a, pose_a, b, pose_b)) return meshcol::Status::OUT_OF_RANGE;
    *intersecting = meshcol::mesh_intersects(a, pose_a, b, pose_b);
    return meshcol::Status::CONVERGED;
}

// The columns of each batched query kind: the fields of its output struct, named as the
// Python result class names them (meshcol/collision/mesh_query.py, ray_cast.py).
using meshcol::MeshContact;
using meshcol::MeshContactsOutput;
using meshcol::MeshDepthOutput;
using meshcol::MeshDistanceOutput;
using meshcol::MeshRayOutput;
const auto kDepthColumns = std::make_tuple(
    field("depth", &MeshDepthOutput::depth), field("point_a", &MeshDepthOutput::point_a),
    field("point_b", &MeshDepthOutput::point_b), field("normal", &MeshDepthOutput::normal),
    field_as<std::int8_t>("deepest_mesh", &MeshDepthOutput::deepest_mesh),
    field("points_tested", &MeshDepthOutput::points_tested), field_as<std::int8_t>("status", &MeshDepthOutput::status));
const auto kContactsColumns = std::make_tuple(
    field("count", &MeshContactsOutput::count), field("depth", &MeshContactsOutput::depth),
    field("normal", &MeshContactsOutput::normal), field("point", &MeshContactsOutput::point),
    field("face_depth", &MeshContactsOutput::face_depth),
    field("triangle_a", &MeshContactsOutput::triangle_a), field("triangle_b", &MeshContactsOutput::triangle_b),
    field_as<std::int8_t>("status", &MeshContactsOutput::status));
// The listed contacts of every pair, one flat column each, named with a contact_ prefix.
const auto kContactColumns = std::make_tuple(
    field("contact_depth", &MeshContact::depth), field("contact_normal", &MeshContact::normal),
    field("contact_point", &MeshContact::point), field("contact_face_depth", &MeshContact::face_depth),
    field("contact_triangle_a", &MeshContact::triangle_a),
    field("contact_triangle_b", &MeshContact::triangle_b));
const auto kRayColumns = std::make_tuple(
    field("hit", &MeshRayOutput::hit), field("distance", &MeshRayOutput::distance), field("point", &MeshRayOutput::point),
    field("normal", &MeshRayOutput::normal), field("triangle", &MeshRayOutput::triangle),
    field_as<std::int8_t>("status", &MeshRayOutput::status));

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Vec3 kNaN3{kNaN, kNaN, kNaN};

// The distance result of one posed pair (shared by both batch entries, so they cannot
// disagree): INVALID_INPUT with NaN fields for a pose that is not rigid.
MeshDistanceOutput distance_one(const meshcol::MeshBvh& a, const meshcol::Pose& pose_a, bool rigid_a,
                                const meshcol::MeshBvh& b, const meshcol::Pose& pose_b, bool rigid_b,
                                double max_distance) {
    if (rigid_a && rigid_b) {
        meshcol::MeshDistanceInput q;
        q.a = &a;
        q.b = &b;
        q.pose_a = pose_a;
        q.pose_b = pose_b;
        q.max_distance = max_distance;
        return meshcol::mesh_distance(q);
    }
    MeshDistanceOutput r;
    r.distance = kNaN;
    r.point_a = r.point_b = kNaN3;
    r.status = meshcol::Status::INVALID_INPUT;
    return r;
}

void check_max_distance(double max_distance) {
    if (!(max_distance >= 0.0))
        throw std::invalid_argument("max_distance must be >= 0, got " + std::to_string(max_distance));
}

nb::dict depth_batch(const MeshBvhSet& set, std::optional<Poses> poses, Pairs pairs, int threads) {
    const PosedPairs in = read_pairs(set, poses, pairs);
    auto columns = columns_of<MeshDepthOutput>(static_cast<size_t>(in.count), kDepthColumns);
    run_items(in.count, threads, meshcol::defaults::mesh_min_pairs_per_thread, columns, [&](long long k) {
        meshcol::MeshDistanceInput q;
        if (in.input(set, k, q)) return meshcol::mesh_penetration_depth(q);
        MeshDepthOutput r;
        r.depth = kNaN;
        r.point_a = r.point_b = r.normal = kNaN3;
        r.status = meshcol::Status::INVALID_INPUT;
        return r;
    });
    return columns.dict();
}

// The contacts of each pair: the per-pair columns, and with max_contacts > 0 the listed
// contacts of every pair in pair order (pair k's are rows contact_offsets[k] ..
// contact_offsets[k + 1] of the contact_ columns).
nb::dict contacts_batch(const MeshBvhSet& set, std::optional<Poses> poses, Pairs pairs, int threads,
                        std::int64_t max_contacts, long long max_work) {
    if (max_contacts < 0)
        throw std::invalid_argument("max_contacts must be >= 0, got " + std::to_string(max_contacts));
    if (max_work < 0) throw std::invalid_argument("max_work must be >= 0, got " + std::to_string(max_work));
    const PosedPairs in = read_pairs(set, poses, pairs);
    const auto n = static_cast<size_t>(in.count);
    auto columns = columns_of<MeshContactsOutput>(n, kContactsColumns);
    std::vector<std::vector<MeshContact>> listed(max_contacts > 0 ? n : 0);
    run_items(in.count, threads, meshcol::defaults::mesh_min_pairs_per_thread, columns, [&](long long k) {
        meshcol::MeshContactsInput c;
        c.max_contacts = max_contacts;
        c.max_work = max_work;
        if (in.input(set, k, c))
            return meshcol::mesh_contacts(c, max_contacts > 0 ? &listed[static_cast<size_t>(k)] : nullptr);
        MeshContactsOutput r;
        r.depth = r.face_depth = kNaN;
        r.normal = r.point = kNaN3;
        r.status = meshcol::Status::INVALID_INPUT;
        return r;
    });
    auto offsets = new_array<Out<std::int64_t, -1>>({n + 1});
    std::int64_t total = 0;
    offsets.data()[0] = 0;
    for (size_t k = 0; k < n; ++k) {
        total += max_contacts > 0 ? static_cast<std::int64_t>(listed[k].size()) : 0;
        offsets.data()[k + 1] = total;
    }
    auto flat = columns_of<MeshContact>(static_cast<size_t>(total), kContactColumns);
    for (size_t k = 0; k < listed.size(); ++k)
        for (size_t i = 0; i < listed[k].size(); ++i)
            flat.write(offsets.data()[k] + static_cast<std::int64_t>(i), listed[k][i]);
    nb::dict out = columns.dict();
    out["contact_offsets"] = offsets.cast();
    for (auto item : flat.dict()) out[item.first] = item.second;
    return out;
}

// The first hit of each ray (origins[k], directions[k], world frame) on mesh meshes[k].
nb::dict ray_cast_batch(const MeshBvhSet& set, Index64 meshes, Points origins, Points directions,
                        std::optional<Poses> poses, double max_distance, int threads) {
    const size_t n = origins.shape(0), m = set.meshes.size();
    if (directions.shape(0) != n || meshes.shape(0) != n)
        throw std::invalid_argument("mesh_indices, origins and directions must have one row per ray, got " +
                                    std::to_string(meshes.shape(0)) + ", " + std::to_string(n) + " and " +
                                    std::to_string(directions.shape(0)));
    if (!(max_distance >= 0.0))
        throw std::invalid_argument("max_distance must be >= 0, got " + std::to_string(max_distance));
    const std::int64_t* index = meshes.data();
    for (size_t k = 0; k < n; ++k)
        if (index[k] < 0 || index[k] >= static_cast<std::int64_t>(m))
            throw std::invalid_argument("mesh_indices: index " + std::to_string(index[k]) + " out of range for " +
                                        std::to_string(m) + " meshes");
    PosedMeshes posed;
    read_poses(set, poses, posed);
    const double* o = origins.data();
    const double* d = directions.data();
    auto columns = columns_of<MeshRayOutput>(n, kRayColumns);
    run_items(static_cast<long long>(n), threads, meshcol::defaults::min_points_per_thread, columns, [&](long long k) {
        const auto i = static_cast<size_t>(index[k]);
        meshcol::MeshRayInput q;
        q.mesh = &set.meshes[i];
        const bool rigid = posed.pose(i, q.pose);
        q.origin = Vec3{o[3 * k], o[3 * k + 1], o[3 * k + 2]};
        q.direction = Vec3{d[3 * k], d[3 * k + 1], d[3 * k + 2]};
        q.max_distance = max_distance;
        if (rigid) return meshcol::mesh_ray_cast(q);
        MeshRayOutput r;
        r.distance = kNaN;
        r.point = r.normal = kNaN3;
        r.status = meshcol::Status::INVALID_INPUT;
        return r;
    });
    return columns.dict();
}

const auto kLargestColumns = std::make_tuple(
    field("distance", &meshcol::LargestDistanceOutput::distance), field("point", &meshcol::LargestDistanceOutput::point),
    field_as<std::int8_t>("status", &meshcol::LargestDistanceOutput::status));

// Item k: the largest distance from points[point_offsets[k]:point_offsets[k + 1]] (mesh
// meshes[k]'s local frame) to that mesh's surface; `point` is the index into the item's block.
nb::dict largest_distance_batch(const MeshBvhSet& set, Index64 meshes, Points points, Index64 point_offsets,
                                int threads) {
    const size_t n = meshes.shape(0), m = set.meshes.size();
    if (point_offsets.shape(0) != n + 1)
        throw std::invalid_argument("point_offsets must have one more entry than meshes, got " +
                                    std::to_string(point_offsets.shape(0)) + " for " + std::to_string(n));
    const std::int64_t* index = meshes.data();
    const std::int64_t* offsets = point_offsets.data();
    const auto total = static_cast<std::int64_t>(points.shape(0));
    if (offsets[0] != 0 || offsets[n] != total)
        throw std::invalid_argument("point_offsets must run from 0 to the number of points, " + std::to_string(total));
    for (size_t k = 0; k < n; ++k) {
        if (index[k] < 0 || index[k] >= static_cast<std::int64_t>(m))
            throw std::invalid_argument("meshes: index " + std::to_string(index[k]) + " out of range for " +
                                        std::to_string(m) + " meshes");
        if (offsets[k + 1] < offsets[k]) throw std::invalid_argument("point_offsets must not decrease");
    }
    const auto* p = reinterpret_cast<const Vec3*>(points.data());
    auto columns = columns_of<meshcol::LargestDistanceOutput>(n, kLargestColumns);
    run_items(static_cast<long long>(n), threads, meshcol::defaults::mesh_min_pairs_per_thread, columns,
              [&](long long k) {
                  return meshcol::largest_distance(set.meshes[static_cast<size_t>(index[k])], p + offsets[k],
                                                   offsets[k + 1] - offsets[k]);
              });
    return columns.dict();
}

using PatchNumbers = In<double, -1, 13>;  // g[9], v0, v1, lu, lv (SurfacePatch)

// The patches of arrays (SurfacePatch's fields), checked: a known map, at least one node.
std::vector<meshcol::SurfacePatch> read_patches(Kinds map, Pairs nodes, PatchNumbers numbers) {
    const size_t n = map.shape(0);
    if (nodes.shape(0) != n || numbers.shape(0) != n)
        throw std::invalid_argument("patch_map, patch_nodes and patch_numbers must have one row per patch, got " +
                                    std::to_string(n) + ", " + std::to_string(nodes.shape(0)) + " and " +
                                    std::to_string(numbers.shape(0)));
    std::vector<meshcol::SurfacePatch> out(n);
    const double* x = numbers.data();
    for (size_t k = 0; k < n; ++k) {
        meshcol::SurfacePatch& p = out[k];
        if (map.data()[k] < 0 || map.data()[k] > 3)
            throw std::invalid_argument("patch_map: unknown map " + std::to_string(map.data()[k]));
        p.map = static_cast<meshcol::PatchMap>(map.data()[k]);
        p.n_u = nodes.data()[2 * k];
        p.n_v = nodes.data()[2 * k + 1];
        if (p.n_u < 1 || p.n_v < 1) throw std::invalid_argument("patch_nodes must be >= 1");
        const int polar = static_cast<int>(x[13 * k + 5]);
        if (p.map == meshcol::PatchMap::SPHEROID && (polar < 0 || polar > 2))
            throw std::invalid_argument("patch_numbers: a spheroid's polar axis must be 0, 1 or 2");
        std::copy(x + 13 * k, x + 13 * k + 9, p.g);
        p.v0 = x[13 * k + 9];
        p.v1 = x[13 * k + 10];
        p.lu = x[13 * k + 11];
        p.lv = x[13 * k + 12];
    }
    return out;
}

// Item k: largest_distance_to_patches of patches[patch_offsets[k]:patch_offsets[k + 1]] to
// mesh meshes[k].
nb::dict largest_distance_to_patches_batch(const MeshBvhSet& set, Index64 meshes, Kinds patch_map, Pairs patch_nodes,
                                           PatchNumbers patch_numbers, Index64 patch_offsets, int threads) {
    const size_t n = meshes.shape(0), m = set.meshes.size();
    const std::vector<meshcol::SurfacePatch> patches = read_patches(patch_map, patch_nodes, patch_numbers);
    if (patch_offsets.shape(0) != n + 1)
        throw std::invalid_argument("patch_offsets must have one more entry than meshes, got " +
                                    std::to_string(patch_offsets.shape(0)) + " for " + std::to_string(n));
    const std::int64_t* index = meshes.data();
    const std::int64_t* offsets = patch_offsets.data();
    if (offsets[0] != 0 || offsets[n] != static_cast<std::int64_t>(patches.size()))
        throw std::invalid_argument("patch_offsets must run from 0 to the number of patches, " +
                                    std::to_string(patches.size()));
    for (size_t k = 0; k < n; ++k) {
        if (index[k] < 0 || index[k] >= static_cast<std::int64_t>(m))
            throw std::invalid_argument("meshes: index " + std::to_string(index[k]) + " out of range for " +
                                        std::to_string(m) + " meshes");
        if (offsets[k + 1] < offsets[k]) throw std::invalid_argument("patch_offsets must not decrease");
    }
    auto columns = columns_of<meshcol::LargestDistanceOutput>(n, kLargestColumns);
    run_items(static_cast<long long>(n), threads, meshcol::defaults::mesh_min_pairs_per_thread, columns,
              [&](long long k) {
                  return meshcol::largest_distance_to_patches(set.meshes[static_cast<size_t>(index[k])],
                                                              patches.data() + offsets[k], offsets[k + 1] - offsets[k]);
              });
    return columns.dict();
}

// Whether the surfaces of posed mesh pairs intersect, as a `result_type(intersecting, status)`
// (meshcol.collision.mesh_query.MeshIntersectsBatch). `poses` (None: the set's defaults) and
// `pairs` are taken as plain objects and read in place when they are already in the core's
// form; otherwise the call returns None and the caller converts them (as_poses, as_pairs) and
// calls again. A batch of one pair thus costs one native call, its two arrays (NumpyColumns)
// and the query: no DLPack import or export, no Python-level checks.
// The poses of a call that takes them as a plain object: None (the set's defaults) or a
// C-contiguous (M, 4, 4) float64 buffer, read in place; false for anything else (the caller
// converts it with as_poses and calls again).
bool read_poses_object(const MeshBvhSet& set, nb::handle poses, Buffer& buffer, PosedMeshes& out) {
    out.set = &set;
    if (poses.is_none()) return true;
    const size_t m = set.meshes.size();
    out.matrices = buffer.get<double>(poses.ptr(), {static_cast<Py_ssize_t>(m), 4, 4});
    return out.matrices != nullptr;
}

nb::object intersects_batch(const MeshBvhSet& set, nb::handle poses, nb::handle pairs, int threads,
                            nb::handle result_type) {
    const size_t m = set.meshes.size();
    Buffer pose_buffer;  // held until the call returns: `posed` reads the poses in place
    PosedMeshes posed;
    if (!read_poses_object(set, poses, pose_buffer, posed)) return nb::none();
    PairsArg in;
    if (!in.read(pairs.ptr())) return nb::none();
    check_pairs(in.data, in.count, m);
    const auto n = static_cast<size_t>(in.count);
    bool* intersecting = nullptr;
    std::int8_t* status = nullptr;
    NumpyColumns arrays;
    const size_t intersecting_arr = arrays.add(n, &intersecting), status_arr = arrays.add(n, &status);
    arrays.make();
    const std::int64_t* ij = in.data;  // replaced by the pinned copy before the GIL goes
    const auto run = [&](long long begin, long long end) {
        for (long long k = begin; k < end; ++k) {
            const auto i = static_cast<size_t>(ij[2 * k]);
            const auto j = static_cast<size_t>(ij[2 * k + 1]);
            meshcol::Pose pose_i, pose_j;
            const bool rigid_i = posed.pose(i, pose_i), rigid_j = posed.pose(j, pose_j);
            status[k] = static_cast<std::int8_t>(
                intersects_one(set.meshes[i], pose_i, rigid_i, set.meshes[j], pose_j, rigid_j, &intersecting[k]));
        }
    };
    const int t = meshcol::resolve_threads(threads, in.count, meshcol::defaults::mesh_min_pairs_per_thread);
    if (t <= 1 && in.count <= 1) {
        run(0, in.count);  // one pair: a disjoint one costs less than releasing the GIL
    } else {
        in.pin();
        ij = in.data;  // the loop reads the copy (`run` holds ij by reference), never numpy's
        nb::gil_scoped_release release;
        meshcol::parallel_for(in.count, t, run);
    }
    static const std::array<PyObject*, 2> names = {interned("intersecting"), interned("status")};
    static DataclassMaker<2> maker;
    return maker.make(result_type, names, {arrays[intersecting_arr], arrays[status_arr]});
}

// Mesh-pair distances as a `result_type(distance, point_a, point_b, intersecting, a_inside_b,
// b_inside_a, triangle_a, triangle_b, status)` (meshcol.collision.mesh_query.MeshDistanceBatch),
// `poses` and `pairs` taken as intersects_batch takes them (None when not in the core's form:
// the caller converts them and calls again). A one-pair batch costs the query and its nine
// arrays (NumpyColumns), where DLPack arrays gathered in a dict cost about ten microseconds.
nb::object distance_batch(const MeshBvhSet& set, nb::handle poses, nb::handle pairs, int threads,
                                 double max_distance, nb::handle result_type) {
    check_max_distance(max_distance);
    Buffer pose_buffer;  // held until the call returns: `posed` reads the poses in place
    PosedMeshes posed;
    if (!read_poses_object(set, poses, pose_buffer, posed)) return nb::none();
    PairsArg in;
    if (!in.read(pairs.ptr())) return nb::none();
    check_pairs(in.data, in.count, set.meshes.size());
    const auto n = static_cast<size_t>(in.count);
    double *distance = nullptr, *point_a = nullptr, *point_b = nullptr;
    bool *intersecting = nullptr, *a_inside_b = nullptr, *b_inside_a = nullptr;
    std::int64_t *triangle_a = nullptr, *triangle_b = nullptr;
    std::int8_t* status = nullptr;
    NumpyColumns arrays;  // made in the order of `names`
    arrays.add(n, &distance);
    arrays.add(n, &point_a, 3);
    arrays.add(n, &point_b, 3);
    arrays.add(n, &intersecting);
    arrays.add(n, &a_inside_b);
    arrays.add(n, &b_inside_a);
    arrays.add(n, &triangle_a);
    arrays.add(n, &triangle_b);
    arrays.add(n, &status);
    arrays.make();
    in.pin();  // the loop reads the copy, never numpy's array, once the GIL is released
    const std::int64_t* ij = in.data;
    {
        nb::gil_scoped_release release;
        const int t = meshcol::resolve_threads(threads, in.count, meshcol::defaults::mesh_min_pairs_per_thread);
        meshcol::parallel_for(in.count, t, [&](long long begin, long long end) {
            for (long long k = begin; k < end; ++k) {
                const auto i = static_cast<size_t>(ij[2 * k]), j = static_cast<size_t>(ij[2 * k + 1]);
                meshcol::Pose pose_i, pose_j;
                const bool rigid_i = posed.pose(i, pose_i), rigid_j = posed.pose(j, pose_j);
                const MeshDistanceOutput r =
                    distance_one(set.meshes[i], pose_i, rigid_i, set.meshes[j], pose_j, rigid_j, max_distance);
                distance[k] = r.distance;
                store_row(point_a, k, r.point_a);
                store_row(point_b, k, r.point_b);
                intersecting[k] = r.intersecting;
                a_inside_b[k] = r.a_inside_b;
                b_inside_a[k] = r.b_inside_a;
                triangle_a[k] = r.triangle_a;
                triangle_b[k] = r.triangle_b;
                status[k] = static_cast<std::int8_t>(r.status);
            }
        });
    }
    static const std::array<PyObject*, 9> names = {
        interned("distance"),   interned("point_a"),    interned("point_b"),    interned("intersecting"),
        interned("a_inside_b"), interned("b_inside_a"), interned("triangle_a"), interned("triangle_b"),
        interned("status")};
    static DataclassMaker<9> maker;
    std::array<nb::handle, 9> values;
    for (size_t k = 0; k < 9; ++k) values[k] = arrays[k];
    return maker.make(result_type, names, values);
}

// Why a single pair has no verdict, as the message of the ValueError the single-pair entry
// raises (a bool cannot carry a status).
[[noreturn]] void no_verdict(meshcol::Status status, std::int64_t i, std::int64_t j, const MeshBvhSet& set,
                             bool rigid_i, bool rigid_j) {
    const std::string pair = "meshes " + std::to_string(i) + " and " + std::to_string(j) + ": ";
    if (status == meshcol::Status::OUT_OF_RANGE)
        throw std::invalid_argument(pair + "lengths outside [2^-100, 2^100] (Status.OUT_OF_RANGE)");
    for (const auto& [k, rigid] : {std::make_pair(i, rigid_i), std::make_pair(j, rigid_j)}) {
        if (!set.meshes[static_cast<size_t>(k)].valid())
            throw std::invalid_argument("mesh " + std::to_string(k) +
                                        " is not valid (a non-finite vertex or no faces)");
        if (!rigid)
            throw std::invalid_argument("pose of mesh " + std::to_string(k) + " is not rigid or not finite");
    }
    throw std::invalid_argument(pair + "no verdict");
}

size_t mesh_index(const MeshBvhSet& set, std::int64_t i) {
    if (i < 0 || i >= static_cast<std::int64_t>(set.meshes.size()))
        throw std::invalid_argument("mesh index " + std::to_string(i) + " out of range for " +
                                    std::to_string(set.meshes.size()) + " meshes");
    return static_cast<size_t>(i);
}

// A pose read in place: a (4, 4) float64 numpy array from numpy's struct (a buffer export
// costs about a third of a disjoint pair's call), other objects through the buffer protocol.
// Null when neither reads it.
const double* pose_in_place(nb::handle pose, Buffer& buffer) {
    return float64_array(pose.ptr(), {4, 4}, buffer);
}

// A pose as a query reads it, and whether it is rigid and finite.
struct ReadPose {
    meshcol::Pose pose;
    bool rigid;
};

// A pose that is not read in place (a list, another dtype or byte order, a strided view, a
// wrong shape): converted as meshcol.collision.arrays.as_pose converts one (numpy.asarray to
// float64, ValueError naming it unless (4, 4)), made C-contiguous, then read. Out of line: the
// pair call's frame keeps none of this.
[[gnu::noinline]] ReadPose converted_pose(nb::handle pose, const char* name) {
    const nb::module_ numpy = nb::module_::import_("numpy");
    const nb::object m = numpy.attr("asarray")(pose, "dtype"_a = numpy.attr("float64"));
    const nb::object shape = m.attr("shape");
    if (!shape.equal(nb::make_tuple(4, 4)))
        throw std::invalid_argument(std::string(name) + " must be (4, 4), got " + nb::repr(shape).c_str());
    const nb::object copy = numpy.attr("ascontiguousarray")(m);
    Buffer buffer;
    const double* p = pose_in_place(copy, buffer);
    if (p == nullptr) throw std::invalid_argument(std::string(name) + " could not be read as (4, 4) float64");
    return {meshcol::Pose::from_matrix4(p), meshcol::is_rigid_matrix4(p, meshcol::defaults::rigid_tolerance)};
}

// `then(pose, rigid)` with the given pose read (in place when it can be) or, for None, the
// set's default pose of mesh k. No pose is copied (a Pose is 96 bytes, which the compiler
// copies or clears with `rep movs` / `rep stos`, whose start-up was about a tenth of the call)
// and nothing is built for None.
template <class Then>
bool with_pose(const MeshBvhSet& set, size_t k, nb::handle pose, const char* name, const Then& then) {
    if (pose.is_none()) return then(set.poses[k], set.rigid[k] != 0);
    Buffer buffer;
    if (const double* p = pose_in_place(pose, buffer); p != nullptr)
        return then(meshcol::Pose::from_matrix4(p), meshcol::is_rigid_matrix4(p, meshcol::defaults::rigid_tolerance));
    const ReadPose read = converted_pose(pose, name);
    return then(read.pose, read.rigid);
}

// One pair at the set's default poses, or at the given ones: the GIL is kept (a disjoint
// pair's root-box test costs less than releasing it) and nothing is allocated for a pose read
// in place. MeshSet.intersects is this method itself (bound per set), so it takes any pose
// form the Python method took.
bool intersects_pair(const MeshBvhSet& set, std::int64_t i, std::int64_t j, nb::handle pose_i,
                     nb::handle pose_j) {
    const size_t a = mesh_index(set, i), b = mesh_index(set, j);
    return with_pose(set, a, pose_i, "pose_i", [&](const meshcol::Pose& pa, bool ra) {
        return with_pose(set, b, pose_j, "pose_j", [&](const meshcol::Pose& pb, bool rb) {
            bool hit = false;
            const meshcol::Status status = intersects_one(set.meshes[a], pa, ra, set.meshes[b], pb, rb, &hit);
            if (status != meshcol::Status::CONVERGED) no_verdict(status, i, j, set, ra, rb);
            return hit;
        });
    });
}

void set_poses(MeshBvhSet& set, Poses poses) {
    const size_t m = set.meshes.size();
    if (poses.shape(0) != m)
        throw std::invalid_argument("poses must be (" + std::to_string(m) + ", 4, 4), got (" +
                                    std::to_string(poses.shape(0)) + ", 4, 4)");
    for (size_t i = 0; i < m; ++i) {
        const double* p = poses.data() + 16 * i;
        set.rigid[i] = meshcol::is_rigid_matrix4(p, meshcol::defaults::rigid_tolerance);
        set.poses[i] = meshcol::Pose::from_matrix4(p);
    }
}

}  // namespace

void bind_mesh_query(nb::module_& m) {
    // The type of the result intersects_batch builds (its caller's dataclass), for the stub.
    m.attr("ResultT") = nb::type_var("ResultT");
    nb::class_<MeshBvhSet>(m, "MeshBvhSet",
                           "Bounding volume hierarchies of M triangle meshes, built once (mesh_bvh.hpp).")
        .def("__init__", &build_set, "vertices"_a, "faces"_a, "vertex_offsets"_a, "face_offsets"_a,
             "threads"_a = 0,
             "Builds every mesh's hierarchy. vertices (V, 3) local frames; faces (F, 3) indices "
             "local to each mesh's vertex block; offsets (M + 1,).")
        .def("__len__", [](const MeshBvhSet& s) { return s.meshes.size(); })
        .def("valid", [](const MeshBvhSet& s, std::int64_t i) { return s.at(i).valid(); }, "i"_a,
             "Whether mesh i has finite vertices and at least one face.")
        .def("closed", [](const MeshBvhSet& s, std::int64_t i) { return s.at(i).closed(); }, "i"_a,
             "Whether mesh i is a closed, consistently wound surface (MeshBvh::closed).")
        .def("node_count", [](const MeshBvhSet& s, std::int64_t i) { return s.at(i).nodes().size(); }, "i"_a)
        .def("distinct_count", [](const MeshBvhSet& s) { return s.meshes.distinct(); },
             "Hierarchies built: one per distinct mesh (meshes of the same vertex and face bytes share one).")
        .def("validate", [](const MeshBvhSet& s) {
            for (const auto& mesh : s.meshes)
                if (!mesh.validate()) return false;
            return true;
        }, "Checks every hierarchy's invariants (for tests).")
        .def("winding_number", [](const MeshBvhSet& s, std::int64_t i, Points points) {
            const meshcol::MeshBvh& mesh = s.at(i);
            if (!mesh.valid()) throw std::invalid_argument("mesh " + std::to_string(i) + " is not valid");
            const size_t n = points.shape(0);
            double* out;
            auto arr = new_array<Out<double, -1>>({n});
            out = arr.data();
            const double* p = points.data();
            {
                nb::gil_scoped_release release;
                for (size_t k = 0; k < n; ++k)
                    out[k] = meshcol::winding_number(mesh, Vec3{p[3 * k], p[3 * k + 1], p[3 * k + 2]});
            }
            return arr;
        }, "i"_a, "points"_a, "Generalized winding numbers of points (mesh i's local frame).")
        .def("fast_winding_number", [](const MeshBvhSet& s, std::int64_t i, Points points, double max_error) {
            const meshcol::MeshBvh& mesh = s.at(i);
            if (!mesh.valid()) throw std::invalid_argument("mesh " + std::to_string(i) + " is not valid");
            if (!(max_error >= 0.0)) throw std::invalid_argument("max_error must be >= 0");
            const size_t n = points.shape(0);
            auto value = new_array<Out<double, -1>>({n});
            auto error = new_array<Out<double, -1>>({n});
            auto visits = new_array<Out<std::int64_t, -1>>({n});
            double *v = value.data(), *e = error.data();
            std::int64_t* c = visits.data();
            const double* p = points.data();
            {
                nb::gil_scoped_release release;
                for (size_t k = 0; k < n; ++k) {
                    const meshcol::WindingEstimate w =
                        meshcol::fast_winding_number(mesh, Vec3{p[3 * k], p[3 * k + 1], p[3 * k + 2]}, max_error);
                    v[k] = w.value;
                    e[k] = w.error;
                    c[k] = w.visits;
                }
            }
            return std::make_tuple(value, error, visits);
        }, "i"_a, "points"_a, "max_error"_a,
           "Fast winding numbers of points (mesh i's local frame) with their error bounds and work.")
        .def("winding_number_inside", [](const MeshBvhSet& s, std::int64_t i, Points points) {
            const meshcol::MeshBvh& mesh = s.at(i);
            if (!mesh.valid()) throw std::invalid_argument("mesh " + std::to_string(i) + " is not valid");
            const size_t n = points.shape(0);
            auto inside = new_array<Out<bool, -1>>({n});
            auto work = new_array<Out<std::int64_t, -1>>({n});
            bool* out = inside.data();
            std::int64_t* w = work.data();
            const double* p = points.data();
            {
                nb::gil_scoped_release release;
                for (size_t k = 0; k < n; ++k) {
                    long long visits = 0;
                    out[k] = meshcol::winding_number_inside(mesh, Vec3{p[3 * k], p[3 * k + 1], p[3 * k + 2]}, &visits);
                    w[k] = visits;
                }
            }
            return std::make_tuple(inside, work);
        }, "i"_a, "points"_a,
           "Whether |winding number| >= winding_number_inside for points (mesh i's local frame), "
           "by the refined fast winding number, with the nodes and triangles visited.")
        .def("closest_points", [](const MeshBvhSet& s, std::int64_t i, Points points, int threads) {
            const meshcol::MeshBvh& mesh = s.at(i);
            const size_t n = points.shape(0);
            auto distance = new_array<Out<double, -1>>({n});
            auto closest = new_array<Out<double, -1, 3>>({n, 3});
            auto triangle = new_array<Out<std::int64_t, -1>>({n});
            const double* p = points.data();
            double* d = distance.data();
            double* c = closest.data();
            std::int64_t* t = triangle.data();
            {
                nb::gil_scoped_release release;
                const auto count = static_cast<long long>(n);
                const int used = meshcol::resolve_threads(threads, count,
                                                          meshcol::defaults::min_points_per_thread);
                meshcol::parallel_for(count, used, [&](long long begin, long long end) {
                    for (long long k = begin; k < end; ++k) {
                        const Vec3 q{p[3 * k], p[3 * k + 1], p[3 * k + 2]};
                        const meshcol::PointDistanceOutput r = meshcol::closest_point(mesh, q);
                        d[k] = r.distance;
                        for (int j = 0; j < 3; ++j) c[3 * k + j] = r.point[j];
                        t[k] = r.triangle;
                    }
                });
            }
            return std::make_tuple(distance, closest, triangle);
        }, "i"_a, "points"_a, "threads"_a = 0,
           "Exact distances (N,), closest surface points (N, 3) and faces (N,) of points (N, 3) "
           "to mesh i (its local frame); NaN and -1 for a non-finite point or an invalid mesh.")
        .def("largest_distance_batch", &largest_distance_batch, "meshes"_a, "points"_a, "point_offsets"_a,
             "threads"_a = 0,
             "Item k: the largest distance from points[point_offsets[k]:point_offsets[k + 1]] (mesh "
             "meshes[k]'s local frame) to that mesh's surface, the maximum of closest_points' "
             "distances bit for bit, by a search pruned at the largest found: {distance, point "
             "(index in the item's block), status}; items on threads.")
        .def("largest_distance_to_patches_batch", &largest_distance_to_patches_batch, "meshes"_a, "patch_map"_a,
             "patch_nodes"_a, "patch_numbers"_a, "patch_offsets"_a, "threads"_a = 0,
             "Item k: the largest distance from the grid nodes of patches "
             "[patch_offsets[k], patch_offsets[k + 1]) (SurfacePatch: map (P,) int8, nodes (P, 2) "
             "n_u, n_v, numbers (P, 13) g[9], v0, v1, lu, lv) to mesh meshes[k], the maximum over "
             "every node by a search that skips the blocks that cannot raise it: {distance, point "
             "(the node, counted patch after patch), status}; items on threads.")
        .def("set_poses", &set_poses, "poses"_a,
             "Sets the default poses (M, 4, 4) that queries with poses=None use (read and "
             "checked for rigidity once).")
        .def("intersects_pair", &intersects_pair, "i"_a, "j"_a, "pose_i"_a = nb::none(),
             "pose_j"_a = nb::none(),
             "Whether meshes i and j intersect, at the default poses or the given (4, 4) ones "
             "(read in place when C-contiguous float64, else converted); ValueError when a pose "
             "is not (4, 4) or the pair has no verdict (invalid mesh or pose, out of range).")
        .def("distance_batch", &distance_batch, "poses"_a.none(), "pairs"_a, "threads"_a,
             "max_distance"_a, "result_type"_a,
             nb::sig("def distance_batch(self, poses: object | None, pairs: object, threads: int, "
                     "max_distance: float, result_type: type[ResultT]) -> ResultT | None"),
             "Mesh-pair distances as result_type(distance, point_a, point_b, intersecting, a_inside_b, "
             "b_inside_a, triangle_a, triangle_b, status); None when poses or pairs are not in the form "
             "intersects_batch reads in place (convert them and call again).")
        .def("depth_batch", &depth_batch, "poses"_a.none(), "pairs"_a, "threads"_a = 0,
             "Mesh-pair penetration depths (lower bounds of the minimum translation distance): "
             "{depth, point_a, point_b, normal, deepest_mesh, points_tested, status}.")
        .def("contacts_batch", &contacts_batch, "poses"_a.none(), "pairs"_a, "threads"_a = 0,
             "max_contacts"_a = 0, "max_work"_a = meshcol::defaults::mesh_contacts_max_work,
             "Mesh-pair contacts (every crossing triangle pair, its own penetration): {count, "
             "depth, normal, point, face_depth, triangle_a, triangle_b, status} of the deepest, "
             "and up to max_contacts listed contacts a pair: {contact_offsets, contact_depth, "
             "contact_normal, contact_point, contact_face_depth, contact_triangle_a, "
             "contact_triangle_b}.")
        .def("ray_cast_batch", &ray_cast_batch, "meshes"_a, "origins"_a, "directions"_a, "poses"_a.none(),
             "max_distance"_a = std::numeric_limits<double>::infinity(), "threads"_a = 0,
             "First hits of rays (world frame) on meshes[k]: {hit, distance, point, normal, "
             "triangle, status}.")
        .def("intersects_batch", &intersects_batch, "poses"_a.none(), "pairs"_a, "threads"_a,
             "result_type"_a,
             nb::sig("def intersects_batch(self, poses: object | None, pairs: object, threads: int, "
                     "result_type: type[ResultT]) -> ResultT | None"),
             "Mesh-pair surface intersection tests as result_type(intersecting, status); None "
             "when poses is not None or a C-contiguous (M, 4, 4) float64 array, or pairs not a "
             "C-contiguous (P, 2) int64 array or a non-empty list of (i, j) Python ints "
             "(convert them and call again).");

    m.def("patch_points", [](Kinds patch_map, Pairs patch_nodes, PatchNumbers patch_numbers) {
        const std::vector<meshcol::SurfacePatch> patches = read_patches(patch_map, patch_nodes, patch_numbers);
        size_t total = 0;
        for (const auto& p : patches) total += static_cast<size_t>(p.n_u * p.n_v);
        auto arr = new_array<Out<double, -1, 3>>({total, 3});
        double* out = arr.data();
        {
            nb::gil_scoped_release release;
            for (const auto& p : patches)
                for (std::int64_t i = 0; i < p.n_u; ++i)
                    for (std::int64_t j = 0; j < p.n_v; ++j) {
                        const Vec3 q = meshcol::patch_point(p, i, j);
                        for (int c = 0; c < 3; ++c) *out++ = q[c];
                    }
        }
        return arr;
    }, "patch_map"_a, "patch_nodes"_a, "patch_numbers"_a,
       "The grid nodes (P, 3) of surface patches (as largest_distance_to_patches_batch takes them), "
       "patch after patch, row by row (i, then j).");

    m.def("triangle_distance_batch", [](Triangles a, Triangles b) {
        if (a.shape(0) != b.shape(0))
            throw std::invalid_argument("a and b must have the same number of triangles, got " +
                                        std::to_string(a.shape(0)) + " and " + std::to_string(b.shape(0)));
        const size_t n = a.shape(0);
        double *distance, *point_a, *point_b;
        bool* intersecting;
        auto d_arr = new_array<Out<double, -1>>({n});
        distance = d_arr.data();
        auto pa_arr = new_array<Out<double, -1, 3>>({n, 3});
        point_a = pa_arr.data();
        auto pb_arr = new_array<Out<double, -1, 3>>({n, 3});
        point_b = pb_arr.data();
        auto i_arr = new_array<Out<bool, -1>>({n});
        intersecting = i_arr.data();
        const double* pa = a.data();
        const double* pb = b.data();
        {
            nb::gil_scoped_release release;
            for (size_t k = 0; k < n; ++k) {
                Vec3 ta[3], tb[3];
                for (int c = 0; c < 3; ++c) {
                    ta[c] = Vec3{pa[9 * k + 3 * c], pa[9 * k + 3 * c + 1], pa[9 * k + 3 * c + 2]};
                    tb[c] = Vec3{pb[9 * k + 3 * c], pb[9 * k + 3 * c + 1], pb[9 * k + 3 * c + 2]};
                }
                const meshcol::TriangleDistanceOutput r = meshcol::triangle_distance(ta, tb);
                distance[k] = r.distance;
                intersecting[k] = r.intersecting;
                for (int c = 0; c < 3; ++c) {
                    point_a[3 * k + c] = r.point_a[c];
                    point_b[3 * k + c] = r.point_b[c];
                }
            }
        }
        return std::make_tuple(d_arr, pa_arr, pb_arr, i_arr);
    }, "a"_a, "b"_a,
       "Exact distances of triangle pairs a[k], b[k] (n, 3, 3): (distance, point_a, point_b, intersecting).");
}
