#pragma once
/// A static bounding volume hierarchy over the triangles of one mesh, in the mesh's local
/// frame: axis-aligned boxes, built top-down with a binned surface area heuristic (Wald 2007),
/// stored flat in depth-first order (32-byte nodes), with the triangles copied in leaf order so
/// a leaf reads one contiguous block. Beside each node, in arrays of their own: an oriented box
/// (the pair traversals' bound, tight under any relative rotation) and the far-field data of
/// the fast winding number.

#include <cstdint>
#include <utility>
#include <vector>

#include "meshcol/vec.hpp"

namespace meshcol {

/// One node. A leaf holds triangles [index, index + count); an internal node (count == 0) has
/// its left child right after it (depth-first order) and its right child at `index`.
struct BvhNode {
    float lower[3];       ///< box minimum, local frame, rounded outwards from the doubles
    float upper[3];       ///< box maximum, local frame, rounded outwards from the doubles
    std::int32_t index;   ///< leaf: first triangle (leaf order); internal: right child
    std::int32_t count;   ///< leaf: number of triangles (>= 1); internal: 0

    bool is_leaf() const { return count > 0; }
};
static_assert(sizeof(BvhNode) == 32, "BvhNode must stay 32 bytes");

/// The far-field data of one node for the fast winding number (Barill, Dickson, Schmidt,
/// Levin and Jacobson 2018, "Fast winding numbers for soups and clouds"), to order 2: seen
/// from a point q far from `center`, the triangles under the node subtend the solid angle of
/// a dipole `dipole` plus a quadrupole `moment` at `center`, within a bound that falls as
/// radius^2 * area / (|q - center| - radius)^4. Kept apart from BvhNode so the pair traversals
/// stay on 32-byte nodes.
struct WindingNode {
    Vec3 center;       ///< area-weighted centroid of the node's triangles, local frame
    Vec3 dipole;       ///< sum of the triangles' area vectors a = cross(p1 - p0, p2 - p0) / 2
    /// Symmetric part of the first moment sum over triangles of a (g - center)^T (g the
    /// triangle's centroid): xx, yy, zz, xy, yz, zx
    double moment[6];
    double radius;     ///< no corner of the node's triangles is farther than this from center
    double area;       ///< sum of the triangles' areas (|a|), >= |dipole|
};
/// An oriented box bounding one node's triangles (Gottschalk, Lin and Manocha 1996, "OBBTree"):
/// {x : |axes.row(k) . (x - center)| <= half[k]}. Its first axis follows the patch's mean
/// normal, so a nearly flat patch gets a thin box whatever its orientation in the mesh's frame;
/// nodes whose normals cancel (a closed piece) keep the axis-aligned box.
struct NodeObb {
    Mat3 axes;    ///< rows: orthonormal axes, local frame
    Vec3 center;  ///< local frame
    Vec3 half;    ///< half extents along the rows of axes, padded outwards for rounding
    /// The axis-aligned box was kept: axes is the identity, exactly, and the pair tests skip
    /// their products with it (most nodes near the root: their normals cancel).
    bool axis_aligned = true;
};

/// A capsule holding one triangle: the segment of its longest edge (corners `edge` and
/// `edge + 1` mod 3) swept by a ball of `radius`, the distance of the opposite corner from that
/// segment (rounded up). For a sliver it is nearly the triangle, so the distance between two
/// capsules bounds a triangle pair's distance tightly from below where boxes and planes do not.
struct TriangleCapsule {
    double radius;
    std::int32_t edge;
    /// A sliver: the radius is under a quarter of the spine's length (for fatter triangles the
    /// capsule bounds no better than the box and plane bounds, and is not worth its cost).
    bool thin;
};

/// The hierarchy of one triangle mesh. Immutable once built; safe to share between threads.
class MeshBvh {
public:
    MeshBvh() = default;

    /// Builds the hierarchy of `face_count` triangles `faces` (3 indices each, into the
    /// `vertex_count` points `vertices`, 3 doubles each, local frame).
    /// Throws std::invalid_argument when a face index is out of [0, vertex_count).
    /// A mesh with a non-finite vertex or no face is kept but marked not `valid()` (no nodes).
    MeshBvh(const double* vertices, std::int64_t vertex_count, const std::int64_t* faces,
            std::int64_t face_count);

