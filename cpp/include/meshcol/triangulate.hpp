#pragma once
// Polygon faces split into triangles: the one splitter of the readers (USD, FBX, OFF), batched
// over a whole mesh's face-count array.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshcol {

/// A polygon mesh as its readers hold it: every face's vertex count, and the vertex indices of
/// all faces one after the other. Views, not owned.
struct PolygonMesh {
    const double* vertices = nullptr;  ///< (n_vertices, 3) row-major
    std::size_t n_vertices = 0;
    const std::int64_t* counts = nullptr;  ///< (n_faces,) corners of each face
    std::size_t n_faces = 0;
    const std::int64_t* indices = nullptr;  ///< (n_indices,) = sum(counts)
    std::size_t n_indices = 0;
};

/// What to split and how.
struct TriangulateOptions {
    std::vector<std::int64_t> holes;  ///< faces left out (USD holeIndices; out-of-range ones ignored)
    bool reverse = false;             ///< each triangle's winding reversed (USD leftHanded)
    std::int64_t max_triangles = -1;  ///< refuse more triangles than this (-1: no limit)
};

/// The triangles of `mesh`'s faces, (t, 3) row-major, in face order: face `f` of k >= 3 corners
/// gives k - 2 consecutive triangles; faces of fewer corners (points, edges) and holes give none.
///
/// A face is convex when, in the plane of its Newell normal (the dominant axis dropped), every
/// turn is to the left and the turns add up to one full turn (a pentagram turns twice): it is
/// fanned from its first corner. Any other face is ear clipped (Eberly, "Triangulation by Ear
/// Clipping", 2002) in that plane; what is left when no ear is found (no area, not simple) is
/// fanned. Sums are taken in numpy's pairwise order, so the split is the one the former numpy
/// splitter made, bit for bit.
///
/// Throws std::invalid_argument, with a message naming the problem, when a count is negative,
/// the counts do not add up to n_indices or an index is out of [0, n_vertices); and
/// std::overflow_error when there would be more than max_triangles triangles (nothing is
/// allocated for them first).
std::vector<std::int64_t> triangulate_polygons(const PolygonMesh& mesh,
                                               const TriangulateOptions& options);

}  // namespace meshcol
