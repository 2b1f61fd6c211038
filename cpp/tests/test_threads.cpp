// Every path that parallel_for (batch.hpp) serves, run on two and three threads: the answers
// equal the one-thread answers bit for bit. Each input is sized past the path's own
// threshold (`resolve_threads` with its default), checked first, so the threads really run:
// `make test-tsan` runs these under ThreadSanitizer, where a data race between them is a
// report even when the answers come out equal.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "check.hpp"
#include "fixtures.hpp"
#include "meshcol/batch.hpp"
#include "meshcol/broadphase.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/fit.hpp"
#include "meshcol/hull.hpp"
#include "meshcol/mesh_bvh.hpp"
#include "meshcol/mesh_query.hpp"
#include "meshcol/mesh_read.hpp"
#include "meshcol/narrowphase.hpp"
#include "meshcol/point_sets.hpp"
#include "meshcol/toi.hpp"
#include "meshcol/triangle.hpp"

using namespace meshcol;

namespace {

constexpr double kPi = 3.14159265358979323846;

using fixtures::same_bytes;

bool same_bytes(const Vec3& a, const Vec3& b) {
    return same_bytes(&a.x, &b.x, 1) && same_bytes(&a.y, &b.y, 1) && same_bytes(&a.z, &b.z, 1);
}

// A rigid (4, 4) row-major pose: a random rotation (a normalised quaternion) at `t`.
void random_pose(std::mt19937_64& random, const Vec3& t, double* m) {
    std::normal_distribution<double> normal;
    double q[4];
    double length = 0.0;
    for (double& c : q) {
        c = normal(random);
        length += c * c;
    }
    length = std::sqrt(length);
    const double w = q[0] / length, x = q[1] / length, y = q[2] / length, z = q[3] / length;
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                         2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m[4 * i + j] = r[3 * i + j];
    }
    m[3] = t.x;
    m[7] = t.y;
    m[11] = t.z;
    m[12] = m[13] = m[14] = 0.0;
    m[15] = 1.0;
}

// `count` point sets of 8 to 31 points in balls of radius 0.5 to 1, the last one with a NaN
// (a shape no pair may query: INVALID_INPUT).
struct PointSets {
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets{0};

    PointSets(int count, unsigned seed) {
        std::mt19937_64 random(seed);
        std::uniform_real_distribution<double> unit(-1.0, 1.0), radius(0.5, 1.0);
        for (int h = 0; h < count; ++h) {
            const int n = 8 + h % 24;
            const double r = radius(random);
            for (int i = 0; i < n; ++i) {
                const Vec3 p{unit(random), unit(random), unit(random)};
                points.push_back(h % 3 == 0 ? r * p : (r / std::max(norm(p), 1e-3)) * p);
            }
            offsets.push_back(static_cast<std::int64_t>(points.size()));
        }
        points.back().y = std::nan("");
    }
    long long size() const { return static_cast<long long>(offsets.size()) - 1; }
};

// `count` random pairs of distinct shapes of `shapes`.
std::vector<std::int64_t> random_pairs(long long count, long long shapes, std::mt19937_64& random) {
    std::uniform_int_distribution<long long> pick(0, shapes - 1);
    std::vector<std::int64_t> pairs;
    while (static_cast<long long>(pairs.size()) < 2 * count) {
        const long long a = pick(random), b = pick(random);
        if (a != b) pairs.insert(pairs.end(), {a, b});
    }
    return pairs;
}

// The columns of a convex batch, compared byte for byte.
struct ConvexColumns {
    std::vector<double> distance, depth, normal, point_a, point_b;
    std::vector<std::int32_t> iterations;
    std::vector<std::int8_t> status;
    std::vector<char> intersects;

