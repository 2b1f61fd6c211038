// Standalone narrow-phase driver for callgrind and CPU-time A/B runs: `run_batch` (one
// thread) on a case dumped by narrowphase_cases.py, no Python in the process. Build against
// any checkout's core (not part of the CMake build):
//   g++ -std=c++17 -O3 -g -ICHECKOUT/cpp/include benchmarks/narrowphase_driver.cpp \
//       CHECKOUT/cpp/src/*.cpp -lpthread -o driver
// Run: ./driver CASE_DIR KIND(0 distance, 1 penetration) REPEAT [RESULTS_FILE]
//   valgrind --tool=callgrind ./driver cases/64_penetrating 1 1
// It prints the best CPU time of REPEAT runs a pair and checksums of the results (equal
// checksums: the same answers), and writes the raw results when asked. The runs share the
// set's checked radii and edge classes, as the extension's batches on one set do (a core
// without `ShapeRadii`: build with -DNO_SHAPE_RADII; one whose set holds the edge classes
// themselves, not the edges they are computed from: -DEAGER_EDGES; one whose set makes
// fixed-stride climb lists, made here from the case's adjacency as a set built from a
// caller's arrays makes them, the same bytes as the hull packing writes: -DCLIMB_LISTS).
// narrowphase_identity.py compares two checkouts' raw results on every case, byte for byte.
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include "meshcol/narrowphase.hpp"
using namespace meshcol;
template <class T> std::vector<T> load(const std::string& dir, const std::string& name) {
    std::ifstream f(dir + "/" + name + ".bin", std::ios::binary | std::ios::ate);
    size_t n = f.tellg(); f.seekg(0);
    std::vector<T> v(n / sizeof(T));
    f.read(reinterpret_cast<char*>(v.data()), n);
    return v;
}
int main(int argc, char** argv) {
    std::string dir = argv[1];
    int kind = std::atoi(argv[2]);
    int reps = argc > 3 ? std::atoi(argv[3]) : 1;
    auto vertices = load<double>(dir, "vertices");
    auto offsets = load<std::int64_t>(dir, "offsets");
    auto kinds = load<std::int8_t>(dir, "kinds");
    auto params = load<double>(dir, "params");
    auto adj_off = load<std::int64_t>(dir, "adjacency_offsets");
    auto adj = load<std::int32_t>(dir, "adjacency");
    auto face_off = load<std::int64_t>(dir, "face_offsets");
    auto face_n = load<double>(dir, "face_normals");
#ifdef EAGER_EDGES
    auto edge_off = load<std::int64_t>(dir, "edge_offsets");
    auto edge_d = load<double>(dir, "edge_directions");
#else
    auto edge_pair_off = load<std::int64_t>(dir, "edge_pair_offsets");
    auto edge_pairs = load<std::int32_t>(dir, "edge_pairs");
#endif
    auto poses = load<double>(dir, "poses");
    auto pairs = load<std::int64_t>(dir, "pairs");
    ConvexSetView s;
    s.vertices = vertices.data(); s.vertex_count = vertices.size() / 3;
    s.offsets = offsets.data(); s.shape_count = kinds.size(); s.kinds = kinds.data();
    s.params = params.data(); s.adjacency_offsets = adj_off.data(); s.adjacency = adj.data();
    s.face_offsets = face_off.data(); s.face_normals = face_n.data();
#ifdef EAGER_EDGES
    s.edge_offsets = edge_off.data(); s.edge_directions = edge_d.data();
#else
    EdgeClasses classes(s.shape_count);
    s.edge_pair_offsets = edge_pair_off.data(); s.edge_pairs = edge_pairs.data();
    s.edge_classes = &classes;
#endif
#ifdef CLIMB_LISTS
    ClimbLists lists(s, 1);
    lists.attach(s);
#endif
    long long p = pairs.size() / 2;
    std::vector<double> dist(p), depth(p), normal(3 * p), pa(3 * p), pb(3 * p);
    std::vector<std::int32_t> its(p);
    std::vector<std::int8_t> st(p);
    BatchOutput out;
    out.distance = dist.data(); out.normal = normal.data(); out.point_a = pa.data();
    out.point_b = pb.data(); out.iterations = its.data(); out.status = st.data();
    if (kind == 1) out.depth = depth.data();
    double best = 1e300;
#ifndef NO_SHAPE_RADII
    ShapeRadii radii(s.shape_count);
#endif
    for (int r = 0; r < reps; ++r) {
        std::clock_t t0 = std::clock();
#ifdef NO_SHAPE_RADII
        run_batch(s, poses.data(), pairs.data(), p, static_cast<QueryKind>(kind), 1, out);
#else
        run_batch(s, poses.data(), pairs.data(), p, static_cast<QueryKind>(kind), 1, out, &radii);
#endif
        double t = double(std::clock() - t0) / CLOCKS_PER_SEC;
        if (t < best) best = t;
    }
    double sd = 0, sdep = 0, sit = 0, sx = 0;
    for (long long i = 0; i < p; ++i) { sd += dist[i]; sdep += depth[i]; sit += its[i]; sx += pa[3*i] + pb[3*i+1] + normal[3*i+2]; }
    std::printf("%s kind=%d pairs=%lld best_cpu_us_per_pair=%.4f sum_dist=%.17g sum_depth=%.17g mean_iter=%.3f chk=%.17g\n",
                dir.c_str(), kind, p, best / p * 1e6, sd, sdep, sit / p, sx);
    if (argc > 4) {  // dump results
        std::ofstream f(argv[4], std::ios::binary);
        f.write((char*)dist.data(), 8 * p); f.write((char*)depth.data(), 8 * p);
        f.write((char*)normal.data(), 24 * p); f.write((char*)pa.data(), 24 * p); f.write((char*)pb.data(), 24 * p);
    }
}