    /// Finite vertices and at least one face.
    bool valid() const { return !nodes_.empty(); }
    /// Every edge (between distinct vertex indices) is shared by exactly two faces that
    /// traverse it in opposite directions: a closed, consistently wound surface, whose winding
    /// number is an integer off the surface (as geometry.topology.is_closed_manifold).
    bool closed() const { return closed_; }
    const std::vector<BvhNode>& nodes() const { return nodes_; }
    /// One per node, same index: the fast winding number's far-field data (validate() checks
    /// the radii).
    const std::vector<WindingNode>& winding_nodes() const { return winding_nodes_; }
    /// One per node, same index: its oriented box (validate() checks that it holds the node's
    /// triangles).
    const std::vector<NodeObb>& obbs() const { return obbs_; }
    std::int32_t triangle_count() const { return static_cast<std::int32_t>(face_index_.size()); }
    /// The three corners of triangle `i` (leaf order), local frame.
    const Vec3* triangle(std::int32_t i) const { return &corners_[3 * static_cast<size_t>(i)]; }
    /// The unit normal of triangle `i` (leaf order), local frame, (p1 - p0) x (p2 - p0)
    /// normalised; zero for a degenerate triangle. The distance search's plane bound reads it.
    const Vec3& triangle_normal(std::int32_t i) const { return normals_[static_cast<size_t>(i)]; }
    /// The capsule of triangle `i` (leaf order), local frame: the distance search's bound for
    /// long thin triangles.
    const TriangleCapsule& triangle_capsule(std::int32_t i) const { return capsules_[static_cast<size_t>(i)]; }
    /// The box of triangle `i` (leaf order), local frame: its lower and upper corner, the
    /// coordinate-wise least and greatest of its corners (the descents' triangle box, kept).
    const Vec3* triangle_bounds(std::int32_t i) const { return &bounds_[2 * static_cast<size_t>(i)]; }
    /// The vertices used by at least one face, each once, local frame (input order).
    const std::vector<Vec3>& vertices() const { return vertices_; }
    /// The three corners of triangle `i` (leaf order) as indices into `vertices()`.
    const std::int32_t* triangle_vertices(std::int32_t i) const { return &corner_vertices_[3 * static_cast<size_t>(i)]; }
    /// The input face index of triangle `i` (leaf order).
    std::int64_t face_index(std::int32_t i) const { return face_index_[static_cast<size_t>(i)]; }
    /// The distance from the local origin to the far corner of the root box (0 when not
    /// valid()): the mesh's reach, for the range check of a pair.
    double box_reach() const { return box_reach_; }
    /// max|centre| + max|half extent| of the root's oriented box (0 when not valid()): the
    /// scale of the rounding allowance of a pair's box bounds.
    double obb_reach() const { return obb_reach_; }

    /// Checks the invariants (for tests): every box contains its triangles and children, every
    /// triangle sits in exactly one leaf, leaves are no larger than the leaf size, the layout is
    /// depth-first. Returns false on the first violation.
    bool validate() const;

private:
    void build_winding_nodes();
    void build_obbs();
    /// Triangles [first, last) (leaf order) under node `id`.
    std::pair<std::int32_t, std::int32_t> triangle_range(std::int32_t id) const;

    std::vector<BvhNode> nodes_;
    std::vector<WindingNode> winding_nodes_;
    std::vector<NodeObb> obbs_;
    std::vector<Vec3> corners_;            ///< 3 per triangle, leaf order
    std::vector<Vec3> normals_;            ///< 1 per triangle, leaf order, unit or zero
    std::vector<TriangleCapsule> capsules_;  ///< 1 per triangle, leaf order
    std::vector<Vec3> bounds_;             ///< 2 per triangle, leaf order: its box's lower, upper
    std::vector<Vec3> vertices_;           ///< vertices referenced by a face, input order
    std::vector<std::int32_t> corner_vertices_;  ///< 3 per triangle, leaf order, into vertices_
    bool closed_ = false;
    double box_reach_ = 0.0;  ///< computed once at build: every pair query reads it
    double obb_reach_ = 0.0;
    std::vector<std::int64_t> face_index_;  ///< leaf order -> input face
};

}  // namespace meshcol