    explicit ConvexColumns(size_t n)
        : distance(n), depth(n), normal(3 * n), point_a(3 * n), point_b(3 * n), iterations(n),
          status(n), intersects(n) {}
    BatchOutput output() {
        BatchOutput out;
        out.distance = distance.data();
        out.depth = depth.data();
        out.normal = normal.data();
        out.point_a = point_a.data();
        out.point_b = point_b.data();
        out.iterations = iterations.data();
        out.status = status.data();
        out.intersects = reinterpret_cast<bool*>(intersects.data());
        return out;
    }
    bool operator==(const ConvexColumns& o) const {
        return same_bytes(distance, o.distance) && same_bytes(depth, o.depth) &&
               same_bytes(normal, o.normal) && same_bytes(point_a, o.point_a) &&
               same_bytes(point_b, o.point_b) && same_bytes(iterations, o.iterations) &&
               same_bytes(status, o.status) && same_bytes(intersects, o.intersects);
    }
};

// A closed, outward-wound UV sphere of radius r: `stacks` bands of `slices` quads, a vertex
// at each pole.
fixtures::TriangleMesh uv_sphere(double r, int stacks, int slices) {
    fixtures::TriangleMesh m;
    m.vertices = {0.0, 0.0, r};
    for (int i = 1; i < stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            const double theta = kPi * i / stacks, phi = 2.0 * kPi * j / slices;
            m.vertices.insert(m.vertices.end(), {r * std::sin(theta) * std::cos(phi),
                                                 r * std::sin(theta) * std::sin(phi), r * std::cos(theta)});
        }
    m.vertices.insert(m.vertices.end(), {0.0, 0.0, -r});
    const auto ring = [&](int i, int j) -> std::int64_t { return 1 + (i - 1) * slices + j % slices; };
    const std::int64_t south = 1 + static_cast<std::int64_t>(stacks - 1) * slices;
    for (int j = 0; j < slices; ++j) {
        m.faces.insert(m.faces.end(), {0, ring(1, j), ring(1, j + 1)});
        for (int i = 1; i + 1 < stacks; ++i)
            m.faces.insert(m.faces.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j),
                                           ring(i + 1, j + 1), ring(i, j + 1)});
        m.faces.insert(m.faces.end(), {ring(stacks - 1, j), south, ring(stacks - 1, j + 1)});
    }
    return m;
}

bool same_fit(const PrimitiveFit& a, const PrimitiveFit& b) {
    return a.status == b.status && same_bytes(a.params, b.params, 3) &&
           same_bytes(&a.rotation.m[0][0], &b.rotation.m[0][0], 9) && same_bytes(a.center, b.center) &&
           same_bytes(&a.volume, &b.volume, 1) && same_bytes(&a.excess, &b.excess, 1);
}

}  // namespace

TEST_CASE("threads: hull packing commits chunks that finish out of order, byte for byte") {
    // Chunk 0 holds the only big shapes (smooth, every point a vertex): the other threads pack
    // and park every later chunk while one still packs it, then one commits them all in order.
    std::vector<Vec3> points;
    std::vector<std::int64_t> offsets = {0};
    std::mt19937_64 random(3);
    std::normal_distribution<double> normal;
    for (int h = 0; h < 64; ++h) {
        const int n = h < 2 ? 1500 : 6 + h % 9;
        for (int i = 0; i < n; ++i) {
            const Vec3 p{normal(random), normal(random), normal(random)};
            points.push_back(p / norm(p));
        }
        offsets.push_back(static_cast<std::int64_t>(points.size()));
    }
    REQUIRE(resolve_threads(3, 64, defaults::hull_min_shapes_per_thread) == 3);
    const PackedPolytopes one = pack_polytopes(points.data(), offsets.data(), 64, 1);
    for (int threads : {2, 3}) {
        const PackedPolytopes many = pack_polytopes(points.data(), offsets.data(), 64, threads);
        CHECK(fixtures::same_packing(one, many));
    }
    CHECK(one.status[0] == HullStatus::OK);
    CHECK(one.offsets[1] > 1000);  // most points of a sphere are vertices
}

