#pragma once
/// Meshes whose faces are not consistently wound (issue 29): winding them consistently
/// (orientation.cpp), and the exact inside test for the ones that cannot be (ray_parity.cpp).
///
/// Both take index arrays as numpy holds them: `vertices` (n, 3) doubles, `faces` (m, 3) int64
/// vertex indices, each in [0, n) (the caller checks).

#include <cstdint>
#include <vector>

namespace meshcol {

/// What `ray_parity` says of a point.
enum class Parity : std::int8_t {
    undecided = -1,  ///< on the surface, or the faces bound nothing (see ray_parity)
    outside = 0,
    inside = 1,
};

/// Inside or outside the solid the faces bound by the even-odd rule, exactly.
///
/// The faces bound a solid when they form a closed surface modulo 2: every edge, its ends
/// taken by their coordinates (vertices at the same place are one), is used by an even number
/// of faces; winding, orientability, self-crossings and nesting do not matter. Otherwise every
/// point is `undecided`: an open surface has no inside.
///
/// A point is inside when a ray from it crosses the faces an odd number of times. The ray goes
/// along +x from the point moved by (0, e, e^2), e infinitesimal (Simulation of Simplicity,
/// Edelsbrunner and Muecke 1990): it meets no vertex and no edge, and lies in no face's plane,
/// so each crossing is a proper one, and it starts in the same cell of space as the point
/// whenever the point is off the surface. Every decision is an exact orientation sign of input
/// coordinates (orient2d of the yz projections, orient3d; predicates.hpp), the perturbation's
/// terms comparisons of coordinates: there is no tolerance. `undecided` then means exactly that
/// the point lies on a face (closed triangle), where inside is not defined.
///
/// Brute force over the faces per point (bounding-interval rejects first): the fallback for
/// the meshes the winding number cannot judge. `out`: one Parity per point.
void ray_parity(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                std::int64_t face_count, const double* points, std::int64_t point_count,
                Parity* out);

/// Whether the faces form a closed surface modulo 2 (see ray_parity).
bool closed_mod_two(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
                    std::int64_t face_count);

/// Closed and consistently wound: every directed edge (u, v), u != v, appears exactly once
/// among the faces' edges and so does (v, u) (MeshBvh::closed). False without such an edge.
bool closed_and_consistent(const std::int64_t* faces, std::int64_t face_count,
                           std::int64_t vertex_count);
/// The same for 32-bit vertex indices (a MeshBvh's compact corner indices).
bool closed_and_consistent(const std::int32_t* faces, std::int64_t face_count,
                           std::int64_t vertex_count);

/// What orient_faces did.
struct FaceOrientation {
    std::vector<std::uint8_t> flipped;  ///< per face: reversed
    bool orientable = true;             ///< every component's manifold edges could be made to agree
    bool balanced = false;              ///< the faces as turned: every edge as often each way
};

/// Each component of the faces wound consistently, closed components outward (inward for the
/// wall of a cavity): the algorithm of meshcol.geometry.topology.orient_consistently.
///
/// Faces whose manifold edges (two faces) all agree already are kept as given. Otherwise a
/// breadth-first pass over the face graph whose links are the manifold edges reverses each face
/// that traverses a shared edge as its parent does (one search from every component's lowest
/// face at once, neighbours in increasing index: the forest scipy's breadth_first_order builds,
/// so that a non-orientable component comes out as the Python version left it). A closed
/// component (each of its edges used by exactly two of its faces) is then turned outward by its
/// signed volume (cones from the centre of the vertices' box, summed in face order), unless it is
/// flat: |volume| at most `flat_volume` times the summed magnitudes of its cones (its sign would
/// be rounding noise; two faces back to back); when there
/// are 2 to `nesting_max_components` closed components, one whose first face's centroid lies
/// inside an odd number of the others (exact ray_parity against their faces) is turned inward,
/// so that a shell keeps its cavity. A centroid on another component's surface leaves it
/// outward.
FaceOrientation orient_faces(const double* vertices, std::int64_t vertex_count,
                             const std::int64_t* faces, std::int64_t face_count,
                             int nesting_max_components, double flat_volume);

}  // namespace meshcol
