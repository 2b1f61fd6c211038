// mesh_topology_batch (mesh_topology.hpp): the counts of small meshes known by hand, each
// mesh's answer independent of its neighbours and of the thread count, a bad index reported
// per mesh.
#include <cstdint>
#include <vector>

#include "check.hpp"
#include "meshcol/mesh_topology.hpp"

using namespace meshcol;

namespace {

// A tetrahedron's four faces, outward.
const std::vector<std::int64_t> kTetra = {0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0};

struct Batch {
    std::vector<std::int64_t> faces, face_offsets{0}, vertex_offsets{0};
    void add(const std::vector<std::int64_t>& f, std::int64_t vertices) {
        faces.insert(faces.end(), f.begin(), f.end());
        face_offsets.push_back(face_offsets.back() + static_cast<std::int64_t>(f.size() / 3));
        vertex_offsets.push_back(vertex_offsets.back() + vertices);
    }
    std::vector<MeshTopology> run(std::vector<std::uint8_t>& used, int threads) const {
        const auto n = static_cast<std::int64_t>(face_offsets.size() - 1);
        std::vector<MeshTopology> out(static_cast<size_t>(n));
        used.assign(static_cast<size_t>(vertex_offsets.back()), 7);
        mesh_topology_batch(faces.data(), face_offsets.data(), vertex_offsets.data(), n, out.data(),
                            used.data(), threads);
        return out;
    }
};

}  // namespace

TEST_CASE("mesh_topology: a tetrahedron, open, flipped, doubled, finned, and a bad index") {
    Batch batch;
    batch.add(kTetra, 5);  // closed; vertex 4 unused
    batch.add({0, 1, 2, 0, 3, 1, 1, 3, 2}, 4);  // one face missing: three boundary edges
    batch.add({0, 1, 2, 0, 3, 1, 1, 3, 2, 0, 3, 2}, 4);  // one face flipped
    std::vector<std::int64_t> twice = kTetra;
    twice.insert(twice.end(), kTetra.begin(), kTetra.end());
    batch.add(twice, 4);  // every face twice: six edges of four faces each
    batch.add({0, 1, 2, 0, 0, 1, 3, 4, 5}, 6);  // a collapsed face and a second piece
    batch.add({0, 1, 9}, 3);  // index out of range
    for (int threads : {1, 2, 4}) {
        std::vector<std::uint8_t> used;
        const auto t = batch.run(used, threads);
        CHECK(t[0].closed && t[0].balanced);
        CHECK_EQ(t[0].boundary_edges + t[0].non_manifold_edges + t[0].inconsistent_edges, 0);
        CHECK_EQ(t[0].components, 1);
        CHECK_EQ(static_cast<int>(used[4]), 0);
        CHECK_EQ(t[1].boundary_edges, 3);
        CHECK(!t[1].closed && !t[1].balanced);
        CHECK_EQ(t[2].inconsistent_edges, 3);
        CHECK(!t[2].closed);
        CHECK_EQ(t[3].non_manifold_edges, 6);
        CHECK_EQ(t[3].duplicate_faces, 4);
        CHECK(t[3].balanced && !t[3].closed);
        CHECK_EQ(t[4].components, 2);
        // the collapsed face uses edge 0-1 both ways: three uses with the first face's
        CHECK_EQ(t[4].boundary_edges, 5);
        CHECK_EQ(t[4].non_manifold_edges, 1);
        CHECK(t[5].status == MeshTopologyStatus::INDEX_OUT_OF_RANGE);
        CHECK(t[0].status == MeshTopologyStatus::OK);
    }
}