TEST_CASE("threads: convex batches, their caches filled on threads, equal one thread") {
    // Polytopes with SAT features, posed close together (most pairs overlap): every query
    // kind, each on a fresh set (its edge classes and radii then filled by racing threads)
    // and again on a set whose caches are full.
    const PointSets sets(800, 11);
    const long long h = sets.size();
    const PackedPolytopes packed = pack_polytopes(sets.points.data(), sets.offsets.data(), h, 1);
    std::mt19937_64 random(12);
    std::uniform_real_distribution<double> place(0.0, 6.0);
    std::vector<double> poses(16 * static_cast<size_t>(h));
    for (long long k = 0; k < h; ++k)
        random_pose(random, {place(random), place(random), place(random)}, poses.data() + 16 * k);
    const std::vector<std::int64_t> pairs = random_pairs(600, h, random);
    const long long p = static_cast<long long>(pairs.size() / 2);
    REQUIRE(resolve_threads(3, h, defaults::min_shapes_per_thread) == 3);
    REQUIRE(resolve_threads(3, p, defaults::min_pairs_per_thread) == 3);
    for (const QueryKind kind : {QueryKind::DISTANCE, QueryKind::PENETRATION, QueryKind::INTERSECTS}) {
        ConvexColumns one(static_cast<size_t>(p));
        {
            const fixtures::PolytopeSet set(packed);
            run_batch(set.view, poses.data(), pairs.data(), p, kind, 1, one.output());
        }
        for (int threads : {2, 3}) {
            const fixtures::PolytopeSet set(packed);
            ShapeRadii radii(h);
            for (int round = 0; round < 2; ++round) {  // caches empty, then full
                ConvexColumns many(static_cast<size_t>(p));
                run_batch(set.view, poses.data(), pairs.data(), p, kind, threads, many.output(), &radii);
                CHECK(many == one);
            }
        }
    }
    // The per-shape passes: world boxes, radii, every shape's edge classes.
    const fixtures::PolytopeSet alone(packed);
    std::vector<double> lo(3 * static_cast<size_t>(h)), hi(lo.size()), radius(static_cast<size_t>(h));
    world_aabbs(alone.view, poses.data(), lo.data(), hi.data(), 1);
    bounding_radii(alone.view, radius.data(), 1);
    std::vector<std::int64_t> class_offsets;
    std::vector<double> directions;
    all_edge_classes(alone.view, 1, class_offsets, directions);
    for (int threads : {2, 3}) {
        const fixtures::PolytopeSet set(packed);
        std::vector<double> lo2(lo.size()), hi2(lo.size()), radius2(radius.size());
        world_aabbs(set.view, poses.data(), lo2.data(), hi2.data(), threads);
        bounding_radii(set.view, radius2.data(), threads);
        std::vector<std::int64_t> class_offsets2;
        std::vector<double> directions2;
        all_edge_classes(set.view, threads, class_offsets2, directions2);
        CHECK(same_bytes(lo, lo2));
        CHECK(same_bytes(hi, hi2));
        CHECK(same_bytes(radius, radius2));
        CHECK(same_bytes(class_offsets, class_offsets2));
        CHECK(same_bytes(directions, directions2));
    }
}

TEST_CASE("threads: a time-of-impact batch equals one thread") {
    const PointSets sets(96, 21);
    const long long h = sets.size();
    const PackedPolytopes packed = pack_polytopes(sets.points.data(), sets.offsets.data(), h, 1);
    const fixtures::PolytopeSet set(packed);
    std::mt19937_64 random(22);
    std::uniform_real_distribution<double> place(0.0, 8.0);
    std::vector<double> start(16 * static_cast<size_t>(h)), end(start.size());
    for (long long k = 0; k < h; ++k) {
        random_pose(random, {place(random), place(random), place(random)}, start.data() + 16 * k);
        random_pose(random, {place(random), place(random), place(random)}, end.data() + 16 * k);
    }
    const std::vector<std::int64_t> pairs = random_pairs(160, h, random);
    const long long p = static_cast<long long>(pairs.size() / 2);
    REQUIRE(resolve_threads(3, p, defaults::toi_min_pairs_per_thread) == 3);
    struct Columns {
        std::vector<double> toi, point, normal;
        std::vector<std::int32_t> iterations;
        std::vector<std::int8_t> status;
    };
    const auto run = [&](int threads) {
        Columns c{std::vector<double>(static_cast<size_t>(p)), std::vector<double>(3 * static_cast<size_t>(p)),
                  std::vector<double>(3 * static_cast<size_t>(p)), std::vector<std::int32_t>(static_cast<size_t>(p)),
                  std::vector<std::int8_t>(static_cast<size_t>(p))};
        ToiBatchOutput out;
        out.toi = c.toi.data();
        out.point = c.point.data();
        out.normal = c.normal.data();
        out.iterations = c.iterations.data();
        out.status = c.status.data();
        run_toi_batch(set.view, start.data(), end.data(), nullptr, nullptr, pairs.data(), p, ToiOptions{},
                      threads, out);
        return c;
    };
    const Columns one = run(1);
    int hits = 0;
    for (const std::int8_t s : one.status) hits += s == static_cast<std::int8_t>(TimeOfImpactStatus::HIT);
    CHECK(hits > 0);
    for (int threads : {2, 3}) {
        const Columns many = run(threads);
        CHECK(same_bytes(one.toi, many.toi));
        CHECK(same_bytes(one.point, many.point));
        CHECK(same_bytes(one.normal, many.normal));
        CHECK(same_bytes(one.iterations, many.iterations));
        CHECK(same_bytes(one.status, many.status));
    }
}

