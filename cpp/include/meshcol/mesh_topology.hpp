#pragma once
/// The topology of many small meshes at once, for `meshcol inspect`'s health checks: edge
/// counts, closedness, balance, duplicate faces, connected pieces and used vertices of each
/// mesh, integer counts only (the same numbers as meshcol/geometry/topology.py's single-mesh
/// functions on each mesh); and the faces' heights its degenerate-face rule compares.

#include <cstdint>

namespace meshcol {

/// Status of one mesh of a topology batch.
enum class MeshTopologyStatus : std::int8_t {
    OK = 0,                  ///< counted
    INDEX_OUT_OF_RANGE = 1,  ///< a face names a vertex outside its mesh: nothing counted
};

/// One mesh's topology (every count >= 0).
struct MeshTopology {
    std::int64_t boundary_edges = 0;      ///< undirected edges with one face
    std::int64_t non_manifold_edges = 0;  ///< undirected edges with more than two faces
    std::int64_t inconsistent_edges = 0;  ///< edges with two faces that traverse them the same way
    std::int64_t duplicate_faces = 0;     ///< faces on the same three vertices as an earlier face
    std::int64_t components = 0;          ///< connected pieces of the used vertices
    bool closed = false;    ///< at least one edge, and every edge two faces, traversed oppositely
    bool balanced = false;  ///< the faces without a repeated corner have an edge, and every
                            ///< edge of theirs is traversed as often each way
    MeshTopologyStatus status = MeshTopologyStatus::OK;
};

/// The topology of each mesh of a batch. Mesh `i` has the faces
/// `faces[3 * face_offsets[i] .. 3 * face_offsets[i + 1])` (indices into its own vertices,
/// `vertex_offsets[i + 1] - vertex_offsets[i]` of them) and the vertices
/// `vertex_offsets[i] .. vertex_offsets[i + 1]` of `used` (one byte per vertex of the batch,
/// set to 1 when a face of the mesh names it, 0 otherwise). Edges of collapsed faces (a
/// repeated index) are left out, as numpy's edge_table does. Threads over meshes (0: every
/// core); never throws for one mesh: its status says what was wrong.
void mesh_topology_batch(const std::int64_t* faces, const std::int64_t* face_offsets,
                         const std::int64_t* vertex_offsets, std::int64_t mesh_count,
                         MeshTopology* out, std::uint8_t* used, int threads);

/// Each face's height on its longest edge (twice its area over that edge's length; 0 when the
/// longest edge has length 0 or is NaN) and whether it names a vertex twice: the bits of
/// meshcol/geometry/triangles.py's numpy `face_heights` (its cross product, and its norms
/// summed x, y, z in that order; built without fused multiply-add). `faces` (n_faces, 3)
/// index `vertices` (in range: the caller checks); threads over faces (0: every core).
void face_heights(const double* vertices, const std::int64_t* faces, std::int64_t n_faces,
                  double* heights, std::uint8_t* repeated, int threads);

}  // namespace meshcol
