// A driver for callgrind and perf (issue 32, item 2): pack_polytopes, one thread by default,
// on H shapes of n points: "hull" (random ellipsoids, randomly turned: every point a vertex),
// "cloud" (Gaussian), or a degenerate family (grid, noisy, flat, line, dup, huge, tiny, box).
// HASH=1 prints a hash of the packed arrays and of the edge classes (compare two builds on the
// same inputs: a build whose packing stores the classes hashes them in the same place as one
// that computes them from the packed edges, so equal hashes mean equal classes; -DEAGER_EDGES
// for a core from before the classes were computed lazily; -DCLIMB_LISTS also hashes the
// climb lists, on a line of their own, for a core that packs them).
//
// Build (from the repository's root) and count:
//   g++ -std=gnu++17 -O3 -g -Icpp/include -Icpp/src benchmarks/hull_driver.cpp
//       cpp/src/hull.cpp cpp/src/quickhull.cpp cpp/src/quickhull_flat.cpp
//       cpp/src/hull_packing.cpp cpp/src/batch.cpp
//       -o /tmp/hull_driver -lpthread
//   valgrind --tool=callgrind --dump-instr=no
//       --toggle-collect='meshcol::pack_polytopes(meshcol::Vec3 const*, long const*, long long, int)'
//       /tmp/hull_driver 200 64 hull
// Arguments: H n family threads (defaults 1000 64 hull 1).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>
#include <ctime>
#include "meshcol/hull.hpp"
using namespace meshcol;
int main(int argc, char** argv) {
    const long long H = argc > 1 ? atoll(argv[1]) : 1000;
    const int n = argc > 2 ? atoi(argv[2]) : 64;
    const char* family = argc > 3 ? argv[3] : "hull";
    const bool cloud = !strcmp(family, "cloud");
    const int threads = argc > 4 ? atoi(argv[4]) : 1;
    std::mt19937_64 rng(1);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> u(0.5, 1.5);
    std::vector<Vec3> pts(H * n);
    std::vector<std::int64_t> off(H + 1);
    for (long long h = 0; h < H; ++h) {
        off[h] = h * n;
        double ax = u(rng), ay = u(rng), az = u(rng);
        double qw = g(rng), qx = g(rng), qy = g(rng), qz = g(rng);
        double qn = std::sqrt(qw*qw+qx*qx+qy*qy+qz*qz); qw/=qn; qx/=qn; qy/=qn; qz/=qn;
        double R[3][3] = {{1-2*(qy*qy+qz*qz), 2*(qx*qy-qz*qw), 2*(qx*qz+qy*qw)},
                          {2*(qx*qy+qz*qw), 1-2*(qx*qx+qz*qz), 2*(qy*qz-qx*qw)},
                          {2*(qx*qz-qy*qw), 2*(qy*qz+qx*qw), 1-2*(qx*qx+qy*qy)}};
        for (int i = 0; i < n; ++i) {
            double x = g(rng), y = g(rng), z = g(rng);
            if (!cloud) { double l = std::sqrt(x*x+y*y+z*z); x = x/l*ax; y = y/l*ay; z = z/l*az; }
            if (!strcmp(family, "grid")) { x = std::floor(x * 2); y = std::floor(y * 2); z = std::floor(z * 2); }
            if (!strcmp(family, "noisy")) { x += 1e-12 * g(rng); y += 1e-12 * g(rng); z += 1e-12 * g(rng); }
            if (!strcmp(family, "flat")) { z = 0.25 * x - 0.5 * y; }
            if (!strcmp(family, "line")) { y = 2 * x; z = -x; }
            if (!strcmp(family, "dup") && i > 0 && (i % 3 == 0)) { pts[h*n+i] = pts[h*n+i-1]; continue; }
            if (!strcmp(family, "huge")) { x *= 1e150; y *= 1e150; z *= 1e150; }
            if (!strcmp(family, "tiny")) { x *= 1e-150; y *= 1e-150; z *= 1e-150; }
            if (!strcmp(family, "box") ) { x = x > 0 ? 1 : -1; if (i % 2) y = y > 0 ? 1 : -1; else z = z > 0 ? 1 : -1; }
            pts[h*n+i] = {R[0][0]*x+R[0][1]*y+R[0][2]*z, R[1][0]*x+R[1][1]*y+R[1][2]*z, R[2][0]*x+R[2][1]*y+R[2][2]*z};
        }
    }
    off[H] = H * n;
    const std::clock_t c0 = std::clock();
    const auto w0 = std::chrono::steady_clock::now();
    PackedPolytopes p = pack_polytopes(pts.data(), off.data(), H, threads);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    // The CPU (all threads) a shape last: scripts read the figure after the last comma.
    std::printf("%lld shapes x %d (%s): %zu vertices, %.3f s wall, %.3f s CPU, %.2f us a shape\n",
                H, n, family, p.vertices.size() / 3, wall, cpu, cpu / H * 1e6);
    if (!getenv("HASH")) return 0;
    std::uint64_t hsh = 1469598103934665603ull;
    auto mix = [&](const void* d, size_t bytes) { auto* c = static_cast<const unsigned char*>(d); for (size_t i = 0; i < bytes; ++i) hsh = (hsh ^ c[i]) * 1099511628211ull; };
    mix(p.status.data(), p.status.size()); mix(p.vertices.data(), 8*p.vertices.size()); mix(p.offsets.data(), 8*p.offsets.size());
    mix(p.adjacency_offsets.data(), 8*p.adjacency_offsets.size()); mix(p.adjacency.data(), 4*p.adjacency.size());
    mix(p.face_offsets.data(), 8*p.face_offsets.size()); mix(p.face_normals.data(), 8*p.face_normals.size());
#ifdef EAGER_EDGES
    const std::vector<std::int64_t>& edge_offsets = p.edge_offsets;
    const std::vector<double>& edge_directions = p.edge_directions;
#else
    // The classes as SAT computes them, shape by shape, from the packed vertices and edges.
    std::vector<std::int64_t> edge_offsets{0};
    std::vector<double> edge_directions;
    for (long long h = 0; h < H; ++h) {
        const std::int64_t first = p.edge_pair_offsets[h];
        const std::int64_t count = edge_direction_classes(
            reinterpret_cast<const Vec3*>(p.vertices.data()) + p.offsets[h],
            p.edge_pairs.data() + 2 * first, static_cast<size_t>(p.edge_pair_offsets[h + 1] - first),
            edge_directions);
        edge_offsets.push_back(edge_offsets.back() + count);
    }
#endif
    mix(edge_offsets.data(), 8*edge_offsets.size()); mix(edge_directions.data(), 8*edge_directions.size());
    // The true edges themselves (their order too), hashed apart so the first hash stays
    // comparable with the runs recorded before it.
    const std::uint64_t classes_hash = hsh;
    hsh = 1469598103934665603ull;
    mix(p.edge_pair_offsets.data(), 8*p.edge_pair_offsets.size()); mix(p.edge_pairs.data(), 4*p.edge_pairs.size());
    std::printf("hash %016llx faces %zu edges %zu pairs %016llx\n", (unsigned long long)classes_hash, p.face_normals.size()/3, edge_directions.size()/3, (unsigned long long)hsh);
#ifdef CLIMB_LISTS
    // The fixed-stride climb lists (a core that packs them: build with -DCLIMB_LISTS), hashed
    // on a line of their own so the lines above compare with a core that does not.
    hsh = 1469598103934665603ull;
    mix(p.climb_list_offsets.data(), 8*p.climb_list_offsets.size()); mix(p.climb_lists.data(), sizeof(ClimbList)*p.climb_lists.size());
    std::printf("climb lists %016llx rows %zu\n", (unsigned long long)hsh, p.climb_lists.size());
#endif
    return 0;
}