TEST_CASE("threads: mesh hierarchies built and queried on threads, as the batches do") {
    // The loops of the mesh batches (cpp/bindings/bind_mesh_query.cpp: the hierarchies built
    // on threads, then distance, depth, intersection, contacts, closest points and rays per
    // pair or item on threads over the shared hierarchies), against the same queries on one
    // thread.
    const std::vector<fixtures::TriangleMesh> meshes = {
        uv_sphere(1.0, 8, 12), fixtures::box_mesh({-1, -1, -1}, {1, 1, 1}), uv_sphere(0.4, 6, 9),
        fixtures::box_mesh({-2, -0.1, -1}, {2, 0.1, 1}), uv_sphere(1.5, 10, 16)};
    const long long m = static_cast<long long>(meshes.size());
    const auto build = [&](int threads) {
        std::vector<MeshBvh> built(meshes.size());
        parallel_for(m, threads, [&](long long begin, long long end) {
            for (long long i = begin; i < end; ++i) built[static_cast<size_t>(i)] = meshes[static_cast<size_t>(i)].bvh();
        });
        return built;
    };
    std::mt19937_64 random(31);
    std::uniform_real_distribution<double> place(0.0, 2.5);
    std::uniform_int_distribution<size_t> pick(0, meshes.size() - 1);
    constexpr long long kPairs = 48;
    std::vector<size_t> a(kPairs), b(kPairs);
    std::vector<Pose> pose_a(kPairs), pose_b(kPairs);
    for (long long k = 0; k < kPairs; ++k) {
        double matrix[16];
        a[k] = pick(random);
        b[k] = pick(random);
        random_pose(random, {place(random), place(random), place(random)}, matrix);
        pose_a[k] = Pose::from_matrix4(matrix);
        random_pose(random, {place(random), place(random), place(random)}, matrix);
        pose_b[k] = Pose::from_matrix4(matrix);
    }
    REQUIRE(resolve_threads(3, kPairs, defaults::mesh_min_pairs_per_thread) == 3);
    struct Answers {
        std::vector<MeshDistanceOutput> distance;
        std::vector<MeshDepthOutput> depth;
        std::vector<char> intersects;
        std::vector<PointDistanceOutput> closest;
        std::vector<MeshRayOutput> ray;
        std::vector<MeshContactsOutput> contacts;
        std::vector<std::vector<MeshContact>> listed;
    };
    const auto run = [&](int threads) {
        const std::vector<MeshBvh> built = build(threads);
        Answers r{std::vector<MeshDistanceOutput>(kPairs), std::vector<MeshDepthOutput>(kPairs),
                  std::vector<char>(kPairs), std::vector<PointDistanceOutput>(kPairs),
                  std::vector<MeshRayOutput>(kPairs), std::vector<MeshContactsOutput>(kPairs),
                  std::vector<std::vector<MeshContact>>(kPairs)};
        parallel_for(kPairs, threads, [&](long long begin, long long end) {
            for (long long k = begin; k < end; ++k) {
                MeshDistanceInput q;
                q.a = &built[a[k]];
                q.b = &built[b[k]];
                q.pose_a = pose_a[k];
                q.pose_b = pose_b[k];
                r.distance[k] = mesh_distance(q);
                r.depth[k] = mesh_penetration_depth(q);
                r.intersects[k] = mesh_intersects(*q.a, q.pose_a, *q.b, q.pose_b);
                r.closest[k] = closest_point(*q.a, pose_b[k].translation);
                MeshRayInput ray;
                ray.mesh = q.b;
                ray.pose = q.pose_b;
                ray.origin = pose_a[k].translation;
                ray.direction = pose_b[k].translation - pose_a[k].translation + Vec3{0.01, 0.02, 0.03};
                r.ray[k] = mesh_ray_cast(ray);
                MeshContactsInput contacts;
                contacts.a = q.a;
                contacts.b = q.b;
                contacts.pose_a = q.pose_a;
                contacts.pose_b = q.pose_b;
                contacts.max_contacts = 1000;
                r.contacts[k] = mesh_contacts(contacts, &r.listed[k]);
            }
        });
        return r;
    };
    const Answers one = run(1);
    int intersecting = 0;
    for (const char c : one.intersects) intersecting += c;
    CHECK(intersecting > 0);
    CHECK(intersecting < kPairs);
    size_t listed = 0;
    for (const auto& list : one.listed) listed += list.size();
    CHECK(listed > static_cast<size_t>(intersecting));  // pairs cross in more than one place
    for (int threads : {2, 3}) {
        const Answers many = run(threads);
        for (long long k = 0; k < kPairs; ++k) {
            const MeshDistanceOutput &d1 = one.distance[k], &d2 = many.distance[k];
            CHECK(same_bytes(&d1.distance, &d2.distance, 1) && same_bytes(d1.point_a, d2.point_a) &&
                  same_bytes(d1.point_b, d2.point_b) && d1.intersecting == d2.intersecting &&
                  d1.a_inside_b == d2.a_inside_b && d1.b_inside_a == d2.b_inside_a &&
                  d1.triangle_a == d2.triangle_a && d1.triangle_b == d2.triangle_b && d1.status == d2.status);
            const MeshDepthOutput &e1 = one.depth[k], &e2 = many.depth[k];
            CHECK(same_bytes(&e1.depth, &e2.depth, 1) && same_bytes(e1.point_a, e2.point_a) &&
                  same_bytes(e1.point_b, e2.point_b) && same_bytes(e1.normal, e2.normal) &&
                  e1.deepest_mesh == e2.deepest_mesh && e1.points_tested == e2.points_tested &&
                  e1.status == e2.status);
            CHECK(one.intersects[k] == many.intersects[k]);
            const PointDistanceOutput &c1 = one.closest[k], &c2 = many.closest[k];
            CHECK(same_bytes(&c1.distance, &c2.distance, 1) && same_bytes(c1.point, c2.point) &&
                  c1.triangle == c2.triangle);
            const MeshRayOutput &r1 = one.ray[k], &r2 = many.ray[k];
            CHECK(r1.hit == r2.hit && same_bytes(&r1.distance, &r2.distance, 1) &&
                  same_bytes(r1.point, r2.point) && same_bytes(r1.normal, r2.normal) &&
                  r1.triangle == r2.triangle && r1.status == r2.status);
            const MeshContactsOutput &m1 = one.contacts[k], &m2 = many.contacts[k];
            CHECK(m1.count == m2.count && same_bytes(&m1.depth, &m2.depth, 1) &&
                  same_bytes(m1.normal, m2.normal) && same_bytes(m1.point, m2.point) &&
                  same_bytes(&m1.face_depth, &m2.face_depth, 1) && m1.triangle_a == m2.triangle_a &&
                  m1.triangle_b == m2.triangle_b && m1.status == m2.status);
            REQUIRE(one.listed[k].size() == many.listed[k].size());
            for (size_t i = 0; i < one.listed[k].size(); ++i) {
                const MeshContact &l1 = one.listed[k][i], &l2 = many.listed[k][i];
                CHECK(same_bytes(&l1.depth, &l2.depth, 1) && same_bytes(l1.normal, l2.normal) &&
                      same_bytes(l1.point, l2.point) && same_bytes(&l1.face_depth, &l2.face_depth, 1) &&
                      l1.triangle_a == l2.triangle_a && l1.triangle_b == l2.triangle_b);
            }
        }
    }
}

