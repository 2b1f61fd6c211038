#pragma once
/// Exact penetration depth of two polytopes (or boxes) by the separating axis theorem: the
/// minimum over the face normals of both shapes and the cross products of their edge
/// directions of the overlap along that axis (Ericson 2004, sec. 5.2.1; Gottschalk 1996).
/// Quadratic in the edge count, so only for shapes with few faces: EPA verification. Axes
/// that a bound shows cannot be the smallest are skipped, with the same answer to the bit
/// (two small scanning polytopes: a value within rounding of each axis's overlap; else two
/// inner balls, for edge axes); between polytopes with arcs on their Gauss maps
/// (`GaussArc`), only the axes of edge pairs whose arcs cross are measured (Gregorius 2013):
/// the same answer unless the shapes touch, where ties within rounding may fall to another
/// axis (sat.cpp).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "meshcol/defaults.hpp"
#include "meshcol/shapes.hpp"
#include "meshcol/vec.hpp"

namespace meshcol {

/// One true edge of a polytope on its Gauss map (local frame): the arc between the outward unit
/// normals of its two faces, on the great circle whose normal is
/// `face_normals[face_b] x face_normals[face_a]`. Indices only (8 bytes an edge): the normals
/// are the shape's own.
struct GaussArc {
    std::int16_t face_a = -1;           ///< one face (index into the shape's face normals)
    std::int16_t face_b = -1;           ///< the other
    std::int16_t vertex = -1;           ///< one end of the edge (a local vertex index)
    std::int16_t direction_class = -1;  ///< the edge's direction class (into the shape's classes)
};

/// The arcs of a polytope's true edges `pairs` ((count, 2) local vertex indices), whose
/// direction classes are `class_of` ((count,), as `edge_direction_classes` gives them), with
/// the faces among `face_normals` whose planes hold both ends (within
/// `defaults::sat_arc_plane_tolerance`), appended to `out`. False, and `out` as it was, when
/// an edge has no class or not exactly two such faces (a flat or degenerate shape), or the
/// shape has more than 64 faces or an index beyond the arc's fields: SAT then measures every
/// edge pair of it.
bool gauss_arcs(const Vec3* vertices, int vertex_count, const Vec3* face_normals, int face_count,
                const std::int32_t* pairs, const std::int32_t* class_of, size_t count,
                std::vector<GaussArc>& out);

/// Result of `sat_penetration`.
struct SatResult {
    bool ran = false;        ///< false when a shape lacks SAT data or the work cap is exceeded
    bool separated = false;  ///< an axis with a positive gap exists (then `depth` is 0)
    double depth = 0.0;      ///< >= 0: the minimum overlap over all candidate axes
    Vec3 normal;             ///< world frame, unit, from a to b: moving b by depth * normal
                             ///< brings the shapes to contact
    int axes = 0;            ///< candidate axes measured (not those the bound skipped)
};

/// True when `shape` carries SAT data (a box, or a polytope with its features attached).
bool has_sat_features(const ShapeView& shape);

/// SAT depth of `a` at `pose_a` against `b` at `pose_b`. Runs when both shapes have SAT data
/// and (candidate axes) x (vertices of a + b) is at most `max_work`.
SatResult sat_penetration(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, long long max_work = defaults::sat_max_work);

}  // namespace meshcol
