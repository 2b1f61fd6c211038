// Callgrind and CPU-time A/B driver of the mesh queries over bench_mesh_query.py's family,
// as written by dump_family.py (benchmarks/RESULTS.md, "Issue 32 item 3 ... meshspeed2").
//
// usage: FAMILY=DIR [REPS=n] driver MODE K CONFIG [print]
//   MODE dist | inter | depth | contacts | contacts_list (every contact listed): the 300 pairs of mesh K in CONFIG (near, touching, apart), one
//   call each (REPS times); "print" writes every result (%.17g) for an old/new comparison;
//   CPU microseconds a query go to stderr.  MODE build: K's hierarchy built CONFIG times.
//   MODE hash: a hash (FNV-1a) of every array of K's hierarchy and its node count (CONFIG is
//   ignored): equal between two checkouts' drivers when their builds make the same tree, bit
//   for bit.
// Build against a checkout's core (every cpp/src/*.cpp, -O3), e.g.
//   g++ -std=c++17 -O3 -Icpp/include benchmarks/mesh_query_driver/driver.cpp cpp/src/*.cpp -lpthread -o driver
// then: valgrind --tool=callgrind --toggle-collect='meshcol::mesh_distance(*' ./driver dist 3 near
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <string>
#include <vector>
#include "meshcol/mesh_bvh.hpp"
#include "meshcol/mesh_query.hpp"
using namespace meshcol;
template <class T> std::vector<T> load(const std::string& p) {
    FILE* f = std::fopen(p.c_str(), "rb");
    if (!f) { std::perror(p.c_str()); std::exit(2); }
    std::fseek(f, 0, SEEK_END); long n = std::ftell(f); std::fseek(f, 0, SEEK_SET);
    std::vector<T> v(n / sizeof(T));
    if (std::fread(v.data(), sizeof(T), v.size(), f) != v.size()) std::exit(3);
    std::fclose(f);
    return v;
}
int main(int argc, char** argv) {
    std::string mode = argv[1], k = argv[2], config = argv[3];
    bool print = argc > 4;
    std::string dir = std::string(std::getenv("FAMILY") ? std::getenv("FAMILY") : "family") + "/";
    auto v = load<double>(dir + "m" + k + ".v");
    auto f = load<std::int64_t>(dir + "m" + k + ".f");
    if (mode == "hash") {
        MeshBvh m(v.data(), v.size() / 3, f.data(), f.size() / 3);
        std::uint64_t h = 1469598103934665603ULL;
        const auto add = [&h](const void* p, size_t n) {
            for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ULL;
        };
        add(m.nodes().data(), m.nodes().size() * sizeof(BvhNode));
        for (const WindingNode& w : m.winding_nodes()) {
            add(&w.center, sizeof(Vec3)); add(&w.dipole, sizeof(Vec3)); add(w.moment, sizeof(w.moment));
            add(&w.radius, sizeof(double)); add(&w.area, sizeof(double));
        }
        for (const NodeObb& o : m.obbs()) { add(&o.axes, sizeof(Mat3)); add(&o.center, sizeof(Vec3)); add(&o.half, sizeof(Vec3)); }
        for (std::int32_t i = 0; i < m.triangle_count(); ++i) {
            const TriangleCapsule& c = m.triangle_capsule(i);
            const std::int64_t face = m.face_index(i);
            const char thin = c.thin;
            add(m.triangle(i), 3 * sizeof(Vec3)); add(&m.triangle_normal(i), sizeof(Vec3));
            add(&c.radius, sizeof(double)); add(&c.edge, sizeof(c.edge)); add(&thin, 1);
            add(m.triangle_vertices(i), 3 * sizeof(std::int32_t)); add(&face, sizeof(face));
        }
        add(m.vertices().data(), m.vertices().size() * sizeof(Vec3));
        const double reach[2] = {m.box_reach(), m.obb_reach()};
        const char closed = m.closed(), valid = m.validate();
        add(reach, sizeof(reach)); add(&closed, 1); add(&valid, 1);
        std::printf("%s %zu %016llx\n", k.c_str(), m.nodes().size(), static_cast<unsigned long long>(h));
        return 0;
    }
    if (mode == "build") {
        int reps = std::atoi(config.c_str());
        long long s = 0;
        for (int i = 0; i < reps; ++i) { MeshBvh m(v.data(), v.size() / 3, f.data(), f.size() / 3); s += m.nodes().size(); }
        std::printf("%lld\n", s);
        return 0;
    }
    MeshBvh mesh(v.data(), v.size() / 3, f.data(), f.size() / 3);
    const char* other = std::getenv("B");
    std::vector<double> v2 = other ? load<double>(dir + "m" + other + ".v") : v;
    std::vector<std::int64_t> f2 = other ? load<std::int64_t>(dir + "m" + other + ".f") : f;
    MeshBvh mesh_b(v2.data(), v2.size() / 3, f2.data(), f2.size() / 3);
    auto p = load<double>(dir + "m" + k + "_" + config + ".p");
    size_t count = p.size() / 32;
    double sum = 0;
    const int reps = std::getenv("REPS") ? std::atoi(std::getenv("REPS")) : 1;
    const std::clock_t start = std::clock();
    for (int rep = 0; rep < reps; ++rep)
    for (size_t i = 0; i < count; ++i) {
        Pose pa = Pose::from_matrix4(&p[32 * i]), pb = Pose::from_matrix4(&p[32 * i + 16]);
        if (mode == "dist") {
            MeshDistanceInput in; in.a = &mesh; in.b = &mesh_b; in.pose_a = pa; in.pose_b = pb;
            MeshDistanceOutput o = mesh_distance(in);
            sum += o.distance;
            if (print) std::printf("%zu %.17g %d %d %d %lld %lld %.17g %.17g %.17g %.17g %.17g %.17g\n", i, o.distance, o.intersecting, o.a_inside_b, o.b_inside_a,
                (long long)o.triangle_a, (long long)o.triangle_b, o.point_a.x, o.point_a.y, o.point_a.z, o.point_b.x, o.point_b.y, o.point_b.z);
        } else if (mode == "inter") {
            bool hit = mesh_intersects(mesh, pa, mesh_b, pb);
            sum += hit;
            if (print) std::printf("%zu %d\n", i, hit);
        } else if (mode == "depth") {
            MeshDistanceInput in; in.a = &mesh; in.b = &mesh_b; in.pose_a = pa; in.pose_b = pb;
            MeshDepthOutput o = mesh_penetration_depth(in);
            sum += o.depth;
            if (print) std::printf("%zu %.17g %d %d %lld %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", i, o.depth, o.deepest_mesh, static_cast<int>(o.status),
                (long long)o.points_tested, o.normal.x, o.normal.y, o.normal.z, o.point_a.x, o.point_a.y, o.point_a.z, o.point_b.x, o.point_b.y, o.point_b.z);
        } else if (mode == "contacts" || mode == "contacts_list") {
            MeshContactsInput in; in.a = &mesh; in.b = &mesh_b; in.pose_a = pa; in.pose_b = pb;
            in.max_contacts = mode == "contacts_list" ? (1LL << 40) : 0;
            std::vector<MeshContact> listed;
            MeshContactsOutput o = mesh_contacts(in, &listed);
            sum += o.depth + o.face_depth + static_cast<double>(o.count);
            if (print) std::printf("%zu %lld %.17g %.17g %lld %lld %d %zu\n", i, (long long)o.count, o.depth, o.face_depth,
                (long long)o.triangle_a, (long long)o.triangle_b, static_cast<int>(o.status), listed.size());
            if (print)
                for (const MeshContact& c : listed)
                    std::printf("  %lld %lld %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", (long long)c.triangle_a,
                        (long long)c.triangle_b, c.depth, c.face_depth, c.normal.x, c.normal.y, c.normal.z, c.point.x,
                        c.point.y, c.point.z);
        }
    }
    std::fprintf(stderr, "cpu_us_per_query %.2f\n", 1e6 * double(std::clock() - start) / CLOCKS_PER_SEC / double(reps * count));
    std::printf("sum %.17g\n", sum);
}