TEST_CASE("threads: broad phase sweeps and trees past their thresholds equal one thread") {
    // 40,000 boxes: two threads' worth at broadphase_min_boxes_per_thread.
    constexpr std::int64_t n = 40000;
    REQUIRE(resolve_threads(2, n, defaults::broadphase_min_boxes_per_thread) == 2);
    std::mt19937_64 random(41);
    std::uniform_real_distribution<double> position(0.0, 60.0), size(0.0, 1.0);
    std::vector<double> lo(3 * n), hi(3 * n), moved_lo(3 * n), moved_hi(3 * n);
    for (std::int64_t i = 0; i < 3 * n; ++i) {
        lo[i] = position(random);
        hi[i] = lo[i] + size(random);
        const double shift = 0.05 * (size(random) - 0.5);
        moved_lo[i] = lo[i] + shift;
        moved_hi[i] = hi[i] + shift;
    }
    const std::vector<std::int64_t> pairs = sort_and_sweep(lo.data(), hi.data(), n, -1, 1);
    SortAndSweep steps(lo.data(), hi.data(), n, -1, 1);
    const std::vector<std::int64_t> moved = steps.update(moved_lo.data(), moved_hi.data(), n);
    AabbTree tree(0.1);
    tree.build(lo.data(), hi.data(), n, 1);
    const std::vector<std::uint64_t> keys = tree.query_pairs(1);
    CHECK(!pairs.empty());
    CHECK(keys.size() == pairs.size() / 2);
    CHECK(sort_and_sweep(lo.data(), hi.data(), n, -1, 2) == pairs);
    SortAndSweep threaded(lo.data(), hi.data(), n, -1, 2);
    CHECK(threaded.update(moved_lo.data(), moved_hi.data(), n) == moved);
    AabbTree tree2(0.1);
    tree2.build(lo.data(), hi.data(), n, 2);
    tree2.validate();
    CHECK(tree2.query_pairs(2) == keys);
}

TEST_CASE("threads: fits, fingerprints, crossing faces and packed files equal one thread") {
    // Fits: a set a thread (fit_min_sets_per_thread is 1).
    const PointSets sets(6, 51);
    const FitShape shapes[4] = {FitShape::SPHERE, FitShape::CAPSULE, FitShape::BOX, FitShape::CYLINDER};
    const std::vector<FitSet> fits = fit_point_sets(sets.points.data(), sets.offsets.data(), 5, shapes, 4, 1);
    for (int threads : {2, 3}) {
        const std::vector<FitSet> many = fit_point_sets(sets.points.data(), sets.offsets.data(), 5, shapes, 4, threads);
        REQUIRE(many.size() == fits.size());
        for (size_t s = 0; s < fits.size(); ++s) {
            CHECK(many[s].hull.vertices == fits[s].hull.vertices);
            REQUIRE(many[s].fits.size() == fits[s].fits.size());
            for (size_t f = 0; f < fits[s].fits.size(); ++f) CHECK(same_fit(many[s].fits[f], fits[s].fits[f]));
        }
    }
    // Fingerprints: 1,024 sets a thread.
    const PointSets many_sets(2100, 52);
    const long long count = many_sets.size();
    REQUIRE(resolve_threads(2, count, 1024) == 2);
    std::vector<std::uint64_t> prints(static_cast<size_t>(count)), prints2(prints.size());
    point_set_fingerprints(&many_sets.points[0].x, many_sets.offsets.data(), count, 1, prints.data());
    point_set_fingerprints(&many_sets.points[0].x, many_sets.offsets.data(), count, 2, prints2.data());
    CHECK(same_bytes(prints, prints2));
    // Crossing faces of one mesh: two spheres' faces, one mesh, crossing where they meet.
    fixtures::TriangleMesh mesh = uv_sphere(1.0, 12, 16);
    const fixtures::TriangleMesh second = uv_sphere(0.8, 12, 16);
    const std::int64_t first_vertices = static_cast<std::int64_t>(mesh.vertices.size() / 3);
    for (size_t k = 0; k < second.vertices.size(); ++k) mesh.vertices.push_back(second.vertices[k] + (k % 3 == 0 ? 1.0 : 0.0));
    for (const std::int64_t v : second.faces) mesh.faces.push_back(v + first_vertices);
    const long long faces = static_cast<long long>(mesh.faces.size() / 3);
    std::mt19937_64 random(53);
    const std::vector<std::int64_t> face_pairs = random_pairs(2 * defaults::triangle_min_pairs_per_thread + 500, faces, random);
    const long long p = static_cast<long long>(face_pairs.size() / 2);
    REQUIRE(resolve_threads(2, p, defaults::triangle_min_pairs_per_thread) == 2);
    std::vector<std::uint8_t> crossing(static_cast<size_t>(p)), crossing2(crossing.size());
    face_pairs_cross(mesh.vertices.data(), mesh.faces.data(), face_pairs.data(), p, crossing.data(), 1);
    face_pairs_cross(mesh.vertices.data(), mesh.faces.data(), face_pairs.data(), p, crossing2.data(), 2);
    CHECK(crossing == crossing2);
    int crossed = 0;
    for (const std::uint8_t c : crossing) crossed += c;
    CHECK(crossed > 0);
    // Packed files: 256 files a thread; the files' objects given, not read.
    std::vector<MeshFile> files(600);
    for (size_t i = 0; i < files.size(); ++i) {
        MeshObject o;
        o.name = "object " + std::to_string(i);
        for (int v = 0; v < 3 + static_cast<int>(i % 5); ++v)
            o.vertices.insert(o.vertices.end(), {0.5 * v, 1.0 * i, -0.25 * v});
        o.faces = {0, 1, 2};
        files[i].objects.push_back(o);
        if (i % 7 == 0) files[i].objects.push_back(o);
    }
    REQUIRE(resolve_threads(2, static_cast<long long>(files.size()), 256) == 2);
    const std::vector<PackedStart> starts = packed_starts(files);
    const PackedStart total = starts.back();
    struct Packed {
        std::vector<double> vertices, largest;
        std::vector<std::int32_t> faces;
        std::vector<std::int64_t> v_off, f_off, owner;
    };
    const auto pack = [&](int threads) {
        std::vector<MeshFile> copy = files;
        Packed r{std::vector<double>(3 * static_cast<size_t>(total.vertex)),
                 std::vector<double>(static_cast<size_t>(total.object)),
                 std::vector<std::int32_t>(3 * static_cast<size_t>(total.face)),
                 std::vector<std::int64_t>(static_cast<size_t>(total.object) + 1),
                 std::vector<std::int64_t>(static_cast<size_t>(total.object) + 1),
                 std::vector<std::int64_t>(static_cast<size_t>(total.object))};
        pack_mesh_files(copy, starts, threads, r.vertices.data(), r.faces.data(), r.v_off.data(), r.f_off.data(),
                        r.owner.data(), r.largest.data());
        return r;
    };
    const Packed packed = pack(1), packed2 = pack(2);
    CHECK(same_bytes(packed.vertices, packed2.vertices));
    CHECK(same_bytes(packed.largest, packed2.largest));
    CHECK(same_bytes(packed.faces, packed2.faces));
    CHECK(same_bytes(packed.v_off, packed2.v_off));
    CHECK(same_bytes(packed.f_off, packed2.f_off));
    CHECK(same_bytes(packed.owner, packed2.owner));
    // File identities: 256 paths a thread (the same few, found and not).
    std::vector<std::string> paths;
    for (int i = 0; i < 600; ++i) paths.push_back(i % 3 == 0 ? "/" : i % 3 == 1 ? "/tmp" : "/no/such/path");
    std::vector<std::uint64_t> device(paths.size()), inode(paths.size()), device2(paths.size()), inode2(paths.size());
    std::vector<std::uint8_t> found(paths.size()), found2(paths.size());
    file_identities(paths, 1, device.data(), inode.data(), found.data());
    file_identities(paths, 2, device2.data(), inode2.data(), found2.data());
    CHECK(device == device2);
    CHECK(inode == inode2);
    CHECK(found == found2);
    CHECK(found[0] == 1);
    CHECK(found[2] == 0);
}
